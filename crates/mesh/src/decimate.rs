//! Fewer triangles where the surface is flat: vertices inside planar
//! regions, and on straight creases between two of them, are removed by
//! half-edge collapses, each checked against the model's f64 field.
//!
//! A vertex is a candidate when the normals of its triangles fall in one
//! direction (inside a flat region) or in two (on a crease, where it may
//! only move along the crease, to one of its two crease neighbours);
//! corners, with three directions or more, and curved regions stay. A
//! collapse of `u` into its neighbour `v` is taken when
//! - the mesh stays a closed 2-manifold: `u` and `v` share exactly the two
//!   neighbours of the triangles on their edge (the link condition);
//! - every changed triangle keeps a proper area and turns by less than
//!   20 degrees;
//! - the changed triangles stay within the tolerance of the surface. Each
//!   triangle carries a bound on its distance from the zero set: at first
//!   the largest `|f| / |grad f|` (f64) at its corners, after a collapse
//!   the largest bound of the fan it replaced plus the distance of `u`
//!   from the new fan (the most two triangulations of one nearly flat
//!   polygon can differ). Where the fan and the new triangles lie in one
//!   plane (normals within 0.05 degrees, per side of a crease) and that
//!   bound is within half the tolerance, it stands (with the field checked
//!   at the new triangles' centroids only); elsewhere the field is
//!   sampled over the new triangles (points no farther
//!   apart than a cell), and the collapse is taken only if every sample
//!   lies within the tolerance.
//!
//! The deviation reported is measured after the last collapse: the field
//! sampled the same way over every triangle a collapse made. Should it
//! exceed the tolerance (a bound that did not hold), the merge is made
//! again from the start with the field sampled at every collapse.
//!
//! The result depends only on the mesh and the field: vertices are visited
//! in index order, the partner chosen by a fixed rule, and passes repeated
//! until none collapses. Vertices keep their order (the removed ones
//! dropped), so the output is the same on any thread count.

use crate::Mesh;
use microfrep_core::geom::{cross, dot, sub};
use microfrep_core::{GradEval, Tape};

/// Normals closer than this (degrees) count as one direction.
const SAME_DEGREES: f64 = 1.0;
/// Normals closer than this (degrees) count as one plane: there the bound
/// of the triangles may stand for sampling the field.
const PLANE_DEGREES: f64 = 0.05;
/// A changed triangle may turn by at most this (degrees).
const TURN_DEGREES: f64 = 20.0;
/// Smallest doubled area of a changed triangle, in cell areas.
const MIN_AREA: f64 = 1e-6;
/// Passes over the vertices at most.
const MAX_PASSES: usize = 64;

/// What [`decimate`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Decimation {
    /// Triangles before and after.
    pub triangles: (usize, usize),
    /// Vertices removed.
    pub removed: usize,
    /// The largest distance from the zero set (`|f| / |grad f|`) measured
    /// at the sample points of every triangle the collapses made, after
    /// the last one, in model units.
    pub deviation: f64,
    /// Sample points evaluated against the field (during the collapses
    /// and for the final measurement).
    pub samples: usize,
}

/// Removes vertices of flat regions and straight creases of the closed
/// mesh `m` while its triangles stay within `tolerance` (model units) of
/// the zero set of `tape`, on a grid of cell size `h` (which sets the
/// sample spacing and the smallest area). Returns what it did; the mesh is
/// left as it is when nothing could be removed.
pub fn decimate(m: &mut Mesh, tape: &Tape, h: f64, tolerance: f64) -> Decimation {
    // With the planes' bounds standing for the field where they may, then
    // measured; should the measurement exceed the tolerance (a bound that
    // did not hold), again from the start with the field sampled at every
    // collapse.
    let (d, fast) = run(m, tape, h, tolerance, true);
    if d.deviation <= tolerance {
        if let Some(out) = fast {
            *m = out;
        }
        return d;
    }
    let (mut slow, out) = run(m, tape, h, tolerance, false);
    slow.samples += d.samples;
    if let Some(out) = out {
        *m = out;
    }
    slow
}

/// One decimation of `m` (left as it is), `bounds` saying whether the
/// triangles' bounds may stand for sampling; the mesh made, if any vertex
/// was removed.
fn run(m: &Mesh, tape: &Tape, h: f64, tolerance: f64, bounds: bool) -> (Decimation, Option<Mesh>) {
    let before = m.triangles.len();
    let mut d = Decimator::new(m, tape, h, tolerance);
    d.use_bounds = bounds;
    let mut removed = 0;
    for _ in 0..MAX_PASSES {
        let mut any = false;
        for u in 0..d.pos.len() as u32 {
            if d.alive_v[u as usize] && d.try_remove(u) {
                removed += 1;
                any = true;
            }
        }
        if !any {
            break;
        }
    }
    let deviation = d.measure();
    let report = Decimation {
        triangles: (before, d.alive_t.iter().filter(|&&a| a).count()),
        removed,
        deviation,
        samples: d.samples,
    };
    let out = (removed > 0).then(|| {
        let mut out = m.clone();
        d.write_back(&mut out);
        out
    });
    (report, out)
}

struct Decimator {
    pos: Vec<[f64; 3]>,
    tris: Vec<[u32; 3]>,
    alive_t: Vec<bool>,
    alive_v: Vec<bool>,
    /// Triangles of each vertex (alive ones; dead ones are dropped when
    /// met).
    around: Vec<Vec<u32>>,
    field: GradEval,
    h: f64,
    tol: f64,
    samples: usize,
    /// Per triangle: the bound on its distance from the zero set (NaN:
    /// not known yet), and whether a collapse made it.
    bound: Vec<f64>,
    made: Vec<bool>,
    /// Per vertex: `|f| / |grad f|` there (NaN: not evaluated yet).
    at_vertex: Vec<f64>,
    cos_same: f64,
    cos_turn: f64,
    cos_plane: f64,
    /// Whether the bounds of planar fans may stand for sampling.
    use_bounds: bool,
}

fn unit(a: [f64; 3]) -> Option<[f64; 3]> {
    let l = dot(a, a).sqrt();
    (l > 0.0 && l.is_finite()).then(|| a.map(|c| c / l))
}

impl Decimator {
    fn new(m: &Mesh, tape: &Tape, h: f64, tol: f64) -> Decimator {
        let pos: Vec<[f64; 3]> = m.vertices.iter().map(|p| p.map(|c| c as f64)).collect();
        let mut around = vec![Vec::new(); pos.len()];
        for (t, tri) in m.triangles.iter().enumerate() {
            for &v in tri {
                around[v as usize].push(t as u32);
            }
        }
        Decimator {
            alive_v: vec![true; pos.len()],
            alive_t: vec![true; m.triangles.len()],
            pos,
            tris: m.triangles.clone(),
            around,
            field: GradEval::new(tape),
            h,
            tol,
            samples: 0,
            bound: vec![f64::NAN; m.triangles.len()],
            made: vec![false; m.triangles.len()],
            at_vertex: vec![f64::NAN; m.vertices.len()],
            cos_same: SAME_DEGREES.to_radians().cos(),
            cos_turn: TURN_DEGREES.to_radians().cos(),
            cos_plane: PLANE_DEGREES.to_radians().cos(),
            use_bounds: true,
        }
    }

    fn normal(&self, t: [u32; 3]) -> [f64; 3] {
        let [a, b, c] = t.map(|v| self.pos[v as usize]);
        cross(sub(b, a), sub(c, a))
    }

    /// The alive triangles of `u`, in order.
    fn fan(&mut self, u: u32) -> Vec<u32> {
        let alive = &self.alive_t;
        self.around[u as usize].retain(|&t| alive[t as usize]);
        self.around[u as usize].clone()
    }

    fn neighbours(&self, fan: &[u32], u: u32) -> Vec<u32> {
        let mut n: Vec<u32> = fan
            .iter()
            .flat_map(|&t| self.tris[t as usize])
            .filter(|&v| v != u)
            .collect();
        n.sort_unstable();
        n.dedup();
        n
    }

    /// Removes `u` by a collapse into one of its neighbours, if one passes.
    fn try_remove(&mut self, u: u32) -> bool {
        let fan = self.fan(u);
        if fan.len() < 3 {
            return false;
        }
        // The directions of the fan's normals: one or two.
        let normals: Vec<Option<[f64; 3]>> = fan
            .iter()
            .map(|&t| unit(self.normal(self.tris[t as usize])))
            .collect();
        if normals.iter().any(|n| n.is_none()) {
            return false;
        }
        let normals: Vec<[f64; 3]> = normals.into_iter().map(Option::unwrap).collect();
        let mut dirs: Vec<[f64; 3]> = Vec::new();
        let mut dir_of = Vec::with_capacity(fan.len());
        for n in &normals {
            match dirs.iter().position(|d| dot(*d, *n) > self.cos_same) {
                Some(k) => dir_of.push(k),
                None => {
                    dirs.push(*n);
                    dir_of.push(dirs.len() - 1);
                }
            }
            if dirs.len() > 2 {
                return false;
            }
        }
        let ring = self.neighbours(&fan, u);
        let candidates: Vec<u32> = if dirs.len() == 1 {
            ring.clone()
        } else {
            // Crease edges: the two triangles on the edge in different
            // directions. Exactly two of them, or `u` is a corner.
            let crease: Vec<u32> = ring
                .iter()
                .copied()
                .filter(|&v| {
                    let on: Vec<usize> = fan
                        .iter()
                        .enumerate()
                        .filter(|(_, &t)| self.tris[t as usize].contains(&v))
                        .map(|(i, _)| dir_of[i])
                        .collect();
                    on.len() == 2 && on[0] != on[1]
                })
                .collect();
            if crease.len() != 2 {
                return false;
            }
            crease
        };
        // The candidate whose changed triangles are the roundest.
        let mut best: Option<(f64, f64, u32)> = None;
        for &v in &candidates {
            if let Some((q, turn)) = self.check(u, v, &fan, &normals, &ring) {
                if best.is_none_or(|(b, _, _)| q > b) {
                    best = Some((q, turn, v));
                }
            }
        }
        let Some((_, turn, v)) = best else {
            return false;
        };
        // One plane (per side of a crease) before and after: the bounds
        // may stand for the field.
        let plane = self.cos_plane;
        let planar = turn > plane
            && normals
                .iter()
                .zip(&dir_of)
                .all(|(n, &k)| dot(*n, dirs[k]) > plane);
        let Some(bound) = self.within_tolerance(u, v, &fan, planar) else {
            return false;
        };
        self.collapse(u, v, &fan, bound);
        true
    }

    /// Whether collapsing `u` into `v` keeps the mesh manifold and its
    /// changed triangles proper and turned little; then the least quality
    /// of those triangles (doubled area over the summed squared edges) and
    /// the least cosine of their turns.
    fn check(
        &self,
        u: u32,
        v: u32,
        fan: &[u32],
        normals: &[[f64; 3]],
        ring: &[u32],
    ) -> Option<(f64, f64)> {
        // Link condition: the common neighbours of u and v are the third
        // corners of the two triangles on the edge u v.
        let on_edge: Vec<u32> = fan
            .iter()
            .copied()
            .filter(|&t| self.tris[t as usize].contains(&v))
            .collect();
        if on_edge.len() != 2 {
            return None;
        }
        let opposite: Vec<u32> = on_edge
            .iter()
            .map(|&t| {
                self.tris[t as usize]
                    .into_iter()
                    .find(|&w| w != u && w != v)
                    .expect("a proper triangle")
            })
            .collect();
        if opposite[0] == opposite[1] {
            return None;
        }
        let v_fan: Vec<u32> = self.around[v as usize]
            .iter()
            .copied()
            .filter(|&t| self.alive_t[t as usize])
            .collect();
        let v_ring = self.neighbours(&v_fan, v);
        let common = ring
            .iter()
            .filter(|&&w| w != v && v_ring.binary_search(&w).is_ok())
            .count();
        if common != 2 {
            return None;
        }
        let min_area = MIN_AREA * self.h * self.h;
        let mut quality = f64::INFINITY;
        let mut turn = 1.0f64;
        for (i, &t) in fan.iter().enumerate() {
            let tri = self.tris[t as usize];
            if tri.contains(&v) {
                continue;
            }
            let moved = tri.map(|w| if w == u { v } else { w });
            let n = self.normal(moved);
            let len = dot(n, n).sqrt();
            if !(len > min_area) || dot(n, normals[i]) <= self.cos_turn * len {
                return None;
            }
            let [a, b, c] = moved.map(|w| self.pos[w as usize]);
            let edges =
                dot(sub(b, a), sub(b, a)) + dot(sub(c, b), sub(c, b)) + dot(sub(a, c), sub(a, c));
            quality = quality.min(len / edges);
            turn = turn.min(dot(n, normals[i]) / len);
        }
        Some((quality, turn))
    }

    /// `|f| / |grad f|` at vertex `w` (evaluated once).
    fn vertex_deviation(&mut self, w: u32) -> f64 {
        let d = self.at_vertex[w as usize];
        if !d.is_nan() {
            return d;
        }
        let d = self.deviation_at(self.pos[w as usize]);
        self.samples += 1;
        self.at_vertex[w as usize] = d;
        d
    }

    /// `|f| / |grad f|` at `q` (infinite where the gradient vanishes).
    fn deviation_at(&mut self, q: [f64; 3]) -> f64 {
        let (f, g) = self.field.eval(q);
        let len = dot(g, g).sqrt();
        if len > 0.0 {
            f.abs() / len
        } else {
            f64::INFINITY
        }
    }

    /// The bound of triangle `t` (from its corners, the first time).
    fn triangle_bound(&mut self, t: u32) -> f64 {
        let b = self.bound[t as usize];
        if !b.is_nan() {
            return b;
        }
        let b = self.tris[t as usize]
            .map(|w| self.vertex_deviation(w))
            .into_iter()
            .fold(0.0, f64::max);
        self.bound[t as usize] = b;
        b
    }

    /// The largest `|f| / |grad f|` at points spread over triangle `abc`
    /// (no farther apart than a cell), stopping early past `limit`.
    fn sample_triangle(&mut self, [a, b, c]: [[f64; 3]; 3], limit: f64) -> f64 {
        let longest = [sub(b, a), sub(c, b), sub(a, c)]
            .iter()
            .map(|e| dot(*e, *e).sqrt())
            .fold(0.0, f64::max);
        let k = ((longest / self.h).ceil() as usize).clamp(1, 256);
        let mut worst: f64 = 0.0;
        for i in 0..=k {
            for j in 0..=k - i {
                let (s, r) = (i as f64 / k as f64, j as f64 / k as f64);
                let q: [f64; 3] =
                    std::array::from_fn(|x| a[x] + s * (b[x] - a[x]) + r * (c[x] - a[x]));
                self.samples += 1;
                worst = worst.max(self.deviation_at(q));
                if !(worst <= limit) {
                    return worst;
                }
            }
        }
        worst
    }

    /// Whether the triangles that collapsing `u` into `v` makes stay within
    /// the tolerance: then their bound.
    fn within_tolerance(&mut self, u: u32, v: u32, fan: &[u32], planar: bool) -> Option<f64> {
        let p = self.pos[u as usize];
        let changed: Vec<[[f64; 3]; 3]> = fan
            .iter()
            .map(|&t| self.tris[t as usize])
            .filter(|tri| !tri.contains(&v))
            .map(|tri| tri.map(|w| self.pos[if w == u { v } else { w } as usize]))
            .collect();
        let nearest = changed
            .iter()
            .map(|&[a, b, c]| crate::measure::point_triangle(p, a, b, c))
            .fold(f64::INFINITY, f64::min);
        if !(nearest <= self.tol) {
            return None;
        }
        let old = fan
            .iter()
            .map(|&t| self.triangle_bound(t))
            .fold(0.0, f64::max);
        let bound = old + nearest;
        if self.use_bounds && planar && bound <= 0.5 * self.tol {
            // One point of each new triangle checked all the same: the
            // centroid, where a bent surface under a flat fan shows most.
            let mut ok = true;
            for &[a, b, c] in &changed {
                let q: [f64; 3] = std::array::from_fn(|x| (a[x] + b[x] + c[x]) / 3.0);
                self.samples += 1;
                if !(self.deviation_at(q) <= 0.5 * self.tol) {
                    ok = false;
                    break;
                }
            }
            if ok {
                return Some(bound);
            }
        }
        let mut worst = nearest;
        for tri in changed {
            worst = worst.max(self.sample_triangle(tri, self.tol));
            if !(worst <= self.tol) {
                return None;
            }
        }
        Some(worst)
    }

    /// The largest `|f| / |grad f|` over the triangles collapses made.
    fn measure(&mut self) -> f64 {
        let mut worst: f64 = 0.0;
        for t in 0..self.tris.len() {
            if self.alive_t[t] && self.made[t] {
                let tri = self.tris[t].map(|w| self.pos[w as usize]);
                let w = self.sample_triangle(tri, f64::INFINITY);
                worst = worst.max(w);
            }
        }
        worst
    }

    fn collapse(&mut self, u: u32, v: u32, fan: &[u32], bound: f64) {
        for &t in fan {
            let tri = &mut self.tris[t as usize];
            if tri.contains(&v) {
                self.alive_t[t as usize] = false;
            } else {
                for w in tri.iter_mut() {
                    if *w == u {
                        *w = v;
                    }
                }
                self.around[v as usize].push(t);
                self.bound[t as usize] = bound;
                self.made[t as usize] = true;
            }
        }
        self.alive_v[u as usize] = false;
        self.around[u as usize].clear();
    }

    fn write_back(self, m: &mut Mesh) {
        let mut index = vec![u32::MAX; self.pos.len()];
        let mut vertices = Vec::new();
        for (i, &a) in self.alive_v.iter().enumerate() {
            if a {
                index[i] = vertices.len() as u32;
                vertices.push(m.vertices[i]);
            }
        }
        m.triangles = self
            .tris
            .iter()
            .zip(&self.alive_t)
            .filter(|(_, &a)| a)
            .map(|(t, _)| t.map(|w| index[w as usize]))
            .collect();
        m.vertices = vertices;
    }
}
