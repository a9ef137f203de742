//! Strut lattices as explicit graphs: nodes, beams between them and a
//! radius at each beam end.
//!
//! The same lattices as [`crate::struts`], but as data instead of an
//! expression: [`StrutGraph::tile`] lays a family over a box with a cell
//! size and a (possibly graded) radius sampled at every beam end,
//! [`StrutGraph::clip_box`] and [`StrutGraph::clip`] drop the beams that
//! cannot touch a part, and [`StrutGraph::field`] turns any graph back into
//! an FRep ([`StrutGraphField`], usable in every evaluation mode through
//! [`microfrep_core::Expr::field`]). Writers of beam-lattice files (3MF)
//! take the graph; readers give one back.
//!
//! A beam with end radii `r1`, `r2` is the solid swept by a ball whose radius
//! goes linearly from `r1` to `r2` along the axis (a frustum), united with
//! balls of radius `r1` and `r2` at its ends: with equal radii, exactly the
//! capsule of [`crate::struts::strut_cell`].
//!
//! ```
//! use microfrep_structures::strut_graph::StrutGraph;
//! use microfrep_structures::struts::StrutLattice;
//! use microfrep_core::Field;
//! // Cells are centred on multiples of the cell size, as in `strut_lattice`.
//! let g = StrutGraph::tile(StrutLattice::SimpleCubic, [-0.5; 3], [0.5; 3], 1.0, |_| 0.1).unwrap();
//! // The 12 cube edges, and the 3 outward edges at each of the 8 corners,
//! // whose round ends reach into the box.
//! assert_eq!(g.beams.len(), 36);
//! let f = g.field().unwrap();
//! assert!((f.eval([0.0, 0.5, 0.5]) - 0.1).abs() < 1e-12); // on an edge axis
//! assert!(f.eval([0.0, 0.0, 0.0]) < 0.0); // cell centre
//! ```

use crate::error::{check_box, Error, Result};
use crate::struts::StrutLattice;
use microfrep_core::{Expr, Field, Interval, IntervalEval, Tape};
use rayon::prelude::*;
use std::collections::HashMap;
use std::sync::Arc;

/// Most beams a tiling may produce, so that an absurd box or cell size is an
/// error and not an allocation failure (about 6 GiB of nodes and beams).
pub const MAX_BEAMS: usize = 1 << 27;

/// A strut lattice as a graph.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StrutGraph {
    /// Node positions (length units).
    pub nodes: Vec<[f64; 3]>,
    /// Beams as pairs of node indices.
    pub beams: Vec<(u32, u32)>,
    /// Radius at the first and the second end of each beam (same length as
    /// `beams`).
    pub radii: Vec<[f64; 2]>,
}

impl StrutLattice {
    /// The struts of [`StrutLattice::struts`] (every strut that comes within
    /// [`crate::struts::MAX_RADIUS`] of the unit cell) as a graph with shared
    /// nodes, radius `r` on every beam end.
    pub fn cell_graph(self, r: f64) -> StrutGraph {
        let mut g = StrutGraph::default();
        let mut index: HashMap<[i64; 3], u32> = HashMap::new();
        let mut node = |g: &mut StrutGraph, p: [f64; 3]| -> u32 {
            // Nodes lie on the quarter grid, so this key is exact.
            let key = p.map(|c| (c * 4.0).round() as i64);
            *index.entry(key).or_insert_with(|| {
                g.nodes.push(p);
                (g.nodes.len() - 1) as u32
            })
        };
        for (a, b) in self.struts() {
            let (ia, ib) = (node(&mut g, a), node(&mut g, b));
            g.beams.push((ia, ib));
            g.radii.push([r, r]);
        }
        g
    }
}

impl StrutGraph {
    /// The lattice `kind` with cubic cells of side `cell`, placed as
    /// [`crate::struts::strut_lattice`] places it (the unit cell `[0, 1]^3`
    /// maps to `[-cell/2, cell/2]^3`, so cell centres are on multiples of
    /// `cell`), over the box `[min, max]`: every beam whose
    /// solid reaches into the box, so that the graph clipped to the box is
    /// the lattice of [`crate::struts::strut_lattice`] clipped to the box.
    /// `radius` is sampled at both ends of every beam; it must be positive
    /// and finite there.
    pub fn tile(
        kind: StrutLattice,
        min: [f64; 3],
        max: [f64; 3],
        cell: f64,
        radius: impl Fn([f64; 3]) -> f64,
    ) -> Result<StrutGraph> {
        check_box(min, max)?;
        if !(cell.is_finite() && cell > 0.0) {
            return Err(Error::OutOfRange {
                what: "cell size",
                value: cell,
                expected: "positive and finite",
            });
        }
        // Cells meeting the box grown by one cell, so beams from outside
        // nodes that reach in are generated too.
        let lo: [i64; 3] = std::array::from_fn(|a| (min[a] / cell + 0.5).floor() as i64 - 1);
        let hi: [i64; 3] = std::array::from_fn(|a| (max[a] / cell + 0.5).ceil() as i64 + 1);
        let offsets = kind.bond_offsets();
        let (basis, _) = kind.basis();
        let per_cell: usize = offsets.iter().map(Vec::len).sum::<usize>() / 2;
        let cells = (0..3)
            .map(|a| (hi[a] - lo[a]).max(0) as u128)
            .product::<u128>();
        if cells.saturating_mul(per_cell as u128) > MAX_BEAMS as u128 {
            return Err(Error::OutOfRange {
                what: "beams in the tiling (cells x beams per cell)",
                value: cells as f64 * per_cell as f64,
                expected: "at most MAX_BEAMS = 2^27",
            });
        }
        let pos = |q: [i64; 3]| q.map(|c| c as f64 * cell / 4.0 - cell / 2.0);
        let mut g = StrutGraph::default();
        let mut index: HashMap<[i64; 3], u32> = HashMap::new();
        let mut node = |g: &mut StrutGraph, q: [i64; 3]| -> u32 {
            *index.entry(q).or_insert_with(|| {
                g.nodes.push(pos(q));
                (g.nodes.len() - 1) as u32
            })
        };
        for k in lo[2]..hi[2] {
            for j in lo[1]..hi[1] {
                for i in lo[0]..hi[0] {
                    for (b, q) in basis.iter().enumerate() {
                        let a: [i64; 3] = [
                            q[0] as i64 + 4 * i,
                            q[1] as i64 + 4 * j,
                            q[2] as i64 + 4 * k,
                        ];
                        for d in &offsets[b] {
                            let e: [i64; 3] = std::array::from_fn(|c| a[c] + d[c] as i64);
                            // Each bond once: from its lexicographically smaller end.
                            if e <= a {
                                continue;
                            }
                            let (pa, pe) = (pos(a), pos(e));
                            let r = [radius(pa), radius(pe)];
                            if let Some(&rv) = r.iter().find(|v| !(v.is_finite() && **v > 0.0)) {
                                return Err(Error::OutOfRange {
                                    what: "strut radius",
                                    value: rv,
                                    expected: "positive and finite at every beam end",
                                });
                            }
                            if segment_box_distance(pa, pe, min, max) > r[0].max(r[1]) {
                                continue;
                            }
                            let (ia, ie) = (node(&mut g, a), node(&mut g, e));
                            g.beams.push((ia, ie));
                            g.radii.push(r);
                        }
                    }
                }
            }
        }
        Ok(g)
    }

    /// Number of beams.
    pub fn len(&self) -> usize {
        self.beams.len()
    }

    /// Whether the graph has no beams.
    pub fn is_empty(&self) -> bool {
        self.beams.is_empty()
    }

    /// Checks indices, lengths and values: every beam end indexes a node,
    /// nodes are finite, radii positive and finite, beams have two distinct
    /// ends. Errors name the first offending beam or node.
    pub fn validate(&self) -> Result<()> {
        if self.radii.len() != self.beams.len() {
            return Err(Error::OutOfRange {
                what: "radii count (must equal the beam count)",
                value: self.radii.len() as f64,
                expected: "one [r1, r2] per beam",
            });
        }
        if let Some(p) = self
            .nodes
            .iter()
            .position(|p| p.iter().any(|c| !c.is_finite()))
        {
            let q = self.nodes[p];
            return Err(Error::NotFinite {
                value: f64::NAN,
                x: q[0],
                y: q[1],
                z: q[2],
            });
        }
        let n = self.nodes.len() as u32;
        for (i, (&(a, b), r)) in self.beams.iter().zip(&self.radii).enumerate() {
            if a >= n || b >= n || a == b {
                return Err(Error::OutOfRange {
                    what: "beam node index",
                    value: i as f64,
                    expected: "beam ends must be two distinct node indices below the node count",
                });
            }
            if r.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
                return Err(Error::OutOfRange {
                    what: "strut radius",
                    value: r[0].min(r[1]),
                    expected: "positive and finite at every beam end",
                });
            }
        }
        Ok(())
    }

    /// The beams whose solid reaches into the box `[min, max]`; nodes not
    /// used by any kept beam are dropped (indices renumbered, order kept).
    pub fn clip_box(&self, min: [f64; 3], max: [f64; 3]) -> StrutGraph {
        let keep: Vec<bool> = self
            .beams
            .iter()
            .zip(&self.radii)
            .map(|(&(a, b), r)| {
                segment_box_distance(self.nodes[a as usize], self.nodes[b as usize], min, max)
                    <= r[0].max(r[1])
            })
            .collect();
        self.keep_beams(&keep)
    }

    /// The beams that may touch the inside (`f >= 0`) of `part`: a beam is
    /// dropped only when interval evaluation proves `part < 0` on boxes
    /// covering its whole solid (16 pieces along its axis), so no beam that
    /// touches the part is lost; the ones kept near the surface are cut by
    /// the part itself when both are combined (a clipping mesh in 3MF).
    pub fn clip(&self, part: &Expr) -> StrutGraph {
        let tape = Tape::new(part);
        const PIECES: usize = 16;
        let keep: Vec<bool> = self
            .beams
            .par_iter()
            .zip(&self.radii)
            .map_init(
                || IntervalEval::new(&tape),
                |ev, (&(a, b), r)| {
                    let (pa, pb) = (self.nodes[a as usize], self.nodes[b as usize]);
                    let rr = r[0].max(r[1]);
                    (0..PIECES).any(|s| {
                        let t0 = s as f64 / PIECES as f64;
                        let t1 = (s + 1) as f64 / PIECES as f64;
                        let iv: [Interval; 3] = std::array::from_fn(|c| {
                            let u = pa[c] + (pb[c] - pa[c]) * t0;
                            let v = pa[c] + (pb[c] - pa[c]) * t1;
                            Interval::new(u.min(v) - rr, u.max(v) + rr)
                        });
                        let v = ev.eval(iv[0], iv[1], iv[2]);
                        // NaN-possible boxes are kept: nothing is proven there.
                        v.hi >= 0.0 || v.may_be_nan()
                    })
                },
            )
            .collect();
        self.keep_beams(&keep)
    }

    fn keep_beams(&self, keep: &[bool]) -> StrutGraph {
        let mut map = vec![u32::MAX; self.nodes.len()];
        let mut g = StrutGraph::default();
        for (i, &(a, b)) in self.beams.iter().enumerate() {
            if !keep[i] {
                continue;
            }
            let mut m = |n: u32| {
                if map[n as usize] == u32::MAX {
                    map[n as usize] = g.nodes.len() as u32;
                    g.nodes.push(self.nodes[n as usize]);
                }
                map[n as usize]
            };
            let (na, nb) = (m(a), m(b));
            g.beams.push((na, nb));
            g.radii.push(self.radii[i]);
        }
        g
    }

    /// Axis-aligned bounds of the solid (beams grown by their radii), or
    /// `None` for an empty graph.
    pub fn bounds(&self) -> Option<[[f64; 3]; 2]> {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for (&(a, b), r) in self.beams.iter().zip(&self.radii) {
            for (n, rv) in [(a, r[0]), (b, r[1])] {
                let p = self.nodes[n as usize];
                for c in 0..3 {
                    lo[c] = lo[c].min(p[c] - rv);
                    hi[c] = hi[c].max(p[c] + rv);
                }
            }
        }
        (!self.beams.is_empty()).then_some([lo, hi])
    }

    /// The solid as a field (checked with [`StrutGraph::validate`] first).
    pub fn field(&self) -> Result<StrutGraphField> {
        StrutGraphField::new(self)
    }

    /// The solid as an expression node.
    pub fn expr(&self) -> Result<Expr> {
        Ok(Expr::field(Arc::new(self.field()?)))
    }
}

/// Distance from the segment `a b` to the box `[min, max]`: convex along the
/// segment, minimised by ternary search to well below any radius.
fn segment_box_distance(a: [f64; 3], b: [f64; 3], min: [f64; 3], max: [f64; 3]) -> f64 {
    let d = |t: f64| {
        (0..3)
            .map(|i| {
                let c = a[i] + (b[i] - a[i]) * t;
                (min[i] - c).max(c - max[i]).max(0.0).powi(2)
            })
            .sum::<f64>()
            .sqrt()
    };
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    for _ in 0..60 {
        let m1 = lo + (hi - lo) / 3.0;
        let m2 = hi - (hi - lo) / 3.0;
        if d(m1) <= d(m2) {
            hi = m2;
        } else {
            lo = m1;
        }
    }
    d(0.0).min(d(1.0)).min(d((lo + hi) / 2.0))
}

/// One beam, prepared for evaluation.
#[derive(Clone, Copy, Debug)]
struct Seg {
    a: [f64; 3],
    b: [f64; 3],
    e: [f64; 3],
    e2: f64,
    r: [f64; 2],
}

impl Seg {
    /// Value and gradient: `max(r(t) - |p - q(t)|, r1 - |p - a|, r2 - |p - b|)`
    /// with `q(t)` the closest axis point (`t` clamped to the beam).
    fn grad(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
        let d: [f64; 3] = std::array::from_fn(|i| p[i] - self.a[i]);
        let tr = (d[0] * self.e[0] + d[1] * self.e[1] + d[2] * self.e[2]) / self.e2;
        let t = tr.clamp(0.0, 1.0);
        let interior = tr > 0.0 && tr < 1.0;
        let w: [f64; 3] = std::array::from_fn(|i| d[i] - t * self.e[i]);
        let dist = norm(w);
        let rt = self.r[0] + (self.r[1] - self.r[0]) * t;
        let unit = |v: [f64; 3], n: f64| -> [f64; 3] {
            if n > 0.0 {
                v.map(|c| c / n)
            } else {
                [0.0; 3]
            }
        };
        let u = unit(w, dist);
        let dr = if interior {
            (self.r[1] - self.r[0]) / self.e2
        } else {
            0.0
        };
        let mut best = (rt - dist, std::array::from_fn(|i| dr * self.e[i] - u[i]));
        if self.r[0] != self.r[1] {
            for (c, r) in [(self.a, self.r[0]), (self.b, self.r[1])] {
                let v: [f64; 3] = std::array::from_fn(|i| p[i] - c[i]);
                let n = norm(v);
                if r - n > best.0 {
                    let uv = unit(v, n);
                    best = (r - n, uv.map(|x| -x));
                }
            }
        }
        best
    }

    fn eval(&self, p: [f64; 3]) -> f64 {
        self.grad(p).0
    }

    /// Distance from `p` to the axis segment.
    fn axis_distance(&self, p: [f64; 3]) -> f64 {
        let d: [f64; 3] = std::array::from_fn(|i| p[i] - self.a[i]);
        let t =
            ((d[0] * self.e[0] + d[1] * self.e[1] + d[2] * self.e[2]) / self.e2).clamp(0.0, 1.0);
        norm(std::array::from_fn(|i| d[i] - t * self.e[i]))
    }
}

fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// The solid of a [`StrutGraph`] as an FRep: the largest beam value at the
/// point, clamped below at `-cutoff` (so that only beams within
/// `cutoff + radius` of a point matter and a bucket grid finds them; the
/// clamp keeps the same solid, its value is a lower bound of the
/// distance-like value where it applies). Beams are sorted into a uniform
/// grid of buckets over the graph's bounds.
#[derive(Debug)]
pub struct StrutGraphField {
    segs: Vec<Seg>,
    cutoff: f64,
    rmax: f64,
    origin: [f64; 3],
    bucket: f64,
    dims: [usize; 3],
    /// Compressed rows: beams of bucket `i` are `items[start[i]..start[i + 1]]`.
    start: Vec<u32>,
    items: Vec<u32>,
}

/// Most buckets of the grid (the bucket size grows to stay below it).
const MAX_BUCKETS: usize = 1 << 22;

impl StrutGraphField {
    /// Builds the bucket grid (the graph is checked first).
    pub fn new(g: &StrutGraph) -> Result<StrutGraphField> {
        g.validate()?;
        let segs: Vec<Seg> = g
            .beams
            .iter()
            .zip(&g.radii)
            .map(|(&(a, b), r)| {
                let (a, b) = (g.nodes[a as usize], g.nodes[b as usize]);
                let e: [f64; 3] = std::array::from_fn(|i| b[i] - a[i]);
                let e2 = (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).max(f64::MIN_POSITIVE);
                Seg { a, b, e, e2, r: *r }
            })
            .collect();
        let rmax = g.radii.iter().flatten().fold(0.0f64, |m, &r| m.max(r));
        let [lo, hi] = g.bounds().unwrap_or([[0.0; 3], [1.0; 3]]);
        let mean_len = if segs.is_empty() {
            1.0
        } else {
            segs.iter().map(|s| s.e2.sqrt()).sum::<f64>() / segs.len() as f64
        };
        let cutoff = (2.0 * rmax).max(1e-9);
        let mut bucket = (mean_len / 2.0).max(cutoff);
        let reach = cutoff + rmax;
        // The grid covers the solid grown by `reach`: outside it every beam
        // value is below -cutoff, so the clamp is exact there.
        let origin: [f64; 3] = std::array::from_fn(|i| lo[i] - reach);
        let ext: [f64; 3] = std::array::from_fn(|i| hi[i] - lo[i] + 2.0 * reach);
        let dims = loop {
            let d: [usize; 3] = std::array::from_fn(|i| (ext[i] / bucket).ceil() as usize + 1);
            if d.iter().product::<usize>() <= MAX_BUCKETS {
                break d;
            }
            bucket *= 1.5;
        };
        let span = |lo: f64, hi: f64, a: usize| -> (usize, usize) {
            let f =
                |v: f64| (((v - origin[a]) / bucket).floor().max(0.0) as usize).min(dims[a] - 1);
            (f(lo), f(hi))
        };
        // Two passes: count, then fill.
        let nb = dims[0] * dims[1] * dims[2];
        let mut count = vec![0u32; nb + 1];
        let each = |s: &Seg, f: &mut dyn FnMut(usize)| {
            let r: [(usize, usize); 3] = std::array::from_fn(|a| {
                span(s.a[a].min(s.b[a]) - reach, s.a[a].max(s.b[a]) + reach, a)
            });
            for k in r[2].0..=r[2].1 {
                for j in r[1].0..=r[1].1 {
                    for i in r[0].0..=r[0].1 {
                        f(i + dims[0] * (j + dims[1] * k));
                    }
                }
            }
        };
        for s in &segs {
            each(s, &mut |b| count[b + 1] += 1);
        }
        for i in 0..nb {
            count[i + 1] += count[i];
        }
        let total = count[nb] as usize;
        let mut items = vec![0u32; total];
        let mut fill = count.clone();
        for (n, s) in segs.iter().enumerate() {
            each(s, &mut |b| {
                items[fill[b] as usize] = n as u32;
                fill[b] += 1;
            });
        }
        Ok(StrutGraphField {
            segs,
            cutoff,
            rmax,
            origin,
            bucket,
            dims,
            start: count,
            items,
        })
    }

    /// The value below which the field is clamped (as a positive number).
    pub fn cutoff(&self) -> f64 {
        self.cutoff
    }

    fn bucket_of(&self, p: [f64; 3]) -> Option<usize> {
        let mut idx = [0usize; 3];
        for a in 0..3 {
            let t = ((p[a] - self.origin[a]) / self.bucket).floor();
            if !(t >= 0.0 && t < self.dims[a] as f64) {
                return None;
            }
            idx[a] = t as usize;
        }
        Some(idx[0] + self.dims[0] * (idx[1] + self.dims[1] * idx[2]))
    }

    fn beams_in(&self, b: usize) -> &[u32] {
        &self.items[self.start[b] as usize..self.start[b + 1] as usize]
    }
}

impl Field for StrutGraphField {
    fn name(&self) -> &str {
        "strut-graph"
    }

    fn eval(&self, p: [f64; 3]) -> f64 {
        if p.iter().any(|c| c.is_nan()) {
            return f64::NAN;
        }
        let mut v = -self.cutoff;
        if let Some(b) = self.bucket_of(p) {
            for &n in self.beams_in(b) {
                v = v.max(self.segs[n as usize].eval(p));
            }
        }
        v
    }

    fn grad(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
        if p.iter().any(|c| c.is_nan()) {
            return (f64::NAN, [f64::NAN; 3]);
        }
        let mut best = (-self.cutoff, [0.0; 3]);
        if let Some(b) = self.bucket_of(p) {
            for &n in self.beams_in(b) {
                let g = self.segs[n as usize].grad(p);
                if g.0 > best.0 {
                    best = g;
                }
            }
        }
        best
    }

    fn interval(&self, b: [Interval; 3]) -> Interval {
        if b.iter().any(|i| i.is_nan() || i.may_be_nan()) {
            return Interval::nan();
        }
        // Every beam value is within [rmin - d, rmax - d] with d the distance
        // to its axis, which is 1-Lipschitz: bound it from the box centre.
        let c: [f64; 3] = std::array::from_fn(|a| b[a].mid());
        let half = norm(std::array::from_fn(|a| b[a].width() / 2.0));
        let whole = Interval::new(-self.cutoff, self.rmax.max(-self.cutoff));
        if !half.is_finite() || !c.iter().all(|v| v.is_finite()) {
            return whole;
        }
        let mut span = [(0usize, 0usize); 3];
        let mut outside = false;
        for a in 0..3 {
            let f = |v: f64| ((v - self.origin[a]) / self.bucket).floor();
            let (l, h) = (f(b[a].lo), f(b[a].hi));
            let top = (self.dims[a] - 1) as f64;
            if h < 0.0 || l > top {
                // Entirely outside the grid: every beam is beyond the cutoff.
                return Interval::point(-self.cutoff);
            }
            outside |= l < 0.0 || h > top;
            span[a] = (l.max(0.0) as usize, h.min(top) as usize);
        }
        let n_buckets: usize = span.iter().map(|&(l, h)| h - l + 1).product();
        if n_buckets > 512 {
            return whole;
        }
        let mut beams: Vec<u32> = Vec::new();
        for k in span[2].0..=span[2].1 {
            for j in span[1].0..=span[1].1 {
                for i in span[0].0..=span[0].1 {
                    beams.extend_from_slice(
                        self.beams_in(i + self.dims[0] * (j + self.dims[1] * k)),
                    );
                }
            }
        }
        beams.sort_unstable();
        beams.dedup();
        let mut lo = -self.cutoff;
        let mut hi = -self.cutoff;
        for &n in &beams {
            let s = &self.segs[n as usize];
            let d = s.axis_distance(c);
            let (rmin, rmax) = (s.r[0].min(s.r[1]), s.r[0].max(s.r[1]));
            lo = lo.max(rmin - (d + half));
            hi = hi.max(rmax - (d - half).max(0.0));
        }
        if outside {
            // Parts of the box outside the grid are clamped values (-cutoff).
            lo = lo.min(-self.cutoff);
        }
        // Rounding in the distance bounds: widen by a relative ulp margin.
        let m = 1e-12 * (1.0 + half + self.rmax);
        Interval::new(lo - m, hi + m)
    }

    fn eval_batch(&self, x: &[f32], y: &[f32], z: &[f32], out: &mut [f32]) {
        for i in 0..out.len() {
            out[i] = self.eval([x[i] as f64, y[i] as f64, z[i] as f64]) as f32;
        }
    }
}
