//! Nonlinear least squares for the fits by simulation: the trust-region Levenberg–Marquardt of
//! [`crate::numerics::levenberg_marquardt`] with a finite-difference Jacobian (the residuals
//! come from simulations whose events make them only piecewise smooth), and the Gauss–Newton
//! covariance s²(JᵀJ)⁻¹ from the column-pivoted QR of J ([`crate::numerics::least_squares`]).

use crate::numerics::least_squares::{independent_columns, inverse_gram, DEFAULT_RCOND};
use crate::numerics::levenberg_marquardt::{minimize, LmOptions};
use faer::Mat;
use nalgebra::{DMatrix, DVector};

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
    let a = Mat::from_fn(j.nrows(), n, |i, k| j[(i, k)]);
    let inverse = independent_columns(&a, DEFAULT_RCOND).and_then(|keep| {
        let sub = Mat::from_fn(j.nrows(), keep.len(), |i, k| j[(i, keep[k])]);
        Ok((inverse_gram(&sub, DEFAULT_RCOND)?, keep))
    });
    let Ok((c, keep)) = inverse else {
        return DMatrix::from_diagonal_element(n, n, f64::INFINITY);
    };
    let mut cov = DMatrix::zeros(n, n);
    for k in (0..n).filter(|k| !keep.contains(k)) {
        cov[(k, k)] = f64::INFINITY;
    }
    for (a, &ka) in keep.iter().enumerate() {
        for (b, &kb) in keep.iter().enumerate() {
            cov[(ka, kb)] = c[(a, b)];
        }
    }
    cov
}

/// s²(JᵀJ)⁻¹ with s² = `rss`/(rows − columns) ([`gauss_newton_cov`]); an infinite variance stays
/// infinite for an exact fit (s² = 0).
pub fn scaled_cov(j: &DMatrix<f64>, rss: f64) -> DMatrix<f64> {
    let s2 = rss / j.nrows().saturating_sub(j.ncols()).max(1) as f64;
    gauss_newton_cov(j).map(|v| if v.is_infinite() { v } else { v * s2 })
}

/// The cluster-robust (sandwich) covariance of a least-squares fit whose residuals come in
/// clusters of rows that may be correlated within a cluster but not between clusters (CR2 of
/// Bell & McCaffrey, with centred scores):
///
/// C = A [Σ_c (s_c − s̄)(s_c − s̄)ᵀ] A,  A = (JᵀJ)⁻¹,
/// s_c = J_cᵀ (I − H_cc)^(−1/2) r_c,  H_cc = J_c A J_cᵀ,  s̄ = (1/G) Σ_c s_c,
///
/// J_c and r_c the rows `start..start + len` of cluster c = (start, len), G the number of
/// clusters. The meat estimates the variance of the score Jᵀr = Σ_c J_cᵀ r_c from the scatter of
/// the clusters' scores, so it carries any correlation and unequal variance within a cluster
/// and a misspecified model's excess scatter; (I − H_cc)^(−1/2) undoes the shrinkage of the
/// fitted residuals by the leverage of the cluster (unbiased for independent, equal-variance
/// residuals), and centring keeps a fit stopped short of its minimum (Jᵀr ≠ 0) from counting its
/// own gradient as scatter (at the minimum s̄ ≈ 0 and centring changes nothing). Computed on the columns scaled to unit norm (the sandwich is
/// equivariant under column scaling); a leverage eigenvalue is capped at 0.999 so that a cluster
/// that alone determines a direction gives a large, finite correction. Parameters that J cannot
/// determine ([`gauss_newton_cov`]) keep their infinite variance and no covariance. `None` for
/// fewer than two clusters or clusters outside J.
pub fn cluster_sandwich(
    jac: &DMatrix<f64>,
    resid: &[f64],
    clusters: &[(usize, usize)],
) -> Option<DMatrix<f64>> {
    let (m, n) = (jac.nrows(), jac.ncols());
    let g = clusters.len();
    if g < 2 || resid.len() != m || clusters.iter().any(|&(a, l)| a + l > m) {
        return None;
    }
    let gram = gauss_newton_cov(jac);
    let keep: Vec<usize> = (0..n).filter(|&k| gram[(k, k)].is_finite()).collect();
    let p = keep.len();
    let mut cov = DMatrix::zeros(n, n);
    for k in (0..n).filter(|k| !keep.contains(k)) {
        cov[(k, k)] = f64::INFINITY;
    }
    if p == 0 {
        return Some(cov);
    }
    // unit-norm columns: J_s = J S, A_s = S⁻¹ A S⁻¹
    let scale: Vec<f64> = keep
        .iter()
        .map(|&k| 1.0 / jac.column(k).norm().max(1e-300))
        .collect();
    let js = DMatrix::from_fn(m, p, |i, a| jac[(i, keep[a])] * scale[a]);
    let a_s = DMatrix::from_fn(p, p, |a, b| {
        gram[(keep[a], keep[b])] / (scale[a] * scale[b])
    });
    let half = sym_sqrt(&a_s);
    let mut scores = Vec::with_capacity(g);
    for &(start, len) in clusters {
        let jc = js.rows(start, len);
        let rc = DVector::from_column_slice(&resid[start..start + len]);
        // H_cc = B Bᵀ with B = J_c A^(1/2); its nonzero eigenpairs from BᵀB = V Λ Vᵀ
        let b = jc * &half;
        let e = (b.transpose() * &b).symmetric_eigen();
        let mut adj = rc.clone();
        for (i, &lam) in e.eigenvalues.iter().enumerate() {
            if lam <= 1e-14 {
                continue;
            }
            let u = &b * e.eigenvectors.column(i) / lam.sqrt();
            let f = 1.0 / (1.0 - lam.min(0.999)).sqrt() - 1.0;
            adj += &u * (f * u.dot(&rc));
        }
        scores.push(jc.transpose() * adj);
    }
    let mean = scores.iter().fold(DVector::zeros(p), |acc, s| acc + s) / g as f64;
    let mut meat = DMatrix::zeros(p, p);
    for s in &scores {
        let d = s - &mean;
        meat += &d * d.transpose();
    }
    let cs = &a_s * meat * &a_s;
    for (a, &ka) in keep.iter().enumerate() {
        for (b, &kb) in keep.iter().enumerate() {
            cov[(ka, kb)] = cs[(a, b)] * scale[a] * scale[b];
        }
    }
    Some(cov)
}

/// The larger of two covariances of the same estimate in every direction: with W the white-noise
/// (model-based) covariance and R the robust one, C = W^(1/2) U max(Λ, 1) Uᵀ W^(1/2), where
/// U Λ Uᵀ = W^(−1/2) R W^(−1/2) is R in the coordinates in which W is the identity. Then
/// C ⪰ W and C ⪰ R (Loewner order): every linear combination of the parameters gets the larger
/// of its two variances (the variance ratio max(λ, 1) along each of R's principal directions
/// relative to W). A robust covariance estimated from few effective clusters scatters about its
/// expectation and is biased low; where it falls below the covariance the camera noise alone
/// implies, that floor is kept (the rule "the larger of the conventional and the robust
/// standard error"). Computed on W's correlation scale. Entries that are not finite in either
/// (undetermined parameters) are infinite on the diagonal with no covariance. Also returns the
/// largest ratio max(λ, 1), how much C widens W.
pub fn covariance_floor(robust: &DMatrix<f64>, white: &DMatrix<f64>) -> (DMatrix<f64>, f64) {
    let n = white.nrows();
    let keep: Vec<usize> = (0..n)
        .filter(|&k| {
            let (w, r) = (white[(k, k)], robust[(k, k)]);
            w.is_finite() && r.is_finite() && w > 0.0 && r >= 0.0
        })
        .collect();
    let mut out = DMatrix::zeros(n, n);
    for k in (0..n).filter(|k| !keep.contains(k)) {
        out[(k, k)] = f64::INFINITY;
    }
    let p = keep.len();
    if p == 0 {
        return (out, 1.0);
    }
    let d: Vec<f64> = keep.iter().map(|&k| white[(k, k)].sqrt()).collect();
    let w = DMatrix::from_fn(p, p, |a, b| white[(keep[a], keep[b])] / (d[a] * d[b]));
    let r = DMatrix::from_fn(p, p, |a, b| robust[(keep[a], keep[b])] / (d[a] * d[b]));
    let e = w.symmetric_eigen();
    let floor = e.eigenvalues.max() * 1e-14;
    let root = |pow: f64| {
        let l = e.eigenvalues.map(|v| v.max(floor).powf(pow));
        &e.eigenvectors * DMatrix::from_diagonal(&l) * e.eigenvectors.transpose()
    };
    let (half, inv_half) = (root(0.5), root(-0.5));
    let rel = &inv_half * r * &inv_half;
    let re = (0.5 * (&rel + rel.transpose())).symmetric_eigen();
    let lam = re.eigenvalues.map(|v| v.max(1.0));
    let widest = lam.iter().copied().fold(1.0, f64::max);
    let c = &half
        * (&re.eigenvectors * DMatrix::from_diagonal(&lam) * re.eigenvectors.transpose())
        * &half;
    for a in 0..p {
        for b in 0..p {
            out[(keep[a], keep[b])] = c[(a, b)] * d[a] * d[b];
        }
    }
    (out, widest)
}

/// The symmetric square root of a symmetric positive semi-definite matrix (negative eigenvalues
/// from rounding taken as 0).
fn sym_sqrt(a: &DMatrix<f64>) -> DMatrix<f64> {
    let e = a.clone().symmetric_eigen();
    let d = DMatrix::from_diagonal(&e.eigenvalues.map(|l| l.max(0.0).sqrt()));
    &e.eigenvectors * d * e.eigenvectors.transpose()
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
    let jac = |p: &[f64], r: &[f64]| fd_jacobian(f, p, r, steps, forward);
    least_squares_with_jacobian(f, &jac, p0, patience, tol)
}

/// Minimises Σ r(p)² from `p0` with the Jacobian `jac(p, r(p))` of the caller (e.g. the
/// variable-projection Jacobian of the refit by simulation,
/// [`super::shooting`]); `patience` and `tol` as [`least_squares_tol`]. The residuals and the
/// Jacobian are evaluated once more at the solution (a residual function with state, such as
/// warm starts, ends on the solution), and the covariance is s²(JᵀJ)⁻¹ of that Jacobian.
pub fn least_squares_with_jacobian<F, J>(
    f: &F,
    jac: &J,
    p0: &[f64],
    patience: usize,
    tol: Option<(f64, f64)>,
) -> Option<LsqFit>
where
    F: Fn(&[f64]) -> Option<Vec<f64>>,
    J: Fn(&[f64], &[f64]) -> Option<DMatrix<f64>>,
{
    let n = p0.len();
    let mut opts = LmOptions {
        max_evaluations: patience.max(1) * (n + 1),
        ..LmOptions::default()
    };
    if let Some((ftol, xtol)) = tol {
        opts.ftol = ftol;
        opts.xtol = xtol;
    }
    let sol = minimize(f, jac, p0, &opts).ok()?;
    let (m, p) = (sol.resid.len(), sol.x);
    if m <= n {
        return None;
    }
    let resid = f(&p)?;
    let rss: f64 = resid.iter().map(|r| r * r).sum();
    let j = jac(&p, &resid)?;
    let cov = scaled_cov(&j, rss);
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
pub(crate) mod tests {
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

    /// Deterministic N(0, 1)-like numbers: sums of 12 uniforms of a linear congruential
    /// generator, minus 6 (also the noise of the shooting module's tests).
    pub(crate) fn normals(n: usize, seed: u64) -> Vec<f64> {
        let mut s = seed;
        (0..n)
            .map(|_| {
                (0..12)
                    .map(|_| {
                        s = s
                            .wrapping_mul(6364136223846793005)
                            .wrapping_add(1442695040888963407);
                        (s >> 11) as f64 / (1u64 << 53) as f64
                    })
                    .sum::<f64>()
                    - 6.0
            })
            .collect()
    }

    /// The mean of n numbers with every row its own cluster: the sandwich is then HC2, which
    /// equals the classical s²/n exactly (Σe²/(1 − 1/n)/n² = Σe²/(n(n − 1))).
    #[test]
    fn sandwich_of_a_mean_with_single_row_clusters_is_the_classical_variance() {
        let y = [1.3, -0.2, 2.7, 0.9, 1.1, -1.4, 0.35, 2.2, 0.0, 1.05];
        let n = y.len();
        let m = y.iter().sum::<f64>() / n as f64;
        let resid: Vec<f64> = y.iter().map(|v| m - v).collect();
        let j = DMatrix::from_element(n, 1, 1.0);
        let clusters: Vec<(usize, usize)> = (0..n).map(|i| (i, 1)).collect();
        let c = cluster_sandwich(&j, &resid, &clusters).unwrap();
        let classical = resid.iter().map(|e| e * e).sum::<f64>() / (n * (n - 1)) as f64;
        assert!(
            (c[(0, 0)] - classical).abs() < 1e-12 * classical,
            "{} vs {classical}",
            c[(0, 0)]
        );
        // fewer than two clusters, or clusters outside J: no covariance
        assert!(cluster_sandwich(&j, &resid, &[(0, n)]).is_none());
        assert!(cluster_sandwich(&j, &resid, &[(0, 5), (5, 6)]).is_none());
    }

    /// A straight line fitted to 40 clusters of 20 rows whose noise is AR(1) within a cluster
    /// (ρ = 0.7, unit variance; independent between clusters): over 2000 noise realisations the
    /// mean sandwich variance of the slope matches the slope's observed variance (±10 %, three
    /// times the Monte Carlo error of the observed variance), while the classical s²(JᵀJ)⁻¹ is
    /// several times too small (the correlation the sandwich is for).
    #[test]
    fn sandwich_matches_the_observed_variance_under_correlated_noise() {
        let (g, len, reps) = (40usize, 20usize, 2000usize);
        let m = g * len;
        let u = |i: usize| -1.0 + 2.0 * (i % len) as f64 / (len - 1) as f64;
        let j = DMatrix::from_fn(m, 2, |i, k| if k == 0 { 1.0 } else { u(i) });
        let gram_inv = (j.transpose() * &j).try_inverse().unwrap();
        let clusters: Vec<(usize, usize)> = (0..g).map(|c| (c * len, len)).collect();
        let rho: f64 = 0.7;
        let (mut slopes, mut sand, mut classical) = (Vec::new(), 0.0, 0.0);
        for r in 0..reps {
            let z = normals(m, 1000 + r as u64);
            let mut y = vec![0.0; m];
            for c in 0..g {
                let mut e = z[c * len];
                for i in 0..len {
                    if i > 0 {
                        e = rho * e + (1.0 - rho * rho).sqrt() * z[c * len + i];
                    }
                    y[c * len + i] = 0.5 + 2.0 * u(c * len + i) + e;
                }
            }
            let yv = DVector::from_column_slice(&y);
            let beta = &gram_inv * (j.transpose() * &yv);
            let resid: Vec<f64> = (&j * &beta - &yv).iter().copied().collect();
            let rss: f64 = resid.iter().map(|e| e * e).sum();
            slopes.push(beta[1]);
            sand += cluster_sandwich(&j, &resid, &clusters).unwrap()[(1, 1)] / reps as f64;
            classical += rss / (m - 2) as f64 * gram_inv[(1, 1)] / reps as f64;
        }
        let mean = slopes.iter().sum::<f64>() / reps as f64;
        let observed = slopes.iter().map(|b| (b - mean).powi(2)).sum::<f64>() / (reps - 1) as f64;
        assert!(
            (sand / observed - 1.0).abs() < 0.1,
            "sandwich {sand:.3e} vs observed {observed:.3e}"
        );
        assert!(classical < 0.5 * observed, "classical {classical:.3e}");
    }

    /// The floor in closed form where W and R commute (both diagonal: each variance is the
    /// larger of the two), a uniform scale (R = 2W gives 2W, R = W/2 gives W), and in general
    /// C − W and C − R positive semi-definite.
    #[test]
    fn covariance_floor_takes_the_larger_variance_in_every_direction() {
        let w = DMatrix::from_row_slice(2, 2, &[4.0, 0.0, 0.0, 1e-6]);
        let r = DMatrix::from_row_slice(2, 2, &[9.0, 0.0, 0.0, 2.5e-7]);
        let (c, widest) = covariance_floor(&r, &w);
        assert!((c[(0, 0)] - 9.0).abs() < 1e-12 && (c[(1, 1)] - 1e-6).abs() < 1e-18);
        assert!(c[(0, 1)].abs() < 1e-15 && (widest - 2.25).abs() < 1e-12);
        let w = DMatrix::from_row_slice(2, 2, &[2.0, 0.9, 0.9, 1.0]);
        let (c, _) = covariance_floor(&(&w * 2.0), &w);
        assert!((c - &w * 2.0).norm() < 1e-12);
        let (c, widest) = covariance_floor(&(&w * 0.5), &w);
        assert!((c - &w).norm() < 1e-12 && widest == 1.0);
        let r = DMatrix::from_row_slice(2, 2, &[1.0, -0.3, -0.3, 3.0]);
        let (c, _) = covariance_floor(&r, &w);
        for other in [&w, &r] {
            let m = &c - other;
            let min = m.symmetric_eigen().eigenvalues.min();
            assert!(min > -1e-12, "{min}");
        }
        // an undetermined parameter stays infinite, without NaN
        let mut wi = w.clone();
        wi[(1, 1)] = f64::INFINITY;
        wi[(0, 1)] = 0.0;
        wi[(1, 0)] = 0.0;
        let (c, _) = covariance_floor(&r, &wi);
        assert!(c[(1, 1)].is_infinite() && !c.iter().any(|v| v.is_nan()));
        assert!((c[(0, 0)] - 2.0).abs() < 1e-12);
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
