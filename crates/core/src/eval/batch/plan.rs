//! Lowering of a tape into the batch evaluator's own program.
//!
//! Each batch step streams whole blocks through the L1 cache, so its cost is
//! mostly loads and stores. The plan cuts them: constant operands become
//! immediates broadcast in the loop instead of register blocks; the alpha = 0
//! R-functions `a + b ± sqrt(a² + b²)` (six tape instructions, the bulk of
//! most FRep models) run as one step; and two one-operand steps in a row
//! (`2 * t - 1`, `tri(x / w)`, `sin(v) - l`: the scalings around waves and
//! periodic functions) run as one, their temporaries kept in vector
//! registers. Results are bit-identical to the unfused code: the same f32
//! operations run in the same order.
//!
//! Fusion removes intermediate values, so the plan takes the tape to SSA form,
//! rewrites it there and allocates its own registers.

use crate::ops::{BinaryOp, UnaryOp};
use crate::tape::{Instr, Tape};

/// One value of the SSA form; operands are indices of earlier values.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Val {
    Input(u32),
    Const(f32),
    /// Index into the tape's parameters.
    Param(usize),
    Unary(UnaryOp, usize),
    Binary(BinaryOp, usize, usize),
    /// A binary op with one constant operand.
    BinaryImm(Imm, usize),
    PowI(usize, i32),
    Select(usize, usize, usize),
    Field {
        field: u32,
        comp: u8,
        args: [usize; 3],
    },
    RFun {
        a: usize,
        b: usize,
        squares: Option<(usize, usize)>,
        union: bool,
    },
    Pair {
        a: usize,
        pair: Pair,
    },
}

/// A binary op with a constant operand: `a op c`, or `c op a` when `left`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Imm {
    pub op: BinaryOp,
    pub c: f32,
    pub left: bool,
}

impl Imm {
    /// The ops a [`Link`] may carry: those of affine maps.
    fn is_affine(&self) -> bool {
        matches!(
            self.op,
            BinaryOp::Add | BinaryOp::Sub | BinaryOp::Mul | BinaryOp::Div
        )
    }
}

/// One half of a fused pair of one-operand steps.
#[derive(Clone, Copy)]
enum Link {
    Unary(UnaryOp),
    /// Only add, subtract, multiply and divide (see [`Imm::is_affine`]).
    Imm(Imm),
}

/// Two one-operand steps run as one, first to last. Never two unary ops:
/// that would need a kernel for each of their hundreds of combinations.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Pair {
    ImmUnary(Imm, UnaryOp),
    UnaryImm(UnaryOp, Imm),
    ImmImm(Imm, Imm),
}

/// A step over one block. Registers are indices into the evaluator's file.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Step {
    Unary {
        op: UnaryOp,
        out: u32,
        a: u32,
    },
    Binary {
        op: BinaryOp,
        out: u32,
        a: u32,
        b: u32,
    },
    /// A binary op with one operand the same in every lane.
    BinaryImm {
        imm: Imm,
        out: u32,
        a: u32,
    },
    PowI {
        out: u32,
        a: u32,
        n: i32,
    },
    Select {
        out: u32,
        c: u32,
        a: u32,
        b: u32,
    },
    Field {
        out: u32,
        field: u32,
        comp: u8,
        args: [u32; 3],
    },
    /// `a + b + sqrt(a*a + b*b)` (union) or `a + b - sqrt(a*a + b*b)`;
    /// with `squares`, `a*a` and `b*b` are read from those registers
    /// (they have other readers, so they are computed anyway).
    RFun {
        out: u32,
        a: u32,
        b: u32,
        squares: Option<(u32, u32)>,
        union: bool,
    },
    Pair {
        out: u32,
        a: u32,
        pair: Pair,
    },
}

pub(super) struct Plan {
    pub steps: Vec<Step>,
    pub nregs: usize,
    /// Registers preloaded with constants that stayed register operands.
    pub consts: Vec<(u32, f32)>,
    /// Register of each tape parameter, in the tape's order.
    pub params: Vec<u32>,
    pub outputs: Vec<u32>,
}

pub(super) fn lower(tape: &Tape) -> Plan {
    let (mut vals, outputs) = to_ssa(tape);
    fuse_rfun(&mut vals, &outputs);
    fold_immediates(&mut vals);
    fuse_pairs(&mut vals, &outputs);
    allocate(&vals, &outputs, tape.params.len())
}

fn to_ssa(tape: &Tape) -> (Vec<Val>, Vec<usize>) {
    let mut vals = Vec::with_capacity(tape.nregs + tape.instrs.len());
    let mut cur = vec![usize::MAX; tape.nregs];
    for (r, c) in cur.iter_mut().enumerate().take(3) {
        *c = vals.len();
        vals.push(Val::Input(r as u32));
    }
    for &(r, c) in &tape.consts {
        cur[r as usize] = vals.len();
        vals.push(Val::Const(c as f32));
    }
    for (k, (r, _)) in tape.params.iter().enumerate() {
        cur[*r as usize] = vals.len();
        vals.push(Val::Param(k));
    }
    for ins in &tape.instrs {
        let v = |r: u32| cur[r as usize];
        let val = match *ins {
            Instr::Unary { op, a, .. } => Val::Unary(op, v(a)),
            Instr::Binary { op, a, b, .. } => Val::Binary(op, v(a), v(b)),
            Instr::PowI { a, n, .. } => Val::PowI(v(a), n),
            Instr::Select { c, a, b, .. } => Val::Select(v(c), v(a), v(b)),
            Instr::Field {
                field, comp, args, ..
            } => Val::Field {
                field,
                comp,
                args: args.map(v),
            },
        };
        cur[ins.out() as usize] = vals.len();
        vals.push(val);
    }
    let outputs = tape.outputs.iter().map(|&r| cur[r as usize]).collect();
    (vals, outputs)
}

fn operands(v: &Val) -> Vec<usize> {
    match *v {
        Val::Input(_) | Val::Const(_) | Val::Param(_) => vec![],
        Val::Unary(_, a) | Val::PowI(a, _) | Val::BinaryImm(_, a) | Val::Pair { a, .. } => {
            vec![a]
        }
        Val::Binary(_, a, b) => vec![a, b],
        Val::RFun { a, b, squares, .. } => match squares {
            Some((qa, qb)) => vec![a, b, qa, qb],
            None => vec![a, b],
        },
        Val::Select(c, a, b) => vec![c, a, b],
        Val::Field { args, .. } => args.to_vec(),
    }
}

fn use_counts(vals: &[Val], outputs: &[usize]) -> Vec<usize> {
    let mut uses = vec![0usize; vals.len()];
    for v in vals {
        for a in operands(v) {
            uses[a] += 1;
        }
    }
    for &o in outputs {
        uses[o] += 1;
    }
    uses
}

/// Rewrites `s ± sqrt(square(p) + square(q))` with `s = p + q` into one
/// R-function value when the sum and the root have no other reader
/// (otherwise they must be computed anyway and fusing would only add work).
fn fuse_rfun(vals: &mut [Val], outputs: &[usize]) {
    let uses = use_counts(vals, outputs);
    let single = |i: usize| uses[i] == 1;
    for n in 0..vals.len() {
        let (union, cands) = match vals[n] {
            Val::Binary(BinaryOp::Add, x, y) => (true, vec![(x, y), (y, x)]),
            Val::Binary(BinaryOp::Sub, x, y) => (false, vec![(x, y)]),
            _ => continue,
        };
        for (s, r) in cands {
            let Val::Unary(UnaryOp::Sqrt, t) = vals[r] else {
                continue;
            };
            let Val::Binary(BinaryOp::Add, qa, qb) = vals[t] else {
                continue;
            };
            let (Val::Unary(UnaryOp::Square, p), Val::Unary(UnaryOp::Square, q)) =
                (vals[qa], vals[qb])
            else {
                continue;
            };
            let Val::Binary(BinaryOp::Add, sa, sb) = vals[s] else {
                continue;
            };
            let same_pair = (sa, sb) == (p, q) || (sa, sb) == (q, p);
            if !same_pair || ![s, r, t].into_iter().all(single) {
                continue;
            }
            // Squares with other readers stay values of their own.
            let squares = (!single(qa) || !single(qb)).then_some((qa, qb));
            vals[n] = Val::RFun {
                a: p,
                b: q,
                squares,
                union,
            };
            break;
        }
    }
}

/// Turns binary ops with one constant operand into immediate forms.
fn fold_immediates(vals: &mut [Val]) {
    for n in 0..vals.len() {
        let Val::Binary(op, a, b) = vals[n] else {
            continue;
        };
        vals[n] = match (vals[a], vals[b]) {
            (Val::Const(_), Val::Const(_)) => continue,
            (_, Val::Const(c)) => Val::BinaryImm(Imm { op, c, left: false }, a),
            (Val::Const(c), _) => Val::BinaryImm(Imm { op, c, left: true }, b),
            _ => continue,
        };
    }
}

/// The value as the half of a pair, with its operand.
fn as_link(v: &Val) -> Option<(Link, usize)> {
    match *v {
        Val::Unary(op, a) => Some((Link::Unary(op), a)),
        Val::BinaryImm(imm, a) if imm.is_affine() => Some((Link::Imm(imm), a)),
        _ => None,
    }
}

/// Fuses a one-operand value into its single reader when that is one too,
/// left to right, so a chain of them becomes a run of pairs.
fn fuse_pairs(vals: &mut [Val], outputs: &[usize]) {
    let uses = use_counts(vals, outputs);
    for n in 0..vals.len() {
        let Some((second, m)) = as_link(&vals[n]) else {
            continue;
        };
        let Some((first, a)) = as_link(&vals[m]) else {
            continue;
        };
        let pair = match (first, second) {
            (Link::Imm(i), Link::Unary(op)) => Pair::ImmUnary(i, op),
            (Link::Unary(op), Link::Imm(i)) => Pair::UnaryImm(op, i),
            (Link::Imm(i), Link::Imm(j)) => Pair::ImmImm(i, j),
            (Link::Unary(_), Link::Unary(_)) => continue,
        };
        if uses[m] == 1 {
            vals[n] = Val::Pair { a, pair };
        }
    }
}

/// Register allocation over the values reachable from the outputs: x, y, z
/// in registers 0..3, then parameters and the constants still read from
/// registers, then temporaries, reused once their last reader has run (and
/// only after it has written, so an output never aliases its inputs).
fn allocate(vals: &[Val], outputs: &[usize], nparams: usize) -> Plan {
    let n = vals.len();
    let mut live = vec![false; n];
    for &o in outputs {
        live[o] = true;
    }
    for i in (0..n).rev() {
        if live[i] {
            for a in operands(&vals[i]) {
                live[a] = true;
            }
        }
    }
    let mut last_use = vec![0usize; n];
    for i in (0..n).filter(|&i| live[i]) {
        for a in operands(&vals[i]) {
            last_use[a] = i;
        }
    }
    for &o in outputs {
        last_use[o] = usize::MAX;
    }

    let mut reg = vec![u32::MAX; n];
    let mut params = vec![0u32; nparams];
    let mut consts = Vec::new();
    let mut nregs = 3u32;
    for i in 0..n {
        match vals[i] {
            Val::Input(r) => reg[i] = r,
            Val::Param(k) => {
                reg[i] = nregs;
                params[k] = nregs;
                nregs += 1;
            }
            Val::Const(c) if live[i] => {
                reg[i] = nregs;
                consts.push((nregs, c));
                nregs += 1;
            }
            _ => {}
        }
    }
    let computed = |v: &Val| !matches!(v, Val::Input(_) | Val::Const(_) | Val::Param(_));
    let mut dying: Vec<Vec<usize>> = vec![Vec::new(); n];
    for i in 0..n {
        if live[i] && last_use[i] != usize::MAX && computed(&vals[i]) {
            dying[last_use[i]].push(i);
        }
    }
    let mut free: Vec<u32> = Vec::new();
    let mut steps = Vec::new();
    for i in 0..n {
        if !live[i] || !computed(&vals[i]) {
            continue;
        }
        let out = free.pop().unwrap_or_else(|| {
            nregs += 1;
            nregs - 1
        });
        reg[i] = out;
        let r = |v: usize| reg[v];
        steps.push(match vals[i] {
            Val::Unary(op, a) => Step::Unary { op, out, a: r(a) },
            Val::Binary(op, a, b) => Step::Binary {
                op,
                out,
                a: r(a),
                b: r(b),
            },
            Val::BinaryImm(imm, a) => Step::BinaryImm { imm, out, a: r(a) },
            Val::Pair { a, pair } => Step::Pair { out, a: r(a), pair },
            Val::PowI(a, n) => Step::PowI { out, a: r(a), n },
            Val::Select(c, a, b) => Step::Select {
                out,
                c: r(c),
                a: r(a),
                b: r(b),
            },
            Val::Field { field, comp, args } => Step::Field {
                out,
                field,
                comp,
                args: args.map(r),
            },
            Val::RFun {
                a,
                b,
                squares,
                union,
            } => Step::RFun {
                out,
                a: r(a),
                b: r(b),
                squares: squares.map(|(qa, qb)| (r(qa), r(qb))),
                union,
            },
            Val::Input(_) | Val::Const(_) | Val::Param(_) => unreachable!("skipped above"),
        });
        free.extend(dying[i].iter().map(|&d| reg[d]));
    }
    Plan {
        steps,
        nregs: nregs as usize,
        consts,
        params,
        outputs: outputs.iter().map(|&o| reg[o]).collect(),
    }
}
