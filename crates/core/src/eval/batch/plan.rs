//! Lowering of a tape into the batch evaluator's own program.
//!
//! Each batch step streams whole blocks through the L1 cache, so its cost is
//! mostly loads and stores. The plan cuts them: constant operands become
//! immediates broadcast in the loop instead of register blocks; set
//! operations (R-functions, the bulk of most FRep models) are single steps
//! with their parameter as an immediate; and two one-operand steps in a row
//! (`2 * t - 1`, `tri(x / w)`, `sin(v) - l`: the scalings around waves and
//! periodic functions) run as one, their temporaries kept in vector
//! registers. Results are bit-identical to the unfused code: the same f32
//! operations run in the same order.
//!
//! The plan rewrites the tape's SSA values and then gives them registers:
//! this is the core's one register allocator ([`allocate`]).

use crate::ops::{BinaryOp, SetOp, UnaryOp};
use crate::tape::{Op, Tape};

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
    Set {
        op: SetOp,
        a: usize,
        b: usize,
        alpha: usize,
    },
    /// A set operation with a constant parameter.
    SetImm {
        op: SetOp,
        a: usize,
        b: usize,
        alpha: SetAlpha,
    },
    Pair {
        a: usize,
        pair: Pair,
    },
}

/// The constants of a set operation with a fixed parameter, rounded to f32
/// from their f64 values as constant folding of the written-out formula
/// would (`2 alpha` and `1 + alpha`); `None` for alpha = 0, which has no
/// scale and no product term.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct SetAlpha(pub Option<(f32, f32)>);

impl SetAlpha {
    fn new(alpha: f64) -> SetAlpha {
        SetAlpha((alpha != 0.0).then(|| ((2.0 * alpha) as f32, (1.0 + alpha) as f32)))
    }
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
    /// A set operation whose parameter is a register.
    Set {
        op: SetOp,
        out: u32,
        a: u32,
        b: u32,
        alpha: u32,
    },
    /// A set operation with a constant parameter.
    SetImm {
        op: SetOp,
        out: u32,
        a: u32,
        b: u32,
        alpha: SetAlpha,
    },
    Pair {
        out: u32,
        a: u32,
        pair: Pair,
    },
}

#[derive(Debug)]
pub(crate) struct Plan {
    pub(super) steps: Vec<Step>,
    pub nregs: usize,
    /// Registers preloaded with constants that stayed register operands.
    pub consts: Vec<(u32, f32)>,
    /// Register of each tape parameter, in the tape's order.
    pub params: Vec<u32>,
    pub outputs: Vec<u32>,
}

pub(crate) fn lower(tape: &Tape) -> Plan {
    let (mut vals, outputs) = to_ssa(tape);
    fold_immediates(&mut vals);
    fuse_pairs(&mut vals, &outputs);
    allocate(&vals, &outputs, tape.params().len())
}

fn to_ssa(tape: &Tape) -> (Vec<Val>, Vec<usize>) {
    let vals = tape
        .ops()
        .iter()
        .map(|op| match *op {
            Op::Var(a) => Val::Input(a as u32),
            Op::Const(c) => Val::Const(c as f32),
            Op::Param(k) => Val::Param(k as usize),
            Op::Unary(op, a) => Val::Unary(op, a as usize),
            Op::Binary(op, a, b) => Val::Binary(op, a as usize, b as usize),
            Op::PowI(a, n) => Val::PowI(a as usize, n),
            Op::Select(c, a, b) => Val::Select(c as usize, a as usize, b as usize),
            Op::Set { op, a, b, alpha } => match tape.ops()[alpha as usize] {
                Op::Const(c) => Val::SetImm {
                    op,
                    a: a as usize,
                    b: b as usize,
                    alpha: SetAlpha::new(c),
                },
                _ => Val::Set {
                    op,
                    a: a as usize,
                    b: b as usize,
                    alpha: alpha as usize,
                },
            },
            Op::Field { field, comp, args } => Val::Field {
                field,
                comp,
                args: args.map(|a| a as usize),
            },
        })
        .collect();
    let outputs = tape.outputs().iter().map(|&o| o as usize).collect();
    (vals, outputs)
}

fn operands(v: &Val) -> Vec<usize> {
    match *v {
        Val::Input(_) | Val::Const(_) | Val::Param(_) => vec![],
        Val::Unary(_, a) | Val::PowI(a, _) | Val::BinaryImm(_, a) | Val::Pair { a, .. } => {
            vec![a]
        }
        Val::Binary(_, a, b) => vec![a, b],
        Val::Set { a, b, alpha, .. } => vec![a, b, alpha],
        Val::SetImm { a, b, .. } => vec![a, b],
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

/// The register allocator: allocation over the values reachable from the outputs: x, y, z
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
            Val::Set { op, a, b, alpha } => Step::Set {
                op,
                out,
                a: r(a),
                b: r(b),
                alpha: r(alpha),
            },
            Val::SetImm { op, a, b, alpha } => Step::SetImm {
                op,
                out,
                a: r(a),
                b: r(b),
                alpha,
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
