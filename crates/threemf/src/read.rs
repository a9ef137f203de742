//! The package reader: finds the root model through `[Content_Types].xml`
//! and `_rels/.rels`, streams its XML (namespace-aware, no DOM, so large
//! meshes cost about what their arrays cost), follows `<s:sliceref>` into
//! other model parts and decodes PNG sheets of image stacks.
//!
//! Errors name the part and the byte offset. Elements of namespaces this
//! crate does not know are skipped unless the model lists them in
//! `requiredextensions`, which is an error.

use crate::beam::{Ball, BallMode, Beam, BeamLattice, BeamSet, Cap, ClipMode};
use crate::error::{invalid, Error, Result};
use crate::implicit::{
    FunctionOutput, ImplicitFunction, ImplicitGraph, ImplicitNode, NodeInput, NodeValue, PortType,
};
use crate::model::*;
use crate::slice::{Slice, SliceStack};
use crate::volumetric::*;
use crate::write::{REL_MODEL, ROOT_MODEL};
use quick_xml::events::{BytesStart, Event};
use quick_xml::name::{QName, ResolveResult};
use quick_xml::NsReader;
use std::collections::HashMap;
use std::io::{BufRead, BufReader, Read, Seek};
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

/// The most bytes of model a part of `declared` uncompressed bytes can
/// give: every array element in memory has at least half as many bytes of
/// XML (a 24-byte vertex needs 27, a 12-byte triangle 33), components
/// (which are counted while reading, like everything else) aside.
fn predicted_from_xml(declared: u64) -> u64 {
    declared / 2
}

/// A part's bytes, refused once they pass the size its zip entry declares
/// (so the declared size, checked before reading, bounds what is read).
struct Declared<R> {
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
fn open_counted<'a, R: Read + Seek>(
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
struct Budget {
    limit: u64,
    used: std::cell::Cell<u64>,
}

impl Budget {
    fn new(limit: u64) -> Budget {
        Budget {
            limit,
            used: std::cell::Cell::new(0),
        }
    }

    /// Refuses `more` bytes when they would pass the limit.
    fn check(&self, part: &str, more: u64, why: impl Fn() -> String) -> Result<()> {
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
    fn take(&self, part: &str, more: u64, why: impl Fn() -> String) -> Result<()> {
        self.check(part, more, why)?;
        self.used.set(self.used.get() + more);
        Ok(())
    }
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
    for (stack_id, refs) in refs.slice_refs {
        let mut slices = Vec::new();
        for (ref_id, path, offset) in refs {
            let part = path.trim_start_matches('/').to_string();
            let ctx = format!("sliceref of slicestack {stack_id} in /{root}");
            let f = open_counted(&mut zip, &part, &ctx, predicted_from_xml, &budget)?;
            let (sub, subrefs) = parse_model(BufReader::new(f), &part, &budget)?;
            if !subrefs.slice_refs.is_empty() {
                return Err(invalid(
                    &part,
                    0,
                    "a referenced slice stack must not hold further slicerefs",
                ));
            }
            let st = sub
                .slice_stacks
                .into_iter()
                .find(|s| s.id == ref_id)
                .ok_or_else(|| {
                    invalid(
                        &root,
                        offset,
                        format!("slicestack {ref_id} not found in /{part}"),
                    )
                })?;
            let last = slices.last().map(|s: &Slice| s.ztop);
            if let (Some(z), Some(first)) = (last, st.slices.first()) {
                if first.ztop.partial_cmp(&z) != Some(std::cmp::Ordering::Greater) {
                    return Err(invalid(
                        &part,
                        0,
                        format!(
                            "slice tops must increase across parts: {} after {z}",
                            first.ztop
                        ),
                    ));
                }
            }
            slices.extend(st.slices);
        }
        if let Some(st) = model.slice_stacks.iter_mut().find(|s| s.id == stack_id) {
            st.slices = slices;
        }
    }
    // Image sheets.
    for im in &mut model.images {
        let expected = im.dims;
        let mut layout = None;
        let mut depth = 0u8;
        let nx = expected[0];
        let ny = expected[1];
        let mut samples = Vec::new();
        for (k, path) in im.sheet_paths.iter().enumerate() {
            let part = path.trim_start_matches('/').to_string();
            let ctx = format!("imagesheet {k} of image3d {} in /{root}", im.id);
            let f = open_counted(&mut zip, &part, &ctx, |_| 0, &budget)?;
            let (l, d, data) = decode_sheet(BufReader::new(f), &part, nx, ny)?;
            if layout.is_some_and(|x| x != l) || (depth != 0 && depth != d) {
                return Err(invalid(
                    &part,
                    0,
                    "all sheets of an image stack must have the same channels and bit depth",
                ));
            }
            if samples.is_empty() {
                let n = (nx * ny * expected[2] * l.channels()) as u64;
                budget.take(&part, n * 2, || {
                    format!("image3d {} of {expected:?} samples", im.id)
                })?;
                samples.reserve(n as usize);
            }
            layout = Some(l);
            depth = d;
            samples.extend(data);
        }
        im.layout = layout.unwrap_or(PixelLayout::Y);
        im.bit_depth = depth.max(8);
        im.samples = samples;
    }
    check_references(&model, &root)?;
    Ok(model)
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

fn xml_err(part: &str, offset: u64) -> impl Fn(quick_xml::Error) -> Error + '_ {
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
fn find_root<R: Read + Seek>(zip: &mut zip::ZipArchive<R>) -> Result<String> {
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

/// Decodes one PNG sheet into samples (flipped so that `iy = 0` is the
/// bottom row).
fn decode_sheet<R: BufRead>(
    r: R,
    part: &str,
    nx: usize,
    ny: usize,
) -> Result<(PixelLayout, u8, Vec<u16>)> {
    let mut dec = png::Decoder::new_with_limits(
        r,
        png::Limits {
            bytes: (nx * ny * 8).max(1 << 16),
        },
    );
    dec.set_transformations(png::Transformations::EXPAND);
    let err = |source| Error::PngDecode {
        part: part.to_string(),
        source,
    };
    let mut reader = dec.read_info().map_err(err)?;
    let (w, h) = (reader.info().width as usize, reader.info().height as usize);
    if w != nx || h != ny {
        return Err(invalid(
            part,
            0,
            format!("sheet is {w}x{h}, the image stack says {nx}x{ny}"),
        ));
    }
    let mut data = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut data).map_err(err)?;
    let layout = match info.color_type {
        png::ColorType::Grayscale => PixelLayout::Y,
        png::ColorType::GrayscaleAlpha => PixelLayout::YA,
        png::ColorType::Rgb => PixelLayout::Rgb,
        png::ColorType::Rgba => PixelLayout::Rgba,
        png::ColorType::Indexed => {
            return Err(invalid(part, 0, "indexed PNG sheets are not supported"))
        }
    };
    let (depth, bytes) = match info.bit_depth {
        png::BitDepth::Sixteen => (16u8, 2usize),
        png::BitDepth::Eight => (8, 1),
        d => {
            return Err(invalid(
                part,
                0,
                format!("PNG bit depth {d:?} (only 8 and 16 are supported)"),
            ));
        }
    };
    let nc = layout.channels();
    let mut out = Vec::with_capacity(nx * ny * nc);
    for iy in 0..ny {
        let row = &data[(ny - 1 - iy) * info.line_size..][..nx * nc * bytes];
        if bytes == 2 {
            out.extend(
                row.chunks_exact(2)
                    .map(|c| u16::from_be_bytes([c[0], c[1]])),
            );
        } else {
            out.extend(row.iter().map(|&b| b as u16));
        }
    }
    Ok((layout, depth, out))
}

/// One `<s:sliceref>`: referenced stack id, part path, byte offset.
type SliceRef = (u32, String, u64);

/// Slice references found while parsing, per referencing stack id.
#[derive(Default)]
struct Refs {
    slice_refs: Vec<(u32, Vec<SliceRef>)>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Ns {
    None,
    Core,
    Material,
    Slice,
    Beam,
    Balls,
    Volumetric,
    Implicit,
    Production,
    Other,
}

fn ns_of(r: &ResolveResult) -> Ns {
    match r {
        ResolveResult::Unbound => Ns::None,
        ResolveResult::Unknown(_) => Ns::Other,
        ResolveResult::Bound(n) => match n.as_ref() {
            x if x == ns::CORE.as_bytes() => Ns::Core,
            x if x == ns::MATERIAL.as_bytes() => Ns::Material,
            x if x == ns::SLICE.as_bytes() => Ns::Slice,
            x if x == ns::BEAM.as_bytes() => Ns::Beam,
            x if x == ns::BALLS.as_bytes() => Ns::Balls,
            x if x == ns::VOLUMETRIC.as_bytes() => Ns::Volumetric,
            x if x == ns::IMPLICIT.as_bytes() => Ns::Implicit,
            x if x == ns::PRODUCTION.as_bytes() => Ns::Production,
            _ => Ns::Other,
        },
    }
}

/// Element contexts of the streaming parser.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Ctx {
    Model,
    Metadata,
    Resources,
    Build,
    BaseMaterials,
    CompositeMaterials,
    ColorGroup,
    Object,
    Mesh,
    Vertices,
    Triangles,
    Components,
    Lattice,
    Beams,
    Balls,
    BeamSets,
    BeamSet,
    SliceStack,
    Slice,
    SliceVertices,
    Polygon,
    Image3D,
    ImageStack,
    VolumeData,
    Composite,
    Implicit,
    FnIn,
    FnOut,
    Node,
    NodeIn,
    NodeOut,
    /// An element skipped with all its content.
    Skip,
}

/// An attribute: namespace, local name, value.
struct Attr {
    ns: Ns,
    name: String,
    value: String,
}

struct Parser<'p> {
    part: &'p str,
    /// Memory the package may still take; every array element is counted
    /// twice its size (a growing vector holds up to twice its length).
    budget: &'p Budget,
    /// Resource ids seen, which must be unique in a model part.
    ids: std::collections::HashSet<u32>,
    off: u64,
    model: Model,
    refs: Refs,
    object: Option<Object>,
    mesh: Option<Mesh>,
    tri_pids: Option<u32>,
    tri_props: Vec<[u32; 3]>,
    tri_props_ok: bool,
    components: Vec<Component>,
    lattice: Option<BeamLattice>,
    beamset: Option<BeamSet>,
    stack: Option<SliceStack>,
    stack_refs: Vec<SliceRef>,
    slice: Option<Slice>,
    slice_vertices: Vec<[f64; 2]>,
    polygon: Option<(u32, Vec<u32>)>,
    image: Option<Image3D>,
    volume: Option<VolumeData>,
    composite: Option<Composite>,
    function: Option<ImplicitFunction>,
    node: Option<ImplicitNode>,
    metadata_name: Option<String>,
    text: String,
}

fn parse_model<R: BufRead>(r: R, part: &str, budget: &Budget) -> Result<(Model, Refs)> {
    let mut reader = NsReader::from_reader(r);
    reader.config_mut().expand_empty_elements = false;
    let mut p = Parser {
        part,
        budget,
        ids: std::collections::HashSet::new(),
        off: 0,
        model: Model::default(),
        refs: Refs::default(),
        object: None,
        mesh: None,
        tri_pids: None,
        tri_props: Vec::new(),
        tri_props_ok: true,
        components: Vec::new(),
        lattice: None,
        beamset: None,
        stack: None,
        stack_refs: Vec::new(),
        slice: None,
        slice_vertices: Vec::new(),
        polygon: None,
        image: None,
        volume: None,
        composite: None,
        function: None,
        node: None,
        metadata_name: None,
        text: String::new(),
    };
    let mut stack: Vec<Ctx> = Vec::new();
    let mut buf = Vec::new();
    let mut seen_model = false;
    loop {
        p.off = reader.buffer_position();
        let (res, ev) = reader
            .read_resolved_event_into(&mut buf)
            .map_err(xml_err(part, p.off))?;
        let ens = ns_of(&res);
        match ev {
            Event::Start(ref e) | Event::Empty(ref e) => {
                let name = std::str::from_utf8(e.local_name().as_ref())
                    .unwrap_or("")
                    .to_string();
                let ctx = match stack.last().copied() {
                    Some(Ctx::Skip) => Ctx::Skip,
                    None => {
                        if ens != Ns::Core || name != "model" || seen_model {
                            return Err(invalid(
                                part,
                                p.off,
                                format!("root element is <{name}>, not one core <model>"),
                            ));
                        }
                        seen_model = true;
                        p.model_start(&reader, e)?;
                        Ctx::Model
                    }
                    Some(parent) => p.start(&reader, parent, ens, &name, e)?,
                };
                if matches!(ev, Event::Empty(_)) {
                    p.end(ctx)?;
                } else {
                    stack.push(ctx);
                }
            }
            Event::End(_) => {
                let ctx = stack
                    .pop()
                    .ok_or_else(|| invalid(part, p.off, "unbalanced end tag"))?;
                p.end(ctx)?;
            }
            Event::Text(t) if stack.last() == Some(&Ctx::Metadata) => {
                let s = t.unescape().map_err(xml_err(part, p.off))?;
                p.text.push_str(&s);
            }
            Event::DocType(_) => {
                return Err(invalid(
                    part,
                    p.off,
                    "DTDs are not allowed (core spec 2.3.2)",
                ))
            }
            Event::Eof => break,
            _ => {}
        }
        buf.clear();
    }
    if !seen_model {
        return Err(invalid(part, 0, "no <model> element"));
    }
    if !stack.is_empty() {
        return Err(invalid(part, p.off, "document ends inside an element"));
    }
    Ok((p.model, p.refs))
}

fn parse_num(part: &str, off: u64, what: &str, v: &str) -> Result<f64> {
    let t = v.trim();
    match t.parse::<f64>() {
        Ok(x) if x.is_finite() && !t.contains(['i', 'I', 'n', 'N']) => Ok(x),
        Ok(_) => Err(invalid(
            part,
            off,
            format!("{what} = \"{v}\" is not a finite number"),
        )),
        Err(_) => Err(invalid(
            part,
            off,
            format!("{what} = \"{v}\" is not a number"),
        )),
    }
}

/// An xs:double (may be INF, -INF, NaN).
/// An sRGB colour `#RRGGBB` or `#RRGGBBAA` (alpha 255 when absent).
fn parse_colour(part: &str, off: u64, v: &str) -> Result<[u8; 4]> {
    let hex = v.trim().strip_prefix('#').unwrap_or("");
    let byte = |i: usize| {
        hex.get(i..i + 2)
            .and_then(|h| u8::from_str_radix(h, 16).ok())
    };
    match (hex.len(), byte(0), byte(2), byte(4)) {
        (6, Some(r), Some(g), Some(b)) => Ok([r, g, b, 255]),
        (8, Some(r), Some(g), Some(b)) => match byte(6) {
            Some(a) => Ok([r, g, b, a]),
            None => Err(invalid(
                part,
                off,
                format!("colour \"{v}\" is not #RRGGBB or #RRGGBBAA"),
            )),
        },
        _ => Err(invalid(
            part,
            off,
            format!("colour \"{v}\" is not #RRGGBB or #RRGGBBAA"),
        )),
    }
}

fn parse_double(part: &str, off: u64, what: &str, v: &str) -> Result<f64> {
    match v.trim() {
        "INF" => Ok(f64::INFINITY),
        "-INF" => Ok(f64::NEG_INFINITY),
        "NaN" => Ok(f64::NAN),
        t => parse_num(part, off, what, t),
    }
}

fn parse_index(part: &str, off: u64, what: &str, v: &str) -> Result<u32> {
    v.trim()
        .parse::<u32>()
        .ok()
        .filter(|&x| x <= i32::MAX as u32)
        .ok_or_else(|| {
            invalid(
                part,
                off,
                format!("{what} = \"{v}\" is not an index in 0..2^31"),
            )
        })
}

fn parse_id(part: &str, off: u64, what: &str, v: &str) -> Result<u32> {
    let x = parse_index(part, off, what, v)?;
    if x == 0 {
        return Err(invalid(
            part,
            off,
            format!("{what} must be a positive resource id"),
        ));
    }
    Ok(x)
}

fn parse_transform(part: &str, off: u64, v: &str) -> Result<Transform> {
    let vals: Vec<&str> = v.split_ascii_whitespace().collect();
    if vals.len() != 12 {
        return Err(invalid(
            part,
            off,
            format!("transform \"{v}\" needs 12 numbers, has {}", vals.len()),
        ));
    }
    let mut m = [0.0; 12];
    for (i, x) in vals.iter().enumerate() {
        m[i] = parse_num(part, off, "transform entry", x)?;
    }
    Ok(Transform(m))
}

fn parse_bool(part: &str, off: u64, what: &str, v: &str) -> Result<bool> {
    match v.trim() {
        "true" | "1" => Ok(true),
        "false" | "0" => Ok(false),
        _ => Err(invalid(
            part,
            off,
            format!("{what} = \"{v}\" is not a boolean"),
        )),
    }
}

impl Parser<'_> {
    fn err(&self, msg: impl Into<String>) -> Error {
        invalid(self.part, self.off, msg)
    }

    /// Counts one more array element of type `T` against the budget.
    fn charge<T>(&self, what: &str) -> Result<()> {
        let off = self.off;
        self.budget
            .take(self.part, 2 * std::mem::size_of::<T>() as u64, || {
                format!("the {what}s up to byte {off}")
            })
    }

    /// Records a resource id, refusing one used before in this part.
    fn resource_id(&mut self, id: u32, kind: &str) -> Result<()> {
        if !self.ids.insert(id) {
            return Err(self.err(format!(
                "{kind} id {id} is already the id of another resource (ids must be unique)"
            )));
        }
        Ok(())
    }

    fn attrs<R>(&self, reader: &NsReader<R>, e: &BytesStart) -> Result<Vec<Attr>> {
        let mut v = Vec::new();
        for a in e.attributes() {
            let a = a.map_err(|err| Error::Xml {
                part: self.part.into(),
                offset: self.off,
                source: err.into(),
            })?;
            let (res, local) = reader.resolve_attribute(a.key);
            let ns = if a.key.as_ref().starts_with(b"xmlns") {
                continue;
            } else {
                ns_of(&res)
            };
            let value = a.unescape_value().map_err(|source| Error::Attribute {
                part: self.part.into(),
                offset: self.off,
                source,
            })?;
            v.push(Attr {
                ns,
                name: String::from_utf8_lossy(local.as_ref()).into_owned(),
                value: value.into_owned(),
            });
        }
        Ok(v)
    }

    fn model_start<R>(&mut self, reader: &NsReader<R>, e: &BytesStart) -> Result<()> {
        for a in self.attrs(reader, e)? {
            match (a.ns, a.name.as_str()) {
                (Ns::None, "unit") => {
                    self.model.unit = Unit::from_name(a.value.trim())
                        .ok_or_else(|| self.err(format!("unknown unit \"{}\"", a.value)))?
                }
                (_, "lang") => self.model.language = Some(a.value),
                (Ns::None, "requiredextensions") => {
                    for prefix in a.value.split_ascii_whitespace() {
                        let q = format!("{prefix}:x");
                        let (res, _) = reader.resolve_element(QName(q.as_bytes()));
                        let namespace = match &res {
                            ResolveResult::Bound(n) => {
                                String::from_utf8_lossy(n.as_ref()).into_owned()
                            }
                            _ => "undeclared".to_string(),
                        };
                        if !ns::SUPPORTED.contains(&namespace.as_str()) {
                            return Err(Error::UnsupportedExtension {
                                part: self.part.into(),
                                prefix: prefix.into(),
                                namespace,
                            });
                        }
                    }
                }
                _ => {}
            }
        }
        Ok(())
    }

    fn start<R>(
        &mut self,
        reader: &NsReader<R>,
        parent: Ctx,
        ens: Ns,
        name: &str,
        e: &BytesStart,
    ) -> Result<Ctx> {
        use Ctx::*;
        // Hot elements parse their attributes as bytes, without allocating.
        match (parent, ens, name) {
            (Vertices, Ns::Core, "vertex") => {
                let mut p = [f64::NAN; 3];
                for a in e.attributes().flatten() {
                    let i = match a.key.as_ref() {
                        b"x" => 0,
                        b"y" => 1,
                        b"z" => 2,
                        _ => continue,
                    };
                    let v = std::str::from_utf8(&a.value).unwrap_or("?");
                    p[i] = parse_num(self.part, self.off, "vertex coordinate", v)?;
                }
                if p.iter().any(|c| c.is_nan()) {
                    let n = self.mesh.as_ref().map_or(0, |m| m.vertices.len());
                    return Err(self.err(format!("vertex {n} lacks x, y or z")));
                }
                self.charge::<[f64; 3]>("vertice")?;
                self.mesh.as_mut().expect("inside a mesh").vertices.push(p);
                return Ok(Skip);
            }
            (Triangles, Ns::Core, "triangle") => {
                let mut t = [u32::MAX; 3];
                let mut pr = [u32::MAX; 3];
                let mut pid = None;
                for a in e.attributes().flatten() {
                    let v = std::str::from_utf8(&a.value).unwrap_or("?");
                    match a.key.as_ref() {
                        b"v1" => t[0] = parse_index(self.part, self.off, "v1", v)?,
                        b"v2" => t[1] = parse_index(self.part, self.off, "v2", v)?,
                        b"v3" => t[2] = parse_index(self.part, self.off, "v3", v)?,
                        b"p1" => pr[0] = parse_index(self.part, self.off, "p1", v)?,
                        b"p2" => pr[1] = parse_index(self.part, self.off, "p2", v)?,
                        b"p3" => pr[2] = parse_index(self.part, self.off, "p3", v)?,
                        b"pid" => pid = Some(parse_id(self.part, self.off, "pid", v)?),
                        _ => {}
                    }
                }
                let mesh = self.mesh.as_mut().expect("inside a mesh");
                let n = mesh.vertices.len() as u32;
                let k = mesh.triangles.len();
                if t.iter().any(|&v| v >= n) {
                    return Err(self.err(format!(
                        "triangle {k} has vertex indices {t:?}; the mesh has {n} vertices (or v1, v2, v3 missing)"
                    )));
                }
                if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                    return Err(self.err(format!("triangle {k} repeats a vertex: {t:?}")));
                }
                mesh.triangles.push(t);
                self.charge::<[u32; 6]>("triangle")?;
                // Properties are kept when the whole mesh uses one group.
                if let (Some(pid), true) = (pid, pr[0] != u32::MAX) {
                    let q = [
                        pr[0],
                        if pr[1] == u32::MAX { pr[0] } else { pr[1] },
                        if pr[2] == u32::MAX { pr[0] } else { pr[2] },
                    ];
                    if self.tri_pids.is_none() && k == 0 {
                        self.tri_pids = Some(pid);
                    }
                    if self.tri_pids != Some(pid) {
                        self.tri_props_ok = false;
                    }
                    self.tri_props.push(q);
                } else {
                    self.tri_props_ok = false;
                }
                return Ok(Skip);
            }
            (Beams, Ns::Beam, "beam") => {
                let l = self.lattice.as_ref().expect("inside a lattice");
                let (mut v1, mut v2) = (u32::MAX, u32::MAX);
                let (mut r1, mut r2) = (None, None);
                let (mut c1, mut c2) = (None, None);
                for a in e.attributes().flatten() {
                    let v = std::str::from_utf8(&a.value).unwrap_or("?");
                    match a.key.as_ref() {
                        b"v1" => v1 = parse_index(self.part, self.off, "v1", v)?,
                        b"v2" => v2 = parse_index(self.part, self.off, "v2", v)?,
                        b"r1" => r1 = Some(parse_num(self.part, self.off, "r1", v)?),
                        b"r2" => r2 = Some(parse_num(self.part, self.off, "r2", v)?),
                        b"cap1" => {
                            c1 = Some(
                                Cap::from_name(v)
                                    .ok_or_else(|| self.err(format!("unknown cap \"{v}\"")))?,
                            )
                        }
                        b"cap2" => {
                            c2 = Some(
                                Cap::from_name(v)
                                    .ok_or_else(|| self.err(format!("unknown cap \"{v}\"")))?,
                            )
                        }
                        _ => {}
                    }
                }
                let n = self.mesh.as_ref().expect("inside a mesh").vertices.len() as u32;
                let k = l.beams.len();
                if v1 >= n || v2 >= n || v1 == v2 {
                    return Err(self.err(format!(
                        "beam {k} ({v1}, {v2}) needs two distinct vertex indices below {n}"
                    )));
                }
                if r2.is_some() && r1.is_none() {
                    return Err(self.err(format!("beam {k} has r2 without r1")));
                }
                let r1v = r1.unwrap_or(l.radius);
                let r2v = r2.unwrap_or(r1v);
                if !(r1v > 0.0 && r2v > 0.0) {
                    return Err(self.err(format!("beam {k}: radii must be positive")));
                }
                self.charge::<Beam>("beam")?;
                self.lattice.as_mut().unwrap().beams.push(Beam {
                    v1,
                    v2,
                    r1: r1v,
                    r2: r2v,
                    cap1: c1,
                    cap2: c2,
                });
                return Ok(Skip);
            }
            (ColorGroup, Ns::Material, "color") => {
                let mut c = None;
                for a in e.attributes().flatten() {
                    if a.key.as_ref() == b"color" {
                        let v = std::str::from_utf8(&a.value).unwrap_or("?");
                        c = Some(parse_colour(self.part, self.off, v)?);
                    }
                }
                let g = self.model.color_groups.last_mut().expect("inside a group");
                let c = c.ok_or_else(|| {
                    invalid(
                        self.part,
                        self.off,
                        format!(
                            "colour {} of colorgroup {} lacks color",
                            g.colors.len(),
                            g.id
                        ),
                    )
                })?;
                g.colors.push(c);
                self.charge::<[u8; 4]>("colour")?;
                return Ok(Skip);
            }
            (SliceVertices, Ns::Slice, "vertex") => {
                let mut p = [f64::NAN; 2];
                for a in e.attributes().flatten() {
                    let i = match a.key.as_ref() {
                        b"x" => 0,
                        b"y" => 1,
                        _ => continue,
                    };
                    let v = std::str::from_utf8(&a.value).unwrap_or("?");
                    p[i] = parse_num(self.part, self.off, "slice vertex coordinate", v)?;
                }
                if p.iter().any(|c| c.is_nan()) {
                    return Err(self.err("slice vertex lacks x or y"));
                }
                self.charge::<[f64; 2]>("slice vertice")?;
                self.slice_vertices.push(p);
                return Ok(Skip);
            }
            (Polygon, Ns::Slice, "segment") => {
                let mut v2 = u32::MAX;
                for a in e.attributes().flatten() {
                    if a.key.as_ref() == b"v2" {
                        let v = std::str::from_utf8(&a.value).unwrap_or("?");
                        v2 = parse_index(self.part, self.off, "v2", v)?;
                    }
                }
                if v2 as usize >= self.slice_vertices.len() {
                    return Err(self.err(format!(
                        "segment v2 = {v2} is not below the slice's {} vertices",
                        self.slice_vertices.len()
                    )));
                }
                self.charge::<[f64; 3]>("polygon segment")?;
                self.polygon.as_mut().expect("inside a polygon").1.push(v2);
                return Ok(Skip);
            }
            _ => {}
        }
        let attrs = self.attrs(reader, e)?;
        let get = |n: &str| {
            attrs
                .iter()
                .find(|a| a.ns == Ns::None && a.name == n)
                .map(|a| a.value.as_str())
        };
        let get_ns = |ns: Ns, n: &str| {
            attrs
                .iter()
                .find(|a| a.ns == ns && a.name == n)
                .map(|a| a.value.as_str())
        };
        let (part, off) = (self.part, self.off);
        let need = |n: &str| {
            get(n).ok_or_else(|| invalid(part, off, format!("<{name}> lacks the attribute {n}")))
        };
        if attrs
            .iter()
            .any(|a| a.ns == Ns::Production && a.name == "path")
        {
            return Err(self.err(
                "p:path (objects in other model parts, production extension) is not supported",
            ));
        }
        let ctx = match (parent, ens, name) {
            (Model, Ns::Core, "metadata") => {
                self.metadata_name = Some(need("name")?.to_string());
                self.text.clear();
                Metadata
            }
            (Model, Ns::Core, "resources") => Resources,
            (Model, Ns::Core, "build") => Build,
            (Build, Ns::Core, "item") => {
                let object = parse_id(part, off, "objectid", need("objectid")?)?;
                let transform = match get("transform") {
                    Some(t) => parse_transform(part, off, t)?,
                    None => Transform::IDENTITY,
                };
                self.charge::<BuildItem>("build item")?;
                self.model.build.push(BuildItem {
                    object,
                    transform,
                    part_number: get("partnumber").map(str::to_string),
                });
                Skip
            }
            (Resources, Ns::Core, "basematerials") => {
                let id = parse_id(part, off, "id", need("id")?)?;
                self.resource_id(id, "basematerials")?;
                self.model.base_materials.push(crate::model::BaseMaterials {
                    id,
                    bases: Vec::new(),
                });
                BaseMaterials
            }
            (BaseMaterials, Ns::Core, "base") => {
                let c = need("displaycolor")?;
                let hex = c.trim().trim_start_matches('#');
                let byte = |i: usize| u8::from_str_radix(hex.get(i..i + 2).unwrap_or("zz"), 16);
                let color = match (hex.len(), byte(0), byte(2), byte(4)) {
                    (6 | 8, Ok(r), Ok(g), Ok(b)) => [
                        r,
                        g,
                        b,
                        if hex.len() == 8 {
                            byte(6).map_err(|_| self.err("bad displaycolor"))?
                        } else {
                            255
                        },
                    ],
                    _ => {
                        return Err(
                            self.err(format!("displaycolor \"{c}\" is not #RRGGBB or #RRGGBBAA"))
                        )
                    }
                };
                let name = need("name")?.to_string();
                self.model
                    .base_materials
                    .last_mut()
                    .unwrap()
                    .bases
                    .push(Base { name, color });
                Skip
            }
            (Resources, Ns::Material, "compositematerials") => {
                let id = parse_id(part, off, "id", need("id")?)?;
                self.resource_id(id, "compositematerials")?;
                let matid = parse_id(part, off, "matid", need("matid")?)?;
                let idx = need("matindices")?
                    .split_ascii_whitespace()
                    .map(|v| parse_index(part, off, "matindices", v))
                    .collect::<Result<Vec<_>>>()?;
                self.model
                    .composite_materials
                    .push(crate::model::CompositeMaterials {
                        id,
                        base_materials: matid,
                        material_indices: idx,
                        composites: Vec::new(),
                    });
                CompositeMaterials
            }
            (CompositeMaterials, Ns::Material, "composite") => {
                let v = need("values")?
                    .split_ascii_whitespace()
                    .map(|v| parse_num(part, off, "composite value", v))
                    .collect::<Result<Vec<_>>>()?;
                self.model
                    .composite_materials
                    .last_mut()
                    .unwrap()
                    .composites
                    .push(v);
                Skip
            }
            (Resources, Ns::Material, "colorgroup") => {
                let id = parse_id(part, off, "id", need("id")?)?;
                self.resource_id(id, "colorgroup")?;
                self.model.color_groups.push(crate::model::ColorGroup {
                    id,
                    colors: Vec::new(),
                });
                ColorGroup
            }
            (Resources, Ns::Core, "object") => {
                let id = parse_id(part, off, "id", need("id")?)?;
                self.resource_id(id, "object")?;
                let kind = match get("type") {
                    Some(t) => ObjectType::from_name(t.trim())
                        .ok_or_else(|| self.err(format!("unknown object type \"{t}\"")))?,
                    None => ObjectType::Model,
                };
                let property = match (get("pid"), get("pindex")) {
                    (Some(a), b) => Some((
                        parse_id(part, off, "pid", a)?,
                        parse_index(part, off, "pindex", b.unwrap_or("0"))?,
                    )),
                    _ => None,
                };
                let slice_stack = get_ns(Ns::Slice, "slicestackid")
                    .map(|v| parse_id(part, off, "s:slicestackid", v))
                    .transpose()?;
                if get_ns(Ns::Slice, "slicepath").is_some() {
                    return Err(self.err("s:slicepath on an object (slices of another part) is not supported; use <s:sliceref>"));
                }
                let mesh_resolution = match get_ns(Ns::Slice, "meshresolution") {
                    Some("lowres") => MeshResolution::Low,
                    Some("fullres") | None => MeshResolution::Full,
                    Some(v) => return Err(self.err(format!("unknown s:meshresolution \"{v}\""))),
                };
                self.object = Some(crate::model::Object {
                    id,
                    name: get("name").map(str::to_string),
                    part_number: get("partnumber").map(str::to_string),
                    kind,
                    property,
                    content: ObjectContent::Components(Vec::new()),
                    slice_stack,
                    mesh_resolution,
                });
                Object
            }
            (Object, Ns::Core, "mesh") => {
                let volume_id = get_ns(Ns::Volumetric, "volumeid")
                    .map(|v| parse_id(part, off, "v:volumeid", v))
                    .transpose()?;
                self.mesh = Some(crate::model::Mesh {
                    volume_id,
                    ..Default::default()
                });
                self.tri_pids = None;
                self.tri_props.clear();
                self.tri_props_ok = true;
                Mesh
            }
            (Object, Ns::Core, "components") => {
                self.components.clear();
                Components
            }
            (Components, Ns::Core, "component") => {
                let object = parse_id(part, off, "objectid", need("objectid")?)?;
                let transform = match get("transform") {
                    Some(t) => parse_transform(part, off, t)?,
                    None => Transform::IDENTITY,
                };
                self.charge::<Component>("component")?;
                self.components.push(Component { object, transform });
                Skip
            }
            (Object, Ns::Volumetric, "levelset") => {
                let ls = ObjectContent::LevelSet(LevelSet {
                    function: parse_id(part, off, "functionid", need("functionid")?)?,
                    channel: need("channel")?.to_string(),
                    transform: get("transform")
                        .map(|t| parse_transform(part, off, t))
                        .transpose()?
                        .unwrap_or_default(),
                    min_feature_size: get("minfeaturesize")
                        .map(|v| parse_num(part, off, "minfeaturesize", v))
                        .transpose()?
                        .unwrap_or(0.0),
                    fallback: get("fallbackvalue")
                        .map(|v| parse_num(part, off, "fallbackvalue", v))
                        .transpose()?
                        .unwrap_or(0.0),
                    mesh: parse_id(part, off, "meshid", need("meshid")?)?,
                    mesh_bbox_only: get("meshbboxonly")
                        .map(|v| parse_bool(part, off, "meshbboxonly", v))
                        .transpose()?
                        .unwrap_or(false),
                    volume_id: get("volumeid")
                        .map(|v| parse_id(part, off, "volumeid", v))
                        .transpose()?,
                });
                self.object.as_mut().unwrap().content = ls;
                Skip
            }
            (Mesh, Ns::Core, "vertices") => Vertices,
            (Mesh, Ns::Core, "triangles") => Triangles,
            (Mesh, Ns::Beam, "beamlattice") => {
                let pos = |n: &str, v: &str| -> Result<f64> {
                    let x = parse_num(part, off, n, v)?;
                    if x > 0.0 {
                        Ok(x)
                    } else {
                        Err(invalid(part, off, format!("{n} must be positive")))
                    }
                };
                let mut l = BeamLattice::new(
                    pos("radius", need("radius")?)?,
                    pos("minlength", need("minlength")?)?,
                );
                if let Some(c) = get("cap") {
                    l.cap = Cap::from_name(c.trim())
                        .ok_or_else(|| self.err(format!("unknown cap \"{c}\"")))?;
                }
                // Balls attributes: the 1.2 namespace, or unprefixed (1.1 drafts).
                let bm = get_ns(Ns::Balls, "ballmode").or(get("ballmode"));
                if let Some(m) = bm {
                    l.ball_mode = BallMode::from_name(m.trim())
                        .ok_or_else(|| self.err(format!("unknown ballmode \"{m}\"")))?;
                }
                if let Some(r) = get_ns(Ns::Balls, "ballradius").or(get("ballradius")) {
                    l.ball_radius = Some(pos("ballradius", r)?);
                }
                if l.ball_mode != BallMode::None && l.ball_radius.is_none() {
                    return Err(self.err("ballmode other than none needs a ballradius"));
                }
                let cm = get("clippingmode").unwrap_or("none");
                let mode = ClipMode::from_name(cm.trim())
                    .ok_or_else(|| self.err(format!("unknown clippingmode \"{cm}\"")))?;
                match (mode, get("clippingmesh")) {
                    (ClipMode::None, _) => {}
                    (m, Some(id)) => {
                        l.clipping = Some((m, parse_id(part, off, "clippingmesh", id)?))
                    }
                    (_, None) => return Err(self.err("clippingmode needs a clippingmesh")),
                }
                l.representation = get("representationmesh")
                    .map(|v| parse_id(part, off, "representationmesh", v))
                    .transpose()?;
                self.lattice = Some(l);
                Lattice
            }
            (Lattice, Ns::Beam, "beams") => Beams,
            (Lattice, Ns::Balls | Ns::Beam, "balls") => Balls,
            (Balls, Ns::Balls | Ns::Beam, "ball") => {
                let vindex = parse_index(part, off, "vindex", need("vindex")?)?;
                let n = self.mesh.as_ref().unwrap().vertices.len() as u32;
                if vindex >= n {
                    return Err(self.err(format!(
                        "ball vindex {vindex} is not below the {n} vertices"
                    )));
                }
                let r = get("r").map(|v| parse_num(part, off, "r", v)).transpose()?;
                self.charge::<Ball>("ball")?;
                self.lattice
                    .as_mut()
                    .unwrap()
                    .balls
                    .push(Ball { vindex, r });
                Skip
            }
            (Lattice, Ns::Beam, "beamsets") => BeamSets,
            (BeamSets, Ns::Beam, "beamset") => {
                self.beamset = Some(crate::beam::BeamSet {
                    name: get("name").map(str::to_string),
                    identifier: get("identifier").map(str::to_string),
                    beams: Vec::new(),
                    balls: Vec::new(),
                });
                BeamSet
            }
            (BeamSet, Ns::Beam, "ref") => {
                let i = parse_index(part, off, "index", need("index")?)?;
                self.charge::<u32>("beam reference")?;
                self.beamset.as_mut().unwrap().beams.push(i);
                Skip
            }
            (BeamSet, Ns::Balls | Ns::Beam, "ballref") => {
                let i = parse_index(part, off, "index", need("index")?)?;
                self.charge::<u32>("ball reference")?;
                self.beamset.as_mut().unwrap().balls.push(i);
                Skip
            }
            (Resources, Ns::Slice, "slicestack") => {
                let id = parse_id(part, off, "id", need("id")?)?;
                self.resource_id(id, "slicestack")?;
                let zbottom = get("zbottom")
                    .map(|v| parse_num(part, off, "zbottom", v))
                    .transpose()?
                    .unwrap_or(0.0);
                self.stack = Some(crate::slice::SliceStack {
                    id,
                    zbottom,
                    slices: Vec::new(),
                });
                self.stack_refs.clear();
                SliceStack
            }
            (SliceStack, Ns::Slice, "slice") => {
                let ztop = parse_num(part, off, "ztop", need("ztop")?)?;
                let st = self.stack.as_ref().unwrap();
                let below = st.slices.last().map(|s| s.ztop).unwrap_or(st.zbottom);
                if ztop.partial_cmp(&below) != Some(std::cmp::Ordering::Greater) {
                    return Err(self.err(format!(
                        "slice ztop {ztop} does not increase (previous {below})"
                    )));
                }
                if !self.stack_refs.is_empty() {
                    return Err(self.err("a slicestack must not mix <slice> and <sliceref>"));
                }
                self.slice = Some(crate::slice::Slice {
                    ztop,
                    polygons: Vec::new(),
                });
                self.slice_vertices.clear();
                Slice
            }
            (SliceStack, Ns::Slice, "sliceref") => {
                let id = parse_id(part, off, "slicestackid", need("slicestackid")?)?;
                let path = need("slicepath")?.to_string();
                if !self.stack.as_ref().unwrap().slices.is_empty() {
                    return Err(self.err("a slicestack must not mix <slice> and <sliceref>"));
                }
                self.stack_refs.push((id, path, off));
                Skip
            }
            (Slice, Ns::Slice, "vertices") => SliceVertices,
            (Slice, Ns::Slice, "polygon") => {
                let s = parse_index(part, off, "startv", need("startv")?)?;
                if s as usize >= self.slice_vertices.len() {
                    return Err(self.err(format!(
                        "polygon startv {s} is not below the {} vertices",
                        self.slice_vertices.len()
                    )));
                }
                self.polygon = Some((s, Vec::new()));
                Polygon
            }
            (Resources, Ns::Volumetric, "image3d") => {
                let id = parse_id(part, off, "id", need("id")?)?;
                self.resource_id(id, "image3d")?;
                self.image = Some(crate::volumetric::Image3D {
                    id,
                    name: get("name").map(str::to_string),
                    dims: [0; 3],
                    layout: PixelLayout::Y,
                    bit_depth: 8,
                    samples: Vec::new(),
                    sheet_paths: Vec::new(),
                });
                Image3D
            }
            (Image3D, Ns::Volumetric, "imagestack") => {
                let n = |k: &str| -> Result<usize> {
                    need(k)?
                        .trim()
                        .parse::<usize>()
                        .ok()
                        .filter(|&v| v > 0)
                        .ok_or_else(|| {
                            invalid(part, off, format!("{k} must be a positive integer"))
                        })
                };
                let dims = [n("columncount")?, n("rowcount")?, n("sheetcount")?];
                check_dims(dims, PixelLayout::Y, 8).map_err(|m| Error::TooLarge {
                    part: part.into(),
                    message: m,
                })?;
                self.image.as_mut().unwrap().dims = dims;
                ImageStack
            }
            (ImageStack, Ns::Volumetric, "imagesheet") => {
                let p = need("path")?.to_string();
                self.image.as_mut().unwrap().sheet_paths.push(p);
                Skip
            }
            (Resources, Ns::Volumetric, "functionfromimage3d") => {
                let id = parse_id(part, off, "id", need("id")?)?;
                self.resource_id(id, "functionfromimage3d")?;
                let tile = |k: &str| -> Result<TileStyle> {
                    match get(k) {
                        None => Ok(TileStyle::Wrap),
                        Some(v) => TileStyle::from_name(v.trim())
                            .ok_or_else(|| invalid(part, off, format!("unknown {k} \"{v}\""))),
                    }
                };
                self.model.image_functions.push(FunctionFromImage3D {
                    id,
                    display_name: get("displayname").map(str::to_string),
                    image: parse_id(part, off, "image3did", need("image3did")?)?,
                    filter: match get("filter").map(str::trim) {
                        None | Some("linear") => Filter::Linear,
                        Some("nearest") => Filter::Nearest,
                        Some(v) => return Err(self.err(format!("unknown filter \"{v}\""))),
                    },
                    value_offset: get("valueoffset")
                        .map(|v| parse_num(part, off, "valueoffset", v))
                        .transpose()?
                        .unwrap_or(0.0),
                    value_scale: get("valuescale")
                        .map(|v| parse_num(part, off, "valuescale", v))
                        .transpose()?
                        .unwrap_or(1.0),
                    tile: [
                        tile("tilestyleu")?,
                        tile("tilestylev")?,
                        tile("tilestylew")?,
                    ],
                });
                Skip
            }
            (Resources, Ns::Volumetric, "volumedata") => {
                let id = parse_id(part, off, "id", need("id")?)?;
                self.resource_id(id, "volumedata")?;
                self.volume = Some(crate::volumetric::VolumeData {
                    id,
                    ..Default::default()
                });
                VolumeData
            }
            (VolumeData, Ns::Volumetric, "composite") => {
                self.composite = Some(crate::volumetric::Composite {
                    base_materials: parse_id(part, off, "basematerialid", need("basematerialid")?)?,
                    mappings: Vec::new(),
                });
                Composite
            }
            (Composite, Ns::Volumetric, "materialmapping") => {
                let r = self.fref(&attrs)?;
                self.composite.as_mut().unwrap().mappings.push(r);
                Skip
            }
            (VolumeData, Ns::Volumetric, "color") => {
                let r = self.fref(&attrs)?;
                self.volume.as_mut().unwrap().color = Some(r);
                Skip
            }
            (VolumeData, Ns::Volumetric, "property") => {
                let r = self.fref(&attrs)?;
                let p = Property {
                    name: need("name")?.to_string(),
                    required: get("required")
                        .map(|v| parse_bool(part, off, "required", v))
                        .transpose()?
                        .unwrap_or(false),
                    value: r,
                };
                self.volume.as_mut().unwrap().properties.push(p);
                Skip
            }
            (Resources, Ns::Implicit, "implicitfunction") => {
                let id = parse_id(part, off, "id", need("id")?)?;
                self.resource_id(id, "implicitfunction")?;
                self.function = Some(ImplicitFunction {
                    id,
                    display_name: get("displayname").map(str::to_string),
                    inputs: Vec::new(),
                    graph: ImplicitGraph::default(),
                    outputs: Vec::new(),
                });
                Implicit
            }
            (Implicit, Ns::Implicit, "in") => FnIn,
            (Implicit, Ns::Implicit, "out") => FnOut,
            (FnIn, Ns::Implicit, t) => {
                let kind = PortType::from_name(t)
                    .ok_or_else(|| self.err(format!("unknown function input type <{t}>")))?;
                let id = need("identifier")?.to_string();
                self.function.as_mut().unwrap().inputs.push((id, kind));
                Skip
            }
            (FnOut, Ns::Implicit, t) => {
                let kind = PortType::from_ref_name(t)
                    .ok_or_else(|| self.err(format!("unknown function output <{t}>")))?;
                let o = FunctionOutput {
                    name: need("identifier")?.to_string(),
                    kind,
                    source: need("ref")?.to_string(),
                };
                self.function.as_mut().unwrap().outputs.push(o);
                Skip
            }
            (Implicit, Ns::Implicit, op) => {
                if crate::implicit::node_spec(op).is_none() {
                    return Err(self.err(format!("unknown implicit node <{op}>")));
                }
                let value = match op {
                    "constant" => {
                        NodeValue::Scalar(parse_double(part, off, "value", need("value")?)?)
                    }
                    "constvec" => NodeValue::Vector([
                        parse_double(part, off, "x", need("x")?)?,
                        parse_double(part, off, "y", need("y")?)?,
                        parse_double(part, off, "z", need("z")?)?,
                    ]),
                    "constmat" => {
                        let v: Vec<f64> = need("matrix")?
                            .split_ascii_whitespace()
                            .map(|x| parse_double(part, off, "matrix", x))
                            .collect::<Result<_>>()?;
                        let m: [f64; 16] = v
                            .try_into()
                            .map_err(|_| self.err("constmat needs 16 numbers"))?;
                        NodeValue::Matrix(m)
                    }
                    "constresourceid" => {
                        NodeValue::Resource(parse_id(part, off, "value", need("value")?)?)
                    }
                    _ => NodeValue::None,
                };
                self.node = Some(ImplicitNode {
                    id: need("identifier")?.to_string(),
                    op: op.to_string(),
                    value,
                    inputs: Vec::new(),
                    outputs: Vec::new(),
                });
                Node
            }
            (Node, Ns::Implicit, "in") => NodeIn,
            (Node, Ns::Implicit, "out") => NodeOut,
            (NodeIn, Ns::Implicit, t) => {
                let kind = PortType::from_ref_name(t)
                    .ok_or_else(|| self.err(format!("unknown node input <{t}>")))?;
                let i = NodeInput {
                    port: need("identifier")?.to_string(),
                    source: need("ref")?.to_string(),
                    kind,
                };
                self.node.as_mut().unwrap().inputs.push(i);
                Skip
            }
            (NodeOut, Ns::Implicit, t) => {
                let kind = PortType::from_name(t)
                    .ok_or_else(|| self.err(format!("unknown node output <{t}>")))?;
                let id = need("identifier")?.to_string();
                self.node.as_mut().unwrap().outputs.push((id, kind));
                Skip
            }
            (_, Ns::Core, _) if parent != Skip => {
                return Err(self.err(format!("unexpected core element <{name}> here")));
            }
            // Other namespaces: extension points, ignored (required ones were
            // rejected at <model>).
            _ => Skip,
        };
        Ok(ctx)
    }

    fn fref(&self, attrs: &[Attr]) -> Result<FunctionRef> {
        let (part, off) = (self.part, self.off);
        let get = |n: &str| {
            attrs
                .iter()
                .find(|a| a.ns == Ns::None && a.name == n)
                .map(|a| a.value.as_str())
        };
        let need =
            |n: &str| get(n).ok_or_else(|| invalid(part, off, format!("lacks the attribute {n}")));
        Ok(FunctionRef {
            function: parse_id(part, off, "functionid", need("functionid")?)?,
            channel: need("channel")?.to_string(),
            transform: get("transform")
                .map(|t| parse_transform(part, off, t))
                .transpose()?
                .unwrap_or_default(),
            min_feature_size: get("minfeaturesize")
                .map(|v| parse_num(part, off, "minfeaturesize", v))
                .transpose()?
                .unwrap_or(0.0),
            fallback: get("fallbackvalue")
                .map(|v| parse_num(part, off, "fallbackvalue", v))
                .transpose()?
                .unwrap_or(0.0),
        })
    }

    fn end(&mut self, ctx: Ctx) -> Result<()> {
        use Ctx::*;
        match ctx {
            Metadata => {
                let name = self.metadata_name.take().unwrap_or_default();
                let value = std::mem::take(&mut self.text);
                self.model
                    .metadata
                    .push(crate::model::Metadata { name, value });
            }
            Mesh => {
                let mut mesh = self.mesh.take().unwrap();
                mesh.beam_lattice = self.lattice.take();
                if self.tri_props_ok
                    && !mesh.triangles.is_empty()
                    && self.tri_props.len() == mesh.triangles.len()
                {
                    mesh.properties = Some(TriangleProperties {
                        pid: self.tri_pids.unwrap(),
                        indices: std::mem::take(&mut self.tri_props),
                    });
                }
                self.object.as_mut().unwrap().content = ObjectContent::Mesh(mesh);
            }
            ColorGroup => {
                let g = self.model.color_groups.last().expect("just read");
                if g.colors.is_empty() {
                    return Err(self.err(format!("colorgroup {} has no colour", g.id)));
                }
            }
            Components => {
                if self.components.is_empty() {
                    return Err(self.err("<components> without a component"));
                }
                self.object.as_mut().unwrap().content =
                    ObjectContent::Components(std::mem::take(&mut self.components));
            }
            Object => {
                let o = self.object.take().unwrap();
                if matches!(&o.content, ObjectContent::Components(c) if c.is_empty()) {
                    return Err(
                        self.err(format!("object {} has neither a mesh nor components", o.id))
                    );
                }
                self.model.objects.push(o);
            }
            BeamSet => {
                let s = self.beamset.take().unwrap();
                self.lattice.as_mut().unwrap().beam_sets.push(s);
            }
            Polygon => {
                let (start, segs) = self.polygon.take().unwrap();
                if segs.last() != Some(&start) {
                    return Err(self.err("open polygon: its last segment must end at startv (open polygons, for support, are not supported)"));
                }
                let mut poly = Vec::with_capacity(segs.len());
                poly.push(self.slice_vertices[start as usize]);
                for &v in &segs[..segs.len() - 1] {
                    poly.push(self.slice_vertices[v as usize]);
                }
                self.slice.as_mut().unwrap().polygons.push(poly);
            }
            Slice => {
                let s = self.slice.take().unwrap();
                self.stack.as_mut().unwrap().slices.push(s);
            }
            SliceStack => {
                let st = self.stack.take().unwrap();
                if !self.stack_refs.is_empty() {
                    self.refs
                        .slice_refs
                        .push((st.id, std::mem::take(&mut self.stack_refs)));
                }
                self.model.slice_stacks.push(st);
            }
            Image3D => {
                let im = self.image.take().unwrap();
                if im.sheet_paths.len() != im.dims[2] {
                    return Err(self.err(format!(
                        "image3d {}: sheetcount {} but {} imagesheets",
                        im.id,
                        im.dims[2],
                        im.sheet_paths.len()
                    )));
                }
                self.model.images.push(im);
            }
            Composite => {
                let c = self.composite.take().unwrap();
                self.volume.as_mut().unwrap().composite = Some(c);
            }
            VolumeData => {
                let v = self.volume.take().unwrap();
                self.model.volume_data.push(v);
            }
            Node => {
                let n = self.node.take().unwrap();
                self.function.as_mut().unwrap().graph.nodes.push(n);
            }
            Implicit => {
                let f = self.function.take().unwrap();
                f.validate()
                    .map_err(|m| self.err(format!("implicitfunction {}: {m}", f.id)))?;
                self.model.implicit_functions.push(f);
            }
            _ => {}
        }
        Ok(())
    }
}

/// References between resources, checked after the whole model is read.
fn check_references(m: &Model, part: &str) -> Result<()> {
    let objects: HashMap<u32, &crate::model::Object> =
        m.objects.iter().map(|o| (o.id, o)).collect();
    let e = |msg: String| invalid(part, 0, msg);
    for o in &m.objects {
        if let ObjectContent::Components(cs) = &o.content {
            for c in cs {
                if !objects.contains_key(&c.object) {
                    return Err(e(format!(
                        "object {}: component references missing object {}",
                        o.id, c.object
                    )));
                }
            }
        }
        if let ObjectContent::Mesh(me) = &o.content {
            if let Some(l) = &me.beam_lattice {
                for r in l.clipping.map(|c| c.1).into_iter().chain(l.representation) {
                    if !matches!(
                        objects.get(&r).map(|x| &x.content),
                        Some(ObjectContent::Mesh(_))
                    ) {
                        return Err(e(format!(
                            "object {}: lattice references {r}, which is not a mesh object",
                            o.id
                        )));
                    }
                }
            }
        }
        if let Some(s) = o.slice_stack {
            if !m.slice_stacks.iter().any(|st| st.id == s) {
                return Err(e(format!("object {}: missing slicestack {s}", o.id)));
            }
        }
    }
    for it in &m.build {
        if !objects.contains_key(&it.object) {
            return Err(e(format!(
                "build item references missing object {}",
                it.object
            )));
        }
    }
    Ok(())
}
