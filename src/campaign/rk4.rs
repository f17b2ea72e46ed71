//! The campaign generator's own integrator, independent of [`crate::integrator`]: classical RK4
//! with a small fixed step on each side of Σ = {β̇ = 0}, crossings of Σ located by bisection on the
//! step length (ω(θ) = 0 with θ the length of an RK4 step from the step's start), and the exact
//! Filippov stick rule: on Σ the output sticks while |smooth part| ≤ R(α_m, β, 0) (the static
//! friction bound) and is released, by bisection in time, at the instant that bound is exceeded,
//! into the direction of the smooth part.

use super::truth::{Drive, TruthModel};
use crate::error::{Error, Result};
use crate::numerics::{Bisection, Side};

/// The integrator's settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rk4Filippov {
    /// Fixed step, s.
    pub step: f64,
}

impl Default for Rk4Filippov {
    fn default() -> Self {
        Self { step: 2.5e-4 }
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Phase {
    Slip(f64),
    Stick,
}

/// The state of an integration: time, (β, ω) and the phase.
#[derive(Debug, Clone, Copy, PartialEq)]
struct State {
    t: f64,
    x: [f64; 2],
    phase: Phase,
}

/// Counters of an integration (for tests and reports).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Rk4Stats {
    /// RK4 steps taken (bisection trial steps included).
    pub steps: usize,
    /// Stick phases entered.
    pub sticks: usize,
    /// Releases from stick.
    pub releases: usize,
    /// Crossings of Σ without sticking.
    pub crossings: usize,
}

struct Sys<'a> {
    m: &'a TruthModel,
    d: Drive,
}

impl Sys<'_> {
    fn parts(&self, t: f64, beta: f64, omega: f64) -> (f64, f64) {
        let am = self.m.magnet_angle(self.d.angle(t), beta);
        (
            self.m.smooth(am, beta, omega),
            self.m.friction(am, beta, omega),
        )
    }
    fn field(&self, t: f64, x: [f64; 2], s: f64) -> [f64; 2] {
        let (a, r) = self.parts(t, x[0], x[1]);
        [x[1], a - s * r]
    }
    fn rk4(&self, t: f64, x: [f64; 2], h: f64, s: f64) -> [f64; 2] {
        let k1 = self.field(t, x, s);
        let k2 = self.field(
            t + 0.5 * h,
            [x[0] + 0.5 * h * k1[0], x[1] + 0.5 * h * k1[1]],
            s,
        );
        let k3 = self.field(
            t + 0.5 * h,
            [x[0] + 0.5 * h * k2[0], x[1] + 0.5 * h * k2[1]],
            s,
        );
        let k4 = self.field(t + h, [x[0] + h * k3[0], x[1] + h * k3[1]], s);
        [
            x[0] + h / 6.0 * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0]),
            x[1] + h / 6.0 * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1]),
        ]
    }
    /// Excess of the smooth part over the static bound at rest: > 0 means the output slips.
    fn release_margin(&self, t: f64, beta: f64) -> (f64, f64) {
        let (a, r) = self.parts(t, beta, 0.0);
        (a.abs() - r, a)
    }
    /// On Σ at (t, β): stick if |a| ≤ R(·, 0), else slip towards sgn a.
    fn phase_on_sigma(&self, t: f64, beta: f64) -> Phase {
        let (margin, a) = self.release_margin(t, beta);
        if margin <= 0.0 {
            Phase::Stick
        } else {
            Phase::Slip(a.signum())
        }
    }
}

impl Rk4Filippov {
    /// Integrates the truth from (t₀, β₀, ω₀) and returns β at `times` (sorted, ≥ t₀).
    pub fn sample(
        &self,
        model: &TruthModel,
        drive: Drive,
        t0: f64,
        x0: [f64; 2],
        times: &[f64],
    ) -> Result<(Vec<f64>, Rk4Stats)> {
        if !(self.step > 0.0 && self.step.is_finite()) {
            return Err(Error::InvalidParameter {
                name: "step",
                value: self.step,
                reason: "the RK4 step must be finite and > 0",
            });
        }
        if let Some(&t) = times.first().filter(|&&t| t < t0) {
            return Err(Error::InvalidTimes {
                t0,
                t1: t,
                reason: "sample times must not be before the start",
            });
        }
        if let Some(w) = times.windows(2).find(|w| w[1] < w[0]) {
            return Err(Error::InvalidTimes {
                t0: w[0],
                t1: w[1],
                reason: "sample times must be sorted",
            });
        }
        let sys = Sys { m: model, d: drive };
        let phase = if x0[1] != 0.0 {
            Phase::Slip(x0[1].signum())
        } else {
            sys.phase_on_sigma(t0, x0[0])
        };
        let mut st = State {
            t: t0,
            x: x0,
            phase,
        };
        let mut stats = Rk4Stats::default();
        let mut out = Vec::with_capacity(times.len());
        for &ts in times {
            self.advance(&sys, &mut st, ts, &mut stats)?;
            out.push(st.x[0]);
        }
        Ok((out, stats))
    }

    fn advance(&self, sys: &Sys, st: &mut State, t_end: f64, stats: &mut Rk4Stats) -> Result<()> {
        while st.t < t_end {
            let h = self.step.min(t_end - st.t);
            match st.phase {
                Phase::Slip(s) => self.slip_step(sys, st, h, s, stats),
                Phase::Stick => {
                    if sys.d.rate == 0.0 {
                        // locked input: nothing depends on time, the output stays stuck
                        st.t = t_end;
                        continue;
                    }
                    self.stick_step(sys, st, h, stats)
                }
            }
            if !(st.x[0].is_finite() && st.x[1].is_finite()) {
                return Err(Error::Integration {
                    t: st.t,
                    reason: "non-finite state in the campaign's RK4 integrator".into(),
                });
            }
        }
        Ok(())
    }

    /// One slip step of length h on side s; a crossing of Σ inside it is located by bisection on
    /// the step length and the Filippov rule decides what follows.
    fn slip_step(&self, sys: &Sys, st: &mut State, h: f64, s: f64, stats: &mut Rk4Stats) {
        let x1 = sys.rk4(st.t, st.x, h, s);
        stats.steps += 1;
        if s * x1[1] > 0.0 {
            st.t += h;
            st.x = x1;
            return;
        }
        // the step length at which ω reaches Σ: the predicate "s ω ≤ 0" switches from false to true
        let mut b = Bisection::new(0.0, h);
        let mut x_hi = x1;
        while let Some(mid) = b.next_point() {
            let xm = sys.rk4(st.t, st.x, mid, s);
            stats.steps += 1;
            if b.update(mid, s * xm[1] <= 0.0) == Side::Hi {
                x_hi = xm;
            }
        }
        let hi = b.hi();
        st.t += hi;
        st.x = [x_hi[0], 0.0];
        st.phase = sys.phase_on_sigma(st.t, st.x[0]);
        match st.phase {
            Phase::Stick => stats.sticks += 1,
            Phase::Slip(_) => stats.crossings += 1,
        }
    }

    /// One step of length h at rest; a release inside it is located by bisection in time.
    fn stick_step(&self, sys: &Sys, st: &mut State, h: f64, stats: &mut Rk4Stats) {
        let beta = st.x[0];
        let (m_end, _) = sys.release_margin(st.t + h, beta);
        if m_end <= 0.0 {
            st.t += h;
            return;
        }
        let mut b = Bisection::new(st.t, st.t + h);
        while let Some(mid) = b.next_point() {
            b.update(mid, sys.release_margin(mid, beta).0 > 0.0);
        }
        let hi = b.hi();
        st.t = hi;
        let (_, a) = sys.release_margin(hi, beta);
        st.phase = Phase::Slip(a.signum());
        stats.releases += 1;
    }
}
