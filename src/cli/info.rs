//! `gearbif info`: derived quantities of a gear.

use super::common::{check_frequency, GearArgs, Output};
use crate::model::gear::cogging_free_input_angles;
use crate::model::{Gear, GearParams};
use crate::Result;
use serde::Serialize;

/// Arguments of `gearbif info`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    gear: GearArgs,
    /// Drive frequency f [Hz], in [1e-3, 1e4], at which to report the lock angles (needs Δ = ±1).
    #[arg(long)]
    f: Option<f64>,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Serialize)]
struct Info {
    params: GearParams,
    convention: crate::model::Convention,
    /// c = μ0 m1 m2 / (4π r³), J.
    coupling_j: f64,
    /// g = c/I, 1/s².
    g: f64,
    /// Δ = cos Θ cos Φ − 2 sin Θ sin Φ.
    delta: f64,
    /// Lock-loss frequency f_c = (g − η)/(2πζ), Hz (Δ = ±1 gears).
    f_c_hz: Option<f64>,
    /// Input shaft angles Θ [deg] for which the coupling is cogging-free (Δ = ±1), given Φ.
    cogging_free_theta_deg: Vec<(f64, f64)>,
    /// Largest static torque c·max|τ| over α at the given Φ, N m.
    max_torque_nm: f64,
    lock: Option<LockInfo>,
}

#[derive(Debug, Serialize)]
struct LockInfo {
    f_hz: f64,
    /// Stable lock phase (δ = β − α for Δ = 1, β + α for Δ = −1), degrees.
    stable_phase_deg: f64,
    unstable_phase_deg: f64,
    stable_multipliers: [(f64, f64); 2],
    unstable_multipliers: [(f64, f64); 2],
}

/// Runs `gearbif info`.
pub fn run(a: Args) -> Result<()> {
    let p = a.gear.params()?;
    let conv = a.gear.convention();
    let delta = p.delta();
    // max over α, β of |τ| = max over α of √(sin²α + Δ² cos²α) = max(1, |Δ|)
    let tmax = 1.0f64.max(delta.abs());
    let lock = match a.f {
        Some(f) => {
            check_frequency(f)?;
            let gear = Gear::new(p.g(), delta, p.zeta, p.eta, f)?.with_convention(conv);
            gear.lock_branch().ok().map(|b| LockInfo {
                f_hz: f,
                stable_phase_deg: b.stable.phase.to_degrees(),
                unstable_phase_deg: b.unstable.phase.to_degrees(),
                stable_multipliers: b.stable.multipliers.map(|c| (c.re, c.im)),
                unstable_multipliers: b.unstable.multipliers.map(|c| (c.re, c.im)),
            })
        }
        None => None,
    };
    let info = Info {
        params: p,
        convention: conv,
        coupling_j: p.coupling(),
        g: p.g(),
        delta,
        f_c_hz: p.lock_loss_frequency(),
        cogging_free_theta_deg: cogging_free_input_angles(p.phi)
            .into_iter()
            .map(|(t, d)| (t.to_degrees(), d))
            .collect(),
        max_torque_nm: p.coupling() * tmax,
        lock,
    };
    Output { json: a.json }.emit_tagged("gearbif.info/1", &info, || {
        let mut s = String::new();
        s += &format!(
            "gear: m1 = {} A m², m2 = {} A m², r = {} m, I = {:e} kg m², Θ = {:.3}°, Φ = {:.3}°, ζ = {} 1/s, η = {} 1/s²\n",
            p.m1, p.m2, p.r, p.inertia, p.theta.to_degrees(), p.phi.to_degrees(), p.zeta, p.eta
        );
        s += &format!("c   = {:.6e} J   (μ0 m1 m2 / 4π r³)\n", info.coupling_j);
        s += &format!("g   = {:.4} 1/s²   (c / I)\n", info.g);
        s += &format!("Δ   = {:.6}   (cos Θ cos Φ − 2 sin Θ sin Φ)\n", info.delta);
        match info.f_c_hz {
            Some(fc) => s += &format!("f_c = {fc:.4} Hz   ((g − η)/(2πζ), lock loss at Δ = ±1)\n"),
            None => s += "f_c = none (ζ = 0 or g ≤ η)\n",
        }
        for (t, d) in &info.cogging_free_theta_deg {
            s += &format!("cogging-free: Θ = {t:.3}° gives Δ = {d:+}\n");
        }
        if let Some(l) = &info.lock {
            s += &format!(
                "lock at f = {} Hz: stable phase {:.4}°, unstable {:.4}°\n",
                l.f_hz, l.stable_phase_deg, l.unstable_phase_deg
            );
        } else if a.f.is_some() {
            s += "lock angles: none (needs Δ = ±1 and f < f_c)\n";
        }
        s
    })
}
