//! The paper's classification (Fig. 5): a multi-harmonic least-squares fit of δ over α
//! (eq. `d_harm`), the RMS of its residual (eq. `rms`), the total harmonic distortion THD_F
//! (eq. `thd`, both the standard and the printed definition) and the flowchart
//! (RMS > 20° → chaotic, THD_F > 1 → T/2, else T).
//!
//! All angles are in **degrees** here, as in the paper: the RMS threshold of 20 is in degrees,
//! and the printed THD (denominator a₁² + b₁², not its square root) is not scale invariant.

use crate::error::{Error, Result};
use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

/// Number of harmonics of the paper's fit (eq. `d_harm`: i = 1..7).
pub const PAPER_HARMONICS: usize = 7;
/// The paper's chaos threshold on the fit residual, degrees.
pub const PAPER_RMS_THRESHOLD: f64 = 20.0;
/// The paper's T/2 threshold on THD_F.
pub const PAPER_THD_THRESHOLD: f64 = 1.0;

/// Harmonic amplitudes below this (degrees) count as zero: δ is flat.
pub const FLAT_AMPLITUDE: f64 = 1e-6;

/// A harmonic fit δ_harm(α) = b₀ + Σ_{i=1..n} aᵢ sin iα + bᵢ cos iα (eq. `d_harm`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HarmonicFit {
    /// Constant term b₀.
    pub b0: f64,
    /// Sine coefficients a₁..aₙ.
    pub a: Vec<f64>,
    /// Cosine coefficients b₁..bₙ.
    pub b: Vec<f64>,
    /// RMS of δ − δ_harm over the fitted samples (eq. `rms`).
    pub rms: f64,
}

impl HarmonicFit {
    /// Number of harmonics n.
    pub fn harmonics(&self) -> usize {
        self.a.len()
    }

    /// δ_harm(α).
    pub fn eval(&self, alpha: f64) -> f64 {
        let mut v = self.b0;
        for i in 0..self.a.len() {
            let (s, c) = ((i + 1) as f64 * alpha).sin_cos();
            v += self.a[i] * s + self.b[i] * c;
        }
        v
    }

    /// Amplitude √(aᵢ² + bᵢ²) of harmonic i (1-based).
    pub fn amplitude(&self, i: usize) -> f64 {
        if i == 0 || i > self.a.len() {
            return 0.0;
        }
        self.a[i - 1].hypot(self.b[i - 1])
    }

    /// √(Σ_{i≥2} aᵢ² + bᵢ²): the combined amplitude of the higher harmonics.
    fn higher(&self) -> f64 {
        (2..=self.a.len())
            .map(|i| self.amplitude(i).powi(2))
            .sum::<f64>()
            .sqrt()
    }

    /// True if no harmonic exceeds [`FLAT_AMPLITUDE`]: δ is constant (a locked orbit at Δ = ±1);
    /// the THD is then reported as 0 (the ratio of rounding noise would be meaningless).
    pub fn is_flat(&self) -> bool {
        (1..=self.a.len()).all(|i| self.amplitude(i) < FLAT_AMPLITUDE)
    }

    /// THD_F with the standard denominator √(a₁² + b₁²) (Shmilovitz); +∞ when the fundamental
    /// vanishes exactly and the higher harmonics do not, 0 for a flat δ ([`Self::is_flat`]).
    pub fn thd(&self) -> f64 {
        if self.is_flat() {
            return 0.0;
        }
        ratio(self.higher(), self.amplitude(1))
    }

    /// THD_F as printed in the paper's eq. `thd` (denominator a₁² + b₁², δ in degrees).
    pub fn thd_printed(&self) -> f64 {
        if self.is_flat() {
            return 0.0;
        }
        ratio(self.higher(), self.amplitude(1).powi(2))
    }
}

fn ratio(num: f64, den: f64) -> f64 {
    if den > 0.0 {
        num / den
    } else if num > 0.0 {
        f64::INFINITY
    } else {
        0.0
    }
}

/// Least-squares fit of `n` harmonics to samples (αₖ, δₖ) (radians for α, any unit for δ).
///
/// Solved by an SVD of the design matrix, so any sampling works; errors on fewer than 2n + 1
/// samples, non-finite data or a rank-deficient design.
///
/// ```
/// use gearbif::analysis::harmonic::fit_harmonics;
/// let alpha: Vec<f64> = (0..100).map(|k| k as f64 * 0.0628).collect();
/// let delta: Vec<f64> = alpha.iter().map(|a| 180.0 + 3.0 * a.sin() + 1.5 * (2.0 * a).cos()).collect();
/// let fit = fit_harmonics(&alpha, &delta, 7).unwrap();
/// assert!((fit.a[0] - 3.0).abs() < 1e-9 && (fit.b[1] - 1.5).abs() < 1e-9);
/// assert!((fit.thd() - 0.5).abs() < 1e-9);
/// ```
pub fn fit_harmonics(alpha: &[f64], delta: &[f64], n: usize) -> Result<HarmonicFit> {
    if alpha.len() != delta.len() {
        return Err(Error::shape(
            "harmonic fit: values",
            format!("{} (one per angle)", alpha.len()),
            delta.len(),
        ));
    }
    let m = alpha.len();
    let p = 2 * n + 1;
    if n == 0 || m < p {
        return Err(Error::shape(
            format!("harmonic fit of {n} harmonics: samples"),
            format!(">= {p} and n >= 1"),
            m,
        ));
    }
    if alpha.iter().chain(delta).any(|v| !v.is_finite()) {
        let (a, d) = alpha
            .iter()
            .zip(delta)
            .find(|(a, d)| !(a.is_finite() && d.is_finite()))
            .map(|(&a, &d)| (a, d))
            .unwrap_or((f64::NAN, f64::NAN));
        return Err(Error::NonFiniteState {
            what: "harmonic fit sample (angle, value)",
            state: vec![a, d],
        });
    }
    let mut x = DMatrix::<f64>::zeros(m, p);
    for (k, &al) in alpha.iter().enumerate() {
        x[(k, 0)] = 1.0;
        for i in 1..=n {
            let (s, c) = (i as f64 * al).sin_cos();
            x[(k, 2 * i - 1)] = s;
            x[(k, 2 * i)] = c;
        }
    }
    let y = DVector::from_column_slice(delta);
    let svd = x.clone().svd(true, true);
    let smax = svd.singular_values.max();
    let smin = svd.singular_values.min();
    if smin.is_nan() || smin <= 1e-10 * smax {
        return Err(Error::option(
            "harmonic fit angles",
            format!("do not determine all {n} harmonics (too few distinct angles)"),
        ));
    }
    let coef = svd
        .solve(&y, 1e-12 * smax)
        .map_err(|e| Error::option("harmonic fit", e.to_string()))?;
    let resid = &y - &x * &coef;
    let rms = (resid.norm_squared() / m as f64).sqrt();
    Ok(HarmonicFit {
        b0: coef[0],
        a: (1..=n).map(|i| coef[2 * i - 1]).collect(),
        b: (1..=n).map(|i| coef[2 * i]).collect(),
        rms,
    })
}

/// Amplitude of the DFT bin at `cycles` cycles per window of a uniformly sampled signal:
/// 2|Xₖ|/N (the amplitude of a sinusoid with exactly `cycles` periods in the window).
/// Independent of [`fit_harmonics`]; on whole-turn uniform sampling the two agree.
pub fn dft_amplitude(x: &[f64], cycles: usize) -> f64 {
    let n = x.len();
    if n == 0 {
        return 0.0;
    }
    let (mut re, mut im) = (0.0, 0.0);
    for (j, &v) in x.iter().enumerate() {
        let ph = TAU * ((cycles * j) % n) as f64 / n as f64;
        re += v * ph.cos();
        im -= v * ph.sin();
    }
    2.0 * re.hypot(im) / n as f64
}

/// Mean and standard deviation √Var of a sample (RMS_δ of the paper's colour maps, Figs. 7–8).
pub fn mean_std(x: &[f64]) -> (f64, f64) {
    if x.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    let n = x.len() as f64;
    let mean = x.iter().sum::<f64>() / n;
    let var = x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
    (mean, var.sqrt())
}

/// The three classes of the paper's flowchart (Fig. 5).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PaperClass {
    /// RMS > 20°: "chaotic" (circles in Figs. 7–8).
    Chaotic,
    /// THD_F > 1: "T/2 periodicity" (crosses).
    HalfPeriod,
    /// Otherwise: "T periodicity" (dashes).
    Period,
}

impl PaperClass {
    /// Short label: "chaos", "T/2", "T".
    pub fn label(self) -> &'static str {
        match self {
            PaperClass::Chaotic => "chaos",
            PaperClass::HalfPeriod => "T/2",
            PaperClass::Period => "T",
        }
    }
}

/// Which THD definition the flowchart uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ThdDefinition {
    /// √(Σ_{i≥2} aᵢ² + bᵢ²)/√(a₁² + b₁²) (the cited standard definition; default).
    #[default]
    Standard,
    /// √(Σ_{i≥2} aᵢ² + bᵢ²)/(a₁² + b₁²), δ in degrees (as printed in eq. `thd`).
    Printed,
}

/// The paper's metrics of a recorded window of δ (degrees) over α (radians).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PaperMetrics {
    /// The 7-harmonic fit.
    pub fit: HarmonicFit,
    /// RMS of the fit residual, degrees (eq. `rms`).
    pub rms_fit_deg: f64,
    /// THD_F, standard definition.
    pub thd: f64,
    /// THD_F, printed definition (denominator a₁² + b₁², degrees).
    pub thd_printed: f64,
    /// Standard deviation of δ, degrees (RMS_δ of Figs. 7–8).
    pub rms_delta_deg: f64,
    /// Mean of δ, degrees (δ_avg of Figs. 9–10).
    pub delta_avg_deg: f64,
    /// Amplitude of the DFT of δ(t) at the drive frequency, degrees (δ_fund of Fig. 9).
    pub delta_fund_deg: f64,
    /// The flowchart's class (with the THD definition in `thd_definition`).
    pub class: PaperClass,
    /// Which THD the class used.
    pub thd_definition: ThdDefinition,
}

/// Applies the flowchart to a fit: RMS > 20° chaotic, THD > 1 T/2, else T.
pub fn paper_class(fit: &HarmonicFit, def: ThdDefinition) -> PaperClass {
    let thd = match def {
        ThdDefinition::Standard => fit.thd(),
        ThdDefinition::Printed => fit.thd_printed(),
    };
    if fit.rms > PAPER_RMS_THRESHOLD {
        PaperClass::Chaotic
    } else if thd > PAPER_THD_THRESHOLD {
        PaperClass::HalfPeriod
    } else {
        PaperClass::Period
    }
}

/// The paper's metrics of δ sampled uniformly over whole turns: `alpha` (rad), `delta_deg`
/// (degrees), `turns` whole drive periods in the window (used for the DFT bin of δ_fund).
pub fn paper_metrics(
    alpha: &[f64],
    delta_deg: &[f64],
    turns: usize,
    def: ThdDefinition,
) -> Result<PaperMetrics> {
    let fit = fit_harmonics(alpha, delta_deg, PAPER_HARMONICS)?;
    let (avg, sd) = mean_std(delta_deg);
    let class = paper_class(&fit, def);
    Ok(PaperMetrics {
        rms_fit_deg: fit.rms,
        thd: fit.thd(),
        thd_printed: fit.thd_printed(),
        rms_delta_deg: sd,
        delta_avg_deg: avg,
        delta_fund_deg: dft_amplitude(delta_deg, turns),
        fit,
        class,
        thd_definition: def,
    })
}

/// The angle the paper's Figs. 9–10 plot, from δ = β − α in the paper convention (β + 180°):
/// α − β with the physical β, mod 360°, i.e. 180° − δ (model.md, "Erratum"). With it the Θ = 0 lock
/// branch is the paper's eq. `delta_lock`, 180° + arcsin((2πfζ + η)/g): 184.4° at f → 0, rising
/// to 270° at the fold.
pub fn paper_figure_delta_deg(delta_paper_convention_deg: f64) -> f64 {
    (180.0 - delta_paper_convention_deg).rem_euclid(360.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_figure_delta_is_the_papers_delta_lock() {
        // eq. `delta_lock`: 180° + arcsin((2πfζ + η)/g); at f → 0 arcsin(η/g) (184.4° for the paper)
        for f in [1e-3, 10.0, 35.0] {
            let g = crate::model::Gear::paper(0.0, f)
                .unwrap()
                .with_convention(crate::model::Convention::Paper);
            let b = g.lock_branch().unwrap();
            let s = (TAU * f * g.zeta + g.eta) / g.g;
            let want = 180.0 + s.asin().to_degrees();
            let got = paper_figure_delta_deg(b.stable.phase.to_degrees());
            assert!((got - want).abs() < 1e-9, "{f}: {got} vs {want}");
        }
        let at0 = paper_figure_delta_deg(
            crate::model::Gear::paper(0.0, 1e-9)
                .unwrap()
                .with_convention(crate::model::Convention::Paper)
                .lock_branch()
                .unwrap()
                .stable
                .phase
                .to_degrees(),
        );
        assert!((at0 - 184.4).abs() < 0.05, "{at0}");
    }

    fn grid(turns: usize, per: usize) -> Vec<f64> {
        (0..turns * per)
            .map(|k| TAU * k as f64 / per as f64)
            .collect()
    }

    #[test]
    fn recovers_coefficients_and_flowchart() {
        let al = grid(10, 50);
        // T/2-type signal: only even harmonics -> THD enormous (fundamental at rounding level) -> T/2
        let d: Vec<f64> = al.iter().map(|a| 200.0 + 5.0 * (2.0 * a).sin()).collect();
        let m = paper_metrics(&al, &d, 10, ThdDefinition::Standard).unwrap();
        assert!(m.rms_fit_deg < 1e-9);
        assert!(m.thd > 1e6);
        assert_eq!(m.class, PaperClass::HalfPeriod);
        assert!(m.delta_fund_deg < 1e-9);
        // T-type: fundamental dominates
        let d: Vec<f64> = al
            .iter()
            .map(|a| 200.0 + 8.0 * a.cos() + 2.0 * (3.0 * a).sin())
            .collect();
        let m = paper_metrics(&al, &d, 10, ThdDefinition::Standard).unwrap();
        assert!((m.thd - 0.25).abs() < 1e-12);
        assert!((m.thd_printed - 2.0 / 64.0).abs() < 1e-12);
        assert_eq!(m.class, PaperClass::Period);
        // DFT and fit agree on the fundamental
        assert!((m.delta_fund_deg - 8.0).abs() < 1e-9);
        assert!((m.rms_delta_deg - (32.0f64 + 2.0).sqrt()).abs() < 1e-9);
        // printed definition with a small fundamental flips the class
        let d: Vec<f64> = al
            .iter()
            .map(|a| 200.0 + 0.5 * a.cos() + 0.4 * (2.0 * a).sin())
            .collect();
        let fit = fit_harmonics(&al, &d, 7).unwrap();
        assert_eq!(
            paper_class(&fit, ThdDefinition::Standard),
            PaperClass::Period
        );
        assert_eq!(
            paper_class(&fit, ThdDefinition::Printed),
            PaperClass::HalfPeriod
        );
        // an incommensurate component leaves a residual above 20°
        let d: Vec<f64> = al
            .iter()
            .map(|a| 200.0 + 40.0 * (0.6180 * a).sin())
            .collect();
        assert_eq!(
            paper_metrics(&al, &d, 10, ThdDefinition::Standard)
                .unwrap()
                .class,
            PaperClass::Chaotic
        );
    }

    #[test]
    fn bad_input_is_an_error() {
        assert!(fit_harmonics(&[0.0, 1.0], &[1.0, 2.0], 7).is_err());
        assert!(fit_harmonics(&[0.0; 20], &[1.0; 20], 7).is_err());
        let al = grid(1, 50);
        let mut d = vec![1.0; 50];
        d[3] = f64::NAN;
        assert!(fit_harmonics(&al, &d, 7).is_err());
        assert!(fit_harmonics(&al, &d[..10], 7).is_err());
    }
}
