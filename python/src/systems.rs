//! The systems: the gear (built from its physical parameters or from reduced ones) and the other
//! driven oscillators with dry friction of the library, all usable by every function of the module.

use crate::convert::{complex2, to_python, vec2};
use crate::errors::{invalid, IntoPyResult};
use gearbif::model::gear::GearParam;
use gearbif::model::params::{Parameter, Parametrised};
use gearbif::model::{
    Convention, CoulombOscillator, DrivenOscillator, ForcedPendulum, Gear, GearParams,
};
use pyo3::prelude::*;
use pyo3::types::PyDict;

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
        let p = GearParam::from_name(name).py()?;
        Ok(Self {
            inner: Parametrised::with_param(&self.inner, p, value).py()?,
        })
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
    /// Raises UnsupportedError unless Δ = ±1, InvalidParameterError beyond f_c.
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
    fn forces(&self, t: f64, beta: f64, omega: f64) -> (f64, f64) {
        let f = self.inner.forces(t, beta, omega);
        (f.a, f.r)
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

/// A Coulomb-damped, harmonically forced linear oscillator (Den Hartog's problem):
///
///   ẍ + 2ξω₀ẋ + ω₀²x + μ sgn(ẋ) = F cos(2π f t)
///
/// CoulombOscillator(omega0, xi, mu, force, f): omega0 [rad/s], xi [1], mu and force
/// [acceleration units, e.g. m/s² for x in m], f [Hz]. The state is (x, ẋ).
/// Parameter columns of the map Jacobians: (f, omega0, xi, mu, force).
#[pyclass(name = "CoulombOscillator", module = "gearbif", frozen)]
#[derive(Clone)]
pub struct PyCoulomb {
    pub inner: CoulombOscillator,
}

#[pymethods]
impl PyCoulomb {
    #[new]
    fn new(omega0: f64, xi: f64, mu: f64, force: f64, f: f64) -> PyResult<Self> {
        Ok(Self {
            inner: CoulombOscillator::new(omega0, xi, mu, force, f).py()?,
        })
    }
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
    /// The forces (a, r) at (t, x, ẋ), in ẍ = a − sgn(ẋ) r.
    fn forces(&self, t: f64, x: f64, v: f64) -> (f64, f64) {
        let f = self.inner.forces(t, x, v);
        (f.a, f.r)
    }
    fn __repr__(&self) -> String {
        let o = &self.inner;
        format!(
            "CoulombOscillator(omega0={}, xi={}, mu={}, force={}, f={})",
            o.omega0, o.xi, o.mu, o.force, o.f
        )
    }
}

/// A forced pendulum with viscous and dry friction:
///
///   θ̈ + γθ̇ + μ sgn(θ̇) + ω₀² sin θ = A cos(2π f t)
///
/// ForcedPendulum(omega0, gamma, mu, amplitude, f): omega0 [rad/s], gamma [1/s], mu and amplitude
/// [1/s²], f [Hz]. The state is (θ [rad], θ̇ [rad/s]).
/// Parameter columns of the map Jacobians: (f, omega0, gamma, mu, amplitude).
#[pyclass(name = "ForcedPendulum", module = "gearbif", frozen)]
#[derive(Clone)]
pub struct PyPendulum {
    pub inner: ForcedPendulum,
}

#[pymethods]
impl PyPendulum {
    #[new]
    fn new(omega0: f64, gamma: f64, mu: f64, amplitude: f64, f: f64) -> PyResult<Self> {
        Ok(Self {
            inner: ForcedPendulum::new(omega0, gamma, mu, amplitude, f).py()?,
        })
    }
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
    /// The forces (a, r) at (t, θ, θ̇), in θ̈ = a − sgn(θ̇) r.
    fn forces(&self, t: f64, theta: f64, v: f64) -> (f64, f64) {
        let f = self.inner.forces(t, theta, v);
        (f.a, f.r)
    }
    fn __repr__(&self) -> String {
        let o = &self.inner;
        format!(
            "ForcedPendulum(omega0={}, gamma={}, mu={}, amplitude={}, f={})",
            o.omega0, o.gamma, o.mu, o.amplitude, o.f
        )
    }
}

/// The names of a system's parameter columns.
pub fn param_names<S: DrivenOscillator + ?Sized>(s: &S) -> Vec<&'static str> {
    (0..s.n_params()).map(|k| s.param_name(k)).collect()
}

/// Any system of the module, owned (so computations can run without the interpreter lock).
pub enum System {
    Gear(Gear),
    Coulomb(CoulombOscillator),
    Pendulum(ForcedPendulum),
}

impl System {
    /// The system as the library's trait object.
    pub fn dynsys(&self) -> &dyn DrivenOscillator {
        match self {
            System::Gear(g) => g,
            System::Coulomb(c) => c,
            System::Pendulum(p) => p,
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
    Err(invalid(format!(
        "expected a gearbif system (Gear, CoulombOscillator, ForcedPendulum), got {}",
        obj.get_type().name()?
    )))
}

/// Extracts a gear (the continuation and the classification are for the gear only).
pub fn gear(obj: &Bound<'_, PyAny>) -> PyResult<Gear> {
    match system(obj)? {
        System::Gear(g) => Ok(g),
        _ => Err(crate::errors::UnsupportedError::new_err(
            "this function is implemented for the gear (gearbif.Gear) only",
        )),
    }
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyGearParams>()?;
    m.add_class::<PyGear>()?;
    m.add_class::<PyCoulomb>()?;
    m.add_class::<PyPendulum>()?;
    Ok(())
}
