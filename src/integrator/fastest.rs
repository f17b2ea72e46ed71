//! The default method: Taylor's method for the systems that provide their Taylor coefficients,
//! the event-driven DOP853 for the others.

use super::{EventDriven853, Flow, FlowMethod, FlowOptions, Taylor};
use crate::error::Result;
use crate::model::DrivenOscillator;

/// The fastest of gearbif's event-driven methods for each system: [`Taylor`] when the system
/// provides its Taylor coefficients ([`DrivenOscillator::as_taylor`]: the gear, the Coulomb
/// oscillator), [`EventDriven853`] otherwise (and for parameter columns, which Taylor's method
/// hands to the DOP853 itself). Same events, saltation matrices and Jacobians with either; on the
/// gear Taylor's method is several times faster than the DOP853 at equal error
/// (docs/performance.md, "Event-driven Taylor method"), and `tests/taylor.rs` checks that located
/// orbits agree between the two.
///
/// ```
/// use gearbif::model::Gear;
/// use gearbif::integrator::{EventDriven853, Fastest, FlowMethod, FlowOptions};
/// let gear = Gear::paper(25.0, 2.7).unwrap();
/// let opts = FlowOptions::with_tol(1e-10);
/// let a = Fastest.flow(&gear, 0.0, [0.5, 2.0], 1.0 / 2.7, &opts).unwrap();
/// let b = EventDriven853.flow(&gear, 0.0, [0.5, 2.0], 1.0 / 2.7, &opts).unwrap();
/// assert!((a.x[0] - b.x[0]).abs() < 1e-8 && (a.x[1] - b.x[1]).abs() < 1e-8);
/// assert_eq!(a.stats.steps, a.stats.rhs_evals); // one Taylor expansion per step
/// ```
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Fastest;

impl<S: DrivenOscillator + ?Sized> FlowMethod<S> for Fastest {
    fn name(&self) -> String {
        "event-driven Taylor or DOP853".into()
    }
    fn flow(&self, sys: &S, t0: f64, x0: [f64; 2], t1: f64, opts: &FlowOptions) -> Result<Flow> {
        match sys.as_taylor() {
            Some(jet) => Taylor.flow(jet, t0, x0, t1, opts),
            None => EventDriven853.flow(sys, t0, x0, t1, opts),
        }
    }
}
