//! A mesh bound as the whole model renders as the formula it approximates:
//! a triangulated sphere against the unit sphere, through the direct
//! ray-triangle path (closed mesh) and through the sampled search (the
//! same mesh with a hole), and the same bytes on one thread or two.

use microfrep_core::Shape;
use microfrep_meshfield::{MeshField, TriMesh};
use microfrep_render::trace::Tracer;
use microfrep_render::{ray_cast, Camera, RgbImage, View};
use microfrep_structures::examples::unit_sphere;
use std::collections::HashMap;
use std::sync::Arc;

const BG: [u8; 3] = [250, 250, 250];
const LO: [f64; 3] = [-1.2; 3];
const HI: [f64; 3] = [1.2; 3];

/// An icosahedron subdivided `levels` times, its vertices on the unit
/// sphere, triangles counter-clockwise seen from outside.
fn icosphere(levels: usize) -> TriMesh {
    let g = (1.0 + 5f64.sqrt()) / 2.0;
    let mut v: Vec<[f64; 3]> = vec![
        [-1.0, g, 0.0],
        [1.0, g, 0.0],
        [-1.0, -g, 0.0],
        [1.0, -g, 0.0],
        [0.0, -1.0, g],
        [0.0, 1.0, g],
        [0.0, -1.0, -g],
        [0.0, 1.0, -g],
        [g, 0.0, -1.0],
        [g, 0.0, 1.0],
        [-g, 0.0, -1.0],
        [-g, 0.0, 1.0],
    ];
    let mut t: Vec<[u32; 3]> = vec![
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
    let unit = |p: [f64; 3]| {
        let l = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        p.map(|c| c / l)
    };
    for p in &mut v {
        *p = unit(*p);
    }
    for _ in 0..levels {
        let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
        let mut next = Vec::with_capacity(4 * t.len());
        for &[a, b, c] in &t {
            let mut m = |i: u32, j: u32| {
                *mid.entry((i.min(j), i.max(j))).or_insert_with(|| {
                    let (p, q) = (v[i as usize], v[j as usize]);
                    v.push(unit([0, 1, 2].map(|k| 0.5 * (p[k] + q[k]))));
                    (v.len() - 1) as u32
                })
            };
            let (ab, bc, ca) = (m(a, b), m(b, c), m(c, a));
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        t = next;
    }
    TriMesh::new(v, t).unwrap()
}

fn mesh_shape(mesh: &TriMesh) -> Shape {
    Shape::from_field(Arc::new(MeshField::new(mesh).unwrap()))
}

fn hit_mask(img: &RgbImage) -> Vec<bool> {
    img.data.chunks(3).map(|c| c != BG).collect()
}

/// Pixels whose centre lies within `band` pixels of the unit circle the
/// sphere projects to (orthographic views: the silhouette).
fn near_silhouette(cam: &Camera, x: usize, y: usize, band: f64) -> bool {
    let (u, v) = cam.screen(x as f64, y as f64);
    let p = cam.point(u, v, 0.0);
    let d = cam.dir;
    // Distance from the origin to the ray, against the radius 1.
    let along = p[0] * d[0] + p[1] * d[1] + p[2] * d[2];
    let q = [0, 1, 2].map(|k| p[k] - along * d[k]);
    let r = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt();
    (r - 1.0).abs() <= band * cam.scale
}

/// Hit masks agree off the silhouette, the depths of the hits within the
/// mesh's distance from the sphere, and the shading within what facets of
/// about 2.6 degrees change.
fn compare_to_formula(mesh: &TriMesh, views: &[View]) {
    let formula = Shape::from(&unit_sphere());
    let part = mesh_shape(mesh);
    for &view in views {
        let cam = Camera::fit(view, LO, HI, 120, 90);
        let (a, b) = (
            ray_cast(&formula, &cam, LO, HI),
            ray_cast(&part, &cam, LO, HI),
        );
        let (ma, mb) = (hit_mask(&a), hit_mask(&b));
        let mut differ = 0;
        for y in 0..90 {
            for x in 0..120 {
                let k = y * 120 + x;
                if ma[k] != mb[k] {
                    differ += 1;
                    assert!(
                        near_silhouette(&cam, x, y, 1.0),
                        "{view:?}: pixel ({x}, {y}) differs away from the silhouette"
                    );
                }
                if ma[k] && mb[k] && !near_silhouette(&cam, x, y, 2.0) {
                    let (ca, cb) = (a.pixel(x, y), b.pixel(x, y));
                    for c in 0..3 {
                        assert!(
                            (ca[c] as i32 - cb[c] as i32).abs() <= 12,
                            "{view:?}: ({x}, {y}) shaded {ca:?} vs {cb:?}"
                        );
                    }
                }
            }
        }
        assert!(differ <= 40, "{view:?}: {differ} pixels differ");
        // Depths: the mesh lies within 1.5e-3 inside the sphere.
        let mut tf = Tracer::new(formula.tape(), &cam, LO, HI);
        let mut tm = Tracer::new(part.tape(), &cam, LO, HI);
        let mut checked = 0;
        for (x, y) in (0..90)
            .step_by(4)
            .flat_map(|y| (0..120).step_by(4).map(move |x| (x, y)))
        {
            let Some(df) = tf.pixel(x, y) else {
                continue;
            };
            if near_silhouette(&cam, x, y, 2.0) {
                continue;
            }
            checked += 1;
            let dm = tm.pixel(x, y).expect("the mesh is hit where the sphere is");
            // Behind the sphere's hit, on the mesh, which lies within
            // 1.5e-3 inside the sphere.
            let (u, v) = cam.screen(x as f64, y as f64);
            let p = cam.point(u, v, dm);
            let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
            assert!(
                dm >= df - 1e-6 && r <= 1.0 + 1e-6 && r >= 1.0 - 1.5e-3,
                "{view:?}: ({x}, {y}) depth {dm} vs {df}, radius {r}"
            );
        }
        assert!(checked > 60, "{view:?}: {checked} depths compared");
    }
}

#[test]
fn closed_mesh_sphere_renders_as_the_formula_sphere() {
    compare_to_formula(&icosphere(4), &[View::Front, View::Top, View::Iso]);
}

#[test]
fn open_mesh_sphere_renders_as_the_formula_sphere() {
    // One triangle away (on the far side from every view used): the mesh is
    // not closed, the winding number signs it, and rays are searched by
    // sampling rather than by the triangles.
    let mut m = icosphere(4);
    let far = m
        .triangles
        .iter()
        .position(|t| t.iter().all(|&i| m.vertices[i as usize][1] > 0.9))
        .unwrap();
    m.triangles.remove(far);
    let m = TriMesh::new(m.vertices, m.triangles).unwrap();
    compare_to_formula(&m, &[View::Front, View::Iso]);
}

#[test]
fn mesh_render_is_the_same_on_one_thread_and_two() {
    let part = mesh_shape(&icosphere(3));
    let cam = Camera::fit(View::Iso, LO, HI, 96, 64);
    let on = |n: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .unwrap()
            .install(|| ray_cast(&part, &cam, LO, HI).encode_png().unwrap())
    };
    assert_eq!(on(1), on(2));
}
