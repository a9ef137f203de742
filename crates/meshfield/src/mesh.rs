//! The triangle mesh type, welding, the topology report, orientation repair
//! and the enclosed volume.

use crate::MeshError;
use rayon::prelude::*;
use std::collections::HashMap;

/// An indexed triangle mesh with f64 positions (millimetres). Triangles are
/// counter-clockwise seen from outside; nothing else is assumed: the mesh may
/// be open, non-manifold, inconsistently oriented or an unwelded soup.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriMesh {
    /// Vertex positions.
    pub vertices: Vec<[f64; 3]>,
    /// Vertex indices of each triangle.
    pub triangles: Vec<[u32; 3]>,
}

/// What [`TriMesh::topology`] found.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Topology {
    /// Triangles.
    pub triangles: usize,
    /// Distinct undirected edges.
    pub edges: usize,
    /// Edges used by one triangle only (the rims of holes).
    pub open_edges: usize,
    /// Edges used by three or more triangles.
    pub nonmanifold_edges: usize,
    /// Edges shared by exactly two triangles that traverse it in the same
    /// direction (one of the two is flipped).
    pub inconsistent_edges: usize,
    /// Vertices whose triangles form more than one fan (e.g. two solids
    /// touching at a point), counted only when every edge is manifold.
    pub nonmanifold_vertices: usize,
    /// Triangles with a repeated index or (nearly) zero area.
    pub degenerate_triangles: usize,
    /// Vertices not used by any triangle.
    pub unused_vertices: usize,
}

impl Topology {
    /// Every edge is shared by exactly two triangles.
    pub fn is_closed(&self) -> bool {
        self.open_edges == 0 && self.nonmanifold_edges == 0
    }

    /// Closed, and every edge is traversed once in each direction.
    pub fn is_closed_and_oriented(&self) -> bool {
        self.is_closed() && self.inconsistent_edges == 0
    }

    /// Closed, oriented, manifold at every vertex and free of degenerate
    /// triangles: the conditions under which the sign of the closest
    /// feature's angle-weighted pseudo-normal is exact (self-intersections
    /// aside, which are not detected).
    pub fn is_watertight(&self) -> bool {
        self.is_closed_and_oriented()
            && self.nonmanifold_vertices == 0
            && self.degenerate_triangles == 0
    }

    /// Human-readable warnings, empty for a watertight mesh.
    pub fn warnings(&self) -> Vec<String> {
        let mut w = Vec::new();
        if self.open_edges > 0 {
            w.push(format!(
                "mesh is not closed: {} open edges",
                self.open_edges
            ));
        }
        if self.nonmanifold_edges > 0 {
            w.push(format!(
                "mesh has {} non-manifold edges (3 or more triangles)",
                self.nonmanifold_edges
            ));
        }
        if self.inconsistent_edges > 0 {
            w.push(format!(
                "mesh is not consistently oriented: {} edges",
                self.inconsistent_edges
            ));
        }
        if self.nonmanifold_vertices > 0 {
            w.push(format!(
                "mesh has {} non-manifold vertices",
                self.nonmanifold_vertices
            ));
        }
        if self.degenerate_triangles > 0 {
            w.push(format!(
                "mesh has {} degenerate triangles",
                self.degenerate_triangles
            ));
        }
        w
    }
}

/// A triangle is degenerate when its area is below this fraction of the
/// square of its longest edge (a sliver with an angle under ~1e-12 rad) or
/// it repeats an index.
pub const DEGENERATE_RATIO: f64 = 1e-12;

/// Largest vertex coordinate accepted (by magnitude): squared distances
/// between points of the mesh's box then fit an f64.
pub const MAX_COORDINATE: f64 = 1e150;

pub(crate) fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
pub(crate) fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
pub(crate) fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
pub(crate) fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

/// Whether the triangle with these corners is degenerate (see
/// [`DEGENERATE_RATIO`]).
pub(crate) fn is_degenerate(t: [[f64; 3]; 3]) -> bool {
    let e = [sub(t[1], t[0]), sub(t[2], t[1]), sub(t[0], t[2])];
    let longest = e.iter().map(|v| dot(*v, *v)).fold(0.0, f64::max);
    let n = cross(e[0], sub(t[2], t[0]));
    norm(n) <= DEGENERATE_RATIO * longest
}

impl TriMesh {
    /// A mesh from vertices and triangles, checked: at least one triangle,
    /// every coordinate finite, every index in range.
    pub fn new(vertices: Vec<[f64; 3]>, triangles: Vec<[u32; 3]>) -> Result<TriMesh, MeshError> {
        let m = TriMesh {
            vertices,
            triangles,
        };
        m.validate()?;
        Ok(m)
    }

    /// Checks what [`TriMesh::new`] checks.
    pub fn validate(&self) -> Result<(), MeshError> {
        if self.triangles.is_empty() {
            return Err(MeshError::Empty);
        }
        if self.vertices.len() > u32::MAX as usize {
            return Err(MeshError::TooManyVertices(self.vertices.len()));
        }
        if let Some((i, v)) = self
            .vertices
            .iter()
            .enumerate()
            .find(|(_, v)| !v.iter().all(|c| c.is_finite()))
        {
            return Err(MeshError::NonFinite {
                vertex: i,
                value: *v,
            });
        }
        if let Some((i, v)) = self
            .vertices
            .iter()
            .enumerate()
            .find(|(_, v)| v.iter().any(|c| c.abs() > MAX_COORDINATE))
        {
            return Err(MeshError::HugeCoordinate {
                vertex: i,
                value: *v,
                limit: MAX_COORDINATE,
            });
        }
        let n = self.vertices.len();
        if let Some((t, tri)) = self
            .triangles
            .iter()
            .enumerate()
            .find(|(_, t)| t.iter().any(|&i| i as usize >= n))
        {
            return Err(MeshError::BadIndex {
                triangle: t,
                indices: *tri,
                vertices: n,
            });
        }
        Ok(())
    }

    /// The corners of triangle `t`.
    pub fn corners(&self, t: usize) -> [[f64; 3]; 3] {
        self.triangles[t].map(|i| self.vertices[i as usize])
    }

    /// Axis-aligned bounds of the vertices used by triangles (min, max).
    pub fn bbox(&self) -> [[f64; 3]; 2] {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for t in &self.triangles {
            for &i in t {
                let v = self.vertices[i as usize];
                for a in 0..3 {
                    lo[a] = lo[a].min(v[a]);
                    hi[a] = hi[a].max(v[a]);
                }
            }
        }
        [lo, hi]
    }

    /// Length of the diagonal of [`TriMesh::bbox`].
    pub fn diagonal(&self) -> f64 {
        let [lo, hi] = self.bbox();
        norm(sub(hi, lo))
    }

    /// Enclosed volume by the divergence theorem: the sum of the signed
    /// volumes of the tetrahedra from a reference point (the bbox centre, to
    /// keep the terms small) to each triangle. Exact for a closed, oriented
    /// mesh (positive when outward-facing); for an open mesh it depends on
    /// the reference point.
    pub fn volume(&self) -> f64 {
        let [lo, hi] = self.bbox();
        let o = [0, 1, 2].map(|a| 0.5 * (lo[a] + hi[a]));
        let sum: f64 = (0..self.triangles.len())
            .into_par_iter()
            .with_min_len(4096)
            .map(|t| {
                let [a, b, c] = self.corners(t).map(|v| sub(v, o));
                dot(a, cross(b, c))
            })
            .sum();
        sum / 6.0
    }

    /// Total area of the triangles.
    pub fn area(&self) -> f64 {
        (0..self.triangles.len())
            .map(|t| {
                let [a, b, c] = self.corners(t);
                0.5 * norm(cross(sub(b, a), sub(c, a)))
            })
            .sum()
    }

    /// Merges vertices closer than `tolerance` (0: only identical
    /// positions; -0.0 equals 0.0) into the first of them in index order,
    /// drops vertices no triangle uses and triangles that collapse to a
    /// repeated index. Deterministic; returns the welded mesh and how many
    /// triangles collapsed. With a tolerance, merging is greedy (a vertex
    /// joins the first earlier representative within the tolerance), so
    /// chains of near points longer than the tolerance are not merged.
    pub fn weld(&self, tolerance: f64) -> (TriMesh, usize) {
        let n = self.vertices.len();
        let mut rep: Vec<u32> = vec![u32::MAX; n];
        let mut used = vec![false; n];
        for t in &self.triangles {
            for &i in t {
                used[i as usize] = true;
            }
        }
        let key = |v: [f64; 3]| v.map(|c| if c == 0.0 { 0u64 } else { c.to_bits() });
        if tolerance > 0.0 && tolerance.is_finite() {
            let cell = |v: [f64; 3]| v.map(|c| (c / tolerance).floor() as i64);
            let mut grid: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
            for i in 0..n {
                if !used[i] {
                    continue;
                }
                let v = self.vertices[i];
                let c = cell(v);
                let mut found: Option<u32> = None;
                for dz in -1..=1 {
                    for dy in -1..=1 {
                        for dx in -1..=1 {
                            let Some(list) = grid.get(&[c[0] + dx, c[1] + dy, c[2] + dz]) else {
                                continue;
                            };
                            for &j in list {
                                let d = sub(self.vertices[j as usize], v);
                                if dot(d, d) <= tolerance * tolerance && found.is_none_or(|f| j < f)
                                {
                                    found = Some(j);
                                }
                            }
                        }
                    }
                }
                match found {
                    Some(j) => rep[i] = j,
                    None => {
                        rep[i] = i as u32;
                        grid.entry(c).or_default().push(i as u32);
                    }
                }
            }
        } else {
            // Exact: sort by position, the smallest index of a run represents it.
            let mut order: Vec<u32> = (0..n as u32).filter(|&i| used[i as usize]).collect();
            order.par_sort_unstable_by_key(|&i| (key(self.vertices[i as usize]), i));
            let mut k = 0;
            while k < order.len() {
                let first = order[k];
                let kv = key(self.vertices[first as usize]);
                let mut e = k;
                while e < order.len() && key(self.vertices[order[e] as usize]) == kv {
                    rep[order[e] as usize] = first;
                    e += 1;
                }
                k = e;
            }
        }
        // Renumber representatives in index order.
        let mut new_index = vec![u32::MAX; n];
        let mut vertices = Vec::new();
        for i in 0..n {
            if used[i] && rep[i] == i as u32 {
                new_index[i] = vertices.len() as u32;
                vertices.push(self.vertices[i]);
            }
        }
        let mut collapsed = 0;
        let mut triangles = Vec::with_capacity(self.triangles.len());
        for t in &self.triangles {
            let m = t.map(|i| new_index[rep[i as usize] as usize]);
            if m[0] == m[1] || m[1] == m[2] || m[0] == m[2] {
                collapsed += 1;
            } else {
                triangles.push(m);
            }
        }
        (
            TriMesh {
                vertices,
                triangles,
            },
            collapsed,
        )
    }

    /// The same triangles with three vertices of their own each (what an STL
    /// file stores).
    pub fn unwelded(&self) -> TriMesh {
        let mut vertices = Vec::with_capacity(3 * self.triangles.len());
        let mut triangles = Vec::with_capacity(self.triangles.len());
        for t in 0..self.triangles.len() {
            let base = vertices.len() as u32;
            vertices.extend_from_slice(&self.corners(t));
            triangles.push([base, base + 1, base + 2]);
        }
        TriMesh {
            vertices,
            triangles,
        }
    }

    /// Half-edges sorted by undirected edge: (min, max, triangle, forward),
    /// where forward says the triangle runs min -> max.
    fn sorted_half_edges(&self) -> Vec<(u32, u32, u32, bool)> {
        let mut h: Vec<(u32, u32, u32, bool)> = Vec::with_capacity(3 * self.triangles.len());
        for (t, tri) in self.triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                if a == b {
                    continue;
                }
                h.push((a.min(b), a.max(b), t as u32, a < b));
            }
        }
        h.par_sort_unstable();
        h
    }

    /// Pairs of triangles across each manifold edge (exactly two users), and
    /// whether the two traverse it in opposite directions.
    fn manifold_pairs(h: &[(u32, u32, u32, bool)]) -> Vec<(u32, u32, u32, u32, bool)> {
        let mut out = Vec::new();
        let mut k = 0;
        while k < h.len() {
            let mut e = k + 1;
            while e < h.len() && h[e].0 == h[k].0 && h[e].1 == h[k].1 {
                e += 1;
            }
            if e - k == 2 {
                out.push((h[k].0, h[k].1, h[k].2, h[k + 1].2, h[k].3 != h[k + 1].3));
            }
            k = e;
        }
        out
    }

    /// Open, non-manifold and inconsistently oriented edges, non-manifold
    /// vertices, degenerate triangles and unused vertices.
    pub fn topology(&self) -> Topology {
        let h = self.sorted_half_edges();
        let mut r = Topology {
            triangles: self.triangles.len(),
            ..Default::default()
        };
        let mut k = 0;
        while k < h.len() {
            let mut e = k + 1;
            while e < h.len() && h[e].0 == h[k].0 && h[e].1 == h[k].1 {
                e += 1;
            }
            r.edges += 1;
            match e - k {
                1 => r.open_edges += 1,
                2 => {
                    if h[k].3 == h[k + 1].3 {
                        r.inconsistent_edges += 1
                    }
                }
                _ => r.nonmanifold_edges += 1,
            }
            k = e;
        }
        r.degenerate_triangles = (0..self.triangles.len())
            .into_par_iter()
            .with_min_len(4096)
            .filter(|&t| {
                let [a, b, c] = self.triangles[t];
                a == b || b == c || a == c || is_degenerate(self.corners(t))
            })
            .count();
        let mut used = vec![false; self.vertices.len()];
        for t in &self.triangles {
            for &i in t {
                used[i as usize] = true;
            }
        }
        r.unused_vertices = used.iter().filter(|u| !**u).count();
        if r.is_closed() {
            r.nonmanifold_vertices = self.count_nonmanifold_vertices(&h);
        }
        r
    }

    /// Fans around each vertex by union-find over the corners joined across
    /// manifold edges; a vertex with more than one fan is non-manifold.
    fn count_nonmanifold_vertices(&self, h: &[(u32, u32, u32, bool)]) -> usize {
        let corner = |t: u32, v: u32| -> usize {
            let tri = self.triangles[t as usize];
            3 * t as usize + tri.iter().position(|&x| x == v).unwrap_or(0)
        };
        let mut parent: Vec<u32> = (0..3 * self.triangles.len() as u32).collect();
        fn find(p: &mut [u32], mut x: usize) -> usize {
            while p[x] as usize != x {
                p[x] = p[p[x] as usize];
                x = p[x] as usize;
            }
            x
        }
        for (a, b, t1, t2, _) in Self::manifold_pairs(h) {
            for v in [a, b] {
                let (x, y) = (
                    find(&mut parent, corner(t1, v)),
                    find(&mut parent, corner(t2, v)),
                );
                if x != y {
                    parent[x.max(y)] = x.min(y) as u32;
                }
            }
        }
        let mut fans = vec![0u32; self.vertices.len()];
        for c in 0..parent.len() {
            if find(&mut parent, c) == c {
                fans[self.triangles[c / 3][c % 3] as usize] += 1;
            }
        }
        fans.iter().filter(|&&f| f > 1).count()
    }

    /// Makes the orientation consistent across every manifold edge: each
    /// patch of triangles connected through manifold edges is made coherent
    /// by a breadth-first walk, then kept or flipped as a whole so that it
    /// agrees with the original orientation of the larger part of its area
    /// (a deliberately inward shell, e.g. a cavity, stays inward). Returns
    /// how many triangles were flipped. Non-manifold edges and holes are
    /// left alone.
    pub fn orient(&mut self) -> usize {
        let nt = self.triangles.len();
        let h = self.sorted_half_edges();
        let pairs = Self::manifold_pairs(&h);
        // Adjacency lists: (neighbour, opposite-direction-in-original).
        let mut deg = vec![0u32; nt + 1];
        for &(_, _, a, b, _) in &pairs {
            deg[a as usize] += 1;
            deg[b as usize] += 1;
        }
        let mut start = vec![0usize; nt + 1];
        for t in 0..nt {
            start[t + 1] = start[t] + deg[t] as usize;
        }
        let mut fill = start.clone();
        let mut adj = vec![(0u32, false); start[nt]];
        for &(_, _, a, b, opposite) in &pairs {
            adj[fill[a as usize]] = (b, opposite);
            fill[a as usize] += 1;
            adj[fill[b as usize]] = (a, opposite);
            fill[b as usize] += 1;
        }
        let area = |t: usize| {
            let [a, b, c] = self.corners(t);
            norm(cross(sub(b, a), sub(c, a)))
        };
        // flip[t]: whether t must be reversed relative to its patch's seed.
        let mut flip = vec![false; nt];
        let mut seen = vec![false; nt];
        let mut out_flip = vec![false; nt];
        let mut queue = std::collections::VecDeque::new();
        let mut patch = Vec::new();
        for seed in 0..nt {
            if seen[seed] {
                continue;
            }
            seen[seed] = true;
            queue.push_back(seed);
            patch.clear();
            while let Some(t) = queue.pop_front() {
                patch.push(t);
                for &(n, opposite) in &adj[start[t]..start[t + 1]] {
                    let n = n as usize;
                    if !seen[n] {
                        seen[n] = true;
                        // Consistent neighbours run the edge in opposite
                        // directions; keep that relation after flips.
                        flip[n] = if opposite { flip[t] } else { !flip[t] };
                        queue.push_back(n);
                    }
                }
            }
            let (mut kept, mut flipped) = (0.0, 0.0);
            for &t in &patch {
                if flip[t] {
                    flipped += area(t);
                } else {
                    kept += area(t);
                }
            }
            let invert = flipped > kept;
            for &t in &patch {
                out_flip[t] = flip[t] != invert;
            }
        }
        let mut count = 0;
        for (t, f) in out_flip.iter().enumerate() {
            if *f {
                self.triangles[t].swap(1, 2);
                count += 1;
            }
        }
        count
    }

    /// For each triangle and each of its edges k (corners k, k+1), the
    /// triangle across that edge when the edge is manifold, else `u32::MAX`.
    pub(crate) fn neighbours(&self) -> Vec<[u32; 3]> {
        let h = self.sorted_half_edges();
        let mut nb = vec![[u32::MAX; 3]; self.triangles.len()];
        let slot = |tri: [u32; 3], a: u32, b: u32| -> usize {
            (0..3)
                .find(|&k| {
                    let (x, y) = (tri[k], tri[(k + 1) % 3]);
                    (x == a && y == b) || (x == b && y == a)
                })
                .unwrap_or(0)
        };
        for (a, b, t1, t2, _) in Self::manifold_pairs(&h) {
            let s1 = slot(self.triangles[t1 as usize], a, b);
            let s2 = slot(self.triangles[t2 as usize], a, b);
            nb[t1 as usize][s1] = t2;
            nb[t2 as usize][s2] = t1;
        }
        nb
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetra() -> TriMesh {
        TriMesh::new(
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
            ],
            vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
        )
        .unwrap()
    }

    #[test]
    fn tetrahedron_topology_and_volume() {
        let m = tetra();
        let t = m.topology();
        assert!(t.is_watertight(), "{t:?}");
        assert_eq!(t.edges, 6);
        assert!((m.volume() - 1.0 / 6.0).abs() < 1e-15);
    }

    #[test]
    fn flips_open_and_nonmanifold_are_counted() {
        let mut m = tetra();
        m.triangles[1].swap(1, 2);
        let t = m.topology();
        assert_eq!(t.inconsistent_edges, 3);
        assert!(t.is_closed() && !t.is_closed_and_oriented());
        assert_eq!(m.orient(), 1);
        assert!(m.topology().is_watertight());
        assert!((m.volume() - 1.0 / 6.0).abs() < 1e-15);

        let mut open = tetra();
        open.triangles.pop();
        let t = open.topology();
        assert_eq!((t.open_edges, t.is_closed()), (3, false));
        assert_eq!(t.warnings()[0], "mesh is not closed: 3 open edges");

        let mut fin = tetra();
        fin.vertices.push([1.0, 1.0, 1.0]);
        fin.triangles.push([0, 1, 4]);
        let t = fin.topology();
        assert_eq!((t.nonmanifold_edges, t.open_edges), (1, 2));
    }

    #[test]
    fn weld_exact_and_with_tolerance() {
        let m = tetra();
        let soup = m.unwelded();
        assert_eq!(soup.topology().open_edges, 12);
        let (w, collapsed) = soup.weld(0.0);
        assert_eq!((w.vertices.len(), collapsed), (4, 0));
        assert!(w.topology().is_watertight());
        let mut noisy = soup.clone();
        for (i, v) in noisy.vertices.iter_mut().enumerate() {
            v[0] += 1e-9 * (i % 3) as f64;
        }
        let distinct: std::collections::HashSet<[u64; 3]> =
            noisy.vertices.iter().map(|v| v.map(f64::to_bits)).collect();
        assert!(distinct.len() > 4);
        assert_eq!(noisy.weld(0.0).0.vertices.len(), distinct.len());
        let (w, _) = noisy.weld(1e-6);
        assert_eq!(w.vertices.len(), 4);
        assert!(w.topology().is_watertight());
        // A triangle collapsing under the tolerance is dropped and counted.
        let tiny = TriMesh::new(
            vec![[0.0; 3], [1e-9, 0.0, 0.0], [0.0, 1.0, 0.0]],
            vec![[0, 1, 2]],
        )
        .unwrap();
        let (w, collapsed) = tiny.weld(1e-6);
        assert_eq!((w.triangles.len(), collapsed), (0, 1));
    }

    #[test]
    fn two_tetrahedra_sharing_a_vertex_are_not_vertex_manifold() {
        let a = tetra();
        let mut v = a.vertices.clone();
        v.extend(
            [
                [0.0, 0.0, 0.0],
                [-1.0, 0.0, 0.0],
                [0.0, -1.0, 0.0],
                [0.0, 0.0, -1.0],
            ]
            .iter()
            .skip(1),
        );
        // Second tetrahedron mirrored through the origin, sharing vertex 0.
        let t2: Vec<[u32; 3]> = vec![[0, 5, 4], [0, 4, 6], [4, 5, 6], [0, 6, 5]];
        let mut tris = a.triangles.clone();
        tris.extend(t2);
        let m = TriMesh::new(v, tris).unwrap();
        let t = m.topology();
        assert!(t.is_closed_and_oriented(), "{t:?}");
        assert_eq!(t.nonmanifold_vertices, 1);
        assert!(!t.is_watertight());
    }

    #[test]
    fn invalid_meshes_are_errors() {
        assert!(matches!(
            TriMesh::new(vec![], vec![]),
            Err(MeshError::Empty)
        ));
        let e = TriMesh::new(vec![[0.0; 3]; 3], vec![[0, 1, 3]]).unwrap_err();
        assert!(matches!(e, MeshError::BadIndex { triangle: 0, .. }), "{e}");
        let e = TriMesh::new(vec![[0.0, f64::NAN, 0.0]; 3], vec![[0, 1, 2]]).unwrap_err();
        assert!(e.to_string().contains("vertex 0"), "{e}");
    }
}
