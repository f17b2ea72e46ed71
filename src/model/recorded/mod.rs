//! The augmented gear: the base model of model.md plus the catalogued extra terms, as a
//! [`DrivenOscillator`] so the exact Filippov integrator runs it (for synthetic recordings, ring-down
//! fits and short-horizon predictions).
//!
//! ```text
//! β̈ = −ζ β̇ − s (η + η_L h(α, β))
//!     + c_sc sin α cos β + c_cs cos α sin β + c_cc cos α cos β + c_ss sin α sin β   (coupling)
//!     + A sin β + B cos β + Σ_{k=2,3} (A_k sin kβ + B_k cos kβ)   (static_torque, lab-fixed)
//!     − q (|β̇|/V)^p sgn β̇                                 (power_law_drag; V = 4 rad/s)
//!     − c_r (β̇ − α̇)                                       (corotating_drag)
//!     + τ(β)                                               (a curve, [`spline`])
//! ```
//! with α(t) = α₀ + α̇ t (α̇ = 0 for a ring-down) in the coupling replaced by the input magnet's
//! true angle α + ε + χ τ_in (a drive offset ε and the quasi-static input compliance χ, with
//! τ_in = c_sc cos α sin β + c_cs sin α cos β − c_cc sin α sin β − c_ss cos α cos β the coupling
//! torque on the input per output inertia, −∂V/∂α of the coupling potential V), and h the
//! magnitude of the dipole–dipole force in units of 3 μ0 m1 m2 / (4π r⁴) ([`force_shape`]). At
//! rest (β̇ = 0) the output stays stuck while |a| ≤ η + η_L h + η_Δs, the static friction bound
//! (`static_friction`: breakaway above the sliding friction by η_Δs ≥ 0); once released it slides
//! with the friction above. The base model is c_sc = −g, c_cs = gΔ, everything else 0.

use super::{DrivenOscillator, Forces, ForcesJet};
use crate::numerics::trig::sin_cos;
use std::f64::consts::TAU;

pub mod effect;
pub mod file;
mod lens;
pub mod spline;
pub use lens::{ParamForces, RecordedModel, RecordedParam};
#[cfg(test)]
mod tests_lens;

/// A term of the sparse search beyond the catalog (an `unexplained` finding), so that it can be
/// simulated and refitted like the catalogued ones.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ExtraTerm {
    /// Unused slot.
    #[default]
    Unused,
    /// cos(kα + lβ), or sin(kα + lβ) when `sin`.
    Trig {
        /// Harmonic of α.
        k: i8,
        /// Harmonic of β.
        l: i8,
        /// Sine instead of cosine.
        sin: bool,
    },
    /// Viscous damping modulated by the angles: the term −β̇ cos(kα + lβ) (sin when `sin`).
    VelTrig {
        /// Harmonic of α.
        k: i8,
        /// Harmonic of β.
        l: i8,
        /// Sine instead of cosine.
        sin: bool,
    },
    /// Dry friction modulated by cos(kα + lβ) (sin when `sin`).
    FricTrig {
        /// Harmonic of α.
        k: i8,
        /// Harmonic of β.
        l: i8,
        /// Sine instead of cosine.
        sin: bool,
    },
}

/// A shape parameter of a catalog family: a nonlinear parameter fitted by simulation next to the
/// family's linear coefficients (its θ entry is the parameter's value itself).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Shape {
    /// Exponent p of the power-law drag −q |β̇|^p sgn β̇ (`power_law_drag`; p = 2 is the
    /// quadratic drag).
    DragExponent,
    /// Vertical component ρ_z of the shaft's weight in units of F₀ (W = −ρ_z ẑ − ρ_n n̂) in the
    /// load-dependent friction's bearing load |F + W| ([`load_shape`]; ρ_z = ρ_n = 0 is the dipole
    /// force alone).
    LoadWeight,
    /// Horizontal component ρ_n of the shaft's weight in units of F₀, along n̂ = ẑ × ê, ê the
    /// output shaft's axis ([`load_shape`]): a set-up tilted by ψ about the output shaft has
    /// (ρ_z, ρ_n) = |W|/F₀ (cos ψ, sin ψ).
    LoadSide,
    /// Width w of the Stribeck decay of the breakaway excess, Δη_s exp(−(|β̇|/w)^δ) in the
    /// sliding friction (`static_friction`; w → 0 is the excess at rest only).
    StribeckWidth,
    /// Shape δ of the Stribeck decay exp(−(|β̇|/w)^δ) (δ = 2 the Gaussian, δ = 1 the
    /// exponential decay).
    StribeckPower,
    /// Settling time τ of a `parameter_drift` that settles exponentially,
    /// (1 − e^(−u/τ))/(1 − e^(−1/τ)) with u ∈ [0, 1] from the first run to the last
    /// (the identification's regression), as a fraction of that span.
    DriftSettling,
}

impl Shape {
    /// Name of the parameter.
    pub fn name(&self) -> &'static str {
        match self {
            Shape::DragExponent => "drag_exponent",
            Shape::LoadWeight => "load_weight_vertical",
            Shape::LoadSide => "load_weight_side",
            Shape::StribeckWidth => "stribeck_width",
            Shape::StribeckPower => "stribeck_power",
            Shape::DriftSettling => "drift_settling_tau",
        }
    }
    /// Range the simulation clamps the parameter to (outside it the family member is not
    /// physical or not distinguishable from another term: p → 1 is the viscous ζ).
    pub fn range(&self) -> (f64, f64) {
        match self {
            Shape::DragExponent => (0.5, 4.0),
            Shape::LoadWeight | Shape::LoadSide => (-50.0, 50.0),
            Shape::StribeckWidth => (1e-3, 20.0),
            Shape::StribeckPower => (0.5, 4.0),
            // from a step after the first run of fifty to a drift close to linear
            Shape::DriftSettling => (0.02, 2.0),
        }
    }
}

/// Slots for [`ExtraTerm`]s in [`Coefficients::extra`] (the field is written with the literal 4).
pub const MAX_EXTRA: usize = 4;

/// Coefficients of the augmented model (per unit inertia, SI units, angles in rad).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Coefficients {
    /// ζ, s⁻¹.
    pub zeta: f64,
    /// η, s⁻².
    pub eta: f64,
    /// Coefficient of sin α cos β (base: −g).
    pub c_sc: f64,
    /// Coefficient of cos α sin β (base: gΔ).
    pub c_cs: f64,
    /// Coefficient of cos α cos β (0 in the base model).
    pub c_cc: f64,
    /// Coefficient of sin α sin β (0 in the base model).
    pub c_ss: f64,
    /// Static torque A sin β, s⁻².
    pub st_a: f64,
    /// Static torque B cos β, s⁻².
    pub st_b: f64,
    /// Static torque harmonics k = 2, 3: (A_k, B_k) of A_k sin kβ + B_k cos kβ, s⁻².
    pub st_harmonics: [(f64, f64); 2],
    /// Drag coefficient: q of −q β̇|β̇| (rad⁻¹) without an exponent, the drag at the reference
    /// speed q of −q (|β̇|/V)^p sgn β̇ (s⁻², [`drag`]) with one.
    pub quad: f64,
    /// Drag exponent p (`None`: 2, the quadratic drag), clamped to [`Shape::range`].
    pub drag_exponent: Option<f64>,
    /// Corotating drag c_r, s⁻¹.
    pub corot: f64,
    /// Load-dependent dry friction η_L, s⁻² per unit bearing load ([`load_shape`]).
    pub eta_load: f64,
    /// The shaft's weight in units of F₀ in the bearing load, (ρ_z, ρ_n) of W = −ρ_z ẑ − ρ_n n̂
    /// ([`load_shape`]; 0: the dipole force alone).
    pub load_weight: [f64; 2],
    /// Only the radial part of the bearing load (perpendicular to the output shaft) counts.
    pub load_radial: bool,
    /// Input compliance χ = I/k_in, s²: the input magnet sits at α + χ τ_in(α, β), τ_in the
    /// coupling torque on it per output inertia (solved by fixed-point iteration).
    pub compliance: f64,
    /// Offset of the true input angle from the recorded one, rad (driven runs of a stepping
    /// drive: about half a step).
    pub alpha_offset: f64,
    /// Growth of that offset per input turn since the start of the run, rad (lost steps). The
    /// integrator does not use it: the predictions evaluate it per window into `alpha_offset`.
    pub alpha_offset_per_turn: f64,
    /// Breakaway (static) friction above the sliding friction, s⁻²: an output at rest stays stuck
    /// until |a| exceeds the sliding friction plus this excess (0: static = sliding friction).
    pub eta_static_excess: f64,
    /// Width w of the Stribeck decay, rad/s: the sliding friction carries the excess as
    /// η_Δs exp(−(|β̇|/w)^δ) (0: the excess acts at rest only).
    pub stribeck_width: f64,
    /// Shape δ of the Stribeck decay (`None`: [`STRIBECK_POWER`], the Gaussian), clamped to
    /// [`Shape::range`].
    pub stribeck_power: Option<f64>,
    /// Settling time of the model's settling drift ([`Shape::DriftSettling`]), as a fraction of
    /// the session; `None`: the grid value its clock names. The drift is applied per run
    /// (by the identification's run specification), not by the simulation.
    pub drift_settling: Option<f64>,
    /// Terms of the sparse search (`unexplained`) with their coefficients.
    pub extra: [(ExtraTerm, f64); 4],
    /// Coefficients of a torque curve τ(β) = Σ c_j B_j(β) ([`spline`]), s⁻² (all zero: none;
    /// the length is [`spline::SPLINE_KNOTS`], written as a literal as for `extra`).
    pub spline_torque: [f64; 24],
    /// Coefficients of a friction curve Σ c_j B_j(β) added to the dry friction ρ
    /// ([`spline`]), s⁻² (all zero: none).
    pub spline_friction: [f64; 24],
}

/// The default shape δ of the Stribeck decay exp(−(|β̇|/w)^δ): 2, the Gaussian form of the
/// Stribeck curve (Armstrong-Hélouvry); the family fits δ by simulation
/// ([`Shape::StribeckPower`]; δ = 1 is the exponential decay).
pub const STRIBECK_POWER: f64 = 2.0;

/// x^e for x > 0: by multiplication (and one square root) when e is an integer or half an
/// integer up to 8 (the shapes held at their grid values while candidates are judged: drag
/// exponents 1.5, 2, 2.5, 3, the Gaussian Stribeck decay), else `powf`, which then dominates the
/// right-hand side. Both agree to a few ulps (unit test `pow_positive_matches_powf`).
#[inline]
pub fn pow_positive(x: f64, e: f64) -> f64 {
    let twice = 2.0 * e;
    if twice == twice.trunc() && twice.abs() <= 16.0 {
        let k = e.floor();
        let int = x.powi(k as i32);
        if e == k {
            int
        } else {
            int * x.sqrt()
        }
    } else {
        x.powf(e)
    }
}

/// The generalised Stribeck part of the sliding friction, e exp(−(|ω|/w)^δ) (δ = `power`, `None`
/// for [`STRIBECK_POWER`]), and its ω-derivative −e δ |x|^(δ−1) sgn(ω)/w · exp(−|x|^δ), x = ω/w
/// (0 for w = 0; at ω = 0 the derivative is taken as 0, the one-sided limits are ∓e/w for δ = 1
/// and unbounded for δ < 1: the stick phase there is handled by the Filippov integrator).
pub fn stribeck(excess: f64, width: f64, power: Option<f64>, omega: f64) -> (f64, f64) {
    if width <= 0.0 || excess == 0.0 {
        return (0.0, 0.0);
    }
    let (lo, hi) = Shape::StribeckWidth.range();
    let w = width.clamp(lo, hi);
    let (plo, phi) = Shape::StribeckPower.range();
    let d = power.unwrap_or(STRIBECK_POWER).clamp(plo, phi);
    let x = (omega / w).abs();
    if x == 0.0 {
        return (excess, 0.0);
    }
    let xd = pow_positive(x, d);
    let v = excess * (-xd).exp();
    (v, -d * xd / x * omega.signum() / w * v)
}

impl Coefficients {
    /// The base model with g, Δ, ζ, η.
    pub fn base(g: f64, delta: f64, zeta: f64, eta: f64) -> Self {
        Self {
            zeta,
            eta,
            c_sc: -g,
            c_cs: g * delta,
            ..Self::default()
        }
    }
    /// g = −c_sc.
    pub fn g(&self) -> f64 {
        -self.c_sc
    }
    /// Δ = c_cs / g.
    pub fn delta(&self) -> f64 {
        self.c_cs / self.g()
    }
}

/// The shaft geometry needed for the force shape h(α, β): the input and output shaft angles Θ
/// and Φ, with their sines and cosines (computed once: the load-dependent friction evaluates the
/// dipole force at every right-hand side).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Geometry {
    theta: f64,
    phi: f64,
    shafts: ShaftTrig,
}

impl Geometry {
    /// Shaft angles Θ (input) and Φ (output), rad.
    pub fn new(theta: f64, phi: f64) -> Self {
        let (st, ct) = theta.sin_cos();
        let (sp, cp) = phi.sin_cos();
        Self {
            theta,
            phi,
            shafts: ShaftTrig { st, ct, sp, cp },
        }
    }
    /// Input shaft angle Θ, rad.
    pub fn theta(&self) -> f64 {
        self.theta
    }
    /// Output shaft angle Φ, rad.
    pub fn phi(&self) -> f64 {
        self.phi
    }
}

/// F / (3 μ0 m1 m2 / (4π r⁴)): the dipole–dipole force on the output magnet for unit moments at
/// unit distance along x̂, F = (u1·x̂) u2 + (u2·x̂) u1 + (u1·u2) x̂ − 5 (u1·x̂)(u2·x̂) x̂ (shafts in
/// the horizontal x-y plane, ẑ up).
pub fn dipole_force(geo: &Geometry, alpha: f64, beta: f64) -> [f64; 3] {
    let shafts = geo.shafts;
    bilinear_force(
        shafts.input_moment(alpha.sin_cos()),
        shafts.output_moment(beta.sin_cos()),
    )
}

/// sin and cos of the shaft angles Θ and Φ, and the unit moments of the magnets they carry.
#[derive(Debug, Clone, Copy, PartialEq)]
struct ShaftTrig {
    st: f64,
    ct: f64,
    sp: f64,
    cp: f64,
}

impl ShaftTrig {
    /// u1 = (−cos α sin Θ, cos α cos Θ, sin α) from (sin α, cos α).
    fn input_moment(&self, (sa, ca): (f64, f64)) -> [f64; 3] {
        [-ca * self.st, ca * self.ct, sa]
    }
    /// u2 = (−cos β sin Φ, cos β cos Φ, sin β) from (sin β, cos β).
    fn output_moment(&self, (sb, cb): (f64, f64)) -> [f64; 3] {
        [-cb * self.sp, cb * self.cp, sb]
    }
    /// ∂u2/∂β from (sin β, cos β).
    fn output_moment_beta(&self, (sb, cb): (f64, f64)) -> [f64; 3] {
        [sb * self.sp, -sb * self.cp, cb]
    }
    /// ∂u1/∂α from (sin α, cos α).
    fn input_moment_alpha(&self, (sa, ca): (f64, f64)) -> [f64; 3] {
        [sa * self.st, -sa * self.ct, ca]
    }
}

/// The dipole force of [`dipole_force`] for the moments u1 and u2 (bilinear in them, so that
/// F(u1, ∂u2/∂β) is ∂F/∂β).
fn bilinear_force(u1: [f64; 3], u2: [f64; 3]) -> [f64; 3] {
    let d = u1[0] * u2[0] + u1[1] * u2[1] + u1[2] * u2[2];
    let mut f = [0.0; 3];
    for k in 0..3 {
        f[k] = u1[0] * u2[k] + u2[0] * u1[k];
    }
    f[0] += d - 5.0 * u1[0] * u2[0];
    f
}

/// |F| / (3 μ0 m1 m2 / (4π r⁴)): the magnitude of the dipole–dipole force ([`dipole_force`]).
pub fn force_shape(geo: &Geometry, alpha: f64, beta: f64) -> f64 {
    load_shape(geo, alpha, beta, [0.0; 2], false)
}

/// The bearing load of the load-dependent friction family in units of F₀ = 3 μ0 m1 m2/(4π r⁴):
/// |F + W| (the dipole force and the shaft's weight added as vectors), or with `radial`
/// |P(F + W)|, P the projection perpendicular to the output shaft's axis ê = (cos Φ, sin Φ, 0) (a
/// radial bearing). The weight W = −ρ_z ẑ − ρ_n n̂, `weight` = (ρ_z, ρ_n), lies in the plane
/// perpendicular to ê (n̂ = ẑ × ê = (−sin Φ, cos Φ, 0)): a set-up tilted by ψ about the output
/// shaft has (ρ_z, ρ_n) = ρ (cos ψ, sin ψ), ρ = |W|/F₀. A zero weight without projection is
/// [`force_shape`].
pub fn load_shape(geo: &Geometry, alpha: f64, beta: f64, weight: [f64; 2], radial: bool) -> f64 {
    let at = LoadPoint {
        shafts: geo.shafts,
        alpha: alpha.sin_cos(),
        beta: beta.sin_cos(),
    };
    at.load(weight, radial, false).0
}

/// The angles at which [`load_shape`] is evaluated, as sin and cos.
#[derive(Debug, Clone, Copy)]
struct LoadPoint {
    shafts: ShaftTrig,
    alpha: (f64, f64),
    beta: (f64, f64),
}

impl LoadPoint {
    /// The load |P(F + W)| of [`load_shape`] and, when `with_beta`, its β-derivative
    /// (P L)·∂F/∂β / |P L| (P a projector, W constant; 0 where the load vanishes).
    fn load(&self, weight: [f64; 2], radial: bool, with_beta: bool) -> (f64, f64) {
        let u1 = self.shafts.input_moment(self.alpha);
        let mut l = bilinear_force(u1, self.shafts.output_moment(self.beta));
        let [rz, rn] = weight;
        l[2] -= rz;
        if rn != 0.0 || radial {
            let ShaftTrig { sp, cp, .. } = self.shafts;
            l[0] += rn * sp;
            l[1] -= rn * cp;
            if radial {
                let along = l[0] * cp + l[1] * sp;
                l[0] -= along * cp;
                l[1] -= along * sp;
            }
        }
        let norm = (l[0] * l[0] + l[1] * l[1] + l[2] * l[2]).sqrt();
        if !with_beta || norm == 0.0 {
            return (norm, 0.0);
        }
        let df = bilinear_force(u1, self.shafts.output_moment_beta(self.beta));
        (norm, (l[0] * df[0] + l[1] * df[1] + l[2] * df[2]) / norm)
    }
    /// The α-derivative of the load |P(F + W)|: (P L)·∂F/∂α / |P L| (as the β-derivative of
    /// [`Self::load`], with ∂u1/∂α; 0 where the load vanishes).
    fn load_alpha(&self, weight: [f64; 2], radial: bool) -> f64 {
        let u2 = self.shafts.output_moment(self.beta);
        let mut l = bilinear_force(self.shafts.input_moment(self.alpha), u2);
        let [rz, rn] = weight;
        l[2] -= rz;
        let ShaftTrig { sp, cp, .. } = self.shafts;
        l[0] += rn * sp;
        l[1] -= rn * cp;
        let mut df = bilinear_force(self.shafts.input_moment_alpha(self.alpha), u2);
        if radial {
            for v in [&mut l, &mut df] {
                let along = v[0] * cp + v[1] * sp;
                v[0] -= along * cp;
                v[1] -= along * sp;
            }
        }
        let norm = (l[0] * l[0] + l[1] * l[1] + l[2] * l[2]).sqrt();
        if norm == 0.0 {
            return 0.0;
        }
        (l[0] * df[0] + l[1] * df[1] + l[2] * df[2]) / norm
    }
}

/// ∂/∂α of [`load_shape`] at (α, β) (the load friction's dependence on the drive phase).
pub fn load_shape_alpha(
    geo: &Geometry,
    alpha: f64,
    beta: f64,
    weight: [f64; 2],
    radial: bool,
) -> f64 {
    let at = LoadPoint {
        shafts: geo.shafts,
        alpha: alpha.sin_cos(),
        beta: beta.sin_cos(),
    };
    at.load_alpha(weight, radial)
}

/// Reference speed V of the drag family, rad/s: the family's coefficient is the drag at V,
/// −q (|β̇|/V)^p sgn β̇ (s⁻²), which keeps q and p nearly uncorrelated for output speeds of a
/// few rad/s. A power of two, so that p = 2 reproduces the quadratic drag q_old β̇|β̇| with
/// q = q_old V² bit for bit.
pub const DRAG_REFERENCE_SPEED: f64 = 4.0;

/// The drag shape and its ω-derivative: `None` (the quadratic drag) ω|ω| and 2|ω|; `Some(p)`
/// (|ω|/V)^p sgn ω and (p/V)(|ω|/V)^(p−1), V = [`DRAG_REFERENCE_SPEED`], p clamped to
/// [`Shape::range`].
pub fn drag(exponent: Option<f64>, omega: f64) -> (f64, f64) {
    match exponent {
        None => (omega * omega.abs(), 2.0 * omega.abs()),
        Some(p) => {
            let (lo, hi) = Shape::DragExponent.range();
            let p = p.clamp(lo, hi);
            let x = omega / DRAG_REFERENCE_SPEED;
            let w = x.abs();
            if w == 0.0 {
                let d0 = if p == 1.0 { 1.0 } else { 0.0 };
                return (0.0, d0 / DRAG_REFERENCE_SPEED);
            }
            let wp = pow_positive(w, p - 1.0);
            (x * wp, p * wp / DRAG_REFERENCE_SPEED)
        }
    }
}

/// The input angle's departure from a uniform drive over a prediction window: α(t) gains
/// Σ_{k=2..5} a_k (t − t_c)^k (a motor's speed ripple; zero for a uniform drive).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct InputBend {
    /// Centre t_c, s.
    pub t_c: f64,
    /// a₂ … a₅, rad/s^k.
    pub a: [f64; 4],
}

impl InputBend {
    /// Σ a_k (t − t_c)^k, rad (Horner).
    #[inline]
    pub fn angle(&self, t: f64) -> f64 {
        let s = t - self.t_c;
        let [a2, a3, a4, a5] = self.a;
        s * s * (a2 + s * (a3 + s * (a4 + s * a5)))
    }
    /// Its rate Σ k a_k (t − t_c)^(k−1), rad/s.
    #[inline]
    pub fn rate(&self, t: f64) -> f64 {
        let s = t - self.t_c;
        let [a2, a3, a4, a5] = self.a;
        s * (2.0 * a2 + s * (3.0 * a3 + s * (4.0 * a4 + s * 5.0 * a5)))
    }
}

/// cos(kα + lβ), or sin when `sin`, and its derivative with respect to the phase kα + lβ: the
/// angle harmonics of the dictionary's torques, damping and friction terms.
#[inline]
pub fn angle_harmonic(k: i8, l: i8, sin: bool, alpha: f64, beta: f64) -> (f64, f64) {
    let (sx, cx) = (k as f64 * alpha + l as f64 * beta).sin_cos();
    if sin {
        (sx, cx)
    } else {
        (cx, -sx)
    }
}

/// e^{i m x} = (cos mx, sin mx) for a small integer m from (sin x, cos x) by repeated complex
/// multiplication (de Moivre): no call of sin or cos, which dominate the right-hand side of the
/// window simulations otherwise (error a few ulps per factor for the |m| ≤ 3 of the dictionary).
#[inline]
fn cis_power(m: i8, (s, c): (f64, f64)) -> (f64, f64) {
    let (mut re, mut im) = (1.0, 0.0);
    for _ in 0..m.unsigned_abs() {
        (re, im) = (re * c - im * s, re * s + im * c);
    }
    if m < 0 {
        im = -im;
    }
    (re, im)
}

/// (sin(x + d), cos(x + d)) from (sin x, cos x): the rotation by d, with sin d and cos d from
/// their Taylor series to d⁹ and d¹⁰ where |d| ≤ 0.05 (truncation below 10⁻²¹), else from sin and
/// cos.
#[inline]
fn rotate_small((s, c): (f64, f64), d: f64) -> (f64, f64) {
    if d == 0.0 {
        return (s, c);
    }
    let (sd, cd) = if d.abs() <= 0.05 {
        let d2 = d * d;
        let sd = d * (1.0 - d2 / 6.0 * (1.0 - d2 / 20.0 * (1.0 - d2 / 42.0 * (1.0 - d2 / 72.0))));
        let cd = 1.0
            - d2 / 2.0
                * (1.0 - d2 / 12.0 * (1.0 - d2 / 30.0 * (1.0 - d2 / 56.0 * (1.0 - d2 / 90.0))));
        (sd, cd)
    } else {
        sin_cos(d)
    };
    (s * cd + c * sd, c * cd - s * sd)
}

/// [`angle_harmonic`] from (sin α, cos α) and (sin β, cos β): e^{i(kα + lβ)} = e^{ikα} e^{ilβ}
/// ([`cis_power`]).
#[inline]
pub fn angle_harmonic_sc(
    k: i8,
    l: i8,
    sin: bool,
    sc_alpha: (f64, f64),
    sc_beta: (f64, f64),
) -> (f64, f64) {
    let (ca, sa) = cis_power(k, sc_alpha);
    let (cb, sb) = cis_power(l, sc_beta);
    let (cx, sx) = (ca * cb - sa * sb, sa * cb + ca * sb);
    if sin {
        (sx, cx)
    } else {
        (cx, -sx)
    }
}

/// An angle, rad, with its (sine, cosine): the right-hand side computes them once.
type AngleSc = (f64, (f64, f64));

/// The augmented gear as a driven oscillator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RecordedGear {
    /// Coefficients.
    pub c: Coefficients,
    /// Geometry (for the force shape).
    pub geo: Geometry,
    /// α at t = 0, rad.
    pub alpha0: f64,
    /// α̇, rad/s (0: locked input).
    pub alpha_rate: f64,
    /// The input's departure from the uniform drive α0 + α̇ t.
    pub bend: InputBend,
}

impl RecordedGear {
    /// α(t) = α0 + α̇ t + the bend.
    #[inline]
    pub fn alpha(&self, t: f64) -> f64 {
        self.alpha0 + self.alpha_rate * t + self.bend.angle(t)
    }
    /// The corotating drag's correction for the bend: −c(β̇ − α̇(t)) where the smooth part has
    /// −c(β̇ − α̇) with the uniform rate.
    #[inline]
    fn corot_bend(&self, t: f64) -> f64 {
        if self.c.corot == 0.0 {
            0.0
        } else {
            self.c.corot * self.bend.rate(t)
        }
    }
    /// The input magnet's angle α_in = α + ε + χ τ_in(α_in, β) (Newton iteration) and its
    /// derivative dα_in/dβ = χ τ_β / (1 − χ τ_α).
    pub fn input_angle(&self, alpha: f64, beta: f64) -> (f64, f64) {
        let (a, da, _) = self.input_angle_sc(alpha, sin_cos(alpha), sin_cos(beta));
        (a, da)
    }
    /// [`Self::input_angle`] with (sin α, cos α) and (sin β, cos β) given (the right-hand side
    /// has them), and (sin, cos) of the input magnet's angle. No sine or cosine of its own: α + ε
    /// is α rotated by the (small) offset ε, and the Newton iterates differ from α + ε by the
    /// small twist δ = χ τ_in; both rotations by their Taylor series ([`rotate_small`]).
    fn input_angle_sc(
        &self,
        alpha: f64,
        sc_alpha: (f64, f64),
        (sb, cb): (f64, f64),
    ) -> (f64, f64, (f64, f64)) {
        let c = &self.c;
        let a0 = alpha + c.alpha_offset;
        let sc0 = rotate_small(sc_alpha, c.alpha_offset);
        if c.compliance == 0.0 {
            return (a0, 0.0, sc0);
        }
        // τ_in and its partial derivatives at the input angle a0 + δ
        let tau = |d: f64| {
            let (sa, ca) = rotate_small(sc0, d);
            (
                c.c_sc * ca * sb + c.c_cs * sa * cb - c.c_cc * sa * sb - c.c_ss * ca * cb,
                -c.c_sc * sa * sb + c.c_cs * ca * cb - c.c_cc * ca * sb + c.c_ss * sa * cb,
                c.c_sc * ca * cb - c.c_cs * sa * sb - c.c_cc * sa * cb + c.c_ss * ca * sb,
                (sa, ca),
            )
        };
        let mut d = c.compliance * tau(0.0).0;
        for _ in 0..3 {
            let (t, ta, _, _) = tau(d);
            d -= (d - c.compliance * t) / (1.0 - c.compliance * ta);
        }
        let (_, ta, tb, sc) = tau(d);
        (a0 + d, c.compliance * tb / (1.0 - c.compliance * ta), sc)
    }
    /// a, ∂a/∂β, ∂a/∂ω at the recorded input angle `alpha` (`sc_alpha` = (sin α, cos α)) and
    /// β given with (sin β, cos β).
    fn smooth(
        &self,
        alpha: f64,
        sc_alpha: (f64, f64),
        (beta, sc_beta): AngleSc,
        omega: f64,
    ) -> (f64, f64, f64) {
        let (_, da_dbeta, sc_in) = self.input_angle_sc(alpha, sc_alpha, sc_beta);
        let (a, a_beta, a_omega, a_alpha) = self.smooth_at(sc_in, (beta, sc_beta), omega);
        (a, a_beta + a_alpha * da_dbeta, a_omega)
    }
    /// a, ∂a/∂β, ∂a/∂ω, ∂a/∂α at the input angle α given by its sine and cosine and β given by
    /// itself with its sine and cosine.
    fn smooth_at(
        &self,
        (sa, ca): (f64, f64),
        (beta, (sb, cb)): AngleSc,
        omega: f64,
    ) -> (f64, f64, f64, f64) {
        let c = &self.c;
        let a = -c.zeta * omega
            + c.c_sc * sa * cb
            + c.c_cs * ca * sb
            + c.c_cc * ca * cb
            + c.c_ss * sa * sb
            + c.st_a * sb
            + c.st_b * cb
            - c.corot * (omega - self.alpha_rate);
        let a_beta = -c.c_sc * sa * sb + c.c_cs * ca * cb - c.c_cc * ca * sb
            + c.c_ss * sa * cb
            + c.st_a * cb
            - c.st_b * sb;
        let a_omega = -c.zeta - c.corot;
        let a_alpha = c.c_sc * ca * cb - c.c_cs * sa * sb - c.c_cc * sa * cb + c.c_ss * ca * sb;
        let (mut a, mut a_beta, mut a_omega, mut a_alpha) = (a, a_beta, a_omega, a_alpha);
        if c.quad != 0.0 {
            let (d, d_omega) = drag(c.drag_exponent, omega);
            a -= c.quad * d;
            a_omega -= c.quad * d_omega;
        }
        for (k, &(ak, bk)) in c.st_harmonics.iter().enumerate() {
            if ak != 0.0 || bk != 0.0 {
                let m = (k + 2) as f64;
                let (co, s) = cis_power(k as i8 + 2, (sb, cb));
                a += ak * s + bk * co;
                a_beta += m * (ak * co - bk * s);
            }
        }
        if spline::active(&c.spline_torque) {
            let (v, d) = spline::eval(&c.spline_torque, beta);
            a += v;
            a_beta += d;
        }
        for &(term, th) in &c.extra {
            if th == 0.0 {
                continue;
            }
            match term {
                ExtraTerm::Trig { k, l, sin } => {
                    let (v, d) = angle_harmonic_sc(k, l, sin, (sa, ca), (sb, cb));
                    a += th * v;
                    a_beta += th * l as f64 * d;
                    a_alpha += th * k as f64 * d;
                }
                ExtraTerm::VelTrig { k, l, sin } => {
                    let (v, d) = angle_harmonic_sc(k, l, sin, (sa, ca), (sb, cb));
                    a -= th * omega * v;
                    a_beta -= th * omega * l as f64 * d;
                    a_alpha -= th * omega * k as f64 * d;
                    a_omega -= th * v;
                }
                ExtraTerm::FricTrig { .. } | ExtraTerm::Unused => {}
            }
        }
        (a, a_beta, a_omega, a_alpha)
    }
    /// The dry friction before its floor, ρ = η + η_L L(α, β) + Σ θ_k (friction harmonics: cos β,
    /// sin β, cos or sin(kα + lβ)) + Σ c_j B_j(β) (a friction curve, [`spline`]) at (α, β), and, when `with_beta`, ∂ρ/∂β (the friction is
    /// max(ρ, 0), [`Self::floored_friction`]); L the bearing load of [`load_shape`] (the `load_dependent_friction`
    /// family of docs/diagnosis.md, "The catalog as families"). α is the recorded input angle,
    /// not the input magnet's (the coupling's, [`Self::input_angle`]). β is given with (sin β,
    /// cos β); `sc_alpha` = (sin α, cos α) when the caller has it.
    fn friction(
        &self,
        alpha: f64,
        (beta, sc_beta): AngleSc,
        sc_alpha: Option<(f64, f64)>,
        with_beta: bool,
    ) -> (f64, f64) {
        let (mut r, mut r_beta) = (self.c.eta, 0.0);
        let mut sc_alpha = sc_alpha;
        let mut sc_alpha = || *sc_alpha.get_or_insert_with(|| sin_cos(alpha));
        if self.c.eta_load != 0.0 {
            let (lo, hi) = Shape::LoadWeight.range();
            let w = self.c.load_weight.map(|x| x.clamp(lo, hi));
            let at = LoadPoint {
                shafts: self.geo.shafts,
                alpha: sc_alpha(),
                beta: sc_beta,
            };
            let (h, h_beta) = at.load(w, self.c.load_radial, with_beta);
            r += self.c.eta_load * h;
            r_beta += self.c.eta_load * h_beta;
        }
        for &(term, th) in &self.c.extra {
            if let ExtraTerm::FricTrig { k, l, sin } = term {
                let (v, d) = angle_harmonic_sc(k, l, sin, sc_alpha(), sc_beta);
                r += th * v;
                r_beta += th * l as f64 * d;
            }
        }
        if spline::active(&self.c.spline_friction) {
            let (v, d) = spline::eval(&self.c.spline_friction, beta);
            r += v;
            r_beta += d;
        }
        (r, r_beta)
    }
    /// Whether the friction ρ of [`Self::friction`] varies with the angles (a load or friction
    /// harmonics): only then can its floor at 0 switch within a slip phase.
    fn friction_varies(&self) -> bool {
        self.c.eta_load != 0.0
            || spline::active(&self.c.spline_friction)
            || self
                .c
                .extra
                .iter()
                .any(|&(term, th)| th != 0.0 && matches!(term, ExtraTerm::FricTrig { .. }))
    }
    /// The friction r and ∂r/∂β: ρ of [`Self::friction`] floored at 0 (`held`: `None`), or on a
    /// held branch of the floor (`Some(true)`: 0; `Some(false)`: ρ itself, also where negative),
    /// plus the Stribeck part.
    fn floored_friction(
        &self,
        alpha: f64,
        omega: f64,
        sc: (AngleSc, Option<(f64, f64)>),
        with_beta: bool,
        held: Option<bool>,
    ) -> (f64, f64, f64) {
        let (sv, sv_omega) = self.stribeck_part(omega);
        if held == Some(true) {
            return (sv, 0.0, sv_omega);
        }
        let (rho, rho_beta) = self.friction(alpha, sc.0, sc.1, with_beta);
        match held {
            Some(_) => (rho + sv, rho_beta, sv_omega),
            None if rho > 0.0 => ((rho + sv).max(0.0), rho_beta, sv_omega),
            None => (sv.max(0.0), 0.0, sv_omega),
        }
    }
    /// [`DrivenOscillator::forces`] on the branch `held` ([`Self::floored_friction`]).
    fn forces_on(&self, t: f64, beta: f64, omega: f64, held: Option<bool>) -> Forces {
        let al = self.alpha(t);
        let (sc_alpha, sc_beta) = (sin_cos(al), sin_cos(beta));
        let (a, _, _) = self.smooth(al, sc_alpha, (beta, sc_beta), omega);
        let (r, _, _) =
            self.floored_friction(al, omega, ((beta, sc_beta), Some(sc_alpha)), false, held);
        Forces {
            a: a + self.corot_bend(t),
            r,
        }
    }
    /// [`DrivenOscillator::forces_jet`] on the branch `held` ([`Self::floored_friction`]).
    fn forces_jet_on(&self, t: f64, beta: f64, omega: f64, held: Option<bool>) -> ForcesJet {
        let al = self.alpha(t);
        let (sc_alpha, sc_beta) = (sin_cos(al), sin_cos(beta));
        let (a, a_beta, a_omega) = self.smooth(al, sc_alpha, (beta, sc_beta), omega);
        let (r, r_beta, r_omega) =
            self.floored_friction(al, omega, ((beta, sc_beta), Some(sc_alpha)), true, held);
        let mut j = ForcesJet::new(a + self.corot_bend(t), r);
        j.a_beta = a_beta;
        j.a_omega = a_omega;
        j.r_omega = r_omega;
        j.r_beta = r_beta;
        j
    }
    /// The Stribeck part of the sliding friction ([`stribeck`]) at ω.
    fn stribeck_part(&self, omega: f64) -> (f64, f64) {
        stribeck(
            self.c.eta_static_excess.max(0.0),
            self.c.stribeck_width,
            self.c.stribeck_power,
            omega,
        )
    }
}

impl DrivenOscillator for RecordedGear {
    fn period(&self) -> f64 {
        if self.alpha_rate.abs() > 1e-12 {
            TAU / self.alpha_rate.abs()
        } else {
            1.0
        }
    }
    fn forces(&self, t: f64, beta: f64, omega: f64) -> Forces {
        self.forces_on(t, beta, omega, None)
    }
    fn forces_jet(&self, t: f64, beta: f64, omega: f64, _params: bool) -> ForcesJet {
        self.forces_jet_on(t, beta, omega, None)
    }
    fn friction_floor(&self, t: f64, beta: f64, _omega: f64) -> Option<f64> {
        self.friction_varies().then(|| {
            self.friction(self.alpha(t), (beta, sin_cos(beta)), None, false)
                .0
        })
    }
    fn forces_held(&self, t: f64, beta: f64, omega: f64, floored: bool) -> Forces {
        self.forces_on(t, beta, omega, Some(floored))
    }
    fn forces_jet_held(
        &self,
        t: f64,
        beta: f64,
        omega: f64,
        _params: bool,
        floored: bool,
    ) -> ForcesJet {
        self.forces_jet_on(t, beta, omega, Some(floored))
    }
    /// With the input at rest (α̇ = 0 and no bend: a ring-down) the forces do not depend on t, so
    /// the release function G = |a(β, 0)| − r_s(β) of a stuck output is constant: it slips at once
    /// or stays stuck through `t_max`. Otherwise the generic scan and bisection
    /// ([`crate::model::default_next_release`]).
    fn next_release(&self, t: f64, beta: f64, t_max: f64) -> Option<f64> {
        if self.alpha_rate == 0.0 && self.bend.a == [0.0; 4] {
            return (crate::model::release_function(self, t, beta) >= 0.0).then_some(t);
        }
        crate::model::default_next_release(self, t, beta, t_max)
    }
    fn static_friction(&self, t: f64, beta: f64) -> f64 {
        let al = self.alpha(t);
        let (fr, _) = self.friction(al, (beta, sin_cos(beta)), None, false);
        fr.max(0.0) + self.c.eta_static_excess.max(0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rotation by a small angle is sin and cos of the sum, on both sides of the switch to
    /// the library functions.
    #[test]
    fn small_rotation_matches_sin_and_cos() {
        for x in [0.3, -2.1, 7.9] {
            for d in [1e-9, -3e-4, 0.01, -0.049, 0.05, 0.051, -0.7] {
                let (s, c) = rotate_small(f64::sin_cos(x), d);
                assert!((s - (x + d).sin()).abs() < 1e-15, "{x} {d}");
                assert!((c - (x + d).cos()).abs() < 1e-15, "{x} {d}");
            }
        }
    }

    /// Powers by multiplication agree with `powf` to a few ulps, at integer and half-integer
    /// exponents (of either sign) and elsewhere.
    #[test]
    fn pow_positive_matches_powf() {
        for e in [
            -1.5, -1.0, 0.0, 0.2, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 7.5, 8.0, 8.5, 9.0,
        ] {
            for x in [1e-9, 0.013, 0.37, 1.0, 1.9, 4.2, 77.0] {
                let (a, b) = (pow_positive(x, e), x.powf(e));
                assert!((a - b).abs() <= 8.0 * f64::EPSILON * b, "{x}^{e}: {a} {b}");
            }
        }
    }

    /// The product form of the angle harmonics is the harmonic itself (every (k, l) of the
    /// dictionary and beyond, value and phase derivative).
    #[test]
    fn harmonics_by_products_match_sin_and_cos() {
        for (alpha, beta) in [(0.3, -2.1), (5.9, 1.7), (-11.2, 40.3)] {
            let (sca, scb) = (f64::sin_cos(alpha), f64::sin_cos(beta));
            for k in -3..=3 {
                for l in -3..=3 {
                    for sin in [false, true] {
                        let want = angle_harmonic(k, l, sin, alpha, beta);
                        let got = angle_harmonic_sc(k, l, sin, sca, scb);
                        assert!((want.0 - got.0).abs() < 1e-13, "{k} {l} {sin}");
                        assert!((want.1 - got.1).abs() < 1e-13, "{k} {l} {sin}");
                    }
                }
            }
        }
    }
    #[test]
    fn force_shape_is_symmetric_and_positive() {
        let geo = Geometry::new(0.5, 0.4);
        for k in 0..20 {
            let (a, b) = (0.3 * k as f64, 1.1 - 0.2 * k as f64);
            let h = force_shape(&geo, a, b);
            assert!((0.0..=5.0).contains(&h));
            // (α, β) → (α + π, β + π) flips both moments: F unchanged
            let h2 = force_shape(&geo, a + std::f64::consts::PI, b + std::f64::consts::PI);
            assert!((h - h2).abs() < 1e-12);
        }
    }

    /// The jet's ∂a/∂β and ∂a/∂ω against central differences of the forces (step 1e-6).
    fn assert_jet_matches_differences(sys: &RecordedGear, t: f64, b: f64, w: f64) {
        let j = sys.forces_jet(t, b, w, false);
        let h = 1e-6;
        let fb = (sys.forces(t, b + h, w).a - sys.forces(t, b - h, w).a) / (2.0 * h);
        let fw = (sys.forces(t, b, w + h).a - sys.forces(t, b, w - h).a) / (2.0 * h);
        assert!(
            (j.a_beta - fb).abs() < 1e-6 * (1.0 + fb.abs()),
            "{} {fb}",
            j.a_beta
        );
        assert!(
            (j.a_omega - fw).abs() < 1e-6 * (1.0 + fw.abs()),
            "{} {fw}",
            j.a_omega
        );
    }

    /// A driven test system: Θ = Φ = 0.5 rad, α = 0.3 + 4t.
    fn driven_test_gear(c: Coefficients) -> RecordedGear {
        RecordedGear {
            c,
            geo: Geometry::new(0.5, 0.5),
            alpha0: 0.3,
            alpha_rate: 4.0,
            bend: InputBend::default(),
        }
    }

    /// With the input at rest the release search answers at once, and as the generic scan over
    /// the whole interval does: stuck states stay stuck, the others slip at t (a friction curve
    /// and a static torque make the release depend on β).
    #[test]
    fn a_ring_down_releases_at_once_or_never_as_the_scan_finds() {
        let mut c = Coefficients::base(300.0, 0.2, 1.0, 40.0);
        c.st_a = 6.0;
        for j in 0..spline::SPLINE_KNOTS {
            c.spline_friction[j] = 30.0 + 20.0 * (j as f64 * 0.9).sin();
        }
        let sys = RecordedGear {
            alpha_rate: 0.0,
            ..driven_test_gear(c)
        };
        let (mut stuck, mut slips) = (0, 0);
        for k in 0..40 {
            let (t, b) = (0.05 * k as f64, 0.3 + 0.157 * k as f64);
            let fast = sys.next_release(t, b, t + 2.0);
            assert_eq!(
                fast,
                crate::model::default_next_release(&sys, t, b, t + 2.0)
            );
            if fast.is_some() {
                slips += 1;
            } else {
                stuck += 1;
            }
        }
        assert!(stuck > 0 && slips > 0, "{stuck} stuck, {slips} slipping");
    }

    #[test]
    fn compliant_input_solves_its_equilibrium_and_the_jacobian_matches() {
        let mut c = Coefficients::base(300.0, 0.2, 1.0, 20.0);
        c.compliance = 2f64.to_radians() / 300.0;
        c.c_cc = 7.0;
        let sys = driven_test_gear(c);
        for k in 0..12 {
            let (t, b) = (0.13 * k as f64, 0.7 * k as f64 - 2.0);
            let al = sys.alpha(t);
            let (a_in, _) = sys.input_angle(al, b);
            let (sa, ca) = a_in.sin_cos();
            let (sb, cb) = b.sin_cos();
            let tau = c.c_sc * ca * sb + c.c_cs * sa * cb - c.c_cc * sa * sb - c.c_ss * ca * cb;
            assert!((a_in - al - c.compliance * tau).abs() < 1e-14);
            let j = sys.forces_jet(t, b, 0.4, false);
            let h = 1e-6;
            let fd = (sys.forces(t, b + h, 0.4).a - sys.forces(t, b - h, 0.4).a) / (2.0 * h);
            assert!(
                (j.a_beta - fd).abs() < 1e-6 * (1.0 + fd.abs()),
                "{} {}",
                j.a_beta,
                fd
            );
        }
    }

    /// With a breakaway excess the event-driven integrator keeps a stuck output at rest until
    /// |a| reaches η + η_Δs (not η), and the output leaves with the acceleration jump η_Δs.
    #[test]
    fn static_friction_delays_the_release_to_the_breakaway_bound() {
        use crate::integrator::{EventDriven, EventKind, FlowMethod, FlowOptions};
        use crate::model::release_function;
        let base = Coefficients::base(310.0, 0.18, 1.1, 23.0);
        let geo = Geometry::new(0.5, 0.5);
        let release = |excess: f64| -> (f64, RecordedGear) {
            let sys = RecordedGear {
                c: Coefficients {
                    eta_static_excess: excess,
                    ..base
                },
                geo,
                alpha0: 0.0,
                alpha_rate: TAU * 0.5,
                bend: InputBend::default(),
            };
            // at rest at β = 0.3 with α = 0: a = gΔ·cos 0·sin 0.3 ≈ 16.5 < η, stuck
            let opts = FlowOptions::with_tol(1e-10).record_events(true);
            let f = EventDriven.flow(&sys, 0.0, [0.3, 0.0], 0.5, &opts).unwrap();
            let ev = f
                .events
                .iter()
                .find(|e| matches!(e.kind, EventKind::Release { .. }))
                .expect("a release");
            assert_eq!(ev.beta, 0.3);
            (ev.t, sys)
        };
        let (t0, s0) = release(0.0);
        let (t1, s1) = release(11.5);
        // the static bound of the model and the release function
        assert!((s1.static_friction(t1, 0.3) - (23.0 + 11.5)).abs() < 1e-12);
        assert!(release_function(&s0, t0, 0.3).abs() < 1e-9);
        assert!(release_function(&s1, t1, 0.3).abs() < 1e-9);
        let a1 = s1.forces(t1, 0.3, 0.0).a.abs();
        assert!((a1 - 34.5).abs() < 1e-9, "|a| at release {a1}");
        assert!(t1 > t0 + 1e-3, "release {t1} not later than {t0}");
    }

    #[test]
    fn extra_terms_have_consistent_jacobians() {
        let mut c = Coefficients::base(300.0, 0.2, 1.0, 20.0);
        c.extra = [
            (
                ExtraTerm::Trig {
                    k: 2,
                    l: -1,
                    sin: true,
                },
                3.0,
            ),
            (
                ExtraTerm::Trig {
                    k: 0,
                    l: 2,
                    sin: false,
                },
                -2.0,
            ),
            (
                ExtraTerm::VelTrig {
                    k: 0,
                    l: 1,
                    sin: false,
                },
                0.4,
            ),
            (
                ExtraTerm::VelTrig {
                    k: 2,
                    l: -2,
                    sin: true,
                },
                -0.3,
            ),
        ];
        let sys = driven_test_gear(c);
        for k in 0..10 {
            let (t, b, w) = (0.17 * k as f64, 0.9 * k as f64 - 3.0, 2.0 - 0.5 * k as f64);
            assert_jet_matches_differences(&sys, t, b, w);
        }
        // friction modulated by cos β: r = η + θ cos β, with its β-derivative
        let mut c2 = c;
        c2.extra = [
            (
                ExtraTerm::FricTrig {
                    k: 0,
                    l: 1,
                    sin: false,
                },
                2.0,
            ),
            Default::default(),
            Default::default(),
            Default::default(),
        ];
        let s2 = RecordedGear { c: c2, ..sys };
        let j = s2.forces_jet(0.1, 0.7, 1.0, false);
        assert!((j.r - (20.0 + 2.0 * 0.7f64.cos())).abs() < 1e-12);
        assert!((j.r_beta + 2.0 * 0.7f64.sin()).abs() < 1e-6);
    }

    /// The curves in β: the torque curve's value and β-derivative in the smooth force, the
    /// friction curve's in the friction (against the spline's own evaluation and central
    /// differences), a zero curve leaving the forces unchanged.
    #[test]
    fn spline_curves_enter_the_forces_with_their_derivatives() {
        let base = Coefficients::base(300.0, 0.2, 1.0, 20.0);
        let mut c = base;
        for j in 0..spline::SPLINE_KNOTS {
            c.spline_torque[j] = (j as f64 * 0.7).sin() * 3.0;
            c.spline_friction[j] = 2.0 + (j as f64 * 1.3).cos();
        }
        let (sys, plain) = (driven_test_gear(c), driven_test_gear(base));
        for k in 0..12 {
            let (t, b, w) = (0.13 * k as f64, 0.77 * k as f64 - 4.0, 1.5 - 0.3 * k as f64);
            assert_jet_matches_differences(&sys, t, b, w);
            let (tau, _) = spline::eval(&c.spline_torque, b);
            let (m, dm) = spline::eval(&c.spline_friction, b);
            let (f, f0) = (sys.forces(t, b, w), plain.forces(t, b, w));
            assert!((f.a - f0.a - tau).abs() < 1e-10, "{k}");
            let j = sys.forces_jet(t, b, w, false);
            assert!((j.r - (20.0 + m)).abs() < 1e-10, "{k}");
            assert!((j.r_beta - dm).abs() < 1e-10, "{k}");
        }
    }

    /// The gear without its floor's switching function: the integrator steps across the kinks
    /// of the floored friction as over any non-smooth point, by rejecting steps.
    struct Unheld(RecordedGear);

    impl DrivenOscillator for Unheld {
        fn period(&self) -> f64 {
            self.0.period()
        }
        fn forces(&self, t: f64, beta: f64, omega: f64) -> Forces {
            self.0.forces(t, beta, omega)
        }
        fn forces_jet(&self, t: f64, beta: f64, omega: f64, params: bool) -> ForcesJet {
            self.0.forces_jet(t, beta, omega, params)
        }
        fn static_friction(&self, t: f64, beta: f64) -> f64 {
            self.0.static_friction(t, beta)
        }
    }

    #[test]
    fn floor_switches_are_located_and_the_flow_and_its_jacobian_agree() {
        use crate::integrator::{
            EventDriven, EventDriven853, FlowMethod, FlowOptions, Sensitivity,
        };
        // a friction harmonic larger than η: the friction is floored at 0 over part of every
        // half turn of β (a driven window of 3.9 s in which β turns 10.4 times: 46 switches)
        let mut c = Coefficients::base(300.0, 0.2, 1.0, 20.0);
        c.extra[0] = (
            ExtraTerm::FricTrig {
                k: 0,
                l: 2,
                sin: true,
            },
            30.0,
        );
        let sys = RecordedGear {
            alpha_rate: 20.0,
            bend: InputBend::default(),
            ..driven_test_gear(c)
        };
        let (x0, t1) = ([0.3, 20.0], 3.9);
        let flow = |s: &dyn Fn(&FlowOptions) -> crate::integrator::Flow, tol: f64, sens| {
            s(&FlowOptions::with_tol(tol).sensitivity(sens))
        };
        let held = |o: &FlowOptions| EventDriven853.flow(&sys, 0.0, x0, t1, o).unwrap();
        let unheld = |o: &FlowOptions| EventDriven853.flow(&Unheld(sys), 0.0, x0, t1, o).unwrap();
        // the two ways agree at a tight tolerance, and at the default one with the error of
        // the tolerance
        let reference = flow(&unheld, 1e-13, Sensitivity::None);
        let tight = flow(&held, 1e-13, Sensitivity::None);
        for i in 0..2 {
            assert!((tight.x[i] - reference.x[i]).abs() < 5e-10 * (1.0 + reference.x[i].abs()));
        }
        let (a, b) = (
            flow(&held, 1e-8, Sensitivity::State),
            flow(&unheld, 1e-8, Sensitivity::State),
        );
        for f in [&a, &b] {
            for i in 0..2 {
                assert!((f.x[i] - reference.x[i]).abs() < 1e-7 * (1.0 + reference.x[i].abs()));
            }
        }
        // far fewer steps (468 against 1901 tried): the kinks no longer reject steps over and over
        let cost = |f: &crate::integrator::Flow| f.stats.steps + f.stats.rejected;
        eprintln!("located: {:?}; stepped across: {:?}", a.stats, b.stats);
        assert!(3 * cost(&a) < cost(&b), "{:?} vs {:?}", a.stats, b.stats);
        // the samples on the continuous extension, and the DP5 pair (its last stage is the
        // solution, no extra dense stages): the same flow
        let times: Vec<f64> = (0..390).map(|k| k as f64 * 0.01).collect();
        let (sa, sr) = (
            held(&FlowOptions::with_tol(1e-8).samples(times.clone())),
            unheld(&FlowOptions::with_tol(1e-13).samples(times.clone())),
        );
        assert_eq!(sa.samples.len(), times.len());
        // the window does cross the floor: sign changes of ρ between the samples (10 ms apart,
        // several per switch interval)
        let rho = |p: &crate::integrator::Sample| sys.friction_floor(p.t, p.beta, p.omega);
        let switches = sr
            .samples
            .windows(2)
            .filter(|w| (rho(&w[0]).unwrap() > 0.0) != (rho(&w[1]).unwrap() > 0.0))
            .count();
        eprintln!("switches of the floor between samples: {switches}");
        assert!(switches >= 40, "{switches}");
        for (p, q) in sa.samples.iter().zip(&sr.samples) {
            assert!(
                (p.beta - q.beta).abs() < 1e-7 * (1.0 + q.beta.abs()),
                "{p:?} {q:?}"
            );
        }
        let dp5 = EventDriven
            .flow(&sys, 0.0, x0, t1, &FlowOptions::with_tol(1e-10))
            .unwrap();
        for i in 0..2 {
            assert!((dp5.x[i] - reference.x[i]).abs() < 1e-7 * (1.0 + reference.x[i].abs()));
        }
        // the state Jacobian against central differences of the held flow
        let jx = a.jac_x.unwrap();
        for j in 0..2 {
            let h = 1e-6 * (1.0 + x0[j].abs());
            let mut xp = x0;
            let mut xm = x0;
            xp[j] += h;
            xm[j] -= h;
            let o = FlowOptions::with_tol(1e-12);
            let fp = EventDriven853.flow(&sys, 0.0, xp, t1, &o).unwrap();
            let fm = EventDriven853.flow(&sys, 0.0, xm, t1, &o).unwrap();
            for i in 0..2 {
                let d = (fp.x[i] - fm.x[i]) / (2.0 * h);
                assert!(
                    (jx[(i, j)] - d).abs() < 1e-6 * (1.0 + d.abs()),
                    "{i}{j}: {} {d}",
                    jx[(i, j)]
                );
            }
        }
    }

    /// The friction's ∂r/∂β (analytic: the load's (P L)·∂F/∂β / |P L| and the harmonics'
    /// derivatives) against central differences of r, for every member of the load family
    /// (vertical, tilted and no weight; total and radial load) with friction harmonics on top.
    #[test]
    fn friction_beta_derivative_matches_differences() {
        let mut c = Coefficients::base(300.0, 0.2, 1.0, 20.0);
        c.eta_load = 6.0;
        c.extra = [
            (
                ExtraTerm::FricTrig {
                    k: 0,
                    l: 1,
                    sin: true,
                },
                -1.5,
            ),
            (
                ExtraTerm::FricTrig {
                    k: 1,
                    l: -2,
                    sin: false,
                },
                0.8,
            ),
            (
                ExtraTerm::FricTrig {
                    k: 0,
                    l: 1,
                    sin: false,
                },
                1.1,
            ),
            (
                ExtraTerm::FricTrig {
                    k: 2,
                    l: 3,
                    sin: true,
                },
                -0.6,
            ),
        ];
        let h = 1e-6;
        let members = [
            ([0.0, 0.0], false, 0.0),
            ([0.0, 0.0], true, 0.0),
            ([2.2, 0.0], false, 0.0),
            ([2.2, 0.0], true, 0.0),
            ([1.4, -0.9], false, 0.0),
            ([0.6, 1.7], true, 0.0),
            // an input offset: the coupling's input angle is not the friction's α
            ([1.4, -0.9], true, 0.2),
        ];
        for (weight, radial, offset) in members {
            let sys = driven_test_gear(Coefficients {
                load_weight: weight,
                load_radial: radial,
                alpha_offset: offset,
                ..c
            });
            for k in 0..15 {
                let (t, b) = (0.19 * k as f64, 0.83 * k as f64 - 4.0);
                let j = sys.forces_jet(t, b, 1.0, false);
                let fd = (sys.forces(t, b + h, 1.0).r - sys.forces(t, b - h, 1.0).r) / (2.0 * h);
                assert!(
                    (j.r_beta - fd).abs() < 1e-7 * (1.0 + fd.abs()),
                    "{weight:?} {radial} {offset}: {} vs {fd}",
                    j.r_beta
                );
            }
        }
        // the floor: a friction that would be negative is zero, and so is its derivative
        let floored = driven_test_gear(Coefficients { eta: -50.0, ..c });
        let j = floored.forces_jet(0.3, 0.7, 1.0, false);
        assert_eq!((j.r, j.r_beta), (0.0, 0.0));
    }

    /// The drag family's member p = 2 is the quadratic drag exactly (bit for bit); other
    /// exponents and the torque harmonics have Jacobians that match central differences.
    #[test]
    fn drag_family_and_torque_harmonics() {
        let mut c = Coefficients::base(300.0, 0.2, 1.0, 20.0);
        c.quad = 0.03;
        let quad = driven_test_gear(c);
        let v2 = DRAG_REFERENCE_SPEED * DRAG_REFERENCE_SPEED;
        let two = driven_test_gear(Coefficients {
            drag_exponent: Some(2.0),
            quad: c.quad * v2,
            ..c
        });
        for k in 0..12 {
            let (t, b, w) = (0.11 * k as f64, 0.6 * k as f64 - 3.0, 9.0 - 1.7 * k as f64);
            assert_eq!(
                quad.forces_jet(t, b, w, false),
                two.forces_jet(t, b, w, false)
            );
            let (d, _) = drag(Some(2.0), w);
            assert_eq!(d * v2, w * w.abs());
        }
        c.drag_exponent = Some(1.5);
        c.st_harmonics = [(2.5, -1.5), (0.0, 0.7)];
        let sys = driven_test_gear(c);
        for k in 0..12 {
            let (t, b, w) = (0.13 * k as f64, 0.7 * k as f64 - 3.0, 5.0 - 0.9 * k as f64);
            assert_jet_matches_differences(&sys, t, b, w);
        }
        // the value: −q |ω|^1.5 sgn ω + 2.5 sin 2β − 1.5 cos 2β + 0.7 cos 3β on top of the base
        let base = driven_test_gear(Coefficients::base(300.0, 0.2, 1.0, 20.0));
        let (t, b, w) = (0.2, 0.9, -2.0);
        let extra = sys.forces(t, b, w).a - base.forces(t, b, w).a;
        let want = 0.03 * (2.0 / DRAG_REFERENCE_SPEED).powf(1.5) + 2.5 * (1.8f64).sin()
            - 1.5 * (1.8f64).cos()
            + 0.7 * (2.7f64).cos();
        assert!((extra - want).abs() < 1e-12, "{extra} vs {want}");
    }

    /// The Stribeck member: sliding friction η + η_Δs exp(−(ω/w)²) with ∂r/∂ω matching central
    /// differences, the static bound η + η_Δs equal to its limit at rest; w = 0 leaves the
    /// sliding friction at η.
    #[test]
    fn stribeck_friction_and_its_velocity_derivative() {
        let mut c = Coefficients::base(300.0, 0.2, 1.0, 20.0);
        c.eta_static_excess = 8.0;
        c.stribeck_width = 0.4;
        let h = 1e-6;
        for power in [None, Some(1.0), Some(1.5), Some(2.0)] {
            let sys = driven_test_gear(Coefficients {
                stribeck_power: power,
                ..c
            });
            let d = power.unwrap_or(2.0);
            for k in 0..10 {
                let (t, b, w) = (0.1 * k as f64, 0.5 * k as f64, 1.2 - 0.27 * k as f64);
                let j = sys.forces_jet(t, b, w, false);
                let expect = 20.0 + 8.0 * (-(w.abs() / 0.4f64).powf(d)).exp();
                assert!((j.r - expect).abs() < 1e-12, "δ = {d}: {} {expect}", j.r);
                let fd = (sys.forces(t, b, w + h).r - sys.forces(t, b, w - h).r) / (2.0 * h);
                assert!(
                    (j.r_omega - fd).abs() < 1e-6 * (1.0 + fd.abs()),
                    "δ = {d}: {} {fd}",
                    j.r_omega
                );
            }
        }
        let sys = driven_test_gear(c);
        assert!((sys.static_friction(0.3, 1.0) - sys.forces(0.3, 1.0, 0.0).r).abs() < 1e-12);
        let at_rest_only = driven_test_gear(Coefficients {
            stribeck_width: 0.0,
            ..c
        });
        assert_eq!(at_rest_only.forces(0.3, 1.0, 0.01).r, 20.0);
        assert_eq!(at_rest_only.static_friction(0.3, 1.0), 28.0);
    }

    /// The load family's bearing load: ρ = 0 without projection is the force magnitude; the
    /// radial load is the force with its component along the output shaft removed, never larger
    /// than the whole load; a weight with a vertical and a side component adds as a vector.
    #[test]
    fn load_shape_members() {
        let geo = Geometry::new(0.55, 0.5);
        let e = [geo.phi().cos(), geo.phi().sin(), 0.0];
        for k in 0..15 {
            let (a, b) = (0.41 * k as f64, 2.0 - 0.37 * k as f64);
            let f = dipole_force(&geo, a, b);
            let norm = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            assert_eq!(
                load_shape(&geo, a, b, [0.0; 2], false),
                force_shape(&geo, a, b)
            );
            assert!((force_shape(&geo, a, b) - norm(f)).abs() < 1e-15);
            let w = [f[0], f[1], f[2] - 2.2];
            assert!((load_shape(&geo, a, b, [2.2, 0.0], false) - norm(w)).abs() < 1e-12);
            let along = w[0] * e[0] + w[1] * e[1];
            let radial = norm([w[0] - along * e[0], w[1] - along * e[1], w[2]]);
            assert!((load_shape(&geo, a, b, [2.2, 0.0], true) - radial).abs() < 1e-12);
            assert!(radial <= norm(w) + 1e-15);
            // a side component along n̂ = ẑ × ê, perpendicular to the shaft: the radial
            // projection keeps it whole
            let n = [-e[1], e[0], 0.0];
            let ws = [f[0] - 1.3 * n[0], f[1] - 1.3 * n[1], f[2] - 2.2];
            assert!((load_shape(&geo, a, b, [2.2, 1.3], false) - norm(ws)).abs() < 1e-12);
            let along = ws[0] * e[0] + ws[1] * e[1];
            let rs = norm([ws[0] - along * e[0], ws[1] - along * e[1], ws[2]]);
            assert!((load_shape(&geo, a, b, [2.2, 1.3], true) - rs).abs() < 1e-12);
        }
    }
}
