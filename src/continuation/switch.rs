//! Branch switching at a flip (onto the period-doubled branch on P_T^{2k}) or at a
//! symmetry-breaking point (onto one of the pair of asymmetric orbits on P_T), along the eigenvector
//! of the critical multiplier (numerics.md, "Floquet multipliers and bifurcations").

use super::branch::{Branch, SpecialPoint};
use super::pinned::new_spec;
use crate::error::{Error, Result};
use crate::integrator::{FlowMethod, DEFAULT_METHOD};
use crate::model::{Gear, Parameter, Parametrised};
use crate::orbits::{detect_period_with, shoot_with, OrbitSpec, PeriodicOrbit, ShootingOptions};
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

/// A start for a new branch after switching.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SwitchStart<S = Gear> {
    /// The system at the start value of the parameter.
    pub system: S,
    /// The new problem (P_T² after a flip, P_T after a symmetry-breaking point).
    pub spec: OrbitSpec,
    /// The orbit on the new branch.
    pub orbit: PeriodicOrbit,
    /// Distance of the new orbit from the old branch's orbit continued to the same parameter.
    pub separation: f64,
}

/// Switches branch at `special` of `branch` with the default integrator (the event-driven
/// DOP853, [`crate::integrator::DEFAULT_METHOD`]): shoots from
/// x* ± ε v at parameter values λ* ± dλ and returns the first orbit distinct from the old branch.
pub fn switch_branch<S: Parametrised>(
    branch: &Branch<S>,
    special: &SpecialPoint,
    dparam: f64,
    opts: &ShootingOptions,
) -> Result<SwitchStart<S>> {
    switch_branch_with(&DEFAULT_METHOD, branch, special, dparam, opts)
}

/// Distance of two orbits on the section, β modulo 2π.
fn separation(o: &PeriodicOrbit, old: &PeriodicOrbit) -> f64 {
    let db = (o.x[0] - old.x[0]).rem_euclid(TAU);
    db.min(TAU - db).hypot(o.x[1] - old.x[1])
}

/// [`switch_branch`] with the flow computed by `method`.
pub fn switch_branch_with<S: Parametrised, M: FlowMethod<S>>(
    method: &M,
    branch: &Branch<S>,
    special: &SpecialPoint,
    dparam: f64,
    opts: &ShootingOptions,
) -> Result<SwitchStart<S>> {
    let spec = new_spec(&branch.spec, special.kind)?;
    let v = special.eigenvector.ok_or(Error::MissingEigenvector {
        kind: special.kind.label(),
        param: special.param,
    })?;
    let mut last_err = None;
    for &dl in &[dparam, -dparam, 10.0 * dparam, -10.0 * dparam] {
        let system = branch.system.with_param(branch.param, special.param + dl)?;
        // the old orbit at this parameter, for the separation test
        let Ok(old) = shoot_with(method, &system, &branch.spec, special.x, opts) else {
            continue;
        };
        let perturbed = |eps: f64, sgn: f64| {
            [
                special.x[0] + sgn * eps * v[0],
                special.x[1] + sgn * eps * v[1],
            ]
        };
        // Newton from a start; a new orbit must lie at least 1e-4 from the old one
        let mut attempt = |x0: [f64; 2]| -> Option<SwitchStart<S>> {
            match shoot_with(method, &system, &spec, x0, opts) {
                Ok(orbit) => {
                    let separation = separation(&orbit, &old);
                    (separation > 1e-4).then(|| SwitchStart {
                        system: system.clone(),
                        spec,
                        orbit,
                        separation,
                    })
                }
                Err(e) => {
                    last_err = Some(e);
                    None
                }
            }
        };
        // Newton from x* ± εv
        for &eps in &[0.02, 0.05, 0.1, 0.2] {
            for sgn in [1.0, -1.0] {
                if let Some(start) = attempt(perturbed(eps, sgn)) {
                    return Ok(start);
                }
            }
        }
        // a stable new branch (supercritical case): relax a simulation from the perturbed state
        for sgn in [1.0, -1.0] {
            let Ok(d) = detect_period_with(
                method,
                &system,
                perturbed(0.05, sgn),
                300,
                spec.iterations,
                1e-3,
                opts.tol,
            ) else {
                continue;
            };
            if let Some(start) = attempt(d.x) {
                return Ok(start);
            }
        }
    }
    Err(Error::NoNewBranch {
        param: branch.param.name(),
        value: special.param,
        reason: last_err
            .map(|e| e.to_string())
            .unwrap_or_else(|| "only the old orbit was found".into()),
    })
}
