//! The report's numbers, computed once and kept as data ([`ReportData`]): the map sweep, the Θ = 0
//! hysteresis loop, the derived quantities, the check of the analytic lock branch, the bifurcations
//! located by continuation, the map's class counts and the operating advice. Nothing here formats
//! text or draws: [`super::markdown`] writes these values, [`super::figures`] draws them, and the
//! JSON of each section is the serialisation of its struct.

use super::ReportOptions;
use crate::analysis::ClassifyOptions;
use crate::continuation::two_param::{lock_loss_boundary, Curve};
use crate::continuation::{
    switch_branch, Branch, Continuation, ContinuationOptions, SpecialKind, SpecialPoint,
    StepOutcome,
};
use crate::error::Result;
use crate::model::gear::cogging_free_parallel_angles;
use crate::model::{Convention, Gear, GearParam, GearParams, Parametrised};
use crate::orbits::{orbit_from_simulation, OrbitSpec, ShootingOptions};
use crate::sweep::{
    lock_loss_hysteresis, Hysteresis, Method, PointRecord, Protocol, SweepOutcome, SweepResult,
    SweepRunner, SweepSpec,
};
use serde::Serialize;

/// Shaft angle of the located bifurcations with the symmetric and asymmetric branches (the paper's
/// Fig. 9), degrees.
pub const BIFURCATION_THETA_DEG: f64 = 25.0;
/// Frequency window of the located bifurcations at [`BIFURCATION_THETA_DEG`], Hz.
pub const BIFURCATION_F_RANGE_HZ: (f64, f64) = (1.5, 3.0);

/// Everything the report shows, computed by [`compute_report`].
#[derive(Debug, Clone)]
pub struct ReportData {
    /// The gear.
    pub gear: GearParams,
    /// Integrator tolerance of the map.
    pub tol: f64,
    /// The classification map (semi-static ramp-up in f per Θ).
    pub map: SweepResult,
    /// The lock-loss hysteresis loop at Θ = 0 (paper Fig. 10 protocol).
    pub hysteresis: Hysteresis,
    /// Derived quantities.
    pub derived: Derived,
    /// The analytic lock branch against the simulated lock angles.
    pub lock_branch: LockBranchCheck,
    /// Located bifurcations and f_c(Θ) (`None` when switched off).
    pub bifurcations: Option<Bifurcations>,
    /// Class counts of the map.
    pub map_summary: MapSummary,
    /// Operating advice.
    pub advice: Advice,
}

/// Derived quantities of the gear.
#[derive(Debug, Clone, Serialize)]
pub struct Derived {
    /// c = μ0 m1 m2 / (4π r³), J.
    pub coupling_j: f64,
    /// g = c / I, s⁻².
    pub g: f64,
    /// Shaft index Δ of this gear.
    pub delta: f64,
    /// f_c = (g − η)/(2πζ), Hz.
    pub f_c_hz: Option<f64>,
    /// η/g (static load).
    pub eta_over_g: f64,
    /// Lock angle offset arcsin(η/g), degrees.
    pub static_offset_deg: f64,
    /// Cogging-free parallel shaft angles (Δ = +1, Δ = −1), degrees.
    pub theta_cogging_free_deg: [f64; 2],
    /// Largest cogging (Δ = 0), degrees.
    pub theta_max_cogging_deg: f64,
}

/// Derived quantities of `gear`.
pub fn derived(gear: &GearParams) -> Derived {
    let (z, d0, m1) = cogging_free_parallel_angles();
    let eg = gear.eta / gear.g();
    Derived {
        coupling_j: gear.coupling(),
        g: gear.g(),
        delta: gear.delta(),
        f_c_hz: gear.lock_loss_frequency(),
        eta_over_g: eg,
        static_offset_deg: eg.min(1.0).asin().to_degrees(),
        theta_cogging_free_deg: [z.to_degrees(), m1.to_degrees()],
        theta_max_cogging_deg: d0.to_degrees(),
    }
}

/// One locked point of the upward run against the analytic lock branch (paper convention).
#[derive(Debug, Clone, Serialize)]
pub struct LockBranchRow {
    /// Drive frequency, Hz.
    pub f_hz: f64,
    /// Analytic stable lock angle δ = β − α, paper convention, degrees.
    pub analytic_deg: f64,
    /// Simulated δ_avg, paper convention, degrees.
    pub simulated_deg: f64,
    /// |μ| of P_T of the analytic lock.
    pub multiplier: f64,
}

/// The analytic lock branch at Θ = 0 checked against the simulated lock angles.
#[derive(Debug, Clone, Serialize)]
pub struct LockBranchCheck {
    /// f_c at Θ = 0, Hz.
    pub f_c_hz: Option<f64>,
    /// Every locked point of the upward run.
    pub points: Vec<LockBranchRow>,
    /// Largest |simulated − analytic|, degrees.
    pub max_deviation_deg: f64,
}

/// The lock branch check from the upward run of `hyst`.
pub fn lock_branch_check(gear: &GearParams, hyst: &Hysteresis) -> Result<LockBranchCheck> {
    let p0 = gear.with_parallel_shafts_deg(0.0);
    let mut points = Vec::new();
    for r in hyst.up.iter().filter(|r| r.locked == Some(true)) {
        let g = Gear::new(p0.g(), 1.0, p0.zeta, p0.eta, r.f_hz)?.with_convention(Convention::Paper);
        if let Ok(b) = g.lock_branch() {
            points.push(LockBranchRow {
                f_hz: r.f_hz,
                analytic_deg: b.stable.phase.to_degrees().rem_euclid(360.0),
                simulated_deg: r.delta_avg_deg,
                multiplier: b.stable.multipliers[0].norm(),
            });
        }
    }
    let max_deviation_deg = points
        .iter()
        .map(|r| (r.analytic_deg - r.simulated_deg).abs())
        .fold(0.0, f64::max);
    Ok(LockBranchCheck {
        f_c_hz: p0.lock_loss_frequency(),
        points,
        max_deviation_deg,
    })
}

/// The lock-loss boundary f_c(Θ) as used by the report: the curves of
/// [`lock_loss_boundary`] (forward lock p = +1, reversed lock p = −1), or the error text.
#[derive(Debug, Clone)]
pub struct LockLossCurves {
    /// Θ step, degrees.
    pub step_deg: f64,
    /// The curves (label, curve), or why they could not be computed.
    pub curves: std::result::Result<Vec<(String, Curve)>, String>,
}

impl LockLossCurves {
    /// Computes f_c(Θ) for parallel shafts of `gear` with Θ step `step_deg`. Never fails: an error
    /// is kept as text.
    pub fn compute(gear: &GearParams, step_deg: f64) -> Self {
        let curves = gear
            .with_parallel_shafts_deg(0.0)
            .driven(1.0)
            .and_then(|g| lock_loss_boundary(&g, step_deg, &ShootingOptions::default()))
            .map_err(|e| e.to_string());
        Self { step_deg, curves }
    }

    /// f_c at `theta_deg` on the curve of winding `p` (linear interpolation between the curve's
    /// points; exact on them), `None` outside the Θ range the curve covers.
    pub fn f_c(&self, theta_deg: f64, p: i32) -> Option<f64> {
        let c = self
            .curves
            .as_ref()
            .ok()?
            .iter()
            .find(|(_, c)| c.spec.winding == p)?;
        curve_at(&c.1, theta_deg)
    }

    /// The JSON of the boundary: per curve its label, winding, stop reason and points, or the
    /// error.
    pub fn to_json(&self) -> serde_json::Value {
        match &self.curves {
            Ok(curves) => serde_json::json!({
                "step_deg": self.step_deg,
                "curves": curves.iter().map(|(label, c)| serde_json::json!({
                    "label": label, "winding": c.spec.winding, "stopped": c.stopped,
                    "points": c.points.iter().map(|p| serde_json::json!({
                        "theta_deg": p.along, "f_c_hz": p.free, "precision_hz": p.precision
                    })).collect::<Vec<_>>(),
                })).collect::<Vec<_>>(),
            }),
            Err(e) => serde_json::json!({
                "step_deg": self.step_deg,
                "error": format!("lock-loss boundary f_c(Θ): {e}"),
            }),
        }
    }
}

/// Linear interpolation of a curve's free parameter at `along`, `None` outside its range.
pub(super) fn curve_at(c: &Curve, along: f64) -> Option<f64> {
    let mut pts: Vec<(f64, f64)> = c.points.iter().map(|p| (p.along, p.free)).collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    for w in pts.windows(2) {
        let ((a0, f0), (a1, f1)) = (w[0], w[1]);
        if (a0 - along).abs() < 1e-9 {
            return Some(f0);
        }
        if (a1 - along).abs() < 1e-9 {
            return Some(f1);
        }
        if a0 < along && along < a1 {
            return Some(f0 + (f1 - f0) * (along - a0) / (a1 - a0));
        }
    }
    match pts.as_slice() {
        [(a, f)] if (a - along).abs() < 1e-9 => Some(*f),
        _ => None,
    }
}

/// A computation that either gave its value or failed with a message (kept in the report instead
/// of aborting it).
#[derive(Debug, Clone, Serialize)]
#[serde(untagged)]
pub enum Outcome<T> {
    /// The value.
    Done(T),
    /// Why it failed.
    Failed {
        /// The message.
        error: String,
    },
}

/// The fold of the Θ = 0 lock branch against the analytic f_c.
#[derive(Debug, Clone, Serialize)]
pub struct Theta0Fold {
    /// Located fold, Hz.
    pub fold_f_hz: f64,
    /// Its precision, Hz.
    pub precision_hz: f64,
    /// Analytic f_c = (g − η)/(2πζ), Hz.
    pub analytic_f_c_hz: f64,
    /// fold − analytic, Hz.
    pub difference_hz: f64,
    /// δ at the fold, paper convention, degrees.
    pub delta_deg_paper: f64,
    /// Multipliers of G at the fold.
    pub multipliers: [[f64; 2]; 2],
    /// Points of the branch.
    pub points: usize,
    /// Map evaluations.
    pub map_evaluations: usize,
    /// Start frequency of the branch, Hz.
    pub start_f_hz: f64,
}

/// Statistics of a continued branch.
#[derive(Debug, Clone, Serialize)]
pub struct BranchStats {
    /// Points.
    pub points: usize,
    /// Map evaluations.
    pub map_evaluations: usize,
    /// Why the continuation stopped.
    pub stop: String,
    /// Winding p.
    pub winding: i32,
}

impl BranchStats {
    fn of(b: &Branch) -> Self {
        Self {
            points: b.points.len(),
            map_evaluations: b.map_evaluations,
            stop: format!("{:?}", b.stop),
            winding: b.spec.winding,
        }
    }
}

/// A located special point as a row of the report.
#[derive(Debug, Clone, Serialize)]
pub struct SpecialRow {
    /// Which branch.
    pub branch: String,
    /// Type label.
    pub kind: String,
    /// Location, Hz.
    pub f_hz: f64,
    /// Precision, Hz.
    pub precision_hz: f64,
    /// Multipliers of the branch's map.
    pub multipliers: [[f64; 2]; 2],
    /// Stability changes across the point.
    pub stability_change: bool,
    /// (crossings, sticks) before a nonsmooth point.
    pub events_before: Option<(usize, usize)>,
    /// (crossings, sticks) after it.
    pub events_after: Option<(usize, usize)>,
    /// Test function a multiplier jumps across at a nonsmooth point.
    pub crosses: Option<String>,
    /// Leading multiplier before and after a nonsmooth point.
    pub jump_multiplier: Option<[[f64; 2]; 2]>,
    /// Criticality of a symmetry-breaking point from the branch switch, or why it failed.
    pub note: String,
}

impl SpecialRow {
    fn new(branch: &str, s: &SpecialPoint, note: String) -> Self {
        Self {
            branch: branch.into(),
            kind: s.kind.label().into(),
            f_hz: s.param,
            precision_hz: s.precision,
            multipliers: s.floquet.multipliers,
            stability_change: s.stability_change,
            events_before: s.jump.as_ref().map(|j| j.events_before.signature()),
            events_after: s.jump.as_ref().map(|j| j.events_after.signature()),
            crosses: s.jump.as_ref().and_then(|j| j.crosses.clone()),
            jump_multiplier: s.jump.as_ref().map(|j| {
                [
                    j.floquet_before.multipliers[0],
                    j.floquet_after.multipliers[0],
                ]
            }),
            note,
        }
    }
}

/// Criticality of a symmetry-breaking point.
#[derive(Debug, Clone, Serialize)]
pub struct SbCriticality {
    /// Location, Hz.
    pub f_hz: f64,
    /// "supercritical", "subcritical", or `None` if the switch failed.
    pub criticality: Option<String>,
}

/// Every special point at Θ = 25° on the symmetric branch and on the asymmetric branches switched
/// onto at its supercritical symmetry-breaking points.
#[derive(Debug, Clone, Serialize)]
pub struct Theta25 {
    /// Θ, degrees.
    pub theta_deg: f64,
    /// Frequency window, Hz.
    pub f_range_hz: [f64; 2],
    /// The special points.
    pub specials: Vec<SpecialRow>,
    /// Criticality of each symmetry-breaking point.
    pub symmetry_breaking: Vec<SbCriticality>,
    /// The symmetric branch, or why it failed.
    pub symmetric: Outcome<BranchStats>,
    /// Per supercritical point (its f in Hz): the asymmetric branch, or why it failed.
    pub asymmetric: Vec<(f64, Outcome<BranchStats>)>,
    /// The branches (for figures).
    #[serde(skip)]
    pub branches: Vec<Branch>,
}

/// The bifurcations section's data.
#[derive(Debug, Clone)]
pub struct Bifurcations {
    /// The Θ = 0 fold.
    pub theta0: Outcome<Theta0Fold>,
    /// The Θ = 25° special points.
    pub theta25: Theta25,
    /// f_c(Θ).
    pub boundary: LockLossCurves,
    /// Every failure, as text.
    pub errors: Vec<String>,
    /// Computing time of the Θ = 0 fold, s.
    pub seconds_theta0: f64,
    /// Computing time of the Θ = 25° branches, s.
    pub seconds_theta25: f64,
}

/// The lock branch at Θ = 0 continued in f from f_c/8 until its fold is located.
fn theta0_fold(gear: &GearParams) -> Result<Theta0Fold> {
    let p0 = gear.with_parallel_shafts_deg(0.0);
    let fc = p0
        .lock_loss_frequency()
        .ok_or(crate::Error::NoLockLossFrequency {
            g: p0.g(),
            zeta: p0.zeta,
            eta: p0.eta,
        })?;
    let f0 = fc / 8.0;
    let g = p0.driven(f0)?;
    let start = g.lock_branch()?.stable.state;
    let opts = ContinuationOptions {
        ds: fc / 80.0,
        ds_max: fc / 8.0,
        param_min: f0 / 2.0,
        param_max: 1.5 * fc,
        max_multiplier: 1e3,
        ..Default::default()
    };
    let mut c = Continuation::new(g, GearParam::F, OrbitSpec::symmetric(1), start, opts)?;
    loop {
        let fold = c.branch().specials_of(SpecialKind::Fold).next().cloned();
        if let Some(f) = fold {
            let b = c.into_branch();
            return Ok(Theta0Fold {
                fold_f_hz: f.param,
                precision_hz: f.precision,
                analytic_f_c_hz: fc,
                difference_hz: f.param - fc,
                delta_deg_paper: (f.x[0].to_degrees() + 180.0).rem_euclid(360.0),
                multipliers: f.floquet.multipliers,
                points: b.points.len(),
                map_evaluations: b.map_evaluations,
                start_f_hz: b.points[0].param,
            });
        }
        if c.step()? == StepOutcome::Done {
            let b = c.into_branch();
            return Err(crate::Error::NotFound {
                what: format!("a fold on the lock branch (it stopped: {:?})", b.stop),
            });
        }
    }
}

/// The symmetric (G, winding 1) branch at Θ = [`BIFURCATION_THETA_DEG`] over
/// [`BIFURCATION_F_RANGE_HZ`], started at the low end (Newton from a guess, else from a relaxed
/// simulation).
fn theta25_symmetric(gear: &GearParams) -> Result<Branch> {
    let (lo, hi) = BIFURCATION_F_RANGE_HZ;
    let g = gear
        .with_parallel_shafts_deg(BIFURCATION_THETA_DEG)
        .driven(lo)?;
    let opts = ContinuationOptions {
        ds: 0.02,
        ds_max: 0.05,
        param_min: lo,
        param_max: hi,
        ..Default::default()
    };
    let spec = OrbitSpec::symmetric(1);
    let c = match Continuation::new(g, GearParam::F, spec, [2.98, 0.6], opts) {
        Ok(c) => c,
        Err(e) => {
            let o = orbit_from_simulation(&g, [2.98, 0.6], 300, 1, true, &opts.shooting).map_err(
                |e2| crate::Error::NoStartOrbit {
                    param: "f",
                    value: lo,
                    reason: format!("no symmetric orbit ({e}); from a simulation: {e2}"),
                },
            )?;
            if o.spec != spec {
                return Err(crate::Error::NoStartOrbit {
                    param: "f",
                    value: lo,
                    reason: format!(
                        "no symmetric orbit of winding 1 ({e}); the simulation settles on {:?}",
                        o.spec
                    ),
                });
            }
            Continuation::from_orbit(g, GearParam::F, &o, opts)?
        }
    };
    c.run(None)
}

/// The Θ = 25° branches: the symmetric one, the criticality of its symmetry-breaking points from
/// the branch switch (the asymmetric orbits born at a supercritical point are stable, at a
/// subcritical one unstable), and the asymmetric branches from the supercritical points.
fn theta25(gear: &GearParams, errors: &mut Vec<String>) -> Theta25 {
    let (lo, hi) = BIFURCATION_F_RANGE_HZ;
    let sh = ShootingOptions::default();
    let mut out = Theta25 {
        theta_deg: BIFURCATION_THETA_DEG,
        f_range_hz: [lo, hi],
        specials: vec![],
        symmetry_breaking: vec![],
        symmetric: Outcome::Failed {
            error: String::new(),
        },
        asymmetric: vec![],
        branches: vec![],
    };
    let sym = match theta25_symmetric(gear) {
        Ok(b) => b,
        Err(e) => {
            let t = format!("Θ = {BIFURCATION_THETA_DEG}° symmetric branch: {e}");
            errors.push(t.clone());
            out.symmetric = Outcome::Failed { error: t };
            return out;
        }
    };
    out.symmetric = Outcome::Done(BranchStats::of(&sym));
    let mut supercritical = Vec::new();
    for s in &sym.specials {
        let mut note = String::new();
        if s.kind == SpecialKind::SymmetryBreaking {
            match switch_branch(&sym, s, -1e-3, &sh) {
                Ok(sw) => {
                    let stable = sw.orbit.floquet.stable;
                    let crit = if stable {
                        "supercritical"
                    } else {
                        "subcritical"
                    };
                    note = format!(
                        "{crit}: the asymmetric orbit at {:.4} Hz is {} (μ of P_T {})",
                        sw.system.param(GearParam::F),
                        if stable { "stable" } else { "unstable" },
                        super::markdown::fmt_mus(&sw.orbit.floquet.multipliers)
                    );
                    out.symmetry_breaking.push(SbCriticality {
                        f_hz: s.param,
                        criticality: Some(crit.into()),
                    });
                    if stable {
                        supercritical.push((s.clone(), sw));
                    }
                }
                Err(e) => {
                    note = format!("branch switching at {:.6} Hz: {e}", s.param);
                    out.symmetry_breaking.push(SbCriticality {
                        f_hz: s.param,
                        criticality: None,
                    });
                    errors.push(note.clone());
                }
            }
        }
        out.specials.push(SpecialRow::new("symmetric (G)", s, note));
    }
    out.branches.push(sym);
    for (s, sw) in supercritical {
        let away = (sw.system.param(GearParam::F) - s.param).signum();
        let opts = ContinuationOptions {
            ds: 0.005 * away,
            ds_max: 0.02,
            param_min: lo,
            param_max: hi,
            max_steps: 400,
            ..Default::default()
        };
        match Continuation::from_orbit(sw.system, GearParam::F, &sw.orbit, opts)
            .and_then(|c| c.run(None))
        {
            Ok(asym) => {
                let name = format!("asymmetric (P_T, from {:.4} Hz)", s.param);
                for a in &asym.specials {
                    out.specials.push(SpecialRow::new(&name, a, String::new()));
                }
                out.asymmetric
                    .push((s.param, Outcome::Done(BranchStats::of(&asym))));
                out.branches.push(asym);
            }
            Err(e) => {
                let t = format!(
                    "asymmetric branch from the supercritical point {:.6} Hz: {e}",
                    s.param
                );
                errors.push(t.clone());
                out.asymmetric.push((s.param, Outcome::Failed { error: t }));
            }
        }
    }
    out
}

/// Bifurcations located by continuation (`crate::continuation`): the fold of the lock at Θ = 0
/// against the analytic f_c, every special point at Θ = 25°, and the lock-loss boundary f_c(Θ)
/// (`boundary`, computed once by [`LockLossCurves::compute`] and shared with the advice). A
/// failing continuation is recorded, not returned as an error.
pub fn bifurcations(gear: &GearParams, boundary: LockLossCurves) -> Bifurcations {
    let mut errors = Vec::new();
    let t0 = std::time::Instant::now();
    let theta0 = match theta0_fold(gear) {
        Ok(f) => Outcome::Done(f),
        Err(e) => {
            let t = format!("Θ = 0 lock branch: {e}");
            errors.push(t.clone());
            Outcome::Failed { error: t }
        }
    };
    let seconds_theta0 = t0.elapsed().as_secs_f64();
    let t1 = std::time::Instant::now();
    let theta25 = theta25(gear, &mut errors);
    let seconds_theta25 = t1.elapsed().as_secs_f64();
    if let Err(e) = &boundary.curves {
        errors.push(format!("lock-loss boundary f_c(Θ): {e}"));
    }
    Bifurcations {
        theta0,
        theta25,
        boundary,
        errors,
        seconds_theta0,
        seconds_theta25,
    }
}

/// Class counts of the map.
#[derive(Debug, Clone, Serialize)]
pub struct MapSummary {
    /// Points.
    pub points: usize,
    /// Symmetric periodic (the paper's T/2).
    pub symmetric: usize,
    /// Asymmetric periodic (T, kT).
    pub asymmetric: usize,
    /// Chaotic.
    pub chaotic: usize,
    /// Quasi-periodic.
    pub quasi_periodic: usize,
    /// Unresolved.
    pub unresolved: usize,
    /// Slipping (|rotation number| ≠ 1).
    pub slipping: usize,
    /// Flowchart and rigorous class disagree.
    pub disagree: usize,
    /// File of the points.
    pub csv: String,
}

/// Class counts of `res`.
pub fn map_summary(res: &SweepResult) -> MapSummary {
    let count = |f: &dyn Fn(&PointRecord) -> bool| res.points().filter(|p| f(p)).count();
    MapSummary {
        points: res.points().count(),
        symmetric: count(&|p| p.symmetric),
        asymmetric: count(&|p| p.half_periods > 0 && !p.symmetric),
        chaotic: count(&|p| p.class == "chaos"),
        quasi_periodic: count(&|p| p.class == "QP"),
        unresolved: count(&|p| p.class == "?"),
        slipping: count(&|p| p.locked == Some(false)),
        disagree: count(&|p| p.agree == Some(false)),
        csv: "map.csv".into(),
    }
}

/// A point counts as a good operating point: locked, periodic, small RMS_δ.
fn good(p: &PointRecord, smooth: f64) -> bool {
    p.locked == Some(true) && p.half_periods > 0 && p.rms_delta_deg <= smooth
}

/// Per Θ: the highest f up to which every point of the ramp-up is a good operating point.
pub fn safe_frequencies(res: &SweepResult, smooth: f64) -> Vec<(f64, Option<f64>)> {
    res.rows
        .iter()
        .map(|r| {
            let mut last = None;
            for p in &r.points {
                if good(p, smooth) {
                    last = Some(p.col_value);
                } else {
                    break;
                }
            }
            (r.row_value, last)
        })
        .collect()
}

/// The mean relative step of an ascending axis, percent.
fn ramp_step_percent(v: &[f64]) -> f64 {
    if v.len() < 2 || v[0] <= 0.0 {
        return 0.0;
    }
    100.0 * ((v[v.len() - 1] / v[0]).powf(1.0 / (v.len() - 1) as f64) - 1.0)
}

/// The lock whose f_c(Θ) limits a gear at shaft index Δ: the forward lock (p = +1) for Δ ≥ 0, the
/// reversed lock (p = −1) for Δ < 0.
fn natural_winding(delta: f64) -> i32 {
    if delta >= 0.0 {
        1
    } else {
        -1
    }
}

/// Safe frequency of one shaft angle.
#[derive(Debug, Clone, Serialize)]
pub struct SafeFrequency {
    /// Θ, degrees.
    pub theta_deg: f64,
    /// Highest good f of the ramp, Hz.
    pub f_hz: Option<f64>,
}

/// The lock-loss limit of one shaft angle.
#[derive(Debug, Clone, Serialize)]
pub struct LockLossLimit {
    /// Θ, degrees.
    pub theta_deg: f64,
    /// Shaft index Δ.
    #[serde(skip)]
    pub delta: f64,
    /// Winding of the lock in the natural sense.
    pub winding: i32,
    /// f_c(Θ) of that lock, Hz.
    pub f_c_hz: Option<f64>,
    /// The lower of the ramp-safe frequency and f_c(Θ), Hz.
    pub recommended_below_hz: Option<f64>,
}

/// Shaft angles safe up to a frequency.
#[derive(Debug, Clone, Serialize)]
pub struct ThetaRange {
    /// The frequency, Hz.
    pub f_min_hz: f64,
    /// The shaft angles whose ramp stayed good at least up to it, degrees.
    pub theta_deg: Vec<f64>,
}

/// Operating advice from the map, the hysteresis loop and f_c(Θ).
#[derive(Debug, Clone, Serialize)]
pub struct Advice {
    /// Largest RMS_δ of a good point, degrees.
    pub smooth_rms_deg: f64,
    /// Per Θ the safe frequency of the ramp.
    pub safe_f_hz: Vec<SafeFrequency>,
    /// Shaft angles safe to 1, 5, 20 Hz.
    pub theta_ranges: Vec<ThetaRange>,
    /// The shaft angle with the lowest safe frequency.
    pub worst_theta_deg: Option<f64>,
    /// First unlocked f of the upward Θ = 0 run, Hz.
    pub lock_lost_up_hz: Option<f64>,
    /// First locked f of the downward Θ = 0 run, Hz.
    pub relock_down_hz: Option<f64>,
    /// Last slipping f of the downward Θ = 0 run before it relocks, Hz.
    pub last_slip_down_hz: Option<f64>,
    /// f_c at Θ = 0 (located, else analytic), Hz.
    pub f_c_theta0_hz: Option<f64>,
    /// Per Θ the lock-loss limit (empty without f_c(Θ)).
    pub lock_loss_limits: Vec<LockLossLimit>,
    /// Shaft angles whose ramp stayed good above f_c(Θ).
    pub ramp_safe_above_f_c_theta_deg: Vec<f64>,
    /// Steps of the ramp.
    pub ramp_steps: usize,
    /// Mean relative step of the ramp, percent.
    pub ramp_step_percent: f64,
    /// f_c(Θ) was computed (successfully or not).
    #[serde(skip)]
    pub with_boundary: bool,
    /// Why f_c(Θ) could not be computed.
    #[serde(skip)]
    pub boundary_error: Option<String>,
}

/// The advice from the map `res`, the Θ = 0 loop `hyst` and, if given, f_c(Θ).
pub fn advice(
    res: &SweepResult,
    hyst: &Hysteresis,
    gear: &GearParams,
    smooth: f64,
    boundary: Option<&LockLossCurves>,
) -> Advice {
    let safe = safe_frequencies(res, smooth);
    let mut limits = Vec::new();
    let mut above = Vec::new();
    if let Some(b) = boundary {
        for (th, f) in &safe {
            let delta = gear.with_parallel_shafts_deg(*th).delta();
            let p = natural_winding(delta);
            let fc = b.f_c(*th, p);
            let rec = match (f, fc) {
                (Some(a), Some(c)) => Some(a.min(c)),
                _ => None,
            };
            if let (Some(a), Some(c)) = (f, fc) {
                if *a > c {
                    above.push(*th);
                }
            }
            limits.push(LockLossLimit {
                theta_deg: *th,
                delta,
                winding: p,
                f_c_hz: fc,
                recommended_below_hz: rec,
            });
        }
    }
    let worst = safe
        .iter()
        .min_by(|a, b| a.1.unwrap_or(0.0).total_cmp(&b.1.unwrap_or(0.0)))
        .map(|x| x.0);
    let theta_ranges = [1.0, 5.0, 20.0]
        .into_iter()
        .map(|thr| ThetaRange {
            f_min_hz: thr,
            theta_deg: safe
                .iter()
                .filter(|(_, f)| f.is_some_and(|f| f >= thr))
                .map(|x| x.0)
                .collect(),
        })
        .collect();
    let relock = hyst.down.iter().position(|r| r.locked == Some(true));
    Advice {
        smooth_rms_deg: smooth,
        safe_f_hz: safe
            .iter()
            .map(|&(theta_deg, f_hz)| SafeFrequency { theta_deg, f_hz })
            .collect(),
        theta_ranges,
        worst_theta_deg: worst,
        lock_lost_up_hz: hyst
            .up
            .iter()
            .find(|r| r.locked != Some(true))
            .map(|r| r.f_hz),
        relock_down_hz: relock.map(|i| hyst.down[i].f_hz),
        last_slip_down_hz: relock.filter(|&i| i > 0).map(|i| hyst.down[i - 1].f_hz),
        f_c_theta0_hz: boundary
            .and_then(|b| b.f_c(0.0, 1))
            .or(gear.with_parallel_shafts_deg(0.0).lock_loss_frequency()),
        lock_loss_limits: limits,
        ramp_safe_above_f_c_theta_deg: above,
        ramp_steps: res.spec.cols.values.len(),
        ramp_step_percent: ramp_step_percent(&res.spec.cols.values),
        with_boundary: boundary.is_some(),
        boundary_error: boundary.and_then(|b| b.curves.as_ref().err().cloned()),
    }
}

/// Computes everything the report shows: the map sweep, the Θ = 0 hysteresis loop
/// ([`lock_loss_hysteresis`], the protocol of `gearbif figure fig10`), f_c(Θ) and the located
/// bifurcations (if `opts.bifurcations`), and the sections' data.
pub fn compute_report(
    gear: &GearParams,
    opts: &ReportOptions,
    observer: &dyn crate::progress::Observer,
) -> Result<ReportData> {
    gear.validate()?;
    let classify = ClassifyOptions {
        settle_turns: opts.settle_turns,
        analysis_turns: 40,
        ..ClassifyOptions::default()
    };
    let spec = SweepSpec {
        gear: *gear,
        f: 1.0,
        rows: opts.theta_deg.clone(),
        cols: opts.f_hz.clone(),
        protocol: Protocol::SemiStatic,
        alpha0_deg: 0.0,
        beta0_deg: 180.0,
        convention: Convention::Paper,
        method: Method::EventDriven853,
        classify: classify.clone(),
    };
    let map = match SweepRunner::new(spec).observer(observer).run()? {
        SweepOutcome::Complete(r) => *r,
        SweepOutcome::Stopped { .. } => {
            return Err(crate::Error::Stopped {
                what: "the report's sweep",
            })
        }
    };
    let hysteresis =
        lock_loss_hysteresis(*gear, &opts.hysteresis_f, opts.hysteresis_settle, observer)?;
    let boundary = opts
        .bifurcations
        .then(|| LockLossCurves::compute(gear, opts.fc_step_deg));
    let advice = advice(
        &map,
        &hysteresis,
        gear,
        opts.smooth_rms_deg,
        boundary.as_ref(),
    );
    Ok(ReportData {
        gear: *gear,
        tol: classify.tol,
        derived: derived(gear),
        lock_branch: lock_branch_check(gear, &hysteresis)?,
        bifurcations: boundary.map(|b| bifurcations(gear, b)),
        map_summary: map_summary(&map),
        advice,
        map,
        hysteresis,
    })
}
