//! Python bindings of gearbif: the extension module `gearbif._core`, which the Python package
//! `gearbif` (python/gearbif/) re-exports with its result classes and type stubs.
//!
//! Units follow the Rust library: time in s, frequencies in Hz, states (β, ω) in rad and rad/s on
//! the lift (windings counted), shaft angles in degrees where the argument name ends in `_deg`.
//! Arrays come back as numpy arrays; composite results as dicts (the same field names as the
//! CLI's JSON, docs/formats.md), which the package turns into its result objects. Every error of
//! the library is raised as a subclass of `gearbif.GearbifError` and of the matching builtin.

mod analysis;
mod branches;
mod convert;
mod dynamics;
mod errors;
mod located;
mod systems;
mod user;

use pyo3::prelude::*;

/// gearbif: exact (Filippov, event-driven) simulation, Poincaré maps with Jacobians, periodic
/// orbits, continuation with special points, classification, sweeps and identification of
/// periodically driven oscillators with dry friction — the dipole magnetic gear of
/// Hartung & Rehberg (2020) built in, and any system written in Python (UserSystem).
///
/// Units: t [s], f [Hz], β [rad], ω [rad/s] (states on the lift); shaft angles Θ, Φ in degrees
/// (arguments ending in `_deg`).
#[pymodule(name = "_core")]
fn gearbif_module(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    errors::register(m)?;
    systems::register(m)?;
    dynamics::register(m)?;
    branches::register(m)?;
    analysis::register(m)?;
    Ok(())
}
