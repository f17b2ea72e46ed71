//! The regularised-friction cross-check (feature `diffsol-check`) against the exact event-driven
//! integrator: convergence ~ ε on a piece with a crossing of Σ (state and saltation-corrected
//! Jacobian), and the documented disagreement in stick phases (slow creep ω ≈ ε artanh(a/r)).
#![cfg(feature = "diffsol-check")]

use gearbif::integrator::{
    EventDriven, EventKind, FlowMethod, FlowOptions, ImplicitMethod, Regularised, Sensitivity,
};
use gearbif::model::{DrivenOscillator, Gear, GearParam, Parametrised};

#[test]
fn converges_linearly_in_epsilon_across_a_crossing() {
    let gear = Gear::paper(25.0, 2.7).unwrap();
    let x0 = [0.5, 2.0];
    let t1 = 1.0 / gear.f;
    let o = FlowOptions::with_tol(1e-10)
        .sensitivity(Sensitivity::State)
        .record_events(true);
    let exact = EventDriven.flow(&gear, 0.0, x0, t1, &o).unwrap();
    let crossings = exact
        .events
        .iter()
        .filter(|e| matches!(e.kind, EventKind::Crossing { .. }))
        .count();
    assert!(crossings >= 1, "the test orbit must cross Σ");
    let mut errs = Vec::new();
    let mut jerrs = Vec::new();
    for eps in [1e-2, 1e-3, 1e-4] {
        let f = Regularised::new(eps).flow(&gear, 0.0, x0, t1, &o).unwrap();
        errs.push((f.x[0] - exact.x[0]).abs() + (f.x[1] - exact.x[1]).abs());
        jerrs.push((f.jac_x.unwrap() - exact.jac_x.unwrap()).norm());
    }
    // first order in ε: a factor ≈ 10 per decade (measured 9.9 and 10.1)
    for w in errs.windows(2).chain(jerrs.windows(2)) {
        let ratio = w[0] / w[1];
        assert!((5.0..20.0).contains(&ratio), "{errs:?} {jerrs:?}");
    }
    assert!(errs[2] < 1e-4 && jerrs[2] < 1e-3, "{errs:?} {jerrs:?}");
}

#[test]
fn tr_bdf2_agrees_with_esdirk34() {
    let gear = Gear::paper(25.0, 2.7).unwrap();
    let (x0, t1) = ([0.5, 2.0], 1.0 / gear.f);
    let o = FlowOptions::with_tol(1e-9);
    let a = Regularised::new(1e-3).flow(&gear, 0.0, x0, t1, &o).unwrap();
    let b = Regularised::new(1e-3)
        .with_method(ImplicitMethod::TrBdf2)
        .flow(&gear, 0.0, x0, t1, &o)
        .unwrap();
    assert!((a.x[0] - b.x[0]).abs() < 1e-6 && (a.x[1] - b.x[1]).abs() < 1e-5);
}

#[test]
fn parameter_columns_match_finite_differences() {
    let gear = Gear::paper(25.0, 2.7).unwrap();
    let (x0, t1) = ([0.5, 2.0], 1.0 / gear.f);
    let m = Regularised::new(1e-2);
    let o = FlowOptions::with_tol(1e-11).sensitivity(Sensitivity::StateAndParams);
    let f = m.flow(&gear, 0.0, x0, t1, &o).unwrap();
    let jp = f.jac_p.unwrap();
    let plain = FlowOptions::with_tol(1e-11);
    // ζ, η, Δ, g at fixed end time (f changes the period; its column is a fixed-t derivative too)
    for (k, &q) in GearParam::COLUMNS.iter().enumerate() {
        assert_eq!(gear.column(q).unwrap().index, k);
        let p = gear.param(q);
        let h = 1e-5 * p.abs().max(1e-2);
        let xp = m
            .flow(&gear.with_param(q, p + h).unwrap(), 0.0, x0, t1, &plain)
            .unwrap()
            .x;
        let xm = m
            .flow(&gear.with_param(q, p - h).unwrap(), 0.0, x0, t1, &plain)
            .unwrap()
            .x;
        for i in 0..2 {
            let fd = (xp[i] - xm[i]) / (2.0 * h);
            assert!(
                (jp[(i, k)] - fd).abs() < 1e-4 * (1.0 + fd.abs()),
                "param {k} row {i}: {} vs {fd}",
                jp[(i, k)]
            );
        }
    }
}

#[test]
fn stick_phase_becomes_creep_at_eps_artanh() {
    // Θ = 31°, f = 0.3 Hz: stick-slip (the output rests for a good part of each period)
    let gear = Gear::paper(31.0, 0.3).unwrap();
    let x0 = [1.0, 0.0];
    let t1 = 2.0 / gear.f;
    let o = FlowOptions::with_tol(1e-10).record_events(true);
    let exact = EventDriven.flow(&gear, 0.0, x0, t1, &o).unwrap();
    // the longest stick phase
    let mut best = (0.0, 0.0, 0.0);
    for w in exact.events.windows(2) {
        if matches!(w[0].kind, EventKind::StickStart)
            && matches!(w[1].kind, EventKind::Release { .. })
            && w[1].t - w[0].t > best.1 - best.0
        {
            best = (w[0].t, w[1].t, w[0].beta);
        }
    }
    assert!(
        best.1 - best.0 > 0.02 / gear.f,
        "need a long stick phase, got {:?}",
        best
    );
    let tm = 0.5 * (best.0 + best.1);
    let eps = 1e-3;
    let reg = Regularised::new(eps)
        .flow(&gear, 0.0, x0, tm, &FlowOptions::with_tol(1e-10))
        .unwrap();
    // quasi-static creep: a(t, β, ω) = r tanh(ω/ε) ⇒ ω ≈ ε artanh(a(t, β, 0)/r)
    let fr = gear.forces(tm, reg.x[0], 0.0);
    let creep = eps * (fr.a / fr.r).atanh();
    assert!(
        (reg.x[1] - creep).abs() < 0.05 * creep.abs() + 1e-9,
        "ω = {} vs creep {creep}",
        reg.x[1]
    );
    // and β has crept away from the stuck value by roughly ω times the time since stick start
    assert!((reg.x[0] - best.2).abs() < 10.0 * eps);
    assert!((reg.x[0] - best.2).abs() > 1e-6);
}

#[test]
fn bad_epsilon_is_an_error() {
    let gear = Gear::paper(25.0, 2.7).unwrap();
    let o = FlowOptions::default();
    for eps in [0.0, -1.0, f64::NAN] {
        assert!(Regularised::new(eps)
            .flow(&gear, 0.0, [0.0, 0.0], 0.1, &o)
            .is_err());
    }
    assert!(Regularised::new(1e-3)
        .flow(&gear, 0.0, [f64::NAN, 0.0], 0.1, &o)
        .is_err());
}

#[test]
fn converges_through_many_stick_phases() {
    // 3 periods of stick-slip (7 stick phases): a long run with many Newton failures in the
    // creep phases (diffsol counts them over the whole solve), still first order in ε
    let gear = Gear::paper(31.0, 0.3).unwrap();
    let (x0, t1) = ([1.0, 0.0], 3.0 / gear.f);
    let o = FlowOptions::with_tol(1e-10);
    let exact = EventDriven.flow(&gear, 0.0, x0, t1, &o).unwrap();
    let errs: Vec<f64> = [1e-3, 1e-4]
        .iter()
        .map(|&eps| {
            let f = Regularised::new(eps).flow(&gear, 0.0, x0, t1, &o).unwrap();
            (f.x[0] - exact.x[0]).abs()
        })
        .collect();
    // measured: 3.6e-4 and 4.0e-5
    assert!(errs[0] < 1e-3 && errs[1] < 1e-4, "{errs:?}");
    assert!((5.0..20.0).contains(&(errs[0] / errs[1])), "{errs:?}");
}

#[test]
fn multipliers_converge_through_stick_phases() {
    use gearbif::maps::{multipliers, poincare_map, Section};
    let gear = Gear::paper(31.0, 0.3).unwrap();
    let x0 = [1.0, 1.0];
    let o = |tol: f64| FlowOptions::with_tol(tol).sensitivity(Sensitivity::State);
    let mu_of = |m: &dyn FlowMethod<Gear>, tol: f64| {
        let img = poincare_map(m, &gear, Section::Stroboscopic, x0, 1, &o(tol)).unwrap();
        multipliers(&img.jac_x.unwrap()).map(|c| c.norm())
    };
    let exact = mu_of(&EventDriven, 1e-11);
    // the stick saltation diag(1, 0) makes one multiplier vanish
    assert!(exact[1] < 1e-12, "{exact:?}");
    let errs: Vec<f64> = [1e-3, 1e-4]
        .iter()
        .map(|&eps| {
            let mu = mu_of(&Regularised::new(eps), 1e-10);
            // the creep contracts at rate ~ r/ε: numerically zero as well
            assert!(mu[1] < 1e-12, "{mu:?}");
            (mu[0] - exact[0]).abs()
        })
        .collect();
    // measured: 3.8e-4 and 5.8e-5
    assert!(
        errs[0] < 1e-3 && (3.0..20.0).contains(&(errs[0] / errs[1])),
        "{errs:?}"
    );
}
