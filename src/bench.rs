//! Work-precision comparison of integrators: any [`FlowMethod`] — gearbif's or your own — is run on
//! the same problem and measured against a tight event-driven reference (error, right-hand-side
//! evaluations, wall time). `gearbif bench-integrators` is a thin layer over [`work_precision`].
//!
//! ```
//! use gearbif::bench::{work_precision, Candidate, WorkPrecisionSetup};
//! use gearbif::integrator::{EventDriven, FixedStep};
//! use gearbif::model::Gear;
//! let gear = Gear::paper(25.0, 2.7).unwrap();
//! let fixed = FixedStep { steps_per_period: 400 };
//! let candidates = [
//!     Candidate::new(&EventDriven, 1e-8, "event-driven DP5"),
//!     Candidate::new(&fixed, 0.0, "fixed-step RK4"),
//! ];
//! let setup = WorkPrecisionSetup { min_time_s: 0.0, ..WorkPrecisionSetup::new([0.5, 2.0]) };
//! let points = work_precision(&gear, &setup, &candidates).unwrap();
//! assert!(points[0].error < points[1].error); // the exact method wins at far less work
//! ```

use crate::error::{finite, non_negative, positive, Error, Result};
use crate::integrator::{EventDriven853, Flow, FlowMethod, FlowOptions, Sensitivity};
use crate::model::DrivenOscillator;
use serde::{Deserialize, Serialize};
use std::hint::black_box;
use std::time::Instant;

/// One method at one setting, as it enters a work-precision diagram.
pub struct Candidate<'a, S: DrivenOscillator + ?Sized> {
    /// The method.
    pub method: &'a dyn FlowMethod<S>,
    /// Its tolerance (rtol = tol, atol = 1e-3·tol); ignored by fixed-step methods (pass 0).
    pub tol: f64,
    /// The series the point belongs to in tables and figures (e.g. "event-driven DP5").
    pub family: String,
}

impl<'a, S: DrivenOscillator + ?Sized> Candidate<'a, S> {
    /// A candidate.
    pub fn new(method: &'a dyn FlowMethod<S>, tol: f64, family: impl Into<String>) -> Self {
        Self {
            method,
            tol,
            family: family.into(),
        }
    }
}

/// The problem of a work-precision run: integrate from (0, x0) over `periods` drive periods.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WorkPrecisionSetup {
    /// Initial state (β, ω).
    pub x0: [f64; 2],
    /// Duration in drive periods (1 = one stroboscopic map).
    pub periods: f64,
    /// Record a sample at every whole drive period (the strobe of a simulation), as a user
    /// watching the stroboscopic map does; the samples do not change the steps.
    pub strobe: bool,
    /// Jacobians to propagate (and compare).
    pub sensitivity: Sensitivity,
    /// Tolerance of the event-driven reference (DOP853).
    pub reference_tol: f64,
    /// Each point is timed in batches of calls until this much wall time has passed, s; the fastest
    /// batch counts (0: a single call).
    pub min_time_s: f64,
}

impl WorkPrecisionSetup {
    /// One period from `x0` with the state Jacobian, reference at tol 1e-13, 0.05 s per point.
    pub fn new(x0: [f64; 2]) -> Self {
        Self {
            x0,
            periods: 1.0,
            strobe: false,
            sensitivity: Sensitivity::State,
            reference_tol: 1e-13,
            min_time_s: 0.05,
        }
    }
    fn validate(&self) -> Result<()> {
        finite("x0 beta", self.x0[0])?;
        finite("x0 omega", self.x0[1])?;
        positive("periods", self.periods)?;
        positive("reference_tol", self.reference_tol)?;
        non_negative("min_time_s", self.min_time_s)?;
        Ok(())
    }
}

/// One point of a work-precision diagram.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WorkPrecisionPoint {
    /// Series (from [`Candidate::family`]).
    pub family: String,
    /// The method's own name (includes its settings).
    pub method: String,
    /// Tolerance used (0 for fixed-step methods).
    pub tol: f64,
    /// max(|Δβ|, |Δω|) at the end against the reference.
    pub error: f64,
    /// Largest entry of |J − J_ref| over max(1, largest |J_ref|), if Jacobians were compared.
    pub jac_error: Option<f64>,
    /// Right-hand-side evaluations of one call.
    pub rhs_evals: usize,
    /// Accepted steps of one call.
    pub steps: usize,
    /// Wall time of one call, s: the mean over the fastest batch of calls.
    pub time_s: f64,
    /// Calls timed.
    pub repeats: usize,
}

/// The event-driven reference flow of a setup.
pub fn reference<S: DrivenOscillator + ?Sized>(
    sys: &S,
    setup: &WorkPrecisionSetup,
) -> Result<Flow> {
    setup.validate()?;
    let t1 = setup.periods * sys.period();
    let opts = FlowOptions::with_tol(setup.reference_tol).sensitivity(setup.sensitivity);
    EventDriven853.flow(sys, 0.0, setup.x0, t1, &opts)
}

/// Runs every candidate on the setup and measures it against the event-driven reference.
///
/// A candidate that fails (e.g. a step-size underflow) is an error naming it.
pub fn work_precision<S: DrivenOscillator + ?Sized>(
    sys: &S,
    setup: &WorkPrecisionSetup,
    candidates: &[Candidate<'_, S>],
) -> Result<Vec<WorkPrecisionPoint>> {
    let refflow = reference(sys, setup)?;
    let t1 = setup.periods * sys.period();
    let strobe: Vec<f64> = if setup.strobe {
        (0..=setup.periods.floor() as usize)
            .map(|i| i as f64 * sys.period())
            .collect()
    } else {
        Vec::new()
    };
    let mut out = Vec::with_capacity(candidates.len());
    for c in candidates {
        let tol = if c.tol > 0.0 { c.tol } else { 1e-9 };
        let opts = FlowOptions::with_tol(tol)
            .sensitivity(setup.sensitivity)
            .samples(strobe.clone());
        let name = c.method.name();
        let wrap = |e: Error| Error::Integration {
            t: 0.0,
            reason: format!("{name} (tol {tol:e}): {e}"),
        };
        let first = c.method.flow(sys, 0.0, setup.x0, t1, &opts).map_err(wrap)?;
        let error = (first.x[0] - refflow.x[0])
            .abs()
            .max((first.x[1] - refflow.x[1]).abs());
        let jac_error = match (first.jac_x, refflow.jac_x) {
            (Some(j), Some(r)) => Some((j - r).amax() / r.amax().max(1.0)),
            _ => None,
        };
        // time: batches of calls (each ≥ ~1 ms) until min_time_s has passed; the fastest batch
        // counts, which filters out interference from other processes on a shared machine
        let once = {
            let s0 = Instant::now();
            black_box(
                c.method
                    .flow(sys, 0.0, black_box(setup.x0), t1, &opts)
                    .map_err(wrap)?,
            );
            s0.elapsed().as_secs_f64()
        };
        let per_batch = ((1e-3 / once.max(1e-9)).ceil() as usize).clamp(1, 10_000);
        let mut repeats = 1usize;
        let mut best = once;
        let start = Instant::now();
        while start.elapsed().as_secs_f64() < setup.min_time_s && repeats < 1_000_000 {
            let b0 = Instant::now();
            for _ in 0..per_batch {
                let f = c
                    .method
                    .flow(sys, 0.0, black_box(setup.x0), t1, &opts)
                    .map_err(wrap)?;
                black_box(&f);
            }
            best = best.min(b0.elapsed().as_secs_f64() / per_batch as f64);
            repeats += per_batch;
        }
        let time_s = best;
        out.push(WorkPrecisionPoint {
            family: c.family.clone(),
            method: name.clone(),
            tol: c.tol,
            error,
            jac_error,
            rhs_evals: first.stats.rhs_evals,
            steps: first.stats.steps,
            time_s,
            repeats,
        });
    }
    Ok(out)
}

/// Wall time of `evals` right-hand-side evaluations alone (the forces, or their jet when
/// `jet` is true), at times spread over one period: the floor any integrator pays, s.
/// The fastest of several repetitions counts.
pub fn rhs_only_time<S: DrivenOscillator + ?Sized>(
    sys: &S,
    x: [f64; 2],
    evals: usize,
    jet: bool,
) -> f64 {
    let dt = sys.period() / evals.max(1) as f64;
    let mut best = f64::INFINITY;
    for _ in 0..20 {
        let start = Instant::now();
        let mut acc = 0.0;
        for i in 0..evals {
            let t = black_box(i as f64 * dt);
            if jet {
                let j = sys.forces_jet(t, black_box(x[0]), black_box(x[1]), false);
                acc += j.a + j.a_beta;
            } else {
                acc += sys.forces(t, black_box(x[0]), black_box(x[1])).a;
            }
        }
        black_box(acc);
        best = best.min(start.elapsed().as_secs_f64());
    }
    best
}

/// The points as CSV with header
/// `family,method,tol,error,jac_error,rhs_evals,steps,time_s,repeats`.
pub fn to_csv(points: &[WorkPrecisionPoint]) -> String {
    let mut s = String::from("family,method,tol,error,jac_error,rhs_evals,steps,time_s,repeats\n");
    for p in points {
        let q = |t: &str| format!("\"{}\"", t.replace('"', "'"));
        s += &format!(
            "{},{},{:e},{:e},{},{},{},{:e},{}\n",
            q(&p.family),
            q(&p.method),
            p.tol,
            p.error,
            p.jac_error.map(|e| format!("{e:e}")).unwrap_or_default(),
            p.rhs_evals,
            p.steps,
            p.time_s,
            p.repeats
        );
    }
    s
}

/// The work-precision figure: log₁₀ error against log₁₀ wall time, one series per family.
#[cfg(feature = "plot")]
pub fn figure(points: &[WorkPrecisionPoint], title: &str) -> crate::plotting::LinePlot {
    use crate::plotting::{LinePlot, Series};
    let mut families: Vec<&str> = Vec::new();
    for p in points {
        if !families.contains(&p.family.as_str()) {
            families.push(&p.family);
        }
    }
    let series = families
        .iter()
        .enumerate()
        .flat_map(|(i, f)| {
            let mut pts: Vec<(f64, f64)> = points
                .iter()
                .filter(|p| p.family == *f)
                .filter(|p| p.time_s > 0.0)
                .map(|p| (p.time_s.log10(), p.error.max(1e-17).log10()))
                .collect();
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            [
                Series {
                    label: f.to_string(),
                    points: pts.clone(),
                    markers: false,
                    color: i,
                },
                Series {
                    label: String::new(),
                    points: pts,
                    markers: true,
                    color: i,
                },
            ]
        })
        .collect();
    LinePlot {
        title: title.to_string(),
        x_label: "log10 of wall time per call [s]".into(),
        y_label: "log10 of max error of (β, ω) vs reference".into(),
        series,
        ..Default::default()
    }
}
