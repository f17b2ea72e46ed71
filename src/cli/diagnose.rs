//! `gearbif diagnose`: report.json, report.md, model.json and figures for a recording set.

use crate::identification::diagnose::{diagnose, DiagnoseOptions};
use crate::identification::report::markdown;
use crate::io::recordings::read_set;
use crate::io::{write_atomic, write_json_atomic};
use crate::Result;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `gearbif diagnose`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The recording set (folder with experiment.toml).
    set: PathBuf,
    /// Output folder for report.json, report.md and figures.
    #[arg(long)]
    out: PathBuf,
    /// Skip the held-out (leave-one-run-out) short-horizon predictions.
    #[arg(long)]
    no_heldout: bool,
    /// Skip the figures.
    #[arg(long)]
    no_figures: bool,
    /// Add the process CPU time and the number of window simulations to every progress line.
    #[arg(long)]
    timing: bool,
    /// Relative tolerance of the simulations, in (0, 1): the window simulations of the refits and
    /// predictions and the stick windows; the ring-down fits are integrated ten times tighter.
    #[arg(long, default_value_t = DiagnoseOptions::default().tol)]
    tol: f64,
    /// Profile the shape parameters of the final model (drag exponent, load weight, Stribeck
    /// width and shape): a check of a shape whose profile is far from quadratic, 3–9 times the
    /// CPU when such a family is named (docs/diagnosis.md, "Shape parameters").
    #[arg(long)]
    profile_shapes: bool,
}

/// CPU time (user + system) of this process, s, from /proc/self/stat (Linux; `None` elsewhere).
fn cpu_seconds() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/stat").ok()?;
    // the fields after the command name (which is in parentheses and may hold spaces)
    let rest = &s[s.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

/// The names of a diagnosis folder: report.md, report.json, model.json and the figures.
fn owned(name: &str, is_dir: bool) -> bool {
    !is_dir
        && (matches!(name, "report.md" | "report.json" | "model.json")
            || name.ends_with(".svg")
            || name.ends_with(".png"))
}

/// Runs `gearbif diagnose`.
pub fn run(a: Args) -> Result<()> {
    let t0 = Instant::now();
    super::common::output_dir("--out", &a.out)?;
    let opts = DiagnoseOptions {
        heldout_predictions: !a.no_heldout,
        tol: super::common::tolerance("tol", a.tol)?,
        profile_shapes: a.profile_shapes,
        ..DiagnoseOptions::default()
    };
    let set = read_set(&a.set)?;
    super::common::warn_ignored_keys(&a.set);
    // the whole output plan before the work; the result is written beside it and moved into place
    let staged = crate::io::StagedDir::begin("--out", &a.out, owned)?;
    let d = diagnose(
        &set,
        &opts,
        &crate::progress::lines(|s| {
            if a.timing {
                let sims = crate::identification::predict::simulations();
                let (steps, over) = crate::identification::predict::simulation_steps();
                eprintln!(
                    "[{:6.1} s, cpu {:6.1} s, {:8} sims, {:5.0} steps/sim, {over} over budget] {s}",
                    t0.elapsed().as_secs_f64(),
                    cpu_seconds().unwrap_or(f64::NAN),
                    sims,
                    steps as f64 / sims.max(1) as f64
                )
            } else {
                eprintln!("[{:6.1} s] {s}", t0.elapsed().as_secs_f64())
            }
        }),
    )?;
    let title = a
        .set
        .file_name()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_default();
    // figures first, then the report (so a report never points at missing figures)
    let dir = staged.path();
    if !a.no_figures {
        crate::plotting::diagnosis::write_figures(&d, dir)?;
    }
    write_atomic(
        dir.join("report.md"),
        markdown(&d.report, &title).as_bytes(),
    )?;
    write_json_atomic(dir.join("report.json"), &d.report)?;
    // the diagnosed gear, for the dynamics commands' --model; a fit the model's lens refuses
    // (a parameter outside its range) leaves the report whole and says why the file is missing
    match crate::identification::export::model_file(&d, &set.gear) {
        Ok(model) => {
            let range = crate::identification::export::recorded_range(&set.runs);
            write_json_atomic(dir.join("model.json"), &model.with_recorded(range))?
        }
        Err(e) => eprintln!("warning: model.json not written: {e}"),
    }
    staged.commit()?;
    println!("verdict: {}", d.report.verdict);
    if let Some(a) = &d.report.assessment {
        println!("  {}", a.statement);
    }
    for f in &d.report.findings {
        let ps: Vec<String> = f
            .params
            .iter()
            .map(|(k, v)| format!("{k} = {v:.4}"))
            .collect();
        println!("  {} [{}]: {}", f.effect, f.class, ps.join(", "));
    }
    eprintln!(
        "[{:6.1} s] wrote {}",
        t0.elapsed().as_secs_f64(),
        a.out.display()
    );
    Ok(())
}
