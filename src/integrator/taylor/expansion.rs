//! One Taylor step: the coefficients of the state and of the variational columns, the step size
//! they admit, and the polynomials' values inside the step.
//!
//! The augmented state y = (β, ω, Z) has the layout of `augmented.rs` (Z's column c at 2 + 2c,
//! 3 + 2c). The state's coefficients come from the system ([`TaylorOscillator`]); the columns of
//! Z solve Ż = [[0, 1], [∂F/∂β, ∂F/∂ω]] Z, whose coefficients follow from those of ∂F/∂β and
//! ∂F/∂ω along the solution by Cauchy sums:
//!
//! ```text
//!   zβ,ₖ₊₁ = zω,ₖ/(k + 1),   zω,ₖ₊₁ = (Σⱼ (∂F/∂β)ⱼ zβ,ₖ₋ⱼ + Σⱼ (∂F/∂ω)ⱼ zω,ₖ₋ⱼ)/(k + 1).
//! ```

use crate::model::taylor::{TaylorOscillator, TaylorSeries, INV, TAYLOR_LEN};

/// The Taylor coefficients of one step of the augmented state of dimension N (2 or 6).
pub(super) struct Expansion<const N: usize> {
    /// The state's coefficients and the linearisation along it.
    pub x: TaylorSeries,
    /// Z's coefficients: `z[c][row][k]`, row 0 = β, 1 = ω.
    pub z: [[[f64; TAYLOR_LEN]; 2]; 2],
    /// The order p.
    pub order: usize,
}

impl<const N: usize> Expansion<N> {
    /// Number of Jacobian columns carried.
    const NCOLS: usize = (N - 2) / 2;

    /// An expansion of order `order` (≤ [`crate::model::TAYLOR_ORDER_MAX`]).
    pub fn new(order: usize) -> Self {
        Self {
            x: TaylorSeries::new([0.0, 0.0]),
            z: [[[0.0; TAYLOR_LEN]; 2]; 2],
            order,
        }
    }

    /// Expands the slip solution of side `s` through (t, y): the state by the system, the
    /// Jacobian columns by the variational recurrence (module docs).
    #[inline(always)]
    pub fn expand<S: TaylorOscillator + ?Sized>(&mut self, sys: &S, t: f64, y: &[f64; N], s: f64) {
        self.x.beta[0] = y[0];
        self.x.omega[0] = y[1];
        sys.taylor_expand(t, s, self.order, &mut self.x, Self::NCOLS > 0);
        if Self::NCOLS > 0 {
            self.variational(y);
        }
    }

    /// The coefficients of the Jacobian columns (both columns in one pass).
    fn variational(&mut self, y: &[f64; N]) {
        let p = self.order;
        let db = &self.x.d_beta;
        let dw = &self.x.d_omega;
        let [c0, c1] = &mut self.z;
        c0[0][0] = y[2];
        c0[1][0] = y[3];
        c1[0][0] = y[4];
        c1[1][0] = y[5];
        for k in 0..p {
            let mut acc = [0.0; 2];
            let zb = c0[0][..=k].iter().rev().zip(c1[0][..=k].iter().rev());
            for (&d, (&b0, &b1)) in db[..=k].iter().zip(zb) {
                acc[0] += d * b0;
                acc[1] += d * b1;
            }
            if self.x.d_omega_constant {
                acc[0] += dw[0] * c0[1][k];
                acc[1] += dw[0] * c1[1][k];
            } else {
                let zw = c0[1][..=k].iter().rev().zip(c1[1][..=k].iter().rev());
                for (&d, (&w0, &w1)) in dw[..=k].iter().zip(zw) {
                    acc[0] += d * w0;
                    acc[1] += d * w1;
                }
            }
            let inv = INV[k + 1];
            c0[0][k + 1] = c0[1][k] * inv;
            c1[0][k + 1] = c1[1][k] * inv;
            c0[1][k + 1] = acc[0] * inv;
            c1[1][k + 1] = acc[1] * inv;
        }
    }

    /// The coefficients of component i of y.
    #[inline(always)]
    pub fn coeffs(&self, i: usize) -> &[f64; TAYLOR_LEN] {
        match i {
            0 => &self.x.beta,
            1 => &self.x.omega,
            _ => &self.z[(i - 2) / 2][(i - 2) % 2],
        }
    }

    /// The step size: the largest h with |cᵢ,ₖ| hᵏ ≤ scaleᵢ for the two highest orders
    /// k = p − 1, p and every component i (the last terms kept are at most the tolerance; with
    /// coefficients that decay like ρ⁻ᵏ, the first term left out is smaller by the factor
    /// h/ρ = tol^(1/p)). `scale[i]` is atol + rtol·|yᵢ| (β: atol + rtol, an
    /// angle on the lift). Infinite when both orders vanish (a polynomial solution).
    pub fn step_size(&self, scale: &[f64; N]) -> f64 {
        let p = self.order;
        let mut ln_h = f64::INFINITY;
        for k in [p - 1, p] {
            let mut norm = 0.0_f64;
            for (i, &sc) in scale.iter().enumerate() {
                norm = norm.max(self.coeffs(i)[k].abs() / sc);
            }
            if norm > 0.0 {
                ln_h = ln_h.min(-norm.ln() / k as f64);
            }
        }
        ln_h.exp()
    }

    /// Component i at t₀ + τ (Horner).
    #[inline(always)]
    pub fn value(&self, i: usize, tau: f64) -> f64 {
        horner(&self.coeffs(i)[..=self.order], tau)
    }

    /// The augmented state at t₀ + τ.
    pub fn state(&self, tau: f64) -> [f64; N] {
        std::array::from_fn(|i| self.value(i, tau))
    }
}

/// Σₖ cₖ τᵏ by Horner's scheme.
#[inline(always)]
pub(super) fn horner(c: &[f64], tau: f64) -> f64 {
    c.iter().rev().fold(0.0, |acc, &ck| acc * tau + ck)
}
