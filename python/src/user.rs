//! A system defined in Python: the forces as a Python function, the parameters by name. It runs
//! through the same generic code as the built-in systems (simulation, maps with Jacobians,
//! shooting, continuation, classification, sweeps).
//!
//! The equations are those of every system of the library (docs/model.md):
//!
//!   β̇ = ω,   ω̇ = a(t, β, ω; p) − sgn(ω) r(t, β, ω; p),
//!
//! driven with period T = 1/f, f the parameter named `f` [Hz]. The derivatives the variational
//! equations need (∂a/∂β, ∂a/∂ω, ∂r/∂β, ∂r/∂ω and the parameter columns ∂a/∂p_k, ∂r/∂p_k at fixed
//! t) come from the user's `jacobian` function if given, else from central differences of `forces`
//! (step 1e-6 relative: about 1e-10 relative accuracy for smooth forces). Forces given as two
//! expressions instead of a function are compiled once into one instruction tape
//! ([`gearbif::model::expression`]): evaluated in Rust, with symbolic derivatives.

use crate::errors::{invalid, IntoPyResult};
use gearbif::model::expression::{Compiled, Constants};
use gearbif::model::{
    Column, DrivenOscillator, Forces, ForcesJet, HalfPeriodSymmetry, Parameter, Parametrised,
    MAX_PARAMS,
};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use serde::{Deserialize, Serialize};
use std::sync::{Arc, Mutex};

/// A parameter of a [`UserSystem`]: its index in the system's parameter list.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct UserParam(pub u8);

impl Parameter for UserParam {
    const ALL: &'static [Self] = &[
        UserParam(0),
        UserParam(1),
        UserParam(2),
        UserParam(3),
        UserParam(4),
        UserParam(5),
        UserParam(6),
        UserParam(7),
    ];
    /// Positional names; the system knows the user's names ([`UserSystem::param_index`]).
    fn name(self) -> &'static str {
        ["p0", "p1", "p2", "p3", "p4", "p5", "p6", "p7"][self.0 as usize % MAX_PARAMS]
    }
}

/// The Python functions of a user system and the first error they raised.
struct Callbacks {
    forces: Py<PyAny>,
    jacobian: Option<Py<PyAny>>,
    error: Mutex<Option<PyErr>>,
}

/// Where a user system's forces come from.
#[derive(Clone)]
enum Source {
    /// Python functions, called at every evaluation.
    Python(Arc<Callbacks>),
    /// Two expressions compiled once, evaluated in Rust, with the values of their terms that read
    /// the parameters only (recomputed when a parameter changes).
    Expressions(Arc<Compiled>, Constants),
}

/// A driven oscillator with dry friction whose forces are a Python function or two expressions.
#[derive(Clone)]
pub struct UserSystem {
    source: Source,
    /// Parameter names (leaked once per constructed system: the trait hands out `&'static str`).
    names: Arc<[&'static str]>,
    values: [f64; MAX_PARAMS],
    /// Index of the drive frequency `f` [Hz].
    f_index: usize,
    symmetry: Option<HalfPeriodSymmetry>,
    angular: bool,
}

impl UserSystem {
    /// Index of the parameter called `name`.
    pub fn param_index(&self, name: &str) -> gearbif::Result<UserParam> {
        self.names
            .iter()
            .position(|n| *n == name)
            .map(|k| UserParam(k as u8))
            .ok_or_else(|| gearbif::Error::UnknownParameter {
                name: name.to_string(),
                expected: self.names.join(", "),
            })
    }
    /// The user's name of `p`.
    pub fn param_label(&self, p: UserParam) -> &'static str {
        self.names.get(p.0 as usize).copied().unwrap_or("?")
    }
    /// The parameter names, in order.
    pub fn names(&self) -> &[&'static str] {
        &self.names
    }
    fn n(&self) -> usize {
        self.names.len()
    }
    /// Takes (and clears) the first error a callback raised.
    pub fn take_error(&self) -> Option<PyErr> {
        match &self.source {
            Source::Python(c) => c.error.lock().ok()?.take(),
            Source::Expressions(..) => None,
        }
    }
    fn record(&self, e: PyErr) {
        if let Source::Python(c) = &self.source {
            if let Ok(mut slot) = c.error.lock() {
                slot.get_or_insert(e);
            }
        }
    }
    /// Calls `f(t, x, v, p)` with p the dict of parameters, expecting `len` floats back.
    fn call(
        &self,
        f: &Py<PyAny>,
        values: &[f64; MAX_PARAMS],
        tx: [f64; 3],
        len: usize,
    ) -> Vec<f64> {
        let out = Python::attach(|py| -> PyResult<Vec<f64>> {
            let p = PyDict::new(py);
            for (k, name) in self.names.iter().enumerate() {
                p.set_item(*name, values[k])?;
            }
            let r = f.bind(py).call1((tx[0], tx[1], tx[2], p))?;
            let v = flatten(&r)?;
            if v.len() != len || !v.iter().all(|x| x.is_finite()) {
                return Err(invalid(format!(
                    "a user system's function must return {len} finite floats, got {v:?}"
                )));
            }
            Ok(v)
        });
        out.unwrap_or_else(|e| {
            self.record(e);
            vec![f64::NAN; len]
        })
    }
    /// The forces at parameter values `values` (the central differences of a Python `forces` vary
    /// them).
    fn forces_with(&self, values: &[f64; MAX_PARAMS], t: f64, x: f64, v: f64) -> (f64, f64) {
        match &self.source {
            Source::Python(c) => {
                let r = self.call(&c.forces, values, [t, x, v], 2);
                (r[0], r[1])
            }
            Source::Expressions(c, _) => c.forces(&c.constants(values), t, x, v),
        }
    }
}

/// The floats of a (possibly nested) tuple, list or numpy array, in order.
fn flatten(obj: &Bound<'_, PyAny>) -> PyResult<Vec<f64>> {
    if let Ok(x) = obj.extract::<f64>() {
        return Ok(vec![x]);
    }
    let mut out = Vec::new();
    for item in obj.try_iter()? {
        out.extend(flatten(&item?)?);
    }
    Ok(out)
}

impl Serialize for UserSystem {
    fn serialize<Se: serde::Serializer>(&self, s: Se) -> Result<Se::Ok, Se::Error> {
        use serde::ser::SerializeMap;
        let mut m = s.serialize_map(Some(self.n()))?;
        for (k, name) in self.names.iter().enumerate() {
            m.serialize_entry(name, &self.values[k])?;
        }
        m.end()
    }
}

impl Parametrised for UserSystem {
    type Param = UserParam;
    fn param(&self, p: UserParam) -> f64 {
        self.values.get(p.0 as usize).copied().unwrap_or(f64::NAN)
    }
    fn with_param(&self, p: UserParam, value: f64) -> gearbif::Result<Self> {
        let k = p.0 as usize;
        if k >= self.n() {
            return Err(gearbif::Error::NoParameterColumn { name: p.name() });
        }
        let name = self.names[k];
        let value = if k == self.f_index {
            check_f(value)?
        } else if value.is_finite() {
            value
        } else {
            return Err(gearbif::Error::InvalidParameter {
                name,
                value,
                reason: "must be finite",
            });
        };
        let mut s = self.clone();
        s.values[k] = value;
        if let Source::Expressions(c, constants) = &mut s.source {
            *constants = c.constants(&s.values);
        }
        Ok(s)
    }
    fn column(&self, p: UserParam) -> Option<Column> {
        ((p.0 as usize) < self.n()).then(|| Column::primary(p.0 as usize))
    }
}

fn check_f(f: f64) -> gearbif::Result<f64> {
    if f.is_finite() && f > 0.0 {
        Ok(f)
    } else {
        Err(gearbif::Error::InvalidParameter {
            name: "f",
            value: f,
            reason: "must be finite and > 0",
        })
    }
}

impl DrivenOscillator for UserSystem {
    fn period(&self) -> f64 {
        1.0 / self.values[self.f_index]
    }
    fn n_params(&self) -> usize {
        self.n()
    }
    fn param_name(&self, k: usize) -> &'static str {
        self.names.get(k).copied().unwrap_or("?")
    }
    fn period_derivative(&self, k: usize) -> f64 {
        if k == self.f_index {
            let f = self.values[k];
            -1.0 / (f * f)
        } else {
            0.0
        }
    }
    fn forces(&self, t: f64, beta: f64, omega: f64) -> Forces {
        let (a, r) = match &self.source {
            Source::Expressions(c, k) => c.forces(k, t, beta, omega),
            Source::Python(_) => self.forces_with(&self.values, t, beta, omega),
        };
        Forces { a, r }
    }
    fn forces_jet(&self, t: f64, beta: f64, omega: f64, params: bool) -> ForcesJet {
        let n = self.n();
        let callbacks = match &self.source {
            Source::Expressions(c, k) => return c.jet(k, t, beta, omega, params),
            Source::Python(c) => c,
        };
        if let Some(jac) = &callbacks.jacobian {
            // (a, a_beta, a_omega, r, r_beta, r_omega, a_p[0..n], r_p[0..n])
            let v = self.call(jac, &self.values, [t, beta, omega], 6 + 2 * n);
            let mut j = ForcesJet::new(v[0], v[3]);
            (j.a_beta, j.a_omega, j.r_beta, j.r_omega) = (v[1], v[2], v[4], v[5]);
            if params {
                j.a_p[..n].copy_from_slice(&v[6..6 + n]);
                j.r_p[..n].copy_from_slice(&v[6 + n..6 + 2 * n]);
            }
            return j;
        }
        // central differences of the forces
        let (a, r) = self.forces_with(&self.values, t, beta, omega);
        let mut j = ForcesJet::new(a, r);
        let diff = |dx: [f64; 2], h: f64| {
            let (ap, rp) = self.forces_with(&self.values, t, beta + dx[0], omega + dx[1]);
            let (am, rm) = self.forces_with(&self.values, t, beta - dx[0], omega - dx[1]);
            ((ap - am) / (2.0 * h), (rp - rm) / (2.0 * h))
        };
        let hb = 1e-6 * beta.abs().max(1.0);
        let ho = 1e-6 * omega.abs().max(1.0);
        (j.a_beta, j.r_beta) = diff([hb, 0.0], hb);
        (j.a_omega, j.r_omega) = diff([0.0, ho], ho);
        if params {
            for k in 0..n {
                let h = 1e-6 * self.values[k].abs().max(1.0);
                let (mut up, mut dn) = (self.values, self.values);
                up[k] += h;
                dn[k] -= h;
                let (ap, rp) = self.forces_with(&up, t, beta, omega);
                let (am, rm) = self.forces_with(&dn, t, beta, omega);
                j.a_p[k] = (ap - am) / (2.0 * h);
                j.r_p[k] = (rp - rm) / (2.0 * h);
            }
        }
        j
    }
    fn half_period_symmetry(&self) -> Option<HalfPeriodSymmetry> {
        self.symmetry
    }
    fn angular(&self) -> bool {
        self.angular
    }
}

/// A driven oscillator with dry friction defined in Python:
///
///   β̇ = ω,   ω̇ = a(t, β, ω; p) − sgn(ω) r(t, β, ω; p),   r ≥ 0,
///
/// UserSystem(forces, params, *, jacobian=None, symmetry=None, angular=True)
///
/// forces(t, beta, omega, p) → (a, r): the smooth acceleration a and the dry-friction magnitude r
/// (per unit inertia), p the dict {name: value} of the parameters. Or forces = (a, r), two
/// expressions in t [s], x (= β), v (= ω) and the parameters by name, e.g.
/// ("A*cos(2*PI*f*t) - gamma*v - w0^2*sin(x)", "mu"): compiled once, with their symbolic
/// derivatives, into one instruction tape evaluated in Rust (operators + - * / and ^ or **, with
/// -x^2 = -(x^2); functions sin cos tan asin acos atan sinh cosh tanh asinh acosh atanh exp
/// log (= ln) log2 log10 sqrt cbrt abs sgn; constants PI, TAU, E); within 3× of the same system written in Rust
/// (docs/tables/user-system-speed.md). params: dict {name: value}, at most 8, one of them `f`, the drive frequency [Hz] (period T = 1/f; the forces must be
/// T-periodic in t). jacobian(t, beta, omega, p) → (a, ∂a/∂β, ∂a/∂ω, r, ∂r/∂β, ∂r/∂ω,
/// ∂a/∂p (n values), ∂r/∂p (n values)) at fixed t, in the order of params; without it the
/// derivatives are central differences of `forces`. symmetry = (σ, c): a half-period symmetry
/// R(β, ω) = (σβ + c, σω) of the equations (σ = ±1), needed for section "half_period". angular:
/// β is an angle (orbits may wind), else a displacement.
///
/// It is accepted by every function that takes a system. An exception raised by `forces` or
/// `jacobian` is re-raised by the function that called them.
#[pyclass(name = "UserSystem", module = "gearbif", frozen)]
#[derive(Clone)]
pub struct PyUserSystem {
    pub inner: UserSystem,
}

#[pymethods]
impl PyUserSystem {
    #[new]
    #[pyo3(signature = (forces, params, *, jacobian=None, symmetry=None, angular=true))]
    fn new(
        forces: Bound<'_, PyAny>,
        params: &Bound<'_, PyDict>,
        jacobian: Option<Bound<'_, PyAny>>,
        symmetry: Option<(f64, f64)>,
        angular: bool,
    ) -> PyResult<Self> {
        let expressions: Option<(String, String)> = if forces.is_callable() {
            None
        } else {
            Some(forces.extract().map_err(|_| {
                invalid("forces must be a function (t, x, v, p) -> (a, r) or a pair of expressions (a, r)")
            })?)
        };
        if jacobian.as_ref().is_some_and(|j| !j.is_callable()) {
            return Err(invalid("jacobian must be callable"));
        }
        if expressions.is_some() && jacobian.is_some() {
            return Err(invalid(
                "forces given as expressions are differentiated symbolically: give no jacobian",
            ));
        }
        if params.len() > MAX_PARAMS {
            return Err(invalid(format!("at most {MAX_PARAMS} parameters")));
        }
        let mut names: Vec<&'static str> = Vec::new();
        let mut values = [0.0; MAX_PARAMS];
        for (k, (key, value)) in params.iter().enumerate() {
            let name: String = key
                .extract()
                .map_err(|_| invalid("parameter names must be strings"))?;
            let v: f64 = value
                .extract()
                .map_err(|_| invalid(format!("parameter `{name}` must be a float")))?;
            if !v.is_finite() {
                return Err(crate::errors::to_py(gearbif::Error::InvalidParameter {
                    name: "params",
                    value: v,
                    reason: "must be finite",
                }));
            }
            values[k] = v;
            names.push(Box::leak(name.into_boxed_str()));
        }
        let f_index = names
            .iter()
            .position(|n| *n == "f")
            .ok_or_else(|| invalid("params must contain the drive frequency `f` [Hz]"))?;
        check_f(values[f_index]).py()?;
        let symmetry = match symmetry {
            None => None,
            Some((sign, shift)) if (sign == 1.0 || sign == -1.0) && shift.is_finite() => {
                Some(HalfPeriodSymmetry { sign, shift })
            }
            Some(s) => {
                return Err(invalid(format!(
                    "symmetry must be (σ, c) with σ = ±1 and c finite, got {s:?}"
                )))
            }
        };
        let source = match expressions {
            Some((a, r)) => {
                let c = Compiled::new(&a, &r, &names).map_err(|e| invalid(e.to_string()))?;
                let constants = c.constants(&values);
                Source::Expressions(Arc::new(c), constants)
            }
            None => Source::Python(Arc::new(Callbacks {
                forces: forces.unbind(),
                jacobian: jacobian.map(Bound::unbind),
                error: Mutex::new(None),
            })),
        };
        Ok(Self {
            inner: UserSystem {
                source,
                names: names.into(),
                values,
                f_index,
                symmetry,
                angular,
            },
        })
    }
    /// Drive period T = 1/f [s].
    #[getter]
    fn period(&self) -> f64 {
        self.inner.period()
    }
    /// Names of the parameters (the Jacobian columns), in order.
    #[getter]
    fn param_names(&self) -> Vec<&'static str> {
        self.inner.names().to_vec()
    }
    /// The parameters as a dict {name: value}.
    #[getter]
    fn params<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for (k, name) in self.inner.names().iter().enumerate() {
            d.set_item(*name, self.inner.values[k])?;
        }
        Ok(d)
    }
    /// A copy with one parameter changed (validated: finite, f > 0).
    fn with_param(&self, name: &str, value: f64) -> PyResult<Self> {
        let p = self.inner.param_index(name).py()?;
        Ok(Self {
            inner: self.inner.with_param(p, value).py()?,
        })
    }
    /// The forces (a, r) at (t [s], β, ω), through the user's function.
    fn forces(&self, t: f64, beta: f64, omega: f64) -> PyResult<(f64, f64)> {
        if !(t.is_finite() && beta.is_finite() && omega.is_finite()) {
            return Err(invalid("forces: t, beta, omega must be finite"));
        }
        let f = self.inner.forces(t, beta, omega);
        match self.inner.take_error() {
            Some(e) => Err(e),
            None => Ok((f.a, f.r)),
        }
    }
    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        let p = self.params(py)?;
        Ok(format!(
            "UserSystem(params={})",
            PyTuple::new(py, [p])?.get_item(0)?.repr()?
        ))
    }
}
