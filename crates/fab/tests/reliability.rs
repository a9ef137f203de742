//! Slicing and voxels on input a user can type: steps larger than the box
//! and grids f32 cannot resolve refused, models f32 cannot resolve refused,
//! empty stacks and voxel files written nowhere with the reason, errors
//! naming the output. Random parameters (property tests) never panic.

use microfrep_core::{Expr, Shape};
use microfrep_fab::voxels::{write_voxels, VoxelGrid};
use microfrep_fab::{write_stack, FabError, Format, SliceGrid};
use microfrep_shapes as prims;
use proptest::prelude::*;
use std::path::{Path, PathBuf};

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("mf-fab-rel-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn entries(d: &Path) -> Vec<String> {
    std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect()
}

fn ball(c: [f64; 3], r: f64) -> Shape {
    Shape::from(&prims::sphere(&Expr::xyz(), &prims::v3(c), r))
}

#[test]
fn steps_larger_than_the_box_and_far_boxes_are_refused() {
    let e = SliceGrid::new([-1.0; 3], [1.0; 3], 5.0, 0.1).unwrap_err();
    assert!(e.to_string().contains("exceeds the box's height"), "{e}");
    let e = SliceGrid::new([-1.0, -1.0, 0.0], [1.0, -0.9, 1.0], 0.1, 0.2).unwrap_err();
    assert!(e.to_string().contains("depth"), "{e}");
    let e = VoxelGrid::new([0.0; 3], [1.0, 1.0, 0.2], 0.5).unwrap_err();
    assert!(e.to_string().contains("exceeds the box's z side"), "{e}");
    let far = ([1e6 - 1.0, -1.0, -1.0], [1e6 + 1.0, 1.0, 1.0]);
    let e = SliceGrid::new(far.0, far.1, 0.05, 0.05).unwrap_err();
    assert!(e.to_string().contains("nearer the origin"), "{e}");
    assert!(VoxelGrid::new(far.0, far.1, 0.05).is_err());
    assert!(SliceGrid::new([-1e300; 3], [1e300; 3], 1e299, 1e299).is_err());
    assert!(VoxelGrid::new([-1e-50; 3], [1e-50; 3], 1e-51).is_err());
}

#[test]
fn layers_in_flight_fit_the_memory() {
    let g = SliceGrid::new([0.0; 3], [1.0; 3], 0.5, 1.0 / 8000.0).unwrap();
    // 64 M pixels: about 640 MB a layer.
    assert_eq!(
        microfrep_fab::stack::layers_in_flight(&g, Some(1.7e9)).unwrap(),
        2
    );
    let e = microfrep_fab::stack::layers_in_flight(&g, Some(5e8)).unwrap_err();
    assert!(
        matches!(e, FabError::TooLarge(_)) && e.to_string().contains("coarser"),
        "{e}"
    );
    let n = microfrep_fab::stack::layers_in_flight(&g, None).unwrap();
    assert_eq!(n, 2 * rayon::current_num_threads());
}

#[test]
fn empty_stacks_and_voxel_files_are_errors_and_write_nothing() {
    let d = dir("empty");
    // A slab between the layer heights, and a ball outside the box.
    let slab = Shape::from(&(0.002 - (Expr::z() - 0.013).abs()));
    let grid = SliceGrid::new([-1.0; 3], [1.0; 3], 0.1, 0.05).unwrap();
    for f in [Format::Png { aa: false }, Format::Svg] {
        let e = write_stack(&slab, &grid, &f, &d.join("s"), &|| {}).unwrap_err();
        assert!(matches!(e, FabError::Empty(_)), "{e}");
        assert!(e.to_string().contains("no pixel"), "{e}");
    }
    let e = write_stack(&slab, &grid, &Format::Cli, &d.join("s.cli"), &|| {}).unwrap_err();
    assert!(e.to_string().contains("s.cli: no pixel"), "{e}");
    let vg = VoxelGrid::new([-1.0; 3], [1.0; 3], 0.25).unwrap();
    for (field, out) in [(false, "v.raw"), (true, "v.nrrd")] {
        let e = write_voxels(&ball([3.0; 3], 0.5), &vg, field, &d.join(out)).unwrap_err();
        assert!(matches!(e, FabError::Empty(_)), "{e}");
        assert!(e.to_string().contains(out), "{e}");
    }
    assert!(entries(&d).is_empty(), "{:?}", entries(&d));
    // A thin slab the layer does hit is written.
    let g = SliceGrid::new([-1.0, -1.0, 0.0], [1.0, 1.0, 0.026], 0.026, 0.05).unwrap();
    write_stack(&slab, &g, &Format::Png { aa: false }, &d.join("ok"), &|| {}).unwrap();
    assert!(d.join("ok/manifest.json").exists());
}

#[test]
fn models_f32_cannot_resolve_are_refused() {
    let d = dir("tiny");
    let r = 1e-25;
    let x = Expr::xyz();
    let tiny = Shape::from(&(r * r - &x[0] * &x[0] - &x[1] * &x[1] - &x[2] * &x[2]));
    let (lo, hi) = ([-2.0 * r; 3], [2.0 * r; 3]);
    let g = SliceGrid::new(lo, hi, 0.5 * r, 0.5 * r).unwrap();
    let e = write_stack(&tiny, &g, &Format::Svg, &d.join("s"), &|| {}).unwrap_err();
    assert!(
        matches!(e, FabError::Precision(_)) && e.to_string().contains("underflow"),
        "{e}"
    );
    let vg = VoxelGrid::new(lo, hi, 0.5 * r).unwrap();
    let e = write_voxels(&tiny, &vg, false, &d.join("v.raw")).unwrap_err();
    assert!(e.to_string().contains("underflow"), "{e}");
    assert!(entries(&d).is_empty());
}

fn config(cases: u32) -> ProptestConfig {
    ProptestConfig {
        cases,
        failure_persistence: None,
        rng_seed: proptest::test_runner::RngSeed::Fixed(7),
        ..ProptestConfig::default()
    }
}

proptest! {
    #![proptest_config(config(64))]

    /// Random boxes and steps: a grid whose samples lie in the box (layer
    /// middles and pixel or voxel centres) or a clear error.
    #[test]
    fn random_parameters_give_grids_in_the_box_or_errors(
        lo in prop::array::uniform3(prop_oneof![
            Just(-1e300), Just(1e6), Just(f64::NAN), -2.0f64..1.0
        ]),
        ext in prop::array::uniform3(prop_oneof![Just(0.0), Just(1e-45), 0.01f64..3.0]),
        layer in prop_oneof![Just(0.0), Just(-1.0), Just(1e-12), Just(f64::INFINITY), 1e-3f64..4.0],
        pixel in prop_oneof![Just(0.0), Just(1e-12), Just(f64::NAN), 1e-3f64..4.0],
    ) {
        let hi: [f64; 3] = std::array::from_fn(|a| lo[a] + ext[a]);
        if let Ok(g) = SliceGrid::new(lo, hi, layer, pixel) {
            prop_assert!(g.z(0) <= hi[2] && g.x(0) <= hi[0] && g.y(0) <= hi[1]);
            prop_assert!(g.nx >= 1 && g.ny >= 1 && g.layers >= 1);
        }
        if let Ok(v) = VoxelGrid::new(lo, hi, pixel) {
            for (o, h) in v.origin.iter().zip(hi) {
                prop_assert!(*o <= h, "{:?}", v);
            }
        }
    }
}
