//! Where the base model fails: χ² per run, residual fingerprints (harmonics of α and β,
//! velocity, sign of velocity), the symmetry (α, β) → (α+π, β+π), ring-downs against driven runs,
//! and κ(α0) from the ring-downs. Words with the numbers behind them; nothing here names an
//! effect.

use super::predict::{fit_window_state, simulate_states, WindowStates};
use super::preprocess::{
    rest_autocovariance, speed_noise, CleanRun, RestAutocov, RestPiece, SpeedPiece,
};
use super::regression::{delta_bic, fit, Design, LinFit, Term};
use super::report::{Dependence, Mismatch, NoiseFloor, Remainder, RemainderBin, SpeedNoiseFloor};
use super::ringdown::KappaFit;
use super::shooting::{par_map, SimModel, Win};
use crate::numerics::least_squares::{weighted, DEFAULT_RCOND};
use nalgebra::DMatrix;
use serde_json::json;
use std::collections::BTreeMap;

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
    let rows: Vec<usize> = (0..n).collect();
    let w = |i: usize| 1.0 / (sigma[i] * sigma[i]);
    let s = weighted(&rows, p, |i, k| regs[k][i], |i| r[i], w, DEFAULT_RCOND).ok()?;
    // Δχ² = χ²(r) − χ²(r − Xx), the χ² the group explains
    let chi0: f64 = (0..n).map(|i| w(i) * r[i] * r[i]).sum();
    let chi1: f64 = s.resid.iter().map(|e| e * e).sum();
    let norm = s.x.iter().map(|v| v * v).sum::<f64>().sqrt();
    Some((norm, (chi0 - chi1) / infl, p))
}

/// Thresholds of [`locate`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MismatchOptions {
    /// BIC decrease that counts as significant.
    pub bic_threshold: f64,
    /// A fingerprint must explain at least this fraction of a row's noise variance.
    pub min_chi2_gain_per_row: f64,
}

/// The located mismatch of the base fit `base_fit` (columns `base_cols` of `design`) and the
/// equation-error χ²/row of every run.
pub fn locate(
    design: &Design,
    base_fit: &LinFit,
    base_cols: &[usize],
    runs: &[CleanRun],
    files: &[String],
    kappa: Option<&KappaFit>,
    opts: &MismatchOptions,
) -> (Vec<Mismatch>, Vec<f64>) {
    let nr = runs.len();
    let mut mismatch = Vec::new();
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
    fingerprints(design, base_fit, runs, opts, &mut mismatch);
    symmetry(design, opts, &mut mismatch);
    consistency(design, base_cols, runs, &mut mismatch);
    if let Some(k) = kappa {
        kappa_checks(k, &mut mismatch);
    }
    (mismatch, chi_run)
}

/// Residual fingerprints: harmonics of α and β, velocity, sign of velocity.
fn fingerprints(
    design: &Design,
    base_fit: &LinFit,
    runs: &[CleanRun],
    opts: &MismatchOptions,
    mismatch: &mut Vec<Mismatch>,
) {
    let infl = base_fit.n as f64 / base_fit.n_eff;
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
}

/// The symmetry test: a flexible symmetric model (base, symmetric catalog and dictionary terms)
/// against the same plus every symmetry-breaking term.
fn symmetry(design: &Design, opts: &MismatchOptions, mismatch: &mut Vec<Mismatch>) {
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
    let symm_cols = cols_of(design, &symm_terms);
    let symm_fit = fit(design, &symm_cols);
    let mut sym_cols = symm_cols.clone();
    sym_cols.extend(cols_of(design, &sym_terms));
    if let (Some(sf), Some(s0)) = (fit(design, &sym_cols), symm_fit.as_ref()) {
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
}

/// Ring-downs against driven runs: the base coefficients fitted separately.
fn consistency(
    design: &Design,
    base_cols: &[usize],
    runs: &[CleanRun],
    mismatch: &mut Vec<Mismatch>,
) {
    let has_rd = runs.iter().any(|r| r.ringdown);
    let has_dr = runs.iter().any(|r| !r.ringdown);
    if has_rd && has_dr {
        let drd = subset(design, |i| runs[design.run[i]].ringdown);
        let ddr = subset(design, |i| !runs[design.run[i]].ringdown);
        if let (Some(a), Some(b)) = (fit(&drd, base_cols), fit(&ddr, base_cols)) {
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
}

/// κ(α0) of the ring-downs: not 180°-periodic, |Δ| against the nominal shaft angles.
fn kappa_checks(k: &KappaFit, mismatch: &mut Vec<Mismatch>) {
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

/// z above which a remainder (or a bin of it) counts as above the camera-noise floor: the
/// judge's smallest threshold.
pub const REMAINDER_Z: f64 = 3.0;

/// E and σ_E of windows given as pairs (χ², floor), see [`Remainder`]: E = Σχ²/Σf − 1 with the
/// ratio estimator's σ over the windows.
fn ratio_excess(pairs: &[(f64, f64)]) -> (f64, f64) {
    let (r, sr) = ratio(pairs);
    (r - 1.0, sr)
}

/// The ratio estimator r = Σa/Σb over units (a, b) with σ_r² = n/(n−1) Σ(a − r b)²/(Σb)² (each
/// unit, a judging window, carries its own correlation); NaN for fewer than two units or Σb ≤ 0.
fn ratio(pairs: &[(f64, f64)]) -> (f64, f64) {
    let n = pairs.len();
    let (sa, sb): (f64, f64) = pairs.iter().fold((0.0, 0.0), |a, p| (a.0 + p.0, a.1 + p.1));
    if n < 2 || sb <= 0.0 {
        return (f64::NAN, f64::NAN);
    }
    let r = sa / sb;
    let v: f64 = pairs.iter().map(|p| (p.0 - r * p.1).powi(2)).sum::<f64>() * n as f64
        / (n - 1) as f64
        / (sb * sb);
    (r, v.sqrt())
}

/// The fraction of the base model's held-out excess that one step of the selection removed, from
/// the model `before` it to the model `after` it: Σ_w (χ²_before − χ²_after) / Σ_w (χ²_base − d_w)
/// over the windows all three predicted, d_w the window's noise floor (`floors`, from
/// [`remainder`]), with the ratio σ ([`ratio`]). With `before` the base model and `after` the
/// final one it is the report's `fraction_removed`. `None` with fewer than two such windows or a
/// base excess that is not positive.
pub fn fraction_removed(
    base: &[Option<f64>],
    before: &[Option<f64>],
    after: &[Option<f64>],
    floors: &[f64],
) -> Option<(f64, f64)> {
    let pairs: Vec<(f64, f64)> = (0..floors.len())
        .filter_map(|k| {
            let (b, x, y) = (
                base.get(k)?.as_ref()?,
                before.get(k)?.as_ref()?,
                after.get(k)?.as_ref()?,
            );
            Some((x - y, b - floors[k]))
        })
        .collect();
    let (r, sr) = ratio(&pairs);
    (r.is_finite() && sr.is_finite()).then_some((r, sr))
}

/// What the noise floor of one judging window needs ([`window_geometry`]).
#[derive(Debug, Clone, PartialEq)]
pub struct WindowGeometry {
    /// Camera frame numbers of the kept frames (from the run's first sample and its median
    /// interval).
    pub frames: Vec<i64>,
    /// Hat matrix of the fitted initial state on the kept frames, H = U Uᵀ with U the left
    /// singular vectors of J = ∂β_sim/∂(β₀, β̇₀) (a direction J cannot see dropped).
    pub hat: DMatrix<f64>,
    /// Samples from the window's first (masked ones included, and up to a window length past
    /// its end) at which the model's trajectory from the window's state is stuck.
    pub stuck: Vec<bool>,
    /// The model's β and β̇ from the window's state at every sample of the window (masked ones
    /// included).
    pub sim: Vec<(f64, f64)>,
}

/// The geometry of every window of `wins` under `model` at θ: the window's state fitted (from the
/// warm start of the refit when there is one, else multi-start), the Jacobian of the simulated β
/// with respect to that state (exact: [`simulate_states`]), its hat matrix H (the first-order
/// projection of the state fit), and the samples at which
/// the simulated output is stuck (β̇ = 0 in the Filippov stick mode). `None` for a window the
/// model cannot fit or simulate.
pub fn window_geometry(
    model: &SimModel,
    theta: &[f64],
    wins: &[Win],
    warm: &[Option<[f64; 2]>],
) -> Vec<Option<WindowGeometry>> {
    par_map(wins.len(), |k| {
        let w = &wins[k];
        let r = &model.runs[w.run];
        let sys = model.system(theta, w);
        let (t, b) = (&r.t[w.lo..w.hi], &r.beta[w.lo..w.hi]);
        let x = match warm.get(k).copied().flatten() {
            Some(x) => x,
            None => {
                let f = fit_window_state(
                    &sys,
                    t,
                    b,
                    &w.keep,
                    r.sigma_camera,
                    [b[0], r.v[w.lo]],
                    true,
                    model.tol,
                )?;
                [f.p[0], f.p[1]]
            }
        };
        // one simulation over the window and up to a window length past it: the stuck flags over
        // both (a stick phase continues across the next window's start, where that window's own
        // fitted velocity may move the model for a frame or two), the window's samples and their
        // derivative with respect to the window's state (variational equations and saltation
        // matrices)
        let ext = &r.t[w.lo..(w.hi + super::predict::WINDOW).min(r.t.len())];
        let WindowStates { mut states, jac } = simulate_states(&sys, ext[0], x, ext, model.tol)?;
        let stuck: Vec<bool> = states.iter().map(|s| s.1 == 0.0).collect();
        states.truncate(t.len());
        let kept: Vec<usize> = (0..t.len()).filter(|&q| w.keep[q]).collect();
        let j = DMatrix::from_fn(kept.len(), 2, |i, c| jac[kept[i]][c]);
        let svd = j.svd(true, false);
        let u = svd.u?;
        let smax = svd.singular_values.max();
        let mut hat = DMatrix::zeros(kept.len(), kept.len());
        for c in 0..svd.singular_values.len() {
            if svd.singular_values[c] > 1e-9 * smax {
                let col = u.column(c).clone_owned();
                hat += &col * col.transpose();
            }
        }
        let dt = r.dt.max(1e-12);
        Some(WindowGeometry {
            frames: kept
                .iter()
                .map(|&q| ((t[q] - r.t[0]) / dt).round() as i64)
                .collect(),
            hat,
            stuck,
            sim: states,
        })
    })
}

/// The frames at rest of the judging windows: samples at which the model's trajectory from a
/// window's state is stuck (over the window and up to a window length past it), without the
/// first and last stuck sample of a stick phase that begins or ends there (the model's stop and
/// release instants are uncertain by a fraction of a frame, where the output moves by up to
/// ½ a dt²) and without the frames a window masks, joined over the windows of a run.
pub fn rest_pieces(
    runs: &[CleanRun],
    wins: &[Win],
    geom: &[Option<WindowGeometry>],
) -> Vec<RestPiece> {
    let mut rest: Vec<Vec<bool>> = runs.iter().map(|r| vec![false; r.t.len()]).collect();
    let mut masked: Vec<Vec<bool>> = runs.iter().map(|r| vec![false; r.t.len()]).collect();
    for w in wins {
        for (q, &k) in w.keep.iter().enumerate() {
            masked[w.run][w.lo + q] |= !k;
        }
    }
    for (w, g) in wins.iter().zip(geom) {
        let Some(g) = g else { continue };
        let n = g.stuck.len();
        for q in 0..n {
            let inner = g.stuck[q] && (q == 0 || g.stuck[q - 1]) && (q + 1 == n || g.stuck[q + 1]);
            if inner {
                rest[w.run][w.lo + q] = true;
            }
        }
    }
    for (rr, mm) in rest.iter_mut().zip(&masked) {
        rr.iter_mut().zip(mm).for_each(|(r, &m)| *r &= !m);
    }
    let mut out = Vec::new();
    for (ri, r) in runs.iter().enumerate() {
        let dt = r.dt.max(1e-12);
        let mut cur = RestPiece::default();
        for (i, &at_rest) in rest[ri].iter().enumerate() {
            if at_rest {
                cur.frames.push(((r.t[i] - r.t[0]) / dt).round() as i64);
                cur.beta.push(r.beta[i]);
            } else if !cur.frames.is_empty() {
                out.push(std::mem::take(&mut cur));
            }
        }
        if !cur.frames.is_empty() {
            out.push(cur);
        }
    }
    out
}

/// The noise floor of every window, f_w = tr((I − H_w)Γ_w)/σ²_camera = Σ_l c_w(l) γ(l): the expected
/// χ² of the window's held-out residuals when the model is right and the camera noise has the
/// autocovariance γ (Γ_w: γ at the frame lags of its kept frames, 0 beyond the lags measured).
/// Returns the coefficients c_w (`None` without geometry).
fn floor_coefficients(
    runs: &[CleanRun],
    wins: &[Win],
    geom: &[Option<WindowGeometry>],
    lags: usize,
) -> Vec<Option<Vec<f64>>> {
    wins.iter()
        .zip(geom)
        .map(|(w, g)| {
            let g = g.as_ref()?;
            let s2 = runs[w.run].sigma_camera.max(1e-12).powi(2);
            let n = g.frames.len();
            let mut c = vec![0.0; lags];
            c[0] = (n as f64 - g.hat.trace()) / s2;
            for i in 0..n {
                for j in 0..n {
                    let l = (g.frames[i] - g.frames[j]).unsigned_abs() as usize;
                    if i != j && l < lags {
                        c[l] -= g.hat[(i, j)] / s2;
                    }
                }
            }
            Some(c)
        })
        .collect()
}

/// The camera-noise floor of the judging windows: per window its expected χ² under the noise
/// measured at rest ([`rest_autocovariance`]) plus, when it is significant, the speed-dependent
/// white noise measured in motion ([`speed_floor`]); the jackknife of the floor (one set of
/// floors per leave-one-unit-out estimate, for each independent measurement); and the report's
/// description. Without two pieces at rest, the rest part is white noise at the cleaning's σ,
/// d_w = frames − 2, with a note.
pub fn noise_floor(
    runs: &[CleanRun],
    wins: &[Win],
    geom: &[Option<WindowGeometry>],
) -> (Vec<f64>, Vec<Vec<Vec<f64>>>, NoiseFloor) {
    let (mut floors, jack, mut nf) = rest_floor(runs, wins, geom);
    let mut sets = vec![jack];
    if let Some((add, speed_jack, report)) = speed_floor(runs, wins, geom, &floors) {
        floors.iter_mut().zip(&add).for_each(|(f, a)| *f += a);
        sets.push(speed_jack);
        nf.speed_noise = Some(report);
    }
    (floors, sets, nf)
}

/// The rest part of [`noise_floor`]: floors, their jackknife over the pieces at rest, the
/// description.
fn rest_floor(
    runs: &[CleanRun],
    wins: &[Win],
    geom: &[Option<WindowGeometry>],
) -> (Vec<f64>, Vec<Vec<f64>>, NoiseFloor) {
    let white: Vec<f64> = wins
        .iter()
        .map(|w| (w.kept() as f64 - 2.0).max(1.0))
        .collect();
    let mut cams: Vec<f64> = runs.iter().map(|r| r.sigma_camera).collect();
    cams.sort_by(f64::total_cmp);
    let cam = cams.get(cams.len() / 2).copied().unwrap_or(f64::NAN);
    let pieces = rest_pieces(runs, wins, geom);
    let ac = rest_autocovariance(&pieces, super::predict::WINDOW - 1);
    let Some(ac) = ac else {
        let nf = NoiseFloor {
            method: "white".into(),
            sigma_rad: cam,
            sigma_cleaning_rad: cam,
            rest_frames: pieces.iter().map(|p| p.frames.len()).sum(),
            rest_pieces: pieces.len(),
            floor_over_frames_minus_2: 1.0,
            note: "fewer than two stretches of two frames at rest in the judging windows: the \
                   floor is white camera noise at the cleaning's σ (frames − 2 per window), which \
                   is too low for a correlated noise"
                .into(),
            ..NoiseFloor::default()
        };
        return (white, vec![], nf);
    };
    let lags = ac.gamma.len().min(super::predict::WINDOW);
    let coef = floor_coefficients(runs, wins, geom, lags);
    let floors_for = |g: &[f64]| -> Vec<f64> {
        coef.iter()
            .zip(wins)
            .map(|(c, w)| match c {
                Some(c) => c.iter().zip(g).map(|(a, b)| a * b).sum(),
                // no geometry: white at the measured variance
                None => (w.kept() as f64 - 2.0).max(1.0) * g[0] / runs[w.run].sigma_camera.powi(2),
            })
            .collect()
    };
    let floors = floors_for(&ac.gamma);
    let jack: Vec<Vec<f64>> = ac.jackknife.iter().map(|g| floors_for(g)).collect();
    let ratio = |g: &[f64]| floors_for(g).iter().sum::<f64>() / white.iter().sum::<f64>();
    (floors, jack, describe(&ac, cam, lags, &ratio))
}

/// The speed-dependent part of the window floors: the white noise of variance σ_t² β̇² measured
/// in motion ([`speed_noise`]: the judging windows are the pieces, the final model's simulated
/// window the reference), added to Γ_w as diag(σ_t² β̇_i²) with β̇ the model's, so that
/// f_w gains σ_t² Σ_i (1 − H_ii) β̇_i² / σ²_camera over the kept frames (the trace of
/// (I − H_w) diag(σ_t² β̇²)). Added only when σ_t² ≥ [`REMAINDER_Z`] times its jackknife σ.
/// Returns the added floors, the floors of every leave-one-window-out σ_t² (the rest floors
/// `rest` plus that part), and the report's entry; `None` when it cannot be measured.
fn speed_floor(
    runs: &[CleanRun],
    wins: &[Win],
    geom: &[Option<WindowGeometry>],
    rest: &[f64],
) -> Option<(Vec<f64>, Vec<Vec<f64>>, SpeedNoiseFloor)> {
    let pieces: Vec<SpeedPiece> = wins
        .iter()
        .zip(geom)
        .filter_map(|(w, g)| {
            let g = g.as_ref()?;
            let r = &runs[w.run];
            (g.sim.len() == w.hi - w.lo).then(|| SpeedPiece {
                t: r.t[w.lo..w.hi].to_vec(),
                beta: r.beta[w.lo..w.hi].to_vec(),
                keep: w.keep.clone(),
                reference: g.sim.iter().map(|s| s.0).collect(),
                speed: g.sim.iter().map(|s| s.1).collect(),
            })
        })
        .collect();
    let sn = speed_noise(&pieces)?;
    let sigma = sn.timing_var_sigma();
    let z = sn.timing_var / sigma;
    let used = z.is_finite() && z >= REMAINDER_Z;
    // per window Σ_kept (1 − H_ii) β̇_i² / σ²_camera
    let unit: Vec<f64> = wins
        .iter()
        .zip(geom)
        .map(|(w, g)| {
            let Some(g) = g else { return 0.0 };
            let s2 = runs[w.run].sigma_camera.max(1e-12).powi(2);
            let kept = (0..w.keep.len()).filter(|&q| w.keep[q]);
            kept.enumerate()
                .map(|(i, q)| (1.0 - g.hat[(i, i)]) * g.sim.get(q).map_or(0.0, |s| s.1 * s.1))
                .sum::<f64>()
                / s2
        })
        .collect();
    let scale = if used { 1.0 } else { 0.0 };
    let add: Vec<f64> = unit.iter().map(|u| scale * sn.timing_var * u).collect();
    let jack: Vec<Vec<f64>> = sn
        .jackknife
        .iter()
        .map(|s| {
            rest.iter()
                .zip(&unit)
                .map(|(f, u)| f + scale * s * u)
                .collect()
        })
        .collect();
    let jitter = sn.timing_var.max(0.0).sqrt();
    let report = SpeedNoiseFloor {
        timing_var_s2: sn.timing_var,
        timing_var_sigma_s2: sigma,
        timing_jitter_s: jitter,
        timing_jitter_s_err: if jitter > 0.0 {
            sigma / (2.0 * jitter)
        } else {
            sigma.sqrt()
        },
        z,
        added: used,
        floor_added: add.iter().sum::<f64>() / rest.iter().sum::<f64>().max(1e-300),
        white_sigma_rad: sn.white_var.max(0.0).sqrt(),
        samples: sn.samples,
        windows: sn.pieces,
    };
    Some((add, jack, report))
}

/// The report's description of the noise measured at rest.
fn describe(ac: &RestAutocov, cam: f64, lags: usize, ratio: &dyn Fn(&[f64]) -> f64) -> NoiseFloor {
    let shown = lags.min(ac.gamma.len()).max(1);
    let rho = ac.correlation();
    NoiseFloor {
        method: "rest".into(),
        sigma_rad: ac.gamma[0].max(0.0).sqrt(),
        sigma_rad_err: ac.sigma_of(|g| g[0].max(0.0).sqrt()),
        sigma_cleaning_rad: cam,
        correlation: rho[1..shown].to_vec(),
        correlation_sigma: (1..shown).map(|k| ac.sigma_of(|g| g[k] / g[0])).collect(),
        max_lag: ac.gamma.len() - 1,
        rest_frames: ac.frames,
        rest_pieces: ac.pieces,
        floor_over_frames_minus_2: ratio(&ac.gamma),
        floor_over_frames_minus_2_sigma: ac.sigma_of(ratio),
        note: format!(
            "autocovariance of the camera noise measured on {} frames at rest ({} stretches, the \
             final model's stick phases in the judging windows); window floors tr((I − H)Γ)/σ²",
            ac.frames, ac.pieces
        ),
        speed_noise: None,
    }
}

/// Relative jackknife σ of the floor summed over the windows `idx`: the σ of each independent
/// measurement in `sets` (its leave-one-unit-out floors) added in quadrature.
fn floor_rel_sigma(floors: &[f64], sets: &[Vec<Vec<f64>>], idx: &[usize]) -> f64 {
    sets.iter()
        .map(|jack| jack_rel_sigma(floors, jack, idx).powi(2))
        .sum::<f64>()
        .sqrt()
}

/// Relative jackknife σ of the floor summed over the windows `idx`, one measurement.
fn jack_rel_sigma(floors: &[f64], jack: &[Vec<f64>], idx: &[usize]) -> f64 {
    if jack.len() < 2 {
        return 0.0;
    }
    let d: f64 = idx.iter().map(|&k| floors[k]).sum();
    let v: Vec<f64> = jack
        .iter()
        .map(|f| idx.iter().map(|&k| f[k]).sum())
        .collect();
    let p = v.len() as f64;
    let mean = v.iter().sum::<f64>() / p;
    ((p - 1.0) / p * v.iter().map(|x| (x - mean).powi(2)).sum::<f64>()).sqrt() / d
}

/// Bins of one grouping: (label, window indices).
type Bins = Vec<(String, Vec<usize>)>;

/// A label by quartile of `value` over the windows `used`: `i: [lo, hi]`.
fn quartile_label<'a>(
    used: &[usize],
    value: impl Fn(usize) -> f64 + 'a,
) -> impl Fn(usize) -> Option<String> + 'a {
    let mut v: Vec<f64> = used.iter().map(|&k| value(k)).collect();
    v.sort_by(f64::total_cmp);
    let q = |p: f64| v[((v.len() - 1) as f64 * p).round() as usize];
    let edges = [q(0.0), q(0.25), q(0.5), q(0.75), q(1.0)];
    move |k| {
        let s = value(k);
        let b = (1..4).filter(|&i| s >= edges[i]).count();
        Some(format!("{}: [{:.2}, {:.2}]", b + 1, edges[b], edges[b + 1]))
    }
}

/// Per-window description used for binning: (run, middle β, mean |β̇|, contains a stick phase).
#[derive(Debug, Clone, Copy)]
struct WinInfo {
    run: usize,
    beta_mid: f64,
    /// α − β at the window's middle, in [0, 2π).
    relative_mid: f64,
    speed: f64,
    /// Mean |coupling torque| over the window in units of g: |Δ cos α sin β − sin α cos β|.
    torque: f64,
    stick: bool,
}

fn win_info(
    runs: &[CleanRun],
    w: &Win,
    delta: f64,
    (rest_sigmas, rest_run): (f64, usize),
) -> WinInfo {
    let r = &runs[w.run];
    let mid = (w.lo + w.hi) / 2;
    let v = &r.v[w.lo..w.hi];
    let speed = v.iter().map(|x| x.abs()).sum::<f64>() / v.len().max(1) as f64;
    let torque = (w.lo..w.hi)
        .map(|i| {
            let (sa, ca) = r.alpha[i].sin_cos();
            let (sb, cb) = r.beta[i].sin_cos();
            (delta * ca * sb - sa * cb).abs()
        })
        .sum::<f64>()
        / v.len().max(1) as f64;
    let thr = rest_sigmas * r.v_gain * r.sigma_beta;
    let (mut longest, mut cur) = (0usize, 0usize);
    for x in v {
        cur = if x.abs() < thr { cur + 1 } else { 0 };
        longest = longest.max(cur);
    }
    WinInfo {
        run: w.run,
        beta_mid: r.beta[mid].rem_euclid(std::f64::consts::TAU),
        relative_mid: (r.alpha[mid] - r.beta[mid]).rem_euclid(std::f64::consts::TAU),
        speed,
        torque,
        stick: longest >= rest_run.max(1),
    }
}

/// The groupings of the remainder's windows `used` (see [`Remainder`]): run kind, drive
/// frequency, β phase, speed quartile, stick or slip.
fn remainder_groups(
    runs: &[CleanRun],
    info: &[WinInfo],
    used: &[usize],
) -> Vec<(&'static str, Bins)> {
    let mut groups: Vec<(&'static str, Bins)> = Vec::new();
    let by = |label: &dyn Fn(usize) -> Option<String>| -> Bins {
        let mut m: BTreeMap<String, Vec<usize>> = BTreeMap::new();
        for &k in used {
            if let Some(l) = label(k) {
                m.entry(l).or_default().push(k);
            }
        }
        m.into_iter().collect()
    };
    groups.push((
        "run_kind",
        by(&|k| {
            Some(if runs[info[k].run].ringdown {
                "ringdown".into()
            } else {
                "driven".into()
            })
        }),
    ));
    groups.push((
        "drive_hz",
        by(&|k| {
            let r = &runs[info[k].run];
            (!r.ringdown).then(|| format!("{:.2}", r.alpha_rate.abs() / std::f64::consts::TAU))
        }),
    ));
    groups.push((
        "beta_phase_deg",
        by(&|k| {
            let b = (info[k].beta_mid.to_degrees() / 60.0)
                .floor()
                .clamp(0.0, 5.0) as i32;
            Some(format!("[{}, {})", 60 * b, 60 * (b + 1)))
        }),
    ));
    groups.push((
        "alpha_minus_beta_deg",
        by(&|k| {
            let b = (info[k].relative_mid.to_degrees() / 60.0)
                .floor()
                .clamp(0.0, 5.0) as i32;
            Some(format!("[{}, {})", 60 * b, 60 * (b + 1)))
        }),
    ));
    groups.push(("speed_rad_s", by(&quartile_label(used, |k| info[k].speed))));
    groups.push((
        "torque_over_g",
        by(&quartile_label(used, |k| info[k].torque)),
    ));
    // the session's order: the runs in the order of experiment.toml, in thirds
    let nr = runs.len();
    if nr >= 3 {
        groups.push((
            "run_order",
            by(&|k| {
                Some(
                    ["1: first third", "2: middle third", "3: last third"]
                        [(3 * info[k].run / nr).min(2)]
                    .to_string(),
                )
            }),
        ));
    }
    groups.push((
        "stick_slip",
        by(&|k| {
            Some(if info[k].stick {
                "stick".into()
            } else {
                "slip".into()
            })
        }),
    ));
    groups
}

/// The remainder of the final model's held-out χ² `fin` against the base model's `base` on the
/// judging windows `wins` (see [`Remainder`]), over the camera-noise floor of each window
/// ([`noise_floor`], from the final model's window geometry `geom`). σ_E combines the ratio
/// estimator's σ over the windows with the floor's jackknife σ: σ_E² = σ_win² + ((1 + E) σ_D/D)².
/// A sample is at rest when |β̇| < `rest_sigmas` σ_v; a window with `rest_run` consecutive
/// samples at rest is a stick window (the weak form's criterion). `None` without windows
/// predicted by the final model.
pub fn remainder(
    runs: &[CleanRun],
    wins: &[Win],
    (base, fin): (&[Option<f64>], &[Option<f64>]),
    rest: (f64, usize),
    geom: &[Option<WindowGeometry>],
    delta: f64,
) -> Option<(Remainder, Vec<f64>)> {
    let used: Vec<usize> = (0..wins.len()).filter(|&k| fin[k].is_some()).collect();
    if used.len() < 2 {
        return None;
    }
    let (floors, jack, noise) = noise_floor(runs, wins, geom);
    let dof = |k: usize| floors[k];
    let excess = |chi: &[Option<f64>], idx: &[usize]| -> (f64, f64) {
        let pairs: Vec<(f64, f64)> = idx
            .iter()
            .filter_map(|&k| Some((chi[k]?, dof(k))))
            .collect();
        let (e, se) = ratio_excess(&pairs);
        let rel = floor_rel_sigma(&floors, &jack, idx);
        (e, se.hypot((1.0 + e) * rel))
    };
    let (e, se) = excess(fin, &used);
    let both: Vec<usize> = used
        .iter()
        .copied()
        .filter(|&k| base[k].is_some())
        .collect();
    let (eb, seb) = excess(base, &both);
    // fraction removed: 1 − Σ(χ²_fin − d)/Σ(χ²_base − d), ratio σ over windows
    let (mut fraction, mut fraction_sigma) = (None, None);
    if eb.is_finite() && eb >= REMAINDER_Z * seb && both.len() >= 2 {
        if let Some((r, sr)) = fraction_removed(base, base, fin, &floors) {
            fraction = Some(r);
            fraction_sigma = Some(sr);
        }
    }
    let info: Vec<WinInfo> = wins
        .iter()
        .map(|w| win_info(runs, w, delta, rest))
        .collect();
    let total_excess: f64 = used.iter().filter_map(|&k| Some(fin[k]? - dof(k))).sum();
    let groups = remainder_groups(runs, &info, &used);
    let mut bins = Vec::new();
    for (group, members) in groups {
        for (bin, idx) in members {
            let (be, bse) = excess(fin, &idx);
            let ex: f64 = idx.iter().filter_map(|&k| Some(fin[k]? - dof(k))).sum();
            bins.push(RemainderBin {
                group: group.to_string(),
                bin,
                windows: idx.len(),
                excess_chi2_per_dof: be,
                excess_sigma: bse,
                share: if total_excess > 0.0 {
                    ex / total_excess
                } else {
                    f64::NAN
                },
            });
        }
    }
    let within_noise = !(e.is_finite() && e >= REMAINDER_Z * se);
    let mut located: Vec<RemainderBin> = if within_noise {
        vec![]
    } else {
        bins.iter()
            .filter(|b| {
                b.excess_sigma > 0.0 && b.excess_chi2_per_dof >= REMAINDER_Z * b.excess_sigma
            })
            .cloned()
            .collect()
    };
    located.sort_by(|a, b| b.share.total_cmp(&a.share));
    let dependence = dependence(&bins);
    let rem = Remainder {
        excess_chi2_per_dof: e,
        excess_sigma: se,
        base_excess_chi2_per_dof: eb,
        base_excess_sigma: seb,
        fraction_removed: fraction,
        fraction_removed_sigma: fraction_sigma,
        within_noise,
        windows: used.len(),
        bins,
        located,
        noise: Some(noise),
        dependence,
    };
    Some((rem, floors))
}

/// What the remainder depends on: for each grouping of `bins` with at least two bins with a σ,
/// the heterogeneity Q = Σ_b (E_b − Ē)²/σ_b² (Ē the inverse-variance mean of the bins' excesses)
/// against χ²(bins − 1), as a normal deviate by the Wilson–Hilferty transform
/// z = ((Q/ν)^{1/3} − (1 − 2/9ν)) / √(2/9ν); significant at [`super::judge::z_threshold`] for the
/// number of groupings tested. Largest z first.
pub fn dependence(bins: &[RemainderBin]) -> Vec<Dependence> {
    let mut groups: Vec<&str> = Vec::new();
    for b in bins {
        if !groups.contains(&b.group.as_str()) {
            groups.push(&b.group);
        }
    }
    let tests: Vec<Dependence> = groups
        .iter()
        .filter_map(|g| {
            let members: Vec<&RemainderBin> = bins
                .iter()
                .filter(|b| {
                    b.group == *g && b.excess_sigma > 0.0 && b.excess_chi2_per_dof.is_finite()
                })
                .collect();
            heterogeneity(g, &members)
        })
        .collect();
    let crit = super::judge::z_threshold(tests.len());
    let mut tests: Vec<Dependence> = tests
        .into_iter()
        .map(|d| Dependence {
            significant: d.z >= crit,
            ..d
        })
        .collect();
    tests.sort_by(|a, b| b.z.total_cmp(&a.z));
    tests
}

/// The heterogeneity test of one grouping's bins (see [`dependence`]); `None` with fewer than two.
fn heterogeneity(group: &str, members: &[&RemainderBin]) -> Option<Dependence> {
    if members.len() < 2 {
        return None;
    }
    let w = |b: &RemainderBin| 1.0 / (b.excess_sigma * b.excess_sigma);
    let sw: f64 = members.iter().map(|b| w(b)).sum();
    let mean = members
        .iter()
        .map(|b| w(b) * b.excess_chi2_per_dof)
        .sum::<f64>()
        / sw;
    let q: f64 = members
        .iter()
        .map(|b| w(b) * (b.excess_chi2_per_dof - mean).powi(2))
        .sum();
    let nu = (members.len() - 1) as f64;
    let a = 2.0 / (9.0 * nu);
    let z = ((q / nu).cbrt() - (1.0 - a)) / a.sqrt();
    let peak = members
        .iter()
        .max_by(|a, b| a.excess_chi2_per_dof.total_cmp(&b.excess_chi2_per_dof))?;
    Some(Dependence {
        variable: group.to_string(),
        bins: members.len(),
        chi2: q,
        dof: members.len() - 1,
        z,
        significant: false,
        peak_bin: peak.bin.clone(),
        peak_excess_chi2_per_dof: peak.excess_chi2_per_dof,
        peak_excess_sigma: peak.excess_sigma,
        experiment: dependence_experiment(group).to_string(),
    })
}

/// The experiment that tells apart the causes of a remainder that depends on `group`.
fn dependence_experiment(group: &str) -> &'static str {
    match group {
        "run_kind" => "compare ring-downs and driven runs at equal speeds: a remainder only in driven runs points to the input side (drive, coupling), one in both to the output's bearing or the camera",
        "drive_hz" => "repeat runs at the frequencies where it is largest and at their neighbours: an effect of the drive frequency (frame resonance, eddy currents) changes smoothly with f, an accident of one run does not repeat",
        "beta_phase_deg" => "ring-downs with the input magnet removed, started at several output angles: a torque or friction fixed to the output angle stays; a distortion of the angle reading shows in stick phases too, as an offset that depends on β",
        "alpha_minus_beta_deg" => "driven runs at several shaft angles: a modulation of the coupling follows the relative angle α − β and scales with g",
        "speed_rad_s" => "ring-downs from several initial speeds: a drag or a Stribeck shape follows |β̇| in every kind of run",
        "torque_over_g" => "runs at several shaft angles transmit different torques at equal speeds: a friction that grows with the transmitted torque follows it",
        "stick_slip" => "long stick phases at several input angles: a breakaway or angle-dependent static friction moves the release angle",
        "run_order" => "repeat the first run at the end of the session: a drift (warming, wear) changes it, a fixed effect does not",
        _ => "",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bin(group: &str, label: &str, excess: f64, sigma: f64) -> RemainderBin {
        RemainderBin {
            group: group.into(),
            bin: label.into(),
            windows: 10,
            excess_chi2_per_dof: excess,
            excess_sigma: sigma,
            share: f64::NAN,
        }
    }

    /// Bins equal within their σ give Q near its degrees of freedom (z small); one bin far above
    /// the others makes the grouping significant and names that bin; the tests are ordered by z.
    #[test]
    fn the_dependence_test_finds_the_variable_whose_bins_differ() {
        let flat = [0.11, 0.09, 0.10, 0.12, 0.08, 0.10];
        let peaked = [0.02, 0.03, 1.50, 0.01, 0.02, 0.04];
        let mut bins = Vec::new();
        for (i, (&a, &b)) in flat.iter().zip(&peaked).enumerate() {
            bins.push(bin("speed_rad_s", &format!("s{i}"), a, 0.05));
            bins.push(bin("beta_phase_deg", &format!("b{i}"), b, 0.05));
        }
        let d = dependence(&bins);
        assert_eq!(d.len(), 2);
        assert_eq!(d[0].variable, "beta_phase_deg");
        assert!(d[0].significant && d[0].z > 10.0, "{:?}", d[0]);
        assert_eq!(d[0].peak_bin, "b2");
        assert_eq!(d[0].dof, 5);
        assert!(!d[1].significant && d[1].z < 1.0, "{:?}", d[1]);
        // Q of the flat bins: Σ (x − 0.1)²/0.05² = 0.001/0.0025
        assert!((d[1].chi2 - 0.4).abs() < 1e-12, "{}", d[1].chi2);
    }

    /// The fraction a step removed is the ratio of the χ² it removed to the base excess over the
    /// floor, on the windows all three models predicted; the whole chain adds up to the total.
    #[test]
    fn the_fraction_removed_is_the_share_of_the_base_excess() {
        let floors = vec![10.0; 4];
        let base = vec![Some(30.0), Some(20.0), Some(40.0), Some(30.0)];
        let mid = vec![Some(20.0), Some(15.0), Some(25.0), None];
        let fin = vec![Some(12.0), Some(11.0), Some(14.0), Some(12.0)];
        let (a, _) = fraction_removed(&base, &base, &mid, &floors).unwrap();
        // windows 0–2: removed 10 + 5 + 15 of 20 + 10 + 30
        assert!((a - 0.5).abs() < 1e-12, "{a}");
        let (b, _) = fraction_removed(&base, &mid, &fin, &floors).unwrap();
        assert!((b - 23.0 / 60.0).abs() < 1e-12, "{b}");
        let (all, s) = fraction_removed(&base, &base, &fin, &floors).unwrap();
        assert!(
            (all - (18.0 + 9.0 + 26.0 + 18.0) / 80.0).abs() < 1e-12,
            "{all}"
        );
        assert!(s > 0.0 && s < 0.1, "{s}");
        assert!(fraction_removed(&base, &mid, &fin, &floors[..1]).is_none());
    }
}
