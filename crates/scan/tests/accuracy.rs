//! Distance accuracy on synthetic volumes built in memory.

use microfrep_core::Field;
use microfrep_scan::{Samples, ScanField, ScanOptions, Volume};

/// A CT-like ball: intensity ramps linearly from 0 to 1000 across `w` mm
/// around radius `r`, so the 500 iso surface is the sphere of radius r.
fn ball(n: usize, h: [f64; 3], c: [f64; 3], r: f64, w: f64) -> Volume {
    let dims = [n, n + 3, n - 2];
    let mut v = Vec::new();
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                let p = [i as f64 * h[0], j as f64 * h[1], k as f64 * h[2]];
                let d =
                    ((p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2) + (p[2] - c[2]).powi(2)).sqrt();
                let t = (0.5 + (r - d) / w).clamp(0.0, 1.0);
                v.push((1000.0 * t) as f32);
            }
        }
    }
    Volume::new(dims, h, [0.0; 3], Samples::F32(v)).unwrap()
}

/// Worst error near the surface (within `band` mm), worst anywhere, and
/// where the worst near the surface is.
fn max_error(f: &ScanField, c: [f64; 3], r: f64, margin: f64, band: f64) -> (f64, f64, [f64; 3]) {
    let [lo, hi] = f.bounds();
    let mut worst = 0.0f64;
    let mut all = 0.0f64;
    let mut at = [0.0; 3];
    let n = 40;
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let t = [i, j, k].map(|x| (x as f64 + 0.37) / n as f64);
                let p: [f64; 3] =
                    std::array::from_fn(|a| lo[a] + margin + (hi[a] - lo[a] - 2.0 * margin) * t[a]);
                let want = r
                    - ((p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2) + (p[2] - c[2]).powi(2))
                        .sqrt();
                let got = f.eval(p);
                let e = (got - want).abs();
                all = all.max(e);
                if want.abs() <= band && e > worst {
                    worst = e;
                    at = p;
                }
            }
        }
    }
    (worst, all, at)
}

#[test]
fn smooth_ball_is_within_a_fraction_of_a_voxel() {
    let h = [0.5, 0.5, 0.5];
    let c = [8.1, 8.3, 7.2];
    let r = 5.3;
    let v = ball(34, h, c, r, 2.0);
    let f = ScanField::build(&v, &ScanOptions::new(500.0)).unwrap();
    let (worst, all, at) = max_error(&f, c, r, 1.0, 1.5);
    eprintln!("isotropic: worst {worst} at {at:?}, anywhere {all} (voxel 0.5)");
    assert!(worst < 0.2 * 0.5, "worst {worst}");
    // Deep inside, the interpolated cone at the centre loses up to about
    // half a voxel.
    assert!(all < 0.6 * 0.5, "anywhere {all}");
}

#[test]
fn anisotropic_ball() {
    let h = [0.4, 0.5, 0.8];
    let c = [7.1, 8.3, 11.2];
    let r = 5.3;
    let v = ball(36, h, c, r, 2.0);
    let f = ScanField::build(&v, &ScanOptions::new(500.0)).unwrap();
    let (worst, all, at) = max_error(&f, c, r, 1.0, 2.4);
    eprintln!("anisotropic: worst {worst} at {at:?}, anywhere {all} (voxels 0.4, 0.5, 0.8)");
    assert!(worst < 0.2 * 0.4, "worst {worst}");
    assert!(all < 0.6 * 0.8, "anywhere {all}");
}
