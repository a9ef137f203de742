//! Syntax tree of a HyperFun file. Names are lower-cased (the language is
//! case-insensitive); every node carries the 1-based position of its first
//! token (of the operator for unary and binary operations), which is where
//! the reference interpreter reports errors. The file name lives in
//! [`crate::Diagnostics`].

/// 1-based line and column; a tab counts as one column.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, PartialOrd, Ord, Hash)]
pub struct Pos {
    /// Line, from 1.
    pub line: u32,
    /// Column, from 1.
    pub col: u32,
}

/// Alias used by the diagnostics vocabulary.
pub type Span = Pos;

/// A whole file: its objects in textual order.
#[derive(Debug, Clone)]
pub struct Program {
    /// The objects (models) defined in the file.
    pub objects: Vec<Object>,
}

/// `array name[size]` inside an object.
#[derive(Debug, Clone)]
pub struct ArrayDecl {
    /// Array name, lower-cased.
    pub name: String,
    /// Number of elements.
    pub size: usize,
    /// Position of the declaration.
    pub pos: Pos,
}

/// `name(x[n], a[m], s[k]) { arrays; statements; name = result; }`.
#[derive(Debug, Clone)]
pub struct Object {
    /// Object name, lower-cased.
    pub name: String,
    /// Declared length `n` of the point array `x`.
    pub x_size: usize,
    /// Declared length `m` of the parameter array `a`.
    pub a_size: usize,
    /// 1 when the header omits `s`.
    pub s_size: usize,
    /// Whether the header declares `s[k]` (the object's attributes).
    pub s_declared: bool,
    /// Local `array` declarations, in order.
    pub arrays: Vec<ArrayDecl>,
    /// Statements before the final assignment, in order.
    pub body: Vec<Stmt>,
    /// The final `name = expr;`.
    pub result: Expr,
    /// Position of the object's name in its header.
    pub pos: Pos,
}

/// A statement of an object body.
#[derive(Debug, Clone)]
pub enum Stmt {
    /// `name = value;` (declares the scalar on first use).
    Assign {
        /// Variable name.
        name: String,
        /// Value stored.
        value: Expr,
        /// Position of the name.
        pos: Pos,
    },
    /// `name[index] = value;` for a local array or `s`.
    AssignIndex {
        /// Array name.
        name: String,
        /// Element index, 1-based as in HyperFun.
        index: Expr,
        /// Value stored.
        value: Expr,
        /// Position of the array name.
        pos: Pos,
    },
    /// `name = [lit, ...];` with exactly as many signed literals as elements.
    AssignArray {
        /// Array name.
        name: String,
        /// The literals, in element order.
        values: Vec<f64>,
        /// Position of the array name.
        pos: Pos,
    },
    /// `if cond then ... [else ...] endif`.
    If {
        /// The condition.
        cond: Cond,
        /// Statements run where the condition holds.
        then_body: Vec<Stmt>,
        /// Statements run elsewhere (empty without `else`).
        else_body: Vec<Stmt>,
        /// Position of `if`.
        pos: Pos,
    },
    /// `while cond loop ... endloop`.
    While {
        /// The condition, tested before each pass.
        cond: Cond,
        /// The loop body.
        body: Vec<Stmt>,
        /// Position of `while`.
        pos: Pos,
    },
}

/// A comparison in a condition; the result is 1 or 0.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CmpOp {
    /// `<`
    Lt,
    /// `>`
    Gt,
    /// `<=`
    Le,
    /// `>=`
    Ge,
    /// `=`: equal within EPS.
    Eq,
    /// `/=`: differ by at least EPS.
    Ne,
}

/// Condition of `if` / `while`; `and` and `or` share one precedence level.
#[derive(Debug, Clone)]
pub enum Cond {
    /// An expression: true where `|value| >= EPS`; as an operand of a
    /// comparison, its plain value.
    Value(Expr),
    /// `not c`.
    Not(Box<Cond>),
    /// `a op b`; comparisons chain to the left (`a < b < c` compares the 0/1
    /// result of `a < b` with `c`).
    Cmp(CmpOp, Box<Cond>, Box<Cond>),
    /// `a and b`.
    And(Box<Cond>, Box<Cond>),
    /// `a or b`.
    Or(Box<Cond>, Box<Cond>),
}

/// A prefix operator of an expression.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UnOp {
    /// `+a` (no effect).
    Plus,
    /// `-a`.
    Neg,
    /// `~`: set complement (plain negation).
    Complement,
}

/// An infix operator of an expression.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BinOp {
    /// `+`
    Add,
    /// `-`
    Sub,
    /// `*`
    Mul,
    /// `/`
    Div,
    /// `^`, real power.
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

/// An expression with its position.
#[derive(Debug, Clone)]
pub struct Expr {
    /// What the expression is.
    pub kind: ExprKind,
    /// Position of its first token, or of the operator for unary and binary
    /// operations.
    pub pos: Pos,
}

/// The forms an expression takes.
#[derive(Debug, Clone)]
pub enum ExprKind {
    /// A number literal.
    Num(f64),
    /// A scalar; as a call argument also a bare array name (`x`, `a`, `s` or
    /// a local array) passed by reference.
    Var(String),
    /// `name[index]` for `x`, `a`, `s` or a local array.
    Index(String, Box<Expr>),
    /// A prefix operation.
    Unary(UnOp, Box<Expr>),
    /// An infix operation, left operand first.
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
