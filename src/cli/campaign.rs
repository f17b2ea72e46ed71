//! `gearbif campaign`: diagnose many sets from the campaign generator (effects × sizes × seeds)
//! and measure the diagnosis: campaign.json (`gearbif.campaign/1`), campaign.md, campaign.svg/.png.

use crate::campaign::cases::EFFECTS;
use crate::campaign::generator::SetSize;
use crate::campaign::render::markdown;
use crate::campaign::runner::{run_campaign, CampaignSpec};
use crate::error::Error;
use crate::identification::diagnose::DiagnoseOptions;
use crate::io::{write_atomic, write_json_atomic};
use crate::Result;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `gearbif campaign`.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "Sizes are levels: multiples of each effect's reference size, e.g. \
    static_torque_2h 6 s^-2, latency 6 ms, compliance 1.5 deg, shaft_angles_off 6 deg \
    (`--list` prints every effect's form, unit and reference). Controls (expected verdict `none`) \
    run once per null seed. Results go to OUT/cases/ one file per case as soon as known; rerunning \
    the same command resumes."
)]
pub struct Args {
    /// Output folder: campaign.json, campaign.md, campaign.svg, campaign.png, cases/ (rerun the
    /// same command to resume); complete.json is written last, when the campaign is complete.
    #[arg(long, required_unless_present = "list")]
    out: Option<PathBuf>,
    /// Effects, comma-separated, or `all` (see `--list`).
    #[arg(long, value_delimiter = ',', default_value = "all")]
    effects: Vec<String>,
    /// Number of seeds (labs and noise realisations) per effect and size, counted from
    /// `--first-seed`; 1 to 100000.
    #[arg(long, default_value_t = 10)]
    seeds: u64,
    /// Number of seeds of each control (expected verdict `none`), counted from `--first-seed`;
    /// 1 to 100000.
    #[arg(long, default_value_t = 20)]
    null_seeds: u64,
    /// First seed; the last seed used (first + seeds − 1) must not pass 2^64 − 1.
    #[arg(long, default_value_t = 1)]
    first_seed: u64,
    /// Effect sizes as multiples of each effect's reference size (dimensionless), comma-separated.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "0.25,0.5,1,2",
        allow_hyphen_values = true
    )]
    sizes: Vec<f64>,
    /// Set size: `ci` (6 ring-downs, 3 driven runs × 12 turns), `medium` (8, 5 × 30), `full`
    /// (12, 8 × 80); 50 samples per turn, ring-downs 3 s at 100 frames/s, 0.5–2.5 Hz.
    #[arg(long, default_value = "medium")]
    set: String,
    /// Override: ring-downs per set, 0 to 1000.
    #[arg(long)]
    ringdowns: Option<usize>,
    /// Override: driven runs per set, 0 to 1000.
    #[arg(long)]
    driven: Option<usize>,
    /// Override: input turns per driven run (each run 10 to 1e6 samples, the set at most 2e6).
    #[arg(long)]
    turns: Option<f64>,
    /// Step of the generator's RK4 integrator, s.
    #[arg(long, default_value_t = 2.5e-4)]
    step: f64,
    /// Relative tolerance of the diagnosis' simulations, in (0, 1) (the ring-downs are integrated
    /// ten times tighter).
    #[arg(long, default_value_t = DiagnoseOptions::default().tol)]
    tol: f64,
    /// Profile the final models' shape parameters (`gearbif diagnose --profile-shapes`).
    #[arg(long)]
    profile_shapes: bool,
    /// Keep the generated recording sets under OUT/sets/.
    #[arg(long)]
    keep_sets: bool,
    /// Skip the figure.
    #[arg(long)]
    no_figures: bool,
    /// List the effects (form, unit, reference size, expected verdict) and exit.
    #[arg(long)]
    list: bool,
}

fn spec_of(a: &Args) -> Result<CampaignSpec> {
    let mut set = SetSize::by_name(&a.set)?;
    if a.ringdowns.is_some() || a.driven.is_some() || a.turns.is_some() {
        set.name = format!("{} (custom)", set.name);
    }
    set.ringdowns = a.ringdowns.unwrap_or(set.ringdowns);
    set.driven = a.driven.unwrap_or(set.driven);
    set.turns = a.turns.unwrap_or(set.turns);
    for (flag, n) in [("seeds", a.seeds), ("null-seeds", a.null_seeds)] {
        super::common::count(flag, usize::try_from(n).unwrap_or(usize::MAX), 1, 100_000)?;
        if a.first_seed.checked_add(n - 1).is_none() {
            return Err(Error::inconsistent(
                format!("--first-seed, --{flag}"),
                format!(
                    "{n} seeds from {} pass the largest seed {}",
                    a.first_seed,
                    u64::MAX
                ),
            ));
        }
    }
    let effects = if a.effects.iter().any(|e| e == "all") {
        EFFECTS.iter().map(|e| e.id.to_string()).collect()
    } else {
        a.effects.iter().map(|e| e.trim().to_string()).collect()
    };
    let spec = CampaignSpec {
        effects,
        levels: a.sizes.clone(),
        seeds: (0..a.seeds).map(|k| a.first_seed + k).collect(),
        null_seeds: (0..a.null_seeds).map(|k| a.first_seed + k).collect(),
        set,
        rk4_step_s: a.step,
        keep_sets: a.keep_sets,
        tol: super::common::tolerance("tol", a.tol)?,
        profile_shapes: a.profile_shapes,
    };
    spec.validate()?;
    Ok(spec)
}

/// The result files of a campaign's output folder (besides spec.json, `cases/` and `sets/`).
const RESULT: [&str; 4] = [
    "campaign.svg",
    "campaign.png",
    "campaign.md",
    "campaign.json",
];

/// Runs `gearbif campaign`.
pub fn run(a: Args) -> Result<()> {
    if a.list {
        for e in EFFECTS {
            println!(
                "{:<26} expected {:<38} reference {} {}\n    {}",
                e.id,
                e.expected.join("+"),
                e.reference,
                e.unit,
                e.form
            );
        }
        return Ok(());
    }
    let spec = spec_of(&a)?;
    let out = a
        .out
        .clone()
        .ok_or_else(|| Error::option("--out", "is required"))?;
    super::common::output_dir("--out", &out)?;
    // a resumable work folder: the cases as they finish, the result files at the end and the
    // completion marker last (src/io/workdir.rs)
    let planned = [&RESULT[..], &["spec.json"]].concat();
    let work = crate::io::WorkDir::begin("--out", &out, "campaign", &planned, &["cases", "sets"])?;
    let t0 = Instant::now();
    let doc = run_campaign(
        &spec,
        &out,
        &crate::progress::lines(|s| eprintln!("[{:7.1} s] {s}", t0.elapsed().as_secs_f64())),
    )?;
    if !a.no_figures {
        let fig = crate::plotting::campaign::CampaignFigure {
            summary: &doc.summary,
        };
        crate::plotting::save(&fig, out.join("campaign.svg"))?;
        crate::plotting::save(&fig, out.join("campaign.png"))?;
    }
    write_atomic(out.join("campaign.md"), markdown(&doc).as_bytes())?;
    write_json_atomic(out.join("campaign.json"), &doc)?;
    work.complete(if a.no_figures {
        &RESULT[2..]
    } else {
        &RESULT[..]
    })?;
    let s = &doc.summary;
    println!(
        "false positives: {}/{}; coverage ±2σ: {}/{}; errors: {}",
        s.false_positive.k, s.false_positive.n, s.coverage.pooled.k, s.coverage.pooled.n, s.errors
    );
    for p in &s.power {
        println!(
            "  {:<26} size at 90 %: {}",
            p.effect,
            p.size_90
                .map(|x| format!("{x} {}", p.unit))
                .unwrap_or_else(|| "not reached".into())
        );
    }
    eprintln!(
        "[{:7.1} s] wrote {}",
        t0.elapsed().as_secs_f64(),
        out.display()
    );
    Ok(())
}
