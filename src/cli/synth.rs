//! `gearbif synth`: a synthetic recording set from a truth model with one catalogued effect.

use crate::identification::synth::{synthesize, SynthOptions, SYNTH_EFFECTS};
use crate::io::recordings::write_set;
use crate::Result;
use std::path::PathBuf;

/// Arguments of `gearbif synth`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Effect in the truth model (none, rescale, static_torque, quadratic_drag, corotating_drag,
    /// coupling_geometry, load_dependent_friction, sensor_latency, input_compliance, drive_steps,
    /// parameter_drift; `--list` explains the sizes).
    #[arg(long, required_unless_present = "list")]
    effect: Option<String>,
    /// List the effects and the meaning of `--size`, then exit.
    #[arg(long)]
    list: bool,
    /// Effect size, finite (see `--list`; e.g. 6 for static_torque in 1/s²).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    size: f64,
    /// Output folder (experiment.toml and CSVs).
    #[arg(long, required_unless_present = "list")]
    out: Option<PathBuf>,
    /// Number of ring-downs, 0 to 1000 (ring-downs and driven runs: at least one in all).
    #[arg(long, default_value_t = 12)]
    ringdowns: usize,
    /// Number of driven runs, 0 to 1000.
    #[arg(long, default_value_t = 8)]
    driven: usize,
    /// Input turns per driven run, in (0, 1e5]; with --samples-per-turn it must give 10 to 1e6
    /// samples per run (the whole set at most 2e6 samples).
    #[arg(long, default_value_t = 80.0)]
    turns: f64,
    /// Lowest drive frequency, Hz, in [1e-3, 1e4].
    #[arg(long, default_value_t = 0.5)]
    f_min: f64,
    /// Highest drive frequency, Hz, in [1e-3, 1e4], >= --f-min.
    #[arg(long, default_value_t = 2.5)]
    f_max: f64,
    /// Samples per input turn of driven runs, 8 to 10000.
    #[arg(long, default_value_t = 50)]
    samples_per_turn: usize,
    /// Camera frame rate of ring-downs, 1/s, in (0, 1e5]; a ring-down lasts 3 s and must have 10
    /// to 1e6 samples (so at least 3.34 frames/s).
    #[arg(long, default_value_t = 100.0)]
    fps: f64,
    /// Camera noise on β, deg, in [0, 180].
    #[arg(long, default_value_t = 0.5)]
    noise_deg: f64,
    /// Fraction of outlier frames, in [0, 1).
    #[arg(long, default_value_t = 0.003)]
    outliers: f64,
    /// Probability per sample that a gap starts, in [0, 1).
    #[arg(long, default_value_t = 0.001)]
    gaps: f64,
    /// Extra sensor latency, s, in [0, 10].
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    latency: f64,
    /// Random seed (also draws the concealed truth).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Write unwrapped angles (default: wrapped to (−180°, 180°]).
    #[arg(long)]
    unwrapped: bool,
    /// Also write the truth (truth.json) beside the set.
    #[arg(long)]
    truth: bool,
}

/// The names of a recording set written by `synth`: experiment.toml, truth.json and the CSVs.
fn owned(name: &str, is_dir: bool) -> bool {
    !is_dir && (matches!(name, "experiment.toml" | "truth.json") || name.ends_with(".csv"))
}

/// Runs `gearbif synth`.
pub fn run(a: Args) -> Result<()> {
    if a.list {
        for (id, meaning) in SYNTH_EFFECTS {
            println!("{id:<24} {meaning}");
        }
        return Ok(());
    }
    let (Some(effect), Some(out)) = (a.effect.clone(), a.out.clone()) else {
        return Err(crate::Error::inconsistent(
            "--effect, --out",
            "synth needs --effect and --out (or --list)",
        ));
    };
    check_args(&a, &out)?;
    let opts = SynthOptions {
        effect: effect.clone(),
        size: a.size,
        ringdowns: a.ringdowns,
        driven: a.driven,
        turns: a.turns,
        f_range: (a.f_min, a.f_max),
        samples_per_turn: a.samples_per_turn,
        fps: a.fps,
        noise_deg: a.noise_deg,
        outlier_fraction: a.outliers,
        gap_prob: a.gaps,
        latency_s: a.latency,
        wrap: !a.unwrapped,
        seed: a.seed,
        ..SynthOptions::default()
    };
    crate::identification::synth::check_options(&opts)?;
    eprintln!(
        "simulating {} ring-downs and {} driven runs ...",
        a.ringdowns, a.driven
    );
    // the whole output plan before the work; the set is written beside it and moved into place
    let staged = crate::io::StagedDir::begin("--out", &out, owned)?;
    let (set, truth) = synthesize(&opts)?;
    write_set(&set, staged.path(), opts.wrap)?;
    if a.truth {
        let c = truth.coefficients;
        let v = serde_json::json!({
            "effect": effect, "size": a.size,
            "g": c.g(), "delta": c.delta(), "zeta": c.zeta, "eta": c.eta,
            "static_torque": [c.st_a, c.st_b], "quad": c.quad, "corot": c.corot,
            "eta_load": c.eta_load, "alpha_offset_deg": truth.alpha_offset.to_degrees(),
            "latency_s": truth.latency, "eta_static_excess": c.eta_static_excess,
            "compliance_s2": c.compliance,
            "eta_per_run": truth.eta_per_run, "lost_steps_per_driven_run": truth.lost_steps,
        });
        crate::io::write_json_atomic(staged.path().join("truth.json"), &v)?;
    }
    staged.commit()?;
    let known: Vec<&str> = SYNTH_EFFECTS.iter().map(|e| e.0).collect();
    eprintln!(
        "wrote {} (effects known: {})",
        out.display(),
        known.join(", ")
    );
    Ok(())
}

/// The domain checks of `synth`, all before anything is simulated or written.
fn check_args(a: &Args, out: &std::path::Path) -> Result<()> {
    use super::common::{count, frequency, output_dir, within};
    crate::error::finite("size", a.size)?;
    count("ringdowns", a.ringdowns, 0, 1000)?;
    count("driven", a.driven, 0, 1000)?;
    if a.ringdowns + a.driven == 0 {
        return Err(crate::Error::inconsistent(
            "--ringdowns, --driven",
            "both are 0: nothing to record",
        ));
    }
    within(
        "turns",
        a.turns,
        f64::MIN_POSITIVE,
        1e5,
        "must be in (0, 1e5]",
    )?;
    frequency("f_min", a.f_min)?;
    frequency("f_max", a.f_max)?;
    if a.f_min > a.f_max {
        return Err(crate::Error::inconsistent(
            "--f-min, --f-max",
            format!(
                "--f-min = {} must not exceed --f-max = {}",
                a.f_min, a.f_max
            ),
        ));
    }
    count("samples-per-turn", a.samples_per_turn, 8, 10_000)?;
    within(
        "fps",
        a.fps,
        f64::MIN_POSITIVE,
        1e5,
        "must be in (0, 1e5] 1/s",
    )?;
    within(
        "noise_deg",
        a.noise_deg,
        0.0,
        180.0,
        "must be in [0, 180] deg",
    )?;
    within(
        "outliers",
        a.outliers,
        0.0,
        1.0 - f64::EPSILON,
        "must be in [0, 1)",
    )?;
    within("gaps", a.gaps, 0.0, 1.0 - f64::EPSILON, "must be in [0, 1)")?;
    within("latency", a.latency, 0.0, 10.0, "must be in [0, 10] s")?;
    output_dir("--out", out)
}
