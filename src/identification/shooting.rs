//! Refit by simulation: multiple shooting over short windows.
//!
//! The weak-form regression ([`super::regression`]) selects the terms and gives starting values,
//! but its quadrature on coarsely sampled runs carries a systematic error of its own (a few tenths
//! of a percent on g, more on terms with higher harmonics). The refit removes it: every run is cut
//! into the short prediction windows of [`super::predict`] (≤ 30 samples, ≤ 0.4 s: short enough
//! for chaos not to matter) and the model is simulated with the exact Filippov integrator over
//! each window. The window initial states (β, β̇) are nuisance parameters, profiled out (variable
//! projection: for every trial parameter vector θ each window's state is refitted, warm-started);
//! θ is fitted to the residuals (β_sim − β_meas)/σ_camera by Levenberg–Marquardt with a central
//! finite-difference Jacobian of the profiled residuals, whose Gauss–Newton covariance is then the
//! correct marginal covariance of θ. The residuals are close to white camera noise, so the
//! covariance needs only a small correction for their autocorrelation.
//!
//! θ is the coefficient vector of a weak-form fit ([`LinFit`]; every term, mapped per run by
//! [`coefficients_for_run`], dictionary terms through [`super::model::ExtraTerm`]) and optionally
//! the sensor latency.

use super::diagnose::coefficients_for_run;
use super::lm::least_squares_tol;
use super::model::{Geometry, MAX_EXTRA};
use super::predict::{fit_window_state, prediction_windows, window_residuals, window_system};
use super::preprocess::CleanRun;
use super::regression::{autocorr_time, Design, LinFit, Term};
use nalgebra::DMatrix;
use std::sync::Mutex;

/// Options of the refit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShootingOptions {
    /// Most windows used (spread evenly over the runs; fewer windows, faster and noisier).
    pub max_windows: usize,
    /// Outer Levenberg–Marquardt patience (evaluations ≈ patience × (parameters + 1)).
    pub patience: usize,
}

impl Default for ShootingOptions {
    fn default() -> Self {
        Self {
            max_windows: 240,
            patience: 3,
        }
    }
}

/// Result of a refit by simulation.
#[derive(Debug, Clone, PartialEq)]
pub struct SimRefit {
    /// Coefficients in the order of the weak-form fit's columns.
    pub coef: Vec<f64>,
    /// Their 1σ uncertainties.
    pub err: Vec<f64>,
    /// Latency and its 1σ, s, when fitted.
    pub latency: Option<(f64, f64)>,
    /// rms of the window residuals at the solution, rad.
    pub rms_rad: f64,
    /// rms of the window residuals at the start (the weak-form coefficients), rad.
    pub rms_start_rad: f64,
    /// Windows used.
    pub windows: usize,
    /// Samples used.
    pub samples: usize,
    /// Covariance inflation n/n_eff from the residual autocorrelation.
    pub inflation: f64,
    /// Whether the optimiser reported convergence.
    pub converged: bool,
}

struct Window {
    run: usize,
    lo: usize,
    hi: usize,
    keep: Vec<bool>,
}

/// Whether every column of `f` has a simulation form: dictionary terms do, up to
/// [`MAX_EXTRA`] of them.
pub fn simulable(d: &Design, f: &LinFit) -> bool {
    f.cols
        .iter()
        .filter(|&&c| {
            matches!(
                d.terms[c],
                Term::Cos(..)
                    | Term::Sin(..)
                    | Term::VCosB
                    | Term::VSinB
                    | Term::SCosB
                    | Term::SSinB
            )
        })
        .count()
        <= MAX_EXTRA
}

/// Refits a window's state from the warm start `x` by Gauss–Newton steps (forward-difference
/// Jacobian, 2×2 normal equations): the projection step of variable projection, a few sims
/// instead of a full optimiser run. Falls back to [`fit_state`] when the result is poor (a stick
/// or slip branch change) or a step fails. Returns (residuals, state).
fn project_state(
    sys: &super::model::AugmentedGear,
    t: &[f64],
    b: &[f64],
    keep: &[bool],
    sigma: f64,
    x: [f64; 2],
) -> Option<(Vec<f64>, [f64; 2])> {
    let resid = |p: [f64; 2]| window_residuals(sys, t, b, keep, sigma, p);
    let rss = |r: &[f64]| r.iter().map(|v| v * v).sum::<f64>();
    let gn = || -> Option<(Vec<f64>, [f64; 2])> {
        let mut x = x;
        let mut r = resid(x)?;
        let mut e = rss(&r);
        for _ in 0..4 {
            let h = [1e-7 * (1.0 + x[0].abs()), 1e-6 * (1.0 + x[1].abs())];
            let r0 = resid([x[0] + h[0], x[1]])?;
            let r1 = resid([x[0], x[1] + h[1]])?;
            let (mut a00, mut a01, mut a11, mut g0, mut g1) = (0.0, 0.0, 0.0, 0.0, 0.0);
            for k in 0..r.len() {
                let j0 = (r0[k] - r[k]) / h[0];
                let j1 = (r1[k] - r[k]) / h[1];
                a00 += j0 * j0;
                a01 += j0 * j1;
                a11 += j1 * j1;
                g0 += j0 * r[k];
                g1 += j1 * r[k];
            }
            let det = a00 * a11 - a01 * a01;
            if !(det.is_finite() && det > 1e-14 * a00 * a11) {
                return None;
            }
            let dx = [-(a11 * g0 - a01 * g1) / det, -(a00 * g1 - a01 * g0) / det];
            let xn = [x[0] + dx[0], x[1] + dx[1]];
            let rn = resid(xn)?;
            let en = rss(&rn);
            if en > e {
                break;
            }
            let small =
                dx[0].abs() < 1e-10 * (1.0 + x[0].abs()) && dx[1].abs() < 1e-9 * (1.0 + x[1].abs());
            let converged = e - en <= 1e-10 * e.max(1e-300);
            x = xn;
            r = rn;
            e = en;
            if small || converged {
                break;
            }
        }
        Some((r, x))
    };
    gn().or_else(|| {
        let f = fit_window_state(sys, t, b, keep, sigma, x, true)?;
        Some((f.resid, [f.p[0], f.p[1]]))
    })
}

fn par_map<T: Send, F: Fn(usize) -> T + Sync + Send>(n: usize, f: F) -> Vec<T> {
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

/// Refits the coefficients of `fit` (and the latency when `fit_latency`) by multiple shooting
/// over short windows of `runs`. `None` when the model has no simulation form (dictionary
/// terms), no window can be fitted, or the optimiser cannot evaluate the start.
pub fn refit_by_simulation(
    d: &Design,
    fit: &LinFit,
    runs: &[CleanRun],
    geo: &Geometry,
    latency: f64,
    fit_latency: bool,
    opts: &ShootingOptions,
) -> Option<SimRefit> {
    if !simulable(d, fit) {
        return None;
    }
    // windows, evenly thinned to at most max_windows
    let all: Vec<(usize, usize, usize)> = runs
        .iter()
        .enumerate()
        .flat_map(|(ri, r)| {
            prediction_windows(r)
                .into_iter()
                .map(move |(i, j)| (ri, i, j))
        })
        .collect();
    if all.is_empty() {
        return None;
    }
    let stride = all.len().div_ceil(opts.max_windows.max(1));
    let chosen: Vec<(usize, usize, usize)> = all.into_iter().step_by(stride).collect();
    let coef_for = |theta: &[f64], run: usize| coefficients_for_run(d, fit, theta, runs, run);
    let lat_of = |theta: &[f64]| {
        if fit_latency {
            theta[fit.coef.len()]
        } else {
            latency
        }
    };
    let mut theta0 = fit.coef.clone();
    if fit_latency {
        theta0.push(latency);
    }
    // start: fit every window's state at θ0, drop poor windows (the model cannot follow them
    // there, e.g. a wrong stick/slip branch) and mask outlier frames beyond 5σ
    let start: Vec<Option<(Window, [f64; 2])>> = par_map(chosen.len(), |k| {
        let (ri, i, j) = chosen[k];
        let r = &runs[ri];
        let sys = window_system(r, &coef_for(&theta0, ri), geo, lat_of(&theta0), i, j);
        let (t, b) = (&r.t[i..j], &r.beta[i..j]);
        let sigma = r.sigma_camera.max(1e-12);
        let mut keep = vec![true; j - i];
        let mut f = fit_window_state(&sys, t, b, &keep, sigma, [b[0], r.v[i]], true)?;
        let bad: Vec<bool> = f.resid.iter().map(|x| x.abs() > 5.0).collect();
        let nbad = bad.iter().filter(|&&x| x).count();
        if nbad > 0 {
            if nbad > (j - i) / 5 {
                return None;
            }
            keep = bad.iter().map(|&x| !x).collect();
            f = fit_window_state(&sys, t, b, &keep, sigma, [f.p[0], f.p[1]], false)?;
        }
        let kept = keep.iter().filter(|&&x| x).count();
        if f.rss / kept as f64 > 4.0 {
            return None;
        }
        Some((
            Window {
                run: ri,
                lo: i,
                hi: j,
                keep,
            },
            [f.p[0], f.p[1]],
        ))
    });
    let (windows, states): (Vec<Window>, Vec<[f64; 2]>) = start.into_iter().flatten().unzip();
    if windows.is_empty() {
        return None;
    }
    let warm = Mutex::new(states);
    let residuals = |theta: &[f64]| -> Option<Vec<f64>> {
        let guesses = warm.lock().ok()?.clone();
        let per: Vec<Option<(Vec<f64>, [f64; 2])>> = par_map(windows.len(), |k| {
            let w = &windows[k];
            let r = &runs[w.run];
            let sys = window_system(r, &coef_for(theta, w.run), geo, lat_of(theta), w.lo, w.hi);
            let (t, b) = (&r.t[w.lo..w.hi], &r.beta[w.lo..w.hi]);
            project_state(&sys, t, b, &w.keep, r.sigma_camera.max(1e-12), guesses[k])
        });
        let mut out = Vec::new();
        let mut new_states = guesses;
        for (k, p) in per.into_iter().enumerate() {
            let (res, x0) = p?;
            out.extend(res);
            new_states[k] = x0;
        }
        *warm.lock().ok()? = new_states;
        Some(out)
    };
    let r0 = residuals(&theta0)?;
    let samples: usize = windows
        .iter()
        .map(|w| w.keep.iter().filter(|&&k| k).count())
        .sum();
    let sigma_rms = |res: &[f64], w: &[Window]| -> f64 {
        // back to radians with each run's camera noise
        let mut ss = 0.0;
        let mut n = 0usize;
        let mut pos = 0usize;
        for win in w {
            let s = runs[win.run].sigma_camera;
            for (k, &kp) in win.keep.iter().enumerate() {
                if kp {
                    ss += (res[pos + k] * s).powi(2);
                    n += 1;
                }
            }
            pos += win.keep.len();
        }
        (ss / n.max(1) as f64).sqrt()
    };
    let rms_start = sigma_rms(&r0, &windows);
    let steps: Vec<f64> = theta0
        .iter()
        .enumerate()
        .map(|(k, _)| {
            if fit_latency && k == fit.coef.len() {
                1e-3
            } else {
                1e-4
            }
        })
        .collect();
    let sol = least_squares_tol(
        &residuals,
        &theta0,
        &steps,
        opts.patience,
        Some((1e-6, 1e-5)),
    )?;
    // residual autocorrelation within windows: inflate the covariance by n/n_eff
    let mut pos = 0usize;
    let mut ratio_n = 0.0;
    let mut ratio_d = 0.0;
    for w in &windows {
        let e: Vec<f64> = (0..w.keep.len())
            .filter(|&k| w.keep[k])
            .map(|k| sol.resid[pos + k])
            .collect();
        pos += w.keep.len();
        ratio_n += e.len() as f64;
        ratio_d += e.len() as f64 / autocorr_time(&e);
    }
    let inflation = (ratio_n / ratio_d.max(1e-300)).max(1.0);
    // degrees of freedom: the profiled states took two per window
    let m = samples as f64;
    let dof = (m - 2.0 * windows.len() as f64 - theta0.len() as f64).max(1.0);
    let s2_fix = (sol.rss / dof) / (sol.rss / (sol.resid.len() - theta0.len()) as f64);
    let cov: DMatrix<f64> = &sol.cov * (inflation * s2_fix);
    let err: Vec<f64> = (0..theta0.len())
        .map(|k| cov[(k, k)].max(0.0).sqrt())
        .collect();
    let nc = fit.coef.len();
    Some(SimRefit {
        coef: sol.p[..nc].to_vec(),
        err: err[..nc].to_vec(),
        latency: fit_latency.then(|| (sol.p[nc], err[nc])),
        rms_rad: sigma_rms(&sol.resid, &windows),
        rms_start_rad: rms_start,
        windows: windows.len(),
        samples,
        inflation,
        converged: sol.converged,
    })
}
