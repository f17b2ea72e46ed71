//! Identification and diagnosis (issue 5): from recording sets (ring-downs and driven runs) to
//! fitted parameters, the location of the model mismatch, and the name of the missing physics.
//!
//! - [`preprocess`]: outlier rejection, noise estimate, local-polynomial velocity.
//! - [`ringdown`]: per-run fits of eq. `model` by simulation with the exact Filippov integrator and
//!   Levenberg–Marquardt; κ(α0) → g, |Δ|, I with the set-up's tolerances.
//! - [`regression`]: weak-form equation-error regression for all runs (chaotic driven runs included).
//! - [`catalog`]: physically parameterised candidate terms and a sparse dictionary search.
//! - [`diagnose`]: mismatch fingerprints, selection by held-out runs and BIC, verdict, report.
//! - [`synth`]: synthetic recording sets from a truth model with a chosen effect.
//! - [`model`]: the augmented gear used by the simulations.
//! - [`shooting`]: refit of a selected model by simulation over short windows (multiple shooting).

pub mod catalog;
pub mod diagnose;
pub mod lm;
pub mod model;
pub mod predict;
pub mod preprocess;
pub mod regression;
pub mod release;
pub mod report;
pub mod ringdown;
pub mod shooting;
pub mod synth;
