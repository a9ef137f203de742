//! Binary little-endian PLY with optional vertex normals.

use crate::Mesh;
use std::io::Write;

pub fn write(w: &mut impl Write, mesh: &Mesh, normals: Option<&[[f32; 3]]>) -> std::io::Result<()> {
    write!(
        w,
        "ply\nformat binary_little_endian 1.0\ncomment microfrep mesh\n\
         element vertex {}\nproperty float x\nproperty float y\nproperty float z\n",
        mesh.vertices.len()
    )?;
    if normals.is_some() {
        write!(
            w,
            "property float nx\nproperty float ny\nproperty float nz\n"
        )?;
    }
    write!(
        w,
        "element face {}\nproperty list uchar uint vertex_indices\nend_header\n",
        mesh.triangles.len()
    )?;
    for (i, p) in mesh.vertices.iter().enumerate() {
        for c in p {
            w.write_all(&c.to_le_bytes())?;
        }
        if let Some(ns) = normals {
            for c in ns[i] {
                w.write_all(&c.to_le_bytes())?;
            }
        }
    }
    for t in &mesh.triangles {
        w.write_all(&[3u8])?;
        for i in t {
            w.write_all(&i.to_le_bytes())?;
        }
    }
    Ok(())
}
