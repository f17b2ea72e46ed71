//! Continuation of periodic orbits of the gear with special points, branch switching, and the
//! lock-loss boundary f_c(Θ).

use crate::convert::{complex2, rows, state, to_python, vec2};
use crate::dynamics::{orbit_dict, orbit_spec, shooting, spec_dict};
use crate::errors::{invalid, IntoPyResult};
use crate::systems::{gear as as_gear, PyGear};
use gearbif::continuation::{
    switch_branch as switch, Branch, Continuation, ContinuationOptions, SpecialPoint,
};
use gearbif::model::gear::GearParam;
use gearbif::model::params::{Parameter, Parametrised};
use numpy::{Complex64, PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyAny, PyDict, PyList};

/// A located special point of a branch (fold, flip, symmetry-breaking, Neimark–Sacker or
/// nonsmooth), with the data needed to switch branches there.
///
/// Attributes: kind ("fold", "flip", "symmetry_breaking", "neimark_sacker", "nonsmooth"), label,
/// param (the located parameter value, in the branch's parameter unit), precision (error estimate
/// of param: bracket half-width plus corrector tolerance), x = (β [rad], ω [rad/s]) numpy array,
/// multipliers (complex numpy array of the orbit's map), test_value, eigenvector (numpy array or
/// None), stability_change, index (position in branch.specials), jump (dict or None: events and
/// multipliers on both sides of a nonsmooth point).
#[pyclass(name = "SpecialPoint", module = "gearbif", frozen)]
pub struct PySpecialPoint {
    pub inner: SpecialPoint,
    /// Position in the branch's list of special points.
    #[pyo3(get)]
    pub index: usize,
}

fn kind_name(p: &SpecialPoint) -> String {
    serde_json::to_value(p.kind)
        .ok()
        .and_then(|v| v.as_str().map(str::to_owned))
        .unwrap_or_default()
}

#[pymethods]
impl PySpecialPoint {
    /// Type: "fold", "flip", "symmetry_breaking", "neimark_sacker" or "nonsmooth".
    #[getter]
    fn kind(&self) -> String {
        kind_name(&self.inner)
    }
    /// Human-readable type.
    #[getter]
    fn label(&self) -> &'static str {
        self.inner.kind.label()
    }
    /// Located parameter value (unit of the branch's parameter: f in Hz, theta in deg, …).
    #[getter]
    fn param(&self) -> f64 {
        self.inner.param
    }
    /// Error estimate of `param` (same unit).
    #[getter]
    fn precision(&self) -> f64 {
        self.inner.precision
    }
    /// State (β [rad], ω [rad/s]) on the section at the located point.
    #[getter]
    fn x<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vec2(py, self.inner.x)
    }
    /// Multipliers of the orbit's map at the point (complex numpy array).
    #[getter]
    fn multipliers<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<Complex64>> {
        complex2(py, self.inner.floquet.multipliers)
    }
    /// Value of the test function at the located point (0 for nonsmooth points).
    #[getter]
    fn test_value(&self) -> f64 {
        self.inner.test_value
    }
    /// Eigenvector of the critical multiplier ±1 (numpy array), or None.
    #[getter]
    fn eigenvector<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        self.inner.eigenvector.map(|v| vec2(py, v))
    }
    /// True if the branch's stability differs on the two sides.
    #[getter]
    fn stability_change(&self) -> bool {
        self.inner.stability_change
    }
    /// For a nonsmooth point: events and Floquet data on both sides (dict), else None.
    #[getter]
    fn jump<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, &self.inner.jump)
    }
    /// All fields as a dict (the JSON of `gearbif continue --json`).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, &self.inner)
    }
    fn __repr__(&self) -> String {
        format!(
            "SpecialPoint(kind=\"{}\", param={:.9}, precision={:.1e}, x=({:.6}, {:.6}))",
            kind_name(&self.inner),
            self.inner.param,
            self.inner.precision,
            self.inner.x[0],
            self.inner.x[1]
        )
    }
}

/// A branch of periodic orbits of the gear, as numpy arrays, with its special points.
///
/// Attributes (n points in continuation order): param_name; param (n,) in the parameter's unit
/// (f [Hz], theta [deg], g [1/s²], zeta [1/s], eta [1/s²], delta [1]); x (n, 2) = (β [rad],
/// ω [rad/s]) on the section at t = 0; beta, omega (n,); stable (n,) bool; multipliers (n, 2)
/// complex (of the orbit's map: G for symmetric orbits, P_T^k otherwise); events (n, 3) int
/// (crossings, sticks, grazes per application of the map); arclength (n,); specials (list of
/// SpecialPoint); stop (why it stopped, dict); spec (section, iterations, winding);
/// map_evaluations; gear (the Gear at the first point).
#[pyclass(name = "Branch", module = "gearbif", frozen)]
pub struct PyBranch {
    pub inner: Branch,
    pub opts: ContinuationOptions,
}

#[pymethods]
impl PyBranch {
    /// Name of the continuation parameter (f, g, zeta, eta, delta, theta).
    #[getter]
    fn param_name(&self) -> &'static str {
        self.inner.param.name()
    }
    /// Parameter values (n,).
    #[getter]
    fn param<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(py, self.inner.points.iter().map(|p| p.param).collect())
    }
    /// States (n, 2): β [rad], ω [rad/s].
    #[getter]
    fn x<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let p = &self.inner.points;
        rows(py, p.len(), 2, |i, j| p[i].x[j])
    }
    /// β [rad] (n,).
    #[getter]
    fn beta<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(py, self.inner.points.iter().map(|p| p.x[0]).collect())
    }
    /// ω [rad/s] (n,).
    #[getter]
    fn omega<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(py, self.inner.points.iter().map(|p| p.x[1]).collect())
    }
    /// Stability of each point (n,) bool.
    #[getter]
    fn stable<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<bool>> {
        PyArray1::from_vec(py, self.inner.points.iter().map(|p| p.stable).collect())
    }
    /// Multipliers (n, 2) complex, largest modulus first.
    #[getter]
    fn multipliers<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<Complex64>>> {
        let flat: Vec<Complex64> = self
            .inner
            .points
            .iter()
            .flat_map(|p| p.floquet.multipliers.map(|z| Complex64::new(z[0], z[1])))
            .collect();
        use numpy::PyArrayMethods;
        PyArray1::from_vec(py, flat).reshape([self.inner.points.len(), 2])
    }
    /// Events per application of the orbit's map (n, 3): crossings, sticks, grazes.
    #[getter]
    fn events<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let p = &self.inner.points;
        rows(py, p.len(), 3, |i, j| {
            let e = p[i].events;
            [e.crossings, e.sticks, e.grazes][j] as f64
        })
    }
    /// Arclength from the first point (n,).
    #[getter]
    fn arclength<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(py, self.inner.points.iter().map(|p| p.arclength).collect())
    }
    /// The located special points, in continuation order.
    #[getter]
    fn specials(&self) -> Vec<PySpecialPoint> {
        self.inner
            .specials
            .iter()
            .enumerate()
            .map(|(index, s)| PySpecialPoint {
                inner: s.clone(),
                index,
            })
            .collect()
    }
    /// Why the continuation stopped: {"reason": ..., "detail": ...}.
    #[getter]
    fn stop<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, &self.inner.stop)
    }
    /// The orbit problem: section, iterations, winding.
    #[getter]
    fn spec<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        spec_dict(py, &self.inner.spec)
    }
    /// Number of map evaluations (integrations with sensitivities).
    #[getter]
    fn map_evaluations(&self) -> usize {
        self.inner.map_evaluations
    }
    /// The gear at the first point.
    #[getter]
    fn gear(&self) -> PyGear {
        PyGear {
            inner: self.inner.system,
        }
    }
    /// The branch as a dict: one entry of `branches` in `gearbif continue --json`
    /// (schema gearbif.branches/1, docs/formats.md).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, &self.inner)
    }
    fn __len__(&self) -> usize {
        self.inner.points.len()
    }
    fn __repr__(&self) -> String {
        let (lo, hi) = self.inner.param_range().unwrap_or((f64::NAN, f64::NAN));
        format!(
            "Branch(param=\"{}\", points={}, range=[{lo:.6}, {hi:.6}], specials={}, section={:?}, iterations={}, winding={})",
            self.inner.param.name(),
            self.inner.points.len(),
            self.inner.specials.len(),
            self.inner.spec.section,
            self.inner.spec.iterations,
            self.inner.spec.winding
        )
    }
}

fn parse_range(range: (f64, f64)) -> PyResult<(f64, f64)> {
    let (lo, hi) = range;
    if !(lo.is_finite() && hi.is_finite() && lo < hi) {
        return Err(invalid(format!(
            "range must be (lo, hi) with lo < hi, got ({lo}, {hi})"
        )));
    }
    Ok((lo, hi))
}

/// Pseudo-arclength continuation of a periodic orbit of the gear in one parameter, with
/// detection and location of folds, flips, symmetry-breaking, Neimark–Sacker and nonsmooth points.
///
/// continuation(gear, x0=None, *, param="f", range, lock=None, section="half_period",
///              iterations=1, winding=1, ds=0.02, ds_max=0.1, ds_min=1e-7, max_steps=2000,
///              tol=1e-11, newton_tol=1e-9, max_multiplier=1e4, locate_tol=1e-8)
///
/// The start orbit is shot from x0 = (β [rad], ω [rad/s]) at the gear's parameter value, or taken
/// from the analytic lock (lock = "stable" or "unstable", Δ = ±1 only). param: f [Hz], theta [deg],
/// g [1/s²], zeta [1/s], eta [1/s²] or delta [1]; range = (lo, hi) in that unit — the continuation
/// stops on its bounds; the sign of ds sets the initial direction (+: up). tol: integrator
/// tolerance; locate_tol: bracket width to which special points are located.
///
/// Returns a Branch. Raises NewtonError if the start orbit is not found, ContinuationError,
/// InvalidInputError for bad options.
#[pyfunction]
#[pyo3(signature = (gear, x0=None, *, param="f", range, lock=None, section="half_period", iterations=1, winding=1, ds=0.02, ds_max=0.1, ds_min=1e-7, max_steps=2000, tol=1e-11, newton_tol=1e-9, max_multiplier=1e4, locate_tol=1e-8))]
#[allow(clippy::too_many_arguments)]
fn continuation(
    py: Python<'_>,
    gear: &Bound<'_, PyAny>,
    x0: Option<&Bound<'_, PyAny>>,
    param: &str,
    range: (f64, f64),
    lock: Option<&str>,
    section: &str,
    iterations: usize,
    winding: i32,
    ds: f64,
    ds_max: f64,
    ds_min: f64,
    max_steps: usize,
    tol: f64,
    newton_tol: f64,
    max_multiplier: f64,
    locate_tol: f64,
) -> PyResult<PyBranch> {
    let g = as_gear(gear)?;
    let param = GearParam::from_name(param).py()?;
    let (lo, hi) = parse_range(range)?;
    let sh = shooting(tol, newton_tol, 30)?;
    let spec = orbit_spec(section, iterations, winding)?;
    let x0 = match (x0, lock) {
        (Some(x), None) => state(x, "x0")?,
        (None, Some(which)) => {
            let lb = g.lock_branch().py()?;
            match which {
                "stable" => lb.stable.state,
                "unstable" => lb.unstable.state,
                _ => return Err(invalid("lock must be \"stable\" or \"unstable\"")),
            }
        }
        _ => return Err(invalid("give exactly one of x0 and lock")),
    };
    if !(max_multiplier > 1.0 && locate_tol > 0.0) {
        return Err(invalid("need max_multiplier > 1 and locate_tol > 0"));
    }
    let opts = ContinuationOptions {
        ds,
        ds_min,
        ds_max,
        max_steps,
        param_min: lo,
        param_max: hi,
        max_multiplier,
        shooting: sh,
        locate_tol,
        ..Default::default()
    };
    let b = py
        .detach(|| Continuation::new(g, param, spec, x0, opts)?.run(None))
        .py()?;
    Ok(PyBranch { inner: b, opts })
}

/// Branch switching at a flip (onto the period-doubled branch, P_T^{2k}) or a symmetry-breaking
/// point (onto an asymmetric orbit on P_T), then continuation of the new branch.
///
/// switch_branch(branch, special, *, dparam=-1e-3, ds=None, ds_max=None, max_steps=None,
///               range=None)
///
/// special: a SpecialPoint of `branch` (or its index in branch.specials). The new orbit is shot
/// from x* ± εv at param* + dparam (then −dparam, ±10·dparam); its continuation starts in the
/// direction of sign(ds) (default: −sign(dparam)·|branch ds|/4) and uses the branch's options
/// otherwise. Returns (Branch, start) where start is the new orbit as a dict with its
/// `separation` from the old branch. Raises ContinuationError if no new orbit is found,
/// UnsupportedError at other kinds of points.
#[pyfunction]
#[pyo3(signature = (branch, special, *, dparam=-1e-3, ds=None, ds_max=None, max_steps=None, range=None))]
#[allow(clippy::too_many_arguments)]
fn switch_branch<'py>(
    py: Python<'py>,
    branch: &PyBranch,
    special: &Bound<'py, PyAny>,
    dparam: f64,
    ds: Option<f64>,
    ds_max: Option<f64>,
    max_steps: Option<usize>,
    range: Option<(f64, f64)>,
) -> PyResult<(PyBranch, Bound<'py, PyDict>)> {
    let sp = if let Ok(i) = special.extract::<usize>() {
        branch.inner.specials.get(i).cloned().ok_or_else(|| {
            invalid(format!(
                "special point {i}: the branch has {}",
                branch.inner.specials.len()
            ))
        })?
    } else if let Ok(s) = special.cast::<PySpecialPoint>() {
        s.get().inner.clone()
    } else {
        return Err(invalid("special must be a SpecialPoint or an index"));
    };
    if !(dparam.is_finite() && dparam != 0.0) {
        return Err(invalid("dparam must be finite and non-zero"));
    }
    let mut opts = branch.opts;
    opts.ds = ds.unwrap_or(-dparam.signum() * 0.25 * opts.ds.abs());
    opts.ds_max = ds_max.unwrap_or(opts.ds_max);
    opts.max_steps = max_steps.unwrap_or(opts.max_steps);
    if let Some(r) = range {
        let (lo, hi) = parse_range(r)?;
        opts.param_min = lo;
        opts.param_max = hi;
    }
    let b = &branch.inner;
    let (start, nb) = py
        .detach(|| {
            let sw = switch(b, &sp, dparam, &opts.shooting)?;
            let nb = Continuation::from_orbit(sw.system, b.param, &sw.orbit, opts)?.run(None)?;
            Ok::<_, gearbif::Error>((sw, nb))
        })
        .py()?;
    let d = orbit_dict(py, &start.orbit)?;
    d.set_item("separation", start.separation)?;
    d.set_item("param", start.system.param(b.param))?;
    Ok((PyBranch { inner: nb, opts }, d))
}

/// The lock-loss boundary f_c(Θ) for parallel shafts: the fold curves of the forward lock
/// (winding +1, from Θ = 0) and of the reversed lock (winding −1, from Θ = 54.74°), each started
/// at the analytic f_c and followed by Newton on the augmented system (fold condition).
///
/// lock_loss_boundary(gear=None, *, step_deg=2.0, tol=1e-11)
///
/// gear: a Gear or GearParams (default: the paper's gear; only g, ζ, η matter, Θ is swept).
/// Returns a list of dicts: label, winding, theta_deg (numpy, deg), f_c (numpy, Hz), precision
/// (numpy, Hz), x (n, 2) states, stopped (why the curve ended early, or None).
#[pyfunction]
#[pyo3(signature = (gear=None, *, step_deg=2.0, tol=1e-11))]
fn lock_loss_boundary<'py>(
    py: Python<'py>,
    gear: Option<&Bound<'py, PyAny>>,
    step_deg: f64,
    tol: f64,
) -> PyResult<Bound<'py, PyList>> {
    let base = match gear {
        None => gearbif::model::Gear::paper(0.0, 1.0).py()?,
        Some(o) => {
            if let Ok(p) = o.cast::<crate::systems::PyGearParams>() {
                p.get().inner.driven(1.0).py()?
            } else {
                as_gear(o)?
            }
        }
    };
    let sh = shooting(tol, 1e-9, 30)?;
    let curves = py
        .detach(|| gearbif::continuation::two_param::lock_loss_boundary(&base, step_deg, &sh))
        .py()?;
    let out = PyList::empty(py);
    for (label, c) in curves {
        let d = PyDict::new(py);
        d.set_item("label", label)?;
        d.set_item("winding", c.spec.winding)?;
        let p = &c.points;
        d.set_item(
            "theta_deg",
            PyArray1::from_vec(py, p.iter().map(|q| q.along).collect()),
        )?;
        d.set_item(
            "f_c",
            PyArray1::from_vec(py, p.iter().map(|q| q.free).collect()),
        )?;
        d.set_item(
            "precision",
            PyArray1::from_vec(py, p.iter().map(|q| q.precision).collect()),
        )?;
        d.set_item("x", rows(py, p.len(), 2, |i, j| p[i].x[j]))?;
        d.set_item("stopped", c.stopped.as_ref().map(|s| s.to_string()))?;
        out.append(d)?;
    }
    Ok(out)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyBranch>()?;
    m.add_class::<PySpecialPoint>()?;
    m.add_function(wrap_pyfunction!(continuation, m)?)?;
    m.add_function(wrap_pyfunction!(switch_branch, m)?)?;
    m.add_function(wrap_pyfunction!(lock_loss_boundary, m)?)?;
    Ok(())
}
