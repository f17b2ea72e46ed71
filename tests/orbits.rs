//! Shooting and Floquet multipliers against independent answers: the analytic lock branch, the
//! symmetry P_T = R² ∘ G², simulations, and the rank-one monodromy of stick phases.

use approx::assert_relative_eq;
use gearbif::model::Gear;
use gearbif::orbits::{
    detect_period, orbit_from_simulation, shoot, Floquet, OrbitSpec, ShootingOptions,
};
use gearbif::Error;

fn opts() -> ShootingOptions {
    ShootingOptions::default()
}

#[test]
fn lock_orbit_by_shooting_equals_analytic_on_g_and_pt() {
    for f in [5.0, 10.0, 30.0] {
        let gear = Gear::paper(0.0, f).unwrap();
        let lb = gear.lock_branch().unwrap();
        for (pt, stable) in [(lb.stable, true), (lb.unstable, false)] {
            let guess = [pt.state[0] + 0.01, pt.state[1] * 1.002];
            for spec in [OrbitSpec::symmetric(1), OrbitSpec::stroboscopic(1, 1)] {
                let o = shoot(&gear, &spec, guess, &opts()).unwrap();
                assert_relative_eq!(o.x[0], pt.state[0], epsilon = 1e-8);
                assert_relative_eq!(o.x[1], pt.state[1], epsilon = 1e-7);
                assert_eq!(o.floquet.stable, stable);
                // P_T multipliers: squares of G's for the symmetric problem; analytic exp(λT)
                let m = o.stroboscopic_multipliers();
                let mut num: Vec<f64> = m.iter().map(|z| z[0].hypot(z[1])).collect();
                let mut ana: Vec<f64> = pt.multipliers.iter().map(|z| z.norm()).collect();
                num.sort_by(f64::total_cmp);
                ana.sort_by(f64::total_cmp);
                for (a, b) in num.iter().zip(&ana) {
                    assert_relative_eq!(a, b, max_relative = 1e-6);
                }
            }
        }
    }
}

#[test]
fn symmetric_orbit_is_fixed_point_of_pt_with_squared_multipliers() {
    let gear = Gear::paper(25.0, 2.7).unwrap();
    let g = orbit_from_simulation(&gear, [3.0, 15.0], 200, 4, true, &opts()).unwrap();
    assert_eq!(g.spec, OrbitSpec::symmetric(1));
    // independent: shoot on P_T from a perturbed guess
    let p = shoot(
        &gear,
        &OrbitSpec::stroboscopic(1, 1),
        [g.x[0] + 0.01, g.x[1] - 0.1],
        &opts(),
    )
    .unwrap();
    assert_relative_eq!(p.x[0], g.x[0], epsilon = 1e-8);
    assert_relative_eq!(p.x[1], g.x[1], epsilon = 1e-7);
    let sq = g.stroboscopic_multipliers();
    let pm = p.floquet.multipliers;
    let mut a: Vec<f64> = sq.iter().map(|z| z[0].hypot(z[1])).collect();
    let mut b: Vec<f64> = pm.iter().map(|z| z[0].hypot(z[1])).collect();
    a.sort_by(f64::total_cmp);
    b.sort_by(f64::total_cmp);
    for (x, y) in a.iter().zip(&b) {
        assert_relative_eq!(x, y, max_relative = 1e-6, epsilon = 1e-9);
    }
}

#[test]
fn stick_phase_gives_an_exact_zero_multiplier() {
    // the backward-turning symmetric orbit at Θ = 25°, f = 1.61 Hz has one stick phase per half period
    let gear = Gear::paper(25.0, 1.61).unwrap();
    let o = shoot(&gear, &OrbitSpec::symmetric(-1), [0.309, -0.5], &opts()).unwrap();
    assert_eq!(o.events.sticks, 1, "{:?}", o.events);
    assert_eq!(o.floquet.det, 0.0);
    assert_eq!(o.floquet.multipliers[1], [0.0, 0.0]);
    // the non-zero multiplier is the trace; check it against finite differences of the map
    let h = 1e-6;
    let img = |x: [f64; 2]| gearbif::maps::half_period(&gear, x, 1e-12).unwrap().x;
    let mut m = nalgebra::Matrix2::zeros();
    for j in 0..2 {
        let (mut xp, mut xm) = (o.x, o.x);
        xp[j] += h;
        xm[j] -= h;
        let (a, b) = (img(xp), img(xm));
        for i in 0..2 {
            m[(i, j)] = (a[i] - b[i]) / (2.0 * h);
        }
    }
    let fd = Floquet::of(&m);
    assert_relative_eq!(fd.trace, o.floquet.trace, epsilon = 1e-4);
    assert!(fd.det.abs() < 1e-4, "fd det {}", fd.det);
}

#[test]
fn detection_of_period_and_winding_from_simulation() {
    let gear = Gear::paper(0.0, 10.0).unwrap();
    let d = detect_period(&gear, [2.5, 60.0], 400, 4, 1e-6, 1e-10).unwrap();
    assert_eq!((d.period, d.winding), (1, 1));
    let o = orbit_from_simulation(&gear, [2.5, 60.0], 400, 4, true, &opts()).unwrap();
    let lb = gear.lock_branch().unwrap().stable;
    assert_relative_eq!(
        o.x[0].rem_euclid(std::f64::consts::TAU),
        lb.state[0],
        epsilon = 1e-8
    );
}

#[test]
fn bad_input_and_failures_are_typed_errors() {
    let gear = Gear::paper(0.0, 10.0).unwrap();
    assert!(matches!(
        shoot(&gear, &OrbitSpec::symmetric(1), [f64::NAN, 0.0], &opts()),
        Err(Error::NonFiniteState { .. })
    ));
    assert!(matches!(
        shoot(&gear, &OrbitSpec::stroboscopic(0, 1), [0.0, 0.0], &opts()),
        Err(gearbif::Error::InvalidOption { .. })
    ));
    // no locked orbit above f_c: Newton must fail with a reason, not return garbage
    let fast = Gear::paper(0.0, 45.0).unwrap();
    let r = shoot(
        &fast,
        &OrbitSpec::symmetric(1),
        [1.57, 45.0 * std::f64::consts::TAU],
        &ShootingOptions {
            max_iter: 15,
            ..opts()
        },
    );
    assert!(matches!(r, Err(Error::NewtonFailed { .. })), "{r:?}");
    // the analytic lock branch: only at Δ = ±1 and below f_c, a typed refusal elsewhere
    let lock = |theta_deg: f64, f: f64| {
        gearbif::model::LockBranch::new(&Gear::paper(theta_deg, f).unwrap())
    };
    assert!(lock(0.0, 10.0).is_ok());
    for (theta, f) in [(25.0, 1.0), (0.0, 45.0)] {
        let r = lock(theta, f);
        assert!(
            matches!(r, Err(Error::OutsideClosedForm { closed_form, .. }) if closed_form.contains("lock")),
            "Θ = {theta}°, f = {f} Hz: {:?}",
            r.err()
        );
    }
}
