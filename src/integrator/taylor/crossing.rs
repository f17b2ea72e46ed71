//! The first point of a Taylor step where s·ω reaches 0: a root of the step's polynomial
//! ω(t₀ + θh) = Σₖ ωₖ hᵏ θᵏ, θ ∈ [0, 1], isolated in its Bernstein form (`bernstein.rs`) and
//! refined by Illinois regula falsi on the polynomial.

use super::super::bernstein;
use super::super::event_driven::refine;
use super::expansion::horner;
use crate::model::taylor::TAYLOR_LEN;
use crate::numerics::Illinois;

/// Binomial coefficients C(n, k), n, k ≤ [`crate::model::TAYLOR_ORDER_MAX`] (exact in f64).
const BINOM: [[f64; TAYLOR_LEN]; TAYLOR_LEN] = {
    let mut c = [[0.0; TAYLOR_LEN]; TAYLOR_LEN];
    let mut n = 0;
    while n < TAYLOR_LEN {
        c[n][0] = 1.0;
        let mut k = 1;
        while k <= n {
            c[n][k] = c[n - 1][k - 1] + if k < n { c[n - 1][k] } else { 0.0 };
            k += 1;
        }
        n += 1;
    }
    c
};

/// The first τ ∈ (0, h] with s·ω(t₀ + τ) ≤ 0 on the polynomial of degree `p` with coefficients
/// `w` (ωₖ), or `None` if s·ω > 0 on the step.
///
/// First a bound: s·ω₀ > Σₖ₌₁ |ωₖ| hᵏ proves s·ω > 0 on the step (most steps end here). Else the
/// Bernstein coefficients bᵢ = Σ_{k ≤ i} C(i, k)/C(p, k) s ωₖ hᵏ are searched for the first sign
/// change (`bernstein::first_zero`, which also handles a step starting on Σ).
pub(super) fn first_crossing(w: &[f64; TAYLOR_LEN], p: usize, h: f64, s: f64) -> Option<f64> {
    let tail = w[1..=p]
        .iter()
        .rev()
        .fold(0.0, |acc, &wk| (acc + wk.abs()) * h);
    if s * w[0] > tail {
        return None;
    }
    let mut c = [0.0; TAYLOR_LEN];
    let mut hk = 1.0;
    for (ck, &wk) in c.iter_mut().zip(&w[..=p]) {
        *ck = s * wk * hk;
        hk *= h;
    }
    let mut b = [0.0; TAYLOR_LEN];
    for (i, bi) in b.iter_mut().enumerate().take(p + 1) {
        *bi = (0..=i).map(|k| BINOM[i][k] / BINOM[p][k] * c[k]).sum();
    }
    b[0] = c[0];
    let (lo, hi) = bernstein::first_zero(&b, p)?;
    let e = |th: f64| horner(&c[..=p], th);
    let flo = if lo == 0.0 { c[0].max(0.0) } else { e(lo) };
    let fhi = e(hi);
    let th = refine(Illinois::new(lo, flo, hi, fhi.min(0.0), 0.0), e, 0.0);
    Some(th * h)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn binomials_are_pascals_triangle() {
        assert_eq!(BINOM[5][2], 10.0);
        assert_eq!(BINOM[32][16], 601_080_390.0);
        assert_eq!(BINOM[7][7], 1.0);
    }

    #[test]
    fn finds_the_first_root_of_a_polynomial_and_none_above_zero() {
        // ω(τ) = (0.3 − τ)(0.8 − τ) = 0.24 − 1.1 τ + τ², on h = 1 from side +1: first root 0.3
        let mut w = [0.0; TAYLOR_LEN];
        w[0] = 0.24;
        w[1] = -1.1;
        w[2] = 1.0;
        let tau = first_crossing(&w, 12, 1.0, 1.0).unwrap();
        assert!((tau - 0.3).abs() < 1e-14, "{tau}");
        // half the step: same root; a step of 0.25 ends before it
        assert!((first_crossing(&w, 12, 0.5, 1.0).unwrap() - 0.3).abs() < 1e-14);
        assert!(first_crossing(&w, 12, 0.25, 1.0).is_none());
        // from side −1 the start is already past Σ: a root at once (the start's bracket)
        let neg = first_crossing(&w, 12, 1.0, -1.0).unwrap();
        assert!(neg <= bernstein::START_GUARD, "{neg}");
        // lifted to a narrow dip above zero: none
        w[0] = 0.3025 + 1e-9;
        assert!(first_crossing(&w, 12, 1.0, 1.0).is_none());
        w[0] = 0.3025 - 1e-9;
        let tau = first_crossing(&w, 12, 1.0, 1.0).unwrap();
        assert!((tau - (0.55 - 1e-9_f64.sqrt())).abs() < 1e-9, "{tau}");
    }
}
