//! Bringing your own system: a pendulum on a horizontally shaken pivot, with dry friction at the
//! pivot, defined here — outside the crate — and run through gearbif's public API only: shooting,
//! continuation with special points, classification and a small two-parameter sweep.
//!
//! ```text
//!   θ̈ + γθ̇ + ω₀² sin θ + μ sgn(θ̇) = A cos(2πft) cos θ
//! ```
//!
//! (the pivot moves as X(t) with Ẍ = −A L cos 2πft; the dry friction torque μ is constant).
//! A system implements two traits: `DrivenOscillator` (the forces a, r and their derivatives) and
//! `Parametrised` (its parameters: names, read/set, Jacobian column).
//!
//! Run: `cargo run --release --example user_system`

use gearbif::analysis::{classify_point, ClassifyOptions, Dynamics};
use gearbif::continuation::{Continuation, ContinuationOptions};
use gearbif::integrator::EventDriven;
use gearbif::model::{
    Column, DrivenOscillator, Forces, ForcesJet, HalfPeriodSymmetry, Parameter, Parametrised,
};
use gearbif::orbits::{orbit_from_simulation, ShootingOptions};
use gearbif::progress::Silent;
use gearbif::sweep::{sweep_grid, Protocol};
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

/// The shaken pendulum.
#[derive(Debug, Clone, Copy, PartialEq)]
struct ShakenPendulum {
    /// Small-amplitude angular frequency ω₀, rad/s.
    omega0: f64,
    /// Viscous damping γ, 1/s.
    gamma: f64,
    /// Dry friction at the pivot μ, 1/s².
    mu: f64,
    /// Shaking amplitude A, 1/s².
    a: f64,
    /// Shaking frequency f, Hz.
    f: f64,
}

/// Its parameters; the first three are the Jacobian columns, in this order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
enum Shaken {
    F,
    A,
    Mu,
}

impl Parameter for Shaken {
    const ALL: &'static [Self] = &[Shaken::F, Shaken::A, Shaken::Mu];
    fn name(self) -> &'static str {
        ["f", "a", "mu"][self as usize]
    }
    fn unit(self) -> &'static str {
        ["Hz", "1/s²", "1/s²"][self as usize]
    }
}

impl DrivenOscillator for ShakenPendulum {
    fn period(&self) -> f64 {
        1.0 / self.f
    }
    fn n_params(&self) -> usize {
        3
    }
    fn param_name(&self, k: usize) -> &'static str {
        Shaken::ALL[k].name()
    }
    fn period_derivative(&self, k: usize) -> f64 {
        if k == Shaken::F as usize {
            -1.0 / (self.f * self.f)
        } else {
            0.0
        }
    }
    fn forces(&self, t: f64, th: f64, w: f64) -> Forces {
        let drive = self.a * (TAU * self.f * t).cos() * th.cos();
        Forces {
            a: drive - self.gamma * w - self.omega0 * self.omega0 * th.sin(),
            r: self.mu,
        }
    }
    fn forces_jet(&self, t: f64, th: f64, w: f64, params: bool) -> ForcesJet {
        let (s, c) = (TAU * self.f * t).sin_cos();
        let (st, ct) = th.sin_cos();
        let w2 = self.omega0 * self.omega0;
        let mut j = ForcesJet::new(self.a * c * ct - self.gamma * w - w2 * st, self.mu);
        j.a_beta = -self.a * c * st - w2 * ct;
        j.a_omega = -self.gamma;
        if params {
            j.a_p[Shaken::F as usize] = -self.a * s * TAU * t * ct;
            j.a_p[Shaken::A as usize] = c * ct;
            j.r_p[Shaken::Mu as usize] = 1.0;
        }
        j
    }
    /// (t, θ) → (t + T/2, −θ) leaves the equation invariant.
    fn half_period_symmetry(&self) -> Option<HalfPeriodSymmetry> {
        Some(HalfPeriodSymmetry {
            sign: -1.0,
            shift: 0.0,
        })
    }
}

impl Parametrised for ShakenPendulum {
    type Param = Shaken;
    fn param(&self, p: Shaken) -> f64 {
        match p {
            Shaken::F => self.f,
            Shaken::A => self.a,
            Shaken::Mu => self.mu,
        }
    }
    fn with_param(&self, p: Shaken, v: f64) -> gearbif::Result<Self> {
        if !v.is_finite() || (p == Shaken::F && v <= 0.0) || (p == Shaken::Mu && v < 0.0) {
            return Err(gearbif::Error::InvalidParameter {
                name: p.name(),
                value: v,
                reason: "f must be > 0, μ >= 0, all finite",
            });
        }
        let mut s = *self;
        match p {
            Shaken::F => s.f = v,
            Shaken::A => s.a = v,
            Shaken::Mu => s.mu = v,
        }
        Ok(s)
    }
    fn column(&self, p: Shaken) -> Option<Column> {
        Some(Column::primary(p as usize))
    }
}

fn main() -> gearbif::Result<()> {
    let sys = ShakenPendulum {
        omega0: TAU,
        gamma: 0.4,
        mu: 1.0,
        a: 12.0,
        f: 1.4,
    };
    let sh = ShootingOptions::default();

    // 1. shooting: relax a simulation, detect its period, solve for the orbit
    let orbit = orbit_from_simulation(&sys, [0.3, 0.0], 200, 4, true, &sh)?;
    println!(
        "orbit at f = {} Hz: {:?} x = ({:.6}, {:.6}), multipliers {:?}, events {:?}",
        sys.f, orbit.spec, orbit.x[0], orbit.x[1], orbit.floquet.multipliers, orbit.events
    );

    // 2. continuation in f with special points
    let opts = ContinuationOptions {
        ds: -0.02,
        ds_max: 0.05,
        param_min: 0.4,
        param_max: 1.6,
        ..Default::default()
    };
    let branch = Continuation::from_orbit(sys, Shaken::F, &orbit, opts)?.run(None)?;
    println!(
        "branch: {} points, f in {:?}, stop: {:?}",
        branch.points.len(),
        branch.param_range(),
        branch.stop
    );
    for s in &branch.specials {
        println!(
            "  {:<18} f = {:.8} ± {:.1e} Hz  x = ({:.5}, {:.5})  stability changes: {}",
            s.kind.label(),
            s.param,
            s.precision,
            s.x[0],
            s.x[1],
            s.stability_change
        );
    }

    // 3. classification of the attractor at one point (rigorous: period on the section, Lyapunov)
    let copts = ClassifyOptions {
        settle_turns: 100,
        ..ClassifyOptions::default()
    };
    let c = classify_point(&sys, [0.3, 0.0], &EventDriven, &copts)?;
    let rig = c.rigorous.expect("rigorous classification requested");
    println!(
        "classification at f = {} Hz: {} (largest Lyapunov exponent per period: {:?})",
        sys.f, rig.label, rig.lyapunov.per_period
    );

    // 4. a small sweep over (A, f), semi-static along f
    let fs = [0.8, 1.0, 1.2, 1.4];
    let amps = [6.0, 12.0];
    let quick = ClassifyOptions {
        settle_turns: 60,
        analysis_turns: 40,
        ..ClassifyOptions::default()
    };
    let grid = sweep_grid(
        &EventDriven,
        &sys,
        (Shaken::A, &amps),
        (Shaken::F, &fs),
        [0.3, 0.0],
        Protocol::SemiStatic,
        &quick,
        &Silent,
    )?;
    println!("sweep (rigorous class; rows A, columns f = {fs:?} Hz):");
    for (row, a) in grid.iter().zip(amps) {
        let labels: Vec<String> = row
            .iter()
            .map(|(_, r)| match r.rigorous.as_ref().map(|c| &c.dynamics) {
                Some(Dynamics::Periodic { .. }) => r.rigorous.as_ref().unwrap().label.clone(),
                Some(d) => format!("{d:?}"),
                None => "-".into(),
            })
            .collect();
        println!("  A = {a:>5}: {labels:?}");
    }
    Ok(())
}
