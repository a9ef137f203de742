//! Ray casting, cut-aways and sections of the unit sphere against closed forms.

use microfrep_core::Shape;
use microfrep_render::trace::Tracer;
use microfrep_render::{cutaway, ray_cast, section, Camera, Plane, View};
use microfrep_structures::examples::{shell_lattice, unit_sphere};
use std::f64::consts::PI;

const BG: [u8; 3] = [250, 250, 250];
const LO: [f64; 3] = [-1.0; 3];
const HI: [f64; 3] = [1.0; 3];

#[test]
fn sphere_silhouette_matches_projected_disc() {
    let tape = Shape::from(&unit_sphere());
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
fn set_node_search_finds_a_thin_rod_cut_by_a_block() {
    // A thin rod cut by a block: the interval search through the
    // intersection node still finds it, and misses the pixel next to it.
    let cam = Camera::fit(View::Front, LO, HI, 200, 200);
    let (px, py) = (120, 80);
    let (_, v) = cam.screen(px as f64, py as f64);
    let r = 0.2 * cam.scale;
    let p = microfrep_core::Expr::xyz();
    let rod = r * r - (&p[1] - 0.0123).square() - (&p[2] - (v + 0.6 * r)).square();
    let cut = Shape::new(microfrep_core::frep::intersection(
        &rod,
        &(0.9 - p[0].square()),
        0.0,
    ));
    let mut tr = Tracer::new(cut.tape(), &cam, LO, HI);
    assert!(tr.pixel(px, py).is_some());
    assert!(tr.pixel(px, py + 1).is_none());
    // The whole image, tiles of rays searched together first.
    let img = ray_cast(&cut, &cam, LO, HI);
    assert_ne!(img.pixel(px, py), BG);
    assert_eq!(img.pixel(px, py + 1), BG);
}

#[test]
fn same_input_same_bytes() {
    let tape = Shape::from(&shell_lattice());
    let cam = Camera::fit(View::Iso, LO, HI, 96, 64);
    let a = ray_cast(&tape, &cam, LO, HI).encode_png().unwrap();
    let b = ray_cast(&tape, &cam, LO, HI).encode_png().unwrap();
    assert_eq!(a, b);
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
    let solid = Shape::from(&unit_sphere());
    let t = Tracer::new(solid.tape(), &cam, LO, HI)
        .pixel(px, py)
        .unwrap();
    let surface = -(1.0 - x * x - z * z).sqrt();
    assert!((y_of(t) - surface).abs() < 1e-6, "{} vs {surface}", y_of(t));
    let cut = cutaway(&Shape::new(unit_sphere()), View::Front, LO, HI);
    let t = Tracer::new(cut.tape(), &cam, LO, HI).pixel(px, py).unwrap();
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
    let tape = Shape::from(&rod);
    let t = Tracer::new(tape.tape(), &cam, LO, HI)
        .pixel(px, py)
        .expect("rod found");
    let hit = cam.point(u, v, t);
    assert!((hit[1] - yc).abs() <= r, "hit at y = {}", hit[1]);
    // The ray beside it misses.
    assert!(Tracer::new(tape.tape(), &cam, LO, HI)
        .pixel(px, py + 1)
        .is_none());
}

#[test]
fn section_colours_inside_outside_and_zero_contour() {
    let tape = Shape::from(&unit_sphere());
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
