//! Recording sets (docs/formats.md): a folder with `experiment.toml` and one CSV file
//! (`t,alpha,beta`) per run. The reader checks everything and reports a [`Error::Recording`] that
//! names the file, the line and what is wrong; angles are unwrapped on reading.

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};
use std::f64::consts::{PI, TAU};
use std::path::{Component, Path, PathBuf};

/// The `[gear]` table: the set-up as measured (nominal values and tolerances).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GearSetup {
    /// Input dipole moment, A m².
    pub m1: f64,
    /// Output dipole moment, A m².
    pub m2: f64,
    /// Centre distance, m.
    pub r: f64,
    /// Input shaft angle to the centre line, deg.
    pub theta_deg: f64,
    /// Output shaft angle, deg.
    pub phi_deg: f64,
    /// Output moment of inertia, kg m² (fitted when absent).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inertia: Option<f64>,
    /// Starting value of ζ, s⁻¹.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub zeta: Option<f64>,
    /// Starting value of η, s⁻².
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub eta: Option<f64>,
    /// Output shaft mass, kg.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shaft_mass: Option<f64>,
    /// Bore of the output bearings, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bearing_bore: Option<f64>,
    /// Camera noise on β, deg, if known.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub beta_noise_deg: Option<f64>,
    /// Tolerance of Θ, deg (default 3).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub theta_tol_deg: Option<f64>,
    /// Tolerance of Φ, deg (default 3).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub phi_tol_deg: Option<f64>,
    /// Tolerance of the moments, A m² (default 0.11).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub m_tol: Option<f64>,
    /// Tolerance of r, m (default 0.5 mm).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub r_tol: Option<f64>,
    /// Tolerance of the inertia, kg m².
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inertia_tol: Option<f64>,
}

impl GearSetup {
    /// The paper's set-up at Θ = Φ = 31°.
    pub fn paper() -> Self {
        Self {
            m1: 3.51,
            m2: 3.51,
            r: 0.040,
            theta_deg: 31.0,
            phi_deg: 31.0,
            inertia: Some(6.45e-5),
            zeta: Some(1.1),
            eta: Some(23.1),
            shaft_mass: Some(0.32),
            bearing_bore: Some(0.030),
            beta_noise_deg: None,
            theta_tol_deg: None,
            phi_tol_deg: None,
            m_tol: None,
            r_tol: None,
            inertia_tol: None,
        }
    }
    /// c = μ0 m1 m2 / (4π r³), N m.
    pub fn coupling(&self) -> f64 {
        crate::model::gear::MU0_OVER_4PI * self.m1 * self.m2 / self.r.powi(3)
    }
    /// Nominal shaft orientation index Δ = cos Θ cos Φ − 2 sin Θ sin Φ.
    pub fn delta(&self) -> f64 {
        crate::model::gear::shaft_index(self.theta_deg.to_radians(), self.phi_deg.to_radians())
    }
    /// Relative 1σ uncertainty of c from the tolerances of m1, m2 and r (paper defaults).
    pub fn coupling_rel_tol(&self) -> f64 {
        let mt = self.m_tol.unwrap_or(0.11);
        let rt = self.r_tol.unwrap_or(0.5e-3);
        ((mt / self.m1).powi(2) + (mt / self.m2).powi(2) + (3.0 * rt / self.r).powi(2)).sqrt()
    }
    /// 1σ uncertainty of the nominal Δ from the shaft-angle tolerances (paper default 3°).
    pub fn delta_tol(&self) -> f64 {
        let (t, p) = (self.theta_deg.to_radians(), self.phi_deg.to_radians());
        let tt = self.theta_tol_deg.unwrap_or(3.0).to_radians();
        let pt = self.phi_tol_deg.unwrap_or(3.0).to_radians();
        let d_t = -t.sin() * p.cos() - 2.0 * t.cos() * p.sin();
        let d_p = -t.cos() * p.sin() - 2.0 * t.sin() * p.cos();
        ((d_t * tt).powi(2) + (d_p * pt).powi(2)).sqrt()
    }
}

/// What was done in a run.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum RunKind {
    /// Input held at α0 (deg in the file, rad here), output released and left to ring down.
    Ringdown {
        /// Locked input angle, rad.
        alpha0: f64,
    },
    /// Input turned at a constant frequency.
    Driven {
        /// Drive frequency, Hz.
        f_hz: f64,
    },
}

/// One recorded run: samples with unwrapped angles.
#[derive(Debug, Clone, PartialEq)]
pub struct Run {
    /// What was done.
    pub kind: RunKind,
    /// The CSV file name (relative to the set folder).
    pub file: String,
    /// Times, s (strictly increasing).
    pub t: Vec<f64>,
    /// Input angle α, rad (unwrapped).
    pub alpha: Vec<f64>,
    /// Output angle β, rad (unwrapped).
    pub beta: Vec<f64>,
}

impl Run {
    /// Input angular velocity α̇ (0 for ring-downs).
    pub fn alpha_rate(&self) -> f64 {
        match self.kind {
            RunKind::Ringdown { .. } => 0.0,
            RunKind::Driven { f_hz } => TAU * f_hz,
        }
    }
    /// True for a ring-down.
    pub fn is_ringdown(&self) -> bool {
        matches!(self.kind, RunKind::Ringdown { .. })
    }
}

/// A recording set: the set-up and its runs.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordingSet {
    /// The folder it was read from (or is to be written to).
    pub dir: PathBuf,
    /// The set-up.
    pub gear: GearSetup,
    /// The runs, in file order.
    pub runs: Vec<Run>,
}

#[derive(Debug, Deserialize)]
struct RawExperiment {
    gear: Option<toml::Value>,
    #[serde(default)]
    run: Vec<toml::Value>,
}

fn rec_err(file: &str, line: Option<usize>, what: impl Into<String>) -> Error {
    Error::Recording {
        file: file.to_string(),
        line,
        what: what.into(),
    }
}

pub(crate) fn line_of_offset(text: &str, offset: usize) -> usize {
    text[..offset.min(text.len())]
        .bytes()
        .filter(|&b| b == b'\n')
        .count()
        + 1
}

/// 1-based line of the `k`-th `[[run]]` header (for messages about that run).
fn run_line(text: &str, k: usize) -> Option<usize> {
    let mut n = 0;
    for (i, l) in text.lines().enumerate() {
        if l.trim_start().starts_with("[[run]]") {
            if n == k {
                return Some(i + 1);
            }
            n += 1;
        }
    }
    None
}

fn gear_line(text: &str) -> Option<usize> {
    text.lines()
        .position(|l| l.trim_start().starts_with("[gear]"))
        .map(|i| i + 1)
}

/// A run as declared in experiment.toml (before its CSV is read).
#[derive(Debug, Clone, PartialEq)]
pub struct RunSpec {
    /// What was done.
    pub kind: RunKind,
    /// CSV file name.
    pub file: String,
    /// Line of its `[[run]]` header.
    pub line: Option<usize>,
}

/// Parses the text of an experiment.toml (`file` names it in errors).
pub fn parse_experiment(text: &str, file: &str) -> Result<(GearSetup, Vec<RunSpec>)> {
    let raw: RawExperiment = toml::from_str(text).map_err(|e| {
        let line = e.span().map(|s| line_of_offset(text, s.start));
        rec_err(file, line, format!("invalid TOML: {}", e.message()))
    })?;
    let gl = gear_line(text);
    let gear_v = raw
        .gear
        .ok_or_else(|| rec_err(file, None, "missing [gear] table"))?;
    let gear: GearSetup = gear_v
        .try_into()
        .map_err(|e: toml::de::Error| rec_err(file, gl, format!("[gear]: {}", e.message())))?;
    for (name, v) in [
        ("m1", gear.m1),
        ("m2", gear.m2),
        ("r", gear.r),
        ("theta_deg", gear.theta_deg),
        ("phi_deg", gear.phi_deg),
    ] {
        if !v.is_finite() {
            return Err(rec_err(
                file,
                gl,
                format!("[gear]: {name} = {v} is not finite"),
            ));
        }
    }
    for (name, v) in [("theta_deg", gear.theta_deg), ("phi_deg", gear.phi_deg)] {
        if v.abs() > 360.0 {
            return Err(rec_err(
                file,
                gl,
                format!(
                    "[gear]: {name} = {} must be an angle in [-360, 360] degrees",
                    crate::error::show(v)
                ),
            ));
        }
    }
    for (name, v) in [("m1", gear.m1), ("m2", gear.m2), ("r", gear.r)] {
        if v <= 0.0 {
            return Err(rec_err(
                file,
                gl,
                format!("[gear]: {name} = {v} must be > 0"),
            ));
        }
    }
    for (name, v) in [
        ("inertia", gear.inertia),
        ("zeta", gear.zeta),
        ("eta", gear.eta),
        ("shaft_mass", gear.shaft_mass),
        ("bearing_bore", gear.bearing_bore),
        ("beta_noise_deg", gear.beta_noise_deg),
        ("theta_tol_deg", gear.theta_tol_deg),
        ("phi_tol_deg", gear.phi_tol_deg),
        ("m_tol", gear.m_tol),
        ("r_tol", gear.r_tol),
        ("inertia_tol", gear.inertia_tol),
    ] {
        if let Some(v) = v {
            if !v.is_finite() || v < 0.0 || (name == "inertia" && v == 0.0) {
                return Err(rec_err(
                    file,
                    gl,
                    format!("[gear]: {name} = {v} must be finite and non-negative (inertia > 0)"),
                ));
            }
        }
    }
    if raw.run.is_empty() {
        return Err(rec_err(file, None, "no [[run]] declared"));
    }
    let mut specs = Vec::new();
    for (k, v) in raw.run.iter().enumerate() {
        let line = run_line(text, k);
        let tbl = v
            .as_table()
            .ok_or_else(|| rec_err(file, line, "[[run]] is not a table"))?;
        let kind_s = tbl
            .get("kind")
            .ok_or_else(|| rec_err(file, line, "run without `kind`"))?
            .as_str()
            .ok_or_else(|| rec_err(file, line, "`kind` must be a string"))?;
        let num = |key: &str| -> Result<f64> {
            let x = tbl
                .get(key)
                .ok_or_else(|| rec_err(file, line, format!("{kind_s} run without `{key}`")))?;
            let x = x
                .as_float()
                .or_else(|| x.as_integer().map(|i| i as f64))
                .ok_or_else(|| rec_err(file, line, format!("`{key}` must be a number")))?;
            if !x.is_finite() {
                return Err(rec_err(file, line, format!("`{key}` = {x} is not finite")));
            }
            Ok(x)
        };
        let kind = match kind_s {
            "ringdown" => RunKind::Ringdown {
                alpha0: num("alpha0_deg")?.to_radians(),
            },
            "driven" => {
                let f = num("f_hz")?;
                if f <= 0.0 {
                    return Err(rec_err(file, line, format!("`f_hz` = {f} must be > 0")));
                }
                RunKind::Driven { f_hz: f }
            }
            other => {
                return Err(rec_err(
                    file,
                    line,
                    format!("unknown kind `{other}` (expected `ringdown` or `driven`)"),
                ))
            }
        };
        let f = tbl
            .get("file")
            .ok_or_else(|| rec_err(file, line, "run without `file`"))?
            .as_str()
            .ok_or_else(|| rec_err(file, line, "`file` must be a string"))?;
        if f.is_empty() {
            return Err(rec_err(file, line, "`file` is empty"));
        }
        let inside = Path::new(f)
            .components()
            .all(|c| matches!(c, Component::Normal(_) | Component::CurDir));
        if !inside {
            return Err(rec_err(
                file,
                line,
                format!("`file` = `{f}` must be a relative path inside the set's folder"),
            ));
        }
        specs.push(RunSpec {
            kind,
            file: f.to_string(),
            line,
        });
    }
    Ok((gear, specs))
}

/// Parsed CSV columns (angles as in the file, not yet unwrapped).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Columns {
    /// Times.
    pub t: Vec<f64>,
    /// α.
    pub alpha: Vec<f64>,
    /// β.
    pub beta: Vec<f64>,
}

/// Parses the text of a run's CSV (`file` names it in errors): header with columns `t`, `alpha`,
/// `beta` (any order, extra columns ignored), `#` comments, finite values, strictly increasing t.
pub fn parse_csv(text: &str, file: &str) -> Result<Columns> {
    let mut idx: Option<[usize; 3]> = None;
    let mut ncols = 0;
    let mut out = Columns::default();
    for (i, raw) in text.lines().enumerate() {
        let ln = i + 1;
        let l = raw.trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = l.split(',').map(|s| s.trim()).collect();
        match idx {
            None => {
                let find = |name: &str| -> Result<usize> {
                    fields
                        .iter()
                        .position(|f| f.eq_ignore_ascii_case(name))
                        .ok_or_else(|| {
                            rec_err(
                                file,
                                Some(ln),
                                format!("missing column `{name}` in header `{l}`"),
                            )
                        })
                };
                idx = Some([find("t")?, find("alpha")?, find("beta")?]);
                ncols = fields.len();
            }
            Some(ix) => {
                if fields.len() < ncols {
                    return Err(rec_err(
                        file,
                        Some(ln),
                        format!("{} fields, the header has {ncols}", fields.len()),
                    ));
                }
                let mut v = [0.0; 3];
                for (k, name) in ["t", "alpha", "beta"].iter().enumerate() {
                    let s = fields[ix[k]];
                    let x: f64 = s.parse().map_err(|_| {
                        rec_err(
                            file,
                            Some(ln),
                            format!("column `{name}`: `{s}` is not a number"),
                        )
                    })?;
                    if !x.is_finite() {
                        return Err(rec_err(
                            file,
                            Some(ln),
                            format!("column `{name}`: {s} is not finite"),
                        ));
                    }
                    v[k] = x;
                }
                if let Some(&tp) = out.t.last() {
                    if v[0] <= tp {
                        return Err(rec_err(
                            file,
                            Some(ln),
                            format!("time not increasing: t = {} after t = {tp}", v[0]),
                        ));
                    }
                }
                out.t.push(v[0]);
                out.alpha.push(v[1]);
                out.beta.push(v[2]);
            }
        }
    }
    if idx.is_none() {
        return Err(rec_err(file, None, "empty file: no header `t,alpha,beta`"));
    }
    if out.t.is_empty() {
        return Err(rec_err(file, None, "run without samples"));
    }
    Ok(out)
}

/// Unwraps an angle sequence: each step is taken modulo 2π into (−π, π].
pub fn unwrap(x: &[f64]) -> Vec<f64> {
    let mut out = Vec::with_capacity(x.len());
    let mut acc = 0.0;
    for (i, &v) in x.iter().enumerate() {
        if i == 0 {
            acc = v;
        } else {
            let mut d = (v - x[i - 1]) % TAU;
            if d > PI {
                d -= TAU;
            } else if d <= -PI {
                d += TAU;
            }
            acc += d;
        }
        out.push(acc);
    }
    out
}

/// Reads a recording set from its folder.
pub fn read_set(dir: impl AsRef<Path>) -> Result<RecordingSet> {
    let dir = dir.as_ref();
    let exp = dir.join("experiment.toml");
    let exp_name = exp.display().to_string();
    let text = std::fs::read_to_string(&exp)
        .map_err(|e| rec_err(&exp_name, None, format!("cannot read: {e}")))?;
    let (gear, specs) = parse_experiment(&text, &exp_name)?;
    let mut runs = Vec::new();
    for s in specs {
        let p = dir.join(&s.file);
        let pn = p.display().to_string();
        if p.exists() && !p.is_file() {
            return Err(rec_err(
                &exp_name,
                s.line,
                format!("run file `{}` is not a regular file", s.file),
            ));
        }
        let ct = std::fs::read_to_string(&p).map_err(|e| {
            rec_err(
                &exp_name,
                s.line,
                format!("run file `{}`: missing or unreadable ({e})", s.file),
            )
        })?;
        let c = parse_csv(&ct, &pn)?;
        runs.push(Run {
            kind: s.kind,
            file: s.file,
            t: c.t,
            alpha: unwrap(&c.alpha),
            beta: unwrap(&c.beta),
        });
    }
    Ok(RecordingSet {
        dir: dir.to_path_buf(),
        gear,
        runs,
    })
}

/// Writes a recording set into `dir` (experiment.toml and one CSV per run), each file atomically.
/// With `wrap`, angles are written wrapped to (−π, π] (the reader must unwrap them).
pub fn write_set(set: &RecordingSet, dir: impl AsRef<Path>, wrap: bool) -> Result<()> {
    let dir = dir.as_ref();
    let mut toml_s = String::from("# recording set written by gearbif\n[gear]\n");
    let gear_s = toml::to_string(&set.gear).map_err(|e| Error::format("TOML", "gear", e))?;
    toml_s.push_str(&gear_s);
    for r in &set.runs {
        toml_s.push_str("\n[[run]]\n");
        match r.kind {
            RunKind::Ringdown { alpha0 } => {
                toml_s.push_str(&format!(
                    "kind = \"ringdown\"\nalpha0_deg = {:?}\n",
                    alpha0.to_degrees()
                ));
            }
            RunKind::Driven { f_hz } => {
                toml_s.push_str(&format!("kind = \"driven\"\nf_hz = {f_hz:?}\n"));
            }
        }
        toml_s.push_str(&format!("file = \"{}\"\n", r.file));
        let mut c = String::from("t,alpha,beta\n");
        let w = |x: f64| {
            if wrap {
                let y = x.rem_euclid(TAU);
                if y > PI {
                    y - TAU
                } else {
                    y
                }
            } else {
                x
            }
        };
        for i in 0..r.t.len() {
            c.push_str(&format!(
                "{:.6},{:.6},{:.6}\n",
                r.t[i],
                w(r.alpha[i]),
                w(r.beta[i])
            ));
        }
        crate::io::write_atomic(dir.join(&r.file), c.as_bytes())?;
    }
    crate::io::write_atomic(dir.join("experiment.toml"), toml_s.as_bytes())
}
