//! The expression graph: one node per distinct subexpression (hash-consing), so that an
//! expression and all its derivatives share their common subexpressions. The constructors fold
//! numbers and drop neutral elements (u + 0 = u, 1·u = u, 0·u = 0, u − u = 0), and
//! [`Graph::derivative`] applies the chain rule node by node, memoised.

use std::collections::HashMap;

/// Index of a node; a node's operands always have smaller indices (the arena is in topological
/// order).
pub type Id = u32;

/// A variable an expression reads: time, the state (x = β, v = ω) or a parameter by position.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Var {
    T,
    X,
    V,
    Param(u8),
}

/// The functions of one argument.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Fun {
    Sin,
    Cos,
    Tan,
    Asin,
    Acos,
    Atan,
    Sinh,
    Cosh,
    Tanh,
    Asinh,
    Acosh,
    Atanh,
    Exp,
    Ln,
    Log2,
    Log10,
    Sqrt,
    Cbrt,
    Abs,
    Sgn,
}

/// The functions by name, as an expression writes them (`log` and `ln` are the natural logarithm,
/// `signum` and `sgn` the sign).
pub const FUNCTIONS: &[(&str, Fun)] = &[
    ("sin", Fun::Sin),
    ("cos", Fun::Cos),
    ("tan", Fun::Tan),
    ("asin", Fun::Asin),
    ("acos", Fun::Acos),
    ("atan", Fun::Atan),
    ("sinh", Fun::Sinh),
    ("cosh", Fun::Cosh),
    ("tanh", Fun::Tanh),
    ("asinh", Fun::Asinh),
    ("acosh", Fun::Acosh),
    ("atanh", Fun::Atanh),
    ("exp", Fun::Exp),
    ("log", Fun::Ln),
    ("ln", Fun::Ln),
    ("log2", Fun::Log2),
    ("log10", Fun::Log10),
    ("sqrt", Fun::Sqrt),
    ("cbrt", Fun::Cbrt),
    ("abs", Fun::Abs),
    ("sgn", Fun::Sgn),
    ("signum", Fun::Sgn),
];

impl Fun {
    /// f(u); sgn(0) = 0.
    #[inline]
    pub fn apply(self, u: f64) -> f64 {
        match self {
            Fun::Sin => u.sin(),
            Fun::Cos => u.cos(),
            Fun::Tan => u.tan(),
            Fun::Asin => u.asin(),
            Fun::Acos => u.acos(),
            Fun::Atan => u.atan(),
            Fun::Sinh => u.sinh(),
            Fun::Cosh => u.cosh(),
            Fun::Tanh => u.tanh(),
            Fun::Asinh => u.asinh(),
            Fun::Acosh => u.acosh(),
            Fun::Atanh => u.atanh(),
            Fun::Exp => u.exp(),
            Fun::Ln => u.ln(),
            Fun::Log2 => u.log2(),
            Fun::Log10 => u.log10(),
            Fun::Sqrt => u.sqrt(),
            Fun::Cbrt => u.cbrt(),
            Fun::Abs => u.abs(),
            Fun::Sgn if u > 0.0 => 1.0,
            Fun::Sgn if u < 0.0 => -1.0,
            Fun::Sgn => u,
        }
    }
}

/// The operators of two arguments.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Bin {
    Add,
    Sub,
    Mul,
    Div,
    /// u^w for a w that is not a small integer (those are [`Node::PowI`]).
    Pow,
}

impl Bin {
    /// u ∘ w.
    #[inline]
    pub fn apply(self, u: f64, w: f64) -> f64 {
        match self {
            Bin::Add => u + w,
            Bin::Sub => u - w,
            Bin::Mul => u * w,
            Bin::Div => u / w,
            Bin::Pow => u.powf(w),
        }
    }
}

/// A node of the graph.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Node {
    /// A number (its bits, so that nodes can be hashed).
    Num(u64),
    Var(Var),
    Neg(Id),
    Fun(Fun, Id),
    Bin(Bin, Id, Id),
    /// u^n for an integer n.
    PowI(Id, i32),
}

/// The arena of nodes, with the index of each distinct node and the memoised derivatives.
#[derive(Default)]
pub struct Graph {
    nodes: Vec<Node>,
    /// The length of the longest path from each node to a leaf (a leaf has 1).
    depth: Vec<u32>,
    index: HashMap<Node, Id>,
    derivatives: HashMap<(Id, Var), Id>,
}

impl Graph {
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// The node `n`, added unless an equal one exists.
    fn intern(&mut self, n: Node) -> Id {
        if let Some(&id) = self.index.get(&n) {
            return id;
        }
        let id = self.nodes.len() as Id;
        let below = match n {
            Node::Num(_) | Node::Var(_) => 0,
            Node::Neg(u) | Node::Fun(_, u) | Node::PowI(u, _) => self.depth(u),
            Node::Bin(_, u, w) => self.depth(u).max(self.depth(w)),
        };
        self.depth.push(below + 1);
        self.nodes.push(n);
        self.index.insert(n, id);
        id
    }

    /// The length of the longest path from `id` to a leaf: the recursion depth of
    /// [`Self::derivative`].
    pub fn depth(&self, id: Id) -> u32 {
        self.depth[id as usize]
    }

    /// The value of `id` if it is a number.
    pub fn number(&self, id: Id) -> Option<f64> {
        match self.nodes[id as usize] {
            Node::Num(b) => Some(f64::from_bits(b)),
            _ => None,
        }
    }

    pub fn num(&mut self, c: f64) -> Id {
        // one zero: −0 and +0 are the same number here
        let c = if c == 0.0 { 0.0 } else { c };
        self.intern(Node::Num(c.to_bits()))
    }

    pub fn var(&mut self, v: Var) -> Id {
        self.intern(Node::Var(v))
    }

    fn is(&self, id: Id, c: f64) -> bool {
        self.number(id) == Some(c)
    }

    pub fn neg(&mut self, u: Id) -> Id {
        match self.nodes[u as usize] {
            Node::Num(b) => self.num(-f64::from_bits(b)),
            Node::Neg(w) => w,
            _ => self.intern(Node::Neg(u)),
        }
    }

    pub fn fun(&mut self, f: Fun, u: Id) -> Id {
        match self.number(u) {
            Some(c) => self.num(f.apply(c)),
            None => self.intern(Node::Fun(f, u)),
        }
    }

    /// u ∘ w, folded where an operand is a number or the neutral element; the operands of + and ·
    /// in index order, so that u + w and w + u are one node.
    pub fn bin(&mut self, op: Bin, u: Id, w: Id) -> Id {
        if let (Some(a), Some(b)) = (self.number(u), self.number(w)) {
            return self.num(op.apply(a, b));
        }
        match op {
            Bin::Add if self.is(u, 0.0) => w,
            Bin::Add | Bin::Sub if self.is(w, 0.0) => u,
            Bin::Sub if self.is(u, 0.0) => self.neg(w),
            Bin::Sub if u == w => self.num(0.0),
            Bin::Mul if self.is(u, 0.0) || self.is(w, 0.0) => self.num(0.0),
            Bin::Mul if self.is(u, 1.0) => w,
            Bin::Mul | Bin::Div if self.is(w, 1.0) => u,
            Bin::Mul if self.is(u, -1.0) => self.neg(w),
            Bin::Mul if self.is(w, -1.0) => self.neg(u),
            Bin::Div if self.is(u, 0.0) => self.num(0.0),
            Bin::Pow => self.pow(u, w),
            Bin::Add | Bin::Mul if w < u => self.intern(Node::Bin(op, w, u)),
            _ => self.intern(Node::Bin(op, u, w)),
        }
    }

    /// u^w: an integer power where w is a small integer.
    fn pow(&mut self, u: Id, w: Id) -> Id {
        match self.number(w) {
            Some(n) if n.fract() == 0.0 && n.abs() <= 64.0 => self.powi(u, n as i32),
            _ => self.intern(Node::Bin(Bin::Pow, u, w)),
        }
    }

    pub fn powi(&mut self, u: Id, n: i32) -> Id {
        match (n, self.number(u)) {
            (0, _) => self.num(1.0),
            (1, _) => u,
            (_, Some(c)) => self.num(c.powi(n)),
            _ => self.intern(Node::PowI(u, n)),
        }
    }

    pub fn add(&mut self, u: Id, w: Id) -> Id {
        self.bin(Bin::Add, u, w)
    }
    pub fn sub(&mut self, u: Id, w: Id) -> Id {
        self.bin(Bin::Sub, u, w)
    }
    pub fn mul(&mut self, u: Id, w: Id) -> Id {
        self.bin(Bin::Mul, u, w)
    }
    pub fn div(&mut self, u: Id, w: Id) -> Id {
        self.bin(Bin::Div, u, w)
    }

    /// ∂u/∂var by the chain rule (memoised: every node is differentiated once per variable).
    pub fn derivative(&mut self, u: Id, var: Var) -> Id {
        if let Some(&d) = self.derivatives.get(&(u, var)) {
            return d;
        }
        let d = match self.nodes[u as usize] {
            Node::Num(_) => self.num(0.0),
            Node::Var(w) => self.num(if w == var { 1.0 } else { 0.0 }),
            Node::Neg(w) => {
                let dw = self.derivative(w, var);
                self.neg(dw)
            }
            Node::Fun(f, w) => {
                let dw = self.derivative(w, var);
                if self.is(dw, 0.0) {
                    dw
                } else {
                    let outer = self.outer_derivative(f, u, w);
                    self.mul(outer, dw)
                }
            }
            Node::Bin(op, a, b) => self.bin_derivative(op, u, (a, b), var),
            Node::PowI(w, n) => {
                // (wⁿ)' = n wⁿ⁻¹ w'
                let dw = self.derivative(w, var);
                let p = self.powi(w, n - 1);
                let n = self.num(f64::from(n));
                let np = self.mul(n, p);
                self.mul(np, dw)
            }
        };
        self.derivatives.insert((u, var), d);
        d
    }

    /// f'(w) for the node u = f(w).
    fn outer_derivative(&mut self, f: Fun, u: Id, w: Id) -> Id {
        let one = self.num(1.0);
        match f {
            Fun::Sin => self.fun(Fun::Cos, w),
            Fun::Cos => {
                let s = self.fun(Fun::Sin, w);
                self.neg(s)
            }
            // 1 + tan²w, 1 − tanh²w
            Fun::Tan | Fun::Tanh => {
                let sq = self.powi(u, 2);
                let op = if f == Fun::Tan { Bin::Add } else { Bin::Sub };
                self.bin(op, one, sq)
            }
            Fun::Asin | Fun::Acos | Fun::Atan | Fun::Asinh | Fun::Acosh | Fun::Atanh => {
                self.inverse_derivative(f, w)
            }
            Fun::Sinh => self.fun(Fun::Cosh, w),
            Fun::Cosh => self.fun(Fun::Sinh, w),
            Fun::Exp => u,
            // 1/(w ln b)
            Fun::Ln | Fun::Log2 | Fun::Log10 => {
                let lb = self.num(match f {
                    Fun::Log2 => std::f64::consts::LN_2,
                    Fun::Log10 => std::f64::consts::LN_10,
                    _ => 1.0,
                });
                let den = self.mul(w, lb);
                self.div(one, den)
            }
            // 1/(2√w), 1/(3 ∛w²)
            Fun::Sqrt | Fun::Cbrt => {
                let k = if f == Fun::Sqrt { 2.0 } else { 3.0 };
                let k = self.num(k);
                let root = if f == Fun::Sqrt { u } else { self.powi(u, 2) };
                let den = self.mul(k, root);
                self.div(one, den)
            }
            Fun::Abs => self.fun(Fun::Sgn, w),
            Fun::Sgn => self.num(0.0),
        }
    }

    /// f'(w) of the inverse trigonometric and hyperbolic functions: ±1/√(1 − w²), 1/(1 + w²),
    /// 1/√(w² ± 1), 1/(1 − w²); NaN for any other function (never called with one).
    fn inverse_derivative(&mut self, f: Fun, w: Id) -> Id {
        let one = self.num(1.0);
        let sq = self.powi(w, 2);
        match f {
            Fun::Asin | Fun::Acos => {
                let d = self.sub(one, sq);
                let root = self.fun(Fun::Sqrt, d);
                let sign = self.num(if f == Fun::Acos { -1.0 } else { 1.0 });
                self.div(sign, root)
            }
            Fun::Asinh | Fun::Acosh => {
                let op = if f == Fun::Asinh { Bin::Add } else { Bin::Sub };
                let d = self.bin(op, sq, one);
                let root = self.fun(Fun::Sqrt, d);
                self.div(one, root)
            }
            Fun::Atan | Fun::Atanh => {
                let op = if f == Fun::Atan { Bin::Add } else { Bin::Sub };
                let d = self.bin(op, one, sq);
                self.div(one, d)
            }
            _ => self.num(f64::NAN),
        }
    }

    /// (a ∘ b)' for the node u = a ∘ b.
    fn bin_derivative(&mut self, op: Bin, u: Id, (a, b): (Id, Id), var: Var) -> Id {
        let da = self.derivative(a, var);
        let db = self.derivative(b, var);
        match op {
            Bin::Add => self.add(da, db),
            Bin::Sub => self.sub(da, db),
            // (ab)' = a'b + ab'
            Bin::Mul => {
                let l = self.mul(da, b);
                let r = self.mul(a, db);
                self.add(l, r)
            }
            // (a/b)' = a'/b − (a/b) b'/b
            Bin::Div => {
                let l = self.div(da, b);
                let q = self.div(db, b);
                let r = self.mul(u, q);
                self.sub(l, r)
            }
            // (a^b)' = b a^(b−1) a' + a^b ln(a) b' (each term only where its derivative is not 0)
            Bin::Pow => {
                let l = if self.is(da, 0.0) {
                    da
                } else {
                    let one = self.num(1.0);
                    let bm1 = self.sub(b, one);
                    let p = self.bin(Bin::Pow, a, bm1);
                    let bp = self.mul(b, p);
                    self.mul(bp, da)
                };
                let r = if self.is(db, 0.0) {
                    db
                } else {
                    let ln = self.fun(Fun::Ln, a);
                    let ul = self.mul(u, ln);
                    self.mul(ul, db)
                };
                self.add(l, r)
            }
        }
    }
}
