//! `microfrep fill` end to end: a HyperFun ball with a 1 mm skin (its value
//! is no distance) measures a 1 mm skin and writes two shells; bad requests
//! are refused with nothing written and name only options `fill` has.

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

fn ball(d: &std::path::Path) -> String {
    let p = d.join("ball.hf");
    std::fs::write(
        &p,
        "my_model(x[3], a[1]) {\n  array c[3];\n  c = [0, 0, 0];\n  my_model = hfSphere(x, c, 10);\n}\n",
    )
    .unwrap();
    p.display().to_string()
}

#[test]
fn a_hyperfun_ball_with_a_one_millimetre_skin() {
    let d = dir("ball");
    let part = ball(&d);
    let out = d.join("f.stl");
    let o = Command::new(bin())
        .args([
            "fill",
            &part,
            "--structure",
            "gyroid",
            "--cell",
            "4",
            "--density",
            "0.3",
            "--shell",
            "1",
            "--json",
            "-o",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let mean = j["skin"]["mean"].as_f64().unwrap();
    assert!((mean - 1.0).abs() < 0.05, "{j}");
    assert!(j["written"]["shells"].as_u64().unwrap() >= 2, "{j}");
    let rho = j["density"]["measured"].as_f64().unwrap();
    assert!((rho - 0.3).abs() < 0.02, "{j}");
    assert_eq!(j["connectivity"]["sealed_by_skin"], serde_json::json!(true));
    assert!(out.exists());
}

#[test]
fn bad_requests_write_nothing_and_advise_real_options() {
    let d = dir("bad");
    let part = ball(&d);
    let help = Command::new(bin())
        .args(["fill", "--help"])
        .output()
        .unwrap();
    let help = String::from_utf8_lossy(&help.stdout).to_string();
    for (extra, out) in [
        (vec!["--density", "0.3"], "x.xyz"),
        (
            vec!["--density", "0.3", "--resolution", "8", "--shell", "1"],
            "y.stl",
        ),
        (vec!["--density-expr", "2"], "z.stl"),
        (
            vec!["--density", "0.3", "--seed", "18014398509481984"],
            "s.stl",
        ),
    ] {
        let target = d.join(out);
        let o = Command::new(bin())
            .args(["fill", &part, "--structure", "gyroid", "--cell", "4"])
            .args(&extra)
            .arg("-o")
            .arg(&target)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr).to_string();
        assert!(!o.status.success(), "{extra:?} {out}");
        assert!(!target.exists(), "{extra:?}: wrote {out}");
        assert!(!err.contains("/tmp/microfrep-fill"), "{err}");
        for w in err.split_whitespace().filter(|w| w.starts_with("--")) {
            let opt: String = w
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '-')
                .collect();
            assert!(
                help.contains(&opt),
                "{err}: advises {opt}, which fill lacks"
            );
        }
    }
}

fn fill_json(args: &[&str], out: &std::path::Path) -> serde_json::Value {
    let o = Command::new(bin())
        .arg("fill")
        .args(args)
        .args(["--json", "-o"])
        .arg(out)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(out.exists());
    serde_json::from_slice(&o.stdout).unwrap()
}

#[test]
fn the_mesh_follows_the_walls_and_names_slivers_it_cannot_show() {
    let d = dir("rule");
    let part = ball(&d);
    // Irregular pores: random walls, some nearly closed. The mesh cells are
    // at most half the designed wall (or the walls' 10th percentile); walls
    // below two cells are named in a note with the resolution that shows
    // them.
    let j = fill_json(
        &[
            &part,
            "--structure",
            "irregular",
            "--cell",
            "3",
            "--density",
            "0.3",
        ],
        &d.join("irr.stl"),
    );
    let cell = j["written"]["cell"].as_f64().unwrap();
    let feature = j["measured"]["feature"].as_f64().unwrap();
    for key in ["thinnest", "pore_size"] {
        let t = &j[key];
        let (min, p10, mean) = (
            t["min"].as_f64().unwrap(),
            t["p10"].as_f64().unwrap(),
            t["mean"].as_f64().unwrap(),
        );
        assert!(min > 0.0 && min <= p10 && p10 <= mean, "{key}: {j}");
    }
    let t = &j["thinnest"];
    let wall = t["min"]
        .as_f64()
        .unwrap()
        .max(t["p10"].as_f64().unwrap().min(feature));
    assert!(
        cell <= wall / 2.0 * 1.01,
        "cells {cell} for walls {wall}: {j}"
    );
    let noted = j["notes"]
        .as_array()
        .unwrap()
        .iter()
        .any(|n| n.as_str().unwrap().contains("under two mesh cells"));
    assert_eq!(
        noted,
        t["min"].as_f64().unwrap() < 2.0 * cell,
        "the sliver note: {j}"
    );

    // A beam lattice meshes only its skin (and the core's clip): the
    // resolution follows the skin, not the struts.
    let j = fill_json(
        &[
            &part,
            "--structure",
            "octet",
            "--cell",
            "4",
            "--density",
            "0.2",
            "--shell",
            "1",
        ],
        &d.join("lattice.3mf"),
    );
    assert_eq!(j["written"]["kind"], "beam-lattice", "{j}");
    let strut = j["thinnest"]["min"].as_f64().unwrap();
    let skin = j["skin"]["min"].as_f64().unwrap();
    assert!(strut < skin, "{j}");
    let n = j["written"]["resolution"].as_f64().unwrap();
    // The ball's box is about 20 mm (bounds from interval analysis may pad
    // it a little): cells near half the skin, well coarser than the struts'.
    assert!(n <= 2.0 * 24.0 / skin + 1.0, "{j}");
    assert!(n >= 2.0 * 20.0 / skin - 1.0, "{j}");
}

#[test]
fn a_mesh_too_large_for_the_machine_is_refused_before_it_is_written() {
    let d = dir("huge");
    let part = d.join("cube.hf");
    std::fs::write(
        &part,
        "my_model(x[3], a[1]) {\n  my_model = min(min(5-abs(x[1]), 5-abs(x[2])), 5-abs(x[3]));\n}\n",
    )
    .unwrap();
    // A 0.05 mm gyroid in a 10 mm cube: walls of about 12 microns, a mesh
    // of over a billion triangles (hundreds of GB to write and check).
    let out = d.join("g.stl");
    let t = std::time::Instant::now();
    let o = Command::new(bin())
        .args(["fill", part.to_str().unwrap(), "--structure", "gyroid"])
        .args(["--cell", "0.05", "--density", "0.3", "-o"])
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{err}");
    assert!(
        err.contains("million triangles") && err.contains("nothing written"),
        "{err}"
    );
    assert!(!out.exists());
    let left: Vec<_> = std::fs::read_dir(&d)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(left.len(), 1, "only the part is left: {left:?}");
    assert!(t.elapsed().as_secs() < 120, "{:?}", t.elapsed());
}

/// `--material-layer` writes attribute channels into a .3mf with a
/// palette, and is refused where they would be lost.
#[test]
fn material_layers_reach_a_3mf_palette_and_are_refused_elsewhere() {
    let d = dir("layers");
    let part = ball(&d);
    let out = d.join("f.3mf");
    let j = fill_json(
        &[
            &part,
            "--structure",
            "gyroid",
            "--cell",
            "4",
            "--density",
            "0.3",
            "--material-layer",
            "1,2",
            "--material-layer",
            "5,1",
            "--palette",
            "outer=#ff0000,inner=#00ff00,skin=#0000ff",
        ],
        &out,
    );
    assert_eq!(
        j["written"]["volumetric"]["attributes"],
        serde_json::json!(2),
        "{j}"
    );
    assert_eq!(
        j["written"]["volumetric"]["materials"],
        serde_json::json!(3),
        "{j}"
    );
    for (args, says) in [
        (vec!["-o", d.join("f.stl").to_str().unwrap()], "only a .3mf"),
        (vec!["-o", d.join("g.3mf").to_str().unwrap()], "only a .3mf"),
        (
            vec![
                "--material-layer",
                "1",
                "-o",
                d.join("h.3mf").to_str().unwrap(),
                "--volumetric",
            ],
            "DEPTH,RAMP",
        ),
    ] {
        let o = Command::new(bin())
            .args([
                "fill",
                &part,
                "--structure",
                "gyroid",
                "--cell",
                "4",
                "--density",
                "0.3",
            ])
            .args(["--material-layer", "1,2"])
            .args(&args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(says), "{args:?}: {err}");
    }
}

/// Irregular pores sized by the paper's volume per pore are those of the
/// cell of its cube root, and hand-set t reach the written model.
#[test]
fn volume_per_pore_and_hand_set_t_reach_the_fill() {
    let d = dir("per-pore");
    let part = ball(&d);
    let run = |args: &[&str], out: &std::path::Path| {
        let o = Command::new(bin())
            .args([
                "fill",
                &part,
                "--structure",
                "irregular",
                "--density",
                "0.4",
            ])
            .args(args)
            .arg("-o")
            .arg(out)
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        std::fs::read_to_string(out).unwrap()
    };
    let by_cell = run(&["--cell", "4"], &d.join("a.hf"));
    let by_volume = run(&["--volume-per-pore", "64"], &d.join("b.hf"));
    assert_eq!(by_cell, by_volume);
    let t = vec!["0.4"; 24].join(",");
    let hand = run(&["--cell", "4", "--pore-t", &t], &d.join("c.hf"));
    assert!(
        hand.contains("mfPoreFieldOpt(") && hand.contains("t set by hand"),
        "{hand}"
    );
    for (args, says) in [
        (vec!["--cell", "4", "--pore-t", "0.4,0.4"], "24 numbers"),
        (vec!["--volume-per-pore=-1"], "positive volume"),
    ] {
        let o = Command::new(bin())
            .args([
                "fill",
                &part,
                "--structure",
                "irregular",
                "--density",
                "0.4",
            ])
            .args(&args)
            .args(["-o", d.join("x.hf").to_str().unwrap()])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(says), "{args:?}: {err}");
    }
}
