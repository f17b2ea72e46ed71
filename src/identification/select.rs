//! A round of the selection ([`super::judge`]'s rule): the weak form proposes candidates for the
//! current model ([`super::propose`]), every candidate is refitted by simulation on top of the
//! accepted ones and judged by its held-out prediction, and the best significant one is accepted
//! (with its close rival, when each is significant on top of the other, or else the rival in a
//! branch of its own: [`super::beam`]). Every candidate tried is kept with its numbers. Also the refits of the final model (polish, profiles).

use super::catalog::{member_choice, same_slot, Effect, MemberChoice};
use super::judge::{
    added_parameters_z, compare, heldout, heldout_after, z_threshold, Comparison, Folds, HeldOut,
};
use super::model::Geometry;
use super::preprocess::CleanRun;
use super::profile::{delta_chi2, profile_shape, profile_side, ProfileSide, ShapeProfile};
use super::propose::{propose, Candidate, ProposeCtx};
use super::regression::Term;
use super::shooting::{
    par_map, refit, refit_sharing, Reselect, ShootingOptions, SimFit, SimModel, StartSearches, Win,
    CONVERGED_PATIENCE,
};
use super::spec::{fix_shapes, free_shapes};
use crate::progress::{stage, Observer};

/// A model with its refit by simulation and its held-out errors.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelState {
    /// Terms.
    pub terms: Vec<Term>,
    /// Whether the latency is fitted (last entry of θ).
    pub fit_latency: bool,
    /// The refit.
    pub fit: SimFit,
    /// Held-out errors.
    pub held: HeldOut,
    /// Effects accepted so far.
    pub effects: Vec<Effect>,
}

impl ModelState {
    /// The simulated model, its windows simulated at the relative tolerance `tol`.
    pub fn model<'a>(&self, runs: &'a [CleanRun], geo: &Geometry, tol: f64) -> SimModel<'a> {
        SimModel {
            runs,
            geo: *geo,
            terms: self.terms.clone(),
            latency: self.latency(),
            fit_latency: self.fit_latency,
            eta_static_excess: 0.0,
            held_shapes: Vec::new(),
            roughness: 0.0,
            session: Default::default(),
            tol,
        }
    }
    /// The latency, s (0 when not fitted).
    pub fn latency(&self) -> f64 {
        if self.fit_latency {
            self.fit.theta[self.terms.len()]
        } else {
            0.0
        }
    }
}

/// A candidate as tried in a round.
#[derive(Debug, Clone, PartialEq)]
pub struct Tried {
    /// Round (1-based).
    pub round: usize,
    /// The candidate.
    pub candidate: Candidate,
    /// Its comparison against the model of that round on all judging windows (`None`: the
    /// refit failed or the candidate did not pass the screening).
    pub cmp: Option<Comparison>,
    /// Its screening comparison (every second judging window).
    pub screen: Option<Comparison>,
    /// Its in-sample comparison on the screening's windows when its refit there fitted them
    /// significantly worse than the current model (z ≤ −[`SCREEN_Z`] with a χ² loss); the
    /// screening then stopped before the held-out prediction, and `screen` is `None`
    /// ([`Screening::FitsWorse`]).
    pub screen_fit: Option<Comparison>,
    /// The screening's leader when it predicts this candidate's screening windows significantly
    /// better: the candidate was then not refitted on all windows ([`judge_round`]).
    pub screen_beaten: Option<BeatenOnScreening>,
    /// The threshold of the round.
    pub z_crit: f64,
    /// Accepted.
    pub accepted: bool,
    /// The refitted model with it (kept for the accepted one).
    pub state: Option<ModelState>,
    /// [`added_parameters_z`] of the parameters the candidate adds, in its refit on all judging
    /// windows (`None` when it was not refitted on them).
    pub added_z: Option<f64>,
    /// For a significant member of a family whose members the judge picks (not the smallest):
    /// the held-out comparison of this member against the smaller member chosen before it (the
    /// larger member replaces it when it improves on it, [`Comparison::improves`]).
    pub member: Option<Comparison>,
    /// Accepted in its round and dropped by the backward check ([`super::backward`]).
    pub dropped: Option<super::backward::Dropped>,
    /// Accepted on the other branch of a fork in its round, the branch that was left
    /// ([`super::beam`]).
    pub forked: bool,
    /// A close rival of the round's accepted candidate, significant on top of it and it on top of
    /// this one: accepted with it in the same round, as refitted on top of it (the entries after
    /// the round's, [`super::beam`]'s joint check).
    pub joined: bool,
    /// Judged on top of the model with this effect, accepted in the same round (the members of
    /// a joined rival's slot refitted on top of the accepted one, [`super::beam`]); `None` for
    /// the round's own candidates, judged on the round's model.
    pub on_top_of: Option<&'static str>,
}

/// A candidate of a round whose screening windows the round's screening leader
/// ([`judge_round`]) predicts significantly better.
#[derive(Debug, Clone, PartialEq)]
pub struct BeatenOnScreening {
    /// The leader (an index into the round's candidates, as [`judge_round`] returns them).
    pub leader: usize,
    /// The leader's effect and terms, "effect (terms)".
    pub label: String,
    /// The paired comparison of the leader against the candidate on the screening's windows
    /// (positive gain: the leader predicts better).
    pub cmp: Comparison,
}

impl Tried {
    /// The held-out χ² gain of its comparison on all judging windows (−∞ without one: never the
    /// largest).
    pub fn gain(&self) -> f64 {
        self.cmp.map_or(f64::NEG_INFINITY, |c| c.gain)
    }
}

/// What the selection needs.
#[derive(Debug, Clone, Copy)]
pub struct SelectCtx<'a> {
    /// Runs.
    pub runs: &'a [CleanRun],
    /// Geometry of the force shape.
    pub geo: &'a Geometry,
    /// Judging windows.
    pub wins: &'a [Win],
    /// Folds.
    pub folds: &'a Folds,
    /// Refit options.
    pub shooting: &'a ShootingOptions,
    /// Relative tolerance of the window simulations ([`super::diagnose::DiagnoseOptions::tol`]).
    pub tol: f64,
    /// The proposer.
    pub propose: &'a ProposeCtx<'a>,
    /// Most effects accepted (one per round, two in a round whose close rivals are accepted
    /// together: [`super::beam`]); also the most rounds.
    pub max_effects: usize,
    /// Whether a round with close rivals checks them jointly and else forks
    /// ([`super::beam::select`]).
    pub fork_close_rivals: bool,
}

/// The terms `cand` adds as judged, with their weak-form values: a family's shape parameter held
/// at the proposal's grid value ([`fix_shapes`]; it is fitted by simulation in [`polish`]).
fn judged_terms(cur: &ModelState, cand: &Candidate) -> (Vec<Term>, Vec<f64>) {
    fix_shapes(&cand.terms, &cand.weak_coef[cur.terms.len()..])
}

/// The starting θ of `cand` on top of `cur`: the current refit shifted by the weak form's change
/// when the candidate's terms are added, the new terms at their weak-form values, the latency at
/// the current fit or the profiled value.
fn start_theta(cur: &ModelState, cand: &Candidate) -> Vec<f64> {
    let nc = cur.terms.len();
    let mut th: Vec<f64> = (0..nc)
        .map(|k| cur.fit.theta[k] + cand.weak_coef[k] - cand.weak_coef_current[k])
        .collect();
    th.extend(judged_terms(cur, cand).1);
    if cur.fit_latency {
        th.push(cur.latency());
    } else if let Some((tau, _)) = cand.latency {
        th.push(tau);
    }
    th
}

/// A candidate refitted on a set of windows ([`evaluate_on`]).
enum Refitted {
    /// The model with it, its held-out errors predicted.
    Judged(Box<ModelState>),
    /// Its refit fits the windows significantly worse than the current model does (the
    /// in-sample comparison, [`fit_gain`]): its held-out errors are not predicted.
    FitsWorse(Comparison),
}

/// The in-sample comparison of a candidate's refit (its windows' χ² `after`) with the current
/// model (`before`, its in-sample χ² of the same windows): [`compare`] with the fitted χ² in
/// place of the held-out ones.
fn fit_gain(
    before: &[Option<f64>],
    after: &[Option<f64>],
    wins: &[Win],
    runs: &[CleanRun],
) -> Comparison {
    // compare reads only `chi2`
    let as_held = |c: &[Option<f64>]| HeldOut {
        chi2: c.to_vec(),
        chi2_fit: Vec::new(),
    };
    compare(&as_held(before), &as_held(after), wins, runs)
}

/// Refits `cur` + `cand` on the windows `wins` (those its start cannot follow tried again at
/// the solution as `reselect` says;
/// [`refit_from_better_start`] with `cur_followed` the number of them the current model follows)
/// and gives its held-out errors on them. With `gate` (the current model's in-sample χ² of
/// `wins`), a refit that fits them significantly worse than the current model ([`fit_gain`]
/// worsens at [`SCREEN_Z`], the screening's threshold mirrored) is not predicted held out:
/// `cand` nests the current model, whose θ is a point of its parameter space, so such a refit
/// has run away from the minimum it would be judged at (a weak-form start far off), and its
/// prediction costs more than the refit (the leave-fold-out predictions search a state for
/// every window it does not follow).
fn evaluate_on(
    ctx: &SelectCtx,
    wins: &[Win],
    cur_followed: usize,
    (cur, cand): (&ModelState, &Candidate),
    (reselect, searches): (Reselect, Option<&StartSearches>),
    gate: Option<&[Option<f64>]>,
) -> Option<Refitted> {
    let mut terms = cur.terms.clone();
    terms.extend(judged_terms(cur, cand).0);
    let fit_latency = cur.fit_latency || cand.latency.is_some();
    let theta0 = start_theta(cur, cand);
    let model = SimModel {
        runs: ctx.runs,
        geo: *ctx.geo,
        terms: terms.clone(),
        latency: if fit_latency {
            theta0[terms.len()]
        } else {
            0.0
        },
        fit_latency,
        eta_static_excess: 0.0,
        tol: ctx.tol,
        held_shapes: Vec::new(),
        roughness: 0.0,
        session: Default::default(),
    };
    let opts = ShootingOptions {
        reselect,
        ..*ctx.shooting
    };
    let fit = refit_from_better_start(&model, cur, &theta0, wins, &opts, (cur_followed, searches))?;
    let in_sample = fit.window_chi2(&model, wins);
    if let Some(before) = gate {
        let c = fit_gain(before, &in_sample.0, wins, ctx.runs);
        if c.worsens(SCREEN_Z) {
            return Some(Refitted::FitsWorse(c));
        }
    }
    let held = heldout_after(&model, &fit, (wins, ctx.folds), ctx.shooting, in_sample);
    let mut effects = cur.effects.clone();
    effects.push(cand.effect.clone());
    Some(Refitted::Judged(Box::new(ModelState {
        terms,
        fit_latency,
        fit,
        held,
        effects,
    })))
}

/// The refit of `model` (`cur` + `cand`) on `wins` from the weak-form start θ₀ and, when its
/// refit uses fewer of the windows than the current model follows (`cur_followed`), also from the
/// nested start: the current θ with the candidate's new coefficients (and a newly fitted latency)
/// at zero, which is the current model itself and follows its windows. The nested refit is kept
/// when it uses more windows; its start then is the current model's, and so is the start rms the
/// report gives for the candidate. The weak form determines some terms poorly: on a full-size set
/// with a Lorentzian breakaway it proposed a Stribeck excess of 151 s⁻² on top of a drag
/// (η ≈ 23 s⁻²); the refit from there used 103 of the screening's 149 windows and was 3.4·10⁵ in
/// χ² worse than the current model, and the judge would reject such an effect for its start, not
/// for its fit. Choosing by the windows used is part of the fit, not of the judgement (the
/// held-out errors are computed afterwards, for the refit kept).
fn refit_from_better_start(
    model: &SimModel,
    cur: &ModelState,
    theta0: &[f64],
    wins: &[Win],
    opts: &ShootingOptions,
    (cur_followed, searches): (usize, Option<&StartSearches>),
) -> Option<SimFit> {
    let fit = refit_sharing(model, theta0, wins, opts, searches);
    if fit.as_ref().is_some_and(|f| f.used.len() >= cur_followed) {
        return fit;
    }
    let nc = cur.terms.len();
    let mut nested: Vec<f64> = cur.fit.theta[..nc].to_vec();
    nested.resize(model.terms.len(), 0.0);
    if model.fit_latency {
        nested.push(if cur.fit_latency { cur.latency() } else { 0.0 });
    }
    let from_nested = refit(model, &nested, wins, opts);
    match (fit, from_nested) {
        (Some(a), Some(b)) => Some(if b.used.len() > a.used.len() { b } else { a }),
        (a, b) => a.or(b),
    }
}

/// Refits `cur` + `cand` on all judging windows and gives its held-out errors. When its start
/// follows fewer than half of the judging windows, the windows it cannot follow are tried again
/// at the solution ([`Reselect::OnceBelow`]): a large effect
/// that the current model misses leaves most driven windows unfollowable from the weak-form
/// start, and a candidate refitted on the rest (ring-downs, where a latency only shifts the
/// window's state) was judged on a refit that had not seen its evidence (docs/diagnosis.md,
/// "Known weaknesses": a 12 ms latency with a Wald z of 0 from 2 driven windows of 97). Not
/// always, and not in the screening ([`screen`]): re-selecting every candidate's windows raised
/// the CPU of a diagnosis by 45–85 % where the start follows nearly all of them.
pub fn evaluate(ctx: &SelectCtx, cur: &ModelState, cand: &Candidate) -> Option<ModelState> {
    evaluate_sharing(ctx, cur, cand, None)
}

/// [`evaluate`], the searches of the windows at the candidate's start shared with its
/// screening ([`screen_sharing`], the same `searches`).
pub fn evaluate_sharing(
    ctx: &SelectCtx,
    cur: &ModelState,
    cand: &Candidate,
    searches: Option<&StartSearches>,
) -> Option<ModelState> {
    let followed = cur.fit.used.len();
    let reselect = Reselect::OnceBelow(CANDIDATE_RESELECT_BELOW);
    match evaluate_on(
        ctx,
        ctx.wins,
        followed,
        (cur, cand),
        (reselect, searches),
        None,
    )? {
        Refitted::Judged(st) => Some(*st),
        Refitted::FitsWorse(_) => None,
    }
}

/// The fraction of the judging windows below which a candidate's refit re-selects its windows
/// ([`evaluate`]): fewer than half followed from the start.
pub const CANDIDATE_RESELECT_BELOW: f64 = 0.5;

/// The final model refitted to convergence (the judge's refits stop after a few
/// Levenberg–Marquardt steps from their warm starts: enough to judge, not to report), the windows
/// left out at its start tried again at the solution ([`Reselect::Always`]), with the
/// families' shape parameters freed ([`free_shapes`]): they are fitted here, by simulation, next
/// to the linear coefficients, and their σ come from this refit's covariance. Its held-out errors
/// are recomputed when no shape was freed; with shapes, the judged model's are kept (the one-step
/// leave-fold-out refits are first order, too coarse for a shape parameter and the coefficient
/// it trades off with).
pub fn polish(ctx: &SelectCtx, st: &ModelState) -> ModelState {
    if st.effects.is_empty() {
        return st.clone();
    }
    let (terms, theta0) = free_shapes(&st.terms, &st.fit.theta);
    let freed = terms != st.terms;
    try_refit_state(ctx, st, terms, &theta0, Reselect::Always, !freed).unwrap_or_else(|| st.clone())
}

/// The judging windows the final refit `fin` used, in its order (the fixed set of windows of its
/// profiles).
fn used_windows(ctx: &SelectCtx, fin: &ModelState) -> Vec<Win> {
    fin.fit
        .used
        .iter()
        .map(|&(w, _)| ctx.wins[w].clone())
        .collect()
}

/// A profile's refit of `model` (a quantity held outside θ) from `theta0` to convergence on the
/// fixed windows `wins` ([`used_windows`]): (Σ window χ² over all of them, θ). Windows left out at
/// the start are tried again at the solution ([`Reselect::Always`]): without, a held value far
/// from the fit loses the windows its start cannot follow, and its χ² (the lost ones by a fresh
/// state fit) comes out too high.
fn held_refit(
    ctx: &SelectCtx,
    model: &SimModel,
    theta0: &[f64],
    wins: &[Win],
) -> Option<(f64, Vec<f64>)> {
    let opts = ShootingOptions {
        patience: CONVERGED_PATIENCE,
        reselect: Reselect::Always,
        ..*ctx.shooting
    };
    let f = refit_to_convergence(model, theta0, wins, &opts)?;
    let chi2 = f
        .window_chi2(model, wins)
        .0
        .iter()
        .map(|c| c.unwrap_or(f64::INFINITY))
        .sum();
    Some((chi2, f.theta))
}

/// [`polish`], then every shape parameter of the final model profiled ([`profile_shape`], in
/// the order of its terms, each from the previous one's minimum) on the windows the polished
/// refit used, the others refitted to convergence at each held value ([`refit_to_convergence`],
/// warm-started from the nearest value); when the profiles' minimum
/// is below the polished fit's χ² on those windows, the model is refitted from it (free, like
/// [`polish`]): the polished refit crept from the grid start along a curved valley and stopped
/// short. Returns the final model and the profiles (their intervals give the shapes' σ and the
/// range of the headline sizes, [`super::findings::judged_finding`]). Only the final model is
/// profiled (10–14 held values per shape parameter, each a refit to convergence: the cost of the
/// profile, about 250 s CPU on a `ci` set with a drag, is far above the rest of the diagnosis).
pub fn polish_profiled(ctx: &SelectCtx, st: &ModelState) -> (ModelState, Vec<ShapeProfile>) {
    let fin = polish(ctx, st);
    let shapes: Vec<usize> = (0..fin.terms.len())
        .filter(|&k| matches!(fin.terms[k], Term::Shape(_)))
        .collect();
    if shapes.is_empty() {
        return (fin, Vec::new());
    }
    let wins = used_windows(ctx, &fin);
    let model = fin.model(ctx.runs, ctx.geo, ctx.tol);
    // every held value refitted to convergence (warm-started from the nearest one): a single
    // Levenberg–Marquardt run leaves ζ and the drag's q where the neighbour had them, and the
    // profile of a drag exponent of 1.5 then had its minimum at 1.96 (docs/diagnosis.md)
    let fit = |m: &SimModel, th: &[f64]| held_refit(ctx, m, th, &wins);
    let chi2_polished: f64 = fin.fit.resid.iter().map(|r| r * r).sum();
    let mut theta = fin.fit.theta.clone();
    let mut profiles = Vec::new();
    for k in shapes {
        if let Some(p) = profile_shape(&model, &theta, k, delta_chi2(&fin.fit, k), &fit) {
            theta = p.best.clone();
            profiles.push(p);
        }
    }
    let best = profiles.last().map(|p| p.chi2_min).unwrap_or(f64::INFINITY);
    if best >= chi2_polished {
        return (fin, profiles);
    }
    let refitted = try_refit_state(
        ctx,
        &fin,
        fin.terms.clone(),
        &theta,
        Reselect::Always,
        false,
    );
    (refitted.unwrap_or(fin), profiles)
}

/// The profile σ of the breakaway excess η_Δs (θ entry [`Term::StaticExcess`]) of a final model
/// whose friction family has shape parameters (the Stribeck member η_Δs exp(−(|β̇|/w)^δ)): the
/// excess held at values on each side ([`profile_side`]) with every other parameter refitted to
/// convergence on the windows the final refit used (the held value is the model's
/// `eta_static_excess`, the term out of θ), the rise of their Σ window χ² over the final refit's
/// measured against Δ ([`delta_chi2`]). The covariance σ is the curvature at the minimum of a
/// valley that curves through (w, δ, η_Δs) and can be several times too small (docs/diagnosis.md,
/// "The Stribeck member's σ"). Returns (lower side, upper side); `None` when the model has no
/// excess with a shape or its σ is not finite. Costs two to four refits to convergence.
pub fn excess_profile(ctx: &SelectCtx, fin: &ModelState) -> Option<(ProfileSide, ProfileSide)> {
    let k = fin.terms.iter().position(|t| *t == Term::StaticExcess)?;
    if !fin.terms.iter().any(|t| matches!(t, Term::Shape(_))) {
        return None;
    }
    let (value, sigma) = (fin.fit.theta[k], fin.fit.err[k]);
    if !(sigma.is_finite() && sigma > 0.0 && value.is_finite()) {
        return None;
    }
    let wins = used_windows(ctx, fin);
    let model = fin.model(ctx.runs, ctx.geo, ctx.tol);
    // the final refit's χ² on its own windows (`wins`, in its order): its residuals
    let chi_min: f64 = fin.fit.resid.iter().map(|r| r * r).sum();
    let mut terms = fin.terms.clone();
    terms.remove(k);
    let delta = delta_chi2(&fin.fit, k);
    let side = |dir: f64| {
        // each held value warm-started from the last one on its side
        let mut warm = fin.fit.theta.clone();
        warm.remove(k);
        let rise = |v: f64| {
            let m = SimModel {
                terms: terms.clone(),
                eta_static_excess: model.eta_static_excess + v,
                ..model.clone()
            };
            let (c, th) = held_refit(ctx, &m, &warm, &wins)?;
            warm = th;
            c.is_finite().then_some(c - chi_min)
        };
        profile_side(rise, value, sigma, delta, dir, 0.0)
    };
    Some((side(-1.0)?, side(1.0)?))
}

/// `st` with `terms` refitted from `theta0` to convergence ([`refit_to_convergence`] at
/// [`CONVERGED_PATIENCE`]; windows re-selected at the solution as `reselect` says), its held-out
/// errors recomputed when `new_heldout` (else kept); `None` when the refit fails.
pub fn try_refit_state(
    ctx: &SelectCtx,
    st: &ModelState,
    terms: Vec<Term>,
    theta0: &[f64],
    reselect: Reselect,
    new_heldout: bool,
) -> Option<ModelState> {
    let model = SimModel {
        terms: terms.clone(),
        ..st.model(ctx.runs, ctx.geo, ctx.tol)
    };
    let opts = ShootingOptions {
        patience: CONVERGED_PATIENCE,
        reselect,
        ..*ctx.shooting
    };
    let fit = refit_to_convergence(&model, theta0, ctx.wins, &opts)?;
    let held = if new_heldout {
        heldout(&model, &fit, (ctx.wins, ctx.folds), ctx.shooting)
    } else {
        st.held.clone()
    };
    Some(ModelState {
        terms,
        fit,
        held,
        ..st.clone()
    })
}

/// Indices into θ of `st` of the parameters it adds to `cur`: the coefficients of its new terms
/// (not the shape parameters, held in the judge's refit) and the latency when newly fitted.
fn added(cur: &ModelState, st: &ModelState) -> Vec<usize> {
    let mut idx: Vec<usize> = (cur.terms.len()..st.terms.len())
        .filter(|&k| !matches!(st.terms[k], Term::Shape(_)))
        .collect();
    if st.fit_latency && !cur.fit_latency {
        idx.push(st.terms.len());
    }
    idx
}

/// The accepted model of a round refitted to convergence (shapes held, windows not re-selected)
/// with its held-out errors, so that the next round's candidates are judged against a model at
/// its optimum ([`try_refit_state`]; `st` itself when the refit fails).
pub fn converge(ctx: &SelectCtx, st: &ModelState) -> ModelState {
    try_refit_state(
        ctx,
        st,
        st.terms.clone(),
        &st.fit.theta,
        Reselect::Never,
        true,
    )
    .unwrap_or_else(|| st.clone())
}

/// Most restarts of the final refit from its own solution ([`refit_to_convergence`]).
pub const MAX_CONVERGE_RESTARTS: usize = 8;

/// [`refit`] from `theta0`, restarted from its own solution while the optimiser stopped on its
/// evaluation budget rather than on its tolerances (at most [`MAX_CONVERGE_RESTARTS`] times; the
/// fit's `converged` says whether it got there). A shape parameter and the coefficient it trades
/// off with (the Stribeck width w and excess η_Δs of η + η_Δs exp(−(|β̇|/w)^δ)) lie along a
/// curved valley of the window χ²: a fit stopped on its budget part-way along it is biased, and
/// the Gauss–Newton covariance taken there is not the σ of any minimum (on a set with w = 1.5,
/// η_Δs = 0.6 η one budget gave w = 1.83 ± 0.007, η_Δs = 0.52 η ± 0.001 η).
pub fn refit_to_convergence(
    model: &SimModel,
    theta0: &[f64],
    wins: &[Win],
    opts: &ShootingOptions,
) -> Option<SimFit> {
    let mut fit = refit(model, theta0, wins, opts)?;
    let rms_start_rad = fit.rms_start_rad;
    for _ in 0..MAX_CONVERGE_RESTARTS {
        if fit.converged {
            break;
        }
        match refit(model, &fit.theta.clone(), wins, opts) {
            Some(f) => fit = f,
            None => break,
        }
    }
    fit.rms_start_rad = rms_start_rad;
    Some(fit)
}

/// Screening z below which a candidate is not refitted on all judging windows.
pub const SCREEN_Z: f64 = 1.0;

/// A candidate's screening on every second judging window ([`screen_sharing`]).
#[derive(Debug, Clone, PartialEq)]
pub enum Screening {
    /// Its held-out comparison with the current model there, and its held-out errors there.
    HeldOut(Comparison, HeldOut),
    /// Its refit fits those windows significantly worse than the current model: the in-sample
    /// comparison (not predicted held out; [`evaluate_on`]'s gate).
    FitsWorse(Comparison),
}

/// Screening: `cand` refitted and judged on every second judging window. A candidate whose
/// full-set z reaches the threshold (≥ 3) has an expected half-set z of ≥ 3/√2 ≈ 2.1, far above
/// [`SCREEN_Z`].
pub fn screen(ctx: &SelectCtx, cur: &ModelState, cand: &Candidate) -> Option<Comparison> {
    match screen_on(ctx, cur, cand, None, false)? {
        Screening::HeldOut(c, _) => Some(c),
        Screening::FitsWorse(_) => None,
    }
}

/// [`screen`] as a round screens: the searches of its windows at the candidate's start kept in
/// `searches` for the candidate's refit on all windows ([`evaluate_sharing`]), and a refit that
/// fits the screening's windows significantly worse than the current model not predicted held
/// out ([`Screening::FitsWorse`]).
pub fn screen_sharing(
    ctx: &SelectCtx,
    cur: &ModelState,
    cand: &Candidate,
    searches: Option<&StartSearches>,
) -> Option<Screening> {
    screen_on(ctx, cur, cand, searches, true)
}

/// The screening's windows: every second judging window (their indices and the windows).
fn screening_windows(ctx: &SelectCtx) -> (Vec<usize>, Vec<Win>) {
    let idx: Vec<usize> = (0..ctx.wins.len()).step_by(2).collect();
    let sub = idx.iter().map(|&k| ctx.wins[k].clone()).collect();
    (idx, sub)
}

/// [`screen`] and [`screen_sharing`] (`gated`: the latter).
fn screen_on(
    ctx: &SelectCtx,
    cur: &ModelState,
    cand: &Candidate,
    searches: Option<&StartSearches>,
    gated: bool,
) -> Option<Screening> {
    let (idx, sub) = screening_windows(ctx);
    let followed = cur.fit.used.iter().filter(|&&(wi, _)| wi % 2 == 0).count();
    let cur_sub = HeldOut {
        chi2: idx.iter().map(|&k| cur.held.chi2[k]).collect(),
        chi2_fit: idx.iter().map(|&k| cur.held.chi2_fit[k]).collect(),
    };
    let gate = gated.then_some(cur_sub.chi2_fit.as_slice());
    let refitted = evaluate_on(
        ctx,
        &sub,
        followed,
        (cur, cand),
        (Reselect::Never, searches),
        gate,
    )?;
    Some(match refitted {
        Refitted::Judged(st) => {
            Screening::HeldOut(compare(&cur_sub, &st.held, &sub, ctx.runs), st.held)
        }
        Refitted::FitsWorse(c) => Screening::FitsWorse(c),
    })
}

/// `round[k]` accepted: the model refitted to convergence; the other candidates' states dropped.
pub fn accept(ctx: &SelectCtx, round: &mut [Tried], k: usize) -> ModelState {
    round[k].accepted = true;
    let cur = converge(ctx, round[k].state.as_ref().expect("evaluated"));
    for (j, t) in round.iter_mut().enumerate() {
        if j != k {
            t.state = None;
        }
    }
    cur
}

/// The named rival of the accepted `round[bi]`, a catalog effect (`None` for a dictionary term):
/// among the significant candidates `passed` of other catalog effects (not `unexplained`, whose
/// choice against a named effect is [`choose_named`]'s), the one of largest gain that
/// `round[bi]` does not predict the held-out windows significantly better than (paired z <
/// `z_crit`), with that z.
pub fn close_rival(
    ctx: &SelectCtx,
    round: &[Tried],
    passed: &[usize],
    bi: usize,
    z_crit: f64,
) -> Option<(usize, f64)> {
    if round[bi].candidate.effect.id == "unexplained" {
        return None;
    }
    let chosen = round[bi].state.as_ref()?;
    let gain = |k: usize| round[k].gain();
    passed
        .iter()
        .copied()
        .filter(|&k| {
            let id = round[k].candidate.effect.id;
            k != bi && id != "unexplained" && id != round[bi].candidate.effect.id
        })
        .filter_map(|k| {
            let s = round[k].state.as_ref()?;
            let c = compare(&s.held, &chosen.held, ctx.wins, ctx.runs);
            (!c.improves(z_crit)).then_some((k, c.z))
        })
        .max_by(|a, b| gain(a.0).total_cmp(&gain(b.0)))
}

/// The candidates of `round` proposed for `cur`, each screened and judged by simulation (in
/// parallel, their lines printed afterwards in the proposer's order, so the output does not
/// depend on the number of threads). A candidate is refitted on all judging windows when its
/// screening z reaches [`SCREEN_Z`] and the screening's leader ([`screening_leader`]) does not
/// predict the screening's windows significantly better than it ([`beaten_on_screening`]), or
/// when the leader, refitted on all windows, may not be accepted itself ([`significant`]):
/// a screening's gain need not carry over (a Stribeck member screened at z = 9.2 and was worse
/// on all windows, gain −2.0·10⁴). `None` when nothing is proposed.
pub fn judge_round(
    ctx: &SelectCtx,
    cur: &ModelState,
    round: usize,
    label: &str,
    progress: &dyn Observer,
) -> Option<Vec<Tried>> {
    let lat = cur.fit_latency.then(|| cur.latency());
    let cands = propose(ctx.propose, &cur.terms, lat, &cur.effects);
    if cands.is_empty() {
        return None;
    }
    let z_crit = z_threshold(cands.len());
    let searches: Vec<StartSearches> = cands.iter().map(|_| StartSearches::default()).collect();
    let screened = par_map(cands.len(), |k| {
        screen_sharing(ctx, cur, &cands[k], Some(&searches[k]))
    });
    let mut beaten = beaten_on_screening(&screening_windows(ctx).1, ctx.runs, &screened, z_crit);
    let refitted = |which: Vec<bool>| {
        par_map(cands.len(), |k| match &screened[k] {
            Some(Screening::HeldOut(sc, _)) if sc.z >= SCREEN_Z && which[k] => {
                evaluate_sharing(ctx, cur, &cands[k], Some(&searches[k]))
            }
            _ => None,
        })
    };
    let record = |k: usize, st: Option<ModelState>| {
        let held_out = match &screened[k] {
            Some(Screening::HeldOut(sc, _)) => Some(*sc),
            _ => None,
        };
        let mut t = tried(ctx, cur, cands[k].clone(), (held_out, st), (round, z_crit));
        if let Some(Screening::FitsWorse(fc)) = &screened[k] {
            t.screen_fit = Some(*fc);
        }
        t
    };
    let states = refitted(beaten.iter().map(Option::is_none).collect());
    let mut out: Vec<Tried> = states
        .into_iter()
        .enumerate()
        .map(|(k, st)| record(k, st))
        .collect();
    // the leader stands in for the candidates it beat only when it may be accepted itself
    let leader_stands = screening_leader(&screened).is_some_and(|j| significant(&out[j], z_crit));
    if !leader_stands && beaten.iter().any(Option::is_some) {
        let more = refitted(beaten.iter().map(Option::is_some).collect());
        for (k, m) in more.into_iter().enumerate() {
            if m.is_some() {
                out[k] = record(k, m);
            }
        }
        beaten.iter_mut().for_each(|b| *b = None);
    }
    for (k, t) in out.iter_mut().enumerate() {
        t.screen_beaten = beaten[k].map(|(j, cmp)| {
            let c = &cands[j];
            let terms: Vec<String> = c.terms.iter().map(|t| t.name()).collect();
            BeatenOnScreening {
                leader: j,
                label: format!("{} ({})", c.effect.id, terms.join(", ")),
                cmp,
            }
        });
        report_tried(t, label, progress);
    }
    Some(out)
}

/// The screening's leader: of the candidates whose screening z reaches [`SCREEN_Z`], the one with
/// the largest screening gain (an index into `screened`).
fn screening_leader(screened: &[Option<Screening>]) -> Option<usize> {
    screened
        .iter()
        .enumerate()
        .filter_map(|(k, s)| match s {
            Some(Screening::HeldOut(c, _)) if c.z >= SCREEN_Z => Some((k, c.gain)),
            _ => None,
        })
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(k, _)| k)
}

/// For each screened candidate that reaches [`SCREEN_Z`]: the leader ([`screening_leader`]) and
/// its paired comparison against the candidate on the screening's windows `sub` when the leader
/// predicts them significantly better (the judge's rule, [`Comparison::improves`] at the round's
/// `z_crit`). Such a candidate is not refitted on all windows: the round accepts the candidate of
/// largest held-out gain, and its close rivals are those it does not predict significantly
/// better; a candidate the leader beats at z ≥ z_crit on half the windows has an expected
/// full-set z of √2 z_crit against it.
fn beaten_on_screening(
    sub: &[Win],
    runs: &[CleanRun],
    screened: &[Option<Screening>],
    z_crit: f64,
) -> Vec<Option<(usize, Comparison)>> {
    let mut out = vec![None; screened.len()];
    let Some(lead) = screening_leader(screened) else {
        return out;
    };
    let Some(Screening::HeldOut(_, lead_held)) = &screened[lead] else {
        return out;
    };
    for (k, s) in screened.iter().enumerate() {
        if let Some(Screening::HeldOut(c, held)) = s {
            if k != lead && c.z >= SCREEN_Z {
                let vs = compare(held, lead_held, sub, runs);
                out[k] = vs.improves(z_crit).then_some((lead, vs));
            }
        }
    }
    out
}

/// The record of `c` tried on top of `cur` in round `round` (threshold `z_crit`): its screening
/// `scr` and its refit `st` on all judging windows, compared with `cur`.
pub fn tried(
    ctx: &SelectCtx,
    cur: &ModelState,
    c: Candidate,
    (scr, st): (Option<Comparison>, Option<ModelState>),
    (round, z_crit): (usize, f64),
) -> Tried {
    let cmp = st
        .as_ref()
        .map(|s| compare(&cur.held, &s.held, ctx.wins, ctx.runs));
    let added_z = st
        .as_ref()
        .map(|s| added_parameters_z(&s.fit, &added(cur, s)));
    Tried {
        round,
        candidate: c,
        added_z,
        cmp,
        screen: scr,
        screen_fit: None,
        screen_beaten: None,
        z_crit,
        accepted: false,
        state: st,
        member: None,
        dropped: None,
        forked: false,
        joined: false,
        on_top_of: None,
    }
}

/// Whether `t` may be accepted at the threshold `z_crit`: its held-out prediction improves
/// significantly ([`Comparison::improves`]) and the parameters it adds are significant in its
/// refit (Wald z ≥ the threshold).
fn significant(t: &Tried, z_crit: f64) -> bool {
    t.cmp.is_some_and(|c| c.improves(z_crit))
        && t.added_z.is_some_and(|z| z >= z_crit)
        && t.state.is_some()
}

/// The candidates proposed for `cur` that fill the slot of `like` ([`same_slot`]: the members of
/// its family the proposer offers there, with their weak-form starts on top of `cur`; empty when
/// it offers none).
pub fn proposed_on(ctx: &SelectCtx, cur: &ModelState, like: &Candidate) -> Vec<Candidate> {
    let lat = cur.fit_latency.then(|| cur.latency());
    propose(ctx.propose, &cur.terms, lat, &cur.effects)
        .into_iter()
        .filter(|c| same_slot(&c.effect, &like.effect))
        .collect()
}

/// The progress lines of a judged candidate.
pub fn report_tried(t: &Tried, label: &str, progress: &dyn Observer) {
    let c = &t.candidate;
    stage(
        progress,
        &format!(
            "round {}{label}: judged {} ({}) by simulation on held-out runs",
            t.round,
            c.effect.id,
            c.terms
                .iter()
                .map(|t| t.name())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    );
    let (scr, cmp) = (t.screen, t.cmp);
    if let Some(BeatenOnScreening {
        label: lead,
        cmp: b,
        ..
    }) = &t.screen_beaten
    {
        let sc = t.screen.map(|c| format!("{:.2} (gain {:.1})", c.z, c.gain));
        stage(
            progress,
            &format!(
                "  screening z = {}; {lead} predicts the screening's windows significantly \
                 better (z = {:.2} ≥ {:.2}, χ² gain {:.1}): not refitted on all windows",
                sc.unwrap_or("–".into()),
                b.z,
                t.z_crit,
                b.gain
            ),
        );
        return;
    }
    if let Some(f) = t.screen_fit {
        stage(
            progress,
            &format!(
                "  screening: its refit fits the screening's windows significantly worse than the \
                 current model (in-sample z = {:.2}, χ² gain {:.1}), not predicted held out \
                 (threshold {:.2}); windows it could not simulate: {}",
                f.z, f.gain, t.z_crit, f.failed_after
            ),
        );
        return;
    }
    stage(
        progress,
        &format!(
            "  screening z = {} (gain {}), held-out z = {} (threshold {:.2}), gain = {}, \
             added parameters' Wald z = {}; windows it could not simulate: {}",
            scr.map(|c| format!("{:.2}", c.z)).unwrap_or("–".into()),
            scr.map(|c| format!("{:.1}", c.gain)).unwrap_or("–".into()),
            cmp.map(|c| format!("{:.2}", c.z)).unwrap_or("–".into()),
            t.z_crit,
            cmp.map(|c| format!("{:.1}", c.gain)).unwrap_or("–".into()),
            t.added_z.map(|z| format!("{z:.2}")).unwrap_or("–".into()),
            cmp.or(scr)
                .map(|c| c.failed_after.to_string())
                .unwrap_or("–".into()),
        ),
    );
}

/// The candidate of a round to accept among the significant ones `passed` (indices into `round`):
/// the one with the largest held-out gain, except that a dictionary term (`unexplained`) gives way
/// to the catalog effect of largest gain when it does not predict the held-out windows
/// significantly better than that effect (the paired comparison of the two, z < `z_crit`; the rule
/// of [`choose_members`] between nested members). Two candidates that explain the same mismatch
/// equally well are told apart by the name they give it, and a named effect is the explanation
/// (a tilted set-up's bearing load before the load family fitted the weight's direction: the
/// family and −sgn β̇ sin(α + β) gained χ² 1921 and 1932 at z 5.79 and 5.80; docs/diagnosis.md,
/// Known weaknesses). `None` when nothing passed.
pub fn choose_named(
    ctx: &SelectCtx,
    round: &[Tried],
    passed: &[usize],
    z_crit: f64,
) -> Option<usize> {
    let gain = |k: usize| round[k].gain();
    let best_of = |named: Option<bool>| {
        passed
            .iter()
            .copied()
            .filter(|&k| named.is_none_or(|n| (round[k].candidate.effect.id != "unexplained") == n))
            .filter(|&k| round[k].cmp.is_some())
            .max_by(|&a, &b| gain(a).total_cmp(&gain(b)))
    };
    let best = best_of(None)?;
    if round[best].candidate.effect.id != "unexplained" {
        return Some(best);
    }
    let Some(named) = best_of(Some(true)) else {
        return Some(best);
    };
    match (&round[named].state, &round[best].state) {
        (Some(a), Some(b)) if !compare(&a.held, &b.held, ctx.wins, ctx.runs).improves(z_crit) => {
            Some(named)
        }
        _ => Some(best),
    }
}

/// The candidates of a round that may be accepted: every significant one (held-out z ≥ `z_crit`),
/// except that of a family of nested members ([`MemberChoice::Nested`])
/// only one passes: starting from the smallest significant member, a larger member replaces it
/// when it predicts the held-out windows significantly better than it (the same rule, z ≥
/// `z_crit`, on the paired windows of the two). Indices into `round`.
pub fn choose_members(ctx: &SelectCtx, round: &mut [Tried], z_crit: f64) -> Vec<usize> {
    let nested = |id: &str| member_choice(id) == MemberChoice::Nested;
    let mut out: Vec<usize> = (0..round.len())
        .filter(|&k| significant(&round[k], z_crit) && !nested(round[k].candidate.effect.id))
        .collect();
    let mut ids: Vec<&'static str> = round
        .iter()
        .map(|t| t.candidate.effect.id)
        .filter(|id| nested(id))
        .collect();
    ids.dedup();
    for id in ids {
        let mut members: Vec<usize> = (0..round.len())
            .filter(|&k| round[k].candidate.effect.id == id && significant(&round[k], z_crit))
            .collect();
        members.sort_by_key(|&k| round[k].candidate.terms.len());
        let Some(&first) = members.first() else {
            continue;
        };
        let mut chosen = first;
        for &k in &members[1..] {
            let (Some(a), Some(b)) = (&round[chosen].state, &round[k].state) else {
                continue;
            };
            let c = compare(&a.held, &b.held, ctx.wins, ctx.runs);
            round[k].member = Some(c);
            if c.improves(z_crit) {
                chosen = k;
            }
        }
        out.push(chosen);
    }
    out
}
