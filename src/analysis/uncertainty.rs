//! σ of a special point located on a recorded gear, from the covariance of its model file
//! (`model.json`, [`crate::model::recorded::file`]): the implicit-function gradient dλ*/dp of
//! [`crate::continuation::sensitivity::point_gradient`] over the covariance's gear parameters,
//! and σ_λ² = (dλ*/dp)ᵀ C (dλ*/dp) with C the covariance restricted to them (the marginal
//! covariance of a subset is its submatrix).
//!
//! Left out of C, and listed as such: the located parameter itself (λ* does not depend on its own
//! fitted value), the stepped parameter of a two-parameter curve (a coordinate of the point, not
//! an uncertain input), the measurement model's latency (not in the dynamics) and parameters without
//! an analytic column (the load weights). A model carries at most [`MAX_PARAMS`] columns, so the
//! gradient is taken in groups of `MAX_PARAMS − 1` parameters beside λ.

use crate::continuation::sensitivity::{linear_sigma, point_gradient};
use crate::continuation::two_param::CurvePoint;
use crate::continuation::SpecialKind;
use crate::error::Result;
use crate::integrator::FlowMethod;
use crate::model::recorded::file::Covariance;
use crate::model::recorded::{RecordedModel, RecordedParam};
use crate::model::{Parameter, Parametrised, MAX_PARAMS};
use crate::orbits::{OrbitSpec, ShootingOptions};
use nalgebra::DMatrix;
use serde::Serialize;

/// σ of a located point and what it is made of.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LocatedSigma {
    /// First-order standard deviation of the located parameter, in its unit.
    pub sigma: f64,
    /// dλ*/dp for each parameter of the covariance that enters.
    pub gradient: Vec<ParamDerivative>,
    /// Names of the covariance that do not enter (module docs: why).
    pub omitted: Vec<String>,
}

/// dλ*/dp of one parameter.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ParamDerivative {
    /// The parameter's lens name.
    pub name: &'static str,
    /// dλ*/dp.
    pub derivative: f64,
}

/// σ of `point` (of kind `kind`, solved for `free` on the orbit problem `spec` of `model`; on a
/// two-parameter curve `along` is the stepped parameter, at `point.along`) from the covariance
/// `cov` of the model file, with the map integrated by `method` (module docs).
#[allow(clippy::too_many_arguments)]
pub fn located_sigma<M: FlowMethod<RecordedModel>>(
    method: &M,
    model: &RecordedModel,
    cov: &Covariance,
    spec: &OrbitSpec,
    kind: SpecialKind,
    (free, along): (RecordedParam, Option<RecordedParam>),
    point: &CurvePoint,
    opts: &ShootingOptions,
) -> Result<LocatedSigma> {
    let model = match along {
        Some(q) => model.with_param(q, point.along)?,
        None => model.clone(),
    };
    let mut used: Vec<(usize, RecordedParam)> = Vec::new();
    let mut omitted = Vec::new();
    for (i, name) in cov.names.iter().enumerate() {
        match RecordedParam::from_name(name) {
            Ok(p) if p != free && Some(p) != along && model.clone().with_column(p).is_ok() => {
                used.push((i, p))
            }
            _ => omitted.push(name.clone()),
        }
    }
    let mut gradient = Vec::with_capacity(used.len());
    for group in used.chunks(MAX_PARAMS - 1) {
        let params: Vec<RecordedParam> = group.iter().map(|&(_, p)| p).collect();
        let cols: Vec<RecordedParam> = std::iter::once(free).chain(params.clone()).collect();
        let m = model.clone().with_columns(&cols)?;
        let g = point_gradient(method, &m, spec, kind, free, point, &params, opts)?;
        gradient.extend(params.iter().zip(g).map(|(p, d)| ParamDerivative {
            name: p.name(),
            derivative: d,
        }));
    }
    let full = cov.matrix();
    let c = DMatrix::from_fn(used.len(), used.len(), |a, b| full[(used[a].0, used[b].0)]);
    let g: Vec<f64> = gradient.iter().map(|d| d.derivative).collect();
    Ok(LocatedSigma {
        sigma: linear_sigma(&g, &c)?,
        gradient,
        omitted,
    })
}

/// σ of the difference λ_a − λ_b of two located points over the covariance `cov`, from the
/// gradient of the difference d = ∇λ_a − ∇λ_b (σ² = dᵀ C d): `held_in_b` are parameters held
/// fixed in b's gear (switched off there), so λ_b does not depend on them and their entries of
/// ∇λ_b count as 0. A name without a derivative in a gradient contributes 0 to it.
pub fn difference_sigma(
    a: &LocatedSigma,
    b: &LocatedSigma,
    held_in_b: &[&str],
    cov: &Covariance,
) -> f64 {
    let of = |s: &LocatedSigma, name: &str| {
        s.gradient
            .iter()
            .find(|d| d.name == name)
            .map_or(0.0, |d| d.derivative)
    };
    let d: Vec<f64> = cov
        .names
        .iter()
        .map(|n| {
            let b_n = if held_in_b.contains(&n.as_str()) {
                0.0
            } else {
                of(b, n)
            };
            of(a, n) - b_n
        })
        .collect();
    let c = cov.matrix();
    let v = nalgebra::DVector::from_column_slice(&d);
    (v.transpose() * c * &v)[(0, 0)].max(0.0).sqrt()
}
