//! The operation set of the expression graph and its scalar (f64) semantics.
//!
//! The f64 functions here are the reference meaning of every op: the point
//! evaluator and constant folding both call them, so a folded constant is
//! bit-identical to what evaluation would have produced.

/// Operations with one argument.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum UnaryOp {
    /// `-a`.
    Neg,
    /// `|a|`.
    Abs,
    /// -1, 0 or 1 (0 for NaN).
    Sign,
    /// Square root (NaN below 0).
    Sqrt,
    /// `a * a`.
    Square,
    /// `e^a`.
    Exp,
    /// Natural logarithm.
    Ln,
    /// Sine (radians).
    Sin,
    /// Cosine (radians).
    Cos,
    /// Tangent (radians).
    Tan,
    /// Arc sine.
    Asin,
    /// Arc cosine.
    Acos,
    /// Arc tangent.
    Atan,
    /// Hyperbolic sine.
    Sinh,
    /// Hyperbolic cosine.
    Cosh,
    /// Hyperbolic tangent.
    Tanh,
    /// Round down.
    Floor,
    /// Round up.
    Ceil,
    /// Towards zero.
    Trunc,
    /// Half away from zero.
    Round,
    /// `v - floor(v)`, in `[0, 1)`.
    Fract,
    /// Triangle wave `1/2 + asin(sin(pi u))/pi`, period 2, values in [0, 1],
    /// computed exactly from `fract` (Fryazinov et al. Eq. 3 with `u = t/a`).
    Tri,
    /// Sawtooth `1/2 + u - floor(u + 1/2)`, period 1, values in [0, 1)
    /// (Fryazinov et al. Eq. 2 with `u = t/a`).
    Saw,
    /// Logical not on truth values: 1 if the argument is 0, else 0.
    Not,
}

/// Operations with two arguments.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum BinaryOp {
    /// `a + b`.
    Add,
    /// `a - b`.
    Sub,
    /// `a * b`.
    Mul,
    /// `a / b`.
    Div,
    /// Real power `a^b` as `powf` (NaN for negative base and fractional exponent).
    Pow,
    /// `atan2(a, b)`, `a` the y-like argument.
    Atan2,
    /// Smaller argument; NaN if either is NaN.
    Min,
    /// Larger argument; NaN if either is NaN.
    Max,
    /// Floored modulo: `a - b*floor(a/b)`, sign of `b`.
    Mod,
    /// Truncated remainder (C `fmod`), sign of `a`.
    Rem,
    /// 1 if `a < b`, else 0.
    Lt,
    /// 1 if `a <= b`, else 0.
    Le,
    /// 1 if `a > b`, else 0.
    Gt,
    /// 1 if `a >= b`, else 0.
    Ge,
    /// 1 if `a == b`, else 0.
    Eq,
    /// 1 if `a != b`, else 0.
    Ne,
    /// Logical and of truth values (nonzero is true); result 1 or 0.
    And,
    /// Logical or of truth values (nonzero is true); result 1 or 0.
    Or,
}

impl UnaryOp {
    /// Every unary op, for tests and listings.
    pub const ALL: [UnaryOp; 24] = [
        UnaryOp::Neg,
        UnaryOp::Abs,
        UnaryOp::Sign,
        UnaryOp::Sqrt,
        UnaryOp::Square,
        UnaryOp::Exp,
        UnaryOp::Ln,
        UnaryOp::Sin,
        UnaryOp::Cos,
        UnaryOp::Tan,
        UnaryOp::Asin,
        UnaryOp::Acos,
        UnaryOp::Atan,
        UnaryOp::Sinh,
        UnaryOp::Cosh,
        UnaryOp::Tanh,
        UnaryOp::Floor,
        UnaryOp::Ceil,
        UnaryOp::Trunc,
        UnaryOp::Round,
        UnaryOp::Fract,
        UnaryOp::Tri,
        UnaryOp::Saw,
        UnaryOp::Not,
    ];

    /// Reference value.
    #[inline]
    pub fn apply(self, a: f64) -> f64 {
        use UnaryOp::*;
        match self {
            Neg => -a,
            Abs => a.abs(),
            Sign => sign(a),
            Sqrt => a.sqrt(),
            Square => a * a,
            Exp => a.exp(),
            Ln => a.ln(),
            Sin => a.sin(),
            Cos => a.cos(),
            Tan => a.tan(),
            Asin => a.asin(),
            Acos => a.acos(),
            Atan => a.atan(),
            Sinh => a.sinh(),
            Cosh => a.cosh(),
            Tanh => a.tanh(),
            Floor => a.floor(),
            Ceil => a.ceil(),
            Trunc => a.trunc(),
            Round => a.round(),
            Fract => a - a.floor(),
            Tri => tri_wave(a),
            Saw => saw_wave(a),
            Not => truth(a == 0.0),
        }
    }

    /// Lower-case name, for listings and `Debug` output.
    pub fn name(self) -> &'static str {
        use UnaryOp::*;
        match self {
            Neg => "neg",
            Abs => "abs",
            Sign => "sign",
            Sqrt => "sqrt",
            Square => "square",
            Exp => "exp",
            Ln => "ln",
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
            Trunc => "trunc",
            Round => "round",
            Fract => "fract",
            Tri => "tri",
            Saw => "saw",
            Not => "not",
        }
    }
}

impl BinaryOp {
    /// Every binary op, for tests and listings.
    pub const ALL: [BinaryOp; 18] = [
        BinaryOp::Add,
        BinaryOp::Sub,
        BinaryOp::Mul,
        BinaryOp::Div,
        BinaryOp::Pow,
        BinaryOp::Atan2,
        BinaryOp::Min,
        BinaryOp::Max,
        BinaryOp::Mod,
        BinaryOp::Rem,
        BinaryOp::Lt,
        BinaryOp::Le,
        BinaryOp::Gt,
        BinaryOp::Ge,
        BinaryOp::Eq,
        BinaryOp::Ne,
        BinaryOp::And,
        BinaryOp::Or,
    ];

    /// Reference value.
    #[inline]
    pub fn apply(self, a: f64, b: f64) -> f64 {
        use BinaryOp::*;
        match self {
            Add => a + b,
            Sub => a - b,
            Mul => a * b,
            Div => a / b,
            Pow => a.powf(b),
            Atan2 => a.atan2(b),
            Min => fmin(a, b),
            Max => fmax(a, b),
            Mod => a - b * (a / b).floor(),
            Rem => a % b,
            Lt => truth(a < b),
            Le => truth(a <= b),
            Gt => truth(a > b),
            Ge => truth(a >= b),
            Eq => truth(a == b),
            Ne => truth(a != b),
            And => truth(a != 0.0 && b != 0.0),
            Or => truth(a != 0.0 || b != 0.0),
        }
    }

    /// True for ops with `op(a, b) == op(b, a)`, used to canonicalise the graph.
    pub fn commutative(self) -> bool {
        use BinaryOp::*;
        matches!(self, Add | Mul | Min | Max | Eq | Ne | And | Or)
    }

    /// Lower-case name, for listings and `Debug` output.
    pub fn name(self) -> &'static str {
        use BinaryOp::*;
        match self {
            Add => "add",
            Sub => "sub",
            Mul => "mul",
            Div => "div",
            Pow => "pow",
            Atan2 => "atan2",
            Min => "min",
            Max => "max",
            Mod => "mod",
            Rem => "rem",
            Lt => "lt",
            Le => "le",
            Gt => "gt",
            Ge => "ge",
            Eq => "eq",
            Ne => "ne",
            And => "and",
            Or => "or",
        }
    }
}

/// 1.0 for true, 0.0 for false.
#[inline]
pub fn truth(b: bool) -> f64 {
    if b {
        1.0
    } else {
        0.0
    }
}

/// -1, 0 or 1 by the sign of `a`; 0 for NaN and for both zeros.
#[inline]
pub fn sign(a: f64) -> f64 {
    if a > 0.0 {
        1.0
    } else if a < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// `min` that propagates NaN (f64::min would hide a NaN argument, and with it
/// an undefined region of the model).
#[inline]
pub fn fmin(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else if a < b {
        a
    } else {
        b
    }
}

/// `max` that propagates NaN, the counterpart of [`fmin`].
#[inline]
pub fn fmax(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else if a > b {
        a
    } else {
        b
    }
}

/// Triangle wave with period 2: 0 at odd-minus-half points (u = -1/2 + 2k),
/// 1 at u = 1/2 + 2k, 1/2 at integers. Equal to `1/2 + asin(sin(pi u))/pi`.
#[inline]
pub fn tri_wave(u: f64) -> f64 {
    let s = 0.5 * u + 0.25;
    1.0 - (2.0 * (s - s.floor()) - 1.0).abs()
}

/// Sawtooth with period 1: `1/2 + u - floor(u + 1/2)`, in [0, 1).
#[inline]
pub fn saw_wave(u: f64) -> f64 {
    0.5 + u - (u + 0.5).floor()
}

/// The R-function set operations (Pasko et al. Eqs. 2-3; inside is `f >= 0`):
/// graph nodes of their own, so interval bounds, batch fusion and per-region
/// simplification read them directly instead of recognising a formula.
/// Subtraction `f1 \ f2` is the intersection with `-f2`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum SetOp {
    /// `(f1 + f2 + sqrt(f1^2 + f2^2 - 2 a f1 f2)) / (1 + a)`.
    Union,
    /// `(f1 + f2 - sqrt(f1^2 + f2^2 - 2 a f1 f2)) / (1 + a)`.
    Intersection,
}

impl SetOp {
    /// Both set operations.
    pub const ALL: [SetOp; 2] = [SetOp::Union, SetOp::Intersection];

    /// Reference value of the R-function with parameter `alpha`. At
    /// `alpha = 0` (HyperFun's `|`, `&`) the scale is left out and the
    /// operations run in the order `(a + b) ± sqrt(a*a + b*b)`, so values
    /// are bit-identical to the formula written out.
    #[inline]
    pub fn apply(self, a: f64, b: f64, alpha: f64) -> f64 {
        let s = a + b;
        if alpha == 0.0 {
            let r = (a * a + b * b).sqrt();
            return match self {
                SetOp::Union => s + r,
                SetOp::Intersection => s - r,
            };
        }
        let r = (a * a + b * b - 2.0 * alpha * a * b).sqrt();
        match self {
            SetOp::Union => (s + r) / (1.0 + alpha),
            SetOp::Intersection => (s - r) / (1.0 + alpha),
        }
    }

    /// Partial derivatives `(d/da, d/db, d/dalpha)` at `(a, b, alpha)`
    /// whose value is `v`. Where `a = b = 0` (the root vanishes) the
    /// one-sided rule of the written-out formula is used: `(1, 1) / (1 + alpha)`.
    pub fn partials(self, a: f64, b: f64, alpha: f64, v: f64) -> (f64, f64, f64) {
        let s = if self == SetOp::Union { 1.0 } else { -1.0 };
        let k = 1.0 + alpha;
        let r = (a * a + b * b - 2.0 * alpha * a * b).sqrt();
        if r == 0.0 || !r.is_finite() {
            return (1.0 / k, 1.0 / k, 0.0);
        }
        let da = (1.0 + s * (a - alpha * b) / r) / k;
        let db = (1.0 + s * (b - alpha * a) / r) / k;
        // d r / d alpha = -a b / r.
        let dalpha = (-s * a * b / r) / k - v / k;
        (da, db, dalpha)
    }

    /// Lower-case name, for listings.
    pub fn name(self) -> &'static str {
        match self {
            SetOp::Union => "union",
            SetOp::Intersection => "intersection",
        }
    }
}
