//! The deduplicated expression graph that gets compiled.
//!
//! Every node is interned: structurally identical nodes get the same id
//! (commutative ops have their arguments ordered first), constants are folded
//! and trivial identities removed. Node ids are in topological order by
//! construction, which the tape compiler relies on.

use crate::expr::{Axis, Expr, ExprNode};
use crate::field::Field;
use crate::ops::{BinaryOp, SetOp, UnaryOp};
use std::collections::HashMap;
use std::sync::Arc;

/// Index of a node in its [`Graph`]; children always have smaller ids.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct NodeId(pub u32);

/// A graph node; children refer to earlier nodes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Node {
    /// A coordinate.
    Var(Axis),
    /// Constant, stored as bits so that nodes can be hashed (NaN payloads and
    /// signed zeros stay distinct, which is what bit-exact folding needs).
    Const(u64),
    /// Parameter by its index in [`Graph::params`].
    Param(u32),
    /// An operation with one argument.
    Unary(UnaryOp, NodeId),
    /// An operation with two arguments, in order (commutative ones sorted).
    Binary(BinaryOp, NodeId, NodeId),
    /// Integer power.
    PowI(NodeId, i32),
    /// `cond != 0 ? a : b` over `(cond, a, b)`.
    Select(NodeId, NodeId, NodeId),
    /// R-function set operation: `op(a, b)` with parameter `alpha`.
    Set {
        /// Union or intersection.
        op: SetOp,
        /// First argument.
        a: NodeId,
        /// Second argument.
        b: NodeId,
        /// The R-function parameter.
        alpha: NodeId,
    },
    /// Blended set operation over `[a, b, alpha, a0, a1, a2]`.
    Blend {
        /// Union or intersection.
        op: SetOp,
        /// The arguments, as in [`crate::expr::ExprNode::Blend`].
        args: [NodeId; 6],
    },
    /// A data-driven field sampled at mapped coordinates.
    Field {
        /// Index in [`Graph::fields`].
        field: u32,
        /// 0 for the value, 1, 2, 3 for the x, y, z partial derivative.
        comp: u8,
        /// The point at which the field is sampled.
        args: [NodeId; 3],
    },
}

impl Node {
    /// The nodes this one reads, in evaluation order.
    pub fn children(&self) -> Vec<NodeId> {
        match *self {
            Node::Var(_) | Node::Const(_) | Node::Param(_) => vec![],
            Node::Unary(_, a) | Node::PowI(a, _) => vec![a],
            Node::Binary(_, a, b) => vec![a, b],
            Node::Select(c, a, b) => vec![c, a, b],
            Node::Set { a, b, alpha, .. } => vec![a, b, alpha],
            Node::Blend { args, .. } => args.to_vec(),
            Node::Field { args, .. } => args.to_vec(),
        }
    }
}

/// A named parameter: its name and default value.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamInfo {
    /// Name as written in the model.
    pub name: String,
    /// Value until an evaluator sets another.
    pub default: f64,
}

/// Interned, constant-folded nodes of one or more expressions, in
/// topological order, with the fields and parameters they use.
#[derive(Default, Clone)]
pub struct Graph {
    nodes: Vec<Node>,
    index: HashMap<Node, NodeId>,
    fields: Vec<Arc<dyn Field>>,
    params: Vec<ParamInfo>,
}

impl Graph {
    /// An empty graph.
    pub fn new() -> Graph {
        Graph::default()
    }

    /// All nodes; a node's children come before it.
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }
    /// The node with id `id`.
    ///
    /// # Panics
    ///
    /// If `id` is not from this graph.
    pub fn node(&self, id: NodeId) -> Node {
        self.nodes[id.0 as usize]
    }
    /// The distinct fields used, indexed by [`Node::Field`]'s `field`.
    pub fn fields(&self) -> &[Arc<dyn Field>] {
        &self.fields
    }
    /// The distinct parameters (by name), indexed by [`Node::Param`].
    pub fn params(&self) -> &[ParamInfo] {
        &self.params
    }
    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }
    /// Whether the graph has no nodes.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Adds an expression tree, returning its root.
    pub fn add(&mut self, e: &Expr) -> NodeId {
        let mut memo = HashMap::new();
        self.add_memo(e, &mut memo)
    }

    fn add_memo(&mut self, e: &Expr, memo: &mut HashMap<*const ExprNode, NodeId>) -> NodeId {
        let key = Arc::as_ptr(&e.0);
        if let Some(&id) = memo.get(&key) {
            return id;
        }
        // Iterative post-order walk: HyperFun models and remapped lattices can
        // nest thousands deep, more than the thread stack would survive.
        let mut stack: Vec<(&Expr, bool)> = vec![(e, false)];
        while let Some((cur, expanded)) = stack.pop() {
            let k = Arc::as_ptr(&cur.0);
            if memo.contains_key(&k) {
                continue;
            }
            if !expanded {
                stack.push((cur, true));
                for c in cur.children().into_iter().rev() {
                    if !memo.contains_key(&Arc::as_ptr(&c.0)) {
                        stack.push((c, false));
                    }
                }
                continue;
            }
            let get = |c: &Expr| memo[&Arc::as_ptr(&c.0)];
            let id = match cur.node() {
                ExprNode::Var(a) => self.intern(Node::Var(*a)),
                ExprNode::Const(c) => self.constant(*c),
                ExprNode::Param { name, default } => {
                    let idx = match self.params.iter().position(|p| p.name == **name) {
                        Some(i) => i,
                        None => {
                            self.params.push(ParamInfo {
                                name: name.to_string(),
                                default: *default,
                            });
                            self.params.len() - 1
                        }
                    };
                    self.intern(Node::Param(idx as u32))
                }
                ExprNode::Unary(op, a) => {
                    let a = get(a);
                    self.unary(*op, a)
                }
                ExprNode::Binary(op, a, b) => {
                    let (a, b) = (get(a), get(b));
                    self.binary(*op, a, b)
                }
                ExprNode::PowI(a, n) => {
                    let a = get(a);
                    self.powi(a, *n)
                }
                ExprNode::Select(c, a, b) => {
                    let (c, a, b) = (get(c), get(a), get(b));
                    self.select(c, a, b)
                }
                ExprNode::Set { op, a, b, alpha } => {
                    let (a, b, alpha) = (get(a), get(b), get(alpha));
                    self.set(*op, a, b, alpha)
                }
                ExprNode::Blend { op, args } => {
                    let args = std::array::from_fn(|i| get(&args[i]));
                    self.intern(Node::Blend { op: *op, args })
                }
                ExprNode::Field { field, comp, args } => {
                    let args = [get(&args[0]), get(&args[1]), get(&args[2])];
                    let fi = match self.fields.iter().position(|f| Arc::ptr_eq(f, field)) {
                        Some(i) => i,
                        None => {
                            self.fields.push(field.clone());
                            self.fields.len() - 1
                        }
                    };
                    self.intern(Node::Field {
                        field: fi as u32,
                        comp: *comp,
                        args,
                    })
                }
            };
            memo.insert(k, id);
        }
        memo[&key]
    }

    fn intern(&mut self, n: Node) -> NodeId {
        if let Some(&id) = self.index.get(&n) {
            return id;
        }
        let id = NodeId(self.nodes.len() as u32);
        self.nodes.push(n);
        self.index.insert(n, id);
        id
    }

    /// The node of constant `c` (bit-exact: `0.0` and `-0.0` differ).
    pub fn constant(&mut self, c: f64) -> NodeId {
        self.intern(Node::Const(c.to_bits()))
    }

    /// The constant value of a node, if it is one.
    pub fn const_value(&self, id: NodeId) -> Option<f64> {
        match self.node(id) {
            Node::Const(b) => Some(f64::from_bits(b)),
            _ => None,
        }
    }

    /// The node of `op(a)`, folded if `a` is constant; `--a` becomes `a`.
    pub fn unary(&mut self, op: UnaryOp, a: NodeId) -> NodeId {
        if let Some(c) = self.const_value(a) {
            return self.constant(op.apply(c));
        }
        if let (UnaryOp::Neg, Node::Unary(UnaryOp::Neg, inner)) = (op, self.node(a)) {
            return inner;
        }
        self.intern(Node::Unary(op, a))
    }

    /// The node of `op(a, b)`: constants fold, identities exact for every input
    /// (`a * 1`, `a - 0`, `min(a, a)`, ...) are removed, `a * a` becomes a square,
    /// and commutative arguments are ordered.
    pub fn binary(&mut self, op: BinaryOp, a: NodeId, b: NodeId) -> NodeId {
        let (ca, cb) = (self.const_value(a), self.const_value(b));
        if let (Some(x), Some(y)) = (ca, cb) {
            return self.constant(op.apply(x, y));
        }
        // Identities that hold for every input, NaN and infinities included.
        match (op, ca, cb) {
            (BinaryOp::Add, Some(z), _) if z == 0.0 && z.is_sign_negative() => return b,
            (BinaryOp::Add, _, Some(z)) if z == 0.0 && z.is_sign_negative() => return a,
            (BinaryOp::Sub, _, Some(z)) if z == 0.0 && z.is_sign_positive() => return a,
            (BinaryOp::Mul, Some(1.0), _) => return b,
            (BinaryOp::Mul, _, Some(o)) | (BinaryOp::Div, _, Some(o)) if o == 1.0 => return a,
            (BinaryOp::Min | BinaryOp::Max, _, _) if a == b => return a,
            // `a * a` is a square: same value bit for bit, but its interval
            // is never negative (a product of two independent ranges can be).
            (BinaryOp::Mul, _, _) if a == b => return self.unary(UnaryOp::Square, a),
            _ => {}
        }
        let (a, b) = if op.commutative() && b < a {
            (b, a)
        } else {
            (a, b)
        };
        self.intern(Node::Binary(op, a, b))
    }

    /// The node of `a^n`; constants fold, `n = 1` and `n = 2` simplify.
    pub fn powi(&mut self, a: NodeId, n: i32) -> NodeId {
        if let Some(c) = self.const_value(a) {
            return self.constant(c.powi(n));
        }
        match n {
            1 => a,
            2 => self.unary(UnaryOp::Square, a),
            _ => self.intern(Node::PowI(a, n)),
        }
    }

    /// An R-function node; `alpha = 1` becomes `max`/`min`, constants fold.
    pub fn set(&mut self, op: SetOp, a: NodeId, b: NodeId, alpha: NodeId) -> NodeId {
        match (
            self.const_value(alpha),
            self.const_value(a),
            self.const_value(b),
        ) {
            (Some(1.0), _, _) => {
                let m = match op {
                    SetOp::Union => BinaryOp::Max,
                    SetOp::Intersection => BinaryOp::Min,
                };
                return self.binary(m, a, b);
            }
            (Some(al), Some(x), Some(y)) => return self.constant(op.apply(x, y, al)),
            _ => {}
        }
        // Both R-functions are symmetric in their arguments, and bit for bit
        // so at alpha = 0 (`a + b`, `a*a + b*b` commute exactly; the
        // `2 alpha a b` term would not).
        let (a, b) = if b < a && self.const_value(alpha) == Some(0.0) {
            (b, a)
        } else {
            (a, b)
        };
        self.intern(Node::Set { op, a, b, alpha })
    }

    /// The node of `c != 0 ? a : b`; a constant condition or equal branches
    /// pick the branch directly.
    pub fn select(&mut self, c: NodeId, a: NodeId, b: NodeId) -> NodeId {
        if let Some(v) = self.const_value(c) {
            return if v != 0.0 { a } else { b };
        }
        if a == b {
            return a;
        }
        self.intern(Node::Select(c, a, b))
    }
}
