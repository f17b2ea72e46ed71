//! Pseudo-arclength continuation by multiple shooting, for the strongly unstable parts of a branch
//! where single shooting loses its accuracy (|μ| above [`super::ContinuationOptions::max_multiplier`]).
//!
//! Unknowns: the segment states y = (x₀, …, x_{m−1}) and λ. Equations: the multiple-shooting
//! residuals E_i(y, λ) = 0 ([`crate::orbits::multiple_shooting`]) and the arclength condition on
//! (x₀, λ) in the same scaled norm as single shooting, n·W(u₀ − u₀,prev) = Δs. The bordered Newton
//! matrix (blocks B_i, −I, parameter columns ∂E_i/∂λ, one border row) is solved by the structured
//! elimination [`crate::orbits::block_cyclic::CyclicBlockSystem`]. When a segment's Jacobian grows
//! beyond [`MultipleShootingOptions::max_segment_growth`], the segments are halved (m doubles).
//!
//! [`continue_branch`] runs single shooting and, when it stops at the multiplier limit, hands the
//! branch over to multiple shooting instead of stopping; the points are appended to the same
//! [`Branch`] and `Branch::multiple_shooting_from` records where the hand-over happened.

use super::{Branch, BranchPoint, Continuation, ContinuationOptions, Observer, StopReason};
use crate::error::{Error, Result};
use crate::model::{param_derivative, Parametrised};
use crate::orbits::block_cyclic::CyclicBlockSystem;
use crate::orbits::multiple_shooting::{
    evaluate, refine, segment_states, segments_for, shoot_multiple, Segments,
};
use crate::orbits::OrbitSpec;
use nalgebra::{DMatrix, DVector, Vector3};
use serde::{Deserialize, Serialize};

/// Options of the multiple-shooting continuation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MultipleShootingOptions {
    /// Largest norm of one segment's Jacobian before the segments are halved.
    pub max_segment_growth: f64,
    /// Largest number of segments.
    pub max_segments: usize,
}

impl Default for MultipleShootingOptions {
    fn default() -> Self {
        Self {
            max_segment_growth: 50.0,
            max_segments: 512,
        }
    }
}

/// What a multiple-shooting step did.
enum MsStep {
    /// A point was added.
    Point(BranchPoint),
    /// A last point was added (on a parameter bound).
    Last(BranchPoint, StopReason),
    /// Stopped without a new point.
    Stop(StopReason),
}

/// The multiple-shooting continuation's state.
struct MsState<S: Parametrised> {
    sys: S,
    param: S::Param,
    spec: OrbitSpec,
    opts: ContinuationOptions,
    ms: MultipleShootingOptions,
    y: Vec<[f64; 2]>,
    lam: f64,
    seg: Segments,
    /// Unit tangent of (x₀, λ) in scaled variables.
    tangent: Vector3<f64>,
    ds: f64,
    evals: usize,
}

impl<S: Parametrised> MsState<S> {
    fn weights(&self) -> Vector3<f64> {
        Vector3::new(1.0, self.opts.omega_weight, 1.0)
    }

    fn eval(&mut self, y: &[[f64; 2]], lam: f64) -> Result<Segments> {
        self.evals += 1;
        let sys = self.sys.with_param(self.param, lam)?;
        evaluate(&sys, &self.spec, y, &self.opts.shooting, true)
    }

    /// The bordered system at `seg` with the border row `border` (scaled (x₀, λ) coefficients).
    fn system(&self, seg: &Segments, lam: f64, border: &Vector3<f64>) -> Result<CyclicBlockSystem> {
        let w = self.weights();
        let sys = self.sys.with_param(self.param, lam)?;
        let mut diagonal = Vec::with_capacity(seg.images.len());
        let mut param_columns = Vec::with_capacity(seg.images.len());
        for img in &seg.images {
            let b = img.jac_x.ok_or(Error::MissingJacobian { what: "state" })?;
            diagonal.push(DMatrix::from_column_slice(2, 2, b.as_slice()));
            let jp = img
                .jac_p
                .as_ref()
                .ok_or(Error::MissingJacobian { what: "parameter" })?;
            let c = param_derivative(&sys, self.param, jp)?;
            param_columns.push(DMatrix::from_column_slice(2, 1, &c));
        }
        Ok(CyclicBlockSystem {
            diagonal,
            param_columns,
            border_state: DMatrix::from_row_slice(1, 2, &[border[0] * w[0], border[1] * w[1]]),
            border_param: DMatrix::from_element(1, 1, border[2] * w[2]),
        })
    }

    /// Full tangent (dy, dλ) with the scaled (x₀, λ) part of unit length, oriented along `prev`.
    fn tangent(
        &self,
        seg: &Segments,
        lam: f64,
        prev: &Vector3<f64>,
    ) -> Result<(Vec<[f64; 2]>, f64, Vector3<f64>)> {
        let a = self.system(seg, lam, prev)?;
        let m = seg.images.len();
        let z = a.solve(&vec![DVector::zeros(2); m], &DVector::from_element(1, 1.0))?;
        let w = self.weights();
        let t3 = Vector3::new(
            z.states[0][0] * w[0],
            z.states[0][1] * w[1],
            z.params[0] * w[2],
        );
        let nrm = t3.norm();
        if !(nrm > 0.0 && nrm.is_finite()) {
            return Err(Error::DegenerateDirection {
                what: "the multiple-shooting tangent is zero or not finite",
            });
        }
        let sg = if t3.dot(prev) < 0.0 { -1.0 } else { 1.0 } / nrm;
        let dy = z.states.iter().map(|d| [sg * d[0], sg * d[1]]).collect();
        Ok((dy, sg * z.params[0], t3 * sg))
    }

    /// Newton corrector on {E = 0, n·W(u₀ − u_ref) = c}; `fixed` = Some(b) instead pins λ = b.
    fn correct(
        &mut self,
        mut y: Vec<[f64; 2]>,
        mut lam: f64,
        normal: &Vector3<f64>,
        u_ref: Vector3<f64>,
        c: f64,
    ) -> Result<(Vec<[f64; 2]>, f64, Segments, usize)> {
        let w = self.weights();
        let tol = self.opts.shooting.newton_tol;
        let mut last = f64::INFINITY;
        for it in 0..10 {
            let seg = self.eval(&y, lam)?;
            let u0 = Vector3::new(y[0][0], y[0][1], lam);
            let g = normal.dot(&(u0 - u_ref).component_mul(&w)) - c;
            let a = self.system(&seg, lam, normal)?;
            let rhs: Vec<DVector<f64>> = seg
                .residuals
                .iter()
                .map(|r| DVector::from_vec(vec![-r[0], -r[1]]))
                .collect();
            let d = a.solve(&rhs, &DVector::from_element(1, -g))?;
            let rn = seg.residual_norm();
            let sn = d
                .states
                .iter()
                .map(|v| v.amax())
                .fold(d.params[0].abs(), f64::max);
            if rn < tol && sn < 10.0 * tol && g.abs() < 10.0 * tol {
                return Ok((y, lam, seg, it));
            }
            if it > 2 && rn > 2.0 * last {
                break;
            }
            last = rn;
            for (x, dx) in y.iter_mut().zip(&d.states) {
                x[0] += dx[0];
                x[1] += dx[1];
            }
            lam += d.params[0];
        }
        Err(Error::NewtonFailed {
            iterations: 10,
            residual: last,
            reason: "multiple-shooting corrector".into(),
        })
    }

    fn point(&self, arclength: f64) -> Result<BranchPoint> {
        let floquet = self
            .seg
            .floquet()
            .ok_or(Error::MissingJacobian { what: "state" })?;
        Ok(BranchPoint {
            param: self.lam,
            x: self.y[0],
            floquet,
            stable: floquet.stable,
            events: self.seg.events(),
            arclength,
        })
    }

    /// One continuation step.
    fn step(&mut self, arclength: f64) -> Result<MsStep> {
        let w = self.weights();
        let (dy, dl, t) = self.tangent(&self.seg.clone(), self.lam, &self.tangent.clone())?;
        self.tangent = t;
        let u_ref = Vector3::new(self.y[0][0], self.y[0][1], self.lam);
        let (y, lam, seg, iters) = loop {
            let yp: Vec<[f64; 2]> = self
                .y
                .iter()
                .zip(&dy)
                .map(|(x, d)| [x[0] + self.ds * d[0], x[1] + self.ds * d[1]])
                .collect();
            let lp = self.lam + self.ds * dl;
            match self.correct(yp, lp, &t, u_ref, self.ds) {
                Ok(r) => break r,
                Err(e) => {
                    self.ds *= 0.5;
                    if self.ds < self.opts.ds_min {
                        let _ = e;
                        return Ok(MsStep::Stop(StopReason::StepTooSmall {
                            at: self.lam,
                            ds_min: self.opts.ds_min,
                        }));
                    }
                }
            }
        };
        let (mut y, mut lam, mut seg) = (y, lam, seg);
        let mut bound = None;
        if lam > self.opts.param_max || lam < self.opts.param_min {
            let b = if lam > self.opts.param_max {
                self.opts.param_max
            } else {
                self.opts.param_min
            };
            let frac = (b - self.lam) / (lam - self.lam);
            let yp: Vec<[f64; 2]> = self
                .y
                .iter()
                .zip(&y)
                .map(|(a, c)| [a[0] + frac * (c[0] - a[0]), a[1] + frac * (c[1] - a[1])])
                .collect();
            let e3 = Vector3::new(0.0, 0.0, 1.0);
            let r = self.correct(yp, b, &e3, Vector3::new(0.0, 0.0, b), 0.0)?;
            (y, lam, seg) = (r.0, r.1, r.2);
            bound = Some(b);
        }
        let du = Vector3::new(
            y[0][0] - self.y[0][0],
            y[0][1] - self.y[0][1],
            lam - self.lam,
        );
        let arc = arclength + du.component_mul(&w).norm();
        self.y = y;
        self.lam = lam;
        self.seg = seg;
        self.ds = match iters {
            0..=2 => (self.ds * 1.6).min(self.opts.ds_max),
            3..=4 => self.ds,
            _ => (self.ds * 0.6).max(self.opts.ds_min),
        };
        let p = self.point(arc)?;
        if let Some(b) = bound {
            return Ok(MsStep::Last(p, StopReason::ParameterBound(b)));
        }
        self.remesh()?;
        Ok(MsStep::Point(p))
    }

    /// Halves the segments while one of them carries more than `max_segment_growth`.
    fn remesh(&mut self) -> Result<()> {
        while self.seg.max_growth() > self.ms.max_segment_growth
            && 2 * self.y.len() <= self.ms.max_segments
        {
            let sys = self.sys.with_param(self.param, self.lam)?;
            let y = refine(&sys, &self.spec, &self.y, self.opts.shooting.tol)?;
            let o = shoot_multiple(&sys, &self.spec, &y, &self.opts.shooting)?;
            self.y = o.states;
            self.seg = self.eval(&self.y.clone(), self.lam)?;
        }
        Ok(())
    }
}

/// Continues `branch` (stopped by single shooting at the multiplier limit) by multiple shooting
/// from its last point, in the direction of its last step, with the continuation options `opts`
/// (the same ones the single-shooting run used). The new points are appended; the stop reason is
/// replaced by the multiple-shooting run's.
pub fn extend_by_multiple_shooting<S: Parametrised>(
    branch: &mut Branch<S>,
    opts: &ContinuationOptions,
    ms: &MultipleShootingOptions,
) -> Result<()> {
    let n = branch.points.len();
    if n < 2 {
        return Err(Error::shape(
            "points of the branch (multiple shooting goes on from the last two)",
            ">= 2",
            n,
        ));
    }
    let (a, b) = (&branch.points[n - 2], &branch.points[n - 1]);
    let w = Vector3::new(1.0, opts.omega_weight, 1.0);
    let dir = Vector3::new(b.x[0] - a.x[0], b.x[1] - a.x[1], b.param - a.param).component_mul(&w);
    if dir.norm().is_nan() || dir.norm() <= 0.0 {
        return Err(Error::DegenerateDirection {
            what: "the last two points of the branch coincide",
        });
    }
    let sys = branch.system.with_param(branch.param, b.param)?;
    let m = segments_for(b.floquet.spectral_radius(), ms.max_segment_growth);
    let y0 = segment_states(&sys, &branch.spec, b.x, m, opts.shooting.tol)?;
    let orbit = shoot_multiple(&sys, &branch.spec, &y0, &opts.shooting)?;
    let mut st = MsState {
        sys: branch.system.clone(),
        param: branch.param,
        spec: branch.spec,
        opts: *opts,
        ms: *ms,
        y: orbit.states,
        lam: b.param,
        seg: evaluate(&sys, &branch.spec, &y0, &opts.shooting, true)?,
        tangent: dir.normalize(),
        ds: (b.arclength - a.arclength)
            .abs()
            .clamp(opts.ds_min, opts.ds_max),
        evals: 1,
    };
    st.seg = st.eval(&st.y.clone(), st.lam)?;
    st.remesh()?;
    branch.multiple_shooting_from = Some(n);
    let mut arc = b.arclength;
    let mut steps = 0;
    let stop = loop {
        if steps >= opts.max_steps {
            break StopReason::MaxSteps(opts.max_steps);
        }
        steps += 1;
        let at = st.lam;
        match st
            .step(arc)
            .unwrap_or(MsStep::Stop(StopReason::StepTooSmall {
                at,
                ds_min: opts.ds_min,
            })) {
            MsStep::Point(p) => {
                arc = p.arclength;
                branch.points.push(p);
            }
            MsStep::Last(p, reason) => {
                branch.points.push(p);
                break reason;
            }
            MsStep::Stop(reason) => break reason,
        }
    };
    branch.stop = stop;
    branch.map_evaluations += st.evals;
    Ok(())
}

/// Runs a continuation; where single shooting stops at the multiplier limit, the branch is continued
/// by multiple shooting (if `ms` is given) instead of stopping.
pub fn continue_branch<S: Parametrised>(
    c: Continuation<S>,
    opts: &ContinuationOptions,
    ms: Option<&MultipleShootingOptions>,
    observer: Option<&dyn Observer>,
) -> Result<Branch<S>> {
    let mut branch = c.run(observer)?;
    if let (Some(ms), StopReason::MultiplierLimit(_)) = (ms, &branch.stop) {
        extend_by_multiple_shooting(&mut branch, opts, ms)?;
    }
    Ok(branch)
}
