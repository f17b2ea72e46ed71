//! The campaign's cases: for each effect, the truth it conceals (a form the catalog does not
//! contain), the verdict a correct diagnosis gives, and the headline size a finding's σ is
//! checked against. A case is (effect, level, seed): the effect at `level` × its reference size,
//! on a lab drawn from `seed`.

use super::generator::{generate, Measurement, SetSize};
use super::rk4::Rk4Filippov;
use super::rng::Rng;
use super::truth::{
    weight_over_force, PowerDrag, Stribeck, StribeckShape, TanhDrag, TruthModel, VectorLoad,
};
use crate::error::{Error, Result};
use crate::io::recordings::{GearSetup, RecordingSet};
use serde::{Deserialize, Serialize};

/// One effect of the campaign.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EffectSpec {
    /// Identifier (`--effects`).
    pub id: &'static str,
    /// The findings a correct diagnosis names (`none`: no finding; `unexplained`: out of catalog).
    pub expected: &'static [&'static str],
    /// Size at level 1, in `unit` (0 for controls, which are not swept).
    pub reference: f64,
    /// Unit of the size.
    pub unit: &'static str,
    /// What the size is and the exact form, for `--list` and the docs.
    pub form: &'static str,
}

impl EffectSpec {
    /// A control (expected `none`): run at one level only.
    pub fn is_null(&self) -> bool {
        self.expected == ["none"]
    }
    /// The verdict label of the confusion matrix (expected effects joined by `+`).
    pub fn label(&self) -> String {
        self.expected.join("+")
    }
}

/// All effects, controls first. The position in this list seeds an effect's random stream
/// ([`build_case`]): new effects go at the end, so the sets of the others stay the same.
pub const EFFECTS: &[EffectSpec] = &[
    EffectSpec {
        id: "none",
        expected: &["none"],
        reference: 0.0,
        unit: "",
        form: "base model only; white camera noise 0.5°",
    },
    EffectSpec {
        id: "none_ar1",
        expected: &["none"],
        reference: 0.0,
        unit: "",
        form: "base model; coloured camera noise, AR(1) with ρ = 0.7 between frames, 0.5° stationary σ",
    },
    EffectSpec {
        id: "none_jitter",
        expected: &["none"],
        reference: 0.0,
        unit: "",
        form: "base model; frame timing jitter 0.5 ms (1σ), time stamps nominal",
    },
    EffectSpec {
        id: "none_coarse",
        expected: &["none"],
        reference: 0.0,
        unit: "",
        form: "base model; coarse sampling: 20 samples per drive turn, ring-downs at 40 frames/s",
    },
    EffectSpec {
        id: "nonparallel_same_delta",
        expected: &["none"],
        reference: 0.0,
        unit: "",
        form: "shafts not parallel: Θ 8° above the drawn angle, Φ solved so that Δ is unchanged \
               (a control: the planar model sees the shaft angles only through Δ)",
    },
    EffectSpec {
        id: "shaft_angles_off",
        expected: &["coupling_geometry"],
        reference: 6.0,
        unit: "deg",
        form: "both true shaft angles lower than stated by `size` (Δ changes); headline: true Δ",
    },
    EffectSpec {
        id: "static_torque_2h",
        expected: &["static_torque"],
        reference: 6.0,
        unit: "s^-2",
        form: "A₁ sin(β − φ₁) + A₂ sin(2β − φ₂), A₁ = size, A₂ = A₁/2, phases drawn uniformly; \
               headline: A₁",
    },
    EffectSpec {
        id: "power_law_drag",
        expected: &["power_law_drag"],
        reference: 0.2,
        unit: "rad^-0.5 s^-0.5",
        form: "−c |β̇|^1.5 sgn β̇, c = size; headline: the exponent 1.5",
    },
    EffectSpec {
        id: "vector_load_friction",
        expected: &["load_dependent_friction"],
        reference: 0.5,
        unit: "1",
        form: "η[(1 − λ) + λ |P(W + F)|/|W|], λ = size (capped at 1): W the shaft weight (0.32 kg), \
               F the dipole–dipole force on the output magnet, P the projection perpendicular to \
               the output shaft; headline: λ",
    },
    EffectSpec {
        id: "stribeck",
        expected: &["static_friction"],
        reference: 0.5,
        unit: "1",
        form: "friction η + Δη_s exp(−(β̇/w)²), Δη_s = size·η, w = 0.5 rad/s; at rest the bound is \
               η + Δη_s; headline: Δη_s/η",
    },
    EffectSpec {
        id: "tanh_drag",
        expected: &["power_law_drag"],
        reference: 0.4,
        unit: "s^-1",
        form: "−c tanh(β̇/v₀)|β̇|, v₀ = 2 rad/s, c = size: quadratic below v₀, linear above; outside \
               the drag family (nearest member: an exponent between 1 and 2)",
    },
    EffectSpec {
        id: "lorentz_stribeck",
        expected: &["static_friction"],
        reference: 0.5,
        unit: "1",
        form: "friction η + Δη_s/(1 + (β̇/w)²), Δη_s = size·η, w = 0.5 rad/s: a Stribeck decay of \
               another shape than the family's",
    },
    EffectSpec {
        id: "tilted_load_friction",
        expected: &["load_dependent_friction"],
        reference: 0.5,
        unit: "1",
        form: "`vector_load_friction` with the set-up tilted by 30° about the output shaft (the \
               weight not vertical in the frame of the magnets): a load geometry outside the family",
    },
    EffectSpec {
        id: "latency",
        expected: &["sensor_latency"],
        reference: 0.006,
        unit: "s",
        form: "β taken `size` seconds before its time stamp; headline: the latency",
    },
    EffectSpec {
        id: "compliance",
        expected: &["input_compliance"],
        reference: 1.5,
        unit: "deg",
        form: "input magnet on a torsional spring: α_m = α_d + L(−cos α_m sin β + Δ sin α_m cos β) \
               solved exactly, L = size (the lag at the peak coupling torque); headline: L",
    },
    EffectSpec {
        id: "angle_modulated_friction",
        expected: &["unexplained"],
        reference: 0.4,
        unit: "1",
        form: "Coulomb friction η sgn(β̇)(1 + ε cos 2β), ε = size (out of catalog)",
    },
    EffectSpec {
        id: "torque_and_latency",
        expected: &["static_torque", "sensor_latency"],
        reference: 1.0,
        unit: "× (6 s^-2, 6 ms)",
        form: "static_torque_2h with A₁ = 6·size s⁻² and latency 0.006·size s together; both \
               must be named",
    },
    EffectSpec {
        id: "frequency_damping",
        expected: &["condition_dependence"],
        reference: 0.3,
        unit: "1/Hz",
        form: "viscous damping that depends on the drive frequency: ζ(1 + k(f − 1 Hz)) in a driven \
               run at f, the ring-downs at ζ, k = size; headline: the change of ζ over the driven \
               runs' frequencies, ζ k (f_max − f_min)",
    },
    EffectSpec {
        id: "none_ar1_weak",
        expected: &["none"],
        reference: 0.0,
        unit: "",
        form: "base model; coloured camera noise, AR(1) with ρ = 0.3 between frames, 0.5° stationary σ",
    },
    EffectSpec {
        id: "none_ar1_strong",
        expected: &["none"],
        reference: 0.0,
        unit: "",
        form: "base model; coloured camera noise, AR(1) with ρ = 0.9 between frames, 0.5° stationary σ",
    },
];

/// Looks an effect up by id.
pub fn effect(id: &str) -> Result<&'static EffectSpec> {
    EFFECTS
        .iter()
        .find(|e| e.id == id)
        .ok_or_else(|| Error::unknown_name("effect", id, EFFECTS.iter().map(|e| e.id)))
}

/// A headline size the diagnosis should report, with the truth.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TruthSize {
    /// The finding's effect it belongs to.
    pub effect: String,
    /// True value, in `unit`.
    pub value: f64,
    /// Unit, as the report states it.
    pub unit: String,
}

/// A generated case: the set, and what a correct diagnosis says about it.
#[derive(Debug, Clone)]
pub struct GeneratedCase {
    /// The recording set (in memory).
    pub set: RecordingSet,
    /// The truth model.
    pub truth: TruthModel,
    /// Effect size at this level, in the effect's unit.
    pub size: f64,
    /// Headline sizes with their true values.
    pub truths: Vec<TruthSize>,
}

/// The lab of a seed: the true base model (drawn inside the stated tolerances) and the set-up a
/// lab would state (the paper's rounded values with explicit tolerances, no inertia).
pub fn draw_lab(rng: &mut Rng) -> (TruthModel, GearSetup, [f64; 3]) {
    let mut stated = GearSetup::paper();
    stated.inertia = None;
    stated.beta_noise_deg = None;
    stated.theta_tol_deg = Some(3.0);
    stated.phi_tol_deg = Some(3.0);
    stated.m_tol = Some(0.11);
    stated.r_tol = Some(0.5e-3);
    // the truth: within half the stated tolerances, uniformly
    let m1 = stated.m1 + rng.range(-0.055, 0.055);
    let m2 = stated.m2 + rng.range(-0.055, 0.055);
    let r = stated.r + rng.range(-0.25e-3, 0.25e-3);
    let inertia = 6.45e-5 * rng.range(0.95, 1.05);
    let theta = (stated.theta_deg + rng.range(-1.5, 1.5)).to_radians();
    let phi = (stated.phi_deg + rng.range(-1.5, 1.5)).to_radians();
    let zeta = 1.1 * rng.range(0.8, 1.2);
    let eta = 23.1 * rng.range(0.8, 1.2);
    let g = crate::model::gear::MU0_OVER_4PI * m1 * m2 / r.powi(3) / inertia;
    (
        TruthModel::base(g, theta, phi, zeta, eta),
        stated,
        [m1, m2, r],
    )
}

/// Φ with cos Θ cos Φ − 2 sin Θ sin Φ = Δ (the root nearest the parallel configuration).
fn phi_for_delta(theta: f64, delta: f64) -> Result<f64> {
    let (st, ct) = theta.sin_cos();
    let rr = (ct * ct + 4.0 * st * st).sqrt();
    if delta.abs() > rr {
        return Err(Error::option(
            "delta",
            format!(
                "no output angle gives Δ = {delta} at Θ = {:.2}°",
                theta.to_degrees()
            ),
        ));
    }
    Ok((delta / rr).acos() - (2.0 * st).atan2(ct))
}

/// Builds the case (effect, level, seed) at set size `size` with the integrator `rk4`.
pub fn build_case(
    spec: &EffectSpec,
    level: f64,
    seed: u64,
    size: &SetSize,
    rk4: &Rk4Filippov,
) -> Result<GeneratedCase> {
    if !(level.is_finite() && level >= 0.0) {
        return Err(Error::InvalidParameter {
            name: "level",
            value: level,
            reason: "an effect level must be finite and >= 0",
        });
    }
    let stream = EFFECTS.iter().position(|e| e.id == spec.id).unwrap_or(0) as u64;
    let mut rng = Rng::new(seed, stream * 1000 + (level * 100.0).round() as u64);
    let (mut truth, stated, [m1, m2, r]) = draw_lab(&mut rng);
    let mut meas = Measurement::default();
    let mut set_size = size.clone();
    let s = spec.reference * level;
    let mut truths = Vec::new();
    match spec.id {
        "none" => {}
        "none_ar1" => meas.ar1 = 0.7,
        "none_ar1_weak" => meas.ar1 = 0.3,
        "none_ar1_strong" => meas.ar1 = 0.9,
        "none_jitter" => meas.jitter_s = 0.5e-3,
        "none_coarse" => {
            set_size.samples_per_turn = 20;
            set_size.fps = 40.0;
        }
        "nonparallel_same_delta" => {
            let d = truth.delta();
            truth.theta += 8f64.to_radians();
            truth.phi = phi_for_delta(truth.theta, d)?;
        }
        "shaft_angles_off" => {
            truth.theta -= s.to_radians();
            truth.phi -= s.to_radians();
            truths.push(TruthSize {
                effect: "coupling_geometry".into(),
                value: truth.delta(),
                unit: "1".into(),
            });
        }
        "static_torque_2h" | "torque_and_latency" => {
            let a1 = if spec.id == "static_torque_2h" {
                s
            } else {
                6.0 * level
            };
            truth.harmonics = vec![
                (1, a1, rng.range(0.0, std::f64::consts::TAU)),
                (2, 0.5 * a1, rng.range(0.0, std::f64::consts::TAU)),
            ];
            truths.push(TruthSize {
                effect: "static_torque".into(),
                value: a1,
                unit: "s^-2".into(),
            });
            if spec.id == "torque_and_latency" {
                meas.latency_s = 0.006 * level;
                truths.push(TruthSize {
                    effect: "sensor_latency".into(),
                    value: meas.latency_s,
                    unit: "s".into(),
                });
            }
        }
        "power_law_drag" => {
            truth.power_drag = Some(PowerDrag {
                coef: s,
                exponent: 1.5,
            });
            truths.push(TruthSize {
                effect: "power_law_drag".into(),
                value: 1.5,
                unit: "1".into(),
            });
        }
        "vector_load_friction" | "tilted_load_friction" => {
            let tilted = spec.id == "tilted_load_friction";
            truth.load = Some(VectorLoad {
                fraction: s.min(1.0),
                weight_over_force: weight_over_force(stated.shaft_mass.unwrap_or(0.32), m1, m2, r),
                tilt: if tilted { 30f64.to_radians() } else { 0.0 },
            });
            if !tilted {
                truths.push(TruthSize {
                    effect: "load_dependent_friction".into(),
                    value: s.min(1.0),
                    unit: "1".into(),
                });
            }
        }
        "stribeck" | "lorentz_stribeck" => {
            truth.stribeck = Some(Stribeck {
                excess: s * truth.eta,
                width: 0.5,
                shape: if spec.id == "stribeck" {
                    StribeckShape::Gaussian
                } else {
                    StribeckShape::Lorentzian
                },
            });
            if spec.id == "stribeck" {
                truths.push(TruthSize {
                    effect: "static_friction".into(),
                    value: s,
                    unit: "1".into(),
                });
            }
        }
        "tanh_drag" => truth.tanh_drag = Some(TanhDrag { coef: s, v0: 2.0 }),
        "latency" => {
            meas.latency_s = s;
            truths.push(TruthSize {
                effect: "sensor_latency".into(),
                value: s,
                unit: "s".into(),
            });
        }
        "compliance" => {
            truth.compliance = s.to_radians();
            truths.push(TruthSize {
                effect: "input_compliance".into(),
                value: s,
                unit: "deg".into(),
            });
        }
        "angle_modulated_friction" => truth.angle_modulation = s,
        "frequency_damping" => {
            truth.zeta_per_hz = s;
            let span = if set_size.driven > 1 {
                set_size.f_max - set_size.f_min
            } else {
                0.0
            };
            truths.push(TruthSize {
                effect: "condition_dependence".into(),
                value: truth.zeta * s * span,
                unit: "s^-1".into(),
            });
        }
        other => {
            return Err(Error::unknown_name(
                "effect with a generator",
                other,
                EFFECTS.iter().map(|e| e.id),
            ))
        }
    }
    let set = generate(&truth, &meas, &set_size, stated, rk4, &mut rng)?;
    Ok(GeneratedCase {
        set,
        truth,
        size: s,
        truths,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nonparallel_control_keeps_delta() {
        for th in [20.0f64, 31.0, 39.0] {
            let t = th.to_radians();
            let phi = phi_for_delta(t, 0.2042).unwrap();
            let d = t.cos() * phi.cos() - 2.0 * t.sin() * phi.sin();
            assert!((d - 0.2042).abs() < 1e-12);
        }
    }
}
