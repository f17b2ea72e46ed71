//! Identification and diagnosis: from recording sets (ring-downs and driven runs) to fitted
//! parameters, the location of the model mismatch, and the name of the missing physics.
//!
//! The diagnosis is a pipeline ([`diagnose`]): clean ([`preprocess`], [`ringdown`]) → fit base
//! ([`regression`], [`shooting`]) → mismatch ([`mismatch`]) → propose ([`propose`], [`catalog`])
//! → judge by simulation on held-out runs ([`beam`], [`select`], [`judge`], [`breakaway`],
//! [`backward`], [`nominal`]) → report ([`findings`], [`report`]).
//!
//! - [`spec`]: a model as terms and coefficients, mapped to the simulated gear ([`model`]).
//! - [`predict`]: short-horizon predictions over windows.
//! - [`profile`]: profiles of the families' shape parameters for the final model's sizes.
//! - [`curve`]: the nonparametric model of what remains (a curve in β with its band).
//! - [`synth`]: synthetic recording sets from a truth model with a chosen effect.

pub mod backward;
pub mod beam;
pub mod breakaway;
pub mod catalog;
pub mod curve;
pub mod diagnose;
pub mod export;
pub mod findings;
pub mod judge;
pub mod lm;
pub mod mismatch;
pub mod model;
pub mod nominal;
pub mod predict;
pub mod preprocess;
pub mod profile;
pub mod propose;
pub mod regression;
pub mod release;
pub mod report;
pub mod ringdown;
pub mod select;
pub mod shooting;
pub mod smoothing;
pub mod spec;
pub mod synth;
pub mod verdict;
