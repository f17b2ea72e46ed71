//! The event-driven integrator with Dormand–Prince 5(4) (Dormand & Prince 1980) and Shampine's
//! continuous extension of order 4 (as in Hairer's DOPRI5); the event location, stick phases and
//! saltation matrices are those of `event_driven.rs`.

use super::tableau::{row, ErrorEstimate, Pair, Tableau, Touch, SMAX};
use super::{FlowMethod, FlowOptions};
use crate::error::Result;
use crate::integrator::Flow;
use crate::model::DrivenOscillator;

const B: [f64; SMAX] = row([
    35.0 / 384.0,
    0.0,
    500.0 / 1113.0,
    125.0 / 192.0,
    -2187.0 / 6784.0,
    11.0 / 84.0,
]);

/// Dormand–Prince 5(4): nodes, coupling coefficients, weights, error weights (b − b̂) and the
/// continuous extension's row d (Hairer, Nørsett & Wanner, Table II.5.2 and §II.6).
pub(super) const DOPRI5: Tableau = Tableau {
    name: "event-driven DP5",
    stages: 7,
    last_stage_is_solution: true,
    dense_extra: 0,
    c: row([0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0]),
    a: [
        row([]),
        row([1.0 / 5.0]),
        row([3.0 / 40.0, 9.0 / 40.0]),
        row([44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0]),
        row([
            19372.0 / 6561.0,
            -25360.0 / 2187.0,
            64448.0 / 6561.0,
            -212.0 / 729.0,
        ]),
        row([
            9017.0 / 3168.0,
            -355.0 / 33.0,
            46732.0 / 5247.0,
            49.0 / 176.0,
            -5103.0 / 18656.0,
        ]),
        B,
        row([]),
        row([]),
        row([]),
        row([]),
        row([]),
        row([]),
        row([]),
        row([]),
        row([]),
    ],
    b: B,
    e: row([
        71.0 / 57600.0,
        0.0,
        -71.0 / 16695.0,
        71.0 / 1920.0,
        -17253.0 / 339200.0,
        22.0 / 525.0,
        -1.0 / 40.0,
    ]),
    estimate: ErrorEstimate::Single,
    d: [
        row([
            -12715105075.0 / 11282082432.0,
            0.0,
            87487479700.0 / 32700410799.0,
            -10690763975.0 / 1880347072.0,
            701980252875.0 / 199316789632.0,
            -1453857185.0 / 822651844.0,
            69997945.0 / 29380423.0,
        ]),
        row([]),
        row([]),
        row([]),
    ],
    dense_rows: 1,
    expo: 0.2 - 0.04 * 0.75,
    beta: 0.04,
    node_gap: 0.5,
    fac_min: 0.1,
    fac_max: 5.0,
};

/// DP5 with 8 interior probes per step for a sign change of ω.
pub(super) struct Dp5;

impl Pair for Dp5 {
    const TAB: Tableau = DOPRI5;
    const TOUCH: Touch = Touch::Probes(8);
}

/// The exact event-driven Filippov integrator with adaptive Dormand–Prince 5(4).
///
/// ```
/// use gearbif::model::Gear;
/// use gearbif::integrator::{EventDriven, FlowMethod, FlowOptions, Sensitivity};
/// let gear = Gear::paper(25.0, 2.7).unwrap();
/// let opts = FlowOptions::with_tol(1e-10).sensitivity(Sensitivity::State);
/// let flow = EventDriven.flow(&gear, 0.0, [3.0, 0.0], 1.0 / 2.7, &opts).unwrap();
/// let m = flow.jac_x.unwrap(); // monodromy-type Jacobian of the stroboscopic map
/// assert!(m.determinant().is_finite());
/// ```
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct EventDriven;

impl<S: DrivenOscillator + ?Sized> FlowMethod<S> for EventDriven {
    fn name(&self) -> String {
        DOPRI5.name.into()
    }
    fn flow(&self, sys: &S, t0: f64, x0: [f64; 2], t1: f64, opts: &FlowOptions) -> Result<Flow> {
        super::event_driven::integrate::<Dp5, S>(sys, t0, x0, t1, opts)
    }
}
