//! The typed fill: every structure on a HyperFun part and on a mesh part
//! builds, stays inside the part, writes HyperFun that loads back to the
//! same values; a skin is a true distance on a non-distance part; the
//! measured report agrees with independent measurements.

mod common;
use microfrep::fill::{fill, Density, FillOptions, MeasureOptions, Part, Structure};
use microfrep::{load, Bounds, LoadOptions};
use std::path::PathBuf;

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("mf-fill-api-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// hfSphere of radius `r`: `r^2 - |x|^2`, not a distance.
fn sphere_hf(d: &std::path::Path, r: f64) -> String {
    let p = d.join("sphere.hf");
    std::fs::write(
        &p,
        format!(
            "my_model(x[3], a[1]) {{\n  array c[3];\n  c = [0, 0, 0];\n  my_model = hfSphere(x, c, {r});\n}}\n"
        ),
    )
    .unwrap();
    p.display().to_string()
}

/// A closed, outward-wound cube mesh of side `s` at the origin corner.
fn cube_stl(d: &std::path::Path, s: f64) -> String {
    let p = d.join("cube.stl");
    let v = |i: usize| -> [f64; 3] {
        [
            s * (i & 1) as f64,
            s * (i >> 1 & 1) as f64,
            s * (i >> 2 & 1) as f64,
        ]
    };
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let mut t = String::from("solid cube\n");
    for q in quads {
        for tri in [[q[0], q[1], q[2]], [q[0], q[2], q[3]]] {
            t.push_str("facet normal 0 0 0\nouter loop\n");
            for i in tri {
                let c = v(i);
                t.push_str(&format!("vertex {} {} {}\n", c[0], c[1], c[2]));
            }
            t.push_str("endloop\nendfacet\n");
        }
    }
    t.push_str("endsolid cube\n");
    std::fs::write(&p, t).unwrap();
    p.display().to_string()
}

fn quiet(_: &str, _: u64, _: u64) {}

fn random_points(b: Bounds, n: usize, seed: u64) -> Vec<[f64; 3]> {
    let mut s = seed;
    let mut next = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..n)
        .map(|_| std::array::from_fn(|a| b.min[a] + next() * (b.max[a] - b.min[a])))
        .collect()
}

#[test]
fn every_structure_on_a_hyperfun_and_a_mesh_part_reloads_from_its_hyperfun() {
    let d = dir("matrix");
    let sphere = sphere_hf(&d, 10.0);
    let cube = cube_stl(&d, 16.0);
    for (spec, cell) in [(sphere.as_str(), 4.0), (cube.as_str(), 4.0)] {
        let part = Part::load(spec, &LoadOptions::default(), None, &quiet).unwrap();
        for s in Structure::all() {
            let density = match s {
                Structure::Pores => 0.7,
                _ => 0.3,
            };
            let mut opts = FillOptions::new(s, cell, density);
            opts.skin = Some(1.0);
            let f =
                fill(&part, &opts, &quiet).unwrap_or_else(|e| panic!("{spec} {}: {e}", s.name()));
            let text = f.hyperfun().unwrap_or_else(|e| panic!("{}: {e}", s.name()));
            let hf = d.join("model.hf");
            std::fs::write(&hf, &text).unwrap();
            let lo = LoadOptions {
                fields: f.binding().into_iter().collect(),
                ..Default::default()
            };
            let back = load::load(&hf.display().to_string(), &lo).unwrap_or_else(|e| {
                panic!(
                    "{} reload: {e}\n{}",
                    s.name(),
                    &text[..text.len().min(2000)]
                )
            });
            let mut a = f.model.point();
            let mut b = back.shape.point();
            let mut part_ev = f.part.point();
            let mut worst: f64 = 0.0;
            for p in random_points(f.bounds, 1000, 7) {
                let (va, vb) = (a.eval(p), b.eval(p));
                // Inside the fill only where inside the part.
                if va >= 0.0 {
                    assert!(
                        part_ev.eval(p) >= -1e-9,
                        "{}: solid outside the part at {p:?}",
                        s.name()
                    );
                }
                if f.binding().is_none() {
                    assert!(
                        va == vb || (va - vb).abs() <= 1e-9 * va.abs().max(1.0),
                        "{} at {p:?}: {va} in process, {vb} from the .hf",
                        s.name()
                    );
                } else {
                    // A mesh part reloads with its exact distance, where the
                    // fill samples it on a grid of an eighth of a cell,
                    // clamped a few steps from where its value matters (the
                    // skin's depth, the surface): the same solid, and the
                    // same values near every surface of the model.
                    if vb.abs() < 1.0 {
                        worst = worst.max((va - vb).abs());
                    } else {
                        assert!(
                            va.signum() == vb.signum(),
                            "{} at {p:?}: {va} in process, {vb} from the .hf",
                            s.name()
                        );
                    }
                }
            }
            // Half the sampling step (the trilinear error at the cube's edges).
            assert!(
                worst < 0.25,
                "{}: mesh part reload differs by {worst}",
                s.name()
            );
        }
    }
}

#[test]
fn a_one_millimetre_skin_on_a_quadratic_ball_is_one_millimetre() {
    // hfSphere is r^2 - |x|^2; its normalised function never exceeds 1, so
    // a skin measured in it would fill the ball (the old fill's bug).
    let d = dir("skin");
    let sphere = sphere_hf(&d, 10.0);
    let part = Part::load(&sphere, &LoadOptions::default(), None, &quiet).unwrap();
    assert!(!part.distance);
    let mut opts = FillOptions::new(
        Structure::Tpms {
            kind: microfrep::structures::tpms::Tpms::Gyroid,
            sheet: false,
        },
        4.0,
        0.3,
    );
    opts.skin = Some(1.0);
    let f = fill(&part, &opts, &quiet).unwrap();
    // Independently: the skin is solid from r = 9 to 10, the core starts
    // at 9 (closed form), at points along random directions.
    let mut m = f.model.point();
    let mut core = f.core.point();
    for (k, p) in random_points(Bounds::new([-1.0; 3], [1.0; 3]), 200, 3)
        .iter()
        .enumerate()
    {
        let n = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        if n < 1e-3 {
            continue;
        }
        let at = |r: f64| -> [f64; 3] { std::array::from_fn(|a| p[a] / n * r) };
        for r in [9.05, 9.5, 9.95] {
            assert!(m.eval(at(r)) > 0.0, "{k}: skin not solid at r = {r}");
        }
        assert!(
            core.eval(at(8.95)) > 0.0 && core.eval(at(9.05)) < 0.0,
            "{k}: core edge"
        );
    }
    let r = f.measure(&MeasureOptions::default(), &quiet).unwrap();
    let s = r.skin.clone().unwrap();
    assert!((s.mean - 1.0).abs() < 0.02 && s.min > 0.97, "{s:?}");
    assert_eq!(s.unbounded, 0);
    // Density against the closed form of the core volume and an
    // independent fine measurement of the infill inside it.
    let grid = microfrep::analysis::Grid::new([[-9.0; 3], [9.0; 3]], 192).unwrap();
    let m = microfrep::analysis::measure(&f.infill, Some(&f.core), &grid, &|_, _| {});
    let core_closed = 4.0 / 3.0 * std::f64::consts::PI * 729.0;
    assert!((m.region_volume.value - core_closed).abs() < 0.005 * core_closed);
    let independent = m.volume.value / m.region_volume.value;
    assert!(
        (r.density.value - independent).abs() <= r.density.error.max(0.002)
            && r.density.error < 0.015,
        "reported {} ± {}, measured {independent}",
        r.density.value,
        r.density.error
    );
    assert_eq!(r.sealed, Some(true));
    assert_eq!(r.connectivity.as_ref().unwrap().open_fraction, 0.0);
}

#[test]
fn struts_report_their_designed_diameter_and_graded_density_follows_depth() {
    let d = dir("struts");
    let cube = cube_stl(&d, 24.0);
    let part = Part::load(&cube, &LoadOptions::default(), None, &quiet).unwrap();
    assert!(part.distance);
    let k = microfrep::structures::struts::StrutLattice::Octet;
    let f = fill(
        &part,
        &FillOptions::new(Structure::Struts(k), 4.0, 0.2),
        &quiet,
    )
    .unwrap();
    let rad = f.design.strut_radius.unwrap();
    let r = f.measure(&MeasureOptions::default(), &quiet).unwrap();
    let t = r.thinnest.clone().unwrap();
    assert!(
        (t.min - 2.0 * rad).abs() < 0.1 * 2.0 * rad,
        "{t:?} vs diameter {}",
        2.0 * rad
    );
    assert!((r.density.value - 0.2).abs() < 0.01, "{:?}", r.density);
    // Graded: 0.15 at the surface to 0.45 from 6 mm in.
    let mut opts = FillOptions::new(
        Structure::Tpms {
            kind: microfrep::structures::tpms::Tpms::Gyroid,
            sheet: false,
        },
        3.0,
        0.3,
    );
    opts.density = Density::Graded {
        at_surface: 0.15,
        at_depth: 0.45,
        depth: 6.0,
    };
    let g = fill(&part, &opts, &quiet).unwrap();
    let mut rho = microfrep::Shape::new(g.density.clone()).point();
    assert!((rho.eval([12.0, 12.0, 0.5]) - (0.15 + 0.3 * 0.5 / 6.0)).abs() < 0.01);
    assert!((rho.eval([12.0, 12.0, 12.0]) - 0.45).abs() < 1e-9);
    // An expression of the depth, and one out of range refused.
    opts.density = Density::Expression("0.2 + 0.02 * d".into());
    let e = fill(&part, &opts, &quiet).unwrap();
    let mut rho = microfrep::Shape::new(e.density.clone()).point();
    assert!((rho.eval([12.0, 12.0, 2.0]) - 0.24).abs() < 1e-3);
    opts.density = Density::Expression("2".into());
    let err = fill(&part, &opts, &quiet).err().unwrap().to_string();
    assert!(err.contains("between 0 and 1"), "{err}");
    opts.density = Density::Expression("0.3 +".into());
    let err = fill(&part, &opts, &quiet).err().unwrap().to_string();
    assert!(
        err.contains("--density-expr") && !err.contains("/tmp"),
        "{err}"
    );
}

#[test]
fn irregular_pores_follow_the_parts_box_and_oversized_cells_are_refused() {
    let d = dir("pores");
    let cube = cube_stl(&d, 10.0);
    let part = Part::load(&cube, &LoadOptions::default(), None, &quiet).unwrap();
    let f = fill(
        &part,
        &FillOptions::new(Structure::Irregular, 2.0, 0.45),
        &quiet,
    )
    .unwrap();
    let (made, _) = f.design.pores.unwrap();
    // The octree halves the cube's own box until cells are at most 2 mm:
    // 8 x 8 x 8 cells of 1.25 mm, every one in the part.
    assert_eq!(made, 512);
    let r = f.measure(&MeasureOptions::default(), &quiet).unwrap();
    assert!(
        (r.density.value - 0.45).abs() < 0.01 + r.density.error,
        "{:?}",
        r.density
    );
    let err = fill(
        &part,
        &FillOptions::new(Structure::Irregular, 50.0, 0.3),
        &quiet,
    )
    .err()
    .unwrap()
    .to_string();
    assert!(err.contains("larger than the part"), "{err}");
    let mut o = FillOptions::new(Structure::Irregular, 2.0, 0.3);
    o.seed = 1 << 60;
    assert!(fill(&part, &o, &quiet).is_err());
}

/// Monte Carlo infill fraction of the core over `n` points of the box, with
/// its standard error.
fn monte_carlo_density(f: &microfrep::fill::Filled, n: usize, seed: u64) -> (f64, f64) {
    let mut core = f.core.point();
    let mut infill = f.infill.point();
    let (mut inside, mut solid) = (0usize, 0usize);
    for p in random_points(f.bounds, n, seed) {
        if core.eval(p) > 0.0 {
            inside += 1;
            if infill.eval(p) > 0.0 {
                solid += 1;
            }
        }
    }
    let r = solid as f64 / inside as f64;
    (r, (r * (1.0 - r) / inside as f64).sqrt())
}

#[test]
fn the_issues_bone_fills_agree_with_independent_measurements() {
    let (Some(hip), Some(femur)) = (common::bone("hip.stl"), common::bone("femur.stl")) else {
        return;
    };
    // The hip with a 0.25 Schwarz D sheet of 6 mm cells in a 1.5 mm skin (a
    // thin part: no whole cell fits inside its core).
    let part = Part::load(&hip, &LoadOptions::default(), None, &quiet).unwrap();
    let mut opts = FillOptions::new(
        Structure::Tpms {
            kind: microfrep::structures::tpms::Tpms::SchwarzD,
            sheet: true,
        },
        6.0,
        0.25,
    );
    opts.skin = Some(1.5);
    let f = fill(&part, &opts, &quiet).unwrap();
    let r = f.measure(&MeasureOptions::default(), &quiet).unwrap();
    let (mc, se) = monte_carlo_density(&f, 600_000, 7);
    assert!(
        (r.density.value - mc).abs() < r.density.error + 3.0 * se,
        "report {:?}, Monte Carlo {mc} ± {se}",
        r.density
    );
    assert!((r.density.value - 0.25).abs() < 0.01, "{:?}", r.density);
    // The sheet's thickness: chords along the infill's gradient through
    // random points of the sheet, bisected to its two faces.
    let mut inf = f.infill.point();
    // Points 3 mm below the skin, by the mesh's exact distance (the fill's
    // cached depth is clamped a little below the skin).
    let mut depth = part.shape.point();
    let mut chords = Vec::new();
    for p in random_points(f.bounds, 4_000_000, 11) {
        if chords.len() >= 400 {
            break;
        }
        if depth.eval(p) < 1.5 + 3.0 || inf.eval(p) <= 0.0 {
            continue;
        }
        let e = 1e-4;
        let g: [f64; 3] = std::array::from_fn(|a| {
            let (mut hi, mut lo) = (p, p);
            hi[a] += e;
            lo[a] -= e;
            (inf.eval(hi) - inf.eval(lo)) / (2.0 * e)
        });
        let n = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
        if n == 0.0 {
            continue;
        }
        let mut reach = |s: f64| {
            let at = |t: f64| std::array::from_fn(|a| p[a] + s * t * g[a] / n);
            let (mut a, mut b) = (0.0, 0.01);
            while inf.eval(at(b)) > 0.0 && b < 5.0 {
                a = b;
                b *= 1.5;
            }
            for _ in 0..40 {
                let m = 0.5 * (a + b);
                if inf.eval(at(m)) > 0.0 {
                    a = m
                } else {
                    b = m
                }
            }
            a
        };
        chords.push(reach(1.0) + reach(-1.0));
    }
    assert!(chords.len() >= 200, "{} chords", chords.len());
    let mean = chords.iter().sum::<f64>() / chords.len() as f64;
    let t = r.thinnest.clone().expect("the hip's sheet is measured");
    eprintln!(
        "hip: density {:?} vs Monte Carlo {mc} ± {se}; walls {t:?} vs chords {mean}",
        r.density
    );
    assert!(
        (t.mean - mean).abs() < 0.1 * mean,
        "report {t:?}, chords mean {mean}"
    );
    assert!(t.min <= mean && t.min > 0.5 * mean, "{t:?} vs {mean}");

    // The femur with a 0.2 octet of 8 mm cells: strut diameter and density.
    let part = Part::load(&femur, &LoadOptions::default(), None, &quiet).unwrap();
    let k = microfrep::structures::struts::StrutLattice::Octet;
    let f = fill(
        &part,
        &FillOptions::new(Structure::Struts(k), 8.0, 0.2),
        &quiet,
    )
    .unwrap();
    let r = f.measure(&MeasureOptions::default(), &quiet).unwrap();
    let (mc, se) = monte_carlo_density(&f, 600_000, 5);
    assert!(
        (r.density.value - mc).abs() < r.density.error + 3.0 * se,
        "report {:?}, Monte Carlo {mc} ± {se}",
        r.density
    );
    let dia = 2.0 * f.design.strut_radius.unwrap();
    let t = r.thinnest.unwrap();
    assert!((t.min - dia).abs() < 0.1 * dia, "{t:?} vs diameter {dia}");
}

/// Kou and Tan's controls reach the fill: irregularity 0 gives regular
/// pores (another field than the default's), the T-mesh another one; the
/// porosity stays on target (Monte Carlo), the `.hf` reloads to the same
/// values, and a control on another structure is refused by name.
#[test]
fn pore_controls_shape_the_fills_irregular_pores() {
    use microfrep::fill::PoreControls;
    let d = dir("pore-controls");
    // A block 16 x 8 x 12 mm (not a cube: the T-mesh's halving of the
    // longest side then gives other cells than the octree).
    let block = d.join("block.hf");
    std::fs::write(
        &block,
        "my_model(x[3], a[1]) {\n  array v[3];\n  v = [0, 0, 0];\n  \
         my_model = hfBlock(x, v, 16, 8, 12);\n}\n",
    )
    .unwrap();
    let part = Part::load(
        &block.display().to_string(),
        &LoadOptions::default(),
        None,
        &quiet,
    )
    .unwrap();
    let build = |pores: PoreControls| {
        let mut opts = FillOptions::new(Structure::Irregular, 4.0, 0.4);
        opts.pores = pores;
        fill(&part, &opts, &quiet).unwrap()
    };
    let base = build(PoreControls::default());
    let regular = build(PoreControls {
        irregularity: Some(0.0),
        ..Default::default()
    });
    let tmesh = build(PoreControls {
        tmesh: true,
        parent_scale: Some(1.8),
        ..Default::default()
    });
    let t: [[f64; 3]; 8] =
        std::array::from_fn(|s| std::array::from_fn(|k| 0.35 + 0.04 * ((s + 2 * k) % 4) as f64));
    let hand = build(PoreControls {
        hand_t: Some(t),
        ..Default::default()
    });
    let pts = random_points(base.bounds, 2000, 3);
    let differ = |a: &microfrep::fill::Filled, b: &microfrep::fill::Filled| {
        let (mut ea, mut eb) = (a.model.point(), b.model.point());
        pts.iter()
            .filter(|&&p| (ea.eval(p) >= 0.0) != (eb.eval(p) >= 0.0))
            .count()
    };
    assert!(
        differ(&base, &regular) > 20,
        "irregularity 0 changed nothing"
    );
    assert!(differ(&base, &tmesh) > 20, "the T-mesh changed nothing");
    assert!(differ(&base, &hand) > 20, "the hand-set t changed nothing");
    for f in [&regular, &tmesh, &hand] {
        let (mc, se) = monte_carlo_density(f, 200_000, 9);
        assert!((mc - 0.4).abs() < 0.01 + 3.0 * se, "density {mc} ± {se}");
        let text = f.hyperfun().unwrap();
        assert!(
            text.contains("mfPoreFieldOpt("),
            "{}",
            &text[..text.len().min(600)]
        );
        let hf = d.join("pores.hf");
        std::fs::write(&hf, &text).unwrap();
        let lo = LoadOptions {
            fields: f.binding().into_iter().collect(),
            ..Default::default()
        };
        let back = load::load(&hf.display().to_string(), &lo).unwrap();
        let (mut a, mut b) = (f.model.point(), back.shape.point());
        let mut pore = |p: [f64; 3]| {
            // Away from the part's surface (reloaded with its exact
            // distance), the pores alone decide.
            let (va, vb) = (a.eval(p), b.eval(p));
            (va.min(1.0), vb.min(1.0))
        };
        let mut same = 0;
        let inner: Vec<_> = pts
            .iter()
            .filter(|p| {
                p[0] > 3.0 && p[0] < 13.0 && p[1] > 3.0 && p[1] < 5.0 && p[2] > 3.0 && p[2] < 9.0
            })
            .collect();
        for &&p in &inner {
            let (va, vb) = pore(p);
            if (va - vb).abs() <= 1e-6 * va.abs().max(1.0) {
                same += 1;
            }
        }
        assert!(inner.len() > 50, "{} inner points", inner.len());
        assert_eq!(same, inner.len(), "the .hf does not reload the same pores");
    }
    let mut opts = FillOptions::new(Structure::parse("gyroid", false).unwrap(), 4.0, 0.3);
    opts.pores.irregularity = Some(0.3);
    let e = fill(&part, &opts, &quiet)
        .err()
        .expect("refused")
        .to_string();
    assert!(e.contains("--irregularity") && e.contains("gyroid"), "{e}");
    let mut opts = FillOptions::new(Structure::Irregular, 4.0, 0.4);
    opts.pores.parent_scale = Some(5.0);
    let e = fill(&part, &opts, &quiet)
        .err()
        .expect("refused")
        .to_string();
    assert!(e.contains("--parent-scale 5"), "{e}");
}

/// Park's material subspaces in the fill: two layers below a cube's
/// surface give the attribute channels of the closed form, by the cube's
/// exact distance to its faces (later layers over earlier ones, the
/// primary material the rest, nothing outside the part).
#[test]
fn material_layers_grade_the_fill_by_depth_below_the_surface() {
    use microfrep::fill::MaterialLayer;
    let d = dir("layers");
    let cube = cube_stl(&d, 16.0);
    let part = Part::load(&cube, &LoadOptions::default(), None, &quiet).unwrap();
    let mut opts = FillOptions::new(Structure::parse("gyroid", false).unwrap(), 4.0, 0.3);
    opts.material_layers = vec![
        MaterialLayer {
            depth: 1.0,
            ramp: 2.0,
        },
        MaterialLayer {
            depth: 5.0,
            ramp: 1.0,
        },
    ];
    let f = fill(&part, &opts, &quiet).unwrap();
    let attrs = f.model.attributes();
    assert_eq!(
        attrs.iter().map(|a| a.name.as_str()).collect::<Vec<_>>(),
        ["s1", "s2"]
    );
    let mut s1 = microfrep::Shape::new(attrs[0].expr.clone()).point();
    let mut s2 = microfrep::Shape::new(attrs[1].expr.clone()).point();
    let mut checked = 0;
    let b = Bounds::new([-2.0; 3], [18.0; 3]);
    for p in random_points(b, 4000, 5) {
        let faces: Vec<f64> = (0..3).flat_map(|a| [p[a], 16.0 - p[a]]).collect();
        let depth = faces.iter().copied().fold(f64::INFINITY, f64::min);
        let (w1, w2) = ((depth - 1.0) / 2.0, depth - 5.0);
        let (e1, e2) = if depth < 0.0 {
            (0.0, 0.0)
        } else if depth >= 5.0 {
            (0.0, w2.clamp(0.0, 1.0))
        } else if depth >= 1.0 {
            (w1.clamp(0.0, 1.0), 0.0)
        } else {
            (0.0, 0.0)
        };
        // Away from the layer boundaries (where a sampled depth may fall on
        // either side) and from the medial planes of the box, where its
        // distance has a crease that the fill's sampled depth (steps of an
        // eighth of a cell, 0.5 mm) rounds off.
        let mut sorted = faces.clone();
        sorted.sort_by(f64::total_cmp);
        if [0.0, 1.0, 5.0].iter().any(|&z| (depth - z).abs() < 0.05) || sorted[1] - sorted[0] < 0.75
        {
            continue;
        }
        let (g1, g2) = (s1.eval(p), s2.eval(p));
        assert!(
            (g1 - e1).abs() < 0.02 && (g2 - e2).abs() < 0.02,
            "at {p:?} (depth {depth}): s1 {g1} s2 {g2}, want {e1} {e2}"
        );
        checked += 1;
    }
    assert!(checked > 1500, "{checked}");
    assert!(f
        .hyperfun()
        .err()
        .expect("refused")
        .to_string()
        .contains("--material-layer"));
    for bad in [
        MaterialLayer {
            depth: -1.0,
            ramp: 1.0,
        },
        MaterialLayer {
            depth: 1.0,
            ramp: 0.0,
        },
    ] {
        opts.material_layers = vec![bad];
        let e = fill(&part, &opts, &quiet)
            .err()
            .expect("refused")
            .to_string();
        assert!(e.contains("--material-layer 1"), "{e}");
    }
}
