//! The largest Lyapunov exponent of a map from the products of its Jacobians.
//!
//! For the gear the Jacobians are the Filippov ones (saltation matrices at every event,
//! numerics.md), so the exponent is that of the non-smooth flow. A tangent vector is multiplied by
//! each Jacobian and renormalised (the 1-column QR), the logs of the growth factors are summed.
//!
//! **log 0.** A stick phase contributes the saltation diag(1, 0), so the map Jacobian of an orbit
//! that sticks is singular (a zero multiplier). A tangent vector can then be annihilated exactly;
//! the exponent is −∞ and is reported as `per_period: None` (JSON `null`), with the number of
//! annihilations counted. The sum of both exponents (from log |det|) is reported the same way; it
//! is −∞ as soon as one step contains a stick phase.

use nalgebra::{Matrix2, Vector2};
use serde::{Deserialize, Serialize};

/// Accumulates log growth factors of a tangent vector (and log |det|) along a Jacobian sequence.
#[derive(Debug, Clone, PartialEq)]
pub struct LyapunovAccumulator {
    w: Vector2<f64>,
    log_sum: f64,
    log_det: f64,
    steps: usize,
    annihilated: usize,
}

impl Default for LyapunovAccumulator {
    fn default() -> Self {
        Self::new()
    }
}

impl LyapunovAccumulator {
    /// Starts with a fixed generic unit vector (deterministic: a run gives the same bits twice).
    pub fn new() -> Self {
        Self {
            w: Vector2::new(0.6, 0.8),
            log_sum: 0.0,
            log_det: 0.0,
            steps: 0,
            annihilated: 0,
        }
    }

    /// Applies one Jacobian.
    pub fn push(&mut self, j: &Matrix2<f64>) {
        self.steps += 1;
        let d = j.determinant().abs();
        self.log_det += d.ln(); // −∞ for a stick phase
        let v = j * self.w;
        let n = v.norm();
        if n > 0.0 && n.is_finite() {
            self.log_sum += n.ln();
            self.w = v / n;
        } else {
            self.annihilated += 1;
            self.log_sum = f64::NEG_INFINITY;
            // restart from the image direction of the Jacobian's largest column, so later steps
            // still carry information for the diagnostics
            let c0 = j.column(0).norm();
            let c1 = j.column(1).norm();
            let c = if c0 >= c1 { j.column(0) } else { j.column(1) };
            let cn = c.norm();
            if cn > 0.0 {
                self.w = Vector2::new(c[0] / cn, c[1] / cn);
            }
        }
    }

    /// Steps pushed.
    pub fn steps(&self) -> usize {
        self.steps
    }

    /// The estimate over `periods` drive periods of length `period`.
    pub fn estimate(&self, periods: f64, period: f64) -> LyapunovEstimate {
        let fin = |v: f64| v.is_finite().then_some(v);
        let per = fin(self.log_sum / periods);
        let sum = fin(self.log_det / periods);
        LyapunovEstimate {
            per_period: per,
            per_second: per.map(|l| l / period),
            sum_per_period: sum,
            periods,
            annihilated: self.annihilated,
        }
    }
}

/// A finite-time estimate of the largest Lyapunov exponent.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LyapunovEstimate {
    /// λ₁ per drive period (log growth per period); `None` = −∞ (tangent vector annihilated).
    pub per_period: Option<f64>,
    /// λ₁ per second; `None` = −∞.
    pub per_second: Option<f64>,
    /// λ₁ + λ₂ per drive period from log |det|; `None` = −∞ (a stick phase in the window).
    pub sum_per_period: Option<f64>,
    /// Drive periods averaged over.
    pub periods: f64,
    /// How many steps annihilated the tangent vector.
    pub annihilated: usize,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constant_matrix_gives_log_spectral_radius() {
        let m = Matrix2::new(2.0, 1.0, 0.0, 0.5);
        let mut acc = LyapunovAccumulator::new();
        for _ in 0..200 {
            acc.push(&m);
        }
        let e = acc.estimate(200.0, 0.5);
        assert!((e.per_period.unwrap() - 2f64.ln()).abs() < 0.01);
        assert!((e.per_second.unwrap() - 2f64.ln() / 0.5).abs() < 0.02);
        assert!((e.sum_per_period.unwrap() - 1f64.ln()).abs() < 1e-12);
    }

    #[test]
    fn stick_gives_minus_infinity_for_the_sum_only() {
        // rank-one Jacobian with a nonzero multiplier 0.5: λ₁ = ln 0.5, λ₁ + λ₂ = −∞
        let m = Matrix2::new(0.5, 0.3, 0.0, 0.0);
        let mut acc = LyapunovAccumulator::new();
        for _ in 0..50 {
            acc.push(&m);
        }
        let e = acc.estimate(50.0, 1.0);
        assert!((e.per_period.unwrap() - 0.5f64.ln()).abs() < 0.05);
        assert_eq!(e.sum_per_period, None);
        // a vector in the kernel is annihilated: −∞
        let k = Matrix2::new(0.8, -0.6, 0.0, 0.0);
        let mut acc = LyapunovAccumulator::new();
        acc.push(&k);
        assert_eq!(acc.estimate(1.0, 1.0).per_period, None);
        assert_eq!(acc.estimate(1.0, 1.0).annihilated, 1);
    }
}
