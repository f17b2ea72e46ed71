//! `gearbif simulate`: a trajectory of the driven gear as CSV (and its events on Σ).

use super::common::{count, limits, output_file, within, GearArgs, Output};
use super::methods::{DriveArgs, MethodArgs};
use super::model_arg::{start, ModelArgs, SystemInfo};
use crate::error::{positive, Error, Result};
use crate::integrator::{Event, EventKind, FlowMethod, FlowOptions, Mode, Stats};
use crate::model::{Convention, DrivenOscillator};
use serde::Serialize;
use std::fmt::Write as _;
use std::path::PathBuf;

/// Arguments of `gearbif simulate`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    gear: GearArgs,
    #[command(flatten)]
    model: ModelArgs,
    #[command(flatten)]
    drive: DriveArgs,
    #[command(flatten)]
    method: MethodArgs,
    /// Number of drive periods to integrate [1], in (0, 1e6] (may be fractional).
    #[arg(long, default_value_t = 10.0, allow_hyphen_values = true)]
    periods: f64,
    /// Output samples per drive period [1], 1 to 1000000 (at most 5e7 samples in all).
    #[arg(long, default_value_t = 50)]
    samples_per_period: usize,
    /// CSV file for the trajectory (columns t [s], alpha, beta, omega [rad/s], delta = beta − alpha,
    /// angles in rad on the lift); stdout if absent (and not --json).
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
    /// CSV file listing the events on ω = 0 (t [s], beta [rad], kind, to); only the event-driven
    /// method has events (the fixed-step and regularised methods list none).
    #[arg(long, value_name = "FILE")]
    events: Option<PathBuf>,
    /// Print a JSON summary on stdout (the CSV then goes only to --out).
    #[arg(long)]
    json: bool,
}

/// Counts of events by kind.
#[derive(Debug, Default, Serialize)]
struct EventCounts {
    crossings: usize,
    stick_starts: usize,
    releases: usize,
    grazes: usize,
}

#[derive(Debug, Serialize)]
struct Summary {
    method: String,
    convention: Convention,
    f_hz: f64,
    g: f64,
    delta: f64,
    zeta: f64,
    eta: f64,
    periods: f64,
    t_end_s: f64,
    /// Initial state (β [rad], ω [rad/s]).
    x0: [f64; 2],
    /// Final state (β [rad] on the lift, ω [rad/s]).
    x_end: [f64; 2],
    mode_end: Mode,
    /// Mean output turns per input turn over the run, (β_end − β0)/(2π · periods).
    mean_winding: f64,
    samples: usize,
    events: EventCounts,
    stats: Stats,
    wall_time_s: f64,
    out: Option<String>,
    events_file: Option<String>,
    /// The model file (--model), if the gear is a recorded one.
    #[serde(skip_serializing_if = "Option::is_none")]
    model: Option<String>,
}

fn kind_fields(k: &EventKind) -> (&'static str, i8) {
    match *k {
        EventKind::Crossing { to, .. } => ("crossing", to),
        EventKind::StickStart => ("stick", 0),
        EventKind::Release { to } => ("release", to),
        EventKind::Graze { side } => ("graze", side),
    }
}

/// The events as CSV text with header `t,beta,kind,to`.
pub fn events_csv(events: &[Event]) -> String {
    let mut s = String::from("t,beta,kind,to\n");
    for e in events {
        let (k, to) = kind_fields(&e.kind);
        let _ = writeln!(s, "{},{},{},{}", e.t, e.beta, k, to);
    }
    s
}

/// Runs `gearbif simulate`.
pub fn run(a: Args) -> Result<()> {
    super::common::check_frequency(a.drive.f)?;
    if let Some(m) = a.model.recorded(&a.gear, a.drive.f)? {
        let x0 = start(&m, &a.drive.x0)?;
        let method = super::model_arg::method(&a.method)?;
        let info = SystemInfo::of_model(&m, &a.model);
        return simulate(&m, &*method, x0, &info, &a);
    }
    let gear = a.drive.gear(&a.gear)?;
    let x0 = a.drive.x0(&gear)?;
    let method = a.method.method()?;
    let info = SystemInfo::of_gear(&gear);
    simulate(&gear, &*method, x0, &info, &a)
}

/// The trajectory of `sys` from `x0` with `method`, written and summarised as `a` asks.
fn simulate<S: DrivenOscillator>(
    sys: &S,
    method: &dyn FlowMethod<S>,
    x0: [f64; 2],
    info: &SystemInfo,
    a: &Args,
) -> Result<()> {
    positive("periods", a.periods)?;
    within("periods", a.periods, 0.0, 1e6, "must be in (0, 1e6]")?;
    count(
        "samples-per-period",
        a.samples_per_period,
        1,
        limits::TURNS_MAX,
    )?;
    for (flag, path) in [("--out", &a.out), ("--events", &a.events)] {
        if let Some(p) = path {
            output_file(flag, p, false)?;
        }
    }
    let mut plan = Vec::new();
    for (flag, path) in [("--out", &a.out), ("--events", &a.events)] {
        if let Some(p) = path {
            plan.push((flag, p.as_path(), crate::io::FileKind::Data));
        }
    }
    let period = sys.period();
    let t_end = a.periods * period;
    let n = (a.periods * a.samples_per_period as f64).floor() as usize;
    if n > 50_000_000 {
        return Err(Error::inconsistent(
            "--periods, --samples-per-period",
            format!("{n} samples requested (at most 5e7): reduce one of them"),
        ));
    }
    let files = crate::io::StagedFiles::begin(&plan)?;
    let dt = period / a.samples_per_period as f64;
    let times: Vec<f64> = (0..=n).map(|i| (i as f64 * dt).min(t_end)).collect();
    let opts = FlowOptions::with_tol(a.method.tol)
        .record_events(true)
        .samples(times);
    let start = std::time::Instant::now();
    let flow = method.flow(sys, 0.0, x0, t_end, &opts)?;
    let wall = start.elapsed().as_secs_f64();

    let mut csv = String::with_capacity(flow.samples.len() * 80);
    csv.push_str("t,alpha,beta,omega,delta\n");
    for s in &flow.samples {
        let alpha = sys.drive_phase(s.t);
        let _ = writeln!(
            csv,
            "{},{},{},{},{}",
            s.t,
            alpha,
            s.beta,
            s.omega,
            s.beta - alpha
        );
    }
    if let Some(p) = &a.out {
        crate::io::write_atomic(files.path(p), csv.as_bytes())?;
    }
    if let Some(p) = &a.events {
        crate::io::write_atomic(files.path(p), events_csv(&flow.events).as_bytes())?;
    }
    files.commit()?;
    let mut counts = EventCounts::default();
    for e in &flow.events {
        match e.kind {
            EventKind::Crossing { .. } => counts.crossings += 1,
            EventKind::StickStart => counts.stick_starts += 1,
            EventKind::Release { .. } => counts.releases += 1,
            EventKind::Graze { .. } => counts.grazes += 1,
        }
    }
    let summary = Summary {
        method: method.name(),
        convention: info.convention,
        f_hz: info.f,
        g: info.base[0],
        delta: info.base[1],
        zeta: info.base[2],
        eta: info.base[3],
        periods: a.periods,
        t_end_s: t_end,
        x0,
        x_end: flow.x,
        mode_end: flow.mode,
        mean_winding: (flow.x[0] - x0[0]) / (std::f64::consts::TAU * a.periods),
        samples: flow.samples.len(),
        events: counts,
        stats: flow.stats,
        wall_time_s: wall,
        out: a.out.as_ref().map(|p| p.display().to_string()),
        events_file: a.events.as_ref().map(|p| p.display().to_string()),
        model: info.model.clone(),
    };
    if a.json {
        Output { json: true }.emit_tagged("gearbif.simulate/1", &summary, String::new)
    } else if a.out.is_none() {
        print!("{csv}");
        Ok(())
    } else {
        eprintln!(
            "wrote {} samples over {} periods ({}; {} events) in {:.3} s",
            summary.samples,
            a.periods,
            summary.method,
            flow.events.len(),
            wall
        );
        Ok(())
    }
}
