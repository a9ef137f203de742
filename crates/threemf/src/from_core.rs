//! The core expression graph ([`microfrep_core::Graph`]) as an implicit
//! function: one vector argument `pos`, one scalar output `value`.
//!
//! Every core operation except data-driven fields maps to native nodes,
//! most one to one, the rest composed from a few (see [`CORE_OP_MAPPING`]).
//! Comparisons and logic become `select` nodes (`A < B ? C : D`), so they
//! agree with the core for all numbers; for NaN inputs they can differ
//! (the draft does not define NaN). Parameters are written as constants
//! with their default value. A [`Node::Field`] has no implicit node:
//! [`unsupported`] lists such nodes so a caller can fall back to an image
//! stack of the field ([`crate::volumetric::Image3D`]).

use crate::implicit::{
    FunctionOutput, ImplicitFunction, ImplicitGraph, ImplicitNode, NodeInput, NodeValue, PortType,
};
use microfrep_core::{Axis, BinaryOp, Expr, Graph, Node, NodeId, SetOp, UnaryOp};
use std::collections::HashMap;

/// How each core operation is written: `(core op, implicit nodes)`.
pub const CORE_OP_MAPPING: &[(&str, &str)] = &[
    ("var x/y/z", "decomposevector of inputs.pos"),
    ("const, param (default)", "constant"),
    ("neg", "multiplication by -1"),
    ("abs", "abs"),
    ("sign", "sign"),
    ("sqrt", "sqrt"),
    ("square", "multiplication"),
    ("exp", "exp"),
    ("ln", "log"),
    ("sin, cos, tan", "sin, cos, tan"),
    ("asin, acos, atan", "arcsin, arccos, arctan"),
    ("sinh, cosh, tanh", "sinh, cosh, tanh"),
    ("floor, ceil, round", "floor, ceil, round"),
    ("trunc", "sign(a) * floor(abs(a))"),
    ("fract", "fract"),
    ("tri", "1 - abs(2 fract(a/2 + 1/4) - 1)"),
    ("saw", "1/2 + a - floor(a + 1/2)"),
    ("not", "select(0, abs(a), 0, 1)"),
    (
        "add, sub, mul, div",
        "addition, subtraction, multiplication, division",
    ),
    ("pow", "pow"),
    ("powi", "pow with a constant exponent"),
    ("atan2", "arctan2"),
    ("min, max", "min, max"),
    ("mod", "mod"),
    ("rem", "fmod"),
    ("lt, gt, le, ge, eq, ne", "select"),
    ("and, or", "select on abs, then multiplication / max"),
    ("select(c, a, b)", "select(0, abs(c), a, b)"),
    ("field", "none: fall back to an image stack"),
];

/// Core operations with no implicit node.
pub const NO_IMPLICIT_NODE: &[&str] = &["field"];

/// A node of the graph that cannot be written as implicit nodes.
#[derive(Clone, Debug, PartialEq)]
pub struct Unsupported {
    /// The node.
    pub node: NodeId,
    /// What it is (`field 'name'`).
    pub what: String,
}

/// The nodes reachable from `root` that have no implicit node.
pub fn unsupported(g: &Graph, root: NodeId) -> Vec<Unsupported> {
    reachable(g, root)
        .into_iter()
        .filter_map(|id| match g.node(id) {
            Node::Field { field, .. } => Some(Unsupported {
                node: id,
                what: format!("field '{}'", g.fields()[field as usize].name()),
            }),
            _ => None,
        })
        .collect()
}

fn children(n: Node) -> Vec<NodeId> {
    n.children()
}

/// Node ids reachable from `root`, ascending (topological).
fn reachable(g: &Graph, root: NodeId) -> Vec<NodeId> {
    let mut seen = vec![false; root.0 as usize + 1];
    seen[root.0 as usize] = true;
    for i in (0..=root.0 as usize).rev() {
        if seen[i] {
            for c in children(g.node(NodeId(i as u32))) {
                seen[c.0 as usize] = true;
            }
        }
    }
    (0..seen.len())
        .filter(|&i| seen[i])
        .map(|i| NodeId(i as u32))
        .collect()
}

struct Builder {
    nodes: Vec<ImplicitNode>,
    consts: HashMap<u64, String>,
}

impl Builder {
    fn push(&mut self, op: &str, value: NodeValue, inputs: &[(&str, &str)]) -> String {
        let id = format!("n{}", self.nodes.len());
        let out = match op {
            "constant" => "value",
            _ => "result",
        };
        self.nodes.push(ImplicitNode {
            id: id.clone(),
            op: op.to_string(),
            value,
            inputs: inputs
                .iter()
                .map(|(port, src)| NodeInput {
                    port: port.to_string(),
                    source: src.to_string(),
                    kind: PortType::Scalar,
                })
                .collect(),
            outputs: vec![(out.to_string(), PortType::Scalar)],
        });
        format!("{id}.{out}")
    }

    fn konst(&mut self, v: f64) -> String {
        if let Some(s) = self.consts.get(&v.to_bits()) {
            return s.clone();
        }
        let s = self.push("constant", NodeValue::Scalar(v), &[]);
        self.consts.insert(v.to_bits(), s.clone());
        s
    }

    fn un(&mut self, op: &str, a: &str) -> String {
        self.push(op, NodeValue::None, &[("A", a)])
    }

    fn bin(&mut self, op: &str, a: &str, b: &str) -> String {
        self.push(op, NodeValue::None, &[("A", a), ("B", b)])
    }

    /// `a < b ? c : d`.
    fn select(&mut self, a: &str, b: &str, c: &str, d: &str) -> String {
        self.push(
            "select",
            NodeValue::None,
            &[("A", a), ("B", b), ("C", c), ("D", d)],
        )
    }

    /// 1 if `a != 0` else 0.
    fn nonzero(&mut self, a: &str) -> String {
        let (zero, one) = (self.konst(0.0), self.konst(1.0));
        let abs = self.un("abs", a);
        self.select(&zero, &abs, &one, &zero)
    }
}

/// The expression as an implicit function (see the module docs), or the
/// nodes that prevent it.
pub fn implicit_from_expr(
    e: &Expr,
    id: u32,
    name: Option<&str>,
) -> Result<ImplicitFunction, Vec<Unsupported>> {
    let mut g = Graph::new();
    let root = g.add(e);
    implicit_from_graph(&g, root, id, name)
}

/// The value of `root` in `g` as an implicit function.
pub fn implicit_from_graph(
    g: &Graph,
    root: NodeId,
    id: u32,
    name: Option<&str>,
) -> Result<ImplicitFunction, Vec<Unsupported>> {
    build(g, root, id, name, false)
}

/// As [`implicit_from_expr`], negated: the sign a `<v:levelset>` expects
/// (inside negative), so the level set's shape is the model's `f >= 0`.
pub fn levelset_function(
    e: &Expr,
    id: u32,
    name: Option<&str>,
) -> Result<ImplicitFunction, Vec<Unsupported>> {
    let mut g = Graph::new();
    let root = g.add(e);
    build(&g, root, id, name, true)
}

fn build(
    g: &Graph,
    root: NodeId,
    id: u32,
    name: Option<&str>,
    negate: bool,
) -> Result<ImplicitFunction, Vec<Unsupported>> {
    let bad = unsupported(g, root);
    if !bad.is_empty() {
        return Err(bad);
    }
    let mut b = Builder {
        nodes: vec![ImplicitNode {
            id: "pos".into(),
            op: "decomposevector".into(),
            value: NodeValue::None,
            inputs: vec![NodeInput {
                port: "A".into(),
                source: "inputs.pos".into(),
                kind: PortType::Vector,
            }],
            outputs: vec![
                ("x".into(), PortType::Scalar),
                ("y".into(), PortType::Scalar),
                ("z".into(), PortType::Scalar),
            ],
        }],
        consts: HashMap::new(),
    };
    let mut src: HashMap<u32, String> = HashMap::new();
    for nid in reachable(g, root) {
        let s = |i: NodeId| src[&i.0].clone();
        let out = match g.node(nid) {
            Node::Var(a) => match a {
                Axis::X => "pos.x".to_string(),
                Axis::Y => "pos.y".to_string(),
                Axis::Z => "pos.z".to_string(),
            },
            Node::Const(bits) => b.konst(f64::from_bits(bits)),
            Node::Param(i) => b.konst(g.params()[i as usize].default),
            Node::Unary(op, a) => unary(&mut b, op, &s(a)),
            Node::Binary(op, x, y) => binary(&mut b, op, &s(x), &s(y)),
            Node::PowI(a, n) => {
                let e = b.konst(n as f64);
                b.bin("pow", &s(a), &e)
            }
            Node::Select(c, x, y) => {
                let zero = b.konst(0.0);
                let abs = b.un("abs", &s(c));
                b.select(&zero, &abs, &s(x), &s(y))
            }
            Node::Set { op, a, b: y, alpha } => set(&mut b, op, &s(a), &s(y), &s(alpha)),
            Node::Blend { op, args } => {
                let [a, y, alpha, a0, a1, a2] = args.map(s);
                let v = set(&mut b, op, &a, &y, &alpha);
                let one = b.konst(1.0);
                let qa = b.bin("division", &a, &a1);
                let qa = b.bin("multiplication", &qa, &qa);
                let qb = b.bin("division", &y, &a2);
                let qb = b.bin("multiplication", &qb, &qb);
                let d = b.bin("addition", &one, &qa);
                let d = b.bin("addition", &d, &qb);
                let d = b.bin("division", &a0, &d);
                b.bin("addition", &v, &d)
            }
            Node::Field { .. } => unreachable!("fields were rejected above"),
        };
        src.insert(nid.0, out);
    }
    let mut result = src[&root.0].clone();
    if negate {
        let m = b.konst(-1.0);
        result = b.bin("multiplication", &result, &m);
    }
    Ok(ImplicitFunction {
        id,
        display_name: name.map(str::to_string),
        inputs: vec![("pos".into(), PortType::Vector)],
        graph: ImplicitGraph { nodes: b.nodes },
        outputs: vec![FunctionOutput {
            name: "value".into(),
            kind: PortType::Scalar,
            source: result,
        }],
    })
}

/// The R-function `(a + b ± sqrt(a² + b² - 2 alpha a b)) / (1 + alpha)`
/// written with native nodes (the implicit extension has no set node).
fn set(b: &mut Builder, op: SetOp, x: &str, y: &str, alpha: &str) -> String {
    let (one, two) = (b.konst(1.0), b.konst(2.0));
    let s = b.bin("addition", x, y);
    let xx = b.bin("multiplication", x, x);
    let yy = b.bin("multiplication", y, y);
    let q = b.bin("addition", &xx, &yy);
    let t = b.bin("multiplication", &two, alpha);
    let t = b.bin("multiplication", &t, x);
    let t = b.bin("multiplication", &t, y);
    let q = b.bin("subtraction", &q, &t);
    let r = b.un("sqrt", &q);
    let v = match op {
        SetOp::Union => b.bin("addition", &s, &r),
        SetOp::Intersection => b.bin("subtraction", &s, &r),
    };
    let k = b.bin("addition", &one, alpha);
    b.bin("division", &v, &k)
}

fn unary(b: &mut Builder, op: UnaryOp, a: &str) -> String {
    use UnaryOp::*;
    let native = match op {
        Abs => Some("abs"),
        Sign => Some("sign"),
        Sqrt => Some("sqrt"),
        Exp => Some("exp"),
        Ln => Some("log"),
        Sin => Some("sin"),
        Cos => Some("cos"),
        Tan => Some("tan"),
        Asin => Some("arcsin"),
        Acos => Some("arccos"),
        Atan => Some("arctan"),
        Sinh => Some("sinh"),
        Cosh => Some("cosh"),
        Tanh => Some("tanh"),
        Floor => Some("floor"),
        Ceil => Some("ceil"),
        Round => Some("round"),
        Fract => Some("fract"),
        _ => None,
    };
    if let Some(n) = native {
        return b.un(n, a);
    }
    match op {
        Neg => {
            let m = b.konst(-1.0);
            b.bin("multiplication", a, &m)
        }
        Square => b.bin("multiplication", a, a),
        Trunc => {
            let s = b.un("sign", a);
            let abs = b.un("abs", a);
            let f = b.un("floor", &abs);
            b.bin("multiplication", &s, &f)
        }
        Tri => {
            // 1 - |2 fract(u/2 + 1/4) - 1|, as the core computes it.
            let (half, quarter, one, two) =
                (b.konst(0.5), b.konst(0.25), b.konst(1.0), b.konst(2.0));
            let h = b.bin("multiplication", &half, a);
            let s = b.bin("addition", &h, &quarter);
            let f = b.un("fract", &s);
            let t = b.bin("multiplication", &two, &f);
            let d = b.bin("subtraction", &t, &one);
            let ab = b.un("abs", &d);
            b.bin("subtraction", &one, &ab)
        }
        Saw => {
            let half = b.konst(0.5);
            let s = b.bin("addition", &half, a);
            let u = b.bin("addition", a, &half);
            let f = b.un("floor", &u);
            b.bin("subtraction", &s, &f)
        }
        Not => {
            let (zero, one) = (b.konst(0.0), b.konst(1.0));
            let abs = b.un("abs", a);
            b.select(&zero, &abs, &zero, &one)
        }
        _ => unreachable!("native ops handled above"),
    }
}

fn binary(b: &mut Builder, op: BinaryOp, x: &str, y: &str) -> String {
    use BinaryOp::*;
    let native = match op {
        Add => Some("addition"),
        Sub => Some("subtraction"),
        Mul => Some("multiplication"),
        Div => Some("division"),
        Pow => Some("pow"),
        Atan2 => Some("arctan2"),
        Min => Some("min"),
        Max => Some("max"),
        Mod => Some("mod"),
        Rem => Some("fmod"),
        _ => None,
    };
    if let Some(n) = native {
        return b.bin(n, x, y);
    }
    let (zero, one) = (b.konst(0.0), b.konst(1.0));
    match op {
        Lt => b.select(x, y, &one, &zero),
        Gt => b.select(y, x, &one, &zero),
        Le => b.select(y, x, &zero, &one),
        Ge => b.select(x, y, &zero, &one),
        Eq | Ne => {
            let (t, f) = if op == Eq {
                (&one, &zero)
            } else {
                (&zero, &one)
            };
            let inner = b.select(y, x, f, t);
            b.select(x, y, f, &inner)
        }
        And => {
            let (p, q) = (b.nonzero(x), b.nonzero(y));
            b.bin("multiplication", &p, &q)
        }
        Or => {
            let (p, q) = (b.nonzero(x), b.nonzero(y));
            b.bin("max", &p, &q)
        }
        _ => unreachable!("native ops handled above"),
    }
}
