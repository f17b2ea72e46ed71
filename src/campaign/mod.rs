//! Proof by campaigns: a second recording generator, separate from the diagnosis catalog (its own
//! equation of motion with terms in forms the catalog does not contain, its own integrator), and a
//! runner that diagnoses many generated sets and measures how often the diagnosis is right.
//!
//! - [`truth`]: the truth model, eq. in its module docs (vector bearing load, Stribeck breakaway,
//!   power-law drag, static torques with several harmonics, angle-modulated friction, compliant
//!   input, non-parallel shafts).
//! - [`rk4`]: classical RK4 with a fixed step, crossings of β̇ = 0 located by bisection, the exact
//!   Filippov stick rule.
//! - [`generator`]: recording sets in the documented format, with white or coloured camera noise,
//!   timing jitter, latency, outliers and coarse sampling.
//! - [`cases`]: the effects, their expected verdicts and headline truths.
//! - [`metrics`]: false-positive rate, power against size, confusion matrix, σ coverage.
//! - [`runner`]: the resumable, parallel campaign.
//! - [`render`]: the Markdown tables.

pub mod cases;
pub mod generator;
pub mod metrics;
pub mod render;
pub mod rk4;
pub mod rng;
pub mod runner;
pub mod truth;
