//! One stroboscopic map P_T with its state Jacobian at Θ = 25°, f = 2.7 Hz, from (β, ω) = (0.5, 2)
//! (a period with a crossing of ω = 0), with friction (η = 23.1 s⁻²) and without (η = 0), for each
//! method at rtol 1e-6, 1e-9, 1e-12 (fixed step: 50, 800, 12800 steps per period), and the cost of
//! the right-hand side alone (as many `forces_jet` calls as the event-driven run makes).
//!
//! `per_period_1e-8`: DP5, DOP853 and the Taylor method at tol 1e-8 with friction, P_T from (0.5, 2) with and without
//! the state Jacobian, and the workload of the per-period cost goals (docs/performance.md): 1000
//! periods from rest with a strobe sample at every period, without (`1000_periods_strobe`) and with
//! the state Jacobian (`1000_periods_strobe_jac`); the time divided by 1000 is the cost per period.
//!
//! Run briefly: `cargo bench --bench integrators -- --warm-up-time 1 --measurement-time 3`
//! (only the 1e-8 group: append `per_period`)

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use gearbif::integrator::{
    EventDriven, EventDriven853, FixedStep, FlowMethod, FlowOptions, Sensitivity, Taylor,
};
use gearbif::model::{DrivenOscillator, Gear};
use std::hint::black_box;

const X0: [f64; 2] = [0.5, 2.0];

fn gears() -> Vec<(&'static str, Gear)> {
    let g = Gear::paper(25.0, 2.7).unwrap();
    let mut free = g;
    free.eta = 0.0;
    vec![("friction", g), ("eta0", free)]
}

fn opts(tol: f64) -> FlowOptions {
    FlowOptions::with_tol(tol).sensitivity(Sensitivity::State)
}

fn bench_methods(c: &mut Criterion) {
    for (label, gear) in gears() {
        let t1 = gear.period();
        let mut group = c.benchmark_group(format!("pt_jac/{label}"));
        for (tol, n) in [(1e-6, 50usize), (1e-9, 800), (1e-12, 12800)] {
            let o = opts(tol);
            group.bench_with_input(BenchmarkId::new("event_dp5", tol), &o, |b, o| {
                b.iter(|| EventDriven.flow(&gear, 0.0, black_box(X0), t1, o).unwrap())
            });
            #[cfg(feature = "diffsol-check")]
            {
                let reg = gearbif::integrator::Regularised::new(1e-4);
                group.bench_with_input(BenchmarkId::new("regularised_eps1e-4", tol), &o, |b, o| {
                    b.iter(|| reg.flow(&gear, 0.0, black_box(X0), t1, o).unwrap())
                });
            }
            let fixed = FixedStep {
                steps_per_period: n,
            };
            group.bench_with_input(BenchmarkId::new("fixed_rk4_steps", n), &o, |b, o| {
                b.iter(|| fixed.flow(&gear, 0.0, black_box(X0), t1, o).unwrap())
            });
            // the right-hand side alone: as many jets as the event-driven run evaluates
            let evals = EventDriven
                .flow(&gear, 0.0, X0, t1, &o)
                .unwrap()
                .stats
                .rhs_evals;
            let dt = t1 / evals as f64;
            group.bench_with_input(
                BenchmarkId::new("rhs_only_jets_of_dp5", tol),
                &evals,
                |b, &n| {
                    b.iter(|| {
                        let mut acc = 0.0;
                        for i in 0..n {
                            let j = gear.forces_jet(black_box(i as f64 * dt), X0[0], X0[1], false);
                            acc += j.a + j.a_beta;
                        }
                        acc
                    })
                },
            );
        }
        group.finish();
    }
}

fn bench_per_period(c: &mut Criterion) {
    let gear = Gear::paper(25.0, 2.7).unwrap();
    let t1 = gear.period();
    let mut group = c.benchmark_group("per_period_1e-8");
    let methods: [(&str, &dyn FlowMethod<Gear>); 3] = [
        ("dp5", &EventDriven),
        ("dop853", &EventDriven853),
        ("taylor", &Taylor),
    ];
    for (name, m) in methods {
        for (label, sens) in [("pt", Sensitivity::None), ("pt_jac", Sensitivity::State)] {
            let o = FlowOptions::with_tol(1e-8).sensitivity(sens);
            group.bench_function(format!("{label}/{name}"), |b| {
                b.iter(|| m.flow(&gear, 0.0, black_box(X0), t1, &o).unwrap())
            });
        }
        // 1000 periods from rest (β = π, the paper's start), a strobe sample at every period
        let n = 1000;
        let strobe: Vec<f64> = (0..=n).map(|i| i as f64 * t1).collect();
        group.sample_size(10);
        for (label, sens) in [
            ("1000_periods_strobe", Sensitivity::None),
            ("1000_periods_strobe_jac", Sensitivity::State),
        ] {
            let o = FlowOptions::with_tol(1e-8)
                .sensitivity(sens)
                .samples(strobe.clone());
            group.bench_function(format!("{label}/{name}"), |b| {
                b.iter(|| {
                    m.flow(
                        &gear,
                        0.0,
                        black_box([std::f64::consts::PI, 0.0]),
                        n as f64 * t1,
                        &o,
                    )
                    .unwrap()
                })
            });
        }
        group.sample_size(100);
    }
    group.finish();
}

// no plots: criterion's plotters backend needs a system font, which a fresh machine may lack
criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = bench_methods, bench_per_period
}
criterion_main!(benches);
