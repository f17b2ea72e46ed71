//! Refit by simulation: multiple shooting over short windows.
//!
//! The weak-form regression ([`super::regression`]) proposes terms and gives starting values, but
//! its quadrature on coarsely sampled runs carries a systematic error of its own (a few tenths of
//! a percent on g, more on terms with higher harmonics). The refit removes it: runs are cut into
//! the short prediction windows of [`super::predict`] (≤ 30 samples, ≤ 0.4 s: short enough for
//! chaos not to matter) and the model is simulated with the exact Filippov integrator over each
//! window. The window initial states (β, β̇) are nuisance parameters, profiled out (variable
//! projection: for every trial parameter vector θ each window's state is refitted, warm-started
//! from the optimiser's current point, to a Gauss–Newton decrement below 10⁻⁸); θ is fitted to the
//! residuals (β_sim − β_meas)/σ_camera by Levenberg–Marquardt with the variable-projection
//! Jacobian of the profiled residuals ([`varpro_jacobian`]: central differences with the states
//! held, the state directions projected out). The covariance of θ is the
//! window-clustered sandwich built on that Jacobian, never below the white-noise s²(JᵀJ)⁻¹
//! ([`window_covariance`]): the windows are the independent units, and the scatter of their
//! scores carries the correlation of a window's residuals and a misfit of the model, which
//! s²(JᵀJ)⁻¹ assumes away.
//!
//! θ is the coefficient vector of a [`SimModel`]'s terms (mapped by [`super::spec`]) and optionally
//! the sensor latency. The Jacobian at the solution is kept: the judge uses it for the one-step
//! leave-fold-out refits ([`SimFit::step_without`]).

use super::lm::{
    cluster_sandwich, covariance_floor, least_squares_with_jacobian, scaled_cov, LsqFit,
};
use super::model::{AugmentedGear, Coefficients, Geometry, Shape};
use super::predict::{
    fit_window_state, prediction_windows, window_residuals, window_residuals_jacobian,
    window_system, RecordedInput,
};
use super::preprocess::CleanRun;
use super::regression::{session_positions, SessionPosition, Term};
use super::spec::{coefficients_for_run, simulable};
use crate::model::recorded::spline::{second_differences, SplineKind};
use crate::numerics::least_squares::{lstsq_determined, DEFAULT_RCOND};
use faer::Mat;
use nalgebra::{DMatrix, DVector};
use std::collections::HashMap;
use std::sync::{Mutex, OnceLock};

/// Options of the refit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShootingOptions {
    /// Most windows used (spread over the runs; fewer windows, faster and noisier).
    pub max_windows: usize,
    /// Outer Levenberg–Marquardt patience (evaluations ≈ patience × (parameters + 1)).
    pub patience: usize,
    /// Whether the windows left out at the start are tried again at the solution ([`refit`]).
    pub reselect: Reselect,
}

/// When a refit tries the windows its start could not follow again at its solution and refits
/// with those the fitted model follows ([`refit`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Reselect {
    /// Never: the windows the start follows are the fit's.
    Never,
    /// Up to [`MAX_RESELECT`] times: the reported fits and the profiles of shape parameters.
    Always,
    /// Once, when the fit from the start used fewer than this fraction of the windows: the
    /// judge's refits of the candidates ([`super::select::evaluate`], 0.5), enough to bring back
    /// the windows a large missed effect made unfollowable from the start, at a fraction of the
    /// cost of `Always`.
    OnceBelow(f64),
}

/// The patience of a refit that must be converged, not only improved: the current model every
/// candidate is judged against ([`super::select`]) and the reported fits. With the judge's
/// patience of 1 (one Levenberg–Marquardt step from a warm start) the current model stops short
/// of its optimum, and a candidate refitted from a different start is then credited with the
/// gain of the current model's own unfinished fit (a corotating drag of 1σ judged at z = 3.7 on
/// a set whose shaft angles alone were off).
pub const CONVERGED_PATIENCE: usize = 4;

impl Default for ShootingOptions {
    fn default() -> Self {
        Self {
            max_windows: 240,
            patience: 1,
            reselect: Reselect::Never,
        }
    }
}

/// A prediction window: samples [lo, hi) of run `run`, frames marked in `keep` used.
#[derive(Debug, Clone, PartialEq)]
pub struct Win {
    /// Run index.
    pub run: usize,
    /// First sample.
    pub lo: usize,
    /// One past the last sample.
    pub hi: usize,
    /// Frames used (outlier frames beyond 5σ masked).
    pub keep: Vec<bool>,
    /// The recorded input over the window, fitted once ([`RecordedInput::fit`]).
    pub input: RecordedInput,
}

impl Win {
    /// Frames used.
    pub fn kept(&self) -> usize {
        self.keep.iter().filter(|&&k| k).count()
    }
}

/// A model to simulate: its terms, the geometry of the force shape, and the latency (a fixed
/// value, or fitted as the last entry of θ).
#[derive(Debug, Clone, PartialEq)]
pub struct SimModel<'a> {
    /// The runs.
    pub runs: &'a [CleanRun],
    /// Geometry for the force shape h(α, β).
    pub geo: Geometry,
    /// Terms (θ holds their coefficients first).
    pub terms: Vec<Term>,
    /// Latency, s (the start value when fitted).
    pub latency: f64,
    /// Whether the latency is the last entry of θ.
    pub fit_latency: bool,
    /// Breakaway excess of the static friction, s⁻² (not fitted here: [`super::release`]).
    pub eta_static_excess: f64,
    /// Relative tolerance of the window simulations ([`super::diagnose::DiagnoseOptions::tol`]).
    pub tol: f64,
    /// Shape parameters held at these values outside θ (a profile over a family's shape,
    /// [`super::profile`]; empty: every shape of the model is an entry of θ).
    pub held_shapes: Vec<(Shape, f64)>,
    /// Weight λ of the roughness penalty of the model's curves ([`super::curve`]): the refit
    /// minimises χ² + λ Σ (c_{j−1} − 2c_j + c_{j+1})² over each curve's coefficients c (s⁻²), as
    /// rows appended after the windows' residuals ([`Self::penalty_rows`]; 0: no penalty).
    pub roughness: f64,
    /// The runs' session positions (the clocks of the drift terms), computed at the first
    /// simulation that needs them ([`Self::session_position`]) and kept with the model.
    pub session: OnceLock<Vec<SessionPosition>>,
}

impl<'a> SimModel<'a> {
    /// The model of `terms` on `runs` with no latency, no breakaway excess and no held shape,
    /// simulated at the relative tolerance `tol`: the plain model a refit starts from.
    pub fn of_terms(runs: &'a [CleanRun], geo: Geometry, terms: Vec<Term>, tol: f64) -> Self {
        Self {
            runs,
            geo,
            terms,
            latency: 0.0,
            fit_latency: false,
            eta_static_excess: 0.0,
            tol,
            held_shapes: Vec::new(),
            roughness: 0.0,
            session: OnceLock::new(),
        }
    }
}

impl SimModel<'_> {
    /// Latency at θ.
    pub fn latency_of(&self, theta: &[f64]) -> f64 {
        if self.fit_latency {
            theta[self.terms.len()]
        } else {
            self.latency
        }
    }
    /// The session position of run `run` ([`session_positions`], computed once per model).
    pub fn session_position(&self, run: usize) -> SessionPosition {
        self.session.get_or_init(|| session_positions(self.runs))[run]
    }
    /// Coefficients of run `run` at θ.
    pub fn coefficients(&self, theta: &[f64], run: usize) -> Coefficients {
        let mut c = coefficients_for_run(
            &self.terms,
            &theta[..self.terms.len()],
            self.session_position(run),
            &self.held_shapes,
        );
        c.eta_static_excess += self.eta_static_excess;
        c
    }
    /// The window's system at θ.
    pub fn system(&self, theta: &[f64], w: &Win) -> AugmentedGear {
        let r = &self.runs[w.run];
        let c = self.coefficients(theta, w.run);
        window_system(
            r,
            &c,
            &self.geo,
            self.latency_of(theta),
            (w.lo, w.hi),
            &w.input,
        )
    }
    /// θ with every shape parameter clamped into its family's range ([`Shape::range`]), the value
    /// the model evaluates: an optimiser may step beyond the range, where the residuals no longer
    /// depend on the shape (its σ is then infinite), and the reported value must be the one used.
    pub fn clamp_shapes(&self, theta: &mut [f64]) {
        for (t, v) in self.terms.iter().zip(theta.iter_mut()) {
            if let Term::Shape(s) = t {
                let (lo, hi) = s.range();
                *v = v.clamp(lo, hi);
            }
        }
    }
    /// Whether a shape parameter of θ lies within its finite-difference step ([`COEF_STEP`]) of
    /// an end of its range ([`Shape::range`]).
    pub fn near_shape_bound(&self, theta: &[f64]) -> bool {
        self.terms.iter().zip(theta).any(|(t, &v)| match t {
            Term::Shape(s) => {
                let (lo, hi) = s.range();
                let h = COEF_STEP * v.abs().max(1.0);
                v + h > hi || v - h < lo
            }
            _ => false,
        })
    }
    /// The roughness penalty's residual rows at θ, √λ times the cyclic second differences of each
    /// curve's coefficients, and their Jacobian (constant: the penalty is quadratic); empty
    /// without a curve or with λ = 0.
    pub fn penalty_rows(&self, theta: &[f64]) -> (Vec<f64>, DMatrix<f64>) {
        let curves = curve_columns(&self.terms);
        let rows: usize = curves.iter().map(|c| c.len()).sum();
        if self.roughness <= 0.0 || rows == 0 {
            return (Vec::new(), DMatrix::zeros(0, theta.len()));
        }
        let w = self.roughness.sqrt();
        let mut r = Vec::with_capacity(rows);
        let mut j = DMatrix::zeros(rows, theta.len());
        for cols in &curves {
            let c: Vec<f64> = cols.iter().map(|&k| theta[k]).collect();
            let n = cols.len();
            for (i, d) in second_differences(&c).into_iter().enumerate() {
                let row = r.len();
                r.push(w * d);
                j[(row, cols[(i + n - 1) % n])] += w;
                j[(row, cols[i])] -= 2.0 * w;
                j[(row, cols[(i + 1) % n])] += w;
            }
        }
        (r, j)
    }
    /// θ from term coefficients and the latency.
    pub fn theta(&self, coef: &[f64], latency: f64) -> Vec<f64> {
        let mut t = coef.to_vec();
        if self.fit_latency {
            t.push(latency);
        }
        t
    }
    /// (χ², frames) of window `w` at θ: its state fitted (multi-start) with the model fixed.
    pub fn window_chi2(&self, theta: &[f64], w: &Win) -> Option<(f64, usize)> {
        let r = &self.runs[w.run];
        let sys = self.system(theta, w);
        let (t, b) = (&r.t[w.lo..w.hi], &r.beta[w.lo..w.hi]);
        let f = fit_window_state(
            &sys,
            t,
            b,
            &w.keep,
            r.sigma_camera.max(1e-12),
            [b[0], r.v[w.lo]],
            true,
            self.tol,
        )?;
        Some((f.rss, w.kept()))
    }
}

impl SimModel<'_> {
    /// χ² of window `w` at θ with its state refitted from the warm start `x` (Gauss–Newton steps,
    /// the projection of the refit).
    pub fn window_chi2_warm(&self, theta: &[f64], w: &Win, x: [f64; 2]) -> Option<f64> {
        let r = &self.runs[w.run];
        let sys = self.system(theta, w);
        let (t, b) = (&r.t[w.lo..w.hi], &r.beta[w.lo..w.hi]);
        let (res, _) = project_state(&sys, t, b, &w.keep, r.sigma_camera.max(1e-12), x, self.tol)?;
        Some(res.iter().map(|v| v * v).sum())
    }
    /// χ² of window `w` at θ: from the warm start when there is one and its fit is good
    /// (≤ 4 per frame), else the better of that and a multi-start state fit.
    pub fn window_chi2_from(&self, theta: &[f64], w: &Win, warm: Option<[f64; 2]>) -> Option<f64> {
        let from_warm = warm.and_then(|x| self.window_chi2_warm(theta, w, x));
        match from_warm {
            Some(c) if c <= 4.0 * w.kept() as f64 => Some(c),
            _ => {
                let fresh = self.window_chi2(theta, w).map(|x| x.0);
                match (fresh, from_warm) {
                    (Some(a), Some(b)) => Some(a.min(b)),
                    (a, b) => a.or(b),
                }
            }
        }
    }
}

#[cfg(test)]
impl Win {
    /// Samples 0..len of run `run`, every frame kept (the unit tests' windows).
    pub(crate) fn whole(run: usize, len: usize) -> Self {
        Self {
            run,
            lo: 0,
            hi: len,
            keep: vec![true; len],
            input: RecordedInput::default(),
        }
    }
}

#[cfg(test)]
impl SimFit {
    /// A fit at θ with Jacobian `jac` and residuals `resid` on consecutive windows of `len` rows
    /// each (window k on run k, [`Win::whole`]), white (inflation 1), unit σ and covariance: the
    /// unit tests of the leave-fold-out step.
    pub(crate) fn of_windows(
        theta: Vec<f64>,
        jac: DMatrix<f64>,
        resid: Vec<f64>,
        len: usize,
    ) -> Self {
        let (p, nw) = (theta.len(), resid.len() / len);
        Self {
            theta,
            err: vec![1.0; p],
            cov: DMatrix::identity(p, p),
            jac,
            resid,
            used: (0..nw).map(|k| (k, k * len)).collect(),
            states: vec![[0.0; 2]; nw],
            rms_rad: 1.0,
            rms_start_rad: 1.0,
            samples: nw * len,
            inflation: 1.0,
            converged: true,
        }
    }
    /// A fit with only θ, its σ and its covariance set, for the unit tests of what reads them
    /// (the Wald test, the reported sizes).
    pub(crate) fn with_covariance(theta: Vec<f64>, err: Vec<f64>, cov: DMatrix<f64>) -> Self {
        let n = theta.len();
        Self {
            theta,
            err,
            cov,
            jac: DMatrix::zeros(0, n),
            resid: Vec::new(),
            used: Vec::new(),
            states: Vec::new(),
            rms_rad: 0.0,
            rms_start_rad: 0.0,
            samples: 0,
            inflation: 1.0,
            converged: true,
        }
    }
}

impl SimFit {
    /// The fitted state of each window of a list of `n` that the refit used.
    pub fn warm_starts(&self, n: usize) -> Vec<Option<[f64; 2]>> {
        let mut warm = vec![None; n];
        for (k, &(wi, _)) in self.used.iter().enumerate() {
            warm[wi] = Some(self.states[k]);
        }
        warm
    }
    /// χ² of every window of `wins` at the solution: from the residuals for the used windows,
    /// by a fresh state fit for the others; and the warm start of each used window.
    pub fn window_chi2(
        &self,
        model: &SimModel,
        wins: &[Win],
    ) -> (Vec<Option<f64>>, Vec<Option<[f64; 2]>>) {
        let mut warm: Vec<Option<[f64; 2]>> = vec![None; wins.len()];
        let mut chi2: Vec<Option<f64>> = vec![None; wins.len()];
        for (k, &(wi, row0)) in self.used.iter().enumerate() {
            warm[wi] = Some(self.states[k]);
            let n = wins[wi].keep.len();
            chi2[wi] = Some(self.resid[row0..row0 + n].iter().map(|v| v * v).sum());
        }
        let missing: Vec<usize> = (0..wins.len()).filter(|&k| chi2[k].is_none()).collect();
        let fresh = par_map(missing.len(), |j| {
            model
                .window_chi2(&self.theta, &wins[missing[j]])
                .map(|x| x.0)
        });
        for (j, k) in missing.into_iter().enumerate() {
            chi2[k] = fresh[j];
        }
        (chi2, warm)
    }
}

/// The windows of `runs`, at most `max` of them: every run keeps an even share (at least
/// `min(6, its windows)`), spread evenly over the run.
pub fn choose_windows(runs: &[CleanRun], max: usize) -> Vec<(usize, usize, usize)> {
    let per: Vec<Vec<(usize, usize)>> = runs.iter().map(prediction_windows).collect();
    let total: usize = per.iter().map(|p| p.len()).sum();
    let mut out = Vec::new();
    for (ri, p) in per.iter().enumerate() {
        if p.is_empty() {
            continue;
        }
        let share = (p.len() * max).div_ceil(total.max(1));
        let quota = share.max(6).min(p.len());
        let stride = p.len() as f64 / quota as f64;
        for q in 0..quota {
            let (i, j) = p[(q as f64 * stride) as usize];
            out.push((ri, i, j));
        }
    }
    out
}

/// Gross outliers of one window: the frames whose residual `r` (σ units, at the times `t`) lies
/// beyond [`OUTLIER_SIGMA`] both from the model and from its neighbours. The second condition is
/// a spike test: s_k = min over the pairs (a, b) of |r_k − r̂_k|/√(1 + w_a² + w_b²), r̂_k =
/// w_a r_a + w_b r_b the straight line in time through two adjacent kept frames among the three
/// nearest on each side — the nearest on both sides, or two on one side (extrapolated) — so each
/// ratio is N(0, 1) for white noise and ≈ 0 for a misfit that is smooth over a few frames: a
/// model that misses an effect leaves a smooth residual (growing over the window from the fitted
/// initial state) and keeps its frames,
/// while a camera outlier frame (10–40°, 20σ and more) is a spike; taking the smallest s over the
/// pairs keeps a good frame next to an outlier (one of its pairs avoids the outlier). The largest
/// spike is removed first and the test repeated. Returns the keep flags.
pub fn gross_outliers(t: &[f64], r: &[f64]) -> Vec<bool> {
    let n = r.len();
    let mut keep = vec![true; n];
    loop {
        let idx: Vec<usize> = (0..n).filter(|&k| keep[k]).collect();
        let m = idx.len();
        if m < 4 {
            return keep;
        }
        let mut worst: Option<(usize, f64)> = None;
        for (j, &k) in idx.iter().enumerate() {
            if r[k].abs() <= OUTLIER_SIGMA {
                continue;
            }
            let pairs = [
                (j >= 3).then(|| (j - 3, j - 2)),
                (j >= 2).then(|| (j - 2, j - 1)),
                (j >= 1 && j + 1 < m).then(|| (j - 1, j + 1)),
                (j + 2 < m).then(|| (j + 1, j + 2)),
                (j + 3 < m).then(|| (j + 2, j + 3)),
            ];
            let spike = pairs
                .into_iter()
                .flatten()
                .map(|(pa, pb)| {
                    let (a, b) = (idx[pa], idx[pb]);
                    let u = (t[k] - t[a]) / (t[b] - t[a]);
                    let (wa, wb) = (1.0 - u, u);
                    ((r[k] - wa * r[a] - wb * r[b]) / (1.0 + wa * wa + wb * wb).sqrt()).abs()
                })
                .fold(f64::INFINITY, f64::min);
            if spike > OUTLIER_SIGMA && worst.is_none_or(|(_, v)| spike > v) {
                worst = Some((k, spike));
            }
        }
        match worst {
            Some((k, _)) => keep[k] = false,
            None => return keep,
        }
    }
}

/// The threshold of [`gross_outliers`], in σ of the camera noise.
pub const OUTLIER_SIGMA: f64 = 5.0;

/// The windows `chosen` with their gross outlier frames ([`gross_outliers`], from the residuals of
/// the window's state fitted under `model` at θ) masked; windows that cannot be fitted, or with
/// more than a fifth of their frames masked, are dropped. The masks target the camera's outlier
/// frames only, not the misfit of `model`: masking every frame beyond 5σ of the base model (as
/// an earlier version did) removed the frames, and dropped the windows, where a missing effect
/// is strongest, and every model refitted on those windows then saw the effect attenuated (a
/// static torque 4–7 % low, a latency 5 % low; docs/diagnosis.md, "Sizes").
pub fn mask_windows(model: &SimModel, theta: &[f64], chosen: &[(usize, usize, usize)]) -> Vec<Win> {
    par_map(chosen.len(), |k| {
        let (run, lo, hi) = chosen[k];
        let r = &model.runs[run];
        let mut w = Win {
            run,
            lo,
            hi,
            keep: vec![true; hi - lo],
            input: RecordedInput::fit(r, lo, hi),
        };
        let sys = model.system(theta, &w);
        let (t, b) = (&r.t[lo..hi], &r.beta[lo..hi]);
        let s = r.sigma_camera.max(1e-12);
        let f = fit_window_state(&sys, t, b, &w.keep, s, [b[0], r.v[lo]], true, model.tol)?;
        w.keep = gross_outliers(t, &f.resid);
        (w.kept() * 5 >= 4 * (hi - lo)).then_some(w)
    })
    .into_iter()
    .flatten()
    .collect()
}

/// Result of a refit by simulation.
#[derive(Debug, Clone, PartialEq)]
pub struct SimFit {
    /// θ (term coefficients, then the latency when fitted).
    pub theta: Vec<f64>,
    /// 1σ of θ.
    pub err: Vec<f64>,
    /// Covariance of θ: the window-clustered sandwich, floored at the white-noise covariance
    /// ([`window_covariance`]).
    pub cov: DMatrix<f64>,
    /// Jacobian of the profiled residuals at θ (rows: the used windows' frames, in order).
    pub jac: DMatrix<f64>,
    /// Residuals at θ, σ units.
    pub resid: Vec<f64>,
    /// Indices (into the window list given) of the windows used, with their first row.
    pub used: Vec<(usize, usize)>,
    /// Fitted initial states of the used windows (warm starts for later predictions).
    pub states: Vec<[f64; 2]>,
    /// rms of the window residuals at θ, rad.
    pub rms_rad: f64,
    /// rms at the start, rad.
    pub rms_start_rad: f64,
    /// Frames used.
    pub samples: usize,
    /// How much the covariance widens the white-noise one s²(JᵀJ)⁻¹: the largest variance ratio
    /// over all directions ([`window_covariance`]; ≥ 1).
    pub inflation: f64,
    /// Whether the optimiser reported convergence.
    pub converged: bool,
}

impl SimFit {
    /// Coefficient values and 1σ of the terms (latency excluded).
    pub fn coef(&self, nterms: usize) -> (&[f64], &[f64]) {
        (&self.theta[..nterms], &self.err[..nterms])
    }
    /// θ refitted without the windows of the runs for which `out(run)` holds, by one
    /// Gauss–Newton step from θ on the remaining rows (linear least squares by column-pivoted
    /// QR): θ₋ = θ + argmin_δ ‖r_in + J_in δ‖. Exact for a model linear in θ; for the small change
    /// of leaving a fold out the usual first-order approximation of a refit. A parameter that the
    /// remaining rows do not determine ([`lstsq_determined`]: its column zero or dependent on the
    /// others) is held at its fitted value: a Stribeck excess whose held width leaves it unseen in
    /// the windows' motion (its column zero) was moved by 10²⁸³ by a minimum-norm SVD step, and the
    /// model then stuck throughout every held-out window (Σχ² 2.5·10⁷ against 3.1·10³ in sample).
    pub fn step_without(&self, wins: &[Win], out: impl Fn(usize) -> bool) -> Option<Vec<f64>> {
        let p = self.theta.len();
        let mut rows = Vec::new();
        for &(wi, row0) in &self.used {
            if !out(wins[wi].run) {
                rows.extend(row0..row0 + wins[wi].keep.len());
            }
        }
        // the rows after the windows' are the roughness penalty's: always kept
        let windows_end = self
            .used
            .iter()
            .map(|&(wi, row0)| row0 + wins[wi].keep.len())
            .max()
            .unwrap_or(0);
        rows.extend(windows_end..self.resid.len());
        if rows.len() <= p {
            return None;
        }
        let j = Mat::from_fn(rows.len(), p, |a, b| self.jac[(rows[a], b)]);
        let r: Vec<f64> = rows.iter().map(|&i| -self.resid[i]).collect();
        let d = lstsq_determined(&j, &r, DEFAULT_RCOND).ok()?;
        let out: Vec<f64> = (0..p).map(|k| self.theta[k] + d[k]).collect();
        out.iter().all(|v| v.is_finite()).then_some(out)
    }
}

/// The θ indices of each curve's coefficients in `terms` ([`Term::Spline`], one list per kind in
/// the order of the basis functions).
pub fn curve_columns(terms: &[Term]) -> Vec<Vec<usize>> {
    SplineKind::ALL
        .iter()
        .map(|&kind| {
            let mut cols: Vec<(u8, usize)> = terms
                .iter()
                .enumerate()
                .filter_map(|(k, t)| match t {
                    Term::Spline(kk, j) if *kk == kind => Some((*j, k)),
                    _ => None,
                })
                .collect();
            cols.sort();
            cols.into_iter().map(|c| c.1).collect::<Vec<usize>>()
        })
        .filter(|c| c.len() >= 3)
        .collect()
}

/// Refits θ of `model` from `theta0` by multiple shooting over the windows `wins`. Windows whose
/// start is poor (rms > 2σ: the model cannot follow them there, e.g. a wrong stick/slip branch)
/// are left out. With [`ShootingOptions::reselect`] the windows left out are tried again at the
/// solution, and the fit is repeated from it with those that the fitted model follows, until no
/// more join (at most [`MAX_RESELECT`] times): the windows left out at a start that lacks part of
/// an effect are those where the effect is strongest, and a fit without them sees it attenuated
/// (a latency of 8 ms came out 7.89 ± 0.05 ms from a start at 5 ms, 7.98 ± 0.03 re-selected).
/// `None` when the model has no simulation form, no window can be fitted, or the optimiser
/// cannot evaluate the start.
pub fn refit(
    model: &SimModel,
    theta0: &[f64],
    wins: &[Win],
    opts: &ShootingOptions,
) -> Option<SimFit> {
    refit_sharing(model, theta0, wins, opts, None)
}

/// [`refit`], the multi-start searches of its windows at the start θ₀ shared through `searches`
/// with other refits of the same model from the same θ₀ (a candidate's screening on every second
/// window and its refit on all of them: [`super::select::judge_round`]).
pub fn refit_sharing(
    model: &SimModel,
    theta0: &[f64],
    wins: &[Win],
    opts: &ShootingOptions,
    searches: Option<&StartSearches>,
) -> Option<SimFit> {
    if !simulable(&model.terms) || wins.is_empty() {
        return None;
    }
    let all: Vec<usize> = (0..wins.len()).collect();
    let mut states = match searches {
        Some(memo) => memo.followed(model, theta0, wins, &all),
        None => followed_windows(model, theta0, wins, &all),
    };
    let mut fit = fit_windows(model, theta0, wins, &states, opts)?;
    let rms_start_rad = fit.rms_start_rad;
    let rounds = match opts.reselect {
        Reselect::Never => 0,
        Reselect::Always => MAX_RESELECT,
        Reselect::OnceBelow(f) => usize::from((fit.used.len() as f64) < f * wins.len() as f64),
    };
    for _ in 0..rounds {
        let out: Vec<usize> = all
            .iter()
            .copied()
            .filter(|&k| states[k].is_none())
            .collect();
        let back = followed_windows(model, &fit.theta, wins, &out);
        if back.iter().all(|s| s.is_none()) {
            break;
        }
        for (k, &(wi, _)) in fit.used.iter().enumerate() {
            states[wi] = Some(fit.states[k]);
        }
        for &k in &out {
            states[k] = back[k];
        }
        match fit_windows(model, &fit.theta.clone(), wins, &states, opts) {
            Some(f) => fit = f,
            None => break,
        }
    }
    fit.rms_start_rad = rms_start_rad;
    Some(fit)
}

/// The windows' multi-start state searches made at a start θ (the result of
/// [`followed_windows`] for each window, by θ and window), for refits of one model that start
/// from the same θ ([`refit_sharing`]). The searches are deterministic, so a shared result is
/// the one the refit would compute; only refits of the same model may share one.
#[derive(Debug, Default)]
pub struct StartSearches {
    found: Mutex<HashMap<SearchKey, Option<[f64; 2]>>>,
}

/// A search's θ (its bits) and window (run, first and end frame).
type SearchKey = (Vec<u64>, usize, usize, usize);

impl StartSearches {
    /// [`followed_windows`] of `model` at θ, each window searched at most once per θ.
    fn followed(
        &self,
        model: &SimModel,
        theta: &[f64],
        wins: &[Win],
        which: &[usize],
    ) -> Vec<Option<[f64; 2]>> {
        let bits: Vec<u64> = theta.iter().map(|v| v.to_bits()).collect();
        let key = |w: &Win| (bits.clone(), w.run, w.lo, w.hi);
        let known: Vec<Option<Option<[f64; 2]>>> = match self.found.lock() {
            Ok(m) => which
                .iter()
                .map(|&k| m.get(&key(&wins[k])).copied())
                .collect(),
            Err(_) => vec![None; which.len()],
        };
        let todo: Vec<usize> = which
            .iter()
            .zip(&known)
            .filter(|(_, h)| h.is_none())
            .map(|(&k, _)| k)
            .collect();
        let mut out = followed_windows(model, theta, wins, &todo);
        if let Ok(mut m) = self.found.lock() {
            for &k in &todo {
                m.insert(key(&wins[k]), out[k]);
            }
        }
        for (&k, h) in which.iter().zip(known) {
            if let Some(x) = h {
                out[k] = x;
            }
        }
        out
    }
}

/// Most rounds of re-selecting the windows at the solution ([`refit`]).
pub const MAX_RESELECT: usize = 3;

/// For each window of `wins` (indexed by the list `which`, in its order): its initial state
/// fitted under `model` at θ (multi-start) when the model follows it there (χ² ≤ 4 per frame,
/// rms ≤ 2σ), else `None`. Returns one entry per window of `wins`; those not in `which` are
/// `None`.
fn followed_windows(
    model: &SimModel,
    theta: &[f64],
    wins: &[Win],
    which: &[usize],
) -> Vec<Option<[f64; 2]>> {
    let found: Vec<Option<[f64; 2]>> = par_map(which.len(), |j| {
        let w = &wins[which[j]];
        let r = &model.runs[w.run];
        let sys = model.system(theta, w);
        let (t, b) = (&r.t[w.lo..w.hi], &r.beta[w.lo..w.hi]);
        let s = r.sigma_camera.max(1e-12);
        let f = fit_window_state(&sys, t, b, &w.keep, s, [b[0], r.v[w.lo]], true, model.tol)?;
        (f.rss / w.kept().max(1) as f64 <= 4.0).then_some([f.p[0], f.p[1]])
    });
    let mut out = vec![None; wins.len()];
    for (&k, s) in which.iter().zip(found) {
        out[k] = s;
    }
    out
}

/// The fit of θ from `theta0` on the windows that have a start state in `start` (the variable
/// projection and the covariance of [`refit`]).
fn fit_windows(
    model: &SimModel,
    theta0: &[f64],
    wins: &[Win],
    start: &[Option<[f64; 2]>],
    opts: &ShootingOptions,
) -> Option<SimFit> {
    let mut used = Vec::new();
    let mut states = Vec::new();
    let mut row = 0usize;
    for (k, s) in start.iter().enumerate() {
        if let Some(x) = *s {
            used.push((k, row));
            states.push(x);
            row += wins[k].keep.len();
        }
    }
    if used.is_empty() {
        return None;
    }
    let warm = Mutex::new(Projected {
        theta: Vec::new(),
        states: states.clone(),
        best: (f64::INFINITY, states),
    });
    let residuals = |theta: &[f64]| -> Option<Vec<f64>> {
        let guesses = warm.lock().ok()?.best.1.clone();
        let per: Vec<Option<(Vec<f64>, [f64; 2])>> = par_map(used.len(), |k| {
            let w = &wins[used[k].0];
            let r = &model.runs[w.run];
            let sys = model.system(theta, w);
            let (t, b) = (&r.t[w.lo..w.hi], &r.beta[w.lo..w.hi]);
            project_state(
                &sys,
                t,
                b,
                &w.keep,
                r.sigma_camera.max(1e-12),
                guesses[k],
                model.tol,
            )
        });
        let mut out = Vec::with_capacity(row);
        let mut new_states = guesses;
        for (k, p) in per.into_iter().enumerate() {
            let (res, x0) = p?;
            out.extend(res);
            new_states[k] = x0;
        }
        out.extend(model.penalty_rows(theta).0);
        let chi2: f64 = out.iter().map(|v| v * v).sum();
        let mut g = warm.lock().ok()?;
        if chi2 <= g.best.0 {
            g.best = (chi2, new_states.clone());
        }
        g.theta = theta.to_vec();
        g.states = new_states;
        Some(out)
    };
    let jacobian = |theta: &[f64], _r: &[f64]| -> Option<DMatrix<f64>> {
        let at_theta = {
            let g = warm.lock().ok()?;
            (g.theta == theta).then(|| g.states.clone())
        };
        let states = match at_theta {
            Some(s) => s,
            None => {
                residuals(theta)?;
                warm.lock().ok()?.states.clone()
            }
        };
        Some(with_penalty(
            model,
            theta,
            varpro_jacobian(model, theta, wins, &used, &states, row, Differences::REFIT),
        ))
    };
    let r0 = residuals(theta0)?;
    let sigma_rms = |res: &[f64]| -> f64 {
        let (mut ss, mut n) = (0.0, 0usize);
        for &(wi, row0) in &used {
            let w = &wins[wi];
            let s = model.runs[w.run].sigma_camera;
            for (k, &kp) in w.keep.iter().enumerate() {
                if kp {
                    ss += (res[row0 + k] * s).powi(2);
                    n += 1;
                }
            }
        }
        (ss / n.max(1) as f64).sqrt()
    };
    let sol = least_squares_with_jacobian(
        &residuals,
        &jacobian,
        theta0,
        opts.patience,
        Some((1e-6, 1e-5)),
    )?;
    let mut sol = sol;
    model.clamp_shapes(&mut sol.p);
    if model.near_shape_bound(&sol.p) {
        // at the end of a shape's range the central column is half the slope (or none, beyond
        // it), and the covariance would hold the shape fixed there: the column is taken one-sided
        // towards the inside, so the σ of the shape and of what trades off with it carry the
        // valley along it
        residuals(&sol.p)?;
        let states = warm.lock().ok()?.states.clone();
        let jac = varpro_jacobian(
            model,
            &sol.p,
            wins,
            &used,
            &states,
            row,
            Differences::AT_SHAPE_BOUND,
        );
        sol.jac = with_penalty(model, &sol.p, jac);
        sol.cov = scaled_cov(&sol.jac, sol.rss);
    }
    let samples: usize = used.iter().map(|&(wi, _)| wins[wi].kept()).sum();
    let (cov, inflation) = window_covariance(&sol, &used, wins, samples);
    let err: Vec<f64> = (0..theta0.len())
        .map(|k| cov[(k, k)].max(0.0).sqrt())
        .collect();
    let (rms_rad, rms_start_rad) = (sigma_rms(&sol.resid), sigma_rms(&r0));
    let states = warm.into_inner().ok()?.states;
    Some(SimFit {
        theta: sol.p.clone(),
        err,
        cov,
        jac: sol.jac.clone(),
        rms_rad,
        resid: sol.resid,
        used,
        states,
        rms_start_rad,
        samples,
        inflation,
        converged: sol.converged,
    })
}

/// The Jacobian `jac` of the windows' residuals with the rows of the roughness penalty
/// appended ([`SimModel::penalty_rows`]; `jac` itself without a penalty).
fn with_penalty(model: &SimModel, theta: &[f64], jac: DMatrix<f64>) -> DMatrix<f64> {
    let (r, jp) = model.penalty_rows(theta);
    if r.is_empty() {
        return jac;
    }
    let (m, n) = (jac.nrows(), jac.ncols());
    let mut out = DMatrix::zeros(m + r.len(), n);
    out.view_mut((0, 0), (m, n)).copy_from(&jac);
    out.view_mut((m, 0), (r.len(), n)).copy_from(&jp);
    out
}

/// The window states projected at the last θ whose residuals were evaluated (the warm starts of
/// the next projection, and the states at which [`varpro_jacobian`] differentiates).
struct Projected {
    theta: Vec<f64>,
    states: Vec<[f64; 2]>,
    /// The states at the smallest χ² evaluated so far (the optimiser's current point: the warm
    /// start of the next projection, so that a rejected trial's states never seed it).
    best: (f64, Vec<[f64; 2]>),
}

/// How [`varpro_jacobian`] differences the columns.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Differences {
    /// A shape parameter near an end of its range is differenced one-sided towards the inside.
    inward: bool,
    /// How a curve's coefficients are differenced.
    curves: CurveColumns,
}

impl Differences {
    /// The refit's steps: central, a curve's coefficients forward.
    const REFIT: Self = Self {
        inward: false,
        curves: CurveColumns::Forward,
    };
    /// The covariance of a fit whose shape lies at an end of its range: as [`Self::REFIT`], the
    /// shapes differenced towards the inside.
    const AT_SHAPE_BOUND: Self = Self {
        inward: true,
        curves: CurveColumns::Forward,
    };
}

/// How [`varpro_jacobian`] differences a curve's coefficients.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum CurveColumns {
    /// Forward from θ (the refits').
    Forward,
    /// Central, as every other coefficient (the check of the forward quotients).
    #[cfg_attr(not(test), allow(dead_code))]
    Central,
}

/// Relative finite-difference step of a term coefficient in [`varpro_jacobian`] (of
/// max(|θ_k|, 1)); the latency's step is [`LATENCY_STEP`].
const COEF_STEP: f64 = 1e-4;
/// Finite-difference step of the latency, s.
const LATENCY_STEP: f64 = 1e-5;

/// The Jacobian of the profiled residuals at θ by variable projection (Kaufman's form of the
/// Golub–Pereyra derivative): for every used window w, with its state x_w held at the projected
/// one,
///
/// J_w = (I − Q_w Q_wᵀ) ∂r_w/∂θ,  Q_w an orthonormal basis of the columns of ∂r_w/∂x_w,
///
/// ∂r_w/∂θ by central differences of simulations from the same state (steps [`COEF_STEP`],
/// [`LATENCY_STEP`]), ∂r_w/∂x_w exactly from the variational equations of the simulation at θ
/// ([`window_residuals_jacobian`]). At a projected state (∂r_w/∂x_wᵀ r_w = 0)
/// this is the derivative of the profiled residuals to first order, and it does not depend on how
/// far each projection was iterated: differencing the projected residuals themselves (each trial
/// θ re-projecting the states from the previous trial's) adds the projections' stopping errors
/// divided by the step, which on a drag family made the exponent's column 30 % too long and its
/// σ 25 times too small. A state direction the window does not see (a window at rest throughout:
/// β̇₀ has no effect) is left out of Q_w. A window that cannot be simulated at θ gives a zero
/// block, and a column whose simulation fails on one side is differenced one-sided from θ (zero
/// when both fail), so that one window does not fail the refit's step.
///
/// A curve's coefficients ([`Term::Spline`], [`CurveColumns::Forward`]) are differenced
/// forward from θ: one simulation per column instead of two, for the 24 columns that make a curve
/// model's Jacobian three quarters of its cost. At the relative step [`COEF_STEP`] the forward
/// quotient's truncation error (half the step times the residuals' curvature in the coefficient,
/// which enters the force linearly) adds little to the integration error the difference carries
/// either way (`forward_curve_columns_match_central_differences`: 5 %).
fn varpro_jacobian(
    model: &SimModel,
    theta: &[f64],
    wins: &[Win],
    used: &[(usize, usize)],
    states: &[[f64; 2]],
    rows: usize,
    Differences { inward, curves }: Differences,
) -> DMatrix<f64> {
    let n = theta.len();
    let nt = model.terms.len();
    let blocks: Vec<DMatrix<f64>> = par_map(used.len(), |k| {
        let w = &wins[used[k].0];
        let r = &model.runs[w.run];
        let (t, b) = (&r.t[w.lo..w.hi], &r.beta[w.lo..w.hi]);
        let s = r.sigma_camera.max(1e-12);
        let sim = |th: &[f64], x: [f64; 2]| {
            window_residuals(&model.system(th, w), t, b, &w.keep, s, x, model.tol)
        };
        let x = states[k];
        let nw = w.keep.len();
        let mut jw = DMatrix::zeros(nw, n);
        // the derivative of the residuals with respect to the window's state, from the
        // variational equations; a window that cannot be simulated at θ (its step budget)
        // contributes no rows (a zero block) instead of failing the whole refit's step
        let Some((_, jx)) =
            window_residuals_jacobian(&model.system(theta, w), t, b, &w.keep, s, x, model.tol)
        else {
            return jw;
        };
        // the residuals at θ itself for one-sided differences (at a range's end, or where one
        // side's simulation fails), by the same plain simulation as the differences (the
        // variational run's step sequence differs, and its rounding would not cancel in the
        // difference); evaluated when first needed
        let mut r0: Option<Option<Vec<f64>>> = None;
        let mut at_theta = || r0.get_or_insert_with(|| sim(theta, x)).clone();
        let mut th = theta.to_vec();
        for c in 0..n {
            let h = if c >= nt {
                LATENCY_STEP
            } else {
                COEF_STEP * theta[c].abs().max(1.0)
            };
            let (up, down) = match model.terms.get(c) {
                Some(Term::Shape(sh)) if inward => {
                    let (lo, hi) = sh.range();
                    (theta[c] + h <= hi, theta[c] - h >= lo)
                }
                Some(Term::Spline(..)) if curves == CurveColumns::Forward => (true, false),
                _ => (true, true),
            };
            let mut side = |dir: f64, inside: bool| {
                let r = if inside {
                    th[c] = theta[c] + dir * h;
                    let r = sim(&th, x);
                    th[c] = theta[c];
                    r.map(|r| (r, h))
                } else {
                    None
                };
                r.or_else(|| at_theta().map(|r| (r, 0.0)))
            };
            // a column whose simulations all fail stays zero: the step does not move along it
            let (Some((rp, hp)), Some((rm, hm))) = (side(1.0, up), side(-1.0, down)) else {
                continue;
            };
            if hp + hm <= 0.0 {
                continue;
            }
            for i in 0..nw {
                jw[(i, c)] = (rp[i] - rm[i]) / (hp + hm);
            }
        }
        let mut basis: Vec<DVector<f64>> = Vec::with_capacity(2);
        for i in 0..2 {
            let mut q = jx.column(i).clone_owned();
            let norm0 = q.norm();
            for e in &basis {
                let d = e.dot(&q);
                q -= e * d;
            }
            let norm = q.norm();
            if norm > 1e-8 * norm0 && norm > 0.0 {
                basis.push(q / norm);
            }
        }
        for c in 0..n {
            let mut col = jw.column(c).clone_owned();
            for e in &basis {
                let d = e.dot(&col);
                col -= e * d;
            }
            jw.set_column(c, &col);
        }
        jw
    });
    let mut j = DMatrix::zeros(rows, n);
    for (k, blk) in blocks.into_iter().enumerate() {
        j.view_mut((used[k].1, 0), (blk.nrows(), n)).copy_from(&blk);
    }
    j
}

/// The covariance of θ of a refit: the window-clustered sandwich ([`cluster_sandwich`], CR2)
///
/// R = A [Σ_w (s_w − s̄)(s_w − s̄)ᵀ] A,  A = (JᵀJ)⁻¹,  s_w = J_wᵀ (I − H_ww)^(−1/2) r_w,
///
/// over the windows w used (J_w, r_w: the window's rows of the Jacobian of the profiled residuals
/// and its residuals, σ units; H_ww = J_w A J_wᵀ), floored in every direction at the white-noise
/// covariance W = s²A, s² = RSS/(frames − 2·windows − parameters) ([`covariance_floor`]:
/// C ⪰ R and C ⪰ W). A window's residuals share its fitted initial state, the camera's correlated
/// noise and the model's misfit along the window; windows are near-independent (their own states
/// and noise), so the scatter of their scores carries all three without a model of the noise.
/// The profiled Jacobian is orthogonal to the directions of each window's state, so the two
/// degrees of freedom per window that the states take need no correction in R. The floor: a
/// parameter that few windows determine (the latency: the fast windows of the driven runs) has a
/// sandwich from few effective clusters, noisy and biased low, and the camera noise sets a variance
/// below which no estimate is honest. Also returns the covariance's inflation, the largest variance
/// ratio of C to W over all directions. With a single window there is no scatter to measure, and
/// the covariance is W.
fn window_covariance(
    sol: &LsqFit,
    used: &[(usize, usize)],
    wins: &[Win],
    samples: usize,
) -> (DMatrix<f64>, f64) {
    let clusters: Vec<(usize, usize)> = used
        .iter()
        .map(|&(wi, row0)| (row0, wins[wi].keep.len()))
        .collect();
    let p = sol.p.len();
    let dof = (samples as f64 - 2.0 * used.len() as f64 - p as f64).max(1.0);
    // the fit's s²(JᵀJ)⁻¹ (s² = RSS/(rows − parameters)) rescaled to s² = RSS/dof: no second
    // factorisation of J (an infinite variance stays infinite)
    let rows = sol.resid.len().saturating_sub(p).max(1) as f64;
    let white = sol.cov.map(|v| v * rows / dof);
    match cluster_sandwich(&sol.jac, &sol.resid, &clusters) {
        Some(robust) => covariance_floor(&robust, &white),
        None => (white, 1.0),
    }
}

/// Refits a window's state from the warm start `x` by Gauss–Newton steps (the exact Jacobian of
/// the simulated window, [`window_residuals_jacobian`]; 2×2 normal equations; a step that does not lower the χ² is halved, up to
/// [`PROJECTION_HALVINGS`] times): the projection step of variable projection, a few simulations
/// instead of a full optimiser run. It stops when the Gauss–Newton decrement gᵀ(JᵀJ)⁻¹g (the χ²
/// a full step would still gain) is below [`PROJECTION_DECREMENT`], or after
/// [`PROJECTION_STEPS`] steps. Falls back to [`fit_window_state`] when no step can be taken at
/// the start. Returns (residuals, state).
fn project_state(
    sys: &AugmentedGear,
    t: &[f64],
    b: &[f64],
    keep: &[bool],
    sigma: f64,
    x: [f64; 2],
    tol: f64,
) -> Option<(Vec<f64>, [f64; 2])> {
    let resid = |p: [f64; 2]| window_residuals_jacobian(sys, t, b, keep, sigma, p, tol);
    let rss = |r: &[f64]| r.iter().map(|v| v * v).sum::<f64>();
    let gn = || -> Option<(Vec<f64>, [f64; 2])> {
        let mut x = x;
        let (mut r, mut jac) = resid(x)?;
        let mut e = rss(&r);
        for step in 0..PROJECTION_STEPS {
            let (mut a00, mut a01, mut a11, mut g0, mut g1) = (0.0, 0.0, 0.0, 0.0, 0.0);
            for k in 0..r.len() {
                let (j0, j1) = (jac[(k, 0)], jac[(k, 1)]);
                a00 += j0 * j0;
                a01 += j0 * j1;
                a11 += j1 * j1;
                g0 += j0 * r[k];
                g1 += j1 * r[k];
            }
            let det = a00 * a11 - a01 * a01;
            let dx = if det.is_finite() && det > 1e-14 * a00 * a11 {
                [-(a11 * g0 - a01 * g1) / det, -(a00 * g1 - a01 * g0) / det]
            } else if a00 > 0.0 && a00.is_finite() {
                // β̇₀ unseen (a window at rest throughout): a step in β₀ alone
                [-g0 / a00, 0.0]
            } else if step == 0 {
                return None;
            } else {
                break;
            };
            let decrement = -(g0 * dx[0] + g1 * dx[1]);
            if decrement <= PROJECTION_DECREMENT {
                return Some((r, x));
            }
            match halved_step(&resid, &rss, x, dx, e) {
                Some((xn, (rn, jn), en)) => {
                    (x, r, jac, e) = (xn, rn, jn, en);
                }
                None if step == 0 => return None,
                None => {
                    // a kink of χ²(x) (a stick phase starting or ending inside the window): the
                    // trust-region fit from here, kept when it is lower
                    if decrement > 1e-6 {
                        if let Some(f) = fit_window_state(sys, t, b, keep, sigma, x, false, tol) {
                            if f.rss < e {
                                return Some((f.resid, [f.p[0], f.p[1]]));
                            }
                        }
                    }
                    break;
                }
            }
        }
        Some((r, x))
    };
    gn().or_else(|| {
        let f = fit_window_state(sys, t, b, keep, sigma, x, true, tol)?;
        Some((f.resid, [f.p[0], f.p[1]]))
    })
}

/// Most Gauss–Newton steps of a window's state projection ([`project_state`]).
const PROJECTION_STEPS: usize = 8;
/// Most halvings of a projection step that does not lower the χ².
const PROJECTION_HALVINGS: usize = 4;
/// The Gauss–Newton decrement (χ² units) below which a projection has converged: the χ² it could
/// still gain is far below the changes the refit resolves (its ftol of 10⁻⁶ relative is ~10⁻³ on
/// a refit of a few thousand frames).
const PROJECTION_DECREMENT: f64 = 1e-8;

/// A window's residuals and their Jacobian with respect to its state
/// ([`window_residuals_jacobian`]).
type ResidualsJacobian = (Vec<f64>, DMatrix<f64>);

/// The step `dx` from `x`, halved until the χ² does not rise (at most [`PROJECTION_HALVINGS`]
/// times): (state, its residuals and Jacobian, χ²), or `None` when no such step lowers it.
fn halved_step(
    resid: &impl Fn([f64; 2]) -> Option<ResidualsJacobian>,
    rss: &impl Fn(&[f64]) -> f64,
    x: [f64; 2],
    dx: [f64; 2],
    e: f64,
) -> Option<([f64; 2], ResidualsJacobian, f64)> {
    let mut f = 1.0;
    for _ in 0..=PROJECTION_HALVINGS {
        let xn = [x[0] + f * dx[0], x[1] + f * dx[1]];
        if let Some(rj) = resid(xn) {
            let en = rss(&rj.0);
            if en <= e {
                return Some((xn, rj, en));
            }
        }
        f *= 0.5;
    }
    None
}

/// `f(0..n)`, in parallel with the `parallel` feature.
pub fn par_map<T: Send, F: Fn(usize) -> T + Sync + Send>(n: usize, f: F) -> Vec<T> {
    #[cfg(feature = "parallel")]
    {
        use rayon::prelude::*;
        (0..n).into_par_iter().map(f).collect()
    }
    #[cfg(not(feature = "parallel"))]
    {
        (0..n).map(f).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::identification::lm::tests::normals as noise;

    /// The roughness penalty's rows are √λ times the cyclic second differences of each curve's
    /// coefficients (wherever its terms sit in θ), zero on a constant curve,
    /// and their Jacobian reproduces the rows exactly (the penalty is linear in θ); no rows
    /// without a curve or with λ = 0.
    #[test]
    fn penalty_rows_are_the_scaled_second_differences() {
        use crate::model::recorded::spline::{SplineKind, SPLINE_KNOTS};
        let mut terms = super::super::regression::BASE_TERMS.to_vec();
        terms.extend(
            (0..SPLINE_KNOTS)
                .rev()
                .map(|j| Term::Spline(SplineKind::Friction, j as u8)),
        );
        let runs: [CleanRun; 0] = [];
        let mut model = SimModel::of_terms(&runs, Geometry::new(0.5, 0.5), terms, 1e-8);
        let theta: Vec<f64> = (0..model.terms.len())
            .map(|k| (k as f64 * 0.9).sin())
            .collect();
        assert!(model.penalty_rows(&theta).0.is_empty());
        model.roughness = 4.0;
        let (r, j) = model.penalty_rows(&theta);
        assert_eq!(
            (r.len(), j.nrows(), j.ncols()),
            (SPLINE_KNOTS, SPLINE_KNOTS, theta.len())
        );
        // coefficient of basis function m sits at θ index 4 + (15 − m)
        let c = |m: usize| theta[4 + (SPLINE_KNOTS - 1 - (m % SPLINE_KNOTS))];
        for m in 0..SPLINE_KNOTS {
            let want = 2.0 * (c(m + SPLINE_KNOTS - 1) - 2.0 * c(m) + c(m + 1));
            assert!((r[m] - want).abs() < 1e-12, "{m}: {} {want}", r[m]);
            let jr: f64 = (0..theta.len()).map(|k| j[(m, k)] * theta[k]).sum();
            assert!((jr - r[m]).abs() < 1e-12, "{m}");
        }
        let mut flat = theta.clone();
        flat[4..].iter_mut().for_each(|v| *v = 7.0);
        assert!(model.penalty_rows(&flat).0.iter().all(|v| v.abs() < 1e-12));
    }

    /// A ring-down of the base model at θ = (ζ, η, −g, gΔ) from β = 1.2 rad, 200 frames at 50
    /// per second, camera noise 0.01 rad (seed 5), and its four windows of 50 frames.
    fn ringdown(theta: &[f64]) -> (Vec<CleanRun>, Vec<Win>) {
        let n = 200;
        let t: Vec<f64> = (0..n).map(|k| k as f64 / 50.0).collect();
        let run = |beta: Vec<f64>| CleanRun::test_ringdown(t.clone(), beta, 0.02);
        let quiet = [run(vec![0.0; n])];
        let terms = super::super::regression::BASE_TERMS.to_vec();
        let model = SimModel::of_terms(&quiet, Geometry::new(0.5, 0.5), terms, 1e-8);
        let whole = Win::whole(0, n);
        let sys = model.system(theta, &whole);
        let clean = window_residuals(&sys, &t, &vec![0.0; n], &whole.keep, 1.0, [1.2, 0.0], 1e-8)
            .expect("the ring-down simulates");
        let e = noise(n, 5);
        let beta: Vec<f64> = clean.iter().zip(&e).map(|(b, e)| b + 0.01 * e).collect();
        let wins = (0..4)
            .map(|k| Win {
                lo: 50 * k,
                hi: 50 * k + 50,
                keep: vec![true; 50],
                ..Win::whole(0, 50)
            })
            .collect();
        (vec![run(beta)], wins)
    }

    /// A curve's forward-differenced columns ([`CurveColumns::Forward`]) are as accurate as central
    /// differences: a torque curve in β on the ring-down's windows (the coefficients of the angles
    /// it passes have columns several σ long), both against central differences of simulations
    /// 10⁴ times tighter. Both carry the integration error divided by the step (measured: 0.5 % of
    /// the columns' length for central, 5 % more for forward); the forward quotients' own
    /// truncation error must add at most a quarter to it. The other columns are the same central
    /// quotients bit for bit.
    #[test]
    fn forward_curve_columns_match_central_differences() {
        use crate::model::recorded::spline::{SplineKind, SPLINE_KNOTS};
        let base = [1.0, 5.0, -295.0, 59.0];
        let (runs, wins) = ringdown(&base);
        let mut terms = super::super::regression::BASE_TERMS.to_vec();
        let mut theta = base.to_vec();
        for j in 0..SPLINE_KNOTS as u8 {
            terms.push(Term::Spline(SplineKind::Torque, j));
            theta.push(3.0 * (0.7 * j as f64).sin());
        }
        let geo = Geometry::new(0.5, 0.5);
        // the windows' states of the base model (the curve moves the ring-down by far more than
        // the noise: its windows are differenced from the states that follow the recording)
        let plain = SimModel::of_terms(
            &runs,
            geo,
            super::super::regression::BASE_TERMS.to_vec(),
            1e-8,
        );
        let all: Vec<usize> = (0..wins.len()).collect();
        let states: Vec<[f64; 2]> = followed_windows(&plain, &base, &wins, &all)
            .into_iter()
            .map(|s| s.expect("the base model follows the ring-down"))
            .collect();
        let used: Vec<(usize, usize)> = (0..wins.len()).map(|k| (k, 50 * k)).collect();
        let jac = |tol, curves| {
            let model = SimModel::of_terms(&runs, geo, terms.clone(), tol);
            let how = Differences {
                curves,
                ..Differences::REFIT
            };
            varpro_jacobian(&model, &theta, &wins, &used, &states, 200, how)
        };
        let fwd = jac(1e-8, CurveColumns::Forward);
        let cen = jac(1e-8, CurveColumns::Central);
        let exact = jac(1e-12, CurveColumns::Central);
        let (mut err_fwd, mut err_cen, mut seen) = (0.0, 0.0, 0);
        for c in 0..theta.len() {
            let (a, b) = (fwd.column(c), cen.column(c));
            if c < 4 || b.norm() == 0.0 {
                // the base columns, and the basis functions the ring-down never reaches
                assert_eq!(a, b, "column {c}");
                continue;
            }
            seen += usize::from(b.norm() > 1.0);
            err_fwd += (a - exact.column(c)).norm_squared();
            err_cen += (b - exact.column(c)).norm_squared();
        }
        let (err_fwd, err_cen) = (err_fwd.sqrt(), err_cen.sqrt());
        let scale = exact.columns(4, SPLINE_KNOTS).norm();
        assert!(seen >= 4, "{seen} curve columns longer than 1");
        eprintln!("curve columns' error (σ units, of {scale:.2}): forward {err_fwd:.2e}, central {err_cen:.2e}");
        assert!(err_cen < 1e-2 * scale && err_fwd <= 1.25 * err_cen);
    }

    /// The searches a refit shares ([`StartSearches`]) are consulted: a window marked as not
    /// followed at the start is left out; with genuine entries (those of a refit on every second
    /// window, as a screening makes them) the shared refit on all windows is the plain one bit
    /// for bit, and it adds only the windows not searched before.
    #[test]
    fn shared_start_searches_are_the_refits_own() {
        let truth = [1.0, 5.0, -295.0, 59.0];
        let (runs, wins) = ringdown(&truth);
        let terms = super::super::regression::BASE_TERMS.to_vec();
        let model = SimModel::of_terms(&runs, Geometry::new(0.5, 0.5), terms, 1e-8);
        let theta0 = [1.1, 4.5, -300.0, 60.0];
        let opts = ShootingOptions::default();
        let plain = refit(&model, &theta0, &wins, &opts).expect("the plain refit");
        assert_eq!(plain.used.len(), 4, "the start follows every window");
        let bits: Vec<u64> = theta0.iter().map(|v| v.to_bits()).collect();
        // a window marked as not followed at θ₀ is not used
        let marked = StartSearches::default();
        marked.found.lock().unwrap().insert((bits, 0, 0, 50), None);
        let f = refit_sharing(&model, &theta0, &wins, &opts, Some(&marked)).expect("the refit");
        assert!(f.used.iter().all(|&(w, _)| w != 0), "{:?}", f.used);
        // genuine entries from every second window, then the refit on all of them
        let shared = StartSearches::default();
        let half = [wins[0].clone(), wins[2].clone()];
        refit_sharing(&model, &theta0, &half, &opts, Some(&shared)).expect("the half refit");
        assert_eq!(shared.found.lock().unwrap().len(), 2);
        let f = refit_sharing(&model, &theta0, &wins, &opts, Some(&shared)).expect("the refit");
        assert_eq!(shared.found.lock().unwrap().len(), 4);
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&f.theta), bits(&plain.theta));
        assert_eq!(f.used, plain.used);
        assert_eq!(f.states, plain.states);
        // and the refit moves to the ring-down's damping and friction (within 2 %; the locked
        // input at α = 0 leaves the coupling's −g column unseen, held at its start)
        for k in [0, 1] {
            assert!(
                (plain.theta[k] / truth[k] - 1.0).abs() < 0.02,
                "{:?}",
                plain.theta
            );
        }
    }

    /// The leave-fold-out step of a fit linear in θ is the exact refit without the fold (the
    /// independent check: least squares on the kept rows alone), and a parameter the rows do not
    /// determine stays at its fitted value: a zero column (a friction term never active in these
    /// windows) and a column that another parameter's trade-off makes dependent.
    #[test]
    fn the_leave_fold_out_step_is_the_refit_and_holds_unseen_parameters() {
        // 3 windows of 8 rows on runs 0, 1, 2; y = 0.5 + 2t + noise; columns 1, t, 0, 1 + t
        let (nw, len) = (3, 8);
        let wins: Vec<Win> = (0..nw).map(|k| Win::whole(k, len)).collect();
        let e = noise(nw * len, 3);
        let t = |i: usize| (i % len) as f64 / len as f64 + (i / len) as f64;
        let y: Vec<f64> = (0..nw * len)
            .map(|i| 0.5 + 2.0 * t(i) + 0.1 * e[i])
            .collect();
        let x = DMatrix::from_fn(nw * len, 4, |i, c| [1.0, t(i), 0.0, 1.0 + t(i)][c]);
        // residuals (model − data) at θ: the fit stopped anywhere; the step of a linear model
        // from there is its exact refit
        let theta = vec![0.1, -0.3, 7.0, 0.2];
        let resid: Vec<f64> = (0..nw * len)
            .map(|i| (0..4).map(|c| x[(i, c)] * theta[c]).sum::<f64>() - y[i])
            .collect();
        let fit = SimFit::of_windows(theta.clone(), x.clone(), resid, len);
        let without = fit.step_without(&wins, |run| run == 1).unwrap();
        let rows: Vec<usize> = (0..nw * len).filter(|i| i / len != 1).collect();
        let a = Mat::from_fn(rows.len(), 2, |k, c| x[(rows[k], c)]);
        let b: Vec<f64> = rows.iter().map(|&i| y[i]).collect();
        let direct = crate::numerics::least_squares::lstsq(&a, &b, DEFAULT_RCOND).unwrap();
        for i in 0..nw * len {
            let refit = direct.x[0] + direct.x[1] * t(i);
            let step: f64 = (0..4).map(|c| x[(i, c)] * without[c]).sum();
            assert!((step - refit).abs() < 1e-12, "row {i}: {step} vs {refit}");
        }
        // the zero column is held, and of the three dependent ones one is held (the
        // factorisation's pivoting decides which)
        assert_eq!(without[2], 7.0, "{without:?}");
        let held = [0, 1, 3]
            .iter()
            .filter(|&&c| without[c] == theta[c])
            .count();
        assert_eq!(held, 1, "{without:?}");
    }

    #[test]
    fn gross_outliers_are_spikes_not_a_smooth_misfit() {
        // a smooth misfit of up to 12σ (a missing constant acceleration after the fitted initial
        // state: a parabola), white noise, and outlier frames of 30σ (next to an end), 40σ and −25σ
        // (at the other end)
        let n = 30;
        let t: Vec<f64> = (0..n).map(|k| k as f64 * 0.01).collect();
        let e = noise(n, 7);
        let mut r: Vec<f64> = (0..n)
            .map(|k| {
                let u = k as f64 / (n - 1) as f64;
                12.0 * 6.0 * (u * u - u + 1.0 / 6.0) + e[k]
            })
            .collect();
        assert!(r.iter().filter(|x| x.abs() > OUTLIER_SIGMA).count() >= 8);
        r[11] += 40.0;
        r[n - 1] -= 25.0;
        r[1] += 30.0;
        let keep = gross_outliers(&t, &r);
        let masked: Vec<usize> = (0..n).filter(|&k| !keep[k]).collect();
        assert_eq!(masked, vec![1, 11, n - 1]);
        // white noise alone: nothing masked in 200 windows (P(|z| > 5) = 5.7e-7 per frame)
        for seed in 0..200 {
            let r = noise(n, 100 + seed);
            assert!(gross_outliers(&t, &r).iter().all(|&k| k));
        }
    }
}
