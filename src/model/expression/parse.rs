//! An expression parsed by recursive descent straight into the [`Graph`], one function per rule of
//! the grammar (the module above states it), resolving each name as it is read.

use super::graph::{Bin, Graph, Id, Var, FUNCTIONS};
use super::ExpressionError;

/// Deepest nesting of an expression: parentheses, functions, powers and signs, and the length of a
/// chain of operations (a sum of 1000 terms is a chain of 999 additions), which bounds the
/// recursion of parsing and differentiation.
pub const MAX_DEPTH: usize = 1000;

/// A token and the character column it starts at.
#[derive(Clone, Debug, PartialEq)]
enum Token {
    Num(f64),
    Name(String),
    /// One of `+ - * / ^ ( )`; `**` is read as `^`.
    Sym(char),
    End,
}

/// The tokens of `text` with their columns (counted from 1).
fn tokens(text: &str) -> Result<Vec<(Token, usize)>, (usize, String)> {
    let chars: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let start = i;
        if c.is_whitespace() {
            i += 1;
            continue;
        }
        let tok = if c.is_ascii_digit()
            || (c == '.' && chars.get(i + 1).is_some_and(|d| d.is_ascii_digit()))
        {
            i = number_end(&chars, i);
            let s: String = chars[start..i].iter().collect();
            Token::Num(
                s.parse()
                    .map_err(|_| (start + 1, format!("`{s}` is not a number")))?,
            )
        } else if c.is_alphabetic() || c == '_' {
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            Token::Name(chars[start..i].iter().collect())
        } else if c == '*' && chars.get(i + 1) == Some(&'*') {
            i += 2;
            Token::Sym('^')
        } else if "+-*/^()".contains(c) {
            i += 1;
            Token::Sym(c)
        } else {
            return Err((start + 1, format!("unexpected `{c}`")));
        };
        out.push((tok, start + 1));
    }
    out.push((Token::End, chars.len() + 1));
    Ok(out)
}

/// The end of the number starting at `i`: digits, a fraction, an exponent (e, E, signed).
fn number_end(chars: &[char], mut i: usize) -> usize {
    let digits = |i: &mut usize| {
        while chars.get(*i).is_some_and(|d| d.is_ascii_digit()) {
            *i += 1;
        }
    };
    digits(&mut i);
    if chars.get(i) == Some(&'.') {
        i += 1;
        digits(&mut i);
    }
    if matches!(chars.get(i), Some('e' | 'E')) {
        let sign = usize::from(matches!(chars.get(i + 1), Some('+' | '-')));
        if chars.get(i + 1 + sign).is_some_and(|d| d.is_ascii_digit()) {
            i += 1 + sign;
            digits(&mut i);
        }
    }
    i
}

/// The parser's state: the tokens, where it is, the names it resolves and the graph it builds.
struct Parser<'a> {
    toks: Vec<(Token, usize)>,
    pos: usize,
    depth: usize,
    params: &'a [&'a str],
    graph: &'a mut Graph,
}

/// Parses `text` into `graph`; `params` are the parameter names in order. Errors carry the column
/// and a message, or name the unknown name.
pub fn parse(text: &str, params: &[&str], graph: &mut Graph) -> Result<Id, ExpressionError> {
    let syntax = |(column, message)| ExpressionError::Syntax {
        text: text.to_string(),
        column,
        message,
    };
    let toks = tokens(text).map_err(syntax)?;
    let mut p = Parser {
        toks,
        pos: 0,
        depth: 0,
        params,
        graph,
    };
    let id = p.sum().map_err(|e| e.into_error(text, params))?;
    match p.peek() {
        Token::End => Ok(id),
        t => Err(syntax((p.column(), format!("unexpected {}", describe(t))))),
    }
}

/// A parse failure before it knows the text: a syntax error at a column, or an unknown name.
enum Failure {
    At(usize, String),
    Unknown(String),
}

impl Failure {
    fn into_error(self, text: &str, params: &[&str]) -> ExpressionError {
        match self {
            Failure::At(column, message) => ExpressionError::Syntax {
                text: text.to_string(),
                column,
                message,
            },
            Failure::Unknown(name) => ExpressionError::UnknownName {
                text: text.to_string(),
                name,
                params: params.join(", "),
            },
        }
    }
}

fn describe(t: &Token) -> String {
    match t {
        Token::Num(x) => format!("number {x}"),
        Token::Name(n) => format!("`{n}`"),
        Token::Sym(c) => format!("`{c}`"),
        Token::End => "end of expression".to_string(),
    }
}

impl Parser<'_> {
    fn peek(&self) -> &Token {
        &self.toks[self.pos].0
    }
    fn column(&self) -> usize {
        self.toks[self.pos].1
    }
    fn next(&mut self) -> Token {
        let t = self.toks[self.pos].0.clone();
        if t != Token::End {
            self.pos += 1;
        }
        t
    }
    fn eat(&mut self, c: char) -> bool {
        let hit = *self.peek() == Token::Sym(c);
        if hit {
            self.pos += 1;
        }
        hit
    }
    fn expect(&mut self, c: char) -> Result<(), Failure> {
        if self.eat(c) {
            Ok(())
        } else {
            Err(Failure::At(
                self.column(),
                format!("expected `{c}`, found {}", describe(self.peek())),
            ))
        }
    }
    /// Enters one more level of nesting, refused beyond [`MAX_DEPTH`].
    fn deeper(&mut self) -> Result<(), Failure> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(Failure::At(
                self.column(),
                format!("nested deeper than {MAX_DEPTH} levels"),
            ));
        }
        Ok(())
    }

    /// Refuses a node deeper than [`MAX_DEPTH`].
    fn shallow(&self, u: Id) -> Result<(), Failure> {
        if self.graph.depth(u) as usize > MAX_DEPTH {
            return Err(Failure::At(
                self.column(),
                format!("nested deeper than {MAX_DEPTH} levels"),
            ));
        }
        Ok(())
    }

    fn sum(&mut self) -> Result<Id, Failure> {
        let mut u = self.product()?;
        loop {
            let sub = match self.peek() {
                Token::Sym('+') => false,
                Token::Sym('-') => true,
                _ => return Ok(u),
            };
            self.pos += 1;
            let w = self.product()?;
            u = if sub {
                self.graph.sub(u, w)
            } else {
                self.graph.add(u, w)
            };
            self.shallow(u)?;
        }
    }

    fn product(&mut self) -> Result<Id, Failure> {
        let mut u = self.unary()?;
        loop {
            let div = match self.peek() {
                Token::Sym('*') => false,
                Token::Sym('/') => true,
                _ => return Ok(u),
            };
            self.pos += 1;
            let w = self.unary()?;
            u = if div {
                self.graph.div(u, w)
            } else {
                self.graph.mul(u, w)
            };
            self.shallow(u)?;
        }
    }

    fn unary(&mut self) -> Result<Id, Failure> {
        self.deeper()?;
        let u = if self.eat('-') {
            let w = self.unary()?;
            self.graph.neg(w)
        } else if self.eat('+') {
            self.unary()?
        } else {
            self.power()?
        };
        self.depth -= 1;
        self.shallow(u)?;
        Ok(u)
    }

    fn power(&mut self) -> Result<Id, Failure> {
        let base = self.atom()?;
        if self.eat('^') {
            let e = self.unary()?;
            return Ok(self.graph.bin(Bin::Pow, base, e));
        }
        Ok(base)
    }

    fn atom(&mut self) -> Result<Id, Failure> {
        let column = self.column();
        match self.next() {
            Token::Num(c) => Ok(self.graph.num(c)),
            Token::Sym('(') => {
                let u = self.sum()?;
                self.expect(')')?;
                Ok(u)
            }
            Token::Name(n) => self.name(&n, column),
            t => Err(Failure::At(
                column,
                format!("expected a number, a name or `(`, found {}", describe(&t)),
            )),
        }
    }

    /// A variable, parameter or constant, or a function applied to a parenthesised argument.
    fn name(&mut self, n: &str, column: usize) -> Result<Id, Failure> {
        if let Some(&(_, f)) = FUNCTIONS.iter().find(|(name, _)| *name == n) {
            if *self.peek() != Token::Sym('(') {
                return Err(Failure::At(
                    column,
                    format!("`{n}` is a function: write {n}(…)"),
                ));
            }
            self.pos += 1;
            let u = self.sum()?;
            self.expect(')')?;
            return Ok(self.graph.fun(f, u));
        }
        if *self.peek() == Token::Sym('(') {
            let known: Vec<&str> = FUNCTIONS.iter().map(|(name, _)| *name).collect();
            return Err(Failure::At(
                column,
                format!(
                    "`{n}` is not a function (the functions: {})",
                    known.join(", ")
                ),
            ));
        }
        let var = match n {
            "t" => Some(Var::T),
            "x" => Some(Var::X),
            "v" => Some(Var::V),
            _ => self
                .params
                .iter()
                .position(|p| *p == n)
                .map(|k| Var::Param(k as u8)),
        };
        if let Some(var) = var {
            return Ok(self.graph.var(var));
        }
        let c = match n {
            "PI" | "π" => std::f64::consts::PI,
            "TAU" | "τ" => std::f64::consts::TAU,
            "E" | "e" => std::f64::consts::E,
            _ => return Err(Failure::Unknown(n.to_string())),
        };
        Ok(self.graph.num(c))
    }
}
