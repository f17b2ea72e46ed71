//! `gearbif fit`: parameters of a recording set (ring-downs by simulation, κ(α0) → g, |Δ|, I;
//! base model over all runs by weak-form equation-error regression, then refitted by simulation
//! over short windows).

use crate::identification::diagnose::{diagnose, DiagnoseOptions};
use crate::io::recordings::read_set;
use crate::Result;
use std::path::PathBuf;

/// Arguments of `gearbif fit`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The recording set (folder with experiment.toml).
    set: PathBuf,
    /// Print JSON.
    #[arg(long)]
    json: bool,
    /// Relative tolerance of the simulations, in (0, 1): the window simulations of the refits and
    /// predictions and the stick windows; the ring-down fits are integrated ten times tighter.
    #[arg(long, default_value_t = DiagnoseOptions::default().tol)]
    tol: f64,
}

/// Runs `gearbif fit`.
pub fn run(a: Args) -> Result<()> {
    let opts = DiagnoseOptions {
        base_only: true,
        heldout_predictions: false,
        tol: super::common::tolerance("tol", a.tol)?,
        ..DiagnoseOptions::default()
    };
    let set = read_set(&a.set)?;
    super::common::warn_ignored_keys(&a.set);
    let d = diagnose(
        &set,
        &opts,
        &crate::progress::lines(|s| eprintln!("[fit] {s}")),
    )?;
    let v = serde_json::json!({
        "schema": "gearbif.fit/1",
        "baseline": d.report.baseline,
        "ringdowns": d.ringdowns,
        "kappa_alpha0": d.kappa,
    });
    if a.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&v).map_err(|e| crate::Error::format("JSON", "fit", e))?
        );
        return Ok(());
    }
    println!("ring-downs (eq. model, exact Filippov simulation + Levenberg–Marquardt):");
    println!(
        "  {:>8} {:>16} {:>14} {:>14} {:>9}",
        "alpha0", "kappa [1/s2]", "zeta [1/s]", "eta [1/s2]", "rms[rad]"
    );
    for f in &d.ringdowns {
        println!(
            "  {:>8.1} {:>8.2} ± {:<5.2} {:>6.3} ± {:<5.3} {:>6.2} ± {:<5.2} {:>9.4}",
            f.alpha0_deg, f.kappa, f.kappa_err, f.zeta, f.zeta_err, f.eta, f.eta_err, f.rms_rad
        );
    }
    if let Some(k) = &d.kappa {
        println!(
            "kappa(alpha0): g = {:.2} ± {:.2} 1/s², |Delta| = {:.4} ± {:.4} (nominal {:.4} ± {:.4}), I = {:.4e} ± {:.2e} kg m², chi2/dof = {:.2}",
            k.g, k.g_err, k.delta_abs, k.delta_err, k.delta_nominal, k.delta_nominal_err, k.inertia, k.inertia_err, k.chi2_dof
        );
    }
    let p = &d.report.baseline.params;
    let g = |k: &str| p.get(k).copied().unwrap_or(f64::NAN);
    println!(
        "base model, all runs: weak-form regression (n = {:.0} rows, n_eff = {:.0}), refitted by \
         simulation over {:.0} short windows:",
        g("n_rows"),
        g("n_eff"),
        g("simulation_refit_windows")
    );
    for k in ["g", "delta", "zeta", "eta"] {
        println!(
            "  {k:>8} = {:.6} ± {:.6}   (weak form {:.6} ± {:.6})",
            g(k),
            g(&format!("{k}_err")),
            g(&format!("{k}_weak_form")),
            g(&format!("{k}_weak_form_err"))
        );
    }
    println!(
        "  {:>8} = {:.4e} ± {:.2e}",
        "inertia",
        g("inertia"),
        g("inertia_err")
    );
    println!(
        "  eq.-error chi2/dof = {:.3}; short-horizon rms = {:.4} rad",
        g("eq_chi2_per_dof"),
        d.report.baseline.rms_rad
    );
    Ok(())
}
