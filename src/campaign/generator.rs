//! Recording sets from a [`TruthModel`], integrated with the campaign's own [`Rk4Filippov`], and a
//! measurement with the imperfections a lab meets: white or coloured (AR(1)) camera noise on β,
//! timing jitter of the frames, a sensor latency, outlier frames, coarse sampling. The layout
//! follows the catalog generator's documented set (ring-downs at a camera frame rate, driven runs
//! sampled on the drive's 7.2° grid) so the two differ only in the physics and the numerics.

use super::rk4::Rk4Filippov;
use super::rng::Rng;
use super::truth::{Drive, TruthModel};
use crate::error::{Error, Result};
use crate::io::recordings::{GearSetup, RecordingSet, Run, RunKind};
use serde::{Deserialize, Serialize};
use std::f64::consts::{FRAC_PI_2, TAU};

/// The size of a recording set.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SetSize {
    /// Name (`ci`, `medium`, `full` or `custom`).
    pub name: String,
    /// Ring-downs (locked input angles spread over a turn).
    pub ringdowns: usize,
    /// Driven runs (frequencies spread evenly over [f_min, f_max]).
    pub driven: usize,
    /// Input turns per driven run.
    pub turns: f64,
    /// Samples per input turn of a driven run.
    pub samples_per_turn: usize,
    /// Ring-down frame rate, 1/s.
    pub fps: f64,
    /// Ring-down duration, s.
    pub ringdown_s: f64,
    /// Lowest drive frequency, Hz.
    pub f_min: f64,
    /// Highest drive frequency, Hz.
    pub f_max: f64,
}

impl SetSize {
    /// The documented full size: 12 ring-downs, 8 driven runs of 80 turns, 50 samples per turn.
    pub fn full() -> Self {
        Self {
            name: "full".into(),
            ringdowns: 12,
            driven: 8,
            turns: 80.0,
            samples_per_turn: 50,
            fps: 100.0,
            ringdown_s: 3.0,
            f_min: 0.5,
            f_max: 2.5,
        }
    }
    /// A medium set: 8 ring-downs, 5 driven runs of 30 turns.
    pub fn medium() -> Self {
        Self {
            name: "medium".into(),
            ringdowns: 8,
            driven: 5,
            turns: 30.0,
            ..Self::full()
        }
    }
    /// A set small enough for CI: 6 ring-downs, 3 driven runs of 12 turns.
    pub fn ci() -> Self {
        Self {
            name: "ci".into(),
            ringdowns: 6,
            driven: 3,
            turns: 12.0,
            ..Self::full()
        }
    }
    /// By name: `ci`, `medium`, `full`.
    pub fn by_name(name: &str) -> Result<Self> {
        match name {
            "ci" => Ok(Self::ci()),
            "medium" => Ok(Self::medium()),
            "full" => Ok(Self::full()),
            other => Err(Error::unknown_name(
                "set size",
                other,
                ["ci", "medium", "full"],
            )),
        }
    }
    /// Checks the numbers.
    pub fn validate(&self) -> Result<()> {
        for (n, v) in [("ringdowns", self.ringdowns), ("driven", self.driven)] {
            if v > 1000 {
                return Err(Error::option(n, format!("{v} runs: at most 1000")));
            }
        }
        if self.ringdowns + self.driven == 0 {
            return Err(Error::inconsistent(
                "ringdowns, driven",
                "a set needs at least one run",
            ));
        }
        if self.samples_per_turn < 8 {
            return Err(Error::option(
                "samples_per_turn",
                format!("{} (need >= 8)", self.samples_per_turn),
            ));
        }
        for (n, v) in [
            ("turns", self.turns),
            ("fps", self.fps),
            ("ringdown_s", self.ringdown_s),
            ("f_min", self.f_min),
            ("f_max", self.f_max),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::InvalidParameter {
                    name: n,
                    value: v,
                    reason: "must be finite and > 0",
                });
            }
        }
        if self.f_max < self.f_min {
            return Err(Error::inconsistent(
                "f_min, f_max",
                format!("f_max = {} < f_min = {}", self.f_max, self.f_min),
            ));
        }
        self.check_samples()
    }

    /// Each run between 10 and [`RUN_SAMPLES_MAX`] samples, the set at most [`SET_SAMPLES_MAX`]
    /// (the limits of a recording set, docs/errors.md).
    fn check_samples(&self) -> Result<()> {
        use crate::io::recordings::limits::{RUN_SAMPLES_MAX, SET_SAMPLES_MAX};
        let min = crate::identification::synth::RUN_SAMPLES_MIN;
        let n = |x: f64| {
            if x.is_finite() && x > 0.0 {
                x.floor() as usize
            } else {
                0
            }
        };
        let (nr, nd) = (
            n(self.ringdown_s * self.fps),
            n(self.turns * self.samples_per_turn as f64),
        );
        for (what, runs, k) in [
            ("ring-down", self.ringdowns, nr),
            ("driven run", self.driven, nd),
        ] {
            if runs > 0 && !(min..=RUN_SAMPLES_MAX).contains(&k) {
                return Err(Error::option(
                    "turns",
                    format!(
                        "{k} samples per {what} ({} turns at {} samples per turn, ring-downs \
                         {} s at {} frames/s): must be in {min}..={RUN_SAMPLES_MAX}",
                        crate::error::show(self.turns),
                        self.samples_per_turn,
                        crate::error::show(self.ringdown_s),
                        crate::error::show(self.fps)
                    ),
                ));
            }
        }
        let total = self.ringdowns as u128 * nr as u128 + self.driven as u128 * nd as u128;
        if total > SET_SAMPLES_MAX as u128 {
            return Err(Error::option(
                "turns",
                format!("a set of {total} samples: at most {SET_SAMPLES_MAX}"),
            ));
        }
        Ok(())
    }
}

/// How β is measured.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Measurement {
    /// Camera noise on β, deg (1σ of the stationary process).
    pub noise_deg: f64,
    /// AR(1) coefficient ρ of the noise between consecutive frames (0 = white):
    /// e_k = ρ e_{k−1} + √(1 − ρ²) σ ξ_k.
    pub ar1: f64,
    /// Timing jitter of the frames, s (1σ): β is taken at t_k + j_k, recorded at t_k.
    pub jitter_s: f64,
    /// Sensor latency, s: β is taken at t_k − τ.
    pub latency_s: f64,
    /// Fraction of outlier frames (β off by 10–40°).
    pub outlier_fraction: f64,
    /// A distortion of the angle reading, periodic in the output angle: β is recorded as
    /// β + m sin(β − φ), (m in rad, φ) this value (an off-axis marker, a lens distortion).
    pub reading_distortion: Option<(f64, f64)>,
}

impl Default for Measurement {
    fn default() -> Self {
        Self {
            noise_deg: 0.5,
            ar1: 0.0,
            jitter_s: 0.0,
            latency_s: 0.0,
            outlier_fraction: 0.002,
            reading_distortion: None,
        }
    }
}

impl SetSize {
    /// The drive frequency of driven run `k`, Hz (rounded to mHz, as the file name states it).
    fn drive_frequency(&self, k: usize) -> f64 {
        let f = if self.driven > 1 {
            self.f_min + (self.f_max - self.f_min) * k as f64 / (self.driven - 1) as f64
        } else {
            self.f_min
        };
        (f * 1000.0).round() / 1000.0
    }
    /// Samples of a ring-down.
    fn ringdown_samples(&self) -> usize {
        (self.ringdown_s * self.fps).floor() as usize
    }
    /// Samples of a driven run.
    fn driven_samples(&self) -> usize {
        (self.turns * self.samples_per_turn as f64).floor() as usize
    }
}

/// The session position u ∈ [0, 1] of each run's middle (ring-downs first, then the driven runs,
/// back to back; a run lasts from its first to its last sample).
pub fn session_middles(size: &SetSize) -> Vec<f64> {
    let rd = size.ringdown_samples().saturating_sub(1) as f64 / size.fps;
    let durations: Vec<f64> = (0..size.ringdowns)
        .map(|_| rd)
        .chain((0..size.driven).map(|k| {
            size.driven_samples().saturating_sub(1) as f64
                / (size.drive_frequency(k) * size.samples_per_turn as f64)
        }))
        .collect();
    let total: f64 = durations.iter().sum::<f64>().max(1e-300);
    let mut start = 0.0;
    durations
        .iter()
        .map(|d| {
            let u = (start + 0.5 * d) / total;
            start += d;
            u
        })
        .collect()
}

/// Makes a recording set from the truth; `stated` is the set-up a lab would write down.
pub fn generate(
    truth: &TruthModel,
    meas: &Measurement,
    size: &SetSize,
    stated: GearSetup,
    integrator: &Rk4Filippov,
    rng: &mut Rng,
) -> Result<RecordingSet> {
    size.validate()?;
    let mut runs = Vec::with_capacity(size.ringdowns + size.driven);
    let session = session_middles(size);
    for (k, &u) in session[..size.ringdowns].iter().enumerate() {
        let alpha0 = TAU * (k as f64 + 0.37) / size.ringdowns as f64;
        let psi = truth.coupling_equilibrium(alpha0);
        let side = if k % 2 == 0 { 1.0 } else { -1.0 };
        let beta0 = psi + side * (FRAC_PI_2 - 0.1 + 0.2 * rng.uniform());
        let n = size.ringdown_samples();
        let t: Vec<f64> = (0..n).map(|i| i as f64 / size.fps).collect();
        let drive = Drive {
            alpha0,
            rate: 0.0,
            ripple: 0.0,
        };
        let run_truth = truth.for_session(u);
        let beta = observe(&run_truth, drive, beta0, &t, meas, integrator, rng)?;
        runs.push(Run {
            kind: RunKind::Ringdown { alpha0 },
            file: format!("ringdown_{k:02}.csv"),
            alpha: vec![alpha0; t.len()],
            t,
            beta,
        });
    }
    for k in 0..size.driven {
        let f = size.drive_frequency(k);
        let n = size.driven_samples();
        let dt = 1.0 / (f * size.samples_per_turn as f64);
        let t: Vec<f64> = (0..n).map(|i| i as f64 * dt).collect();
        let drive = Drive {
            alpha0: 0.0,
            rate: TAU * f,
            ripple: truth.drive_ripple,
        };
        let alpha: Vec<f64> = (0..n)
            .map(|i| {
                let x = TAU * i as f64 / size.samples_per_turn as f64;
                x + drive.ripple_at(x)
            })
            .collect();
        let beta0 = TAU * rng.uniform();
        let run_truth = truth
            .for_drive_frequency(f)
            .for_session(session[size.ringdowns + k]);
        let beta = observe(&run_truth, drive, beta0, &t, meas, integrator, rng)?;
        runs.push(Run {
            kind: RunKind::Driven { f_hz: f },
            file: format!("driven_{k:02}_{f:.3}.csv"),
            t,
            alpha,
            beta,
        });
    }
    Ok(RecordingSet {
        dir: std::path::PathBuf::new(),
        gear: stated,
        runs,
    })
}

/// Integrates from rest at β₀ (t = 0) and measures β at the nominal times `t` with the latency,
/// jitter, noise and outliers of `meas`. The motion before a negative latency's first sample is
/// the state at rest (the output is released at t = 0).
fn observe(
    truth: &TruthModel,
    drive: Drive,
    beta0: f64,
    t: &[f64],
    meas: &Measurement,
    integrator: &Rk4Filippov,
    rng: &mut Rng,
) -> Result<Vec<f64>> {
    let mut actual: Vec<f64> = t
        .iter()
        .map(|&tk| {
            let j = if meas.jitter_s > 0.0 {
                meas.jitter_s * rng.normal()
            } else {
                0.0
            };
            (tk - meas.latency_s + j).max(0.0)
        })
        .collect();
    // jitter smaller than the frame interval keeps the order; sort for safety
    let mut order: Vec<usize> = (0..actual.len()).collect();
    order.sort_by(|&a, &b| actual[a].total_cmp(&actual[b]));
    let sorted: Vec<f64> = order.iter().map(|&i| actual[i]).collect();
    let (b_sorted, _) = integrator.sample(truth, drive, 0.0, [beta0, 0.0], &sorted)?;
    for (k, &i) in order.iter().enumerate() {
        actual[i] = b_sorted[k];
    }
    let sigma = meas.noise_deg.to_radians();
    let rho = meas.ar1;
    let mut e = sigma * rng.normal();
    let mut beta = Vec::with_capacity(actual.len());
    for (k, b) in actual.into_iter().enumerate() {
        if k > 0 {
            e = rho * e + (1.0 - rho * rho).sqrt() * sigma * rng.normal();
        }
        let distortion = meas
            .reading_distortion
            .map_or(0.0, |(m, ph)| m * (b - ph).sin());
        let mut y = b + distortion + e;
        if k > 0 && rng.uniform() < meas.outlier_fraction {
            let s = if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
            y += s * (10.0 + 30.0 * rng.uniform()).to_radians();
        }
        beta.push(y);
    }
    Ok(beta)
}
