//! Which found effect moves which operating limit by how much: each accepted effect of the
//! dynamics switched off in turn (its parameters at their off value,
//! [`crate::model::recorded::effect::Effect::parameters`]), and all of them together (the nominal
//! gear), each located limit followed there and
//!
//! ```text
//!   Δλ = λ*(p) − λ*(p with the effect off),   σ_Δ² = dᵀ C d,   d = ∇λ*(p) − ∇λ*_off(p)
//! ```
//!
//! with ∇λ*_off the implicit-function gradient of the limit on the gear without the effect, whose
//! entries for the effect's own parameters are 0 (held at their off value there): the σ of the
//! difference from the gradient of the difference ([`difference_sigma`]), so a parameter shared by
//! both (g, ζ, η, …) cancels as far as it moves both alike.
//!
//! The limit is followed from the file's gear to the gear without the effect by a homotopy: the
//! effect's parameters moved in `homotopy_steps` equal steps to their off value, the point
//! re-located from the previous one at each.

use super::{driven, LocatedLimit, RecordedReportOptions};
use crate::analysis::uncertainty::{difference_sigma, located_sigma};
use crate::continuation::two_param::{locate_augmented_with, CurvePoint};
use crate::continuation::SpecialKind;
use crate::error::Result;
use crate::integrator::DEFAULT_METHOD;
use crate::model::recorded::effect::Effect;
use crate::model::recorded::file::ModelFile;
use crate::model::recorded::RecordedParam;
use crate::model::Parameter;
use crate::orbits::{OrbitSpec, ShootingOptions};
use serde::Serialize;

/// One row of the table: a limit with some effects switched off.
#[derive(Debug, Clone, Serialize)]
pub struct Shift {
    /// The effects switched off (one, or every accepted effect of the dynamics: the nominal gear).
    pub off: Vec<&'static str>,
    /// The limit's name (`f_c`, `flip`, …).
    pub limit: String,
    /// The limit with the effects (the file's gear), Hz.
    pub with_hz: f64,
    /// The limit without them, Hz (`None` when it could not be followed there).
    pub without_hz: Option<f64>,
    /// Δλ = with − without, Hz.
    pub delta_hz: Option<f64>,
    /// σ of Δλ, Hz.
    pub sigma_hz: Option<f64>,
    /// Why the limit could not be followed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub failed: Option<String>,
}

/// The table over the limits with a σ and the accepted effects of the dynamics.
pub fn effect_table(
    file: &ModelFile,
    spec: &OrbitSpec,
    limits: &[LocatedLimit],
    o: &RecordedReportOptions,
) -> Result<Vec<Shift>> {
    let effects: Vec<Effect> = file
        .effect_list()
        .into_iter()
        .filter(|e| e.in_dynamics())
        .collect();
    let mut sets: Vec<Vec<Effect>> = effects.iter().map(|&e| vec![e]).collect();
    if effects.len() > 1 {
        sets.push(effects.clone());
    }
    let mut rows = Vec::new();
    for l in limits.iter().filter(|l| l.sigma.is_some()) {
        for set in &sets {
            rows.push(shift(file, spec, l, set, o)?);
        }
    }
    Ok(rows)
}

/// The row of limit `l` with the effects `set` switched off.
fn shift(
    file: &ModelFile,
    spec: &OrbitSpec,
    l: &LocatedLimit,
    set: &[Effect],
    o: &RecordedReportOptions,
) -> Result<Shift> {
    let mut row = Shift {
        off: set.iter().map(|e| e.name()).collect(),
        limit: l.name.clone(),
        with_hz: l.f_hz,
        without_hz: None,
        delta_hz: None,
        sigma_hz: None,
        failed: None,
    };
    let opts = o.shooting();
    let off = file.scaled(set, 0.0);
    let followed =
        follow(file, set, spec, l.kind, &l.point, o.homotopy_steps, &opts).and_then(|p| {
            let m = driven(&off, p.free)?;
            let cov = &file.covariance;
            let s = located_sigma(
                &DEFAULT_METHOD,
                &m,
                cov,
                spec,
                l.kind,
                (RecordedParam::F, None),
                &p,
                &opts,
            )?;
            Ok((p, s))
        });
    match (followed, &l.sigma) {
        (Ok((p, s_off)), Some(s_on)) => {
            let held: Vec<&str> = set
                .iter()
                .flat_map(|e| e.parameters().iter().map(|(q, _)| q.name()))
                .collect();
            row.without_hz = Some(p.free);
            row.delta_hz = Some(l.f_hz - p.free);
            row.sigma_hz = Some(difference_sigma(s_on, &s_off, &held, &file.covariance));
        }
        (Err(e), _) => row.failed = Some(e.to_string()),
        (Ok(_), None) => {}
    }
    Ok(row)
}

/// The point `p` (of kind `kind`, free f) followed from `file`'s gear to the gear with the effects
/// `set` off, in `steps` homotopy steps (module docs).
fn follow(
    file: &ModelFile,
    set: &[Effect],
    spec: &OrbitSpec,
    kind: SpecialKind,
    p: &CurvePoint,
    steps: usize,
    opts: &ShootingOptions,
) -> Result<CurvePoint> {
    let mut p = p.clone();
    let steps = steps.max(1);
    for k in (0..steps).rev() {
        let s = k as f64 / steps as f64;
        let m = driven(&file.scaled(set, s), p.free)?;
        p = locate_augmented_with(
            &DEFAULT_METHOD,
            &m,
            spec,
            kind,
            RecordedParam::F,
            p.x,
            p.free,
            opts,
        )?;
    }
    Ok(p)
}
