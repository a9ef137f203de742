//! The real bone meshes of `../shared/meshes` (read relative to this crate:
//! `../../../shared/meshes`, or from `MICROFREP_MESHES`): they load, weld
//! closed, and the field's inside has the volume of the divergence theorem.
//! Skipped, with a message, where the folder is absent.

mod common;

use common::*;
use microfrep_core::field_check::{check_field, FieldCheck};
use microfrep_core::Field;
use microfrep_meshfield::read::read_mesh;
use microfrep_meshfield::{MeshField, SignMethod};
use rayon::prelude::*;
use std::path::PathBuf;
use std::sync::Arc;

fn meshes_dir() -> Option<PathBuf> {
    let dir = std::env::var_os("MICROFREP_MESHES")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/meshes")
        });
    dir.join("femur.stl").exists().then_some(dir)
}

/// Fraction of cell centres of a grid over the bbox that are inside, times
/// the bbox volume; batches of 256 points per row chunk, rows in parallel.
fn grid_volume(f: &MeshField, cell: f64) -> f64 {
    let [lo, hi] = f.bbox();
    let n = [0, 1, 2].map(|a| ((hi[a] - lo[a]) / cell).ceil() as usize);
    let inside: usize = (0..n[2] * n[1])
        .into_par_iter()
        .map(|row| {
            let (k, j) = (row / n[1], row % n[1]);
            let y = (lo[1] + (j as f64 + 0.5) * cell) as f32;
            let z = (lo[2] + (k as f64 + 0.5) * cell) as f32;
            let mut count = 0;
            for start in (0..n[0]).step_by(256) {
                let m = (n[0] - start).min(256);
                let xs: Vec<f32> = (start..start + m)
                    .map(|i| (lo[0] + (i as f64 + 0.5) * cell) as f32)
                    .collect();
                let mut out = vec![0f32; m];
                f.eval_batch(&xs, &vec![y; m], &vec![z; m], &mut out);
                count += out.iter().filter(|v| **v > 0.0).count();
            }
            count
        })
        .sum();
    inside as f64 * cell * cell * cell
}

#[test]
fn bone_meshes_load_close_and_measure() {
    let Some(dir) = meshes_dir() else {
        println!("skipped: ../shared/meshes not found (set MICROFREP_MESHES to its folder)");
        return;
    };
    for (name, triangles) in [("femur.stl", 7904), ("hip.stl", 16218)] {
        let raw = read_mesh(dir.join(name)).unwrap();
        assert_eq!(raw.triangles.len(), triangles, "{name}");
        let (mesh, collapsed) = raw.weld(0.0);
        assert_eq!(collapsed, 0);
        let topo = mesh.topology();
        assert!(topo.is_closed_and_oriented(), "{name}: {topo:?}");
        let volume = mesh.volume();
        assert!(volume > 0.0, "{name}: {volume}");
        let f = MeshField::new(&mesh).unwrap();
        println!(
            "{name}: {} vertices, volume {volume:.1} mm^3, area {:.1} mm^2, sign {:?}, {:?}",
            mesh.vertices.len(),
            mesh.area(),
            f.sign_method(),
            topo.warnings()
        );
        // The field's inside measured on a grid (~300k cells) against the
        // divergence theorem: the boundary cells' error is about area x cell
        // and mostly cancels.
        let [lo, hi] = mesh.bbox();
        let bv: f64 = (0..3).map(|a| hi[a] - lo[a]).product();
        let cell = (bv / 3e5).cbrt();
        let grid = grid_volume(&f, cell);
        let tol = 0.01 * mesh.area() * cell;
        println!("{name}: grid volume {grid:.1}, divergence {volume:.1}, tolerance {tol:.1}");
        assert!((grid - volume).abs() < tol, "{name}: {grid} vs {volume}");
        // Distance and sign against brute force; the soup (as read) too.
        let pts = sample_points(&mesh, 300, 5);
        check_reference(name, &f, &mesh, &mesh, &pts, 1e-3);
        let soup = MeshField::new(&raw).unwrap();
        assert_eq!(soup.sign_method(), SignMethod::Winding);
        check_reference(
            &format!("{name} unwelded"),
            &soup,
            &raw,
            &mesh,
            &pts[..100],
            1e-3,
        );
        // Four-mode check around the bone.
        let g = 0.1 * mesh.diagonal();
        let mut cfg = FieldCheck::new([lo.map(|c| c - g), hi.map(|c| c + g)]);
        cfg.points = 300;
        cfg.boxes = 100;
        let field: Arc<dyn Field> = Arc::new(f);
        check_field(&field, &cfg).unwrap_or_else(|e| panic!("{name}: {e}"));
    }
}
