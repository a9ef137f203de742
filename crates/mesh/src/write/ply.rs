//! Binary little-endian PLY with optional vertex normals.

use crate::Mesh;
use std::io::Write;

/// The header for `nv` vertices and `nf` triangles.
pub fn header(nv: u64, nf: u64, normals: bool) -> String {
    let mut s = format!(
        "ply\nformat binary_little_endian 1.0\ncomment microfrep mesh\n\
         element vertex {nv}\nproperty float x\nproperty float y\nproperty float z\n"
    );
    if normals {
        s.push_str("property float nx\nproperty float ny\nproperty float nz\n");
    }
    s.push_str(&format!(
        "element face {nf}\nproperty list uchar uint vertex_indices\nend_header\n"
    ));
    s
}

/// One vertex record: position, then the normal if any.
pub fn vertex(w: &mut impl Write, p: [f32; 3], n: Option<[f32; 3]>) -> std::io::Result<()> {
    let mut rec = [0u8; 24];
    for (k, c) in p.iter().chain(n.iter().flatten()).enumerate() {
        rec[4 * k..4 * k + 4].copy_from_slice(&c.to_le_bytes());
    }
    w.write_all(&rec[..if n.is_some() { 24 } else { 12 }])
}

/// One face record: a count of 3 and the indices.
pub fn face(w: &mut impl Write, t: [u32; 3]) -> std::io::Result<()> {
    let mut rec = [3u8; 13];
    for (k, i) in t.iter().enumerate() {
        rec[1 + 4 * k..5 + 4 * k].copy_from_slice(&i.to_le_bytes());
    }
    w.write_all(&rec)
}

pub fn write(w: &mut impl Write, mesh: &Mesh, normals: Option<&[[f32; 3]]>) -> std::io::Result<()> {
    let (nv, nf) = (mesh.vertices.len() as u64, mesh.triangles.len() as u64);
    w.write_all(header(nv, nf, normals.is_some()).as_bytes())?;
    for (i, p) in mesh.vertices.iter().enumerate() {
        vertex(w, *p, normals.map(|ns| ns[i]))?;
    }
    for t in &mesh.triangles {
        face(w, *t)?;
    }
    Ok(())
}
