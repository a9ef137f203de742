//! `microfrep analyze`: JSON report of a built-in example and of a HyperFun
//! file, porosity inside a region, and clear errors on bad input.

use std::process::Command;

fn run(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_microfrep"))
        .arg("analyze")
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Writes `src` to a fresh temporary `.hf` file and returns its path.
fn model(name: &str, src: &str) -> String {
    let dir = std::env::temp_dir().join(format!("microfrep-cli-analyze-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, src).unwrap();
    p.display().to_string()
}

fn json(args: &[&str]) -> serde_json::Value {
    let (code, out, err) = run(args);
    assert_eq!(code, 0, "{err}");
    serde_json::from_str(&out).unwrap_or_else(|e| panic!("{e}: {out}"))
}

#[test]
fn sphere_json_report() {
    let v = json(&["sphere", "--resolution", "64", "--json"]);
    let vol = v["volume"]["value"].as_f64().unwrap();
    assert!(
        (vol / (4.0 / 3.0 * std::f64::consts::PI) - 1.0).abs() < 3e-3,
        "{vol}"
    );
    assert!(v["volume"]["error"].as_f64().unwrap() > 0.0);
    let area = v["area"]["value"].as_f64().unwrap();
    assert!(
        (area / (4.0 * std::f64::consts::PI) - 1.0).abs() < 3e-3,
        "{area}"
    );
    assert_eq!(v["dims"], serde_json::json!([64, 64, 64]));
    assert_eq!(v["connectivity"]["solid_components"], 1);
    assert_eq!(v["connectivity"]["euler_surface"], 2);
    assert!(v["thickness"]["solid"]["median"].as_f64().is_some());
}

#[test]
fn lattice_file_in_a_region_with_text_output() {
    let lattice = model(
        "lattice.hf",
        "my_model(x[3], a[1]) {\n  my_model = mfLattice(x, 6.283185307179586, 0, 0.5, 1);\n}\n",
    );
    let ball = model(
        "ball.hf",
        "my_model(x[3], a[1]) {\n  my_model = 1.5^2 - x[1]^2 - x[2]^2 - x[3]^2;\n}\n",
    );
    // Volume fraction 7/27 in a box of whole periods.
    let v = json(&[
        &lattice,
        "--bounds",
        "-1,-1,-1,1,1,1",
        "--resolution",
        "64",
        "--json",
        "--no-thickness",
    ]);
    let f = v["volume_fraction"]["value"].as_f64().unwrap();
    assert!((f - 7.0 / 27.0).abs() < 2e-3, "{f}");
    assert_eq!(v["connectivity"]["percolates"]["z"], true);
    assert!(v["thickness"].is_null());
    // Inside the ball the pores reach the outside through its surface.
    let (code, out, err) = run(&[
        &lattice,
        "--bounds",
        "-2,-2,-2,2,2,2",
        "--region",
        &ball,
        "--resolution",
        "48",
        "--no-thickness",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("inside region"), "{out}");
    assert!(out.contains("100 % of pore volume open"), "{out}");
}

#[test]
fn bad_inputs_are_errors() {
    let plane = model(
        "plane.hf",
        "my_model(x[3], a[1]) {\n  my_model = x[3];\n}\n",
    );
    let (code, _, err) = run(&[&plane, "--resolution", "16"]);
    assert_ne!(code, 0);
    assert!(err.contains("--bounds"), "{err}");
    for args in [
        ["sphere", "--resolution", "0"],
        ["sphere", "--resolution", "-3"],
        ["sphere", "--resolution", "100000000"],
        ["sphere", "--voxel", "0"],
        ["sphere", "--voxel", "-0.5"],
        ["sphere", "--bounds", "1,1,1,0,0,0"],
        ["no_such_model", "--resolution", "8"],
    ] {
        let (code, _, err) = run(&args);
        assert_ne!(code, 0, "{args:?}");
        assert!(err.contains("error"), "{args:?}: {err}");
    }
}

/// Kou and Tan's controls from the command line: `analyze` of a model with
/// rational 2D pores (`mfPores2Opt`, weight sqrt(2)/2) measures the
/// porosity it was built for, and a bad weight is refused with the
/// element it names.
#[test]
fn rational_pores_from_a_model_file_keep_their_porosity() {
    let src = |w: &str| {
        format!(
            "my_model(x[3], a[1]) {{\n  array v[3], o[4];\n  v = [0, 0, 0];\n  \
             o = [0.15, 1, 0, {w}];\n  b = hfBlock(x, v, 4, 4, 1);\n  \
             my_model = mfPores2Opt(x, b, 1, 0.6, 1, o);\n}}\n"
        )
    };
    let m = model("rational_pores.hf", &src("0.7071067811865476"));
    let v = json(&[
        &m,
        "--bounds",
        "0,0,0,4,4,1",
        "--resolution",
        "256",
        "--json",
        "--no-thickness",
    ]);
    let f = v["volume_fraction"]["value"].as_f64().unwrap();
    let e = v["volume_fraction"]["error"].as_f64().unwrap_or(0.0);
    assert!((f - 0.4).abs() < 0.003 + e, "{f} ± {e}");
    let bad = model("bad_weight.hf", &src("0"));
    let (code, _, err) = run(&[&bad, "--json"]);
    assert!(code != 0 && err.contains("weight"), "{err}");
}
