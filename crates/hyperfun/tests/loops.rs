//! Loops: a loop that never ends costs a bounded amount of work for the
//! whole model, not seconds per point; legitimate loop-heavy models still
//! evaluate exactly.

use microfrep_hyperfun::load;
use std::time::Instant;

/// Diverges for x > -1 (every step moves t up), ends at once otherwise.
const RUNAWAY: &str =
    "my_model(x[3], a[1]) { t = x[1]; while t > -1 loop t = t + 1; endloop; my_model = t; }";

#[test]
fn a_loop_that_never_ends_is_one_error_for_the_model() {
    let m = load(RUNAWAY, "r.hf", None).unwrap();
    assert!(!m.lowered);
    assert_eq!(m.runaway_loop(), None);
    let pts: Vec<[f64; 3]> = (0..10_000).map(|i| [i as f64 * 1e-3, 0.0, 0.0]).collect();
    let t = Instant::now();
    let r = m.eval_points(&pts);
    // Before: about a second per point (hours for these points).
    assert!(t.elapsed().as_secs_f64() < 10.0, "{:?}", t.elapsed());
    for v in &r {
        let e = v.clone().unwrap_err();
        assert!(e.message.contains("iteration limit"), "{e}");
        assert_eq!((e.line, e.col), (1, 34));
    }
    let e = m.runaway_loop().expect("recorded");
    assert_eq!((e.line, e.col), (1, 34));
}

#[test]
fn a_constant_loop_that_never_ends_fails_once_at_load() {
    let src =
        "my_model(x[3], a[1]) { t = 0; while 1 loop t = t + 1; endloop; my_model = t + x[1]; }";
    let m = load(src, "r.hf", None).unwrap();
    let e = m.eval_points(&[[0.0; 3]])[0].clone().unwrap_err();
    assert!(e.message.contains("iteration limit") && e.col == 31, "{e}");
}

/// Escape-time iteration `z <- z^2 + c` in the (x, y) plane, up to 1000
/// steps: the trip count depends on the point, so it runs per point.
#[test]
fn a_loop_heavy_model_evaluates_exactly() {
    let src = "my_model(x[3], a[1]) {\n\
        zr = 0; zi = 0; i = 0;\n\
        while i < 1000 and zr*zr + zi*zi < 4 loop\n\
          t = zr*zr - zi*zi + x[1]; zi = 2*zr*zi + x[2]; zr = t; i = i + 1;\n\
        endloop;\n\
        my_model = i - 500; }";
    let m = load(src, "m.hf", None).unwrap();
    assert!(!m.lowered);
    let direct = |cr: f64, ci: f64| {
        let (mut zr, mut zi, mut i) = (0.0f64, 0.0f64, 0.0f64);
        while i < 1000.0 && zr * zr + zi * zi < 4.0 {
            let t = zr * zr - zi * zi + cr;
            zi = 2.0 * zr * zi + ci;
            zr = t;
            i += 1.0;
        }
        i - 500.0
    };
    let mut pts = Vec::new();
    for a in 0..20 {
        for b in 0..20 {
            pts.push([
                -2.0 + 2.5 * a as f64 / 19.0,
                -1.25 + 2.5 * b as f64 / 19.0,
                0.0,
            ]);
        }
    }
    let r = m.eval_points(&pts);
    let mut full = 0;
    for (p, v) in pts.iter().zip(&r) {
        let want = direct(p[0], p[1]);
        full += usize::from(want == 500.0);
        assert_eq!(v.clone().unwrap(), want, "{p:?}");
    }
    assert!(full > 10, "some points run all 1000 steps ({full})");
    assert_eq!(m.runaway_loop(), None);
}

/// A loop with a fixed trip count of 100k (e.g. building a large union) is
/// lowered once and evaluates exactly.
#[test]
fn a_long_fixed_loop_is_lowered() {
    let src = "my_model(x[3], a[1]) { i = 1; u = 0; while i <= 100000 loop u = u + x[1]; \
               i = i + 1; endloop; my_model = u; }";
    let m = load(src, "f.hf", None).unwrap();
    assert!(m.lowered);
    assert_eq!(m.eval_points(&[[0.5, 0.0, 0.0]])[0], Ok(50_000.0));
}
