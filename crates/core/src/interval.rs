//! Interval arithmetic with sound bounds.
//!
//! Contract: for every op, the result contains the f64 reference value
//! (`ops.rs`) at every point of the argument boxes where that value is not NaN,
//! and [`Interval::may_be_nan`] is set wherever some such value may be NaN.
//! The flag matters because comparisons, logic, `sign` and `select` turn a NaN
//! (an undefined sub-expression, e.g. `sqrt` of a negative) into 0 or 1, so
//! their bounds must include that outcome. A NaN bound means "nothing is
//! known" (consumers must treat it as the whole line). IEEE `+ - * /` and `sqrt` are correctly rounded and monotone, so their
//! endpoint formulas bound the point values exactly; libm functions are only
//! faithful, so their results are widened by a few ulps.

use crate::ops::{self, BinaryOp, SetOp, UnaryOp};
use std::f64::consts::{FRAC_PI_2, PI};

/// A closed range `[lo, hi]` of f64 values plus a flag for possible NaN
/// values (see the module docs for the soundness contract).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval {
    /// Lower bound.
    pub lo: f64,
    /// Upper bound.
    pub hi: f64,
    /// Some point value covered by this bound may be NaN.
    nan: bool,
}

const ENTIRE: Interval = Interval {
    lo: f64::NEG_INFINITY,
    hi: f64::INFINITY,
    nan: false,
};
const UNIT: Interval = Interval {
    lo: 0.0,
    hi: 1.0,
    nan: false,
};

fn down(v: f64) -> f64 {
    v.next_down().next_down()
}
fn up(v: f64) -> f64 {
    v.next_up().next_up()
}

// `add`, `mul`, ... take and return plain values and sit next to ops with
// no std trait (`sqrt`, `hull`); the names read like the formulas they
// implement, so the std operator traits are not used for them.
#[allow(clippy::should_implement_trait)]
impl Interval {
    /// The whole line `[-inf, inf]`.
    pub const ENTIRE: Interval = ENTIRE;

    /// `[lo, hi]` without the NaN flag.
    pub fn new(lo: f64, hi: f64) -> Interval {
        Interval { lo, hi, nan: false }
    }
    /// `[a, b]` (`a <= b`) widened to hold the f32 roundings of its ends:
    /// the coordinates the batch evaluator is actually given, so that an
    /// interval over a tile bounds the f32 samples taken in it.
    pub fn with_f32_ends(a: f64, b: f64) -> Interval {
        let (fa, fb) = (a as f32 as f64, b as f32 as f64);
        Interval::new(a.min(fa), b.max(fb))
    }
    /// The single value `v`.
    pub fn point(v: f64) -> Interval {
        Interval::new(v, v)
    }
    /// The "nothing known" bound (consumers treat it as the whole line).
    pub fn nan() -> Interval {
        Interval::new(f64::NAN, f64::NAN)
    }
    /// The bound of a value that is NaN everywhere (the constant NaN, e.g.
    /// where a model raises a run-time error): no finite range, only the
    /// NaN flag, so `select(error, NaN, value)` keeps the value's range.
    pub fn only_nan() -> Interval {
        Interval {
            lo: f64::INFINITY,
            hi: f64::NEG_INFINITY,
            nan: true,
        }
    }
    /// Whether a point value covered by this bound may be NaN (also true
    /// for the "nothing known" NaN bound).
    pub fn may_be_nan(&self) -> bool {
        self.nan || self.is_nan()
    }
    /// This bound, also covering NaN values.
    pub fn with_nan(self, nan: bool) -> Interval {
        Interval {
            nan: self.nan || nan,
            ..self
        }
    }
    /// Whether a bound is NaN (the "nothing known" bound).
    pub fn is_nan(&self) -> bool {
        self.lo.is_nan() || self.hi.is_nan()
    }
    /// Whether `v` lies in the range; always true for a NaN bound.
    pub fn contains(&self, v: f64) -> bool {
        self.is_nan() || (self.lo <= v && v <= self.hi)
    }
    /// `hi - lo`.
    pub fn width(&self) -> f64 {
        self.hi - self.lo
    }
    /// The midpoint.
    pub fn mid(&self) -> f64 {
        0.5 * (self.lo + self.hi)
    }
    /// The smallest range covering both (NaN if either is); the NaN flag is
    /// the union of both.
    pub fn hull(self, o: Interval) -> Interval {
        if self.is_nan() || o.is_nan() {
            return Interval::nan();
        }
        Interval::new(self.lo.min(o.lo), self.hi.max(o.hi)).with_nan(self.nan || o.nan)
    }
    /// Widens by two ulps on each side (for libm results).
    fn widen(self) -> Interval {
        Interval::new(down(self.lo), up(self.hi))
    }
    /// Applies a nondecreasing function to both ends.
    fn mono_inc(self, f: impl Fn(f64) -> f64) -> Interval {
        Interval::new(f(self.lo), f(self.hi))
    }

    /// Bound of `-a`.
    /// The arithmetic methods (`neg` to `max`) bound the non-NaN values and do
    /// not track the NaN flag; [`Interval::unary`] and [`Interval::binary`] do.
    pub fn neg(self) -> Interval {
        Interval::new(-self.hi, -self.lo)
    }
    /// Bound of `a + b`.
    pub fn add(self, o: Interval) -> Interval {
        Interval::new(self.lo + o.lo, self.hi + o.hi)
    }
    /// Bound of `a - b`.
    pub fn sub(self, o: Interval) -> Interval {
        Interval::new(self.lo - o.hi, self.hi - o.lo)
    }
    /// Bound of `a * b`; the whole line where `0 * inf` could occur.
    pub fn mul(self, o: Interval) -> Interval {
        let c = [
            self.lo * o.lo,
            self.lo * o.hi,
            self.hi * o.lo,
            self.hi * o.hi,
        ];
        if c.iter().any(|v| v.is_nan()) {
            // 0 * inf: the product of finite interior points can be anything.
            return if self.is_nan() || o.is_nan() {
                Interval::nan()
            } else {
                ENTIRE
            };
        }
        Interval::new(
            c.iter().cloned().fold(f64::INFINITY, f64::min),
            c.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
        )
    }
    /// Bound of `1 / a`.
    pub fn recip(self) -> Interval {
        Interval::point(1.0).div(self)
    }
    /// Bound of `a / b`; the whole line when `b` may be 0.
    pub fn div(self, o: Interval) -> Interval {
        if o.lo <= 0.0 && o.hi >= 0.0 {
            // Division by (values near) zero: anything, infinities included.
            return ENTIRE;
        }
        let c = [
            self.lo / o.lo,
            self.lo / o.hi,
            self.hi / o.lo,
            self.hi / o.hi,
        ];
        if c.iter().any(|v| v.is_nan()) {
            return ENTIRE;
        }
        Interval::new(
            c.iter().cloned().fold(f64::INFINITY, f64::min),
            c.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
        )
    }
    /// Bound of `|a|`.
    pub fn abs(self) -> Interval {
        if self.lo >= 0.0 {
            self
        } else if self.hi <= 0.0 {
            self.neg()
        } else {
            Interval::new(0.0, (-self.lo).max(self.hi))
        }
    }
    /// Bound of `a * a` (never negative, unlike `mul` of the same range).
    pub fn square(self) -> Interval {
        let a = self.abs();
        Interval::new(a.lo * a.lo, a.hi * a.hi)
    }
    /// Bound of the square root of the non-negative part; NaN bound when all
    /// of the range is negative.
    pub fn sqrt(self) -> Interval {
        if self.hi < 0.0 {
            return Interval::nan();
        }
        Interval::new(self.lo.max(0.0).sqrt(), self.hi.sqrt())
    }
    /// Bound of `a^n` by repeated multiplication (keeps the NaN flag).
    pub fn powi(self, n: i32) -> Interval {
        if self.is_nan() {
            return self;
        }
        if n == 0 {
            return Interval::point(1.0);
        }
        // Square-and-multiply (what powi compiles to) rounds monotonically, so
        // the end values bound it; no negation of n, which could overflow.
        integer_power(self, n % 2 != 0, n < 0, |v| v.powi(n)).with_nan(self.nan)
    }
    /// Bound of `min(a, b)`.
    pub fn min(self, o: Interval) -> Interval {
        Interval::new(self.lo.min(o.lo), self.hi.min(o.hi))
    }
    /// Bound of `max(a, b)`.
    pub fn max(self, o: Interval) -> Interval {
        Interval::new(self.lo.max(o.lo), self.hi.max(o.hi))
    }

    /// sin over the interval: extremes where pi/2 + k pi lies inside.
    pub fn sin(self) -> Interval {
        periodic_bounds(self, 0.0, f64::sin)
    }
    /// Bound of cos over the interval.
    pub fn cos(self) -> Interval {
        // cos(t) = sin(t + pi/2): maxima at 2k pi.
        periodic_bounds(self, -FRAC_PI_2, f64::cos)
    }

    /// Sound bound of `op` over this range, NaN flag included; a NaN bound
    /// stays NaN.
    pub fn unary(self, op: UnaryOp) -> Interval {
        if self.is_nan() {
            return self;
        }
        let r = self.unary_values(op);
        if matches!(op, UnaryOp::Sign | UnaryOp::Not) {
            // NaN maps to 0 here: a value, not a NaN.
            return if self.nan {
                r.hull(Interval::point(op.apply(f64::NAN)))
            } else {
                r
            };
        }
        r.with_nan(self.nan || unary_makes_nan(op, self))
    }

    /// Bounds of the non-NaN values of a unary op.
    fn unary_values(self, op: UnaryOp) -> Interval {
        use UnaryOp::*;
        match op {
            Neg => self.neg(),
            Abs => self.abs(),
            Sign => self.mono_inc(ops::sign),
            Sqrt => self.sqrt(),
            Square => self.square(),
            Exp => self.mono_inc(f64::exp).widen().max(Interval::point(0.0)),
            Ln => {
                if self.hi <= 0.0 {
                    // ln(0) = -inf is a value, ln(negative) is NaN.
                    if self.hi == 0.0 {
                        Interval::point(f64::NEG_INFINITY)
                    } else {
                        Interval::nan()
                    }
                } else {
                    Interval::new(self.lo.max(0.0).ln(), self.hi.ln()).widen()
                }
            }
            Sin => self.sin(),
            Cos => self.cos(),
            Tan => {
                // tan is increasing between poles at pi/2 + k pi.
                let k_lo = ((self.lo - FRAC_PI_2) / PI).floor();
                let k_hi = ((self.hi - FRAC_PI_2) / PI).floor();
                let (a, b) = (self.lo.tan(), self.hi.tan());
                // The rounded pole test can misplace an end lying within an ulp
                // of a pole; an inverted pair of values reveals that.
                if k_lo != k_hi || self.width() >= PI || !self.width().is_finite() || a > b {
                    ENTIRE
                } else {
                    Interval::new(a, b).widen()
                }
            }
            Asin => {
                if self.lo > 1.0 || self.hi < -1.0 {
                    Interval::nan()
                } else {
                    Interval::new(self.lo.max(-1.0).asin(), self.hi.min(1.0).asin()).widen()
                }
            }
            Acos => {
                if self.lo > 1.0 || self.hi < -1.0 {
                    Interval::nan()
                } else {
                    Interval::new(self.hi.min(1.0).acos(), self.lo.max(-1.0).acos()).widen()
                }
            }
            Atan => self.mono_inc(f64::atan).widen(),
            Sinh => self.mono_inc(f64::sinh).widen(),
            Cosh => {
                let a = self.abs();
                Interval::new(a.lo.cosh(), a.hi.cosh())
                    .widen()
                    .max(Interval::point(1.0))
            }
            Tanh => self.mono_inc(f64::tanh).widen(),
            Floor => self.mono_inc(f64::floor),
            Ceil => self.mono_inc(f64::ceil),
            Trunc => self.mono_inc(f64::trunc),
            Round => self.mono_inc(f64::round),
            Fract => {
                if self.lo.floor() == self.hi.floor() && self.width().is_finite() {
                    self.mono_inc(|v| v - v.floor())
                } else {
                    UNIT
                }
            }
            Tri => tri_bounds(self),
            Saw => {
                if (self.lo + 0.5).floor() == (self.hi + 0.5).floor() && self.width().is_finite() {
                    self.mono_inc(ops::saw_wave)
                } else {
                    UNIT
                }
            }
            Not => truth_not(self),
        }
    }

    /// Sound bound of `op` over the two ranges, NaN flag included. Comparisons
    /// and logic give a subrange of `[0, 1]`; a NaN argument bound gives a NaN
    /// bound.
    pub fn binary(self, op: BinaryOp, o: Interval) -> Interval {
        use BinaryOp::*;
        if self.is_nan() || o.is_nan() {
            return Interval::nan();
        }
        let r = self.binary_values(op, o);
        let nan_in = self.nan || o.nan;
        if matches!(op, Lt | Le | Gt | Ge | Eq | Ne | And | Or) {
            // Truth values: a NaN argument gives 0 or 1, never NaN.
            return if nan_in { r.hull(UNIT) } else { r };
        }
        r.with_nan(nan_in || binary_makes_nan(op, self, o))
    }

    /// Bounds of the non-NaN values of a binary op.
    fn binary_values(self, op: BinaryOp, o: Interval) -> Interval {
        use BinaryOp::*;
        match op {
            Add => self.add(o),
            Sub => self.sub(o),
            Mul => self.mul(o),
            Div => self.div(o),
            Pow => pow_bounds(self, o),
            Atan2 => atan2_bounds(self, o),
            Min => self.min(o),
            Max => self.max(o),
            Mod => mod_bounds(self, o),
            Rem => {
                let m = o.lo.abs().max(o.hi.abs());
                if m.is_nan() || m <= 0.0 {
                    return Interval::nan();
                }
                let b_apart = o.lo > 0.0 || o.hi < 0.0;
                if b_apart && o.abs().lo > self.abs().hi {
                    // |a| < |b| everywhere: fmod returns a unchanged.
                    return self;
                }
                // fmod is exact: the sign of a, |r| <= |a| and |r| < |b|.
                let lo = if self.lo >= 0.0 { 0.0 } else { self.lo.max(-m) };
                let hi = if self.hi <= 0.0 { 0.0 } else { self.hi.min(m) };
                Interval::new(lo, hi)
            }
            Lt => compare(self.hi < o.lo, self.lo >= o.hi),
            Le => compare(self.hi <= o.lo, self.lo > o.hi),
            Gt => compare(self.lo > o.hi, self.hi <= o.lo),
            Ge => compare(self.lo >= o.hi, self.hi < o.lo),
            Eq => compare(
                self.lo == self.hi && o.lo == o.hi && self.lo == o.lo,
                self.hi < o.lo || self.lo > o.hi,
            ),
            Ne => compare(
                self.hi < o.lo || self.lo > o.hi,
                self.lo == self.hi && o.lo == o.hi && self.lo == o.lo,
            ),
            And => compare(
                definitely_true(self) && definitely_true(o),
                definitely_false(self) || definitely_false(o),
            ),
            Or => compare(
                definitely_true(self) || definitely_true(o),
                definitely_false(self) && definitely_false(o),
            ),
        }
    }

    /// Bounds of the R-function `op(a, b)` with parameter `alpha`.
    ///
    /// For a constant `alpha` in `(-1, 1]` both R-functions are
    /// nondecreasing in each argument (`|a - alpha b| <= sqrt(a^2 + b^2 -
    /// 2 alpha a b)` when `alpha^2 <= 1`), so the values at the lower and at
    /// the upper ends bound them exactly, up to rounding (widened by a
    /// relative 16 ulp of the arguments). This is what makes set operations
    /// tight: plain interval arithmetic on the formula meets each argument
    /// twice and comes out wide, while here the bound has the sign of
    /// `min`/`max` of the arguments' bounds. Otherwise the formula's natural
    /// interval extension is used.
    pub fn set(op: SetOp, a: Interval, b: Interval, alpha: Interval) -> Interval {
        if a.is_nan() || b.is_nan() || alpha.is_nan() {
            return Interval::nan();
        }
        let nan = a.nan || b.nan || alpha.nan;
        let al = alpha.lo;
        if !(al == alpha.hi && al > -1.0 && al <= 1.0) {
            return set_natural(op, a, b, alpha).with_nan(nan);
        }
        let lo = set_end(op, a.lo, b.lo, al);
        let hi = set_end(op, a.hi, b.hi, al);
        let slack = |x: f64, y: f64| 16.0 * f64::EPSILON * (x.abs() + y.abs()) + f64::MIN_POSITIVE;
        // An overflow inside the formula (|args| near 1e154) can give an
        // infinite or NaN end from finite ones: then nothing is claimed there.
        let finite_in = |x: f64, y: f64| x.is_finite() && y.is_finite();
        let lo = if lo.is_finite() {
            lo - slack(a.lo, b.lo)
        } else if finite_in(a.lo, b.lo) || lo.is_nan() {
            f64::NEG_INFINITY
        } else {
            lo
        };
        let hi = if hi.is_finite() {
            hi + slack(a.hi, b.hi)
        } else if finite_in(a.hi, b.hi) || hi.is_nan() {
            f64::INFINITY
        } else {
            hi
        };
        Interval::new(lo, hi).with_nan(nan)
    }

    /// `cond != 0 ? a : b`.
    pub fn select(c: Interval, a: Interval, b: Interval) -> Interval {
        if c.nan {
            // A NaN condition counts as true.
            let r = Interval::select(Interval { nan: false, ..c }, a, b);
            return r.hull(a);
        }
        if definitely_true(c) {
            a
        } else if definitely_false(c) {
            b
        } else {
            a.hull(b)
        }
    }
}

/// The R-function at one pair of interval ends, with its limits where an
/// end is infinite (`x + y - sqrt(...)` would be `inf - inf` there).
fn set_end(op: SetOp, x: f64, y: f64, alpha: f64) -> f64 {
    let inf = f64::INFINITY;
    match op {
        SetOp::Intersection => {
            if x == -inf || y == -inf {
                -inf
            } else if x == inf {
                y
            } else if y == inf {
                x
            } else {
                op.apply(x, y, alpha)
            }
        }
        SetOp::Union => {
            if x == inf || y == inf {
                inf
            } else if x == -inf {
                y
            } else if y == -inf {
                x
            } else {
                op.apply(x, y, alpha)
            }
        }
    }
}

/// The R-function's formula evaluated in interval arithmetic.
fn set_natural(op: SetOp, a: Interval, b: Interval, alpha: Interval) -> Interval {
    let s = a.binary(BinaryOp::Add, b);
    let q = a.square().binary(BinaryOp::Add, b.square());
    let q = if alpha.lo == 0.0 && alpha.hi == 0.0 {
        q
    } else {
        let t = Interval::point(2.0)
            .binary(BinaryOp::Mul, alpha)
            .binary(BinaryOp::Mul, a)
            .binary(BinaryOp::Mul, b);
        q.binary(BinaryOp::Sub, t)
    };
    let r = q.unary(UnaryOp::Sqrt);
    let v = match op {
        SetOp::Union => s.binary(BinaryOp::Add, r),
        SetOp::Intersection => s.binary(BinaryOp::Sub, r),
    };
    if alpha.lo == 0.0 && alpha.hi == 0.0 {
        v
    } else {
        v.binary(
            BinaryOp::Div,
            Interval::point(1.0).binary(BinaryOp::Add, alpha),
        )
    }
}

fn infinite_end(a: Interval) -> bool {
    a.lo == f64::NEG_INFINITY || a.hi == f64::INFINITY
}
fn has_zero(a: Interval) -> bool {
    a.lo <= 0.0 && a.hi >= 0.0
}

/// Whether a unary op can produce NaN from a non-NaN value of `a`.
fn unary_makes_nan(op: UnaryOp, a: Interval) -> bool {
    use UnaryOp::*;
    match op {
        Sqrt | Ln => a.lo < 0.0,
        Asin | Acos => a.lo < -1.0 || a.hi > 1.0,
        // inf - inf inside, or libm's sin(inf).
        Sin | Cos | Tan | Fract | Tri | Saw => infinite_end(a),
        _ => false,
    }
}

/// Whether a binary op can produce NaN from non-NaN values of `a` and `b`.
fn binary_makes_nan(op: BinaryOp, a: Interval, b: Interval) -> bool {
    use BinaryOp::*;
    let (ninf, pinf) = (f64::NEG_INFINITY, f64::INFINITY);
    match op {
        Add => (a.lo == ninf && b.hi == pinf) || (a.hi == pinf && b.lo == ninf),
        Sub => (a.lo == ninf && b.lo == ninf) || (a.hi == pinf && b.hi == pinf),
        Mul => (has_zero(a) && infinite_end(b)) || (has_zero(b) && infinite_end(a)),
        Div => (has_zero(a) && has_zero(b)) || (infinite_end(a) && infinite_end(b)),
        // Negative base with a non-integer exponent.
        Pow => a.lo < 0.0 && !(b.lo == b.hi && b.lo == b.lo.trunc()),
        Mod => has_zero(b) || infinite_end(a) || infinite_end(b),
        Rem => has_zero(b) || infinite_end(a),
        _ => false,
    }
}

fn definitely_true(c: Interval) -> bool {
    !c.is_nan() && (c.lo > 0.0 || c.hi < 0.0)
}
fn definitely_false(c: Interval) -> bool {
    c.lo == 0.0 && c.hi == 0.0
}
fn truth_not(c: Interval) -> Interval {
    compare(definitely_false(c), definitely_true(c))
}
fn compare(always: bool, never: bool) -> Interval {
    if always {
        Interval::point(1.0)
    } else if never {
        Interval::point(0.0)
    } else {
        UNIT
    }
}

/// Bounds of a 2pi-periodic function with maxima at `phase + pi/2 + 2k pi`
/// and minima at `phase - pi/2 + 2k pi` (sin: phase 0, cos: phase -pi/2).
fn periodic_bounds(v: Interval, phase: f64, f: fn(f64) -> f64) -> Interval {
    // NaN widths fail `is_finite` first.
    if !v.lo.is_finite() || !v.hi.is_finite() || v.width() >= 2.0 * PI {
        return Interval::new(-1.0, 1.0);
    }
    let (a, b) = (f(v.lo), f(v.hi));
    let mut lo = a.min(b);
    let mut hi = a.max(b);
    // First peak at or after v.lo: t = phase + pi/2 + 2k pi.
    let has = |offset: f64| {
        let t0 = phase + offset;
        let k = ((v.lo - t0) / (2.0 * PI)).ceil();
        // Compare with some slack: rounding of k*2pi may place the peak a hair off.
        t0 + k * 2.0 * PI <= v.hi + 1e-9 * (1.0 + v.hi.abs())
    };
    if has(FRAC_PI_2) {
        hi = 1.0;
    }
    if has(-FRAC_PI_2) {
        lo = -1.0;
    }
    Interval::new(down(lo).max(-1.0), up(hi).min(1.0))
}

fn tri_bounds(v: Interval) -> Interval {
    if !v.lo.is_finite() || !v.hi.is_finite() || v.width() >= 2.0 {
        return UNIT;
    }
    let (a, b) = (ops::tri_wave(v.lo), ops::tri_wave(v.hi));
    let mut lo = a.min(b);
    let mut hi = a.max(b);
    // Peaks (value 1) at u = 1/2 + 2k, troughs (value 0) at u = -1/2 + 2k.
    let has = |t0: f64| t0 + ((v.lo - t0) / 2.0).ceil() * 2.0 <= v.hi;
    if has(0.5) {
        hi = 1.0;
    }
    if has(-0.5) {
        lo = 0.0;
    }
    // tri_wave rounds in fract: allow an ulp of slack.
    Interval::new(down(lo).max(0.0), up(hi).min(1.0))
}

/// Floored modulo `a - b floor(a/b)`.
fn mod_bounds(a: Interval, b: Interval) -> Interval {
    if b.lo == b.hi && b.lo != 0.0 && b.lo.is_finite() && a.width().is_finite() {
        // With one quotient over the whole box the result is monotone in a.
        let q = b.lo;
        let (q0, q1) = ((a.lo / q).floor(), (a.hi / q).floor());
        if q0 == q1 {
            let (r0, r1) = (a.lo - q * q0, a.hi - q * q0);
            return Interval::new(r0.min(r1), r0.max(r1)).widen();
        }
    }
    // Near b = 0, or when a/b overflows, the result can be anything.
    let amax = a.abs().hi;
    if !(b.lo > 0.0 || b.hi < 0.0) || !(amax / b.abs().lo).is_finite() {
        return ENTIRE;
    }
    // In exact arithmetic the result lies between 0 and b; the rounded
    // quotient and product can leave that range by about 2 ulps of |a|.
    let e = 4.0 * f64::EPSILON * amax;
    if b.lo > 0.0 {
        Interval::new(-e, b.hi + e)
    } else {
        Interval::new(b.lo - e, e)
    }
}

/// Bounds of `f = v^n` for an integer `n` (odd or even, negative or not):
/// `|v|^n` is monotone in `|v|`, odd powers keep the sign, negative powers
/// have a pole at 0.
fn integer_power(a: Interval, odd: bool, neg: bool, f: impl Fn(f64) -> f64) -> Interval {
    let has_zero = a.lo <= 0.0 && a.hi >= 0.0;
    let r = match (odd, neg) {
        (true, false) => Interval::new(f(a.lo), f(a.hi)),
        (false, false) => Interval::new(f(a.abs().lo), f(a.abs().hi)),
        (true, true) if has_zero => ENTIRE,
        (true, true) => Interval::new(f(a.hi), f(a.lo)),
        (false, true) => Interval::new(f(a.abs().hi), f(a.abs().lo)),
    };
    r.widen()
}

fn pow_bounds(a: Interval, b: Interval) -> Interval {
    if b.lo == b.hi && b.lo == b.lo.trunc() && b.lo.is_finite() {
        // powf with an integer exponent follows the sign rules of powi.
        let e = b.lo;
        if e == 0.0 {
            return Interval::point(1.0);
        }
        return integer_power(a, e % 2.0 != 0.0, e < 0.0, |v| v.powf(e));
    }
    // Negative bases give real values only at integer exponents, +-|a|^b;
    // -0 matters too, as (-0)^b is -inf for negative odd b.
    let has_integer = b.lo.ceil() <= b.hi;
    if has_integer && (a.lo < 0.0 || (a.lo == 0.0 && b.lo < 0.0)) {
        let m = nonneg_pow(a.abs(), b);
        return if m.is_nan() {
            ENTIRE
        } else {
            Interval::new(-m.hi, m.hi)
        };
    }
    if a.hi < 0.0 {
        return Interval::nan();
    }
    let r = nonneg_pow(Interval::new(a.lo.max(0.0), a.hi), b);
    if a.lo == f64::NEG_INFINITY {
        // Unlike finite negative bases, (-inf)^b is a value: +inf or +0.
        r.hull(Interval::new(0.0, f64::INFINITY))
    } else {
        r
    }
}

/// `a^b` for `a >= 0`.
fn nonneg_pow(pos: Interval, b: Interval) -> Interval {
    // A -0 end would give (-0)^b, which differs from 0^b in sign.
    let pos = Interval::new(pos.lo.abs(), pos.hi.abs());
    let corners = [
        pos.lo.powf(b.lo),
        pos.lo.powf(b.hi),
        pos.hi.powf(b.lo),
        pos.hi.powf(b.hi),
    ];
    if corners.iter().any(|c| c.is_nan()) {
        return ENTIRE;
    }
    // a^b is monotone in a for fixed b and in b for fixed a, so the extremes
    // over the box lie on its corners.
    let lo = corners.iter().cloned().fold(f64::INFINITY, f64::min);
    let hi = corners.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    Interval::new(down(lo).max(0.0), up(hi))
}

fn atan2_bounds(y: Interval, x: Interval) -> Interval {
    let full = Interval::new(-PI, PI).widen();
    let crosses_cut = x.lo < 0.0 && y.lo <= 0.0 && y.hi >= 0.0;
    let has_origin = x.lo <= 0.0 && x.hi >= 0.0 && y.lo <= 0.0 && y.hi >= 0.0;
    if crosses_cut || has_origin {
        return full;
    }
    let c = [
        y.lo.atan2(x.lo),
        y.lo.atan2(x.hi),
        y.hi.atan2(x.lo),
        y.hi.atan2(x.hi),
    ];
    Interval::new(
        c.iter().cloned().fold(f64::INFINITY, f64::min),
        c.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
    )
    .widen()
}

#[cfg(test)]
mod tests {
    use super::Interval;

    #[test]
    fn f32_ends_hold_the_rounded_coordinates() {
        // 0.1 rounds up in f32, 0.7 rounds down: both ends must move out.
        for (a, b) in [(0.1, 0.7), (-0.7, -0.1), (0.1, 0.1), (1.0, 2.0)] {
            let i = Interval::with_f32_ends(a, b);
            for v in [a, b, a as f32 as f64, b as f32 as f64] {
                assert!(i.lo <= v && v <= i.hi, "{v} outside {i:?}");
            }
            assert!(i.lo >= (a as f32 as f64).min(a) && i.hi <= (b as f32 as f64).max(b));
        }
        assert!(Interval::with_f32_ends(0.1, 0.1).hi > 0.1);
    }
}
