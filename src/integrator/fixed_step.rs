//! The paper's fixed-step scheme: classical Runge–Kutta 4 with Δt = T/n and a naive sgn(ω).
//!
//! The paper (eq. `deltat`) integrates with Δt = 1/(n f), n = 50, and does not say which stepper; we
//! use RK4 and evaluate sgn(ω) at every stage with sgn(0) = 0. Near ω = 0 the friction term then
//! flips sign from stage to stage (chattering): stick phases are not resolved, the output creeps.
//! The Jacobian is the derivative of the smooth field on each side (no saltation), which is what a
//! naive variational integration gives. Kept as a comparison method, not for production use.

use super::augmented::{augmented_rhs, Layout, NMAX, V};
use super::{check_interval, Flow, FlowMethod, FlowOptions, Mode, Sample, Sensitivity, Stats};
use crate::error::{positive, Error, Result};
use crate::model::DrivenOscillator;

/// Fixed-step RK4 with a naive sgn(ω): `steps_per_period` steps per drive period (paper: 50).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FixedStep {
    /// Steps per drive period n (Δt = T/n).
    pub steps_per_period: usize,
}

impl Default for FixedStep {
    fn default() -> Self {
        Self {
            steps_per_period: 50,
        }
    }
}

fn sgn(w: f64) -> f64 {
    if w > 0.0 {
        1.0
    } else if w < 0.0 {
        -1.0
    } else {
        0.0
    }
}

impl<S: DrivenOscillator + ?Sized> FlowMethod<S> for FixedStep {
    fn name(&self) -> String {
        format!("fixed-step RK4 (T/{})", self.steps_per_period)
    }

    fn flow(&self, sys: &S, t0: f64, x0: [f64; 2], t1: f64, opts: &FlowOptions) -> Result<Flow> {
        check_interval(t0, x0, t1)?;
        opts.validate()?;
        if self.steps_per_period == 0 {
            return Err(Error::option("steps_per_period", "must be >= 1, got 0"));
        }
        let period = positive("period", sys.period())?;
        let layout = Layout::new(sys, opts.sensitivity);
        let n = layout.dim();
        let dt = period / self.steps_per_period as f64;
        let nsteps = ((t1 - t0) / dt).ceil().max(0.0) as usize;
        let mut y: V = [0.0; NMAX];
        layout.init(x0, &mut y);
        let mut stats = Stats::default();
        let mut samples = Vec::with_capacity(opts.sample_times.len());
        let mut next = 0usize;
        let mut t = t0;
        let (mut k1, mut k2, mut k3, mut k4, mut ys) = (
            [0.0; NMAX],
            [0.0; NMAX],
            [0.0; NMAX],
            [0.0; NMAX],
            [0.0; NMAX],
        );
        let f = |t: f64, y: &V, out: &mut V| {
            augmented_rhs(sys, layout, t, y, sgn(y[1]), out);
        };
        for step in 0..nsteps {
            let h = if step + 1 == nsteps { t1 - t } else { dt };
            f(t, &y, &mut k1);
            for i in 0..n {
                ys[i] = y[i] + 0.5 * h * k1[i];
            }
            f(t + 0.5 * h, &ys, &mut k2);
            for i in 0..n {
                ys[i] = y[i] + 0.5 * h * k2[i];
            }
            f(t + 0.5 * h, &ys, &mut k3);
            for i in 0..n {
                ys[i] = y[i] + h * k3[i];
            }
            f(t + h, &ys, &mut k4);
            let mut yn = y;
            for i in 0..n {
                yn[i] = y[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
            }
            stats.rhs_evals += 4;
            stats.steps += 1;
            // samples: cubic Hermite between the step ends
            while let Some(&ts) = opts.sample_times.get(next) {
                if ts > t + h {
                    break;
                }
                let th = ((ts - t) / h).clamp(0.0, 1.0);
                let (h00, h10, h01, h11) = (
                    2.0 * th.powi(3) - 3.0 * th.powi(2) + 1.0,
                    th.powi(3) - 2.0 * th.powi(2) + th,
                    -2.0 * th.powi(3) + 3.0 * th.powi(2),
                    th.powi(3) - th.powi(2),
                );
                let mut kn = [0.0; NMAX];
                augmented_rhs(
                    sys,
                    Layout::new(sys, Sensitivity::None),
                    t + h,
                    &yn,
                    sgn(yn[1]),
                    &mut kn,
                );
                let beta = h00 * y[0] + h10 * h * y[1] + h01 * yn[0] + h11 * h * yn[1];
                let omega = h00 * y[1] + h10 * h * k1[1] + h01 * yn[1] + h11 * h * kn[1];
                samples.push(Sample { t: ts, beta, omega });
                next += 1;
            }
            y = yn;
            t += h;
            if !y[0].is_finite() || !y[1].is_finite() {
                return Err(Error::Integration {
                    t,
                    reason: "non-finite state".into(),
                });
            }
        }
        let mode = if y[1] > 0.0 {
            Mode::Positive
        } else if y[1] < 0.0 {
            Mode::Negative
        } else {
            Mode::Stick
        };
        let (jac_x, jac_p) = layout.jacobians(&y);
        Ok(Flow {
            t: t1,
            x: [y[0], y[1]],
            mode,
            jac_x,
            jac_p,
            events: Vec::new(),
            samples,
            sample_jacobians: Vec::new(),
            stats,
        })
    }
}
