//! Each Fryazinov et al. figure model in `examples/` loads, evaluates and
//! shows the property its figure illustrates.
mod common;
use common::*;
use microfrep_core::frep::{normalize, union_all};
use microfrep_core::Expr;
use microfrep_mesh::check::check;
use microfrep_mesh::{MeshOptions, Plan};
use microfrep_shapes::{torus, v3};
use microfrep_structures::cell_report::cell_report;
use microfrep_structures::examples::toriball;
use microfrep_structures::replicate::{replicate, Wave};

const CELL: ([f64; 3], [f64; 3]) = ([-1.0; 3], [1.0; 3]);

#[test]
fn fig3_triangle_mirrors_every_second_cell_and_sawtooth_translates() {
    let file = "fryazinov_fig3_nonsymmetric_cell.hf";
    let cell = example(file, Some("cell"));
    let r = cell_report(&cell.value, CELL.0, CELL.1, 9, 1e-9).unwrap();
    assert!(!r.axes[0].symmetric && !r.axes[0].triangle_safe(), "{r:?}");
    assert!(r.geometric() && !r.full(), "{r:?}");
    let tri = Probe::new(&example(file, None));
    let saw = Probe::new(&example(file, Some("sawtooth")));
    let a = 0.5;
    for q in points([-1.0; 3], [1.0; 3], 300) {
        // Triangle: mirror image about the cell face x = a/2, period 2a.
        assert!((tri.at(q) - tri.at([a - q[0], q[1], q[2]])).abs() < 1e-9);
        assert!((tri.at(q) - tri.at(add(q, [2.0 * a, 0.0, 0.0]))).abs() < 1e-9);
        // Sawtooth: plain translation by one cell.
        assert!((saw.at(q) - saw.at(add(q, [a, 0.0, 0.0]))).abs() < 1e-9);
    }
    // The triangle copy of the next cell is not a translation.
    let q = [0.15, 0.05, 0.0];
    assert!((tri.at(q) - tri.at(add(q, [a, 0.0, 0.0]))).abs() > 0.1);
    // Both show the cell itself in the cell [-a/2, a/2]^3 (scaled by 4).
    let c = Probe::new(&cell);
    for q in points([-0.24; 3], [0.24; 3], 100) {
        let v = c.at(q.map(|t| 4.0 * t));
        assert!((tri.at(q) - v).abs() < 1e-9 && (saw.at(q) - v).abs() < 1e-9);
    }
}

#[test]
fn fig4_toriball_block_matches_algorithm_1_and_meshes_watertight() {
    let m = example("fryazinov_fig4_toriball_block.hf", None);
    let p = Probe::new(&m);
    let r = Probe::of(&toriball());
    for q in points([-1.1; 3], [1.1; 3], 500) {
        assert!((p.at(q) - r.at(q)).abs() < 1e-9, "{q:?}");
    }
    // 1000 balls: the centre of each cell (0.2 apart) is a torus hole.
    assert!(!p.inside([0.0; 3]) && !p.inside([0.4, -0.2, 0.6]));
    // The tube of the x torus of the centre cell, at radius 0.8 * 0.1.
    assert!(p.inside([0.0, 0.08, 0.0]));
    let mesh = Plan::new(&m.shape(), &MeshOptions::new([[-1.0; 3], [1.0; 3]], 64))
        .unwrap()
        .run(&|_| {})
        .unwrap();
    let c = check(&mesh);
    assert!(c.is_closed_manifold() && c.triangles > 100_000, "{c:?}");
}

/// `a & b` with HyperFun's R0 intersection.
fn r0_and(a: f64, b: f64) -> f64 {
    a + b - (a * a + b * b).sqrt()
}

/// hfBlock `[-10, 10]^3` at `q`.
fn block10(q: [f64; 3]) -> f64 {
    let s: Vec<f64> = q.iter().map(|c| (c + 10.0) * (10.0 - c)).collect();
    r0_and(r0_and(s[0], s[1]), s[2])
}

/// Union (R0) of the three tori at a cell point.
fn tori_at(q: [f64; 3]) -> f64 {
    let p = v3(q);
    let c = v3([0.0; 3]);
    let t: Vec<Expr> = (0..3).map(|a| torus(&p, &c, a, 0.8, 0.2)).collect();
    Probe::of(&union_all(&t, 0.0)).at([0.0; 3])
}

#[test]
fn fig5_cell_metamorphoses_from_ball_to_tori_along_z() {
    let p = Probe::new(&example("fryazinov_fig5_metamorphosis.hf", None));
    // Cell centres (mapped point 0) at even coordinates.
    for z in [-8.0, -4.0, 0.0, 4.0, 8.0] {
        let t = (z + 10.0) / 20.0;
        let q = [2.0, -6.0, z];
        let want = r0_and((1.0 - t) * 0.81 + t * tori_at([0.0; 3]), block10(q));
        assert!((p.at(q) - want).abs() < 1e-9, "z {z}");
    }
    assert!(p.inside([0.0, 0.0, -8.0]) && !p.inside([0.0, 0.0, 8.0]));
    // Near the top the cell is the tori: inside on a torus tube.
    assert!(p.inside([0.0, 0.8, 8.0]) && p.inside([0.0, 0.8, 9.99]));
    // Near the bottom it is the ball: inside off the tubes too.
    assert!(p.inside([0.3, 0.3, -9.99]) && !p.inside([0.3, 0.3, 9.99]));
    assert!(!p.inside([0.0, 0.0, 20.0]) && !p.inside([10.5, 0.0, 0.0]));
}

#[test]
fn fig6_cells_are_smaller_near_the_shell() {
    let p = Probe::new(&example("fryazinov_fig6_period_by_shell_distance.hf", None));
    // Crossings per unit length on circles (z = 0.01) at two depths.
    let rate = |r: f64| {
        let n = crossings(&p, 20_000, |t| {
            let a = 2.0 * std::f64::consts::PI * t;
            [r * a.cos(), r * a.sin(), 0.01]
        });
        n as f64 / (2.0 * std::f64::consts::PI * r)
    };
    let (near, deep) = (rate(0.85), rate(0.3));
    // Periods 0.225 and 0.45: about twice the rate near the surface.
    assert!(near > 1.5 * deep && deep > 0.0, "near {near}, deep {deep}");
    // The outer shell 0.05 thick is solid.
    for d in points([-1.0; 3], [1.0; 3], 50) {
        let n = norm(d);
        assert!(p.inside(d.map(|c| c / n * 0.97)) && !p.inside(d.map(|c| c / n * 1.02)));
    }
}

fn ball(c: [f64; 3], r: f64, count: usize) -> Vec<[f64; 3]> {
    points([-r; 3], [r; 3], count)
        .into_iter()
        .filter(|q| norm(*q) < r)
        .map(|q| add(q, c))
        .collect()
}

#[test]
fn fig7_transfinite_period_and_shape() {
    let file = "fryazinov_fig7_transfinite.hf";
    for cell in ["hexcell", "rhombcell"] {
        let r = cell_report(&example(file, Some(cell)).value, CELL.0, CELL.1, 9, 1e-9).unwrap();
        assert!(r.symmetric(), "{cell}: {r:?}");
    }
    let hex = Probe::new(&example(file, Some("hexagonal")));
    let per = Probe::new(&example(file, Some("periods")));
    let shape = Probe::new(&example(file, None));
    let (c1, c2) = ([-3.0, 0.0, 0.0], [3.0, 0.0, 0.0]);
    // (c) triangle period 2 * 0.5 on x and y.
    for q in points([-2.0, -2.0, -0.1], [2.0, 2.0, 0.1], 200) {
        assert!((hex.at(q) - hex.at(add(q, [1.0, 0.0, 0.0]))).abs() < 1e-9);
        assert!((hex.at(q) - hex.at(add(q, [0.0, -1.0, 0.0]))).abs() < 1e-9);
    }
    // (d) inside partition 1 the period is 0.5 (hexagonal structure), in
    // partition 2 it is 1 (repeats every 2).
    for q in ball(c1, 1.5, 400) {
        let q = [q[0], q[1], q[2] * 0.05];
        assert!((per.at(q) - hex.at(q)).abs() < 1e-9, "{q:?}");
        // (e) the cell shape is hexagonal there.
        assert!((shape.at(q) - hex.at(q)).abs() < 1e-9, "{q:?}");
    }
    let rhomb = |q: [f64; 3]| {
        let w = Wave::Triangle(Expr::constant(0.5));
        let m = replicate(&v3(q), &[w.clone(), w, Wave::Identity], CELL.0, CELL.1);
        let m = Probe::of(&(m[0].abs() + m[1].abs())).at([0.0; 3]);
        (0.12 - (m - 0.85).abs()).min(0.1 - q[2].abs())
    };
    let mut checked = 0;
    for q in ball(c2, 1.5, 400) {
        let q = [q[0], q[1], q[2] * 0.05];
        let q2 = add(q, [0.0, 2.0, 0.0]);
        if norm(add(q2, [-3.0, 0.0, 0.0])) < 1.5 {
            assert!((per.at(q) - per.at(q2)).abs() < 1e-9, "{q:?}");
            checked += 1;
        }
        // Rhombic cells: same sign as the rhombic structure (min of the
        // ring and the plate, R0 differs in value only).
        assert_eq!(shape.inside(q), rhomb(q) >= 0.0, "{q:?}");
    }
    assert!(checked > 10);
    // Between the partitions the period is in between: crossings along y.
    let rate = |x: f64, p: &Probe| crossings(p, 4000, |t| [x, -2.0 + 4.0 * t, 0.0]);
    let (r1, r0, r2) = (rate(-3.0, &per), rate(0.0, &per), rate(3.0, &per));
    assert!(r1 > r0 && r0 > r2, "{r1} {r0} {r2}");
}

#[test]
fn fig7_weights_sum_to_one_and_pick_their_partition() {
    let src = "my_model(x[3], a[1]) { array d[2];
        d[1] = mfPartDist(1.5 - sqrt((x[1] + 3)^2 + x[2]^2 + x[3]^2));
        d[2] = mfPartDist(1.5 - sqrt((x[1] - 3)^2 + x[2]^2 + x[3]^2));
        my_model = mfTfWeight(d, 1) + 10 * mfTfWeight(d, 2); }";
    let p = Probe::new(&load_src(src, "weights", None));
    for q in points([-6.0; 3], [6.0; 3], 500) {
        let v = p.at(q);
        // v = W1 + 10 W2 with W1 + W2 = 1: W2 = (v - 1)/9 in [0, 1].
        let w2 = (v - 1.0) / 9.0;
        assert!((-1e-12..=1.0 + 1e-12).contains(&w2), "{q:?}: {v}");
        if norm(add(q, [3.0, 0.0, 0.0])) < 1.5 {
            assert!((v - 1.0).abs() < 1e-12);
        }
        if norm(add(q, [-3.0, 0.0, 0.0])) < 1.5 {
            assert!((v - 10.0).abs() < 1e-12);
        }
    }
    // Half way between, by symmetry, equal weights.
    assert!((p.at([0.0, 1.0, 0.5]) - 5.5).abs() < 1e-9);
}

#[test]
fn fig8_microstructure_left_torus_right() {
    let p = Probe::new(&example("fryazinov_fig8_morph_to_torus.hf", None));
    // Right end: t = 1, the torus (radii 6 and 3 around z).
    let big = |q: [f64; 3]| {
        let rho = (q[0] * q[0] + q[1] * q[1]).sqrt();
        9.0 - (rho - 6.0).powi(2) - q[2] * q[2]
    };
    for q in points([9.99, -9.9, -9.9], [9.999, 9.9, 9.9], 200) {
        assert_eq!(p.inside(q), big(q) >= 0.0, "{q:?}");
    }
    // Left end: t = 0, the tori-ball cells (width 2): the centre of a cell is
    // a hole, the tube of its x torus is material.
    assert!(!p.inside([-9.99, 0.0, 0.0]) && !p.inside([-9.99, 4.0, -2.0]));
    assert!(p.inside([-9.99, 0.8, 0.0]) && p.inside([-9.99, 4.8, 2.0]));
    // In the middle the value is the average of both.
    let t = 0.5;
    let q = [0.0, 0.8, 0.0];
    let want = r0_and(
        (1.0 - t) * tori_at([0.0, 0.8, 0.0]) + t * big(q),
        block10(q),
    );
    assert!((p.at(q) - want).abs() < 1e-9);
}

#[test]
fn fig9_nested_filter_is_periodic_at_both_scales() {
    let file = "fryazinov_fig9_nested_filter.hf";
    let fine = example(file, Some("fine"));
    let r = cell_report(&fine.value, CELL.0, CELL.1, 9, 1e-9).unwrap();
    assert!(r.full() && r.symmetric(), "{r:?}");
    let f = Probe::new(&fine);
    let coarse = Probe::new(&example(file, Some("coarse")));
    let m = Probe::new(&example(file, None));
    for q in points([-3.0; 3], [3.0; 3], 300) {
        assert!((coarse.at(q) - coarse.at(add(q, [2.0, -4.0, 2.0]))).abs() < 1e-9);
    }
    // The fine scale inside a coarse cell: same inside/outside a fine period
    // apart, where the frame is absent.
    let frame = |q: [f64; 3]| {
        let s = |a: f64, b: f64| a * a + b * b < 0.15 * 0.15 + 1e-9;
        s(q[1], q[2]) || s(q[0], q[2]) || s(q[0], q[1])
    };
    let mut n = 0;
    for q in points([-0.4; 3], [0.4; 3], 600) {
        let q2 = add(q, [0.25, 0.0, 0.0]);
        if norm(q2) < 0.75 && !frame(q) && !frame(q2) {
            assert_eq!(f.inside(q), f.inside(q2), "{q:?}");
            n += 1;
        }
    }
    assert!(n > 100);
    // The filter: the rim is solid, nothing beyond radius 7 or |z| 1.
    assert!(m.inside([6.75, 0.0, 0.0]) && m.inside([0.0, -6.8, 0.5]));
    assert!(!m.inside([7.2, 0.0, 0.0]) && !m.inside([1.0, 1.0, 1.1]));
    // Inside, the coarse structure shows through.
    for q in points([-4.0, -4.0, -0.9], [4.0, 4.0, 0.9], 300) {
        assert_eq!(m.inside(q), coarse.inside(q), "{q:?}");
    }
}

#[test]
fn fig10_surficial_structures_hug_both_surfaces() {
    let file = "fryazinov_fig10_surficial.hf";
    let vase = Probe::new(&example(file, Some("vase")));
    let cells = Probe::new(&example(file, Some("cells")));
    let constant = Probe::new(&example(file, None));
    let normalised = Probe::new(&example(file, Some("normalised")));
    let pts = points([-1.5, -1.5, -1.6], [1.5, 1.5, 1.6], 300_000);
    let (vv, vc) = (vase.values(&pts), cells.values(&pts));
    let (v1, v2) = (constant.values(&pts), normalised.values(&pts));
    // Distance-like versions of both functions.
    let nv = Probe::of(&normalize(&example(file, Some("vase")).value)).values(&pts);
    let nc = Probe::of(&normalize(&example(file, Some("cells")).value)).values(&pts);
    let (mut n1, mut n2, mut near) = (0, 0, 0);
    for i in 0..pts.len() {
        if v1[i] >= 0.0 {
            // Eq. 12-13 with R0: g + d >= 0 only where f1^2 <= d and f2^2 <= d.
            assert!(vv[i].powi(2) <= 0.001 + 1e-12 && vc[i].powi(2) <= 0.001 + 1e-12);
            n1 += 1;
        }
        if v2[i] >= 0.0 {
            n2 += 1;
            // Near both surfaces in (normalised) distance. The normalised
            // offset is not a constant-radius tube (the paper's remark on
            // badly behaved gradients: near the ball centres the cell
            // function is flat), so only most of it is.
            near += (nv[i].abs() < 0.1 && nc[i].abs() < 0.1) as usize;
        }
    }
    assert!(near as f64 > 0.9 * n2 as f64, "{near} of {n2}");
    assert!(n1 > 50 && n2 > 50, "{n1} {n2}");
}

#[test]
fn fig11_shell_with_holes() {
    let p = Probe::new(&example("fryazinov_fig11_shell_minus_cells.hf", None));
    let torus_f = |q: [f64; 3]| {
        let rho = (q[0] * q[0] + q[1] * q[1]).sqrt();
        0.64 - q[0] * q[0] - q[1] * q[1] - q[2] * q[2] - 4.0 + 4.0 * rho
    };
    let pts = points([-3.2, -3.2, -1.2], [3.2, 3.2, 1.2], 100_000);
    let v = p.values(&pts);
    let (mut shell, mut kept) = (0, 0);
    for (q, &f) in pts.iter().zip(&v) {
        let t = torus_f(*q);
        if f >= 0.0 {
            assert!((-0.3..0.0).contains(&t), "{q:?}: {t}");
        }
        if (-0.3..0.0).contains(&t) {
            shell += 1;
            kept += (f >= 0.0) as usize;
        }
    }
    let share = kept as f64 / shell as f64;
    assert!(
        shell > 1000 && (0.2..0.95).contains(&share),
        "{kept} of {shell}"
    );
}
