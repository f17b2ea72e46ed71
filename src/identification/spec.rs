//! A model as a list of terms with a coefficient vector: the map from the coefficients of the
//! weak-form columns ([`Term`]) to the [`Coefficients`] of the augmented gear that the simulations
//! run. Shared by the weak form, the refit by simulation and the judge, so none of them imports
//! another to build a model.

use super::model::{Coefficients, ExtraTerm, Shape};
use super::regression::{grid_weight, load_grid_term, Clock, DriftParam, SessionPosition, Term};
use crate::model::recorded::spline::SplineKind;

/// A fitted model's θ as the refit by simulation left it: its terms, whether the last entry is
/// the latency, θ and its covariance (an infinite variance: a held entry). What model.json's
/// covariance is propagated from.
#[derive(Debug, Clone, PartialEq)]
pub struct FittedTheta {
    /// The terms of θ (then the latency when `fit_latency`).
    pub terms: Vec<Term>,
    /// Whether θ's last entry is the latency.
    pub fit_latency: bool,
    /// θ.
    pub theta: Vec<f64>,
    /// Covariance of θ.
    pub cov: nalgebra::DMatrix<f64>,
}

/// The column standing for `t` at the shape values `shapes`: a family's term with its shape
/// parameter baked in (the drag's −β̇|β̇| becomes −(|β̇|/V)^p sgn β̇ on the grid of tenths, the
/// load friction the load at the weight (ρ_z, ρ_n) in hundredths, the Stribeck excess the decay
/// at w); other terms unchanged.
pub fn column_term(t: Term, shapes: &[(Shape, f64)]) -> Term {
    let shape = |s: Shape| shapes.iter().find(|x| x.0 == s).map(|x| x.1);
    let weight = || match (shape(Shape::LoadWeight), shape(Shape::LoadSide)) {
        (None, None) => None,
        (z, n) => Some([z.unwrap_or(0.0), n.unwrap_or(0.0)]),
    };
    // `as u8` (and `as i16` in `load_grid_term`) saturates: values beyond the grid's range stay
    // at its ends
    match t {
        Term::Quad => shape(Shape::DragExponent).map(|p| Term::PowDrag((10.0 * p).round() as u8)),
        Term::LoadFric => weight().map(|w| load_grid_term(w, false)),
        Term::RadialLoadFric => weight().map(|w| load_grid_term(w, true)),
        Term::StaticExcess => shape(Shape::StribeckWidth).map(|w| {
            let d = shape(Shape::StribeckPower).unwrap_or(super::model::STRIBECK_POWER);
            Term::StribeckGrid((100.0 * w).round() as u8, (10.0 * d).round() as u8)
        }),
        Term::Drift(p, clock) => shape(Shape::DriftSettling).and_then(|tau| {
            let h = (100.0 * tau).round().max(1.0) as u8;
            match clock {
                Clock::RunIndexSettling(_) => Some(Term::Drift(p, Clock::RunIndexSettling(h))),
                Clock::SessionTimeSettling(_) => {
                    Some(Term::Drift(p, Clock::SessionTimeSettling(h)))
                }
                _ => None,
            }
        }),
        _ => None,
    }
    .unwrap_or(t)
}

/// Sets the shape parameter `s` of the coefficients `c` to `v` (the value a [`Term::Shape`] entry
/// of θ sets; used for a shape held outside θ, e.g. on a profile over it).
pub fn set_shape(c: &mut Coefficients, s: Shape, v: f64) {
    match s {
        Shape::DragExponent => c.drag_exponent = Some(v),
        Shape::LoadWeight => c.load_weight[0] = v,
        Shape::LoadSide => c.load_weight[1] = v,
        Shape::StribeckWidth => c.stribeck_width = v,
        Shape::StribeckPower => c.stribeck_power = Some(v),
        Shape::DriftSettling => c.drift_settling = Some(v),
    }
}

/// `terms` with values `coef` (shape parameters as their own entries) with every shape held
/// fixed: the shape entries dropped and baked into their family's term ([`column_term`]).
pub fn fix_shapes(terms: &[Term], coef: &[f64]) -> (Vec<Term>, Vec<f64>) {
    let shapes: Vec<(Shape, f64)> = terms
        .iter()
        .zip(coef)
        .filter_map(|(t, &v)| match t {
            Term::Shape(s) => Some((*s, v)),
            _ => None,
        })
        .collect();
    terms
        .iter()
        .zip(coef)
        .filter(|(t, _)| !matches!(t, Term::Shape(_)))
        .map(|(&t, &v)| (column_term(t, &shapes), v))
        .unzip()
}

/// The inverse of [`fix_shapes`]: every family term with a baked-in shape becomes the family's
/// term followed by its shape parameter, with the value of the grid. `theta` may carry entries
/// after the terms' (the latency): they are kept at the end.
pub fn free_shapes(terms: &[Term], theta: &[f64]) -> (Vec<Term>, Vec<f64>) {
    let (mut t, mut v) = (Vec::new(), Vec::new());
    // one settling time per model: with two settling drifts it stays at their grid values
    // (and a model whose settling time is already free keeps its one entry)
    let free_settling = terms.iter().filter(|t| settling_tau(**t).is_some()).count() == 1
        && !terms.contains(&Term::Shape(Shape::DriftSettling));
    for (&term, &x) in terms.iter().zip(theta) {
        let (base, shapes) = match term {
            Term::Drift(..) if free_settling && settling_tau(term).is_some() => (
                term,
                vec![(Shape::DriftSettling, settling_tau(term).unwrap_or(0.0))],
            ),
            Term::PowDrag(p) => (Term::Quad, vec![(Shape::DragExponent, f64::from(p) / 10.0)]),
            Term::LoadGrid(z, n, radial) => {
                let [wz, wn] = grid_weight(z, n);
                let base = if radial {
                    Term::RadialLoadFric
                } else {
                    Term::LoadFric
                };
                (base, vec![(Shape::LoadWeight, wz), (Shape::LoadSide, wn)])
            }
            Term::StribeckGrid(w, d) => (
                Term::StaticExcess,
                vec![
                    (Shape::StribeckWidth, f64::from(w) / 100.0),
                    (Shape::StribeckPower, f64::from(d) / 10.0),
                ],
            ),
            other => (other, Vec::new()),
        };
        t.push(base);
        v.push(x);
        for (s, value) in shapes {
            t.push(Term::Shape(s));
            v.push(value);
        }
    }
    v.extend_from_slice(&theta[terms.len().min(theta.len())..]);
    (t, v)
}

/// Which static-torque harmonic slot (k = 2, 3 → 0, 1) a lab-fixed torque term fills.
pub fn torque_harmonic(t: Term) -> Option<(usize, bool)> {
    match t {
        Term::Sin(0, l) if (2..=3).contains(&l) => Some((l as usize - 2, true)),
        Term::Cos(0, l) if (2..=3).contains(&l) => Some((l as usize - 2, false)),
        _ => None,
    }
}

/// The simulation form of a dictionary term (an [`ExtraTerm`] slot), `None` for catalog terms
/// (the lab-fixed torque harmonics sin/cos kβ, k = 2, 3, have their own coefficients).
pub fn extra_term(t: Term) -> Option<ExtraTerm> {
    if torque_harmonic(t).is_some() {
        return None;
    }
    match t {
        Term::Cos(k, l) => Some(ExtraTerm::Trig { k, l, sin: false }),
        Term::Sin(k, l) => Some(ExtraTerm::Trig { k, l, sin: true }),
        // the modulations by β (k = 0, l = 1) named on their own in the dictionary
        Term::VCosB | Term::VSinB => Some(ExtraTerm::VelTrig {
            k: 0,
            l: 1,
            sin: t == Term::VSinB,
        }),
        Term::SCosB | Term::SSinB => Some(ExtraTerm::FricTrig {
            k: 0,
            l: 1,
            sin: t == Term::SSinB,
        }),
        Term::VTrig(k, l, sin) => Some(ExtraTerm::VelTrig { k, l, sin }),
        Term::STrig(k, l, sin) => Some(ExtraTerm::FricTrig { k, l, sin }),
        _ => None,
    }
}

/// Whether every term has a simulation form: dictionary terms do, up to
/// [`super::model::MAX_EXTRA`] of them.
pub fn simulable(terms: &[Term]) -> bool {
    terms.iter().filter(|&&t| extra_term(t).is_some()).count() <= super::model::MAX_EXTRA
}

/// The model coefficients of `terms` with values `coef` (dictionary terms go to the
/// [`Coefficients::extra`] slots; drift terms need the run: see [`coefficients_for_run`]).
/// Compliance and drive offsets are fitted as χg², −gε, −g·(ε per turn) (regression.rs).
pub fn coefficients(terms: &[Term], coef: &[f64]) -> Coefficients {
    let mut c = Coefficients::default();
    let (mut compliance, mut offset, mut offset_rate) = (0.0, 0.0, 0.0);
    for (&t, &v) in terms.iter().zip(coef) {
        match t {
            Term::Zeta => c.zeta = v,
            Term::Eta => c.eta = v,
            Term::SinACosB => c.c_sc = v,
            Term::CosASinB => c.c_cs = v,
            Term::CosACosB => c.c_cc = v,
            Term::SinASinB => c.c_ss = v,
            Term::SinB => c.st_a = v,
            Term::CosB => c.st_b = v,
            Term::Quad => c.quad = v,
            Term::PowDrag(p) => {
                c.quad = v;
                c.drag_exponent.get_or_insert(f64::from(p) / 10.0);
            }
            Term::Shape(s) => set_shape(&mut c, s, v),
            Term::Corot => c.corot = v,
            Term::LoadFric => c.eta_load = v,
            Term::RadialLoadFric => {
                c.eta_load = v;
                c.load_radial = true;
            }
            Term::LoadGrid(z, n, radial) => {
                c.eta_load = v;
                c.load_radial = radial;
                c.load_weight = grid_weight(z, n);
            }
            Term::StaticExcess => c.eta_static_excess = v,
            Term::StribeckGrid(w, d) => {
                c.eta_static_excess = v;
                c.stribeck_width = f64::from(w) / 100.0;
                c.stribeck_power = Some(f64::from(d) / 10.0);
            }
            Term::Compliance => compliance = v,
            Term::DrivenOffset => offset = v,
            Term::DrivenOffsetRate => offset_rate = v,
            Term::Drift(..) => {}
            Term::Spline(kind, j) => {
                let curve = match kind {
                    SplineKind::Torque => &mut c.spline_torque,
                    SplineKind::Friction => &mut c.spline_friction,
                };
                if let Some(x) = curve.get_mut(usize::from(j)) {
                    *x = v;
                }
            }
            other if torque_harmonic(other).is_some() => {
                if let Some((k, sin)) = torque_harmonic(other) {
                    if sin {
                        c.st_harmonics[k].0 = v;
                    } else {
                        c.st_harmonics[k].1 = v;
                    }
                }
            }
            other => {
                if let (Some(e), Some(slot)) = (
                    extra_term(other),
                    c.extra.iter_mut().find(|s| s.0 == ExtraTerm::Unused),
                ) {
                    *slot = (e, v);
                }
            }
        }
    }
    let g = c.g();
    if g != 0.0 {
        c.compliance = compliance / (g * g);
        c.alpha_offset = -offset / g;
        c.alpha_offset_per_turn = -offset_rate / g;
    }
    c
}

/// The settling time of a settling drift term's clock (`None` for other terms).
fn settling_tau(t: Term) -> Option<f64> {
    match t {
        Term::Drift(_, clock) => clock.settling_tau(),
        _ => None,
    }
}

/// The coefficients that hold in the run at session position `pos`: [`coefficients`] with the
/// shapes `held` (held outside the coefficients, e.g. on a profile) plus the parameter drift at
/// the run's position (its middle; a settling drift with the model's settling time, else its
/// clock's), and the driven-run input offsets only on driven runs.
pub fn coefficients_for_run(
    terms: &[Term],
    coef: &[f64],
    pos: SessionPosition,
    held: &[(Shape, f64)],
) -> Coefficients {
    let mut c = coefficients(terms, coef);
    for &(s, v) in held {
        set_shape(&mut c, s, v);
    }
    if !pos.driven {
        c.alpha_offset = 0.0;
        c.alpha_offset_per_turn = 0.0;
    }
    if !terms.iter().any(|t| matches!(t, Term::Drift(..))) {
        return c;
    }
    for (&t, &v) in terms.iter().zip(coef) {
        if let Term::Drift(p, clock) = t {
            let s = pos.s_with(clock, c.drift_settling);
            let dv = v * s;
            match p {
                DriftParam::Zeta => c.zeta += dv,
                DriftParam::Eta => c.eta += dv,
                DriftParam::Coupling => {
                    // g(s) = g + dv scales the base coupling −g sin α cos β + gΔ cos α sin β
                    let g = c.g();
                    if g != 0.0 {
                        let scale = (g + dv) / g;
                        c.c_sc *= scale;
                        c.c_cs *= scale;
                    }
                }
            }
        }
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn base_terms_map_to_the_base_coefficients() {
        let terms = super::super::regression::BASE_TERMS;
        let c = coefficients(&terms, &[1.1, 23.0, -310.0, 310.0 * 0.2]);
        assert_eq!(c, Coefficients::base(310.0, 0.2, 1.1, 23.0));
        // compliance: the column's coefficient is χ g²
        let mut t2 = terms.to_vec();
        t2.push(Term::Compliance);
        let c2 = coefficients(&t2, &[1.1, 23.0, -310.0, 62.0, 310.0 * 310.0 * 1e-4]);
        assert!((c2.compliance - 1e-4).abs() < 1e-15);
    }

    /// Family terms: the drag exponent and the torque harmonics get their own coefficients (not
    /// the dictionary's extra slots); a weak-form grid column carries its exponent.
    #[test]
    fn family_terms_map_to_their_coefficients() {
        use super::super::model::Shape;
        let mut terms = super::super::regression::BASE_TERMS.to_vec();
        terms.extend([
            Term::Quad,
            Term::Shape(Shape::DragExponent),
            Term::Sin(0, 2),
            Term::Cos(0, 3),
            Term::Cos(1, 2),
        ]);
        let c = coefficients(
            &terms,
            &[1.0, 20.0, -300.0, 60.0, 0.04, 1.6, 2.0, -3.0, 0.5],
        );
        assert_eq!((c.quad, c.drag_exponent), (0.04, Some(1.6)));
        assert_eq!(c.st_harmonics, [(2.0, 0.0), (0.0, -3.0)]);
        assert_eq!(c.extra[0].1, 0.5);
        assert_eq!(c.extra[1].0, ExtraTerm::Unused);
        assert!(simulable(&terms));
        let g = coefficients(&[Term::PowDrag(15)], &[0.2]);
        assert_eq!((g.quad, g.drag_exponent), (0.2, Some(1.5)));
    }

    /// Fixing the shapes bakes them into grid terms with the same simulation; freeing them
    /// restores the family's terms with the shape entries (and keeps a trailing latency).
    #[test]
    fn shapes_fix_and_free() {
        use super::super::model::Shape;
        let terms = [
            Term::Eta,
            Term::Quad,
            Term::Shape(Shape::DragExponent),
            Term::RadialLoadFric,
            Term::Shape(Shape::LoadWeight),
            Term::Shape(Shape::LoadSide),
            Term::StaticExcess,
            Term::Shape(Shape::StribeckWidth),
            Term::Shape(Shape::StribeckPower),
        ];
        let coef = [20.0, 0.4, 1.5, 3.0, 2.2, -0.65, 12.0, 1.5, 1.0];
        let (ft, fc) = fix_shapes(&terms, &coef);
        assert_eq!(
            ft,
            [
                Term::Eta,
                Term::PowDrag(15),
                Term::LoadGrid(220, -65, true),
                Term::StribeckGrid(150, 10)
            ]
        );
        assert_eq!(fc, [20.0, 0.4, 3.0, 12.0]);
        assert_eq!(coefficients(&ft, &fc), coefficients(&terms, &coef));
        let mut th = fc.clone();
        th.push(0.006);
        let (bt, bc) = free_shapes(&ft, &th);
        assert_eq!(bt, terms);
        assert_eq!(bc[..9], coef);
        assert_eq!(bc[9], 0.006);
    }
}
