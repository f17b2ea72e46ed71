//! Cleaning a run before it is fitted: outlier frames are *rejected* (leave-one-out local cubic
//! prediction, robust MAD scale, the largest local excess removed first, iterated), the rejected
//! frame becomes a gap; the camera noise σ_β is estimated from the same prediction errors; the
//! velocity is estimated by a local polynomial (Savitzky–Golay-type, on the real sample times, so
//! gaps are handled).

use crate::io::recordings::Run;
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

/// Leave-one-out prediction error of sample i from kept neighbours within `reach` intervals.
fn loo_residual(t: &[f64], b: &[f64], keep: &[bool], i: usize, dt: f64) -> Option<(f64, f64)> {
    let reach = 3.5 * dt;
    let mut xs = Vec::new();
    let mut ys = Vec::new();
    let lo = i.saturating_sub(6);
    let hi = (i + 7).min(t.len());
    for j in lo..hi {
        if j != i && keep[j] && (t[j] - t[i]).abs() <= reach {
            xs.push(t[j] - t[i]);
            ys.push(b[j]);
        }
    }
    if xs.len() < 4 || !xs.iter().any(|&x| x < 0.0) || !xs.iter().any(|&x| x > 0.0) {
        return None;
    }
    let deg = if xs.len() >= 6 { 3 } else { 2 };
    let w = poly_weights(&xs, deg, 0)?;
    let pred: f64 = w.iter().zip(&ys).map(|(a, b)| a * b).sum();
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
}
