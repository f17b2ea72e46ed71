//! `gearbif report`: the self-contained report folder of a gear (report.md, report.json, figures).

use super::common::{output_dir, GearArgs};
use super::model_arg::ModelArgs;
use super::sweep::Progress;
use crate::model::recorded::file::ModelFile;
use crate::report::recorded::{self, RecordedReportOptions};
use crate::report::{build_report, ReportOptions};
use crate::{Error, Result};
use std::path::PathBuf;

/// Arguments of `gearbif report`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    gear: GearArgs,
    #[command(flatten)]
    model: ModelArgs,
    /// With --model: the frequency where the locked orbit is found by simulation [Hz] (default:
    /// the lowest recorded drive frequency, or 1 Hz).
    #[arg(long)]
    f_start: Option<f64>,
    /// With --model: the highest frequency the lock branch is followed to [Hz].
    #[arg(long, default_value_t = 200.0)]
    f_max: f64,
    /// Output folder.
    #[arg(long, default_value = "gearbif-report")]
    out: PathBuf,
    /// A finer map and hysteresis (minutes instead of seconds).
    #[arg(long)]
    fine: bool,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
}

/// The names of a report folder: report.md, report.json, map.csv and the folder figures.
fn owned(name: &str, is_dir: bool) -> bool {
    if is_dir {
        name == "figures"
    } else {
        matches!(name, "report.md" | "report.json" | "map.csv")
    }
}

/// Runs `gearbif report`.
pub fn run(a: Args) -> Result<()> {
    if let Some(file) = a.model.file(&a.gear)? {
        return run_recorded(&a, &file);
    }
    let gear = a.gear.params()?;
    output_dir("--out", &a.out)?;
    let opts = if a.fine {
        ReportOptions::fine()?
    } else {
        ReportOptions::coarse()?
    };
    let progress = Progress::new(a.quiet);
    write_staged(&a.out, |dir| {
        let rep = build_report(&gear, &opts, dir, &progress)?;
        progress.finish();
        rep.write(dir)
    })
}

/// Writes a report into a folder staged beside `out` (the whole output plan checked before the
/// work) and moves it into place; says where and how long it took.
fn write_staged(
    out: &std::path::Path,
    write: impl FnOnce(&std::path::Path) -> Result<()>,
) -> Result<()> {
    let t = std::time::Instant::now();
    let staged = crate::io::StagedDir::begin("--out", out, owned)?;
    write(staged.path())?;
    staged.commit()?;
    eprintln!(
        "wrote {}/report.md and report.json in {:.1} s",
        out.display(),
        t.elapsed().as_secs_f64()
    );
    Ok(())
}

/// `gearbif report --model FILE`: the recorded gear against the nominal one
/// ([`crate::report::recorded`]).
fn run_recorded(a: &Args, file: &ModelFile) -> Result<()> {
    if a.fine {
        return Err(Error::inconsistent(
            "--model, --fine",
            "--fine refines the paper's gear's map; the recorded gear's report has no map",
        ));
    }
    let mut o = RecordedReportOptions::for_file(file);
    if let Some(f) = a.f_start {
        o.f_start = super::common::frequency("f_start", f)?;
    }
    o.f_max = super::common::frequency("f_max", a.f_max)?;
    if o.f_max <= o.f_start {
        return Err(Error::inconsistent(
            "--f-start, --f-max",
            format!(
                "--f-max {} must exceed the start frequency {}",
                o.f_max, o.f_start
            ),
        ));
    }
    output_dir("--out", &a.out)?;
    let name = a
        .model
        .model
        .as_ref()
        .map(|p| p.display().to_string())
        .unwrap_or_default();
    write_staged(&a.out, |dir| {
        let data = recorded::compute(file, &name, &o)?;
        recorded::text::report(&data).write(dir)
    })
}
