//! Recording sets (docs/formats.md): a folder with `experiment.toml` and one CSV file
//! (`t,alpha,beta`) per run. The reader checks everything and reports a [`Error::Recording`] that
//! names the file, the line and what is wrong; angles are unwrapped on reading.

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};
use std::f64::consts::{PI, TAU};
use std::path::{Component, Path, PathBuf};

/// The sizes a recording set may have (docs/errors.md states them): the readers refuse larger
/// inputs before allocating them, the generator refuses to make them.
pub mod limits {
    /// Most samples of one run.
    pub const RUN_SAMPLES_MAX: usize = 1_000_000;
    /// Most samples of a whole set (all runs).
    pub const SET_SAMPLES_MAX: usize = 2_000_000;
    /// Largest run file, bytes (64 MiB).
    pub const RUN_FILE_BYTES_MAX: u64 = 64 << 20;
    /// Most runs of a set.
    pub const RUNS_MAX: usize = 10_000;
}

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

/// Lowest drive frequency of a driven run, Hz (as the command line's `--f`).
const F_HZ_MIN: f64 = 1e-3;
/// Highest drive frequency of a driven run, Hz.
const F_HZ_MAX: f64 = 1e4;

/// 1-based line of `key = …` in the table whose header is on line `table` (up to the next table
/// header); `None` if the key is not found there (e.g. an inline table).
fn key_line(text: &str, table: Option<usize>, key: &str) -> Option<usize> {
    let start = table?;
    text.lines()
        .enumerate()
        .skip(start)
        .take_while(|(_, l)| !l.trim_start().starts_with('['))
        .find(|(_, l)| {
            l.trim_start()
                .strip_prefix(key)
                .is_some_and(|r| r.trim_start().starts_with('='))
        })
        .map(|(i, _)| i + 1)
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
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
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
                key_line(text, gl, name).or(gl),
                format!("[gear]: {name} = {v} is not finite"),
            ));
        }
    }
    for (name, v) in [("theta_deg", gear.theta_deg), ("phi_deg", gear.phi_deg)] {
        if v.abs() > 360.0 {
            return Err(rec_err(
                file,
                key_line(text, gl, name).or(gl),
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
                key_line(text, gl, name).or(gl),
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
                    key_line(text, gl, name).or(gl),
                    format!("[gear]: {name} = {v} must be finite and non-negative (inertia > 0)"),
                ));
            }
        }
    }
    if raw.run.is_empty() {
        return Err(rec_err(file, None, "no [[run]] declared"));
    }
    if raw.run.len() > limits::RUNS_MAX {
        return Err(rec_err(
            file,
            run_line(text, limits::RUNS_MAX),
            format!(
                "{} runs declared: a set has at most {}",
                raw.run.len(),
                limits::RUNS_MAX
            ),
        ));
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
            "ringdown" => {
                let a = num("alpha0_deg")?;
                if a.abs() > 360.0 {
                    return Err(rec_err(
                        file,
                        key_line(text, line, "alpha0_deg").or(line),
                        format!(
                            "`alpha0_deg` = {} must be an angle in [-360, 360] degrees",
                            crate::error::show(a)
                        ),
                    ));
                }
                RunKind::Ringdown {
                    alpha0: a.to_radians(),
                }
            }
            "driven" => {
                let f = num("f_hz")?;
                if !(F_HZ_MIN..=F_HZ_MAX).contains(&f) {
                    return Err(rec_err(
                        file,
                        key_line(text, line, "f_hz").or(line),
                        format!(
                            "`f_hz` = {} must be a drive frequency in [1e-3, 1e4] Hz",
                            crate::error::show(f)
                        ),
                    ));
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

/// The keys of an experiment.toml that the reader does not know and ignores (a misspelt key, e.g.
/// `zetta`), each as "`key` in [table] (line N)"; empty if the text is not TOML.
pub fn ignored_keys(text: &str) -> Vec<String> {
    const GEAR: &[&str] = &[
        "m1",
        "m2",
        "r",
        "theta_deg",
        "phi_deg",
        "inertia",
        "zeta",
        "eta",
        "shaft_mass",
        "bearing_bore",
        "beta_noise_deg",
        "theta_tol_deg",
        "phi_tol_deg",
        "m_tol",
        "r_tol",
        "inertia_tol",
    ];
    const RUN: &[&str] = &["kind", "file", "f_hz", "alpha0_deg"];
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let Ok(v) = text.parse::<toml::Table>() else {
        return Vec::new();
    };
    let mut out = Vec::new();
    let at = |table: Option<usize>, key: &str| {
        key_line(text, table, key)
            .map(|l| format!(" (line {l})"))
            .unwrap_or_default()
    };
    for (k, val) in &v {
        match (k.as_str(), val) {
            ("gear", toml::Value::Table(t)) => {
                for key in t.keys().filter(|key| !GEAR.contains(&key.as_str())) {
                    out.push(format!("`{key}` in [gear]{}", at(gear_line(text), key)));
                }
            }
            ("run", toml::Value::Array(runs)) => {
                for (i, r) in runs.iter().enumerate() {
                    if let toml::Value::Table(t) = r {
                        for key in t.keys().filter(|key| !RUN.contains(&key.as_str())) {
                            out.push(format!(
                                "`{key}` in [[run]] {}{}",
                                i + 1,
                                at(run_line(text, i), key)
                            ));
                        }
                    }
                }
            }
            ("gear" | "run", _) => {}
            (other, _) => out.push(format!("`{other}` at the top level")),
        }
    }
    out
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
    // a UTF-8 byte-order mark (as some spreadsheet programs write) is not part of the header
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
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
                                format!(
                                    "missing column `{name}` in the header (it must name the \
                                     columns t, alpha and beta, comma-separated)"
                                ),
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
                        rec_err(file, Some(ln), format!("column `{name}`: not a number"))
                    })?;
                    if !x.is_finite() {
                        return Err(rec_err(
                            file,
                            Some(ln),
                            format!("column `{name}`: {x} is not finite"),
                        ));
                    }
                    v[k] = x;
                }
                if out.t.len() == limits::RUN_SAMPLES_MAX {
                    return Err(rec_err(
                        file,
                        Some(ln),
                        format!(
                            "more than {} samples: a run has at most that many",
                            limits::RUN_SAMPLES_MAX
                        ),
                    ));
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

/// Reads a text file of at most `max` bytes: a regular file (not a device, FIFO or folder), valid
/// UTF-8 (an invalid byte is reported with its line). Errors name `name` (and `at`, the line of
/// the declaration in `decl`, when the file is declared there); the file's content is never
/// quoted.
fn read_text(
    path: &Path,
    name: &str,
    max: u64,
    decl: Option<(&str, Option<usize>)>,
) -> Result<String> {
    use std::io::Read;
    let fail = |what: String| match decl {
        Some((exp, line)) => rec_err(exp, line, what),
        None => rec_err(name, None, what),
    };
    let meta = std::fs::metadata(path).map_err(|e| fail(format!("cannot read `{name}`: {e}")))?;
    if !meta.is_file() {
        return Err(fail(format!("`{name}` is not a regular file")));
    }
    if meta.len() > max {
        return Err(fail(format!(
            "`{name}` has {} bytes: at most {max} are read",
            meta.len()
        )));
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    std::fs::File::open(path)
        .and_then(|f| f.take(max + 1).read_to_end(&mut bytes))
        .map_err(|e| fail(format!("cannot read `{name}`: {e}")))?;
    if bytes.len() as u64 > max {
        return Err(fail(format!("`{name}` has more than {max} bytes")));
    }
    String::from_utf8(bytes).map_err(|e| {
        let ok = e.utf8_error().valid_up_to();
        let bytes = e.as_bytes();
        let line = bytes[..ok].iter().filter(|&&b| b == b'\n').count() + 1;
        rec_err(
            name,
            Some(line),
            format!(
                "byte 0x{:02X} is not UTF-8 text (save the file as UTF-8; a Latin-1 or \
                 Windows-1252 character?)",
                bytes[ok]
            ),
        )
    })
}

/// Least-squares slope of `y` over `t` (`None` for fewer than two distinct times).
fn slope(t: &[f64], y: &[f64]) -> Option<f64> {
    let n = t.len() as f64;
    let (tm, ym) = (t.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let (mut sty, mut stt) = (0.0, 0.0);
    for (&ti, &yi) in t.iter().zip(y) {
        sty += (ti - tm) * (yi - ym);
        stt += (ti - tm) * (ti - tm);
    }
    (stt > 0.0 && (sty / stt).is_finite()).then(|| sty / stt)
}

/// Refuses a run whose angles look like degrees (the CSV's are in radians), and a driven run whose
/// α column advances at another rate than its `f_hz` (more than 5 % apart; a constant α column is
/// not checked). `cols` as read (not unwrapped); errors name the CSV `file` or experiment.toml.
fn check_units_and_drive(
    cols: &Columns,
    spec: &RunSpec,
    file: &str,
    exp: &str,
    text: &str,
) -> Result<()> {
    let degrees = |why: String| {
        Err(rec_err(
            file,
            None,
            format!(
                "the angles look like degrees ({why}); the CSV's alpha and beta are in radians \
                 (multiply by π/180)"
            ),
        ))
    };
    // a wrapped angle in degrees jumps by about 360 between two samples
    for (name, col) in [("alpha", &cols.alpha), ("beta", &cols.beta)] {
        if col
            .windows(2)
            .any(|w| (300.0..=420.0).contains(&(w[1] - w[0]).abs()))
        {
            return degrees(format!("column `{name}` jumps by about 360"));
        }
    }
    let moves = cols.alpha.iter().any(|&a| a != cols.alpha[0]);
    match spec.kind {
        RunKind::Ringdown { alpha0 } => {
            let deg = alpha0.to_degrees();
            if !moves && (deg - alpha0).abs() > 0.01 && (cols.alpha[0] - deg).abs() < 1e-3 {
                return degrees(format!(
                    "column `alpha` holds {}, which is `alpha0_deg`",
                    crate::error::show(cols.alpha[0])
                ));
            }
        }
        RunKind::Driven { f_hz } => {
            if !moves {
                return Ok(());
            }
            let Some(raw) = slope(&cols.t, &cols.alpha) else {
                return Ok(());
            };
            if ((raw / 360.0) - f_hz).abs() <= 0.05 * f_hz {
                return degrees(format!(
                    "column `alpha` advances by {} per second, 360 × f_hz",
                    crate::error::show(raw)
                ));
            }
            let Some(rate) = slope(&cols.t, &unwrap(&cols.alpha)) else {
                return Ok(());
            };
            let f_alpha = (rate / TAU * 1e4).round() / 1e4;
            if (f_alpha - f_hz).abs() > 0.05 * f_hz {
                return Err(rec_err(
                    exp,
                    key_line(text, spec.line, "f_hz").or(spec.line),
                    format!(
                        "`f_hz` = {} but the alpha column of `{}` turns at {} Hz (more than 5 % \
                         apart)",
                        crate::error::show(f_hz),
                        spec.file,
                        crate::error::show(f_alpha)
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// Largest experiment.toml read, bytes (1 MiB).
const EXPERIMENT_BYTES_MAX: u64 = 1 << 20;

/// Reads a recording set from its folder: experiment.toml, then each run file, which must resolve
/// (symbolic links followed) to a regular file inside the set's folder, of at most
/// [`limits::RUN_FILE_BYTES_MAX`] bytes and [`limits::RUN_SAMPLES_MAX`] samples; the set holds at
/// most [`limits::SET_SAMPLES_MAX`] samples.
pub fn read_set(dir: impl AsRef<Path>) -> Result<RecordingSet> {
    let dir = dir.as_ref();
    let exp = dir.join("experiment.toml");
    let exp_name = exp.display().to_string();
    let text = read_text(&exp, &exp_name, EXPERIMENT_BYTES_MAX, None)?;
    let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
    let (gear, specs) = parse_experiment(text, &exp_name)?;
    let root = dir.canonicalize().map_err(|e| {
        rec_err(
            &exp_name,
            None,
            format!("cannot resolve the set's folder: {e}"),
        )
    })?;
    let mut runs = Vec::new();
    let mut total = 0usize;
    for s in specs {
        let p = dir.join(&s.file);
        let pn = p.display().to_string();
        let real = p.canonicalize().map_err(|e| {
            rec_err(
                &exp_name,
                s.line,
                format!("run file `{}`: missing or unreadable ({e})", s.file),
            )
        })?;
        if !real.starts_with(&root) {
            return Err(rec_err(
                &exp_name,
                s.line,
                format!(
                    "run file `{}` resolves (through a symbolic link) to a file outside the \
                     set's folder",
                    s.file
                ),
            ));
        }
        let ct = read_text(
            &real,
            &pn,
            limits::RUN_FILE_BYTES_MAX,
            Some((&exp_name, s.line)),
        )?;
        let c = parse_csv(&ct, &pn)?;
        check_units_and_drive(&c, &s, &pn, &exp_name, text)?;
        total += c.t.len();
        if total > limits::SET_SAMPLES_MAX {
            return Err(rec_err(
                &pn,
                None,
                format!(
                    "the set passes {} samples with this run: a set has at most that many",
                    limits::SET_SAMPLES_MAX
                ),
            ));
        }
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
