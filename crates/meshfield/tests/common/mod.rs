//! Test meshes with known fields, brute-force references and damage.
#![allow(dead_code)]

use microfrep_core::Field;
use microfrep_meshfield::geom::closest_on_triangle;
use microfrep_meshfield::winding::winding_number_exact;
use microfrep_meshfield::{MeshField, TriMesh};
use std::collections::HashMap;

/// Deterministic generator (splitmix64).
pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    pub fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

fn normalize(v: [f64; 3], r: f64) -> [f64; 3] {
    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    v.map(|c| c * r / l)
}

/// Icosphere of radius `r` about `c`: the icosahedron subdivided `level`
/// times (20 * 4^level triangles), outward-facing.
pub fn icosphere(level: usize, r: f64, c: [f64; 3]) -> TriMesh {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let mut v: Vec<[f64; 3]> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .iter()
    .map(|p| normalize(*p, 1.0))
    .collect();
    let mut f: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..level {
        let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
        let mut g = Vec::with_capacity(4 * f.len());
        for tri in &f {
            let mut m = [0u32; 3];
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                let key = (a.min(b), a.max(b));
                m[k] = *mid.entry(key).or_insert_with(|| {
                    let (pa, pb) = (v[a as usize], v[b as usize]);
                    v.push(normalize([0, 1, 2].map(|i| pa[i] + pb[i]), 1.0));
                    (v.len() - 1) as u32
                });
            }
            g.push([tri[0], m[0], m[2]]);
            g.push([tri[1], m[1], m[0]]);
            g.push([tri[2], m[2], m[1]]);
            g.push(m);
        }
        f = g;
    }
    let v = v
        .iter()
        .map(|p| [0, 1, 2].map(|i| c[i] + r * p[i]))
        .collect();
    let m = TriMesh::new(v, f).unwrap();
    assert!(m.volume() > 0.0);
    m
}

/// Torus about the z axis: major radius `big`, minor `small`, `nu` x `nv`
/// quads split in two, outward-facing.
pub fn torus(nu: usize, nv: usize, big: f64, small: f64) -> TriMesh {
    let mut v = Vec::new();
    for i in 0..nu {
        let u = 2.0 * std::f64::consts::PI * i as f64 / nu as f64;
        for j in 0..nv {
            let w = 2.0 * std::f64::consts::PI * j as f64 / nv as f64;
            let rr = big + small * w.cos();
            v.push([rr * u.cos(), rr * u.sin(), small * w.sin()]);
        }
    }
    let id = |i: usize, j: usize| ((i % nu) * nv + (j % nv)) as u32;
    let mut f = Vec::new();
    for i in 0..nu {
        for j in 0..nv {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            f.push([a, b, c]);
            f.push([a, c, d]);
        }
    }
    let mut m = TriMesh::new(v, f).unwrap();
    if m.volume() < 0.0 {
        for t in &mut m.triangles {
            t.swap(1, 2);
        }
    }
    m
}

/// A microfrep mesh (f32) as a TriMesh.
pub fn from_microfrep(m: &microfrep_mesh::Mesh) -> TriMesh {
    TriMesh::new(
        m.vertices.iter().map(|v| v.map(|c| c as f64)).collect(),
        m.triangles.clone(),
    )
    .unwrap()
}

/// All triangles' corners.
pub fn soup(m: &TriMesh) -> Vec<[[f64; 3]; 3]> {
    (0..m.triangles.len()).map(|t| m.corners(t)).collect()
}

/// Distance to the polyhedron by brute force over every triangle.
pub fn brute_distance(tris: &[[[f64; 3]; 3]], p: [f64; 3]) -> f64 {
    tris.iter()
        .map(|t| {
            let (c, _) = closest_on_triangle(p, t, microfrep_meshfield_is_degenerate(t));
            let d = [0, 1, 2].map(|a| p[a] - c[a]);
            d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
        })
        .fold(f64::INFINITY, f64::min)
        .sqrt()
}

fn microfrep_meshfield_is_degenerate(t: &[[f64; 3]; 3]) -> bool {
    let e1 = [0, 1, 2].map(|a| t[1][a] - t[0][a]);
    let e2 = [0, 1, 2].map(|a| t[2][a] - t[0][a]);
    let n = [
        e1[1] * e2[2] - e1[2] * e2[1],
        e1[2] * e2[0] - e1[0] * e2[2],
        e1[0] * e2[1] - e1[1] * e2[0],
    ];
    n.iter().all(|c| *c == 0.0)
}

/// Exact inside test by the brute-force winding number.
pub fn brute_inside(tris: &[[[f64; 3]; 3]], p: [f64; 3]) -> bool {
    winding_number_exact(tris, p) > 0.5
}

/// Query points: half uniform in the bbox grown by 15 %, half offset from
/// random surface points along the face normal by +-(0.002 .. 0.05) of the
/// diagonal.
pub fn sample_points(m: &TriMesh, n: usize, seed: u64) -> Vec<[f64; 3]> {
    let mut rng = Rng(seed);
    let [lo, hi] = m.bbox();
    let diag = m.diagonal();
    let mut pts = Vec::with_capacity(n);
    for i in 0..n {
        if i % 2 == 0 {
            pts.push([0, 1, 2].map(|a| {
                let w = hi[a] - lo[a];
                lo[a] - 0.15 * w + 1.3 * w * rng.unit()
            }));
        } else {
            let t = m.corners(rng.below(m.triangles.len()));
            let (mut u, mut v) = (rng.unit(), rng.unit());
            if u + v > 1.0 {
                (u, v) = (1.0 - u, 1.0 - v);
            }
            let q = [0, 1, 2].map(|a| t[0][a] + u * (t[1][a] - t[0][a]) + v * (t[2][a] - t[0][a]));
            let nrm = microfrep_meshfield::geom::unit_normal(&t);
            let off =
                (0.002 + 0.048 * rng.unit()) * diag * if rng.unit() < 0.5 { -1.0 } else { 1.0 };
            pts.push([0, 1, 2].map(|a| q[a] + off * nrm[a]));
        }
    }
    pts
}

/// The mesh without a fraction of its triangles (chosen by seed).
pub fn remove_fraction(m: &TriMesh, frac: f64, seed: u64) -> TriMesh {
    let mut rng = Rng(seed);
    let mut out = m.clone();
    out.triangles.retain(|_| rng.unit() >= frac);
    out
}

/// The mesh with a fraction of its triangles reversed; returns how many.
pub fn flip_fraction(m: &TriMesh, frac: f64, seed: u64) -> (TriMesh, usize) {
    let mut rng = Rng(seed);
    let mut out = m.clone();
    let mut n = 0;
    for t in &mut out.triangles {
        if rng.unit() < frac {
            t.swap(1, 2);
            n += 1;
        }
    }
    (out, n)
}

/// ASCII STL text of a mesh (shortest round-trip f32 decimals).
pub fn ascii_stl(m: &TriMesh) -> String {
    let mut s = String::from("solid test\n");
    for t in 0..m.triangles.len() {
        let c = m.corners(t);
        let n = microfrep_meshfield::geom::unit_normal(&c);
        s += &format!(
            "  facet normal {} {} {}\n    outer loop\n",
            n[0] as f32, n[1] as f32, n[2] as f32
        );
        for v in c {
            s += &format!(
                "      vertex {} {} {}\n",
                v[0] as f32, v[1] as f32, v[2] as f32
            );
        }
        s += "    endloop\n  endfacet\n";
    }
    s + "endsolid test\n"
}

/// Binary STL bytes of a mesh, with a header that starts with "solid".
pub fn binary_stl(m: &TriMesh) -> Vec<u8> {
    let mut d = vec![b' '; 80];
    d[..18].copy_from_slice(b"solid binary part ");
    d.extend_from_slice(&(m.triangles.len() as u32).to_le_bytes());
    for t in 0..m.triangles.len() {
        let c = m.corners(t);
        let n = microfrep_meshfield::geom::unit_normal(&c);
        for x in n.iter().chain(c.iter().flatten()) {
            d.extend_from_slice(&(*x as f32).to_le_bytes());
        }
        d.extend_from_slice(&[0, 0]);
    }
    d
}

/// What [`check_reference`] saw.
#[derive(Debug, Default)]
pub struct Seen {
    pub points: usize,
    pub signed: usize,
    pub max_dist_err: f64,
}

/// Checks `field` against brute force: distance to `damaged` within 1e-9
/// of the diagonal at every point, the sign of the clean mesh wherever the
/// point is farther than `sign_margin` (fraction of the diagonal) from both
/// surfaces, and the batch path against the point path.
pub fn check_reference(
    tag: &str,
    field: &MeshField,
    damaged: &TriMesh,
    clean: &TriMesh,
    pts: &[[f64; 3]],
    sign_margin: f64,
) -> Seen {
    let diag = clean.diagonal();
    let dt = soup(damaged);
    let ct = soup(clean);
    let mut seen = Seen::default();
    let mut wrong = Vec::new();
    for &p in pts {
        let v = field.eval(p);
        let d_ref = brute_distance(&dt, p);
        let err = (v.abs() - d_ref).abs();
        assert!(
            err <= 1e-9 * diag,
            "{tag}: distance at {p:?}: field {} brute force {d_ref}",
            v.abs()
        );
        seen.max_dist_err = seen.max_dist_err.max(err);
        let d_clean = brute_distance(&ct, p);
        if d_ref.min(d_clean) > sign_margin * diag {
            seen.signed += 1;
            if (v > 0.0) != brute_inside(&ct, p) {
                wrong.push((p, v, d_ref));
            }
        }
        seen.points += 1;
    }
    assert!(
        wrong.is_empty(),
        "{tag}: wrong sign at {} of {} points, e.g. {:?}",
        wrong.len(),
        seen.signed,
        &wrong[..wrong.len().min(3)]
    );
    // Batch equals point (f32 outputs), over blocks of 256.
    for chunk in pts.chunks(256) {
        let x: Vec<f32> = chunk.iter().map(|p| p[0] as f32).collect();
        let y: Vec<f32> = chunk.iter().map(|p| p[1] as f32).collect();
        let z: Vec<f32> = chunk.iter().map(|p| p[2] as f32).collect();
        let mut out = vec![0f32; chunk.len()];
        field.eval_batch(&x, &y, &z, &mut out);
        for i in 0..chunk.len() {
            let p = [x[i] as f64, y[i] as f64, z[i] as f64];
            assert_eq!(out[i], field.eval(p) as f32, "{tag}: batch at {p:?}");
        }
    }
    seen
}
