//! A drive whose frequency changes linearly in time: the system of a slow sweep.
//!
//! For a system whose forces depend on time only through the drive phase φ(t) = 2π f₀ t (the gear:
//! α = α₀ + 2π f t), a ramp f(t) = f₀ + ḟ t has the phase 2π (f₀ t + ḟ t²/2) = 2π f₀ w(t) with the
//! warped time
//!
//! ```text
//!   w(t) = t + ḟ t² / (2 f₀),
//! ```
//!
//! so the ramped forces are the inner forces at time w(t): F̂(t, β, ω) = F(w(t), β, ω). The
//! instantaneous frequency is f(t) = f₀ w'(t). Valid while f(t) > 0. The ramp breaks the time
//! periodicity: no half-period symmetry, no parameter columns; `period()` is the inner T = 1/f₀
//! (it only sets the integrator's largest step).

use super::{DrivenOscillator, Forces, ForcesJet};
use crate::error::{Error, Result};

/// `inner` with its drive frequency ramped at `rate` (Hz/s) from f₀ = 1/T at t = 0 (module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ramped<S> {
    inner: S,
    rate: f64,
    f0: f64,
}

impl<S: DrivenOscillator> Ramped<S> {
    /// Ramps the drive of `inner` (whose forces depend on t only through 2πt/T) at `rate` Hz/s.
    pub fn new(inner: S, rate: f64) -> Result<Self> {
        if !rate.is_finite() {
            return Err(Error::InvalidParameter {
                name: "rate",
                value: rate,
                reason: "a ramp rate must be finite",
            });
        }
        let f0 = 1.0 / inner.period();
        Ok(Self { inner, rate, f0 })
    }

    /// The instantaneous drive frequency f(t) = f₀ + ḟ t.
    pub fn frequency(&self, t: f64) -> f64 {
        self.f0 + self.rate * t
    }

    /// The warped time w(t) = t + ḟ t²/(2 f₀) at which the inner system is evaluated.
    pub fn warped(&self, t: f64) -> f64 {
        t + 0.5 * self.rate * t * t / self.f0
    }

    /// The time at which the ramp reaches frequency `f` (may be negative or past the end).
    pub fn time_of(&self, f: f64) -> f64 {
        if self.rate == 0.0 {
            f64::INFINITY
        } else {
            (f - self.f0) / self.rate
        }
    }
}

impl<S: DrivenOscillator> DrivenOscillator for Ramped<S> {
    fn period(&self) -> f64 {
        self.inner.period()
    }

    fn forces(&self, t: f64, beta: f64, omega: f64) -> Forces {
        self.inner.forces(self.warped(t), beta, omega)
    }

    fn forces_jet(&self, t: f64, beta: f64, omega: f64, _params: bool) -> ForcesJet {
        self.inner.forces_jet(self.warped(t), beta, omega, false)
    }

    fn static_friction(&self, t: f64, beta: f64) -> f64 {
        self.inner.static_friction(self.warped(t), beta)
    }

    fn angular(&self) -> bool {
        self.inner.angular()
    }

    fn reduce_angle(&self, beta: f64) -> f64 {
        self.inner.reduce_angle(beta)
    }

    fn drive_phase(&self, t: f64) -> f64 {
        self.inner.drive_phase(self.warped(t))
    }

    fn co_rotation(&self) -> f64 {
        self.inner.co_rotation()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Gear;

    #[test]
    fn ramped_drive_phase_is_the_integral_of_the_frequency() {
        let g = Gear::paper(0.0, 4.0).unwrap();
        let r = Ramped::new(g, -0.01).unwrap();
        let t = 37.0;
        // φ(t) = 2π ∫ f = 2π (f₀ t + ḟ t²/2)
        let phase = std::f64::consts::TAU * (4.0 * t - 0.005 * t * t);
        assert!((r.drive_phase(t) - phase).abs() < 1e-9 * phase.abs());
        assert!((r.frequency(t) - 3.63).abs() < 1e-12);
        assert!((r.time_of(3.63) - t).abs() < 1e-9);
        // forces equal to those of the gear at the warped time
        let (a, b) = (r.forces(t, 0.3, 1.0), g.forces(r.warped(t), 0.3, 1.0));
        assert_eq!(a, b);
        assert!(Ramped::new(g, f64::NAN).is_err());
    }
}
