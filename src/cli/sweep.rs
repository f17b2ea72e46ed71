//! `gearbif sweep`: a two-parameter atlas with the paper's protocols, in parallel over rows, with
//! a progress bar and resumable checkpoints in the output directory.

use super::common::GearArgs;
use crate::analysis::ClassifyOptions;
use crate::sweep::{Axis, Method, Protocol, SweepObserver, SweepOutcome, SweepRunner, SweepSpec};
use crate::Result;
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};

/// Arguments of `gearbif sweep`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    gear: GearArgs,
    /// Row axis (parallel): param:start:stop:step or param:start:stop:n:log
    /// (param: theta, f, zeta, eta, inertia).
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
    /// Drive frequency when f is not an axis [Hz].
    #[arg(long, default_value_t = 1.0)]
    f: f64,
    /// Input angle α at t = 0 [deg].
    #[arg(long, default_value_t = 90.0, allow_hyphen_values = true)]
    alpha0_deg: f64,
    /// Output angle β at t = 0 [deg], in the --convention.
    #[arg(long, default_value_t = 90.0, allow_hyphen_values = true)]
    beta0_deg: f64,
    /// Settling turns per point (paper: 90 fresh, 1000 semi-static).
    #[arg(long)]
    settle: Option<usize>,
    /// Recorded turns per point.
    #[arg(long, default_value_t = 10)]
    record: usize,
    /// Turns of the rigorous analysis per point (0: skip it).
    #[arg(long, default_value_t = 60)]
    analysis: usize,
    /// Integrator tolerance.
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
    /// (e.g. 1e-8); default: integrate every settling turn as the paper did.
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
