//! Optional cross-check against PoreSpy (porosity and local thickness on
//! the same voxels). Off by default so CI spends no time installing it: run
//! with `MICROFREP_PORESPY=1 cargo test --release -p microfrep-analysis
//! --test porespy -- --nocapture`. It uses `MICROFREP_PORESPY_PYTHON`, or
//! the venv `target/porespy-venv` (created with `pip install porespy` when
//! missing and the registry is reachable); without PoreSpy it prints why
//! and passes.
//!
//! PoreSpy's `local_thickness` (default method) returns integer radii: a
//! voxel gets the largest integer `r` whose sphere, centred where the
//! distance transform is at least `r`, covers it. Ours is the exact
//! Hildebrand value: the largest ball of radius `sqrt(D)` (not floored)
//! covering the voxel, on the same grid. So ours is never lower, and higher
//! by the flooring of the radius (up to 2 voxels of diameter) plus, for
//! voxels in the shell between a floored and a full ball, by the drop to
//! the next ball (a few voxels). Tolerances, ours minus PoreSpy's, in
//! voxels of diameter: per voxel in [-0.01, 6) for 99.9 % of the voxels;
//! mean and median in [0, 2]; max in [0, 2). Porosity: identical.

use microfrep_analysis::grid::{Grid, Sampler, PORE, SOLID};
use microfrep_analysis::thickness::local_thickness_field;
use microfrep_core::{Expr, Shape};
use microfrep_structures::examples::toriball;
use microfrep_structures::lattice::{rod_lattice, Slabs};
use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The Python with PoreSpy, or why there is none.
fn python() -> Result<PathBuf, String> {
    let dir = root().join("target");
    microfrep_testsupport::pyvenv::python_with(&microfrep_testsupport::pyvenv::PythonSpec {
        override_var: "MICROFREP_PORESPY_PYTHON",
        venv: &dir.join("porespy-venv"),
        check: "import porespy",
        packages: &["porespy"],
        log: &dir.join("porespy-install.log"),
    })
}

/// Diameters (voxels) from PoreSpy for `phase` of `labels`, and its porosity.
fn porespy(py: &Path, labels: &[u8], dims: [usize; 3], phase: u8, tag: &str) -> (Vec<f32>, f64) {
    let dir = root().join("target/porespy-check");
    std::fs::create_dir_all(&dir).unwrap();
    let raw = dir.join(format!("{tag}.raw"));
    let field = dir.join(format!("{tag}-{phase}.f32"));
    std::fs::write(&raw, labels).unwrap();
    let out = Command::new(py)
        .arg(root().join("bench/porespy_thickness.py"))
        .arg(&raw)
        .args(dims.map(|d| d.to_string()))
        .arg(phase.to_string())
        .arg(&field)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "PoreSpy script failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    let key = "\"porosity\":";
    let at = text.find(key).expect("porosity in output") + key.len();
    let porosity: f64 = text[at..]
        .split([',', '}'])
        .next()
        .unwrap()
        .trim()
        .parse()
        .unwrap();
    let bytes = std::fs::read(&field).unwrap();
    let values = bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    (values, porosity)
}

fn mean(v: &[f32]) -> f64 {
    v.iter().map(|&x| x as f64).sum::<f64>() / v.len() as f64
}

fn median(v: &[f32]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f32::total_cmp);
    s[(s.len() - 1) / 2] as f64
}

fn max(v: &[f32]) -> f64 {
    v.iter().cloned().fold(0.0, f32::max) as f64
}

fn compare(py: &Path, tag: &str, model: &Expr, bounds: [[f64; 3]; 2], n: usize) {
    let tape = Shape::from(model);
    let grid = Grid::new(bounds, n).unwrap();
    let dims = grid.dims;
    let labels = Sampler::new(&tape, None, grid).all(&|_, _| {});
    let ours_porosity = labels.iter().filter(|&&l| l == PORE).count() as f64 / labels.len() as f64;
    for phase in [PORE, SOLID] {
        let ours = local_thickness_field(&labels, dims, phase).unwrap();
        let (theirs, porosity) = porespy(py, &labels, dims, phase, tag);
        assert!(
            (porosity - ours_porosity).abs() < 1e-12,
            "porosity {porosity} vs {ours_porosity}"
        );
        let idx: Vec<usize> = (0..labels.len()).filter(|&i| labels[i] == phase).collect();
        let a: Vec<f32> = idx.iter().map(|&i| ours[i]).collect();
        let b: Vec<f32> = idx.iter().map(|&i| theirs[i]).collect();
        let close = a
            .iter()
            .zip(&b)
            .filter(|(a, b)| (-0.01..6.0).contains(&(**a - **b)))
            .count();
        let frac = close as f64 / a.len() as f64;
        let (dm, dmed, dmax) = (
            mean(&a) - mean(&b),
            median(&a) - median(&b),
            max(&a) - max(&b),
        );
        println!(
            "{tag} phase {phase}: porosity {porosity:.4}; diameters (voxels) ours/PoreSpy mean {:.3}/{:.3} \
             median {:.3}/{:.3} max {:.3}/{:.3}; voxels within [-0.01, 6): {:.5}",
            mean(&a),
            mean(&b),
            median(&a),
            median(&b),
            max(&a),
            max(&b),
            frac
        );
        assert!(
            frac >= 0.99,
            "{tag} phase {phase}: only {frac} of voxels agree"
        );
        assert!(
            (0.0..=2.0).contains(&dm),
            "{tag} phase {phase}: mean differs by {dm}"
        );
        assert!(
            (0.0..=2.0).contains(&dmed),
            "{tag} phase {phase}: median differs by {dmed}"
        );
        assert!(
            (0.0..2.0).contains(&dmax),
            "{tag} phase {phase}: max differs by {dmax}"
        );
    }
}

#[test]
fn local_thickness_and_porosity_agree_with_porespy() {
    if std::env::var("MICROFREP_PORESPY").is_err() {
        println!("skipped: set MICROFREP_PORESPY=1 to cross-check against PoreSpy");
        return;
    }
    let py = match python() {
        Ok(py) => py,
        Err(e) => {
            println!("skipped: PoreSpy unavailable: {e}");
            return;
        }
    };
    compare(&py, "toriball128", &toriball(), [[-1.0; 3], [1.0; 3]], 128);
    let q = 4.0 * std::f64::consts::PI;
    let l = (std::f64::consts::PI / 4.0).sin();
    let lattice = rod_lattice(&Expr::xyz(), &Slabs::uniform(q, l), 1.0);
    compare(&py, "rods96", &lattice, [[-0.875; 3], [0.625; 3]], 96);
}
