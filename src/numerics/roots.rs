//! Bracketing root finders as small state machines: the caller asks for the next point, evaluates
//! its function there (however expensive: a dense-output polynomial in the integrator, a corrected
//! orbit in the continuation) and reports back, and decides itself when the bracket is narrow enough.
//!
//! - [`Illinois`]: regula falsi with the Illinois modification (the retained end's value is halved
//!   when the same end is kept twice), falling back to bisection when the secant point lands within
//!   `margin` of an end. Superlinear on smooth functions, never leaves the bracket.
//! - [`Bisection`]: for a predicate (e.g. "the event sequence has changed") with no value to
//!   interpolate.

/// Which end of a bracket a new point replaced.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// The low end (the side where the function is positive, or the predicate false).
    Lo,
    /// The high end.
    Hi,
}

/// Illinois regula falsi on a bracket [lo, hi] with f(lo) > 0 ≥ f(hi) (negate f if needed; lo may
/// be larger than hi). An exact zero moves the high end; a value f(lo) = 0 forces bisection.
///
/// ```
/// use gearbif::numerics::Illinois;
/// let f = |x: f64| 2.0 - x * x; // positive at 0, negative at 2
/// let mut r = Illinois::new(0.0, f(0.0), 2.0, f(2.0), 0.0);
/// while (r.hi() - r.lo()).abs() > 1e-14 {
///     let Some(x) = r.next_point() else { break };
///     r.update(x, f(x));
/// }
/// assert!((r.hi() - 2f64.sqrt()).abs() < 1e-14);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Illinois {
    lo: f64,
    f_lo: f64,
    hi: f64,
    f_hi: f64,
    margin: f64,
    last: Option<Side>,
}

impl Illinois {
    /// A bracket with f(lo) > 0 ≥ f(hi); `margin` ∈ [0, ½) is the fraction of the bracket near each
    /// end where a secant point is replaced by the midpoint.
    pub fn new(lo: f64, f_lo: f64, hi: f64, f_hi: f64, margin: f64) -> Self {
        Self {
            lo,
            f_lo,
            hi,
            f_hi,
            margin,
            last: None,
        }
    }

    /// The low end (f > 0).
    pub fn lo(&self) -> f64 {
        self.lo
    }

    /// The high end (f ≤ 0).
    pub fn hi(&self) -> f64 {
        self.hi
    }

    /// The next point to evaluate, strictly inside the bracket; `None` once the bracket cannot be
    /// split in floating point.
    pub fn next_point(&self) -> Option<f64> {
        let (a, b) = (self.lo.min(self.hi), self.lo.max(self.hi));
        let mid = 0.5 * (a + b);
        if !(mid > a && mid < b) {
            return None;
        }
        let w = b - a;
        let secant = if self.f_lo > 0.0 && self.f_hi < 0.0 {
            (self.lo * self.f_hi - self.hi * self.f_lo) / (self.f_hi - self.f_lo)
        } else {
            mid
        };
        Some(
            if secant > a + self.margin * w && secant < b - self.margin * w {
                secant
            } else {
                mid
            },
        )
    }

    /// Reports f(x) at the point `x` from [`Illinois::next_point`]; returns the end it replaced.
    pub fn update(&mut self, x: f64, fx: f64) -> Side {
        let side = if fx > 0.0 { Side::Lo } else { Side::Hi };
        match side {
            Side::Lo => {
                self.lo = x;
                self.f_lo = fx;
                if self.last == Some(Side::Lo) {
                    self.f_hi *= 0.5;
                }
            }
            Side::Hi => {
                self.hi = x;
                self.f_hi = fx;
                if self.last == Some(Side::Hi) {
                    self.f_lo *= 0.5;
                }
            }
        }
        self.last = Some(side);
        side
    }

    /// Moves the high end to `x` without a function value: the function is not continuous beyond
    /// `x` (e.g. a nonsmooth point lies between), so the root is sought on the low side of it.
    pub fn cut(&mut self, x: f64) {
        self.hi = x;
        self.last = None;
    }
}

/// Bisection for the point where a predicate switches from false (at `lo`) to true (at `hi`).
///
/// ```
/// use gearbif::numerics::Bisection;
/// let mut b = Bisection::new(0.0, 1.0);
/// while let Some(x) = b.next_point() {
///     b.update(x, x >= 0.3);
/// }
/// assert!(b.lo() < 0.3 && b.hi() >= 0.3 && b.hi() - b.lo() < 1e-15);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bisection {
    lo: f64,
    hi: f64,
}

impl Bisection {
    /// A bracket: the predicate is false at `lo` and true at `hi`.
    pub fn new(lo: f64, hi: f64) -> Self {
        Self { lo, hi }
    }

    /// The end where the predicate is false.
    pub fn lo(&self) -> f64 {
        self.lo
    }

    /// The end where the predicate is true.
    pub fn hi(&self) -> f64 {
        self.hi
    }

    /// The midpoint, or `None` once it is no longer strictly inside (machine precision).
    pub fn next_point(&self) -> Option<f64> {
        let mid = 0.5 * (self.lo + self.hi);
        let (a, b) = (self.lo.min(self.hi), self.lo.max(self.hi));
        (mid > a && mid < b).then_some(mid)
    }

    /// Reports the predicate at `x`; returns the end it replaced.
    pub fn update(&mut self, x: f64, predicate: bool) -> Side {
        if predicate {
            self.hi = x;
            Side::Hi
        } else {
            self.lo = x;
            Side::Lo
        }
    }
}
