//! The section of the basin computation: its map (G or P_T), the reduction of β modulo 2π, and the
//! distance used for neighbourhoods, recurrences and orbit identity.

use crate::error::Result;
use crate::integrator::{FlowOptions, DEFAULT_METHOD};
use crate::maps::{poincare_map, Section};
use crate::model::DrivenOscillator;
use std::f64::consts::{PI, TAU};

/// The section t ≡ 0 (mod T) of a system, with the distance
///
/// ```text
///   d(a, b) = √( (Δβ)² + (Δω · T/2π)² ),
/// ```
///
/// Δβ taken modulo 2π into [−π, π) when β is an angle ([`DrivenOscillator::angular`]): both terms
/// are angles (ω·T/2π is the angle turned in 1/2π of a period at speed ω).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SectionMetric {
    /// T/2π, the weight of ω.
    pub omega_weight: f64,
    /// β is an angle (compared modulo 2π).
    pub angular: bool,
    /// The iterated map is G (the system has the half-period symmetry) rather than P_T.
    pub half_period: bool,
}

impl SectionMetric {
    /// The section of `sys`.
    pub fn of<S: DrivenOscillator + ?Sized>(sys: &S) -> Self {
        Self {
            omega_weight: sys.period() / TAU,
            angular: sys.angular(),
            half_period: sys.half_period_symmetry().is_some(),
        }
    }

    /// The distance d(a, b) of the type documentation.
    pub fn distance(&self, a: [f64; 2], b: [f64; 2]) -> f64 {
        let mut db = a[0] - b[0];
        if self.angular {
            db = (db + PI).rem_euclid(TAU) - PI;
        }
        db.hypot(self.omega_weight * (a[1] - b[1]))
    }

    /// Smallest distance of `x` to one of `points`.
    pub fn distance_to(&self, x: [f64; 2], points: &[[f64; 2]]) -> f64 {
        points
            .iter()
            .map(|p| self.distance(x, *p))
            .fold(f64::INFINITY, f64::min)
    }

    /// β reduced into [0, 2π) for an angle, unchanged otherwise.
    pub fn reduce(&self, x: [f64; 2]) -> [f64; 2] {
        if self.angular {
            [x[0].rem_euclid(TAU), x[1]]
        } else {
            x
        }
    }

    /// Map applications per drive period: 2 for G, 1 for P_T.
    pub fn steps_per_period(&self) -> usize {
        if self.half_period {
            2
        } else {
            1
        }
    }

    /// One application of the iterated map (G or P_T) at tolerance `tol`, reduced.
    pub fn step<S: DrivenOscillator + ?Sized>(
        &self,
        sys: &S,
        x: [f64; 2],
        tol: f64,
    ) -> Result<[f64; 2]> {
        self.apply(sys, x, 1, tol)
    }

    /// `n` applications of the iterated map in one integration, reduced.
    pub fn apply<S: DrivenOscillator + ?Sized>(
        &self,
        sys: &S,
        x: [f64; 2],
        n: usize,
        tol: f64,
    ) -> Result<[f64; 2]> {
        let section = if self.half_period {
            Section::HalfPeriod
        } else {
            Section::Stroboscopic
        };
        let o = FlowOptions::with_tol(tol);
        Ok(self.reduce(poincare_map(&DEFAULT_METHOD, sys, section, x, n, &o)?.x))
    }

    /// P_T applied `n` times (β on the lift, not reduced).
    pub fn stroboscopic<S: DrivenOscillator + ?Sized>(
        &self,
        sys: &S,
        x: [f64; 2],
        n: usize,
        tol: f64,
    ) -> Result<[f64; 2]> {
        let o = FlowOptions::with_tol(tol);
        Ok(poincare_map(&DEFAULT_METHOD, sys, Section::Stroboscopic, x, n, &o)?.x)
    }
}
