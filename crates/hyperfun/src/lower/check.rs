//! Checks done before lowering: the array arguments of every library call
//! against the lengths the function needs ([`crate::library::shapes`]).
//! Array lengths are fixed by declarations, so this needs no evaluation
//! and also covers calls that only some points reach.

use super::LowerError;
use crate::ast::{Cond, Expr, ExprKind, Object, Program, Stmt};
use crate::library::shapes::{self, Len};
use crate::library::Registry;
use std::collections::HashMap;

/// The first (in source order) bad array argument in object `object` and
/// the objects it calls.
pub fn check_calls(
    program: &Program,
    object: usize,
    registry: &Registry,
) -> Result<(), LowerError> {
    let mut todo = vec![object];
    let mut seen = vec![false; program.objects.len()];
    let mut errors = Vec::new();
    while let Some(i) = todo.pop() {
        if std::mem::replace(&mut seen[i], true) {
            continue;
        }
        let obj = &program.objects[i];
        let mut calls = Vec::new();
        stmts(&obj.body, &mut calls);
        calls.push(&obj.result);
        let sizes = array_sizes(obj);
        let mut stack = calls;
        while let Some(e) = stack.pop() {
            match &e.kind {
                ExprKind::Num(_) | ExprKind::Var(_) => {}
                ExprKind::Index(_, a) | ExprKind::Unary(_, a) => stack.push(a),
                ExprKind::Binary(_, a, b) => stack.extend([&**a, &**b]),
                ExprKind::Call(name, args) => {
                    if let Some(k) = program.objects[..i].iter().position(|o| o.name == *name) {
                        todo.push(k);
                    } else if registry.get(name).is_some() {
                        if let Some(e) = check_call(name, args, &sizes) {
                            errors.push(e);
                        }
                    }
                    stack.extend(args);
                }
            }
        }
    }
    match errors.into_iter().min_by_key(|e| e.pos) {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

/// Lengths of the arrays visible in an object: `x`, `a`, `s` and its own.
fn array_sizes(obj: &Object) -> HashMap<&str, usize> {
    let mut m = HashMap::from([
        ("x", obj.x_size),
        ("a", obj.a_size),
        ("s", obj.s_size.max(1)),
    ]);
    for d in &obj.arrays {
        m.insert(d.name.as_str(), d.size);
    }
    m
}

/// Every expression of a statement list (conditions included).
fn stmts<'a>(ss: &'a [Stmt], out: &mut Vec<&'a Expr>) {
    for s in ss {
        match s {
            Stmt::Assign { value, .. } => out.push(value),
            Stmt::AssignIndex { index, value, .. } => out.extend([index, value]),
            Stmt::AssignArray { .. } => {}
            Stmt::If {
                cond,
                then_body,
                else_body,
                ..
            } => {
                conds(cond, out);
                stmts(then_body, out);
                stmts(else_body, out);
            }
            Stmt::While { cond, body, .. } => {
                conds(cond, out);
                stmts(body, out);
            }
        }
    }
}

fn conds<'a>(root: &'a Cond, out: &mut Vec<&'a Expr>) {
    let mut stack = vec![root];
    while let Some(c) = stack.pop() {
        match c {
            Cond::Value(e) => out.push(e),
            Cond::Not(a) => stack.push(a),
            Cond::Cmp(_, a, b) | Cond::And(a, b) | Cond::Or(a, b) => stack.extend([&**a, &**b]),
        }
    }
}

/// The error for the first array argument of this call that breaks its
/// function's rule.
fn check_call(name: &str, args: &[Expr], sizes: &HashMap<&str, usize>) -> Option<LowerError> {
    let rules = shapes::rules(name)?;
    let names: Vec<String> = args
        .iter()
        .map(|a| match &a.kind {
            ExprKind::Var(n) => n.clone(),
            _ => String::new(),
        })
        .collect();
    let lens: Vec<Option<usize>> = args
        .iter()
        .zip(rules.iter().chain(std::iter::repeat(&None)))
        .map(|(a, rule)| match (&a.kind, rule) {
            (ExprKind::Var(n), Some(_)) => sizes.get(n.as_str()).copied(),
            _ => None,
        })
        .collect();
    for (k, rule) in rules.iter().enumerate() {
        let (Some(rule), Some(Some(n))) = (rule, lens.get(k)) else {
            continue;
        };
        if matches!(rule, Len::Point | Len::Any) || rule.accepts(*n, &lens) {
            continue;
        }
        return Some(LowerError {
            message: format!(
                "{}: argument {} ('{}') has {n} element{}; it must have {}",
                shapes::display_name(name),
                k + 1,
                names[k],
                if *n == 1 { "" } else { "s" },
                rule.describe(&lens, &names)
            ),
            pos: args[k].pos,
        });
    }
    None
}
