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

use super::codim2::Codim2Point;
use super::minaug::linearise_map;
use super::SpecialKind;
use crate::error::{Error, Result};
use crate::integrator::{FlowMethod, DEFAULT_METHOD};
use crate::model::{Gear, GearParam, Parameter, Parametrised};
use crate::numerics::{newton, Linearisation, NewtonOptions};
use crate::orbits::{EventCounts, Floquet, OrbitSpec, ShootingOptions};
use nalgebra::{Matrix3, Vector3};
use serde::de::DeserializeOwned;
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

/// Why a two-parameter curve stopped before the last requested value.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "reason")]
pub enum CurveStop {
    /// The augmented Newton failed at `along` = `at`, also after halving the step five times.
    NotConverged {
        /// The value of the stepped parameter.
        at: f64,
        /// The solver's error.
        error: String,
    },
    /// The solution lies far from the secant prediction: the Newton iteration jumped to another
    /// curve.
    Jumped {
        /// The value of the stepped parameter.
        at: f64,
        /// The free parameter found.
        free: f64,
        /// The free parameter predicted.
        predicted: f64,
    },
    /// Pseudo-arclength: the step fell below `ds_min` at (free, along).
    StepTooSmall {
        /// The free parameter at the last point.
        free: f64,
        /// The other parameter at the last point.
        along: f64,
        /// The smallest step allowed.
        ds_min: f64,
    },
    /// Pseudo-arclength: the curve reached a bound of a parameter's range.
    ParameterBound {
        /// The parameter's name.
        param: String,
        /// The bound.
        value: f64,
    },
    /// Pseudo-arclength: the largest number of steps was taken.
    MaxSteps {
        /// The number of steps.
        steps: usize,
    },
    /// Pseudo-arclength: a multiplier's modulus exceeded the limit at (free, along).
    MultiplierLimit {
        /// The spectral radius reached.
        modulus: f64,
        /// The free parameter at the last point.
        free: f64,
        /// The other parameter at the last point.
        along: f64,
    },
}

impl std::fmt::Display for CurveStop {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CurveStop::NotConverged { at, error } => write!(f, "at {at}: {error}"),
            CurveStop::Jumped {
                at,
                free,
                predicted,
            } => write!(
                f,
                "at {at}: solution {free} is far from the prediction {predicted} (another curve?)"
            ),
            CurveStop::StepTooSmall {
                free,
                along,
                ds_min,
            } => write!(
                f,
                "at ({free}, {along}): the arclength step fell below {ds_min}"
            ),
            CurveStop::ParameterBound { param, value } => {
                write!(f, "at the bound {param} = {value}")
            }
            CurveStop::MaxSteps { steps } => {
                write!(f, "after the largest number of steps, {steps}")
            }
            CurveStop::MultiplierLimit {
                modulus,
                free,
                along,
            } => write!(
                f,
                "at ({free}, {along}): a multiplier's modulus {modulus:.3e} exceeds the limit"
            ),
        }
    }
}

/// A two-parameter curve of special points.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(bound(
    serialize = "S::Param: Serialize",
    deserialize = "S::Param: DeserializeOwned"
))]
pub struct Curve<S: Parametrised = Gear> {
    /// Type of the special points.
    pub kind: SpecialKind,
    /// The parameter stepped along the curve.
    pub along: S::Param,
    /// The parameter solved for.
    pub free: S::Param,
    /// The orbit problem.
    pub spec: OrbitSpec,
    /// The points.
    pub points: Vec<CurvePoint>,
    /// Why the curve stopped before the last requested value, if it did.
    pub stopped: Option<CurveStop>,
    /// Codimension-two points and turning points located on the curve (pseudo-arclength curves
    /// only, [`super::palc2`]).
    #[serde(default)]
    pub codim2: Vec<Codim2Point>,
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

/// The orbit problem of one special point: everything but the unknowns.
struct Problem<'a, S: Parametrised, M> {
    method: &'a M,
    sys: &'a S,
    spec: &'a OrbitSpec,
    kind: SpecialKind,
    free: S::Param,
    opts: &'a ShootingOptions,
}

impl<S: Parametrised, M: FlowMethod<S>> Problem<'_, S, M> {
    fn eval(&self, u: &Vector3<f64>) -> Result<Eval> {
        let sys = self.sys.with_param(self.free, u[2])?;
        let lin = linearise_map(
            self.method,
            &sys,
            self.spec,
            [u[0], u[1]],
            &[self.free],
            self.opts,
        )?;
        let fq = lin.floquet();
        Ok(Eval {
            r: lin.residual,
            jac: lin.jac,
            fl: lin.columns[0],
            psi: test_value(self.kind, &fq),
            fq,
            events: lin.events,
        })
    }

    /// The augmented residual (F, ψ) and its Jacobian; the ψ row by forward differences.
    fn linearise(&self, u: &Vector3<f64>) -> Result<Linearisation<3, Eval>> {
        let e = self.eval(u)?;
        let hs = [
            1e-6,
            1e-6 * u[1].abs().max(1.0),
            1e-7 * u[2].abs().max(1e-2),
        ];
        let mut dpsi = [0.0; 3];
        for j in 0..3 {
            let mut up = *u;
            up[j] += hs[j];
            dpsi[j] = (self.eval(&up)?.psi - e.psi) / hs[j];
        }
        let jacobian = Matrix3::new(
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
        Ok(Linearisation {
            residual: Vector3::new(e.r[0], e.r[1], e.psi),
            jacobian,
            data: e,
        })
    }
}

/// Solves the augmented system for a special point of type `kind` of the orbit problem `spec` of
/// `sys`, with `free` the unknown parameter, from the guess (x0, λ0), with the event-driven
/// integrator.
pub fn locate_augmented<S: Parametrised>(
    sys: &S,
    spec: &OrbitSpec,
    kind: SpecialKind,
    free: S::Param,
    x0: [f64; 2],
    lambda0: f64,
    opts: &ShootingOptions,
) -> Result<CurvePoint> {
    locate_augmented_with(&DEFAULT_METHOD, sys, spec, kind, free, x0, lambda0, opts)
}

/// [`locate_augmented`] with the flow computed by `method`: Newton on (F, ψ) = 0 to
/// `opts.newton_tol`, the λ step capped at 20 % of λ.
#[allow(clippy::too_many_arguments)]
pub fn locate_augmented_with<S: Parametrised, M: FlowMethod<S>>(
    method: &M,
    sys: &S,
    spec: &OrbitSpec,
    kind: SpecialKind,
    free: S::Param,
    x0: [f64; 2],
    lambda0: f64,
    opts: &ShootingOptions,
) -> Result<CurvePoint> {
    crate::error::finite_state("start of the augmented Newton", &[x0[0], x0[1], lambda0])?;
    let problem = Problem {
        method,
        sys,
        spec,
        kind,
        free,
        opts,
    };
    let newton_opts = NewtonOptions {
        divergence_ratio: 4.0,
        ..NewtonOptions::new(opts.newton_tol, opts.max_iter)
    };
    let mut last_step = 0.0;
    let sol = newton(
        Vector3::new(x0[0], x0[1], lambda0),
        &newton_opts,
        |u| problem.linearise(u),
        |u, du| {
            last_step = du[2].abs();
            let cap = 0.2 * u[2].abs().max(0.1);
            if du[2].abs() > cap {
                cap / du[2].abs()
            } else {
                1.0
            }
        },
        &format!("augmented system for a {} point", kind.label()),
    )?;
    let e = &sol.at.data;
    let du = crate::numerics::newton::solve(&sol.at.jacobian, &(-sol.at.residual))
        .map(|d| d[2].abs())
        .unwrap_or(last_step);
    Ok(CurvePoint {
        along: f64::NAN,
        free: sol.x[2],
        x: [sol.x[0], sol.x[1]],
        floquet: e.fq,
        events: e.events,
        test_value: e.psi,
        precision: du + opts.newton_tol,
        newton_iterations: sol.iterations,
    })
}

/// The secant predictor of the next curve point at `v` from the last two points (or the start).
fn predict(pts: &[CurvePoint], start: ([f64; 2], f64), v: f64) -> ([f64; 2], f64) {
    match pts.len() {
        0 => start,
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
    }
}

/// Follows a special point of type `kind` along `along` (the values in `values`, in order), solving
/// for `free` each time with a secant predictor, with the event-driven integrator. Stops with a
/// reason at the first failure.
#[allow(clippy::too_many_arguments)]
pub fn follow<S: Parametrised>(
    sys: &S,
    spec: &OrbitSpec,
    kind: SpecialKind,
    free: S::Param,
    along: S::Param,
    x0: [f64; 2],
    free0: f64,
    values: &[f64],
    opts: &ShootingOptions,
) -> Result<Curve<S>> {
    follow_with(
        &DEFAULT_METHOD,
        sys,
        spec,
        kind,
        free,
        along,
        x0,
        free0,
        values,
        opts,
    )
}

/// [`follow`] with the flow computed by `method`.
#[allow(clippy::too_many_arguments)]
pub fn follow_with<S: Parametrised, M: FlowMethod<S>>(
    method: &M,
    sys: &S,
    spec: &OrbitSpec,
    kind: SpecialKind,
    free: S::Param,
    along: S::Param,
    x0: [f64; 2],
    free0: f64,
    values: &[f64],
    opts: &ShootingOptions,
) -> Result<Curve<S>> {
    check_curve_args(free, along, x0, free0)?;
    let mut pts: Vec<CurvePoint> = Vec::new();
    let mut stopped = None;
    'values: for (i, &v) in values.iter().enumerate() {
        // on failure, halve the step towards v (at most 5 times) before giving up
        let mut target = v;
        let mut halvings = 0;
        loop {
            let g = sys.with_param(along, target)?;
            let (xg, lg) = predict(&pts, (x0, free0), target);
            // a solution far from the prediction has jumped to another curve: treat it as a failure
            let res = locate_augmented_with(method, &g, spec, kind, free, xg, lg, opts).map(|p| {
                let far_x = (p.x[0] - xg[0]).abs() > 0.5
                    || (p.x[1] - xg[1]).abs() > 0.5 + 0.2 * xg[1].abs();
                if pts.len() >= 2 && ((p.free - lg).abs() > 0.1 * lg.abs().max(1e-2) || far_x) {
                    Err(CurveStop::Jumped {
                        at: target,
                        free: p.free,
                        predicted: lg,
                    })
                } else {
                    Ok(p)
                }
            });
            let res = match res {
                Ok(r) => r,
                Err(e) if pts.is_empty() => return Err(e),
                Err(e) => Err(CurveStop::NotConverged {
                    at: target,
                    error: e.to_string(),
                }),
            };
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
                Err(stop) => {
                    let last = pts.last().map(|p| p.along).unwrap_or(target);
                    if i == 0 || halvings >= 5 {
                        stopped = Some(stop);
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
        codim2: Vec::new(),
    })
}

/// Checks the arguments shared by the two-parameter curves ([`follow_with`] and
/// [`super::palc2::continue_curve`]): two different parameters and a finite start (x0, λ₁ = `free0`).
pub(crate) fn check_curve_args<P: Parameter>(
    free: P,
    along: P,
    x0: [f64; 2],
    free0: f64,
) -> Result<()> {
    if free == along {
        return Err(Error::inconsistent(
            "free, along",
            format!(
                "the two parameters of a curve must differ (both are `{}`)",
                free.name()
            ),
        ));
    }
    crate::error::finite_state("start of a curve", &[x0[0], x0[1], free0])
}

/// One start of the lock-loss boundary f_c(Θ) for parallel shafts ([`lock_loss_starts`]).
pub(crate) struct LockLossStart {
    /// The winding p of the lock: +1 forward, −1 reversed.
    pub winding: i32,
    /// The gear at the start: Θ = 0 (p = +1) or 54.74° (p = −1, Δ = −1), f = f_c.
    pub gear: Gear,
    /// The symmetric orbit (half-period section) of winding p.
    pub spec: OrbitSpec,
    /// The start state (π/2, 2πp f_c).
    pub x0: [f64; 2],
    /// The analytic lock-loss frequency f_c (model.md).
    pub fc: f64,
    /// 54.74°: the end of the Θ range of both curves.
    pub theta_rev_deg: f64,
    /// A short label: "fold of the lock, winding +1".
    pub label: String,
}

/// The two starts of the lock-loss boundary, shared by [`lock_loss_boundary`] (natural
/// parameter) and [`super::palc2::lock_loss_curves`] (pseudo-arclength): the forward lock from
/// Θ = 0 and the reversed lock from Θ = 54.74°, each at the analytic f_c of `base`.
pub(crate) fn lock_loss_starts(base: &Gear) -> Result<[LockLossStart; 2]> {
    let fc = base
        .lock_loss_frequency()
        .ok_or(Error::NoLockLossFrequency {
            g: base.g,
            zeta: base.zeta,
            eta: base.eta,
        })?;
    let th_rev = crate::model::gear::cogging_free_parallel_angles()
        .2
        .to_degrees();
    let start = |p: i32, from: f64| -> Result<LockLossStart> {
        Ok(LockLossStart {
            winding: p,
            gear: base.with_param(GearParam::ThetaDeg, from)?.with_f(fc)?,
            spec: OrbitSpec::symmetric(p),
            x0: [FRAC_PI_2, p as f64 * TAU * fc],
            fc,
            theta_rev_deg: th_rev,
            label: format!("fold of the lock, winding {p:+}"),
        })
    };
    Ok([start(1, 0.0)?, start(-1, th_rev)?])
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
) -> Result<Vec<(String, Curve<Gear>)>> {
    if !(step_deg > 0.0 && step_deg.is_finite()) {
        return Err(Error::InvalidParameter {
            name: "step",
            value: step_deg,
            reason: "the Θ step must be finite and > 0",
        });
    }
    let mut out = Vec::new();
    for s in lock_loss_starts(base)? {
        let vals = grid(0.0, s.theta_rev_deg, step_deg, s.winding < 0);
        let c = follow(
            &s.gear,
            &s.spec,
            SpecialKind::Fold,
            GearParam::F,
            GearParam::ThetaDeg,
            s.x0,
            s.fc,
            &vals,
            opts,
        )?;
        out.push((s.label, c));
    }
    Ok(out)
}
