//! Nonlinear least squares through the `levenberg-marquardt` crate (built on nalgebra 0.34; the
//! parameters and residuals cross the boundary as slices), with a central finite-difference
//! Jacobian (the residuals come from simulations whose events make them only piecewise smooth).

use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt};
use nalgebra::DMatrix;
use nalgebra034 as na34;

/// Result of a least-squares fit.
#[derive(Debug, Clone, PartialEq)]
pub struct LsqFit {
    /// Parameters.
    pub p: Vec<f64>,
    /// Residuals at the solution.
    pub resid: Vec<f64>,
    /// Covariance s²(JᵀJ)⁻¹ with s² = RSS/(n − p) (not yet corrected for correlated residuals).
    pub cov: DMatrix<f64>,
    /// Residual sum of squares.
    pub rss: f64,
    /// Whether the optimiser reported success.
    pub converged: bool,
    /// Jacobian of the residuals at the solution (central differences), rows × parameters.
    pub jac: DMatrix<f64>,
}

struct Problem<'a, F: Fn(&[f64]) -> Option<Vec<f64>>> {
    f: &'a F,
    p: na34::DVector<f64>,
    steps: Vec<f64>,
    m: usize,
    forward: bool,
}

impl<F: Fn(&[f64]) -> Option<Vec<f64>>> Problem<'_, F> {
    fn jac(&self, p: &[f64]) -> Option<DMatrix<f64>> {
        let n = p.len();
        let mut j = DMatrix::zeros(self.m, n);
        let mut q = p.to_vec();
        let r0 = if self.forward {
            Some((self.f)(p)?)
        } else {
            None
        };
        for k in 0..n {
            let h = self.steps[k] * p[k].abs().max(1.0);
            q[k] = p[k] + h;
            let rp = (self.f)(&q)?;
            let (rm, den) = if let Some(r0) = &r0 {
                (r0.clone(), h)
            } else {
                q[k] = p[k] - h;
                ((self.f)(&q)?, 2.0 * h)
            };
            q[k] = p[k];
            if rp.len() != self.m || rm.len() != self.m {
                return None;
            }
            for i in 0..self.m {
                j[(i, k)] = (rp[i] - rm[i]) / den;
            }
        }
        Some(j)
    }
}

impl<F: Fn(&[f64]) -> Option<Vec<f64>>> LeastSquaresProblem<f64, na34::Dyn, na34::Dyn>
    for Problem<'_, F>
{
    type ResidualStorage = na34::VecStorage<f64, na34::Dyn, na34::U1>;
    type JacobianStorage = na34::VecStorage<f64, na34::Dyn, na34::Dyn>;
    type ParameterStorage = na34::VecStorage<f64, na34::Dyn, na34::U1>;

    fn set_params(&mut self, x: &na34::DVector<f64>) {
        self.p.copy_from(x);
    }
    fn params(&self) -> na34::DVector<f64> {
        self.p.clone()
    }
    fn residuals(&self) -> Option<na34::DVector<f64>> {
        let r = (self.f)(self.p.as_slice())?;
        if r.len() != self.m || r.iter().any(|v| !v.is_finite()) {
            return None;
        }
        Some(na34::DVector::from_vec(r))
    }
    fn jacobian(&self) -> Option<na34::DMatrix<f64>> {
        let j = self.jac(self.p.as_slice())?;
        Some(na34::DMatrix::from_column_slice(
            j.nrows(),
            j.ncols(),
            j.as_slice(),
        ))
    }
}

/// Minimises Σ r(p)² from `p0`; `steps` are the relative finite-difference steps per parameter.
/// `None` when the residuals cannot be evaluated at `p0`.
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
    let r0 = f(p0)?;
    let m = r0.len();
    let n = p0.len();
    if m <= n {
        return None;
    }
    let prob = Problem {
        f,
        p: na34::DVector::from_column_slice(p0),
        steps: steps.to_vec(),
        m,
        forward,
    };
    let mut lm = LevenbergMarquardt::new().with_patience(patience);
    if let Some((ftol, xtol)) = tol {
        lm = lm.with_ftol(ftol).with_xtol(xtol);
    }
    let (prob, report) = lm.minimize(prob);
    let p: Vec<f64> = prob.p.as_slice().to_vec();
    let resid = f(&p)?;
    let rss: f64 = resid.iter().map(|r| r * r).sum();
    let j = prob.jac(&p)?;
    let jtj = j.transpose() * &j;
    let s: Vec<f64> = (0..n)
        .map(|k| 1.0 / jtj[(k, k)].abs().sqrt().max(1e-300))
        .collect();
    let sj = DMatrix::from_fn(n, n, |a, b| jtj[(a, b)] * s[a] * s[b]);
    let inv = sj
        .try_inverse()
        .unwrap_or_else(|| DMatrix::from_element(n, n, f64::NAN));
    let s2 = rss / (m - n) as f64;
    let cov = DMatrix::from_fn(n, n, |a, b| inv[(a, b)] * s[a] * s[b] * s2);
    Some(LsqFit {
        p,
        resid,
        cov,
        rss,
        converged: report.termination.was_successful(),
        jac: j,
    })
}

#[cfg(test)]
mod tests {
    #[test]
    fn fits_an_exponential() {
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
        let fit = super::least_squares(&f, &[1.0, 0.3], &[1e-6, 1e-6], 200).unwrap();
        assert!((fit.p[0] - 2.0).abs() < 1e-6 && (fit.p[1] - 0.7).abs() < 1e-6);
    }
}
