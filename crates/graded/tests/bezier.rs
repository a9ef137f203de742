//! Bernstein-Bezier fields: interpolation through samples, agreement with a
//! direct Bernstein sum, exact reproduction of polynomials on the
//! tetrahedron, the four-mode field check, and the CSV reader's errors.

use microfrep_core::field_check::{check_field, FieldCheck};
use microfrep_core::{Field, Interval};
use microfrep_graded::bezier::{
    collocation_condition, tet_index, tet_weight_count, BezierBox, BezierTet, MAX_DEGREE,
};
use microfrep_graded::csv::{parse_csv, read_csv, CsvMode};
use microfrep_graded::Error;
use std::sync::Arc;

struct Rng(u64);
impl Rng {
    fn unit(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn binom(n: usize, k: usize) -> f64 {
    (0..k).fold(1.0, |c, i| c * (n - i) as f64 / (i + 1) as f64)
}

/// The Bernstein sum written out from its definition (binomials and powers).
fn direct(w: &[f64], deg: [usize; 3], min: [f64; 3], max: [f64; 3], p: [f64; 3]) -> f64 {
    let u: [f64; 3] =
        std::array::from_fn(|a| ((p[a] - min[a]) / (max[a] - min[a])).clamp(0.0, 1.0));
    let b = |n: usize, i: usize, t: f64| {
        binom(n, i) * t.powi(i as i32) * (1.0 - t).powi((n - i) as i32)
    };
    let mut s = 0.0;
    for k in 0..=deg[2] {
        for j in 0..=deg[1] {
            for i in 0..=deg[0] {
                let wi = w[i + (deg[0] + 1) * (j + (deg[1] + 1) * k)];
                s += wi * b(deg[0], i, u[0]) * b(deg[1], j, u[1]) * b(deg[2], k, u[2]);
            }
        }
    }
    s
}

fn grid_point(min: [f64; 3], max: [f64; 3], deg: [usize; 3], q: usize) -> [f64; 3] {
    let idx = [
        q % (deg[0] + 1),
        (q / (deg[0] + 1)) % (deg[1] + 1),
        q / ((deg[0] + 1) * (deg[1] + 1)),
    ];
    std::array::from_fn(|a| min[a] + (max[a] - min[a]) * idx[a] as f64 / deg[a].max(1) as f64)
}

#[test]
fn interpolation_passes_through_every_sample_and_equals_the_bernstein_sum() {
    let mut rng = Rng(42);
    for deg in [[3, 3, 3], [1, 1, 1], [2, 4, 1], [5, 2, 3], [6, 6, 6]] {
        let (min, max) = ([-1.0, 0.5, 2.0], [1.5, 2.0, 2.25]);
        let count = (deg[0] + 1) * (deg[1] + 1) * (deg[2] + 1);
        let samples: Vec<f64> = (0..count).map(|_| 10.0 * rng.unit() - 3.0).collect();
        let range = samples.iter().copied().fold(f64::MIN, f64::max)
            - samples.iter().copied().fold(f64::MAX, f64::min);
        let f = BezierBox::interpolate("s", min, max, deg, &samples).unwrap();
        for (q, &s) in samples.iter().enumerate() {
            let p = grid_point(min, max, deg, q);
            assert!(
                (f.eval(p) - s).abs() <= 1e-9 * range,
                "deg {deg:?} sample {q}"
            );
        }
        for _ in 0..200 {
            let p: [f64; 3] =
                std::array::from_fn(|a| min[a] - 0.2 + (max[a] - min[a] + 0.4) * rng.unit());
            let want = direct(f.weights(), deg, min, max, p);
            assert!(
                (f.eval(p) - want).abs() <= 1e-12 * (1.0 + want.abs()),
                "{p:?}"
            );
        }
        let cond = f.conditioning().unwrap();
        for a in 0..3 {
            assert_eq!(cond[a], collocation_condition(deg[a]));
        }
    }
}

#[test]
fn collocation_conditioning_is_small_for_small_degrees() {
    let c: Vec<f64> = (0..=6).map(collocation_condition).collect();
    // The figures stated in the docs.
    assert!((c[0] - 1.0).abs() < 1e-12 && (c[1] - 1.0).abs() < 1e-12);
    assert!(
        (c[2] - 2.5).abs() < 1e-9 && (c[3] - 6.0).abs() < 1e-9,
        "{c:?}"
    );
    assert!((c[4] - 17.5).abs() < 0.05, "{c:?}");
    assert!(c[1..].windows(2).all(|w| w[1] > w[0]));
    let c10 = collocation_condition(10);
    assert!((5.8e3..6.0e3).contains(&c10), "{c10}");
    let cmax = collocation_condition(MAX_DEGREE);
    assert!(cmax < 1e7, "{cmax}");
}

#[test]
fn box_field_passes_the_four_mode_check() {
    let mut rng = Rng(7);
    let deg = [3, 2, 4];
    let n = (deg[0] + 1) * (deg[1] + 1) * (deg[2] + 1);
    let w: Vec<f64> = (0..n).map(|_| rng.unit() * 2.0 - 1.0).collect();
    let (min, max) = ([-1.0, -0.5, 0.0], [1.0, 0.5, 2.0]);
    let f: Arc<dyn Field> = Arc::new(BezierBox::new("b", min, max, deg, w).unwrap());
    // A region reaching past the box, where the clamp applies.
    let r = check_field(&f, &FieldCheck::new([[-1.3, -0.7, -0.3], [1.3, 0.7, 2.3]])).unwrap();
    assert!(r.points == 2000 && r.boxes == 300, "{r:?}");
    let interp = BezierBox::interpolate("i", min, max, [3, 3, 3], &vec![0.25; 64]).unwrap();
    // A constant sample set gives constant weights and a point bound.
    let b = interp.interval([Interval::new(-5.0, 5.0); 3]);
    assert!((b.lo - 0.25).abs() < 1e-12 && (b.hi - 0.25).abs() < 1e-12);
}

#[test]
fn box_bounds_tighten_on_sub_boxes() {
    // P = u on [0, 1]^3 (degree 3 in x, weights i/3): the bound over
    // x in [a, b] is exactly [a, b] (linear precision of the net).
    let mut w = Vec::new();
    for _k in 0..2 {
        for _j in 0..2 {
            for i in 0..4 {
                w.push(i as f64 / 3.0);
            }
        }
    }
    let f = BezierBox::new("u", [0.0; 3], [1.0; 3], [3, 1, 1], w).unwrap();
    let b = f.interval([
        Interval::new(0.25, 0.5),
        Interval::new(0.0, 1.0),
        Interval::new(0.3, 0.4),
    ]);
    assert!(
        (b.lo - 0.25).abs() < 1e-12 && (b.hi - 0.5).abs() < 1e-12,
        "{b:?}"
    );
    let g = f.grad_interval([
        Interval::new(0.25, 0.5),
        Interval::new(0.0, 1.0),
        Interval::new(0.0, 1.0),
    ]);
    assert!((g[0].lo - 1.0).abs() < 1e-12 && (g[0].hi - 1.0).abs() < 1e-12);
    assert!(g[1].lo.abs() < 1e-12 && g[1].hi.abs() < 1e-12);
    // Reaching outside the box on x: the clamped partial 0 is included.
    let g = f.grad_interval([
        Interval::new(0.9, 1.2),
        Interval::new(0.0, 1.0),
        Interval::new(0.0, 1.0),
    ]);
    assert!(g[0].lo <= 0.0 && g[0].hi >= 1.0);
}

/// Tetrahedron used in the tests.
const TET: [[f64; 3]; 4] = [
    [0.1, -0.2, 0.0],
    [1.3, 0.1, 0.2],
    [0.0, 1.1, -0.1],
    [0.2, 0.3, 0.9],
];

fn lambdas(p: [f64; 3]) -> [f64; 4] {
    // Solve p - v0 = sum l_r (v_r - v0) by Cramer's rule.
    let e: [[f64; 3]; 3] =
        std::array::from_fn(|r| std::array::from_fn(|c| TET[r + 1][c] - TET[0][c]));
    let d: [f64; 3] = std::array::from_fn(|c| p[c] - TET[0][c]);
    let det3 = |a: [f64; 3], b: [f64; 3], c: [f64; 3]| {
        a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
            + a[2] * (b[0] * c[1] - b[1] * c[0])
    };
    let det = det3(e[0], e[1], e[2]);
    let l1 = det3(d, e[1], e[2]) / det;
    let l2 = det3(e[0], d, e[2]) / det;
    let l3 = det3(e[0], e[1], d) / det;
    [1.0 - l1 - l2 - l3, l1, l2, l3]
}

#[test]
fn barycentric_field_reproduces_polynomials_of_its_degree() {
    let mut rng = Rng(99);
    for m in 0..=4usize {
        // q(p) = sum_r s_r (ell_r(p))^m with affine ell_r: by the multinomial
        // theorem its Bernstein weights are sum_r s_r prod_a c_ra^alpha_a
        // with c_ra = ell_r(v_a).
        let forms: Vec<(f64, [f64; 4])> = (0..4)
            .map(|_| {
                (
                    rng.unit() * 2.0 - 1.0,
                    std::array::from_fn(|_| rng.unit() * 2.0 - 1.0),
                )
            })
            .collect();
        let mut w = vec![0.0; tet_weight_count(m)];
        for i in 0..=m {
            for j in 0..=m - i {
                for k in 0..=m - i - j {
                    let l = m - i - j - k;
                    let idx = tet_index(m, i, j, k);
                    w[idx] = forms
                        .iter()
                        .map(|(s, c)| {
                            s * c[0].powi(l as i32)
                                * c[1].powi(i as i32)
                                * c[2].powi(j as i32)
                                * c[3].powi(k as i32)
                        })
                        .sum();
                }
            }
        }
        let f = BezierTet::new("t", TET, m, w).unwrap();
        for _ in 0..300 {
            let p: [f64; 3] = std::array::from_fn(|_| rng.unit() * 1.6 - 0.3);
            let lam = lambdas(p);
            let want: f64 = forms
                .iter()
                .map(|(s, c)| s * (0..4).map(|a| c[a] * lam[a]).sum::<f64>().powi(m as i32))
                .sum();
            assert!(
                (f.eval(p) - want).abs() < 1e-11 * (1.0 + want.abs()),
                "m {m} {p:?}"
            );
        }
        let f: Arc<dyn Field> = Arc::new(f);
        check_field(&f, &FieldCheck::new([[-0.2, -0.3, -0.2], [1.4, 1.2, 1.0]]))
            .unwrap_or_else(|e| panic!("degree {m}: {e}"));
    }
}

#[test]
fn tet_weights_follow_parks_summation_order() {
    let m = 3;
    let mut order = Vec::new();
    for i in 0..=m {
        for j in 0..=m - i {
            for k in 0..=m - i - j {
                order.push((i, j, k));
            }
        }
    }
    assert_eq!(order.len(), tet_weight_count(m));
    for (pos, &(i, j, k)) in order.iter().enumerate() {
        assert_eq!(tet_index(m, i, j, k), pos);
    }
    // Weight (i, j, k) is the value at its domain point for affine data: a
    // weight set of the x coordinate of the domain points reproduces x.
    let mut w = vec![0.0; order.len()];
    for &(i, j, k) in &order {
        let l = m - i - j - k;
        w[tet_index(m, i, j, k)] = (l as f64 * TET[0][0]
            + i as f64 * TET[1][0]
            + j as f64 * TET[2][0]
            + k as f64 * TET[3][0])
            / m as f64;
    }
    let f = BezierTet::new("x", TET, m, w).unwrap();
    for p in [[0.3, 0.2, 0.1], [2.0, -1.0, 0.5]] {
        assert!((f.eval(p) - p[0]).abs() < 1e-13);
    }
    // Inside the tetrahedron the bound is within the weights.
    let b = f.interval([
        Interval::new(0.35, 0.4),
        Interval::new(0.3, 0.35),
        Interval::new(0.2, 0.25),
    ]);
    assert!(b.lo >= 0.0 - 1e-12 && b.hi <= 1.3 + 1e-12, "{b:?}");
}

#[test]
fn bad_weights_degrees_boxes_and_tetrahedra_are_errors() {
    let e = BezierBox::new("b", [0.0; 3], [1.0; 3], [1, 1, 1], vec![0.0; 7]).unwrap_err();
    assert!(
        e.to_string()
            .contains("need (l+1)(m+1)(n+1) = 8 weights, got 7"),
        "{e}"
    );
    let e = BezierBox::new("b", [0.0; 3], [0.0, 1.0, 1.0], [1, 1, 1], vec![0.0; 8]).unwrap_err();
    assert!(e.to_string().contains("axis 0"), "{e}");
    let e = BezierBox::new("b", [0.0; 3], [1.0; 3], [17, 0, 0], vec![0.0; 18]).unwrap_err();
    assert!(e.to_string().contains("exceeds the limit"), "{e}");
    let mut w = vec![0.0; 8];
    w[3] = f64::NAN;
    let e = BezierBox::new("b", [0.0; 3], [1.0; 3], [1, 1, 1], w).unwrap_err();
    assert!(e.to_string().contains("weight 3"), "{e}");
    let flat = [[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]];
    let e = BezierTet::new("t", flat, 1, vec![0.0; 4]).unwrap_err();
    assert!(e.to_string().contains("degenerate"), "{e}");
    let e = BezierTet::new("t", TET, 2, vec![0.0; 9]).unwrap_err();
    assert!(e.to_string().contains("= 10 weights, got 9"), "{e}");
    // NaN points are NaN values, never a panic.
    let f = BezierBox::new("b", [0.0; 3], [1.0; 3], [1, 1, 1], vec![1.0; 8]).unwrap();
    assert!(f.eval([f64::NAN, 0.5, 0.5]).is_nan());
    assert!(f
        .interval([Interval::nan(), Interval::point(0.0), Interval::point(0.0)])
        .is_nan());
}

/// CSV text of the samples of `f` on the grid with `n` points per axis over
/// [0,1] x [0,2] x [-1,1], rows in the given order.
fn csv_of(n: [usize; 3], f: impl Fn([f64; 3]) -> f64, reverse: bool) -> String {
    let mut rows = Vec::new();
    for k in 0..n[2] {
        for j in 0..n[1] {
            for i in 0..n[0] {
                let p = [
                    i as f64 / (n[0] - 1) as f64,
                    2.0 * j as f64 / (n[1] - 1) as f64,
                    -1.0 + 2.0 * k as f64 / (n[2] - 1) as f64,
                ];
                rows.push(format!("{},{},{},{}", p[0], p[1], p[2], f(p)));
            }
        }
    }
    if reverse {
        rows.reverse();
    }
    format!("x,y,z,value\n{}\n", rows.join("\n"))
}

#[test]
fn csv_grid_interpolates_its_samples_in_any_row_order() {
    let f = |p: [f64; 3]| (3.0 * p[0]).sin() + p[1] * p[2] - 0.5 * p[2] * p[2];
    for reverse in [false, true] {
        let text = csv_of([4, 3, 5], f, reverse);
        let b = parse_csv(&text, "mem.csv", CsvMode::Interpolate).unwrap();
        assert_eq!(b.degrees(), [3, 2, 4]);
        assert_eq!(b.bounds(), ([0.0, 0.0, -1.0], [1.0, 2.0, 1.0]));
        for line in text.lines().skip(1) {
            let v: Vec<f64> = line.split(',').map(|s| s.parse().unwrap()).collect();
            assert!((b.eval([v[0], v[1], v[2]]) - v[3]).abs() < 1e-12, "{line}");
        }
    }
    // Weights mode: the values are the control net.
    let text = csv_of([2, 2, 2], |p| p[0] + p[1], false);
    let b = parse_csv(&text, "w.csv", CsvMode::Weights).unwrap();
    assert_eq!(b.weights(), &[0.0, 1.0, 2.0, 3.0, 0.0, 1.0, 2.0, 3.0]);
    // The bundled Fig. 1 data file reads and interpolates.
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples/data/park_fig1_bezier_4x4x4.csv");
    let b = read_csv(&path, CsvMode::Interpolate).unwrap();
    assert_eq!(b.degrees(), [3, 3, 3]);
}

fn csv_err(text: &str) -> (usize, String) {
    match parse_csv(text, "bad.csv", CsvMode::Interpolate) {
        Err(Error::Csv { line, message, .. }) => (line, message),
        Err(Error::CsvNumber {
            line, column, text, ..
        }) => (line, format!("number column {column} {text}")),
        Err(e) => panic!("unexpected error {e}"),
        Ok(_) => panic!("accepted {text:?}"),
    }
}

#[test]
fn irregular_csv_data_is_an_error_naming_the_line_and_what_is_expected() {
    let good = csv_of([2, 2, 2], |p| p[0], false);
    // Missing header.
    let (l, m) = csv_err(&good.replacen("x,y,z,value\n", "", 1));
    assert!(
        l == 1 && m.contains("missing header") && m.contains("x,y,z,value"),
        "{l} {m}"
    );
    let (l, m) = csv_err(&good.replacen("x,y,z,value", "x,y,value,z", 1));
    assert!(l == 1 && m.contains("header must be"), "{l} {m}");
    // Non-numeric value on line 4.
    let mut lines: Vec<String> = good.lines().map(String::from).collect();
    lines[3] = "0,2,-1,abc".into();
    let (l, m) = csv_err(&lines.join("\n"));
    assert!(
        l == 4 && m.contains("column 4") && m.contains("abc"),
        "{l} {m}"
    );
    let mut bad = lines.clone();
    bad[3] = "0,2,-1,nan".into();
    let (l, m) = csv_err(&bad.join("\n"));
    assert!(l == 4 && m.contains("finite"), "{l} {m}");
    // Wrong field count.
    let mut bad: Vec<String> = good.lines().map(String::from).collect();
    bad[5] = "1,0,1".into();
    let (l, m) = csv_err(&bad.join("\n"));
    assert!(l == 6 && m.contains("expected 4"), "{l} {m}");
    // Duplicate point: line 9 repeats line 2.
    let mut bad: Vec<String> = good.lines().map(String::from).collect();
    bad[8] = bad[1].clone();
    let (l, m) = csv_err(&bad.join("\n"));
    assert!(
        l == 9 && m.contains("duplicate") && m.contains("line 2"),
        "{l} {m}"
    );
    // Not a full grid: one point missing.
    let short: Vec<String> = good.lines().take(8).map(String::from).collect();
    let (_, m) = csv_err(&short.join("\n"));
    assert!(
        m.contains("not a full grid") && m.contains("missing"),
        "{m}"
    );
    // Irregular spacing on x.
    let text = "x,y,z,value\n0,0,0,1\n0.4,0,0,1\n1,0,0,1\n0,1,0,1\n0.4,1,0,1\n1,1,0,1\n\
                0,0,1,1\n0.4,0,1,1\n1,0,1,1\n0,1,1,1\n0.4,1,1,1\n1,1,1,1\n";
    let (l, m) = csv_err(text);
    assert!(
        l == 3 && m.contains("regular grid") && m.contains("equally spaced"),
        "{l} {m}"
    );
    // A single value on an axis, and no data at all.
    let (_, m) = csv_err("x,y,z,value\n0,0,0,1\n1,0,0,2\n");
    assert!(m.contains("single value"), "{m}");
    let (l, m) = csv_err("");
    assert!(l == 1 && m.contains("no data"), "{l} {m}");
    let (_, m) = csv_err("x,y,z,value\n");
    assert!(m.contains("no samples"), "{m}");
    // A missing file is an io error with the path.
    let e = read_csv(
        std::path::Path::new("/nonexistent/data.csv"),
        CsvMode::Weights,
    )
    .unwrap_err();
    assert!(matches!(e, Error::Io { .. }) && e.to_string().contains("/nonexistent/data.csv"));
}
