//! The event-driven Taylor method against independent answers: agreement with the event-driven
//! DOP853 at tight tolerance (states, event sequence and times, state Jacobians, samples),
//! convergence in tolerance against one reference, the state Jacobian against central finite
//! differences through crossings and stick phases, the analytic lock branch at Θ = 0, Den
//! Hartog's closed-form steady state of the Coulomb oscillator, and the default method (Taylor's
//! for the gear) locating the orbits the DOP853 locates.

use gearbif::integrator::{
    EventDriven853, EventKind, Fastest, Flow, FlowMethod, FlowOptions, Sensitivity, Taylor,
    DEFAULT_METHOD,
};
use gearbif::model::den_hartog::non_stop_orbit;
use gearbif::model::{CoulombOscillator, DrivenOscillator, ForcedPendulum, Gear};
use std::f64::consts::{PI, TAU};

fn opts(tol: f64) -> FlowOptions {
    FlowOptions::with_tol(tol).sensitivity(Sensitivity::State)
}

/// The largest difference of the final states.
fn state_gap(a: &Flow, b: &Flow) -> f64 {
    (a.x[0] - b.x[0]).abs().max((a.x[1] - b.x[1]).abs())
}

/// The gear cases: (Θ, f, x₀, periods): a crossing per period, stick/slip at 4.5 Hz, a stick
/// phase at low frequency, the reversed sense, the co-rotating lock from rest.
const CASES: [(f64, f64, [f64; 2], f64); 6] = [
    (25.0, 2.7, [0.5, 2.0], 3.0),
    (25.0, 4.5, [0.0, 0.0], 6.0),
    (31.0, 0.3, [1.0, 0.0], 2.0),
    (25.0, 2.1, [2.5, -3.0], 4.0),
    (54.0, 2.7, [0.0, 0.0], 5.0),
    (25.0, 2.7, [PI, 0.0], 20.0),
];

/// At tol 1e-12 the Taylor method and the DOP853 give the same states, the same sequence of
/// events at the same times, and the same state Jacobians.
#[test]
fn agrees_with_dop853_at_tight_tolerance() {
    let mut n_events = 0;
    for (th, f, x0, periods) in CASES {
        let gear = Gear::paper(th, f).unwrap();
        let o = opts(1e-12).record_events(true);
        let t1 = periods * gear.period();
        let a = Taylor.flow(&gear, 0.0, x0, t1, &o).unwrap();
        let b = EventDriven853.flow(&gear, 0.0, x0, t1, &o).unwrap();
        eprintln!(
            "Θ={th} f={f}: gap {:.2e}, {} events, {} Taylor steps, {} DOP853 steps",
            state_gap(&a, &b),
            a.events.len(),
            a.stats.steps,
            b.stats.steps
        );
        assert!(
            state_gap(&a, &b) < 1e-9,
            "Θ={th} f={f}: {:?} vs {:?}",
            a.x,
            b.x
        );
        assert_eq!(a.mode, b.mode);
        assert_eq!(a.events.len(), b.events.len(), "Θ={th} f={f}: events");
        for (ea, eb) in a.events.iter().zip(&b.events) {
            assert_eq!(
                std::mem::discriminant(&ea.kind),
                std::mem::discriminant(&eb.kind),
                "Θ={th} f={f}: {ea:?} vs {eb:?}"
            );
            assert!((ea.t - eb.t).abs() < 1e-10, "event times {} {}", ea.t, eb.t);
        }
        n_events += a.events.len();
        let (ja, jb) = (a.jac_x.unwrap(), b.jac_x.unwrap());
        let sc = ja.abs().max().max(1.0);
        assert!(
            (ja - jb).abs().max() < 1e-8 * sc,
            "Θ={th} f={f}: {ja} vs {jb}"
        );
    }
    assert!(n_events > 20, "the cases hold events: {n_events}");
}

/// Without the Jacobian the state is the same to rounding (the Jacobian only adds to the
/// step-size norm), and with parameter columns the flow is the DOP853's.
#[test]
fn sensitivities_none_and_params() {
    let gear = Gear::paper(25.0, 2.7).unwrap();
    let t1 = 3.0 * gear.period();
    let a = Taylor
        .flow(&gear, 0.0, [0.5, 2.0], t1, &FlowOptions::with_tol(1e-12))
        .unwrap();
    let b = EventDriven853
        .flow(&gear, 0.0, [0.5, 2.0], t1, &FlowOptions::with_tol(1e-12))
        .unwrap();
    assert!(a.jac_x.is_none());
    assert!(state_gap(&a, &b) < 1e-9);
    let o = FlowOptions::with_tol(1e-10).sensitivity(Sensitivity::StateAndParams);
    let p = Taylor.flow(&gear, 0.0, [0.5, 2.0], t1, &o).unwrap();
    let q = EventDriven853.flow(&gear, 0.0, [0.5, 2.0], t1, &o).unwrap();
    assert_eq!(p, q);
}

/// The error against one reference (DOP853 at tol 1e-14) falls with the tolerance, and stays
/// within 100 tol over 20 periods with stick/slip events.
#[test]
fn converges_in_tolerance() {
    let gear = Gear::paper(25.0, 4.5).unwrap();
    let t1 = 20.0 * gear.period();
    let x0 = [0.0, 0.0];
    let reference = EventDriven853
        .flow(&gear, 0.0, x0, t1, &FlowOptions::with_tol(1e-14))
        .unwrap();
    let mut last = f64::INFINITY;
    for tol in [1e-6, 1e-8, 1e-10, 1e-12] {
        let fl = Taylor
            .flow(&gear, 0.0, x0, t1, &FlowOptions::with_tol(tol))
            .unwrap();
        let err = state_gap(&fl, &reference);
        eprintln!("tol {tol:e}: error {err:.2e}, {} steps", fl.stats.steps);
        assert!(err < 100.0 * tol, "tol {tol:e}: error {err:e}");
        assert!(err < last, "tol {tol:e}: {err:e} not below {last:e}");
        last = err;
    }
}

/// The state Jacobian (saltations at crossings, stick entries and releases) equals central
/// finite differences of the flow computed with the same method.
#[test]
fn jacobian_matches_finite_differences() {
    let mut kinds = [0usize; 3];
    for (th, f, x0, periods) in [
        (25.0, 2.7, [2.0, 1.0], 1.0),
        (31.0, 1.33, [3.0, 0.7], 2.0),
        (31.0, 0.2, [1.0, 0.3], 1.0),
        (25.0, 4.5, [0.3, 0.5], 3.0),
    ] {
        let gear = Gear::paper(th, f).unwrap();
        let t1 = periods * gear.period();
        let fl = Taylor
            .flow(&gear, 0.0, x0, t1, &opts(1e-12).record_events(true))
            .unwrap();
        for e in &fl.events {
            match e.kind {
                EventKind::Crossing { .. } => kinds[0] += 1,
                EventKind::StickStart => kinds[1] += 1,
                EventKind::Release { .. } => kinds[2] += 1,
                EventKind::Graze { .. } => {}
            }
        }
        let fo = FlowOptions::with_tol(1e-13);
        let map = |x: [f64; 2]| Taylor.flow(&gear, 0.0, x, t1, &fo).unwrap().x;
        let j = fl.jac_x.unwrap();
        let sc = j.abs().max().max(1.0);
        for c in 0..2 {
            let h = 1e-6;
            let (mut xp, mut xm) = (x0, x0);
            xp[c] += h;
            xm[c] -= h;
            let (p, m) = (map(xp), map(xm));
            for r in 0..2 {
                let fd = (p[r] - m[r]) / (2.0 * h);
                assert!(
                    (j[(r, c)] - fd).abs() < 2e-5 * sc,
                    "Θ={th} f={f}: ∂x{r}/∂x0{c} = {} vs FD {fd}",
                    j[(r, c)]
                );
            }
        }
    }
    assert!(
        kinds.iter().all(|&k| k > 0),
        "crossings, sticks, releases: {kinds:?}"
    );
}

/// Samples and their Jacobians on the step polynomials equal the DOP853's on its continuous
/// extension.
#[test]
fn samples_agree_with_dop853() {
    let gear = Gear::paper(25.0, 4.5).unwrap();
    let t1 = 4.0 * gear.period();
    let times: Vec<f64> = (0..=40).map(|i| i as f64 / 40.0 * t1).collect();
    let o = opts(1e-12).samples(times.clone());
    let a = Taylor.flow(&gear, 0.0, [0.0, 0.0], t1, &o).unwrap();
    let b = EventDriven853.flow(&gear, 0.0, [0.0, 0.0], t1, &o).unwrap();
    assert_eq!(
        (a.samples.len(), b.samples.len()),
        (times.len(), times.len())
    );
    assert_eq!(a.sample_jacobians.len(), times.len());
    for (sa, sb) in a.samples.iter().zip(&b.samples) {
        assert_eq!(sa.t, sb.t);
        assert!((sa.beta - sb.beta).abs() < 1e-9 && (sa.omega - sb.omega).abs() < 1e-8);
    }
    for (ja, jb) in a.sample_jacobians.iter().zip(&b.sample_jacobians) {
        assert!(
            (ja - jb).abs().max() < 1e-7 * ja.abs().max().max(1.0),
            "{ja} vs {jb}"
        );
    }
}

/// Θ = 0: the locked orbit δ = β − α = const and its multipliers μ = exp(λT) are analytic
/// (numerics.md, "Validation oracles").
#[test]
fn lock_branch_at_theta_zero() {
    for f in [1.0, 5.0, 20.0] {
        let gear = Gear::paper(0.0, f).unwrap();
        let lock = gear.lock_branch().unwrap().stable;
        let fl = Taylor
            .flow(&gear, 0.0, lock.state, gear.period(), &opts(1e-12))
            .unwrap();
        assert!((fl.x[0] - (lock.state[0] + TAU)).abs() < 1e-10, "f={f}");
        assert!((fl.x[1] - lock.state[1]).abs() < 1e-9, "f={f}");
        let m = fl.jac_x.unwrap();
        let (tr, det) = (m.trace(), m.determinant());
        let (m1, m2) = (lock.multipliers[0], lock.multipliers[1]);
        assert!((tr - (m1 + m2).re).abs() < 1e-8, "f={f}: trace {tr}");
        assert!((det - (m1 * m2).re).abs() < 1e-8, "f={f}: det {det}");
    }
}

/// Den Hartog's closed-form steady state (no stops) of the Coulomb oscillator is reproduced over
/// two periods from its initial state, with the reversals as crossings.
#[test]
fn coulomb_oscillator_closed_form() {
    for f in [0.9, 1.5, 2.5] {
        let osc = CoulombOscillator::new(TAU, 0.05, 0.3, 1.0, f).unwrap();
        let dh = non_stop_orbit(&osc).unwrap();
        let x0 = dh.state(0.0);
        let t1 = 2.0 * osc.period();
        let fl = Taylor
            .flow(&osc, 0.0, x0, t1, &opts(1e-12).record_events(true))
            .unwrap();
        let want = dh.state(t1);
        assert!(
            (fl.x[0] - want[0]).abs() < 1e-9,
            "f={f}: {:?} vs {want:?}",
            fl.x
        );
        assert!(
            (fl.x[1] - want[1]).abs() < 1e-8,
            "f={f}: {:?} vs {want:?}",
            fl.x
        );
        assert_eq!(fl.events.len(), 4, "f={f}: two reversals per period");
        assert!(fl
            .events
            .iter()
            .all(|e| matches!(e.kind, EventKind::Crossing { .. })));
    }
}

/// The second-method check of the default: [`DEFAULT_METHOD`] integrates the gear by Taylor's
/// method (one expansion per step) and a system without a jet (the forced pendulum) by the
/// DOP853, and
/// the orbits it locates (a slipping symmetric orbit found from a simulation, a stick/slip orbit
/// with one stick phase per half period, the same orbit on P_T) are those the DOP853 locates:
/// states to 1e-8, the same events, multipliers to 1e-6.
#[test]
fn default_method_locates_the_dop853_orbits() {
    use gearbif::orbits::{orbit_from_simulation, shoot, shoot_with, OrbitSpec, ShootingOptions};
    assert_eq!(DEFAULT_METHOD, Fastest);
    let gear = Gear::paper(25.0, 2.7).unwrap();
    let o = FlowOptions::with_tol(1e-9);
    let fl = DEFAULT_METHOD
        .flow(&gear, 0.0, [0.5, 2.0], 1.0, &o)
        .unwrap();
    assert_eq!(fl.stats.steps, fl.stats.rhs_evals);
    let rk = EventDriven853
        .flow(&gear, 0.0, [0.5, 2.0], 1.0, &o)
        .unwrap();
    assert!(rk.stats.rhs_evals > 5 * rk.stats.steps);
    let pendulum = ForcedPendulum::new(6.0, 0.3, 0.5, 20.0, 1.2).unwrap();
    let (a, b) = (
        DEFAULT_METHOD
            .flow(&pendulum, 0.0, [0.5, 2.0], 2.0, &o)
            .unwrap(),
        EventDriven853
            .flow(&pendulum, 0.0, [0.5, 2.0], 2.0, &o)
            .unwrap(),
    );
    assert_eq!((a.x, a.stats), (b.x, b.stats));
    let so = ShootingOptions::default();
    let sym = orbit_from_simulation(&gear, [3.0, 15.0], 100, 2, true, &so).unwrap();
    let slow = Gear::paper(25.0, 1.61).unwrap();
    let cases = [
        (&gear, sym.spec, sym.x),
        (&gear, OrbitSpec::stroboscopic(1, 1), sym.x),
        (&slow, OrbitSpec::symmetric(-1), [0.309, -0.5]),
    ];
    for (g, spec, guess) in cases {
        let a = shoot(g, &spec, guess, &so).unwrap();
        let b = shoot_with(&EventDriven853, g, &spec, guess, &so).unwrap();
        let gap = (a.x[0] - b.x[0]).abs().max((a.x[1] - b.x[1]).abs());
        assert!(gap < 1e-8, "{spec:?}: {:?} vs {:?}", a.x, b.x);
        assert_eq!(a.events, b.events, "{spec:?}");
        for (ma, mb) in a.floquet.multipliers.iter().zip(&b.floquet.multipliers) {
            let d = (ma[0] - mb[0]).hypot(ma[1] - mb[1]);
            assert!(d < 1e-6, "{spec:?}: {ma:?} vs {mb:?}");
        }
    }
}
