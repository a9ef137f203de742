//! The zip archive of a package: fixed timestamps, deflated or stored
//! parts, zip64 where a model part may grow large.

use crate::error::{Error, Result};
use std::io::{Seek, Write};
use zip::write::SimpleFileOptions;

pub(super) fn io_err(part: &str, source: std::io::Error) -> Error {
    Error::Io {
        path: part.to_string(),
        source,
    }
}

/// A zip archive being written, with fixed timestamps. The writer is not
/// dropped when writing fails (a dropped `ZipWriter` tries to finish the
/// archive on the failed stream and prints to stderr); only
/// [`Package::finish`] closes it. The failed package's buffers are left to
/// the process (the caller removes the output).
pub(super) struct Package<W: Write + Seek> {
    zip: std::mem::ManuallyDrop<zip::ZipWriter<W>>,
    opts: SimpleFileOptions,
    part: String,
}

impl<W: Write + Seek> Package<W> {
    pub(super) fn new(w: W, deflate: bool) -> Self {
        let method = if deflate {
            zip::CompressionMethod::Deflated
        } else {
            zip::CompressionMethod::Stored
        };
        let opts = SimpleFileOptions::default()
            .compression_method(method)
            .last_modified_time(zip::DateTime::default())
            .large_file(false);
        Package {
            zip: std::mem::ManuallyDrop::new(zip::ZipWriter::new(w)),
            opts,
            part: String::new(),
        }
    }

    pub(super) fn start(&mut self, name: &str) -> Result<()> {
        self.part = name.to_string();
        // Parts over 4 GiB need zip64; the writer decides per part by size
        // only when told, so ask for it where a part might grow large.
        let opts = if name.ends_with(".model") {
            self.opts.large_file(true)
        } else {
            self.opts
        };
        self.zip
            .start_file(name, opts)
            .map_err(|source| Error::Zip {
                part: name.to_string(),
                source,
            })
    }

    pub(super) fn add(&mut self, name: &str, data: &[u8]) -> Result<()> {
        self.zip
            .start_file(name, self.opts)
            .map_err(|source| Error::Zip {
                part: name.to_string(),
                source,
            })?;
        self.zip.write_all(data).map_err(|e| io_err(name, e))
    }

    pub(super) fn finish(self) -> Result<W> {
        std::mem::ManuallyDrop::into_inner(self.zip)
            .finish()
            .map_err(|source| Error::Zip {
                part: "the archive".into(),
                source,
            })
    }
}

impl<W: Write + Seek> Write for Package<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.zip.write(buf)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.zip.flush()
    }
}
