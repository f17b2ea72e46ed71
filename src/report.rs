//! The gear report (`gearbif report`): a self-contained folder with `report.md`, its figures and
//! `report.json`. A [`Report`] is a list of [`ReportSection`]s, each computed by its own function,
//! so further sections (e.g. located bifurcations from the continuation) can be appended by other
//! modules: build one and push it before [`Report::write`].
//!
//! Sections built here: derived quantities (g, Δ, f_c, cogging-free angles); the analytic lock
//! branch with a numerical check; the stability/classification map (a coarse Θ × f sweep,
//! semi-static ramp-up as a gear is started); the lock-loss hysteresis at Θ = 0; operating advice
//! computed from the map and the hysteresis.

use crate::analysis::ClassifyOptions;
use crate::error::Result;
use crate::model::gear::cogging_free_parallel_angles;
use crate::model::{Convention, Gear, GearParams};
use crate::sweep::{
    hysteresis, Axis, Hysteresis, Method, PointRecord, Protocol, SweepObserver, SweepOutcome,
    SweepParam, SweepResult, SweepRunner, SweepSpec,
};
use serde::Serialize;
use std::path::{Path, PathBuf};

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
        crate::io::write_json_atomic(dir.join("report.json"), self)
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

/// Section: operating advice, computed from the map and the hysteresis loop.
pub fn section_advice(
    res: &SweepResult,
    hyst: &Hysteresis,
    gear: &GearParams,
    smooth: f64,
) -> ReportSection {
    let safe = safe_frequencies(res, smooth);
    let mut md = format!(
        "A point is a *good operating point* if the output is locked (|rotation number| = 1), \
         periodic and RMS_δ ≤ {smooth}°. Safe frequency: the highest f of the ramp-up up to which \
         every step was good (a property of this ramp: {} steps of {:.1} % each; finer ramps keep \
         the lock longer near f_c).\n\n| Θ [°] | Δ | safe up to f [Hz] |\n|---|---|---|\n",
        res.spec.cols.values.len(),
        ramp_step_percent(&res.spec.cols.values)
    );
    for (th, f) in &safe {
        let d = gear.with_parallel_shafts_deg(*th).delta();
        md += &format!("| {th:.0} | {d:+.3} | {} |\n", fmt_opt(*f, 2));
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
         Lock loss at Θ = 0: going up, the lock is lost at {} Hz (analytic f_c = {} Hz); coming \
         down, the slipping state persists until it relocks at {} Hz. Between these the gear is \
         bistable: **to be safe against slip-through, operate below {} Hz**, or restart from \
         standstill after an overload. A stronger coupling g raises both.\n",
        fmt_opt(worst, 0),
        fmt_opt(lost_up, 1),
        fmt_opt(gear.with_parallel_shafts_deg(0.0).lock_loss_frequency(), 2),
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
    observer: &dyn SweepObserver,
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
    rep.push(section_derived(gear));
    rep.push(section_lock_branch(gear, &hyst, fig_dir.as_deref())?);
    rep.push(section_map(&res, fig_dir.as_deref())?);
    rep.push(section_advice(&res, &hyst, gear, opts.smooth_rms_deg));
    Ok(rep)
}
