//! Synthetic recording sets from a truth model ([`AugmentedGear`]) with one catalogued effect at a
//! chosen size, and a realistic measurement: driven runs sampled 50 times per input turn on the
//! 7.2° drive grid, ring-downs at a camera frame rate, Gaussian camera noise on β, optional sensor
//! latency, outlier frames and gaps. Simulated with the exact Filippov integrator.

use super::model::{AugmentedGear, Coefficients, Geometry, InputBend, Rng};
use crate::error::{Error, Result};
use crate::integrator::{EventDriven, FlowMethod, FlowOptions};
use crate::io::recordings::{GearSetup, RecordingSet, Run, RunKind};
use std::f64::consts::{PI, TAU};

/// The effects the generator can put into the truth model, with the meaning of `size`.
pub const SYNTH_EFFECTS: &[(&str, &str)] = &[
    ("none", "no extra physics (size ignored)"),
    (
        "rescale",
        "output dipole tilt: g multiplied by `size` (e.g. 0.9); the refit base model absorbs it",
    ),
    (
        "static_torque",
        "lab-fixed torque size·sin(β + 60°), s⁻² (e.g. 6)",
    ),
    ("quadratic_drag", "−size·β̇|β̇|, rad⁻¹ (e.g. 0.05)"),
    ("corotating_drag", "−size·(β̇ − α̇), s⁻¹ (e.g. 0.6)"),
    (
        "coupling_geometry",
        "input angle zero offset of `size` degrees (e.g. 6)",
    ),
    (
        "load_dependent_friction",
        "dry friction η(1 + size·h(α, β)), h the dipole force shape (e.g. 0.5)",
    ),
    (
        "sensor_latency",
        "β recorded `size` seconds late relative to α (e.g. 0.006)",
    ),
    (
        "input_compliance",
        "the input magnet lags by its coupling torque over a torsional stiffness; `size` = the \
         lag at the peak coupling torque, deg (e.g. 1.5)",
    ),
    (
        "drive_steps",
        "driven runs: the input rests between steps (one step per sample interval, the sample \
         taken just after the step) and each step is lost with probability `size` (e.g. 0.001; \
         0 = stepping only)",
    ),
    (
        "parameter_drift",
        "η drifts linearly over the session (runs in file order): relative change `size` from \
         the first run to the last (e.g. 0.3)",
    ),
    (
        "static_friction",
        "breakaway friction η(1 + size) at rest, sliding friction η (e.g. 0.5)",
    ),
];

/// Options of the generator.
#[derive(Debug, Clone, PartialEq)]
pub struct SynthOptions {
    /// Effect identifier (see [`SYNTH_EFFECTS`]).
    pub effect: String,
    /// Effect size (meaning per effect).
    pub size: f64,
    /// Number of ring-downs (locked input angles spread over a turn).
    pub ringdowns: usize,
    /// Number of driven runs.
    pub driven: usize,
    /// Input turns per driven run.
    pub turns: f64,
    /// Lowest and highest drive frequency, Hz.
    pub f_range: (f64, f64),
    /// Samples per input turn of driven runs.
    pub samples_per_turn: usize,
    /// Camera frame rate of ring-downs, 1/s.
    pub fps: f64,
    /// Ring-down duration, s.
    pub ringdown_s: f64,
    /// Camera noise on β, deg (1σ).
    pub noise_deg: f64,
    /// Fraction of outlier frames.
    pub outlier_fraction: f64,
    /// Probability per sample that a gap (3–10 lost samples) starts.
    pub gap_prob: f64,
    /// Extra sensor latency on top of the effect, s.
    pub latency_s: f64,
    /// Write wrapped angles.
    pub wrap: bool,
    /// Random seed (also draws the concealed truth: shaft angle, inertia, ζ, η off nominal).
    pub seed: u64,
}

impl Default for SynthOptions {
    fn default() -> Self {
        Self {
            effect: "none".into(),
            size: 0.0,
            ringdowns: 12,
            driven: 8,
            turns: 80.0,
            f_range: (0.5, 2.5),
            samples_per_turn: 50,
            fps: 100.0,
            ringdown_s: 3.0,
            noise_deg: 0.5,
            outlier_fraction: 0.003,
            gap_prob: 0.001,
            latency_s: 0.0,
            wrap: true,
            seed: 1,
        }
    }
}

/// The truth behind a synthetic set.
#[derive(Debug, Clone, PartialEq)]
pub struct SynthTruth {
    /// Truth coefficients.
    pub coefficients: Coefficients,
    /// True geometry.
    pub geometry: Geometry,
    /// Input angle zero offset, rad.
    pub alpha_offset: f64,
    /// Sensor latency, s.
    pub latency: f64,
    /// `parameter_drift`: η of each run in file order (empty otherwise).
    pub eta_per_run: Vec<f64>,
    /// `drive_steps`: steps lost in each driven run (empty otherwise).
    pub lost_steps: Vec<usize>,
}

/// Makes a synthetic recording set (not yet written; see [`crate::io::recordings::write_set`]).
pub fn synthesize(opts: &SynthOptions) -> Result<(RecordingSet, SynthTruth)> {
    check_options(opts)?;
    let mut rng = Rng::new(opts.seed);
    let setup = GearSetup::paper();
    let mut truth = draw_truth(opts, &setup, &mut rng)?;
    // parameter_drift: η of run k (file order: ring-downs, then driven runs)
    if opts.effect == "parameter_drift" {
        let n_runs = opts.ringdowns + opts.driven;
        truth.eta_per_run = (0..n_runs)
            .map(|k| coefficients_of_run(opts, &truth.coefficients, k).eta)
            .collect();
    }
    let mut runs = ringdown_runs(opts, &truth, &mut rng)?;
    runs.extend(driven_runs(opts, &mut truth, &mut rng)?);
    let mut gear = setup;
    gear.inertia = None;
    gear.beta_noise_deg = None;
    Ok((
        RecordingSet {
            dir: std::path::PathBuf::new(),
            gear,
            runs,
        },
        truth,
    ))
}

/// Fewest samples a synthetic run may have.
pub const RUN_SAMPLES_MIN: usize = 10;

/// Samples of each ring-down (`ringdown_s · fps`) and of each driven run (`turns ·
/// samples_per_turn`), rounded down; saturating for huge values.
pub fn samples_per_run(opts: &SynthOptions) -> (usize, usize) {
    let n = |x: f64| {
        if x.is_finite() && x > 0.0 {
            x.floor() as usize
        } else {
            0
        }
    };
    (
        n(opts.ringdown_s * opts.fps),
        n(opts.turns * opts.samples_per_turn as f64),
    )
}

/// Checks the sizes the generator allocates: each run between [`RUN_SAMPLES_MIN`] and
/// [`RUN_SAMPLES_MAX`](crate::io::recordings::limits::RUN_SAMPLES_MAX) samples, the set at most
/// [`SET_SAMPLES_MAX`](crate::io::recordings::limits::SET_SAMPLES_MAX).
fn check_sizes(opts: &SynthOptions) -> Result<()> {
    use crate::io::recordings::limits::{RUN_SAMPLES_MAX, SET_SAMPLES_MAX};
    let (nr, nd) = samples_per_run(opts);
    let range = format!("must be in {RUN_SAMPLES_MIN}..={RUN_SAMPLES_MAX}");
    if opts.ringdowns > 0 && !(RUN_SAMPLES_MIN..=RUN_SAMPLES_MAX).contains(&nr) {
        return Err(Error::option(
            "--fps",
            format!(
                "{} frames/s over a {} s ring-down give {nr} samples per ring-down; the samples \
                 per run {range}",
                crate::error::show(opts.fps),
                crate::error::show(opts.ringdown_s)
            ),
        ));
    }
    if opts.driven > 0 && !(RUN_SAMPLES_MIN..=RUN_SAMPLES_MAX).contains(&nd) {
        return Err(Error::inconsistent(
            "--turns, --samples-per-turn",
            format!(
                "{} turns × {} samples per turn give {nd} samples per driven run; the samples \
                 per run {range}",
                crate::error::show(opts.turns),
                opts.samples_per_turn
            ),
        ));
    }
    let total = (opts.ringdowns as u128) * (nr as u128) + (opts.driven as u128) * (nd as u128);
    if total > SET_SAMPLES_MAX as u128 {
        return Err(Error::inconsistent(
            "--ringdowns, --driven, --turns, --samples-per-turn, --fps",
            format!("the set would hold {total} samples, at most {SET_SAMPLES_MAX}"),
        ));
    }
    Ok(())
}

/// Rejects unknown effects and out-of-range options, and sizes beyond the generator's limits
/// ([`check_sizes`]).
pub fn check_options(opts: &SynthOptions) -> Result<()> {
    if !SYNTH_EFFECTS.iter().any(|(e, _)| *e == opts.effect) {
        return Err(Error::unknown_name(
            "effect",
            opts.effect.as_str(),
            SYNTH_EFFECTS.iter().map(|e| e.0),
        ));
    }
    crate::error::finite("size", opts.size)?;
    crate::error::non_negative("noise_deg", opts.noise_deg)?;
    crate::error::positive("fps", opts.fps)?;
    crate::error::positive("turns", opts.turns)?;
    if opts.samples_per_turn < 8 {
        return Err(Error::option(
            "samples_per_turn",
            format!("{} (need >= 8)", opts.samples_per_turn),
        ));
    }
    if opts.effect == "drive_steps" && !(0.0..1.0).contains(&opts.size) {
        return Err(Error::InvalidParameter {
            name: "size",
            value: opts.size,
            reason: "the size of drive_steps is a probability per step, in [0, 1)",
        });
    }
    crate::error::positive("ringdown_s", opts.ringdown_s)?;
    check_sizes(opts)
}

/// The concealed truth: the set-up within its tolerances (shaft angle, inertia, ζ, η drawn from
/// `rng` in this order) and the chosen effect at its size. The coupling with the input angle
/// offset ε is −g sin(α+ε) cos β + gΔ cos(α+ε) sin β.
fn draw_truth(opts: &SynthOptions, setup: &GearSetup, rng: &mut Rng) -> Result<SynthTruth> {
    let theta_true = (setup.theta_deg + 2.0 * (rng.uniform() - 0.5) * 3.0).to_radians();
    let phi_true = theta_true;
    let inertia_true = 6.45e-5 * (1.0 + 0.1 * (rng.uniform() - 0.5));
    let mut g = setup.coupling() / inertia_true;
    let delta = crate::model::gear::shaft_index(theta_true, phi_true);
    let zeta = 1.1 * (0.8 + 0.4 * rng.uniform());
    let eta = 23.1 * (0.8 + 0.4 * rng.uniform());
    let mut alpha_offset = 0.0;
    let mut latency = opts.latency_s;
    let mut extra = Coefficients::default();
    match opts.effect.as_str() {
        "rescale" => g *= opts.size,
        "static_torque" => {
            let ph = 60f64.to_radians();
            extra.st_a = opts.size * ph.cos();
            extra.st_b = opts.size * ph.sin();
        }
        "quadratic_drag" => extra.quad = opts.size,
        "corotating_drag" => extra.corot = opts.size,
        "coupling_geometry" => alpha_offset = opts.size.to_radians(),
        "load_dependent_friction" => extra.eta_load = opts.size * eta,
        "sensor_latency" => latency += opts.size,
        "input_compliance" => extra.compliance = opts.size.to_radians() / g,
        "static_friction" => extra.eta_static_excess = opts.size * eta,
        _ => {}
    }
    let (se, ce) = alpha_offset.sin_cos();
    Ok(SynthTruth {
        coefficients: Coefficients {
            zeta,
            eta,
            c_sc: -g * ce,
            c_cs: g * delta * ce,
            c_cc: -g * se,
            c_ss: -g * delta * se,
            ..extra
        },
        geometry: Geometry::new(theta_true, phi_true),
        alpha_offset,
        latency,
        eta_per_run: vec![],
        lost_steps: vec![],
    })
}

/// The coefficients of run `k` (file order: ring-downs, then driven runs): `coef` itself, or for
/// `parameter_drift` η(1 + size·(k/(n − 1) − ½)).
fn coefficients_of_run(opts: &SynthOptions, coef: &Coefficients, k: usize) -> Coefficients {
    if opts.effect != "parameter_drift" {
        return *coef;
    }
    let n_runs = opts.ringdowns + opts.driven;
    let s = if n_runs > 1 {
        k as f64 / (n_runs - 1) as f64 - 0.5
    } else {
        0.0
    };
    Coefficients {
        eta: coef.eta * (1.0 + opts.size * s),
        ..*coef
    }
}

/// The ring-downs: released at rest about a quarter turn from the coupling potential's minimum at
/// evenly spread input angles α0, alternately on either side.
fn ringdown_runs(opts: &SynthOptions, truth: &SynthTruth, rng: &mut Rng) -> Result<Vec<Run>> {
    let coef = truth.coefficients;
    let noise = opts.noise_deg.to_radians();
    let mut runs = Vec::new();
    for k in 0..opts.ringdowns {
        let alpha0 = TAU * (k as f64 + 0.37) / opts.ringdowns as f64;
        let sys = AugmentedGear {
            c: coefficients_of_run(opts, &coef, k),
            geo: truth.geometry,
            alpha0,
            alpha_rate: 0.0,
            bend: InputBend::default(),
        };
        // equilibrium of the truth near which it is released: minimum of the coupling potential
        let psi = (coef.c_sc * alpha0.sin() + coef.c_cc * alpha0.cos())
            .atan2(-(coef.c_cs * alpha0.cos() + coef.c_ss * alpha0.sin()));
        let side = if k % 2 == 0 { 1.0 } else { -1.0 };
        let beta_start = psi + side * (0.5 * PI - 0.1 + 0.2 * rng.uniform());
        let n = (opts.ringdown_s * opts.fps).floor() as usize;
        let times: Vec<f64> = (0..n).map(|i| i as f64 / opts.fps).collect();
        let (t, beta) = simulate(&sys, [beta_start, 0.0], &times, truth.latency)?;
        let alpha = vec![alpha0; t.len()];
        runs.push(measure(
            RunKind::Ringdown { alpha0 },
            format!("ringdown_{:03}.csv", k),
            t,
            alpha,
            beta,
            noise,
            opts,
            rng,
        ));
    }
    Ok(runs)
}

/// The driven runs at frequencies evenly spread over `f_range` (rounded to 1 mHz), the output
/// released at rest at a random angle; `drive_steps` records the steps each run lost in `truth`.
fn driven_runs(opts: &SynthOptions, truth: &mut SynthTruth, rng: &mut Rng) -> Result<Vec<Run>> {
    let noise = opts.noise_deg.to_radians();
    let mut runs = Vec::new();
    for k in 0..opts.driven {
        let (f0, f1) = opts.f_range;
        let f = if opts.driven > 1 {
            f0 + (f1 - f0) * k as f64 / (opts.driven - 1) as f64
        } else {
            f0
        };
        let f = (f * 1000.0).round() / 1000.0;
        // the coefficients carry the input angle offset: the drive itself starts at α = 0
        let sys = AugmentedGear {
            c: coefficients_of_run(opts, &truth.coefficients, opts.ringdowns + k),
            geo: truth.geometry,
            alpha0: 0.0,
            alpha_rate: TAU * f,
            bend: InputBend::default(),
        };
        let n = (opts.turns * opts.samples_per_turn as f64).floor() as usize;
        let dt = 1.0 / (f * opts.samples_per_turn as f64);
        let times: Vec<f64> = (0..n).map(|i| i as f64 * dt).collect();
        let beta_start = TAU * rng.uniform();
        let (t, beta) = if opts.effect == "drive_steps" {
            let (t, beta, lost) = simulate_stepped(
                &sys,
                [beta_start, 0.0],
                &times,
                TAU / opts.samples_per_turn as f64,
                opts.size,
                rng,
            )?;
            truth.lost_steps.push(lost);
            (t, beta)
        } else {
            simulate(&sys, [beta_start, 0.0], &times, truth.latency)?
        };
        let alpha: Vec<f64> = t
            .iter()
            .map(|&ti| TAU * (ti / dt / opts.samples_per_turn as f64))
            .collect();
        runs.push(measure(
            RunKind::Driven { f_hz: f },
            format!("driven_{:02}_{:.3}.csv", k, f),
            t,
            alpha,
            beta,
            noise,
            opts,
            rng,
        ));
    }
    Ok(runs)
}

/// Simulates from t = −latency so that β(t_k − latency) is available at every recorded time.
fn simulate(
    sys: &AugmentedGear,
    x0: [f64; 2],
    times: &[f64],
    latency: f64,
) -> Result<(Vec<f64>, Vec<f64>)> {
    let shifted: Vec<f64> = times.iter().map(|t| t - latency.max(0.0)).collect();
    let t_start = shifted[0].min(0.0);
    let t_end = *shifted.last().unwrap_or(&0.0);
    let opts = FlowOptions::with_tol(1e-9).samples(shifted);
    let flow = EventDriven.flow(sys, t_start, x0, t_end.max(t_start), &opts)?;
    let beta = flow.samples.iter().map(|s| s.beta).collect();
    Ok((times.to_vec(), beta))
}

/// A stepping drive: the input steps by `step` at each sample time (the sample is taken just
/// after the step) and rests in between; each step is lost with probability `p_lost`. Returns
/// the times, β and the number of lost steps.
fn simulate_stepped(
    sys: &AugmentedGear,
    x0: [f64; 2],
    times: &[f64],
    step: f64,
    p_lost: f64,
    rng: &mut Rng,
) -> Result<(Vec<f64>, Vec<f64>, usize)> {
    let mut x = x0;
    let mut beta = Vec::with_capacity(times.len());
    let mut lost = 0usize;
    let opts = FlowOptions::with_tol(1e-9);
    for (k, &tk) in times.iter().enumerate() {
        beta.push(x[0]);
        if k > 0 && rng.uniform() < p_lost {
            lost += 1;
        }
        let Some(&t_next) = times.get(k + 1) else {
            break;
        };
        let rest = AugmentedGear {
            alpha0: sys.alpha0 + step * (k - lost) as f64,
            alpha_rate: 0.0,
            bend: InputBend::default(),
            ..*sys
        };
        let flow = EventDriven.flow(&rest, tk, x, t_next, &opts)?;
        x = flow.x;
    }
    Ok((times.to_vec(), beta, lost))
}

#[allow(clippy::too_many_arguments)]
fn measure(
    kind: RunKind,
    file: String,
    t: Vec<f64>,
    alpha: Vec<f64>,
    beta: Vec<f64>,
    noise: f64,
    opts: &SynthOptions,
    rng: &mut Rng,
) -> Run {
    let mut out = Run {
        kind,
        file,
        t: Vec::new(),
        alpha: Vec::new(),
        beta: Vec::new(),
    };
    let mut skip = 0usize;
    for i in 0..t.len() {
        if skip > 0 {
            skip -= 1;
            continue;
        }
        if i > 10 && rng.uniform() < opts.gap_prob {
            skip = 2 + (rng.uniform() * 8.0) as usize;
            continue;
        }
        let mut b = beta[i] + noise * rng.normal();
        if i > 0 && rng.uniform() < opts.outlier_fraction {
            let s = if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
            b += s * (10.0 + 30.0 * rng.uniform()).to_radians();
        }
        out.t.push(t[i]);
        out.alpha.push(alpha[i]);
        out.beta.push(b);
    }
    out
}
