//! Global events located by bisection on the parameter, with a stated transient rule: where an
//! attractor that is not a low-period orbit (the slip-through state of the gear, a chaotic band)
//! ends on a slow sweep.
//!
//! A *slow sweep* is made exact by bisection: the state at the end of the last trial that still
//! showed the old behaviour is carried to the midpoint, relaxed for `transient` drive periods and
//! judged on the state reached (e.g. its mean winding over `window` more periods, or whether it is
//! symmetric); the bracket [new side, old side] shrinks to `tol`. The answer depends on the
//! transient rule through the slow relaxation near the event, so the caller repeats it with several
//! rules and reports the spread (tests `theta0_relock_…`, `theta25_return_to_t2_…`).

use crate::error::{Error, Result};
use crate::integrator::{EventDriven, FlowOptions};
use crate::maps::{poincare_map, Section};
use crate::model::Parametrised;
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

/// The transient rule: relax, then judge.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TransientRule {
    /// Drive periods discarded at each trial value.
    pub transient: usize,
    /// Drive periods over which the judge may measure (e.g. the winding per period).
    pub window: usize,
}

/// Relaxes `x0` for `rule.transient` drive periods (P_T) at tolerance `tol`.
pub fn relax<S: Parametrised>(
    sys: &S,
    x0: [f64; 2],
    rule: &TransientRule,
    tol: f64,
) -> Result<[f64; 2]> {
    if rule.transient == 0 {
        return Ok(x0);
    }
    let o = FlowOptions::with_tol(tol);
    Ok(poincare_map(
        &EventDriven,
        sys,
        Section::Stroboscopic,
        x0,
        rule.transient,
        &o,
    )?
    .x)
}

/// Mean winding per drive period of β over `rule.window` periods from `x`, and the state reached
/// (β reduced modulo 2π).
pub fn mean_winding<S: Parametrised>(
    sys: &S,
    x: [f64; 2],
    rule: &TransientRule,
    tol: f64,
) -> Result<(f64, [f64; 2])> {
    let o = FlowOptions::with_tol(tol);
    let n = rule.window.max(1);
    let y = poincare_map(&EventDriven, sys, Section::Stroboscopic, x, n, &o)?.x;
    Ok((
        (y[0] - x[0]) / (TAU * n as f64),
        [y[0].rem_euclid(TAU), y[1]],
    ))
}

/// The located event: the last value with the old behaviour and the first with the new one.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Located {
    /// Parameter value still showing the old behaviour (e.g. slipping).
    pub old_side: f64,
    /// Parameter value showing the new behaviour (e.g. locked).
    pub new_side: f64,
    /// The rule used.
    pub rule: TransientRule,
    /// Trials (each `transient + window` periods at most).
    pub trials: usize,
}

impl Located {
    /// Midpoint of the bracket; its error is half the bracket plus the spread over transient rules.
    pub fn value(&self) -> f64 {
        0.5 * (self.old_side + self.new_side)
    }
}

/// What a judge says about the relaxed state at one parameter value: whether it shows the new
/// behaviour, and the state to carry on from if it does not.
pub struct Verdict {
    /// The new behaviour is seen.
    pub is_new: bool,
    /// The state reached (carried to the next trial if the old behaviour persists).
    pub state: [f64; 2],
}

/// Bisection for the value where the state carried from `old_side` (state `x_old` on its attractor)
/// stops showing the old behaviour. `judge(sys, relaxed state)` decides; `new_side` must show the
/// new behaviour when started from `x_old`.
#[allow(clippy::too_many_arguments)]
pub fn bisect_sweep<S, J>(
    base: &S,
    param: S::Param,
    mut old_side: f64,
    mut new_side: f64,
    mut x_old: [f64; 2],
    rule: &TransientRule,
    judge: J,
    tol: f64,
    integrator_tol: f64,
) -> Result<Located>
where
    S: Parametrised,
    J: Fn(&S, [f64; 2]) -> Result<Verdict>,
{
    if !(tol > 0.0 && old_side.is_finite() && new_side.is_finite()) {
        return Err(Error::option(
            "bisection bracket",
            format!("needs finite ends and tol > 0, got [{old_side}, {new_side}], tol = {tol}"),
        ));
    }
    let trial = |v: f64, x: [f64; 2]| -> Result<Verdict> {
        let sys = base.with_param(param, v)?;
        let y = relax(&sys, x, rule, integrator_tol)?;
        judge(&sys, y)
    };
    if !trial(new_side, x_old)?.is_new {
        return Err(Error::option(
            "bisection bracket",
            format!("the bracket end {new_side} does not show the new behaviour"),
        ));
    }
    let mut trials = 1;
    while (old_side - new_side).abs() > tol {
        let mid = 0.5 * (old_side + new_side);
        let v = trial(mid, x_old)?;
        trials += 1;
        if v.is_new {
            new_side = mid;
        } else {
            old_side = mid;
            x_old = v.state;
        }
    }
    Ok(Located {
        old_side,
        new_side,
        rule: *rule,
        trials,
    })
}
