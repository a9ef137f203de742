//! Meshes streamed to disk equal the in-memory ones byte for byte; the
//! pipeline's grouping of slabs (which follows the thread count) does not
//! change the output.

use microfrep_core::Shape;
use microfrep_mesh::check::check;
use microfrep_mesh::write::{stream_mesh, write_mesh};
use microfrep_mesh::{Mesh, MeshOptions, Plan};
use microfrep_structures::examples::toriball;
use std::path::PathBuf;

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("microfrep-stream-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The tori-ball at 40 cells in bricks of 8: six slabs of 36 bricks.
fn plan() -> Plan {
    let mut o = MeshOptions::new([[-1.0; 3], [1.0; 3]], 40);
    o.brick = 8;
    Plan::new(&Shape::from(&toriball()), &o).unwrap()
}

fn with_threads<T: Send>(n: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .unwrap()
        .install(f)
}

#[test]
fn streamed_stl_and_ply_equal_the_in_memory_files() {
    let p = plan();
    let mesh = p.run(&|_| {}).unwrap();
    let r = check(&mesh);
    assert!(r.is_closed_manifold() && r.triangles > 10_000, "{r:?}");
    let d = dir("eq");
    for (ext, normals) in [("stl", false), ("ply", true), ("ply", false)] {
        let (a, b) = (d.join(format!("a.{ext}")), d.join(format!("b.{ext}")));
        let ns = normals.then(|| p.normals(&mesh));
        write_mesh(&a, &mesh, ns.as_deref()).unwrap();
        let t = stream_mesh(&p, &b, normals, &|_| {}).unwrap();
        assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
        assert_eq!(
            (t.vertices, t.triangles),
            (r.vertices as u64, r.triangles as u64)
        );
        assert!((t.volume - r.volume).abs() < 1e-9 && (t.area - r.area).abs() < 1e-9);
        assert_eq!(t.bbox, r.bbox);
        // Edges counted while streaming, as the in-memory check counts them.
        assert_eq!(t.edges, Some(microfrep_mesh::check::edges(&mesh)));
        assert_eq!(t.edges.map(|e| e.1), Some(0));
        let left: Vec<_> = std::fs::read_dir(&d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".partial"))
            .collect();
        assert!(left.is_empty(), "{left:?} left behind");
    }
}

#[test]
fn output_does_not_depend_on_the_thread_count() {
    // 36 bricks a slab: 1 thread puts one slab in each pipeline step, 16
    // threads two, 40 threads five.
    let run = |n| -> Mesh { with_threads(n, || plan().run(&|_| {}).unwrap()) };
    let one = run(1);
    assert!(one == run(16));
    assert!(one == run(40));
}

#[test]
fn failed_streams_leave_nothing() {
    let d = dir("fail");
    let out = d.join("missing").join("m.stl");
    let e = stream_mesh(&plan(), &out, false, &|_| {}).unwrap_err();
    assert!(e.to_string().contains("missing"), "{e}");
    let obj = d.join("m.obj");
    assert!(stream_mesh(&plan(), &obj, false, &|_| {}).is_err());
    assert_eq!(std::fs::read_dir(&d).unwrap().count(), 0);
}
