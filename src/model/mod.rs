//! Periodically driven planar oscillators with dry friction, and the dipole magnetic gear.
//!
//! Every system in gearbif is a [`DrivenOscillator`]: a single angle (or displacement) β with
//! velocity ω = β̇, driven with period T, obeying on either side of the switching surface
//! Σ = {ω = 0}
//!
//! ```text
//!   β̇ = ω,   ω̇ = a(t, β, ω) − s · r(t, β, ω),   s = sgn(ω) ∈ {+1, −1},
//! ```
//!
//! with a smooth force `a` (everything but the dry friction) and a dry-friction magnitude `r ≥ 0`.
//! On Σ the Filippov convention applies: the output *sticks* while |a(t, β, 0)| ≤ r_s(t, β) (the
//! static friction bound, by default r(t, β, 0)), and *crosses* otherwise (numerics.md).
//!
//! The integrator, the maps, the orbit solvers and the continuation only see this trait, so a forced
//! pendulum or a Coulomb-damped linear oscillator ([`oscillators`]) run through the same code as the
//! gear ([`gear`]).

pub mod den_hartog;
pub mod gear;
pub mod oscillators;
pub mod params;

pub use gear::{Convention, Gear, GearParam, GearParams, LockBranch, LockPoint};
pub use oscillators::{CoulombOscillator, CoulombParam, ForcedPendulum, PendulumParam};
pub use params::{param_derivative, Column, Parameter, Parametrised};

/// Maximum number of parameters whose derivative columns a system can expose.
pub const MAX_PARAMS: usize = 8;

/// The forces at one point: smooth part `a` and dry-friction magnitude `r` (eq. of [`DrivenOscillator`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Forces {
    /// Smooth acceleration a(t, β, ω) (all forces but dry friction, per unit inertia).
    pub a: f64,
    /// Dry-friction magnitude r(t, β, ω) ≥ 0 (per unit inertia).
    pub r: f64,
}

/// Forces with their first derivatives with respect to state and parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ForcesJet {
    /// a(t, β, ω).
    pub a: f64,
    /// ∂a/∂β.
    pub a_beta: f64,
    /// ∂a/∂ω.
    pub a_omega: f64,
    /// r(t, β, ω).
    pub r: f64,
    /// ∂r/∂β.
    pub r_beta: f64,
    /// ∂r/∂ω.
    pub r_omega: f64,
    /// ∂a/∂p_k at fixed t (only the first [`DrivenOscillator::n_params`] entries are used).
    pub a_p: [f64; MAX_PARAMS],
    /// ∂r/∂p_k at fixed t.
    pub r_p: [f64; MAX_PARAMS],
}

impl ForcesJet {
    /// A jet with all derivatives zero.
    pub fn new(a: f64, r: f64) -> Self {
        Self {
            a,
            a_beta: 0.0,
            a_omega: 0.0,
            r,
            r_beta: 0.0,
            r_omega: 0.0,
            a_p: [0.0; MAX_PARAMS],
            r_p: [0.0; MAX_PARAMS],
        }
    }
}

/// A half-period symmetry R(β, ω) = (σ β + c, σ ω) with σ = ±1, such that the equations are
/// invariant under (t, β, ω) → (t + T/2, R(β, ω)).
///
/// For the gear, (α, β) → (α + π, β + π) gives σ = +1, c = π (model.md, "Symmetry"); for an
/// odd oscillator driven by cos Ωt, σ = −1, c = 0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HalfPeriodSymmetry {
    /// σ = ±1.
    pub sign: f64,
    /// The shift c added to σβ.
    pub shift: f64,
}

impl HalfPeriodSymmetry {
    /// R(β, ω).
    pub fn apply(&self, x: [f64; 2]) -> [f64; 2] {
        [self.sign * x[0] + self.shift, self.sign * x[1]]
    }
    /// R⁻¹(β, ω) = (σ(β − c), σω).
    pub fn invert(&self, x: [f64; 2]) -> [f64; 2] {
        [self.sign * (x[0] - self.shift), self.sign * x[1]]
    }
}

/// A periodically driven planar oscillator with dry friction (see the module docs for the equations).
///
/// Implementors provide the forces and their derivatives; the integrator handles the switching.
/// The drive phase is referenced to t = 0: every map starts at t = 0 (stroboscopic section).
pub trait DrivenOscillator: Send + Sync {
    /// Drive period T > 0.
    fn period(&self) -> f64;

    /// Number of parameters with derivative columns (≤ [`MAX_PARAMS`]).
    fn n_params(&self) -> usize {
        0
    }

    /// Name of parameter `k` (used in outputs).
    fn param_name(&self, k: usize) -> &'static str {
        let _ = k;
        "?"
    }

    /// dT/dp_k: how the drive period depends on parameter `k` (e.g. −1/f² for the frequency).
    fn period_derivative(&self, k: usize) -> f64 {
        let _ = k;
        0.0
    }

    /// The forces a and r at (t, β, ω).
    fn forces(&self, t: f64, beta: f64, omega: f64) -> Forces;

    /// The forces with their derivatives in state and (when `params` is true) parameters.
    fn forces_jet(&self, t: f64, beta: f64, omega: f64, params: bool) -> ForcesJet;

    /// The static friction bound r_s(t, β) that decides stick versus crossing on Σ.
    /// Defaults to the sliding friction at ω = 0.
    fn static_friction(&self, t: f64, beta: f64) -> f64 {
        self.forces(t, beta, 0.0).r
    }

    /// The first time in [t, t_max] at which an output stuck at β starts to slip, i.e. where
    /// |a(t, β, 0)| reaches r_s(t, β); `None` if it stays stuck through t_max.
    ///
    /// The default scans the interval on a grid of T/512 and refines the first sign change by
    /// bisection to machine precision; systems with an analytic answer (the gear) override it.
    fn next_release(&self, t: f64, beta: f64, t_max: f64) -> Option<f64> {
        default_next_release(self, t, beta, t_max)
    }

    /// The half-period symmetry, if the system has one.
    fn half_period_symmetry(&self) -> Option<HalfPeriodSymmetry> {
        None
    }
}

/// The release function G(t) = |a(t, β, 0)| − r_s(t, β): the output at rest slips once G ≥ 0.
pub fn release_function<S: DrivenOscillator + ?Sized>(sys: &S, t: f64, beta: f64) -> f64 {
    sys.forces(t, beta, 0.0).a.abs() - sys.static_friction(t, beta)
}

/// Generic release search used by [`DrivenOscillator::next_release`].
pub fn default_next_release<S: DrivenOscillator + ?Sized>(
    sys: &S,
    t: f64,
    beta: f64,
    t_max: f64,
) -> Option<f64> {
    let g0 = release_function(sys, t, beta);
    if g0 >= 0.0 {
        return Some(t);
    }
    let dt = sys.period() / 512.0;
    let mut ta = t;
    while ta < t_max {
        let tb = (ta + dt).min(t_max);
        let gb = release_function(sys, tb, beta);
        if gb >= 0.0 {
            // bisection to machine precision on [ta, tb]
            let mut bracket = crate::numerics::Bisection::new(ta, tb);
            while let Some(mid) = bracket.next_point() {
                bracket.update(mid, release_function(sys, mid, beta) >= 0.0);
            }
            return Some(bracket.hi());
        }
        ta = tb;
    }
    None
}
