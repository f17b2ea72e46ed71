//! The second worked system (docs/second_system.md): Den Hartog's forced oscillator with Coulomb and
//! viscous friction, ẍ + 2ξω₀ẋ + ω₀²x + μ sgn ẋ = F cos 2πft, continued in the forcing frequency
//! by the same continuation as the gear, against Den Hartog's closed-form steady state and the
//! frequency where stops begin.
//!
//! Run: `cargo run --release --example den_hartog`

use gearbif::continuation::{Continuation, ContinuationOptions, SpecialKind};
use gearbif::integrator::{EventDriven, EventKind, FlowOptions};
use gearbif::maps::{poincare_map, Section};
use gearbif::model::den_hartog::{
    den_hartog_coulomb_amplitude, non_stop_orbit, stop_boundary_frequency,
};
use gearbif::model::{CoulombOscillator, CoulombParam};
use gearbif::orbits::OrbitSpec;
use std::f64::consts::TAU;

/// The amplitude of a computed orbit: |x| at its velocity reversals (crossings or stops).
fn numerical_amplitude(osc: &CoulombOscillator, x: [f64; 2]) -> gearbif::Result<f64> {
    let o = FlowOptions::with_tol(1e-12).record_events(true);
    let img = poincare_map(&EventDriven, osc, Section::Stroboscopic, x, 1, &o)?;
    Ok(img
        .events
        .iter()
        .filter(|e| matches!(e.kind, EventKind::Crossing { .. } | EventKind::StickStart))
        .map(|e| e.beta.abs())
        .fold(0.0, f64::max))
}

fn main() -> gearbif::Result<()> {
    // ω₀ = 2π (natural frequency 1 Hz), ξ = 0.05, μ = 0.3, F = 1
    let osc = CoulombOscillator::new(TAU, 0.05, 0.3, 1.0, 2.0)?;
    let start = non_stop_orbit(&osc)?.state(0.0);
    let opts = ContinuationOptions {
        ds: -0.05,
        ds_max: 0.1,
        param_min: 0.3,
        param_max: 2.0,
        ..Default::default()
    };
    let branch =
        Continuation::new(osc, CoulombParam::F, OrbitSpec::symmetric(0), start, opts)?.run(None)?;
    println!(
        "continuation in f from 2 Hz down: {} points, stop: {:?}",
        branch.points.len(),
        branch.stop
    );
    println!(
        "{:>10} {:>14} {:>14} {:>10}",
        "f [Hz]", "X numeric", "X Den Hartog", "rel. diff"
    );
    for p in branch.points.iter().step_by(3) {
        let sys = CoulombOscillator { f: p.param, ..osc };
        let xn = numerical_amplitude(&sys, p.x)?;
        match non_stop_orbit(&sys) {
            Ok(dh) if dh.is_valid() => println!(
                "{:>10.5} {:>14.10} {:>14.10} {:>10.1e}",
                p.param,
                xn,
                dh.amplitude,
                (xn - dh.amplitude).abs() / dh.amplitude
            ),
            _ => println!(
                "{:>10.5} {:>14.10} {:>14} {:>10}",
                p.param, xn, "(stops)", ""
            ),
        }
    }
    let f_b = stop_boundary_frequency(&osc, 0.45, 2.0, 1e-13)?;
    for s in branch.specials_of(SpecialKind::Nonsmooth) {
        let j = s.jump.as_ref().expect("a nonsmooth point carries its jump");
        println!(
            "nonsmooth point at f = {:.10} ± {:.1e} Hz: events per half period {:?} -> {:?}",
            s.param,
            s.precision,
            j.events_before.signature(),
            j.events_after.signature()
        );
    }
    println!(
        "Den Hartog: stops begin at f_b = {f_b:.10} Hz (reversal margin F cos ψ + ω₀²X − μ = 0)"
    );
    // ξ = 0: the boundary-value solution is Den Hartog's U, V formula
    println!(
        "{:>10} {:>16} {:>16}",
        "f [Hz]", "X (ξ = 0)", "Den Hartog U, V"
    );
    for f in [0.6, 1.3, 2.0] {
        let c = CoulombOscillator::new(TAU, 0.0, 0.3, 1.0, f)?;
        let dh = den_hartog_coulomb_amplitude(&c).unwrap_or(f64::NAN);
        println!(
            "{f:>10.3} {:>16.12} {dh:>16.12}",
            non_stop_orbit(&c)?.amplitude
        );
    }
    Ok(())
}
