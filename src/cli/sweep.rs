//! `gearbif sweep`: a two-parameter atlas with the paper's protocols, in parallel over rows, with
//! a progress bar and resumable checkpoints in the output directory; `--shard i/N` runs one part of
//! the rows (a cluster job-array task) and `gearbif sweep merge` combines the parts.

use super::common::{angle_deg, count, frequency, limits, output_dir, tolerance, GearArgs};
use crate::analysis::ClassifyOptions;
use crate::io::WorkDir;
use crate::sweep::{
    merge_shards, spec_hash, Axis, Method, Protocol, Shard, SweepOutcome, SweepParam, SweepResult,
    SweepRunner, SweepSpec,
};
use crate::Result;
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};

/// Arguments of `gearbif sweep`.
#[derive(Debug, clap::Args)]
#[command(args_conflicts_with_subcommands = true)]
pub struct Args {
    #[command(subcommand)]
    command: Option<SweepCommand>,
    #[command(flatten)]
    pub(super) gear: GearArgs,
    #[command(flatten)]
    model: super::model_arg::ModelArgs,
    /// Row axis (parallel): param:start:stop:step or param:start:stop:n:log
    /// (param: a name of the gear's lens — theta [deg, within ±360], f [Hz, in [1e-3, 1e4]], zeta,
    /// eta, g [>= 0], delta — or inertia [> 0]). At most 1e7 points per axis and in the whole grid.
    #[arg(long, default_value = "theta:0:50:10")]
    pub(super) rows: String,
    /// Column axis (sequential; the semi-static protocol carries the state along it), as --rows.
    #[arg(long, default_value = "f:0.5:3:0.25")]
    pub(super) cols: String,
    /// Start every point afresh (Fig. 7b) or carry the state along a row (Fig. 8).
    #[arg(long, value_enum, default_value_t = ProtocolArg::Fresh)]
    pub(super) protocol: ProtocolArg,
    /// Preset: the paper's Fig. 8 grid (overrides axes, protocol, start, settle).
    #[arg(long)]
    pub(super) fig8: bool,
    /// Drive frequency when f is not an axis [Hz], in [1e-3, 1e4].
    #[arg(long, default_value_t = 1.0)]
    pub(super) f: f64,
    /// Input angle α at t = 0 [deg], in [-360, 360].
    #[arg(long, default_value_t = 90.0, allow_hyphen_values = true)]
    pub(super) alpha0_deg: f64,
    /// Output angle β at t = 0 [deg], in [-360, 360], in the --convention.
    #[arg(long, default_value_t = 90.0, allow_hyphen_values = true)]
    pub(super) beta0_deg: f64,
    /// Settling turns per point, 0 to 1000000 (paper: 90 fresh, 1000 semi-static).
    #[arg(long)]
    settle: Option<usize>,
    /// Recorded turns per point, 1 to 100000.
    #[arg(long, default_value_t = 10)]
    record: usize,
    /// Turns of the rigorous analysis per point, 0 (skip it) or 2 to 1000000.
    #[arg(long, default_value_t = 60)]
    analysis: usize,
    /// Integrator tolerance, in (0, 1).
    #[arg(long, default_value_t = 1e-9)]
    pub(super) tol: f64,
    /// Use the paper's fixed-step RK4 (T/50) instead of the exact integrator.
    #[arg(long)]
    pub(super) rk4: bool,
    /// Use the event-driven DP5 instead of the default event-driven DOP853.
    #[arg(long, conflicts_with = "rk4")]
    pub(super) dp5: bool,
    /// Output directory (checkpoints in it; rerun the same command to resume); complete.json is
    /// written last, when the sweep is complete.
    #[arg(long, default_value = "sweep-out")]
    pub(super) out: PathBuf,
    /// Stop after this many new rows (the rest can be resumed later).
    #[arg(long)]
    pub(super) max_rows: Option<usize>,
    /// No progress bar.
    #[arg(long)]
    pub(super) quiet: bool,
    /// End the settling early once the state repeats (period ≤ 8 turns) to this distance
    /// (e.g. 1e-8; in (0, 1)); default: integrate every settling turn as the paper did.
    #[arg(long)]
    settle_tol: Option<f64>,
    /// Settling turns of a semi-static point that follows a non-periodic (quasi-periodic or
    /// chaotic) point, whose start already lies on the neighbouring attractor (e.g. 100; 1 to the
    /// settling turns); default: the full settling for every point.
    #[arg(long, value_name = "TURNS")]
    settle_nonperiodic: Option<usize>,
    /// Compute only shard i of N (0 <= i < N; rows r with r mod N = i), e.g. `--shard
    /// $SLURM_ARRAY_TASK_ID/8`; combine the shards' --out directories with `gearbif sweep merge`.
    #[arg(long, value_name = "i/N")]
    pub(super) shard: Option<String>,
}

/// Subcommands of `gearbif sweep`.
#[derive(Debug, clap::Subcommand)]
pub enum SweepCommand {
    /// Combine the --out directories of all shards of one sweep into the sweep's outputs; refuses
    /// if the shards belong to different specs (hash), a shard is missing or incomplete.
    Merge(MergeArgs),
}

/// Arguments of `gearbif sweep merge`.
#[derive(Debug, clap::Args)]
pub struct MergeArgs {
    /// The shards' --out directories (or their checkpoint directories).
    #[arg(required = true)]
    dirs: Vec<PathBuf>,
    /// Output directory of the merged sweep (complete.json written last).
    #[arg(long, default_value = "sweep-out")]
    out: PathBuf,
}

/// `--protocol` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ProtocolArg {
    /// Fresh start at every point.
    Fresh,
    /// Carry the state along a row.
    SemiStatic,
}

/// A progress bar with an ETA, as a sweep observer; when stderr is not a terminal (a log file, a
/// batch job), one line per finished row with the points done and the estimated time left.
pub struct Progress {
    bar: ProgressBar,
    /// Log lines instead of a bar: (start, points done before, points done now, points in all).
    lines: Option<std::sync::Mutex<(std::time::Instant, usize, usize, usize)>>,
}

impl Progress {
    /// A hidden bar when `quiet`.
    pub fn new(quiet: bool) -> Self {
        let bar = if quiet {
            ProgressBar::hidden()
        } else {
            let b = ProgressBar::new(0);
            b.set_style(
                ProgressStyle::with_template(
                    "{elapsed_precise} [{bar:40}] {pos}/{len} points, ETA {eta} {msg}",
                )
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
            );
            b
        };
        let lines = (!quiet && !std::io::IsTerminal::is_terminal(&std::io::stderr()))
            .then(|| std::sync::Mutex::new((std::time::Instant::now(), 0, 0, 0)));
        Self { bar, lines }
    }

    /// A log line (no terminal): the points done, the elapsed time and the time left.
    fn log(&self, event: &crate::progress::Event<'_>) {
        use crate::progress::Event;
        let Some(m) = &self.lines else {
            return;
        };
        let Ok(mut st) = m.lock() else {
            return;
        };
        match *event {
            Event::Started { total, done } => {
                *st = (std::time::Instant::now(), done, done, total.unwrap_or(0));
                eprintln!("sweep: {} points, {done} done before", st.3);
            }
            Event::SweepPoint { .. } => st.2 += 1,
            Event::RowDone { row, .. } => {
                let (t0, before, now, total) = *st;
                let secs = t0.elapsed().as_secs_f64();
                let rate = (now - before) as f64 / secs.max(1e-9);
                let left = total.saturating_sub(now) as f64 / rate.max(1e-9);
                eprintln!(
                    "sweep: row {row} done, {now}/{total} points in {secs:.0} s, about {left:.0} s left"
                );
            }
            _ => {}
        }
    }
    /// Finishes the bar.
    pub fn finish(&self) {
        self.bar.finish();
    }
}

impl crate::progress::Observer for Progress {
    fn observe(&self, event: &crate::progress::Event<'_>) {
        use crate::progress::Event;
        self.log(event);
        match *event {
            Event::Started { total, done } => {
                if let Some(total) = total {
                    self.bar.set_length(total as u64);
                }
                self.bar.set_position(done as u64);
                self.bar.reset_eta();
            }
            Event::SweepPoint { .. } => self.bar.inc(1),
            Event::RowDone { row, .. } => {
                self.bar.set_message(format!("(row {row} checkpointed)"));
            }
            _ => {}
        }
    }
}

/// The spec from the arguments.
pub fn spec(a: &Args) -> Result<SweepSpec> {
    check_args(a, true)?;
    let gear = a.gear.params()?;
    let mut s = if a.fig8 {
        SweepSpec::paper_fig8()?
    } else {
        SweepSpec {
            gear,
            f: crate::error::positive("f", a.f)?,
            rows: Axis::parse(&a.rows)?,
            cols: Axis::parse(&a.cols)?,
            protocol: match a.protocol {
                ProtocolArg::Fresh => Protocol::Fresh,
                ProtocolArg::SemiStatic => Protocol::SemiStatic,
            },
            alpha0_deg: a.alpha0_deg,
            beta0_deg: a.beta0_deg,
            convention: a.gear.convention(),
            method: Method::EventDriven853,
            classify: ClassifyOptions::default(),
        }
    };
    if a.fig8 {
        s.gear = gear;
    }
    s.classify = classify_options(a, s.classify.clone(), s.protocol == Protocol::SemiStatic);
    s.method = if a.rk4 {
        Method::FixedStep
    } else if a.dp5 {
        Method::EventDriven
    } else {
        Method::EventDriven853
    };
    s.validate()?;
    Ok(s)
}

/// The classification settings of the arguments over `base` (the protocol's defaults): a
/// semi-static sweep settles 1000 turns unless --settle or --fig8 says otherwise.
fn classify_options(a: &Args, base: ClassifyOptions, semi_static: bool) -> ClassifyOptions {
    let mut c = base;
    if let Some(n) = a.settle {
        c.settle_turns = n;
    } else if !a.fig8 && semi_static {
        c.settle_turns = 1000;
    }
    c.record_turns = a.record;
    c.settle_tol = a.settle_tol;
    c.settle_after_nonperiodic = a.settle_nonperiodic;
    c.tol = a.tol;
    if a.analysis == 0 || a.rk4 {
        c.rigorous = false;
    } else {
        c.analysis_turns = a.analysis;
    }
    c
}

/// The result files of a sweep's output folder (besides its `checkpoint` folder).
const RESULT: [&str; 4] = ["points.csv", "sweep.json", "rms_map.svg", "rms_map.png"];

/// The output folder of a sweep, its plan checked (a resumable work folder with a completion
/// marker, `src/io/workdir.rs`).
fn work_dir(out: &Path) -> Result<WorkDir> {
    WorkDir::begin("--out", out, "sweep", &RESULT, &["checkpoint"])
}

/// Writes the outputs of a complete sweep (points.csv, sweep.json, the RMS map), then the
/// completion marker.
fn write_outputs(res: &SweepResult, work: WorkDir, seconds: f64) -> Result<()> {
    let out = work.path().to_path_buf();
    res.write(&out)?;
    #[cfg(feature = "plot")]
    {
        let fig = crate::plotting::atlas::RmsMap::from_sweep(res);
        crate::plotting::save(&fig, out.join("rms_map.svg"))?;
        crate::plotting::save(&fig, out.join("rms_map.png"))?;
    }
    let written = if cfg!(feature = "plot") {
        &RESULT[..]
    } else {
        &RESULT[..2]
    };
    work.complete(written)?;
    let n = res.points().count();
    let dis = res.points().filter(|p| p.agree == Some(false)).count();
    eprintln!(
        "done: {n} points in {seconds:.1} s; wrote {}/points.csv, sweep.json, rms_map.svg/png; paper and rigorous classes disagree at {dis} points",
        out.display()
    );
    Ok(())
}

/// Runs `gearbif sweep merge`.
fn merge(a: MergeArgs) -> Result<()> {
    output_dir("--out", &a.out)?;
    let t = std::time::Instant::now();
    let dirs: Vec<PathBuf> = a
        .dirs
        .iter()
        .map(|d| {
            let c = d.join("checkpoint");
            if c.is_dir() {
                c
            } else {
                d.clone()
            }
        })
        .collect();
    let work = work_dir(&a.out)?;
    let res = merge_shards(&dirs)?;
    eprintln!(
        "merged {} shards of sweep {}",
        dirs.len(),
        spec_hash(&res.spec)?
    );
    write_outputs(&res, work, t.elapsed().as_secs_f64())
}

/// Runs `gearbif sweep`.
pub fn run(a: Args) -> Result<()> {
    if let Some(SweepCommand::Merge(m)) = a.command {
        return merge(m);
    }
    if let Some(file) = a.model.file(&a.gear)? {
        check_args(&a, false)?;
        let semi = a.protocol == ProtocolArg::SemiStatic;
        let opts = classify_options(&a, ClassifyOptions::default(), semi);
        return super::sweep_model::run(&a, &a.model, &file, &opts);
    }
    let spec = spec(&a)?;
    let shard = a.shard.as_deref().map(Shard::parse).transpose()?;
    let work = work_dir(&a.out)?;
    let progress = Progress::new(a.quiet);
    let mut runner = SweepRunner::new(spec)
        .checkpoint(a.out.join("checkpoint"))
        .observer(&progress);
    if let Some(n) = a.max_rows {
        runner = runner.max_new_rows(n);
    }
    let t = std::time::Instant::now();
    if let Some(shard) = shard {
        let st = runner.run_shard(shard)?;
        progress.finish();
        eprintln!(
            "shard {}/{}: {}/{} rows done in {:.1} s ({}); merge with `gearbif sweep merge DIR...`",
            shard.index,
            shard.count,
            st.rows_done,
            st.rows_total,
            t.elapsed().as_secs_f64(),
            if st.complete() {
                "complete"
            } else {
                "rerun the same command to resume"
            }
        );
        return Ok(());
    }
    let outcome = runner.run()?;
    progress.finish();
    match outcome {
        SweepOutcome::Complete(res) => {
            write_outputs(&res, work, t.elapsed().as_secs_f64())?;
        }
        SweepOutcome::Stopped {
            rows_done,
            rows_total,
        } => eprintln!(
            "stopped after {rows_done}/{rows_total} rows; rerun the same command to resume from {}",
            a.out.join("checkpoint").display()
        ),
    }
    Ok(())
}

/// The domain checks of `sweep`, all before any point is computed or any file written.
/// (`gear_axes`: the axes are the paper's gear's; a recorded gear's are checked by its lens.)
fn check_args(a: &Args, gear_axes: bool) -> Result<()> {
    frequency("f", a.f)?;
    angle_deg("alpha0_deg", a.alpha0_deg)?;
    angle_deg("beta0_deg", a.beta0_deg)?;
    tolerance("tol", a.tol)?;
    if let Some(e) = a.settle_tol {
        tolerance("settle_tol", e)?;
    }
    if let Some(n) = a.settle {
        count("settle", n, 0, limits::TURNS_MAX)?;
    }
    if let Some(n) = a.settle_nonperiodic {
        count("settle_nonperiodic", n, 1, limits::TURNS_MAX)?;
    }
    count("record", a.record, 1, 100_000)?;
    if a.analysis != 0 {
        count("analysis", a.analysis, 2, limits::TURNS_MAX)?;
    }
    if gear_axes && !a.fig8 {
        for axis in [&a.rows, &a.cols] {
            check_axis(&Axis::parse(axis)?)?;
        }
    }
    output_dir("--out", &a.out)
}

/// Checks every value of an axis against its parameter's domain.
fn check_axis(axis: &Axis) -> Result<()> {
    for &v in &axis.values {
        match axis.param {
            SweepParam::Lens(p) => super::common::param_value(p, v).map(drop)?,
            SweepParam::Inertia => crate::error::positive("inertia", v).map(drop)?,
        }
    }
    Ok(())
}
