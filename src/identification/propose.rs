//! Proposals by the weak form: for the current model, every catalog family's best member and the
//! best dictionary terms, each with starting values for the refit by simulation. The weak form
//! only proposes; [`super::judge`] decides by simulation on held-out runs.

use super::catalog::{catalog, dictionary, same_slot, Effect};
use super::model::Geometry;
use super::preprocess::CleanRun;
use super::regression::{build, delta_bic, fit, Design, LinFit, Term, WeakOptions};

/// A candidate effect to judge.
#[derive(Debug, Clone, PartialEq)]
pub struct Candidate {
    /// The effect (for dictionary terms an `unexplained` entry naming the term).
    pub effect: Effect,
    /// The new terms.
    pub terms: Vec<Term>,
    /// Weak-form coefficients of the current terms followed by the new ones, fitted together.
    pub weak_coef: Vec<f64>,
    /// Weak-form coefficients of the current terms alone (the same design).
    pub weak_coef_current: Vec<f64>,
    /// `sensor_latency`: the profiled τ and its 1σ, s.
    pub latency: Option<(f64, f64)>,
    /// ΔBIC of the weak form (effective n) against the current terms.
    pub weak_dbic: f64,
}

/// What the proposer needs.
#[derive(Debug, Clone, Copy)]
pub struct ProposeCtx<'a> {
    /// Runs.
    pub runs: &'a [CleanRun],
    /// Geometry of the force shape.
    pub geo: &'a Geometry,
    /// Weak-form options.
    pub weak: &'a WeakOptions,
    /// Half-width of the latency profile, s.
    pub latency_span: f64,
    /// Most dictionary proposals per round.
    pub max_dictionary: usize,
}

/// The `unexplained` entry for dictionary terms.
pub fn unexplained(terms: Vec<Term>) -> Effect {
    Effect {
        id: "unexplained",
        class: "unexplained",
        explanation: "structured residual that no catalogued term explains; named by its \
                      dictionary terms (params)",
        terms,
        candidates: vec![],
        discriminating_experiment: "",
    }
}

fn cols_of(d: &Design, terms: &[Term]) -> Vec<usize> {
    terms.iter().filter_map(|&t| d.col(t)).collect()
}

fn candidate(
    d: &Design,
    current: &[Term],
    cur: &LinFit,
    effect: Effect,
    latency: Option<(f64, f64)>,
) -> Option<Candidate> {
    let mut terms = current.to_vec();
    terms.extend(effect.terms.iter().copied());
    let f = fit(d, &cols_of(d, &terms))?;
    Some(Candidate {
        terms: effect.terms.clone(),
        weak_dbic: delta_bic(&f, cur),
        weak_coef: f.coef,
        weak_coef_current: cur.coef.clone(),
        effect,
        latency,
    })
}

/// Proposals for the model `current` (terms) at `latency`, given the effects already `accepted`.
/// Catalog families (effects sharing an id and slot) give their best member by ΔBIC when it
/// lowers the BIC at all; the dictionary gives its best `max_dictionary` terms with ΔBIC < −10.
pub fn propose(
    ctx: &ProposeCtx,
    current: &[Term],
    latency: Option<f64>,
    accepted: &[Effect],
) -> Vec<Candidate> {
    let lat = latency.unwrap_or(0.0);
    let mut all: Vec<Term> = current.to_vec();
    for e in catalog() {
        all.extend(
            e.terms
                .iter()
                .filter(|t| !all.contains(t))
                .copied()
                .collect::<Vec<_>>(),
        );
    }
    all.extend(
        dictionary()
            .into_iter()
            .filter(|t| !all.contains(t))
            .collect::<Vec<_>>(),
    );
    let d = build(ctx.runs, ctx.geo, &all, ctx.weak, lat);
    let Some(cur) = fit(&d, &cols_of(&d, current)) else {
        return vec![];
    };
    let mut out: Vec<Candidate> = Vec::new();
    for e in catalog() {
        if e.id == "static_friction" || accepted.iter().any(|a| same_slot(a, &e)) {
            continue;
        }
        if e.id == "sensor_latency" {
            if latency.is_none() {
                if let Some(c) = latency_candidate(ctx, current, &cur, e) {
                    out.push(c);
                }
            }
            continue;
        }
        if e.terms.iter().any(|t| current.contains(t)) {
            continue;
        }
        let Some(c) = candidate(&d, current, &cur, e, None) else {
            continue;
        };
        // one member per family (slot): the best by ΔBIC
        match out.iter_mut().find(|o| same_slot(&o.effect, &c.effect)) {
            Some(o) if o.weak_dbic <= c.weak_dbic => {}
            Some(o) => *o = c,
            None => out.push(c),
        }
    }
    out.retain(|c| c.weak_dbic < 0.0);
    let mut dict: Vec<Candidate> = dictionary()
        .into_iter()
        .filter(|t| !current.contains(t))
        .filter_map(|t| candidate(&d, current, &cur, unexplained(vec![t]), None))
        .filter(|c| c.weak_dbic < -10.0)
        .collect();
    dict.sort_by(|a, b| a.weak_dbic.total_cmp(&b.weak_dbic));
    dict.truncate(ctx.max_dictionary);
    out.extend(dict);
    out
}

/// The latency candidate: the BIC profiled over τ (driven rows shift α by −α̇τ), the minimum
/// refined by a parabola; `None` without an interior minimum.
fn latency_candidate(
    ctx: &ProposeCtx,
    current: &[Term],
    cur: &LinFit,
    effect: Effect,
) -> Option<Candidate> {
    if ctx.runs.iter().all(|r| r.ringdown) {
        return None;
    }
    let span = ctx.latency_span;
    let n = 24;
    let ne = cur.n_eff.max(2.0);
    let cols: Vec<usize> = (0..current.len()).collect();
    let mut prof = Vec::new();
    for k in 0..=n {
        let tau = -span + 2.0 * span * k as f64 / n as f64;
        let d = build(ctx.runs, ctx.geo, current, ctx.weak, tau);
        let f = fit(&d, &cols)?;
        prof.push((tau, ne * f.chi2.ln()));
    }
    let (kbest, _) = prof
        .iter()
        .enumerate()
        .min_by(|a, b| a.1 .1.total_cmp(&b.1 .1))?;
    if kbest == 0 || kbest == n {
        return None;
    }
    // parabola through the three points around the minimum; −2 ln L ≈ n_eff ln χ²
    let (t0, y0) = prof[kbest - 1];
    let (t1, y1) = prof[kbest];
    let (_, y2) = prof[kbest + 1];
    let h = t1 - t0;
    let curv = (y0 - 2.0 * y1 + y2) / (h * h);
    let (tau, tau_err) = if curv > 0.0 {
        (
            t1 - 0.5 * h * (y2 - y0) / (y2 - 2.0 * y1 + y0),
            (2.0 / curv).sqrt(),
        )
    } else {
        (t1, f64::NAN)
    };
    let d = build(ctx.runs, ctx.geo, current, ctx.weak, tau);
    let f = fit(&d, &cols)?;
    let dbic = ne * (f.chi2 / cur.chi2).ln() + ne.ln();
    Some(Candidate {
        effect,
        terms: vec![],
        weak_coef: f.coef,
        weak_coef_current: cur.coef.clone(),
        latency: Some((tau, tau_err)),
        weak_dbic: dbic,
    })
}
