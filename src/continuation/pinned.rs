//! Branch switching with the amplitude pinned: the new branch's start is found at a given distance
//! from the bifurcating orbit along the critical eigenvector, with the parameter free, so it lands
//! on the side of the bifurcation point where the new branch exists without being told.

use super::identity::{section_distance, OrbitImages};
use super::minaug::linearise_map;
use super::{Branch, SpecialKind, SpecialPoint};
use crate::error::{Error, Result};
use crate::integrator::DEFAULT_METHOD;
use crate::model::{Parameter, Parametrised};
use crate::orbits::{shoot, OrbitSpec, PeriodicOrbit, ShootingOptions};
use nalgebra::{Matrix3, Vector3};

/// The problem on the new branch at a flip (P_T^{2k}) or symmetry-breaking point (P_T).
pub fn new_spec(old: &OrbitSpec, kind: SpecialKind) -> Result<OrbitSpec> {
    match kind {
        SpecialKind::Flip => Ok(OrbitSpec::stroboscopic(2 * old.iterations, 2 * old.winding)),
        SpecialKind::SymmetryBreaking => {
            let s = old.on_stroboscopic();
            Ok(OrbitSpec::stroboscopic(s.iterations, s.winding))
        }
        k => Err(Error::UnsupportedPoint {
            operation: "branch switching (implemented at flips and symmetry-breaking points)",
            kind: k.label(),
        }),
    }
}

/// Branch switching with the amplitude pinned: at a flip or symmetry-breaking point (x*, λ*) with
/// critical eigenvector v, solves the new problem `new_spec` for (x, λ) with
///
/// ```text
///   Pᵏ(x; λ) − x − (s, 0) = 0,   q · (x − x*, λ − λ*) = ε,
/// ```
///
/// q = (v, 0) minus its component along the parent branch's tangent, so the parent branch (also a
/// solution of the new problem) is excluded and λ lands by itself on the side where the new branch
/// exists (no direction to guess). ε runs through `offset` × (1, 0.3, 3, 0.1, 10) with both signs.
/// A solution counts only if it lies within 2 % of λ* and its orbit's primitive length (see
/// [`super::identity`]) is twice the parent's `parent_primitive` (the period-doubled or the
/// asymmetric orbit, not another orbit that also solves the new problem).
pub fn switch_pinned<S: Parametrised>(
    b: &Branch<S>,
    sp: &SpecialPoint,
    new_spec: &OrbitSpec,
    parent_primitive: usize,
    offset: f64,
    sh: &ShootingOptions,
) -> Result<(S, PeriodicOrbit)> {
    let v = sp.eigenvector.ok_or(Error::MissingEigenvector {
        kind: sp.kind.label(),
        param: sp.param,
    })?;
    let n = b.points.len();
    if n < 2 {
        return Err(Error::shape("points of the parent branch", ">= 2", n));
    }
    let i = sp.after_point.min(n - 2);
    let (pa, pb) = (&b.points[i], &b.points[i + 1]);
    let t = Vector3::new(pb.x[0] - pa.x[0], pb.x[1] - pa.x[1], pb.param - pa.param);
    let t = if t.norm() > 0.0 {
        t.normalize()
    } else {
        Vector3::z()
    };
    let e = Vector3::new(v[0], v[1], 0.0);
    let q = e - e.dot(&t) * t;
    if q.norm() < 1e-3 {
        return Err(Error::DegenerateDirection {
            what: "the critical eigenvector is tangent to the parent branch",
        });
    }
    let q = q.normalize();
    let mut last_err = None;
    for scale in [1.0, 0.3, 3.0, 0.1, 10.0] {
        for sgn in [1.0, -1.0] {
            let eps = sgn * scale * offset;
            let u0 = Vector3::new(sp.x[0], sp.x[1], sp.param) + eps * q;
            match pinned_newton(
                b,
                new_spec,
                Vector3::new(sp.x[0], sp.x[1], sp.param),
                q,
                eps,
                u0,
                sh,
            ) {
                Ok((gear, orbit)) => {
                    let lam = gear.param(b.param);
                    let near = (lam - sp.param).abs() < 0.02 * sp.param.abs().max(1.0);
                    let prim = OrbitImages::of(&gear, new_spec, orbit.x, sh.tol, 1e-6)
                        .map(|im| im.primitive)
                        .unwrap_or(0);
                    // must differ from the parent's orbit at the same parameter
                    let distinct = shoot(&gear, &b.spec, sp.x, sh)
                        .map(|old| section_distance(old.x, orbit.x, 1.0) > 0.1 * eps.abs())
                        .unwrap_or(false);
                    if near && distinct && prim == 2 * parent_primitive {
                        return Ok((gear, orbit));
                    }
                    last_err = Some(Error::NoNewBranch {
                        param: b.param.name(),
                        value: sp.param,
                        reason: format!(
                            "found one at {} = {lam} with primitive length {prim}, parent \
                             {parent_primitive}",
                            b.param.name()
                        ),
                    });
                }
                Err(e) => last_err = Some(e),
            }
        }
    }
    Err(last_err.unwrap_or_else(|| Error::NoNewBranch {
        param: b.param.name(),
        value: sp.param,
        reason: "no pinned Newton step was tried".into(),
    }))
}

/// Newton on {F_new(x, λ) = 0, q·(u − u*) = ε} from u0 = (x0, λ0).
fn pinned_newton<S: Parametrised>(
    b: &Branch<S>,
    spec: &OrbitSpec,
    ustar: Vector3<f64>,
    q: Vector3<f64>,
    eps: f64,
    u0: Vector3<f64>,
    sh: &ShootingOptions,
) -> Result<(S, PeriodicOrbit)> {
    let mut u = u0;
    for it in 0..sh.max_iter {
        let gear = b.system.with_param(b.param, u[2])?;
        let lin = linearise_map(&DEFAULT_METHOD, &gear, spec, [u[0], u[1]], &[b.param], sh)?;
        let (r, jac, fl) = (lin.residual, lin.jac, lin.columns[0]);
        let g = q.dot(&(u - ustar)) - eps;
        let a = Matrix3::new(
            jac[(0, 0)] - 1.0,
            jac[(0, 1)],
            fl[0],
            jac[(1, 0)],
            jac[(1, 1)] - 1.0,
            fl[1],
            q[0],
            q[1],
            q[2],
        );
        let du = a
            .lu()
            .solve(&Vector3::new(-r[0], -r[1], -g))
            .filter(|d| d.iter().all(|x| x.is_finite()))
            .ok_or_else(|| Error::NewtonFailed {
                iterations: it,
                residual: r[0].hypot(r[1]),
                reason: "singular pinned switching system".into(),
            })?;
        if r[0].hypot(r[1]) < sh.newton_tol && du.norm() < 10.0 * sh.newton_tol && g.abs() < 1e-12 {
            let orbit = shoot(&gear, spec, [u[0], u[1]], sh)?;
            return Ok((gear, orbit));
        }
        // keep the parameter step modest
        let cap = 0.05 * u[2].abs().max(0.1);
        let s = if du[2].abs() > cap {
            cap / du[2].abs()
        } else {
            1.0
        };
        u += s * du;
    }
    Err(Error::NewtonFailed {
        iterations: sh.max_iter,
        residual: f64::NAN,
        reason: "pinned branch switching".into(),
    })
}

/// [`switch_pinned`] at a flip or symmetry-breaking point `sp` of `b`, with the new problem and the
/// parent's primitive length worked out here; `amplitude` is ε.
pub fn switch_at<S: Parametrised>(
    b: &Branch<S>,
    sp: &SpecialPoint,
    amplitude: f64,
    sh: &ShootingOptions,
) -> Result<(S, PeriodicOrbit)> {
    let spec = new_spec(&b.spec, sp.kind)?;
    let sys = b.system.with_param(b.param, sp.param)?;
    let parent = OrbitImages::of(&sys, &b.spec, sp.x, sh.tol, 1e-6)?.primitive;
    switch_pinned(b, sp, &spec, parent, amplitude, sh)
}
