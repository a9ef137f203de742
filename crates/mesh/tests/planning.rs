//! Bounds from interval analysis, memory prediction and input errors.

use microfrep_core::Expr;
use microfrep_core::Shape;
use microfrep_mesh::{memory, MeshError, MeshOptions, Plan};
use microfrep_shapes as prims;
use microfrep_structures::examples::{shell_lattice, toriball};

fn ball() -> Expr {
    prims::sphere(&Expr::xyz(), &prims::v3([0.5, 0.0, -0.25]), 1.0)
}

#[test]
fn bounds_of_a_ball_enclose_it_tightly() {
    let b = Shape::from(&ball()).bounds().unwrap().corners();
    let c = [0.5, 0.0, -0.25];
    for a in 0..3 {
        assert!(b[0][a] <= c[a] - 1.0 && b[0][a] > c[a] - 1.1, "{b:?}");
        assert!(b[1][a] >= c[a] + 1.0 && b[1][a] < c[a] + 1.1, "{b:?}");
    }
}

#[test]
fn lattices_cut_by_a_block_or_a_shell_get_that_box() {
    // Plain interval arithmetic on the whole R-function gives boxes of about
    // [-1.6, 1.6] x [-1.6, 1.6] x [-1.9, 1.9] and [-7, 7]^3 here; the
    // budgeted subdivision proves boxes within 0.5 % of the cutting block.
    for (name, e) in [("toriball", toriball()), ("shell_lattice", shell_lattice())] {
        let b = Shape::from(&e).bounds().unwrap().corners();
        for a in 0..3 {
            assert!(b[0][a] <= -1.0 && b[0][a] > -1.005, "{name}: {b:?}");
            assert!(b[1][a] >= 1.0 && b[1][a] < 1.005, "{name}: {b:?}");
        }
    }
}

#[test]
fn a_slab_bounds_only_its_own_axis() {
    let p = Expr::xyz();
    let slab = (&p[0] - 0.5) * (2.0 - &p[0]);
    let e = Shape::from(&slab).bounds().unwrap_err();
    assert!(e.to_string().contains("--bounds"), "{e}");
    let ball = prims::sphere(&p, &prims::v3([0.0; 3]), 1.0);
    let cut = microfrep_core::frep::intersection(&ball, &slab, 0.0);
    let b = Shape::from(&cut).bounds().unwrap().corners();
    assert!(
        b[0][0] <= 0.5 && b[0][0] > 0.49 && b[1][0] >= 1.0 && b[1][0] < 1.01,
        "{b:?}"
    );
    // The whole model then shows that y and z stay within the disc x = 0.5
    // cuts from the ball (radius 0.866).
    assert!(b[0][1] <= -0.866 && b[0][1] > -1.0, "{b:?}");
}

#[test]
fn unbounded_models_ask_for_bounds() {
    let half = prims::half_space(&Expr::xyz(), [0.0; 3], [0.0, 0.0, 1.0]);
    let e = Shape::from(&half).bounds().unwrap_err();
    assert!(e.to_string().contains("--bounds"), "{e}");
    let e = Shape::from(&half.min(&half)).bounds().unwrap_err();
    assert!(e.to_string().contains("--bounds"), "{e}");
    // A lattice alone is periodic over all space.
    let slabs = microfrep_structures::lattice::Slabs::uniform(6.0, 0.3);
    let lattice = microfrep_structures::lattice::rod_lattice(&Expr::xyz(), &slabs, 1.0);
    let e = Shape::from(&lattice.min(&half)).bounds().unwrap_err();
    assert!(e.to_string().contains("--bounds"), "{e}");
}

#[test]
fn predicted_size_is_close_to_the_real_one() {
    let opts = MeshOptions::new([[-0.6, -1.1, -1.35], [1.6, 1.1, 0.85]], 96);
    let plan = Plan::new(&Shape::from(&ball()), &opts).unwrap();
    let est = memory::estimate(&plan);
    let m = plan.run(&|_| {}).unwrap();
    let ratio = est.triangles / m.triangles.len() as f64;
    assert!((0.9..1.5).contains(&ratio), "{ratio}");
    assert!(est.bytes > 60.0 * m.triangles.len() as f64);
}

#[test]
fn bad_options_are_errors() {
    let bad = |bounds: [[f64; 3]; 2], n: usize| {
        matches!(
            Plan::new(&Shape::from(&ball()), &MeshOptions::new(bounds, n)),
            Err(MeshError::Input(_))
        )
    };
    assert!(bad([[-1.0; 3], [1.0; 3]], 0));
    assert!(bad([[-1.0; 3], [1.0, 1.0, -1.0]], 16));
    assert!(bad([[f64::NAN; 3], [1.0; 3]], 16));
    assert!(bad([[-1.0; 3], [1.0; 3]], 1 << 20));
}

#[test]
fn a_model_missing_the_box_gives_an_empty_mesh() {
    let opts = MeshOptions::new([[3.0; 3], [4.0; 3]], 16);
    let m = Plan::new(&Shape::from(&ball()), &opts)
        .unwrap()
        .run(&|_| {})
        .unwrap();
    assert!(m.triangles.is_empty() && m.vertices.is_empty());
}

#[test]
fn features_thinner_than_a_cell_vanish_and_are_reported() {
    // A plate 0.002 thick between two node layers of a 0.1 grid.
    let z = Expr::z();
    let plate = 0.001 - (&z - 0.05).abs();
    let opts = MeshOptions::new([[-1.0; 3], [1.0; 3]], 20);
    let plan = Plan::new(&Shape::from(&plate), &opts).unwrap();
    let m = plan.run(&|_| {}).unwrap();
    assert!(m.triangles.is_empty());
    assert!(plan.thin_cells() > 0);
    // A ball resolved by the grid: nothing to report.
    let plan = Plan::new(
        &Shape::from(&ball()),
        &MeshOptions::new([[-1.0; 3], [2.0; 3]], 32),
    )
    .unwrap();
    assert!(!plan.run(&|_| {}).unwrap().triangles.is_empty());
    assert_eq!(plan.thin_cells(), 0);
}
