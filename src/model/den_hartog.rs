//! Den Hartog's closed-form steady state of the harmonically forced oscillator with Coulomb and
//! viscous friction ([`CoulombOscillator`]), for continuous motion (no stops), and the forcing
//! frequency where stops begin (Den Hartog 1931, Phil. Mag. 9, 801–817).
//!
//! Equation: ẍ + 2ξω₀ẋ + ω₀²x + μ sgn(ẋ) = F cos Ωt, Ω = 2πf. A continuous (non-stop) steady state
//! is odd-symmetric, x(t + T/2) = −x(t), and reverses twice per period. Counting time s = t − t₀
//! from the lower reversal x = −X, on the upward half period 0 ≤ s ≤ π/Ω the equation is linear,
//! ẍ + 2ξω₀ẋ + ω₀²x = F cos(Ωs + ψ) − μ with ψ = Ωt₀, and
//!
//! ```text
//!   x(s) = a cos Ωs + b sin Ωs − μ/ω₀² + e^{−ξω₀s} (C₁ cos ω_d s + C₂ sin ω_d s),
//!   a = R cos(ψ − θ),  b = −R sin(ψ − θ),  R = F / √((ω₀² − Ω²)² + (2ξω₀Ω)²),
//!   θ = atan2(2ξω₀Ω, ω₀² − Ω²),  ω_d = ω₀ √(1 − ξ²).
//! ```
//!
//! Den Hartog's four conditions x(0) = −X, ẋ(0) = 0, x(π/Ω) = X, ẋ(π/Ω) = 0 are linear in
//! (a, b, C₁, C₂) for given X, so (a, b) = p + X q; the amplitude X is the positive root of
//! |p + X q|² = R² and the phase follows from (a, b). For ξ = 0 this is Den Hartog's
//! x₀/(F/ω₀²) = √(V² − (μ/F)² U²) with V = 1/(1 − r²), U = sin(π/r) / (r (1 + cos(π/r))),
//! r = Ω/ω₀ ([`den_hartog_coulomb_amplitude`]); the tests check the two against each other.
//!
//! The solution is a motion without stops as long as the mass, at rest at a reversal, is pulled on
//! at once: the smooth force there exceeds the friction, F cos ψ + ω₀² X > μ (numerics.md: crossing
//! when |a| > r on Σ). Where F cos ψ + ω₀² X = μ the reversal becomes tangential and stops begin
//! ([`NonStopOrbit::reversal_margin`], [`stop_boundary_frequency`]).

use super::oscillators::CoulombOscillator;
use crate::error::{Error, Result};
use crate::numerics::newton::solve;
use crate::numerics::Illinois;
use nalgebra::{Matrix4, Vector4};
use std::f64::consts::{PI, TAU};

/// The continuous-motion steady state of a [`CoulombOscillator`] in closed form.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NonStopOrbit {
    /// Amplitude X: the displacement at the reversals is ±X.
    pub amplitude: f64,
    /// Drive phase ψ = Ωt₀ ∈ [0, 2π) at the lower reversal x = −X.
    pub phase: f64,
    /// F cos ψ + ω₀² X − μ: the net force beyond friction at a reversal; stops begin where it is 0.
    pub reversal_margin: f64,
    omega: f64,
    omega0: f64,
    xi: f64,
    mu: f64,
    coef: [f64; 4],
}

impl NonStopOrbit {
    /// True if the closed form is a motion without stops: positive reversal margin and no velocity
    /// reversal inside a half period ([`NonStopOrbit::interior_velocity_min`] > 0).
    pub fn is_valid(&self) -> bool {
        self.reversal_margin > 0.0 && self.interior_velocity_min().1 > 0.0
    }

    /// Smallest ẋ on the open upward half period divided by the largest, both located as in
    /// [`NonStopOrbit::interior_velocity_min`]: negative if the velocity reverses inside the half
    /// period (the closed form then does not describe the motion), −1 if ẋ ≤ 0 throughout.
    pub fn min_velocity_ratio(&self) -> f64 {
        let vmin = self.interior_velocity_min().1;
        let vmax = -self.interior_extremum(-1.0).1;
        if vmax > 0.0 {
            vmin / vmax
        } else {
            -1.0
        }
    }

    /// (x, ẋ) at time s after the lower reversal, 0 ≤ s ≤ T/2.
    fn upward(&self, s: f64) -> [f64; 2] {
        let [a, b, c1, c2] = self.coef;
        let (w, k) = (self.omega, self.xi * self.omega0);
        let wd = self.omega0 * (1.0 - self.xi * self.xi).sqrt();
        let (sw, cw) = (w * s).sin_cos();
        let (sd, cd) = (wd * s).sin_cos();
        let e = (-k * s).exp();
        let x = a * cw + b * sw - self.mu / (self.omega0 * self.omega0) + e * (c1 * cd + c2 * sd);
        let v =
            -a * w * sw + b * w * cw + e * ((-k * c1 + wd * c2) * cd + (-k * c2 - wd * c1) * sd);
        [x, v]
    }

    /// The smallest velocity on the open upward half period, located to 1e-13 of the half period
    /// (a grid of 400 points, then golden-section search around the smallest): (s, ẋ(s)), s after
    /// the lower reversal. Where it is negative the velocity reverses inside the half period: a
    /// stop begins there before the reversal becomes tangential (an interior grazing).
    pub fn interior_velocity_min(&self) -> (f64, f64) {
        self.interior_extremum(1.0)
    }

    /// The minimum of `sign`·ẋ on the open upward half period (`sign` = −1: the maximum of ẋ, as
    /// (s, −ẋ(s))): a grid of 400 points, then golden-section search around the smallest.
    fn interior_extremum(&self, sign: f64) -> (f64, f64) {
        let h = PI / self.omega;
        let v = |s: f64| sign * self.upward(s)[1];
        let n = 400;
        let (mut best, mut vbest) = (1, f64::INFINITY);
        for i in 1..n {
            let vi = v(h * i as f64 / n as f64);
            if vi < vbest {
                (best, vbest) = (i, vi);
            }
        }
        let (mut a, mut b) = (
            h * (best - 1) as f64 / n as f64,
            h * (best + 1) as f64 / n as f64,
        );
        let g = 0.5 * (5f64.sqrt() - 1.0);
        while b - a > 1e-13 * h {
            let (c, d) = (b - g * (b - a), a + g * (b - a));
            if v(c) < v(d) {
                b = d;
            } else {
                a = c;
            }
        }
        let s = 0.5 * (a + b);
        (s, v(s))
    }

    /// The state (x, ẋ) at time t of the steady state (t = 0 is the stroboscopic section).
    pub fn state(&self, t: f64) -> [f64; 2] {
        let period = TAU / self.omega;
        let t0 = self.phase / self.omega;
        let s = (t - t0).rem_euclid(period);
        if s <= 0.5 * period {
            self.upward(s)
        } else {
            let [x, v] = self.upward(s - 0.5 * period);
            [-x, -v]
        }
    }
}

/// The closed-form continuous-motion steady state of `osc` (see the module docs). Fails if ξ ≥ 1,
/// if the boundary conditions are singular, or if no amplitude solves |p + X q| = R (friction too
/// large for a motion without stops).
pub fn non_stop_orbit(osc: &CoulombOscillator) -> Result<NonStopOrbit> {
    let (w0, xi, mu, force) = (osc.omega0, osc.xi, osc.mu, osc.force);
    if xi >= 1.0 {
        return Err(Error::OutsideClosedForm {
            closed_form: "Den Hartog's closed form",
            needs: format!("an underdamped oscillator (ξ < 1), not ξ = {xi}"),
        });
    }
    let w = TAU * osc.f;
    let (k, wd) = (xi * w0, w0 * (1.0 - xi * xi).sqrt());
    let tau = PI / w;
    let e = (-k * tau).exp();
    let (sd, cd) = (wd * tau).sin_cos();
    let r_amp = force.abs() / ((w0 * w0 - w * w).powi(2) + (2.0 * xi * w0 * w).powi(2)).sqrt();
    let theta = (2.0 * xi * w0 * w).atan2(w0 * w0 - w * w);
    // rows: x(0) = −X, ẋ(0) = 0, x(τ) = X, ẋ(τ) = 0 in the unknowns (a, b, C₁, C₂)
    let m = Matrix4::new(
        1.0,
        0.0,
        1.0,
        0.0,
        0.0,
        w,
        -k,
        wd,
        -1.0,
        0.0,
        e * cd,
        e * sd,
        0.0,
        -w,
        e * (-k * cd - wd * sd),
        e * (wd * cd - k * sd),
    );
    let st = mu / (w0 * w0);
    let singular = || Error::OutsideClosedForm {
        closed_form: "Den Hartog's closed form",
        needs: format!("regular boundary conditions (Ω ≠ ω_d/(2n+1)), not Ω = {w}"),
    };
    let p = solve(&m, &Vector4::new(st, 0.0, st, 0.0)).ok_or_else(singular)?;
    let q = solve(&m, &Vector4::new(-1.0, 0.0, 1.0, 0.0)).ok_or_else(singular)?;
    // |p + X q|² = R² for the (a, b) components
    let qa = q[0] * q[0] + q[1] * q[1];
    let qb = 2.0 * (p[0] * q[0] + p[1] * q[1]);
    let qc = p[0] * p[0] + p[1] * p[1] - r_amp * r_amp;
    let disc = qb * qb - 4.0 * qa * qc;
    if disc < 0.0 || qa == 0.0 {
        return Err(Error::OutsideClosedForm {
            closed_form: "Den Hartog's motion without stops",
            needs: "a friction small enough for this forcing (no real amplitude)".into(),
        });
    }
    let x_amp = (-qb + disc.sqrt()) / (2.0 * qa);
    if x_amp <= 0.0 {
        return Err(Error::OutsideClosedForm {
            closed_form: "Den Hartog's motion without stops",
            needs: format!("a positive amplitude, not X = {x_amp}"),
        });
    }
    let z = p + q * x_amp;
    let (a, b) = (z[0], z[1]);
    // F cos(Ωs + ψ) with a = R cos(ψ − θ), b = −R sin(ψ − θ); F < 0 is F > 0 shifted by π
    let shift = if force < 0.0 { PI } else { 0.0 };
    let phase = (theta + (-b).atan2(a) + shift).rem_euclid(TAU);
    Ok(NonStopOrbit {
        amplitude: x_amp,
        phase,
        reversal_margin: force * phase.cos() + w0 * w0 * x_amp - mu,
        omega: w,
        omega0: w0,
        xi,
        mu,
        coef: [a, b, z[2], z[3]],
    })
}

/// Den Hartog's amplitude for Coulomb friction alone (ξ = 0):
/// X = (F/ω₀²) √(V² − (μ/F)² U²), V = 1/(1 − r²), U = sin(π/r) / (r (1 + cos(π/r))), r = Ω/ω₀.
/// `None` where the root is imaginary (stops) or U is singular.
pub fn den_hartog_coulomb_amplitude(osc: &CoulombOscillator) -> Option<f64> {
    let r = TAU * osc.f / osc.omega0;
    let v = 1.0 / (1.0 - r * r);
    let u = (PI / r).sin() / (r * (1.0 + (PI / r).cos()));
    let h = v * v - (osc.mu / osc.force).powi(2) * u * u;
    (h >= 0.0 && h.is_finite()).then(|| osc.force.abs() / (osc.omega0 * osc.omega0) * h.sqrt())
}

/// Den Hartog's boundary of motion without stops for Coulomb friction alone (ξ = 0): the friction
/// ratio μ/F at which stops begin for the frequency ratio r = Ω/ω₀,
///
/// ```text
///   (μ/F)_stop = |V| / √(U² + r⁻⁴),   V = 1/(1 − r²),   U = tan(π/(2r)) / r,
/// ```
///
/// (U is Den Hartog's sin(π/r) / (r (1 + cos(π/r)))). It follows from his solution alone: with
/// ξ = 0 the reversal conditions give X = −R cos ψ and R sin ψ = (μ/ω₀²) U (R = FV/ω₀²), so the
/// tangency F cos ψ + ω₀² X = μ at the reversal becomes X = μ/(ω₀² r²), and with X² = R² − (μU/ω₀²)²
/// the formula above. Its limit at resonance, π/4, is Den Hartog's classical bound. `None` where U
/// is singular (r = 1/(2k+1)) or r is not positive.
pub fn den_hartog_coulomb_stop_ratio(r: f64) -> Option<f64> {
    if r.is_nan() || r <= 0.0 || (r - 1.0).abs() < 1e-12 {
        return None;
    }
    let v = 1.0 / (1.0 - r * r);
    let u = (PI / (2.0 * r)).tan() / r;
    let q = v.abs() / (u * u + r.powi(-4)).sqrt();
    q.is_finite().then_some(q)
}

/// The forcing frequency in [f_lo, f_hi] where stops begin: the zero of the reversal margin
/// F cos ψ + ω₀² X − μ of the closed form, by Illinois regula falsi to `tol` in f. The margin
/// must change sign on the interval.
pub fn stop_boundary_frequency(
    osc: &CoulombOscillator,
    f_lo: f64,
    f_hi: f64,
    tol: f64,
) -> Result<f64> {
    let margin = |f: f64| -> Result<f64> {
        let o = CoulombOscillator { f, ..*osc };
        Ok(non_stop_orbit(&o)?.reversal_margin)
    };
    let (m_lo, m_hi) = (margin(f_lo)?, margin(f_hi)?);
    if m_lo.signum() == m_hi.signum() {
        return Err(Error::NotBracketed {
            what: "the reversal margin",
            lo: f_lo,
            hi: f_hi,
            f_lo: m_lo,
            f_hi: m_hi,
        });
    }
    // orient: the low end of the root finder is where the margin is positive
    let (a, fa, b, fb) = if m_lo > 0.0 {
        (f_lo, m_lo, f_hi, m_hi)
    } else {
        (f_hi, m_hi, f_lo, m_lo)
    };
    let mut root = Illinois::new(a, fa, b, fb, 0.0);
    while (root.hi() - root.lo()).abs() > tol {
        let Some(f) = root.next_point() else {
            break;
        };
        root.update(f, margin(f)?);
    }
    Ok(0.5 * (root.lo() + root.hi()))
}
