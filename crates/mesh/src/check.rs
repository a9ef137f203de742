//! Mesh checks: edge manifoldness, orientation, degenerate and duplicate
//! elements, Euler characteristic, volume and area. The edge census and
//! the shell count live in [`crate::edges`] (re-exported here).

pub use crate::edges::{edges, shells, BrickEdges, EdgeCensus, ShellCensus};
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
    let sums = mesh
        .triangles
        .par_chunks(crate::write::CHUNK)
        .map(|ch| chunk_volume_area(&mesh.vertices, ch))
        .collect::<Vec<_>>();
    total_volume_area(&sums)
}

/// The volume and area sums of one chunk of [`volume_area`] (triangles
/// `ts` of vertices `vs`), in its order.
pub(crate) fn chunk_volume_area(vs: &[[f32; 3]], ts: &[[u32; 3]]) -> (f64, f64) {
    let (mut v, mut a) = (0.0, 0.0);
    for t in ts {
        let [p, q, r] = t.map(|i| p64(vs[i as usize]));
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
}

/// [`volume_area`] from the sums of its chunks ([`chunk_volume_area`] of
/// each [`crate::write::CHUNK`] triangles), added in order.
pub(crate) fn total_volume_area(sums: &[(f64, f64)]) -> (f64, f64) {
    sums.iter()
        .fold((0.0, 0.0), |(v, a), &(dv, da)| (v + dv, a + da))
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

    /// `n` tetrahedra with scrambled vertex numbers (`4 n` vertices, so
    /// several ranges of the census and edges between them), some faces
    /// flipped, dropped, doubled or degenerate.
    fn scrambled(n: u32) -> Mesh {
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
        m
    }

    #[test]
    fn edge_census_matches_the_definition_across_vertex_ranges() {
        let n = 5000;
        let m = scrambled(n);
        let got = edges(&m);
        assert_eq!(got, edges_by_map(&m));
        // Closed tetrahedra (k % 7 in 0, 5, 6) have no bad edges; each
        // defect adds 3 (flipped, hole, doubled) or, for the repeated
        // corner, its self-loop and the two edges it doubles.
        assert!(got.1 > 0 && got.0 > 6 * n as usize);
        assert_eq!(edges(&tetra()), (6, 0));
        // A vertex with more upper neighbours than a range's table holds
        // (a fan of 20 triangles around vertex 0) takes the sorting path.
        let mut fan = Mesh {
            vertices: vec![[0.0; 3]; 22],
            triangles: (1..21).map(|i| [0, i, i + 1]).collect(),
        };
        fan.triangles.push([0, 21, 1]);
        fan.triangles.push([0, 21, 1]);
        assert_eq!(edges(&fan), edges_by_map(&fan));
    }

    /// The census of `m` given all its vertices as one batch, then its
    /// triangles in `parts` pieces.
    fn census_in_one_batch(m: &Mesh, parts: usize) -> Option<(usize, usize)> {
        let mut c = EdgeCensus::new();
        c.vertices(m.vertices.len());
        let per = m.triangles.len().div_ceil(parts.max(1)).max(1);
        for t in m.triangles.chunks(per) {
            c.triangles(t);
        }
        c.finish()
    }

    #[test]
    fn streamed_census_matches_the_definition() {
        // Defects of every kind, ends up to 20000 apart.
        let m = scrambled(5000);
        assert_eq!(census_in_one_batch(&m, 7), Some(edges_by_map(&m)));
        assert_eq!(census_in_one_batch(&tetra(), 1), Some((6, 0)));
        // A fan of 20 triangles around vertex 0: more upper neighbours
        // than a row holds (the side list), one edge doubled.
        let mut fan = Mesh {
            vertices: vec![[0.0; 3]; 22],
            triangles: (1..21).map(|i| [0, i, i + 1]).collect(),
        };
        fan.triangles.push([0, 21, 1]);
        fan.triangles.push([0, 21, 1]);
        assert_eq!(census_in_one_batch(&fan, 3), Some(edges_by_map(&fan)));
        // Ends more than 65535 apart (the side list), and an edge used 40
        // times one way and 20 the other (counts stuck at 15: bad).
        let mut far = tetra();
        far.vertices.resize(100_000, [0.0; 3]);
        far.triangles.extend([[0, 99_999, 1], [1, 99_999, 0]]);
        for _ in 0..20 {
            far.triangles.extend([[2, 3, 50], [2, 3, 51], [3, 2, 52]]);
        }
        // Repeated corners at vertices with other upper neighbours, before
        // and after them, near and far (whatever slots their keys take).
        for k in 0..40u32 {
            let v = 100 + 200 * k;
            far.triangles.push([v, v, v + 1 + k]);
            far.triangles.push([v, v + 1 + k, v + 2 + 2 * k]);
            far.triangles.push([v + 2 + 2 * k, v + 1 + k, v]);
            far.triangles.push([v, v + 3 + 3 * k, v]);
        }
        let want = edges_by_map(&far);
        assert!(want.1 > 0);
        assert_eq!(census_in_one_batch(&far, 5), Some(want));
        assert_eq!(census_in_one_batch(&Mesh::default(), 1), Some((0, 0)));
    }

    #[test]
    fn streamed_census_counts_meshes_as_the_pipeline_emits_them() {
        // A sink that keeps the mesh and takes the census as it comes:
        // triangle by triangle, or from the bricks' edges (`by_brick`).
        #[derive(Default)]
        struct Both {
            mesh: Mesh,
            census: EdgeCensus,
            by_brick: bool,
            own: u64,
            shared: usize,
        }
        impl crate::sink::MeshSink for Both {
            fn vertices(&mut self, v: &[[f32; 3]]) -> Result<(), crate::MeshError> {
                self.census.vertices(v.len());
                self.mesh.vertices.extend_from_slice(v);
                Ok(())
            }
            fn triangles(
                &mut self,
                t: &[[u32; 3]],
                _: &crate::sink::VertexWindow,
            ) -> Result<(), crate::MeshError> {
                self.census.triangles(t);
                self.mesh.triangles.extend_from_slice(t);
                Ok(())
            }
            fn counts_edges(&self) -> bool {
                self.by_brick
            }
            fn take_counted(
                &mut self,
                part: crate::sink::Counted,
                _: &crate::sink::VertexWindow,
            ) -> Result<(), crate::MeshError> {
                self.census.brick(&part.edges);
                self.own += part.edges.own_uses;
                self.shared += part.edges.shared.len();
                self.mesh.triangles.extend_from_slice(&part.tris);
                Ok(())
            }
        }
        use microfrep_core::{Expr, Shape};
        use microfrep_shapes as prims;
        let p = Expr::xyz();
        // Two balls (one through the box's face), small bricks: many
        // slabs, so many batches and closed vertices; and a dense gyroid
        // sheet cut by the box.
        let a = prims::sphere(&p, &prims::v3([0.1, 0.0, -0.2]), 0.7);
        let b = prims::sphere(&p, &prims::v3([0.6, 0.5, 0.9]), 0.35);
        let balls = Shape::new(a.max(&b));
        use microfrep_structures::tpms::{tpms, Solid, Tpms};
        let gyroid = Shape::new(tpms(Tpms::Gyroid, Solid::Sheet, &p, 0.5, 0.1));
        let cases = [
            (&balls, 60, 8, crate::CellMethod::Cubes),
            (&balls, 33, 4, crate::CellMethod::Cubes),
            (&balls, 40, 32, crate::CellMethod::Cubes),
            (&balls, 45, 8, crate::CellMethod::Tetrahedra),
            (&gyroid, 50, 8, crate::CellMethod::Cubes),
            (&gyroid, 37, 16, crate::CellMethod::Tetrahedra),
        ];
        for (shape, cells, brick, method) in cases {
            for by_brick in [false, true] {
                let mut o = crate::MeshOptions::new([[-1.0; 3], [1.0; 3]], cells);
                o.brick = brick;
                o.cells = method;
                let plan = crate::Plan::new(shape, &o).unwrap();
                let mut b = Both {
                    by_brick,
                    ..Both::default()
                };
                plan.run_into(&mut b, &|_| {}).unwrap();
                let want = edges(&b.mesh);
                assert_eq!(want.1, 0);
                let what = format!("{cells} cells, bricks of {brick}, {method:?}, {by_brick}");
                assert_eq!(b.census.finish(), Some(want), "{what}");
                if by_brick {
                    // Most edges are a brick's own; the stitched ones are
                    // checked use by use.
                    assert!(b.shared > 0 && b.own > 2 * b.shared as u64, "{what}");
                    assert_eq!(b.own as usize + b.shared, 3 * b.mesh.triangles.len());
                    // The in-memory mesh counted while it is made.
                    let (m, e) = plan.run_counted(&|_| {}).unwrap();
                    assert!(m == b.mesh, "{what}");
                    assert_eq!(e, Some(want), "{what}");
                }
            }
        }
    }

    #[test]
    fn brick_edges_are_counted_whole_and_shared_ones_checked() {
        // Shared uses alone are counted as the triangles would be, defects
        // and all.
        let m = scrambled(3000);
        let mut c = EdgeCensus::new();
        c.vertices(m.vertices.len());
        for part in m.triangles.chunks(777) {
            let e = BrickEdges::of(part, &vec![true; m.vertices.len()]);
            assert_eq!(e.own_uses, 0);
            c.brick(&e);
        }
        assert_eq!(c.finish(), Some(edges_by_map(&m)));
        // A closed tetrahedron with no vertex on a face: its own edges,
        // counted whole.
        let t = tetra();
        let e = BrickEdges::of(&t.triangles, &[false; 4]);
        assert_eq!((e.own_uses, e.shared.len()), (12, 0));
        let mut c = EdgeCensus::new();
        c.vertices(4);
        c.brick(&e);
        assert_eq!(c.finish(), Some((6, 0)));
        // Vertices 0 and 1 on a face: edge 0-1 is shared, the rest own.
        let e = BrickEdges::of(&t.triangles, &[true, true, false, false]);
        assert_eq!((e.own_uses, e.shared.len()), (10, 2));
        let mut c = EdgeCensus::new();
        c.vertices(4);
        c.brick(&e);
        assert_eq!(c.finish(), Some((6, 0)));
        // Own uses that do not pair up cannot be: the census says it does
        // not know.
        let mut c = EdgeCensus::new();
        c.vertices(4);
        c.brick(&BrickEdges {
            own_uses: 11,
            shared: Vec::new(),
        });
        assert_eq!(c.finish(), None);
    }

    #[test]
    fn streamed_census_knows_when_the_order_does_not_hold() {
        let t = tetra();
        let mut c = EdgeCensus::new();
        c.vertices(4);
        c.triangles(&t.triangles);
        c.vertices(4);
        c.vertices(4);
        // Vertices 0..4 are closed now.
        c.triangles(&[[0, 8, 9]]);
        assert_eq!(c.finish(), None);
        // A vertex not received yet.
        let mut c = EdgeCensus::new();
        c.vertices(3);
        c.triangles(&t.triangles);
        assert_eq!(c.finish(), None);
        // Triangles before any vertex.
        let mut c = EdgeCensus::new();
        c.triangles(&t.triangles);
        assert_eq!(c.finish(), None);
        // In order across batches, rows growing: exact.
        let mut c = EdgeCensus::new();
        let mut all = Mesh::default();
        for k in 0..6u32 {
            let n = 4 * (k as usize + 1) * 500;
            let base = all.vertices.len() as u32;
            c.vertices(n);
            all.vertices.resize(base as usize + n, [0.0; 3]);
            let tris: Vec<[u32; 3]> = (0..n as u32 / 4)
                .flat_map(|j| {
                    tetra()
                        .triangles
                        .into_iter()
                        .map(move |t| t.map(|v| base + 4 * j + v))
                })
                .collect();
            c.triangles(&tris);
            all.triangles.extend(tris);
        }
        assert_eq!(c.finish(), Some(edges_by_map(&all)));
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
