//! Each Pasko et al. 2009 figure model in `examples/` loads, evaluates and
//! shows the property its figure illustrates.
mod common;
use common::*;
use microfrep_core::Expr;
use microfrep_mesh::check::check;
use microfrep_mesh::{MeshOptions, Plan};
use microfrep_structures::lattice::{rod_lattice, rod_lattice_volume_fraction, Slabs};
use std::f64::consts::PI;

const UNIT: ([f64; 3], [f64; 3]) = ([0.0; 3], [1.0; 3]);

#[test]
fn fig2a_lattice_has_the_closed_form_volume_fraction() {
    let m = example("pasko_fig2a_lattice.hf", None);
    let p = Probe::new(&m);
    let vf = fraction(&p, &points(UNIT.0, UNIT.1, 60_000));
    let want = rod_lattice_volume_fraction(0.5);
    assert!((want - 7.0 / 27.0).abs() < 1e-12);
    assert!((vf - want).abs() / want < 0.005, "{vf} vs {want}");
    // Same function as the Rust API's lattice.
    let r = Probe::of(&rod_lattice(
        &Expr::xyz(),
        &Slabs::uniform(2.0 * PI, 0.5),
        1.0,
    ));
    for q in points([-2.0; 3], [2.0; 3], 200) {
        assert!((p.at(q) - r.at(q)).abs() < 1e-12);
    }
}

#[test]
fn fig2b_double_frequency_halves_the_period() {
    let p = Probe::new(&example("pasko_fig2b_double_frequency.hf", None));
    for q in points([-1.0; 3], [1.0; 3], 200) {
        for axis in 0..3 {
            let mut s = q;
            s[axis] += 0.5;
            assert!((p.at(q) - p.at(s)).abs() < 1e-9);
        }
    }
    // Not periodic with a quarter of the period of Fig. 2a.
    assert!((p.at([0.1, 0.12, 0.0]) - p.at([0.35, 0.12, 0.0])).abs() > 0.1);
    let vf = fraction(&p, &points([0.0; 3], [0.5; 3], 60_000));
    assert!((vf - 7.0 / 27.0).abs() / (7.0 / 27.0) < 0.005, "{vf}");
}

#[test]
fn fig2c_rods_thicken_along_x() {
    let p = Probe::new(&example("pasko_fig2c_variable_thickness.hf", None));
    let mut last = 0.0;
    for k in 0..4 {
        let k = k as f64;
        let vf = fraction(&p, &points([k, 0.0, 0.0], [k + 1.0, 1.0, 1.0], 20_000));
        // Close to the constant-threshold fraction at the cell's centre.
        let want = rod_lattice_volume_fraction(0.6 - 0.3 * (k + 0.5));
        assert!((vf - want).abs() < 0.03, "cell {k}: {vf} vs {want}");
        assert!(vf > last + 0.05, "cell {k}: {vf} after {last}");
        last = vf;
    }
}

#[test]
fn fig2d_blending_adds_material_and_keeps_the_period() {
    let p = Probe::new(&example("pasko_fig2d_blended_rods.hf", None));
    let plain = Probe::of(&rod_lattice(
        &Expr::xyz(),
        &Slabs::uniform(2.0 * PI, 0.5),
        0.0,
    ));
    let pts = points(UNIT.0, UNIT.1, 20_000);
    let (vb, vp) = (fraction(&p, &pts), fraction(&plain, &pts));
    assert!((vp - 7.0 / 27.0).abs() < 0.005, "{vp}");
    assert!(vb > vp + 0.02, "blended {vb}, plain {vp}");
    for q in points([-1.0; 3], [1.0; 3], 100) {
        assert!((p.at(q) - p.at(add(q, [1.0, -1.0, 1.0]))).abs() < 1e-9);
    }
}

/// Volume of the sphere-with-lattice of Fig. 3a: a shell from radius 0.9 to
/// 1 plus 7/27 of the inner ball.
fn fig3a_volume() -> f64 {
    let ball = |r: f64| 4.0 / 3.0 * PI * r * r * r;
    ball(1.0) - ball(0.9) + 7.0 / 27.0 * ball(0.9)
}

#[test]
fn fig3a_sphere_shell_with_lattice() {
    let m = example("pasko_fig3a_sphere_shell_lattice.hf", None);
    let p = Probe::new(&m);
    // Shell from radius 0.9 to 1.
    for d in points([-1.0; 3], [1.0; 3], 50) {
        let n = norm(d);
        let at = |r: f64| d.map(|c| c / n * r);
        assert!(p.inside(at(0.95)) && !p.inside(at(1.05)));
    }
    // A z rod passes through x = y = 1/8 (slabs positive for x in [1/24, 5/24]).
    assert!(p.inside([0.125, 0.125, 0.3]) && p.inside([0.125, 0.125, -0.55]));
    assert!(!p.inside([0.35, 0.35, 0.35]) && !p.inside([0.0, 0.0, 0.0]));
    let b = [-1.1, 1.1];
    let pts = points([b[0]; 3], [b[1]; 3], 200_000);
    let vol = fraction(&p, &pts) * 2.2f64.powi(3);
    assert!(
        (vol - fig3a_volume()).abs() / fig3a_volume() < 0.015,
        "{vol}"
    );
    // Watertight through the mesher, with the same volume.
    let mesh = Plan::new(&m.shape(), &MeshOptions::new([[b[0]; 3], [b[1]; 3]], 48))
        .unwrap()
        .run(&|_| {})
        .unwrap();
    let r = check(&mesh);
    assert!(r.is_closed_manifold(), "{r:?}");
    assert!(
        (r.volume - fig3a_volume()).abs() / fig3a_volume() < 0.05,
        "{r:?}"
    );
}

#[test]
fn fig3b_blending_only_adds_material() {
    let p = Probe::new(&example("pasko_fig3b_blended_shell_lattice.hf", None));
    let plain = Probe::new(&load_src(
        "my_model(x[3], a[1]) { array c[3]; c = [0, 0, 0]; f = hfSphere(x, c, 1);
         g = mfLattice(x, 12.566370614359172, 0, 0.6, 0);
         my_model = mfShellInfill(f, 0.19, g, 0); }",
        "plain",
        None,
    ));
    let pts = points([-1.1; 3], [1.1; 3], 20_000);
    let (vb, vp) = (p.values(&pts), plain.values(&pts));
    assert!(vb.iter().zip(&vp).all(|(b, q)| b >= q));
    let inside = |v: &[f64]| v.iter().filter(|&&f| f >= 0.0).count();
    assert!(inside(&vb) as f64 > 1.05 * inside(&vp) as f64);
    // The fillets stay close to the sphere.
    for d in points([-1.0; 3], [1.0; 3], 100) {
        let n = norm(d);
        assert!(!p.inside(d.map(|c| c / n * 1.3)));
    }
}

#[test]
fn fig3c_lattice_is_twice_as_dense_as_fig3b() {
    let b = Probe::new(&example("pasko_fig3b_blended_shell_lattice.hf", None));
    let c = Probe::new(&example("pasko_fig3c_dense_lattice.hf", None));
    // Along a line through the lattice, inside the shell.
    let line = |t: f64| [-0.6 + 1.2 * t, 0.11, 0.37];
    let (nb, nc) = (crossings(&b, 2000, line), crossings(&c, 2000, line));
    assert!(nb >= 4 && nc as f64 >= 1.7 * nb as f64, "{nb} {nc}");
}

#[test]
fn fig3d_lattice_is_denser_near_the_surface() {
    let p = Probe::new(&example("pasko_fig3d_graded_lattice.hf", None));
    let pts = points([-1.0; 3], [1.0; 3], 100_000);
    let band = |lo: f64, hi: f64| -> Vec<[f64; 3]> {
        pts.iter()
            .copied()
            .filter(|q| (lo..hi).contains(&norm(*q)))
            .collect()
    };
    let outer = fraction(&p, &band(0.7, 0.88));
    let core = fraction(&p, &band(0.0, 0.5));
    assert!(outer > core + 0.2, "outer {outer}, core {core}");
}

#[test]
fn fig4_shape_truncation_and_variable_frequency() {
    let shape = Probe::new(&example("pasko_fig4_shape_with_lattice.hf", Some("shape")));
    let trunc = Probe::new(&example(
        "pasko_fig4_shape_with_lattice.hf",
        Some("truncated"),
    ));
    let m = Probe::new(&example("pasko_fig4_shape_with_lattice.hf", None));
    assert!(shape.inside([1.5, 0.0, 0.0]) && shape.inside([0.6, 0.0, 1.2]));
    assert!(!shape.inside([0.0, 0.0, 0.0]) && !shape.inside([1.5, 0.0, 0.7]));
    let pts = points([-2.2, -1.2, -0.7], [2.2, 1.2, 1.7], 20_000);
    let (vs, vt, vm) = (shape.values(&pts), trunc.values(&pts), m.values(&pts));
    for i in 0..pts.len() {
        // (b) is inside (a); (c) is inside (a) and holds (b).
        assert!(vt[i] < 0.0 || vs[i] >= 0.0);
        assert!(vm[i] < 0.0 || vs[i] >= 0.0);
        assert!(vt[i] < 0.0 || vm[i] >= 0.0);
    }
    // On the line (x, 0.1, -0.1) the truncated lattice is inside exactly
    // where sin(q x) >= 0.5, q = 10 + 1.5 x: more cells on the right.
    let left = crossings(&trunc, 4000, |t| [-1.9 + 0.8 * t, 0.1, -0.1]);
    let right = crossings(&trunc, 4000, |t| [1.1 + 0.8 * t, 0.1, -0.1]);
    assert!(right >= left + 2, "left {left}, right {right}");
}

/// Share of the period box where the mapped point `sin(10 x_i)` lies in the
/// pore ball of radius `r`, by an independent Monte Carlo estimate.
fn pore_share(r: f64) -> f64 {
    let pts = points([0.0; 3], [1.0; 3], 200_000);
    let hit = pts
        .iter()
        .filter(|u| {
            let s: f64 = u.iter().map(|c| (2.0 * PI * c).sin().powi(2)).sum();
            s < r * r
        })
        .count();
    hit as f64 / pts.len() as f64
}

fn ball_points(r: f64, count: usize) -> Vec<[f64; 3]> {
    points([-r; 3], [r; 3], count)
        .into_iter()
        .filter(|q| norm(*q) < r)
        .collect()
}

#[test]
fn fig5a_pores_are_periodic_with_the_expected_porosity() {
    let p = Probe::new(&example("pasko_fig5a_porous.hf", None));
    assert!(!p.inside([0.0; 3]), "a pore at the origin");
    assert!(p.inside([0.157, 0.157, 0.157]), "material between pores");
    let step = PI / 10.0;
    for q in ball_points(0.6, 400) {
        assert_eq!(p.inside(q), p.inside(add(q, [step, 0.0, -step])));
    }
    let porosity = 1.0 - fraction(&p, &ball_points(0.8, 60_000));
    let want = pore_share(0.5);
    assert!((porosity - want).abs() < 0.01, "{porosity} vs {want}");
}

#[test]
fn fig5b_pores_shrink_with_depth() {
    let p = Probe::new(&example("pasko_fig5b_graded_pores.hf", None));
    let pts = ball_points(1.0, 80_000);
    let band = |lo: f64, hi: f64| -> Vec<[f64; 3]> {
        pts.iter()
            .copied()
            .filter(|q| (lo..hi).contains(&norm(*q)))
            .collect()
    };
    let outer = 1.0 - fraction(&p, &band(0.85, 0.98));
    let core = 1.0 - fraction(&p, &band(0.0, 0.5));
    // The core has the constant radius 0.4.
    assert!((core - pore_share(0.4)).abs() < 0.01, "{core}");
    assert!(
        outer > 3.0 * core && outer > core + 0.05,
        "outer {outer}, core {core}"
    );
}

#[test]
fn fig5c_noise_breaks_the_period_but_keeps_a_porous_solid() {
    let p = Probe::new(&example("pasko_fig5c_noisy_pores.hf", None));
    let step = PI / 10.0;
    let pts = ball_points(0.6, 2000);
    let differ = pts
        .iter()
        .filter(|&&q| p.inside(q) != p.inside(add(q, [step, 0.0, -step])))
        .count();
    assert!(differ > pts.len() / 20, "{differ} of {}", pts.len());
    let porosity = 1.0 - fraction(&p, &ball_points(0.8, 40_000));
    assert!((0.05..0.6).contains(&porosity), "{porosity}");
    // Deterministic.
    let again = Probe::new(&example("pasko_fig5c_noisy_pores.hf", None));
    assert_eq!(p.values(&pts[..50]), again.values(&pts[..50]));
}
