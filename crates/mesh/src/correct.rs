//! Volume correction of the chordal error. Triangles with their corners on
//! a curved surface lie below it on the convex side (the tori-ball's tubes,
//! 1.3 cells thick at 128^3, lose 1.8 % of their volume). For a surface that
//! is quadratic over a triangle and meets its corners, the mean gap is 3/4
//! of the gap `d` at the centroid; moving every vertex along its normal by
//! the area-weighted mean of 3/4 `d` over its triangles removes that gap to
//! second order. The combinatorics (hence the guarantees) do not change.
//!
//! Work is split so bricks can do it on their own: a brick's
//! [`accumulate`] sums each of its triangles' contribution into its
//! corners' accumulators, the pipeline adds the accumulators of vertices
//! shared with other bricks into their owner's, and [`apply_all`] moves
//! the vertices once all their triangles have been seen (in the brick
//! itself for vertices no other brick touches). The
//! sums are in fixed point (integers in units of 2^-24 of the cell's area
//! or volume), so they are exact and do not depend on the order in which a
//! vertex's triangles arrive: the mesh is the same bytes whatever the brick
//! size and the grouping of bricks.

use crate::lanes::select;
use microfrep_core::{BatchEval, BLOCK};

/// Per-vertex sums: area-weighted normal (x, y, z) and area in units of
/// `h^2 / 2^24`, area times gap in units of `h^3 / 2^24`, and the number
/// of the vertex's triangles that lie in sharp-feature fans
/// ([`crate::sharp`]; such vertices are not moved). A vertex's
/// triangles lie in the few cells around its grid edge (at most 24 of
/// them, none larger than a cell's largest cross-section, sqrt 3 cell
/// areas; gaps at most half a cell), so every sum stays under 2^30 and
/// plain wrapping adds are exact, in any order.
pub type Acc = [i32; 6];

/// The squared ratio of the summed area normal's length to the summed area
/// above which a vertex's triangles count as coplanar (cosine of a quarter
/// degree, squared).
const FLAT: f32 = 0.999_981;

/// Fixed-point units per cell area (or volume).
const UNIT: f32 = (1u32 << 24) as f32;
/// Bound of a quantised contribution (far above any real one: a triangle
/// within a cell has at most sqrt 3 cell areas).
const LIMIT: f32 = (1u32 << 30) as f32;

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
///
/// A block of triangles at a time, in columns (one array per quantity), so
/// the arithmetic before and after the evaluation vectorises; only the
/// gathering of corners and the scattering of sums are scalar.
pub fn accumulate(
    ev: &mut BatchEval,
    pos: &[[f32; 3]],
    tris: &[[u32; 3]],
    h: f64,
    acc: &mut [Acc],
) {
    const HALF: usize = BLOCK / 2;
    let step = (h / 8.0) as f32;
    let inv_step = 1.0 / step;
    // Edges, normals and areas are taken in cell units, so they neither
    // underflow nor overflow f32 whatever the cell size (a grid of cells
    // of 1e-21 has areas of 1e-42, below f32's normal range).
    let inv_h = (1.0 / h) as f32;
    // Centroids, the edges q - p and r - p, area normals, areas.
    let mut cen = [[0.0f32; HALF]; 3];
    let mut e1 = [[0.0f32; HALF]; 3];
    let mut e2 = [[0.0f32; HALF]; 3];
    let mut an = [[0.0f32; HALF]; 3];
    let mut area = [0.0f32; HALF];
    let mut sums = [[0i32; HALF]; 5];
    for chunk in tris.chunks(HALF) {
        let n = chunk.len();
        for (i, t) in chunk.iter().enumerate() {
            let [a, b, c] = t.map(|v| pos[v as usize]);
            for k in 0..3 {
                cen[k][i] = (a[k] + b[k] + c[k]) * (1.0 / 3.0);
                e1[k][i] = (b[k] - a[k]) * inv_h;
                e2[k][i] = (c[k] - a[k]) * inv_h;
            }
        }
        {
            let (x, y, z) = ev.coords_mut();
            for i in 0..n {
                let (u, v) = (
                    [e1[0][i], e1[1][i], e1[2][i]],
                    [e2[0][i], e2[1][i], e2[2][i]],
                );
                let a = cross(u, v);
                let len = norm(a);
                for k in 0..3 {
                    an[k][i] = a[k];
                }
                area[i] = len;
                let s = step / len;
                // The centroid, and a point a step out along the normal.
                let c = [cen[0][i], cen[1][i], cen[2][i]];
                (x[i], y[i], z[i]) = (c[0], c[1], c[2]);
                x[i + n] = c[0] + s * a[0];
                y[i + n] = c[1] + s * a[1];
                z[i + n] = c[2] + s * a[2];
            }
        }
        let f = ev.eval_loaded(2 * n);
        let (f0, f1) = f.split_at(n);
        let mut gap = [0.0f32; HALF];
        for i in 0..n {
            // Gap along the outward normal from the centroid to the surface,
            // from f and its slope along the normal (one-sided difference).
            let slope = (f1[i] - f0[i]) * inv_step;
            // In cells, at most half a cell either way.
            let d = -f0[i] / slope * inv_h;
            let ok = (slope < 0.0) as u32 & d.is_finite() as u32;
            gap[i] = select(ok, d.clamp(-0.5, 0.5), 0.0);
        }
        // Separate loops, so each vectorises.
        // Rounded to the nearest unit, kept within +-2^30 (NaN-free: `max`
        // and `min` drop a NaN, where `clamp` would keep it), where the
        // conversion is exact.
        #[allow(clippy::manual_clamp)]
        let q = |v: f32| {
            let r = v.round_ties_even().max(-LIMIT).min(LIMIT);
            // SAFETY: `r` is finite and within the range of i32 (see above),
            // where the conversion is defined (and vectorises, unlike the
            // saturating `as`).
            unsafe { r.to_int_unchecked::<i32>() }
        };
        for k in 0..3 {
            for i in 0..n {
                sums[k][i] = q(an[k][i] * UNIT);
            }
        }
        for i in 0..n {
            sums[3][i] = q(area[i] * gap[i] * UNIT);
        }
        for i in 0..n {
            sums[4][i] = q(area[i] * UNIT);
        }
        for (i, t) in chunk.iter().enumerate() {
            let add = [0, 1, 2, 3, 4].map(|k| sums[k][i]);
            for &v in t {
                let s = &mut acc[v as usize];
                for k in 0..5 {
                    s[k] = s[k].wrapping_add(add[k]);
                }
            }
        }
    }
}

/// Adds `b` into `a`.
pub fn add(a: &mut Acc, b: &Acc) {
    for k in 0..6 {
        a[k] = a[k].wrapping_add(b[k]);
    }
}

/// Moves every vertex of `pos` along its mean normal by 3/4 of its mean
/// gap, from its sums `own + inbound` (one entry each per vertex; an empty
/// `inbound` adds nothing) on a grid
/// of cell size `h`, with no part of a move taking a vertex further
/// outside the box `lo..hi` than it is: along an axis where the move would
/// take it more than half way to a face it stops there (a vertex on a face
/// slides within it, and two vertices of a part thinner than a cell beside
/// a face cannot meet on it), so the correction never pushes a vertex
/// through the box's faces,
/// edges or corners. Then every vertex is clamped into the box. Vertices
/// whose sums are degenerate (no area, no normal) do not move; with
/// `keep_flat`, neither do vertices in a sharp-feature fan (a nonzero
/// count in their sums) nor those whose triangles are coplanar to within
/// a quarter of a degree (the length of the summed area normal within
/// `FLAT` of the summed area): a flat face stays where refinement put it,
/// on the surface.
///
/// In f32 and a block of vertices at a time, in columns, so the square
/// roots and divisions vectorise.
pub fn apply_all(
    pos: &mut [[f32; 3]],
    own: &[Acc],
    inbound: &[Acc],
    h: f64,
    lo: [f32; 3],
    hi: [f32; 3],
    keep_flat: bool,
) {
    const N: usize = 64;
    let scale = (0.75 * h) as f32;
    let mut col = [[0.0f32; N]; 6];
    let mut d = [[0.0f32; N]; 3];
    let zeros = [[0; 6]; N];
    for (c, p) in pos.chunks_mut(N).enumerate() {
        let n = p.len();
        let a = &own[c * N..][..n];
        let b = if inbound.is_empty() {
            &zeros[..n]
        } else {
            &inbound[c * N..][..n]
        };
        for i in 0..n {
            for k in 0..6 {
                col[k][i] = a[i][k].wrapping_add(b[i][k]) as f32;
            }
        }
        for i in 0..n {
            let len2 = col[0][i] * col[0][i] + col[1][i] * col[1][i] + col[2][i] * col[2][i];
            let f = scale * col[3][i] / (col[4][i] * len2.sqrt());
            let ok = (len2 > 0.0) as u32 & (col[4][i] > 0.0) as u32 & f.is_finite() as u32;
            let flat = (col[5][i] > 0.0) as u32 | (len2 >= FLAT * col[4][i] * col[4][i]) as u32;
            let ok = ok & !(keep_flat as u32 & flat) & 1;
            let f = select(ok, f, 0.0);
            for k in 0..3 {
                d[k][i] = f * col[k][i];
            }
        }
        // Columns of the positions, so the moves vectorise too.
        let mut c = [[0.0f32; N]; 3];
        for (i, v) in p.iter().enumerate() {
            for k in 0..3 {
                c[k][i] = v[k];
            }
        }
        for k in 0..3 {
            let (c, d) = (&mut c[k][..n], &d[k][..n]);
            for i in 0..n {
                let q = c[i] + d[i];
                // A vertex off the face goes at most half way to it: one
                // of a solid thinner than a cell there must not land on a
                // vertex of the face itself.
                let up = q.min(select((c[i] < hi[k]) as u32, 0.5 * (c[i] + hi[k]), c[i]));
                let down = q.max(select((c[i] > lo[k]) as u32, 0.5 * (c[i] + lo[k]), c[i]));
                let moved = select((d[i] > 0.0) as u32, up, down);
                c[i] = moved.clamp(lo[k], hi[k]);
            }
        }
        for (i, v) in p.iter_mut().enumerate() {
            *v = [c[0][i], c[1][i], c[2][i]];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moves_follow_the_sums_and_stop_at_the_box() {
        // Unit area-weighted normal +x, mean gap 0.2 cells: a move of
        // 0.75 * 0.2 * h along +x; degenerate sums do not move.
        let h = 0.5;
        let u = 1 << 20;
        let out: Acc = [u, 0, 0, u / 5, u, 0];
        let zero: Acc = [0; 6];
        let lo = [-1.0f32; 3];
        let hi = [1.0f32; 3];
        let mut p = vec![
            [0.0f32; 3],
            [0.99, 0.5, 0.0],
            [0.3, 0.3, 0.3],
            [1.0, 0.0, 0.0],
        ];
        let own = vec![out, out, zero, out];
        let inbound = vec![zero, zero, zero, zero];
        apply_all(&mut p, &own, &inbound, h, lo, hi, false);
        assert!((p[0][0] - 0.075).abs() < 1e-6, "{:?}", p[0]);
        assert_eq!(&p[0][1..], &[0.0, 0.0]);
        // Near the face x = 1: stops half way to it, and slides nowhere
        // else.
        assert_eq!(p[1], [0.995, 0.5, 0.0]);
        assert_eq!(p[2], [0.3, 0.3, 0.3]);
        assert_eq!(p[3], [1.0, 0.0, 0.0]);
        // Own and inbound sums add: half the gap each way gives the same.
        let half: Acc = [u / 2, 0, 0, u / 10, u / 2, 0];
        let mut q = vec![[0.0f32; 3]];
        apply_all(&mut q, &[half], &[half], h, lo, hi, false);
        assert!((q[0][0] - 0.075).abs() < 1e-6, "{:?}", q[0]);
        // Kept flat: a single plane does not move, nor a fan vertex.
        let mut q = vec![[0.0f32; 3]];
        apply_all(&mut q, &[half], &[half], h, lo, hi, true);
        assert_eq!(q[0], [0.0; 3]);
        let curved: Acc = [u / 2, u / 4, 0, u / 10, u, 0];
        let fan: Acc = [0, 0, 0, 0, 0, 1];
        let mut q = vec![[0.0f32; 3]; 2];
        apply_all(&mut q, &[curved, curved], &[zero, fan], h, lo, hi, true);
        assert!(q[0][0] > 0.0, "{:?}", q[0]);
        assert_eq!(q[1], [0.0; 3]);
    }

    #[test]
    fn a_vertex_outside_the_box_is_clamped_onto_it() {
        let zero: Acc = [0; 6];
        let mut p = vec![[1.5f32, -2.0, 0.25]];
        apply_all(&mut p, &[zero], &[zero], 0.1, [-1.0; 3], [1.0; 3], false);
        assert_eq!(p[0], [1.0, -1.0, 0.25]);
    }
}
