//! Typed errors: every fallible operation in gearbif returns [`Error`].

use thiserror::Error;

/// The error type of gearbif.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum Error {
    /// A parameter is non-finite or outside its admissible range.
    #[error("invalid parameter `{name}` = {}: {reason}", show(*value))]
    InvalidParameter {
        /// The parameter's name as in the docs (e.g. `inertia`, `f`).
        name: &'static str,
        /// The offending value.
        value: f64,
        /// What the admissible range is.
        reason: &'static str,
    },
    /// A state or time given to the integrator is non-finite or inconsistent.
    #[error("invalid input: {0}")]
    InvalidInput(String),
    /// The integrator could not finish (step size underflow, too many steps, non-finite state).
    #[error("integration failed at t = {t}: {reason}")]
    Integration {
        /// Time reached.
        t: f64,
        /// Why it stopped.
        reason: String,
    },
    /// A Newton iteration did not converge.
    #[error(
        "Newton iteration failed after {iterations} iterations (residual {residual:e}): {reason}"
    )]
    NewtonFailed {
        /// Iterations done.
        iterations: usize,
        /// Last residual norm.
        residual: f64,
        /// Context.
        reason: String,
    },
    /// A continuation could not proceed.
    #[error("continuation stopped: {0}")]
    Continuation(String),
    /// Reading or parsing input files failed.
    #[error("{0}")]
    Io(String),
    /// The requested operation is not available for this system (e.g. no half-period symmetry).
    #[error("unsupported: {0}")]
    Unsupported(String),
    /// An input file is malformed: a recording set's experiment.toml or CSV file, a `--config`
    /// TOML file or a sweep checkpoint.
    #[error("{file}{}: {what}", line.map(|l| format!(":{l}")).unwrap_or_default())]
    Recording {
        /// The file at fault.
        file: String,
        /// The 1-based line, when one line is at fault.
        line: Option<usize>,
        /// What is wrong.
        what: String,
    },
}

/// A number for a message: plain when moderate, in scientific notation when very large or small
/// (so `1e308` is not printed with 309 digits).
pub(crate) fn show(v: f64) -> String {
    if v == 0.0 || !v.is_finite() || (1e-4..1e6).contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// Result alias used throughout the crate.
pub type Result<T> = std::result::Result<T, Error>;

/// Checks that `value` is finite, returning [`Error::InvalidParameter`] otherwise.
pub(crate) fn finite(name: &'static str, value: f64) -> Result<f64> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(Error::InvalidParameter {
            name,
            value,
            reason: "must be finite",
        })
    }
}

/// Checks that `value` is finite and strictly positive.
pub(crate) fn positive(name: &'static str, value: f64) -> Result<f64> {
    finite(name, value)?;
    if value > 0.0 {
        Ok(value)
    } else {
        Err(Error::InvalidParameter {
            name,
            value,
            reason: "must be > 0",
        })
    }
}

/// Checks that `value` is finite and non-negative.
pub(crate) fn non_negative(name: &'static str, value: f64) -> Result<f64> {
    finite(name, value)?;
    if value >= 0.0 {
        Ok(value)
    } else {
        Err(Error::InvalidParameter {
            name,
            value,
            reason: "must be >= 0",
        })
    }
}
