//! The exception hierarchy: one Python class per concern of `gearbif::Error`, all subclasses of
//! `GearbifError`. The input errors (an option, a name, a combination of options, a state, times,
//! a shape, a checkpoint folder) share `InvalidInputError`; it, `ContinuationError` and
//! `UnsupportedError` carry the attribute `kind`, the variant's name.

use gearbif::Error;
use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;

create_exception!(
    gearbif,
    GearbifError,
    PyException,
    "Base class of every error raised by gearbif."
);
create_exception!(
    gearbif,
    InvalidParameterError,
    GearbifError,
    "A parameter is non-finite or outside its admissible range (attributes: name, value)."
);
create_exception!(
    gearbif,
    InvalidInputError,
    GearbifError,
    "An input (option, name, combination of options, state, times, shape, checkpoint folder) is \
     malformed or inconsistent (attribute kind: the variant of gearbif::Error, e.g. \
     \"InvalidOption\", \"NonFiniteState\")."
);
create_exception!(
    gearbif,
    IntegrationError,
    GearbifError,
    "The integrator could not finish (step size underflow, too many steps, non-finite state)."
);
create_exception!(
    gearbif,
    NewtonError,
    GearbifError,
    "A Newton iteration (shooting, location of a special point) did not converge."
);
create_exception!(
    gearbif,
    ContinuationError,
    GearbifError,
    "A continuation, a branch switch or a location could not proceed (attribute kind: the \
     variant of gearbif::Error, e.g. \"SingularMatrix\", \"NoNewBranch\")."
);
create_exception!(
    gearbif,
    GearbifIOError,
    GearbifError,
    "Reading, parsing or writing a file failed."
);
create_exception!(
    gearbif,
    UnsupportedError,
    GearbifError,
    "The operation is not available for this system (e.g. no half-period symmetry; attribute \
     kind: the variant of gearbif::Error, e.g. \"OutsideClosedForm\")."
);
create_exception!(
    gearbif,
    NoPeriodError,
    GearbifError,
    "A simulation did not settle on a periodic orbit of the largest period tried."
);
create_exception!(
    gearbif,
    RecordingError,
    GearbifError,
    "A recording set (experiment.toml or a CSV file) is malformed (attributes: file, line)."
);

/// Converts a library error into the matching Python exception.
pub fn to_py(e: Error) -> PyErr {
    let msg = e.to_string();
    match e {
        Error::InvalidParameter { name, value, .. } => {
            let err = InvalidParameterError::new_err(msg);
            Python::attach(|py| {
                let v = err.value(py);
                v.setattr("name", name).ok();
                v.setattr("value", value).ok();
            });
            err
        }
        Error::UnknownParameter { .. } => input_error(msg, "UnknownParameter"),
        Error::InvalidOption { .. } => input_error(msg, "InvalidOption"),
        Error::UnknownName { .. } => input_error(msg, "UnknownName"),
        Error::InconsistentOptions { .. } => input_error(msg, "InconsistentOptions"),
        Error::NonFiniteState { .. } => input_error(msg, "NonFiniteState"),
        Error::InvalidTimes { .. } => input_error(msg, "InvalidTimes"),
        Error::Shape { .. } => input_error(msg, "Shape"),
        Error::Checkpoint { .. } => input_error(msg, "Checkpoint"),
        Error::Stopped { .. } => GearbifError::new_err(msg),
        Error::NoParameterColumn { .. } => UnsupportedError::new_err(msg),
        Error::NoPeriodDetected { .. } => NoPeriodError::new_err(msg),
        Error::Integration { .. } | Error::StepBudget { .. } => IntegrationError::new_err(msg),
        Error::NewtonFailed { .. } => NewtonError::new_err(msg),
        Error::SingularMatrix { .. }
        | Error::DegenerateDirection { .. }
        | Error::NoArrival
        | Error::MissingEigenvector { .. }
        | Error::NoNewBranch { .. }
        | Error::MultiplierTooLarge { .. }
        | Error::NonFiniteTestFunction { .. }
        | Error::TestFunctionJump { .. }
        | Error::NotFound { .. }
        | Error::NoStartOrbit { .. }
        | Error::ManifoldUndecided { .. } => {
            with_kind(ContinuationError::new_err(msg), variant_name(&e))
        }
        Error::Io(_) | Error::File { .. } | Error::Format { .. } => GearbifIOError::new_err(msg),
        Error::NoHalfPeriodSymmetry
        | Error::MissingJacobian { .. }
        | Error::NoLockLossFrequency { .. }
        | Error::OutsideClosedForm { .. }
        | Error::NotBracketed { .. }
        | Error::UnsupportedPoint { .. }
        | Error::FeatureDisabled { .. } => {
            with_kind(UnsupportedError::new_err(msg), variant_name(&e))
        }
        Error::Recording { file, line, .. } => {
            let err = RecordingError::new_err(msg);
            Python::attach(|py| {
                let v = err.value(py);
                v.setattr("file", file).ok();
                v.setattr("line", line).ok();
            });
            err
        }
    }
}

/// The name of `e`'s variant (`"SingularMatrix"`), for the attribute `kind`.
fn variant_name(e: &Error) -> String {
    let debug = format!("{e:?}");
    debug
        .split(|c: char| !c.is_alphanumeric())
        .next()
        .unwrap_or_default()
        .to_string()
}

/// `err` with its attribute `kind`, the variant of `gearbif::Error`.
fn with_kind(err: PyErr, kind: String) -> PyErr {
    Python::attach(|py| {
        err.value(py).setattr("kind", kind).ok();
    });
    err
}

/// An `InvalidInputError` with its attribute `kind`, the variant of `gearbif::Error`.
fn input_error(msg: String, kind: &str) -> PyErr {
    let err = InvalidInputError::new_err(msg);
    Python::attach(|py| {
        err.value(py).setattr("kind", kind).ok();
    });
    err
}

/// `Result<T, gearbif::Error>` → `PyResult<T>`.
pub trait IntoPyResult<T> {
    /// Maps the error to its Python exception.
    fn py(self) -> PyResult<T>;
}

impl<T> IntoPyResult<T> for gearbif::Result<T> {
    fn py(self) -> PyResult<T> {
        self.map_err(to_py)
    }
}

/// An `InvalidInputError` with a message, for a keyword argument the bindings refuse before the
/// library sees it (`kind` = "InvalidOption", as the library's own option errors).
pub fn invalid(msg: impl Into<String>) -> PyErr {
    input_error(msg.into(), "InvalidOption")
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("GearbifError", py.get_type::<GearbifError>())?;
    m.add(
        "InvalidParameterError",
        py.get_type::<InvalidParameterError>(),
    )?;
    m.add("InvalidInputError", py.get_type::<InvalidInputError>())?;
    m.add("IntegrationError", py.get_type::<IntegrationError>())?;
    m.add("NewtonError", py.get_type::<NewtonError>())?;
    m.add("ContinuationError", py.get_type::<ContinuationError>())?;
    m.add("GearbifIOError", py.get_type::<GearbifIOError>())?;
    m.add("UnsupportedError", py.get_type::<UnsupportedError>())?;
    m.add("NoPeriodError", py.get_type::<NoPeriodError>())?;
    m.add("RecordingError", py.get_type::<RecordingError>())?;
    Ok(())
}
