//! Classification of one point, two-parameter sweeps, synthetic recordings, fitting and diagnosis.

use crate::convert::{count, floats, state, to_python};
use crate::dynamics::{check_tol, parse_method};
use crate::errors::{invalid, IntoPyResult};
use crate::systems::{dispatch, parse_convention, PyGearParams, PySystem, System};
use gearbif::analysis::{classify_point, ClassifyOptions, PointResult};
use gearbif::identification::diagnose::{diagnose as run_diagnosis, DiagnoseOptions};
use gearbif::identification::synth::{synthesize, SynthOptions};
use gearbif::integrator::{EventDriven, EventDriven853};
use gearbif::io::recordings::{read_set, write_set};
use gearbif::io::with_schema;
use gearbif::model::gear::GearParam;
use gearbif::model::params::Parametrised;
use gearbif::model::GearParams;
use gearbif::progress::StopFlag;
use gearbif::sweep::{sweep_grid, Axis, Method, Protocol, SweepOutcome, SweepRunner, SweepSpec};
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::{PyAny, PyDict};
use std::path::PathBuf;

/// The classification keyword arguments shared by `classify`, `sweep_grid` and `sweep` (one
/// place for their meaning and checks; the defaults of their signatures are [`Default`]).
struct ClassifyArgs {
    settle_turns: i64,
    record_turns: i64,
    samples_per_turn: i64,
    rigorous: bool,
    analysis_turns: i64,
    tol: f64,
    keep_samples: bool,
}

impl Default for ClassifyArgs {
    /// The library's defaults ([`ClassifyOptions::default`]), so the two cannot drift apart.
    fn default() -> Self {
        let o = ClassifyOptions::default();
        let int = |n: usize| i64::try_from(n).unwrap_or(i64::MAX);
        Self {
            settle_turns: int(o.settle_turns),
            record_turns: int(o.record_turns),
            samples_per_turn: int(o.samples_per_turn),
            rigorous: o.rigorous,
            analysis_turns: int(o.analysis_turns),
            tol: o.tol,
            keep_samples: o.keep_samples,
        }
    }
}

impl ClassifyArgs {
    /// The validated options (analysis_turns = 0 skips the rigorous class).
    fn options(self) -> PyResult<ClassifyOptions> {
        check_tol(self.tol)?;
        let opts = ClassifyOptions {
            settle_turns: count(self.settle_turns, "settle_turns", 0)?,
            record_turns: count(self.record_turns, "record_turns", 1)?,
            samples_per_turn: count(self.samples_per_turn, "samples_per_turn", 15)?,
            rigorous: self.rigorous && self.analysis_turns > 0,
            analysis_turns: count(self.analysis_turns, "analysis_turns", 0)?.max(2),
            tol: self.tol,
            keep_samples: self.keep_samples,
            ..ClassifyOptions::default()
        };
        opts.validate().py()?;
        Ok(opts)
    }
}

/// The start state `x0` of `classify` and `sweep_grid`, validated; by default (π/2, 0) for the
/// gear (the paper's Fig. 6 start β = 90°), the rest state (0, 0) otherwise.
fn start(sys: &System, x0: Option<&Bound<'_, PyAny>>) -> PyResult<[f64; 2]> {
    match (x0, sys) {
        (Some(x), _) => state(x, "x0"),
        (None, System::Gear(_)) => Ok([std::f64::consts::FRAC_PI_2, 0.0]),
        (None, _) => Ok([0.0, 0.0]),
    }
}

/// Classifies the attractor reached from x0: the paper's flowchart (7-harmonic fit of δ, RMS,
/// THD) and the rigorous class (period and symmetry by Newton on the map, Lyapunov exponent),
/// for any system (Gear, CoulombOscillator, ForcedPendulum).
///
/// classify(system, x0=None, *, settle_turns=90, record_turns=10, samples_per_turn=50,
///          rigorous=True, analysis_turns=60, tol=1e-9, keep_samples=False, method="dop853")
///
/// x0 = (β [rad], ω [rad/s]) at t = 0 (default (π/2, 0) for the gear, (0, 0) otherwise). δ is
/// β − α for the gear (α the drive phase) and β itself for an oscillator. analysis_turns = 0
/// skips the rigorous class. method: "dop853" (event-driven Dormand–Prince 8(5,3), the default) or
/// "event" (event-driven Dormand–Prince 5(4)). Returns the dict of `gearbif classify --json` (schema
/// gearbif.classify/1, docs/formats.md): system (class name), params {name: value}, for the gear
/// also theta_deg and f_hz, and event_driven = {paper metrics (rms, thd, class, …), rigorous class,
/// agree, net_rotation_hz, end_state}.
#[pyfunction]
#[pyo3(signature = (system, x0=None, *, settle_turns=90, record_turns=10, samples_per_turn=50, rigorous=true, analysis_turns=60, tol=1e-9, keep_samples=false, method="dop853"))]
#[allow(clippy::too_many_arguments)]
fn classify<'py>(
    py: Python<'py>,
    system: &Bound<'py, PyAny>,
    x0: Option<&Bound<'py, PyAny>>,
    settle_turns: i64,
    record_turns: i64,
    samples_per_turn: i64,
    rigorous: bool,
    analysis_turns: i64,
    tol: f64,
    keep_samples: bool,
    method: &str,
) -> PyResult<Bound<'py, PyAny>> {
    let method = parse_method(method)?;
    let sys = crate::systems::system(system)?;
    let x0 = start(&sys, x0)?;
    let opts = ClassifyArgs {
        settle_turns,
        record_turns,
        samples_per_turn,
        rigorous,
        analysis_turns,
        tol,
        keep_samples,
    }
    .options()?;
    let r = py.detach(|| match method {
        Method::EventDriven => classify_point(sys.dynsys(), x0, &EventDriven, &opts),
        _ => classify_point(sys.dynsys(), x0, &EventDriven853, &opts),
    });
    let r = sys.finish(r)?;
    let mut doc = serde_json::json!({
        "schema": "gearbif.classify/1",
        "system": system.get_type().name()?.to_string(),
        "params": dispatch!(&sys, s => params_json(s)),
        "event_driven": r,
    });
    if let System::Gear(g) = &sys {
        doc["theta_deg"] = Parametrised::param(g, GearParam::ThetaDeg).into();
        doc["f_hz"] = g.f.into();
    }
    to_python(py, &doc)
}

/// Runs `work` on a worker thread without the GIL while this thread checks for Python signals
/// every 50 ms: on Ctrl-C (or any signal whose handler raises) the work's [`StopFlag`] is set, the
/// work ends at its next point ([`gearbif::Error::Stopped`]) and the handler's exception
/// (`KeyboardInterrupt`) is raised; nothing else touches Python (or numpy) after the signal.
pub(crate) fn interruptible<T: Send>(
    py: Python<'_>,
    work: impl FnOnce(&StopFlag<'_>) -> T + Send,
) -> PyResult<T> {
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::mpsc;
    use std::time::Duration;
    let flag = AtomicBool::new(false);
    let stop = StopFlag(&flag);
    std::thread::scope(|scope| {
        let (tx, rx) = mpsc::channel();
        let stop = &stop;
        scope.spawn(move || {
            // the receiver may be gone after an interrupt: the result is dropped then
            let _ = tx.send(work(stop));
        });
        let mut rx = rx;
        loop {
            let (got, back) = py.detach(move || (rx.recv_timeout(Duration::from_millis(50)), rx));
            rx = back;
            match got {
                Ok(v) => return Ok(v),
                Err(mpsc::RecvTimeoutError::Disconnected) => {
                    return Err(pyo3::exceptions::PyRuntimeError::new_err(
                        "the computation's thread ended without a result",
                    ))
                }
                Err(mpsc::RecvTimeoutError::Timeout) => {}
            }
            if let Err(e) = py.check_signals() {
                flag.store(true, Ordering::Relaxed);
                // wait (without the GIL) for the work to notice the flag and end
                py.detach(move || drop(rx.recv()));
                return Err(e);
            }
        }
    })
}

/// {name: value} of a system's parameters as JSON.
fn params_json<S: PySystem>(s: &S) -> serde_json::Value {
    s.param_values()
        .into_iter()
        .map(|(n, v)| (n.to_string(), v.into()))
        .collect::<serde_json::Map<_, _>>()
        .into()
}

/// One generic sweep: the grid of classifications of `base` over (rows × cols), as JSON rows.
#[allow(clippy::too_many_arguments)]
fn sweep_system<S: PySystem>(
    base: &S,
    rows: (&str, &[f64]),
    cols: (&str, &[f64]),
    x0: [f64; 2],
    protocol: Protocol,
    opts: &ClassifyOptions,
    method: Method,
    stop: &StopFlag<'_>,
) -> gearbif::Result<Vec<Vec<PointResult>>> {
    let r = (base.param_by_name(rows.0)?, rows.1);
    let c = (base.param_by_name(cols.0)?, cols.1);
    let grid = match method {
        Method::EventDriven => sweep_grid(&EventDriven, base, r, c, x0, protocol, opts, stop)?,
        _ => sweep_grid(&EventDriven853, base, r, c, x0, protocol, opts, stop)?,
    };
    Ok(grid
        .into_iter()
        .map(|row| row.into_iter().map(|(_, p)| p).collect())
        .collect())
}

fn protocol(name: &str) -> PyResult<Protocol> {
    match name {
        "fresh" => Ok(Protocol::Fresh),
        "semi_static" => Ok(Protocol::SemiStatic),
        p => Err(invalid(format!(
            "protocol `{p}`: expected \"fresh\" or \"semi_static\""
        ))),
    }
}

/// An axis (name, values) of `sweep_grid`.
fn grid_axis(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<(String, Vec<f64>)> {
    let (name, values): (String, Bound<'_, PyAny>) = obj
        .extract()
        .map_err(|_| invalid(format!("{what} must be (parameter name, values)")))?;
    let values = floats(&values, what)?;
    if values.is_empty() {
        return Err(invalid(format!("{what}: no values")));
    }
    Ok((name, values))
}

/// A two-parameter sweep of any system (Gear, CoulombOscillator, ForcedPendulum): the attractor
/// at every grid point classified as by `classify` (rows in parallel).
///
/// sweep_grid(system, rows, cols, *, x0=None, protocol="fresh", settle_turns=90, record_turns=10,
///            samples_per_turn=50, analysis_turns=60, tol=1e-9, method="dop853")
///
/// rows, cols = (name, values): a parameter of system.params and its values (1-d sequence or numpy
/// array, in the parameter's unit); the other parameters keep their values in `system`. protocol
/// "fresh": every point starts at x0 (default as in `classify`); "semi_static": along a row the
/// end state of one point starts the next. analysis_turns = 0 skips the rigorous class. method:
/// "dop853" (event-driven Dormand–Prince 8(5,3), the default) or "event" (Dormand–Prince 5(4)).
///
/// Returns a dict: row_param, row_values (numpy), col_param, col_values (numpy), label (list of
/// lists of str: "T/2", "T", "3T", "QP", "chaos", "?", "rest" — the rigorous class, or the paper's class
/// when analysis_turns = 0), rotation_number, net_rotation_hz, rms_delta_deg, lyapunov (numpy
/// arrays of shape (rows, cols), NaN where not computed) and points (list of lists of the
/// classification dicts).
#[pyfunction]
#[pyo3(name = "sweep_grid", signature = (system, rows, cols, *, x0=None, protocol="fresh", settle_turns=90, record_turns=10, samples_per_turn=50, analysis_turns=60, tol=1e-9, method="dop853"))]
#[allow(clippy::too_many_arguments)]
fn sweep_grid_py<'py>(
    py: Python<'py>,
    system: &Bound<'py, PyAny>,
    rows: &Bound<'py, PyAny>,
    cols: &Bound<'py, PyAny>,
    x0: Option<&Bound<'py, PyAny>>,
    protocol: &str,
    settle_turns: i64,
    record_turns: i64,
    samples_per_turn: i64,
    analysis_turns: i64,
    tol: f64,
    method: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let method = parse_method(method)?;
    let sys = crate::systems::system(system)?;
    let (rname, rvals) = grid_axis(rows, "rows")?;
    let (cname, cvals) = grid_axis(cols, "cols")?;
    let x0 = start(&sys, x0)?;
    let protocol = self::protocol(protocol)?;
    let opts = ClassifyArgs {
        settle_turns,
        record_turns,
        samples_per_turn,
        analysis_turns,
        tol,
        ..ClassifyArgs::default()
    }
    .options()?;
    // Ctrl-C stops the sweep at its next point and raises KeyboardInterrupt
    let r = interruptible(
        py,
        |stop| dispatch!(&sys, s => sweep_system(s, (&rname, &rvals), (&cname, &cvals), x0, protocol, &opts, method, stop)),
    )?;
    let grid = sys.finish(r)?;
    let (n, m) = (rvals.len(), cvals.len());
    let field = |f: &dyn Fn(&PointResult) -> Option<f64>| {
        crate::convert::rows(py, n, m, |i, j| f(&grid[i][j]).unwrap_or(f64::NAN))
    };
    let d = PyDict::new(py);
    d.set_item("row_param", &rname)?;
    d.set_item("row_values", PyArray1::from_slice(py, &rvals))?;
    d.set_item("col_param", &cname)?;
    d.set_item("col_values", PyArray1::from_slice(py, &cvals))?;
    let labels: Vec<Vec<String>> = grid
        .iter()
        .map(|row| row.iter().map(point_label).collect())
        .collect();
    d.set_item("label", labels)?;
    d.set_item(
        "rotation_number",
        field(&|p| p.rigorous.as_ref().map(|r| r.rotation_number)),
    )?;
    d.set_item("net_rotation_hz", field(&|p| Some(p.net_rotation_hz)))?;
    d.set_item("rms_delta_deg", field(&|p| Some(p.paper.rms_delta_deg)))?;
    d.set_item(
        "lyapunov",
        field(&|p| p.rigorous.as_ref().and_then(|r| r.lyapunov.per_period)),
    )?;
    d.set_item("points", to_python(py, &grid)?)?;
    Ok(d)
}

/// The class label of a sweep point: the rigorous one, else the paper's.
fn point_label(p: &PointResult) -> String {
    match &p.rigorous {
        Some(r) => r.label.clone(),
        None => serde_json::to_value(p.paper.class)
            .ok()
            .and_then(|v| v.as_str().map(str::to_owned))
            .unwrap_or_default(),
    }
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
///       record_turns=10, analysis_turns=60, tol=1e-9, out_dir=None, method="dop853")
///
/// Axes as on the command line ("param:start:stop:step", "param:start:stop:n:log", param a name of
/// the gear's lens — theta [deg], f [Hz], zeta [1/s], eta [1/s²], g [1/s²], delta — or inertia
/// [kg m²]) or (param, values). params: a
/// GearParams (default: the paper's gear); f [Hz] when f is not an axis; protocol "fresh" (every
/// point from (alpha0_deg, beta0_deg), Fig. 7b) or "semi_static" (state carried along a row,
/// Fig. 8); settle_turns default 90 (fresh) or 1000 (semi_static); analysis_turns = 0 skips the
/// rigorous class. out_dir: also write points.csv and sweep.json there. method: "dop853"
/// (event-driven Dormand–Prince 8(5,3), the default, as `gearbif sweep`) or "event" (DP5).
/// Returns the dict of sweep.json (schema gearbif.sweep/1, docs/formats.md).
#[pyfunction]
#[pyo3(signature = (rows=None, cols=None, *, params=None, f=1.0, protocol="fresh", alpha0_deg=90.0, beta0_deg=90.0, convention="physical", settle_turns=None, record_turns=10, analysis_turns=60, tol=1e-9, out_dir=None, method="dop853"))]
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
    settle_turns: Option<i64>,
    record_turns: i64,
    analysis_turns: i64,
    tol: f64,
    out_dir: Option<PathBuf>,
    method: &str,
) -> PyResult<Bound<'py, PyAny>> {
    let method = parse_method(method)?;
    let protocol = self::protocol(protocol)?;
    let settle = settle_turns.unwrap_or(match protocol {
        Protocol::Fresh => 90,
        Protocol::SemiStatic => 1000,
    });
    let classify = ClassifyArgs {
        settle_turns: settle,
        record_turns,
        analysis_turns,
        tol,
        ..ClassifyArgs::default()
    }
    .options()?;
    let spec = SweepSpec {
        gear: params.map(|p| p.inner).unwrap_or_else(GearParams::paper),
        f,
        rows: axis(rows, "theta:0:50:10")?,
        cols: axis(cols, "f:0.5:3:0.25")?,
        protocol,
        alpha0_deg,
        beta0_deg,
        convention: parse_convention(convention)?,
        method,
        classify,
    };
    spec.validate().py()?;
    let res = interruptible(py, |stop| {
        match SweepRunner::new(spec).observer(stop).run()? {
            SweepOutcome::Complete(r) => {
                if let Some(d) = &out_dir {
                    r.write(d)?;
                }
                Ok(*r)
            }
            SweepOutcome::Stopped { .. } => Err(gearbif::Error::Stopped { what: "the sweep" }),
        }
    })?
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
/// load_dependent_friction, sensor_latency, input_compliance, drive_steps, parameter_drift,
/// static_friction
/// (`gearbif synth --list` gives the meaning of size). f_range [Hz], fps [1/s], noise_deg [deg].
/// Returns a dict: effect, size, g [1/s²], delta [1], zeta [1/s], eta [1/s²], latency_s [s].
#[pyfunction]
#[pyo3(signature = (out_dir, effect="none", size=0.0, *, ringdowns=12, driven=8, turns=80.0, f_range=None, samples_per_turn=50, fps=100.0, noise_deg=0.5, seed=1))]
#[allow(clippy::too_many_arguments)]
fn synth<'py>(
    py: Python<'py>,
    out_dir: PathBuf,
    effect: &str,
    size: f64,
    ringdowns: i64,
    driven: i64,
    turns: f64,
    f_range: Option<&Bound<'py, PyAny>>,
    samples_per_turn: i64,
    fps: f64,
    noise_deg: f64,
    seed: i64,
) -> PyResult<Bound<'py, PyDict>> {
    let opts = SynthOptions {
        effect: effect.to_owned(),
        size,
        ringdowns: count(ringdowns, "ringdowns", 0)?,
        driven: count(driven, "driven", 0)?,
        turns,
        f_range: match f_range {
            Some(r) => crate::convert::range(r, "f_range")?,
            None => (0.5, 2.5),
        },
        samples_per_turn: count(samples_per_turn, "samples_per_turn", 1)?,
        fps,
        noise_deg,
        seed: count(seed, "seed", 0)? as u64,
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
/// fit(set_dir, *, tol=None) — set_dir: folder with experiment.toml (docs/formats.md); tol:
/// relative tolerance of the simulations, in (0, 1) (None: the library's default, 1e-8; the
/// ring-downs are integrated ten times tighter).
/// Returns the dict of `gearbif fit --json` (schema gearbif.fit/1): baseline (params with errors),
/// ringdowns, kappa_alpha0. Raises RecordingError for a malformed set, InvalidParameterError for a
/// tolerance outside (0, 1).
#[pyfunction]
#[pyo3(signature = (set_dir, *, tol=None))]
fn fit<'py>(py: Python<'py>, set_dir: PathBuf, tol: Option<f64>) -> PyResult<Bound<'py, PyAny>> {
    let defaults = DiagnoseOptions::default();
    let opts = DiagnoseOptions {
        base_only: true,
        heldout_predictions: false,
        tol: tol.unwrap_or(defaults.tol),
        ..defaults
    };
    let d = py
        .detach(|| {
            let set = read_set(&set_dir)?;
            run_diagnosis(&set, &opts, &gearbif::progress::Silent)
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
/// diagnose(set_dir, *, heldout=True, out_dir=None, tol=None, profile_shapes=False)
///
/// heldout: compute the leave-one-run-out short-horizon predictions (slower). out_dir: also write
/// report.json there. tol: relative tolerance of the simulations, in (0, 1) (None: the library's
/// default, 1e-8). profile_shapes: profile the final model's shape parameters, a check of a
/// shape whose profile is far from quadratic (3–9 times the CPU when a family with a shape is
/// named; docs/diagnosis.md). Returns the report as a dict (schema gearbif.diagnosis/1, docs/formats.md):
/// verdict, findings, baseline, …. Raises RecordingError for a malformed set,
/// InvalidParameterError for a tolerance outside (0, 1).
#[pyfunction]
#[pyo3(signature = (set_dir, *, heldout=true, out_dir=None, tol=None, profile_shapes=false))]
fn diagnose<'py>(
    py: Python<'py>,
    set_dir: PathBuf,
    heldout: bool,
    out_dir: Option<PathBuf>,
    tol: Option<f64>,
    profile_shapes: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let defaults = DiagnoseOptions::default();
    let opts = DiagnoseOptions {
        heldout_predictions: heldout,
        tol: tol.unwrap_or(defaults.tol),
        profile_shapes,
        ..defaults
    };
    let d = py
        .detach(|| {
            let set = read_set(&set_dir)?;
            let d = run_diagnosis(&set, &opts, &gearbif::progress::Silent)?;
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
    m.add_function(wrap_pyfunction!(sweep_grid_py, m)?)?;
    m.add_function(wrap_pyfunction!(synth, m)?)?;
    m.add_function(wrap_pyfunction!(fit, m)?)?;
    m.add_function(wrap_pyfunction!(diagnose, m)?)?;
    Ok(())
}
