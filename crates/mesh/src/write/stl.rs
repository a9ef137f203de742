//! Binary STL: 50 bytes per triangle with a facet normal from its corners.
//! Written whole (chunks encoded in parallel) or streamed ([`StlWriter`]:
//! triangles as they come, the count patched at the end).

use super::{write_encoded, MeshFormat};
use crate::Mesh;
use microfrep_io::{AtomicFile, OutputFormat};
use std::io::{Seek, SeekFrom, Write};

pub(super) struct Stl;

impl OutputFormat for Stl {
    fn name(&self) -> &'static str {
        "binary STL"
    }
    fn extensions(&self) -> &'static [&'static str] {
        &["stl"]
    }
}

impl MeshFormat for Stl {
    fn streams(&self) -> bool {
        true
    }
    fn write(
        &self,
        mesh: &Mesh,
        _: Option<&[[f32; 3]]>,
        _: Option<&[[u8; 3]]>,
        out: &mut AtomicFile,
    ) -> std::io::Result<()> {
        let n = count(mesh.triangles.len() as u64)?;
        out.write_all(&header())?;
        out.write_all(&n.to_le_bytes())?;
        write_encoded(out, &mesh.triangles, |ts, b| {
            b.reserve(50 * ts.len());
            for t in ts {
                b.extend_from_slice(&record(t.map(|i| mesh.vertices[i as usize])));
            }
        })
    }
}

fn header() -> [u8; 80] {
    let mut header = [0u8; 80];
    let tag = b"binary STL written by microfrep";
    header[..tag.len()].copy_from_slice(tag);
    header
}

fn count(n: u64) -> std::io::Result<u32> {
    u32::try_from(n).map_err(|_| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "binary STL holds at most 2^32-1 triangles",
        )
    })
}

/// One triangle record: facet normal, corners, attribute count 0.
fn record(t: [[f32; 3]; 3]) -> [u8; 50] {
    let [p, q, r] = t.map(|v| v.map(|c| c as f64));
    let e1 = [q[0] - p[0], q[1] - p[1], q[2] - p[2]];
    let e2 = [r[0] - p[0], r[1] - p[1], r[2] - p[2]];
    let n = [
        e1[1] * e2[2] - e1[2] * e2[1],
        e1[2] * e2[0] - e1[0] * e2[2],
        e1[0] * e2[1] - e1[1] * e2[0],
    ];
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    let n = if len > 0.0 { n.map(|c| c / len) } else { n };
    let mut rec = [0u8; 50];
    let vals = n
        .iter()
        .map(|&c| c as f32)
        .chain(t.iter().flatten().copied());
    for (k, v) in vals.enumerate() {
        rec[4 * k..4 * k + 4].copy_from_slice(&v.to_le_bytes());
    }
    rec
}

/// Binary STL written triangle by triangle; [`StlWriter::finish`] patches
/// the count into the header.
pub struct StlWriter<W: Write + Seek> {
    w: W,
    count: u64,
}

impl<W: Write + Seek> StlWriter<W> {
    /// Writes the header with a placeholder count.
    pub fn new(mut w: W) -> std::io::Result<Self> {
        w.write_all(&header())?;
        w.write_all(&0u32.to_le_bytes())?;
        Ok(StlWriter { w, count: 0 })
    }

    /// Appends one triangle (counter-clockwise from outside); its facet
    /// normal is computed from the corners.
    pub fn push(&mut self, t: [[f32; 3]; 3]) -> std::io::Result<()> {
        self.w.write_all(&record(t))?;
        self.count += 1;
        Ok(())
    }

    /// Patches the triangle count and returns the inner writer.
    pub fn finish(mut self) -> std::io::Result<W> {
        let n = count(self.count)?;
        self.w.seek(SeekFrom::Start(80))?;
        self.w.write_all(&n.to_le_bytes())?;
        self.w.seek(SeekFrom::End(0))?;
        self.w.flush()?;
        Ok(self.w)
    }
}
