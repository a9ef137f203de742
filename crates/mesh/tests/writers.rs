//! Writers: each format read back; failures leave no file behind.

use microfrep_mesh::write::{format_of, write_mesh, StlWriter};
use microfrep_mesh::Mesh;
use std::io::Cursor;
use std::path::PathBuf;

fn tetra() -> Mesh {
    Mesh {
        vertices: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.5]],
        triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
    }
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("microfrep-mesh-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn f32_at(b: &[u8], at: usize) -> f32 {
    f32::from_le_bytes(b[at..at + 4].try_into().unwrap())
}

#[test]
fn stl_round_trip() {
    let m = tetra();
    let p = dir("stl").join("t.stl");
    write_mesh(&p, &m, None).unwrap();
    let b = std::fs::read(&p).unwrap();
    assert_eq!(b.len(), 84 + 50 * 4);
    assert_eq!(u32::from_le_bytes(b[80..84].try_into().unwrap()), 4);
    // Last facet: normal of (1,0,0) (0,1,0) (0,0,1.5) points along +x+y+z.
    let rec = 84 + 50 * 3;
    assert!((0..3).all(|k| f32_at(&b, rec + 4 * k) > 0.0));
    let corners: Vec<f32> = (0..9).map(|k| f32_at(&b, rec + 12 + 4 * k)).collect();
    assert_eq!(corners, [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.5]);
    assert_eq!(std::fs::read_dir(p.parent().unwrap()).unwrap().count(), 1);
}

#[test]
fn streamed_stl_patches_the_count() {
    let mut w = StlWriter::new(Cursor::new(Vec::new())).unwrap();
    for _ in 0..7 {
        w.push([[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
            .unwrap();
    }
    let b = w.finish().unwrap().into_inner();
    assert_eq!((b.len(), b[80]), (84 + 7 * 50, 7));
}

#[test]
fn obj_round_trip() {
    let m = tetra();
    let p = dir("obj").join("t.obj");
    let normals = vec![[0.0, 0.0, 1.0]; 4];
    write_mesh(&p, &m, Some(&normals)).unwrap();
    let s = std::fs::read_to_string(&p).unwrap();
    let verts: Vec<Vec<f32>> = s
        .lines()
        .filter(|l| l.starts_with("v "))
        .map(|l| l[2..].split(' ').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(verts[3], vec![0.0, 0.0, 1.5]);
    assert_eq!(s.lines().filter(|l| l.starts_with("vn ")).count(), 4);
    assert!(s.lines().any(|l| l == "f 2//2 3//3 4//4"));
}

#[test]
fn ply_round_trip() {
    let m = tetra();
    let p = dir("ply").join("t.ply");
    write_mesh(&p, &m, None).unwrap();
    let b = std::fs::read(&p).unwrap();
    let end = b.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    let header = std::str::from_utf8(&b[..end]).unwrap();
    assert!(header.contains("element vertex 4\n") && header.contains("element face 4\n"));
    assert_eq!(b.len() - end, 4 * 12 + 4 * 13);
    assert_eq!(f32_at(&b, end + 3 * 12 + 8), 1.5);
    let face3 = end + 48 + 3 * 13;
    assert_eq!(b[face3], 3);
    let idx: Vec<u32> = (0..3)
        .map(|k| u32::from_le_bytes(b[face3 + 1 + 4 * k..face3 + 5 + 4 * k].try_into().unwrap()))
        .collect();
    assert_eq!(idx, [1, 2, 3]);
}

#[test]
fn threemf_package_holds_one_millimetre_object() {
    let m = tetra();
    let p = dir("3mf").join("t.3mf");
    write_mesh(&p, &m, None).unwrap();
    let read = microfrep_3mf::read_meshes(&p).unwrap();
    assert_eq!(read.len(), 1);
    let r = &read[0];
    assert_eq!(r.triangles, m.triangles);
    let want: Vec<[f64; 3]> = m.vertices.iter().map(|v| v.map(|c| c as f64)).collect();
    assert_eq!(r.vertices, want);
}

#[test]
fn failures_leave_nothing_and_formats_come_from_extensions() {
    let d = dir("fail");
    let p = d.join("missing-dir").join("t.stl");
    let e = write_mesh(&p, &tetra(), None).unwrap_err();
    assert!(e.to_string().contains("missing-dir"), "{e}");
    assert_eq!(std::fs::read_dir(&d).unwrap().count(), 0);
    assert_eq!(format_of(&d.join("a.3MF")).unwrap().name(), "3MF");
    let e = format_of(&d.join("a.step")).err().unwrap().to_string();
    assert!(
        e.contains("unknown mesh format (use .stl, .obj, .ply, .3mf)"),
        "{e}"
    );
}
