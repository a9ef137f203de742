//! MeshField against brute force on meshes with known fields, clean and
//! damaged, and through the core's four-mode field check.
#![allow(clippy::needless_range_loop)]

mod common;

use common::*;
use microfrep_core::field_check::{check_field, FieldCheck};
use microfrep_core::{Field, Interval};
use microfrep_meshfield::read::{parse, Format};
use microfrep_meshfield::{BuildOptions, MeshError, MeshField, SignMethod, TriMesh};
use std::sync::Arc;

fn build(m: &TriMesh) -> MeshField {
    MeshField::new(m).unwrap()
}

fn region(m: &TriMesh) -> [[f64; 3]; 2] {
    let [lo, hi] = m.bbox();
    let g = 0.2 * m.diagonal();
    [lo.map(|c| c - g), hi.map(|c| c + g)]
}

/// The clean sphere and torus: watertight, pseudo-normal sign, exact.
#[test]
fn clean_sphere_and_torus_match_brute_force() {
    for (tag, m) in [
        ("sphere", icosphere(3, 1.0, [0.1, -0.2, 0.3])),
        ("torus", torus(48, 24, 1.0, 0.35)),
    ] {
        let f = build(&m);
        assert_eq!(f.sign_method(), SignMethod::PseudoNormal, "{tag}");
        assert!(f.topology().is_watertight());
        let pts = sample_points(&m, 1500, 7);
        let seen = check_reference(tag, &f, &m, &m, &pts, 1e-3);
        assert!(seen.signed > 1400, "{tag}: {seen:?}");
    }
    // The icosphere's field inside is below the sphere's (chords cut in).
    let m = icosphere(3, 1.0, [0.0; 3]);
    let f = build(&m);
    let at_centre = f.eval([0.0; 3]);
    assert!(at_centre < 1.0 && at_centre > 0.98, "{at_centre}");
}

/// Damaged variants: 1 % removed, 15 % flipped (repaired, and not),
/// unwelded, and an ASCII STL round trip.
#[test]
fn damaged_meshes_keep_the_right_inside() {
    for (tag, m) in [
        ("sphere", icosphere(4, 1.0, [0.0; 3])),
        ("torus", torus(64, 32, 1.0, 0.35)),
    ] {
        let pts = sample_points(&m, 1000, 11);

        let holes = remove_fraction(&m, 0.01, 3);
        assert!(holes.triangles.len() < m.triangles.len());
        let f = build(&holes);
        assert_eq!(f.sign_method(), SignMethod::Winding);
        assert!(f.topology().open_edges > 0);
        check_reference(&format!("{tag} 1% removed"), &f, &holes, &m, &pts, 1e-3);

        let (flipped, n) = flip_fraction(&m, 0.15, 5);
        assert!(n > m.triangles.len() / 10);
        assert!(flipped.topology().inconsistent_edges > 0);
        let f = build(&flipped);
        assert_eq!(
            f.flipped(),
            n,
            "{tag}: repair flips back exactly the flipped ones"
        );
        assert_eq!(f.sign_method(), SignMethod::PseudoNormal);
        check_reference(&format!("{tag} 15% flipped"), &f, &flipped, &m, &pts, 1e-3);
        // Without the repair the winding number alone is right away from
        // the flipped triangles (near one, it sees a half-space).
        let opts = BuildOptions {
            orient: false,
            ..Default::default()
        };
        let f = MeshField::build(&flipped, &opts, &|_, _| {}).unwrap();
        assert_eq!(f.sign_method(), SignMethod::Winding);
        check_reference(
            &format!("{tag} 15% flipped, no repair"),
            &f,
            &flipped,
            &m,
            &pts,
            0.05,
        );

        let soup = m.unwelded();
        let f = build(&soup);
        assert_eq!(f.sign_method(), SignMethod::Winding);
        assert_eq!(f.topology().open_edges, 3 * m.triangles.len());
        check_reference(&format!("{tag} unwelded"), &f, &soup, &m, &pts, 1e-3);

        let text = ascii_stl(&m);
        let read = parse(Format::Stl, text.as_bytes()).unwrap();
        assert_eq!(read.triangles.len(), m.triangles.len());
        let (welded, collapsed) = read.weld(0.0);
        assert_eq!((welded.vertices.len(), collapsed), (m.vertices.len(), 0));
        assert_eq!(welded.topology(), m.topology());
        let f = build(&welded);
        assert_eq!(f.sign_method(), SignMethod::PseudoNormal);
        check_reference(
            &format!("{tag} ASCII STL"),
            &f,
            &welded,
            &welded,
            &pts,
            1e-3,
        );
    }
}

/// The core's four-mode check (batch, intervals, gradients, graph node).
#[test]
fn passes_the_core_field_check() {
    let sphere = icosphere(3, 1.0, [0.0; 3]);
    let torus = torus(40, 20, 1.0, 0.35);
    let holes = remove_fraction(&torus, 0.02, 9);
    let soup = sphere.unwelded();
    for (tag, m) in [
        ("sphere", &sphere),
        ("torus", &torus),
        ("torus with holes", &holes),
        ("sphere soup", &soup),
    ] {
        let f: Arc<dyn Field> = Arc::new(build(m));
        let mut cfg = FieldCheck::new(region(m));
        cfg.points = 800;
        cfg.boxes = 200;
        let r = check_field(&f, &cfg).unwrap_or_else(|e| panic!("{tag}: {e}"));
        assert!(r.points == 800 && r.boxes == 200, "{tag}: {r:?}");
    }
}

/// Intervals contain the values and are sign-definite where they can be.
#[test]
fn intervals_bound_values_and_decide_clear_boxes() {
    let m = torus(48, 24, 1.0, 0.35);
    let holes = remove_fraction(&m, 0.01, 4);
    for (tag, f) in [("closed", build(&m)), ("holes", build(&holes))] {
        let mut rng = Rng(21);
        let reg = region(&m);
        let (mut inside, mut outside, mut either) = (0, 0, 0);
        for _ in 0..400 {
            let w = 0.02 + 0.15 * rng.unit();
            let b: [Interval; 3] = std::array::from_fn(|a| {
                let c = reg[0][a] + (reg[1][a] - reg[0][a]) * rng.unit();
                Interval::new(c - w, c + w)
            });
            let iv = f.interval(b);
            for _ in 0..20 {
                let p = b.map(|i| i.lo + (i.hi - i.lo) * rng.unit());
                let v = f.eval(p);
                assert!(iv.contains(v), "{tag}: {v} at {p:?} outside {iv:?}");
            }
            if iv.lo > 0.0 {
                inside += 1;
            } else if iv.hi < 0.0 {
                outside += 1;
            } else {
                either += 1;
            }
        }
        // Boxes as large as their distance to the surface stay undecided
        // for the winding bound; the closed mesh decides them by topology.
        assert!(
            outside > 100 && either > 0,
            "{tag}: {inside} {outside} {either}"
        );
        assert!(
            tag != "closed" || inside > 0,
            "{tag}: {inside} {outside} {either}"
        );
        // A small box in the tube, clear of the surface: inside for sure.
        let b = [
            Interval::new(0.98, 1.02),
            Interval::new(-0.02, 0.02),
            Interval::new(-0.02, 0.02),
        ];
        let iv = f.interval(b);
        assert!(iv.lo > 0.25 && iv.hi < 0.4, "{tag}: {iv:?}");
        // The hole of the torus: outside for sure (the winding-number bound
        // adds up |gradient| bounds without cancellation, so it decides
        // boxes small against their distance to the surface).
        let b = [
            Interval::new(-0.01, 0.01),
            Interval::new(-0.01, 0.01),
            Interval::new(-0.01, 0.01),
        ];
        let iv = f.interval(b);
        assert!(iv.hi < -0.6 && iv.lo > -0.67, "{tag}: {iv:?}");
    }
}

/// Meshes written by microfrep's own mesher: a sphere and a lattice part.
#[test]
fn microfrep_meshes_of_a_sphere_and_a_lattice_part() {
    use microfrep_core::{frep, Expr};
    use microfrep_mesh::{MeshOptions, Plan};
    use microfrep_shapes as prims;
    let ball = prims::sphere(&Expr::xyz(), &prims::v3([0.0; 3]), 1.0);
    let opts = MeshOptions::new([[-1.1; 3], [1.1; 3]], 24);
    let mesh = from_microfrep(
        &Plan::new(&microfrep_core::Shape::from(&ball), &opts)
            .unwrap()
            .run(&|_| {})
            .unwrap(),
    );
    let f = build(&mesh);
    assert_eq!(f.sign_method(), SignMethod::PseudoNormal);
    let pts = sample_points(&mesh, 800, 1);
    check_reference("microfrep sphere", &f, &mesh, &mesh, &pts, 1e-3);
    // The mesher's surface is within a fraction of a cell of the sphere.
    for p in [[0.0f64; 3], [0.5, 0.0, 0.0], [0.0, 0.0, 1.5]] {
        let exact = 1.0 - (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        assert!(
            (f.eval(p) - exact).abs() < 0.03,
            "{p:?}: {} vs {exact}",
            f.eval(p)
        );
    }
    let q = 4.0 * std::f64::consts::PI;
    let rods = microfrep_structures::lattice::rod_lattice(
        &Expr::xyz(),
        &microfrep_structures::lattice::Slabs::uniform(q, 0.5),
        1.0,
    );
    let part = frep::intersection(&rods, &ball, 1.0);
    let mesh = from_microfrep(
        &Plan::new(&microfrep_core::Shape::from(&part), &opts)
            .unwrap()
            .run(&|_| {})
            .unwrap(),
    );
    assert!(mesh.topology().is_watertight(), "{:?}", mesh.topology());
    let f = build(&mesh);
    // At this coarse resolution the mesher's output is closed and oriented
    // but some triangles cross (found by the build, which then signs by the
    // winding number; the pseudo-normal sign was wrong at some points).
    assert_eq!(f.self_intersecting(), Some(true));
    assert_eq!(f.sign_method(), SignMethod::Winding);
    let pts = sample_points(&mesh, 300, 2);
    let seen = check_reference("microfrep lattice part", &f, &mesh, &mesh, &pts, 1e-3);
    assert!(seen.signed > 250, "{seen:?}");
}

/// Two overlapping closed spheres: watertight but crossing, so the build
/// signs by the winding number (2 in the overlap: inside).
#[test]
fn overlapping_shells_are_found_and_signed_by_winding() {
    let a = icosphere(3, 1.0, [0.0; 3]);
    let b = icosphere(3, 1.0, [1.0, 0.0, 0.0]);
    let n = a.vertices.len() as u32;
    let mut m = a.clone();
    m.vertices.extend(&b.vertices);
    m.triangles
        .extend(b.triangles.iter().map(|t| t.map(|i| i + n)));
    assert!(m.topology().is_watertight());
    let f = build(&m);
    assert_eq!(f.self_intersecting(), Some(true));
    assert_eq!(f.sign_method(), SignMethod::Winding);
    let w = f.winding_number([0.5, 0.0, 0.0]).unwrap();
    assert!((w - 2.0).abs() < 0.01, "{w}");
    let pts = sample_points(&m, 600, 3);
    check_reference("overlapping spheres", &f, &m, &m, &pts, 1e-3);
    // One sphere alone is clean.
    assert_eq!(build(&a).self_intersecting(), Some(false));
}

/// Bounds of the BVH contain their triangles; every triangle is in one leaf.
#[test]
fn bvh_is_complete_and_conservative() {
    let m = torus(64, 32, 1.0, 0.3);
    let f = build(&m);
    let bvh = f.bvh();
    let mut count = vec![0; m.triangles.len()];
    fn walk(b: &microfrep_meshfield::bvh::Bvh, i: usize, count: &mut [u32], depth: usize) -> usize {
        let n = b.nodes[i];
        if n.is_leaf() {
            assert!(n.count as usize <= microfrep_meshfield::bvh::MAX_LEAF);
            for t in n.index as usize..(n.index + n.count) as usize {
                count[b.original[t] as usize] += 1;
                for v in b.tris[t] {
                    for a in 0..3 {
                        assert!(n.lo[a] as f64 <= v[a] && v[a] <= n.hi[a] as f64);
                    }
                }
            }
            return depth;
        }
        for c in [i + 1, n.index as usize] {
            let k = b.nodes[c];
            for a in 0..3 {
                assert!(n.lo[a] <= k.lo[a] && k.hi[a] <= n.hi[a]);
            }
        }
        walk(b, i + 1, count, depth + 1).max(walk(b, n.index as usize, count, depth + 1))
    }
    let depth = walk(bvh, 0, &mut count, 1);
    assert!(count.iter().all(|&c| c == 1));
    assert_eq!(depth, bvh.depth());
    assert!(depth < 40, "{depth}");
    assert!(std::mem::size_of::<microfrep_meshfield::bvh::Node>() == 32);
}

#[test]
fn readers_round_trip_a_mesh() {
    let m = icosphere(2, 2.0, [1.0, 0.0, 0.0]);
    let bin = binary_stl(&m);
    assert!(bin.starts_with(b"solid"));
    let a = parse(Format::Stl, &bin).unwrap().weld(0.0).0;
    let mut b = parse(Format::Stl, ascii_stl(&m).as_bytes())
        .unwrap()
        .weld(0.0)
        .0;
    // The text holds the shortest decimal of each f32; back to the f32.
    for v in &mut b.vertices {
        *v = v.map(|c| c as f32 as f64);
    }
    assert_eq!(a, b);
    let mut obj = String::new();
    for v in &m.vertices {
        obj += &format!("v {} {} {}\n", v[0], v[1], v[2]);
    }
    for t in &m.triangles {
        obj += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    assert_eq!(parse(Format::Obj, obj.as_bytes()).unwrap(), m);
    let mut ply = format!(
        "ply\nformat binary_big_endian 1.0\nelement vertex {}\nproperty double x\nproperty double y\n\
         property double z\nelement face {}\nproperty list uchar uint vertex_indices\nend_header\n",
        m.vertices.len(),
        m.triangles.len()
    )
    .into_bytes();
    for v in &m.vertices {
        for c in v {
            ply.extend(c.to_be_bytes());
        }
    }
    for t in &m.triangles {
        ply.push(3);
        for i in t {
            ply.extend(i.to_be_bytes());
        }
    }
    assert_eq!(parse(Format::Ply, &ply).unwrap(), m);
}

#[test]
fn memory_limit_and_progress() {
    let m = icosphere(3, 1.0, [0.0; 3]);
    let opts = BuildOptions {
        memory_limit: 1 << 16,
        ..Default::default()
    };
    let e = MeshField::build(&m, &opts, &|_, _| {}).unwrap_err();
    assert!(matches!(e, MeshError::TooLarge { .. }), "{e}");
    assert!(MeshField::predict_memory(1 << 20, 1 << 19, SignMethod::Winding) > 400 << 20);
    let calls = std::sync::Mutex::new(Vec::new());
    MeshField::build(&m, &BuildOptions::default(), &|d, t| {
        calls.lock().unwrap().push((d, t))
    })
    .unwrap();
    let calls = calls.into_inner().unwrap();
    let total = 4 * m.triangles.len() as u64;
    assert!(calls.windows(2).all(|w| w[0].0 <= w[1].0));
    assert_eq!(*calls.last().unwrap(), (total, total));
    let holes = remove_fraction(&m, 0.05, 1);
    let opts = BuildOptions {
        sign: SignMethod::PseudoNormal,
        ..Default::default()
    };
    let e = MeshField::build(&holes, &opts, &|_, _| {}).unwrap_err();
    assert!(e.to_string().contains("open edges"), "{e}");
}
