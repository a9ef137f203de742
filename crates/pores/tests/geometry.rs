//! The paper's formulas and the pore geometry against independent
//! references: Eq. 4 against the shoelace area, Eq. 8 against Eq. 4, the
//! 5/6 area ratio of the closed quadratic B-spline, clipped areas and
//! distances against dense polylines, the Doo-Sabin limit surface, Eq. 9,
//! the 3D table's tolerance and the porosity extremes.

use microfrep_core::Field;
use microfrep_pores::cubemap::gauge;
use microfrep_pores::curve::{
    bspline, chain_area, clipped_area, derived_polygon, eq4_area, eq8_l4, polygon_fraction,
    shoelace, signed_distance, solve_r4, ALPHA, P2,
};
use microfrep_pores::doo_sabin::{corner_sign, limit_mesh};
use microfrep_pores::pore3::{control, derived_polyhedron, tabulate_shape, KAPPA};
use microfrep_pores::{porosity_extremes_3d, Options, PoreShape, Pores, Spec};

/// Deterministic uniform numbers in [0, 1).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The closed curve as a dense polygon.
fn dense(ctrl: &[P2; 4], per_arc: usize) -> Vec<P2> {
    bspline(ctrl)
        .iter()
        .flat_map(|a| (0..per_arc).map(move |k| a.at(k as f64 / per_arc as f64)))
        .collect()
}

#[test]
fn eq4_is_the_shoelace_area_of_the_derived_polygon() {
    let mut r = Lcg(1);
    for _ in 0..200 {
        let l = 0.5 + 3.0 * r.next();
        let o = [r.next() * 10.0 - 5.0, r.next() * 10.0 - 5.0];
        let d: [f64; 4] = std::array::from_fn(|_| l * r.next());
        let poly = derived_polygon(o, [o[0] + l, o[1] + l], d.map(|v| v / l));
        let a = shoelace(&poly);
        assert!(
            (a - eq4_area(l, d[0], d[1], d[2], d[3])).abs() < 1e-12 * l * l,
            "{a}"
        );
        // The fraction form on rectangles.
        let w = [0.3 + r.next(), 0.3 + r.next()];
        let f: [f64; 4] = std::array::from_fn(|_| r.next());
        let rect = derived_polygon(o, [o[0] + w[0], o[1] + w[1]], f);
        assert!((shoelace(&rect) / (w[0] * w[1]) - polygon_fraction(f)).abs() < 1e-12);
    }
    // The paper's special cases: the parent itself, and a vanished polygon.
    assert_eq!(eq4_area(2.0, 0.0, 0.0, 0.0, 0.0), 4.0);
    assert_eq!(eq4_area(2.0, 2.0, 2.0, 2.0, 2.0), 4.0);
    assert_eq!(eq4_area(2.0, 0.0, 2.0, 0.0, 2.0), 0.0);
}

#[test]
fn eq8_gives_the_porosity_by_eq4() {
    let mut r = Lcg(2);
    let mut checked = 0;
    for _ in 0..500 {
        // Parent square of side l around a cell of side c <= l (Eq. 7 keeps
        // the two apart).
        let c = 1.0 + r.next();
        let l = c * (1.0 + 0.3 * r.next());
        let p = 0.05 + 0.75 * r.next();
        let (l1, l2, l3) = (l * r.next(), l * r.next(), l * r.next());
        let l4 = eq8_l4(l, l1, l2, l3, p, c * c, ALPHA);
        if !(0.0..=l).contains(&l4) {
            continue;
        }
        let area = eq4_area(l, l1, l2, l3, l4);
        assert!((ALPHA * area / (c * c) - p).abs() < 1e-10, "{p}");
        // Same as the fraction form.
        let q = p * c * c / (ALPHA * l * l);
        assert!((solve_r4(l1 / l, l2 / l, l3 / l, q) - l4 / l).abs() < 1e-10);
        checked += 1;
    }
    assert!(checked > 80, "{checked}");
}

#[test]
fn closed_quadratic_bspline_encloses_five_sixths_of_its_polygon() {
    // Square control polygon: exactly 5/6 (the paper's alpha = 0.83).
    let sq: [P2; 4] = [[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]];
    assert!((chain_area(&bspline(&sq)) / 4.0 - 5.0 / 6.0).abs() < 1e-15);
    // Independently: a polygon of 40 000 points on the curve.
    let a = shoelace(&dense(&sq, 10_000));
    assert!((a / 4.0 - 5.0 / 6.0).abs() < 1e-8, "{a}");
    // The curve passes through (1.75, 1.75): 3/4 of the way to the corner.
    let d = signed_distance(&bspline(&sq), [1.75, 1.75]).0;
    assert!(d.abs() < 1e-12, "{d}");
    // Any derived polygon: still 5/6.
    let mut r = Lcg(3);
    for _ in 0..100 {
        let f: [f64; 4] = std::array::from_fn(|_| r.next());
        let poly = derived_polygon([0.0, 0.0], [1.5, 0.7], f);
        let ratio = chain_area(&bspline(&poly)) / shoelace(&poly);
        assert!((ratio - ALPHA).abs() < 1e-12, "{ratio}");
    }
}

/// Sutherland-Hodgman clipping of a polygon to a rectangle.
fn clip_polygon(mut p: Vec<P2>, lo: P2, hi: P2) -> Vec<P2> {
    for (axis, bound, keep_below) in [
        (0, hi[0], true),
        (0, lo[0], false),
        (1, hi[1], true),
        (1, lo[1], false),
    ] {
        let inside = |q: &P2| {
            if keep_below {
                q[axis] <= bound
            } else {
                q[axis] >= bound
            }
        };
        let mut out = Vec::new();
        for i in 0..p.len() {
            let (a, b) = (p[i], p[(i + 1) % p.len()]);
            if inside(&a) {
                out.push(a);
            }
            if inside(&a) != inside(&b) {
                let t = (bound - a[axis]) / (b[axis] - a[axis]);
                out.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]);
            }
        }
        p = out;
        if p.is_empty() {
            break;
        }
    }
    p
}

#[test]
fn clipped_area_matches_polygon_clipping() {
    let mut r = Lcg(4);
    for _ in 0..60 {
        // A parent up to 1.3 times the cell [-1, 1]^2.
        let k = 1.0 + 0.3 * r.next();
        let f: [f64; 4] = std::array::from_fn(|_| r.next());
        let ctrl = derived_polygon([-k, -k], [k, k], f);
        let exact = clipped_area(&bspline(&ctrl), [-1.0, -1.0], [1.0, 1.0]);
        let poly = clip_polygon(dense(&ctrl, 4000), [-1.0, -1.0], [1.0, 1.0]);
        let approx = shoelace(&poly);
        assert!((exact - approx).abs() < 1e-5, "{exact} vs {approx}");
    }
}

#[test]
fn signed_distance_matches_a_dense_polyline() {
    let mut r = Lcg(5);
    for _ in 0..20 {
        let f: [f64; 4] = std::array::from_fn(|_| r.next());
        let ctrl = derived_polygon([0.0, 0.0], [1.0, 1.0], f);
        let arcs = bspline(&ctrl);
        let poly = dense(&ctrl, 20_000);
        for _ in 0..25 {
            let q = [r.next() * 1.4 - 0.2, r.next() * 1.4 - 0.2];
            let (d, g) = signed_distance(&arcs, q);
            let near = poly
                .iter()
                .map(|p| ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt())
                .fold(f64::INFINITY, f64::min);
            // The polyline's vertices are on the curve: the exact distance
            // is never larger, and smaller by at most the chords' sagitta.
            assert!(
                d.abs() <= near + 1e-12,
                "{d} vs {near} at {q:?} for {ctrl:?}"
            );
            assert!(near - d.abs() < 1e-6, "{d} vs {near} at {q:?} for {ctrl:?}");
            // Inside by the crossing rule.
            let mut inside = false;
            for i in 0..poly.len() {
                let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
                if (a[1] > q[1]) != (b[1] > q[1])
                    && q[0] < a[0] + (q[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0])
                {
                    inside = !inside;
                }
            }
            if near > 1e-4 {
                assert_eq!(d > 0.0, inside, "{q:?}");
            }
            assert!((g[0].hypot(g[1]) - 1.0).abs() < 1e-9);
        }
    }
}

#[test]
fn doo_sabin_limit_mesh_of_the_cube() {
    let ctrl: [[f64; 3]; 8] = std::array::from_fn(|s| std::array::from_fn(|a| corner_sign(s, a)));
    let mut vols = Vec::new();
    for level in 1..=6 {
        let m = limit_mesh(level);
        assert_eq!(m.points.len(), 6 * 4usize.pow(level as u32) + 2);
        assert_eq!(m.quads.len(), 6 * 4usize.pow(level as u32));
        let pos = m.positions(&ctrl);
        // The face centres of the control cube are limit points, and the
        // surface stays in the cube (convex hull property).
        for f in 0..6 {
            let mut c = [0.0; 3];
            c[f / 2] = if f % 2 == 0 { 1.0 } else { -1.0 };
            assert!(pos
                .iter()
                .any(|p| (0..3).all(|a| (p[a] - c[a]).abs() < 1e-12)));
        }
        assert!(pos.iter().all(|p| p.iter().all(|v| v.abs() <= 1.0 + 1e-12)));
        vols.push(m.volume(&pos));
    }
    // Outward orientation and convergence by a factor of 4 per level
    // (a quadratic scheme).
    assert!(vols.iter().all(|&v| v > 0.0));
    for w in vols[2..].windows(3) {
        let ratio = (w[1] - w[0]) / (w[2] - w[1]);
        assert!((ratio - 4.0).abs() < 0.1, "{ratio}");
    }
    let limit = vols[5] + (vols[5] - vols[4]) / 3.0;
    assert!((limit / 8.0 - 0.6291).abs() < 2e-4, "{}", limit / 8.0);
}

#[test]
fn eq9_derived_polyhedron_is_the_centroid_of_the_derived_points() {
    let c = [1.0, -2.0, 0.5];
    let h = [0.5, 0.25, 1.0];
    let mut r = Lcg(6);
    let t: [[f64; 3]; 8] = std::array::from_fn(|_| std::array::from_fn(|_| r.next()));
    let v = derived_polyhedron(c, h, KAPPA, &t);
    for s in 0..8 {
        let a: [f64; 3] = std::array::from_fn(|k| c[k] + corner_sign(s, k) * KAPPA * h[k]);
        // The three neighbours of A along its edges, and the derived
        // points on them.
        let mut sum = a;
        for k in 0..3 {
            let mut b = a;
            b[k] = 2.0 * c[k] - a[k];
            for j in 0..3 {
                sum[j] += (1.0 - t[s][k]) * a[j] + t[s][k] * b[j];
            }
        }
        for j in 0..3 {
            assert!((v[s][j] - sum[j] / 4.0).abs() < 1e-12);
            // Closed form: kappa (1 - t / 2) along each axis.
            let want = c[j] + corner_sign(s, j) * KAPPA * h[j] * (1.0 - t[s][j] / 2.0);
            assert!((v[s][j] - want).abs() < 1e-12);
        }
    }
    // t = 0 is the parent vertex, t = 1 halfway to the centre.
    let v0 = derived_polyhedron(c, h, KAPPA, &[[0.0; 3]; 8]);
    let v1 = derived_polyhedron(c, h, KAPPA, &[[1.0; 3]; 8]);
    assert!((v0[7][0] - (c[0] + KAPPA * h[0])).abs() < 1e-15);
    assert!((v1[7][0] - (c[0] + 0.5 * KAPPA * h[0])).abs() < 1e-15);
}

#[test]
fn tabulated_pore_is_the_limit_surface_within_tolerance() {
    // Exact limit points (face centroids after 7 steps) against the
    // tabulated gauge, for the regular and irregular shapes.
    let fine = limit_mesh(7);
    let mut r = Lcg(7);
    for sigma in [0.0, 0.15, 0.3] {
        let b: [[f64; 3]; 8] =
            std::array::from_fn(|_| std::array::from_fn(|_| 1.0 + sigma * (2.0 * r.next() - 1.0)));
        let table = tabulate_shape(&b).unwrap();
        let pos = fine.positions(&control(&b));
        let (mut worst, mut mean) = (0.0f64, 0.0);
        for p in &pos {
            let e = gauge(&table, *p).0 - 1.0;
            worst = worst.max(e.abs());
            mean += e;
        }
        mean /= pos.len() as f64;
        println!("sigma {sigma}: |g - 1| max {worst:.2e}, mean {mean:.2e}");
        // The stated tolerance: 1 % of the radius at worst, 0.2 % on average.
        assert!(worst < 0.01 && mean.abs() < 0.002, "{worst} {mean}");
    }
}

#[test]
fn porosity_extremes_against_the_paper() {
    let (face, edge) = porosity_extremes_3d();
    // The Doo-Sabin pore is fuller than a sphere: 62.7 % touching the
    // faces (sphere: pi / 6 = 52.36 %), 99.0 % touching the edges (sphere
    // of radius sqrt(2) / 2 side, clipped: 96.5 %).
    println!("Doo-Sabin pore: {face:.4} .. {edge:.4}; paper (spheres): 0.5236 .. 0.965");
    // The table's pore lies just inside the exact surface (0.6291).
    assert!((face - 0.6291).abs() < 0.003, "{face}");
    assert!(face > 0.6245 && face < 0.6291);
    assert!((edge - 0.990).abs() < 0.002, "{edge}");
    // The paper's sphere figures, by quasi-random sampling of [-1, 1]^3.
    let n = 400_000;
    let (mut inscribed, mut through_edges) = (0usize, 0usize);
    for i in 1..=n {
        let phi = 1.220_744_084_605_759_5_f64;
        let p: [f64; 3] =
            std::array::from_fn(|k| 2.0 * (0.5 + i as f64 / phi.powi(k as i32 + 1)).fract() - 1.0);
        let r2: f64 = p.iter().map(|v| v * v).sum();
        inscribed += (r2 < 1.0) as usize;
        through_edges += (r2 < 2.0) as usize;
    }
    assert!((inscribed as f64 / n as f64 - std::f64::consts::PI / 6.0).abs() < 2e-3);
    assert!((through_edges as f64 / n as f64 - 0.965).abs() < 2e-3);
}

#[test]
fn one_cell_porosity_matches_sampling_of_its_field() {
    // A single cell: the fraction of points where the field is negative is
    // the porosity the pore was solved for.
    let lo = [0.0; 3];
    let hi = [1.0; 3];
    let p = microfrep_core::Expr::xyz();
    let part = (0..3)
        .map(|a| (&p[a] - lo[a]).min(microfrep_core::Expr::constant(hi[a]) - &p[a]))
        .reduce(|a, b| a.min(b))
        .unwrap();
    for target in [0.5, 0.7, 0.95] {
        let b = Pores::build(
            &part,
            [lo, hi],
            Spec::Constant(1.0),
            Spec::Constant(target),
            9,
            &Options::default(),
        )
        .unwrap();
        assert_eq!(b.pores, 1);
        let PoreShape::Three {
            vertices,
            lambda,
            irregularity,
            t,
            ..
        } = &b.cells[0].shape
        else {
            panic!()
        };
        assert!(t.iter().flatten().all(|v| (0.0..=1.0).contains(v)));
        assert!(*irregularity <= 0.15 && *lambda > 0.7 && vertices.len() == 8);
        let n = 200_000;
        let mut pore = 0;
        for i in 1..=n {
            let phi = 1.220_744_084_605_759_5_f64;
            let q: [f64; 3] =
                std::array::from_fn(|k| (0.5 + i as f64 / phi.powi(k as i32 + 1)).fract());
            pore += (b.field.eval(q) < 0.0) as usize;
        }
        let measured = pore as f64 / n as f64;
        assert!((measured - target).abs() < 0.004, "{target}: {measured}");
    }
}

#[test]
fn walking_and_rasterising_tabulate_the_same_surface() {
    use microfrep_pores::raster::{tabulate, Walker};
    let m = limit_mesh(4);
    let tris: Vec<[u32; 3]> = m
        .quads
        .iter()
        .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .collect();
    let reference = m.positions(&control(&[[1.0; 3]; 8]));
    let walker = Walker::new(&reference, &tris, 16);
    let mut r = Lcg(8);
    for _ in 0..10 {
        let b: [[f64; 3]; 8] =
            std::array::from_fn(|_| std::array::from_fn(|_| 1.0 + 0.3 * (2.0 * r.next() - 1.0)));
        let pos = m.positions(&control(&b));
        let walked = walker.tabulate(&pos).unwrap();
        let (raster, report) = tabulate(&pos, &tris, 16).unwrap();
        assert_eq!(report.conflicts, 0);
        for (a, b) in walked.values().iter().zip(raster.values()) {
            assert!((a - b).abs() <= 1e-6 * b, "{a} {b}");
        }
    }
}
