//! Explicit embedded Runge–Kutta pairs with a continuous extension, as data: the event-driven
//! integrator (`event_driven.rs`) runs any [`Tableau`]; Dormand–Prince 5(4) and 8(5,3) are two
//! values of it (`dopri5.rs`, `dop853.rs`).
//!
//! Stage numbering: stage 0 is f(t, y) (first same as last from the previous step); the main stages
//! 0..`stages` give the solution y₁ = y₀ + h Σ bᵢ kᵢ; stage [`Tableau::fsal`] is f(t + h, y₁); the
//! `dense_extra` stages after it are evaluated only when the continuous extension is needed.
//!
//! The continuous extension has Hairer's nested form (Hairer, Nørsett & Wanner, Solving ODEs I,
//! §II.6 and the codes DOPRI5/DOP853), with θ ∈ [0, 1] and θ₁ = 1 − θ:
//!
//! ```text
//!   u(θ) = r₀ + θ (r₁ + θ₁ (r₂ + θ (r₃ + θ₁ (r₄ + θ (r₅ + …))))),
//!   r₀ = y₀,  r₁ = y₁ − y₀,  r₂ = h k₀ − r₁,  r₃ = r₁ − h k_fsal − r₂,  r₄₊ⱼ = h Σᵢ dⱼᵢ kᵢ.
//! ```

/// Largest number of stages (main, first-same-as-last and dense-output stages) of a tableau.
pub(super) const SMAX: usize = 16;
/// Largest number of rows dⱼ of the continuous extension.
pub(super) const DMAX: usize = 4;

/// How the local error estimate is formed from the stages.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum ErrorEstimate {
    /// err = ‖h Σ eᵢ kᵢ / sc‖ (RMS), as in DOPRI5.
    Single,
    /// DOP853: err = h E₅ / √(n (E₅ + 0.01 E₃)) with E₅ = Σ (Σ eᵢ kᵢ / sc)² and
    /// E₃ = Σ (Σ e3ᵢ kᵢ / sc)², the 5th- and 3rd-order estimates.
    Dop853 {
        /// Weights of the 3rd-order estimate.
        e3: [f64; SMAX],
    },
}

/// An embedded explicit Runge–Kutta pair with its continuous extension and step-size controller.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Tableau {
    /// Name for tables ("event-driven DP5").
    pub name: &'static str,
    /// Main stages (including stage 0).
    pub stages: usize,
    /// Whether the last main stage is evaluated at the solution (its row of `a` equals `b`, as in
    /// DOPRI5): then it is also the first-same-as-last stage.
    pub last_stage_is_solution: bool,
    /// Stages evaluated only for the continuous extension (after the first-same-as-last stage).
    pub dense_extra: usize,
    /// Nodes cᵢ.
    pub c: [f64; SMAX],
    /// Coupling coefficients aᵢⱼ (j < i), main and dense-output stages.
    pub a: [[f64; SMAX]; SMAX],
    /// Weights of the propagated solution.
    pub b: [f64; SMAX],
    /// Weights of the (main) error estimate.
    pub e: [f64; SMAX],
    /// Kind of error estimate.
    pub estimate: ErrorEstimate,
    /// Rows dⱼ of the continuous extension (over all stages).
    pub d: [[f64; SMAX]; DMAX],
    /// Number of rows in `d`.
    pub dense_rows: usize,
    /// Exponent of the step-size proposal (1/(q+1), q the order of the error estimate) minus the
    /// PI term (Hairer's expo1 = 1/(q+1) − 0.75 β).
    pub expo: f64,
    /// PI (Lund) stabilisation exponent β.
    pub beta: f64,
    /// Largest gap between consecutive sorted nodes of the main stages (with 0 and 1), as a
    /// fraction of the step.
    pub node_gap: f64,
    /// Smallest ratio h/h_new (1/largest growth of the step).
    pub fac_min: f64,
    /// Largest ratio h/h_new (largest shrinking of the step).
    pub fac_max: f64,
}

/// A pair as a type, so the event-driven solver is compiled with its coefficients as constants.
pub(super) trait Pair: 'static {
    /// The coefficients.
    const TAB: Tableau;
    /// How a step's continuous extension is searched for the first point with s·ω ≤ 0.
    const TOUCH: Touch;
}

/// The search of a step's continuous extension for the first point with s·ω ≤ 0.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Touch {
    /// Sign test at this many equally spaced points of the step (the last one its end): a dip of
    /// ω through 0 that starts and ends between two points is not seen.
    Probes(usize),
    /// Exact: from the Bernstein form of the continuous extension (`bernstein.rs`), whatever
    /// the step length.
    Exact,
}

impl Tableau {
    /// Index of the first-same-as-last stage f(t + h, y₁).
    pub fn fsal(&self) -> usize {
        if self.last_stage_is_solution {
            self.stages - 1
        } else {
            self.stages
        }
    }
    /// err^expo (three square roots for DOP853's 1/8, cheaper than `powf`).
    #[inline(always)]
    pub fn pow_expo(&self, err: f64) -> f64 {
        if self.expo == 0.125 {
            err.sqrt().sqrt().sqrt()
        } else {
            err.powf(self.expo)
        }
    }
    /// Total number of stages including the dense-output ones.
    pub fn total(&self) -> usize {
        self.fsal() + 1 + self.dense_extra
    }
}

/// Evaluates the nested continuous extension u(θ) from its coefficients r₀ … r_{m−1}.
#[inline(always)]
pub(super) fn nested(r: &[f64], th: f64) -> f64 {
    let th1 = 1.0 - th;
    let m = r.len();
    let mut v = r[m - 1];
    for idx in (0..m - 1).rev() {
        let w = if idx % 2 == 0 { th } else { th1 };
        v = r[idx] + w * v;
    }
    v
}

/// Builds an `[f64; SMAX]` from the leading entries.
pub(super) const fn row<const N: usize>(v: [f64; N]) -> [f64; SMAX] {
    let mut r = [0.0; SMAX];
    let mut i = 0;
    while i < N {
        r[i] = v[i];
        i += 1;
    }
    r
}

#[cfg(test)]
mod tests {
    use super::super::{dop853::DOP853, dopri5::DOPRI5};
    use super::*;

    /// Order conditions of a tableau checked as data: row sums Σⱼ aᵢⱼ = cᵢ for all stages,
    /// Σ bᵢ = 1, Σ bᵢ cᵢ = 1/2, Σ bᵢ cᵢ² = 1/3, error weights summing to 0, and the continuous
    /// extension reproducing y₁ at θ = 1 (automatic from the nested form).
    fn check(t: &Tableau, order: usize) {
        for i in 1..t.total() {
            if i == t.fsal() && !t.last_stage_is_solution {
                continue; // evaluated at y₁ (the b row)
            }
            let s: f64 = t.a[i][..i].iter().sum();
            let ci = if i == t.fsal() { 1.0 } else { t.c[i] };
            assert!(
                (s - ci).abs() < 1e-13,
                "{}: row {i} sums to {s}, c = {ci}",
                t.name
            );
        }
        for q in 0..order.min(6) {
            let s: f64 = (0..t.stages).map(|i| t.b[i] * t.c[i].powi(q as i32)).sum();
            assert!(
                (s - 1.0 / (q as f64 + 1.0)).abs() < 1e-12,
                "{}: Σ b c^{q} = {s}",
                t.name
            );
        }
        let se: f64 = t.e.iter().sum();
        assert!(se.abs() < 1e-12, "{}: Σ e = {se}", t.name);
        let mut nodes: Vec<f64> = t.c[..t.stages].to_vec();
        nodes.push(1.0);
        nodes.sort_by(f64::total_cmp);
        let gap = nodes.windows(2).map(|w| w[1] - w[0]).fold(0.0, f64::max);
        assert!(
            (gap - t.node_gap).abs() < 1e-12,
            "{}: node gap {gap}",
            t.name
        );
    }

    #[test]
    fn tableaux_satisfy_quadrature_conditions() {
        check(&DOPRI5, 5);
        check(&DOP853, 8);
    }

    #[test]
    fn nested_form_matches_explicit_cubic() {
        // r = (y0, y1−y0, bspl, …) with a single extra term: u(θ) = r0 + θ r1 + θ(1−θ)(r2 + θ r3)
        let r = [1.0, 2.0, 3.0, 4.0];
        let th = 0.3;
        let u = 1.0 + th * 2.0 + th * (1.0 - th) * (3.0 + th * 4.0);
        assert!((nested(&r, th) - u).abs() < 1e-15);
    }
}
