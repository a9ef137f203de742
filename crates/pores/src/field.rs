//! The pore structure as a [`Field`]: positive in the solid, negative in the
//! pores, about a distance near the pore surfaces.
//!
//! Each cell `C` subtracts its own pore `P_C` (the paper's Boolean
//! difference of the pore and the sub-region), so the pore space is the
//! union of the `C ∩ P_C` and the field is
//! `f = min(cap, min_C max(-c_C, -q_C))`, with `c_C` the distance-like
//! function of the cell box (`min_i (h_i - |x_i - m_i|)`, positive inside)
//! and `q_C` that of the pore (positive inside). It is continuous across
//! cell faces (a min and max of continuous functions).
//!
//! Evaluation in about constant time: a uniform index grid over the
//! subdivided box points into the tree of splits, which gives the leaf of
//! the point in a step or two. A cell farther than `cap` (Chebyshev) from a
//! point cannot bring `f` below `cap`, so each leaf keeps the list of pore
//! cells within `cap` of it, sorted by the side of the leaf they lie
//! beyond; a neighbour beyond a side gives at least the point's distance to
//! that side, so once the own pore gives `f <= c_C(x)` (inside the pore, or
//! nearer to it than to the cell's faces) no neighbour is visited, and
//! otherwise only those beyond the near sides. The f32 batch keeps the last
//! leaf and computes the own cells' terms over runs of points in one cell
//! in straight-line loops the compiler vectorises.
//!
//! The 3D batch costs about 4 times a gyroid's per point (the cube-map
//! reads and the leaf look-up do not vectorise; `bench/run pores`).
//!
//! Bounds: every term is Lipschitz (the box functions with constant 1, the
//! 2D signed distances with 1, the 3D pores with the constant of their
//! table), so over a box with centre `c` and half-diagonal `r`,
//! `f in f(c) +- L r`, clamped to `[floor, cap]` where `floor` is minus the
//! largest cell half-extent; boxes with no pore cell within `cap` are
//! exactly `cap`. Partial derivatives lie in `[-L, L]`.

use crate::cubemap::View;
use crate::curve::{signed_distance, Quad};
use crate::tree::{Node, Tree, NONE};
use microfrep_core::{Field, Interval};

/// A 3D pore: `-q = k g(y) - m` with `y = (x - centre) * inv_half` and `g`
/// the gauge of the table at `offset`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Pore3 {
    pub inv_half: [f64; 3],
    /// `m / lambda`.
    pub k: f64,
    /// `lambda R_mean h_min`: makes `q` about a distance near the surface.
    pub m: f64,
    /// Start of the pore's table in [`PoreField::tables`].
    pub offset: usize,
}

/// Everything the value of a 3D cell's term needs, in one place (the hot
/// path): centre, half extents, their inverses, the pore's `k`, `m` and
/// table offset (`u32::MAX`: no pore).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Fast3 {
    pub c: [f64; 3],
    pub h: [f64; 3],
    pub inv: [f64; 3],
    pub k: f64,
    pub m: f64,
    pub off: u32,
}

#[derive(Clone, Debug)]
pub(crate) enum Pores {
    Two(Vec<Option<[Quad; 4]>>),
    Three(Vec<Option<Pore3>>),
}

/// Centre and half extents of a cell.
#[derive(Clone, Copy, Debug)]
pub(crate) struct CellBox {
    pub c: [f64; 3],
    pub h: [f64; 3],
}

/// The pore structure of a part: `f >= 0` in the solid between the pores
/// (intersect it with the part, [`crate::Built::solid`], for the porous
/// part).
#[derive(Debug)]
pub struct PoreField {
    pub(crate) name: String,
    pub(crate) dim: usize,
    pub(crate) tree: Tree,
    pub(crate) index: Index,
    /// Per leaf: its own cell if that has a pore, else NONE.
    pub(crate) own: Vec<u32>,
    /// Per leaf and side (x-, x+, y-, y+, z-, z+): range into `cand` of the
    /// other pore cells within `cap` beyond that side of the leaf (a cell
    /// beyond an edge or corner is listed under each of its sides).
    pub(crate) cand_start: Vec<u32>,
    pub(crate) cand: Vec<u32>,
    /// Leaf boxes (the same as the tree's), for the side distances.
    pub(crate) leaf_box: Vec<CellBox>,
    pub(crate) boxes: Vec<CellBox>,
    pub(crate) pores: Pores,
    /// Texels per face side of the 3D tables.
    pub(crate) texels: usize,
    /// All 3D tables, one after the other.
    pub(crate) tables: Vec<f32>,
    /// Per cell, for the 3D hot path (empty in 2D).
    pub(crate) fast3: Vec<Fast3>,
    pub(crate) cap: f64,
    pub(crate) lip: f64,
    pub(crate) floor: f64,
}

/// A uniform grid over the root box; each entry is the deepest tree node
/// holding the whole grid cell, where the descent starts.
#[derive(Clone, Debug)]
pub(crate) struct Index {
    lo: [f64; 3],
    inv: [f64; 3],
    dims: [usize; 3],
    start: Vec<u32>,
}

/// Most entries of the index grid.
const INDEX_MAX: usize = 1 << 21;

impl Index {
    #[allow(clippy::needless_range_loop)]
    pub(crate) fn new(tree: &Tree) -> Index {
        let [lo, hi] = tree.root_box();
        let dim = tree.dim;
        // Resolution of the smallest cell on each axis, within the limit.
        let mut side = [f64::INFINITY; 3];
        for c in &tree.leaves {
            for a in 0..dim {
                side[a] = side[a].min(c.1[a] - c.0[a]);
            }
        }
        let mut dims = [1usize; 3];
        for a in 0..dim {
            dims[a] = ((hi[a] - lo[a]) / side[a]).round().clamp(1.0, 1e9) as usize;
        }
        while dims.iter().product::<usize>() > INDEX_MAX {
            for d in dims.iter_mut().take(dim) {
                *d = (*d).div_ceil(2);
            }
        }
        let inv = std::array::from_fn(|a| dims[a] as f64 / (hi[a] - lo[a]));
        let mut start = Vec::with_capacity(dims.iter().product());
        for k in 0..dims[2] {
            for j in 0..dims[1] {
                for i in 0..dims[0] {
                    let ijk = [i, j, k];
                    let glo: [f64; 3] = std::array::from_fn(|a| {
                        lo[a] + (hi[a] - lo[a]) * ijk[a] as f64 / dims[a] as f64
                    });
                    let ghi: [f64; 3] = std::array::from_fn(|a| {
                        lo[a] + (hi[a] - lo[a]) * (ijk[a] + 1) as f64 / dims[a] as f64
                    });
                    let mut n = 0usize;
                    while let Node::Split { axis, at, kids } = tree.nodes[n] {
                        let a = axis as usize;
                        if ghi[a] <= at {
                            n = kids[0] as usize;
                        } else if glo[a] >= at {
                            n = kids[1] as usize;
                        } else {
                            break;
                        }
                    }
                    start.push(n as u32);
                }
            }
        }
        Index {
            lo,
            inv,
            dims,
            start,
        }
    }

    /// The leaf holding `p` (inside the root box).
    #[inline]
    #[allow(clippy::needless_range_loop)]
    fn leaf(&self, tree: &Tree, p: [f64; 3]) -> usize {
        let mut idx = 0;
        let mut stride = 1;
        for a in 0..3 {
            let t = (p[a] - self.lo[a]) * self.inv[a];
            let i = (t as i64).clamp(0, self.dims[a] as i64 - 1) as usize;
            idx += i * stride;
            stride *= self.dims[a];
        }
        let mut n = self.start[idx] as usize;
        loop {
            match tree.nodes[n] {
                Node::Leaf(l) => return l as usize,
                Node::Split { axis, at, kids } => {
                    n = if p[axis as usize] < at {
                        kids[0]
                    } else {
                        kids[1]
                    } as usize;
                }
            }
        }
    }
}

impl PoreField {
    /// The term `max(-c_C, -q_C)` of cell `c` at `p`, with its gradient if
    /// asked, given `-c_C` and its axis.
    #[inline]
    fn term(&self, c: usize, p: [f64; 3], box_d: f64, axis: usize, grad: bool) -> (f64, [f64; 3]) {
        let (nq, gq) = match &self.pores {
            Pores::Three(v) => {
                // Only pore cells are ever visited.
                let pore = v[c].as_ref().expect("a pore cell");
                let b = &self.boxes[c];
                let y: [f64; 3] = std::array::from_fn(|a| (p[a] - b.c[a]) * pore.inv_half[a]);
                let view = View {
                    n: self.texels,
                    values: &self.tables[pore.offset..pore.offset + 6 * (self.texels + 1).pow(2)],
                };
                let (g, dg) = view.gauge(y);
                (
                    pore.k * g - pore.m,
                    std::array::from_fn(|a| pore.k * dg[a] * pore.inv_half[a]),
                )
            }
            Pores::Two(v) => {
                let arcs = v[c].as_ref().expect("a pore cell");
                let (d, g) = signed_distance(arcs, [p[0], p[1]]);
                (-d, [-g[0], -g[1], 0.0])
            }
        };
        if box_d >= nq {
            let mut g = [0.0; 3];
            if grad {
                g[axis] = if p[axis] >= self.boxes[c].c[axis] {
                    1.0
                } else {
                    -1.0
                };
            }
            (box_d, g)
        } else {
            (nq, gq)
        }
    }

    /// A 2D cell's term, value only.
    #[inline(always)]
    fn term2_value(&self, c: usize, p: [f64; 3], box_d: f64) -> f64 {
        let Pores::Two(v) = &self.pores else {
            unreachable!("2D terms of a 3D field")
        };
        match &v[c] {
            Some(arcs) => box_d.max(-signed_distance(arcs, [p[0], p[1]]).0),
            None => f64::INFINITY,
        }
    }

    /// The 3D term of cell `c` at `p`: `max(-c_C, -q_C)` and `-c_C`.
    #[inline(always)]
    fn term3(&self, c: &Fast3, p: [f64; 3]) -> (f64, f64) {
        let d = [p[0] - c.c[0], p[1] - c.c[1], p[2] - c.c[2]];
        let bd = (d[0].abs() - c.h[0])
            .max(d[1].abs() - c.h[1])
            .max(d[2].abs() - c.h[2]);
        if c.off == u32::MAX {
            return (f64::INFINITY, bd);
        }
        let y = [d[0] * c.inv[0], d[1] * c.inv[1], d[2] * c.inv[2]];
        let a = [y[0].abs(), y[1].abs(), y[2].abs()];
        let len = (y[0] * y[0] + y[1] * y[1] + y[2] * y[2]).sqrt();
        if len == 0.0 {
            return (bd.max(-c.m), bd);
        }
        let (m, b, cc) = if a[0] >= a[1] && a[0] >= a[2] {
            (0, 1, 2)
        } else if a[1] >= a[2] {
            (1, 0, 2)
        } else {
            (2, 0, 1)
        };
        let n = self.texels;
        let half = 0.5 * n as f64;
        let inv = 1.0 / a[m];
        let tu = (y[b] * inv + 1.0) * half;
        let tv = (y[cc] * inv + 1.0) * half;
        let i = (tu as i32).clamp(0, n as i32 - 1) as usize;
        let j = (tv as i32).clamp(0, n as i32 - 1) as usize;
        let (fu, fv) = (tu - i as f64, tv - j as f64);
        let w = n + 1;
        let face = 2 * m + (y[m] < 0.0) as usize;
        let k = c.off as usize + (face * w + j) * w + i;
        let t = &self.tables[k..k + w + 2];
        let (r00, r10, r01, r11) = (t[0] as f64, t[1] as f64, t[w] as f64, t[w + 1] as f64);
        let lo = r00 + (r10 - r00) * fu;
        let hi = r01 + (r11 - r01) * fu;
        let nq = c.k * (len / (lo + (hi - lo) * fv)) - c.m;
        (bd.max(nq), bd)
    }

    /// The 3D value in a known leaf.
    #[inline(always)]
    fn value3(&self, p: [f64; 3], leaf: usize) -> f64 {
        let mut best = self.cap;
        let own = self.own[leaf];
        if own != NONE {
            let (t, bd) = self.term3(&self.fast3[own as usize], p);
            best = best.min(t);
            if best <= -bd {
                return best;
            }
        }
        let lb = &self.leaf_box[leaf];
        for side in 0..6 {
            let a = side / 2;
            let d = if side % 2 == 0 {
                p[a] - (lb.c[a] - lb.h[a])
            } else {
                lb.c[a] + lb.h[a] - p[a]
            };
            if d >= best {
                continue;
            }
            let k = leaf * 6 + side;
            let (s, e) = (self.cand_start[k] as usize, self.cand_start[k + 1] as usize);
            for &c in &self.cand[s..e] {
                let f = &self.fast3[c as usize];
                let bd = (p[0] - f.c[0]).abs() - f.h[0];
                let bd = bd.max((p[1] - f.c[1]).abs() - f.h[1]);
                let bd = bd.max((p[2] - f.c[2]).abs() - f.h[2]);
                if bd < best {
                    best = best.min(self.term3(f, p).0);
                }
            }
        }
        best
    }

    /// The value alone (3D: [`PoreField::value3`]).
    #[inline]
    fn value_only(&self, p: [f64; 3]) -> f64 {
        if p[0].is_nan() || p[1].is_nan() || p[2].is_nan() {
            return f64::NAN;
        }
        let [lo, hi] = &self.tree.root_box_ref();
        let q: [f64; 3] = std::array::from_fn(|a| p[a].clamp(lo[a], hi[a]));
        let leaf = self.index.leaf(&self.tree, q);
        if self.dim == 3 {
            return self.value3(p, leaf);
        }
        let mut best = self.cap;
        let own = self.own[leaf];
        if own != NONE {
            let bd = self.box_distance(own as usize, p).0;
            best = best.min(self.term2_value(own as usize, p, bd));
            if best <= -bd {
                return best;
            }
        }
        let lb = &self.leaf_box[leaf];
        for side in 0..2 * self.dim {
            let a = side / 2;
            // Distance from p to this side's plane (inwards positive):
            // cells beyond it are at least that far.
            let d = if side % 2 == 0 {
                p[a] - (lb.c[a] - lb.h[a])
            } else {
                lb.c[a] + lb.h[a] - p[a]
            };
            if d >= best {
                continue;
            }
            let k = leaf * 6 + side;
            let (s, e) = (self.cand_start[k] as usize, self.cand_start[k + 1] as usize);
            for &c in &self.cand[s..e] {
                let bd = self.box_distance(c as usize, p).0;
                if bd < best {
                    best = best.min(self.term2_value(c as usize, p, bd));
                }
            }
        }
        best
    }

    /// `-c_C(p)` (the Chebyshev distance outside the box, negative inside)
    /// and the axis that decides it.
    #[inline(always)]
    #[allow(clippy::needless_range_loop)]
    fn box_distance(&self, c: usize, p: [f64; 3]) -> (f64, usize) {
        let b = &self.boxes[c];
        let mut d = f64::NEG_INFINITY;
        let mut axis = 0;
        for a in 0..self.dim {
            let v = (p[a] - b.c[a]).abs() - b.h[a];
            if v > d {
                d = v;
                axis = a;
            }
        }
        (d, axis)
    }

    /// Value and gradient (the gradient of the deciding term).
    #[inline]
    fn value(&self, p: [f64; 3], grad: bool) -> (f64, [f64; 3]) {
        if p.iter().any(|v| v.is_nan()) {
            return (f64::NAN, [f64::NAN; 3]);
        }
        let [lo, hi] = self.tree.root_box();
        let q: [f64; 3] = std::array::from_fn(|a| p[a].clamp(lo[a], hi[a]));
        let leaf = self.index.leaf(&self.tree, q);
        let mut best = self.cap;
        let mut g = [0.0; 3];
        let own = self.own[leaf];
        if own != NONE {
            let (bd, axis) = self.box_distance(own as usize, p);
            let (t, tg) = self.term(own as usize, p, bd, axis, grad);
            if t < best {
                best = t;
                g = tg;
            }
            // Neighbours give at least the distance to this cell's faces.
            if best <= -bd {
                return (best, g);
            }
        }
        let lb = &self.leaf_box[leaf];
        for side in 0..2 * self.dim {
            let a = side / 2;
            let d = if side % 2 == 0 {
                p[a] - (lb.c[a] - lb.h[a])
            } else {
                lb.c[a] + lb.h[a] - p[a]
            };
            if d >= best {
                continue;
            }
            let k = leaf * 6 + side;
            let (s, e) = (self.cand_start[k] as usize, self.cand_start[k + 1] as usize);
            for &c in &self.cand[s..e] {
                let (bd, axis) = self.box_distance(c as usize, p);
                if bd >= best {
                    continue;
                }
                let (t, tg) = self.term(c as usize, p, bd, axis, grad);
                if t < best {
                    best = t;
                    g = tg;
                }
            }
        }
        (best, g)
    }

    /// The value cap (the field's largest value: solid far from any pore),
    /// half the smallest cell side.
    pub fn cap(&self) -> f64 {
        self.cap
    }

    /// A Lipschitz constant of the field.
    pub fn lipschitz(&self) -> f64 {
        self.lip
    }

    /// 2 or 3.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// The subdivision.
    pub fn tree(&self) -> &Tree {
        &self.tree
    }

    /// Heap bytes held by the field (tables, tree, index, lists).
    pub fn heap_bytes(&self) -> usize {
        let pores = match &self.pores {
            Pores::Two(v) => v.len() * std::mem::size_of::<Option<[Quad; 4]>>(),
            Pores::Three(v) => v.len() * std::mem::size_of::<Option<Pore3>>(),
        };
        self.tables.len() * 4
            + pores
            + self.boxes.len() * std::mem::size_of::<CellBox>()
            + (self.own.len() + self.cand_start.len() + self.cand.len() + self.index.start.len())
                * 4
            + self.leaf_box.len() * std::mem::size_of::<CellBox>()
            + self.fast3.len() * std::mem::size_of::<Fast3>()
            + self.tree.nodes.len() * std::mem::size_of::<Node>()
            + self.tree.leaves.len() * std::mem::size_of::<([f64; 3], [f64; 3], u32)>()
            + self.tree.cells.len() * std::mem::size_of::<crate::tree::Cell>()
    }
}

impl Field for PoreField {
    fn name(&self) -> &str {
        &self.name
    }

    fn eval(&self, p: [f64; 3]) -> f64 {
        self.value_only(p)
    }

    fn grad(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
        self.value(p, true)
    }

    fn interval(&self, b: [Interval; 3]) -> Interval {
        if b.iter().any(|i| i.is_nan()) {
            return Interval::nan();
        }
        let dim = self.dim;
        let lo: [f64; 3] = std::array::from_fn(|a| b[a].lo);
        let hi: [f64; 3] = std::array::from_fn(|a| b[a].hi);
        // No pore cell within the cap: the field is the cap throughout.
        let [rlo, rhi] = self.tree.root_box();
        let q: [f64; 3] = std::array::from_fn(|a| {
            if a < dim {
                (lo[a] - self.cap).max(rlo[a])
            } else {
                rlo[a]
            }
        });
        let r: [f64; 3] = std::array::from_fn(|a| {
            if a < dim {
                (hi[a] + self.cap).min(rhi[a])
            } else {
                rhi[a]
            }
        });
        let has_pore = |c: u32| match &self.pores {
            Pores::Two(v) => v[c as usize].is_some(),
            Pores::Three(v) => v[c as usize].is_some(),
        };
        if (0..dim).any(|a| q[a] > r[a]) || !self.tree.any(q, r, &has_pore) {
            return Interval::point(self.cap);
        }
        let c: [f64; 3] =
            std::array::from_fn(|a| if a < dim { 0.5 * (lo[a] + hi[a]) } else { 0.0 });
        let rad = (0..dim)
            .map(|a| (0.5 * (hi[a] - lo[a])).powi(2))
            .sum::<f64>()
            .sqrt();
        if !rad.is_finite() || !c.iter().all(|v| v.is_finite()) {
            return Interval::new(self.floor, self.cap);
        }
        let v = self.eval(c);
        let w = self.lip * rad;
        // Rounding in the value and the radius: widen slightly.
        let eps = 1e-12 * (v.abs() + w + self.cap);
        Interval::new((v - w).max(self.floor) - eps, (v + w).min(self.cap) + eps)
    }

    fn grad_interval(&self, _b: [Interval; 3]) -> [Interval; 3] {
        let l = Interval::new(-self.lip, self.lip);
        if self.dim == 2 {
            [l, l, Interval::point(0.0)]
        } else {
            [l, l, l]
        }
    }

    fn eval_batch(&self, x: &[f32], y: &[f32], z: &[f32], out: &mut [f32]) {
        if self.dim != 3 {
            for i in 0..out.len() {
                out[i] = self.value_only([x[i] as f64, y[i] as f64, z[i] as f64]) as f32;
            }
            return;
        }
        let n = out.len();
        let mut start = 0;
        while start < n {
            let m = CHUNK.min(n - start);
            let r = start..start + m;
            self.batch3(&x[r.clone()], &y[r.clone()], &z[r.clone()], &mut out[r]);
            start += m;
        }
    }
}

/// Points per pass of the 3D batch.
const CHUNK: usize = 64;

impl PoreField {
    /// Up to [`CHUNK`] points: leaves (the last one kept, as neighbouring
    /// points mostly share it), then the own cells' terms over runs of
    /// points in the same cell (straight-line loops the compiler
    /// vectorises, the table reads apart), then the neighbours for the
    /// points nearer to their cell's faces than to its pore.
    fn batch3(&self, x: &[f32], y: &[f32], z: &[f32], out: &mut [f32]) {
        let m = out.len();
        let mut px = [0.0f64; CHUNK];
        let mut py = [0.0f64; CHUNK];
        let mut pz = [0.0f64; CHUNK];
        let mut leafs = [u32::MAX; CHUNK];
        let mut own = [NONE; CHUNK];
        let [lo, hi] = self.tree.root_box_ref();
        let mut leaf = usize::MAX;
        let (mut llo, mut lhi) = ([0.0; 3], [0.0; 3]);
        for i in 0..m {
            let p = [x[i] as f64, y[i] as f64, z[i] as f64];
            (px[i], py[i], pz[i]) = (p[0], p[1], p[2]);
            if p[0].is_nan() || p[1].is_nan() || p[2].is_nan() {
                continue;
            }
            let q: [f64; 3] = std::array::from_fn(|a| p[a].clamp(lo[a], hi[a]));
            let hit = leaf != usize::MAX && (0..3).all(|a| q[a] >= llo[a] && q[a] < lhi[a]);
            if !hit {
                leaf = self.index.leaf(&self.tree, q);
                (llo, lhi, _) = self.tree.leaves[leaf];
            }
            leafs[i] = leaf as u32;
            own[i] = self.own[leaf];
        }
        let mut best = [self.cap; CHUNK];
        let mut inner = [f64::NEG_INFINITY; CHUNK];
        let mut s = 0;
        while s < m {
            let o = own[s];
            let mut e = s + 1;
            while e < m && own[e] == o {
                e += 1;
            }
            if o != NONE {
                self.own_run(
                    &self.fast3[o as usize],
                    &px[s..e],
                    &py[s..e],
                    &pz[s..e],
                    &mut best[s..e],
                    &mut inner[s..e],
                );
            }
            s = e;
        }
        for i in 0..m {
            out[i] = if leafs[i] == u32::MAX {
                f32::NAN
            } else if best[i] <= inner[i] {
                best[i] as f32
            } else {
                self.rest3([px[i], py[i], pz[i]], leafs[i] as usize, best[i]) as f32
            };
        }
    }

    /// The own cell's term for a run of points of that cell: `best` gets
    /// `min(cap, term)`, `inner` the distance to the cell's faces.
    #[inline(never)]
    fn own_run(
        &self,
        c: &Fast3,
        x: &[f64],
        y: &[f64],
        z: &[f64],
        best: &mut [f64],
        inner: &mut [f64],
    ) {
        let m = x.len();
        let (y, z, best, inner) = (&y[..m], &z[..m], &mut best[..m], &mut inner[..m]);
        let mut bd = [0.0f64; CHUNK];
        let mut len = [0.0f64; CHUNK];
        let mut fu = [0.0f64; CHUNK];
        let mut fv = [0.0f64; CHUNK];
        let mut idx = [0u32; CHUNK];
        let n = self.texels;
        let half = 0.5 * n as f64;
        let w = (n + 1) as i32;
        let top = n as i32 - 1;
        for i in 0..m {
            let d = [x[i] - c.c[0], y[i] - c.c[1], z[i] - c.c[2]];
            bd[i] = (d[0].abs() - c.h[0])
                .max(d[1].abs() - c.h[1])
                .max(d[2].abs() - c.h[2]);
            let q = [d[0] * c.inv[0], d[1] * c.inv[1], d[2] * c.inv[2]];
            let a = [q[0].abs(), q[1].abs(), q[2].abs()];
            len[i] = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt();
            let m0 = a[0] >= a[1] && a[0] >= a[2];
            let m1 = !m0 && a[1] >= a[2];
            let am = if m0 {
                a[0]
            } else if m1 {
                a[1]
            } else {
                a[2]
            };
            let ym = if m0 {
                q[0]
            } else if m1 {
                q[1]
            } else {
                q[2]
            };
            let yb = if m0 { q[1] } else { q[0] };
            let yc = if m0 || m1 { q[2] } else { q[1] };
            let axis = if m0 {
                0
            } else if m1 {
                1
            } else {
                2
            };
            let inv = 1.0 / am.max(f64::MIN_POSITIVE);
            let tu = (yb * inv + 1.0) * half;
            let tv = (yc * inv + 1.0) * half;
            let ii = (tu as i32).clamp(0, top);
            let jj = (tv as i32).clamp(0, top);
            fu[i] = tu - ii as f64;
            fv[i] = tv - jj as f64;
            let face = 2 * axis + (ym < 0.0) as i32;
            idx[i] = ((face * w + jj) * w + ii) as u32;
        }
        let t = &self.tables[c.off as usize..];
        let wu = w as usize;
        for i in 0..m {
            let k = idx[i] as usize;
            let (r00, r10) = (t[k] as f64, t[k + 1] as f64);
            let (r01, r11) = (t[k + wu] as f64, t[k + wu + 1] as f64);
            let lo = r00 + (r10 - r00) * fu[i];
            let hi = r01 + (r11 - r01) * fu[i];
            let nq = c.k * (len[i] / (lo + (hi - lo) * fv[i])) - c.m;
            best[i] = self.cap.min(bd[i].max(nq));
            inner[i] = -bd[i];
        }
    }

    /// The neighbours' terms for a point of `leaf`, from `best`.
    fn rest3(&self, p: [f64; 3], leaf: usize, mut best: f64) -> f64 {
        let lb = &self.leaf_box[leaf];
        for side in 0..6 {
            let a = side / 2;
            let d = if side % 2 == 0 {
                p[a] - (lb.c[a] - lb.h[a])
            } else {
                lb.c[a] + lb.h[a] - p[a]
            };
            if d >= best {
                continue;
            }
            let k = leaf * 6 + side;
            let (s, e) = (self.cand_start[k] as usize, self.cand_start[k + 1] as usize);
            for &c in &self.cand[s..e] {
                let f = &self.fast3[c as usize];
                let bd = (p[0] - f.c[0]).abs() - f.h[0];
                let bd = bd.max((p[1] - f.c[1]).abs() - f.h[1]);
                let bd = bd.max((p[2] - f.c[2]).abs() - f.h[2]);
                if bd < best {
                    best = best.min(self.term3(f, p).0);
                }
            }
        }
        best
    }
}

/// Per leaf: its own pore cell (or NONE), and per side of the leaf the
/// other pore cells within `cap` of it (Chebyshev, on the subdivided axes)
/// that lie beyond that side.
pub(crate) fn neighbours(
    tree: &Tree,
    cap: f64,
    has_pore: &dyn Fn(u32) -> bool,
) -> (Vec<u32>, Vec<u32>, Vec<u32>, Vec<CellBox>) {
    let mut own = Vec::with_capacity(tree.leaves.len());
    let mut start = Vec::with_capacity(6 * tree.leaves.len() + 1);
    let mut cand = Vec::new();
    let mut boxes = Vec::with_capacity(tree.leaves.len());
    let mut found = Vec::new();
    for &(lo, hi, cell) in &tree.leaves {
        own.push(if cell != NONE && has_pore(cell) {
            cell
        } else {
            NONE
        });
        boxes.push(CellBox {
            c: std::array::from_fn(|a| 0.5 * (lo[a] + hi[a])),
            h: std::array::from_fn(|a| 0.5 * (hi[a] - lo[a])),
        });
        let elo: [f64; 3] = std::array::from_fn(|a| if a < tree.dim { lo[a] - cap } else { lo[a] });
        let ehi: [f64; 3] = std::array::from_fn(|a| if a < tree.dim { hi[a] + cap } else { hi[a] });
        found.clear();
        tree.query(elo, ehi, &mut |c| {
            if c != cell && has_pore(c) {
                found.push(c);
            }
        });
        for side in 0..6 {
            start.push(cand.len() as u32);
            let a = side / 2;
            if a >= tree.dim {
                continue;
            }
            for &c in &found {
                let b = &tree.cells[c as usize];
                let beyond = if side % 2 == 0 {
                    b.hi[a] <= lo[a]
                } else {
                    b.lo[a] >= hi[a]
                };
                if beyond {
                    cand.push(c);
                }
            }
        }
    }
    start.push(cand.len() as u32);
    (own, start, cand, boxes)
}
