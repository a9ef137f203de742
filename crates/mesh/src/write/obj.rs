//! Wavefront OBJ: `v`, optional `vn`, and 1-based faces.

use super::{write_encoded, MeshFormat};
use crate::Mesh;
use microfrep_io::{AtomicFile, OutputFormat};

pub(super) struct Obj;

impl OutputFormat for Obj {
    fn name(&self) -> &'static str {
        "Wavefront OBJ"
    }
    fn extensions(&self) -> &'static [&'static str] {
        &["obj"]
    }
}

impl MeshFormat for Obj {
    fn wants_normals(&self) -> bool {
        true
    }
    fn write(
        &self,
        mesh: &Mesh,
        normals: Option<&[[f32; 3]]>,
        out: &mut AtomicFile,
    ) -> std::io::Result<()> {
        use std::io::Write;
        writeln!(out, "# microfrep mesh")?;
        write_encoded(out, &mesh.vertices, |ps, b| {
            for p in ps {
                let _ = writeln!(b, "v {} {} {}", p[0], p[1], p[2]);
            }
        })?;
        if let Some(ns) = normals {
            write_encoded(out, ns, |ns, b| {
                for n in ns {
                    let _ = writeln!(b, "vn {} {} {}", n[0], n[1], n[2]);
                }
            })?;
        }
        let with_n = normals.is_some();
        write_encoded(out, &mesh.triangles, |ts, b| {
            for t in ts {
                let [a, c, d] = t.map(|i| i as u64 + 1);
                let _ = if with_n {
                    writeln!(b, "f {a}//{a} {c}//{c} {d}//{d}")
                } else {
                    writeln!(b, "f {a} {c} {d}")
                };
            }
        })
    }
}
