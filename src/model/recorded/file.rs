//! `model.json`: a recorded gear as the diagnosis found it (schema `gearbif.model/1`, described in
//! docs/formats.md): the set-up, every parameter of the lens [`RecordedParam`] with its value and
//! unit, the terms of the sparse search, the covariance of the fitted parameters, the accepted
//! effects and, apart from the gear, the measurement model (the sensor latency).
//!
//! [`ModelFile::read`] checks everything a command relies on and names the file and the field at
//! fault: the schema, every parameter name, unit and value (the lens's own checks), the covariance
//! (square, symmetric, positive semi-definite, over known names), the effect names.

use super::effect::Effect;
use super::{Coefficients, ExtraTerm, Geometry, RecordedModel, RecordedParam, MAX_EXTRA};
use crate::error::{Error, Result};
use crate::model::params::{Parameter, Parametrised};
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The schema id of `model.json`.
pub const MODEL_SCHEMA: &str = "gearbif.model/1";

/// The effects a model file may list (the catalog's identifiers, docs/diagnosis.md).
pub const KNOWN_EFFECTS: &[&str] = &[
    "coupling_geometry",
    "static_torque",
    "load_dependent_friction",
    "static_friction",
    "corotating_drag",
    "quadratic_drag",
    "power_law_drag",
    "input_compliance",
    "drive_steps",
    "sensor_latency",
    "parameter_drift",
    "condition_dependence",
    "unexplained",
];

/// The name of the latency in the covariance (the measurement model's one parameter).
pub const LATENCY: &str = "latency";

/// The document `model.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelFile {
    /// [`MODEL_SCHEMA`].
    pub schema: String,
    /// The set-up the parameters belong to.
    pub setup: Setup,
    /// Every parameter of the gear (all of [`RecordedParam`] but the drive frequency f, which
    /// each command sets).
    pub parameters: Vec<ParamValue>,
    /// Terms of the sparse search (`unexplained`), at most four.
    #[serde(default)]
    pub extra_terms: Vec<ExtraTermValue>,
    /// The covariance of the fitted parameters (the others are held: no variance).
    pub covariance: Covariance,
    /// The accepted effects, in the order of the findings.
    pub effects: Vec<String>,
    /// How the recording saw the gear (not part of the dynamics).
    pub measurement: Measurement,
    /// The range of the driven runs the parameters were fitted to (optional: a file without it
    /// makes no statement on extrapolation).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub recorded: Option<RecordedRange>,
}

/// The range of drive frequencies of the recordings behind a model file.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RecordedRange {
    /// Lowest and highest drive frequency of the driven runs, Hz.
    pub drive_hz: [f64; 2],
}

/// A located frequency counts as far outside the recorded range beyond this factor past its
/// ends (f > 1.25 f_max or f < f_min / 1.25).
pub const FAR_FACTOR: f64 = 1.25;

impl RecordedRange {
    /// The range of `freqs` (Hz), or `None` when there is none.
    pub fn of(freqs: impl IntoIterator<Item = f64>) -> Option<Self> {
        let (lo, hi) = freqs
            .into_iter()
            .filter(|f| f.is_finite() && *f > 0.0)
            .fold((f64::INFINITY, 0.0f64), |(a, b), f| (a.min(f), b.max(f)));
        (lo <= hi).then_some(Self { drive_hz: [lo, hi] })
    }

    /// True when the drive frequency `f` lies far outside the range ([`FAR_FACTOR`]).
    pub fn far_outside(&self, f: f64) -> bool {
        f > FAR_FACTOR * self.drive_hz[1] || f * FAR_FACTOR < self.drive_hz[0]
    }

    /// The sentence on `name` = `f` Hz, or `None` when it lies within reach of the range
    /// (`drag`: the model has a fitted drag law, whose extrapolation the sentence names).
    pub fn statement(&self, name: &str, f: f64, drag: bool) -> Option<String> {
        self.far_outside(f).then(|| {
            let [lo, hi] = self.drive_hz;
            format!(
                "{name} = {} Hz lies outside the recorded {}–{} Hz: an extrapolation of the {}",
                round_sig(f, 3),
                round_sig(lo, 3),
                round_sig(hi, 3),
                if drag { "drag law" } else { "fitted model" }
            )
        })
    }

    /// Checks: finite, positive, ordered.
    fn check(&self, file: &str) -> Result<()> {
        let [lo, hi] = self.drive_hz;
        if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && lo <= hi) {
            return Err(bad(
                file,
                format!("recorded.drive_hz: [{lo}, {hi}] must be 0 < low <= high, finite"),
            ));
        }
        Ok(())
    }
}

/// `x` to `n` significant digits, as text.
fn round_sig(x: f64, n: i32) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let d = (n - 1 - x.abs().log10().floor() as i32).max(0) as usize;
    format!("{x:.d$}")
}

/// The set-up: shaft angles and the conventions of the equation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Setup {
    /// Input shaft angle Θ to the centre line, deg.
    pub theta_deg: f64,
    /// Output shaft angle Φ, deg.
    pub phi_deg: f64,
    /// Only the radial part of the bearing load counts in the load friction.
    #[serde(default)]
    pub load_radial: bool,
    /// The drive: "alpha = 2 pi f t" (uniform, α₀ = 0 at t = 0, f set by the command).
    pub drive: String,
    /// The sign of the coupling: "physical" (τ = −∂U/∂β, docs/model.md).
    pub sign: String,
}

/// The drive as written.
pub const DRIVE: &str = "alpha = 2 pi f t";
/// The sign as written.
pub const SIGN: &str = "physical";

/// One parameter: its lens name, value and unit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParamValue {
    /// Name ([`Parameter::name`]).
    pub name: String,
    /// Value.
    pub value: f64,
    /// Unit ([`Parameter::unit`]; empty when dimensionless).
    pub unit: String,
}

/// A term of the sparse search: cos/sin(kα + lβ) as a torque (`trig`), a damping −β̇·(…)
/// (`vel_trig`) or a friction (`fric_trig`), with its coefficient.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExtraTermValue {
    /// "trig", "vel_trig" or "fric_trig".
    pub kind: ExtraKind,
    /// Harmonic of α.
    pub k: i8,
    /// Harmonic of β.
    pub l: i8,
    /// Sine instead of cosine.
    pub sin: bool,
    /// Coefficient.
    pub value: f64,
}

/// The kind of a sparse-search term.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ExtraKind {
    /// A torque.
    Trig,
    /// A modulated viscous damping.
    VelTrig,
    /// A modulated dry friction.
    FricTrig,
}

/// A covariance over named parameters (lens names and [`LATENCY`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct Covariance {
    /// The parameters, in the order of the rows.
    pub names: Vec<String>,
    /// The matrix, row by row.
    pub matrix: Vec<Vec<f64>>,
}

/// The measurement model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Measurement {
    /// The camera's latency: β(t) is recorded at t + latency, s.
    pub latency_s: f64,
}

impl ModelFile {
    /// The document for `model` (f not written) with the covariance, effects and latency given.
    pub fn new(
        model: &RecordedModel,
        covariance: Covariance,
        effects: Vec<String>,
        latency_s: f64,
    ) -> Self {
        let geo = model.geometry();
        let c = model.coefficients();
        let parameters = RecordedParam::ALL
            .iter()
            .filter(|&&p| p != RecordedParam::F)
            .map(|&p| ParamValue {
                name: p.name().into(),
                value: model.param(p),
                unit: p.unit().into(),
            })
            .collect();
        let extra_terms = c
            .extra
            .iter()
            .filter_map(|&(t, value)| extra_value(t, value))
            .collect();
        Self {
            schema: MODEL_SCHEMA.into(),
            setup: Setup {
                theta_deg: geo.theta().to_degrees(),
                phi_deg: geo.phi().to_degrees(),
                load_radial: c.load_radial,
                drive: DRIVE.into(),
                sign: SIGN.into(),
            },
            parameters,
            extra_terms,
            covariance,
            effects,
            measurement: Measurement { latency_s },
            recorded: None,
        }
    }

    /// This file with the recorded range `r`.
    pub fn with_recorded(self, r: Option<RecordedRange>) -> Self {
        Self {
            recorded: r,
            ..self
        }
    }

    /// The accepted effects as [`Effect`]s (checked by [`Self::read`]).
    pub fn effect_list(&self) -> Vec<Effect> {
        self.effects
            .iter()
            .filter_map(|e| Effect::from_name(e).ok())
            .collect()
    }

    /// True when an accepted effect is of the drag family.
    pub fn has_drag(&self) -> bool {
        self.effect_list().iter().any(|e| e.is_drag())
    }

    /// This file with the parameters of `effects` moved to `s` of the way from their off value
    /// to the file's (s = 0: the effects switched off; s = 1: the file), the sparse-search terms
    /// too when [`Effect::Unexplained`] is among them.
    pub fn scaled(&self, effects: &[Effect], s: f64) -> Self {
        let mut out = self.clone();
        for e in effects {
            for &(p, off) in e.parameters() {
                if let Some(v) = out.parameters.iter_mut().find(|v| v.name == p.name()) {
                    v.value = off + s * (v.value - off);
                }
            }
            if *e == Effect::Unexplained {
                for t in &mut out.extra_terms {
                    t.value *= s;
                }
            }
        }
        out
    }

    /// Reads and checks a model file (errors name the file and the field).
    pub fn read(path: &Path) -> Result<Self> {
        let file = path.display().to_string();
        let text =
            std::fs::read_to_string(path).map_err(|e| bad(&file, format!("cannot read: {e}")))?;
        Self::parse(&text, &file)
    }

    /// Parses and checks the text of a model file named `file` in errors: section by section,
    /// so that a value of the wrong type is named by its field.
    pub fn parse(text: &str, file: &str) -> Result<Self> {
        let v: serde_json::Value = serde_json::from_str(text).map_err(|e| Error::Recording {
            file: file.to_string(),
            line: Some(e.line()),
            what: format!("invalid JSON: {e}"),
        })?;
        let obj = v
            .as_object()
            .ok_or_else(|| bad(file, "the model file must be a JSON object".into()))?;
        const KEYS: [&str; 8] = [
            "schema",
            "setup",
            "parameters",
            "extra_terms",
            "covariance",
            "effects",
            "measurement",
            "recorded",
        ];
        if let Some(k) = obj.keys().find(|k| !KEYS.contains(&k.as_str())) {
            return Err(bad(
                file,
                format!("{k}: unknown field (expected {})", KEYS.join(", ")),
            ));
        }
        let m = ModelFile {
            schema: section(obj, "schema", file)?,
            setup: section(obj, "setup", file)?,
            parameters: list(obj, "parameters", file)?,
            extra_terms: match obj.get("extra_terms") {
                None => Vec::new(),
                Some(_) => list(obj, "extra_terms", file)?,
            },
            covariance: section(obj, "covariance", file)?,
            effects: section(obj, "effects", file)?,
            measurement: section(obj, "measurement", file)?,
            recorded: match obj.get("recorded") {
                None => None,
                Some(_) => Some(section(obj, "recorded", file)?),
            },
        };
        m.check(file)?;
        Ok(m)
    }

    /// The checks of [`Self::read`].
    pub fn check(&self, file: &str) -> Result<()> {
        if self.schema != MODEL_SCHEMA {
            return Err(bad(
                file,
                format!("schema: \"{}\" is not \"{MODEL_SCHEMA}\"", self.schema),
            ));
        }
        if self.setup.drive != DRIVE || self.setup.sign != SIGN {
            return Err(bad(
                file,
                format!("setup: drive must be \"{DRIVE}\" and sign \"{SIGN}\""),
            ));
        }
        for (i, e) in self.effects.iter().enumerate() {
            if !KNOWN_EFFECTS.contains(&e.as_str()) {
                return Err(bad(
                    file,
                    format!(
                        "effects[{i}]: unknown effect \"{e}\" (known: {})",
                        KNOWN_EFFECTS.join(", ")
                    ),
                ));
            }
        }
        if !self.measurement.latency_s.is_finite() {
            return Err(bad(file, "measurement.latency_s: must be finite".into()));
        }
        if self.extra_terms.len() > MAX_EXTRA {
            return Err(bad(file, format!("extra_terms: at most {MAX_EXTRA} terms")));
        }
        self.covariance.check(file)?;
        if let Some(r) = &self.recorded {
            r.check(file)?;
        }
        self.model_at(1.0, file).map(|_| ())
    }

    /// The recorded gear of this file driven at `f` Hz (the file checked by [`Self::read`]).
    pub fn model(&self, f: f64) -> Result<RecordedModel> {
        self.model_at(f, "model file")
    }

    fn model_at(&self, f: f64, file: &str) -> Result<RecordedModel> {
        let geo = Geometry::new(
            self.setup.theta_deg.to_radians(),
            self.setup.phi_deg.to_radians(),
        );
        let mut seen: Vec<RecordedParam> = Vec::new();
        for (i, pv) in self.parameters.iter().enumerate() {
            let field = format!("parameters[{i}] ({})", pv.name);
            let p = RecordedParam::from_name(&pv.name)
                .map_err(|e| bad(file, format!("{field}: {e}")))?;
            if p == RecordedParam::F || seen.contains(&p) {
                return Err(bad(
                    file,
                    format!("{field}: f is set by the command, every other parameter once"),
                ));
            }
            if pv.unit != p.unit() {
                return Err(bad(
                    file,
                    format!("{field}: unit \"{}\" is not \"{}\"", pv.unit, p.unit()),
                ));
            }
            seen.push(p);
        }
        for p in [
            RecordedParam::G,
            RecordedParam::Delta,
            RecordedParam::Zeta,
            RecordedParam::Eta,
        ] {
            if !seen.contains(&p) {
                return Err(bad(file, format!("parameters: {} is missing", p.name())));
            }
        }
        let value = |p: RecordedParam| {
            self.parameters
                .iter()
                .find(|v| v.name == p.name())
                .map(|v| v.value)
        };
        let mut c = Coefficients::base(
            value(RecordedParam::G).unwrap_or(0.0),
            value(RecordedParam::Delta).unwrap_or(0.0),
            0.0,
            0.0,
        );
        c.load_radial = self.setup.load_radial;
        for (slot, t) in c.extra.iter_mut().zip(&self.extra_terms) {
            *slot = (extra_term(t), t.value);
        }
        let mut m =
            RecordedModel::new(c, geo, f).map_err(|e| bad(file, format!("parameters: {e}")))?;
        for (i, pv) in self.parameters.iter().enumerate() {
            let p = RecordedParam::from_name(&pv.name)?;
            m = m
                .with_param(p, pv.value)
                .map_err(|e| bad(file, format!("parameters[{i}] ({}): {e}", pv.name)))?;
        }
        Ok(m)
    }
}

impl Covariance {
    /// The matrix.
    pub fn matrix(&self) -> DMatrix<f64> {
        let n = self.names.len();
        DMatrix::from_fn(n, n, |i, j| self.matrix[i][j])
    }

    /// Square over known, distinct names, finite, symmetric and positive semi-definite (to
    /// 1e-9 of its largest variance).
    pub fn check(&self, file: &str) -> Result<()> {
        let n = self.names.len();
        for (i, name) in self.names.iter().enumerate() {
            let known = name == LATENCY
                || RecordedParam::from_name(name).is_ok_and(|p| p != RecordedParam::F);
            if !known || self.names[..i].contains(name) {
                return Err(bad(
                    file,
                    format!("covariance.names[{i}]: \"{name}\" is not a distinct parameter name"),
                ));
            }
        }
        if self.matrix.len() != n || self.matrix.iter().any(|r| r.len() != n) {
            return Err(bad(file, format!("covariance.matrix: must be {n} × {n}")));
        }
        if self.matrix.iter().flatten().any(|v| !v.is_finite()) {
            return Err(bad(file, "covariance.matrix: must be finite".into()));
        }
        let a = self.matrix();
        let scale = a.diagonal().iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let tol = 1e-9 * scale.max(f64::MIN_POSITIVE);
        for i in 0..n {
            for j in 0..i {
                if (a[(i, j)] - a[(j, i)]).abs() > tol {
                    return Err(bad(
                        file,
                        format!("covariance.matrix: not symmetric at [{i}][{j}]"),
                    ));
                }
            }
        }
        if n > 0 {
            let lowest = a.symmetric_eigen().eigenvalues.min();
            if lowest < -tol {
                return Err(bad(
                    file,
                    format!(
                        "covariance.matrix: not positive semi-definite (eigenvalue {lowest:e})"
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// The field `key` of the document, decoded (errors name the field).
fn section<T: serde::de::DeserializeOwned>(
    obj: &serde_json::Map<String, serde_json::Value>,
    key: &str,
    file: &str,
) -> Result<T> {
    let v = obj
        .get(key)
        .ok_or_else(|| bad(file, format!("{key}: missing field")))?;
    serde_json::from_value(v.clone()).map_err(|e| bad(file, format!("{key}: {e}")))
}

/// The array field `key`, decoded element by element (errors name the element).
fn list<T: serde::de::DeserializeOwned>(
    obj: &serde_json::Map<String, serde_json::Value>,
    key: &str,
    file: &str,
) -> Result<Vec<T>> {
    let items: Vec<serde_json::Value> = section(obj, key, file)?;
    items
        .into_iter()
        .enumerate()
        .map(|(i, v)| serde_json::from_value(v).map_err(|e| bad(file, format!("{key}[{i}]: {e}"))))
        .collect()
}

/// An input-file error naming `file` (the field is named in `what`).
fn bad(file: &str, what: String) -> Error {
    Error::Recording {
        file: file.to_string(),
        line: None,
        what,
    }
}

/// The file form of a sparse-search term (`None` for an unused slot).
fn extra_value(t: ExtraTerm, value: f64) -> Option<ExtraTermValue> {
    let (kind, k, l, sin) = match t {
        ExtraTerm::Unused => return None,
        ExtraTerm::Trig { k, l, sin } => (ExtraKind::Trig, k, l, sin),
        ExtraTerm::VelTrig { k, l, sin } => (ExtraKind::VelTrig, k, l, sin),
        ExtraTerm::FricTrig { k, l, sin } => (ExtraKind::FricTrig, k, l, sin),
    };
    Some(ExtraTermValue {
        kind,
        k,
        l,
        sin,
        value,
    })
}

/// The model form of a sparse-search term.
fn extra_term(v: &ExtraTermValue) -> ExtraTerm {
    let (k, l, sin) = (v.k, v.l, v.sin);
    match v.kind {
        ExtraKind::Trig => ExtraTerm::Trig { k, l, sin },
        ExtraKind::VelTrig => ExtraTerm::VelTrig { k, l, sin },
        ExtraKind::FricTrig => ExtraTerm::FricTrig { k, l, sin },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::DrivenOscillator;

    fn sample() -> ModelFile {
        let mut c = Coefficients::base(300.0, 0.9, 1.1, 23.0);
        c.st_a = 2.0;
        c.eta_load = 4.0;
        c.extra[0] = (
            ExtraTerm::Trig {
                k: 1,
                l: -2,
                sin: true,
            },
            0.7,
        );
        let m = RecordedModel::new(c, Geometry::new(0.1, 0.2), 2.0).unwrap();
        let cov = Covariance {
            names: vec!["g".into(), "static_a".into(), LATENCY.into()],
            matrix: vec![
                vec![4.0, 0.5, 0.0],
                vec![0.5, 1.0, 0.0],
                vec![0.0, 0.0, 1e-6],
            ],
        };
        ModelFile::new(&m, cov, vec!["static_torque".into()], 0.012)
            .with_recorded(RecordedRange::of([1.0, 2.5, 1.5]))
    }

    /// The recorded range: its sentence only far outside, and switching an effect off moves its
    /// parameters (and only its) to the off value.
    #[test]
    fn recorded_range_and_effects_switched_off() {
        let r = RecordedRange::of([2.5, 1.0, 1.7]).unwrap();
        assert_eq!(r.drive_hz, [1.0, 2.5]);
        assert!(r.statement("f_c", 3.0, true).is_none());
        assert_eq!(
            r.statement("f_c", 4.1, true).unwrap(),
            "f_c = 4.10 Hz lies outside the recorded 1.00–2.50 Hz: an extrapolation of the drag law"
        );
        assert!(r.far_outside(0.7) && !r.far_outside(0.9));
        let f = sample();
        let off = f.scaled(&[Effect::StaticTorque], 0.0).model(2.0).unwrap();
        let on = f.model(2.0).unwrap();
        assert_eq!(off.param(RecordedParam::StaticA), 0.0);
        assert_eq!(on.param(RecordedParam::StaticA), 2.0);
        assert_eq!(off.param(RecordedParam::G), on.param(RecordedParam::G));
        let half = f.scaled(&[Effect::Unexplained], 0.5);
        assert_eq!(half.extra_terms[0].value, 0.35);
    }

    /// Written and read back, the file gives the same gear (forces equal bit for bit).
    #[test]
    fn round_trip_gives_the_same_gear() {
        let f = sample();
        let text = serde_json::to_string_pretty(&f).unwrap();
        let back = ModelFile::parse(&text, "model.json").unwrap();
        assert_eq!(back, f);
        let (a, b) = (f.model(2.0).unwrap(), back.model(2.0).unwrap());
        for k in 0..5 {
            let (t, x, v) = (0.1 * k as f64, 0.7 * k as f64, 1.0 - 0.4 * k as f64);
            assert_eq!(a.forces_jet(t, x, v, true), b.forces_jet(t, x, v, true));
        }
        assert_eq!(a.param(RecordedParam::StaticA), 2.0);
    }

    /// An edit of a valid file.
    type Edit = dyn Fn(&mut ModelFile);

    /// Every malformed field is refused with the file and the field named.
    #[test]
    fn malformed_files_name_the_field() {
        let cases: Vec<(Box<Edit>, &str)> = vec![
            (Box::new(|m| m.schema = "gearbif.model/2".into()), "schema"),
            (
                Box::new(|m| m.parameters[0].name = "gg".into()),
                "parameters[0] (gg)",
            ),
            (
                Box::new(|m| {
                    let p = m
                        .parameters
                        .iter_mut()
                        .find(|p| p.name == "drag_p")
                        .unwrap();
                    p.value = 9.0;
                }),
                "(drag_p): invalid",
            ),
            (
                Box::new(|m| m.parameters[0].unit = "Hz".into()),
                "parameters[0] (g): unit",
            ),
            (
                Box::new(|m| m.parameters.retain(|p| p.name != "eta")),
                "eta is missing",
            ),
            (
                Box::new(|m| m.effects.push("gremlins".into())),
                "effects[1]",
            ),
            (
                Box::new(|m| m.covariance.names[1] = "f".into()),
                "covariance.names[1]",
            ),
            (
                Box::new(|m| m.covariance.matrix[0][1] = 0.6),
                "not symmetric",
            ),
            (
                Box::new(|m| {
                    m.covariance.matrix[0][1] = 3.0;
                    m.covariance.matrix[1][0] = 3.0;
                }),
                "not positive semi-definite",
            ),
            (
                Box::new(|m| m.covariance.matrix.pop().map(|_| ()).unwrap()),
                "must be 3 × 3",
            ),
            (
                Box::new(|m| {
                    m.recorded = Some(RecordedRange {
                        drive_hz: [2.0, 1.0],
                    })
                }),
                "recorded.drive_hz",
            ),
        ];
        for (edit, field) in cases {
            let mut m = sample();
            edit(&mut m);
            let text = serde_json::to_string(&m).unwrap();
            let e = ModelFile::parse(&text, "rec/model.json")
                .unwrap_err()
                .to_string();
            assert!(e.starts_with("rec/model.json"), "{e}");
            assert!(e.contains(field), "{field}: {e}");
        }
        let e = ModelFile::parse("{\"schema\": 1}", "m.json")
            .unwrap_err()
            .to_string();
        assert!(e.contains("m.json") && e.contains("schema"), "{e}");
    }
}
