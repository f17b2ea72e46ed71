//! `gearbif figure <name>`: the paper's figures that the model can make (Figs. 5–10), an orbit
//! diagram and the Lyapunov exponent against f, as SVG and PNG in an output folder.

use super::common::{output_dir, GearArgs};
use super::model_arg::ModelArgs;
use super::sweep::Progress;
use crate::analysis::classify::WindowSample;
use crate::analysis::{classify_point, paper_fig6_start, ClassifyOptions};
use crate::integrator::EventDriven;
use crate::model::recorded::file::ModelFile;
use crate::model::recorded::RecordedModel;
use crate::model::{Convention, DrivenOscillator, Gear, GearParams};
use crate::plotting::atlas::{
    fit_plot, hysteresis_lock_plot, lyapunov_plot, orbit_diagram, paper_figure_delta_deg,
    updown_series, Landscape, Markers, PolarDelta, RmsMap, PAPER_FIGURE_DELTA_LABEL,
};
use crate::plotting::{save, Figure, LinePlot, Series};
use crate::progress::Observer;
use crate::sweep::{
    hysteresis, lock_loss_hysteresis, Axis, Hysteresis, PointRecord, SweepOutcome, SweepParam,
    SweepRunner, SweepSpec,
};
use crate::{Error, Result};
use std::path::{Path, PathBuf};

/// The figures.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Name {
    /// δ over α with the 7-harmonic fit at Θ = 31°: chaos, T/2, T (Fig. 5).
    Fig5,
    /// Polar δ diagrams at Θ = 31° for the paper's seven frequencies (Fig. 6).
    Fig6,
    /// RMS_δ map, fresh start at every point, Θ 0–55°, f 0.5–3 Hz (Fig. 7b).
    Fig7,
    /// RMS_δ map, semi-static ramp-up, Θ −90–90°, f 0.1–100 Hz (Fig. 8; coarse unless --full).
    Fig8,
    /// Hysteresis of the T/2 ↔ T transition at Θ = 25°: THD⁻¹, δ_fund, δ_avg, insets (Fig. 9).
    Fig9,
    /// Lock loss at Θ = 0: δ_avg with the analytic branch, net rotation, insets (Fig. 10).
    Fig10,
    /// Orbit diagram (symmetry-reduced section points) against f at Θ = 31°.
    Orbit,
    /// Largest Lyapunov exponent against f at Θ = 31°.
    Lyapunov,
}

/// Arguments of `gearbif figure`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Which figure.
    #[arg(value_enum)]
    name: Name,
    #[command(flatten)]
    gear: GearArgs,
    #[command(flatten)]
    model: ModelArgs,
    /// With --model (orbit, lyapunov): the frequency range "LO:HI" [Hz] (default: the file's
    /// recorded drive frequencies).
    #[arg(long, value_name = "LO:HI")]
    f_range: Option<String>,
    /// With --model: the number of frequencies, 2 to 10000.
    #[arg(long, default_value_t = 91)]
    points: usize,
    /// Output folder (other figures in it are kept; this figure's files are replaced together at
    /// the end).
    #[arg(long, default_value = "figures")]
    out: PathBuf,
    /// Fig. 8 at the paper's full resolution (37 × 4996 points, 1000 settling turns each), at
    /// tolerance 1e-6 with early settling and the paper's classification only (minutes).
    #[arg(long)]
    full: bool,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
}

fn save_both(fig: &impl Figure, dir: &Path, stem: &str, out: &mut Vec<PathBuf>) -> Result<()> {
    for ext in ["svg", "png"] {
        save(fig, dir.join(format!("{stem}.{ext}")))?;
        out.push(format!("{stem}.{ext}").into());
    }
    Ok(())
}

/// The paper's start of Figs. 5–6 ([`paper_fig6_start`]): simulated and shown in the physical
/// convention, where δ = β − α stays near 180° (no wrap at 0/360°).
fn paper_gear(p: &GearParams, theta: f64, f: f64) -> Result<(Gear, [f64; 2])> {
    paper_fig6_start(p, theta, f)
}

fn window<S: DrivenOscillator>(
    g: &S,
    x0: [f64; 2],
    settle: usize,
) -> Result<crate::analysis::PointResult>
where
    EventDriven: crate::integrator::FlowMethod<S>,
{
    let o = ClassifyOptions {
        settle_turns: settle,
        keep_samples: true,
        ..ClassifyOptions::default()
    };
    // the DP5, as `examples/theta31.rs`, whose table (docs/atlas.md) these windows show: the
    // numbers of the chaotic points depend on the integrator's rounding
    classify_point(g, x0, &EventDriven, &o)
}

/// The attractor of a hysteresis point, re-simulated from its end state with samples.
fn inset(p: &GearParams, r: &PointRecord, alpha0_deg: f64, title: &str) -> Result<Landscape> {
    let g = p
        .driven(r.f_hz)?
        .with_convention(Convention::Paper)
        .with_alpha0(alpha0_deg.to_radians())?;
    let w = window(&g, [r.beta_end, r.omega_end], 2)?;
    Ok(Landscape {
        title: title.into(),
        delta: g.delta,
        coupling_j: p.coupling(),
        convention: Convention::Paper,
        samples: w.samples.unwrap_or_default(),
    })
}

fn updown_plot(
    h: &Hysteresis,
    title: &str,
    y: &str,
    val: impl Fn(&PointRecord) -> Option<f64>,
) -> LinePlot {
    let pts = |v: &[PointRecord]| {
        v.iter()
            .filter_map(|r| val(r).map(|y| (r.f_hz, y)))
            .collect::<Vec<_>>()
    };
    let (series, marker_shapes) = updown_series(pts(&h.up), pts(&h.down));
    LinePlot {
        title: title.into(),
        x_label: "f [Hz]".into(),
        y_label: y.into(),
        series,
        marker_shapes,
        ..Default::default()
    }
}

/// Fig. 10b: the net rotation frequency of the output on a log axis (locked points at f_out = f,
/// slip-through points at a few percent of f and below), with the lines f_out = f and 1 % of f.
fn net_rotation_plot(h: &Hysteresis) -> LinePlot {
    let mut fig = updown_plot(
        h,
        "Θ = 0: net rotation frequency of the output (log scale)",
        "f_out [Hz]",
        |r| Some(r.net_rotation_hz),
    );
    let fs: Vec<f64> = h.up.iter().chain(&h.down).map(|r| r.f_hz).collect();
    let (lo, hi) = fs
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), &f| (a.min(f), b.max(f)));
    let not_shown =
        h.up.iter()
            .chain(&h.down)
            .filter(|r| r.net_rotation_hz <= 0.0)
            .count();
    if not_shown > 0 {
        fig.title += &format!(" ({not_shown} points with f_out ≤ 0 not shown)");
    }
    fig.log_y = true;
    for (label, k, color) in [
        ("f_out = f (locked)", 1.0, 0),
        ("f_out = 1 % of f", 0.01, 7),
    ] {
        fig.series.push(Series {
            label: label.into(),
            // sampled densely: a straight line in f is curved on the log axis
            points: (0..=200)
                .map(|i| lo + (hi - lo) * i as f64 / 200.0)
                .map(|f| (f, k * f))
                .collect(),
            markers: false,
            color,
        });
    }
    fig
}

/// Builds figure `name` into `dir` (a sweep's checkpoint into `work`); returns the names of the
/// files written.
pub fn make(
    name: Name,
    p: &GearParams,
    (dir, work): (&Path, &Path),
    full: bool,
    progress: &Progress,
) -> Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    match name {
        Name::Fig5 => fit_windows(p, dir, &mut out)?,
        Name::Fig6 => polar_windows(p, dir, &mut out)?,
        Name::Fig7 | Name::Fig8 => rms_map(name, p, (dir, work), full, progress, &mut out)?,
        Name::Fig9 => transition_hysteresis(p, dir, progress, &mut out)?,
        Name::Fig10 => lock_loss(p, dir, progress, &mut out)?,
        Name::Orbit | Name::Lyapunov => frequency_scan(name, p, dir, progress, &mut out)?,
    }
    Ok(out)
}

/// THD_F for a title: three decimals, or "≫ 1 (no component at f)" where the fundamental is
/// nearly absent (a T/2 orbit has none: the ratio is then the rounding of a vanishing amplitude).
fn thd_text(thd: f64) -> String {
    if thd.is_finite() && thd < 100.0 {
        format!("{thd:.3}")
    } else {
        "≫ 1: no component at f".into()
    }
}

/// Fig. 5: δ over α with the 7-harmonic fit at Θ = 31° for the chaotic, T/2 and T windows
/// (1.65, 1.48, 1.33 Hz), one file pair each; appends the files written to `out`.
fn fit_windows(p: &GearParams, dir: &Path, out: &mut Vec<PathBuf>) -> Result<()> {
    for (f, stem) in [(1.65, "fig5a"), (1.48, "fig5b"), (1.33, "fig5c")] {
        let (g, x0) = paper_gear(p, 31.0, f)?;
        let r = window(&g, x0, 90)?;
        let s = r.samples.clone().unwrap_or_default();
        let title = format!(
            "Θ = 31°, {f} Hz: flowchart {} (RMS_fit {:.2}°, THD {}), rigorous {}",
            r.paper.class.label(),
            r.paper.rms_fit_deg,
            thd_text(r.paper.thd),
            r.rigorous.as_ref().map(|c| c.label.as_str()).unwrap_or("")
        );
        let y = "δ = β − α [deg] (physical), within ±180° of its mean";
        save_both(&fit_plot(&title, y, &s, &r.paper.fit), dir, stem, out)?;
    }
    Ok(())
}

/// Fig. 6: the polar δ diagrams at Θ = 31° for the paper's seven frequencies, one panel each,
/// labelled with the flowchart and the rigorous class; appends the files written to `out`.
fn polar_windows(p: &GearParams, dir: &Path, out: &mut Vec<PathBuf>) -> Result<()> {
    let mut panels: Vec<(String, Vec<WindowSample>)> = Vec::new();
    for f in [1.00, 1.07, 1.33, 1.48, 1.63, 1.65, 1.68] {
        let (g, x0) = paper_gear(p, 31.0, f)?;
        let r = window(&g, x0, 90)?;
        let lab = r
            .rigorous
            .as_ref()
            .map(|c| c.label.clone())
            .unwrap_or_default();
        panels.push((
            format!("{f:.2} Hz: {} / {lab}", r.paper.class.label()),
            r.samples.unwrap_or_default(),
        ));
    }
    save_both(&PolarDelta { panels }, dir, "fig6", out)
}

/// Figs. 7b and 8: the RMS_δ map of a sweep (fresh start at every point for Fig. 7, the
/// semi-static ramp-up for Fig. 8; Fig. 8 coarse unless `full`), with the paper's classes and,
/// in a second file pair, the rigorous ones (at Fig. 8's full resolution the map alone, the
/// classes in the data folder); the sweep's data folder beside it. Appends the figure files
/// written to `out`.
fn rms_map(
    name: Name,
    p: &GearParams,
    (dir, work): (&Path, &Path),
    full: bool,
    progress: &Progress,
    out: &mut Vec<PathBuf>,
) -> Result<()> {
    let spec = if name == Name::Fig7 {
        let mut s = SweepSpec::paper_fig7(
            Axis::range(SweepParam::ThetaDeg, 0.0, 55.0, 5.0)?,
            Axis::range(SweepParam::F, 0.5, 3.0, 0.1)?,
        );
        s.gear = *p;
        s
    } else {
        let mut s = SweepSpec::paper_fig8()?;
        s.gear = *p;
        if full {
            // the paper's grid with the settings measured in docs/atlas.md (≈ 4 min):
            // tolerance 1e-6, early settling at 1e-6, the paper's classification only
            s.classify.tol = 1e-6;
            s.classify.settle_tol = Some(1e-6);
            s.classify.rigorous = false;
        } else {
            s.rows = Axis::range(SweepParam::ThetaDeg, -90.0, 90.0, 10.0)?;
            s.cols = Axis::log(SweepParam::F, 0.1, 100.0, 80)?;
            s.classify.settle_turns = 300;
        }
        s
    };
    let (stem, rigorous_stem) = match (name, full) {
        (Name::Fig7, _) => ("fig7", "fig7-rigorous"),
        (_, true) => ("fig8-full", "fig8-full-rigorous"),
        _ => ("fig8", "fig8-rigorous"),
    };
    let res = match SweepRunner::new(spec)
        .checkpoint(work.join(format!("{stem}-checkpoint")))
        .observer(progress)
        .run()?
    {
        SweepOutcome::Complete(r) => r,
        SweepOutcome::Stopped { .. } => return Err(Error::Stopped { what: "the sweep" }),
    };
    res.write(dir.join(format!("{stem}-data")))?;
    let mut fig = RmsMap::from_sweep(&res);
    if full && matches!(name, Name::Fig8) {
        // at the paper's resolution the cells are too small for class markers: the
        // classes are in the data folder
        fig.markers = Markers::None;
        fig.title = format!("{stem}: RMS_δ (classes in {stem}-data/points.csv)");
        return save_both(&fig, dir, stem, out);
    }
    fig.title = format!("{stem}: RMS_δ with the paper's classes");
    save_both(&fig, dir, stem, out)?;
    fig.markers = Markers::Rigorous;
    fig.title = format!("{stem}: RMS_δ with the rigorous classes");
    save_both(&fig, dir, rigorous_stem, out)
}

/// Fig. 9: the hysteresis of the T/2 ↔ T transition at Θ = 25° (f 1.5–3 Hz up and down):
/// THD⁻¹, δ_fund and δ_avg over f, and the attractors at 2.1 and 2.7 Hz on the way down as
/// insets; the data as `fig9-data.json`. Appends the figure files written to `out`.
fn transition_hysteresis(
    p: &GearParams,
    dir: &Path,
    progress: &Progress,
    out: &mut Vec<PathBuf>,
) -> Result<()> {
    let fs: Vec<f64> = (0..=30).map(|i| 1.5 + 0.05 * i as f64).collect();
    let o = ClassifyOptions {
        settle_turns: 1000,
        analysis_turns: 20,
        ..ClassifyOptions::default()
    };
    let pp = p.with_parallel_shafts_deg(25.0);
    let h = hysteresis(pp, &fs, 0.0, 180.0, Convention::Paper, &o, progress)?;
    crate::io::write_json_atomic(dir.join("fig9-data.json"), &h)?;
    let inv = updown_plot(
        &h,
        "Θ = 25°: inverse total harmonic distortion of δ",
        "1/THD_F (dimensionless)",
        |r| {
            Some(
                r.thd
                    .map(|t| if t > 0.0 { 1.0 / t } else { f64::INFINITY })
                    .unwrap_or(0.0),
            )
            .filter(|v| v.is_finite())
        },
    );
    save_both(&inv, dir, "fig9-thd-inv", out)?;
    let fund = updown_plot(
        &h,
        "Θ = 25°: δ_fund, amplitude of δ at the drive frequency",
        "δ_fund [deg]",
        |r| Some(r.delta_fund_deg),
    );
    save_both(&fund, dir, "fig9-fund", out)?;
    let avg = updown_plot(
        &h,
        "Θ = 25°: δ_avg, mean angle difference over a drive period",
        &format!("δ_avg: {PAPER_FIGURE_DELTA_LABEL}"),
        |r| Some(paper_figure_delta_deg(r.delta_avg_deg)),
    );
    save_both(&avg, dir, "fig9-avg", out)?;
    for (f, stem) in [(2.1, "fig9-inset-2.1-down"), (2.7, "fig9-inset-2.7-down")] {
        if let Some(r) = h.down.iter().find(|r| (r.f_hz - f).abs() < 1e-9) {
            let l = inset(&pp, r, 0.0, &format!("Θ = 25°, {f} Hz, f decreasing"))?;
            save_both(&l, dir, stem, out)?;
        }
    }
    Ok(())
}

/// Fig. 10: the lock loss at Θ = 0 (f 1–45 Hz up and down): δ_avg with the analytic branch,
/// the net rotation of the output, and the attractors at 6 Hz on both branches as insets; the
/// data as `fig10-data.json`. Appends the figure files written to `out`.
fn lock_loss(
    p: &GearParams,
    dir: &Path,
    progress: &Progress,
    out: &mut Vec<PathBuf>,
) -> Result<()> {
    let fs: Vec<f64> = (1..=45).map(|i| i as f64).collect();
    let pp = p.with_parallel_shafts_deg(0.0);
    let h = lock_loss_hysteresis(pp, &fs, 1000, progress)?;
    crate::io::write_json_atomic(dir.join("fig10-data.json"), &h)?;
    save_both(&hysteresis_lock_plot(&h, &pp)?, dir, "fig10a", out)?;
    save_both(&net_rotation_plot(&h), dir, "fig10b", out)?;
    for (branch, stem, what) in [
        (&h.up, "fig10-inset-6-up", "f increasing (locked)"),
        (&h.down, "fig10-inset-6-down", "f decreasing (slip-through)"),
    ] {
        if let Some(r) = branch.iter().find(|r| (r.f_hz - 6.0).abs() < 1e-9) {
            let l = inset(&pp, r, 0.0, &format!("Θ = 0, 6 Hz, {what}"))?;
            save_both(&l, dir, stem, out)?;
        }
    }
    Ok(())
}

/// The orbit diagram or the largest Lyapunov exponent (`name`) against f at Θ = 31° (f 0.9–1.8
/// Hz, fresh start at each f as in Fig. 6): one window per f gives both, the figure shows the
/// one asked for. Appends the files written to `out`.
fn frequency_scan(
    name: Name,
    p: &GearParams,
    dir: &Path,
    progress: &Progress,
    out: &mut Vec<PathBuf>,
) -> Result<()> {
    let fs: Vec<f64> = (0..=90).map(|i| 0.9 + 0.01 * i as f64).collect();
    let scan = scan_frequencies(&fs, |f| paper_gear(p, 31.0, f), progress)?;
    let title = "Θ = 31°, fresh start (paper Fig. 6 protocol)";
    draw_scan(name, &scan, title, dir, out)
}

/// The section points (the last 40) and the largest Lyapunov exponent per period of the window
/// of each f of `fs` (the system and its start from `at`).
type Scan = (Vec<(f64, f64)>, Vec<(f64, f64)>);

fn scan_frequencies<S: DrivenOscillator>(
    fs: &[f64],
    at: impl Fn(f64) -> Result<(S, [f64; 2])>,
    progress: &Progress,
) -> Result<Scan>
where
    EventDriven: crate::integrator::FlowMethod<S>,
{
    let mut orbit = Vec::new();
    let mut lyap = Vec::new();
    for (i, &f) in fs.iter().enumerate() {
        let (g, x0) = at(f)?;
        let r = window(&g, x0, 90)?;
        if let Some(z) = &r.section {
            let n = z.len();
            for v in &z[n.saturating_sub(40)..] {
                orbit.push((f, v[0].to_degrees()));
            }
        }
        if let Some(l) = r.rigorous.as_ref().and_then(|c| c.lyapunov.per_period) {
            lyap.push((f, l));
        }
        progress.observe(&crate::progress::Event::SweepPoint { row: 0, col: i });
    }
    Ok((orbit, lyap))
}

/// The figure `name` (orbit or Lyapunov) of a scan, titled `title`.
fn draw_scan(
    name: Name,
    scan: &Scan,
    title: &str,
    dir: &Path,
    out: &mut Vec<PathBuf>,
) -> Result<()> {
    if name == Name::Orbit {
        save_both(&orbit_diagram(title, &scan.0, false), dir, "orbit", out)
    } else {
        let t = format!("{title}: largest Lyapunov exponent");
        save_both(&lyapunov_plot(&t, &scan.1, false), dir, "lyapunov", out)
    }
}

/// The frequencies of `figure orbit|lyapunov --model FILE`: `--points` over `--f-range` (or the
/// file's recorded drive frequencies). The paper's figures (fig5–fig10) are the paper's gear's.
fn recorded_frequencies(a: &Args, file: &ModelFile) -> Result<Vec<f64>> {
    if !matches!(a.name, Name::Orbit | Name::Lyapunov) {
        return Err(Error::inconsistent(
            format!("--model, {:?}", a.name).to_lowercase(),
            "figures fig5–fig10 draw the paper's gear at the paper's set-ups; with --model: orbit, lyapunov",
        ));
    }
    let (lo, hi) = match (&a.f_range, file.recorded) {
        (Some(r), _) => super::continue_::parse_range(r)?,
        (None, Some(r)) => (r.drive_hz[0], r.drive_hz[1]),
        (None, None) => {
            return Err(Error::inconsistent(
                "--model, --f-range",
                "the model file has no recorded range: give --f-range LO:HI",
            ))
        }
    };
    super::common::frequency("f_range", lo)?;
    super::common::frequency("f_range", hi)?;
    super::common::count("points", a.points, 2, 10_000)?;
    let n = a.points - 1;
    Ok((0..=n)
        .map(|i| lo + (hi - lo) * i as f64 / n as f64)
        .collect())
}

/// The scan of the recorded gear of `file` over `fs`, fresh start from the locked input's
/// equilibrium at each frequency.
fn recorded_scan(
    a: &Args,
    (file, fs): (&ModelFile, &[f64]),
    dir: &Path,
    progress: &Progress,
) -> Result<Vec<PathBuf>> {
    let at = |f: f64| -> Result<(RecordedModel, [f64; 2])> {
        let m = file.model(f)?;
        let x0 = super::model_arg::start(&m, &None)?;
        Ok((m, x0))
    };
    let scan = scan_frequencies(fs, at, progress)?;
    let title = format!("Θ = {}° (model file), fresh start", file.setup.theta_deg);
    let mut out = Vec::new();
    draw_scan(a.name, &scan, &title, dir, &mut out)?;
    Ok(out)
}

/// The names a figure writes into its folder: figures (`.svg`, `.png`) and data (`.json`)
/// files, a sweep's `-data` and `-checkpoint` folders.
fn owned(name: &str, is_dir: bool) -> bool {
    if is_dir {
        name.ends_with("-data") || name.ends_with("-checkpoint")
    } else {
        [".svg", ".png", ".json"].iter().any(|e| name.ends_with(e))
    }
}

/// Runs `gearbif figure`.
pub fn run(a: Args) -> Result<()> {
    let file = a.model.file(&a.gear)?;
    let fs = file
        .as_ref()
        .map(|f| recorded_frequencies(&a, f))
        .transpose()?;
    let p = a.gear.params()?;
    output_dir("--out", &a.out)?;
    // the plan before the work; the figure's files are written into a staging folder inside
    // --out and moved into place at the end, beside the other figures (a sweep's checkpoint is
    // the work and stays in --out, so a rerun resumes from it)
    let label = format!("figure-{:?}", a.name).to_lowercase();
    let staged = crate::io::StagedDir::begin_merge("--out", &a.out, &label, owned)?;
    let progress = Progress::new(a.quiet);
    let t = std::time::Instant::now();
    let files = match (&file, &fs) {
        (Some(f), Some(fs)) => recorded_scan(&a, (f, fs), staged.path(), &progress)?,
        _ => make(a.name, &p, (staged.path(), &a.out), a.full, &progress)?,
    };
    progress.finish();
    staged.commit()?;
    for f in files {
        eprintln!("wrote {}", a.out.join(f).display());
    }
    eprintln!("in {:.1} s", t.elapsed().as_secs_f64());
    Ok(())
}
