//! Graded outputs: `analyze` integrates the attribute channels, a
//! `slice --attribute` stack holds the same integral in its grey levels,
//! and a `materials` stack gives each material its volume.

use std::path::PathBuf;
use std::process::Command;

fn bin() -> PathBuf {
    PathBuf::from(env!("CARGO_BIN_EXE_microfrep"))
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

const MODEL: &str = "../../examples/park_fig4_wiffle_gradient.hf";

#[test]
fn attribute_integral_grey_stack_and_material_volumes_agree() {
    let d = std::env::temp_dir().join(format!("mf-cli-graded-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    // One grid for all three: voxel 0.04 over the part's box.
    let bounds = "--bounds=-2,-2,-2,2,2,2";
    let a = run(&[
        "analyze",
        MODEL,
        bounds,
        "--voxel",
        "0.04",
        "--no-connectivity",
        "--no-thickness",
        "--json",
    ]);
    let s1 = &a["attributes"][0];
    let integral = s1["integral"]["value"].as_f64().unwrap();
    assert!(integral > 0.0 && s1["min"].as_f64().unwrap() >= 0.0, "{a}");

    let stack = d.join("grey");
    run(&[
        "slice",
        MODEL,
        bounds,
        "-o",
        stack.to_str().unwrap(),
        "--layer",
        "0.04",
        "--pixel",
        "0.04",
        "--attribute",
        "1",
        "--quiet",
    ]);
    let mut sum = 0u64;
    for e in std::fs::read_dir(&stack).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "png") {
            let img = microfrep_io::png::read(&p).unwrap();
            sum += img.data.iter().map(|&v| v as u64).sum::<u64>();
        }
    }
    let grey = sum as f64 * 0.04f64.powi(3) / 255.0;
    assert!(
        (grey - integral).abs() / integral < 0.005,
        "{grey} vs {integral}"
    );

    let mats = d.join("mats");
    let r = run(&[
        "materials",
        MODEL,
        bounds,
        "-o",
        mats.to_str().unwrap(),
        "--layer",
        "0.04",
        "--pixel",
        "0.04",
        "--palette",
        "hard=#ff0000,soft=#0000ff",
        "--json",
    ]);
    let counts = r["counts"].as_array().unwrap();
    let integrals = r["integrals"].as_array().unwrap();
    for (c, i) in counts.iter().zip(integrals) {
        let (c, i) = (c.as_f64().unwrap(), i.as_f64().unwrap());
        assert!((c - i).abs() <= 0.005 * i.max(1.0) + 1.0, "{r}");
    }
    let _ = std::fs::remove_dir_all(&d);
}
