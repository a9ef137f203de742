//! Batch evaluation of the tensor-product Bezier field gives the same bits
//! as its point evaluation rounded to f32, inside the box, outside it
//! (clamped) and at NaN.

use microfrep_core::Field;
use microfrep_graded::bezier::BezierBox;

#[test]
fn bezier_box_batch_has_point_bits() {
    let deg = [3, 2, 4];
    let count = (deg[0] + 1) * (deg[1] + 1) * (deg[2] + 1);
    let w: Vec<f64> = (0..count)
        .map(|i| ((i * 37 % 11) as f64 - 4.0) / 7.0)
        .collect();
    let f = BezierBox::new("b", [-1.0, 0.0, 0.5], [1.0, 2.0, 1.5], deg, w).unwrap();
    // 1000 points over a box larger than the field's, in odd batch lengths.
    let mut xs = Vec::new();
    let (mut ys, mut zs) = (Vec::new(), Vec::new());
    let mut state = 12345u64;
    let mut next = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 40) as f64 / (1u64 << 24) as f64
    };
    for _ in 0..1000 {
        xs.push((-1.5 + 3.0 * next()) as f32);
        ys.push((-0.5 + 3.0 * next()) as f32);
        zs.push((0.0 + 2.0 * next()) as f32);
    }
    xs[7] = f32::NAN;
    for len in [1usize, 7, 8, 9, 250, 1000] {
        let mut out = vec![0f32; len];
        f.eval_batch(&xs[..len], &ys[..len], &zs[..len], &mut out);
        for i in 0..len {
            let p = [xs[i] as f64, ys[i] as f64, zs[i] as f64];
            let want = f.eval(p) as f32;
            assert!(
                out[i].to_bits() == want.to_bits() || (out[i].is_nan() && want.is_nan()),
                "point {i} of {len}: {} vs {want}",
                out[i]
            );
        }
    }
    let mut out = [0f32; 8];
    f.eval_batch(&xs[..8], &ys[..8], &zs[..8], &mut out);
    assert!(out[7].is_nan() && out[..7].iter().all(|v| v.is_finite()));
}
