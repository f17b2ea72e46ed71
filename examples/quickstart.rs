//! Quick start: the paper's gear at Θ = 25°, driven at 2.7 Hz. Integrate ten periods exactly, then
//! apply the stroboscopic map P_T to the final state and read its multipliers.
//!
//! Run: `cargo run --release --example quickstart`

use gearbif::integrator::{EventDriven, FlowMethod, FlowOptions, Sensitivity};
use gearbif::maps::{multipliers, poincare_map, Section};
use gearbif::model::Gear;

fn main() -> gearbif::Result<()> {
    let gear = Gear::paper(25.0, 2.7)?; // Θ = Φ = 25°, f = 2.7 Hz, the paper's m, r, I, ζ, η
    let period = 1.0 / gear.f;
    // ten periods of transient from rest at β = 0.5 rad, recording the events on ω = 0
    let opts = FlowOptions::with_tol(1e-10).record_events(true);
    let flow = EventDriven.flow(&gear, 0.0, [0.5, 0.0], 10.0 * period, &opts)?;
    println!(
        "after 10 periods: β = {:.6} rad, ω = {:.6} rad/s, {} events on ω = 0",
        flow.x[0],
        flow.x[1],
        flow.events.len()
    );
    // P_T with its Jacobian (saltation matrices included) and the multipliers
    let opts = FlowOptions::with_tol(1e-10).sensitivity(Sensitivity::State);
    let img = poincare_map(&EventDriven, &gear, Section::Stroboscopic, flow.x, 1, &opts)?;
    let jac = img.jac_x.expect("requested");
    let mu = multipliers(&jac);
    println!(
        "P_T: winding {:.4}, |μ| = {:.4}, {:.4}",
        (img.x[0] - flow.x[0]) / std::f64::consts::TAU,
        mu[0].norm(),
        mu[1].norm()
    );
    Ok(())
}
