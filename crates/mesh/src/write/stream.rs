//! Writing a mesh while it is made, never holding it whole: binary STL
//! (triangles as they come, the count patched at the end) and binary PLY
//! (vertices and faces to two scratch files, joined behind the header once
//! the counts are known). Same bytes as [`super::write_mesh`] of the same
//! mesh; temporary files next to the output, renamed only on success.

use super::{ply, temp_path, Format, StlWriter};
use crate::sink::{MeshSink, Tally, Tallying, VertexWindow};
use crate::{MeshError, Plan};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// Every temporary file [`stream_mesh`] may create for `out`: the output's
/// own temporary name first, then PLY's vertex and face scratch files.
pub fn stream_temp_paths(out: &Path) -> Vec<PathBuf> {
    let t = temp_path(out);
    let side = |ext: &str| {
        let mut s = t.clone().into_os_string();
        s.push(ext);
        PathBuf::from(s)
    };
    vec![t.clone(), side(".vertices"), side(".faces")]
}

fn io(out: &Path) -> impl Fn(std::io::Error) -> MeshError + '_ {
    move |source| MeshError::Io {
        path: out.display().to_string(),
        source,
    }
}

struct StlSink<'a> {
    w: StlWriter<BufWriter<File>>,
    out: &'a Path,
}

impl MeshSink for StlSink<'_> {
    fn vertices(&mut self, _: &[[f32; 3]]) -> Result<(), MeshError> {
        Ok(())
    }

    fn triangles(&mut self, t: &[[u32; 3]], window: &VertexWindow) -> Result<(), MeshError> {
        for tri in t {
            self.w
                .push(tri.map(|i| window.get(i)))
                .map_err(io(self.out))?;
        }
        Ok(())
    }
}

struct PlySink<'a> {
    verts: BufWriter<File>,
    faces: BufWriter<File>,
    /// Set when vertex normals are wanted.
    normals: Option<&'a Plan>,
    out: &'a Path,
}

impl MeshSink for PlySink<'_> {
    fn vertices(&mut self, v: &[[f32; 3]]) -> Result<(), MeshError> {
        let ns = self.normals.map(|p| p.normals_at(v));
        for (i, p) in v.iter().enumerate() {
            ply::vertex(&mut self.verts, *p, ns.as_ref().map(|n| n[i])).map_err(io(self.out))?;
        }
        Ok(())
    }

    fn triangles(&mut self, t: &[[u32; 3]], _: &VertexWindow) -> Result<(), MeshError> {
        for tri in t {
            ply::face(&mut self.faces, *tri).map_err(io(self.out))?;
        }
        Ok(())
    }
}

/// Meshes `plan` straight into `out` (STL or PLY; PLY with vertex normals
/// when `normals`), holding only a few slabs of bricks in memory. Returns
/// the mesh's counts, volume, area and bounding box. On error nothing is
/// left behind.
pub fn stream_mesh(
    plan: &Plan,
    out: &Path,
    format: Format,
    normals: bool,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Tally, MeshError> {
    let paths = stream_temp_paths(out);
    let res = match format {
        Format::Stl => stream_stl(plan, out, &paths[0], progress),
        Format::Ply => stream_ply(plan, out, &paths, normals, progress),
        _ => Err(MeshError::Input(format!(
            "{}: only STL and PLY meshes can be streamed to disk",
            out.display()
        ))),
    };
    let res = res.and_then(|t| {
        std::fs::rename(&paths[0], out).map_err(io(out))?;
        Ok(t)
    });
    for p in &paths[if res.is_ok() { 1 } else { 0 }..] {
        let _ = std::fs::remove_file(p);
    }
    res
}

fn create(p: &Path, out: &Path) -> Result<BufWriter<File>, MeshError> {
    Ok(BufWriter::with_capacity(
        1 << 20,
        File::create(p).map_err(io(out))?,
    ))
}

fn stream_stl(
    plan: &Plan,
    out: &Path,
    tmp: &Path,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Tally, MeshError> {
    let w = StlWriter::new(create(tmp, out)?).map_err(io(out))?;
    let mut sink = StlSink { w, out };
    let mut t = Tallying {
        inner: &mut sink,
        tally: Tally::default(),
    };
    plan.run_into(&mut t, progress)?;
    let tally = t.tally;
    let file = sink
        .w
        .finish()
        .map_err(io(out))?
        .into_inner()
        .map_err(|e| io(out)(e.into_error()))?;
    file.sync_all().map_err(io(out))?;
    Ok(tally)
}

fn stream_ply(
    plan: &Plan,
    out: &Path,
    paths: &[PathBuf],
    normals: bool,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Tally, MeshError> {
    let mut sink = PlySink {
        verts: create(&paths[1], out)?,
        faces: create(&paths[2], out)?,
        normals: normals.then_some(plan),
        out,
    };
    let mut t = Tallying {
        inner: &mut sink,
        tally: Tally::default(),
    };
    plan.run_into(&mut t, progress)?;
    let tally = t.tally;
    sink.verts.flush().map_err(io(out))?;
    sink.faces.flush().map_err(io(out))?;
    drop(sink);
    let mut w = File::create(&paths[0]).map_err(io(out))?;
    let head = ply::header(tally.vertices, tally.triangles, normals);
    w.write_all(head.as_bytes()).map_err(io(out))?;
    for p in &paths[1..] {
        let mut r = File::open(p).map_err(io(out))?;
        std::io::copy(&mut r, &mut w).map_err(io(out))?;
        // The scratch file is no longer needed; free its space early.
        let _ = std::fs::remove_file(p);
    }
    w.sync_all().map_err(io(out))?;
    Ok(tally)
}
