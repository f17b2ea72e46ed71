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

use crate::model::taylor::{simd_arch, TaylorOscillator, TaylorSeries, INV, TAYLOR_LEN};

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
    /// Jacobian columns by the variational recurrence (module docs), the latter with the
    /// processor's widest vector instructions ([`simd_arch`]).
    #[inline(always)]
    pub fn expand<S: TaylorOscillator + ?Sized>(&mut self, sys: &S, t: f64, y: &[f64; N], s: f64) {
        self.x.beta[0] = y[0];
        self.x.omega[0] = y[1];
        sys.taylor_expand(t, s, self.order, &mut self.x, Self::NCOLS > 0);
        if Self::NCOLS > 0 {
            simd_arch().dispatch(Variational { ex: self, y });
        }
    }

    /// The coefficients of the Jacobian columns, both columns in one pass: the β rows of the two
    /// columns side by side (`zb[k]`, the ω rows `zw[k]`), and the coefficients of ∂F/∂β and
    /// ∂F/∂ω stored last to first, each twice (`db[M − j] = [(∂F/∂β)ⱼ; 2]`), so that every
    /// Cauchy sum runs over two slices in the same direction, four lanes at a time.
    #[inline(always)]
    fn variational(&mut self, y: &[f64; N]) {
        let p = self.order;
        let mut db = [[0.0; 2]; TAYLOR_LEN];
        let mut dw = [[0.0; 2]; TAYLOR_LEN];
        for j in 0..p {
            db[TAYLOR_LEN - 1 - j] = [self.x.d_beta[j]; 2];
            dw[TAYLOR_LEN - 1 - j] = [self.x.d_omega[j]; 2];
        }
        let dw0 = self.x.d_omega[0];
        let mut zb = [[0.0; 2]; TAYLOR_LEN];
        let mut zw = [[0.0; 2]; TAYLOR_LEN];
        zb[0] = [y[2], y[4]];
        zw[0] = [y[3], y[5]];
        for k in 0..p {
            let mut acc = cauchy2(&db, &zb, k);
            let rest = if self.x.d_omega_constant {
                [dw0 * zw[k][0], dw0 * zw[k][1]]
            } else {
                cauchy2(&dw, &zw, k)
            };
            let inv = INV[k + 1];
            for l in 0..2 {
                acc[l] += rest[l];
                zb[k + 1][l] = zw[k][l] * inv;
                zw[k + 1][l] = acc[l] * inv;
            }
        }
        let [c0, c1] = &mut self.z;
        for k in 0..=p {
            [c0[0][k], c1[0][k]] = zb[k];
            [c0[1][k], c1[1][k]] = zw[k];
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

/// [`Expansion::variational`] as an operation that `pulp` compiles for each instruction set
/// (everything it calls is inlined into it).
struct Variational<'a, const N: usize> {
    ex: &'a mut Expansion<N>,
    y: &'a [f64; N],
}

impl<const N: usize> pulp::WithSimd for Variational<'_, N> {
    type Output = ();
    #[inline(always)]
    fn with_simd<V: pulp::Simd>(self, _: V) {
        self.ex.variational(self.y);
    }
}

/// The Cauchy sum Σⱼ dⱼ zₖ₋ⱼ, j = 0 … k, of two lanes, with d stored last to first
/// (`dr[M − j] = dⱼ`, M = [`TAYLOR_LEN`] − 1): Σᵢ dr[M − k + i] zᵢ over i = 0 … k, in two partial
/// sums (even and odd i) so that consecutive additions do not wait for each other.
#[inline(always)]
fn cauchy2(dr: &[[f64; 2]; TAYLOR_LEN], z: &[[f64; 2]; TAYLOR_LEN], k: usize) -> [f64; 2] {
    let (d, z) = (&dr[TAYLOR_LEN - 1 - k..], &z[..=k]);
    let mut a = [[0.0; 2]; 2];
    let (mut dc, mut zc) = (d.chunks_exact(2), z.chunks_exact(2));
    for (dd, zz) in (&mut dc).zip(&mut zc) {
        for l in 0..2 {
            a[0][l] += dd[0][l] * zz[0][l];
            a[1][l] += dd[1][l] * zz[1][l];
        }
    }
    if let (Some(dd), Some(zz)) = (dc.remainder().first(), zc.remainder().first()) {
        for l in 0..2 {
            a[0][l] += dd[l] * zz[l];
        }
    }
    [a[0][0] + a[1][0], a[0][1] + a[1][1]]
}

/// Σₖ cₖ τᵏ by Horner's scheme.
#[inline(always)]
pub(super) fn horner(c: &[f64], tau: f64) -> f64 {
    c.iter().rev().fold(0.0, |acc, &ck| acc * tau + ck)
}
