//! Bounding volume hierarchy over triangles: binned SAH build in parallel,
//! 32-byte nodes with f32 boxes rounded outward, triangles stored with f64
//! corners in leaf order; nearest-triangle queries.

use crate::geom::{closest_on_triangle, Feature};
use crate::mesh::{is_degenerate, TriMesh};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

/// Most triangles in a leaf.
pub const MAX_LEAF: usize = 4;
const BINS: usize = 16;
/// Past this depth splits are by median (keeps the query stack bounded).
const MAX_SAH_DEPTH: usize = 48;
/// Below this many triangles a subtree is built on the current thread.
const PAR_MIN: usize = 4096;
/// Query stack size; depth is at most MAX_SAH_DEPTH + log2(2^32) + 1.
const STACK: usize = 96;

/// A node: its box (f32, rounded outward so it contains the f64 triangles)
/// and either two children (`count == 0`: left is the next node, right is
/// `index`) or a leaf (`count` triangles from position `index`).
#[derive(Clone, Copy, Debug, Default)]
#[repr(C)]
pub struct Node {
    /// Box minimum.
    pub lo: [f32; 3],
    /// Box maximum.
    pub hi: [f32; 3],
    /// Right child, or first triangle of a leaf.
    pub index: u32,
    /// Triangles of a leaf, 0 for an inner node.
    pub count: u32,
}

impl Node {
    /// Whether this is a leaf.
    pub fn is_leaf(&self) -> bool {
        self.count > 0
    }

    /// Squared distance from `p` to the box (0 inside).
    #[inline]
    pub fn dist2(&self, p: [f64; 3]) -> f64 {
        // Branch free: the larger of the two excesses, and 0 inside (for a
        // NaN coordinate the comparisons fall to 0, as before).
        let mut d = 0.0;
        for a in 0..3 {
            let u = self.lo[a] as f64 - p[a];
            let v = p[a] - self.hi[a] as f64;
            let e = if u > v { u } else { v };
            let e = if e > 0.0 { e } else { 0.0 };
            d += e * e;
        }
        d
    }

    /// Depth at which the ray `o + t d` (`inv` the reciprocals of `d`)
    /// enters the box within `[t0, t1]`, if it meets the box there. The
    /// slabs are widened by a relative 1e-12 so rounding never loses a ray
    /// that grazes a face of the box.
    #[inline]
    pub fn ray_entry(
        &self,
        o: [f64; 3],
        d: [f64; 3],
        inv: [f64; 3],
        t0: f64,
        t1: f64,
    ) -> Option<f64> {
        let (mut a, mut b) = (t0, t1);
        for k in 0..3 {
            let (lo, hi) = (self.lo[k] as f64, self.hi[k] as f64);
            let pad = 1e-12 * (hi - lo).abs().max(lo.abs()).max(hi.abs());
            let (lo, hi) = (lo - pad, hi + pad);
            if d[k] == 0.0 {
                if o[k] < lo || o[k] > hi {
                    return None;
                }
                continue;
            }
            let (p, q) = ((lo - o[k]) * inv[k], (hi - o[k]) * inv[k]);
            let (p, q) = if p <= q { (p, q) } else { (q, p) };
            // Widened a little too, against rounding of the products.
            let w = 1e-12 * (p.abs().max(q.abs()));
            a = a.max(p - w);
            b = b.min(q + w);
            if !(a <= b) {
                return None;
            }
        }
        Some(a)
    }
}

/// How far outside a triangle (in barycentric units) a ray may pass and
/// still count as crossing it in [`Bvh::first_hit`]: wide enough to close
/// the cracks rounding opens between neighbours, far below any pixel.
pub const RAY_EDGE_SLACK: f64 = 1e-9;

/// Depth at which the ray `o + t d` crosses the triangle `tri`, if it does
/// (within [`RAY_EDGE_SLACK`] of its edges); `None` for a ray in the
/// triangle's plane or a degenerate triangle.
#[inline]
pub fn ray_triangle(o: [f64; 3], d: [f64; 3], tri: &[[f64; 3]; 3]) -> Option<f64> {
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let e1 = sub(tri[1], tri[0]);
    let e2 = sub(tri[2], tri[0]);
    let pv = cross(d, e2);
    let det = dot(e1, pv);
    // A ray (nearly) in the plane: its neighbours across the plane's
    // edges are met instead.
    let scale = dot(e1, e1).sqrt() * dot(e2, e2).sqrt() * dot(d, d).sqrt();
    if !(det.abs() > 1e-14 * scale) {
        return None;
    }
    let inv = 1.0 / det;
    let tv = sub(o, tri[0]);
    let u = dot(tv, pv) * inv;
    if !(-RAY_EDGE_SLACK..=1.0 + RAY_EDGE_SLACK).contains(&u) {
        return None;
    }
    let qv = cross(tv, e1);
    let v = dot(d, qv) * inv;
    if !(v >= -RAY_EDGE_SLACK && u + v <= 1.0 + RAY_EDGE_SLACK) {
        return None;
    }
    let t = dot(e2, qv) * inv;
    t.is_finite().then_some(t)
}

fn down32(x: f64) -> f32 {
    let f = x as f32;
    if (f as f64) > x {
        f.next_down()
    } else {
        f
    }
}
fn up32(x: f64) -> f32 {
    let f = x as f32;
    if (f as f64) < x {
        f.next_up()
    } else {
        f
    }
}

/// The nearest triangle to a point.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    /// Squared distance.
    pub d2: f64,
    /// Closest point.
    pub point: [f64; 3],
    /// Triangle, in leaf order ([`Bvh::original`] maps it back).
    pub tri: u32,
    /// Feature of the triangle the closest point lies on.
    pub feature: Feature,
}

impl Hit {
    /// No triangle yet: infinitely far.
    pub const NONE: Hit = Hit {
        d2: f64::INFINITY,
        point: [f64::NAN; 3],
        tri: u32::MAX,
        feature: Feature::Face,
    };
}

/// The hierarchy and the triangles in leaf order.
pub struct Bvh {
    /// Nodes, depth first; node 0 is the root.
    pub nodes: Vec<Node>,
    /// Triangle corners in leaf order.
    pub tris: Vec<[[f64; 3]; 3]>,
    /// Whether each triangle (leaf order) is degenerate.
    pub degenerate: Vec<bool>,
    /// Index in the input mesh of each triangle (leaf order).
    pub original: Vec<u32>,
}

#[derive(Clone, Copy)]
struct Aabb {
    lo: [f64; 3],
    hi: [f64; 3],
}

impl Aabb {
    const EMPTY: Aabb = Aabb {
        lo: [f64::INFINITY; 3],
        hi: [f64::NEG_INFINITY; 3],
    };
    fn grow(&mut self, o: &Aabb) {
        for a in 0..3 {
            self.lo[a] = self.lo[a].min(o.lo[a]);
            self.hi[a] = self.hi[a].max(o.hi[a]);
        }
    }
    fn grow_point(&mut self, p: [f64; 3]) {
        for a in 0..3 {
            self.lo[a] = self.lo[a].min(p[a]);
            self.hi[a] = self.hi[a].max(p[a]);
        }
    }
    fn half_area(&self) -> f64 {
        let d = [0, 1, 2].map(|a| (self.hi[a] - self.lo[a]).max(0.0));
        d[0] * d[1] + d[1] * d[2] + d[2] * d[0]
    }
}

enum Tmp {
    Leaf {
        bounds: Aabb,
        start: usize,
        count: usize,
    },
    Inner {
        bounds: Aabb,
        children: Box<[Tmp; 2]>,
    },
}

struct Ctx<'a> {
    boxes: &'a [Aabb],
    centroids: &'a [[f64; 3]],
    done: &'a AtomicU64,
    progress: &'a (dyn Fn(u64, u64) + Sync),
    /// Triangles of this stage.
    total: u64,
    /// Progress before this stage, and of all stages.
    offset: u64,
    grand: u64,
}

impl Ctx<'_> {
    fn leaf_done(&self, n: usize) {
        let before = self.done.fetch_add(n as u64, Ordering::Relaxed);
        let after = before + n as u64;
        if before >> 16 != after >> 16 || after == self.total {
            (self.progress)(self.offset + after, self.grand);
        }
    }
}

/// Bounds of the boxes and of the centroids of `prims`.
fn bounds_of(ctx: &Ctx, prims: &[u32]) -> (Aabb, Aabb) {
    let fold = |(mut b, mut c): (Aabb, Aabb), &i: &u32| {
        b.grow(&ctx.boxes[i as usize]);
        c.grow_point(ctx.centroids[i as usize]);
        (b, c)
    };
    if prims.len() > 65536 {
        prims
            .par_chunks(16384)
            .map(|ch| ch.iter().fold((Aabb::EMPTY, Aabb::EMPTY), fold))
            .reduce(
                || (Aabb::EMPTY, Aabb::EMPTY),
                |(mut a, mut b), (c, d)| {
                    a.grow(&c);
                    b.grow(&d);
                    (a, b)
                },
            )
    } else {
        prims.iter().fold((Aabb::EMPTY, Aabb::EMPTY), fold)
    }
}

type Bins = [[(Aabb, u32); BINS]; 3];

fn bin_of(c: f64, lo: f64, scale: f64) -> usize {
    (((c - lo) * scale) as usize).min(BINS - 1)
}

fn fill_bins(ctx: &Ctx, prims: &[u32], cb: &Aabb) -> Bins {
    let scale: [f64; 3] = [0, 1, 2].map(|a| {
        let w = cb.hi[a] - cb.lo[a];
        if w > 0.0 {
            BINS as f64 / w
        } else {
            0.0
        }
    });
    let add = |mut bins: Bins, &i: &u32| {
        let c = ctx.centroids[i as usize];
        for a in 0..3 {
            let b = &mut bins[a][bin_of(c[a], cb.lo[a], scale[a])];
            b.0.grow(&ctx.boxes[i as usize]);
            b.1 += 1;
        }
        bins
    };
    let empty = || [[(Aabb::EMPTY, 0u32); BINS]; 3];
    let merge = |mut x: Bins, y: Bins| {
        for a in 0..3 {
            for k in 0..BINS {
                x[a][k].0.grow(&y[a][k].0);
                x[a][k].1 += y[a][k].1;
            }
        }
        x
    };
    if prims.len() > 65536 {
        prims
            .par_chunks(16384)
            .map(|ch| ch.iter().fold(empty(), add))
            .reduce(empty, merge)
    } else {
        prims.iter().fold(empty(), add)
    }
}

fn build_node(ctx: &Ctx, prims: &mut [u32], start: usize, depth: usize) -> Tmp {
    let n = prims.len();
    let (bounds, cb) = bounds_of(ctx, prims);
    let leaf = |ctx: &Ctx| {
        ctx.leaf_done(n);
        Tmp::Leaf {
            bounds,
            start,
            count: n,
        }
    };
    if n <= 2 {
        return leaf(ctx);
    }
    // Split position: (axis, bin boundary) by SAH, or None for a median split.
    let mut split = None;
    if depth < MAX_SAH_DEPTH {
        let bins = fill_bins(ctx, prims, &cb);
        let mut best = f64::INFINITY;
        for (a, axis_bins) in bins.iter().enumerate() {
            if cb.hi[a] <= cb.lo[a] {
                continue;
            }
            // Sweep from the right, then from the left.
            let mut right = [(0.0, 0u32); BINS];
            let (mut acc, mut cnt) = (Aabb::EMPTY, 0);
            for k in (1..BINS).rev() {
                acc.grow(&axis_bins[k].0);
                cnt += axis_bins[k].1;
                right[k] = (acc.half_area(), cnt);
            }
            let (mut acc, mut cnt) = (Aabb::EMPTY, 0);
            for k in 0..BINS - 1 {
                acc.grow(&axis_bins[k].0);
                cnt += axis_bins[k].1;
                let (ra, rc) = right[k + 1];
                if cnt == 0 || rc == 0 {
                    continue;
                }
                let cost = acc.half_area() * cnt as f64 + ra * rc as f64;
                if cost < best {
                    best = cost;
                    split = Some((a, k + 1));
                }
            }
        }
        let leaf_cost = bounds.half_area() * n as f64;
        if n <= MAX_LEAF && leaf_cost <= best + bounds.half_area() {
            return leaf(ctx);
        }
    }
    let mid = match split {
        Some((a, k)) => {
            let w = cb.hi[a] - cb.lo[a];
            let scale = BINS as f64 / w;
            let (lo, c) = (cb.lo[a], ctx.centroids);
            // In-place partition.
            let mut i = 0;
            let mut j = n;
            while i < j {
                if bin_of(c[prims[i] as usize][a], lo, scale) < k {
                    i += 1;
                } else {
                    j -= 1;
                    prims.swap(i, j);
                }
            }
            i
        }
        None => {
            // Median on the longest centroid axis.
            let a = (0..3)
                .max_by(|&x, &y| (cb.hi[x] - cb.lo[x]).total_cmp(&(cb.hi[y] - cb.lo[y])))
                .unwrap_or(0);
            let m = n / 2;
            prims.select_nth_unstable_by(m, |&x, &y| {
                ctx.centroids[x as usize][a]
                    .total_cmp(&ctx.centroids[y as usize][a])
                    .then(x.cmp(&y))
            });
            m
        }
    };
    let mid = if mid == 0 || mid == n { n / 2 } else { mid };
    let (l, r) = prims.split_at_mut(mid);
    let (left, right) = if n > PAR_MIN {
        rayon::join(
            || build_node(ctx, l, start, depth + 1),
            || build_node(ctx, r, start + mid, depth + 1),
        )
    } else {
        (
            build_node(ctx, l, start, depth + 1),
            build_node(ctx, r, start + mid, depth + 1),
        )
    };
    Tmp::Inner {
        bounds,
        children: Box::new([left, right]),
    }
}

fn flatten(t: &Tmp, nodes: &mut Vec<Node>) {
    let node = |b: &Aabb, index: usize, count: usize| Node {
        lo: b.lo.map(down32),
        hi: b.hi.map(up32),
        index: index as u32,
        count: count as u32,
    };
    match t {
        Tmp::Leaf {
            bounds,
            start,
            count,
        } => nodes.push(node(bounds, *start, *count)),
        Tmp::Inner { bounds, children } => {
            let me = nodes.len();
            nodes.push(node(bounds, 0, 0));
            flatten(&children[0], nodes);
            nodes[me].index = nodes.len() as u32;
            flatten(&children[1], nodes);
        }
    }
}

/// Bytes a BVH over `triangles` needs at most, temporaries included.
pub fn predict_bytes(triangles: u64) -> u64 {
    // Leaf-order corners 72, flags 1, original index 4, nodes <= 2 x 32,
    // build boxes 48 + centroids 24 + indices 4 + temporary tree <= 2 x 48.
    triangles.saturating_mul(72 + 1 + 4 + 64 + 48 + 24 + 4 + 96)
}

impl Bvh {
    /// Builds the hierarchy; `progress(offset + done, total)` is called as
    /// leaves are made (`offset` and `total` chain it with other stages).
    pub fn build(
        mesh: &TriMesh,
        progress: &(dyn Fn(u64, u64) + Sync),
        offset: u64,
        total: u64,
    ) -> Bvh {
        let n = mesh.triangles.len();
        let boxes: Vec<Aabb> = (0..n)
            .into_par_iter()
            .with_min_len(4096)
            .map(|t| {
                let mut b = Aabb::EMPTY;
                for v in mesh.corners(t) {
                    b.grow_point(v);
                }
                b
            })
            .collect();
        let centroids: Vec<[f64; 3]> = boxes
            .par_iter()
            .with_min_len(4096)
            .map(|b| [0, 1, 2].map(|a| 0.5 * (b.lo[a] + b.hi[a])))
            .collect();
        let mut prims: Vec<u32> = (0..n as u32).collect();
        let done = AtomicU64::new(0);
        let ctx = Ctx {
            boxes: &boxes,
            centroids: &centroids,
            done: &done,
            progress,
            total: n as u64,
            offset,
            grand: total,
        };
        let tmp = build_node(&ctx, &mut prims, 0, 0);
        drop(boxes);
        drop(centroids);
        let mut nodes = Vec::with_capacity(2 * n / 2 + 1);
        flatten(&tmp, &mut nodes);
        drop(tmp);
        let tris: Vec<[[f64; 3]; 3]> = prims
            .par_iter()
            .with_min_len(4096)
            .map(|&t| mesh.corners(t as usize))
            .collect();
        let degenerate = tris
            .par_iter()
            .with_min_len(4096)
            .map(|t| is_degenerate(*t))
            .collect();
        Bvh {
            nodes,
            tris,
            degenerate,
            original: prims,
        }
    }

    /// Tests triangle `t` (leaf order) and keeps it in `best` if nearer.
    #[inline]
    pub fn test(&self, p: [f64; 3], t: usize, best: &mut Hit) {
        let (c, f) = closest_on_triangle(p, &self.tris[t], self.degenerate[t]);
        let d = [p[0] - c[0], p[1] - c[1], p[2] - c[2]];
        let d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        if d2 < best.d2 {
            *best = Hit {
                d2,
                point: c,
                tri: t as u32,
                feature: f,
            };
        }
    }

    /// The nearest triangle to `p`, starting from `best` (a known triangle
    /// and its distance prune the search; [`Hit::NONE`] for none). Ties are
    /// resolved by traversal order, which depends only on the tree.
    pub fn closest(&self, p: [f64; 3], mut best: Hit) -> Hit {
        let mut stack = [(0u32, 0.0f64); STACK];
        let mut sp = 0;
        // The node in hand and its box distance; the nearer child of an
        // inner node is taken next without a trip through the stack.
        let (mut ni, mut d2) = (0u32, self.nodes[0].dist2(p));
        loop {
            if d2 < best.d2 {
                let node = &self.nodes[ni as usize];
                if node.is_leaf() {
                    let s = node.index as usize;
                    for t in s..s + node.count as usize {
                        self.test(p, t, &mut best);
                    }
                } else {
                    let (l, r) = (ni + 1, node.index);
                    let dl = self.nodes[l as usize].dist2(p);
                    let dr = self.nodes[r as usize].dist2(p);
                    let (near, dn, far, df) = if dl <= dr {
                        (l, dl, r, dr)
                    } else {
                        (r, dr, l, dl)
                    };
                    if dn < best.d2 {
                        if df < best.d2 {
                            stack[sp] = (far, df);
                            sp += 1;
                        }
                        (ni, d2) = (near, dn);
                        continue;
                    }
                }
            }
            if sp == 0 {
                break;
            }
            sp -= 1;
            (ni, d2) = stack[sp];
        }
        best
    }

    /// The first triangle the ray `o + t d` crosses with `t` in
    /// `range`: its depth and index (leaf order). Triangles are tested in
    /// f64 (Moller-Trumbore) with their barycentric bounds widened by
    /// [`RAY_EDGE_SLACK`], so a ray through an edge or a vertex shared by
    /// several triangles meets at least one of them despite rounding;
    /// degenerate triangles and rays in a triangle's plane are skipped.
    /// Ties keep the first found in the fixed traversal order, so the
    /// answer depends only on the tree and the ray.
    pub fn first_hit(&self, o: [f64; 3], d: [f64; 3], range: [f64; 2]) -> Option<(f64, u32)> {
        let inv = d.map(|c| 1.0 / c);
        let (t0, mut best) = (range[0], range[1]);
        if !(t0 <= best) || self.nodes.is_empty() {
            return None;
        }
        let mut found = None;
        let mut stack = [(0u32, 0.0f64); STACK];
        let mut sp = 0;
        if let Some(te) = self.nodes[0].ray_entry(o, d, inv, t0, best) {
            stack[0] = (0, te);
            sp = 1;
        }
        while sp > 0 {
            sp -= 1;
            let (ni, te) = stack[sp];
            if te > best {
                continue;
            }
            let node = &self.nodes[ni as usize];
            if node.is_leaf() {
                let s = node.index as usize;
                for t in s..s + node.count as usize {
                    if self.degenerate[t] {
                        continue;
                    }
                    if let Some(th) = ray_triangle(o, d, &self.tris[t]) {
                        if th >= t0 && th <= best && (found.is_none() || th < best) {
                            best = th;
                            found = Some((th, t as u32));
                        }
                    }
                }
            } else {
                let (l, r) = (ni + 1, node.index);
                let el = self.nodes[l as usize].ray_entry(o, d, inv, t0, best);
                let er = self.nodes[r as usize].ray_entry(o, d, inv, t0, best);
                // Push the farther child first so the nearer is searched
                // first and its hits prune the other.
                let mut push = |n: u32, e: Option<f64>| {
                    if let Some(e) = e {
                        stack[sp] = (n, e);
                        sp += 1;
                    }
                };
                match (el, er) {
                    (Some(a), Some(b)) if b < a => {
                        push(l, el);
                        push(r, er);
                    }
                    _ => {
                        push(r, er);
                        push(l, el);
                    }
                }
            }
        }
        found
    }

    /// Depth of the tree (the root alone is 1).
    pub fn depth(&self) -> usize {
        fn go(nodes: &[Node], i: usize) -> usize {
            let n = &nodes[i];
            if n.is_leaf() {
                1
            } else {
                1 + go(nodes, i + 1).max(go(nodes, n.index as usize))
            }
        }
        go(&self.nodes, 0)
    }
}
