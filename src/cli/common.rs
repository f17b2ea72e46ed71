//! Arguments and output helpers shared by the commands.

use crate::error::{Error, Result};
use crate::model::{Convention, GearParams};
use clap::Args;
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// Gear parameters: the paper's gear by default, overridden by a TOML file, then by flags.
///
/// The TOML file uses the `[gear]` table of a recording set's `experiment.toml`
/// (keys m1, m2, r, inertia, theta_deg, phi_deg, zeta, eta; unknown keys are errors).
#[derive(Debug, Clone, Args, Default)]
pub struct GearArgs {
    /// TOML file with a [gear] table (m1, m2, r, inertia, theta_deg, phi_deg, zeta, eta).
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// Input dipole moment m1 [A m²], > 0 (paper: 3.51).
    #[arg(long, allow_hyphen_values = true)]
    pub m1: Option<f64>,
    /// Output dipole moment m2 [A m²], > 0 (paper: 3.51).
    #[arg(long, allow_hyphen_values = true)]
    pub m2: Option<f64>,
    /// Centre distance r [m], > 0 (paper: 0.040).
    #[arg(long, allow_hyphen_values = true)]
    pub r: Option<f64>,
    /// Output moment of inertia I [kg m²], > 0 (paper: 6.45e-5); with m1, m2, r it sets the
    /// coupling g = μ0 m1 m2 / (4π r³ I), which must be in (0, 1e8] 1/s².
    #[arg(long, allow_hyphen_values = true)]
    pub inertia: Option<f64>,
    /// Input shaft angle Θ [deg], in [-360, 360] (paper figures: 0 to 54.74; default 0).
    #[arg(long, allow_hyphen_values = true)]
    pub theta_deg: Option<f64>,
    /// Output shaft angle Φ [deg], in [-360, 360] (default: equal to Θ, parallel shafts).
    #[arg(long, allow_hyphen_values = true)]
    pub phi_deg: Option<f64>,
    /// Viscous damping ζ [1/s], in [0, 1e4] (paper: 1.1).
    #[arg(long, allow_hyphen_values = true)]
    pub zeta: Option<f64>,
    /// Dry friction η [1/s²], in [0, 1e8] (paper: 23.1).
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

/// The `[gear]` table of a `--config` file, as written (absent keys are `None`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GearConfig {
    /// m1 [A m²].
    pub m1: Option<f64>,
    /// m2 [A m²].
    pub m2: Option<f64>,
    /// r [m].
    pub r: Option<f64>,
    /// I [kg m²].
    pub inertia: Option<f64>,
    /// Θ [deg].
    pub theta_deg: Option<f64>,
    /// Φ [deg].
    pub phi_deg: Option<f64>,
    /// ζ [1/s].
    pub zeta: Option<f64>,
    /// η [1/s²].
    pub eta: Option<f64>,
    // accepted and ignored here (recording-set metadata)
    #[serde(default, rename = "shaft_mass")]
    _shaft_mass: Option<f64>,
    #[serde(default, rename = "bearing_bore")]
    _bearing_bore: Option<f64>,
    #[serde(default, rename = "beta_noise_deg")]
    _beta_noise_deg: Option<f64>,
    #[serde(default, rename = "theta_tol_deg")]
    _theta_tol_deg: Option<f64>,
    #[serde(default, rename = "phi_tol_deg")]
    _phi_tol_deg: Option<f64>,
    #[serde(default, rename = "m_tol")]
    _m_tol: Option<f64>,
    #[serde(default, rename = "r_tol")]
    _r_tol: Option<f64>,
    #[serde(default, rename = "inertia_tol")]
    _inertia_tol: Option<f64>,
}

#[derive(Debug, Deserialize)]
struct ConfigFile {
    gear: Option<GearConfig>,
}

/// A key of the `[gear]` table, its value, its admissible set and that set in words.
type KeyCheck = (&'static str, Option<f64>, fn(f64) -> bool, &'static str);

/// Parses the text of a `--config` TOML file (`file` names it in errors): its `[gear]` table, each
/// value checked (m1, m2, r, inertia > 0; ζ in [0, 1e4] 1/s, η in [0, 1e8] 1/s²; Θ, Φ within
/// ±360°). Errors are
/// [`Error::Recording`] with the file and, where one line is at fault, its number.
pub fn parse_config(text: &str, file: &str) -> Result<GearConfig> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let err = |line: Option<usize>, what: String| Error::Recording {
        file: file.to_string(),
        line,
        what,
    };
    let cfg: ConfigFile = toml::from_str(text).map_err(|e| {
        let line = e
            .span()
            .map(|s| crate::io::recordings::line_of_offset(text, s.start));
        err(line, format!("invalid TOML: {}", e.message().trim_end()))
    })?;
    let g = cfg.gear.unwrap_or_default();
    let checks: [KeyCheck; 8] = [
        ("m1", g.m1, |v| v > 0.0, "> 0"),
        ("m2", g.m2, |v| v > 0.0, "> 0"),
        ("r", g.r, |v| v > 0.0, "> 0"),
        ("inertia", g.inertia, |v| v > 0.0, "> 0"),
        (
            "zeta",
            g.zeta,
            |v| (0.0..=limits::ZETA_MAX).contains(&v),
            "in [0, 1e4] 1/s",
        ),
        (
            "eta",
            g.eta,
            |v| (0.0..=limits::ETA_MAX).contains(&v),
            "in [0, 1e8] 1/s²",
        ),
        (
            "theta_deg",
            g.theta_deg,
            |v| v.abs() <= limits::ANGLE_DEG,
            "in [-360, 360]",
        ),
        (
            "phi_deg",
            g.phi_deg,
            |v| v.abs() <= limits::ANGLE_DEG,
            "in [-360, 360]",
        ),
    ];
    for (key, value, ok, range) in checks {
        if let Some(v) = value {
            if !(v.is_finite() && ok(v)) {
                return Err(err(
                    key_line(text, key),
                    format!(
                        "[gear]: {key} = {} must be finite and {range}",
                        crate::error::show(v)
                    ),
                ));
            }
        }
    }
    Ok(g)
}

/// 1-based line of the first `key = …` in a TOML text.
fn key_line(text: &str, key: &str) -> Option<usize> {
    text.lines()
        .position(|l| {
            l.trim_start()
                .strip_prefix(key)
                .is_some_and(|r| r.trim_start().starts_with('='))
        })
        .map(|i| i + 1)
}

impl GearArgs {
    /// Resolves the parameters (defaults ← TOML ← flags) and validates them: the checks of
    /// [`GearParams::validate`], angles within ±360°, and a finite coupling g = c/I.
    pub fn params(&self) -> Result<GearParams> {
        let cfg = match &self.config {
            Some(path) => {
                let name = path.display().to_string();
                let text = std::fs::read_to_string(path).map_err(|e| Error::Recording {
                    file: name.clone(),
                    line: None,
                    what: format!("cannot read: {e}"),
                })?;
                parse_config(&text, &name)?
            }
            None => GearConfig::default(),
        };
        let mut p = GearParams::paper();
        p.m1 = self.m1.or(cfg.m1).unwrap_or(p.m1);
        p.m2 = self.m2.or(cfg.m2).unwrap_or(p.m2);
        p.r = self.r.or(cfg.r).unwrap_or(p.r);
        p.inertia = self.inertia.or(cfg.inertia).unwrap_or(p.inertia);
        p.zeta = self.zeta.or(cfg.zeta).unwrap_or(p.zeta);
        p.eta = self.eta.or(cfg.eta).unwrap_or(p.eta);
        let theta_deg = angle_deg("theta_deg", self.theta_deg.or(cfg.theta_deg).unwrap_or(0.0))?;
        let phi_deg = angle_deg("phi_deg", self.phi_deg.or(cfg.phi_deg).unwrap_or(theta_deg))?;
        p.theta = theta_deg.to_radians();
        p.phi = phi_deg.to_radians();
        p.validate()?;
        let g = p.g();
        if !(g.is_finite() && g > 0.0 && g <= limits::G_MAX) {
            return Err(Error::InvalidParameter {
                name: "g",
                value: g,
                reason: "the coupling g = μ0 m1 m2 / (4π r³ I) must be finite and in (0, 1e8] \
                         1/s² (set by m1, m2, r and inertia)",
            });
        }
        within(
            "zeta",
            p.zeta,
            0.0,
            limits::ZETA_MAX,
            "must be in [0, 1e4] 1/s",
        )?;
        within(
            "eta",
            p.eta,
            0.0,
            limits::ETA_MAX,
            "must be in [0, 1e8] 1/s²",
        )?;
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
            let s = serde_json::to_string_pretty(value)
                .map_err(|e| Error::format("JSON", "output", e))?;
            println!("{s}");
        } else {
            print!("{}", text());
        }
        Ok(())
    }
}

/// The documented limits of command-line values (docs/errors.md lists them per command).
pub mod limits {
    /// Largest |angle| accepted for shaft angles Θ, Φ and drive/start phases [deg].
    pub const ANGLE_DEG: f64 = 360.0;
    /// Lowest drive frequency [Hz] (a period of 1000 s).
    pub const F_MIN_HZ: f64 = 1e-3;
    /// Highest drive frequency [Hz].
    pub const F_MAX_HZ: f64 = 1e4;
    /// Largest |ω| of a start state [rad/s].
    pub const OMEGA_MAX: f64 = 1e6;
    /// Largest number of drive periods, turns or map iterations of one run.
    pub const TURNS_MAX: usize = 1_000_000;
    /// Largest number of points of a parameter grid (boundary curves).
    pub const GRID_MAX: usize = 100_000;
    /// Smallest relative tolerance.
    pub const TOL_MIN: f64 = 1e-14;
    /// Largest coupling g [1/s²] (a natural frequency of 1e4 rad/s).
    pub const G_MAX: f64 = 1e8;
    /// Largest viscous damping ζ [1/s].
    pub const ZETA_MAX: f64 = 1e4;
    /// Largest dry friction η [1/s²].
    pub const ETA_MAX: f64 = 1e8;
}

/// Checks `value` is finite and in `[lo, hi]`; `reason` states that range for the message.
pub fn within(
    name: &'static str,
    value: f64,
    lo: f64,
    hi: f64,
    reason: &'static str,
) -> Result<f64> {
    crate::error::finite(name, value)?;
    if (lo..=hi).contains(&value) {
        Ok(value)
    } else {
        Err(Error::InvalidParameter {
            name,
            value,
            reason,
        })
    }
}

/// Checks an angle in degrees: finite and |angle| ≤ 360° ([`limits::ANGLE_DEG`]). Beyond that an
/// angle means nothing more (it is periodic) and large values lose the digits of their sine.
pub fn angle_deg(name: &'static str, value: f64) -> Result<f64> {
    within(
        name,
        value,
        -limits::ANGLE_DEG,
        limits::ANGLE_DEG,
        "must be an angle in [-360, 360] degrees",
    )
}

/// Checks a drive frequency in Hz: finite and in [1e-3, 1e4] ([`limits`]).
pub fn frequency(name: &'static str, value: f64) -> Result<f64> {
    crate::error::positive(name, value)?;
    within(
        name,
        value,
        limits::F_MIN_HZ,
        limits::F_MAX_HZ,
        "must be a frequency in [1e-3, 1e4] Hz",
    )
}

/// Checks a relative tolerance: finite and in [1e-14, 1) ([`limits::TOL_MIN`]).
pub fn tolerance(name: &'static str, value: f64) -> Result<f64> {
    crate::error::relative_tolerance(name, value)?;
    if value < limits::TOL_MIN {
        return Err(Error::InvalidParameter {
            name,
            value,
            reason: "must be in [1e-14, 1): a double cannot resolve a smaller relative step",
        });
    }
    Ok(value)
}

/// Checks a count given by flag `--flag`: `lo ≤ value ≤ hi`.
pub fn count(flag: &str, value: usize, lo: usize, hi: usize) -> Result<usize> {
    if (lo..=hi).contains(&value) {
        Ok(value)
    } else {
        Err(Error::option(
            format!("--{flag}"),
            format!("{value} must be in {lo}..={hi}"),
        ))
    }
}

/// Checks a start state (β [deg if `beta_in_deg`, else rad], ω [rad/s]): β finite and within
/// ±360° (±2π rad), ω finite and |ω| ≤ 1e6 rad/s.
pub fn start_state(flag: &str, beta: f64, omega: f64, beta_in_deg: bool) -> Result<()> {
    let lim = if beta_in_deg {
        limits::ANGLE_DEG
    } else {
        limits::ANGLE_DEG.to_radians()
    };
    let unit = if beta_in_deg { "deg" } else { "rad" };
    if !beta.is_finite() || beta.abs() > lim {
        return Err(Error::option(
            flag,
            format!(
                "beta = {} must be finite with |beta| <= {} {unit}",
                crate::error::show(beta),
                crate::error::show(lim)
            ),
        ));
    }
    if !omega.is_finite() || omega.abs() > limits::OMEGA_MAX {
        return Err(Error::option(
            flag,
            format!(
                "omega = {} must be finite with |omega| <= 1e6 rad/s",
                crate::error::show(omega)
            ),
        ));
    }
    Ok(())
}

/// Checks that `path` can become an output folder before any work is done: it is not an existing
/// file, and its nearest existing ancestor is a folder.
pub fn output_dir(flag: &str, path: &Path) -> Result<()> {
    if path.exists() && !path.is_dir() {
        return Err(Error::option(
            format!("{flag} {}", path.display()),
            "exists and is not a folder",
        ));
    }
    writable_parent(flag, path)
}

/// Checks that `path` can become an output file before any work is done: not an existing folder,
/// its nearest existing ancestor a folder, and (with `figure`) an `.svg` or `.png` extension.
pub fn output_file(flag: &str, path: &Path, figure: bool) -> Result<()> {
    if path.is_dir() {
        return Err(Error::option(
            format!("{flag} {}", path.display()),
            "is a folder, expected a file",
        ));
    }
    if figure {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        if !matches!(ext.as_deref(), Some("svg" | "png")) {
            return Err(Error::option(
                format!("{flag} {}", path.display()),
                "a figure must end in .svg or .png",
            ));
        }
    }
    match path.parent().filter(|p| !p.as_os_str().is_empty()) {
        Some(parent) => writable_parent(flag, parent),
        None => Ok(()),
    }
}

fn writable_parent(flag: &str, path: &Path) -> Result<()> {
    let mut p = Some(path);
    while let Some(q) = p {
        if q.as_os_str().is_empty() {
            return Ok(());
        }
        if q.exists() {
            if q.is_dir() {
                if std::fs::metadata(q).is_ok_and(|m| m.permissions().readonly()) {
                    return Err(Error::option(
                        format!("{flag} {}", path.display()),
                        format!("folder {} is read-only", q.display()),
                    ));
                }
                return Ok(());
            }
            return Err(Error::option(
                format!("{flag} {}", path.display()),
                format!("{} is not a folder", q.display()),
            ));
        }
        p = q.parent();
    }
    Ok(())
}

/// Checks one value of a gear parameter against its domain: f in [1e-3, 1e4] Hz, Θ within ±360°,
/// g, ζ, η ≥ 0, Δ finite (the values of a `--range` or a sweep axis).
pub fn param_value(p: crate::model::GearParam, v: f64) -> Result<f64> {
    use crate::model::GearParam;
    match p {
        GearParam::ThetaDeg => angle_deg("theta_deg", v),
        GearParam::F => frequency("f", v),
        GearParam::G => within("g", v, 0.0, limits::G_MAX, "must be in [0, 1e8] 1/s²"),
        GearParam::Zeta => within("zeta", v, 0.0, limits::ZETA_MAX, "must be in [0, 1e4] 1/s"),
        GearParam::Eta => within("eta", v, 0.0, limits::ETA_MAX, "must be in [0, 1e8] 1/s²"),
        GearParam::Delta => crate::error::finite("delta", v),
    }
}

/// Warns (on stderr) about the keys of `set`/experiment.toml the reader ignores.
pub fn warn_ignored_keys(set: &Path) {
    let exp = set.join("experiment.toml");
    if let Ok(text) = std::fs::read_to_string(&exp) {
        for k in crate::io::recordings::ignored_keys(&text) {
            eprintln!("warning: {}: ignored unknown key {k}", exp.display());
        }
    }
}

/// Checks a frequency given on the command line (see [`frequency`]).
pub fn check_frequency(f: f64) -> Result<f64> {
    frequency("f", f)
}
