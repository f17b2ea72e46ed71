//! The forces of a user system as expressions, parsed once and evaluated in Rust.
//!
//! A user gives a(t, x, v; p) and r(t, x, v; p) of β̈ = a − sgn(β̇) r as two strings in the
//! variables `t` [s], `x` (β), `v` (ω) and the parameters by name, with the usual operators
//! (`+ - * / ^`), functions (`sin`, `cos`, `tan`, `exp`, `log`, `sqrt`, `abs`, `tanh`, …) and the
//! constants `PI`/`π` and `E` (exmex's default operators). The partial derivatives the variational
//! equations need — ∂a/∂x, ∂a/∂v, ∂r/∂x, ∂r/∂v and the parameter columns ∂a/∂p_k, ∂r/∂p_k at
//! fixed t — are differentiated symbolically once, when the system is made, so no evaluation calls
//! back into Python and no derivative is a finite difference.

use exmex::prelude::*;
use gearbif::model::MAX_PARAMS;

/// Slots of the values an expression may read: t, x, v, then the parameters in order.
pub const SLOTS: usize = 3 + MAX_PARAMS;

/// One compiled expression and where each of its variables (exmex orders them by name) is read
/// from the slot array.
#[derive(Clone, Debug)]
struct Expr {
    ex: FlatEx<f64>,
    slots: Vec<usize>,
}

impl Expr {
    /// The value at `vals` (laid out as [`SLOTS`]); NaN where the expression is undefined.
    fn eval(&self, vals: &[f64; SLOTS]) -> f64 {
        let mut buf = [0.0; SLOTS];
        for (b, &s) in buf.iter_mut().zip(&self.slots) {
            *b = vals[s];
        }
        self.ex.eval(&buf[..self.slots.len()]).unwrap_or(f64::NAN)
    }
}

/// One term of a jet: an expression, or 0 where the expression does not read the variable it is
/// differentiated in.
#[derive(Clone, Debug)]
enum Term {
    /// Identically 0.
    Zero,
    /// Reads the parameters only: evaluated once per parameter set ([`Compiled::constants`]).
    Constant(Expr),
    /// Reads t, x or v: evaluated at every call.
    Varying(Expr),
}

impl Term {
    fn of(ex: FlatEx<f64>, slots: Vec<usize>) -> Self {
        let e = Expr { ex, slots };
        if e.slots.iter().any(|&s| s < 3) {
            Term::Varying(e)
        } else {
            Term::Constant(e)
        }
    }

    fn eval(&self, vals: &[f64; SLOTS], constant: f64) -> f64 {
        match self {
            Term::Zero => 0.0,
            Term::Constant(_) => constant,
            Term::Varying(e) => e.eval(vals),
        }
    }
}

/// The terms of a and r: each expression, then its derivatives in x, v and every parameter.
const TERMS: usize = 2 * SLOTS;

/// The values of the terms that read the parameters only, for one parameter set.
pub type Constants = [f64; TERMS];

/// Parses `text` and differentiates it in x, v and each parameter: its [`SLOTS`] − 2 + 1 terms
/// (the expression first).
fn compile(what: &str, text: &str, names: &[&'static str]) -> Result<Vec<Term>, String> {
    let ex = FlatEx::<f64>::parse(text).map_err(|e| format!("{what} = {text:?}: {e}"))?;
    let slot_of = |name: &str| -> Option<usize> {
        match name {
            "t" => Some(0),
            "x" => Some(1),
            "v" => Some(2),
            _ => names.iter().position(|n| *n == name).map(|k| 3 + k),
        }
    };
    let mut slots = Vec::with_capacity(ex.var_names().len());
    for name in ex.var_names() {
        let s = slot_of(name).ok_or_else(|| {
            format!(
                "{what} = {text:?} uses `{name}`, which is neither a variable (t, x, v) nor a \
                 parameter ({})",
                names.join(", ")
            )
        })?;
        slots.push(s);
    }
    let mut terms = vec![Term::of(ex.clone(), slots.clone())];
    for s in 1..3 + names.len() {
        terms.push(match slots.iter().position(|&k| k == s) {
            None => Term::Zero,
            Some(i) => {
                let d = ex
                    .clone()
                    .partial(i)
                    .map_err(|e| format!("{what} = {text:?}: no derivative: {e}"))?;
                Term::of(d, slots.clone())
            }
        });
    }
    Ok(terms)
}

/// The forces a and r of a user system as compiled expressions.
#[derive(Clone, Debug)]
pub struct Compiled {
    /// a, ∂a/∂x, ∂a/∂v, ∂a/∂p_k …, then the same for r (offset [`SLOTS`]).
    terms: Vec<Term>,
    n: usize,
}

/// The forces and their derivatives at one point (what `ForcesJet` holds).
pub struct Evaluated {
    pub a: f64,
    pub r: f64,
    /// ∂a/∂x, ∂a/∂v.
    pub a_state: [f64; 2],
    /// ∂r/∂x, ∂r/∂v.
    pub r_state: [f64; 2],
    pub a_p: [f64; MAX_PARAMS],
    pub r_p: [f64; MAX_PARAMS],
}

impl Compiled {
    /// Parses a and r and differentiates them in x, v and every parameter. A parameter may not be
    /// called t, x or v; every name an expression uses must be a variable or a parameter.
    pub fn new(a: &str, r: &str, names: &[&'static str]) -> Result<Self, String> {
        if let Some(bad) = names.iter().find(|n| matches!(**n, "t" | "x" | "v")) {
            return Err(format!(
                "a parameter may not be called `{bad}`: t, x and v are the expressions' variables"
            ));
        }
        let mut terms = compile("a", a, names)?;
        terms.resize(SLOTS, Term::Zero);
        terms.extend(compile("r", r, names)?);
        terms.resize(TERMS, Term::Zero);
        Ok(Compiled {
            terms,
            n: names.len(),
        })
    }

    /// The slot array of (t, x, v) and the parameter values.
    fn slots(values: &[f64; MAX_PARAMS], t: f64, x: f64, v: f64) -> [f64; SLOTS] {
        let mut s = [0.0; SLOTS];
        s[..3].copy_from_slice(&[t, x, v]);
        s[3..].copy_from_slice(values);
        s
    }

    /// The terms that read the parameters only, at `values` (kept with the parameter set).
    pub fn constants(&self, values: &[f64; MAX_PARAMS]) -> Constants {
        let s = Self::slots(values, 0.0, 0.0, 0.0);
        let mut c = [0.0; TERMS];
        for (c, term) in c.iter_mut().zip(&self.terms) {
            if let Term::Constant(e) = term {
                *c = e.eval(&s);
            }
        }
        c
    }

    fn term(&self, k: usize, s: &[f64; SLOTS], c: &Constants) -> f64 {
        self.terms[k].eval(s, c[k])
    }

    /// a and r at (t, x, v).
    pub fn forces(
        &self,
        values: &[f64; MAX_PARAMS],
        c: &Constants,
        t: f64,
        x: f64,
        v: f64,
    ) -> (f64, f64) {
        let s = Self::slots(values, t, x, v);
        (self.term(0, &s, c), self.term(SLOTS, &s, c))
    }

    /// a, r and their derivatives in the state and (when `params`) the parameters.
    pub fn jet(
        &self,
        (values, c): (&[f64; MAX_PARAMS], &Constants),
        t: f64,
        x: f64,
        v: f64,
        params: bool,
    ) -> Evaluated {
        let s = Self::slots(values, t, x, v);
        let (a, r) = (0, SLOTS);
        let mut out = Evaluated {
            a: self.term(a, &s, c),
            r: self.term(r, &s, c),
            a_state: [self.term(a + 1, &s, c), self.term(a + 2, &s, c)],
            r_state: [self.term(r + 1, &s, c), self.term(r + 2, &s, c)],
            a_p: [0.0; MAX_PARAMS],
            r_p: [0.0; MAX_PARAMS],
        };
        if params {
            for k in 0..self.n {
                out.a_p[k] = self.term(a + 3 + k, &s, c);
                out.r_p[k] = self.term(r + 3 + k, &s, c);
            }
        }
        out
    }
}
