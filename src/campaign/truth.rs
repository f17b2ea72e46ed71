//! The campaign's truth model: the gear's equation of motion with composable extra terms in forms
//! the diagnosis catalog does not contain. Per unit output inertia (all terms in s⁻²):
//!
//! β̈ = g B(α_m, β) + Σ_k A_k sin(k β − φ_k) − ζ β̇ − c |β̇|^p sgn β̇ − c_t tanh(β̇/v₀) |β̇|
//!      − sgn(β̇) R(α_m, β, β̇),
//!
//! - B(α, β) = −sin α cos β + Δ cos α sin β, Δ = cos Θ cos Φ − 2 sin Θ sin Φ (eq. `tauax`, with
//!   the true shaft angles, which may be non-parallel);
//! - α_m, the input magnet's angle: the drive angle α_d, or with a compliant input the root of
//!   α_m = α_d + L (−cos α_m sin β + Δ sin α_m cos β) (the magnet turned by its own magnetic
//!   torque against a torsional spring; L = c/k, the lag at the peak coupling torque);
//! - R = η [(1 − λ) + λ |P(W + F(α_m, β))| / |W|] (1 + ε cos 2β) + Δη_s exp(−(β̇/w)²): Coulomb
//!   friction with a fraction λ proportional to the radial bearing load (weight W plus the
//!   dipole–dipole force F on the output magnet, added as vectors, projected perpendicular to the
//!   output shaft by P; with the set-up tilted by ψ about the output shaft the weight points along
//!   −(cos ψ ẑ + sin ψ n̂), n̂ = ẑ × e), modulated by angle (ε), and a Stribeck breakaway excess
//!   Δη_s of width w (Gaussian exp(−(β̇/w)²), or Lorentzian 1/(1 + (β̇/w)²)).
//!   At rest the friction bound is R(α_m, β, 0) (Filippov stick rule |smooth part| ≤ R).

use std::f64::consts::PI;

/// Standard gravity, m/s².
const G0: f64 = 9.806_65;

/// Vector bearing load: a fraction of the Coulomb friction proportional to |P(W + F)|.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VectorLoad {
    /// Fraction λ of the friction that is load-dependent, in [0, 1].
    pub fraction: f64,
    /// |W| / F₀ with F₀ = 3 μ0 m1 m2 / (4π r⁴), the scale of the dipole force.
    pub weight_over_force: f64,
    /// Tilt ψ of the set-up about the output shaft axis, rad (0: shafts horizontal).
    pub tilt: f64,
}

/// Shape of the Stribeck decay.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StribeckShape {
    /// exp(−(β̇/w)²).
    Gaussian,
    /// 1/(1 + (β̇/w)²).
    Lorentzian,
}

/// Drag c_t tanh(β̇/v₀) |β̇|: quadratic below v₀, linear above.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TanhDrag {
    /// Coefficient c_t, s⁻¹.
    pub coef: f64,
    /// Crossover speed v₀, rad/s.
    pub v0: f64,
}

/// Stribeck breakaway: extra friction Δη_s exp(−(β̇/w)²).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stribeck {
    /// Breakaway excess Δη_s, s⁻².
    pub excess: f64,
    /// Decay width w, rad/s.
    pub width: f64,
    /// Shape of the decay.
    pub shape: StribeckShape,
}

/// Power-law drag c |β̇|^p sgn β̇.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PowerDrag {
    /// Coefficient c, rad^(1−p) s^(p−2).
    pub coef: f64,
    /// Exponent p.
    pub exponent: f64,
}

/// The truth: base parameters and the extra terms (all off by default).
#[derive(Debug, Clone, PartialEq)]
pub struct TruthModel {
    /// g = c/I, s⁻².
    pub g: f64,
    /// True input shaft angle Θ, rad.
    pub theta: f64,
    /// True output shaft angle Φ, rad.
    pub phi: f64,
    /// Viscous damping ζ, s⁻¹.
    pub zeta: f64,
    /// Coulomb friction η, s⁻².
    pub eta: f64,
    /// Lab-fixed torques (k, A_k in s⁻², φ_k in rad): Σ A_k sin(k β − φ_k).
    pub harmonics: Vec<(u32, f64, f64)>,
    /// Power-law drag.
    pub power_drag: Option<PowerDrag>,
    /// tanh drag.
    pub tanh_drag: Option<TanhDrag>,
    /// Load-dependent friction.
    pub load: Option<VectorLoad>,
    /// Stribeck breakaway.
    pub stribeck: Option<Stribeck>,
    /// Angle modulation ε of the Coulomb friction.
    pub angle_modulation: f64,
    /// Input compliance: lag L at the peak coupling torque, rad (0 = rigid input).
    pub compliance: f64,
    /// Damping that depends on the drive frequency: a driven run at f Hz has the viscous damping
    /// ζ(1 + k(f − 1 Hz)), k in 1/Hz; the ring-downs keep ζ (applied per run by the generator,
    /// [`TruthModel::for_drive_frequency`]).
    pub zeta_per_hz: f64,
    /// Dry friction that differs by the direction of motion: η(1 + a d) for motion in the
    /// direction d = ±1, with a this value. As a force, −d η(1 + a d) = −d η − a η while sliding,
    /// and the stick band [−η(1 − a), η(1 + a)] of the smooth force is that of η about the
    /// torque −aη: the generator applies it as that constant torque (the same Filippov system).
    pub friction_asymmetry: f64,
    /// Viscous damping modulated by the magnets' relative angle (eddy currents that follow the
    /// field): ζ(1 + ε cos²(α_m − β)) β̇, with ε this value.
    pub zeta_relative: f64,
    /// The driving motor's speed ripple ε, rad ([`Drive::ripple`]; the recorded α shows it).
    pub drive_ripple: f64,
    /// Dry friction falling as the bearings warm up over the session: a run whose middle lies at
    /// the session position u ∈ [0, 1] (recording time accumulated over the runs in file order)
    /// has η(1 − a tanh(u/[`WARMING_WIDTH`])), a this value (applied per run by the generator,
    /// [`TruthModel::for_session`]).
    pub warming: f64,
    /// The coupling modulated once per output turn (an output magnet mounted off-centre, so that
    /// the distance to the input magnet changes with β): the coupling torque times
    /// 1 + m cos(β − φ), (m, φ) this value.
    pub coupling_modulation: Option<(f64, f64)>,
    /// A bearing defect: the Coulomb friction times 1 + b exp(−d²/(2w²)) with d the output angle's
    /// distance to β₀ (wrapped to (−π, π]); (b, β₀, w) this value.
    pub friction_bump: Option<(f64, f64, f64)>,
    /// Dry friction that grows with the transmitted magnetic torque: the Coulomb friction times
    /// 1 + k |B(α_m, β)|, B the coupling's shape (−sin α cos β + Δ cos α sin β), k this value.
    pub torque_friction: f64,
}

/// The session position by which the warm-up of [`TruthModel::warming`] is 76 % done (tanh 1).
pub const WARMING_WIDTH: f64 = 0.2;

/// The input: held at α₀ (rate 0) or turned at a mean rate, with a speed ripple of one period
/// per input turn.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Drive {
    /// Drive angle at t = 0, rad.
    pub alpha0: f64,
    /// Mean drive rate α̇, rad/s.
    pub rate: f64,
    /// Amplitude ε of the ripple, rad: α_d(t) = α₀ + α̇ t + ε sin α̇t.
    pub ripple: f64,
}

impl Drive {
    /// α_d(t) = α₀ + α̇ t + ε sin α̇t.
    pub fn angle(&self, t: f64) -> f64 {
        self.alpha0 + self.rate * t + self.ripple_at(self.rate * t)
    }
    /// ε sin x at the uniform drive's advance x = α̇t.
    pub fn ripple_at(&self, x: f64) -> f64 {
        if self.ripple == 0.0 {
            0.0
        } else {
            self.ripple * x.sin()
        }
    }
}

impl TruthModel {
    /// The base model (no extra terms).
    pub fn base(g: f64, theta: f64, phi: f64, zeta: f64, eta: f64) -> Self {
        Self {
            g,
            theta,
            phi,
            zeta,
            eta,
            harmonics: Vec::new(),
            power_drag: None,
            tanh_drag: None,
            load: None,
            stribeck: None,
            angle_modulation: 0.0,
            compliance: 0.0,
            zeta_per_hz: 0.0,
            friction_asymmetry: 0.0,
            zeta_relative: 0.0,
            drive_ripple: 0.0,
            warming: 0.0,
            coupling_modulation: None,
            friction_bump: None,
            torque_friction: 0.0,
        }
    }

    /// The truth of a driven run at `f_hz`: ζ(1 + k(f − 1 Hz)) with k = [`TruthModel::zeta_per_hz`].
    pub fn for_drive_frequency(&self, f_hz: f64) -> Self {
        Self {
            zeta: self.zeta * (1.0 + self.zeta_per_hz * (f_hz - 1.0)),
            ..self.clone()
        }
    }

    /// The truth of a run whose middle lies at the session position `u` ∈ [0, 1]: the dry
    /// friction η(1 − a tanh(u/[`WARMING_WIDTH`])) with a = [`TruthModel::warming`].
    pub fn for_session(&self, u: f64) -> Self {
        Self {
            eta: self.eta * (1.0 - self.warming * (u / WARMING_WIDTH).tanh()),
            ..self.clone()
        }
    }

    /// The true curve in β that the diagnosis's curve of `kind` ([`crate::identification::curve`])
    /// estimates, at the output angle `beta` (rad), s⁻², for a truth whose effect is a curve of
    /// that kind and nothing else depends on the angles: for `friction` the Coulomb friction
    /// η(1 + ε cos 2β)(1 + b exp(−d²/2w²)) of an angle-modulated friction or a bearing defect,
    /// for `torque` the static torque Σ A_k sin(kβ − φ_k). `None` for any other truth (no curve
    /// of the kind, or a load, a Stribeck excess, a warm-up, a torque-dependent friction, a
    /// direction asymmetry, a coupling modulation or an angle-dependent damping beside it).
    pub fn curve(&self, kind: &str, beta: f64) -> Option<f64> {
        let others = self.load.is_some()
            || self.stribeck.is_some()
            || self.warming != 0.0
            || self.torque_friction != 0.0
            || self.friction_asymmetry != 0.0
            || self.coupling_modulation.is_some()
            || self.zeta_relative != 0.0;
        let friction_curve = self.friction_bump.is_some() || self.angle_modulation != 0.0;
        let torque_curve = !self.harmonics.is_empty();
        match kind {
            "friction" if friction_curve && !torque_curve && !others => {
                let bump = self.friction_bump.map_or(0.0, |(b, b0, w)| {
                    let d = (beta - b0 + PI).rem_euclid(2.0 * PI) - PI;
                    b * (-d * d / (2.0 * w * w)).exp()
                });
                let modulation = 1.0 + self.angle_modulation * (2.0 * beta).cos();
                Some(self.eta * modulation * (1.0 + bump))
            }
            "torque" if torque_curve && !friction_curve && !others => Some(
                self.harmonics
                    .iter()
                    .map(|&(k, amp, ph)| amp * (k as f64 * beta - ph).sin())
                    .sum(),
            ),
            _ => None,
        }
    }

    /// Δ = cos Θ cos Φ − 2 sin Θ sin Φ.
    pub fn delta(&self) -> f64 {
        self.theta.cos() * self.phi.cos() - 2.0 * self.theta.sin() * self.phi.sin()
    }

    /// The magnet angle α_m for drive angle `alpha_d` (Newton on the compliance equation).
    pub fn magnet_angle(&self, alpha_d: f64, beta: f64) -> f64 {
        if self.compliance == 0.0 {
            return alpha_d;
        }
        let (sb, cb) = beta.sin_cos();
        let d = self.delta();
        let mut x = alpha_d;
        for _ in 0..30 {
            let (sx, cx) = x.sin_cos();
            let f = x - alpha_d - self.compliance * (-cx * sb + d * sx * cb);
            let fp = 1.0 - self.compliance * (sx * sb + d * cx * cb);
            let dx = f / fp;
            x -= dx;
            if dx.abs() < 1e-15 {
                break;
            }
        }
        x
    }

    /// The smooth part of β̈ (everything except the friction R): s⁻².
    pub fn smooth(&self, alpha_m: f64, beta: f64, omega: f64) -> f64 {
        let (sa, ca) = alpha_m.sin_cos();
        let (sb, cb) = beta.sin_cos();
        let modulation = self
            .coupling_modulation
            .map_or(1.0, |(m, ph)| 1.0 + m * (beta - ph).cos());
        let mut a = self.g * modulation * (-sa * cb + self.delta() * ca * sb) - self.zeta * omega;
        a -= self.friction_asymmetry * self.eta;
        if self.zeta_relative != 0.0 {
            a -= self.zeta * self.zeta_relative * (alpha_m - beta).cos().powi(2) * omega;
        }
        for &(k, amp, ph) in &self.harmonics {
            a += amp * (k as f64 * beta - ph).sin();
        }
        if let Some(pd) = self.power_drag {
            a -= pd.coef * omega.abs().powf(pd.exponent) * omega.signum();
        }
        if let Some(td) = self.tanh_drag {
            a -= td.coef * (omega / td.v0).tanh() * omega.abs();
        }
        a
    }

    /// Friction magnitude R(α_m, β, β̇) ≥ 0, s⁻²; R(α_m, β, 0) is the static bound.
    pub fn friction(&self, alpha_m: f64, beta: f64, omega: f64) -> f64 {
        let mut coulomb = self.eta;
        if let Some(l) = self.load {
            let ratio =
                self.radial_load(alpha_m, beta, l.weight_over_force, l.tilt) / l.weight_over_force;
            coulomb *= (1.0 - l.fraction) + l.fraction * ratio;
        }
        coulomb *= 1.0 + self.angle_modulation * (2.0 * beta).cos();
        if let Some((b, b0, w)) = self.friction_bump {
            let d = (beta - b0 + PI).rem_euclid(2.0 * PI) - PI;
            coulomb *= 1.0 + b * (-d * d / (2.0 * w * w)).exp();
        }
        if self.torque_friction != 0.0 {
            let (sa, ca) = alpha_m.sin_cos();
            let (sb, cb) = beta.sin_cos();
            coulomb *= 1.0 + self.torque_friction * (-sa * cb + self.delta() * ca * sb).abs();
        }
        if let Some(s) = self.stribeck {
            let x = (omega / s.width).powi(2);
            coulomb += s.excess
                * match s.shape {
                    StribeckShape::Gaussian => (-x).exp(),
                    StribeckShape::Lorentzian => 1.0 / (1.0 + x),
                };
        }
        coulomb.max(0.0)
    }

    /// The dipole–dipole force on the output magnet in units of F₀ = 3 μ0 m1 m2 / (4π r⁴), x̂
    /// along the centre line from the input to the output magnet:
    /// F/F₀ = (m̂1·x̂) m̂2 + (m̂2·x̂) m̂1 + (m̂1·m̂2) x̂ − 5 (m̂1·x̂)(m̂2·x̂) x̂.
    pub fn dipole_force(&self, alpha_m: f64, beta: f64) -> [f64; 3] {
        let (st, ct) = self.theta.sin_cos();
        let (sp, cp) = self.phi.sin_cos();
        let (sa, ca) = alpha_m.sin_cos();
        let (sb, cb) = beta.sin_cos();
        let m1 = [-ca * st, ca * ct, sa];
        let m2 = [-cb * sp, cb * cp, sb];
        let (m1x, m2x) = (m1[0], m2[0]);
        let m12 = m1[0] * m2[0] + m1[1] * m2[1] + m1[2] * m2[2];
        let mut f = [0.0; 3];
        for i in 0..3 {
            f[i] = m1x * m2[i] + m2x * m1[i];
        }
        f[0] += m12 - 5.0 * m1x * m2x;
        f
    }

    /// |P(W + F)| / F₀: the radial bearing load in units of the dipole force scale, shafts in the
    /// x-y plane, weight along −(cos ψ ẑ + sin ψ n̂) with n̂ = ẑ × e = (−sin Φ, cos Φ, 0) (ψ = 0:
    /// horizontal shafts), P the projection perpendicular to the output shaft axis
    /// e = (cos Φ, sin Φ, 0).
    pub fn radial_load(&self, alpha_m: f64, beta: f64, weight_over_force: f64, tilt: f64) -> f64 {
        let mut l = self.dipole_force(alpha_m, beta);
        let (sp, cp) = self.phi.sin_cos();
        let (st, ct) = tilt.sin_cos();
        l[0] += weight_over_force * st * sp;
        l[1] -= weight_over_force * st * cp;
        l[2] -= weight_over_force * ct;
        let le = l[0] * cp + l[1] * sp;
        let p = [l[0] - le * cp, l[1] - le * sp, l[2]];
        (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt()
    }

    /// The equilibrium of the coupling alone at a locked magnet angle α: the minimum of the
    /// field energy, tan β = tan α / Δ on the stable branch.
    pub fn coupling_equilibrium(&self, alpha: f64) -> f64 {
        let d = self.delta();
        // U ∝ sin α sin β + Δ cos α cos β = ρ cos(β − ψ); minimum at β = ψ + π
        alpha.sin().atan2(d * alpha.cos()) + PI
    }
}

/// |W| / F₀ for a shaft of mass `mass` (kg) and dipoles m1, m2 (A m²) at distance r (m).
pub fn weight_over_force(mass: f64, m1: f64, m2: f64, r: f64) -> f64 {
    let f0 = 3.0 * crate::model::gear::MU0_OVER_4PI * m1 * m2 / r.powi(4);
    mass * G0 / f0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The force formula against −∇(−m2·B1) by central differences, B1 the dipole field
    /// (μ0/4π)(3(m1·r̂)r̂ − m1)/r³; and the coupling torque against −∂U/∂β.
    #[test]
    fn dipole_force_and_torque_are_gradients_of_the_energy() {
        let m = TruthModel::base(300.0, 0.4, -0.7, 1.0, 20.0);
        let (a, b): (f64, f64) = (0.9, -2.1);
        let (st, ct) = m.theta.sin_cos();
        let (sp, cp) = m.phi.sin_cos();
        let m1 = [-a.cos() * st, a.cos() * ct, a.sin()];
        let m2 = |b: f64| [-b.cos() * sp, b.cos() * cp, b.sin()];
        // energy of m2 at position r in the field of m1 (units μ0/4π = 1, |m| = 1)
        let energy = |r: [f64; 3], mm2: [f64; 3]| {
            let rn = (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt();
            let u = [r[0] / rn, r[1] / rn, r[2] / rn];
            let m1u = m1[0] * u[0] + m1[1] * u[1] + m1[2] * u[2];
            let bf: Vec<f64> = (0..3)
                .map(|i| (3.0 * m1u * u[i] - m1[i]) / rn.powi(3))
                .collect();
            -(mm2[0] * bf[0] + mm2[1] * bf[1] + mm2[2] * bf[2])
        };
        let f = m.dipole_force(a, b);
        let h = 1e-5;
        for i in 0..3 {
            let mut rp = [1.0, 0.0, 0.0];
            let mut rm = [1.0, 0.0, 0.0];
            rp[i] += h;
            rm[i] -= h;
            // F = −∂U/∂r; F₀ = 3 at r = 1
            let fd = -(energy(rp, m2(b)) - energy(rm, m2(b))) / (2.0 * h) / 3.0;
            assert!((fd - f[i]).abs() < 1e-8, "component {i}: {fd} vs {}", f[i]);
        }
        // torque: −∂U/∂β with U = −m2·B1 at r = x̂ equals c (−sin α cos β + Δ cos α sin β), c = 1
        let dudb =
            (energy([1.0, 0.0, 0.0], m2(b + h)) - energy([1.0, 0.0, 0.0], m2(b - h))) / (2.0 * h);
        let tau = -a.sin() * b.cos() + m.delta() * a.cos() * b.sin();
        assert!((-dudb - tau).abs() < 1e-8, "{} vs {tau}", -dudb);
    }

    /// The truth's radial load of a set-up tilted by ψ (its own force and tilt formulas) is the
    /// diagnosis's load family at the weight (ρ cos ψ, ρ sin ψ): two implementations of the same
    /// geometry agree, so a tilted bearing load lies inside the family.
    #[test]
    fn a_tilted_load_is_the_family_at_the_rotated_weight() {
        use crate::identification::model::{load_shape, Geometry};
        let m = TruthModel::base(300.0, 0.4, -0.7, 1.0, 20.0);
        let geo = Geometry::new(m.theta, m.phi);
        for k in 0..12 {
            let (a, b) = (0.53 * k as f64, 1.7 - 0.61 * k as f64);
            for (rho, psi) in [(0.7, 0.0), (2.3, 0.52), (1.1, -1.3), (4.0, 2.9)] {
                let t = m.radial_load(a, b, rho, psi);
                let f = load_shape(&geo, a, b, [rho * psi.cos(), rho * psi.sin()], true);
                assert!((t - f).abs() < 1e-12, "{a} {b} {rho} {psi}: {t} vs {f}");
            }
        }
    }
}
