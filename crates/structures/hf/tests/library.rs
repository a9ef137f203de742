//! The `mf*` functions: registration, documentation, parameters as
//! expressions, errors, and the density and cell checks through HyperFun.
mod common;
use common::*;
use microfrep_core::{Expr, PointEval, Tape};
use microfrep_hyperfun::library::Registry;
use microfrep_structures::cell_report::cell_report;
use microfrep_structures::lattice::{rod_lattice, Slabs};
use microfrep_structures::tpms::{tpms, Solid, Tpms};

fn model(body: &str) -> String {
    // Array declarations come first in HyperFun.
    let (decl, body) = match body.trim_start().strip_prefix("array") {
        Some(rest) => {
            let (d, b) = rest.split_once(';').unwrap();
            (format!("array{d};"), b)
        }
        None => (String::new(), body),
    };
    format!(
        "my_model(x[3], a[2]) {{ array c[3], lo[3], hi[3]; {decl} c = [0, 0, 0]; \
         lo = [-1, -1, -1]; hi = [1, 1, 1]; {body} }}"
    )
}

fn probe(body: &str) -> Probe {
    Probe::new(&load_src(&model(body), "test", None))
}

/// The load error of a model body.
fn load_error(body: &str) -> String {
    microfrep_structures_hf::install();
    match microfrep_hyperfun::load(&model(body), "bad.hf", None) {
        Ok(_) => panic!("{body}: loaded"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn every_function_is_registered_and_documented() {
    let names = microfrep_structures_hf::names();
    assert!(names.len() >= 40, "{}", names.len());
    assert!(names
        .iter()
        .all(|n| n.starts_with(microfrep_structures_hf::PREFIX)));
    let doc = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../LIBRARY.md"))
        .unwrap()
        .to_ascii_lowercase();
    for n in &names {
        assert!(doc.contains(&format!("`{n}")), "{n} is not documented");
    }
    // Every documented `mf...(` name exists.
    for part in doc.split('`').skip(1).step_by(2) {
        if let Some(name) = part
            .strip_prefix("mf")
            .filter(|n| !n.is_empty() && !n.starts_with('*'))
        {
            let name = format!("mf{}", name.split(['(', ' ']).next().unwrap());
            assert!(
                names.contains(&name.as_str()),
                "documented {name} is missing"
            );
        }
    }
    // The reference library stays as it was; the standard one gains them
    // once installed.
    assert!(Registry::reference().get("mfLattice").is_none());
    microfrep_structures_hf::install();
    microfrep_structures_hf::install();
    assert!(Registry::standard().get("MFLATTICE").is_some());
    assert_eq!(
        microfrep_hyperfun::library::extensions()
            .iter()
            .filter(|k| **k == "microfrep-structures")
            .count(),
        1
    );
    assert!(microfrep_structures_hf::registry()
        .get("mfgyroid")
        .is_some());
}

#[test]
fn every_parameter_may_be_an_expression() {
    // q, p, l and alpha as fields of the point and of a[1], a[2].
    let m = load_src(
        &model("my_model = mfLattice(x, 6 + x[3] + a[1], 0.1 * x[2], 0.3 + 0.1 * x[1], a[2]);"),
        "fields",
        None,
    );
    let p = Expr::xyz();
    let (a1, a2) = (Expr::param("a1", 0.0), Expr::param("a2", 0.0));
    let q = 6.0 + &p[2] + &a1;
    let s = Slabs {
        q: [q.clone(), q.clone(), q],
        p: std::array::from_fn(|_| 0.1 * &p[1]),
        l: std::array::from_fn(|_| 0.3 + 0.1 * &p[0]),
    };
    let want = rod_lattice(&p, &s, a2);
    let (t1, t2) = (m.tape(), Tape::new(&want));
    for (v1, v2) in [(0.0, 0.0), (1.5, 0.5), (-2.0, 1.0)] {
        let mut e1 = PointEval::new(&t1);
        let mut e2 = PointEval::new(&t2);
        for (t, e) in [(&t1, &mut e1), (&t2, &mut e2)] {
            e.set_param(t.param_index("a1").unwrap(), v1);
            e.set_param(t.param_index("a2").unwrap(), v2);
        }
        for q in points([-1.0; 3], [1.0; 3], 50) {
            assert!((e1.eval(q) - e2.eval(q)).abs() < 1e-12);
        }
    }
    // Fields everywhere else too, still lowered to a graph.
    for body in [
        "my_model = mfGyroid(x, 1 + 0.1 * x[1], a[1] * x[2]);",
        "t = mfTriangleMap(x, 0.3 + 0.1 * x[3], lo, hi); my_model = hfSphere(x, c, 0.5);",
        "t = mfPoreMap(x, 1 + 0.1 * x[1], 9 + a[1]); my_model = hfSphere(x, c, 0.5);",
        "my_model = mfStruts(x, 2, 1 + 0.2 * x[1], 0.05 + 0.02 * x[3]);",
        "my_model = mfShellInfill(hfSphere(x, c, 1), 0.1 + 0.1 * x[1], x[2], a[1]);",
        "my_model = mfTpmsDensity(x, 1, 0, 1 + 0.1 * x[3], 0.2 + 0.1 * x[1]);",
    ] {
        let p = probe(body);
        p.values(&points([-1.0; 3], [1.0; 3], 20));
    }
}

#[test]
fn replication_maps_write_the_cell_point_into_x() {
    let p = probe("t = mfSawtoothMap(x, 0.5, lo, hi); my_model = x[1] + 10 * t;");
    let saw = |t: f64| 0.5 + (t / 0.5 - (t / 0.5 + 0.5).floor());
    for q in points([-2.0; 3], [2.0; 3], 50) {
        assert!((p.at(q) - (10.0 - 1.0 + 2.0 * saw(q[0]))).abs() < 1e-9);
    }
    // Per-axis kinds: z passes through unchanged, y is a triangle wave.
    let p = probe(
        "array k[3], per[3]; k = [1, 2, 0]; per = [0.5, 0.25, 9];
         t = mfReplicate(x, k, per, lo, hi); my_model = x[3] + 100 * x[2];",
    );
    let tri = |t: f64| 0.5 + (t * std::f64::consts::PI / 0.25).sin().asin() / std::f64::consts::PI;
    for q in points([-2.0; 3], [2.0; 3], 50) {
        let want = q[2] + 100.0 * (-1.0 + 2.0 * tri(q[1]));
        assert!((p.at(q) - want).abs() < 1e-9);
    }
}

#[test]
fn bad_arguments_are_load_errors_with_a_position() {
    let e = load_error("my_model = mfTpms(x, 7, 0, 1, 0);");
    assert!(
        e.contains("mftpms") && e.contains("TPMS kind") && e.contains("1:"),
        "{e}"
    );
    let e = load_error("array q[2]; q = [1, 2]; my_model = mfLattice3(x, q, c, c, 0);");
    assert!(e.contains("q must be an array of 3 elements, not 2"), "{e}");
    let e = load_error("my_model = mfStruts(x, 2.5, 1, 0.1);");
    assert!(e.contains("strut lattice kind"), "{e}");
    let e =
        load_error("array k[3]; k = [1, 3, 0]; t = mfReplicate(x, k, c, lo, hi); my_model = 1;");
    assert!(e.contains("replication kind"), "{e}");
    let e = load_error("array d[2]; d = [1, 2]; my_model = mfTfWeight(d, 3);");
    assert!(e.contains("partition index"), "{e}");
    let e = load_error("my_model = mfLattice(x, 1, 2, 3);");
    // The parser knows the arity from the registry.
    assert!(e.contains("1:") && e.contains("expected"), "{e}");
    // A point-dependent code falls back to the per-point interpreter.
    microfrep_structures_hf::install();
    let m = microfrep_hyperfun::load(
        &model("my_model = mfTpms(x, 1 + a[1], 0, 1, 0);"),
        "param-kind",
        None,
    )
    .unwrap();
    assert!(!m.lowered);
}

#[test]
fn tpms_network_volume_fractions_through_hyperfun() {
    let pts = points([0.0; 3], [1.0; 3], 40_000);
    for (name, want) in [
        ("mfGyroid", [0.170, 0.338, 0.5, 0.662, 0.830]),
        ("mfSchwarzP", [0.213, 0.357, 0.5, 0.643, 0.787]),
        ("mfSchwarzD", [0.081, 0.294, 0.5, 0.706, 0.919]),
    ] {
        for (t, w) in ["-1", "-0.5", "0", "0.5", "1"].iter().zip(want) {
            let p = probe(&format!("my_model = {name}(x, 1, {t});"));
            let vf = fraction(&p, &pts);
            assert!((vf - w).abs() < 0.005, "{name} {t}: {vf} vs {w}");
        }
    }
    // Named and generic forms agree with the Rust API.
    for (k, kind) in Tpms::ALL.iter().enumerate() {
        for sheet in [0, 1] {
            let solid = if sheet == 1 {
                Solid::Sheet
            } else {
                Solid::Network
            };
            let p = probe(&format!(
                "my_model = mfTpms(x, {}, {sheet}, 0.7, 0.3);",
                k + 1
            ));
            let r = Probe::of(&tpms(*kind, solid, &Expr::xyz(), 0.7, 0.3));
            for q in points([-1.0; 3], [1.0; 3], 30) {
                assert!((p.at(q) - r.at(q)).abs() < 1e-12);
            }
        }
    }
}

#[test]
fn density_targets_are_hit_through_hyperfun() {
    let pts = points([0.0; 3], [1.0; 3], 50_000);
    for body in [
        "mfTpmsDensity(x, 1, 0, 1, RHO)",
        "mfTpmsDensity(x, 2, 1, 1, RHO)",
    ] {
        for rho in [0.1, 0.2, 0.3, 0.5] {
            let p = probe(&format!(
                "my_model = {};",
                body.replace("RHO", &rho.to_string())
            ));
            let vf = fraction(&p, &pts);
            assert!((vf - rho).abs() / rho < 0.005, "{body} {rho}: {vf}");
        }
    }
    let pts = points([0.0; 3], [1.0; 3], 20_000);
    for rho in [0.1, 0.2, 0.3] {
        let p = probe(&format!("my_model = mfStrutsDensity(x, 2, 1, {rho});"));
        let vf = fraction(&p, &pts);
        assert!((vf - rho).abs() / rho < 0.005, "bcc {rho}: {vf}");
    }
    // A density varying in space: 0.15 + 0.1 x over four gyroid cells.
    let p = probe("my_model = mfTpmsDensity(x, 1, 0, 1, 0.15 + 0.1 * x[1]);");
    for k in 0..4 {
        let k = k as f64;
        let vf = fraction(&p, &points([k, 0.0, 0.0], [k + 1.0, 1.0, 1.0], 30_000));
        let want = 0.15 + 0.1 * (k + 0.5);
        assert!((vf - want).abs() < 0.02, "cell {k}: {vf} vs {want}");
    }
}

#[test]
fn cell_report_classifies_hyperfun_cells() {
    let cyl = load_src(
        &model(
            "my_model = hfCylinderX(x, c, 0.3) | hfCylinderY(x, c, 0.3) | hfCylinderZ(x, c, 0.3);",
        ),
        "cylinders",
        None,
    );
    let r = cell_report(&cyl.value, [-1.0; 3], [1.0; 3], 9, 1e-9).unwrap();
    assert!(r.full() && r.geometric() && r.symmetric(), "{r:?}");
    let off = load_src(
        &model("array d[3]; d = [0.5, 0, 0]; my_model = hfSphere(x, d, 0.7);"),
        "off-centre",
        None,
    );
    let r = cell_report(&off.value, [-1.0; 3], [1.0; 3], 9, 1e-9).unwrap();
    let x = r.axes[0];
    assert!(!x.geometric && !x.full && !x.symmetric, "{r:?}");
}

#[test]
fn noise_is_bounded_deterministic_and_seeded() {
    let a = probe("my_model = mfNoise(x, 0.5, 3, 7);");
    let b = probe("my_model = mfNoise(x, 0.5, 3, 8);");
    let pts = points([-2.0; 3], [2.0; 3], 500);
    let (va, vb) = (a.values(&pts), b.values(&pts));
    assert!(va.iter().all(|v| v.abs() <= 1.0 + 1e-9));
    assert!(va.iter().zip(&vb).any(|(x, y)| (x - y).abs() > 0.05));
    assert_eq!(va, probe("my_model = mfNoise(x, 0.5, 3, 7);").values(&pts));
}
