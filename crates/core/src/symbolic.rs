//! Symbolic differentiation of expressions, for operations whose definition
//! contains a gradient (the normalised offset, Eq. 14). The derivative rules
//! mirror `eval::deriv`, written as expressions.

use crate::expr::{Expr, ExprNode};
use crate::ops::{BinaryOp, SetOp, UnaryOp};
use std::collections::HashMap;
use std::sync::Arc;

type Grad = [Expr; 3];

fn zero() -> Grad {
    [
        Expr::constant(0.0),
        Expr::constant(0.0),
        Expr::constant(0.0),
    ]
}

fn is_zero(e: &Expr) -> bool {
    e.as_const() == Some(0.0)
}

/// `d * k` per component, skipping known zeros.
fn scale(d: &Grad, k: &Expr) -> Grad {
    std::array::from_fn(|i| {
        if is_zero(&d[i]) {
            Expr::constant(0.0)
        } else {
            &d[i] * k
        }
    })
}

fn add(a: &Grad, b: &Grad) -> Grad {
    std::array::from_fn(|i| match (is_zero(&a[i]), is_zero(&b[i])) {
        (true, _) => b[i].clone(),
        (_, true) => a[i].clone(),
        _ => &a[i] + &b[i],
    })
}

impl Expr {
    /// The gradient `(df/dx, df/dy, df/dz)` as expressions.
    pub fn gradient(&self) -> [Expr; 3] {
        let mut memo = HashMap::new();
        grad(self, &mut memo)
    }
}

/// Children whose gradients the gradient of `e` is built from.
fn grad_inputs(e: &Expr) -> Vec<&Expr> {
    match e.node() {
        ExprNode::Var(_) | ExprNode::Const(_) | ExprNode::Param { .. } => vec![],
        ExprNode::Unary(_, a) | ExprNode::PowI(a, _) => vec![a],
        ExprNode::Binary(_, a, b) | ExprNode::Select(_, a, b) => vec![a, b],
        ExprNode::Set { a, b, alpha, .. } => vec![a, b, alpha],
        ExprNode::Blend { args, .. } => args.iter().collect(),
        // Second derivatives of data fields are not modelled.
        ExprNode::Field { comp, args, .. } if *comp == 0 => args.iter().collect(),
        ExprNode::Field { .. } => vec![],
    }
}

/// Iterative post-order walk (models chain 100k nodes deep): a node's
/// gradient is built once those of its inputs are in `memo`.
fn grad(root: &Expr, memo: &mut HashMap<*const ExprNode, Grad>) -> Grad {
    let key = |e: &Expr| Arc::as_ptr(&e.0);
    let mut stack: Vec<(&Expr, bool)> = vec![(root, false)];
    while let Some((e, expanded)) = stack.pop() {
        if memo.contains_key(&key(e)) {
            continue;
        }
        if !expanded {
            stack.push((e, true));
            for c in grad_inputs(e).into_iter().rev() {
                if !memo.contains_key(&key(c)) {
                    stack.push((c, false));
                }
            }
            continue;
        }
        let d = |c: &Expr| &memo[&key(c)];
        let g = match e.node() {
            ExprNode::Var(a) => {
                let mut g = zero();
                g[*a as usize] = Expr::constant(1.0);
                g
            }
            ExprNode::Const(_) | ExprNode::Param { .. } => zero(),
            ExprNode::Unary(op, a) => scale(d(a), &unary_factor(*op, a, e)),
            ExprNode::Binary(op, a, b) => {
                let (ka, kb) = binary_factors(*op, a, b, e);
                add(&scale(d(a), &ka), &scale(d(b), &kb))
            }
            ExprNode::PowI(a, n) => scale(d(a), &(*n as f64 * a.powi(n - 1))),
            ExprNode::Select(c, a, b) => {
                let (da, db) = (d(a), d(b));
                std::array::from_fn(|i| Expr::select(c.clone(), da[i].clone(), db[i].clone()))
            }
            ExprNode::Set { op, a, b, alpha } => {
                let [ka, kb, kc] = set_factors(*op, a, b, alpha, e);
                add(
                    &add(&scale(d(a), &ka), &scale(d(b), &kb)),
                    &scale(d(alpha), &kc),
                )
            }
            ExprNode::Blend { op, args } => {
                let [a, b, alpha, a0, a1, a2] = &**args;
                let set = Expr::set(*op, a, b, alpha.clone());
                let [ka, kb, kc] = set_factors(*op, a, b, alpha, &set);
                // D = a0 / q, q = 1 + (a/a1)^2 + (b/a2)^2.
                let q = 1.0 + (a / a1).square() + (b / a2).square();
                let m = -(a0 / q.square());
                let k0 = 1.0 / &q;
                let qa = 2.0 * a / a1.square();
                let qb = 2.0 * b / a2.square();
                let q1 = -2.0 * a.square() / a1.powi(3);
                let q2 = -2.0 * b.square() / a2.powi(3);
                let parts = [
                    (a, &ka + &m * qa),
                    (b, &kb + &m * qb),
                    (alpha, kc),
                    (a0, k0),
                    (a1, &m * q1),
                    (a2, &m * q2),
                ];
                parts
                    .iter()
                    .fold(zero(), |acc, (x, k)| add(&acc, &scale(d(x), k)))
            }
            ExprNode::Field { field, comp, args } => {
                let mut out = zero();
                if *comp == 0 {
                    for (k, arg) in args.iter().enumerate() {
                        let part = Expr::field_comp(field.clone(), k as u8 + 1, args.clone());
                        out = add(&out, &scale(d(arg), &part));
                    }
                }
                out
            }
        };
        memo.insert(key(e), g);
    }
    memo[&key(root)].clone()
}

/// Partial derivatives of the R-function `v = op(a, b; alpha)` as
/// expressions (see [`crate::SetOp::partials`]; `(1, 1, 0) / (1 + alpha)`
/// where the root vanishes).
fn set_factors(op: SetOp, a: &Expr, b: &Expr, alpha: &Expr, v: &Expr) -> [Expr; 3] {
    let s = if op == SetOp::Union { 1.0 } else { -1.0 };
    let k = 1.0 + alpha;
    let r = (a.square() + b.square() - 2.0 * alpha * a * b).sqrt();
    let zero_r = r.eq_(0.0);
    let guard = |f: Expr, at_zero: Expr| Expr::select(zero_r.clone(), at_zero, f);
    let ka = guard((1.0 + s * (a - alpha * b) / &r) / &k, 1.0 / &k);
    let kb = guard((1.0 + s * (b - alpha * a) / &r) / &k, 1.0 / &k);
    let kc = guard((-s * a * b / &r) / &k - v / &k, Expr::constant(0.0));
    [ka, kb, kc]
}

fn unary_factor(op: UnaryOp, a: &Expr, v: &Expr) -> Expr {
    use UnaryOp::*;
    match op {
        Neg => Expr::constant(-1.0),
        Abs => a.sign(),
        Sqrt => 0.5 / v,
        Square => 2.0 * a,
        Exp => v.clone(),
        Ln => 1.0 / a,
        Sin => a.cos(),
        Cos => -a.sin(),
        Tan => 1.0 + v.square(),
        Asin => 1.0 / (1.0 - a.square()).sqrt(),
        Acos => -1.0 / (1.0 - a.square()).sqrt(),
        Atan => 1.0 / (1.0 + a.square()),
        Sinh => a.cosh(),
        Cosh => a.sinh(),
        Tanh => 1.0 - v.square(),
        Sign | Floor | Ceil | Trunc | Round | Not => Expr::constant(0.0),
        Fract | Saw => Expr::constant(1.0),
        Tri => {
            let s = 0.5 * a + 0.25;
            Expr::select(s.fract().lt(0.5), Expr::constant(1.0), Expr::constant(-1.0))
        }
    }
}

fn binary_factors(op: BinaryOp, a: &Expr, b: &Expr, v: &Expr) -> (Expr, Expr) {
    use BinaryOp::*;
    let c = Expr::constant;
    match op {
        Add => (c(1.0), c(1.0)),
        Sub => (c(1.0), c(-1.0)),
        Mul => (b.clone(), a.clone()),
        Div => (1.0 / b, -(a / b.square())),
        Pow => (
            // As in `eval::deriv`: 0 at b = 0, where b a^(b-1) would be 0 * inf at a = 0.
            Expr::select(b.eq_(0.0), c(0.0), b * a.pow(b - 1.0)),
            Expr::select(a.gt(0.0), v * a.max(1e-300).ln(), c(0.0)),
        ),
        Atan2 => {
            let r2 = a.square() + b.square();
            (b / &r2, -(a / r2))
        }
        Min => {
            let s = a.le(b);
            (
                Expr::select(s.clone(), c(1.0), c(0.0)),
                Expr::select(s, c(0.0), c(1.0)),
            )
        }
        Max => {
            let s = a.ge(b);
            (
                Expr::select(s.clone(), c(1.0), c(0.0)),
                Expr::select(s, c(0.0), c(1.0)),
            )
        }
        Mod => (c(1.0), -(a / b).floor()),
        Rem => (c(1.0), -(a / b).trunc()),
        Lt | Le | Gt | Ge | Eq | Ne | And | Or => (c(0.0), c(0.0)),
    }
}
