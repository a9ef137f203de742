//! SARDEF operations (signed approximate real distance functions, Fayolle et
//! al.; LIBRARY.md section 4): `hfDUni`, `hfDInt`, `hfDSub`. Their case
//! analysis and the quartic branch (whose root is picked by position in the
//! reference solver's output) are computed on numbers, so a model using them
//! evaluates through the per-point fallback.

use super::{Arg, Kind::*, Output, Registry};
use microfrep_core::Expr;

/// "Zero" in the case analysis.
const TINY: f64 = 1e-7;

/// `a / b` with `0 / x = 0`, as the reference solver divides.
fn div(a: f64, b: f64) -> f64 {
    if a == 0.0 {
        0.0
    } else {
        a / b
    }
}

/// Real roots of `c2 x^2 + c1 x + c0`, the `+sqrt` root first.
fn quadratic(c2: f64, c1: f64, c0: f64, out: &mut Vec<f64>) {
    if c2 == 0.0 {
        if c1 != 0.0 {
            out.push(div(-c0, c1));
        }
        return;
    }
    let d = c1 * c1 - 4.0 * c2 * c0;
    if d == 0.0 {
        out.push(div(-c1, 2.0 * c2));
    } else if d > 0.0 {
        out.push(div(-c1 + d.sqrt(), 2.0 * c2));
        out.push(div(-c1 - d.sqrt(), 2.0 * c2));
    }
}

/// Real roots of a cubic in the order the reference produces them
/// (trigonometric form for three roots, Cardano for one).
fn cubic(c3: f64, c2: f64, c1: f64, c0: f64) -> Vec<f64> {
    let mut out = Vec::new();
    if c3 == 0.0 {
        quadratic(c2, c1, c0, &mut out);
    } else if c2 == 0.0 && c1 == 0.0 {
        out.push(div(-c0, c3).cbrt());
    } else if c0 == 0.0 {
        out.push(0.0);
        let mut q = Vec::new();
        quadratic(c3, c2, c1, &mut q);
        out.extend(q.into_iter().filter(|&r| r != 0.0));
    } else {
        let (k, p, q) = if c2 != 0.0 {
            (
                div(-c2, 3.0 * c3),
                div(3.0 * c3 * c1 - c2 * c2, -3.0 * c3 * c3),
                div(
                    2.0 * c2 * c2 * c2 - 9.0 * c3 * c2 * c1 + 27.0 * c3 * c3 * c0,
                    -27.0 * c3 * c3 * c3,
                ),
            )
        } else {
            (0.0, div(-c1, c3), div(-c0, c3))
        };
        let p3 = p * p / 27.0 * p;
        let w = q / 4.0 * q - p3;
        if w < 0.0 {
            let a = div(q, 2.0 * p3.sqrt()).acos() / 3.0;
            let t = (p * 1.33333333333333).sqrt();
            let pi = std::f64::consts::PI;
            out.push(t * a.cos() + k);
            out.push(t * (a + 2.0 * pi / 3.0).cos() + k);
            out.push(t * (a + 4.0 * pi / 3.0).cos() + k);
        } else if w == 0.0 {
            out.push(2.0 * (q / 2.0).cbrt() + k);
        } else {
            out.push((q / 2.0 + w.sqrt()).cbrt() + (q / 2.0 - w.sqrt()).cbrt() + k);
        }
    }
    out
}

/// Real roots of the monic-normalised quartic via its resolvent cubic, in
/// the reference order: roots of the first quadratic factor, then the second.
fn quartic(c4: f64, c3: f64, c2: f64, c1: f64, c0: f64) -> Vec<f64> {
    if c0 == 0.0 {
        let mut out = vec![0.0];
        out.extend(cubic(c4, c3, c2, c1).into_iter().filter(|&r| r != 0.0));
        return out;
    }
    let (a3, a2, a1, a0) = (div(c3, c4), div(c2, c4), div(c1, c4), div(c0, c4));
    let cb = cubic(
        -8.0,
        4.0 * a2,
        8.0 * a0 - 2.0 * a1 * a3,
        a1 * a1 - a0 * (4.0 * a2 - a3 * a3),
    );
    let hi = cb.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let mut out = Vec::new();
    if hi * hi > a0 {
        let b = (hi * hi - a0).sqrt();
        let m = div(a3 * hi - a1, 2.0 * b);
        quadratic(1.0, a3 / 2.0 + m, hi + b, &mut out);
        quadratic(1.0, a3 / 2.0 - m, hi - b, &mut out);
    }
    out
}

/// Root number 1 of the quartic (NaN when there is none: the reference
/// would read stale memory).
fn quartic_root1(c3: f64, c2: f64, c1: f64, c0: f64) -> f64 {
    quartic(1.0, c3, c2, c1, c0)
        .get(1)
        .copied()
        .unwrap_or(f64::NAN)
}

fn union(x: f64, y: f64, r: f64, alpha: f64) -> f64 {
    let (zx, zy) = (x.abs() < TINY, y.abs() < TINY);
    if zx && zy {
        return 0.0;
    }
    if zx {
        return if y > 0.0 { y } else { 0.0 };
    }
    if zy {
        return if x > 0.0 { x } else { 0.0 };
    }
    if x < 0.0 && y > 0.0 {
        return y;
    }
    if x > 0.0 && y < 0.0 {
        return x;
    }
    if x > 0.0 {
        let (t, gt) = (alpha.tan(), x / y);
        if gt < 1.0 / t && gt > t {
            let (a, b, c) = (t * t + 2.0 * t - 1.0, -2.0 * t * (x + y), x * x + y * y);
            return (-b - (b * b - 4.0 * a * c).sqrt()) / (2.0 * a);
        }
        return if gt >= 1.0 / t { x } else { y };
    }
    let lim2 = (x + 2.0 * r).powi(2) + (y + 2.0 * r).powi(2);
    if x >= -r || y >= -r || (x >= -2.0 * r && y >= -2.0 * r && lim2 >= r * r) {
        let (xx, yy) = (-x * x / (4.0 * r), -y * y / (4.0 * r));
        if x <= yy && y <= xx {
            let sr = r.sqrt();
            let m = quartic_root1(-4.0 * sr, -4.0 * r, -4.0 * sr * (x + y), -(x * x + y * y));
            return -m * m;
        }
        if y > xx {
            return y;
        }
        if yy < x {
            return x;
        }
        return 0.0;
    }
    if y <= x + r && y >= x - r {
        let (b, c) = (
            -2.0 * x - 4.0 * r - 2.0 * y,
            x * x + y * y + r * r + 2.0 * x * r + 2.0 * y * r,
        );
        let ds = b * b - 8.0 * c;
        return if ds >= 0.0 {
            (-b - ds.sqrt()) / 4.0
        } else {
            0.0
        };
    }
    if y < x - r {
        x
    } else {
        y
    }
}

fn intersection(x: f64, y: f64, r: f64, alpha: f64) -> f64 {
    let (zx, zy) = (x.abs() < TINY, y.abs() < TINY);
    if zx && zy {
        return 0.0;
    }
    if zy {
        return if x > 0.0 { 0.0 } else { x };
    }
    if zx {
        return if y > 0.0 { 0.0 } else { y };
    }
    if x < 0.0 && y > 0.0 {
        return x;
    }
    if y < 0.0 && x > 0.0 {
        return y;
    }
    if x > 0.0 {
        let lim = (x - 2.0 * r).powi(2) + (y - 2.0 * r).powi(2);
        if x <= r || y <= r || (x <= 2.0 * r && y <= 2.0 * r && lim >= r * r) {
            let (xx, yy) = (x * x / (4.0 * r), y * y / (4.0 * r));
            if xx <= y && yy <= x {
                let sr = r.sqrt();
                let m = quartic_root1(-4.0 * sr, -4.0 * r, 4.0 * sr * (x + y), -(x * x + y * y));
                return m * m;
            }
            if xx > y {
                return y;
            }
            if yy > x {
                return x;
            }
            return 0.0;
        }
        if (y - x).abs() <= r {
            let (b, c) = (
                -2.0 * x + 4.0 * r - 2.0 * y,
                x * x + y * y + r * r - 2.0 * x * r - 2.0 * y * r,
            );
            let ds = b * b - 8.0 * c;
            return if ds >= 0.0 {
                (-b + ds.sqrt()) / 4.0
            } else {
                0.0
            };
        }
        return if y < x - r { y } else { x };
    }
    let (t, gt) = (alpha.tan(), x / y);
    if gt < 1.0 / t && gt > t {
        let (a, b, c) = (1.0 - t * t - 2.0 * t, 2.0 * t * (x + y), -x * x - y * y);
        return (-b - (b * b - 4.0 * a * c).sqrt()) / (2.0 * a);
    }
    if gt >= 1.0 / t {
        x
    } else {
        y
    }
}

/// Applies `op` to constant arguments; symbolic ones need the fallback.
fn numeric(a: &[Arg], negate_second: bool, op: fn(f64, f64, f64, f64) -> f64) -> Output {
    let mut v = [0.0; 4];
    for (slot, arg) in v.iter_mut().zip(a) {
        match arg.real().as_const() {
            Some(c) => *slot = c,
            None => return Output::needs_constants(),
        }
    }
    let y = if negate_second { -v[1] } else { v[1] };
    Output::value(Expr::constant(op(v[0], y, v[2], v[3])))
}

pub(super) fn register(r: &mut Registry) {
    r.register("hfduni", &[R, R, R, R], |a| numeric(a, false, union));
    r.register("hfdint", &[R, R, R, R], |a| numeric(a, false, intersection));
    r.register("hfdsub", &[R, R, R, R], |a| numeric(a, true, intersection));
}
