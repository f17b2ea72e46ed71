//! The gear report (`gearbif report`): a self-contained folder with `report.md`, its figures and
//! `report.json`. The report is made in three separate steps:
//!
//! 1. [`compute`]: every number, as data ([`ReportData`]): the map sweep, the Θ = 0 hysteresis
//!    loop, derived quantities, the analytic lock branch with its numerical check, the
//!    bifurcations located by continuation (fold of the lock at Θ = 0, every special point at
//!    Θ = 25° between 1.5 and 3 Hz, the lock-loss boundary f_c(Θ)), class counts of the map and
//!    the operating advice;
//! 2. [`figures`] (feature `plot`): the figures, drawn from that data;
//! 3. [`markdown`]: the text of each section, from the data and the figure links.
//!
//! [`build_report`] runs the three and returns a [`Report`]: a list of [`ReportSection`]s whose
//! `data` is the JSON of the section's data. Further sections can be pushed before
//! [`Report::write`].

pub mod compute;
#[cfg(feature = "plot")]
pub mod figures;
pub mod markdown;
pub mod recorded;

pub use compute::{
    compute_report, safe_frequencies, LockLossCurves, ReportData, BIFURCATION_F_RANGE_HZ,
    BIFURCATION_THETA_DEG,
};

use crate::error::Result;
use crate::sweep::{Axis, SweepParam};
use serde::Serialize;
use std::path::Path;

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
    /// Frequencies of the Θ = 0 hysteresis loop (ascending; the coarse default is the loop of
    /// `gearbif figure fig10`, 1–45 Hz in 1 Hz with 1000 settling turns).
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
            hysteresis_settle: 1000,
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

fn to_json<T: Serialize>(v: &T) -> serde_json::Value {
    serde_json::to_value(v).unwrap_or_else(|e| serde_json::json!({ "error": e.to_string() }))
}

fn section(
    id: &str,
    title: &str,
    markdown: String,
    figures: &[(String, String)],
    data: serde_json::Value,
) -> ReportSection {
    ReportSection {
        id: id.into(),
        title: title.into(),
        markdown: markdown + &markdown::figure_links(figures),
        figures: figures.iter().map(|f| f.0.clone()).collect(),
        data,
    }
}

/// Figure links of the sections (empty without figures).
#[derive(Debug, Clone, Default)]
struct Links {
    lock_branch: Vec<(String, String)>,
    bifurcations: Vec<(String, String)>,
    bifurcation_errors: Vec<String>,
    map: Vec<(String, String)>,
}

#[cfg(feature = "plot")]
fn draw_figures(d: &ReportData, dir: &Path) -> Result<Links> {
    std::fs::create_dir_all(dir).map_err(|e| crate::Error::file("create", dir, e))?;
    let f = figures::draw(d, dir)?;
    Ok(Links {
        lock_branch: f.lock_branch,
        bifurcations: f.bifurcations,
        bifurcation_errors: f.bifurcation_errors,
        map: f.map,
    })
}

#[cfg(not(feature = "plot"))]
fn draw_figures(_: &ReportData, _: &Path) -> Result<Links> {
    Ok(Links::default())
}

/// The report of computed data `d` with figure links `l`.
fn assemble(d: &ReportData, l: &Links) -> Report {
    let mut rep = Report {
        title: "gearbif report".into(),
        preamble: format!(
            "Gear: m1 = {} A m², m2 = {} A m², r = {} m, I = {:e} kg m², ζ = {} s⁻¹, η = {} s⁻². \
             Exact event-driven (Filippov) integration, tolerance {:e}. Angles in the paper's \
             convention (β + 180°, see model.md) unless said otherwise. Generated by \
             `gearbif report`.\n",
            d.gear.m1, d.gear.m2, d.gear.r, d.gear.inertia, d.gear.zeta, d.gear.eta, d.tol
        ),
        sections: vec![],
    };
    rep.push(section(
        "derived",
        "Derived quantities",
        markdown::derived(&d.derived),
        &[],
        to_json(&d.derived),
    ));
    rep.push(section(
        "lock_branch",
        "Analytic lock branch and f_c",
        markdown::lock_branch(&d.lock_branch),
        &l.lock_branch,
        to_json(&d.lock_branch),
    ));
    if let Some(b) = &d.bifurcations {
        let mut errors = b.errors.clone();
        errors.extend(l.bifurcation_errors.iter().map(|e| format!("figures: {e}")));
        let md = markdown::bifurcations(&d.gear, b, &l.bifurcations, &l.bifurcation_errors);
        let data = serde_json::json!({
            "theta0": to_json(&b.theta0),
            "theta25": to_json(&b.theta25),
            "lock_loss_boundary": b.boundary.to_json(),
            "errors": errors,
            "seconds_theta0": b.seconds_theta0,
            "seconds_theta25": b.seconds_theta25,
        });
        // the figures are linked inside the section's text (after the f_c(Θ) table)
        let mut s = section(
            "bifurcations",
            "Located bifurcations (continuation)",
            md,
            &[],
            data,
        );
        s.figures = l.bifurcations.iter().map(|f| f.0.clone()).collect();
        rep.push(s);
    }
    rep.push(section(
        "map",
        "Stability and classification map",
        markdown::map(&d.map, &d.map_summary),
        &l.map,
        to_json(&d.map_summary),
    ));
    rep.push(section(
        "advice",
        "Operating advice",
        markdown::advice(&d.advice, &d.gear),
        &[],
        to_json(&d.advice),
    ));
    rep
}

/// Builds the report of `gear` into `dir`: computes its data ([`compute_report`]), writes the
/// map's points to `dir/map.csv`, draws the figures into `dir/figures` (if `opts.figures` and the
/// feature `plot`), and returns the report (not yet written: call [`Report::write`], possibly after
/// appending sections).
pub fn build_report(
    gear: &crate::model::GearParams,
    opts: &ReportOptions,
    dir: impl AsRef<Path>,
    observer: &dyn crate::progress::Observer,
) -> Result<Report> {
    let dir = dir.as_ref();
    let d = compute_report(gear, opts, observer)?;
    crate::io::write_atomic(dir.join("map.csv"), d.map.to_csv()?.as_bytes())?;
    let links = if opts.figures {
        draw_figures(&d, &dir.join("figures"))?
    } else {
        Links::default()
    };
    Ok(assemble(&d, &links))
}
