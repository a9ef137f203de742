//! `Expr`: the user-facing way to build a model.
//!
//! An `Expr` is an immutable, reference-counted expression tree with operator
//! overloading, so models read like their formulas. Shared subtrees are shared
//! by pointer; [`crate::Graph`] later merges structurally identical ones and
//! folds constants, so how a model was written does not change what runs.

use crate::field::Field;
use crate::ops::{BinaryOp, SetOp, UnaryOp};
use std::collections::HashMap;
use std::fmt;
use std::sync::Arc;

/// Coordinate axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Axis {
    /// The x axis.
    X = 0,
    /// The y axis.
    Y = 1,
    /// The z axis.
    Z = 2,
}

/// One node of an expression tree.
#[derive(Clone)]
pub enum ExprNode {
    /// A coordinate of the point being evaluated.
    Var(Axis),
    /// A constant.
    Const(f64),
    /// A named parameter whose value is chosen at evaluation time.
    Param {
        /// Name the evaluators look the parameter up by.
        name: Arc<str>,
        /// Value used until an evaluator sets another.
        default: f64,
    },
    /// An operation with one argument.
    Unary(UnaryOp, Expr),
    /// An operation with two arguments, in order.
    Binary(BinaryOp, Expr, Expr),
    /// Integer power by repeated multiplication.
    PowI(Expr, i32),
    /// `cond != 0 ? then : else`.
    Select(Expr, Expr, Expr),
    /// An R-function set operation of `a` and `b` with parameter `alpha`
    /// (see [`SetOp`]); `alpha = 1` is built as `min`/`max` instead.
    Set {
        /// Union or intersection.
        op: SetOp,
        /// First argument.
        a: Expr,
        /// Second argument.
        b: Expr,
        /// The R-function parameter, in `[-1, 1]` for the sign laws to hold.
        alpha: Expr,
    },
    /// A blended set operation (Pasko et al. Eq. 7): the R-function plus
    /// the displacement `a0 / (1 + (a/a1)^2 + (b/a2)^2)`.
    Blend {
        /// Union or intersection (a blended subtraction is an intersection
        /// with the negated second argument).
        op: SetOp,
        /// `[a, b, alpha, a0, a1, a2]`.
        args: Box<[Expr; 6]>,
    },
    /// A data-driven field at mapped coordinates. `comp` 0 is the value,
    /// 1..=3 the partial derivatives along x, y, z.
    Field {
        /// The field being sampled.
        field: Arc<dyn Field>,
        /// 0 for the value, 1, 2, 3 for the x, y, z partial derivative.
        comp: u8,
        /// The (mapped) point at which the field is sampled.
        args: [Expr; 3],
    },
}

/// A scalar field over space, built from nodes. Cheap to clone.
#[derive(Clone)]
pub struct Expr(pub(crate) Arc<ExprNode>);

impl fmt::Debug for Expr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.node() {
            ExprNode::Var(a) => write!(f, "{}", ["x", "y", "z"][*a as usize]),
            ExprNode::Const(c) => write!(f, "{c}"),
            ExprNode::Param { name, .. } => write!(f, "${name}"),
            ExprNode::Unary(op, a) => write!(f, "{}({a:?})", op.name()),
            ExprNode::Binary(op, a, b) => write!(f, "{}({a:?}, {b:?})", op.name()),
            ExprNode::PowI(a, n) => write!(f, "powi({a:?}, {n})"),
            ExprNode::Select(c, a, b) => write!(f, "select({c:?}, {a:?}, {b:?})"),
            ExprNode::Set { op, a, b, alpha } => {
                write!(f, "{}({a:?}, {b:?}, {alpha:?})", op.name())
            }
            ExprNode::Blend { op, args } => write!(f, "blend_{}{:?}", op.name(), &args[..]),
            ExprNode::Field {
                field, comp, args, ..
            } => write!(
                f,
                "{}[{comp}]({:?}, {:?}, {:?})",
                field.name(),
                args[0],
                args[1],
                args[2]
            ),
        }
    }
}

thread_local! {
    /// Nodes created on this thread so far (see [`Expr::nodes_created`]).
    static CREATED: std::cell::Cell<u64> = const { std::cell::Cell::new(0) };
}

impl Expr {
    fn new(n: ExprNode) -> Expr {
        CREATED.with(|c| c.set(c.get().wrapping_add(1)));
        Expr(Arc::new(n))
    }
    /// How many expression nodes this thread has created so far. A builder
    /// that runs untrusted programs (HyperFun lowering) reads it before and
    /// while it works, to refuse a model whose graph outgrows a budget
    /// before the memory is spent, rather than after.
    pub fn nodes_created() -> u64 {
        CREATED.with(|c| c.get())
    }
    /// The node at the root of this expression.
    pub fn node(&self) -> &ExprNode {
        &self.0
    }
    /// The x coordinate.
    pub fn x() -> Expr {
        Expr::new(ExprNode::Var(Axis::X))
    }
    /// The y coordinate.
    pub fn y() -> Expr {
        Expr::new(ExprNode::Var(Axis::Y))
    }
    /// The z coordinate.
    pub fn z() -> Expr {
        Expr::new(ExprNode::Var(Axis::Z))
    }
    /// The three coordinates `(x, y, z)`.
    pub fn xyz() -> [Expr; 3] {
        [Expr::x(), Expr::y(), Expr::z()]
    }
    /// The coordinate along `a`.
    pub fn var(a: Axis) -> Expr {
        Expr::new(ExprNode::Var(a))
    }
    /// A constant (also available through `From<f64>`, so plain numbers mix
    /// with expressions in arithmetic).
    pub fn constant(c: f64) -> Expr {
        Expr::new(ExprNode::Const(c))
    }
    /// A named parameter with a default value, settable per evaluator.
    pub fn param(name: &str, default: f64) -> Expr {
        Expr::new(ExprNode::Param {
            name: name.into(),
            default,
        })
    }
    /// A data-driven field evaluated at `(x, y, z)`.
    pub fn field(field: Arc<dyn Field>) -> Expr {
        Expr::field_at(field, Expr::xyz())
    }
    /// A data-driven field evaluated at mapped coordinates.
    pub fn field_at(field: Arc<dyn Field>, args: [Expr; 3]) -> Expr {
        Expr::new(ExprNode::Field {
            field,
            comp: 0,
            args,
        })
    }
    pub(crate) fn field_comp(field: Arc<dyn Field>, comp: u8, args: [Expr; 3]) -> Expr {
        Expr::new(ExprNode::Field { field, comp, args })
    }

    /// The constant value, if this node is one.
    pub fn as_const(&self) -> Option<f64> {
        match self.node() {
            ExprNode::Const(c) => Some(*c),
            _ => None,
        }
    }

    /// `op(a)`; folded to a constant when `a` is one.
    pub fn unary(op: UnaryOp, a: Expr) -> Expr {
        if let Some(c) = a.as_const() {
            return Expr::constant(op.apply(c));
        }
        Expr::new(ExprNode::Unary(op, a))
    }
    /// `op(a, b)`; folded to a constant when both arguments are.
    pub fn binary(op: BinaryOp, a: Expr, b: Expr) -> Expr {
        if let (Some(x), Some(y)) = (a.as_const(), b.as_const()) {
            return Expr::constant(op.apply(x, y));
        }
        Expr::new(ExprNode::Binary(op, a, b))
    }
    /// `cond != 0 ? a : b`.
    pub fn select(cond: Expr, a: Expr, b: Expr) -> Expr {
        if let Some(c) = cond.as_const() {
            return if c != 0.0 { a } else { b };
        }
        Expr::new(ExprNode::Select(cond, a, b))
    }

    /// `-self`.
    pub fn neg(&self) -> Expr {
        Expr::unary(UnaryOp::Neg, self.clone())
    }
    /// `|self|`.
    pub fn abs(&self) -> Expr {
        Expr::unary(UnaryOp::Abs, self.clone())
    }
    /// -1, 0 or 1 by the sign of `self` (0 where it is NaN).
    pub fn sign(&self) -> Expr {
        Expr::unary(UnaryOp::Sign, self.clone())
    }
    /// Square root (NaN below 0).
    pub fn sqrt(&self) -> Expr {
        Expr::unary(UnaryOp::Sqrt, self.clone())
    }
    /// `self * self`; its interval bound is never negative.
    pub fn square(&self) -> Expr {
        Expr::unary(UnaryOp::Square, self.clone())
    }
    /// `e^self`.
    pub fn exp(&self) -> Expr {
        Expr::unary(UnaryOp::Exp, self.clone())
    }
    /// Natural logarithm (-inf at 0, NaN below).
    pub fn ln(&self) -> Expr {
        Expr::unary(UnaryOp::Ln, self.clone())
    }
    /// Sine, argument in radians.
    pub fn sin(&self) -> Expr {
        Expr::unary(UnaryOp::Sin, self.clone())
    }
    /// Cosine, argument in radians.
    pub fn cos(&self) -> Expr {
        Expr::unary(UnaryOp::Cos, self.clone())
    }
    /// Tangent, argument in radians.
    pub fn tan(&self) -> Expr {
        Expr::unary(UnaryOp::Tan, self.clone())
    }
    /// Arc sine in `[-pi/2, pi/2]` (NaN outside `[-1, 1]`).
    pub fn asin(&self) -> Expr {
        Expr::unary(UnaryOp::Asin, self.clone())
    }
    /// Arc cosine in `[0, pi]` (NaN outside `[-1, 1]`).
    pub fn acos(&self) -> Expr {
        Expr::unary(UnaryOp::Acos, self.clone())
    }
    /// Arc tangent in `(-pi/2, pi/2)`.
    pub fn atan(&self) -> Expr {
        Expr::unary(UnaryOp::Atan, self.clone())
    }
    /// Hyperbolic sine.
    pub fn sinh(&self) -> Expr {
        Expr::unary(UnaryOp::Sinh, self.clone())
    }
    /// Hyperbolic cosine.
    pub fn cosh(&self) -> Expr {
        Expr::unary(UnaryOp::Cosh, self.clone())
    }
    /// Hyperbolic tangent.
    pub fn tanh(&self) -> Expr {
        Expr::unary(UnaryOp::Tanh, self.clone())
    }
    /// Largest integer not above `self`.
    pub fn floor(&self) -> Expr {
        Expr::unary(UnaryOp::Floor, self.clone())
    }
    /// Smallest integer not below `self`.
    pub fn ceil(&self) -> Expr {
        Expr::unary(UnaryOp::Ceil, self.clone())
    }
    /// Integer part, rounding towards zero.
    pub fn trunc(&self) -> Expr {
        Expr::unary(UnaryOp::Trunc, self.clone())
    }
    /// Nearest integer, halves away from zero.
    pub fn round(&self) -> Expr {
        Expr::unary(UnaryOp::Round, self.clone())
    }
    /// `self - floor(self)`, in `[0, 1)`.
    pub fn fract(&self) -> Expr {
        Expr::unary(UnaryOp::Fract, self.clone())
    }
    /// Logical not of a truth value.
    pub fn not(&self) -> Expr {
        Expr::unary(UnaryOp::Not, self.clone())
    }
    /// Real power `self^e` (NaN for a negative base with a fractional
    /// exponent; use [`Expr::powi`] for integer exponents).
    pub fn pow(&self, e: impl Into<Expr>) -> Expr {
        Expr::binary(BinaryOp::Pow, self.clone(), e.into())
    }
    /// Integer power (exact repeated multiplication, defined for negative bases).
    pub fn powi(&self, n: i32) -> Expr {
        match n {
            0 => Expr::constant(1.0),
            1 => self.clone(),
            2 => self.square(),
            _ => match self.as_const() {
                Some(c) => Expr::constant(c.powi(n)),
                None => Expr::new(ExprNode::PowI(self.clone(), n)),
            },
        }
    }
    /// `atan2(self, x)`: the angle of the point `(x, self)`, in `[-pi, pi]`.
    pub fn atan2(&self, x: impl Into<Expr>) -> Expr {
        Expr::binary(BinaryOp::Atan2, self.clone(), x.into())
    }
    /// Smaller of the two; NaN if either is NaN.
    pub fn min(&self, b: impl Into<Expr>) -> Expr {
        Expr::binary(BinaryOp::Min, self.clone(), b.into())
    }
    /// Larger of the two; NaN if either is NaN.
    pub fn max(&self, b: impl Into<Expr>) -> Expr {
        Expr::binary(BinaryOp::Max, self.clone(), b.into())
    }
    /// Floored modulo (result has the sign of `b`).
    pub fn modulo(&self, b: impl Into<Expr>) -> Expr {
        Expr::binary(BinaryOp::Mod, self.clone(), b.into())
    }
    /// Truncated remainder, C `fmod`.
    pub fn rem(&self, b: impl Into<Expr>) -> Expr {
        Expr::binary(BinaryOp::Rem, self.clone(), b.into())
    }
    /// 1 where `self < b`, else 0.
    pub fn lt(&self, b: impl Into<Expr>) -> Expr {
        Expr::binary(BinaryOp::Lt, self.clone(), b.into())
    }
    /// 1 where `self <= b`, else 0.
    pub fn le(&self, b: impl Into<Expr>) -> Expr {
        Expr::binary(BinaryOp::Le, self.clone(), b.into())
    }
    /// 1 where `self > b`, else 0.
    pub fn gt(&self, b: impl Into<Expr>) -> Expr {
        Expr::binary(BinaryOp::Gt, self.clone(), b.into())
    }
    /// 1 where `self >= b`, else 0.
    pub fn ge(&self, b: impl Into<Expr>) -> Expr {
        Expr::binary(BinaryOp::Ge, self.clone(), b.into())
    }
    /// 1 where `self == b`, else 0 (named so as not to clash with
    /// [`PartialEq::eq`]).
    pub fn eq_(&self, b: impl Into<Expr>) -> Expr {
        Expr::binary(BinaryOp::Eq, self.clone(), b.into())
    }
    /// 1 where `self != b`, else 0.
    pub fn ne_(&self, b: impl Into<Expr>) -> Expr {
        Expr::binary(BinaryOp::Ne, self.clone(), b.into())
    }
    /// 1 where both are nonzero, else 0.
    pub fn and(&self, b: impl Into<Expr>) -> Expr {
        Expr::binary(BinaryOp::And, self.clone(), b.into())
    }
    /// 1 where either is nonzero, else 0.
    pub fn or(&self, b: impl Into<Expr>) -> Expr {
        Expr::binary(BinaryOp::Or, self.clone(), b.into())
    }

    /// This expression with data-field nodes replaced: `with(field, comp,
    /// args)` gets every field node (its arguments already rewritten) and
    /// returns its replacement, or `None` to keep it. Used to bind a
    /// placeholder field of a parsed expression to a graph (for example a
    /// depth below a surface).
    pub fn replace_fields(
        &self,
        with: &dyn Fn(&Arc<dyn Field>, u8, &[Expr; 3]) -> Option<Expr>,
    ) -> Expr {
        self.rewrite(|cur, m| match cur.node() {
            ExprNode::Field { field, comp, args } => {
                let args: [Expr; 3] = std::array::from_fn(|i| m(&args[i]));
                with(field, *comp, &args).unwrap_or_else(|| cur.with_children(m))
            }
            _ => cur.with_children(m),
        })
    }

    /// This expression with the coordinates replaced by `p`: the inverse space
    /// mapping on which every transform and replication is built.
    pub fn remap(&self, p: &[Expr; 3]) -> Expr {
        self.rewrite(|cur, m| match cur.node() {
            ExprNode::Var(a) => p[*a as usize].clone(),
            _ => cur.with_children(m),
        })
    }

    /// This expression with every set and blend node written out as its
    /// formula (identical values): what plain interval arithmetic sees of
    /// a model, for comparisons and for consumers that cannot read set
    /// nodes.
    pub fn written_out(&self) -> Expr {
        self.rewrite(|cur, m| match cur.node() {
            ExprNode::Set { op, a, b, alpha } => Expr::set(*op, &m(a), &m(b), m(alpha)).expand(),
            ExprNode::Blend { op, args } => Expr::blend(*op, std::array::from_fn(|i| m(&args[i])))
                .expand()
                .written_out(),
            _ => cur.with_children(m),
        })
    }

    /// This expression with every real power whose exponent is a whole
    /// constant `n`, `|n| <= 16`, written as the integer power `powi(n)`:
    /// the same function (also for negative, zero, infinite and NaN bases),
    /// evaluated by a few multiplications instead of the exp/ln kernels, at
    /// the price of a few roundings (about `|n|` ulps in f32, so batch
    /// values may differ from the original's in their last bits). For
    /// consumers that quantise values far more coarsely than that.
    /// Subexpressions without such powers are shared with `self`.
    pub fn with_integer_powers(&self) -> Expr {
        let whole = |e: &Expr| {
            e.as_const()
                .filter(|c| c.fract() == 0.0 && c.abs() <= 16.0)
                .map(|c| c as i32)
        };
        self.rewrite(|cur, m| match cur.node() {
            ExprNode::Binary(BinaryOp::Pow, a, b) if whole(b).is_some() => {
                m(a).powi(whole(b).unwrap_or(1))
            }
            _ if cur.children().iter().all(|&c| Arc::ptr_eq(&m(c).0, &c.0)) => cur.clone(),
            _ => cur.with_children(m),
        })
    }

    /// This expression with every division by a constant `c` written as
    /// the product with the constant `1 / c` (where both are normal
    /// numbers in f32): the same function, a multiplication instead of a
    /// division in f32 (several times faster), at the price of one more
    /// rounding (the quotient is exact for powers of two, else within
    /// about 1 ulp in f32). For consumers that quantise values far more
    /// coarsely than that. Subexpressions without such divisions are
    /// shared with `self`.
    pub fn with_constant_divisors_inverted(&self) -> Expr {
        let inverse = |e: &Expr| {
            e.as_const()
                .filter(|c| (*c as f32).is_normal())
                .map(|c| 1.0 / c)
                .filter(|r| (*r as f32).is_normal())
        };
        self.rewrite(|cur, m| match cur.node() {
            ExprNode::Binary(BinaryOp::Div, a, b) if inverse(b).is_some() => {
                m(a) * Expr::constant(inverse(b).unwrap_or(1.0))
            }
            _ if cur.children().iter().all(|&c| Arc::ptr_eq(&m(c).0, &c.0)) => cur.clone(),
            _ => cur.with_children(m),
        })
    }

    /// This expression with a real power `pow(x, f - 1)` (not a whole
    /// exponent) written as `pow(x, f) / x` where `pow(x, f)` of the same
    /// base `x` is in the expression too, as the derivative of a power
    /// makes it (`f - 1` as f64 computes it): one power kernel instead of two. At `x = +-0` and
    /// `x = +-inf` the quotient would be NaN, so those bases take the
    /// power's value there (0 or infinity, a constant); elsewhere the same
    /// function at the price of one more rounding (within about 2 ulps in
    /// f32). For consumers that quantise values far more coarsely than
    /// that. Subexpressions without such powers are shared with `self`.
    pub fn with_neighbour_powers_shared(&self) -> Expr {
        // Bases compared by structure (equal subexpressions built apart
        // are one node of a graph).
        let graph = std::cell::RefCell::new(crate::graph::Graph::new());
        let key = |e: &Expr| graph.borrow_mut().add(e);
        let real = |e: &Expr| e.as_const().filter(|c| c.is_finite() && c.fract() != 0.0);
        // The real exponents of each base.
        let mut powers: HashMap<crate::graph::NodeId, Vec<f64>> = HashMap::new();
        self.rewrite(|cur, _| {
            if let ExprNode::Binary(BinaryOp::Pow, a, b) = cur.node() {
                if let Some(e) = real(b) {
                    powers.entry(key(a)).or_default().push(e);
                }
            }
            cur.clone()
        });
        self.rewrite(|cur, m| match cur.node() {
            ExprNode::Binary(BinaryOp::Pow, a, b)
                if real(b).is_some_and(|e| {
                    powers
                        .get(&key(a))
                        .is_some_and(|es| es.iter().any(|&f| f - 1.0 == e))
                }) =>
            {
                // The exponent e + 1 as the other power has it (e itself
                // may be its f64 difference with 1).
                let e = real(b).unwrap_or(0.0);
                let f = powers
                    .get(&key(a))
                    .and_then(|es| es.iter().copied().find(|&f| f - 1.0 == e))
                    .unwrap_or(e + 1.0);
                let x = m(a);
                let (at_zero, at_inf) = (0f64.powf(e), f64::INFINITY.powf(e));
                Expr::select(
                    x.eq_(0.0),
                    Expr::constant(at_zero),
                    Expr::select(
                        x.abs().eq_(f64::INFINITY),
                        Expr::constant(at_inf),
                        x.pow(f) / &x,
                    ),
                )
            }
            _ if cur.children().iter().all(|&c| Arc::ptr_eq(&m(c).0, &c.0)) => cur.clone(),
            _ => cur.with_children(m),
        })
    }

    /// Rebuilds the graph bottom-up: `f` gets each distinct node (children
    /// first) and the rebuilt form of any of its children, and returns the
    /// node's rebuilt form. An iterative post-order walk: generated models
    /// chain 100k nodes deep, more than a thread stack survives recursively.
    fn rewrite(&self, mut f: impl FnMut(&Expr, &dyn Fn(&Expr) -> Expr) -> Expr) -> Expr {
        let key = |e: &Expr| Arc::as_ptr(&e.0);
        let mut memo: HashMap<*const ExprNode, Expr> = HashMap::new();
        let mut stack: Vec<(&Expr, bool)> = vec![(self, false)];
        while let Some((cur, expanded)) = stack.pop() {
            if memo.contains_key(&key(cur)) {
                continue;
            }
            if !expanded {
                stack.push((cur, true));
                for c in cur.children().into_iter().rev() {
                    if !memo.contains_key(&key(c)) {
                        stack.push((c, false));
                    }
                }
                continue;
            }
            let out = f(cur, &|c: &Expr| memo[&key(c)].clone());
            memo.insert(key(cur), out);
        }
        memo[&key(self)].clone()
    }

    /// This node over the children `m(child)` (leaves unchanged).
    fn with_children(&self, m: &dyn Fn(&Expr) -> Expr) -> Expr {
        match self.node() {
            ExprNode::Var(_) | ExprNode::Const(_) | ExprNode::Param { .. } => self.clone(),
            ExprNode::Unary(op, a) => Expr::unary(*op, m(a)),
            ExprNode::Binary(op, a, b) => Expr::binary(*op, m(a), m(b)),
            ExprNode::PowI(a, n) => m(a).powi(*n),
            ExprNode::Select(c, a, b) => Expr::select(m(c), m(a), m(b)),
            ExprNode::Set { op, a, b, alpha } => Expr::set(*op, &m(a), &m(b), m(alpha)),
            ExprNode::Blend { op, args } => Expr::blend(*op, std::array::from_fn(|i| m(&args[i]))),
            ExprNode::Field { field, comp, args } => Expr::field_comp(
                field.clone(),
                *comp,
                [m(&args[0]), m(&args[1]), m(&args[2])],
            ),
        }
    }

    /// Number of distinct tree nodes (by pointer), a size measure for tests and reports.
    pub fn node_count(&self) -> usize {
        let mut seen = std::collections::HashSet::new();
        let mut stack = vec![self];
        while let Some(e) = stack.pop() {
            if seen.insert(Arc::as_ptr(&e.0)) {
                stack.extend(e.children());
            }
        }
        seen.len()
    }

    /// Direct children in evaluation order.
    pub fn children(&self) -> Vec<&Expr> {
        match self.node() {
            ExprNode::Var(_) | ExprNode::Const(_) | ExprNode::Param { .. } => vec![],
            ExprNode::Unary(_, a) | ExprNode::PowI(a, _) => vec![a],
            ExprNode::Binary(_, a, b) => vec![a, b],
            ExprNode::Select(c, a, b) => vec![c, a, b],
            ExprNode::Set { a, b, alpha, .. } => vec![a, b, alpha],
            ExprNode::Blend { args, .. } => args.iter().collect(),
            ExprNode::Field { args, .. } => args.iter().collect(),
        }
    }

    /// The R-function set operation `op` of `a` and `b` with parameter
    /// `alpha` (any expression; `alpha = 1` gives exact `max`/`min`).
    pub fn set(op: SetOp, a: &Expr, b: &Expr, alpha: impl Into<Expr>) -> Expr {
        let alpha = alpha.into();
        match (alpha.as_const(), a.as_const(), b.as_const()) {
            (Some(1.0), _, _) => match op {
                SetOp::Union => a.max(b),
                SetOp::Intersection => a.min(b),
            },
            (Some(al), Some(x), Some(y)) => Expr::constant(op.apply(x, y, al)),
            _ => Expr::new(ExprNode::Set {
                op,
                a: a.clone(),
                b: b.clone(),
                alpha,
            }),
        }
    }

    /// A blended set operation from `[a, b, alpha, a0, a1, a2]` (see
    /// [`ExprNode::Blend`]).
    pub fn blend(op: SetOp, args: [Expr; 6]) -> Expr {
        if args.iter().all(|a| a.as_const().is_some()) {
            let [a, b, alpha, a0, a1, a2] = &args;
            return Expr::set(op, a, b, alpha.clone()) + blend_displacement(a, b, a0, a1, a2);
        }
        Expr::new(ExprNode::Blend {
            op,
            args: Box::new(args),
        })
    }

    /// The node written out with arithmetic only (identical values): the
    /// meaning of a set or blend node, for symbolic differentiation and for
    /// consumers that do not know set nodes. Other nodes are returned as
    /// they are.
    pub fn expand(&self) -> Expr {
        match self.node() {
            ExprNode::Set { op, a, b, alpha } => expand_set(*op, a, b, alpha),
            ExprNode::Blend { op, args } => {
                let [a, b, alpha, a0, a1, a2] = &**args;
                Expr::set(*op, a, b, alpha.clone()) + blend_displacement(a, b, a0, a1, a2)
            }
            _ => self.clone(),
        }
    }
}

/// The R-function written out, in the operation order of [`SetOp::apply`].
fn expand_set(op: SetOp, a: &Expr, b: &Expr, alpha: &Expr) -> Expr {
    let s = a + b;
    let sign = |r: Expr| match op {
        SetOp::Union => &s + r,
        SetOp::Intersection => &s - r,
    };
    if alpha.as_const() == Some(0.0) {
        return sign((a.square() + b.square()).sqrt());
    }
    sign((a.square() + b.square() - 2.0 * alpha * a * b).sqrt()) / (1.0 + alpha)
}

/// `a0 / (1 + (a/a1)^2 + (b/a2)^2)`: the blend displacement of Eq. 7.
pub fn blend_displacement(a: &Expr, b: &Expr, a0: &Expr, a1: &Expr, a2: &Expr) -> Expr {
    a0 / (1.0 + (a / a1).square() + (b / a2).square())
}

impl From<f64> for Expr {
    fn from(c: f64) -> Expr {
        Expr::constant(c)
    }
}
impl From<&Expr> for Expr {
    fn from(e: &Expr) -> Expr {
        e.clone()
    }
}

macro_rules! binop {
    ($tr:ident, $m:ident, $op:expr) => {
        impl<T: Into<Expr>> std::ops::$tr<T> for Expr {
            type Output = Expr;
            fn $m(self, rhs: T) -> Expr {
                Expr::binary($op, self, rhs.into())
            }
        }
        impl<T: Into<Expr>> std::ops::$tr<T> for &Expr {
            type Output = Expr;
            fn $m(self, rhs: T) -> Expr {
                Expr::binary($op, self.clone(), rhs.into())
            }
        }
        impl std::ops::$tr<Expr> for f64 {
            type Output = Expr;
            fn $m(self, rhs: Expr) -> Expr {
                Expr::binary($op, Expr::constant(self), rhs)
            }
        }
        impl std::ops::$tr<&Expr> for f64 {
            type Output = Expr;
            fn $m(self, rhs: &Expr) -> Expr {
                Expr::binary($op, Expr::constant(self), rhs.clone())
            }
        }
    };
}
binop!(Add, add, BinaryOp::Add);
binop!(Sub, sub, BinaryOp::Sub);
binop!(Mul, mul, BinaryOp::Mul);
binop!(Div, div, BinaryOp::Div);

impl std::ops::Neg for Expr {
    type Output = Expr;
    fn neg(self) -> Expr {
        Expr::unary(UnaryOp::Neg, self)
    }
}
impl std::ops::Neg for &Expr {
    type Output = Expr;
    fn neg(self) -> Expr {
        Expr::unary(UnaryOp::Neg, self.clone())
    }
}

// Dropping a long chain (a sum of 100k terms, 100k statements of HyperFun,
// `e = e.min(&e)` a million times) would recurse once per node and overflow
// the stack. Every child with children of its own is moved out of the node
// being dropped (a shared leaf takes its place) into a worklist; an entry
// of the worklist is only taken apart when it held the last reference
// (`Arc::into_inner` decides that atomically), otherwise it just loses one
// reference. So no drop ever recurses more than one level, whether a
// subtree is owned once, shared with other nodes, or held twice by the
// same node (`v + v`, whose second reference used to free it from inside
// the parent's own drop).
impl Drop for ExprNode {
    fn drop(&mut self) {
        let mut work = Vec::new();
        self.take_inner_children(&mut work);
        while let Some(e) = work.pop() {
            if let Some(mut node) = Arc::into_inner(e.0) {
                node.take_inner_children(&mut work);
                // `node` drops here with leaves only.
            }
        }
    }
}

impl ExprNode {
    fn is_leaf(&self) -> bool {
        matches!(
            self,
            ExprNode::Var(_) | ExprNode::Const(_) | ExprNode::Param { .. }
        )
    }

    /// Moves every child that has children itself into `out`, leaving a
    /// shared leaf in its place.
    fn take_inner_children(&mut self, out: &mut Vec<Expr>) {
        fn take(e: &mut Expr, out: &mut Vec<Expr>) {
            if !e.0.is_leaf() {
                static PLACEHOLDER: std::sync::OnceLock<Expr> = std::sync::OnceLock::new();
                let hole = PLACEHOLDER
                    .get_or_init(|| Expr(Arc::new(ExprNode::Const(0.0))))
                    .clone();
                out.push(std::mem::replace(e, hole));
            }
        }
        // Every kind with children must be listed, or its drop recurses.
        match self {
            ExprNode::Var(_) | ExprNode::Const(_) | ExprNode::Param { .. } => {}
            ExprNode::Unary(_, a) | ExprNode::PowI(a, _) => take(a, out),
            ExprNode::Binary(_, a, b) => {
                take(a, out);
                take(b, out);
            }
            ExprNode::Select(c, a, b) => {
                take(c, out);
                take(a, out);
                take(b, out);
            }
            ExprNode::Set { a, b, alpha, .. } => {
                take(a, out);
                take(b, out);
                take(alpha, out);
            }
            ExprNode::Blend { args, .. } => args.iter_mut().for_each(|a| take(a, out)),
            ExprNode::Field { args, .. } => args.iter_mut().for_each(|a| take(a, out)),
        }
    }
}
