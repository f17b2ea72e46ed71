//! The one-sided (virtual) flow of a system: the smooth vector field of one side of the switching
//! surface Σ = {ω = 0}, continued across Σ without events.
//!
//! For a side s ∈ {+1, −1} the system
//!
//! ```text
//!   β̇ = ω,   ω̇ = a(t, β, ω) − s · r(t, β, ω)      (s fixed, also where sgn ω ≠ s)
//! ```
//!
//! is smooth. It is written as a [`DrivenOscillator`] with smooth force a − s·r and no dry friction
//! (r = 0), so every integrator, map and Jacobian of the crate applies unchanged: with r = 0 an
//! arrival on Σ is a crossing with saltation diag(1, a/a) = I and the output never sticks. Where
//! an orbit of the original system stays on side s, the two flows coincide; where the original
//! orbit touches Σ (grazing, the onset of sticking) the one-sided orbit dips through it. Grazing
//! curves are defined on this flow ([`crate::continuation::palc2::continue_grazing_curve`]): its
//! smallest s·ω over the orbit is a smooth, signed test function.

use super::{Column, MAX_PARAMS};
use super::{DrivenOscillator, Forces, ForcesJet, HalfPeriodSymmetry, Parametrised};
use crate::error::{Error, Result};

/// A system restricted to the smooth field of one side of Σ (module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OneSided<S> {
    inner: S,
    side: f64,
}

impl<S: DrivenOscillator> OneSided<S> {
    /// The one-sided flow of `inner` on side `side` (+1: ω > 0, −1: ω < 0).
    pub fn new(inner: S, side: f64) -> Result<Self> {
        if side != 1.0 && side != -1.0 {
            return Err(Error::InvalidParameter {
                name: "side",
                value: side,
                reason: "the side of a one-sided flow is +1 or -1",
            });
        }
        Ok(Self { inner, side })
    }

    /// The original system.
    pub fn inner(&self) -> &S {
        &self.inner
    }

    /// The side s.
    pub fn side(&self) -> f64 {
        self.side
    }
}

impl<S: DrivenOscillator> DrivenOscillator for OneSided<S> {
    fn period(&self) -> f64 {
        self.inner.period()
    }

    fn n_params(&self) -> usize {
        self.inner.n_params()
    }

    fn param_name(&self, k: usize) -> &'static str {
        self.inner.param_name(k)
    }

    fn period_derivative(&self, k: usize) -> f64 {
        self.inner.period_derivative(k)
    }

    /// a − s·r, and r = 0.
    fn forces(&self, t: f64, beta: f64, omega: f64) -> Forces {
        let f = self.inner.forces(t, beta, omega);
        Forces {
            a: f.a - self.side * f.r,
            r: 0.0,
        }
    }

    fn forces_jet(&self, t: f64, beta: f64, omega: f64, params: bool) -> ForcesJet {
        let j = self.inner.forces_jet(t, beta, omega, params);
        let s = self.side;
        let mut out = ForcesJet::new(j.a - s * j.r, 0.0);
        out.a_beta = j.a_beta - s * j.r_beta;
        out.a_omega = j.a_omega - s * j.r_omega;
        for k in 0..MAX_PARAMS {
            out.a_p[k] = j.a_p[k] - s * j.r_p[k];
        }
        out
    }

    fn static_friction(&self, _t: f64, _beta: f64) -> f64 {
        0.0
    }

    /// Never stuck: a state on Σ leaves at once.
    fn next_release(&self, t: f64, _beta: f64, _t_max: f64) -> Option<f64> {
        Some(t)
    }

    /// The original symmetry if it keeps the side (σ = +1); a reflection ω → −ω exchanges the
    /// sides, so the one-sided flow has no half-period symmetry then.
    fn half_period_symmetry(&self) -> Option<HalfPeriodSymmetry> {
        self.inner.half_period_symmetry().filter(|r| r.sign > 0.0)
    }

    fn angular(&self) -> bool {
        self.inner.angular()
    }

    fn reduce_angle(&self, beta: f64) -> f64 {
        self.inner.reduce_angle(beta)
    }

    fn drive_phase(&self, t: f64) -> f64 {
        self.inner.drive_phase(t)
    }

    fn co_rotation(&self) -> f64 {
        self.inner.co_rotation()
    }
}

impl<S: Parametrised> Parametrised for OneSided<S> {
    type Param = S::Param;

    fn param(&self, p: S::Param) -> f64 {
        self.inner.param(p)
    }

    fn with_param(&self, p: S::Param, value: f64) -> Result<Self> {
        Ok(Self {
            inner: self.inner.with_param(p, value)?,
            side: self.side,
        })
    }

    fn column(&self, p: S::Param) -> Option<Column> {
        self.inner.column(p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrator::{EventDriven, FlowMethod, FlowOptions, Sensitivity};
    use crate::model::Gear;

    #[test]
    fn one_sided_flow_equals_the_original_while_on_its_side_and_passes_sigma_smoothly() {
        // the lock at Θ = 25°, 5 Hz turns forward (ω > 0) all the time: both flows agree
        let g = Gear::paper(25.0, 5.0).unwrap();
        let o = FlowOptions::with_tol(1e-11).sensitivity(Sensitivity::State);
        let x0 = [1.57, std::f64::consts::TAU * 5.0];
        let a = EventDriven.flow(&g, 0.0, x0, 0.2, &o).unwrap();
        let os = OneSided::new(g, 1.0).unwrap();
        let b = EventDriven.flow(&os, 0.0, x0, 0.2, &o).unwrap();
        assert!(a.events.is_empty());
        assert!((a.x[0] - b.x[0]).abs() < 1e-12 && (a.x[1] - b.x[1]).abs() < 1e-10);
        // from rest the original sticks; the one-sided flow (ω̇ = a − η) runs through Σ
        let o = o.record_events(true);
        let c = EventDriven.flow(&os, 0.0, [0.0, 0.0], 0.2, &o).unwrap();
        assert!(c
            .events
            .iter()
            .all(|e| !matches!(e.kind, crate::integrator::EventKind::StickStart)));
        let m = c.jac_x.unwrap();
        assert!(
            m.determinant() > 0.0,
            "no stick saltation: det = {}",
            m.determinant()
        );
        assert!(OneSided::new(g, 0.5).is_err());
    }
}
