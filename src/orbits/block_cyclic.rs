//! Structured Gaussian elimination for the cyclic block-bidiagonal systems of multiple shooting.
//!
//! The Newton matrix of multiple shooting with m segments (states y₀ … y_{m−1} ∈ ℝⁿ) and p extra
//! unknowns λ (free parameters) is
//!
//! ```text
//!   B_i y_i − y_{(i+1) mod m} + C_i λ = r_i      (i = 0 … m−1, n rows each)
//!   A y₀ + D λ                      = r_b      (p border rows: arclength or pinning)
//! ```
//!
//! It is solved by Gaussian elimination with partial pivoting in the order of the segments: the last
//! segment's rows (which couple y_{m−1} back to y₀) and the border rows start as the "carried" rows;
//! at step j the carried rows and segment j's rows are stacked and the n columns of y_j are
//! eliminated with row pivoting among them. Since no other row has a nonzero in the columns of y_j,
//! this is exactly partial pivoting on the whole matrix (same stability as a dense LU), but it costs
//! O(m (n + p)³) instead of O((mn)³) and never forms the monodromy product B_{m−1}⋯B₀, whose
//! condition number is what makes single shooting fail for strongly unstable orbits. The last
//! (n + p) carried rows in the unknowns (y_{m−1}, λ) are solved by a dense LU; then back substitution.

use crate::error::{Error, Result};
use nalgebra::{DMatrix, DVector};

/// A cyclic block-bidiagonal system with p bordering rows and columns (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct CyclicBlockSystem {
    /// B_i (n × n), one per segment.
    pub diagonal: Vec<DMatrix<f64>>,
    /// C_i (n × p), one per segment (p = 0: empty).
    pub param_columns: Vec<DMatrix<f64>>,
    /// A (p × n): the border rows' coefficients of y₀.
    pub border_state: DMatrix<f64>,
    /// D (p × p): the border rows' coefficients of λ.
    pub border_param: DMatrix<f64>,
}

/// The solution of a [`CyclicBlockSystem`]: the segment states' increments and the extra unknowns.
#[derive(Debug, Clone, PartialEq)]
pub struct CyclicSolution {
    /// y_i, one vector of length n per segment.
    pub states: Vec<DVector<f64>>,
    /// λ (length p).
    pub params: DVector<f64>,
}

/// One block of pivot rows kept for the back substitution: U y_j + N y_{j+1} + T (y_{m−1}, λ) = b.
struct PivotRows {
    u: DMatrix<f64>,
    next: DMatrix<f64>,
    tail: DMatrix<f64>,
    rhs: DVector<f64>,
}

fn singular(step: usize) -> Error {
    Error::NewtonFailed {
        iterations: 0,
        residual: f64::NAN,
        reason: format!("singular multiple-shooting matrix (zero pivot at segment {step})"),
    }
}

impl CyclicBlockSystem {
    fn dims(&self) -> Result<(usize, usize, usize)> {
        let m = self.diagonal.len();
        if m == 0 {
            return Err(Error::shape("segments of the cyclic system", ">= 1", 0));
        }
        let n = self.diagonal[0].nrows();
        let p = self.border_param.nrows();
        let ok = self.diagonal.iter().all(|b| b.shape() == (n, n))
            && self.param_columns.len() == m
            && self.param_columns.iter().all(|c| c.shape() == (n, p))
            && self.border_state.shape() == (p, n)
            && self.border_param.shape() == (p, p);
        if ok {
            Ok((m, n, p))
        } else {
            Err(Error::shape(
                "blocks of the cyclic system",
                format!("{m} diagonal and parameter blocks of sizes {n}×{n}, {n}×{p}"),
                self.param_columns.len(),
            ))
        }
    }

    /// The same system as one dense matrix (unknowns y₀ … y_{m−1}, λ; rows segment by segment, then
    /// the border). For tests and small problems.
    pub fn to_dense(&self) -> Result<DMatrix<f64>> {
        let (m, n, p) = self.dims()?;
        let size = m * n + p;
        let mut a = DMatrix::zeros(size, size);
        for i in 0..m {
            let j = (i + 1) % m;
            a.view_mut((i * n, i * n), (n, n))
                .copy_from(&self.diagonal[i]);
            for k in 0..n {
                a[(i * n + k, j * n + k)] -= 1.0;
            }
            a.view_mut((i * n, m * n), (n, p))
                .copy_from(&self.param_columns[i]);
        }
        a.view_mut((m * n, 0), (p, n)).copy_from(&self.border_state);
        a.view_mut((m * n, m * n), (p, p))
            .copy_from(&self.border_param);
        Ok(a)
    }

    /// Solves the system for the right-hand sides r_i (one per segment) and r_b (border).
    #[allow(clippy::needless_range_loop)] // segment j indexes B_j, C_j and r_j together
    pub fn solve(&self, rhs: &[DVector<f64>], rhs_border: &DVector<f64>) -> Result<CyclicSolution> {
        let (m, n, p) = self.dims()?;
        if rhs.len() != m || rhs.iter().any(|r| r.len() != n) || rhs_border.len() != p {
            return Err(Error::shape(
                "right-hand sides of the cyclic system",
                format!("{m} of length {n} and a border of length {p}"),
                rhs.len(),
            ));
        }
        if m == 1 {
            return self.solve_dense(rhs, rhs_border);
        }
        let t = n + p; // tail unknowns: y_{m−1} and λ
        let scale = self.diagonal.iter().map(|b| b.amax()).fold(1.0, f64::max);
        let tiny = 1e-300_f64.max(scale * f64::EPSILON * 1e-6);
        // carried rows: columns [cur (n) | tail (t)], rhs
        let mut carried = DMatrix::zeros(n + p, n + t);
        let mut carried_rhs = DVector::zeros(n + p);
        for k in 0..n {
            carried[(k, k)] = -1.0; // −y₀ in the last segment's rows
        }
        carried
            .view_mut((0, n), (n, n))
            .copy_from(&self.diagonal[m - 1]);
        carried
            .view_mut((0, 2 * n), (n, p))
            .copy_from(&self.param_columns[m - 1]);
        carried_rhs.rows_mut(0, n).copy_from(&rhs[m - 1]);
        carried
            .view_mut((n, 0), (p, n))
            .copy_from(&self.border_state);
        carried
            .view_mut((n, 2 * n), (p, p))
            .copy_from(&self.border_param);
        carried_rhs.rows_mut(n, p).copy_from(rhs_border);
        let mut pivots = Vec::with_capacity(m - 1);
        for j in 0..m - 1 {
            // stacked rows: columns [cur (n) | next (n) | tail (t)]
            let rows = 2 * n + p;
            let mut w = DMatrix::zeros(rows, 2 * n + t);
            let mut b = DVector::zeros(rows);
            w.view_mut((0, 0), (n + p, n))
                .copy_from(&carried.view((0, 0), (n + p, n)));
            w.view_mut((0, 2 * n), (n + p, t))
                .copy_from(&carried.view((0, n), (n + p, t)));
            b.rows_mut(0, n + p).copy_from(&carried_rhs);
            w.view_mut((n + p, 0), (n, n)).copy_from(&self.diagonal[j]);
            // −y_{j+1}: into "next", or into the tail when j + 1 = m − 1
            let col = if j + 1 == m - 1 { 2 * n } else { n };
            for k in 0..n {
                w[(n + p + k, col + k)] = -1.0;
            }
            w.view_mut((n + p, 3 * n), (n, p))
                .copy_from(&self.param_columns[j]);
            b.rows_mut(n + p, n).copy_from(&rhs[j]);
            // partial pivoting on the n columns of y_j
            for c in 0..n {
                let (piv, val) = (c..rows)
                    .map(|r| (r, w[(r, c)].abs()))
                    .fold((c, -1.0), |acc, x| if x.1 > acc.1 { x } else { acc });
                if val <= tiny {
                    return Err(singular(j));
                }
                w.swap_rows(c, piv);
                b.swap_rows(c, piv);
                for r in c + 1..rows {
                    let l = w[(r, c)] / w[(c, c)];
                    if l != 0.0 {
                        for k in c..w.ncols() {
                            w[(r, k)] -= l * w[(c, k)];
                        }
                        b[r] -= l * b[c];
                    }
                }
            }
            pivots.push(PivotRows {
                u: w.view((0, 0), (n, n)).upper_triangle(),
                next: w.view((0, n), (n, n)).into_owned(),
                tail: w.view((0, 2 * n), (n, t)).into_owned(),
                rhs: b.rows(0, n).into_owned(),
            });
            carried
                .view_mut((0, 0), (n + p, n))
                .copy_from(&w.view((n, n), (n + p, n)));
            carried
                .view_mut((0, n), (n + p, t))
                .copy_from(&w.view((n, 2 * n), (n + p, t)));
            carried_rhs.copy_from(&b.rows(n, n + p));
        }
        // after the last step the carried rows have no "cur" entries (y_{m−1} went to the tail)
        let tail_mat = carried.view((0, n), (t, t)).into_owned();
        let tail = tail_mat
            .lu()
            .solve(&carried_rhs)
            .filter(|v| v.iter().all(|x| x.is_finite()))
            .ok_or_else(|| singular(m - 1))?;
        let mut states = vec![DVector::zeros(n); m];
        states[m - 1] = tail.rows(0, n).into_owned();
        for j in (0..m - 1).rev() {
            let pr = &pivots[j];
            let mut r = &pr.rhs - &pr.tail * &tail;
            if j + 1 < m - 1 {
                r -= &pr.next * &states[j + 1];
            }
            let y =
                pr.u.solve_upper_triangular(&r)
                    .filter(|v| v.iter().all(|x| x.is_finite()))
                    .ok_or_else(|| singular(j))?;
            states[j] = y;
        }
        Ok(CyclicSolution {
            states,
            params: tail.rows(n, p).into_owned(),
        })
    }

    fn solve_dense(
        &self,
        rhs: &[DVector<f64>],
        rhs_border: &DVector<f64>,
    ) -> Result<CyclicSolution> {
        let (m, n, p) = self.dims()?;
        let a = self.to_dense()?;
        let mut b = DVector::zeros(m * n + p);
        for (i, r) in rhs.iter().enumerate() {
            b.rows_mut(i * n, n).copy_from(r);
        }
        b.rows_mut(m * n, p).copy_from(rhs_border);
        let z = a
            .lu()
            .solve(&b)
            .filter(|v| v.iter().all(|x| x.is_finite()))
            .ok_or_else(|| singular(0))?;
        Ok(CyclicSolution {
            states: (0..m).map(|i| z.rows(i * n, n).into_owned()).collect(),
            params: z.rows(m * n, p).into_owned(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lcg(seed: &mut u64) -> f64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }

    fn random_system(
        m: usize,
        n: usize,
        p: usize,
        growth: f64,
        seed: &mut u64,
    ) -> CyclicBlockSystem {
        let mut mk = |r: usize, c: usize, s: f64| DMatrix::from_fn(r, c, |_, _| s * lcg(seed));
        CyclicBlockSystem {
            diagonal: (0..m).map(|_| mk(n, n, growth)).collect(),
            param_columns: (0..m).map(|_| mk(n, p, 1.0)).collect(),
            border_state: mk(p, n, 1.0),
            border_param: mk(p, p, 1.0),
        }
    }

    #[test]
    fn structured_elimination_equals_dense_lu() {
        let mut seed = 7u64;
        for &(m, n, p) in &[
            (1, 2, 0),
            (2, 2, 0),
            (5, 2, 1),
            (17, 2, 1),
            (6, 3, 2),
            (40, 2, 0),
        ] {
            let sys = random_system(m, n, p, 3.0, &mut seed);
            let rhs: Vec<DVector<f64>> = (0..m)
                .map(|_| DVector::from_fn(n, |_, _| lcg(&mut seed)))
                .collect();
            let rb = DVector::from_fn(p, |_, _| lcg(&mut seed));
            let sol = sys.solve(&rhs, &rb).unwrap();
            // residual of the dense system
            let a = sys.to_dense().unwrap();
            let mut z = DVector::zeros(m * n + p);
            for (i, y) in sol.states.iter().enumerate() {
                z.rows_mut(i * n, n).copy_from(y);
            }
            z.rows_mut(m * n, p).copy_from(&sol.params);
            let mut b = DVector::zeros(m * n + p);
            for (i, r) in rhs.iter().enumerate() {
                b.rows_mut(i * n, n).copy_from(r);
            }
            b.rows_mut(m * n, p).copy_from(&rb);
            let res = (&a * &z - &b).amax();
            assert!(res < 1e-10 * (1.0 + z.amax()), "m={m} n={n} p={p}: {res}");
            let dense = a.lu().solve(&b).unwrap();
            assert!((dense - z).amax() < 1e-8, "m={m} n={n} p={p}");
        }
    }

    #[test]
    #[allow(clippy::needless_range_loop)]
    fn strongly_growing_blocks_stay_accurate() {
        // B_i = diag(e^3, e^-3): monodromy e^{±3m}; with m = 30 the product has condition ~e^180,
        // but the segmented system is well conditioned: y_i = B_i^{-1}... solved exactly.
        let m = 30;
        let b = DMatrix::from_diagonal(&DVector::from_vec(vec![3f64.exp(), (-3f64).exp()]));
        let sys = CyclicBlockSystem {
            diagonal: vec![b; m],
            param_columns: vec![DMatrix::zeros(2, 0); m],
            border_state: DMatrix::zeros(0, 2),
            border_param: DMatrix::zeros(0, 0),
        };
        let rhs: Vec<DVector<f64>> = (0..m)
            .map(|i| DVector::from_vec(vec![(i as f64).sin(), (i as f64).cos()]))
            .collect();
        let sol = sys.solve(&rhs, &DVector::zeros(0)).unwrap();
        for i in 0..m {
            let j = (i + 1) % m;
            let r = &sys.diagonal[i] * &sol.states[i] - &sol.states[j] - &rhs[i];
            assert!(r.amax() < 1e-12, "segment {i}: {}", r.amax());
        }
    }

    #[test]
    fn singular_and_malformed_systems_are_errors() {
        let sys = CyclicBlockSystem {
            diagonal: vec![DMatrix::identity(2, 2); 3],
            param_columns: vec![DMatrix::zeros(2, 0); 3],
            border_state: DMatrix::zeros(0, 2),
            border_param: DMatrix::zeros(0, 0),
        };
        // the product of identities minus I is singular: y_i all equal is a null vector
        let rhs = vec![DVector::from_vec(vec![1.0, 0.0]); 3];
        assert!(sys.solve(&rhs, &DVector::zeros(0)).is_err());
        assert!(sys.solve(&rhs[..2], &DVector::zeros(0)).is_err());
    }
}
