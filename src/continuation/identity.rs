//! Is this periodic orbit one already on a computed branch? Orbit identity modulo the half-period
//! symmetry R, the 2π lift of β and the choice of map (G, P_T, P_Tᵏ).
//!
//! An orbit with P_T-period K is represented by its *section images*: the states at t ≡ 0 (mod T)
//! of the orbit and of its symmetric twin, i.e. Gʲ(x) for j = 0 … 2K − 1 when the system has the
//! half-period symmetry (P_T = R²G² and G = R⁻¹P_{T/2}, so G(x) is the twin's point on the section),
//! or P_Tʲ(x) for j = 0 … K − 1 without it, with β reduced modulo 2π. Two orbits at the same
//! parameter are the same (up to symmetry) iff one's point lies among the other's images and both
//! have the same *primitive length* j₀ (the least j ≥ 1 with Gʲ(x) ≡ x): j₀ = 1 for a symmetric
//! orbit, 2 for an asymmetric T-periodic one, 4 after one period doubling, … The primitive length
//! keeps a period-2 branch from claiming the period-1 orbit that is also a fixed point of P_T².

use super::Branch;
use crate::error::Result;
use crate::integrator::{FlowOptions, DEFAULT_METHOD};
use crate::maps::{poincare_map, Section};
use crate::model::{DrivenOscillator, Parametrised};
use crate::orbits::{shoot, OrbitSpec, ShootingOptions};
use std::f64::consts::TAU;

/// Distance of two section states with β compared modulo 2π (ω in rad/s weighted by `omega_weight`).
pub fn section_distance(a: [f64; 2], b: [f64; 2], omega_weight: f64) -> f64 {
    let d = (a[0] - b[0]).rem_euclid(TAU);
    d.min(TAU - d).hypot(omega_weight * (a[1] - b[1]))
}

/// The section images of the orbit through `x` (see the module docs) and its primitive length j₀.
#[derive(Debug, Clone, PartialEq)]
pub struct OrbitImages {
    /// Gʲ(x) (or P_Tʲ(x)), j = 0 … n − 1.
    pub images: Vec<[f64; 2]>,
    /// Least j ≥ 1 with image j ≡ x (the number of images if none closes earlier).
    pub primitive: usize,
}

impl OrbitImages {
    /// Images of the orbit of `spec` through `x` in `sys`, integrated at tolerance `tol`; images
    /// closer than `close_tol` to x close the orbit.
    pub fn of<S: DrivenOscillator + ?Sized>(
        sys: &S,
        spec: &OrbitSpec,
        x: [f64; 2],
        tol: f64,
        close_tol: f64,
    ) -> Result<Self> {
        let k = spec.on_stroboscopic().iterations.max(1);
        let (section, n) = if sys.half_period_symmetry().is_some() {
            (Section::HalfPeriod, 2 * k)
        } else {
            (Section::Stroboscopic, k)
        };
        let o = FlowOptions::with_tol(tol);
        let mut images = vec![x];
        let mut y = x;
        let mut primitive = n;
        for j in 1..n {
            y = poincare_map(&DEFAULT_METHOD, sys, section, y, 1, &o)?.x;
            if primitive == n && section_distance(y, x, 1.0) < close_tol {
                primitive = j;
            }
            images.push(y);
        }
        Ok(Self { images, primitive })
    }

    /// Smallest section distance of `x` to one of the images.
    pub fn distance(&self, x: [f64; 2]) -> f64 {
        self.images
            .iter()
            .map(|y| section_distance(*y, x, 1.0))
            .fold(f64::INFINITY, f64::min)
    }
}

/// Options of the identity test.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IdentityOptions {
    /// Two converged orbits closer than this are the same.
    pub same_tol: f64,
    /// A branch point (interpolated) farther than this from every image is not examined further.
    pub coarse_tol: f64,
    /// Shooting used to put the known branch onto the parameter value.
    pub shooting: ShootingOptions,
}

impl Default for IdentityOptions {
    fn default() -> Self {
        Self {
            same_tol: 1e-6,
            coarse_tol: 0.1,
            shooting: ShootingOptions::default(),
        }
    }
}

/// Whether the orbit with images `orbit` (of `sys`, the system at the branch parameter `lam`) lies
/// on `branch`, a branch of orbits with primitive length `branch_primitive`: each stretch of the
/// branch that brackets `lam` is interpolated, and if it comes near an image, the branch's orbit
/// there is shot at `lam` exactly and compared.
pub fn lies_on_branch<S: Parametrised>(
    branch: &Branch<S>,
    branch_primitive: usize,
    lam: f64,
    orbit: &OrbitImages,
    opts: &IdentityOptions,
) -> Result<bool> {
    if orbit.primitive != branch_primitive {
        return Ok(false);
    }
    let gear = branch.system.with_param(branch.param, lam)?;
    let pts = &branch.points;
    for w in pts.windows(2) {
        let (a, b) = (&w[0], &w[1]);
        let (lo, hi) = (a.param.min(b.param), a.param.max(b.param));
        if !(lam >= lo && lam <= hi) {
            continue;
        }
        let s = if hi > lo {
            (lam - a.param) / (b.param - a.param)
        } else {
            0.0
        };
        let xi = [
            a.x[0] + s * (b.x[0] - a.x[0]),
            a.x[1] + s * (b.x[1] - a.x[1]),
        ];
        if orbit.distance(xi) > opts.coarse_tol * (1.0 + 0.1 * xi[1].abs()) {
            continue;
        }
        let Ok(o) = shoot(&gear, &branch.spec, xi, &opts.shooting) else {
            continue;
        };
        if section_distance(o.x, xi, 1.0) > opts.coarse_tol * (1.0 + 0.1 * xi[1].abs()) {
            continue;
        }
        if orbit.distance(o.x) < opts.same_tol {
            return Ok(true);
        }
    }
    Ok(false)
}
