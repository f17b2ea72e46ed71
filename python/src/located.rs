//! `Model.locate`: a special point of a recorded gear located on its augmented system, with its
//! σ from the model file's covariance (the implicit-function theorem,
//! `gearbif::analysis::uncertainty::located_sigma`; docs/recorded_gear.md).

use crate::convert::{complex2, vec2};
use crate::dynamics::{orbit_spec, shooting};
use crate::errors::{invalid, IntoPyResult};
use gearbif::analysis::uncertainty::located_sigma;
use gearbif::continuation::two_param::locate_augmented_with;
use gearbif::continuation::SpecialKind;
use gearbif::integrator::DEFAULT_METHOD;
use gearbif::model::params::{Parameter, Parametrised};
use gearbif::model::recorded::file::Covariance;
use gearbif::model::recorded::{RecordedModel, RecordedParam};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The kind of a special point by its name.
fn kind(s: &str) -> PyResult<SpecialKind> {
    Ok(match s {
        "fold" => SpecialKind::Fold,
        "flip" => SpecialKind::Flip,
        "sb" | "symmetry_breaking" => SpecialKind::SymmetryBreaking,
        "ns" | "neimark_sacker" => SpecialKind::NeimarkSacker,
        _ => {
            return Err(invalid(format!(
                "kind `{s}`: expected \"fold\", \"flip\", \"sb\" or \"ns\""
            )))
        }
    })
}

/// The located point as a dict (keys: kind, param, value, x, multipliers, precision, sigma,
/// gradient {name: dλ/dp}, omitted [names]).
#[allow(clippy::too_many_arguments)]
pub fn locate<'py>(
    py: Python<'py>,
    model: &RecordedModel,
    cov: &Covariance,
    kind_name: &str,
    x: [f64; 2],
    (param, section, iterations, winding): (&str, &str, i64, i32),
    tol: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let k = kind(kind_name)?;
    let p = RecordedParam::from_name(param).py()?;
    let spec = orbit_spec(section, iterations, winding)?;
    let opts = shooting(tol, 1e-9, 30)?;
    let m = model.clone().with_column(p).py()?;
    let lam = m.param(p);
    let (pt, s) = py
        .detach(|| {
            let pt = locate_augmented_with(&DEFAULT_METHOD, &m, &spec, k, p, x, lam, &opts)?;
            let s = located_sigma(&DEFAULT_METHOD, &m, cov, &spec, k, (p, None), &pt, &opts)?;
            Ok::<_, gearbif::Error>((pt, s))
        })
        .py()?;
    let d = PyDict::new(py);
    d.set_item("kind", kind_name)?;
    d.set_item("param", p.name())?;
    d.set_item("value", pt.free)?;
    d.set_item("x", vec2(py, pt.x))?;
    d.set_item("multipliers", complex2(py, pt.floquet.multipliers))?;
    d.set_item("precision", pt.precision)?;
    d.set_item("sigma", s.sigma)?;
    let g = PyDict::new(py);
    for q in &s.gradient {
        g.set_item(q.name, q.derivative)?;
    }
    d.set_item("gradient", g)?;
    d.set_item("omitted", s.omitted.clone())?;
    Ok(d)
}
