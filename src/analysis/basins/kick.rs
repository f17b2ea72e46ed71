//! The minimal fatal kick of an attractor: the smallest instantaneous change of the state, applied
//! at a drive phase φ on the attractor, after which the trajectory ends on another attractor.
//!
//! Along each direction d the kick size s runs over a scan s_i = i · s_max / n_scan; the first s_i
//! whose kicked state x(φT) + s_i d leaves the basin brackets the boundary with s_{i−1}, and
//! bisection narrows the bracket to a relative width `rel_tol`. The kick returned is the bracket's
//! upper end (a kick known to be fatal); its resolution is the scan step, since a fatal sliver
//! thinner than s_max / n_scan below the first fatal scan point can be missed.

use super::attractor::AttractorSet;
use super::grid::run_rows;
use super::recognise::recognise;
use super::BasinOptions;
use crate::error::{Error, Result};
use crate::integrator::{FlowMethod, FlowOptions, DEFAULT_METHOD};
use crate::model::DrivenOscillator;
use serde::{Deserialize, Serialize};

/// The norm of a kick.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum KickNorm {
    /// An angular-velocity kick Δω (rad/s), directions +ω and −ω.
    Velocity,
    /// A kick of the state of size √(Δβ² + (Δω T/2π)²) (rad, the [`super::SectionMetric`]),
    /// directions spread evenly over the circle.
    State,
}

/// Options of the minimal fatal kick.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct KickOptions {
    /// The norm.
    pub norm: KickNorm,
    /// Directions for [`KickNorm::State`] (the velocity norm has two).
    pub directions: usize,
    /// Drive phases φ = j / phases, j = 0 … phases − 1, at which the kick is applied.
    pub phases: usize,
    /// Largest kick tried (rad/s or rad).
    pub max_kick: f64,
    /// Scan points up to `max_kick`.
    pub scan: usize,
    /// Relative width at which the bisection stops.
    pub rel_tol: f64,
}

impl KickOptions {
    /// Checks the options.
    pub fn validate(&self) -> Result<()> {
        crate::error::positive("max_kick", self.max_kick)?;
        crate::error::relative_tolerance("kick rel_tol", self.rel_tol)?;
        for (name, v) in [
            ("kick directions", self.directions),
            ("kick phases", self.phases),
            ("kick scan", self.scan),
        ] {
            if v == 0 {
                return Err(Error::option(name, "must be >= 1, got 0"));
            }
        }
        Ok(())
    }
}

/// The result along one direction at one phase.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DirectionKick {
    /// Drive phase of the kick, in periods.
    pub phase: f64,
    /// Unit direction (Δβ, Δω) in the norm.
    pub direction: [f64; 2],
    /// Smallest fatal kick found, `None` if none up to `max_kick`.
    pub size: Option<f64>,
    /// The largest kick known to keep the attractor: the lower end of the final bracket (or
    /// `max_kick` when no kick was fatal).
    pub safe: f64,
    /// The attractor reached after that kick.
    pub lands_on: Option<usize>,
}

/// The minimal fatal kick of an attractor.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FatalKick {
    /// The attractor kicked.
    pub attractor: usize,
    /// The options used.
    pub options: KickOptions,
    /// The worst case: the smallest fatal kick over directions and phases.
    pub worst: Option<DirectionKick>,
    /// Every direction and phase.
    pub all: Vec<DirectionKick>,
}

impl FatalKick {
    /// Renumbers the attractors with `new_of` (from [`AttractorSet::finish`]).
    pub fn relabel(&mut self, new_of: &[usize]) {
        self.attractor = new_of[self.attractor];
        for d in self.all.iter_mut().chain(self.worst.iter_mut()) {
            d.lands_on = d.lands_on.map(|l| new_of[l]);
        }
    }
}

/// The minimal fatal kick of periodic attractor `target` of `set` (module docs), kicked at the
/// first point of its cycle advanced to each phase.
pub fn minimal_fatal_kick<S: DrivenOscillator + ?Sized>(
    sys: &S,
    set: &AttractorSet,
    target: usize,
    kopts: &KickOptions,
    opts: &BasinOptions,
) -> Result<FatalKick> {
    kopts.validate()?;
    let list = set.snapshot();
    let a = list
        .get(target)
        .ok_or_else(|| Error::shape("attractor index", format!("< {}", list.len()), target))?;
    if !a.is_periodic() {
        return Err(Error::option(
            "kick attractor",
            format!("#{target} ({}) is not periodic", a.label),
        ));
    }
    let dirs = directions(kopts, set.metric.omega_weight);
    let cases: Vec<(f64, [f64; 2])> = (0..kopts.phases)
        .flat_map(|j| {
            let phase = j as f64 / kopts.phases as f64;
            dirs.iter().map(move |d| (phase, *d))
        })
        .collect();
    let ctx = KickContext {
        sys,
        set,
        target,
        y0: a.points[0],
        kopts,
        opts,
    };
    let all = run_rows(cases.len(), |i| {
        let (phase, d) = cases[i];
        ctx.along(phase, d)
    })
    .into_iter()
    .collect::<Result<Vec<_>>>()?;
    let worst = all
        .iter()
        .filter(|d| d.size.is_some())
        .min_by(|a, b| {
            a.size
                .partial_cmp(&b.size)
                .unwrap_or(std::cmp::Ordering::Equal)
        })
        .copied();
    Ok(FatalKick {
        attractor: target,
        options: *kopts,
        worst,
        all,
    })
}

/// Unit directions in the norm, as (Δβ, Δω) per unit kick.
fn directions(k: &KickOptions, omega_weight: f64) -> Vec<[f64; 2]> {
    match k.norm {
        KickNorm::Velocity => vec![[0.0, 1.0], [0.0, -1.0]],
        KickNorm::State => (0..k.directions)
            .map(|i| {
                let th = std::f64::consts::TAU * i as f64 / k.directions as f64;
                [th.cos(), th.sin() / omega_weight]
            })
            .collect(),
    }
}

/// What every kick of one search shares: the system, the attractors, the kicked attractor
/// `target` and the cycle point `y0` it is kicked from, and the options.
struct KickContext<'a, S: ?Sized> {
    sys: &'a S,
    set: &'a AttractorSet,
    target: usize,
    y0: [f64; 2],
    kopts: &'a KickOptions,
    opts: &'a BasinOptions,
}

impl<S: DrivenOscillator + ?Sized> KickContext<'_, S> {
    /// Scan and bisection along direction `d` at phase `phase`.
    fn along(&self, phase: f64, d: [f64; 2]) -> Result<DirectionKick> {
        let (sys, set, target, y0, k, opts) = (
            self.sys,
            self.set,
            self.target,
            self.y0,
            self.kopts,
            self.opts,
        );
        let lands = |s: f64| -> Result<Option<usize>> {
            let x = kicked(sys, set, y0, phase, [s * d[0], s * d[1]], opts)?;
            Ok(recognise(sys, set, x, opts).index())
        };
        let mut out = DirectionKick {
            phase,
            direction: d,
            size: None,
            safe: k.max_kick,
            lands_on: None,
        };
        let step = k.max_kick / k.scan as f64;
        let Some((i, mut to)) = (1..=k.scan)
            .map(|i| lands(i as f64 * step).map(|l| (i, l)))
            .find(|r| !matches!(r, Ok((_, Some(l))) if *l == target))
            .transpose()?
        else {
            return Ok(out);
        };
        let (mut lo, mut hi) = ((i - 1) as f64 * step, i as f64 * step);
        while hi - lo > k.rel_tol * hi {
            let mid = 0.5 * (lo + hi);
            match lands(mid)? {
                Some(l) if l == target => lo = mid,
                l => {
                    hi = mid;
                    to = l;
                }
            }
        }
        out.size = Some(hi);
        out.safe = lo;
        out.lands_on = to;
        Ok(out)
    }
}
/// The state on the section t ≡ 0 after a kick `dx` at phase φ on the orbit through `y0`: the
/// orbit integrated to φT, kicked, integrated to T (φ = 0: y0 + dx itself).
fn kicked<S: DrivenOscillator + ?Sized>(
    sys: &S,
    set: &AttractorSet,
    y0: [f64; 2],
    phase: f64,
    dx: [f64; 2],
    opts: &BasinOptions,
) -> Result<[f64; 2]> {
    if phase == 0.0 {
        return Ok([y0[0] + dx[0], y0[1] + dx[1]]);
    }
    let t = sys.period();
    let o = FlowOptions::with_tol(opts.tol);
    let x = DEFAULT_METHOD.flow(sys, 0.0, y0, phase * t, &o)?.x;
    let x = [x[0] + dx[0], x[1] + dx[1]];
    Ok(set
        .metric
        .reduce(DEFAULT_METHOD.flow(sys, phase * t, x, t, &o)?.x))
}
