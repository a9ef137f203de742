//! Binary little-endian PLY with optional vertex normals and vertex
//! colours (`uchar red, green, blue`, after the normals).

use super::{write_encoded, write_encoded_with, MeshFormat};
use crate::Mesh;
use microfrep_io::{AtomicFile, OutputFormat};
use std::io::Write;

pub(super) struct Ply;

impl OutputFormat for Ply {
    fn name(&self) -> &'static str {
        "binary PLY"
    }
    fn extensions(&self) -> &'static [&'static str] {
        &["ply"]
    }
}

impl MeshFormat for Ply {
    fn wants_normals(&self) -> bool {
        true
    }
    fn streams(&self) -> bool {
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
        write_ply(mesh, normals, colours, out, false).map(|_| ())
    }
    fn measures_volume(&self) -> bool {
        true
    }
    /// The volume and area are summed while the faces are encoded, chunk
    /// by chunk as `check::volume_area` sums them (the same values).
    fn write_measured(
        &self,
        mesh: &Mesh,
        normals: Option<&[[f32; 3]]>,
        colours: Option<&[[u8; 3]]>,
        out: &mut AtomicFile,
    ) -> std::io::Result<Option<(f64, f64)>> {
        write_ply(mesh, normals, colours, out, true)
    }
}

/// Writes the mesh; with `measure`, also its volume and area, summed while
/// the faces are encoded.
fn write_ply(
    mesh: &Mesh,
    normals: Option<&[[f32; 3]]>,
    colours: Option<&[[u8; 3]]>,
    out: &mut AtomicFile,
    measure: bool,
) -> std::io::Result<Option<(f64, f64)>> {
    let (nv, nf) = (mesh.vertices.len() as u64, mesh.triangles.len() as u64);
    let head = header(nv, nf, normals.is_some(), colours.is_some());
    out.write_all(head.as_bytes())?;
    let base = mesh.vertices.as_ptr() as usize;
    write_encoded(out, &mesh.vertices, |vs, b| {
        // The index of the chunk's first vertex (chunks are subslices).
        let first = (vs.as_ptr() as usize - base) / std::mem::size_of::<[f32; 3]>();
        for (i, &p) in (first..).zip(vs) {
            vertex(b, p, normals.map(|ns| ns[i]));
            if let Some(cs) = colours {
                b.extend_from_slice(&cs[i]);
            }
        }
    })?;
    let sums = write_encoded_with(out, &mesh.triangles, |ts, b| {
        for t in ts {
            face(b, *t);
        }
        measure.then(|| crate::check::chunk_volume_area(&mesh.vertices, ts))
    })?;
    Ok(measure.then(|| {
        let sums: Vec<(f64, f64)> = sums.into_iter().flatten().collect();
        crate::check::total_volume_area(&sums)
    }))
}

/// The header for `nv` vertices (with normals, colours when asked) and
/// `nf` triangles.
pub fn header(nv: u64, nf: u64, normals: bool, colours: bool) -> String {
    let mut s = format!(
        "ply\nformat binary_little_endian 1.0\ncomment microfrep mesh\n\
         element vertex {nv}\nproperty float x\nproperty float y\nproperty float z\n"
    );
    if normals {
        s.push_str("property float nx\nproperty float ny\nproperty float nz\n");
    }
    if colours {
        s.push_str("property uchar red\nproperty uchar green\nproperty uchar blue\n");
    }
    s.push_str(&format!(
        "element face {nf}\nproperty list uchar uint vertex_indices\nend_header\n"
    ));
    s
}

/// One vertex record: position, then the normal if any.
pub fn vertex(b: &mut Vec<u8>, p: [f32; 3], n: Option<[f32; 3]>) {
    for c in p.iter().chain(n.iter().flatten()) {
        b.extend_from_slice(&c.to_le_bytes());
    }
}

/// One face record: a count of 3 and the indices.
pub fn face(b: &mut Vec<u8>, t: [u32; 3]) {
    b.push(3);
    for i in t {
        b.extend_from_slice(&i.to_le_bytes());
    }
}
