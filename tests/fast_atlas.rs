//! The fast atlas protocol (event-driven DOP853, early end of the settling once the strobe states
//! repeat, one integrator start per chunk of turns) gives the same paper and rigorous classes as
//! the slow one (DP5, every settling turn integrated) on a sample of the semi-static ramp that
//! contains T/2, T and longer periods or chaos.

use gearbif::sweep::{Axis, Method, Protocol, SweepOutcome, SweepParam, SweepRunner, SweepSpec};

fn run(spec: SweepSpec) -> gearbif::sweep::SweepResult {
    match SweepRunner::new(spec).run().unwrap() {
        SweepOutcome::Complete(r) => *r,
        o => panic!("{o:?}"),
    }
}

#[test]
fn fast_protocol_gives_the_slow_classes() {
    let mut slow = SweepSpec::paper_fig8().unwrap();
    // a stretch of the Fig. 8 ramp with T/2, 3T and chaos (1000 settling turns as in the paper)
    slow.rows = Axis::range(SweepParam::ThetaDeg, 30.0, 30.0, 5.0).unwrap();
    slow.cols = Axis::range(SweepParam::F, 0.76, 0.98, 0.02).unwrap();
    slow.protocol = Protocol::SemiStatic;
    slow.method = Method::EventDriven;
    let mut fast = slow.clone();
    fast.method = Method::EventDriven853;
    fast.classify.settle_tol = Some(1e-8);
    let (a, b) = (run(slow), run(fast));
    let mut labels = std::collections::BTreeSet::new();
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
    // the sample is not trivial: more than one rigorous class
    assert!(labels.len() >= 2, "{labels:?}");
    eprintln!("classes in the sample: {labels:?}");
}
