//! The pseudo-arclength solver: tangent predictor, Newton corrector on the bordered system,
//! step-size control from the corrector's convergence, as a state machine.
//!
//! In scaled unknowns v = W u (W = diag(1, w_ω, 1), [`ContinuationOptions::omega_weight`]) a step
//! from v₀ with unit tangent t predicts v_pred = v₀ + ds t and corrects
//!
//! ```text
//!   F(x, λ) = Pᵏ(x; λ) − x − (s, 0) = 0,   t·(W u − v_pred) = 0
//! ```
//!
//! by Newton ([`crate::numerics::newton`]); the next tangent solves [[F_x, F_λ] W⁻¹; tᵀ] t' = e₃.
//! The step grows by 1.6 after ≤ 2 corrector iterations, shrinks by 0.6 after ≥ 5, and halves on a
//! failed corrector, a correction longer than the step, or a tangent turning by more than 60°.

use super::branch::{Branch, BranchPoint, StopReason};
use super::minaug::linearise_map;
use super::options::ContinuationOptions;
use crate::error::{Error, Result};
use crate::integrator::{DefaultMethod, FlowMethod, DEFAULT_METHOD};
use crate::model::{Parameter, Parametrised};
use crate::numerics::{newton, Linearisation, NewtonOptions};
use crate::orbits::{shoot_with, EventCounts, Floquet, OrbitSpec, PeriodicOrbit};
use crate::progress::{Event, Observer};
use nalgebra::{Matrix2, Matrix3, Vector3};

/// A corrected point with everything needed afterwards.
#[derive(Debug, Clone)]
pub(super) struct Solved {
    pub u: Vector3<f64>,
    pub jac: Matrix2<f64>,
    pub f_lambda: [f64; 2],
    pub events: EventCounts,
    pub iterations: usize,
}

impl Solved {
    pub fn floquet(&self) -> Floquet {
        Floquet::of_orbit(&self.jac, &self.events)
    }
}

/// The continuation solver and its state, for system `S` integrated by method `M`.
#[derive(Debug, Clone)]
pub struct Continuation<S: Parametrised, M = DefaultMethod> {
    pub(super) method: M,
    pub(super) sys: S,
    pub(super) param: S::Param,
    pub(super) spec: OrbitSpec,
    pub(super) opts: ContinuationOptions,
    pub(super) last: Solved,
    pub(super) tangent: Vector3<f64>,
    pub(super) ds: f64,
    steps: usize,
    evals: usize,
    pub(super) branch: Branch<S>,
}

/// What a step did.
#[derive(Debug, Clone, PartialEq)]
pub enum StepOutcome {
    /// A point was added (with the number of special points found in the step).
    Point(usize),
    /// The continuation has stopped (see the branch's stop reason).
    Done,
}

impl<S: Parametrised> Continuation<S, DefaultMethod> {
    /// Starts a continuation in `param` from the orbit near `x0` of `sys` (the parameter's start
    /// value is its value in `sys`), with the default integrator, the event-driven DOP853
    /// ([`crate::integrator::DEFAULT_METHOD`]). Shoots the first orbit at fixed parameter.
    pub fn new(
        sys: S,
        param: S::Param,
        spec: OrbitSpec,
        x0: [f64; 2],
        opts: ContinuationOptions,
    ) -> Result<Self> {
        Self::with_method(DEFAULT_METHOD, sys, param, spec, x0, opts)
    }

    /// Starts from a periodic orbit already found (e.g. by [`crate::orbits::orbit_from_simulation`]).
    pub fn from_orbit(
        sys: S,
        param: S::Param,
        orbit: &PeriodicOrbit,
        opts: ContinuationOptions,
    ) -> Result<Self> {
        Self::new(sys, param, orbit.spec, orbit.x, opts)
    }
}

impl<S: Parametrised, M: FlowMethod<S>> Continuation<S, M> {
    /// [`Continuation::new`] with the flow (and its Jacobians) computed by `method`.
    pub fn with_method(
        method: M,
        sys: S,
        param: S::Param,
        spec: OrbitSpec,
        x0: [f64; 2],
        opts: ContinuationOptions,
    ) -> Result<Self> {
        opts.validate()?;
        let lam0 = sys.param(param);
        if lam0 < opts.param_min || lam0 > opts.param_max {
            return Err(Error::InvalidParameter {
                name: param.name(),
                value: lam0,
                reason: "start value outside the continuation range [param_min, param_max]",
            });
        }
        let orbit = shoot_with(&method, &sys, &spec, x0, &opts.shooting)?;
        let branch = Branch {
            param,
            spec,
            system: sys.clone(),
            points: Vec::new(),
            specials: Vec::new(),
            stop: StopReason::Running,
            map_evaluations: 0,
            multiple_shooting_from: None,
        };
        let mut c = Self {
            method,
            sys,
            param,
            spec,
            opts,
            last: Solved {
                u: Vector3::new(orbit.x[0], orbit.x[1], lam0),
                jac: Matrix2::identity(),
                f_lambda: [0.0; 2],
                events: orbit.events,
                iterations: orbit.newton_iterations,
            },
            tangent: Vector3::zeros(),
            ds: opts.ds.abs(),
            steps: 0,
            evals: orbit.newton_iterations + 1,
            branch,
        };
        let (solved, _) = c.eval(c.last.u)?;
        c.last = solved;
        // initial tangent: [[J − I, F_λ], [e_λᵀ]] t = e₃, oriented by the sign of ds
        let t = c.tangent_from(&c.last, &Vector3::new(0.0, 0.0, 1.0))?;
        c.tangent = if opts.ds < 0.0 { -t } else { t };
        let p = c.make_point(&c.last, 0.0);
        let rho = p.floquet.spectral_radius();
        if rho > opts.max_multiplier {
            return Err(Error::MultiplierTooLarge {
                multiplier: rho,
                limit: opts.max_multiplier,
            });
        }
        c.branch.points.push(p);
        Ok(c)
    }

    /// The branch so far.
    pub fn branch(&self) -> &Branch<S> {
        &self.branch
    }

    /// Finishes and returns the branch.
    pub fn into_branch(mut self) -> Branch<S> {
        self.branch.map_evaluations = self.evals;
        self.branch
    }

    /// Runs until the continuation stops, reporting each point to `observer`
    /// ([`Event::BranchPoint`]).
    pub fn run(mut self, observer: Option<&dyn Observer>) -> Result<Branch<S>> {
        loop {
            match self.step()? {
                StepOutcome::Done => break,
                StepOutcome::Point(_) => {
                    if let Some(o) = observer {
                        let index = self.branch.points.len() - 1;
                        let p = &self.branch.points[index];
                        o.observe(&Event::BranchPoint {
                            index,
                            param: p.param,
                            stable: p.stable,
                            ds: self.ds,
                        });
                    }
                }
            }
        }
        Ok(self.into_branch())
    }

    pub(super) fn weights(&self) -> Vector3<f64> {
        Vector3::new(1.0, self.opts.omega_weight, 1.0)
    }

    /// Evaluates F, F_x + I (the map Jacobian) and F_λ at u.
    pub(super) fn eval(&mut self, u: Vector3<f64>) -> Result<(Solved, [f64; 2])> {
        self.evals += 1;
        let sys = self.sys.with_param(self.param, u[2])?;
        let lin = linearise_map(
            &self.method,
            &sys,
            &self.spec,
            [u[0], u[1]],
            &[self.param],
            &self.opts.shooting,
        )?;
        Ok((
            Solved {
                u,
                jac: lin.jac,
                f_lambda: lin.columns[0],
                events: lin.events,
                iterations: 0,
            },
            lin.residual,
        ))
    }

    /// Bordered matrix [[J − I, F_λ] W⁻¹, [borderᵀ]] in scaled variables.
    fn bordered(&self, s: &Solved, border: &Vector3<f64>) -> Matrix3<f64> {
        let w = self.weights();
        let mut a = Matrix3::zeros();
        for i in 0..2 {
            for j in 0..2 {
                let id = if i == j { 1.0 } else { 0.0 };
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
    pub(super) fn tangent_from(&self, s: &Solved, prev: &Vector3<f64>) -> Result<Vector3<f64>> {
        let a = self.bordered(s, prev);
        let t = a
            .lu()
            .solve(&Vector3::new(0.0, 0.0, 1.0))
            .filter(|t| t.iter().all(|v| v.is_finite()) && t.norm() > 0.0)
            .ok_or(Error::SingularMatrix {
                what: "bordered matrix: cannot compute the tangent",
            })?;
        let t = t.normalize();
        Ok(if t.dot(prev) < 0.0 { -t } else { t })
    }

    /// Newton corrector on {F = 0, n·(W u − v_ref) = c} from u_pred, at most `max_evals`
    /// evaluations, to the shooting tolerance `opts.shooting.newton_tol`.
    pub(super) fn correct(
        &mut self,
        u_pred: Vector3<f64>,
        normal: Vector3<f64>,
        v_ref: Vector3<f64>,
        c: f64,
        max_evals: usize,
    ) -> Result<Solved> {
        let w = self.weights();
        let border = normal.component_mul(&w);
        let opts = NewtonOptions::new(self.opts.shooting.newton_tol, max_evals.saturating_sub(1));
        let sol = newton(
            u_pred,
            &opts,
            |u| {
                let (s, r) = self.eval(*u)?;
                let g = normal.dot(&(u.component_mul(&w) - v_ref)) - c;
                let mut jacobian = Matrix3::zeros();
                for i in 0..2 {
                    for j in 0..2 {
                        jacobian[(i, j)] = s.jac[(i, j)] - if i == j { 1.0 } else { 0.0 };
                    }
                    jacobian[(i, 2)] = s.f_lambda[i];
                }
                for j in 0..3 {
                    jacobian[(2, j)] = border[j];
                }
                Ok(Linearisation {
                    residual: Vector3::new(r[0], r[1], g),
                    jacobian,
                    data: s,
                })
            },
            |_, _| 1.0,
            "continuation corrector",
        )?;
        let mut s = sol.at.data;
        s.iterations = sol.iterations;
        Ok(s)
    }

    pub(super) fn make_point(&self, s: &Solved, arclength: f64) -> BranchPoint {
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

    /// Predicts and corrects one point from `prev`, halving the step until the corrector succeeds;
    /// `None` when the step falls below `ds_min`.
    fn predict_correct(&mut self, prev: &Solved) -> Option<(Solved, Vector3<f64>)> {
        let w = self.weights();
        let v0 = prev.u.component_mul(&w);
        loop {
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
                        return Some((s, tn));
                    }
                }
            }
            self.ds *= 0.5;
            if self.ds < self.opts.ds_min {
                return None;
            }
        }
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
        let Some((mut s, tn)) = self.predict_correct(&prev) else {
            return self.stop(StopReason::StepTooSmall {
                at: prev.u[2],
                ds_min: self.opts.ds_min,
            });
        };
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
                Err(_) => return self.stop(StopReason::BoundNotReached(b)),
            }
            bound_hit = Some(b);
        }
        let arc = self
            .branch
            .points
            .last()
            .map(|p| p.arclength)
            .unwrap_or(0.0)
            + (s.u - prev.u).component_mul(&w).norm();
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
    pub(super) fn point_at(
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
}
