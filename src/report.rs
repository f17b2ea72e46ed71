//! The gear report (`gearbif report`): a self-contained folder with `report.md`, its figures and
//! `report.json`. A [`Report`] is a list of [`ReportSection`]s, each computed by its own function,
//! so further sections (e.g. located bifurcations from the continuation) can be appended by other
//! modules: build one and push it before [`Report::write`].
//!
//! Sections built here: derived quantities (g, Δ, f_c, cogging-free angles); the analytic lock
//! branch with a numerical check; the bifurcations located by the continuation module (the fold of
//! the lock at Θ = 0, every special point at Θ = 25° between 1.5 and 3 Hz, the lock-loss boundary
//! f_c(Θ)); the stability/classification map (a coarse Θ × f sweep, semi-static ramp-up as a gear
//! is started); the lock-loss hysteresis at Θ = 0; operating advice computed from the map, the
//! hysteresis and f_c(Θ).

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
    hysteresis, Axis, Hysteresis, Method, PointRecord, Protocol, SweepOutcome, SweepParam,
    SweepResult, SweepRunner, SweepSpec,
};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Schema id of `report.json` (docs/formats.md).
pub const SCHEMA: &str = "gearbif.report/1";

/// One section of a report.
#[derive(Debug, Clone, Serialize)]
pub struct ReportSection {
    /// Stable identifier (JSON key), e.g. `derived`, `lock_branch`.
    pub id: String,
    /// Heading.
    pub title: String,
    /// Markdown body (figures are referenced by relative paths).
    pub markdown: String,
    /// Figure files relative to the report folder.
    pub figures: Vec<String>,
    /// Machine-readable data of the section.
    pub data: serde_json::Value,
}

/// A report: title, preamble and sections, written as `report.md` + `report.json`.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    /// Title.
    pub title: String,
    /// Text before the first section (parameters, how it was made).
    pub preamble: String,
    /// The sections in order.
    pub sections: Vec<ReportSection>,
}

impl Report {
    /// Appends a section.
    pub fn push(&mut self, s: ReportSection) {
        self.sections.push(s);
    }

    /// The markdown text.
    pub fn markdown(&self) -> String {
        let mut s = format!("# {}\n\n{}\n", self.title, self.preamble);
        for sec in &self.sections {
            s += &format!("\n## {}\n\n{}\n", sec.title, sec.markdown);
        }
        s
    }

    /// Writes `report.md` and `report.json` into `dir` (atomically; figures are written by the
    /// section builders into `dir/figures`).
    pub fn write(&self, dir: impl AsRef<Path>) -> Result<()> {
        let dir = dir.as_ref();
        crate::io::write_atomic(dir.join("report.md"), self.markdown().as_bytes())?;
        crate::io::write_json_atomic(
            dir.join("report.json"),
            &crate::io::with_schema(SCHEMA, self),
        )
    }
}

/// How much to compute.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReportOptions {
    /// Θ values of the map, degrees (the model depends on Θ only through Δ, so 0–90° covers ±Θ).
    pub theta_deg: Axis,
    /// f values of the map (ascending; the state is carried up each row).
    pub f_hz: Axis,
    /// Settling turns per map point.
    pub settle_turns: usize,
    /// Frequencies of the Θ = 0 hysteresis loop (ascending).
    pub hysteresis_f: Vec<f64>,
    /// Settling turns per hysteresis point.
    pub hysteresis_settle: usize,
    /// Largest RMS_δ of an operating point counted as smooth, degrees.
    pub smooth_rms_deg: f64,
    /// Write figures (feature `plot`).
    pub figures: bool,
    /// Add the section of located bifurcations (continuation) and use f_c(Θ) in the advice.
    pub bifurcations: bool,
    /// Θ step of the lock-loss boundary f_c(Θ), degrees.
    pub fc_step_deg: f64,
}

impl ReportOptions {
    /// The default, coarse grid (finishes in well under two minutes on two cores in release).
    pub fn coarse() -> Result<Self> {
        Ok(Self {
            theta_deg: Axis::range(SweepParam::ThetaDeg, 0.0, 90.0, 10.0)?,
            f_hz: Axis::log(SweepParam::F, 0.2, 60.0, 48)?,
            settle_turns: 200,
            hysteresis_f: (1..=45).map(|i| i as f64).collect(),
            hysteresis_settle: 300,
            smooth_rms_deg: 20.0,
            figures: true,
            bifurcations: true,
            fc_step_deg: 1.0,
        })
    }
    /// A finer grid (`--fine`).
    pub fn fine() -> Result<Self> {
        Ok(Self {
            theta_deg: Axis::range(SweepParam::ThetaDeg, 0.0, 90.0, 5.0)?,
            f_hz: Axis::log(SweepParam::F, 0.1, 100.0, 150)?,
            settle_turns: 1000,
            hysteresis_f: (2..=90).map(|i| 0.5 * i as f64).collect(),
            hysteresis_settle: 1000,
            smooth_rms_deg: 20.0,
            figures: true,
            bifurcations: true,
            fc_step_deg: 0.5,
        })
    }
}

fn fmt_opt(v: Option<f64>, prec: usize) -> String {
    match v {
        Some(x) => format!("{x:.prec$}"),
        None => "—".into(),
    }
}

/// Section: derived quantities.
pub fn section_derived(gear: &GearParams) -> ReportSection {
    let (z, d0, m1) = cogging_free_parallel_angles();
    let fc = gear.lock_loss_frequency();
    let md = format!(
        "| quantity | value | formula |\n|---|---|---|\n\
         | c | {:.5e} J | μ0 m1 m2 / (4π r³) |\n\
         | g | {:.3} s⁻² | c / I |\n\
         | Δ (this gear) | {:.4} | cos Θ cos Φ − 2 sin Θ sin Φ |\n\
         | f_c | {} Hz | (g − η)/(2πζ), lock loss at Δ = ±1 |\n\
         | η/g | {:.4} | static load; lock angle offset arcsin(η/g) = {:.2}° |\n\
         | cogging-free parallel shaft angles | Θ = {:.2}° (Δ = +1), {:.2}° (Δ = −1) | Δ = 1 − 3 sin²Θ |\n\
         | largest cogging (Δ = 0) | Θ = {:.2}° | sense of rotation flips |\n",
        gear.coupling(),
        gear.g(),
        gear.delta(),
        fmt_opt(fc, 3),
        gear.eta / gear.g(),
        (gear.eta / gear.g()).min(1.0).asin().to_degrees(),
        z.to_degrees(),
        m1.to_degrees(),
        d0.to_degrees()
    );
    ReportSection {
        id: "derived".into(),
        title: "Derived quantities".into(),
        markdown: md,
        figures: vec![],
        data: serde_json::json!({
            "coupling_j": gear.coupling(), "g": gear.g(), "delta": gear.delta(), "f_c_hz": fc,
            "theta_cogging_free_deg": [z.to_degrees(), m1.to_degrees()],
            "theta_max_cogging_deg": d0.to_degrees(),
        }),
    }
}

/// Section: the analytic lock branch at Θ = 0 (Δ = 1), checked against simulated lock angles.
pub fn section_lock_branch(
    gear: &GearParams,
    hyst: &Hysteresis,
    fig_dir: Option<&Path>,
) -> Result<ReportSection> {
    let p0 = gear.with_parallel_shafts_deg(0.0);
    let fc = p0.lock_loss_frequency();
    let mut rows = Vec::new();
    let mut md = String::from(
        "At Θ = 0 (Δ = 1) the locked orbit has a constant δ with sin δ = (2πfζ + η)/g; \
         stable δ = 180° − arcsin(…) (physical convention; the paper's convention adds 180°, \
         its eq. `delta_lock` prints 180° + arcsin, i.e. α − β). The branch ends in a saddle-node \
         at f_c. Simulated: the upward semi-static run of the hysteresis section (mean δ over the \
         window, paper convention).\n\n\
         | f [Hz] | analytic stable δ (paper conv.) [°] | simulated δ_avg [°] | |μ| of P_T |\n|---|---|---|---|\n",
    );
    for r in hyst.up.iter().filter(|r| r.locked == Some(true)) {
        let g = Gear::new(p0.g(), 1.0, p0.zeta, p0.eta, r.f_hz)?.with_convention(Convention::Paper);
        if let Ok(b) = g.lock_branch() {
            let an = b.stable.phase.to_degrees().rem_euclid(360.0);
            let mu = b.stable.multipliers[0].norm();
            rows.push(serde_json::json!({"f_hz": r.f_hz, "analytic_deg": an,
                "simulated_deg": r.delta_avg_deg, "multiplier": mu}));
            if (r.f_hz as usize) % 5 == 0 || r.f_hz < 1.5 {
                md += &format!(
                    "| {:.1} | {:.4} | {:.4} | {:.4} |\n",
                    r.f_hz, an, r.delta_avg_deg, mu
                );
            }
        }
    }
    let max_dev = rows
        .iter()
        .filter_map(|v| Some((v["analytic_deg"].as_f64()? - v["simulated_deg"].as_f64()?).abs()))
        .fold(0.0, f64::max);
    md += &format!(
        "\nLargest |simulated − analytic| over the {} locked points: {:.2e}°. f_c = {} Hz.\n",
        rows.len(),
        max_dev,
        fmt_opt(fc, 3)
    );
    #[cfg_attr(not(feature = "plot"), allow(unused_mut))]
    let mut figures = vec![];
    #[cfg(feature = "plot")]
    if let Some(dir) = fig_dir {
        let fig = crate::plotting::atlas::hysteresis_lock_plot(hyst, &p0)?;
        crate::plotting::save(&fig, dir.join("lock_branch.svg"))?;
        crate::plotting::save(&fig, dir.join("lock_branch.png"))?;
        figures.push("figures/lock_branch.png".into());
        md += "\n![lock branch and hysteresis](figures/lock_branch.png)\n";
    }
    #[cfg(not(feature = "plot"))]
    let _ = fig_dir;
    Ok(ReportSection {
        id: "lock_branch".into(),
        title: "Analytic lock branch and f_c".into(),
        markdown: md,
        figures,
        data: serde_json::json!({"f_c_hz": fc, "points": rows, "max_deviation_deg": max_dev}),
    })
}

/// Shaft angle of the located bifurcations with the symmetric and asymmetric branches (the paper's
/// Fig. 9), degrees.
pub const BIFURCATION_THETA_DEG: f64 = 25.0;
/// Frequency window of the located bifurcations at [`BIFURCATION_THETA_DEG`], Hz.
pub const BIFURCATION_F_RANGE_HZ: (f64, f64) = (1.5, 3.0);

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
}

/// Linear interpolation of a curve's free parameter at `along`, `None` outside its range.
fn curve_at(c: &Curve, along: f64) -> Option<f64> {
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

fn fmt_mu(z: [f64; 2]) -> String {
    if z[1] == 0.0 {
        format!("{:.6}", z[0])
    } else {
        format!("{:.4}{:+.4}i", z[0], z[1])
    }
}

fn fmt_mus(m: &[[f64; 2]; 2]) -> String {
    format!("{}, {}", fmt_mu(m[0]), fmt_mu(m[1]))
}

/// The lock branch at Θ = 0 continued in f from f_c/8 until its fold is located.
fn theta0_fold(gear: &GearParams) -> Result<(Branch, SpecialPoint, f64)> {
    let p0 = gear.with_parallel_shafts_deg(0.0);
    let fc = p0.lock_loss_frequency().ok_or_else(|| {
        crate::Error::Unsupported("no lock-loss frequency (ζ = 0 or g ≤ η)".into())
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
            return Ok((c.into_branch(), f, fc));
        }
        if c.step()? == StepOutcome::Done {
            let b = c.into_branch();
            return Err(crate::Error::Continuation(format!(
                "the lock branch stopped ({:?}) without a fold",
                b.stop
            )));
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
                |e2| {
                    crate::Error::Continuation(format!(
                        "no symmetric orbit at {lo} Hz: {e}; from a simulation: {e2}"
                    ))
                },
            )?;
            if o.spec != spec {
                return Err(crate::Error::Continuation(format!(
                    "no symmetric orbit of winding 1 at {lo} Hz ({e}); the simulation settles on {:?}",
                    o.spec
                )));
            }
            Continuation::from_orbit(g, GearParam::F, &o, opts)?
        }
    };
    c.run(None)
}

/// One row (JSON) of a special point.
fn special_json(branch: &str, s: &SpecialPoint, note: &str) -> serde_json::Value {
    serde_json::json!({
        "branch": branch, "kind": s.kind.label(), "f_hz": s.param, "precision_hz": s.precision,
        "multipliers": s.floquet.multipliers, "stability_change": s.stability_change,
        "events_before": s.jump.as_ref().map(|j| j.events_before.signature()),
        "events_after": s.jump.as_ref().map(|j| j.events_after.signature()),
        "crosses": s.jump.as_ref().and_then(|j| j.crosses.clone()),
        "note": note,
    })
}

/// Section: bifurcations located by continuation (`crate::continuation`): the fold of the lock at
/// Θ = 0 against the analytic f_c, every special point at Θ = 25° on the symmetric branch and on
/// the asymmetric branch switched onto at the supercritical symmetry-breaking point, and the
/// lock-loss boundary f_c(Θ) (`boundary`, computed once by [`LockLossCurves::compute`] and shared
/// with the advice). A failing continuation is recorded in the section, not returned as an error.
pub fn section_bifurcations(
    gear: &GearParams,
    boundary: &LockLossCurves,
    fig_dir: Option<&Path>,
) -> ReportSection {
    let mut errors: Vec<String> = Vec::new();
    #[cfg_attr(not(feature = "plot"), allow(unused_mut))]
    let mut figures: Vec<String> = vec![];
    let sh = ShootingOptions::default();
    // 1. Θ = 0: the fold of the lock branch
    let mut md = String::from(
        "Pseudo-arclength continuation of periodic orbits with located special points \
         (`gearbif::continuation`, docs/continuation.md). Frequencies are located to the stated \
         precision (half-width of the final bracket plus the corrector tolerance; integrator \
         tolerance 1e-11). Multipliers are those of the orbit's map: the half-period map G on a \
         symmetric branch (μ_G = −1 is a symmetry-breaking pitchfork of P_T), P_T on an \
         asymmetric branch.\n\n### Θ = 0: fold of the lock branch\n\n",
    );
    let t0 = std::time::Instant::now();
    let theta0 = match theta0_fold(gear) {
        Ok((b, fold, fc)) => {
            let diff = fold.param - fc;
            md += &format!(
                "The lock branch, continued in f from {:.3} Hz ({} points, {} map evaluations), \
                 folds at **f = {:.10} ± {:.1e} Hz**; analytic f_c = (g − η)/(2πζ) = {:.10} Hz; \
                 difference {:+.2e} Hz. At the fold δ = {:.6}° (paper convention), μ_G = {}.\n",
                b.points[0].param,
                b.points.len(),
                b.map_evaluations,
                fold.param,
                fold.precision,
                fc,
                diff,
                (fold.x[0].to_degrees() + 180.0).rem_euclid(360.0),
                fmt_mus(&fold.floquet.multipliers)
            );
            serde_json::json!({
                "fold_f_hz": fold.param, "precision_hz": fold.precision, "analytic_f_c_hz": fc,
                "difference_hz": diff, "delta_deg_paper": (fold.x[0].to_degrees() + 180.0).rem_euclid(360.0),
                "multipliers": fold.floquet.multipliers, "points": b.points.len(),
                "map_evaluations": b.map_evaluations,
            })
        }
        Err(e) => {
            let t = format!("Θ = 0 lock branch: {e}");
            md += &format!("**Failed:** {t}\n");
            errors.push(t.clone());
            serde_json::json!({ "error": t })
        }
    };
    let t_theta0 = t0.elapsed().as_secs_f64();
    // 2. Θ = 25°: the symmetric branch, switching at its symmetry-breaking points
    let (lo, hi) = BIFURCATION_F_RANGE_HZ;
    md += &format!("\n### Θ = {BIFURCATION_THETA_DEG}°, {lo}–{hi} Hz: every special point\n\n");
    let t1 = std::time::Instant::now();
    let mut rows = Vec::new();
    let mut table = String::from(
        "| branch | type | f [Hz] | precision [Hz] | multipliers | note |\n|---|---|---|---|---|---|\n",
    );
    let mut branches: Vec<Branch> = Vec::new();
    let mut sb_json = Vec::new();
    let mut push_row = |branch: &str, s: &SpecialPoint, note: String, table: &mut String| {
        let note = match &s.jump {
            Some(j) => format!(
                "(crossings, sticks) {:?} → {:?}, μ₁ {} → {}{}{}",
                j.events_before.signature(),
                j.events_after.signature(),
                fmt_mu(j.floquet_before.multipliers[0]),
                fmt_mu(j.floquet_after.multipliers[0]),
                j.crosses
                    .as_ref()
                    .map(|c| format!("; a multiplier jumps across the {c} value"))
                    .unwrap_or_default(),
                if note.is_empty() {
                    String::new()
                } else {
                    format!("; {note}")
                }
            ),
            None => note,
        };
        *table += &format!(
            "| {branch} | {} | {:.9} | {:.1e} | {} | {} |\n",
            s.kind.label(),
            s.param,
            s.precision,
            fmt_mus(&s.floquet.multipliers),
            note
        );
        rows.push(special_json(branch, s, &note));
    };
    match theta25_symmetric(gear) {
        Ok(sym) => {
            md += &format!(
                "Symmetric branch (fixed points of G, winding 1): {} points, {} map evaluations, \
                 stop {:?}.",
                sym.points.len(),
                sym.map_evaluations,
                sym.stop
            );
            // criticality from the branch switch: the asymmetric orbits born at a supercritical
            // point are stable, at a subcritical one unstable
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
                                fmt_mus(&sw.orbit.floquet.multipliers)
                            );
                            sb_json.push(serde_json::json!({"f_hz": s.param, "criticality": crit}));
                            if stable {
                                supercritical.push((s.clone(), sw));
                            }
                        }
                        Err(e) => {
                            let t = format!("branch switching at {:.6} Hz: {e}", s.param);
                            note = t.clone();
                            sb_json.push(serde_json::json!({"f_hz": s.param, "criticality": null}));
                            errors.push(t);
                        }
                    }
                }
                push_row("symmetric (G)", s, note, &mut table);
            }
            branches.push(sym.clone());
            if supercritical.is_empty() {
                md += " No supercritical symmetry-breaking point: no asymmetric branch continued.";
            }
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
                        md += &format!(
                            " Asymmetric branch (P_T, winding {}) switched onto at the \
                             supercritical point {:.6} Hz: {} points, {} map evaluations, stop {:?}.",
                            asym.spec.winding,
                            s.param,
                            asym.points.len(),
                            asym.map_evaluations,
                            asym.stop
                        );
                        let name = format!("asymmetric (P_T, from {:.4} Hz)", s.param);
                        for a in &asym.specials {
                            push_row(&name, a, String::new(), &mut table);
                        }
                        branches.push(asym);
                    }
                    Err(e) => {
                        let t = format!(
                            "asymmetric branch from the supercritical point {:.6} Hz: {e}",
                            s.param
                        );
                        md += &format!(" **Failed:** {t}.");
                        errors.push(t);
                    }
                }
            }
            md += "\n\n";
            md += &table;
        }
        Err(e) => {
            let t = format!("Θ = {BIFURCATION_THETA_DEG}° symmetric branch: {e}");
            md += &format!("**Failed:** {t}\n");
            errors.push(t);
        }
    }
    let t_theta25 = t1.elapsed().as_secs_f64();
    // 3. f_c(Θ)
    md += &format!(
        "\n### Lock-loss boundary f_c(Θ)\n\nFold of the symmetric locked orbit followed in Θ \
         (parallel shafts, {}° steps, halved where Newton fails): forward lock p = +1 from Θ = 0, \
         reversed lock p = −1 from Θ = 54.7356° (Δ = −1), each started at the analytic f_c. \
         Above f_c(Θ) the lock of that sense does not exist.\n\n",
        boundary.step_deg
    );
    let boundary_json = match &boundary.curves {
        Ok(curves) => {
            let mut thetas: Vec<f64> = Vec::new();
            for (_, c) in curves {
                for (i, p) in c.points.iter().enumerate() {
                    let on5 = (p.along / 5.0 - (p.along / 5.0).round()).abs() < 1e-9;
                    if on5 || i + 1 == c.points.len() || i == 0 {
                        thetas.push(p.along);
                    }
                }
            }
            thetas.sort_by(f64::total_cmp);
            thetas.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
            md += "| Θ [°] | Δ | f_c, p = +1 [Hz] | f_c, p = −1 [Hz] |\n|---|---|---|---|\n";
            let exact = |c: &Curve, th: f64| {
                c.points
                    .iter()
                    .find(|p| (p.along - th).abs() < 1e-9)
                    .map(|p| p.free)
            };
            for th in &thetas {
                let cell = |p: i32| {
                    curves
                        .iter()
                        .find(|(_, c)| c.spec.winding == p)
                        .and_then(|(_, c)| exact(c, *th))
                };
                md += &format!(
                    "| {:.4} | {:+.4} | {} | {} |\n",
                    th,
                    gear.with_parallel_shafts_deg(*th).delta(),
                    fmt_opt(cell(1), 9),
                    fmt_opt(cell(-1), 9)
                );
            }
            for (label, c) in curves {
                let r = c.points.iter().map(|p| p.along);
                let (a, b) = r.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                    (a.min(v), b.max(v))
                });
                md += &format!(
                    "\n{label}: {} points over Θ = {:.3}–{:.3}°, largest Newton error estimate \
                     {:.1e} Hz{}.",
                    c.points.len(),
                    a,
                    b,
                    c.points.iter().map(|p| p.precision).fold(0.0, f64::max),
                    c.stopped
                        .as_ref()
                        .map(|s| format!("; stopped {s}"))
                        .unwrap_or_default()
                );
            }
            md += "\n";
            serde_json::json!({
                "step_deg": boundary.step_deg,
                "curves": curves.iter().map(|(label, c)| serde_json::json!({
                    "label": label, "winding": c.spec.winding, "stopped": c.stopped,
                    "points": c.points.iter().map(|p| serde_json::json!({
                        "theta_deg": p.along, "f_c_hz": p.free, "precision_hz": p.precision
                    })).collect::<Vec<_>>(),
                })).collect::<Vec<_>>(),
            })
        }
        Err(e) => {
            let t = format!("lock-loss boundary f_c(Θ): {e}");
            md += &format!("**Failed:** {t}\n");
            errors.push(t.clone());
            serde_json::json!({ "step_deg": boundary.step_deg, "error": t })
        }
    };
    #[cfg(feature = "plot")]
    if let Some(dir) = fig_dir {
        use crate::plotting::branch::{BoundaryPlot, BranchDiagram};
        let mut plot = || -> Result<()> {
            if let Ok(curves) = &boundary.curves {
                let mut marks = Vec::new();
                if let Some(fc) = gear.lock_loss_frequency() {
                    let th_rev = (2.0f64 / 3.0).sqrt().asin().to_degrees();
                    marks.push(("analytic f_c (Δ = +1)".to_string(), 0.0, fc));
                    marks.push(("f_c (Δ = −1)".to_string(), th_rev, fc));
                }
                let fig = BoundaryPlot {
                    title: "lock-loss boundary f_c(Θ) (fold of the lock)".into(),
                    curves: curves.clone(),
                    marks,
                };
                crate::plotting::save(&fig, dir.join("fc_theta.svg"))?;
                crate::plotting::save(&fig, dir.join("fc_theta.png"))?;
                figures.push("figures/fc_theta.png".into());
                md += "\n![lock-loss boundary f_c(Θ)](figures/fc_theta.png)\n";
            }
            if !branches.is_empty() {
                let fig = BranchDiagram {
                    title: format!(
                        "Θ = {BIFURCATION_THETA_DEG}°: symmetric and asymmetric orbits (β physical convention)"
                    ),
                    branches: branches.clone(),
                    paper_convention: false,
                    ..Default::default()
                };
                crate::plotting::save(&fig, dir.join("theta25_branches.svg"))?;
                crate::plotting::save(&fig, dir.join("theta25_branches.png"))?;
                figures.push("figures/theta25_branches.png".into());
                md += "\n![Θ = 25° branches](figures/theta25_branches.png)\n";
            }
            Ok(())
        };
        if let Err(e) = plot() {
            let t = format!("figures: {e}");
            md += &format!("\n**Failed:** {t}\n");
            errors.push(t);
        }
    }
    #[cfg(not(feature = "plot"))]
    let _ = (fig_dir, &branches);
    md += &format!(
        "\nComputing time: Θ = 0 fold {t_theta0:.2} s, Θ = {BIFURCATION_THETA_DEG}° branches \
         {t_theta25:.2} s.\n"
    );
    ReportSection {
        id: "bifurcations".into(),
        title: "Located bifurcations (continuation)".into(),
        markdown: md,
        figures,
        data: serde_json::json!({
            "theta0": theta0,
            "theta25": {
                "theta_deg": BIFURCATION_THETA_DEG,
                "f_range_hz": [lo, hi],
                "specials": rows,
                "symmetry_breaking": sb_json,
            },
            "lock_loss_boundary": boundary_json,
            "errors": errors,
        }),
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

/// Section: the classification map.
pub fn section_map(res: &SweepResult, fig_dir: Option<&Path>) -> Result<ReportSection> {
    let n = res.points().count();
    let count = |f: &dyn Fn(&PointRecord) -> bool| res.points().filter(|p| f(p)).count();
    let chaos = count(&|p| p.class == "chaos");
    let qp = count(&|p| p.class == "QP");
    let unres = count(&|p| p.class == "?");
    let sym = count(&|p| p.symmetric);
    let asym = count(&|p| p.half_periods > 0 && !p.symmetric);
    let slip = count(&|p| p.locked == Some(false));
    let dis = count(&|p| p.agree == Some(false));
    #[cfg_attr(not(feature = "plot"), allow(unused_mut))]
    let mut md = format!(
        "Semi-static ramp-up: for each Θ the drive frequency rises through {} log-spaced values \
         from {:.2} to {:.1} Hz, carrying the state, {} settling turns per step, start α = {}°, \
         β = {}° (paper convention). {} points: {} symmetric periodic (the paper's T/2), {} \
         asymmetric periodic (T, kT), {} chaotic (λ_max > {} per period), {} quasi-periodic, {} \
         unresolved; {} points slip (|rotation number| ≠ 1). The paper's flowchart and the rigorous \
         class disagree at {} points.\n",
        res.spec.cols.values.len(),
        res.spec.cols.values[0],
        res.spec.cols.values[res.spec.cols.values.len() - 1],
        res.spec.classify.settle_turns,
        res.spec.alpha0_deg,
        res.spec.beta0_deg,
        n,
        sym,
        asym,
        chaos,
        res.spec.classify.lyapunov_threshold,
        qp,
        unres,
        slip,
        dis
    );
    #[cfg_attr(not(feature = "plot"), allow(unused_mut))]
    let mut figures = vec![];
    #[cfg(feature = "plot")]
    if let Some(dir) = fig_dir {
        use crate::plotting::atlas::{Markers, RmsMap};
        let mut fig = RmsMap::from_sweep(res);
        fig.title = "RMS_δ, paper classes (○ chaos, × T/2, — T)".into();
        crate::plotting::save(&fig, dir.join("map_paper.png"))?;
        crate::plotting::save(&fig, dir.join("map_paper.svg"))?;
        fig.markers = Markers::Rigorous;
        fig.title = "RMS_δ, rigorous classes (○ chaos/QP, × symmetric, — asymmetric, □ ?)".into();
        crate::plotting::save(&fig, dir.join("map_rigorous.png"))?;
        crate::plotting::save(&fig, dir.join("map_rigorous.svg"))?;
        figures.push("figures/map_paper.png".into());
        figures.push("figures/map_rigorous.png".into());
        md += "\n![map, paper classes](figures/map_paper.png)\n\n![map, rigorous classes](figures/map_rigorous.png)\n";
    }
    #[cfg(not(feature = "plot"))]
    let _ = fig_dir;
    Ok(ReportSection {
        id: "map".into(),
        title: "Stability and classification map".into(),
        markdown: md,
        figures,
        data: serde_json::json!({
            "points": n, "symmetric": sym, "asymmetric": asym, "chaotic": chaos,
            "quasi_periodic": qp, "unresolved": unres, "slipping": slip, "disagree": dis,
            "csv": "map.csv"
        }),
    })
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

/// Section: operating advice, computed from the map, the hysteresis loop and, if given, the
/// lock-loss boundary f_c(Θ) from the continuation.
pub fn section_advice(
    res: &SweepResult,
    hyst: &Hysteresis,
    gear: &GearParams,
    smooth: f64,
    boundary: Option<&LockLossCurves>,
) -> ReportSection {
    let safe = safe_frequencies(res, smooth);
    let mut md = format!(
        "A point is a *good operating point* if the output is locked (|rotation number| = 1), \
         periodic and RMS_δ ≤ {smooth}°. Safe frequency: the highest f of the ramp-up up to which \
         every step was good (a property of this ramp: {} steps of {:.1} % each; finer ramps keep \
         the lock longer near f_c).",
        res.spec.cols.values.len(),
        ramp_step_percent(&res.spec.cols.values)
    );
    if boundary.is_some() {
        md += " Lock-loss limit: f_c(Θ) of the lock in the gear's natural sense (forward, p = +1, \
               for Δ ≥ 0; reversed, p = −1, for Δ < 0), located by continuation (section \
               *Located bifurcations*); above it that lock does not exist, so it bounds every safe \
               frequency from above. Recommended limit: the lower of the two; — where either is \
               missing (no good ramp step, or Θ outside the range of the computed f_c(Θ) curve).\n\n\
               | Θ [°] | Δ | safe up to f (ramp) [Hz] | lock-loss limit f_c(Θ) [Hz] | lock | recommended: below f [Hz] |\n\
               |---|---|---|---|---|---|\n";
    } else {
        md += "\n\n| Θ [°] | Δ | safe up to f [Hz] |\n|---|---|---|\n";
    }
    let mut limits = Vec::new();
    let mut above = Vec::new();
    for (th, f) in &safe {
        let d = gear.with_parallel_shafts_deg(*th).delta();
        match boundary {
            Some(b) => {
                let p = natural_winding(d);
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
                md += &format!(
                    "| {th:.0} | {d:+.3} | {} | {} | {p:+} | {} |\n",
                    fmt_opt(*f, 2),
                    fmt_opt(fc, 3),
                    fmt_opt(rec, 2)
                );
                limits.push(serde_json::json!({"theta_deg": th, "winding": p,
                    "f_c_hz": fc, "recommended_below_hz": rec}));
            }
            None => md += &format!("| {th:.0} | {d:+.3} | {} |\n", fmt_opt(*f, 2)),
        }
    }
    if let Some(b) = boundary {
        match &b.curves {
            Ok(_) => {
                md += &format!(
                    "\nRamp-safe frequencies above the lock-loss limit: {} (a locked ramp step \
                     above f_c(Θ) would be locked in the other sense).\n",
                    if above.is_empty() {
                        "none".to_string()
                    } else {
                        above
                            .iter()
                            .map(|t| format!("Θ = {t:.0}°"))
                            .collect::<Vec<_>>()
                            .join(", ")
                    }
                );
            }
            Err(e) => md += &format!("\nf_c(Θ) could not be computed: {e}\n"),
        }
    }
    // the worst shaft angle and ranges
    let worst = safe
        .iter()
        .min_by(|a, b| a.1.unwrap_or(0.0).total_cmp(&b.1.unwrap_or(0.0)))
        .map(|x| x.0);
    let mut ranges = Vec::new();
    for thr in [1.0, 5.0, 20.0] {
        let ok: Vec<f64> = safe
            .iter()
            .filter(|(_, f)| f.is_some_and(|f| f >= thr))
            .map(|x| x.0)
            .collect();
        ranges.push(serde_json::json!({"f_min_hz": thr, "theta_deg": ok}));
        md += &format!(
            "\nShaft angles safe up to at least {thr} Hz: {}.",
            if ok.is_empty() {
                "none".to_string()
            } else {
                ok.iter()
                    .map(|t| format!("{t:.0}°"))
                    .collect::<Vec<_>>()
                    .join(", ")
            }
        );
    }
    // slip-through hysteresis at Θ = 0: where does the downward run relock?
    let lost_up = hyst
        .up
        .iter()
        .find(|r| r.locked != Some(true))
        .map(|r| r.f_hz);
    let relock_down = hyst
        .down
        .iter()
        .find(|r| r.locked == Some(true))
        .map(|r| r.f_hz);
    md += &format!(
        "\n\nWorst shaft angle of the grid: Θ = {}° (largest cogging at Δ = 0, Θ = 35.26°).\n\n\
         Lock loss at Θ = 0: going up, the lock is lost at {} Hz (f_c = {} Hz); coming \
         down, the slipping state persists until it relocks at {} Hz. Between these the gear is \
         bistable: **to be safe against slip-through, operate below {} Hz**, or restart from \
         standstill after an overload. A stronger coupling g raises both.\n",
        fmt_opt(worst, 0),
        fmt_opt(lost_up, 1),
        fmt_opt(
            boundary
                .and_then(|b| b.f_c(0.0, 1))
                .or(gear.with_parallel_shafts_deg(0.0).lock_loss_frequency()),
            2
        ),
        fmt_opt(relock_down, 1),
        fmt_opt(relock_down, 1),
    );
    ReportSection {
        id: "advice".into(),
        title: "Operating advice".into(),
        markdown: md,
        figures: vec![],
        data: serde_json::json!({
            "smooth_rms_deg": smooth,
            "safe_f_hz": safe.iter().map(|(t, f)| serde_json::json!({"theta_deg": t, "f_hz": f})).collect::<Vec<_>>(),
            "theta_ranges": ranges,
            "worst_theta_deg": worst,
            "lock_lost_up_hz": lost_up,
            "relock_down_hz": relock_down,
            "lock_loss_limits": limits,
            "ramp_safe_above_f_c_theta_deg": above,
        }),
    }
}

/// Builds the report of `gear` into `dir` (figures in `dir/figures`, the map's points in
/// `dir/map.csv`), and returns it (not yet written: call [`Report::write`], possibly after
/// appending sections).
pub fn build_report(
    gear: &GearParams,
    opts: &ReportOptions,
    dir: impl AsRef<Path>,
    observer: &dyn crate::progress::Observer,
) -> Result<Report> {
    gear.validate()?;
    let dir = dir.as_ref();
    let fig_dir: Option<PathBuf> =
        (opts.figures && cfg!(feature = "plot")).then(|| dir.join("figures"));
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
        method: Method::EventDriven,
        classify: classify.clone(),
    };
    let res = match SweepRunner::new(spec).observer(observer).run()? {
        SweepOutcome::Complete(r) => r,
        SweepOutcome::Stopped { .. } => {
            return Err(crate::Error::InvalidInput("report sweep stopped".into()))
        }
    };
    crate::io::write_atomic(dir.join("map.csv"), res.to_csv()?.as_bytes())?;
    let hopts = ClassifyOptions {
        settle_turns: opts.hysteresis_settle,
        analysis_turns: 10,
        ..ClassifyOptions::default()
    };
    let hyst = hysteresis(
        gear.with_parallel_shafts_deg(0.0),
        &opts.hysteresis_f,
        0.0,
        180.0,
        Convention::Paper,
        &hopts,
        observer,
    )?;
    let mut rep = Report {
        title: "gearbif report".into(),
        preamble: format!(
            "Gear: m1 = {} A m², m2 = {} A m², r = {} m, I = {:e} kg m², ζ = {} s⁻¹, η = {} s⁻². \
             Exact event-driven (Filippov) integration, tolerance {:e}. Angles in the paper's \
             convention (β + 180°, see model.md) unless said otherwise. Generated by \
             `gearbif report`.\n",
            gear.m1, gear.m2, gear.r, gear.inertia, gear.zeta, gear.eta, classify.tol
        ),
        sections: vec![],
    };
    let boundary = opts
        .bifurcations
        .then(|| LockLossCurves::compute(gear, opts.fc_step_deg));
    rep.push(section_derived(gear));
    rep.push(section_lock_branch(gear, &hyst, fig_dir.as_deref())?);
    if let Some(b) = &boundary {
        rep.push(section_bifurcations(gear, b, fig_dir.as_deref()));
    }
    rep.push(section_map(&res, fig_dir.as_deref())?);
    rep.push(section_advice(
        &res,
        &hyst,
        gear,
        opts.smooth_rms_deg,
        boundary.as_ref(),
    ));
    Ok(rep)
}
