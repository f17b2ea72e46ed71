//! Short-horizon prediction: the check in angle units. Each run is cut into windows of a few dozen
//! samples; in each window the initial state (β, β̇) is fitted (Levenberg–Marquardt) with the model
//! held fixed and the model is simulated with the exact Filippov integrator over the window. The
//! rms of β_measured − β_simulated (rad) measures how well the model predicts the motion over a
//! horizon short enough for chaos not to matter; with a perfect model it is the camera noise.

use super::lm::{
    fd_jacobian, gauss_newton_cov, least_squares_tol, least_squares_with_jacobian, LsqFit,
};
use super::model::{AugmentedGear, Coefficients, Geometry, InputBend};
use super::preprocess::CleanRun;
use crate::integrator::{EventDriven853, Flow, FlowMethod, FlowOptions, Sensitivity};
use crate::numerics::least_squares::{lstsq, DEFAULT_RCOND};
use faer::Mat;
use nalgebra::DMatrix;
use std::cell::RefCell;
use std::sync::atomic::{AtomicU64, Ordering};

/// Samples per prediction window (at most).
pub const WINDOW: usize = 30;
/// Longest prediction horizon, s (unless that leaves fewer than 8 samples).
pub const HORIZON: f64 = 0.4;

/// Prediction residuals of one run.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Prediction {
    /// Times of the predicted samples.
    pub t: Vec<f64>,
    /// Simulated β.
    pub beta: Vec<f64>,
    /// Measured − simulated.
    pub resid: Vec<f64>,
    /// rms of the residuals, rad (degrees of freedom of the fitted initial states removed).
    pub rms: f64,
    /// Frames rejected as outliers (beyond 5σ of the camera noise).
    pub rejected: usize,
}

/// The prediction windows of a run as index ranges [i, j): at most [`WINDOW`] samples and
/// [`HORIZON`] seconds (but at least 8 samples), cut at gaps, windows shorter than 8 dropped.
pub fn prediction_windows(r: &CleanRun) -> Vec<(usize, usize)> {
    let n = r.t.len();
    let mut out = Vec::new();
    let mut i = 0;
    while i + 8 <= n {
        let mut j = (i + WINDOW).min(n);
        // a short horizon in time as well (chaos), but at least 8 samples
        while j > i + 8 && r.t[j - 1] - r.t[i] > HORIZON {
            j -= 1;
        }
        // no large gap inside a window
        if let Some(k) = (i..j - 1).find(|&k| r.t[k + 1] - r.t[k] > 2.5 * r.dt) {
            j = k + 1;
        }
        if j - i >= 8 {
            out.push((i, j));
        }
        i = j;
    }
    out
}

/// The model of window [i, j) of run `r`: its recorded input `input` ([`RecordedInput::fit`] of
/// the window; a β recorded `latency` late), and a lost-step input offset taken at the window's
/// middle.
pub fn window_system(
    r: &CleanRun,
    c: &Coefficients,
    geo: &Geometry,
    latency: f64,
    (i, j): (usize, usize),
    input: &RecordedInput,
) -> AugmentedGear {
    let mut cw = *c;
    if c.alpha_offset_per_turn != 0.0 {
        let tm = 0.5 * (r.t[i] + r.t[j - 1]);
        cw.alpha_offset +=
            c.alpha_offset_per_turn * r.alpha_rate.abs() * (tm - r.t[0]) / std::f64::consts::TAU;
    }
    let (alpha0, alpha_rate, bend) = input.drive(latency);
    AugmentedGear {
        c: cw,
        geo: *geo,
        alpha0,
        alpha_rate,
        bend,
    }
}

/// The input of window [i, j) of run `r` as the model's α(t) = α₀ + α̇ t + bend, for a β
/// recorded `latency` late: [`RecordedInput::fit`], then [`RecordedInput::drive`].
pub fn window_input(r: &CleanRun, latency: f64, i: usize, j: usize) -> (f64, f64, InputBend) {
    RecordedInput::fit(r, i, j).drive(latency)
}

/// The recorded input over a window, fitted once (it does not depend on the model; a latency
/// only moves the time axis, [`RecordedInput::drive`]). A driven run's recorded α over the window
/// is fitted by a polynomial of degree 5 in time (least squares by column-pivoted QR, centred on
/// the window), so a drive whose speed is not uniform (a motor's speed ripple, a frequency off
/// its stated value) is followed as recorded; a uniform drive is its own polynomial. Ring-downs,
/// windows of fewer than 8 samples and a failed fit: the line through the window's first
/// recorded α at the stated rate. `Default`: the line α = 0 at rest.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RecordedInput {
    /// The window's first sample (t_i, α_i) and the stated rate α̇_s.
    anchor: (f64, f64, f64),
    /// Centre t_c and half-width h of the window, s (h = 0: the line).
    t_c: f64,
    h: f64,
    /// Coefficients c_p of the departure from the line, Σ c_p s^p with s = (τ − t_c)/h.
    c: [f64; 6],
}

impl RecordedInput {
    /// The fit over samples [i, j) of run `r` (see the type).
    pub fn fit(r: &CleanRun, i: usize, j: usize) -> Self {
        const DEGREE: usize = 5;
        let line = Self {
            anchor: (r.t[i], r.alpha[i], r.alpha_rate),
            ..Self::default()
        };
        let j = j.min(r.t.len());
        if r.ringdown || j < i + DEGREE + 3 {
            return line;
        }
        // the departure from the stated line through the first sample, in a scaled time s ∈ [−1, 1]
        let (t_c, h) = (0.5 * (r.t[i] + r.t[j - 1]), 0.5 * (r.t[j - 1] - r.t[i]));
        if h.is_nan() || h <= 0.0 {
            return line;
        }
        let a = Mat::from_fn(j - i, DEGREE + 1, |k, p| {
            ((r.t[i + k] - t_c) / h).powi(p as i32)
        });
        let y: Vec<f64> = (i..j)
            .map(|k| r.alpha[k] - r.alpha[i] - r.alpha_rate * (r.t[k] - r.t[i]))
            .collect();
        match lstsq(&a, &y, DEFAULT_RCOND) {
            Ok(fit) => Self {
                t_c,
                h,
                c: std::array::from_fn(|p| fit.x[p]),
                ..line
            },
            Err(_) => line,
        }
    }

    /// The model's input (α₀, α̇, bend) for a β recorded `latency` late: α at model time t is the
    /// recorded α at t − latency, α_rec(τ) = α_i + α̇_s (τ − t_i) + Σ c_p s^p.
    pub fn drive(&self, latency: f64) -> (f64, f64, InputBend) {
        let (t_i, alpha_i, rate_s) = self.anchor;
        let (c, h) = (&self.c, self.h);
        if h == 0.0 {
            return (
                alpha_i - rate_s * (t_i + latency),
                rate_s,
                InputBend::default(),
            );
        }
        let rate = rate_s + c[1] / h;
        let alpha0 = alpha_i - rate_s * (latency + t_i) + c[0] - c[1] / h * (latency + self.t_c);
        let bend = InputBend {
            t_c: self.t_c + latency,
            a: [2, 3, 4, 5].map(|p| c[p] / h.powi(p as i32)),
        };
        (alpha0, rate, bend)
    }
}

/// Window simulations run by this process (all threads): the unit of work of the diagnosis,
/// a load-independent measure of its cost.
static SIMULATIONS: AtomicU64 = AtomicU64::new(0);

/// Integration steps (accepted and rejected) of the window simulations, and the simulations
/// stopped by the step budget [`WINDOW_MAX_STEPS`].
static STEPS: AtomicU64 = AtomicU64::new(0);
static OVER_BUDGET: AtomicU64 = AtomicU64::new(0);

/// The number of window simulations ([`simulate`]) run so far by this process.
pub fn simulations() -> u64 {
    SIMULATIONS.load(Ordering::Relaxed)
}

/// The integration steps of the finished window simulations so far (accepted and rejected), and
/// the simulations stopped by the step budget [`WINDOW_MAX_STEPS`] (all threads).
pub fn simulation_steps() -> (u64, u64) {
    (
        STEPS.load(Ordering::Relaxed),
        OVER_BUDGET.load(Ordering::Relaxed),
    )
}

/// Most integration steps (accepted and rejected) of one window simulation. A window lasts at
/// most [`HORIZON`] (or [`WINDOW`] samples); a model that follows the data is simulated over it
/// at the default tolerance ([`super::diagnose::DiagnoseOptions::tol`], 1e-8) in about 40 steps of
/// DP5 (mean over the base model's windows of a campaign set, `gearbif diagnose --timing`), so the
/// budget was set at 50 times that; with DOP853 (see [`simulate`]) the mean over all window
/// simulations of a diagnosis is 16 steps (the `latency9` set of
/// `scripts/independent_recordings.py`, seed 5), and the budget is kept. A trial model whose motion runs
/// away inside a window (an extrapolated drift with a negative damping, a torque harmonic driven
/// far off by a leave-fold-out step) would otherwise shrink its steps without bound and hold the
/// diagnosis for minutes; with the budget its simulation fails, and the judge counts the window
/// as that model's loss ([`super::judge::compare`]). The same budget holds for the simulations
/// with the variational equations ([`simulate_with_jacobian`]), whose step control also holds the
/// Jacobian columns' error: 19–22 steps per window simulation on average against 16 (the full-size
/// `torque_and_latency` set of docs/performance.md), far inside it.
pub const WINDOW_MAX_STEPS: usize = 2_000;

/// β of `sys` from the state `x0` at `t0`, at `times` (exact Filippov flow of eq. `model`,
/// relative tolerance `tol`: [`super::diagnose::DiagnoseOptions::tol`]); `None` when the flow
/// fails or needs more than [`WINDOW_MAX_STEPS`] steps. The integrator is the event-driven
/// Dormand–Prince 8(5,3) ([`EventDriven853`]: the same events and stick phases as DP5, 16 instead
/// of 52 steps per window simulation on average; docs/performance.md, "Identification and
/// diagnosis").
pub fn simulate(
    sys: &AugmentedGear,
    t0: f64,
    x0: [f64; 2],
    times: &[f64],
    tol: f64,
) -> Option<Vec<f64>> {
    let f = window_flow(sys, t0, x0, times, tol, Sensitivity::None)?;
    Some(f.samples.iter().map(|s| s.beta).collect())
}

/// [`simulate`] with the derivative of each simulated β with respect to the initial state,
/// ∂β(tᵢ)/∂(β₀, β̇₀) (the variational equations and the saltation matrices of the events:
/// [`crate::integrator::Flow::sample_jacobians`]).
pub fn simulate_with_jacobian(
    sys: &AugmentedGear,
    t0: f64,
    x0: [f64; 2],
    times: &[f64],
    tol: f64,
) -> Option<(Vec<f64>, Vec<[f64; 2]>)> {
    let f = state_flow(sys, t0, x0, times, tol)?;
    Some((
        f.samples.iter().map(|s| s.beta).collect(),
        beta_jacobians(&f),
    ))
}

/// A window's simulated samples ([`simulate_states`]).
#[derive(Debug, Clone)]
pub struct WindowStates {
    /// (β, β̇) at the sample times (β̇ = 0 exactly in a stick phase, the Filippov stick mode).
    pub states: Vec<(f64, f64)>,
    /// ∂β(tᵢ)/∂(β₀, β̇₀).
    pub jac: Vec<[f64; 2]>,
}

/// [`simulate_with_jacobian`] with the simulated velocities: the states (β, β̇) of `sys` from
/// `x0` at `t0`, at `times`, with ∂β(tᵢ)/∂(β₀, β̇₀).
pub fn simulate_states(
    sys: &AugmentedGear,
    t0: f64,
    x0: [f64; 2],
    times: &[f64],
    tol: f64,
) -> Option<WindowStates> {
    let f = state_flow(sys, t0, x0, times, tol)?;
    Some(WindowStates {
        states: f.samples.iter().map(|s| (s.beta, s.omega)).collect(),
        jac: beta_jacobians(&f),
    })
}

/// The window's flow with the variational equations ([`window_flow`]), `None` also when a
/// sample's Jacobian is missing.
fn state_flow(sys: &AugmentedGear, t0: f64, x0: [f64; 2], times: &[f64], tol: f64) -> Option<Flow> {
    let f = window_flow(sys, t0, x0, times, tol, Sensitivity::State)?;
    (f.sample_jacobians.len() == times.len()).then_some(f)
}

/// The β rows of the flow's sample Jacobians, ∂β(tᵢ)/∂(β₀, β̇₀).
fn beta_jacobians(f: &Flow) -> Vec<[f64; 2]> {
    f.sample_jacobians
        .iter()
        .map(|j| [j[(0, 0)], j[(0, 1)]])
        .collect()
}

/// The window's flow with the samples at `times` (counted in [`simulations`] and
/// [`simulation_steps`]); `None` when it fails, needs more than [`WINDOW_MAX_STEPS`] steps or
/// misses a sample.
fn window_flow(
    sys: &AugmentedGear,
    t0: f64,
    x0: [f64; 2],
    times: &[f64],
    tol: f64,
    sensitivity: Sensitivity,
) -> Option<Flow> {
    SIMULATIONS.fetch_add(1, Ordering::Relaxed);
    let t1 = *times.last()?;
    let mut opts = FlowOptions::with_tol(tol)
        .samples(times.to_vec())
        .sensitivity(sensitivity);
    opts.max_steps = WINDOW_MAX_STEPS;
    let f = match EventDriven853.flow(sys, t0, x0, t1, &opts) {
        Ok(f) => f,
        Err(e) => {
            if matches!(e, crate::error::Error::StepBudget { .. }) {
                OVER_BUDGET.fetch_add(1, Ordering::Relaxed);
                STEPS.fetch_add(WINDOW_MAX_STEPS as u64, Ordering::Relaxed);
            }
            return None;
        }
    };
    STEPS.fetch_add((f.stats.steps + f.stats.rejected) as u64, Ordering::Relaxed);
    (f.samples.len() == times.len()).then_some(f)
}

/// (β_sim − β)/σ of a window simulated from the state `x0` at its first sample (tolerance `tol`);
/// 0 on masked samples.
pub fn window_residuals(
    sys: &AugmentedGear,
    t: &[f64],
    b: &[f64],
    keep: &[bool],
    sigma: f64,
    x0: [f64; 2],
    tol: f64,
) -> Option<Vec<f64>> {
    let s = simulate(sys, t[0], x0, t, tol)?;
    Some(
        s.iter()
            .zip(b)
            .zip(keep)
            .map(|((s, m), &k)| if k { (s - m) / sigma } else { 0.0 })
            .collect(),
    )
}

/// [`window_residuals`] and their Jacobian with respect to `x0` (rows: samples; 0 on masked
/// samples), from one simulation with the variational equations ([`simulate_with_jacobian`]).
pub fn window_residuals_jacobian(
    sys: &AugmentedGear,
    t: &[f64],
    b: &[f64],
    keep: &[bool],
    sigma: f64,
    x0: [f64; 2],
    tol: f64,
) -> Option<(Vec<f64>, DMatrix<f64>)> {
    let (s, jac) = simulate_with_jacobian(sys, t[0], x0, t, tol)?;
    let mut j = DMatrix::zeros(t.len(), 2);
    let mut r = vec![0.0; t.len()];
    for i in 0..t.len() {
        if keep[i] {
            r[i] = (s[i] - b[i]) / sigma;
            j[(i, 0)] = jac[i][0] / sigma;
            j[(i, 1)] = jac[i][1] / sigma;
        }
    }
    Some((r, j))
}

/// Evaluation budget of a window's state fit ([`fit_window_state`]) per start, in units of
/// (parameters + 1) = 3 residual evaluations.
const STATE_FIT_PATIENCE: usize = 20;
/// Relative tolerances (ftol on the reduction of χ², xtol on the step) of a window's state fit
/// ([`fit_window_state`]). A window simulated at the relative tolerance 10⁻⁸ carries an
/// integration error in every residual that makes reductions of χ² below ~10⁻¹⁰ of it noise; with
/// the optimiser's own default (30 ε) the fits shrank their trust region through that noise (the
/// `cubic_drag` set of docs/performance.md: 3.09 million window simulations in the diagnosis with
/// the default, 2.30 million with these).
const STATE_FIT_TOL: (f64, f64) = (1e-10, 1e-10);
/// Relative central-difference steps (of max(|x|, 1)) of a window's state fit by differences
/// ([`fit_window_state`]: β₀, β̇₀).
const FD_STATE_STEP: [f64; 2] = [1e-7, 1e-6];

/// Whether a window state fit by the exact derivative stopped short of its minimum: the
/// Gauss–Newton step of the central-difference Jacobian J_h at the fit's end (steps
/// [`FD_STATE_STEP`]) predicts a decrease of χ² by more than 1, ‖r‖² − min_δ ‖r + J_h δ‖² > 1
/// (one standard error of a state coordinate; also when J_h cannot be formed), over the columns
/// J_h determines ([`gauss_newton_cov`]: a window at rest throughout does not see β̇₀).
///
/// The exact derivative of the flow holds for perturbations below the distance to the nearest
/// change of the event sequence. Near an arrival at Σ where the acceleration is a hair from the
/// static bound r_s (the end of a ring-down), that distance falls far below a
/// Levenberg–Marquardt step (a crossing with a post-crossing acceleration of 10⁻¹¹ rad/s²
/// against a difference quotient at 10⁻⁶ that sees the motion stop), and the exact fit stalls
/// (χ² 563 against 95 on a 30-frame window); a difference quotient over the step sees the change.
fn stalled<F: Fn(&[f64]) -> Option<Vec<f64>>>(plain: &F, fit: &LsqFit) -> bool {
    let Some(jh) = fd_jacobian(plain, &fit.p, &fit.resid, &FD_STATE_STEP, false) else {
        return true;
    };
    // the decrease of the Gauss–Newton step, gᵀ (JᵀJ)⁻¹ g with g = Jᵀr; a column J does not
    // determine (β̇₀ of a window at rest) has an infinite variance there and adds nothing
    let g = jh.tr_mul(&nalgebra::DVector::from_column_slice(&fit.resid));
    let c = gauss_newton_cov(&jh);
    let mut decrease = 0.0;
    for a in 0..g.len() {
        for b in 0..g.len() {
            if c[(a, b)].is_finite() {
                decrease += g[a] * c[(a, b)] * g[b];
            }
        }
    }
    !decrease.is_finite() || decrease > 1.0
}

/// Fits a window's initial state with the model fixed, from `guess` and, when that fit is poor,
/// from finite-difference and at-rest velocities. Residuals are (β_sim − β)/σ on kept samples;
/// the window is simulated at the relative tolerance `tol`. The Levenberg–Marquardt steps use the
/// exact derivative of the simulated window, ∂β(tᵢ)/∂(β₀, β̇₀) ([`window_residuals_jacobian`]).
/// Where a start's fit stays poor (χ² > 4 per frame), the central-difference derivative at its
/// end is asked whether the fit stalled ([`stalled`]); only then is it fitted on by central
/// differences from there, and the better of the two is kept.
#[allow(clippy::too_many_arguments)]
pub fn fit_window_state(
    sys: &AugmentedGear,
    t: &[f64],
    b: &[f64],
    keep: &[bool],
    sigma: f64,
    guess: [f64; 2],
    multi_start: bool,
    tol: f64,
) -> Option<LsqFit> {
    // every evaluation also gives the Jacobian (one simulation with the variational equations,
    // instead of four more by central differences); the optimiser asks for it at the last
    // point evaluated
    let last: RefCell<Option<([f64; 2], DMatrix<f64>)>> = RefCell::new(None);
    let f = |p: &[f64]| {
        let x = [p[0], p[1]];
        let (r, j) = window_residuals_jacobian(sys, t, b, keep, sigma, x, tol)?;
        *last.borrow_mut() = Some((x, j));
        Some(r)
    };
    let jac = |p: &[f64], _r: &[f64]| {
        let x = [p[0], p[1]];
        if let Some((at, j)) = last.borrow().as_ref() {
            if *at == x {
                return Some(j.clone());
            }
        }
        window_residuals_jacobian(sys, t, b, keep, sigma, x, tol).map(|(_, j)| j)
    };
    let kept = keep.iter().filter(|&&k| k).count().max(1) as f64;
    let poor = |x: &Option<LsqFit>| x.as_ref().map(|f| f.rss / kept > 4.0).unwrap_or(true);
    let plain = |p: &[f64]| window_residuals(sys, t, b, keep, sigma, [p[0], p[1]], tol);
    let fit_from = |p0: [f64; 2]| {
        let exact =
            least_squares_with_jacobian(&f, &jac, &p0, STATE_FIT_PATIENCE, Some(STATE_FIT_TOL));
        if !poor(&exact) {
            return exact;
        }
        // a genuine poor minimum (the model does not follow the window) costs one differenced
        // Jacobian; a stall moves on by differences from where it stopped (from the start when
        // the exact fit failed)
        if let Some(a) = &exact {
            if !stalled(&plain, a) {
                return exact;
            }
        }
        let from = exact.as_ref().map_or(p0, |a| [a.p[0], a.p[1]]);
        let differenced = least_squares_tol(
            &plain,
            &from,
            &FD_STATE_STEP,
            STATE_FIT_PATIENCE,
            Some(STATE_FIT_TOL),
            false,
        );
        match (exact, differenced) {
            (Some(a), Some(d)) => Some(if d.rss < a.rss { d } else { a }),
            (a, d) => a.or(d),
        }
    };
    let mut fit = fit_from(guess);
    if multi_start && poor(&fit) {
        let fd = (b[1] - b[0]) / (t[1] - t[0]);
        for v0 in [fd, 0.0, 0.5 * fd, 2.0 * fd] {
            if let Some(f2) = fit_from([b[0], v0]) {
                if fit.as_ref().map(|f1| f2.rss < f1.rss).unwrap_or(true) {
                    fit = Some(f2);
                }
            }
            if !poor(&fit) {
                break;
            }
        }
    }
    fit
}

/// Predicts a cleaned run with the model `c` (and a sensor latency `latency`, s); the windows are
/// simulated at the relative tolerance `tol` ([`super::diagnose::DiagnoseOptions::tol`]).
pub fn predict(
    r: &CleanRun,
    c: &Coefficients,
    geo: &Geometry,
    latency: f64,
    tol: f64,
) -> Prediction {
    let mut out = Prediction::default();
    let mut ss = 0.0;
    let mut dof = 0usize;
    for (i, j) in prediction_windows(r) {
        let t = &r.t[i..j];
        let b = &r.beta[i..j];
        let sys = window_system(r, c, geo, latency, (i, j), &RecordedInput::fit(r, i, j));
        let sigma = r.sigma_camera.max(1e-12);
        let all = vec![true; t.len()];
        if let Some(mut fit) = fit_window_state(&sys, t, b, &all, sigma, [b[0], r.v[i]], true, tol)
        {
            // outlier frames the cleaning missed (coarse sampling): beyond 5σ of the camera noise,
            // dropped and the window refitted once without them
            let bad: Vec<bool> = fit.resid.iter().map(|x| x.abs() > 5.0).collect();
            let nbad = bad.iter().filter(|&&x| x).count();
            if nbad > 0 && nbad <= t.len() / 5 {
                let keep: Vec<bool> = bad.iter().map(|&o| !o).collect();
                if let Some(f2) =
                    fit_window_state(&sys, t, b, &keep, sigma, [fit.p[0], fit.p[1]], false, tol)
                {
                    fit = f2;
                }
            }
            // back to radians
            fit.resid.iter_mut().for_each(|x| *x *= sigma);
            let mut kept = 0usize;
            for k in 0..t.len() {
                if nbad <= t.len() / 5 && bad[k] {
                    out.rejected += 1;
                    continue;
                }
                out.t.push(t[k]);
                out.beta.push(b[k] + fit.resid[k]);
                out.resid.push(-fit.resid[k]);
                ss += fit.resid[k] * fit.resid[k];
                kept += 1;
            }
            dof += kept.saturating_sub(2);
        }
    }
    out.rms = if dof > 0 {
        (ss / dof as f64).sqrt()
    } else {
        f64::NAN
    };
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::TAU;

    /// A driven run at 1.5 Hz (50 samples per turn, 3 turns, β = 0) whose recorded input is
    /// `alpha(t)`.
    fn driven_run(alpha: impl Fn(f64) -> f64) -> CleanRun {
        let t: Vec<f64> = (0..150).map(|k| k as f64 / 75.0).collect();
        CleanRun {
            alpha: t.iter().map(|&x| alpha(x)).collect(),
            beta: vec![0.0; t.len()],
            v: vec![0.0; t.len()],
            t,
            dt: 1.0 / 75.0,
            outliers: 0,
            sigma_beta: 0.01,
            sigma_camera: 0.01,
            v_gain: 1.0,
            alpha_rate: TAU * 1.5,
            ringdown: false,
        }
    }

    /// The windows' input follows the recorded α: a uniform drive gives the line through the
    /// window's first sample at the stated rate (to rounding), here with a latency of 6 ms; a
    /// speed ripple α = Ωt + 0.15 sin Ωt is followed within the degree-5 polynomial's error over
    /// the window (three times the Chebyshev bound ε (Ωh)⁶/(2⁵ 6!)), where the line misses it by
    /// 0.15–0.22 rad.
    #[test]
    fn the_window_input_follows_the_recorded_drive() {
        let (omega, lat) = (TAU * 1.5, 0.006);
        let uniform = driven_run(|t| 0.4 + omega * t);
        let (a0, rate, bend) = window_input(&uniform, lat, 10, 40);
        assert!((a0 - (uniform.alpha[10] - omega * (uniform.t[10] + lat))).abs() < 1e-12);
        assert!((rate - omega).abs() < 1e-9 && bend.a.iter().all(|a| a.abs() < 1e-6));
        let ripple = driven_run(|t| omega * t + 0.15 * (omega * t).sin());
        for (i, j) in [(0, 30), (55, 85), (120, 130)] {
            let (alpha0, alpha_rate, bend) = window_input(&ripple, lat, i, j);
            let sys = AugmentedGear {
                c: Coefficients::default(),
                geo: Geometry::new(0.5, 0.5),
                alpha0,
                alpha_rate,
                bend,
            };
            let (mut worst, mut worst_line) = (0.0f64, 0.0f64);
            for k in i..j {
                let line = ripple.alpha[i] + omega * (ripple.t[k] - ripple.t[i]);
                worst = worst.max((sys.alpha(ripple.t[k] + lat) - ripple.alpha[k]).abs());
                worst_line = worst_line.max((line - ripple.alpha[k]).abs());
            }
            let h = 0.5 * (ripple.t[j - 1] - ripple.t[i]);
            let bound = 3.0 * 0.15 * (omega * h).powi(6) / (32.0 * 720.0);
            assert!(
                worst < bound && worst_line > 0.02,
                "[{i}, {j}): {worst} (bound {bound}), line {worst_line}"
            );
        }
    }

    /// A fit stopped where its residuals r(p) = A p − b still decrease (by more than 1 in χ²
    /// along the differenced Gauss–Newton step: 30 at a distance 1 in p₀ over 30 rows) has
    /// stalled; at the least-squares minimum, or 0.01 from it (a decrease of 0.003), it has not.
    #[test]
    fn a_stall_is_told_from_a_minimum_by_the_differenced_step() {
        let rows: Vec<([f64; 2], f64)> = (0..30)
            .map(|i| {
                let t = i as f64 / 29.0;
                ([1.0, t], 3.0 * (5.0 * t).sin())
            })
            .collect();
        let plain = |p: &[f64]| -> Option<Vec<f64>> {
            Some(
                rows.iter()
                    .map(|(a, b)| a[0] * p[0] + a[1] * p[1] - b)
                    .collect(),
            )
        };
        let fit_of = |f: &dyn Fn(&[f64]) -> Option<Vec<f64>>, p: [f64; 2]| {
            let resid = f(&p).unwrap();
            LsqFit {
                p: p.to_vec(),
                rss: resid.iter().map(|r| r * r).sum(),
                resid,
                cov: DMatrix::zeros(2, 2),
                converged: true,
                jac: DMatrix::zeros(30, 2),
            }
        };
        // the minimum by QR
        let a = Mat::from_fn(30, 2, |i, k| rows[i].0[k]);
        let b: Vec<f64> = rows.iter().map(|r| r.1).collect();
        let m = lstsq(&a, &b, DEFAULT_RCOND).unwrap().x;
        let fit_at = |p: [f64; 2]| fit_of(&plain, p);
        assert!(!stalled(&plain, &fit_at([m[0], m[1]])));
        assert!(!stalled(&plain, &fit_at([m[0] + 0.01, m[1]])));
        assert!(stalled(&plain, &fit_at([m[0] + 1.0, m[1]])));
        // a second coordinate the residuals do not see (β̇₀ of a window at rest): judged on the
        // first alone, not taken as a stall for its singular Jacobian
        let blind = |p: &[f64]| plain(&[p[0], m[1]]);
        assert!(!stalled(&blind, &fit_of(&blind, [m[0], 7.0])));
        assert!(stalled(&blind, &fit_of(&blind, [m[0] + 1.0, 7.0])));
    }
}
