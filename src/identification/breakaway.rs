//! The `static_friction` candidate: proposed by the stick-phase profile of [`super::release`]
//! (the weak form skips stick phases and cannot see it) and judged like every other candidate by
//! the held-out prediction of the judging windows ([`super::judge`]): for each fold the excess is
//! profiled on the other folds' runs with the final model refitted without the fold, and the
//! fold's windows are predicted with it.

use super::catalog::catalog;
use super::judge::{added_parameters_z, compare, z_threshold, Comparison, Folds, HeldOut};
use super::model::{Coefficients, Geometry};
use super::preprocess::CleanRun;
use super::profile::ShapeProfile;
use super::propose::Candidate;
use super::release::{fit_static_friction, ReleaseOptions, StaticFrictionFit};
use super::report::{EffectSize, Finding};
use super::select::{evaluate, screen, ModelState, SelectCtx, Tried, SCREEN_Z};
use super::shooting::{par_map, Win};
use super::spec::coefficients;
use serde_json::json;
use std::collections::BTreeMap;

/// z of the stick-phase profile (ŝ/σ_s) from which the candidate is judged.
pub const PROPOSE_Z: f64 = 2.0;

fn profile_on(
    runs: &[CleanRun],
    st: &ModelState,
    theta: &[f64],
    geo: &Geometry,
    take: &dyn Fn(usize) -> bool,
    tol: f64,
) -> Option<StaticFrictionFit> {
    let nt = st.terms.len();
    let model = st.model(runs, geo, tol);
    let idx: Vec<usize> = (0..runs.len()).filter(|&r| take(r)).collect();
    let sub: Vec<CleanRun> = idx.iter().map(|&r| runs[r].clone()).collect();
    let per: Vec<Coefficients> = idx.iter().map(|&r| model.coefficients(theta, r)).collect();
    let c = coefficients(&st.terms, &theta[..nt]);
    fit_static_friction(
        &sub,
        &c,
        Some(&per),
        geo,
        model.latency_of(theta),
        &ReleaseOptions {
            tol,
            ..ReleaseOptions::default()
        },
    )
}

/// The judged `static_friction` finding on top of the final model `st` (`None` when the profile
/// does not propose it); with the comparison when judged, whether it stands, the excess η_Δs
/// (s⁻²) and the held-out errors of the model with it.
pub fn judge(
    runs: &[CleanRun],
    st: &ModelState,
    geo: &Geometry,
    wins: &[Win],
    folds: &Folds,
    tol: f64,
) -> Option<(Finding, Comparison, bool, f64, HeldOut)> {
    let all = profile_on(runs, st, &st.fit.theta, geo, &|_| true, tol)?;
    if !(all.s_err.is_finite() && all.s_err > 0.0 && all.s / all.s_err >= PROPOSE_Z) {
        return None;
    }
    let thetas: Vec<Vec<f64>> = (0..folds.k)
        .map(|f| {
            st.fit
                .step_without(wins, |run| folds.of_run[run] == f)
                .unwrap_or_else(|| st.fit.theta.clone())
        })
        .collect();
    // each fold's profile on the other folds' runs, the folds side by side
    let excess: Vec<f64> = par_map(folds.k, |f| {
        profile_on(runs, st, &thetas[f], geo, &|r| folds.of_run[r] != f, tol)
            .map(|x| x.s * x.eta)
            .unwrap_or(0.0)
    });
    let warm = st.fit.warm_starts(wins.len());
    let chi2: Vec<Option<f64>> = par_map(wins.len(), |k| {
        let w = &wins[k];
        let f = folds.of_run[w.run];
        let mut m = st.model(runs, geo, tol);
        m.eta_static_excess = excess[f];
        m.window_chi2_from(&thetas[f], w, warm[k])
    });
    let held = HeldOut {
        chi2,
        chi2_fit: st.held.chi2_fit.clone(),
    };
    let cmp = compare(&st.held, &held, wins, runs);
    let z_crit = z_threshold(SLOT_MEMBERS);
    let stands = cmp.improves(z_crit);
    let e = catalog().into_iter().find(|e| e.id == "static_friction")?;
    let mut p = BTreeMap::new();
    p.insert("eta_sliding".to_string(), all.eta);
    p.insert("eta_static".to_string(), all.eta * (1.0 + all.s));
    p.insert("eta_static_err".to_string(), all.eta * all.s_err);
    p.insert("excess_relative".to_string(), all.s);
    p.insert("excess_relative_err".to_string(), all.s_err);
    p.insert("excess_relative_err_stat".to_string(), all.s_stat);
    p.insert("excess_relative_err_sys".to_string(), all.s_sys);
    p.insert("events".to_string(), all.sticks as f64);
    let mut ev = BTreeMap::new();
    ev.insert("heldout_z".into(), json!(cmp.z));
    ev.insert("heldout_z_cluster_by_run".into(), json!(cmp.z_cluster));
    ev.insert("heldout_z_chi2".into(), json!(cmp.z_chi2));
    ev.insert("z_threshold".into(), json!(z_crit));
    ev.insert("heldout_chi2_gain".into(), json!(cmp.gain));
    ev.insert("windows".into(), json!(cmp.windows));
    ev.insert("profile_z".into(), json!(all.s / all.s_err));
    ev.insert("stick_windows".into(), json!(all.windows));
    ev.insert("delta_chi2_profile".into(), json!(all.delta_chi2));
    ev.insert("excess_per_fold".into(), json!(excess));
    ev.insert("profile".into(), json!(all.profile));
    // a minimum at the end of the profiled range is a lower bound, not a value with a σ
    let s_max = ReleaseOptions::default().s_max;
    let at_bound = all.s >= s_max * (1.0 - 1e-3);
    if at_bound {
        p.insert("excess_relative_lower_bound".to_string(), all.s);
        ev.insert(
            "profile_at_range_end".into(),
            json!(format!(
                "the profile's minimum is the end of its range (s = {s_max}): a lower bound, no σ"
            )),
        );
    }
    let size = (!at_bound).then(|| EffectSize {
        name: "excess".into(),
        value: all.s,
        sigma: all.s_err,
        unit: "1".into(),
    });
    let f = Finding {
        effect: e.id.to_string(),
        class: e.class.to_string(),
        explanation: e.explanation.to_string(),
        params: p,
        candidates: e.candidates.iter().map(|s| s.to_string()).collect(),
        discriminating_experiment: e.discriminating_experiment.to_string(),
        rms_before_rad: None,
        rms_after_rad: None,
        heldout_rms_before_rad: Some(cmp.rms_before),
        heldout_rms_after_rad: Some(cmp.rms_after),
        evidence: ev,
        size,
        standing: None,
    };
    Some((f, cmp, stands, all.s * all.eta, held))
}

/// Starting shapes (w in rad/s, δ) of the Stribeck member refitted when the stick-phase profile
/// proposes a breakaway excess: three widths from a tenth of the driven runs' speeds to about
/// them (points of [`super::propose::STRIBECK_WIDTH_GRID`]), each with the exponential and the
/// Gaussian decay ([`super::propose::STRIBECK_POWER_GRID`]). The refit by simulation fits the
/// excess at each; the best start is judged ([`width_member`]), and its shapes are freed in the
/// final refit ([`super::select::polish`]).
pub const WIDTH_STARTS: [(f64, f64); 6] = [
    (0.2, 1.0),
    (0.5, 1.0),
    (1.2, 1.0),
    (0.2, 2.0),
    (0.5, 2.0),
    (1.2, 2.0),
];

/// Members of the `static_friction` slot judged after the rounds: the excess at rest
/// ([`judge`]) and the Stribeck member with a width ([`width_member`]); the threshold of each
/// counts both ([`z_threshold`] of 2).
pub const SLOT_MEMBERS: usize = 2;

/// The Stribeck member η + η_Δs exp(−(|β̇|/w)^δ) (the catalog's `static_friction` with a width)
/// on top of the final model `fin`, started from the excess `excess` (s⁻²) that the stick-phase
/// profile measured at rest and from each of [`WIDTH_STARTS`]: each start is screened like the
/// rounds' candidates (refitted by simulation with its shapes held, judged on every second
/// judging window), the one with the largest held-out gain is refitted on all judging windows
/// and judged against `fin` by its held-out prediction, with the Wald z of its excess: the same
/// rule as the rounds' candidates, at the threshold of [`SLOT_MEMBERS`]. The profile at rest is the member's w → 0 limit: on a
/// Stribeck decay it sees the braking of slow sliding as a larger excess at rest (on the
/// campaign's Gaussian decay of w = 0.5 rad/s it gave 1.5–1.8 times the true excess,
/// docs/diagnosis.md), while the member with a width is fitted where the decay acts. Also
/// returns the best-screened start of a width at least twice or half the chosen one's, for a
/// second final refit ([`final_member`]). `None` when no start could be refitted. `round` numbers
/// it in the report.
pub fn width_member(
    ctx: &SelectCtx,
    fin: &ModelState,
    excess: f64,
    round: usize,
) -> Option<(Tried, Option<Candidate>)> {
    let effect = catalog()
        .into_iter()
        .find(|e| e.id == "static_friction" && !e.terms.is_empty())?;
    let nc = fin.terms.len();
    let current = fin.fit.theta[..nc].to_vec();
    let cands: Vec<Candidate> = WIDTH_STARTS
        .iter()
        .map(|&(w, d)| {
            let mut weak_coef = current.clone();
            weak_coef.extend([excess, w, d]);
            Candidate {
                effect: effect.clone(),
                terms: effect.terms.clone(),
                weak_coef,
                weak_coef_current: current.clone(),
                latency: None,
                weak_dbic: f64::NAN,
            }
        })
        .collect();
    // the starts screened like the rounds' candidates (every second judging window), the one
    // with the largest held-out gain refitted on all windows and judged
    let screens = par_map(cands.len(), |k| screen(ctx, fin, &cands[k]));
    let mut ranked: Vec<(usize, Comparison)> = screens
        .into_iter()
        .enumerate()
        .filter_map(|(k, s)| Some((k, s?)))
        .collect();
    ranked.sort_by(|a, b| b.1.gain.total_cmp(&a.1.gain));
    let (k, scr) = *ranked.first()?;
    // the best-screened start whose width differs from the chosen one's by a factor 2 or more
    let width = |j: usize| WIDTH_STARTS[j].0;
    let alternate = ranked
        .iter()
        .find(|(j, _)| (width(*j) / width(k)).ln().abs() >= std::f64::consts::LN_2)
        .map(|(j, _)| cands[*j].clone());
    let z_crit = z_threshold(SLOT_MEMBERS);
    let st = (scr.z >= SCREEN_Z)
        .then(|| evaluate(ctx, fin, &cands[k]))
        .flatten();
    let cmp = st
        .as_ref()
        .map(|s| compare(&fin.held, &s.held, ctx.wins, ctx.runs));
    let added_z = st.as_ref().map(|s| added_parameters_z(&s.fit, &[nc]));
    let accepted = cmp.is_some_and(|c| c.improves(z_crit)) && added_z.is_some_and(|z| z >= z_crit);
    let tried = Tried {
        round,
        candidate: cands[k].clone(),
        cmp,
        screen: Some(scr),
        screen_fit: None,
        screen_beaten: None,
        z_crit,
        accepted,
        state: st.filter(|_| accepted),
        added_z,
        member: None,
        dropped: None,
        forked: false,
        joined: false,
        on_top_of: None,
    };
    Some((tried, alternate))
}

/// The other of the two final refits of [`final_member`]: its model and how far its χ² lies
/// above the kept one's on the kept refit's own objective (the windows that refit used); a
/// second minimum of the non-convex χ², whose headline widens the σ
/// ([`super::findings::second_minimum_size`]).
#[derive(Debug, Clone)]
pub struct SecondMinimum {
    /// The refit not kept.
    pub state: ModelState,
    /// Its χ² minus the kept refit's over the windows the kept refit used (χ² in camera-noise
    /// σ units; ≥ 0: a lower value, possible where the two used other windows, counts as 0).
    pub rise: f64,
}

/// The final refit of an accepted Stribeck member: `polish` (shapes freed, refitted to
/// convergence) from its judged state `judged` and, when there is one, from the `alternate`
/// start refitted on top of `fin`; the one with the smaller χ² summed over the judging windows
/// both simulate, with the other as a [`SecondMinimum`]. The window χ² of a stick–slip model is
/// not convex in the width w: on the campaign's Gaussian Stribeck set of level 2, seed 5 (truth
/// Δη_s/η = 1, w = 0.5 rad/s, δ = 2) the refit from the start w = 1.2 stopped at w = 0.94, δ = 4,
/// Δη_s/η = 0.79 ± 0.02, where the profile of w (`--profile-shapes`) found a lower χ² at w = 0.47,
/// Δη_s/η = 0.95 (docs/diagnosis.md).
pub fn final_member<P>(
    ctx: &SelectCtx,
    fin: &ModelState,
    judged: &ModelState,
    alternate: Option<&Candidate>,
    polish: P,
) -> (ModelState, Vec<ShapeProfile>, Option<SecondMinimum>)
where
    P: Fn(&ModelState) -> (ModelState, Vec<ShapeProfile>),
{
    let first = polish(judged);
    let Some(second) = alternate
        .and_then(|c| evaluate(ctx, fin, c))
        .map(|st| polish(&st))
    else {
        return (first.0, first.1, None);
    };
    let chi2 = |st: &ModelState| {
        st.fit
            .window_chi2(&st.model(ctx.runs, ctx.geo, ctx.tol), ctx.wins)
            .0
    };
    let (a, b) = (chi2(&first.0), chi2(&second.0));
    let (mut sa, mut sb) = (0.0, 0.0);
    for (x, y) in a.iter().zip(&b) {
        if let (Some(x), Some(y)) = (x, y) {
            sa += x;
            sb += y;
        }
    }
    let (kept, other, (ck, co)) = if sb < sa {
        (second, first, (b, a))
    } else {
        (first, second, (a, b))
    };
    // the rise on the kept refit's objective: the windows it used (the other refit's χ² there
    // by its own residuals or, for a window it left out, a fresh state fit at its θ)
    let mut rise = 0.0;
    for &(w, _) in &kept.0.fit.used {
        rise += co[w].unwrap_or(f64::INFINITY) - ck[w].unwrap_or(0.0);
    }
    let other = SecondMinimum {
        state: other.0,
        rise: rise.max(0.0),
    };
    (kept.0, kept.1, Some(other))
}
