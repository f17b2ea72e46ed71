//! Global stability of a driven oscillator: the attractors of its stroboscopic map P_T, their
//! basins on the section t ≡ 0 (mod T), basin fractions with their binomial error, and the smallest
//! kick that throws a state out of its basin (docs/basins.md).
//!
//! - [`attractor`]: an attractor of P_T, periodic (refined by shooting, with its multipliers and a
//!   certified neighbourhood) or not (chaotic, quasi-periodic, at rest: told apart by the statistics
//!   of [`crate::analysis::rigorous_classify`]), and the thread-safe set of those found so far;
//! - [`recognise`]: iterates the map from one state until it enters a known attractor's
//!   neighbourhood or closes on a new periodic orbit;
//! - [`grid`]: the basin map on a (β, ω) grid, in parallel;
//! - [`sampling`]: basin fractions from uniform random samples, σ = √(p(1 − p)/n);
//! - [`kick`]: the minimal fatal kick of an attractor by scan and bisection along directions;
//! - [`follow`]: the attractors and their fractions followed over a parameter, with births and
//!   deaths.
//!
//! The iterated map is the half-period map G = R⁻¹ ∘ P_{T/2} when the system has the symmetry R,
//! else P_T. Modulo the 2π lift, P_T = G² (R² is the identity or the shift by 2π, model.md,
//! "Symmetry"), so the even iterates of G are those of P_T and the odd ones are their images under
//! G, which maps the basin of an attractor A of P_T onto the basin of its twin G(A) exactly.

pub mod attractor;
pub mod follow;
pub mod grid;
pub mod kick;
pub mod metric;
pub mod recognise;
pub mod sampling;

pub use attractor::{Attractor, AttractorKind, AttractorSet};
pub use follow::{follow_attractors, Follow, FollowOptions, FollowStep, TrackEvent};
pub use grid::{basin_map, BasinMap, Region};
pub use kick::{minimal_fatal_kick, FatalKick, KickNorm, KickOptions};
pub use metric::SectionMetric;
pub use recognise::{recognise, Outcome};
pub use sampling::{basin_fractions, Fraction, Fractions};

use crate::error::{Error, Result};
use crate::orbits::ShootingOptions;
use serde::{Deserialize, Serialize};

/// Options of the attractor search.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BasinOptions {
    /// Relative tolerance of the event-driven integrator while iterating.
    pub tol: f64,
    /// Largest number of map applications (half periods with the symmetry) before a trajectory is
    /// handed to the statistics of the non-periodic classification.
    pub max_steps: usize,
    /// Largest period of a new periodic attractor searched, in map applications.
    pub max_period: usize,
    /// A candidate period is shot when the trajectory repeats to within this distance
    /// ([`SectionMetric`]) on its last three returns.
    pub period_tol: f64,
    /// Initial radius of an attractor's neighbourhood; halved until certified
    /// ([`attractor::certify`]).
    pub neighbourhood: f64,
    /// Points on the circle that certifies a neighbourhood.
    pub ring_points: usize,
    /// Shooting that refines a periodic attractor.
    pub shooting: ShootingOptions,
    /// Turns of the non-periodic classification ([`crate::analysis::ClassifyOptions::analysis_turns`]).
    pub analysis_turns: usize,
}

impl Default for BasinOptions {
    fn default() -> Self {
        Self {
            tol: 1e-8,
            max_steps: 600,
            max_period: 16,
            period_tol: 1e-4,
            neighbourhood: 0.05,
            ring_points: 12,
            shooting: ShootingOptions::default(),
            analysis_turns: 60,
        }
    }
}

impl BasinOptions {
    /// Checks every option: a clear error instead of a hang or a NaN.
    pub fn validate(&self) -> Result<()> {
        crate::error::relative_tolerance("tol", self.tol)?;
        crate::error::positive("period_tol", self.period_tol)?;
        crate::error::positive("neighbourhood", self.neighbourhood)?;
        let at_least = |name: &str, v: usize, min: usize| {
            if v < min {
                Err(Error::option(name, format!("must be >= {min}, got {v}")))
            } else {
                Ok(())
            }
        };
        at_least("max_period", self.max_period, 1)?;
        at_least("max_steps", self.max_steps, 4 * self.max_period)?;
        at_least("ring_points", self.ring_points, 4)?;
        at_least("analysis_turns", self.analysis_turns, 2)
    }
}
