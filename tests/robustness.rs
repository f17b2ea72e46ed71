//! Robustness of the event-driven integrator: many gears and states, degenerate parameters, and
//! states placed exactly on the awkward places (Σ, the stick boundary).

use gearbif::integrator::{EventDriven, EventKind, FlowMethod, FlowOptions, Mode, Sensitivity};
use gearbif::model::{DrivenOscillator, Gear};
use std::f64::consts::{PI, TAU};

/// A small deterministic generator (SplitMix64) so the cases are reproducible.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.next()
    }
}

#[test]
fn random_gears_integrate_and_converge_in_tolerance() {
    let mut rng = Rng(7);
    let mut worst: f64 = 0.0;
    for case in 0..150 {
        let theta = rng.range(-90.0, 90.0);
        let f = 10f64.powf(rng.range(-1.0, 1.7));
        let mut gear = Gear::paper(theta, f).unwrap();
        gear.eta = rng.range(0.0, 80.0);
        gear.zeta = rng.range(0.0, 3.0);
        let x0 = [rng.range(-PI, PI), rng.range(-30.0, 30.0)];
        // two periods: short enough that chaos does not amplify the tolerance difference much
        let t1 = 2.0 / f;
        let a = EventDriven
            .flow(&gear, 0.0, x0, t1, &FlowOptions::with_tol(1e-9))
            .unwrap_or_else(|e| panic!("case {case} {gear:?} x0 {x0:?}: {e}"));
        let b = EventDriven
            .flow(&gear, 0.0, x0, t1, &FlowOptions::with_tol(1e-12))
            .unwrap_or_else(|e| panic!("case {case} {gear:?} x0 {x0:?}: {e}"));
        assert!(a.x[0].is_finite() && a.x[1].is_finite());
        let d = (a.x[0] - b.x[0]).abs() + (a.x[1] - b.x[1]).abs() / (1.0 + b.x[1].abs());
        worst = worst.max(d);
        assert!(
            d < 1e-4,
            "case {case}: tol 1e-9 vs 1e-12 differ by {d} ({gear:?}, x0 {x0:?})"
        );
    }
    eprintln!("worst tolerance discrepancy over 150 random cases: {worst:e}");
}

#[test]
fn jacobian_columns_are_finite_for_random_gears() {
    let mut rng = Rng(11);
    for _ in 0..60 {
        let gear = Gear::paper(rng.range(0.0, 60.0), 10f64.powf(rng.range(-0.5, 1.0))).unwrap();
        let x0 = [rng.range(-PI, PI), rng.range(-10.0, 10.0)];
        let o = FlowOptions::with_tol(1e-9).sensitivity(Sensitivity::StateAndParams);
        let fl = EventDriven.flow(&gear, 0.0, x0, 1.0 / gear.f, &o).unwrap();
        assert!(fl.jac_x.unwrap().iter().all(|v| v.is_finite()));
        assert!(fl.jac_p.unwrap().iter().all(|v| v.is_finite()));
    }
}

#[test]
fn degenerate_parameters() {
    let o = FlowOptions::with_tol(1e-10).record_events(true);
    // no friction at all: never sticks, ω crosses freely
    let g = Gear::new(298.45, 0.3, 1.1, 0.0, 1.5).unwrap();
    let fl = EventDriven.flow(&g, 0.0, [1.0, 0.0], 4.0, &o).unwrap();
    assert!(fl
        .events
        .iter()
        .all(|e| !matches!(e.kind, EventKind::StickStart)));
    // friction larger than any torque: stuck forever, nothing to integrate
    let g = Gear::new(298.45, 0.3, 1.1, 400.0, 1.5).unwrap();
    let fl = EventDriven.flow(&g, 0.0, [1.0, 0.0], 40.0, &o).unwrap();
    assert_eq!(fl.mode, Mode::Stick);
    assert_eq!(fl.x, [1.0, 0.0]);
    assert_eq!(fl.stats.steps, 0);
    // no coupling: pure dry + viscous decay, stops for good after a finite time
    let g = Gear::new(0.0, 0.3, 1.1, 23.1, 1.5).unwrap();
    let fl = EventDriven.flow(&g, 0.0, [0.0, 5.0], 10.0, &o).unwrap();
    assert_eq!(fl.mode, Mode::Stick);
    // exact stop time: ω̇ = −ζω − η ⇒ t* = ln(1 + ζω₀/η)/ζ, distance (ω₀ − η t*)/ζ
    let ts = (1.0 + 1.1 * 5.0 / 23.1_f64).ln() / 1.1;
    let dist = (5.0 - 23.1 * ts) / 1.1;
    assert!((fl.events[0].t - ts).abs() < 1e-9);
    assert!((fl.x[0] - dist).abs() < 1e-9);
    // Δ = 0 (largest cogging) and very high and very low frequencies
    for (d, f) in [(0.0, 2.0), (0.5, 100.0), (-1.0, 0.05), (1.0, 0.01)] {
        let g = Gear::new(298.45, d, 1.1, 23.1, f).unwrap();
        let fl = EventDriven
            .flow(&g, 0.0, [2.0, 1.0], 3.0 / f, &FlowOptions::with_tol(1e-9))
            .unwrap();
        assert!(fl.x[0].is_finite());
    }
}

#[test]
fn starting_exactly_on_the_stick_boundary() {
    let g = Gear::paper(25.0, 1.0).unwrap();
    // find β* where |a(0, β*, 0)| = η exactly (bisection), then start there on Σ
    let h = |b: f64| g.forces(0.0, b, 0.0).a.abs() - g.eta;
    let (mut lo, mut hi) = (0.0, PI / 2.0);
    assert!(h(lo) < 0.0 && h(hi) > 0.0);
    for _ in 0..200 {
        let m = 0.5 * (lo + hi);
        if h(m) < 0.0 {
            lo = m
        } else {
            hi = m
        }
    }
    for b in [lo, hi, 0.5 * (lo + hi)] {
        let fl = EventDriven
            .flow(
                &g,
                0.0,
                [b, 0.0],
                3.0,
                &FlowOptions::with_tol(1e-10)
                    .record_events(true)
                    .sensitivity(Sensitivity::StateAndParams),
            )
            .unwrap();
        assert!(fl.x[0].is_finite());
    }
}

#[test]
fn long_runs_keep_windings_exact_on_the_lift() {
    // slip-through at Θ = 0 above f_c: β advances slowly; the lock below f_c: exactly one winding per period
    let g = Gear::paper(0.0, 20.0).unwrap();
    let lock = g.lock_branch().unwrap().stable;
    let fl = EventDriven
        .flow(
            &g,
            0.0,
            lock.state,
            200.0 / g.f,
            &FlowOptions::with_tol(1e-11),
        )
        .unwrap();
    assert!((fl.x[0] - lock.state[0] - 200.0 * TAU).abs() < 1e-6);
}
