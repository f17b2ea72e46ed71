//! Other periodically driven oscillators with dry friction, with known answers; they run through the
//! same integrator, maps and orbit solvers as the gear and serve as test problems.

use super::params::{Column, Parameter, Parametrised};
use super::taylor::{TaylorOscillator, TaylorSeries, INV};
use super::{DrivenOscillator, Forces, ForcesJet, HalfPeriodSymmetry};
use crate::error::{finite, non_negative, positive, Result};
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

/// A Coulomb-damped, harmonically forced linear oscillator (Den Hartog's problem):
///
/// ```text
///   ẍ + 2ξω₀ ẋ + ω₀² x + μ sgn(ẋ) = F cos(2π f t).
/// ```
///
/// Parameter columns: (f, ω₀, ξ, μ, F). Half-period symmetry x → −x.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CoulombOscillator {
    /// Natural angular frequency ω₀, rad/s.
    pub omega0: f64,
    /// Viscous damping ratio ξ.
    pub xi: f64,
    /// Coulomb friction μ (acceleration units).
    pub mu: f64,
    /// Forcing amplitude F (acceleration units).
    pub force: f64,
    /// Forcing frequency f, Hz.
    pub f: f64,
}

impl CoulombOscillator {
    /// Validated constructor: ω₀ > 0, ξ ≥ 0, μ ≥ 0, F finite, f > 0.
    pub fn new(omega0: f64, xi: f64, mu: f64, force: f64, f: f64) -> Result<Self> {
        Ok(Self {
            omega0: positive("omega0", omega0)?,
            xi: non_negative("xi", xi)?,
            mu: non_negative("mu", mu)?,
            force: finite("force", force)?,
            f: positive("f", f)?,
        })
    }
}

/// Parameters of [`CoulombOscillator`], in Jacobian column order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CoulombParam {
    /// Forcing frequency f, Hz.
    F,
    /// Natural angular frequency ω₀, rad/s.
    Omega0,
    /// Damping ratio ξ.
    Xi,
    /// Coulomb friction μ.
    Mu,
    /// Forcing amplitude F.
    Force,
}

impl Parameter for CoulombParam {
    const ALL: &'static [Self] = &[Self::F, Self::Omega0, Self::Xi, Self::Mu, Self::Force];
    fn name(self) -> &'static str {
        ["f", "omega0", "xi", "mu", "force"][self as usize]
    }
    fn unit(self) -> &'static str {
        ["Hz", "rad/s", "", "m/s²", "m/s²"][self as usize]
    }
}

impl Parametrised for CoulombOscillator {
    type Param = CoulombParam;
    fn param(&self, p: CoulombParam) -> f64 {
        match p {
            CoulombParam::F => self.f,
            CoulombParam::Omega0 => self.omega0,
            CoulombParam::Xi => self.xi,
            CoulombParam::Mu => self.mu,
            CoulombParam::Force => self.force,
        }
    }
    fn with_param(&self, p: CoulombParam, v: f64) -> Result<Self> {
        let mut s = *self;
        match p {
            CoulombParam::F => s.f = positive("f", v)?,
            CoulombParam::Omega0 => s.omega0 = positive("omega0", v)?,
            CoulombParam::Xi => s.xi = non_negative("xi", v)?,
            CoulombParam::Mu => s.mu = non_negative("mu", v)?,
            CoulombParam::Force => s.force = finite("force", v)?,
        }
        Ok(s)
    }
    fn column(&self, p: CoulombParam) -> Option<Column> {
        Some(Column::primary(p as usize))
    }
}

/// Taylor coefficients of the slip solution (`model/taylor.rs`): with φ = 2πf t, the forcing's
/// coefficients follow (cos φ)ₖ = −(ν/k)(sin φ)ₖ₋₁, (sin φ)ₖ = (ν/k)(cos φ)ₖ₋₁ (ν = 2πf), and
/// Fₖ = F (cos φ)ₖ − 2ξω₀ ẋₖ − ω₀² xₖ − sμ [k = 0]; ∂F/∂x = −ω₀², ∂F/∂ẋ = −2ξω₀.
impl TaylorOscillator for CoulombOscillator {
    fn taylor_expand(
        &self,
        t0: f64,
        side: f64,
        order: usize,
        x: &mut TaylorSeries,
        linearised: bool,
    ) {
        let nu = TAU * self.f;
        let w0 = self.omega0;
        let (mut sn, mut cs) = (TAU * self.f * t0).sin_cos();
        for k in 0..order {
            if k > 0 {
                let inv = nu * INV[k];
                (sn, cs) = (inv * cs, -inv * sn);
            }
            let mut f = self.force * cs - 2.0 * self.xi * w0 * x.omega[k] - w0 * w0 * x.beta[k];
            if k == 0 {
                f -= side * self.mu;
            }
            x.omega[k + 1] = f * INV[k + 1];
            x.beta[k + 1] = x.omega[k] * INV[k + 1];
        }
        if linearised {
            x.d_beta[..order].fill(0.0);
            x.d_beta[0] = -w0 * w0;
            x.d_omega[0] = -2.0 * self.xi * w0;
            x.d_omega_constant = true;
        }
    }
}

impl DrivenOscillator for CoulombOscillator {
    /// Taylor's method applies (the recurrences below).
    fn as_taylor(&self) -> Option<&dyn TaylorOscillator> {
        Some(self)
    }
    fn period(&self) -> f64 {
        1.0 / self.f
    }
    /// x is a displacement.
    fn angular(&self) -> bool {
        false
    }
    fn n_params(&self) -> usize {
        5
    }
    fn param_name(&self, k: usize) -> &'static str {
        CoulombParam::ALL.get(k).map(|p| p.name()).unwrap_or("?")
    }
    fn period_derivative(&self, k: usize) -> f64 {
        if k == 0 {
            -1.0 / (self.f * self.f)
        } else {
            0.0
        }
    }
    fn forces(&self, t: f64, x: f64, v: f64) -> Forces {
        let w0 = self.omega0;
        Forces {
            a: self.force * (TAU * self.f * t).cos() - 2.0 * self.xi * w0 * v - w0 * w0 * x,
            r: self.mu,
        }
    }
    fn forces_jet(&self, t: f64, x: f64, v: f64, params: bool) -> ForcesJet {
        let w0 = self.omega0;
        let (s, c) = (TAU * self.f * t).sin_cos();
        let mut j = ForcesJet::new(
            self.force * c - 2.0 * self.xi * w0 * v - w0 * w0 * x,
            self.mu,
        );
        j.a_beta = -w0 * w0;
        j.a_omega = -2.0 * self.xi * w0;
        if params {
            j.a_p[0] = -self.force * s * TAU * t;
            j.a_p[1] = -2.0 * self.xi * v - 2.0 * w0 * x;
            j.a_p[2] = -2.0 * w0 * v;
            j.r_p[3] = 1.0;
            j.a_p[4] = c;
        }
        j
    }
    fn half_period_symmetry(&self) -> Option<HalfPeriodSymmetry> {
        Some(HalfPeriodSymmetry {
            sign: -1.0,
            shift: 0.0,
        })
    }
}

/// A forced pendulum with viscous and dry friction:
///
/// ```text
///   θ̈ + γ θ̇ + μ sgn(θ̇) + ω₀² sin θ = A cos(2π f t).
/// ```
///
/// Parameter columns: (f, ω₀, γ, μ, A). Half-period symmetry θ → −θ.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ForcedPendulum {
    /// Small-amplitude angular frequency ω₀, rad/s.
    pub omega0: f64,
    /// Viscous damping γ, s⁻¹.
    pub gamma: f64,
    /// Dry friction μ, s⁻².
    pub mu: f64,
    /// Forcing amplitude A, s⁻².
    pub amplitude: f64,
    /// Forcing frequency f, Hz.
    pub f: f64,
}

impl ForcedPendulum {
    /// Validated constructor: ω₀ > 0, γ ≥ 0, μ ≥ 0, A finite, f > 0.
    pub fn new(omega0: f64, gamma: f64, mu: f64, amplitude: f64, f: f64) -> Result<Self> {
        Ok(Self {
            omega0: positive("omega0", omega0)?,
            gamma: non_negative("gamma", gamma)?,
            mu: non_negative("mu", mu)?,
            amplitude: finite("amplitude", amplitude)?,
            f: positive("f", f)?,
        })
    }
}

/// Parameters of [`ForcedPendulum`], in Jacobian column order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PendulumParam {
    /// Forcing frequency f, Hz.
    F,
    /// Small-amplitude angular frequency ω₀, rad/s.
    Omega0,
    /// Viscous damping γ, s⁻¹.
    Gamma,
    /// Dry friction μ, s⁻².
    Mu,
    /// Forcing amplitude A, s⁻².
    Amplitude,
}

impl Parameter for PendulumParam {
    const ALL: &'static [Self] = &[
        Self::F,
        Self::Omega0,
        Self::Gamma,
        Self::Mu,
        Self::Amplitude,
    ];
    fn name(self) -> &'static str {
        ["f", "omega0", "gamma", "mu", "amplitude"][self as usize]
    }
    fn unit(self) -> &'static str {
        ["Hz", "rad/s", "1/s", "1/s²", "1/s²"][self as usize]
    }
}

impl Parametrised for ForcedPendulum {
    type Param = PendulumParam;
    fn param(&self, p: PendulumParam) -> f64 {
        match p {
            PendulumParam::F => self.f,
            PendulumParam::Omega0 => self.omega0,
            PendulumParam::Gamma => self.gamma,
            PendulumParam::Mu => self.mu,
            PendulumParam::Amplitude => self.amplitude,
        }
    }
    fn with_param(&self, p: PendulumParam, v: f64) -> Result<Self> {
        let mut s = *self;
        match p {
            PendulumParam::F => s.f = positive("f", v)?,
            PendulumParam::Omega0 => s.omega0 = positive("omega0", v)?,
            PendulumParam::Gamma => s.gamma = non_negative("gamma", v)?,
            PendulumParam::Mu => s.mu = non_negative("mu", v)?,
            PendulumParam::Amplitude => s.amplitude = finite("amplitude", v)?,
        }
        Ok(s)
    }
    fn column(&self, p: PendulumParam) -> Option<Column> {
        Some(Column::primary(p as usize))
    }
}

impl DrivenOscillator for ForcedPendulum {
    fn period(&self) -> f64 {
        1.0 / self.f
    }
    fn n_params(&self) -> usize {
        5
    }
    fn param_name(&self, k: usize) -> &'static str {
        PendulumParam::ALL.get(k).map(|p| p.name()).unwrap_or("?")
    }
    fn period_derivative(&self, k: usize) -> f64 {
        if k == 0 {
            -1.0 / (self.f * self.f)
        } else {
            0.0
        }
    }
    fn forces(&self, t: f64, th: f64, v: f64) -> Forces {
        Forces {
            a: self.amplitude * (TAU * self.f * t).cos()
                - self.gamma * v
                - self.omega0 * self.omega0 * th.sin(),
            r: self.mu,
        }
    }
    fn forces_jet(&self, t: f64, th: f64, v: f64, params: bool) -> ForcesJet {
        let (s, c) = (TAU * self.f * t).sin_cos();
        let (st, ct) = th.sin_cos();
        let w2 = self.omega0 * self.omega0;
        let mut j = ForcesJet::new(self.amplitude * c - self.gamma * v - w2 * st, self.mu);
        j.a_beta = -w2 * ct;
        j.a_omega = -self.gamma;
        if params {
            j.a_p[0] = -self.amplitude * s * TAU * t;
            j.a_p[1] = -2.0 * self.omega0 * st;
            j.a_p[2] = -v;
            j.r_p[3] = 1.0;
            j.a_p[4] = c;
        }
        j
    }
    fn half_period_symmetry(&self) -> Option<HalfPeriodSymmetry> {
        Some(HalfPeriodSymmetry {
            sign: -1.0,
            shift: 0.0,
        })
    }
}
