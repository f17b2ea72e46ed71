//! The event-driven Filippov integrator by Taylor's method, for systems that provide their Taylor
//! coefficients ([`TaylorOscillator`]: the gear, the Coulomb oscillator, or a user's system).
//!
//! Each step expands the slip solution about its start to order p (`expansion.rs`): the state by
//! the system's recurrences, the columns of the state Jacobian Z by the variational recurrence in
//! the same arithmetic. The step size follows from the two highest coefficients: the largest h
//! with |cᵢ,ₖ| hᵏ ≤ atol + rtol·|yᵢ| for k = p − 1, p and every component (the error of the
//! truncated series is then about tol·h/ρ, ρ the coefficients' decay radius), times a safety
//! factor; no step is rejected. The order is p = ⌈−ln(rtol)/2⌉ + 1 (Jorba & Zou 2005, the order
//! that minimises the work per unit time for coefficients decaying geometrically; 11 at tol
//! 1e-8, 13 at 1e-10).
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
    /// The order p for relative tolerance `rtol`: ⌈−ln(rtol)/2⌉ + 1, within 4 …
    /// [`TAYLOR_ORDER_MAX`].
    pub fn order_for(&self, rtol: f64) -> usize {
        let p = (-rtol.ln() / 2.0).ceil() + 1.0;
        (p.max(4.0) as usize).min(TAYLOR_ORDER_MAX)
    }

    /// The safety factor on the step size at order p: exp(−0.7/(p − 1)) (as in Jorba & Zou's
    /// rule).
    fn safety(&self, order: usize) -> f64 {
        (-0.7 / (order as f64 - 1.0)).exp()
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
