//! The culled, per-channel layer source of a shape against the
//! straightforward one: the shape's whole output tape evaluated at every
//! voxel centre (the same mask, the same fraction bits at inside voxels).

use microfrep_core::{frep, BatchEval, Expr, Shape};
use microfrep_graded::stack::{ShapeSource, StackGrid};

/// A ball with a hole along z and three graded channels: a smooth field
/// above z = 0.2 and 0 below (a branch intervals decide), a radial field,
/// and a square root NaN where x < -0.5.
fn graded_ball() -> Shape {
    let [x, y, z] = Expr::xyz();
    let r2 = x.square() + y.square() + z.square();
    let value = frep::intersection(&(1.0 - &r2), &(x.square() + y.square() - 0.04), 0.0);
    let smooth = 0.5 + 0.4 * (3.0 * &x).sin() * (2.0 * &y).cos();
    Shape::new(value)
        .with_attribute("s1", Expr::select(z.ge(0.2), smooth, Expr::constant(0.0)))
        .with_attribute("s2", 1.6 - 2.0 * &r2)
        .with_attribute("s3", (&x + 0.5).sqrt())
}

#[test]
fn shape_source_equals_full_evaluation() {
    let shape = graded_ball();
    let grid = StackGrid::new([-1.05; 3], [1.05; 3], [0.009, 0.013], 0.09).unwrap();
    let (nx, ny) = (grid.nx, grid.ny);
    let plane = nx * ny;
    let n = 4;
    let src = ShapeSource::new(&shape, &grid, n).unwrap();
    let mut ev = BatchEval::new(shape.outputs());
    let (mut x, mut y, mut z) = (vec![0f32; plane], vec![0f32; plane], vec![0f32; plane]);
    let mut v = vec![0f32; plane];
    let (mut inside_total, mut nan_inside) = (0usize, 0usize);
    for k in 0..grid.layers {
        let mut frac = vec![0f32; plane * n];
        let mut mask = vec![false; plane];
        src.fill(k, &mut frac, &mut mask);
        for q in 0..plane {
            (x[q], y[q], z[q]) = (
                grid.x(q % nx) as f32,
                grid.y(q / nx) as f32,
                grid.z(k) as f32,
            );
        }
        ev.eval_output(0, &x, &y, &z, &mut v);
        for q in 0..plane {
            assert_eq!(mask[q], v[q] >= 0.0, "layer {k}, voxel {q}");
        }
        inside_total += mask.iter().filter(|&&m| m).count();
        for c in 0..n - 1 {
            ev.eval_output(shape.attribute_output(c), &x, &y, &z, &mut v);
            for q in (0..plane).filter(|&q| mask[q]) {
                let want = if v[q].is_nan() { 0.0 } else { v[q] };
                nan_inside += usize::from(v[q].is_nan());
                assert_eq!(
                    frac[q * n + c].to_bits(),
                    want.to_bits(),
                    "layer {k}, voxel {q}, channel {c}"
                );
            }
        }
    }
    assert!(
        inside_total > 100_000 && nan_inside > 10_000,
        "{inside_total} {nan_inside}"
    );
}

#[test]
fn shape_source_needs_the_channels() {
    let shape = graded_ball();
    let grid = StackGrid::new([-1.0; 3], [1.0; 3], [0.1, 0.1], 0.1).unwrap();
    assert!(ShapeSource::new(&shape, &grid, 4).is_ok());
    let e = ShapeSource::new(&shape, &grid, 5)
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("5 materials need 4 attribute channels"), "{e}");
}
