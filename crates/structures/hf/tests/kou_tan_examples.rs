//! Each Kou and Tan 2013 figure model in `examples/` loads, evaluates and
//! shows the property its figure illustrates.
mod common;
use common::*;
use microfrep_core::{Expr, ExprNode};
use microfrep_mesh::check::check;
use microfrep_mesh::{MeshOptions, Plan};

/// The pore count in the name of the pore field of a model.
fn pore_count(e: &Expr) -> usize {
    let mut stack = vec![e.clone()];
    while let Some(e) = stack.pop() {
        if let ExprNode::Field { field, .. } = e.node() {
            let name = field.name();
            let n = name
                .split(", ")
                .nth(1)
                .and_then(|s| s.strip_suffix(" pores"));
            return n
                .and_then(|n| n.parse().ok())
                .unwrap_or_else(|| panic!("{name}"));
        }
        stack.extend(e.children().into_iter().cloned());
    }
    panic!("no pore field in the model")
}

/// Share of `pts` in the pores (outside the solid).
fn pore_fraction(p: &Probe, pts: &[[f64; 3]]) -> f64 {
    1.0 - fraction(p, pts)
}

#[test]
fn fig12_plates_have_their_porosities_and_closed_pores() {
    let file = "kou_tan_fig12_2d_porosity.hf";
    let pts = points([0.0; 3], [4.0, 4.0, 0.5], 60_000);
    let mut last = 0.0;
    for (object, target) in [("p40", 0.4), ("p50", 0.5), ("p60", 0.6), ("p70", 0.7)] {
        let m = example(file, Some(object));
        assert_eq!(pore_count(&m.value), 64, "{object}");
        let p = Probe::new(&m);
        let por = pore_fraction(&p, &pts);
        assert!((por - target).abs() < 0.01, "{object}: {por}");
        assert!(por > last + 0.08);
        last = por;
        // Closed pores: the cell corners inside the plate are solid.
        for i in 1..8 {
            for j in 1..8 {
                assert!(p.inside([0.5 * i as f64, 0.5 * j as f64, 0.25]), "{object}");
            }
        }
        // Extruded along z.
        for q in points([0.1, 0.1, 0.05], [3.9, 3.9, 0.05], 500) {
            assert_eq!(p.inside(q), p.inside([q[0], q[1], 0.45]));
        }
    }
    // my_model is p40.
    let m = Probe::new(&example(file, None));
    let p40 = Probe::new(&example(file, Some("p40")));
    for q in points([0.0; 3], [4.0, 4.0, 0.5], 300) {
        assert_eq!(m.at(q), p40.at(q));
    }
}

/// Solid-to-pore transitions per unit length along the circle of radius
/// `r` at height 0.5.
fn pores_per_length(p: &Probe, r: f64) -> f64 {
    let n = 20_000;
    let inside: Vec<bool> = (0..n)
        .map(|k| {
            let t = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
            p.inside([r * t.cos(), r * t.sin(), 0.5])
        })
        .collect();
    let changes = (0..n)
        .filter(|&k| inside[k] && !inside[(k + 1) % n])
        .count();
    changes as f64 / (2.0 * std::f64::consts::PI * r)
}

#[test]
fn fig13_grassy_stem_pores_are_smaller_and_denser_outside() {
    let m = example("kou_tan_fig13_grassy_stem.hf", None);
    assert_eq!(pore_count(&m.value), 604);
    let p = Probe::new(&m);
    // Hollow inside, bounded outside.
    for q in points([-0.3, -0.3, 0.0], [0.3, 0.3, 1.0], 200) {
        assert!(!p.inside(q));
    }
    assert!(!p.inside([1.02, 0.0, 0.5]) && !p.inside([0.0, -1.02, 0.5]));
    let outer = pores_per_length(&p, 0.95);
    let inner = pores_per_length(&p, 0.53);
    assert!(outer > 1.6 * inner, "outer {outer}, inner {inner}");
    // Porosity of the tube.
    let pts: Vec<[f64; 3]> = points([-1.0, -1.0, 0.0], [1.0, 1.0, 1.0], 80_000)
        .into_iter()
        .filter(|q| {
            let r = q[0].hypot(q[1]);
            r > 0.45 && r < 1.0
        })
        .collect();
    let por = pore_fraction(&p, &pts);
    assert!((por - 0.6).abs() < 0.02, "{por}");
}

#[test]
fn fig9_10_single_pores_open_into_the_faces_and_stay_off_the_edges() {
    let file = "kou_tan_fig9_11_single_pores.hf";
    let pts = points([0.0; 3], [1.0; 3], 60_000);
    for (object, target) in [("fig9", 0.75), ("fig10a", 0.63), ("fig10b", 0.985)] {
        let m = example(file, Some(object));
        assert_eq!(pore_count(&m.value), 1, "{object}");
        let p = Probe::new(&m);
        let por = pore_fraction(&p, &pts);
        assert!((por - target).abs() < 0.005, "{object}: {por}");
        assert!(!p.inside([0.5; 3]));
        for a in 0..3 {
            for side in [0.001, 0.999] {
                // Open at every face centre...
                let mut q = [0.5; 3];
                q[a] = side;
                assert!(!p.inside(q), "{object} face {a} {side}");
                // ...and solid along the edges.
                let mut e = [0.002; 3];
                e[a] = 0.5;
                e[(a + 1) % 3] = side;
                assert!(p.inside(e), "{object} edge {e:?}");
            }
        }
    }
    // The smallest pore opens only a little into each face, the largest
    // leaves only thin struts along the edges.
    let small = Probe::new(&example(file, Some("fig10a")));
    assert!(small.inside([0.5, 0.8, 0.001]) && small.inside([0.75, 0.75, 0.001]));
    let large = Probe::new(&example(file, Some("fig10b")));
    assert!(!large.inside([0.5, 0.06, 0.06]) && !large.inside([0.9, 0.9, 0.001]));
}

#[test]
fn fig11_block_pores_connect_through_every_face_and_mesh_watertight() {
    let m = example("kou_tan_fig9_11_single_pores.hf", None);
    assert_eq!(pore_count(&m.value), 64);
    let p = Probe::new(&m);
    let por = pore_fraction(&p, &points([0.0; 3], [4.0; 3], 60_000));
    assert!((por - 0.75).abs() < 0.01, "{por}");
    // Every face between two cells: pore on both sides of its centre.
    for a in 0..3 {
        for k in 1..4 {
            for i in 0..4 {
                for j in 0..4 {
                    let (b, c) = ((a + 1) % 3, (a + 2) % 3);
                    let mut q = [0.0; 3];
                    q[b] = i as f64 + 0.5;
                    q[c] = j as f64 + 0.5;
                    for d in [-1e-3, 1e-3] {
                        q[a] = k as f64 + d;
                        assert!(!p.inside(q), "{q:?}");
                    }
                }
            }
        }
    }
    // Cell corners are solid: the struts along the cell edges hold.
    for q in points([0.5; 3], [3.5; 3], 50) {
        assert!(p.inside(q.map(|v| v.round())));
    }
    // No two pores alike.
    let a = p.at([0.2, 0.2, 0.2]);
    assert!((a - p.at([1.2, 0.2, 0.2])).abs() > 1e-6, "{a}");
    let mesh = Plan::new(&m.shape(), &MeshOptions::new([[-0.05; 3], [4.05; 3]], 64))
        .unwrap()
        .run(&|_| {})
        .unwrap();
    let r = check(&mesh);
    assert!(r.is_closed_manifold(), "{r:?}");
    assert!((r.volume / 64.0 - 0.25).abs() < 0.02, "{r:?}");
}

#[test]
fn fig14_bone_has_over_a_thousand_pores_denser_solid_at_the_surface() {
    let m = example("kou_tan_fig14_bone.hf", None);
    // Cells on the tightened box of the part (1102 on the padded interval box).
    assert_eq!(pore_count(&m.value), 1096);
    let p = Probe::new(&m);
    assert!(!p.inside([4.6, 0.0, 0.0]) && !p.inside([0.0, 0.7, 0.0]));
    // Shaft, |x| < 3: near the axis (target 0.85) against near the
    // surface (target about 0.66).
    let shaft = points([-3.0, -0.6, -0.6], [3.0, 0.6, 0.6], 200_000);
    let core: Vec<[f64; 3]> = shaft
        .iter()
        .copied()
        .filter(|q| q[1].hypot(q[2]) < 0.15)
        .collect();
    let skin: Vec<[f64; 3]> = shaft
        .iter()
        .copied()
        .filter(|q| {
            let r = q[1].hypot(q[2]);
            r > 0.45 && r < 0.58
        })
        .collect();
    let (c, s) = (pore_fraction(&p, &core), pore_fraction(&p, &skin));
    assert!(c > 0.78 && s < 0.74 && c > s + 0.1, "core {c}, skin {s}");
}

/// The load error of a model body over the unit block.
fn load_error(body: &str) -> String {
    microfrep_structures_hf::install();
    let src = format!(
        "my_model(x[3], a[1]) {{\n  array v[3];\n  v = [0, 0, 0];\n  b = hfBlock(x, v, 1, 1, 1);\n  {body}\n}}\n"
    );
    match microfrep_hyperfun::load(&src, "bad.hf", None) {
        Ok(_) => panic!("{body}: loaded"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn bad_arguments_are_load_errors_with_their_reason() {
    let e = load_error("my_model = mfPores(x, b, 0.5, 0.2, 1);");
    assert!(
        e.contains("porosity 0.2") && e.contains("0.3212") && e.contains("0.9898"),
        "{e}"
    );
    let e = load_error("my_model = mfPores2(x, b, 0.5, 0.9, 1);");
    assert!(e.contains("0.8333"), "{e}");
    let e = load_error("my_model = mfPores(x, b, 0.5, 0.7, x[1]);");
    assert!(e.contains("seed must be a constant"), "{e}");
    let e = load_error("my_model = mfPores(x, b, 0.5, 0.7, 1.5);");
    assert!(e.contains("whole number"), "{e}");
    let e = load_error("my_model = mfPores(x, b, 0.5 - x[1], 0.7, 1);");
    assert!(e.contains("pore size") && e.contains("positive"), "{e}");
    let e = load_error("my_model = mfPores(x, 1, 0.5, 0.7, 1);");
    assert!(e.contains("expression of the coordinates"), "{e}");
    // Same seed, same structure; another seed, other pores.
    microfrep_structures_hf::install();
    let model = |seed: u32| {
        let src = format!(
            "my_model(x[3], a[1]) {{\n  array v[3];\n  v = [0, 0, 0];\n  b = hfBlock(x, v, 2, 2, 2);\n  my_model = mfPores(x, b, 0.5, 0.8, {seed});\n}}\n"
        );
        Probe::new(&load_src(&src, "seed.hf", None))
    };
    let (a, b, c) = (model(4), model(4), model(5));
    let pts = points([0.0; 3], [2.0; 3], 500);
    let va: Vec<u64> = pts.iter().map(|&q| a.at(q).to_bits()).collect();
    assert_eq!(
        va,
        pts.iter().map(|&q| b.at(q).to_bits()).collect::<Vec<_>>()
    );
    let differ = pts.iter().filter(|&&q| a.at(q) != c.at(q)).count();
    assert!(differ > 100, "{differ}");
}

/// Kou and Tan's porosity control (Sec. 4.3) on a block: the cells follow
/// the block's exact box (not the padded interval bounds), so each cell
/// meets its porosity and the block does too: within 0.1 % relative,
/// measured by the analysis (tetrahedral volume, with its error) for
/// targets from 0.4 to 0.9, in a unit cube and a 10 mm cube.
#[test]
fn block_porosity_meets_its_target_to_a_thousandth() {
    use microfrep_analysis::{measure::measure, Grid};
    for (side, target, res) in [
        (1.0, 0.40, 128),
        (1.0, 0.55, 192),
        (1.0, 0.70, 192),
        (1.0, 0.90, 224),
        (10.0, 0.40, 128),
        (10.0, 0.55, 192),
        (10.0, 0.70, 192),
        (10.0, 0.90, 224),
    ] {
        let src = format!(
            "my_model(x[3], a[1]) {{ array v[3]; v = [0, 0, 0]; \
             b = hfBlock(x, v, {side}, {side}, {side}); \
             my_model = mfPores(x, b, {}, {target}, 1); }}",
            side / 4.0
        );
        let m = load_src(&src, "pores.hf", None);
        let grid = Grid::new([[0.0; 3], [side; 3]], res).unwrap();
        let v = measure(&m.shape(), None, &grid, &|_, _| {}).volume;
        let total = side * side * side;
        let porosity = 1.0 - v.value / total;
        let err = v.error() / total;
        println!("{side} mm cube, target {target}: porosity {porosity:.5} ± {err:.5}");
        assert!(err < 8e-4 * target, "{side} {target}: measured to {err}");
        assert!(
            (porosity - target).abs() < 1e-3 * target,
            "{side} mm, {target}: porosity {porosity} ± {err}"
        );
    }
}
