//! Simulation, Poincaré maps with Jacobians, and periodic orbits by shooting.

use crate::convert::{complex2, count, floats, mat2, rows, state, to_python, vec2};
use crate::errors::invalid;
use crate::systems::{param_names, system as extract_system, System};
use gearbif::integrator::{
    EventDriven, EventDriven853, FlowMethod, FlowOptions, Mode, Sensitivity,
};
use gearbif::maps::{poincare_map as map, Section};
use gearbif::orbits::{OrbitSpec, PeriodicOrbit, ShootingOptions};
use gearbif::sweep::Method;
use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyAny, PyDict};

/// Parses a section name: "stroboscopic" (P_T; also "strob", "P") or "half_period" (G; also
/// "sym", "G").
pub fn parse_section(s: &str) -> PyResult<Section> {
    match s {
        "stroboscopic" | "strob" | "P" => Ok(Section::Stroboscopic),
        "half_period" | "sym" | "G" => Ok(Section::HalfPeriod),
        _ => Err(invalid(format!(
            "section `{s}`: expected \"stroboscopic\" (P_T) or \"half_period\" (G)"
        ))),
    }
}

/// The `method=` keyword: "dop853" (the event-driven Dormand–Prince 8(5,3), the default, as the
/// CLI's `--method`) or "event" (the event-driven Dormand–Prince 5(4)).
pub fn parse_method(s: &str) -> PyResult<Method> {
    match s {
        "dop853" => Ok(Method::EventDriven853),
        "event" => Ok(Method::EventDriven),
        _ => Err(invalid(format!(
            "method `{s}`: expected \"dop853\" (event-driven DOP853) or \"event\" (event-driven DP5)"
        ))),
    }
}

fn section_name(s: Section) -> &'static str {
    match s {
        Section::Stroboscopic => "stroboscopic",
        Section::HalfPeriod => "half_period",
    }
}

fn mode_name(m: Mode) -> &'static str {
    match m {
        Mode::Positive => "positive",
        Mode::Negative => "negative",
        Mode::Stick => "stick",
    }
}

/// Checks an integrator tolerance: in (0, 1).
pub fn check_tol(tol: f64) -> PyResult<()> {
    if tol > 0.0 && tol < 1.0 {
        Ok(())
    } else {
        Err(crate::errors::to_py(gearbif::Error::InvalidParameter {
            name: "tol",
            value: tol,
            reason: "must be in (0, 1)",
        }))
    }
}

/// Integrates a system exactly (event-driven Filippov integration, Dormand–Prince 8(5,3) by
/// default, with the crossings, stick phases and releases on ω = 0 located to the tolerance).
///
/// simulate(system, x0, t_end, *, t0=0.0, samples_per_period=50, sample_times=None, tol=1e-9,
///          method="dop853", jacobians=False)
///
/// x0 = (β [rad], ω [rad/s]) at t0 [s]; the trajectory is sampled at sample_times [s] (sorted, in
/// [t0, t_end]) or on a uniform grid of samples_per_period points per drive period. tol is the
/// relative local error tolerance (absolute 1e-3·tol). method: "dop853" (event-driven
/// Dormand–Prince 8(5,3), faster at every tolerance) or "event" (event-driven Dormand–Prince 5(4)),
/// as the CLI's --method.
///
/// Returns a dict: t [s], beta [rad, on the lift], omega [rad/s] (numpy arrays), for the gear also
/// alpha [rad] = 2πft + α₀ and delta = beta − alpha [rad]; events (list of dicts: t [s],
/// beta [rad], kind = crossing | stick_start | release | graze, and the sides from/to/side);
/// x_end (numpy), mode at t_end (positive | negative | stick), stats (work counters). With
/// jacobians=True also jac, an (n, 2, 2) numpy array: ∂(β, ω)(tᵢ)/∂(β₀, ω₀) at every sample (the
/// variational equations on the continuous extension, with the saltation matrices of the events
/// before tᵢ; constant during a stick phase), e.g. for a Gauss–Newton fit of an initial state.
#[pyfunction]
#[pyo3(signature = (system, x0, t_end, *, t0=0.0, samples_per_period=50, sample_times=None, tol=1e-9, method="dop853", jacobians=false))]
#[allow(clippy::too_many_arguments)]
fn simulate<'py>(
    py: Python<'py>,
    system: &Bound<'py, PyAny>,
    x0: &Bound<'py, PyAny>,
    t_end: f64,
    t0: f64,
    samples_per_period: i64,
    sample_times: Option<&Bound<'py, PyAny>>,
    tol: f64,
    method: &str,
    jacobians: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let sys = extract_system(system)?;
    let x0 = state(x0, "x0")?;
    check_tol(tol)?;
    let method = parse_method(method)?;
    if !(t0.is_finite() && t_end.is_finite() && t_end >= t0) {
        return Err(invalid(format!(
            "need finite t0 <= t_end, got t0 = {t0}, t_end = {t_end}"
        )));
    }
    let times = match sample_times {
        Some(v) => {
            let v = floats(v, "sample_times")?;
            if v.windows(2).any(|w| w[0] > w[1]) {
                return Err(invalid("sample_times must be sorted"));
            }
            v
        }
        None => {
            let per = count(samples_per_period, "samples_per_period", 1)?;
            let dt = sys.dynsys().period() / per as f64;
            let n = ((t_end - t0) / dt + 1e-9).floor() as usize;
            if n > 50_000_000 {
                return Err(invalid("more than 5e7 samples requested"));
            }
            (0..=n).map(|i| t0 + i as f64 * dt).collect()
        }
    };
    if times.iter().any(|&t| t < t0 || t > t_end) {
        return Err(invalid("sample_times must lie in [t0, t_end]"));
    }
    let opts = FlowOptions::with_tol(tol)
        .record_events(true)
        .samples(times)
        .sensitivity(if jacobians {
            Sensitivity::State
        } else {
            Sensitivity::None
        });
    let r = py.detach(|| match method {
        Method::EventDriven => EventDriven.flow(sys.dynsys(), t0, x0, t_end, &opts),
        _ => EventDriven853.flow(sys.dynsys(), t0, x0, t_end, &opts),
    });
    let flow = sys.finish(r)?;
    let d = PyDict::new(py);
    let t: Vec<f64> = flow.samples.iter().map(|s| s.t).collect();
    let beta: Vec<f64> = flow.samples.iter().map(|s| s.beta).collect();
    if let System::Gear(g) = &sys {
        let alpha: Vec<f64> = t.iter().map(|&t| g.alpha(t)).collect();
        let delta: Vec<f64> = beta.iter().zip(&alpha).map(|(b, a)| b - a).collect();
        d.set_item("alpha", PyArray1::from_vec(py, alpha))?;
        d.set_item("delta", PyArray1::from_vec(py, delta))?;
    }
    d.set_item("t", PyArray1::from_vec(py, t))?;
    d.set_item("beta", PyArray1::from_vec(py, beta))?;
    d.set_item(
        "omega",
        PyArray1::from_vec(py, flow.samples.iter().map(|s| s.omega).collect()),
    )?;
    if jacobians {
        let n = flow.sample_jacobians.len();
        let flat: Vec<f64> = flow
            .sample_jacobians
            .iter()
            .flat_map(|j| [j[(0, 0)], j[(0, 1)], j[(1, 0)], j[(1, 1)]])
            .collect();
        let jac = PyArray1::from_vec(py, flat)
            .reshape([n, 2, 2])
            .expect("4n elements reshape to (n, 2, 2)");
        d.set_item("jac", jac)?;
    }
    d.set_item("events", to_python(py, &flow.events)?)?;
    d.set_item("x_end", vec2(py, flow.x))?;
    d.set_item("mode", mode_name(flow.mode))?;
    d.set_item("stats", to_python(py, &flow.stats)?)?;
    Ok(d)
}

/// Applies a Poincaré map `iterations` times, with its Jacobians (variational equations with
/// saltation matrices at every event).
///
/// poincare_map(system, x, *, section="stroboscopic", iterations=1, tol=1e-10, jacobians=True,
///              method="dop853")
///
/// section: "stroboscopic" = P_T: x(0) ↦ x(T) on the lift, or "half_period" = G = R⁻¹ ∘ P_{T/2}
/// (systems with a half-period symmetry R; for the gear R(β, ω) = (β + π, ω), P_T = R² ∘ G²).
/// x = (β [rad], ω [rad/s]) at t = 0. method: "dop853" (event-driven Dormand–Prince 8(5,3)) or
/// "event" (event-driven Dormand–Prince 5(4)), as in `simulate`.
///
/// Returns a dict: x (image, numpy), jac_x = ∂map/∂x (2×2), jac_p = total ∂map/∂p (2×n, columns
/// param_names, including the period's dependence on f), multipliers (complex eigenvalues of
/// jac_x, largest modulus first), trace, det, mode, events (list of dicts), stats.
#[pyfunction]
#[pyo3(signature = (system, x, *, section="stroboscopic", iterations=1, tol=1e-10, jacobians=true, method="dop853"))]
#[allow(clippy::too_many_arguments)]
fn poincare_map<'py>(
    py: Python<'py>,
    system: &Bound<'py, PyAny>,
    x: &Bound<'py, PyAny>,
    section: &str,
    iterations: i64,
    tol: f64,
    jacobians: bool,
    method: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let method = parse_method(method)?;
    let sys = extract_system(system)?;
    let x = state(x, "x")?;
    let section = parse_section(section)?;
    let iterations = count(iterations, "iterations", 1)?;
    check_tol(tol)?;
    let opts = FlowOptions::with_tol(tol)
        .record_events(true)
        .sensitivity(if jacobians {
            Sensitivity::StateAndParams
        } else {
            Sensitivity::None
        });
    let r = py.detach(|| match method {
        Method::EventDriven => map(&EventDriven, sys.dynsys(), section, x, iterations, &opts),
        _ => map(&EventDriven853, sys.dynsys(), section, x, iterations, &opts),
    });
    let img = sys.finish(r)?;
    let d = PyDict::new(py);
    d.set_item("x", vec2(py, img.x))?;
    if let Some(j) = &img.jac_x {
        let fl = gearbif::orbits::Floquet::of(j);
        d.set_item("jac_x", mat2(py, j))?;
        d.set_item("multipliers", complex2(py, fl.multipliers))?;
        d.set_item("trace", fl.trace)?;
        d.set_item("det", fl.det)?;
    }
    if let Some(j) = &img.jac_p {
        d.set_item("jac_p", rows(py, 2, j.ncols(), |i, k| j[(i, k)]))?;
    }
    d.set_item("param_names", param_names(sys.dynsys()))?;
    d.set_item("mode", mode_name(img.mode))?;
    d.set_item("events", to_python(py, &img.events)?)?;
    d.set_item("stats", to_python(py, &img.stats)?)?;
    Ok(d)
}

/// Eigenvalues (Floquet multipliers) of a 2×2 map Jacobian (numpy array or nested sequence),
/// largest modulus first, as a complex numpy array (computed from trace and determinant without
/// cancellation). Raises InvalidInputError unless the Jacobian is a finite 2×2 matrix.
#[pyfunction]
fn multipliers<'py>(
    py: Python<'py>,
    jac: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray1<numpy::Complex64>>> {
    let bad = || invalid("the Jacobian must be a finite 2×2 matrix");
    let a: Vec<Vec<f64>> = jac.extract().map_err(|_| bad())?;
    if a.len() != 2
        || a.iter()
            .any(|r| r.len() != 2 || !r.iter().all(|x| x.is_finite()))
    {
        return Err(bad());
    }
    let m = nalgebra::Matrix2::new(a[0][0], a[0][1], a[1][0], a[1][1]);
    Ok(complex2(py, gearbif::orbits::Floquet::of(&m).multipliers))
}

/// An orbit as a dict: x (numpy), multipliers of the orbit's map (complex numpy), stroboscopic
/// multipliers (of P_T^k; squares of G's for a symmetric orbit), stable, trace, det, events
/// (crossings, sticks, grazes per application of the map), residual, newton_iterations, spec.
pub fn orbit_dict<'py>(py: Python<'py>, o: &PeriodicOrbit) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("x", vec2(py, o.x))?;
    d.set_item("multipliers", complex2(py, o.floquet.multipliers))?;
    d.set_item(
        "stroboscopic_multipliers",
        complex2(py, o.stroboscopic_multipliers()),
    )?;
    d.set_item("stable", o.floquet.stable)?;
    d.set_item("trace", o.floquet.trace)?;
    d.set_item("det", o.floquet.det)?;
    d.set_item("events", to_python(py, &o.events)?)?;
    d.set_item("residual", o.residual)?;
    d.set_item("newton_iterations", o.newton_iterations)?;
    d.set_item("spec", spec_dict(py, &o.spec)?)?;
    Ok(d)
}

pub fn spec_dict<'py>(py: Python<'py>, s: &OrbitSpec) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("section", section_name(s.section))?;
    d.set_item("iterations", s.iterations)?;
    d.set_item("winding", s.winding)?;
    Ok(d)
}

/// The orbit problem: `section` with `iterations` and `winding`.
pub fn orbit_spec(section: &str, iterations: i64, winding: i32) -> PyResult<OrbitSpec> {
    let iterations = count(iterations, "iterations", 1)?;
    Ok(match parse_section(section)? {
        Section::Stroboscopic => OrbitSpec::stroboscopic(iterations, winding),
        Section::HalfPeriod => OrbitSpec {
            section: Section::HalfPeriod,
            iterations,
            winding,
        },
    })
}

/// Shooting options, validated.
pub fn shooting(tol: f64, newton_tol: f64, max_iter: i64) -> PyResult<ShootingOptions> {
    check_tol(tol)?;
    let max_iter = count(max_iter, "max_iter", 0)?;
    if !(newton_tol > 0.0 && newton_tol.is_finite()) {
        return Err(invalid("newton_tol must be > 0"));
    }
    Ok(ShootingOptions {
        tol,
        newton_tol,
        max_iter,
    })
}

/// A periodic orbit by Newton shooting on a Poincaré map: a zero of F(x) = Pᵏ(x) − x − (s, 0).
///
/// shoot(system, x0, *, section="half_period", iterations=1, winding=None, tol=1e-11,
///       newton_tol=1e-9, max_iter=30)
///
/// section "half_period": a symmetric orbit, fixed point of G with `winding` turns of β per drive
/// period (s = π·winding − π for the gear); "stroboscopic": a period-`iterations` orbit of P_T
/// with `winding` turns over the `iterations` periods (s = 2π·winding). winding defaults to 1 for
/// the gear (the lock) and 0 for the oscillators (x → −x symmetric orbits have winding 0).
/// x0 = (β [rad], ω [rad/s]).
/// tol: integrator tolerance; newton_tol: residual and step norm at convergence.
///
/// Returns a dict (see `orbit_dict`): x, multipliers, stroboscopic_multipliers, stable, trace,
/// det, events, residual, newton_iterations, spec. Raises NewtonError if Newton fails.
#[pyfunction]
#[pyo3(signature = (system, x0, *, section="half_period", iterations=1, winding=None, tol=1e-11, newton_tol=1e-9, max_iter=30))]
#[allow(clippy::too_many_arguments)]
fn shoot<'py>(
    py: Python<'py>,
    system: &Bound<'py, PyAny>,
    x0: &Bound<'py, PyAny>,
    section: &str,
    iterations: i64,
    winding: Option<i32>,
    tol: f64,
    newton_tol: f64,
    max_iter: i64,
) -> PyResult<Bound<'py, PyDict>> {
    let sys = extract_system(system)?;
    let x0 = state(x0, "x0")?;
    let spec = orbit_spec(
        section,
        iterations,
        winding.unwrap_or(sys.default_winding()),
    )?;
    let opts = shooting(tol, newton_tol, max_iter)?;
    let r = py.detach(|| gearbif::orbits::shoot(sys.dynsys(), &spec, x0, &opts));
    let o = sys.finish(r)?;
    orbit_dict(py, &o)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    m.add_function(wrap_pyfunction!(poincare_map, m)?)?;
    m.add_function(wrap_pyfunction!(multipliers, m)?)?;
    m.add_function(wrap_pyfunction!(shoot, m)?)?;
    Ok(())
}
