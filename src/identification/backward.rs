//! The backward check (stage 5c of the pipeline): the rounds add one effect each (two when close
//! rivals are accepted together, [`super::beam`]), and an
//! effect accepted early may have absorbed part of a mismatch that a later effect explains
//! better. On a full-size Lorentzian breakaway set (`lorentz_stribeck`, level 1, seed 1,
//! docs/diagnosis.md), before the candidates' nested start ([`super::select`]), round 1 accepted
//! a power-law drag and round 2 an input compliance, both consistent with zero once round 3's
//! Stribeck member was in (the drag's coefficient 0.02 ± 3.3 s⁻², the lag −0.03 ± 0.04°), and the
//! verdict was the drag.
//!
//! Once every effect is in, each accepted effect is tested in the final model, in ascending order
//! of the Wald z of its parameters there ([`added_parameters_z`], the test the rounds apply to a
//! candidate's added parameters). When that z is below the threshold of the round that accepted
//! the effect, the model without it is refitted to convergence and its held-out prediction
//! compared with the final model's ([`compare`]); when the final model does not predict
//! significantly better (held-out z below the same threshold), the effect is dropped and the
//! model without it becomes the final model. Only with two or more accepted effects, each effect
//! tried once; an effect is never dropped when it is the last one.

use super::judge::HeldOut;
use super::judge::{added_parameters_z, compare, heldout};
use super::regression::Term;
use super::select::{try_refit_state, ModelState, SelectCtx, Tried};
use super::shooting::Reselect;
use crate::progress::{stage, Observer};

/// An accepted effect dropped by the backward check.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dropped {
    /// The Wald z of its parameters in the final model with it.
    pub wald_z: f64,
    /// The held-out z of the final model with it against the model without it.
    pub heldout_z: f64,
}

/// Positions in θ of `fin` of the parameters `t`'s effect added: its coefficients (the terms that
/// are not shape parameters, and the latency of `sensor_latency`), and every term of it (shape
/// parameters included), to be removed with it.
fn positions(fin: &ModelState, t: &Tried) -> (Vec<usize>, Vec<usize>) {
    let (mut coef, mut all) = (Vec::new(), Vec::new());
    for term in &t.candidate.terms {
        if let Some(k) = fin.terms.iter().position(|x| x == term) {
            all.push(k);
            if !matches!(term, Term::Shape(_)) {
                coef.push(k);
            }
        }
    }
    if t.candidate.effect.id == "sensor_latency" && fin.fit_latency {
        coef.push(fin.terms.len());
    }
    (coef, all)
}

/// `fin` without `t`'s effect (the terms at `drop`, and the latency for `sensor_latency`),
/// refitted to convergence from `fin`'s values (windows re-selected at the solution) with its
/// held-out errors ([`try_refit_state`]); `None` when the refit fails.
fn without(ctx: &SelectCtx, fin: &ModelState, t: &Tried, drop: &[usize]) -> Option<ModelState> {
    let nt = fin.terms.len();
    let kept: Vec<usize> = (0..nt).filter(|k| !drop.contains(k)).collect();
    let latency = fin.fit_latency && t.candidate.effect.id != "sensor_latency";
    let mut theta0: Vec<f64> = kept.iter().map(|&k| fin.fit.theta[k]).collect();
    if latency {
        theta0.push(fin.fit.theta[nt]);
    }
    let terms: Vec<Term> = kept.iter().map(|&k| fin.terms[k]).collect();
    let st = ModelState {
        terms: terms.clone(),
        fit_latency: latency,
        effects: without_first(&fin.effects, &t.candidate.effect),
        ..fin.clone()
    };
    try_refit_state(ctx, &st, terms, &theta0, Reselect::Always, true)
}

/// `effects` without the first entry equal to `e` (an effect id such as `unexplained` may be
/// accepted more than once).
fn without_first(
    effects: &[super::catalog::Effect],
    e: &super::catalog::Effect,
) -> Vec<super::catalog::Effect> {
    let mut out = effects.to_vec();
    if let Some(k) = out.iter().position(|x| x == e) {
        out.remove(k);
    }
    out
}

/// The backward check on the final model `fin` over the accepted effects of `tried` (see the
/// module): returns the final model, with `accepted` cleared and `dropped` set on every effect
/// dropped.
pub fn backward(
    ctx: &SelectCtx,
    mut fin: ModelState,
    tried: &mut [Tried],
    progress: &dyn Observer,
) -> ModelState {
    let accepted: Vec<usize> = (0..tried.len()).filter(|&i| tried[i].accepted).collect();
    if accepted.len() < 2 {
        return fin;
    }
    let mut order: Vec<(usize, f64)> = accepted
        .iter()
        .map(|&i| {
            (
                i,
                added_parameters_z(&fin.fit, &positions(&fin, &tried[i]).0),
            )
        })
        .collect();
    order.sort_by(|a, b| a.1.total_cmp(&b.1));
    // the final model's held-out errors computed as the reduced model's are (one-step
    // leave-fold-out refits from the converged fit): the final model may carry those of the
    // judge's refit with its shapes held at their starts, and the comparison must not set a
    // converged model against a stale one; computed once per final model
    let mut fin_held: Option<HeldOut> = None;
    for (i, _) in order {
        if tried.iter().filter(|t| t.accepted).count() < 2 {
            break;
        }
        let (coef, all) = positions(&fin, &tried[i]);
        let z = added_parameters_z(&fin.fit, &coef);
        if coef.is_empty() || z >= tried[i].z_crit {
            continue;
        }
        let Some(reduced) = without(ctx, &fin, &tried[i], &all) else {
            continue;
        };
        let held = fin_held.get_or_insert_with(|| {
            heldout(
                &fin.model(ctx.runs, ctx.geo, ctx.tol),
                &fin.fit,
                (ctx.wins, ctx.folds),
                ctx.shooting,
            )
        });
        let cmp = compare(&reduced.held, held, ctx.wins, ctx.runs);
        let drop = !cmp.improves(tried[i].z_crit);
        stage(
            progress,
            &format!(
                "backward check: {} (round {}) has Wald z {z:.2} in the final model (threshold \
                 {:.2}); the model with it predicts the held-out windows at z = {:.2} against \
                 the model without it: {}",
                tried[i].candidate.effect.id,
                tried[i].round,
                tried[i].z_crit,
                cmp.z,
                if drop { "dropped" } else { "kept" }
            ),
        );
        if drop {
            tried[i].accepted = false;
            tried[i].dropped = Some(Dropped {
                wald_z: z,
                heldout_z: cmp.z,
            });
            fin_held = Some(reduced.held.clone());
            fin = reduced;
        }
    }
    fin
}
