//! The flat instruction tape of an expression graph: every node an output needs, once, in
//! topological order, each writing one register.
//!
//! The registers are laid out as [constants | t, x, v | varying]: the nodes that read only numbers
//! and parameters are evaluated by [`Tape::constants`], once per parameter set; the others by one
//! pass per evaluation ([`Tape::eval`]), which copies the constants in, sets t, x, v and runs the
//! instructions its [`Level`] needs: the forces alone, with their state derivatives, or with their
//! parameter columns as well.

use super::graph::{Bin, Fun, Graph, Id, Node, Var};

/// What one instruction computes from its operands (register indices); the operators of two
/// arguments each have their own variant, so that running an instruction is one dispatch.
#[derive(Clone, Copy, Debug)]
enum Op {
    Num(f64),
    Param(u8),
    Neg(u32),
    Add(u32, u32),
    Sub(u32, u32),
    Mul(u32, u32),
    Div(u32, u32),
    Pow(u32, u32),
    PowI(u32, i32),
    Fun(Fun, u32),
}

/// One instruction: its result goes to register `dst`.
#[derive(Clone, Copy, Debug)]
struct Instr {
    dst: u32,
    op: Op,
}

/// How much of the jet a pass computes: the first [`Tape::outputs`] `count` outputs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Level {
    /// a and r.
    Forces,
    /// a, r and their derivatives in x and v.
    State,
    /// and the parameter columns.
    Params,
}

/// The compiled tape: the constants' pass, one pass per [`Level`], and where each output is read.
#[derive(Clone, Debug)]
pub struct Tape {
    constants: Vec<Instr>,
    n_const: usize,
    passes: [Vec<Instr>; 3],
    n_regs: usize,
    outputs: Vec<u32>,
}

/// Runs `instrs` over `regs`, a parameter read from `params`.
#[inline]
fn run(instrs: &[Instr], regs: &mut [f64], params: &[f64]) {
    for ins in instrs {
        let r = &*regs;
        let val = match ins.op {
            Op::Num(c) => c,
            Op::Param(k) => params[k as usize],
            Op::Neg(u) => -r[u as usize],
            Op::Add(u, w) => r[u as usize] + r[w as usize],
            Op::Sub(u, w) => r[u as usize] - r[w as usize],
            Op::Mul(u, w) => r[u as usize] * r[w as usize],
            Op::Div(u, w) => r[u as usize] / r[w as usize],
            Op::Pow(u, w) => r[u as usize].powf(r[w as usize]),
            Op::PowI(u, n) => r[u as usize].powi(n),
            Op::Fun(f, u) => f.apply(r[u as usize]),
        };
        regs[ins.dst as usize] = val;
    }
}

/// Whether each node reads t, x or v, directly or through its operands.
fn varying(nodes: &[Node]) -> Vec<bool> {
    let mut out: Vec<bool> = Vec::with_capacity(nodes.len());
    for n in nodes {
        let v = match *n {
            Node::Num(_) | Node::Var(Var::Param(_)) => false,
            Node::Var(_) => true,
            Node::Neg(u) | Node::Fun(_, u) | Node::PowI(u, _) => out[u as usize],
            Node::Bin(_, u, w) => out[u as usize] || out[w as usize],
        };
        out.push(v);
    }
    out
}

/// The nodes `roots` read, directly or through their operands.
fn reachable(nodes: &[Node], roots: &[Id]) -> Vec<bool> {
    let mut seen = vec![false; nodes.len()];
    for &r in roots {
        seen[r as usize] = true;
    }
    for id in (0..nodes.len()).rev() {
        if !seen[id] {
            continue;
        }
        match nodes[id] {
            Node::Num(_) | Node::Var(_) => {}
            Node::Neg(u) | Node::Fun(_, u) | Node::PowI(u, _) => seen[u as usize] = true,
            Node::Bin(_, u, w) => {
                seen[u as usize] = true;
                seen[w as usize] = true;
            }
        }
    }
    seen
}

impl Tape {
    /// The tape of `outputs` (node ids), of which each [`Level`] needs the first `counts[level]`.
    pub fn new(graph: &Graph, outputs: &[Id], counts: [usize; 3]) -> Self {
        let nodes = graph.nodes();
        let vary = varying(nodes);
        let all = reachable(nodes, outputs);
        let mut reg = vec![u32::MAX; nodes.len()];
        let mut next = 0u32;
        for id in (0..nodes.len()).filter(|&i| all[i] && !vary[i]) {
            reg[id] = next;
            next += 1;
        }
        let n_const = next as usize;
        for (k, var) in [Var::T, Var::X, Var::V].into_iter().enumerate() {
            if let Some(id) = (0..nodes.len()).find(|&i| nodes[i] == Node::Var(var)) {
                reg[id] = next + k as u32;
            }
        }
        next += 3;
        for id in
            (0..nodes.len()).filter(|&i| all[i] && vary[i] && !matches!(nodes[i], Node::Var(_)))
        {
            reg[id] = next;
            next += 1;
        }
        let instr = |id: usize| Instr {
            dst: reg[id],
            op: op_of(nodes[id], &reg),
        };
        let constants = (0..nodes.len())
            .filter(|&i| all[i] && !vary[i])
            .map(instr)
            .collect();
        let passes = counts.map(|count| {
            let need = reachable(nodes, &outputs[..count]);
            (0..nodes.len())
                .filter(|&i| need[i] && vary[i] && !matches!(nodes[i], Node::Var(_)))
                .map(instr)
                .collect()
        });
        Tape {
            constants,
            n_const,
            passes,
            n_regs: next as usize,
            outputs: outputs.iter().map(|&id| reg[id as usize]).collect(),
        }
    }

    /// The register file at the parameter values `params`: the registers that read only numbers
    /// and parameters evaluated, the others 0; its length is the size class of [`Self::eval`].
    pub fn constants(&self, params: &[f64]) -> Box<[f64]> {
        let len = match self.n_regs {
            0..=32 => 32,
            33..=64 => 64,
            65..=128 => 128,
            n => n,
        };
        let mut regs = vec![0.0; len];
        run(&self.constants, &mut regs, params);
        regs.into_boxed_slice()
    }

    /// The outputs of `level` at (t, x, v), into `out` (as many as `out` holds), starting from the
    /// register file of [`Self::constants`]: copied onto the stack whole (one fixed-size copy, no
    /// clearing) up to 128 registers.
    pub fn eval(&self, level: Level, file: &[f64], txv: [f64; 3], out: &mut [f64]) {
        match file.len() {
            32 => self.eval_in::<32>(file, level, txv, out),
            64 => self.eval_in::<64>(file, level, txv, out),
            128 => self.eval_in::<128>(file, level, txv, out),
            _ => self.finish(&mut file.to_vec(), level, txv, out),
        }
    }

    #[inline]
    fn eval_in<const N: usize>(&self, file: &[f64], level: Level, txv: [f64; 3], out: &mut [f64]) {
        let mut regs: [f64; N] = file.try_into().unwrap_or([f64::NAN; N]);
        self.finish(&mut regs, level, txv, out);
    }

    #[inline]
    fn finish(&self, regs: &mut [f64], level: Level, txv: [f64; 3], out: &mut [f64]) {
        let k = self.n_const;
        regs[k..k + 3].copy_from_slice(&txv);
        run(&self.passes[level as usize], regs, &[]);
        for (o, &r) in out.iter_mut().zip(&self.outputs) {
            *o = regs[r as usize];
        }
    }
}

/// The instruction of a node, its operands replaced by their registers.
fn op_of(n: Node, reg: &[u32]) -> Op {
    let r = |id: Id| reg[id as usize];
    match n {
        Node::Num(b) => Op::Num(f64::from_bits(b)),
        Node::Var(Var::Param(k)) => Op::Param(k),
        // t, x, v are set by the pass, never computed
        Node::Var(_) => Op::Num(f64::NAN),
        Node::Neg(u) => Op::Neg(r(u)),
        Node::Fun(f, u) => Op::Fun(f, r(u)),
        Node::Bin(b, u, w) => {
            let (u, w) = (r(u), r(w));
            match b {
                Bin::Add => Op::Add(u, w),
                Bin::Sub => Op::Sub(u, w),
                Bin::Mul => Op::Mul(u, w),
                Bin::Div => Op::Div(u, w),
                Bin::Pow => Op::Pow(u, w),
            }
        }
        Node::PowI(u, n) => Op::PowI(r(u), n),
    }
}
