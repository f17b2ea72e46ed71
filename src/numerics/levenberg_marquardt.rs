//! Levenberg–Marquardt for min ½‖r(x)‖² as a trust-region method (Moré 1978, the MINPACK
//! `lmder` logic), with the subproblem solved on faer.
//!
//! Each iteration takes the Jacobian J at x, the scaling D = diag(max over the iterations of
//! ‖J e_j‖) and the trust radius Δ, and solves
//!
//!   min_p ‖J p + r‖² + λ‖D p‖²,   λ ≥ 0 the smallest with ‖D p‖ ≤ Δ,
//!
//! in the scaled variable u = D p: the QR factorisation of [J D⁻¹ | r] gives R and Qᵀr, the SVD
//! R = U Σ Vᵀ then makes ‖u(λ)‖ = ‖diag(σᵢ/(σᵢ² + λ)) Uᵀ Qᵀ r‖ a closed form, and λ is found from
//! the secular equation 1/‖u(λ)‖ = 1/Δ by a safeguarded Newton iteration (relative tolerance
//! 0.1, as Moré). A singular J is no exception: directions with σᵢ ≤ n·ε·σ₁ are left out of the
//! Gauss–Newton step (minimum-norm step). The ratio ρ of the actual to the predicted reduction
//! updates Δ (ρ < ¼: shrink, ρ > ¾: expand) and accepts the step when ρ ≥ 10⁻⁴. A trial point
//! whose residuals cannot be evaluated counts as a failed step (Δ shrinks).
//!
//! Termination as MINPACK: `ftol` on the actual and predicted relative reductions of ‖r‖², `xtol`
//! on Δ relative to ‖D x‖, `gtol` on the cosine between r and the columns of J, or the number of
//! residual evaluations.

use super::least_squares::thin_r;
use faer::Mat;
use nalgebra::DMatrix;
use thiserror::Error;

/// Options of [`minimize`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LmOptions {
    /// Relative reduction of ‖r‖² (actual and predicted) below which the fit has converged.
    pub ftol: f64,
    /// Relative size of the trust region (Δ/‖D x‖) below which the fit has converged.
    pub xtol: f64,
    /// Largest cosine between r and a column of J at which the fit has converged.
    pub gtol: f64,
    /// Most residual evaluations (the start included; Jacobians are not counted).
    pub max_evaluations: usize,
    /// Initial trust radius relative to ‖D x₀‖ (or absolute when x₀ = 0).
    pub stepbound: f64,
}

impl Default for LmOptions {
    fn default() -> Self {
        Self {
            ftol: 30.0 * f64::EPSILON,
            xtol: 30.0 * f64::EPSILON,
            gtol: 30.0 * f64::EPSILON,
            max_evaluations: 100,
            stepbound: 100.0,
        }
    }
}

/// Why [`minimize`] stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Termination {
    /// The relative reduction (`ftol`) and/or the trust region (`xtol`) became small.
    Converged {
        /// The `ftol` test passed.
        ftol: bool,
        /// The `xtol` test passed.
        xtol: bool,
    },
    /// r is orthogonal to the columns of J to `gtol`.
    Orthogonal,
    /// The residuals are zero.
    ResidualsZero,
    /// No further reduction is possible in floating point.
    NoImprovementPossible,
    /// The evaluation budget is spent.
    MaxEvaluations,
}

impl Termination {
    /// Whether the minimum was reached (rather than the budget spent).
    pub fn converged(&self) -> bool {
        !matches!(self, Termination::MaxEvaluations)
    }
}

/// Why [`minimize`] could not run.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum LmError {
    /// The residuals at the start are not finite or cannot be evaluated.
    #[error("Levenberg–Marquardt: the residuals cannot be evaluated at the start")]
    Start,
    /// The Jacobian cannot be evaluated or has the wrong shape or non-finite entries.
    #[error("Levenberg–Marquardt: the Jacobian cannot be evaluated")]
    Jacobian,
    /// Fewer residuals than parameters, or no parameters.
    #[error("Levenberg–Marquardt: {residuals} residuals for {params} parameters")]
    Shape {
        /// Residuals.
        residuals: usize,
        /// Parameters.
        params: usize,
    },
}

/// Result of [`minimize`].
#[derive(Debug, Clone, PartialEq)]
pub struct LmSolution {
    /// x at the end.
    pub x: Vec<f64>,
    /// r(x).
    pub resid: Vec<f64>,
    /// Residual evaluations made.
    pub evaluations: usize,
    /// Jacobians evaluated.
    pub jacobians: usize,
    /// Why it stopped.
    pub termination: Termination,
}

/// The trust-region subproblem of one Jacobian in the scaled variable u = D p.
struct Subproblem {
    /// Singular values of R (R from the QR of [J D⁻¹ | r]).
    sigma: Vec<f64>,
    /// Right singular vectors (columns).
    v: DMatrix<f64>,
    /// Uᵀ Qᵀ r.
    c: Vec<f64>,
}

impl Subproblem {
    fn new(j: &DMatrix<f64>, r: &[f64], d: &[f64]) -> Option<Self> {
        let (m, n) = j.shape();
        let aug = Mat::from_fn(m, n + 1, |i, k| if k < n { j[(i, k)] / d[k] } else { r[i] });
        let rr = thin_r(aug);
        let rmat = Mat::from_fn(n, n, |a, b| if b >= a { rr[(a, b)] } else { 0.0 });
        let svd = rmat.thin_svd().ok()?;
        let (u, s, vv) = (svd.U(), svd.S(), svd.V());
        let sigma: Vec<f64> = (0..n).map(|k| s[k]).collect();
        let c: Vec<f64> = (0..n)
            .map(|k| (0..n).map(|a| u[(a, k)] * rr[(a, n)]).sum())
            .collect();
        let v = DMatrix::from_fn(n, n, |a, b| vv[(a, b)]);
        let smax = sigma.iter().copied().fold(0.0, f64::max);
        let cut = n as f64 * f64::EPSILON * smax;
        let sigma = sigma
            .into_iter()
            .map(|s| if s > cut { s } else { 0.0 })
            .collect();
        Some(Self { sigma, v, c })
    }
    /// Components of Vᵀu(λ) = −σᵢcᵢ/(σᵢ² + λ).
    fn coords(&self, lambda: f64) -> Vec<f64> {
        self.sigma
            .iter()
            .zip(&self.c)
            .map(|(&s, &c)| {
                if s > 0.0 {
                    -s * c / (s * s + lambda)
                } else {
                    0.0
                }
            })
            .collect()
    }
    fn norm(&self, lambda: f64) -> f64 {
        self.coords(lambda)
            .iter()
            .map(|x| x * x)
            .sum::<f64>()
            .sqrt()
    }
    /// The smallest λ ≥ 0 with ‖u(λ)‖ ≤ 1.1 Δ, ‖u(λ)‖ ≥ 0.9 Δ when λ > 0 (Newton on
    /// 1/‖u(λ)‖ − 1/Δ, kept inside a bracket by bisection).
    fn lambda(&self, delta: f64) -> f64 {
        if self.norm(0.0) <= 1.1 * delta {
            return 0.0;
        }
        // ‖u(λ)‖ ≤ ‖Σc‖/λ: this λ is an upper bound
        let g = self
            .sigma
            .iter()
            .zip(&self.c)
            .map(|(s, c)| (s * c).powi(2))
            .sum::<f64>()
            .sqrt();
        let (mut lo, mut hi) = (0.0, g / delta);
        let mut lam = 0.0;
        for _ in 0..100 {
            let x = self.coords(lam);
            let nu = x.iter().map(|v| v * v).sum::<f64>().sqrt();
            if (nu - delta).abs() <= 0.1 * delta {
                return lam;
            }
            if nu > delta {
                lo = lam;
            } else {
                hi = lam;
            }
            // d‖u‖/dλ = −Σ xᵢ²/(σᵢ² + λ) / ‖u‖
            let dn = -self
                .sigma
                .iter()
                .zip(&x)
                .map(|(&s, &xi)| {
                    if s > 0.0 {
                        xi * xi / (s * s + lam)
                    } else {
                        0.0
                    }
                })
                .sum::<f64>()
                / nu.max(1e-300);
            // Newton on φ(λ) = 1/‖u‖ − 1/Δ: λ+ = λ − φ/φ', φ' = −‖u‖'/‖u‖²
            let next = lam - (1.0 / nu - 1.0 / delta) * nu * nu / (-dn).max(1e-300);
            lam = if next > lo && next < hi && next.is_finite() {
                next
            } else {
                0.5 * (lo + hi)
            };
        }
        lam
    }
    /// (p = D⁻¹u, ‖u‖, ‖J p‖) at λ.
    fn step(&self, lambda: f64, d: &[f64]) -> (Vec<f64>, f64, f64) {
        let x = self.coords(lambda);
        let n = d.len();
        let u: Vec<f64> = (0..n)
            .map(|a| (0..n).map(|k| self.v[(a, k)] * x[k]).sum())
            .collect();
        let unorm = x.iter().map(|v| v * v).sum::<f64>().sqrt();
        let jp = x
            .iter()
            .zip(&self.sigma)
            .map(|(x, s)| (x * s).powi(2))
            .sum::<f64>()
            .sqrt();
        ((0..n).map(|k| u[k] / d[k]).collect(), unorm, jp)
    }
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// The state of the iteration between Jacobians.
struct State {
    x: Vec<f64>,
    r: Vec<f64>,
    rnorm: f64,
    d: Vec<f64>,
    delta: f64,
    evaluations: usize,
    jacobians: usize,
}

/// Minimises ½‖r(x)‖² from `x0` (module docs). `residuals(x)` returns `None` where r cannot be
/// evaluated; `jacobian(x, r)` returns ∂r/∂x (rows × parameters) at x with r = r(x).
pub fn minimize(
    residuals: impl Fn(&[f64]) -> Option<Vec<f64>>,
    jacobian: impl Fn(&[f64], &[f64]) -> Option<DMatrix<f64>>,
    x0: &[f64],
    opts: &LmOptions,
) -> Result<LmSolution, LmError> {
    let r = residuals(x0).ok_or(LmError::Start)?;
    let (m, n) = (r.len(), x0.len());
    if n == 0 || m < n {
        return Err(LmError::Shape {
            residuals: m,
            params: n,
        });
    }
    if r.iter().any(|v| !v.is_finite()) {
        return Err(LmError::Start);
    }
    let rnorm = norm(&r);
    let mut st = State {
        x: x0.to_vec(),
        r,
        rnorm,
        d: vec![0.0; n],
        delta: 0.0,
        evaluations: 1,
        jacobians: 0,
    };
    let finish = |st: State, termination| LmSolution {
        x: st.x,
        resid: st.r,
        evaluations: st.evaluations,
        jacobians: st.jacobians,
        termination,
    };
    if st.rnorm == 0.0 {
        return Ok(finish(st, Termination::ResidualsZero));
    }
    loop {
        let j = jacobian(&st.x, &st.r).ok_or(LmError::Jacobian)?;
        st.jacobians += 1;
        if j.shape() != (m, n) || j.iter().any(|v| !v.is_finite()) {
            return Err(LmError::Jacobian);
        }
        match iterate(&residuals, &j, &mut st, opts) {
            Some(t) => return Ok(finish(st, t)),
            None => continue,
        }
    }
}

/// The trust-region iterations on one Jacobian: `None` after an accepted step (a new Jacobian is
/// needed), else why the minimisation stops.
fn iterate(
    residuals: &impl Fn(&[f64]) -> Option<Vec<f64>>,
    j: &DMatrix<f64>,
    st: &mut State,
    opts: &LmOptions,
) -> Option<Termination> {
    let n = st.x.len();
    let colnorm: Vec<f64> = (0..n).map(|k| j.column(k).norm()).collect();
    // scaled gradient: max_k |(Jᵀr)_k| / (‖J e_k‖ ‖r‖)
    let r = nalgebra::DVector::from_column_slice(&st.r);
    let gnorm = (0..n)
        .filter(|&k| colnorm[k] > 0.0)
        .map(|k| j.column(k).dot(&r).abs() / (colnorm[k] * st.rnorm))
        .fold(0.0, f64::max);
    if gnorm <= opts.gtol {
        return Some(Termination::Orthogonal);
    }
    let first = st.jacobians == 1;
    for (d, &c) in st.d.iter_mut().zip(&colnorm) {
        *d = if first {
            if c > 0.0 {
                c
            } else {
                1.0
            }
        } else {
            d.max(c)
        };
    }
    let dx = |x: &[f64], d: &[f64]| norm(&x.iter().zip(d).map(|(a, b)| a * b).collect::<Vec<_>>());
    let mut xnorm = dx(&st.x, &st.d);
    if first {
        st.delta = if xnorm > 0.0 {
            opts.stepbound * xnorm
        } else {
            opts.stepbound
        };
    }
    let Some(sub) = Subproblem::new(j, &st.r, &st.d) else {
        return Some(Termination::NoImprovementPossible);
    };
    let mut first_step = first;
    loop {
        let lambda = sub.lambda(st.delta);
        let (p, pnorm, jp) = sub.step(lambda, &st.d);
        if first_step && pnorm < st.delta {
            st.delta = pnorm;
        }
        first_step = false;
        let t1 = (jp / st.rnorm).powi(2);
        let t2 = (lambda.sqrt() * pnorm / st.rnorm).powi(2);
        let pred = t1 + 2.0 * t2;
        let dirder = -(t1 + t2);
        let xt: Vec<f64> = st.x.iter().zip(&p).map(|(a, b)| a + b).collect();
        st.evaluations += 1;
        let trial =
            residuals(&xt).filter(|r| r.len() == st.r.len() && r.iter().all(|v| v.is_finite()));
        let tnorm = trial.as_ref().map(|r| norm(r)).unwrap_or(f64::INFINITY);
        let actual = if 0.1 * tnorm < st.rnorm {
            1.0 - (tnorm / st.rnorm).powi(2)
        } else {
            -1.0
        };
        let ratio = if pred > 0.0 { actual / pred } else { 0.0 };
        if ratio <= 0.25 {
            let mut temp = if actual >= 0.0 {
                0.5
            } else {
                0.5 * dirder / (dirder + 0.5 * actual)
            };
            if 0.1 * tnorm >= st.rnorm || temp.is_nan() || temp < 0.1 {
                temp = 0.1;
            }
            st.delta = temp * st.delta.min(10.0 * pnorm);
        } else if lambda == 0.0 || ratio >= 0.75 {
            st.delta = 2.0 * pnorm;
        }
        let accepted = ratio >= 1e-4;
        if accepted {
            st.x = xt;
            st.r = trial.expect("accepted steps were evaluated");
            st.rnorm = tnorm;
            xnorm = dx(&st.x, &st.d);
        }
        if st.rnorm == 0.0 {
            return Some(Termination::ResidualsZero);
        }
        let ftol = actual.abs() <= opts.ftol && pred <= opts.ftol && ratio <= 2.0;
        let xtol = st.delta <= opts.xtol * xnorm;
        if ftol || xtol {
            return Some(Termination::Converged { ftol, xtol });
        }
        if st.evaluations >= opts.max_evaluations {
            return Some(Termination::MaxEvaluations);
        }
        let eps = f64::EPSILON;
        if (actual.abs() <= eps && pred <= eps && ratio <= 2.0) || st.delta <= eps * xnorm {
            return Some(Termination::NoImprovementPossible);
        }
        if accepted {
            return None;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fd_jacobian(f: &impl Fn(&[f64]) -> Option<Vec<f64>>, x: &[f64]) -> Option<DMatrix<f64>> {
        let r0 = f(x)?;
        let mut j = DMatrix::zeros(r0.len(), x.len());
        for k in 0..x.len() {
            let h = 1e-6 * x[k].abs().max(1.0);
            let (mut a, mut b) = (x.to_vec(), x.to_vec());
            a[k] += h;
            b[k] -= h;
            let (ra, rb) = (f(&a)?, f(&b)?);
            for i in 0..r0.len() {
                j[(i, k)] = (ra[i] - rb[i]) / (2.0 * h);
            }
        }
        Some(j)
    }

    #[test]
    fn rosenbrock_to_machine_precision() {
        // r = (10(x₂ − x₁²), 1 − x₁): minimum 0 at (1, 1); analytic Jacobian
        let f = |x: &[f64]| Some(vec![10.0 * (x[1] - x[0] * x[0]), 1.0 - x[0]]);
        let jac = |x: &[f64], _: &[f64]| {
            Some(DMatrix::from_row_slice(
                2,
                2,
                &[-20.0 * x[0], 10.0, -1.0, 0.0],
            ))
        };
        let s = minimize(f, jac, &[-1.2, 1.0], &LmOptions::default()).unwrap();
        assert!(s.termination.converged(), "{:?}", s.termination);
        assert!(
            (s.x[0] - 1.0).abs() < 1e-10 && (s.x[1] - 1.0).abs() < 1e-10,
            "{:?}",
            s.x
        );
    }

    #[test]
    fn exponential_fit_to_1e10() {
        // y = 2 e^{−0.7 t} + 0.5, exact data, from a poor start
        let t: Vec<f64> = (0..40).map(|i| i as f64 * 0.15).collect();
        let f = |p: &[f64]| {
            Some(
                t.iter()
                    .map(|t| p[0] * (-p[1] * t).exp() + p[2] - (2.0 * (-0.7 * t).exp() + 0.5))
                    .collect(),
            )
        };
        let s = minimize(
            f,
            |x, _| fd_jacobian(&f, x),
            &[1.0, 0.2, 0.0],
            &LmOptions::default(),
        )
        .unwrap();
        for (got, want) in s.x.iter().zip([2.0, 0.7, 0.5]) {
            assert!((got - want).abs() < 1e-10, "{:?}", s.x);
        }
    }

    #[test]
    fn a_singular_jacobian_takes_the_minimum_norm_step() {
        // r depends on x₀ + x₁ only: J has rank 1 everywhere; any x with x₀ + x₁ = 3 is a minimum
        let f = |x: &[f64]| Some(vec![x[0] + x[1] - 3.0, 2.0 * (x[0] + x[1] - 3.0)]);
        let jac = |_: &[f64], _: &[f64]| Some(DMatrix::from_row_slice(2, 2, &[1.0, 1.0, 2.0, 2.0]));
        let s = minimize(f, jac, &[0.0, 0.0], &LmOptions::default()).unwrap();
        assert!((s.x[0] + s.x[1] - 3.0).abs() < 1e-12, "{:?}", s.x);
        assert!(
            (s.x[0] - s.x[1]).abs() < 1e-12,
            "minimum-norm step: {:?}",
            s.x
        );
    }

    #[test]
    fn unevaluable_trial_points_shrink_the_region() {
        // r undefined for x < 0.5; the minimum x = 1 is approached from x = 3 through a
        // first step that overshoots into the undefined part
        let f = |x: &[f64]| (x[0] >= 0.5).then(|| vec![(x[0] - 1.0) * 4.0, (x[0] - 1.0).powi(3)]);
        let jac = |x: &[f64], _: &[f64]| {
            Some(DMatrix::from_row_slice(
                2,
                1,
                &[4.0, 3.0 * (x[0] - 1.0).powi(2)],
            ))
        };
        let s = minimize(f, jac, &[3.0], &LmOptions::default()).unwrap();
        assert!((s.x[0] - 1.0).abs() < 1e-10, "{:?}", s.x);
        assert_eq!(
            minimize(f, jac, &[0.0], &LmOptions::default()),
            Err(LmError::Start)
        );
    }
}
