//! Breakaway (static) friction: an output at rest stays stuck until |a| exceeds a static bound
//! η_s = η + η_Δs above the sliding friction η (catalog effect `static_friction`).
//!
//! The weak-form regression skips every window that contains a stick phase, so it cannot see this.
//! The signature sits where the output's velocity passes through zero, and only there:
//!
//! - a stuck output is released at |a| = η_s (later than at η), and leaves with the acceleration
//!   jump η_s − η (it departs quadratically instead of cubically);
//! - an output reaching zero velocity where η < |a| ≤ η_s sticks instead of reversing (this ends
//!   ring-downs earlier, further from the equilibrium);
//! - a reversal (no stick) at |a| just above η bounds η_s from above.
//!
//! Each velocity zero (stick stretch or reversal) whose |a| is within reach of the static bound
//! gets a short window of samples around it; the windows whose fitted trajectory sticks are used
//! (see [`fit_static_friction`] for why not the reversals). There the short-horizon prediction of
//! predict.rs is repeated: the initial state of the window is fitted (Levenberg–Marquardt) and the model,
//! with the fitted base (and accepted) coefficients held fixed, simulated by the exact Filippov
//! integrator with a trial excess. The summed χ² (camera noise) is profiled over the relative excess
//! s = η_Δs/η: a coarse grid, golden-section refinement, and the 1σ interval where the profile rises
//! by the χ²/dof of the windows (≥ 1). Which windows are used, and why the uncertainty carries a
//! systematic part: [`fit_static_friction`].

use super::lm::{least_squares, LsqFit};
use super::model::{AugmentedGear, Coefficients, Geometry, InputBend};
use super::predict::window_input;
use super::preprocess::CleanRun;
use crate::integrator::{EventDriven, EventKind, FlowMethod, FlowOptions};
use crate::model::DrivenOscillator;
use serde::Serialize;

/// Options of the static-friction profile.
#[derive(Debug, Clone, PartialEq)]
pub struct ReleaseOptions {
    /// Largest relative excess s = η_Δs/η profiled.
    pub s_max: f64,
    /// Samples kept on either side of a velocity zero.
    pub half_window: usize,
    /// Coarse grid of s (ascending, from 0 to `s_max`).
    pub grid: Vec<f64>,
    /// Golden-section steps of the refinement.
    pub refine_steps: usize,
    /// Relative systematic error of the coupling coefficients and of η from the weak form (docs:
    /// a few tenths of a percent; up to 0.6% measured on c_cs), propagated to s.
    pub coef_rel_sys: f64,
    /// Most stick windows profiled (an even subset beyond).
    pub max_windows: usize,
    /// Relative tolerance of the window simulations (the diagnosis passes its
    /// [`super::diagnose::DiagnoseOptions::tol`]; default 1e-8, as the documented results).
    pub tol: f64,
}

impl Default for ReleaseOptions {
    fn default() -> Self {
        Self {
            s_max: 1.5,
            half_window: 6,
            grid: vec![0.0, 0.15, 0.3, 0.5, 0.75, 1.0, 1.5],
            refine_steps: 6,
            coef_rel_sys: 0.005,
            max_windows: 80,
            tol: 1e-8,
        }
    }
}

/// The fitted static friction.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StaticFrictionFit {
    /// Sliding friction η of the model the excess is fitted on, s⁻².
    pub eta: f64,
    /// Relative excess s = η_Δs/η.
    pub s: f64,
    /// 1σ of s: statistical and systematic combined.
    pub s_err: f64,
    /// Statistical 1σ of s: half the profile interval where χ² rises by the χ²/dof of the windows
    /// (≥ 1); the upper end when ŝ = 0.
    pub s_stat: f64,
    /// Systematic 1σ of s from the base coefficients (see [`fit_static_friction`]).
    pub s_sys: f64,
    /// Lower and upper ends of the 1σ profile interval of s.
    pub s_interval: (f64, f64),
    /// χ²(s = 0) − χ²(ŝ), divided by the χ²/dof of the windows.
    pub delta_chi2: f64,
    /// Velocity zeros with information on s (χ² depends on s).
    pub windows: usize,
    /// Of those, the windows whose fitted trajectory at ŝ has a stick phase.
    pub sticks: usize,
    /// Velocity zeros examined.
    pub windows_examined: usize,
    /// Samples in the informative windows.
    pub samples: usize,
    /// χ²/dof of the informative windows at ŝ.
    pub chi2_per_dof: f64,
    /// The profile: (s, χ² − χ²(ŝ)), ascending in s.
    pub profile: Vec<(f64, f64)>,
}

/// A window of samples around one velocity zero.
struct Window<'a> {
    t: &'a [f64],
    b: &'a [f64],
    v0: f64,
    sigma: f64,
    /// The input (α₀, α̇, bend) of [`window_input`].
    input: (f64, f64, InputBend),
    /// The run's own coefficients relative to the common ones (parameter drift, driven-run
    /// input offset): added ζ and η, factor on the coupling, input offset.
    d_zeta: f64,
    d_eta: f64,
    g_scale: f64,
    alpha_offset: f64,
    /// Relative tolerance of its simulations ([`ReleaseOptions::tol`]).
    tol: f64,
}

impl Window<'_> {
    fn system(&self, c: &Coefficients, geo: &Geometry, excess: f64) -> AugmentedGear {
        AugmentedGear {
            c: Coefficients {
                eta_static_excess: excess,
                zeta: c.zeta + self.d_zeta,
                eta: c.eta + self.d_eta,
                c_sc: c.c_sc * self.g_scale,
                c_cs: c.c_cs * self.g_scale,
                alpha_offset: self.alpha_offset,
                alpha_offset_per_turn: 0.0,
                ..*c
            },
            geo: *geo,
            alpha0: self.input.0,
            alpha_rate: self.input.1,
            bend: self.input.2,
        }
    }

    fn simulate(&self, sys: &AugmentedGear, p: &[f64], events: bool) -> Option<(Vec<f64>, bool)> {
        let t = self.t;
        // the step budget of every window simulation: a trial model whose motion chatters
        // (a drag exponent at the end of its range with a large coefficient) would otherwise
        // hold the profile for minutes (a `stribeck` campaign set: over 10 min in this stage)
        let mut opts = FlowOptions::with_tol(self.tol)
            .samples(t.to_vec())
            .record_events(events);
        opts.max_steps = super::predict::WINDOW_MAX_STEPS;
        let f = EventDriven
            .flow(sys, t[0], [p[0], p[1]], t[t.len() - 1], &opts)
            .ok()?;
        if f.samples.len() != t.len() {
            return None;
        }
        let stuck = f
            .events
            .iter()
            .any(|e| matches!(e.kind, EventKind::StickStart));
        Some((f.samples.iter().map(|s| s.beta).collect(), stuck))
    }

    /// Fits the initial state with the excess `excess`; `warm` is tried first, the plain starts
    /// when it is missing or poor. Returns (χ², initial state).
    fn fit(
        &self,
        c: &Coefficients,
        geo: &Geometry,
        excess: f64,
        warm: Option<&[f64]>,
    ) -> Option<(f64, Vec<f64>)> {
        let sys = self.system(c, geo, excess);
        let f = |p: &[f64]| -> Option<Vec<f64>> {
            let (s, _) = self.simulate(&sys, p, false)?;
            Some(
                s.iter()
                    .zip(self.b)
                    .map(|(s, m)| (s - m) / self.sigma)
                    .collect(),
            )
        };
        let m = self.t.len() as f64;
        let poor = |x: &Option<LsqFit>| x.as_ref().map(|f| f.rss > 3.0 * m).unwrap_or(true);
        let mut best: Option<LsqFit> = None;
        let consider = |p0: &[f64], best: &mut Option<LsqFit>| {
            if let Some(ft) = least_squares(&f, p0, &[1e-7, 1e-6], 25) {
                if best.as_ref().map(|b| ft.rss < b.rss).unwrap_or(true) {
                    *best = Some(ft);
                }
            }
        };
        if let Some(w) = warm {
            consider(w, &mut best);
        }
        if poor(&best) {
            let (t, b) = (self.t, self.b);
            let fd = (b[1] - b[0]) / (t[1] - t[0]);
            for v in [self.v0, fd, 0.0, 0.5 * fd] {
                consider(&[b[0], v], &mut best);
                if !poor(&best) {
                    break;
                }
            }
        }
        best.map(|b| (b.rss, b.p))
    }
}

/// Runs `work` over `0..n` (in parallel with the `parallel` feature).
fn map_windows<T: Send>(n: usize, work: impl Fn(usize) -> T + Sync + Send) -> Vec<T> {
    #[cfg(feature = "parallel")]
    {
        use rayon::prelude::*;
        (0..n).into_par_iter().map(work).collect()
    }
    #[cfg(not(feature = "parallel"))]
    {
        (0..n).map(work).collect()
    }
}

/// The windows around velocity zeros of the cleaned runs whose |a| is within reach of the static
/// bound (|a| − r ≤ (s_max + 0.3) η at a sample next to the zero).
fn windows<'a>(
    runs: &'a [CleanRun],
    c: &Coefficients,
    per_run: Option<&[Coefficients]>,
    geo: &Geometry,
    latency: f64,
    opts: &ReleaseOptions,
) -> Vec<Window<'a>> {
    let k = opts.half_window;
    let mut out = Vec::new();
    for (ri, r) in runs.iter().enumerate() {
        let n = r.t.len();
        if n < 2 * k + 2 {
            continue;
        }
        let rc = per_run.and_then(|p| p.get(ri)).copied().unwrap_or(*c);
        let g_scale = if c.c_sc != 0.0 { rc.c_sc / c.c_sc } else { 1.0 };
        let offset_at = |t: f64| {
            rc.alpha_offset
                + rc.alpha_offset_per_turn * r.alpha_rate.abs() * (t - r.t[0])
                    / std::f64::consts::TAU
        };
        // the model at sample j, its input through the recorded α_j
        let at_sample = |j: usize| AugmentedGear {
            c: rc,
            geo: *geo,
            alpha0: r.alpha[j] - r.alpha_rate * (r.t[j] + latency),
            alpha_rate: r.alpha_rate,
            bend: InputBend::default(),
        };
        let thr = 3.0 * r.v_gain * r.sigma_beta;
        let near: Vec<bool> = (0..n)
            .map(|i| r.v[i].abs() < thr || (i + 1 < n && r.v[i] * r.v[i + 1] <= 0.0))
            .collect();
        let reach = (opts.s_max + 0.3) * c.eta.abs();
        let mut last_hi = 0usize;
        let mut i = 0usize;
        while i < n {
            if !near[i] {
                i += 1;
                continue;
            }
            let i0 = i;
            while i < n && near[i] {
                i += 1;
            }
            let i1 = i - 1;
            let relevant = (i0.saturating_sub(1)..(i1 + 2).min(n)).any(|j| {
                let f = at_sample(j).forces(r.t[j], r.beta[j], 0.0);
                f.a.abs() - f.r <= reach
            });
            if !relevant {
                continue;
            }
            // a long stretch at rest: one window on its entry, one on its release
            let spans = if i1 - i0 > 2 * k {
                vec![(i0.saturating_sub(k), i0 + k + 1), (i1 - k, i1 + k + 1)]
            } else {
                vec![(i0.saturating_sub(k), i1 + k + 1)]
            };
            for (lo, hi) in spans {
                let lo = lo.max(last_hi);
                let hi = hi.min(n);
                if hi < lo + 8 || (lo..hi - 1).any(|j| r.t[j + 1] - r.t[j] > 2.5 * r.dt) {
                    continue;
                }
                last_hi = hi;
                out.push(Window {
                    t: &r.t[lo..hi],
                    b: &r.beta[lo..hi],
                    v0: r.v[lo],
                    sigma: r.sigma_camera,
                    input: window_input(r, latency, lo, hi),
                    d_zeta: rc.zeta - c.zeta,
                    d_eta: rc.eta - c.eta,
                    g_scale,
                    alpha_offset: offset_at(0.5 * (r.t[lo] + r.t[hi - 1])),
                    tol: opts.tol,
                });
            }
        }
    }
    out
}

/// A profile of the summed χ² of `active` windows over s, for the coefficients `c`.
struct Profile {
    s: f64,
    s_lo: f64,
    s_hi: f64,
    chi0: f64,
    chi_min: f64,
    infl: f64,
    /// (s, χ², per-window initial states), ascending in s.
    evaluated: Vec<(f64, f64, Vec<Vec<f64>>)>,
}

type EndFits = ((f64, Vec<f64>), (f64, Vec<f64>));

/// χ² and initial state of window `w` at the excess `excess`, warm-started from `near` (and from
/// the s = 0 state when that fails or fits poorly).
fn window_at(
    w: &Window,
    c: &Coefficients,
    geo: &Geometry,
    excess: f64,
    near: &[f64],
    f0: &(f64, Vec<f64>),
    f1: &(f64, Vec<f64>),
) -> (f64, Vec<f64>) {
    let m = w.t.len() as f64;
    let a = w.fit(c, geo, excess, Some(near));
    if let Some(a) = &a {
        if a.0 <= 3.0 * m {
            return a.clone();
        }
    }
    match (a, w.fit(c, geo, excess, Some(&f0.1))) {
        (Some(a), Some(b)) => {
            if a.0 <= b.0 {
                a
            } else {
                b
            }
        }
        (Some(a), None) | (None, Some(a)) => a,
        // unfittable at this s: as bad as the worse end
        (None, None) => (f0.0.max(f1.0), f0.1.clone()),
    }
}

fn profile(
    ws: &[&Window],
    ends: &[EndFits],
    c: &Coefficients,
    geo: &Geometry,
    opts: &ReleaseOptions,
    dof: f64,
) -> Option<Profile> {
    let eta = c.eta;
    let s_top = *opts.grid.last()?;
    // summed χ² at one s, with per-window warm starts from the nearest s fitted so far and from s = 0
    let chi2_at = |s: f64, evaluated: &mut Vec<(f64, f64, Vec<Vec<f64>>)>| -> f64 {
        if let Some(e) = evaluated.iter().find(|e| (e.0 - s).abs() < 1e-12) {
            return e.1;
        }
        let res: Vec<(f64, Vec<f64>)> = map_windows(ws.len(), |k| {
            let w = ws[k];
            let (f0, f1) = &ends[k];
            if s == 0.0 {
                return f0.clone();
            }
            if s == s_top {
                return f1.clone();
            }
            let near = evaluated
                .iter()
                .min_by(|a, b| (a.0 - s).abs().total_cmp(&(b.0 - s).abs()))
                .map(|e| e.2[k].clone())
                .unwrap_or_else(|| f0.1.clone());
            window_at(w, c, geo, s * eta, &near, f0, f1)
        });
        let tot = res.iter().map(|r| r.0).sum();
        let ps = res.into_iter().map(|r| r.1).collect();
        evaluated.push((s, tot, ps));
        evaluated.sort_by(|a, b| a.0.total_cmp(&b.0));
        tot
    };
    let mut evaluated: Vec<(f64, f64, Vec<Vec<f64>>)> = Vec::new();
    let coarse: Vec<f64> = opts
        .grid
        .iter()
        .map(|&s| chi2_at(s, &mut evaluated))
        .collect();
    // golden-section refinement inside the bracket of the coarse minimum
    let kmin = (0..coarse.len())
        .min_by(|&a, &b| coarse[a].total_cmp(&coarse[b]))
        .unwrap_or(0);
    let mut lo = opts.grid[kmin.saturating_sub(1)];
    let mut hi = opts.grid[(kmin + 1).min(opts.grid.len() - 1)];
    let gr = 0.5 * (5f64.sqrt() - 1.0);
    let mut x1 = hi - gr * (hi - lo);
    let mut x2 = lo + gr * (hi - lo);
    let mut f1 = chi2_at(x1, &mut evaluated);
    let mut f2 = chi2_at(x2, &mut evaluated);
    for _ in 0..opts.refine_steps {
        if f1 <= f2 {
            hi = x2;
            x2 = x1;
            f2 = f1;
            x1 = hi - gr * (hi - lo);
            f1 = chi2_at(x1, &mut evaluated);
        } else {
            lo = x1;
            x1 = x2;
            f1 = f2;
            x2 = lo + gr * (hi - lo);
            f2 = chi2_at(x2, &mut evaluated);
        }
    }
    let (s_hat, chi_min) = evaluated
        .iter()
        .map(|e| (e.0, e.1))
        .min_by(|a, b| a.1.total_cmp(&b.1))?;
    let infl = (chi_min / dof).max(1.0);
    // 1σ interval: where the profile rises by `infl`, bisected on each side
    let side = |dir: f64, evaluated: &mut Vec<(f64, f64, Vec<Vec<f64>>)>| -> f64 {
        let target = chi_min + infl;
        let beyond = evaluated
            .iter()
            .filter(|e| (e.0 - s_hat) * dir > 0.0 && e.1 >= target)
            .min_by(|a, b| (a.0 - s_hat).abs().total_cmp(&(b.0 - s_hat).abs()))
            .map(|e| e.0);
        let Some(mut far) = beyond else {
            // the profile stays within 1σ up to the end of the grid
            return if dir > 0.0 { s_top } else { 0.0 };
        };
        let mut near = evaluated
            .iter()
            .filter(|e| (e.0 - s_hat) * dir >= 0.0 && (e.0 - far) * dir < 0.0 && e.1 < target)
            .max_by(|a, b| ((a.0 - s_hat) * dir).total_cmp(&((b.0 - s_hat) * dir)))
            .map(|e| e.0)
            .unwrap_or(s_hat);
        for _ in 0..3 {
            let mid = 0.5 * (near + far);
            if chi2_at(mid, evaluated) >= target {
                far = mid;
            } else {
                near = mid;
            }
        }
        // linear interpolation inside the last bracket
        let (fn_, ff) = (chi2_at(near, evaluated), chi2_at(far, evaluated));
        near + (far - near) * ((target - fn_) / (ff - fn_).max(1e-300)).clamp(0.0, 1.0)
    };
    let s_lo = side(-1.0, &mut evaluated);
    let s_hi = side(1.0, &mut evaluated);
    let chi0 = evaluated.first().map(|e| e.1).unwrap_or(chi_min);
    Some(Profile {
        s: s_hat,
        s_lo,
        s_hi,
        chi0,
        chi_min,
        infl,
        evaluated,
    })
}

/// Fits of every window at s = 0 and at the top of the grid; a window is kept when its fitted
/// trajectory at s = 0 sticks (a release or stick entry inside) and its χ² depends on s.
fn end_fits(
    ws: &[&Window],
    c: &Coefficients,
    geo: &Geometry,
    s_top: f64,
    select: bool,
) -> Vec<Option<EndFits>> {
    map_windows(ws.len(), |i| {
        let w = ws[i];
        let f0 = w.fit(c, geo, 0.0, None)?;
        if select && !w.simulate(&w.system(c, geo, 0.0), &f0.1, true)?.1 {
            return None;
        }
        let f1 = w.fit(c, geo, s_top * c.eta, Some(&f0.1))?;
        let m = w.t.len() as f64;
        // not fitted at either end (an outlier the cleaning missed): no information
        if select && (f0.0.min(f1.0) > 9.0 * m || (f0.0 - f1.0).abs() <= 1e-6 * (1.0 + f0.0)) {
            return None;
        }
        Some((f0, f1))
    })
}

/// Profiles the breakaway excess over the stick phases of `runs`, with the model `c` (its
/// `eta_static_excess` ignored) and sensor latency `latency`. `None` without informative windows.
///
/// Only windows whose fitted trajectory already sticks without an excess are used: there the
/// excess shifts the release (and the stick entry) smoothly. Reversals that would stick under a
/// trial excess give one-sided, threshold-like constraints whose profile is biased (measured: a
/// 0.5 Hz run with the truth model rejected its own excess by Δχ² ≈ 15), so they are left out.
///
/// The excess is measured as |a| at the release, a small difference of coupling terms ~10 times
/// larger, so it inherits the systematic error of the coupling coefficients and of η from the
/// weak form: the shift of the profile minimum when each of c_sc, c_cs, η changes by the relative
/// systematic `opts.coef_rel_sys` enters its uncertainty.
pub fn fit_static_friction(
    runs: &[CleanRun],
    c: &Coefficients,
    per_run: Option<&[Coefficients]>,
    geo: &Geometry,
    latency: f64,
    opts: &ReleaseOptions,
) -> Option<StaticFrictionFit> {
    let eta = c.eta;
    if eta.is_nan() || eta <= 0.0 || opts.grid.len() < 3 {
        return None;
    }
    let c = &Coefficients {
        eta_static_excess: 0.0,
        ..*c
    };
    let all = windows(runs, c, per_run, geo, latency, opts);
    let examined = all.len();
    let s_top = *opts.grid.last()?;
    let refs: Vec<&Window> = all.iter().collect();
    let ends = end_fits(&refs, c, geo, s_top, true);
    let mut ws: Vec<&Window> = Vec::new();
    let mut ends_kept = Vec::new();
    for (w, e) in all.iter().zip(ends) {
        if let Some(e) = e {
            ws.push(w);
            ends_kept.push(e);
        }
    }
    if ws.is_empty() {
        return None;
    }
    if ws.len() > opts.max_windows {
        // an even subset: beyond this the statistical error is far below the systematic one
        let n = ws.len();
        let keep: Vec<usize> = (0..opts.max_windows)
            .map(|k| k * n / opts.max_windows)
            .collect();
        ws = keep.iter().map(|&k| ws[k]).collect();
        ends_kept = keep.iter().map(|&k| ends_kept[k].clone()).collect();
    }
    let m_tot: usize = ws.iter().map(|w| w.t.len()).sum();
    let dof = (m_tot as f64 - 2.0 * ws.len() as f64 - 1.0).max(1.0);
    let pr = profile(&ws, &ends_kept, c, geo, opts, dof)?;
    let s_stat = if pr.s <= 0.0 {
        pr.s_hi
    } else {
        0.5 * (pr.s_hi - pr.s_lo)
    };
    // systematic of the base coefficients: the shift of the minimum, ∂χ²/∂s / ∂²χ²/∂s² at ŝ, when
    // c_sc, c_cs or η change by the relative systematic (states warm-started from the profile)
    let mut sys2 = 0.0;
    let eps = opts.coef_rel_sys;
    // steps wide enough to average over the kinks of single windows' profiles
    let h = s_stat.max(0.03);
    if eps > 0.0 && pr.s > h && pr.s + h < s_top {
        let states = |s: f64| -> &Vec<Vec<f64>> {
            &pr.evaluated
                .iter()
                .min_by(|a, b| (a.0 - s).abs().total_cmp(&(b.0 - s).abs()))
                .expect("evaluated")
                .2
        };
        let chi2 = |cc: &Coefficients, s: f64| -> f64 {
            let st = states(s);
            map_windows(ws.len(), |k| {
                window_at(
                    ws[k],
                    cc,
                    geo,
                    s * cc.eta,
                    &st[k],
                    &ends_kept[k].0,
                    &ends_kept[k].1,
                )
                .0
            })
            .into_iter()
            .sum()
        };
        let (cm, c0, cpl) = (chi2(c, pr.s - h), pr.chi_min, chi2(c, pr.s + h));
        let curv = (cm + cpl - 2.0 * c0) / (h * h);
        if curv > 0.0 {
            for k in 0..3 {
                let mut cp = *c;
                match k {
                    0 => cp.c_sc *= 1.0 + eps,
                    1 => cp.c_cs *= 1.0 + eps,
                    _ => cp.eta *= 1.0 + eps,
                }
                let grad = (chi2(&cp, pr.s + h) - chi2(&cp, pr.s - h)) / (2.0 * h);
                sys2 += (grad / curv).clamp(-2.0 * h, 2.0 * h).powi(2);
            }
        }
    }
    let s_err = (s_stat * s_stat + sys2).sqrt();
    let delta_chi2 = (pr.chi0 - pr.chi_min) / pr.infl;
    // windows that stick at ŝ
    let kbest = pr.evaluated.iter().position(|e| e.0 == pr.s)?;
    let best_p = &pr.evaluated[kbest].2;
    let sticks = map_windows(ws.len(), |k| {
        let w = ws[k];
        let sys = w.system(c, geo, pr.s * eta);
        w.simulate(&sys, &best_p[k], true)
            .map(|x| x.1)
            .unwrap_or(false)
    })
    .into_iter()
    .filter(|&x| x)
    .count();
    Some(StaticFrictionFit {
        eta,
        s: pr.s,
        s_err,
        s_stat,
        s_sys: sys2.sqrt(),
        s_interval: (pr.s_lo, pr.s_hi),
        delta_chi2,
        windows: ws.len(),
        sticks,
        windows_examined: examined,
        samples: m_tot,
        chi2_per_dof: pr.chi_min / dof,
        profile: pr
            .evaluated
            .iter()
            .map(|e| (e.0, e.1 - pr.chi_min))
            .collect(),
    })
}
