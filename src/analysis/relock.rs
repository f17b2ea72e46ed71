//! The slip-through state of the gear at Δ = 1 (Θ = 0) and the frequency where it re-locks.
//!
//! At Δ = 1 the coupling is g sin(β − α) (model.md), so in the co-rotating angle δ = β − α,
//! α = α₀ + Ωt, Ω = 2πf, the equation of motion
//!
//! ```text
//!   δ̇ = ω − Ω,   ω̇ = −ζ ω − η sgn ω + g sin δ
//! ```
//!
//! is autonomous: a damped pendulum on the cylinder driven by the drag of the turning input. The
//! lock is its pair of equilibria ω = Ω, g sin δ = ζΩ + η: the stable one δ_s = π − arcsin((ζΩ + η)/g)
//! and the **saddle** δ_u = arcsin((ζΩ + η)/g), with eigenvalues
//! λ = (−ζ ± √(ζ² + 4 g cos δ_u))/2. The slip-through state is a limit cycle on the cylinder on
//! which δ falls by 2π per cycle of duration τ (the output loses one turn against the input); its
//! mean winding per drive period is 1 − 1/(fτ).
//!
//! On a down-sweep the cycle ends in a **homoclinic bifurcation**: it collides with the saddle, its
//! duration diverges like τ ≈ −ln(f − f_h)/λ_u, and below f_h every slipping state falls into the
//! lock. f_h is located exactly as the frequency where the branch of the saddle's unstable manifold
//! that leaves towards lower δ stops passing the next saddle copy δ_u − 2π and turns back into the
//! lock ([`homoclinic_frequency`], bisection on that binary fate; its error is the bracket plus the
//! change with the integrator tolerance and the start offset along the eigenvector). Second routes:
//! the cycle itself by shooting ([`slip_cycle`]), whose duration follows the logarithmic law, and
//! linear down-ramps of the drive ([`ramp_relock`], [`crate::model::Ramped`]) whose last slip
//! converges to f_h as the ramp rate goes to 0.

use crate::error::{Error, Result};
use crate::integrator::{vector_field, EventDriven, FlowMethod, FlowOptions, Sensitivity};
use crate::model::{Convention, DrivenOscillator, Gear, Ramped};
use crate::numerics::{newton, Linearisation, NewtonOptions};
use nalgebra::{Matrix2, Vector2};
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

/// Checks that `gear` is autonomous in δ (Δ = 1, physical convention) and returns Ω.
fn co_rotating(gear: &Gear) -> Result<f64> {
    if (gear.delta - 1.0).abs() > 1e-12 || gear.convention != Convention::Physical {
        return Err(Error::OutsideClosedForm {
            closed_form: "the slip-through cycle",
            needs: format!(
                "Δ = 1 in the physical convention (Δ = {}, {:?})",
                gear.delta, gear.convention
            ),
        });
    }
    Ok(TAU * gear.f)
}

/// The saddle of the co-rotating system (the unstable lock).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Saddle {
    /// δ_u = arcsin((ζΩ + η)/g), rad.
    pub delta: f64,
    /// Unstable eigenvalue λ_u = (−ζ + √(ζ² + 4 g cos δ_u))/2, 1/s.
    pub unstable: f64,
}

/// The saddle δ_u and its unstable eigenvalue; an error above the lock-loss frequency.
pub fn saddle(gear: &Gear) -> Result<Saddle> {
    let om = co_rotating(gear)?;
    let s = (gear.zeta * om + gear.eta) / gear.g;
    if s.is_nan() || s.abs() >= 1.0 {
        return Err(Error::InvalidParameter {
            name: "f",
            value: gear.f,
            reason: "above the lock-loss frequency: no lock, no saddle",
        });
    }
    let delta = s.asin();
    let c = gear.g * delta.cos();
    let unstable = 0.5 * (-gear.zeta + (gear.zeta * gear.zeta + 4.0 * c).sqrt());
    Ok(Saddle { delta, unstable })
}

/// The slip-through cycle at one frequency.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SlipCycle {
    /// δ on the section (β = δ at t = 0 with α₀ = 0), rad.
    pub delta0: f64,
    /// ω on the section, rad/s.
    pub omega0: f64,
    /// Duration τ of one cycle (δ falls by 2π), s.
    pub duration: f64,
    /// The nontrivial multiplier det M of the cycle (the other is 1, along the flow).
    pub multiplier: f64,
    /// Mean winding of β per drive period, 1 − 1/(fτ).
    pub winding: f64,
    /// Newton iterations.
    pub iterations: usize,
}

/// The slip-through cycle by shooting: unknowns (ω₀, τ) with the phase δ(0) = `delta0` fixed,
/// equations δ(τ) = δ₀ − 2π, ω(τ) = ω₀; Newton with the flow's Jacobian (saltation at every event)
/// and the vector field at τ for the τ column, with backtracking, to a residual below 100·`tol`.
/// `guess` = (ω₀, τ).
pub fn slip_cycle(gear: &Gear, delta0: f64, guess: (f64, f64), tol: f64) -> Result<SlipCycle> {
    let om = co_rotating(gear)?;
    let (mut w0, mut tau) = guess;
    if !(w0.is_finite() && tau > 0.0 && delta0.is_finite()) {
        return Err(Error::NonFiniteState {
            what: "start of a slip cycle (δ₀, ω₀, τ > 0)",
            state: vec![delta0, w0, tau],
        });
    }
    let o = FlowOptions::with_tol(tol).sensitivity(Sensitivity::State);
    let b0 = delta0 + gear.alpha(0.0);
    let nopts = NewtonOptions {
        line_search: true,
        ..NewtonOptions::new(1e2 * tol, 40)
    };
    let sol = newton(
        Vector2::new(w0, tau),
        &nopts,
        |u| {
            if u[1].is_nan() || u[1] <= 0.0 {
                return Err(Error::NotFound {
                    what: format!(
                        "slip-through cycle (the Newton iterate reached a duration {} ≤ 0)",
                        u[1]
                    ),
                });
            }
            let fl = EventDriven.flow(gear, 0.0, [b0, u[0]], u[1], &o)?;
            let j = fl.jac_x.ok_or(Error::MissingJacobian { what: "state" })?;
            let vf = vector_field(gear, u[1], fl.x, fl.mode);
            Ok(Linearisation {
                residual: Vector2::new(fl.x[0] - gear.alpha(u[1]) - (delta0 - TAU), fl.x[1] - u[0]),
                jacobian: Matrix2::new(j[(0, 1)], vf[0] - om, j[(1, 1)] - 1.0, vf[1]),
                data: j.determinant(),
            })
        },
        |_, _| 1.0,
        &format!("slip cycle at f = {} Hz", gear.f),
    )?;
    (w0, tau) = (sol.x[0], sol.x[1]);
    Ok(SlipCycle {
        delta0,
        omega0: w0,
        duration: tau,
        multiplier: sol.at.data,
        winding: 1.0 - 1.0 / (gear.f * tau),
        iterations: sol.iterations,
    })
}

/// Follows the branch of the saddle's unstable manifold that leaves towards lower δ, from
/// δ_u − ε along the eigenvector (δ, ω − Ω) ∝ (1, λ_u): `true` if it passes the next saddle copy
/// (δ < δ_u − 2π − 0.5: the output slips a turn), `false` if it turns back first (ω > Ω while
/// δ_u − 2π < δ < δ_u − 0.5: it falls into the lock).
pub fn unstable_manifold_passes(gear: &Gear, eps: f64, tol: f64) -> Result<bool> {
    let om = co_rotating(gear)?;
    let sd = saddle(gear)?;
    let mut x = [sd.delta - eps + gear.alpha(0.0), om - eps * sd.unstable];
    let o = FlowOptions::with_tol(tol);
    let h = 0.05 * gear.period();
    let mut t = 0.0;
    // the first cycle from the saddle takes at most a few hundred drive periods
    for _ in 0..200_000 {
        x = EventDriven.flow(gear, t, x, t + h, &o)?.x;
        t += h;
        let d = x[0] - gear.alpha(t);
        if d < sd.delta - TAU - 0.5 {
            return Ok(true);
        }
        if x[1] > om && d > sd.delta - TAU && d < sd.delta - 0.5 {
            return Ok(false);
        }
    }
    Err(Error::ManifoldUndecided { t, f: gear.f })
}

/// The located homoclinic bifurcation of the slip-through cycle.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Homoclinic {
    /// Largest frequency found where the manifold falls back into the lock, Hz.
    pub below: f64,
    /// Smallest frequency found where it passes (the cycle exists above f_h), Hz.
    pub above: f64,
    /// Start offset ε along the unstable eigenvector.
    pub eps: f64,
    /// Integrator tolerance.
    pub tol: f64,
}

impl Homoclinic {
    /// The midpoint of the bracket.
    pub fn value(&self) -> f64 {
        0.5 * (self.below + self.above)
    }
}

/// Bisection on f in [`lo`, `hi`] for the frequency where the saddle's unstable manifold stops
/// passing the next saddle ([`unstable_manifold_passes`]), to a bracket below `ftol`. `base` gives
/// every parameter but f. The manifold must turn back at `lo` and pass at `hi`.
pub fn homoclinic_frequency(
    base: &Gear,
    lo: f64,
    hi: f64,
    eps: f64,
    tol: f64,
    ftol: f64,
) -> Result<Homoclinic> {
    if !(lo < hi && ftol > 0.0 && eps > 0.0) {
        return Err(Error::inconsistent(
            "lo, hi, eps, ftol",
            format!("the search needs lo < hi, eps > 0, ftol > 0 ({lo}, {hi}, {eps}, {ftol})"),
        ));
    }
    let passes = |f: f64| unstable_manifold_passes(&base.with_f(f)?, eps, tol);
    if passes(lo)? || !passes(hi)? {
        return Err(Error::inconsistent(
            "lo, hi",
            format!("[{lo}, {hi}] Hz does not bracket the homoclinic frequency"),
        ));
    }
    let mut bracket = crate::numerics::Bisection::new(lo, hi);
    while bracket.hi() - bracket.lo() > ftol {
        let Some(m) = bracket.next_point() else { break };
        bracket.update(m, passes(m)?);
    }
    Ok(Homoclinic {
        below: bracket.lo(),
        above: bracket.hi(),
        eps,
        tol,
    })
}

/// The outcome of one linear down-ramp of the drive.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RampRelock {
    /// Ramp rate ḟ, Hz/s.
    pub rate: f64,
    /// Drive frequency at the last slip (the last time δ − δ_u(f) fell through a multiple of 2π), Hz.
    pub last_slip: f64,
    /// Number of slips during the ramp.
    pub slips: usize,
    /// |δ − δ_s| at the end of the ramp, rad (small: locked).
    pub lock_offset: f64,
}

/// Ramps the drive of `gear` (Δ = 1) from its f at rate `rate` < 0 Hz/s down to `f_end`, from the
/// state `x0` at t = 0, and returns the frequency of the last slip. The run is sampled every T/64
/// (of the start frequency); a slip is a passage of δ − δ_u(f(t)) through a multiple of 2π
/// downwards, its time interpolated linearly between samples.
pub fn ramp_relock(
    gear: &Gear,
    x0: [f64; 2],
    rate: f64,
    f_end: f64,
    tol: f64,
) -> Result<RampRelock> {
    co_rotating(gear)?;
    if !(rate < 0.0 && f_end < gear.f && f_end > 0.0) {
        return Err(Error::inconsistent(
            "rate, f_end",
            format!("a down-ramp needs rate < 0 and 0 < f_end < f ({rate}, {f_end})"),
        ));
    }
    let ramp = Ramped::new(*gear, rate)?;
    let t_end = ramp.time_of(f_end);
    let dt = gear.period() / 64.0;
    let level = |t: f64, beta: f64| -> Result<f64> {
        let g = gear.with_f(ramp.frequency(t))?;
        Ok((beta - ramp.drive_phase(t) - saddle(&g)?.delta) / TAU)
    };
    let (mut t, mut x) = (0.0, x0);
    let mut prev = level(t, x[0])?;
    let (mut slips, mut last) = (0, None);
    let o = FlowOptions::with_tol(tol);
    while t < t_end {
        let t1 = (t + dt).min(t_end);
        x = EventDriven.flow(&ramp, t, x, t1, &o)?.x;
        let cur = level(t1, x[0])?;
        if cur.floor() < prev.floor() {
            let frac = (prev - prev.floor()) / (prev - cur);
            slips += 1;
            last = Some(t + frac * (t1 - t));
        }
        prev = cur;
        t = t1;
    }
    let last = last
        .ok_or_else(|| Error::option("x0", "the ramp started locked: no slip during the ramp"))?;
    let g_end = gear.with_f(f_end)?;
    let d_s = std::f64::consts::PI - saddle(&g_end)?.delta;
    let d = (x[0] - ramp.drive_phase(t) - d_s).rem_euclid(TAU);
    Ok(RampRelock {
        rate,
        last_slip: ramp.frequency(last),
        slips,
        lock_offset: d.min(TAU - d),
    })
}
