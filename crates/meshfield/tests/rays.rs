//! Ray queries of the mesh field: the BVH's first crossing against brute
//! force, where rays enter a closed mesh against the field's own sign, the
//! cases left to the caller, and gradients at points refined onto the
//! surface.

mod common;

use common::*;
use microfrep_core::{Field, RayEntry};
use microfrep_meshfield::bvh::ray_triangle;
use microfrep_meshfield::geom::unit_normal;
use microfrep_meshfield::{MeshField, SignMethod, TriMesh};

/// A ray towards a random point of the box [-1.2, 1.2]^3 from `back`
/// before it (6 puts the start outside the boxes of the test meshes).
fn random_ray(rng: &mut Rng, back: f64) -> ([f64; 3], [f64; 3]) {
    let target = [0, 1, 2].map(|_| 2.4 * rng.unit() - 1.2);
    let (z, phi) = (
        2.0 * rng.unit() - 1.0,
        2.0 * std::f64::consts::PI * rng.unit(),
    );
    let s = (1.0 - z * z).sqrt();
    let dir = [s * phi.cos(), s * phi.sin(), z];
    let o = [0, 1, 2].map(|k| target[k] - back * dir[k]);
    (o, dir)
}

fn brute_first(m: &TriMesh, o: [f64; 3], d: [f64; 3], range: [f64; 2]) -> Option<f64> {
    soup(m)
        .iter()
        .filter_map(|t| ray_triangle(o, d, t))
        .filter(|&t| t >= range[0] && t <= range[1])
        .min_by(f64::total_cmp)
}

#[test]
fn first_hit_is_the_nearest_crossing() {
    for (tag, m) in [
        ("sphere", icosphere(3, 1.0, [0.1, -0.2, 0.3])),
        ("torus", torus(48, 24, 1.0, 0.35)),
    ] {
        let f = MeshField::new(&m).unwrap();
        let mut rng = Rng(7);
        let mut hits = 0;
        for _ in 0..400 {
            let (o, d) = random_ray(&mut rng, 3.0);
            let range = [0.5 + rng.unit(), 3.0 + 2.0 * rng.unit()];
            let got = f.bvh().first_hit(o, d, range).map(|h| h.0);
            let want = brute_first(&m, o, d, range);
            assert_eq!(got.is_some(), want.is_some(), "{tag}: {o:?} {d:?}");
            if let (Some(a), Some(b)) = (got, want) {
                assert!((a - b).abs() <= 1e-12, "{tag}: {a} vs {b}");
                hits += 1;
            }
        }
        assert!(hits > 100, "{tag}: {hits} hits");
    }
}

/// Checks an answer of `ray_entry` against the field's value along the ray.
fn check_entry(tag: &str, f: &MeshField, o: [f64; 3], d: [f64; 3], range: [f64; 2]) -> RayEntry {
    let at = |t: f64| f.eval([0, 1, 2].map(|k| o[k] + t * d[k]));
    let e = f.ray_entry(o, d, range);
    match e {
        RayEntry::Unknown => {}
        RayEntry::Miss => {
            for k in 0..=200 {
                let t = range[0] + (range[1] - range[0]) * k as f64 / 200.0;
                assert!(at(t) < 0.0, "{tag}: a miss is inside at {t}");
            }
        }
        RayEntry::Enter(t) => {
            assert!(t >= range[0] && t <= range[1], "{tag}: {t} out of range");
            assert!(at(t + 1e-7) > 0.0, "{tag}: not inside after {t}");
            assert!(at(t - 1e-7) < 0.0, "{tag}: not outside before {t}");
            for k in 0..200 {
                let s = range[0] + (t - range[0]) * k as f64 / 200.0;
                assert!(at(s) < 0.0, "{tag}: inside at {s} before the entry {t}");
            }
        }
    }
    e
}

#[test]
fn rays_enter_closed_meshes_where_the_sign_changes() {
    // Pseudo-normal sign, and the winding number on two spheres that
    // cross (closed and oriented, so still answered).
    let a = icosphere(3, 0.8, [0.0; 3]);
    let b = icosphere(3, 0.8, [0.6, 0.0, 0.0]);
    let n = a.vertices.len() as u32;
    let mut two = a.clone();
    two.vertices.extend(&b.vertices);
    two.triangles
        .extend(b.triangles.iter().map(|t| t.map(|i| i + n)));
    for (tag, m, sign) in [
        ("torus", torus(48, 24, 1.0, 0.35), SignMethod::PseudoNormal),
        ("two spheres", two, SignMethod::Winding),
    ] {
        let f = MeshField::new(&m).unwrap();
        assert_eq!(f.sign_method(), sign, "{tag}");
        let mut rng = Rng(11);
        let (mut enter, mut miss) = (0, 0);
        for _ in 0..300 {
            let (o, d) = random_ray(&mut rng, 6.0);
            match check_entry(tag, &f, o, d, [0.0, 12.0]) {
                RayEntry::Enter(_) => enter += 1,
                RayEntry::Miss => miss += 1,
                RayEntry::Unknown => panic!("{tag}: a ray from outside is answered"),
            }
        }
        assert!(
            enter > 50 && miss > 10,
            "{tag}: {enter} entries, {miss} misses"
        );
        // Starting inside the mesh's box: left to the caller.
        assert_eq!(
            f.ray_entry([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 3.0]),
            RayEntry::Unknown
        );
        // Bad input: no answer, no panic.
        for (o, d, r) in [
            ([f64::NAN, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0]),
            ([-5.0, 0.0, 0.0], [f64::INFINITY, 0.0, 0.0], [0.0, 1.0]),
            ([-5.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 1.0]),
        ] {
            assert_eq!(f.ray_entry(o, d, r), RayEntry::Unknown);
        }
    }
}

#[test]
fn open_meshes_are_left_to_the_caller() {
    let m = remove_fraction(&icosphere(3, 1.0, [0.0; 3]), 0.05, 3);
    let f = MeshField::new(&m).unwrap();
    assert_eq!(f.sign_method(), SignMethod::Winding);
    assert_eq!(
        f.ray_entry([-3.0, 0.01, 0.02], [1.0, 0.0, 0.0], [0.0, 6.0]),
        RayEntry::Unknown
    );
}

#[test]
fn gradient_next_to_a_face_is_its_normal() {
    // A point a rounding's width off a face: the direction to the closest
    // point is noise there, the face's inward normal is not.
    let m = icosphere(2, 1.0, [0.0; 3]);
    let f = MeshField::new(&m).unwrap();
    let t = m.corners(5);
    let n = unit_normal(&t);
    let c = [0, 1, 2].map(|k| (t[0][k] + t[1][k] + t[2][k]) / 3.0);
    for off in [1e-15, -1e-15, 1e-12, -1e-12] {
        let p = [0, 1, 2].map(|k| c[k] + off * n[k]);
        let (_, g) = f.grad(p);
        let dot = -(g[0] * n[0] + g[1] * n[1] + g[2] * n[2]);
        assert!(
            dot > 1.0 - 1e-9,
            "offset {off}: gradient {g:?}, normal {n:?}"
        );
    }
    // Farther off, the gradient is the exact direction, as before.
    let p = [0, 1, 2].map(|k| c[k] + 0.3 * n[k] + 0.01);
    let (v, g) = f.grad(p);
    assert!(v < 0.0);
    let q = f.closest(p).unwrap().point;
    let e: [f64; 3] = std::array::from_fn(|k| (q[k] - p[k]) / -v);
    assert!(
        (0..3).all(|k| (g[k] - e[k]).abs() < 1e-12),
        "{g:?} vs {e:?}"
    );
}
