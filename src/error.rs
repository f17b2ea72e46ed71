//! Typed errors: every fallible operation in gearbif returns [`Error`].

use std::sync::Arc;
use thiserror::Error;

/// The underlying error (io, JSON, TOML, CSV) kept as the source of an [`Error`]; shared, so that
/// errors stay cheap to clone. Two sources compare equal when their messages do.
#[derive(Debug, Clone)]
pub struct Source(pub Arc<dyn std::error::Error + Send + Sync + 'static>);

impl Source {
    /// Wraps an error.
    pub fn new(e: impl std::error::Error + Send + Sync + 'static) -> Self {
        Self(Arc::new(e))
    }
}

impl PartialEq for Source {
    fn eq(&self, other: &Self) -> bool {
        self.0.to_string() == other.0.to_string()
    }
}

impl std::fmt::Display for Source {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.0.fmt(f)
    }
}

impl std::error::Error for Source {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        self.0.source()
    }
}

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
    /// A parameter name that the system does not declare.
    #[error("unknown parameter `{name}` (expected one of: {expected})")]
    UnknownParameter {
        /// The name given.
        name: String,
        /// The names the system declares.
        expected: String,
    },
    /// The parameter has no column in the map's parameter Jacobian, so it cannot be continued.
    #[error("parameter `{name}` has no Jacobian column: it can be swept but not continued")]
    NoParameterColumn {
        /// The parameter's name.
        name: &'static str,
    },
    /// A simulation did not settle on a periodic orbit of period ≤ `max_period`.
    #[error(
        "no period <= {max_period} detected after {relax_periods} periods (best closing error \
         {best_closing_error:e}); quasi-periodic, chaotic or not yet relaxed"
    )]
    NoPeriodDetected {
        /// Largest period tried, in drive periods.
        max_period: usize,
        /// Drive periods of relaxation before the test.
        relax_periods: usize,
        /// The smallest closing error |P_T^k(x) − x − (2πp, 0)| seen.
        best_closing_error: f64,
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
    /// Reading or parsing input files failed (without an underlying error to carry).
    #[error("{0}")]
    Io(String),
    /// A file or folder could not be read, written, created or moved into place.
    #[error("cannot {action} {path}: {source}")]
    File {
        /// What was attempted: "read", "write", "create", "move into place".
        action: &'static str,
        /// The path.
        path: String,
        /// The operating system's error.
        #[source]
        source: Source,
    },
    /// Data could not be encoded or decoded in a file format.
    #[error("{format} {what}: {source}")]
    Format {
        /// "JSON", "TOML" or "CSV".
        format: &'static str,
        /// What was being encoded or decoded (a file, a table).
        what: String,
        /// The format library's error.
        #[source]
        source: Source,
    },
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

impl Error {
    /// [`Error::File`] for `action` on `path`.
    pub fn file(
        action: &'static str,
        path: &std::path::Path,
        e: impl std::error::Error + Send + Sync + 'static,
    ) -> Self {
        Error::File {
            action,
            path: path.display().to_string(),
            source: Source::new(e),
        }
    }

    /// [`Error::Format`] for `what` in `format`.
    pub fn format(
        format: &'static str,
        what: impl Into<String>,
        e: impl std::error::Error + Send + Sync + 'static,
    ) -> Self {
        Error::Format {
            format,
            what: what.into(),
            source: Source::new(e),
        }
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
