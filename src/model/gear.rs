//! The dipole magnetic gear of Hartung & Rehberg (2020).
//!
//! Physical quantities ([`GearParams`], SI units) and the driven dynamical system ([`Gear`]):
//!
//! ```text
//!   β̈ + ζ β̇ + η sgn(β̇) − g (−sin α cos β + Δ cos α sin β) = 0,   α = α₀ + 2π f t,
//!   g = μ₀ m₁ m₂ / (4π r³ I)                       (paper eq. `g`),
//!   Δ = cos Θ cos Φ − 2 sin Θ sin Φ                (paper eq. `Delta`).
//! ```
//!
//! **Sign convention.** This is the physical sign: the torque is τ_ax = −∂U/∂β (paper eq. `tauax`).
//! The paper's eq. `modeldyn` prints `+ g(…)`, which is the same system with β relabelled by β + π.
//! [`Convention::Paper`] integrates the printed equation, so results can be compared with the paper's
//! figures; every bifurcation frequency is the same in both conventions, angles differ by 180°.

use super::params::{Column, Parameter, Parametrised};
use super::taylor::{TaylorOscillator, TaylorSeries, INV, TAYLOR_LEN};
use super::{DrivenOscillator, Forces, ForcesJet, HalfPeriodSymmetry};
use crate::error::{finite, non_negative, positive, Error, Result};
use crate::numerics::trig::sin_cos;
use nalgebra::Complex;
use serde::{Deserialize, Serialize};
use std::f64::consts::{PI, TAU};

/// μ₀/(4π) in T m / A (CODATA 2018: μ₀ = 1.25663706212e-6 N A⁻²).
pub const MU0_OVER_4PI: f64 = 1.256_637_062_12e-6 / (4.0 * PI);

/// Which sign of the coupling term the equation of motion uses (model.md, "Erratum").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Convention {
    /// The physical sign, τ_ax = −∂U/∂β: β̈ = … + g τ(α, β). The default.
    #[default]
    Physical,
    /// The paper's printed eq. `modeldyn`: β̈ = … − g τ(α, β); equals the physical model with β → β + π.
    Paper,
}

impl std::fmt::Display for Convention {
    /// "physical sign" or "paper's sign".
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Convention::Physical => "physical sign",
            Convention::Paper => "paper's sign",
        })
    }
}

impl Convention {
    /// +1 for [`Convention::Physical`], −1 for [`Convention::Paper`].
    pub fn sign(self) -> f64 {
        match self {
            Convention::Physical => 1.0,
            Convention::Paper => -1.0,
        }
    }
    /// The angle added to the physical β to obtain β in this convention (0 or π).
    pub fn beta_offset(self) -> f64 {
        match self {
            Convention::Physical => 0.0,
            Convention::Paper => PI,
        }
    }
}

/// The gear as built: dipole moments, distance, inertia, shaft angles and friction, in SI units.
///
/// The default is the paper's gear (eq. `inertia_fit`, `zeta`; Θ = Φ = 0).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GearParams {
    /// Input dipole moment m₁, A m².
    pub m1: f64,
    /// Output dipole moment m₂, A m².
    pub m2: f64,
    /// Centre distance r, m.
    pub r: f64,
    /// Output moment of inertia I, kg m².
    pub inertia: f64,
    /// Input shaft angle Θ to the centre line, rad.
    pub theta: f64,
    /// Output shaft angle Φ to the centre line, rad.
    pub phi: f64,
    /// Viscous damping ζ, s⁻¹.
    pub zeta: f64,
    /// Dry friction η, s⁻² (friction torque over inertia, paper eq. `eta`).
    pub eta: f64,
}

impl Default for GearParams {
    fn default() -> Self {
        Self::paper()
    }
}

impl GearParams {
    /// The paper's values: m₁ = m₂ = 3.51 A m², r = 40.0 mm, I = 6.45e-5 kg m², ζ = 1.1 s⁻¹,
    /// η = 23.1 s⁻², Θ = Φ = 0.
    pub fn paper() -> Self {
        Self {
            m1: 3.51,
            m2: 3.51,
            r: 0.040,
            inertia: 6.45e-5,
            theta: 0.0,
            phi: 0.0,
            zeta: 1.1,
            eta: 23.1,
        }
    }

    /// The paper's gear with parallel shafts at Θ = Φ = `theta_deg` degrees.
    pub fn paper_at_deg(theta_deg: f64) -> Self {
        Self {
            theta: theta_deg.to_radians(),
            phi: theta_deg.to_radians(),
            ..Self::paper()
        }
    }

    /// Returns a copy with parallel shaft angles Θ = Φ = `theta_deg` degrees.
    pub fn with_parallel_shafts_deg(mut self, theta_deg: f64) -> Self {
        self.theta = theta_deg.to_radians();
        self.phi = self.theta;
        self
    }

    /// Checks every field: finite; m₁, m₂, r, I > 0; ζ, η ≥ 0.
    pub fn validate(&self) -> Result<()> {
        positive("m1", self.m1)?;
        positive("m2", self.m2)?;
        positive("r", self.r)?;
        positive("inertia", self.inertia)?;
        finite("theta", self.theta)?;
        finite("phi", self.phi)?;
        non_negative("zeta", self.zeta)?;
        non_negative("eta", self.eta)?;
        Ok(())
    }

    /// Coupling energy scale c = μ₀ m₁ m₂ / (4π r³), in J (eq. `field_energy`).
    pub fn coupling(&self) -> f64 {
        MU0_OVER_4PI * self.m1 * self.m2 / self.r.powi(3)
    }

    /// g = c / I, s⁻² (eq. `g`).
    pub fn g(&self) -> f64 {
        self.coupling() / self.inertia
    }

    /// Shaft orientation index Δ = cos Θ cos Φ − 2 sin Θ sin Φ (eq. `Delta`).
    pub fn delta(&self) -> f64 {
        shaft_index(self.theta, self.phi)
    }

    /// Field energy U(α, β) = c (sin α sin β + Δ cos α cos β) of m₂ in the field of m₁, J (eq. `field_energy`).
    pub fn field_energy(&self, alpha: f64, beta: f64) -> f64 {
        self.coupling() * energy_bracket(self.delta(), alpha, beta)
    }

    /// Axial torque on the output τ_ax = −∂U/∂β = c (−sin α cos β + Δ cos α sin β), N m (eq. `tauax`).
    pub fn torque(&self, alpha: f64, beta: f64) -> f64 {
        self.coupling() * coupling_bracket(self.delta(), alpha, beta)
    }

    /// Stable equilibrium β₀ of the output for a locked input at α₀: the minimum of U(α₀, ·),
    /// tan β₀ = tan(α₀)/Δ on the branch with ∂²U/∂β² > 0 (the corrected eq. `equilibrium`).
    /// Returned in [0, 2π), physical convention.
    pub fn equilibrium(&self, alpha0: f64) -> f64 {
        equilibrium_angle(self.delta(), alpha0)
    }

    /// Restoring coefficient κ(α₀) = g √(sin²α₀ + Δ² cos²α₀), s⁻², at the stable equilibrium
    /// of a locked input (eq. `kappaex` evaluated at β₀).
    pub fn kappa(&self, alpha0: f64) -> f64 {
        kappa(self.g(), self.delta(), alpha0)
    }

    /// Lock-loss frequency f_c = (g − η) / (2π ζ), Hz, of the analytic lock branch at Δ = ±1.
    /// `None` when ζ = 0 (no viscous limit) or g ≤ η (never locks).
    pub fn lock_loss_frequency(&self) -> Option<f64> {
        lock_loss_frequency(self.g(), self.zeta, self.eta)
    }

    /// The driven system at input frequency `f` (Hz), physical convention, α₀ = 0.
    pub fn driven(&self, f: f64) -> Result<Gear> {
        self.validate()?;
        Gear::new(self.g(), self.delta(), self.zeta, self.eta, f)
    }
}

/// Δ(Θ, Φ) = cos Θ cos Φ − 2 sin Θ sin Φ.
pub fn shaft_index(theta: f64, phi: f64) -> f64 {
    theta.cos() * phi.cos() - 2.0 * theta.sin() * phi.sin()
}

/// The bracket sin α sin β + Δ cos α cos β of eq. `field_energy` (field energy over c).
pub fn energy_bracket(delta: f64, alpha: f64, beta: f64) -> f64 {
    alpha.sin() * beta.sin() + delta * alpha.cos() * beta.cos()
}

/// The bracket τ(α, β) = −sin α cos β + Δ cos α sin β of eq. `tauax` (torque over c); the same
/// arithmetic as the right-hand side ([`Gear`]'s `forces`), so the stick and release tests agree
/// with it to the last bit.
pub fn coupling_bracket(delta: f64, alpha: f64, beta: f64) -> f64 {
    let (sa, ca) = sin_cos(alpha);
    let (sb, cb) = sin_cos(beta);
    -sa * cb + delta * ca * sb
}

/// Stable equilibrium of the output for a locked input (see [`GearParams::equilibrium`]).
pub fn equilibrium_angle(delta: f64, alpha0: f64) -> f64 {
    // U ∝ sin α₀ sin β + Δ cos α₀ cos β = R cos(β − ψ), minimum at β = ψ + π.
    let psi = alpha0.sin().atan2(delta * alpha0.cos());
    (psi + PI).rem_euclid(TAU)
}

/// κ(α₀) = g √(sin²α₀ + Δ² cos²α₀).
pub fn kappa(g: f64, delta: f64, alpha0: f64) -> f64 {
    g * (alpha0.sin().powi(2) + delta.powi(2) * alpha0.cos().powi(2)).sqrt()
}

/// f_c = (g − η)/(2πζ), or `None` if ζ = 0 or g ≤ η.
pub fn lock_loss_frequency(g: f64, zeta: f64, eta: f64) -> Option<f64> {
    if zeta > 0.0 && g > eta {
        Some((g - eta) / (TAU * zeta))
    } else {
        None
    }
}

/// Input shaft angles Θ (rad, in (−π/2, π/2]) at which the coupling is cogging-free (Δ = ±1) for a
/// given output shaft angle Φ. For parallel shafts (Θ = Φ) use [`cogging_free_parallel_angles`].
pub fn cogging_free_input_angles(phi: f64) -> Vec<(f64, f64)> {
    // Δ = R cos(Θ + ψ), R = √(cos²Φ + 4 sin²Φ), ψ = atan2(2 sin Φ, cos Φ).
    let (s, c) = phi.sin_cos();
    let rr = (c * c + 4.0 * s * s).sqrt();
    let psi = (2.0 * s).atan2(c);
    let mut out: Vec<(f64, f64)> = Vec::new();
    for target in [1.0, -1.0] {
        let base = (target / rr).clamp(-1.0, 1.0).acos();
        for cand in [base - psi, -base - psi] {
            // fold to (−π/2, π/2]: reversing the axis direction flips the sign of Δ
            let mut th = cand.rem_euclid(PI);
            if th > PI / 2.0 {
                th -= PI;
            }
            let d = shaft_index(th, phi).round();
            if !out.iter().any(|&(t, _)| (t - th).abs() < 1e-9) {
                out.push((th, d));
            }
        }
    }
    out.sort_by(|a, b| a.0.total_cmp(&b.0));
    out
}

/// Parallel shaft angles (Θ = Φ, rad, in [0, π/2]) where Δ = 1 − 3 sin²Θ equals +1, 0 and −1:
/// (0, 35.26°, 54.74°).
pub fn cogging_free_parallel_angles() -> (f64, f64, f64) {
    (
        0.0,
        (1.0f64 / 3.0).sqrt().asin(),
        (2.0f64 / 3.0).sqrt().asin(),
    )
}

/// The gear as a driven dynamical system: the reduced parameters of eq. `modeldyn`.
///
/// Parameter columns of Jacobians are, in order, [`GearParam::COLUMNS`] = (f, g, ζ, η, Δ).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Gear {
    /// g = c/I, s⁻².
    pub g: f64,
    /// Shaft orientation index Δ.
    pub delta: f64,
    /// Viscous damping ζ, s⁻¹.
    pub zeta: f64,
    /// Dry friction η, s⁻².
    pub eta: f64,
    /// Drive frequency f, Hz (α = α₀ + 2π f t).
    pub f: f64,
    /// Drive phase α₀ at t = 0, rad.
    pub alpha0: f64,
    /// Sign convention of the coupling term.
    pub convention: Convention,
}

/// The gear's parameters (its [`Parametrised`] lens). The first five are the Jacobian columns in
/// this order; Θ is derived: parallel shafts Θ = Φ in degrees, Δ = cos²Θ − 2 sin²Θ = 1 − 3 sin²Θ.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GearParam {
    /// Drive frequency f, Hz.
    F,
    /// Coupling g, s⁻².
    G,
    /// Viscous damping ζ, s⁻¹.
    Zeta,
    /// Dry friction η, s⁻².
    Eta,
    /// Shaft index Δ.
    Delta,
    /// Parallel shaft angle Θ = Φ in degrees, Θ ∈ [0°, 90°] (read back from Δ = 1 − 3 sin²Θ).
    #[serde(rename = "theta")]
    ThetaDeg,
}

impl Parameter for GearParam {
    const ALL: &'static [Self] = &[
        GearParam::F,
        GearParam::G,
        GearParam::Zeta,
        GearParam::Eta,
        GearParam::Delta,
        GearParam::ThetaDeg,
    ];
    fn name(self) -> &'static str {
        match self {
            GearParam::F => "f",
            GearParam::G => "g",
            GearParam::Zeta => "zeta",
            GearParam::Eta => "eta",
            GearParam::Delta => "delta",
            GearParam::ThetaDeg => "theta",
        }
    }
    fn symbol(self) -> &'static str {
        match self {
            GearParam::F => "f",
            GearParam::G => "g",
            GearParam::Zeta => "ζ",
            GearParam::Eta => "η",
            GearParam::Delta => "Δ",
            GearParam::ThetaDeg => "Θ",
        }
    }
    fn unit(self) -> &'static str {
        match self {
            GearParam::F => "Hz",
            GearParam::G | GearParam::Eta => "1/s²",
            GearParam::Zeta => "1/s",
            GearParam::Delta => "",
            GearParam::ThetaDeg => "deg",
        }
    }
}

impl GearParam {
    /// The parameters with a Jacobian column, in column order (f, g, ζ, η, Δ).
    pub const COLUMNS: [GearParam; 5] = [
        GearParam::F,
        GearParam::G,
        GearParam::Zeta,
        GearParam::Eta,
        GearParam::Delta,
    ];
}

impl Parametrised for Gear {
    type Param = GearParam;

    fn param(&self, p: GearParam) -> f64 {
        match p {
            GearParam::F => self.f,
            GearParam::G => self.g,
            GearParam::Zeta => self.zeta,
            GearParam::Eta => self.eta,
            GearParam::Delta => self.delta,
            // Θ from Δ = 1 − 3 sin²Θ, Θ ∈ [0°, 90°]
            GearParam::ThetaDeg => ((1.0 - self.delta) / 3.0)
                .clamp(0.0, 1.0)
                .sqrt()
                .asin()
                .to_degrees(),
        }
    }

    fn with_param(&self, p: GearParam, value: f64) -> Result<Self> {
        let mut g = *self;
        match p {
            GearParam::F => g.f = positive("f", value)?,
            GearParam::G => g.g = non_negative("g", value)?,
            GearParam::Zeta => g.zeta = non_negative("zeta", value)?,
            GearParam::Eta => g.eta = non_negative("eta", value)?,
            GearParam::Delta => g.delta = finite("delta", value)?,
            GearParam::ThetaDeg => {
                // Δ is even in Θ and symmetric about 90°: [0°, 90°] covers every Δ, and there
                // the lens reads back the value it set
                if !(0.0..=90.0).contains(&value) {
                    return Err(Error::InvalidParameter {
                        name: "theta",
                        value,
                        reason: "the parallel shaft angle of the lens must lie in [0°, 90°]",
                    });
                }
                let t = value.to_radians();
                g.delta = shaft_index(t, t);
            }
        }
        Ok(g)
    }

    fn column(&self, p: GearParam) -> Option<Column> {
        Some(match p {
            GearParam::ThetaDeg => {
                // dΔ/dΘ = −3 sin 2Θ, per degree
                let th = self.param(GearParam::ThetaDeg).to_radians();
                Column {
                    index: COL_DELTA,
                    factor: -3.0 * (2.0 * th).sin() * PI / 180.0,
                }
            }
            p => Column::primary(p as usize),
        })
    }
}

const COL_F: usize = GearParam::F as usize;
const COL_G: usize = GearParam::G as usize;
const COL_ZETA: usize = GearParam::Zeta as usize;
const COL_ETA: usize = GearParam::Eta as usize;
const COL_DELTA: usize = GearParam::Delta as usize;

impl Gear {
    /// A gear with reduced parameters; validates: all finite, g ≥ 0, ζ ≥ 0, η ≥ 0, f > 0.
    pub fn new(g: f64, delta: f64, zeta: f64, eta: f64, f: f64) -> Result<Self> {
        non_negative("g", g)?;
        finite("delta", delta)?;
        non_negative("zeta", zeta)?;
        non_negative("eta", eta)?;
        positive("f", f)?;
        Ok(Self {
            g,
            delta,
            zeta,
            eta,
            f,
            alpha0: 0.0,
            convention: Convention::Physical,
        })
    }

    /// The paper's gear at parallel shaft angle `theta_deg` and frequency `f`.
    pub fn paper(theta_deg: f64, f: f64) -> Result<Self> {
        finite("theta_deg", theta_deg)?;
        GearParams::paper_at_deg(theta_deg).driven(f)
    }

    /// Returns a copy with drive phase α₀.
    pub fn with_alpha0(mut self, alpha0: f64) -> Result<Self> {
        self.alpha0 = finite("alpha0", alpha0)?;
        Ok(self)
    }

    /// Returns a copy with the given sign convention.
    pub fn with_convention(mut self, convention: Convention) -> Self {
        self.convention = convention;
        self
    }

    /// Returns a copy with drive frequency `f` (validated).
    pub fn with_f(mut self, f: f64) -> Result<Self> {
        self.f = positive("f", f)?;
        Ok(self)
    }

    /// Drive angle α(t) = α₀ + 2π f t.
    #[inline]
    pub fn alpha(&self, t: f64) -> f64 {
        self.alpha0 + TAU * self.f * t
    }

    /// Lock-loss frequency f_c = (g − η)/(2πζ) (see [`lock_loss_frequency`]).
    pub fn lock_loss_frequency(&self) -> Option<f64> {
        lock_loss_frequency(self.g, self.zeta, self.eta)
    }

    /// The analytic lock branch; only defined at the cogging-free points Δ = ±1 (to 1e-12).
    pub fn lock_branch(&self) -> Result<LockBranch> {
        LockBranch::new(self)
    }
}

impl DrivenOscillator for Gear {
    /// Taylor's method applies (the recurrences below).
    fn as_taylor(&self) -> Option<&dyn TaylorOscillator> {
        Some(self)
    }
    #[inline]
    fn period(&self) -> f64 {
        1.0 / self.f
    }

    fn n_params(&self) -> usize {
        5
    }

    fn param_name(&self, k: usize) -> &'static str {
        GearParam::COLUMNS.get(k).map(|p| p.name()).unwrap_or("?")
    }

    fn period_derivative(&self, k: usize) -> f64 {
        if k == COL_F {
            -1.0 / (self.f * self.f)
        } else {
            0.0
        }
    }

    #[inline(always)]
    fn forces(&self, t: f64, beta: f64, omega: f64) -> Forces {
        let (sa, ca) = sin_cos(self.alpha(t));
        let (sb, cb) = sin_cos(beta);
        let tau = -sa * cb + self.delta * ca * sb;
        Forces {
            a: -self.zeta * omega + self.convention.sign() * self.g * tau,
            r: self.eta,
        }
    }

    #[inline(always)]
    fn forces_jet(&self, t: f64, beta: f64, omega: f64, params: bool) -> ForcesJet {
        let sg = self.convention.sign();
        let (sa, ca) = sin_cos(self.alpha(t));
        let (sb, cb) = sin_cos(beta);
        let tau = -sa * cb + self.delta * ca * sb;
        let tau_b = sa * sb + self.delta * ca * cb;
        let mut jet = ForcesJet::new(-self.zeta * omega + sg * self.g * tau, self.eta);
        jet.a_beta = sg * self.g * tau_b;
        jet.a_omega = -self.zeta;
        if params {
            let tau_a = -ca * cb - self.delta * sa * sb;
            jet.a_p[COL_F] = sg * self.g * tau_a * TAU * t;
            jet.a_p[COL_G] = sg * tau;
            jet.a_p[COL_ZETA] = -omega;
            jet.a_p[COL_DELTA] = sg * self.g * ca * sb;
            jet.r_p[COL_ETA] = 1.0;
        }
        jet
    }

    fn static_friction(&self, _t: f64, _beta: f64) -> f64 {
        self.eta
    }

    /// Exact release time: at rest, |a| = g |τ(α, β*)| = g R |sin(α + φ)| with
    /// R = √(cos²β* + Δ² sin²β*), so release happens at the next α with |sin(α + φ)| = η/(gR)
    /// on a rising flank of |sin|.
    fn next_release(&self, t: f64, beta: f64, t_max: f64) -> Option<f64> {
        let (sb, cb) = sin_cos(beta);
        let amp = self.g * (cb * cb + self.delta * self.delta * sb * sb).sqrt();
        if self.g * coupling_bracket(self.delta, self.alpha(t), beta).abs() >= self.eta {
            return Some(t);
        }
        if amp <= self.eta {
            return None;
        }
        let phi = (self.delta * sb).atan2(-cb);
        let c = (self.eta / amp).asin();
        let u0 = self.alpha(t) + phi;
        // |sin u| rises through sin(c) at u = c + kπ.
        let k = ((u0 - c) / PI).ceil();
        let mut u = c + k * PI;
        if u < u0 {
            u += PI;
        }
        let tr = t + (u - u0) / (TAU * self.f);
        if tr <= t_max {
            Some(tr)
        } else {
            None
        }
    }

    fn half_period_symmetry(&self) -> Option<HalfPeriodSymmetry> {
        Some(HalfPeriodSymmetry {
            sign: 1.0,
            shift: PI,
        })
    }

    fn drive_phase(&self, t: f64) -> f64 {
        self.alpha(t)
    }

    /// +1 for Δ ≥ 0 (the output turns with the input), −1 for Δ < 0 (the reversed mode).
    fn co_rotation(&self) -> f64 {
        if self.delta >= 0.0 {
            1.0
        } else {
            -1.0
        }
    }
}

/// The gear's Taylor coefficients (`model/taylor.rs`). With u = β + α and v = β − α the torque
/// bracket is τ = ((Δ − 1)/2) sin u + ((Δ + 1)/2) sin v and ∂τ/∂β = ((Δ − 1)/2) cos u +
/// ((Δ + 1)/2) cos v, so F = −ζω − sη + σ g τ (σ the convention's sign) needs only the sin/cos
/// recurrences of u and v (u̇ = ω + 2πf, v̇ = ω − 2πf): four Cauchy sums per order, and ∂F/∂β comes
/// with them at no cost; ∂F/∂ω = −ζ.
/// The recurrences run with the processor's widest vector instructions
/// ([`simd_arch`](super::taylor::simd_arch)).
impl TaylorOscillator for Gear {
    fn taylor_expand(
        &self,
        t0: f64,
        side: f64,
        order: usize,
        x: &mut TaylorSeries,
        linearised: bool,
    ) {
        super::taylor::simd_arch().dispatch(GearJet {
            gear: self,
            t0,
            side,
            order,
            x,
            linearised,
        });
    }
}

/// One call of the gear's [`TaylorOscillator::taylor_expand`] as an operation that `pulp`
/// compiles for each instruction set.
struct GearJet<'a> {
    gear: &'a Gear,
    t0: f64,
    side: f64,
    order: usize,
    x: &'a mut TaylorSeries,
    linearised: bool,
}

impl pulp::WithSimd for GearJet<'_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<V: pulp::Simd>(self, _: V) {
        let GearJet {
            gear,
            t0,
            side,
            order,
            x,
            linearised,
        } = self;
        gear.jet(t0, side, order, x, linearised);
    }
}

impl Gear {
    /// The recurrences of the gear's Taylor coefficients (the impl's docs).
    #[inline(always)]
    fn jet(&self, t0: f64, side: f64, order: usize, x: &mut TaylorSeries, linearised: bool) {
        let nu = TAU * self.f;
        let half_g = 0.5 * self.convention.sign() * self.g;
        let (ku, kv) = (half_g * (self.delta - 1.0), half_g * (self.delta + 1.0));
        let alpha = self.alpha(t0);
        // q[m] = ((cos u)ₘ, (sin u)ₘ, (cos v)ₘ, (sin v)ₘ): one 4-lane Cauchy sum per order;
        // j uⱼ = ωⱼ₋₁ except 1·u₁ = ω₀ + ν (v: ω₀ − ν)
        let mut q = [[0.0; 4]; TAYLOR_LEN];
        let (su, cu) = sin_cos(x.beta[0] + alpha);
        let (sv, cv) = sin_cos(x.beta[0] - alpha);
        q[0] = [cu, su, cv, sv];
        let (du, dv) = (x.omega[0] + nu, x.omega[0] - nu);
        let d1 = [du, du, dv, dv];
        for k in 0..order {
            if k > 0 {
                // (sin u)ₖ = (1/k) Σⱼ j uⱼ (cos u)ₖ₋ⱼ, (cos u)ₖ = −(1/k) Σⱼ j uⱼ (sin u)ₖ₋ⱼ;
                // the newest term (j = 1, q[k − 1]) is added last: it ends the chain of orders
                let mut acc = older_terms(&x.omega, &q, k);
                for (a, (&d, &qn)) in acc.iter_mut().zip(d1.iter().zip(&q[k - 1])) {
                    *a += d * qn;
                }
                let inv = INV[k];
                q[k] = [-acc[1] * inv, acc[0] * inv, -acc[3] * inv, acc[2] * inv];
            }
            let mut f = -self.zeta * x.omega[k] + ku * q[k][1] + kv * q[k][3];
            if k == 0 {
                f -= side * self.eta;
            }
            x.omega[k + 1] = f * INV[k + 1];
            x.beta[k + 1] = x.omega[k] * INV[k + 1];
            if linearised {
                x.d_beta[k] = ku * q[k][0] + kv * q[k][2];
            }
        }
        if linearised {
            x.d_omega[0] = -self.zeta;
            x.d_omega_constant = true;
        }
    }
}

/// Σⱼ ωⱼ₋₁ q[k − j] over j = 2 … k lane by lane (the terms of the Cauchy sum of order k that
/// are known before q[k − 1]), in two partial sums so that consecutive additions do not wait for
/// each other.
#[inline(always)]
fn older_terms(omega: &[f64; TAYLOR_LEN], q: &[[f64; 4]; TAYLOR_LEN], k: usize) -> [f64; 4] {
    let mut a = [[0.0; 4]; 2];
    let mut j = 2;
    while j < k {
        let (w0, w1) = (omega[j - 1], omega[j]);
        let (q0, q1) = (q[k - j], q[k - j - 1]);
        for l in 0..4 {
            a[0][l] += w0 * q0[l];
            a[1][l] += w1 * q1[l];
        }
        j += 2;
    }
    if j == k {
        let w = omega[k - 1];
        for l in 0..4 {
            a[0][l] += w * q[0][l];
        }
    }
    std::array::from_fn(|l| a[0][l] + a[1][l])
}

/// One point of the analytic lock branch at Δ = ±1 (numerics.md, "Validation oracles").
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LockPoint {
    /// Phase offset of the locked orbit: δ = β − α for Δ = +1, σ = β + α for Δ = −1, rad,
    /// in the gear's convention.
    pub phase: f64,
    /// Initial state (β, ω) at t = 0 of the locked orbit, in the gear's convention.
    pub state: [f64; 2],
    /// Winding p of β per drive period: +1 (Δ = +1) or −1 (Δ = −1).
    pub winding: i32,
    /// Floquet multipliers μ = exp(λT), λ = (−ζ ± √(ζ² − 4k))/2, of the stroboscopic map.
    pub multipliers: [Complex<f64>; 2],
    /// True if both multipliers lie inside the unit circle.
    pub stable: bool,
}

/// The analytic locked orbits of the gear at a cogging-free point (Δ = ±1).
///
/// For Δ = +1 the bracket is sin(β − α): with β = α + δ, β̇ = 2πf, the equation gives
/// sin δ = (2πfζ + η)/g; stable δ = π − arcsin(…), unstable δ = arcsin(…). For Δ = −1 it is
/// −sin(α + β): with β = σ − α, β̇ = −2πf, sin σ = (2πfζ + η)/g; stable σ = arcsin(…).
/// Both branches end in a saddle-node at f_c = (g − η)/(2πζ).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LockBranch {
    /// Stable locked orbit.
    pub stable: LockPoint,
    /// Unstable (saddle) locked orbit.
    pub unstable: LockPoint,
    /// sin of the phase: (2πfζ + η)/g.
    pub load: f64,
}

impl LockBranch {
    /// The lock branch of `gear` at its frequency; errors unless Δ = ±1 and f < f_c.
    pub fn new(gear: &Gear) -> Result<Self> {
        let d = gear.delta;
        let sense = if (d - 1.0).abs() < 1e-12 {
            1.0
        } else if (d + 1.0).abs() < 1e-12 {
            -1.0
        } else {
            return Err(Error::OutsideClosedForm {
                closed_form: "the analytic lock branch",
                needs: format!("Δ = ±1 (cogging-free), not Δ = {d}"),
            });
        };
        if gear.g <= 0.0 {
            return Err(Error::InvalidParameter {
                name: "g",
                value: gear.g,
                reason: "must be > 0 for a locked state",
            });
        }
        let w = TAU * gear.f;
        let load = (w * gear.zeta + gear.eta) / gear.g;
        if load > 1.0 {
            return Err(Error::OutsideClosedForm {
                closed_form: "a locked state",
                needs: format!("f below f_c, (2πfζ + η)/g ≤ 1, not {load}"),
            });
        }
        let asn = load.asin();
        let off = gear.convention.beta_offset();
        let t = 1.0 / gear.f;
        let mk = |phase: f64| -> LockPoint {
            // linearisation ε̈ + ζ ε̇ + k ε = 0
            let k = if sense > 0.0 {
                -gear.g * phase.cos()
            } else {
                gear.g * phase.cos()
            };
            let disc = Complex::new(gear.zeta * gear.zeta - 4.0 * k, 0.0).sqrt();
            let l1 = (Complex::new(-gear.zeta, 0.0) + disc) * 0.5;
            let l2 = (Complex::new(-gear.zeta, 0.0) - disc) * 0.5;
            let m1 = (l1 * t).exp();
            let m2 = (l2 * t).exp();
            let beta0 = sense * gear.alpha0 + phase + off;
            LockPoint {
                phase: phase + off,
                state: [beta0, sense * w],
                winding: sense as i32,
                multipliers: [m1, m2],
                stable: m1.norm() < 1.0 && m2.norm() < 1.0,
            }
        };
        let (ps, pu) = if sense > 0.0 {
            (PI - asn, asn)
        } else {
            (asn, PI - asn)
        };
        Ok(Self {
            stable: mk(ps),
            unstable: mk(pu),
            load,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn paper_g_and_fc() {
        let p = GearParams::paper();
        assert_relative_eq!(p.g(), 298.45, max_relative = 2e-4);
        assert_relative_eq!(p.lock_loss_frequency().unwrap(), 39.84, max_relative = 3e-4);
    }

    #[test]
    fn torque_is_minus_energy_gradient_and_matches_dipole_vectors() {
        let p = GearParams {
            theta: 0.3,
            phi: -0.7,
            ..GearParams::paper()
        };
        for &(a, b) in &[(0.1, 0.2), (2.0, -1.0), (-3.0, 4.0)] {
            let h = 1e-6;
            let du = (p.field_energy(a, b + h) - p.field_energy(a, b - h)) / (2.0 * h);
            assert_relative_eq!(p.torque(a, b), -du, epsilon = 1e-9 * p.coupling());
            // τ = m2 × B1 projected on the output axis (cos Φ, sin Φ, 0)
            let m1 = [
                -a.cos() * p.theta.sin() * p.m1,
                a.cos() * p.theta.cos() * p.m1,
                a.sin() * p.m1,
            ];
            let m2 = [
                -b.cos() * p.phi.sin() * p.m2,
                b.cos() * p.phi.cos() * p.m2,
                b.sin() * p.m2,
            ];
            let r = p.r;
            let rv = [r, 0.0, 0.0];
            let mdr = m1[0] * rv[0];
            let bf: Vec<f64> = (0..3)
                .map(|i| MU0_OVER_4PI * (3.0 * mdr * rv[i] - m1[i] * r * r) / r.powi(5))
                .collect();
            let tq = [
                m2[1] * bf[2] - m2[2] * bf[1],
                m2[2] * bf[0] - m2[0] * bf[2],
                m2[0] * bf[1] - m2[1] * bf[0],
            ];
            let tax = tq[0] * p.phi.cos() + tq[1] * p.phi.sin();
            assert_relative_eq!(p.torque(a, b), tax, epsilon = 1e-12);
        }
    }

    #[test]
    fn equilibrium_is_energy_minimum_and_kappa_is_curvature() {
        for &th in &[0.0, 20.0, 31.0, 50.0, 54.7356] {
            let p = GearParams::paper_at_deg(th);
            for k in 0..12 {
                let a0 = k as f64 * 0.5;
                let b0 = p.equilibrium(a0);
                assert!(p.torque(a0, b0).abs() < 1e-12 * p.coupling());
                let h = 1e-4;
                let curv = (p.field_energy(a0, b0 + h) - 2.0 * p.field_energy(a0, b0)
                    + p.field_energy(a0, b0 - h))
                    / (h * h);
                assert!(curv > 0.0);
                assert_relative_eq!(curv / p.inertia, p.kappa(a0), max_relative = 1e-6);
            }
        }
    }

    #[test]
    fn parallel_special_angles() {
        let (a, b, c) = cogging_free_parallel_angles();
        assert_eq!(a, 0.0);
        assert_relative_eq!(b.to_degrees(), 35.26, epsilon = 5e-3);
        assert_relative_eq!(c.to_degrees(), 54.74, epsilon = 5e-3);
        assert_relative_eq!(shaft_index(b, b), 0.0, epsilon = 1e-12);
        assert_relative_eq!(shaft_index(c, c), -1.0, epsilon = 1e-12);
        for phi in [0.0, 0.3, -0.9] {
            let v = cogging_free_input_angles(phi);
            assert!(!v.is_empty());
            for (th, d) in v {
                assert_relative_eq!(shaft_index(th, phi), d, epsilon = 1e-9);
            }
        }
    }

    #[test]
    fn bad_parameters_are_errors() {
        assert!(Gear::new(298.0, 1.0, 1.1, 23.1, 0.0).is_err());
        assert!(Gear::new(f64::NAN, 1.0, 1.1, 23.1, 1.0).is_err());
        assert!(Gear::new(298.0, 1.0, -1.0, 23.1, 1.0).is_err());
        let p = GearParams {
            inertia: -1.0,
            ..GearParams::paper()
        };
        assert!(matches!(
            p.driven(1.0),
            Err(Error::InvalidParameter {
                name: "inertia",
                ..
            })
        ));
        assert!(Gear::paper(25.0, 2.0).unwrap().lock_branch().is_err());
        assert!(Gear::paper(0.0, 45.0).unwrap().lock_branch().is_err());
    }

    #[test]
    fn analytic_release_matches_generic_scan() {
        let g = Gear::paper(25.0, 2.7).unwrap();
        for &b in &[0.1, 1.0, 2.5, -2.0, 3.1] {
            for &t0 in &[0.0, 0.05, 0.17] {
                let ex = g.next_release(t0, b, 10.0);
                let sc = super::super::default_next_release(&g, t0, b, 10.0);
                match (ex, sc) {
                    (Some(x), Some(y)) => assert_relative_eq!(x, y, epsilon = 1e-12),
                    (None, None) => {}
                    other => panic!("mismatch {other:?}"),
                }
            }
        }
    }
}
