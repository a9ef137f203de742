//! The marching-cubes cell method: the same guarantees as the default, and
//! convergence on models with known answers.

use microfrep_core::Expr;
use microfrep_core::Shape;
use microfrep_mesh::check::{check, CheckReport};
use microfrep_mesh::{CellMethod, MeshOptions, Plan};
use microfrep_shapes as prims;
use microfrep_structures::examples::toriball;
use microfrep_structures::lattice::{
    rod_lattice, rod_lattice_area_in_unit_cube, rod_lattice_volume_fraction, Slabs,
};
use std::f64::consts::PI;

fn opts(bounds: [[f64; 3]; 2], n: usize) -> MeshOptions {
    let mut o = MeshOptions::new(bounds, n);
    o.cells = CellMethod::Cubes;
    o
}

fn mesh(e: &Expr, bounds: [[f64; 3]; 2], n: usize) -> CheckReport {
    let m = Plan::new(&Shape::from(e), &opts(bounds, n))
        .unwrap()
        .run(&|_| {})
        .unwrap();
    let r = check(&m);
    assert!(r.is_closed_manifold(), "n = {n}: {r:?}");
    r
}

/// Relative volume and area errors at each resolution, checked against
/// `limits`.
fn converges(e: &Expr, b: [[f64; 3]; 2], ns: &[usize], exact: (f64, f64), limits: &[(f64, f64)]) {
    let errs: Vec<(f64, f64)> = ns
        .iter()
        .map(|&n| {
            let r = mesh(e, b, n);
            let rel = |v: f64, x: f64| (v - x).abs() / x;
            (rel(r.volume, exact.0), rel(r.area, exact.1))
        })
        .collect();
    println!("{errs:?}");
    for (e, l) in errs.iter().zip(limits) {
        assert!(e.0 < l.0 && e.1 < l.1, "{errs:?}");
    }
}

#[test]
fn sphere_is_a_sphere_and_converges() {
    let sphere = prims::sphere(&Expr::xyz(), &prims::v3([0.1, -0.05, 0.02]), 1.0);
    let b = [[-1.2; 3], [1.2; 3]];
    assert_eq!(mesh(&sphere, b, 24).euler, 2);
    let exact = (4.0 * PI / 3.0, 4.0 * PI);
    let limits = [(1e-3, 3e-3), (2.5e-4, 8e-4), (6e-5, 2e-4)];
    converges(&sphere, b, &[16, 32, 64], exact, &limits);
}

#[test]
fn torus_has_genus_one_and_converges() {
    let torus = prims::torus(&Expr::xyz(), &prims::v3([0.0; 3]), 2, 0.7, 0.25);
    let b = [[-1.0, -1.0, -0.3], [1.0, 1.0, 0.3]];
    assert_eq!(mesh(&torus, b, 32).euler, 0);
    let (big_r, r) = (0.7, 0.25);
    let exact = (2.0 * PI * PI * big_r * r * r, 4.0 * PI * PI * big_r * r);
    let limits = [(1.5e-3, 8e-3), (4e-4, 2e-3), (1e-4, 6e-4)];
    converges(&torus, b, &[24, 48, 96], exact, &limits);
}

#[test]
fn rod_lattice_converges_with_chamfered_creases() {
    // Marching cubes cuts the lattice's sharp creases by a chamfer: the
    // area converges about as h^0.7 (3.3 %, 1.1 %, 0.7 % measured).
    let l = 0.3;
    let lattice = rod_lattice(&Expr::xyz(), &Slabs::uniform(2.0 * PI, l), 1.0);
    let b = [[0.0; 3], [1.0; 3]];
    let exact = (
        rod_lattice_volume_fraction(l),
        rod_lattice_area_in_unit_cube(l),
    );
    let limits = [(1.5e-3, 4.5e-2), (5e-4, 1.5e-2), (1.5e-4, 9e-3)];
    converges(&lattice, b, &[20, 40, 80], exact, &limits);
}

#[test]
fn toriball_at_128_is_watertight_with_the_monte_carlo_volume() {
    let r = mesh(&toriball(), [[-1.0; 3], [1.0; 3]], 128);
    println!("toriball {r:?}");
    assert!((r.volume - 1.6378).abs() / 1.6378 < 0.01, "{r:?}");
}

#[test]
fn output_is_deterministic_and_independent_of_brick_size() {
    // With simplification (the default) the output is deterministic and
    // watertight for one brick size.
    let simplified = |brick: usize| {
        let mut o = MeshOptions::new([[-1.0; 3], [1.0; 3]], 40);
        o.brick = brick;
        Plan::new(&Shape::from(&toriball()), &o)
            .unwrap()
            .run(&|_| {})
            .unwrap()
    };
    let s8 = simplified(8);
    assert_eq!(s8, simplified(8));
    assert!(check(&s8).is_closed_manifold());
    let run = |brick: usize| {
        let mut o = opts([[-1.0; 3], [1.0; 3]], 40);
        o.brick = brick;
        // Per-brick tape simplification keeps signs, not values, so the
        // surface depends on the brick layout unless it is off.
        o.simplify = false;
        Plan::new(&Shape::from(&toriball()), &o)
            .unwrap()
            .run(&|_| {})
            .unwrap()
    };
    let a = run(8);
    assert_eq!(a, run(8));
    let (ra, rc) = (check(&a), check(&run(16)));
    assert!(ra.is_closed_manifold() && rc.is_closed_manifold());
    assert_eq!((ra.triangles, ra.vertices), (rc.triangles, rc.vertices));
    assert!((ra.volume - rc.volume).abs() < 1e-9);
}

#[test]
fn ambiguous_cells_everywhere_still_give_a_closed_manifold() {
    // A product of sines sampled at about 2.5 cells per half period: saddles
    // everywhere, so faces with inside corners on a diagonal are common.
    let p = Expr::xyz();
    let k = 9.0;
    let f = (&p[0] * k).sin() * (&p[1] * k).sin() * (&p[2] * k).sin() - 0.05;
    for n in [13, 17, 23] {
        let r = mesh(&f, [[-1.0; 3], [1.0; 3]], n);
        assert!(r.triangles > 1000 && r.volume > 0.0, "{r:?}");
    }
}

#[test]
fn predicted_size_is_close_to_the_real_one() {
    let ball = prims::sphere(&Expr::xyz(), &prims::v3([0.5, 0.0, -0.25]), 1.0);
    let plan = Plan::new(
        &Shape::from(&ball),
        &opts([[-0.6, -1.1, -1.35], [1.6, 1.1, 0.85]], 96),
    )
    .unwrap();
    let est = microfrep_mesh::memory::estimate(&plan);
    let m = plan.run(&|_| {}).unwrap();
    let ratio = est.triangles / m.triangles.len() as f64;
    assert!((0.9..1.5).contains(&ratio), "{ratio}");
    let ratio = est.vertices / m.vertices.len() as f64;
    assert!((0.9..1.5).contains(&ratio), "{ratio}");
}

#[test]
fn output_does_not_depend_on_the_thread_count() {
    let run = |threads: usize| {
        let mut o = opts([[-1.0; 3], [1.0; 3]], 40);
        o.brick = 8;
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                Plan::new(&Shape::from(&toriball()), &o)
                    .unwrap()
                    .run(&|_| {})
                    .unwrap()
            })
    };
    assert_eq!(run(1), run(3));
}
