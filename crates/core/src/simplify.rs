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
    /// [`Simplify::Exact`] and identities that keep every output bit for
    /// bit too, once branches are cut: `x * 1`, `1 * x`, `x / 1`, `x - 0`,
    /// `x + (-0)` are `x`; `select(c, a, a)` is `a`; and a sum or
    /// difference `a + z`, `z + a`, `a - z` with `z` proven to be a signed
    /// zero (a product or quotient of a zero with a value the region
    /// bounds away from infinity, such as a gradient term whose branch
    /// was cut) is `a` where the region bounds `a` away from zero (as the
    /// branch cuts, this trusts the bounds to hold the f32 values, with
    /// wide margins against underflow and overflow). For consumers that
    /// evaluate one shortened tape per region (the attribute layers).
    Folded,
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
        // Values proven to be a signed zero (only with Folded).
        let mut zero = vec![false; n];
        let fold = mode == Simplify::Folded;
        let mut cut = false;
        for (i, op) in ops.iter().enumerate() {
            let pick = |v: ValueId| alias[v as usize];
            let iv = |v: ValueId| intervals[v as usize];
            if fold {
                let (to, z) = fold_identity(ops, op, &alias, &zero, intervals);
                zero[i] = z;
                if let Some(t) = to {
                    alias[i] = t;
                    cut = true;
                    continue;
                }
            }
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

/// Bounds far from f32 overflow (and from f32 underflow for
/// [`nonzero`]): a product of a finite f32 with a zero is a zero, and a
/// value bounded away from zero by this much is not rounded to zero.
const FINITE: f64 = 1e30;
const TINY: f64 = 1e-30;

fn finite(i: &Interval) -> bool {
    clean(i) && i.lo > -FINITE && i.hi < FINITE
}

fn nonzero(i: &Interval) -> bool {
    clean(i) && (i.lo > TINY || i.hi < -TINY)
}

/// The identity folds of [`Simplify::Folded`] for `op` (operands read
/// through `alias`): the old value `op` equals, if any, and whether `op`
/// is proven to be a signed zero.
fn fold_identity(
    ops: &[Op],
    op: &Op,
    alias: &[ValueId],
    zero: &[bool],
    intervals: &[Interval],
) -> (Option<ValueId>, bool) {
    let pick = |v: ValueId| alias[v as usize];
    let konst = |v: ValueId| match ops[pick(v) as usize] {
        Op::Const(c) => Some(c),
        _ => None,
    };
    let one = |v: ValueId| konst(v).is_some_and(|c| c == 1.0);
    // A zero constant of either sign, or a value proven zero.
    let is_zero = |v: ValueId| zero[pick(v) as usize] || konst(v) == Some(0.0);
    let is_const = |v: ValueId, bits: u64| konst(v).is_some_and(|c| c.to_bits() == bits);
    let iv = |v: ValueId| intervals[v as usize];
    match *op {
        Op::Binary(BinaryOp::Mul, a, b) if one(b) => (Some(pick(a)), false),
        Op::Binary(BinaryOp::Mul, a, b) if one(a) => (Some(pick(b)), false),
        Op::Binary(BinaryOp::Div, a, b) if one(b) => (Some(pick(a)), false),
        Op::Binary(BinaryOp::Mul, a, b) => (
            None,
            (is_zero(a) && finite(&iv(b))) || (is_zero(b) && finite(&iv(a))),
        ),
        Op::Binary(BinaryOp::Div, a, b) => (None, is_zero(a) && nonzero(&iv(b))),
        // x - (+0) and x + (-0) are x for every x, -0 included.
        Op::Binary(BinaryOp::Sub, a, b) if is_const(b, 0f64.to_bits()) => (Some(pick(a)), false),
        Op::Binary(BinaryOp::Add, a, b) if is_const(b, (-0f64).to_bits()) => (Some(pick(a)), false),
        Op::Binary(BinaryOp::Add, a, b) if is_const(a, (-0f64).to_bits()) => (Some(pick(b)), false),
        // a + z and a - z are a when a is not a zero itself.
        Op::Binary(BinaryOp::Add | BinaryOp::Sub, a, b) if is_zero(b) && nonzero(&iv(a)) => {
            (Some(pick(a)), false)
        }
        Op::Binary(BinaryOp::Add, a, b) if is_zero(a) && nonzero(&iv(b)) => (Some(pick(b)), false),
        Op::Select(_, a, b) if pick(a) == pick(b) => (Some(pick(a)), false),
        Op::Select(_, a, b) => (None, is_zero(a) && is_zero(b)),
        Op::Unary(crate::ops::UnaryOp::Neg | crate::ops::UnaryOp::Square, a) => (None, is_zero(a)),
        _ => (None, false),
    }
}

/// `op` with its operands replaced through `f`.
pub(crate) fn map_operands(op: &Op, f: impl Fn(ValueId) -> ValueId) -> Op {
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

    /// The gradient of max(a, b) written out (the derivative of each side
    /// times a select of 1 or 0, as symbolic differentiation writes it):
    /// where the region decides the max, Folded drops the products with 1,
    /// the products with the other side's 0 and their sums, leaving a
    /// shorter tape than Exact, with the same bits in f32 and f64.
    #[test]
    fn folds_of_decided_derivatives_keep_the_bits() {
        let [x, y, z] = Expr::xyz();
        let a = (&x - 0.3).square() + y.square() * 2.0 + 1.0;
        let b = (&y * 1.7).sin() * &z + 0.5;
        let pick = a.ge(&b);
        let one = Expr::constant(1.0);
        let zero = Expr::constant(0.0);
        let sa = Expr::select(pick.clone(), one.clone(), zero.clone());
        let sb = Expr::select(pick, zero, one);
        let ga = [2.0 * (&x - 0.3), 4.0 * &y, Expr::constant(0.0) * &x];
        let gb = [
            Expr::constant(0.0) * &x,
            1.7 * (&y * 1.7).cos() * &z,
            (&y * 1.7).sin(),
        ];
        let grad: Vec<Expr> = (0..3).map(|k| &ga[k] * &sa + &gb[k] * &sb).collect();
        let e = (grad[0].square() + grad[1].square() + grad[2].square()).sqrt();
        let t = Tape::new(&e);
        // a >= 1 + ... > b there: a's side only.
        let (lo, hi) = ([0.5, 0.2, -0.4], [0.9, 0.6, 0.4]);
        let iv = region(&t, lo, hi);
        let exact = t.simplify(&iv, Simplify::Exact).unwrap();
        let folded = t.simplify(&iv, Simplify::Folded).unwrap();
        assert!(
            folded.len() + 8 < exact.len(),
            "{} vs {}",
            folded.len(),
            exact.len()
        );
        let (mut pt, mut pf) = (PointEval::new(&t), PointEval::new(&folded));
        let (mut bt, mut bf) = (BatchEval::new(&t), BatchEval::new(&folded));
        for k in 0..500 {
            let f = |m: usize, d: usize| lo[d] + (hi[d] - lo[d]) * ((k * m) % 499) as f64 / 498.0;
            let p = [f(7, 0), f(13, 1), f(29, 2)];
            assert_eq!(pt.eval(p).to_bits(), pf.eval(p).to_bits(), "{p:?}");
            let (px, py, pz) = ([p[0] as f32], [p[1] as f32], [p[2] as f32]);
            let (mut u, mut v) = ([0f32], [0f32]);
            bt.eval(&px, &py, &pz, &mut u);
            bf.eval(&px, &py, &pz, &mut v);
            assert_eq!(u[0].to_bits(), v[0].to_bits(), "{p:?}");
        }
    }

    /// A zero product is added away only to a value bounded away from
    /// zero (-0 + +0 is +0, not -0), and only when the factor is bounded
    /// (0 times infinity is NaN); x * 1 and x - 0 fold always.
    #[test]
    fn zero_sums_fold_only_where_the_bits_are_kept() {
        let [x, y, _] = Expr::xyz();
        let zero = Expr::constant(0.0);
        let t = Tape::new(&(&x + &zero * &y));
        // x straddles 0 here: x + 0 y is +0 where x = -0.
        let iv = region(&t, [-1.0, 1.0, 0.0], [1.0, 2.0, 0.0]);
        assert!(t.simplify(&iv, Simplify::Folded).is_none());
        // x positive: x alone (nothing computed).
        let iv = region(&t, [0.5, 1.0, 0.0], [1.0, 2.0, 0.0]);
        assert!(t.simplify(&iv, Simplify::Folded).unwrap().is_empty());
        // 0 / y with y reaching 0 may be NaN: kept.
        let t = Tape::new(&(&x + &zero / &y));
        let iv = region(&t, [0.5, -1.0, 0.0], [1.0, 1.0, 0.0]);
        assert!(t.simplify(&iv, Simplify::Folded).is_none());
        // Selects the region decides leave x * 1 / 1 - 0: x.
        let c = Expr::constant;
        let big = y.gt(5.0);
        let e = &x * Expr::select(big.clone(), c(2.0), c(1.0));
        let e = e / Expr::select(big.clone(), c(3.0), c(1.0)) - Expr::select(big, c(4.0), c(0.0));
        let t = Tape::new(&e);
        let iv = region(&t, [-1.0, -1.0, 0.0], [1.0, 1.0, 0.0]);
        assert_eq!(t.simplify(&iv, Simplify::Exact).unwrap().len(), 3);
        assert!(t.simplify(&iv, Simplify::Folded).unwrap().is_empty());
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
