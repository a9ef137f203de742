//! Mesh writers behind one trait, [`MeshFormat`], chosen by extension from
//! [`formats`]: binary STL, OBJ, binary PLY and 3MF. Every file goes through
//! [`microfrep_io::AtomicFile`] (a unique temporary next to the target,
//! renamed on success, removed on error or interruption), and the bytes of
//! large meshes are encoded in parallel chunks and written in large blocks.
//! PLY, OBJ and 3MF also store per-vertex colours ([`colour`]).

pub mod colour;
mod obj;
mod ply;
mod stl;
mod stream;
mod threemf;

pub use stl::StlWriter;
pub use stream::{stream_mesh, stream_mesh_checked, stream_mesh_coloured};

use crate::{Mesh, MeshError};
use microfrep_io::{AtomicFile, FormatRegistry, OutputFormat};
use rayon::prelude::*;
use std::io::Write;
use std::path::Path;
use std::sync::OnceLock;

/// A mesh file format.
pub trait MeshFormat: OutputFormat {
    /// Whether the format stores vertex normals (then they are computed
    /// from the model's gradient and passed to [`MeshFormat::write`]).
    fn wants_normals(&self) -> bool {
        false
    }
    /// Whether [`stream_mesh`] can write it while meshing.
    fn streams(&self) -> bool {
        false
    }
    /// Whether the format stores per-vertex colours (passed to
    /// [`MeshFormat::write`]).
    fn stores_colours(&self) -> bool {
        false
    }
    /// Writes the whole mesh to `out`, with `colours` (one per vertex)
    /// where the format stores them.
    fn write(
        &self,
        mesh: &Mesh,
        normals: Option<&[[f32; 3]]>,
        colours: Option<&[[u8; 3]]>,
        out: &mut AtomicFile,
    ) -> std::io::Result<()>;
    /// Whether [`MeshFormat::write_measured`] returns the volume and area.
    fn measures_volume(&self) -> bool {
        false
    }
    /// [`MeshFormat::write`], also returning the mesh's volume and area
    /// ([`crate::check::volume_area`], the same values bit for bit) where
    /// the format computes them while encoding (STL's facet normals; PLY
    /// sums them as it encodes its faces), so a job saves a pass over the
    /// triangles; `None` where it does not.
    fn write_measured(
        &self,
        mesh: &Mesh,
        normals: Option<&[[f32; 3]]>,
        colours: Option<&[[u8; 3]]>,
        out: &mut AtomicFile,
    ) -> std::io::Result<Option<(f64, f64)>> {
        self.write(mesh, normals, colours, out).map(|_| None)
    }
}

/// The mesh formats, by extension.
pub fn formats() -> &'static FormatRegistry<dyn MeshFormat> {
    static R: OnceLock<FormatRegistry<dyn MeshFormat>> = OnceLock::new();
    R.get_or_init(|| {
        let mut r: FormatRegistry<dyn MeshFormat> = FormatRegistry::new("mesh");
        r.register(Box::new(stl::Stl));
        r.register(Box::new(obj::Obj));
        r.register(Box::new(ply::Ply));
        r.register(Box::new(threemf::ThreeMf));
        r
    })
}

/// The format of `path` by its extension.
pub fn format_of(path: &Path) -> Result<&'static dyn MeshFormat, MeshError> {
    formats().for_path(path).map_err(MeshError::from)
}

/// Writes `mesh` to `out` in the format its extension names; `normals`
/// (one per vertex) are used by the formats that store them. On error
/// nothing is left behind.
pub fn write_mesh(out: &Path, mesh: &Mesh, normals: Option<&[[f32; 3]]>) -> Result<(), MeshError> {
    write_mesh_coloured(out, mesh, normals, None)
}

/// [`write_mesh`] with per-vertex sRGB `colours` (one per vertex); an
/// error, before anything is written, for a format that cannot store them
/// (STL) or a count that does not match the vertices.
pub fn write_mesh_coloured(
    out: &Path,
    mesh: &Mesh,
    normals: Option<&[[f32; 3]]>,
    colours: Option<&[[u8; 3]]>,
) -> Result<(), MeshError> {
    write_uncommitted(out, mesh, normals, colours)?.commit()?;
    Ok(())
}

/// As [`write_mesh_coloured`], but the file is left under its temporary
/// name: [`AtomicFile::commit`] puts it in place, dropping it removes it.
/// Lets a job check the mesh while it is being written and commit only if
/// the checks pass.
pub fn write_uncommitted(
    out: &Path,
    mesh: &Mesh,
    normals: Option<&[[f32; 3]]>,
    colours: Option<&[[u8; 3]]>,
) -> Result<AtomicFile, MeshError> {
    write_uncommitted_measured(out, mesh, normals, colours).map(|(f, _)| f)
}

/// [`write_uncommitted`], also returning the volume and area where the
/// format measured them while encoding ([`MeshFormat::write_measured`]).
pub fn write_uncommitted_measured(
    out: &Path,
    mesh: &Mesh,
    normals: Option<&[[f32; 3]]>,
    colours: Option<&[[u8; 3]]>,
) -> Result<(AtomicFile, Option<(f64, f64)>), MeshError> {
    let format = format_of(out)?;
    if colours.is_some() {
        check_colours(format, out)?;
    }
    if let Some(c) = colours.filter(|c| c.len() != mesh.vertices.len()) {
        return Err(MeshError::Input(format!(
            "{}: {} colours for {} vertices",
            out.display(),
            c.len(),
            mesh.vertices.len()
        )));
    }
    let mut f = AtomicFile::create(out)?;
    let measured = format
        .write_measured(mesh, normals, colours, &mut f)
        .map_err(|e| MeshError::from(f.err(e)))?;
    Ok((f, measured))
}

/// Meshes `plan` straight into `out` as binary STL (see
/// [`stl::StlJob`]), left uncommitted: the file, and the mesh's counts,
/// volume, area, bounding box and (where the census could count them as
/// the mesh came) edges.
pub(crate) fn mesh_to_stl(
    plan: &crate::Plan,
    out: &Path,
    expected_vertices: usize,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<(AtomicFile, stl::StlJobSummary), MeshError> {
    let mut f = AtomicFile::create(out)?;
    let at = |e: std::io::Error| MeshError::Io {
        path: out.display().to_string(),
        source: e,
    };
    let mut sink = stl::StlJob::new(&mut f, expected_vertices).map_err(at)?;
    plan.run_into(&mut sink, progress).map_err(|e| match e {
        MeshError::Stream(e) => at(e),
        e => e,
    })?;
    let collected = sink.finish().map_err(at)?;
    Ok((f, collected))
}

/// Whether `format` is binary STL.
pub(crate) fn is_stl(format: &dyn MeshFormat) -> bool {
    format.extensions().contains(&"stl")
}

/// An error unless `format` (of `out`) stores per-vertex colours.
pub fn check_colours(format: &dyn MeshFormat, out: &Path) -> Result<(), MeshError> {
    if format.stores_colours() {
        return Ok(());
    }
    Err(MeshError::Input(format!(
        "{}: {} has no per-vertex colours; write .ply, .obj or .3mf to colour by an attribute",
        out.display(),
        format.name()
    )))
}

/// Items per parallel encoding chunk (the chunk of
/// [`crate::check::volume_area`] too, so sums per chunk agree).
pub(crate) const CHUNK: usize = 1 << 16;

/// Encodes `items` in parallel chunks with `enc` and writes the chunks in
/// order, a few at a time so memory stays bounded. The chunk buffers are
/// reused from group to group (fresh ones cost a page fault per 4 KiB).
pub(crate) fn write_encoded<T: Sync>(
    w: &mut impl Write,
    items: &[T],
    enc: impl Fn(&[T], &mut Vec<u8>) + Sync,
) -> std::io::Result<()> {
    write_encoded_with(w, items, enc).map(|_| ())
}

/// [`write_encoded`], returning what `enc` gave for each chunk of
/// [`CHUNK`] items, in order (the chunks of `items` from its start).
pub(crate) fn write_encoded_with<T: Sync, R: Send>(
    w: &mut impl Write,
    items: &[T],
    enc: impl Fn(&[T], &mut Vec<u8>) -> R + Sync,
) -> std::io::Result<Vec<R>> {
    let per_group = 4 * rayon::current_num_threads().max(1);
    let mut bufs: Vec<Vec<u8>> = Vec::new();
    let mut out = Vec::with_capacity(items.len().div_ceil(CHUNK));
    for g in items.chunks(CHUNK * per_group) {
        let n = g.len().div_ceil(CHUNK);
        if bufs.len() < n {
            bufs.resize_with(n, Vec::new);
        }
        let got: Vec<R> = g
            .par_chunks(CHUNK)
            .zip(bufs[..n].par_iter_mut())
            .map(|(c, b)| {
                b.clear();
                enc(c, b)
            })
            .collect();
        out.extend(got);
        for b in &bufs[..n] {
            w.write_all(b)?;
        }
    }
    Ok(out)
}
