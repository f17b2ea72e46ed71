//! Pseudo-arclength continuation of periodic orbits of the gear, with detection and location of
//! folds, flips, symmetry-breaking points, Neimark–Sacker points and nonsmooth events, branch
//! switching, and two-parameter curves ([`two_param`]).
//!
//! The solver is a state machine: [`Continuation::new`] finds the first orbit, each
//! [`Continuation::step`] adds one point (tangent predictor, Newton corrector on the bordered
//! system, step-size control) and locates the special points passed in that step;
//! [`Continuation::run`] drives it to the end with an optional observer, and
//! [`Continuation::into_branch`] returns the one result type [`Branch`].
//!
//! Unknowns u = (β, ω, λ). Equations: F(x, λ) = Pᵏ(x; λ) − x − (s, 0) = 0 and the arclength
//! condition t·(u − u_pred) = 0, with t the unit tangent. The λ column ∂F/∂λ is the map's `jac_p`
//! column (with the chain rule for Θ, Δ = cos²Θ − 2 sin²Θ).

pub mod branch;
pub mod diagram;
pub mod identity;
pub mod multiple_shooting;
pub mod two_param;

pub use branch::{Branch, BranchPoint, NonsmoothJump, SpecialKind, SpecialPoint, StopReason};

use crate::error::{Error, Result};
use crate::maps::{MapImage, Section};
use crate::model::Gear;
use crate::orbits::{
    eigenvector, residual, shoot, EventCounts, Floquet, OrbitSpec, PeriodicOrbit, ShootingOptions,
};
use nalgebra::{Matrix3, Vector2, Vector3};
use serde::{Deserialize, Serialize};

/// The continuation parameter.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Param {
    /// Drive frequency f, Hz.
    F,
    /// Coupling g, s⁻².
    G,
    /// Viscous damping ζ, s⁻¹.
    Zeta,
    /// Dry friction η, s⁻².
    Eta,
    /// Shaft index Δ.
    Delta,
    /// Parallel shaft angle Θ = Φ in degrees; Δ = cos²Θ − 2 sin²Θ (Θ ∈ [0°, 90°]).
    ThetaDeg,
}

impl Param {
    /// All parameters, with their names.
    pub const ALL: [(Param, &'static str); 6] = [
        (Param::F, "f"),
        (Param::G, "g"),
        (Param::Zeta, "zeta"),
        (Param::Eta, "eta"),
        (Param::Delta, "delta"),
        (Param::ThetaDeg, "theta"),
    ];

    /// Name as used on the command line and in JSON.
    pub fn name(self) -> &'static str {
        Self::ALL
            .iter()
            .find(|(p, _)| *p == self)
            .map(|x| x.1)
            .unwrap_or("?")
    }

    /// Parses a name (`f`, `g`, `zeta`, `eta`, `delta`, `theta`).
    pub fn from_name(s: &str) -> Result<Self> {
        Self::ALL
            .iter()
            .find(|(_, n)| *n == s)
            .map(|x| x.0)
            .ok_or_else(|| {
                Error::InvalidInput(format!(
                    "unknown parameter `{s}` (expected f, g, zeta, eta, delta or theta)"
                ))
            })
    }

    fn column(self) -> usize {
        match self {
            Param::F => Gear::P_F,
            Param::G => Gear::P_G,
            Param::Zeta => Gear::P_ZETA,
            Param::Eta => Gear::P_ETA,
            Param::Delta | Param::ThetaDeg => Gear::P_DELTA,
        }
    }

    /// The parameter's value in `gear` (Θ from Δ = 1 − 3 sin²Θ, Θ ∈ [0°, 90°]).
    pub fn get(self, gear: &Gear) -> f64 {
        match self {
            Param::ThetaDeg => ((1.0 - gear.delta) / 3.0)
                .clamp(0.0, 1.0)
                .sqrt()
                .asin()
                .to_degrees(),
            p => gear.param(p.column()),
        }
    }

    /// A copy of `gear` with the parameter set to `v` (validated).
    pub fn set(self, gear: &Gear, v: f64) -> Result<Gear> {
        match self {
            Param::ThetaDeg => {
                crate::error::finite("theta", v)?;
                let t = v.to_radians();
                gear.with_param(Gear::P_DELTA, crate::model::gear::shaft_index(t, t))
            }
            p => gear.with_param(p.column(), v),
        }
    }

    /// ∂F/∂λ from the map's parameter columns (chain rule dΔ/dΘ = −3 sin 2Θ · π/180 for Θ in degrees).
    pub fn derivative(self, img: &MapImage, value: f64) -> Result<[f64; 2]> {
        let jp = img
            .jac_p
            .as_ref()
            .ok_or_else(|| Error::Continuation("map returned no parameter Jacobian".into()))?;
        let c = self.column();
        let scale = match self {
            Param::ThetaDeg => {
                -3.0 * (2.0 * value.to_radians()).sin() * std::f64::consts::PI / 180.0
            }
            _ => 1.0,
        };
        Ok([jp[(0, c)] * scale, jp[(1, c)] * scale])
    }
}

/// Options of the continuation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ContinuationOptions {
    /// Initial arclength step (signed: its sign sets the initial direction in λ).
    pub ds: f64,
    /// Smallest step before giving up.
    pub ds_min: f64,
    /// Largest step.
    pub ds_max: f64,
    /// Largest number of continuation steps.
    pub max_steps: usize,
    /// Parameter range [min, max]: the continuation stops on its bounds.
    pub param_min: f64,
    /// See `param_min`.
    pub param_max: f64,
    /// Stop when a multiplier modulus exceeds this (single shooting loses accuracy beyond).
    pub max_multiplier: f64,
    /// Shooting options (integrator tolerance, corrector tolerance, iterations).
    pub shooting: ShootingOptions,
    /// Locate special points to this parameter accuracy (bracket width).
    pub locate_tol: f64,
    /// Detect and locate special points.
    pub detect: bool,
    /// Weight of ω in the arclength norm (ω is in rad/s, β in rad).
    pub omega_weight: f64,
}

impl Default for ContinuationOptions {
    fn default() -> Self {
        Self {
            ds: 0.05,
            ds_min: 1e-7,
            ds_max: 0.5,
            max_steps: 2000,
            param_min: f64::NEG_INFINITY,
            param_max: f64::INFINITY,
            max_multiplier: 1e4,
            shooting: ShootingOptions::default(),
            locate_tol: 1e-8,
            detect: true,
            omega_weight: 0.1,
        }
    }
}

/// A corrected point with everything needed afterwards.
#[derive(Debug, Clone)]
struct Solved {
    u: Vector3<f64>,
    jac: nalgebra::Matrix2<f64>,
    f_lambda: [f64; 2],
    events: EventCounts,
    iterations: usize,
}

impl Solved {
    fn floquet(&self) -> Floquet {
        Floquet::of_orbit(&self.jac, &self.events)
    }
}

/// An observer of the continuation's progress (called after every step).
pub trait Observer {
    /// Called after each accepted point.
    fn point(&mut self, branch_len: usize, point: &BranchPoint, ds: f64);
}

impl<F: FnMut(usize, &BranchPoint, f64)> Observer for F {
    fn point(&mut self, n: usize, p: &BranchPoint, ds: f64) {
        self(n, p, ds)
    }
}

/// The continuation solver and its state.
#[derive(Debug, Clone)]
pub struct Continuation {
    gear: Gear,
    param: Param,
    spec: OrbitSpec,
    opts: ContinuationOptions,
    last: Solved,
    tangent: Vector3<f64>,
    ds: f64,
    steps: usize,
    evals: usize,
    branch: Branch,
}

/// What a step did.
#[derive(Debug, Clone, PartialEq)]
pub enum StepOutcome {
    /// A point was added (with the number of special points found in the step).
    Point(usize),
    /// The continuation has stopped (see the branch's stop reason).
    Done,
}

impl Continuation {
    /// Starts a continuation in `param` from the orbit near `x0` of `gear` (the parameter's start value
    /// is its value in `gear`). Shoots the first orbit at fixed parameter.
    pub fn new(
        gear: Gear,
        param: Param,
        spec: OrbitSpec,
        x0: [f64; 2],
        opts: ContinuationOptions,
    ) -> Result<Self> {
        if !(opts.ds.is_finite() && opts.ds != 0.0) {
            return Err(Error::InvalidInput("ds must be finite and non-zero".into()));
        }
        if !(opts.ds_min > 0.0 && opts.ds_max >= opts.ds_min && opts.ds.abs() >= opts.ds_min) {
            return Err(Error::InvalidInput(
                "need 0 < ds_min ≤ |ds| ≤ ds_max".into(),
            ));
        }
        if opts.param_min.is_nan() || opts.param_max.is_nan() || opts.param_min > opts.param_max {
            return Err(Error::InvalidInput(
                "parameter range must be ordered".into(),
            ));
        }
        let lam0 = param.get(&gear);
        if lam0 < opts.param_min || lam0 > opts.param_max {
            return Err(Error::InvalidInput(format!(
                "start value {lam0} of {} outside the range [{}, {}]",
                param.name(),
                opts.param_min,
                opts.param_max
            )));
        }
        let orbit = shoot(&gear, &spec, x0, &opts.shooting)?;
        let mut c = Self {
            gear,
            param,
            spec,
            opts,
            last: Solved {
                u: Vector3::new(orbit.x[0], orbit.x[1], lam0),
                jac: nalgebra::Matrix2::identity(),
                f_lambda: [0.0; 2],
                events: orbit.events,
                iterations: orbit.newton_iterations,
            },
            tangent: Vector3::zeros(),
            ds: opts.ds.abs(),
            steps: 0,
            evals: orbit.newton_iterations + 1,
            branch: Branch {
                param,
                spec,
                gear,
                points: Vec::new(),
                specials: Vec::new(),
                stop: StopReason::Running,
                map_evaluations: 0,
                multiple_shooting_from: None,
            },
        };
        let (solved, _) = c.eval(c.last.u)?;
        c.last = solved;
        // initial tangent: [[J − I, F_λ], [e_λᵀ]] t = e₃, oriented by the sign of ds
        let t = c.tangent_from(&c.last, &Vector3::new(0.0, 0.0, 1.0))?;
        c.tangent = if opts.ds < 0.0 { -t } else { t };
        let p = c.make_point(&c.last, 0.0);
        if p.floquet.spectral_radius() > opts.max_multiplier {
            return Err(Error::Continuation(format!(
                "the start orbit has |μ| = {:e} above the single-shooting limit {:e}",
                p.floquet.spectral_radius(),
                opts.max_multiplier
            )));
        }
        c.branch.points.push(p);
        Ok(c)
    }

    /// Starts from a periodic orbit already found (e.g. by [`crate::orbits::orbit_from_simulation`]).
    pub fn from_orbit(
        gear: Gear,
        param: Param,
        orbit: &PeriodicOrbit,
        opts: ContinuationOptions,
    ) -> Result<Self> {
        Self::new(gear, param, orbit.spec, orbit.x, opts)
    }

    /// The branch so far.
    pub fn branch(&self) -> &Branch {
        &self.branch
    }

    /// Finishes and returns the branch.
    pub fn into_branch(mut self) -> Branch {
        self.branch.map_evaluations = self.evals;
        self.branch
    }

    /// Runs until the continuation stops, reporting each point to `observer`.
    pub fn run(mut self, mut observer: Option<&mut dyn Observer>) -> Result<Branch> {
        loop {
            match self.step()? {
                StepOutcome::Done => break,
                StepOutcome::Point(_) => {
                    if let Some(o) = observer.as_deref_mut() {
                        let n = self.branch.points.len();
                        o.point(n, &self.branch.points[n - 1], self.ds);
                    }
                }
            }
        }
        Ok(self.into_branch())
    }

    fn weights(&self) -> Vector3<f64> {
        Vector3::new(1.0, self.opts.omega_weight, 1.0)
    }

    /// Evaluates F, J, F_λ at u.
    fn eval(&mut self, u: Vector3<f64>) -> Result<(Solved, [f64; 2])> {
        self.evals += 1;
        let sys = self.param.set(&self.gear, u[2])?;
        let (r, img) = residual(&sys, &self.spec, [u[0], u[1]], &self.opts.shooting, true)?;
        let jac = img
            .jac_x
            .ok_or_else(|| Error::Continuation("map returned no state Jacobian".into()))?;
        let fl = self.param.derivative(&img, u[2])?;
        Ok((
            Solved {
                u,
                jac,
                f_lambda: fl,
                events: EventCounts::from_image(&img),
                iterations: 0,
            },
            r,
        ))
    }

    /// Bordered matrix [[J − I, F_λ], [wᵀ]] in scaled variables.
    fn bordered(&self, s: &Solved, border: &Vector3<f64>) -> Matrix3<f64> {
        let w = self.weights();
        let mut a = Matrix3::zeros();
        for i in 0..2 {
            for j in 0..2 {
                let id = if i == j { 1.0 } else { 0.0 };
                // columns in scaled unknowns v = W u: ∂F/∂v_j = ∂F/∂u_j / w_j
                a[(i, j)] = (s.jac[(i, j)] - id) / w[j];
            }
            a[(i, 2)] = s.f_lambda[i] / w[2];
        }
        for j in 0..3 {
            a[(2, j)] = border[j];
        }
        a
    }

    /// Unit tangent (scaled variables) at `s`, oriented along `prev`.
    fn tangent_from(&self, s: &Solved, prev: &Vector3<f64>) -> Result<Vector3<f64>> {
        let a = self.bordered(s, prev);
        let t = a
            .lu()
            .solve(&Vector3::new(0.0, 0.0, 1.0))
            .filter(|t| t.iter().all(|v| v.is_finite()) && t.norm() > 0.0)
            .ok_or_else(|| {
                Error::Continuation("singular bordered matrix: cannot compute the tangent".into())
            })?;
        let t = t.normalize();
        Ok(if t.dot(prev) < 0.0 { -t } else { t })
    }

    /// Newton corrector on {F = 0, n·(v − v_ref) = c} in scaled variables v = W u, from u_pred.
    fn correct(
        &mut self,
        u_pred: Vector3<f64>,
        normal: Vector3<f64>,
        v_ref: Vector3<f64>,
        c: f64,
        max_iter: usize,
    ) -> Result<Solved> {
        let w = self.weights();
        let mut u = u_pred;
        let tol = self.opts.shooting.newton_tol;
        let mut last_norm = f64::INFINITY;
        for it in 0..max_iter {
            let (mut s, r) = self.eval(u)?;
            let v = u.component_mul(&w);
            let g = normal.dot(&(v - v_ref)) - c;
            let rhs = Vector3::new(-r[0], -r[1], -g);
            let a = self.bordered(&s, &normal);
            let dv = a
                .lu()
                .solve(&rhs)
                .filter(|d| d.iter().all(|x| x.is_finite()))
                .ok_or_else(|| Error::Continuation("singular bordered matrix".into()))?;
            let du = dv.component_div(&w);
            let rn = Vector2::new(r[0], r[1]).norm();
            if rn < tol && du.norm() < 10.0 * tol && g.abs() < 10.0 * tol {
                s.iterations = it;
                return Ok(s);
            }
            // divergence guard
            if it > 2 && rn > 2.0 * last_norm {
                break;
            }
            last_norm = rn;
            u += du;
            if u[2] <= 0.0 && self.param == Param::F {
                break;
            }
        }
        Err(Error::NewtonFailed {
            iterations: max_iter,
            residual: last_norm,
            reason: "continuation corrector".into(),
        })
    }

    fn make_point(&self, s: &Solved, arclength: f64) -> BranchPoint {
        let fq = s.floquet();
        BranchPoint {
            param: s.u[2],
            x: [s.u[0], s.u[1]],
            floquet: fq,
            stable: fq.stable,
            events: s.events,
            arclength,
        }
    }

    fn stop(&mut self, r: StopReason) -> Result<StepOutcome> {
        self.branch.stop = r;
        self.branch.map_evaluations = self.evals;
        Ok(StepOutcome::Done)
    }

    /// One continuation step: predict, correct (halving the step on failure), check bounds, detect and
    /// locate special points between the last two points.
    pub fn step(&mut self) -> Result<StepOutcome> {
        if self.branch.stop != StopReason::Running {
            return Ok(StepOutcome::Done);
        }
        if self.steps >= self.opts.max_steps {
            return self.stop(StopReason::MaxSteps(self.steps));
        }
        self.steps += 1;
        let w = self.weights();
        let prev = self.last.clone();
        let v0 = prev.u.component_mul(&w);
        let solved = loop {
            let v_pred = v0 + self.ds * self.tangent;
            let u_pred = v_pred.component_div(&w);
            let t = self.tangent;
            // a failed corrector (or a parameter leaving its admissible range) halves the step
            if let Ok(s) = self.correct(u_pred, t, v_pred, 0.0, 8) {
                // refuse corrections longer than the step (the corrector jumped to another part of
                // the branch, e.g. across a nonsmooth fold) and steps that turn the tangent by > 60°
                let jump = (s.u.component_mul(&w) - v_pred).norm();
                if let Ok(tn) = self.tangent_from(&s, &t) {
                    let small = self.ds <= self.opts.ds_min * 2.0;
                    if (tn.dot(&t) > 0.5 && jump <= self.ds) || small {
                        break (s, tn);
                    }
                }
            }
            self.ds *= 0.5;
            if self.ds < self.opts.ds_min {
                let lam = prev.u[2];
                return self.stop(StopReason::StepTooSmall(format!(
                    "corrector failed at {} = {lam} with ds < {:e}",
                    self.param.name(),
                    self.opts.ds_min
                )));
            }
        };
        let (mut s, tn) = solved;
        let mut bound_hit = None;
        let lam = s.u[2];
        if lam > self.opts.param_max || lam < self.opts.param_min {
            // land exactly on the bound by a corrector with the parameter fixed
            let b = if lam > self.opts.param_max {
                self.opts.param_max
            } else {
                self.opts.param_min
            };
            let frac = (b - prev.u[2]) / (lam - prev.u[2]);
            let u_pred = prev.u + frac * (s.u - prev.u);
            let e3 = Vector3::new(0.0, 0.0, 1.0);
            match self.correct(u_pred, e3, Vector3::new(0.0, 0.0, b * w[2]), 0.0, 10) {
                Ok(sb) => s = sb,
                Err(e) => {
                    return self.stop(StopReason::StepTooSmall(format!(
                        "could not land on the bound {b}: {e}"
                    )))
                }
            }
            bound_hit = Some(b);
        }
        let arc = self
            .branch
            .points
            .last()
            .map(|p| p.arclength)
            .unwrap_or(0.0)
            + (s.u.component_mul(&w) - v0).norm();
        let point = self.make_point(&s, arc);
        let idx = self.branch.points.len() - 1;
        let mut found = 0;
        if self.opts.detect {
            found = self.detect(&prev, &s, idx)?;
        }
        self.branch.points.push(point.clone());
        // step-size control from the corrector's iterations
        self.ds = match s.iterations {
            0..=2 => (self.ds * 1.6).min(self.opts.ds_max),
            3..=4 => self.ds,
            _ => (self.ds * 0.6).max(self.opts.ds_min),
        };
        self.tangent = tn;
        self.last = s;
        if let Some(b) = bound_hit {
            return self
                .stop(StopReason::ParameterBound(b))
                .map(|_| StepOutcome::Point(found));
        }
        let rho = point.floquet.spectral_radius();
        if rho > self.opts.max_multiplier {
            self.stop(StopReason::MultiplierLimit(rho))?;
        }
        Ok(StepOutcome::Point(found))
    }

    /// Solves the point at scaled arclength `sig` along the chord from `a` (normal t_a).
    fn point_at(
        &mut self,
        a: &Solved,
        b: &Solved,
        ta: &Vector3<f64>,
        sig: f64,
        sb: f64,
    ) -> Result<Solved> {
        let w = self.weights();
        let va = a.u.component_mul(&w);
        let frac = if sb != 0.0 { sig / sb } else { 0.0 };
        let u_pred = a.u + frac * (b.u - a.u);
        self.correct(u_pred, *ta, va, sig, 12)
    }

    fn detect(&mut self, a: &Solved, b: &Solved, idx: usize) -> Result<usize> {
        let w = self.weights();
        let ta = self.tangent;
        let sb = ta.dot(&(b.u.component_mul(&w) - a.u.component_mul(&w)));
        let mut specials = Vec::new();
        let smooth_tests = |f: &Floquet| [f.fold_test(), f.flip_test(), f.ns_test()];
        // nonsmooth events first: they split the step into smooth pieces
        let mut pieces: Vec<(Solved, f64, Solved, f64)> = Vec::new();
        if a.events.signature() != b.events.signature() {
            let (lo, slo, hi, shi) = self.bisect_signature(a, b, &ta, sb);
            let flo = lo.floquet();
            let fhi = hi.floquet();
            // which test functions change sign across the jump
            let tl = smooth_tests(&flo);
            let th = smooth_tests(&fhi);
            let crosses = if tl[0].signum() != th[0].signum() {
                Some("fold".to_string())
            } else if tl[1].signum() != th[1].signum() {
                Some("flip".to_string())
            } else {
                None
            };
            let lam = 0.5 * (lo.u[2] + hi.u[2]);
            specials.push(SpecialPoint {
                kind: SpecialKind::Nonsmooth,
                param: lam,
                precision: 0.5 * (hi.u[2] - lo.u[2]).abs() + self.opts.shooting.newton_tol,
                x: [hi.u[0], hi.u[1]],
                floquet: fhi,
                test_value: 0.0,
                eigenvector: None,
                after_point: idx,
                jump: Some(NonsmoothJump {
                    events_before: lo.events,
                    events_after: hi.events,
                    floquet_before: flo,
                    floquet_after: fhi,
                    param_before: lo.u[2],
                    param_after: hi.u[2],
                    crosses,
                }),
                stability_change: flo.stable != fhi.stable,
            });
            pieces.push((a.clone(), 0.0, lo, slo));
            pieces.push((hi, shi, b.clone(), sb));
        } else {
            pieces.push((a.clone(), 0.0, b.clone(), sb));
        }
        for (pa, spa, pb, spb) in pieces {
            let f1 = pa.floquet();
            let f2 = pb.floquet();
            let t1 = smooth_tests(&f1);
            let t2 = smooth_tests(&f2);
            for k in 0..3 {
                if t1[k] == 0.0 || t2[k] == 0.0 || t1[k].signum() == t2[k].signum() {
                    continue;
                }
                if k == 2 && !(f1.complex_pair() && f2.complex_pair()) {
                    continue;
                }
                let kind = match (k, self.spec.section) {
                    (0, _) => SpecialKind::Fold,
                    (1, Section::HalfPeriod) => SpecialKind::SymmetryBreaking,
                    (1, Section::Stroboscopic) => SpecialKind::Flip,
                    _ => SpecialKind::NeimarkSacker,
                };
                let sp = match self.locate_smooth(&pa, spa, &pb, spb, &ta, sb, a, b, k, kind, idx) {
                    Ok(sp) => sp,
                    // the corrector failed inside the step: report the bracket, honestly wide
                    Err(_) => SpecialPoint {
                        kind,
                        param: 0.5 * (pa.u[2] + pb.u[2]),
                        precision: 0.5 * (pa.u[2] - pb.u[2]).abs(),
                        x: [pb.u[0], pb.u[1]],
                        floquet: f2,
                        test_value: t2[k],
                        eigenvector: None,
                        after_point: idx,
                        jump: None,
                        stability_change: f1.stable != f2.stable,
                    },
                };
                specials.push(sp);
            }
        }
        specials.sort_by(|x, y| {
            let d = |s: &SpecialPoint| (s.param - a.u[2]).abs();
            d(x).total_cmp(&d(y))
        });
        let n = specials.len();
        self.branch.specials.extend(specials);
        Ok(n)
    }

    /// Bisection on the arclength for a change of the event signature: returns the two bracket points.
    fn bisect_signature(
        &mut self,
        a: &Solved,
        b: &Solved,
        ta: &Vector3<f64>,
        sb: f64,
    ) -> (Solved, f64, Solved, f64) {
        let sig_a = a.events.signature();
        let (mut lo, mut slo, mut hi, mut shi) = (a.clone(), 0.0, b.clone(), sb);
        for _ in 0..80 {
            if (hi.u[2] - lo.u[2]).abs() < self.opts.locate_tol && (shi - slo).abs() < 1e-6 {
                break;
            }
            let sm = 0.5 * (slo + shi);
            if sm <= slo.min(shi) || sm >= slo.max(shi) {
                break;
            }
            let Ok(m) = self.point_at(a, b, ta, sm, sb) else {
                break;
            };
            if m.events.signature() == sig_a {
                lo = m;
                slo = sm;
            } else {
                hi = m;
                shi = sm;
            }
        }
        (lo, slo, hi, shi)
    }

    /// Illinois (regula falsi) on the arclength for a zero of test function `k` on [pa, pb].
    #[allow(clippy::too_many_arguments)]
    fn locate_smooth(
        &mut self,
        pa: &Solved,
        spa: f64,
        pb: &Solved,
        spb: f64,
        ta: &Vector3<f64>,
        sb: f64,
        a: &Solved,
        b: &Solved,
        k: usize,
        kind: SpecialKind,
        idx: usize,
    ) -> Result<SpecialPoint> {
        let test = |s: &Solved| {
            let f = s.floquet();
            [f.fold_test(), f.flip_test(), f.ns_test()][k]
        };
        let (mut lo, mut slo, mut flo) = (pa.clone(), spa, test(pa));
        let (mut hi, mut shi, mut fhi) = (pb.clone(), spb, test(pb));
        let mut side = 0i32;
        let mut best = if flo.abs() < fhi.abs() {
            lo.clone()
        } else {
            hi.clone()
        };
        for _ in 0..100 {
            let width = (hi.u[2] - lo.u[2]).abs();
            if width < self.opts.locate_tol && (shi - slo).abs() < 1e-5 {
                break;
            }
            let mut sm = (slo * fhi - shi * flo) / (fhi - flo);
            let (smin, smax) = (slo.min(shi), slo.max(shi));
            let margin = 0.01 * (smax - smin);
            if !(sm > smin + margin && sm < smax - margin) {
                sm = 0.5 * (slo + shi);
            }
            if sm <= smin || sm >= smax {
                break;
            }
            let m = self.point_at(a, b, ta, sm, sb)?;
            let fm = test(&m);
            if m.events.signature() != pa.events.signature() {
                // a nonsmooth event inside: bisect towards pa's side
                hi = m;
                shi = sm;
                continue;
            }
            if fm == 0.0 {
                lo = m.clone();
                hi = m.clone();
                best = m;
                break;
            }
            if fm.signum() == flo.signum() {
                lo = m.clone();
                slo = sm;
                flo = fm;
                if side == -1 {
                    fhi *= 0.5;
                }
                side = -1;
            } else {
                hi = m.clone();
                shi = sm;
                fhi = fm;
                if side == 1 {
                    flo *= 0.5;
                }
                side = 1;
            }
            best = m;
        }
        let fq = best.floquet();
        let lam = best.u[2];
        let precision =
            (hi.u[2] - lam).abs().max((lo.u[2] - lam).abs()) + self.opts.shooting.newton_tol;
        let crit = match k {
            0 => Some(1.0),
            1 => Some(-1.0),
            _ => None,
        };
        let eigenvector = crit.and_then(|mu| eigenvector(&best.jac, mu));
        Ok(SpecialPoint {
            kind,
            param: lam,
            precision,
            x: [best.u[0], best.u[1]],
            floquet: fq,
            test_value: test(&best),
            eigenvector,
            after_point: idx,
            jump: None,
            stability_change: pa.floquet().stable != pb.floquet().stable,
        })
    }
}

/// A start for a new branch after switching.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SwitchStart {
    /// The system at the start value of the parameter.
    pub gear: Gear,
    /// The new problem (P_T² after a flip, P_T after a symmetry-breaking point).
    pub spec: OrbitSpec,
    /// The orbit on the new branch.
    pub orbit: PeriodicOrbit,
    /// Distance of the new orbit from the old branch's orbit continued to the same parameter.
    pub separation: f64,
}

/// Branch switching at a flip (onto the period-doubled branch on P_T^{2k}) or at a symmetry-breaking
/// point (onto one of the pair of asymmetric orbits on P_T): shoots from x* ± ε v at parameter values
/// λ* ± dλ and returns the first orbit distinct from the old branch.
pub fn switch_branch(
    branch: &Branch,
    special: &SpecialPoint,
    dparam: f64,
    opts: &ShootingOptions,
) -> Result<SwitchStart> {
    let spec = match special.kind {
        SpecialKind::Flip => {
            OrbitSpec::stroboscopic(2 * branch.spec.iterations, 2 * branch.spec.winding)
        }
        SpecialKind::SymmetryBreaking => {
            let s = branch.spec.on_stroboscopic();
            OrbitSpec::stroboscopic(s.iterations, s.winding)
        }
        k => {
            return Err(Error::Unsupported(format!(
            "branch switching is implemented at flips and symmetry-breaking points, not at a {}",
            k.label()
        )))
        }
    };
    let v = special.eigenvector.ok_or_else(|| {
        Error::Continuation("the special point carries no eigenvector to switch along".into())
    })?;
    let old_spec = branch.spec;
    let mut last_err = None;
    let distinct = |o: &PeriodicOrbit, old: &PeriodicOrbit| {
        let db = (o.x[0] - old.x[0]).rem_euclid(std::f64::consts::TAU);
        let db = db.min(std::f64::consts::TAU - db);
        db.hypot(o.x[1] - old.x[1])
    };
    for &dl in &[dparam, -dparam, 10.0 * dparam, -10.0 * dparam] {
        let lam = special.param + dl;
        let gear = branch.param.set(&branch.gear, lam)?;
        // the old orbit at this parameter, for the separation test
        let Ok(old) = shoot(&gear, &old_spec, special.x, opts) else {
            continue;
        };
        let perturbed = |eps: f64, sgn: f64| {
            [
                special.x[0] + sgn * eps * v[0],
                special.x[1] + sgn * eps * v[1],
            ]
        };
        // Newton from a start; a new orbit must lie at least 1e-4 from the old one
        let mut attempt = |x0: [f64; 2]| -> Option<SwitchStart> {
            match shoot(&gear, &spec, x0, opts) {
                Ok(orbit) => {
                    let separation = distinct(&orbit, &old);
                    (separation > 1e-4).then_some(SwitchStart {
                        gear,
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
            let Ok(d) = crate::orbits::detect_period(
                &gear,
                perturbed(0.05, sgn),
                300,
                spec.iterations,
                1e-3,
                opts.tol.max(1e-10),
            ) else {
                continue;
            };
            if let Some(start) = attempt(d.x) {
                return Ok(start);
            }
        }
    }
    Err(Error::Continuation(format!(
        "branch switching at {} = {} found no new orbit ({})",
        branch.param.name(),
        special.param,
        last_err
            .map(|e| e.to_string())
            .unwrap_or_else(|| "only the old orbit was found".into())
    )))
}
