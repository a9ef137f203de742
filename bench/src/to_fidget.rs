//! Translation of a microfrep expression into a fidget `Context`, node by
//! node over the deduplicated graph, so both engines run the same arithmetic.
//!
//! fidget's shapes are inside-negative, so the result is the negated model.
//! Ops fidget lacks are spelled with ops it has (waves and modulo with
//! `floor`, hyperbolic functions with `exp`); parameters take their defaults.
//! Data-driven fields have no fidget counterpart and are an error.

use fidget::context::{Context, Node as FNode};
use microfrep_core::{Axis, BinaryOp, Expr, Graph, Node, UnaryOp};

type R = Result<FNode, String>;

/// Returns the context and the root of `-e`.
pub fn translate(e: &Expr) -> Result<(Context, FNode), String> {
    let mut g = Graph::new();
    let root = g.add(e);
    let mut ctx = Context::new();
    let mut map: Vec<FNode> = Vec::with_capacity(g.len());
    for (i, n) in g.nodes().iter().enumerate() {
        let node = lower(&mut ctx, &g, &map, *n).map_err(|e| format!("graph node {i}: {e}"))?;
        map.push(node);
    }
    let out = ctx.neg(map[root.0 as usize]).map_err(err)?;
    Ok((ctx, out))
}

fn err(e: impl std::fmt::Display) -> String {
    e.to_string()
}

fn lower(c: &mut Context, g: &Graph, map: &[FNode], n: Node) -> R {
    let m = |id: microfrep_core::NodeId| map[id.0 as usize];
    match n {
        Node::Var(Axis::X) => Ok(c.x()),
        Node::Var(Axis::Y) => Ok(c.y()),
        Node::Var(Axis::Z) => Ok(c.z()),
        Node::Const(bits) => Ok(c.constant(f64::from_bits(bits) as f32)),
        Node::Param(p) => Ok(c.constant(g.params()[p as usize].default as f32)),
        Node::Unary(op, a) => unary(c, op, m(a)),
        Node::Binary(op, a, b) => binary(c, op, m(a), m(b)),
        Node::PowI(a, k) => powi(c, m(a), k),
        Node::Select(cond, a, b) => c.if_nonzero_else(m(cond), m(a), m(b)).map_err(err),
        Node::Set { op, a, b, alpha } => set(c, op, m(a), m(b), m(alpha)),
        Node::Blend { op, args } => {
            let [a, b, alpha, a0, a1, a2] = args.map(m);
            let s = set(c, op, a, b, alpha)?;
            let qa = c.div(a, a1).map_err(err)?;
            let qa = c.square(qa).map_err(err)?;
            let qb = c.div(b, a2).map_err(err)?;
            let qb = c.square(qb).map_err(err)?;
            let d = c.add(qa, qb).map_err(err)?;
            let d = c.add(d, 1.0).map_err(err)?;
            let d = c.div(a0, d).map_err(err)?;
            c.add(s, d).map_err(err)
        }
        Node::Field { .. } => Err("data-driven fields have no fidget equivalent".into()),
    }
}

/// The R-function written out in fidget's operations.
fn set(c: &mut Context, op: microfrep_core::SetOp, a: FNode, b: FNode, alpha: FNode) -> R {
    let s = c.add(a, b).map_err(err)?;
    let aa = c.square(a).map_err(err)?;
    let bb = c.square(b).map_err(err)?;
    let q = c.add(aa, bb).map_err(err)?;
    let zero = c.get_const(alpha).map(|v| v == 0.0).unwrap_or(false);
    let q = if zero {
        q
    } else {
        let t = c.mul(alpha, 2.0).map_err(err)?;
        let t = c.mul(t, a).map_err(err)?;
        let t = c.mul(t, b).map_err(err)?;
        c.sub(q, t).map_err(err)?
    };
    let r = c.sqrt(q).map_err(err)?;
    let v = match op {
        microfrep_core::SetOp::Union => c.add(s, r),
        microfrep_core::SetOp::Intersection => c.sub(s, r),
    }
    .map_err(err)?;
    if zero {
        Ok(v)
    } else {
        let k = c.add(alpha, 1.0).map_err(err)?;
        c.div(v, k).map_err(err)
    }
}

/// 1 where `a` is nonzero, else 0.
fn truthy(c: &mut Context, a: FNode) -> R {
    let n = c.not(a).map_err(err)?;
    c.not(n).map_err(err)
}

fn trunc(c: &mut Context, a: FNode) -> R {
    let neg = c.less_than(a, 0.0).map_err(err)?;
    let up = c.ceil(a).map_err(err)?;
    let down = c.floor(a).map_err(err)?;
    c.if_nonzero_else(neg, up, down).map_err(err)
}

fn unary(c: &mut Context, op: UnaryOp, a: FNode) -> R {
    use UnaryOp::*;
    let r = match op {
        Neg => c.neg(a),
        Abs => c.abs(a),
        Sign => c.compare(a, 0.0),
        Sqrt => c.sqrt(a),
        Square => c.square(a),
        Exp => c.exp(a),
        Ln => c.ln(a),
        Sin => c.sin(a),
        Cos => c.cos(a),
        Tan => c.tan(a),
        Asin => c.asin(a),
        Acos => c.acos(a),
        Atan => c.atan(a),
        Sinh | Cosh => {
            let ep = c.exp(a).map_err(err)?;
            let na = c.neg(a).map_err(err)?;
            let en = c.exp(na).map_err(err)?;
            let s = if op == Sinh {
                c.sub(ep, en)
            } else {
                c.add(ep, en)
            }
            .map_err(err)?;
            c.mul(s, 0.5)
        }
        Tanh => {
            // 1 - 2 / (exp(2a) + 1): no overflow to inf/inf for large a.
            let a2 = c.mul(a, 2.0).map_err(err)?;
            let e = c.exp(a2).map_err(err)?;
            let d = c.add(e, 1.0).map_err(err)?;
            let q = c.div(2.0, d).map_err(err)?;
            c.sub(1.0, q)
        }
        Floor => c.floor(a),
        Ceil => c.ceil(a),
        Trunc => return trunc(c, a),
        Round => {
            // Half away from zero: trunc(a + sign(a) / 2).
            let s = c.compare(a, 0.0).map_err(err)?;
            let h = c.mul(s, 0.5).map_err(err)?;
            let v = c.add(a, h).map_err(err)?;
            return trunc(c, v);
        }
        Fract => {
            let f = c.floor(a).map_err(err)?;
            c.sub(a, f)
        }
        Tri => {
            // 1 - |2 fract(u/2 + 1/4) - 1|
            let s = c.mul(a, 0.5).map_err(err)?;
            let s = c.add(s, 0.25).map_err(err)?;
            let f = c.floor(s).map_err(err)?;
            let fr = c.sub(s, f).map_err(err)?;
            let t = c.mul(fr, 2.0).map_err(err)?;
            let t = c.sub(t, 1.0).map_err(err)?;
            let t = c.abs(t).map_err(err)?;
            c.sub(1.0, t)
        }
        Saw => {
            // 1/2 + u - floor(u + 1/2)
            let s = c.add(a, 0.5).map_err(err)?;
            let f = c.floor(s).map_err(err)?;
            c.sub(s, f)
        }
        Not => c.not(a),
    };
    r.map_err(err)
}

fn binary(c: &mut Context, op: BinaryOp, a: FNode, b: FNode) -> R {
    use BinaryOp::*;
    let r = match op {
        Add => c.add(a, b),
        Sub => c.sub(a, b),
        Mul => c.mul(a, b),
        Div => c.div(a, b),
        Pow => {
            let l = c.ln(a).map_err(err)?;
            let p = c.mul(b, l).map_err(err)?;
            c.exp(p)
        }
        Atan2 => c.atan2(a, b),
        Min => c.min(a, b),
        Max => c.max(a, b),
        Mod | Rem => {
            // a - b * floor(a / b) (floored) or with trunc (C fmod).
            let q = c.div(a, b).map_err(err)?;
            let q = if op == Mod {
                c.floor(q).map_err(err)?
            } else {
                trunc(c, q)?
            };
            let p = c.mul(b, q).map_err(err)?;
            c.sub(a, p)
        }
        Lt => c.less_than(a, b),
        Le => c.less_than_or_equal(a, b),
        Gt => c.less_than(b, a),
        Ge => c.less_than_or_equal(b, a),
        Eq => {
            let d = c.compare(a, b).map_err(err)?;
            c.not(d)
        }
        Ne => {
            let d = c.compare(a, b).map_err(err)?;
            return truthy(c, d);
        }
        And => {
            let v = c.and(a, b).map_err(err)?;
            return truthy(c, v);
        }
        Or => {
            let v = c.or(a, b).map_err(err)?;
            return truthy(c, v);
        }
    };
    r.map_err(err)
}

/// Square-and-multiply, as the batch evaluator does it.
fn powi(c: &mut Context, a: FNode, n: i32) -> R {
    let mut acc: Option<FNode> = None;
    let mut base = a;
    let mut e = n.unsigned_abs();
    while e > 0 {
        if e & 1 == 1 {
            acc = Some(match acc {
                Some(v) => c.mul(v, base).map_err(err)?,
                None => base,
            });
        }
        e >>= 1;
        if e > 0 {
            base = c.square(base).map_err(err)?;
        }
    }
    let v = acc.unwrap_or_else(|| c.constant(1.0));
    if n < 0 {
        c.div(1.0, v).map_err(err)
    } else {
        Ok(v)
    }
}
