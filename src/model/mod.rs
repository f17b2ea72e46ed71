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
pub mod expression;
pub mod gear;
pub mod one_sided;
pub mod oscillators;
pub mod params;
pub mod ramped;
pub mod recorded;
pub mod taylor;

pub use gear::{Convention, Gear, GearParam, GearParams, LockBranch, LockPoint};
pub use one_sided::OneSided;
pub use oscillators::{CoulombOscillator, CoulombParam, ForcedPendulum, PendulumParam};
pub use params::{param_derivative, Column, Parameter, Parametrised};
pub use ramped::Ramped;
pub use taylor::{TaylorOscillator, TaylorSeries, TAYLOR_ORDER_MAX};

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
///
/// # What a system must implement
///
/// - [`period`](Self::period): the drive period T;
/// - [`forces`](Self::forces): the smooth force a(t, β, ω) and the dry-friction magnitude
///   r(t, β, ω) ≥ 0 (per unit inertia);
/// - [`forces_jet`](Self::forces_jet): the same with ∂a/∂β, ∂a/∂ω, ∂r/∂β, ∂r/∂ω and, when asked,
///   the parameter derivatives ∂a/∂p_k, ∂r/∂p_k of its first [`n_params`](Self::n_params)
///   parameters (the Jacobian columns; the period's dependence goes in
///   [`period_derivative`](Self::period_derivative));
/// - optionally: the half-period symmetry (symmetric orbits, the half-period map), a static
///   friction bound, an analytic release time, whether β is an angle.
///
/// To be continued, swept or switched, a system also implements [`Parametrised`] (its parameters).
/// Every Jacobian can be checked against finite differences of the map (tests/core.rs does so for
/// the built-in systems). A linear oscillator with Coulomb friction, its periodic orbit shot, and
/// one continuation step in the forcing frequency:
///
/// ```
/// use gearbif::continuation::{Continuation, ContinuationOptions, StepOutcome};
/// use gearbif::model::{
///     Column, DrivenOscillator, Forces, ForcesJet, HalfPeriodSymmetry, Parameter, Parametrised,
/// };
/// use gearbif::orbits::{shoot, OrbitSpec, ShootingOptions};
/// use serde::{Deserialize, Serialize};
/// use std::f64::consts::TAU;
///
/// /// ẍ + 0.2ẋ + 4π²x + 0.5 sgn ẋ = 3 cos 2πft
/// #[derive(Clone)]
/// struct Slider {
///     f: f64,
/// }
///
/// #[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
/// enum P {
///     F,
/// }
///
/// impl Parameter for P {
///     const ALL: &'static [Self] = &[P::F];
///     fn name(self) -> &'static str {
///         "f"
///     }
/// }
///
/// impl DrivenOscillator for Slider {
///     fn period(&self) -> f64 {
///         1.0 / self.f
///     }
///     fn n_params(&self) -> usize {
///         1
///     }
///     fn period_derivative(&self, _k: usize) -> f64 {
///         -1.0 / (self.f * self.f) // dT/df
///     }
///     fn forces(&self, t: f64, x: f64, v: f64) -> Forces {
///         let a = 3.0 * (TAU * self.f * t).cos() - 0.2 * v - TAU * TAU * x;
///         Forces { a, r: 0.5 }
///     }
///     fn forces_jet(&self, t: f64, x: f64, v: f64, params: bool) -> ForcesJet {
///         let mut j = ForcesJet::new(self.forces(t, x, v).a, 0.5);
///         j.a_beta = -TAU * TAU;
///         j.a_omega = -0.2;
///         if params {
///             j.a_p[0] = -3.0 * (TAU * self.f * t).sin() * TAU * t; // ∂a/∂f
///         }
///         j
///     }
///     fn half_period_symmetry(&self) -> Option<HalfPeriodSymmetry> {
///         Some(HalfPeriodSymmetry { sign: -1.0, shift: 0.0 }) // x → −x
///     }
///     fn angular(&self) -> bool {
///         false // x is a displacement
///     }
/// }
///
/// impl Parametrised for Slider {
///     type Param = P;
///     fn param(&self, _p: P) -> f64 {
///         self.f
///     }
///     fn with_param(&self, _p: P, v: f64) -> gearbif::Result<Self> {
///         if v > 0.0 {
///             Ok(Slider { f: v })
///         } else {
///             Err(gearbif::Error::InvalidParameter { name: "f", value: v, reason: "must be > 0" })
///         }
///     }
///     fn column(&self, _p: P) -> Option<Column> {
///         Some(Column::primary(0))
///     }
/// }
///
/// let sys = Slider { f: 1.5 };
/// let orbit = shoot(&sys, &OrbitSpec::symmetric(0), [0.05, 0.0], &ShootingOptions::default())?;
/// assert!(orbit.floquet.stable && orbit.events.crossings == 1); // one reversal per half period
/// let mut c = Continuation::from_orbit(sys, P::F, &orbit, ContinuationOptions::default())?;
/// assert!(matches!(c.step()?, StepOutcome::Point(_)));
/// assert_eq!(c.branch().points.len(), 2);
/// # Ok::<(), gearbif::Error>(())
/// ```
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

    /// The switching function ρ(t, β, ω) of a dry friction floored at zero, r = max(ρ, 0) + (a
    /// part that stays ≥ 0): r is continuous but has a kink where ρ changes sign. `None` (the
    /// default) when r has no such floor. A step of the event-driven integrator that is rejected
    /// with ρ on opposite sides at its ends is tried again on the branch of its start
    /// ([`Self::forces_held`]) and ended where ρ changes sign, as a step is ended on Σ: a step
    /// across the kink would be rejected over and over (docs/model.md, "A friction floored at
    /// zero").
    fn friction_floor(&self, t: f64, beta: f64, omega: f64) -> Option<f64> {
        let _ = (t, beta, omega);
        None
    }

    /// [`Self::forces`] on one branch of the floor of [`Self::friction_floor`]: `floored`, the
    /// floored part of r is 0; else it is ρ, continued smoothly where ρ < 0. The default (no
    /// floor) is [`Self::forces`].
    fn forces_held(&self, t: f64, beta: f64, omega: f64, floored: bool) -> Forces {
        let _ = floored;
        self.forces(t, beta, omega)
    }

    /// [`Self::forces_jet`] on one branch of the floor ([`Self::forces_held`]).
    fn forces_jet_held(
        &self,
        t: f64,
        beta: f64,
        omega: f64,
        params: bool,
        floored: bool,
    ) -> ForcesJet {
        let _ = floored;
        self.forces_jet(t, beta, omega, params)
    }

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

    /// True (default) if β is an angle: states may be reduced modulo 2π and orbits wind; false for
    /// a displacement (e.g. [`CoulombOscillator`]), which is never reduced and has winding 0.
    fn angular(&self) -> bool {
        true
    }

    /// β reduced to its representative: unchanged for a displacement; for an angle in [−π, π) when
    /// the half-period symmetry reflects (σ = −1, orbits centred on 0), else in [0, 2π).
    fn reduce_angle(&self, beta: f64) -> f64 {
        use std::f64::consts::{PI, TAU};
        if !self.angular() {
            beta
        } else if self.half_period_symmetry().is_some_and(|r| r.sign < 0.0) {
            (beta + PI).rem_euclid(TAU) - PI
        } else {
            beta.rem_euclid(TAU)
        }
    }

    /// The drive phase α(t) against which the paper's metrics fit the response (default 2πt/T).
    fn drive_phase(&self, t: f64) -> f64 {
        std::f64::consts::TAU * t / self.period()
    }

    /// The sense s of an output that turns with the drive: the paper's metrics fit δ = β − s·α.
    /// ±1 for a rotor following the drive (the gear), 0 (default) for an oscillator, where δ = β.
    fn co_rotation(&self) -> f64 {
        0.0
    }

    /// This system as a [`TaylorOscillator`] when it provides the Taylor coefficients of its
    /// slip solutions, so that the default method
    /// ([`Fastest`](crate::integrator::Fastest)) integrates it by Taylor's method; `None` (the
    /// default) otherwise.
    fn as_taylor(&self) -> Option<&dyn TaylorOscillator> {
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
