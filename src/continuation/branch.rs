//! The one result type of a continuation: a [`Branch`] with its points and special points, read by
//! the CLI, the JSON output and the plots alike.

use crate::model::{Gear, Parametrised};
use crate::orbits::{EventCounts, Floquet, OrbitSpec};
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

/// One point of a branch.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BranchPoint {
    /// Value of the continuation parameter.
    pub param: f64,
    /// State (β, ω) on the section at t = 0 (physical convention).
    pub x: [f64; 2],
    /// Floquet data of the orbit's map.
    pub floquet: Floquet,
    /// True if all multipliers have modulus < 1.
    pub stable: bool,
    /// Events per application of the orbit's map.
    pub events: EventCounts,
    /// Arclength from the first point (in the scaled (β, ω, λ) space of the continuation).
    pub arclength: f64,
}

/// What kind of special point.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SpecialKind {
    /// Saddle-node (fold) of the orbit: a multiplier +1 of the orbit's map; the branch turns back.
    Fold,
    /// Period doubling: a multiplier −1 of P_Tᵏ.
    Flip,
    /// Symmetry-breaking pitchfork of P_T: a multiplier −1 of the half-period map G.
    SymmetryBreaking,
    /// Neimark–Sacker: a complex pair on the unit circle (det = 1).
    NeimarkSacker,
    /// A change of the number of crossings or stick phases per period (grazing, onset or end of
    /// sticking): a discontinuity-induced bifurcation, with a jump of the multipliers.
    Nonsmooth,
}

impl SpecialKind {
    /// Short label for tables and plots.
    pub fn label(self) -> &'static str {
        match self {
            SpecialKind::Fold => "fold",
            SpecialKind::Flip => "flip",
            SpecialKind::SymmetryBreaking => "symmetry-breaking",
            SpecialKind::NeimarkSacker => "Neimark-Sacker",
            SpecialKind::Nonsmooth => "nonsmooth",
        }
    }
}

/// A located special point.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SpecialPoint {
    /// Type.
    pub kind: SpecialKind,
    /// Located parameter value.
    pub param: f64,
    /// Error estimate of `param`: half-width of the final bracket on the branch plus the corrector
    /// tolerance (it does not include the integrator's truncation error; see docs/continuation.md).
    pub precision: f64,
    /// State on the section at the located point.
    pub x: [f64; 2],
    /// Floquet data at the located point (for a nonsmooth point: on the side of `param` reached last).
    pub floquet: Floquet,
    /// The value of the test function at the located point (0 for nonsmooth points).
    pub test_value: f64,
    /// Eigenvector of the critical real multiplier (±1), for branch switching.
    pub eigenvector: Option<[f64; 2]>,
    /// Index of the branch point after which the special point lies.
    pub after_point: usize,
    /// For nonsmooth points: events and Floquet data on both sides (before, after along the branch).
    pub jump: Option<NonsmoothJump>,
    /// Stability changes at this point (the branch's stability differs on both sides).
    pub stability_change: bool,
}

/// The two sides of a nonsmooth point.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NonsmoothJump {
    /// Events per map before the point (along the branch direction).
    pub events_before: EventCounts,
    /// Events per map after the point.
    pub events_after: EventCounts,
    /// Floquet data just before.
    pub floquet_before: Floquet,
    /// Floquet data just after.
    pub floquet_after: Floquet,
    /// Parameter values of the two bracket points.
    pub param_before: f64,
    /// See `param_before`.
    pub param_after: f64,
    /// If a multiplier jumps across +1 or −1 here, which test function changes sign in the jump
    /// (a fold/flip-like nonsmooth bifurcation): "fold", "flip" or none.
    pub crosses: Option<String>,
}

/// Why a continuation stopped.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "reason", content = "detail")]
pub enum StopReason {
    /// The parameter reached a bound of the requested range (the last point lies on it).
    ParameterBound(f64),
    /// The largest number of steps was reached.
    MaxSteps(usize),
    /// A multiplier exceeded the limit for single shooting.
    MultiplierLimit(f64),
    /// The corrector failed at the smallest step size `ds_min` after the point at parameter `at`.
    StepTooSmall {
        /// Parameter value of the last point.
        at: f64,
        /// The smallest step tried.
        ds_min: f64,
    },
    /// The branch left the parameter range but no orbit could be corrected onto the bound.
    BoundNotReached(f64),
    /// The branch ran onto a branch already computed (same orbits, up to the symmetry R, the 2π
    /// lift and the choice of map); the detail names it. Used by the automatic diagram.
    KnownBranch(String),
    /// Not stopped yet.
    Running,
}

impl std::fmt::Display for StopReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StopReason::ParameterBound(v) => write!(f, "reached the range's bound {v}"),
            StopReason::MaxSteps(n) => write!(f, "took the largest number of steps, {n}"),
            StopReason::MultiplierLimit(m) => write!(
                f,
                "a multiplier's modulus {m:.3e} exceeds the limit of single shooting"
            ),
            StopReason::StepTooSmall { at, ds_min } => write!(
                f,
                "the corrector failed at the smallest step {ds_min:e} after the point at {at}"
            ),
            StopReason::BoundNotReached(v) => write!(
                f,
                "left the range but no orbit could be corrected onto the bound {v}"
            ),
            StopReason::KnownBranch(which) => write!(f, "ran onto a known branch ({which})"),
            StopReason::Running => f.write_str("running"),
        }
    }
}

/// A branch of periodic orbits of system `S` with its special points.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(bound(serialize = "S: Serialize", deserialize = "S: DeserializeOwned"))]
pub struct Branch<S: Parametrised = Gear> {
    /// The continuation parameter.
    pub param: S::Param,
    /// The fixed-point problem (section, period, winding).
    pub spec: OrbitSpec,
    /// The system at the first point.
    pub system: S,
    /// The points, in continuation order.
    pub points: Vec<BranchPoint>,
    /// Located special points, in continuation order.
    pub specials: Vec<SpecialPoint>,
    /// Why the continuation stopped.
    pub stop: StopReason,
    /// Map evaluations (each one integration with sensitivities; with multiple shooting one
    /// evaluation of all segments).
    pub map_evaluations: usize,
    /// Index of the first point computed by multiple shooting (where single shooting reached its
    /// multiplier limit), if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub multiple_shooting_from: Option<usize>,
}

impl<S: Parametrised> Branch<S> {
    /// Special points of a given kind.
    pub fn specials_of(&self, kind: SpecialKind) -> impl Iterator<Item = &SpecialPoint> {
        self.specials.iter().filter(move |s| s.kind == kind)
    }
    /// Range of the parameter covered.
    pub fn param_range(&self) -> Option<(f64, f64)> {
        let mut it = self.points.iter().map(|p| p.param);
        let first = it.next()?;
        Some(it.fold((first, first), |(a, b), v| (a.min(v), b.max(v))))
    }
}
