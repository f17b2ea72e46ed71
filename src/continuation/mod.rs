//! Pseudo-arclength continuation of periodic orbits of any [`Parametrised`] system, with
//! detection and location of folds, flips, symmetry-breaking points, Neimark–Sacker points and
//! nonsmooth events, branch switching, and two-parameter curves. Split by concern, as in
//! BifurcationKit:
//!
//! - [`options`]: the options [`ContinuationOptions`];
//! - [`palc`]: the solver [`Continuation`] — tangent predictor, Newton corrector on the bordered
//!   system, step-size control — as a state machine ([`Continuation::step`]) with an observer;
//! - [`detect`]: test functions on the Floquet data and the location of their zeros and of changes
//!   of the event sequence between two points;
//! - [`switch`]: branch switching at flips and symmetry-breaking points;
//! - [`branch`]: the one result type [`Branch`] with its [`SpecialPoint`]s;
//! - [`two_param`]: special points as solutions of an augmented system and their curves in two
//!   parameters by natural continuation;
//! - [`minaug`]: the map linearisation shared by every corrector, and the bordered test function of
//!   the minimally augmented systems;
//! - [`palc2`]: two-parameter curves by pseudo-arclength on the minimally augmented systems and of
//!   nonsmooth points (grazing, end of sticking), with [`codim2`]: codimension-two points located
//!   on them;
//! - [`sensitivity`]: dλ*/dp of a located special point by the implicit-function theorem on its
//!   augmented system, and its σ from a parameter covariance.
//!
//! Unknowns u = (β, ω, λ). Equations: F(x, λ) = Pᵏ(x; λ) − x − (s, 0) = 0 and the arclength
//! condition t·(u − u_pred) = 0, with t the unit tangent. The λ column ∂F/∂λ is the map's `jac_p`
//! column chosen by the system's parameter lens ([`crate::model::params`]), with its chain rule.
//!
//! [`Parametrised`]: crate::model::Parametrised

pub mod branch;
pub mod codim2;
pub mod detect;
pub mod diagram;
pub mod identity;
pub mod minaug;
pub mod multiple_shooting;
pub mod options;
pub mod palc;
pub mod palc2;
pub mod pinned;
pub mod sensitivity;
pub mod switch;
pub mod two_param;

pub use crate::progress::Observer;
pub use branch::{Branch, BranchPoint, NonsmoothJump, SpecialKind, SpecialPoint, StopReason};
pub use options::ContinuationOptions;
pub use palc::{Continuation, StepOutcome};
pub use switch::{switch_branch, switch_branch_with, SwitchStart};
