//! Dithering: each material's voxel count against its integral, local
//! shares of error diffusion in 8x8x8 regions, determinism, input reading.

use microfrep_graded::dither::{dither, DitherReport, Layout, Method, OUTSIDE};

/// Dithers a field given per voxel by `f(i, j, k) -> (fractions, inside)`;
/// returns the report and the whole voxel grid (k major).
fn run(
    nx: usize,
    ny: usize,
    layers: usize,
    n: usize,
    method: Method,
    f: impl Fn(usize, usize, usize, &mut [f32]) -> bool + Sync,
) -> (DitherReport, Vec<u8>, Vec<f32>) {
    let mut all = Vec::new();
    let mut fracs = Vec::new();
    let layout = Layout {
        nx,
        ny,
        layers,
        materials: n,
    };
    let report = dither(
        layout,
        method,
        1 << 30,
        &mut |k, frac, mask| {
            for j in 0..ny {
                for i in 0..nx {
                    let q = j * nx + i;
                    mask[q] = f(i, j, k, &mut frac[q * n..(q + 1) * n]);
                }
            }
            fracs.extend_from_slice(frac);
        },
        &mut |_, layer| {
            all.extend_from_slice(layer);
            Ok(())
        },
        &|_, _| {},
    )
    .unwrap();
    (report, all, fracs)
}

fn volume_ok(r: &DitherReport, tol: f64) {
    for (m, (&c, &i)) in r.counts.iter().zip(&r.integrals).enumerate() {
        let err = (c as f64 - i).abs();
        assert!(
            err <= tol * i.max(1.0) + 1.0,
            "material {m}: {c} voxels, integral {i}"
        );
    }
}

/// Largest deviation of a material's share from its mean fraction over
/// 8x8x8 blocks fully inside, at offsets 0 and 4.
fn worst_block(nx: usize, ny: usize, nz: usize, n: usize, vox: &[u8], fr: &[f32]) -> f64 {
    let mut worst = 0.0f64;
    for off in [0, 4] {
        for bz in (off..nz.saturating_sub(7)).step_by(8) {
            for by in (off..ny.saturating_sub(7)).step_by(8) {
                for bx in (off..nx.saturating_sub(7)).step_by(8) {
                    let mut count = vec![0.0f64; n];
                    let mut mean = vec![0.0f64; n];
                    let mut full = true;
                    for k in bz..bz + 8 {
                        for j in by..by + 8 {
                            for i in bx..bx + 8 {
                                let q = (k * ny + j) * nx + i;
                                if vox[q] == OUTSIDE {
                                    full = false;
                                    continue;
                                }
                                count[vox[q] as usize] += 1.0;
                                let f = &fr[q * n..(q + 1) * n];
                                let s: f32 = f[..n - 1].iter().sum();
                                for m in 0..n - 1 {
                                    mean[m] += f[m] as f64;
                                }
                                mean[n - 1] += 1.0 - s as f64;
                            }
                        }
                    }
                    if !full {
                        continue;
                    }
                    for m in 0..n {
                        worst = worst.max((count[m] - mean[m]).abs() / 512.0);
                    }
                }
            }
        }
    }
    worst
}

#[test]
fn error_diffusion_preserves_volume_and_local_shares_on_gradients_and_constants() {
    let (nx, ny, nz) = (48, 40, 32);
    // Two materials, smooth gradient along a diagonal.
    let grad2 = move |i: usize, j: usize, k: usize, f: &mut [f32]| {
        f[0] = ((i + j + 2 * k) as f32 / (nx + ny + 2 * nz) as f32).clamp(0.0, 1.0);
        true
    };
    // Three materials, smooth in x and z.
    let grad3 = move |i: usize, _j: usize, k: usize, f: &mut [f32]| {
        let u = i as f32 / nx as f32;
        let w = k as f32 / nz as f32;
        f[0] = 0.6 * u * (1.0 - w);
        f[1] = 0.3 * w + 0.1 * (1.0 - u);
        true
    };
    type Case<'a> = (
        &'a str,
        usize,
        Box<dyn Fn(usize, usize, usize, &mut [f32]) -> bool + Sync>,
    );
    let cases: Vec<Case> = vec![
        ("gradient 2", 2, Box::new(grad2)),
        ("gradient 3", 3, Box::new(grad3)),
        (
            "constant 0.5",
            2,
            Box::new(|_, _, _, f: &mut [f32]| {
                f[0] = 0.5;
                true
            }),
        ),
        (
            "constant 0.03",
            2,
            Box::new(|_, _, _, f: &mut [f32]| {
                f[0] = 0.03;
                true
            }),
        ),
        (
            "constant thirds",
            3,
            Box::new(|_, _, _, f: &mut [f32]| {
                f[0] = 1.0 / 3.0;
                f[1] = 1.0 / 3.0;
                true
            }),
        ),
    ];
    for (name, n, f) in &cases {
        let (r, vox, fr) = run(nx, ny, nz, *n, Method::ErrorDiffusion, f);
        assert_eq!(r.inside, (nx * ny * nz) as u64);
        // Well within 0.5 %: within a voxel or two.
        volume_ok(&r, 0.0);
        let w = worst_block(nx, ny, nz, *n, &vox, &fr);
        assert!(w <= 0.15, "{name}: an 8^3 block deviates by {w}");
        assert!(w <= 0.06, "{name}: {w}");
    }
}

#[test]
fn error_diffusion_preserves_volume_inside_a_ball() {
    let (nx, ny, nz) = (40, 40, 40);
    let ball = |i: usize, j: usize, k: usize, f: &mut [f32]| {
        let c = |v: usize| v as f32 - 19.5;
        let r2 = c(i) * c(i) + c(j) * c(j) + c(k) * c(k);
        f[0] = (r2.sqrt() / 20.0).clamp(0.0, 1.0);
        f[1] = 0.2;
        r2 < 19.0 * 19.0
    };
    let (r, vox, fr) = run(nx, ny, nz, 3, Method::ErrorDiffusion, ball);
    assert!(r.inside > 25_000);
    volume_ok(&r, 0.0);
    assert!(worst_block(nx, ny, nz, 3, &vox, &fr) <= 0.15);
    // Outside stays outside.
    for (q, &v) in vox.iter().enumerate() {
        let (i, j, k) = (q % nx, (q / nx) % ny, q / (nx * ny));
        let mut f = [0.0; 3];
        assert_eq!(v == OUTSIDE, !ball(i, j, k, &mut f));
    }
}

#[test]
fn ordered_and_stochastic_meet_the_integrals() {
    let (nx, ny, nz) = (64, 64, 32);
    let grad = |i: usize, j: usize, k: usize, f: &mut [f32]| {
        f[0] = 0.8 * (i as f32 + 0.5) / nx as f32;
        f[1] = 0.15 * (1.0 + ((j + k) as f32 * 0.1).sin());
        true
    };
    // Two materials: the threshold window always starts at 0, so a smooth
    // fraction is met within 0.5 %.
    let grad2 = |i: usize, j: usize, k: usize, f: &mut [f32]| {
        f[0] = 0.2 + 0.6 * (i as f32 + 0.5) / nx as f32 + 0.1 * ((j + k) as f32 * 0.1).sin();
        true
    };
    let (r, vox, fr) = run(nx, ny, nz, 2, Method::Ordered, grad2);
    volume_ok(&r, 0.005);
    assert!(worst_block(nx, ny, nz, 2, &vox, &fr) <= 0.15);
    // With three, a material's window [C_(m-1), C_m) moves with the
    // fractions before it and meets the threshold pattern unevenly: the
    // documented limit is 2 %.
    let (r, vox, fr) = run(nx, ny, nz, 3, Method::Ordered, grad);
    volume_ok(&r, 0.02);
    assert!(worst_block(nx, ny, nz, 3, &vox, &fr) <= 0.15);
    // A constant fraction is exact over every aligned 8^3 block.
    let (_, vox, _) = run(16, 16, 16, 2, Method::Ordered, |_, _, _, f| {
        f[0] = 0.3;
        true
    });
    for b in 0..8 {
        let (bx, by, bz) = ((b & 1) * 8, (b >> 1 & 1) * 8, (b >> 2) * 8);
        let mut c = 0;
        for k in bz..bz + 8 {
            for j in by..by + 8 {
                for i in bx..bx + 8 {
                    c += (vox[(k * 16 + j) * 16 + i] == 0) as usize;
                }
            }
        }
        assert_eq!(c, (0.3f64 * 512.0).round() as usize);
    }
    // Stochastic: within 4 binomial standard deviations of each integral
    // (here about 0.7 %: independent draws cannot promise 0.5 % at this
    // size, which is why error diffusion is the default).
    let (r, _, _) = run(nx, ny, nz, 3, Method::Stochastic { seed: 5 }, grad);
    let total = r.inside as f64;
    for m in 0..3 {
        let p = r.integrals[m] / total;
        let sd = (total * p * (1.0 - p)).sqrt();
        let err = (r.counts[m] as f64 - r.integrals[m]).abs();
        assert!(err <= 4.0 * sd, "material {m}: {err} vs sd {sd}");
    }
}

#[test]
fn dithering_is_deterministic_whatever_the_thread_count() {
    let f = |i: usize, j: usize, k: usize, fr: &mut [f32]| {
        fr[0] = ((i * 7 + j * 3 + k) % 23) as f32 / 23.0;
        (i * 7 + j + k * 3) % 5 < 4
    };
    for method in [
        Method::ErrorDiffusion,
        Method::Ordered,
        Method::Stochastic { seed: 9 },
    ] {
        let a = run(30, 20, 10, 2, method, f).1;
        let b = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| run(30, 20, 10, 2, method, f).1);
        assert_eq!(a, b, "{method:?}");
    }
    let a = run(30, 20, 10, 2, Method::Stochastic { seed: 1 }, f).1;
    let b = run(30, 20, 10, 2, Method::Stochastic { seed: 2 }, f).1;
    assert_ne!(a, b);
}

#[test]
fn fractions_are_read_clamped_with_the_remainder_last() {
    // NaN -> 0; over-full sums scaled down; the last slot is ignored.
    let (r, vox, _) = run(8, 8, 8, 3, Method::Ordered, |i, _, _, f| {
        match i % 4 {
            0 => {
                f[0] = f32::NAN;
                f[1] = 0.0;
                f[2] = 0.9;
            }
            1 => {
                f[0] = 2.0;
                f[1] = 2.0;
            }
            2 => {
                f[0] = -1.0;
                f[1] = 1.0;
            }
            _ => {
                f[0] = 1.0;
                f[1] = 0.0;
            }
        }
        true
    });
    let col = |i: usize| -> Vec<u8> { (0..64).map(|q| vox[q * 8 + i]).collect() };
    // Column 0 is all the last material (remainder 1), column 2 all
    // material 1, column 3 all material 0.
    assert!(col(0).iter().all(|&m| m == 2));
    assert!(col(2).iter().all(|&m| m == 1));
    assert!(col(3).iter().all(|&m| m == 0));
    // Column 1 is half and half of materials 0 and 1.
    let c1 = col(1);
    let zeros = c1.iter().filter(|&&m| m == 0).count();
    assert!(
        c1.iter().all(|&m| m < 2) && (24..=40).contains(&zeros),
        "{zeros}"
    );
    assert!((r.integrals[2] - 128.0).abs() < 1e-6, "{:?}", r.integrals);
}

#[test]
fn oversized_jobs_and_bad_layouts_are_errors() {
    let layout = Layout {
        nx: 100_000,
        ny: 100_000,
        layers: 10,
        materials: 4,
    };
    let e = dither(
        layout,
        Method::ErrorDiffusion,
        1 << 30,
        &mut |_, _, _| {},
        &mut |_, _| Ok(()),
        &|_, _| {},
    )
    .unwrap_err();
    assert!(e.to_string().contains("more than the limit"), "{e}");
    for (nx, m) in [(0, 2), (4, 0), (4, 256)] {
        let l = Layout {
            nx,
            ny: 4,
            layers: 1,
            materials: m,
        };
        assert!(dither(
            l,
            Method::Ordered,
            1 << 30,
            &mut |_, _, _| {},
            &mut |_, _| Ok(()),
            &|_, _| {}
        )
        .is_err());
    }
}
