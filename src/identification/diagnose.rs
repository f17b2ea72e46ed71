//! The diagnosis, a pipeline of stages with typed hand-overs:
//!
//! 1. **clean** ([`prepare`]): outlier rejection, noise, velocity; ring-down fits and κ(α0).
//! 2. **fit base** ([`fit_base`]): weak-form base fit, geometry refined from its Δ, then the base
//!    model refitted by simulation on the judging windows with its held-out errors.
//! 3. **mismatch** ([`super::mismatch::locate`]): where the base model fails, in words.
//! 4. **propose** ([`super::propose`]): the weak form proposes every catalog family's best member
//!    and the best dictionary terms.
//! 5. **judge** ([`super::beam`], [`super::select`], [`super::judge`]): each candidate is refitted
//!    by simulation and judged by its prediction of held-out runs; rounds, forked on close rivals
//!    (at most two branches at a time), and the backward check ([`super::backward`]). Then the
//!    breakaway friction ([`super::breakaway`]) and the nominal consistency ([`super::nominal`]).
//! 6. **report** ([`report`]): findings, rejected candidates, predictions for the figures.

use super::beam::{select, Rivals};
use super::breakaway;
use super::findings::{
    excess_profile_size, judged_finding, profiled_size, rejected, rivals, second_minimum_size,
};
use super::judge::{rms_per_run, rms_rad, Folds};
use super::mismatch::{locate, MismatchOptions};
use super::model::{Coefficients, Geometry};
use super::nominal;
use super::predict::{predict, Prediction};
use super::preprocess::{clean, CleanRun};
use super::propose::ProposeCtx;
use super::regression::{build, fit_checked, Design, LinFit, Term, WeakOptions, BASE_TERMS};
use super::report::{Baseline, Finding, Mismatch, Report, RunRms, SCHEMA};
use super::ringdown::{fit_kappa, fit_ringdown, KappaFit, RingdownFit};
use super::select::{ModelState, SelectCtx, Tried};
use super::shooting::{
    choose_windows, mask_windows, par_map, refit, ShootingOptions, SimModel, Win,
    CONVERGED_PATIENCE,
};
use crate::error::{Error, Result};
use crate::io::recordings::{RecordingSet, RunKind};
use crate::progress::{stage, Observer};
use serde_json::json;
use std::collections::BTreeMap;

/// Options of the diagnosis.
#[derive(Debug, Clone, PartialEq)]
pub struct DiagnoseOptions {
    /// Weak-form options.
    pub weak: WeakOptions,
    /// Most effects accepted by the judge (one per round, two in a round whose close rivals are
    /// accepted together; also the most rounds).
    pub max_effects: usize,
    /// Decide close rivals: a round whose accepted candidate does not predict the held-out
    /// windows significantly better than a named rival accepts both when each is significant on
    /// top of the other, and else runs on in a branch for each, at most two at a time
    /// ([`super::beam`]). Off: the greedy choice.
    pub fork_close_rivals: bool,
    /// BIC decrease that makes a mismatch fingerprint significant.
    pub bic_threshold: f64,
    /// Report per-run held-out rms of the base model (from the judge's folds).
    pub heldout_predictions: bool,
    /// Fit the ring-downs one by one by simulation (eq. `model`).
    pub ringdown_fits: bool,
    /// Latency profile half-width, s, for the `sensor_latency` proposal.
    pub latency_span: f64,
    /// A mismatch fingerprint must explain at least this fraction of a row's noise variance.
    pub min_chi2_gain_per_row: f64,
    /// Refit and judge by simulation (without it: the weak-form base fit only, no findings).
    pub simulation_refit: bool,
    /// Options of the refits by simulation; `max_windows` is the number of judging windows.
    pub shooting: ShootingOptions,
    /// Fit the base model only (`gearbif fit`): no proposals, no judge.
    pub base_only: bool,
    /// Folds (by run) of the held-out judgement.
    pub folds: usize,
    /// Most dictionary proposals per round.
    pub max_dictionary: usize,
    /// Relative tolerance of every simulation of the diagnosis (eq. `model`, exact Filippov flow):
    /// the window simulations of the refits, the judge and the predictions, and the stick windows
    /// of the static-friction profile. Default 1e-8, the tolerance the documented results were
    /// computed with. Must lie in (0, 1) ([`DiagnoseOptions::check`]).
    pub tol: f64,
    /// The ring-down fits are simulated at `tol × ringdown_tol_ratio`
    /// ([`DiagnoseOptions::ringdown_tol`]): a ring-down is one simulation over the whole run (up
    /// to minutes of decay), not a short window, so it is integrated tighter. Default 0.1 (1e-9 at
    /// the default `tol`, as the documented results). Must lie in (0, 1].
    pub ringdown_tol_ratio: f64,
    /// Profile the shape parameters of the final model (drag exponent, load weight, Stribeck
    /// width and shape; [`super::select::polish_profiled`]): each held on a ladder over its range
    /// with the others refitted to convergence, the refit restarted from the profile's minimum,
    /// and the headline σ of a family with a shape taken from the profile's 1σ interval. Off by
    /// default: it costs 3–9 times the CPU of a diagnosis that names such a family (about 20 s
    /// CPU per held value; docs/diagnosis.md, "Shape parameters"); without it the shapes keep
    /// the refit's covariance σ, which agrees with the profile's curvature where the profile is
    /// near quadratic (docs/diagnosis.md, "The Jacobian"); the profile is the check where it is
    /// not (an interval that reaches the end of the shape's range).
    pub profile_shapes: bool,
}

impl Default for DiagnoseOptions {
    fn default() -> Self {
        Self {
            weak: WeakOptions::default(),
            max_effects: 3,
            fork_close_rivals: true,
            bic_threshold: 10.0,
            heldout_predictions: true,
            ringdown_fits: true,
            latency_span: 0.03,
            min_chi2_gain_per_row: 0.005,
            simulation_refit: true,
            shooting: ShootingOptions::default(),
            base_only: false,
            folds: 4,
            max_dictionary: 3,
            tol: 1e-8,
            ringdown_tol_ratio: 0.1,
            profile_shapes: false,
        }
    }
}

impl DiagnoseOptions {
    /// The relative tolerance of the ring-down simulations: `tol × ringdown_tol_ratio`.
    pub fn ringdown_tol(&self) -> f64 {
        self.tol * self.ringdown_tol_ratio
    }

    /// Checks the tolerances: [`Error::InvalidParameter`] unless `tol` lies in (0, 1) and
    /// `ringdown_tol_ratio` in (0, 1].
    pub fn check(&self) -> Result<()> {
        crate::error::relative_tolerance("tol", self.tol)?;
        crate::error::positive("ringdown_tol_ratio", self.ringdown_tol_ratio)?;
        if self.ringdown_tol_ratio > 1.0 {
            return Err(Error::InvalidParameter {
                name: "ringdown_tol_ratio",
                value: self.ringdown_tol_ratio,
                reason: "must be in (0, 1] (ring-downs are not integrated looser than `tol`)",
            });
        }
        Ok(())
    }
}

/// Everything the diagnosis computed.
#[derive(Debug, Clone)]
pub struct Diagnosis {
    /// The report (report.json).
    pub report: Report,
    /// Cleaned runs.
    pub runs: Vec<CleanRun>,
    /// Files of the runs.
    pub files: Vec<String>,
    /// Base model coefficients.
    pub base: Coefficients,
    /// Augmented model coefficients (equal to `base` when the verdict is `none`).
    pub augmented: Coefficients,
    /// Latency of the augmented model, s.
    pub latency: f64,
    /// Ring-down fits.
    pub ringdowns: Vec<RingdownFit>,
    /// κ(α0) fit.
    pub kappa: Option<KappaFit>,
    /// Base-model predictions per run.
    pub base_pred: Vec<Prediction>,
    /// Augmented-model predictions per run.
    pub aug_pred: Vec<Prediction>,
    /// Row centres (α, β, β̇) and base / augmented equation-error residuals (for fingerprints).
    pub fingerprint: Vec<(f64, f64, f64, f64, f64)>,
    /// θ and covariance of the final refit (the base refit's when nothing was accepted; `None`
    /// without a refit by simulation): model.json's covariance.
    pub fitted: Option<super::spec::FittedTheta>,
}

/// Stage 1 output: cleaned runs and the ring-down route.
#[derive(Debug, Clone)]
pub struct Prepared {
    /// Cleaned runs.
    pub runs: Vec<CleanRun>,
    /// Their files.
    pub files: Vec<String>,
    /// Ring-down fits.
    pub ringdowns: Vec<RingdownFit>,
    /// κ(α0) → g, |Δ|, I.
    pub kappa: Option<KappaFit>,
}

/// The proposer's context of stage 5 on the cleaned `runs` with the base model `base`.
pub fn propose_ctx<'a>(
    runs: &'a [CleanRun],
    base: &'a BaseModel,
    opts: &'a DiagnoseOptions,
) -> ProposeCtx<'a> {
    ProposeCtx {
        runs,
        geo: &base.geo,
        weak: &opts.weak,
        latency_span: opts.latency_span,
        max_dictionary: opts.max_dictionary,
    }
}

/// The selection's context of stage 5 (the rounds, the final refit, static friction, the
/// backward check): the proposer `pctx`, the base model's judging windows and `folds`.
pub fn select_ctx<'a>(
    pctx: &'a ProposeCtx<'a>,
    base: &'a BaseModel,
    folds: &'a Folds,
    opts: &'a DiagnoseOptions,
) -> SelectCtx<'a> {
    SelectCtx {
        runs: pctx.runs,
        geo: &base.geo,
        wins: &base.wins,
        folds,
        shooting: &opts.shooting,
        tol: opts.tol,
        propose: pctx,
        max_effects: opts.max_effects,
        fork_close_rivals: opts.fork_close_rivals,
    }
}

/// Stage 1: cleaning (one camera: the pooled noise of the runs sets the outlier threshold of the
/// predictions unless experiment.toml states it) and the ring-down fits.
pub fn prepare(
    set: &RecordingSet,
    opts: &DiagnoseOptions,
    progress: &dyn Observer,
) -> Result<Prepared> {
    opts.check()?;
    if set.runs.is_empty() {
        return Err(Error::shape("runs of the recording set", ">= 1", 0));
    }
    let setup = &set.gear;
    let hint = setup.beta_noise_deg.map(|d| d.to_radians());
    stage(
        progress,
        "cleaning runs (outlier rejection, noise, velocity)",
    );
    let mut runs: Vec<CleanRun> = set.runs.iter().map(|r| clean(r, hint)).collect();
    if hint.is_none() {
        let mut s: Vec<f64> = runs.iter().map(|r| r.sigma_beta).collect();
        s.sort_by(|a, b| a.total_cmp(b));
        let pooled = s[s.len() / 2];
        for r in &mut runs {
            r.sigma_camera = pooled;
        }
    }
    let files: Vec<String> = set.runs.iter().map(|r| r.file.clone()).collect();
    let mut ringdowns = Vec::new();
    if opts.ringdown_fits {
        let rd: Vec<usize> = (0..runs.len()).filter(|&i| runs[i].ringdown).collect();
        stage(
            progress,
            &format!("ring-down fits of {} runs (in parallel)", rd.len()),
        );
        // independent fits, collected in file order
        let fits = par_map(rd.len(), |k| {
            let i = rd[k];
            match set.runs[i].kind {
                RunKind::Ringdown { alpha0 } => fit_ringdown(
                    &runs[i],
                    &files[i],
                    alpha0,
                    setup.zeta.unwrap_or(1.1),
                    setup.eta.unwrap_or(23.1),
                    opts.ringdown_tol(),
                ),
                _ => None,
            }
        });
        ringdowns.extend(fits.into_iter().flatten());
    }
    let kappa = fit_kappa(&ringdowns, setup);
    Ok(Prepared {
        runs,
        files,
        ringdowns,
        kappa,
    })
}

/// Stage 2 output: the base model.
#[derive(Debug, Clone)]
pub struct BaseModel {
    /// Weak-form rows of the base terms.
    pub design: Design,
    /// Weak-form base fit.
    pub weak: LinFit,
    /// Geometry of the force shape, refined from the fitted Δ.
    pub geo: Geometry,
    /// Judging windows.
    pub wins: Vec<Win>,
    /// The base model refitted by simulation, with its held-out errors (`None` without the
    /// simulation refit).
    pub state: Option<ModelState>,
}

/// Stage 2: the weak-form base fit, the geometry refined from its Δ, the judging windows (outlier
/// frames masked under the base model) and the base refit by simulation with its held-out errors.
pub fn fit_base(
    prep: &Prepared,
    set: &RecordingSet,
    opts: &DiagnoseOptions,
    folds: &Folds,
    progress: &dyn Observer,
) -> Result<BaseModel> {
    let setup = &set.gear;
    let geo0 = Geometry::new(setup.theta_deg.to_radians(), setup.phi_deg.to_radians());
    stage(progress, "equation-error rows (weak form), base fit");
    // every catalog and dictionary term (base terms first): the mismatch tests use them
    let mut terms: Vec<Term> = BASE_TERMS.to_vec();
    for t in super::catalog::catalog()
        .into_iter()
        .flat_map(|e| e.terms)
        .chain(super::catalog::dictionary())
    {
        if !terms.contains(&t) && !matches!(t, Term::Shape(_)) {
            terms.push(t);
        }
    }
    let design = build(&prep.runs, &geo0, &terms, &opts.weak, 0.0);
    let weak = fit_checked(&design, &[0, 1, 2, 3]).map_err(|e| {
        Error::shape(
            format!(
                "usable samples for the equation-error fit (runs too short or always at rest; {e})"
            ),
            "more than 6 with independent columns",
            design.y.len(),
        )
    })?;
    let geo = refine_geometry(&geo0, weak.coef[3] / -weak.coef[2]);
    let mut wins = Vec::new();
    let mut state = None;
    if opts.simulation_refit {
        stage(
            progress,
            "base model refitted by simulation on the judging windows",
        );
        let model = SimModel {
            runs: &prep.runs,
            geo,
            terms: BASE_TERMS.to_vec(),
            latency: 0.0,
            fit_latency: false,
            eta_static_excess: 0.0,
            tol: opts.tol,
            held_shapes: Vec::new(),
            roughness: 0.0,
            session: Default::default(),
        };
        let chosen = choose_windows(&prep.runs, opts.shooting.max_windows);
        wins = mask_windows(&model, &weak.coef, &chosen);
        // converged: every candidate is judged against this fit
        let converged = ShootingOptions {
            patience: CONVERGED_PATIENCE,
            ..opts.shooting
        };
        if let Some(f) = refit(&model, &weak.coef, &wins, &converged) {
            stage(progress, "base model: held-out predictions of the folds");
            let held = super::judge::heldout(&model, &f, (&wins, folds), &opts.shooting);
            state = Some(ModelState {
                terms: BASE_TERMS.to_vec(),
                fit_latency: false,
                fit: f,
                held,
                effects: vec![],
            });
        }
    }
    Ok(BaseModel {
        design,
        weak,
        geo,
        wins,
        state,
    })
}

/// Runs the diagnosis of a recording set. `progress` receives one line per step.
pub fn diagnose(
    set: &RecordingSet,
    opts: &DiagnoseOptions,
    progress: &dyn Observer,
) -> Result<Diagnosis> {
    let prep = prepare(set, opts, progress)?;
    let folds = Folds::new(&prep.runs, opts.folds);
    let base = fit_base(&prep, set, opts, &folds, progress)?;
    stage(
        progress,
        "locating the mismatch (fingerprints, symmetry, consistency)",
    );
    let (mut mismatch, chi_run) = locate(
        &base.design,
        &base.weak,
        &[0, 1, 2, 3],
        &prep.runs,
        &prep.files,
        prep.kappa.as_ref(),
        &MismatchOptions {
            bic_threshold: opts.bic_threshold,
            min_chi2_gain_per_row: opts.min_chi2_gain_per_row,
        },
    );
    let runs = &prep.runs;
    let mut tried: Vec<Tried> = Vec::new();
    let mut decided = Rivals::default();
    let mut findings: Vec<Finding> = Vec::new();
    let mut final_state = base.state.clone();
    let mut excess = 0.0;
    let mut remains = None;
    let mut curve = None;
    // the fraction of the base model's held-out excess each judged finding removed, in the
    // findings' order (the nominal consistency's findings, appended last, have none)
    let mut fractions: Vec<Option<(f64, f64)>> = Vec::new();
    if let (Some(b), false) = (&base.state, opts.base_only) {
        let pctx = propose_ctx(runs, &base, opts);
        let sctx = select_ctx(&pctx, &base, &folds, opts);
        let sel = select(&sctx, b.clone(), progress);
        let fin = sel.fin;
        tried = sel.tried;
        decided = sel.rivals;
        stage(progress, "final model refitted to convergence");
        let (fin, profiles) = polish_final(&sctx, &fin, opts.profile_shapes);
        stage(
            progress,
            "static friction (stick phases), judged on held-out runs",
        );
        let sf = static_friction(
            &sctx,
            (fin, profiles, opts.profile_shapes),
            &mut tried,
            &mut mismatch,
            progress,
        );
        stage(progress, "backward check of the accepted effects");
        let fin = super::backward::backward(&sctx, sf.fin, &mut tried, progress);
        let (fin, profiles, final_held) = if tried.iter().all(|t| t.dropped.is_none()) {
            (fin, sf.profiles, sf.held)
        } else if opts.profile_shapes {
            let (f, p) = super::select::polish_profiled(&sctx, &fin);
            let h = f.held.clone();
            (f, p, h)
        } else {
            let h = fin.held.clone();
            (fin, Vec::new(), h)
        };
        excess = sf.excess;
        // the Stribeck member's excess: its σ from its profile (the covariance's σ is the
        // curvature of a curved valley at its minimum)
        let excess_sides = if tried
            .iter()
            .any(|t| t.accepted && t.candidate.effect.id == "static_friction")
        {
            stage(progress, "profile of the breakaway excess (its σ)");
            super::select::excess_profile(&sctx, &fin)
        } else {
            None
        };
        let mut before = b;
        // each finding's step: the held-out χ² of the model before it and of the model with it
        let mut steps: Vec<Option<Step>> = Vec::new();
        // the chain of round models runs through the effects the backward check dropped too (each
        // finding's "before" is the model it was judged against: the round's model, or for a
        // close rival accepted together with the round's accepted effect the model with that
        // effect), but only the accepted ones are findings
        for t in tried.iter().filter(|t| t.accepted || t.dropped.is_some()) {
            let found = t.accepted.then(|| {
                let rv = rivals(t, &tried);
                judged_finding(t, before, &base.wins, runs, folds.k, &rv, &fin)
            });
            let after = t.state.as_ref().expect("accepted state");
            if let Some(mut f) = found.flatten() {
                steps.push(Some((before.held.chi2.clone(), after.held.chi2.clone())));
                let e = &t.candidate.effect;
                f.size = profiled_size(e, &fin, &profiles, f.size.take(), &mut f.params);
                if let Some(sides) = excess_sides.as_ref().filter(|_| e.id == "static_friction") {
                    f.size =
                        excess_profile_size(sides, f.size.take(), &mut f.params, &mut f.evidence);
                }
                if let Some(sec) = sf.second.as_ref().filter(|_| e.id == "static_friction") {
                    f.size = second_minimum_size(e, &fin, sec, f.size.take(), &mut f.params);
                }
                findings.push(f);
            }
            before = after;
        }
        if let Some(f) = sf.at_rest {
            steps.push(Some((fin.held.chi2.clone(), final_held.chi2.clone())));
            findings.push(f);
        }
        remaining(&mut mismatch, &fin, &base.wins, runs, &prep.files);
        // the floor's window geometry and stick phases under the final model (with the
        // breakaway excess when it stands)
        let mut model = fin.model(runs, &base.geo, opts.tol);
        model.eta_static_excess = excess;
        let warm = fin.fit.warm_starts(base.wins.len());
        let geom = super::mismatch::window_geometry(&model, &fin.fit.theta, &base.wins, &warm);
        let measured = super::mismatch::remainder(
            runs,
            &base.wins,
            (&b.held.chi2, &final_held.chi2),
            (opts.weak.rest_sigmas, opts.weak.rest_run),
            &geom,
            // Δ = c_cs / g of the base refit
            b.fit.theta[3] / -b.fit.theta[2],
        );
        if let Some((rem, floors)) = measured {
            // a step's share only where the base model's excess is above noise (as the total's)
            if rem.fraction_removed.is_some() {
                fractions = steps
                    .iter()
                    .map(|s| {
                        let (x, y) = s.as_ref()?;
                        super::mismatch::fraction_removed(&b.held.chi2, x, y, &floors)
                    })
                    .collect();
            }
            remains = Some(rem);
        }
        // the nonparametric curve, where the selection named something or a significant
        // remainder is left (a control the base model explains skips it)
        let named = !fin.effects.is_empty() || excess > 0.0;
        if named || remains.as_ref().is_some_and(|r| !r.within_noise) {
            stage(
                progress,
                "a curve in the output angle (friction, torque), judged on held-out runs",
            );
            curve = super::curve::fit_curve(&sctx, &opts.weak, (&fin, &final_held), &b.fit.theta);
        }
        final_state = Some(fin);
    }
    // nominal consistency of the base parameters
    if let Some(st) = &final_state {
        let map = super::findings::coefficient_map(st);
        let (g, ge) = map
            .get(&Term::SinACosB.name())
            .map(|v| (-v.0, v.1))
            .unwrap_or((f64::NAN, f64::NAN));
        let cs = map
            .get(&Term::CosASinB.name())
            .copied()
            .unwrap_or((f64::NAN, f64::NAN));
        let delta = (
            cs.0 / g,
            ((cs.1 / g).powi(2) + (cs.0 * ge / (g * g)).powi(2)).sqrt(),
        );
        findings.extend(nominal::shaft_angles(&set.gear, delta));
        findings.extend(nominal::coupling_strength(&set.gear, (g, ge)));
    }
    let mut d = report(
        set,
        opts,
        prep,
        base,
        final_state,
        excess,
        (mismatch, chi_run),
        findings,
        (&tried, &decided),
        progress,
    )?;
    super::verdict::set_standings(&mut d.report.findings, &fractions);
    let (verdict, assessment) =
        super::verdict::decide(&mut d.report.findings, remains.as_ref(), curve.as_ref());
    d.report.verdict = verdict;
    d.report.assessment = Some(assessment);
    d.report.remaining = remains;
    d.report.curve = curve;
    Ok(d)
}

/// The held-out χ² per judging window of the model before a finding and of the model with it.
type Step = (Vec<Option<f64>>, Vec<Option<f64>>);

/// What the accepted findings leave: the runs whose held-out prediction by the final model is
/// still above 1.25 times the camera noise, by run kind.
fn remaining(
    mismatch: &mut Vec<Mismatch>,
    fin: &ModelState,
    wins: &[Win],
    runs: &[CleanRun],
    files: &[String],
) {
    if fin.effects.is_empty() {
        return;
    }
    let per = rms_per_run(&fin.held.chi2, wins, runs);
    let bad: BTreeMap<String, serde_json::Value> = (0..runs.len())
        .filter_map(|r| {
            let v = per[r]?;
            (v > 1.25 * runs[r].sigma_camera).then(|| {
                (
                    files[r].clone(),
                    json!({"heldout_rms_over_noise": v / runs[r].sigma_camera,
                           "kind": if runs[r].ringdown { "ringdown" } else { "driven" },
                           "drive_hz": runs[r].alpha_rate.abs() / std::f64::consts::TAU}),
                )
            })
        })
        .collect();
    if !bad.is_empty() {
        mismatch.push(Mismatch {
            where_: format!(
                "after the findings, {} of {} runs are still predicted worse than 1.25× the camera noise on held-out windows: the findings explain only part of the mismatch there",
                bad.len(),
                runs.len()
            ),
            evidence: bad,
        });
    }
}

/// The final model refitted to convergence, its shapes profiled when `profiled`
/// ([`super::select::polish_profiled`], else [`super::select::polish`]).
fn polish_final(
    ctx: &SelectCtx,
    st: &ModelState,
    profiled: bool,
) -> (ModelState, Vec<super::profile::ShapeProfile>) {
    if profiled {
        super::select::polish_profiled(ctx, st)
    } else {
        (super::select::polish(ctx, st), Vec::new())
    }
}

/// What the static-friction stage hands on: the final model (with the Stribeck member when it
/// was accepted), its shape profiles, its held-out errors (with the excess at rest when that
/// finding stands), the excess at rest (s⁻², 0 without it) and the finding at rest.
struct StaticFrictionStage {
    fin: ModelState,
    profiles: Vec<super::profile::ShapeProfile>,
    held: super::judge::HeldOut,
    excess: f64,
    at_rest: Option<Finding>,
    second: Option<breakaway::SecondMinimum>,
}

/// Stage 5b: static friction, which the weak form cannot propose (it skips stick phases). The
/// stick-phase profile at rest proposes it ([`breakaway::judge`], judged); then the Stribeck
/// member with a width is refitted by simulation from its excess ([`breakaway::width_member`])
/// and, when it stands, replaces the excess at rest: the final model is refitted with it (its
/// shapes freed) and it is reported like the rounds' findings (appended to `tried`). Otherwise
/// the excess at rest is reported when it stands. Every member tried is in `tried` or
/// `mismatch` with its numbers. Skipped when the rounds accepted a Stribeck member.
fn static_friction(
    ctx: &SelectCtx,
    (fin, profiles, profiled): (ModelState, Vec<super::profile::ShapeProfile>, bool),
    tried: &mut Vec<Tried>,
    mismatch: &mut Vec<Mismatch>,
    progress: &dyn Observer,
) -> StaticFrictionStage {
    let mut out = StaticFrictionStage {
        held: fin.held.clone(),
        fin,
        profiles,
        excess: 0.0,
        at_rest: None,
        second: None,
    };
    if tried
        .iter()
        .any(|t| t.accepted && t.candidate.effect.id == "static_friction")
    {
        return out;
    }
    let Some((f, cmp, stands, ex, held)) =
        breakaway::judge(ctx.runs, &out.fin, ctx.geo, ctx.wins, ctx.folds, ctx.tol)
    else {
        return out;
    };
    stage(
        progress,
        &format!(
            "  excess at rest: s = {:.3}, held-out z = {:.2} (threshold {:.2}); the Stribeck \
             member with a width refitted from it",
            f.params.get("excess_relative").copied().unwrap_or(f64::NAN),
            cmp.z,
            super::judge::z_threshold(breakaway::SLOT_MEMBERS)
        ),
    );
    let round = tried.iter().map(|t| t.round).max().unwrap_or(0) + 1;
    let width = breakaway::width_member(ctx, &out.fin, ex, round);
    if let Some((w, _)) = &width {
        stage(
            progress,
            &format!(
                "  Stribeck member (w, δ start {}): screening z = {}, held-out z = {}, Wald z of \
                 its excess = {}",
                w.candidate.weak_coef[out.fin.terms.len() + 1..]
                    .iter()
                    .map(|v| format!("{v}"))
                    .collect::<Vec<_>>()
                    .join(", "),
                w.screen
                    .map(|c| format!("{:.2}", c.z))
                    .unwrap_or("–".into()),
                w.cmp.map(|c| format!("{:.2}", c.z)).unwrap_or("–".into()),
                w.added_z.map(|z| format!("{z:.2}")).unwrap_or("–".into()),
            ),
        );
    }
    let stick_phases = |f: &Finding| Mismatch {
        where_: "stick phases: the output stays at rest beyond the sliding friction \
                 (release later, with an acceleration jump)"
            .into(),
        evidence: f.evidence.clone(),
    };
    let (width, alternate) = match width {
        Some((w, alt)) => (Some(w), alt),
        None => (None, None),
    };
    match width {
        Some(w) if w.accepted => {
            mismatch.push(stick_phases(&f));
            let st = w.state.as_ref().expect("accepted state");
            let (fin, profiles, second) =
                breakaway::final_member(ctx, &out.fin, st, alternate.as_ref(), |s| {
                    polish_final(ctx, s, profiled)
                });
            out.held = fin.held.clone();
            out.fin = fin;
            out.profiles = profiles;
            out.second = second;
            tried.push(w);
        }
        other => {
            tried.extend(other);
            if stands {
                mismatch.push(stick_phases(&f));
                out.held = held;
                out.excess = ex;
                out.at_rest = Some(f);
            } else {
                tried_static_friction_rejected(mismatch, &f, cmp.z);
            }
        }
    }
    out
}

fn tried_static_friction_rejected(mismatch: &mut Vec<Mismatch>, f: &Finding, z: f64) {
    let mut ev = f.evidence.clone();
    ev.insert(
        "judged".into(),
        json!("rejected: held-out prediction not significantly better"),
    );
    mismatch.push(Mismatch {
        where_: format!(
            "stick phases: the profile proposes a breakaway excess s = {:.3}, but the held-out \
             prediction does not improve significantly (z = {z:.2})",
            f.params.get("excess_relative").copied().unwrap_or(f64::NAN)
        ),
        evidence: ev,
    });
}

/// Stage 6: the report, the base and final predictions (figures) and the fingerprints.
#[allow(clippy::too_many_arguments)]
fn report(
    set: &RecordingSet,
    opts: &DiagnoseOptions,
    prep: Prepared,
    base: BaseModel,
    final_state: Option<ModelState>,
    excess: f64,
    (mismatch, chi_run): (Vec<Mismatch>, Vec<f64>),
    findings: Vec<Finding>,
    (tried, rivals): (&[Tried], &Rivals),
    progress: &dyn Observer,
) -> Result<Diagnosis> {
    let runs = &prep.runs;
    let nr = runs.len();
    let params = baseline_params(set, &base);
    let base_theta = base
        .state
        .as_ref()
        .map(|s| s.fit.theta.clone())
        .unwrap_or(base.weak.coef.clone());
    stage(
        progress,
        "short-horizon predictions of every run (base and final model)",
    );
    let base_model = SimModel {
        runs,
        geo: base.geo,
        terms: BASE_TERMS.to_vec(),
        latency: 0.0,
        fit_latency: false,
        eta_static_excess: 0.0,
        tol: opts.tol,
        held_shapes: Vec::new(),
        roughness: 0.0,
        session: Default::default(),
    };
    let base_pred: Vec<Prediction> = par_map(nr, |r| {
        predict(
            &runs[r],
            &base_model.coefficients(&base_theta, r),
            &base.geo,
            0.0,
            opts.tol,
        )
    });
    let base_coef = base_model.coefficients(&base_theta, 0);
    let (aug_pred, augmented, latency) = match &final_state {
        Some(st) if !st.effects.is_empty() || excess > 0.0 => {
            let mut m = st.model(runs, &base.geo, opts.tol);
            m.eta_static_excess = excess;
            let lat = st.latency();
            let p = par_map(nr, |r| {
                let c = m.coefficients(&st.fit.theta, r);
                predict(&runs[r], &c, &base.geo, lat, opts.tol)
            });
            let c = super::spec::coefficients(&st.terms, &st.fit.theta[..st.terms.len()]);
            (
                p,
                Coefficients {
                    eta_static_excess: excess,
                    ..c
                },
                lat,
            )
        }
        _ => (base_pred.clone(), base_coef, 0.0),
    };
    let pooled = |p: &[Prediction]| -> f64 {
        let (mut ss, mut n) = (0.0, 0usize);
        for q in p {
            ss += q.resid.iter().map(|r| r * r).sum::<f64>();
            n += q.resid.len();
        }
        if n > 0 {
            (ss / n as f64).sqrt()
        } else {
            f64::NAN
        }
    };
    let held_runs = match (&base.state, opts.heldout_predictions) {
        (Some(s), true) => rms_per_run(&s.held.chi2, &base.wins, runs),
        _ => vec![None; nr],
    };
    let baseline = Baseline {
        params,
        rms_rad: pooled(&base_pred),
        runs: (0..nr)
            .map(|r| RunRms {
                file: prep.files[r].clone(),
                rms_rad: base_pred[r].rms,
                heldout_rms_rad: held_runs[r],
                chi2_per_row: Some(chi_run[r]).filter(|v| v.is_finite()),
            })
            .collect(),
    };
    let fits = fits_document(
        opts,
        &prep,
        &base,
        final_state.as_ref(),
        latency,
        (tried, rivals),
    );
    // fingerprints: base equation-error residuals (the final model's on the same rows)
    let fingerprint = fingerprints(&base, final_state.as_ref(), runs, &opts.weak, latency);
    let fitted = match &final_state {
        Some(st) if !st.effects.is_empty() || excess > 0.0 => Some(st),
        _ => base.state.as_ref(),
    }
    .map(|st| super::spec::FittedTheta {
        terms: st.terms.clone(),
        fit_latency: st.fit_latency,
        theta: st.fit.theta.clone(),
        cov: st.fit.cov.clone(),
    });
    Ok(Diagnosis {
        report: Report {
            schema: SCHEMA.into(),
            baseline,
            mismatch,
            findings,
            // decided with the remainder ([`super::verdict::decide`])
            verdict: super::verdict::NONE.into(),
            fits: Some(fits),
            remaining: None,
            assessment: None,
            curve: None,
        },
        runs: prep.runs,
        files: prep.files,
        base: base_coef,
        augmented,
        latency,
        ringdowns: prep.ringdowns,
        kappa: prep.kappa,
        base_pred,
        aug_pred,
        fingerprint,
        fitted,
    })
}

/// The base model's parameters for the report: the weak-form fit's (g, Δ, ζ, η with their σ and
/// what they imply against the set-up's nominal coupling), replaced by the refit by simulation's
/// when there is one (the weak-form values kept under `*_weak_form`), and the weak form's χ²/dof
/// and row counts.
fn baseline_params(set: &RecordingSet, base: &BaseModel) -> BTreeMap<String, f64> {
    let setup = &set.gear;
    let w = &base.weak;
    let err = |k: usize| w.cov[(k, k)].max(0.0).sqrt();
    let mut params = base_params(
        (w.coef[0], err(0)),
        (w.coef[1], err(1)),
        (w.coef[2], err(2)),
        (w.coef[3], err(3)),
        setup.coupling(),
        setup.coupling_rel_tol(),
    );
    if let Some(sb) = &base.state {
        for k in ["g", "delta", "zeta", "eta"] {
            for suffix in ["", "_err"] {
                if let Some(v) = params.get(&format!("{k}{suffix}")).copied() {
                    params.insert(format!("{k}_weak_form{suffix}"), v);
                }
            }
        }
        let f = &sb.fit;
        params.extend(base_params(
            (f.theta[0], f.err[0]),
            (f.theta[1], f.err[1]),
            (f.theta[2], f.err[2]),
            (f.theta[3], f.err[3]),
            setup.coupling(),
            setup.coupling_rel_tol(),
        ));
        params.insert("simulation_refit_windows".into(), f.used.len() as f64);
    }
    params.insert("eq_chi2_per_dof".to_string(), w.chi2_dof);
    params.insert("n_rows".to_string(), w.n as f64);
    params.insert("n_eff".to_string(), w.n_eff);
    params
}

/// The report's `fits` document: ring-down and κ(α0) fits, the cleaning's noise and outliers,
/// the final model's coefficients, the rejected candidates and the judge's settings.
fn fits_document(
    opts: &DiagnoseOptions,
    prep: &Prepared,
    base: &BaseModel,
    final_state: Option<&ModelState>,
    latency: f64,
    (tried, rivals): (&[Tried], &Rivals),
) -> serde_json::Value {
    let runs = &prep.runs;
    let final_map: BTreeMap<String, serde_json::Value> = final_state
        .map(|st| {
            super::findings::coefficient_map(st)
                .into_iter()
                .map(|(k, v)| (k, json!([v.0, v.1])))
                .collect()
        })
        .unwrap_or_default();
    json!({
        "ringdowns": prep.ringdowns,
        "kappa_alpha0": prep.kappa,
        "noise_rad": runs.iter().map(|r| r.sigma_beta).collect::<Vec<_>>(),
        "outliers_rejected": runs.iter().map(|r| r.outliers).collect::<Vec<_>>(),
        "augmented_coefficients": final_map,
        "latency_s": latency,
        "rejected_candidates": rejected(tried),
        "selection_forks": rivals.forks,
        "selection_joints": rivals.joints,
        "judge": {
            "folds": if base.wins.is_empty() { 0 } else { opts.folds },
            "windows": base.wins.len(),
            "base_heldout_rms_rad": base.state.as_ref().map(|s| rms_rad(&s.held.chi2, &base.wins, runs)),
            "base_fit_rms_rad": base.state.as_ref().map(|s| rms_rad(&s.held.chi2_fit, &base.wins, runs)),
            "rule": "held-out prediction by k-fold over runs; paired window χ² gain, cluster-robust z by run; z ≥ max(3, Φ⁻¹(1 − 0.01/m)), m candidates in the round",
        },
        "outlier_handling": "rejection: leave-one-out local cubic prediction, 6 robust σ; Huber weights (2.5 σ) in the regression; frames beyond 5σ masked in the windows",
    })
}

/// (α, β, β̇, base residual, final residual) of every weak-form row: the final model's
/// coefficients from the refit by simulation applied to the rows of its terms.
fn fingerprints(
    base: &BaseModel,
    fin: Option<&ModelState>,
    runs: &[CleanRun],
    weak: &WeakOptions,
    latency: f64,
) -> Vec<(f64, f64, f64, f64, f64)> {
    let d0 = &base.design;
    let final_resid: Vec<f64> = match fin {
        Some(st) if !st.effects.is_empty() => {
            let cols = super::propose::weak_columns(&st.terms, &st.fit.theta);
            let d = build(runs, &base.geo, &cols, weak, latency);
            (0..d.rows())
                .map(|i| {
                    d.y[i]
                        - (0..st.terms.len())
                            .map(|k| st.fit.theta[k] * d.at(i, k))
                            .sum::<f64>()
                })
                .collect()
        }
        _ => base.weak.resid.clone(),
    };
    (0..d0.rows())
        .map(|i| {
            let c = d0.centre[i];
            (
                c.0,
                c.1,
                c.2,
                base.weak.resid[i],
                final_resid.get(i).copied().unwrap_or(f64::NAN),
            )
        })
        .collect()
}

/// The baseline table from the base coefficients (value, 1σ) of ζ, η, c_sc = −g and c_cs = gΔ:
/// g, Δ, ζ, η and I = c/g (σ_I with the set-up's relative tolerance on c), each with `_err`.
fn base_params(
    zeta: (f64, f64),
    eta: (f64, f64),
    c_sc: (f64, f64),
    c_cs: (f64, f64),
    c: f64,
    c_rel_tol: f64,
) -> BTreeMap<String, f64> {
    let (g, ge) = (-c_sc.0, c_sc.1);
    let (cs, cse) = c_cs;
    [
        ("g", g),
        ("g_err", ge),
        ("delta", cs / g),
        (
            "delta_err",
            ((cse / g).powi(2) + (cs * ge / (g * g)).powi(2)).sqrt(),
        ),
        ("zeta", zeta.0),
        ("zeta_err", zeta.1),
        ("eta", eta.0),
        ("eta_err", eta.1),
        ("inertia", c / g),
        (
            "inertia_err",
            c / g * ((ge / g).powi(2) + c_rel_tol.powi(2)).sqrt(),
        ),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), v))
    .collect()
}

/// The geometry with both shaft angles shifted by a common amount so that Δ matches the fitted
/// value (within ±15°; the nominal geometry when no shift matches).
pub fn refine_geometry(nominal: &Geometry, delta_fit: f64) -> Geometry {
    if !delta_fit.is_finite() {
        return *nominal;
    }
    let mut best = (f64::INFINITY, 0.0);
    for k in -1500..=1500 {
        let s = (k as f64 * 0.01).to_radians();
        let e = (crate::model::gear::shaft_index(nominal.theta() + s, nominal.phi() + s)
            - delta_fit)
            .abs();
        if e < best.0 {
            best = (e, s);
        }
    }
    if best.0 < 1e-3 {
        Geometry::new(nominal.theta() + best.1, nominal.phi() + best.1)
    } else {
        *nominal
    }
}
