//! The whole bifurcation diagram of the gear over a parameter range, automatically.
//!
//! 1. **Seeds**: attractors found by simulation on a grid of the parameter (relaxed, period and
//!    winding detected, shot; symmetric orbits on G), and the analytic lock branch (stable and
//!    unstable) where the system has one (Δ = ±1).
//! 2. Each seed not already on a computed branch is **continued in both directions** to the ends of
//!    the range.
//! 3. At every **flip** (onto P_T^{2k}, up to `max_period`) and **symmetry-breaking** point (onto P_T)
//!    the new branch is started by [`super::switch_branch`] and continued in both directions: away from
//!    the point, and towards it, where it passes the tip of the pitchfork and runs onto its twin
//!    (the same orbits shifted by the symmetry R or by P_Tᵏ), which is recognised and stops it.
//!    Nonsmooth folds are passed by the continuation itself (the branch turns back).
//! 4. **Identity** ([`super::identity`]): every few steps the current orbit is compared with all
//!    branches computed so far, modulo R, the 2π lift and the choice of map, so a branch met again
//!    (from another seed, through the tip of a pitchfork, or as a period-1 orbit seen on P_T²)
//!    stops the run with [`StopReason::KnownBranch`] instead of being recomputed.
//!
//! Output: the branches with their origin, every special point typed (symmetry-breaking and flip
//! points with their criticality; duplicates — the same bifurcation seen on two maps — linked by
//! `same_as`), serialised with the schema id [`DIAGRAM_SCHEMA`].

use super::identity::{lies_on_branch, section_distance, IdentityOptions, OrbitImages};
use super::multiple_shooting::{extend_by_multiple_shooting, MultipleShootingOptions};
use super::pinned::{new_spec, switch_pinned};
use super::{
    Branch, Continuation, ContinuationOptions, SpecialKind, SpecialPoint, StepOutcome, StopReason,
};
use crate::error::{Error, Result};
use crate::model::{Gear, Parameter, Parametrised};
use crate::orbits::{orbit_from_simulation, shoot, OrbitSpec, PeriodicOrbit};
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use std::collections::VecDeque;

/// Schema id of the diagram JSON.
pub const DIAGRAM_SCHEMA: &str = "gearbif.diagram/1";

/// Options of [`diagram`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DiagramOptions<P> {
    /// The parameter.
    pub param: P,
    /// Its range [lo, hi].
    pub range: (f64, f64),
    /// Number of parameter values at which attractors are sought by simulation.
    pub grid: usize,
    /// Drive periods of relaxation before a period is detected.
    pub relax_periods: usize,
    /// Largest P_T-period detected in a simulation and followed through period doublings.
    pub max_period: usize,
    /// Continuation options (the parameter range is taken from `range`).
    pub continuation: ContinuationOptions,
    /// Amplitude ε of the pinned branch switch: the new branch's start lies ε from the bifurcating
    /// orbit along the critical eigenvector (larger ε are tried if Newton fails).
    pub switch_offset: f64,
    /// The current orbit is compared with the known branches every this many steps.
    pub check_every: usize,
    /// Continue by multiple shooting where single shooting reaches its multiplier limit.
    pub multiple_shooting: Option<MultipleShootingOptions>,
    /// Largest number of continuation runs.
    pub max_runs: usize,
}

impl<P: Parameter> DiagramOptions<P> {
    /// Defaults for the parameter `param` over `range`.
    pub fn new(param: P, range: (f64, f64)) -> Self {
        Self {
            param,
            range,
            grid: 6,
            relax_periods: 300,
            max_period: 16,
            continuation: ContinuationOptions {
                ds: 0.01,
                ds_max: 0.05,
                max_steps: 600,
                ..Default::default()
            },
            switch_offset: 1e-2,
            check_every: 2,
            multiple_shooting: Some(MultipleShootingOptions::default()),
            max_runs: 80,
        }
    }
}

/// Where a branch of the diagram comes from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "type")]
pub enum Origin {
    /// An attractor of a simulation at this parameter value.
    Simulation {
        /// Parameter value.
        at: f64,
    },
    /// The analytic lock branch ("stable" or "unstable").
    Analytic {
        /// Which one.
        which: String,
    },
    /// Branch switching at a special point of another branch.
    Switch {
        /// Index of the parent branch.
        parent: usize,
        /// Index of the special point in [`Diagram::special_points`].
        point: usize,
    },
}

impl std::fmt::Display for Origin {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Origin::Simulation { at } => write!(f, "a simulation at {at}"),
            Origin::Analytic { which } => write!(f, "the analytic {which} lock"),
            Origin::Switch { parent, point } => {
                write!(f, "switching at point [{point}] of run [{parent}]")
            }
        }
    }
}

/// One continuation run of the diagram.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(bound(serialize = "S: Serialize", deserialize = "S: DeserializeOwned"))]
pub struct DiagramBranch<S: Parametrised = Gear> {
    /// Where its start orbit came from.
    pub origin: Origin,
    /// +1 or −1: the initial direction in the parameter.
    pub direction: f64,
    /// The primitive length of its orbits (1: symmetric, 2: asymmetric T-periodic, 4: period 2, …;
    /// see [`super::identity`]).
    pub primitive: usize,
    /// The branch.
    pub branch: Branch<S>,
}

/// Criticality of a symmetry-breaking or flip point.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Criticality {
    /// The new branch is stable where it is born (the parent loses stability): supercritical.
    Supercritical,
    /// The new branch is unstable where it is born: subcritical.
    Subcritical,
    /// The parent is unstable on both sides, so stability does not tell.
    Undetermined,
}

impl std::fmt::Display for Criticality {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Criticality::Supercritical => "supercritical",
            Criticality::Subcritical => "subcritical",
            Criticality::Undetermined => "criticality undetermined",
        })
    }
}

/// A special point of the diagram.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DiagramPoint {
    /// Index of the branch in [`Diagram::branches`].
    pub branch: usize,
    /// The special point as located on that branch.
    pub point: SpecialPoint,
    /// For symmetry-breaking and flip points: criticality, if the switch succeeded.
    pub criticality: Option<Criticality>,
    /// Branches started here.
    pub switched_to: Vec<usize>,
    /// Why no branch was started here, if none was.
    pub not_switched: Option<String>,
    /// The index of an earlier special point that is the same bifurcation (same parameter and orbit,
    /// possibly seen on another map: a symmetry-breaking point of G is a branch point of P_T).
    pub same_as: Option<usize>,
}

/// A seed and what became of it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Seed {
    /// Origin.
    pub origin: Origin,
    /// The orbit problem and state, if a periodic orbit was found.
    pub orbit: Option<PeriodicOrbit>,
    /// Index of the branch it started or was found on, if any.
    pub branch: Option<usize>,
    /// True if it lay on a branch already computed.
    pub known: bool,
    /// Why no orbit came of it, if none did.
    pub failure: Option<String>,
}

/// The automatic bifurcation diagram.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(bound(serialize = "S: Serialize", deserialize = "S: DeserializeOwned"))]
pub struct Diagram<S: Parametrised = Gear> {
    /// [`DIAGRAM_SCHEMA`].
    pub schema: String,
    /// The parameter.
    pub param: S::Param,
    /// The range.
    pub range: (f64, f64),
    /// The system (at the first grid value).
    pub system: S,
    /// The continuation runs.
    pub branches: Vec<DiagramBranch<S>>,
    /// Every special point (in the order found).
    pub special_points: Vec<DiagramPoint>,
    /// The seeds.
    pub seeds: Vec<Seed>,
    /// Map evaluations of all runs.
    pub map_evaluations: usize,
}

impl<S: Parametrised> Diagram<S> {
    /// The distinct special points (those not `same_as` an earlier one) of a kind.
    pub fn distinct(&self, kind: SpecialKind) -> impl Iterator<Item = &DiagramPoint> {
        self.special_points
            .iter()
            .filter(move |p| p.point.kind == kind && p.same_as.is_none())
    }
}

/// A seed known analytically (e.g. the gear's lock branch at Δ = ±1).
#[derive(Debug, Clone, PartialEq)]
pub struct AnalyticSeed<S> {
    /// Its name ("stable lock", …).
    pub name: String,
    /// The system at the seed's parameter value.
    pub system: S,
    /// The orbit (shot from the analytic state).
    pub orbit: Result<PeriodicOrbit>,
}

/// The gear's analytic lock branch (stable and unstable) as seeds, if Δ = ±1.
pub fn lock_seeds(gear: &Gear, opts: &crate::orbits::ShootingOptions) -> Vec<AnalyticSeed<Gear>> {
    let Ok(lb) = gear.lock_branch() else {
        return Vec::new();
    };
    [("stable", lb.stable), ("unstable", lb.unstable)]
        .into_iter()
        .map(|(which, pt)| AnalyticSeed {
            name: which.into(),
            system: *gear,
            orbit: shoot(gear, &OrbitSpec::symmetric(pt.winding), pt.state, opts),
        })
        .collect()
}

struct Start<S> {
    gear: S,
    orbit: PeriodicOrbit,
    origin: Origin,
    /// For switches: run only these directions (both by default).
    directions: [f64; 2],
}

struct Builder<'a, S: Parametrised> {
    opts: &'a DiagramOptions<S::Param>,
    ident: IdentityOptions,
    d: Diagram<S>,
}

impl<S: Parametrised> Builder<'_, S> {
    fn images(&self, gear: &S, spec: &OrbitSpec, x: [f64; 2]) -> Result<OrbitImages> {
        OrbitImages::of(gear, spec, x, self.opts.continuation.shooting.tol, 1e-6)
    }

    /// The index of a computed branch the orbit lies on.
    fn known(&self, lam: f64, im: &OrbitImages, skip: Option<usize>) -> Result<Option<usize>> {
        for (i, b) in self.d.branches.iter().enumerate() {
            if Some(i) == skip {
                continue;
            }
            if lies_on_branch(&b.branch, b.primitive, lam, im, &self.ident)? {
                return Ok(Some(i));
            }
        }
        Ok(None)
    }

    /// One continuation run from `start` in `direction`, stopped when it meets a known branch.
    fn run(&mut self, start: &Start<S>, direction: f64) -> Result<usize> {
        let p = self.opts.param;
        let (lo, hi) = self.opts.range;
        // switched branches start close to the bifurcation point: smaller first steps
        let ds0 = match start.origin {
            Origin::Switch { .. } => 0.25 * self.opts.continuation.ds.abs(),
            _ => self.opts.continuation.ds.abs(),
        };
        let copts = ContinuationOptions {
            ds: direction * ds0,
            param_min: lo,
            param_max: hi,
            ..self.opts.continuation
        };
        let im0 = self.images(&start.gear, &start.orbit.spec, start.orbit.x)?;
        let mut c = Continuation::from_orbit(start.gear.clone(), p, &start.orbit, copts)?;
        let id = self.d.branches.len();
        let mut known_at = None;
        let mut steps = 0usize;
        loop {
            match c.step()? {
                StepOutcome::Done => break,
                StepOutcome::Point(_) => {
                    steps += 1;
                    if steps % self.opts.check_every.max(1) != 0 {
                        continue;
                    }
                    let last = c.branch().points.last().cloned();
                    if let Some(pt) = last {
                        let g = start.gear.with_param(p, pt.param)?;
                        if let Ok(im) = self.images(&g, &start.orbit.spec, pt.x) {
                            if let Some(k) = self.known(pt.param, &im, None)? {
                                known_at = Some((k, pt.param));
                                break;
                            }
                        }
                    }
                }
            }
        }
        let mut branch = c.into_branch();
        if let Some((k, at)) = known_at {
            branch.stop = StopReason::KnownBranch(format!(
                "branch {k} ({:?}, k = {}, p = {}) at {} = {at}",
                self.d.branches[k].branch.spec.section,
                self.d.branches[k].branch.spec.iterations,
                self.d.branches[k].branch.spec.winding,
                p.name()
            ));
        } else if let (Some(ms), StopReason::MultiplierLimit(_)) =
            (self.opts.multiple_shooting.as_ref(), &branch.stop)
        {
            extend_by_multiple_shooting(&mut branch, &copts, ms)?;
        }
        self.d.map_evaluations += branch.map_evaluations;
        self.d.branches.push(DiagramBranch {
            origin: start.origin.clone(),
            direction,
            primitive: im0.primitive,
            branch,
        });
        self.register_specials(id)?;
        Ok(id)
    }

    /// Adds the special points of branch `id`, linking duplicates.
    fn register_specials(&mut self, id: usize) -> Result<()> {
        let b = self.d.branches[id].branch.clone();
        for sp in &b.specials {
            let mut same_as = None;
            for (j, q) in self.d.special_points.iter().enumerate() {
                let tol = 1e-6 * sp.param.abs().max(1.0) + sp.precision + q.point.precision;
                if (q.point.param - sp.param).abs() > tol {
                    continue;
                }
                let g = b.system.with_param(b.param, sp.param)?;
                let im = self.images(&g, &b.spec, sp.x)?;
                if im.distance(q.point.x) < 1e-4 {
                    same_as = Some(j);
                    break;
                }
            }
            self.d.special_points.push(DiagramPoint {
                branch: id,
                point: sp.clone(),
                criticality: None,
                switched_to: Vec::new(),
                not_switched: None,
                same_as,
            });
        }
        Ok(())
    }

    /// Starts for the new branches at special point `k`, if it is a distinct flip or symmetry-
    /// breaking point within the period limit.
    fn switch_start(&mut self, k: usize) -> Option<Start<S>> {
        let dp = &self.d.special_points[k];
        if dp.same_as.is_some() {
            return None;
        }
        let parent = dp.branch;
        let b = &self.d.branches[parent].branch;
        let sp = dp.point.clone();
        match sp.kind {
            SpecialKind::Flip if 2 * b.spec.on_stroboscopic().iterations > self.opts.max_period => {
                self.d.special_points[k].not_switched = Some(format!(
                    "period {} beyond max_period",
                    2 * b.spec.iterations
                ));
                return None;
            }
            SpecialKind::Flip | SpecialKind::SymmetryBreaking => {}
            _ => return None,
        }
        let new_spec = new_spec(&b.spec, sp.kind).ok()?;
        let prim = self.d.branches[parent].primitive;
        match switch_pinned(
            b,
            &sp,
            &new_spec,
            prim,
            self.opts.switch_offset,
            &self.opts.continuation.shooting,
        ) {
            Ok((gear, orbit)) => {
                let lam = gear.param(self.opts.param);
                let side = (lam - sp.param).signum();
                // the parent's stability on the new branch's side of the point
                let i = sp.after_point.min(b.points.len() - 1);
                let j = (i + 1).min(b.points.len() - 1);
                let (pa, pb) = (&b.points[i], &b.points[j]);
                let parent_side_stable = if (pa.param - sp.param).signum() == side {
                    pa.stable
                } else {
                    pb.stable
                };
                let crit = if !sp.stability_change {
                    Criticality::Undetermined
                } else if parent_side_stable {
                    Criticality::Subcritical
                } else {
                    Criticality::Supercritical
                };
                self.d.special_points[k].criticality = Some(crit);
                Some(Start {
                    gear,
                    orbit,
                    origin: Origin::Switch { parent, point: k },
                    directions: [side, -side],
                })
            }
            Err(e) => {
                self.d.special_points[k].not_switched = Some(e.to_string());
                None
            }
        }
    }

    fn process(&mut self, start: Start<S>) -> Result<()> {
        let mut queue = VecDeque::from([start]);
        while let Some(st) = queue.pop_front() {
            let n0 = self.d.special_points.len();
            for &dir in &st.directions {
                if self.d.branches.len() >= self.opts.max_runs {
                    return Ok(());
                }
                let id = self.run(&st, dir)?;
                if let Origin::Switch { point, .. } = st.origin {
                    self.d.special_points[point].switched_to.push(id);
                }
            }
            for k in n0..self.d.special_points.len() {
                if let Some(s) = self.switch_start(k) {
                    queue.push_back(s);
                }
            }
        }
        Ok(())
    }

    fn seed(&mut self, origin: Origin, gear: S, orbit: Result<PeriodicOrbit>) -> Result<()> {
        let orbit = match orbit {
            Ok(o) => o,
            Err(e) => {
                self.d.seeds.push(Seed {
                    origin,
                    orbit: None,
                    branch: None,
                    known: false,
                    failure: Some(e.to_string()),
                });
                return Ok(());
            }
        };
        let lam = gear.param(self.opts.param);
        let im = self.images(&gear, &orbit.spec, orbit.x)?;
        if let Some(k) = self.known(lam, &im, None)? {
            self.d.seeds.push(Seed {
                origin,
                orbit: Some(orbit),
                branch: Some(k),
                known: true,
                failure: None,
            });
            return Ok(());
        }
        let first = self.d.branches.len();
        self.d.seeds.push(Seed {
            origin: origin.clone(),
            orbit: Some(orbit.clone()),
            branch: Some(first),
            known: false,
            failure: None,
        });
        self.process(Start {
            gear,
            orbit,
            origin,
            directions: [-1.0, 1.0],
        })
    }
}

/// Computes the bifurcation diagram of `base` (its parameter value is replaced by the grid values)
/// over `opts.range`, seeded by simulations on the grid and by `analytic` (see the module docs).
pub fn diagram<S: Parametrised>(
    base: &S,
    opts: &DiagramOptions<S::Param>,
    analytic: Vec<AnalyticSeed<S>>,
) -> Result<Diagram<S>> {
    let (lo, hi) = opts.range;
    if !(lo.is_finite() && hi.is_finite() && lo < hi) {
        return Err(Error::option(
            "diagram range",
            format!("{lo}:{hi} must be finite numbers with lo < hi"),
        ));
    }
    if opts.grid == 0 || opts.max_period == 0 {
        return Err(Error::option(
            "diagram grid, max_period",
            format!("must be >= 1, got {} and {}", opts.grid, opts.max_period),
        ));
    }
    let p = opts.param;
    let values: Vec<f64> = (0..opts.grid)
        .map(|j| lo + (hi - lo) * (j as f64 + 0.5) / opts.grid as f64)
        .collect();
    let g0 = base.with_param(p, values[0])?;
    let mut b = Builder {
        opts,
        ident: IdentityOptions {
            shooting: opts.continuation.shooting,
            ..Default::default()
        },
        d: Diagram {
            schema: DIAGRAM_SCHEMA.into(),
            param: p,
            range: opts.range,
            system: g0,
            branches: Vec::new(),
            special_points: Vec::new(),
            seeds: Vec::new(),
            map_evaluations: 0,
        },
    };
    for a in analytic {
        b.seed(Origin::Analytic { which: a.name }, a.system, a.orbit)?;
    }
    for &v in &values {
        let g = base.with_param(p, v)?;
        for x0 in [[0.0, 0.0], [std::f64::consts::PI, 0.0]] {
            let o = orbit_from_simulation(
                &g,
                x0,
                opts.relax_periods,
                opts.max_period.min(8),
                true,
                &opts.continuation.shooting,
            );
            b.seed(Origin::Simulation { at: v }, g.clone(), o)?;
        }
    }
    Ok(b.d)
}

/// The distance (β modulo 2π) between two special points' states.
pub fn state_distance(a: &SpecialPoint, b: &SpecialPoint) -> f64 {
    section_distance(a.x, b.x, 1.0)
}
