//! Classification of one point, two-parameter sweeps, synthetic recordings, fitting and diagnosis.

use crate::convert::{state, to_python};
use crate::errors::{invalid, IntoPyResult};
use crate::systems::{gear as as_gear, parse_convention, PyGearParams};
use gearbif::analysis::{classify_point, ClassifyOptions};
use gearbif::identification::diagnose::{diagnose as run_diagnosis, DiagnoseOptions};
use gearbif::identification::synth::{synthesize, SynthOptions};
use gearbif::integrator::EventDriven;
use gearbif::io::recordings::{read_set, write_set};
use gearbif::io::with_schema;
use gearbif::model::GearParams;
use gearbif::sweep::{Axis, Method, Protocol, SweepOutcome, SweepRunner, SweepSpec};
use pyo3::prelude::*;
use pyo3::types::{PyAny, PyDict};
use std::path::PathBuf;

/// Classifies the attractor reached from x0: the paper's flowchart (7-harmonic fit of δ, RMS,
/// THD) and the rigorous class (period and symmetry by Newton on the map, Lyapunov exponent).
///
/// classify(gear, x0=(π/2, 0), *, settle_turns=90, record_turns=10, samples_per_turn=50,
///          rigorous=True, analysis_turns=60, tol=1e-9, keep_samples=False)
///
/// x0 = (β [rad], ω [rad/s]) at t = 0 (drive phase α₀ of the gear). Returns the dict of
/// `gearbif classify --json` (schema gearbif.classify/1, docs/formats.md): theta_deg, f_hz and
/// event_driven = {paper metrics (rms, thd, class, …), rigorous class, agree, net_rotation_hz,
/// end_state}.
#[pyfunction]
#[pyo3(signature = (gear, x0=None, *, settle_turns=90, record_turns=10, samples_per_turn=50, rigorous=true, analysis_turns=60, tol=1e-9, keep_samples=false))]
#[allow(clippy::too_many_arguments)]
fn classify<'py>(
    py: Python<'py>,
    gear: &Bound<'py, PyAny>,
    x0: Option<&Bound<'py, PyAny>>,
    settle_turns: usize,
    record_turns: usize,
    samples_per_turn: usize,
    rigorous: bool,
    analysis_turns: usize,
    tol: f64,
    keep_samples: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let g = as_gear(gear)?;
    let x0 = match x0 {
        Some(x) => state(x, "x0")?,
        None => [std::f64::consts::FRAC_PI_2, 0.0],
    };
    let opts = ClassifyOptions {
        settle_turns,
        record_turns,
        samples_per_turn,
        rigorous,
        analysis_turns,
        tol,
        keep_samples,
        ..ClassifyOptions::default()
    };
    let r = py
        .detach(|| classify_point(&g, x0, &EventDriven, &opts))
        .py()?;
    // the document of `gearbif classify --json` (one method: event_driven)
    let doc = serde_json::json!({
        "schema": "gearbif.classify/1",
        "theta_deg": gearbif::model::params::Parametrised::param(
            &g,
            gearbif::model::gear::GearParam::ThetaDeg
        ),
        "f_hz": g.f,
        "event_driven": r,
    });
    to_python(py, &doc)
}

fn axis(obj: Option<&Bound<'_, PyAny>>, default: &str) -> PyResult<Axis> {
    let Some(obj) = obj else {
        return Axis::parse(default).py();
    };
    if let Ok(s) = obj.extract::<String>() {
        return Axis::parse(&s).py();
    }
    let (name, values): (String, Vec<f64>) = obj.extract().map_err(|_| {
        invalid(
            "an axis is \"param:start:stop:step\", \"param:start:stop:n:log\" or (param, values)",
        )
    })?;
    Ok(Axis {
        param: gearbif::sweep::SweepParam::parse(&name).py()?,
        values,
    })
}

/// A two-parameter atlas: every grid point classified (parallel over rows).
///
/// sweep(rows="theta:0:50:10", cols="f:0.5:3:0.25", *, params=None, f=1.0, protocol="fresh",
///       alpha0_deg=90.0, beta0_deg=90.0, convention="physical", settle_turns=None,
///       record_turns=10, analysis_turns=60, tol=1e-9, out_dir=None)
///
/// Axes as on the command line ("param:start:stop:step", "param:start:stop:n:log", param in theta
/// [deg], f [Hz], zeta [1/s], eta [1/s²], inertia [kg m²]) or (param, values). params: a
/// GearParams (default: the paper's gear); f [Hz] when f is not an axis; protocol "fresh" (every
/// point from (alpha0_deg, beta0_deg), Fig. 7b) or "semi_static" (state carried along a row,
/// Fig. 8); settle_turns default 90 (fresh) or 1000 (semi_static); analysis_turns = 0 skips the
/// rigorous class. out_dir: also write points.csv and sweep.json there.
/// Returns the dict of sweep.json (schema gearbif.sweep/1, docs/formats.md).
#[pyfunction]
#[pyo3(signature = (rows=None, cols=None, *, params=None, f=1.0, protocol="fresh", alpha0_deg=90.0, beta0_deg=90.0, convention="physical", settle_turns=None, record_turns=10, analysis_turns=60, tol=1e-9, out_dir=None))]
#[allow(clippy::too_many_arguments)]
fn sweep<'py>(
    py: Python<'py>,
    rows: Option<&Bound<'py, PyAny>>,
    cols: Option<&Bound<'py, PyAny>>,
    params: Option<PyRef<'py, PyGearParams>>,
    f: f64,
    protocol: &str,
    alpha0_deg: f64,
    beta0_deg: f64,
    convention: &str,
    settle_turns: Option<usize>,
    record_turns: usize,
    analysis_turns: usize,
    tol: f64,
    out_dir: Option<PathBuf>,
) -> PyResult<Bound<'py, PyAny>> {
    let protocol = match protocol {
        "fresh" => Protocol::Fresh,
        "semi_static" => Protocol::SemiStatic,
        p => {
            return Err(invalid(format!(
                "protocol `{p}`: expected \"fresh\" or \"semi_static\""
            )))
        }
    };
    let mut classify = ClassifyOptions {
        settle_turns: settle_turns.unwrap_or(match protocol {
            Protocol::Fresh => 90,
            Protocol::SemiStatic => 1000,
        }),
        record_turns,
        tol,
        ..ClassifyOptions::default()
    };
    if analysis_turns == 0 {
        classify.rigorous = false;
    } else {
        classify.analysis_turns = analysis_turns;
    }
    let spec = SweepSpec {
        gear: params.map(|p| p.inner).unwrap_or_else(GearParams::paper),
        f,
        rows: axis(rows, "theta:0:50:10")?,
        cols: axis(cols, "f:0.5:3:0.25")?,
        protocol,
        alpha0_deg,
        beta0_deg,
        convention: parse_convention(convention)?,
        method: Method::EventDriven,
        classify,
    };
    spec.validate().py()?;
    let res = py
        .detach(|| match SweepRunner::new(spec).run()? {
            SweepOutcome::Complete(r) => {
                if let Some(d) = &out_dir {
                    r.write(d)?;
                }
                Ok(*r)
            }
            SweepOutcome::Stopped { .. } => Err(gearbif::Error::InvalidInput(
                "the sweep stopped early".into(),
            )),
        })
        .py()?;
    to_python(py, &with_schema("gearbif.sweep/1", &res))
}

/// Writes a synthetic recording set (experiment.toml and CSV files, docs/formats.md) made by
/// simulating a concealed truth gear with one catalogued effect, and returns the truth.
///
/// synth(out_dir, effect="none", size=0.0, *, ringdowns=12, driven=8, turns=80.0,
///       f_range=(0.5, 2.5), samples_per_turn=50, fps=100.0, noise_deg=0.5, seed=1)
///
/// effect: none, rescale, static_torque, quadratic_drag, corotating_drag, coupling_geometry,
/// load_dependent_friction, sensor_latency, input_compliance, drive_steps, parameter_drift
/// (`gearbif synth --list` gives the meaning of size). f_range [Hz], fps [1/s], noise_deg [deg].
/// Returns a dict: effect, size, g [1/s²], delta [1], zeta [1/s], eta [1/s²], latency_s [s].
#[pyfunction]
#[pyo3(signature = (out_dir, effect="none", size=0.0, *, ringdowns=12, driven=8, turns=80.0, f_range=(0.5, 2.5), samples_per_turn=50, fps=100.0, noise_deg=0.5, seed=1))]
#[allow(clippy::too_many_arguments)]
fn synth<'py>(
    py: Python<'py>,
    out_dir: PathBuf,
    effect: &str,
    size: f64,
    ringdowns: usize,
    driven: usize,
    turns: f64,
    f_range: (f64, f64),
    samples_per_turn: usize,
    fps: f64,
    noise_deg: f64,
    seed: u64,
) -> PyResult<Bound<'py, PyDict>> {
    let opts = SynthOptions {
        effect: effect.to_owned(),
        size,
        ringdowns,
        driven,
        turns,
        f_range,
        samples_per_turn,
        fps,
        noise_deg,
        seed,
        ..SynthOptions::default()
    };
    let truth = py
        .detach(|| {
            let (set, truth) = synthesize(&opts)?;
            write_set(&set, &out_dir, opts.wrap)?;
            Ok::<_, gearbif::Error>(truth)
        })
        .py()?;
    let c = &truth.coefficients;
    let d = PyDict::new(py);
    d.set_item("effect", effect)?;
    d.set_item("size", size)?;
    d.set_item("g", c.g())?;
    d.set_item("delta", c.delta())?;
    d.set_item("zeta", c.zeta)?;
    d.set_item("eta", c.eta)?;
    d.set_item("latency_s", truth.latency)?;
    Ok(d)
}

/// Fits the base model to a recording set: ring-downs one by one (exact simulation +
/// Levenberg–Marquardt), κ(α₀) → g, |Δ|, I, and the base model on all runs.
///
/// fit(set_dir) — set_dir: folder with experiment.toml (docs/formats.md).
/// Returns the dict of `gearbif fit --json` (schema gearbif.fit/1): baseline (params with errors),
/// ringdowns, kappa_alpha0. Raises RecordingError for a malformed set.
#[pyfunction]
fn fit<'py>(py: Python<'py>, set_dir: PathBuf) -> PyResult<Bound<'py, PyAny>> {
    let opts = DiagnoseOptions {
        base_only: true,
        heldout_predictions: false,
        ..DiagnoseOptions::default()
    };
    let d = py
        .detach(|| {
            let set = read_set(&set_dir)?;
            run_diagnosis(&set, &opts, &|_| {})
        })
        .py()?;
    let v = serde_json::json!({
        "schema": "gearbif.fit/1",
        "baseline": d.report.baseline,
        "ringdowns": d.ringdowns,
        "kappa_alpha0": d.kappa,
    });
    to_python(py, &v)
}

/// Diagnoses a recording set: fits the base model, locates the mismatch and names the missing
/// physics from the catalogue.
///
/// diagnose(set_dir, *, heldout=True, out_dir=None)
///
/// heldout: compute the leave-one-run-out short-horizon predictions (slower). out_dir: also write
/// report.json there. Returns the report as a dict (schema gearbif.diagnosis/1, docs/formats.md):
/// verdict, findings, baseline, …. Raises RecordingError for a malformed set.
#[pyfunction]
#[pyo3(signature = (set_dir, *, heldout=true, out_dir=None))]
fn diagnose<'py>(
    py: Python<'py>,
    set_dir: PathBuf,
    heldout: bool,
    out_dir: Option<PathBuf>,
) -> PyResult<Bound<'py, PyAny>> {
    let opts = DiagnoseOptions {
        heldout_predictions: heldout,
        ..DiagnoseOptions::default()
    };
    let d = py
        .detach(|| {
            let set = read_set(&set_dir)?;
            let d = run_diagnosis(&set, &opts, &|_| {})?;
            if let Some(o) = &out_dir {
                gearbif::io::write_json_atomic(o.join("report.json"), &d.report)?;
            }
            Ok::<_, gearbif::Error>(d)
        })
        .py()?;
    to_python(py, &d.report)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(classify, m)?)?;
    m.add_function(wrap_pyfunction!(sweep, m)?)?;
    m.add_function(wrap_pyfunction!(synth, m)?)?;
    m.add_function(wrap_pyfunction!(fit, m)?)?;
    m.add_function(wrap_pyfunction!(diagnose, m)?)?;
    Ok(())
}
