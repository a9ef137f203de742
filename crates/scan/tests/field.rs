//! ScanField and IntensityField as core Fields: the four-mode check,
//! interval bounds against brute force, the solid's volume, the outside.

use microfrep_core::field_check::{check_field, FieldCheck};
use microfrep_core::{Field, Interval};
use microfrep_scan::{IntensityField, Samples, ScanError, ScanField, ScanOptions, Volume};
use std::sync::Arc;

/// CT-like i16 ball with slope 1, intercept -1024 (HU): -1000 outside,
/// +1000 inside, a linear ramp 2 mm wide at radius r.
fn ct_ball(dims: [usize; 3], h: [f64; 3], origin: [f64; 3], c: [f64; 3], r: f64) -> Volume {
    let mut v = Vec::new();
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                let p = [0, 1, 2].map(|a| origin[a] + [i, j, k][a] as f64 * h[a]);
                let d =
                    ((p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2) + (p[2] - c[2]).powi(2)).sqrt();
                let hu = (1000.0 * (r - d)).clamp(-1000.0, 1000.0);
                v.push((hu + 1024.0).round() as i16);
            }
        }
    }
    let mut vol = Volume::new(dims, h, origin, Samples::I16(v)).unwrap();
    vol.intercept = -1024.0;
    vol
}

fn region(f: &ScanField, pad: f64) -> [[f64; 3]; 2] {
    let [lo, hi] = f.bounds();
    [lo.map(|v| v - pad), hi.map(|v| v + pad)]
}

#[test]
fn scan_field_passes_the_four_mode_check_inside_and_outside_the_volume() {
    let vol = ct_ball(
        [20, 18, 16],
        [0.5, 0.6, 0.7],
        [-5.0, -5.0, -5.5],
        [-0.2, 0.1, 0.0],
        3.0,
    );
    let f = ScanField::build(&vol, &ScanOptions::new(300.0)).unwrap();
    let reg = region(&f, 2.0);
    let f: Arc<dyn Field> = Arc::new(f);
    let mut cfg = FieldCheck::new(reg);
    cfg.max_box = 0.6;
    let rep = check_field(&f, &cfg).unwrap();
    assert!(rep.points == 2000 && rep.boxes == 300);
    // Most points are smooth enough for the gradient check.
    assert!(rep.not_smooth < rep.points / 2, "{rep:?}");
}

#[test]
fn intensity_field_passes_the_four_mode_check() {
    let vol = Arc::new(ct_ball(
        [12, 10, 9],
        [0.5, 0.6, 0.7],
        [0.0; 3],
        [3.0, 3.0, 3.0],
        2.0,
    ));
    let f = IntensityField::new("ct", vol.clone()).unwrap();
    // The value at a sample centre is the scaled sample.
    let p = vol.position([3, 4, 5]);
    assert!((f.eval(p) - vol.value(3, 4, 5)).abs() < 1e-9);
    let f: Arc<dyn Field> = Arc::new(f);
    let mut cfg = FieldCheck::new([[-1.0; 3], [7.0; 3]]);
    cfg.grad_tol = 1e-2;
    check_field(&f, &cfg).unwrap();
}

#[test]
fn intervals_bound_and_are_tight_on_large_boxes() {
    let vol = ct_ball([64, 60, 56], [0.25; 3], [0.0; 3], [8.0, 7.5, 7.0], 5.0);
    let f = ScanField::build(&vol, &ScanOptions::new(0.0)).unwrap();
    let d = f.distances();
    // The whole volume: the range of the grid, cut by the box distance.
    let b = f.bounds();
    let whole = f.interval([0, 1, 2].map(|a| Interval::new(b[0][a], b[1][a])));
    let (lo, hi) = d
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| {
            (l.min(v as f64), h.max(v as f64))
        });
    assert!(whole.lo <= lo.min(0.0) && whole.hi >= 0.0);
    assert!(whole.hi <= hi + 1e-9);
    // Random sub-boxes: the pyramid gives exactly the brute-force node range.
    let mut s = 12345u64;
    let mut rnd = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let [nx, ny, _] = f.dims();
    for _ in 0..200 {
        let bx: [Interval; 3] = std::array::from_fn(|a| {
            let len = (f.dims()[a] - 1) as f64 * 0.25;
            let w = len * 0.7 * rnd();
            let c = len * 0.05 + (len * 0.9 - w) * rnd();
            Interval::new(c, c + w)
        });
        let iv = f.interval(bx);
        let r: [[usize; 2]; 3] = std::array::from_fn(|a| {
            [
                (bx[a].lo / 0.25).floor() as usize,
                ((bx[a].hi / 0.25).ceil() as usize).min(f.dims()[a] - 1),
            ]
        });
        let mut bl = f64::INFINITY;
        let mut bh = f64::NEG_INFINITY;
        for k in r[2][0]..=r[2][1] {
            for j in r[1][0]..=r[1][1] {
                for i in r[0][0]..=r[0][1] {
                    let v = d[i + nx * (j + ny * k)] as f64;
                    bl = bl.min(v);
                    bh = bh.max(v);
                }
            }
        }
        // The boxes keep 0.9 mm from the faces, so below that the box
        // distance cannot bind: the bound is the node range, widened by
        // rounding only.
        let tol = |v: f64| 1e-9 * (1.0 + v.abs());
        assert!(iv.lo <= bl && iv.hi >= bh, "{iv:?} vs [{bl}, {bh}]");
        if bl < 0.8 {
            assert!(bl - iv.lo < tol(bl), "{iv:?} vs {bl} over {bx:?}");
        }
        if bh < 0.8 {
            assert!(iv.hi - bh < tol(bh), "{iv:?} vs {bh} over {bx:?}");
        }
        // Sample points of the box lie inside the bound.
        for _ in 0..5 {
            let p: [f64; 3] = std::array::from_fn(|a| bx[a].lo + bx[a].width() * rnd());
            assert!(iv.contains(f.eval(p)));
        }
    }
}

#[test]
fn solid_volume_matches_the_ball() {
    let h = 0.2;
    let r = 2.5;
    let vol = ct_ball([36, 36, 36], [h; 3], [-3.5; 3], [0.05, -0.03, 0.02], r);
    let f = ScanField::build(&vol, &ScanOptions::new(0.0)).unwrap();
    // Midpoint rule on a fine lattice of the field itself.
    let m = 70;
    let side = 7.0 / m as f64;
    let mut inside = 0usize;
    for k in 0..m {
        for j in 0..m {
            for i in 0..m {
                let p = [i, j, k].map(|x| -3.5 + (x as f64 + 0.5) * side);
                if f.eval(p) >= 0.0 {
                    inside += 1;
                }
            }
        }
    }
    let vol_est = inside as f64 * side.powi(3);
    let want = 4.0 / 3.0 * std::f64::consts::PI * r.powi(3);
    assert!((vol_est / want - 1.0).abs() < 0.01, "{vol_est} vs {want}");
}

#[test]
fn outside_the_volume_the_field_is_negative_and_conservative() {
    // A ball cut by the volume's box: the solid must close at the box.
    let vol = ct_ball([20, 20, 20], [0.5; 3], [0.0; 3], [0.0, 4.75, 4.75], 3.0);
    let f = ScanField::build(&vol, &ScanOptions::new(0.0)).unwrap();
    let [lo, _] = f.bounds();
    assert_eq!(lo, [-0.25; 3]);
    // Just inside the box face x = -0.25 on the ball's axis: inside, small.
    let v = f.eval([-0.2, 4.75, 4.75]);
    assert!(v > 0.0 && v <= 0.05 + 1e-12, "{v}");
    // Outside: negative, magnitude at most the true distance to the cut ball.
    for &x in &[-0.3, -1.0, -5.0, -50.0] {
        let v = f.eval([x, 4.75, 4.75]);
        assert!(v < 0.0 && -v <= -0.25 - x + 1e-9, "x {x}: {v}");
    }
    let far = f.eval([100.0, 100.0, 100.0]);
    assert!(far < -100.0);
}

#[test]
fn bad_iso_and_non_finite_samples_are_errors() {
    let vol = ct_ball([8, 8, 8], [1.0; 3], [0.0; 3], [3.5; 3], 2.0);
    match ScanField::build(&vol, &ScanOptions::new(5000.0)) {
        Err(ScanError::NoSurface { min, max, .. }) => assert_eq!((min, max), (-1000.0, 1000.0)),
        other => panic!("{other:?}"),
    }
    assert!(matches!(
        ScanField::build(&vol, &ScanOptions::new(-5000.0)),
        Err(ScanError::NoSurface { .. })
    ));
    assert!(matches!(
        ScanField::build(&vol, &ScanOptions::new(f64::NAN)),
        Err(ScanError::Invalid(_))
    ));
    let mut v = vec![0.0f32; 64];
    v[2] = 1.0;
    v[1 + 4 * (2 + 4 * 3)] = f32::NAN;
    let vol = Volume::new([4; 3], [1.0; 3], [0.0; 3], Samples::F32(v)).unwrap();
    match ScanField::build(&vol, &ScanOptions::new(0.5)) {
        Err(ScanError::NotFinite { index, .. }) => assert_eq!(index, [1, 2, 3]),
        other => panic!("{other:?}"),
    }
    let flat = Volume::new([4, 4, 1], [1.0; 3], [0.0; 3], Samples::U8(vec![0; 16])).unwrap();
    assert!(matches!(
        ScanField::build(&flat, &ScanOptions::new(0.5)),
        Err(ScanError::Invalid(_))
    ));
}

#[test]
fn memory_limit_is_checked_before_the_transform() {
    let vol = ct_ball([32, 32, 32], [0.5; 3], [0.0; 3], [8.0; 3], 4.0);
    let mut o = ScanOptions::new(0.0);
    o.memory_limit = 100_000;
    match ScanField::build(&vol, &o) {
        Err(e @ ScanError::TooLarge { .. }) => {
            let m = e.to_string();
            assert!(m.contains("step of 2"), "{m}");
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn smoothing_keeps_the_surface_of_a_ball() {
    let h = 0.25;
    let r = 3.0;
    let c = [4.1, 4.0, 3.9];
    let vol = ct_ball([32, 32, 32], [h; 3], [0.0; 3], c, r);
    let mut o = ScanOptions::new(0.0);
    o.smooth = 0.3;
    let f = ScanField::build(&vol, &o).unwrap();
    // A Gaussian shrinks a sphere's iso-0 surface by about sigma^2 / r.
    for p in [
        [c[0] + r, c[1], c[2]],
        [c[0], c[1] - r, c[2]],
        [c[0], c[1], c[2] + r],
    ] {
        let v = f.eval(p);
        assert!(v.abs() < 0.06, "{v} at {p:?}");
    }
}

#[test]
fn progress_reaches_its_total_and_builds_are_deterministic() {
    let vol = ct_ball([16, 16, 16], [0.5; 3], [0.0; 3], [4.0; 3], 2.5);
    let last = std::sync::Mutex::new((0u64, 0u64));
    let a = ScanField::build_with_progress(&vol, &ScanOptions::new(0.0), &|d, t| {
        let mut l = last.lock().unwrap();
        l.0 = l.0.max(d);
        l.1 = t;
    })
    .unwrap();
    let (d, t) = *last.lock().unwrap();
    assert!(t > 0 && d == t, "{d} / {t}");
    let b = ScanField::build(&vol, &ScanOptions::new(0.0)).unwrap();
    assert_eq!(a.distances(), b.distances());
}

#[test]
fn smoothing_wider_than_the_scan_is_refused_and_the_field_is_a_distance() {
    // 8 x 8 x 6 samples 0.5 mm apart: 3.5 mm across the longest side.
    let vol = ct_ball([8, 8, 6], [0.5; 3], [0.0; 3], [1.75, 1.75, 1.25], 1.2);
    for w in [3.6, 1e6, 1e300, f64::MAX] {
        let mut o = ScanOptions::new(0.0);
        o.smooth = w;
        match ScanField::build(&vol, &o) {
            Err(e @ ScanError::Invalid(_)) => {
                let t = e.to_string();
                assert!(
                    t.contains("wider than the whole scan") && t.contains("3.5 mm"),
                    "{t}"
                );
            }
            other => panic!("smooth {w}: {other:?}"),
        }
    }
    for w in [-0.1, f64::NAN, f64::INFINITY] {
        let mut o = ScanOptions::new(0.0);
        o.smooth = w;
        let e = ScanField::build(&vol, &o).unwrap_err().to_string();
        assert!(e.contains("non-negative"), "{w}: {e}");
    }
    // A width of the scan's extent is not refused as too wide (it blurs
    // this small ball away, which is a different error).
    let mut o = ScanOptions::new(0.0);
    o.smooth = 3.5;
    if let Err(e) = ScanField::build(&vol, &o) {
        assert!(!e.to_string().contains("wider than"), "{e}");
    }
    // A sensible width builds, and the value is a signed distance
    // (positive inside), as the Field trait declares.
    o.smooth = 0.3;
    let f = ScanField::build(&vol, &o).unwrap();
    assert!(f.is_signed_distance());
    let vol = ct_ball([24; 3], [0.5; 3], [0.0; 3], [6.0; 3], 3.0);
    let f = ScanField::build(&vol, &ScanOptions::new(0.0)).unwrap();
    assert!(f.is_signed_distance());
    for (p, want) in [
        ([6.0, 6.0, 6.0], 3.0),
        ([7.0, 6.0, 6.0], 2.0),
        ([10.5, 6.0, 6.0], -1.5),
    ] {
        let v = f.eval(p);
        assert!((v - want).abs() < 0.15, "{v} at {p:?}, want {want}");
    }
}
