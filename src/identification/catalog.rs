//! The catalog of physically parameterised candidate terms (recordings.md) and the dictionary for
//! the sparse search beyond it.
//!
//! Implemented (they enter the weak-form regression linearly, or through one profiled parameter):
//! `coupling_geometry`, `static_torque`, `quadratic_drag`, `corotating_drag`,
//! `load_dependent_friction`, `sensor_latency` (profiled time shift), `input_compliance`,
//! `drive_steps`, `parameter_drift` (one entry per drifting parameter and session clock),
//! `static_friction` (no regression term: profiled over the stick phases by simulation,
//! [`super::release`]).

use super::model::{Shape, DRAG_REFERENCE_SPEED};
use super::regression::{Clock, DriftParam, Term};
use std::collections::BTreeMap;

/// A catalogued effect.
#[derive(Debug, Clone, PartialEq)]
pub struct Effect {
    /// Identifier (recordings.md).
    pub id: &'static str,
    /// Class: effects in one class leave the same fingerprint in these data.
    pub class: &'static str,
    /// What it is, in words.
    pub explanation: &'static str,
    /// Extra regression terms (empty for `sensor_latency`, which is profiled).
    pub terms: Vec<Term>,
    /// Physical causes that give the same term.
    pub candidates: Vec<&'static str>,
    /// The experiment that would separate the candidates.
    pub discriminating_experiment: &'static str,
}

/// The implemented catalog.
pub fn catalog() -> Vec<Effect> {
    let mut v = static_torque_members();
    v.extend(load_friction_members());
    v.extend([
        Effect {
            id: "coupling_geometry",
            class: "coupling",
            explanation: "the bilinear coupling differs from the nominal one: terms cos α cos β and \
                          sin α sin β appear (a zero offset of the input or of the output angle \
                          reading, read off as alpha_offset_deg and beta_offset_deg; an \
                          out-of-plane tilt or true shaft angles other than nominal)",
            terms: vec![Term::CosACosB, Term::SinASinB],
            candidates: vec![
                "input angle zero offset",
                "output angle (camera) zero offset",
                "out-of-plane tilt of a shaft",
                "shaft angles other than nominal",
            ],
            discriminating_experiment: "measure the equilibrium β0(α0) of ring-downs over a full \
                turn of α0 with the camera zero re-calibrated: a constant offset between α0 and the \
                fitted coupling phase is a zero offset; a dependence on the shaft angle setting is \
                a tilt",
        },
        Effect {
            id: "power_law_drag",
            class: "velocity-dependent damping",
            explanation: "drag −q (|β̇|/V)^p sgn β̇ (q the drag at V = 4 rad/s) with the exponent p \
                          fitted by simulation (p = 2: \
                          the quadratic air drag of the rotating magnet; p between 1 and 2: drag \
                          in the transition from laminar to turbulent flow)",
            terms: vec![Term::Quad, Term::Shape(Shape::DragExponent)],
            candidates: vec![
                "air drag",
                "turbulent drag of the rotor",
                "drag in the laminar–turbulent transition",
            ],
            discriminating_experiment: "ring-downs from larger initial amplitudes (faster peak \
                velocities): the decrement grows with amplitude as |β̇|^(p−1); the exponent \
                changes with the air pressure or a shroud around the rotor for air drag",
        },
        Effect {
            id: "corotating_drag",
            class: "drive-dependent damping",
            explanation: "viscous drag relative to the input, −c (β̇ − α̇): damping seen by the \
                          driven runs but not the ring-downs (eddy currents in parts turning with \
                          the input)",
            terms: vec![Term::Corot],
            candidates: vec![
                "eddy currents in conductive parts turning with the input",
                "air dragged along by the input rotor",
            ],
            discriminating_experiment: "ring-downs with the input turning slowly at a constant \
                rate (or locked at different α0 and then at rest): a drift of the output's rest \
                angle with the input rate identifies the corotating drag",
        },
        Effect {
            id: "sensor_latency",
            class: "timing",
            explanation: "β is recorded with a time offset relative to α (camera latency): an \
                          effective input angle offset proportional to the drive frequency, absent \
                          in ring-downs",
            terms: vec![],
            candidates: vec!["camera exposure/trigger delay", "clock offset between drive and camera"],
            discriminating_experiment: "film a marker on the input shaft with the same camera: its \
                recorded angle lags the commanded α by α̇·τ",
        },
        Effect {
            id: "input_compliance",
            class: "input compliance",
            explanation: "the input magnet lags the drive by the coupling torque on it over a \
                          torsional stiffness k_in: α_in = α + χ τ_in(α, β), χ = I/k_in; the output \
                          sees twice-per-turn harmonics of α and β that a rigid drive cannot make",
            terms: vec![Term::Compliance],
            candidates: vec![
                "torsional compliance of the input shaft or shaft coupling",
                "load angle of the stepper motor (its holding torque acts as a spring)",
                "elastic motor mount",
            ],
            discriminating_experiment: "film a marker on the input magnet: its lag behind the \
                commanded angle follows the coupling torque (twice per input turn); a stiffer \
                coupling or a motor with more holding torque shrinks it",
        },
        Effect {
            id: "drive_steps",
            class: "input angle in driven runs",
            explanation: "in driven runs the input's true angle departs from the recorded \
                          (commanded) one, absent in ring-downs: a constant lag (a drive that rests \
                          between steps lags its commanded angle by about half a step) and a lag \
                          growing with the turns (lost steps)",
            terms: vec![Term::DrivenOffset, Term::DrivenOffsetRate],
            candidates: vec![
                "stepping drive: the input rests between steps",
                "lost steps of the stepper motor",
                "drive angle zero set differently from the ring-downs' hold angle",
            ],
            discriminating_experiment: "film a marker on the input magnet at a frame rate well \
                above the step rate (or read an encoder on the input shaft): steps, their phase \
                to the commanded angle and lost steps show directly",
        },
        Effect {
            id: "static_friction",
            class: "friction",
            explanation: "breakaway (static) friction above the sliding friction: an output at rest \
                          stays stuck until the torque exceeds η(1 + s), then slides with η; the \
                          stick phases last longer and the output leaves them with a jump of the \
                          acceleration (Stribeck-like)",
            terms: vec![],
            candidates: vec![
                "breakaway/Stribeck friction of the bearings",
                "stiction of a seal or cable",
            ],
            discriminating_experiment: "slow-ramp release experiment: from a stuck state turn the \
                input very slowly and record the input angle at which the output breaks away; the \
                torque there, compared with the sliding friction from ring-downs, is the breakaway \
                excess (a Stribeck curve also shows as a friction falling with speed in ring-downs \
                from small amplitudes)",
        },
        Effect {
            id: "static_friction",
            class: "friction",
            explanation: "breakaway (static) friction above the sliding friction that decays into \
                          sliding over a Stribeck width w: the friction is η + η_Δs \
                          exp(−(|β̇|/w)^δ) (w and the shape δ fitted by simulation: δ = 2 the \
                          Gaussian, δ = 1 the exponential Stribeck curve; w → 0 is the excess at \
                          rest only): an output at rest stays stuck until the torque exceeds \
                          η + η_Δs, and slow sliding is braked more than fast sliding",
            terms: vec![
                Term::StaticExcess,
                Term::Shape(Shape::StribeckWidth),
                Term::Shape(Shape::StribeckPower),
            ],
            candidates: vec![
                "breakaway/Stribeck friction of the bearings",
                "stiction of a seal or cable",
            ],
            discriminating_experiment: "slow-ramp release experiment: from a stuck state turn the \
                input very slowly and record the input angle at which the output breaks away; the \
                torque there, compared with the sliding friction from ring-downs, is the breakaway \
                excess (a Stribeck curve also shows as a friction falling with speed in ring-downs \
                from small amplitudes)",
        },
    ]);
    v.extend(drift_members());
    v
}

/// The terms of a `condition_dependence` of `p` on `clock`: the drive frequency exists on the
/// driven runs only, so its member also carries the ring-downs' own level ([`Clock::RunKind`]);
/// the velocity range is a condition of every run.
fn condition_terms(p: DriftParam, clock: Clock) -> Vec<Term> {
    match clock {
        Clock::DriveFrequency => vec![Term::Drift(p, clock), Term::Drift(p, Clock::RunKind)],
        _ => vec![Term::Drift(p, clock)],
    }
}

/// The per-run parameter effects: `condition_dependence` (a base parameter linear in a run
/// condition) and `parameter_drift` (linear in a session clock, or settling exponentially along
/// it: [`Clock::session_orders`]), for each of ζ, η and g.
fn drift_members() -> Vec<Effect> {
    let mut v = Vec::new();
    for p in DriftParam::ALL {
        for clock in [Clock::DriveFrequency, Clock::VelocityRange] {
            v.push(Effect {
                id: "condition_dependence",
                class: "state-dependent parameter",
                explanation: match p {
                    DriftParam::Eta => {
                        "the dry friction η differs from run to run with the run's conditions (drive frequency or velocity range): a friction law that depends on the state, which one linear model cannot hold"
                    }
                    DriftParam::Zeta => {
                        "the viscous damping ζ differs from run to run with the run's conditions (drive frequency or velocity range): a damping law that is not linear in the velocity"
                    }
                    DriftParam::Coupling => {
                        "the coupling strength g differs from run to run with the run's conditions (drive frequency or velocity range)"
                    }
                },
                terms: condition_terms(p, clock),
                candidates: vec![
                    "a friction or damping law depending on the velocity or the angles",
                    "a drift over the session (when the runs were recorded in the order of the condition)",
                ],
                discriminating_experiment: "repeat runs of one condition at the start and the end of a session, and record the conditions in shuffled order: a condition dependence stays with the condition, a drift with the time",
            });
        }
        for clock in Clock::session_orders() {
            v.push(Effect {
                id: "parameter_drift",
                class: "drift",
                explanation: match p {
                    DriftParam::Eta => {
                        "the dry friction η changes over the recording session (linear in the \
                         session position of the runs, or settling exponentially as in a \
                         warm-up)"
                    }
                    DriftParam::Zeta => {
                        "the viscous damping ζ changes over the recording session (linear in the \
                         session position of the runs, or settling exponentially as in a \
                         warm-up)"
                    }
                    DriftParam::Coupling => {
                        "the coupling strength g changes over the recording session (linear in \
                         the session position of the runs, or settling exponentially as in a \
                         warm-up)"
                    }
                },
                terms: vec![Term::Drift(p, clock)],
                candidates: match p {
                    DriftParam::Eta => vec!["bearings warming up (lubricant viscosity)", "wear"],
                    DriftParam::Zeta => vec![
                        "air temperature",
                        "eddy-current damping changing with temperature",
                    ],
                    DriftParam::Coupling => vec![
                        "magnet temperature (NdFeB remanence falls ≈0.1 %/K)",
                        "centre distance creeping",
                    ],
                },
                discriminating_experiment: "repeat a reference ring-down every few runs (and at \
                    the end of the session) and log the temperature of bearings and magnets: the \
                    drift shows between the repeats and follows the temperature",
            });
        }
    }
    v
}

/// The `static_torque` family: lab-fixed torques Σ_k (A_k sin kβ + B_k cos kβ) with harmonics
/// k = 1..K, K = 1, 2, 3 (nested members; the held-out judge picks K, [`MemberChoice::Nested`]).
fn static_torque_members() -> Vec<Effect> {
    let harmonics: [&[Term]; 3] = [
        &[Term::SinB, Term::CosB],
        &[Term::Sin(0, 2), Term::Cos(0, 2)],
        &[Term::Sin(0, 3), Term::Cos(0, 3)],
    ];
    (1..=3)
        .map(|k| Effect {
            id: "static_torque",
            class: "lab-fixed",
            explanation: "a torque on the output fixed in the lab, periodic in β: \
                          A₁ sin β + B₁ cos β plus harmonics A_k sin kβ + B_k cos kβ (k ≤ 3, as many \
                          as the held-out judge accepts); it breaks the (α, β) → (α+π, β+π) \
                          symmetry of the base model",
            terms: harmonics[..k].concat(),
            candidates: vec![
                "input dipole tilt",
                "output mass imbalance",
                "stray static field",
                "magnetised or ferromagnetic parts near the output (higher harmonics)",
            ],
            discriminating_experiment: "remove the input magnet and record ring-downs of the output \
                alone: a remaining once-per-turn torque is mass imbalance (it scales with gravity: \
                tilt the set-up by 90° and it changes) or a stray field (it follows a compass \
                needle / moves with the set-up's position in the room); if it vanishes, the input \
                dipole is tilted (rotate the input magnet in its socket by 180° and the torque \
                changes sign); harmonics that remain without the input magnet point to \
                ferromagnetic parts near the output",
        })
        .collect()
}

/// The `load_dependent_friction` family: dry friction η + η_L L with the bearing load
/// L = |F + W| (the dipole force F and the shaft's weight W = −ρ_z ẑ − ρ_n n̂ added as vectors)
/// or its radial part |P(F + W)| (perpendicular to the output shaft), the weight's vertical and
/// side components (units F₀) fitted by simulation: its size ρ = |W|/F₀ and its direction, the
/// tilt ψ of the set-up about the output shaft ([`super::model::load_shape`]). Written as
/// η_t [(1 − λ) + λ L/ρ]: a fraction λ = η_L ρ / (η + η_L ρ) of the friction is load-dependent.
/// A zero weight with the whole load is the dipole force alone.
fn load_friction_members() -> Vec<Effect> {
    [Term::LoadFric, Term::RadialLoadFric]
        .into_iter()
        .map(|t| Effect {
            id: "load_dependent_friction",
            class: "friction",
            explanation: "dry friction grows with the bearing load, the shaft's weight and the \
                          magnetic force between the magnets added as vectors (the whole load, or \
                          its radial part): η + η_L |(P)(F + W)|, a fraction λ of the friction \
                          load-dependent, the weight W of fitted size and direction (the set-up's \
                          tilt about the output shaft)",
            terms: vec![
                t,
                Term::Shape(Shape::LoadWeight),
                Term::Shape(Shape::LoadSide),
            ],
            candidates: vec![
                "bearing friction proportional to the radial load",
                "bearing friction proportional to the total load (axial and radial)",
            ],
            discriminating_experiment: "ring-downs at a larger centre distance r (weaker magnetic \
                force): the dry friction should fall towards the weight-only value; adding a known \
                mass to the output shaft raises ρ and the friction by the fitted fraction",
        })
        .collect()
}

/// How the member of a family that goes into a model is chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MemberChoice {
    /// The weak form's best member by ΔBIC is the family's one proposal.
    WeakForm,
    /// Nested members (`static_torque`'s harmonics 1..K): all proposed, and the held-out judge
    /// keeps the smallest one that no larger member beats significantly.
    Nested,
    /// Alternative members that the weak form cannot be trusted to choose between: each
    /// member's best start is proposed and the held-out judge keeps the one that predicts best
    /// like any other candidates of the round (the whole and the radial bearing load of
    /// `load_dependent_friction` differ only by the force's component along the output shaft:
    /// on a full-size set of a radial load the weak form preferred the whole load by ΔBIC, whose
    /// refit then lost to a dictionary term; docs/diagnosis.md, "The catalog as families").
    Alternatives,
}

/// How the members of the family `id` are chosen ([`MemberChoice`]).
pub fn member_choice(id: &str) -> MemberChoice {
    match id {
        "static_torque" => MemberChoice::Nested,
        "load_dependent_friction" => MemberChoice::Alternatives,
        _ => MemberChoice::WeakForm,
    }
}

/// Whether two catalog entries fill the same slot (one finding per slot): the same effect, and
/// for `parameter_drift` the same drifting parameter.
pub fn same_slot(a: &Effect, b: &Effect) -> bool {
    let drift_param = |e: &Effect| {
        e.terms.iter().find_map(|t| match t {
            Term::Drift(p, _) => Some(*p),
            _ => None,
        })
    };
    a.id == b.id && drift_param(a) == drift_param(b)
}

/// Whether two members of a family compete for one proposal ([`super::propose`]: the best of
/// them by the weak form's ΔBIC is proposed): the same slot ([`same_slot`]) and, for a drift,
/// the same kind of session clock, run index or recording time. The weak form's rows weigh the
/// short ring-downs little, so it cannot tell the two clocks apart where they differ most (at
/// the start of a session of ring-downs); the best member of each is proposed and the held-out
/// judge decides, as for [`MemberChoice::Alternatives`].
pub fn same_proposal(a: &Effect, b: &Effect) -> bool {
    let session_time = |e: &Effect| {
        e.terms.iter().find_map(|t| match t {
            Term::Drift(_, c) => Some(c.follows_session_time()),
            _ => None,
        })
    };
    same_slot(a, b) && session_time(a) == session_time(b)
}

/// The angle harmonics (k, l) of cos/sin(kα + lβ) that modulate the dictionary's viscous and dry
/// friction terms beyond (0, 1): the output angle's second harmonic, the input angle's first
/// two, and the first two of the sum and of the difference (the magnets' relative angle).
pub const MODULATIONS: [(i8, i8); 7] = [(0, 2), (1, 0), (2, 0), (1, 1), (1, -1), (2, 2), (2, -2)];

/// Dictionary for the sparse search: a constant torque (`const`: a bias torque, or a dry
/// friction that differs by the direction of motion, η₊ ≠ η₋, which is the same force),
/// trig(kα + lβ) with |k|, |l| ≤ 2 (not already in the base model or the catalog) and
/// cos/sin 3β, viscous damping −β̇ and dry friction −sgn β̇ modulated by cos/sin β and by
/// cos/sin(kα + lβ) for the (k, l) of [`MODULATIONS`].
pub fn dictionary() -> Vec<Term> {
    // a constant torque c: −sgn β̇ η (1 + a sgn β̇) = −sgn β̇ η − aη while sliding, and its stick
    // band [−η(1 − a), η(1 + a)] is that of η about a torque −aη: the same Filippov system
    let mut v = vec![Term::Cos(0, 0)];
    for k in 0..=2i8 {
        for l in -2..=2i8 {
            if k == 0 && l <= 0 {
                continue;
            }
            // k = ±1, l = ±1 products are the coupling terms; k = 0, l = 1 the static torque
            if (k == 1 && l.abs() == 1) || (k == 0 && l == 1) {
                continue;
            }
            v.push(Term::Cos(k, l));
            v.push(Term::Sin(k, l));
        }
    }
    // torques with the third harmonic of β
    v.extend([Term::Cos(0, 3), Term::Sin(0, 3)]);
    v.extend([Term::VCosB, Term::VSinB, Term::SCosB, Term::SSinB]);
    // viscous damping and dry friction modulated by harmonics of α and β
    for (k, l) in MODULATIONS {
        for sin in [false, true] {
            v.push(Term::VTrig(k, l, sin));
            v.push(Term::STrig(k, l, sin));
        }
    }
    v
}

/// Physical parameters of an effect from its fitted coefficients (value, 1σ), by term; `base`
/// holds the fitted base values (ζ, η, g) the effect is measured against.
pub fn effect_params(
    effect: &Effect,
    coef: &BTreeMap<String, (f64, f64)>,
    base: (f64, f64, f64),
) -> BTreeMap<String, f64> {
    let (_, base_eta, g) = base;
    let mut p = BTreeMap::new();
    let get = |t: Term| coef.get(&t.name()).copied();
    match effect.id {
        "parameter_drift" | "condition_dependence" => {
            drift_params(&effect.terms, &get, base, &mut p)
        }
        "input_compliance" => compliance_params(&get, g, &mut p),
        "drive_steps" => drive_steps_params(&get, g, &mut p),
        "static_torque" => static_torque_params(&get, &mut p),
        "coupling_geometry" => coupling_geometry_params(&get, g, &mut p),
        "static_friction" => static_friction_params(&get, base_eta, &mut p),
        "power_law_drag" => power_law_drag_params(&get, &mut p),
        "corotating_drag" => {
            if let Some((c, s)) = get(Term::Corot) {
                p.insert("c".into(), c);
                p.insert("c_err".into(), s);
            }
        }
        "load_dependent_friction" => load_friction_params(&get, base_eta, &mut p),
        _ => {}
    }
    p
}

/// A drifting or condition-dependent base parameter, for each [`Term::Drift`] of `terms` with a
/// coefficient: the driven runs' level minus the ring-downs' ([`Clock::RunKind`]), or the
/// change v from the first run to the last or over the condition range (the column is
/// s·(base term), s from −½ to ½), relative to the base value of `base` = (ζ, η, g), the values
/// at the start and the end (base ∓ v/2), and which clock it runs on (with a settling clock's
/// τ).
fn drift_params(
    terms: &[Term],
    get: &dyn Fn(Term) -> Option<(f64, f64)>,
    base: (f64, f64, f64),
    p: &mut BTreeMap<String, f64>,
) {
    let (base_zeta, base_eta, g) = base;
    for t in terms {
        if let (Term::Drift(dp, clock), Some((v, s))) = (t, get(*t)) {
            let name = dp.name();
            let reference = match dp {
                DriftParam::Zeta => base_zeta,
                DriftParam::Eta => base_eta,
                DriftParam::Coupling => g,
            };
            if *clock == Clock::RunKind {
                // s = +½ driven, −½ ring-downs: v is the driven runs' level minus the
                // ring-downs'
                p.insert(format!("{name}_driven_minus_ringdown"), v);
                p.insert(format!("{name}_driven_minus_ringdown_err"), s);
                continue;
            }
            // the column is s·(base term), s from −½ (first run) to ½ (last run): v is the change
            // between the first and the last run
            p.insert(format!("{name}_change"), v);
            p.insert(format!("{name}_change_err"), s);
            if reference != 0.0 {
                p.insert(format!("{name}_relative_change"), v / reference);
                p.insert(format!("{name}_relative_change_err"), s / reference.abs());
            }
            p.insert(format!("{name}_start"), reference - 0.5 * v);
            p.insert(format!("{name}_end"), reference + 0.5 * v);
            p.insert(
                "clock_session_time".into(),
                f64::from(u8::from(clock.follows_session_time())),
            );
            // 0 for a linear drift, else the settling time in fractions of the session: the
            // refitted one when the model frees it, else the clock's grid value
            let tau = get(Term::Shape(Shape::DriftSettling));
            p.insert(
                "clock_settling_tau".into(),
                tau.map_or(clock.settling_tau().unwrap_or(0.0), |t| t.0),
            );
            if let Some((_, err)) = tau {
                p.insert("clock_settling_tau_err".into(), err);
            }
            p.insert(
                "clock_drive_frequency".into(),
                f64::from(u8::from(*clock == Clock::DriveFrequency)),
            );
            p.insert(
                "clock_velocity_range".into(),
                f64::from(u8::from(*clock == Clock::VelocityRange)),
            );
        }
    }
}

/// Input compliance from the coefficient χg² of [`Term::Compliance`]: χ, the lag χg at the peak
/// coupling torque (τ_in = g), and the stiffness over inertia g²/(χg²) when positive.
fn compliance_params(
    get: &dyn Fn(Term) -> Option<(f64, f64)>,
    g: f64,
    p: &mut BTreeMap<String, f64>,
) {
    if let Some((v, s)) = get(Term::Compliance) {
        // coefficient χ g²: the lag at the peak coupling torque (τ_in = g) is χ g
        p.insert("chi_s2".into(), v / (g * g));
        p.insert("chi_err_s2".into(), s / (g * g));
        p.insert("lag_at_peak_torque_deg".into(), (v / g).to_degrees());
        p.insert(
            "lag_at_peak_torque_err_deg".into(),
            (s / g.abs()).to_degrees(),
        );
        if v > 0.0 {
            p.insert("stiffness_over_inertia_s2".into(), g * g / v);
        }
    }
}

/// Drive steps: the constant input angle offset ε of the driven runs from the coefficient −gε
/// of [`Term::DrivenOffset`], and the offset per input turn from [`Term::DrivenOffsetRate`].
fn drive_steps_params(
    get: &dyn Fn(Term) -> Option<(f64, f64)>,
    g: f64,
    p: &mut BTreeMap<String, f64>,
) {
    if let Some((v, s)) = get(Term::DrivenOffset) {
        // coefficient −g ε
        p.insert("offset_deg".into(), (-v / g).to_degrees());
        p.insert("offset_err_deg".into(), (s / g.abs()).to_degrees());
    }
    if let Some((v, s)) = get(Term::DrivenOffsetRate) {
        p.insert("offset_per_turn_deg".into(), (-v / g).to_degrees());
        p.insert("offset_per_turn_err_deg".into(), (s / g.abs()).to_degrees());
    }
}

/// Coupling geometry: the coefficients of cos α cos β and sin α sin β, and the input angle zero
/// offset ε they imply (c_cc = −g sin ε with c_sc = −g cos ε: ε = atan2(−c_cc, g)).
fn coupling_geometry_params(
    get: &dyn Fn(Term) -> Option<(f64, f64)>,
    g: f64,
    p: &mut BTreeMap<String, f64>,
) {
    if let (Some((cc, scc)), Some((ss, sss))) = (get(Term::CosACosB), get(Term::SinASinB)) {
        p.insert("c_cos_alpha_cos_beta".into(), cc);
        p.insert("c_cos_alpha_cos_beta_err".into(), scc);
        p.insert("c_sin_alpha_sin_beta".into(), ss);
        p.insert("c_sin_alpha_sin_beta_err".into(), sss);
        // an input angle zero offset ε gives c_cc = −g sin ε (with c_sc = −g cos ε)
        let eps = (-cc).atan2(g);
        p.insert("alpha_offset_deg".into(), eps.to_degrees());
        p.insert(
            "alpha_offset_err_deg".into(),
            (scc / (g * g + cc * cc).sqrt()).to_degrees(),
        );
    }
}

/// Static friction: the breakaway excess Δη_s (absolute and relative to the base η
/// `base_eta` when positive) and the Stribeck decay's width w and power δ when fitted.
fn static_friction_params(
    get: &dyn Fn(Term) -> Option<(f64, f64)>,
    base_eta: f64,
    p: &mut BTreeMap<String, f64>,
) {
    if let Some((e, s)) = get(Term::StaticExcess) {
        p.insert("eta_static_excess".into(), e);
        p.insert("eta_static_excess_err".into(), s);
        if base_eta > 0.0 {
            p.insert("excess_relative".into(), e / base_eta);
            p.insert("excess_relative_err".into(), s / base_eta);
        }
    }
    if let Some((w, s)) = get(Term::Shape(Shape::StribeckWidth)) {
        p.insert("stribeck_width".into(), w);
        p.insert("stribeck_width_err".into(), s);
    }
    if let Some((d, s)) = get(Term::Shape(Shape::StribeckPower)) {
        p.insert("stribeck_power".into(), d);
        p.insert("stribeck_power_err".into(), s);
    }
}

/// Power-law drag −q (|β̇|/V)^p sgn β̇: q at the reference speed V, the exponent p, and whether
/// the quadratic member (p = 2) is within 2σ.
fn power_law_drag_params(get: &dyn Fn(Term) -> Option<(f64, f64)>, p: &mut BTreeMap<String, f64>) {
    if let (Some((q, s)), Some((pe, pe_err))) =
        (get(Term::Quad), get(Term::Shape(Shape::DragExponent)))
    {
        // −q (|β̇|/V)^p sgn β̇: q is the drag at the reference speed V
        p.insert("q_at_reference_speed".into(), q);
        p.insert("q_at_reference_speed_err".into(), s);
        p.insert("reference_speed".into(), DRAG_REFERENCE_SPEED);
        p.insert("exponent".into(), pe);
        p.insert("exponent_err".into(), pe_err);
        // the quadratic member (p = 2) within 2σ
        p.insert(
            "quadratic_within_2sigma".into(),
            f64::from(u8::from((pe - 2.0).abs() <= 2.0 * pe_err)),
        );
    }
}

/// Load-dependent friction: η_L (whole or radial load; k = η_L/η relative to the base η
/// `base_eta` when positive) and the fitted weight's components (ρ_z, ρ_n) (its size and tilt,
/// which need the covariance, are added in [`super::findings`]).
fn load_friction_params(
    get: &dyn Fn(Term) -> Option<(f64, f64)>,
    base_eta: f64,
    p: &mut BTreeMap<String, f64>,
) {
    let load = get(Term::LoadFric).or(get(Term::RadialLoadFric));
    if let Some((e, s)) = load {
        p.insert("eta_load".into(), e);
        p.insert("eta_load_err".into(), s);
        p.insert(
            "radial".into(),
            f64::from(u8::from(get(Term::RadialLoadFric).is_some())),
        );
        if base_eta > 0.0 {
            p.insert("k".into(), e / base_eta);
            p.insert("k_err".into(), s / base_eta);
        }
    }
    for (shape, key) in [
        (Shape::LoadWeight, "weight_vertical"),
        (Shape::LoadSide, "weight_side"),
    ] {
        if let Some((r, s)) = get(Term::Shape(shape)) {
            p.insert(key.into(), r);
            p.insert(format!("{key}_err"), s);
        }
    }
}

/// Amplitude and phase of each static-torque harmonic present: A sin kβ + B cos kβ =
/// R sin(kβ + φ), R = √(A² + B²), φ = atan2(B, A), with first-order σ. Keys for k = 1:
/// `amplitude`, `phase_deg` (and `a_sin_beta`, `b_cos_beta`); for k ≥ 2: `amplitude_k`,
/// `phase_k_deg`; `harmonics` = the highest k.
fn static_torque_params(get: &dyn Fn(Term) -> Option<(f64, f64)>, p: &mut BTreeMap<String, f64>) {
    let pairs = [
        (1, Term::SinB, Term::CosB),
        (2, Term::Sin(0, 2), Term::Cos(0, 2)),
        (3, Term::Sin(0, 3), Term::Cos(0, 3)),
    ];
    for (k, ts, tc) in pairs {
        let (Some((a, sa)), Some((b, sb))) = (get(ts), get(tc)) else {
            continue;
        };
        let amp = (a * a + b * b).sqrt();
        let err = ((a * sa).powi(2) + (b * sb).powi(2)).sqrt() / amp.max(1e-300);
        let phase_err =
            (((b * sa).powi(2) + (a * sb).powi(2)).sqrt() / (amp * amp).max(1e-300)).to_degrees();
        let suffix = if k == 1 {
            String::new()
        } else {
            format!("_{k}")
        };
        p.insert(format!("amplitude{suffix}"), amp);
        p.insert(format!("amplitude{suffix}_err"), err);
        p.insert(format!("phase{suffix}_deg"), b.atan2(a).to_degrees());
        p.insert(format!("phase{suffix}_err_deg"), phase_err);
        if k == 1 {
            p.insert("a_sin_beta".into(), a);
            p.insert("b_cos_beta".into(), b);
        }
        p.insert("harmonics".into(), k as f64);
    }
}
