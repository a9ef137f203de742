//! Volume correction of the chordal error. Triangles with their corners on
//! a curved surface lie below it on the convex side (the tori-ball's tubes,
//! 1.3 cells thick at 128^3, lose 1.8 % of their volume). For a surface that
//! is quadratic over a triangle and meets its corners, the mean gap is 3/4
//! of the gap `d` at the centroid; moving every vertex along its normal by
//! the area-weighted mean of 3/4 `d` over its triangles removes that gap to
//! second order. The combinatorics (hence the guarantees) do not change.
//!
//! Work is split so bricks can do it on their own: [`accumulate`] sums each
//! triangle's contribution into its corners' accumulators, the pipeline adds
//! the accumulators of vertices shared with other bricks into their owner's,
//! and [`apply`] moves a vertex once all its triangles have been seen. The
//! sums are in fixed point (integers in units of 2^-24 of the cell's area
//! or volume), so they are exact and do not depend on the order in which a
//! vertex's triangles arrive: the mesh is the same bytes whatever the brick
//! size and the grouping of bricks.

use microfrep_core::{BatchEval, BLOCK};

/// Per-vertex sums: area-weighted normal (x, y, z) and area in units of
/// `h^2 / 2^24`, area times gap in units of `h^3 / 2^24`.
pub type Acc = [i32; 5];

/// Fixed-point units per cell area (or volume).
const UNIT: f32 = (1u32 << 24) as f32;

fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn norm(a: [f32; 3]) -> f32 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

/// Adds the contribution of every triangle of `tris` (indices into `pos`)
/// to `acc` (one entry per position), in triangle order. `h` is the cell
/// size of the grid the triangles were made on.
pub fn accumulate(
    ev: &mut BatchEval,
    pos: &[[f32; 3]],
    tris: &[[u32; 3]],
    h: f64,
    acc: &mut [Acc],
) {
    let step = (h / 8.0) as f32;
    let inv_step = 1.0 / step;
    let limit = (h / 2.0) as f32;
    let to_area = (UNIT as f64 / (h * h)) as f32;
    let to_volume = (UNIT as f64 / (h * h * h)) as f32;
    const HALF: usize = BLOCK / 2;
    let mut an = [[0.0f32; 3]; HALF];
    let mut area = [0.0f32; HALF];
    for chunk in tris.chunks(HALF) {
        let n = chunk.len();
        {
            let (x, y, z) = ev.coords_mut();
            for (i, t) in chunk.iter().enumerate() {
                let [p, q, r] = t.map(|v| pos[v as usize]);
                let c: [f32; 3] = std::array::from_fn(|k| (p[k] + q[k] + r[k]) * (1.0 / 3.0));
                let a = cross(sub(q, p), sub(r, p));
                let len = norm(a);
                (an[i], area[i]) = (a, len);
                let s = step / len;
                (x[i], y[i], z[i]) = (c[0], c[1], c[2]);
                let j = i + n;
                x[j] = c[0] + s * a[0];
                y[j] = c[1] + s * a[1];
                z[j] = c[2] + s * a[2];
            }
        }
        let f = ev.eval_loaded(2 * n);
        let (f0, f1) = f.split_at(n);
        for (i, t) in chunk.iter().enumerate() {
            // Gap along the outward normal from the centroid to the surface,
            // from f and its slope along the normal (one-sided difference).
            let slope = (f1[i] - f0[i]) * inv_step;
            let d = -f0[i] / slope;
            let gap = if slope < 0.0 && d.is_finite() {
                d.clamp(-limit, limit)
            } else {
                0.0
            };
            let (a, w) = (an[i], area[i]);
            let q = |v: f32, unit: f32| (v * unit).round() as i32;
            let add = [
                q(a[0], to_area),
                q(a[1], to_area),
                q(a[2], to_area),
                q(w * gap, to_volume),
                q(w, to_area),
            ];
            for &v in t {
                let s = &mut acc[v as usize];
                for k in 0..5 {
                    s[k] = s[k].saturating_add(add[k]);
                }
            }
        }
    }
}

/// Adds `b` into `a`.
pub fn add(a: &mut Acc, b: &Acc) {
    for k in 0..5 {
        a[k] = a[k].saturating_add(b[k]);
    }
}

/// The displacement of a vertex along its mean normal by 3/4 of its mean
/// gap, from its sums on a grid of cell size `h` (zero where they are
/// degenerate).
pub fn displacement(a: &Acc, h: f64) -> [f32; 3] {
    let n = [a[0] as f64, a[1] as f64, a[2] as f64];
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    if len > 0.0 && a[4] > 0 {
        let d = 0.75 * h * (a[3] as f64 / a[4] as f64) / len;
        if d.is_finite() {
            return n.map(|v| (d * v) as f32);
        }
    }
    [0.0; 3]
}

/// Moves `p` along its mean normal by 3/4 of its mean gap.
pub fn apply(p: &mut [f32; 3], a: &Acc, h: f64) {
    let d = displacement(a, h);
    for k in 0..3 {
        p[k] += d[k];
    }
}

/// Like [`apply`], but no part of the move takes `p` further outside the
/// box `lo..hi` than it is: along an axis where the move would leave the
/// box, it stops at the face (so a vertex on a face slides within it). The
/// correction never pushes a vertex through the box's faces, edges or
/// corners.
pub fn apply_within(p: &mut [f32; 3], a: &Acc, h: f64, lo: [f32; 3], hi: [f32; 3]) {
    let d = displacement(a, h);
    for k in 0..3 {
        let q = p[k] + d[k];
        p[k] = if d[k] > 0.0 {
            q.min(hi[k].max(p[k]))
        } else {
            q.max(lo[k].min(p[k]))
        };
    }
}
