//! Binary STL: 50 bytes per triangle with a facet normal from its corners.
//! Written whole (chunks encoded in parallel) or streamed ([`StlWriter`]:
//! triangles as they come, the count patched at the end).

use super::{MeshFormat, CHUNK};
use crate::Mesh;
use microfrep_io::{AtomicFile, OutputFormat};
use rayon::prelude::*;
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
    fn measures_volume(&self) -> bool {
        true
    }
    fn write(
        &self,
        mesh: &Mesh,
        normals: Option<&[[f32; 3]]>,
        colours: Option<&[[u8; 3]]>,
        out: &mut AtomicFile,
    ) -> std::io::Result<()> {
        self.write_measured(mesh, normals, colours, out).map(|_| ())
    }
    fn write_measured(
        &self,
        mesh: &Mesh,
        _: Option<&[[f32; 3]]>,
        _: Option<&[[u8; 3]]>,
        out: &mut AtomicFile,
    ) -> std::io::Result<Option<(f64, f64)>> {
        let n = count(mesh.triangles.len() as u64)?;
        out.write_all(&header())?;
        out.write_all(&n.to_le_bytes())?;
        // Records straight into reused buffers of two encoding chunks
        // (larger than the file's write buffer, so they bypass it); the
        // volume and area summed per chunk and then over the chunks in
        // order, as `check::volume_area` does (same chunks, same
        // operations).
        let block = 2 * CHUNK;
        let per_group = 2 * rayon::current_num_threads().max(1);
        let mut bufs: Vec<Vec<u8>> = Vec::new();
        let mut sums = Vec::with_capacity(mesh.triangles.len().div_ceil(CHUNK));
        for g in mesh.triangles.chunks(block * per_group) {
            let n = g.len().div_ceil(block);
            if bufs.len() < n {
                bufs.resize_with(n, Vec::new);
            }
            let s: Vec<Vec<(f64, f64)>> = g
                .par_chunks(block)
                .zip(bufs[..n].par_iter_mut())
                .map(|(ts, b)| {
                    // Only a shorter last block changes the length.
                    b.resize(50 * ts.len(), 0);
                    ts.chunks(CHUNK)
                        .zip(b.chunks_mut(50 * CHUNK))
                        .map(|(c, bc)| {
                            let (mut v, mut a) = (0.0, 0.0);
                            for (t, rec) in c.iter().zip(bc.chunks_exact_mut(50)) {
                                let (dv, da) = encode(t.map(|i| mesh.vertices[i as usize]), rec);
                                v += dv;
                                a += da;
                            }
                            (v, a)
                        })
                        .collect()
                })
                .collect();
            sums.extend(s.into_iter().flatten());
            for b in &bufs[..n] {
                out.write_all(b)?;
            }
        }
        Ok(Some(
            sums.into_iter()
                .fold((0.0, 0.0), |(v, a), (dv, da)| (v + dv, a + da)),
        ))
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
    let mut rec = [0u8; 50];
    encode(t, &mut rec);
    rec
}

/// Writes the record of `t` into `rec` (50 bytes) and returns the
/// triangle's signed volume term and area, computed as
/// `check::volume_area` computes them (the facet normal is the same f64
/// cross product).
#[inline]
fn encode(t: [[f32; 3]; 3], rec: &mut [u8]) -> (f64, f64) {
    let [p, q, r] = t.map(|v| v.map(|c| c as f64));
    let e1 = [q[0] - p[0], q[1] - p[1], q[2] - p[2]];
    let e2 = [r[0] - p[0], r[1] - p[1], r[2] - p[2]];
    let n = [
        e1[1] * e2[2] - e1[2] * e2[1],
        e1[2] * e2[0] - e1[0] * e2[2],
        e1[0] * e2[1] - e1[1] * e2[0],
    ];
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    let volume = (p[0] * (q[1] * r[2] - q[2] * r[1]) - p[1] * (q[0] * r[2] - q[2] * r[0])
        + p[2] * (q[0] * r[1] - q[1] * r[0]))
        / 6.0;
    let n = if len > 0.0 { n.map(|c| c / len) } else { n };
    let mut vals = [0.0f32; 12];
    vals[..3].copy_from_slice(&n.map(|c| c as f32));
    for (k, v) in t.iter().enumerate() {
        vals[3 + 3 * k..6 + 3 * k].copy_from_slice(v);
    }
    for (k, v) in vals.iter().enumerate() {
        rec[4 * k..4 * k + 4].copy_from_slice(&v.to_le_bytes());
    }
    rec[48..50].fill(0);
    (volume, 0.5 * len)
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn measured_volume_and_area_equal_the_checks_bit_for_bit() {
        // More triangles than one encoding chunk, so the per-chunk sums
        // and their order matter.
        let mut x = 12345u64;
        let mut next = || {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((x >> 40) as f32 / (1u64 << 24) as f32) * 10.0 - 5.0
        };
        let vertices: Vec<[f32; 3]> = (0..1000).map(|_| [next(), next(), next()]).collect();
        let triangles: Vec<[u32; 3]> = (0..150_000u32)
            .map(|i| [i % 1000, (i * 7 + 1) % 1000, (i * 13 + 5) % 1000])
            .collect();
        let mesh = Mesh {
            vertices,
            triangles,
        };
        let dir =
            std::env::temp_dir().join(format!("microfrep-stl-measured-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("m.stl");
        let mut f = AtomicFile::create(&path).unwrap();
        let got = Stl.write_measured(&mesh, None, None, &mut f).unwrap();
        f.commit().unwrap();
        let want = crate::check::volume_area(&mesh);
        let got = got.expect("STL measures");
        assert_eq!(got.0.to_bits(), want.0.to_bits());
        assert_eq!(got.1.to_bits(), want.1.to_bits());
        // The records are the ones the streaming writer makes.
        let bytes = std::fs::read(&path).unwrap();
        assert_eq!(bytes.len(), 84 + 50 * mesh.triangles.len());
        for i in [0usize, 65_535, 65_536, 149_999] {
            let t = mesh.triangles[i].map(|v| mesh.vertices[v as usize]);
            assert_eq!(&bytes[84 + 50 * i..134 + 50 * i], &record(t)[..]);
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
