//! `gearbif sweep`: a two-parameter atlas with the paper's protocols, in parallel over rows, with
//! a progress bar and resumable checkpoints in the output directory.

use super::common::{angle_deg, count, frequency, limits, output_dir, tolerance, GearArgs};
use crate::analysis::ClassifyOptions;
use crate::sweep::{
    Axis, Method, Protocol, SweepObserver, SweepOutcome, SweepParam, SweepRunner, SweepSpec,
};
use crate::Result;
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};

/// Arguments of `gearbif sweep`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    gear: GearArgs,
    /// Row axis (parallel): param:start:stop:step or param:start:stop:n:log
    /// (param: theta [deg, within ±360], f [Hz, in [1e-3, 1e4]], zeta, eta [>= 0], inertia [> 0]).
    #[arg(long, default_value = "theta:0:50:10")]
    rows: String,
    /// Column axis (sequential; the semi-static protocol carries the state along it).
    #[arg(long, default_value = "f:0.5:3:0.25")]
    cols: String,
    /// Start every point afresh (Fig. 7b) or carry the state along a row (Fig. 8).
    #[arg(long, value_enum, default_value_t = ProtocolArg::Fresh)]
    protocol: ProtocolArg,
    /// Preset: the paper's Fig. 8 grid (overrides axes, protocol, start, settle).
    #[arg(long)]
    fig8: bool,
    /// Drive frequency when f is not an axis [Hz], in [1e-3, 1e4].
    #[arg(long, default_value_t = 1.0)]
    f: f64,
    /// Input angle α at t = 0 [deg], in [-360, 360].
    #[arg(long, default_value_t = 90.0, allow_hyphen_values = true)]
    alpha0_deg: f64,
    /// Output angle β at t = 0 [deg], in [-360, 360], in the --convention.
    #[arg(long, default_value_t = 90.0, allow_hyphen_values = true)]
    beta0_deg: f64,
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
    tol: f64,
    /// Use the paper's fixed-step RK4 (T/50) instead of the exact integrator.
    #[arg(long)]
    rk4: bool,
    /// Output directory (checkpoints in it; rerun the same command to resume).
    #[arg(long, default_value = "sweep-out")]
    out: PathBuf,
    /// Stop after this many new rows (the rest can be resumed later).
    #[arg(long)]
    max_rows: Option<usize>,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
    /// End the settling early once the state repeats (period ≤ 8 turns) to this distance
    /// (e.g. 1e-8; in (0, 1)); default: integrate every settling turn as the paper did.
    #[arg(long)]
    settle_tol: Option<f64>,
}

/// `--protocol` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum ProtocolArg {
    /// Fresh start at every point.
    Fresh,
    /// Carry the state along a row.
    SemiStatic,
}

/// A progress bar with an ETA, as a sweep observer.
pub struct Progress {
    bar: ProgressBar,
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
        Self { bar }
    }
    /// Finishes the bar.
    pub fn finish(&self) {
        self.bar.finish();
    }
}

impl SweepObserver for Progress {
    fn started(&self, total: usize, done: usize) {
        self.bar.set_length(total as u64);
        self.bar.set_position(done as u64);
        self.bar.reset_eta();
    }
    fn point_done(&self, _row: usize, _col: usize) {
        self.bar.inc(1);
    }
    fn row_done(&self, row: usize, _path: Option<&Path>) {
        self.bar.set_message(format!("(row {row} checkpointed)"));
    }
}

/// The spec from the arguments.
pub fn spec(a: &Args) -> Result<SweepSpec> {
    check_args(a)?;
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
            method: Method::EventDriven,
            classify: ClassifyOptions::default(),
        }
    };
    if a.fig8 {
        s.gear = gear;
    }
    if let Some(n) = a.settle {
        s.classify.settle_turns = n;
    } else if !a.fig8 && s.protocol == Protocol::SemiStatic {
        s.classify.settle_turns = 1000;
    }
    s.classify.record_turns = a.record;
    s.classify.settle_tol = a.settle_tol;
    s.classify.tol = a.tol;
    if a.analysis == 0 || a.rk4 {
        s.classify.rigorous = false;
    } else {
        s.classify.analysis_turns = a.analysis;
    }
    if a.rk4 {
        s.method = Method::FixedStep;
    }
    s.validate()?;
    Ok(s)
}

/// Runs `gearbif sweep`.
pub fn run(a: Args) -> Result<()> {
    let spec = spec(&a)?;
    let progress = Progress::new(a.quiet);
    let mut runner = SweepRunner::new(spec)
        .checkpoint(a.out.join("checkpoint"))
        .observer(&progress);
    if let Some(n) = a.max_rows {
        runner = runner.max_new_rows(n);
    }
    let t = std::time::Instant::now();
    let outcome = runner.run()?;
    progress.finish();
    match outcome {
        SweepOutcome::Complete(res) => {
            res.write(&a.out)?;
            #[cfg(feature = "plot")]
            {
                let fig = crate::plotting::atlas::RmsMap::from_sweep(&res);
                crate::plotting::save(&fig, a.out.join("rms_map.svg"))?;
                crate::plotting::save(&fig, a.out.join("rms_map.png"))?;
            }
            let n = res.points().count();
            let dis = res.points().filter(|p| p.agree == Some(false)).count();
            eprintln!(
                "done: {n} points in {:.1} s; wrote {}/points.csv, sweep.json, rms_map.svg/png; paper and rigorous classes disagree at {dis} points",
                t.elapsed().as_secs_f64(),
                a.out.display()
            );
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
fn check_args(a: &Args) -> Result<()> {
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
    count("record", a.record, 1, 100_000)?;
    if a.analysis != 0 {
        count("analysis", a.analysis, 2, limits::TURNS_MAX)?;
    }
    if !a.fig8 {
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
            SweepParam::ThetaDeg => angle_deg("theta_deg", v).map(drop)?,
            SweepParam::F => frequency("f", v).map(drop)?,
            SweepParam::Zeta => crate::error::non_negative("zeta", v).map(drop)?,
            SweepParam::Eta => crate::error::non_negative("eta", v).map(drop)?,
            SweepParam::Inertia => crate::error::positive("inertia", v).map(drop)?,
        }
    }
    Ok(())
}
