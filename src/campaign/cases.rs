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
               weight not vertical in the frame of the magnets; the family fits the weight's \
               direction); headline: λ",
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
    EffectSpec {
        id: "direction_friction",
        expected: &["unexplained"],
        reference: 0.1,
        unit: "1",
        form: "Coulomb friction η(1 + a d) for motion in the direction d = ±1, a = size (out of \
               catalog; the same force as a constant torque −aη)",
    },
    EffectSpec {
        id: "relative_angle_damping",
        expected: &["unexplained"],
        reference: 0.6,
        unit: "1",
        form: "viscous damping ζ(1 + ε cos²(α − β)) β̇, ε = size (eddy currents that follow the \
               magnets' relative angle; out of catalog)",
    },
    EffectSpec {
        id: "none_drive_ripple",
        expected: &["none"],
        reference: 0.0,
        unit: "",
        form: "base model; the drive's speed ripples once per input turn, α = Ωt + 0.15 sin Ωt, \
               recorded as it is",
    },
    EffectSpec {
        id: "warming_friction",
        expected: &["parameter_drift"],
        reference: 0.2,
        unit: "1",
        form: "dry friction falling as the bearings warm up: a run whose middle lies at the \
               session position u ∈ [0, 1] (recording time, runs in file order) has \
               η(1 − a tanh(u/0.2)), a = size (a warm-up of another shape than the catalog's \
               linear and exponential drifts); headline: η's change from the first run's \
               middle to the last's",
    },
    EffectSpec {
        id: "offcentre_coupling",
        expected: &["unexplained"],
        reference: 0.03,
        unit: "1",
        form: "an output magnet mounted off-centre: the whole coupling torque times \
               1 + m cos(β − φ), m = size, φ drawn uniformly (out of catalog)",
    },
    EffectSpec {
        id: "bearing_bump",
        expected: &["unexplained"],
        reference: 1.0,
        unit: "1",
        form: "a bearing defect: the Coulomb friction times 1 + b exp(−d²/2w²), d the output \
               angle's distance to β₀, b = size, w = 15°, β₀ drawn uniformly (out of catalog)",
    },
    EffectSpec {
        id: "torque_friction",
        expected: &["unexplained"],
        reference: 0.5,
        unit: "1",
        form: "dry friction growing with the transmitted magnetic torque: η(1 + k |B(α, β)|), B \
               the coupling's shape −sin α cos β + Δ cos α sin β, k = size (out of catalog)",
    },
    EffectSpec {
        id: "narrow_stribeck",
        expected: &["static_friction"],
        reference: 0.5,
        unit: "1",
        form: "a Stribeck peak far narrower than the family's widths: friction \
               η + Δη_s/(1 + (β̇/w)²), Δη_s = size·η, w = 0.05 rad/s; headline: Δη_s/η",
    },
    EffectSpec {
        id: "angle_reading",
        expected: &["unexplained"],
        reference: 1.0,
        unit: "deg",
        form: "a distortion of the angle reading: β recorded as β + m sin(β − φ), m = size, φ \
               drawn uniformly (a measurement effect, out of catalog)",
    },
];

/// The effects whose concealed form the diagnosis's catalog does not contain: the campaign's
/// rate of honest verdicts is asserted on these ([`super::metrics::confident_wrong`]).
pub const OUT_OF_CATALOG: &[&str] = &[
    "angle_modulated_friction",
    "direction_friction",
    "relative_angle_damping",
    "offcentre_coupling",
    "bearing_bump",
    "torque_friction",
    "narrow_stribeck",
    "angle_reading",
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
    let (truth, stated, lab) = draw_lab(&mut rng);
    let mut d = Draft {
        truth,
        meas: Measurement::default(),
        set_size: size.clone(),
        truths: Vec::new(),
    };
    let s = spec.reference * level;
    apply_effect(spec.id, level, s, &stated, lab, &mut rng, &mut d)?;
    let set = generate(&d.truth, &d.meas, &d.set_size, stated, rk4, &mut rng)?;
    Ok(GeneratedCase {
        set,
        truth: d.truth,
        size: s,
        truths: d.truths,
    })
}

/// A case being built: the truth model, the measurement and the set size an effect changes,
/// and the headline sizes it adds.
struct Draft {
    truth: TruthModel,
    meas: Measurement,
    set_size: SetSize,
    truths: Vec<TruthSize>,
}

impl Draft {
    /// Adds a headline size of the finding `effect`.
    fn headline(&mut self, effect: &str, value: f64, unit: &str) {
        self.truths.push(TruthSize {
            effect: effect.into(),
            value,
            unit: unit.into(),
        });
    }
}

/// Applies the effect `id` at size `s` (`level` × its reference size) to the drawn lab: the
/// stated set-up `stated` and the true magnet moments and distance `[m₁, m₂, r]`, and `rng`
/// for the effects with random phases (drawn after the lab, before the set).
fn apply_effect(
    id: &str,
    level: f64,
    s: f64,
    stated: &GearSetup,
    [m1, m2, r]: [f64; 3],
    rng: &mut Rng,
    d: &mut Draft,
) -> Result<()> {
    match id {
        "none" => {}
        "none_ar1" => d.meas.ar1 = 0.7,
        "none_ar1_weak" => d.meas.ar1 = 0.3,
        "none_ar1_strong" => d.meas.ar1 = 0.9,
        "none_jitter" => d.meas.jitter_s = 0.5e-3,
        "none_coarse" => {
            d.set_size.samples_per_turn = 20;
            d.set_size.fps = 40.0;
        }
        "nonparallel_same_delta" => {
            let delta = d.truth.delta();
            d.truth.theta += 8f64.to_radians();
            d.truth.phi = phi_for_delta(d.truth.theta, delta)?;
        }
        "shaft_angles_off" => {
            d.truth.theta -= s.to_radians();
            d.truth.phi -= s.to_radians();
            let delta = d.truth.delta();
            d.headline("coupling_geometry", delta, "1");
        }
        "static_torque_2h" => static_torque(s, rng, d),
        "torque_and_latency" => {
            static_torque(6.0 * level, rng, d);
            latency(0.006 * level, d);
        }
        "power_law_drag" => {
            d.truth.power_drag = Some(PowerDrag {
                coef: s,
                exponent: 1.5,
            });
            d.headline("power_law_drag", 1.5, "1");
        }
        "vector_load_friction" | "tilted_load_friction" => {
            let weight = weight_over_force(stated.shaft_mass.unwrap_or(0.32), m1, m2, r);
            load_friction(s, weight, id == "tilted_load_friction", d);
        }
        "stribeck" => stribeck(s, StribeckShape::Gaussian, d),
        "lorentz_stribeck" => stribeck(s, StribeckShape::Lorentzian, d),
        "tanh_drag" => d.truth.tanh_drag = Some(TanhDrag { coef: s, v0: 2.0 }),
        "latency" => latency(s, d),
        "compliance" => {
            d.truth.compliance = s.to_radians();
            d.headline("input_compliance", s, "deg");
        }
        "angle_modulated_friction" => d.truth.angle_modulation = s,
        "frequency_damping" => frequency_damping(s, d),
        "direction_friction" => d.truth.friction_asymmetry = s,
        "relative_angle_damping" => d.truth.zeta_relative = s,
        "none_drive_ripple" => d.truth.drive_ripple = 0.15,
        "warming_friction" => warming_friction(s, d),
        "offcentre_coupling" => {
            d.truth.coupling_modulation = Some((s, rng.range(0.0, std::f64::consts::TAU)))
        }
        "bearing_bump" => {
            let b0 = rng.range(0.0, std::f64::consts::TAU);
            d.truth.friction_bump = Some((s, b0, 15f64.to_radians()));
        }
        "torque_friction" => d.truth.torque_friction = s,
        "narrow_stribeck" => {
            d.truth.stribeck = Some(Stribeck {
                excess: s * d.truth.eta,
                width: 0.05,
                shape: StribeckShape::Lorentzian,
            });
            d.headline("static_friction", s, "1");
        }
        "angle_reading" => {
            d.meas.reading_distortion =
                Some((s.to_radians(), rng.range(0.0, std::f64::consts::TAU)))
        }
        other => {
            return Err(Error::unknown_name(
                "effect with a generator",
                other,
                EFFECTS.iter().map(|e| e.id),
            ))
        }
    }
    Ok(())
}

/// Static torque A₁ sin(β − φ₁) + A₂ sin(2β − φ₂) with A₁ = `a1`, A₂ = A₁/2 and the phases
/// drawn uniformly from `rng` (φ₁ first); headline A₁.
fn static_torque(a1: f64, rng: &mut Rng, d: &mut Draft) {
    d.truth.harmonics = vec![
        (1, a1, rng.range(0.0, std::f64::consts::TAU)),
        (2, 0.5 * a1, rng.range(0.0, std::f64::consts::TAU)),
    ];
    d.headline("static_torque", a1, "s^-2");
}

/// β taken `latency_s` seconds before its time stamp; headline the latency.
fn latency(latency_s: f64, d: &mut Draft) {
    d.meas.latency_s = latency_s;
    d.headline("sensor_latency", latency_s, "s");
}

/// Friction η[(1 − λ) + λ |P(W + F)|/|W|] with λ = `s` capped at 1 and |W|/F₀ = `weight`
/// ([`weight_over_force`]); `tilted`: the set-up tilted by 30° about the output shaft (the
/// weight's direction, a shape parameter of the family). Headline λ.
fn load_friction(s: f64, weight: f64, tilted: bool, d: &mut Draft) {
    d.truth.load = Some(VectorLoad {
        fraction: s.min(1.0),
        weight_over_force: weight,
        tilt: if tilted { 30f64.to_radians() } else { 0.0 },
    });
    d.headline("load_dependent_friction", s.min(1.0), "1");
}

/// Friction η + Δη_s h(β̇/w) with Δη_s = `s`·η, w = 0.5 rad/s and the decay h of `shape`; the
/// Gaussian (the family's own shape) has the headline Δη_s/η, the Lorentzian none.
fn stribeck(s: f64, shape: StribeckShape, d: &mut Draft) {
    let gaussian = shape == StribeckShape::Gaussian;
    d.truth.stribeck = Some(Stribeck {
        excess: s * d.truth.eta,
        width: 0.5,
        shape,
    });
    if gaussian {
        d.headline("static_friction", s, "1");
    }
}

/// Viscous damping ζ(1 + k(f − 1 Hz)) in a driven run at f, k = `s`; headline the change of ζ
/// over the driven runs' frequencies, ζ k (f_max − f_min) (0 with one driven run).
fn frequency_damping(s: f64, d: &mut Draft) {
    d.truth.zeta_per_hz = s;
    let span = if d.set_size.driven > 1 {
        d.set_size.f_max - d.set_size.f_min
    } else {
        0.0
    };
    let value = d.truth.zeta * s * span;
    d.headline("condition_dependence", value, "s^-1");
}

/// The warm-up of the bearings' friction ([`TruthModel::warming`]); the headline is η's change
/// from the first run to the last (their middles), the span over which a drift is reported.
fn warming_friction(s: f64, d: &mut Draft) {
    d.truth.warming = s;
    let u = super::generator::session_middles(&d.set_size);
    let eta = |u: f64| d.truth.for_session(u).eta;
    let change = match (u.first(), u.last()) {
        (Some(&a), Some(&b)) => eta(b) - eta(a),
        _ => 0.0,
    };
    d.headline("parameter_drift", change, "s^-2");
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
