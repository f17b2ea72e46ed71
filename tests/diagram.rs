//! The automatic bifurcation diagram at Θ = 25°, 1.5–3 Hz: with no indices or directions given it
//! must find every special point of the hand-made example (docs/continuation.md), each to 1e-6 Hz,
//! and recognise the branches it meets again instead of recomputing them.

use gearbif::continuation::diagram::{
    diagram, lock_seeds, Criticality, Diagram, DiagramOptions, DIAGRAM_SCHEMA,
};
use gearbif::continuation::{SpecialKind, StopReason};
use gearbif::model::{Gear, GearParam};

fn find(d: &Diagram, kind: SpecialKind, f: f64, tol: f64) -> Option<usize> {
    d.special_points.iter().position(|p| {
        p.point.kind == kind && p.same_as.is_none() && (p.point.param - f).abs() < tol
    })
}

#[test]
fn theta25_diagram_finds_every_documented_special_point() {
    let t0 = std::time::Instant::now();
    let gear = Gear::paper(25.0, 2.0).unwrap();
    // CI size: period doublings followed up to period 8 (the flip on the period-8 branch is still
    // located, not switched); `gearbif diagram --theta-deg 25 --range 1.5:3` goes to period 16
    let opts = DiagramOptions {
        grid: 4,
        max_period: 8,
        ..DiagramOptions::new(GearParam::F, (1.5, 3.0))
    };
    // no analytic branch at Θ = 25° (Δ ≠ ±1): the seeds come from simulations only
    let seeds = lock_seeds(&gear, &opts.continuation.shooting);
    assert!(seeds.is_empty());
    let d = diagram(&gear, &opts, seeds).unwrap();
    println!(
        "diagram: {} runs, {} map evaluations, {:?}",
        d.branches.len(),
        d.map_evaluations,
        t0.elapsed()
    );
    for (i, b) in d.branches.iter().enumerate() {
        let (lo, hi) = b.branch.param_range().unwrap_or((f64::NAN, f64::NAN));
        println!(
            "  [{i}] {:?} k={} p={} prim={} dir={:+} {} pts f∈[{lo:.4},{hi:.4}] from {:?} stop {:?}",
            b.branch.spec.section,
            b.branch.spec.iterations,
            b.branch.spec.winding,
            b.primitive,
            b.direction,
            b.branch.points.len(),
            b.origin,
            b.branch.stop
        );
    }
    for (i, p) in d.special_points.iter().enumerate() {
        println!(
            "  sp{i} br{} {:<18} f = {:.9} ± {:.1e} crit {:?} → {:?} {:?} same_as {:?}",
            p.branch,
            p.point.kind.label(),
            p.point.param,
            p.point.precision,
            p.criticality,
            p.switched_to,
            p.not_switched,
            p.same_as
        );
    }
    assert_eq!(d.schema, DIAGRAM_SCHEMA);
    let tol = 1e-6;
    let sb_sub = find(&d, SpecialKind::SymmetryBreaking, 2.077740215, tol).expect("SB 2.0777");
    let sb_sup = find(&d, SpecialKind::SymmetryBreaking, 2.501384436, tol).expect("SB 2.5014");
    assert_eq!(
        d.special_points[sb_sub].criticality,
        Some(Criticality::Subcritical)
    );
    assert_eq!(
        d.special_points[sb_sup].criticality,
        Some(Criticality::Supercritical)
    );
    for f in [1.854934873, 1.821913436, 1.816292918] {
        find(&d, SpecialKind::Flip, f, tol).unwrap_or_else(|| panic!("flip at {f}"));
    }
    find(&d, SpecialKind::Fold, 1.957902300, tol).expect("fold 1.9579");
    for f in [
        1.927811511,
        1.930900381,
        1.944786963,
        2.370338766,
        2.364173282,
        2.342996371,
    ] {
        find(&d, SpecialKind::Nonsmooth, f, tol).unwrap_or_else(|| panic!("nonsmooth at {f}"));
    }
    // the narrow T window is born at a nonsmooth fold (a multiplier jumps across +1)
    let nf = find(&d, SpecialKind::Nonsmooth, 1.927811511, tol).unwrap();
    let jump = d.special_points[nf].point.jump.as_ref().unwrap();
    assert_eq!(jump.crosses.as_deref(), Some("fold"));
    // twins and re-met branches are recognised, not recomputed
    assert!(d
        .branches
        .iter()
        .any(|b| matches!(b.branch.stop, StopReason::KnownBranch(_))));
    assert!(d.seeds.iter().any(|s| s.known));
}

#[test]
fn pinned_switch_at_the_subcritical_point_continues_to_lower_f() {
    // what `continue --switch-at` does: the new orbit is found with the parameter free, on the side
    // where the asymmetric branch exists (below 2.0777 Hz), and continued away from the point
    use gearbif::continuation::pinned::switch_at;
    use gearbif::continuation::{Continuation, ContinuationOptions};
    use gearbif::model::Parametrised;
    use gearbif::orbits::{OrbitSpec, ShootingOptions};
    let opts = ContinuationOptions {
        ds: 0.02,
        ds_max: 0.05,
        param_min: 1.9,
        param_max: 2.2,
        ..Default::default()
    };
    let gear = Gear::paper(25.0, 1.9).unwrap();
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
        .next()
        .unwrap()
        .clone();
    assert!((sb.param - 2.077740215).abs() < 1e-6);
    let (sys, orbit) = switch_at(&sym, &sb, 1e-2, &ShootingOptions::default()).unwrap();
    let f1 = sys.param(GearParam::F);
    assert!(f1 < sb.param && sb.param - f1 < 1e-2, "{f1}");
    assert!(!orbit.floquet.stable);
    let o1 = ContinuationOptions {
        ds: -0.005,
        ds_max: 0.02,
        max_steps: 200,
        ..opts
    };
    let asym = Continuation::from_orbit(sys, GearParam::F, &orbit, o1)
        .unwrap()
        .run(None)
        .unwrap();
    let nf = asym
        .specials_of(SpecialKind::Nonsmooth)
        .find(|s| (s.param - 1.927811511).abs() < 1e-6)
        .expect("the nonsmooth fold at 1.9278 Hz");
    assert_eq!(nf.jump.as_ref().unwrap().crosses.as_deref(), Some("fold"));
}
