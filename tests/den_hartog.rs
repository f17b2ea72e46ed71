//! The second worked system: Den Hartog's harmonically forced oscillator with Coulomb and viscous
//! friction, continued in the forcing frequency by the generic continuation and compared with the
//! closed-form continuous-motion steady state and the frequency where stops begin.

use gearbif::continuation::{Continuation, ContinuationOptions, SpecialKind};
use gearbif::model::den_hartog::{
    den_hartog_coulomb_amplitude, non_stop_orbit, stop_boundary_frequency,
};
use gearbif::model::{CoulombOscillator, CoulombParam};
use gearbif::orbits::{shoot, OrbitSpec, ShootingOptions};
use std::f64::consts::TAU;

/// ω₀ = 2π (f₀ = 1 Hz), ξ = 0.05, μ = 0.3, F = 1.
fn oscillator(f: f64) -> CoulombOscillator {
    CoulombOscillator::new(TAU, 0.05, 0.3, 1.0, f).unwrap()
}

#[test]
fn closed_form_reduces_to_den_hartog_coulomb_formula() {
    // ξ = 0: the boundary-value solution against Den Hartog's U, V formula (two derivations)
    for &f in &[0.6, 0.8, 1.3, 2.0, 3.5] {
        let osc = CoulombOscillator::new(TAU, 0.0, 0.3, 1.0, f).unwrap();
        let x = non_stop_orbit(&osc).unwrap().amplitude;
        let dh = den_hartog_coulomb_amplitude(&osc).unwrap();
        assert!((x - dh).abs() < 1e-12 * dh.max(1.0), "f = {f}: {x} vs {dh}");
    }
}

#[test]
fn closed_form_is_the_shooting_orbit() {
    let sh = ShootingOptions {
        tol: 1e-12,
        newton_tol: 1e-11,
        ..Default::default()
    };
    for &f in &[0.9, 1.0, 1.5, 2.5] {
        let osc = oscillator(f);
        let dh = non_stop_orbit(&osc).unwrap();
        assert!(dh.is_valid(), "f = {f}");
        let x0 = dh.state(0.0);
        let o = shoot(&osc, &OrbitSpec::symmetric(0), [x0[0] + 0.01, x0[1]], &sh).unwrap();
        assert!(
            (o.x[0] - x0[0]).abs() < 1e-9,
            "f = {f}: {:?} vs {x0:?}",
            o.x
        );
        assert!(
            (o.x[1] - x0[1]).abs() < 1e-8,
            "f = {f}: {:?} vs {x0:?}",
            o.x
        );
        assert_eq!((o.events.crossings, o.events.sticks), (1, 0));
    }
}

#[test]
fn continuation_in_f_follows_den_hartog_and_locates_the_onset_of_stops() {
    let f_start = 2.0;
    let osc = oscillator(f_start);
    let x0 = non_stop_orbit(&osc).unwrap().state(0.0);
    let opts = ContinuationOptions {
        ds: -0.05,
        ds_max: 0.1,
        param_min: 0.3,
        param_max: 2.0,
        ..Default::default()
    };
    let b = Continuation::new(osc, CoulombParam::F, OrbitSpec::symmetric(0), x0, opts)
        .unwrap()
        .run(None)
        .unwrap();
    let ns: Vec<_> = b.specials_of(SpecialKind::Nonsmooth).collect();
    assert!(!ns.is_empty(), "{:?}", b.specials);
    let onset = ns[0];
    let f_b = stop_boundary_frequency(&osc, 0.45, 2.0, 1e-13).unwrap();
    eprintln!(
        "onset of stops: continuation {} ± {:e}, closed form {f_b}, difference {:e}",
        onset.param,
        onset.precision,
        onset.param - f_b
    );
    assert!((onset.param - f_b).abs() < onset.precision + 1e-9);
    let jump = onset.jump.as_ref().unwrap();
    assert_eq!(jump.events_before.signature(), (1, 0));
    assert!(jump.events_after.sticks > 0);
    // every point on the non-stop side is Den Hartog's steady state
    let mut n = 0;
    let mut worst: f64 = 0.0;
    for p in b.points.iter().filter(|p| p.param > onset.param) {
        let dh = non_stop_orbit(&oscillator(p.param)).unwrap();
        assert!(dh.is_valid());
        let x = dh.state(0.0);
        worst = worst
            .max((p.x[0] - x[0]).abs())
            .max((p.x[1] - x[1]).abs() / TAU);
        n += 1;
    }
    eprintln!("{n} non-stop points, worst state difference {worst:e}");
    assert!(n >= 10);
    assert!(worst < 1e-8, "{worst}");
}

#[test]
fn generic_sweep_classifies_den_hartog_orbits() {
    // the sweep and the classification of the gear, run on the Coulomb oscillator through its lens
    use gearbif::analysis::{ClassifyOptions, Dynamics};
    use gearbif::integrator::EventDriven;
    use gearbif::progress::Silent;
    use gearbif::sweep::{sweep_grid, Protocol};
    let opts = ClassifyOptions {
        settle_turns: 40,
        analysis_turns: 20,
        ..ClassifyOptions::default()
    };
    let mus = [0.2, 0.3];
    let fs = [0.8, 1.5];
    let grid = sweep_grid(
        &EventDriven,
        &oscillator(1.0),
        (CoulombParam::Mu, &mus[..]),
        (CoulombParam::F, &fs[..]),
        [0.05, 0.0],
        Protocol::SemiStatic,
        &opts,
        &Silent,
    )
    .unwrap();
    for row in &grid {
        for (sys, r) in row {
            let rig = r.rigorous.as_ref().unwrap();
            let Dynamics::Periodic {
                half_periods,
                symmetric,
                orbit,
                ..
            } = rig.dynamics
            else {
                panic!("{:?}", rig.dynamics);
            };
            assert_eq!((half_periods, symmetric), (1, true));
            let dh = non_stop_orbit(sys).unwrap();
            assert!(dh.is_valid());
            // the classification's Newton-confirmed orbit point is Den Hartog's state at t = 0
            let x = dh.state(0.0);
            assert!((orbit[0] - x[0]).abs() < 1e-8, "{orbit:?} vs {x:?}");
            assert!((orbit[1] - x[1]).abs() < 1e-7, "{orbit:?} vs {x:?}");
        }
    }
}
