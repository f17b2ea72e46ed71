//! Special points as solutions of an augmented system, and their continuation in a second
//! parameter (two-parameter curves such as the lock-loss boundary f_c(Θ)).
//!
//! Unknowns (β, ω, λ) with λ the free parameter; equations
//!
//! ```text
//!   Pᵏ(x; λ) − x − (s, 0) = 0,   ψ(x, λ) = 0,
//! ```
//!
//! with ψ the test function of the special point (fold 1 − tr + det, flip/symmetry-breaking
//! 1 + tr + det, Neimark–Sacker det − 1). The first two rows of the Newton matrix are the map's
//! Jacobians (`jac_x`, `jac_p`); the row of ψ is a forward difference of the test function (ψ is
//! built from the Jacobian, so its derivative would need second-order sensitivities).
//! A curve is followed by natural continuation in the second parameter with a secant predictor.

use super::{Param, SpecialKind};
use crate::error::{Error, Result};
use crate::model::Gear;
use crate::orbits::{residual, EventCounts, Floquet, OrbitSpec, ShootingOptions};
use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};
use std::f64::consts::{FRAC_PI_2, TAU};

/// One solution of the augmented system.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CurvePoint {
    /// Value of the fixed (second) parameter.
    pub along: f64,
    /// Value of the free parameter at the special point.
    pub free: f64,
    /// State on the section.
    pub x: [f64; 2],
    /// Floquet data at the point.
    pub floquet: Floquet,
    /// Events per map.
    pub events: EventCounts,
    /// |ψ| at the solution.
    pub test_value: f64,
    /// Error estimate of `free` from the last Newton correction.
    pub precision: f64,
    /// Newton iterations used.
    pub newton_iterations: usize,
}

/// A two-parameter curve of special points.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Curve {
    /// Type of the special points.
    pub kind: SpecialKind,
    /// The parameter stepped along the curve.
    pub along: Param,
    /// The parameter solved for.
    pub free: Param,
    /// The orbit problem.
    pub spec: OrbitSpec,
    /// The points.
    pub points: Vec<CurvePoint>,
    /// Why the curve stopped before the last requested value, if it did.
    pub stopped: Option<String>,
}

fn test_value(kind: SpecialKind, f: &Floquet) -> f64 {
    match kind {
        SpecialKind::Fold => f.fold_test(),
        SpecialKind::Flip | SpecialKind::SymmetryBreaking => f.flip_test(),
        SpecialKind::NeimarkSacker | SpecialKind::Nonsmooth => f.ns_test(),
    }
}

struct Eval {
    r: [f64; 2],
    jac: nalgebra::Matrix2<f64>,
    fl: [f64; 2],
    psi: f64,
    fq: Floquet,
    events: EventCounts,
}

fn eval(
    gear: &Gear,
    spec: &OrbitSpec,
    kind: SpecialKind,
    free: Param,
    u: &Vector3<f64>,
    opts: &ShootingOptions,
) -> Result<Eval> {
    let sys = free.set(gear, u[2])?;
    let (r, img) = residual(&sys, spec, [u[0], u[1]], opts, true)?;
    let jac = img
        .jac_x
        .ok_or_else(|| Error::Continuation("map returned no Jacobian".into()))?;
    let fl = free.derivative(&img, u[2])?;
    let events = EventCounts::from_image(&img);
    let fq = Floquet::of_orbit(&jac, &events);
    Ok(Eval {
        r,
        jac,
        fl,
        psi: test_value(kind, &fq),
        fq,
        events,
    })
}

/// Solves the augmented system for a special point of type `kind` of the orbit problem `spec` of
/// `gear`, with `free` the unknown parameter, from the guess (x0, λ0).
pub fn locate_augmented(
    gear: &Gear,
    spec: &OrbitSpec,
    kind: SpecialKind,
    free: Param,
    x0: [f64; 2],
    lambda0: f64,
    opts: &ShootingOptions,
) -> Result<CurvePoint> {
    if !(x0[0].is_finite() && x0[1].is_finite() && lambda0.is_finite()) {
        return Err(Error::InvalidInput(
            "non-finite start of the augmented Newton".into(),
        ));
    }
    let mut u = Vector3::new(x0[0], x0[1], lambda0);
    let mut last = f64::INFINITY;
    for it in 0..opts.max_iter {
        let e = eval(gear, spec, kind, free, &u, opts)?;
        // forward differences of ψ
        let hs = [
            1e-6,
            1e-6 * u[1].abs().max(1.0),
            1e-7 * u[2].abs().max(1e-2),
        ];
        let mut dpsi = [0.0; 3];
        for j in 0..3 {
            let mut up = u;
            up[j] += hs[j];
            let ep = eval(gear, spec, kind, free, &up, opts)?;
            dpsi[j] = (ep.psi - e.psi) / hs[j];
        }
        let a = Matrix3::new(
            e.jac[(0, 0)] - 1.0,
            e.jac[(0, 1)],
            e.fl[0],
            e.jac[(1, 0)],
            e.jac[(1, 1)] - 1.0,
            e.fl[1],
            dpsi[0],
            dpsi[1],
            dpsi[2],
        );
        let du = a
            .lu()
            .solve(&Vector3::new(-e.r[0], -e.r[1], -e.psi))
            .filter(|d| d.iter().all(|v| v.is_finite()))
            .ok_or_else(|| Error::NewtonFailed {
                iterations: it,
                residual: e.r[0].hypot(e.r[1]).hypot(e.psi),
                reason: "singular augmented matrix (degenerate special point)".into(),
            })?;
        let rn = e.r[0].hypot(e.r[1]);
        if rn < opts.newton_tol && e.psi.abs() < 1e-9 && du.norm() < 1e-8 {
            return Ok(CurvePoint {
                along: f64::NAN,
                free: u[2],
                x: [u[0], u[1]],
                floquet: e.fq,
                events: e.events,
                test_value: e.psi,
                precision: du[2].abs() + opts.newton_tol,
                newton_iterations: it,
            });
        }
        let norm = rn.hypot(e.psi);
        if it > 3 && norm > 4.0 * last {
            break;
        }
        last = norm;
        // limit the step in λ to 20 % of its value
        let cap = 0.2 * u[2].abs().max(0.1);
        let scale = if du[2].abs() > cap {
            cap / du[2].abs()
        } else {
            1.0
        };
        u += scale * du;
        if let Param::F = free {
            if u[2] <= 0.0 {
                break;
            }
        }
    }
    Err(Error::NewtonFailed {
        iterations: opts.max_iter,
        residual: last,
        reason: format!("augmented system for a {} point", kind.label()),
    })
}

/// Follows a special point of type `kind` along `along` (the values in `values`, in order), solving
/// for `free` each time with a secant predictor. Stops with a reason at the first failure.
#[allow(clippy::too_many_arguments)]
pub fn follow(
    gear: &Gear,
    spec: &OrbitSpec,
    kind: SpecialKind,
    free: Param,
    along: Param,
    x0: [f64; 2],
    free0: f64,
    values: &[f64],
    opts: &ShootingOptions,
) -> Result<Curve> {
    if free == along {
        return Err(Error::InvalidInput(
            "the free and the stepped parameter must differ".into(),
        ));
    }
    let mut pts: Vec<CurvePoint> = Vec::new();
    let mut stopped = None;
    // predictor from the last two points (secant), or the start
    let predict = |pts: &[CurvePoint], v: f64| match pts.len() {
        0 => (x0, free0),
        1 => (pts[0].x, pts[0].free),
        n => {
            let (a, b) = (&pts[n - 2], &pts[n - 1]);
            let c = (v - b.along) / (b.along - a.along);
            (
                [
                    b.x[0] + c * (b.x[0] - a.x[0]),
                    b.x[1] + c * (b.x[1] - a.x[1]),
                ],
                b.free + c * (b.free - a.free),
            )
        }
    };
    'values: for (i, &v) in values.iter().enumerate() {
        // on failure, halve the step towards v (at most 5 times) before giving up
        let mut target = v;
        let mut halvings = 0;
        loop {
            let g = along.set(gear, target)?;
            let (xg, lg) = predict(&pts, target);
            // a solution far from the prediction has jumped to another curve: treat it as a failure
            let res = locate_augmented(&g, spec, kind, free, xg, lg, opts).and_then(|p| {
                let far_x = (p.x[0] - xg[0]).abs() > 0.5
                    || (p.x[1] - xg[1]).abs() > 0.5 + 0.2 * xg[1].abs();
                if pts.len() >= 2 && ((p.free - lg).abs() > 0.1 * lg.abs().max(1e-2) || far_x) {
                    Err(Error::Continuation(format!(
                        "solution {} = {} is far from the prediction {lg} (another curve?)",
                        free.name(),
                        p.free
                    )))
                } else {
                    Ok(p)
                }
            });
            match res {
                Ok(mut p) => {
                    p.along = target;
                    pts.push(p);
                    if target == v {
                        break;
                    }
                    target = v;
                    halvings = 0;
                }
                Err(e) => {
                    let Some(last) = pts.last().map(|p| p.along) else {
                        return Err(e);
                    };
                    if i == 0 || halvings >= 5 {
                        stopped = Some(format!("at {} = {target}: {e}", along.name()));
                        break 'values;
                    }
                    target = 0.5 * (last + target);
                    halvings += 1;
                }
            }
        }
    }
    Ok(Curve {
        kind,
        along,
        free,
        spec: *spec,
        points: pts,
        stopped,
    })
}

/// An inclusive grid from `lo` to `hi` with spacing `step` (the last step may be shorter), reversed if
/// asked.
pub fn grid(lo: f64, hi: f64, step: f64, reverse: bool) -> Vec<f64> {
    let n = ((hi - lo) / step).ceil().max(1.0) as usize;
    let mut v: Vec<f64> = (0..=n).map(|i| (lo + i as f64 * step).min(hi)).collect();
    v.dedup();
    if reverse {
        v.reverse();
    }
    v
}

/// The lock-loss boundary f_c(Θ) for parallel shafts: fold curves of the forward lock (p = +1, from Θ = 0) and of the reversed
/// lock (p = −1, from Θ = 54.74°), each started at the analytic f_c.
pub fn lock_loss_boundary(
    base: &Gear,
    step_deg: f64,
    opts: &ShootingOptions,
) -> Result<Vec<(String, Curve)>> {
    if !(step_deg > 0.0 && step_deg.is_finite()) {
        return Err(Error::InvalidInput("step must be > 0".into()));
    }
    let fc = base
        .lock_loss_frequency()
        .ok_or_else(|| Error::Unsupported("no lock-loss frequency (ζ = 0 or g ≤ η)".into()))?;
    let th_rev = crate::model::gear::cogging_free_parallel_angles()
        .2
        .to_degrees();
    let mut out = Vec::new();
    for (p, from) in [(1, 0.0), (-1, th_rev)] {
        let g = Param::ThetaDeg.set(base, from)?;
        let vals = grid(0.0, th_rev, step_deg, p < 0);
        let c = follow(
            &g.with_f(fc)?,
            &OrbitSpec::symmetric(p),
            SpecialKind::Fold,
            Param::F,
            Param::ThetaDeg,
            [FRAC_PI_2, p as f64 * TAU * fc],
            fc,
            &vals,
            opts,
        )?;
        out.push((format!("fold of the lock, winding {p:+}"), c));
    }
    Ok(out)
}
