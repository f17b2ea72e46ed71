//! Cleaning a run before it is fitted: outlier frames are *rejected* (leave-one-out local cubic
//! prediction, robust MAD scale, the largest local excess removed first, iterated), the rejected
//! frame becomes a gap; the camera noise σ_β is estimated from the same prediction errors; the
//! velocity is estimated by a local polynomial (Savitzky–Golay-type, on the real sample times, so
//! gaps are handled).

use crate::io::recordings::Run;
use crate::numerics::least_squares::{weighted, DEFAULT_RCOND};
use nalgebra::DMatrix;

/// A cleaned run.
#[derive(Debug, Clone, PartialEq)]
pub struct CleanRun {
    /// Times of the kept samples.
    pub t: Vec<f64>,
    /// α at kept samples.
    pub alpha: Vec<f64>,
    /// β at kept samples.
    pub beta: Vec<f64>,
    /// Local-polynomial velocity estimate.
    pub v: Vec<f64>,
    /// Median sample interval.
    pub dt: f64,
    /// Number of rejected outlier frames.
    pub outliers: usize,
    /// Estimated camera noise σ_β, rad.
    pub sigma_beta: f64,
    /// Camera noise of the set, rad (the per-run estimate until the set's is known).
    pub sigma_camera: f64,
    /// Noise gain of the velocity estimator: σ_v = gain · σ_β.
    pub v_gain: f64,
    /// α̇ (0 for ring-downs).
    pub alpha_rate: f64,
    /// Whether it is a ring-down.
    pub ringdown: bool,
}

/// Least-squares polynomial of degree `deg` through (x_j, y_j); returns the linear weights w_j such
/// that p^(d)(0) = Σ w_j y_j for derivative order `d` (0 or 1). `None` when ill-posed.
pub fn poly_weights(x: &[f64], deg: usize, d: usize) -> Option<Vec<f64>> {
    let n = x.len();
    let m = deg + 1;
    if n < m {
        return None;
    }
    let scale = x.iter().fold(0.0f64, |a, &b| a.max(b.abs())).max(1e-300);
    let a = DMatrix::from_fn(n, m, |i, k| (x[i] / scale).powi(k as i32));
    // row d of the pseudo-inverse A⁺ = R⁻¹Qᵀ (thin QR, no normal equations): w = Q R⁻ᵀ e_d,
    // times d!/scale^d
    let qr = a.qr();
    let r = qr.r();
    let rmax = (0..m).map(|k| r[(k, k)].abs()).fold(0.0, f64::max);
    if rmax.is_nan() || (0..m).any(|k| r[(k, k)].abs() <= 1e-12 * rmax) {
        return None;
    }
    let mut ed = nalgebra::DVector::zeros(m);
    ed[d] = 1.0;
    let z = r.transpose().solve_lower_triangular(&ed)?;
    let w = qr.q() * z;
    let fact = if d == 1 { 1.0 / scale } else { 1.0 };
    Some((0..n).map(|j| w[j] * fact).collect())
}

fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(|a, b| a.total_cmp(b));
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Median sample interval of a time series.
pub fn median_dt(t: &[f64]) -> f64 {
    let mut d: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    median(&mut d)
}

/// The cleaning's leave-one-out predictor of sample i: the kept neighbours within 3.5 intervals
/// (at most 6 samples either side, at least one on each side and 4 in all) and the weights w_j of
/// the local cubic (quadratic below 6 neighbours) through them at t_i, so that the prediction is
/// Σ_j w_j β_j.
fn loo_weights(t: &[f64], keep: &[bool], i: usize, dt: f64) -> Option<(Vec<usize>, Vec<f64>)> {
    let reach = 3.5 * dt;
    let lo = i.saturating_sub(6);
    let hi = (i + 7).min(t.len());
    let idx: Vec<usize> = (lo..hi)
        .filter(|&j| j != i && keep[j] && (t[j] - t[i]).abs() <= reach)
        .collect();
    let xs: Vec<f64> = idx.iter().map(|&j| t[j] - t[i]).collect();
    if xs.len() < 4 || !xs.iter().any(|&x| x < 0.0) || !xs.iter().any(|&x| x > 0.0) {
        return None;
    }
    let deg = if xs.len() >= 6 { 3 } else { 2 };
    Some((idx, poly_weights(&xs, deg, 0)?))
}

/// Leave-one-out prediction error of sample i from kept neighbours within `reach` intervals.
fn loo_residual(t: &[f64], b: &[f64], keep: &[bool], i: usize, dt: f64) -> Option<(f64, f64)> {
    let (idx, w) = loo_weights(t, keep, i, dt)?;
    let pred: f64 = w.iter().zip(&idx).map(|(a, &j)| a * b[j]).sum();
    let gain = 1.0 + w.iter().map(|x| x * x).sum::<f64>();
    Some((b[i] - pred, gain))
}

/// Cleans a run: outlier rejection, noise estimate, velocity. `noise_hint` (rad) overrides the
/// noise estimate when the set-up states it.
pub fn clean(run: &Run, noise_hint: Option<f64>) -> CleanRun {
    let n = run.t.len();
    let dt = median_dt(&run.t).max(1e-9);
    let mut keep = vec![true; n];
    let mut outliers = 0;
    let mut sigma = noise_hint.unwrap_or(0.0);
    for _pass in 0..20 {
        let res: Vec<Option<(f64, f64)>> = (0..n)
            .map(|i| {
                if keep[i] {
                    loo_residual(&run.t, &run.beta, &keep, i, dt)
                } else {
                    None
                }
            })
            .collect();
        let mut abs: Vec<f64> = res.iter().flatten().map(|r| r.0.abs()).collect();
        if abs.len() < 8 {
            break;
        }
        let scale = 1.4826 * median(&mut abs);
        let mut gains: Vec<f64> = res.iter().flatten().map(|r| r.1).collect();
        let gain = median(&mut gains).max(1.0);
        if noise_hint.is_none() {
            sigma = scale / gain.sqrt();
        }
        let thr = 6.0 * scale.max(1e-9);
        let mut flagged = 0;
        for i in 0..n {
            let Some((r, _)) = res[i] else { continue };
            if r.abs() <= thr {
                continue;
            }
            let lo = i.saturating_sub(3);
            let hi = (i + 4).min(n);
            let is_max =
                (lo..hi).all(|j| j == i || res[j].map(|x| x.0.abs()).unwrap_or(0.0) <= r.abs());
            if is_max {
                keep[i] = false;
                flagged += 1;
            }
        }
        outliers += flagged;
        if flagged == 0 {
            break;
        }
    }
    let idx: Vec<usize> = (0..n).filter(|&i| keep[i]).collect();
    let t: Vec<f64> = idx.iter().map(|&i| run.t[i]).collect();
    let alpha: Vec<f64> = idx.iter().map(|&i| run.alpha[i]).collect();
    let beta: Vec<f64> = idx.iter().map(|&i| run.beta[i]).collect();
    let (v, v_gain) = velocity(&t, &beta, dt);
    CleanRun {
        t,
        alpha,
        beta,
        v,
        dt,
        outliers,
        sigma_beta: sigma.max(1e-6),
        sigma_camera: sigma.max(1e-6),
        v_gain,
        alpha_rate: run.alpha_rate(),
        ringdown: run.is_ringdown(),
    }
}

/// Local cubic velocity over ±3 intervals (real times); returns the velocities and the median
/// noise gain √Σw².
pub fn velocity(t: &[f64], b: &[f64], dt: f64) -> (Vec<f64>, f64) {
    let n = t.len();
    let mut v = vec![0.0; n];
    let mut gains = Vec::new();
    for i in 0..n {
        let lo = i.saturating_sub(3);
        let hi = (i + 4).min(n);
        let mut xs = Vec::new();
        let mut ys = Vec::new();
        for j in lo..hi {
            if (t[j] - t[i]).abs() <= 3.5 * dt {
                xs.push(t[j] - t[i]);
                ys.push(b[j]);
            }
        }
        let deg = if xs.len() >= 6 {
            3
        } else if xs.len() >= 4 {
            2
        } else {
            1
        };
        if let Some(w) = poly_weights(&xs, deg, 1) {
            v[i] = w.iter().zip(&ys).map(|(a, b)| a * b).sum();
            gains.push(w.iter().map(|x| x * x).sum::<f64>().sqrt());
        } else if i > 0 {
            v[i] = v[i - 1];
        }
    }
    (v, median(&mut gains))
}

/// A stretch of frames at rest: the output does not move, so β is a constant plus the camera
/// noise. `frames` are camera frame numbers (increasing; a missing number is a rejected frame),
/// `beta` the angles there.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RestPiece {
    /// Frame numbers, increasing.
    pub frames: Vec<i64>,
    /// β at those frames, rad.
    pub beta: Vec<f64>,
}

/// Longest span (in frames) of a piece in [`rest_autocovariance`]: longer stretches are cut into
/// pieces of this span, each with its own mean, which are the jackknife's units. Four prediction
/// windows ([`super::predict::WINDOW`]): long against the lags the windows need (< 30), so the
/// mean removed per piece costs little.
pub const REST_PIECE_SPAN: i64 = 4 * super::predict::WINDOW as i64;

/// The camera noise's autocovariance measured at rest ([`rest_autocovariance`]).
#[derive(Debug, Clone, PartialEq)]
pub struct RestAutocov {
    /// γ(k) for the frame lags k = 0 … L, rad² (γ(k) beyond L taken as 0).
    pub gamma: Vec<f64>,
    /// The same without each piece in turn (leave-one-piece-out), for the jackknife.
    pub jackknife: Vec<Vec<f64>>,
    /// Pieces used (the jackknife's units).
    pub pieces: usize,
    /// Frames at rest used.
    pub frames: usize,
}

impl RestAutocov {
    /// Jackknife 1σ of a function of γ: √((P−1)/P Σ_p (f(γ_(−p)) − f̄)²).
    pub fn sigma_of(&self, f: impl Fn(&[f64]) -> f64) -> f64 {
        let v: Vec<f64> = self.jackknife.iter().map(|g| f(g)).collect();
        let p = v.len() as f64;
        let mean = v.iter().sum::<f64>() / p;
        ((p - 1.0) / p * v.iter().map(|x| (x - mean).powi(2)).sum::<f64>()).sqrt()
    }
    /// The correlation ρ(k) = γ(k)/γ(0), k = 0 … L.
    pub fn correlation(&self) -> Vec<f64> {
        self.gamma.iter().map(|g| g / self.gamma[0]).collect()
    }
}

/// Moment sums of one piece at the lags 0 … `lmax`: S(k) = Σ over the pairs (i ≤ j) at frame lag k
/// of r_i r_j (r = β minus the piece's mean) and the matrix A with E[S(k)] = Σ_l A(k, l) γ(l).
/// With u_i(l) the frames of the piece at lag l from frame i (u_i(0) = 1), U(l) = Σ_i u_i(l) and m
/// frames, E[r_i r_j] = γ(|f_i − f_j|) − Σ_l γ(l)(u_i(l) + u_j(l))/m + Σ_l γ(l) U(l)/m² (the mean's
/// part, exact for a stationary noise); lags beyond `lmax` enter as γ = 0. Returns (A row-major,
/// S).
fn piece_moments(p: &RestPiece, lmax: usize) -> (Vec<f64>, Vec<f64>) {
    let nl = lmax + 1;
    let (mut a, mut s) = (vec![0.0; nl * nl], vec![0.0; nl]);
    let m = p.frames.len();
    if m < 2 {
        return (a, s);
    }
    let f0 = p.frames[0];
    let span = (p.frames[m - 1] - f0) as usize;
    let mut pos = vec![usize::MAX; span + 1];
    for (i, &f) in p.frames.iter().enumerate() {
        pos[(f - f0) as usize] = i;
    }
    let at = |o: i64| -> Option<usize> {
        if o >= 0 && o as usize <= span && pos[o as usize] != usize::MAX {
            Some(pos[o as usize])
        } else {
            None
        }
    };
    let mf = m as f64;
    let mean = p.beta.iter().sum::<f64>() / mf;
    let r: Vec<f64> = p.beta.iter().map(|b| b - mean).collect();
    let off: Vec<i64> = p.frames.iter().map(|f| f - f0).collect();
    // u[i * nl + l]
    let mut u = vec![0.0; m * nl];
    for i in 0..m {
        u[i * nl] = 1.0;
        for l in 1..nl {
            let li = l as i64;
            u[i * nl + l] =
                at(off[i] - li).is_some() as u8 as f64 + at(off[i] + li).is_some() as u8 as f64;
        }
    }
    let big_u: Vec<f64> = (0..nl)
        .map(|l| (0..m).map(|i| u[i * nl + l]).sum())
        .collect();
    for k in 0..nl {
        for i in 0..m {
            let Some(j) = at(off[i] + k as i64) else {
                continue;
            };
            s[k] += r[i] * r[j];
            for l in 0..nl {
                let d = if k == l { 1.0 } else { 0.0 };
                a[k * nl + l] += d - (u[i * nl + l] + u[j * nl + l]) / mf + big_u[l] / (mf * mf);
            }
        }
    }
    (a, s)
}

/// Solves A γ = S (A: `n`×`n` row-major); `None` when singular.
fn solve_moments(a: &[f64], s: &[f64], n: usize) -> Option<Vec<f64>> {
    let am = DMatrix::from_row_slice(n, n, a);
    let x = am.lu().solve(&nalgebra::DVector::from_column_slice(s))?;
    x.iter()
        .all(|v| v.is_finite())
        .then(|| x.iter().copied().collect())
}

/// Drops the pieces whose spread is an outlier among the pieces: ln of a piece's variance about
/// its mean beyond the median by more than 6 robust σ (1.4826 MAD) of these logs, the cleaning's
/// rule (step 2 of the pipeline). A piece the model holds stuck while the output still moves
/// (a stick phase the model predicts and the data do not have) has a variance many times the
/// camera noise's; pieces of noise alone scatter by √(2/(m − 1)) in ln variance, more for a
/// correlated noise, which the MAD carries.
fn reject_moving_pieces(pieces: &mut Vec<RestPiece>) {
    let logv: Vec<f64> = pieces
        .iter()
        .map(|p| {
            let m = p.beta.len() as f64;
            let mean = p.beta.iter().sum::<f64>() / m;
            let v = p.beta.iter().map(|b| (b - mean).powi(2)).sum::<f64>() / (m - 1.0);
            v.max(1e-300).ln()
        })
        .collect();
    if logv.len() < 3 {
        return;
    }
    let mut sorted = logv.clone();
    let med = median(&mut sorted);
    let mut dev: Vec<f64> = logv.iter().map(|l| (l - med).abs()).collect();
    let scale = 1.4826 * median(&mut dev);
    if scale > 0.0 {
        let mut k = 0;
        pieces.retain(|_| {
            k += 1;
            logv[k - 1] <= med + 6.0 * scale
        });
    }
}

/// The autocovariance γ(k) of the camera noise at the frame lags k = 0 … L from frames at rest,
/// with no model of its form: the moment equations E[S(k)] = Σ_l A(k, l) γ(l) of every piece
/// ([`piece_moments`]: sample products at lag k with the piece's mean removed, and the exact
/// effect of that removal) are summed over the pieces and solved, so γ is unbiased for any
/// stationary noise whose correlation vanishes beyond L. Pieces spanning more than
/// [`REST_PIECE_SPAN`] frames are cut. L is `max_lag`, or less: at most half the longest piece's
/// span (the lags beyond L anchor the level the mean removal leaves free), and only lags that
/// two pieces carry (the jackknife leaves one out). `None` when fewer than two pieces of two frames
/// remain or the lags 0 and 1 cannot be solved.
pub fn rest_autocovariance(pieces: &[RestPiece], max_lag: usize) -> Option<RestAutocov> {
    let mut cut: Vec<RestPiece> = Vec::new();
    for p in pieces {
        let mut cur = RestPiece::default();
        for (&f, &b) in p.frames.iter().zip(&p.beta) {
            if cur
                .frames
                .first()
                .is_some_and(|&f0| f - f0 >= REST_PIECE_SPAN)
            {
                cut.push(std::mem::take(&mut cur));
            }
            cur.frames.push(f);
            cur.beta.push(b);
        }
        cut.push(cur);
    }
    cut.retain(|p| p.frames.len() >= 2);
    reject_moving_pieces(&mut cut);
    if cut.len() < 2 {
        return None;
    }
    // L: at most half the longest piece's span, so that pairs at lags beyond L (where γ is
    // taken as 0) fix the level that the removal of each piece's mean leaves undetermined (a
    // covariance constant over every lag of a piece is a random offset, which the mean removes);
    // and every lag up to L has pairs in at least two pieces
    let longest = cut
        .iter()
        .map(|p| (p.frames[p.frames.len() - 1] - p.frames[0]) as usize)
        .max()
        .unwrap_or(0);
    let mut lmax = 0;
    while lmax < max_lag.min(longest / 2) {
        let k = (lmax + 1) as i64;
        let carrying = cut
            .iter()
            .filter(|p| {
                p.frames
                    .iter()
                    .any(|f| p.frames.binary_search(&(f + k)).is_ok())
            })
            .count();
        if carrying < 2 {
            break;
        }
        lmax += 1;
    }
    if lmax < 1 {
        return None;
    }
    let nl = lmax + 1;
    let parts: Vec<(Vec<f64>, Vec<f64>)> = cut.iter().map(|p| piece_moments(p, lmax)).collect();
    let mut a = vec![0.0; nl * nl];
    let mut s = vec![0.0; nl];
    for (pa, ps) in &parts {
        a.iter_mut().zip(pa).for_each(|(x, y)| *x += y);
        s.iter_mut().zip(ps).for_each(|(x, y)| *x += y);
    }
    let gamma = solve_moments(&a, &s, nl)?;
    let mut jackknife = Vec::with_capacity(parts.len());
    for (pa, ps) in &parts {
        let a1: Vec<f64> = a.iter().zip(pa).map(|(x, y)| x - y).collect();
        let s1: Vec<f64> = s.iter().zip(ps).map(|(x, y)| x - y).collect();
        jackknife.push(solve_moments(&a1, &s1, nl)?);
    }
    Some(RestAutocov {
        gamma,
        jackknife,
        pieces: cut.len(),
        frames: cut.iter().map(|p| p.frames.len()).sum(),
    })
}

/// A stretch of samples in motion for [`speed_noise`]: the measured β, a smooth reference motion
/// through it (the final model's simulated output) and that reference's velocity β̇.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SpeedPiece {
    /// Sample times, s (nominal: a timing error is in β).
    pub t: Vec<f64>,
    /// Measured β, rad.
    pub beta: Vec<f64>,
    /// Whether a sample is used.
    pub keep: Vec<bool>,
    /// The reference β at `t`, rad.
    pub reference: Vec<f64>,
    /// The reference's β̇ at `t`, rad/s.
    pub speed: Vec<f64>,
}

/// A white noise whose variance grows with the speed, measured by [`speed_noise`]: per sample
/// Var = σ_β² + σ_t² β̇², the part σ_t² β̇² of a timing jitter of σ_t (or of any error that grows
/// as |β̇|).
#[derive(Debug, Clone, PartialEq)]
pub struct SpeedNoise {
    /// σ_t², s² (may come out negative: an estimate, not clipped).
    pub timing_var: f64,
    /// The same without each piece in turn (leave-one-piece-out), for the jackknife.
    pub jackknife: Vec<f64>,
    /// The speed-free white variance σ_β² of the same fit, rad².
    pub white_var: f64,
    /// Samples used.
    pub samples: usize,
    /// Pieces used (the jackknife's units).
    pub pieces: usize,
}

impl SpeedNoise {
    /// Jackknife 1σ of σ_t²: √((P−1)/P Σ_p (σ_t²_(−p) − mean)²).
    pub fn timing_var_sigma(&self) -> f64 {
        let p = self.jackknife.len() as f64;
        let mean = self.jackknife.iter().sum::<f64>() / p;
        ((p - 1.0) / p
            * self
                .jackknife
                .iter()
                .map(|x| (x - mean).powi(2))
                .sum::<f64>())
        .sqrt()
    }
}

/// One row of the regression in [`speed_noise`]: (piece, e², g, q).
type SpeedRow = (usize, f64, f64, f64);

/// The rows of [`speed_noise`]: per sample with a leave-one-out predictor ([`loo_weights`]) the
/// squared prediction error e² of d = β − reference and its factors g = 1 + Σw_j² and
/// q = β̇_i² + Σ w_j² β̇_j².
fn speed_rows(pieces: &[SpeedPiece]) -> Vec<SpeedRow> {
    let mut rows = Vec::new();
    for (p, pc) in pieces.iter().enumerate() {
        let n = pc.t.len();
        if n < 5 || pc.beta.len() != n || pc.keep.len() != n {
            continue;
        }
        if pc.reference.len() != n || pc.speed.len() != n {
            continue;
        }
        let dt = median_dt(&pc.t).max(1e-12);
        let d: Vec<f64> = pc
            .beta
            .iter()
            .zip(&pc.reference)
            .map(|(b, r)| b - r)
            .collect();
        for i in 0..n {
            if !pc.keep[i] {
                continue;
            }
            let Some((idx, w)) = loo_weights(&pc.t, &pc.keep, i, dt) else {
                continue;
            };
            let e = d[i] - w.iter().zip(&idx).map(|(a, &j)| a * d[j]).sum::<f64>();
            let g = 1.0 + w.iter().map(|x| x * x).sum::<f64>();
            let q = pc.speed[i].powi(2)
                + w.iter()
                    .zip(&idx)
                    .map(|(a, &j)| a * a * pc.speed[j].powi(2))
                    .sum::<f64>();
            if e.is_finite() && q.is_finite() {
                rows.push((p, e * e, g, q));
            }
        }
    }
    rows
}

/// A speed-dependent white noise, model-free: the cleaning's leave-one-out cubic (step 2 of the
/// pipeline) predicts every sample of d = β − reference from its neighbours; for a white error
/// ε_i of variance σ_β² + σ_t² β̇_i² (a camera noise plus a timing jitter δt_i, ε = β̇ δt) the
/// prediction error e_i = d_i − Σ_j w_j d_j has the exact expectation
/// E[e_i²] = σ_β² (1 + Σ_j w_j²) + σ_t² (β̇_i² + Σ_j w_j² β̇_j²) = σ_β² g_i + σ_t² q_i
/// (the weights w of the predictor, docs/diagnosis.md), a linear regression of e² on (g, q)
/// without intercept. The reference removes the cubic's truncation error on the motion itself
/// (0.64 dt⁴ β⁗ on a full stencil), which grows with the speed of fast motion; what the
/// reference misses enters only through the cubic's high-pass, and a correlation of the camera
/// noise enters the σ_β² term (a level the speed does not change). Weighted least squares (QR,
/// `numerics::least_squares::weighted`) with
/// weights 1/(σ_β² g + σ_t² q)² (the variance of a squared Gaussian, up to the factor 2),
/// iterated from the speed-free fit; a row with e² beyond 36 times its expectation is dropped
/// (the cleaning's 6σ rule: a spike the reference does not follow, e.g. a release it misplaces).
/// σ is the jackknife over the pieces. `None` with fewer than two pieces or 10 rows, or a
/// singular fit.
pub fn speed_noise(pieces: &[SpeedPiece]) -> Option<SpeedNoise> {
    let rows = speed_rows(pieces);
    // (σ_β², σ_t²) by weighted least squares (QR) over the rows `sel`, row variances `var`
    let fit = |sel: &[usize], var: &dyn Fn(usize) -> f64| -> Option<(f64, f64)> {
        let f = weighted(
            sel,
            2,
            |i, j| if j == 0 { rows[i].2 } else { rows[i].3 },
            |i| rows[i].1,
            |i| 1.0 / var(i).powi(2),
            DEFAULT_RCOND,
        )
        .ok()?;
        (f.x[0].is_finite() && f.x[1].is_finite()).then_some((f.x[0], f.x[1]))
    };
    let mut sel: Vec<usize> = (0..rows.len()).collect();
    let (mut a, mut s) = fit(&sel, &|i| rows[i].2)?;
    let (mut va, mut vs) = (a, s);
    for _ in 1..5 {
        (va, vs) = (a.max(1e-300), s.max(0.0));
        let var = |i: usize| va * rows[i].2 + vs * rows[i].3;
        sel = (0..rows.len())
            .filter(|&i| rows[i].1 <= 36.0 * var(i))
            .collect();
        (a, s) = fit(&sel, &var)?;
    }
    let var = |i: usize| va * rows[i].2 + vs * rows[i].3;
    let mut units: Vec<usize> = sel.iter().map(|&i| rows[i].0).collect();
    units.dedup();
    if units.len() < 2 || sel.len() < 10 {
        return None;
    }
    let jackknife = units
        .iter()
        .map(|&p| {
            let rest: Vec<usize> = sel.iter().copied().filter(|&i| rows[i].0 != p).collect();
            fit(&rest, &var).map(|x| x.1)
        })
        .collect::<Option<Vec<f64>>>()?;
    Some(SpeedNoise {
        timing_var: s,
        jackknife,
        white_var: a,
        samples: sel.len(),
        pieces: units.len(),
    })
}

#[cfg(test)]
impl CleanRun {
    /// A clean ring-down (locked input at α = 0, velocity estimate 0, camera noise 0.01 rad) of
    /// the angles `beta` at the times `t`, frame interval `dt`: the unit tests' runs.
    pub(crate) fn test_ringdown(t: Vec<f64>, beta: Vec<f64>, dt: f64) -> Self {
        Self {
            alpha: vec![0.0; t.len()],
            v: vec![0.0; t.len()],
            t,
            beta,
            dt,
            outliers: 0,
            sigma_beta: 0.01,
            sigma_camera: 0.01,
            v_gain: 1.0,
            alpha_rate: 0.0,
            ringdown: true,
        }
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn polynomial_weights_reproduce_a_cubic_and_its_slope() {
        // uneven abscissae around 0; y = 0.4 − 1.5x + 0.8x² + 2x³: p(0) = 0.4, p'(0) = −1.5
        let x = [-0.031, -0.019, -0.01, 0.012, 0.02, 0.033, 0.041];
        let y: Vec<f64> = x
            .iter()
            .map(|x| 0.4 - 1.5 * x + 0.8 * x * x + 2.0 * x * x * x)
            .collect();
        for (d, want) in [(0, 0.4), (1, -1.5)] {
            let w = super::poly_weights(&x, 3, d).unwrap();
            let got: f64 = w.iter().zip(&y).map(|(a, b)| a * b).sum();
            assert!((got - want).abs() < 1e-11, "d = {d}: {got}");
        }
        // three distinct points cannot carry a cubic
        assert!(super::poly_weights(&x[..3], 3, 0).is_none());
    }

    /// AR(1) pieces: `count` stretches of `len` frames with stationary σ² = 1 and coefficient
    /// `rho`, every 7th frame of odd pieces missing (a rejected frame).
    fn ar1_pieces(
        rho: f64,
        count: usize,
        len: i64,
        rng: &mut crate::campaign::rng::Rng,
    ) -> Vec<super::RestPiece> {
        (0..count)
            .map(|p| {
                let mut e = rng.normal();
                let mut out = super::RestPiece::default();
                for f in 0..len {
                    if f > 0 {
                        e = rho * e + (1.0 - rho * rho).sqrt() * rng.normal();
                    }
                    if p % 2 == 1 && f % 7 == 3 {
                        continue;
                    }
                    out.frames.push(1000 * p as i64 + f);
                    out.beta.push(0.3 * p as f64 + e);
                }
                out
            })
            .collect()
    }

    /// The moment matrix of a piece is exact: for a stationary covariance Γ (AR(1), ρ = 0.8, a
    /// piece with missing frames), E[S(k)] computed by brute force from the covariance of the
    /// residuals about the mean, (I − P)Γ(I − P), equals Σ_l A(k, l) γ(l) when every lag of the
    /// piece is modelled.
    #[test]
    fn rest_moments_match_the_brute_force_expectation() {
        let frames: Vec<i64> = vec![0, 1, 2, 4, 5, 6, 7, 9, 12, 13, 14];
        let piece = super::RestPiece {
            frames: frames.clone(),
            beta: vec![0.0; frames.len()],
        };
        let rho: f64 = 0.8;
        let span = 14;
        let (a, _) = super::piece_moments(&piece, span);
        let m = frames.len();
        let g = |i: usize, j: usize| rho.powi((frames[i] - frames[j]).abs() as i32);
        // C = (I − P)Γ(I − P), P = 11ᵀ/m
        let row: Vec<f64> = (0..m)
            .map(|i| (0..m).map(|j| g(i, j)).sum::<f64>() / m as f64)
            .collect();
        let all: f64 = row.iter().sum::<f64>() / m as f64;
        let c = |i: usize, j: usize| g(i, j) - row[i] - row[j] + all;
        let nl = span + 1;
        for k in 0..nl {
            let want: f64 = (0..m)
                .flat_map(|i| (0..m).map(move |j| (i, j)))
                .filter(|&(i, j)| frames[j] - frames[i] == k as i64)
                .map(|(i, j)| c(i, j))
                .sum();
            let got: f64 = (0..nl).map(|l| a[k * nl + l] * rho.powi(l as i32)).sum();
            assert!((got - want).abs() < 1e-12, "lag {k}: {got} vs {want}");
        }
    }

    /// The estimator against exact AR(1) values γ(k) = σ²ρ^k (σ = 1), ρ = 0.3, 0.7, 0.9: 24
    /// pieces of 120 frames (every 7th frame of half of them missing), each with its own offset.
    /// γ(0) and ρ(1), ρ(2), ρ(5) lie within 3.5 of their jackknife σ (a fixed seed; the σ is
    /// checked for calibration below).
    #[test]
    fn rest_autocovariance_recovers_ar1() {
        let mut rng = crate::campaign::rng::Rng::new(7, 11);
        for rho in [0.3, 0.7, 0.9] {
            let pieces = ar1_pieces(rho, 24, 120, &mut rng);
            let ac = super::rest_autocovariance(&pieces, 40).unwrap();
            assert_eq!(ac.pieces, 24);
            assert_eq!(ac.gamma.len(), 41);
            let s0 = ac.sigma_of(|g| g[0]);
            assert!(
                (ac.gamma[0] - 1.0).abs() < 3.5 * s0,
                "ρ = {rho}: γ(0) = {} ± {s0}",
                ac.gamma[0]
            );
            let r = ac.correlation();
            for k in [1usize, 2, 5] {
                let sk = ac.sigma_of(|g| g[k] / g[0]);
                let want = rho.powi(k as i32);
                assert!(
                    (r[k] - want).abs() < 3.5 * sk,
                    "ρ = {rho}, lag {k}: {} ± {sk} vs {want}",
                    r[k]
                );
            }
        }
    }

    /// Unbiased, with an honest σ: over 200 sets of AR(1) noise (ρ = 0.7, 16 pieces of 100
    /// frames) the mean of γ̂(0) is within 3 standard errors of σ² = 1, and the spread of
    /// (γ̂(0) − 1)/σ_jackknife is 1 within its sampling error (0.85 … 1.2 for 200 sets and 16
    /// jackknife units).
    #[test]
    fn rest_autocovariance_sigma_is_calibrated() {
        let mut rng = crate::campaign::rng::Rng::new(3, 5);
        let (mut z, mut g0) = (Vec::new(), Vec::new());
        for _ in 0..200 {
            let pieces = ar1_pieces(0.7, 16, 100, &mut rng);
            let ac = super::rest_autocovariance(&pieces, 30).unwrap();
            let s = ac.sigma_of(|g| g[0]);
            z.push((ac.gamma[0] - 1.0) / s);
            g0.push(ac.gamma[0]);
        }
        let n = g0.len() as f64;
        let mean = g0.iter().sum::<f64>() / n;
        let sd = (g0.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        assert!(
            (mean - 1.0).abs() < 3.0 * sd / n.sqrt(),
            "mean γ(0) = {mean} (sd {sd})"
        );
        let zsd = (z.iter().map(|x| x * x).sum::<f64>() / n).sqrt();
        assert!((0.85..1.2).contains(&zsd), "rms z = {zsd}");
    }

    /// Too few frames at rest: no estimate (the caller falls back to white noise).
    #[test]
    fn rest_autocovariance_needs_two_pieces() {
        let one = vec![super::RestPiece {
            frames: (0..50).collect(),
            beta: (0..50).map(|i| (i as f64 * 0.7).sin()).collect(),
        }];
        assert!(super::rest_autocovariance(&one, 20).is_none());
        assert!(super::rest_autocovariance(&[], 20).is_none());
    }
    /// `count` pieces of 30 samples of β = A sin(ωt) + B sin(3ωt) (A = 1.5 rad, B = 0.3 rad,
    /// ω = 2π·1.5 /s, peak speed about 18 rad/s) taken at t_k + δ_k (δ Gaussian, σ `jitter`) plus a
    /// white camera noise of σ 0.5°, recorded at the nominal t_k = k·`dt`; the reference is the
    /// motion at t_k and its velocity, every 11th sample masked.
    fn jittered_sines(
        jitter: f64,
        dt: f64,
        count: usize,
        rng: &mut crate::campaign::rng::Rng,
    ) -> Vec<super::SpeedPiece> {
        let w = std::f64::consts::TAU * 1.5;
        let f = |t: f64| 1.5 * (w * t).sin() + 0.3 * (3.0 * w * t).sin();
        let fd = |t: f64| 1.5 * w * (w * t).cos() + 0.9 * w * (3.0 * w * t).cos();
        (0..count)
            .map(|p| {
                let mut pc = super::SpeedPiece::default();
                for k in 0..30 {
                    let t = (40 * p + k) as f64 * dt;
                    pc.t.push(t);
                    pc.beta
                        .push(f(t + jitter * rng.normal()) + 0.5f64.to_radians() * rng.normal());
                    pc.keep.push(k % 11 != 5);
                    pc.reference.push(f(t));
                    pc.speed.push(fd(t));
                }
                pc
            })
            .collect()
    }

    /// The speed-dependent noise recovers a known timing jitter: σ_t = 0.5 ms (the campaign's
    /// control) and 1 ms at 50 frames/s, and 0 without jitter, also at 20 frames/s where the
    /// cubic's truncation error on the motion is many times the noise (the reference removes it).
    /// Over 40 seeds each, z = (σ_t² − truth)/σ has a mean within 3 standard errors of 0 (no
    /// bias), an rms in 0.75 … 1.3 (the σ is right: the sampling range of an rms of 40) and no
    /// |z| above 4.5 (a gross failure); the white σ is the camera's within 10 %.
    #[test]
    fn speed_noise_recovers_timing_jitter() {
        let mut rng = crate::campaign::rng::Rng::new(17, 3);
        for (jitter, dt) in [(0.5e-3, 0.02), (1e-3, 0.02), (0.0, 0.02), (0.0, 0.05)] {
            let mut z = Vec::new();
            for _ in 0..40 {
                let pieces = jittered_sines(jitter, dt, 60, &mut rng);
                let sn = super::speed_noise(&pieces).unwrap();
                let sg = sn.timing_var_sigma();
                let zz = (sn.timing_var - jitter * jitter) / sg;
                assert!(
                    zz.abs() < 4.5,
                    "σ_t = {jitter}, dt = {dt}: σ_t² = {:e} ± {sg:e}",
                    sn.timing_var
                );
                let sb = (sn.white_var.sqrt() / 0.5f64.to_radians() - 1.0).abs();
                assert!(sb < 0.1, "σ_β off by {sb}");
                z.push(zz);
            }
            let n = z.len() as f64;
            let mean = z.iter().sum::<f64>() / n;
            let rms = (z.iter().map(|x| x * x).sum::<f64>() / n).sqrt();
            assert!(
                (0.75..1.3).contains(&rms),
                "σ_t = {jitter}, dt = {dt}: rms z = {rms}"
            );
            assert!(
                mean.abs() < 3.0 * rms / n.sqrt(),
                "σ_t = {jitter}, dt = {dt}: mean z = {mean}"
            );
        }
    }

    /// Too little to go on: no estimate.
    #[test]
    fn speed_noise_needs_two_pieces() {
        let mut rng = crate::campaign::rng::Rng::new(1, 1);
        let one = jittered_sines(0.0, 0.02, 1, &mut rng);
        assert!(super::speed_noise(&one).is_none());
        assert!(super::speed_noise(&[]).is_none());
    }
}
