//! `microfrep fill`: a sphere mesh filled with a gyroid network at 30 %
//! with a skin; measured density, skin thickness, watertight output; the
//! HyperFun form reloads to the same model.

use std::path::PathBuf;
use std::process::Command;

fn bin() -> PathBuf {
    PathBuf::from(env!("CARGO_BIN_EXE_microfrep"))
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("mf-cli-fill-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn run(args: &[&str]) -> serde_json::Value {
    let out = Command::new(bin()).args(args).output().unwrap();
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap_or(serde_json::Value::Null)
}

#[test]
fn sphere_mesh_with_a_gyroid_at_30_percent_and_a_skin() {
    let d = dir("sphere");
    let part = d.join("ball.stl");
    let part = part.to_str().unwrap();
    run(&[
        "mesh",
        "sphere",
        "-o",
        part,
        "--resolution",
        "96",
        "--quiet",
    ]);
    let out = d.join("filled.stl");
    let r = run(&[
        "fill",
        part,
        "-o",
        out.to_str().unwrap(),
        "--structure",
        "gyroid",
        "--cell",
        "0.25",
        "--density",
        "0.3",
        "--shell",
        "0.05",
        "--resolution",
        "128",
        "--json",
    ]);
    let rho = r["density"]["measured"].as_f64().unwrap();
    assert!((rho - 0.3).abs() / 0.3 < 0.01, "{r}");
    // Half a voxel of the 128 grid over the ball's box (side 2).
    let skin = r["skin"]["measured"].as_f64().unwrap();
    assert!((skin - 0.05).abs() < 0.5 * 2.0 / 128.0, "{r}");
    assert_eq!(r["written"]["bad_edges"], 0, "{r}");
    assert_eq!(r["solid_components"], 1, "{r}");
    // A closed skin: no pore reaches the part's outside.
    assert!(r["open_pore_fraction"].as_f64().unwrap() < 1e-6, "{r}");

    // The HyperFun form, with its binding, is the same model.
    let hf = d.join("filled.hf");
    run(&[
        "fill",
        part,
        "-o",
        hf.to_str().unwrap(),
        "--structure",
        "gyroid",
        "--cell",
        "0.25",
        "--density",
        "0.3",
        "--shell",
        "0.05",
        "--quiet",
    ]);
    let text = std::fs::read_to_string(&hf).unwrap();
    assert!(text.contains("--field part="), "{text}");
    let field = format!("part={part}");
    let out = Command::new(bin())
        .args([
            "eval",
            hf.to_str().unwrap(),
            "--field",
            &field,
            "0",
            "0",
            "0",
            "0.99",
            "0",
            "0",
            "2",
            "0",
            "0",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Vec<f64> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| l.parse().unwrap())
        .collect();
    // In the skin, outside the part.
    assert!(v[1] > 0.0 && v[2] < 0.0, "{v:?}");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_hyperfun_part_with_struts_and_bad_requests() {
    let d = dir("hf");
    let out = d.join("f.stl");
    let r = run(&[
        "fill",
        "../../examples/pasko_fig3a_sphere_shell_lattice.hf",
        "-o",
        out.to_str().unwrap(),
        "--structure",
        "octet",
        "--cell",
        "0.3",
        "--density",
        "0.2",
        "--resolution",
        "96",
        "--json",
    ]);
    let rho = r["density"]["measured"].as_f64().unwrap();
    assert!((rho - 0.2).abs() < 0.02, "{r}");
    assert_eq!(r["written"]["bad_edges"], 0, "{r}");
    for (args, msg) in [
        (
            vec!["--structure", "nope", "--density", "0.3"],
            "unknown structure",
        ),
        (
            vec!["--structure", "gyroid", "--density", "1.5"],
            "between 0 and 1",
        ),
        (
            vec!["--structure", "pores", "--density", "0.2"],
            "out of range",
        ),
    ] {
        let mut a = vec!["fill", "sphere", "-o", "/tmp/x.stl", "--cell", "0.3"];
        a.extend(args);
        let o = Command::new(bin()).args(&a).output().unwrap();
        assert!(!o.status.success());
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(e.contains(msg), "{a:?}: {e}");
    }
    let _ = std::fs::remove_dir_all(&d);
}
