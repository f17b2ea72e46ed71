//! The verdict: what the findings explain of the base model's held-out mismatch, and what is left.
//!
//! Two questions decide it, both answered by numbers the diagnosis has already measured:
//!
//! 1. **Does a finding stand?** Its strength (the parameter that is zero when the effect is
//!    absent, [`strength`]) must differ from zero by at least [`ZERO_Z`] standard errors, and a
//!    physical effect must have its physical sign: a drag that accelerates, a friction that falls
//!    as the load rises, a breakaway friction below the sliding friction, or a compliance that
//!    makes the input lead its torque is not a finding ([`Status`]).
//! 2. **Is anything left?** The remainder's floor test ([`super::mismatch::remainder`]): the final
//!    model's held-out excess χ²/dof E above the camera-noise floor, significant when
//!    E ≥ [`super::mismatch::REMAINDER_Z`] σ_E.
//!
//! | findings that stand | remainder above the floor | verdict |
//! |---|---|---|
//! | yes | no (or not measured) | the first finding's effect |
//! | yes | yes | `partly_explained` |
//! | no | yes | `unexplained` |
//! | no, but findings that do not stand | no | `unexplained` |
//! | none at all | no | `none` |
//!
//! A third question can overrule the table: **does a curve beat the findings?** Where the
//! nonparametric curve in β ([`super::curve`]) predicts the held-out runs significantly better
//! than the base model with every accepted finding, the findings' catalog forms are wrong for
//! this set: the verdict is `unexplained` whatever the remainder, the findings are listed as
//! partial, and the curve is what characterises the missing physics. A curve that does not beat
//! them leaves the verdict of the table.
//!
//! A catalog name is therefore never the verdict while the diagnosis's own remainder test says
//! that a significant mismatch is left: the report then says how much each standing finding
//! removed (the fraction of the base model's held-out excess, [`Standing::fraction_removed`]),
//! how much is left and where ([`super::report::Remainder::dependence`]).

use super::curve::Curve;
use super::model::Shape;
use super::report::{EffectSize, Finding, Remainder};
use serde::{Deserialize, Serialize};

/// A finding's strength must be at least this many standard errors from zero to stand (a
/// two-sided 95 % interval that excludes zero).
pub const ZERO_Z: f64 = 2.0;

/// Class of the findings of the nominal consistency ([`super::nominal`]): they compare the fitted
/// base parameters with the set-up's stated ones and explain none of the held-out mismatch.
pub const NOMINAL_CLASS: &str = "nominal";

/// Verdict when findings stand but a significant remainder is left.
pub const PARTLY_EXPLAINED: &str = "partly_explained";
/// Verdict when a significant mismatch is left that no standing finding explains (also the
/// effect id of the dictionary's findings, [`super::catalog::dictionary`]).
pub const UNEXPLAINED: &str = "unexplained";
/// Verdict when the base model explains the recordings to the noise.
pub const NONE: &str = "none";

/// Whether a finding stands.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    /// Its strength differs from zero by ≥ [`ZERO_Z`] σ and has the physical sign.
    Stands,
    /// Its strength is within [`ZERO_Z`] σ of zero.
    ConsistentWithZero,
    /// Its strength differs from zero with the sign no physical effect of its kind has.
    Unphysical,
    /// The finding reports no strength with a standard error: it cannot be tested and does not
    /// stand.
    Unsized,
}

/// A finding's standing (report key `standing` of a finding).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Standing {
    /// Whether it stands.
    pub status: Status,
    /// The parameter tested against zero and the physical sign.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub strength: Option<EffectSize>,
    /// Fraction of the base model's held-out excess χ² (over the noise floor) that adding this
    /// effect removed, on the judging windows both models predicted
    /// ([`super::mismatch::fraction_removed`]); absent for findings that are not judged by
    /// held-out prediction (the nominal consistency) or when the base model's excess is within
    /// noise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fraction_removed: Option<f64>,
    /// 1σ of it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fraction_removed_sigma: Option<f64>,
    /// In words.
    pub reason: String,
}

/// Which kind of verdict (report key `assessment.kind`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Kind {
    /// Standing findings and nothing significant left: the verdict is the first finding.
    Explained,
    /// Standing findings, and a significant remainder left.
    PartlyExplained,
    /// A significant mismatch and no standing finding.
    Unexplained,
    /// Nothing to explain.
    Nothing,
}

/// The verdict with its reasons (report key `assessment`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Assessment {
    /// Which kind of verdict.
    pub kind: Kind,
    /// Effects of the standing findings, in the report's order.
    pub explained_by: Vec<String>,
    /// Effects of the findings that do not stand.
    pub not_standing: Vec<String>,
    /// The remainder's excess over its σ (absent when not measured).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub remainder_z: Option<f64>,
    /// Whether the remainder is above the floor (absent when not measured).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub remainder_above_floor: Option<bool>,
    /// Whether the curve of what remains predicts the held-out runs significantly better than the
    /// final model (absent when no curve was fitted; report key `curve`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub curve_beats_findings: Option<bool>,
    /// The sentence report.md prints under the verdict.
    pub statement: String,
}

/// Which sign a strength must have.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Sign {
    /// Any sign (offsets, latencies, drifts, modulations).
    Any,
    /// Positive: an effect that dissipates or resists (drags, frictions, compliance).
    Positive(&'static str),
}

/// The parameter of `effect` that is zero when the effect is absent, and its physical sign; `None`
/// for an effect without one (its headline is then used, of any sign).
fn strength_key(effect: &str) -> Option<(&'static str, &'static str, &'static str, Sign)> {
    let positive = Sign::Positive;
    Some(match effect {
        "power_law_drag" => (
            "q_at_reference_speed",
            "q_at_reference_speed_err",
            "s^-2",
            positive("a drag that accelerates the output"),
        ),
        "corotating_drag" => (
            "c",
            "c_err",
            "s^-1",
            positive("a co-rotating drag that pushes the output away from the input's speed"),
        ),
        "load_dependent_friction" => (
            "eta_load",
            "eta_load_err",
            "s^-2",
            positive("a dry friction that falls as the bearing load rises"),
        ),
        "static_friction" => (
            "eta_static_excess",
            "eta_static_excess_err",
            "s^-2",
            positive("a breakaway friction below the sliding friction"),
        ),
        "input_compliance" => (
            "chi_s2",
            "chi_err_s2",
            "s^2",
            positive("a compliance that makes the input lead its torque"),
        ),
        _ => return None,
    })
}

/// The strength of a finding: the parameter tested against zero (its named strength parameter,
/// else its headline size) and the sign it must have.
fn strength(f: &Finding) -> Option<(EffectSize, Sign)> {
    if let Some((v, e, unit, sign)) = strength_key(&f.effect) {
        let get = |k: &str| f.params.get(k).copied();
        if let Some(profiled) = (f.effect == "static_friction")
            .then(|| profiled_strength(f, sign))
            .flatten()
        {
            return Some(profiled);
        }
        if let (Some(value), Some(sigma)) = (get(v), get(e)) {
            return Some((
                EffectSize {
                    name: v.into(),
                    value,
                    sigma,
                    unit: unit.into(),
                },
                sign,
            ));
        }
    }
    f.size.clone().map(|s| (s, Sign::Any))
}

/// The breakaway excess with the σ of its profile on the side toward zero
/// (`size_profile_sigma_lo` for a positive excess; [`super::findings::excess_profile_size`]): the
/// excess's valley is curved, so the covariance's σ at its minimum says little about how far zero
/// lies, and the profile measures exactly that. `None` without a profile.
fn profiled_strength(f: &Finding, sign: Sign) -> Option<(EffectSize, Sign)> {
    let get = |k: &str| f.params.get(k).copied();
    let value = get("excess_relative")?;
    let sigma = if value >= 0.0 {
        get("size_profile_sigma_lo")?
    } else {
        get("size_profile_sigma_hi")?
    };
    (sigma.is_finite() && sigma > 0.0).then(|| {
        (
            EffectSize {
                name: "excess_relative".into(),
                value,
                sigma,
                unit: "1".into(),
            },
            sign,
        )
    })
}

/// Whether `f` stands ([`Status`]); `fraction` is the fraction of the base model's excess it
/// removed, with its σ.
pub fn standing(f: &Finding, fraction: Option<(f64, f64)>) -> Standing {
    let (status, strength, reason) = match strength(f) {
        // a departure from the set-up's stated values, tested by the nominal consistency itself
        Some((s, _)) if f.class == NOMINAL_CLASS => (
            Status::Stands,
            Some(s),
            "outside the interval the set-up's tolerances allow (nominal consistency)".to_string(),
        ),
        None => (
            Status::Unsized,
            None,
            "no size with a standard error to test against zero".to_string(),
        ),
        Some((s, _)) if !(s.value.is_finite() && s.sigma.is_finite() && s.sigma > 0.0) => (
            Status::Unsized,
            Some(s),
            "its size has no finite, positive standard error".to_string(),
        ),
        Some((s, sign)) => {
            let z = s.value / s.sigma;
            let quoted = format!(
                "{} = {} ± {} {}",
                s.name,
                sig(s.value, s.sigma),
                sig(s.sigma, s.sigma),
                s.unit
            );
            let (status, reason) = if z.abs() < ZERO_Z {
                (
                    Status::ConsistentWithZero,
                    format!(
                        "{quoted} is consistent with zero ({:.1}σ < {ZERO_Z}σ)",
                        z.abs()
                    ),
                )
            } else if let (Sign::Positive(what), true) = (sign, z < 0.0) {
                (
                    Status::Unphysical,
                    format!("{quoted} is negative at {:.1}σ: {what}", -z),
                )
            } else {
                (
                    Status::Stands,
                    format!("{quoted} ({:.1}σ from zero)", z.abs()),
                )
            };
            (status, Some(s), reason)
        }
    };
    Standing {
        status,
        strength,
        fraction_removed: fraction.map(|f| f.0),
        fraction_removed_sigma: fraction.map(|f| f.1),
        reason,
    }
}

/// `v` rounded to two significant digits of its standard error `s`.
fn sig(v: f64, s: f64) -> String {
    if !(s.is_finite() && s > 0.0) {
        return format!("{v:.3e}");
    }
    let digits = (1 - s.log10().floor() as i32).clamp(0, 12) as usize;
    format!("{v:.digits$}")
}

/// Whether a finding stands (one without a standing yet is taken as standing).
fn stands(f: &Finding) -> bool {
    f.standing
        .as_ref()
        .is_none_or(|s| s.status == Status::Stands)
}

/// Orders `findings` so that the standing ones come first (otherwise in their order) and returns
/// the verdict with its assessment, from the standings already set on each finding, the
/// remainder `rem` (`None` when it was not measured) and the curve of what remains (`None` when
/// none was fitted).
pub fn decide(
    findings: &mut [Finding],
    rem: Option<&Remainder>,
    curve: Option<&Curve>,
) -> (String, Assessment) {
    // stable: standing findings first, each group in the selection's order
    findings.sort_by_key(|f| !stands(f));
    let explained_by: Vec<String> = findings
        .iter()
        .filter(|f| stands(f))
        .map(|f| f.effect.clone())
        .collect();
    let not_standing: Vec<String> = findings
        .iter()
        .filter(|f| !stands(f))
        .map(|f| f.effect.clone())
        .collect();
    let above = rem.map(|r| !r.within_noise);
    // the nominal consistency explains none of the held-out mismatch
    let dynamical = findings
        .iter()
        .any(|f| stands(f) && f.class != NOMINAL_CLASS);
    let beaten = curve.is_some_and(|c| c.stands);
    let kind = match (explained_by.is_empty(), above == Some(true)) {
        _ if beaten => Kind::Unexplained,
        (false, true) if !dynamical => Kind::Unexplained,
        (false, false) => Kind::Explained,
        (false, true) => Kind::PartlyExplained,
        (true, true) => Kind::Unexplained,
        (true, false) if !not_standing.is_empty() => Kind::Unexplained,
        (true, false) => Kind::Nothing,
    };
    let verdict = match kind {
        Kind::Explained => explained_by[0].clone(),
        Kind::PartlyExplained => PARTLY_EXPLAINED.into(),
        Kind::Unexplained => UNEXPLAINED.into(),
        Kind::Nothing => NONE.into(),
    };
    let mut statement = statement(kind, findings, rem);
    if let Some(c) = curve {
        statement.push_str(&curve_words(c));
    }
    (
        verdict,
        Assessment {
            kind,
            explained_by,
            not_standing,
            remainder_z: rem.map(|r| r.excess_chi2_per_dof / r.excess_sigma),
            remainder_above_floor: above,
            curve_beats_findings: curve.map(|c| c.stands),
            statement,
        },
    )
}

/// The sentence under the verdict: what each standing finding removed, what is left and where.
fn statement(kind: Kind, findings: &[Finding], rem: Option<&Remainder>) -> String {
    let removed = |f: &Finding| {
        let s = f.standing.as_ref()?;
        let (v, e) = (s.fraction_removed?, s.fraction_removed_sigma?);
        Some(format!(
            "`{}` removes {} ± {} of the base model's held-out excess",
            f.effect,
            sig(v, e),
            sig(e, e)
        ))
    };
    let standing: Vec<String> = findings
        .iter()
        .filter(|f| stands(f))
        .map(|f| removed(f).unwrap_or_else(|| format!("`{}`", f.effect)))
        .collect();
    let rejected: Vec<String> = findings
        .iter()
        .filter_map(|f| {
            let s = f.standing.as_ref()?;
            (s.status != Status::Stands).then(|| format!("`{}` ({})", f.effect, s.reason))
        })
        .collect();
    let left = rem.map(remainder_words).unwrap_or_default();
    let mut out = match kind {
        Kind::Explained if rem.is_none() => format!(
            "Found: {} (what is left was not measured).",
            standing.join("; ")
        ),
        Kind::Explained => format!("Explained to the noise: {}.{left}", standing.join("; ")),
        Kind::PartlyExplained => format!(
            "Partly explained: {}. A significant mismatch is left that none of the findings \
             explains.{left}",
            standing.join("; ")
        ),
        Kind::Unexplained => {
            format!("Unexplained: no finding that stands explains the mismatch.{left}")
        }
        Kind::Nothing => format!("Nothing to explain: the base model predicts to the noise.{left}"),
    };
    if !rejected.is_empty() {
        out.push_str(&format!(
            " Not findings (listed, never the verdict): {}.",
            rejected.join("; ")
        ));
    }
    out
}

/// What the curve of the remainder says: whether it beats the findings, and its shape.
fn curve_words(c: &Curve) -> String {
    let what = match c.kind.as_str() {
        "friction" => "the dry friction as a curve η(β) of the output angle",
        _ => "a torque curve τ(β) of the output angle",
    };
    let against = if c.against.is_empty() {
        "the base model".to_string()
    } else {
        format!("the base model with `{}`", c.against.join("`, `"))
    };
    let cmp = format!(
        "held-out gain {} ± {} χ², z = {:.1}, threshold {:.2}",
        sig(c.heldout_gain, c.heldout_gain_sigma),
        sig(c.heldout_gain_sigma, c.heldout_gain_sigma),
        c.z,
        c.z_crit
    );
    if !c.stands {
        return format!(
            " A curve in β ({what}) does not predict the held-out runs significantly better than \
             {against} ({cmp})."
        );
    }
    let (imax, vmax) =
        c.value.iter().enumerate().fold(
            (0, f64::NEG_INFINITY),
            |m, (i, &v)| if v > m.1 { (i, v) } else { m },
        );
    let vmin = c.value.iter().copied().fold(f64::INFINITY, f64::min);
    format!(
        " The catalog's forms are wrong for this set: {what} predicts the held-out runs \
         significantly better than {against} ({cmp}); it is largest at β = {:.0}° ({} s⁻², \
         {} s⁻² at its smallest; report key `curve`, figure remainder_curve.svg).",
        c.grid_deg[imax],
        sig(vmax, c.sigma[imax]),
        sig(vmin, c.sigma[imax]),
    )
}

/// " Left: E ± σ χ²/dof above the noise floor (zσ), …" with where the remainder depends most.
fn remainder_words(r: &Remainder) -> String {
    let e = format!(
        "{} ± {} χ²/dof above the noise floor ({:.1}σ)",
        sig(r.excess_chi2_per_dof, r.excess_sigma),
        sig(r.excess_sigma, r.excess_sigma),
        r.excess_chi2_per_dof / r.excess_sigma
    );
    if r.within_noise {
        return format!(" What is left, {e}, is within noise.");
    }
    let mut s = format!(" Left: {e}");
    if let Some(d) = r.dependence.iter().find(|d| d.significant) {
        s.push_str(&format!(
            "; it depends most on {} (z = {:.1}), largest in {} = {}",
            d.variable, d.z, d.variable, d.peak_bin
        ));
    } else if !r.dependence.is_empty() {
        s.push_str("; it depends significantly on none of the variables tested (spread)");
    }
    s.push('.');
    s
}

/// The standings of `findings` from their fractions removed (`fractions[i]` of `findings[i]`),
/// after their shapes at the end of their range are marked ([`mark_shape_bounds`]).
pub fn set_standings(findings: &mut [Finding], fractions: &[Option<(f64, f64)>]) {
    for (i, f) in findings.iter_mut().enumerate() {
        mark_shape_bounds(f);
        f.standing = Some(standing(f, fractions.get(i).copied().flatten()));
    }
}

/// The report keys of the families' shape parameters and their ranges ([`Shape::range`]).
const SHAPE_KEYS: &[(&str, Shape)] = &[
    ("exponent", Shape::DragExponent),
    ("stribeck_width", Shape::StribeckWidth),
    ("stribeck_power", Shape::StribeckPower),
    ("weight_vertical", Shape::LoadWeight),
    ("weight_side", Shape::LoadSide),
    ("clock_settling_tau", Shape::DriftSettling),
];

/// A fitted shape parameter within 10⁻³ of its range's width from an end of its range is a bound, not an
/// estimate: its covariance σ (`{key}_err`) is removed and `{key}_at_bound` set to the end's value
/// (the σ of a curvature at a clamp says nothing about how far the data would take it); a headline
/// size on that parameter is removed with it.
pub fn mark_shape_bounds(f: &mut Finding) {
    for &(key, shape) in SHAPE_KEYS {
        // only fitted shapes (with a σ); a value held on a grid has none to remove
        let (Some(&v), true) = (
            f.params.get(key),
            f.params.contains_key(&format!("{key}_err")),
        ) else {
            continue;
        };
        let (lo, hi) = shape.range();
        let tol = 1e-3 * (hi - lo);
        let end = if (v - lo).abs() <= tol {
            lo
        } else if (hi - v).abs() <= tol {
            hi
        } else {
            continue;
        };
        f.params.remove(&format!("{key}_err"));
        f.params.insert(format!("{key}_at_bound"), end);
        if f.size.as_ref().is_some_and(|s| s.name == key) {
            f.size = None;
        }
        f.evidence.insert(
            format!("{key}_at_bound"),
            serde_json::json!(format!(
                "{key} = {v} is at the end {end} of its range [{lo}, {hi}]: a bound, reported without σ"
            )),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::identification::report::Dependence;
    use std::collections::BTreeMap;

    fn params(pairs: &[(&str, f64)]) -> BTreeMap<String, f64> {
        pairs.iter().map(|(k, v)| (k.to_string(), *v)).collect()
    }

    fn finding(effect: &str, p: &[(&str, f64)], size: Option<(f64, f64)>) -> Finding {
        Finding {
            effect: effect.into(),
            class: String::new(),
            explanation: String::new(),
            params: params(p),
            candidates: vec![],
            discriminating_experiment: String::new(),
            rms_before_rad: None,
            rms_after_rad: None,
            heldout_rms_before_rad: None,
            heldout_rms_after_rad: None,
            evidence: BTreeMap::new(),
            size: size.map(|(value, sigma)| EffectSize {
                name: "amplitude".into(),
                value,
                sigma,
                unit: "s^-2".into(),
            }),
            standing: None,
        }
    }

    fn remainder(excess: f64, sigma: f64) -> Remainder {
        Remainder {
            excess_chi2_per_dof: excess,
            excess_sigma: sigma,
            base_excess_chi2_per_dof: 10.0,
            base_excess_sigma: 1.0,
            fraction_removed: None,
            fraction_removed_sigma: None,
            within_noise: excess < super::super::mismatch::REMAINDER_Z * sigma,
            windows: 40,
            bins: vec![],
            located: vec![],
            noise: None,
            dependence: vec![Dependence {
                variable: "beta_phase_deg".into(),
                bins: 6,
                chi2: 40.0,
                dof: 5,
                z: 4.5,
                significant: true,
                peak_bin: "[60, 120)".into(),
                peak_excess_chi2_per_dof: 3.0,
                peak_excess_sigma: 0.4,
                experiment: String::new(),
            }],
        }
    }

    fn decided(mut f: Vec<Finding>, rem: Option<&Remainder>) -> (String, Assessment, Vec<Finding>) {
        let n = f.len();
        set_standings(&mut f, &vec![Some((0.5, 0.05)); n]);
        let (v, a) = decide(&mut f, rem, None);
        (v, a, f)
    }

    #[test]
    fn a_standing_finding_is_the_verdict_only_when_nothing_significant_is_left() {
        let torque = || finding("static_torque", &[], Some((3.9, 0.11)));
        let (v, a, _) = decided(vec![torque()], Some(&remainder(0.05, 0.04)));
        assert_eq!((v.as_str(), a.kind), ("static_torque", Kind::Explained));
        let (v, a, _) = decided(vec![torque()], Some(&remainder(2.70, 0.36)));
        assert_eq!(
            (v.as_str(), a.kind),
            (PARTLY_EXPLAINED, Kind::PartlyExplained)
        );
        assert_eq!(a.explained_by, vec!["static_torque"]);
        assert!(
            a.statement.contains("removes 0.500 ± 0.050"),
            "{}",
            a.statement
        );
        assert!(a.statement.contains("beta_phase_deg"), "{}", a.statement);
        // the remainder not measured: the finding stands alone
        let (v, _, _) = decided(vec![torque()], None);
        assert_eq!(v, "static_torque");
    }

    #[test]
    fn a_size_consistent_with_zero_or_unphysical_is_never_the_verdict() {
        let drag = finding(
            "power_law_drag",
            &[
                ("q_at_reference_speed", -0.009),
                ("q_at_reference_speed_err", 0.034),
            ],
            Some((2.8, 1.7)),
        );
        let (v, a, f) = decided(vec![drag.clone()], Some(&remainder(0.51, 0.09)));
        assert_eq!((v.as_str(), a.kind), (UNEXPLAINED, Kind::Unexplained));
        assert_eq!(
            f[0].standing.as_ref().unwrap().status,
            Status::ConsistentWithZero
        );
        // within noise, but the only finding does not stand: unexplained, not `none`
        let (v, _, _) = decided(vec![drag], Some(&remainder(0.01, 0.05)));
        assert_eq!(v, UNEXPLAINED);
        // an accelerating drag next to a standing friction: the friction leads, the drag is
        // listed after it and named as not a finding
        let accelerating = finding(
            "power_law_drag",
            &[
                ("q_at_reference_speed", -0.30),
                ("q_at_reference_speed_err", 0.05),
            ],
            None,
        );
        let friction = finding(
            "static_friction",
            &[("eta_static_excess", 12.0), ("eta_static_excess_err", 0.4)],
            None,
        );
        let (v, a, f) = decided(vec![accelerating, friction], Some(&remainder(0.02, 0.07)));
        assert_eq!(v, "static_friction");
        assert_eq!(f[1].standing.as_ref().unwrap().status, Status::Unphysical);
        assert_eq!(a.not_standing, vec!["power_law_drag"]);
        assert!(
            a.statement.contains("drag that accelerates"),
            "{}",
            a.statement
        );
    }

    #[test]
    fn a_shape_at_the_end_of_its_range_is_a_bound_without_sigma() {
        let mut f = finding(
            "static_friction",
            &[
                ("stribeck_power", 0.5),
                ("stribeck_power_err", 0.01),
                ("stribeck_width", 0.3),
                ("stribeck_width_err", 0.05),
            ],
            None,
        );
        mark_shape_bounds(&mut f);
        assert_eq!(f.params.get("stribeck_power_at_bound"), Some(&0.5));
        assert!(!f.params.contains_key("stribeck_power_err"));
        assert!(f.params.contains_key("stribeck_width_err"));
        assert!(!f.params.contains_key("stribeck_width_at_bound"));
        let mut drag = finding(
            "power_law_drag",
            &[("exponent", 4.0), ("exponent_err", 0.2)],
            Some((4.0, 0.2)),
        );
        drag.size.as_mut().unwrap().name = "exponent".into();
        mark_shape_bounds(&mut drag);
        assert!(drag.size.is_none());
    }

    #[test]
    fn offsets_of_either_sign_stand_and_nothing_found_is_none_or_unexplained() {
        let latency = finding("sensor_latency", &[], Some((-0.004, 0.0005)));
        let (v, _, _) = decided(vec![latency], Some(&remainder(0.0, 0.05)));
        assert_eq!(v, "sensor_latency");
        let (v, a, _) = decided(vec![], Some(&remainder(0.0, 0.05)));
        assert_eq!((v.as_str(), a.kind), (NONE, Kind::Nothing));
        let (v, a, _) = decided(vec![], Some(&remainder(14.2, 4.6)));
        assert_eq!((v.as_str(), a.kind), (UNEXPLAINED, Kind::Unexplained));
        let unsized_ = finding("drive_steps", &[], None);
        let (v, _, f) = decided(vec![unsized_], None);
        assert_eq!(v, UNEXPLAINED);
        assert_eq!(f[0].standing.as_ref().unwrap().status, Status::Unsized);
    }
}
