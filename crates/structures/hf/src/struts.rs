//! Strut lattices: the unit cell, the replicated lattice with a radius
//! field, and the lattice with a target density field.

use crate::args::{code, out, three, value};
use crate::tables::strut_table;
use microfrep_core::{Axis, Expr, ExprNode, SetOp};
use microfrep_hyperfun::library::{Arg, Kind::*, Output, Registry};
use microfrep_structures::struts::{strut_cell, strut_lattice, StrutLattice};
use std::collections::VecDeque;
use std::sync::Mutex;

/// An `mfStruts` or `mfStrutsDensity` call made while lowering a model:
/// its arguments and the expression it gave, so that a host can write the
/// lattice as beams (see [`strut_model`]).
#[derive(Clone, Debug)]
pub struct StrutCall {
    /// The lattice family.
    pub kind: StrutLattice,
    /// The point argument.
    pub x: [Expr; 3],
    /// Cell size.
    pub cell: Expr,
    /// Strut radius in length units (for `mfStrutsDensity`, the radius its
    /// density gives).
    pub radius: Expr,
    /// The call's value.
    pub value: Expr,
}

/// Most recent calls kept (older ones are forgotten, so a long-running
/// host does not accumulate expressions).
const KEPT_CALLS: usize = 64;

static CALLS: Mutex<VecDeque<StrutCall>> = Mutex::new(VecDeque::new());

fn record(call: StrutCall) {
    let mut q = CALLS.lock().unwrap_or_else(|e| e.into_inner());
    if q.len() == KEPT_CALLS {
        q.pop_front();
    }
    q.push_back(call);
}

fn same(a: &Expr, b: &Expr) -> bool {
    std::ptr::eq(a.node(), b.node())
}

/// A strut lattice model: the lattice and the part that clips it.
#[derive(Clone, Debug)]
pub struct StrutModel {
    /// The lattice family.
    pub kind: StrutLattice,
    /// Cell size.
    pub cell: f64,
    /// Strut radius.
    pub radius: f64,
    /// The part the lattice is intersected with (`None`: the whole box).
    pub part: Option<Expr>,
}

/// Whether `e` has the same value everywhere (no coordinate or field).
fn constant_value(e: &Expr) -> Option<f64> {
    if let Some(c) = e.as_const() {
        return Some(c);
    }
    let mut stack = vec![e.clone()];
    let mut seen = 0usize;
    while let Some(n) = stack.pop() {
        seen += 1;
        if seen > 10_000 {
            return None;
        }
        match n.node() {
            ExprNode::Var(_) | ExprNode::Field { .. } => return None,
            _ => stack.extend(n.children().into_iter().cloned()),
        }
    }
    let v = microfrep_core::PointEval::new(&microfrep_core::Tape::new(e)).eval([0.0; 3]);
    v.is_finite().then_some(v)
}

/// The strut lattice that a lowered model's value `value` is, if it is
/// one: the value of an `mfStruts`/`mfStrutsDensity` call of this process
/// (among the last 64) at the untransformed point `x` with a constant cell
/// size and radius, alone or intersected (`&`, any R-function parameter
/// in `(-1, 1]`, or `min`) with a part. The call's struts are capsules of
/// one radius, so the lattice is exactly a beam lattice of that radius
/// clipped by the part. `None` for anything else (a transformed point, a
/// graded radius, a union with other solids, ...).
pub fn strut_model(value: &Expr) -> Option<StrutModel> {
    let calls: Vec<StrutCall> = {
        let q = CALLS.lock().unwrap_or_else(|e| e.into_inner());
        q.iter().cloned().collect()
    };
    let find = |e: &Expr| calls.iter().rev().find(|c| same(&c.value, e)).cloned();
    let (call, part) = match find(value) {
        Some(c) => (c, None),
        None => {
            let (a, b) = match value.node() {
                ExprNode::Set {
                    op: SetOp::Intersection,
                    a,
                    b,
                    alpha,
                } if alpha.as_const().is_some_and(|al| al > -1.0 && al <= 1.0) => (a, b),
                ExprNode::Binary(microfrep_core::BinaryOp::Min, a, b) => (a, b),
                _ => return None,
            };
            match (find(a), find(b)) {
                (Some(c), _) => (c, Some(b.clone())),
                (None, Some(c)) => (c, Some(a.clone())),
                _ => return None,
            }
        }
    };
    let axes = [Axis::X, Axis::Y, Axis::Z];
    let plain = call
        .x
        .iter()
        .zip(axes)
        .all(|(e, a)| matches!(e.node(), ExprNode::Var(v) if *v == a));
    let cell = constant_value(&call.cell)?;
    let radius = constant_value(&call.radius)?;
    (plain && cell > 0.0 && radius > 0.0).then_some(StrutModel {
        kind: call.kind,
        cell,
        radius,
        part,
    })
}

fn kind(a: &Arg) -> Result<StrutLattice, Output> {
    Ok(StrutLattice::ALL[code(a, "strut lattice kind", 1, 6)? as usize - 1])
}

/// `mfStrutCell(q, kind, r)`: the unit cell on [0, 1]^3.
fn cell(a: &[Arg]) -> Output {
    out(|| {
        let q = three(&a[0], "q")?;
        value(strut_cell(kind(&a[1])?, &q, a[2].real()))
    })
}

/// `mfStruts(x, kind, cell, r)`.
fn lattice(a: &[Arg]) -> Output {
    out(|| {
        let x = three(&a[0], "x")?;
        let k = kind(&a[1])?;
        let v = strut_lattice(k, &x, a[2].real(), a[3].real());
        record(StrutCall {
            kind: k,
            x,
            cell: a[2].real(),
            radius: a[3].real(),
            value: v.clone(),
        });
        value(v)
    })
}

/// `mfStrutsDensity(x, kind, cell, rho)`.
fn density(a: &[Arg]) -> Output {
    out(|| {
        let x = three(&a[0], "x")?;
        let k = kind(&a[1])?;
        let table = strut_table(k).map_err(Output::error)?;
        let cell = a[2].real();
        let r = table.piecewise(&a[3].real()) * &cell;
        let v = strut_lattice(k, &x, cell.clone(), r.clone());
        record(StrutCall {
            kind: k,
            x,
            cell,
            radius: r,
            value: v.clone(),
        });
        value(v)
    })
}

pub(crate) fn register(r: &mut Registry) {
    r.register("mfstrutcell", &[A, R, R], cell);
    r.register("mfstruts", &[A, R, R, R], lattice);
    r.register("mfstrutsdensity", &[A, R, R, R], density);
}
