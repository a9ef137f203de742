//! Ray casting, cut-aways and sections of the unit sphere against closed forms.

use microfrep_core::Tape;
use microfrep_core::{Interval, PointEval};
use microfrep_render::csg::CsgEval;
use microfrep_render::trace::Tracer;
use microfrep_render::{cutaway, ray_cast, ray_cast_with, section, Camera, Csg, Plane, View};
use microfrep_structures::examples::{shell_lattice, unit_sphere};
use std::f64::consts::PI;

const BG: [u8; 3] = [250, 250, 250];
const LO: [f64; 3] = [-1.0; 3];
const HI: [f64; 3] = [1.0; 3];

#[test]
fn sphere_silhouette_matches_projected_disc() {
    let tape = Tape::new(&unit_sphere());
    for view in [View::Front, View::Top, View::Iso] {
        let cam = Camera::fit(view, LO, HI, 160, 120);
        let img = ray_cast(&tape, &cam, LO, HI);
        let n = (0..120)
            .flat_map(|y| (0..160).map(move |x| (x, y)))
            .filter(|&(x, y)| img.pixel(x, y) != BG)
            .count() as f64;
        let disc = PI / (cam.scale * cam.scale);
        // Only pixels the silhouette crosses can differ.
        let edge = 2.0 * PI / cam.scale;
        assert!(
            (n - disc).abs() <= edge,
            "{view:?}: {n} px vs {disc} +- {edge}"
        );
    }
}

#[test]
fn csg_bounds_are_sound_for_the_sign_and_tighter() {
    // Boxes of several sizes over the shell-with-lattice and its cut-away:
    // where the set-operation bounds say empty (solid), every sample is
    // outside (inside); and they decide at least as often as plain ones.
    for e in [
        shell_lattice(),
        cutaway(&shell_lattice(), View::Iso, LO, HI),
    ] {
        let tape = Tape::new(&e);
        let csg = Csg::new(&e);
        assert!(csg.leaves() > 3);
        let mut ce = CsgEval::new(&csg);
        let mut pe = PointEval::new(&tape);
        let mut ie = microfrep_core::IntervalEval::new(&tape);
        let (mut decided, mut plain_decided) = (0, 0);
        let mut seed = 12345u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for k in 0..3000 {
            let size = [0.4, 0.1, 0.02][k % 3];
            let c: [f64; 3] = std::array::from_fn(|_| -1.1 + 2.2 * rnd());
            let iv = |a: usize| Interval::new(c[a] - size, c[a] + size);
            let r = ce.eval(iv(0), iv(1), iv(2));
            let empty = r.hi < 0.0;
            let solid = r.lo >= 0.0 && !r.may_be_nan();
            let p = ie.eval(iv(0), iv(1), iv(2));
            plain_decided += (p.hi < 0.0 || p.lo >= 0.0) as usize;
            decided += (empty || solid) as usize;
            if empty || solid {
                for _ in 0..20 {
                    let q: [f64; 3] = std::array::from_fn(|a| c[a] - size + 2.0 * size * rnd());
                    let inside = pe.eval(q) >= 0.0;
                    if empty {
                        assert!(!inside, "empty box {c:?} +- {size}");
                    }
                    if solid {
                        assert!(inside, "solid box {c:?} +- {size}");
                    }
                }
            }
        }
        assert!(
            decided >= plain_decided && decided > 1000,
            "{decided} vs {plain_decided}"
        );
    }
}

#[test]
fn csg_search_finds_the_same_sphere_and_rod() {
    let tape = Tape::new(&unit_sphere());
    let csg = Csg::new(&unit_sphere());
    let cam = Camera::fit(View::Iso, LO, HI, 120, 90);
    let a = ray_cast(&tape, &cam, LO, HI);
    let b = ray_cast_with(&tape, Some(&csg), &cam, LO, HI);
    assert_eq!(a, b);
    // A thin rod cut by a block: the set-operation search still finds it.
    let cam = Camera::fit(View::Front, LO, HI, 200, 200);
    let (px, py) = (120, 80);
    let (_, v) = cam.screen(px as f64, py as f64);
    let r = 0.2 * cam.scale;
    let p = microfrep_core::Expr::xyz();
    let rod = r * r - (&p[1] - 0.0123).square() - (&p[2] - (v + 0.6 * r)).square();
    let cut = microfrep_core::frep::intersection(&rod, &(0.9 - p[0].square()), 0.0);
    let tape = Tape::new(&cut);
    let csg = Csg::new(&cut);
    assert_eq!(csg.leaves(), 2);
    let mut tr = Tracer::with_csg(&tape, &csg, &cam, LO, HI);
    assert!(tr.pixel(px, py).is_some());
    assert!(tr.pixel(px, py + 1).is_none());
    // The whole image, tiles of rays searched together first.
    let img = ray_cast_with(&tape, Some(&csg), &cam, LO, HI);
    assert_ne!(img.pixel(px, py), BG);
    assert_eq!(img.pixel(px, py + 1), BG);
}

#[test]
fn same_input_same_bytes() {
    let tape = Tape::new(&shell_lattice());
    let cam = Camera::fit(View::Iso, LO, HI, 96, 64);
    let a = ray_cast(&tape, &cam, LO, HI).encode_png().unwrap();
    let b = ray_cast(&tape, &cam, LO, HI).encode_png().unwrap();
    assert_eq!(a, b);
    let csg = Csg::new(&shell_lattice());
    let c = ray_cast_with(&tape, Some(&csg), &cam, LO, HI);
    assert_eq!(c, ray_cast_with(&tape, Some(&csg), &cam, LO, HI));
}

#[test]
fn hit_depth_is_on_the_surface_and_cutaway_reaches_the_inside() {
    // Front view: rays run along +y. The ray through (x, z) = (0.5, 0.5)
    // meets the sphere at y = -sqrt(0.5); with the front octant (x > 0,
    // y < 0, z > 0) removed it meets the cut plane y = 0 instead.
    let cam = Camera::fit(View::Front, LO, HI, 200, 200);
    let px = (0.5 / cam.scale + 100.0 - 0.5).round() as usize;
    let py = (100.0 - 0.5 - 0.5 / cam.scale).round() as usize;
    let (u, v) = cam.screen(px as f64, py as f64);
    let (x, z) = (u, v); // right is +x and up is +z in this view
    let y_of = |t: f64| cam.point(u, v, t)[1];
    let solid = Tape::new(&unit_sphere());
    let t = Tracer::new(&solid, &cam, LO, HI).pixel(px, py).unwrap();
    let surface = -(1.0 - x * x - z * z).sqrt();
    assert!((y_of(t) - surface).abs() < 1e-6, "{} vs {surface}", y_of(t));
    let cut = Tape::new(&cutaway(&unit_sphere(), View::Front, LO, HI));
    let t = Tracer::new(&cut, &cam, LO, HI).pixel(px, py).unwrap();
    assert!(y_of(t).abs() < 1e-6, "cut face at y = {}", y_of(t));
}

#[test]
fn thin_rod_is_not_skipped() {
    // Front view, rays along +y. A rod along x of radius 0.2 pixel, set so
    // the ray through one pixel crosses it off its axis for a path shorter
    // than the half-pixel sample spacing: the interval search still finds it.
    let cam = Camera::fit(View::Front, LO, HI, 200, 200);
    let (px, py) = (120, 80);
    let (u, v) = cam.screen(px as f64, py as f64);
    let r = 0.2 * cam.scale;
    let (yc, zc) = (0.0123, v + 0.6 * r);
    let p = microfrep_core::Expr::xyz();
    let rod = r * r - (&p[1] - yc).square() - (&p[2] - zc).square();
    let tape = Tape::new(&rod);
    let t = Tracer::new(&tape, &cam, LO, HI)
        .pixel(px, py)
        .expect("rod found");
    let hit = cam.point(u, v, t);
    assert!((hit[1] - yc).abs() <= r, "hit at y = {}", hit[1]);
    // The ray beside it misses.
    assert!(Tracer::new(&tape, &cam, LO, HI).pixel(px, py + 1).is_none());
}

#[test]
fn section_colours_inside_outside_and_zero_contour() {
    let tape = Tape::new(&unit_sphere());
    let img = section(&tape, "z=0".parse::<Plane>().unwrap(), LO, HI, 101, 101);
    let centre = img.pixel(50, 50);
    let corner = img.pixel(0, 0);
    assert!(centre[0] > centre[2], "inside is red: {centre:?}");
    assert!(corner[2] > corner[0], "outside is blue: {corner:?}");
    let black = img.data.chunks(3).filter(|c| c == &[0, 0, 0]).count() as f64;
    // The contour is about one pixel wide around a circle of 50 pixels.
    let perimeter = 2.0 * PI * 50.0;
    assert!(
        black > 0.8 * perimeter && black < 1.6 * perimeter,
        "{black}"
    );
    assert!("w=1".parse::<Plane>().is_err());
    assert!("x=nan".parse::<Plane>().is_err());
}
