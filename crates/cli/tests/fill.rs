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
