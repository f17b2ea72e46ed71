//! Conversions between Python objects and the library's types.

use crate::errors::{invalid, Kind};
use numpy::{Complex64, PyArray1, PyArray2, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyAny;

/// A state (β [rad], ω [rad/s]) from any sequence of two finite floats (list, tuple, numpy array).
pub fn state(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<[f64; 2]> {
    let v: Vec<f64> = obj.extract().map_err(|_| {
        invalid(format!(
            "{what} must be a sequence of two floats (beta, omega)"
        ))
    })?;
    if v.len() != 2 {
        return Err(invalid(format!(
            "{what} must have two entries (beta [rad], omega [rad/s]), got {}",
            v.len()
        )));
    }
    if !v.iter().all(|x| x.is_finite()) {
        return Err(invalid(format!(
            "{what} must be finite, got ({}, {})",
            v[0], v[1]
        )));
    }
    Ok([v[0], v[1]])
}

/// Any serialisable value as Python objects (dicts, lists, floats), through JSON.
pub fn to_python<'py, T: serde::Serialize>(py: Python<'py>, v: &T) -> PyResult<Bound<'py, PyAny>> {
    let s = serde_json::to_string(v).map_err(|e| Kind::Io.err(e.to_string()))?;
    py.import("json")?.call_method1("loads", (s,))
}

/// A 2-vector as a numpy array.
pub fn vec2<'py>(py: Python<'py>, x: [f64; 2]) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_slice(py, &x)
}

/// Multipliers stored as [[re, im], [re, im]] as a complex numpy array.
pub fn complex2<'py>(py: Python<'py>, m: [[f64; 2]; 2]) -> Bound<'py, PyArray1<Complex64>> {
    PyArray1::from_vec(py, m.iter().map(|z| Complex64::new(z[0], z[1])).collect())
}

/// A 2×2 nalgebra matrix as a (2, 2) numpy array.
pub fn mat2<'py>(py: Python<'py>, m: &nalgebra::Matrix2<f64>) -> Bound<'py, PyArray2<f64>> {
    rows(py, 2, m.ncols(), |i, j| m[(i, j)])
}

/// An (n, m) numpy array filled by `f(i, j)`.
pub fn rows<'py>(
    py: Python<'py>,
    n: usize,
    m: usize,
    f: impl Fn(usize, usize) -> f64,
) -> Bound<'py, PyArray2<f64>> {
    let flat: Vec<f64> = (0..n * m).map(|k| f(k / m.max(1), k % m.max(1))).collect();
    PyArray1::from_vec(py, flat)
        .reshape([n, m])
        .expect("n·m elements reshape to (n, m)")
}

/// A (lo, hi) pair of finite floats with lo < hi, from any sequence of two numbers.
pub fn range(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<(f64, f64)> {
    let v = floats(obj, what)?;
    match v[..] {
        [lo, hi] if lo < hi => Ok((lo, hi)),
        _ => Err(invalid(format!(
            "{what} must be (lo, hi) with lo < hi, got {v:?}"
        ))),
    }
}

/// A list of finite floats from any sequence of numbers (list, tuple, 1-d numpy array).
pub fn floats(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<f64>> {
    let v: Vec<f64> = obj
        .extract()
        .map_err(|_| invalid(format!("{what} must be a sequence of floats")))?;
    if let Some(x) = v.iter().find(|x| !x.is_finite()) {
        return Err(invalid(format!("{what} must be finite, got {x}")));
    }
    Ok(v)
}

/// A count (number of iterations, turns, steps) from a Python int: negative values are an
/// InvalidInputError, not an OverflowError.
pub fn count(n: i64, what: &str, min: usize) -> PyResult<usize> {
    usize::try_from(n)
        .ok()
        .filter(|&k| k >= min)
        .ok_or_else(|| invalid(format!("{what} must be an integer >= {min}, got {n}")))
}
