//! Writing a mesh while it is made, never holding it whole: binary STL
//! (triangles as they come, the count patched at the end) and binary PLY
//! (vertices and faces to two scratch files, joined behind the header once
//! the counts are known). Same bytes as [`super::write_mesh`] of the same
//! mesh; everything goes through one [`AtomicFile`], whose scratch files
//! are removed with it.

use super::{format_of, ply, StlWriter};
use crate::sink::{MeshSink, Tally, Tallying, VertexWindow};
use crate::{MeshError, Plan};
use microfrep_io::AtomicFile;
use std::fs::File;
use std::io::{BufWriter, Write};
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
    buf: Vec<u8>,
}

impl MeshSink for PlySink<'_> {
    fn vertices(&mut self, v: &[[f32; 3]]) -> Result<(), MeshError> {
        let ns = self.normals.map(|p| p.normals_at(v));
        self.buf.clear();
        for (i, p) in v.iter().enumerate() {
            ply::vertex(&mut self.buf, *p, ns.as_ref().map(|n| n[i]));
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
    let format = format_of(out)?;
    if !format.streams() {
        return Err(MeshError::Input(format!(
            "{}: only STL and PLY meshes can be streamed to disk",
            out.display()
        )));
    }
    let mut f = AtomicFile::create(out)?;
    let at = |e: MeshError| match e {
        MeshError::Stream(io) => MeshError::Io {
            path: out.display().to_string(),
            source: io,
        },
        e => e,
    };
    let tally = if format.extensions().contains(&"stl") {
        stream_stl(plan, &mut f, progress).map_err(at)?
    } else {
        stream_ply(plan, &mut f, normals, progress, verdict).map_err(at)?
    };
    if format.extensions().contains(&"stl") {
        verdict(&tally)?;
    }
    f.commit()?;
    Ok(tally)
}

fn stream_stl(
    plan: &Plan,
    f: &mut AtomicFile,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Tally, MeshError> {
    let w = StlWriter::new(f).map_err(io_err)?;
    let mut sink = StlSink { w };
    let mut t = Tallying {
        inner: &mut sink,
        tally: Tally::default(),
    };
    plan.run_into(&mut t, progress)?;
    let tally = t.tally;
    sink.w.finish().map_err(io_err)?;
    Ok(tally)
}

fn stream_ply(
    plan: &Plan,
    f: &mut AtomicFile,
    normals: bool,
    progress: &(dyn Fn(usize) + Sync),
    verdict: &dyn Fn(&Tally) -> Result<(), MeshError>,
) -> Result<Tally, MeshError> {
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
        buf: Vec::new(),
    };
    let mut t = Tallying {
        inner: &mut sink,
        tally: Tally::default(),
    };
    plan.run_into(&mut t, progress)?;
    let tally = t.tally;
    sink.verts.flush().map_err(io_err)?;
    sink.faces.flush().map_err(io_err)?;
    drop(sink);
    // Before the parts are joined: a refused mesh costs no more copying.
    verdict(&tally)?;
    let head = ply::header(tally.vertices, tally.triangles, normals);
    f.write_all(head.as_bytes()).map_err(io_err)?;
    for p in [&vp, &fp] {
        let mut r = File::open(p).map_err(io_err)?;
        std::io::copy(&mut r, f).map_err(io_err)?;
        // The scratch file is no longer needed; free its space early.
        let _ = std::fs::remove_file(p);
    }
    Ok(tally)
}
