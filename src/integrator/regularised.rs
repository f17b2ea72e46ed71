//! Regularised friction solved by diffsol (feature `diffsol-check`): an independent cross-check of
//! the event-driven integrator.
//!
//! The dry friction s·r is replaced by r·tanh(ω/ε), which makes the system smooth but stiff
//! (∂ω̇/∂ω ≈ −r/ε near ω = 0):
//!
//! ```text
//!   β̇ = ω,   ω̇ = a(t, β, ω) − r(t, β, ω) tanh(ω/ε).
//! ```
//!
//! As ε → 0 the solution of a piece with crossings of Σ converges to the Filippov solution with an
//! error O(ε); a stick phase becomes a slow *creep*: ω ≈ ε artanh(a/r) instead of 0, so β drifts by
//! about ε artanh(a/r) times the stick duration (docs/model.md).
//!
//! The Jacobians are obtained by integrating the variational equation as part of the ODE (the
//! augmented state y = (β, ω, Z) as in the event-driven integrator), with diffsol's singly diagonally
//! implicit Runge–Kutta methods (ESDIRK3(4) or TR-BDF2). There is no saltation: the regularised
//! field is smooth, so its variational equation already converges to the saltation-corrected one as
//! ε → 0 away from stick phases.
//!
//! Step size: diffsol has no maximum step option, so the step is capped at
//! `max_step_fraction · T` before every step (the first step too), which keeps the solver from stepping
//! over the forcing when the right-hand side vanishes at the start (dependencies.md).

use super::augmented::{augmented_rhs_law, z_beta, z_omega, Layout, NMAX, V};
use super::{check_interval, Flow, FlowMethod, FlowOptions, Mode, Sample, Stats};
use crate::error::{positive, Error, Result};
use crate::model::DrivenOscillator;
use diffsol::{NalgebraLU, NalgebraMat, OdeBuilder, OdeSolverMethod, OdeSolverStopReason};
use serde::{Deserialize, Serialize};
use std::cell::Cell;

/// Which implicit diffsol method integrates the regularised system.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ImplicitMethod {
    /// ESDIRK3(4): L-stable, order 4 with an embedded order-3 error estimate (the default).
    #[default]
    Esdirk34,
    /// TR-BDF2: L-stable, order 2.
    TrBdf2,
}

/// Regularised friction r·tanh(ω/ε) integrated as a smooth stiff ODE by diffsol.
///
/// ```
/// use gearbif::model::Gear;
/// use gearbif::integrator::{EventDriven, FlowMethod, FlowOptions, Regularised};
/// let gear = Gear::paper(25.0, 2.7).unwrap();
/// let opts = FlowOptions::with_tol(1e-8);
/// let t1 = 1.0 / gear.f;
/// let exact = EventDriven.flow(&gear, 0.0, [2.0, 1.0], t1, &opts).unwrap();
/// let reg = Regularised::new(1e-4).flow(&gear, 0.0, [2.0, 1.0], t1, &opts).unwrap();
/// assert!((reg.x[0] - exact.x[0]).abs() < 1e-2);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Regularised {
    /// Regularisation velocity ε > 0, in the units of ω (rad/s for the gear).
    pub epsilon: f64,
    /// The diffsol method.
    pub method: ImplicitMethod,
}

impl Regularised {
    /// ESDIRK3(4) with regularisation velocity `epsilon`.
    pub fn new(epsilon: f64) -> Self {
        Self {
            epsilon,
            method: ImplicitMethod::Esdirk34,
        }
    }
    /// Returns a copy using `method`.
    pub fn with_method(mut self, method: ImplicitMethod) -> Self {
        self.method = method;
        self
    }
}

/// The regularised augmented right-hand side (state and `ncols` Jacobian columns).
#[inline]
fn reg_rhs<S: DrivenOscillator + ?Sized>(
    sys: &S,
    ncols: usize,
    with_params: bool,
    eps: f64,
    t: f64,
    y: &[f64],
    out: &mut [f64],
) {
    let ph = (y[1] / eps).tanh();
    let dph = (1.0 - ph * ph) / eps;
    let layout = Layout { ncols, with_params };
    augmented_rhs_law(sys, layout, t, y, ph, dph, None, out);
}

/// Jacobian-vector product of [`reg_rhs`]: exact in the Jacobian columns Z and for the state rows;
/// the derivative of the variational rows with respect to (β, ω) (second derivatives of the forces)
/// by a central difference along (v_β, v_ω) with a step scaled to ε.
#[allow(clippy::too_many_arguments)]
#[inline]
fn reg_jac<S: DrivenOscillator + ?Sized>(
    sys: &S,
    ncols: usize,
    with_params: bool,
    eps: f64,
    t: f64,
    y: &[f64],
    v: &[f64],
    out: &mut [f64],
    evals: &Cell<usize>,
) {
    let j = sys.forces_jet(t, y[0], y[1], false);
    let ph = (y[1] / eps).tanh();
    let dph = (1.0 - ph * ph) / eps;
    let db = j.a_beta - j.r_beta * ph;
    let dw = j.a_omega - j.r_omega * ph - j.r * dph;
    out[0] = v[1];
    out[1] = db * v[0] + dw * v[1];
    if ncols == 0 {
        return;
    }
    for c in 0..ncols {
        out[z_beta(c)] = v[z_omega(c)];
        out[z_omega(c)] = db * v[z_beta(c)] + dw * v[z_omega(c)];
    }
    let dn = v[0].abs().max(v[1].abs());
    if dn > 0.0 {
        let n = 2 + 2 * ncols;
        let h = 6e-6 * eps.min(1.0) / dn;
        let mut yp: V = [0.0; NMAX];
        let mut ym: V = [0.0; NMAX];
        yp[..n].copy_from_slice(&y[..n]);
        ym[..n].copy_from_slice(&y[..n]);
        yp[0] += h * v[0];
        yp[1] += h * v[1];
        ym[0] -= h * v[0];
        ym[1] -= h * v[1];
        let mut fp: V = [0.0; NMAX];
        let mut fm: V = [0.0; NMAX];
        reg_rhs(sys, ncols, with_params, eps, t, &yp[..n], &mut fp[..n]);
        reg_rhs(sys, ncols, with_params, eps, t, &ym[..n], &mut fm[..n]);
        evals.set(evals.get() + 2);
        for c in 0..ncols {
            let i = z_omega(c);
            out[i] += (fp[i] - fm[i]) / (2.0 * h);
        }
    }
}

fn dsol_err(t: f64, e: impl std::fmt::Display) -> Error {
    Error::Integration {
        t,
        reason: format!("diffsol: {e}"),
    }
}

impl<S: DrivenOscillator + ?Sized> FlowMethod<S> for Regularised {
    fn name(&self) -> String {
        let m = match self.method {
            ImplicitMethod::Esdirk34 => "ESDIRK34",
            ImplicitMethod::TrBdf2 => "TR-BDF2",
        };
        format!("regularised tanh(ω/{:e}) diffsol {m}", self.epsilon)
    }

    fn flow(&self, sys: &S, t0: f64, x0: [f64; 2], t1: f64, opts: &FlowOptions) -> Result<Flow> {
        check_interval(t0, x0, t1)?;
        opts.validate()?;
        let eps = positive("epsilon", self.epsilon)?;
        let period = positive("period", sys.period())?;
        let layout = Layout::new(sys, opts.sensitivity);
        let (ncols, with_params) = (layout.ncols, layout.with_params);
        let n = layout.dim();
        let mut y0 = vec![0.0; n];
        layout.init(x0, &mut y0);
        let mut samples = Vec::with_capacity(opts.sample_times.len());
        let mut next = opts.sample_times.partition_point(|&ts| ts < t0);
        let jac_of = |y: &[f64]| layout.jacobians(y);
        let mode_of = |w: f64| {
            if w > 0.0 {
                Mode::Positive
            } else if w < 0.0 {
                Mode::Negative
            } else {
                Mode::Stick
            }
        };
        if t1 == t0 {
            while opts.sample_times.get(next).is_some_and(|&ts| ts <= t1) {
                samples.push(Sample {
                    t: opts.sample_times[next],
                    beta: x0[0],
                    omega: x0[1],
                });
                next += 1;
            }
            let (jac_x, jac_p) = jac_of(&y0);
            return Ok(Flow {
                t: t1,
                x: x0,
                mode: mode_of(x0[1]),
                jac_x,
                jac_p,
                events: Vec::new(),
                samples,
                sample_jacobians: Vec::new(),
                stats: Stats::default(),
            });
        }

        let hmax = opts.max_step_fraction * period;
        let h0 = (period / 100.0).min(hmax).min(t1 - t0);
        let evals = Cell::new(0usize);
        let mut atol = vec![opts.atol.max(1e-300); n];
        // β lives on the lift: measure its error in radians, as the event-driven integrator does
        atol[0] = opts.atol + opts.rtol;
        let mut problem = OdeBuilder::<NalgebraMat<f64>>::new()
            .t0(t0)
            .h0(h0)
            .rtol(opts.rtol)
            .atol(atol)
            .rhs_implicit(
                |y: &[f64], _p: &[f64], t: f64, out: &mut [f64]| {
                    evals.set(evals.get() + 1);
                    reg_rhs(sys, ncols, with_params, eps, t, y, out);
                },
                |y: &[f64], _p: &[f64], t: f64, v: &[f64], out: &mut [f64]| {
                    reg_jac(sys, ncols, with_params, eps, t, y, v, out, &evals);
                },
            )
            .init(
                |_p: &[f64], _t: f64, out: &mut [f64]| out.copy_from_slice(&y0),
                n,
            )
            .build()
            .map_err(|e| dsol_err(t0, e))?;
        // tanh(ω/ε) saturates a few ε away from Σ: a Newton matrix a few steps old is then far
        // from the true one and the stage solves fail in stick phases (creep). The system is tiny,
        // so re-evaluate the Jacobian at every step.
        problem.ode_options.update_jacobian_after_steps = 1;
        problem.ode_options.update_rhs_jacobian_after_steps = 1;
        // diffsol counts nonlinear-solver failures over the whole solve, not per step (0.18):
        // a long run through many stick phases would hit the default of 50 although every
        // failed step recovers by a smaller step; bound the work by `max_steps` instead
        problem.ode_options.max_nonlinear_solver_failures = opts.max_steps;
        let mut stats = Stats::default();
        let mut y = vec![0.0; n];
        macro_rules! drive {
            ($solver:expr) => {{
                let mut solver = $solver.map_err(|e| dsol_err(t0, e))?;
                solver.set_stop_time(t1).map_err(|e| dsol_err(t0, e))?;
                loop {
                    if stats.steps + stats.rejected > opts.max_steps {
                        return Err(Error::StepBudget {
                            t: solver.state().t,
                            max_steps: opts.max_steps,
                        });
                    }
                    if solver.state().h > hmax {
                        *solver.state_mut().h = hmax;
                    }
                    let reason = solver.step().map_err(|e| dsol_err(solver.state().t, e))?;
                    stats.steps += 1;
                    let t_now = solver.state().t;
                    while let Some(&ts) = opts.sample_times.get(next) {
                        if ts > t_now {
                            break;
                        }
                        let v = solver.interpolate(ts).map_err(|e| dsol_err(t_now, e))?;
                        samples.push(Sample {
                            t: ts,
                            beta: v[0],
                            omega: v[1],
                        });
                        next += 1;
                    }
                    let ys = solver.state().y;
                    if !ys[0].is_finite() || !ys[1].is_finite() {
                        return Err(Error::Integration {
                            t: t_now,
                            reason: "non-finite state".into(),
                        });
                    }
                    if matches!(reason, OdeSolverStopReason::TstopReached) {
                        for (i, yi) in y.iter_mut().enumerate() {
                            *yi = ys[i];
                        }
                        break;
                    }
                }
            }};
        }
        match self.method {
            ImplicitMethod::Esdirk34 => drive!(problem.esdirk34::<NalgebraLU<f64>>()),
            ImplicitMethod::TrBdf2 => drive!(problem.tr_bdf2::<NalgebraLU<f64>>()),
        }
        stats.rhs_evals = evals.get();
        let (jac_x, jac_p) = jac_of(&y);
        Ok(Flow {
            t: t1,
            x: [y[0], y[1]],
            mode: mode_of(y[1]),
            jac_x,
            jac_p,
            events: Vec::new(),
            samples,
            sample_jacobians: Vec::new(),
            stats,
        })
    }
}
