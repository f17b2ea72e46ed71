//! An attractor of the stroboscopic map P_T and the thread-safe set of the attractors found so far.
//!
//! A periodic attractor is a cycle y₀ … y_{m−1} of P_T on the section (β reduced modulo 2π for an
//! angle), refined by shooting on F(x) = P_Tᵐ(x) − x − (2πp, 0) = 0 ([`crate::orbits::shoot`]) so
//! that it carries the multipliers of P_Tᵐ. With the half-period symmetry its twin is the cycle
//! G(y₀) … G(y_{m−1}); when that is the cycle itself the orbit is symmetric, otherwise the twin is a
//! second attractor whose basin is the image of the first under G (module docs of
//! [`super`]). Two cycles are the same attractor when a point of one lies within
//! [`SAME_TOL`] of the other's points: the identity modulo R and the 2π lift that the
//! bifurcation diagram uses ([`crate::continuation::identity`]).

use super::metric::SectionMetric;
use super::BasinOptions;
use crate::analysis::classify::period_label;
use crate::analysis::Dynamics;
use crate::error::Result;
use crate::model::DrivenOscillator;
use crate::orbits::PeriodicOrbit;
use serde::{Deserialize, Serialize};
use std::sync::RwLock;

/// Two converged periodic orbits closer than this ([`SectionMetric`]) are the same.
pub const SAME_TOL: f64 = 1e-6;
/// Smallest neighbourhood radius tried by [`certify`].
pub const MIN_RADIUS: f64 = 1e-4;

/// What an attractor is.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum AttractorKind {
    /// A stable periodic orbit of P_T.
    Periodic {
        /// Least m with P_Tᵐ(y₀) ≡ y₀.
        period: usize,
        /// Its period in half drive periods modulo the symmetry (1 = T/2, 2 = T), as the
        /// classification counts it.
        half_periods: usize,
        /// Invariant under the half-period symmetry.
        symmetric: bool,
        /// Turns of β over the m periods (0 for a displacement).
        winding: i32,
        /// Multipliers of P_Tᵐ as (re, im), largest modulus first.
        multipliers: [[f64; 2]; 2],
        /// Residual of the shooting.
        residual: f64,
    },
    /// A set without a period up to the search limit, told apart by its statistics.
    NonPeriodic {
        /// Chaotic, quasi-periodic, unresolved or at rest.
        dynamics: Dynamics,
        /// Largest Lyapunov exponent per drive period, if finite.
        lyapunov: Option<f64>,
    },
}

/// An attractor of P_T.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Attractor {
    /// What it is.
    pub kind: AttractorKind,
    /// Short name: "T/2 sym", "T asym", "2T asym", "chaos", "QP", "rest", "?".
    pub label: String,
    /// Mean turns of β per drive period.
    pub rotation_number: f64,
    /// Its points on the section: the cycle y₀ … y_{m−1} in order of P_T, or up to 200 section
    /// points of a non-periodic set.
    pub points: Vec<[f64; 2]>,
    /// The index of its twin G(A) when that is another attractor.
    pub twin: Option<usize>,
    /// Radius of the certified neighbourhood ([`certify`]); 0 for a non-periodic set (no early
    /// stopping).
    pub radius: f64,
    /// Whether every ring point of [`certify`] returned at that radius.
    pub certified: bool,
}

impl Attractor {
    /// Is this a periodic attractor?
    pub fn is_periodic(&self) -> bool {
        matches!(self.kind, AttractorKind::Periodic { .. })
    }

    /// Legend text: label, rotation number and, for a twin pair, which member.
    pub fn legend(&self, index: usize) -> String {
        let member = match self.twin {
            Some(t) if t > index => " (a)",
            Some(_) => " (b)",
            None => "",
        };
        format!(
            "#{index} {}{member}, ρ = {:.3}",
            self.label, self.rotation_number
        )
    }

    /// The spectral radius of the periodic orbit's P_Tᵐ (NaN for a non-periodic set).
    pub fn spectral_radius(&self) -> f64 {
        match &self.kind {
            AttractorKind::Periodic { multipliers, .. } => multipliers
                .iter()
                .map(|z| z[0].hypot(z[1]))
                .fold(0.0, f64::max),
            AttractorKind::NonPeriodic { .. } => f64::NAN,
        }
    }
}

/// The attractors found so far, shared by the worker threads (found while iterating, appended
/// under a write lock after a second identity check, never removed; [`AttractorSet::finish`]
/// orders them reproducibly).
#[derive(Debug)]
pub struct AttractorSet {
    /// The section.
    pub metric: SectionMetric,
    list: RwLock<Vec<Attractor>>,
}

impl AttractorSet {
    /// An empty set for `sys`.
    pub fn new<S: DrivenOscillator + ?Sized>(sys: &S) -> Self {
        Self {
            metric: SectionMetric::of(sys),
            list: RwLock::new(Vec::new()),
        }
    }

    /// A copy of the attractors found so far.
    pub fn snapshot(&self) -> Vec<Attractor> {
        self.list.read().map(|l| l.clone()).unwrap_or_default()
    }

    /// Number of attractors found so far.
    pub fn len(&self) -> usize {
        self.list.read().map(|l| l.len()).unwrap_or(0)
    }

    /// True if none was found yet.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The attractor of P_T whose certified neighbourhood holds `z`, for a state `z` reached after
    /// `odd` (true) or an even number of applications of G: after an odd number the trajectory's
    /// P_T-limit is G of the attractor found ([`super`]).
    pub fn locate(&self, z: [f64; 2], odd: bool) -> Option<usize> {
        let list = self.list.read().ok()?;
        let i = list
            .iter()
            .position(|a| a.radius > 0.0 && self.metric.distance_to(z, &a.points) < a.radius)?;
        Some(if odd { list[i].twin.unwrap_or(i) } else { i })
    }

    /// The periodic attractor having a point within [`SAME_TOL`] of `y`.
    pub fn find_periodic(&self, y: [f64; 2]) -> Option<usize> {
        let list = self.list.read().ok()?;
        find_in(&list, &self.metric, y)
    }

    /// Adds the stable periodic orbit `orbit` (with its cycle `points` and its twin's cycle, if any),
    /// certifying its neighbourhood first; returns its index (an existing one if it is known).
    pub fn insert_periodic<S: DrivenOscillator + ?Sized>(
        &self,
        sys: &S,
        orbit: &PeriodicOrbit,
        points: Vec<[f64; 2]>,
        twin: Option<Vec<[f64; 2]>>,
        opts: &BasinOptions,
    ) -> Result<usize> {
        if let Some(i) = self.find_periodic(points[0]) {
            return Ok(i);
        }
        let a = self.certified(
            sys,
            periodic(&self.metric, orbit, points, twin.is_none()),
            opts,
        )?;
        // the twin's neighbourhood is certified on its own: G need not preserve distances
        let twin = match twin {
            Some(t) => Some(self.certified(
                sys,
                Attractor {
                    points: t,
                    ..a.clone()
                },
                opts,
            )?),
            None => None,
        };
        let mut list = self.list.write().map_err(|_| poisoned())?;
        if let Some(i) = find_in(&list, &self.metric, a.points[0]) {
            return Ok(i);
        }
        let i = list.len();
        let has_twin = twin.is_some();
        list.push(Attractor {
            twin: has_twin.then_some(i + 1),
            ..a
        });
        list.extend(twin.map(|t| Attractor { twin: Some(i), ..t }));
        Ok(i)
    }

    /// `a` with the radius of its certified neighbourhood ([`certify`]).
    fn certified<S: DrivenOscillator + ?Sized>(
        &self,
        sys: &S,
        a: Attractor,
        opts: &BasinOptions,
    ) -> Result<Attractor> {
        let (radius, certified) = certify(sys, &self.metric, &a, opts)?;
        Ok(Attractor {
            radius,
            certified,
            ..a
        })
    }

    /// Adds a non-periodic set, or returns the known one with the same dynamics and a rotation
    /// number within 0.05.
    pub fn insert_nonperiodic(&self, a: Attractor) -> Result<usize> {
        let mut list = self.list.write().map_err(|_| poisoned())?;
        let same = list.iter().position(|b| {
            !b.is_periodic()
                && b.label == a.label
                && (b.rotation_number - a.rotation_number).abs() < 0.05
        });
        Ok(same.unwrap_or_else(|| {
            list.push(a);
            list.len() - 1
        }))
    }

    /// For each index used while searching, its index in the reproducible order of
    /// [`AttractorSet::finish`] (periodic by period, rotation number and position, then the
    /// non-periodic ones).
    pub fn order(&self) -> Vec<usize> {
        let Ok(list) = self.list.read() else {
            return Vec::new();
        };
        let key = |a: &Attractor| {
            let (np, hp) = match &a.kind {
                AttractorKind::Periodic { half_periods, .. } => (0, *half_periods),
                AttractorKind::NonPeriodic { .. } => (1, usize::MAX),
            };
            let first = a.points.first().copied().unwrap_or([0.0, 0.0]);
            (np, hp, a.rotation_number, first[0], first[1])
        };
        let mut order: Vec<usize> = (0..list.len()).collect();
        order.sort_by(|&i, &j| {
            key(&list[i])
                .partial_cmp(&key(&list[j]))
                .unwrap_or(std::cmp::Ordering::Equal)
        });
        let mut new_of = vec![0; list.len()];
        for (new, &old) in order.iter().enumerate() {
            new_of[old] = new;
        }
        new_of
    }

    /// The attractors in the order of [`AttractorSet::order`], and that order.
    pub fn finish(self) -> (Vec<Attractor>, Vec<usize>) {
        let new_of = self.order();
        let list = self.list.into_inner().unwrap_or_else(|e| e.into_inner());
        let mut sorted: Vec<Option<Attractor>> = vec![None; list.len()];
        for (old, a) in list.into_iter().enumerate() {
            sorted[new_of[old]] = Some(Attractor {
                twin: a.twin.map(|t| new_of[t]),
                ..a
            });
        }
        (sorted.into_iter().flatten().collect(), new_of)
    }
}

fn poisoned() -> crate::Error {
    crate::Error::Integration {
        t: 0.0,
        reason: "a worker thread panicked while adding an attractor".into(),
    }
}

fn find_in(list: &[Attractor], metric: &SectionMetric, y: [f64; 2]) -> Option<usize> {
    list.iter()
        .position(|a| a.is_periodic() && metric.distance_to(y, &a.points) < SAME_TOL)
}

/// The attractor of a shot orbit with cycle `points` (rotated to start at its least β).
fn periodic(
    metric: &SectionMetric,
    orbit: &PeriodicOrbit,
    mut points: Vec<[f64; 2]>,
    symmetric: bool,
) -> Attractor {
    let m = points.len();
    let first = (0..m)
        .min_by(|&i, &j| points[i][0].total_cmp(&points[j][0]))
        .unwrap_or(0);
    points.rotate_left(first);
    let half_periods = if symmetric && metric.half_period {
        m
    } else {
        2 * m
    };
    let sym = if symmetric && metric.half_period {
        "sym"
    } else if metric.half_period {
        "asym"
    } else {
        "periodic"
    };
    let winding = orbit.spec.winding;
    Attractor {
        kind: AttractorKind::Periodic {
            period: m,
            half_periods,
            symmetric: symmetric && metric.half_period,
            winding,
            multipliers: orbit.floquet.multipliers,
            residual: orbit.residual,
        },
        label: format!("{} {sym}", period_label(half_periods)),
        rotation_number: winding as f64 / m as f64,
        points,
        twin: None,
        radius: 0.0,
        certified: false,
    }
}

/// The neighbourhood radius r of a periodic attractor: starting at
/// [`BasinOptions::neighbourhood`] and halved down to [`MIN_RADIUS`] until every one of
/// [`BasinOptions::ring_points`] points on the circle d(x, yᵢ) = r around every cycle point yᵢ comes
/// within r/2 of the cycle in at most N applications of P_T, with
///
/// ```text
///   N = m · (3 ⌈ln 2 / (−ln ρ)⌉ + 10),   ρ the spectral radius of P_Tᵐ,
/// ```
///
/// three times the linear halving time (a margin for non-normal transients), capped at 5000.
/// Returns (r, certified); at [`MIN_RADIUS`] without success the radius is kept but not certified.
pub fn certify<S: DrivenOscillator + ?Sized>(
    sys: &S,
    metric: &SectionMetric,
    a: &Attractor,
    opts: &BasinOptions,
) -> Result<(f64, bool)> {
    let m = a.points.len();
    let rho = a.spectral_radius().min(0.999_999);
    let halving = if rho > 0.0 {
        (2f64.ln() / -rho.ln()).ceil() as usize
    } else {
        0
    };
    let n_max = (m * (3 * halving + 10)).min(5000);
    let mut r = opts.neighbourhood;
    loop {
        if ring_returns(sys, metric, a, r, n_max, opts)? {
            return Ok((r, true));
        }
        if r / 2.0 < MIN_RADIUS {
            return Ok((r / 2.0, false));
        }
        r /= 2.0;
    }
}

/// Do all ring points at radius `r` come within r/2 of the cycle within `n_max` periods?
fn ring_returns<S: DrivenOscillator + ?Sized>(
    sys: &S,
    metric: &SectionMetric,
    a: &Attractor,
    r: f64,
    n_max: usize,
    opts: &BasinOptions,
) -> Result<bool> {
    let n = opts.ring_points;
    for y in &a.points {
        for i in 0..n {
            let phi = std::f64::consts::TAU * i as f64 / n as f64;
            let mut x = [
                y[0] + r * phi.cos(),
                y[1] + r * phi.sin() / metric.omega_weight,
            ];
            let mut back = false;
            for _ in 0..n_max {
                x = metric.reduce(metric.stroboscopic(sys, x, 1, opts.tol)?);
                if metric.distance_to(x, &a.points) < 0.5 * r {
                    back = true;
                    break;
                }
            }
            if !back {
                return Ok(false);
            }
        }
    }
    Ok(true)
}
