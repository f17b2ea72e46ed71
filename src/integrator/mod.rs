//! Integration of a [`DrivenOscillator`]: the problem (system, interval, options) is separate from
//! the method ([`FlowMethod`]), so methods can be compared on the same problem
//! (`gearbif bench-integrators`) and a user's own method plugs in through the same trait.
//!
//! Methods:
//! - [`EventDriven`]: the exact Filippov integrator — adaptive Dormand–Prince 5(4) with dense
//!   output, crossings of Σ = {ω = 0} located on the dense output, stick phases solved directly
//!   (no integration while stuck), and variational equations with saltation matrices at every event,
//!   so the Jacobian of the flow with respect to the initial state and the parameters comes out of
//!   one integration (numerics.md, "Monodromy with saltation matrices").
//! - [`EventDriven853`]: the same event handling with Dormand–Prince 8(5,3) and its continuous
//!   extension of order 7 (fewer, longer steps; the Runge–Kutta pairs are data, `tableau.rs`).
//! - [`Taylor`]: the same event handling with Taylor's method of adaptive step, for systems that
//!   provide their Taylor coefficients ([`TaylorOscillator`](crate::model::TaylorOscillator): the
//!   gear, the Coulomb oscillator); crossings of Σ are roots of each step's polynomial.
//! - [`FixedStep`]: the paper's scheme — classical RK4 with a fixed step Δt = T/n (n = 50 in the paper)
//!   and a naive sgn(ω); kept as a comparison method (it chatters around Σ).
//! - `Regularised` (feature `diffsol-check`): friction η tanh(ω/ε) integrated as a stiff ODE by
//!   diffsol; an independent cross-check.

mod augmented;
mod bernstein;
mod dop853;
mod dopri5;
mod event_driven;
mod fastest;
mod fixed_step;
#[cfg(feature = "diffsol-check")]
mod regularised;
mod tableau;
mod taylor;

pub use dop853::EventDriven853;
pub use dopri5::EventDriven;
pub use taylor::Taylor;

pub use fastest::Fastest;

/// The method of the library's entry points that take none (`maps::stroboscopic`,
/// `maps::half_period`, single shooting `orbits::shoot` and its relatives, one-parameter
/// continuation `Continuation::new`, `switch_branch`, `diagram`, multiple shooting,
/// `two_param::locate_augmented` and `follow`, the lock-loss curves, the classification of
/// `sweep::hysteresis`, the CLI's `locate`, `boundary` and `classify`): [`Fastest`], Taylor's
/// method for the systems that provide their Taylor coefficients (the gear, the Coulomb
/// oscillator) and the event-driven Dormand–Prince 8(5,3) for the others. Taylor's method is
/// several times faster than the DOP853 on the gear at every tolerance of docs/tables/peers.md,
/// and the DOP853 is faster than the DP5 at every tolerance of the work-precision table in
/// docs/performance.md. The CLI's `--method` default stays `dop853` (it also serves recorded
/// models, which have no Taylor coefficients). The global events (`analysis::global_events`) and
/// the identification's ring-down fits, stick windows and synthesis use [`EventDriven`] (the
/// DP5); docs/performance.md, "Which method is the default where", has the full table. The
/// `_with` variants take any [`FlowMethod`].
pub type DefaultMethod = Fastest;

/// The value of [`DefaultMethod`].
pub const DEFAULT_METHOD: DefaultMethod = Fastest;
pub use fixed_step::FixedStep;
#[cfg(feature = "diffsol-check")]
pub use regularised::{ImplicitMethod, Regularised};

use crate::error::{Error, Result};
use crate::model::DrivenOscillator;
use nalgebra::{Matrix2, Matrix2xX};
use serde::{Deserialize, Serialize};

/// Where the trajectory is with respect to the switching surface Σ = {ω = 0}.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    /// Slipping with ω > 0 (s = +1).
    Positive,
    /// Slipping with ω < 0 (s = −1).
    Negative,
    /// Stuck on Σ: ω = 0, β constant (attracting sliding with zero sliding field).
    Stick,
}

impl std::fmt::Display for Mode {
    /// "ω > 0", "ω < 0" or "stuck".
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Mode::Positive => "ω > 0",
            Mode::Negative => "ω < 0",
            Mode::Stick => "stuck",
        })
    }
}

impl Mode {
    /// s = +1, −1, or 0 while stuck.
    pub fn side(self) -> f64 {
        match self {
            Mode::Positive => 1.0,
            Mode::Negative => -1.0,
            Mode::Stick => 0.0,
        }
    }
    fn from_side(s: f64) -> Self {
        if s > 0.0 {
            Mode::Positive
        } else {
            Mode::Negative
        }
    }
}

/// What happened at an event on Σ.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum EventKind {
    /// ω changed sign: |a| > r_s on Σ. Saltation diag(1, a_after/a_before).
    Crossing {
        /// Side before (+1/−1).
        from: i8,
        /// Side after.
        to: i8,
    },
    /// ω reached 0 with |a| ≤ r_s: the output sticks. Saltation diag(1, 0).
    StickStart,
    /// The stuck output starts to slip: |a| reached r_s. Saltation I for r_s = r(t, β, 0).
    Release {
        /// Side it leaves to.
        to: i8,
    },
    /// ω touched 0 and the trajectory returned to the same side (tangency with Σ).
    Graze {
        /// The side it stays on.
        side: i8,
    },
}

/// An event on the switching surface.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Event {
    /// Time of the event.
    pub t: f64,
    /// β at the event (ω = 0 there).
    pub beta: f64,
    /// What happened.
    #[serde(flatten)]
    pub kind: EventKind,
}

/// Which Jacobians to propagate alongside the state.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Sensitivity {
    /// State only.
    #[default]
    None,
    /// ∂x(t₁)/∂x(t₀).
    State,
    /// ∂x(t₁)/∂x(t₀) and ∂x(t₁)/∂p at fixed t₁ (all [`DrivenOscillator::n_params`] columns).
    StateAndParams,
}

/// Options of a flow computation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FlowOptions {
    /// Relative tolerance of the local error.
    pub rtol: f64,
    /// Absolute tolerance of the local error.
    pub atol: f64,
    /// Largest step, as a fraction of the drive period (default 1/8).
    pub max_step_fraction: f64,
    /// Largest number of steps before giving up.
    pub max_steps: usize,
    /// Which Jacobians to propagate.
    pub sensitivity: Sensitivity,
    /// Record the events on Σ.
    pub record_events: bool,
    /// Times at which to record (t, β, ω); sorted ascending, inside [t₀, t₁].
    pub sample_times: Vec<f64>,
}

impl Default for FlowOptions {
    fn default() -> Self {
        Self {
            rtol: 1e-9,
            atol: 1e-12,
            max_step_fraction: 0.125,
            max_steps: 50_000_000,
            sensitivity: Sensitivity::None,
            record_events: false,
            sample_times: Vec::new(),
        }
    }
}

impl FlowOptions {
    /// Options with tolerance `tol` (rtol = tol, atol = tol·1e-3).
    pub fn with_tol(tol: f64) -> Self {
        Self {
            rtol: tol,
            atol: tol * 1e-3,
            ..Self::default()
        }
    }
    /// Sets the sensitivities to propagate.
    pub fn sensitivity(mut self, s: Sensitivity) -> Self {
        self.sensitivity = s;
        self
    }
    /// Records events.
    pub fn record_events(mut self, on: bool) -> Self {
        self.record_events = on;
        self
    }
    /// Records samples at the given times.
    pub fn samples(mut self, times: Vec<f64>) -> Self {
        self.sample_times = times;
        self
    }
    /// Validates the options.
    pub fn validate(&self) -> Result<()> {
        crate::error::positive("rtol", self.rtol)?;
        crate::error::non_negative("atol", self.atol)?;
        crate::error::positive("max_step_fraction", self.max_step_fraction)?;
        if let Some(&t) = self.sample_times.iter().find(|t| !t.is_finite()) {
            return Err(Error::InvalidTimes {
                t0: t,
                t1: t,
                reason: "sample times must be finite",
            });
        }
        if let Some(w) = self.sample_times.windows(2).find(|w| w[0] > w[1]) {
            return Err(Error::InvalidTimes {
                t0: w[0],
                t1: w[1],
                reason: "sample times must be sorted ascending",
            });
        }
        Ok(())
    }
}

/// One recorded sample of the trajectory.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Sample {
    /// Time.
    pub t: f64,
    /// β (on the lift: windings counted).
    pub beta: f64,
    /// ω = β̇.
    pub omega: f64,
}

/// Work counters of a flow computation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct Stats {
    /// Right-hand-side evaluations (with or without the variational part).
    pub rhs_evals: usize,
    /// Accepted steps.
    pub steps: usize,
    /// Rejected steps.
    pub rejected: usize,
    /// Events handled.
    pub events: usize,
}

impl std::ops::AddAssign for Stats {
    fn add_assign(&mut self, o: Self) {
        self.rhs_evals += o.rhs_evals;
        self.steps += o.steps;
        self.rejected += o.rejected;
        self.events += o.events;
    }
}

/// The result of integrating from t₀ to t₁.
#[derive(Debug, Clone, PartialEq)]
pub struct Flow {
    /// Final time t₁.
    pub t: f64,
    /// Final state (β, ω); β on the lift.
    pub x: [f64; 2],
    /// Mode at t₁.
    pub mode: Mode,
    /// ∂x(t₁)/∂x(t₀), if requested.
    pub jac_x: Option<Matrix2<f64>>,
    /// ∂x(t₁)/∂p at fixed t₁, one column per parameter, if requested.
    pub jac_p: Option<Matrix2xX<f64>>,
    /// Events, if requested.
    pub events: Vec<Event>,
    /// Samples at the requested times.
    pub samples: Vec<Sample>,
    /// ∂(β, ω)(tᵢ)/∂(β₀, ω₀) at each sample, when a sensitivity is requested: the variational
    /// columns on the continuous extension, with the saltation matrices of the events before tᵢ
    /// (the derivative of the computed samples, e.g. for a Gauss–Newton fit of the initial
    /// state). Filled by the event-driven methods ([`EventDriven`], [`EventDriven853`]); empty
    /// otherwise.
    pub sample_jacobians: Vec<Matrix2<f64>>,
    /// Work counters.
    pub stats: Stats,
}

/// A method that integrates a driven oscillator over an interval.
///
/// Implement it to benchmark your own integrator against gearbif's in `bench-integrators`.
pub trait FlowMethod<S: DrivenOscillator + ?Sized>: Send + Sync {
    /// A short name for tables and figures.
    fn name(&self) -> String;
    /// Integrates from (t₀, x₀) to t₁ ≥ t₀.
    fn flow(&self, sys: &S, t0: f64, x0: [f64; 2], t1: f64, opts: &FlowOptions) -> Result<Flow>;
}

/// The mode of a state at time t: the side of ω, or, on Σ, stick if |a| ≤ r_s and otherwise the
/// side the acceleration points to.
pub fn initial_mode<S: DrivenOscillator + ?Sized>(sys: &S, t: f64, x: [f64; 2]) -> Mode {
    if x[1] > 0.0 {
        Mode::Positive
    } else if x[1] < 0.0 {
        Mode::Negative
    } else {
        let a = sys.forces(t, x[0], 0.0).a;
        if a.abs() <= sys.static_friction(t, x[0]) {
            Mode::Stick
        } else {
            Mode::from_side(a.signum())
        }
    }
}

/// The Filippov vector field at (t, x) in mode `m`: (ω, a − s r) when slipping, 0 when stuck.
pub fn vector_field<S: DrivenOscillator + ?Sized>(
    sys: &S,
    t: f64,
    x: [f64; 2],
    m: Mode,
) -> [f64; 2] {
    match m {
        Mode::Stick => [0.0, 0.0],
        _ => {
            let f = sys.forces(t, x[0], x[1]);
            [x[1], f.a - m.side() * f.r]
        }
    }
}

pub(crate) fn check_interval(t0: f64, x0: [f64; 2], t1: f64) -> Result<()> {
    if !t0.is_finite() || !t1.is_finite() {
        return Err(Error::InvalidTimes {
            t0,
            t1,
            reason: "times must be finite",
        });
    }
    if t1 < t0 {
        return Err(Error::InvalidTimes {
            t0,
            t1,
            reason: "t1 is before t0: only forward integration is supported",
        });
    }
    crate::error::finite_state("initial state", &x0)
}
