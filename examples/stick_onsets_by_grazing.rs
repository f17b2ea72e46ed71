//! The stick onsets ((0, 0) → (0, 1)) that `gearbif diagram --theta-deg 25 --range 1.5:3` locates
//! by bisection on the event signature, solved as regular roots instead: the grazing system of
//! the one-sided flow (`palc2::locate_grazing`, docs/continuation.md, "Curves of nonsmooth
//! points") at fixed Θ = 25°, by the DP5 and by the DOP853 at three tolerances. The start guesses
//! are the diagram's located states. An independent check of the located points of both methods
//! (docs/continuation.md, "Second method").
//!
//! `cargo run --release --example stick_onsets_by_grazing`

use gearbif::continuation::palc2::{locate_grazing, CurveOptions};
use gearbif::integrator::{EventDriven, EventDriven853, FlowMethod};
use gearbif::model::{Gear, GearParam, OneSided};
use gearbif::orbits::{OrbitSpec, ShootingOptions};

/// One onset: (label, orbit problem, side of Σ the orbit moves on, state guess, f guess).
type Onset = (&'static str, OrbitSpec, f64, [f64; 2], f64);

fn grazing<M: FlowMethod<OneSided<Gear>>>(method: &M, name: &str, onset: &Onset) {
    let (label, spec, side, x, f0) = *onset;
    for tol in [1e-10, 1e-11, 1e-12] {
        let opts = CurveOptions {
            shooting: ShootingOptions {
                tol,
                newton_tol: 1e-10,
                ..Default::default()
            },
            ..Default::default()
        };
        let g = Gear::paper(25.0, f0).expect("a valid gear");
        let (f, th) = (GearParam::F, GearParam::ThetaDeg);
        match locate_grazing(method, &g, &spec, side, f, th, x, f0, &opts) {
            Ok(p) => println!(
                "{label}, {name}, tol {tol:e}: grazing at {:.11} Hz (margin {:.1e})",
                p.free, p.test_value
            ),
            Err(e) => println!("{label}, {name}, tol {tol:e}: {e}"),
        }
    }
}

fn main() {
    let onsets: [Onset; 4] = [
        (
            "asymmetric T, p = +1",
            OrbitSpec::stroboscopic(1, 1),
            1.0,
            [2.8344344126, 0.0414908945],
            2.3703387841,
        ),
        (
            "unstable asymmetric T, p = +1",
            OrbitSpec::stroboscopic(1, 1),
            1.0,
            [1.8900860054, 5.7458617828],
            1.9278115099,
        ),
        (
            "asymmetric T, p = -1",
            OrbitSpec::stroboscopic(1, -1),
            -1.0,
            [0.3083316274, -0.6273029414],
            1.8684689467,
        ),
        (
            "symmetric T/2, p = -1",
            OrbitSpec::symmetric(-1),
            -1.0,
            [0.3090246554, -0.7235603166],
            1.6194888637,
        ),
    ];
    for o in &onsets {
        grazing(&EventDriven, "DP5", o);
        grazing(&EventDriven853, "DOP853", o);
    }
}
