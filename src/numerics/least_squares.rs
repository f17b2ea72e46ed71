//! Linear least squares by a column-pivoted Householder QR factorisation (faer).
//!
//! min_x ‖A x − b‖₂ is solved from A S P = Q R, with S = diag(1/‖a_j‖) the column equilibration
//! and P the column pivoting: x = S P R⁻¹ Qᵀ b. The normal equations AᵀA x = Aᵀb are never formed,
//! so the condition number enters once, not squared: a Vandermonde fit that loses every digit
//! through (AᵀA)⁻¹ keeps about 16 − log₁₀ κ(A) of them here.
//!
//! The unscaled covariance (AᵀA)⁻¹ = S P R⁻¹ R⁻ᵀ Pᵀ S comes from the triangular factor. The rank
//! is read off the pivoted diagonal: column k of R counts when |R_kk| > `rcond`·|R_00|. A rank
//! below the number of columns is the typed [`LeastSquaresError::RankDeficient`] naming the
//! columns that carry no independent information, never a NaN.

use faer::linalg::solvers::SolveLstsq;
use faer::Mat;
use nalgebra::DMatrix;
use thiserror::Error;

/// Default relative threshold on the pivoted diagonal of R below which a column is dependent:
/// columns are equilibrated first, so this is 1/κ of the scaled problem (≈ 10⁴ ulp).
pub const DEFAULT_RCOND: f64 = 1e-12;

/// Why a linear least-squares problem has no unique solution.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum LeastSquaresError {
    /// Fewer rows than columns.
    #[error("least squares: {rows} rows for {cols} unknowns")]
    TooFewRows {
        /// Rows of A.
        rows: usize,
        /// Columns of A.
        cols: usize,
    },
    /// The columns are linearly dependent (to `rcond`): `dependent` lists the columns (indices
    /// of A) that the pivoted factorisation found to add nothing independent.
    #[error("least squares: rank {rank} < {cols} columns (dependent columns {dependent:?})")]
    RankDeficient {
        /// Numerical rank.
        rank: usize,
        /// Columns of A.
        cols: usize,
        /// The columns beyond the rank, in pivot order.
        dependent: Vec<usize>,
    },
    /// A or b holds a NaN or an infinity.
    #[error("least squares: non-finite entry in the matrix or the right-hand side")]
    NonFinite,
}

/// Solution of min ‖A x − b‖.
#[derive(Debug, Clone, PartialEq)]
pub struct LinearSolution {
    /// x.
    pub x: Vec<f64>,
    /// (AᵀA)⁻¹ from the R factor: the covariance of x for unit-variance rows.
    pub cov_unit: DMatrix<f64>,
    /// b − A x.
    pub resid: Vec<f64>,
}

/// A column-pivoted QR factorisation of an equilibrated matrix, ready to solve and to give
/// (AᵀA)⁻¹.
struct Factor {
    qr: faer::linalg::solvers::ColPivQr<f64>,
    /// 1/‖a_j‖ of every column.
    scale: Vec<f64>,
    /// perm[k]: the column of A in pivot position k.
    perm: Vec<usize>,
}

fn factor(a: &Mat<f64>, rcond: f64) -> Result<Factor, LeastSquaresError> {
    let (m, n) = (a.nrows(), a.ncols());
    if m < n {
        return Err(LeastSquaresError::TooFewRows { rows: m, cols: n });
    }
    let mut scale = vec![0.0; n];
    for (j, s) in scale.iter_mut().enumerate() {
        let norm = (0..m).map(|i| a[(i, j)] * a[(i, j)]).sum::<f64>().sqrt();
        if !norm.is_finite() {
            return Err(LeastSquaresError::NonFinite);
        }
        *s = if norm > 0.0 { 1.0 / norm } else { 0.0 };
    }
    let scaled = Mat::from_fn(m, n, |i, j| a[(i, j)] * scale[j]);
    let qr = scaled.col_piv_qr();
    let perm: Vec<usize> = qr.P().arrays().0.to_vec();
    let r = qr.thin_R();
    let r00 = if n > 0 { r[(0, 0)].abs() } else { 0.0 };
    let rank = (0..n)
        .take_while(|&k| r[(k, k)].abs() > rcond * r00 && r00 > 0.0)
        .count();
    if rank < n {
        return Err(LeastSquaresError::RankDeficient {
            rank,
            cols: n,
            dependent: perm[rank..].to_vec(),
        });
    }
    Ok(Factor { qr, scale, perm })
}

impl Factor {
    /// x of min ‖A x − b‖.
    fn solve(&self, b: &[f64]) -> Vec<f64> {
        let rhs = Mat::from_fn(b.len(), 1, |i, _| b[i]);
        let y = self.qr.solve_lstsq(&rhs);
        (0..self.scale.len())
            .map(|j| y[(j, 0)] * self.scale[j])
            .collect()
    }
    /// (AᵀA)⁻¹ = S P R⁻¹R⁻ᵀ Pᵀ S.
    fn cov_unit(&self) -> DMatrix<f64> {
        let r = self.qr.thin_R();
        let n = self.scale.len();
        // R⁻¹ by back substitution, column by column (upper triangular)
        let mut inv = DMatrix::<f64>::zeros(n, n);
        for c in 0..n {
            for i in (0..=c).rev() {
                let mut s = if i == c { 1.0 } else { 0.0 };
                for k in i + 1..=c {
                    s -= r[(i, k)] * inv[(k, c)];
                }
                inv[(i, c)] = s / r[(i, i)];
            }
        }
        let rrt = &inv * inv.transpose();
        let mut cov = DMatrix::zeros(n, n);
        for a in 0..n {
            for b in 0..n {
                let (ja, jb) = (self.perm[a], self.perm[b]);
                cov[(ja, jb)] = rrt[(a, b)] * self.scale[ja] * self.scale[jb];
            }
        }
        cov
    }
}

/// Solves min ‖A x − b‖₂ by column-pivoted QR (module docs), with (AᵀA)⁻¹ and the residual.
///
/// ```
/// use gearbif::numerics::least_squares::{lstsq, DEFAULT_RCOND};
/// use faer::Mat;
/// // y = 1 + 2t through three exact points
/// let a = Mat::from_fn(3, 2, |i, j| if j == 0 { 1.0 } else { i as f64 });
/// let s = lstsq(&a, &[1.0, 3.0, 5.0], DEFAULT_RCOND).unwrap();
/// assert!((s.x[0] - 1.0).abs() < 1e-14 && (s.x[1] - 2.0).abs() < 1e-14);
/// ```
pub fn lstsq(a: &Mat<f64>, b: &[f64], rcond: f64) -> Result<LinearSolution, LeastSquaresError> {
    if b.len() != a.nrows() {
        return Err(LeastSquaresError::TooFewRows {
            rows: b.len(),
            cols: a.ncols(),
        });
    }
    if b.iter().any(|v| !v.is_finite()) {
        return Err(LeastSquaresError::NonFinite);
    }
    let f = factor(a, rcond)?;
    let x = f.solve(b);
    if x.iter().any(|v| !v.is_finite()) {
        return Err(LeastSquaresError::NonFinite);
    }
    let resid = (0..a.nrows())
        .map(|i| b[i] - (0..a.ncols()).map(|j| a[(i, j)] * x[j]).sum::<f64>())
        .collect();
    Ok(LinearSolution {
        x,
        cov_unit: f.cov_unit(),
        resid,
    })
}

/// The R factor (upper triangle, min(m, n) × n) of the QR factorisation of `a`, computed
/// sequentially. faer's default (global) parallelism splits the blocked Householder updates of a
/// tall matrix over rayon's threads, so the rounding, and with it every fit by simulation, depended
/// on the thread count (a campaign set's base refit: ζ and g differed by 1e-8 and 5e-9 relative
/// between 1 and 2 threads);
/// the matrices here are a few thousand rows by a few columns, too small to gain from threads.
pub fn thin_r(mut a: Mat<f64>) -> Mat<f64> {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::qr::no_pivoting::factor;
    let (m, n) = a.shape();
    let size = m.min(n);
    let block = factor::recommended_block_size::<f64>(m, n);
    let mut coeff = Mat::zeros(block, size);
    let par = faer::Par::Seq;
    let scratch = factor::qr_in_place_scratch::<f64>(m, n, block, par, Default::default());
    factor::qr_in_place(
        a.as_mut(),
        coeff.as_mut(),
        par,
        MemStack::new(&mut MemBuffer::new(scratch)),
        Default::default(),
    );
    Mat::from_fn(size, n, |i, j| if j >= i { a[(i, j)] } else { 0.0 })
}

/// The columns of A that carry independent information (to `rcond`), in increasing order: the
/// dependent columns of the pivoted factorisation ([`LeastSquaresError::RankDeficient`]) are
/// dropped and the rest factorised again, until it has full rank. A zero column is always
/// dropped. Errors other than a rank deficiency (too few rows, a non-finite entry) are returned.
pub fn independent_columns(a: &Mat<f64>, rcond: f64) -> Result<Vec<usize>, LeastSquaresError> {
    let mut keep: Vec<usize> = (0..a.ncols()).collect();
    loop {
        let sub = Mat::from_fn(a.nrows(), keep.len(), |i, k| a[(i, keep[k])]);
        match factor(&sub, rcond) {
            Ok(_) => return Ok(keep),
            Err(LeastSquaresError::RankDeficient { dependent, .. }) if !dependent.is_empty() => {
                let drop: Vec<usize> = dependent.iter().map(|&d| keep[d]).collect();
                keep.retain(|k| !drop.contains(k));
            }
            Err(e) => return Err(e),
        }
    }
}

/// min ‖A x − b‖₂ over the columns A determines ([`independent_columns`]), the others held at
/// x_j = 0: the least-squares step that does not move along a direction the data cannot see
/// (an SVD's minimum-norm solution would, by a rounding error divided by a vanishing column
/// norm). A is first reduced sequentially ([`thin_r`]) to the R factor [R c; 0 ρ] of [A b],
/// which has the same Gram matrix and right-hand side (RᵀR = AᵀA, Rᵀc = Aᵀb): the result does
/// not depend on the number of threads, and the pivoted factorisations work on n × n. A
/// non-finite entry of A or b reaches R and c and is reported there
/// ([`LeastSquaresError::NonFinite`]).
pub fn lstsq_determined(
    a: &Mat<f64>,
    b: &[f64],
    rcond: f64,
) -> Result<Vec<f64>, LeastSquaresError> {
    let (m, n) = a.shape();
    if b.len() != m || m < n {
        return Err(LeastSquaresError::TooFewRows {
            rows: b.len().min(m),
            cols: n,
        });
    }
    let rr = thin_r(Mat::from_fn(
        m,
        n + 1,
        |i, j| if j < n { a[(i, j)] } else { b[i] },
    ));
    let r = Mat::from_fn(n, n, |i, j| rr[(i, j)]);
    let c: Vec<f64> = (0..n).map(|i| rr[(i, n)]).collect();
    let keep = independent_columns(&r, rcond)?;
    let sub = Mat::from_fn(n, keep.len(), |i, k| r[(i, keep[k])]);
    let s = lstsq(&sub, &c, rcond)?;
    let mut x = vec![0.0; n];
    for (k, &j) in keep.iter().enumerate() {
        x[j] = s.x[k];
    }
    Ok(x)
}

/// (AᵀA)⁻¹ of a full-rank A by column-pivoted QR (the Gauss–Newton covariance of a Jacobian).
pub fn inverse_gram(a: &Mat<f64>, rcond: f64) -> Result<DMatrix<f64>, LeastSquaresError> {
    Ok(factor(a, rcond)?.cov_unit())
}

/// Weighted least squares: min Σ wᵢ (yᵢ − Σⱼ xᵢⱼ θⱼ)² over the rows `rows`, with the design given
/// as a function `x(i, j)`. Returns the solution of the √w-scaled problem (its `resid` is
/// √wᵢ(yᵢ − xᵢθ), its `cov_unit` (XᵀWX)⁻¹).
pub fn weighted(
    rows: &[usize],
    cols: usize,
    x: impl Fn(usize, usize) -> f64,
    y: impl Fn(usize) -> f64,
    w: impl Fn(usize) -> f64,
    rcond: f64,
) -> Result<LinearSolution, LeastSquaresError> {
    let sw: Vec<f64> = rows.iter().map(|&i| w(i).max(0.0).sqrt()).collect();
    let a = Mat::from_fn(rows.len(), cols, |k, j| sw[k] * x(rows[k], j));
    let b: Vec<f64> = rows.iter().zip(&sw).map(|(&i, s)| s * y(i)).collect();
    lstsq(&a, &b, rcond)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Monomials 1, t, …, t^deg at n points in [0, 1].
    fn vandermonde(n: usize, deg: usize) -> Mat<f64> {
        Mat::from_fn(n, deg + 1, |i, j| {
            (i as f64 / (n - 1) as f64).powi(j as i32)
        })
    }

    #[test]
    fn exact_polynomial_is_recovered() {
        let coef = [0.3, -1.2, 2.5, 0.7];
        let a = vandermonde(40, 3);
        let b: Vec<f64> = (0..40)
            .map(|i| (0..4).map(|j| a[(i, j)] * coef[j]).sum())
            .collect();
        let s = lstsq(&a, &b, DEFAULT_RCOND).unwrap();
        for (x, c) in s.x.iter().zip(coef) {
            assert!((x - c).abs() < 1e-12, "{x} vs {c}");
        }
        assert!(s.resid.iter().all(|r| r.abs() < 1e-13));
    }

    #[test]
    fn covariance_matches_the_inverse_gram_matrix() {
        // a well-conditioned, permuted-scale matrix: (AᵀA)⁻¹ by LU as the independent check
        let a = Mat::from_fn(30, 4, |i, j| {
            let t = i as f64 / 29.0;
            [1.0, 1e3 * t, (3.0 * t).sin(), 1e-2 * (t * t - 0.3)][j]
        });
        let na = DMatrix::from_fn(30, 4, |i, j| a[(i, j)]);
        let gram_inv = (na.transpose() * &na).try_inverse().unwrap();
        let cov = inverse_gram(&a, DEFAULT_RCOND).unwrap();
        for i in 0..4 {
            for j in 0..4 {
                let rel = (cov[(i, j)] - gram_inv[(i, j)]).abs()
                    / (gram_inv[(i, i)] * gram_inv[(j, j)]).sqrt();
                assert!(
                    rel < 1e-9,
                    "({i},{j}): {} vs {}",
                    cov[(i, j)],
                    gram_inv[(i, j)]
                );
            }
        }
    }

    #[test]
    fn ill_conditioned_vandermonde_keeps_its_digits() {
        // degree 11 monomials on [0, 1]: κ(A) ≈ 1e8, so κ(AᵀA) ≈ 1e16 and the normal equations
        // lose every digit, while QR keeps about 16 − 8
        let (n, deg) = (60, 11);
        let a = vandermonde(n, deg);
        let coef: Vec<f64> = (0..=deg).map(|j| 1.0 / (1.0 + j as f64)).collect();
        let b: Vec<f64> = (0..n)
            .map(|i| (0..=deg).map(|j| a[(i, j)] * coef[j]).sum())
            .collect();
        let s = lstsq(&a, &b, DEFAULT_RCOND).unwrap();
        let err_qr = (0..=deg)
            .map(|j| (s.x[j] - coef[j]).abs())
            .fold(0.0, f64::max);
        assert!(err_qr < 1e-5, "QR error {err_qr}");
        // the normal equations on the same data (Cholesky of AᵀA, the best case of that route)
        let na = DMatrix::from_fn(n, deg + 1, |i, j| a[(i, j)]);
        let nb = nalgebra::DVector::from_vec(b.clone());
        let err_ne = match (na.transpose() * &na).cholesky() {
            Some(ch) => {
                let x = ch.solve(&(na.transpose() * nb));
                (0..=deg)
                    .map(|j| (x[j] - coef[j]).abs())
                    .fold(0.0, f64::max)
            }
            None => f64::INFINITY,
        };
        assert!(
            err_ne > 1e3 * err_qr,
            "normal equations {err_ne} vs QR {err_qr}"
        );
    }

    #[test]
    fn undetermined_columns_are_held() {
        // column 1 is zero and column 3 = column 0 + column 2: the determined columns fit b
        // exactly, and the undetermined ones stay at 0 (an exact fit needs none of them)
        let a = Mat::from_fn(12, 4, |i, j| {
            let t = i as f64 / 11.0;
            [1.0, 0.0, t, 1.0 + t][j]
        });
        let b: Vec<f64> = (0..12).map(|i| 2.0 - 3.0 * i as f64 / 11.0).collect();
        assert_eq!(independent_columns(&a, DEFAULT_RCOND).unwrap().len(), 2);
        let x = lstsq_determined(&a, &b, DEFAULT_RCOND).unwrap();
        assert_eq!(x[1], 0.0);
        for i in 0..12 {
            let fit: f64 = (0..4).map(|j| a[(i, j)] * x[j]).sum();
            assert!((fit - b[i]).abs() < 1e-13, "row {i}: {fit} vs {}", b[i]);
        }
        assert_eq!(x.iter().filter(|v| **v == 0.0).count(), 2, "{x:?}");
        // a non-finite entry of A (in the zero column, last row) or of b is an error, not a NaN
        let mut bad = a.clone();
        bad[(11, 1)] = f64::NAN;
        let mut inf_b = b.clone();
        inf_b[5] = f64::INFINITY;
        for (m, rhs) in [(&bad, &b), (&a, &inf_b)] {
            assert_eq!(
                lstsq_determined(m, rhs, DEFAULT_RCOND),
                Err(LeastSquaresError::NonFinite)
            );
        }
    }

    #[test]
    fn dependent_columns_are_a_typed_error() {
        // column 2 = column 0 + column 1
        let a = Mat::from_fn(10, 3, |i, j| {
            let t = i as f64;
            [1.0, t, 1.0 + t][j]
        });
        let b: Vec<f64> = (0..10).map(|i| i as f64).collect();
        match lstsq(&a, &b, DEFAULT_RCOND) {
            Err(LeastSquaresError::RankDeficient {
                rank,
                cols,
                dependent,
            }) => {
                assert_eq!((rank, cols, dependent.len()), (2, 3, 1));
            }
            other => panic!("expected rank deficiency, got {other:?}"),
        }
        let zero = Mat::from_fn(5, 2, |i, j| if j == 0 { i as f64 } else { 0.0 });
        assert!(matches!(
            lstsq(&zero, &[0.0; 5], DEFAULT_RCOND),
            Err(LeastSquaresError::RankDeficient { dependent, .. }) if dependent == vec![1]
        ));
        assert!(matches!(
            lstsq(&vandermonde(2, 3), &[0.0; 2], DEFAULT_RCOND),
            Err(LeastSquaresError::TooFewRows { .. })
        ));
        assert!(matches!(
            lstsq(
                &vandermonde(5, 1),
                &[0.0, f64::NAN, 0.0, 0.0, 0.0],
                DEFAULT_RCOND
            ),
            Err(LeastSquaresError::NonFinite)
        ));
    }
}
