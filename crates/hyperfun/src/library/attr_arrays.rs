//! Attribute helpers that write arrays (LIBRARY.md section 7): colour and
//! attribute setters, interpolation, lookup tables, Catmull-Rom splines,
//! the checker board and the RGB/HSV conversions.
//!
//! The C code writes through its output pointer for as many elements as its
//! loops run, which can pass the end of a short array (undefined behaviour);
//! here writes beyond an array's length are dropped and reads beyond it are
//! NaN ([`el`]).

use super::{el, Arg, Kind::*, Output, Registry};
use microfrep_core::Expr;

fn c(v: f64) -> Expr {
    Expr::constant(v)
}

/// `old` with element `i` replaced by `new(i)` where that gives a value.
pub(super) fn overwrite(old: &[Expr], new: impl Fn(usize) -> Option<Expr>) -> Vec<Expr> {
    (0..old.len())
        .map(|i| new(i).unwrap_or_else(|| old[i].clone()))
        .collect()
}

/// `hfA_SetColor(f, s, r, g, b)`: `s[1..3] = (r, g, b)` where `f >= 0`.
fn set_color(a: &[Arg]) -> Output {
    let f = a[0].real();
    let s = a[1].array();
    let rgb = [a[2].real(), a[3].real(), a[4].real()];
    let on = f.ge(0.0);
    let new = overwrite(s, |i| {
        rgb.get(i)
            .map(|v| Expr::select(on.clone(), v.clone(), s[i].clone()))
    });
    Output::writes(c(1.0), vec![(1, new)])
}

/// `hfA_SetAttributes(f, s, s1)`: copies `s1` into `s` (shorter length)
/// where `f >= 0`.
fn set_attributes(a: &[Arg]) -> Output {
    let f = a[0].real();
    let (s, s1) = (a[1].array(), a[2].array());
    let on = f.ge(0.0);
    let new = overwrite(s, |i| {
        s1.get(i)
            .map(|v| Expr::select(on.clone(), v.clone(), s[i].clone()))
    });
    Output::writes(c(1.0), vec![(1, new)])
}

/// `hfA_Lerp(s, s1, s2, f, fmin, fmax)` (and `hfA_Cerp`, which the
/// reference's function table maps to the same code): `u = (f - fmin) /
/// (fmax - fmin)`; `s = s1` below 0, `s2` above 1, else `(1 - u) s1 + u s2`;
/// returns `u`.
fn lerp(a: &[Arg]) -> Output {
    let (s, s1, s2) = (a[0].array(), a[1].array(), a[2].array());
    let (f, fmin, fmax) = (a[3].real(), a[4].real(), a[5].real());
    let u = (f - &fmin) / (fmax - &fmin);
    let (below, above) = (u.lt(0.0), u.gt(1.0));
    let new = overwrite(s, |i| {
        let (p, q) = (el(s1, i), el(s2, i));
        let mid = (1.0 - &u) * &p + &u * &q;
        Some(Expr::select(
            below.clone(),
            p,
            Expr::select(above.clone(), q, mid),
        ))
    });
    Output::writes(u, vec![(0, new)])
}

/// `hfA_LookUpTable` / `hfA_SmoothLookUpTable(t, out, attrs, map)`: the
/// group of `attrs` (group size = length of `out`) for the first interval
/// `[map[i], map[i+1])` holding `t`, blended linearly with the next group
/// when `smooth`; the last group when no interval holds `t`.
fn lookup(a: &[Arg], smooth: bool) -> Output {
    let t = a[0].real();
    let (out, attrs, map) = (a[1].array(), a[2].array(), a[3].array());
    let dim = out.len();
    let n = map.len();
    let new = overwrite(out, |j| {
        // Not filled by any interval: the last group.
        let mut v = el(attrs, dim * n.saturating_sub(1) + j);
        // The first matching interval wins (the C loop breaks): fold from
        // the last so the first ends outermost.
        for i in (0..n.saturating_sub(1)).rev() {
            let (e0, e1) = (&map[i], &map[i + 1]);
            let hit = t.ge(e0).and(t.lt(e1));
            let here = if smooth {
                let l = (&t - e0) / (e1 - e0);
                (1.0 - &l) * el(attrs, dim * i + j) + &l * el(attrs, dim * (i + 1) + j)
            } else {
                el(attrs, dim * i + j)
            };
            v = Expr::select(hit, here, v);
        }
        // The C code copies the first group when `t` is below the first
        // entry, but its "nothing matched" fallback then overwrites it with
        // the last group; the net effect (kept here) is the last group.
        Some(v)
    });
    Output::writes(c(1.0), vec![(1, new)])
}

fn lookup_table(a: &[Arg]) -> Output {
    lookup(a, false)
}

fn smooth_lookup_table(a: &[Arg]) -> Output {
    lookup(a, true)
}

/// Catmull-Rom basis rows (highest power first), as in the reference.
const CATMULL_ROM: [[f64; 4]; 4] = [
    [-0.5, 1.5, -1.5, 0.5],
    [1.0, -2.5, 2.0, -0.5],
    [-0.5, 0.0, 0.5, 0.0],
    [0.0, 1.0, 0.0, 0.0],
];

/// `hfA_Spline(s, knots, t, tmin, tmax)`: Catmull-Rom spline through the
/// groups of `knots` (group size = length of `s`), parameter
/// `(t - tmin)/(tmax - tmin)`, the end groups outside [0, 1]. At exactly 1
/// the reference jumps back three spans; kept.
fn spline(a: &[Arg]) -> Output {
    let (s, knots) = (a[0].array(), a[1].array());
    let (t, tmin, tmax) = (a[2].real(), a[3].real(), a[4].real());
    let n = s.len();
    if n == 0 {
        // The C code divides by the group size 0.
        return Output::value(c(f64::NAN));
    }
    let size = knots.len() / n;
    let nspans = size as i64 - 3;
    let x = (t - &tmin) / (tmax - &tmin);
    let (below, above) = (x.lt(0.0), x.gt(1.0));
    let xs = &x * nspans as f64;
    let span_of = xs.trunc();
    let new = overwrite(s, |i| {
        let k = |span: i64, m: i64| -> Expr {
            let idx = (span + m) * n as i64 + i as i64;
            if idx < 0 {
                c(f64::NAN)
            } else {
                el(knots, idx as usize)
            }
        };
        let piece = |span: i64| -> Expr {
            let co: Vec<Expr> = CATMULL_ROM
                .iter()
                .map(|row| (0..4).fold(c(0.0), |acc, m| acc + row[m as usize] * k(span, m)))
                .collect();
            let u = &xs - span as f64;
            ((&co[0] * &u + &co[1]) * &u + &co[2]) * &u + &co[3]
        };
        // Span nspans (x = 1) maps to span nspans - 3, as in the C code.
        let mut v = if nspans >= 0 {
            piece(nspans - 3)
        } else {
            c(f64::NAN)
        };
        for span in (0..nspans.max(0)).rev() {
            v = Expr::select(span_of.eq_(span as f64), piece(span), v);
        }
        let last = el(knots, (size.max(1) - 1) * n + i);
        Some(Expr::select(
            below.clone(),
            el(knots, i),
            Expr::select(above.clone(), last, v),
        ))
    });
    Output::writes(c(1.0), vec![(0, new)])
}

/// `hfA_CheckerBoard(p, size, gap, out, c_block, c_gap)`: `out = c_block`
/// where p lies strictly inside the block part of its cell (period
/// `gap + size`) on all three axes, else `c_gap`; nothing is written when
/// the two colour arrays differ in length.
fn checker_board(a: &[Arg]) -> Output {
    let (p, size, gap) = (a[0].array(), a[1].array(), a[2].array());
    let (out, cb, cg) = (a[3].array(), a[4].array(), a[5].array());
    if cb.len() != cg.len() {
        return Output::value(c(1.0));
    }
    let mut inside = c(1.0);
    for k in 0..3 {
        let period = el(gap, k) + el(size, k);
        let lo = &period * (el(p, k) / &period).floor();
        let hi = &lo + el(size, k);
        let pk = el(p, k);
        inside = inside.and(pk.gt(&lo)).and(pk.lt(&hi));
    }
    let new = overwrite(out, |i| {
        (i < cb.len()).then(|| Expr::select(inside.clone(), cb[i].clone(), cg[i].clone()))
    });
    Output::writes(c(1.0), vec![(3, new)])
}

/// `hfA_RGBToHSV(rgb, hsv)`: hue in degrees, saturation, value.
fn rgb_to_hsv(a: &[Arg]) -> Output {
    let (rgb, hsv) = (a[0].array(), a[1].array());
    let (r, g, b) = (el(rgb, 0), el(rgb, 1), el(rgb, 2));
    let lo = Expr::select(g.lt(&b), g.clone(), b.clone());
    let lo = Expr::select(r.lt(&lo), r.clone(), lo);
    let hi = Expr::select(g.gt(&b), g.clone(), b.clone());
    let hi = Expr::select(r.gt(&hi), r.clone(), hi);
    let delta = &hi - &lo;
    let s = Expr::select(hi.gt(0.0), &delta / &hi, c(0.0));
    // The three hue terms add up where their conditions overlap, as in C.
    let term = |cond: Expr, v: Expr| Expr::select(cond, v, c(0.0));
    let h = term(hi.eq_(&r).and(hi.ne_(&g)), (&g - &b) / &delta)
        + term(hi.eq_(&g).and(hi.ne_(&b)), 2.0 + (&b - &r) / &delta)
        + term(hi.eq_(&b).and(hi.ne_(&r)), 4.0 + (&r - &g) / &delta);
    let h = Expr::select(delta.gt(0.0), h * 60.0, c(0.0));
    let vals = [h, s, hi];
    let new = overwrite(hsv, |i| vals.get(i).cloned());
    Output::writes(c(1.0), vec![(1, new)])
}

/// Hue wrapped into [0, 360] as the reference's loops do (`+= 360` while
/// negative, `-= 360` while above 360), in closed form for symbolic hues.
fn wrap_hue(h: &Expr) -> Expr {
    if let Some(mut v) = h.as_const() {
        if v.is_finite() {
            while v < 0.0 {
                v += 360.0;
            }
            while v > 360.0 {
                v -= 360.0;
            }
        }
        return c(v);
    }
    let up = h + 360.0 * (-h / 360.0).ceil();
    let down = h - 360.0 * ((h - 360.0) / 360.0).ceil();
    Expr::select(h.lt(0.0), up, Expr::select(h.gt(360.0), down, h.clone()))
}

/// `hfA_HSVToRGB(hsv, rgb)`: the piecewise-linear hue wheel.
fn hsv_to_rgb(a: &[Arg]) -> Output {
    let (hsv, rgb) = (a[0].array(), a[1].array());
    let (h, s, v) = (wrap_hue(&el(hsv, 0)), el(hsv, 1), el(hsv, 2));
    let (lt120, lt240) = (h.lt(120.0), h.lt(240.0));
    let pick = |p: Expr, q: Expr, r: Expr| {
        Expr::select(lt120.clone(), p, Expr::select(lt240.clone(), q, r))
    };
    let r = pick((120.0 - &h) / 60.0, c(0.0), (&h - 240.0) / 60.0);
    let g = pick(&h / 60.0, (240.0 - &h) / 60.0, c(0.0));
    let b = pick(c(0.0), (&h - 120.0) / 60.0, (360.0 - &h) / 60.0);
    let chan = |x: Expr| {
        let x = Expr::select(x.lt(1.0), x, c(1.0));
        (1.0 - &s + &s * x) * &v
    };
    let vals = [chan(r), chan(g), chan(b)];
    let new = overwrite(rgb, |i| vals.get(i).cloned());
    Output::writes(c(1.0), vec![(1, new)])
}

pub(super) fn register(r: &mut Registry) {
    r.register("hfa_setcolor", &[R, A, R, R, R], set_color);
    r.register("hfa_setattributes", &[R, A, A], set_attributes);
    r.register("hfa_lerp", &[A, A, A, R, R, R], lerp);
    r.register("hfa_cerp", &[A, A, A, R, R, R], lerp);
    r.register("hfa_lookuptable", &[R, A, A, A], lookup_table);
    r.register("hfa_smoothlookuptable", &[R, A, A, A], smooth_lookup_table);
    r.register("hfa_spline", &[A, A, R, R, R], spline);
    r.register("hfa_checkerboard", &[A, A, A, A, A, A], checker_board);
    r.register("hfa_rgbtohsv", &[A, A], rgb_to_hsv);
    r.register("hfa_hsvtorgb", &[A, A], hsv_to_rgb);
}
