//! The work-precision library (`gearbif::bench`): errors are measured against the reference and
//! shrink with the tolerance; a user-defined method enters the comparison.

use gearbif::bench::{reference, to_csv, work_precision, Candidate, WorkPrecisionSetup};
use gearbif::integrator::{EventDriven, FixedStep, Flow, FlowMethod, FlowOptions, Sensitivity};
use gearbif::model::{DrivenOscillator, Gear};

/// A user method: explicit Euler with naive sgn, 20000 steps per period.
struct Euler;
impl<S: DrivenOscillator + ?Sized> FlowMethod<S> for Euler {
    fn name(&self) -> String {
        "euler".into()
    }
    fn flow(
        &self,
        sys: &S,
        t0: f64,
        x0: [f64; 2],
        t1: f64,
        _o: &FlowOptions,
    ) -> gearbif::Result<Flow> {
        let n = 20_000;
        let h = (t1 - t0) / n as f64;
        let mut x = x0;
        for i in 0..n {
            let t = t0 + i as f64 * h;
            let f = sys.forces(t, x[0], x[1]);
            let s = x[1].signum() * (x[1] != 0.0) as i32 as f64;
            x = [x[0] + h * x[1], x[1] + h * (f.a - s * f.r)];
        }
        let mut fl = EventDriven.flow(sys, t0, x0, t0, &FlowOptions::default())?;
        fl.t = t1;
        fl.x = x;
        fl.stats.rhs_evals = n;
        Ok(fl)
    }
}

#[test]
fn errors_shrink_with_tolerance_and_user_methods_enter() {
    let gear = Gear::paper(25.0, 2.7).unwrap();
    let fixed = FixedStep {
        steps_per_period: 50,
    };
    let cands = [
        Candidate::new(&EventDriven, 1e-5, "dp5"),
        Candidate::new(&EventDriven, 1e-9, "dp5"),
        Candidate::new(&fixed, 0.0, "rk4"),
        Candidate::new(&Euler, 0.0, "user"),
    ];
    let setup = WorkPrecisionSetup {
        min_time_s: 0.0,
        ..WorkPrecisionSetup::new([0.5, 2.0])
    };
    let pts = work_precision(&gear, &setup, &cands).unwrap();
    assert_eq!(pts.len(), 4);
    assert!(pts[1].error < pts[0].error * 1e-2, "{pts:?}");
    assert!(pts[1].error < 1e-7 && pts[1].jac_error.unwrap() < 1e-6);
    assert!(pts[0].rhs_evals < pts[1].rhs_evals);
    // the error is really against the reference: recompute one by hand
    let r = reference(&gear, &setup).unwrap();
    let f = fixed
        .flow(&gear, 0.0, [0.5, 2.0], 1.0 / 2.7, &FlowOptions::default())
        .unwrap();
    let e = (f.x[0] - r.x[0]).abs().max((f.x[1] - r.x[1]).abs());
    assert!((pts[2].error - e).abs() <= 1e-12 * e.max(1.0));
    // Euler (first order, 20000 steps) lands between the two DP5 points, and has no Jacobian
    assert_eq!(pts[3].method, "euler");
    assert!(pts[3].error > pts[1].error && pts[3].error < 1e-1);
    assert!(pts[3].jac_error.is_none());
    let csv = to_csv(&pts);
    assert_eq!(csv.lines().count(), 5);
    assert!(pts.iter().all(|p| p.time_s > 0.0 && p.time_s.is_finite()));
    // bad setups are errors
    let bad = WorkPrecisionSetup {
        periods: f64::NAN,
        sensitivity: Sensitivity::None,
        ..setup
    };
    assert!(work_precision(&gear, &bad, &cands).is_err());
}
