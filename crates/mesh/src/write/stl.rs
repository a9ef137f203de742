//! Binary STL: 50 bytes per triangle with a facet normal from its corners.
//! Written whole (chunks encoded in parallel, a block of triangles at a
//! time in vector instructions), streamed ([`StlWriter`]: triangles as
//! they come, the count patched at the end), or, for a job, written,
//! measured and edge-counted while the mesh is made (`StlJob`).

use super::{MeshFormat, CHUNK};
use crate::edges::EdgeCensus;
use crate::sink::{Counted, MeshSink, VertexWindow};
use crate::{Mesh, MeshError};
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
        let mut enc = Encoder::default();
        let v = &mesh.vertices;
        enc.encode(v, &mesh.triangles, out)?;
        Ok(Some(enc.total()))
    }
}

/// Encodes triangles into STL records in parallel, straight into the
/// file's own buffers ([`AtomicFile::lend`]: with direct writes the disk
/// reads them from there, no copy), with the volume and area summed per
/// chunk of [`CHUNK`] triangles and then over the chunks in order, as
/// `check::volume_area` does (same chunks, same operations, so the same
/// bits). Two chunks a thread at a time, so memory stays bounded.
#[derive(Default)]
struct Encoder {
    /// Volume and area per chunk encoded so far.
    sums: Vec<(f64, f64)>,
}

impl Encoder {
    /// Encodes and writes `tris` (corners in `v`), which
    /// continue the triangles encoded before; every call but the last must
    /// pass whole chunks.
    fn encode(
        &mut self,
        v: &[[f32; 3]],
        tris: &[[u32; 3]],
        out: &mut AtomicFile,
    ) -> std::io::Result<()> {
        let per_group = 2 * rayon::current_num_threads().max(1);
        for g in tris.chunks(CHUNK * per_group) {
            let mut lent = out.lend(50 * g.len())?;
            let s: Vec<(f64, f64)> = g
                .par_chunks(CHUNK)
                .zip(lent.bytes().par_chunks_mut(50 * CHUNK))
                .map(|(c, b)| encode_all(v, c, b))
                .collect();
            self.sums.extend(s);
            out.put(lent)?;
        }
        Ok(())
    }

    /// Volume and area of everything encoded.
    fn total(&self) -> (f64, f64) {
        self.sums
            .iter()
            .fold((0.0, 0.0), |(v, a), (dv, da)| (v + dv, a + da))
    }
}

/// A [`MeshSink`] that writes the mesh to `out` as binary STL and counts
/// its edges while it arrives, holding its vertices but not its triangles:
/// those are kept until a few chunks have come, then encoded in parallel
/// (so the file is on its way to the disk while the rest is meshed), and
/// the edges are counted alongside ([`crate::edges::EdgeCensus`]). The
/// bytes are those of [`super::write_mesh`]; [`StlJob::finish`] returns
/// the counts, the volume and area measured while encoding (bit for bit
/// those of `check::volume_area`), the bounding box and the edge census.
pub(crate) struct StlJob<'a> {
    out: &'a mut AtomicFile,
    enc: Encoder,
    vertices: Vec<[f32; 3]>,
    /// Triangles received and not yet encoded; the first of them is at a
    /// multiple of [`CHUNK`] until `finish`.
    waiting: Vec<[u32; 3]>,
    /// How many of `waiting` the census has seen.
    counted: usize,
    census: EdgeCensus,
    /// Connected shells, as the triangles come.
    shells: crate::edges::ShellCensus,
    triangles: u64,
    /// Bounding box of the vertices, in f32 (exact: the same as in f64).
    bbox: [[f32; 3]; 2],
}

impl<'a> StlJob<'a> {
    /// Writes the header (the count is patched by `finish`); room is made
    /// for `expected_vertices` (the job's estimate), so the vertices are
    /// not copied again as they grow.
    pub(crate) fn new(out: &'a mut AtomicFile, expected_vertices: usize) -> std::io::Result<Self> {
        out.write_all(&header())?;
        out.write_all(&0u32.to_le_bytes())?;
        Ok(StlJob {
            out,
            enc: Encoder::default(),
            vertices: Vec::with_capacity(expected_vertices),
            waiting: Vec::new(),
            counted: 0,
            census: EdgeCensus::new(),
            shells: crate::edges::ShellCensus::new(),
            triangles: 0,
            bbox: [[f32::INFINITY; 3], [f32::NEG_INFINITY; 3]],
        })
    }

    /// Triangles encoded at a time: two chunks a thread.
    fn step() -> usize {
        2 * CHUNK * rayon::current_num_threads().max(1)
    }

    /// Gives the census the triangles it has not seen and encodes the
    /// waiting ones, side by side: all of them (`all`), or the whole
    /// chunks among them.
    fn catch_up(&mut self, all: bool) -> std::io::Result<()> {
        let n = if all {
            self.waiting.len()
        } else {
            self.waiting.len() / CHUNK * CHUNK
        };
        let Self {
            out,
            enc,
            vertices,
            waiting,
            counted,
            census,
            ..
        } = self;
        // Every vertex of a triangle arrives before it (the sink's
        // contract); a bad index would panic here as in `write_mesh`.
        let v = &vertices[..];
        let ((), written) = rayon::join(
            || census.triangles(&waiting[*counted..]),
            || enc.encode(v, &waiting[..n], out),
        );
        written?;
        waiting.drain(..n);
        *counted = waiting.len();
        Ok(())
    }

    /// Encodes the rest and patches the triangle count into the header.
    pub(crate) fn finish(mut self) -> std::io::Result<StlJobSummary> {
        let n = count(self.triangles)?;
        self.catch_up(true)?;
        self.out.seek(SeekFrom::Start(80))?;
        self.out.write_all(&n.to_le_bytes())?;
        self.out.seek(SeekFrom::End(0))?;
        let [lo, hi] = self.bbox;
        Ok(StlJobSummary {
            vertices: self.vertices.len() as u64,
            triangles: self.triangles,
            measured: self.enc.total(),
            bbox: [lo.map(|c| c as f64), hi.map(|c| c as f64)],
            edges: self.census.finish(),
            shells: self.shells.finish(),
        })
    }
}

/// What [`StlJob::finish`] returns.
pub(crate) struct StlJobSummary {
    pub(crate) vertices: u64,
    pub(crate) triangles: u64,
    /// Volume and area.
    pub(crate) measured: (f64, f64),
    pub(crate) bbox: [[f64; 3]; 2],
    /// Edges and bad edges; `None` when the mesh did not come in the order
    /// the census relies on (count them with [`crate::edges::edges`]).
    pub(crate) edges: Option<(usize, usize)>,
    /// Connected shells (`None` if a triangle named an unknown vertex).
    pub(crate) shells: Option<usize>,
}

impl MeshSink for StlJob<'_> {
    fn vertices(&mut self, v: &[[f32; 3]]) -> Result<(), MeshError> {
        // The triangles so far go to the census before it closes vertices.
        if self.counted < self.waiting.len() {
            self.catch_up(false).map_err(MeshError::Stream)?;
        }
        self.census.vertices(v.len());
        self.shells.vertices(v.len());
        self.vertices.extend_from_slice(v);
        let [lo, hi] = &mut self.bbox;
        let (l, h) = bounds_of(v);
        for a in 0..3 {
            lo[a] = lo[a].min(l[a]);
            hi[a] = hi[a].max(h[a]);
        }
        Ok(())
    }

    fn triangles(&mut self, t: &[[u32; 3]], _: &VertexWindow) -> Result<(), MeshError> {
        self.waiting.extend_from_slice(t);
        self.shells.triangles(t);
        self.triangles += t.len() as u64;
        if self.waiting.len() >= Self::step() {
            self.catch_up(false).map_err(MeshError::Stream)?;
        }
        Ok(())
    }

    fn counts_edges(&self) -> bool {
        true
    }

    fn take_counted(&mut self, part: Counted, window: &VertexWindow) -> Result<(), MeshError> {
        // In order: any triangles the census has not seen, then this
        // brick's edges.
        if self.counted < self.waiting.len() {
            self.census.triangles(&self.waiting[self.counted..]);
        }
        self.census.brick(&part.edges);
        self.counted = self.waiting.len() + part.tris.len();
        self.triangles(&part.tris, window)
    }
}

/// The least and greatest coordinates of `v` on each axis (infinite ends
/// for no points; the points are finite). Eight points at a time as one
/// flat row of 24 coordinates, so the comparisons vectorise.
fn bounds_of(v: &[[f32; 3]]) -> ([f32; 3], [f32; 3]) {
    let mut lo = [f32::INFINITY; 24];
    let mut hi = [f32::NEG_INFINITY; 24];
    let blocks = v.chunks_exact(8);
    let rest = blocks.remainder();
    for b in blocks {
        let flat: &[f32; 24] = b.as_flattened().try_into().expect("8 points");
        for j in 0..24 {
            lo[j] = if flat[j] < lo[j] { flat[j] } else { lo[j] };
            hi[j] = if flat[j] > hi[j] { flat[j] } else { hi[j] };
        }
    }
    let (mut l, mut h) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    for j in 0..24 {
        l[j % 3] = l[j % 3].min(lo[j]);
        h[j % 3] = h[j % 3].max(hi[j]);
    }
    for p in rest {
        for a in 0..3 {
            l[a] = l[a].min(p[a]);
            h[a] = h[a].max(p[a]);
        }
    }
    (l, h)
}

/// The corners of triangle `t`. (Written out: `[T; 3]::map` was not
/// inlined here and cost more than the encoding.)
#[inline(always)]
fn corners_of(v: &[[f32; 3]], t: &[u32; 3]) -> [[f32; 3]; 3] {
    [v[t[0] as usize], v[t[1] as usize], v[t[2] as usize]]
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
    put_record(rec, n.map(|c| c as f32), t);
    (volume, 0.5 * len)
}

/// Writes one record: normal, corners, attribute count 0.
#[inline(always)]
fn put_record(rec: &mut [u8], n: [f32; 3], t: [[f32; 3]; 3]) {
    let mut vals = [0.0f32; 12];
    vals[..3].copy_from_slice(&n);
    for (k, v) in t.iter().enumerate() {
        vals[3 + 3 * k..6 + 3 * k].copy_from_slice(v);
    }
    let rec: &mut [u8; 50] = rec.try_into().expect("records are 50 bytes");
    for (k, v) in vals.iter().enumerate() {
        rec[4 * k..4 * k + 4].copy_from_slice(&v.to_le_bytes());
    }
    rec[48..50].fill(0);
}

/// Triangles per block of [`encode_all`]: their arithmetic runs lane by
/// lane (vectorised), their sums in order.
const LANES: usize = 16;

/// Writes the records of `tris` (corners in `v`) into `out` (50 bytes
/// each) and returns their volume and area summed in order: bit for bit
/// what [`encode`] triangle by triangle and `check::volume_area` give (the
/// same operations on each triangle, the same order of the sums), but a
/// block of triangles at a time, each step for all of them, so the
/// compiler can use vector instructions.
///
/// The corners go straight from the vertices into columns of f64, one
/// coordinate at a time, and the records are written from those columns
/// (f32 to f64 and back is exact). Copying each triangle's corners whole
/// to the stack first made the compiler store them in 8- and 4-byte
/// pieces and read them back 16 bytes at a time, a stalled load per
/// triangle that took 40 % of the encoding.
#[inline(always)]
fn encode_all(v: &[[f32; 3]], tris: &[[u32; 3]], out: &mut [u8]) -> (f64, f64) {
    let (mut vol, mut area) = (0.0, 0.0);
    let blocks = tris.chunks_exact(LANES);
    let rest = blocks.remainder();
    let mut recs = out.chunks_exact_mut(50 * LANES);
    // Corner coordinates by lane: c[corner * 3 + axis][lane].
    let mut c = [[0.0f64; LANES]; 9];
    for (b, rec) in blocks.zip(&mut recs) {
        for (i, tri) in b.iter().enumerate() {
            for (k, &j) in tri.iter().enumerate() {
                // Every vertex of a triangle exists (the sinks' contract);
                // a bad index panics here as in `write_mesh`.
                let p = &v[j as usize];
                c[3 * k][i] = p[0] as f64;
                c[3 * k + 1][i] = p[1] as f64;
                c[3 * k + 2][i] = p[2] as f64;
            }
        }
        let [px, py, pz, qx, qy, qz, rx, ry, rz] = &c;
        let mut nx = [0.0f64; LANES];
        let mut ny = [0.0f64; LANES];
        let mut nz = [0.0f64; LANES];
        let mut len = [0.0f64; LANES];
        let mut dv = [0.0f64; LANES];
        for i in 0..LANES {
            let e1 = [qx[i] - px[i], qy[i] - py[i], qz[i] - pz[i]];
            let e2 = [rx[i] - px[i], ry[i] - py[i], rz[i] - pz[i]];
            nx[i] = e1[1] * e2[2] - e1[2] * e2[1];
            ny[i] = e1[2] * e2[0] - e1[0] * e2[2];
            nz[i] = e1[0] * e2[1] - e1[1] * e2[0];
            len[i] = (nx[i] * nx[i] + ny[i] * ny[i] + nz[i] * nz[i]).sqrt();
            dv[i] = (px[i] * (qy[i] * rz[i] - qz[i] * ry[i])
                - py[i] * (qx[i] * rz[i] - qz[i] * rx[i])
                + pz[i] * (qx[i] * ry[i] - qy[i] * rx[i]))
                / 6.0;
        }
        // The record's twelve values by lane: normal, then the corners.
        let mut vals = [[0.0f32; LANES]; 12];
        for i in 0..LANES {
            // A zero normal stays zero (as in `encode`).
            let l = if len[i] > 0.0 { len[i] } else { 1.0 };
            vals[0][i] = (nx[i] / l) as f32;
            vals[1][i] = (ny[i] / l) as f32;
            vals[2][i] = (nz[i] / l) as f32;
        }
        for (k, col) in c.iter().enumerate() {
            for i in 0..LANES {
                vals[3 + k][i] = col[i] as f32;
            }
        }
        for i in 0..LANES {
            vol += dv[i];
            area += 0.5 * len[i];
        }
        for (i, r) in rec.chunks_exact_mut(50).enumerate() {
            let r: &mut [u8; 50] = r.try_into().expect("records are 50 bytes");
            for (k, col) in vals.iter().enumerate() {
                r[4 * k..4 * k + 4].copy_from_slice(&col[i].to_le_bytes());
            }
            r[48..50].fill(0);
        }
    }
    for (t, rec) in rest.iter().zip(recs.into_remainder().chunks_exact_mut(50)) {
        let (dv, da) = encode(corners_of(v, t), rec);
        vol += dv;
        area += da;
    }
    (vol, area)
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
    fn bounds_of_any_count_of_points_are_the_plain_min_and_max() {
        for n in [0usize, 1, 7, 8, 9, 23, 24, 100] {
            let v: Vec<[f32; 3]> = (0..n)
                .map(|i| {
                    let x = i as f32;
                    [(x * 0.37).sin(), -(x * 1.3).cos() * 5.0, x - 40.0]
                })
                .collect();
            let mut want = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
            for p in &v {
                for a in 0..3 {
                    want.0[a] = want.0[a].min(p[a]);
                    want.1[a] = want.1[a].max(p[a]);
                }
            }
            assert_eq!(bounds_of(&v), want, "{n} points");
        }
    }

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
        // Some degenerate (a zero normal stays zero), the count not a
        // multiple of the vector blocks.
        let triangles: Vec<[u32; 3]> = (0..150_003u32)
            .map(|i| match i % 997 {
                0 => [i % 1000, i % 1000, (i * 13 + 5) % 1000],
                _ => [i % 1000, (i * 7 + 1) % 1000, (i * 13 + 5) % 1000],
            })
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
        // The records are the ones the streaming writer makes, one
        // triangle at a time.
        let bytes = std::fs::read(&path).unwrap();
        assert_eq!(bytes.len(), 84 + 50 * mesh.triangles.len());
        for (i, rec) in bytes[84..].chunks_exact(50).enumerate() {
            let t = mesh.triangles[i].map(|v| mesh.vertices[v as usize]);
            assert_eq!(rec, &record(t)[..], "triangle {i}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
