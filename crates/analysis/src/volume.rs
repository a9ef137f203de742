//! Volume of `{f >= 0}` inside a tetrahedron for the linear interpolant of
//! the vertex values: closed forms for the 1-3 and 2-2 sign splits, from
//! the cut points of the zero set on the edges; the measures of the cells
//! of [`mod@crate::measure`] with a sign change, cut at the roots of the field
//! on their tetrahedra's edges, with the polygons' bulges; and the error
//! estimate of a measure.

use crate::area::{iso_polygon_cut, IsoPolygon};
use crate::crease::{roots, Seg};
use crate::measure::{Ctx, TETS};
use microfrep_core::geom::{cross, dot};

/// Fraction of a tetrahedron where the linear interpolant of the vertex
/// values `u` is `>= 0`. With the vertices sorted into `p_i >= 0 > n_j`,
/// the closed forms have only positive terms (no cancellation):
/// one vertex in, `p^3 / prod (p - n_j)`; two in, the polynomial below over
/// `prod (p_i - n_j)`; three in, one minus the one-vertex form of `-u`.
pub fn tet_fraction(u: [f64; 4]) -> f64 {
    let (mut pos, mut neg) = ([0.0; 4], [0.0; 4]);
    let (mut np, mut nn) = (0, 0);
    for v in u {
        if v >= 0.0 {
            pos[np] = v;
            np += 1;
        } else {
            neg[nn] = v;
            nn += 1;
        }
    }
    let corner = |a: f64, o: [f64; 3]| a * a * a / ((a - o[0]) * (a - o[1]) * (a - o[2]));
    match np {
        0 => 0.0,
        1 => corner(pos[0], [neg[0], neg[1], neg[2]]),
        2 => {
            let (p, q, r, s) = (pos[0], pos[1], -neg[0], -neg[1]);
            // With r, s >= 0 standing for the negated negative values.
            let num =
                p * p * q * q + (p * p * q + p * q * q) * (r + s) + (p * p + p * q + q * q) * r * s;
            num / ((p + r) * (p + s) * (q + r) * (q + s))
        }
        3 => 1.0 - corner(-neg[0], [-pos[0], -pos[1], -pos[2]]),
        _ => 1.0,
    }
}

/// Statistic of one measure: the value at the grid's resolution, the value
/// on the grid coarsened by two, and the error estimate from the two.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Estimate {
    /// Value at the grid's resolution.
    pub value: f64,
    /// Value from every other node (voxels twice as large).
    pub coarse: f64,
    /// The part of `value - coarse` from cells refined around creases,
    /// where the method is of first order (for the area, also from cells
    /// found creased but not refined: the polygons cut across a crease
    /// miss area in proportion to the cell's size).
    pub kink_diff: f64,
}

impl Estimate {
    /// Exact value (from cells proven full or empty).
    pub fn exact(v: f64) -> Estimate {
        Estimate {
            value: v,
            coarse: v,
            kink_diff: 0.0,
        }
    }

    /// Estimated error of `value` (Richardson): on smooth parts the method
    /// is of second order, so the error is a third of the difference to the
    /// coarse value; around creases it is of first order, so the error is
    /// the whole difference.
    pub fn error(&self) -> f64 {
        let smooth = self.value - self.coarse - self.kink_diff;
        smooth.abs() / 3.0 + self.kink_diff.abs()
    }

    pub(crate) fn add(&mut self, o: Estimate) {
        self.value += o.value;
        self.coarse += o.coarse;
        self.kink_diff += o.kink_diff;
    }
}

/// A cell with a sign change, measured once the zero crossings on its
/// tetrahedra's edges are refined; its measures go to `slot`.
#[derive(Clone, Copy)]
pub(crate) struct Leaf {
    pub(crate) p0: [f64; 3],
    pub(crate) h: [f64; 3],
    pub(crate) f: [f64; 8],
    pub(crate) r: [f64; 8],
    pub(crate) slot: usize,
}

/// The 19 edges of the Kuhn split, `(lo, hi)` with the corner `lo` a
/// subset of `hi`: the 12 cube edges, 6 face diagonals and the main one.
const EDGES: [(usize, usize); 19] = edges();

const fn edges() -> [(usize, usize); 19] {
    let mut out = [(0, 0); 19];
    let (mut n, mut hi) = (0, 1);
    while hi < 8 {
        let mut lo = 0;
        while lo < hi {
            if lo & hi == lo {
                out[n] = (lo, hi);
                n += 1;
            }
            lo += 1;
        }
        hi += 1;
    }
    out
}

/// Index in [`EDGES`] of the edge between corners `lo` and `hi` (either
/// order), or 19 for corners that share no edge.
const EDGE_AT: [[usize; 8]; 8] = edge_at();

const fn edge_at() -> [[usize; 8]; 8] {
    let mut out = [[19; 8]; 8];
    let mut e = 0;
    while e < 19 {
        let (lo, hi) = EDGES[e];
        out[lo][hi] = e;
        out[hi][lo] = e;
        e += 1;
    }
    out
}

/// Measures the cells left in `ctx.s.leaves` into their slots: the sign
/// changes on their tetrahedra's edges are refined to roots of the field,
/// all at once, then each cell is cut at them.
pub(crate) fn measure_leaves(ctx: &mut Ctx) {
    let mut slots = std::mem::take(&mut ctx.slots);
    measure_into(ctx, &mut slots);
    ctx.slots = slots;
}

fn measure_into(ctx: &mut Ctx, slots: &mut [[f64; 3]]) {
    let mut leaves = std::mem::take(&mut ctx.s.leaves);
    // Per leaf and edge, the index of its segment (solid, region), or
    // NONE.
    const NONE: u32 = u32::MAX;
    let mut at_f = vec![NONE; 19 * leaves.len()];
    let mut at_r = vec![NONE; if ctx.with_region { at_f.len() } else { 0 }];
    let (mut seg_f, mut seg_r) = (Vec::new(), Vec::new());
    let push = |segs: &mut Vec<Seg>, seg: Seg| -> u32 {
        segs.push(seg);
        segs.len() as u32 - 1
    };
    for (l, leaf) in leaves.iter().enumerate() {
        for (e, &(lo, hi)) in EDGES.iter().enumerate() {
            let pos = |c: usize| [c & 1, (c >> 1) & 1, (c >> 2) & 1].map(|b| b as f64);
            let (plo, phi) = (pos(lo), pos(hi));
            let seg = |v: &[f64; 8]| Seg {
                a: std::array::from_fn(|a| leaf.p0[a] + leaf.h[a] * plo[a]),
                d: std::array::from_fn(|a| leaf.h[a] * (phi[a] - plo[a])),
                fa: v[lo],
                fb: v[hi],
            };
            if (leaf.f[lo] >= 0.0) != (leaf.f[hi] >= 0.0) {
                at_f[19 * l + e] = push(&mut seg_f, seg(&leaf.f));
            }
            if ctx.with_region && (leaf.r[lo] >= 0.0) != (leaf.r[hi] >= 0.0) {
                at_r[19 * l + e] = push(&mut seg_r, seg(&leaf.r));
            }
        }
    }
    let (mut tf, mut tr, mut sf, mut sr) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    roots(ctx, false, &seg_f, &mut tf, &mut sf);
    if ctx.with_region {
        roots(ctx, true, &seg_r, &mut tr, &mut sr);
    }
    let mut bulges = Vec::new();
    for (l, leaf) in leaves.iter().enumerate() {
        let get = |at: &[u32], t: &[f64]| -> [f64; 19] {
            std::array::from_fn(|e| match at.get(19 * l + e) {
                Some(&k) if k != NONE => t[k as usize],
                _ => f64::NAN,
            })
        };
        let roots = Roots {
            f: get(&at_f, &tf),
            r: get(&at_r, &tr),
            slope: get(&at_f, &sf),
        };
        let m = leaf_measures(ctx.with_region, leaf, &roots, &mut bulges);
        for q in 0..3 {
            slots[leaf.slot][q] += m[q];
        }
    }
    leaves.clear();
    ctx.s.leaves = leaves;
    if bulges.is_empty() || !ctx.eval_solid {
        return;
    }
    let s = &mut *ctx.s;
    s.xs.clear();
    s.ys.clear();
    s.zs.clear();
    for b in &bulges {
        s.xs.push(b.at[0] as f32);
        s.ys.push(b.at[1] as f32);
        s.zs.push(b.at[2] as f32);
    }
    let mut v = std::mem::take(&mut s.root_vals);
    v.clear();
    v.resize(bulges.len(), 0.0);
    s.solid_ev.eval(&s.xs, &s.ys, &s.zs, &mut v);
    for (b, &fc) in bulges.iter().zip(&v) {
        // Distance from the polygon's centre to the surface along the
        // normal, no more than half a cell (a NaN is far outside).
        let d = (fc as f64 / b.grad).clamp(-b.cap, b.cap);
        if d.is_finite() {
            slots[b.slot][0] += b.weight * d;
        }
    }
    ctx.s.root_vals = v;
}

/// The roots of the solid (`f`) and of the region (`r`) on the edges of a
/// cell where they change sign, by index in [`EDGES`], as parameters from
/// the edge's `lo` corner; `slope` is the solid's derivative there in that
/// parameter; NaN where there is none.
struct Roots {
    f: [f64; 19],
    r: [f64; 19],
    slope: [f64; 19],
}

/// The volume between a cut polygon and the curved surface through its
/// vertices: `weight` times the distance from the polygon's centre `at` to
/// the surface, that is times the field there over its gradient's length
/// `grad`, with at most `cap`. For a quadratic surface the weight is 3/4
/// of the area for a triangle, 2/3 for a quadrilateral (the cubature
/// rules of their centres and vertices, the surface's height being zero at
/// the vertices).
struct Bulge {
    slot: usize,
    at: [f64; 3],
    weight: f64,
    grad: f64,
    cap: f64,
}

/// The bulge of the polygon `poly` of area `a` cut from the tetrahedron
/// `t` of the cell `leaf` (corner offsets `corner`): the field's gradient
/// from its slopes along three of the cut edges, which span space.
fn bulge(
    leaf: &Leaf,
    t: [usize; 4],
    poly: &IsoPolygon,
    a: f64,
    corner: &[[f64; 3]; 8],
    slope: &[f64; 19],
) -> Option<Bulge> {
    if poly.n < 3 || a <= 0.0 {
        return None;
    }
    let mut rows = [[0.0; 3]; 3];
    let mut rhs = [0.0; 3];
    let mut at = [0.0; 3];
    for (k, &(i, j, x)) in poly.verts[..poly.n].iter().enumerate() {
        let (ci, cj) = (t[i], t[j]);
        let d: [f64; 3] = std::array::from_fn(|q| corner[cj][q] - corner[ci][q]);
        for q in 0..3 {
            at[q] += (leaf.p0[q] + corner[ci][q] + x * d[q]) / poly.n as f64;
        }
        if k < 3 {
            let s = slope[EDGE_AT[ci][cj]];
            if s.is_nan() {
                return None;
            }
            rows[k] = d;
            rhs[k] = if ci < cj { s } else { -s };
        }
    }
    let c12 = cross(rows[1], rows[2]);
    let det = dot(rows[0], c12);
    if det.abs() < 1e-30 {
        return None;
    }
    let (c20, c01) = (cross(rows[2], rows[0]), cross(rows[0], rows[1]));
    let g: [f64; 3] =
        std::array::from_fn(|q| (rhs[0] * c12[q] + rhs[1] * c20[q] + rhs[2] * c01[q]) / det);
    let grad = dot(g, g).sqrt();
    if !(grad > 0.0 && grad.is_finite()) {
        return None;
    }
    let w = if poly.n == 3 { 0.75 } else { 2.0 / 3.0 };
    Some(Bulge {
        slot: leaf.slot,
        at,
        weight: w * a,
        grad,
        cap: 0.5 * leaf.h.iter().cloned().fold(0.0, f64::max),
    })
}

/// Solid volume, region volume and area of a cell with a sign change,
/// given the roots of the solid (`rf`) and the region (`rr`) on the
/// edges where they change sign (parameters from the edge's `lo` corner).
/// Without a region, the polygons' bulges (see [`Bulge`]) go to `bulges`.
fn leaf_measures(
    with_region: bool,
    leaf: &Leaf,
    roots: &Roots,
    bulges: &mut Vec<Bulge>,
) -> [f64; 3] {
    let (rf, rr) = (&roots.f, &roots.r);
    let (h, f, r) = (leaf.h, &leaf.f, &leaf.r);
    let cv = h[0] * h[1] * h[2];
    let corner: [[f64; 3]; 8] =
        std::array::from_fn(|c| std::array::from_fn(|a| h[a] * ((c >> a) & 1) as f64));
    // The crossing on the tetrahedron edge (i, j) from its vertex i, for
    // roots `at` of the field `v` (linear where none is known).
    let cut = |v: &[f64; 8], t: [usize; 4], i: usize, j: usize, at: &[f64; 19]| {
        let (ci, cj) = (t[i], t[j]);
        let x = at[EDGE_AT[ci][cj]];
        if x.is_nan() {
            v[ci] / (v[ci] - v[cj])
        } else if ci < cj {
            x
        } else {
            1.0 - x
        }
    };
    if !with_region {
        let (mut frac, mut area) = (0.0, 0.0);
        for t in TETS {
            let poly = iso_polygon_cut(t.map(|c| f[c]), |i, j| cut(f, t, i, j, rf));
            frac += poly.inside_fraction();
            let a = poly.area(&t.map(|c| corner[c]));
            area += a;
            if let Some(b) = bulge(leaf, t, &poly, a, &corner, &roots.slope) {
                bulges.push(b);
            }
        }
        return [cv * frac / 6.0, cv, area];
    }
    // min(f, r) changes sign where the first of them to leave the inside
    // does, seen from its inside end.
    let m: [f64; 8] = std::array::from_fn(|c| f[c].min(r[c]));
    let rm: [f64; 19] = std::array::from_fn(|e| {
        let (lo, _) = EDGES[e];
        let ts = [rf[e], rr[e]].into_iter().filter(|x| !x.is_nan());
        let t = if m[lo] >= 0.0 {
            ts.reduce(f64::min)
        } else {
            ts.reduce(f64::max)
        };
        t.unwrap_or(f64::NAN)
    });
    let frac = |v: &[f64; 8], at: &[f64; 19]| {
        TETS.iter()
            .map(|&t| {
                iso_polygon_cut(t.map(|c| v[c]), |i, j| cut(v, t, i, j, at)).inside_fraction()
            })
            .sum::<f64>()
            / 6.0
    };
    let vol = cv * frac(&m, &rm);
    let rvol = cv * frac(r, rr);
    let mut area = 0.0;
    for t in TETS {
        let poly = iso_polygon_cut(t.map(|c| f[c]), |i, j| cut(f, t, i, j, rf));
        if poly.n == 0 || poly.mean_of(t.map(|c| r[c])) < 0.0 {
            continue;
        }
        area += poly.area(&t.map(|c| corner[c]));
    }
    [vol, rvol, area]
}

/// Cells measured together at most (bounds the memory where refinement
/// meets sign changes everywhere; larger batches evaluate faster).
pub(crate) const LEAF_BATCH: usize = 8192;

#[cfg(test)]
mod tests {
    use super::*;

    /// Monte Carlo-free check: the fraction of a linear function's positive
    /// part agrees with midpoint quadrature over a fine barycentric lattice.
    fn quadrature(f: [f64; 4]) -> f64 {
        let n = 60;
        let (mut inside, mut all) = (0usize, 0usize);
        for i in 0..n {
            for j in 0..n - i {
                for k in 0..n - i - j {
                    // Sub-tet barycentric centre (one orientation suffices
                    // for this tolerance).
                    let b = [
                        (i as f64 + 0.25) / n as f64,
                        (j as f64 + 0.25) / n as f64,
                        (k as f64 + 0.25) / n as f64,
                    ];
                    let b0 = 1.0 - b[0] - b[1] - b[2];
                    let v = b0 * f[0] + b[0] * f[1] + b[1] * f[2] + b[2] * f[3];
                    inside += (v >= 0.0) as usize;
                    all += 1;
                }
            }
        }
        inside as f64 / all as f64
    }

    #[test]
    fn fractions_match_quadrature_and_complements() {
        let cases = [
            [1.0, -1.0, -2.0, -0.5],
            [1.0, 0.3, -2.0, -0.5],
            [0.2, 0.7, 0.1, -0.9],
            [0.5, -0.5, 0.5, -0.5],
        ];
        for f in cases {
            let v = tet_fraction(f);
            assert!((v - quadrature(f)).abs() < 0.03, "{f:?}: {v}");
            let neg = tet_fraction(f.map(|x| -x));
            assert!((v + neg - 1.0).abs() < 1e-12, "{f:?}");
        }
        assert_eq!(tet_fraction([1.0; 4]), 1.0);
        assert_eq!(tet_fraction([-1.0; 4]), 0.0);
        assert!((tet_fraction([1.0, -1.0, -1.0, -1.0]) - 0.125).abs() < 1e-15);
    }
}
