//! Crease detection and refinement for [`crate::measure`]: the centre
//! samples of surface cells, the test that tells a crease (min, max,
//! R-function edge) or unresolved curvature from a smooth surface, the
//! halving of a cell into eight sampled children, and the refinement of the
//! zero crossings on the cells' edges to roots of the field ([`roots`]).

use crate::grid::Grid;
use crate::measure::{cell, Ctx};

/// Threshold on a cell's departure from linear, relative to its change
/// across the cell, above which the cell holds a crease and is refined.
const KINK: f64 = 0.1;

/// Samples the 27 nodes of the cell's halving and the centres of its eight
/// children, and sums the children.
pub(crate) fn split(
    ctx: &mut Ctx,
    p0: [f64; 3],
    h: [f64; 3],
    f: &[f64; 8],
    r: &[f64; 8],
    depth: u32,
) -> [f64; 3] {
    let s = &mut *ctx.s;
    s.xs.clear();
    s.ys.clear();
    s.zs.clear();
    let mut push = |t: [f64; 3]| {
        s.xs.push((p0[0] + h[0] * t[0]) as f32);
        s.ys.push((p0[1] + h[1] * t[1]) as f32);
        s.zs.push((p0[2] + h[2] * t[2]) as f32);
    };
    for k in 0..3 {
        for j in 0..3 {
            for i in 0..3 {
                push([i, j, k].map(|v| 0.5 * v as f64));
            }
        }
    }
    for c in 0..8 {
        push([c & 1, (c >> 1) & 1, (c >> 2) & 1].map(|v| 0.25 + 0.5 * v as f64));
    }
    let mut fv = [0.0f32; 35];
    let mut rv = [f32::INFINITY; 35];
    eval_both(ctx, &mut fv, &mut rv);
    // Keep the parent's corner values exactly (the same f32 samples).
    for c in 0..8 {
        let at = 2 * (c & 1) + 3 * 2 * ((c >> 1) & 1) + 9 * 2 * ((c >> 2) & 1);
        fv[at] = f[c] as f32;
        rv[at] = r[c] as f32;
    }
    let half = h.map(|v| 0.5 * v);
    let mut sum = [0.0; 3];
    for child in 0..8 {
        let o = [child & 1, (child >> 1) & 1, (child >> 2) & 1];
        let at =
            |c: usize| (o[0] + (c & 1)) + 3 * (o[1] + ((c >> 1) & 1)) + 9 * (o[2] + ((c >> 2) & 1));
        let cf: [f64; 8] = std::array::from_fn(|c| fv[at(c)] as f64);
        let cr: [f64; 8] = std::array::from_fn(|c| rv[at(c)] as f64);
        let centre = [fv[27 + child] as f64, rv[27 + child] as f64];
        let p: [f64; 3] = std::array::from_fn(|a| p0[a] + half[a] * o[a] as f64);
        let m = cell(ctx, p, half, &cf, &cr, centre, depth + 1);
        for q in 0..3 {
            sum[q] += m[q];
        }
    }
    sum
}

/// Evaluates the solid and the region (where they vary) at the points in
/// the scratch coordinates; constants elsewhere.
pub(crate) fn eval_both(ctx: &mut Ctx, fv: &mut [f32], rv: &mut [f32]) {
    let s = &mut *ctx.s;
    fv.fill(ctx.solid_const);
    rv.fill(f32::INFINITY);
    if ctx.eval_solid {
        s.solid_ev.eval(&s.xs, &s.ys, &s.zs, fv);
        no_nan(fv);
    }
    if ctx.with_region {
        if let Some(ev) = &mut s.region_ev {
            ev.eval(&s.xs, &s.ys, &s.zs, rv);
            no_nan(rv);
        }
    }
}

/// Where a model is undefined (NaN) it is outside, far from its surface:
/// the most negative finite value keeps the interpolation finite.
pub(crate) fn no_nan(v: &mut [f32]) {
    for x in v.iter_mut().filter(|x| x.is_nan()) {
        *x = -f32::MAX;
    }
}

/// Values at the centres of the brick's fine cells, then of its coarse
/// cells, where the cell's corners differ in sign (NaN elsewhere): the
/// crease test of [`cell`] needs them.
pub(crate) fn sample_centers(
    g: &Grid,
    ctx: &mut Ctx,
    lo: [usize; 3],
    n: [usize; 3],
) -> Vec<[f64; 2]> {
    let idx = |i: usize, j: usize, k: usize| i + n[0] * (j + n[1] * k);
    let mut slots = Vec::new();
    ctx.s.xs.clear();
    ctx.s.ys.clear();
    ctx.s.zs.clear();
    let mut slot = 0;
    for step in [1, 2] {
        for k in (0..n[2] - 1).step_by(step) {
            for j in (0..n[1] - 1).step_by(step) {
                for i in (0..n[0] - 1).step_by(step) {
                    let at = |c: usize| {
                        idx(
                            i + step * (c & 1),
                            j + step * ((c >> 1) & 1),
                            k + step * ((c >> 2) & 1),
                        )
                    };
                    let s = &*ctx.s;
                    let (mut fpos, mut rpos, mut mpos) = (0, 0, 0);
                    for c in 0..8 {
                        let (f, r) = (s.f[at(c)], s.r[at(c)]);
                        fpos += (f >= 0.0) as usize;
                        rpos += (r >= 0.0) as usize;
                        mpos += (f.min(r) >= 0.0) as usize;
                    }
                    if [fpos, rpos, mpos].iter().any(|&p| p != 0 && p != 8) {
                        let p0 = g.node([lo[0] + i, lo[1] + j, lo[2] + k]);
                        let s = &mut *ctx.s;
                        s.xs.push((p0[0] + 0.5 * step as f64 * g.step[0]) as f32);
                        s.ys.push((p0[1] + 0.5 * step as f64 * g.step[1]) as f32);
                        s.zs.push((p0[2] + 0.5 * step as f64 * g.step[2]) as f32);
                        slots.push(slot);
                    }
                    slot += 1;
                }
            }
        }
    }
    let n = slots.len();
    let (mut fv, mut rv) = (vec![0.0f32; n], vec![f32::INFINITY; n]);
    eval_both(ctx, &mut fv, &mut rv);
    let mut out = vec![[f64::NAN; 2]; slot];
    for (q, &sl) in slots.iter().enumerate() {
        out[sl] = [fv[q] as f64, rv[q] as f64];
    }
    out
}

/// Whether the field has a crease (min, max, R-function edge) in the cell
/// rather than a smooth curve: the centre value or a corner value departs
/// from the best linear fit of the corners by more than [`KINK`] times the
/// fit's change across the cell. Smooth fields depart by O(h^2) only.
pub(crate) fn creased(v: &[f64; 8], center: f64) -> bool {
    let mean = v.iter().sum::<f64>() / 8.0;
    let mut g = [0.0; 3];
    for (a, ga) in g.iter_mut().enumerate() {
        let bit = 1 << a;
        *ga = (0..8)
            .filter(|c| c & bit == 0)
            .map(|c| v[c | bit] - v[c])
            .sum::<f64>()
            / 4.0;
    }
    let change = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
    let corners = (0..8)
        .map(|c| {
            let lin = mean
                + (0..3)
                    .map(|a| g[a] * (((c >> a) & 1) as f64 - 0.5))
                    .sum::<f64>();
            (v[c] - lin).abs()
        })
        .fold(0.0, f64::max);
    let residual = corners.max((center - mean).abs());
    residual.is_nan() || residual > KINK * change
}

/// Illinois steps (each one batch evaluation of every segment) that refine
/// a zero crossing after its linear estimate.
pub(crate) const ROOT_STEPS: usize = 3;

/// A segment from `a` to `a + d` with field values `fa` and `fb` at its
/// ends, of opposite signs (`fa >= 0` or `fb >= 0`, not both).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Seg {
    pub(crate) a: [f64; 3],
    pub(crate) d: [f64; 3],
    pub(crate) fa: f64,
    pub(crate) fb: f64,
}

/// The parameter in `[0, 1]` from `a` where the solid's field (the
/// region's with `region`) changes sign on each segment: the linear
/// estimate refined by [`ROOT_STEPS`] steps of the Illinois method, every
/// step one batch evaluation of all the segments. Where the field is
/// linear the first estimate is its root already; elsewhere the bracket
/// keeps the result on the segment, and between samples of opposite signs.
///
/// `slope` gets the field's derivative in the parameter at each root: the
/// secant from the root to the first estimate, or across the segment where
/// that estimate was already on the root.
pub(crate) fn roots(
    ctx: &mut Ctx,
    region: bool,
    segs: &[Seg],
    out: &mut Vec<f64>,
    slope: &mut Vec<f64>,
) {
    // Bracket (t_lo, f_lo, t_hi, f_hi) and the side kept last (-1, 0, 1).
    let mut br: Vec<([f64; 4], i8)> = segs.iter().map(|s| ([0.0, s.fa, 1.0, s.fb], 0)).collect();
    let secant = |b: &[f64; 4]| {
        let t = b[0] + (b[2] - b[0]) * b[1] / (b[1] - b[3]);
        if t.is_finite() {
            t.clamp(b[0], b[2])
        } else {
            0.5 * (b[0] + b[2])
        }
    };
    let mut v = std::mem::take(&mut ctx.s.root_vals);
    let evaluates = if region {
        ctx.with_region
    } else {
        ctx.eval_solid
    };
    let steps = if evaluates { ROOT_STEPS } else { 0 };
    // The first estimate and the field there.
    let mut first: Vec<(f64, f64)> = Vec::new();
    for step in 0..steps {
        let s = &mut *ctx.s;
        s.xs.clear();
        s.ys.clear();
        s.zs.clear();
        out.clear();
        for (seg, (b, _)) in segs.iter().zip(&br) {
            let t = secant(b);
            out.push(t);
            s.xs.push((seg.a[0] + t * seg.d[0]) as f32);
            s.ys.push((seg.a[1] + t * seg.d[1]) as f32);
            s.zs.push((seg.a[2] + t * seg.d[2]) as f32);
        }
        v.clear();
        v.resize(segs.len(), 0.0);
        let ev = if region {
            s.region_ev.as_mut()
        } else {
            Some(&mut s.solid_ev)
        };
        if let Some(ev) = ev {
            ev.eval(&s.xs, &s.ys, &s.zs, &mut v);
        }
        no_nan(&mut v);
        if step == 0 {
            first.extend(out.iter().zip(v.iter()).map(|(&t, &fv)| (t, fv as f64)));
        }
        for ((b, last), (&t, &fv)) in br.iter_mut().zip(out.iter().zip(v.iter())) {
            let fv = fv as f64;
            if (fv >= 0.0) == (b[1] >= 0.0) {
                b[0] = t;
                b[1] = fv;
                if *last == -1 {
                    b[3] *= 0.5;
                }
                *last = -1;
            } else {
                b[2] = t;
                b[3] = fv;
                if *last == 1 {
                    b[1] *= 0.5;
                }
                *last = 1;
            }
        }
    }
    ctx.s.root_vals = v;
    out.clear();
    out.extend(br.iter().map(|(b, _)| secant(b)));
    slope.clear();
    for (k, (&t, s)) in out.iter().zip(segs).enumerate() {
        let chord = s.fb - s.fa;
        slope.push(match first.get(k) {
            Some(&(t1, f1)) if (t1 - t).abs() > 1e-3 && f1.is_finite() => f1 / (t1 - t),
            _ => chord,
        });
    }
}
