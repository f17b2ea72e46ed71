//! The nonparametric model of what remains: a smooth curve in the output angle β, fitted by
//! simulation and judged on held-out runs like every catalog candidate.
//!
//! Where the catalog's forms do not contain the missing physics, a family of the catalog may
//! still improve the prediction (a Stribeck excess stands in for a friction bump at one angle).
//! The curve asks the question without a form: the base model with a periodic cubic B-spline in β
//! ([`crate::model::recorded::spline`], [`SPLINE_KNOTS`] coefficients) of one kind,
//!
//! - **friction**: the dry friction as a function of the angle, −sgn β̇ η(β) with
//!   η(β) = Σ c_j B_j(β) in place of the constant η;
//! - **torque**: a lab-fixed torque τ(β) = Σ c_j B_j(β) added to the base model,
//!
//! is refitted by multiple shooting ([`super::shooting`]) with the roughness penalty
//! λ Σ_j (c_{j−1} − 2c_j + c_{j+1})² ([`super::shooting::SimModel::penalty_rows`]) and predicts the
//! judging windows held out by fold ([`super::judge::heldout`]).
//!
//! - **Which kind.** A pilot of each kind, refitted without penalty from the weak form's start;
//!   the kind whose pilot fits the judging windows better in sample (the paired gain against the
//!   final model's in-sample χ²) goes on. No held-out prediction is used for the choice.
//! - **λ by the held-out judge.** λ runs over [`RELATIVE_LAMBDAS`] times the mean information
//!   I = mean_j Σ_i J_ij² of a curve coefficient in the pilot (so the grid is in the data's own
//!   units); at every λ the curve is refitted (warm-started from the last) and its held-out
//!   comparison against the final model ([`super::judge::compare`]) computed; the largest
//!   held-out gain Σ d_w is kept.
//! - **Does the curve beat the findings?** The kept curve stands when it predicts the held-out
//!   windows significantly better than the final model (the base model with every accepted
//!   finding): [`Comparison::improves`] at the judge's family-wise threshold
//!   [`z_threshold`]`(m)`, m the number of (kind, λ) pairs (both kinds count: one was chosen).
//!   Then the catalog's forms are wrong for this set and the curve characterises what is missing
//!   (the verdict, [`super::verdict`]); where it does not, the findings stand as they are.
//! - **Band.** The kept refit linearised at its solution, its λ chosen by generalised
//!   cross-validation within the span of [`RELATIVE_LAMBDAS`] ([`super::smoothing`]: the held-out
//!   grid is a factor 100 apart, and at a λ above GCV's a narrow bump comes out flattened with
//!   raised flanks, several σ outside a band that holds only the noise); the curve on a grid of
//!   [`GRID_POINTS`] angles with σ(β) = √(b(β)ᵀ C b(β)), b the basis functions at β and C the
//!   coefficients' block of the Bayesian covariance s²(JᵀJ + λDᵀD)⁻¹ floored by the
//!   window-clustered sandwich; the report's band is ± [`BAND_SIGMAS`] σ, which holds the true
//!   curve on about 95 % of the angles on average (Nychka 1988).
//!
//! The stage runs when the selection accepted an effect or the remainder is above the noise
//! floor ([`super::report::Remainder::within_noise`]): where the base model explains the
//! recordings there is nothing for a curve to stand in for.

use super::judge::{compare, heldout, z_threshold, Comparison, HeldOut};
use super::regression::{build, Term, WeakOptions, BASE_TERMS};
use super::select::{ModelState, SelectCtx};
use super::shooting::{curve_columns, par_map, refit, Reselect, ShootingOptions, SimFit, SimModel};
use super::smoothing::{add_penalty, gcv_refine, Linearised, Smoothed};
use crate::model::recorded::spline::{basis, SplineKind, SPLINE_KNOTS};
use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

/// The grid of the roughness weight λ in units of a curve coefficient's mean information I in
/// the pilot refit: from nearly unpenalised to smooth on the scale of a few knots.
pub const RELATIVE_LAMBDAS: [f64; 3] = [1.0, 1e-2, 1e-4];

/// Points of the reported curve on the period (every 2°).
pub const GRID_POINTS: usize = 180;

/// Half-width of the reported band in σ (a two-sided 95 % band).
pub const BAND_SIGMAS: f64 = 2.0;

/// Levenberg–Marquardt patience of the curve's refits (the judge's, [`ShootingOptions`]'s
/// default): each λ is warm-started from the last, the first from the pilot's refit.
const CURVE_PATIENCE: usize = 1;

/// One (kind, λ) tried (report key `curve.tried`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CurveTrial {
    /// `friction` or `torque`.
    pub kind: String,
    /// λ, (χ² units) per (s⁻²)².
    pub lambda: f64,
    /// λ / I.
    pub lambda_relative: f64,
    /// Held-out χ² gain Σ d_w against the final model (positive: the curve predicts better).
    pub heldout_gain: f64,
    /// The judge's z of it (log scores).
    pub z: f64,
}

/// The curve kept, with its band and its held-out comparison (report key `curve`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Curve {
    /// `friction` (η(β), the dry friction as a function of the output angle) or `torque` (τ(β),
    /// a lab-fixed torque).
    pub kind: String,
    /// The variable: `beta`, the output angle.
    pub variable: String,
    /// Unit of the values: s⁻² (per output inertia).
    pub unit: String,
    /// Basis functions on the period.
    pub knots: usize,
    /// λ kept by the held-out judge, per (s⁻²)².
    pub lambda: f64,
    /// λ / I.
    pub lambda_relative: f64,
    /// The grid, degrees of β.
    pub grid_deg: Vec<f64>,
    /// The curve on the grid, s⁻².
    pub value: Vec<f64>,
    /// Its 1σ on the grid, s⁻².
    pub sigma: Vec<f64>,
    /// Half-width of the band in σ.
    pub band_sigmas: f64,
    /// λ of the reported curve and band, per (s⁻²)²: generalised cross-validation on the kept
    /// refit linearised at its solution ([`super::smoothing`]; `lambda` where it finds none).
    #[serde(default)]
    pub band_lambda: f64,
    /// band_lambda / I.
    #[serde(default)]
    pub band_lambda_relative: f64,
    /// The band's effective number of parameters tr H (`None`: the refit's own covariance).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub band_edf: Option<f64>,
    /// Held-out χ² gain Σ d_w of the curve against the final model.
    pub heldout_gain: f64,
    /// 1σ of the gain (Σ d_w / z of the raw gains).
    pub heldout_gain_sigma: f64,
    /// The judge's z (log scores).
    pub z: f64,
    /// The threshold: [`z_threshold`] of the pairs tried.
    pub z_crit: f64,
    /// Windows compared.
    pub windows: usize,
    /// Whether the curve predicts significantly better than the final model.
    pub stands: bool,
    /// The effects of the final model it was compared with (empty: the base model).
    pub against: Vec<String>,
    /// Every (kind, λ) tried.
    pub tried: Vec<CurveTrial>,
}

impl Curve {
    /// The curve's value and σ at β (rad), linear between the grid points.
    pub fn at(&self, beta: f64) -> (f64, f64) {
        let n = self.grid_deg.len();
        let u = beta.to_degrees().rem_euclid(360.0) / 360.0 * n as f64;
        let i = (u.floor() as usize).min(n - 1);
        let f = u - i as f64;
        let j = (i + 1) % n;
        (
            self.value[i] * (1.0 - f) + self.value[j] * f,
            self.sigma[i] * (1.0 - f) + self.sigma[j] * f,
        )
    }
    /// The fraction of the grid where the band ± [`BAND_SIGMAS`] σ holds `truth(β)` (β in rad).
    pub fn coverage(&self, truth: impl Fn(f64) -> f64) -> f64 {
        let inside = self
            .grid_deg
            .iter()
            .zip(self.value.iter().zip(&self.sigma))
            .filter(|(x, (v, s))| (truth(x.to_radians()) - *v).abs() <= self.band_sigmas * *s)
            .count();
        inside as f64 / self.grid_deg.len().max(1) as f64
    }
}

impl Curve {
    /// The largest |curve − truth(β)|/σ on the grid and the β (degrees) where it is.
    pub fn worst(&self, truth: impl Fn(f64) -> f64) -> [f64; 2] {
        self.grid_deg
            .iter()
            .zip(self.value.iter().zip(&self.sigma))
            .map(|(x, (v, s))| [((truth(x.to_radians()) - v) / s).abs(), *x])
            .fold([0.0, 0.0], |m, d| if d[0] > m[0] { d } else { m })
    }
}

/// The terms of the base model with a curve of `kind`: the friction curve takes η's place.
pub fn curve_terms(kind: SplineKind) -> Vec<Term> {
    let mut t: Vec<Term> = BASE_TERMS
        .iter()
        .copied()
        .filter(|&x| !(kind == SplineKind::Friction && x == Term::Eta))
        .collect();
    t.extend((0..SPLINE_KNOTS).map(|j| Term::Spline(kind, j as u8)));
    t
}

/// A refitted curve model with its held-out comparison against the final model.
struct Judged {
    kind: SplineKind,
    model_terms: Vec<Term>,
    fit: SimFit,
    cmp: Comparison,
    lambda: f64,
    relative: f64,
}

/// The stage (see the module): a pilot of each kind, the kind whose pilot fits the judging
/// windows better refitted at every λ and judged against the final model `fin` (its held-out
/// errors `fin_held`), the best curve with its band; `None` when no curve model could be
/// refitted. `base_theta` is the base model's refit (ζ, η, −g, gΔ), the start of the curve
/// model's base coefficients; `weak` the weak form's options (the curve's start).
pub fn fit_curve(
    ctx: &SelectCtx,
    weak: &WeakOptions,
    (fin, fin_held): (&ModelState, &HeldOut),
    base_theta: &[f64],
) -> Option<Curve> {
    // the kinds' pilots are independent refits: side by side (each result as computed alone)
    let pilots: Vec<Pilot> = par_map(SplineKind::ALL.len(), |k| {
        pilot(ctx, weak, fin, base_theta, SplineKind::ALL[k])
    })
    .into_iter()
    .flatten()
    .collect();
    // the kind is chosen in sample, before any held-out prediction: the comparison that decides
    // counts every (kind, λ) pair of the grid as tried
    let chosen = pilots
        .into_iter()
        .map(|p| {
            let chi2 = p.fit.window_chi2(&p.model, ctx.wins).0;
            let gain = compare(
                &in_sample(&fin_held.chi2_fit),
                &in_sample(&chi2),
                ctx.wins,
                ctx.runs,
            )
            .gain;
            (p, gain)
        })
        .max_by(|a, b| a.1.total_cmp(&b.1))?
        .0;
    let judged = judge_grid(ctx, fin_held, chosen);
    let m = SplineKind::ALL.len() * RELATIVE_LAMBDAS.len();
    let best = judged
        .iter()
        .max_by(|a, b| a.cmp.gain.total_cmp(&b.cmp.gain))?;
    let z_crit = z_threshold(m);
    let smooth = smoothed(ctx, best);
    let (value, sigma, grid) = band(best, smooth.as_ref());
    let band_lambda = smooth.as_ref().map_or(best.lambda, |s| s.lambda);
    Some(Curve {
        kind: best.kind.name().into(),
        variable: "beta".into(),
        unit: "s^-2".into(),
        knots: SPLINE_KNOTS,
        lambda: best.lambda,
        lambda_relative: best.relative,
        grid_deg: grid,
        value,
        sigma,
        band_sigmas: BAND_SIGMAS,
        band_lambda,
        band_lambda_relative: band_lambda / best.lambda * best.relative,
        band_edf: smooth.as_ref().map(|s| s.edf),
        heldout_gain: best.cmp.gain,
        heldout_gain_sigma: if best.cmp.z_chi2 != 0.0 {
            (best.cmp.gain / best.cmp.z_chi2).abs()
        } else {
            f64::INFINITY
        },
        z: best.cmp.z,
        z_crit,
        windows: best.cmp.windows,
        stands: best.cmp.improves(z_crit),
        against: fin.effects.iter().map(|e| e.id.to_string()).collect(),
        tried: judged
            .iter()
            .map(|j| CurveTrial {
                kind: j.kind.name().into(),
                lambda: j.lambda,
                lambda_relative: j.relative,
                heldout_gain: j.cmp.gain,
                z: j.cmp.z,
            })
            .collect(),
    })
}

/// In-sample window χ² as the held-out errors [`compare`] reads.
fn in_sample(chi2: &[Option<f64>]) -> HeldOut {
    HeldOut {
        chi2: chi2.to_vec(),
        chi2_fit: Vec::new(),
    }
}

/// A curve model's pilot refit without penalty, and the information I of a coefficient in it.
struct Pilot<'a> {
    kind: SplineKind,
    model: SimModel<'a>,
    fit: SimFit,
    info: f64,
}

/// The pilot of `kind`: the curve model (the final model's latency when it fits one) refitted
/// from the weak form's start by one Levenberg–Marquardt round without penalty.
fn pilot<'a>(
    ctx: &SelectCtx<'a>,
    weak: &WeakOptions,
    fin: &ModelState,
    base_theta: &[f64],
    kind: SplineKind,
) -> Option<Pilot<'a>> {
    let terms = curve_terms(kind);
    let mut model = SimModel::of_terms(ctx.runs, *ctx.geo, terms.clone(), ctx.tol);
    model.fit_latency = fin.fit_latency;
    model.latency = fin.latency();
    let mut theta = start(ctx, weak, &terms, base_theta, model.latency)?;
    if model.fit_latency {
        theta.push(model.latency);
    }
    let fit = refit(&model, &theta, ctx.wins, &curve_options(ctx))?;
    let info = information(&fit, &curve_columns(&terms));
    (info.is_finite() && info > 0.0).then_some(Pilot {
        kind,
        model,
        fit,
        info,
    })
}

/// The refit options of the curve's fits: one Levenberg–Marquardt round from a warm start (the
/// judge's patience), the windows the start follows.
fn curve_options(ctx: &SelectCtx) -> ShootingOptions {
    ShootingOptions {
        patience: CURVE_PATIENCE,
        reselect: Reselect::Never,
        ..*ctx.shooting
    }
}

/// The curve of the pilot's kind refitted at every λ of the grid (smoothest first, each
/// warm-started from the last) and judged against the final model.
fn judge_grid(ctx: &SelectCtx, fin_held: &HeldOut, p: Pilot) -> Vec<Judged> {
    let Pilot {
        kind,
        mut model,
        fit,
        info,
    } = p;
    let mut theta = fit.theta;
    let mut out = Vec::new();
    for rel in RELATIVE_LAMBDAS {
        model.roughness = rel * info;
        let Some(fit) = refit(&model, &theta, ctx.wins, &curve_options(ctx)) else {
            continue;
        };
        theta = fit.theta.clone();
        let held = heldout(&model, &fit, (ctx.wins, ctx.folds), ctx.shooting);
        let cmp = compare(fin_held, &held, ctx.wins, ctx.runs);
        out.push(Judged {
            kind,
            model_terms: model.terms.clone(),
            fit,
            cmp,
            lambda: model.roughness,
            relative: rel,
        });
    }
    out
}

/// Mean over the curve's coefficients of the Jacobian columns' squared norms (the window rows):
/// the information I of a coefficient, the unit of λ.
fn information(fit: &SimFit, cols: &[Vec<usize>]) -> f64 {
    let windows_end = fit.resid.len().min(fit.jac.nrows());
    let all: Vec<usize> = cols.iter().flatten().copied().collect();
    let sum: f64 = all
        .iter()
        .map(|&k| fit.jac.view((0, k), (windows_end, 1)).norm_squared())
        .sum();
    sum / all.len().max(1) as f64
}

/// The start of the curve model: the weak form's weighted least squares of `terms` with a small
/// roughness penalty on the curve (10⁻² of its mean information, for a start that stays smooth
/// where few rows see the angle), the base coefficients then replaced by the base refit's
/// `base_theta` (the weak form's quadrature bias removed where the refit has it).
fn start(
    ctx: &SelectCtx,
    weak: &WeakOptions,
    terms: &[Term],
    base_theta: &[f64],
    latency: f64,
) -> Option<Vec<f64>> {
    let d = build(ctx.runs, ctx.geo, terms, weak, latency);
    let p = terms.len();
    if d.rows() <= p {
        return None;
    }
    let mut a = DMatrix::<f64>::zeros(p, p);
    let mut b = DVector::<f64>::zeros(p);
    for i in 0..d.rows() {
        let w = 1.0 / d.sigma[i].max(1e-300).powi(2);
        for r in 0..p {
            let xr = d.at(i, r) * w;
            b[r] += xr * d.y[i];
            for c in 0..p {
                a[(r, c)] += xr * d.at(i, c);
            }
        }
    }
    for cols in curve_columns(terms) {
        let info = cols.iter().map(|&k| a[(k, k)]).sum::<f64>() / cols.len() as f64;
        add_penalty(&mut a, &cols, 1e-2 * info);
    }
    let mut theta: Vec<f64> = a.cholesky()?.solve(&b).iter().copied().collect();
    for (k, t) in terms.iter().enumerate() {
        if let Some(i) = BASE_TERMS.iter().position(|x| x == t) {
            if let Some(&v) = base_theta.get(i) {
                theta[k] = v;
            }
        }
    }
    theta.iter().all(|v| v.is_finite()).then_some(theta)
}

/// The curve of `j` on the grid with its σ (see the module) and the grid in degrees: the
/// coefficients and covariance at the λ of [`smoothed`], or the refit's own where that finds none.
fn band(j: &Judged, smooth: Option<&Smoothed>) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let cols = curve_columns(&j.model_terms)
        .into_iter()
        .next()
        .unwrap_or_default();
    let (theta, cov) = smooth.map_or((&j.fit.theta, &j.fit.cov), |s| (&s.theta, &s.cov));
    let grid: Vec<f64> = (0..GRID_POINTS)
        .map(|k| 360.0 * k as f64 / GRID_POINTS as f64)
        .collect();
    let (mut value, mut sigma) = (Vec::new(), Vec::new());
    for x in &grid {
        let (idx, val, _) = basis(x.to_radians());
        let mut v = 0.0;
        let mut var = 0.0;
        for a in 0..4 {
            let ka = cols[idx[a]];
            v += theta[ka] * val[a];
            for b in 0..4 {
                var += val[a] * val[b] * cov[(ka, cols[idx[b]])];
            }
        }
        value.push(v);
        sigma.push(var.max(0.0).sqrt());
    }
    (value, sigma, grid)
}

/// The kept refit linearised at its solution and its λ chosen by generalised cross-validation
/// within the span of [`RELATIVE_LAMBDAS`] ([`gcv_refine`]): the band's λ and Bayesian covariance.
fn smoothed(ctx: &SelectCtx, j: &Judged) -> Option<Smoothed> {
    let info = j.lambda / j.relative;
    let cols = curve_columns(&j.model_terms).into_iter().next()?;
    let clusters: Vec<(usize, usize)> = j
        .fit
        .used
        .iter()
        .map(|&(wi, row0)| (row0, ctx.wins[wi].keep.len()))
        .collect();
    let rows = clusters.iter().map(|c| c.0 + c.1).max()?;
    let jac = j.fit.jac.rows(0, rows).into_owned();
    let lin = Linearised {
        jac: &jac,
        resid: &j.fit.resid[..rows],
        theta: &j.fit.theta,
        cols: &cols,
        clusters: &clusters,
        dof: j.fit.samples as f64 - 2.0 * clusters.len() as f64,
    };
    let (lo, hi) = RELATIVE_LAMBDAS
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), &r| (a.min(r), b.max(r)));
    gcv_refine(&lin, lo * info, hi * info)
}
