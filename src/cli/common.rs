//! Arguments and output helpers shared by the commands.

use crate::error::{Error, Result};
use crate::model::{Convention, GearParams};
use clap::Args;
use serde::Deserialize;
use std::path::PathBuf;

/// Gear parameters: the paper's gear by default, overridden by a TOML file, then by flags.
///
/// The TOML file uses the `[gear]` table of a recording set's `experiment.toml`
/// (keys m1, m2, r, inertia, theta_deg, phi_deg, zeta, eta; unknown keys are errors).
#[derive(Debug, Clone, Args, Default)]
pub struct GearArgs {
    /// TOML file with a [gear] table (m1, m2, r, inertia, theta_deg, phi_deg, zeta, eta).
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// Input dipole moment m1 [A m²] (paper: 3.51).
    #[arg(long, allow_hyphen_values = true)]
    pub m1: Option<f64>,
    /// Output dipole moment m2 [A m²] (paper: 3.51).
    #[arg(long, allow_hyphen_values = true)]
    pub m2: Option<f64>,
    /// Centre distance r [m] (paper: 0.040).
    #[arg(long, allow_hyphen_values = true)]
    pub r: Option<f64>,
    /// Output moment of inertia I [kg m²] (paper: 6.45e-5).
    #[arg(long, allow_hyphen_values = true)]
    pub inertia: Option<f64>,
    /// Input shaft angle Θ [deg] (paper figures: 0 to 54.74; default 0).
    #[arg(long, allow_hyphen_values = true)]
    pub theta_deg: Option<f64>,
    /// Output shaft angle Φ [deg] (default: equal to Θ, parallel shafts).
    #[arg(long, allow_hyphen_values = true)]
    pub phi_deg: Option<f64>,
    /// Viscous damping ζ [1/s] (paper: 1.1).
    #[arg(long, allow_hyphen_values = true)]
    pub zeta: Option<f64>,
    /// Dry friction η [1/s²] (paper: 23.1).
    #[arg(long, allow_hyphen_values = true)]
    pub eta: Option<f64>,
    /// Sign convention of outputs: physical (default) or paper (β shifted by 180°, model.md).
    #[arg(long, value_enum, default_value_t = ConventionArg::Physical)]
    pub convention: ConventionArg,
}

/// `--convention` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum ConventionArg {
    /// τ = −∂U/∂β (the physical sign; default).
    #[default]
    Physical,
    /// The paper's printed eq. `modeldyn` (β + 180°).
    Paper,
}

impl From<ConventionArg> for Convention {
    fn from(c: ConventionArg) -> Self {
        match c {
            ConventionArg::Physical => Convention::Physical,
            ConventionArg::Paper => Convention::Paper,
        }
    }
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct GearTable {
    m1: Option<f64>,
    m2: Option<f64>,
    r: Option<f64>,
    inertia: Option<f64>,
    theta_deg: Option<f64>,
    phi_deg: Option<f64>,
    zeta: Option<f64>,
    eta: Option<f64>,
    // accepted and ignored here (recording-set metadata)
    shaft_mass: Option<f64>,
    bearing_bore: Option<f64>,
    beta_noise_deg: Option<f64>,
    theta_tol_deg: Option<f64>,
    phi_tol_deg: Option<f64>,
    m_tol: Option<f64>,
    r_tol: Option<f64>,
    inertia_tol: Option<f64>,
}

#[derive(Debug, Deserialize)]
struct ConfigFile {
    gear: Option<GearTable>,
}

impl GearArgs {
    /// Resolves the parameters (defaults ← TOML ← flags) and validates them.
    pub fn params(&self) -> Result<GearParams> {
        let mut p = GearParams::paper();
        let mut theta_deg = 0.0;
        let mut phi_deg: Option<f64> = None;
        if let Some(path) = &self.config {
            let text = std::fs::read_to_string(path)
                .map_err(|e| Error::Io(format!("cannot read {}: {e}", path.display())))?;
            let cfg: ConfigFile =
                toml::from_str(&text).map_err(|e| Error::Io(format!("{}: {e}", path.display())))?;
            if let Some(g) = cfg.gear {
                let _ = (
                    g.shaft_mass,
                    g.bearing_bore,
                    g.beta_noise_deg,
                    g.theta_tol_deg,
                    g.phi_tol_deg,
                    g.m_tol,
                    g.r_tol,
                    g.inertia_tol,
                );
                p.m1 = g.m1.unwrap_or(p.m1);
                p.m2 = g.m2.unwrap_or(p.m2);
                p.r = g.r.unwrap_or(p.r);
                p.inertia = g.inertia.unwrap_or(p.inertia);
                p.zeta = g.zeta.unwrap_or(p.zeta);
                p.eta = g.eta.unwrap_or(p.eta);
                theta_deg = g.theta_deg.unwrap_or(theta_deg);
                phi_deg = g.phi_deg.or(phi_deg);
            }
        }
        p.m1 = self.m1.unwrap_or(p.m1);
        p.m2 = self.m2.unwrap_or(p.m2);
        p.r = self.r.unwrap_or(p.r);
        p.inertia = self.inertia.unwrap_or(p.inertia);
        p.zeta = self.zeta.unwrap_or(p.zeta);
        p.eta = self.eta.unwrap_or(p.eta);
        theta_deg = self.theta_deg.unwrap_or(theta_deg);
        phi_deg = self.phi_deg.or(phi_deg);
        p.theta = theta_deg.to_radians();
        p.phi = phi_deg.unwrap_or(theta_deg).to_radians();
        p.validate()?;
        Ok(p)
    }

    /// The chosen output convention.
    pub fn convention(&self) -> Convention {
        self.convention.into()
    }
}

/// Prints a result either as pretty JSON (`--json`) or as text.
pub struct Output {
    /// Machine-readable output requested.
    pub json: bool,
}

impl Output {
    /// Prints `value` tagged with its schema id (`{"schema": schema, …}`, docs/formats.md) as
    /// JSON, or `text()` otherwise.
    pub fn emit_tagged<T: serde::Serialize>(
        &self,
        schema: &'static str,
        value: &T,
        text: impl FnOnce() -> String,
    ) -> Result<()> {
        self.emit(&crate::io::with_schema(schema, value), text)
    }

    /// Prints `value` as JSON, or `text()` otherwise.
    pub fn emit<T: serde::Serialize>(
        &self,
        value: &T,
        text: impl FnOnce() -> String,
    ) -> Result<()> {
        if self.json {
            let s = serde_json::to_string_pretty(value).map_err(|e| Error::Io(e.to_string()))?;
            println!("{s}");
        } else {
            print!("{}", text());
        }
        Ok(())
    }
}

/// Checks a frequency given on the command line.
pub fn check_frequency(f: f64) -> Result<f64> {
    crate::error::positive("f", f)
}
