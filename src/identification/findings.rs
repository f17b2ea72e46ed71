//! Findings from the judged selection: physical parameters from the refit by simulation, the
//! headline size ([`EffectSize`]) and the numbers of the held-out judgement.

use super::breakaway::SecondMinimum;
use super::catalog::{effect_params, Effect};
use super::judge::{rms_rad, Comparison};
use super::model::{Shape, DRAG_REFERENCE_SPEED};
use super::preprocess::CleanRun;
use super::profile::{delta_chi2, quadratic_sigma, ProfileSide, ShapeProfile};
use super::regression::{DriftParam, Term};
use super::report::{EffectSize, Finding};
use super::select::{ModelState, Tried};
use super::shooting::{SimFit, Win};
use super::spec::free_shapes;
use serde_json::json;
use std::collections::BTreeMap;

/// (value, 1σ) of every term of a refitted model, by term name.
///
/// A family member with its shapes on the weak-form grid (a final model whose refit with the
/// shapes freed failed, [`super::select::polish`]) is entered under the family's coefficient
/// (the Stribeck grid member's excess as [`Term::StaticExcess`]), so that its finding has the
/// coefficient's parameters; its held shapes are not entered (they have no σ: a drag held at a
/// grid exponent reports no exponent, and so no headline, rather than one with σ 0).
pub fn coefficient_map(st: &ModelState) -> BTreeMap<String, (f64, f64)> {
    let n = st.terms.len();
    let (terms, theta) = free_shapes(&st.terms, &st.fit.theta[..n]);
    let mut out = BTreeMap::new();
    let mut k = 0;
    for (t, &v) in terms.iter().zip(&theta) {
        if matches!(t, Term::Shape(_)) && !st.terms.contains(t) {
            continue;
        }
        out.insert(t.name(), (v, st.fit.err[k]));
        k += 1;
    }
    out
}

/// (ζ, η, g) of a refitted model.
pub fn base_values(map: &BTreeMap<String, (f64, f64)>) -> (f64, f64, f64) {
    let v = |t: Term| map.get(&t.name()).map(|x| x.0).unwrap_or(f64::NAN);
    (v(Term::Zeta), v(Term::Eta), -v(Term::SinACosB))
}

/// The headline size of a static torque Σ_k A_k sin(kβ − φ_k): the amplitude A_k of its largest
/// harmonic (`amplitude` for k = 1, `amplitude_k` for k = 2, 3), so that a torque with only a
/// higher harmonic is not headlined by a first harmonic fitted at zero.
fn dominant_harmonic(p: &BTreeMap<String, f64>) -> Option<EffectSize> {
    (1..=3)
        .filter_map(|k| {
            let name = if k == 1 {
                "amplitude".to_string()
            } else {
                format!("amplitude_{k}")
            };
            let value = *p.get(&name)?;
            let sigma = *p.get(&format!("{name}_err"))?;
            Some(EffectSize {
                name,
                value,
                sigma,
                unit: "s^-2".into(),
            })
        })
        .max_by(|a, b| a.value.total_cmp(&b.value))
}

/// The headline size of a finding from its parameters (docs/diagnosis.md, "Sizes").
pub fn headline_size(effect: &Effect, p: &BTreeMap<String, f64>) -> Option<EffectSize> {
    let mk = |name: &str, v: &str, e: &str, unit: &str| -> Option<EffectSize> {
        Some(EffectSize {
            name: name.into(),
            value: *p.get(v)?,
            sigma: *p.get(e)?,
            unit: unit.into(),
        })
    };
    match effect.id {
        "static_torque" => dominant_harmonic(p),
        "power_law_drag" => mk("exponent", "exponent", "exponent_err", "1"),
        "corotating_drag" => mk("c", "c", "c_err", "s^-1"),
        "load_dependent_friction" => {
            mk("fraction", "fraction", "fraction_err", "1").or_else(|| mk("k", "k", "k_err", "1"))
        }
        "sensor_latency" => mk("latency", "tau_s", "tau_err_s", "s"),
        "input_compliance" => mk(
            "lag_at_peak_torque",
            "lag_at_peak_torque_deg",
            "lag_at_peak_torque_err_deg",
            "deg",
        ),
        "coupling_geometry" => {
            // the angle offset that the bilinear terms show more clearly ([`angle_offsets`])
            let input = mk(
                "alpha_offset",
                "alpha_offset_deg",
                "alpha_offset_err_deg",
                "deg",
            );
            let output = mk(
                "beta_offset",
                "beta_offset_deg",
                "beta_offset_err_deg",
                "deg",
            );
            let z = |s: &Option<EffectSize>| s.as_ref().map_or(-1.0, |s| (s.value / s.sigma).abs());
            if z(&output) > z(&input) {
                output
            } else {
                input
            }
        }
        "drive_steps" => mk("offset", "offset_deg", "offset_err_deg", "deg"),
        "static_friction" => mk("excess", "excess_relative", "excess_relative_err", "1"),
        "parameter_drift" | "condition_dependence" => DriftParam::ALL.iter().find_map(|d| {
            let n = d.name();
            mk(
                &format!("{n}_change"),
                &format!("{n}_change"),
                &format!("{n}_change_err"),
                match d {
                    DriftParam::Zeta => "s^-1",
                    DriftParam::Eta | DriftParam::Coupling => "s^-2",
                },
            )
        }),
        "unexplained" => effect
            .terms
            .iter()
            .filter_map(|t| {
                Some((
                    *t,
                    *p.get(&t.name())?,
                    *p.get(&format!("{}_err", t.name()))?,
                ))
            })
            .max_by(|a, b| (a.1 / a.2).abs().total_cmp(&(b.1 / b.2).abs()))
            .map(|(t, v, e)| EffectSize {
                name: t.name(),
                value: v,
                sigma: e,
                // a damping coefficient multiplies β̇; every other term is an acceleration
                unit: match t {
                    Term::VCosB | Term::VSinB | Term::VTrig(..) => "s^-1",
                    _ => "s^-2",
                }
                .into(),
            }),
        _ => None,
    }
}

/// The physical parameters of the accepted `effect` in the refitted model `st`.
pub fn params_of(effect: &Effect, st: &ModelState) -> BTreeMap<String, f64> {
    let map = coefficient_map(st);
    match effect.id {
        "sensor_latency" => {
            let k = st.terms.len();
            [
                ("tau_s".to_string(), st.fit.theta[k]),
                ("tau_err_s".to_string(), st.fit.err[k]),
            ]
            .into_iter()
            .collect()
        }
        "unexplained" => {
            let mut p: BTreeMap<String, f64> = effect
                .terms
                .iter()
                .filter_map(|t| {
                    map.get(&t.name())
                        .map(|v| [(t.name(), v.0), (format!("{}_err", t.name()), v.1)])
                })
                .flatten()
                .collect();
            if let Some([(a, sa), (phi, sphi)]) =
                effect.terms.first().and_then(|&t| quadrature(st, t))
            {
                p.insert("harmonic_amplitude".into(), a);
                p.insert("harmonic_amplitude_err".into(), sa);
                p.insert("harmonic_phase_deg".into(), phi.to_degrees());
                p.insert("harmonic_phase_err_deg".into(), sphi.to_degrees());
            }
            p
        }
        "power_law_drag" => {
            let mut p = effect_params(effect, &map, base_values(&map));
            if let Some((q, e)) = drag_coefficient(st) {
                p.insert("q".into(), q);
                p.insert("q_err".into(), e);
            }
            p
        }
        "load_dependent_friction" => {
            let mut p = effect_params(effect, &map, base_values(&map));
            if let Some((l, e)) = load_fraction(st) {
                p.insert("fraction".into(), l);
                p.insert("fraction_err".into(), e);
            }
            if let Some(w) = load_weight(st) {
                p.insert("weight_over_force".into(), w.size.0);
                p.insert("weight_over_force_err".into(), w.size.1);
                if let Some((psi, s_psi)) = w.tilt_deg {
                    p.insert("tilt_deg".into(), psi);
                    p.insert("tilt_deg_err".into(), s_psi);
                }
            }
            p
        }
        "coupling_geometry" => {
            let mut p = effect_params(effect, &map, base_values(&map));
            if let Some([a, b]) = angle_offsets(st) {
                for (name, (v, e)) in [("alpha_offset", a), ("beta_offset", b)] {
                    p.insert(format!("{name}_deg"), v.to_degrees());
                    p.insert(format!("{name}_err_deg"), e.to_degrees());
                }
            }
            p
        }
        _ => effect_params(effect, &map, base_values(&map)),
    }
}

/// The coupling's bilinear terms read as zero offsets of the two angle readings, each (value,
/// 1σ) in radians. The input magnet at α + ε_α gives c_cc = −g sin ε_α, c_ss = −gΔ sin ε_α
/// (and c_sc = −g cos ε_α, c_cs = gΔ cos ε_α); β recorded ε_β above the output magnet's angle
/// gives c_cc = −gΔ sin ε_β, c_ss = −g sin ε_β. With g = −c_sc and Δ = c_cs/g both are solved
/// from the linear system: tan ε_α = −(c_cc − Δ c_ss)/(g(1 − Δ²)), tan ε_β = −(c_ss −
/// Δ c_cc)/(g(1 − Δ²)), exact for either offset alone, first order for both together. The σ
/// by first-order propagation through the refit's covariance of (c_sc, c_cs, c_cc, c_ss).
/// `None` without the four terms or when |Δ| > 0.95: the coupling then depends nearly on α − β
/// alone, and the two offsets are one (the catalog's `alpha_offset_deg` from c_cc alone).
pub fn angle_offsets(st: &ModelState) -> Option<[(f64, f64); 2]> {
    let at = |t: Term| st.terms.iter().position(|&x| x == t);
    let idx = [
        at(Term::SinACosB)?,
        at(Term::CosASinB)?,
        at(Term::CosACosB)?,
        at(Term::SinASinB)?,
    ];
    let offsets = |c: [f64; 4]| {
        let g = -c[0];
        let delta = c[1] / g;
        let den = g * (1.0 - delta * delta);
        [
            (-(c[2] - delta * c[3]) / den).atan(),
            (-(c[3] - delta * c[2]) / den).atan(),
        ]
    };
    let c = idx.map(|i| st.fit.theta[i]);
    let delta = c[1] / -c[0];
    if !c.iter().all(|x| x.is_finite()) || delta.is_nan() || delta.abs() > 0.95 {
        return None;
    }
    let value = offsets(c);
    Some([0, 1].map(|j| {
        let grad: Vec<(usize, f64)> = (0..4)
            .map(|i| {
                let h = 1e-6 * c[i].abs().max(1.0);
                let (mut up, mut down) = (c, c);
                up[i] += h;
                down[i] -= h;
                (idx[i], (offsets(up)[j] - offsets(down)[j]) / (2.0 * h))
            })
            .collect();
        first_order(st, value[j], &grad)
    }))
}

/// The cosine and sine members of a dictionary term's angle harmonic X (torque, viscous or dry
/// friction modulated by cos/sin X), `None` for a term without a partner.
fn harmonic_pair(t: Term) -> Option<[Term; 2]> {
    match t {
        Term::Cos(k, l) | Term::Sin(k, l) => Some([Term::Cos(k, l), Term::Sin(k, l)]),
        Term::VTrig(k, l, _) => Some([Term::VTrig(k, l, false), Term::VTrig(k, l, true)]),
        Term::STrig(k, l, _) => Some([Term::STrig(k, l, false), Term::STrig(k, l, true)]),
        Term::VCosB | Term::VSinB => Some([Term::VCosB, Term::VSinB]),
        Term::SCosB | Term::SSinB => Some([Term::SCosB, Term::SSinB]),
        _ => None,
    }
}

/// An `unexplained` term and its quadrature partner (the sine of the same harmonic X for a
/// cosine, and back) both in the final model `st`, read as one harmonic with a phase:
/// c cos X + s sin X = A cos(X − φ), A = √(c² + s²), φ = atan2(s, c) (rad), each (value, 1σ) by
/// first-order propagation through the refit's covariance. A friction modulated by cos(β − 0.5)
/// is found as two terms, cos β and sin β: this is the one physical modulation they are.
/// `None` without the partner in the model.
pub fn quadrature(st: &ModelState, t: Term) -> Option<[(f64, f64); 2]> {
    let [tc, ts] = harmonic_pair(t)?;
    let at = |t: Term| st.terms.iter().position(|&x| x == t);
    let (ic, is) = (at(tc)?, at(ts)?);
    let (c, s) = (st.fit.theta[ic], st.fit.theta[is]);
    let a = c.hypot(s);
    if !(a.is_finite() && a > 0.0) {
        return None;
    }
    Some([
        first_order(st, a, &[(ic, c / a), (is, s / a)]),
        first_order(st, s.atan2(c), &[(ic, -s / (a * a)), (is, c / (a * a))]),
    ])
}

/// A function of θ entries with its 1σ by first-order propagation through the refit's
/// covariance: `grad` lists (θ index, ∂f/∂θ_index).
fn first_order(st: &ModelState, value: f64, grad: &[(usize, f64)]) -> (f64, f64) {
    let mut var = 0.0;
    for &(a, ga) in grad {
        for &(b, gb) in grad {
            var += ga * gb * st.fit.cov[(a, b)];
        }
    }
    (value, var.max(0.0).sqrt())
}

/// The drag family's coefficient in SI form, q_SI = q V^(−p) of −q_SI |β̇|^p sgn β̇
/// (rad^(1−p) s^(p−2); rad⁻¹ for p = 2), with its 1σ from the refit's covariance (first order).
pub fn drag_coefficient(st: &ModelState) -> Option<(f64, f64)> {
    let at = |t: Term| st.terms.iter().position(|&x| x == t);
    let (iq, ip) = (at(Term::Quad)?, at(Term::Shape(Shape::DragExponent))?);
    let (q, p) = (st.fit.theta[iq], st.fit.theta[ip]);
    let v = DRAG_REFERENCE_SPEED;
    let qs = q * v.powf(-p);
    Some(first_order(st, qs, &[(iq, v.powf(-p)), (ip, -qs * v.ln())]))
}

/// The θ indices of the load family's weight components (ρ_z, ρ_n) and their values (the
/// family carries both shapes: catalog.rs, `spec::free_shapes`).
fn weight_components(st: &ModelState) -> Option<([usize; 2], [f64; 2])> {
    let at = |t: Term| st.terms.iter().position(|&x| x == t);
    let k = [
        at(Term::Shape(Shape::LoadWeight))?,
        at(Term::Shape(Shape::LoadSide))?,
    ];
    Some((k, k.map(|i| st.fit.theta[i])))
}

/// The load family's weight: its size and direction, each as (value, 1σ).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoadWeight {
    /// ρ = |W|/F₀.
    pub size: (f64, f64),
    /// The tilt ψ of the set-up about the output shaft, degrees (`None` when ρ = 0).
    pub tilt_deg: Option<(f64, f64)>,
}

/// The load family's weight W = −ρ_z ẑ − ρ_n n̂ (catalog.rs, `load_dependent_friction`) as its
/// size ρ = |W|/F₀ = √(ρ_z² + ρ_n²) and its direction, the tilt ψ = atan2(ρ_n, ρ_z) of the
/// set-up about the output shaft, each with its 1σ from the refit's covariance (first order).
/// ψ is reported as fitted, in (−180°, 180°]: ψ and 180° − ψ load the bearings alike at states
/// mirrored by the gear's symmetry (α, β) → (−α, −β), so on recordings that sample both a fit
/// may land on either.
pub fn load_weight(st: &ModelState) -> Option<LoadWeight> {
    let ([iz, i_n], [z, n]) = weight_components(st)?;
    let rho = z.hypot(n);
    if !rho.is_finite() {
        return None;
    }
    if rho == 0.0 {
        // no direction at zero weight: the size's σ from both components' variances
        let var = st.fit.err[iz].powi(2) + st.fit.err[i_n].powi(2);
        return Some(LoadWeight {
            size: (0.0, var.sqrt()),
            tilt_deg: None,
        });
    }
    let r2 = rho * rho;
    let (psi, s_psi) = first_order(st, n.atan2(z), &[(iz, -n / r2), (i_n, z / r2)]);
    Some(LoadWeight {
        size: first_order(st, rho, &[(iz, z / rho), (i_n, n / rho)]),
        tilt_deg: Some((psi.to_degrees(), s_psi.to_degrees())),
    })
}

/// The load-dependent fraction λ = η_L ρ / (η + η_L ρ) of the friction η + η_L L, ρ = |W|/F₀
/// (catalog.rs, `load_dependent_friction`) with its 1σ from the refit's covariance (first
/// order).
pub fn load_fraction(st: &ModelState) -> Option<(f64, f64)> {
    let at = |t: Term| st.terms.iter().position(|&x| x == t);
    let i_eta = at(Term::Eta)?;
    let i_load = at(Term::LoadFric).or(at(Term::RadialLoadFric))?;
    let ([iz, i_n], [z, side]) = weight_components(st)?;
    let (eta, el) = (st.fit.theta[i_eta], st.fit.theta[i_load]);
    let rho = z.hypot(side);
    let n = el * rho;
    let d = eta + n;
    if !(rho > 0.0 && d > 0.0) {
        return None;
    }
    // ∂λ/∂ρ, carried to the components by ∂ρ/∂ρ_z = ρ_z/ρ, ∂ρ/∂ρ_n = ρ_n/ρ
    let dl_drho = el * eta / (d * d);
    let grad = [
        (i_eta, -n / (d * d)),
        (i_load, rho * eta / (d * d)),
        (iz, dl_drho * z / rho),
        (i_n, dl_drho * side / rho),
    ];
    Some(first_order(st, n / d, &grad))
}

/// The headline `size` of `effect` in the final model `fin` with its σ taken from the profiles of
/// the effect's shape parameters ([`super::profile`]): the headline evaluated at θ of each end of
/// each profile's 1σ interval (the other parameters refitted there), and σ the largest distance of
/// these from the headline, when larger than the covariance's σ (a symmetric σ that covers the
/// skewed side; the interval itself goes to `params` as `size_profile_lo`/`size_profile_hi`, with
/// each shape's interval as `<shape>_profile_lo`/`_hi` and `_open_lo`/`_open_hi` = 1 where it
/// reaches the end of the shape's range, and the covariance's σ as `size_sigma_covariance`).
pub fn profiled_size(
    effect: &Effect,
    fin: &ModelState,
    profiles: &[ShapeProfile],
    size: Option<EffectSize>,
    params: &mut BTreeMap<String, f64>,
) -> Option<EffectSize> {
    let mut size = size?;
    let mine: Vec<&ShapeProfile> = profiles
        .iter()
        .filter(|p| effect.terms.contains(&Term::Shape(p.shape)))
        .collect();
    if mine.is_empty() {
        return Some(size);
    }
    let (mut lo, mut hi) = (size.value, size.value);
    for p in &mine {
        let n = p.shape.name();
        params.insert(format!("{n}_profile_lo"), p.interval.0);
        params.insert(format!("{n}_profile_hi"), p.interval.1);
        params.insert(
            format!("{n}_profile_open_lo"),
            f64::from(u8::from(p.open.0)),
        );
        params.insert(
            format!("{n}_profile_open_hi"),
            f64::from(u8::from(p.open.1)),
        );
        for th in &p.ends {
            if th.len() != fin.fit.theta.len() {
                continue;
            }
            let at = ModelState {
                fit: SimFit {
                    theta: th.clone(),
                    ..fin.fit.clone()
                },
                ..fin.clone()
            };
            if let Some(h) = headline_size(effect, &params_of(effect, &at)) {
                if h.value.is_finite() {
                    lo = lo.min(h.value);
                    hi = hi.max(h.value);
                }
            }
        }
    }
    params.insert("size_profile_lo".into(), lo);
    params.insert("size_profile_hi".into(), hi);
    params.insert("size_sigma_covariance".into(), size.sigma);
    size.sigma = size.sigma.max(size.value - lo).max(hi - size.value);
    Some(size)
}

/// The headline `size` of the Stribeck member (the relative excess η_Δs/η of the
/// `static_friction` family) with its σ widened to the profile σ of its excess, the larger of the
/// two sides of [`super::select::excess_profile`] (`sides`: lower, upper; a symmetric σ that covers
/// the flatter side), scaled from η_Δs to the headline by the fitted η (`params`'
/// `excess_relative`/`eta_static_excess`). `params` get each side's σ (headline units) as
/// `size_profile_sigma_lo`/`_hi`, `size_profile_beyond_lo`/`_hi` = 1 where that side's σ
/// extrapolates beyond its last point, and the covariance's σ as `size_sigma_covariance`;
/// `evidence` the profile's points (η_Δs, rise) and Δ as `excess_profile`.
pub fn excess_profile_size(
    sides: &(ProfileSide, ProfileSide),
    size: Option<EffectSize>,
    params: &mut BTreeMap<String, f64>,
    evidence: &mut BTreeMap<String, serde_json::Value>,
) -> Option<EffectSize> {
    evidence.insert(
        "excess_profile".into(),
        json!({
            "delta_chi2": sides.0.delta,
            "points_excess_rise": sides.0.points.iter().rev().chain(&sides.1.points).collect::<Vec<_>>(),
        }),
    );
    let mut size = size?;
    let (Some(&rel), Some(&abs)) = (
        params.get("excess_relative"),
        params.get("eta_static_excess"),
    ) else {
        return Some(size);
    };
    if !(abs != 0.0 && (rel / abs).is_finite()) {
        return Some(size);
    }
    let scale = (rel / abs).abs();
    let (lo, hi) = (sides.0.sigma * scale, sides.1.sigma * scale);
    params.insert("size_profile_sigma_lo".into(), lo);
    params.insert("size_profile_sigma_hi".into(), hi);
    params.insert(
        "size_profile_beyond_lo".into(),
        f64::from(u8::from(sides.0.beyond)),
    );
    params.insert(
        "size_profile_beyond_hi".into(),
        f64::from(u8::from(sides.1.beyond)),
    );
    // the covariance's σ (already entered when a shape profile widened the size first)
    params
        .entry("size_sigma_covariance".into())
        .or_insert(size.sigma);
    if lo.is_finite() && hi.is_finite() {
        size.sigma = size.sigma.max(lo).max(hi);
    }
    Some(size)
}

/// The headline `size` of the Stribeck member (`effect`, the `static_friction` family with its
/// coefficient [`Term::StaticExcess`]) in the final model `fin` with its σ widened by a second
/// minimum of the windows' χ² (`second`: the other final refit, its χ² on the windows `fin`'s
/// refit used a rise r above `fin`'s). Under a quadratic profile of the headline s,
/// χ²_P(s) = χ²_min + Δ (s − ŝ)²/σ², with Δ the rise at one σ ([`delta_chi2`] of η_Δs; the
/// headline η_Δs/η is η_Δs scaled by the fitted η, and Δ does not change under scaling), a refit
/// at s₂ shows χ²_P(s₂) − χ²_min ≤ r (a profile minimises over the other parameters), so
/// σ ≥ |s₂ − ŝ| √(Δ/r). The bound is capped at |s₂ − ŝ| so that a flat valley (r → 0) does not
/// give an unbounded σ. This assumes `fin` is at the minimum of its χ²; where it is not (its
/// refit stopped along the valley), r is the smaller and the bound the larger. The second
/// minimum's headline and rise go to `params` as `size_second_minimum` and
/// `size_second_minimum_chi2_rise`, the σ before as `size_sigma_one_minimum`; the size is
/// returned unchanged when the second refit has no headline or the rise is not finite.
pub fn second_minimum_size(
    effect: &Effect,
    fin: &ModelState,
    second: &SecondMinimum,
    size: Option<EffectSize>,
    params: &mut BTreeMap<String, f64>,
) -> Option<EffectSize> {
    let mut size = size?;
    let Some(other) = headline_size(effect, &params_of(effect, &second.state)) else {
        return Some(size);
    };
    let Some(k) = fin.terms.iter().position(|t| *t == Term::StaticExcess) else {
        return Some(size);
    };
    if !(other.value.is_finite() && size.value.is_finite() && second.rise.is_finite()) {
        return Some(size);
    }
    let bound = second_minimum_sigma(
        (other.value - size.value).abs(),
        delta_chi2(&fin.fit, k),
        second.rise,
    );
    params.insert("size_second_minimum".into(), other.value);
    params.insert("size_second_minimum_chi2_rise".into(), second.rise);
    params.insert("size_sigma_one_minimum".into(), size.sigma);
    size.sigma = size.sigma.max(bound);
    Some(size)
}

/// The smallest σ of a quadratic profile χ²_P(s) = χ²_min + Δ (s − ŝ)²/σ² that lets a second
/// refit at distance `dist` = |s₂ − ŝ| lie `rise` = r above the minimum: |s₂ − ŝ| √(Δ/r)
/// ([`quadratic_sigma`]), capped at |s₂ − ŝ| (see [`second_minimum_size`]).
pub fn second_minimum_sigma(dist: f64, delta: f64, rise: f64) -> f64 {
    quadratic_sigma(dist, delta, rise).min(dist)
}

/// The judgement's numbers as evidence.
pub fn judgement_evidence(
    t: &Tried,
    cmp: &Comparison,
    folds: usize,
) -> BTreeMap<String, serde_json::Value> {
    let mut ev = BTreeMap::new();
    ev.insert("round".into(), json!(t.round));
    ev.insert("heldout_z".into(), json!(cmp.z));
    ev.insert("heldout_z_cluster_by_run".into(), json!(cmp.z_cluster));
    ev.insert("heldout_z_chi2".into(), json!(cmp.z_chi2));
    ev.insert("z_threshold".into(), json!(t.z_crit));
    ev.insert("added_parameters_z".into(), json!(t.added_z));
    ev.insert("heldout_chi2_gain".into(), json!(cmp.gain));
    ev.insert("windows".into(), json!(cmp.windows));
    ev.insert("runs".into(), json!(cmp.runs));
    ev.insert("windows_failed_before".into(), json!(cmp.failed_before));
    ev.insert("windows_failed_after".into(), json!(cmp.failed_after));
    ev.insert("folds".into(), json!(folds));
    ev.insert("delta_bic_weak_form".into(), json!(t.candidate.weak_dbic));
    ev.insert(
        "terms".into(),
        json!(t
            .candidate
            .terms
            .iter()
            .map(|x| x.name())
            .collect::<Vec<_>>()),
    );
    ev
}

/// The experiment that tells an `unexplained` term's possible causes apart.
pub fn dictionary_experiment(t: Term) -> &'static str {
    match t {
        Term::STrig(0, _, _) | Term::SCosB | Term::SSinB => {
            "dry friction that depends on the output angle: record small-amplitude ring-downs around equilibria spread over a turn of β (step α0 over a full turn); the linear decrement per swing follows the modulation in β (a bent shaft or an eccentric bearing load)"
        }
        Term::STrig(..) => {
            "dry friction that depends on the input angle: ring-downs at many α0 over a turn; the dry-friction decrement changes with α0 (bearing load from the input side, e.g. a force on the output shaft that turns with the input)"
        }
        Term::Cos(0, 0) => {
            "a constant torque on the output, or a dry friction that differs by the direction of motion (η₊ − η₋ = −2 × const: the same force): spin the output by hand without the input magnet, both ways; the decelerations differ by 2 × const in either case, and a torque that stays when the bearing is turned end for end or exchanged is a bias (air draught, cable), not the bearing"
        }
        Term::Cos(0, _) | Term::Sin(0, _) => {
            "a torque that depends on the output angle only: ring-downs of the output with the input magnet removed; the remaining torque and its harmonics are lab-fixed"
        }
        Term::Cos(..) | Term::Sin(..) => {
            "a coupling harmonic: ring-downs at finely stepped α0 over a full turn; κ(α0) and the equilibrium β0(α0) show the harmonic (dipole shape or position of the magnets)"
        }
        Term::VCosB | Term::VSinB | Term::VTrig(0, _, _) => {
            "damping that depends on the output angle: ring-downs from large amplitudes at several α0; the viscous decay rate varies with the angle range swept"
        }
        Term::VTrig(..) => {
            "damping that depends on the input angle or on the magnets' relative angle (eddy currents in conductors near the magnets): ring-downs at many α0 over a turn; the viscous decay rate changes with α0, and with a conductor moved away it does not"
        }
        _ => "",
    }
}

/// The finding of the accepted candidate `t`, judged against `before`.
pub fn judged_finding(
    t: &Tried,
    before: &ModelState,
    wins: &[Win],
    runs: &[CleanRun],
    folds: usize,
    rivals: &[String],
    fin: &ModelState,
) -> Option<Finding> {
    let st = t.state.as_ref()?;
    let cmp = t.cmp?;
    let e = &t.candidate.effect;
    // parameters from the final model refitted to convergence (it holds every accepted effect)
    let params = params_of(e, fin);
    let mut ev = judgement_evidence(t, &cmp, folds);
    if let Some(first) = t.on_top_of {
        ev.insert(
            "accepted_together_with".into(),
            json!({"effect": first, "note": "a close rival of it in the round, significant on \
                   top of it and it on top of this one: judged on top of the model with it \
                   (fits.selection_joints)"}),
        );
    }
    ev.insert(
        "simulation_refit".into(),
        json!({"windows": st.fit.used.len(), "samples": st.fit.samples,
               "rms_start_rad": st.fit.rms_start_rad, "rms_rad": st.fit.rms_rad,
               "converged": st.fit.converged, "inflation": st.fit.inflation}),
    );
    // the refit the reported parameters and their σ come from: a σ of an unconverged fit is not
    // the σ of a minimum
    ev.insert(
        "final_refit".into(),
        json!({"windows": fin.fit.used.len(), "rms_rad": fin.fit.rms_rad,
               "converged": fin.fit.converged}),
    );
    let size = headline_size(e, &params);
    let (candidates, experiment) = if e.id == "unexplained" {
        (
            rivals
                .iter()
                .map(|r| r.to_string())
                .collect::<Vec<String>>(),
            e.terms
                .iter()
                .map(|&t| dictionary_experiment(t))
                .collect::<Vec<_>>()
                .join("; "),
        )
    } else {
        (
            e.candidates.iter().map(|s| s.to_string()).collect(),
            e.discriminating_experiment.to_string(),
        )
    };
    if !rivals.is_empty() {
        ev.insert("significant_rivals".into(), json!(rivals));
    }
    Some(Finding {
        effect: e.id.to_string(),
        class: e.class.to_string(),
        explanation: e.explanation.to_string(),
        params,
        candidates,
        discriminating_experiment: experiment,
        rms_before_rad: Some(rms_rad(&before.held.chi2_fit, wins, runs)),
        rms_after_rad: Some(rms_rad(&st.held.chi2_fit, wins, runs)),
        heldout_rms_before_rad: Some(cmp.rms_before),
        heldout_rms_after_rad: Some(cmp.rms_after),
        evidence: ev,
        size,
        standing: None,
    })
}

/// The other candidates of the round of `t` judged on the same model that were significant too
/// (they explain part of the same mismatch), as "effect (terms): z, gain"; also those significant
/// on the screening's windows that the screening's leader predicted significantly better there
/// (not refitted on all windows, [`super::select::judge_round`]), with their screening numbers.
/// Not rivals: the family's other members (the judge chose among them) and the members of an
/// effect accepted in the same round (close rivals accepted together, [`super::beam`]).
pub fn rivals(t: &Tried, tried: &[Tried]) -> Vec<String> {
    let same_round = |o: &&Tried| o.round == t.round;
    let accepted_ids: Vec<&str> = tried
        .iter()
        .filter(same_round)
        .filter(|o| o.accepted || o.joined)
        .map(|o| o.candidate.effect.id)
        .collect();
    tried
        .iter()
        .filter(same_round)
        .filter(|o| o.on_top_of == t.on_top_of && !o.accepted)
        .filter(|o| o.candidate.effect.id != t.candidate.effect.id)
        .filter(|o| !accepted_ids.contains(&o.candidate.effect.id))
        .filter_map(|o| {
            let name = format!(
                "{} ({})",
                o.candidate.effect.id,
                o.candidate
                    .terms
                    .iter()
                    .map(|x| x.name())
                    .collect::<Vec<_>>()
                    .join(", ")
            );
            match (o.cmp, o.screen, &o.screen_beaten) {
                (Some(c), ..) => c
                    .improves(o.z_crit)
                    .then(|| format!("{name}: held-out z = {:.1}, χ² gain {:.0}", c.z, c.gain)),
                (None, Some(s), Some(b)) => s.improves(o.z_crit).then(|| {
                    format!(
                        "{name}: screening (half the windows) held-out z = {:.1}, χ² gain {:.0}; \
                         {} predicts them better at z = {:.1}",
                        s.z, s.gain, b.label, b.cmp.z
                    )
                }),
                _ => None,
            }
        })
        .collect()
}

/// Whether the dictionary term `t` (held-out gain `gain`) gained more than the candidate accepted
/// in its round, a catalog effect ([`super::select`]'s choice between the two).
fn gave_way(t: &Tried, gain: f64, tried: &[Tried]) -> bool {
    t.candidate.effect.id == "unexplained"
        && tried.iter().any(|o| {
            o.round == t.round
                && o.on_top_of == t.on_top_of
                && o.accepted
                && o.candidate.effect.id != "unexplained"
                && o.cmp.is_some_and(|c| c.gain < gain)
        })
}

/// The rejected candidates with their numbers (for `fits.rejected_candidates`).
pub fn rejected(tried: &[Tried]) -> Vec<serde_json::Value> {
    tried
        .iter()
        .filter(|t| !t.accepted)
        .map(|t| {
            let c = &t.candidate;
            let member_reason = smaller_member_reason(t);
            json!({
                "round": t.round,
                "effect": c.effect.id,
                "terms": c.terms.iter().map(|x| x.name()).collect::<Vec<_>>(),
                "latency_start_s": c.latency.map(|l| l.0),
                "delta_bic_weak_form": c.weak_dbic,
                "heldout_z": t.cmp.map(|m| m.z),
                "heldout_z_cluster_by_run": t.cmp.map(|m| m.z_cluster),
                "heldout_z_chi2": t.cmp.map(|m| m.z_chi2),
                "screening_z": t.screen.map(|m| m.z),
                "screening_in_sample_z": t.screen_fit.map(|m| m.z),
                "screening_in_sample_chi2_gain": t.screen_fit.map(|m| m.gain),
                "screening_beaten_by": t.screen_beaten.as_ref().map(|b| b.label.clone()),
                "screening_beaten_z": t.screen_beaten.as_ref().map(|b| b.cmp.z),
                "z_threshold": t.z_crit,
                "heldout_chi2_gain": t.cmp.map(|m| m.gain),
                "heldout_rms_before_rad": t.cmp.map(|m| m.rms_before),
                "heldout_rms_after_rad": t.cmp.map(|m| m.rms_after),
                "windows_failed": t.cmp.map(|m| m.failed_after),
                "member_z_against_smaller": t.member.map(|c| c.z),
                "added_parameters_z": t.added_z,
                "dropped_wald_z": t.dropped.map(|d| d.wald_z),
                "dropped_heldout_z": t.dropped.map(|d| d.heldout_z),
                "reason": if let Some(d) = t.dropped { format!(
                    "accepted in its round, dropped by the backward check: in the final model its \
                     parameters are consistent with zero (Wald z = {:.2} < {:.2}) and the model \
                     without it predicts the held-out windows as well (z = {:.2} < {:.2})",
                    d.wald_z, t.z_crit, d.heldout_z, t.z_crit) } else { match t.cmp {
                    None => match (t.screen, t.screen_fit, &t.screen_beaten) {
                        (Some(s), _, Some(b)) => format!(
                            "screening (half the windows): held-out z = {:.2}, but {} predicts \
                             them significantly better (z = {:.2} ≥ {:.2}, χ² gain {:.1}); not \
                             refitted on all windows",
                            s.z, b.label, b.cmp.z, t.z_crit, b.cmp.gain
                        ),
                        (Some(s), _, None) => format!(
                            "screening (half the windows): held-out z = {:.2} < {}",
                            s.z,
                            super::select::SCREEN_Z
                        ),
                        (None, Some(f), _) => format!(
                            "screening (half the windows): its refit fits them significantly \
                             worse than the current model, which it nests (in-sample z = {:.2}, \
                             χ² gain {:.1}): a refit that ran away; not predicted held out",
                            f.z, f.gain
                        ),
                        (None, None, _) => "the refit by simulation failed".to_string(),
                    },
                    Some(m) if m.z < t.z_crit => format!(
                        "held-out improvement not significant (z = {:.2} < {:.2})", m.z, t.z_crit),
                    Some(m) if !m.improves(t.z_crit) => format!(
                        "most held-out windows improve (z = {:.2}), but the summed held-out χ² is \
                         worse (gain {:.1})", m.z, m.gain),
                    Some(m) if t.added_z.is_some_and(|z| z < t.z_crit) => format!(
                        "held-out gain (z = {:.2}) with added parameters consistent with zero \
                         (Wald z = {:.2} < {:.2})", m.z, t.added_z.unwrap_or(0.0), t.z_crit),
                    Some(_) if member_reason.is_some() => member_reason.unwrap_or_default(),
                    Some(_) if t.joined => "a close rival of the accepted candidate, significant \
                        on top of it and it on top of this one: accepted with it in the same round \
                        as refitted on top of it (fits.selection_joints)"
                        .to_string(),
                    Some(_) if t.forked => "a close rival of the accepted candidate: accepted on \
                        the other branch of the fork of its round, the branch that was left \
                        (fits.selection_forks)"
                        .to_string(),
                    Some(m) if gave_way(t, m.gain, tried) => "significant and gained more, but a \
                        dictionary term gives way to a catalog effect of the round that it does not \
                        predict significantly better than (the accepted one)"
                        .to_string(),
                    Some(_) => "significant, but another candidate of the round gained more"
                        .to_string(),
                } },
            })
        })
        .collect()
}

/// The reason a significant member of a nested family was rejected when the smaller member
/// chosen before it predicts as well: its comparison against that member does not improve on it
/// ([`super::judge::Comparison::improves`]: z below the threshold, or a worse summed χ²).
fn smaller_member_reason(t: &Tried) -> Option<String> {
    let c = t.member.filter(|c| !c.improves(t.z_crit))?;
    Some(format!(
        "a smaller member of the family predicts as well (held-out z of this member against it \
         {:.2}, threshold {:.2}; summed held-out χ² gain {:.1})",
        c.z, t.z_crit, c.gain
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::TAU;

    #[test]
    fn a_torque_with_only_a_third_harmonic_is_headlined_by_it() {
        let p: BTreeMap<String, f64> = [
            ("amplitude", 0.05),
            ("amplitude_err", 0.05),
            ("amplitude_2", 0.08),
            ("amplitude_2_err", 0.06),
            ("amplitude_3", 3.0),
            ("amplitude_3_err", 0.07),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect();
        let s = dominant_harmonic(&p).unwrap();
        assert_eq!(
            (s.name.as_str(), s.value, s.sigma),
            ("amplitude_3", 3.0, 0.07)
        );
        let first: BTreeMap<String, f64> = [("amplitude", 12.0), ("amplitude_err", 0.2)]
            .into_iter()
            .map(|(k, v)| (k.to_string(), v))
            .collect();
        assert_eq!(dominant_harmonic(&first).unwrap().name, "amplitude");
    }

    /// A second refit on an exact quadratic profile gives back the profile's σ, wherever it lies
    /// beyond the 1σ region; inside it, the distance.
    #[test]
    fn a_second_minimum_on_a_quadratic_profile_gives_its_sigma() {
        let (sigma, delta) = (0.07, 2.3);
        for n in [1.5, 2.0, 3.0, 7.0] {
            let rise = delta * n * n;
            let got = second_minimum_sigma(n * sigma, delta, rise);
            assert!((got - sigma).abs() < 1e-15 * sigma.max(1.0), "{n}: {got}");
        }
        assert_eq!(second_minimum_sigma(0.05, delta, 0.5 * delta), 0.05);
        assert_eq!(second_minimum_sigma(0.05, delta, 0.0), 0.05);
    }

    /// A final model whose Stribeck member kept its shapes on the grid (its free refit failed)
    /// reports the family's coefficient: the excess relative to η with its σ and a headline
    /// size, and no held shape (they have no σ).
    #[test]
    fn a_grid_member_reports_the_family_parameters() {
        let terms = vec![
            Term::Zeta,
            Term::Eta,
            Term::SinACosB,
            Term::CosASinB,
            Term::StribeckGrid(50, 10),
        ];
        let theta = vec![1.25, 20.0, -287.0, 66.0, 11.5];
        let err = vec![0.01, 0.12, 0.17, 0.10, 0.43];
        let n = terms.len();
        let st = state(terms, theta, err, nalgebra::DMatrix::zeros(n, n));
        let e = super::super::catalog::catalog()
            .into_iter()
            .find(|e| e.id == "static_friction")
            .unwrap();
        let p = params_of(&e, &st);
        assert_eq!(p["eta_static_excess"], 11.5);
        assert_eq!(p["excess_relative"], 11.5 / 20.0);
        assert_eq!(p["excess_relative_err"], 0.43 / 20.0);
        assert!(!p.contains_key("stribeck_width") && !p.contains_key("stribeck_power"));
        let size = headline_size(&e, &p).unwrap();
        assert_eq!((size.value, size.sigma), (11.5 / 20.0, 0.43 / 20.0));
    }

    /// A final model with θ, its σ and covariance (no residuals or windows).
    fn state(
        terms: Vec<Term>,
        theta: Vec<f64>,
        err: Vec<f64>,
        cov: nalgebra::DMatrix<f64>,
    ) -> ModelState {
        ModelState {
            terms,
            fit_latency: false,
            fit: SimFit::with_covariance(theta, err, cov),
            held: super::super::judge::HeldOut {
                chi2: Vec::new(),
                chi2_fit: Vec::new(),
            },
            effects: Vec::new(),
        }
    }

    /// The coupling's four bilinear coefficients of −g sin(α + a) cos(β − b) + gΔ cos(α + a)
    /// sin(β − b), projected numerically on the basis (sin α cos β, cos α sin β, cos α cos β,
    /// sin α sin β) by quadrature over the torus (independent of the algebra under test).
    fn projected_coupling(g: f64, delta: f64, a: f64, b: f64) -> [f64; 4] {
        let n = 64;
        let mut c = [0.0; 4];
        for i in 0..n {
            for j in 0..n {
                let (al, be) = (TAU * i as f64 / n as f64, TAU * j as f64 / n as f64);
                let f = -g * (al + a).sin() * (be - b).cos()
                    + g * delta * (al + a).cos() * (be - b).sin();
                let basis = [
                    al.sin() * be.cos(),
                    al.cos() * be.sin(),
                    al.cos() * be.cos(),
                    al.sin() * be.sin(),
                ];
                for k in 0..4 {
                    // each basis function has mean square 1/4 over the torus
                    c[k] += 4.0 * f * basis[k] / (n * n) as f64;
                }
            }
        }
        c
    }

    /// Two dictionary terms of one harmonic in a final model, −sgn β̇ (c cos β + s sin β), are
    /// read as one modulation A cos(β − φ): A = √(c² + s²), φ = atan2(s, c), with σ through the
    /// covariance, checked against central differences of A and φ and the covariance's
    /// quadratic form; a term without its partner in the model has none.
    #[test]
    fn a_cosine_and_sine_pair_is_one_harmonic_with_a_phase() {
        let (c, s) = (6.27, 3.42);
        let cov = nalgebra::DMatrix::from_row_slice(2, 2, &[0.0044, 0.0009, 0.0009, 0.0017]);
        let st = state(
            vec![Term::SCosB, Term::SSinB],
            vec![c, s],
            vec![0.0044f64.sqrt(), 0.0017f64.sqrt()],
            cov.clone(),
        );
        let [(a, sa), (phi, sphi)] = quadrature(&st, Term::SSinB).unwrap();
        assert!((a - (c * c + s * s).sqrt()).abs() < 1e-12);
        // A cos(β − φ) is the pair at every β
        for b in [0.0, 1.0, 2.5, 4.0] {
            let pair = c * f64::cos(b) + s * f64::sin(b);
            assert!((a * (b - phi).cos() - pair).abs() < 1e-12, "β = {b}");
        }
        let h = 1e-6;
        let d = |f: &dyn Fn(f64, f64) -> f64| {
            let g = [
                (f(c + h, s) - f(c - h, s)) / (2.0 * h),
                (f(c, s + h) - f(c, s - h)) / (2.0 * h),
            ];
            (g[0] * g[0] * cov[(0, 0)]
                + 2.0 * g[0] * g[1] * cov[(0, 1)]
                + g[1] * g[1] * cov[(1, 1)])
                .sqrt()
        };
        assert!((sa - d(&|c, s| c.hypot(s))).abs() < 1e-8, "{sa}");
        assert!((sphi - d(&|c, s| s.atan2(c))).abs() < 1e-8, "{sphi}");
        let alone = state(
            vec![Term::SCosB],
            vec![c],
            vec![0.07],
            cov.view((0, 0), (1, 1)).into(),
        );
        assert!(quadrature(&alone, Term::SCosB).is_none());
        assert!(quadrature(&st, Term::Eta).is_none());
    }

    /// Zero offsets of the input and of the output angle reading are told apart by the
    /// coupling's bilinear terms: exact for either alone, to second order for both; the σ are
    /// the first-order propagation of a diagonal covariance of c_cc and c_ss.
    #[test]
    fn coupling_terms_give_the_input_and_output_angle_offsets() {
        let terms = vec![
            Term::SinACosB,
            Term::CosASinB,
            Term::CosACosB,
            Term::SinASinB,
        ];
        let (g, delta) = (295.0, 0.204);
        let (s_cc, s_ss) = (0.08, 0.06);
        let mut cov = nalgebra::DMatrix::<f64>::zeros(4, 4);
        cov[(2, 2)] = s_cc * s_cc;
        cov[(3, 3)] = s_ss * s_ss;
        let offsets = |a: f64, b: f64| {
            let c = projected_coupling(g, delta, a, b);
            let st = state(
                terms.clone(),
                c.to_vec(),
                vec![0.0, 0.0, s_cc, s_ss],
                cov.clone(),
            );
            angle_offsets(&st).unwrap()
        };
        let deg = 1f64.to_radians();
        for (a, b, tol) in [
            (4.0 * deg, 0.0, 1e-12),
            (0.0, 4.0 * deg, 1e-12),
            (-2.0 * deg, 0.0, 1e-12),
            // both together: first order, off by terms of second order in the offsets
            (1.0 * deg, 3.0 * deg, 3.0 * deg * deg),
        ] {
            let [(ea, _), (eb, _)] = offsets(a, b);
            assert!(
                (ea - a).abs() < tol && (eb - b).abs() < tol,
                "{a} {b}: {ea} {eb}"
            );
        }
        let [(_, sa), (_, sb)] = offsets(0.0, 4.0 * deg);
        let den = g * (1.0 - delta * delta);
        let want_b = (s_ss.powi(2) + (delta * s_cc).powi(2)).sqrt() / den;
        let want_a = (s_cc.powi(2) + (delta * s_ss).powi(2)).sqrt() / den;
        assert!((sb / want_b - 1.0).abs() < 1e-2, "{sb} {want_b}");
        assert!((sa / want_a - 1.0).abs() < 1e-2, "{sa} {want_a}");
        // nearly parallel magnets: the coupling depends on α − β alone, the offsets are one
        let c = projected_coupling(g, 0.97, 0.0, 0.05);
        let st = state(terms.clone(), c.to_vec(), vec![0.0; 4], cov.clone());
        assert!(angle_offsets(&st).is_none());
    }

    /// The load family's fraction λ, weight ρ and tilt ψ with their first-order σ: the values
    /// from their definitions, the σ against J C Jᵀ with J by central differences of the same
    /// definitions written here, on a correlated covariance.
    #[test]
    fn load_fraction_weight_and_tilt_propagate_the_covariance() {
        let terms = vec![
            Term::Eta,
            Term::RadialLoadFric,
            Term::Shape(Shape::LoadWeight),
            Term::Shape(Shape::LoadSide),
        ];
        let theta = vec![11.0, 5.0, 1.9, 1.1];
        let l = nalgebra::DMatrix::<f64>::from_row_slice(
            4,
            4,
            &[
                0.4, 0.0, 0.0, 0.0, 0.1, 0.2, 0.0, 0.0, -0.05, 0.03, 0.15, 0.0, 0.02, -0.04, 0.06,
                0.1,
            ],
        );
        let cov = &l * l.transpose();
        let err = (0..4).map(|k| cov[(k, k)].sqrt()).collect::<Vec<f64>>();
        let st = state(terms, theta.clone(), err, cov.clone());
        let defs: [fn(&[f64]) -> f64; 3] = [
            |t| t[1] * t[2].hypot(t[3]) / (t[0] + t[1] * t[2].hypot(t[3])),
            |t| t[2].hypot(t[3]),
            |t| t[3].atan2(t[2]).to_degrees(),
        ];
        let sigma = |f: fn(&[f64]) -> f64| {
            let j: Vec<f64> = (0..4)
                .map(|k| {
                    let (mut up, mut dn) = (theta.clone(), theta.clone());
                    up[k] += 1e-6;
                    dn[k] -= 1e-6;
                    (f(&up) - f(&dn)) / 2e-6
                })
                .collect();
            let mut v = 0.0;
            for a in 0..4 {
                for b in 0..4 {
                    v += j[a] * j[b] * cov[(a, b)];
                }
            }
            (f(&theta), v.sqrt())
        };
        let (lam, s_lam) = load_fraction(&st).unwrap();
        let w = load_weight(&st).unwrap();
        let ((rho, s_rho), (psi, s_psi)) = (w.size, w.tilt_deg.unwrap());
        for ((v, s), f) in [(lam, s_lam), (rho, s_rho), (psi, s_psi)]
            .into_iter()
            .zip(defs)
        {
            let (v_fd, s_fd) = sigma(f);
            assert!((v - v_fd).abs() < 1e-12 * v.abs().max(1.0), "{v} vs {v_fd}");
            assert!((s - s_fd).abs() < 1e-6 * s_fd, "{s} vs {s_fd}");
        }
    }
}
