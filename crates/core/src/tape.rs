//! Compilation of a graph into a tape: straight-line code in SSA form.
//!
//! A tape is the live part of a graph, in topological order, one value per
//! operation: each [`Op`] reads earlier values by index. It is the one
//! program form of the core. The point, interval and gradient evaluators run
//! it with one slot per value; the batch evaluator lowers it once more
//! ([`crate::eval`]) to fuse steps and give blocks of lanes to registers
//! (the only register allocator, in `eval/batch/plan.rs`), since there a
//! register is a whole block of 256 lanes and the working set must stay in
//! cache. Blend nodes are written out here as their R-function plus the
//! displacement; set operations stay operations of their own.
//!
//! A tape is cheap to clone (shared data), immutable and shareable between
//! threads; each thread makes its own evaluators from it.

use crate::expr::{Axis, Expr};
use crate::field::Field;
use crate::graph::{Graph, Node, NodeId, ParamInfo};
use crate::ops::{BinaryOp, SetOp, UnaryOp};
use std::sync::{Arc, OnceLock};

/// Index of a value of the tape.
pub type ValueId = u32;

/// One operation of a tape, producing one value from earlier ones.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Op {
    /// A coordinate.
    Var(Axis),
    /// A constant.
    Const(f64),
    /// Parameter `k` of [`Tape::params`].
    Param(u32),
    /// A one-argument operation.
    Unary(UnaryOp, ValueId),
    /// A two-argument operation.
    Binary(BinaryOp, ValueId, ValueId),
    /// Integer power.
    PowI(ValueId, i32),
    /// `c != 0 ? a : b`.
    Select(ValueId, ValueId, ValueId),
    /// R-function set operation `op(a, b)` with parameter `alpha`.
    Set {
        /// Union or intersection.
        op: SetOp,
        /// First argument.
        a: ValueId,
        /// Second argument.
        b: ValueId,
        /// The R-function parameter.
        alpha: ValueId,
    },
    /// Component `comp` (0 value, 1..=3 partials) of field `field` of
    /// [`Tape::fields`] at mapped coordinates.
    Field {
        /// Index into [`Tape::fields`].
        field: u32,
        /// 0 for the value, 1..=3 for a partial derivative.
        comp: u8,
        /// The coordinates it is evaluated at.
        args: [ValueId; 3],
    },
}

impl Op {
    /// The values this operation reads.
    pub fn operands(&self) -> impl Iterator<Item = ValueId> {
        let (arr, n): ([ValueId; 3], usize) = match *self {
            Op::Var(_) | Op::Const(_) | Op::Param(_) => ([0; 3], 0),
            Op::Unary(_, a) | Op::PowI(a, _) => ([a, 0, 0], 1),
            Op::Binary(_, a, b) => ([a, b, 0], 2),
            Op::Select(c, a, b) => ([c, a, b], 3),
            Op::Set { a, b, alpha, .. } => ([a, b, alpha], 3),
            Op::Field { args, .. } => (args, 3),
        };
        arr.into_iter().take(n)
    }

    /// Whether the value is computed per point (not an input, a constant or
    /// a parameter).
    pub fn is_computed(&self) -> bool {
        !matches!(self, Op::Var(_) | Op::Const(_) | Op::Param(_))
    }
}

/// A compiled model: one or more outputs over a shared list of values.
#[derive(Clone, Debug)]
pub struct Tape(pub(crate) Arc<TapeData>);

#[derive(Debug)]
pub(crate) struct TapeData {
    pub(crate) ops: Vec<Op>,
    pub(crate) outputs: Vec<ValueId>,
    pub(crate) params: Vec<ParamInfo>,
    pub(crate) fields: Vec<Arc<dyn Field>>,
    /// The batch evaluator's lowering, made once on first use.
    pub(crate) plan: OnceLock<Arc<crate::eval::batch::plan::Plan>>,
}

impl Tape {
    /// Compiles one expression.
    pub fn new(e: &Expr) -> Tape {
        let mut g = Graph::new();
        let root = g.add(e);
        Tape::from_graph(&g, &[root])
    }

    /// Compiles several outputs that share one value list (a value, an error
    /// flag, attribute channels).
    pub fn with_outputs(es: &[Expr]) -> Tape {
        let mut g = Graph::new();
        let roots: Vec<NodeId> = es.iter().map(|e| g.add(e)).collect();
        Tape::from_graph(&g, &roots)
    }

    /// Compiles the nodes reachable from `roots`.
    pub fn from_graph(g: &Graph, roots: &[NodeId]) -> Tape {
        let n = g.len();
        let mut live = vec![false; n];
        for r in roots {
            live[r.0 as usize] = true;
        }
        // Ids are topologically ordered, so one backward sweep marks all.
        for i in (0..n).rev() {
            if live[i] {
                for c in g.nodes()[i].children() {
                    live[c.0 as usize] = true;
                }
            }
        }
        let mut b = Builder::default();
        let mut val: Vec<ValueId> = vec![ValueId::MAX; n];
        let mut field_map: Vec<Option<u32>> = vec![None; g.fields().len()];
        let mut param_map: Vec<Option<u32>> = vec![None; g.params().len()];
        for i in (0..n).filter(|&i| live[i]) {
            let v = |id: NodeId| val[id.0 as usize];
            let op = match g.nodes()[i] {
                Node::Var(a) => Op::Var(a),
                Node::Const(bits) => Op::Const(f64::from_bits(bits)),
                Node::Param(p) => Op::Param(*param_map[p as usize].get_or_insert_with(|| {
                    b.params.push(g.params()[p as usize].clone());
                    (b.params.len() - 1) as u32
                })),
                Node::Unary(op, a) => Op::Unary(op, v(a)),
                Node::Binary(op, x, y) => Op::Binary(op, v(x), v(y)),
                Node::PowI(a, k) => Op::PowI(v(a), k),
                Node::Select(c, x, y) => Op::Select(v(c), v(x), v(y)),
                Node::Set { op, a, b: y, alpha } => Op::Set {
                    op,
                    a: v(a),
                    b: v(y),
                    alpha: v(alpha),
                },
                Node::Blend { op, args } => {
                    val[i] = b.blend(op, args.map(v));
                    continue;
                }
                Node::Field { field, comp, args } => {
                    let fi = *field_map[field as usize].get_or_insert_with(|| {
                        b.fields.push(g.fields()[field as usize].clone());
                        (b.fields.len() - 1) as u32
                    });
                    Op::Field {
                        field: fi,
                        comp,
                        args: args.map(v),
                    }
                }
            };
            val[i] = b.push(op);
        }
        let outputs = roots.iter().map(|r| val[r.0 as usize]).collect();
        b.finish(outputs)
    }

    /// Assembles a tape from its parts (for transformations of tapes such as
    /// per-region simplification). Operands must refer to earlier values.
    pub(crate) fn from_parts(
        ops: Vec<Op>,
        outputs: Vec<ValueId>,
        params: Vec<ParamInfo>,
        fields: Vec<Arc<dyn Field>>,
    ) -> Tape {
        debug_assert!(ops
            .iter()
            .enumerate()
            .all(|(i, o)| o.operands().all(|a| (a as usize) < i)));
        Tape(Arc::new(TapeData {
            ops,
            outputs,
            params,
            fields,
            plan: OnceLock::new(),
        }))
    }

    /// The values, in evaluation order.
    pub fn ops(&self) -> &[Op] {
        &self.0.ops
    }
    /// Number of values computed per point (inputs, constants and
    /// parameters excluded): the tape's length.
    pub fn len(&self) -> usize {
        self.0.ops.iter().filter(|o| o.is_computed()).count()
    }
    /// Whether no value is computed per point.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// The values returned, in output order.
    pub fn outputs(&self) -> &[ValueId] {
        &self.0.outputs
    }
    /// The data fields the tape calls.
    pub fn fields(&self) -> &[Arc<dyn Field>] {
        &self.0.fields
    }
    /// Parameters, indexed by [`Op::Param`] and by `set_param` of evaluators.
    pub fn params(&self) -> &[ParamInfo] {
        &self.0.params
    }
    /// Index of a parameter by name, for `set_param` on evaluators.
    pub fn param_index(&self, name: &str) -> Option<usize> {
        self.0.params.iter().position(|p| p.name == name)
    }
    /// Whether both handles share one compiled tape.
    pub fn ptr_eq(&self, other: &Tape) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }

    /// A stable textual listing, for debugging and for tape equality checks.
    pub fn listing(&self) -> String {
        use std::fmt::Write;
        let mut s = String::new();
        for (i, op) in self.0.ops.iter().enumerate() {
            let _ = match *op {
                Op::Var(a) => writeln!(s, "v{i} = {}", ["x", "y", "z"][a as usize]),
                Op::Const(c) => writeln!(s, "v{i} = const {c:e} ({:016x})", c.to_bits()),
                Op::Param(p) => {
                    let p = &self.0.params[p as usize];
                    writeln!(s, "v{i} = param {} = {}", p.name, p.default)
                }
                Op::Unary(op, a) => writeln!(s, "v{i} = {} v{a}", op.name()),
                Op::Binary(op, a, b) => writeln!(s, "v{i} = {} v{a} v{b}", op.name()),
                Op::PowI(a, n) => writeln!(s, "v{i} = powi v{a} {n}"),
                Op::Select(c, a, b) => writeln!(s, "v{i} = select v{c} v{a} v{b}"),
                Op::Set { op, a, b, alpha } => {
                    writeln!(s, "v{i} = {} v{a} v{b} v{alpha}", op.name())
                }
                Op::Field { field, comp, args } => writeln!(
                    s,
                    "v{i} = field{field}.{comp} v{} v{} v{}",
                    args[0], args[1], args[2]
                ),
            };
        }
        let _ = writeln!(s, "out {:?}", self.0.outputs);
        s
    }
}

/// Collects ops, merging repeated constants (blend expansion makes some).
#[derive(Default)]
struct Builder {
    ops: Vec<Op>,
    consts: std::collections::HashMap<u64, ValueId>,
    params: Vec<ParamInfo>,
    fields: Vec<Arc<dyn Field>>,
}

impl Builder {
    fn push(&mut self, op: Op) -> ValueId {
        if let Op::Const(c) = op {
            if let Some(&v) = self.consts.get(&c.to_bits()) {
                return v;
            }
            self.consts.insert(c.to_bits(), self.ops.len() as ValueId);
        }
        self.ops.push(op);
        (self.ops.len() - 1) as ValueId
    }

    fn constant(&mut self, c: f64) -> ValueId {
        self.push(Op::Const(c))
    }

    /// `set(a, b) + a0 / (1 + (a/a1)^2 + (b/a2)^2)`, in the order of
    /// [`crate::expr::blend_displacement`].
    fn blend(&mut self, op: SetOp, [a, b, alpha, a0, a1, a2]: [ValueId; 6]) -> ValueId {
        let set = match self.ops[alpha as usize] {
            Op::Const(c) if c == 1.0 => {
                let m = match op {
                    SetOp::Union => BinaryOp::Max,
                    SetOp::Intersection => BinaryOp::Min,
                };
                self.push(Op::Binary(m, a, b))
            }
            _ => self.push(Op::Set { op, a, b, alpha }),
        };
        let one = self.constant(1.0);
        let qa = self.push(Op::Binary(BinaryOp::Div, a, a1));
        let qa = self.push(Op::Unary(UnaryOp::Square, qa));
        let qb = self.push(Op::Binary(BinaryOp::Div, b, a2));
        let qb = self.push(Op::Unary(UnaryOp::Square, qb));
        let s = self.push(Op::Binary(BinaryOp::Add, one, qa));
        let s = self.push(Op::Binary(BinaryOp::Add, s, qb));
        let d = self.push(Op::Binary(BinaryOp::Div, a0, s));
        self.push(Op::Binary(BinaryOp::Add, set, d))
    }

    fn finish(self, outputs: Vec<ValueId>) -> Tape {
        Tape::from_parts(self.ops, outputs, self.params, self.fields)
    }
}
