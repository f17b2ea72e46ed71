//! Bring your own integrator: anything implementing `FlowMethod` enters the same work-precision
//! comparison as gearbif's methods.
//!
//! Here a user-written Heun (explicit RK2) scheme with a fixed step and a naive sgn(ω) — the kind of
//! integrator often written by hand for friction oscillators — is compared with the exact
//! event-driven integrator on one drive period of the gear (Θ = 25°, f = 2.7 Hz).
//!
//! Run: `cargo run --release --example custom_integrator`

use gearbif::bench::{work_precision, Candidate, WorkPrecisionSetup};
use gearbif::integrator::{EventDriven, Flow, FlowMethod, FlowOptions, Mode, Sensitivity, Stats};
use gearbif::model::{DrivenOscillator, Gear};

/// Heun's method (explicit trapezoidal RK2) with `n` steps per period and friction −r·sgn(ω).
struct Heun {
    n: usize,
}

impl Heun {
    fn field<S: DrivenOscillator + ?Sized>(sys: &S, t: f64, x: [f64; 2]) -> [f64; 2] {
        let f = sys.forces(t, x[0], x[1]);
        let s = if x[1] > 0.0 {
            1.0
        } else if x[1] < 0.0 {
            -1.0
        } else {
            0.0
        };
        [x[1], f.a - s * f.r]
    }
}

impl<S: DrivenOscillator + ?Sized> FlowMethod<S> for Heun {
    fn name(&self) -> String {
        format!("user Heun RK2 (T/{})", self.n)
    }

    fn flow(
        &self,
        sys: &S,
        t0: f64,
        x0: [f64; 2],
        t1: f64,
        _opts: &FlowOptions,
    ) -> gearbif::Result<Flow> {
        let steps = ((t1 - t0) / (sys.period() / self.n as f64)).ceil().max(1.0) as usize;
        let h = (t1 - t0) / steps as f64;
        let (mut t, mut x) = (t0, x0);
        for _ in 0..steps {
            let k1 = Self::field(sys, t, x);
            let xp = [x[0] + h * k1[0], x[1] + h * k1[1]];
            let k2 = Self::field(sys, t + h, xp);
            x = [
                x[0] + 0.5 * h * (k1[0] + k2[0]),
                x[1] + 0.5 * h * (k1[1] + k2[1]),
            ];
            t += h;
        }
        Ok(Flow {
            t: t1,
            x,
            mode: if x[1] >= 0.0 {
                Mode::Positive
            } else {
                Mode::Negative
            },
            jac_x: None,
            jac_p: None,
            events: Vec::new(),
            samples: Vec::new(),
            sample_jacobians: Vec::new(),
            stats: Stats {
                rhs_evals: 2 * steps,
                steps,
                ..Stats::default()
            },
        })
    }
}

fn main() -> gearbif::Result<()> {
    let gear = Gear::paper(25.0, 2.7)?;
    let heuns: Vec<Heun> = [50, 200, 800, 3200, 12800]
        .into_iter()
        .map(|n| Heun { n })
        .collect();
    let mut candidates: Vec<Candidate<'_, Gear>> = heuns
        .iter()
        .map(|m| Candidate::new(m as &dyn FlowMethod<Gear>, 0.0, "user Heun RK2"))
        .collect();
    for tol in [1e-4, 1e-6, 1e-8, 1e-10] {
        candidates.push(Candidate::new(&EventDriven, tol, "event-driven DP5"));
    }
    let setup = WorkPrecisionSetup {
        sensitivity: Sensitivity::None, // the user's method computes no Jacobian
        min_time_s: 0.02,
        ..WorkPrecisionSetup::new([0.5, 2.0])
    };
    let points = work_precision(&gear, &setup, &candidates)?;
    println!(
        "{:<28} {:>8} {:>10} {:>8} {:>10}",
        "method", "tol", "error", "rhs", "time [µs]"
    );
    for p in &points {
        println!(
            "{:<28} {:>8.0e} {:>10.2e} {:>8} {:>10.1}",
            p.method,
            p.tol,
            p.error,
            p.rhs_evals,
            p.time_s * 1e6
        );
    }
    #[cfg(feature = "plot")]
    {
        let path = std::env::temp_dir().join("gearbif-custom-integrator.svg");
        gearbif::plotting::save(
            &gearbif::bench::figure(&points, "user Heun vs event-driven DP5"),
            &path,
        )?;
        println!("figure: {}", path.display());
    }
    Ok(())
}
