//! First-order uncertainty of a located special point: the implicit-function theorem on the
//! augmented system of [`super::two_param`] that locates it.
//!
//! The point solves G(x, λ; p) = 0 with
//!
//! ```text
//!   G = ( Pᵏ(x; λ, p) − x − (s, 0),  ψ(M(x; λ, p)) ),   M = ∂Pᵏ/∂x,
//! ```
//!
//! ψ the test function of its kind (fold 1 − tr M + det M, flip and symmetry-breaking
//! 1 + tr M + det M, Neimark–Sacker det M − 1). Along the solution, dλ*/dp is the last row of
//!
//! ```text
//!   d(x, λ)/dp = −[G_x  G_λ]⁻¹ G_p                                              (IFT)
//! ```
//!
//! and σ_λ² = (dλ*/dp)ᵀ C (dλ*/dp) for a covariance C of p ([`linear_sigma`]).
//!
//! **The bordered Jacobian from three map evaluations.** The first two rows of G_x, G_λ, G_p are
//! the map's Jacobians M − I and its analytic parameter columns ∂Pᵏ/∂q. The ψ row needs ∂M/∂x and
//! ∂M/∂q, second derivatives of the map; with ∂ψ/∂M = s_tr I + s_det cof(M) (the sign pair of the
//! kind; det M ≡ 0 with a stick phase, [`crate::orbits::Floquet::of_orbit`], so then s_det = 0),
//!
//! ```text
//!   ∂ψ/∂x_m = Σ_ij (∂ψ/∂M_ij) ∂M_ij/∂x_m,   ∂ψ/∂q = Σ_ij (∂ψ/∂M_ij) ∂²P_i/∂x_j∂q,
//! ```
//!
//! and both come from forward differences in x alone: ∂M/∂x_m from M at x + h e_m, and the mixed
//! derivative ∂²P_i/∂x_j∂q = ∂(∂P_i/∂q)/∂x_j from the parameter columns at x + h e_j (Schwarz). So
//! the whole Jacobian costs three linearisations of the map with the columns of λ and of every p,
//! whatever the number of parameters.

use super::minaug::{linearise_map, MapLinearisation};
use super::two_param::CurvePoint;
use super::SpecialKind;
use crate::error::{Error, Result};
use crate::integrator::FlowMethod;
use crate::model::Parametrised;
use crate::orbits::{OrbitSpec, ShootingOptions};
use nalgebra::{DMatrix, Matrix2, Matrix3, Vector3};

/// Relative step of the forward differences in x (β in rad, ω scaled by max(|ω|, 1)).
const STEP: f64 = 1e-5;

/// dλ*/dp of the special point `point` (of kind `kind`, solved for `free` on the orbit problem
/// `spec` of `sys`) for each parameter of `params`, by the implicit-function theorem (module
/// docs). `sys` must have a Jacobian column for `free` and for every parameter of `params`; the
/// map is integrated by `method` at the tolerance of `opts`.
#[allow(clippy::too_many_arguments)]
pub fn point_gradient<S: Parametrised, M: FlowMethod<S>>(
    method: &M,
    sys: &S,
    spec: &OrbitSpec,
    kind: SpecialKind,
    free: S::Param,
    point: &CurvePoint,
    params: &[S::Param],
    opts: &ShootingOptions,
) -> Result<Vec<f64>> {
    let sys = sys.with_param(free, point.free)?;
    let cols: Vec<S::Param> = std::iter::once(free)
        .chain(params.iter().copied())
        .collect();
    let x = point.x;
    let h = [STEP, STEP * x[1].abs().max(1.0)];
    let at = |y: [f64; 2]| linearise_map(method, &sys, spec, y, &cols, opts);
    let l0 = at(x)?;
    let shifted = [at([x[0] + h[0], x[1]])?, at([x[0], x[1] + h[1]])?];
    let dpsi_dm = test_gradient(kind, &l0)?;
    // ∂ψ/∂x_m and, per column q, ∂ψ/∂q (module docs)
    let dpsi_dx: [f64; 2] =
        std::array::from_fn(|m| contract(&dpsi_dm, &((shifted[m].jac - l0.jac) / h[m])));
    let dpsi_dq = |q: usize| {
        let d2 = Matrix2::from_fn(|i, j| (shifted[j].columns[q][i] - l0.columns[q][i]) / h[j]);
        contract(&dpsi_dm, &d2)
    };
    let a = Matrix3::new(
        l0.jac[(0, 0)] - 1.0,
        l0.jac[(0, 1)],
        l0.columns[0][0],
        l0.jac[(1, 0)],
        l0.jac[(1, 1)] - 1.0,
        l0.columns[0][1],
        dpsi_dx[0],
        dpsi_dx[1],
        dpsi_dq(0),
    );
    let lu = a.lu();
    (1..cols.len())
        .map(|q| {
            let gp = Vector3::new(l0.columns[q][0], l0.columns[q][1], dpsi_dq(q));
            lu.solve(&(-gp)).map(|z| z[2]).ok_or(Error::SingularMatrix {
                what:
                    "bordered Jacobian [G_x G_λ] of the located point (implicit-function theorem)",
            })
        })
        .collect()
}

/// ∂ψ/∂M of the test function of `kind` at the linearisation `l` (module docs).
fn test_gradient(kind: SpecialKind, l: &MapLinearisation) -> Result<Matrix2<f64>> {
    let (s_tr, s_det) = match kind {
        SpecialKind::Fold => (-1.0, 1.0),
        SpecialKind::Flip | SpecialKind::SymmetryBreaking => (1.0, 1.0),
        SpecialKind::NeimarkSacker => (0.0, 1.0),
        SpecialKind::Nonsmooth => {
            return Err(Error::UnsupportedPoint {
                operation: "the implicit-function gradient of a located point",
                kind: kind.label(),
            })
        }
    };
    let s_det = if l.events.sticks > 0 { 0.0 } else { s_det };
    let m = &l.jac;
    let cof = Matrix2::new(m[(1, 1)], -m[(1, 0)], -m[(0, 1)], m[(0, 0)]);
    Ok(Matrix2::identity() * s_tr + cof * s_det)
}

/// Σ_ij a_ij b_ij.
fn contract(a: &Matrix2<f64>, b: &Matrix2<f64>) -> f64 {
    a.component_mul(b).sum()
}

/// σ = √(gᵀ C g), the first-order standard deviation of a quantity with gradient `g` over
/// parameters of covariance `c` (the delta method).
pub fn linear_sigma(g: &[f64], c: &DMatrix<f64>) -> Result<f64> {
    if c.nrows() != g.len() || c.ncols() != g.len() {
        return Err(Error::shape(
            "covariance of the located point's parameters",
            format!("{0} × {0}", g.len()),
            c.nrows(),
        ));
    }
    let g = nalgebra::DVector::from_column_slice(g);
    Ok((g.transpose() * c * &g)[(0, 0)].max(0.0).sqrt())
}

#[cfg(test)]
#[path = "tests_sensitivity.rs"]
mod tests;
