//! Wavefront OBJ: `v`, optional `vn`, and 1-based faces.

use crate::Mesh;
use std::io::Write;

pub fn write(w: &mut impl Write, mesh: &Mesh, normals: Option<&[[f32; 3]]>) -> std::io::Result<()> {
    writeln!(w, "# microfrep mesh")?;
    for p in &mesh.vertices {
        writeln!(w, "v {} {} {}", p[0], p[1], p[2])?;
    }
    if let Some(ns) = normals {
        for n in ns {
            writeln!(w, "vn {} {} {}", n[0], n[1], n[2])?;
        }
    }
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| i as u64 + 1);
        if normals.is_some() {
            writeln!(w, "f {a}//{a} {b}//{b} {c}//{c}")?;
        } else {
            writeln!(w, "f {a} {b} {c}")?;
        }
    }
    Ok(())
}
