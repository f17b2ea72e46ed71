//! The pieces shared by every Newton iteration on an orbit problem with free parameters, and the
//! minimally augmented test function of a codimension-one point.
//!
//! [`linearise_map`] evaluates the shooting residual F(x; λ) = Pᵏ(x; λ) − x − (s, 0), the map's
//! Jacobian M = ∂Pᵏ/∂x and the columns ∂F/∂λⱼ of the requested parameters (through the parameter
//! lens, [`crate::model::params`]); the continuation corrector, the augmented systems of
//! [`super::two_param`] and [`super::palc2`] and the pinned switching of [`super::pinned`] all use it.
//!
//! [`bordered_test`] is the test function of a minimally augmented system (Govaerts, *Numerical
//! Methods for Bifurcations of Dynamical Equilibria*, 2000, ch. 4): with A = M − σI (σ = +1 for a
//! fold, σ = −1 for a flip, and for a symmetry-breaking point of the half-period map G, where the
//! P_T-multiplier +1 of the antisymmetric mode is G's multiplier −1) and bordering vectors b, c
//! close to the left and right null vectors of A,
//!
//! ```text
//!   [ A   b ] [ v ]   [ 0 ]          [ Aᵀ  c ] [ w ]   [ 0 ]
//!   [ cᵀ  0 ] [ g ] = [ 1 ],         [ bᵀ  0 ] [ g ] = [ 1 ],
//! ```
//!
//! g = 0 exactly where A is singular; v and w are then its right and left null vectors. Unlike
//! det A, g is scaled like the smallest singular value of A, whatever the other multiplier.

use super::SpecialKind;
use crate::error::{Error, Result};
use crate::integrator::{FlowMethod, FlowOptions};
use crate::model::{param_derivative, Parametrised};
use crate::orbits::{residual_with, EventCounts, Floquet, OrbitSpec, ShootingOptions};
use nalgebra::{Matrix2, Matrix3, Vector2, Vector3};

/// F, ∂Pᵏ/∂x and the parameter columns of F at one point.
#[derive(Debug, Clone)]
pub struct MapLinearisation {
    /// The shooting residual F(x; λ).
    pub residual: [f64; 2],
    /// The map Jacobian M = ∂Pᵏ/∂x (F_x = M − I).
    pub jac: Matrix2<f64>,
    /// ∂F/∂λⱼ for the requested parameters, in order.
    pub columns: Vec<[f64; 2]>,
    /// Events per application of the orbit's map.
    pub events: EventCounts,
}

impl MapLinearisation {
    /// Floquet data of the orbit's map.
    pub fn floquet(&self) -> Floquet {
        Floquet::of_orbit(&self.jac, &self.events)
    }
}

/// Evaluates [`MapLinearisation`] of the problem `spec` of `sys` at `x` with the columns of
/// `params`, the flow computed by `method`.
pub fn linearise_map<S: Parametrised, M: FlowMethod<S>>(
    method: &M,
    sys: &S,
    spec: &OrbitSpec,
    x: [f64; 2],
    params: &[S::Param],
    opts: &ShootingOptions,
) -> Result<MapLinearisation> {
    let (residual, img) = residual_with(method, sys, spec, x, opts, true)?;
    let jac = img.jac_x.ok_or(Error::MissingJacobian { what: "state" })?;
    let jp = img
        .jac_p
        .as_ref()
        .ok_or(Error::MissingJacobian { what: "parameter" })?;
    let columns = params
        .iter()
        .map(|&p| param_derivative(sys, p, jp))
        .collect::<Result<Vec<_>>>()?;
    Ok(MapLinearisation {
        residual,
        jac,
        columns,
        events: EventCounts::from_image(&img),
    })
}

/// σ in A = M − σI for the special points that have a minimally augmented system.
pub fn critical_multiplier(kind: SpecialKind) -> Result<f64> {
    match kind {
        SpecialKind::Fold => Ok(1.0),
        SpecialKind::Flip | SpecialKind::SymmetryBreaking => Ok(-1.0),
        k => Err(Error::UnsupportedPoint {
            operation: "a minimally augmented system (fold, flip or symmetry-breaking only)",
            kind: k.label(),
        }),
    }
}

/// The bordered test function of A = `m` − σI with bordering vectors `b`, `c`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BorderedTest {
    /// The test function g (zero where A is singular).
    pub g: f64,
    /// Right vector v: A v = −g b, cᵀv = 1 (the null vector of A where g = 0).
    pub v: [f64; 2],
    /// Left vector w: Aᵀ w = −g c, bᵀw = 1.
    pub w: [f64; 2],
}

/// Solves the two bordered systems of the module doc for A = `m` − σI.
pub fn bordered_test(
    m: &Matrix2<f64>,
    sigma: f64,
    b: [f64; 2],
    c: [f64; 2],
) -> Result<BorderedTest> {
    let a = m - sigma * Matrix2::identity();
    let border = |a: &Matrix2<f64>, col: [f64; 2], row: [f64; 2]| {
        Matrix3::new(
            a[(0, 0)],
            a[(0, 1)],
            col[0],
            a[(1, 0)],
            a[(1, 1)],
            col[1],
            row[0],
            row[1],
            0.0,
        )
    };
    let rhs = Vector3::new(0.0, 0.0, 1.0);
    let solve = |mat: Matrix3<f64>| {
        mat.lu()
            .solve(&rhs)
            .filter(|s| s.iter().all(|z| z.is_finite()))
            .ok_or(Error::SingularMatrix {
                what: "bordered matrix (bordering vectors degenerate)",
            })
    };
    let r = solve(border(&a, b, c))?;
    let l = solve(border(&a.transpose(), c, b))?;
    Ok(BorderedTest {
        g: r[2],
        v: [r[0], r[1]],
        w: [l[0], l[1]],
    })
}

/// The grazing test function of an orbit: the smallest value of `side`·ω(t) over one drive period
/// (over the orbit's map if longer), from `x` on the section. It is positive while the orbit stays
/// on one side of Σ = {ω = 0}, and zero where it touches Σ with ω̇ = 0 there (grazing; for dry
/// friction with |a| ≤ r at the touch point, the onset of sticking). The minimum is found on 400
/// dense-output samples (two more past the end, so a minimum at the section is found inside the
/// window) and refined on 40 samples around the smallest; ω is then evaluated by the
/// flow at the vertex time of the parabola through the three smallest samples (error ½ω̈δt² from
/// the vertex time's error δt ~ ω‴h²/ω̈, h = T/16000, plus the integrator's).
pub fn grazing_margin<S: Parametrised, M: FlowMethod<S>>(
    method: &M,
    sys: &S,
    spec: &OrbitSpec,
    x: [f64; 2],
    side: f64,
    tol: f64,
) -> Result<f64> {
    let t1 = spec.periods() * sys.period();
    let sample = |a: f64, b: f64, n: usize| -> Result<Vec<(f64, f64)>> {
        let times: Vec<f64> = (0..=n).map(|i| a + (b - a) * i as f64 / n as f64).collect();
        let opts = FlowOptions::with_tol(tol).samples(times);
        let fl = method.flow(sys, 0.0, x, b, &opts)?;
        Ok(fl.samples.iter().map(|s| (s.t, side * s.omega)).collect())
    };
    let argmin = |v: &[(f64, f64)]| {
        (0..v.len())
            .min_by(|&i, &j| v[i].1.total_cmp(&v[j].1))
            .unwrap_or(0)
    };
    // two samples past the end, so that a minimum at t ≈ 0 ≡ t1 (mod the period) is interior
    let n = 400;
    let coarse = sample(0.0, t1 * (1.0 + 2.0 / n as f64), n + 2)?;
    let i = 1 + argmin(&coarse[1..=n]);
    let (a, b) = (coarse[i - 1].0, coarse[i + 1].0);
    let fine = sample(a, b, 40)?;
    let j = argmin(&fine);
    if j == 0 || j + 1 >= fine.len() {
        return Ok(fine[j].1);
    }
    let (y0, y1, y2) = (fine[j - 1].1, fine[j].1, fine[j + 1].1);
    let curv = y0 - 2.0 * y1 + y2;
    if curv <= 0.0 {
        return Ok(y1);
    }
    // the vertex time, then ω there from the flow's end point (not the dense output): an error δt
    // in the time costs only ½ω̈δt² at a minimum
    let h = fine[j].0 - fine[j - 1].0;
    let t_min = fine[j].0 + 0.5 * h * (y0 - y2) / curv;
    let fl = method.flow(sys, 0.0, x, t_min, &FlowOptions::with_tol(tol))?;
    Ok(side * fl.x[1])
}

/// The edge margin of one arrival on Σ: a(t, β, 0) − σ r_s(t, β) at the arrival's time `t`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArrivalEdge {
    /// The margin (zero where the arrival lies on the edge σ of the stick region).
    pub margin: f64,
    /// Time of the arrival.
    pub t: f64,
}

/// The arrivals on Σ (stick entries and crossings) of the orbit from `x` over the map's duration,
/// each with the side it arrives from.
fn arrivals<S: Parametrised, M: FlowMethod<S>>(
    method: &M,
    sys: &S,
    spec: &OrbitSpec,
    x: [f64; 2],
    tol: f64,
) -> Result<Vec<(crate::integrator::Event, f64)>> {
    use crate::integrator::EventKind;
    let t1 = spec.periods() * sys.period();
    let opts = FlowOptions::with_tol(tol).record_events(true);
    let fl = method.flow(sys, 0.0, x, t1, &opts)?;
    let mut side = crate::integrator::initial_mode(sys, 0.0, x).side();
    let mut out = Vec::new();
    for e in fl.events {
        match e.kind {
            EventKind::Crossing { to, .. } => {
                out.push((e, side));
                side = f64::from(to);
            }
            EventKind::StickStart => {
                out.push((e, side));
                side = 0.0;
            }
            EventKind::Release { to } => side = f64::from(to),
            EventKind::Graze { .. } => {}
        }
    }
    Ok(out)
}

/// The edge margin a − σ r_s of the orbit's arrival on Σ from side `edge.1` nearest in time to
/// `edge.2`, with `edge` = (σ, side, t_ref).
pub fn arrival_edge<S: Parametrised, M: FlowMethod<S>>(
    method: &M,
    sys: &S,
    spec: &OrbitSpec,
    x: [f64; 2],
    edge: (f64, f64, f64),
    tol: f64,
) -> Result<ArrivalEdge> {
    let (sigma, side, t_ref) = edge;
    let ev = arrivals(method, sys, spec, x, tol)?;
    let e = ev
        .iter()
        .filter(|(_, s)| *s == side)
        .map(|(e, _)| e)
        .min_by(|a, b| (a.t - t_ref).abs().total_cmp(&(b.t - t_ref).abs()))
        .ok_or(Error::NoArrival)?;
    Ok(ArrivalEdge {
        margin: sys.forces(e.t, e.beta, 0.0).a - sigma * sys.static_friction(e.t, e.beta),
        t: e.t,
    })
}

/// The arrival on Σ nearest to the edge between sticking and crossing: (σ, the side s it comes
/// from, its time), with σ = −s.
///
/// An arrival from side s (s·ω̇ = s·a − r ≤ 0) sticks while |a| ≤ r_s and crosses once
/// s·a < −r_s, so the only edge it can reach is a = −s r_s, with the margin a + s r_s; the
/// arrival with the smallest |a + s r_s| is chosen. Near such an edge, on its crossing side, the
/// orbit may return to Σ from the other side −s at once with a ≈ −s r_s (where r = r_s, as in the
/// gear, tangentially: −s·ω̇ = −s·a − r → 0). That return also has |a| ≈ r_s but is not an edge of
/// this kind: it exists only on one side of the edge (it disappears with the crossing), so a curve
/// that tracked it would correct the orbit across the edge onto a side where the tracked arrival
/// does not exist.
pub fn nearest_edge_arrival<S: Parametrised, M: FlowMethod<S>>(
    method: &M,
    sys: &S,
    spec: &OrbitSpec,
    x: [f64; 2],
    tol: f64,
) -> Result<(f64, f64, f64)> {
    let ev = arrivals(method, sys, spec, x, tol)?;
    let gap = |(e, side): &(crate::integrator::Event, f64)| {
        (sys.forces(e.t, e.beta, 0.0).a + side * sys.static_friction(e.t, e.beta)).abs()
    };
    let (e, side) = ev
        .iter()
        .filter(|(_, side)| *side != 0.0)
        .min_by(|a, b| gap(a).total_cmp(&gap(b)))
        .ok_or(Error::NoArrival)?;
    Ok((-side, *side, e.t))
}

/// Unit vector along `v` (unchanged if it is zero or not finite).
pub fn unit(v: [f64; 2]) -> [f64; 2] {
    let n = Vector2::from(v).norm();
    if n > 0.0 && n.is_finite() {
        [v[0] / n, v[1] / n]
    } else {
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bordered_test_vanishes_exactly_at_a_singular_matrix_and_gives_its_null_vectors() {
        // M has eigenvalues 1 and 0.3: A = M − I singular, null vectors known
        let p = Matrix2::new(1.0, 0.4, 0.2, 1.0);
        let m = p * Matrix2::new(1.0, 0.0, 0.0, 0.3) * p.try_inverse().unwrap();
        let t = bordered_test(&m, 1.0, [0.3, 0.9], [1.0, 0.1]).unwrap();
        assert!(t.g.abs() < 1e-14, "g = {}", t.g);
        let a = m - Matrix2::identity();
        let v = Vector2::from(t.v);
        let w = Vector2::from(t.w);
        assert!((a * v).norm() < 1e-14 && (a.transpose() * w).norm() < 1e-14);
        // away from singularity g changes sign with the eigenvalue through 1, like det(A)
        let m2 = p * Matrix2::new(1.1, 0.0, 0.0, 0.3) * p.try_inverse().unwrap();
        let m3 = p * Matrix2::new(0.9, 0.0, 0.0, 0.3) * p.try_inverse().unwrap();
        let g2 = bordered_test(&m2, 1.0, t.w, t.v).unwrap().g;
        let g3 = bordered_test(&m3, 1.0, t.w, t.v).unwrap().g;
        assert!(g2 * g3 < 0.0);
        // first order in the eigenvalue's distance from 1: g(1.1) ≈ −g(0.9)
        assert!((g2 + g3).abs() < 0.1 * g2.abs(), "{g2} {g3}");
    }
}
