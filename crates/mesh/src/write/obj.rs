//! Wavefront OBJ: `v`, optional `vn`, and 1-based faces. Vertex colours
//! use the common extension `v x y z r g b` with components in 0..1 (read
//! by MeshLab, Blender and most OBJ readers); 255 times each component
//! rounds back to the 8-bit colour.

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
    fn stores_colours(&self) -> bool {
        true
    }
    fn write(
        &self,
        mesh: &Mesh,
        normals: Option<&[[f32; 3]]>,
        colours: Option<&[[u8; 3]]>,
        out: &mut AtomicFile,
    ) -> std::io::Result<()> {
        use std::io::Write;
        writeln!(out, "# microfrep mesh")?;
        match colours {
            None => write_encoded(out, &mesh.vertices, |ps, b| {
                for p in ps {
                    let _ = writeln!(b, "v {} {} {}", p[0], p[1], p[2]);
                }
            })?,
            Some(cs) => {
                let idx: Vec<usize> = (0..mesh.vertices.len()).collect();
                write_encoded(out, &idx, |is, b| {
                    for &i in is {
                        let (p, c) = (mesh.vertices[i], cs[i].map(|v| v as f32 / 255.0));
                        let _ =
                            writeln!(b, "v {} {} {} {} {} {}", p[0], p[1], p[2], c[0], c[1], c[2]);
                    }
                })?
            }
        }
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
