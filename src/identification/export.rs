//! The diagnosed gear as a model file ([`crate::model::recorded::file`], model.json): the final
//! coefficients as a [`RecordedModel`], and the covariance of θ carried to the lens's named
//! parameters by the delta method, C = J Σ Jᵀ, J = ∂(named parameters)/∂θ by central
//! differences of the map θ → coefficients → lens (linear but for g, Δ = c_cs/g and the
//! compliance and drive offset, which the fit carries as χg² and −gε).

use super::diagnose::Diagnosis;
use super::spec::{coefficients, FittedTheta};
use crate::error::Result;
use crate::io::recordings::{GearSetup, Run, RunKind};
use crate::model::recorded::file::{Covariance, ModelFile, RecordedRange, LATENCY};
use crate::model::recorded::{Coefficients, Geometry, RecordedModel, RecordedParam};
use crate::model::{Parameter, Parametrised};
use nalgebra::DMatrix;

/// The model file of a diagnosis on the set-up `setup`. A drive offset's growth per turn (lost
/// steps) and a parameter drift are not part of a driven model: the file holds the gear at the
/// start of the session.
pub fn model_file(d: &Diagnosis, setup: &GearSetup) -> Result<ModelFile> {
    let geo = Geometry::new(setup.theta_deg.to_radians(), setup.phi_deg.to_radians());
    let model = driven(d.augmented, geo)?;
    let covariance = match &d.fitted {
        Some(fit) => named_covariance(fit, &d.augmented, geo)?,
        None => Covariance::default(),
    };
    let effects = d.report.findings.iter().map(|f| f.effect.clone()).collect();
    Ok(ModelFile::new(&model, covariance, effects, d.latency))
}

/// The range of drive frequencies of the driven runs of `runs` (model.json's `recorded`).
pub fn recorded_range(runs: &[Run]) -> Option<RecordedRange> {
    RecordedRange::of(runs.iter().filter_map(|r| match r.kind {
        RunKind::Driven { f_hz } => Some(f_hz),
        RunKind::Ringdown { .. } => None,
    }))
}

/// The coefficients as a driven model (f = 1 Hz: f is not written).
fn driven(c: Coefficients, geo: Geometry) -> Result<RecordedModel> {
    RecordedModel::new(
        Coefficients {
            alpha_offset_per_turn: 0.0,
            ..c
        },
        geo,
        1.0,
    )
}

/// The lens parameters (all but f) and the latency at θ: the vector the covariance is carried to.
fn named(fit: &FittedTheta, theta: &[f64], held: &Coefficients, geo: Geometry) -> Result<Vec<f64>> {
    let nt = fit.terms.len();
    let c = Coefficients {
        eta_static_excess: held.eta_static_excess,
        ..coefficients(&fit.terms, &theta[..nt])
    };
    let m = driven(c, geo)?;
    let mut v: Vec<f64> = lens_names().map(|p| m.param(p)).collect();
    v.push(if fit.fit_latency { theta[nt] } else { 0.0 });
    Ok(v)
}

/// Every lens parameter but f.
fn lens_names() -> impl Iterator<Item = RecordedParam> {
    RecordedParam::ALL
        .iter()
        .copied()
        .filter(|&p| p != RecordedParam::F)
}

/// C = J Σ Jᵀ over the named parameters that depend on θ (held entries of θ, with an infinite or
/// zero variance, contribute nothing).
fn named_covariance(fit: &FittedTheta, held: &Coefficients, geo: Geometry) -> Result<Covariance> {
    let n = fit.theta.len();
    let base = named(fit, &fit.theta, held, geo)?;
    let mut jac = DMatrix::zeros(base.len(), n);
    let mut sigma = DMatrix::zeros(n, n);
    let free: Vec<usize> = (0..n)
        .filter(|&k| fit.cov[(k, k)].is_finite() && fit.cov[(k, k)] > 0.0)
        .collect();
    for &k in &free {
        let h = 1e-4 * fit.cov[(k, k)].sqrt();
        let (mut tp, mut tm) = (fit.theta.clone(), fit.theta.clone());
        tp[k] += h;
        tm[k] -= h;
        let (vp, vm) = (named(fit, &tp, held, geo)?, named(fit, &tm, held, geo)?);
        for i in 0..base.len() {
            jac[(i, k)] = (vp[i] - vm[i]) / (2.0 * h);
        }
        for &l in &free {
            sigma[(k, l)] = fit.cov[(k, l)];
        }
    }
    let c = &jac * sigma * jac.transpose();
    let names: Vec<String> = lens_names()
        .map(|p| p.name().to_string())
        .chain([LATENCY.to_string()])
        .collect();
    let rows: Vec<usize> = (0..base.len())
        .filter(|&i| jac.row(i).iter().any(|&v| v != 0.0))
        .collect();
    Ok(Covariance {
        names: rows.iter().map(|&i| names[i].clone()).collect(),
        matrix: rows
            .iter()
            .map(|&i| {
                rows.iter()
                    .map(|&j| 0.5 * (c[(i, j)] + c[(j, i)]))
                    .collect()
            })
            .collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::identification::regression::BASE_TERMS;

    /// For the base terms (c_sc = −g, c_cs = gΔ, ζ, η) the propagated covariance is the exact
    /// linear transformation: var g = var c_sc, and Δ's to first order.
    #[test]
    fn base_covariance_is_the_delta_method() {
        let (g, d) = (300.0, 0.8);
        // θ in the order of BASE_TERMS: ζ, η, c_sc, c_cs
        let theta = vec![1.1, 23.0, -g, g * d];
        let mut cov =
            DMatrix::from_diagonal(&nalgebra::DVector::from_vec(vec![0.01, 1.0, 4.0, 9.0]));
        cov[(2, 3)] = 1.5;
        cov[(3, 2)] = 1.5;
        let fit = FittedTheta {
            terms: BASE_TERMS.to_vec(),
            fit_latency: false,
            theta,
            cov,
        };
        let held = Coefficients::default();
        let c = named_covariance(&fit, &held, Geometry::new(0.0, 0.0)).unwrap();
        assert_eq!(c.names, ["g", "delta", "zeta", "eta"]);
        // g = −c_sc, Δ = −c_cs/c_sc: ∂Δ/∂c_sc = c_cs/c_sc², ∂Δ/∂c_cs = −1/c_sc = 1/g
        let (dg_dsc, dd_dsc, dd_dcs) = (-1.0, g * d / (g * g), 1.0 / g);
        let var_g = 4.0;
        let var_d = dd_dsc * dd_dsc * 4.0 + dd_dcs * dd_dcs * 9.0 + 2.0 * dd_dsc * dd_dcs * 1.5;
        let cov_gd = dg_dsc * (dd_dsc * 4.0 + dd_dcs * 1.5);
        let m = &c.matrix;
        assert!((m[0][0] - var_g).abs() < 1e-8, "{}", m[0][0]);
        assert!(
            (m[1][1] - var_d).abs() < 1e-10 * var_d.max(1.0),
            "{} {var_d}",
            m[1][1]
        );
        assert!((m[0][1] - cov_gd).abs() < 1e-9, "{} {cov_gd}", m[0][1]);
        assert!((m[2][2] - 0.01).abs() < 1e-12 && (m[3][3] - 1.0).abs() < 1e-10);
        c.check("test").unwrap();
    }
}
