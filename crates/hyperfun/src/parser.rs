//! Recursive-descent parser for the grammar of SPEC sections 2-5 and 9, with
//! the reference interpreter's error texts and positions. Errors are
//! collected: a bad statement is skipped up to its `;` and parsing goes on.

use crate::ast::*;
use crate::diag::{Diagnostic, Severity};
use crate::lexer::{Tok, Token};
use std::collections::HashSet;

/// Kind of a function parameter: any expression, or a bare array name
/// passed by reference.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ParamKind {
    /// Any expression.
    Real,
    /// A bare array name.
    Array,
}

/// Decides which names are functions (built-in or library) and their
/// parameters; every such name is reserved.
pub type FunctionTable<'a> = &'a dyn Fn(&str) -> Option<Vec<ParamKind>>;

const KEYWORDS: [&str; 12] = [
    "array", "if", "then", "else", "endif", "while", "loop", "endloop", "and", "or", "not", "xor",
];
/// Deeper nesting of expressions (parentheses, calls, unary operators,
/// indices) is refused rather than risking the stack.
pub const MAX_DEPTH: usize = 200;
/// Deeper nesting of `if` and `while` statements is refused likewise.
pub const MAX_STMT_DEPTH: usize = 100;
/// Arrays larger than this are refused rather than allocated.
const MAX_ARRAY: f64 = 1e6;

/// The reference's rounding for sizes and indices: half up.
pub fn hf_round(d: f64) -> f64 {
    let c = d.ceil();
    if c - d > 0.5 {
        c - 1.0
    } else {
        c
    }
}

/// Marker that an error was recorded; the caller recovers.
struct Failed;
type PResult<T> = Result<T, Failed>;

struct Callee {
    name: String,
    /// x, a, s sizes; None when the header itself was broken.
    sizes: Option<[usize; 3]>,
}

pub struct Parser<'a> {
    toks: Vec<Token>,
    i: usize,
    funcs: FunctionTable<'a>,
    pub diags: Vec<Diagnostic>,
    objects: Vec<Callee>,
    /// Current object: its name, arrays (x, a, s first) and assigned scalars.
    name: String,
    arrays: Vec<(String, usize)>,
    scalars: HashSet<String>,
    depth: usize,
    /// Nesting of `if` and `while` statements.
    stmt_depth: usize,
    /// Open `if`/`while` statements, for recovery.
    nesting: usize,
}

impl<'a> Parser<'a> {
    pub fn new(toks: Vec<Token>, funcs: FunctionTable<'a>, diags: Vec<Diagnostic>) -> Self {
        Parser {
            toks,
            i: 0,
            funcs,
            diags,
            objects: Vec::new(),
            name: String::new(),
            arrays: Vec::new(),
            scalars: HashSet::new(),
            depth: 0,
            stmt_depth: 0,
            nesting: 0,
        }
    }

    fn tok(&self) -> &Tok {
        &self.toks[self.i].tok
    }

    fn pos(&self) -> Pos {
        self.toks[self.i].pos
    }

    fn bump(&mut self) {
        if self.i + 1 < self.toks.len() {
            self.i += 1;
        }
    }

    fn at(&self, p: &str) -> bool {
        matches!(self.tok(), Tok::P(q) if *q == p)
    }

    fn at_kw(&self, k: &str) -> bool {
        matches!(self.tok(), Tok::Id(n) if n == k)
    }

    fn eof(&self) -> bool {
        *self.tok() == Tok::Eof
    }

    fn error_at(&mut self, pos: Pos, message: &str) {
        // One message per position: recovery may stop twice at the same token.
        if self
            .diags
            .last()
            .is_some_and(|d| d.pos == pos && d.severity == Severity::Error)
        {
            return;
        }
        self.diags.push(Diagnostic {
            severity: Severity::Error,
            pos,
            message: message.into(),
        });
    }

    fn fail<T>(&mut self, message: &str) -> PResult<T> {
        self.error_at(self.pos(), message);
        Err(Failed)
    }

    fn expect(&mut self, p: &str, message: &str) -> PResult<()> {
        if self.at(p) {
            self.bump();
            Ok(())
        } else {
            self.fail(message)
        }
    }

    fn expect_kw(&mut self, k: &str, message: &str) -> PResult<()> {
        if self.at_kw(k) {
            self.bump();
            Ok(())
        } else {
            self.fail(message)
        }
    }

    fn is_function(&self, n: &str) -> bool {
        (self.funcs)(n).is_some()
    }

    fn object_index(&self, n: &str) -> Option<usize> {
        self.objects.iter().position(|o| o.name == n)
    }

    /// A name that no keyword, reserved letter or function claims.
    fn free_name(&self, n: &str) -> bool {
        !KEYWORDS.contains(&n) && !["x", "a", "s"].contains(&n) && !self.is_function(n)
    }

    fn array_size(&self, n: &str) -> Option<usize> {
        self.arrays.iter().find(|(a, _)| a == n).map(|a| a.1)
    }

    /// Skips to just after the `;` ending the current statement (counting
    /// the `if`/`while` already open in it), or to a `}` / end of file.
    /// Scalars assigned in the skipped text count as declared, so that
    /// their later uses do not add errors.
    fn recover(&mut self, mut open: usize) {
        loop {
            if let (Tok::Id(n), Some(Tok::P("="))) =
                (self.tok(), self.toks.get(self.i + 1).map(|t| &t.tok))
            {
                if self.free_name(n) && *n != self.name && self.array_size(n).is_none() {
                    self.scalars.insert(n.clone());
                }
            }
            match self.tok() {
                Tok::Eof => return,
                Tok::P("}") => return,
                Tok::P(";") => {
                    self.bump();
                    if open == 0 {
                        return;
                    }
                }
                Tok::Id(n) if n == "if" || n == "while" => {
                    open += 1;
                    self.bump()
                }
                Tok::Id(n) if n == "endif" || n == "endloop" => {
                    open = open.saturating_sub(1);
                    self.bump()
                }
                _ => self.bump(),
            }
        }
    }

    pub fn program(&mut self) -> Program {
        let mut objects = Vec::new();
        while !self.eof() {
            if let Some(o) = self.object() {
                objects.push(o);
            }
        }
        if objects.is_empty() && self.diags.iter().all(|d| d.severity != Severity::Error) {
            self.error_at(self.pos(), "Body name expected");
        }
        Program { objects }
    }

    fn object(&mut self) -> Option<Object> {
        let pos = self.pos();
        let name = match self.tok() {
            Tok::Id(n) if self.free_name(n) => n.clone(),
            _ => {
                let _ = self.fail::<()>("Body name expected");
                // Resynchronise on the next name.
                self.bump();
                while !self.eof() && !matches!(self.tok(), Tok::Id(_)) {
                    self.bump();
                }
                return None;
            }
        };
        self.bump();
        if self.object_index(&name).is_some() {
            self.error_at(pos, "Body name is not unique");
        }
        self.objects.push(Callee {
            name: name.clone(),
            sizes: None,
        });
        let Ok((sizes, s_declared)) = self.header() else {
            // Skip the rest of an object whose header is broken.
            while !self.eof() && !self.at("}") {
                self.bump();
            }
            self.bump();
            return None;
        };
        self.objects.last_mut().expect("pushed above").sizes = Some(sizes);
        self.name = name.clone();
        self.scalars.clear();
        self.arrays = vec![
            ("x".into(), sizes[0]),
            ("a".into(), sizes[1]),
            ("s".into(), sizes[2]),
        ];
        let arrays = self.array_decls();
        let (body, result) = self.body();
        Some(Object {
            name,
            x_size: sizes[0],
            a_size: sizes[1],
            s_size: sizes[2],
            s_declared,
            arrays,
            body,
            result: result?,
            pos,
        })
    }

    /// `(x[n], a[m] [, s[k]]) {`: the three sizes, and whether `s` is given.
    fn header(&mut self) -> PResult<([usize; 3], bool)> {
        self.expect("(", "Left parenthes expected")?;
        self.expect_kw("x", "\"X\" expected")?;
        let x = self.size()?;
        self.expect(",", "Comma expected")?;
        self.expect_kw("a", "\"A\" expected")?;
        let a = self.size()?;
        let (mut s, mut declared) = (1, false);
        if self.at(",") {
            self.bump();
            self.expect_kw("s", "\"S\" expected")?;
            s = self.size()?;
            declared = true;
        }
        self.expect(")", "Right parenthes expected")?;
        self.expect("{", "Left brace expected")?;
        Ok(([x, a, s], declared))
    }

    /// `[NUM]`, rounded half up; at least 1.
    fn size(&mut self) -> PResult<usize> {
        self.expect("[", "Left bracket expected")?;
        let Tok::Num(v) = *self.tok() else {
            return self.fail("Real number expected");
        };
        let pos = self.pos();
        self.bump();
        self.expect("]", "Right bracket expected")?;
        let n = hf_round(v);
        if n < 1.0 {
            self.error_at(pos, "Array size must be greater zero");
            Ok(1)
        } else if n > MAX_ARRAY {
            self.error_at(pos, "Array size is too large (limit 1000000)");
            Ok(1)
        } else {
            Ok(n as usize)
        }
    }

    fn array_decls(&mut self) -> Vec<ArrayDecl> {
        let mut out = Vec::new();
        while self.at_kw("array") {
            self.bump();
            if self.array_decl_list(&mut out).is_err() {
                self.recover(0);
            }
        }
        out
    }

    fn array_decl_list(&mut self, out: &mut Vec<ArrayDecl>) -> PResult<()> {
        loop {
            let pos = self.pos();
            let name = match self.tok() {
                Tok::Id(n)
                    if self.free_name(n)
                        && *n != self.name
                        && self.object_index(n).is_none()
                        && self.array_size(n).is_none() =>
                {
                    n.clone()
                }
                _ => return self.fail("Identifier expected"),
            };
            self.bump();
            let size = self.size()?;
            self.arrays.push((name.clone(), size));
            out.push(ArrayDecl { name, size, pos });
            if !self.at(",") {
                break;
            }
            self.bump();
        }
        self.expect(";", "Semicolon expected")
    }

    /// Can the current token start a statement?
    fn at_statement(&self) -> bool {
        match self.tok() {
            Tok::Id(n) => {
                n == "if"
                    || n == "while"
                    || n == "s"
                    || (self.free_name(n) && *n != self.name && self.object_index(n).is_none())
            }
            _ => false,
        }
    }

    fn statement_or_recover(&mut self, out: &mut Vec<Stmt>) {
        let open = self.nesting;
        match self.statement() {
            Ok(s) => out.push(s),
            Err(Failed) => {
                let extra = self.nesting - open;
                self.nesting = open;
                self.recover(extra);
            }
        }
    }

    /// Statements, then the final `name = expr;` and `}`.
    fn body(&mut self) -> (Vec<Stmt>, Option<Expr>) {
        let mut body = Vec::new();
        loop {
            if self.at_kw(&self.name.clone()) {
                let result = self.final_assignment();
                if result.is_err() {
                    self.recover(0);
                }
                if self.at("}") {
                    self.bump();
                    return (body, result.ok());
                }
                self.error_at(self.pos(), "Right brace expected");
                if self.eof() {
                    return (body, None);
                }
            } else if self.at_statement() {
                self.statement_or_recover(&mut body);
            } else {
                let _ = self.fail::<()>("Body name expected");
                if self.eof() || self.at("}") {
                    self.bump();
                    return (body, None);
                }
                self.recover(0);
            }
        }
    }

    fn final_assignment(&mut self) -> PResult<Expr> {
        self.bump();
        self.expect("=", "Assign mark expected")?;
        let e = self.expr()?;
        self.expect(";", "Semicolon expected")?;
        Ok(e)
    }

    /// Statements of a branch or loop body, up to a token in `ends`.
    fn block(&mut self, ends: &[&str], message: &str) -> Vec<Stmt> {
        let mut out = Vec::new();
        loop {
            if self.at_statement() {
                self.statement_or_recover(&mut out);
            } else if ends.iter().any(|e| self.at_kw(e)) || self.eof() || self.at("}") {
                return out;
            } else {
                let _ = self.fail::<()>(message);
                self.recover(0);
            }
        }
    }

    fn statement(&mut self) -> PResult<Stmt> {
        let pos = self.pos();
        if self.at_kw("if") || self.at_kw("while") {
            if self.stmt_depth >= MAX_STMT_DEPTH {
                return self.fail(&format!(
                    "Statements are nested too deeply: more than {MAX_STMT_DEPTH} levels of \
                     \"if\" and \"while\""
                ));
            }
            self.stmt_depth += 1;
            let r = crate::lower::grow(|| {
                if self.at_kw("if") {
                    self.if_statement(pos)
                } else {
                    self.while_statement(pos)
                }
            });
            self.stmt_depth -= 1;
            return r;
        }
        let Tok::Id(name) = self.tok().clone() else {
            return self.fail("Identifier, \"if\" or \"while\"  expected");
        };
        self.bump();
        if let Some(size) = self.array_size(&name) {
            if self.at("[") {
                self.bump();
                let index = self.expr()?;
                self.expect("]", "Right bracket expected")?;
                self.expect("=", "Assign mark expected")?;
                let value = self.expr()?;
                self.expect(";", "Semicolon expected")?;
                return Ok(Stmt::AssignIndex {
                    name,
                    index,
                    value,
                    pos,
                });
            }
            self.expect("=", "Left bracket or assign mark expected")?;
            let values = self.literals(size)?;
            self.expect(";", "Semicolon expected")?;
            return Ok(Stmt::AssignArray { name, values, pos });
        }
        let value = self
            .expect("=", "Assign mark expected")
            .and_then(|_| self.expr());
        // Declared even when its expression is broken, to avoid follow-up errors.
        self.scalars.insert(name.clone());
        let value = value?;
        self.expect(";", "Semicolon expected")?;
        Ok(Stmt::Assign { name, value, pos })
    }

    fn if_statement(&mut self, pos: Pos) -> PResult<Stmt> {
        self.bump();
        self.nesting += 1;
        let cond = self.cond()?;
        self.expect_kw("then", "Reserved word \"then\" expected")?;
        let else_or_endif = "Reserved words \"else\" or \"endif\" expected";
        let then_body = self.block(&["else", "endif"], else_or_endif);
        let mut else_body = Vec::new();
        if self.at_kw("else") {
            self.bump();
            else_body = self.block(&["endif"], "Reserved word \"endif\" expected");
            self.expect_kw("endif", "Reserved word \"endif\" expected")?;
        } else {
            self.expect_kw("endif", else_or_endif)?;
        }
        self.nesting -= 1;
        self.expect(";", "Semicolon expected")?;
        Ok(Stmt::If {
            cond,
            then_body,
            else_body,
            pos,
        })
    }

    fn while_statement(&mut self, pos: Pos) -> PResult<Stmt> {
        self.bump();
        self.nesting += 1;
        let cond = self.cond()?;
        self.expect_kw("loop", "Reserved word \"loop\" expected")?;
        let body = self.block(&["endloop"], "Reserved word \"endloop\" expected");
        self.expect_kw("endloop", "Reserved word \"endloop\" expected")?;
        self.nesting -= 1;
        self.expect(";", "Semicolon expected")?;
        Ok(Stmt::While { cond, body, pos })
    }

    /// `[lit, ...]` with exactly `n` optionally signed number literals.
    fn literals(&mut self, n: usize) -> PResult<Vec<f64>> {
        self.expect("[", "Left bracket expected")?;
        let mut out = Vec::with_capacity(n);
        for k in 0..n {
            if k > 0 {
                self.expect(",", "Comma expected")?;
            }
            let neg = self.at("-");
            if neg || self.at("+") {
                self.bump();
            }
            let Tok::Num(v) = *self.tok() else {
                return self.fail("Real number expected");
            };
            self.bump();
            out.push(if neg { -v } else { v });
        }
        self.expect("]", "Right bracket expected")?;
        Ok(out)
    }

    fn nested<T>(&mut self, f: impl FnOnce(&mut Self) -> PResult<T>) -> PResult<T> {
        if self.depth >= MAX_DEPTH {
            return self.fail("Expression is nested too deeply");
        }
        self.depth += 1;
        let r = crate::lower::grow(|| f(self));
        self.depth -= 1;
        r
    }

    fn cond(&mut self) -> PResult<Cond> {
        let mut c = self.cmp()?;
        loop {
            let and = self.at_kw("and");
            if !and && !self.at_kw("or") {
                return Ok(c);
            }
            self.bump();
            let d = self.cmp()?;
            c = if and {
                Cond::And(c.into(), d.into())
            } else {
                Cond::Or(c.into(), d.into())
            };
        }
    }

    fn cmp(&mut self) -> PResult<Cond> {
        let mut c = self.bprim()?;
        loop {
            let op = match self.tok() {
                Tok::P("<") => CmpOp::Lt,
                Tok::P(">") => CmpOp::Gt,
                Tok::P("<=") => CmpOp::Le,
                Tok::P(">=") => CmpOp::Ge,
                Tok::P("=") => CmpOp::Eq,
                Tok::P("/=") => CmpOp::Ne,
                _ => return Ok(c),
            };
            self.bump();
            let d = self.bprim()?;
            c = Cond::Cmp(op, c.into(), d.into());
        }
    }

    /// A leading `(` opens a condition, not an expression (SPEC section 5).
    fn bprim(&mut self) -> PResult<Cond> {
        self.nested(|p| {
            if p.at_kw("not") {
                p.bump();
                return Ok(Cond::Not(p.bprim()?.into()));
            }
            if p.at("(") {
                p.bump();
                let c = p.cond()?;
                p.expect(")", "Right parenthes expected")?;
                return Ok(c);
            }
            Ok(Cond::Value(p.expr()?))
        })
    }

    fn binary(
        &mut self,
        ops: &[(&str, BinOp)],
        next: fn(&mut Self) -> PResult<Expr>,
    ) -> PResult<Expr> {
        let mut a = next(self)?;
        loop {
            let pos = self.pos();
            let Some(&(_, op)) = ops.iter().find(|(s, _)| self.at(s)) else {
                return Ok(a);
            };
            self.bump();
            let b = next(self)?;
            a = Expr {
                kind: ExprKind::Binary(op, a.into(), b.into()),
                pos,
            };
        }
    }

    fn expr(&mut self) -> PResult<Expr> {
        use BinOp::*;
        let ops = [
            ("+", Add),
            ("-", Sub),
            ("|", Union),
            ("&", Intersection),
            ("\\", Subtraction),
            ("@", Product),
        ];
        self.binary(&ops, Self::term)
    }

    fn term(&mut self) -> PResult<Expr> {
        self.binary(&[("*", BinOp::Mul), ("/", BinOp::Div)], Self::factor)
    }

    fn factor(&mut self) -> PResult<Expr> {
        self.binary(&[("^", BinOp::Pow)], Self::unary)
    }

    fn unary(&mut self) -> PResult<Expr> {
        self.nested(|p| {
            let pos = p.pos();
            let ops = [
                ("+", UnOp::Plus, "plus"),
                ("-", UnOp::Neg, "minus"),
                ("~", UnOp::Complement, "tilda"),
            ];
            let Some(&(s, op, word)) = ops.iter().find(|(s, _, _)| p.at(s)) else {
                return p.primary();
            };
            p.bump();
            if p.at(s) {
                return p.fail(&format!("Second unary {word} is not allowed"));
            }
            let a = p.unary()?;
            Ok(Expr {
                kind: ExprKind::Unary(op, a.into()),
                pos,
            })
        })
    }

    fn primary(&mut self) -> PResult<Expr> {
        let pos = self.pos();
        let e = |kind| Ok(Expr { kind, pos });
        match self.tok().clone() {
            Tok::Num(v) => {
                self.bump();
                e(ExprKind::Num(v))
            }
            Tok::P("(") => {
                self.bump();
                let inner = self.expr()?;
                self.expect(")", "Right parenthes expected")?;
                Ok(inner)
            }
            Tok::Id(n) if self.array_size(&n).is_some() => {
                self.bump();
                self.expect("[", "Left bracket expected")?;
                let index = self.expr()?;
                self.expect("]", "Right bracket expected")?;
                e(ExprKind::Index(n, index.into()))
            }
            Tok::Id(n) if KEYWORDS.contains(&n.as_str()) => self.fail("Expression expected"),
            Tok::Id(n) => {
                if let Some(sig) = (self.funcs)(&n) {
                    return self.call(n, &sig, pos);
                }
                // The object itself is not callable yet (no recursion).
                if let Some(k) = self.object_index(&n).filter(|_| n != self.name) {
                    return self.object_call(n, k, pos);
                }
                self.bump();
                if !self.scalars.contains(&n) {
                    let why = self.unknown_name(&n);
                    self.error_at(
                        pos,
                        &format!("Unassigned identificator used in expression: {why}"),
                    );
                    self.skip_group();
                }
                e(ExprKind::Var(n))
            }
            _ => self.fail("Expression expected"),
        }
    }

    /// Arguments after the current `,` up to the closing parenthesis
    /// (counting commas outside nested brackets); looks ahead only.
    fn count_remaining_args(&self) -> usize {
        let (mut depth, mut n) = (0usize, 0);
        for t in &self.toks[self.i..] {
            match &t.tok {
                Tok::P("(" | "[") => depth += 1,
                Tok::P(")" | "]") if depth == 0 => break,
                Tok::P(")" | "]") => depth -= 1,
                Tok::P(",") if depth == 0 => n += 1,
                Tok::P(";" | "}") | Tok::Eof => break,
                _ => {}
            }
        }
        n
    }

    /// Why a name cannot be used here, in plain words, with the closest
    /// known name when one is near. The current token follows the name.
    fn unknown_name(&self, n: &str) -> String {
        if n == self.name {
            return format!("'{n}' is the object being defined; it cannot use its own value");
        }
        if self.at("(") {
            let registry = crate::library::Registry::standard();
            let builtins = crate::lower::ops::BUILTINS.iter().map(|(b, _)| *b);
            let names = registry.names().into_iter().chain(builtins);
            let funcs = names.filter(|f| self.is_function(f)).map(str::to_string);
            let objects = self.objects.iter().map(|o| o.name.clone());
            let objects = objects.filter(|o| *o != self.name);
            let near = closest(n, funcs.chain(objects));
            let hint = near.map_or(String::new(), |m| {
                format!(
                    " (did you mean {}?)",
                    crate::library::shapes::display_name(&m)
                )
            });
            return format!("'{n}' is not a known function or an object defined above{hint}");
        }
        let vars = self.scalars.iter().cloned();
        let arrays = self.arrays.iter().map(|(a, _)| a.clone());
        let near = closest(n, vars.chain(arrays));
        let hint = near.map_or(String::new(), |m| format!(" (did you mean {m}?)"));
        format!("'{n}' is not a variable assigned before this point{hint}")
    }

    /// After an unknown name: skips a following `( ... )` or `[ ... ]` so a
    /// call to a later object gives one error, not several.
    fn skip_group(&mut self) {
        if !self.at("(") && !self.at("[") {
            return;
        }
        let mut depth = 0usize;
        loop {
            match self.tok() {
                Tok::P("(" | "[") => depth += 1,
                Tok::P(")" | "]") => depth -= 1,
                Tok::P(";" | "}") | Tok::Eof => return,
                _ => {}
            }
            self.bump();
            if depth == 0 {
                return;
            }
        }
    }

    /// A bare array name as an argument; returns it with its length.
    fn array_arg(&mut self, message: &str) -> PResult<(Expr, usize)> {
        let pos = self.pos();
        if let Tok::Id(n) = self.tok().clone() {
            if let Some(size) = self.array_size(&n) {
                self.bump();
                return Ok((
                    Expr {
                        kind: ExprKind::Var(n),
                        pos,
                    },
                    size,
                ));
            }
        }
        self.fail(message)
    }

    fn call(&mut self, name: String, sig: &[ParamKind], pos: Pos) -> PResult<Expr> {
        self.bump();
        self.expect("(", "Left parenthes expected")?;
        let shown = crate::library::shapes::display_name(&name).to_string();
        let mut args = Vec::with_capacity(sig.len());
        for (k, kind) in sig.iter().enumerate() {
            if k > 0 && !self.at(",") {
                let few = if self.at(")") {
                    format!(
                        ": too few arguments to {shown}: expected {}, got {k}",
                        sig.len()
                    )
                } else {
                    String::new()
                };
                return self.fail(&format!("Comma expected{few}"));
            }
            if k > 0 {
                self.bump();
            }
            args.push(match kind {
                ParamKind::Real => self.expr()?,
                ParamKind::Array => {
                    let m = format!(
                        "Error in argument in function call: argument {} of {shown} must be \
                         the name of an array (x, a, s or a declared array)",
                        k + 1
                    );
                    self.array_arg(&m)?.0
                }
            });
        }
        if self.at(",") {
            let got = sig.len() + self.count_remaining_args();
            return self.fail(&format!(
                "Right parenthes expected: too many arguments to {shown}: expected {}, got {got}",
                sig.len()
            ));
        }
        self.expect(")", "Right parenthes expected")?;
        Ok(Expr {
            kind: ExprKind::Call(name, args),
            pos,
        })
    }

    /// `object(xarr, aarr [, sarr])`: lengths must equal the callee's sizes.
    fn object_call(&mut self, name: String, k: usize, pos: Pos) -> PResult<Expr> {
        self.bump();
        self.expect("(", "Left parenthes expected")?;
        let sizes = self.objects[k].sizes;
        let mut args = Vec::with_capacity(3);
        for j in 0..3 {
            if j == 2 {
                if !self.at(",") {
                    if sizes.is_some_and(|s| s[2] != 1) {
                        self.error_at(self.pos(), "Wrong number of items in array");
                    }
                    break;
                }
                self.bump();
            } else if j == 1 {
                self.expect(",", "Comma expected")?;
            }
            let apos = self.pos();
            let (arg, len) = self.array_arg("Only array name expected")?;
            if sizes.is_some_and(|s| s[j] != len) {
                self.error_at(apos, "Wrong number of items in array");
            }
            args.push(arg);
        }
        if self.at(",") {
            let got = 3 + self.count_remaining_args();
            return self.fail(&format!(
                "Right parenthes expected: too many arguments to object '{name}': it takes \
                 x, a and optionally s (3 arrays), got {got}"
            ));
        }
        self.expect(")", "Right parenthes expected")?;
        Ok(Expr {
            kind: ExprKind::Call(name, args),
            pos,
        })
    }
}

/// The candidate nearest to `n` by edit distance, if it is close (at most
/// one edit per three letters; names shorter than three get none).
fn closest(n: &str, candidates: impl Iterator<Item = String>) -> Option<String> {
    let limit = n.chars().count() / 3;
    if limit == 0 {
        return None;
    }
    candidates
        .filter(|c| c != n)
        .map(|c| (edit_distance(n, &c), c))
        .filter(|(d, _)| *d <= limit)
        .min()
        .map(|(_, c)| c)
}

/// Levenshtein distance (insertions, deletions, substitutions).
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut prev = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let cur = row[j + 1];
            row[j + 1] = if ca == *cb {
                prev
            } else {
                1 + prev.min(cur).min(row[j])
            };
            prev = cur;
        }
    }
    row[b.len()]
}
