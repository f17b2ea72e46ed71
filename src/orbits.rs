//! Periodic orbits by shooting on a Poincaré map, and their Floquet multipliers.
//!
//! A periodic orbit is a zero of the shooting residual
//!
//! ```text
//!   F(x) = Pᵏ(x) − x − (s, 0),
//! ```
//!
//! where P is the stroboscopic map P_T or the half-period map G = R⁻¹ ∘ P_{T/2} of a system with a
//! half-period symmetry (model.md, "Symmetry"), k the number of iterations and s the shift on the
//! lift that encodes the winding ([`OrbitSpec::shift`]). Newton's method uses the map's Jacobian
//! `jac_x` (with saltation at every event), so it converges quadratically also through crossings and
//! stick phases.
//!
//! Multipliers are reported as multipliers, never as exponents: an orbit with a stick phase has an
//! exact zero multiplier (the stick saltation diag(1, 0) makes the monodromy rank one), and it is
//! returned as 0.

pub mod block_cyclic;
pub mod multiple_shooting;

use crate::error::{Error, Result};
use crate::integrator::{EventKind, FlowMethod, FlowOptions, Sensitivity, DEFAULT_METHOD};
use crate::maps::{multipliers, poincare_map, MapImage, Section};
use crate::model::DrivenOscillator;
use crate::numerics::{newton, Linearisation, NewtonOptions};
use nalgebra::{Matrix2, Vector2};
use serde::{Deserialize, Serialize};
use std::f64::consts::{PI, TAU};

/// Which fixed-point problem: the section, the number of map iterations and the winding.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct OrbitSpec {
    /// The Poincaré section (P_T or G).
    pub section: Section,
    /// Number of applications of the map (the period k in units of the map).
    pub iterations: usize,
    /// Winding p: for [`Section::Stroboscopic`] the number of turns of β over the k periods;
    /// for [`Section::HalfPeriod`] the number of turns per drive period T (odd for the gear).
    pub winding: i32,
}

impl OrbitSpec {
    /// A period-k orbit of P_T with total winding p over the k periods.
    pub fn stroboscopic(k: usize, p: i32) -> Self {
        Self {
            section: Section::Stroboscopic,
            iterations: k,
            winding: p,
        }
    }

    /// A symmetric orbit (fixed point of the half-period map G) with winding p per drive period.
    pub fn symmetric(p: i32) -> Self {
        Self {
            section: Section::HalfPeriod,
            iterations: 1,
            winding: p,
        }
    }

    /// Duration of the orbit's map in drive periods (k for P_T, k/2 for G).
    pub fn periods(&self) -> f64 {
        self.iterations as f64 * self.section.periods()
    }

    /// The β-shift s on the lift in F(x) = Pᵏ(x) − x − (s, 0).
    ///
    /// P_T: s = 2πp. G with R(β, ω) = (σβ + c, σω): a symmetric orbit advances by πp per half period,
    /// so G(x) = x + (πp − c) per application when σ = +1; when σ = −1 only p = 0 is meaningful and s = 0.
    pub fn shift<S: DrivenOscillator + ?Sized>(&self, sys: &S) -> Result<f64> {
        if self.iterations == 0 {
            return Err(Error::option("orbit iterations", "must be >= 1, got 0"));
        }
        match self.section {
            Section::Stroboscopic => Ok(TAU * self.winding as f64),
            Section::HalfPeriod => {
                let r = sys
                    .half_period_symmetry()
                    .ok_or(Error::NoHalfPeriodSymmetry)?;
                if r.sign > 0.0 {
                    Ok(self.iterations as f64 * (PI * self.winding as f64 - r.shift))
                } else if self.winding == 0 {
                    Ok(0.0)
                } else {
                    Err(Error::inconsistent(
                        "section, winding",
                        format!(
                            "with a reflecting symmetry (σ = −1) a symmetric orbit has winding 0, \
                             not {}",
                            self.winding
                        ),
                    ))
                }
            }
        }
    }

    /// The equivalent problem on P_T: the same orbit seen on the stroboscopic section.
    /// A fixed point of G (k = 1) is a fixed point of P_T with the same winding.
    pub fn on_stroboscopic(&self) -> Self {
        match self.section {
            Section::Stroboscopic => *self,
            Section::HalfPeriod => {
                // G^k with k even covers k/2 periods; k odd: the orbit closes after 2k half periods only
                // through the symmetry; P_T^{⌈k/2⌉} is exact for k = 1.
                let k = self.iterations.div_ceil(2).max(1);
                Self::stroboscopic(k, self.winding * k as i32)
            }
        }
    }
}

/// Numbers of events on Σ over one application of the orbit's map (k iterations).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct EventCounts {
    /// Crossings of Σ (ω changes sign).
    pub crossings: usize,
    /// Stick phases begun.
    pub sticks: usize,
    /// Tangential touches of Σ (grazing) without crossing or sticking.
    pub grazes: usize,
}

impl std::fmt::Display for EventCounts {
    /// "2 crossings, 0 sticks, 0 grazes".
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} crossings, {} sticks, {} grazes",
            self.crossings, self.sticks, self.grazes
        )
    }
}

impl EventCounts {
    /// Counts the events of a map image.
    pub fn from_image(img: &MapImage) -> Self {
        let mut c = Self::default();
        for e in &img.events {
            match e.kind {
                EventKind::Crossing { .. } => c.crossings += 1,
                EventKind::StickStart => c.sticks += 1,
                EventKind::Graze { .. } => c.grazes += 1,
                EventKind::Release { .. } => {}
            }
        }
        c
    }

    /// The signature that, when it changes along a branch, marks a nonsmooth (discontinuity-induced)
    /// event: (crossings, sticks). Grazes are not counted: they are the boundary itself.
    pub fn signature(&self) -> (usize, usize) {
        (self.crossings, self.sticks)
    }
}

/// Floquet data of a fixed point of a planar map with Jacobian M.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Floquet {
    /// Multipliers as (re, im), largest modulus first. A stick phase gives an exact 0.
    pub multipliers: [[f64; 2]; 2],
    /// tr M.
    pub trace: f64,
    /// det M.
    pub det: f64,
    /// True if every multiplier has modulus < 1.
    pub stable: bool,
}

impl Floquet {
    /// Floquet data of the Jacobian `m`.
    pub fn of(m: &Matrix2<f64>) -> Self {
        let mu = multipliers(m);
        let stable = mu.iter().all(|z| z.norm() < 1.0);
        Self {
            multipliers: [[mu[0].re, mu[0].im], [mu[1].re, mu[1].im]],
            trace: m.trace(),
            det: m.determinant(),
            stable,
        }
    }
    /// Floquet data of the Jacobian `m` of an orbit's map, given its events: with a stick phase the
    /// monodromy contains the saltation diag(1, 0) and is rank one analytically, so det = 0 and the
    /// multipliers are exactly (tr M, 0); rounding in the product would otherwise leave ~1e-16.
    pub fn of_orbit(m: &Matrix2<f64>, events: &EventCounts) -> Self {
        if events.sticks == 0 {
            return Self::of(m);
        }
        let tr = m.trace();
        Self {
            multipliers: [[tr, 0.0], [0.0, 0.0]],
            trace: tr,
            det: 0.0,
            stable: tr.abs() < 1.0,
        }
    }
    /// Largest multiplier modulus.
    pub fn spectral_radius(&self) -> f64 {
        self.multipliers
            .iter()
            .map(|z| z[0].hypot(z[1]))
            .fold(0.0, f64::max)
    }
    /// Fold test function 1 − tr + det = det(I − M) (zero when μ = +1).
    pub fn fold_test(&self) -> f64 {
        1.0 - self.trace + self.det
    }
    /// Flip test function 1 + tr + det = det(I + M) (zero when μ = −1).
    pub fn flip_test(&self) -> f64 {
        1.0 + self.trace + self.det
    }
    /// Neimark–Sacker test function det − 1 (meaningful with a complex pair).
    pub fn ns_test(&self) -> f64 {
        self.det - 1.0
    }
    /// True if the multipliers are a complex pair.
    pub fn complex_pair(&self) -> bool {
        self.multipliers[0][1] != 0.0
    }
}

/// A real eigenvector of the 2×2 matrix `m` for the real eigenvalue `mu` (unit length), if any.
pub fn eigenvector(m: &Matrix2<f64>, mu: f64) -> Option<[f64; 2]> {
    let a = [m[(0, 1)], mu - m[(0, 0)]];
    let b = [mu - m[(1, 1)], m[(1, 0)]];
    let na = a[0].hypot(a[1]);
    let nb = b[0].hypot(b[1]);
    let (v, n) = if na >= nb { (a, na) } else { (b, nb) };
    if n > 0.0 && n.is_finite() {
        Some([v[0] / n, v[1] / n])
    } else {
        None
    }
}

/// Options of the shooting Newton iteration.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ShootingOptions {
    /// Integrator tolerance (rtol; atol = tol·1e-3).
    pub tol: f64,
    /// Convergence: residual norm and last Newton step below this.
    pub newton_tol: f64,
    /// Largest number of Newton iterations.
    pub max_iter: usize,
}

impl Default for ShootingOptions {
    fn default() -> Self {
        Self {
            tol: 1e-11,
            newton_tol: 1e-9,
            max_iter: 30,
        }
    }
}

impl ShootingOptions {
    pub(crate) fn flow(&self, events: bool) -> FlowOptions {
        FlowOptions::with_tol(self.tol)
            .sensitivity(Sensitivity::StateAndParams)
            .record_events(events)
    }
}

/// A periodic orbit: fixed point of Pᵏ up to the winding shift, with its Floquet data.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PeriodicOrbit {
    /// State (β, ω) on the section at t = 0.
    pub x: [f64; 2],
    /// The fixed-point problem solved.
    pub spec: OrbitSpec,
    /// Floquet data of the orbit's map (of G for symmetric orbits: square the multipliers for P_T).
    pub floquet: Floquet,
    /// Events per application of the orbit's map.
    pub events: EventCounts,
    /// Final residual norm |F(x)|.
    pub residual: f64,
    /// Newton iterations used.
    pub newton_iterations: usize,
}

impl PeriodicOrbit {
    /// Multipliers of the orbit on P_T per drive period... for a G-orbit the squares of G's
    /// multipliers (P_T = R² ∘ G²); for a P_T^k orbit the multipliers of P_T^k as computed.
    pub fn stroboscopic_multipliers(&self) -> [[f64; 2]; 2] {
        match self.spec.section {
            Section::Stroboscopic => self.floquet.multipliers,
            Section::HalfPeriod => {
                let sq = |z: [f64; 2]| [z[0] * z[0] - z[1] * z[1], 2.0 * z[0] * z[1]];
                [
                    sq(self.floquet.multipliers[0]),
                    sq(self.floquet.multipliers[1]),
                ]
            }
        }
    }
}

/// Evaluates the shooting residual F(x) = Pᵏ(x) − x − (s, 0) and the map image (with Jacobians),
/// with the default integrator (the event-driven DOP853, [`DEFAULT_METHOD`]).
pub fn residual<S: DrivenOscillator + ?Sized>(
    sys: &S,
    spec: &OrbitSpec,
    x: [f64; 2],
    opts: &ShootingOptions,
    events: bool,
) -> Result<([f64; 2], MapImage)> {
    residual_with(&DEFAULT_METHOD, sys, spec, x, opts, events)
}

/// [`residual`] with the flow computed by `method`.
pub fn residual_with<S, M>(
    method: &M,
    sys: &S,
    spec: &OrbitSpec,
    x: [f64; 2],
    opts: &ShootingOptions,
    events: bool,
) -> Result<([f64; 2], MapImage)>
where
    S: DrivenOscillator + ?Sized,
    M: FlowMethod<S> + ?Sized,
{
    let s = spec.shift(sys)?;
    let img = poincare_map(
        method,
        sys,
        spec.section,
        x,
        spec.iterations,
        &opts.flow(events),
    )?;
    let r = [img.x[0] - x[0] - s, img.x[1] - x[1]];
    if !(r[0].is_finite() && r[1].is_finite()) {
        return Err(Error::NewtonFailed {
            iterations: 0,
            residual: f64::NAN,
            reason: "non-finite map image".into(),
        });
    }
    Ok((r, img))
}

/// The winding number of an advance `d` of β: round(d/2π) for an angle, 0 for a displacement.
fn winding_of<S: DrivenOscillator + ?Sized>(sys: &S, d: f64) -> f64 {
    if sys.angular() {
        (d / TAU).round()
    } else {
        0.0
    }
}

fn check_state(x: [f64; 2]) -> Result<()> {
    crate::error::finite_state("initial state", &x)
}

/// Newton shooting for a periodic orbit from the guess `x0`, with the default integrator (the
/// event-driven DOP853, [`DEFAULT_METHOD`]).
///
/// ```
/// use gearbif::model::Gear;
/// use gearbif::orbits::{shoot, OrbitSpec, ShootingOptions};
/// let gear = Gear::paper(0.0, 10.0).unwrap();
/// let lock = gear.lock_branch().unwrap().stable;
/// let guess = [lock.state[0] + 0.05, lock.state[1] - 1.0];
/// let orbit = shoot(&gear, &OrbitSpec::symmetric(1), guess, &ShootingOptions::default()).unwrap();
/// assert!((orbit.x[0] - lock.state[0]).abs() < 1e-8);
/// assert!(orbit.floquet.stable);
/// ```
pub fn shoot<S: DrivenOscillator + ?Sized>(
    sys: &S,
    spec: &OrbitSpec,
    x0: [f64; 2],
    opts: &ShootingOptions,
) -> Result<PeriodicOrbit> {
    shoot_with(&DEFAULT_METHOD, sys, spec, x0, opts)
}

/// [`shoot`] with the flow computed by `method`: Newton ([`crate::numerics::newton`], with line
/// search) on F(x) = 0 with the Jacobian Pᵏ'(x) − I.
pub fn shoot_with<S, M>(
    method: &M,
    sys: &S,
    spec: &OrbitSpec,
    x0: [f64; 2],
    opts: &ShootingOptions,
) -> Result<PeriodicOrbit>
where
    S: DrivenOscillator + ?Sized,
    M: FlowMethod<S> + ?Sized,
{
    check_state(x0)?;
    let eval = |x: &Vector2<f64>| -> Result<Linearisation<2, MapImage>> {
        let (r, img) = residual_with(method, sys, spec, [x[0], x[1]], opts, true)?;
        let jac = img.jac_x.ok_or(Error::MissingJacobian { what: "state" })?;
        Ok(Linearisation {
            residual: Vector2::from(r),
            jacobian: jac - Matrix2::identity(),
            data: img,
        })
    };
    let newton_opts = NewtonOptions {
        line_search: true,
        ..NewtonOptions::new(opts.newton_tol, opts.max_iter)
    };
    let sol = newton(
        Vector2::new(x0[0], x0[1]),
        &newton_opts,
        eval,
        |_, _| 1.0,
        "shooting",
    )?;
    let img = &sol.at.data;
    let events = EventCounts::from_image(img);
    let jac = sol.at.jacobian + Matrix2::identity();
    Ok(PeriodicOrbit {
        x: [sol.x[0], sol.x[1]],
        spec: *spec,
        floquet: Floquet::of_orbit(&jac, &events),
        events,
        residual: sol.at.residual.norm(),
        newton_iterations: sol.iterations,
    })
}

/// What a simulation settles on: period and winding on the stroboscopic section.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DetectedPeriod {
    /// The state after relaxation.
    pub x: [f64; 2],
    /// The smallest k ≤ max_period with |P_T^k(x) − x − (2πp, 0)| small.
    pub period: usize,
    /// The winding p over those k periods.
    pub winding: i32,
    /// The closing error that was accepted.
    pub closing_error: f64,
}

/// Relaxes a simulation for `relax_periods` drive periods from `x0`, then detects its period k ≤
/// `max_period` and winding on P_T (closing error below `closing_tol`), integrating at tolerance
/// `tol` with the default integrator (the event-driven DOP853, [`DEFAULT_METHOD`]).
pub fn detect_period<S: DrivenOscillator + ?Sized>(
    sys: &S,
    x0: [f64; 2],
    relax_periods: usize,
    max_period: usize,
    closing_tol: f64,
    tol: f64,
) -> Result<DetectedPeriod> {
    detect_period_with(
        &DEFAULT_METHOD,
        sys,
        x0,
        relax_periods,
        max_period,
        closing_tol,
        tol,
    )
}

/// [`detect_period`] with the flow computed by `method`. Fails with [`Error::NoPeriodDetected`].
pub fn detect_period_with<S, M>(
    method: &M,
    sys: &S,
    x0: [f64; 2],
    relax_periods: usize,
    max_period: usize,
    closing_tol: f64,
    tol: f64,
) -> Result<DetectedPeriod>
where
    S: DrivenOscillator + ?Sized,
    M: FlowMethod<S> + ?Sized,
{
    check_state(x0)?;
    let o = FlowOptions::with_tol(tol);
    let mut x = x0;
    if relax_periods > 0 {
        x = poincare_map(method, sys, Section::Stroboscopic, x, relax_periods, &o)?.x;
    }
    x[0] = sys.reduce_angle(x[0]);
    let mut y = x;
    let mut best = f64::INFINITY;
    for k in 1..=max_period {
        y = poincare_map(method, sys, Section::Stroboscopic, y, 1, &o)?.x;
        let p = winding_of(sys, y[0] - x[0]);
        let err = (y[0] - x[0] - TAU * p).hypot(y[1] - x[1]);
        best = best.min(err);
        if err < closing_tol {
            return Ok(DetectedPeriod {
                x,
                period: k,
                winding: p as i32,
                closing_error: err,
            });
        }
    }
    Err(Error::NoPeriodDetected {
        max_period,
        relax_periods,
        best_closing_error: best,
    })
}

/// Finds a periodic orbit from a simulation: relax, detect period and winding, then shoot. A period-1
/// orbit of a system with a half-period symmetry whose half-period map closes is returned as a
/// symmetric orbit (on G) when `prefer_symmetric` is set. The default integrator (the event-driven
/// DOP853, [`DEFAULT_METHOD`]) at `opts.tol`.
pub fn orbit_from_simulation<S: DrivenOscillator + ?Sized>(
    sys: &S,
    x0: [f64; 2],
    relax_periods: usize,
    max_period: usize,
    prefer_symmetric: bool,
    opts: &ShootingOptions,
) -> Result<PeriodicOrbit> {
    orbit_from_simulation_with(
        &DEFAULT_METHOD,
        sys,
        x0,
        relax_periods,
        max_period,
        prefer_symmetric,
        opts,
    )
}

/// [`orbit_from_simulation`] with the flow computed by `method`.
pub fn orbit_from_simulation_with<S, M>(
    method: &M,
    sys: &S,
    x0: [f64; 2],
    relax_periods: usize,
    max_period: usize,
    prefer_symmetric: bool,
    opts: &ShootingOptions,
) -> Result<PeriodicOrbit>
where
    S: DrivenOscillator + ?Sized,
    M: FlowMethod<S> + ?Sized,
{
    let d = detect_period_with(method, sys, x0, relax_periods, max_period, 1e-4, opts.tol)?;
    if prefer_symmetric && d.period == 1 && sys.half_period_symmetry().is_some() {
        let spec = OrbitSpec::symmetric(d.winding);
        if let Ok((r, _)) = residual_with(method, sys, &spec, d.x, opts, false) {
            if r[0].hypot(r[1]) < 1e-3 {
                if let Ok(o) = shoot_with(method, sys, &spec, d.x, opts) {
                    return Ok(o);
                }
            }
        }
    }
    shoot_with(
        method,
        sys,
        &OrbitSpec::stroboscopic(d.period, d.winding),
        d.x,
        opts,
    )
}

/// One step of a quasi-static sweep of a simulation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SweepPoint {
    /// Parameter value (set with the closure given to [`quasi_static_sweep`]).
    pub param: f64,
    /// State on P_T after relaxation.
    pub x: [f64; 2],
    /// Distance of G(x) from x + shift for winding p = round(ΔP_T/2π) (0 for a symmetric orbit).
    pub asymmetry: f64,
    /// Closing error |P_T(x) − x − (2πp, 0)|.
    pub closing: f64,
    /// Winding per period.
    pub winding: i32,
}

/// A quasi-static sweep, as in the paper: at each value the simulation continues from the last state
/// and relaxes for `relax_periods` periods; then symmetry (on G) and closing (on P_T) are measured.
/// `make` builds the system at each value. An independent check of the continuation: no Newton, no
/// Jacobians. The default integrator (the event-driven DOP853, [`DEFAULT_METHOD`]) at tolerance
/// `tol`.
pub fn quasi_static_sweep<S, F>(
    make: F,
    values: &[f64],
    x0: [f64; 2],
    relax_periods: usize,
    tol: f64,
) -> Result<Vec<SweepPoint>>
where
    S: DrivenOscillator,
    F: Fn(f64) -> Result<S>,
{
    quasi_static_sweep_with(&DEFAULT_METHOD, make, values, x0, relax_periods, tol)
}

/// [`quasi_static_sweep`] with the flow computed by `method`.
pub fn quasi_static_sweep_with<S, M, F>(
    method: &M,
    make: F,
    values: &[f64],
    x0: [f64; 2],
    relax_periods: usize,
    tol: f64,
) -> Result<Vec<SweepPoint>>
where
    S: DrivenOscillator,
    M: FlowMethod<S> + ?Sized,
    F: Fn(f64) -> Result<S>,
{
    check_state(x0)?;
    let o = FlowOptions::with_tol(tol);
    let mut x = x0;
    let mut out = Vec::with_capacity(values.len());
    for &v in values {
        let sys = make(v)?;
        x = poincare_map(method, &sys, Section::Stroboscopic, x, relax_periods, &o)?.x;
        x[0] = sys.reduce_angle(x[0]);
        let y = poincare_map(method, &sys, Section::Stroboscopic, x, 1, &o)?.x;
        let p = winding_of(&sys, y[0] - x[0]);
        let closing = (y[0] - x[0] - TAU * p).hypot(y[1] - x[1]);
        let asymmetry = match sys.half_period_symmetry() {
            Some(_) => {
                let spec = OrbitSpec::symmetric(p as i32);
                let s = spec.shift(&sys)?;
                let g = poincare_map(method, &sys, Section::HalfPeriod, x, 1, &o)?.x;
                (g[0] - x[0] - s).hypot(g[1] - x[1])
            }
            None => f64::NAN,
        };
        out.push(SweepPoint {
            param: v,
            x,
            asymmetry,
            closing,
            winding: p as i32,
        });
    }
    Ok(out)
}
