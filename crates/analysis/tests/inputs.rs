//! Bad inputs give errors, not panics or runaway jobs.

use microfrep_analysis::grid::MAX_RESOLUTION;
use microfrep_analysis::{analyze, AnalysisError, AnalyzeOptions, Grid};
use microfrep_core::{Expr, Shape};
use microfrep_shapes::{sphere, v3};

const B: [[f64; 3]; 2] = [[-1.0; 3], [1.0; 3]];

#[test]
fn resolution_must_be_positive_and_bounded() {
    assert!(matches!(Grid::new(B, 0), Err(AnalysisError::Input(_))));
    assert!(matches!(
        Grid::new(B, MAX_RESOLUTION + 1),
        Err(AnalysisError::Input(_))
    ));
    assert!(Grid::new(B, 1).is_ok());
}

#[test]
fn voxel_size_must_be_positive_and_not_absurd() {
    for v in [0.0, -0.1, f64::NAN, f64::INFINITY, 1e-9] {
        assert!(Grid::with_voxel(B, v).is_err(), "voxel {v}");
    }
    let g = Grid::with_voxel(B, 0.1).unwrap();
    assert_eq!(g.dims, [20; 3]);
}

#[test]
fn bounds_must_be_finite_and_ordered() {
    let bad = [
        [[0.0; 3], [0.0; 3]],
        [[1.0; 3], [-1.0; 3]],
        [[f64::NEG_INFINITY, 0.0, 0.0], [1.0; 3]],
        [[f64::NAN, 0.0, 0.0], [1.0; 3]],
    ];
    for b in bad {
        assert!(Grid::new(b, 16).is_err(), "{b:?}");
    }
}

#[test]
fn grid_counts_are_even_and_tile_the_box() {
    let g = Grid::new([[0.0, 0.0, 0.0], [1.0, 0.3, 0.55]], 33).unwrap();
    assert!(g.dims.iter().all(|d| d % 2 == 0), "{:?}", g.dims);
    for a in 0..3 {
        assert!((g.step[a] * g.dims[a] as f64 - (g.hi[a] - g.lo[a])).abs() < 1e-12);
    }
}

#[test]
fn jobs_over_the_memory_limit_are_refused() {
    let p = Expr::xyz();
    let t = Shape::from(&sphere(&p, &v3([0.0; 3]), 1.0));
    let opts = AnalyzeOptions {
        memory_limit: 1 << 20,
        ..AnalyzeOptions::default()
    };
    let g = Grid::new(B, 4096).unwrap();
    match analyze(&t, None, g, &opts, &|_, _, _| {}) {
        Err(AnalysisError::Memory(m)) => assert!(m.contains("lower the resolution"), "{m}"),
        other => panic!("expected a memory error, got {other:?}"),
    }
}
