//! Symbolic execution of one object: statements run in order on symbolic
//! values (SSA style), so the result is a core expression for the value and
//! one for the error code. With constant coordinates everything folds and
//! the same code is the per-point fallback interpreter.

use super::errors::{ErrorTable, RuntimeError};
use super::ops::{self, Fault};
use crate::ast::{self, BinOp, CmpOp, Cond, ExprKind, Object, Pos, Program, Stmt, UnOp};
use crate::library::{Arg, Kind, Registry, EPS};
use microfrep_core::Expr;
use std::collections::{HashMap, HashSet};

/// Loop iterations allowed when a model is lowered (once, at load; the
/// reference would hang). Loops whose trip count is fixed run here, e.g. a
/// loop building a union of 100k spheres.
pub const LOOP_BUDGET: u64 = 1_000_000;
/// Loop iterations allowed per point in the per-point fallback: 100 times
/// the iterations of a heavy escape-time fractal, about 0.2 s of work.
pub const POINT_LOOP_BUDGET: u64 = 100_000;

/// Select nodes that merging the branches of point-dependent `if`s may add
/// in all (each merged variable or array element adds one, nested `if`s
/// merge again at every level). Past this the model takes the per-point
/// fallback, so a pathological program cannot grow the graph without
/// bound; real models stay far below (a loop of 100k iterations around an
/// `if` that sets two variables adds 200k).
pub const MERGE_BUDGET: u64 = 1 << 21;

/// Expression nodes one lowering (or one point of the per-point fallback)
/// may build, about 1 GiB with everything the graph later costs. Objects
/// calling objects multiply: 30 objects each calling the one before with
/// two different arguments build 2^30 copies of the first. Calls with the
/// same arguments are shared (see [`Exec::call_object`]), so this only
/// refuses programs whose graph is really that large, and does so while
/// it grows, before the memory is spent.
pub const NODE_BUDGET: u64 = 1 << 24;

/// Why a model cannot become one expression graph.
#[derive(Debug, Clone, PartialEq)]
pub enum Stop {
    /// Control flow depends on the point: use the per-point fallback.
    NeedsPoint(PerPoint),
    /// A static error (bad call between objects, ...), reported at load.
    Static(String, Pos),
}

/// Why a model runs on the per-point interpreter, and where.
#[derive(Debug, Clone, PartialEq)]
pub struct PerPoint {
    /// What depends on the point.
    pub message: String,
    /// The loop, call or `if` that needs it.
    pub pos: Pos,
}

fn needs_point(message: impl Into<String>, pos: Pos) -> Stop {
    Stop::NeedsPoint(PerPoint {
        message: message.into(),
        pos,
    })
}

fn c(v: f64) -> Expr {
    Expr::constant(v)
}

fn is_true(e: &Expr) -> bool {
    e.as_const().is_some_and(|v| v != 0.0)
}

/// Whether two expressions are known to be the same (one node, or equal
/// constants), so a `select` between them is either of them.
fn same(a: &Expr, b: &Expr) -> bool {
    std::ptr::eq(a.node(), b.node())
        || matches!((a.as_const(), b.as_const()), (Some(x), Some(y)) if x.to_bits() == y.to_bits())
}

/// `select(cond, a, b)`, or `a` when both are the same.
fn pick(cond: &Expr, a: &Expr, b: &Expr) -> Expr {
    if same(a, b) {
        a.clone()
    } else {
        Expr::select(cond.clone(), a.clone(), b.clone())
    }
}

/// A variable cell: its value and whether it holds one (truth value).
#[derive(Clone)]
struct Slot {
    v: Expr,
    init: Expr,
}

impl Slot {
    fn set(v: Expr) -> Slot {
        Slot { v, init: c(1.0) }
    }
    fn unset() -> Slot {
        Slot {
            v: c(f64::NAN),
            init: c(0.0),
        }
    }
    fn same(&self, o: &Slot) -> bool {
        same(&self.v, &o.v) && same(&self.init, &o.init)
    }
}

/// `select` over slots: `cond` picks `a`, else `b`.
fn merge(cond: &Expr, a: &Slot, b: &Slot) -> Slot {
    Slot {
        v: pick(cond, &a.v, &b.v),
        init: pick(cond, &a.init, &b.init),
    }
}

/// A variable or one array element, as a branch records its writes.
#[derive(Clone, PartialEq, Eq, Hash)]
enum Key {
    Scalar(String),
    Elem(String, usize),
}

/// The writes of one branch of a point-dependent `if`: for each key, its
/// value before the branch first wrote it (`None`: a scalar not yet
/// defined). Undoing and merging a branch costs what the branch wrote, not
/// the size of the environment.
#[derive(Default)]
struct Frame {
    saved: Vec<(Key, Option<Slot>)>,
    seen: HashSet<Key>,
}

/// Variables of one activation. Arrays include `x`, `a` and `s`.
#[derive(Default)]
struct Env {
    scalars: HashMap<String, Slot>,
    arrays: HashMap<String, Vec<Slot>>,
    /// Branches of point-dependent `if`s being run, innermost last.
    frames: Vec<Frame>,
}

impl Env {
    fn get(&self, key: &Key) -> Option<Slot> {
        match key {
            Key::Scalar(n) => self.scalars.get(n).cloned(),
            Key::Elem(n, k) => self.arrays.get(n).and_then(|a| a.get(*k)).cloned(),
        }
    }

    /// Sets `key` without recording it.
    fn put(&mut self, key: &Key, slot: Option<Slot>) {
        match (key, slot) {
            (Key::Scalar(n), Some(s)) => {
                self.scalars.insert(n.clone(), s);
            }
            (Key::Scalar(n), None) => {
                self.scalars.remove(n);
            }
            (Key::Elem(n, k), Some(s)) => {
                if let Some(e) = self.arrays.get_mut(n).and_then(|a| a.get_mut(*k)) {
                    *e = s;
                }
            }
            (Key::Elem(..), None) => {}
        }
    }

    /// Records `old` as the value of `key` before the innermost open
    /// branch, unless that branch has written `key` already.
    fn note(&mut self, key: &Key, old: Option<Slot>) {
        if let Some(f) = self.frames.last_mut() {
            if f.seen.insert(key.clone()) {
                f.saved.push((key.clone(), old));
            }
        }
    }

    /// Writes `slot` to `key`, recording the old value in an open branch.
    fn write(&mut self, key: Key, slot: Slot) {
        if !self.frames.is_empty() {
            let old = self.get(&key);
            if old.as_ref().is_some_and(|o| o.same(&slot)) {
                return;
            }
            self.note(&key, old);
        }
        self.put(&key, Some(slot));
    }

    fn set_scalar(&mut self, name: &str, slot: Slot) {
        if self.frames.is_empty() {
            self.scalars.insert(name.to_string(), slot);
        } else {
            self.write(Key::Scalar(name.to_string()), slot);
        }
    }

    fn set_elem(&mut self, name: &str, k: usize, slot: Slot) {
        if self.frames.is_empty() {
            if let Some(e) = self.arrays.get_mut(name).and_then(|a| a.get_mut(k)) {
                *e = slot;
            }
        } else {
            self.write(Key::Elem(name.to_string(), k), slot);
        }
    }

    /// Replaces the contents of an existing array. Element by element when
    /// the length stays; a library call may write more or fewer elements
    /// than the array holds, which changes its length: not inside a
    /// point-dependent branch (the branches could disagree on it).
    fn set_array(&mut self, name: &str, vals: Vec<Slot>, pos: Pos) -> Result<(), Stop> {
        match self.arrays.get_mut(name) {
            None => Ok(()),
            Some(arr) if self.frames.is_empty() && arr.len() != vals.len() => {
                *arr = vals;
                Ok(())
            }
            Some(arr) if arr.len() != vals.len() => Err(needs_point(
                format!(
                    "a call changes the length of array '{name}' inside a point-dependent `if`"
                ),
                pos,
            )),
            Some(_) => {
                for (k, v) in vals.into_iter().enumerate() {
                    self.set_elem(name, k, v);
                }
                Ok(())
            }
        }
    }
}

/// Inputs of one run: coordinates and parameters as expressions.
pub struct Inputs {
    pub x: Vec<Expr>,
    pub a: Vec<Expr>,
}

pub struct Exec<'p> {
    program: &'p Program,
    registry: &'p Registry,
    table: &'p ErrorTable,
    /// Error code so far (0 = none).
    pub err: Expr,
    /// Every error site met, in evaluation order: (truth value of "this
    /// error is raised here", code). `err` is their first-wins fold. The
    /// code is a constant, or for a whole object call the callee's own
    /// error code.
    pub sites: Vec<(Expr, Expr)>,
    /// Call results replayed into `sites` so far, by guard and callee
    /// error code: the same pair again adds nothing (first wins).
    replayed: HashSet<(Part, Part)>,
    /// Truth value of "this statement runs" (inside point-dependent `if`s).
    guard: Expr,
    budget: u64,
    /// Select nodes left for merging branches ([`MERGE_BUDGET`]).
    merges: u64,
    /// Set when a loop ran out of iterations.
    pub limit_hit: bool,
    /// [`Expr::nodes_created`] when this run started.
    nodes_at_start: u64,
    /// Object calls already run, by callee, guard and argument values.
    calls: HashMap<CallKey, Called>,
    /// Run-time errors raised whenever their statement runs, whatever the
    /// point (a constant index out of range): bugs `check` reports.
    pub certain: Vec<(String, Pos)>,
}

/// One part of a call's identity: a node, or a constant by its bits
/// (constants built apart are equal; the per-point fallback makes every
/// value one).
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
enum Part {
    Node(*const microfrep_core::ExprNode),
    Const(u64),
}

fn part(e: &Expr) -> Part {
    match e.as_const() {
        Some(v) => Part::Const(v.to_bits()),
        None => Part::Node(e.node()),
    }
}

/// An object call: the callee and its arguments.
#[derive(Clone, PartialEq, Eq, Hash)]
struct CallKey {
    object: *const Object,
    args: Vec<Vec<Part>>,
}

/// What a call gave: its value, the callee's final `s` and its error code
/// wherever it is reached (0: none). It keeps the argument expressions
/// alive, so the node addresses in its key cannot be reused by other
/// nodes while the entry exists.
struct Called {
    value: Expr,
    s: Vec<Slot>,
    error: Expr,
    _args: Vec<Vec<Expr>>,
}

/// What running the evaluated object gives: its value and the final
/// contents of its attribute array `s`.
pub struct Outcome {
    pub value: Expr,
    pub s: Vec<Expr>,
}

impl<'p> Exec<'p> {
    pub fn new(program: &'p Program, registry: &'p Registry, table: &'p ErrorTable) -> Self {
        Self::with_budget(program, registry, table, LOOP_BUDGET)
    }

    /// An executor allowing `budget` loop iterations in all.
    pub fn with_budget(
        program: &'p Program,
        registry: &'p Registry,
        table: &'p ErrorTable,
        budget: u64,
    ) -> Self {
        Exec {
            program,
            registry,
            table,
            err: c(0.0),
            sites: Vec::new(),
            replayed: HashSet::new(),
            guard: c(1.0),
            budget,
            merges: MERGE_BUDGET,
            limit_hit: false,
            nodes_at_start: Expr::nodes_created(),
            calls: HashMap::new(),
            certain: Vec::new(),
        }
    }

    /// Refuses to go on once this run has built [`NODE_BUDGET`] nodes.
    fn check_size(&self, pos: Pos) -> Result<(), Stop> {
        let built = Expr::nodes_created().wrapping_sub(self.nodes_at_start);
        if built <= NODE_BUDGET {
            return Ok(());
        }
        Err(Stop::Static(
            format!(
                "the model grows past {NODE_BUDGET} expression nodes while it is built; objects that call other objects with different arguments, or \
                 loops around calls, multiply its size: reuse results in variables, or \
                 write the model with fewer nested calls"
            ),
            pos,
        ))
    }

    /// True once an error is certain: nothing after it matters.
    fn dead(&self) -> bool {
        is_true(&self.err)
    }

    fn fault(&mut self, cond: Expr, message: &str, pos: Pos) {
        let hit = self.guard.and(&cond);
        if hit.as_const() == Some(0.0) || self.dead() {
            return;
        }
        if cond.as_const().is_some_and(|v| v != 0.0) && !self.certain.iter().any(|c| c.1 == pos) {
            self.certain.push((message.to_string(), pos));
        }
        let code = self.table.code(RuntimeError {
            message: message.to_string(),
            line: pos.line,
            col: pos.col,
        });
        self.sites.push((hit.clone(), c(code)));
        let new = Expr::select(hit, c(code), c(0.0));
        self.err = Expr::select(self.err.clone(), self.err.clone(), new);
    }

    fn faults(&mut self, fs: Vec<Fault>, pos: Pos) {
        for (cond, msg) in fs {
            self.fault(cond, msg, pos);
        }
    }

    /// Runs object `obj` with the given inputs. Its attributes `s` start at
    /// 0 (the reference keeps them from the previous evaluation, which is
    /// 0 at the first one); they count as assigned.
    pub fn run(&mut self, obj: &'p Object, inputs: Inputs) -> Result<Outcome, Stop> {
        let mut env = Env::default();
        env.arrays.insert("x".into(), fit(inputs.x, obj.x_size));
        env.arrays.insert("a".into(), fit(inputs.a, obj.a_size));
        env.arrays
            .insert("s".into(), vec![Slot::set(c(0.0)); obj.s_size.max(1)]);
        let value = self.call_body(obj, &mut env)?;
        let s = env.arrays.remove("s").unwrap_or_default();
        Ok(Outcome {
            value,
            s: s.into_iter().map(|slot| slot.v).collect(),
        })
    }

    fn call_body(&mut self, obj: &'p Object, env: &mut Env) -> Result<Expr, Stop> {
        for d in &obj.arrays {
            env.arrays
                .insert(d.name.clone(), vec![Slot::unset(); d.size.max(1)]);
        }
        self.block(&obj.body, env)?;
        if self.dead() {
            return Ok(c(f64::NAN));
        }
        self.expr(&obj.result, env)
    }

    fn block(&mut self, stmts: &[Stmt], env: &mut Env) -> Result<(), Stop> {
        for s in stmts {
            if self.dead() {
                return Ok(());
            }
            self.stmt(s, env)?;
        }
        Ok(())
    }

    fn stmt(&mut self, s: &Stmt, env: &mut Env) -> Result<(), Stop> {
        self.check_size(stmt_pos(s))?;
        grow(|| self.stmt_inner(s, env))
    }

    fn stmt_inner(&mut self, s: &Stmt, env: &mut Env) -> Result<(), Stop> {
        match s {
            Stmt::Assign { name, value, .. } => {
                let v = self.expr(value, env)?;
                env.set_scalar(name, Slot::set(v));
            }
            Stmt::AssignIndex {
                name, index, value, ..
            } => {
                // Right to left: the value first, then the index.
                let v = self.expr(value, env)?;
                let i = self.expr(index, env)?;
                let i = ops::hf_round(&i);
                let n = env.arrays.get(name).map_or(0, Vec::len);
                self.fault(i.lt(1.0).or(i.gt(n as f64)), ops::INDEX_RANGE, index.pos);
                match i.as_const() {
                    Some(k) => {
                        if k >= 1.0 && k <= n as f64 {
                            env.set_elem(name, k as usize - 1, Slot::set(v));
                        }
                    }
                    None => {
                        let new = Slot::set(v);
                        for k in 0..n {
                            let old = env.arrays[name][k].clone();
                            let m = merge(&i.eq_((k + 1) as f64), &new, &old);
                            env.set_elem(name, k, m);
                        }
                    }
                }
            }
            Stmt::AssignArray { name, values, pos } => {
                let arr = values.iter().map(|&v| Slot::set(c(v))).collect();
                env.set_array(name, arr, *pos)?;
            }
            Stmt::If {
                cond,
                then_body,
                else_body,
                pos,
            } => {
                let t = self.cond(cond, env)?;
                match t.as_const() {
                    Some(v) if v != 0.0 => self.block(then_body, env)?,
                    Some(_) => self.block(else_body, env)?,
                    None => self.branch(&t, then_body, else_body, *pos, env)?,
                }
            }
            Stmt::While { cond, body, pos } => loop {
                let t = self.cond(cond, env)?;
                match t.as_const() {
                    None => {
                        return Err(needs_point(
                            "the condition of this loop depends on the point",
                            *pos,
                        ))
                    }
                    Some(0.0) => break,
                    Some(_) => {}
                }
                if self.budget == 0 {
                    self.limit_hit = true;
                    self.fault(c(1.0), ops::LOOP_LIMIT, *pos);
                    break;
                }
                self.budget -= 1;
                self.block(body, env)?;
                if self.dead() {
                    break;
                }
            },
        }
        Ok(())
    }

    /// Both branches of a point-dependent `if`, merged with `select`. Each
    /// branch runs under its condition (so its error sites count only
    /// where it is taken) on the state before the `if`, recording what it
    /// writes; every variable or element written by either branch then
    /// holds `select(t, then-value, else-value)`.
    fn branch(
        &mut self,
        t: &Expr,
        yes: &[Stmt],
        no: &[Stmt],
        pos: Pos,
        env: &mut Env,
    ) -> Result<(), Stop> {
        let outer = self.guard.clone();
        self.guard = outer.and(t);
        env.frames.push(Frame::default());
        let r = self.block(yes, env);
        let yes_frame = env.frames.pop().expect("pushed above");
        r?;
        // The then-values; back to the state before the `if`.
        let mut taken = Vec::with_capacity(yes_frame.saved.len());
        for (key, old) in yes_frame.saved {
            let now = env.get(&key);
            env.put(&key, old.clone());
            taken.push((key, old, now));
        }
        self.guard = outer.and(t.not());
        env.frames.push(Frame::default());
        let r = self.block(no, env);
        let no_frame = env.frames.pop().expect("pushed above");
        self.guard = outer;
        r?;
        let only_no = no_frame
            .saved
            .into_iter()
            .filter(|(key, _)| !yes_frame.seen.contains(key))
            .map(|(key, old)| (key, old.clone(), old));
        let all: Vec<_> = taken.into_iter().chain(only_no).collect();
        for (key, before, then_v) in all {
            let else_v = env.get(&key);
            let a = then_v.unwrap_or_else(Slot::unset);
            let b = else_v.unwrap_or_else(Slot::unset);
            let m = merge(t, &a, &b);
            let added = u64::from(!same(&m.v, &a.v)) + u64::from(!same(&m.init, &a.init));
            if added > self.merges {
                return Err(needs_point(
                    format!(
                        "merging the branches of point-dependent `if`s would add more than \
                         {MERGE_BUDGET} select nodes"
                    ),
                    pos,
                ));
            }
            self.merges -= added;
            // An enclosing branch learns the value from before this `if`.
            env.note(&key, before);
            env.put(&key, Some(m));
        }
        Ok(())
    }

    fn cond(&mut self, cond: &Cond, env: &mut Env) -> Result<Expr, Stop> {
        // `and`, `or` and comparisons chain to the left without limit
        // (`c1 and c2 and ...`): the chain is walked in a loop, right
        // operands first as the reference evaluates them.
        let (mut spine, mut rights) = (Vec::new(), Vec::new());
        let mut cur = cond;
        while let Cond::Cmp(_, a, b) | Cond::And(a, b) | Cond::Or(a, b) = cur {
            spine.push(cur);
            let right = match cur {
                Cond::Cmp(..) => self.cond_value(b, env)?,
                _ => self.cond(b, env)?,
            };
            rights.push(right);
            cur = a;
        }
        let mut acc = match (spine.last(), cur) {
            (_, Cond::Not(a)) => self.cond(a, env)?.not(),
            (Some(Cond::Cmp(..)), Cond::Value(e)) => self.expr(e, env)?,
            (_, Cond::Value(e)) => ops::truth(&self.expr(e, env)?),
            (_, Cond::Cmp(..) | Cond::And(..) | Cond::Or(..)) => unreachable!("walked above"),
        };
        for (node, b) in spine.iter().zip(rights).rev() {
            acc = match node {
                Cond::Cmp(op, ..) => {
                    let a = acc;
                    match op {
                        CmpOp::Lt => a.lt(b),
                        CmpOp::Gt => a.gt(b),
                        CmpOp::Le => a.le(b),
                        CmpOp::Ge => a.ge(b),
                        CmpOp::Eq => (a - b).abs().lt(EPS),
                        CmpOp::Ne => (a - b).abs().ge(EPS),
                    }
                }
                Cond::And(..) => acc.and(b),
                Cond::Or(..) => acc.or(b),
                Cond::Value(_) | Cond::Not(_) => unreachable!("spine nodes are binary"),
            };
        }
        Ok(acc)
    }

    /// A comparison operand: a plain value, or the 0/1 value of a condition.
    fn cond_value(&mut self, cond: &Cond, env: &mut Env) -> Result<Expr, Stop> {
        match cond {
            Cond::Value(e) => self.expr(e, env),
            other => self.cond(other, env),
        }
    }

    fn read_array(&mut self, name: &str, index: &Expr, pos: Pos, ipos: Pos, env: &mut Env) -> Expr {
        let Some(arr) = env.arrays.get(name) else {
            self.fault(c(1.0), ops::UNASSIGNED, pos);
            return c(f64::NAN);
        };
        let i = ops::hf_round(index);
        let n = arr.len() as f64;
        self.fault(i.lt(1.0).or(i.gt(n)), ops::INDEX_RANGE, ipos);
        let slot = match i.as_const() {
            Some(k) if k >= 1.0 && k <= n => arr[k as usize - 1].clone(),
            Some(_) => return c(f64::NAN),
            None => arr
                .iter()
                .enumerate()
                .rev()
                .fold(Slot::unset(), |acc, (k, s)| {
                    merge(&i.eq_((k + 1) as f64), s, &acc)
                }),
        };
        self.fault(slot.init.not(), ops::UNASSIGNED, pos);
        slot.v
    }

    fn expr(&mut self, e: &ast::Expr, env: &mut Env) -> Result<Expr, Stop> {
        self.check_size(e.pos)?;
        grow(|| self.expr_inner(e, env))
    }

    fn expr_inner(&mut self, e: &ast::Expr, env: &mut Env) -> Result<Expr, Stop> {
        // Operators chain to the left without limit (a generated union of
        // 100k spheres): the chain is walked in a loop, right operands
        // first (top down) as the reference evaluates them, then the
        // leftmost operand, then the operators bottom up. Everything else
        // nests only as deep as the parser allows.
        let (mut spine, mut rights) = (Vec::new(), Vec::new());
        let mut cur = e;
        while let ExprKind::Binary(op, a, b) = &cur.kind {
            spine.push((*op, cur.pos));
            rights.push(self.expr(b, env)?);
            cur = a;
        }
        let mut acc = self.operand(cur, env)?;
        for ((op, pos), b) in spine.into_iter().zip(rights).rev() {
            acc = self.binary(op, acc, b, pos);
        }
        Ok(acc)
    }

    fn binary(&mut self, op: BinOp, a: Expr, b: Expr, pos: Pos) -> Expr {
        match op {
            BinOp::Add => a + b,
            BinOp::Sub => a - b,
            BinOp::Mul => a * b,
            BinOp::Div => {
                let (v, f) = ops::div(&a, &b);
                self.faults(f, pos);
                v
            }
            BinOp::Pow => {
                let (v, f) = ops::pow(&a, &b);
                self.faults(f, pos);
                v
            }
            BinOp::Union => ops::union(&a, &b),
            BinOp::Intersection | BinOp::Product => ops::intersection(&a, &b),
            BinOp::Subtraction => ops::subtraction(&a, &b),
        }
    }

    /// An expression that is not a binary operation.
    fn operand(&mut self, e: &ast::Expr, env: &mut Env) -> Result<Expr, Stop> {
        let pos = e.pos;
        Ok(match &e.kind {
            ExprKind::Num(v) => c(*v),
            ExprKind::Var(name) => match env.scalars.get(name) {
                Some(s) => {
                    self.fault(s.init.not(), ops::NOT_INIT, pos);
                    s.v.clone()
                }
                None => {
                    self.fault(c(1.0), ops::NOT_INIT, pos);
                    c(f64::NAN)
                }
            },
            ExprKind::Index(name, index) => {
                let i = self.expr(index, env)?;
                self.read_array(name, &i, pos, index.pos, env)
            }
            ExprKind::Unary(op, a) => {
                let a = self.expr(a, env)?;
                match op {
                    UnOp::Plus => a,
                    UnOp::Neg | UnOp::Complement => -a,
                }
            }
            ExprKind::Binary(..) => return self.expr(e, env),
            ExprKind::Call(name, args) => return self.call(name, args, pos, env),
        })
    }

    fn call(
        &mut self,
        name: &str,
        args: &[ast::Expr],
        pos: Pos,
        env: &mut Env,
    ) -> Result<Expr, Stop> {
        if let Some(obj) = self.program.objects.iter().find(|o| o.name == name) {
            return self.call_object(obj, args, pos, env);
        }
        if let Some(f) = self.registry.get(name) {
            let f = f.clone();
            if args.len() != f.kinds.len() {
                let msg = format!("{name} takes {} arguments", f.kinds.len());
                return Err(Stop::Static(msg, pos));
            }
            // Last argument first, as the reference evaluates them.
            let mut vals = vec![Arg::Real(c(0.0)); args.len()];
            for (k, a) in args.iter().enumerate().rev() {
                vals[k] = match (f.kinds.get(k), &a.kind) {
                    (Some(Kind::A), ExprKind::Var(n)) => Arg::Array(self.array_arg(n, a.pos, env)),
                    _ => Arg::Real(self.expr(a, env)?),
                };
            }
            let out = (f.build)(&vals);
            if out.needs_constants {
                let shown = crate::library::shapes::display_name(name);
                return Err(needs_point(
                    format!("{shown} needs a constant argument that depends on the point"),
                    pos,
                ));
            }
            if let Some(m) = out.error {
                let shown = crate::library::shapes::display_name(name);
                return Err(Stop::Static(format!("{shown}: {m}"), pos));
            }
            for (k, v) in out.writes {
                if let ExprKind::Var(n) = &args[k].kind {
                    env.set_array(n, v.into_iter().map(Slot::set).collect(), pos)?;
                }
            }
            return Ok(out.value);
        }
        let mut vals = vec![c(0.0); args.len()];
        for (k, a) in args.iter().enumerate().rev() {
            vals[k] = self.expr(a, env)?;
        }
        match ops::builtin(name, &vals) {
            Some((v, f)) => {
                self.faults(f, pos);
                Ok(v)
            }
            None => Err(Stop::Static(format!("unknown function '{name}'"), pos)),
        }
    }

    /// An array passed by reference: its current values; every element must
    /// hold one.
    fn array_arg(&mut self, name: &str, pos: Pos, env: &mut Env) -> Vec<Expr> {
        let Some(arr) = env.arrays.get(name) else {
            self.fault(c(1.0), ops::UNASSIGNED, pos);
            return Vec::new();
        };
        let all = arr.iter().fold(c(1.0), |acc, s| acc.and(&s.init));
        let vals = arr.iter().map(|s| s.v.clone()).collect();
        self.fault(all.not(), ops::ARRAY_UNASSIGNED, pos);
        vals
    }

    /// A call of an earlier object: it runs on copies of `x` and `a`; its `s`
    /// is copied back into the caller's third argument.
    fn call_object(
        &mut self,
        obj: &'p Object,
        args: &[ast::Expr],
        pos: Pos,
        env: &mut Env,
    ) -> Result<Expr, Stop> {
        let sizes = [obj.x_size, obj.a_size, obj.s_size.max(1)];
        if !(2..=3).contains(&args.len()) {
            return Err(Stop::Static("Wrong number of items in array".into(), pos));
        }
        let mut names = Vec::new();
        for (k, a) in args.iter().enumerate() {
            let ExprKind::Var(n) = &a.kind else {
                return Err(Stop::Static("array name expected".into(), a.pos));
            };
            let len = env.arrays.get(n).map_or(0, Vec::len);
            if len != sizes[k.min(2)] {
                return Err(Stop::Static("Wrong number of items in array".into(), a.pos));
            }
            names.push(n.clone());
        }
        if names.len() == 2 && sizes[2] != 1 {
            return Err(Stop::Static("Wrong number of items in array".into(), pos));
        }
        let mut vals = vec![Vec::new(); names.len()];
        for (k, n) in names.iter().enumerate().rev() {
            vals[k] = self.array_arg(n, args[k].pos, env);
        }
        // A call with the same callee and argument values as an earlier
        // one gives the same value, `s` and error code, so its result is
        // shared: the graph stays a DAG instead of copying the callee once
        // per call path (18 objects each calling the one before twice were
        // 2^18 copies). For that the callee runs unguarded, collecting its
        // own error sites; its error code then joins this run's sites as
        // one site under the guard of each call. Not once an error is
        // certain: the callee then stops early.
        if self.dead() {
            let (value, s) = self.call_fresh(obj, vals)?;
            if let Some(sname) = names.get(2) {
                env.set_array(sname, s, pos)?;
            }
            return Ok(value);
        }
        let key = CallKey {
            object: obj,
            args: vals.iter().map(|a| a.iter().map(part).collect()).collect(),
        };
        if !self.calls.contains_key(&key) {
            let outer = (
                std::mem::take(&mut self.sites),
                std::mem::take(&mut self.replayed),
                std::mem::replace(&mut self.err, c(0.0)),
                std::mem::replace(&mut self.guard, c(1.0)),
            );
            let run = self.call_fresh(obj, vals.clone());
            let own = std::mem::replace(&mut self.sites, outer.0);
            (self.replayed, self.err, self.guard) = (outer.1, outer.2, outer.3);
            let (value, s) = run?;
            let error = super::prune::error_code(&own);
            let done = Called {
                value,
                s,
                error,
                _args: vals,
            };
            self.calls.insert(key.clone(), done);
        }
        let done = &self.calls[&key];
        let (value, s, error) = (done.value.clone(), done.s.clone(), done.error.clone());
        self.raise_from_call(error);
        if let Some(sname) = names.get(2) {
            env.set_array(sname, s, pos)?;
        }
        Ok(value)
    }

    /// Records the error code `code` of an object call (0 where the callee
    /// raises nothing) as a site under the current guard.
    fn raise_from_call(&mut self, code: Expr) {
        if code.as_const() == Some(0.0) || self.dead() {
            return;
        }
        if !self.replayed.insert((part(&self.guard), part(&code))) {
            return;
        }
        let hit = if is_true(&self.guard) {
            code.ne_(0.0)
        } else {
            self.guard.and(&code)
        };
        let new = Expr::select(hit.clone(), code.clone(), c(0.0));
        self.sites.push((hit, code));
        self.err = Expr::select(self.err.clone(), self.err.clone(), new);
    }

    /// Runs the body of `obj` on the argument values `vals` (`x`, `a` and
    /// maybe `s`): its value and final `s`.
    fn call_fresh(
        &mut self,
        obj: &'p Object,
        vals: Vec<Vec<Expr>>,
    ) -> Result<(Expr, Vec<Slot>), Stop> {
        let mut callee = Env::default();
        let roles = ["x", "a", "s"];
        for (k, v) in vals.into_iter().enumerate() {
            callee
                .arrays
                .insert(roles[k].into(), v.into_iter().map(Slot::set).collect());
        }
        callee
            .arrays
            .entry("s".into())
            .or_insert_with(|| vec![Slot::set(c(0.0))]);
        let v = self.call_body(obj, &mut callee)?;
        let s = callee.arrays.remove("s").unwrap_or_default();
        Ok((v, s))
    }
}

/// Runs `f` with at least [`RED_ZONE`] bytes of stack, moving to a fresh
/// segment on the heap when the current one runs low: nesting through
/// calls and objects has no fixed bound, and the per-point fallback runs
/// on whatever thread evaluates the model.
pub(crate) fn grow<R>(f: impl FnOnce() -> R) -> R {
    stacker::maybe_grow(RED_ZONE, STACK_SEGMENT, f)
}

/// Stack left before a recursive step moves to a new segment.
const RED_ZONE: usize = 128 * 1024;
/// Size of each new stack segment.
const STACK_SEGMENT: usize = 2 * 1024 * 1024;

/// Coordinates or parameters padded (or cut) to the declared size.
fn fit(v: Vec<Expr>, n: usize) -> Vec<Slot> {
    let mut s: Vec<Slot> = v.into_iter().take(n).map(Slot::set).collect();
    s.resize(n.max(1), Slot::set(c(0.0)));
    s
}

/// Where a statement starts.
fn stmt_pos(s: &Stmt) -> Pos {
    match s {
        Stmt::Assign { pos, .. }
        | Stmt::AssignIndex { pos, .. }
        | Stmt::AssignArray { pos, .. }
        | Stmt::If { pos, .. }
        | Stmt::While { pos, .. } => *pos,
    }
}
