//! 3MF outputs: a strut fill is a beam lattice (with the part as clipping
//! and representation mesh); a slice stack holds the SVG output's polygons.

use std::path::PathBuf;
use std::process::Command;

fn bin() -> PathBuf {
    PathBuf::from(env!("CARGO_BIN_EXE_microfrep"))
}

fn ok(args: &[&str]) -> String {
    let out = Command::new(bin()).args(args).output().unwrap();
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("mf-cli-3mf-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn strut_fill_is_a_beam_lattice_and_triangles_on_request() {
    let d = dir("beams");
    let part = d.join("ball.stl");
    ok(&[
        "mesh",
        "sphere",
        "-o",
        part.to_str().unwrap(),
        "--resolution",
        "48",
        "--quiet",
    ]);
    let out = d.join("lattice.3mf");
    let j: serde_json::Value = serde_json::from_str(&ok(&[
        "fill",
        part.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--structure",
        "octet",
        "--cell",
        "0.5",
        "--density",
        "0.2",
        "--resolution",
        "72",
        "--json",
    ]))
    .unwrap();
    let model = microfrep_3mf::read_file(&out).unwrap();
    let lat = microfrep_3mf::lattices(&model).unwrap();
    assert_eq!(lat.len(), 1);
    assert_eq!(
        lat[0].beams.len() as u64,
        j["written"]["beams"].as_u64().unwrap()
    );
    let r = j["written"]["radius"].as_f64().unwrap();
    assert!(lat[0]
        .beams
        .iter()
        .all(|b| (b.r1 - r).abs() < 1e-9 && (b.r2 - r).abs() < 1e-9));
    // Beams reach inside the ball only (clipped to the part, radius slack).
    for b in &lat[0].beams {
        for v in [b.v1, b.v2] {
            let p = lat[0].nodes[v as usize];
            assert!((p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt() < 1.0 + 0.5 * 3f64.sqrt());
        }
    }
    let tri = d.join("tri.3mf");
    ok(&[
        "fill",
        part.to_str().unwrap(),
        "-o",
        tri.to_str().unwrap(),
        "--structure",
        "octet",
        "--cell",
        "0.5",
        "--density",
        "0.2",
        "--resolution",
        "72",
        "--triangles",
        "--quiet",
    ]);
    let m = microfrep_3mf::read_meshes(&tri).unwrap();
    assert!(!m.is_empty() && m[0].triangles.len() > 1000);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn slice_stack_3mf_holds_the_svg_polygons() {
    let d = dir("slices");
    let (svg, tmf) = (d.join("svg"), d.join("stack.3mf"));
    // Layers of 0.1: toriball's tubes cross every layer centre (at 0.2 the
    // centres all fall between them and the stack is refused as empty).
    let common = ["--layer", "0.1", "--pixel", "0.02", "--quiet"];
    let mut a = vec![
        "slice",
        "toriball",
        "-o",
        svg.to_str().unwrap(),
        "--format",
        "svg",
    ];
    a.extend(common);
    ok(&a);
    let mut b = vec![
        "slice",
        "toriball",
        "-o",
        tmf.to_str().unwrap(),
        "--format",
        "3mf",
    ];
    b.extend(common);
    ok(&b);
    let model = microfrep_3mf::read_file(&tmf).unwrap();
    let stack = &model.slice_stacks[0];
    assert_eq!(stack.slices.len(), 20);
    for (k, s) in stack.slices.iter().enumerate() {
        let text = std::fs::read_to_string(svg.join(format!("layer_{k:05}.svg"))).unwrap();
        assert!(!s.polygons.is_empty(), "layer {k} is empty");
        assert_eq!(
            s.polygons.len(),
            microfrep_fab::svg::read_layer_svg(&text).len(),
            "layer {k}"
        );
    }
    // Strictly increasing tops.
    assert!(stack.slices.windows(2).all(|w| w[1].ztop > w[0].ztop));
    let _ = std::fs::remove_dir_all(&d);
}
