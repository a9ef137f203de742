//! Finding where a program calls a given function (for `check` warnings,
//! e.g. on `sign`, which the reference always evaluates to 1).

use crate::ast::{Cond, Expr, ExprKind, Pos, Program, Stmt};

/// Positions of every call of `name` (lower case), in source order.
pub fn calls_of(program: &Program, name: &str) -> Vec<Pos> {
    let mut out = Vec::new();
    for o in &program.objects {
        stmts(&o.body, name, &mut out);
        expr(&o.result, name, &mut out);
    }
    out
}

fn stmts(ss: &[Stmt], name: &str, out: &mut Vec<Pos>) {
    for s in ss {
        match s {
            Stmt::Assign { value, .. } => expr(value, name, out),
            Stmt::AssignIndex { index, value, .. } => {
                expr(index, name, out);
                expr(value, name, out);
            }
            Stmt::AssignArray { .. } => {}
            Stmt::If {
                cond,
                then_body,
                else_body,
                ..
            } => {
                cond_(cond, name, out);
                stmts(then_body, name, out);
                stmts(else_body, name, out);
            }
            Stmt::While { cond, body, .. } => {
                cond_(cond, name, out);
                stmts(body, name, out);
            }
        }
    }
}

fn cond_(root: &Cond, name: &str, out: &mut Vec<Pos>) {
    // Iterative, in source order: `and` chains can be 100k long.
    let mut stack = vec![root];
    while let Some(c) = stack.pop() {
        match c {
            Cond::Value(e) => expr(e, name, out),
            Cond::Not(a) => stack.push(a),
            Cond::Cmp(_, a, b) | Cond::And(a, b) | Cond::Or(a, b) => stack.extend([&**b, &**a]),
        }
    }
}

/// Iterative: operator chains in generated models are 100k deep.
fn expr(root: &Expr, name: &str, out: &mut Vec<Pos>) {
    let mut found = Vec::new();
    let mut stack = vec![root];
    while let Some(e) = stack.pop() {
        match &e.kind {
            ExprKind::Num(_) | ExprKind::Var(_) => {}
            ExprKind::Index(_, i) | ExprKind::Unary(_, i) => stack.push(i),
            ExprKind::Binary(_, a, b) => stack.extend([&**a, &**b]),
            ExprKind::Call(f, args) => {
                if f == name {
                    found.push(e.pos);
                }
                stack.extend(args);
            }
        }
    }
    found.sort();
    out.extend(found);
}
