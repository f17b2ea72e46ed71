//! `gearbif sweep --model FILE`: the two-parameter sweep of a recorded gear in any two of its
//! parameters ([`crate::sweep::sweep_grid`]), written as `points.csv` (no checkpoints: a recorded
//! gear's sweep is not resumable, and --fig8, --shard and --max-rows are refused).

use super::model_arg::ModelArgs;
use super::sweep::{Args, Progress, ProtocolArg};
use crate::analysis::{ClassifyOptions, PointResult};
use crate::error::{Error, Result};
use crate::integrator::{EventDriven853, FixedStep, FlowMethod};
use crate::model::recorded::file::ModelFile;
use crate::model::recorded::{RecordedModel, RecordedParam};
use crate::model::{Parameter, Parametrised};
use crate::sweep::{parse_axis, sweep_grid, Protocol};
use std::fmt::Write;

/// The flags of `sweep` that a recorded gear's sweep does not take.
fn refuse(a: &Args) -> Result<()> {
    let set: Vec<&str> = [
        ("--fig8", a.fig8),
        ("--shard", a.shard.is_some()),
        ("--max-rows", a.max_rows.is_some()),
        ("--dp5", a.dp5),
    ]
    .into_iter()
    .filter_map(|(f, on)| on.then_some(f))
    .collect();
    if set.is_empty() {
        Ok(())
    } else {
        Err(Error::inconsistent(
            format!("--model, {}", set.join(", ")),
            "a recorded gear's sweep runs in one go with the default integrator (or --rk4)",
        ))
    }
}

/// An axis of the recorded gear's lens (the file fixes Θ: no `theta` axis).
fn axis(flag: &str, s: &str) -> Result<(RecordedParam, Vec<f64>)> {
    parse_axis::<RecordedParam>(s).map_err(|e| {
        Error::inconsistent(
            format!("--model, {flag} {s}"),
            format!("{e} (the model file fixes the set-up: sweep parameters of the recorded gear, docs/recorded_gear.md)"),
        )
    })
}

/// Runs the sweep of the recorded gear of `file` (the model argument `m`).
pub fn run(a: &Args, m: &ModelArgs, file: &ModelFile, opts: &ClassifyOptions) -> Result<()> {
    refuse(a)?;
    let rows = axis("--rows", &a.rows)?;
    let cols = axis("--cols", &a.cols)?;
    let base = file.model(a.f)?.with_alpha0(a.alpha0_deg.to_radians())?;
    for (p, values) in [&rows, &cols] {
        for &v in values {
            base.with_param(*p, v)?;
        }
    }
    let method: Box<dyn FlowMethod<RecordedModel>> = if a.rk4 {
        Box::new(FixedStep::default())
    } else {
        Box::new(EventDriven853)
    };
    let protocol = match a.protocol {
        ProtocolArg::Fresh => Protocol::Fresh,
        ProtocolArg::SemiStatic => Protocol::SemiStatic,
    };
    let staged = crate::io::StagedDir::begin("--out", &a.out, |n, d| !d && n == "points.csv")?;
    let progress = Progress::new(a.quiet);
    let t = std::time::Instant::now();
    let x0 = [a.beta0_deg.to_radians(), 0.0];
    let res = sweep_grid(
        method.as_ref(),
        &base,
        (rows.0, &rows.1),
        (cols.0, &cols.1),
        x0,
        protocol,
        opts,
        &progress,
    )?;
    progress.finish();
    let csv = to_csv(rows.0, cols.0, &res);
    crate::io::write_atomic(staged.path().join("points.csv"), csv.as_bytes())?;
    staged.commit()?;
    eprintln!(
        "done: {} points of {} in {:.1} s; wrote {}/points.csv",
        rows.1.len() * cols.1.len(),
        m.model
            .as_ref()
            .map(|p| p.display().to_string())
            .unwrap_or_default(),
        t.elapsed().as_secs_f64(),
        a.out.display()
    );
    Ok(())
}

/// One line per point: indices, the two parameters, the paper's class and metrics, the rigorous
/// class, rotation number and largest Lyapunov exponent per period.
fn to_csv(
    row: RecordedParam,
    col: RecordedParam,
    res: &[Vec<(RecordedModel, PointResult)>],
) -> String {
    let mut s = format!(
        "row,col,{},{},paper_class,rms_delta_deg,delta_avg_deg,net_rotation_hz,rigorous,rotation_number,lyapunov_per_period\n",
        row.name(),
        col.name()
    );
    for (i, r) in res.iter().enumerate() {
        for (j, (sys, p)) in r.iter().enumerate() {
            let rig = p.rigorous.as_ref();
            let opt = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v}"));
            let _ = writeln!(
                s,
                "{i},{j},{},{},{},{},{},{},{},{},{}",
                sys.param(row),
                sys.param(col),
                p.paper.class.label(),
                p.paper.rms_delta_deg,
                p.paper.delta_avg_deg,
                p.net_rotation_hz,
                rig.map_or(String::new(), |c| c.label.replace(',', ";")),
                opt(rig.map(|c| c.rotation_number)),
                opt(rig.and_then(|c| c.lyapunov.per_period)),
            );
        }
    }
    s
}
