//! Taylor coefficients of a slip solution: the jet a system provides to be integrated by Taylor's
//! method (`integrator::Taylor`).
//!
//! On a slip piece of side s the solution of β̇ = ω, ω̇ = a(t, β, ω) − s r(t, β, ω) is expanded
//! about t₀ as
//!
//! ```text
//!   β(t₀ + τ) = Σₖ βₖ τᵏ,   ω(t₀ + τ) = Σₖ ωₖ τᵏ,   k = 0 … p,
//!   βₖ₊₁ = ωₖ/(k + 1),       ωₖ₊₁ = Fₖ/(k + 1),
//! ```
//!
//! with Fₖ the k-th Taylor coefficient of F(τ) = a − s r along the solution, which a system computes
//! from the coefficients of β and ω up to order k by the standard recurrences of automatic
//! differentiation (products: Cauchy sums; sin and cos of u: (sin u)ₖ = (1/k) Σⱼ j uⱼ (cos u)ₖ₋ⱼ,
//! (cos u)ₖ = −(1/k) Σⱼ j uⱼ (sin u)ₖ₋ⱼ, j = 1 … k).
//!
//! For the state Jacobian the integrator also needs the coefficients of ∂F/∂β and ∂F/∂ω along the
//! solution (the variational equation Ż = [[0, 1], [∂F/∂β, ∂F/∂ω]] Z is then expanded by the
//! integrator itself, in the same arithmetic).

use super::DrivenOscillator;

/// Largest Taylor order p a [`TaylorSeries`] holds.
pub const TAYLOR_ORDER_MAX: usize = 32;

/// Number of coefficients a [`TaylorSeries`] holds (orders 0 … [`TAYLOR_ORDER_MAX`]).
pub const TAYLOR_LEN: usize = TAYLOR_ORDER_MAX + 1;

/// 1/k for k = 0 … [`TAYLOR_ORDER_MAX`] (0 at k = 0): the recurrences divide by k at every order.
pub const INV: [f64; TAYLOR_LEN] = {
    let mut v = [0.0; TAYLOR_LEN];
    let mut k = 1;
    while k < TAYLOR_LEN {
        v[k] = 1.0 / k as f64;
        k += 1;
    }
    v
};

/// The widest vector instructions of this processor, detected once: the recurrences are compiled
/// for them as well as for the baseline (`pulp`), and run with the widest. Without fused
/// multiply–add contraction (Rust does not contract) AVX2 performs the same IEEE operations in the
/// same order as the baseline: the same coefficients to the bit, in wider registers.
pub(crate) fn simd_arch() -> pulp::Arch {
    static ARCH: std::sync::OnceLock<pulp::Arch> = std::sync::OnceLock::new();
    *ARCH.get_or_init(pulp::Arch::new)
}

/// Taylor coefficients of one slip solution about t₀ (fixed-size arrays: no heap traffic).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TaylorSeries {
    /// βₖ, k = 0 … p.
    pub beta: [f64; TAYLOR_LEN],
    /// ωₖ, k = 0 … p.
    pub omega: [f64; TAYLOR_LEN],
    /// Coefficients of ∂F/∂β along the solution, k = 0 … p − 1 (filled when asked).
    pub d_beta: [f64; TAYLOR_LEN],
    /// Coefficients of ∂F/∂ω along the solution, k = 0 … p − 1 (filled when asked).
    pub d_omega: [f64; TAYLOR_LEN],
    /// True when ∂F/∂ω is constant along the solution (only `d_omega[0]` is used then).
    pub d_omega_constant: bool,
}

impl TaylorSeries {
    /// A series with the initial state (β₀, ω₀) and every other coefficient 0.
    pub fn new(x0: [f64; 2]) -> Self {
        let mut s = Self {
            beta: [0.0; TAYLOR_LEN],
            omega: [0.0; TAYLOR_LEN],
            d_beta: [0.0; TAYLOR_LEN],
            d_omega: [0.0; TAYLOR_LEN],
            d_omega_constant: false,
        };
        s.beta[0] = x0[0];
        s.omega[0] = x0[1];
        s
    }
}

/// A [`DrivenOscillator`] that provides the Taylor coefficients of its slip solutions (module
/// docs), so that it can be integrated by Taylor's method.
///
/// The forces must be analytic along a slip piece (no kink of r inside a step: a system with a
/// [`DrivenOscillator::friction_floor`] is integrated by the Runge–Kutta methods). The
/// coefficients must be those of [`DrivenOscillator::forces`] on side s: `tests/taylor.rs`
/// checks them against the Runge–Kutta flow for the built-in systems.
pub trait TaylorOscillator: DrivenOscillator {
    /// Fills `series.beta[1..=order]` and `series.omega[1..=order]` of the solution on slip side
    /// `side` (±1) through (t₀, β₀, ω₀) = (`t0`, `series.beta[0]`, `series.omega[0]`); with
    /// `linearised`, also `series.d_beta[..order]`, `series.d_omega[..order]` and
    /// `series.d_omega_constant` (the coefficients of ∂F/∂β and ∂F/∂ω, F = a − s r).
    /// `order` ≤ [`TAYLOR_ORDER_MAX`].
    fn taylor_expand(
        &self,
        t0: f64,
        side: f64,
        order: usize,
        series: &mut TaylorSeries,
        linearised: bool,
    );
}
