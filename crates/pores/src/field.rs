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
//! otherwise only those beyond the near sides.
//!
//! The 3D batch works in f32 on blocks of up to 256 points: it finds each
//! point's leaf (a whole block in one leaf is found with one look-up and a
//! vectorised check), groups the points by leaf, and computes the own
//! cell's term over a group in straight-line loops the compiler vectorises
//! (the four cube-map reads per point apart). A neighbour is then evaluated
//! only over the points it may lower: a lower bound of its term, the larger
//! of its box distance and `k |y| / R_max - m` (the gauge is at least
//! `|y| / R_max`, `R_max` the largest radius of its table), must be below a
//! point's value, and first a bound over the group's bounding box rules out
//! most neighbours at once. Skipped terms cannot lower the minimum, so the
//! batch gives the point values up to f32 rounding; slicing the bone of
//! `bench/run pores` costs 1.6 to 2 times slicing a gyroid of its cell
//! size (about 4 times with the earlier f64 batch).
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
    /// The same in f32, for the 3D batch.
    pub(crate) fast3f: Vec<Fast3f>,
    /// The leaf boxes in f32, for the 3D batch.
    pub(crate) leaf_box_f: Vec<LeafBoxF>,
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
            + self.fast3f.len() * std::mem::size_of::<Fast3f>()
            + self.leaf_box_f.len() * std::mem::size_of::<LeafBoxF>()
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

/// Points per pass of the 3D batch (the block of the batch evaluator).
const CHUNK: usize = 256;

/// Most distinct leaves one pass groups its points by; points of further
/// leaves take the scalar path (only scattered points get there).
const GROUPS: usize = 32;

/// The f32 copy of [`Fast3`] the batch reads (one cache line a cell).
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(64))]
pub(crate) struct Fast3f {
    c: [f32; 3],
    h: [f32; 3],
    inv: [f32; 3],
    k: f32,
    m: f32,
    off: u32,
    /// `k / R_max` with `R_max` the largest value of the pore's table:
    /// `kr |y| - m` is at most the pore's term at `y` (the gauge is at
    /// least `|y| / R_max`).
    kr: f32,
}

impl Fast3f {
    pub(crate) fn new(f: &Fast3, tables: &[f32], texels: usize) -> Fast3f {
        let kr = if f.off == u32::MAX {
            0.0
        } else {
            let o = f.off as usize;
            let rmax = tables[o..o + 6 * (texels + 1).pow(2)]
                .iter()
                .fold(0.0f32, |a, &v| a.max(v));
            // Rounded down, so the bound stays below the term.
            (f.k / rmax as f64 * (1.0 - 1e-6)) as f32
        };
        Fast3f {
            kr,
            c: f.c.map(|v| v as f32),
            h: f.h.map(|v| v as f32),
            inv: f.inv.map(|v| v as f32),
            k: f.k as f32,
            m: f.m as f32,
            off: f.off,
        }
    }
}

/// A leaf's faces in f32 (lower and upper corner), for the batch's side
/// distances.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct LeafBoxF {
    lo: [f32; 3],
    hi: [f32; 3],
}

impl LeafBoxF {
    pub(crate) fn new(b: &CellBox) -> LeafBoxF {
        LeafBoxF {
            lo: std::array::from_fn(|a| (b.c[a] - b.h[a]) as f32),
            hi: std::array::from_fn(|a| (b.c[a] + b.h[a]) as f32),
        }
    }
}

/// Per-point scratch of [`PoreField::terms3`].
struct Terms {
    bd: [f32; CHUNK],
    len: [f32; CHUNK],
    fu: [f32; CHUNK],
    fv: [f32; CHUNK],
    idx: [u32; CHUNK],
    /// The four table values around each point.
    r: [[f32; CHUNK]; 4],
    term: [f32; CHUNK],
}

/// Scratch of one batch pass (one per thread, reused).
struct Scratch {
    /// Group of each point (u8::MAX: NaN or scalar path).
    group: [u8; CHUNK],
    /// Point indices sorted by group.
    order: [u16; CHUNK],
    /// A group's points and values.
    g: [[f32; CHUNK]; 4],
    /// Its points that may need the neighbours: coordinates, values, and
    /// their place in the group.
    p: [[f32; CHUNK]; 4],
    at: [u16; CHUNK],
    /// Per such point: its value where the side in hand may lower it,
    /// else -inf.
    near: [f32; CHUNK],
    /// Per such point: whether the neighbour in hand may lower it.
    low: [bool; CHUNK],
    /// The points one neighbour may lower: their places among `p`, and
    /// their coordinates.
    sel: [u16; CHUNK],
    q: [[f32; CHUNK]; 3],
    terms: Terms,
}

impl Scratch {
    fn new() -> Box<Scratch> {
        Box::new(Scratch {
            group: [0; CHUNK],
            order: [0; CHUNK],
            g: [[0.0; CHUNK]; 4],
            p: [[0.0; CHUNK]; 4],
            at: [0; CHUNK],
            near: [0.0; CHUNK],
            low: [false; CHUNK],
            sel: [0; CHUNK],
            q: [[0.0; CHUNK]; 3],
            terms: Terms {
                bd: [0.0; CHUNK],
                len: [0.0; CHUNK],
                fu: [0.0; CHUNK],
                fv: [0.0; CHUNK],
                idx: [0; CHUNK],
                r: [[0.0; CHUNK]; 4],
                term: [0.0; CHUNK],
            },
        })
    }
}

thread_local! {
    static SCRATCH: std::cell::RefCell<Box<Scratch>> = std::cell::RefCell::new(Scratch::new());
}

impl PoreField {
    /// Up to [`CHUNK`] points: the leaf of every point (the last one kept,
    /// as neighbouring points mostly share it), the points grouped by leaf,
    /// and per group the own cell's term over all its points, then, for the
    /// points nearer to their cell's faces than to its pore, each neighbour
    /// that can lower the value of one of them over the points it can
    /// lower. All loops but the table reads are straight-line f32 the
    /// compiler vectorises; the values are the minimum over the same terms
    /// as [`PoreField::value3`] (skipped terms cannot lower it).
    fn batch3(&self, x: &[f32], y: &[f32], z: &[f32], out: &mut [f32]) {
        SCRATCH.with(|s| match s.try_borrow_mut() {
            Ok(mut sc) => self.batch3_in(x, y, z, out, &mut sc),
            Err(_) => self.batch3_in(x, y, z, out, &mut Scratch::new()),
        })
    }

    #[allow(clippy::needless_range_loop)]
    fn batch3_in(&self, x: &[f32], y: &[f32], z: &[f32], out: &mut [f32], sc: &mut Scratch) {
        let m = out.len();
        let [lo, hi] = self.tree.root_box_ref();
        if m > 0 && !(x[0].is_nan() || y[0].is_nan() || z[0].is_nan()) {
            // All in the leaf of the first point (the common case)?
            let p = [x[0] as f64, y[0] as f64, z[0] as f64];
            let q: [f64; 3] = std::array::from_fn(|a| p[a].clamp(lo[a], hi[a]));
            let leaf = self.index.leaf(&self.tree, q);
            let (llo, lhi, _) = self.tree.leaves[leaf];
            let mut all = true;
            for i in 0..m {
                let p = [x[i] as f64, y[i] as f64, z[i] as f64];
                for a in 0..3 {
                    let q = p[a].clamp(lo[a], hi[a]);
                    // NaN fails both.
                    all &= q >= llo[a] && q < lhi[a];
                }
            }
            if all {
                sc.g[0][..m].copy_from_slice(x);
                sc.g[1][..m].copy_from_slice(y);
                sc.g[2][..m].copy_from_slice(z);
                self.group3(leaf, m, sc);
                out.copy_from_slice(&sc.g[3][..m]);
                return;
            }
        }
        let mut leaves = [0u32; GROUPS];
        let mut ng = 0usize;
        // Whether every point is in the first group.
        let mut single = true;
        let mut leaf = usize::MAX;
        let mut g = u8::MAX;
        let (mut llo, mut lhi) = ([0.0; 3], [0.0; 3]);
        for i in 0..m {
            sc.group[i] = u8::MAX;
            let p = [x[i] as f64, y[i] as f64, z[i] as f64];
            if p[0].is_nan() || p[1].is_nan() || p[2].is_nan() {
                out[i] = f32::NAN;
                single = false;
                continue;
            }
            let q: [f64; 3] = std::array::from_fn(|a| p[a].clamp(lo[a], hi[a]));
            let hit = leaf != usize::MAX && (0..3).all(|a| q[a] >= llo[a] && q[a] < lhi[a]);
            if !hit {
                leaf = self.index.leaf(&self.tree, q);
                (llo, lhi, _) = self.tree.leaves[leaf];
                g = match leaves[..ng].iter().position(|&l| l as usize == leaf) {
                    Some(k) => k as u8,
                    None if ng < GROUPS => {
                        leaves[ng] = leaf as u32;
                        ng += 1;
                        (ng - 1) as u8
                    }
                    None => u8::MAX,
                };
            }
            if g == u8::MAX {
                out[i] = self.value3(p, leaf) as f32;
                single = false;
            } else {
                sc.group[i] = g;
                single &= g == 0;
            }
        }
        if ng == 0 {
            return;
        }
        if ng == 1 && single {
            // All in one leaf (the common case): no sorting.
            sc.g[0][..m].copy_from_slice(x);
            sc.g[1][..m].copy_from_slice(y);
            sc.g[2][..m].copy_from_slice(z);
            self.group3(leaves[0] as usize, m, sc);
            out.copy_from_slice(&sc.g[3][..m]);
            return;
        }
        // Per group, its points (few groups: a pass each).
        for k in 0..ng {
            let mut n = 0;
            for i in 0..m {
                sc.order[n] = i as u16;
                n += (sc.group[i] as usize == k) as usize;
            }
            for j in 0..n {
                let i = sc.order[j] as usize;
                (sc.g[0][j], sc.g[1][j], sc.g[2][j]) = (x[i], y[i], z[i]);
            }
            self.group3(leaves[k] as usize, n, sc);
            for j in 0..n {
                out[sc.order[j] as usize] = sc.g[3][j];
            }
        }
    }

    /// The values of the `n` points `sc.g[0..3]`, all in `leaf`, into
    /// `sc.g[3]`.
    #[allow(clippy::needless_range_loop)]
    fn group3(&self, leaf: usize, n: usize, sc: &mut Scratch) {
        let cap = self.cap as f32;
        let own = self.own[leaf];
        let Scratch {
            g,
            p,
            at,
            near,
            low,
            sel,
            q,
            terms,
            ..
        } = sc;
        let [gx, gy, gz, best] = g;
        let (gx, gy, gz, best) = (&gx[..n], &gy[..n], &gz[..n], &mut best[..n]);
        let mut np = 0;
        if own != NONE {
            self.terms3(&self.fast3f[own as usize], gx, gy, gz, terms);
            for j in 0..n {
                best[j] = cap.min(terms.term[j]);
            }
            // Neighbours give at least the distance to this cell's faces:
            // keep the points nearer to those than to the own pore.
            let mut any = false;
            for j in 0..n {
                any |= best[j] > -terms.bd[j];
            }
            if !any {
                return;
            }
            for j in 0..n {
                at[np] = j as u16;
                np += (best[j] > -terms.bd[j]) as usize;
            }
            for t in 0..np {
                let j = at[t] as usize;
                (p[0][t], p[1][t], p[2][t], p[3][t]) = (gx[j], gy[j], gz[j], best[j]);
            }
        } else {
            best.fill(cap);
            p[0][..n].copy_from_slice(gx);
            p[1][..n].copy_from_slice(gy);
            p[2][..n].copy_from_slice(gz);
            p[3][..n].fill(cap);
            for (j, a) in at[..n].iter_mut().enumerate() {
                *a = j as u16;
            }
            np = n;
        }
        if np == 0 {
            return;
        }
        let [px, py, pz, pb] = p;
        let (px, py, pz, pb) = (&px[..np], &py[..np], &pz[..np], &mut pb[..np]);
        let near = &mut near[..np];
        let low = &mut low[..np];
        let lb = &self.leaf_box_f[leaf];
        // Bounding box of those points and their largest value: a cell
        // farther from the box than that lowers none of them.
        let (mut blo, mut bhi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        let mut top = f32::NEG_INFINITY;
        for j in 0..np {
            for (a, v) in [px[j], py[j], pz[j]].into_iter().enumerate() {
                blo[a] = blo[a].min(v);
                bhi[a] = bhi[a].max(v);
            }
            top = top.max(pb[j]);
        }
        for side in 0..6 {
            let k = leaf * 6 + side;
            let (s, e) = (self.cand_start[k] as usize, self.cand_start[k + 1] as usize);
            if s == e {
                continue;
            }
            // Distance to this side's plane (cells beyond it are at least
            // that far): where that is not below the value, -inf rules
            // them out.
            let a = side / 2;
            let pa = [px, py, pz][a];
            let mut any = false;
            for j in 0..np {
                let d = if side % 2 == 0 {
                    pa[j] - lb.lo[a]
                } else {
                    lb.hi[a] - pa[j]
                };
                let keep = d < pb[j];
                near[j] = if keep { pb[j] } else { f32::NEG_INFINITY };
                any |= keep;
            }
            if !any {
                continue;
            }
            for &c in &self.cand[s..e] {
                let f = &self.fast3f[c as usize];
                let gap = (0..3)
                    .map(|a| (blo[a] - f.c[a]).max(f.c[a] - bhi[a]) - f.h[a])
                    .fold(f32::NEG_INFINITY, f32::max);
                if gap >= top {
                    continue;
                }
                // The points whose value this cell's box distance is below.
                // A lower bound of the term (the box distance, and the
                // gauge bound), then the points it may lower.
                let mut any = false;
                for j in 0..np {
                    let d = [px[j] - f.c[0], py[j] - f.c[1], pz[j] - f.c[2]];
                    let bd = (d[0].abs() - f.h[0])
                        .max(d[1].abs() - f.h[1])
                        .max(d[2].abs() - f.h[2]);
                    let y = [d[0] * f.inv[0], d[1] * f.inv[1], d[2] * f.inv[2]];
                    let len = (y[0] * y[0] + y[1] * y[1] + y[2] * y[2]).sqrt();
                    let lower = bd.max(f.kr * len - f.m) < near[j];
                    low[j] = lower;
                    any |= lower;
                }
                if !any {
                    continue;
                }
                let mut ns = 0;
                for j in 0..np {
                    sel[ns] = j as u16;
                    ns += low[j] as usize;
                }
                if ns == 0 {
                    continue;
                }
                if 2 * ns > np {
                    self.terms3(f, px, py, pz, terms);
                    for j in 0..np {
                        pb[j] = pb[j].min(terms.term[j]);
                        near[j] = near[j].min(pb[j]);
                    }
                } else {
                    for t in 0..ns {
                        let j = sel[t] as usize;
                        (q[0][t], q[1][t], q[2][t]) = (px[j], py[j], pz[j]);
                    }
                    self.terms3(f, &q[0][..ns], &q[1][..ns], &q[2][..ns], terms);
                    for t in 0..ns {
                        let j = sel[t] as usize;
                        pb[j] = pb[j].min(terms.term[t]);
                        near[j] = near[j].min(pb[j]);
                    }
                }
            }
        }
        for j in 0..np {
            best[at[j] as usize] = pb[j];
        }
    }

    /// The term `max(-c_C, -q_C)` of pore cell `c` at the points into
    /// `sc.term`, `-c_C` into `sc.bd`.
    #[inline(never)]
    #[allow(clippy::needless_range_loop)]
    fn terms3(&self, c: &Fast3f, x: &[f32], y: &[f32], z: &[f32], sc: &mut Terms) {
        let m = x.len();
        let (y, z) = (&y[..m], &z[..m]);
        let (bd, len, fu, fv, idx) = (
            &mut sc.bd[..m],
            &mut sc.len[..m],
            &mut sc.fu[..m],
            &mut sc.fv[..m],
            &mut sc.idx[..m],
        );
        let n = self.texels;
        let half = 0.5 * n as f32;
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
            let inv = 1.0 / am.max(f32::MIN_POSITIVE);
            let tu = (yb * inv + 1.0) * half;
            let tv = (yc * inv + 1.0) * half;
            let ii = (tu as i32).clamp(0, top);
            let jj = (tv as i32).clamp(0, top);
            fu[i] = tu - ii as f32;
            fv[i] = tv - jj as f32;
            let face = 2 * axis + (ym < 0.0) as i32;
            idx[i] = ((face * w + jj) * w + ii) as u32;
        }
        let wu = w as usize;
        let t = &self.tables[c.off as usize..c.off as usize + 6 * wu * wu];
        let [r00, r10, r01, r11] = &mut sc.r;
        for i in 0..m {
            let k = idx[i] as usize;
            let v = &t[k..k + wu + 2];
            (r00[i], r10[i], r01[i], r11[i]) = (v[0], v[1], v[wu], v[wu + 1]);
        }
        let term = &mut sc.term[..m];
        let (r00, r10, r01, r11) = (&r00[..m], &r10[..m], &r01[..m], &r11[..m]);
        for i in 0..m {
            let lo = r00[i] + (r10[i] - r00[i]) * fu[i];
            let hi = r01[i] + (r11[i] - r01[i]) * fu[i];
            let nq = c.k * (len[i] / (lo + (hi - lo) * fv[i])) - c.m;
            term[i] = bd[i].max(nq);
        }
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
