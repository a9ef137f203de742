//! The package writer: validates a [`Model`] and writes the OPC package
//! (content types, relationships, the root model part, slice parts, PNG
//! sheets). Output is deterministic: fixed part order and zip timestamps.

// `package` is the zip archive, `xml` the number formats and the model
// head, `validate` the checks before writing; the root model part is
// written by `core_ns` (metadata, objects, meshes, build), which calls the
// files of the extensions (`materials`, `beam`, `slice`, `volumetric`,
// `implicit`) for their resources.
mod beam;
mod core_ns;
mod implicit;
mod materials;
mod package;
mod slice;
mod validate;
mod volumetric;
mod xml;

pub use validate::validate;

use crate::error::{Error, Result};
use crate::model::Model;
use package::{io_err, Package};
use std::fmt::Write as _;
use std::io::{BufWriter, Seek, Write};
use std::path::Path;
use xml::Extensions;

/// The root model part written by this crate.
pub const ROOT_MODEL: &str = "3D/3dmodel.model";

const CT_MODEL: &str = "application/vnd.ms-package.3dmanufacturing-3dmodel+xml";
const CT_RELS: &str = "application/vnd.openxmlformats-package.relationships+xml";
/// Relationship type of the StartPart and of other model parts.
pub(crate) const REL_MODEL: &str = "http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel";
/// Relationship type of textures (PNG sheets).
pub(crate) const REL_TEXTURE: &str =
    "http://schemas.microsoft.com/3dmanufacturing/2013/01/3dtexture";

/// How the writer splits and compresses.
#[derive(Clone, Debug)]
pub struct WriteOptions {
    /// A slice stack with more slices than this goes to separate parts
    /// referenced by `<s:sliceref>`, at most this many slices each.
    pub max_slices_per_part: usize,
    /// ... or when its XML would exceed this many bytes (per part).
    pub max_slice_bytes_per_part: usize,
    /// Deflate the parts (the default); `false` stores them.
    pub deflate: bool,
}

impl Default for WriteOptions {
    fn default() -> Self {
        WriteOptions {
            max_slices_per_part: 1000,
            max_slice_bytes_per_part: 32 << 20,
            deflate: true,
        }
    }
}

/// Writes `model` to the file `path` atomically: a temporary next to it,
/// renamed when complete (see `microfrep_io::atomic`); on an error nothing
/// is left behind.
pub fn write_file(path: impl AsRef<Path>, model: &Model, opts: &WriteOptions) -> Result<()> {
    let path = path.as_ref();
    let io = |e: microfrep_io::IoError| match e {
        microfrep_io::IoError::Io { source, .. } => Error::Io {
            path: path.display().to_string(),
            source,
        },
        other => Error::Io {
            path: path.display().to_string(),
            source: std::io::Error::other(other),
        },
    };
    let mut f = microfrep_io::AtomicFile::create(path).map_err(io)?;
    write_to(&mut f, model, opts)?;
    f.commit().map_err(io)
}

/// Writes `model` as a package into `w` and gives `w` back.
pub fn write_to<W: Write + Seek>(w: W, model: &Model, opts: &WriteOptions) -> Result<W> {
    validate(model)?;
    let mut pkg = Package::new(w, opts.deflate);
    let ext = Extensions::of(model);
    // Plan the slice parts and image sheets first: the root part names them.
    let (slice_parts, slice_refs) = slice::plan_slice_parts(model, opts);
    let (sheets, sheet_names) = volumetric::plan_sheets(model);

    // [Content_Types].xml and the package relationships.
    let mut ct = String::from(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<Types xmlns=\"http://schemas.openxmlformats.org/package/2006/content-types\">",
    );
    write!(
        ct,
        "<Default Extension=\"rels\" ContentType=\"{CT_RELS}\"/>"
    )
    .unwrap();
    write!(
        ct,
        "<Default Extension=\"model\" ContentType=\"{CT_MODEL}\"/>"
    )
    .unwrap();
    if !sheets.is_empty() {
        ct.push_str("<Default Extension=\"png\" ContentType=\"image/png\"/>");
    }
    ct.push_str("</Types>\n");
    pkg.add("[Content_Types].xml", ct.as_bytes())?;
    let rels = format!(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<Relationships xmlns=\"http://schemas.openxmlformats.org/package/2006/relationships\"><Relationship Target=\"/{ROOT_MODEL}\" Id=\"rel0\" Type=\"{REL_MODEL}\"/></Relationships>\n"
    );
    pkg.add("_rels/.rels", rels.as_bytes())?;

    // The root model part, streamed (meshes can be large).
    pkg.start(ROOT_MODEL)?;
    {
        let mut out = BufWriter::with_capacity(1 << 20, &mut pkg);
        core_ns::write_root(&mut out, model, &ext, &slice_refs, &sheet_names)
            .map_err(|e| io_err(ROOT_MODEL, e))?;
        out.flush().map_err(|e| io_err(ROOT_MODEL, e))?;
    }
    if !slice_parts.is_empty() || !sheets.is_empty() {
        let mut r = String::from(
            "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<Relationships xmlns=\"http://schemas.openxmlformats.org/package/2006/relationships\">",
        );
        let mut n = 0;
        for (name, _) in &slice_parts {
            write!(
                r,
                "<Relationship Target=\"/{name}\" Id=\"rel{n}\" Type=\"{REL_MODEL}\"/>"
            )
            .unwrap();
            n += 1;
        }
        for (name, _, _) in &sheets {
            write!(
                r,
                "<Relationship Target=\"/{name}\" Id=\"rel{n}\" Type=\"{REL_TEXTURE}\"/>"
            )
            .unwrap();
            n += 1;
        }
        r.push_str("</Relationships>\n");
        pkg.add("3D/_rels/3dmodel.model.rels", r.as_bytes())?;
    }
    for (name, xml) in &slice_parts {
        pkg.add(name, xml.as_bytes())?;
    }
    for (name, id, k) in &sheets {
        let im = model
            .images
            .iter()
            .find(|i| i.id == *id)
            .expect("planned above");
        let png = im.encode_sheet(*k, name)?;
        pkg.add(name, &png)?;
    }
    pkg.finish()
}
