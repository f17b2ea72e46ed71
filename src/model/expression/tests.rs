//! Every derivative of the tape against central differences of its values, on random points, for
//! expressions that use every operator and function; values against the same formula in Rust;
//! the grammar's precedences; and the refusals.

use super::{Compiled, Constants, ExpressionError};
use crate::model::MAX_PARAMS;

const NAMES: [&str; 3] = ["f", "k", "mu"];

/// Pairs (a, r) that together use every operator, function, constant and number form.
const CASES: &[(&str, &str)] = &[
    ("x^3 - 2*x*v + v/(1 + x^2) - k*x", "mu + 0.1*x^2"),
    ("sin(x)*cos(v) + tan(x/3) - f*t", "mu*(1 + sinh(x/4)^2)"),
    ("asin(x/4) + acos(v/5) + atan(t*x*k)", "cosh(v/3) - 1 + mu"),
    ("tanh(k*v) + exp(-k*x) * log(2 + v^2)", "mu*exp(-x^2)"),
    (
        "ln(3 + x^2) + log2(4 + v^2*k) - log10(5 + t*x)",
        "sqrt(mu + x^2)",
    ),
    (
        "cbrt(3 + v*x) + abs(v)*x - sgn(v)*signum(x)*k",
        "mu/(1 + abs(v))",
    ),
    (
        "(2 + x)^k + (2 + v^2)^(x/3) - 2^-x + -x^2",
        "mu^2 + k^0.5*x**2",
    ),
    (
        "asinh(x) + acosh(2 + v^2) - atanh(x/2)",
        "mu*acosh(1.5 + x^2)",
    ),
    (
        "PI*t + π*x - TAU*v + τ*k + E*x - e*v + 1.5e-1*x + .5E+1*v",
        "mu*2.5",
    ),
];

/// A generator of uniform numbers in [0, 1) (splitmix64), so the points are the same every run.
struct Points(u64);

impl Points {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
    /// A number of either sign with magnitude in [0.2, 1.5].
    fn signed(&mut self) -> f64 {
        let m = 0.2 + 1.3 * self.next();
        if self.next() < 0.5 {
            -m
        } else {
            m
        }
    }
}

fn values(f: f64, k: f64, mu: f64) -> [f64; MAX_PARAMS] {
    let mut p = [0.0; MAX_PARAMS];
    p[..3].copy_from_slice(&[f, k, mu]);
    p
}

/// Central difference of (a, r) in the slot `which` (0 = x, 1 = v, 2 + k = parameter k).
fn difference(c: &Compiled, p: &[f64; MAX_PARAMS], txv: [f64; 3], which: usize) -> [f64; 2] {
    let at = |s: f64| {
        let (mut q, mut y) = (*p, txv);
        let h = if which < 2 {
            1e-6 * y[1 + which].abs().max(1.0)
        } else {
            1e-6 * q[which - 2].abs().max(1.0)
        };
        if which < 2 {
            y[1 + which] += s * h;
        } else {
            q[which - 2] += s * h;
        }
        let (a, r) = c.forces(&c.constants(&q), y[0], y[1], y[2]);
        ([a, r], h)
    };
    let ((up, h), (dn, _)) = (at(1.0), at(-1.0));
    [(up[0] - dn[0]) / (2.0 * h), (up[1] - dn[1]) / (2.0 * h)]
}

#[test]
fn every_derivative_equals_central_differences_on_random_points() {
    let mut rng = Points(42);
    for (a, r) in CASES {
        let c = Compiled::new(a, r, &NAMES).unwrap();
        for _ in 0..20 {
            let p = values(0.5 + rng.next(), 0.5 + rng.next(), 0.2 + rng.next());
            let txv = [2.0 * rng.next(), rng.signed(), rng.signed()];
            let k: Constants = c.constants(&p);
            let j = c.jet(&k, txv[0], txv[1], txv[2], true);
            assert_eq!((j.a, j.r), c.forces(&k, txv[0], txv[1], txv[2]));
            let state = c.jet(&k, txv[0], txv[1], txv[2], false);
            assert_eq!(
                [state.a_beta, state.a_omega, state.r_beta, state.r_omega],
                [j.a_beta, j.a_omega, j.r_beta, j.r_omega]
            );
            let mut exact = vec![[j.a_beta, j.r_beta], [j.a_omega, j.r_omega]];
            exact.extend((0..NAMES.len()).map(|i| [j.a_p[i], j.r_p[i]]));
            for (which, e) in exact.iter().enumerate() {
                let d = difference(&c, &p, txv, which);
                for (e, d) in e.iter().zip(d) {
                    assert!(e.is_finite(), "{a} | {r}: slot {which} at {txv:?}");
                    let tol = 1e-6 * e.abs().max(1.0);
                    assert!(
                        (e - d).abs() < tol,
                        "{a} | {r}: slot {which} at {txv:?}, {p:?}: {e} vs {d}"
                    );
                }
            }
        }
    }
}

#[test]
fn values_equal_the_formulas_written_in_rust() {
    let c = Compiled::new(
        "amplitude*cos(2*PI*f*t) - gamma*v - omega0^2*sin(x)",
        "mu",
        &["f", "omega0", "gamma", "mu", "amplitude"],
    )
    .unwrap();
    let p = [0.7, 3.0, 0.2, 0.4, 5.0, 0.0, 0.0, 0.0];
    let (t, x, v) = (0.3, 0.5, -1.2);
    let (a, r) = c.forces(&c.constants(&p), t, x, v);
    let w = std::f64::consts::TAU * 0.7 * t;
    let exact = 5.0 * w.cos() - 0.2 * v - 9.0 * x.sin();
    assert!((a - exact).abs() < 1e-14 * exact.abs(), "{a} vs {exact}");
    assert_eq!(r, 0.4);
    let value = |text: &str| {
        let c = Compiled::new(text, "0", &[]).unwrap();
        c.forces(&c.constants(&[0.0; MAX_PARAMS]), 0.0, 3.0, -2.0).0
    };
    // −x^2 is −(x²), ^ is right-associative and takes a signed exponent, ** is ^
    assert_eq!(value("-x^2"), -9.0);
    assert_eq!(value("2^3^2"), 512.0);
    assert_eq!(value("2^-1"), 0.5);
    assert_eq!(value("x**2 - x*x"), 0.0);
    assert_eq!(value("x - v - 1"), 4.0);
    assert_eq!(value("x / v / 3"), -0.5);
    assert_eq!(value("sgn(0*x) + abs(v)"), 2.0);
    assert_eq!(value("v^3"), -8.0);
}

#[test]
fn bad_expressions_are_refused_with_what_is_wrong() {
    let err = |a: &str| Compiled::new(a, "mu", &NAMES).unwrap_err().to_string();
    assert!(err("q*x")
        .contains("`q`, which is neither a variable (t, x, v) nor a parameter (f, k, mu)"));
    assert!(err("x +* 2").contains("column 4"), "{}", err("x +* 2"));
    assert!(err("foo(x)").contains("`foo` is not a function"));
    assert!(err("sin x").contains("write sin(…)"));
    assert!(err("(x").contains("expected `)`"));
    assert!(err("x $ 2").contains("unexpected `$`"));
    assert!(err("").contains("end of expression"));
    let deep = format!("{}x{}", "(".repeat(5000), ")".repeat(5000));
    assert!(err(&deep).contains("nested deeper"));
    assert!(err(&vec!["x"; 5000].join("+")).contains("nested deeper"));
    assert!(Compiled::new("x", "mu2", &NAMES)
        .unwrap_err()
        .to_string()
        .starts_with("r = \"mu2\""));
    assert_eq!(
        Compiled::new("x", "0", &["f", "v"]).unwrap_err(),
        ExpressionError::ReservedName("v".into())
    );
}
