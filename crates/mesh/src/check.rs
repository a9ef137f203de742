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
        .par_chunks(crate::write::CHUNK)
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
/// mesh (no global sort), in parallel ([`edges`]). Duplicate triangles
/// show as bad edges; coincident vertices and degenerate triangles are not
/// looked for (the mesher makes neither by construction; [`check`] counts
/// them).
pub fn summary(mesh: &Mesh) -> CheckReport {
    let nv = mesh.vertices.len();
    let (volume, area) = volume_area(mesh);
    let (edges, bad_edges) = edges(mesh);
    let bbox = bbox(mesh);
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

/// Bounding box of the vertices (min, max; infinite the wrong way round
/// when there are none).
pub fn bbox(mesh: &Mesh) -> [[f64; 3]; 2] {
    mesh.vertices
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
        )
}

/// Triangles per chunk of the edge census.
const EDGE_CHUNK: usize = 1 << 15;

/// Undirected edges and bad edges of `mesh`: an edge `{a, b}` is good when
/// `a -> b` and `b -> a` are each used by exactly one triangle; an edge
/// from a vertex to itself (a triangle with a repeated corner) counts once
/// per vertex, as a bad edge. Linear time, in parallel: every directed
/// edge goes to the bucket of its lower-numbered end (vertices in ranges,
/// one parallel scatter into contiguous per-range regions), then each
/// range is sorted by its lower end by counting and each vertex's few
/// edges are grouped by the other end.
///
/// # Panics
/// When a triangle refers to a vertex that does not exist.
pub fn edges(mesh: &Mesh) -> (usize, usize) {
    let nv = mesh.vertices.len();
    if mesh.triangles.is_empty() {
        return (0, 0);
    }
    // Ranges of 2^shift vertices, about 256 of them (at least 4096 each).
    let shift = (nv.max(1).div_ceil(256).next_power_of_two().trailing_zeros()).max(12);
    let ranges = (nv >> shift) + 1;
    let low = |t: &[u32; 3], k: usize| t[k].min(t[(k + 1) % 3]);
    // Per chunk of triangles, directed edges per range.
    let counts: Vec<Vec<u32>> = mesh
        .triangles
        .par_chunks(EDGE_CHUNK)
        .map(|ch| {
            let mut c = vec![0u32; ranges];
            for t in ch {
                for k in 0..3 {
                    let v = low(t, k) as usize;
                    assert!(
                        v < nv && t[k].max(t[(k + 1) % 3]) < nv as u32,
                        "triangle refers to a vertex past {nv}"
                    );
                    c[v >> shift] += 1;
                }
            }
            c
        })
        .collect();
    // Range r's region holds its edges from chunk 0, then chunk 1, ...
    let mut buf = vec![0u64; 3 * mesh.triangles.len()];
    let mut slots: Vec<Vec<&mut [u64]>> = counts.iter().map(|_| Vec::new()).collect();
    let mut regions: Vec<&mut [u64]> = Vec::with_capacity(ranges);
    {
        let mut rest = &mut buf[..];
        for r in 0..ranges {
            let len: usize = counts.iter().map(|c| c[r] as usize).sum();
            let (region, tail) = rest.split_at_mut(len);
            rest = tail;
            regions.push(region);
        }
    }
    // Split each region into its chunks' parts (the regions stay borrowed
    // through the parts).
    let mut bounds = Vec::with_capacity(ranges);
    for (r, region) in regions.into_iter().enumerate() {
        bounds.push(region.len());
        let mut rest = region;
        for (c, cnt) in counts.iter().enumerate() {
            let (part, tail) = rest.split_at_mut(cnt[r] as usize);
            rest = tail;
            slots[c].push(part);
        }
    }
    // Scatter: entry = (lower end - range start) << 33 | upper end << 1 |
    // (1 when the edge runs from the lower end to the upper).
    mesh.triangles
        .par_chunks(EDGE_CHUNK)
        .zip(slots.par_iter_mut())
        .for_each(|(ch, parts)| {
            let mut at = vec![0usize; ranges];
            for t in ch {
                for k in 0..3 {
                    let (a, b) = (t[k], t[(k + 1) % 3]);
                    let (lo, hi) = (a.min(b) as u64, a.max(b) as u64);
                    let r = (lo >> shift) as usize;
                    let local = lo - ((r as u64) << shift);
                    parts[r][at[r]] = local << 33 | hi << 1 | (a < b) as u64;
                    at[r] += 1;
                }
            }
        });
    drop(slots);
    // Per range: counting sort by lower end, then each vertex's edges.
    let mut regions: Vec<&[u64]> = Vec::with_capacity(ranges);
    let mut rest = &buf[..];
    for len in bounds {
        let (region, tail) = rest.split_at(len);
        rest = tail;
        regions.push(region);
    }
    let size = 1usize << shift;
    regions
        .par_iter()
        .map_init(
            || (Vec::<u32>::new(), Vec::<u64>::new()),
            |(start, sorted), region| {
                start.clear();
                start.resize(size + 1, 0);
                for &e in region.iter() {
                    start[(e >> 33) as usize + 1] += 1;
                }
                for i in 0..size {
                    start[i + 1] += start[i];
                }
                sorted.clear();
                sorted.resize(region.len(), 0);
                for &e in region.iter() {
                    let s = &mut start[(e >> 33) as usize];
                    sorted[*s as usize] = e;
                    *s += 1;
                }
                // `start[i]` is now the end of vertex i's edges.
                let (mut e, mut b) = (0usize, 0usize);
                let mut from = 0usize;
                for v in 0..size {
                    let to = start[v] as usize;
                    let fan = &mut sorted[from..to];
                    from = to;
                    if fan.is_empty() {
                        continue;
                    }
                    fan.sort_unstable();
                    let mut i = 0;
                    while i < fan.len() {
                        let hi = (fan[i] >> 1) & 0xffff_ffff;
                        let mut j = i;
                        let (mut ups, mut downs) = (0, 0);
                        while j < fan.len() && (fan[j] >> 1) & 0xffff_ffff == hi {
                            if fan[j] & 1 == 1 {
                                ups += 1;
                            } else {
                                downs += 1;
                            }
                            j += 1;
                        }
                        e += 1;
                        // A repeated corner (upper end = lower end) only
                        // ever counts as `downs`: never good.
                        if ups != 1 || downs != 1 {
                            b += 1;
                        }
                        i = j;
                    }
                }
                (e, b)
            },
        )
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1))
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

    /// Edges and bad edges by a map of directed-edge counts: the definition
    /// [`edges`] implements (a self-loop is one bad edge).
    fn edges_by_map(m: &Mesh) -> (usize, usize) {
        let mut count = std::collections::BTreeMap::<(u32, u32), usize>::new();
        for t in &m.triangles {
            for k in 0..3 {
                *count.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
            }
        }
        let (mut e, mut b) = (0, 0);
        let mut seen = std::collections::BTreeSet::new();
        for &(a, c) in count.keys() {
            let key = (a.min(c), a.max(c));
            if !seen.insert(key) {
                continue;
            }
            e += 1;
            let n = |x, y| count.get(&(x, y)).copied().unwrap_or(0);
            if a == c || n(key.0, key.1) != 1 || n(key.1, key.0) != 1 {
                b += 1;
            }
        }
        (e, b)
    }

    #[test]
    fn edge_census_matches_the_definition_across_vertex_ranges() {
        // 5000 tetrahedra with scrambled vertex numbers (20000 vertices:
        // several ranges of the census, edges between them), some faces
        // flipped, dropped, doubled or degenerate.
        let n = 5000u32;
        let nv = 4 * n;
        let perm = |i: u32| ((i as u64 * 7919 + 13) % nv as u64) as u32;
        let mut m = Mesh {
            vertices: vec![[0.0; 3]; nv as usize],
            triangles: Vec::new(),
        };
        for k in 0..n {
            let v = |i: u32| perm(4 * k + i);
            let mut faces = vec![
                [v(0), v(2), v(1)],
                [v(0), v(1), v(3)],
                [v(0), v(3), v(2)],
                [v(1), v(2), v(3)],
            ];
            match k % 7 {
                1 => faces[3] = [v(1), v(3), v(2)],
                2 => {
                    faces.pop();
                }
                3 => faces.push([v(3), v(2), v(1)]),
                4 => faces.push([v(1), v(1), v(2)]),
                _ => {}
            }
            m.triangles.extend(faces);
        }
        let got = edges(&m);
        assert_eq!(got, edges_by_map(&m));
        // Closed tetrahedra (k % 7 in 0, 5, 6) have no bad edges; each
        // defect adds 3 (flipped, hole, doubled) or, for the repeated
        // corner, its self-loop and the two edges it doubles.
        assert!(got.1 > 0 && got.0 > 6 * n as usize);
        assert_eq!(edges(&tetra()), (6, 0));
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
