//! The `static_friction` candidate: proposed by the stick-phase profile of [`super::release`]
//! (the weak form skips stick phases and cannot see it) and judged like every other candidate by
//! the held-out prediction of the judging windows ([`super::judge`]): for each fold the excess is
//! profiled on the other folds' runs with the final model refitted without the fold, and the
//! fold's windows are predicted with it.

use super::catalog::catalog;
use super::judge::{compare, z_threshold, Comparison, Folds, HeldOut};
use super::model::{Coefficients, Geometry};
use super::preprocess::CleanRun;
use super::release::{fit_static_friction, ReleaseOptions, StaticFrictionFit};
use super::report::{EffectSize, Finding};
use super::select::ModelState;
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
    let excess: Vec<f64> = (0..folds.k)
        .map(|f| {
            profile_on(runs, st, &thetas[f], geo, &|r| folds.of_run[r] != f, tol)
                .map(|x| x.s * x.eta)
                .unwrap_or(0.0)
        })
        .collect();
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
    let z_crit = z_threshold(1);
    let stands = cmp.z >= z_crit;
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
    ev.insert("z_threshold".into(), json!(z_crit));
    ev.insert("heldout_chi2_gain".into(), json!(cmp.gain));
    ev.insert("windows".into(), json!(cmp.windows));
    ev.insert("profile_z".into(), json!(all.s / all.s_err));
    ev.insert("stick_windows".into(), json!(all.windows));
    ev.insert("delta_chi2_profile".into(), json!(all.delta_chi2));
    ev.insert("excess_per_fold".into(), json!(excess));
    ev.insert("profile".into(), json!(all.profile));
    let size = Some(EffectSize {
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
    };
    Some((f, cmp, stands, all.s * all.eta, held))
}
