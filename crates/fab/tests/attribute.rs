//! The attribute stack's culled, per-channel evaluation against two
//! straightforward references: the shape's value and the channel (with
//! integer powers, as the stack evaluates it) compiled together and
//! evaluated in f32 at every pixel centre (the same bytes), and the f64
//! point evaluator of the channel as given at every pixel centre (within
//! one grey level).

use microfrep_core::{Expr, PointEval, Shape, Tape};
use microfrep_fab::attribute::reference_layer_pixels;
use microfrep_fab::{rasterize, AttributeStack, SliceGrid};

/// A ball of radius 1 with a hole along z, graded six ways: a smooth
/// field above z = 0.2 and 0 below (a branch intervals decide, whole layers
/// at once), a radial field clamped at both ends, a square root NaN where
/// x < -0.5, Schlick's gain of the radius (two powers, one of which tiles
/// away from the middle radius cut: a shorter tape by cost, not by steps),
/// steps of powers switched on along x (tiles keep different sets, so
/// many shorter tapes are in use at once), powers with whole exponents
/// (odd of negative bases, negative), which the stack evaluates as integer
/// powers, divisions by constants, which it evaluates as products with the
/// inverses, a power with its gradient (whose power with the exponent one
/// less the stack shares with it), and a ramp over the normalised depth of
/// a union of two ellipsoids (a gradient written out, with the derivative
/// of the max as selects of 1 and 0 that tiles decide).
fn graded_ball() -> Shape {
    let [x, y, z] = Expr::xyz();
    let r2 = x.square() + y.square() + z.square();
    let ball = 1.0 - &r2;
    let hole = x.square() + y.square() - 0.04;
    let value = microfrep_core::frep::intersection(&ball, &hole, 0.0);
    let smooth = 0.5 + 0.4 * (3.0 * &x).sin() * (2.0 * &y).cos();
    let s1 = Expr::select(z.ge(0.2), smooth, Expr::constant(0.0));
    let s2 = 1.6 - 2.0 * &r2;
    let s3 = (&x + 0.5).sqrt();
    let t = (1.0 - r2.sqrt()).max(0.0).min(1.0);
    let gain = Expr::select(
        t.lt(0.5),
        0.5 * (2.0 * &t).pow(1.7),
        1.0 - 0.5 * (2.0 - 2.0 * &t).pow(1.7),
    );
    let mut steps = Expr::constant(0.05);
    for k in 0..24 {
        let at = -0.95 + 0.08 * k as f64;
        let power = (&x + 1.5).pow(1.1 + 0.03 * k as f64) * 0.02;
        steps = steps + Expr::select(x.gt(at), power, Expr::constant(0.0));
    }
    Shape::new(value)
        .with_attribute("s1", s1)
        .with_attribute("s2", s2)
        .with_attribute("s3", s3)
        .with_attribute("gain", gain)
        .with_attribute("steps", steps)
        .with_attribute("ratio", (&x / 0.3 + &y / 7.0) / 3.0 + 0.5 + &z / 0.25)
        .with_attribute("power_gradient", {
            let s = (x.square() + 2.0 * y.square() + 0.05).pow(0.3);
            0.2 + 0.5 * &s + 0.04 * &s.gradient()[0]
        })
        .with_attribute("depth", {
            let e1 = 1.0 - (x.square() / 0.8 + y.square() / 0.5 + z.square());
            let e2 = 1.0 - ((&x - 0.3).square() * 4.0 + y.square() / 0.9 + z.square() / 0.7);
            let depth = microfrep_core::frep::normalize(&e1.max(&e2));
            let ramp = ((&depth - 0.1) / 0.2).max(0.0).min(1.0).pow(0.7);
            Expr::select(depth.ge(0.1), ramp, Expr::constant(0.0))
        })
        .with_attribute(
            "whole",
            0.5 + 0.6 * (&x - 0.2).pow(3.0) - 0.3 * (&y + 0.1).pow(4.0)
                + 0.05 * (&z + 1.5).pow(-2.0),
        )
}

#[test]
fn culled_attribute_layers_equal_full_evaluation() {
    let shape = graded_ball();
    let grid = SliceGrid::new([-1.05; 3], [1.05; 3], 0.07, 0.011).unwrap();
    assert!(grid.nx > 150 && grid.layers > 20);
    for channel in 0..9 {
        let stack = AttributeStack::new(&shape, channel).unwrap();
        let attr = Tape::new(&shape.attributes()[channel].expr);
        let mut point = PointEval::new(&attr);
        let (mut grey, mut levels) = (0usize, std::collections::BTreeSet::new());
        for k in 0..grid.layers {
            let fast = stack.layer_pixels(&shape, &grid, k);
            let full = reference_layer_pixels(&shape, &grid, k, channel);
            assert_eq!(fast, full, "channel {channel}, layer {k}");
            // The f64 reference, pixel by pixel, at the f32 pixel centres.
            let layer = rasterize(&shape, &grid, k);
            let (nx, ny) = (grid.nx, grid.ny);
            for j in 0..ny {
                for i in 0..nx {
                    let got = fast[(ny - 1 - j) * nx + i];
                    let p = [grid.x(i), grid.y(j), grid.z(k)].map(|c| c as f32 as f64);
                    let s = point.eval(p);
                    let want = if layer.inside(i, j) && !s.is_nan() {
                        (255.0 * s.clamp(0.0, 1.0)).round()
                    } else {
                        0.0
                    };
                    assert!(
                        (got as f64 - want).abs() <= 1.0,
                        "channel {channel}, layer {k}, pixel ({i}, {j}): {got} vs {want}"
                    );
                    grey += usize::from(got > 0 && got < 255);
                    levels.insert(got);
                }
            }
        }
        // The cases are not trivial: many intermediate levels.
        assert!(
            grey > 1000 && levels.len() > 50,
            "channel {channel}: {grey} {}",
            levels.len()
        );
    }
}

#[test]
fn attribute_stack_refuses_missing_channel() {
    let shape = graded_ball();
    let e = AttributeStack::new(&shape, 9).unwrap_err().to_string();
    assert!(
        e.contains("attribute 10 does not exist") && e.contains("9 attribute"),
        "{e}"
    );
}
