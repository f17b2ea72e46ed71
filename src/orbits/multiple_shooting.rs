//! Multiple shooting for strongly unstable periodic orbits.
//!
//! The orbit's map (Pᵏ over the duration D = k·T or k·T/2) is split at the times t_i = i·D/m into m
//! segments with their own initial states x_i; the unknowns are (x₀, …, x_{m−1}) and the equations
//!
//! ```text
//!   E_i = φ(t_{i+1}; t_i, x_i) − x_{i+1} = 0           (i < m − 1)
//!   E_{m−1} = R⁻ᵏ φ(t_m; t_{m−1}, x_{m−1}) − x₀ − (s, 0) = 0
//! ```
//!
//! with φ the flow, R the half-period symmetry (identity for P_T) and s the winding shift of
//! [`OrbitSpec::shift`]. Newton's matrix is cyclic block-bidiagonal (segment Jacobians B_i and −I);
//! it is solved by the structured elimination of [`super::block_cyclic`], never through the
//! monodromy product B_{m−1}⋯B₀, which for an orbit with multiplier μ has condition number ~|μ|
//! (single shooting loses log₁₀|μ| digits; at Θ = 0, 0.2 Hz on the unstable lock, |μ_G| ≈ 1e18).
//! The multipliers are those of the product, computed from its trace and determinant
//! ([`Floquet::of_orbit`]): the large one to relative rounding accuracy, the small one as det/μ₁.
//! The segments are integrated by the default integrator, the event-driven DOP853
//! ([`crate::integrator::DEFAULT_METHOD`]), as single shooting and the continuation.

use super::block_cyclic::CyclicBlockSystem;
use super::{EventCounts, Floquet, OrbitSpec, PeriodicOrbit, ShootingOptions};
use crate::error::{Error, Result};
use crate::integrator::{initial_mode, vector_field, FlowMethod, FlowOptions, DEFAULT_METHOD};
use crate::maps::{MapImage, Section};
use crate::model::DrivenOscillator;
use nalgebra::{DMatrix, DVector, Matrix2};
use serde::{Deserialize, Serialize};

/// A periodic orbit found by multiple shooting: the states at the segment boundaries.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MultipleShootingOrbit {
    /// States x_i at t_i = i·D/m (x₀ at t = 0 is the orbit's point on the section).
    pub states: Vec<[f64; 2]>,
    /// The fixed-point problem solved.
    pub spec: OrbitSpec,
    /// Floquet data of the orbit's map (the product of the segment Jacobians).
    pub floquet: Floquet,
    /// Events per application of the orbit's map (all segments).
    pub events: EventCounts,
    /// Final residual max_i |E_i|.
    pub residual: f64,
    /// Newton iterations used.
    pub newton_iterations: usize,
    /// Largest norm of a segment Jacobian (the growth a segment has to carry).
    pub max_segment_growth: f64,
}

impl MultipleShootingOrbit {
    /// The same orbit in the single-shooting result type (state x₀, same multipliers and residual).
    pub fn to_periodic_orbit(&self) -> PeriodicOrbit {
        PeriodicOrbit {
            x: self.states[0],
            spec: self.spec,
            floquet: self.floquet,
            events: self.events,
            residual: self.residual,
            newton_iterations: self.newton_iterations,
        }
    }
}

/// All segments evaluated at one set of states.
#[derive(Debug, Clone)]
pub struct Segments {
    /// Segment images: `x` = end state (after R⁻ᵏ for the last segment), `jac_x` = B_i,
    /// `jac_p` = total parameter derivatives of the end state (with the dependence of t_i, t_{i+1}
    /// on the period), if requested.
    pub images: Vec<MapImage>,
    /// E_i, one per segment.
    pub residuals: Vec<[f64; 2]>,
}

impl Segments {
    /// max_i |E_i|.
    pub fn residual_norm(&self) -> f64 {
        self.residuals
            .iter()
            .map(|r| r[0].hypot(r[1]))
            .fold(0.0, f64::max)
    }
    /// The monodromy B_{m−1}⋯B₀ (Jacobian of the orbit's map), if Jacobians were computed.
    pub fn monodromy(&self) -> Option<Matrix2<f64>> {
        self.images
            .iter()
            .try_fold(Matrix2::identity(), |acc, img| img.jac_x.map(|b| b * acc))
    }
    /// Events summed over the segments (needs events recorded).
    pub fn events(&self) -> EventCounts {
        self.images
            .iter()
            .map(EventCounts::from_image)
            .fold(EventCounts::default(), |a, e| EventCounts {
                crossings: a.crossings + e.crossings,
                sticks: a.sticks + e.sticks,
                grazes: a.grazes + e.grazes,
            })
    }
    /// Floquet data of the monodromy.
    pub fn floquet(&self) -> Option<Floquet> {
        self.monodromy()
            .map(|m| Floquet::of_orbit(&m, &self.events()))
    }
    /// Largest norm of a segment Jacobian.
    pub fn max_growth(&self) -> f64 {
        self.images
            .iter()
            .filter_map(|i| i.jac_x.map(|b| b.norm()))
            .fold(0.0, f64::max)
    }
}

/// Duration of the orbit's map, D = k·T (P_T) or k·T/2 (G), and the segment boundaries t_i = i·D/m.
pub fn segment_times<S: DrivenOscillator + ?Sized>(
    sys: &S,
    spec: &OrbitSpec,
    m: usize,
) -> Vec<f64> {
    let d = spec.periods() * sys.period();
    (0..=m).map(|i| d * i as f64 / m as f64).collect()
}

/// Evaluates the segments at `states` (with state and parameter Jacobians).
pub fn evaluate<S: DrivenOscillator + ?Sized>(
    sys: &S,
    spec: &OrbitSpec,
    states: &[[f64; 2]],
    opts: &ShootingOptions,
    events: bool,
) -> Result<Segments> {
    let m = states.len();
    if m == 0 {
        return Err(Error::shape("multiple-shooting segments", ">= 1", 0));
    }
    for x in states {
        crate::error::finite_state("segment state", x)?;
    }
    let s = spec.shift(sys)?;
    let sym = match spec.section {
        Section::Stroboscopic => None,
        Section::HalfPeriod => Some(
            sys.half_period_symmetry()
                .ok_or(Error::NoHalfPeriodSymmetry)?,
        ),
    };
    let times = segment_times(sys, spec, m);
    // dt_i/dp = (t_i / T) dT/dp for parameters that change the period
    let np = sys.n_params();
    let dperiod: Vec<f64> = (0..np).map(|c| sys.period_derivative(c)).collect();
    let t_per = sys.period();
    let flow_opts: FlowOptions = opts.flow(events);
    let mut images = Vec::with_capacity(m);
    let mut residuals = Vec::with_capacity(m);
    for i in 0..m {
        let (t0, t1) = (times[i], times[i + 1]);
        let fl = DEFAULT_METHOD.flow(sys, t0, states[i], t1, &flow_opts)?;
        let mut jac_x = fl.jac_x;
        let mut jac_p = fl.jac_p;
        if let (Some(jp), Some(jx)) = (jac_p.as_mut(), jac_x.as_ref()) {
            let f1 = vector_field(sys, t1, fl.x, fl.mode);
            let f0 = vector_field(sys, t0, states[i], initial_mode(sys, t0, states[i]));
            let jf0 = jx * nalgebra::Vector2::from(f0);
            for c in 0..jp.ncols().min(np) {
                let (d0, d1) = (t0 / t_per * dperiod[c], t1 / t_per * dperiod[c]);
                jp[(0, c)] += f1[0] * d1 - jf0[0] * d0;
                jp[(1, c)] += f1[1] * d1 - jf0[1] * d0;
            }
        }
        let mut xe = fl.x;
        let (target, shift) = if i + 1 == m {
            if let Some(r) = sym {
                for _ in 0..spec.iterations {
                    xe = r.invert(xe);
                }
                let sg = r.sign.powi(spec.iterations as i32);
                if let Some(j) = jac_x.as_mut() {
                    *j *= sg;
                }
                if let Some(j) = jac_p.as_mut() {
                    *j *= sg;
                }
            }
            (states[0], s)
        } else {
            (states[i + 1], 0.0)
        };
        let r = [xe[0] - target[0] - shift, xe[1] - target[1]];
        if !(r[0].is_finite() && r[1].is_finite()) {
            return Err(Error::NewtonFailed {
                iterations: 0,
                residual: f64::NAN,
                reason: format!("non-finite image of segment {i}"),
            });
        }
        residuals.push(r);
        images.push(MapImage {
            x: xe,
            mode: fl.mode,
            jac_x,
            jac_p,
            events: fl.events,
            stats: fl.stats,
        });
    }
    Ok(Segments { images, residuals })
}

/// Initial segment states by integrating from x₀ (usable while the orbit's multipliers are moderate,
/// e.g. at the hand-over from single shooting).
pub fn segment_states<S: DrivenOscillator + ?Sized>(
    sys: &S,
    spec: &OrbitSpec,
    x0: [f64; 2],
    m: usize,
    tol: f64,
) -> Result<Vec<[f64; 2]>> {
    if m == 0 {
        return Err(Error::shape("multiple-shooting segments", ">= 1", 0));
    }
    let times = segment_times(sys, spec, m);
    let o = FlowOptions::with_tol(tol);
    let mut out = vec![x0];
    let mut x = x0;
    for i in 0..m - 1 {
        x = DEFAULT_METHOD.flow(sys, times[i], x, times[i + 1], &o)?.x;
        out.push(x);
    }
    Ok(out)
}

/// Doubles the number of segments: each segment is split at its midpoint by integrating from x_i.
pub fn refine<S: DrivenOscillator + ?Sized>(
    sys: &S,
    spec: &OrbitSpec,
    states: &[[f64; 2]],
    tol: f64,
) -> Result<Vec<[f64; 2]>> {
    let m = states.len();
    let times = segment_times(sys, spec, 2 * m);
    let o = FlowOptions::with_tol(tol);
    let mut out = Vec::with_capacity(2 * m);
    for (i, x) in states.iter().enumerate() {
        out.push(*x);
        out.push(
            DEFAULT_METHOD
                .flow(sys, times[2 * i], *x, times[2 * i + 1], &o)?
                .x,
        );
    }
    Ok(out)
}

/// Newton's matrix of the segments (no free parameter) as a cyclic block system.
fn state_system(seg: &Segments) -> Result<CyclicBlockSystem> {
    let m = seg.images.len();
    let diagonal = seg
        .images
        .iter()
        .map(|img| {
            img.jac_x
                .map(|b| DMatrix::from_column_slice(2, 2, b.as_slice()))
                .ok_or(Error::MissingJacobian { what: "state" })
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(CyclicBlockSystem {
        diagonal,
        param_columns: vec![DMatrix::zeros(2, 0); m],
        border_state: DMatrix::zeros(0, 2),
        border_param: DMatrix::zeros(0, 0),
    })
}

/// Newton's method on the multiple-shooting equations from the segment states `states0` (m = their
/// number), with step halving on the residual. The linear systems are solved by structured
/// elimination with partial pivoting ([`CyclicBlockSystem::solve`]).
pub fn shoot_multiple<S: DrivenOscillator + ?Sized>(
    sys: &S,
    spec: &OrbitSpec,
    states0: &[[f64; 2]],
    opts: &ShootingOptions,
) -> Result<MultipleShootingOrbit> {
    let mut y = states0.to_vec();
    let mut seg = evaluate(sys, spec, &y, opts, true)?;
    let mut rn = seg.residual_norm();
    for it in 0..=opts.max_iter {
        let a = state_system(&seg)?;
        let rhs: Vec<DVector<f64>> = seg
            .residuals
            .iter()
            .map(|r| DVector::from_vec(vec![-r[0], -r[1]]))
            .collect();
        let dy = a.solve(&rhs, &DVector::zeros(0))?;
        let sn = dy.states.iter().map(|d| d.amax()).fold(0.0, f64::max);
        if rn < opts.newton_tol && sn < opts.newton_tol.max(1e-12) * 10.0 {
            let floquet = seg
                .floquet()
                .ok_or(Error::MissingJacobian { what: "state" })?;
            return Ok(MultipleShootingOrbit {
                states: y,
                spec: *spec,
                floquet,
                events: seg.events(),
                residual: rn,
                newton_iterations: it,
                max_segment_growth: seg.max_growth(),
            });
        }
        if it == opts.max_iter {
            break;
        }
        let mut lam = 1.0;
        let mut accepted = false;
        for _ in 0..8 {
            let yt: Vec<[f64; 2]> = y
                .iter()
                .zip(&dy.states)
                .map(|(x, d)| [x[0] + lam * d[0], x[1] + lam * d[1]])
                .collect();
            if let Ok(st) = evaluate(sys, spec, &yt, opts, true) {
                let rt = st.residual_norm();
                if rt < rn || rn < opts.newton_tol * 10.0 {
                    y = yt;
                    seg = st;
                    rn = rt;
                    accepted = true;
                    break;
                }
            }
            lam *= 0.5;
        }
        if !accepted {
            return Err(Error::NewtonFailed {
                iterations: it,
                residual: rn,
                reason: "multiple shooting: no descent along the Newton direction".into(),
            });
        }
    }
    Err(Error::NewtonFailed {
        iterations: opts.max_iter,
        residual: rn,
        reason: "multiple shooting did not converge".into(),
    })
}

/// The number of segments for an orbit whose map has spectral radius `rho`: each segment carries at
/// most a factor `max_growth` (at least 2 segments).
pub fn segments_for(rho: f64, max_growth: f64) -> usize {
    if !(rho > 1.0 && max_growth > 1.0) {
        return 2;
    }
    ((rho.ln() / max_growth.ln()).ceil() as usize).max(2)
}
