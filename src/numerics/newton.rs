//! One Newton iteration for small fixed-size systems R(x) = 0, shared by single shooting
//! (x = (β, ω)), the pseudo-arclength corrector (x = (β, ω, λ) with the arclength row) and the
//! augmented system of a special point (x = (β, ω, λ) with a test-function row):
//!
//! ```text
//!   J(xₖ) Δx = −R(xₖ),   xₖ₊₁ = xₖ + s Δx,
//! ```
//!
//! with s = 1, or the largest of 1, ½, ¼, … (at most 8 halvings) that decreases ‖R‖ when a line
//! search is asked for, and s capped by a caller's step limit. Converged when ‖R(xₖ)‖ < tol and
//! ‖Δx‖ < 10 tol, with the caller's tolerance as given.

use crate::error::{Error, Result};
use nalgebra::{SMatrix, SVector};

/// Options of [`newton`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NewtonOptions {
    /// Convergence: ‖R‖ < tol and ‖Δx‖ < 10 tol.
    pub tol: f64,
    /// Largest number of Newton steps.
    pub max_iter: usize,
    /// Backtracking on ‖R‖ (shooting); without it a step is always taken.
    pub line_search: bool,
    /// Give up when ‖R‖ grows by more than this factor in one step after the third iteration.
    pub divergence_ratio: f64,
}

impl NewtonOptions {
    /// Plain Newton with tolerance `tol` and at most `max_iter` steps, no line search, giving up
    /// when the residual doubles.
    pub fn new(tol: f64, max_iter: usize) -> Self {
        Self {
            tol,
            max_iter,
            line_search: false,
            divergence_ratio: 2.0,
        }
    }
}

/// The residual and Jacobian at a point, with whatever else the caller computed there (`data`: the
/// map image, the events, the Floquet data).
#[derive(Debug, Clone)]
pub struct Linearisation<const N: usize, C> {
    /// R(x).
    pub residual: SVector<f64, N>,
    /// ∂R/∂x.
    pub jacobian: SMatrix<f64, N, N>,
    /// The caller's data at x.
    pub data: C,
}

/// A converged Newton iteration.
#[derive(Debug, Clone)]
pub struct NewtonSolution<const N: usize, C> {
    /// The root.
    pub x: SVector<f64, N>,
    /// The linearisation at the root.
    pub at: Linearisation<N, C>,
    /// Newton steps taken.
    pub iterations: usize,
}

fn failed(iterations: usize, residual: f64, reason: &str, context: &str) -> Error {
    Error::NewtonFailed {
        iterations,
        residual,
        reason: format!("{context}: {reason}"),
    }
}

/// Newton's method from `x0`. `eval` linearises R at a point; `limit(x, Δx)` returns the largest
/// admissible step fraction s ∈ (0, 1] (return 1.0 for none); `context` names the problem in errors.
///
/// ```
/// use gearbif::numerics::{newton, Linearisation, NewtonOptions};
/// use nalgebra::{Matrix2, Vector2};
/// // x² + y² = 4, x = y
/// let sol = newton(
///     Vector2::new(1.0, 0.5),
///     &NewtonOptions::new(1e-12, 20),
///     |x| Ok(Linearisation {
///         residual: Vector2::new(x[0] * x[0] + x[1] * x[1] - 4.0, x[0] - x[1]),
///         jacobian: Matrix2::new(2.0 * x[0], 2.0 * x[1], 1.0, -1.0),
///         data: (),
///     }),
///     |_, _| 1.0,
///     "circle",
/// )
/// .unwrap();
/// assert!((sol.x[0] - 2f64.sqrt()).abs() < 1e-12);
/// ```
pub fn newton<const N: usize, C>(
    x0: SVector<f64, N>,
    opts: &NewtonOptions,
    mut eval: impl FnMut(&SVector<f64, N>) -> Result<Linearisation<N, C>>,
    mut limit: impl FnMut(&SVector<f64, N>, &SVector<f64, N>) -> f64,
    context: &str,
) -> Result<NewtonSolution<N, C>> {
    let mut x = x0;
    let mut lin = eval(&x)?;
    let mut rn = lin.residual.norm();
    for it in 0..=opts.max_iter {
        if !rn.is_finite() {
            return Err(failed(it, rn, "non-finite residual", context));
        }
        let dx = solve(&lin.jacobian, &(-lin.residual))
            .ok_or_else(|| failed(it, rn, "singular Jacobian", context))?;
        if rn < opts.tol && dx.norm() < 10.0 * opts.tol {
            return Ok(NewtonSolution {
                x,
                at: lin,
                iterations: it,
            });
        }
        if it == opts.max_iter {
            break;
        }
        let s = limit(&x, &dx).clamp(0.0, 1.0);
        if opts.line_search {
            let mut lam = s;
            let mut accepted = false;
            for _ in 0..9 {
                let xt = x + dx * lam;
                if let Ok(lt) = eval(&xt) {
                    let rt = lt.residual.norm();
                    if rt < rn || rn < 10.0 * opts.tol {
                        x = xt;
                        lin = lt;
                        rn = rt;
                        accepted = true;
                        break;
                    }
                }
                lam *= 0.5;
            }
            if !accepted {
                return Err(failed(
                    it,
                    rn,
                    "no descent along the Newton direction",
                    context,
                ));
            }
        } else {
            x += dx * s;
            lin = eval(&x)?;
            let rt = lin.residual.norm();
            if it >= 2 && rt > opts.divergence_ratio * rn {
                return Err(failed(it + 1, rt, "diverging", context));
            }
            rn = rt;
        }
    }
    Err(failed(opts.max_iter, rn, "did not converge", context))
}

/// Solves A x = b by Gaussian elimination with partial pivoting; `None` if A is singular or the
/// solution is not finite.
pub fn solve<const N: usize>(
    a: &SMatrix<f64, N, N>,
    b: &SVector<f64, N>,
) -> Option<SVector<f64, N>> {
    let (mut a, mut b) = (*a, *b);
    for k in 0..N {
        let p = (k..N).max_by(|&i, &j| a[(i, k)].abs().total_cmp(&a[(j, k)].abs()))?;
        if a[(p, k)] == 0.0 || !a[(p, k)].is_finite() {
            return None;
        }
        a.swap_rows(k, p);
        b.swap_rows(k, p);
        for i in k + 1..N {
            let m = a[(i, k)] / a[(k, k)];
            for j in k..N {
                a[(i, j)] -= m * a[(k, j)];
            }
            b[i] -= m * b[k];
        }
    }
    let mut x = SVector::<f64, N>::zeros();
    for i in (0..N).rev() {
        let s: f64 = (i + 1..N).map(|j| a[(i, j)] * x[j]).sum();
        x[i] = (b[i] - s) / a[(i, i)];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}
