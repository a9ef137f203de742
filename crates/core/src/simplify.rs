//! Per-region tape simplification: where interval evaluation over a region
//! (a brick, a tile) decides a branch of a set operation, the region is
//! evaluated with a shorter tape (as libfive and Fidget do).
//!
//! Two kinds of shortcut:
//! - exact: `min(a, b)` where `a <= b` on the whole region is `a` (and the
//!   like for `max`), `select(c, a, b)` with a decided condition is the
//!   branch; values are unchanged bit for bit;
//! - sign-preserving, only where the consumer reads just the sign and the
//!   zero set of the output (the set-operation tree above output 0, with
//!   [`Simplify::Sign`]): an R-function intersection whose argument `a` is
//!   positive on the whole region has the sign of `b` there (and `b`'s zero
//!   set), so it is replaced by `b`; a union whose argument is negative by
//!   the other one. Values change (the R-function rounds differently), so a
//!   consumer that stitches regions must evaluate shared samples with the
//!   full tape.
//!
//! Shortcuts are taken only where the interval excludes NaN, so undefined
//! points stay undefined.

use crate::interval::Interval;
use crate::ops::{BinaryOp, SetOp};
use crate::tape::{Op, Tape, ValueId};

/// Which shortcuts are allowed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Simplify {
    /// Only those that keep every value bit for bit.
    Exact,
    /// Also sign-preserving ones above output 0 (its sign and zero set
    /// are kept; other outputs stay exact).
    Sign,
}

fn clean(i: &Interval) -> bool {
    !i.may_be_nan() && i.lo <= i.hi
}

fn positive_const(t: &Tape, v: ValueId) -> bool {
    matches!(t.ops()[v as usize], Op::Const(c) if c > 0.0 && c.is_finite())
}

impl Tape {
    /// The tape with the branches decided by `intervals` (the bounds of
    /// every value over a region, [`crate::IntervalEval::values`]) cut
    /// away, or `None` when nothing could be cut.
    pub fn simplify(&self, intervals: &[Interval], mode: Simplify) -> Option<Tape> {
        let ops = self.ops();
        let n = ops.len();
        debug_assert_eq!(intervals.len(), n);
        // Values whose every reader only needs their sign (and zero set).
        let sign_ctx = if mode == Simplify::Sign {
            sign_context(self)
        } else {
            vec![false; n]
        };
        // Where each old value now comes from (an old value id).
        let mut alias: Vec<ValueId> = (0..n as ValueId).collect();
        let mut cut = false;
        for (i, op) in ops.iter().enumerate() {
            let pick = |v: ValueId| alias[v as usize];
            let iv = |v: ValueId| intervals[v as usize];
            let to = match *op {
                Op::Binary(BinaryOp::Min, a, b) if clean(&iv(a)) && clean(&iv(b)) => {
                    if iv(a).hi < iv(b).lo {
                        Some(pick(a))
                    } else if iv(b).hi < iv(a).lo {
                        Some(pick(b))
                    } else {
                        None
                    }
                }
                Op::Binary(BinaryOp::Max, a, b) if clean(&iv(a)) && clean(&iv(b)) => {
                    if iv(a).lo > iv(b).hi {
                        Some(pick(a))
                    } else if iv(b).lo > iv(a).hi {
                        Some(pick(b))
                    } else {
                        None
                    }
                }
                Op::Select(c, a, b) if clean(&iv(c)) => {
                    let ic = iv(c);
                    if ic.lo > 0.0 || ic.hi < 0.0 {
                        Some(pick(a))
                    } else if ic.lo == 0.0 && ic.hi == 0.0 {
                        Some(pick(b))
                    } else {
                        None
                    }
                }
                Op::Set { op, a, b, alpha } if sign_ctx[i] && clean(&iv(a)) && clean(&iv(b)) => {
                    let al = iv(alpha);
                    let law = al.lo == al.hi && al.lo > -1.0 && al.lo <= 1.0;
                    match op {
                        _ if !law => None,
                        SetOp::Intersection if iv(a).lo > 0.0 => Some(pick(b)),
                        SetOp::Intersection if iv(b).lo > 0.0 => Some(pick(a)),
                        SetOp::Union if iv(a).hi < 0.0 => Some(pick(b)),
                        SetOp::Union if iv(b).hi < 0.0 => Some(pick(a)),
                        _ => None,
                    }
                }
                _ => None,
            };
            if let Some(t) = to {
                alias[i] = t;
                cut = true;
            }
        }
        if !cut {
            return None;
        }
        // Rebuild from the outputs through the aliases, dropping dead values.
        let outputs: Vec<ValueId> = self.outputs().iter().map(|&o| alias[o as usize]).collect();
        let mut live = vec![false; n];
        for &o in &outputs {
            live[o as usize] = true;
        }
        for i in (0..n).rev() {
            if live[i] {
                for a in remap(&ops[i], &alias).operands() {
                    live[a as usize] = true;
                }
            }
        }
        let mut new_id = vec![ValueId::MAX; n];
        let mut new_ops = Vec::new();
        for i in (0..n).filter(|&i| live[i]) {
            let op = remap(&ops[i], &alias);
            let op = remap_ids(&op, &new_id);
            new_id[i] = new_ops.len() as ValueId;
            new_ops.push(op);
        }
        let outputs = outputs.iter().map(|&o| new_id[o as usize]).collect();
        Some(Tape::from_parts(
            new_ops,
            outputs,
            self.params().to_vec(),
            self.fields().to_vec(),
        ))
    }
}

/// `op` with its operands replaced through `f`.
fn map_operands(op: &Op, f: impl Fn(ValueId) -> ValueId) -> Op {
    match *op {
        Op::Var(_) | Op::Const(_) | Op::Param(_) => *op,
        Op::Unary(u, a) => Op::Unary(u, f(a)),
        Op::Binary(b, x, y) => Op::Binary(b, f(x), f(y)),
        Op::PowI(a, k) => Op::PowI(f(a), k),
        Op::Select(c, a, b) => Op::Select(f(c), f(a), f(b)),
        Op::Set { op, a, b, alpha } => Op::Set {
            op,
            a: f(a),
            b: f(b),
            alpha: f(alpha),
        },
        Op::Field { field, comp, args } => Op::Field {
            field,
            comp,
            args: args.map(f),
        },
    }
}

fn remap(op: &Op, alias: &[ValueId]) -> Op {
    map_operands(op, |v| alias[v as usize])
}

fn remap_ids(op: &Op, ids: &[ValueId]) -> Op {
    map_operands(op, |v| ids[v as usize])
}

/// For each value, whether all its readers use only its sign: it is
/// output 0 (and no other output) or read only by set operations, min,
/// max, negation or positive scalings that are themselves sign-only.
fn sign_context(t: &Tape) -> Vec<bool> {
    let ops = t.ops();
    let n = ops.len();
    let mut uses = vec![0u32; n];
    for op in ops {
        for a in op.operands() {
            uses[a as usize] += 1;
        }
    }
    let outs = t.outputs();
    for &o in outs {
        uses[o as usize] += 1;
    }
    let mut sign_uses = vec![0u32; n];
    let mut ctx = vec![false; n];
    if let Some(&o) = outs.first() {
        sign_uses[o as usize] += 1;
    }
    for i in (0..n).rev() {
        ctx[i] = uses[i] > 0 && sign_uses[i] == uses[i];
        if !ctx[i] {
            continue;
        }
        match ops[i] {
            Op::Set { a, b, .. } | Op::Binary(BinaryOp::Min | BinaryOp::Max, a, b) => {
                sign_uses[a as usize] += 1;
                sign_uses[b as usize] += 1;
            }
            Op::Unary(crate::ops::UnaryOp::Neg, a) => sign_uses[a as usize] += 1,
            Op::Binary(BinaryOp::Mul | BinaryOp::Div, a, c) if positive_const(t, c) => {
                sign_uses[a as usize] += 1
            }
            Op::Binary(BinaryOp::Mul, c, a) if positive_const(t, c) => sign_uses[a as usize] += 1,
            _ => {}
        }
    }
    ctx
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frep::{intersection, union};
    use crate::{BatchEval, Expr, IntervalEval, PointEval};

    fn region(t: &Tape, lo: [f64; 3], hi: [f64; 3]) -> Vec<Interval> {
        let mut ie = IntervalEval::new(t);
        ie.eval(
            Interval::new(lo[0], hi[0]),
            Interval::new(lo[1], hi[1]),
            Interval::new(lo[2], hi[2]),
        );
        ie.values().to_vec()
    }

    #[test]
    fn decided_min_and_select_cut_exactly() {
        let [x, y, z] = Expr::xyz();
        let heavy = (x.sin() * y.cos() + &z).sin();
        let e = heavy.min(&(10.0 + &x)) + Expr::select(x.gt(5.0), y.clone(), z.clone());
        let t = Tape::new(&e);
        let (lo, hi) = ([-1.0; 3], [1.0; 3]);
        let s = t.simplify(&region(&t, lo, hi), Simplify::Exact).unwrap();
        assert!(s.len() < t.len(), "{} vs {}", s.len(), t.len());
        let (mut a, mut b) = (PointEval::new(&t), PointEval::new(&s));
        for k in 0..200 {
            let p = [
                (k % 7) as f64 / 3.5 - 1.0,
                (k % 5) as f64 / 2.5 - 1.0,
                (k % 3) as f64 - 1.0,
            ];
            assert_eq!(a.eval(p).to_bits(), b.eval(p).to_bits());
        }
    }

    #[test]
    fn decided_set_branches_keep_the_sign_and_only_the_sign() {
        let [x, y, z] = Expr::xyz();
        let lattice = (3.0 * &x).sin() * (3.0 * &y).cos() + (3.0 * &z).sin() - 0.2;
        let ball = 4.0 - (x.square() + y.square() + z.square());
        let shell = intersection(&ball, &(x.square() + y.square() + z.square() - 3.0), 0.0);
        let part = union(&shell, &intersection(&ball, &lattice, 0.0), 0.0);
        let t = Tape::new(&part);
        // Deep inside the ball, away from the shell: the lattice alone.
        let (lo, hi) = ([-0.5; 3], [0.5; 3]);
        assert!(t.simplify(&region(&t, lo, hi), Simplify::Exact).is_none());
        let s = t.simplify(&region(&t, lo, hi), Simplify::Sign).unwrap();
        assert!(s.len() * 2 < t.len(), "{} vs {}", s.len(), t.len());
        let (mut a, mut b) = (PointEval::new(&t), PointEval::new(&s));
        let mut changed = 0;
        for k in 0..2000 {
            let f = |m: usize| ((k * m) % 997) as f64 / 997.0 - 0.5;
            let p = [f(7), f(13), f(29)];
            let (va, vb) = (a.eval(p), b.eval(p));
            assert_eq!(va >= 0.0, vb >= 0.0, "{p:?}: {va} vs {vb}");
            changed += (va != vb) as usize;
        }
        assert!(changed > 0, "values should differ: only the sign is kept");
        // The batch path runs the shortened tape.
        let mut out = [0.0f32; 1];
        BatchEval::new(&s).eval(&[0.1], &[0.2], &[0.3], &mut out);
        assert_eq!(
            out[0] >= 0.0,
            b.eval([0.1f32 as f64, 0.2f32 as f64, 0.3f32 as f64]) >= 0.0
        );
    }

    #[test]
    fn nan_and_other_outputs_block_shortcuts() {
        let [x, y, _] = Expr::xyz();
        let e = intersection(&(10.0 + &x), &y, 0.0);
        // As a second output the value must stay exact.
        let t = Tape::with_outputs(&[Expr::constant(1.0), e.clone()]);
        assert!(t
            .simplify(&region(&t, [-1.0; 3], [1.0; 3]), Simplify::Sign)
            .is_none());
        let t = Tape::new(&e);
        assert!(t
            .simplify(&region(&t, [-1.0; 3], [1.0; 3]), Simplify::Sign)
            .is_some());
        let undefined = intersection(&(10.0 + &x).sqrt().sqrt(), &y, 0.0);
        let t = Tape::new(&undefined);
        // sqrt of a possibly negative value may be NaN over a wide region.
        assert!(t
            .simplify(&region(&t, [-20.0; 3], [1.0; 3]), Simplify::Sign)
            .is_none());
    }
}
