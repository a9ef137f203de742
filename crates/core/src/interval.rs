//! Interval arithmetic with sound bounds.
//!
//! Contract: for every op, the result contains the f64 reference value
//! (`ops.rs`) at every point of the argument boxes where that value is not NaN.
//! A NaN bound means "nothing is known" (consumers must treat it as the whole
//! line). IEEE `+ - * /` and `sqrt` are correctly rounded and monotone, so their
//! endpoint formulas bound the point values exactly; libm functions are only
//! faithful, so their results are widened by a few ulps.

use crate::ops::{self, BinaryOp, UnaryOp};
use std::f64::consts::{FRAC_PI_2, PI};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval {
    pub lo: f64,
    pub hi: f64,
}

const ENTIRE: Interval = Interval {
    lo: f64::NEG_INFINITY,
    hi: f64::INFINITY,
};
const UNIT: Interval = Interval { lo: 0.0, hi: 1.0 };

fn down(v: f64) -> f64 {
    v.next_down().next_down()
}
fn up(v: f64) -> f64 {
    v.next_up().next_up()
}

impl Interval {
    pub const ENTIRE: Interval = ENTIRE;

    pub fn new(lo: f64, hi: f64) -> Interval {
        Interval { lo, hi }
    }
    pub fn point(v: f64) -> Interval {
        Interval { lo: v, hi: v }
    }
    pub fn nan() -> Interval {
        Interval {
            lo: f64::NAN,
            hi: f64::NAN,
        }
    }
    pub fn is_nan(&self) -> bool {
        self.lo.is_nan() || self.hi.is_nan()
    }
    pub fn contains(&self, v: f64) -> bool {
        self.is_nan() || (self.lo <= v && v <= self.hi)
    }
    pub fn width(&self) -> f64 {
        self.hi - self.lo
    }
    pub fn mid(&self) -> f64 {
        0.5 * (self.lo + self.hi)
    }
    pub fn hull(self, o: Interval) -> Interval {
        if self.is_nan() || o.is_nan() {
            return Interval::nan();
        }
        Interval::new(self.lo.min(o.lo), self.hi.max(o.hi))
    }
    /// Widens by two ulps on each side (for libm results).
    fn widen(self) -> Interval {
        Interval::new(down(self.lo), up(self.hi))
    }
    /// Applies a nondecreasing function to both ends.
    fn mono_inc(self, f: impl Fn(f64) -> f64) -> Interval {
        Interval::new(f(self.lo), f(self.hi))
    }

    pub fn neg(self) -> Interval {
        Interval::new(-self.hi, -self.lo)
    }
    pub fn add(self, o: Interval) -> Interval {
        Interval::new(self.lo + o.lo, self.hi + o.hi)
    }
    pub fn sub(self, o: Interval) -> Interval {
        Interval::new(self.lo - o.hi, self.hi - o.lo)
    }
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
    pub fn recip(self) -> Interval {
        Interval::point(1.0).div(self)
    }
    pub fn div(self, o: Interval) -> Interval {
        if o.lo <= 0.0 && o.hi >= 0.0 {
            return if o.lo == 0.0 && o.hi == 0.0 && self.lo > 0.0 {
                // x / 0 with x > 0 is +inf or -inf depending on the zero's sign.
                ENTIRE
            } else {
                ENTIRE
            };
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
    pub fn abs(self) -> Interval {
        if self.lo >= 0.0 {
            self
        } else if self.hi <= 0.0 {
            self.neg()
        } else {
            Interval::new(0.0, (-self.lo).max(self.hi))
        }
    }
    pub fn square(self) -> Interval {
        let a = self.abs();
        Interval::new(a.lo * a.lo, a.hi * a.hi)
    }
    pub fn sqrt(self) -> Interval {
        if self.hi < 0.0 {
            return Interval::nan();
        }
        Interval::new(self.lo.max(0.0).sqrt(), self.hi.sqrt())
    }
    pub fn powi(self, n: i32) -> Interval {
        if n == 0 {
            return Interval::point(1.0);
        }
        if n < 0 {
            return self.powi(-n).recip().widen();
        }
        let base = if n % 2 == 0 { self.abs() } else { self };
        // powi is not guaranteed correctly rounded: widen.
        Interval::new(base.lo.powi(n), base.hi.powi(n)).widen()
    }
    pub fn min(self, o: Interval) -> Interval {
        Interval::new(self.lo.min(o.lo), self.hi.min(o.hi))
    }
    pub fn max(self, o: Interval) -> Interval {
        Interval::new(self.lo.max(o.lo), self.hi.max(o.hi))
    }

    /// sin over the interval: extremes where pi/2 + k pi lies inside.
    pub fn sin(self) -> Interval {
        periodic_bounds(self, 0.0, f64::sin)
    }
    pub fn cos(self) -> Interval {
        periodic_bounds(self, FRAC_PI_2, f64::cos)
    }

    pub fn unary(self, op: UnaryOp) -> Interval {
        use UnaryOp::*;
        if self.is_nan() {
            return self;
        }
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
                if k_lo != k_hi || self.width() >= PI || !self.width().is_finite() {
                    ENTIRE
                } else {
                    self.mono_inc(f64::tan).widen()
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

    pub fn binary(self, op: BinaryOp, o: Interval) -> Interval {
        use BinaryOp::*;
        if self.is_nan() || o.is_nan() {
            return Interval::nan();
        }
        match op {
            Add => self.add(o),
            Sub => self.sub(o),
            Mul => self.mul(o),
            Div => self.div(o),
            Pow => pow_bounds(self, o),
            Atan2 => atan2_bounds(self, o),
            Min => self.min(o),
            Max => self.max(o),
            Mod => {
                // a - b floor(a/b): exact when a single period holds a, else [0, b) or (b, 0].
                if o.lo == o.hi && o.lo != 0.0 && o.lo.is_finite() {
                    let b = o.lo;
                    let (q0, q1) = ((self.lo / b).floor(), (self.hi / b).floor());
                    if q0 == q1 && self.width().is_finite() {
                        let (a0, a1) = (self.lo - b * q0, self.hi - b * q0);
                        return Interval::new(a0.min(a1), a0.max(a1)).widen();
                    }
                }
                let m = o.lo.abs().max(o.hi.abs());
                if o.lo > 0.0 {
                    Interval::new(0.0, o.hi)
                } else if o.hi < 0.0 {
                    Interval::new(o.lo, 0.0)
                } else {
                    Interval::new(-m, m)
                }
            }
            Rem => {
                let m = o.lo.abs().max(o.hi.abs());
                if !(m > 0.0) {
                    return Interval::nan();
                }
                if self.lo > -m && self.hi < m && o.lo.abs().min(o.hi.abs()) > self.abs().hi {
                    // |a| < |b| everywhere: fmod returns a unchanged.
                    return self;
                }
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

    /// `cond != 0 ? a : b`.
    pub fn select(c: Interval, a: Interval, b: Interval) -> Interval {
        if definitely_true(c) {
            a
        } else if definitely_false(c) {
            b
        } else {
            a.hull(b)
        }
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
/// and minima at `phase - pi/2 + 2k pi` (sin: phase 0, cos: phase pi/2).
fn periodic_bounds(v: Interval, phase: f64, f: fn(f64) -> f64) -> Interval {
    if !(v.width() < 2.0 * PI) || !v.lo.is_finite() || !v.hi.is_finite() {
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
    if !(v.width() < 2.0) || !v.lo.is_finite() {
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

fn pow_bounds(a: Interval, b: Interval) -> Interval {
    if b.lo == b.hi && b.lo == b.lo.trunc() && b.lo.abs() < 1e9 {
        // powf with an integer exponent agrees with the sign rules of powi.
        let n = b.lo as i32;
        let r = a.powi(n);
        return r.hull(a.powi(n)).widen();
    }
    if a.hi < 0.0 {
        return Interval::nan();
    }
    // For a >= 0: a^b = exp(b ln a); treat ln(0) = -inf.
    let pos = Interval::new(a.lo.max(0.0), a.hi);
    let corners = [
        pos.lo.powf(b.lo),
        pos.lo.powf(b.hi),
        pos.hi.powf(b.lo),
        pos.hi.powf(b.hi),
    ];
    let mut lo = corners.iter().cloned().fold(f64::INFINITY, f64::min);
    let mut hi = corners.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    // a^b is monotone in a for fixed b and in b for fixed a, except that the
    // direction in b flips at a = 1 and the direction in a flips at b = 0: the
    // extremes still lie on corners, plus the value 1 when a or b crosses.
    if (pos.lo <= 1.0 && pos.hi >= 1.0) || (b.lo <= 0.0 && b.hi >= 0.0) {
        lo = lo.min(1.0);
        hi = hi.max(1.0);
    }
    if corners.iter().any(|c| c.is_nan()) {
        return ENTIRE;
    }
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
