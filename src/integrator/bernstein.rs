//! The first zero of a continuous extension inside a step, found exactly from its Bernstein form.
//!
//! A polynomial p(θ) = Σₖ bₖ C(d, k) θᵏ (1 − θ)^{d−k} on [0, 1] lies between the smallest and the
//! largest of its Bernstein coefficients bₖ (convex hull property), and has at most as many zeros in
//! (0, 1) as the sequence bₖ has sign changes (Descartes' rule in the Bernstein basis). So all bₖ > 0
//! proves p > 0 on the step, and b₀ > 0 ≥ b_d with one sign change proves exactly one zero; otherwise
//! de Casteljau's algorithm splits the interval at ½ and both halves are tested, the left one first.
//! A touch of p = 0 between any two sample points is found this way, whatever the step length.

use super::tableau::DMAX;

/// Largest number of coefficients (degree + 1) of a continuous extension.
pub(super) const BMAX: usize = 4 + DMAX;

/// Subdivision depth below which an undecided interval (a minimum within rounding of 0, ~2⁻⁴⁰ of
/// the step wide) counts as free of zeros unless its right end is ≤ 0.
const MAX_DEPTH: u32 = 40;

/// Bernstein coefficients on [0, 1] of the nested continuous extension
/// u(θ) = r₀ + θ(r₁ + (1 − θ)(r₂ + θ(r₃ + (1 − θ)(…)))) (`tableau::nested`), scaled by `s`; returns
/// them and the degree m − 1. Multiplying a degree-d form by θ or by 1 − θ is exact in the basis of
/// degree d + 1: (θ b)ₖ = k/(d+1) b_{k−1}, ((1 − θ) b)ₖ = (d+1−k)/(d+1) bₖ; a constant c has all
/// coefficients c.
pub(super) fn from_nested(r: &[f64], s: f64) -> ([f64; BMAX], usize) {
    let m = r.len();
    let mut b = [0.0; BMAX];
    b[0] = s * r[m - 1];
    let mut d = 0;
    for idx in (0..m - 1).rev() {
        let inv = 1.0 / (d + 1) as f64;
        if idx % 2 == 0 {
            // times θ
            for k in (1..=d + 1).rev() {
                b[k] = k as f64 * inv * b[k - 1];
            }
            b[0] = 0.0;
        } else {
            // times 1 − θ
            b[d + 1] = 0.0;
            for (k, bk) in b.iter_mut().enumerate().take(d + 1) {
                *bk *= (d + 1 - k) as f64 * inv;
            }
        }
        d += 1;
        let c = s * r[idx];
        for bk in b.iter_mut().take(d + 1) {
            *bk += c;
        }
    }
    (b, d)
}

/// Fraction of a step that starts on the zero set (just after an event) in which only the sign at
/// its end is tested, as by a sign test at 16 points per step.
pub(super) const START_GUARD: f64 = 1.0 / 16.0;

/// A bracket (lo, hi) ⊂ [0, 1] of the first zero in (0, 1] of the polynomial with Bernstein
/// coefficients `b[..=d]` (any array length M > d: the continuous extensions of the Runge–Kutta
/// pairs and the Taylor polynomials of `taylor/`): p(lo) > 0 (or lo = 0) and p(hi) ≤ 0; `None` if p > 0 on (0, 1].
///
/// A step that starts on the zero set (b₀ ≤ 0, just after an event) is searched exactly only
/// from θ = [`START_GUARD`] on; before it only the sign at the guard counts. Right after a release
/// s·ω grows like (a − s·r)·t, which is 0 at a tangential release, so near the start the sign of
/// the continuous extension is that of its interpolation error, not of ω: an exact search there
/// finds spurious returns to Σ (a release followed at once by a new stick, repeated).
pub(super) fn first_zero<const M: usize>(b: &[f64; M], d: usize) -> Option<(f64, f64)> {
    if b[0] > 0.0 {
        return search(b, d, 0.0, 1.0, 0);
    }
    let right = split_at(b, d, START_GUARD).1;
    if right[0] <= 0.0 {
        return Some((0.0, START_GUARD));
    }
    search(&right, d, START_GUARD, 1.0 - START_GUARD, 0)
}

/// [`first_zero`] on [a, a + w] given p(a) = b₀ > 0.
fn search<const M: usize>(
    b: &[f64; M],
    d: usize,
    a: f64,
    w: f64,
    depth: u32,
) -> Option<(f64, f64)> {
    let mut changes = 0;
    for k in 1..=d {
        if (b[k] > 0.0) != (b[k - 1] > 0.0) {
            changes += 1;
        }
    }
    if changes == 0 {
        return None;
    }
    if changes == 1 || depth >= MAX_DEPTH {
        // one change from b₀ > 0: b_d ≤ 0 and exactly one zero
        return (b[d] <= 0.0).then_some((a, a + w));
    }
    let (left, right) = split(b, d);
    let h = 0.5 * w;
    // the left half has no zero only if p(a + w/2) = left[d] > 0: the right half's precondition
    search(&left, d, a, h, depth + 1).or_else(|| search(&right, d, a + h, h, depth + 1))
}

/// De Casteljau subdivision at θ = ½: the Bernstein coefficients on [0, ½] and on [½, 1].
fn split<const M: usize>(b: &[f64; M], d: usize) -> ([f64; M], [f64; M]) {
    split_at(b, d, 0.5)
}

/// De Casteljau subdivision at θ = τ: the Bernstein coefficients on [0, τ] and on [τ, 1].
fn split_at<const M: usize>(b: &[f64; M], d: usize, tau: f64) -> ([f64; M], [f64; M]) {
    let mut t = *b;
    let mut left = [0.0; M];
    let mut right = [0.0; M];
    left[0] = t[0];
    right[d] = t[d];
    for j in 1..=d {
        for i in 0..=d - j {
            t[i] = (1.0 - tau) * t[i] + tau * t[i + 1];
        }
        left[j] = t[0];
        right[d - j] = t[d - j];
    }
    (left, right)
}

#[cfg(test)]
mod tests {
    use super::super::tableau::nested;
    use super::*;

    fn bern_eval(b: &[f64; BMAX], d: usize, th: f64) -> f64 {
        let mut t = *b;
        for j in 1..=d {
            for i in 0..=d - j {
                t[i] = (1.0 - th) * t[i] + th * t[i + 1];
            }
        }
        t[0]
    }

    #[test]
    fn bernstein_form_equals_nested_form() {
        let r = [0.3, -1.2, 2.5, -0.7, 4.1, 0.9, -3.3, 1.7];
        for m in [4, 5, 8] {
            let (b, d) = from_nested(&r[..m], -1.0);
            assert_eq!(d, m - 1);
            for i in 0..=20 {
                let th = i as f64 / 20.0;
                let want = -nested(&r[..m], th);
                assert!((bern_eval(&b, d, th) - want).abs() < 1e-13, "m {m} θ {th}");
            }
        }
    }

    #[test]
    fn finds_a_narrow_dip_between_any_samples() {
        // p(θ) = (θ − 0.61)² − 1e-10 = θ² − 1.22 θ + 0.3721 − 1e-10: zeros 0.61 ± 1e-5, a dip far
        // narrower than any fixed sampling of the step; as a nested form r = (c, 1 − 1.22 − …).
        // Build the Bernstein form directly: degree 2, b = (c, c − 0.61, c + 1 − 1.22).
        let c = 0.3721 - 1e-10;
        let mut b = [0.0; BMAX];
        b[0] = c;
        b[1] = c - 0.61;
        b[2] = c + 1.0 - 1.22;
        let (lo, hi) = first_zero(&b, 2).unwrap();
        let root = 0.61 - 1e-5;
        assert!(lo < root && root <= hi, "{lo} {hi}");
        assert!(bern_eval(&b, 2, lo) > 0.0 && bern_eval(&b, 2, hi) <= 0.0);
        // lifted by 2e-10 the dip stays above zero: no bracket
        for bk in b.iter_mut().take(3) {
            *bk += 2e-10;
        }
        assert!(first_zero(&b, 2).is_none());
    }

    #[test]
    fn the_first_of_several_zeros_and_a_start_on_the_zero_set() {
        // u(θ) = θ (0.3 − θ)(0.8 − θ): 0 at the start, positive on (0, 0.3), zeros 0.3 and 0.8;
        // monomial coefficients a = (0, 0.24, −1.1, 1), Bernstein bₖ = Σ_{j≤k} C(k, j)/C(3, j) aⱼ
        let u = |th: f64| th * (0.3 - th) * (0.8 - th);
        let a = [0.0, 0.24, -1.1, 1.0];
        let binom = |n: usize, k: usize| -> f64 {
            (0..k).fold(1.0, |acc, i| acc * (n - i) as f64 / (i + 1) as f64)
        };
        let mut b = [0.0; BMAX];
        for (k, bk) in b.iter_mut().enumerate().take(4) {
            *bk = (0..=k).map(|j| binom(k, j) / binom(3, j) * a[j]).sum();
        }
        for i in 0..=10 {
            let th = i as f64 / 10.0;
            assert!((bern_eval(&b, 3, th) - u(th)).abs() < 1e-14);
        }
        let (lo, hi) = first_zero(&b, 3).unwrap();
        assert!(lo < 0.3 && (0.3..0.8).contains(&hi), "{lo} {hi}");
        // leaving the start on the wrong side: −u is ≤ 0 at the guard
        let neg = b.map(|v| -v);
        assert_eq!(first_zero(&neg, 3), Some((0.0, START_GUARD)));
    }
}
