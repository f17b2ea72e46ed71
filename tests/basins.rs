//! Global stability (docs/basins.md), each result checked by something independent of the basin
//! search: the stable branches of the bifurcation diagram at Θ = 25° (tests/diagram.rs), the stable
//! manifold of a saddle from its shooting Jacobian, the binomial law of random sampling, and the
//! exact map of basins onto basins by the half-period map G.

use clap::Parser;
use gearbif::analysis::basins::{
    basin_fractions, basin_map, minimal_fatal_kick, recognise, AttractorSet, BasinOptions,
    KickNorm, KickOptions, Region,
};
use gearbif::integrator::{FlowOptions, Sensitivity, DEFAULT_METHOD};
use gearbif::maps::{poincare_map, Section};
use gearbif::model::{ForcedPendulum, Gear};
use gearbif::orbits::{shoot, OrbitSpec, ShootingOptions};
use gearbif::progress::Event;
use std::f64::consts::{PI, TAU};

fn quiet(_: &Event) {}

fn gear_region(f: f64) -> Region {
    let w = TAU * f;
    Region {
        beta: (0.0, TAU),
        omega: (-3.0 * w, 3.0 * w),
    }
}

/// The classes (a twin pair counted once) of the co-rotating attractors (ρ = +1) at Θ = 25°, f.
fn gear_classes(f: f64) -> (Vec<String>, Vec<f64>) {
    let gear = Gear::paper(25.0, f).unwrap();
    let set = AttractorSet::new(&gear);
    let opts = BasinOptions::default();
    basin_map(&gear, &set, gear_region(f), 24, 24, &opts, &quiet).unwrap();
    let (att, _) = set.finish();
    let mut co = Vec::new();
    let mut other = Vec::new(); // rotation numbers of the others
    for (i, a) in att.iter().enumerate() {
        println!("f = {f}: {} |μ| = {:.4}", a.legend(i), a.spectral_radius());
        assert!(a.is_periodic() && a.spectral_radius() < 1.0 && a.certified);
        if a.twin.is_some_and(|t| t < i) {
            continue; // the second of a twin pair
        }
        if (a.rotation_number - 1.0).abs() < 1e-9 {
            co.push(a.label.clone());
        } else {
            other.push(a.rotation_number);
        }
    }
    (co, other)
}

/// Attractor counts against the diagram's stable branches at Θ = 25° (docs/continuation.md, located
/// by tests/diagram.rs): the symmetric T/2 orbit is stable below 2.0777 and above 2.5014 Hz, the
/// asymmetric T pair between 1.8549 and 2.5014 Hz, the narrow second asymmetric pair between
/// 1.9278 and 1.9579 Hz. The diagram follows the co-rotating orbits (ρ = +1) only; the other
/// attractors found must turn the other way (ρ < 0: the reversed lock and its relatives).
#[test]
fn gear_attractors_are_the_stable_branches_of_the_diagram_at_theta25() {
    let expect: [(f64, &[&str]); 4] = [
        (1.7, &["T/2 sym"]),
        (1.94, &["T/2 sym", "T asym", "T asym"]),
        (2.2, &["T asym"]),
        (2.7, &["T/2 sym"]),
    ];
    for (f, want) in expect {
        let (co, other) = gear_classes(f);
        assert_eq!(co, want, "co-rotating attractors at f = {f}");
        assert!(other.iter().all(|&r| r < 0.0), "{other:?} at f = {f}");
    }
}

fn pendulum() -> ForcedPendulum {
    // Coulomb friction μ = 0.5: small and large symmetric oscillations coexist at 0.9 Hz
    ForcedPendulum::new(TAU, 0.3, 0.5, 3.0, 0.9).unwrap()
}

fn pendulum_region() -> Region {
    Region {
        beta: (-PI, PI),
        omega: (-15.0, 15.0),
    }
}

/// The saddle between the two stable orbits a and b of the pendulum: a point of the boundary
/// (bisection on the segment from a to b), carried 8 periods along its stable manifold towards the
/// saddle, then shot on P_T; with its stable and unstable unit directions (metric units) from the
/// eigenvectors of its Jacobian.
fn saddle(
    p: &ForcedPendulum,
    set: &AttractorSet,
    opts: &BasinOptions,
    a: [f64; 2],
    b: [f64; 2],
) -> ([f64; 2], [f64; 2], [f64; 2]) {
    let w = set.metric.omega_weight;
    let b0 = [a[0] + ((b[0] - a[0] + PI).rem_euclid(TAU) - PI), b[1]];
    let at = |s: f64| [a[0] + s * (b0[0] - a[0]), a[1] + s * (b0[1] - a[1])];
    let la = recognise(p, set, a, opts).index();
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..50 {
        let mid = 0.5 * (lo + hi);
        if recognise(p, set, at(mid), opts).index() == la {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let x = set.metric.stroboscopic(p, at(lo), 8, 1e-12).unwrap();
    let o = shoot(
        p,
        &OrbitSpec::stroboscopic(1, 0),
        x,
        &ShootingOptions::default(),
    )
    .unwrap();
    let fo = FlowOptions::with_tol(1e-11).sensitivity(Sensitivity::State);
    let m = poincare_map(&DEFAULT_METHOD, p, Section::Stroboscopic, o.x, 1, &fo)
        .unwrap()
        .jac_x
        .unwrap();
    let mu = o.floquet.multipliers;
    println!("saddle {:?}, multipliers {mu:?}", o.x);
    assert!(
        mu[0][1] == 0.0 && mu[0][0].abs() > 1.0 && mu[1][0].abs() < 1.0,
        "a saddle: {mu:?}"
    );
    let dir = |l: f64| {
        // (M − λ) v = 0 in state coordinates, then scaled to the metric (ω · w)
        let v = [m[(0, 1)], (l - m[(0, 0)]) * w];
        let n = v[0].hypot(v[1]);
        [v[0] / n, v[1] / n]
    };
    (o.x, dir(mu[1][0]), dir(mu[0][0]))
}

/// The basin boundary of the bistable Coulomb-damped pendulum is the stable manifold of the saddle
/// orbit between the two attractors: on a 24 × 24 basin map of cell size h = 1e-3 around the
/// saddle, every change of label between neighbouring cells lies within one cell diagonal of the
/// line through the saddle along its stable eigenvector (from the shooting Jacobian of P_T); the
/// boundary crosses the box; and the line along the unstable eigenvector is not a boundary.
#[test]
fn pendulum_basin_boundary_is_the_saddles_stable_manifold() {
    let p = pendulum();
    let set = AttractorSet::new(&p);
    let opts = BasinOptions::default();
    basin_map(&p, &set, pendulum_region(), 12, 12, &opts, &quiet).unwrap();
    let att = set.snapshot();
    assert_eq!(att.len(), 2, "{att:?}");
    let w = set.metric.omega_weight;
    let (xs, vs, vu) = saddle(&p, &set, &opts, att[0].points[0], att[1].points[0]);
    println!("saddle {xs:?}, stable {vs:?}, unstable {vu:?}");
    let (n, h) = (24usize, 1e-3);
    let half = 0.5 * n as f64 * h;
    let region = Region {
        beta: (xs[0] - half, xs[0] + half),
        omega: (xs[1] - half / w, xs[1] + half / w),
    };
    let map = basin_map(&p, &set, region, n, n, &opts, &quiet).unwrap();
    assert!(map.labels.iter().all(|l| l.is_some()));
    let dist_to_line = |x: [f64; 2]| {
        let d = [x[0] - xs[0], (x[1] - xs[1]) * w];
        (d[0] * vs[1] - d[1] * vs[0]).abs()
    };
    let mut worst: f64 = 0.0;
    let mut changes = 0;
    for row in 0..n {
        for col in 0..n {
            for (c2, r2) in [(col + 1, row), (col, row + 1)] {
                if c2 < n && r2 < n && map.labels[row * n + col] != map.labels[r2 * n + c2] {
                    let (a, b) = (map.centre(col, row), map.centre(c2, r2));
                    let mid = [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
                    worst = worst.max(dist_to_line(mid));
                    changes += 1;
                }
            }
        }
    }
    // a line through the centre crosses at least n − 1 cell edges of the box
    assert!(changes >= n - 1, "{changes} label changes");
    println!("largest distance of a label change from the stable line: {worst:.2e} (h = {h})");
    assert!(worst < h * 2f64.sqrt());
    // control: across the unstable line, near the saddle, the label does not change
    for t in [-0.01, 0.01] {
        let at = |s: f64| {
            let x = [
                xs[0] + t * vu[0] + s * vs[0],
                xs[1] + (t * vu[1] + s * vs[1]) / w,
            ];
            recognise(&p, &set, x, &opts).index()
        };
        assert_eq!(at(-h), at(h), "the unstable line is no boundary at t = {t}");
    }
}

/// χ² of the batch fractions about their pooled mean with binomial variance p(1 − p)/n.
fn chi2(batches: &[f64], n: usize) -> f64 {
    let k = batches.len() as f64;
    let p = batches.iter().sum::<f64>() / k;
    let var = p * (1.0 - p) / n as f64;
    batches.iter().map(|b| (b - p).powi(2) / var).sum()
}

/// Random-sample basin fractions converge at the binomial rate: 16 independent batches of n = 64
/// and of n = 256 samples scatter about their mean as χ² with 15 degrees of freedom (inside the
/// 0.1 % and 99.9 % quantiles 3.48 and 37.70, for both n: the spread halves when n quadruples), and
/// the pooled fraction agrees with the cell fraction of a 60 × 60 basin map within 4σ plus the
/// share of the map's boundary cells.
#[test]
fn basin_fractions_converge_at_the_binomial_rate() {
    let p = pendulum();
    let set = AttractorSet::new(&p);
    let opts = BasinOptions::default();
    let region = pendulum_region();
    let map = basin_map(&p, &set, region, 60, 60, &opts, &quiet).unwrap();
    let grid = map.cell_fractions(2)[0];
    let boundary = (0..60 * 59)
        .filter(|&i| map.labels[i] != map.labels[i + 60])
        .count() as f64
        / 3600.0;
    let mut pooled = (0usize, 0usize);
    for (n, seed0) in [(64usize, 100u64), (256, 200)] {
        let batches: Vec<f64> = (0..16)
            .map(|k| {
                let fr = basin_fractions(&p, &set, region, n, seed0 + k, &opts, &quiet).unwrap();
                assert_eq!(fr.failed, 0);
                pooled.0 += fr.fractions[0].count;
                pooled.1 += n;
                fr.fractions[0].fraction
            })
            .collect();
        let c = chi2(&batches, n);
        println!("n = {n}: χ² = {c:.2} (15 dof), batches {batches:.3?}");
        assert!(c > 3.48 && c < 37.70, "χ² = {c} at n = {n}");
    }
    let pp = pooled.0 as f64 / pooled.1 as f64;
    let sigma = (pp * (1.0 - pp) / pooled.1 as f64).sqrt();
    println!("pooled {pp:.4} ± {sigma:.4}, grid {grid:.4}, boundary share {boundary:.4}");
    assert!((pp - grid).abs() < 4.0 * sigma + boundary);
}

/// With the half-period symmetry, G maps the basin of each attractor onto the basin of its twin
/// exactly (P_T = G² modulo 2π): from every start x of a 10 × 10 grid at Θ = 25°, f = 2.2 Hz (an
/// asymmetric twin pair and the reversed lock), the attractor reached from G(x) is the twin of the
/// one reached from x. And the minimal fatal velocity kick of the lock is larger than its certified
/// neighbourhood, changes the attractor, and every kick of a 100-point scan below its bracket keeps it.
#[test]
fn g_maps_basins_onto_the_twins_basins_and_the_fatal_kick_brackets_the_boundary() {
    let gear = Gear::paper(25.0, 2.2).unwrap();
    let set = AttractorSet::new(&gear);
    let opts = BasinOptions::default();
    let map = basin_map(&gear, &set, gear_region(2.2), 10, 10, &opts, &quiet).unwrap();
    let att = set.snapshot();
    assert!(att.iter().any(|a| a.twin.is_some()));
    for row in 0..10 {
        for col in 0..10 {
            let x = map.centre(col, row);
            let a = map.labels[row * 10 + col].unwrap();
            let gx = set.metric.step(&gear, x, opts.tol).unwrap();
            let b = recognise(&gear, &set, gx, &opts).index().unwrap();
            assert_eq!(b, att[a].twin.unwrap_or(a), "start {x:?}");
        }
    }
    let lock = (0..att.len())
        .find(|&i| att[i].twin.is_some() && (att[i].rotation_number - 1.0).abs() < 1e-9)
        .unwrap();
    let k = KickOptions {
        norm: KickNorm::Velocity,
        directions: 2,
        phases: 1,
        max_kick: 4.0 * TAU * 2.2,
        scan: 16,
        rel_tol: 1e-3,
    };
    let kick = minimal_fatal_kick(&gear, &set, lock, &k, &opts).unwrap();
    let w = kick.worst.expect("a fatal kick within 4 · 2πf");
    let s = w.size.unwrap();
    println!(
        "fatal kick {s:.4} rad/s along {:?} → #{:?}",
        w.direction, w.lands_on
    );
    assert!(s * set.metric.omega_weight >= att[lock].radius);
    let y = att[lock].points[0];
    let at = |s: f64| recognise(&gear, &set, [y[0], y[1] + s * w.direction[1]], &opts).index();
    assert_ne!(at(s), Some(lock));
    // no fatal sliver below the bracket at 100 times the scan's resolution
    for i in 1..=100 {
        assert_eq!(
            at(w.safe * i as f64 / 100.0),
            Some(lock),
            "kick {i}/100 of the safe one"
        );
    }
}

/// `gearbif basins`: bad input is an error (exit code 2 in the binary), a small run writes its
/// folder with a JSON that names the attractors, and `--f-values` writes the continuation's.
#[test]
fn cli_basins_rejects_bad_input_and_writes_its_folder() {
    let run = |args: &[&str]| {
        let mut v = vec!["gearbif", "basins", "--quiet"];
        v.extend_from_slice(args);
        gearbif::cli::run(gearbif::cli::Cli::try_parse_from(v).unwrap())
    };
    for bad in [
        &["--f", "-1"][..],
        &["--f", "2", "--tol", "2"],
        &["--f", "2", "--cells-beta", "0"],
        &["--f", "2", "--omega-range", "5:1"],
        &["--f", "2", "--kick-norm", "energy"],
        &["--f", "2", "--max-steps", "3"],
        &["--f", "2", "--f-values", "3:1:0.1"],
        &["--f", "2", "--f-values", "1:2:0"],
    ] {
        assert!(run(bad).is_err(), "{bad:?} accepted");
    }
    let dir = std::env::temp_dir().join(format!("gearbif-basins-{}", std::process::id()));
    let out = dir.join("b");
    let o = out.to_str().unwrap();
    run(&[
        "--theta-deg",
        "25",
        "--f",
        "2.7",
        "--cells-beta",
        "6",
        "--cells-omega",
        "6",
        "--samples",
        "20",
        "--kick-phases",
        "1",
        "--out",
        o,
    ])
    .unwrap();
    let text = std::fs::read_to_string(out.join("basins.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(v["schema"], "gearbif.basins/1");
    assert!(!v["attractors"].as_array().unwrap().is_empty());
    assert_eq!(v["map"]["labels"].as_array().unwrap().len(), 36);
    assert!(out.join("basins.png").exists() && out.join("basins.svg").exists());
    let out2 = dir.join("follow");
    run(&[
        "--theta-deg",
        "25",
        "--f",
        "2",
        "--f-values",
        "2.0:2.2:0.1",
        "--samples",
        "30",
        "--out",
        out2.to_str().unwrap(),
    ])
    .unwrap();
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out2.join("follow.json")).unwrap()).unwrap();
    assert_eq!(v["schema"], "gearbif.basins-follow/1");
    assert_eq!(v["steps"].as_array().unwrap().len(), 3);
    assert!(out2.join("fractions.png").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// Global continuation over f at Θ = 25°: the co-rotating attractors are born and die between the
/// two frequencies that bracket the diagram's located points (docs/continuation.md): the symmetric
/// lock dies across the subcritical symmetry breaking at 2.0777 Hz and is born again across the
/// supercritical one at 2.5014 Hz; the asymmetric T pair is born across the flip at 1.8549 Hz and
/// dies at 2.5014 Hz. 200 samples per frequency.
#[test]
fn global_continuation_births_and_deaths_bracket_the_diagrams_bifurcations() {
    use gearbif::analysis::basins::{follow_attractors, FollowOptions, TrackEvent};
    use gearbif::model::GearParam;
    let values = [1.7, 1.9, 2.0, 2.1, 2.2, 2.4, 2.6, 2.8];
    let fo = FollowOptions {
        samples: 200,
        seed: 7,
        match_distance: 0.5,
    };
    let gear = Gear::paper(25.0, 2.0).unwrap();
    let opts = BasinOptions::default();
    let region = gear_region(2.0);
    let fol = follow_attractors(&gear, GearParam::F, &values, region, &fo, &opts, &quiet).unwrap();
    // the track's label and rotation number, from its first appearance
    let class = |t: usize| {
        fol.steps.iter().find_map(|s| {
            let i = s.tracks.iter().position(|&x| x == t)?;
            Some((
                s.attractors[i].label.clone(),
                s.attractors[i].rotation_number,
            ))
        })
    };
    for s in &fol.steps {
        let names: Vec<String> = (0..s.attractors.len())
            .map(|i| {
                format!(
                    "[{}] {} {:.2}",
                    s.tracks[i],
                    s.attractors[i].legend(i),
                    s.fractions[i].fraction
                )
            })
            .collect();
        println!("f = {}: {}", s.value, names.join("; "));
    }
    let co =
        |t: usize, label: &str| class(t).is_some_and(|(l, r)| l == label && (r - 1.0).abs() < 1e-9);
    let mut found = Vec::new();
    for e in &fol.events {
        println!("{e:?}");
        let (t, from, to, birth) = match *e {
            TrackEvent::Birth { track, from, to } => (track, from, to, true),
            TrackEvent::Death { track, from, to } => (track, from, to, false),
        };
        let label = if co(t, "T/2 sym") {
            "T/2 sym"
        } else if co(t, "T asym") {
            "T asym"
        } else {
            continue;
        };
        found.push((label, birth, from, to));
    }
    let expect = [
        ("T/2 sym", false, 2.0777),
        ("T/2 sym", true, 2.5014),
        ("T asym", true, 1.8549),
        ("T asym", false, 2.5014),
    ];
    for (label, birth, f) in expect {
        let n = found
            .iter()
            .filter(|e| e.0 == label && e.1 == birth && e.2 < f && f < e.3)
            .count();
        let want = if label == "T asym" { 2 } else { 1 }; // the twins
        assert_eq!(n, want, "{label} birth={birth} across {f} Hz: {found:?}");
    }
    assert_eq!(found.len(), 6, "no other co-rotating event: {found:?}");
}
