//! The attractor reached from one state: iterate the section map (G or P_T) until the state enters
//! the certified neighbourhood of a known attractor (early stopping), or repeats with a period
//! k ≤ [`BasinOptions::max_period`] on its last three returns (then the cycle is refined by
//! shooting and added to the set), or the step budget is spent (then the statistics of
//! [`crate::analysis::rigorous_classify`] name the set: chaos, QP, rest, or a long period).

use super::attractor::{Attractor, AttractorKind, AttractorSet};
use super::metric::SectionMetric;
use super::BasinOptions;
use crate::analysis::{rigorous_classify, ClassifyOptions, Dynamics};
use crate::error::Result;
use crate::model::DrivenOscillator;
use crate::orbits::{shoot, OrbitSpec};
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

/// What became of one initial state.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum Outcome {
    /// It ends on attractor `index` of the set, after `steps` map applications.
    Attractor {
        /// Index in the set.
        index: usize,
        /// Map applications used.
        steps: usize,
    },
    /// The integration failed (e.g. a state that runs away); counted apart, never guessed.
    Failed,
}

impl Outcome {
    /// The attractor's index, if one was reached.
    pub fn index(&self) -> Option<usize> {
        match self {
            Outcome::Attractor { index, .. } => Some(*index),
            Outcome::Failed => None,
        }
    }
}

/// The attractor of `sys` reached from `x0` (a state at t = 0), found in or added to `set`.
pub fn recognise<S: DrivenOscillator + ?Sized>(
    sys: &S,
    set: &AttractorSet,
    x0: [f64; 2],
    opts: &BasinOptions,
) -> Outcome {
    match iterate(sys, set, x0, opts) {
        Ok(o) => o,
        Err(_) => Outcome::Failed,
    }
}

fn iterate<S: DrivenOscillator + ?Sized>(
    sys: &S,
    set: &AttractorSet,
    x0: [f64; 2],
    opts: &BasinOptions,
) -> Result<Outcome> {
    crate::error::finite_state("initial state", &x0)?;
    let mut z = set.metric.reduce(x0);
    let mut j = 0;
    if let Some(o) = walk(sys, set, &mut z, &mut j, opts)? {
        return Ok(o);
    }
    let (class, end) = classify_tail(sys, z, opts)?;
    if let Dynamics::Periodic {
        half_periods,
        orbit,
        ..
    } = class.dynamics
    {
        // a period beyond the search or a slow approach: add the confirmed cycle, walk on
        let k = if set.metric.half_period {
            half_periods
        } else {
            (half_periods / 2).max(1)
        };
        if add_cycle(sys, set, set.metric.reduce(orbit), k, opts)?.is_some() {
            if let Some(o) = walk(sys, set, &mut z, &mut j, opts)? {
                return Ok(o);
            }
        }
    }
    let index = nonperiodic(sys, set, class, end, opts)?;
    Ok(Outcome::Attractor { index, steps: j })
}

/// Up to [`BasinOptions::max_steps`] map applications from `z` (the `j`-th iterate of the start);
/// the outcome once a known neighbourhood is entered or a new cycle is added and entered.
fn walk<S: DrivenOscillator + ?Sized>(
    sys: &S,
    set: &AttractorSet,
    z: &mut [f64; 2],
    j: &mut usize,
    opts: &BasinOptions,
) -> Result<Option<Outcome>> {
    let metric = set.metric;
    let mut hist: Vec<[f64; 2]> = Vec::with_capacity(opts.max_steps + 1);
    let mut skip_until = 0;
    for n in 0..=opts.max_steps {
        let odd = metric.half_period && *j % 2 == 1;
        if let Some(index) = set.locate(*z, odd) {
            return Ok(Some(Outcome::Attractor { index, steps: *j }));
        }
        hist.push(*z);
        if n >= skip_until {
            if let Some(k) = recurrence(&metric, &hist, opts) {
                match add_cycle(sys, set, *z, k, opts)? {
                    Some(_) => {
                        if let Some(index) = set.locate(*z, odd) {
                            return Ok(Some(Outcome::Attractor { index, steps: *j }));
                        }
                    }
                    None => skip_until = n + 8 * k,
                }
            }
        }
        if n < opts.max_steps {
            *z = metric.step(sys, *z, opts.tol)?;
            *j += 1;
        }
    }
    Ok(None)
}

/// The least k ≤ max_period with d(z_{j−ik}, z_{j−(i+1)k}) < period_tol for i = 0, 1, 2.
fn recurrence(metric: &SectionMetric, hist: &[[f64; 2]], opts: &BasinOptions) -> Option<usize> {
    let n = hist.len();
    (1..=opts.max_period).find(|&k| {
        n > 3 * k
            && (0..3).all(|i| {
                metric.distance(hist[n - 1 - i * k], hist[n - 1 - (i + 1) * k]) < opts.period_tol
            })
    })
}

/// Shoots the cycle through `z` of k map applications on P_Tᵐ and adds it with its twin if it is
/// stable; `None` if shooting fails or the orbit is unstable.
fn add_cycle<S: DrivenOscillator + ?Sized>(
    sys: &S,
    set: &AttractorSet,
    z: [f64; 2],
    k: usize,
    opts: &BasinOptions,
) -> Result<Option<usize>> {
    let metric = set.metric;
    let m = if metric.half_period && k % 2 == 0 {
        k / 2
    } else {
        k
    };
    if let Some(i) = set.find_periodic(z) {
        return Ok(Some(i));
    }
    let winding = if metric.angular {
        let end = metric.stroboscopic(sys, z, m, opts.tol)?;
        ((end[0] - z[0]) / TAU).round() as i32
    } else {
        0
    };
    let Ok(orbit) = shoot(sys, &OrbitSpec::stroboscopic(m, winding), z, &opts.shooting) else {
        return Ok(None);
    };
    if !orbit.floquet.stable || metric.distance(orbit.x, z) > 10.0 * opts.period_tol {
        return Ok(None);
    }
    let tol = opts.shooting.tol;
    let mut points = vec![metric.reduce(orbit.x)];
    for _ in 1..m {
        let y = metric.reduce(metric.stroboscopic(sys, points[points.len() - 1], 1, tol)?);
        if metric.distance(y, points[0]) < super::attractor::SAME_TOL {
            return Ok(None); // not the least period: the shorter cycle is found at its own k
        }
        points.push(y);
    }
    let twin = if metric.half_period {
        let t: Vec<[f64; 2]> = points
            .iter()
            .map(|y| metric.step(sys, *y, tol))
            .collect::<Result<_>>()?;
        (metric.distance_to(t[0], &points) > super::attractor::SAME_TOL).then_some(t)
    } else {
        None
    };
    set.insert_periodic(sys, &orbit, points, twin, opts)
        .map(Some)
}

/// The rigorous classification of the set reached after the step budget.
fn classify_tail<S: DrivenOscillator + ?Sized>(
    sys: &S,
    z: [f64; 2],
    opts: &BasinOptions,
) -> Result<(crate::analysis::RigorousClass, [f64; 2])> {
    let co = ClassifyOptions {
        analysis_turns: opts.analysis_turns,
        tol: opts.tol,
        max_half_periods: 2 * opts.max_period,
        ..ClassifyOptions::default()
    };
    rigorous_classify(sys, z, &co)
}

/// Adds (or finds) the non-periodic set named by `class`, with 100 of its section points from `end`.
fn nonperiodic<S: DrivenOscillator + ?Sized>(
    sys: &S,
    set: &AttractorSet,
    class: crate::analysis::RigorousClass,
    end: [f64; 2],
    opts: &BasinOptions,
) -> Result<usize> {
    let mut points = vec![set.metric.reduce(end)];
    for _ in 1..100 {
        let y = set.metric.step(sys, points[points.len() - 1], opts.tol)?;
        points.push(y);
    }
    set.insert_nonperiodic(Attractor {
        kind: AttractorKind::NonPeriodic {
            dynamics: class.dynamics,
            lyapunov: class.lyapunov.per_period,
        },
        label: class.label,
        rotation_number: class.rotation_number,
        points,
        twin: None,
        radius: 0.0,
        certified: false,
    })
}
