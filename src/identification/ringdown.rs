//! Ring-down fits of eq. `model`, β̈ + ζβ̇ + η sgn β̇ + κ sin(β − β0) = 0, run by run (as the paper's
//! Figs. 3–4): simulated with the exact Filippov integrator (stick phases included) and fitted by
//! Levenberg–Marquardt over (κ, β0, ζ, η, β(t₀), β̇(t₀)). Then κ(α0) = g √(sin²α0 + Δ² cos²α0)
//! (eq. `kappaex`) is fitted for g and |Δ|, and I = c/g with c = μ0 m1 m2/(4π r³) from the
//! set-up, its uncertainty from the fit and the tolerances of m1, m2, r.

use super::lm::least_squares;
use super::model::{AugmentedGear, Coefficients, Geometry, InputBend};
use super::preprocess::CleanRun;
use super::regression::autocorr_time;
use crate::integrator::{EventDriven, FlowMethod, FlowOptions};
use crate::io::recordings::GearSetup;
use serde::Serialize;
use std::f64::consts::PI;

/// The fit of one ring-down.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RingdownFit {
    /// Run file.
    pub file: String,
    /// Locked input angle, deg.
    pub alpha0_deg: f64,
    /// κ, s⁻², and 1σ.
    pub kappa: f64,
    /// 1σ of κ.
    pub kappa_err: f64,
    /// β0, rad.
    pub beta0: f64,
    /// ζ, s⁻¹.
    pub zeta: f64,
    /// 1σ of ζ.
    pub zeta_err: f64,
    /// η, s⁻².
    pub eta: f64,
    /// 1σ of η.
    pub eta_err: f64,
    /// rms residual, rad.
    pub rms_rad: f64,
    /// Samples fitted.
    pub n: usize,
    /// Effective samples (residual autocorrelation).
    pub n_eff: f64,
    /// Optimiser converged.
    pub converged: bool,
}

/// Most integration steps (accepted and rejected) of one ring-down simulation lasting `span`
/// seconds: [`RINGDOWN_BASE_STEPS`] plus [`RINGDOWN_STEPS_PER_S`] per second. A ring-down the
/// model follows takes at most 533 steps at tolerance 1e-9 (over the 12 822 simulations of the
/// ring-down fits of a set of `scripts/independent_recordings.py`, 1.5–3 s each; median 13, 99th
/// percentile 416), so a 3 s ring-down's budget of 5000 is about ten times that. Some trial
/// parameters of the Levenberg–Marquardt fit make the simulation chatter (8–17 million steps,
/// 65 s of CPU for one fit): with the budget their simulation fails and the optimiser rejects the
/// trial, as it rejected the worse fit the simulation gave after those steps.
pub fn ringdown_max_steps(span: f64) -> usize {
    RINGDOWN_BASE_STEPS + (RINGDOWN_STEPS_PER_S * span.max(0.0)) as usize
}

/// Fixed part of [`ringdown_max_steps`].
pub const RINGDOWN_BASE_STEPS: usize = 2_000;

/// Steps per second of a ring-down simulation in [`ringdown_max_steps`].
pub const RINGDOWN_STEPS_PER_S: f64 = 1_000.0;

/// Simulates eq. `model` at the given times (exact Filippov flow, relative tolerance `tol`; at most [`ringdown_max_steps`] integration steps;
/// `None` beyond).
pub fn simulate_model(p: &[f64], t0: f64, times: &[f64], tol: f64) -> Option<Vec<f64>> {
    let (kappa, beta0, zeta, eta) = (p[0], p[1], p[2] * p[2], p[3] * p[3]);
    if kappa.is_nan() || kappa <= 0.0 || !p.iter().all(|v| v.is_finite()) {
        return None;
    }
    let sys = AugmentedGear {
        c: Coefficients {
            zeta,
            eta,
            st_a: -kappa * beta0.cos(),
            st_b: kappa * beta0.sin(),
            ..Coefficients::default()
        },
        geo: Geometry::new(0.0, 0.0),
        alpha0: 0.0,
        alpha_rate: 0.0,
        bend: InputBend::default(),
    };
    let t1 = *times.last()?;
    let mut opts = FlowOptions::with_tol(tol).samples(times.to_vec());
    opts.max_steps = ringdown_max_steps(t1 - t0);
    let flow = EventDriven.flow(&sys, t0, [p[4], p[5]], t1, &opts).ok()?;
    if flow.samples.len() != times.len() {
        return None;
    }
    Some(flow.samples.iter().map(|s| s.beta).collect())
}

/// Fits one cleaned ring-down. `zeta0`, `eta0`: starting values; `tol`: relative tolerance of
/// its simulations ([`super::diagnose::DiagnoseOptions::ringdown_tol`]).
pub fn fit_ringdown(
    r: &CleanRun,
    file: &str,
    alpha0: f64,
    zeta0: f64,
    eta0: f64,
    tol: f64,
) -> Option<RingdownFit> {
    let n = r.t.len();
    if n < 20 {
        return None;
    }
    // end of motion: last sample moving clearly, plus a margin of rest
    let v_thr = 3.0 * r.v_gain * r.sigma_beta;
    let last_move = (0..n)
        .rev()
        .find(|&i| r.v[i].abs() > v_thr)
        .unwrap_or(n - 1);
    let end = (last_move + 30).min(n);
    let t = &r.t[..end];
    let b = &r.beta[..end];
    if t.len() < 12 {
        return None;
    }
    let tail = &r.beta[last_move.min(n - 1)..n];
    let mut tl = tail.to_vec();
    tl.sort_by(|a, b| a.total_cmp(b));
    let b_end = tl[tl.len() / 2];
    // half-period from crossings of the final position
    // (with hysteresis of 3σ, and only while moving, so noise at rest adds no crossings)
    let mut cross = Vec::new();
    let band = 3.0 * r.sigma_beta;
    let mut side = 0.0;
    for i in 0..=last_move.min(t.len() - 1) {
        let d = b[i] - b_end;
        if d.abs() > band && d.signum() != side {
            if side != 0.0 {
                cross.push(t[i]);
            }
            side = d.signum();
        }
    }
    let kappa0 = if cross.len() >= 3 {
        let half = (cross[cross.len() - 1] - cross[0]) / (cross.len() - 1) as f64;
        (PI / half).powi(2)
    } else {
        100.0
    };
    let t0 = t[0];
    let f = |p: &[f64]| -> Option<Vec<f64>> {
        let sim = simulate_model(p, t0, t, tol)?;
        Some(sim.iter().zip(b).map(|(s, m)| s - m).collect())
    };
    // ζ and η enter as squares (p[2]² = ζ, p[3]² = η) so they stay non-negative; the crossing
    // period underestimates κ at large amplitude (pendulum), hence a second start above it
    let mut best: Option<super::lm::LsqFit> = None;
    for kscale in [1.0, 1.3, 0.8] {
        let p0 = [
            kappa0 * kscale,
            b_end,
            zeta0.max(0.01).sqrt(),
            eta0.max(0.01).sqrt(),
            b[0],
            r.v[0],
        ];
        if let Some(fit) = least_squares(&f, &p0, &[1e-6; 6], 30) {
            let good = (fit.rss / t.len() as f64).sqrt() < 2.0 * r.sigma_beta;
            if best.as_ref().map(|bf| fit.rss < bf.rss).unwrap_or(true) {
                best = Some(fit);
            }
            if good {
                break;
            }
        }
    }
    let fit = best?;
    let m = t.len();
    let tau = autocorr_time(&fit.resid);
    let n_eff = (m as f64 / tau).max(7.0);
    let infl = m as f64 / n_eff;
    let err = |k: usize| (fit.cov[(k, k)] * infl).max(0.0).sqrt();
    Some(RingdownFit {
        file: file.to_string(),
        alpha0_deg: alpha0.to_degrees(),
        kappa: fit.p[0],
        kappa_err: err(0),
        beta0: fit.p[1],
        zeta: fit.p[2] * fit.p[2],
        zeta_err: 2.0 * fit.p[2].abs() * err(2),
        eta: fit.p[3] * fit.p[3],
        eta_err: 2.0 * fit.p[3].abs() * err(3),
        rms_rad: (fit.rss / m as f64).sqrt(),
        n: m,
        n_eff,
        converged: fit.converged,
    })
}

/// κ(α0) fitted for g and |Δ|, and the inertia from the set-up.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct KappaFit {
    /// g, s⁻².
    pub g: f64,
    /// 1σ of g.
    pub g_err: f64,
    /// |Δ| (κ depends on Δ²).
    pub delta_abs: f64,
    /// 1σ of |Δ|.
    pub delta_err: f64,
    /// Nominal Δ from the set-up's shaft angles.
    pub delta_nominal: f64,
    /// 1σ of the nominal Δ from the angle tolerances.
    pub delta_nominal_err: f64,
    /// I = c/g, kg m².
    pub inertia: f64,
    /// 1σ of I (fit and tolerances of m1, m2, r).
    pub inertia_err: f64,
    /// χ²/dof of the κ(α0) fit.
    pub chi2_dof: f64,
    /// Amplitude of a once-per-turn (180°-periodicity-breaking) component in the κ residuals, s⁻².
    pub once_per_turn: f64,
    /// Its 1σ.
    pub once_per_turn_err: f64,
}

/// Fits κ(α0) over the ring-downs.
pub fn fit_kappa(fits: &[RingdownFit], setup: &GearSetup) -> Option<KappaFit> {
    let pts: Vec<(f64, f64, f64)> = fits
        .iter()
        .filter(|f| f.kappa_err.is_finite() && f.kappa_err > 0.0)
        .map(|f| {
            (
                f.alpha0_deg.to_radians(),
                f.kappa,
                f.kappa_err.max(1e-3 * f.kappa),
            )
        })
        .collect();
    if pts.len() < 3 {
        return None;
    }
    let model = crate::model::gear::kappa;
    let f = |p: &[f64]| -> Option<Vec<f64>> {
        Some(
            pts.iter()
                .map(|&(a, k, s)| (model(p[0], p[1], a) - k) / s)
                .collect(),
        )
    };
    let d0 = setup.delta().abs().max(0.05);
    let g0 =
        pts.iter().map(|p| p.1).sum::<f64>() / pts.iter().map(|p| model(1.0, d0, p.0)).sum::<f64>();
    let fit = least_squares(&f, &[g0, d0], &[1e-7, 1e-7], 200)?;
    let dof = (pts.len() - 2) as f64;
    let chi2 = fit.rss / dof;
    // uncertainties: scale by max(1, χ²/dof) (model error shows up as excess scatter)
    let infl = chi2.max(1.0);
    let g = fit.p[0];
    let g_err = (fit.cov[(0, 0)] / chi2.max(1e-300) * infl).max(0.0).sqrt();
    let delta_err = (fit.cov[(1, 1)] / chi2.max(1e-300) * infl).max(0.0).sqrt();
    let c = setup.coupling();
    let inertia = c / g;
    let inertia_err = inertia * ((g_err / g).powi(2) + setup.coupling_rel_tol().powi(2)).sqrt();
    // once-per-turn component of the relative residuals: weighted LS on cos α0, sin α0
    let mut a = [[0.0; 2]; 2];
    let mut bb = [0.0; 2];
    for &(al, k, s) in &pts {
        let r = k - model(g, fit.p[1], al);
        let x = [al.cos(), al.sin()];
        let w = 1.0 / (s * s);
        for i in 0..2 {
            bb[i] += w * x[i] * r;
            for j in 0..2 {
                a[i][j] += w * x[i] * x[j];
            }
        }
    }
    let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
    let (opt, opt_err) = if det.abs() > 1e-300 {
        let c0 = (a[1][1] * bb[0] - a[0][1] * bb[1]) / det;
        let c1 = (a[0][0] * bb[1] - a[1][0] * bb[0]) / det;
        let v0 = a[1][1] / det * infl;
        let v1 = a[0][0] / det * infl;
        ((c0 * c0 + c1 * c1).sqrt(), (0.5 * (v0 + v1)).sqrt())
    } else {
        (0.0, f64::NAN)
    };
    Some(KappaFit {
        g,
        g_err,
        delta_abs: fit.p[1].abs(),
        delta_err,
        delta_nominal: setup.delta(),
        delta_nominal_err: setup.delta_tol(),
        inertia,
        inertia_err,
        chi2_dof: chi2,
        once_per_turn: opt,
        once_per_turn_err: opt_err,
    })
}
