//! The forces of a system given as two expressions, compiled once into one instruction tape.
//!
//! A user gives a(t, x, v; p) and r(t, x, v; p) of β̈ = a − sgn(β̇) r (eq. of
//! [`DrivenOscillator`](super::DrivenOscillator)) as text in the variables `t` [s], `x` (β), `v`
//! (ω) and the parameters by name, with the grammar
//!
//! ```text
//!   sum     = product (("+" | "-") product)*
//!   product = unary (("*" | "/") unary)*
//!   unary   = ("-" | "+") unary | power
//!   power   = atom (("^" | "**") unary)?          right-associative: 2^3^2 = 2^9
//!   atom    = number | name | function "(" sum ")" | "(" sum ")"
//! ```
//!
//! (so −x^2 = −(x²) and 2^−x = 2^(−x), as in mathematics and Python); a name is t, x, v, a
//! parameter, or a constant PI (π), TAU (τ), E (e), a parameter taking precedence; the functions
//! are sin cos tan asin acos atan sinh cosh tanh asinh acosh atanh exp log (= ln) ln log2 log10
//! sqrt cbrt abs and sgn (= signum, with sgn 0 = 0). An expression nests at most 1000 levels deep (a sum of 1000
//! terms is 1000 levels). [`Compiled::new`] parses both, differentiates them symbolically in x, v
//! and every parameter — the terms of the variational equations, ∂a/∂x, ∂a/∂v, ∂r/∂x, ∂r/∂v and
//! the parameter columns ∂a/∂p_k, ∂r/∂p_k at fixed t — into one graph whose common
//! subexpressions are shared, and lays that graph out as one instruction tape: the terms that read only
//! parameters are evaluated once per parameter set ([`Compiled::constants`]), the rest by one pass
//! per right-hand side, which computes the forces and every derivative the caller asks for.
//!
//! ```
//! use gearbif::model::expression::Compiled;
//! let c = Compiled::new("A*cos(2*PI*f*t) - w0^2*sin(x)", "mu", &["f", "A", "w0", "mu"]).unwrap();
//! let k = c.constants(&[0.5, 2.0, 3.0, 0.1, 0.0, 0.0, 0.0, 0.0]);
//! let j = c.jet(&k, 0.0, 0.0, 1.0, true);
//! assert_eq!((j.a, j.r, j.a_beta, j.a_p[1], j.r_p[3]), (2.0, 0.1, -9.0, 1.0, 1.0));
//! ```

mod graph;
mod parse;
mod tape;

use super::{ForcesJet, MAX_PARAMS};
use graph::{Graph, Var};
use tape::{Level, Tape};

/// Why an expression cannot be compiled.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ExpressionError {
    /// The text is not an expression of the grammar ([`parse`]).
    #[error("{text:?}, column {column}: {message}")]
    Syntax {
        /// The expression.
        text: String,
        /// Where the error is (characters, from 1).
        column: usize,
        /// What is wrong there.
        message: String,
    },
    /// A name that is neither a variable, a parameter nor a constant.
    #[error(
        "{text:?} uses `{name}`, which is neither a variable (t, x, v) nor a parameter ({params})"
    )]
    UnknownName {
        /// The expression.
        text: String,
        /// The unknown name.
        name: String,
        /// The parameters' names, comma-separated.
        params: String,
    },
    /// A parameter named like a variable.
    #[error("a parameter may not be called `{0}`: t, x and v are the expressions' variables")]
    ReservedName(String),
    /// More parameters than a jet has columns.
    #[error("at most {MAX_PARAMS} parameters, got {0}")]
    TooManyParams(usize),
    /// The error of one of the two forces.
    #[error("{force} = {error}")]
    Force {
        /// `a` or `r`.
        force: &'static str,
        /// What is wrong with it.
        error: Box<ExpressionError>,
    },
}

/// The tape's register file for one parameter set, its registers that read only numbers and
/// parameters evaluated ([`Compiled::constants`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Constants(Box<[f64]>);

/// The forces a and r of a system as one compiled tape, with their derivatives.
#[derive(Clone, Debug)]
pub struct Compiled {
    tape: Tape,
    n: usize,
}

/// The outputs of a jet: a, r, ∂a/∂x, ∂a/∂v, ∂r/∂x, ∂r/∂v, then ∂a/∂p_k and ∂r/∂p_k.
const OUTPUTS: usize = 6 + 2 * MAX_PARAMS;

impl Compiled {
    /// Parses a and r and differentiates them in x, v and every parameter. A parameter may not be
    /// called t, x or v; every name an expression uses must be a variable, a parameter or a
    /// constant.
    pub fn new(a: &str, r: &str, names: &[&str]) -> Result<Self, ExpressionError> {
        if let Some(bad) = names.iter().find(|n| matches!(**n, "t" | "x" | "v")) {
            return Err(ExpressionError::ReservedName(bad.to_string()));
        }
        if names.len() > MAX_PARAMS {
            return Err(ExpressionError::TooManyParams(names.len()));
        }
        let mut g = Graph::default();
        let mut force = |force: &'static str, text: &str| {
            parse::parse(text, names, &mut g).map_err(|e| ExpressionError::Force {
                force,
                error: Box::new(e),
            })
        };
        let (a, r) = (force("a", a)?, force("r", r)?);
        let mut outputs = vec![a, r];
        for var in [Var::X, Var::V] {
            outputs.extend([g.derivative(a, var), g.derivative(r, var)]);
        }
        // a, r, a_x, r_x, a_v, r_v → a, r, a_x, a_v, r_x, r_v
        outputs.swap(3, 4);
        for f in [a, r] {
            for k in 0..names.len() {
                outputs.push(g.derivative(f, Var::Param(k as u8)));
            }
        }
        let n = names.len();
        Ok(Compiled {
            tape: Tape::new(&g, &outputs, [2, 6, 6 + 2 * n]),
            n,
        })
    }

    /// The terms that read only parameters, at `values` (kept with the parameter set).
    pub fn constants(&self, values: &[f64; MAX_PARAMS]) -> Constants {
        Constants(self.tape.constants(values))
    }

    /// a and r at (t, x, v).
    pub fn forces(&self, c: &Constants, t: f64, x: f64, v: f64) -> (f64, f64) {
        let mut out = [0.0; 2];
        self.tape.eval(Level::Forces, &c.0, [t, x, v], &mut out);
        (out[0], out[1])
    }

    /// a, r and their derivatives in the state and, when `params`, the parameters.
    pub fn jet(&self, c: &Constants, t: f64, x: f64, v: f64, params: bool) -> ForcesJet {
        let mut out = [0.0; OUTPUTS];
        let level = if params { Level::Params } else { Level::State };
        self.tape.eval(level, &c.0, [t, x, v], &mut out);
        let mut j = ForcesJet::new(out[0], out[1]);
        [j.a_beta, j.a_omega, j.r_beta, j.r_omega] = [out[2], out[3], out[4], out[5]];
        if params {
            let n = self.n;
            j.a_p[..n].copy_from_slice(&out[6..6 + n]);
            j.r_p[..n].copy_from_slice(&out[6 + n..6 + 2 * n]);
        }
        j
    }
}

#[cfg(test)]
mod tests;
