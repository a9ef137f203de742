//! The package reader: finds the root model through `[Content_Types].xml`
//! and `_rels/.rels`, streams its XML (namespace-aware, no DOM, so large
//! meshes cost about what their arrays cost), follows `<s:sliceref>` into
//! other model parts and decodes PNG sheets of image stacks.
//!
//! Errors name the part and the byte offset. Elements of namespaces this
//! crate does not know are skipped unless the model lists them in
//! `requiredextensions`, which is an error.

// `package` finds the parts and bounds what they may take, `parser` streams
// a model part and hands each element to the file of its namespace
// (`core_ns`, `materials`, `beam`, `slice`, `volumetric`, `implicit`;
// attribute values in `values`), and `image` decodes the PNG sheets of
// image stacks.
mod beam;
mod core_ns;
mod image;
mod implicit;
mod materials;
mod package;
mod parser;
mod slice;
mod values;
mod volumetric;

use crate::error::{Error, Result};
use crate::model::Model;
use package::{find_root, open_counted, predicted_from_xml, Budget};
use parser::parse_model;
use std::io::{BufReader, Read, Seek};
use std::path::Path;

/// Limits of a read.
#[derive(Clone, Debug)]
pub struct ReadOptions {
    /// Most bytes the model read (and, in [`crate::flatten`], its flattened
    /// geometry) may take.
    pub memory_limit: u64,
}

impl Default for ReadOptions {
    /// 80 % of what the process may allocate, else 4 GiB
    /// ([`microfrep_io::limits::default_memory_budget`]).
    fn default() -> Self {
        ReadOptions {
            memory_limit: microfrep_io::limits::default_memory_budget(),
        }
    }
}

/// Reads the package at `path`.
pub fn read_file(path: impl AsRef<Path>) -> Result<Model> {
    read_file_with(path, &ReadOptions::default())
}

/// [`read_file`] with limits.
pub fn read_file_with(path: impl AsRef<Path>, opts: &ReadOptions) -> Result<Model> {
    let path = path.as_ref();
    let io = |source| Error::Io {
        path: path.display().to_string(),
        source,
    };
    let f = std::fs::File::open(path).map_err(io)?;
    // A zip is read by seeking from its end: that needs a regular file.
    if !f.metadata().map_err(io)?.is_file() {
        return Err(io(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "not a regular file (a device, a pipe or a folder); a 3MF package is a zip file",
        )));
    }
    read_from_with(f, opts)
}

/// Reads a package from a seekable stream.
pub fn read_from<R: Read + Seek>(r: R) -> Result<Model> {
    read_from_with(r, &ReadOptions::default())
}

/// [`read_from`] with limits: each part's declared size is checked
/// against the memory limit before it is read, what is read is bounded by
/// that size, and the arrays are counted against the limit as they grow.
pub fn read_from_with<R: Read + Seek>(r: R, opts: &ReadOptions) -> Result<Model> {
    let mut zip = zip::ZipArchive::new(r).map_err(|source| Error::Zip {
        part: "the archive".into(),
        source,
    })?;
    let budget = Budget::new(opts.memory_limit);
    let root = find_root(&mut zip)?;
    let (mut model, refs) = {
        let f = open_counted(
            &mut zip,
            &root,
            "_rels/.rels (StartPart)",
            predicted_from_xml,
            &budget,
        )?;
        parse_model(BufReader::new(f), &root, &budget)?
    };
    // Slices kept in other parts.
    slice::read_slice_refs(&mut zip, &root, &mut model, refs, &budget)?;
    // Image sheets.
    image::read_sheets(&mut zip, &root, &mut model, &budget)?;
    core_ns::check_references(&model, &root)?;
    Ok(model)
}
