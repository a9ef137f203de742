//! One costly operation for both branches of a `select`: where
//! `select(c, A, B)` has, among the values only `A` needs, some
//! `pow(u1, e)` and, among those only `B` needs, `pow(u2, e)` (the same
//! exponent), both become `pow(select(c, u1, u2), e)`. At every point the
//! branch the select picks sees the same operation on the same operand, so
//! every output keeps its bits, while the batch evaluator (which runs both
//! branches at every point) runs the costly operation once. Park's gain
//! `select(t < 1/2, pow(2t, g) / 2, 1 - pow(2 - 2t, g) / 2)` is the case
//! in point. Transcendental unary operations (`exp`, `ln`, `sin`, ...)
//! merge the same way.

use crate::ops::{BinaryOp, UnaryOp};
use crate::simplify::map_operands;
use crate::tape::{Op, Tape, ValueId};
use std::collections::HashMap;

/// Tapes longer than this are left alone (each select costs a pass over
/// the tape).
const MAX_OPS: usize = 50_000;
/// Merges tried at most per tape.
const MAX_MERGES: usize = 64;

/// Whether `op` is costly enough to merge: a real power or a
/// transcendental function (tens of simple steps each in the batch
/// evaluator).
fn costly(op: &Op) -> bool {
    use UnaryOp as U;
    matches!(
        op,
        Op::Binary(BinaryOp::Pow | BinaryOp::Atan2, ..)
            | Op::Unary(
                U::Exp
                    | U::Ln
                    | U::Sin
                    | U::Cos
                    | U::Tan
                    | U::Asin
                    | U::Acos
                    | U::Atan
                    | U::Sinh
                    | U::Cosh
                    | U::Tanh,
                _
            )
    )
}

/// The values reachable from the outputs, not following operand `skip`
/// (index 1 or 2: the select's first or second branch) of value `sel`.
fn reach(ops: &[Op], outputs: &[ValueId], sel: usize, skip: usize) -> Vec<bool> {
    let mut live = vec![false; ops.len()];
    for &o in outputs {
        live[o as usize] = true;
    }
    for i in (0..ops.len()).rev() {
        if !live[i] {
            continue;
        }
        for (k, a) in ops[i].operands().enumerate() {
            if !(i == sel && k == skip) {
                live[a as usize] = true;
            }
        }
    }
    live
}

/// The values only branch `which` (1 or 2) of select `sel` needs.
fn exclusive(ops: &[Op], outputs: &[ValueId], sel: usize, which: usize) -> Vec<bool> {
    let other = reach(ops, outputs, sel, which);
    let root = ops[sel]
        .operands()
        .nth(which)
        .expect("a select has 3 operands") as usize;
    let mut mine = vec![false; ops.len()];
    mine[root] = !other[root];
    for i in (0..=root).rev() {
        if mine[i] {
            for a in ops[i].operands() {
                mine[a as usize] = !other[a as usize];
            }
        }
    }
    mine
}

/// Whether two costly values apply the same operation with the same other
/// operand (constants compared by their bits); the operand that differs.
fn same_op(ops: &[Op], p: &Op, q: &Op) -> Option<(ValueId, ValueId)> {
    let same = |a: ValueId, b: ValueId| {
        a == b
            || matches!((ops[a as usize], ops[b as usize]),
                (Op::Const(x), Op::Const(y)) if x.to_bits() == y.to_bits())
    };
    match (*p, *q) {
        (Op::Binary(f, u1, e1), Op::Binary(g, u2, e2)) if f == g && same(e1, e2) => Some((u1, u2)),
        (Op::Unary(f, u1), Op::Unary(g, u2)) if f == g => Some((u1, u2)),
        _ => None,
    }
}

impl Tape {
    /// The tape with costly operations shared by the two branches of
    /// selects (see the module docs), or `None` when there were none.
    /// Every output keeps its bits at every point.
    pub fn merge_branches(&self) -> Option<Tape> {
        if self.len() > MAX_OPS {
            return None;
        }
        let (mut ops, mut outputs) = (self.ops().to_vec(), self.outputs().to_vec());
        let mut merged = 0;
        while merged < MAX_MERGES {
            let Some(next) = merge_once(&ops, &outputs) else {
                break;
            };
            (ops, outputs) = next;
            merged += 1;
        }
        (merged > 0)
            .then(|| Tape::from_parts(ops, outputs, self.params().to_vec(), self.fields().to_vec()))
    }
}

/// The first merge of the tape `ops`, `outputs` (see the module docs).
fn merge_once(ops: &[Op], outputs: &[ValueId]) -> Option<(Vec<Op>, Vec<ValueId>)> {
    for s in 0..ops.len() {
        let Op::Select(c, _, _) = ops[s] else {
            continue;
        };
        let in_a = exclusive(ops, outputs, s, 1);
        if !(0..s).any(|i| in_a[i] && costly(&ops[i])) {
            continue;
        }
        let in_b = exclusive(ops, outputs, s, 2);
        for p in (0..s).filter(|&i| in_a[i] && costly(&ops[i])) {
            for q in (0..s).filter(|&i| in_b[i] && costly(&ops[i])) {
                let Some((u1, u2)) = same_op(ops, &ops[p], &ops[q]) else {
                    continue;
                };
                let mut ops = ops.to_vec();
                // select(c, u1, u2), then the operation on it.
                let pick = ops.len() as ValueId;
                ops.push(Op::Select(c, u1, u2));
                let one = ops.len() as ValueId;
                ops.push(match ops[p] {
                    Op::Binary(f, _, e) => Op::Binary(f, pick, e),
                    Op::Unary(f, _) => Op::Unary(f, pick),
                    _ => unreachable!("costly ops are unary or binary"),
                });
                // The readers of p in branch a and of q in branch b (the
                // select too, if a branch is p or q itself) read the merged
                // value: no other value reads p or q.
                let (p, q) = (p as ValueId, q as ValueId);
                for (i, op) in ops.iter_mut().enumerate().take(pick as usize) {
                    if in_a[i] || in_b[i] || i == s {
                        *op = map_operands(op, |v| if v == p || v == q { one } else { v });
                    }
                }
                return Some(reorder(&ops, outputs));
            }
        }
    }
    None
}

/// Dependency order of the values the outputs need, equal values shared:
/// the new ops and the new ids of the outputs.
fn reorder(ops: &[Op], outputs: &[ValueId]) -> (Vec<Op>, Vec<ValueId>) {
    let mut new_id: Vec<ValueId> = vec![ValueId::MAX; ops.len()];
    let mut out_ops: Vec<Op> = Vec::new();
    let mut seen: HashMap<String, ValueId> = HashMap::new();
    for &root in outputs {
        // Iterative post-order.
        let mut stack = vec![(root as usize, false)];
        while let Some((v, expanded)) = stack.pop() {
            if new_id[v] != ValueId::MAX {
                continue;
            }
            if !expanded {
                stack.push((v, true));
                for a in ops[v].operands() {
                    if new_id[a as usize] == ValueId::MAX {
                        stack.push((a as usize, false));
                    }
                }
                continue;
            }
            let op = map_operands(&ops[v], |a| new_id[a as usize]);
            let key = match op {
                Op::Const(c) => format!("c{:x}", c.to_bits()),
                _ => format!("{op:?}"),
            };
            let id = *seen.entry(key).or_insert_with(|| {
                out_ops.push(op);
                (out_ops.len() - 1) as ValueId
            });
            new_id[v] = id;
        }
    }
    let outs = outputs.iter().map(|&o| new_id[o as usize]).collect();
    (out_ops, outs)
}

#[cfg(test)]
mod tests {
    use crate::{BatchEval, BinaryOp, Expr, Op, PointEval, Tape, UnaryOp};

    fn count(t: &Tape, f: impl Fn(&Op) -> bool) -> usize {
        t.ops().iter().filter(|op| f(op)).count()
    }

    fn pows(t: &Tape) -> usize {
        count(t, |op| matches!(op, Op::Binary(BinaryOp::Pow, ..)))
    }

    /// Points along x from -0.5 to 1.5 (both branches, the clamps, the
    /// branch point), and special values.
    fn points() -> Vec<f32> {
        let mut xs: Vec<f32> = (0..4001).map(|k| -0.5 + k as f32 * 5e-4).collect();
        xs.extend([0.5, 0.0, -0.0, 1.0, f32::NAN, f32::INFINITY, -f32::INFINITY]);
        xs
    }

    /// Both tapes give the same bits in f32 batches and in f64 points.
    fn same_everywhere(a: &Tape, b: &Tape) {
        let xs = points();
        let ys: Vec<f32> = xs.iter().map(|x| 0.3 - x).collect();
        let zs = vec![0.25f32; xs.len()];
        let (mut oa, mut ob) = (vec![0f32; xs.len()], vec![0f32; xs.len()]);
        BatchEval::new(a).eval(&xs, &ys, &zs, &mut oa);
        BatchEval::new(b).eval(&xs, &ys, &zs, &mut ob);
        let (mut pa, mut pb) = (PointEval::new(a), PointEval::new(b));
        for i in 0..xs.len() {
            let same = |u: f32, v: f32| u.to_bits() == v.to_bits() || (u.is_nan() && v.is_nan());
            assert!(same(oa[i], ob[i]), "x = {}: {} vs {}", xs[i], oa[i], ob[i]);
            let p = [xs[i] as f64, ys[i] as f64, zs[i] as f64];
            let (u, v) = (pa.eval(p), pb.eval(p));
            assert!(
                u.to_bits() == v.to_bits() || (u.is_nan() && v.is_nan()),
                "x = {}: {u} vs {v}",
                xs[i]
            );
        }
    }

    /// Schlick's gain of a biased x: the two powers of the gain become
    /// one, the bias's power stays, and every value keeps its bits.
    #[test]
    fn gain_powers_merge_with_the_same_bits() {
        let x = Expr::x();
        let t = x.max(0.0).min(1.0).pow(1.3).min(1.0);
        let g = 1.7;
        let gain = Expr::select(
            t.lt(0.5),
            0.5 * (2.0 * &t).pow(g),
            1.0 - 0.5 * (2.0 - 2.0 * &t).pow(g),
        );
        let full = Tape::new(&(1.0 - gain));
        assert_eq!(pows(&full), 3);
        let merged = full.merge_branches().expect("the gain's powers merge");
        assert_eq!(pows(&merged), 2);
        same_everywhere(&full, &merged);
    }

    /// A power also read outside its branch, or with another exponent in
    /// the other branch, stays; transcendental functions of both branches
    /// merge, nested selects too.
    #[test]
    fn only_powers_private_to_each_branch_and_alike_merge() {
        let [x, y, _] = Expr::xyz();
        let shared = (&x + 2.0).pow(1.5);
        let e = Expr::select(x.lt(&y), shared.clone(), (&y + 2.0).pow(1.5)) + &shared;
        assert!(Tape::new(&e).merge_branches().is_none());
        let e = Expr::select(x.lt(&y), (&x + 2.0).pow(1.5), (&y + 2.0).pow(2.5));
        assert!(Tape::new(&e).merge_branches().is_none());
        let inner = Expr::select(x.gt(0.0), (&x * 3.0).exp(), (&y * 2.0).exp() + 1.0);
        let e = Expr::select(y.gt(0.1), inner.sin(), (&x - &y).sin() * 2.0);
        let full = Tape::new(&e);
        let merged = full.merge_branches().expect("exp and sin merge");
        let un = |t: &Tape, u: UnaryOp| count(t, |op| matches!(op, Op::Unary(v, _) if *v == u));
        assert_eq!((un(&full, UnaryOp::Exp), un(&full, UnaryOp::Sin)), (2, 2));
        assert_eq!(
            (un(&merged, UnaryOp::Exp), un(&merged, UnaryOp::Sin)),
            (1, 1)
        );
        same_everywhere(&full, &merged);
    }
}
