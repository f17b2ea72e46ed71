//! `gearbif report`: the self-contained report folder of a gear (report.md, report.json, figures).

use super::common::{output_dir, GearArgs};
use super::sweep::Progress;
use crate::report::{build_report, ReportOptions};
use crate::Result;
use std::path::PathBuf;

/// Arguments of `gearbif report`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    gear: GearArgs,
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
    let gear = a.gear.params()?;
    output_dir("--out", &a.out)?;
    let opts = if a.fine {
        ReportOptions::fine()?
    } else {
        ReportOptions::coarse()?
    };
    let t = std::time::Instant::now();
    let progress = Progress::new(a.quiet);
    // the whole output plan before the work; the result is written beside it and moved into place
    let staged = crate::io::StagedDir::begin("--out", &a.out, owned)?;
    let rep = build_report(&gear, &opts, staged.path(), &progress)?;
    progress.finish();
    rep.write(staged.path())?;
    staged.commit()?;
    eprintln!(
        "wrote {}/report.md and report.json in {:.1} s",
        a.out.display(),
        t.elapsed().as_secs_f64()
    );
    Ok(())
}
