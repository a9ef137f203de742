//! The STL job (`mesh_to_file` to `.stl`) encodes, measures and counts the
//! edges while the mesh is made, and sends the file to the disk by direct
//! I/O as it grows: its bytes and figures are those of meshing in memory,
//! writing with `write_mesh` and checking with `check`, whatever the
//! thread count; and a job that fails leaves nothing behind.

use microfrep_core::{Expr, Shape};
use microfrep_mesh::check::{bbox, check, volume_area};
use microfrep_mesh::job::{mesh_to_file, JobOptions};
use microfrep_mesh::write::write_mesh;
use microfrep_mesh::{MeshError, MeshOptions, Plan};
use microfrep_structures::tpms::{tpms, Solid, Tpms};
use std::path::PathBuf;

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("microfrep-stljob-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn entries(d: &std::path::Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// A 12 mm cube of 4 mm gyroid sheets: at 100 cells about 570 000
/// triangles (more than one encoding step at up to 4 threads, a 28 MB
/// file) in four slabs of bricks.
fn gyroid() -> (Shape, MeshOptions) {
    let p = Expr::xyz();
    let cube = microfrep_shapes::block(
        &p,
        &microfrep_shapes::v3([0.0; 3]),
        &microfrep_shapes::v3([12.0; 3]),
    );
    let shape = Shape::new(cube.min(tpms(Tpms::Gyroid, Solid::Sheet, &p, 4.0, 0.3)));
    let b = shape.bounds().unwrap().corners();
    (shape, MeshOptions::new(b, 100))
}

fn with_threads<T: Send>(n: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .unwrap()
        .install(f)
}

#[test]
fn stl_jobs_write_the_bytes_and_figures_of_meshing_in_memory() {
    let (shape, opts) = gyroid();
    let d = dir("eq");
    let reference = d.join("reference.stl");
    let mesh = Plan::new(&shape, &opts).unwrap().run(&|_| {}).unwrap();
    write_mesh(&reference, &mesh, None).unwrap();
    let want = std::fs::read(&reference).unwrap();
    let r = check(&mesh);
    assert!(r.is_closed_manifold() && r.triangles > 500_000, "{r:?}");
    let (volume, area) = volume_area(&mesh);
    for threads in [1, 2, 3] {
        let out = d.join(format!("job{threads}.stl"));
        let s = with_threads(threads, || {
            mesh_to_file(&shape, &opts, &out, &JobOptions::default(), &|_, _| {}).unwrap()
        });
        assert!(std::fs::read(&out).unwrap() == want, "{threads} threads");
        assert_eq!(
            (s.vertices, s.triangles),
            (r.vertices as u64, r.triangles as u64)
        );
        assert_eq!((s.bad_edges, s.euler), (Some(0), Some(r.euler)));
        // Measured while encoding: the same sums in the same order.
        assert_eq!(s.volume.to_bits(), volume.to_bits());
        assert_eq!(s.area.to_bits(), area.to_bits());
        assert_eq!(s.bbox, bbox(&mesh));
        assert!(!s.streamed && s.volume_loss.unwrap().abs() < 0.01, "{s:?}");
    }
    // Streamed to disk (STL and PLY): the same figures, the edges counted
    // while streaming.
    for ext in ["stl", "ply"] {
        let out = d.join(format!("streamed.{ext}"));
        let job = JobOptions {
            stream: true,
            ..JobOptions::default()
        };
        let s = mesh_to_file(&shape, &opts, &out, &job, &|_, _| {}).unwrap();
        assert!(s.streamed, "{s:?}");
        assert_eq!((s.bad_edges, s.euler), (Some(0), Some(r.euler)), "{ext}");
        std::fs::remove_file(&out).unwrap();
    }
    assert_eq!(
        entries(&d),
        ["job1.stl", "job2.stl", "job3.stl", "reference.stl"]
    );
    std::fs::remove_dir_all(&d).unwrap();
}

/// A PLY job (meshed in memory, the volume sampled alongside, the shells
/// counted and the volume measured while encoding) writes the bytes of
/// `write_mesh` with the plan's normals and reports the figures of the
/// checks, whatever the thread count.
#[test]
fn ply_jobs_write_the_bytes_and_figures_of_meshing_in_memory() {
    let (shape, opts) = gyroid();
    let d = dir("ply");
    let reference = d.join("reference.ply");
    let plan = Plan::new(&shape, &opts).unwrap();
    let mesh = plan.run(&|_| {}).unwrap();
    write_mesh(&reference, &mesh, Some(&plan.normals(&mesh))).unwrap();
    let want = std::fs::read(&reference).unwrap();
    let r = check(&mesh);
    let (volume, area) = volume_area(&mesh);
    let sampled = microfrep_mesh::sampled::sampled_volume(&plan);
    for threads in [1, 2, 3] {
        let out = d.join(format!("job{threads}.ply"));
        let s = with_threads(threads, || {
            mesh_to_file(&shape, &opts, &out, &JobOptions::default(), &|_, _| {}).unwrap()
        });
        assert!(std::fs::read(&out).unwrap() == want, "{threads} threads");
        assert_eq!(
            (s.vertices, s.triangles),
            (r.vertices as u64, r.triangles as u64)
        );
        assert_eq!((s.bad_edges, s.euler), (Some(0), Some(r.euler)));
        assert_eq!(s.volume.to_bits(), volume.to_bits());
        assert_eq!(s.area.to_bits(), area.to_bits());
        assert_eq!(s.bbox, bbox(&mesh));
        assert_eq!(s.shells, Some(microfrep_mesh::check::shells(&mesh)));
        assert_eq!(s.sampled_volume, Some(sampled), "{threads} threads");
        assert!(!s.streamed && s.volume_loss.unwrap().abs() < 0.01, "{s:?}");
    }
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn a_failed_stl_job_leaves_nothing_behind() {
    let (shape, opts) = gyroid();
    let d = dir("fail");
    // No volume loss is small enough: the verdict fails after the whole
    // file (direct I/O past its first 4 MiB) was written.
    let job = JobOptions {
        max_volume_loss: Some(-1.0),
        ..JobOptions::default()
    };
    let out = d.join("g.stl");
    let e = mesh_to_file(&shape, &opts, &out, &job, &|_, _| {}).unwrap_err();
    assert!(matches!(e, MeshError::VolumeLoss(_)), "{e}");
    assert!(entries(&d).is_empty(), "{:?}", entries(&d));
    // A target in a missing directory: refused, nothing anywhere.
    let e = mesh_to_file(
        &shape,
        &opts,
        &d.join("missing").join("g.stl"),
        &JobOptions::default(),
        &|_, _| {},
    )
    .unwrap_err();
    assert!(e.to_string().contains("missing"), "{e}");
    assert!(entries(&d).is_empty(), "{:?}", entries(&d));
    std::fs::remove_dir_all(&d).unwrap();
}

/// A hollow ball (outer and inner surface) beside a solid one: three
/// shells, counted by the job as the mesh comes, the same for the STL job,
/// for a format written from memory, and by hand from the welded mesh.
#[test]
fn jobs_count_the_shells_of_what_they_write() {
    let p = Expr::xyz();
    let s = microfrep_shapes::v3;
    let hollow = microfrep_shapes::sphere(&p, &s([0.0; 3]), 5.0).min(-microfrep_shapes::sphere(
        &p,
        &s([0.0; 3]),
        3.0,
    ));
    let solid = microfrep_shapes::sphere(&p, &s([9.0, 0.0, 0.0]), 2.0);
    let shape = Shape::new(hollow.max(solid));
    let opts = MeshOptions::new([[-6.0, -6.0, -6.0], [12.0, 6.0, 6.0]], 60);
    let d = dir("shells");
    let mesh = Plan::new(&shape, &opts).unwrap().run(&|_| {}).unwrap();
    assert_eq!(microfrep_mesh::check::shells(&mesh), 3);
    for name in ["a.stl", "a.obj", "a.ply"] {
        let out = d.join(name);
        let r = mesh_to_file(&shape, &opts, &out, &JobOptions::default(), &|_, _| {}).unwrap();
        assert_eq!(r.shells, Some(3), "{name}");
    }
    // One ball: one shell.
    let one = Shape::new(microfrep_shapes::sphere(&p, &s([0.0; 3]), 5.0));
    let out = d.join("b.stl");
    let r = mesh_to_file(&one, &opts, &out, &JobOptions::default(), &|_, _| {}).unwrap();
    assert_eq!(r.shells, Some(1));
    let _ = std::fs::remove_dir_all(&d);
}
