//! Mesh writers: binary STL, OBJ, binary PLY and 3MF, written to a temporary
//! file next to the target and renamed into place only on success.

mod obj;
mod ply;
mod stl;
mod stream;
mod threemf;

pub use stl::StlWriter;
pub use stream::{stream_mesh, stream_temp_paths};

use crate::{Mesh, MeshError};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Stl,
    Obj,
    Ply,
    ThreeMf,
}

impl Format {
    /// The format named by the file extension.
    pub fn from_path(p: &Path) -> Result<Format, MeshError> {
        let ext = p
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase());
        match ext.as_deref() {
            Some("stl") => Ok(Format::Stl),
            Some("obj") => Ok(Format::Obj),
            Some("ply") => Ok(Format::Ply),
            Some("3mf") => Ok(Format::ThreeMf),
            _ => Err(MeshError::Input(format!(
                "{}: unknown mesh format (use .stl, .obj, .ply or .3mf)",
                p.display()
            ))),
        }
    }

    /// Whether the format stores vertex normals.
    pub fn wants_normals(self) -> bool {
        matches!(self, Format::Obj | Format::Ply)
    }
}

/// The temporary name `out` is written under before the rename (hidden, in
/// the same directory so the rename is atomic).
pub fn temp_path(out: &Path) -> PathBuf {
    let name = out
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    out.with_file_name(format!(".{name}.part"))
}

/// Writes `mesh` to `out` in `format`; `normals` (one per vertex) are used
/// by the formats that store them. On error nothing is left behind.
pub fn write_mesh(
    out: &Path,
    format: Format,
    mesh: &Mesh,
    normals: Option<&[[f32; 3]]>,
) -> Result<(), MeshError> {
    let tmp = temp_path(out);
    let io = |source| MeshError::Io {
        path: out.display().to_string(),
        source,
    };
    let res = (|| -> std::io::Result<()> {
        let file = File::create(&tmp)?;
        match format {
            Format::Stl => {
                let mut w = StlWriter::new(BufWriter::new(file))?;
                for t in &mesh.triangles {
                    w.push(t.map(|i| mesh.vertices[i as usize]))?;
                }
                w.finish()?
                    .into_inner()
                    .map_err(|e| e.into_error())?
                    .sync_all()
            }
            Format::ThreeMf => threemf::write(file, mesh).and_then(|f| f.sync_all()),
            Format::Obj | Format::Ply => {
                let mut w = BufWriter::new(file);
                if format == Format::Obj {
                    obj::write(&mut w, mesh, normals)?;
                } else {
                    ply::write(&mut w, mesh, normals)?;
                }
                w.flush()?;
                w.into_inner().map_err(|e| e.into_error())?.sync_all()
            }
        }
    })();
    match res.and_then(|_| std::fs::rename(&tmp, out)) {
        Ok(()) => Ok(()),
        Err(e) => {
            let _ = std::fs::remove_file(&tmp);
            Err(io(e))
        }
    }
}
