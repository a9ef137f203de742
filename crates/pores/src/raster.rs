//! The radial function of a closed triangulated surface around the origin,
//! sampled at the vertices of a cube map by central projection.
//!
//! Each triangle is projected from the origin onto the planes of the cube
//! faces its vertices see (a central projection maps the triangle to a
//! triangle), and every grid direction inside the projection gets the
//! distance along that direction to the triangle's plane. For a surface
//! that is star-shaped around the origin each direction meets it once.

use crate::cubemap::{direction, face_axis, CubeMap};
use crate::doo_sabin::other_axes;

/// What tabulation found.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RasterReport {
    /// Grid directions no projected triangle covered (filled by a direct
    /// ray cast against every triangle).
    pub missed: usize,
    /// Grid directions two triangles covered at distances differing by more
    /// than 1e-9 relative: the surface is not star-shaped there (the
    /// outermost distance is kept).
    pub conflicts: usize,
}

/// Tabulates the radial function of the triangles `tris` of the closed
/// surface with vertices `pos` around the origin, `n` texels per face.
/// Returns `None` when some direction meets no triangle at all (the origin
/// is not inside the surface).
pub fn tabulate(pos: &[[f64; 3]], tris: &[[u32; 3]], n: usize) -> Option<(CubeMap, RasterReport)> {
    let mut map = CubeMap::constant(n, f32::NAN);
    let mut best = vec![f64::NAN; map.values().len()];
    let mut report = RasterReport::default();
    let half = 0.5 * n as f64;
    let coord: Vec<f64> = (0..=n).map(|i| map.coord(i)).collect();
    // The faces whose region, widened by 5 %, holds each vertex: a small
    // triangle only reaches the faces of its vertices (a direction still
    // missed is cast directly below).
    let masks: Vec<u8> = pos
        .iter()
        .map(|p| {
            let a = [p[0].abs(), p[1].abs(), p[2].abs()];
            let mut mask = 0u8;
            for m in 0..3 {
                let (b, c) = other_axes(m);
                if a[b] <= 1.05 * a[m] && a[c] <= 1.05 * a[m] {
                    mask |= 1 << (2 * m + (p[m] < 0.0) as usize);
                }
            }
            mask
        })
        .collect();
    for t in tris {
        let p = t.map(|i| pos[i as usize]);
        let faces = t.iter().fold(0u8, |m, &i| m | masks[i as usize]);
        let nrm = cross(sub(p[1], p[0]), sub(p[2], p[0]));
        let off = dot(nrm, p[0]);
        for f in 0..6 {
            if faces >> f & 1 == 0 {
                continue;
            }
            let (m, s) = face_axis(f);
            if p.iter().any(|q| q[m] * s <= 0.0) {
                continue;
            }
            let (b, c) = other_axes(m);
            let uv = p.map(|q| {
                let inv = 1.0 / (q[m] * s);
                [q[b] * inv, q[c] * inv]
            });
            let (mut u0, mut u1, mut v0, mut v1) = (uv[0][0], uv[0][0], uv[0][1], uv[0][1]);
            for q in &uv[1..] {
                u0 = u0.min(q[0]);
                u1 = u1.max(q[0]);
                v0 = v0.min(q[1]);
                v1 = v1.max(q[1]);
            }
            if u1 < -1.0 || u0 > 1.0 || v1 < -1.0 || v0 > 1.0 {
                continue;
            }
            let eps = 1e-9;
            let i0 = ((u0 + 1.0) * half - eps).ceil().max(0.0) as usize;
            let i1 = ((u1 + 1.0) * half + eps).floor().min(n as f64) as i64;
            let j0 = ((v0 + 1.0) * half - eps).ceil().max(0.0) as usize;
            let j1 = ((v1 + 1.0) * half + eps).floor().min(n as f64) as i64;
            if i1 < i0 as i64 || j1 < j0 as i64 {
                continue;
            }
            let area = orient(uv[0], uv[1], uv[2]);
            if area == 0.0 {
                continue;
            }
            let inv_area = 1.0 / area;
            for j in j0..=j1 as usize {
                for i in i0..=i1 as usize {
                    let q = [coord[i], coord[j]];
                    let w0 = orient(uv[1], uv[2], q) * inv_area;
                    let w1 = orient(uv[2], uv[0], q) * inv_area;
                    let w2 = 1.0 - w0 - w1;
                    let tol = -1e-9;
                    if w0 < tol || w1 < tol || w2 < tol {
                        continue;
                    }
                    let d = direction(f, q[0], q[1]);
                    let dn = dot(nrm, d);
                    if dn == 0.0 {
                        continue;
                    }
                    let r = off / dn * norm(d);
                    if r <= 0.0 {
                        continue;
                    }
                    let k = map.index(f, i, j);
                    let old = best[k];
                    if old.is_nan() {
                        best[k] = r;
                    } else if (r - old).abs() > 1e-9 * old {
                        report.conflicts += 1;
                        best[k] = old.max(r);
                    }
                }
            }
        }
    }
    // Directions that slipped between triangles (rounding): a direct cast.
    for f in 0..6 {
        for j in 0..=n {
            for i in 0..=n {
                let k = map.index(f, i, j);
                if best[k].is_nan() {
                    report.missed += 1;
                    best[k] = cast(pos, tris, direction(f, map.coord(i), map.coord(j)))?;
                }
            }
        }
    }
    for (v, b) in map.values_mut().iter_mut().zip(&best) {
        *v = *b as f32;
    }
    map.share_edges();
    Some((map, report))
}

/// Distance from the origin along `d` to the farthest triangle it meets.
fn cast(pos: &[[f64; 3]], tris: &[[u32; 3]], d: [f64; 3]) -> Option<f64> {
    let len = norm(d);
    let d = [d[0] / len, d[1] / len, d[2] / len];
    let mut best: Option<f64> = None;
    for t in tris {
        let p = t.map(|i| pos[i as usize]);
        // Moller-Trumbore with a small tolerance on the edges.
        let e1 = sub(p[1], p[0]);
        let e2 = sub(p[2], p[0]);
        let h = cross(d, e2);
        let a = dot(e1, h);
        if a.abs() < 1e-300 {
            continue;
        }
        let s = [-p[0][0], -p[0][1], -p[0][2]];
        let u = dot(s, h) / a;
        let q = cross(s, e1);
        let v = dot(d, q) / a;
        let tol = 1e-7;
        if u < -tol || v < -tol || u + v > 1.0 + tol {
            continue;
        }
        let t = dot(e2, q) / a;
        if t > 0.0 {
            best = Some(best.map_or(t, |b: f64| b.max(t)));
        }
    }
    best
}

fn orient(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Tabulation by walking: the grid directions are fixed, and a surface
/// close to a reference one is met by each direction in the reference's
/// triangle or one a few steps away across the mesh, so each direction
/// walks from its reference triangle to the one it passes through.
#[derive(Clone, Debug)]
pub struct Walker {
    n: usize,
    tris: Vec<[u32; 3]>,
    /// Neighbour across edge `k` (from vertex `k` to `k + 1`) of each triangle.
    adj: Vec<[u32; 3]>,
    /// Unit direction of each table vertex.
    dirs: Vec<[f64; 3]>,
    /// Triangle each direction meets on the reference surface.
    start: Vec<u32>,
}

impl Walker {
    /// Prepares walks over the closed triangle mesh `tris` for tables of
    /// `n` texels, from the reference surface `reference` (positions).
    pub fn new(reference: &[[f64; 3]], tris: &[[u32; 3]], n: usize) -> Walker {
        use std::collections::HashMap;
        let mut edges: HashMap<(u32, u32), (u32, usize)> = HashMap::new();
        for (ti, t) in tris.iter().enumerate() {
            for k in 0..3 {
                edges.insert((t[k], t[(k + 1) % 3]), (ti as u32, k));
            }
        }
        let adj = tris
            .iter()
            .map(|t| {
                std::array::from_fn(|k| {
                    edges.get(&(t[(k + 1) % 3], t[k])).map_or(u32::MAX, |e| e.0)
                })
            })
            .collect();
        let map = CubeMap::constant(n, 0.0);
        let mut dirs = vec![[0.0; 3]; map.values().len()];
        for f in 0..6 {
            for j in 0..=n {
                for i in 0..=n {
                    let d = direction(f, map.coord(i), map.coord(j));
                    let l = norm(d);
                    dirs[map.index(f, i, j)] = [d[0] / l, d[1] / l, d[2] / l];
                }
            }
        }
        let mut w = Walker {
            n,
            tris: tris.to_vec(),
            adj,
            dirs,
            start: Vec::new(),
        };
        let mut start = Vec::with_capacity(w.dirs.len());
        let mut at = 0u32;
        for k in 0..w.dirs.len() {
            at = w
                .walk(reference, w.dirs[k], at, 1 << 20)
                .map_or(0, |(t, _)| t);
            start.push(at);
        }
        w.start = start;
        w
    }

    /// The triangle `d` passes through, walking from `from`, and the
    /// distance along `d` to its plane; `None` after `steps` steps.
    fn walk(&self, pos: &[[f64; 3]], d: [f64; 3], from: u32, steps: usize) -> Option<(u32, f64)> {
        let mut t = from;
        let mut prev = u32::MAX;
        for _ in 0..steps {
            let v = self.tris[t as usize];
            let p = v.map(|i| pos[i as usize]);
            let s = [
                dot(d, cross(p[0], p[1])),
                dot(d, cross(p[1], p[2])),
                dot(d, cross(p[2], p[0])),
            ];
            let scale = 1e-12 * (dot(p[0], p[0]) + dot(p[1], p[1]));
            // The most negative side, not back where we came from.
            let mut k = 3;
            let mut worst = -scale;
            for (e, &se) in s.iter().enumerate() {
                if se < worst && self.adj[t as usize][e] != prev {
                    worst = se;
                    k = e;
                }
            }
            if k == 3 {
                if s.iter().any(|&se| se < -scale) {
                    // Only the way back is left: take it after all.
                    let e = (0..3).min_by(|&a, &b| s[a].total_cmp(&s[b])).unwrap_or(0);
                    prev = t;
                    t = self.adj[t as usize][e];
                    if t == u32::MAX {
                        return None;
                    }
                    continue;
                }
                let nrm = cross(sub(p[1], p[0]), sub(p[2], p[0]));
                let dn = dot(nrm, d);
                if dn <= 0.0 {
                    return None;
                }
                return Some((t, dot(nrm, p[0]) / dn));
            }
            prev = t;
            t = self.adj[t as usize][k];
            if t == u32::MAX {
                return None;
            }
        }
        None
    }

    /// The radial table of the surface with vertex positions `pos` (same
    /// mesh as the reference); `None` when a walk fails (the surface is
    /// far from the reference or not star-shaped).
    pub fn tabulate(&self, pos: &[[f64; 3]]) -> Option<CubeMap> {
        let mut map = CubeMap::constant(self.n, 0.0);
        for (k, v) in map.values_mut().iter_mut().enumerate() {
            let (_, r) = self.walk(pos, self.dirs[k], self.start[k], 256)?;
            if r.is_nan() || r <= 0.0 {
                return None;
            }
            *v = r as f32;
        }
        map.share_edges();
        Some(map)
    }
}
