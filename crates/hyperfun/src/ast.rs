//! Syntax tree of a HyperFun file. Names are lower-cased (the language is
//! case-insensitive); every node carries the 1-based position of its first
//! token (of the operator for unary and binary operations), which is where
//! the reference interpreter reports errors. The file name lives in
//! [`crate::Diagnostics`].

/// 1-based line and column; a tab counts as one column.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, PartialOrd, Ord, Hash)]
pub struct Pos {
    pub line: u32,
    pub col: u32,
}

/// Alias used by the diagnostics vocabulary.
pub type Span = Pos;

/// A whole file: its objects in textual order.
#[derive(Debug, Clone)]
pub struct Program {
    pub objects: Vec<Object>,
}

/// `array name[size]` inside an object.
#[derive(Debug, Clone)]
pub struct ArrayDecl {
    pub name: String,
    pub size: usize,
    pub pos: Pos,
}

/// `name(x[n], a[m], s[k]) { arrays; statements; name = result; }`.
#[derive(Debug, Clone)]
pub struct Object {
    pub name: String,
    pub x_size: usize,
    pub a_size: usize,
    /// 1 when the header omits `s`.
    pub s_size: usize,
    /// Whether the header declares `s[k]` (the object's attributes).
    pub s_declared: bool,
    pub arrays: Vec<ArrayDecl>,
    pub body: Vec<Stmt>,
    /// The final `name = expr;`.
    pub result: Expr,
    pub pos: Pos,
}

#[derive(Debug, Clone)]
pub enum Stmt {
    /// `name = value;` (declares the scalar on first use).
    Assign { name: String, value: Expr, pos: Pos },
    /// `name[index] = value;` for a local array or `s`.
    AssignIndex {
        name: String,
        index: Expr,
        value: Expr,
        pos: Pos,
    },
    /// `name = [lit, ...];` with exactly as many signed literals as elements.
    AssignArray {
        name: String,
        values: Vec<f64>,
        pos: Pos,
    },
    If {
        cond: Cond,
        then_body: Vec<Stmt>,
        else_body: Vec<Stmt>,
        pos: Pos,
    },
    While {
        cond: Cond,
        body: Vec<Stmt>,
        pos: Pos,
    },
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CmpOp {
    Lt,
    Gt,
    Le,
    Ge,
    /// `=`: equal within EPS.
    Eq,
    /// `/=`: differ by at least EPS.
    Ne,
}

/// Condition of `if` / `while`; `and` and `or` share one precedence level.
#[derive(Debug, Clone)]
pub enum Cond {
    Value(Expr),
    Not(Box<Cond>),
    Cmp(CmpOp, Box<Cond>, Box<Cond>),
    And(Box<Cond>, Box<Cond>),
    Or(Box<Cond>, Box<Cond>),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UnOp {
    Plus,
    Neg,
    /// `~`: set complement (plain negation).
    Complement,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BinOp {
    Add,
    Sub,
    Mul,
    Div,
    Pow,
    /// `|`
    Union,
    /// `&`
    Intersection,
    /// `@` (same as `&` in the reference)
    Product,
    /// `\`
    Subtraction,
}

#[derive(Debug, Clone)]
pub struct Expr {
    pub kind: ExprKind,
    pub pos: Pos,
}

#[derive(Debug, Clone)]
pub enum ExprKind {
    Num(f64),
    /// A scalar; as a call argument also a bare array name (`x`, `a`, `s` or
    /// a local array) passed by reference.
    Var(String),
    /// `name[index]` for `x`, `a`, `s` or a local array.
    Index(String, Box<Expr>),
    Unary(UnOp, Box<Expr>),
    Binary(BinOp, Box<Expr>, Box<Expr>),
    /// A built-in, library function or earlier object.
    Call(String, Vec<Expr>),
}

// A generated model can chain 100k operators (`f1 | f2 | ...`), which the
// parser builds as a left-deep tree; the derived drop would recurse once per
// node and overflow the stack. These drops move the children into a
// worklist instead, so the recursion depth stays one.
impl Drop for Expr {
    fn drop(&mut self) {
        if matches!(self.kind, ExprKind::Num(_) | ExprKind::Var(_)) {
            return;
        }
        let mut work = Vec::new();
        take_children(&mut self.kind, &mut work);
        while let Some(mut e) = work.pop() {
            take_children(&mut e.kind, &mut work);
        }
    }
}

fn take_children(kind: &mut ExprKind, out: &mut Vec<Expr>) {
    match std::mem::replace(kind, ExprKind::Num(0.0)) {
        ExprKind::Num(_) | ExprKind::Var(_) => {}
        ExprKind::Index(_, a) | ExprKind::Unary(_, a) => out.push(*a),
        ExprKind::Binary(_, a, b) => out.extend([*a, *b]),
        ExprKind::Call(_, args) => out.extend(args),
    }
}

impl Drop for Cond {
    fn drop(&mut self) {
        if matches!(self, Cond::Value(_)) {
            return;
        }
        let mut work = Vec::new();
        take_conds(self, &mut work);
        while let Some(mut c) = work.pop() {
            take_conds(&mut c, &mut work);
        }
    }
}

fn take_conds(c: &mut Cond, out: &mut Vec<Cond>) {
    let mut take = |b: &mut Box<Cond>| {
        if !matches!(**b, Cond::Value(_)) {
            let leaf = Cond::Value(Expr {
                kind: ExprKind::Num(0.0),
                pos: Pos::default(),
            });
            out.push(std::mem::replace(&mut **b, leaf));
        }
    };
    match c {
        Cond::Value(_) => {}
        Cond::Not(a) => take(a),
        Cond::Cmp(_, a, b) | Cond::And(a, b) | Cond::Or(a, b) => {
            take(a);
            take(b);
        }
    }
}
