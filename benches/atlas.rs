//! One classified point: the paper's protocol (90 + 10 turns) plus the rigorous analysis
//! (60 turns with Jacobians), at Θ = 31°, and one semi-static Fig. 8 point (1000 + 10 turns).
use criterion::{criterion_group, criterion_main, Criterion};
use gearbif::analysis::{classify_point, ClassifyOptions};
use gearbif::integrator::EventDriven;
use gearbif::model::Gear;

fn bench(c: &mut Criterion) {
    let g = Gear::paper(31.0, 1.48)
        .unwrap()
        .with_alpha0(90f64.to_radians())
        .unwrap();
    let x0 = [90f64.to_radians(), 0.0];
    let o = ClassifyOptions::default();
    c.bench_function("classify_point theta31 1.48Hz (90+10+60 turns)", |b| {
        b.iter(|| classify_point(&g, x0, &EventDriven, &o).unwrap())
    });
    let g8 = Gear::paper(25.0, 10.0).unwrap();
    let o8 = ClassifyOptions {
        settle_turns: 1000,
        ..ClassifyOptions::default()
    };
    let mut grp = c.benchmark_group("fig8");
    grp.sample_size(10);
    grp.bench_function("fig8 point theta25 10Hz (1000+10+60 turns)", |b| {
        b.iter(|| classify_point(&g8, [0.0, 0.0], &EventDriven, &o8).unwrap())
    });
    grp.finish();
}

criterion_group! {
    name = benches;
    // no HTML plots: they need a system font that a fresh machine may lack
    config = Criterion::default().without_plots();
    targets = bench
}
criterion_main!(benches);
