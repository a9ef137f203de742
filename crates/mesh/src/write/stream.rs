//! Writing a mesh while it is made, never holding it whole: binary STL
//! (triangles as they come, the count patched at the end) and binary PLY
//! (vertices and faces to two scratch files, joined behind the header once
//! the counts are known). Same bytes as [`super::write_mesh`] of the same
//! mesh; everything goes through one [`AtomicFile`], whose scratch files
//! are removed with it. PLY vertex colours stream too: the attribute's
//! value goes to the scratch file with each vertex and becomes a colour
//! when the parts are joined, once the value range is known.

use super::colour::{channel_tape, eval_at, scale_of, ColourBy};
use super::{format_of, ply, StlWriter};
use crate::edges::EdgeCensus;
use crate::sink::{Counting, MeshSink, Tally, Tallying, VertexWindow};
use crate::{MeshError, Plan};
use microfrep_core::Tape;
use microfrep_io::colormap::ColourScale;
use microfrep_io::AtomicFile;
use std::fs::File;
use std::io::{BufReader, BufWriter, Read, Write};
use std::path::Path;

struct StlSink<'a> {
    w: StlWriter<&'a mut AtomicFile>,
}

impl MeshSink for StlSink<'_> {
    fn vertices(&mut self, _: &[[f32; 3]]) -> Result<(), MeshError> {
        Ok(())
    }

    fn triangles(&mut self, t: &[[u32; 3]], window: &VertexWindow) -> Result<(), MeshError> {
        for tri in t {
            self.w.push(tri.map(|i| window.get(i))).map_err(io_err)?;
        }
        Ok(())
    }
}

struct PlySink<'a> {
    verts: BufWriter<File>,
    faces: BufWriter<File>,
    /// Set when vertex normals are wanted.
    normals: Option<&'a Plan>,
    /// The attribute channel colouring the vertices, if any; its value is
    /// written after each vertex record.
    channel: Option<Tape>,
    /// Smallest and largest finite attribute value so far.
    seen: [f64; 2],
    buf: Vec<u8>,
}

impl MeshSink for PlySink<'_> {
    fn vertices(&mut self, v: &[[f32; 3]]) -> Result<(), MeshError> {
        let ns = self.normals.map(|p| p.normals_at(v));
        let values = self.channel.as_ref().map(|t| eval_at(t, v));
        self.buf.clear();
        for (i, p) in v.iter().enumerate() {
            ply::vertex(&mut self.buf, *p, ns.as_ref().map(|n| n[i]));
            if let Some(s) = &values {
                let x = s[i];
                if x.is_finite() {
                    self.seen = [self.seen[0].min(x as f64), self.seen[1].max(x as f64)];
                }
                self.buf.extend_from_slice(&x.to_le_bytes());
            }
        }
        self.verts.write_all(&self.buf).map_err(io_err)
    }

    fn triangles(&mut self, t: &[[u32; 3]], _: &VertexWindow) -> Result<(), MeshError> {
        self.buf.clear();
        for tri in t {
            ply::face(&mut self.buf, *tri);
        }
        self.faces.write_all(&self.buf).map_err(io_err)
    }
}

/// A sink's I/O error, given the target's path by [`stream_mesh`].
fn io_err(e: std::io::Error) -> MeshError {
    MeshError::Stream(e)
}

/// Meshes `plan` straight into `out` (STL or PLY by extension; PLY with
/// vertex normals when `normals`), holding only a few slabs of bricks in
/// memory. Returns the mesh's counts, volume, area and bounding box. On
/// error or interruption nothing is left behind.
pub fn stream_mesh(
    plan: &Plan,
    out: &Path,
    normals: bool,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Tally, MeshError> {
    stream_mesh_checked(plan, out, normals, progress, &|_| Ok(()))
}

/// [`stream_mesh`], with `verdict` asked about the finished mesh's tally
/// before the file is committed: an error from it leaves nothing behind.
pub fn stream_mesh_checked(
    plan: &Plan,
    out: &Path,
    normals: bool,
    progress: &(dyn Fn(usize) + Sync),
    verdict: &dyn Fn(&Tally) -> Result<(), MeshError>,
) -> Result<Tally, MeshError> {
    stream_mesh_coloured(plan, out, normals, None, progress, verdict).map(|r| r.0)
}

/// [`stream_mesh_checked`], with the vertices coloured by the attribute
/// `colour` names (a channel of `colour.0`; PLY only, an error before
/// anything is meshed for STL); returns the colour scale used too.
pub fn stream_mesh_coloured(
    plan: &Plan,
    out: &Path,
    normals: bool,
    colour: Option<(&microfrep_core::Shape, &ColourBy)>,
    progress: &(dyn Fn(usize) + Sync),
    verdict: &dyn Fn(&Tally) -> Result<(), MeshError>,
) -> Result<(Tally, Option<ColourScale>), MeshError> {
    let format = format_of(out)?;
    if !format.streams() {
        return Err(MeshError::Input(format!(
            "{}: only STL and PLY meshes can be streamed to disk",
            out.display()
        )));
    }
    let channel = match colour {
        Some((shape, by)) => {
            super::check_colours(format, out)?;
            // A bad range is refused before meshing.
            scale_of(by, &[])?;
            Some((channel_tape(shape, by.channel)?, by))
        }
        None => None,
    };
    let mut f = AtomicFile::create(out)?;
    let at = |e: MeshError| match e {
        MeshError::Stream(io) => MeshError::Io {
            path: out.display().to_string(),
            source: io,
        },
        e => e,
    };
    let (tally, scale) = if format.extensions().contains(&"stl") {
        (stream_stl(plan, &mut f, progress).map_err(at)?, None)
    } else {
        stream_ply(plan, &mut f, normals, channel, progress, verdict).map_err(at)?
    };
    if format.extensions().contains(&"stl") {
        verdict(&tally)?;
    }
    f.commit()?;
    Ok((tally, scale))
}

fn stream_stl(
    plan: &Plan,
    f: &mut AtomicFile,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Tally, MeshError> {
    let w = StlWriter::new(f).map_err(io_err)?;
    let mut sink = StlSink { w };
    let mut counting = Counting {
        inner: &mut sink,
        census: EdgeCensus::new(),
    };
    let mut t = Tallying {
        inner: &mut counting,
        tally: Tally::default(),
    };
    plan.run_into(&mut t, progress)?;
    let mut tally = t.tally;
    tally.edges = counting.census.finish();
    sink.w.finish().map_err(io_err)?;
    Ok(tally)
}

fn stream_ply(
    plan: &Plan,
    f: &mut AtomicFile,
    normals: bool,
    channel: Option<(Tape, &ColourBy)>,
    progress: &(dyn Fn(usize) + Sync),
    verdict: &dyn Fn(&Tally) -> Result<(), MeshError>,
) -> Result<(Tally, Option<ColourScale>), MeshError> {
    let by = channel.as_ref().map(|c| c.1);
    let (vp, fp) = (f.scratch_path(), f.scratch_path());
    let create = |p: &Path| -> Result<BufWriter<File>, MeshError> {
        Ok(BufWriter::with_capacity(
            4 << 20,
            File::create(p).map_err(io_err)?,
        ))
    };
    let mut sink = PlySink {
        verts: create(&vp)?,
        faces: create(&fp)?,
        normals: normals.then_some(plan),
        channel: channel.map(|c| c.0),
        seen: [f64::INFINITY, f64::NEG_INFINITY],
        buf: Vec::new(),
    };
    let mut counting = Counting {
        inner: &mut sink,
        census: EdgeCensus::new(),
    };
    let mut t = Tallying {
        inner: &mut counting,
        tally: Tally::default(),
    };
    plan.run_into(&mut t, progress)?;
    let mut tally = t.tally;
    tally.edges = counting.census.finish();
    sink.verts.flush().map_err(io_err)?;
    sink.faces.flush().map_err(io_err)?;
    let seen = sink.seen;
    drop(sink);
    // Before the parts are joined: a refused mesh costs no more copying.
    verdict(&tally)?;
    // The range asked for, or the values' own (as over all vertices).
    let scale = match by {
        Some(by) if by.range.is_some() => Some(scale_of(by, &[])?),
        Some(by) => Some(ColourScale::over(by.colormap, seen)),
        None => None,
    };
    let head = ply::header(tally.vertices, tally.triangles, normals, scale.is_some());
    f.write_all(head.as_bytes()).map_err(io_err)?;
    for (k, p) in [&vp, &fp].into_iter().enumerate() {
        let mut r = File::open(p).map_err(io_err)?;
        match (k, &scale) {
            (0, Some(s)) => colour_records(&mut r, f, if normals { 24 } else { 12 }, s)?,
            _ => {
                std::io::copy(&mut r, f).map_err(io_err)?;
            }
        }
        // The scratch file is no longer needed; free its space early.
        let _ = std::fs::remove_file(p);
    }
    Ok((tally, scale))
}

/// Copies vertex records of `head` bytes, each followed by an f32
/// attribute value, from `r` to `w`, the value replaced by its colour.
fn colour_records(
    r: &mut File,
    w: &mut AtomicFile,
    head: usize,
    scale: &ColourScale,
) -> Result<(), MeshError> {
    const RECORDS: usize = 1 << 16;
    let rec = head + 4;
    let mut r = BufReader::with_capacity(4 << 20, r);
    let mut inp = vec![0u8; rec * RECORDS];
    let mut outp = Vec::with_capacity((head + 3) * RECORDS);
    loop {
        // Fill whole records (the last read may be short).
        let mut n = 0;
        while n < inp.len() {
            match r.read(&mut inp[n..]).map_err(io_err)? {
                0 => break,
                k => n += k,
            }
        }
        if n % rec != 0 {
            return Err(MeshError::Internal(format!(
                "vertex scratch file ends inside a record ({n} bytes in the last block)"
            )));
        }
        outp.clear();
        for c in inp[..n].chunks_exact(rec) {
            outp.extend_from_slice(&c[..head]);
            let v = f32::from_le_bytes(c[head..].try_into().expect("4 bytes"));
            outp.extend_from_slice(&scale.colour(v as f64));
        }
        w.write_all(&outp).map_err(io_err)?;
        if n < inp.len() {
            return Ok(());
        }
    }
}
