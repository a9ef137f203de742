//! Mesh checks: edge manifoldness, orientation, degenerate and duplicate
//! elements, Euler characteristic, volume and area.

use crate::Mesh;
use rayon::prelude::*;

/// What [`check`] found in a mesh: element counts, defects, the Euler
/// characteristic and the enclosed volume and area (model units). A mesh of
/// a solid is sound when [`CheckReport::is_closed_manifold`] holds; a
/// connected one then has genus `(2 - euler) / 2`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CheckReport {
    /// Number of vertices.
    pub vertices: usize,
    /// Number of triangles.
    pub triangles: usize,
    /// Undirected edges.
    pub edges: usize,
    /// Edges not used exactly once in each direction (boundary, non-manifold
    /// or inconsistently oriented).
    pub bad_edges: usize,
    /// Triangles with a repeated index or zero area.
    pub degenerate: usize,
    /// Triangles on the same three vertices as an earlier one.
    pub duplicate_triangles: usize,
    /// Vertices at the same position as another one.
    pub duplicate_vertices: usize,
    /// V - E + F.
    pub euler: i64,
    /// Signed volume (positive for outward orientation).
    pub volume: f64,
    /// Total area of the triangles, in square model units.
    pub area: f64,
    /// Bounding box of the vertices (min, max).
    pub bbox: [[f64; 3]; 2],
}

impl CheckReport {
    /// Every edge in exactly two triangles with opposite directions, no
    /// degenerate or duplicate elements, positive volume.
    pub fn is_closed_manifold(&self) -> bool {
        self.bad_edges == 0
            && self.degenerate == 0
            && self.duplicate_triangles == 0
            && self.duplicate_vertices == 0
            && (self.triangles == 0 || self.volume > 0.0)
    }
}

fn p64(p: [f32; 3]) -> [f64; 3] {
    p.map(|v| v as f64)
}

/// Volume and area of a mesh (divergence theorem; f64 sums in a fixed order).
pub fn volume_area(mesh: &Mesh) -> (f64, f64) {
    mesh.triangles
        .par_chunks(1 << 16)
        .map(|ch| {
            let (mut v, mut a) = (0.0, 0.0);
            for t in ch {
                let [p, q, r] = t.map(|i| p64(mesh.vertices[i as usize]));
                let e1 = [q[0] - p[0], q[1] - p[1], q[2] - p[2]];
                let e2 = [r[0] - p[0], r[1] - p[1], r[2] - p[2]];
                let n = [
                    e1[1] * e2[2] - e1[2] * e2[1],
                    e1[2] * e2[0] - e1[0] * e2[2],
                    e1[0] * e2[1] - e1[1] * e2[0],
                ];
                a += 0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
                v += (p[0] * (q[1] * r[2] - q[2] * r[1]) - p[1] * (q[0] * r[2] - q[2] * r[0])
                    + p[2] * (q[0] * r[1] - q[1] * r[0]))
                    / 6.0;
            }
            (v, a)
        })
        .collect::<Vec<_>>()
        .into_iter()
        .fold((0.0, 0.0), |(v, a), (dv, da)| (v + dv, a + da))
}

/// What a mesher's summary reports: counts, bad edges, Euler
/// characteristic, volume, area and bounding box, in time linear in the
/// mesh (no sorting), in parallel. Each vertex checks the edges to its
/// higher-numbered neighbours from its own triangle fan: an edge is good
/// when it is used once in each direction. Duplicate triangles show as bad
/// edges; coincident vertices and degenerate triangles are not looked for
/// (the mesher makes neither by construction; [`check`] counts them).
pub fn summary(mesh: &Mesh) -> CheckReport {
    let nv = mesh.vertices.len();
    let (volume, area) = volume_area(mesh);
    // Triangle fans by counting sort: offsets, then incident corners
    // packed as triangle * 4 + corner.
    let mut start = vec![0u32; nv + 1];
    for t in &mesh.triangles {
        for &v in t {
            start[v as usize + 1] += 1;
        }
    }
    for i in 0..nv {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut inc = vec![0u64; 3 * mesh.triangles.len()];
    for (ti, t) in mesh.triangles.iter().enumerate() {
        for (k, &v) in t.iter().enumerate() {
            let s = &mut fill[v as usize];
            inc[*s as usize] = (ti as u64) << 2 | k as u64;
            *s += 1;
        }
    }
    drop(fill);
    let (edges, bad_edges) = (0..nv)
        .into_par_iter()
        .with_min_len(4096)
        .fold(
            || (0usize, 0usize, Vec::<(u32, i8)>::new()),
            |(mut e, mut b, mut nb), v| {
                nb.clear();
                for &c in &inc[start[v] as usize..start[v + 1] as usize] {
                    let t = mesh.triangles[(c >> 2) as usize];
                    let k = (c & 3) as usize;
                    // v -> next is outgoing, prev -> v incoming.
                    nb.push((t[(k + 1) % 3], 1));
                    nb.push((t[(k + 2) % 3], -1));
                }
                nb.sort_unstable();
                let mut i = 0;
                while i < nb.len() {
                    let w = nb[i].0;
                    let mut j = i;
                    let (mut outs, mut ins) = (0, 0);
                    while j < nb.len() && nb[j].0 == w {
                        if nb[j].1 > 0 {
                            outs += 1;
                        } else {
                            ins += 1;
                        }
                        j += 1;
                    }
                    if w as usize > v {
                        e += 1;
                        if outs != 1 || ins != 1 {
                            b += 1;
                        }
                    } else if w as usize == v {
                        // A triangle with a repeated corner.
                        e += 1;
                        b += 1;
                    }
                    i = j;
                }
                (e, b, nb)
            },
        )
        .map(|(e, b, _)| (e, b))
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
    let bbox = mesh
        .vertices
        .par_chunks(1 << 16)
        .map(|ch| {
            let mut bb = [[f64::INFINITY; 3], [f64::NEG_INFINITY; 3]];
            for p in ch {
                for a in 0..3 {
                    bb[0][a] = bb[0][a].min(p[a] as f64);
                    bb[1][a] = bb[1][a].max(p[a] as f64);
                }
            }
            bb
        })
        .reduce(
            || [[f64::INFINITY; 3], [f64::NEG_INFINITY; 3]],
            |a, b| {
                [
                    std::array::from_fn(|k| a[0][k].min(b[0][k])),
                    std::array::from_fn(|k| a[1][k].max(b[1][k])),
                ]
            },
        );
    CheckReport {
        vertices: nv,
        triangles: mesh.triangles.len(),
        edges,
        bad_edges,
        degenerate: 0,
        duplicate_triangles: 0,
        duplicate_vertices: 0,
        euler: nv as i64 - edges as i64 + mesh.triangles.len() as i64,
        volume,
        area,
        bbox,
    }
}

/// The full check: [`summary`]'s figures plus degenerate and duplicate
/// triangles and coincident vertices (sorting; for tests and audits).
pub fn check(mesh: &Mesh) -> CheckReport {
    let nv = mesh.vertices.len();
    let (volume, area) = volume_area(mesh);

    // Directed half-edges a -> b as a << 32 | b, sorted.
    let mut half: Vec<u64> = mesh
        .triangles
        .par_iter()
        .flat_map_iter(|t| (0..3).map(move |k| ((t[k] as u64) << 32) | t[(k + 1) % 3] as u64))
        .collect();
    half.par_sort_unstable();
    let count = |h: u64| -> usize {
        let s = half.partition_point(|&x| x < h);
        half[s..].iter().take_while(|&&x| x == h).count()
    };
    // An undirected edge {a, b} is good when a->b and b->a occur once each;
    // it is examined from its smaller end.
    let mut edges = 0;
    let mut bad_edges = 0;
    let mut i = 0;
    while i < half.len() {
        let h = half[i];
        let mut j = i;
        while j < half.len() && half[j] == h {
            j += 1;
        }
        let (a, b) = (h >> 32, h & 0xffff_ffff);
        let rev = (b << 32) | a;
        let n_rev = count(rev);
        if a < b || n_rev == 0 {
            edges += 1;
            if j - i != 1 || n_rev != 1 {
                bad_edges += 1;
            }
        }
        i = j;
    }

    let degenerate = mesh
        .triangles
        .par_iter()
        .filter(|t| {
            if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                return true;
            }
            let [p, q, r] = t.map(|i| p64(mesh.vertices[i as usize]));
            let e1 = [q[0] - p[0], q[1] - p[1], q[2] - p[2]];
            let e2 = [r[0] - p[0], r[1] - p[1], r[2] - p[2]];
            let n = [
                e1[1] * e2[2] - e1[2] * e2[1],
                e1[2] * e2[0] - e1[0] * e2[2],
                e1[0] * e2[1] - e1[1] * e2[0],
            ];
            n == [0.0; 3]
        })
        .count();

    let mut sorted: Vec<[u32; 3]> = mesh
        .triangles
        .par_iter()
        .map(|t| {
            let mut s = *t;
            s.sort_unstable();
            s
        })
        .collect();
    sorted.par_sort_unstable();
    let duplicate_triangles = sorted.windows(2).filter(|w| w[0] == w[1]).count();
    drop(sorted);

    let mut pos: Vec<[u32; 3]> = mesh
        .vertices
        .par_iter()
        .map(|p| p.map(|v| (v + 0.0).to_bits()))
        .collect();
    pos.par_sort_unstable();
    let duplicate_vertices = pos.windows(2).filter(|w| w[0] == w[1]).count();

    let mut bbox = [[f64::INFINITY; 3], [f64::NEG_INFINITY; 3]];
    for p in &mesh.vertices {
        for a in 0..3 {
            bbox[0][a] = bbox[0][a].min(p[a] as f64);
            bbox[1][a] = bbox[1][a].max(p[a] as f64);
        }
    }
    CheckReport {
        vertices: nv,
        triangles: mesh.triangles.len(),
        edges,
        bad_edges,
        degenerate,
        duplicate_triangles,
        duplicate_vertices,
        euler: nv as i64 - edges as i64 + mesh.triangles.len() as i64,
        volume,
        area,
        bbox,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetra() -> Mesh {
        Mesh {
            vertices: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        }
    }

    #[test]
    fn tetrahedron_is_closed_with_known_volume_and_area() {
        let r = check(&tetra());
        assert!(r.is_closed_manifold(), "{r:?}");
        assert_eq!((r.edges, r.euler), (6, 2));
        assert!((r.volume - 1.0 / 6.0).abs() < 1e-12);
        let area = 1.5 + 3f64.sqrt() / 2.0;
        assert!((r.area - area).abs() < 1e-6);
    }

    #[test]
    fn summary_agrees_with_the_full_check() {
        let mut meshes = vec![tetra()];
        let mut m = tetra();
        m.triangles[3] = [1, 3, 2];
        meshes.push(m);
        let mut m = tetra();
        m.triangles.pop();
        meshes.push(m);
        let mut m = tetra();
        m.triangles.push([3, 2, 1]);
        meshes.push(m);
        for m in &meshes {
            let (s, c) = (summary(m), check(m));
            assert_eq!(
                (s.edges, s.bad_edges, s.euler, s.volume, s.area, s.bbox),
                (c.edges, c.bad_edges, c.euler, c.volume, c.area, c.bbox),
                "{m:?}"
            );
        }
    }

    #[test]
    fn defects_are_counted() {
        let mut m = tetra();
        m.triangles[3] = [1, 3, 2]; // flipped face: 3 edges now one-directional
        assert_eq!(check(&m).bad_edges, 3);
        let mut m = tetra();
        m.triangles.pop(); // hole
        assert_eq!(check(&m).bad_edges, 3);
        let mut m = tetra();
        m.triangles.push([3, 2, 1]);
        let r = check(&m);
        assert_eq!(r.duplicate_triangles, 1);
        let mut m = tetra();
        m.vertices.push([0.0; 3]);
        m.triangles.push([4, 4, 1]);
        let r = check(&m);
        assert_eq!((r.duplicate_vertices, r.degenerate), (1, 1));
    }
}
