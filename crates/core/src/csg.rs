//! Interval bounds that know the model's set operations. Plain interval
//! arithmetic on an R-function `f1 + f2 - sqrt(f1^2 + f2^2)` meets `f1`
//! twice and comes out loose, so on CSG trees of lattices and shells it
//! rarely proves a box empty until the box is tiny. A ray caster only needs
//! the sign, and an R-function intersection (union) with alpha in [-1, 1]
//! has everywhere the sign of `min` (`max`) of its arguments; so the tree of
//! set operations is read off the expression, its leaves get ordinary
//! interval evaluation, and the nodes combine them with `min`, `max` and
//! negation. The result bounds a function with the model's signs, not the
//! model's values: use it for "empty" (`hi < 0`) and "solid" (`lo >= 0`)
//! only. Shared by the mesher (brick classification, bounds) and the ray
//! caster.

use crate::{BinaryOp, Expr, ExprNode, Interval, IntervalEval, Tape, UnaryOp};

enum Node {
    Leaf(usize),
    And(Box<Node>, Box<Node>),
    Or(Box<Node>, Box<Node>),
    Not(Box<Node>),
}

/// A model's set-operation tree with its leaves compiled.
pub struct Csg {
    root: Node,
    tapes: Vec<Tape>,
}

fn same(a: &Expr, b: &Expr) -> bool {
    std::ptr::eq(a.node(), b.node())
}

fn positive_const(e: &Expr) -> bool {
    e.as_const().is_some_and(|c| c > 0.0 && c.is_finite())
}

/// Whether `s` is `f1^2 + f2^2`, or that minus `c f1 f2` with |c| <= 2:
/// the root argument of an R-function with alpha in [-1, 1].
fn is_r_root_arg(s: &Expr, f1: &Expr, f2: &Expr) -> bool {
    let squares = |e: &Expr| match e.node() {
        ExprNode::Binary(BinaryOp::Add, a, b) => matches!(
            (a.node(), b.node()),
            (ExprNode::Unary(UnaryOp::Square, p), ExprNode::Unary(UnaryOp::Square, q))
                if same(p, f1) && same(q, f2)
        ),
        _ => false,
    };
    match s.node() {
        ExprNode::Binary(BinaryOp::Sub, sq, prod) if squares(sq) => match prod.node() {
            ExprNode::Binary(BinaryOp::Mul, cf1, g2) if same(g2, f2) => match cf1.node() {
                ExprNode::Binary(BinaryOp::Mul, c, g1) if same(g1, f1) => {
                    c.as_const().is_some_and(|c| c.abs() <= 2.0)
                }
                _ => false,
            },
            _ => false,
        },
        _ => squares(s),
    }
}

impl Csg {
    pub fn new(e: &Expr) -> Csg {
        let mut leaves: Vec<(*const ExprNode, Tape)> = Vec::new();
        let root = build(e, &mut leaves);
        Csg {
            root,
            tapes: leaves.into_iter().map(|(_, t)| t).collect(),
        }
    }

    /// Number of leaves (1 when no set operation was found).
    pub fn leaves(&self) -> usize {
        self.tapes.len()
    }
}

/// One set operation read off an expression: the sign of an R-function
/// intersection (union) with alpha in [-1, 1] is that of `min` (`max`) of
/// its arguments, a positive constant factor keeps the solid, negation is
/// the complement.
pub enum SetOp<'e> {
    And(&'e Expr, &'e Expr),
    Or(&'e Expr, &'e Expr),
    Same(&'e Expr),
    Not(&'e Expr),
}

/// The set operation at the root of `e`, if it is one.
pub fn set_op(e: &Expr) -> Option<SetOp<'_>> {
    match e.node() {
        ExprNode::Binary(BinaryOp::Min, a, b) => Some(SetOp::And(a, b)),
        ExprNode::Binary(BinaryOp::Max, a, b) => Some(SetOp::Or(a, b)),
        ExprNode::Binary(BinaryOp::Div | BinaryOp::Mul, a, c) if positive_const(c) => {
            Some(SetOp::Same(a))
        }
        ExprNode::Binary(BinaryOp::Mul, c, a) if positive_const(c) => Some(SetOp::Same(a)),
        ExprNode::Unary(UnaryOp::Neg, a) => Some(SetOp::Not(a)),
        ExprNode::Binary(op @ (BinaryOp::Sub | BinaryOp::Add), sum, root) => {
            let (ExprNode::Binary(BinaryOp::Add, f1, f2), ExprNode::Unary(UnaryOp::Sqrt, s)) =
                (sum.node(), root.node())
            else {
                return None;
            };
            if !is_r_root_arg(s, f1, f2) {
                return None;
            }
            Some(if *op == BinaryOp::Sub {
                SetOp::And(f1, f2)
            } else {
                SetOp::Or(f1, f2)
            })
        }
        _ => None,
    }
}

fn build(e: &Expr, leaves: &mut Vec<(*const ExprNode, Tape)>) -> Node {
    let mut node = |a: &Expr| Box::new(build(a, leaves));
    match set_op(e) {
        Some(SetOp::And(a, b)) => Node::And(node(a), node(b)),
        Some(SetOp::Or(a, b)) => Node::Or(node(a), node(b)),
        Some(SetOp::Same(a)) => build(a, leaves),
        Some(SetOp::Not(a)) => Node::Not(node(a)),
        None => leaf(e, leaves),
    }
}

fn leaf(e: &Expr, leaves: &mut Vec<(*const ExprNode, Tape)>) -> Node {
    let key = e.node() as *const ExprNode;
    if let Some(i) = leaves.iter().position(|(k, _)| *k == key) {
        return Node::Leaf(i);
    }
    leaves.push((key, Tape::new(e)));
    Node::Leaf(leaves.len() - 1)
}

/// Evaluates a [`Csg`] on boxes.
pub struct CsgEval<'c> {
    csg: &'c Csg,
    evals: Vec<IntervalEval<'c>>,
    memo: Vec<Option<Interval>>,
}

impl<'c> CsgEval<'c> {
    pub fn new(csg: &'c Csg) -> Self {
        CsgEval {
            csg,
            evals: csg.tapes.iter().map(IntervalEval::new).collect(),
            memo: vec![None; csg.tapes.len()],
        }
    }

    /// Bounds of a function with the model's signs over the box.
    pub fn eval(&mut self, x: Interval, y: Interval, z: Interval) -> Interval {
        self.memo.iter_mut().for_each(|m| *m = None);
        self.node(&self.csg.root, [x, y, z])
    }

    fn node(&mut self, n: &Node, b: [Interval; 3]) -> Interval {
        match n {
            Node::Leaf(i) => {
                if let Some(r) = self.memo[*i] {
                    return r;
                }
                let r = self.evals[*i].eval(b[0], b[1], b[2]);
                self.memo[*i] = Some(r);
                r
            }
            // NaN in either argument makes the R-function NaN (outside).
            Node::And(p, q) => {
                let a = self.node(p, b);
                // An empty argument makes the intersection empty, NaN or not.
                if a.hi < 0.0 {
                    return a;
                }
                let c = self.node(q, b);
                a.min(c).with_nan(a.may_be_nan() || c.may_be_nan())
            }
            Node::Or(p, q) => {
                let (a, c) = (self.node(p, b), self.node(q, b));
                a.max(c).with_nan(a.may_be_nan() || c.may_be_nan())
            }
            Node::Not(p) => self.node(p, b).neg(),
        }
    }
}
