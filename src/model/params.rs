//! The parameter lens (as in BifurcationKit): a system declares its parameters — their names, how
//! to read and set one, and which column of the map's parameter Jacobian belongs to each, with the
//! chain rule for derived parameters. Continuation, two-parameter curves, branch switching and sweeps
//! vary parameters only through [`Parametrised`], so they work for any system that implements it.
//!
//! For a parameter λ whose value enters the equations through a Jacobian parameter q_k (the k-th
//! column of `jac_p`, [`crate::model::DrivenOscillator::n_params`]), the derivative of a map is
//!
//! ```text
//!   ∂P/∂λ = (dq_k/dλ) · ∂P/∂q_k,
//! ```
//!
//! and [`Column`] carries k and dq_k/dλ (1 for a primary parameter; for the gear's shaft angle Θ,
//! dΔ/dΘ = −3 sin 2Θ · π/180 per degree, since Δ = 1 − 3 sin²Θ for Θ = Φ).

use super::DrivenOscillator;
use crate::error::{Error, Result};
use nalgebra::Matrix2xX;
use serde::de::DeserializeOwned;
use serde::Serialize;
use std::fmt::Debug;

/// A parameter of a system: usually a field-less enum with one variant per parameter.
pub trait Parameter:
    Copy + Eq + Debug + Send + Sync + Serialize + DeserializeOwned + 'static
{
    /// Every parameter, in a fixed order.
    const ALL: &'static [Self];

    /// The name used on the command line, in JSON and in CSV headers (e.g. `f`, `theta`).
    fn name(self) -> &'static str;

    /// The unit for axis labels and tables (e.g. `Hz`), empty if dimensionless.
    fn unit(self) -> &'static str {
        ""
    }

    /// The symbol for axis labels (e.g. `Θ`); the name unless the system gives one.
    fn symbol(self) -> &'static str {
        self.name()
    }

    /// Parses a name (one of [`Parameter::name`] over [`Parameter::ALL`]).
    fn from_name(s: &str) -> Result<Self> {
        Self::ALL
            .iter()
            .copied()
            .find(|p| p.name() == s)
            .ok_or_else(|| Error::UnknownParameter {
                name: s.to_string(),
                expected: Self::ALL
                    .iter()
                    .map(|p| p.name())
                    .collect::<Vec<_>>()
                    .join(", "),
            })
    }

    /// `symbol [unit]` for axis labels (`Θ [deg]`), `symbol (dimensionless)` without a unit.
    fn label(self) -> String {
        match self.unit() {
            "" => format!("{} (dimensionless)", self.symbol()),
            u => format!("{} [{u}]", self.symbol()),
        }
    }
}

/// Where the derivative with respect to a parameter is read: column `index` of the map's parameter
/// Jacobian, multiplied by `factor` = dq_index/dλ (the chain rule; 1 for a primary parameter).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Column {
    /// Index of the Jacobian parameter column (< [`DrivenOscillator::n_params`]).
    pub index: usize,
    /// dq_index/dλ at the current value of λ.
    pub factor: f64,
}

impl Column {
    /// A primary parameter: column `index` itself.
    pub fn primary(index: usize) -> Self {
        Self { index, factor: 1.0 }
    }
}

/// The parameter lens of a system.
///
/// What an implementor provides: the parameter type, how to read one, how to set one (validated:
/// an inadmissible value is an [`Error::InvalidParameter`], which continuation treats as "step too
/// long"), and the Jacobian column of each parameter. A parameter without a column
/// ([`Parametrised::column`] returns `None`) can be swept but not continued.
pub trait Parametrised: DrivenOscillator + Clone + Sized {
    /// The system's parameters.
    type Param: Parameter;

    /// The current value of `p`.
    fn param(&self, p: Self::Param) -> f64;

    /// A copy with `p` set to `value`, validated.
    fn with_param(&self, p: Self::Param, value: f64) -> Result<Self>;

    /// The Jacobian column of `p` at the current value, with the chain rule for derived parameters.
    fn column(&self, p: Self::Param) -> Option<Column>;
}

/// ∂x/∂λ for parameter `p` of `sys` from a parameter Jacobian `jac_p` (columns as in
/// [`DrivenOscillator::n_params`]): `factor · jac_p[:, index]` ([`Column`]).
pub fn param_derivative<S: Parametrised>(
    sys: &S,
    p: S::Param,
    jac_p: &Matrix2xX<f64>,
) -> Result<[f64; 2]> {
    let c = sys
        .column(p)
        .ok_or(Error::NoParameterColumn { name: p.name() })?;
    if c.index >= jac_p.ncols() {
        return Err(Error::NoParameterColumn { name: p.name() });
    }
    Ok([
        jac_p[(0, c.index)] * c.factor,
        jac_p[(1, c.index)] * c.factor,
    ])
}
