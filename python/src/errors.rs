//! The exception hierarchy: one Python class per concern of `gearbif::Error`, all subclasses of
//! `GearbifError` and each also of the builtin exception a Python user catches for that concern
//! (`except ValueError` catches a bad parameter, as in numpy and scipy). The input errors (an
//! option, a name, a combination of options, a state, times, a shape, a checkpoint folder) share
//! `InvalidInputError`; it, `ContinuationError` and `UnsupportedError` carry the attribute `kind`,
//! the variant's name.
//!
//! The classes are made once, when the module is imported, by `type(name, (GearbifError,
//! builtin), namespace)`: a class with two bases is what `create_exception!` cannot make.

use gearbif::Error;
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyDict, PyTuple, PyType};

/// The exception classes of the module.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// `GearbifError`, the base of every other.
    Base,
    /// `InvalidParameterError`.
    InvalidParameter,
    /// `InvalidInputError`.
    InvalidInput,
    /// `IntegrationError`.
    Integration,
    /// `NewtonError`.
    Newton,
    /// `ContinuationError`.
    Continuation,
    /// `GearbifIOError`.
    Io,
    /// `UnsupportedError`.
    Unsupported,
    /// `NoPeriodError`.
    NoPeriod,
    /// `RecordingError`.
    Recording,
}

impl Kind {
    /// Every class, the base first (the order of [`TYPES`]).
    const ALL: [Kind; 10] = [
        Kind::Base,
        Kind::InvalidParameter,
        Kind::InvalidInput,
        Kind::Integration,
        Kind::Newton,
        Kind::Continuation,
        Kind::Io,
        Kind::Unsupported,
        Kind::NoPeriod,
        Kind::Recording,
    ];

    /// The class's name in the module.
    pub fn name(self) -> &'static str {
        match self {
            Kind::Base => "GearbifError",
            Kind::InvalidParameter => "InvalidParameterError",
            Kind::InvalidInput => "InvalidInputError",
            Kind::Integration => "IntegrationError",
            Kind::Newton => "NewtonError",
            Kind::Continuation => "ContinuationError",
            Kind::Io => "GearbifIOError",
            Kind::Unsupported => "UnsupportedError",
            Kind::NoPeriod => "NoPeriodError",
            Kind::Recording => "RecordingError",
        }
    }

    /// The builtin exception the class also derives from.
    fn builtin(self) -> &'static str {
        match self {
            Kind::Base => "Exception",
            Kind::InvalidParameter | Kind::InvalidInput | Kind::Recording => "ValueError",
            Kind::Integration | Kind::Newton | Kind::Continuation | Kind::NoPeriod => {
                "RuntimeError"
            }
            Kind::Io => "OSError",
            Kind::Unsupported => "NotImplementedError",
        }
    }

    /// The class's docstring.
    fn doc(self) -> &'static str {
        match self {
            Kind::Base => "Base class of every error raised by gearbif.",
            Kind::InvalidParameter => {
                "A parameter is non-finite or outside its admissible range (also a ValueError; \
                 attributes: name, value)."
            }
            Kind::InvalidInput => {
                "An input (option, name, combination of options, state, times, shape, checkpoint \
                 folder) is malformed or inconsistent (also a ValueError; attribute kind: the \
                 variant of gearbif::Error, e.g. \"InvalidOption\", \"NonFiniteState\")."
            }
            Kind::Integration => {
                "The integrator could not finish (step size underflow, too many steps, non-finite \
                 state; also a RuntimeError)."
            }
            Kind::Newton => {
                "A Newton iteration (shooting, location of a special point) did not converge (also \
                 a RuntimeError)."
            }
            Kind::Continuation => {
                "A continuation, a branch switch or a location could not proceed (also a \
                 RuntimeError; attribute kind: the variant of gearbif::Error, e.g. \
                 \"SingularMatrix\", \"NoNewBranch\")."
            }
            Kind::Io => "Reading, parsing or writing a file failed (also an OSError).",
            Kind::Unsupported => {
                "The operation is not available for this system (e.g. no half-period symmetry; \
                 also a NotImplementedError; attribute kind: the variant of gearbif::Error, e.g. \
                 \"OutsideClosedForm\")."
            }
            Kind::NoPeriod => {
                "A simulation did not settle on a periodic orbit of the largest period tried \
                 (also a RuntimeError)."
            }
            Kind::Recording => {
                "A recording set (experiment.toml or a CSV file) is malformed (also a ValueError; \
                 attributes: file, line)."
            }
        }
    }

    /// The class, made on first use.
    pub fn class(self, py: Python<'_>) -> Bound<'_, PyType> {
        let all = TYPES
            .get_or_try_init(py, || make_classes(py))
            .expect("the exception classes derive from builtins that always exist");
        let i = Kind::ALL.iter().position(|k| *k == self).unwrap_or(0);
        all[i].bind(py).clone()
    }

    /// A new exception of this class with a message.
    pub fn err(self, msg: impl Into<String>) -> PyErr {
        let msg = msg.into();
        Python::attach(|py| PyErr::from_type(self.class(py), msg))
    }
}

/// The classes of [`Kind::ALL`], in its order.
static TYPES: PyOnceLock<Vec<Py<PyType>>> = PyOnceLock::new();

/// `type(name, (GearbifError, builtin), {"__module__": "gearbif", "__doc__": doc})` for every
/// class (the base with the builtin alone).
fn make_classes(py: Python<'_>) -> PyResult<Vec<Py<PyType>>> {
    let builtins = py.import("builtins")?;
    let type_ = builtins.getattr("type")?;
    let mut made: Vec<Py<PyType>> = Vec::with_capacity(Kind::ALL.len());
    for kind in Kind::ALL {
        let builtin = builtins.getattr(kind.builtin())?;
        let bases = match made.first() {
            Some(base) => PyTuple::new(py, [base.bind(py).clone().into_any(), builtin])?,
            None => PyTuple::new(py, [builtin])?,
        };
        let namespace = PyDict::new(py);
        namespace.set_item("__module__", "gearbif")?;
        namespace.set_item("__doc__", kind.doc())?;
        let class = type_.call1((kind.name(), bases, namespace))?;
        made.push(class.cast_into::<PyType>()?.unbind());
    }
    Ok(made)
}

/// Converts a library error into the matching Python exception.
pub fn to_py(e: Error) -> PyErr {
    let msg = e.to_string();
    match e {
        Error::InvalidParameter { name, value, .. } => {
            let err = Kind::InvalidParameter.err(msg);
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
        Error::Stopped { .. } => Kind::Base.err(msg),
        Error::NoParameterColumn { .. } => Kind::Unsupported.err(msg),
        Error::NoPeriodDetected { .. } => Kind::NoPeriod.err(msg),
        Error::Integration { .. } | Error::StepBudget { .. } => Kind::Integration.err(msg),
        Error::NewtonFailed { .. } => Kind::Newton.err(msg),
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
            with_kind(Kind::Continuation.err(msg), variant_name(&e))
        }
        Error::Io(_) | Error::File { .. } | Error::Format { .. } => Kind::Io.err(msg),
        Error::NoHalfPeriodSymmetry
        | Error::MissingJacobian { .. }
        | Error::NoLockLossFrequency { .. }
        | Error::OutsideClosedForm { .. }
        | Error::NotBracketed { .. }
        | Error::UnsupportedPoint { .. }
        | Error::FeatureDisabled { .. } => with_kind(Kind::Unsupported.err(msg), variant_name(&e)),
        Error::Recording { file, line, .. } => {
            let err = Kind::Recording.err(msg);
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
    let err = Kind::InvalidInput.err(msg);
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
    for kind in Kind::ALL {
        m.add(kind.name(), kind.class(py))?;
    }
    Ok(())
}
