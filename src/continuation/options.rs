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
        use crate::error::Error;
        let bad = |name: &'static str, value: f64, reason: &'static str| {
            Err(Error::InvalidParameter {
                name,
                value,
                reason,
            })
        };
        if !(self.ds.is_finite() && self.ds != 0.0) {
            return bad("ds", self.ds, "must be finite and non-zero");
        }
        crate::error::positive("ds_min", self.ds_min)?;
        if !(self.ds_max >= self.ds_min && self.ds.abs() >= self.ds_min) {
            return bad("ds_max", self.ds_max, "need 0 < ds_min <= |ds| <= ds_max");
        }
        if self.param_min.is_nan() || self.param_max.is_nan() || self.param_min > self.param_max {
            return bad(
                "param_min",
                self.param_min,
                "the parameter range must be ordered",
            );
        }
        crate::error::positive("shooting.newton_tol", self.shooting.newton_tol)?;
        crate::error::positive("shooting.tol", self.shooting.tol)?;
        crate::error::positive("locate_tol", self.locate_tol)?;
        crate::error::positive("omega_weight", self.omega_weight)?;
        Ok(())
    }
}
