//! Profiles of the catalog families' shape parameters (docs/diagnosis.md, "Shape parameters:
//! profiled, not crept to").
//!
//! A shape parameter (the drag exponent p, the load's weight components ρ_z and ρ_n, the Stribeck
//! width w and shape δ) trades off with the family's coefficient and the base parameters along a curved
//! valley of the windows' χ²: a Levenberg–Marquardt refit started at the weak-form grid value
//! creeps along it and stops short (a drag exponent of 1.5 refitted from the quadratic member
//! ended at 1.96 ± 0.02). Here the parameter is *profiled*: held at values of a coarse ladder over
//! its range, every other parameter refitted to convergence on one fixed set of windows
//! (warm-started from the nearest value done), the profile
//! χ²_P(v) = min over the others of Σ_windows χ²_w
//! bracketed and refined (golden section) around its smallest value, and its 1σ interval taken
//! where it rises by Δ = σ²_k / [(JᵀJ)⁻¹]_kk above the minimum: the factor by which the fit's
//! covariance scales the Gauss–Newton one (s² and the inflation for correlated residuals), i.e.
//! the rise a quadratic profile has at one reported σ. Where the profile is quadratic the interval
//! is ±σ of the covariance; where it is not (a bound, a skewed valley) it is the honest one.

use super::lm::gauss_newton_cov;
use super::model::Shape;
use super::propose::{DRAG_EXPONENT_GRID, LOAD_WEIGHT_GRID, STRIBECK_WIDTH_GRID};
use super::regression::{Term, SETTLING_HUNDREDTHS};
use super::shooting::{SimFit, SimModel};
use crate::numerics::Bisection;

/// The profile of one shape parameter.
#[derive(Debug, Clone, PartialEq)]
pub struct ShapeProfile {
    /// The parameter.
    pub shape: Shape,
    /// Its index in θ of the model with the shape free.
    pub index: usize,
    /// The value at the profile's minimum.
    pub value: f64,
    /// The profile's minimum, Σ window χ² (σ units).
    pub chi2_min: f64,
    /// The rise of the profile that marks 1σ.
    pub delta: f64,
    /// The 1σ interval: where the profile rises by `delta` on each side, or the end of the
    /// parameter's range where it stays below.
    pub interval: (f64, f64),
    /// Whether the interval's lower/upper end is the range's (the profile stays within 1σ up to
    /// it: a bound, not a measured end).
    pub open: (bool, bool),
    /// θ of the free model (the shape entry included) at the minimum and at the interval's ends
    /// (interpolated between the profile points around each end).
    pub best: Vec<f64>,
    /// θ at the interval's lower and upper end.
    pub ends: [Vec<f64>; 2],
    /// The profile: (value, χ²_P − χ²_min), ascending in the value.
    pub points: Vec<(f64, f64)>,
}

/// The values a profile over `s` may visit, ascending: the weak-form grid of the family (always
/// evaluated, [`start_grid`]) continued to the ends of the parameter's documented range
/// ([`Shape::range`]; the weight's vertical component from 0, its side component both ways, the
/// Stribeck width from 0.02 rad/s: below it the decay is inside the stick phase).
pub fn ladder(s: Shape) -> Vec<f64> {
    match s {
        Shape::DragExponent => vec![0.5, 0.8, 1.2, 1.5, 1.8, 2.0, 2.5, 3.0, 3.5, 4.0],
        Shape::LoadWeight => vec![
            0.0, 0.5, 1.0, 1.5, 2.0, 3.0, 5.0, 8.0, 13.0, 20.0, 32.0, 50.0,
        ],
        Shape::LoadSide => vec![
            -50.0, -32.0, -20.0, -13.0, -8.0, -5.0, -3.0, -2.0, -1.0, -0.5, 0.0, 0.5, 1.0, 2.0,
            3.0, 5.0, 8.0, 13.0, 20.0, 32.0, 50.0,
        ],
        Shape::StribeckWidth => vec![
            0.02, 0.05, 0.1, 0.2, 0.35, 0.5, 0.75, 1.2, 2.0, 3.5, 6.0, 10.0, 20.0,
        ],
        Shape::StribeckPower => vec![0.5, 0.75, 1.0, 1.5, 2.0, 3.0, 4.0],
        Shape::DriftSettling => vec![0.02, 0.05, 0.1, 0.2, 0.4, 0.8, 1.2, 2.0],
    }
}

/// The values of [`ladder`] evaluated on every profile: the weak-form grid of the family
/// ([`super::propose`]; for the weight its magnitudes as the vertical component, and the side
/// component up to a weight of 2 tilted by 30°); for δ the exponential, the Gaussian and values
/// between and beyond.
pub fn start_grid(s: Shape) -> Vec<f64> {
    match s {
        Shape::DragExponent => DRAG_EXPONENT_GRID
            .iter()
            .map(|&p| f64::from(p) / 10.0)
            .collect(),
        Shape::LoadWeight => LOAD_WEIGHT_GRID
            .iter()
            .map(|&r| f64::from(r) / 10.0)
            .collect(),
        Shape::LoadSide => vec![-1.0, -0.5, 0.0, 0.5, 1.0],
        Shape::StribeckWidth => STRIBECK_WIDTH_GRID
            .iter()
            .map(|&w| f64::from(w) / 100.0)
            .collect(),
        Shape::StribeckPower => vec![0.75, 1.0, 1.5, 2.0, 3.0],
        Shape::DriftSettling => SETTLING_HUNDREDTHS
            .iter()
            .map(|&h| f64::from(h) / 100.0)
            .collect(),
    }
}

/// Δ of the profile of θ entry `k` of `fit`: σ²_k / [(JᵀJ)⁻¹]_kk, the χ² rise of a quadratic
/// profile at one reported σ (s² times the inflation for correlated residuals, whatever the
/// covariance's form); at least 1 (the rise at 1σ for white residuals in σ units), and 1 when the
/// Gauss–Newton variance is not finite.
pub fn delta_chi2(fit: &SimFit, k: usize) -> f64 {
    let gn = gauss_newton_cov(&fit.jac)[(k, k)];
    let c = fit.cov[(k, k)];
    if gn.is_finite() && gn > 0.0 && c.is_finite() && c > 0.0 {
        (c / gn).max(1.0)
    } else {
        1.0
    }
}

/// Golden-section steps of the refinement inside the bracket of the profile's smallest value.
pub const REFINE_STEPS: usize = 2;

/// Bisection steps for each end of the 1σ interval.
pub const END_STEPS: usize = 1;

/// One evaluated point: (value, χ²_P, θ of the free model).
type Point = (f64, f64, Vec<f64>);

/// The profile state: the evaluated points (ascending) and the refit at a held value.
struct Walker<'a, F> {
    model: &'a SimModel<'a>,
    k: usize,
    shape: Shape,
    fit: &'a F,
    start: Vec<f64>,
    pts: Vec<Point>,
}

impl<F> Walker<'_, F>
where
    F: Fn(&SimModel, &[f64]) -> Option<(f64, Vec<f64>)>,
{
    /// χ²_P at `v` (evaluated once; warm-started from the nearest point done). A value whose
    /// refit fails counts as an infinite χ².
    fn at(&mut self, v: f64) -> f64 {
        if let Some(p) = self.pts.iter().find(|p| (p.0 - v).abs() < 1e-12) {
            return p.1;
        }
        let warm = self
            .pts
            .iter()
            .min_by(|a, b| (a.0 - v).abs().total_cmp(&(b.0 - v).abs()))
            .map(|p| p.2.clone())
            .unwrap_or_else(|| self.start.clone());
        let mut held_theta = warm.clone();
        held_theta.remove(self.k);
        let mut terms = self.model.terms.clone();
        terms.remove(self.k);
        let mut held_shapes = self.model.held_shapes.clone();
        held_shapes.push((self.shape, v));
        let m = SimModel {
            terms,
            held_shapes,
            ..self.model.clone()
        };
        let (chi2, theta) = match (self.fit)(&m, &held_theta) {
            Some((c, mut th)) if c.is_finite() => {
                th.insert(self.k, v);
                (c, th)
            }
            _ => {
                let mut th = warm;
                th[self.k] = v;
                (f64::INFINITY, th)
            }
        };
        self.pts.push((v, chi2, theta));
        self.pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        chi2
    }
    /// Index of the smallest χ²_P.
    fn best(&self) -> usize {
        (0..self.pts.len())
            .min_by(|&a, &b| self.pts[a].1.total_cmp(&self.pts[b].1))
            .unwrap_or(0)
    }
}

/// Profiles θ entry `k` of `model` (a [`Term::Shape`]) from `theta`: the start grid evaluated
/// (nearest to the current value first, each warm-started from its neighbour), continued along
/// the [`ladder`] while the smallest value is at an end, the minimum refined by golden section
/// inside its bracket, and each end of the 1σ interval (rise `delta`) bisected, the ladder
/// continued when the profile has not risen by `delta` at the last value. `fit` refits the model
/// with the shape held (its `held_shapes`) from a start and gives (Σ window χ² over one fixed set
/// of windows, θ). `None` when entry `k` is not a shape or no value could be fitted.
pub fn profile_shape<F>(
    model: &SimModel,
    theta: &[f64],
    k: usize,
    delta: f64,
    fit: &F,
) -> Option<ShapeProfile>
where
    F: Fn(&SimModel, &[f64]) -> Option<(f64, Vec<f64>)>,
{
    let Some(&Term::Shape(shape)) = model.terms.get(k) else {
        return None;
    };
    let lad = ladder(shape);
    let mut w = Walker {
        model,
        k,
        shape,
        fit,
        start: theta.to_vec(),
        pts: Vec::new(),
    };
    let mut grid = start_grid(shape);
    let cur = theta[k];
    grid.sort_by(|a, b| (a - cur).abs().total_cmp(&(b - cur).abs()));
    for v in grid {
        w.at(v);
    }
    // continue along the ladder while the smallest value is at an end
    loop {
        let b = w.best();
        let v = w.pts[b].0;
        let next = if b == 0 {
            lad.iter().rev().find(|&&x| x < v - 1e-12).copied()
        } else if b + 1 == w.pts.len() {
            lad.iter().find(|&&x| x > v + 1e-12).copied()
        } else {
            None
        };
        match next {
            Some(x) => {
                w.at(x);
            }
            None => break,
        }
    }
    if !w.pts[w.best()].1.is_finite() {
        return None;
    }
    refine(&mut w);
    let b = w.best();
    let (v_hat, chi_min, best) = (w.pts[b].0, w.pts[b].1, w.pts[b].2.clone());
    let (lo, open_lo, th_lo) = end(&mut w, &lad, v_hat, chi_min + delta, -1.0);
    let (hi, open_hi, th_hi) = end(&mut w, &lad, v_hat, chi_min + delta, 1.0);
    Some(ShapeProfile {
        shape,
        index: k,
        value: v_hat,
        chi2_min: chi_min,
        delta,
        interval: (lo, hi),
        open: (open_lo, open_hi),
        best,
        ends: [th_lo, th_hi],
        points: w.pts.iter().map(|p| (p.0, p.1 - chi_min)).collect(),
    })
}

/// Golden-section refinement of the smallest χ²_P inside the bracket of its neighbours.
fn refine<F>(w: &mut Walker<F>)
where
    F: Fn(&SimModel, &[f64]) -> Option<(f64, Vec<f64>)>,
{
    let b = w.best();
    let n = w.pts.len();
    if n < 3 {
        return;
    }
    let (mut lo, mut hi) = (w.pts[b.saturating_sub(1)].0, w.pts[(b + 1).min(n - 1)].0);
    let gr = 0.5 * (5f64.sqrt() - 1.0);
    let (mut x1, mut x2) = (hi - gr * (hi - lo), lo + gr * (hi - lo));
    let (mut f1, mut f2) = (w.at(x1), w.at(x2));
    for _ in 1..REFINE_STEPS {
        if f1 <= f2 {
            hi = x2;
            x2 = x1;
            f2 = f1;
            x1 = hi - gr * (hi - lo);
            f1 = w.at(x1);
        } else {
            lo = x1;
            x1 = x2;
            f1 = f2;
            x2 = lo + gr * (hi - lo);
            f2 = w.at(x2);
        }
    }
}

/// The end of the 1σ interval on side `dir` (−1 below, +1 above `v_hat`): the crossing of
/// `target` bisected between the last point below it and the first above, linear inside the last
/// bracket, with θ interpolated there; the ladder continued while no point above the target is
/// found on that side; the range's end (open) when the profile stays below it up there.
fn end<F>(
    w: &mut Walker<F>,
    lad: &[f64],
    v_hat: f64,
    target: f64,
    dir: f64,
) -> (f64, bool, Vec<f64>)
where
    F: Fn(&SimModel, &[f64]) -> Option<(f64, Vec<f64>)>,
{
    let beyond = |w: &Walker<F>| {
        w.pts
            .iter()
            .filter(|p| (p.0 - v_hat) * dir > 0.0 && p.1 >= target)
            .min_by(|a, b| (a.0 - v_hat).abs().total_cmp(&(b.0 - v_hat).abs()))
            .map(|p| p.0)
    };
    let far = loop {
        if let Some(f) = beyond(&*w) {
            break Some(f);
        }
        let last = w
            .pts
            .iter()
            .map(|p| p.0)
            .filter(|&x| (x - v_hat) * dir >= 0.0)
            .max_by(|a, b| (a * dir).total_cmp(&(b * dir)))
            .unwrap_or(v_hat);
        let next = if dir > 0.0 {
            lad.iter().copied().find(|&x| x > last + 1e-12)
        } else {
            lad.iter().rev().copied().find(|&x| x < last - 1e-12)
        };
        match next {
            Some(x) => {
                w.at(x);
            }
            None => break None,
        }
    };
    let Some(far) = far else {
        // within 1σ up to the end of the range on this side
        let p = w
            .pts
            .iter()
            .max_by(|a, b| (a.0 * dir).total_cmp(&(b.0 * dir)))
            .expect("points");
        return (p.0, true, p.2.clone());
    };
    let near = w
        .pts
        .iter()
        .filter(|p| (p.0 - v_hat) * dir >= 0.0 && (p.0 - far) * dir < 0.0 && p.1 < target)
        .max_by(|a, b| ((a.0 - v_hat) * dir).total_cmp(&((b.0 - v_hat) * dir)))
        .map(|p| p.0)
        .unwrap_or(v_hat);
    let mut b = Bisection::new(near, far);
    for _ in 0..END_STEPS {
        let Some(mid) = b.next_point() else { break };
        b.update(mid, w.at(mid) >= target);
    }
    let (near, far) = (b.lo(), b.hi());
    let get = |w: &Walker<F>, v: f64| {
        w.pts
            .iter()
            .find(|p| (p.0 - v).abs() < 1e-12)
            .cloned()
            .expect("evaluated")
    };
    let (pn, pf) = (get(&*w, near), get(&*w, far));
    let u = if pf.1.is_finite() {
        ((target - pn.1) / (pf.1 - pn.1).max(1e-300)).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let v = near + (far - near) * u;
    let th =
        pn.2.iter()
            .zip(&pf.2)
            .map(|(a, b)| a + (b - a) * u)
            .collect();
    (v, false, th)
}

/// One side of a coefficient's profile: the profile χ²_P(v) − χ²_min (the rise) evaluated at
/// distances d from the fitted value ŝ on one side, and the σ that side implies.
#[derive(Debug, Clone, PartialEq)]
pub struct ProfileSide {
    /// The σ of this side: d √(Δ/r) at the last distance d evaluated, the σ of a quadratic
    /// profile through the minimum and that point (the rise Δ marks 1σ, [`delta_chi2`]).
    pub sigma: f64,
    /// Whether the last point evaluated lies inside the 1σ end (r < Δ): `sigma` then extrapolates
    /// a quadratic profile beyond the points seen, at most to [`SIDE_MAX_SIGMAS`] σ (that cap
    /// where the profile is flat).
    pub beyond: bool,
    /// The evaluated points: (held value, rise).
    pub points: Vec<(f64, f64)>,
    /// The rise Δ that marks 1σ.
    pub delta: f64,
}

/// Distance of a coefficient profile's first point from the fitted value, in units of the
/// covariance's σ ([`profile_side`]): a profile that is quadratic with that σ rises there by 4Δ,
/// far above the scatter of refits, and the point stays inside the quadratic region.
pub const SIDE_FIRST_SIGMAS: f64 = 2.0;
/// The farthest a coefficient profile's second point goes, in covariance σ ([`profile_side`]).
pub const SIDE_MAX_SIGMAS: f64 = 8.0;

/// The σ of a quadratic profile χ²_P(s) = χ²_min + Δ (s − ŝ)²/σ² through a point at distance
/// `dist` = |s − ŝ| that lies `rise` = r above the minimum: dist √(Δ/r); infinite for r ≤ 0 (a
/// flat profile).
pub fn quadratic_sigma(dist: f64, delta: f64, rise: f64) -> f64 {
    if rise > 0.0 {
        dist * (delta / rise).sqrt()
    } else {
        f64::INFINITY
    }
}

/// One side (`dir` = ±1) of the profile of a coefficient fitted at `value` with the covariance σ
/// `sigma`, its range ending at `lower` below: `rise(v)` refits the model with the coefficient
/// held at v and returns χ²_P(v) − χ²_min (`None`: the refit failed). The first point lies
/// [`SIDE_FIRST_SIGMAS`] σ away; its rise r gives σ₁ = d √(Δ/r). When σ₁ > d (the 1σ end lies
/// beyond the point: a flatter valley than the covariance says) one more point is evaluated at
/// d₂ = min(σ₁, [`SIDE_MAX_SIGMAS`] σ) and the side's σ is d₂ √(Δ/r₂). A rise that is not
/// positive counts as flat (σ = ∞ before the cap: the second point goes to the cap). A side
/// whose range ends within the first distance (the lower end, e.g. an excess of 0) is evaluated
/// at the end, and a side with no room (the fitted value at the end) has σ 0 and no points;
/// `None` when no point could be evaluated.
pub fn profile_side(
    mut rise: impl FnMut(f64) -> Option<f64>,
    value: f64,
    sigma: f64,
    delta: f64,
    dir: f64,
    lower: f64,
) -> Option<ProfileSide> {
    let at = |d: f64| {
        let v = value + dir * d;
        if dir < 0.0 {
            v.max(lower)
        } else {
            v
        }
    };
    let implied = |d: f64, r: f64| quadratic_sigma(d, delta, r);
    let mut points = Vec::new();
    if dir < 0.0 && value <= lower {
        // at (or below) the range's end: this side has no room, and tells nothing
        return Some(ProfileSide {
            sigma: 0.0,
            beyond: false,
            points,
            delta,
        });
    }
    let d1 = (at(SIDE_FIRST_SIGMAS * sigma) - value).abs();
    if d1 <= 0.0 {
        return None;
    }
    let r1 = rise(value + dir * d1)?;
    points.push((value + dir * d1, r1));
    let s1 = implied(d1, r1);
    if s1 <= d1 {
        return Some(ProfileSide {
            sigma: s1,
            beyond: false,
            points,
            delta,
        });
    }
    let d2 = (at(s1.min(SIDE_MAX_SIGMAS * sigma)) - value).abs();
    if d2 <= d1 * (1.0 + 1e-9) {
        // the range ends at the first point: the profile stays within 1σ up to it
        return Some(ProfileSide {
            sigma: s1.min(SIDE_MAX_SIGMAS * sigma).max(d1),
            beyond: true,
            points,
            delta,
        });
    }
    let Some(r2) = rise(value + dir * d2) else {
        return Some(ProfileSide {
            sigma: s1.min(SIDE_MAX_SIGMAS * sigma),
            beyond: true,
            points,
            delta,
        });
    };
    points.push((value + dir * d2, r2));
    let s2 = implied(d2, r2).min(SIDE_MAX_SIGMAS * sigma).max(d1);
    Some(ProfileSide {
        sigma: s2,
        beyond: r2 < delta * (1.0 - 1e-9),
        points,
        delta,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::identification::model::Geometry;
    use crate::identification::regression::BASE_TERMS;

    /// A model with the drag family's terms (no runs: the fit below is a closed form of the held
    /// value, read from the model as the profile sets it).
    fn drag_model() -> SimModel<'static> {
        let mut terms = BASE_TERMS.to_vec();
        terms.extend([Term::Quad, Term::Shape(Shape::DragExponent)]);
        SimModel {
            runs: &[],
            geo: Geometry::new(0.5, 0.5),
            terms,
            latency: 0.0,
            fit_latency: false,
            eta_static_excess: 0.0,
            tol: 1e-8,
            held_shapes: Vec::new(),
            roughness: 0.0,
            session: Default::default(),
        }
    }

    /// The profile of a closed-form χ²_P(p) = 500 + Δ·((p − 1.63)/σ)² (+ a cubic skew): the
    /// minimum and the crossings of 500 + Δ are found to the accuracy of the golden section and
    /// the bisection, and the shape is held (outside θ) on every refit.
    #[test]
    fn a_profile_finds_the_minimum_and_the_crossings_of_a_known_curve() {
        let m = drag_model();
        let k = m.terms.len() - 1;
        let delta = 2.5;
        let chi = |p: f64| {
            let x = (p - 1.63) / 0.12;
            500.0 + delta * (x * x + 0.15 * x * x * x)
        };
        let fit = |mm: &SimModel, th: &[f64]| -> Option<(f64, Vec<f64>)> {
            assert!(!mm.terms.contains(&Term::Shape(Shape::DragExponent)));
            assert_eq!(th.len(), mm.terms.len());
            let p = mm.held_shapes.last()?.1;
            let mut out = th.to_vec();
            out[4] = 0.3 * p; // q follows the exponent along the valley
            Some((chi(p), out))
        };
        let theta = [1.0, 20.0, -300.0, 60.0, 0.5, 2.0];
        let pr = profile_shape(&m, &theta, k, delta, &fit).unwrap();
        assert!((pr.value - 1.63).abs() < 0.03, "{pr:?}");
        // crossings of χ² = 500 + Δ: x + 0.15x³ ... solved: x² + 0.15x³ = 1
        let root = |lo: f64, hi: f64| {
            let (mut a, mut b) = (lo, hi);
            for _ in 0..60 {
                let c = 0.5 * (a + b);
                if (c * c + 0.15 * c * c * c - 1.0) * (a * a + 0.15 * a * a * a - 1.0) <= 0.0 {
                    b = c;
                } else {
                    a = c;
                }
            }
            1.63 + 0.12 * 0.5 * (a + b)
        };
        let (lo, hi) = (root(-1.5, 0.0), root(0.0, 1.5));
        assert!(
            (pr.interval.0 - lo).abs() < 0.01,
            "{:?} vs {lo}",
            pr.interval
        );
        assert!(
            (pr.interval.1 - hi).abs() < 0.01,
            "{:?} vs {hi}",
            pr.interval
        );
        assert_eq!(pr.open, (false, false));
        // θ at the ends interpolated along the valley, the shape entry restored
        assert!((pr.ends[1][k] - pr.interval.1).abs() < 1e-9);
        assert!((pr.ends[1][4] - 0.3 * pr.interval.1).abs() < 0.01);
        assert!((pr.best[4] - 0.3 * pr.value).abs() < 1e-12);
    }

    /// A profile falling towards the end of the range is followed along the ladder to it, and an
    /// interval that reaches the range's end is marked open there.
    #[test]
    fn a_profile_at_the_end_of_the_range_is_open_there() {
        let m = drag_model();
        let k = m.terms.len() - 1;
        let fit = |mm: &SimModel, th: &[f64]| -> Option<(f64, Vec<f64>)> {
            let p = mm.held_shapes.last()?.1;
            Some((100.0 + 0.5 * p, th.to_vec()))
        };
        let pr = profile_shape(&m, &[1.0, 20.0, -300.0, 60.0, 0.5, 2.0], k, 1.0, &fit).unwrap();
        assert_eq!(pr.value, 0.5);
        assert_eq!(pr.open, (true, false), "{pr:?}");
        assert_eq!(pr.interval.0, 0.5);
        // linear: the crossing of χ²(0.5) + 1 = 101.25 is found exactly, p = 2.5
        assert!((pr.interval.1 - 2.5).abs() < 1e-9, "{pr:?}");
    }

    /// Every start-grid value lies on the ladder, which lies inside the documented range.
    #[test]
    fn the_ladders_hold_the_grids_inside_the_ranges() {
        for s in [
            Shape::DragExponent,
            Shape::LoadWeight,
            Shape::LoadSide,
            Shape::StribeckWidth,
            Shape::StribeckPower,
            Shape::DriftSettling,
        ] {
            let (lo, hi) = s.range();
            let l = ladder(s);
            assert!(l.windows(2).all(|p| p[0] < p[1]), "{s:?}");
            assert!(l.iter().all(|&v| v >= lo && v <= hi), "{s:?}");
            for g in start_grid(s) {
                assert!(l.iter().any(|&v| (v - g).abs() < 1e-12), "{s:?} {g}");
            }
        }
    }

    /// A quadratic profile with σ = 0.05 where the covariance says 0.05: one point per side, σ
    /// exact; with σ = 0.2 (a valley four times flatter than the covariance's σ of 0.05) the
    /// second point at 4σ_cov lands on the 1σ end and gives 0.2 again; a flat side is capped.
    #[test]
    fn a_profile_side_recovers_the_sigma_of_a_quadratic_profile() {
        let (s_hat, delta) = (0.84, 2.7);
        for true_sigma in [0.05, 0.2] {
            let mut calls = 0;
            let rise = |v: f64| {
                calls += 1;
                Some(delta * ((v - s_hat) / true_sigma).powi(2))
            };
            let side = profile_side(rise, s_hat, 0.05, delta, 1.0, 0.0).unwrap();
            assert!((side.sigma - true_sigma).abs() < 1e-12, "{side:?}");
            assert_eq!(side.points.len(), if true_sigma > 0.1 { 2 } else { 1 });
            assert!(!side.beyond);
        }
        let side = profile_side(|_| Some(0.0), s_hat, 0.05, delta, 1.0, 0.0).unwrap();
        assert!((side.sigma - SIDE_MAX_SIGMAS * 0.05).abs() < 1e-12 && side.beyond);
        // the lower side of an excess of 0.06 ends at 0: evaluated there, and flat beyond
        let side = profile_side(|_| Some(0.5), 0.06, 0.05, delta, -1.0, 0.0).unwrap();
        assert_eq!(side.points.len(), 1);
        assert!((side.points[0].0 - 0.0).abs() < 1e-15 && side.beyond);
        assert!(side.sigma >= 0.06);
        // an excess fitted at the range's end: the lower side has no room
        let side = profile_side(|_| panic!("no evaluation"), 0.0, 0.05, delta, -1.0, 0.0).unwrap();
        assert!(side.points.is_empty() && side.sigma == 0.0);
    }
}
