//! The diagnosis: refit the base model, locate the mismatch, name the missing physics, show the fit
//! improve, and write the report.
//!
//! Selection: forward, one effect at a time. A candidate is accepted when it lowers the BIC computed
//! with the effective sample size by more than [`DiagnoseOptions::bic_threshold`] *and* lowers the
//! leave-one-run-out prediction error of the equation-error rows (whole runs held out). When no
//! candidate passes both, the base model with refitted parameters explains the data at the noise
//! level and the verdict is `none`.

use super::catalog::{catalog, dictionary, effect_params, same_slot, Effect};
use super::model::{Coefficients, ExtraTerm, Geometry};
use super::predict::{predict, Prediction};
use super::preprocess::{clean, CleanRun};
use super::regression::{
    build, coef_without, delta_bic, fit, loro, session_positions, Clock, Design, DriftParam,
    LinFit, Term, WeakOptions, BASE_TERMS,
};
use super::report::{Baseline, Finding, Mismatch, Report, RunRms, SCHEMA};
use super::ringdown::{fit_kappa, fit_ringdown, KappaFit, RingdownFit};
use super::shooting::{refit_by_simulation, ShootingOptions, SimRefit};
use crate::error::{Error, Result};
use crate::io::recordings::{RecordingSet, RunKind};
use serde_json::json;
use std::collections::BTreeMap;

/// Options of the diagnosis.
#[derive(Debug, Clone, PartialEq)]
pub struct DiagnoseOptions {
    /// Weak-form options.
    pub weak: WeakOptions,
    /// Most effects to accept.
    pub max_effects: usize,
    /// Required BIC decrease.
    pub bic_threshold: f64,
    /// Compute held-out short-horizon predictions (leave-one-run-out refits).
    pub heldout_predictions: bool,
    /// Fit the ring-downs one by one by simulation (eq. `model`).
    pub ringdown_fits: bool,
    /// Latency grid half-width, s, for the `sensor_latency` profile.
    pub latency_span: f64,
    /// The noise-level gate: an accepted term must lower χ² by at least this much per row, i.e.
    /// explain at least this fraction of the camera-noise variance of a row. Below it the term is
    /// statistically detectable on a large set but smaller than the systematic error of the weak
    /// form, and the data are explained "to the noise level".
    pub min_chi2_gain_per_row: f64,
    /// Refit the base and the final augmented model by simulation (multiple shooting over short
    /// windows, [`refit_by_simulation`]); the reported parameters then come from it.
    pub simulation_refit: bool,
    /// Options of that refit.
    pub shooting: ShootingOptions,
    /// Fit the base model only (`gearbif fit`): no effect selection, no dictionary search, no
    /// static-friction profile.
    pub base_only: bool,
}

impl Default for DiagnoseOptions {
    fn default() -> Self {
        Self {
            weak: WeakOptions::default(),
            max_effects: 3,
            bic_threshold: 10.0,
            heldout_predictions: true,
            ringdown_fits: true,
            latency_span: 0.03,
            min_chi2_gain_per_row: 0.005,
            simulation_refit: true,
            shooting: ShootingOptions::default(),
            base_only: false,
        }
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
}

/// Converts fitted columns to model coefficients (dictionary terms go to the
/// [`Coefficients::extra`] slots, at most [`super::model::MAX_EXTRA`]; drift terms need the run:
/// see [`coefficients_for_run`]).
pub fn to_coefficients(d: &Design, fitr: &LinFit, coef: &[f64]) -> Coefficients {
    let mut c = Coefficients::default();
    let (mut compliance, mut offset, mut offset_rate) = (0.0, 0.0, 0.0);
    for (k, &col) in fitr.cols.iter().enumerate() {
        let v = coef[k];
        match d.terms[col] {
            Term::Zeta => c.zeta = v,
            Term::Eta => c.eta = v,
            Term::SinACosB => c.c_sc = v,
            Term::CosASinB => c.c_cs = v,
            Term::CosACosB => c.c_cc = v,
            Term::SinASinB => c.c_ss = v,
            Term::SinB => c.st_a = v,
            Term::CosB => c.st_b = v,
            Term::Quad => c.quad = v,
            Term::Corot => c.corot = v,
            Term::LoadFric => c.eta_load = v,
            Term::Compliance => compliance = v,
            Term::DrivenOffset => offset = v,
            Term::DrivenOffsetRate => offset_rate = v,
            _ => {
                let extra = match d.terms[col] {
                    Term::Cos(k, l) => Some(ExtraTerm::Trig { k, l, sin: false }),
                    Term::Sin(k, l) => Some(ExtraTerm::Trig { k, l, sin: true }),
                    Term::VCosB => Some(ExtraTerm::VelCos),
                    Term::VSinB => Some(ExtraTerm::VelSin),
                    Term::SCosB => Some(ExtraTerm::FricCos),
                    Term::SSinB => Some(ExtraTerm::FricSin),
                    _ => None,
                };
                if let (Some(e), Some(slot)) =
                    (extra, c.extra.iter_mut().find(|s| s.0 == ExtraTerm::Unused))
                {
                    *slot = (e, v);
                }
            }
        }
    }
    // coefficients χg², −gε, −g·(ε per turn) (regression.rs)
    let g = c.g();
    if g != 0.0 {
        c.compliance = compliance / (g * g);
        c.alpha_offset = -offset / g;
        c.alpha_offset_per_turn = -offset_rate / g;
    }
    c
}

/// The coefficients that hold in run `run`: [`to_coefficients`] plus the parameter drift at the
/// run's session position (its middle) and the driven-run input offsets only on driven runs.
pub fn coefficients_for_run(
    d: &Design,
    fitr: &LinFit,
    coef: &[f64],
    runs: &[CleanRun],
    run: usize,
) -> Coefficients {
    let mut c = to_coefficients(d, fitr, coef);
    if runs[run].ringdown {
        c.alpha_offset = 0.0;
        c.alpha_offset_per_turn = 0.0;
    }
    let pos = session_positions(runs)[run];
    for (k, &col) in fitr.cols.iter().enumerate() {
        if let Term::Drift(p, clock) = d.terms[col] {
            let s = match clock {
                Clock::RunIndex => pos.0,
                Clock::SessionTime => pos.1,
            };
            let dv = coef[k] * s;
            match p {
                DriftParam::Zeta => c.zeta += dv,
                DriftParam::Eta => c.eta += dv,
                DriftParam::Coupling => {
                    // g(s) = g + dv scales the base coupling −g sin α cos β + gΔ cos α sin β
                    let g = c.g();
                    if g != 0.0 {
                        let scale = (g + dv) / g;
                        c.c_sc *= scale;
                        c.c_cs *= scale;
                    }
                }
            }
        }
    }
    c
}

fn all_terms() -> Vec<Term> {
    let mut t: Vec<Term> = BASE_TERMS.to_vec();
    for e in catalog() {
        for term in e.terms {
            if !t.contains(&term) {
                t.push(term);
            }
        }
    }
    for term in dictionary() {
        if !t.contains(&term) {
            t.push(term);
        }
    }
    t
}

fn cols_of(d: &Design, terms: &[Term]) -> Vec<usize> {
    terms.iter().filter_map(|&t| d.col(t)).collect()
}

/// Rows of `d` selected by `keep(row)`.
fn subset(d: &Design, keep: impl Fn(usize) -> bool) -> Design {
    let p = d.terms.len();
    let mut s = Design {
        terms: d.terms.clone(),
        y: vec![],
        x: vec![],
        sigma: vec![],
        run: vec![],
        tc: vec![],
        centre: vec![],
    };
    for i in 0..d.rows() {
        if keep(i) {
            s.y.push(d.y[i]);
            s.x.extend_from_slice(&d.x[i * p..(i + 1) * p]);
            s.sigma.push(d.sigma[i]);
            s.run.push(d.run[i]);
            s.tc.push(d.tc[i]);
            s.centre.push(d.centre[i]);
        }
    }
    s
}

/// Significance of a group of regressors in explaining the residuals `r` (weights 1/σ², the
/// covariance inflated by n/n_eff): returns (amplitude of the fitted component, Δχ², dof).
fn fingerprint_group(
    r: &[f64],
    sigma: &[f64],
    regs: &[Vec<f64>],
    infl: f64,
) -> Option<(f64, f64, usize)> {
    let p = regs.len();
    let n = r.len();
    if n <= p + 2 {
        return None;
    }
    let mut a = nalgebra::DMatrix::<f64>::zeros(p, p);
    let mut b = nalgebra::DVector::<f64>::zeros(p);
    for i in 0..n {
        let w = 1.0 / (sigma[i] * sigma[i]);
        for k in 0..p {
            b[k] += w * regs[k][i] * r[i];
            for l in 0..p {
                a[(k, l)] += w * regs[k][i] * regs[l][i];
            }
        }
    }
    let inv = a.clone().try_inverse()?;
    let x = &inv * &b;
    let dchi = (x.transpose() * &b)[(0, 0)] / infl;
    Some((x.norm(), dchi, p))
}

/// (ΔBIC, effect index, fit, CV score, latency (τ, σ_τ, design) when profiled).
type Candidate = (f64, usize, LinFit, f64, Option<(f64, f64, Design)>);

/// Runs the diagnosis of a recording set. `progress` receives one line per step.
pub fn diagnose(
    set: &RecordingSet,
    opts: &DiagnoseOptions,
    progress: &dyn Fn(&str),
) -> Result<Diagnosis> {
    if set.runs.is_empty() {
        return Err(Error::InvalidInput("the recording set has no runs".into()));
    }
    let setup = &set.gear;
    let geo = Geometry {
        theta: setup.theta_deg.to_radians(),
        phi: setup.phi_deg.to_radians(),
    };
    let hint = setup.beta_noise_deg.map(|d| d.to_radians());
    progress("cleaning runs (outlier rejection, noise, velocity)");
    let mut runs: Vec<CleanRun> = set.runs.iter().map(|r| clean(r, hint)).collect();
    // one camera: its noise is a property of the set. Runs sampled too coarsely for a local cubic
    // show a larger per-run scatter (signal the cubic cannot follow); that per-run level weights
    // their rows, while the camera noise (median over runs) sets the outlier threshold of the
    // predictions.
    if hint.is_none() {
        let mut s: Vec<f64> = runs.iter().map(|r| r.sigma_beta).collect();
        s.sort_by(|a, b| a.total_cmp(b));
        let pooled = s[s.len() / 2];
        for r in &mut runs {
            r.sigma_camera = pooled;
        }
    }
    let files: Vec<String> = set.runs.iter().map(|r| r.file.clone()).collect();
    let nr = runs.len();

    // ---- ring-downs by simulation
    let mut ringdowns = Vec::new();
    if opts.ringdown_fits {
        let rd: Vec<usize> = (0..nr).filter(|&i| runs[i].ringdown).collect();
        for (k, &i) in rd.iter().enumerate() {
            progress(&format!(
                "ring-down fit {}/{}: {}",
                k + 1,
                rd.len(),
                files[i]
            ));
            if let RunKind::Ringdown { alpha0 } = set.runs[i].kind {
                if let Some(f) = fit_ringdown(
                    &runs[i],
                    &files[i],
                    alpha0,
                    setup.zeta.unwrap_or(1.1),
                    setup.eta.unwrap_or(23.1),
                ) {
                    ringdowns.push(f);
                }
            }
        }
    }
    let kappa = fit_kappa(&ringdowns, setup);

    // ---- weak-form design and base fit
    progress("equation-error rows (weak form)");
    let terms = all_terms();
    let mut design = build(&runs, &geo, &terms, &opts.weak, 0.0);
    let base_cols = cols_of(&design, &BASE_TERMS);
    let base_fit = fit(&design, &base_cols).ok_or_else(|| {
        Error::InvalidInput(
            "too few usable samples for the equation-error fit (runs too short or always at rest)"
                .into(),
        )
    })?;
    let base_coef = to_coefficients(&design, &base_fit, &base_fit.coef);
    let (g, ge) = base_fit
        .get(base_cols[2])
        .map(|(v, e)| (-v, e))
        .unwrap_or((f64::NAN, f64::NAN));
    let (cs, cse) = base_fit.get(base_cols[3]).unwrap_or((f64::NAN, f64::NAN));
    let (zeta, zeta_e) = base_fit.get(base_cols[0]).unwrap_or((f64::NAN, f64::NAN));
    let (eta, eta_e) = base_fit.get(base_cols[1]).unwrap_or((f64::NAN, f64::NAN));
    let delta = cs / g;
    let mut params = base_params(
        (zeta, zeta_e),
        (eta, eta_e),
        (-g, ge),
        (cs, cse),
        setup.coupling(),
        setup.coupling_rel_tol(),
    );

    // ---- geometry refined from the fitted Δ (a common shift of both shaft angles), used by the
    // force shape h(α, β) of load-dependent friction; the remaining freedom (how the shift is
    // split between Θ and Φ, within the tolerance) becomes a systematic uncertainty below
    let geo_nominal = geo;
    let geo = refine_geometry(&geo_nominal, delta);
    if geo != geo_nominal {
        design = build(&runs, &geo, &terms, &opts.weak, 0.0);
    }
    let tol_split = setup.theta_tol_deg.unwrap_or(3.0).to_radians();

    // ---- mismatch
    progress("locating the mismatch (fingerprints, symmetry, consistency)");
    let mut mismatch = Vec::new();
    let infl = base_fit.n as f64 / base_fit.n_eff;
    let mut chi_run = vec![f64::NAN; nr];
    for (r, cr) in chi_run.iter_mut().enumerate() {
        let idx: Vec<usize> = (0..design.rows()).filter(|&i| design.run[i] == r).collect();
        if !idx.is_empty() {
            *cr = idx
                .iter()
                .map(|&i| (base_fit.resid[i] / design.sigma[i]).powi(2))
                .sum::<f64>()
                / idx.len() as f64;
        }
    }
    let bad: Vec<(String, f64)> = (0..nr)
        .filter(|&r| chi_run[r] > 2.0)
        .map(|r| (files[r].clone(), chi_run[r]))
        .collect();
    if !bad.is_empty() {
        mismatch.push(Mismatch {
            where_: format!(
                "{} of {} runs have equation-error residuals above twice the noise (χ²/row > 2; \
                 missing physics, or sampling too coarse for the run's dynamics)",
                bad.len(),
                nr
            ),
            evidence: bad.iter().map(|(f, c)| (f.clone(), json!(c))).collect(),
        });
    }
    {
        let rr = &base_fit.resid;
        let (cen, sig) = (&design.centre, &design.sigma);
        let drv = |i: usize| !runs[design.run[i]].ringdown;
        let groups: Vec<(&str, String, Vec<Vec<f64>>, bool)> = vec![
            (
                "alpha_h1",
                "once per input turn (harmonic 1 of α, driven runs)".into(),
                vec![
                    cen.iter().map(|c| c.0.cos()).collect(),
                    cen.iter().map(|c| c.0.sin()).collect(),
                ],
                true,
            ),
            (
                "alpha_h2",
                "twice per input turn (harmonic 2 of α, driven runs)".into(),
                vec![
                    cen.iter().map(|c| (2.0 * c.0).cos()).collect(),
                    cen.iter().map(|c| (2.0 * c.0).sin()).collect(),
                ],
                true,
            ),
            (
                "beta_h1",
                "once per output turn (harmonic 1 of β): a lab-fixed torque".into(),
                vec![
                    cen.iter().map(|c| c.1.cos()).collect(),
                    cen.iter().map(|c| c.1.sin()).collect(),
                ],
                false,
            ),
            (
                "beta_h2",
                "twice per output turn (harmonic 2 of β)".into(),
                vec![
                    cen.iter().map(|c| (2.0 * c.1).cos()).collect(),
                    cen.iter().map(|c| (2.0 * c.1).sin()).collect(),
                ],
                false,
            ),
            (
                "velocity",
                "with the output velocity (β̇ and β̇|β̇|): damping law".into(),
                vec![
                    cen.iter().map(|c| c.2).collect(),
                    cen.iter().map(|c| c.2 * c.2.abs()).collect(),
                ],
                false,
            ),
            (
                "sign",
                "with the sign of the velocity: dry friction law".into(),
                vec![cen.iter().map(|c| c.2.signum()).collect()],
                false,
            ),
        ];
        for (key, words, regs, driven_only) in groups {
            let keep: Vec<usize> = (0..design.rows())
                .filter(|&i| !driven_only || drv(i))
                .collect();
            let r: Vec<f64> = keep.iter().map(|&i| rr[i]).collect();
            let s: Vec<f64> = keep.iter().map(|&i| sig[i]).collect();
            let rg: Vec<Vec<f64>> = regs
                .iter()
                .map(|v| keep.iter().map(|&i| v[i]).collect())
                .collect();
            if let Some((amp, dchi, dof)) = fingerprint_group(&r, &s, &rg, infl) {
                // significant at a BIC-like level: Δχ² > dof·ln(n_eff) + 10
                // significant (BIC-like) and above the noise-level gate
                if dchi > dof as f64 * base_fit.n_eff.ln() + 10.0
                    && dchi * infl / r.len() as f64 >= opts.min_chi2_gain_per_row
                {
                    mismatch.push(Mismatch {
                        where_: format!("residual acceleration varies {words}"),
                        evidence: [
                            (format!("{key}_amplitude_rad_s2"), json!(amp)),
                            ("delta_chi2_eff".to_string(), json!(dchi)),
                            ("dof".to_string(), json!(dof)),
                        ]
                        .into_iter()
                        .collect(),
                    });
                }
            }
        }
    }
    // symmetry test: a flexible symmetric model (base, symmetric catalog and dictionary terms)
    // against the same plus every symmetry-breaking term
    let sym_terms: Vec<Term> = design
        .terms
        .iter()
        .copied()
        .filter(|t| t.breaks_symmetry())
        .collect();
    let symm_terms: Vec<Term> = design
        .terms
        .iter()
        .copied()
        .filter(|t| !t.breaks_symmetry())
        .collect();
    let symm_cols = cols_of(&design, &symm_terms);
    let symm_fit = fit(&design, &symm_cols);
    let mut sym_cols = symm_cols.clone();
    sym_cols.extend(cols_of(&design, &sym_terms));
    if let (Some(sf), Some(s0)) = (fit(&design, &sym_cols), symm_fit.as_ref()) {
        let dbic = delta_bic(&sf, s0);
        let broken = dbic < -opts.bic_threshold;
        mismatch.push(Mismatch {
            where_: if broken {
                "the symmetry (α, β) → (α+π, β+π) of the base model is broken: something lab-fixed acts on the output".into()
            } else {
                "symmetry (α, β) → (α+π, β+π) holds within the noise".into()
            },
            evidence: [
                ("delta_bic".to_string(), json!(dbic)),
                ("terms".to_string(), json!(sym_terms.len())),
                ("broken".to_string(), json!(broken)),
            ]
            .into_iter()
            .collect(),
        });
    }
    // consistency between ring-downs and driven runs
    let has_rd = runs.iter().any(|r| r.ringdown);
    let has_dr = runs.iter().any(|r| !r.ringdown);
    if has_rd && has_dr {
        let drd = subset(&design, |i| runs[design.run[i]].ringdown);
        let ddr = subset(&design, |i| !runs[design.run[i]].ringdown);
        if let (Some(a), Some(b)) = (fit(&drd, &base_cols), fit(&ddr, &base_cols)) {
            let mut ev = BTreeMap::new();
            let mut worst: (f64, &str) = (0.0, "");
            for (k, name) in [
                "zeta",
                "eta",
                "c_sin_alpha_cos_beta",
                "c_cos_alpha_sin_beta",
            ]
            .iter()
            .enumerate()
            {
                let (va, ea) = (a.coef[k], a.cov[(k, k)].sqrt());
                let (vb, eb) = (b.coef[k], b.cov[(k, k)].sqrt());
                let z = (va - vb) / (ea * ea + eb * eb).sqrt();
                ev.insert(format!("{name}_ringdowns"), json!(va));
                ev.insert(format!("{name}_driven"), json!(vb));
                ev.insert(format!("{name}_z"), json!(z));
                if z.abs() > worst.0 {
                    worst = (z.abs(), name);
                }
            }
            if worst.0 > 3.0 {
                mismatch.push(Mismatch {
                    where_: format!(
                        "ring-downs and driven runs disagree on {} ({:.1} σ)",
                        worst.1, worst.0
                    ),
                    evidence: ev,
                });
            }
        }
    }
    if let Some(k) = &kappa {
        if k.once_per_turn_err.is_finite() && k.once_per_turn > 3.0 * k.once_per_turn_err {
            mismatch.push(Mismatch {
                where_: "ring-downs: stiffness κ not 180°-periodic in α0".into(),
                evidence: [
                    (
                        "once_per_turn_amplitude".to_string(),
                        json!(k.once_per_turn),
                    ),
                    ("once_per_turn_err".to_string(), json!(k.once_per_turn_err)),
                ]
                .into_iter()
                .collect(),
            });
        }
        let z = (k.delta_abs - k.delta_nominal.abs())
            / (k.delta_err.powi(2) + k.delta_nominal_err.powi(2)).sqrt();
        if z.abs() > 3.0 {
            mismatch.push(Mismatch {
                where_: "ring-downs: |Δ| from κ(α0) differs from the nominal shaft angles".into(),
                evidence: [
                    ("delta_abs".to_string(), json!(k.delta_abs)),
                    ("delta_nominal".to_string(), json!(k.delta_nominal)),
                    ("z".to_string(), json!(z)),
                ]
                .into_iter()
                .collect(),
            });
        }
    }

    // ---- selection
    let effects = catalog();
    let mut model_terms: Vec<Term> = BASE_TERMS.to_vec();
    let mut current = base_fit.clone();
    let (mut current_per, mut current_cv) = loro(&design, &current, nr);
    let mut latency = 0.0;
    let mut latency_err = f64::NAN;
    struct Accepted {
        effect: Effect,
        dbic: f64,
        cv_before: f64,
        cv_after: f64,
        eq_rms_before: f64,
        eq_rms_after: f64,
        latency: f64,
        latency_err: f64,
        terms_after: Vec<Term>,
        latency_after: f64,
        dictionary_terms: Vec<Term>,
    }
    let mut accepted: Vec<Accepted> = Vec::new();
    let mut tried_latency = false;
    let rounds = if opts.base_only { 0 } else { opts.max_effects };
    for round in 0..rounds {
        progress(&format!("selecting effects, round {}", round + 1));
        let mut best: Option<Candidate> = None;
        for (ei, e) in effects.iter().enumerate() {
            if accepted.iter().any(|a| same_slot(&a.effect, e)) {
                continue;
            }
            if e.id == "sensor_latency" {
                if !has_dr || tried_latency && latency != 0.0 {
                    continue;
                }
                if let Some((tau, tau_err, dbic, d2, f2)) =
                    profile_latency(&runs, &geo, &model_terms, opts, &current)
                {
                    let (per, cv) = loro(&d2, &f2, nr);
                    if dbic < -opts.bic_threshold
                        && (current.chi2 - f2.chi2) / f2.n as f64 >= opts.min_chi2_gain_per_row
                        && cv < current_cv
                        && generalises(&per, &current_per)
                        && best.as_ref().map(|b| dbic < b.0).unwrap_or(true)
                    {
                        best = Some((dbic, ei, f2, cv, Some((tau, tau_err, d2))));
                    }
                }
                continue;
            }
            let mut cols = cols_of(&design, &model_terms);
            cols.extend(cols_of(&design, &e.terms));
            let Some(f2) = fit(&design, &cols) else {
                continue;
            };
            let dbic = delta_bic(&f2, &current);
            let (per, cv) = loro(&design, &f2, nr);
            if dbic < -opts.bic_threshold
                && (current.chi2 - f2.chi2) / f2.n as f64 >= opts.min_chi2_gain_per_row
                && cv < current_cv
                && generalises(&per, &current_per)
                && best.as_ref().map(|b| dbic < b.0).unwrap_or(true)
            {
                best = Some((dbic, ei, f2, cv, None));
            }
        }
        tried_latency = true;
        let Some((dbic, ei, f2, cv, lat)) = best else {
            break;
        };
        let e = effects[ei].clone();
        let (mut lt, mut lte) = (f64::NAN, f64::NAN);
        if let Some((tau, tau_err, _d2)) = lat {
            latency = tau;
            latency_err = tau_err;
            lt = tau;
            lte = tau_err;
            design = build(&runs, &geo, &terms, &opts.weak, latency);
        } else {
            model_terms.extend(e.terms.iter().copied());
        }
        let newfit = fit(&design, &cols_of(&design, &model_terms)).unwrap_or(f2);
        accepted.push(Accepted {
            effect: e,
            dbic,
            cv_before: current_cv,
            cv_after: cv,
            eq_rms_before: current.rms,
            eq_rms_after: newfit.rms,
            latency: lt,
            latency_err: lte,
            terms_after: model_terms.clone(),
            latency_after: latency,
            dictionary_terms: vec![],
        });
        current = newfit;
        (current_per, current_cv) = loro(&design, &current, nr);
    }
    // ---- sparse search beyond the catalog
    progress("sparse dictionary search");
    let dict = dictionary();
    let mut dict_terms: Vec<Term> = Vec::new();
    let mut dict_fit = current.clone();
    let mut dict_cv = current_cv;
    let mut dict_per = current_per.clone();
    let dict_cv0 = current_cv;
    let dict_rms0 = current.rms;
    let mut dict_dbic = 0.0;
    for _ in 0..if opts.base_only { 0 } else { 3 } {
        let mut best: Option<(f64, Term, LinFit, f64)> = None;
        for &t in &dict {
            if dict_terms.contains(&t) {
                continue;
            }
            let mut cols = cols_of(&design, &model_terms);
            cols.extend(cols_of(&design, &dict_terms));
            cols.extend(cols_of(&design, &[t]));
            let Some(f2) = fit(&design, &cols) else {
                continue;
            };
            let db = delta_bic(&f2, &dict_fit);
            if db < -opts.bic_threshold
                && (dict_fit.chi2 - f2.chi2) / f2.n as f64 >= opts.min_chi2_gain_per_row
                && best.as_ref().map(|b| db < b.0).unwrap_or(true)
            {
                let (per, cv) = loro(&design, &f2, nr);
                if cv < dict_cv && generalises(&per, &dict_per) {
                    best = Some((db, t, f2, cv));
                }
            }
        }
        let Some((db, t, f2, cv)) = best else { break };
        dict_per = loro(&design, &f2, nr).0;
        dict_terms.push(t);
        dict_dbic += db;
        dict_fit = f2;
        dict_cv = cv;
    }
    if !dict_terms.is_empty() {
        accepted.push(Accepted {
            effect: Effect {
                id: "unexplained",
                class: "unexplained",
                explanation: "structured residual that no catalogued term explains; the best \
                              dictionary terms are named in params/evidence",
                terms: dict_terms.clone(),
                candidates: vec![],
                discriminating_experiment: "",
            },
            dbic: dict_dbic,
            cv_before: dict_cv0,
            cv_after: dict_cv,
            eq_rms_before: dict_rms0,
            eq_rms_after: dict_fit.rms,
            latency: f64::NAN,
            latency_err: f64::NAN,
            terms_after: model_terms.clone(),
            latency_after: latency,
            dictionary_terms: dict_terms.clone(),
        });
    }

    // ---- predictions (base, then each accepted stage)
    progress("short-horizon predictions");
    let stage_fit = |terms_s: &[Term], lat: f64| -> Option<(Design, LinFit)> {
        let d = build(&runs, &geo, &terms, &opts.weak, lat);
        let f = fit(&d, &cols_of(&d, terms_s))?;
        Some((d, f))
    };
    let design0 = build(&runs, &geo, &terms, &opts.weak, 0.0);
    // predictions with the coefficients `coef` of the columns of `f` (the weak-form fit or its
    // refit by simulation); held out: shifted by the change of the weak-form fit when run r is
    // left out (a first-order leave-one-run-out of the refit)
    let pred_stage =
        |d: &Design, f: &LinFit, coef: &[f64], lat: f64| -> (Vec<Prediction>, Vec<Option<f64>>) {
            let preds: Vec<Prediction> = (0..nr)
                .map(|r| {
                    let c = coefficients_for_run(d, f, coef, &runs, r);
                    predict(&runs[r], &c, &geo, lat)
                })
                .collect();
            let held: Vec<Option<f64>> = if opts.heldout_predictions {
                (0..nr)
                    .map(|r| {
                        let cw = coef_without(d, f, r)?;
                        let shifted: Vec<f64> = (0..coef.len())
                            .map(|k| coef[k] + cw[k] - f.coef[k])
                            .collect();
                        let c = coefficients_for_run(d, f, &shifted, &runs, r);
                        Some(predict(&runs[r], &c, &geo, lat).rms)
                    })
                    .collect()
            } else {
                vec![None; nr]
            };
            (preds, held)
        };
    let pooled = |p: &[Prediction]| -> f64 {
        let (mut ss, mut n) = (0.0, 0usize);
        for q in p {
            for r in &q.resid {
                ss += r * r;
                n += 1;
            }
        }
        if n > 0 {
            (ss / n as f64).sqrt()
        } else {
            f64::NAN
        }
    };
    let pooled_held = |h: &[Option<f64>], p: &[Prediction]| -> Option<f64> {
        let (mut ss, mut n) = (0.0, 0usize);
        for (hh, q) in h.iter().zip(p) {
            let hv = (*hh)?;
            ss += hv * hv * q.resid.len() as f64;
            n += q.resid.len();
        }
        if n > 0 {
            Some((ss / n as f64).sqrt())
        } else {
            None
        }
    };
    // ---- refits by simulation (base, final augmented model)
    let latency_accepted = accepted.iter().any(|a| a.effect.id == "sensor_latency");
    let sim_base: Option<SimRefit> = if opts.simulation_refit {
        progress("refit of the base model by simulation (multiple shooting)");
        refit_by_simulation(&design0, &base_fit, &runs, &geo, 0.0, false, &opts.shooting)
    } else {
        None
    };
    // a fit on the final design (at the accepted latency, refitted with it)
    let refit_with_latency = |f: &LinFit| {
        refit_by_simulation(
            &design,
            f,
            &runs,
            &geo,
            latency,
            latency_accepted,
            &opts.shooting,
        )
    };
    let final_stage = accepted.iter().rposition(|a| a.effect.id != "unexplained");
    let sim_final: Option<SimRefit> = if opts.simulation_refit && final_stage.is_some() {
        progress("refit of the augmented model by simulation (multiple shooting)");
        refit_with_latency(&current)
    } else {
        None
    };
    if let Some(sb) = &sim_base {
        // base parameters from the refit by simulation; the weak-form values stay beside them
        for k in ["g", "delta", "zeta", "eta"] {
            for suffix in ["", "_err"] {
                if let Some(v) = params.get(&format!("{k}{suffix}")).copied() {
                    params.insert(format!("{k}_weak_form{suffix}"), v);
                }
            }
        }
        let at = |t: Term| {
            base_cols
                .iter()
                .position(|&c| design0.terms[c] == t)
                .map(|k| (sb.coef[k], sb.err[k]))
        };
        if let (Some(z), Some(e), Some(sc), Some(cs)) = (
            at(Term::Zeta),
            at(Term::Eta),
            at(Term::SinACosB),
            at(Term::CosASinB),
        ) {
            params.extend(base_params(
                z,
                e,
                sc,
                cs,
                setup.coupling(),
                setup.coupling_rel_tol(),
            ));
            params.insert("simulation_refit_windows".into(), sb.windows as f64);
        }
    }
    // the model with the dictionary terms (an `unexplained` finding), refitted the same way
    let sim_dict: Option<SimRefit> =
        if opts.simulation_refit && accepted.iter().any(|a| a.effect.id == "unexplained") {
            progress("refit of the model with the dictionary terms by simulation");
            refit_with_latency(&dict_fit)
        } else {
            None
        };
    let base_sim_coef = sim_base
        .as_ref()
        .map(|s| s.coef.clone())
        .unwrap_or_else(|| base_fit.coef.clone());
    let (base_pred, base_held) = pred_stage(&design0, &base_fit, &base_sim_coef, 0.0);
    let mut stage_rms = vec![(
        Some(pooled(&base_pred)),
        pooled_held(&base_held, &base_pred),
    )];
    let mut aug_pred = base_pred.clone();
    let mut aug_coef = to_coefficients(&design0, &base_fit, &base_sim_coef);
    let mut aug_per_run: Vec<Coefficients> = vec![aug_coef; nr];
    let mut aug_latency = 0.0;
    for (k, a) in accepted.iter().enumerate() {
        progress(&format!("predictions with {}", a.effect.id));
        if a.effect.id == "unexplained" {
            match &sim_dict {
                Some(sd) => {
                    let lat = sd.latency.map(|l| l.0).unwrap_or(latency);
                    let (p, h) = pred_stage(&design, &dict_fit, &sd.coef, lat);
                    stage_rms.push((Some(pooled(&p)), pooled_held(&h, &p)));
                }
                None => stage_rms.push((None, None)),
            }
            continue;
        }
        let refit = if Some(k) == final_stage {
            sim_final.as_ref()
        } else {
            None
        };
        let lat_k = refit
            .and_then(|s| s.latency)
            .map(|l| l.0)
            .unwrap_or(a.latency_after);
        if let Some((d, f)) = stage_fit(&a.terms_after, a.latency_after) {
            let coef = refit.map(|s| s.coef.clone()).unwrap_or(f.coef.clone());
            let (p, h) = pred_stage(&d, &f, &coef, lat_k);
            stage_rms.push((Some(pooled(&p)), pooled_held(&h, &p)));
            if k + 1 == accepted.len() || accepted[k + 1].effect.id == "unexplained" {
                aug_pred = p;
                aug_coef = to_coefficients(&d, &f, &coef);
                aug_per_run = (0..nr)
                    .map(|r| coefficients_for_run(&d, &f, &coef, &runs, r))
                    .collect();
                aug_latency = lat_k;
            }
        } else {
            stage_rms.push((None, None));
        }
    }

    // ---- findings
    let coef_map = |f: &LinFit, d: &Design| -> BTreeMap<String, (f64, f64)> {
        f.cols
            .iter()
            .enumerate()
            .map(|(k, &c)| {
                (
                    d.terms[c].name(),
                    (f.coef[k], f.cov[(k, k)].max(0.0).sqrt()),
                )
            })
            .collect()
    };
    let weak_map = coef_map(&current, &design);
    // the final model's parameters: from the refit by simulation when there is one
    let final_map: BTreeMap<String, (f64, f64)> = match &sim_final {
        Some(sf) => current
            .cols
            .iter()
            .enumerate()
            .map(|(k, &c)| (design.terms[c].name(), (sf.coef[k], sf.err[k])))
            .collect(),
        None => weak_map.clone(),
    };
    let dict_map: BTreeMap<String, (f64, f64)> = match &sim_dict {
        Some(sd) => dict_fit
            .cols
            .iter()
            .enumerate()
            .map(|(k, &c)| (design.terms[c].name(), (sd.coef[k], sd.err[k])))
            .collect(),
        None => coef_map(&dict_fit, &design),
    };
    let mut findings = Vec::new();
    let final_eta = final_map.get(&Term::Eta.name()).map(|v| v.0).unwrap_or(eta);
    let final_g = final_map
        .get(&Term::SinACosB.name())
        .map(|v| -v.0)
        .unwrap_or(g);
    // confirmation by the refit by simulation: an effect the weak form accepted stays a finding
    // only when the refit finds one of its coefficients ≥ 3σ from zero, with the physical sign
    // where the physics fixes it (drag, load-dependent friction, compliance are ≥ 0)
    let mut rejected = Vec::new();
    let confirm = |a_terms: &[Term], id: &str| -> Option<String> {
        sim_final.as_ref()?;
        if id == "sensor_latency" {
            let (tau, err) = sim_final.as_ref()?.latency?;
            return (tau.abs() < 3.0 * err).then(|| format!("τ = {tau:.2e} ± {err:.1e} s"));
        }
        let mut best_z: f64 = 0.0;
        for t in a_terms {
            let (v, e) = *final_map.get(&t.name())?;
            let z = v / e.max(1e-300);
            let physical = match t {
                Term::Quad | Term::Corot | Term::LoadFric | Term::Compliance => z,
                _ => z.abs(),
            };
            best_z = best_z.max(physical);
        }
        (best_z < 3.0).then(|| {
            format!("largest coefficient {best_z:.1} σ (with its physical sign) in the refit by simulation")
        })
    };
    for (k, a) in accepted.iter().enumerate() {
        if a.effect.id != "unexplained" {
            if let Some(why) = confirm(&a.effect.terms, a.effect.id) {
                rejected.push(json!({"effect": a.effect.id, "reason": why,
                                     "delta_bic_weak_form": a.dbic}));
                continue;
            }
        } else if sim_dict.is_some() {
            // dictionary terms: confirmed when one is ≥ 3σ from zero in the refit
            let z = a
                .dictionary_terms
                .iter()
                .filter_map(|t| dict_map.get(&t.name()))
                .map(|&(v, e)| (v / e.max(1e-300)).abs())
                .fold(0.0, f64::max);
            if z < 3.0 {
                rejected.push(json!({"effect": a.effect.id,
                    "terms": a.dictionary_terms.iter().map(|t| t.name()).collect::<Vec<_>>(),
                    "reason": format!("largest coefficient {z:.1} σ in the refit by simulation"),
                    "delta_bic_weak_form": a.dbic}));
                continue;
            }
        }
        let mut p = if a.effect.id == "sensor_latency" {
            let (tau, tau_err) = sim_final
                .as_ref()
                .and_then(|s| s.latency)
                .unwrap_or((a.latency, a.latency_err));
            [
                ("tau_s".to_string(), tau),
                ("tau_err_s".to_string(), tau_err),
            ]
            .into_iter()
            .collect()
        } else if a.effect.id == "unexplained" {
            a.dictionary_terms
                .iter()
                .filter_map(|t| {
                    dict_map
                        .get(&t.name())
                        .map(|v| [(t.name(), v.0), (format!("{}_err", t.name()), v.1)])
                })
                .flatten()
                .collect()
        } else {
            let final_zeta = final_map
                .get(&Term::Zeta.name())
                .map(|v| v.0)
                .unwrap_or(zeta);
            let mut p = effect_params(&a.effect, &final_map, (final_zeta, final_eta, final_g));
            if a.effect.id == "load_dependent_friction" {
                // the force shape is evaluated on the geometry refined from the final Δ; the
                // systematic: how Θ, Φ split that Δ within the tolerance
                let delta_final = final_map
                    .get(&Term::CosASinB.name())
                    .map(|v| v.0 / final_g)
                    .unwrap_or(delta);
                let geo_c = refine_geometry(&geo_nominal, delta_final);
                let cols: Vec<usize> = (0..model_terms.len()).collect();
                let dc = build(&runs, &geo_c, &model_terms, &opts.weak, latency);
                // the systematic is measured on weak-form fits, against the one at geo_c
                let mut k_ref = p.get("k").copied();
                if let Some(fc) = fit(&dc, &cols) {
                    let mc = coef_map(&fc, &dc);
                    let ec = mc.get(&Term::Eta.name()).map(|v| v.0).unwrap_or(final_eta);
                    let gc = mc
                        .get(&Term::SinACosB.name())
                        .map(|v| -v.0)
                        .unwrap_or(final_g);
                    let pc = effect_params(&a.effect, &mc, (final_zeta, ec, gc));
                    k_ref = pc.get("k").copied().or(k_ref);
                    if sim_final.is_none() {
                        p = pc;
                    }
                }
                let mut sys: f64 = 0.0;
                for sgn in [-1.0, 1.0] {
                    let th = geo_c.theta + sgn * tol_split;
                    if let Some(ph) = solve_phi(th, delta_final, geo_c.phi) {
                        let g2 = Geometry { theta: th, phi: ph };
                        let d2 = build(&runs, &g2, &model_terms, &opts.weak, latency);
                        if let Some(f2) = fit(&d2, &cols) {
                            let m2 = coef_map(&f2, &d2);
                            let e2 = m2.get(&Term::Eta.name()).map(|v| v.0).unwrap_or(final_eta);
                            if let Some(l2) = m2.get(&Term::LoadFric.name()) {
                                let k2 = l2.0 / e2;
                                if let Some(k) = k_ref {
                                    sys = sys.max((k2 - k).abs());
                                }
                            }
                        }
                    }
                }
                if let (Some(k), Some(ke)) = (p.get("k").copied(), p.get("k_err").copied()) {
                    p.insert("k_err".into(), (ke * ke + sys * sys).sqrt());
                    p.insert("k_sys_geometry".into(), sys);
                    if let Some(el) = p.get("eta_load").copied() {
                        p.insert(
                            "eta_load_err".into(),
                            (p["eta_load_err"].powi(2) + (sys * el / k.abs().max(1e-12)).powi(2))
                                .sqrt(),
                        );
                    }
                }
            }
            p
        };
        if p.is_empty() {
            p.insert("size".into(), f64::NAN);
        }
        let mut ev = BTreeMap::new();
        ev.insert("delta_bic".to_string(), json!(a.dbic));
        ev.insert("n_eff".to_string(), json!(current.n_eff));
        ev.insert("heldout_cv_chi2_before".to_string(), json!(a.cv_before));
        ev.insert("heldout_cv_chi2_after".to_string(), json!(a.cv_after));
        ev.insert("eq_rms_before_rad_s2".to_string(), json!(a.eq_rms_before));
        ev.insert("eq_rms_after_rad_s2".to_string(), json!(a.eq_rms_after));
        if a.effect.id != "unexplained" && a.effect.id != "sensor_latency" {
            ev.insert(
                "weak_form_params".to_string(),
                json!(effect_params(
                    &a.effect,
                    &weak_map,
                    (
                        weak_map
                            .get(&Term::Zeta.name())
                            .map(|v| v.0)
                            .unwrap_or(zeta),
                        weak_map.get(&Term::Eta.name()).map(|v| v.0).unwrap_or(eta),
                        weak_map
                            .get(&Term::SinACosB.name())
                            .map(|v| -v.0)
                            .unwrap_or(g),
                    )
                )),
            );
        }
        if let (Some(sf), true) = (&sim_final, a.effect.id != "unexplained") {
            ev.insert(
                "simulation_refit".to_string(),
                json!({"windows": sf.windows, "samples": sf.samples,
                       "rms_start_rad": sf.rms_start_rad, "rms_rad": sf.rms_rad,
                       "converged": sf.converged, "inflation": sf.inflation}),
            );
        }
        if a.effect.id == "parameter_drift" {
            // the drifting parameter run by run (the others held at the fitted values, no drift
            // term): a clock-free view of the drift
            if let Some(Term::Drift(dp, _)) = a.effect.terms.first().copied() {
                ev.insert(
                    "per_run".to_string(),
                    json!(per_run_parameter(&design, &current, dp, &files)),
                );
            }
        }
        if a.effect.id == "unexplained" {
            ev.insert(
                "terms".to_string(),
                json!(a
                    .dictionary_terms
                    .iter()
                    .map(|t| t.name())
                    .collect::<Vec<_>>()),
            );
        }
        findings.push(Finding {
            effect: a.effect.id.to_string(),
            class: a.effect.class.to_string(),
            explanation: a.effect.explanation.to_string(),
            params: p,
            candidates: a.effect.candidates.iter().map(|s| s.to_string()).collect(),
            discriminating_experiment: a.effect.discriminating_experiment.to_string(),
            rms_before_rad: stage_rms[k].0.or(stage_rms[0].0),
            rms_after_rad: stage_rms[k + 1].0,
            heldout_rms_before_rad: stage_rms[k].1.or(stage_rms[0].1),
            heldout_rms_after_rad: stage_rms[k + 1].1,
            evidence: ev,
            size: None,
        });
    }
    // ---- static friction (breakaway above the sliding friction): no regression term (the weak
    // form skips stick phases); profiled over the stick phases by simulation with the final model,
    // and ordered with the other findings by its ΔBIC-like evidence
    if !opts.base_only {
        use super::release::{fit_static_friction, ReleaseOptions};
        progress("static friction (stick phases)");
        let sf = fit_static_friction(
            &runs,
            &aug_coef,
            Some(&aug_per_run),
            &geo,
            aug_latency,
            &ReleaseOptions::default(),
        );
        if let Some(sf) = sf.filter(|f| f.s_err.is_finite() && f.s_err > 0.0) {
            // evidence in χ² units with the systematic included: z² against one parameter
            let z = sf.s / sf.s_err;
            let dbic = -(z * z).min(sf.delta_chi2) + (sf.samples as f64).ln();
            let fired = z >= 3.0 && dbic < -opts.bic_threshold;
            let mut ev = BTreeMap::new();
            ev.insert("delta_bic".to_string(), json!(dbic));
            ev.insert("z".to_string(), json!(z));
            ev.insert("delta_chi2_profile".to_string(), json!(sf.delta_chi2));
            ev.insert("windows".to_string(), json!(sf.windows));
            ev.insert("windows_examined".to_string(), json!(sf.windows_examined));
            ev.insert("samples".to_string(), json!(sf.samples));
            ev.insert("chi2_per_dof".to_string(), json!(sf.chi2_per_dof));
            ev.insert(
                "s_interval_stat".to_string(),
                json!([sf.s_interval.0, sf.s_interval.1]),
            );
            ev.insert("profile".to_string(), json!(sf.profile));
            if fired {
                mismatch.push(Mismatch {
                    where_: "stick phases: the output stays at rest beyond the sliding friction \
                             (release later, with an acceleration jump)"
                        .into(),
                    evidence: ev.clone(),
                });
                let mut p = BTreeMap::new();
                let eta_s = sf.eta * (1.0 + sf.s);
                p.insert("eta_sliding".to_string(), sf.eta);
                p.insert("eta_static".to_string(), eta_s);
                p.insert("eta_static_err".to_string(), sf.eta * sf.s_err);
                p.insert("excess_relative".to_string(), sf.s);
                p.insert("excess_relative_err".to_string(), sf.s_err);
                p.insert("excess_relative_err_stat".to_string(), sf.s_stat);
                p.insert("excess_relative_err_sys".to_string(), sf.s_sys);
                p.insert("events".to_string(), sf.sticks as f64);
                progress("predictions with static_friction");
                let before = pooled(&aug_pred);
                let c_sf = Coefficients {
                    eta_static_excess: sf.s * sf.eta,
                    ..aug_coef
                };
                let p_sf: Vec<Prediction> = (0..nr)
                    .map(|r| {
                        let c_r = Coefficients {
                            eta_static_excess: sf.s * sf.eta,
                            ..aug_per_run[r]
                        };
                        predict(&runs[r], &c_r, &geo, aug_latency)
                    })
                    .collect();
                let after = pooled(&p_sf);
                aug_coef = c_sf;
                aug_pred = p_sf;
                let e = catalog()
                    .into_iter()
                    .find(|e| e.id == "static_friction")
                    .expect("catalogued");
                let f = Finding {
                    effect: e.id.to_string(),
                    class: e.class.to_string(),
                    explanation: e.explanation.to_string(),
                    params: p,
                    candidates: e.candidates.iter().map(|s| s.to_string()).collect(),
                    discriminating_experiment: e.discriminating_experiment.to_string(),
                    rms_before_rad: Some(before),
                    rms_after_rad: Some(after),
                    heldout_rms_before_rad: None,
                    heldout_rms_after_rad: None,
                    evidence: ev,
                    size: None,
                };
                let support = |f: &Finding| {
                    f.evidence
                        .get("delta_bic")
                        .and_then(|v| v.as_f64())
                        .unwrap_or(0.0)
                };
                let at = findings
                    .iter()
                    .position(|g| support(g) > dbic)
                    .unwrap_or(findings.len());
                findings.insert(at, f);
            }
        }
    }
    let verdict = findings
        .first()
        .map(|f| f.effect.clone())
        .unwrap_or_else(|| "none".into());
    params.insert("eq_chi2_per_dof".to_string(), base_fit.chi2_dof);
    params.insert("n_rows".to_string(), base_fit.n as f64);
    params.insert("n_eff".to_string(), base_fit.n_eff);
    let baseline = Baseline {
        params,
        rms_rad: stage_rms[0].0.unwrap_or(f64::NAN),
        runs: (0..nr)
            .map(|r| RunRms {
                file: files[r].clone(),
                rms_rad: base_pred[r].rms,
                heldout_rms_rad: base_held[r],
                chi2_per_row: Some(chi_run[r]).filter(|v| v.is_finite()),
            })
            .collect(),
    };
    let fits = json!({
        "ringdowns": ringdowns,
        "kappa_alpha0": kappa,
        "noise_rad": runs.iter().map(|r| r.sigma_beta).collect::<Vec<_>>(),
        "outliers_rejected": runs.iter().map(|r| r.outliers).collect::<Vec<_>>(),
        "augmented_coefficients": final_map.iter().map(|(k, v)| (k.clone(), json!([v.0, v.1]))).collect::<BTreeMap<_, _>>(),
        "latency_s": [latency, latency_err],
        "findings_not_confirmed": rejected,
        "outlier_handling": "rejection: leave-one-out local cubic prediction, 6 robust σ; Huber weights (2.5 σ) in the regression",
    });
    // fingerprints for figures
    let final_resid = &current.resid;
    let fingerprint = (0..design0.rows().min(base_fit.resid.len()))
        .map(|i| {
            let c = design0.centre[i];
            (
                c.0,
                c.1,
                c.2,
                base_fit.resid[i],
                final_resid.get(i).copied().unwrap_or(f64::NAN),
            )
        })
        .collect();
    Ok(Diagnosis {
        report: Report {
            schema: SCHEMA.into(),
            baseline,
            mismatch,
            findings,
            verdict,
            fits: Some(fits),
        },
        runs,
        files,
        base: base_coef,
        augmented: aug_coef,
        latency,
        ringdowns,
        kappa,
        base_pred,
        aug_pred,
        fingerprint,
    })
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

/// The base parameter `p` fitted run by run on the weak-form rows with every other column of
/// `f` held at its fitted value and the drift columns dropped: one weighted 1-D regression per
/// run, its σ inflated by n/n_eff. Returns {file, value, err} per run with rows.
fn per_run_parameter(
    d: &Design,
    f: &LinFit,
    p: DriftParam,
    files: &[String],
) -> Vec<serde_json::Value> {
    let target = match p {
        DriftParam::Zeta => Term::Zeta,
        DriftParam::Eta => Term::Eta,
        DriftParam::Coupling => Term::SinACosB,
    };
    let Some(kt) = f.cols.iter().position(|&c| d.terms[c] == target) else {
        return vec![];
    };
    let delta = match (
        f.cols.iter().position(|&c| d.terms[c] == Term::CosASinB),
        f.coef.get(kt),
    ) {
        (Some(kc), Some(&v)) if v != 0.0 => -f.coef[kc] / v,
        _ => 0.0,
    };
    let cs_col = d.col(Term::CosASinB);
    let infl = f.n as f64 / f.n_eff.max(1.0);
    let mut out = Vec::new();
    for (r, file) in files.iter().enumerate() {
        let (mut sxx, mut sxy, mut n) = (0.0, 0.0, 0usize);
        for i in (0..d.rows()).filter(|&i| d.run[i] == r) {
            // column of the parameter: for g the whole base coupling −sin α cos β + Δ cos α sin β
            let x = match p {
                DriftParam::Coupling => {
                    -d.at(i, f.cols[kt]) + delta * cs_col.map(|c| d.at(i, c)).unwrap_or(0.0)
                }
                _ => d.at(i, f.cols[kt]),
            };
            let mut y = d.y[i];
            for (k, &c) in f.cols.iter().enumerate() {
                let skip = matches!(d.terms[c], Term::Drift(..))
                    || k == kt
                    || (p == DriftParam::Coupling && Some(c) == cs_col);
                if !skip {
                    y -= f.coef[k] * d.at(i, c);
                }
            }
            let w = f.w[i];
            sxx += w * x * x;
            sxy += w * x * y;
            n += 1;
        }
        if n > 2 && sxx > 0.0 {
            out.push(json!({"file": file, "value": sxy / sxx,
                            "err": (infl / sxx).sqrt()}));
        }
    }
    out
}

/// Profiles the BIC over a sensor latency τ (driven rows shift α by −α̇τ). Returns
/// (τ, 1σ from the profile, ΔBIC including the extra parameter, design at τ, fit at τ).
fn profile_latency(
    runs: &[CleanRun],
    geo: &Geometry,
    model_terms: &[Term],
    opts: &DiagnoseOptions,
    cur: &LinFit,
) -> Option<(f64, f64, f64, Design, LinFit)> {
    let span = opts.latency_span;
    let n = 24;
    let ne = cur.n_eff.max(2.0);
    let cols: Vec<usize> = (0..model_terms.len()).collect();
    let mut prof = Vec::new();
    for k in 0..=n {
        let tau = -span + 2.0 * span * k as f64 / n as f64;
        let d = build(runs, geo, model_terms, &opts.weak, tau);
        let f = fit(&d, &cols)?;
        prof.push((tau, ne * f.chi2.ln()));
    }
    let (kbest, _) = prof
        .iter()
        .enumerate()
        .min_by(|a, b| a.1 .1.total_cmp(&b.1 .1))?;
    if kbest == 0 || kbest == n {
        return None; // no interior minimum: not a latency
    }
    // parabola through the three points around the minimum; −2 ln L ≈ n_eff ln χ², so the 1σ
    // interval is where the profile rises by 1
    let (t0, y0) = prof[kbest - 1];
    let (t1, y1) = prof[kbest];
    let (_, y2) = prof[kbest + 1];
    let h = t1 - t0;
    let curv = (y0 - 2.0 * y1 + y2) / (h * h);
    let tau = if curv > 0.0 {
        t1 - 0.5 * h * (y2 - y0) / (y2 - 2.0 * y1 + y0)
    } else {
        t1
    };
    let tau_err = if curv > 0.0 {
        (2.0 / curv).sqrt()
    } else {
        f64::NAN
    };
    let d = build(runs, geo, model_terms, &opts.weak, tau);
    let f = fit(&d, &cols)?;
    let dbic = ne * (f.chi2 / cur.chi2).ln() + ne.ln();
    Some((tau, tau_err, dbic, d, f))
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
        let e =
            (crate::model::gear::shaft_index(nominal.theta + s, nominal.phi + s) - delta_fit).abs();
        if e < best.0 {
            best = (e, s);
        }
    }
    if best.0 < 1e-3 {
        Geometry {
            theta: nominal.theta + best.1,
            phi: nominal.phi + best.1,
        }
    } else {
        *nominal
    }
}

/// Φ such that Δ(Θ, Φ) = Δ, the solution closest to `guess`.
fn solve_phi(theta: f64, delta: f64, guess: f64) -> Option<f64> {
    let rr = (theta.cos().powi(2) + 4.0 * theta.sin().powi(2)).sqrt();
    let psi = (2.0 * theta.sin()).atan2(theta.cos());
    let c = delta / rr;
    if c.abs() > 1.0 {
        return None;
    }
    let a = c.acos();
    let cands = [a - psi, -a - psi];
    let wrap = |x: f64| {
        (x - guess + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI
            + guess
    };
    cands
        .iter()
        .map(|&x| wrap(x))
        .min_by(|x, y| (x - guess).abs().total_cmp(&(y - guess).abs()))
}

/// A term generalises when it lowers the held-out error of at least half of the runs that have
/// rows (whole runs left out): an improvement carried by one or two runs is not accepted.
fn generalises(new: &[f64], old: &[f64]) -> bool {
    let mut better = 0;
    let mut total = 0;
    for (a, b) in new.iter().zip(old) {
        if *b > 0.0 {
            total += 1;
            if a < b {
                better += 1;
            }
        }
    }
    total > 0 && 2 * better >= total
}
