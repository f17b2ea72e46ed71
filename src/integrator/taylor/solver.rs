//! The event-driven Filippov loop of the Taylor method: one expansion per step, the step size
//! from the coefficients (no rejected steps), crossings of Σ as roots of the step's polynomial
//! of ω, and the events, stick phases and saltation matrices of `event_driven.rs` (numerics.md).

use super::super::augmented::{z_beta, z_omega, Layout};
use super::super::event_driven::{arrival, release_gradient, Arrival, ZenoGuard};
use super::super::{check_interval, Event, EventKind, Flow, FlowOptions, Mode, Sample, Stats};
use super::crossing::first_crossing;
use super::expansion::Expansion;
use super::Taylor;
use crate::error::{Error, Result};
use crate::model::TaylorOscillator;
use nalgebra::Matrix2;

/// Integrates over [t₀, t₁] with the augmented dimension N (2: the state, 6: with the state
/// Jacobian).
pub(super) fn integrate<S: TaylorOscillator + ?Sized, const N: usize>(
    method: &Taylor,
    sys: &S,
    t0: f64,
    x0: [f64; 2],
    t1: f64,
    opts: &FlowOptions,
) -> Result<Flow> {
    check_interval(t0, x0, t1)?;
    opts.validate()?;
    Solver::<S, N>::new(method, sys, opts).run(t0, x0, t1)
}

struct Solver<'a, S: ?Sized, const N: usize> {
    sys: &'a S,
    opts: &'a FlowOptions,
    layout: Layout,
    ex: Expansion<N>,
    stats: Stats,
    events: Vec<Event>,
    samples: Vec<Sample>,
    sample_jacobians: Vec<Matrix2<f64>>,
    next_sample: usize,
}

impl<'a, S: TaylorOscillator + ?Sized, const N: usize> Solver<'a, S, N> {
    fn new(method: &Taylor, sys: &'a S, opts: &'a FlowOptions) -> Self {
        let order = method.order_for(opts.rtol);
        Self {
            sys,
            opts,
            layout: Layout {
                ncols: (N - 2) / 2,
                with_params: false,
            },
            ex: Expansion::new(order),
            stats: Stats::default(),
            events: Vec::new(),
            samples: Vec::with_capacity(opts.sample_times.len()),
            sample_jacobians: Vec::new(),
            next_sample: 0,
        }
    }

    /// The loop: stick phases solved directly, slip steps by Taylor expansion, each ended at the
    /// first arrival on Σ.
    fn run(mut self, t0: f64, x0: [f64; 2], t1: f64) -> Result<Flow> {
        let period = self.sys.period();
        let hmax = self.opts.max_step_fraction * period;
        let (mut y, mut mode) = self.start(t0, x0);
        let mut t = t0;
        let mut guard = ZenoGuard::new(period);
        while t < t1 {
            if self.stats.steps > self.opts.max_steps {
                return Err(Error::StepBudget {
                    t,
                    max_steps: self.opts.max_steps,
                });
            }
            if mode == Mode::Stick {
                let Some((tr, s)) = self.stick_phase(t, &mut y, t1, guard.degenerate()) else {
                    t = t1;
                    break;
                };
                guard.record(
                    tr,
                    "events repeat without progress (stick/slip chattering at a degenerate point)",
                )?;
                t = tr;
                mode = if s > 0.0 {
                    Mode::Positive
                } else {
                    Mode::Negative
                };
                continue;
            }
            let s = mode.side();
            self.ex.expand(self.sys, t, &y, s);
            self.stats.rhs_evals += 1;
            self.stats.steps += 1;
            let hs = self.step(t, &y, hmax, t1)?;
            if let Some(tau) = first_crossing(&self.ex.x.omega, self.ex.order, hs, s) {
                let tc = t + tau;
                self.samples_poly(t, tc, false);
                let mut yc = self.ex.state(tc - t);
                yc[1] = 0.0;
                guard.record(
                    tc,
                    "events repeat without progress (degenerate contact with ω = 0)",
                )?;
                mode = self.handle_arrival(tc, &mut yc, s, guard.degenerate());
                (t, y) = (tc, yc);
                continue;
            }
            let tn = if hs >= t1 - t { t1 } else { t + hs };
            self.samples_poly(t, tn, true);
            y = self.ex.state(tn - t);
            t = tn;
        }
        Ok(self.finish(t, y, mode))
    }

    /// The size of the step from (t, y) ([`Expansion::step_size`] with the tolerances' scales),
    /// at most `hmax` and to t₁; an error when it is not positive and finite.
    fn step(&self, t: f64, y: &[f64; N], hmax: f64, t1: f64) -> Result<f64> {
        let (rtol, atol) = (self.opts.rtol, self.opts.atol);
        let scale: [f64; N] = std::array::from_fn(|i| {
            if i == 0 {
                atol + rtol
            } else {
                atol + rtol * y[i].abs()
            }
        });
        let h = self.ex.step_size(&scale).min(hmax).min(t1 - t);
        if h > 0.0 && h.is_finite() && t + h > t {
            Ok(h)
        } else {
            Err(Error::Integration {
                t,
                reason: format!("Taylor step size underflow or non-finite state (h = {h:e})"),
            })
        }
    }

    /// The start: skips the samples before t₀; the augmented state and the initial mode (a
    /// start that sticks has ω = 0 and the stick-entry saltation applied).
    fn start(&mut self, t0: f64, x0: [f64; 2]) -> ([f64; N], Mode) {
        let mut y = [0.0; N];
        self.layout.init(x0, &mut y);
        self.next_sample = self
            .opts
            .sample_times
            .iter()
            .take_while(|&&ts| ts < t0)
            .count();
        let mode = super::super::initial_mode(self.sys, t0, x0);
        if mode == Mode::Stick {
            y[1] = 0.0;
            self.stick_saltation(&mut y);
        }
        (y, mode)
    }

    /// Records the samples in [t, t_end) (`inclusive`: [t, t_end]) from the step's polynomials,
    /// with the state Jacobian when it is carried.
    fn samples_poly(&mut self, t: f64, t_end: f64, inclusive: bool) {
        while let Some(&ts) = self.opts.sample_times.get(self.next_sample) {
            if ts > t_end || (!inclusive && ts >= t_end) {
                break;
            }
            let tau = (ts - t).max(0.0);
            self.samples.push(Sample {
                t: ts,
                beta: self.ex.value(0, tau),
                omega: self.ex.value(1, tau),
            });
            if self.layout.ncols > 0 {
                let z: [f64; 6] =
                    std::array::from_fn(|i| if i < 2 { 0.0 } else { self.ex.value(i, tau) });
                self.sample_jacobians.extend(self.layout.state_jacobian(&z));
            }
            self.next_sample += 1;
        }
    }

    /// Records the samples in [.., t] of a constant state `y` (a stick phase; at the end, the
    /// samples at t₁ left by a step that ended on Σ there).
    fn samples_constant(&mut self, t: f64, y: &[f64; N]) {
        while let Some(&ts) = self.opts.sample_times.get(self.next_sample) {
            if ts > t {
                break;
            }
            self.samples.push(Sample {
                t: ts,
                beta: y[0],
                omega: y[1],
            });
            self.sample_jacobians.extend(self.layout.state_jacobian(y));
            self.next_sample += 1;
        }
    }

    fn record_event(&mut self, t: f64, beta: f64, kind: EventKind) {
        self.stats.events += 1;
        if self.opts.record_events {
            self.events.push(Event { t, beta, kind });
        }
    }

    /// What happens when ω reaches 0 from side `s` at `tc` (as in `event_driven.rs`): stick
    /// (saltation diag(1, 0)) while |a| ≤ r_s, a graze when a points back to side s (I), else a
    /// crossing (saltation diag(1, a₊/a₋)).
    fn handle_arrival(&mut self, tc: f64, y: &mut [f64; N], s: f64, force_stick: bool) -> Mode {
        let beta = y[0];
        match arrival(self.sys, tc, beta, s, force_stick) {
            Arrival::Stick => {
                self.stick_saltation(y);
                self.record_event(tc, beta, EventKind::StickStart);
                Mode::Stick
            }
            Arrival::Graze => {
                self.record_event(tc, beta, EventKind::Graze { side: s as i8 });
                Mode::from_side(s)
            }
            Arrival::Cross { to, ratio } => {
                for c in 0..self.layout.ncols {
                    y[z_omega(c)] *= ratio;
                }
                let (from, to) = (s as i8, to as i8);
                self.record_event(tc, beta, EventKind::Crossing { from, to });
                Mode::from_side(f64::from(to))
            }
        }
    }

    /// Stick entry: S = diag(1, 0).
    fn stick_saltation(&self, y: &mut [f64; N]) {
        for c in 0..self.layout.ncols {
            y[z_omega(c)] = 0.0;
        }
    }

    /// A stick phase from t (release time from [`crate::model::DrivenOscillator::next_release`]):
    /// records its samples and the release, applies the release saltation; returns (release time,
    /// side) or `None` if stuck through t₁.
    fn stick_phase(
        &mut self,
        t: f64,
        y: &mut [f64; N],
        t1: f64,
        nudge: bool,
    ) -> Option<(f64, f64)> {
        let sys = self.sys;
        let beta = y[0];
        let from = if nudge { t + 1e-9 * sys.period() } else { t };
        let Some(tr) = sys.next_release(from, beta, t1) else {
            self.samples_constant(t1, y);
            return None;
        };
        let tr = tr.max(t);
        self.samples_constant(tr, y);
        let f = sys.forces(tr, beta, 0.0);
        let s = if f.a >= 0.0 { 1.0 } else { -1.0 };
        let jump = f.a - s * f.r;
        if jump != 0.0 && self.layout.ncols > 0 {
            self.release_saltation(y, tr, jump);
        }
        self.record_event(tr, beta, EventKind::Release { to: s as i8 });
        Some((tr, s))
    }

    /// Release with a jump of the acceleration (static above sliding friction), as in
    /// `event_driven.rs`: Z₊ = Z₋ − (0, jump) dt_r/dz, dt_r/dz = −G_β Z_β / G_t from
    /// G(t, β) = |a| − r_s = 0 (central differences of G).
    fn release_saltation(&self, y: &mut [f64; N], tr: f64, jump: f64) {
        let Some((gt, gb)) = release_gradient(self.sys, tr, y[0]) else {
            return;
        };
        for c in 0..self.layout.ncols {
            let dt = -gb * y[z_beta(c)] / gt;
            y[z_omega(c)] -= jump * dt;
        }
    }

    fn finish(mut self, t: f64, y: [f64; N], mode: Mode) -> Flow {
        self.samples_constant(t, &y);
        let (jac_x, jac_p) = self.layout.jacobians(&y);
        Flow {
            t,
            x: [y[0], y[1]],
            mode,
            jac_x,
            jac_p,
            events: self.events,
            samples: self.samples,
            sample_jacobians: self.sample_jacobians,
            stats: self.stats,
        }
    }
}
