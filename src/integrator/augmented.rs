//! The augmented state y = (β, ω, Z) shared by all integrators: Z = ∂(β, ω)/∂(β₀, ω₀, p) stored
//! column by column (row β at 2 + 2c, row ω at 3 + 2c), and its right-hand side
//!
//! ```text
//!   β̇ = ω,  ω̇ = a − r φ(ω),   Ż = DF Z + [0 | ∂F/∂p],
//! ```
//!
//! with the friction law φ: φ = s (a slip side, or 0 for a naive sgn at ω = 0) or φ = tanh(ω/ε)
//! (regularised), and dφ/dω its derivative.

use super::Sensitivity;
use crate::model::{DrivenOscillator, MAX_PARAMS};
use nalgebra::{Matrix2, Matrix2xX};

/// Largest augmented dimension: 2 state + 2 rows × (2 + MAX_PARAMS) columns.
pub(super) const NMAX: usize = 2 + 2 * (2 + MAX_PARAMS);
/// A fixed-size augmented state (no heap traffic in the inner loop).
pub(super) type V = [f64; NMAX];

/// Index in y of β (the state's first component).
pub(super) const BETA: usize = 0;
/// Index in y of ω.
pub(super) const OMEGA: usize = 1;
/// Column of Z holding ∂/∂β₀.
pub(super) const COL_BETA0: usize = 0;
/// Column of Z holding ∂/∂ω₀.
pub(super) const COL_OMEGA0: usize = 1;
/// Column of Z holding ∂/∂p_k: parameter columns follow the two state columns.
pub(super) const fn param_col(k: usize) -> usize {
    2 + k
}
/// Index in y of Z's β row in column c: ∂β/∂(column c).
#[inline(always)]
pub(super) const fn z_beta(c: usize) -> usize {
    2 + 2 * c
}
/// Index in y of Z's ω row in column c: ∂ω/∂(column c).
#[inline(always)]
pub(super) const fn z_omega(c: usize) -> usize {
    3 + 2 * c
}

/// Which Jacobian columns an integration carries.
#[derive(Debug, Clone, Copy)]
pub(super) struct Layout {
    /// Number of Jacobian columns (0, 2 or 2 + n_params).
    pub ncols: usize,
    /// Whether the parameter columns are carried.
    pub with_params: bool,
}

impl Layout {
    pub fn new<S: DrivenOscillator + ?Sized>(sys: &S, s: Sensitivity) -> Self {
        let np = sys.n_params().min(MAX_PARAMS);
        let (ncols, with_params) = match s {
            Sensitivity::None => (0, false),
            Sensitivity::State => (2, false),
            Sensitivity::StateAndParams => (2 + np, true),
        };
        Self { ncols, with_params }
    }

    /// The state alone, no Jacobian columns.
    pub const STATE: Layout = Layout {
        ncols: 0,
        with_params: false,
    };

    /// Dimension of the augmented state.
    pub fn dim(&self) -> usize {
        2 + 2 * self.ncols
    }

    /// Writes the initial augmented state: x₀ and Z = [I | 0].
    pub fn init(&self, x0: [f64; 2], y: &mut [f64]) {
        y[..self.dim()].fill(0.0);
        y[BETA] = x0[0];
        y[OMEGA] = x0[1];
        if self.ncols > 0 {
            y[z_beta(COL_BETA0)] = 1.0;
            y[z_omega(COL_OMEGA0)] = 1.0;
        }
    }

    /// The state Jacobian ∂(β, ω)/∂(β₀, ω₀) stored in `y` (components 2..6), if carried.
    pub fn state_jacobian(&self, y: &[f64]) -> Option<Matrix2<f64>> {
        (self.ncols > 0).then(|| {
            Matrix2::new(
                y[z_beta(COL_BETA0)],
                y[z_beta(COL_OMEGA0)],
                y[z_omega(COL_BETA0)],
                y[z_omega(COL_OMEGA0)],
            )
        })
    }

    /// The state and parameter Jacobians stored in `y`.
    pub fn jacobians(&self, y: &[f64]) -> (Option<Matrix2<f64>>, Option<Matrix2xX<f64>>) {
        let Some(jx) = self.state_jacobian(y) else {
            return (None, None);
        };
        let jp = self.with_params.then(|| {
            let np = self.ncols - 2;
            let mut m = Matrix2xX::zeros(np);
            for c in 0..np {
                m[(0, c)] = y[z_beta(param_col(c))];
                m[(1, c)] = y[z_omega(param_col(c))];
            }
            m
        });
        (Some(jx), jp)
    }
}

/// Right-hand side of the augmented system with friction law φ(ω) (value `phi`, derivative
/// `dphi`), on the branch `held` of a floored friction ([`DrivenOscillator::forces_held`]; `None`:
/// the forces as they are).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) fn augmented_rhs_law<S: DrivenOscillator + ?Sized>(
    sys: &S,
    layout: Layout,
    t: f64,
    y: &[f64],
    phi: f64,
    dphi: f64,
    held: Option<bool>,
    out: &mut [f64],
) {
    if layout.ncols == 0 {
        let f = match held {
            None => sys.forces(t, y[0], y[1]),
            Some(floored) => sys.forces_held(t, y[0], y[1], floored),
        };
        out[0] = y[1];
        out[1] = f.a - phi * f.r;
        return;
    }
    let j = match held {
        None => sys.forces_jet(t, y[0], y[1], layout.with_params),
        Some(floored) => sys.forces_jet_held(t, y[0], y[1], layout.with_params, floored),
    };
    out[0] = y[1];
    out[1] = j.a - phi * j.r;
    let db = j.a_beta - phi * j.r_beta;
    let dw = j.a_omega - phi * j.r_omega - dphi * j.r;
    for c in 0..layout.ncols {
        let zb = y[z_beta(c)];
        let zw = y[z_omega(c)];
        out[z_beta(c)] = zw;
        let mut v = db * zb + dw * zw;
        if c >= param_col(0) {
            let k = c - param_col(0);
            v += j.a_p[k] - phi * j.r_p[k];
        }
        out[z_omega(c)] = v;
    }
}

/// Right-hand side on slip side `s` (s = ±1; s = 0 gives the friction-free field of a naive sgn).
#[inline(always)]
pub(super) fn augmented_rhs<S: DrivenOscillator + ?Sized>(
    sys: &S,
    layout: Layout,
    t: f64,
    y: &V,
    s: f64,
    out: &mut V,
) {
    augmented_rhs_law(sys, layout, t, y, s, 0.0, None, out);
}
