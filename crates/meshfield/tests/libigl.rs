//! Optional cross-check against libigl's `signed_distance` with the fast
//! winding number sign, on the same meshes and points. Off by default so CI
//! installs nothing: run with `MICROFREP_LIBIGL=1 cargo test --release -p
//! microfrep-meshfield --test libigl -- --nocapture`. It uses
//! `MICROFREP_LIBIGL_PYTHON`, or the venv `target/libigl-venv` (created with
//! `pip install libigl numpy` when missing); when requested and libigl
//! cannot be had, the test fails.
//!
//! Asserted: our unsigned distance agrees within 1e-6 of the bbox diagonal
//! with libigl's exact `point_mesh_squared_distance` at every point (the
//! magnitudes of `signed_distance` with the fast winding number sign are
//! not exact: their largest difference is printed); at points farther than 1e-3 of the diagonal
//! from the surface our sign is the exact (brute-force winding number) sign
//! of the clean mesh, and so is libigl's on the clean mesh. How often
//! libigl's sign is wrong on the damaged variants is printed.

mod common;

use common::*;
use microfrep_core::Field;
use microfrep_meshfield::{MeshField, TriMesh};
use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The Python with libigl, or why there is none.
fn python() -> Result<PathBuf, String> {
    let dir = root().join("target");
    microfrep_testsupport::pyvenv::python_with(&microfrep_testsupport::pyvenv::PythonSpec {
        override_var: "MICROFREP_LIBIGL_PYTHON",
        venv: &dir.join("libigl-venv"),
        check: "import igl, numpy",
        packages: &["libigl", "numpy"],
        log: &dir.join("libigl-install.log"),
    })
}

fn write_f64(path: &Path, rows: &[[f64; 3]]) {
    let bytes: Vec<u8> = rows
        .iter()
        .flatten()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    std::fs::write(path, bytes).unwrap();
}

fn read_f64(path: &Path) -> Vec<f64> {
    std::fs::read(path)
        .unwrap()
        .chunks_exact(8)
        .map(|b| f64::from_le_bytes(b.try_into().unwrap()))
        .collect()
}

/// libigl's signed distances (positive inside, fast winding number sign)
/// and exact unsigned distances at `pts`.
fn libigl(py: &Path, m: &TriMesh, pts: &[[f64; 3]], tag: &str) -> (Vec<f64>, Vec<f64>) {
    let dir = root().join("target/libigl-check");
    std::fs::create_dir_all(&dir).unwrap();
    let (v, f, p, o) = (
        dir.join(format!("{tag}.v")),
        dir.join(format!("{tag}.f")),
        dir.join(format!("{tag}.p")),
        dir.join(format!("{tag}.s")),
    );
    write_f64(&v, &m.vertices);
    let fb: Vec<u8> = m
        .triangles
        .iter()
        .flatten()
        .flat_map(|&i| (i as i64).to_le_bytes())
        .collect();
    std::fs::write(&f, fb).unwrap();
    write_f64(&p, pts);
    let out = Command::new(py)
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/libigl_sd.py"))
        .args([&v, &f, &p, &o])
        .args(["1", "1"])
        .env("IGL_NUM_THREADS", "2")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "libigl script failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mut exact = o.clone().into_os_string();
    exact.push(".exact");
    (read_f64(&o), read_f64(Path::new(&exact)))
}

fn compare(py: &Path, tag: &str, m: &TriMesh, clean: &TriMesh, pts: &[[f64; 3]], clean_case: bool) {
    let diag = clean.diagonal();
    let f = MeshField::new(m).unwrap();
    let (theirs, exact) = libigl(py, m, pts, tag);
    let (ct, dt) = (soup(clean), soup(m));
    let (mut checked, mut ours_wrong, mut theirs_wrong) = (0, 0, 0);
    let (mut max_diff, mut max_fwn_diff) = (0.0f64, 0.0f64);
    for (i, &p) in pts.iter().enumerate() {
        let v = f.eval(p);
        let diff = (v.abs() - exact[i]).abs();
        max_diff = max_diff.max(diff);
        max_fwn_diff = max_fwn_diff.max((v.abs() - theirs[i].abs()).abs());
        assert!(
            diff <= 1e-6 * diag,
            "{tag}: distance at {p:?}: ours {v}, libigl {}",
            exact[i]
        );
        if brute_distance(&ct, p).min(brute_distance(&dt, p)) > 1e-3 * diag {
            checked += 1;
            let inside = brute_inside(&ct, p);
            ours_wrong += ((v > 0.0) != inside) as usize;
            theirs_wrong += ((theirs[i] > 0.0) != inside) as usize;
        }
    }
    println!(
        "{tag}: {} points, max |distance difference| {max_diff:.2e} (against signed_distance's \
         magnitude {max_fwn_diff:.2e}; diag {diag:.3}); signs checked at {checked}: \
         ours wrong {ours_wrong}, libigl wrong {theirs_wrong}",
        pts.len(),
    );
    assert_eq!(ours_wrong, 0, "{tag}");
    if clean_case {
        assert_eq!(theirs_wrong, 0, "{tag}: libigl on the clean mesh");
    }
}

#[test]
fn signed_distance_agrees_with_libigl() {
    if std::env::var("MICROFREP_LIBIGL").is_err() {
        println!("skipped: set MICROFREP_LIBIGL=1 to cross-check against libigl");
        return;
    }
    let py = python()
        .unwrap_or_else(|e| panic!("MICROFREP_LIBIGL is set but libigl is unavailable: {e}"));
    for (tag, m) in [
        ("sphere", icosphere(4, 1.0, [0.0; 3])),
        ("torus", torus(64, 32, 1.0, 0.35)),
    ] {
        let pts = sample_points(&m, 2000, 17);
        compare(&py, tag, &m, &m, &pts, true);
        compare(
            &py,
            &format!("{tag}-holes"),
            &remove_fraction(&m, 0.01, 3),
            &m,
            &pts,
            false,
        );
        compare(
            &py,
            &format!("{tag}-flipped"),
            &flip_fraction(&m, 0.15, 5).0,
            &m,
            &pts,
            false,
        );
        compare(
            &py,
            &format!("{tag}-unwelded"),
            &m.unwelded(),
            &m,
            &pts,
            false,
        );
    }
}
