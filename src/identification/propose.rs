//! Proposals by the weak form: for the current model, every catalog family's best member and the
//! best dictionary terms, each with starting values for the refit by simulation. The weak form
//! only proposes; [`super::judge`] decides by simulation on held-out runs.

use super::catalog::{
    catalog, dictionary, member_choice, same_proposal, same_slot, Effect, MemberChoice,
};
use super::model::{Geometry, Shape};
use super::preprocess::CleanRun;
use super::regression::{
    build, delta_bic, fit, grid_hundredths, grid_weight, load_grid_term, Design, LinFit, Term,
    WeakOptions,
};
use super::spec::column_term;

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

/// The terms with a weak-form column: shape parameters ([`Term::Shape`]) have none.
pub fn weak_terms(terms: &[Term]) -> Vec<Term> {
    terms
        .iter()
        .filter(|t| !matches!(t, Term::Shape(_)))
        .copied()
        .collect()
}

/// Coefficients aligned with `terms` from the weak-form coefficients `coef` of its column terms
/// (in order); a shape parameter takes its value from `shapes`, else 0 (a shape parameter of the
/// current model: [`Candidate::weak_coef`] − [`Candidate::weak_coef_current`] leaves its refitted
/// value unchanged).
fn align(terms: &[Term], coef: &[f64], shapes: &[(Shape, f64)]) -> Vec<f64> {
    let mut it = coef.iter();
    terms
        .iter()
        .map(|t| match t {
            Term::Shape(s) => shapes
                .iter()
                .find(|x| x.0 == *s)
                .map(|x| x.1)
                .unwrap_or(0.0),
            _ => it.next().copied().unwrap_or(0.0),
        })
        .collect()
}

/// The weak-form columns of a refitted model's `terms` at its θ: the drag at its fitted exponent
/// (rounded to a tenth), shape parameters as zero columns (so row · θ stays aligned).
pub fn weak_columns(terms: &[Term], theta: &[f64]) -> Vec<Term> {
    let shapes: Vec<(Shape, f64)> = terms
        .iter()
        .zip(theta)
        .filter_map(|(t, &v)| match t {
            Term::Shape(s) => Some((*s, v)),
            _ => None,
        })
        .collect();
    terms.iter().map(|&t| column_term(t, &shapes)).collect()
}

fn candidate(
    d: &Design,
    current: &[Term],
    cur: &LinFit,
    effect: Effect,
    latency: Option<(f64, f64)>,
    shapes: &[(Shape, f64)],
) -> Option<Candidate> {
    let mut terms = current.to_vec();
    terms.extend(effect.terms.iter().copied());
    let cols: Vec<Term> = weak_terms(&terms)
        .into_iter()
        .map(|t| column_term(t, shapes))
        .collect();
    let f = fit(d, &cols_of(d, &cols))?;
    if f.cols.len() != cols.len() {
        return None;
    }
    Some(Candidate {
        terms: effect.terms.clone(),
        weak_dbic: delta_bic(&f, cur),
        weak_coef: align(&terms, &f.coef, shapes),
        weak_coef_current: align(current, &cur.coef, &[]),
        effect,
        latency,
    })
}

/// Exponents (× 10) of the drag family's weak-form profile (p = 1 is left out: it is the
/// viscous column of ζ).
pub const DRAG_EXPONENT_GRID: [u8; 6] = [12, 15, 18, 20, 25, 30];

/// Weight-to-force ratios ρ = |W|/F₀ (× 10) of the load family's weak-form profile.
pub const LOAD_WEIGHT_GRID: [u8; 8] = [0, 5, 10, 15, 20, 30, 50, 80];

/// Directions ψ of the weight (degrees from −ẑ about the output shaft: the tilt of the set-up)
/// of the load family's weak-form profile. Half a turn: the gear's symmetry (α, β) → (−α, −β)
/// reverses the dipole force's vertical component and keeps the others, so a weight at ψ and at
/// 180° − ψ load the bearings alike on recordings that sample both signs.
pub const LOAD_TILT_GRID: [i16; 7] = [-90, -60, -30, 0, 30, 60, 90];

/// The weights (ρ_z, ρ_n) = ρ (cos ψ, sin ψ) of the load family's weak-form profile, ρ on
/// [`LOAD_WEIGHT_GRID`] and ψ on [`LOAD_TILT_GRID`], in hundredths as their [`Term::LoadGrid`]
/// columns hold them (ρ = 0 once).
pub fn load_weight_grid() -> Vec<[f64; 2]> {
    let mut v: Vec<[f64; 2]> = vec![[0.0; 2]];
    for &r in &LOAD_WEIGHT_GRID[1..] {
        let rho = f64::from(r) / 10.0;
        for &psi in &LOAD_TILT_GRID {
            let (s, c) = f64::from(psi).to_radians().sin_cos();
            v.push(grid_weight(
                grid_hundredths(rho * c),
                grid_hundredths(rho * s),
            ));
        }
    }
    v
}

/// Widths w (× 100, rad/s) of the Stribeck family's weak-form profile: output speeds from a
/// tenth of a rad/s to the few rad/s of the driven runs.
pub const STRIBECK_WIDTH_GRID: [u8; 7] = [10, 20, 35, 50, 75, 120, 200];

/// Shapes δ (× 10) of the Stribeck family's weak-form profile: the exponential and the Gaussian
/// decay (δ is then fitted by simulation).
pub const STRIBECK_POWER_GRID: [u8; 2] = [10, 20];

/// The weak-form grid columns of the families' profiles.
fn grid_columns() -> Vec<Term> {
    let mut v: Vec<Term> = DRAG_EXPONENT_GRID
        .iter()
        .map(|&p| Term::PowDrag(p))
        .collect();
    for d in STRIBECK_POWER_GRID {
        v.extend(
            STRIBECK_WIDTH_GRID
                .iter()
                .map(|&w| Term::StribeckGrid(w, d)),
        );
    }
    for radial in [false, true] {
        v.extend(
            load_weight_grid()
                .into_iter()
                .map(|w| load_grid_term(w, radial)),
        );
    }
    v
}

/// The shape values to profile for effect `e` (one empty entry for a family without shape).
fn shape_grid(e: &Effect) -> Vec<Vec<(Shape, f64)>> {
    if e.terms.contains(&Term::Shape(Shape::DragExponent)) {
        DRAG_EXPONENT_GRID
            .iter()
            .map(|&p| vec![(Shape::DragExponent, f64::from(p) / 10.0)])
            .collect()
    } else if e.terms.contains(&Term::Shape(Shape::StribeckWidth)) {
        STRIBECK_POWER_GRID
            .iter()
            .flat_map(|&d| {
                STRIBECK_WIDTH_GRID.iter().map(move |&w| {
                    vec![
                        (Shape::StribeckWidth, f64::from(w) / 100.0),
                        (Shape::StribeckPower, f64::from(d) / 10.0),
                    ]
                })
            })
            .collect()
    } else if e.terms.contains(&Term::Shape(Shape::LoadWeight)) {
        load_weight_grid()
            .into_iter()
            .map(|[z, n]| vec![(Shape::LoadWeight, z), (Shape::LoadSide, n)])
            .collect()
    } else {
        vec![vec![]]
    }
}

/// The family's best member by the weak form: for a family with a shape parameter the
/// parameter profiled on its coarse grid (the start value of the refit by simulation). The drag
/// family is proposed by its best exponent but starts from the quadratic member (p = 2): the
/// weak form's velocities carry noise, which biases the columns |β̇|^p the more the larger p
/// (errors in variables), so its best exponent is not a reliable start; the simulation fits p.
fn family_candidate(d: &Design, current: &[Term], cur: &LinFit, e: Effect) -> Option<Candidate> {
    let all: Vec<Candidate> = shape_grid(&e)
        .iter()
        .filter_map(|shapes| candidate(d, current, cur, e.clone(), None, shapes))
        .collect();
    let best = all
        .iter()
        .min_by(|a, b| a.weak_dbic.total_cmp(&b.weak_dbic))?
        .clone();
    if !e.terms.contains(&Term::Shape(Shape::DragExponent)) {
        return Some(best);
    }
    let quadratic = candidate(d, current, cur, e, None, &[(Shape::DragExponent, 2.0)])?;
    Some(Candidate {
        weak_dbic: best.weak_dbic,
        ..quadratic
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
    let weak_current = weak_terms(current);
    let mut all: Vec<Term> = weak_current.clone();
    for e in catalog() {
        all.extend(
            weak_terms(&e.terms)
                .into_iter()
                .filter(|t| !all.contains(t))
                .collect::<Vec<_>>(),
        );
    }
    all.extend(grid_columns());
    all.extend(
        dictionary()
            .into_iter()
            .filter(|t| !all.contains(t))
            .collect::<Vec<_>>(),
    );
    let d = build(ctx.runs, ctx.geo, &all, ctx.weak, lat);
    let Some(cur) = fit(&d, &cols_of(&d, &weak_current)) else {
        return vec![];
    };
    let mut out: Vec<Candidate> = Vec::new();
    for e in catalog() {
        // the breakaway at rest only (no terms) is profiled over the stick phases (breakaway.rs)
        if (e.id == "static_friction" && e.terms.is_empty())
            || accepted.iter().any(|a| same_slot(a, &e))
        {
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
        let Some(c) = family_candidate(&d, current, &cur, e) else {
            continue;
        };
        if member_choice(c.effect.id) != MemberChoice::WeakForm {
            // nested or alternative members: all proposed, the held-out judge picks (select.rs)
            out.push(c);
            continue;
        }
        // one member per family (slot; a drift's per kind of clock): the best by ΔBIC
        match out.iter_mut().find(|o| same_proposal(&o.effect, &c.effect)) {
            Some(o) if o.weak_dbic <= c.weak_dbic => {}
            Some(o) => *o = c,
            None => out.push(c),
        }
    }
    out.retain(|c| c.weak_dbic < 0.0);
    let mut dict: Vec<Candidate> = dictionary()
        .into_iter()
        .filter(|t| !current.contains(t))
        .filter_map(|t| candidate(&d, current, &cur, unexplained(vec![t]), None, &[]))
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
    let weak_current = weak_terms(current);
    let cols: Vec<usize> = (0..weak_current.len()).collect();
    let mut prof = Vec::new();
    for k in 0..=n {
        let tau = -span + 2.0 * span * k as f64 / n as f64;
        let d = build(ctx.runs, ctx.geo, &weak_current, ctx.weak, tau);
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
    let d = build(ctx.runs, ctx.geo, &weak_current, ctx.weak, tau);
    let f = fit(&d, &cols)?;
    let dbic = ne * (f.chi2 / cur.chi2).ln() + ne.ln();
    Some(Candidate {
        effect,
        terms: vec![],
        weak_coef: align(current, &f.coef, &[]),
        weak_coef_current: align(current, &cur.coef, &[]),
        latency: Some((tau, tau_err)),
        weak_dbic: dbic,
    })
}
