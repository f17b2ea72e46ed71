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
    /// An option (a command-line flag, a field of an options struct, a keyword argument) does not
    /// parse or lies outside its domain. One number with a fixed name outside its range is an
    /// [`Error::InvalidParameter`] instead.
    #[error("invalid {option}: {reason}")]
    InvalidOption {
        /// The option as the user wrote it (`--winding`, `axis \`f:1:x:2\``, `iterations`).
        option: String,
        /// What is wrong, with the value.
        reason: String,
    },
    /// A name (a kind, section, effect, method, set size) that is not one of the accepted ones.
    /// Parameter names have [`Error::UnknownParameter`].
    #[error("unknown {what} `{name}` (expected {expected})")]
    UnknownName {
        /// What the name names: "effect", "kind", "section", …
        what: &'static str,
        /// The name given.
        name: String,
        /// The accepted names, as a list ending in "or".
        expected: String,
    },
    /// Options that are each valid but do not go together: two sweep axes on one parameter, a
    /// flag that needs another, a minimum above a maximum, nothing to do.
    #[error("inconsistent options {options}: {reason}")]
    InconsistentOptions {
        /// The options involved (`--ds, --ds-max`).
        options: String,
        /// Why they do not go together.
        reason: String,
    },
    /// A state given to the integrator, a shooting, a curve or a classification is not finite.
    #[error("{what} must be finite, got ({})", state.iter().map(|&v| show(v)).collect::<Vec<_>>().join(", "))]
    NonFiniteState {
        /// Which state: "initial state", "start of a curve", …
        what: &'static str,
        /// Its components.
        state: Vec<f64>,
    },
    /// Integration or sample times that are not finite or not in increasing order.
    #[error("{reason} (t0 = {}, t1 = {})", show(*t0), show(*t1))]
    InvalidTimes {
        /// The first time of the offending pair.
        t0: f64,
        /// The second time of the offending pair.
        t1: f64,
        /// What is wrong.
        reason: &'static str,
    },
    /// Data of the wrong size: lengths that do not match, too few samples, no segments, no runs,
    /// an index beyond the end.
    #[error("{what}: expected {expected}, got {got}")]
    Shape {
        /// What was counted.
        what: String,
        /// What the operation needs (`>= 1`, `15 (one per angle)`).
        expected: String,
        /// What it got.
        got: usize,
    },
    /// A checkpoint or output folder that holds another computation, or is incomplete or damaged
    /// beyond what can be recomputed (a file that does not parse is an [`Error::Recording`]).
    #[error("{path}: {reason}")]
    Checkpoint {
        /// The folder or file at fault.
        path: String,
        /// What is wrong and what to do.
        reason: String,
    },
    /// A long computation was stopped by its observer before it finished.
    #[error("{what} was stopped before it finished")]
    Stopped {
        /// What was stopped: "sweep", "report sweep".
        what: &'static str,
    },
    /// The integrator could not finish (step size underflow, too many steps, non-finite state).
    #[error("integration failed at t = {t}: {reason}")]
    Integration {
        /// Time reached.
        t: f64,
        /// Why it stopped.
        reason: String,
    },
    /// The integrator used up its step budget (`FlowOptions::max_steps`, accepted and rejected
    /// steps) before the end time: a motion that needs far more steps than expected (a run-away
    /// trial model, chattering).
    #[error("integration stopped at t = {t}: more than {max_steps} steps")]
    StepBudget {
        /// Time reached.
        t: f64,
        /// The budget.
        max_steps: usize,
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
    /// A linear system of a continuation (a bordered matrix for a tangent or a test function)
    /// is singular.
    #[error("continuation stopped: singular {what}")]
    SingularMatrix {
        /// Which matrix, and what it was needed for.
        what: &'static str,
    },
    /// A continuation has no direction to go on in: a zero or non-finite tangent, two equal
    /// points, an eigenvector along the branch.
    #[error("continuation stopped: no direction to continue in ({what})")]
    DegenerateDirection {
        /// Which direction is degenerate.
        what: &'static str,
    },
    /// The orbit has no arrival on the stick surface Σ (ω = 0) whose edge could be tracked.
    #[error("continuation stopped: the orbit has no arrival on the stick surface Σ to track")]
    NoArrival,
    /// A special point without the critical eigenvector a branch switch needs.
    #[error("the {kind} point at {} carries no eigenvector to switch along", show(*param))]
    MissingEigenvector {
        /// The point's kind ("flip", "symmetry-breaking", …).
        kind: &'static str,
        /// The continuation parameter's value at the point.
        param: f64,
    },
    /// A branch switch found no orbit of the new branch near the special point.
    #[error("branch switching at {param} = {} found no new orbit ({reason})", show(*value))]
    NoNewBranch {
        /// The continuation parameter's name.
        param: &'static str,
        /// Its value at the special point.
        value: f64,
        /// What was found instead, or the last error.
        reason: String,
    },
    /// The start orbit of a continuation is too unstable for single shooting.
    #[error(
        "continuation stopped: the start orbit has |μ| = {multiplier:e} above the          single-shooting limit {limit:e}"
    )]
    MultiplierTooLarge {
        /// Spectral radius of the start orbit's monodromy matrix.
        multiplier: f64,
        /// The limit (`ContinuationOptions::max_multiplier`).
        limit: f64,
    },
    /// A test function of a codimension-two point is not finite inside its bracket.
    #[error("continuation stopped: non-finite {kind} test function")]
    NonFiniteTestFunction {
        /// The point's kind.
        kind: &'static str,
    },
    /// A test function changes sign across a discontinuity instead of vanishing.
    #[error(
        "the {kind} test function jumps instead of vanishing ({before:.2e} → {after:.2e},          {at_bracket:.2e} at the bracket)"
    )]
    TestFunctionJump {
        /// The point's kind.
        kind: &'static str,
        /// Value at the start of the bracket.
        before: f64,
        /// Value at its end.
        after: f64,
        /// Value at the last point of the location.
        at_bracket: f64,
    },
    /// A computation that looks for a point (a special point, a boundary, a start orbit) did not
    /// find it.
    #[error("not found: {what}")]
    NotFound {
        /// What was looked for, and where.
        what: String,
    },
    /// No periodic orbit to start a continuation from.
    #[error("no start orbit at {param} = {}: {reason}", show(*value))]
    NoStartOrbit {
        /// The continuation parameter's name.
        param: &'static str,
        /// Its value.
        value: f64,
        /// Why neither shooting nor a simulation gave one.
        reason: String,
    },
    /// The fate of the unstable manifold of the lock (re-lock or slip) was not decided within the
    /// time simulated.
    #[error("unstable manifold undecided after {t} s at f = {f} Hz")]
    ManifoldUndecided {
        /// Time simulated, s.
        t: f64,
        /// Drive frequency, Hz.
        f: f64,
    },
    /// A plotting backend failed; its message is kept as text.
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
    /// The half-period section G was asked of a system that declares no half-period symmetry
    /// ([`crate::model::DrivenOscillator::half_period_symmetry`]).
    #[error("unsupported: this system has no half-period symmetry (use the stroboscopic section)")]
    NoHalfPeriodSymmetry,
    /// A flow method returned no Jacobian where one was asked for (`what`: "state" for ∂x/∂x₀,
    /// "parameter" for ∂x/∂p): the method does not propagate sensitivities.
    #[error("unsupported: the flow method returned no {what} Jacobian")]
    MissingJacobian {
        /// "state" or "parameter".
        what: &'static str,
    },
    /// The gear never locks or has no viscous limit: f_c = (g − η)/(2πζ) needs ζ > 0 and g > η.
    #[error("unsupported: no lock-loss frequency f_c = (g − η)/(2πζ) for g = {}, ζ = {}, η = {} (needs ζ > 0 and g > η)", show(*g), show(*zeta), show(*eta))]
    NoLockLossFrequency {
        /// Coupling g, s⁻².
        g: f64,
        /// Viscous damping ζ, s⁻¹.
        zeta: f64,
        /// Dry friction η, s⁻².
        eta: f64,
    },
    /// A closed-form solution asked for outside the range where it exists (the gear's analytic
    /// lock branch away from Δ = ±1 or above f_c, Den Hartog's solution of an overdamped
    /// oscillator or with stops, the slip-through cycle away from Δ = 1).
    #[error("unsupported: {closed_form} needs {needs}")]
    OutsideClosedForm {
        /// The solution asked for.
        closed_form: &'static str,
        /// The condition it needs, with the value that violates it.
        needs: String,
    },
    /// A function whose root is sought has the same sign at both ends of the interval given.
    #[error(
        "{what} does not change sign on [{}, {}] ({f_lo:e}, {f_hi:e})",
        show(*lo),
        show(*hi)
    )]
    NotBracketed {
        /// The function.
        what: &'static str,
        /// Low end of the interval.
        lo: f64,
        /// High end.
        hi: f64,
        /// The function's value at `lo`.
        f_lo: f64,
        /// Its value at `hi`.
        f_hi: f64,
    },
    /// An operation on a special point of a kind it does not exist for.
    #[error("unsupported: {operation} is not available at a {kind} point")]
    UnsupportedPoint {
        /// The operation, with the kinds it exists for.
        operation: &'static str,
        /// The point's kind.
        kind: &'static str,
    },
    /// An operation that needs a cargo feature this build was made without.
    #[error("unsupported: {what} needs the `{feature}` feature")]
    FeatureDisabled {
        /// The operation.
        what: &'static str,
        /// The cargo feature.
        feature: &'static str,
    },
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
    /// [`Error::InvalidOption`] for `option`.
    pub fn option(option: impl Into<String>, reason: impl Into<String>) -> Self {
        Error::InvalidOption {
            option: option.into(),
            reason: reason.into(),
        }
    }

    /// [`Error::InconsistentOptions`] for `options`.
    pub fn inconsistent(options: impl Into<String>, reason: impl Into<String>) -> Self {
        Error::InconsistentOptions {
            options: options.into(),
            reason: reason.into(),
        }
    }

    /// [`Error::UnknownName`]: `name` is not one of `expected` (listed as "a, b or c").
    pub fn unknown_name<T: AsRef<str>>(
        what: &'static str,
        name: impl Into<String>,
        expected: impl IntoIterator<Item = T>,
    ) -> Self {
        let names: Vec<String> = expected
            .into_iter()
            .map(|e| e.as_ref().to_string())
            .collect();
        let expected = match names.split_last() {
            Some((last, init)) if !init.is_empty() => format!("{} or {last}", init.join(", ")),
            _ => names.join(""),
        };
        Error::UnknownName {
            what,
            name: name.into(),
            expected,
        }
    }

    /// [`Error::Shape`]: `what` needs `expected` but has `got`.
    pub fn shape(what: impl Into<String>, expected: impl Into<String>, got: usize) -> Self {
        Error::Shape {
            what: what.into(),
            expected: expected.into(),
            got,
        }
    }

    /// [`Error::Checkpoint`] for `path`.
    pub fn checkpoint(path: &std::path::Path, reason: impl Into<String>) -> Self {
        Error::Checkpoint {
            path: path.display().to_string(),
            reason: reason.into(),
        }
    }

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

/// Checks that every component of `state` is finite, returning [`Error::NonFiniteState`] for
/// `what` otherwise.
pub(crate) fn finite_state(what: &'static str, state: &[f64]) -> Result<()> {
    if state.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(Error::NonFiniteState {
            what,
            state: state.to_vec(),
        })
    }
}

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

/// Checks a relative tolerance: finite and in the open interval (0, 1).
pub(crate) fn relative_tolerance(name: &'static str, value: f64) -> Result<f64> {
    positive(name, value)?;
    if value < 1.0 {
        Ok(value)
    } else {
        Err(Error::InvalidParameter {
            name,
            value,
            reason: "must be in (0, 1)",
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_names_list_the_accepted_ones() {
        let e = Error::unknown_name("--lock", "sideways", ["stable", "unstable"]);
        assert_eq!(
            e.to_string(),
            "unknown --lock `sideways` (expected stable or unstable)"
        );
        let e = Error::unknown_name("kind", "cusp", ["fold", "flip", "sb", "ns"]);
        assert!(e.to_string().ends_with("(expected fold, flip, sb or ns)"));
    }

    #[test]
    fn file_errors_keep_their_source() {
        use std::error::Error as _;
        let path = std::path::Path::new("/nonexistent/gearbif/x.toml");
        let io = std::fs::read(path).unwrap_err();
        let e = Error::file("read", path, io);
        let src = e.source().expect("the io error is the source");
        assert!(src.to_string().contains("No such file"), "{src}");
        let toml_err = toml::from_str::<toml::Value>("a = = 1").unwrap_err();
        let e = Error::format("TOML", "x.toml", toml_err);
        assert!(e.source().is_some());
    }
}
