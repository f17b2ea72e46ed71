//! Continuation of periodic orbits of any system of the module with special points, branch
//! switching, and the gear's lock-loss boundary f_c(Θ). One generic code path: a branch of any
//! system is held as a [`AnyBranch`] trait object.

use crate::convert::{complex2, count, range as parse_range, rows, state, to_python, vec2};
use crate::dynamics::{orbit_dict, orbit_spec, shooting, spec_dict};
use crate::errors::{invalid, IntoPyResult};
use crate::systems::{dispatch, gear as as_gear, PySystem, System};
use gearbif::continuation::{
    switch_branch as switch, Branch, BranchPoint, Continuation, ContinuationOptions, SpecialPoint,
    StopReason,
};
use gearbif::orbits::{OrbitSpec, PeriodicOrbit};
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

/// A branch of any system, seen through what Python reads from it.
pub trait AnyBranch: Send + Sync {
    /// The points, in continuation order.
    fn points(&self) -> &[BranchPoint];
    /// The located special points.
    fn specials(&self) -> &[SpecialPoint];
    /// Why the continuation stopped.
    fn stop(&self) -> &StopReason;
    /// The orbit problem.
    fn spec(&self) -> &OrbitSpec;
    /// Map evaluations.
    fn map_evaluations(&self) -> usize;
    /// Name of the continuation parameter.
    fn param_name(&self) -> &'static str;
    /// The first exception a Python callback of the system raised (user systems).
    fn take_error(&self) -> Option<PyErr>;
    /// The system at the first point, as its Python object.
    fn system_object<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>>;
    /// The branch as JSON (one entry of `branches` in `gearbif continue --json`).
    fn to_json(&self) -> gearbif::Result<serde_json::Value>;
    /// Switches at `sp` and continues the new branch with `opts`.
    fn switch(
        &self,
        sp: &SpecialPoint,
        dparam: f64,
        opts: ContinuationOptions,
    ) -> gearbif::Result<(Box<dyn AnyBranch>, SwitchInfo)>;
}

/// The start of a switched branch: its first orbit, the distance from the old branch and the
/// parameter value.
pub struct SwitchInfo {
    pub orbit: PeriodicOrbit,
    pub separation: f64,
    pub param: f64,
}

impl<S: PySystem> AnyBranch for Branch<S> {
    fn points(&self) -> &[BranchPoint] {
        &self.points
    }
    fn specials(&self) -> &[SpecialPoint] {
        &self.specials
    }
    fn stop(&self) -> &StopReason {
        &self.stop
    }
    fn spec(&self) -> &OrbitSpec {
        &self.spec
    }
    fn map_evaluations(&self) -> usize {
        self.map_evaluations
    }
    fn param_name(&self) -> &'static str {
        self.system.param_label(self.param)
    }
    fn take_error(&self) -> Option<PyErr> {
        self.system.take_error()
    }
    fn system_object<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.system.to_object(py)
    }
    fn to_json(&self) -> gearbif::Result<serde_json::Value> {
        serde_json::to_value(self).map_err(|e| gearbif::Error::format("JSON", "branch", e))
    }
    fn switch(
        &self,
        sp: &SpecialPoint,
        dparam: f64,
        opts: ContinuationOptions,
    ) -> gearbif::Result<(Box<dyn AnyBranch>, SwitchInfo)> {
        let sw = switch(self, sp, dparam, &opts.shooting)?;
        let nb =
            Continuation::from_orbit(sw.system.clone(), self.param, &sw.orbit, opts)?.run(None)?;
        let info = SwitchInfo {
            param: sw.system.param(self.param),
            orbit: sw.orbit,
            separation: sw.separation,
        };
        Ok((Box::new(nb), info))
    }
}

/// A branch of periodic orbits, as numpy arrays, with its special points.
///
/// Attributes (n points in continuation order): param_name; param (n,) in the parameter's unit
/// (for the gear f [Hz], theta [deg], g [1/s²], zeta [1/s], eta [1/s²], delta [1]; for the other
/// systems the unit of their parameter); x (n, 2) = (β [rad], ω [rad/s]) on the section at t = 0;
/// beta, omega (n,); stable (n,) bool; multipliers (n, 2) complex (of the orbit's map: G for
/// symmetric orbits, P_T^k otherwise); events (n, 3) int (crossings, sticks, grazes per
/// application of the map); arclength (n,); specials (list of SpecialPoint); stop (why it stopped,
/// dict); spec (section, iterations, winding); map_evaluations; system (the system at the first
/// point; `gear` is the same for the gear).
#[pyclass(name = "Branch", module = "gearbif", frozen)]
pub struct PyBranch {
    pub inner: Box<dyn AnyBranch>,
    pub opts: ContinuationOptions,
}

impl PyBranch {
    fn column<'py>(
        &self,
        py: Python<'py>,
        f: impl Fn(&BranchPoint) -> f64,
    ) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(py, self.inner.points().iter().map(f).collect())
    }
}

#[pymethods]
impl PyBranch {
    /// Name of the continuation parameter.
    #[getter]
    fn param_name(&self) -> &'static str {
        self.inner.param_name()
    }
    /// Parameter values (n,).
    #[getter]
    fn param<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.column(py, |p| p.param)
    }
    /// States (n, 2): β [rad], ω [rad/s].
    #[getter]
    fn x<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let p = self.inner.points();
        rows(py, p.len(), 2, |i, j| p[i].x[j])
    }
    /// β [rad] (n,).
    #[getter]
    fn beta<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.column(py, |p| p.x[0])
    }
    /// ω [rad/s] (n,).
    #[getter]
    fn omega<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.column(py, |p| p.x[1])
    }
    /// Stability of each point (n,) bool.
    #[getter]
    fn stable<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<bool>> {
        PyArray1::from_vec(py, self.inner.points().iter().map(|p| p.stable).collect())
    }
    /// Multipliers (n, 2) complex, largest modulus first.
    #[getter]
    fn multipliers<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<Complex64>>> {
        use numpy::PyArrayMethods;
        let p = self.inner.points();
        let flat: Vec<Complex64> = p
            .iter()
            .flat_map(|p| p.floquet.multipliers.map(|z| Complex64::new(z[0], z[1])))
            .collect();
        PyArray1::from_vec(py, flat).reshape([p.len(), 2])
    }
    /// Events per application of the orbit's map (n, 3): crossings, sticks, grazes.
    #[getter]
    fn events<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let p = self.inner.points();
        rows(py, p.len(), 3, |i, j| {
            let e = p[i].events;
            [e.crossings, e.sticks, e.grazes][j] as f64
        })
    }
    /// Arclength from the first point (n,).
    #[getter]
    fn arclength<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.column(py, |p| p.arclength)
    }
    /// The located special points, in continuation order.
    #[getter]
    fn specials(&self) -> Vec<PySpecialPoint> {
        self.inner
            .specials()
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
        to_python(py, self.inner.stop())
    }
    /// The orbit problem: section, iterations, winding.
    #[getter]
    fn spec<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        spec_dict(py, self.inner.spec())
    }
    /// Number of map evaluations (integrations with sensitivities).
    #[getter]
    fn map_evaluations(&self) -> usize {
        self.inner.map_evaluations()
    }
    /// The system at the first point (Gear, CoulombOscillator or ForcedPendulum).
    #[getter]
    fn system<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.inner.system_object(py)
    }
    /// The gear at the first point (the same as `system`, for branches of the gear).
    #[getter]
    fn gear<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.inner.system_object(py)
    }
    /// The branch as a dict: one entry of `branches` in `gearbif continue --json`
    /// (schema gearbif.branches/1, docs/formats.md).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let v = self.inner.to_json().py()?;
        to_python(py, &v)
    }
    fn __len__(&self) -> usize {
        self.inner.points().len()
    }
    fn __repr__(&self) -> String {
        let p = self.inner.points();
        let lo = p.iter().map(|q| q.param).fold(f64::INFINITY, f64::min);
        let hi = p.iter().map(|q| q.param).fold(f64::NEG_INFINITY, f64::max);
        let spec = self.inner.spec();
        format!(
            "Branch(param=\"{}\", points={}, range=[{lo:.6}, {hi:.6}], specials={}, section={:?}, iterations={}, winding={})",
            self.inner.param_name(),
            p.len(),
            self.inner.specials().len(),
            spec.section,
            spec.iterations,
            spec.winding
        )
    }
}

/// Continues from `x0` in the parameter named `param` of `sys` (any system of the module).
fn continue_system<S: PySystem>(
    sys: S,
    param: &str,
    spec: OrbitSpec,
    x0: [f64; 2],
    opts: ContinuationOptions,
) -> gearbif::Result<Box<dyn AnyBranch>> {
    let p = sys.param_by_name(param)?;
    let sys = sys.for_param(p)?;
    Ok(Box::new(
        Continuation::new(sys, p, spec, x0, opts)?.run(None)?,
    ))
}

/// The start state: x0, or the gear's analytic lock orbit ("stable" or "unstable").
fn start_state(
    sys: &System,
    x0: Option<&Bound<'_, PyAny>>,
    lock: Option<&str>,
) -> PyResult<[f64; 2]> {
    match (x0, lock) {
        (Some(x), None) => state(x, "x0"),
        (None, Some(which)) => {
            let System::Gear(g) = sys else {
                return Err(crate::errors::Kind::Unsupported
                    .err("lock= is the gear's analytic lock orbit; give x0 for other systems"));
            };
            let lb = g.lock_branch().py()?;
            match which {
                "stable" => Ok(lb.stable.state),
                "unstable" => Ok(lb.unstable.state),
                _ => Err(invalid("lock must be \"stable\" or \"unstable\"")),
            }
        }
        _ => Err(invalid("give exactly one of x0 and lock")),
    }
}

/// Pseudo-arclength continuation of a periodic orbit of any system (Gear, CoulombOscillator,
/// ForcedPendulum) in one parameter, with detection and location of folds, flips,
/// symmetry-breaking, Neimark–Sacker and nonsmooth points.
///
/// continuation(system, x0=None, *, param="f", range, lock=None, section="half_period",
///              iterations=1, winding=None, ds=0.02, ds_max=0.1, ds_min=1e-7, max_steps=2000,
///              tol=1e-11, newton_tol=1e-9, max_multiplier=1e4, locate_tol=1e-8)
///
/// The start orbit is shot from x0 = (β [rad], ω [rad/s]) at the system's parameter value, or (the
/// gear only) taken from the analytic lock (lock = "stable" or "unstable", Δ = ±1 only). param: a
/// name of system.params (the gear: f [Hz], theta [deg], g [1/s²], zeta [1/s], eta [1/s²],
/// delta [1]); range = (lo, hi) in that unit — the continuation stops on its bounds; the sign of
/// ds sets the initial direction (+: up). section "half_period" needs a system with a half-period
/// symmetry (all three have one); winding counts turns of β per period (default 1 for the gear,
/// 0 for the oscillators). tol: integrator tolerance; locate_tol: bracket width to which special
/// points are located.
///
/// Returns a Branch. Raises NewtonError if the start orbit is not found, InvalidParameterError or
/// InvalidInputError for bad options, ContinuationError if the continuation cannot proceed.
#[pyfunction]
#[pyo3(signature = (system, x0=None, *, param="f", range, lock=None, section="half_period", iterations=1, winding=None, ds=0.02, ds_max=0.1, ds_min=1e-7, max_steps=2000, tol=1e-11, newton_tol=1e-9, max_multiplier=1e4, locate_tol=1e-8))]
#[allow(clippy::too_many_arguments)]
fn continuation(
    py: Python<'_>,
    system: &Bound<'_, PyAny>,
    x0: Option<&Bound<'_, PyAny>>,
    param: &str,
    range: &Bound<'_, PyAny>,
    lock: Option<&str>,
    section: &str,
    iterations: i64,
    winding: Option<i32>,
    ds: f64,
    ds_max: f64,
    ds_min: f64,
    max_steps: i64,
    tol: f64,
    newton_tol: f64,
    max_multiplier: f64,
    locate_tol: f64,
) -> PyResult<PyBranch> {
    let sys = crate::systems::system(system)?;
    let (lo, hi) = parse_range(range, "range")?;
    let sh = shooting(tol, newton_tol, 30)?;
    let spec = orbit_spec(
        section,
        iterations,
        winding.unwrap_or(sys.default_winding()),
    )?;
    let x0 = start_state(&sys, x0, lock)?;
    if max_multiplier.is_nan() || max_multiplier <= 1.0 {
        return Err(invalid("need max_multiplier > 1"));
    }
    let opts = ContinuationOptions {
        ds,
        ds_min,
        ds_max,
        max_steps: count(max_steps, "max_steps", 1)?,
        param_min: lo,
        param_max: hi,
        max_multiplier,
        shooting: sh,
        locate_tol,
        ..Default::default()
    };
    opts.validate().py()?;
    let r = py.detach(|| dispatch!(sys.clone(), s => continue_system(s, param, spec, x0, opts)));
    let b = sys.finish(r)?;
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
/// `separation` from the old branch and its `param`. Raises ContinuationError if no new orbit is
/// found, UnsupportedError at other kinds of points.
#[pyfunction]
#[pyo3(signature = (branch, special, *, dparam=-1e-3, ds=None, ds_max=None, max_steps=None, range=None))]
#[allow(clippy::too_many_arguments)]
fn switch_branch<'py>(
    py: Python<'py>,
    branch: &Bound<'py, PyAny>,
    special: &Bound<'py, PyAny>,
    dparam: f64,
    ds: Option<f64>,
    ds_max: Option<f64>,
    max_steps: Option<i64>,
    range: Option<&Bound<'py, PyAny>>,
) -> PyResult<(PyBranch, Bound<'py, PyDict>)> {
    let branch = branch
        .cast::<PyBranch>()
        .map_err(|_| invalid("branch must be a gearbif.Branch"))?
        .get();
    let specials = branch.inner.specials();
    let sp = if let Ok(i) = special.extract::<i64>() {
        usize::try_from(i)
            .ok()
            .and_then(|i| specials.get(i))
            .cloned()
            .ok_or_else(|| {
                invalid(format!(
                    "special point {i}: the branch has {}",
                    specials.len()
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
    if let Some(n) = max_steps {
        opts.max_steps = count(n, "max_steps", 1)?;
    }
    if let Some(r) = range {
        (opts.param_min, opts.param_max) = parse_range(r, "range")?;
    }
    opts.validate().py()?;
    let b = &branch.inner;
    let r = py.detach(|| b.switch(&sp, dparam, opts));
    if let Some(e) = b.take_error() {
        return Err(e);
    }
    let (nb, start) = r.py()?;
    let d = orbit_dict(py, &start.orbit)?;
    d.set_item("separation", start.separation)?;
    d.set_item("param", start.param)?;
    Ok((PyBranch { inner: nb, opts }, d))
}

/// The lock-loss boundary f_c(Θ) of the gear for parallel shafts: the fold curves of the forward
/// lock (winding +1, from Θ = 0) and of the reversed lock (winding −1, from Θ = 54.74°), each
/// started at the analytic f_c and followed by Newton on the augmented system (fold condition).
///
/// lock_loss_boundary(gear=None, *, step_deg=2.0, tol=1e-11)
///
/// gear: a Gear or GearParams (default: the paper's gear; only g, ζ, η matter, Θ is swept);
/// step_deg in (0, 90]. Returns a list of dicts: label, winding, theta_deg (numpy, deg), f_c
/// (numpy, Hz), precision (numpy, Hz), x (n, 2) states, stopped (why the curve ended early, or
/// None).
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
    if !(step_deg > 0.0 && step_deg <= 90.0) {
        return Err(crate::errors::to_py(gearbif::Error::InvalidParameter {
            name: "step_deg",
            value: step_deg,
            reason: "must be in (0, 90]",
        }));
    }
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
        let col = |f: fn(&gearbif::continuation::two_param::CurvePoint) -> f64| {
            PyArray1::from_vec(py, p.iter().map(f).collect())
        };
        d.set_item("theta_deg", col(|q| q.along))?;
        d.set_item("f_c", col(|q| q.free))?;
        d.set_item("precision", col(|q| q.precision))?;
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
