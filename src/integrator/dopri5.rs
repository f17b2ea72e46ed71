//! Event-driven Filippov integration with Dormand–Prince 5(4), dense output, and saltation matrices.
//!
//! The augmented state is y = (β, ω, Z) with Z = ∂(β, ω)/∂(β₀, ω₀, p) stored column by column.
//! On a slip piece of side s, Ż = DF_s Z + [0 | ∂F_s/∂p] (variational equation), integrated with the
//! same Runge–Kutta stages as the state ("internal differentiation"); the local error is controlled on
//! (β, ω). At each event the saltation matrix S = I + (F₊ − F₋)∇hᵀ/(∇h·F₋) multiplies Z:
//! diag(1, a₊/a₋) at a crossing, diag(1, 0) at stick entry, I at a release (numerics.md).

use super::augmented::{augmented_rhs, param_col, z_beta, z_omega, Layout, NMAX, V};
use super::{check_interval, Event, EventKind, Flow, FlowMethod, FlowOptions, Mode, Sample, Stats};
use crate::error::{Error, Result};
use crate::model::{release_function, DrivenOscillator};
use crate::numerics::Illinois;

// Dormand–Prince 5(4) coefficients (Dormand & Prince 1980; dense output of Hairer, Nørsett & Wanner).
const C2: f64 = 1.0 / 5.0;
const C3: f64 = 3.0 / 10.0;
const C4: f64 = 4.0 / 5.0;
const C5: f64 = 8.0 / 9.0;
const A21: f64 = 1.0 / 5.0;
const A31: f64 = 3.0 / 40.0;
const A32: f64 = 9.0 / 40.0;
const A41: f64 = 44.0 / 45.0;
const A42: f64 = -56.0 / 15.0;
const A43: f64 = 32.0 / 9.0;
const A51: f64 = 19372.0 / 6561.0;
const A52: f64 = -25360.0 / 2187.0;
const A53: f64 = 64448.0 / 6561.0;
const A54: f64 = -212.0 / 729.0;
const A61: f64 = 9017.0 / 3168.0;
const A62: f64 = -355.0 / 33.0;
const A63: f64 = 46732.0 / 5247.0;
const A64: f64 = 49.0 / 176.0;
const A65: f64 = -5103.0 / 18656.0;
const A71: f64 = 35.0 / 384.0;
const A73: f64 = 500.0 / 1113.0;
const A74: f64 = 125.0 / 192.0;
const A75: f64 = -2187.0 / 6784.0;
const A76: f64 = 11.0 / 84.0;
const E1: f64 = 71.0 / 57600.0;
const E3: f64 = -71.0 / 16695.0;
const E4: f64 = 71.0 / 1920.0;
const E5: f64 = -17253.0 / 339200.0;
const E6: f64 = 22.0 / 525.0;
const E7: f64 = -1.0 / 40.0;
const D1: f64 = -12715105075.0 / 11282082432.0;
const D3: f64 = 87487479700.0 / 32700410799.0;
const D4: f64 = -10690763975.0 / 1880347072.0;
const D5: f64 = 701980252875.0 / 199316789632.0;
const D6: f64 = -1453857185.0 / 822651844.0;
const D7: f64 = 69997945.0 / 29380423.0;

/// Interior points per step at which the dense output is checked for a sign change of ω
/// (catches short slips that start and end inside one step).
const EVENT_PROBES: usize = 8;

/// The exact event-driven Filippov integrator (adaptive Dormand–Prince 5(4)).
///
/// ```
/// use gearbif::model::Gear;
/// use gearbif::integrator::{EventDriven, FlowMethod, FlowOptions, Sensitivity};
/// let gear = Gear::paper(25.0, 2.7).unwrap();
/// let opts = FlowOptions::with_tol(1e-10).sensitivity(Sensitivity::State);
/// let flow = EventDriven.flow(&gear, 0.0, [3.0, 0.0], 1.0 / 2.7, &opts).unwrap();
/// let m = flow.jac_x.unwrap(); // monodromy-type Jacobian of the stroboscopic map
/// assert!(m.determinant().is_finite());
/// ```
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct EventDriven;

impl<S: DrivenOscillator + ?Sized> FlowMethod<S> for EventDriven {
    fn name(&self) -> String {
        "event-driven DP5".into()
    }
    fn flow(&self, sys: &S, t0: f64, x0: [f64; 2], t1: f64, opts: &FlowOptions) -> Result<Flow> {
        check_interval(t0, x0, t1)?;
        opts.validate()?;
        Solver::new(sys, opts).run(t0, x0, t1)
    }
}

struct Solver<'a, S: ?Sized> {
    sys: &'a S,
    opts: &'a FlowOptions,
    /// Which Jacobian columns are propagated.
    layout: Layout,
    stats: Stats,
    events: Vec<Event>,
    samples: Vec<Sample>,
    next_sample: usize,
}

impl<'a, S: DrivenOscillator + ?Sized> Solver<'a, S> {
    fn new(sys: &'a S, opts: &'a FlowOptions) -> Self {
        let layout = Layout::new(sys, opts.sensitivity);
        Self {
            sys,
            opts,
            layout,
            stats: Stats::default(),
            events: Vec::new(),
            samples: Vec::with_capacity(opts.sample_times.len()),
            next_sample: 0,
        }
    }

    #[inline(always)]
    fn rhs(&mut self, t: f64, y: &V, s: f64, out: &mut V) {
        self.stats.rhs_evals += 1;
        augmented_rhs(self.sys, self.layout, t, y, s, out);
    }

    fn record_event(&mut self, t: f64, beta: f64, kind: EventKind) {
        self.stats.events += 1;
        if self.opts.record_events {
            self.events.push(Event { t, beta, kind });
        }
    }

    /// Records the samples in (.., t] of a constant state (stick phases).
    fn samples_constant(&mut self, t: f64, beta: f64) {
        while let Some(&ts) = self.opts.sample_times.get(self.next_sample) {
            if ts > t {
                break;
            }
            self.samples.push(Sample {
                t: ts,
                beta,
                omega: 0.0,
            });
            self.next_sample += 1;
        }
    }

    fn run(mut self, t0: f64, x0: [f64; 2], t1: f64) -> Result<Flow> {
        let sys = self.sys;
        let period = sys.period();
        let hmax = self.opts.max_step_fraction * period;
        let mut y: V = [0.0; NMAX];
        self.layout.init(x0, &mut y);
        // skip samples before t0
        while self
            .opts
            .sample_times
            .get(self.next_sample)
            .is_some_and(|&ts| ts < t0)
        {
            self.next_sample += 1;
        }
        let mut t = t0;
        let mut mode = super::initial_mode(sys, t0, x0);
        if mode == Mode::Stick {
            y[1] = 0.0;
            self.stick_saltation(&mut y);
        }
        let mut h = (period / 100.0)
            .min(hmax)
            .min((t1 - t0).max(f64::MIN_POSITIVE));
        let mut k: [V; 7] = [[0.0; NMAX]; 7];
        let mut fsal = false;
        let mut facold: f64 = 1e-4;
        let mut last_rejected = false;
        // guard against Zeno-like repetition of events without progress
        let mut stalled = 0usize;
        let mut last_event_t = f64::NEG_INFINITY;
        let tiny = 1e-13 * period.max(1e-300);

        while t < t1 {
            if self.stats.steps + self.stats.rejected > self.opts.max_steps {
                return Err(Error::Integration {
                    t,
                    reason: format!("more than {} steps", self.opts.max_steps),
                });
            }
            if mode == Mode::Stick {
                let beta = y[0];
                let from = if stalled > 8 { t + 1e-9 * period } else { t };
                match sys.next_release(from, beta, t1) {
                    None => {
                        self.samples_constant(t1, beta);
                        t = t1;
                        break;
                    }
                    Some(tr) => {
                        let tr = tr.max(t);
                        self.samples_constant(tr, beta);
                        let f = sys.forces(tr, beta, 0.0);
                        let s = if f.a >= 0.0 { 1.0 } else { -1.0 };
                        // the output leaves with a − s r; zero for r_s = r(t, β, 0) (tangential release)
                        let jump = f.a - s * f.r;
                        if jump != 0.0 && self.layout.ncols > 0 {
                            self.release_saltation(&mut y, tr, jump, s);
                        }
                        if tr - last_event_t <= tiny {
                            stalled += 1;
                        } else {
                            stalled = 0;
                        }
                        if stalled > 16 {
                            return Err(Error::Integration {
                                t: tr,
                                reason: "events repeat without progress (stick/slip chattering at a degenerate point)".into(),
                            });
                        }
                        last_event_t = tr;
                        t = tr;
                        mode = Mode::from_side(s);
                        fsal = false;
                        self.record_event(tr, beta, EventKind::Release { to: s as i8 });
                        continue;
                    }
                }
            }

            let s = mode.side();
            if !fsal {
                let mut k0 = [0.0; NMAX];
                self.rhs(t, &y, s, &mut k0);
                k[0] = k0;
                fsal = true;
            }
            let hh = h.min(hmax).min(t1 - t);
            let last = hh >= t1 - t;
            let tn = if last { t1 } else { t + hh };
            let hs = tn - t;
            if hs <= 0.0 || !hs.is_finite() {
                return Err(Error::Integration {
                    t,
                    reason: format!("step size underflow (h = {hs:e})"),
                });
            }
            let n = self.layout.dim();
            let mut ys = [0.0; NMAX];
            let mut kt = [0.0; NMAX];
            // stage 2
            for i in 0..n {
                ys[i] = y[i] + hs * A21 * k[0][i];
            }
            self.rhs(t + C2 * hs, &ys, s, &mut kt);
            k[1] = kt;
            for i in 0..n {
                ys[i] = y[i] + hs * (A31 * k[0][i] + A32 * k[1][i]);
            }
            self.rhs(t + C3 * hs, &ys, s, &mut kt);
            k[2] = kt;
            for i in 0..n {
                ys[i] = y[i] + hs * (A41 * k[0][i] + A42 * k[1][i] + A43 * k[2][i]);
            }
            self.rhs(t + C4 * hs, &ys, s, &mut kt);
            k[3] = kt;
            for i in 0..n {
                ys[i] = y[i] + hs * (A51 * k[0][i] + A52 * k[1][i] + A53 * k[2][i] + A54 * k[3][i]);
            }
            self.rhs(t + C5 * hs, &ys, s, &mut kt);
            k[4] = kt;
            for i in 0..n {
                ys[i] = y[i]
                    + hs * (A61 * k[0][i]
                        + A62 * k[1][i]
                        + A63 * k[2][i]
                        + A64 * k[3][i]
                        + A65 * k[4][i]);
            }
            self.rhs(tn, &ys, s, &mut kt);
            k[5] = kt;
            let mut yn = [0.0; NMAX];
            for i in 0..n {
                yn[i] = y[i]
                    + hs * (A71 * k[0][i]
                        + A73 * k[2][i]
                        + A74 * k[3][i]
                        + A75 * k[4][i]
                        + A76 * k[5][i]);
            }
            self.rhs(tn, &yn, s, &mut kt);
            k[6] = kt;
            // error: RMS over the state (β, ω) and, separately, over the Jacobian columns; the
            // larger counts. Controlling the variational part too matters: on an exactly
            // representable orbit (the locked state) the state error vanishes while the
            // variational equation oscillates at √g and would be left unresolved.
            let mut err_x = 0.0;
            let mut err_z = 0.0;
            for i in 0..n {
                let ei = hs
                    * (E1 * k[0][i]
                        + E3 * k[2][i]
                        + E4 * k[3][i]
                        + E5 * k[4][i]
                        + E6 * k[5][i]
                        + E7 * k[6][i]);
                let scale = if i == 0 {
                    // β lives on the lift: measure its error in radians, not relative to windings
                    self.opts.atol + self.opts.rtol
                } else {
                    self.opts.atol + self.opts.rtol * y[i].abs().max(yn[i].abs())
                };
                let q = (ei / scale).powi(2);
                if i < 2 {
                    err_x += q;
                } else {
                    err_z += q;
                }
            }
            let mut err = (0.5 * err_x).sqrt();
            if n > 2 {
                err = err.max((err_z / (n - 2) as f64).sqrt());
            }
            if !err.is_finite() || !yn[0].is_finite() || !yn[1].is_finite() {
                if hs < 1e-14 * period {
                    return Err(Error::Integration {
                        t,
                        reason: "non-finite state".into(),
                    });
                }
                h = hs * 0.1;
                self.stats.rejected += 1;
                last_rejected = true;
                continue;
            }
            // step-size proposal (PI control as in Hairer's DOPRI5)
            let expo1 = 0.2 - 0.04 * 0.75;
            let fac11 = err.powf(expo1);
            if err > 1.0 {
                let fac = (fac11 / 0.9).min(5.0);
                h = hs / fac;
                self.stats.rejected += 1;
                last_rejected = true;
                if h < 1e-15 * period.max(t.abs()) {
                    return Err(Error::Integration {
                        t,
                        reason: format!("step size underflow (h = {h:e})"),
                    });
                }
                continue;
            }
            let mut fac = fac11 / facold.powf(0.04);
            fac = (fac / 0.9).clamp(0.1, 5.0);
            let mut hnew = hs / fac;
            facold = err.max(1e-4);
            if last_rejected {
                hnew = hnew.min(hs);
            }
            last_rejected = false;
            self.stats.steps += 1;

            // dense output (Hairer's continuous extension of order 4). The coefficients of β and ω
            // serve the event probes and samples on every step; those of the Jacobian columns are
            // formed only when an event needs the augmented state inside the step.
            let coeffs = |i: usize| -> [f64; 5] {
                let ydiff = yn[i] - y[i];
                let bspl = hs * k[0][i] - ydiff;
                [
                    y[i],
                    ydiff,
                    bspl,
                    ydiff - hs * k[6][i] - bspl,
                    hs * (D1 * k[0][i]
                        + D3 * k[2][i]
                        + D4 * k[3][i]
                        + D5 * k[4][i]
                        + D6 * k[5][i]
                        + D7 * k[6][i]),
                ]
            };
            let state_coeffs = [coeffs(0), coeffs(1)];
            let dense = |i: usize, th: f64| -> f64 {
                let c = if i < 2 { state_coeffs[i] } else { coeffs(i) };
                let th1 = 1.0 - th;
                c[0] + th * (c[1] + th1 * (c[2] + th * (c[3] + th1 * c[4])))
            };

            // event search: first θ with s·ω(θ) ≤ 0
            let e = |th: f64| -> f64 { s * dense(1, th) };
            let mut root: Option<(f64, f64)> = None;
            let mut th_prev = 0.0;
            for j in 1..=EVENT_PROBES {
                let th = j as f64 / EVENT_PROBES as f64;
                let ev = if j == EVENT_PROBES { s * yn[1] } else { e(th) };
                if ev <= 0.0 {
                    root = Some((th_prev, th));
                    break;
                }
                th_prev = th;
            }

            if let Some((lo, hi)) = root {
                // bracket: e(lo) > 0 (or lo = 0, the start), e(hi) ≤ 0; refine by Illinois regula falsi
                let mut flo = if lo == 0.0 { s * y[1] } else { e(lo) };
                let fhi = if hi == 1.0 { s * yn[1] } else { e(hi) };
                if flo <= 0.0 {
                    // starts on Σ (just after an event) and the sign is wrong at once: bisect the
                    // interior for a positive point to bracket with; if none, the root is at the start
                    flo = 0.0;
                }
                let mut root = Illinois::new(lo, flo, hi, fhi, 0.0);
                for _ in 0..200 {
                    if root.hi() - root.lo() <= 4.0 * f64::EPSILON * root.hi().max(1e-300) {
                        break;
                    }
                    let Some(mid) = root.next_point() else {
                        break;
                    };
                    root.update(mid, e(mid));
                }
                let thc = root.hi();
                let tc = t + thc * hs;
                // samples strictly before the event from the dense output
                self.samples_dense(t, hs, tc, &dense, false);
                let mut yc = [0.0; NMAX];
                for (i, v) in yc.iter_mut().enumerate().take(n) {
                    *v = dense(i, thc);
                }
                yc[1] = 0.0;
                if tc - last_event_t <= tiny {
                    stalled += 1;
                } else {
                    stalled = 0;
                }
                if stalled > 16 {
                    return Err(Error::Integration {
                        t: tc,
                        reason: "events repeat without progress (degenerate contact with ω = 0)"
                            .into(),
                    });
                }
                last_event_t = tc;
                mode = self.handle_arrival(tc, &mut yc, s, stalled > 8);
                y = yc;
                t = tc;
                fsal = false;
                h = hnew.max(hs * 0.5);
                continue;
            }

            // no event: accept the whole step
            self.samples_dense(t, hs, tn, &dense, true);
            y = yn;
            k[0] = k[6];
            t = tn;
            h = hnew;
        }

        if self.next_sample < self.opts.sample_times.len() && mode == Mode::Stick {
            self.samples_constant(t, y[0]);
        }
        let (jac_x, jac_p) = self.layout.jacobians(&y);
        Ok(Flow {
            t,
            x: [y[0], y[1]],
            mode,
            jac_x,
            jac_p,
            events: self.events,
            samples: self.samples,
            stats: self.stats,
        })
    }

    /// Records the requested samples in (t, t_end) (or (t, t_end] when `inclusive`) from the dense output.
    fn samples_dense<F: Fn(usize, f64) -> f64>(
        &mut self,
        t: f64,
        hs: f64,
        t_end: f64,
        dense: &F,
        inclusive: bool,
    ) {
        while let Some(&ts) = self.opts.sample_times.get(self.next_sample) {
            if ts > t_end || (!inclusive && ts >= t_end) {
                break;
            }
            let th = ((ts - t) / hs).clamp(0.0, 1.0);
            self.samples.push(Sample {
                t: ts,
                beta: dense(0, th),
                omega: dense(1, th),
            });
            self.next_sample += 1;
        }
    }

    /// Decides what happens when ω reaches 0 from side `s` at time `tc`, applies the saltation
    /// matrix to the Jacobian columns, records the event, and returns the new mode.
    fn handle_arrival(&mut self, tc: f64, y: &mut V, s: f64, force_stick: bool) -> Mode {
        let sys = self.sys;
        let beta = y[0];
        let f = sys.forces(tc, beta, 0.0);
        let rs = sys.static_friction(tc, beta);
        if f.a.abs() <= rs || force_stick {
            self.stick_saltation(y);
            self.record_event(tc, beta, EventKind::StickStart);
            return Mode::Stick;
        }
        let new_side = if f.a > 0.0 { 1.0 } else { -1.0 };
        if new_side == s {
            // tangency: the acceleration on side s points away from Σ; no switch, S = I
            self.record_event(tc, beta, EventKind::Graze { side: s as i8 });
            return Mode::from_side(s);
        }
        let a_before = f.a - s * f.r;
        let a_after = f.a - new_side * f.r;
        let ratio = a_after / a_before;
        for c in 0..self.layout.ncols {
            y[z_omega(c)] *= ratio;
        }
        self.record_event(
            tc,
            beta,
            EventKind::Crossing {
                from: s as i8,
                to: new_side as i8,
            },
        );
        Mode::from_side(new_side)
    }

    /// Stick entry: S = diag(1, 0) (the sliding field vanishes).
    fn stick_saltation(&self, y: &mut V) {
        for c in 0..self.layout.ncols {
            y[z_omega(c)] = 0.0;
        }
    }

    /// Release with a jump of the acceleration (static friction above sliding friction):
    /// Z₊ = Z₋ − F₊ dt_r/dz, with dt_r/dz = −(G_β Z_β + G_p)/G_t from G(t, β) = |a| − r_s = 0.
    fn release_saltation(&self, y: &mut V, tr: f64, jump: f64, s: f64) {
        let sys = self.sys;
        let beta = y[0];
        let period = sys.period();
        let ht = 1e-7 * period;
        let hb = 1e-7;
        let gt = (release_function(sys, tr + ht, beta) - release_function(sys, tr - ht, beta))
            / (2.0 * ht);
        let gb = (release_function(sys, tr, beta + hb) - release_function(sys, tr, beta - hb))
            / (2.0 * hb);
        if gt == 0.0 || !gt.is_finite() {
            return;
        }
        let jet = sys.forces_jet(tr, beta, 0.0, self.layout.with_params);
        for c in 0..self.layout.ncols {
            let mut gz = gb * y[z_beta(c)];
            if c >= param_col(0) {
                // ∂G/∂p = sgn(a) ∂a/∂p − ∂r_s/∂p, taking ∂r_s/∂p = ∂r/∂p
                let k = c - param_col(0);
                gz += s * jet.a_p[k] - jet.r_p[k];
            }
            let dt = -gz / gt;
            // F₊ − F₋ = (0, jump)
            y[z_omega(c)] -= jump * dt;
        }
    }
}
