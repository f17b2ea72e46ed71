//! Multiple shooting: segment Jacobians against finite differences, agreement with single shooting
//! where both work, and the strongly unstable lock branch at Θ = 0 continued down to 0.2 Hz
//! (|μ_G| ≈ 1e18, far beyond single shooting) against the analytic branch
//! δ = arcsin((2πfζ + η)/g).

use gearbif::continuation::multiple_shooting::{continue_branch, MultipleShootingOptions};
use gearbif::continuation::{Continuation, ContinuationOptions, StopReason};
use gearbif::model::{DrivenOscillator, Gear, GearParam};
use gearbif::orbits::multiple_shooting::{evaluate, segment_states, segment_times, shoot_multiple};
use gearbif::orbits::{shoot, OrbitSpec, ShootingOptions};
use std::f64::consts::TAU;

#[test]
fn segment_jacobians_match_central_differences() {
    // Θ = 25°, 2.2 Hz: the symmetric orbit crosses Σ; segments start at t_i ≠ 0
    let gear = Gear::paper(25.0, 2.2).unwrap();
    let spec = OrbitSpec::stroboscopic(1, 1);
    let opts = ShootingOptions::default();
    let y = segment_states(&gear, &spec, [2.9, 5.0], 3, 1e-12).unwrap();
    let seg = evaluate(&gear, &spec, &y, &opts, false).unwrap();
    let h = 1e-6;
    for i in 0..3 {
        let b = seg.images[i].jac_x.unwrap();
        for j in 0..2 {
            let mut yp = y.clone();
            let mut ym = y.clone();
            yp[i][j] += h;
            ym[i][j] -= h;
            let ep = evaluate(&gear, &spec, &yp, &opts, false).unwrap();
            let em = evaluate(&gear, &spec, &ym, &opts, false).unwrap();
            for k in 0..2 {
                let fd = (ep.residuals[i][k] - em.residuals[i][k]) / (2.0 * h);
                assert!(
                    (fd - b[(k, j)]).abs() < 1e-5 * (1.0 + b[(k, j)].abs()),
                    "B_{i}[{k},{j}]: {fd} vs {}",
                    b[(k, j)]
                );
            }
        }
        // the frequency column includes the shift of t_i and t_{i+1} with the period
        let jp = seg.images[i].jac_p.as_ref().unwrap();
        let hf = 1e-6;
        let gp = gear.with_f(2.2 + hf).unwrap();
        let gm = gear.with_f(2.2 - hf).unwrap();
        let ep = evaluate(&gp, &spec, &y, &opts, false).unwrap();
        let em = evaluate(&gm, &spec, &y, &opts, false).unwrap();
        for k in 0..2 {
            let fd = (ep.residuals[i][k] - em.residuals[i][k]) / (2.0 * hf);
            let an = jp[(k, 0)]; // column 0: f
            assert!(
                (fd - an).abs() < 1e-4 * (1.0 + an.abs()),
                "∂E_{i}/∂f [{k}]: {fd} vs {an}"
            );
        }
    }
    assert_eq!(segment_times(&gear, &spec, 4)[4], gear.period());
}

#[test]
fn multiple_and_single_shooting_agree_where_both_work() {
    let gear = Gear::paper(25.0, 2.3).unwrap();
    let opts = ShootingOptions::default();
    for spec in [OrbitSpec::symmetric(1), OrbitSpec::stroboscopic(1, 1)] {
        let single = shoot(&gear, &spec, [2.98, 8.0], &opts).unwrap();
        let y0 = segment_states(&gear, &spec, [2.95, 8.3], 5, 1e-11).unwrap();
        let multi = shoot_multiple(&gear, &spec, &y0, &opts).unwrap();
        assert!((multi.states[0][0] - single.x[0]).abs() < 1e-9);
        assert!((multi.states[0][1] - single.x[1]).abs() < 1e-8);
        for k in 0..2 {
            for c in 0..2 {
                let (a, b) = (
                    multi.floquet.multipliers[k][c],
                    single.floquet.multipliers[k][c],
                );
                assert!((a - b).abs() < 1e-6 * (1.0 + b.abs()), "{a} vs {b}");
            }
        }
        assert_eq!(multi.events, single.events);
    }
}

#[test]
fn unstable_lock_at_0p2_hz_by_multiple_shooting_equals_analytic() {
    // |μ_G| = exp(λ T/2) ≈ 1e18 at 0.2 Hz: single shooting cannot resolve 1e-8 rad there
    let gear = Gear::paper(0.0, 0.2).unwrap();
    let lock = gear.lock_branch().unwrap().unstable;
    let spec = OrbitSpec::symmetric(1);
    let m = 24;
    let t = segment_times(&gear, &spec, m);
    // a perturbed start: the analytic orbit β = β₀ + 2πf t shifted by 1e-3 rad
    let y0: Vec<[f64; 2]> = t[..m]
        .iter()
        .map(|&ti| {
            [
                lock.state[0] + 1e-3 + TAU * 0.2 * ti,
                lock.state[1] * (1.0 + 1e-3),
            ]
        })
        .collect();
    let o = shoot_multiple(&gear, &spec, &y0, &ShootingOptions::default()).unwrap();
    assert!(
        (o.states[0][0] - lock.state[0]).abs() < 1e-8,
        "{}",
        o.states[0][0] - lock.state[0]
    );
    for (i, x) in o.states.iter().enumerate() {
        assert!((x[0] - lock.state[0] - TAU * 0.2 * t[i]).abs() < 1e-8);
        assert!((x[1] - lock.state[1]).abs() < 1e-8);
    }
    let ana = lock.multipliers[0].norm().sqrt(); // P_T multiplier → G multiplier
    let num = o.floquet.spectral_radius();
    println!(
        "0.2 Hz, {m} segments: {} Newton iterations, residual {:.1e}, largest segment growth {:.1}, \
         δ error {:.1e} rad, |μ_G| = {num:.4e} (analytic {ana:.4e})",
        o.newton_iterations,
        o.residual,
        o.max_segment_growth,
        o.states[0][0] - lock.state[0]
    );
    assert!(ana > 1e17, "{ana}");
    assert!((num / ana - 1.0).abs() < 1e-5, "{num} vs {ana}");
}

#[test]
fn unstable_lock_branch_continued_to_0p2_hz_by_multiple_shooting() {
    // from the unstable lock at 1.5 Hz downwards: single shooting to |μ| = 1e3, then multiple shooting
    let gear = Gear::paper(0.0, 1.5).unwrap();
    let lock = gear.lock_branch().unwrap().unstable;
    let opts = ContinuationOptions {
        ds: -0.2,
        ds_max: 0.5,
        param_min: 0.2,
        param_max: 2.0,
        max_multiplier: 1e3,
        ..Default::default()
    };
    let c = Continuation::new(
        gear,
        GearParam::F,
        OrbitSpec::symmetric(1),
        lock.state,
        opts,
    )
    .unwrap();
    let b = continue_branch(c, &opts, Some(&MultipleShootingOptions::default()), None).unwrap();
    let from = b
        .multiple_shooting_from
        .expect("handed over to multiple shooting");
    assert!(from >= 2 && from < b.points.len());
    assert!(
        matches!(b.stop, StopReason::ParameterBound(v) if v == 0.2),
        "{:?}",
        b.stop
    );
    let last = b.points.last().unwrap();
    assert_eq!(last.param, 0.2);
    assert!(last.floquet.spectral_radius() > 1e17);
    let mut worst: f64 = 0.0;
    for p in &b.points {
        let lb = Gear::paper(0.0, p.param)
            .unwrap()
            .lock_branch()
            .unwrap()
            .unstable;
        worst = worst.max((p.x[0] - lb.state[0]).abs());
        assert!((p.x[1] - TAU * p.param).abs() < 1e-7 * TAU * p.param.max(1.0));
        assert!(!p.stable);
        let ana = lb.multipliers[0].norm().sqrt();
        let num = p.floquet.spectral_radius();
        assert!(
            (num / ana - 1.0).abs() < 1e-5,
            "at {}: {num} vs {ana}",
            p.param
        );
    }
    println!(
        "{} points ({} by multiple shooting from f = {:.4} Hz), {} map evaluations, \
         |μ_G| at 0.2 Hz = {:.3e}, largest |δ − δ_analytic| = {worst:.2e} rad",
        b.points.len(),
        b.points.len() - from,
        b.points[from - 1].param,
        b.map_evaluations,
        last.floquet.spectral_radius()
    );
    assert!(worst < 1e-8, "largest |δ − δ_analytic| = {worst:e} rad");
}
