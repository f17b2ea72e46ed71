//! Codimension-two points on a two-parameter curve of codimension-one points, from test functions
//! that change sign along the curve (Kuznetsov, *Elements of Applied Bifurcation Theory*, ch. 9, for
//! fixed points of maps). With μ₁ the critical multiplier of the curve and μ₂ the other one
//! (μ₂ = det M / μ₁):
//!
//! | curve | point | test function |
//! |---|---|---|
//! | fold (μ₁ = 1) | cusp | ⟨∇ₓg, v⟩/‖∇ₓg‖ (the fold's quadratic coefficient, up to a factor) |
//! | fold | fold–flip (μ₂ = −1) | det M + 1 |
//! | fold | 1:1 resonance (μ₂ = 1) | det M − 1 |
//! | flip (μ₁ = −1) | fold–flip (μ₂ = 1) | det M + 1 |
//! | flip | 1:2 resonance (μ₂ = −1) | det M − 1 |
//! | symmetry-breaking (G-multiplier −1) | fold of the symmetric orbit at the SB point (μ₂,G = 1) | det G + 1 |
//! | symmetry-breaking | double −1 of G (1:1 resonance of P_T = R²G²) | det G − 1 |
//! | Neimark–Sacker (det M = 1) | 1:1, 1:2, 1:3, 1:4 resonances | tr M − 2, tr M + 2, tr M + 1, tr M |
//! | grazing (one-sided orbit touches Σ) | fold–grazing (μ = 1) | 1 − tr M + det M |
//! | grazing | flip–grazing (μ = −1; on G: symmetry-breaking–grazing) | 1 + tr M + det M |
//! | any | turning point in either parameter | dλ/ds of the unit tangent |
//!
//! On a fold curve g_x·v = 0 is equivalent to the tangent having no λ-component (the fold equation's
//! row applied to (v, 0, 0)), so at a cusp both dλ₁/ds and dλ₂/ds vanish: the turning points located
//! separately confirm a located cusp. A turning point of a symmetry-breaking curve in the stepped
//! parameter is where the two symmetry-breaking points of a one-parameter branch meet.

use super::SpecialKind;
use crate::orbits::Floquet;
use serde::{Deserialize, Serialize};

/// What kind of codimension-two point (or turning point) was located on a curve.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Codim2Kind {
    /// Cusp of folds: the fold's quadratic coefficient vanishes; two fold curves meet tangentially.
    Cusp,
    /// Fold–flip: multipliers +1 and −1.
    FoldFlip,
    /// On a symmetry-breaking curve: the symmetric orbit also folds (G-multipliers −1 and +1).
    FoldSymmetryBreaking,
    /// Strong resonance 1:1 (double multiplier +1; on a symmetry-breaking curve double −1 of G).
    Resonance1To1,
    /// Strong resonance 1:2 (double multiplier −1).
    Resonance1To2,
    /// Strong resonance 1:3 (multipliers e^{±2πi/3}).
    Resonance1To3,
    /// Strong resonance 1:4 (multipliers ±i).
    Resonance1To4,
    /// On a grazing curve: the grazing orbit also folds (multiplier +1 of the one-sided map).
    FoldGrazing,
    /// On a grazing curve: a multiplier −1 of the one-sided map (on the half-period map G, a
    /// symmetry-breaking point of the grazing orbit).
    FlipGrazing,
    /// The curve turns back in the solved-for parameter.
    TurningFree,
    /// The curve turns back in the other parameter (for symmetry-breaking curves: two
    /// symmetry-breaking points of the one-parameter branch meet).
    TurningAlong,
}

impl Codim2Kind {
    /// Short label for tables and plots.
    pub fn label(self) -> &'static str {
        match self {
            Codim2Kind::Cusp => "cusp",
            Codim2Kind::FoldFlip => "fold-flip",
            Codim2Kind::FoldSymmetryBreaking => "fold-symmetry-breaking",
            Codim2Kind::Resonance1To1 => "1:1 resonance",
            Codim2Kind::Resonance1To2 => "1:2 resonance",
            Codim2Kind::Resonance1To3 => "1:3 resonance",
            Codim2Kind::Resonance1To4 => "1:4 resonance",
            Codim2Kind::FoldGrazing => "fold-grazing",
            Codim2Kind::FlipGrazing => "flip-grazing",
            Codim2Kind::TurningFree => "turning point in the free parameter",
            Codim2Kind::TurningAlong => "turning point in the stepped parameter",
        }
    }
}

/// A located codimension-two point (or turning point) of a curve.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Codim2Point {
    /// Type.
    pub kind: Codim2Kind,
    /// Value of the solved-for parameter.
    pub free: f64,
    /// Value of the other parameter.
    pub along: f64,
    /// State on the section.
    pub x: [f64; 2],
    /// Floquet data.
    pub floquet: Floquet,
    /// The test function at the located point.
    pub test_value: f64,
    /// (dλ_free/ds, dλ_along/ds) of the unit tangent (scaled arclength) at the point.
    pub tangent_lambda: [f64; 2],
    /// Half-width of the final bracket in scaled arclength plus the corrector tolerance.
    pub precision: f64,
    /// Index of the curve point after which it lies.
    pub after_point: usize,
}

/// What the test functions need at one point of the curve.
#[derive(Debug, Clone, Copy)]
pub struct CurveLocal<'a> {
    /// Floquet data of the orbit's map.
    pub floquet: &'a Floquet,
    /// Right null vector v of A (fold, flip and SB curves).
    pub v: [f64; 2],
    /// ∇ₓg of the bordered test function.
    pub grad_x: [f64; 2],
    /// (dλ_free/ds, dλ_along/ds) of the unit tangent.
    pub tangent_lambda: [f64; 2],
}

/// The test functions of the codimension-two points on a curve of `kind` (module doc).
pub fn test_functions(kind: SpecialKind, p: &CurveLocal) -> Vec<(Codim2Kind, f64)> {
    let (det, tr) = (p.floquet.det, p.floquet.trace);
    let mut out = vec![
        (Codim2Kind::TurningFree, p.tangent_lambda[0]),
        (Codim2Kind::TurningAlong, p.tangent_lambda[1]),
    ];
    match kind {
        SpecialKind::Fold => {
            let n = p.grad_x[0].hypot(p.grad_x[1]) * p.v[0].hypot(p.v[1]);
            let cusp = (p.grad_x[0] * p.v[0] + p.grad_x[1] * p.v[1]) / n.max(f64::MIN_POSITIVE);
            out.push((Codim2Kind::Cusp, cusp));
            out.push((Codim2Kind::FoldFlip, det + 1.0));
            out.push((Codim2Kind::Resonance1To1, det - 1.0));
        }
        SpecialKind::Flip => {
            out.push((Codim2Kind::FoldFlip, det + 1.0));
            out.push((Codim2Kind::Resonance1To2, det - 1.0));
        }
        SpecialKind::SymmetryBreaking => {
            out.push((Codim2Kind::FoldSymmetryBreaking, det + 1.0));
            out.push((Codim2Kind::Resonance1To1, det - 1.0));
        }
        SpecialKind::NeimarkSacker => {
            out.push((Codim2Kind::Resonance1To1, tr - 2.0));
            out.push((Codim2Kind::Resonance1To2, tr + 2.0));
            out.push((Codim2Kind::Resonance1To3, tr + 1.0));
            out.push((Codim2Kind::Resonance1To4, tr));
        }
        SpecialKind::Nonsmooth => {
            out.push((Codim2Kind::FoldGrazing, p.floquet.fold_test()));
            out.push((Codim2Kind::FlipGrazing, p.floquet.flip_test()));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Matrix2;

    #[test]
    fn resonance_tests_vanish_at_the_resonant_multipliers() {
        // a rotation by 2π/3 (1:3) and by π/2 (1:4), det = 1
        for (angle, kind) in [
            (std::f64::consts::TAU / 3.0, Codim2Kind::Resonance1To3),
            (std::f64::consts::FRAC_PI_2, Codim2Kind::Resonance1To4),
        ] {
            let (s, c) = angle.sin_cos();
            let fq = Floquet::of(&Matrix2::new(c, -s, s, c));
            let local = CurveLocal {
                floquet: &fq,
                v: [1.0, 0.0],
                grad_x: [0.0, 1.0],
                tangent_lambda: [1.0, 0.0],
            };
            let t = test_functions(SpecialKind::NeimarkSacker, &local);
            let val = t.iter().find(|(k, _)| *k == kind).unwrap().1;
            assert!(val.abs() < 1e-15, "{kind:?}: {val}");
        }
        // fold–flip on a fold curve: multipliers 1 and −1
        let fq = Floquet::of(&Matrix2::new(1.0, 0.0, 0.0, -1.0));
        let local = CurveLocal {
            floquet: &fq,
            v: [1.0, 0.0],
            grad_x: [0.0, 1.0],
            tangent_lambda: [1.0, 0.0],
        };
        let t = test_functions(SpecialKind::Fold, &local);
        for (k, val) in t {
            match k {
                Codim2Kind::FoldFlip | Codim2Kind::Cusp | Codim2Kind::TurningAlong => {
                    assert!(val.abs() < 1e-15, "{k:?}")
                }
                _ => assert!(val.abs() > 0.5, "{k:?}"),
            }
        }
    }
}
