//! Poincaré maps of a driven oscillator and their Jacobians.
//!
//! - The stroboscopic map P_T: x(0) ↦ x(T) on the lift (β ∈ ℝ, windings counted), and its iterates
//!   P_T^k, integrated in one go from 0 to kT.
//! - The half-period map G = R⁻¹ ∘ P_{T/2} for systems with a half-period symmetry R
//!   (model.md, "Symmetry"); for the gear R(β, ω) = (β + π, ω), and P_T = R² ∘ G².
//!
//! Parameter columns are total derivatives of the map: the flow's ∂x/∂p at fixed end time plus
//! F(x(kT)) · k dT/dp for parameters that change the period (the drive frequency).

use crate::error::{Error, Result};
use crate::integrator::{vector_field, Event, FlowMethod, FlowOptions, Mode, Sensitivity, Stats};
use crate::model::DrivenOscillator;
use nalgebra::{Complex, Matrix2, Matrix2xX};
use serde::{Deserialize, Serialize};

/// Which Poincaré section.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Section {
    /// The stroboscopic map P_T over one drive period.
    #[default]
    Stroboscopic,
    /// The half-period map G = R⁻¹ ∘ P_{T/2} (needs a half-period symmetry).
    HalfPeriod,
}

impl std::fmt::Display for Section {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Section::Stroboscopic => "stroboscopic P_T",
            Section::HalfPeriod => "half-period G",
        })
    }
}

impl Section {
    /// Duration of one application of the map, in drive periods (1 or ½).
    pub fn periods(self) -> f64 {
        match self {
            Section::Stroboscopic => 1.0,
            Section::HalfPeriod => 0.5,
        }
    }
}

/// The image of a state under a Poincaré map, with its Jacobians.
#[derive(Debug, Clone, PartialEq)]
pub struct MapImage {
    /// The image (β, ω) on the lift.
    pub x: [f64; 2],
    /// Mode at the section.
    pub mode: Mode,
    /// ∂(map)/∂x, if sensitivities were requested.
    pub jac_x: Option<Matrix2<f64>>,
    /// ∂(map)/∂p (total, including the period's dependence), if requested.
    pub jac_p: Option<Matrix2xX<f64>>,
    /// Events along the way, if requested.
    pub events: Vec<Event>,
    /// Work counters.
    pub stats: Stats,
}

/// Applies `iterations` times the map of `section` to `x`, with Jacobians as requested in `opts`.
///
/// ```
/// use gearbif::model::Gear;
/// use gearbif::integrator::{EventDriven, FlowOptions, Sensitivity};
/// use gearbif::maps::{poincare_map, Section};
/// let gear = Gear::paper(25.0, 2.7).unwrap();
/// let opts = FlowOptions::with_tol(1e-10).sensitivity(Sensitivity::State);
/// let g2 = poincare_map(&EventDriven, &gear, Section::HalfPeriod, [3.0, 1.0], 2, &opts).unwrap();
/// let p = poincare_map(&EventDriven, &gear, Section::Stroboscopic, [3.0, 1.0], 1, &opts).unwrap();
/// // P_T = R² ∘ G²: the images differ by the 2π shift R² on the lift
/// assert!((p.x[0] - (g2.x[0] + 2.0 * std::f64::consts::PI)).abs() < 1e-7);
/// assert!((p.x[1] - g2.x[1]).abs() < 1e-7);
/// ```
pub fn poincare_map<S, M>(
    method: &M,
    sys: &S,
    section: Section,
    x: [f64; 2],
    iterations: usize,
    opts: &FlowOptions,
) -> Result<MapImage>
where
    S: DrivenOscillator + ?Sized,
    M: FlowMethod<S> + ?Sized,
{
    if iterations == 0 {
        return Err(Error::option("iterations", "must be >= 1, got 0"));
    }
    let sym = match section {
        Section::Stroboscopic => None,
        Section::HalfPeriod => Some(
            sys.half_period_symmetry()
                .ok_or(Error::NoHalfPeriodSymmetry)?,
        ),
    };
    let k = iterations as f64 * section.periods();
    let t1 = k * sys.period();
    let flow = method.flow(sys, 0.0, x, t1, opts)?;
    let mut jac_x = flow.jac_x;
    let mut jac_p = flow.jac_p;
    if let Some(jp) = jac_p.as_mut() {
        let fv = vector_field(sys, t1, flow.x, flow.mode);
        for c in 0..jp.ncols() {
            let dt = k * sys.period_derivative(c);
            jp[(0, c)] += fv[0] * dt;
            jp[(1, c)] += fv[1] * dt;
        }
    }
    let mut xe = flow.x;
    if let Some(r) = sym {
        for _ in 0..iterations {
            xe = r.invert(xe);
        }
        let sg = r.sign.powi(iterations as i32);
        if let Some(j) = jac_x.as_mut() {
            *j *= sg;
        }
        if let Some(j) = jac_p.as_mut() {
            *j *= sg;
        }
    }
    Ok(MapImage {
        x: xe,
        mode: flow.mode,
        jac_x,
        jac_p,
        events: flow.events,
        stats: flow.stats,
    })
}

/// P_T(x) with ∂P_T/∂x and ∂P_T/∂p, using the event-driven integrator at tolerance `tol`.
pub fn stroboscopic<S: DrivenOscillator + ?Sized>(
    sys: &S,
    x: [f64; 2],
    tol: f64,
) -> Result<MapImage> {
    let opts = FlowOptions::with_tol(tol).sensitivity(Sensitivity::StateAndParams);
    poincare_map(
        &crate::integrator::DEFAULT_METHOD,
        sys,
        Section::Stroboscopic,
        x,
        1,
        &opts,
    )
}

/// G(x) = R⁻¹ P_{T/2}(x) with its Jacobians, using the event-driven integrator at tolerance `tol`.
pub fn half_period<S: DrivenOscillator + ?Sized>(
    sys: &S,
    x: [f64; 2],
    tol: f64,
) -> Result<MapImage> {
    let opts = FlowOptions::with_tol(tol).sensitivity(Sensitivity::StateAndParams);
    poincare_map(
        &crate::integrator::DEFAULT_METHOD,
        sys,
        Section::HalfPeriod,
        x,
        1,
        &opts,
    )
}

/// Eigenvalues (Floquet multipliers) of a 2×2 map Jacobian, largest modulus first.
///
/// Computed from trace and determinant in a cancellation-free way (μ₂ = det/μ₁), so an orbit with a
/// stick phase (det = 0 exactly) has an exact zero multiplier.
pub fn multipliers(m: &Matrix2<f64>) -> [Complex<f64>; 2] {
    let tr = m[(0, 0)] + m[(1, 1)];
    let det = m[(0, 0)] * m[(1, 1)] - m[(0, 1)] * m[(1, 0)];
    let half = 0.5 * tr;
    let disc = half * half - det;
    if disc >= 0.0 {
        let sq = disc.sqrt();
        let mu1 = if half >= 0.0 { half + sq } else { half - sq };
        let mu2 = if mu1 != 0.0 { det / mu1 } else { 0.0 };
        [Complex::new(mu1, 0.0), Complex::new(mu2, 0.0)]
    } else {
        let im = (-disc).sqrt();
        [Complex::new(half, im), Complex::new(half, -im)]
    }
}
