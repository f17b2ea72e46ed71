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
//! **The bordered Jacobian from two or three map evaluations.** The first two rows of G_x, G_λ,
//! G_p are the map's Jacobian M − I and its analytic parameter columns ∂Pᵏ/∂q. The ψ row needs
//! ∂M/∂x and ∂M/∂q, second derivatives of the map. With D = ∂ψ/∂M = s_tr I + s_det cof(M) (the
//! sign pair of the kind; det M ≡ 0 with a stick phase, [`crate::orbits::Floquet::of_orbit`], so
//! then s_det = 0) written as its singular value decomposition D = Σ_k d_k u_k v_kᵀ, and with the
//! symmetry of second derivatives (∂M_ij/∂x_m = ∂M_im/∂x_j, ∂M_ij/∂q = ∂(∂P_i/∂q)/∂x_j),
//!
//! ```text
//!   ∂ψ/∂x_m = Σ_k d_k (u_kᵀ D_{v_k} M)_m,   ∂ψ/∂q = Σ_k d_k u_kᵀ D_{v_k}(∂Pᵏ/∂q),
//! ```
//!
//! with D_v the derivative along v, a forward difference of the linearisation at x + h v. At a
//! fold or a flip without sticking D is the cofactor matrix of M ∓ I, of rank one at the point (its
//! second singular value is |ψ|/d_1, zero to the locating tolerance), so one direction suffices:
//! the whole Jacobian costs two linearisations of the map with the columns of λ and of every p,
//! whatever the number of parameters (three for a Neimark–Sacker point or with a stick phase).

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

/// Singular values of ∂ψ/∂M below this fraction of the largest are dropped: at a located fold or
/// flip the second one is |ψ|/d_1, of the order of the locating tolerance.
const RANK_TOL: f64 = 1e-6;

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
    let at = |y: [f64; 2]| linearise_map(method, &sys, spec, y, &cols, opts);
    let l0 = at(x)?;
    let scale = [1.0, x[1].abs().max(1.0)];
    // ψ row: Σ_k d_k u_kᵀ D_{v_k}(·) of M (per x_m) and of every column (module docs)
    let mut dpsi_dx = [0.0; 2];
    let mut dpsi_dq = vec![0.0; cols.len()];
    for (d, u, v) in directions(&test_gradient(kind, &l0)?) {
        let h = STEP
            * (0..2)
                .map(|i| scale[i] / v[i].abs())
                .fold(f64::INFINITY, f64::min);
        let lv = at([x[0] + h * v[0], x[1] + h * v[1]])?;
        let dm = (lv.jac - l0.jac) / h;
        for (m, out) in dpsi_dx.iter_mut().enumerate() {
            *out += d * (u[0] * dm[(0, m)] + u[1] * dm[(1, m)]);
        }
        for (q, out) in dpsi_dq.iter_mut().enumerate() {
            let dc = [0, 1].map(|i| (lv.columns[q][i] - l0.columns[q][i]) / h);
            *out += d * (u[0] * dc[0] + u[1] * dc[1]);
        }
    }
    let a = Matrix3::new(
        l0.jac[(0, 0)] - 1.0,
        l0.jac[(0, 1)],
        l0.columns[0][0],
        l0.jac[(1, 0)],
        l0.jac[(1, 1)] - 1.0,
        l0.columns[0][1],
        dpsi_dx[0],
        dpsi_dx[1],
        dpsi_dq[0],
    );
    let lu = a.lu();
    (1..cols.len())
        .map(|q| {
            let gp = Vector3::new(l0.columns[q][0], l0.columns[q][1], dpsi_dq[q]);
            lu.solve(&(-gp)).map(|z| z[2]).ok_or(Error::SingularMatrix {
                what:
                    "bordered Jacobian [G_x G_λ] of the located point (implicit-function theorem)",
            })
        })
        .collect()
}

/// The terms (d_k, u_k, v_k) of the singular value decomposition of `dm` whose d_k exceeds
/// [`RANK_TOL`] of the largest (module docs).
fn directions(dm: &Matrix2<f64>) -> Vec<(f64, [f64; 2], [f64; 2])> {
    let svd = dm.svd(true, true);
    let (Some(u), Some(vt)) = (svd.u, svd.v_t) else {
        return Vec::new();
    };
    let top = svd.singular_values.max();
    (0..2)
        .filter(|&k| svd.singular_values[k] > RANK_TOL * top)
        .map(|k| {
            (
                svd.singular_values[k],
                [u[(0, k)], u[(1, k)]],
                [vt[(k, 0)], vt[(k, 1)]],
            )
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
