//! The bundled paper examples through the binary: `cell` classifies unit
//! cells as the figures say, and `mesh` turns an example into a closed,
//! manifold mesh whose volume agrees with the paper's closed form.

use std::path::{Path, PathBuf};
use std::process::Command;

fn example(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples")
        .join(name)
}

/// Runs the binary; returns (exit code, stdout, stderr).
fn run(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_microfrep"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn json(s: &str) -> serde_json::Value {
    serde_json::from_str(s).unwrap_or_else(|e| panic!("not JSON ({e}): {s}"))
}

#[test]
fn cell_report_of_the_symmetric_cylinder_cell_is_full_and_symmetric() {
    // Three orthogonal cylinders of radius 0.3 on [-1,1]^3 (the fine cell of
    // Fryazinov Fig. 9): every face pattern matches its opposite face.
    let m = example("fryazinov_fig9_nested_filter.hf");
    let (code, out, err) = run(&[
        "cell",
        m.to_str().unwrap(),
        "--object",
        "fine",
        "--box",
        "-1,-1,-1,1,1,1",
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let v = json(&out);
    assert_eq!(v["full"], true);
    assert_eq!(v["symmetric"], true);
    assert_eq!(v["sawtooth_safe_axes"].as_array().unwrap().len(), 3);
    assert_eq!(v["triangle_safe_axes"].as_array().unwrap().len(), 3);
}

#[test]
fn cell_report_of_the_off_centre_cell_is_not_symmetric() {
    // Fryazinov Fig. 3: a sphere off the cell centre and a corner cube.
    let m = example("fryazinov_fig3_nonsymmetric_cell.hf");
    let (code, out, err) = run(&[
        "cell",
        m.to_str().unwrap(),
        "--object",
        "cell",
        "--box",
        "-1,-1,-1,1,1,1",
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let v = json(&out);
    assert_eq!(v["symmetric"], false);
    assert_eq!(v["full"], false);
}

#[test]
fn cell_rejects_an_inverted_box() {
    let m = example("fryazinov_fig3_nonsymmetric_cell.hf");
    let (code, _, err) = run(&["cell", m.to_str().unwrap(), "--box", "1,1,1,-1,-1,-1"]);
    assert_ne!(code, 0);
    assert!(!err.is_empty());
}

#[test]
fn mesh_of_the_lattice_example_is_closed_with_the_closed_form_volume() {
    // Pasko Fig. 2a: rod lattice with alpha = 1 has volume fraction
    // 3w^2 - 2w^3, w = (pi - 2 asin l) / (2 pi), inside whatever box the
    // example is cut to; the mesh must be closed and manifold.
    let m = example("pasko_fig2a_lattice.hf");
    let dir = std::env::temp_dir().join(format!("microfrep-cli-ex-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out_path = dir.join("fig2a.stl");
    let (code, out, err) = run(&[
        "mesh",
        m.to_str().unwrap(),
        "-o",
        out_path.to_str().unwrap(),
        "--bounds",
        "-1,-1,-1,1,1,1",
        "--resolution",
        "96",
        "--json",
        "--quiet",
    ]);
    assert_eq!(code, 0, "{err}");
    let v = json(&out);
    assert_eq!(v["bad_edges"], 0, "{out}");
    assert!(v["triangles"].as_u64().unwrap() > 1000);
    let bytes = std::fs::metadata(&out_path).unwrap().len();
    // Binary STL: 80-byte header, count, 50 bytes a triangle.
    assert_eq!(bytes, 84 + 50 * v["triangles"].as_u64().unwrap());
    let volume = v["volume"].as_f64().unwrap();
    // The figure's volume fraction is 7/27 (see the example's header); the
    // box has volume 8.
    let expected = 8.0 * 7.0 / 27.0;
    assert!(
        (volume - expected).abs() / expected < 0.01,
        "volume {volume} vs {expected}"
    );
    std::fs::remove_dir_all(&dir).ok();
}
