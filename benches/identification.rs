//! Fitting kernels of the identification: the weak-form regression rows of one synthetic driven
//! run, one ring-down fit by simulation and Levenberg–Marquardt, and the whole diagnosis of a small
//! synthetic set (4 ring-downs, 2 driven runs of 15 turns, no held-out refits), and the refit of
//! the base model by simulation (multiple shooting) over all windows of that set.
use criterion::{criterion_group, criterion_main, Criterion};
use gearbif::identification::diagnose::{diagnose, DiagnoseOptions};
use gearbif::identification::model::Geometry;
use gearbif::identification::preprocess::clean;
use gearbif::identification::regression::{build, fit, WeakOptions, BASE_TERMS};
use gearbif::identification::ringdown::fit_ringdown;
use gearbif::identification::shooting::{
    choose_windows, mask_windows, refit, ShootingOptions, SimModel,
};
use gearbif::identification::synth::{synthesize, SynthOptions};
use gearbif::io::recordings::RunKind;

fn bench(c: &mut Criterion) {
    let opts = SynthOptions {
        ringdowns: 4,
        driven: 2,
        turns: 15.0,
        seed: 7,
        ..SynthOptions::default()
    };
    let (set, _) = synthesize(&opts).unwrap();
    let geo = Geometry::new(
        set.gear.theta_deg.to_radians(),
        set.gear.phi_deg.to_radians(),
    );
    let driven = set.runs.iter().find(|r| !r.is_ringdown()).unwrap();
    let cd = clean(driven, None);
    let n = cd.t.len();
    c.bench_function(
        &format!("weak-form rows + base fit, driven run ({n} samples)"),
        |b| {
            b.iter(|| {
                let d = build(
                    std::slice::from_ref(&cd),
                    &geo,
                    &BASE_TERMS,
                    &WeakOptions::default(),
                    0.0,
                );
                let cols: Vec<usize> = (0..BASE_TERMS.len()).collect();
                fit(&d, &cols).unwrap()
            })
        },
    );
    let rd = set.runs.iter().find(|r| r.is_ringdown()).unwrap();
    let alpha0 = match rd.kind {
        RunKind::Ringdown { alpha0 } => alpha0,
        RunKind::Driven { .. } => unreachable!(),
    };
    let cr = clean(rd, None);
    let mut grp = c.benchmark_group("identification");
    grp.sample_size(10);
    grp.bench_function(format!("ring-down fit ({} samples)", cr.t.len()), |b| {
        b.iter(|| {
            fit_ringdown(
                &cr,
                &rd.file,
                alpha0,
                1.1,
                23.1,
                DiagnoseOptions::default().ringdown_tol(),
            )
            .unwrap()
        })
    });
    // refit by simulation of the base model over the windows of all runs of the set
    let mut all: Vec<_> = set.runs.iter().map(|r| clean(r, None)).collect();
    let sig = all.iter().map(|r| r.sigma_beta).fold(f64::NAN, f64::min);
    all.iter_mut().for_each(|r| r.sigma_camera = sig);
    let d = build(&all, &geo, &BASE_TERMS, &WeakOptions::default(), 0.0);
    let f = fit(&d, &(0..BASE_TERMS.len()).collect::<Vec<_>>()).unwrap();
    let so = ShootingOptions::default();
    let model = SimModel {
        runs: &all,
        geo,
        terms: BASE_TERMS.to_vec(),
        latency: 0.0,
        fit_latency: false,
        eta_static_excess: 0.0,
        tol: DiagnoseOptions::default().tol,
        held_shapes: Vec::new(),
        roughness: 0.0,
        session: Default::default(),
    };
    let wins = mask_windows(&model, &f.coef, &choose_windows(&all, so.max_windows));
    let w = refit(&model, &f.coef, &wins, &so).unwrap().used.len();
    grp.bench_function(
        format!("refit by simulation, base model ({w} windows)"),
        |b| b.iter(|| refit(&model, &f.coef, &wins, &so).unwrap()),
    );
    let dopts = DiagnoseOptions {
        heldout_predictions: false,
        ..DiagnoseOptions::default()
    };
    grp.bench_function("diagnose (4 ring-downs + 2 driven x 15 turns)", |b| {
        b.iter(|| diagnose(&set, &dopts, &gearbif::progress::Silent).unwrap())
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
