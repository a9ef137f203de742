//! The OPC package: zip parts, the content types and the package
//! relationships (which name the root model part), each part's bytes
//! bounded by its declared size, and the memory budget of a read.

use crate::error::{invalid, Error, Result};
use crate::write::{REL_MODEL, ROOT_MODEL};
use quick_xml::events::{BytesStart, Event};
use std::collections::HashMap;
use std::io::{BufReader, Read, Seek};

/// The most bytes of model a part of `declared` uncompressed bytes can
/// give: every array element in memory has at least half as many bytes of
/// XML (a 24-byte vertex needs 27, a 12-byte triangle 33), components
/// (which are counted while reading, like everything else) aside.
pub(super) fn predicted_from_xml(declared: u64) -> u64 {
    declared / 2
}

/// A part's bytes, refused once they pass the size its zip entry declares
/// (so the declared size, checked before reading, bounds what is read).
pub(super) struct Declared<R> {
    inner: R,
    left: u64,
    part: String,
}

impl<R: Read> Read for Declared<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        if n as u64 > self.left {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                format!(
                    "/{} holds more bytes than its zip entry declares",
                    self.part
                ),
            ));
        }
        self.left -= n as u64;
        Ok(n)
    }
}

/// Checks a part's declared uncompressed size against what may still be
/// used, before reading it; gives its reader, bounded by that size.
pub(super) fn open_counted<'a, R: Read + Seek>(
    zip: &'a mut zip::ZipArchive<R>,
    part: &str,
    context: &str,
    predicted: impl Fn(u64) -> u64,
    budget: &Budget,
) -> Result<Declared<zip::read::ZipFile<'a, R>>> {
    let f = open_part(zip, part, context)?;
    let declared = f.size();
    budget.check(part, predicted(declared), || {
        format!("its zip entry declares {declared} bytes uncompressed")
    })?;
    Ok(Declared {
        inner: f,
        left: declared,
        part: part.to_string(),
    })
}

/// Bytes a read may still take, shared by the parts of a package.
#[derive(Clone, Debug)]
pub(super) struct Budget {
    limit: u64,
    used: std::cell::Cell<u64>,
}

impl Budget {
    pub(super) fn new(limit: u64) -> Budget {
        Budget {
            limit,
            used: std::cell::Cell::new(0),
        }
    }

    /// Refuses `more` bytes when they would pass the limit.
    pub(super) fn check(&self, part: &str, more: u64, why: impl Fn() -> String) -> Result<()> {
        let need = self.used.get().saturating_add(more);
        if need > self.limit {
            return Err(Error::TooLarge {
                part: format!("/{part}"),
                message: format!(
                    "reading it needs about {} MiB ({}), more than the {} MiB this job may \
                     use (the memory limit); use a machine with more memory or a smaller model",
                    need >> 20,
                    why(),
                    self.limit >> 20
                ),
            });
        }
        Ok(())
    }

    /// Takes `more` bytes, refusing them when they would pass the limit.
    pub(super) fn take(&self, part: &str, more: u64, why: impl Fn() -> String) -> Result<()> {
        self.check(part, more, why)?;
        self.used.set(self.used.get() + more);
        Ok(())
    }
}

fn open_part<'a, R: Read + Seek>(
    zip: &'a mut zip::ZipArchive<R>,
    part: &str,
    context: &str,
) -> Result<zip::read::ZipFile<'a, R>> {
    match zip.by_name(part) {
        Ok(f) => Ok(f),
        Err(zip::result::ZipError::FileNotFound) => Err(Error::MissingPart {
            part: format!("/{part}"),
            context: if context.is_empty() {
                String::new()
            } else {
                format!(": referenced by {context}")
            },
        }),
        Err(source) => Err(Error::Zip {
            part: format!("/{part}"),
            source,
        }),
    }
}

pub(super) fn xml_err(part: &str, offset: u64) -> impl Fn(quick_xml::Error) -> Error + '_ {
    move |source| Error::Xml {
        part: part.to_string(),
        offset,
        source,
    }
}

/// Attributes of an element as (local name, value), unprefixed ones only.
fn plain_attrs(e: &BytesStart, part: &str, offset: u64) -> Result<Vec<(String, String)>> {
    let mut v = Vec::new();
    for a in e.attributes() {
        let a = a.map_err(|e| Error::Xml {
            part: part.into(),
            offset,
            source: e.into(),
        })?;
        let val = a.unescape_value().map_err(|source| Error::Attribute {
            part: part.into(),
            offset,
            source,
        })?;
        v.push((
            String::from_utf8_lossy(a.key.as_ref()).into_owned(),
            val.into_owned(),
        ));
    }
    Ok(v)
}

/// The StartPart from `_rels/.rels`, checked against the content types.
pub(super) fn find_root<R: Read + Seek>(zip: &mut zip::ZipArchive<R>) -> Result<String> {
    let ct = "[Content_Types].xml";
    let mut defaults = HashMap::new();
    let mut overrides = HashMap::new();
    {
        let f = open_part(zip, ct, "")?;
        let mut r = quick_xml::Reader::from_reader(BufReader::new(f));
        let mut buf = Vec::new();
        loop {
            let off = r.buffer_position();
            match r.read_event_into(&mut buf).map_err(xml_err(ct, off))? {
                Event::Start(e) | Event::Empty(e) => {
                    let a = plain_attrs(&e, ct, off)?;
                    let get = |k: &str| a.iter().find(|x| x.0 == k).map(|x| x.1.clone());
                    match e.local_name().as_ref() {
                        b"Default" => {
                            if let (Some(x), Some(t)) = (get("Extension"), get("ContentType")) {
                                defaults.insert(x.to_ascii_lowercase(), t);
                            }
                        }
                        b"Override" => {
                            if let (Some(p), Some(t)) = (get("PartName"), get("ContentType")) {
                                overrides.insert(p.trim_start_matches('/').to_string(), t);
                            }
                        }
                        _ => {}
                    }
                }
                Event::DocType(_) => return Err(invalid(ct, off, "DTDs are not allowed")),
                Event::Eof => break,
                _ => {}
            }
            buf.clear();
        }
    }
    let rels = "_rels/.rels";
    let mut root = None;
    {
        let f = open_part(zip, rels, "")?;
        let mut r = quick_xml::Reader::from_reader(BufReader::new(f));
        let mut buf = Vec::new();
        loop {
            let off = r.buffer_position();
            match r.read_event_into(&mut buf).map_err(xml_err(rels, off))? {
                Event::Start(e) | Event::Empty(e) if e.local_name().as_ref() == b"Relationship" => {
                    let a = plain_attrs(&e, rels, off)?;
                    let get = |k: &str| a.iter().find(|x| x.0 == k).map(|x| x.1.clone());
                    if get("Type").as_deref() == Some(REL_MODEL) {
                        let t = get("Target")
                            .ok_or_else(|| invalid(rels, off, "Relationship without Target"))?;
                        if root.is_some() {
                            return Err(invalid(rels, off, "more than one StartPart relationship"));
                        }
                        root = Some(t.trim_start_matches('/').to_string());
                    }
                }
                Event::DocType(_) => return Err(invalid(rels, off, "DTDs are not allowed")),
                Event::Eof => break,
                _ => {}
            }
            buf.clear();
        }
    }
    let root = root.ok_or_else(|| {
        invalid(
            rels,
            0,
            format!("no StartPart relationship ({REL_MODEL}); a writer would use /{ROOT_MODEL}"),
        )
    })?;
    let ext = root.rsplit('.').next().unwrap_or("").to_ascii_lowercase();
    let ctype = overrides.get(&root).or_else(|| defaults.get(&ext));
    if ctype.map(String::as_str) != Some("application/vnd.ms-package.3dmanufacturing-3dmodel+xml") {
        return Err(invalid(
            ct,
            0,
            format!("the model part /{root} has content type {ctype:?}, not the 3D model type"),
        ));
    }
    Ok(root)
}
