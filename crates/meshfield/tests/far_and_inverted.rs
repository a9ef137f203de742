//! Queries far from the mesh (huge, infinite, NaN coordinates) in all four
//! evaluation modes, and closed meshes wound inside out.
#![allow(clippy::needless_range_loop)]

mod common;

use common::*;
use microfrep_core::{Field, Interval};
use microfrep_meshfield::read::{parse, Format};
use microfrep_meshfield::{BuildOptions, MeshError, MeshField, SignMethod, TriMesh};
use proptest::prelude::*;

/// An axis-aligned box, outward-facing.
fn cuboid(lo: [f64; 3], hi: [f64; 3]) -> TriMesh {
    let v: Vec<[f64; 3]> = (0..8)
        .map(|i| {
            [
                if i & 1 == 0 { lo[0] } else { hi[0] },
                if i & 2 == 0 { lo[1] } else { hi[1] },
                if i & 4 == 0 { lo[2] } else { hi[2] },
            ]
        })
        .collect();
    let quads = [
        [0, 2, 3, 1], // z = lo
        [4, 5, 7, 6], // z = hi
        [0, 1, 5, 4], // y = lo
        [2, 6, 7, 3], // y = hi
        [0, 4, 6, 2], // x = lo
        [1, 3, 7, 5], // x = hi
    ];
    let mut t = Vec::new();
    for q in quads {
        t.push([q[0], q[1], q[2]]);
        t.push([q[0], q[2], q[3]]);
    }
    TriMesh {
        vertices: v,
        triangles: t,
    }
}

fn reversed(m: &TriMesh) -> TriMesh {
    let t = m.triangles.iter().map(|&[a, b, c]| [a, c, b]).collect();
    TriMesh::new(m.vertices.clone(), t).unwrap()
}

fn with_sign(m: &TriMesh, sign: SignMethod) -> MeshField {
    let o = BuildOptions {
        sign,
        ..BuildOptions::default()
    };
    MeshField::build(m, &o, &|_, _| {}).unwrap()
}

/// Distance from `p` to the box [lo, hi], scaled so that no square
/// overflows: a lower bound on the distance to a mesh in the box, and
/// within the box's diagonal of it.
fn box_distance(p: [f64; 3], lo: [f64; 3], hi: [f64; 3]) -> f64 {
    let q: [f64; 3] = std::array::from_fn(|a| (lo[a] - p[a]).max(p[a] - hi[a]).max(0.0));
    let m = q.iter().fold(0.0f64, |m, c| m.max(*c));
    if m == 0.0 || m.is_infinite() {
        return m;
    }
    m * q.iter().map(|c| (c / m) * (c / m)).sum::<f64>().sqrt()
}

/// Checks all four modes at `p`, which lies outside the mesh's box.
fn check_far(tag: &str, f: &MeshField, m: &TriMesh, p: [f64; 3]) {
    let [lo, hi] = m.bbox();
    let diag = m.diagonal();
    let v = f.eval(p);
    assert!(v < 0.0, "{tag} at {p:?}: value {v} is not outside");
    let bd = box_distance(p, lo, hi);
    if bd.is_infinite() {
        assert_eq!(v, f64::NEG_INFINITY, "{tag} at {p:?}");
    } else {
        assert!(
            -v >= bd * (1.0 - 1e-12) && -v <= bd + diag * (1.0 + 1e-9) + bd * 1e-12,
            "{tag} at {p:?}: value {v}, box distance {bd}"
        );
    }
    let (gv, g) = f.grad(p);
    assert_eq!(gv.to_bits(), v.to_bits(), "{tag} at {p:?}: grad value");
    let len = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
    assert!((len - 1.0).abs() < 1e-9, "{tag} at {p:?}: gradient {g:?}");
    // The gradient points back towards the mesh.
    let c: [f64; 3] = std::array::from_fn(|a| 0.5 * (lo[a] + hi[a]));
    let s = p.map(|x| x.signum());
    let towards: f64 = (0..3)
        .map(|a| {
            if (p[a] - c[a]).abs() > diag {
                g[a] * s[a]
            } else {
                0.0
            }
        })
        .sum();
    assert!(towards < 0.0, "{tag} at {p:?}: gradient {g:?} points away");
    let iv = f.interval(p.map(Interval::point));
    assert!(
        iv.lo <= v && v <= iv.hi || iv.lo == f64::NEG_INFINITY,
        "{tag} at {p:?}: interval {iv:?} misses {v}"
    );
    let around = p.map(|x| {
        let r = 1e-3 * x.abs().clamp(1.0, 1e300);
        if x.is_finite() {
            Interval::new(x - r, x + r)
        } else {
            Interval::point(x)
        }
    });
    let iv = f.interval(around);
    assert!(
        iv.lo <= v && v <= iv.hi,
        "{tag} at {p:?}: box interval {iv:?} misses {v}"
    );
    assert!(
        iv.hi <= 0.0 || iv.lo == f64::NEG_INFINITY,
        "{tag} at {p:?}: box interval {iv:?}"
    );
    let pf = p.map(|x| x as f32);
    let mut out = [0f32; 1];
    f.eval_batch(&[pf[0]], &[pf[1]], &[pf[2]], &mut out);
    assert!(out[0] < 0.0, "{tag} at {pf:?}: batch value {}", out[0]);
    if p.iter().all(|x| x.abs() < 1e30) {
        let want = f.eval(pf.map(|x| x as f64)) as f32;
        assert_eq!(out[0], want, "{tag} at {pf:?}: batch");
    }
}

fn meshes() -> Vec<(&'static str, TriMesh, SignMethod)> {
    let cube = cuboid([0.0; 3], [10.0; 3]);
    let sphere = icosphere(2, 1.0, [0.3, -0.2, 0.1]);
    let open = remove_fraction(&icosphere(2, 1.0, [0.0; 3]), 0.1, 3);
    vec![
        ("cube", cube.clone(), SignMethod::PseudoNormal),
        ("cube/winding", cube, SignMethod::Winding),
        ("sphere", sphere.clone(), SignMethod::PseudoNormal),
        ("sphere/winding", sphere, SignMethod::Winding),
        ("open sphere", open, SignMethod::Winding),
    ]
}

/// The example of the report: a 10 mm cube seen from 1e20 away.
#[test]
fn cube_far_along_x_is_outside() {
    let m = cuboid([0.0; 3], [10.0; 3]);
    for sign in [SignMethod::PseudoNormal, SignMethod::Winding] {
        let f = with_sign(&m, sign);
        assert_eq!(f.eval([1e20, 5.0, 5.0]), -(1e20 - 10.0));
        assert_eq!(f.eval([-1e20, 5.0, 5.0]), -1e20);
        assert_eq!(f.eval([f64::INFINITY, 5.0, 5.0]), f64::NEG_INFINITY);
        let (_, g) = f.grad([f64::INFINITY, 5.0, 5.0]);
        assert_eq!(g, [-1.0, 0.0, 0.0]);
        assert!(f.eval([f64::NAN, 5.0, 5.0]).is_nan());
        assert!(f.grad([5.0, f64::NAN, 5.0]).1[0].is_nan());
        assert!(f.interval([Interval::point(f64::NAN); 3]).is_nan());
        assert_eq!(
            f.interval([Interval::point(f64::INFINITY); 3]).lo,
            f64::NEG_INFINITY
        );
        assert!(f.closest([1e300, 0.0, 0.0]).is_none());
        assert!(f.closest([f64::INFINITY, 0.0, 0.0]).is_none());
        assert!(f.closest([1e20, 5.0, 5.0]).is_some());
        // Inside stays inside.
        assert_eq!(f.eval([5.0, 5.0, 5.0]), 5.0);
        check_far("cube", &f, &m, [1e20, 5.0, 5.0]);
        check_far("cube", &f, &m, [1e39, 1e39, -1e39]);
        check_far("cube", &f, &m, [f64::MAX, f64::MAX, f64::MAX]);
        check_far("cube", &f, &m, [f64::INFINITY, f64::NEG_INFINITY, 0.0]);
    }
}

/// Every magnitude from just beyond the box to f64::MAX, and infinities,
/// in every direction: outside, at about the right distance, in all modes.
#[test]
fn far_points_in_every_direction_and_at_every_scale() {
    let mut rng = Rng(11);
    for (tag, m, sign) in meshes() {
        let f = with_sign(&m, sign);
        for k in 0..400 {
            let dir: [f64; 3] = std::array::from_fn(|_| 2.0 * rng.unit() - 1.0);
            let exp = 1.0 + 307.0 * rng.unit();
            let r = 10f64.powf(exp);
            let mut p = dir.map(|c| c * r);
            if k % 10 == 0 {
                p[rng.below(3)] = if rng.unit() < 0.5 {
                    f64::INFINITY
                } else {
                    f64::NEG_INFINITY
                };
            }
            let [lo, hi] = m.bbox();
            if box_distance(p, lo, hi) < 2.0 * m.diagonal() {
                continue;
            }
            check_far(tag, &f, &m, p);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// Points on one axis at any distance (the coordinates where the
    /// search loses precision first), with the others inside the box.
    #[test]
    fn far_along_an_axis(axis in 0usize..3, exp in 0.5f64..308.0, neg: bool, u in 0.0f64..1.0, v in 0.0f64..1.0) {
        for (tag, m, sign) in meshes() {
            let f = with_sign(&m, sign);
            let [lo, hi] = m.bbox();
            let mut p: [f64; 3] = std::array::from_fn(|a| lo[a] + [u, v, 0.5][(a + 3 - axis) % 3] * (hi[a] - lo[a]));
            let r = 10f64.powf(exp) * m.diagonal();
            p[axis] = if neg { lo[axis] - r } else { hi[axis] + r };
            check_far(tag, &f, &m, p);
        }
    }
}

#[test]
fn huge_vertex_coordinates_are_refused() {
    let m = cuboid([0.0; 3], [1e200, 1.0, 1.0]);
    match MeshField::new(&m) {
        Err(MeshError::HugeCoordinate { vertex, .. }) => assert_eq!(vertex, 1),
        other => panic!("{other:?}"),
    }
    let e = MeshField::new(&m).unwrap_err().to_string();
    assert!(e.contains("scale"), "{e}");
}

/// Points well inside and well outside a closed mesh, by brute force.
fn classify_like_brute(tag: &str, f: &MeshField, truth: &TriMesh, seed: u64) {
    let tris = soup(truth);
    let pts = sample_points(truth, 300, seed);
    for p in pts {
        let d = brute_distance(&tris, p);
        if d < 1e-6 * truth.diagonal() {
            continue;
        }
        let inside = brute_inside(&tris, p);
        let v = f.eval(p);
        assert_eq!(v > 0.0, inside, "{tag} at {p:?}: {v}");
        assert!(
            (v.abs() - d).abs() < 1e-9 * truth.diagonal(),
            "{tag} at {p:?}: {v} vs {d}"
        );
    }
}

/// Inside-out closed meshes are turned over, under every sign rule, and
/// say so; correctly wound ones and cavities are left alone.
#[test]
fn inside_out_meshes_are_turned_over() {
    let shapes = [
        ("cube", cuboid([0.0; 3], [10.0; 3])),
        ("sphere", icosphere(3, 1.0, [0.1, 0.2, 0.3])),
        ("torus", torus(32, 16, 1.0, 0.3)),
    ];
    for (tag, m) in &shapes {
        let inv = reversed(m);
        assert!(inv.volume() < 0.0);
        for sign in [
            SignMethod::Auto,
            SignMethod::PseudoNormal,
            SignMethod::Winding,
        ] {
            let f = with_sign(&inv, sign);
            let v = f.inverted().expect("turned over");
            assert!(
                (v + m.volume()).abs() < 1e-9 * m.volume().abs(),
                "{tag}: {v}"
            );
            classify_like_brute(tag, &f, m, 5);
            let ok = with_sign(m, sign);
            assert_eq!(ok.inverted(), None, "{tag}");
        }
        // Also when some triangles were flipped on top (repaired first).
        let (damaged, _) = flip_fraction(&inv, 0.2, 9);
        let f = with_sign(&damaged, SignMethod::Auto);
        assert!(f.inverted().is_some(), "{tag}");
        classify_like_brute(tag, &f, m, 6);
    }
    // A box with an inward cavity: the cavity stays a cavity.
    let outer = cuboid([0.0; 3], [10.0; 3]);
    let inner = reversed(&cuboid([3.0; 3], [6.0; 3]));
    let mut v = outer.vertices.clone();
    let mut t = outer.triangles.clone();
    let n = v.len() as u32;
    v.extend(inner.vertices.iter().copied());
    t.extend(inner.triangles.iter().map(|tr| tr.map(|i| i + n)));
    let hollow = TriMesh::new(v, t).unwrap();
    let f = MeshField::new(&hollow).unwrap();
    assert_eq!(f.inverted(), None);
    assert!(f.eval([4.5; 3]) < 0.0 && f.eval([1.0; 3]) > 0.0);
}

/// The report's cone: an OBJ with every face wound clockwise.
#[test]
fn reversed_obj_cone_has_its_volume() {
    let n = 96;
    let mut obj = String::from("v 0 0 0\nv 0 0 1\n");
    for i in 0..n {
        let a = std::f64::consts::TAU * i as f64 / n as f64;
        obj += &format!("v {} {} 0\n", a.cos(), a.sin());
    }
    for i in 0..n {
        let (a, b) = (3 + i, 3 + (i + 1) % n);
        // Clockwise seen from outside: base seen from below, side from out.
        obj += &format!("f 1 {a} {b}\nf 2 {b} {a}\n");
    }
    let m = parse(Format::Obj, obj.as_bytes()).unwrap();
    assert!(m.volume() < 0.0);
    for sign in [SignMethod::Auto, SignMethod::Winding] {
        let f = with_sign(&m, sign);
        assert!(f.inverted().is_some());
        // Midpoint sampling of the unit cube around the cone.
        let k = 60;
        let mut inside = 0usize;
        for i in 0..k {
            for j in 0..k {
                for l in 0..k {
                    let p = [
                        -1.0 + 2.0 * (i as f64 + 0.5) / k as f64,
                        -1.0 + 2.0 * (j as f64 + 0.5) / k as f64,
                        (l as f64 + 0.5) / k as f64,
                    ];
                    if f.eval(p) > 0.0 {
                        inside += 1;
                    }
                }
            }
        }
        let vol = inside as f64 * 2.0 * 2.0 / (k * k * k) as f64;
        let pi3 = std::f64::consts::PI / 3.0;
        assert!(
            (vol - pi3).abs() < 0.03 * pi3,
            "{sign:?}: volume {vol}, want {pi3}"
        );
    }
}
