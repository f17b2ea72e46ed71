//! Nonlinear least squares for the fits by simulation: the trust-region Levenberg–Marquardt of
//! [`crate::numerics::levenberg_marquardt`] with a finite-difference Jacobian (the residuals
//! come from simulations whose events make them only piecewise smooth), and the Gauss–Newton
//! covariance s²(JᵀJ)⁻¹ from the column-pivoted QR of J ([`crate::numerics::least_squares`]).

use crate::numerics::least_squares::{inverse_gram, LeastSquaresError, DEFAULT_RCOND};
use crate::numerics::levenberg_marquardt::{minimize, LmOptions};
use faer::Mat;
use nalgebra::DMatrix;

/// Result of a least-squares fit.
#[derive(Debug, Clone, PartialEq)]
pub struct LsqFit {
    /// Parameters.
    pub p: Vec<f64>,
    /// Residuals at the solution.
    pub resid: Vec<f64>,
    /// Covariance s²(JᵀJ)⁻¹ with s² = RSS/(n − p) (not yet corrected for correlated residuals).
    /// A parameter that J cannot determine (a dependent column of J) has an infinite variance
    /// and no covariance with the others: it is held, not estimated.
    pub cov: DMatrix<f64>,
    /// Residual sum of squares.
    pub rss: f64,
    /// Whether the optimiser converged (rather than spent its evaluations).
    pub converged: bool,
    /// Jacobian of the residuals at the solution (finite differences), rows × parameters.
    pub jac: DMatrix<f64>,
}

/// Finite-difference Jacobian of `f` at `p` with relative steps `steps`: central, or forward
/// from the residuals `r0` at p (one evaluation per parameter).
pub fn fd_jacobian<F: Fn(&[f64]) -> Option<Vec<f64>>>(
    f: &F,
    p: &[f64],
    r0: &[f64],
    steps: &[f64],
    forward: bool,
) -> Option<DMatrix<f64>> {
    let (m, n) = (r0.len(), p.len());
    let mut j = DMatrix::zeros(m, n);
    let mut q = p.to_vec();
    for k in 0..n {
        let h = steps[k] * p[k].abs().max(1.0);
        q[k] = p[k] + h;
        let rp = f(&q)?;
        let (rm, den) = if forward {
            (r0.to_vec(), h)
        } else {
            q[k] = p[k] - h;
            (f(&q)?, 2.0 * h)
        };
        q[k] = p[k];
        if rp.len() != m || rm.len() != m {
            return None;
        }
        for i in 0..m {
            j[(i, k)] = (rp[i] - rm[i]) / den;
        }
    }
    Some(j)
}

/// (JᵀJ)⁻¹ by QR; the dependent columns of a rank-deficient J get an infinite variance and the
/// others the inverse of their own Gram matrix.
pub fn gauss_newton_cov(j: &DMatrix<f64>) -> DMatrix<f64> {
    let n = j.ncols();
    let mut keep: Vec<usize> = (0..n).collect();
    loop {
        let a = Mat::from_fn(j.nrows(), keep.len(), |i, k| j[(i, keep[k])]);
        match inverse_gram(&a, DEFAULT_RCOND) {
            Ok(c) => {
                let mut cov = DMatrix::zeros(n, n);
                for k in 0..n {
                    if !keep.contains(&k) {
                        cov[(k, k)] = f64::INFINITY;
                    }
                }
                for (a, &ka) in keep.iter().enumerate() {
                    for (b, &kb) in keep.iter().enumerate() {
                        cov[(ka, kb)] = c[(a, b)];
                    }
                }
                return cov;
            }
            Err(LeastSquaresError::RankDeficient { dependent, .. }) if !dependent.is_empty() => {
                let drop: Vec<usize> = dependent.iter().map(|&d| keep[d]).collect();
                keep.retain(|k| !drop.contains(k));
            }
            Err(_) => return DMatrix::from_diagonal_element(n, n, f64::INFINITY),
        }
    }
}

/// Minimises Σ r(p)² from `p0`; `steps` are the relative finite-difference steps per parameter,
/// `patience` sets the evaluation budget to patience·(parameters + 1). `None` when the residuals
/// cannot be evaluated at `p0` or there are not more residuals than parameters.
pub fn least_squares<F: Fn(&[f64]) -> Option<Vec<f64>>>(
    f: &F,
    p0: &[f64],
    steps: &[f64],
    patience: usize,
) -> Option<LsqFit> {
    least_squares_tol(f, p0, steps, patience, None, false)
}

/// [`least_squares`] with the optimiser's relative tolerances (ftol, xtol) set: looser ones stop
/// earlier when every residual evaluation is expensive and the start is already close; `forward`:
/// forward differences (one evaluation per parameter, with the residual at p evaluated once per
/// Jacobian) instead of central ones.
pub fn least_squares_tol<F: Fn(&[f64]) -> Option<Vec<f64>>>(
    f: &F,
    p0: &[f64],
    steps: &[f64],
    patience: usize,
    tol: Option<(f64, f64)>,
    forward: bool,
) -> Option<LsqFit> {
    let n = p0.len();
    let mut opts = LmOptions {
        max_evaluations: patience.max(1) * (n + 1),
        ..LmOptions::default()
    };
    if let Some((ftol, xtol)) = tol {
        opts.ftol = ftol;
        opts.xtol = xtol;
    }
    let jac = |p: &[f64], r: &[f64]| fd_jacobian(f, p, r, steps, forward);
    let sol = minimize(f, jac, p0, &opts).ok()?;
    let (m, p) = (sol.resid.len(), sol.x);
    if m <= n {
        return None;
    }
    // the residuals once more at the solution: a residual function with state (warm starts)
    // ends on the solution
    let resid = f(&p)?;
    let rss: f64 = resid.iter().map(|r| r * r).sum();
    let j = fd_jacobian(f, &p, &resid, steps, forward)?;
    let s2 = rss / (m - n) as f64;
    // an infinite variance stays infinite for an exact fit (s² = 0)
    let cov = gauss_newton_cov(&j).map(|v| if v.is_infinite() { v } else { v * s2 });
    Some(LsqFit {
        p,
        resid,
        cov,
        rss,
        converged: sol.termination.converged(),
        jac: j,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fits_an_exponential_with_its_covariance() {
        // y = 2 e^{−0.7 t} + noise-free: the fit is exact; the covariance of an exactly linear
        // model (a straight line) equals s²(XᵀX)⁻¹ in closed form
        let t: Vec<f64> = (0..50).map(|i| i as f64 * 0.1).collect();
        let y: Vec<f64> = t.iter().map(|t| 2.0 * (-0.7 * t).exp()).collect();
        let f = |p: &[f64]| {
            Some(
                t.iter()
                    .zip(&y)
                    .map(|(t, y)| p[0] * (-p[1] * t).exp() - y)
                    .collect(),
            )
        };
        let fit = least_squares(&f, &[1.0, 0.3], &[1e-6, 1e-6], 200).unwrap();
        assert!((fit.p[0] - 2.0).abs() < 1e-10 && (fit.p[1] - 0.7).abs() < 1e-10);
        // line a + b t through y_i = 1 + 0.5 t_i + (−1)^i 0.1
        let yl: Vec<f64> = (0..50)
            .map(|i| 1.0 + 0.5 * t[i] + if i % 2 == 0 { 0.1 } else { -0.1 })
            .collect();
        let g = |p: &[f64]| Some((0..50).map(|i| p[0] + p[1] * t[i] - yl[i]).collect());
        let fit = least_squares(&g, &[0.0, 0.0], &[1e-6, 1e-6], 200).unwrap();
        let (n, st, stt) = (
            50.0,
            t.iter().sum::<f64>(),
            t.iter().map(|x| x * x).sum::<f64>(),
        );
        let det = n * stt - st * st;
        let s2 = fit.rss / 48.0;
        assert!((fit.cov[(1, 1)] - s2 * n / det).abs() < 1e-9 * s2 * n / det);
        assert!((fit.cov[(0, 1)] + s2 * st / det).abs() < 1e-9 * s2 * st / det);
    }

    #[test]
    fn an_undetermined_parameter_gets_an_infinite_variance_not_a_nan() {
        let f = |p: &[f64]| Some((0..10).map(|i| p[0] * i as f64 - 2.0 * i as f64).collect());
        // p[1] does not enter the residuals
        let g = |p: &[f64]| f(&p[..1]);
        let fit = least_squares(&g, &[1.0, 5.0], &[1e-6, 1e-6], 50).unwrap();
        assert!((fit.p[0] - 2.0).abs() < 1e-10);
        assert!(fit.cov[(1, 1)].is_infinite() && !fit.cov.iter().any(|v| v.is_nan()));
    }
}
