//! The report of a recorded gear (`gearbif report --model FILE`): your gear against the nominal
//! one. From the model file ([`crate::model::recorded::file`]):
//!
//! 1. the locked orbit (one output turn per drive turn) found by simulation at the lowest
//!    frequency and continued up in f on the stroboscopic section P_T until it loses lock at a
//!    fold, f_c, with every special point on the way (the bifurcation diagram of the lock branch
//!    at the recorded set-up);
//! 2. each special point re-located on its augmented system and given its σ from the file's
//!    covariance ([`located_sigma`]: the implicit-function theorem, docs/recorded_gear.md);
//! 3. the effect table ([`shifts`]): each accepted effect switched off in turn, and all of them
//!    together (the nominal gear), the points followed there, Δλ ± σ;
//! 4. where the file carries its recorded range, a sentence for each limit far outside it.
//!
//! The text is [`text`].

pub mod shifts;
pub mod text;

use crate::analysis::uncertainty::{located_sigma, LocatedSigma};
use crate::continuation::two_param::{locate_augmented_with, CurvePoint};
use crate::continuation::{Continuation, ContinuationOptions, SpecialKind, StepOutcome};
use crate::error::{Error, Result};
use crate::integrator::DEFAULT_METHOD;
use crate::model::recorded::file::{Covariance, ModelFile};
use crate::model::recorded::{RecordedModel, RecordedParam};
use crate::model::Parametrised;
use crate::orbits::{orbit_from_simulation, OrbitSpec, ShootingOptions};
use serde::Serialize;

/// How far the report looks.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RecordedReportOptions {
    /// Frequency of the start simulation, Hz (default: the lowest recorded drive frequency, or
    /// 1 Hz without a recorded range).
    pub f_start: f64,
    /// Highest frequency of the lock branch, Hz.
    pub f_max: f64,
    /// Largest number of continuation steps.
    pub max_steps: usize,
    /// Largest continuation step (arclength in (f, ω/10)).
    pub ds_max: f64,
    /// Integrator tolerance.
    pub tol: f64,
    /// Homotopy steps from the file's gear to an effect switched off.
    pub homotopy_steps: usize,
}

impl RecordedReportOptions {
    /// The defaults for `file`.
    pub fn for_file(file: &ModelFile) -> Self {
        Self {
            f_start: file.recorded.map_or(1.0, |r| r.drive_hz[0]),
            f_max: 200.0,
            max_steps: 200,
            ds_max: 2.0,
            tol: 1e-10,
            homotopy_steps: 4,
        }
    }

    fn shooting(&self) -> ShootingOptions {
        ShootingOptions {
            tol: self.tol,
            ..Default::default()
        }
    }
}

/// A special point of the lock branch, located with its σ.
#[derive(Debug, Clone, Serialize)]
pub struct LocatedLimit {
    /// Its kind.
    pub kind: SpecialKind,
    /// Its name in the text: `f_c` for the lock loss, else the kind's label.
    pub name: String,
    /// The located frequency, Hz.
    pub f_hz: f64,
    /// The located point (state, multipliers).
    pub point: CurvePoint,
    /// σ of f from the file's covariance (`None` for a nonsmooth point, with the reason).
    pub sigma: Option<LocatedSigma>,
    /// Why there is no σ.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub no_sigma: Option<String>,
    /// The parameter contributing most to σ, with |∂f/∂p| σ_p, Hz.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub main_source: Option<(String, f64)>,
    /// The sentence when it lies far outside the recorded range.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub outside: Option<String>,
}

/// The lock branch at the recorded set-up.
#[derive(Debug, Clone, Serialize)]
pub struct LockBranch {
    /// The orbit problem (section, period, winding).
    pub spec: OrbitSpec,
    /// Points of the branch.
    pub points: usize,
    /// Frequency intervals where the continued orbit is stable, Hz (up to the lock loss).
    pub stable_hz: Vec<[f64; 2]>,
    /// Why the continuation stopped.
    pub stop: String,
    /// Map evaluations.
    pub map_evaluations: usize,
}

/// Everything the report computes.
#[derive(Debug, Clone, Serialize)]
pub struct RecordedReportData {
    /// The model file, as given.
    pub file: String,
    /// Input shaft angle Θ of the set-up, deg.
    pub theta_deg: f64,
    /// The accepted effects.
    pub effects: Vec<String>,
    /// The recorded drive frequencies, Hz (if the file has them).
    pub recorded_hz: Option<[f64; 2]>,
    /// The options.
    pub options: RecordedReportOptions,
    /// The lock branch.
    pub branch: LockBranch,
    /// Its special points with σ; the lock loss is the one named `f_c`.
    pub limits: Vec<LocatedLimit>,
    /// The effect table.
    pub shifts: Vec<shifts::Shift>,
    /// Wall time, s.
    pub wall_time_s: f64,
}

/// Computes the report of the model file `file` (named `name` in the text).
pub fn compute(
    file: &ModelFile,
    name: &str,
    o: &RecordedReportOptions,
) -> Result<RecordedReportData> {
    let clock = std::time::Instant::now();
    let (branch, specials) = lock_branch(file, o)?;
    let mut limits = Vec::new();
    let mut lock_lost = false;
    for sp in specials {
        let l = locate_limit(file, &branch.spec, sp, !lock_lost, o)?;
        lock_lost |= l.name == "f_c";
        limits.push(l);
    }
    let shifts = shifts::effect_table(file, &branch.spec, &limits, o)?;
    Ok(RecordedReportData {
        file: name.to_string(),
        theta_deg: file.setup.theta_deg,
        effects: file.effects.clone(),
        recorded_hz: file.recorded.map(|r| r.drive_hz),
        options: *o,
        branch,
        limits,
        shifts,
        wall_time_s: clock.elapsed().as_secs_f64(),
    })
}

/// A special point found on the branch: kind, f and state.
type Found = (SpecialKind, f64, [f64; 2]);

/// The lock branch from a simulation at `o.f_start`, continued up in f until its first fold
/// (or `o.f_max`, or `o.max_steps`), and its special points.
fn lock_branch(file: &ModelFile, o: &RecordedReportOptions) -> Result<(LockBranch, Vec<Found>)> {
    let m = file.model(o.f_start)?;
    let beta = crate::model::gear::equilibrium_angle(m.param(RecordedParam::Delta), 0.0);
    let start = [beta, std::f64::consts::TAU * o.f_start];
    let orbit = orbit_from_simulation(&m, start, 200, 1, false, &o.shooting())?;
    if orbit.spec.winding != 1 {
        return Err(Error::inconsistent(
            "--model, --f-start",
            format!(
                "the gear is not locked at {} Hz (winding {} per drive turn): give a lower --f-start",
                o.f_start, orbit.spec.winding
            ),
        ));
    }
    let opts = ContinuationOptions {
        ds: 0.1,
        ds_max: o.ds_max,
        max_steps: o.max_steps,
        param_min: 0.5 * o.f_start,
        param_max: o.f_max,
        shooting: o.shooting(),
        ..Default::default()
    };
    let mut c = Continuation::from_orbit(m, RecordedParam::F, &orbit, opts)?;
    while let StepOutcome::Point(_) = c.step()? {
        if c.branch()
            .specials
            .iter()
            .any(|s| s.kind == SpecialKind::Fold)
        {
            break;
        }
    }
    let b = c.into_branch();
    let fold_at = b
        .specials
        .iter()
        .find(|s| s.kind == SpecialKind::Fold)
        .map_or(b.points.len(), |s| s.after_point + 1);
    let mut stable_hz: Vec<[f64; 2]> = Vec::new();
    let mut open = false;
    for p in b.points.iter().take(fold_at) {
        match (p.stable, open, stable_hz.last_mut()) {
            (true, true, Some(last)) => last[1] = p.param,
            (true, _, _) => stable_hz.push([p.param, p.param]),
            _ => {}
        }
        open = p.stable;
    }
    let found = b.specials.iter().map(|s| (s.kind, s.param, s.x)).collect();
    let stop = if b.specials.iter().any(|s| s.kind == SpecialKind::Fold) {
        "the lock loss (a fold)".to_string()
    } else {
        b.stop.to_string()
    };
    Ok((
        LockBranch {
            spec: b.spec,
            points: b.points.len(),
            stable_hz,
            stop,
            map_evaluations: b.map_evaluations,
        },
        found,
    ))
}

/// The model of `file` driven at `f` with a column for f.
pub(crate) fn driven(file: &ModelFile, f: f64) -> Result<RecordedModel> {
    file.model(f)?.with_column(RecordedParam::F)
}

/// The special point `sp` re-located (a nonsmooth point as found), with σ and the range sentence;
/// the first fold (`first_fold`) is the lock loss f_c.
fn locate_limit(
    file: &ModelFile,
    spec: &OrbitSpec,
    (kind, f, x): Found,
    first_fold: bool,
    o: &RecordedReportOptions,
) -> Result<LocatedLimit> {
    let name = if first_fold && kind == SpecialKind::Fold {
        "f_c".to_string()
    } else {
        kind.label().to_string()
    };
    let outside = file
        .recorded
        .and_then(|r| r.statement(&name, f, file.has_drag()));
    let m = driven(file, f)?;
    let opts = o.shooting();
    let (point, sigma, no_sigma) = match kind {
        SpecialKind::Nonsmooth => (
            nonsmooth_point(&m, spec, x, f)?,
            None,
            Some("a nonsmooth point (change of the event sequence) has no first-order σ".into()),
        ),
        _ => {
            let p = locate_augmented_with(
                &DEFAULT_METHOD,
                &m,
                spec,
                kind,
                RecordedParam::F,
                x,
                f,
                &opts,
            )?;
            let s = located_sigma(
                &DEFAULT_METHOD,
                &m,
                &file.covariance,
                spec,
                kind,
                (RecordedParam::F, None),
                &p,
                &opts,
            )?;
            (p, Some(s), None)
        }
    };
    let main_source = sigma
        .as_ref()
        .and_then(|s| main_source(s, &file.covariance));
    Ok(LocatedLimit {
        kind,
        name,
        f_hz: point.free,
        point,
        sigma,
        no_sigma,
        main_source,
        outside,
    })
}

/// The parameter of the largest |∂λ/∂p| σ_p (σ_p from the covariance's diagonal) and that product.
fn main_source(s: &LocatedSigma, cov: &Covariance) -> Option<(String, f64)> {
    s.gradient
        .iter()
        .filter_map(|d| {
            let i = cov.names.iter().position(|n| n == d.name)?;
            Some((
                d.name.to_string(),
                (d.derivative * cov.matrix[i][i].max(0.0).sqrt()).abs(),
            ))
        })
        .max_by(|a, b| a.1.total_cmp(&b.1))
}

/// A nonsmooth point as the continuation located it (its Floquet data at the state found).
fn nonsmooth_point(m: &RecordedModel, spec: &OrbitSpec, x: [f64; 2], f: f64) -> Result<CurvePoint> {
    let o = crate::orbits::shoot(m, spec, x, &ShootingOptions::default())?;
    Ok(CurvePoint {
        along: f64::NAN,
        free: f,
        x: o.x,
        floquet: o.floquet,
        events: o.events,
        test_value: 0.0,
        precision: 0.0,
        newton_iterations: o.newton_iterations,
    })
}
