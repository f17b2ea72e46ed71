//! Tests of the model, the event-driven integrator and the maps against independent answers:
//! the analytic lock branch, exact piecewise solutions, finite differences, the symmetry, and
//! convergence in tolerance.

use approx::assert_relative_eq;
use gearbif::integrator::{
    EventDriven, EventDriven853, EventKind, FixedStep, FlowMethod, FlowOptions, Mode, Sensitivity,
};
use gearbif::maps::{multipliers, poincare_map, Section};
use gearbif::model::{
    Convention, CoulombOscillator, DrivenOscillator, ForcedPendulum, Gear, GearParam, Parameter,
    Parametrised,
};
use std::f64::consts::{PI, TAU};

fn opts(tol: f64) -> FlowOptions {
    FlowOptions::with_tol(tol).sensitivity(Sensitivity::StateAndParams)
}

/// Central finite differences of a map image with respect to the state and the parameters.
fn fd_jacobian_gear(
    gear: &Gear,
    section: Section,
    x: [f64; 2],
    iters: usize,
    tol: f64,
) -> (nalgebra::Matrix2<f64>, nalgebra::Matrix2xX<f64>) {
    let o = FlowOptions::with_tol(tol);
    let img = |g: &Gear, x: [f64; 2]| {
        poincare_map(&EventDriven, g, section, x, iters, &o)
            .unwrap()
            .x
    };
    let mut jx = nalgebra::Matrix2::zeros();
    for j in 0..2 {
        let h = 1e-6;
        let mut xp = x;
        let mut xm = x;
        xp[j] += h;
        xm[j] -= h;
        let (a, b) = (img(gear, xp), img(gear, xm));
        for i in 0..2 {
            jx[(i, j)] = (a[i] - b[i]) / (2.0 * h);
        }
    }
    let mut jp = nalgebra::Matrix2xX::zeros(5);
    for (k, &q) in GearParam::COLUMNS.iter().enumerate() {
        let p = gear.param(q);
        let h = 1e-6 * p.abs().max(1e-2);
        let gp = gear.with_param(q, p + h).unwrap();
        let gm = gear.with_param(q, p - h).unwrap();
        let (a, b) = (img(&gp, x), img(&gm, x));
        for i in 0..2 {
            jp[(i, k)] = (a[i] - b[i]) / (2.0 * h);
        }
    }
    (jx, jp)
}

#[test]
fn lock_branch_is_a_fixed_point_with_analytic_multipliers() {
    let gear0 = Gear::paper(0.0, 1.0).unwrap();
    let fc = gear0.lock_loss_frequency().unwrap();
    for &f in &[0.1, 0.5, 1.0, 3.0, 10.0, 25.0, 39.0, fc * 0.999] {
        let gear = gear0.with_f(f).unwrap();
        let lock = gear.lock_branch().unwrap();
        for pt in [lock.stable, lock.unstable] {
            let mu_max = pt.multipliers[0].norm().max(pt.multipliers[1].norm());
            if mu_max > 1e4 {
                // a saddle with multiplier > 1e4 cannot be followed over a period in floating point
                continue;
            }
            let img = poincare_map(
                &EventDriven,
                &gear,
                Section::Stroboscopic,
                pt.state,
                1,
                &opts(1e-12),
            )
            .unwrap();
            assert!(
                (img.x[0] - pt.state[0] - TAU).abs() < 1e-8,
                "f = {f}: β drift {}",
                img.x[0] - pt.state[0] - TAU
            );
            assert!((img.x[1] - pt.state[1]).abs() < 1e-8 * pt.state[1].abs().max(1.0));
            assert_eq!(img.stats.events, 0, "locked orbit never touches ω = 0");
            let mu = multipliers(&img.jac_x.unwrap());
            // compare as unordered sets
            let an = pt.multipliers;
            let d1 = (mu[0] - an[0]).norm() + (mu[1] - an[1]).norm();
            let d2 = (mu[0] - an[1]).norm() + (mu[1] - an[0]).norm();
            let scale = an[0].norm().max(an[1].norm()).max(1e-3);
            assert!(
                d1.min(d2) < 1e-7 * scale,
                "f = {f}: multipliers {mu:?} vs analytic {an:?}"
            );
        }
    }
}

#[test]
fn reversed_lock_at_delta_minus_one() {
    let g = Gear::new(298.45, -1.0, 1.1, 23.1, 4.0).unwrap();
    let lock = g.lock_branch().unwrap();
    assert!(lock.stable.stable && !lock.unstable.stable);
    let img = poincare_map(
        &EventDriven,
        &g,
        Section::Stroboscopic,
        lock.stable.state,
        1,
        &opts(1e-12),
    )
    .unwrap();
    assert!((img.x[0] - lock.stable.state[0] + TAU).abs() < 1e-8);
    let mu = multipliers(&img.jac_x.unwrap());
    let an = lock.stable.multipliers;
    assert!((mu[0].norm() - an[0].norm()).abs() < 1e-7);
}

#[test]
fn jacobians_match_finite_differences_with_crossings_and_sticks() {
    // (Θ, f, x0): a cogging orbit with crossings, one with long stick phases, a slip-through state
    let cases = [
        (25.0, 2.7, [2.0, 1.0], Section::Stroboscopic, 1),
        (31.0, 1.33, [3.0, 0.7], Section::Stroboscopic, 2),
        (31.0, 0.2, [1.0, 0.3], Section::Stroboscopic, 1),
        (25.0, 2.1, [2.5, -3.0], Section::HalfPeriod, 3),
        (0.0, 6.0, [0.5, 2.0], Section::Stroboscopic, 1),
    ];
    let (mut total_cross, mut total_stick) = (0, 0);
    for (th, f, x0, sec, it) in cases {
        let gear = Gear::paper(th, f).unwrap();
        let oo = opts(1e-12).record_events(true);
        let img = poincare_map(&EventDriven, &gear, sec, x0, it, &oo).unwrap();
        let n_cross = img
            .events
            .iter()
            .filter(|e| matches!(e.kind, EventKind::Crossing { .. }))
            .count();
        let n_stick = img
            .events
            .iter()
            .filter(|e| matches!(e.kind, EventKind::StickStart))
            .count();
        total_cross += n_cross;
        total_stick += n_stick;
        let (jx, jp) = fd_jacobian_gear(&gear, sec, x0, it, 1e-13);
        let ax = img.jac_x.unwrap();
        let ap = img.jac_p.unwrap();
        let sx = jx.abs().max().max(1.0);
        assert!(
            (ax - jx).abs().max() < 2e-5 * sx,
            "Θ={th} f={f}: state Jacobian\n{ax}\nvs FD\n{jx} (crossings {n_cross}, sticks {n_stick})"
        );
        for k in 0..5 {
            let sp = jp.column(k).abs().max().max(1e-3);
            let d = (ap.column(k) - jp.column(k)).abs().max();
            assert!(
                d < 2e-5 * sp.max(1.0),
                "Θ={th} f={f}: param column {} analytic {} vs FD {}",
                GearParam::COLUMNS[k].name(),
                ap.column(k),
                jp.column(k)
            );
        }
        if n_stick > 0 {
            // an orbit piece through a stick phase has a rank-one Jacobian (det = 0 up to rounding)
            assert!(ax.determinant().abs() <= 1e-13 * ax.norm_squared().max(1.0));
        }
    }
    // the cases must really exercise both kinds of event
    assert!(
        total_cross > 0 && total_stick > 0,
        "crossings {total_cross}, sticks {total_stick}"
    );
}

#[test]
fn stick_phases_begin_and_end_at_the_friction_bound() {
    let gear = Gear::paper(31.0, 0.3).unwrap();
    let o = FlowOptions::with_tol(1e-11).record_events(true);
    let fl = EventDriven
        .flow(&gear, 0.0, [1.0, 0.0], 5.0 / gear.f, &o)
        .unwrap();
    let mut n_rel = 0;
    let mut n_stick = 0;
    for e in &fl.events {
        let a = gear.forces(e.t, e.beta, 0.0).a;
        match e.kind {
            EventKind::StickStart => {
                n_stick += 1;
                assert!(a.abs() <= gear.eta * (1.0 + 1e-12));
            }
            EventKind::Release { to } => {
                n_rel += 1;
                assert_relative_eq!(a.abs(), gear.eta, max_relative = 1e-9);
                assert_eq!(a.signum() as i8, to);
            }
            EventKind::Crossing { .. } => assert!(a.abs() > gear.eta),
            EventKind::Graze { .. } => {}
        }
    }
    assert!(
        n_rel > 3 && n_stick > 3,
        "releases {n_rel}, sticks {n_stick}"
    );
}

#[test]
fn convergence_in_tolerance() {
    let gear = Gear::paper(25.0, 2.7).unwrap();
    let x0 = [2.0, 1.0];
    let t1 = 5.0 / gear.f;
    let reference = EventDriven
        .flow(&gear, 0.0, x0, t1, &FlowOptions::with_tol(1e-14))
        .unwrap();
    let mut last = f64::INFINITY;
    for tol in [1e-5, 1e-7, 1e-9, 1e-11] {
        let fl = EventDriven
            .flow(&gear, 0.0, x0, t1, &FlowOptions::with_tol(tol))
            .unwrap();
        let err = (fl.x[0] - reference.x[0]).abs() + (fl.x[1] - reference.x[1]).abs();
        assert!(
            err < last,
            "tol {tol}: error {err} did not decrease (was {last})"
        );
        assert!(err < 1e3 * tol, "tol {tol}: error {err}");
        last = err;
    }
}

#[test]
fn stroboscopic_map_is_half_period_map_squared() {
    for (th, f) in [(25.0, 2.7), (25.0, 2.1), (31.0, 1.07), (10.0, 0.4)] {
        let gear = Gear::paper(th, f).unwrap();
        let o = opts(1e-12);
        for x0 in [[0.3, 0.0], [2.0, 4.0], [-1.0, -2.0]] {
            let p = poincare_map(&EventDriven, &gear, Section::Stroboscopic, x0, 1, &o).unwrap();
            let g1 = poincare_map(&EventDriven, &gear, Section::HalfPeriod, x0, 1, &o).unwrap();
            let g2 = poincare_map(&EventDriven, &gear, Section::HalfPeriod, g1.x, 1, &o).unwrap();
            assert!((p.x[0] - (g2.x[0] + TAU)).abs() < 1e-8, "Θ={th} f={f}");
            assert!((p.x[1] - g2.x[1]).abs() < 1e-8);
            // Jacobians: DP_T = DG(G x) DG(x)
            let chain = g2.jac_x.unwrap() * g1.jac_x.unwrap();
            assert!((p.jac_x.unwrap() - chain).abs().max() < 1e-6 * chain.abs().max().max(1.0));
        }
    }
}

#[test]
fn paper_convention_is_the_physical_one_shifted_by_pi() {
    let phys = Gear::paper(25.0, 1.3).unwrap();
    let pap = phys.with_convention(Convention::Paper);
    let o = FlowOptions::with_tol(1e-12);
    let a = EventDriven.flow(&phys, 0.0, [1.0, 0.5], 3.0, &o).unwrap();
    let b = EventDriven
        .flow(&pap, 0.0, [1.0 + PI, 0.5], 3.0, &o)
        .unwrap();
    assert!((b.x[0] - a.x[0] - PI).abs() < 1e-8);
    assert!((b.x[1] - a.x[1]).abs() < 1e-8);
}

#[test]
fn coulomb_free_vibration_is_exact() {
    // ẍ + ω₀² x = −μ sgn(ẋ): half-cycles of length π/ω₀ about ±μ/ω₀², amplitude loss 2μ/ω₀²
    let w0 = 3.0;
    let mu = 0.9;
    let osc = CoulombOscillator::new(w0, 0.0, mu, 0.0, 0.1).unwrap();
    let x0 = 1.0;
    let o = FlowOptions::with_tol(1e-12).record_events(true);
    let fl = EventDriven.flow(&osc, 0.0, [x0, 0.0], 20.0, &o).unwrap();
    let xs = mu / (w0 * w0);
    let mut x = x0;
    let mut t = 0.0;
    let mut expected = Vec::new();
    while x.abs() > xs {
        t += PI / w0;
        x = -(x - 2.0 * xs * x.signum());
        expected.push((t, x));
    }
    let ev: Vec<_> = fl.events.iter().collect();
    // crossings at all but the last turning point, where it sticks for good
    assert_eq!(ev.len(), expected.len(), "{ev:?}");
    for (e, (te, xe)) in ev.iter().zip(&expected) {
        assert_relative_eq!(e.t, *te, epsilon = 1e-9);
        assert_relative_eq!(e.beta, *xe, epsilon = 1e-9);
    }
    assert!(matches!(ev.last().unwrap().kind, EventKind::StickStart));
    assert_eq!(fl.mode, Mode::Stick);
    assert_relative_eq!(fl.x[0], expected.last().unwrap().1, epsilon = 1e-9);
}

#[test]
fn linear_oscillator_monodromy_is_exact() {
    // μ = 0: the monodromy is exp(AT) whatever the state
    let (w0, xi, f) = (2.0 * TAU, 0.05, 1.3);
    let osc = CoulombOscillator::new(w0, xi, 0.0, 5.0, f).unwrap();
    let img = poincare_map(
        &EventDriven,
        &osc,
        Section::Stroboscopic,
        [0.1, 0.2],
        1,
        &opts(1e-12),
    )
    .unwrap();
    let m = img.jac_x.unwrap();
    let t = 1.0 / f;
    let wd = w0 * (1.0 - xi * xi).sqrt();
    assert_relative_eq!(
        m.determinant(),
        (-2.0 * xi * w0 * t).exp(),
        max_relative = 1e-9
    );
    assert_relative_eq!(
        m.trace(),
        2.0 * (-xi * w0 * t).exp() * (wd * t).cos(),
        epsilon = 1e-9
    );
}

#[test]
fn odd_symmetry_half_period_map_for_pendulum_and_coulomb() {
    let p = ForcedPendulum::new(TAU, 0.3, 0.8, 6.0, 0.7).unwrap();
    let c = CoulombOscillator::new(TAU, 0.05, 1.5, 10.0, 0.8).unwrap();
    let o = opts(1e-12);
    for x0 in [[0.2, 0.0], [1.0, -1.0]] {
        let a = poincare_map(&EventDriven, &p, Section::Stroboscopic, x0, 1, &o).unwrap();
        let b = poincare_map(&EventDriven, &p, Section::HalfPeriod, x0, 2, &o).unwrap();
        assert!((a.x[0] - b.x[0]).abs() < 1e-8 && (a.x[1] - b.x[1]).abs() < 1e-8);
        let a = poincare_map(&EventDriven, &c, Section::Stroboscopic, x0, 1, &o).unwrap();
        let b = poincare_map(&EventDriven, &c, Section::HalfPeriod, x0, 2, &o).unwrap();
        assert!((a.x[0] - b.x[0]).abs() < 1e-8 && (a.x[1] - b.x[1]).abs() < 1e-8);
        assert!((a.jac_x.unwrap() - b.jac_x.unwrap()).abs().max() < 1e-6);
    }
}

#[test]
fn generic_oscillator_jacobians_match_finite_differences() {
    let p = ForcedPendulum::new(TAU, 0.3, 2.5, 9.0, 0.6).unwrap();
    let x0 = [0.4, 0.5];
    let o = opts(1e-12).record_events(true);
    let img = poincare_map(&EventDriven, &p, Section::Stroboscopic, x0, 1, &o).unwrap();
    assert!(img.events.len() >= 2);
    let plain = FlowOptions::with_tol(1e-13);
    let h = 1e-6;
    for j in 0..2 {
        let mut xp = x0;
        let mut xm = x0;
        xp[j] += h;
        xm[j] -= h;
        let a = poincare_map(&EventDriven, &p, Section::Stroboscopic, xp, 1, &plain).unwrap();
        let b = poincare_map(&EventDriven, &p, Section::Stroboscopic, xm, 1, &plain).unwrap();
        for i in 0..2 {
            let fd = (a.x[i] - b.x[i]) / (2.0 * h);
            assert!((img.jac_x.unwrap()[(i, j)] - fd).abs() < 1e-5 * fd.abs().max(1.0));
        }
    }
    // frequency column: includes dT/df
    let hp = 1e-6;
    let a = ForcedPendulum { f: p.f + hp, ..p };
    let b = ForcedPendulum { f: p.f - hp, ..p };
    let ia = poincare_map(&EventDriven, &a, Section::Stroboscopic, x0, 1, &plain).unwrap();
    let ib = poincare_map(&EventDriven, &b, Section::Stroboscopic, x0, 1, &plain).unwrap();
    for i in 0..2 {
        let fd = (ia.x[i] - ib.x[i]) / (2.0 * hp);
        assert!((img.jac_p.as_ref().unwrap()[(i, 0)] - fd).abs() < 1e-5 * fd.abs().max(1.0));
    }
}

#[test]
fn fixed_step_converges_to_event_driven() {
    let gear = Gear::paper(25.0, 2.7).unwrap();
    let x0 = [2.0, 1.0];
    let t1 = 2.0 / gear.f;
    let reference = EventDriven
        .flow(&gear, 0.0, x0, t1, &FlowOptions::with_tol(1e-13))
        .unwrap();
    let mut errs = Vec::new();
    for n in [50, 200, 800, 3200] {
        let fl = FixedStep {
            steps_per_period: n,
        }
        .flow(&gear, 0.0, x0, t1, &FlowOptions::default())
        .unwrap();
        errs.push((fl.x[0] - reference.x[0]).abs());
    }
    assert!(errs[3] < errs[0], "{errs:?}");
    assert!(errs[3] < 1e-3, "{errs:?}");
}

#[test]
fn bad_input_gives_errors_not_panics() {
    use gearbif::Error;
    let gear = Gear::paper(25.0, 2.7).unwrap();
    let o = FlowOptions::default();
    assert!(matches!(
        EventDriven.flow(&gear, 0.0, [f64::NAN, 0.0], 1.0, &o),
        Err(Error::NonFiniteState { what: "initial state", ref state })
            if state[0].is_nan() && state[1] == 0.0
    ));
    assert!(matches!(
        EventDriven.flow(&gear, 0.0, [0.0, 0.0], f64::INFINITY, &o),
        Err(Error::InvalidTimes { t1, .. }) if t1 == f64::INFINITY
    ));
    assert!(matches!(
        EventDriven.flow(&gear, 1.0, [0.0, 0.0], 0.0, &o),
        Err(Error::InvalidTimes { t0, t1, .. }) if t0 == 1.0 && t1 == 0.0
    ));
    let bad = FlowOptions {
        rtol: -1.0,
        ..FlowOptions::default()
    };
    assert!(matches!(
        EventDriven.flow(&gear, 0.0, [0.0, 0.0], 1.0, &bad),
        Err(Error::InvalidParameter { name: "rtol", .. })
    ));
    let unsorted = FlowOptions::default().samples(vec![0.5, 0.2]);
    assert!(matches!(
        EventDriven.flow(&gear, 0.0, [0.0, 0.0], 1.0, &unsorted),
        Err(Error::InvalidTimes { t0, t1, .. }) if t0 == 0.5 && t1 == 0.2
    ));
    assert!(matches!(
        Gear::paper(f64::NAN, 1.0),
        Err(Error::InvalidParameter { .. })
    ));
    assert!(matches!(
        poincare_map(
            &EventDriven,
            &gear,
            Section::Stroboscopic,
            [0.0, 0.0],
            0,
            &o
        ),
        Err(Error::InvalidOption { ref option, .. }) if option == "iterations"
    ));
    // a step budget too small for ten drive periods: the typed budget error, for both methods
    let tight = FlowOptions {
        max_steps: 5,
        ..FlowOptions::default()
    };
    for m in [&EventDriven as &dyn FlowMethod<Gear>, &EventDriven853] {
        assert!(matches!(
            m.flow(&gear, 0.0, [0.5, 2.0], 10.0 / 2.7, &tight),
            Err(Error::StepBudget { max_steps: 5, t }) if t > 0.0 && t < 10.0 / 2.7
        ));
    }
}

/// Bad options of the analyses, sweeps and curves give their specific error variant.
#[test]
fn bad_options_give_their_specific_variant() {
    use gearbif::analysis::{fit_harmonics, ClassifyOptions};
    use gearbif::continuation::two_param::lock_loss_boundary;
    use gearbif::sweep::{merge_shards, Axis, SweepSpec};
    use gearbif::Error;
    let opts = ClassifyOptions {
        record_turns: 0,
        ..ClassifyOptions::default()
    };
    assert!(matches!(
        opts.validate(),
        Err(Error::InvalidOption { ref option, .. }) if option == "record_turns"
    ));
    assert!(matches!(
        fit_harmonics(&[0.0; 20], &[0.0; 19], 7),
        Err(Error::Shape { expected, got: 19, .. }) if expected.starts_with("20")
    ));
    let axis = Axis::parse("f:1:2:0.5").unwrap();
    assert!(matches!(
        SweepSpec::paper_fig7(axis.clone(), axis).validate(),
        Err(Error::InconsistentOptions { ref options, .. }) if options == "rows, cols"
    ));
    assert!(matches!(
        Axis::parse("mass:0:1:1"),
        Err(Error::UnknownParameter { ref name, .. }) if name == "mass"
    ));
    assert!(matches!(
        merge_shards(&[]),
        Err(Error::Shape { got: 0, .. })
    ));
    let no_viscosity = Gear::new(400.0, 1.0, 0.0, 23.1, 1.0).unwrap();
    assert!(matches!(
        lock_loss_boundary(&no_viscosity, 5.0, &Default::default()),
        Err(Error::NoLockLossFrequency { zeta, .. }) if zeta == 0.0
    ));
}

#[test]
fn samples_follow_the_trajectory() {
    let gear = Gear::paper(31.0, 0.5).unwrap();
    let times: Vec<f64> = (0..=200).map(|i| i as f64 * 0.02).collect();
    let o = FlowOptions::with_tol(1e-11).samples(times.clone());
    let fl = EventDriven.flow(&gear, 0.0, [1.0, 0.0], 4.0, &o).unwrap();
    assert_eq!(fl.samples.len(), times.len());
    for s in fl.samples.iter().step_by(37) {
        let direct = EventDriven
            .flow(&gear, 0.0, [1.0, 0.0], s.t, &FlowOptions::with_tol(1e-11))
            .unwrap();
        assert!((direct.x[0] - s.beta).abs() < 1e-7, "t = {}", s.t);
        assert!((direct.x[1] - s.omega).abs() < 1e-6, "t = {}", s.t);
    }
}
