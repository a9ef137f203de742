//! Times the distance transform of a synthetic CT volume and reports the
//! peak memory:
//! `cargo run --release -p microfrep-scan --example scan_bench -- 256 [smooth_mm] [gyroid|ball]`.
//!
//! The volume is an i16 "CT" of trabecular-like bone (a gyroid sheet,
//! +1000 HU in the walls, -1000 HU elsewhere, a linear ramp between) at
//! 0.1 mm voxels, so a large share of the voxels lies next to the surface;
//! or a ball filling the volume (little surface).

use microfrep_core::{Field, Interval};
use microfrep_scan::{Samples, ScanField, ScanOptions, Volume};
use rayon::prelude::*;
use std::time::Instant;

fn peak_rss_kib() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse().ok())
        })
        .unwrap_or(0)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(256);
    let smooth: f64 = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(0.0);
    let ball = args.get(3).map(|s| s == "ball").unwrap_or(false);
    let h = 0.1;
    let period = 3.2; // mm
    let k = 2.0 * std::f64::consts::PI / period;
    let plane = n * n;
    let mut v = vec![0i16; n * n * n];
    v.par_chunks_mut(plane).enumerate().for_each(|(z, p)| {
        for y in 0..n {
            for x in 0..n {
                let q = [x, y, z].map(|c| c as f64 * h * k);
                let hu = if ball {
                    let ctr = 0.5 * n as f64 * h;
                    let d = [x, y, z].map(|i| (i as f64 * h - ctr).powi(2));
                    let r = 0.4 * n as f64 * h;
                    let dist = (d[0] + d[1] + d[2]).sqrt();
                    (1000.0 * (r - dist)).clamp(-1000.0, 1000.0)
                } else {
                    let g =
                        q[0].sin() * q[1].cos() + q[1].sin() * q[2].cos() + q[2].sin() * q[0].cos();
                    // Walls where |g| < 0.4, about 0.3 mm thick.
                    (2500.0 * (0.4 - g.abs())).clamp(-1000.0, 1000.0)
                };
                p[x + n * y] = (hu + 1024.0) as i16;
            }
        }
    });
    let mut vol = Volume::new([n; 3], [h; 3], [0.0; 3], Samples::I16(v)).unwrap();
    vol.intercept = -1024.0;
    let before = peak_rss_kib();
    let mut opts = ScanOptions::new(300.0);
    opts.smooth = smooth;
    opts.memory_limit = 16 << 30;
    let t = Instant::now();
    let f = ScanField::build(&vol, &opts).unwrap();
    let build = t.elapsed().as_secs_f64();
    let peak = peak_rss_kib();
    // Point throughput through eval_batch, and a large-box interval.
    let m = 1 << 20;
    let side = n as f64 * h;
    let xs: Vec<f32> = (0..m)
        .map(|i| ((i * 7919) % m) as f32 / m as f32 * side as f32)
        .collect();
    let ys: Vec<f32> = (0..m)
        .map(|i| ((i * 104729) % m) as f32 / m as f32 * side as f32)
        .collect();
    let zs: Vec<f32> = (0..m)
        .map(|i| ((i * 15485863) % m) as f32 / m as f32 * side as f32)
        .collect();
    let mut out = vec![0f32; m];
    let t = Instant::now();
    f.eval_batch(&xs, &ys, &zs, &mut out);
    let batch = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let mut iv = Interval::point(0.0);
    for i in 0..1000 {
        let o = (i % 10) as f64 * 0.05 * side;
        iv = f.interval([Interval::new(o, o + 0.4 * side); 3]);
    }
    let interval = t.elapsed().as_secs_f64() / 1000.0;
    println!(
        "RESULT scan_edt shape={} n={n} smooth_mm={smooth} threads={} build_s={build:.3} surface_voxels={} \
         volume_mib={:.0} field_mib={:.0} peak_rss_mib={:.0} rss_before_build_mib={:.0} \
         batch_mpts_s={:.1} interval_us={:.1} last_interval=[{:.3},{:.3}]",
        if ball { "ball" } else { "gyroid" },
        rayon::current_num_threads(),
        f.surface_voxels(),
        vol.bytes() as f64 / (1 << 20) as f64,
        f.bytes() as f64 / (1 << 20) as f64,
        peak as f64 / 1024.0,
        before as f64 / 1024.0,
        m as f64 / batch / 1e6,
        interval * 1e6,
        iv.lo,
        iv.hi
    );
}
