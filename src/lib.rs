//! # gearbif
//!
//! Exact simulation, periodic orbits, bifurcations and identification of periodically driven
//! oscillators with dry friction. The flagship system is the dipole magnetic gear of
//! Hartung & Rehberg (2020), [`model::Gear`].
//!
//! Data flows one way: parameters → system ([`model`]) → integrator ([`integrator`]) →
//! Poincaré maps ([`maps`]) → orbits, continuation, analysis, identification → outputs.
//!
//! ```
//! use gearbif::model::GearParams;
//! let gear = GearParams::paper();               // the paper's gear, Θ = Φ = 0
//! let fc = gear.lock_loss_frequency().unwrap(); // f_c = (g − η)/(2πζ)
//! assert!((fc - 39.84).abs() < 0.01);
//! ```
#![warn(missing_docs)]

pub mod analysis;
pub mod bench;
pub mod campaign;
#[cfg(feature = "cli")]
pub mod cli;
pub mod continuation;
pub mod error;
pub mod identification;
pub mod integrator;
pub mod io;
pub mod maps;
pub mod model;
pub mod numerics;
pub mod orbits;
#[cfg(feature = "plot")]
pub mod plotting;
pub mod progress;
pub mod report;
pub mod sweep;

pub use error::{Error, Result};

/// The README's library example, compiled and run as a doc test.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;
