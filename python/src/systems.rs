//! The systems: the gear (built from its physical parameters or from reduced ones) and the other
//! driven oscillators with dry friction of the library, all usable by every function of the module.

use crate::convert::{complex2, to_python, vec2};
use crate::errors::{invalid, IntoPyResult};
use crate::user::{PyUserSystem, UserParam, UserSystem};
use gearbif::model::gear::GearParam;
use gearbif::model::params::{Parameter, Parametrised};
use gearbif::model::recorded::file::{Covariance, ModelFile};
use gearbif::model::recorded::{RecordedModel, RecordedParam};
use gearbif::model::{
    Convention, CoulombOscillator, DrivenOscillator, ForcedPendulum, Gear, GearParams,
};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use serde::Serialize;

/// The gear as built: dipole moments, centre distance, inertia, shaft angles, friction (SI units).
///
/// GearParams(m1=3.51, m2=3.51, r=0.040, inertia=6.45e-5, theta_deg=0.0, phi_deg=None,
///            zeta=1.1, eta=23.1)
///
/// m1, m2 [A m²], r [m], inertia [kg m²], theta_deg/phi_deg: input/output shaft angles to the
/// centre line [deg] (phi_deg defaults to theta_deg: parallel shafts), zeta [1/s], eta [1/s²].
/// The defaults are the paper's gear. Raises InvalidParameterError for values out of range.
#[pyclass(name = "GearParams", module = "gearbif", frozen)]
#[derive(Clone)]
pub struct PyGearParams {
    pub inner: GearParams,
}

#[pymethods]
impl PyGearParams {
    #[new]
    #[pyo3(signature = (m1=3.51, m2=3.51, r=0.040, inertia=6.45e-5, theta_deg=0.0, phi_deg=None, zeta=1.1, eta=23.1))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        m1: f64,
        m2: f64,
        r: f64,
        inertia: f64,
        theta_deg: f64,
        phi_deg: Option<f64>,
        zeta: f64,
        eta: f64,
    ) -> PyResult<Self> {
        let inner = GearParams {
            m1,
            m2,
            r,
            inertia,
            theta: theta_deg.to_radians(),
            phi: phi_deg.unwrap_or(theta_deg).to_radians(),
            zeta,
            eta,
        };
        inner.validate().py()?;
        Ok(Self { inner })
    }

    /// The paper's gear with parallel shafts at Θ = Φ = theta_deg [deg].
    #[staticmethod]
    #[pyo3(signature = (theta_deg=0.0))]
    fn paper(theta_deg: f64) -> PyResult<Self> {
        let inner = GearParams::paper_at_deg(theta_deg);
        inner.validate().py()?;
        Ok(Self { inner })
    }

    /// The driven gear at drive frequency f [Hz] (drive phase alpha0_deg [deg] at t = 0;
    /// convention "physical" or "paper", docs/model.md).
    #[pyo3(signature = (f, alpha0_deg=0.0, convention="physical"))]
    fn driven(&self, f: f64, alpha0_deg: f64, convention: &str) -> PyResult<PyGear> {
        let g = self
            .inner
            .driven(f)
            .py()?
            .with_alpha0(alpha0_deg.to_radians())
            .py()?
            .with_convention(parse_convention(convention)?);
        Ok(PyGear { inner: g })
    }

    /// Input dipole moment m1 [A m²].
    #[getter]
    fn m1(&self) -> f64 {
        self.inner.m1
    }
    /// Output dipole moment m2 [A m²].
    #[getter]
    fn m2(&self) -> f64 {
        self.inner.m2
    }
    /// Centre distance r [m].
    #[getter]
    fn r(&self) -> f64 {
        self.inner.r
    }
    /// Output moment of inertia [kg m²].
    #[getter]
    fn inertia(&self) -> f64 {
        self.inner.inertia
    }
    /// Input shaft angle Θ [deg].
    #[getter]
    fn theta_deg(&self) -> f64 {
        self.inner.theta.to_degrees()
    }
    /// Output shaft angle Φ [deg].
    #[getter]
    fn phi_deg(&self) -> f64 {
        self.inner.phi.to_degrees()
    }
    /// Viscous damping ζ [1/s].
    #[getter]
    fn zeta(&self) -> f64 {
        self.inner.zeta
    }
    /// Dry friction η [1/s²].
    #[getter]
    fn eta(&self) -> f64 {
        self.inner.eta
    }
    /// Coupling g = μ₀ m1 m2 / (4π r³ I) [1/s²].
    #[getter]
    fn g(&self) -> f64 {
        self.inner.g()
    }
    /// Shaft index Δ = cosΘ cosΦ − 2 sinΘ sinΦ [1].
    #[getter]
    fn delta(&self) -> f64 {
        self.inner.delta()
    }
    /// Lock-loss frequency f_c = (g − η)/(2πζ) [Hz] at Θ = Φ = 0 scaling (None if ζ = 0 or g ≤ η).
    #[getter]
    fn lock_loss_frequency(&self) -> Option<f64> {
        self.inner.lock_loss_frequency()
    }
    /// The parameters as a dict (angles in rad, as in the Rust struct).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, &self.inner)
    }
    fn __repr__(&self) -> String {
        let p = &self.inner;
        format!(
            "GearParams(m1={}, m2={}, r={}, inertia={}, theta_deg={}, phi_deg={}, zeta={}, eta={})",
            p.m1,
            p.m2,
            p.r,
            p.inertia,
            p.theta.to_degrees(),
            p.phi.to_degrees(),
            p.zeta,
            p.eta
        )
    }
}

/// The driven dipole gear in reduced parameters:
///
///   β̈ = s·g·τ(α, β; Δ) − ζ β̇ − η sgn(β̇),   α = 2π f t + α₀,
///
/// Gear(g, delta, zeta, eta, f, alpha0_deg=0.0, convention="physical")
///
/// g [1/s²], delta = Δ [1], zeta [1/s], eta [1/s²], f [Hz], alpha0_deg [deg]. Use Gear.paper(theta_deg, f)
/// for the paper's gear, or GearParams(...).driven(f) for a gear built from physical parameters.
/// Parameter columns of the map Jacobians: (f, g, zeta, eta, delta).
#[pyclass(name = "Gear", module = "gearbif", frozen)]
#[derive(Clone)]
pub struct PyGear {
    pub inner: Gear,
}

pub fn parse_convention(s: &str) -> PyResult<Convention> {
    match s {
        "physical" => Ok(Convention::Physical),
        "paper" => Ok(Convention::Paper),
        _ => Err(invalid(format!(
            "convention `{s}`: expected \"physical\" or \"paper\""
        ))),
    }
}

#[pymethods]
impl PyGear {
    #[new]
    #[pyo3(signature = (g, delta, zeta, eta, f, alpha0_deg=0.0, convention="physical"))]
    fn new(
        g: f64,
        delta: f64,
        zeta: f64,
        eta: f64,
        f: f64,
        alpha0_deg: f64,
        convention: &str,
    ) -> PyResult<Self> {
        let inner = Gear::new(g, delta, zeta, eta, f)
            .py()?
            .with_alpha0(alpha0_deg.to_radians())
            .py()?
            .with_convention(parse_convention(convention)?);
        Ok(Self { inner })
    }

    /// The paper's gear with parallel shafts at Θ = Φ = theta_deg [deg], driven at f [Hz].
    #[staticmethod]
    #[pyo3(signature = (theta_deg, f))]
    fn paper(theta_deg: f64, f: f64) -> PyResult<Self> {
        Ok(Self {
            inner: Gear::paper(theta_deg, f).py()?,
        })
    }

    /// A copy with one parameter changed: name in f [Hz], g [1/s²], zeta [1/s], eta [1/s²],
    /// delta [1], theta [deg] (parallel shafts, sets Δ = cos²Θ − 2 sin²Θ).
    fn with_param(&self, name: &str, value: f64) -> PyResult<Self> {
        Ok(Self {
            inner: with_named_param(&self.inner, name, value)?,
        })
    }
    /// The parameters as a dict {name: value}: f [Hz], g [1/s²], zeta [1/s], eta [1/s²],
    /// delta [1], theta [deg].
    #[getter]
    fn params<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        params_dict(py, &self.inner)
    }

    /// Coupling g [1/s²].
    #[getter]
    fn g(&self) -> f64 {
        self.inner.g
    }
    /// Shaft index Δ [1].
    #[getter]
    fn delta(&self) -> f64 {
        self.inner.delta
    }
    /// Viscous damping ζ [1/s].
    #[getter]
    fn zeta(&self) -> f64 {
        self.inner.zeta
    }
    /// Dry friction η [1/s²].
    #[getter]
    fn eta(&self) -> f64 {
        self.inner.eta
    }
    /// Drive frequency f [Hz].
    #[getter]
    fn f(&self) -> f64 {
        self.inner.f
    }
    /// Drive period T = 1/f [s].
    #[getter]
    fn period(&self) -> f64 {
        self.inner.period()
    }
    /// Parallel shaft angle Θ [deg] with Δ = 1 − 3 sin²Θ, Θ ∈ [0°, 90°].
    #[getter]
    fn theta_deg(&self) -> f64 {
        Parametrised::param(&self.inner, GearParam::ThetaDeg)
    }
    /// Drive phase α₀ at t = 0 [deg].
    #[getter]
    fn alpha0_deg(&self) -> f64 {
        self.inner.alpha0.to_degrees()
    }
    /// "physical" or "paper".
    #[getter]
    fn convention(&self) -> &'static str {
        match self.inner.convention {
            Convention::Physical => "physical",
            Convention::Paper => "paper",
        }
    }
    /// Names of the parameter columns of the map Jacobians.
    #[getter]
    fn param_names(&self) -> Vec<&'static str> {
        param_names(&self.inner)
    }
    /// Lock-loss frequency f_c = (g − η)/(2πζ) [Hz] (None if ζ = 0 or g ≤ η).
    #[getter]
    fn lock_loss_frequency(&self) -> Option<f64> {
        self.inner.lock_loss_frequency()
    }
    /// The analytic locked orbits at Δ = ±1 (stable and unstable): a dict with `stable` and
    /// `unstable` entries (phase [rad], state (β [rad], ω [rad/s]) as numpy array, winding,
    /// multipliers of P_T as complex numpy array, stable) and `load` = (2πfζ + η)/g.
    /// Raises UnsupportedError unless Δ = ±1 and f < f_c.
    fn lock_branch<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let lb = self.inner.lock_branch().py()?;
        let d = PyDict::new(py);
        for (name, p) in [("stable", lb.stable), ("unstable", lb.unstable)] {
            let e = PyDict::new(py);
            e.set_item("phase", p.phase)?;
            e.set_item("state", vec2(py, p.state))?;
            e.set_item("winding", p.winding)?;
            let mu = [
                [p.multipliers[0].re, p.multipliers[0].im],
                [p.multipliers[1].re, p.multipliers[1].im],
            ];
            e.set_item("multipliers", complex2(py, mu))?;
            e.set_item("stable", p.stable)?;
            d.set_item(name, e)?;
        }
        d.set_item("load", lb.load)?;
        Ok(d)
    }
    /// The forces (a, r) at (t [s], β [rad], ω [rad/s]): smooth acceleration a and dry-friction
    /// magnitude r, both [1/s²], in β̈ = a − sgn(ω) r.
    fn forces(&self, t: f64, beta: f64, omega: f64) -> PyResult<(f64, f64)> {
        forces(&self.inner, t, beta, omega)
    }
    fn __repr__(&self) -> String {
        let g = &self.inner;
        format!(
            "Gear(g={}, delta={}, zeta={}, eta={}, f={}, alpha0_deg={}, convention=\"{}\")",
            g.g,
            g.delta,
            g.zeta,
            g.eta,
            g.f,
            g.alpha0.to_degrees(),
            self.convention()
        )
    }
}

/// A recorded gear: the gear of a model file (`model.json` of `gearbif diagnose`, schema
/// `gearbif.model/1`) with every term the diagnosis found, driven at f [Hz]. Usable wherever a
/// system is (simulate, poincare_map, continuation, classify, sweep, …); its parameters are the
/// lens names of docs/recorded_gear.md (f, g, delta, zeta, eta, static_a, drag_q, …).
///
/// Model.load(path, f=1.0). Raises RecordingError naming the file and the field for a malformed
/// file (another schema, a covariance that is not symmetric positive semi-definite, an unknown
/// parameter or effect).
#[pyclass(name = "Model", module = "gearbif", frozen)]
#[derive(Clone)]
pub struct PyModel {
    pub inner: RecordedModel,
    /// The model file's covariance (empty for a model a computation handed back).
    pub covariance: Covariance,
}

#[pymethods]
impl PyModel {
    /// The recorded gear of the model file at `path`, driven at `f` [Hz].
    #[staticmethod]
    #[pyo3(signature = (path, f=1.0))]
    fn load(path: std::path::PathBuf, f: f64) -> PyResult<Self> {
        let file = ModelFile::read(&path).py()?;
        Ok(Self {
            inner: file.model(f).py()?,
            covariance: file.covariance,
        })
    }
    /// A copy with one parameter changed (by its name); the covariance is kept.
    fn with_param(&self, name: &str, value: f64) -> PyResult<Self> {
        Ok(Self {
            inner: with_named_param(&self.inner, name, value)?,
            covariance: self.covariance.clone(),
        })
    }
    /// Locates a special point (kind "fold", "flip", "sb" or "ns") in the parameter `param`
    /// (its current value the guess) from the state guess x = (β [rad], ω [rad/s]), on the orbit
    /// problem section/period/winding, and gives its σ from the model file's covariance to first
    /// order (the implicit-function theorem on the augmented system, docs/recorded_gear.md).
    ///
    /// locate(kind, x, *, param="f", section="stroboscopic", period=1, winding=1, tol=1e-11)
    ///
    /// Returns a dict: kind, param, value, x, multipliers, precision, sigma, gradient
    /// {name: dvalue/dname}, omitted (covariance names not in σ: the parameter itself, the
    /// latency, the load weights).
    #[pyo3(signature = (kind, x, *, param="f", section="stroboscopic", period=1, winding=1, tol=1e-11))]
    #[allow(clippy::too_many_arguments)]
    fn locate<'py>(
        &self,
        py: Python<'py>,
        kind: &str,
        x: &Bound<'py, PyAny>,
        param: &str,
        section: &str,
        period: i64,
        winding: i32,
        tol: f64,
    ) -> PyResult<Bound<'py, PyDict>> {
        let x = crate::convert::state(x, "x")?;
        crate::located::locate(
            py,
            &self.inner,
            &self.covariance,
            kind,
            x,
            (param, section, period, winding),
            tol,
        )
    }
    /// The model file's covariance: (names, matrix as a list of rows).
    #[getter]
    fn covariance(&self) -> (Vec<String>, Vec<Vec<f64>>) {
        (
            self.covariance.names.clone(),
            self.covariance.matrix.clone(),
        )
    }
    /// Every parameter as a dict {name: value}.
    #[getter]
    fn params<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        params_dict(py, &self.inner)
    }
    /// Drive frequency f [Hz].
    #[getter]
    fn f(&self) -> f64 {
        self.inner.param(RecordedParam::F)
    }
    /// Drive period T = 1/f [s].
    #[getter]
    fn period(&self) -> f64 {
        self.inner.period()
    }
    /// Names of the parameter columns of the map Jacobians (the active set; a continuation adds
    /// its parameter).
    #[getter]
    fn param_names(&self) -> Vec<&'static str> {
        param_names(&self.inner)
    }
    /// The forces (a, r) at (t [s], β [rad], ω [rad/s]), both [1/s²], in β̈ = a − sgn(ω) r.
    fn forces(&self, t: f64, beta: f64, omega: f64) -> PyResult<(f64, f64)> {
        forces(&self.inner, t, beta, omega)
    }
    fn __repr__(&self) -> String {
        repr("Model", &self.inner)
    }
}

/// Defines the Python class of a built-in oscillator with a parameter lens: the constructor takes
/// the parameters by name (validated by the Rust constructor), one getter per parameter, and the
/// methods every system shares (`period`, `param_names`, `params`, `with_param`, `forces`).
macro_rules! oscillator_class {
    ($(#[$doc:meta])* $py_ty:ident, $py_name:literal, $sys:ty, $variant:ident, ($($arg:ident: $arg_doc:literal),+)) => {
        $(#[$doc])*
        #[pyclass(name = $py_name, module = "gearbif", frozen)]
        #[derive(Clone)]
        pub struct $py_ty {
            pub inner: $sys,
        }

        #[pymethods]
        impl $py_ty {
            #[new]
            #[pyo3(signature = ($($arg),+))]
            fn new($($arg: f64),+) -> PyResult<Self> {
                Ok(Self {
                    inner: <$sys>::new($($arg),+).py()?,
                })
            }
            $(
                #[doc = $arg_doc]
                #[getter]
                fn $arg(&self) -> f64 {
                    self.inner.$arg
                }
            )+
            /// Drive period T = 1/f [s].
            #[getter]
            fn period(&self) -> f64 {
                self.inner.period()
            }
            /// Names of the parameter columns of the map Jacobians.
            #[getter]
            fn param_names(&self) -> Vec<&'static str> {
                param_names(&self.inner)
            }
            /// The parameters as a dict {name: value} (the names of `with_param`).
            #[getter]
            fn params<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
                params_dict(py, &self.inner)
            }
            /// A copy with one parameter (a name of `params`) changed, validated.
            fn with_param(&self, name: &str, value: f64) -> PyResult<Self> {
                Ok(Self {
                    inner: with_named_param(&self.inner, name, value)?,
                })
            }
            /// The forces (a, r) at (t [s], state, velocity), in ẍ = a − sgn(ẋ) r.
            fn forces(&self, t: f64, x: f64, v: f64) -> PyResult<(f64, f64)> {
                forces(&self.inner, t, x, v)
            }
            fn __repr__(&self) -> String {
                repr($py_name, &self.inner)
            }
        }

        impl PySystem for $sys {
            fn to_object<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
                Ok(Bound::new(py, $py_ty { inner: *self })?.into_any())
            }
            fn into_system(self) -> System {
                System::$variant(self)
            }
        }
    };
}

oscillator_class!(
    /// A Coulomb-damped, harmonically forced linear oscillator (Den Hartog's problem):
    ///
    ///   ẍ + 2ξω₀ẋ + ω₀²x + μ sgn(ẋ) = F cos(2π f t)
    ///
    /// CoulombOscillator(omega0, xi, mu, force, f): omega0 [rad/s], xi [1], mu and force
    /// [acceleration units, e.g. m/s² for x in m], f [Hz]. The state is (x, ẋ).
    /// Parameters (and Jacobian columns): f, omega0, xi, mu, force. Raises InvalidParameterError
    /// for a non-finite or out-of-range value (omega0, f > 0; xi, mu >= 0).
    PyCoulomb,
    "CoulombOscillator",
    CoulombOscillator,
    Coulomb,
    (
        omega0: "Natural angular frequency ω₀ [rad/s].",
        xi: "Viscous damping ratio ξ [1].",
        mu: "Coulomb friction μ [acceleration units].",
        force: "Forcing amplitude F [acceleration units].",
        f: "Forcing frequency f [Hz]."
    )
);

oscillator_class!(
    /// A forced pendulum with viscous and dry friction:
    ///
    ///   θ̈ + γθ̇ + μ sgn(θ̇) + ω₀² sin θ = A cos(2π f t)
    ///
    /// ForcedPendulum(omega0, gamma, mu, amplitude, f): omega0 [rad/s], gamma [1/s], mu and
    /// amplitude [1/s²], f [Hz]. The state is (θ [rad], θ̇ [rad/s]).
    /// Parameters (and Jacobian columns): f, omega0, gamma, mu, amplitude. Raises
    /// InvalidParameterError for a non-finite or out-of-range value (omega0, f > 0; gamma, mu >= 0).
    PyPendulum,
    "ForcedPendulum",
    ForcedPendulum,
    Pendulum,
    (
        omega0: "Small-amplitude angular frequency ω₀ [rad/s].",
        gamma: "Viscous damping γ [1/s].",
        mu: "Dry friction μ [1/s²].",
        amplitude: "Forcing amplitude A [1/s²].",
        f: "Forcing frequency f [Hz]."
    )
);

/// A system of the module: converts back to its Python class and into [`System`], and names its
/// parameters (the built-in systems by their parameter type, a [`UserSystem`] by the user's names).
pub trait PySystem: Parametrised + Serialize + 'static {
    /// The Python object (Gear, CoulombOscillator, ForcedPendulum, UserSystem) of this system.
    fn to_object<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>>;
    /// The owned system as the module's enum.
    fn into_system(self) -> System;
    /// The parameter called `name`.
    fn param_by_name(&self, name: &str) -> gearbif::Result<Self::Param> {
        Self::Param::from_name(name)
    }
    /// The name of parameter `p`.
    fn param_label(&self, p: Self::Param) -> &'static str {
        p.name()
    }
    /// Every parameter with its value, in order.
    fn param_values(&self) -> Vec<(&'static str, f64)> {
        <Self::Param as Parameter>::ALL
            .iter()
            .map(|&p| (p.name(), self.param(p)))
            .collect()
    }
    /// The first exception a Python callback of the system raised (user systems only).
    fn take_error(&self) -> Option<PyErr> {
        None
    }
    /// The system ready to be continued in `p`: with `p` among its Jacobian columns (a recorded
    /// gear carries an active set of columns; every other system has them all).
    fn for_param(self, _p: Self::Param) -> gearbif::Result<Self> {
        Ok(self)
    }
}

impl PySystem for RecordedModel {
    fn to_object<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        Ok(Bound::new(
            py,
            PyModel {
                inner: self.clone(),
                covariance: Default::default(),
            },
        )?
        .into_any())
    }
    fn into_system(self) -> System {
        System::Recorded(self)
    }
    fn for_param(self, p: RecordedParam) -> gearbif::Result<Self> {
        self.with_column(p)
    }
}

impl PySystem for UserSystem {
    fn to_object<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        Ok(Bound::new(
            py,
            PyUserSystem {
                inner: self.clone(),
            },
        )?
        .into_any())
    }
    fn into_system(self) -> System {
        System::User(self)
    }
    fn param_by_name(&self, name: &str) -> gearbif::Result<UserParam> {
        self.param_index(name)
    }
    fn param_label(&self, p: UserParam) -> &'static str {
        UserSystem::param_label(self, p)
    }
    fn param_values(&self) -> Vec<(&'static str, f64)> {
        self.names()
            .iter()
            .enumerate()
            .map(|(k, n)| (*n, self.param(UserParam(k as u8))))
            .collect()
    }
    fn take_error(&self) -> Option<PyErr> {
        UserSystem::take_error(self)
    }
}

impl PySystem for Gear {
    fn to_object<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        Ok(Bound::new(py, PyGear { inner: *self })?.into_any())
    }
    fn into_system(self) -> System {
        System::Gear(self)
    }
}

/// The parameters of a system as a dict {name: value}, in order.
pub fn params_dict<'py, S: PySystem>(py: Python<'py>, s: &S) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for (name, v) in s.param_values() {
        d.set_item(name, v)?;
    }
    Ok(d)
}

/// `with_param` by name, validated.
pub fn with_named_param<S: PySystem>(s: &S, name: &str, value: f64) -> PyResult<S> {
    let p = s.param_by_name(name).py()?;
    s.with_param(p, value).py()
}

/// The forces (a, r) at a finite point.
fn forces<S: DrivenOscillator>(s: &S, t: f64, x: f64, v: f64) -> PyResult<(f64, f64)> {
    if !(t.is_finite() && x.is_finite() && v.is_finite()) {
        return Err(invalid(format!(
            "forces: t, x, v must be finite, got ({t}, {x}, {v})"
        )));
    }
    let f = s.forces(t, x, v);
    Ok((f.a, f.r))
}

/// `Name(p1=v1, p2=v2, …)` over the system's parameters.
fn repr<S: PySystem>(name: &str, s: &S) -> String {
    let args: Vec<String> = s
        .param_values()
        .iter()
        .map(|(n, v)| format!("{n}={v}"))
        .collect();
    format!("{name}({})", args.join(", "))
}

/// The names of a system's parameter columns.
pub fn param_names<S: DrivenOscillator + ?Sized>(s: &S) -> Vec<&'static str> {
    (0..s.n_params()).map(|k| s.param_name(k)).collect()
}

/// Any system of the module, owned (so computations can run without the interpreter lock).
// one System per call from Python: its size does not matter, and boxing the recorded gear would
// break the one generic code path of `dispatch!`
#[allow(clippy::large_enum_variant)]
#[derive(Clone)]
pub enum System {
    Gear(Gear),
    Coulomb(CoulombOscillator),
    Pendulum(ForcedPendulum),
    User(UserSystem),
    Recorded(RecordedModel),
}

/// Runs `$body` with `$s` bound to the concrete system inside a [`System`] (one generic code path
/// for every system).
macro_rules! dispatch {
    ($sys:expr, $s:ident => $body:expr) => {
        match $sys {
            $crate::systems::System::Gear($s) => $body,
            $crate::systems::System::Coulomb($s) => $body,
            $crate::systems::System::Pendulum($s) => $body,
            $crate::systems::System::User($s) => $body,
            $crate::systems::System::Recorded($s) => $body,
        }
    };
}
pub(crate) use dispatch;

impl System {
    /// The system as the library's trait object.
    pub fn dynsys(&self) -> &dyn DrivenOscillator {
        dispatch!(self, s => s)
    }
    /// The first exception a Python callback raised during a computation (user systems), else
    /// the library's result.
    pub fn finish<T>(&self, r: gearbif::Result<T>) -> PyResult<T> {
        match dispatch!(self, s => s.take_error()) {
            Some(e) => Err(e),
            None => r.py(),
        }
    }
    /// The default winding of an orbit: 1 for the gears (the lock), 0 for the oscillators.
    pub fn default_winding(&self) -> i32 {
        match self {
            System::Gear(_) | System::Recorded(_) => 1,
            _ => 0,
        }
    }
}

/// Extracts a system (Gear, CoulombOscillator or ForcedPendulum).
pub fn system(obj: &Bound<'_, PyAny>) -> PyResult<System> {
    if let Ok(g) = obj.cast::<PyGear>() {
        return Ok(System::Gear(g.get().inner));
    }
    if let Ok(c) = obj.cast::<PyCoulomb>() {
        return Ok(System::Coulomb(c.get().inner));
    }
    if let Ok(p) = obj.cast::<PyPendulum>() {
        return Ok(System::Pendulum(p.get().inner));
    }
    if let Ok(u) = obj.cast::<PyUserSystem>() {
        return Ok(System::User(u.get().inner.clone()));
    }
    if let Ok(m) = obj.cast::<PyModel>() {
        return Ok(System::Recorded(m.get().inner.clone()));
    }
    Err(invalid(format!(
        "expected a gearbif system (Gear, CoulombOscillator, ForcedPendulum, UserSystem, Model), got {}",
        obj.get_type().name()?
    )))
}

/// Extracts a gear (for the gear's own functions: the lock, the lock-loss boundary, the paper's
/// sweep protocol).
pub fn gear(obj: &Bound<'_, PyAny>) -> PyResult<Gear> {
    match system(obj)? {
        System::Gear(g) => Ok(g),
        _ => Err(crate::errors::Kind::Unsupported
            .err("this function is implemented for the gear (gearbif.Gear) only")),
    }
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyGearParams>()?;
    m.add_class::<PyGear>()?;
    m.add_class::<PyCoulomb>()?;
    m.add_class::<PyPendulum>()?;
    m.add_class::<PyUserSystem>()?;
    m.add_class::<PyModel>()?;
    Ok(())
}
