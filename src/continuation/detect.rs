//! Detection and location of special points between two consecutive branch points.
//!
//! Test functions of the Floquet data (numerics.md, "Floquet multipliers and bifurcations"):
//! fold ψ = 1 − tr + det (μ = +1), flip ψ = 1 + tr + det (μ = −1; on the half-period map a
//! symmetry-breaking pitchfork), Neimark–Sacker ψ = det − 1 (with a complex pair). A sign change of
//! ψ between two points is located by Illinois regula falsi on the arclength
//! ([`crate::numerics::Illinois`]), each probe a corrected point on the branch. A change of the
//! event sequence (crossings, stick phases per period) is a nonsmooth point, bracketed by bisection
//! ([`crate::numerics::Bisection`]); it splits the step into smooth pieces, searched separately.

use super::branch::{NonsmoothJump, SpecialKind, SpecialPoint};
use super::palc::{Continuation, Solved};
use crate::error::Result;
use crate::integrator::FlowMethod;
use crate::maps::Section;
use crate::model::Parametrised;
use crate::numerics::{Bisection, Illinois, Side};
use crate::orbits::{eigenvector, Floquet};
use nalgebra::Vector3;

/// Which smooth test function.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Test {
    Fold,
    Flip,
    NeimarkSacker,
}

impl Test {
    const ALL: [Test; 3] = [Test::Fold, Test::Flip, Test::NeimarkSacker];

    fn value(self, f: &Floquet) -> f64 {
        match self {
            Test::Fold => f.fold_test(),
            Test::Flip => f.flip_test(),
            Test::NeimarkSacker => f.ns_test(),
        }
    }

    /// The kind of special point at a zero of this test on `section`.
    fn kind(self, section: Section) -> SpecialKind {
        match (self, section) {
            (Test::Fold, _) => SpecialKind::Fold,
            (Test::Flip, Section::HalfPeriod) => SpecialKind::SymmetryBreaking,
            (Test::Flip, Section::Stroboscopic) => SpecialKind::Flip,
            (Test::NeimarkSacker, _) => SpecialKind::NeimarkSacker,
        }
    }

    /// The critical real multiplier, if any.
    fn critical_multiplier(self) -> Option<f64> {
        match self {
            Test::Fold => Some(1.0),
            Test::Flip => Some(-1.0),
            Test::NeimarkSacker => None,
        }
    }
}

/// A piece of the step without a change of the event sequence: end points with their arclengths.
struct Piece {
    a: Solved,
    sa: f64,
    b: Solved,
    sb: f64,
}

/// The chord of the step being searched: its end points, the tangent at `a` and the arclength of `b`.
struct Chord<'a> {
    a: &'a Solved,
    b: &'a Solved,
    ta: Vector3<f64>,
    sb: f64,
}

impl<S: Parametrised, M: FlowMethod<S>> Continuation<S, M> {
    /// Detects and locates the special points between the accepted points `a` and `b` (`b` follows
    /// the branch point `idx`); returns how many it added to the branch.
    pub(super) fn detect(&mut self, a: &Solved, b: &Solved, idx: usize) -> Result<usize> {
        let w = self.weights();
        let ta = self.tangent;
        let sb = ta.dot(&(b.u.component_mul(&w) - a.u.component_mul(&w)));
        let chord = Chord { a, b, ta, sb };
        let mut specials = Vec::new();
        let mut pieces = Vec::new();
        // nonsmooth events first: they split the step into smooth pieces
        if a.events.signature() != b.events.signature() {
            let (lo, slo, hi, shi) = self.bisect_signature(&chord);
            specials.push(self.nonsmooth_point(&lo, &hi, idx));
            pieces.push(Piece {
                a: a.clone(),
                sa: 0.0,
                b: lo,
                sb: slo,
            });
            pieces.push(Piece {
                a: hi,
                sa: shi,
                b: b.clone(),
                sb,
            });
        } else {
            pieces.push(Piece {
                a: a.clone(),
                sa: 0.0,
                b: b.clone(),
                sb,
            });
        }
        for piece in &pieces {
            let (f1, f2) = (piece.a.floquet(), piece.b.floquet());
            for test in Test::ALL {
                let (t1, t2) = (test.value(&f1), test.value(&f2));
                if t1 == 0.0 || t2 == 0.0 || t1.signum() == t2.signum() {
                    continue;
                }
                if test == Test::NeimarkSacker && !(f1.complex_pair() && f2.complex_pair()) {
                    continue;
                }
                let kind = test.kind(self.spec.section);
                let sp = match self.locate_smooth(piece, &chord, test, kind, idx) {
                    Ok(sp) => sp,
                    // the corrector failed inside the step: report the bracket, honestly wide
                    Err(_) => SpecialPoint {
                        kind,
                        param: 0.5 * (piece.a.u[2] + piece.b.u[2]),
                        precision: 0.5 * (piece.a.u[2] - piece.b.u[2]).abs(),
                        x: [piece.b.u[0], piece.b.u[1]],
                        floquet: f2,
                        test_value: t2,
                        eigenvector: None,
                        after_point: idx,
                        jump: None,
                        stability_change: f1.stable != f2.stable,
                    },
                };
                specials.push(sp);
            }
        }
        specials.sort_by(|x, y| {
            let d = |s: &SpecialPoint| (s.param - a.u[2]).abs();
            d(x).total_cmp(&d(y))
        });
        let n = specials.len();
        self.branch.specials.extend(specials);
        Ok(n)
    }

    /// The special point of a change of the event sequence between the bracket points `lo`, `hi`.
    fn nonsmooth_point(&self, lo: &Solved, hi: &Solved, idx: usize) -> SpecialPoint {
        let (flo, fhi) = (lo.floquet(), hi.floquet());
        // which test function changes sign across the jump
        let crosses = if Test::Fold.value(&flo).signum() != Test::Fold.value(&fhi).signum() {
            Some("fold".to_string())
        } else if Test::Flip.value(&flo).signum() != Test::Flip.value(&fhi).signum() {
            Some("flip".to_string())
        } else {
            None
        };
        SpecialPoint {
            kind: SpecialKind::Nonsmooth,
            param: 0.5 * (lo.u[2] + hi.u[2]),
            precision: 0.5 * (hi.u[2] - lo.u[2]).abs() + self.opts.shooting.newton_tol,
            x: [hi.u[0], hi.u[1]],
            floquet: fhi,
            test_value: 0.0,
            eigenvector: None,
            after_point: idx,
            jump: Some(NonsmoothJump {
                events_before: lo.events,
                events_after: hi.events,
                floquet_before: flo,
                floquet_after: fhi,
                param_before: lo.u[2],
                param_after: hi.u[2],
                crosses,
            }),
            stability_change: flo.stable != fhi.stable,
        }
    }

    /// Bisection on the arclength for a change of the event signature: the two bracket points and
    /// their arclengths, narrowed until the parameter bracket is below `locate_tol`.
    fn bisect_signature(&mut self, chord: &Chord) -> (Solved, f64, Solved, f64) {
        let sig_a = chord.a.events.signature();
        let (mut lo, mut hi) = (chord.a.clone(), chord.b.clone());
        let mut bracket = Bisection::new(0.0, chord.sb);
        for _ in 0..80 {
            if (hi.u[2] - lo.u[2]).abs() < self.opts.locate_tol
                && (bracket.hi() - bracket.lo()).abs() < 1e-6
            {
                break;
            }
            let Some(sm) = bracket.next_point() else {
                break;
            };
            let Ok(m) = self.point_at(chord.a, chord.b, &chord.ta, sm, chord.sb) else {
                break;
            };
            match bracket.update(sm, m.events.signature() != sig_a) {
                Side::Lo => lo = m,
                Side::Hi => hi = m,
            }
        }
        (lo, bracket.lo(), hi, bracket.hi())
    }

    /// Illinois regula falsi on the arclength for a zero of `test` on a smooth piece.
    fn locate_smooth(
        &mut self,
        piece: &Piece,
        chord: &Chord,
        test: Test,
        kind: SpecialKind,
        idx: usize,
    ) -> Result<SpecialPoint> {
        let f = |s: &Solved| test.value(&s.floquet());
        let (fa, fb) = (f(&piece.a), f(&piece.b));
        // orient so that the low end is positive, as the root finder expects
        let orient = fa.signum();
        let mut root = Illinois::new(piece.sa, orient * fa, piece.sb, orient * fb, 0.01);
        let (mut lo, mut hi) = (piece.a.clone(), piece.b.clone());
        let mut best = if fa.abs() < fb.abs() {
            lo.clone()
        } else {
            hi.clone()
        };
        for _ in 0..100 {
            if (hi.u[2] - lo.u[2]).abs() < self.opts.locate_tol
                && (root.hi() - root.lo()).abs() < 1e-5
            {
                break;
            }
            let Some(sm) = root.next_point() else {
                break;
            };
            let m = self.point_at(chord.a, chord.b, &chord.ta, sm, chord.sb)?;
            if m.events.signature() != piece.a.events.signature() {
                // a nonsmooth event inside: search on the near side of it
                root.cut(sm);
                hi = m;
                continue;
            }
            let fm = f(&m);
            if fm == 0.0 {
                lo = m.clone();
                hi = m.clone();
                best = m;
                break;
            }
            match root.update(sm, orient * fm) {
                Side::Lo => lo = m.clone(),
                Side::Hi => hi = m.clone(),
            }
            best = m;
        }
        let lam = best.u[2];
        let precision =
            (hi.u[2] - lam).abs().max((lo.u[2] - lam).abs()) + self.opts.shooting.newton_tol;
        Ok(SpecialPoint {
            kind,
            param: lam,
            precision,
            x: [best.u[0], best.u[1]],
            floquet: best.floquet(),
            test_value: f(&best),
            eigenvector: test
                .critical_multiplier()
                .and_then(|mu| eigenvector(&best.jac, mu)),
            after_point: idx,
            jump: None,
            stability_change: piece.a.floquet().stable != piece.b.floquet().stable,
        })
    }
}
