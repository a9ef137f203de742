//! Writes a core expression as a HyperFun object.
//!
//! Shared subexpressions become local variables `t1, t2, ...`; so do operands
//! needed twice by a rewrite and every comparison operand (a condition
//! operand starting with `(` would open a condition, SPEC section 5). Core
//! operations without a HyperFun equivalent are rewritten: `sign`, `round`
//! and logic via `if` on a temporary, `fract`/`tri`/`saw`/`mod`/`rem` via
//! `floor`/`int`, `powi` by repeated multiplication. Division by a constant
//! becomes multiplication by its reciprocal (HyperFun rejects `|b| < 1e-6`
//! at run time). Parameters become `a[1], a[2], ...` in order of first use.
//! HyperFun still differs where the core gives NaN (`sqrt`, `log` of a
//! negative) or divides by a small non-constant: it reports an error there.

use microfrep_core::{BinaryOp, Expr, ExprNode, Field, SetOp, UnaryOp};
use std::collections::HashMap;
use std::fmt::Write;
use std::sync::Arc;

/// Deeper text is moved into a temporary, keeping the parser's nesting low.
const MAX_TEXT_DEPTH: usize = 24;
/// Subtrees this tall are written into temporaries bottom up before the
/// (recursive) writer runs, so its recursion stays this shallow however
/// long the expression's chains are.
const MAX_TREE_DEPTH: usize = 32;

/// The object `name(x[3], a[n]) { ... }` computing `expr`. An expression
/// that cannot be written (a data-driven field, a bad object name) gives a
/// comment that explains why and does not parse.
pub fn to_hyperfun(expr: &Expr, object_name: &str) -> String {
    try_to_hyperfun(expr, object_name)
        .unwrap_or_else(|e| format!("-- cannot write HyperFun: {e}\n"))
}

/// As [`to_hyperfun`], with an error for what HyperFun cannot express.
pub fn try_to_hyperfun(expr: &Expr, object_name: &str) -> Result<String, String> {
    try_to_hyperfun_with(expr, object_name, &|_, _| None)
}

/// How a data field is written in HyperFun: a call `name(args)` of a
/// function the reader of the file binds (a `--field NAME=FILE` part) or of
/// the library (a structure rebuilt from its parameters).
#[derive(Clone, Debug)]
pub struct FieldCall {
    /// The function's name.
    pub name: String,
    /// Its arguments, in order.
    pub args: Vec<FieldArg>,
}

/// An argument of a [`FieldCall`].
#[derive(Clone, Debug)]
pub enum FieldArg {
    /// The point the field is sampled at (`x`, or a local array of the
    /// mapped coordinates).
    Point,
    /// A scalar expression.
    Expr(Expr),
    /// An array of constants (a local array assigned whole).
    Array(Vec<f64>),
}

/// Names the data fields of an expression: `(field, component)` to its
/// call, `None` where the field has no HyperFun form.
pub type FieldNames<'a> = dyn Fn(&Arc<dyn Field>, u8) -> Option<FieldCall> + 'a;

/// As [`try_to_hyperfun`], writing data fields as the calls `fields`
/// gives them.
pub fn try_to_hyperfun_with(
    expr: &Expr,
    object_name: &str,
    fields: &FieldNames<'_>,
) -> Result<String, String> {
    let name = object_name.to_ascii_lowercase();
    let valid = name.starts_with(|c: char| c.is_ascii_alphabetic())
        && name.len() <= 255
        && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
    if !valid || crate::parse(&format!("{name}(x[1], a[1]) {{ {name} = 0; }}"), "").is_err() {
        return Err(format!("'{object_name}' is not a usable object name"));
    }
    let mut p = Printer {
        fields: Some(fields),
        ..Printer::default()
    };
    p.count(expr);
    p.name_deep(expr)?;
    let (root, _) = p.emit(expr)?;
    let mut out = String::new();
    for (k, (pname, default)) in p.params.iter().enumerate() {
        let _ = writeln!(out, "-- a[{}]: {pname} (default {default})", k + 1);
    }
    let _ = writeln!(out, "{name}(x[3], a[{}]) {{", p.params.len().max(1));
    if !p.arrays.is_empty() {
        let _ = writeln!(out, "  array {};", p.arrays.join(", "));
    }
    for line in &p.lines {
        let _ = writeln!(out, "  {line}");
    }
    let _ = writeln!(out, "  {name} = {root};\n}}");
    Ok(out)
}

type Key = *const ExprNode;

#[derive(Default)]
struct Printer<'a> {
    uses: HashMap<Key, usize>,
    names: HashMap<Key, String>,
    params: Vec<(String, f64)>,
    lines: Vec<String>,
    temps: usize,
    /// Local array declarations (`p1[3]`), written first.
    arrays: Vec<String>,
    fields: Option<&'a FieldNames<'a>>,
}

/// Emitted text and its parenthesis depth.
type Text = (String, usize);

fn key(e: &Expr) -> Key {
    e.node() as Key
}

fn is_leaf(e: &Expr) -> bool {
    matches!(
        e.node(),
        ExprNode::Var(_) | ExprNode::Const(_) | ExprNode::Param { .. }
    )
}

/// A HyperFun literal: no sign, no exponent starting with 0.
fn number(c: f64) -> String {
    if c.is_nan() {
        return "(0 * (1e300 * 1e300))".into();
    }
    if c.is_infinite() {
        return if c > 0.0 {
            "(1e300 * 1e300)"
        } else {
            "(-(1e300 * 1e300))"
        }
        .into();
    }
    let a = c.abs();
    let text = if a != 0.0 && !(1e-5..1e16).contains(&a) {
        format!("{a:e}")
    } else {
        format!("{a}")
    };
    if c.is_sign_negative() && c != 0.0 {
        format!("(-{text})")
    } else {
        text
    }
}

impl Printer<'_> {
    /// Counts the parents of every node (each shared node once).
    fn count(&mut self, root: &Expr) {
        let mut stack = vec![root];
        while let Some(e) = stack.pop() {
            let n = self.uses.entry(key(e)).or_insert(0);
            *n += 1;
            if *n == 1 {
                stack.extend(e.children());
            }
        }
    }

    /// Names every node whose subtree, counting named nodes as leaves, is
    /// [`MAX_TREE_DEPTH`] tall, in post order (iteratively).
    fn name_deep(&mut self, root: &Expr) -> Result<(), String> {
        let mut height: HashMap<Key, usize> = HashMap::new();
        let mut stack = vec![(root, false)];
        while let Some((e, expanded)) = stack.pop() {
            if height.contains_key(&key(e)) {
                continue;
            }
            if !expanded {
                stack.push((e, true));
                for c in e.children() {
                    if !height.contains_key(&key(c)) {
                        stack.push((c, false));
                    }
                }
                continue;
            }
            let below = e.children().iter().map(|c| height[&key(c)]).max();
            let mut h = below.map_or(0, |b| b + 1);
            if h >= MAX_TREE_DEPTH {
                self.name(e)?;
                h = 0;
            }
            height.insert(key(e), h);
        }
        Ok(())
    }

    /// Writes `e` now and refers to it by a temporary from then on.
    fn name(&mut self, e: &Expr) -> Result<(), String> {
        let (text, depth) = self.emit(e)?;
        if !self.names.contains_key(&key(e)) && !is_leaf(e) {
            let name = if depth == 0 && text.starts_with('t') {
                text
            } else {
                self.temp(text)
            };
            self.names.insert(key(e), name);
        }
        Ok(())
    }

    fn temp(&mut self, text: String) -> String {
        self.temps += 1;
        let name = format!("t{}", self.temps);
        self.lines.push(format!("{name} = {text};"));
        name
    }

    /// `e` as a variable or leaf, for operands used more than once.
    fn atom(&mut self, e: &Expr) -> Result<String, String> {
        let (t, _) = self.emit(e)?;
        let simple = is_leaf(e) || self.names.contains_key(&key(e));
        Ok(if simple { t } else { self.temp(t) })
    }

    /// A 0/1 temporary: `t = 0; if cond then t = 1; endif;`.
    fn flag(&mut self, cond: String) -> String {
        let t = self.temp("0".into());
        self.lines.push(format!("if {cond} then {t} = 1; endif;"));
        t
    }

    fn nonzero(v: &str) -> String {
        format!("({v} < 0 or {v} > 0)")
    }

    fn emit(&mut self, e: &Expr) -> Result<Text, String> {
        if let Some(n) = self.names.get(&key(e)) {
            return Ok((n.clone(), 0));
        }
        let (text, depth) = self.emit_node(e)?;
        let shared = self.uses.get(&key(e)).copied().unwrap_or(0) > 1 && !is_leaf(e);
        if shared || depth > MAX_TEXT_DEPTH {
            // Rewrites that end in a temporary are already named.
            let name = if depth == 0 && text.starts_with('t') {
                text
            } else {
                self.temp(text)
            };
            self.names.insert(key(e), name.clone());
            return Ok((name, 0));
        }
        Ok((text, depth))
    }

    fn call(&mut self, f: &str, args: &[&Expr]) -> Result<Text, String> {
        let mut texts = Vec::new();
        let mut depth = 0;
        for a in args {
            let (t, d) = self.emit(a)?;
            texts.push(t);
            depth = depth.max(d + 1);
        }
        Ok((format!("{f}({})", texts.join(", ")), depth))
    }

    /// A local array `pN[n]`, declared at the top of the object.
    fn array(&mut self, n: usize) -> String {
        let name = format!("p{}", self.arrays.len() + 1);
        self.arrays.push(format!("{name}[{n}]"));
        name
    }

    fn field_call(&mut self, call: &FieldCall, at: &[Expr; 3]) -> Result<Text, String> {
        let mut texts = Vec::new();
        let mut depth = 0;
        for a in &call.args {
            texts.push(match a {
                FieldArg::Point => {
                    let identity = at
                        .iter()
                        .enumerate()
                        .all(|(i, e)| matches!(e.node(), ExprNode::Var(v) if *v as usize == i));
                    if identity {
                        "x".to_string()
                    } else {
                        let mut coords = Vec::new();
                        for e in at {
                            coords.push(self.emit(e)?.0);
                        }
                        let p = self.array(3);
                        for (i, c) in coords.iter().enumerate() {
                            self.lines.push(format!("{p}[{}] = {c};", i + 1));
                        }
                        p
                    }
                }
                FieldArg::Expr(e) => {
                    let (t, d) = self.emit(e)?;
                    depth = depth.max(d + 1);
                    t
                }
                FieldArg::Array(v) => {
                    let p = self.array(v.len().max(1));
                    let lits: Vec<String> = v
                        .iter()
                        .map(|&c| {
                            // Whole-array assignment takes signed literals only.
                            if !c.is_finite() {
                                "0".to_string()
                            } else if c < 0.0 {
                                format!("-{}", number(-c))
                            } else {
                                number(c)
                            }
                        })
                        .collect();
                    self.lines.push(format!("{p} = [{}];", lits.join(", ")));
                    p
                }
            });
        }
        // A call is a temporary: its text may not be nested arbitrarily
        // (array arguments must be names, and the call may be costly).
        let _ = depth;
        let t = self.temp(format!("{}({})", call.name, texts.join(", ")));
        Ok((t, 0))
    }

    fn bin(&mut self, a: &Expr, op: &str, b: &Expr) -> Result<Text, String> {
        let (ta, da) = self.emit(a)?;
        let (tb, db) = self.emit(b)?;
        Ok((format!("({ta} {op} {tb})"), da.max(db) + 1))
    }

    fn emit_node(&mut self, e: &Expr) -> Result<Text, String> {
        Ok(match e.node() {
            ExprNode::Var(axis) => (format!("x[{}]", *axis as usize + 1), 0),
            ExprNode::Const(c) => (number(*c), 1),
            ExprNode::Param { name, default } => {
                let k = match self.params.iter().position(|(n, _)| **n == **name) {
                    Some(k) => k,
                    None => {
                        self.params.push((name.to_string(), *default));
                        self.params.len() - 1
                    }
                };
                (format!("a[{}]", k + 1), 0)
            }
            ExprNode::Unary(op, a) => self.unary(*op, a)?,
            ExprNode::Binary(op, a, b) => self.binary(*op, a, b)?,
            ExprNode::PowI(a, n) => {
                if *n == 0 {
                    return Ok(("1".into(), 0));
                }
                let v = self.atom(a)?;
                if n.unsigned_abs() > 16 {
                    (format!("({v} ^ {})", number(f64::from(*n))), 2)
                } else {
                    let prod = vec![v; n.unsigned_abs() as usize].join(" * ");
                    if *n < 0 {
                        (format!("(1 / ({prod}))"), 2)
                    } else {
                        (format!("({prod})"), 1)
                    }
                }
            }
            ExprNode::Select(c, a, b) => {
                let c = self.atom(c)?;
                let (ta, _) = self.emit(a)?;
                let (tb, _) = self.emit(b)?;
                let t = self.temp(tb);
                self.lines
                    .push(format!("if {} then {t} = {ta}; endif;", Self::nonzero(&c)));
                (t, 0)
            }
            ExprNode::Set { op, a, b, alpha } if alpha.as_const() == Some(0.0) => {
                let sym = if *op == SetOp::Union { "|" } else { "&" };
                self.bin(a, sym, b)?
            }
            ExprNode::Blend { op, args } if args[2].as_const() == Some(0.0) => {
                let f = if *op == SetOp::Union {
                    "hfBlendUni"
                } else {
                    "hfBlendInt"
                };
                let [a, b, _, a0, a1, a2] = &**args;
                self.call(f, &[a, b, a0, a1, a2])?
            }
            // Other parameters have no HyperFun operator: the formula.
            ExprNode::Set { .. } | ExprNode::Blend { .. } => self.emit(&e.expand())?,
            ExprNode::Field { field, comp, args } => {
                let call = self.fields.and_then(|f| f(field, *comp)).ok_or_else(|| {
                    format!("data-driven field '{}' has no HyperFun form", field.name())
                })?;
                self.field_call(&call, args)?
            }
        })
    }

    fn unary(&mut self, op: UnaryOp, a: &Expr) -> Result<Text, String> {
        use UnaryOp::*;
        let f = match op {
            Abs => "abs",
            Sqrt => "sqrt",
            Exp => "exp",
            Ln => "log",
            Sin => "sin",
            Cos => "cos",
            Tan => "tan",
            Asin => "asin",
            Acos => "acos",
            Atan => "atan",
            Sinh => "sinh",
            Cosh => "cosh",
            Tanh => "tanh",
            Floor => "floor",
            Ceil => "ceil",
            Trunc => "int",
            Neg => {
                let (t, d) = self.emit(a)?;
                return Ok((format!("(-{t})"), d + 1));
            }
            Square => {
                let v = self.atom(a)?;
                return Ok((format!("({v} * {v})"), 1));
            }
            // HyperFun's own `sign` always returns 1.
            Sign => {
                let v = self.atom(a)?;
                let t = self.temp("0".into());
                self.lines.push(format!("if {v} > 0 then {t} = 1; endif;"));
                self.lines.push(format!("if {v} < 0 then {t} = -1; endif;"));
                return Ok((t, 0));
            }
            // Half away from zero.
            Round => {
                let v = self.atom(a)?;
                let t = self.temp(format!("floor(abs({v}) + 0.5)"));
                self.lines
                    .push(format!("if {v} < 0 then {t} = -{t}; endif;"));
                return Ok((t, 0));
            }
            Fract => {
                let v = self.atom(a)?;
                return Ok((format!("({v} - floor({v}))"), 2));
            }
            Tri => {
                let v = self.atom(a)?;
                let s = self.temp(format!("0.5 * {v} + 0.25"));
                return Ok((format!("(1 - abs(2 * ({s} - floor({s})) - 1))"), 3));
            }
            Saw => {
                let v = self.atom(a)?;
                return Ok((format!("(0.5 + {v} - floor({v} + 0.5))"), 2));
            }
            Not => {
                let v = self.atom(a)?;
                return Ok((self.flag(format!("{v} >= 0 and {v} <= 0")), 0));
            }
        };
        self.call(f, &[a])
    }

    fn binary(&mut self, op: BinaryOp, a: &Expr, b: &Expr) -> Result<Text, String> {
        use BinaryOp::*;
        let cmp = |p: &mut Self, op: &str| -> Result<Text, String> {
            let (va, vb) = (p.atom(a)?, p.atom(b)?);
            Ok((p.flag(format!("{va} {op} {vb}")), 0))
        };
        Ok(match op {
            Add => self.bin(a, "+", b)?,
            Sub => self.bin(a, "-", b)?,
            Mul => self.bin(a, "*", b)?,
            Div => match b.as_const() {
                Some(c) if c != 0.0 => {
                    let (t, d) = self.emit(a)?;
                    (format!("({t} * {})", number(1.0 / c)), d + 1)
                }
                _ => self.bin(a, "/", b)?,
            },
            Pow => self.bin(a, "^", b)?,
            Atan2 => self.call("atan2", &[a, b])?,
            Min => self.call("min", &[a, b])?,
            Max => self.call("max", &[a, b])?,
            // a - b*floor(a/b) and a - b*int(a/b).
            Mod | Rem => {
                let (va, vb) = (self.atom(a)?, self.atom(b)?);
                let f = if op == Mod { "floor" } else { "int" };
                let q = match b.as_const() {
                    Some(c) if c != 0.0 => format!("{va} * {}", number(1.0 / c)),
                    _ => format!("{va} / {vb}"),
                };
                (format!("({va} - {vb} * {f}({q}))"), 2)
            }
            Lt => cmp(self, "<")?,
            Le => cmp(self, "<=")?,
            Gt => cmp(self, ">")?,
            Ge => cmp(self, ">=")?,
            Eq => {
                let (va, vb) = (self.atom(a)?, self.atom(b)?);
                (self.flag(format!("{va} <= {vb} and {va} >= {vb}")), 0)
            }
            // HyperFun's `=` and `/=` compare within 1e-6; the core's are exact.
            Ne => {
                let (va, vb) = (self.atom(a)?, self.atom(b)?);
                (self.flag(format!("{va} < {vb} or {va} > {vb}")), 0)
            }
            And | Or => {
                let (va, vb) = (self.atom(a)?, self.atom(b)?);
                let word = if op == And { "and" } else { "or" };
                let c = format!("{} {word} {}", Self::nonzero(&va), Self::nonzero(&vb));
                (self.flag(c), 0)
            }
        })
    }
}
