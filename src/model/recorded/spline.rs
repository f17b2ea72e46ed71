//! Periodic cubic B-splines in the output angle β: the basis of the identification's
//! nonparametric curves of what the catalog does not explain (a torque τ(β), a dry friction
//! η(β)), linear in their coefficients so that the weak-form regression and the refit by
//! simulation fit them like every other term.
//!
//! With n = [`SPLINE_KNOTS`] uniform knots x_j = j h on the period, h = 2π/n, the basis function j
//! is the centred cardinal cubic B-spline
//!
//! ```text
//! B_j(x) = b((x − x_j)/h),   b(t) = (4 − 6t² + 3|t|³)/6  for |t| < 1,
//!                            b(t) = (2 − |t|)³/6        for 1 ≤ |t| < 2,   0 beyond,
//! ```
//!
//! with x − x_j wrapped to the period. The basis is a partition of unity (Σ_j B_j = 1), each
//! B_j is C² and nonzero on four knot intervals, so a curve s(x) = Σ_j c_j B_j(x) is local: a
//! bump at one angle moves only the coefficients near it.

use std::f64::consts::TAU;

/// Knots (and basis functions) of a curve on the period: a spacing of 15°. The best fit of this
/// basis to a Gaussian bump of 15° standard deviation is off by at most 1.2 % of the bump's
/// height wherever the bump sits (8 % with 16 knots, 3.4 % with 20: least squares on a fine
/// grid, the spacing against the bump's width).
pub const SPLINE_KNOTS: usize = 24;

// the coefficient arrays of `Coefficients` are written with the literal length
const _: () = assert!(SPLINE_KNOTS == 24);

/// What a curve in β adds to the model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SplineKind {
    /// A lab-fixed torque τ(β) added to the smooth force, s⁻².
    Torque,
    /// The dry friction η(β): the Coulomb friction as a function of the output angle, s⁻² (it
    /// takes the place of the constant η).
    Friction,
}

impl SplineKind {
    /// Both kinds, in the order the identification tries them.
    pub const ALL: [SplineKind; 2] = [SplineKind::Friction, SplineKind::Torque];
    /// Name (report key `kind` of the curve).
    pub fn name(&self) -> &'static str {
        match self {
            SplineKind::Torque => "torque",
            SplineKind::Friction => "friction",
        }
    }
}

/// The four basis functions nonzero at x: their indices, values and x-derivatives (rad⁻¹).
pub fn basis(x: f64) -> ([usize; 4], [f64; 4], [f64; 4]) {
    const N: f64 = SPLINE_KNOTS as f64;
    const INV_H: f64 = N / TAU;
    const SIXTH: f64 = 1.0 / 6.0;
    // x/h wrapped to [0, n) by its floor (f64::rem_euclid's fmod and the divisions cost more
    // than the rest: this runs at every right-hand side of a curve model)
    let u = x * INV_H;
    let u = u - N * (u * (1.0 / N)).floor();
    let i = (u.max(0.0) as usize).min(SPLINE_KNOTS - 1);
    let f = u - i as f64;
    let g = 1.0 - f;
    let wrap = |k: usize| {
        if k >= SPLINE_KNOTS {
            k - SPLINE_KNOTS
        } else {
            k
        }
    };
    let idx = [wrap(i + SPLINE_KNOTS - 1), i, wrap(i + 1), wrap(i + 2)];
    let (f2, g2) = (f * f, g * g);
    let val = [
        g2 * g * SIXTH,
        (4.0 - 6.0 * f2 + 3.0 * f2 * f) * SIXTH,
        (4.0 - 6.0 * g2 + 3.0 * g2 * g) * SIXTH,
        f2 * f * SIXTH,
    ];
    let du = [
        -0.5 * g2 * INV_H,
        (-2.0 * f + 1.5 * f2) * INV_H,
        (2.0 * g - 1.5 * g2) * INV_H,
        0.5 * f2 * INV_H,
    ];
    (idx, val, du)
}

/// B_j(x), the basis function `j` at x (the weak-form column of a curve's coefficient j).
pub fn basis_value(j: usize, x: f64) -> f64 {
    let (idx, val, _) = basis(x);
    idx.iter()
        .zip(val)
        .filter(|(&k, _)| k == j)
        .map(|(_, v)| v)
        .sum()
}

/// s(x) = Σ_j c_j B_j(x) and its x-derivative.
pub fn eval(coef: &[f64; SPLINE_KNOTS], x: f64) -> (f64, f64) {
    let (idx, val, der) = basis(x);
    let (mut v, mut d) = (0.0, 0.0);
    for k in 0..4 {
        v += coef[idx[k]] * val[k];
        d += coef[idx[k]] * der[k];
    }
    (v, d)
}

/// Whether a curve has a nonzero coefficient (a zero curve is skipped by the right-hand side).
pub fn active(coef: &[f64; SPLINE_KNOTS]) -> bool {
    coef.iter().any(|&c| c != 0.0)
}

/// The cyclic second differences c_{j−1} − 2c_j + c_{j+1} of the coefficients: the rows D of the
/// roughness penalty λ‖Dc‖² (a row per knot, each with the three entries (1, −2, 1)).
pub fn second_differences(coef: &[f64]) -> Vec<f64> {
    let n = coef.len();
    (0..n)
        .map(|j| coef[(j + n - 1) % n] - 2.0 * coef[j] + coef[(j + 1) % n])
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The basis sums to one everywhere, is periodic, and its derivative matches central
    /// differences of the values (step 10⁻⁶).
    #[test]
    fn basis_is_a_periodic_partition_of_unity_with_its_derivative() {
        for k in 0..400 {
            let x = -7.0 + 0.0371 * k as f64;
            let (_, val, _) = basis(x);
            assert!((val.iter().sum::<f64>() - 1.0).abs() < 1e-14, "{x}");
            for j in 0..SPLINE_KNOTS {
                let (a, b) = (basis_value(j, x), basis_value(j, x + TAU));
                assert!((a - b).abs() < 1e-12, "{j} {x}");
            }
            let mut coef = [0.0; SPLINE_KNOTS];
            for (j, c) in coef.iter_mut().enumerate() {
                *c = ((j * 7 + 3) % 5) as f64 - 2.0;
            }
            let (_, d) = eval(&coef, x);
            let h = 1e-6;
            let fd = (eval(&coef, x + h).0 - eval(&coef, x - h).0) / (2.0 * h);
            assert!((d - fd).abs() < 1e-6, "{x}: {d} {fd}");
        }
    }

    /// A basis function peaks at its knot with b(0) = 2/3 and is 1/6 one knot away.
    #[test]
    fn basis_function_values_at_the_knots() {
        let h = TAU / SPLINE_KNOTS as f64;
        assert!((basis_value(3, 3.0 * h) - 2.0 / 3.0).abs() < 1e-14);
        assert!((basis_value(3, 4.0 * h) - 1.0 / 6.0).abs() < 1e-14);
        assert!((basis_value(0, TAU - h) - 1.0 / 6.0).abs() < 1e-14);
        assert!(basis_value(3, 6.0 * h).abs() < 1e-14);
    }

    /// Constant and linear coefficients have zero second differences (a constant curve is not
    /// penalised), a single spike −2 at its knot.
    #[test]
    fn second_differences_vanish_on_a_constant() {
        assert!(second_differences(&[2.0; 5])
            .iter()
            .all(|d| d.abs() < 1e-15));
        let d = second_differences(&[0.0, 0.0, 1.0, 0.0, 0.0]);
        assert_eq!(d, vec![0.0, 1.0, -2.0, 1.0, 0.0]);
    }
}
