//! Continuation benchmarks (the targets of issue 3) and a brute-force comparison.
//!
//! - `lock_branch_theta0_to_fold`: the lock branch at Θ = 0 from 5 Hz up to and including the
//!   located fold at f_c (target < 50 ms);
//! - `theta25_all_special_points`: at Θ = 25° the symmetric branch 1.5–3 Hz with both
//!   symmetry-breaking points, the switch onto the asymmetric branch and its continuation to 1.8 Hz
//!   with its nonsmooth points and flip (target < 2 s);
//! - `fc_theta_curve`: the lock-loss boundary f_c(Θ), both senses, 1° steps (target < 10 s);
//! - `brute_force_sweep_theta25`: a quasi-static up-and-down sweep at 0.02 Hz resolution, 1.5–3 Hz,
//!   200 periods per value: the cost of locating the same points to only ±0.01 Hz.

use criterion::{criterion_group, criterion_main, Criterion};
use gearbif::continuation::two_param::lock_loss_boundary;
use gearbif::continuation::{
    switch_branch, Continuation, ContinuationOptions, SpecialKind, StepOutcome,
};
use gearbif::model::{Gear, GearParam};
use gearbif::orbits::{quasi_static_sweep, OrbitSpec, ShootingOptions};
use std::hint::black_box;

fn lock_to_fold() -> f64 {
    let gear = Gear::paper(0.0, 5.0).unwrap();
    let opts = ContinuationOptions {
        ds: 0.5,
        ds_max: 5.0,
        param_min: 0.5,
        param_max: 60.0,
        ..Default::default()
    };
    let x = gear.lock_branch().unwrap().stable.state;
    let mut c = Continuation::new(gear, GearParam::F, OrbitSpec::symmetric(1), x, opts).unwrap();
    loop {
        if let Some(f) = c.branch().specials_of(SpecialKind::Fold).next() {
            return f.param;
        }
        if c.step().unwrap() == StepOutcome::Done {
            panic!("no fold");
        }
    }
}

fn theta25_all() -> usize {
    let opts = ContinuationOptions {
        ds: 0.02,
        ds_max: 0.05,
        param_min: 1.5,
        param_max: 3.0,
        ..Default::default()
    };
    let gear = Gear::paper(25.0, 1.5).unwrap();
    let sym = Continuation::new(
        gear,
        GearParam::F,
        OrbitSpec::symmetric(1),
        [2.98, 0.6],
        opts,
    )
    .unwrap()
    .run(None)
    .unwrap();
    let sb = sym
        .specials_of(SpecialKind::SymmetryBreaking)
        .last()
        .unwrap()
        .clone();
    let sw = switch_branch(&sym, &sb, -1e-3, &ShootingOptions::default()).unwrap();
    let asym = Continuation::from_orbit(
        sw.system,
        GearParam::F,
        &sw.orbit,
        ContinuationOptions {
            ds: -0.01,
            ds_max: 0.05,
            param_min: 1.8,
            max_steps: 400,
            ..opts
        },
    )
    .unwrap()
    .run(None)
    .unwrap();
    let n = sym.specials.len() + asym.specials.len();
    // 2 symmetry-breaking points, 3 nonsmooth points and the flip
    assert!(n >= 6, "only {n} special points");
    n
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("continuation");
    g.sample_size(10);
    g.bench_function("lock_branch_theta0_to_fold", |b| {
        b.iter(|| black_box(lock_to_fold()))
    });
    g.bench_function("theta25_all_special_points", |b| {
        b.iter(|| black_box(theta25_all()))
    });
    g.bench_function("fc_theta_curve", |b| {
        b.iter(|| {
            let base = Gear::paper(0.0, 1.0).unwrap();
            black_box(lock_loss_boundary(&base, 1.0, &ShootingOptions::default()).unwrap())
        })
    });
    g.bench_function("brute_force_sweep_theta25", |b| {
        b.iter(|| {
            let up: Vec<f64> = (0..=75).map(|i| 1.5 + 0.02 * i as f64).collect();
            let dn: Vec<f64> = up.iter().rev().copied().collect();
            let mk = |f| Gear::paper(25.0, f);
            let a = quasi_static_sweep(mk, &up, [2.98, 0.6], 200, 1e-9).unwrap();
            let x = a.last().unwrap().x;
            black_box(quasi_static_sweep(mk, &dn, x, 200, 1e-9).unwrap())
        })
    });
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = bench
}
criterion_main!(benches);
