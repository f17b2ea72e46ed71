//! The fast atlas protocol (event-driven DOP853, early end of the settling once the strobe states
//! repeat, the rigorous analysis seeded by the cycle found, twin rows copied) gives the same paper
//! and rigorous classes as the slow one (DP5, every settling turn integrated, the full analysis) on
//! stretches of the semi-static ramp that contain T/2, T, longer periods, chaos and quasi-periodic
//! motion.

use gearbif::sweep::{
    Axis, Method, Protocol, SweepOutcome, SweepParam, SweepResult, SweepRunner, SweepSpec,
};
use std::collections::BTreeSet;

fn run(spec: SweepSpec) -> SweepResult {
    match SweepRunner::new(spec).run().unwrap() {
        SweepOutcome::Complete(r) => *r,
        o => panic!("{o:?}"),
    }
}

/// The slow (paper's 1000 turns, DP5) and fast specs of one stretch of the Fig. 8 ramp.
fn specs(theta: (f64, f64, f64), f: (f64, f64)) -> (SweepSpec, SweepSpec) {
    let mut slow = SweepSpec::paper_fig8().unwrap();
    slow.rows = Axis::range(SweepParam::ThetaDeg, theta.0, theta.1, theta.2).unwrap();
    slow.cols = Axis::range(SweepParam::F, f.0, f.1, 0.02).unwrap();
    slow.protocol = Protocol::SemiStatic;
    slow.method = Method::EventDriven;
    let mut fast = slow.clone();
    fast.method = Method::EventDriven853;
    fast.classify.settle_tol = Some(1e-8);
    (slow, fast)
}

/// Asserts equal paper and rigorous classes point by point; returns the rigorous labels seen.
fn same_classes(a: &SweepResult, b: &SweepResult) -> BTreeSet<String> {
    let mut labels = BTreeSet::new();
    for (p, q) in a.points().zip(b.points()) {
        assert_eq!(
            (&p.class, &p.paper_class),
            (&q.class, &q.paper_class),
            "Θ = {}°, f = {} Hz",
            p.row_value,
            p.col_value
        );
        labels.insert(p.class.clone());
    }
    labels
}

#[test]
fn fast_protocol_gives_the_slow_classes() {
    // a stretch with T/2, 3T and chaos (1000 settling turns as in the paper)
    let (slow, fast) = specs((30.0, 30.0, 5.0), (0.76, 0.98));
    let labels = same_classes(&run(slow), &run(fast));
    assert!(labels.len() >= 2, "{labels:?}");
    // a quasi-periodic stretch at Θ = 0 (the points where the shortened settling applies)
    let (slow, mut fast) = specs((0.0, 0.0, 5.0), (80.0, 80.22));
    let slow = run(slow);
    let labels_qp = same_classes(&slow, &run(fast.clone()));
    assert!(labels_qp.contains("QP"), "{labels_qp:?}");
    // there the short settling after non-periodic points gives the same classes too
    fast.classify.settle_after_nonperiodic = Some(100);
    same_classes(&slow, &run(fast));
    eprintln!("classes in the samples: {labels:?}, {labels_qp:?}");
}

#[test]
fn twin_rows_are_copied_and_equal_a_computed_row() {
    // Θ = −20° and 20° are the same gear (Δ = 1 − 3 sin²Θ): the runner copies one of them
    let (_, mut fast) = specs((-20.0, 20.0, 40.0), (2.0, 2.1));
    fast.classify.settle_turns = 200;
    assert!(fast.same_systems(0, 1));
    assert!(!specs((0.0, 20.0, 20.0), (2.0, 2.1)).1.same_systems(0, 1));
    let res = run(fast.clone());
    let computed = fast.compute_row(1, &gearbif::sweep::Silent).unwrap();
    assert_eq!(res.rows[1], computed);
    assert_eq!(res.rows[1].row_value, 20.0);
    for (p, q) in res.rows[0].points.iter().zip(&res.rows[1].points) {
        assert_eq!((p.row, p.row_value), (0, -20.0));
        assert_eq!(
            (&p.class, p.beta_end, p.rms_delta_deg),
            (&q.class, q.beta_end, q.rms_delta_deg)
        );
    }
}
