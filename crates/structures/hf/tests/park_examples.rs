//! Each Park, Crawford, Beaman figure model in `examples/` loads, evaluates
//! and shows the property of its figure: the geometry directly, the graded
//! material through its attribute channels `s1`, `s2` (the model's `s[k]`,
//! channels of its `Shape`), checked against the graded crate's functions.
//! The channels are also checked against a probe object appended to the
//! source that returns `s[k]` as its value.
mod common;
use common::*;
use microfrep_core::{BatchEval, Field, PointEval, Shape};
use microfrep_graded::csv::{read_csv, CsvMode};
use microfrep_graded::dmf::{bias_value, gain_value};
use microfrep_mesh::check::check;
use microfrep_mesh::{MeshOptions, Plan};

fn source(file: &str) -> String {
    let path = examples_dir().join(file);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path:?}: {e}"))
}

/// A probe object for attribute `k` (1-based) of `my_model` with `n`
/// attributes: the attribute as the value of another object.
fn probe(file: &str, n: usize, k: usize) -> Probe {
    let src = format!(
        "{}\nprobe_s(x[3], a[1], s[{n}]) {{\n  v = my_model(x, a, s);\n  probe_s = s[{k}];\n}}\n",
        source(file)
    );
    Probe::new(&load_src(&src, file, Some("probe_s")))
}

/// One attribute channel of a model's shape, evaluated in f64.
struct Channel {
    shape: Shape,
    k: usize,
}

impl Channel {
    /// The value of the channel at `p`; an error or NaN fails the test.
    fn at(&self, p: [f64; 3]) -> f64 {
        let out = PointEval::new(self.shape.outputs()).eval_all(p);
        if let Some(e) = self.shape.error_output() {
            assert_eq!(out[e], 0.0, "run-time error at {p:?}");
        }
        let v = out[self.shape.attribute_output(self.k)];
        assert!(v.is_finite(), "s{} = {v} at {p:?}", self.k + 1);
        v
    }
}

/// Channels `s1` and `s2` of an example, as the CLI's consumers see them.
fn attrs(file: &str) -> (Channel, Channel) {
    let shape = example(file, None).shape();
    let names: Vec<&str> = shape.attributes().iter().map(|a| a.name.as_str()).collect();
    assert_eq!(names, ["s1", "s2"], "{file}");
    let ch = |k| Channel {
        shape: shape.clone(),
        k,
    };
    (ch(0), ch(1))
}

/// Channel values of the four graded figures equal the probe object's
/// (the same numbers by another path through the interpreter), and the
/// batch evaluator agrees to f32 precision.
#[test]
fn attribute_channels_match_probe_objects_and_batch() {
    let boxes = [
        (
            "park_fig1_bezier_cube.hf",
            [-1.0, -1.0, -1.0],
            [1.0, 1.0, 1.0],
        ),
        ("park_fig2_bias_gain.hf", [0.0, 0.0, 0.0], [5.5, 1.0, 1.0]),
        ("park_fig4_wiffle_gradient.hf", [-2.2; 3], [2.2; 3]),
        (
            "park_fig6_femur_gradient.hf",
            [-1.3, -3.0, -0.9],
            [1.6, 4.3, 0.9],
        ),
    ];
    for (file, lo, hi) in boxes {
        let (s1, s2) = attrs(file);
        let (p1, p2) = (probe(file, 2, 1), probe(file, 2, 2));
        let pts = points(lo, hi, 300);
        for &q in &pts {
            if norm(q) < 0.1 {
                continue; // the wiffle's 1/r^12 term
            }
            assert_eq!(s1.at(q).to_bits(), p1.at(q).to_bits(), "{file} s1 at {q:?}");
            assert_eq!(s2.at(q).to_bits(), p2.at(q).to_bits(), "{file} s2 at {q:?}");
        }
        let pts: Vec<[f64; 3]> = pts
            .iter()
            .map(|q| q.map(|c| c as f32 as f64))
            .filter(|q| norm(*q) >= 0.1)
            .collect();
        let lanes = |a: usize| pts.iter().map(|q| q[a] as f32).collect::<Vec<f32>>();
        let mut out = vec![0.0f32; pts.len()];
        let tape = s2.shape.outputs();
        BatchEval::new(tape).eval_output(
            s2.shape.attribute_output(1),
            &lanes(0),
            &lanes(1),
            &lanes(2),
            &mut out,
        );
        for (q, b) in pts.iter().zip(out) {
            let want = s2.at(*q);
            assert!(
                (b as f64 - want).abs() < 1e-4,
                "{file} batch s2 {b} vs {want} at {q:?}"
            );
        }
    }
}

fn sketch(t: f64, b: f64, g: f64) -> f64 {
    gain_value(bias_value(t, b), g)
}

#[test]
fn fig1_bezier_cube_passes_through_the_64_samples() {
    let file = "park_fig1_bezier_cube.hf";
    let geo = Probe::new(&example(file, None));
    assert!(geo.inside([0.0, 0.0, 0.0]) && geo.inside([0.95, -0.95, 0.95]));
    assert!(!geo.inside([1.05, 0.0, 0.0]) && !geo.inside([0.0, 0.0, -1.05]));
    let (s1, s2) = attrs(file);
    // The CSV read independently gives the same polynomial.
    let csv = examples_dir().join("data/park_fig1_bezier_4x4x4.csv");
    let field = read_csv(&csv, CsvMode::Interpolate).unwrap();
    let text = std::fs::read_to_string(&csv).unwrap();
    for line in text.lines().filter(|l| !l.starts_with('#')).skip(1) {
        let v: Vec<f64> = line.split(',').map(|t| t.parse().unwrap()).collect();
        let p = [2.0 * v[0] - 1.0, 2.0 * v[1] - 1.0, 1.0 - 0.5 * v[2]];
        // Through every sample (relative to the data range, about 0.9).
        assert!((s2.at(p) - v[3]).abs() < 1e-9, "{line}: {}", s2.at(p));
        assert!((s1.at(p) + s2.at(p) - 1.0).abs() < 1e-12);
    }
    for q in points([-1.0, -1.0, 0.5], [1.0, 1.0, 1.0], 300) {
        let u = [(q[0] + 1.0) / 2.0, (q[1] + 1.0) / 2.0, (1.0 - q[2]) / 0.5];
        let want = field.eval(u).clamp(0.0, 1.0);
        assert!((s2.at(q) - want).abs() < 1e-9, "{q:?}");
    }
    // Below the prescribed depth: homogeneous primary material.
    for q in points([-1.0, -1.0, -1.0], [1.0, 1.0, 0.49], 200) {
        assert_eq!((s1.at(q), s2.at(q)), (1.0, 0.0));
    }
}

#[test]
fn fig2_each_cube_follows_its_bias_and_gain() {
    let file = "park_fig2_bias_gain.hf";
    let geo = Probe::new(&example(file, None));
    let (_, s2) = attrs(file);
    let cubes = [
        (0.0, 0.25, 0.5),
        (1.5, 0.75, 0.5),
        (3.0, 0.5, 0.2),
        (4.5, 0.5, 0.85),
    ];
    for (x0, b, g) in cubes {
        assert!(geo.inside([x0 + 0.5, 0.5, 0.5]) && !geo.inside([x0 + 1.25, 0.5, 0.5]));
        for k in 0..=20 {
            let t = 0.02 + 0.96 * k as f64 / 20.0;
            let got = s2.at([x0 + 0.3, 0.6, t]);
            assert!((got - sketch(t, b, g)).abs() < 1e-12, "cube {x0} t {t}");
        }
        // The defining values: bias(0.5) = b with g = 0.5; gain(0.25) =
        // 0.5 - g/2 with b = 0.5.
        if g == 0.5 {
            assert!((s2.at([x0 + 0.5, 0.5, 0.5]) - b).abs() < 1e-12);
        } else {
            assert!((s2.at([x0 + 0.5, 0.5, 0.25]) - (0.5 - g / 2.0)).abs() < 1e-12);
        }
    }
}

fn wiffle(p: [f64; 3]) -> f64 {
    let r2 = p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
    let q8: f64 = p.iter().map(|c| c.powi(8)).sum();
    1.0 - (0.43f64.powi(2) * r2).powi(-6) - (0.5f64.powi(8) * q8).powi(6)
}

#[test]
fn fig3_wiffle_cube_is_a_rounded_cube_with_holes_through_the_faces() {
    let m = example("park_fig3_wiffle_cube.hf", None);
    let p = Probe::new(&m);
    for q in points([-2.2; 3], [2.2; 3], 300) {
        if norm(q) > 0.1 {
            assert!((p.at(q) - wiffle(q)).abs() <= 1e-9 * wiffle(q).abs().max(1.0));
        }
    }
    // Along each axis the sphere (r < 2.33) meets the cube (|x| < 2): no
    // material, the holes of the figure; along the diagonals, material.
    for axis in 0..3 {
        assert_eq!(
            crossings(&p, 400, |t| {
                let mut q = [0.0; 3];
                q[axis] = 0.01 + 2.5 * t;
                q
            }),
            0
        );
        let mut q = [0.0; 3];
        q[axis] = 2.1;
        assert!(!p.inside(q));
    }
    assert!(p.inside([1.5, 1.5, 1.5]) && p.inside([1.9, 1.4, 0.3]));
    assert!(!p.inside([1.0, 1.0, 1.0]) && !p.inside([2.2, 2.2, 2.2]));
    // Watertight through the mesher.
    let mesh = Plan::new(&m.shape(), &MeshOptions::new([[-2.2; 3], [2.2; 3]], 48))
        .unwrap()
        .run(&|_| {})
        .unwrap();
    let r = check(&mesh);
    assert!(r.is_closed_manifold() && r.volume > 1.0, "{r:?}");
    let vol = fraction(&p, &points([-2.2; 3], [2.2; 3], 100_000)) * 4.4f64.powi(3);
    assert!((r.volume - vol).abs() / vol < 0.05, "{} vs {vol}", r.volume);
}

#[test]
fn fig4_spherical_gradient_is_densest_at_the_inner_surface() {
    let file = "park_fig4_wiffle_gradient.hf";
    let geo = Probe::new(&example(file, None));
    let (_, s2) = attrs(file);
    let (r0, r1) = (1.0 / 0.43, 3.05);
    let dir = [0.6, 0.55, 0.58];
    let n = norm(dir);
    let mut last = f64::INFINITY;
    for k in 0..=30 {
        let r = r0 + (r1 - r0) * k as f64 / 30.0;
        let q = dir.map(|c| c / n * r);
        let got = s2.at(q);
        let t = (r1 - r) / (r1 - r0);
        assert!((got - sketch(t, 0.35, 0.7)).abs() < 1e-9, "r {r}");
        assert!(got <= last + 1e-15);
        last = got;
    }
    assert!((s2.at(dir.map(|c| c / n * r0)) - 1.0).abs() < 1e-9);
    assert!(s2.at(dir.map(|c| c / n * r1)).abs() < 1e-12);
    // The geometry is Fig. 3's.
    for q in points([-2.2; 3], [2.2; 3], 200) {
        if norm(q) > 0.1 {
            assert_eq!(geo.inside(q), wiffle(q) >= 0.0);
        }
    }
}

#[test]
fn fig5_femur_union_a_is_parks_blend() {
    let file = "park_fig5_femur_implant.hf";
    let m = example(file, None);
    let ours = Probe::new(&m);
    let park = Probe::new(&example(file, Some("park_literal")));
    // ours = U - 1 and Park's (negated) 1 - 1/U: the same surface, and
    // U recovered from either agrees.
    for q in points([-1.3, -3.0, -0.9], [1.6, 4.3, 0.9], 2000) {
        let (a, b) = (ours.at(q), park.at(q));
        assert_eq!(a >= 0.0, b >= 0.0, "{q:?}");
        let (u1, u2) = (a + 1.0, 1.0 / (1.0 - b));
        assert!((u1 - u2).abs() <= 1e-9 * u1, "{q:?}: {u1} {u2}");
    }
    assert!(ours.inside([0.0, 0.0, 0.0]) && ours.inside([0.0, -2.0, 0.0]));
    assert!(ours.inside([0.6, 3.4, 0.0]) && ours.inside([0.0, 2.0, 0.0]));
    assert!(!ours.inside([0.7, 0.0, 0.0]) && !ours.inside([0.0, -3.0, 0.0]));
    let mesh = Plan::new(
        &m.shape(),
        &MeshOptions::new([[-1.3, -3.0, -0.9], [1.6, 4.3, 0.9]], 48),
    )
    .unwrap()
    .run(&|_| {})
    .unwrap();
    let r = check(&mesh);
    assert!(r.is_closed_manifold(), "{r:?}");
}

/// Depth of the surface below `from` along `dir`: the first `t` where the
/// model is outside.
fn surface_along(p: &Probe, from: [f64; 3], dir: [f64; 3]) -> f64 {
    let (mut lo, mut hi) = (0.0, 2.0);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if p.inside(add(from, dir.map(|c| c * mid))) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

#[test]
fn fig6_femur_has_a_primary_shell_of_constant_depth() {
    let file = "park_fig6_femur_gradient.hf";
    let geo = Probe::new(&example(file, None));
    let (s1, s2) = attrs(file);
    // Rays from inside the stem (several heights and directions) and from
    // the head's centre: the secondary material starts at depth 0.1.
    let mut rays = Vec::new();
    for y in [-1.5, -0.5, 0.5] {
        for a in 0..6 {
            let ang = a as f64 * std::f64::consts::PI / 3.0;
            rays.push(([0.0, y, 0.0], [ang.cos(), 0.0, ang.sin()]));
        }
    }
    for a in 0..5 {
        let ang = 0.3 + a as f64 * 0.6;
        rays.push((
            [0.6, 3.4, 0.0],
            [ang.cos() * 0.6, ang.sin(), 0.8 * ang.cos()],
        ));
    }
    for (from, dir) in rays {
        let n = norm(dir);
        let dir = dir.map(|c| c / n);
        let surf = surface_along(&geo, from, dir);
        // Walk in from the surface: where does s[2] become positive?
        let mut start = None;
        for k in 0..=400 {
            let d = 0.4 * k as f64 / 400.0;
            let q = add(from, dir.map(|c| c * (surf - d)));
            let (a, b) = (s1.at(q), s2.at(q));
            assert!((a + b - 1.0).abs() < 1e-12);
            if b > 0.0 && start.is_none() {
                start = Some(d);
            }
        }
        let start = start.expect("secondary material below the shell");
        assert!(
            (start - 0.1).abs() < 0.012,
            "{from:?} {dir:?}: shell {start}"
        );
    }
    // The core is all titanium, the very surface all ceramic.
    assert!(s2.at([0.0, 0.0, 0.0]) > 0.99);
    assert_eq!(s2.at([0.49, 0.0, 0.0]), 0.0);
}

/// `n` directions spread over the unit sphere (Fibonacci lattice).
fn directions(n: usize) -> Vec<[f64; 3]> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let r = (1.0 - z * z).sqrt();
            let t = golden * i as f64;
            [r * t.cos(), r * t.sin(), z]
        })
        .collect()
}

/// Fig. 6 through its channels over the whole part: the fractions sum to
/// 1 (and lie in [0, 1] inside); the secondary material is 0 within depth
/// 0.1 of the surface (a point with s[2] > 0 has a ball of radius 0.088
/// inside the part around it) and present deeper down. `mfDepth` is exact
/// only near a single quadric: in the blend where the neck meets the stem
/// (y about 2.4 to 2.6) it reads up to a third short, so the shell is up to
/// about 0.15 thick there; a point whose ball of radius 0.16 lies inside
/// always has s[2] > 0.
#[test]
fn fig6_channels_hold_the_shell_everywhere() {
    let file = "park_fig6_femur_gradient.hf";
    let m = example(file, None);
    let geo = Probe::new(&m);
    let (s1, s2) = attrs(file);
    let dirs = directions(200);
    let ball_inside = |c: [f64; 3], r: f64| {
        let pts: Vec<[f64; 3]> = dirs.iter().map(|d| add(c, d.map(|v| v * r))).collect();
        geo.values(&pts).iter().all(|&v| v >= 0.0)
    };
    let (mut inside, mut graded, mut shell, mut deep) = (0, 0, 0, 0);
    for q in points([-1.3, -3.0, -0.9], [1.6, 4.3, 0.9], 6000) {
        let (a, b) = (s1.at(q), s2.at(q));
        assert!((a + b - 1.0).abs() < 1e-12, "{q:?}: {a} + {b}");
        if !geo.inside(q) {
            continue;
        }
        inside += 1;
        assert!((0.0..=1.0).contains(&b), "{q:?}: s2 = {b}");
        if b > 0.0 {
            graded += 1;
            assert!(
                ball_inside(q, 0.088),
                "{q:?}: s2 = {b} within 0.088 of the surface"
            );
        } else {
            shell += 1;
        }
        if ball_inside(q, 0.16) {
            deep += 1;
            assert!(b > 0.0, "{q:?}: depth over 0.16 but s2 = 0");
        }
    }
    // Every kind of point was met.
    assert!(
        inside > 300 && graded > 100 && shell > 50 && deep > 50,
        "{inside} {graded} {shell} {deep}"
    );
}
