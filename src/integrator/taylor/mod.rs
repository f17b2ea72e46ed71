//! The event-driven Filippov integrator by Taylor's method, for systems that provide their Taylor
//! coefficients ([`TaylorOscillator`]: the gear, the Coulomb oscillator, or a user's system).
//!
//! Each step expands the slip solution about its start to order p (`expansion.rs`): the state by
//! the system's recurrences, the columns of the state Jacobian Z by the variational recurrence in
//! the same arithmetic. The step size follows from the two highest coefficients: the largest h
//! with |cᵢ,ₖ| hᵏ ≤ atol + rtol·|yᵢ| for k = p − 1, p and every component (β: atol + rtol, an
//! angle on the lift); with coefficients decaying like ρ⁻ᵏ the truncation error is then about
//! tol·h/ρ = tol^(1 + 1/p). No step is rejected. The order is p = ⌈−ln(rtol)/2⌉ + 5 (15 at tol
//! 1e-8, 17 at 1e-10): four above the order that minimises the cost of the recurrences alone
//! (Jorba & Zou 2005), because each step also pays a fixed cost (two sin/cos, the step-size
//! logarithms, the event test); on the gear this gave the fewest steps and the least time at
//! equal error (docs/performance.md, "Event-driven Taylor method").
//!
//! Events: in each step the polynomial ω(t₀ + τ) is tested for a zero of s·ω in (0, h]
//! (`crossing.rs`: a bound on the tail first, then the Bernstein form and de Casteljau
//! subdivision of `bernstein.rs`, then regula falsi); the step ends at the first one, where the
//! arrival is handled as by [`EventDriven853`](super::EventDriven853): crossing, stick (solved
//! directly, release from [`DrivenOscillator::next_release`](crate::model::DrivenOscillator::next_release)),
//! graze, with the saltation matrices of numerics.md. Samples and their Jacobians are read off
//! the step's polynomials.
//!
//! Parameter columns ([`Sensitivity::StateAndParams`]) are not expanded: such a flow is computed
//! by [`EventDriven853`](super::EventDriven853) (same events and saltations), and its `Flow`
//! says so only through its statistics (its steps are Runge–Kutta steps).

mod crossing;
mod expansion;
mod solver;

use super::{EventDriven853, Flow, FlowMethod, FlowOptions, Sensitivity};
use crate::error::Result;
use crate::model::{TaylorOscillator, TAYLOR_ORDER_MAX};

/// Event-driven Filippov integration by Taylor's method with adaptive step (module docs).
/// `Flow::stats.rhs_evals` counts Taylor expansions (one per step).
///
/// ```
/// use gearbif::model::Gear;
/// use gearbif::integrator::{EventDriven853, FlowMethod, FlowOptions, Sensitivity, Taylor};
/// let gear = Gear::paper(25.0, 2.7).unwrap();
/// let opts = FlowOptions::with_tol(1e-12).sensitivity(Sensitivity::State);
/// let a = Taylor.flow(&gear, 0.0, [0.5, 2.0], 1.0 / 2.7, &opts).unwrap();
/// let b = EventDriven853.flow(&gear, 0.0, [0.5, 2.0], 1.0 / 2.7, &opts).unwrap();
/// assert!((a.x[0] - b.x[0]).abs() < 1e-9 && (a.x[1] - b.x[1]).abs() < 1e-9);
/// assert!((a.jac_x.unwrap() - b.jac_x.unwrap()).norm() < 1e-8);
/// ```
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Taylor;

impl Taylor {
    /// The order p for relative tolerance `rtol`: ⌈−ln(rtol)/2⌉ + 5, at most
    /// [`TAYLOR_ORDER_MAX`] (15 at tol 1e-8, 17 at 1e-10).
    pub fn order_for(&self, rtol: f64) -> usize {
        let p = (-rtol.ln() / 2.0).ceil().max(0.0) + 5.0;
        (p as usize).min(TAYLOR_ORDER_MAX)
    }
}

impl<S: TaylorOscillator + ?Sized> FlowMethod<S> for Taylor {
    fn name(&self) -> String {
        "event-driven Taylor".into()
    }
    fn flow(&self, sys: &S, t0: f64, x0: [f64; 2], t1: f64, opts: &FlowOptions) -> Result<Flow> {
        match opts.sensitivity {
            Sensitivity::None => solver::integrate::<S, 2>(self, sys, t0, x0, t1, opts),
            Sensitivity::State => solver::integrate::<S, 6>(self, sys, t0, x0, t1, opts),
            Sensitivity::StateAndParams => EventDriven853.flow(sys, t0, x0, t1, opts),
        }
    }
}
