//! Options of a pseudo-arclength continuation.

use crate::orbits::ShootingOptions;
use serde::{Deserialize, Serialize};

/// Options of the continuation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ContinuationOptions {
    /// Initial arclength step (signed: its sign sets the initial direction in λ).
    pub ds: f64,
    /// Smallest step before giving up.
    pub ds_min: f64,
    /// Largest step.
    pub ds_max: f64,
    /// Largest number of continuation steps.
    pub max_steps: usize,
    /// Parameter range [min, max]: the continuation stops on its bounds.
    pub param_min: f64,
    /// See `param_min`.
    pub param_max: f64,
    /// Stop when a multiplier modulus exceeds this (single shooting loses accuracy beyond).
    pub max_multiplier: f64,
    /// Shooting options (integrator tolerance, corrector tolerance, iterations); the corrector and
    /// the located special points use `shooting.newton_tol` as given.
    pub shooting: ShootingOptions,
    /// Locate special points to this parameter accuracy (bracket width).
    pub locate_tol: f64,
    /// Detect and locate special points.
    pub detect: bool,
    /// Weight of ω in the arclength norm (ω is in rad/s, β in rad).
    pub omega_weight: f64,
}

impl Default for ContinuationOptions {
    fn default() -> Self {
        Self {
            ds: 0.05,
            ds_min: 1e-7,
            ds_max: 0.5,
            max_steps: 2000,
            param_min: f64::NEG_INFINITY,
            param_max: f64::INFINITY,
            max_multiplier: 1e4,
            shooting: ShootingOptions::default(),
            locate_tol: 1e-8,
            detect: true,
            omega_weight: 0.1,
        }
    }
}

impl ContinuationOptions {
    /// Checks the step sizes and the parameter range.
    pub fn validate(&self) -> crate::Result<()> {
        check_steps(self.ds, self.ds_min, self.ds_max, self.max_steps)?;
        check_range("param_min", (self.param_min, self.param_max))?;
        check_accuracy(&self.shooting, self.locate_tol, self.omega_weight)
    }
}

/// The step checks shared by one- and two-parameter continuation ([`ContinuationOptions`],
/// [`super::palc2::CurveOptions`]): ds finite and non-zero, 0 < ds_min ≤ |ds| ≤ ds_max, at least
/// one step.
pub(crate) fn check_steps(
    ds: f64,
    ds_min: f64,
    ds_max: f64,
    max_steps: usize,
) -> crate::Result<()> {
    use crate::error::Error;
    if !(ds.is_finite() && ds != 0.0) {
        return Err(Error::InvalidParameter {
            name: "ds",
            value: ds,
            reason: "must be finite and non-zero",
        });
    }
    crate::error::positive("ds_min", ds_min)?;
    if !(ds_max >= ds_min && ds.abs() >= ds_min) {
        return Err(Error::InvalidParameter {
            name: "ds_max",
            value: ds_max,
            reason: "need 0 < ds_min <= |ds| <= ds_max",
        });
    }
    if max_steps == 0 {
        return Err(Error::option("max_steps", "must be >= 1, got 0"));
    }
    Ok(())
}

/// A parameter range (lo, hi) that is ordered and not NaN (infinite ends allowed); `name` names
/// its lower end in the error.
pub(crate) fn check_range(name: &'static str, (lo, hi): (f64, f64)) -> crate::Result<()> {
    if lo.is_nan() || hi.is_nan() || lo > hi {
        return Err(crate::Error::InvalidParameter {
            name,
            value: lo,
            reason: "the parameter range must be ordered",
        });
    }
    Ok(())
}

/// The tolerances and weights shared by one- and two-parameter continuation: all > 0.
pub(crate) fn check_accuracy(
    shooting: &ShootingOptions,
    locate_tol: f64,
    omega_weight: f64,
) -> crate::Result<()> {
    crate::error::positive("shooting.newton_tol", shooting.newton_tol)?;
    crate::error::positive("shooting.tol", shooting.tol)?;
    crate::error::positive("locate_tol", locate_tol)?;
    crate::error::positive("omega_weight", omega_weight)?;
    Ok(())
}
