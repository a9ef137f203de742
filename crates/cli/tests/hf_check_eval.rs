//! `microfrep check` and `microfrep eval` on HyperFun files: every error
//! with its location, source line and caret; warnings; exit codes; values,
//! gradients and run-time errors per point; `--object` and `--param`.

use std::io::Write;
use std::process::{Command, Stdio};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_microfrep"))
}

/// Writes `src` to a fresh temporary `.hf` file and returns its path.
fn model(name: &str, src: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("microfrep-cli-hf-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, src).unwrap();
    p
}

/// Runs with `stdin`; returns (exit code, stdout, stderr).
fn run(args: &[&str], stdin: &str) -> (i32, String, String) {
    let mut child = bin()
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    child
        .stdin
        .take()
        .unwrap()
        .write_all(stdin.as_bytes())
        .unwrap();
    let out = child.wait_with_output().unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn check_reports_every_error_with_line_column_and_caret() {
    let p = model(
        "bad.hf",
        "my_model(x[3], a[1])\n{\n  y = sin(x[1]) + ;\n  z = q + 1;\n  w = 01;\n  my_model = y;\n}\n",
    );
    let (code, _, err) = run(&["check", p.to_str().unwrap()], "");
    assert_ne!(code, 0);
    let f = p.display().to_string();
    for (loc, msg, caret_line) in [
        (
            "3:19",
            "Expression expected",
            "    y = sin(x[1]) + ;\n                    ^",
        ),
        (
            "4:7",
            "Unassigned identificator used in expression",
            "    z = q + 1;\n        ^",
        ),
        ("5:7", "Expression expected", "    w = 01;\n        ^"),
    ] {
        assert!(err.contains(&format!("{f}:{loc}: error: {msg}")), "{err}");
        assert!(err.contains(caret_line), "{caret_line:?} in\n{err}");
    }
    assert!(err.contains("3 error(s)"), "{err}");
}

#[test]
fn check_lists_objects_and_parameters_and_warns_on_quirks() {
    let p = model(
        "ok.hf",
        "inner(x[3], a[2])\n{\n  inner = a[1] - x[1];\n}\r\nmy_model(x[3], a[2])\n{\n  my_model = inner(x, a) + sign(x[2]);\n}\n",
    );
    let (code, out, err) = run(&["check", p.to_str().unwrap()], "");
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("object inner(x[3], a[2], s[1])"), "{out}");
    assert!(out.contains("object my_model(x[3], a[2], s[1])"), "{out}");
    assert!(out.contains("evaluated object: my_model"), "{out}");
    assert!(out.contains("parameters: a[1] a[2]"), "{out}");
    // The CR of line 4 and the call of sign on line 7.
    assert!(err.contains(":4:2: warning: carriage return"), "{err}");
    assert!(
        err.contains(":7:28: warning: sign() always returns 1"),
        "{err}"
    );
    // Another object by name.
    let (code, out, _) = run(&["check", p.to_str().unwrap(), "--object", "inner"], "");
    assert_eq!(code, 0);
    assert!(out.contains("evaluated object: inner"), "{out}");
    let (code, _, err) = run(&["check", p.to_str().unwrap(), "--object", "nope"], "");
    assert_ne!(code, 0);
    assert!(err.contains("no object named 'nope'"), "{err}");
}

#[test]
fn eval_prints_values_gradients_and_located_run_time_errors() {
    let p = model(
        "rt.hf",
        "first(x[3], a[2])\n{\n  first = a[1] - x[1];\n}\nmy_model(x[3], a[2])\n{\n  my_model = 1 / (x[1] - a[2]) + sqrt(x[2]) + a[1];\n}\n",
    );
    let f = p.to_str().unwrap();
    let (code, out, err) = run(
        &["eval", f, "-a", "2=0.5", "--param", "1=3"],
        "1 0 0\n0.5 0 0\n1 -1 0\n",
    );
    assert_eq!(code, 0, "{err}");
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(
        lines,
        [
            "5",
            "error: Division by zero at 7:16",
            "error: Negative value for square root at 7:34",
        ]
    );
    // Gradient of a[1] - x[1] in `first`, and the shortest round-trip decimal.
    let (code, out, _) = run(
        &["eval", f, "--object", "first", "-a", "1=0.1", "--grad"],
        "0.2 5 6\n",
    );
    assert_eq!(code, 0);
    assert_eq!(out.trim(), "-0.1 -1 0 0");
    // Points as arguments, and bad input is an error, not a panic.
    let (code, out, _) = run(&["eval", f, "--object", "first", "0.25", "0", "0"], "");
    assert_eq!((code, out.trim()), (0, "-0.25"));
    let (code, _, err) = run(&["eval", f], "1 2\n");
    assert_ne!(code, 0);
    assert!(err.contains("expected 3 numbers"), "{err}");
    let (code, _, err) = run(&["eval", f, "-a", "3=1", "0", "0", "0"], "");
    assert_ne!(code, 0);
    assert!(err.contains("a[3] out of range"), "{err}");
}

#[test]
fn eval_reports_all_parse_errors_with_carets() {
    let p = model(
        "bad_eval.hf",
        "my_model(x[3], a[1])\n{\n  y = 1 + ;\n  my_model = q;\n}\n",
    );
    let (code, out, err) = run(&["eval", p.to_str().unwrap(), "0", "0", "0"], "");
    assert_ne!(code, 0);
    assert!(out.is_empty());
    assert!(
        err.contains(":3:11: error: Expression expected\n    y = 1 + ;\n            ^"),
        "{err}"
    );
    assert!(
        err.contains(":4:14: error: Unassigned identificator"),
        "{err}"
    );
}
