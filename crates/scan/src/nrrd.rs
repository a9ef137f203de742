//! NRRD reader: attached (`.nrrd`) and detached (`.nhdr` + data files)
//! data, `raw`, `gzip` and `text` encodings, both byte orders, geometry from
//! `space directions` / `space origin` or `spacings` / `axis mins`.
//!
//! The header is parsed here (it is a few lines of text); the data is
//! streamed slice by slice into the volume, so only the volume and one
//! slice are in memory.

use crate::error::{header, io_at, Result, ScanError};
use crate::volume::{
    push_bytes, read_full, stream_slices, Assembler, FileType, Geometry, Progress, ReadOptions,
    Volume,
};
use flate2::read::MultiGzDecoder;
use std::fs::File;
use std::io::{BufRead, BufReader, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

/// Longest header we read before deciding the file is not NRRD.
const MAX_HEADER: usize = 1 << 20;

#[derive(Clone, Copy, Debug, PartialEq)]
enum Encoding {
    Raw,
    Gzip,
    Text,
}

/// What the header says.
struct Header {
    ty: Option<FileType>,
    dimension: Option<usize>,
    sizes: Option<Vec<usize>>,
    little: Option<bool>,
    encoding: Option<Encoding>,
    space: Option<String>,
    directions: Option<Vec<Option<[f64; 3]>>>,
    origin: Option<[f64; 3]>,
    spacings: Option<Vec<f64>>,
    axis_mins: Option<Vec<f64>>,
    units_scale: f64,
    data_files: Vec<PathBuf>,
    line_skip: usize,
    byte_skip: i64,
    /// Bytes of the header including its closing blank line.
    length: u64,
    /// The header line each field was on, for messages.
    lines: std::collections::HashMap<&'static str, usize>,
}

/// Reads an NRRD file (`.nrrd` or `.nhdr`).
pub fn read_nrrd(path: &Path, opts: &ReadOptions, progress: Progress) -> Result<Volume> {
    let f = File::open(path).map_err(io_at(path))?;
    let mut r = BufReader::new(f);
    let h = parse_header(path, &mut r)?;
    let at = |k: &str| format!("line {}", h.lines.get(k).copied().unwrap_or(1));
    let ty =
        h.ty.ok_or_else(|| header(path, "header", "missing required field `type`"))?;
    let dim = h
        .dimension
        .ok_or_else(|| header(path, "header", "missing required field `dimension`"))?;
    if dim != 3 {
        return Err(header(
            path,
            at("dimension"),
            format!("dimension {dim}: only 3D volumes are read (expected 3)"),
        ));
    }
    let sizes = h
        .sizes
        .clone()
        .ok_or_else(|| header(path, "header", "missing required field `sizes`"))?;
    if sizes.len() != 3 {
        return Err(header(
            path,
            at("sizes"),
            format!("`sizes` has {} values, dimension is 3", sizes.len()),
        ));
    }
    let dims = [sizes[0], sizes[1], sizes[2]];
    let encoding = h
        .encoding
        .ok_or_else(|| header(path, "header", "missing required field `encoding`"))?;
    let little = match (h.little, ty.size(), encoding) {
        (Some(l), _, _) => l,
        (None, 1, _) | (None, _, Encoding::Text) => true,
        (None, _, _) => {
            return Err(header(
                path,
                "header",
                "missing field `endian` (required for multi-byte samples)",
            ))
        }
    };
    let geometry = geometry(path, &h)?;
    let frame = h.space.clone().unwrap_or_else(|| "unknown".into());
    let plane = dims[0].saturating_mul(dims[1]).saturating_mul(ty.size()) as u64;
    let mut asm = Assembler::new(
        path,
        dims,
        ty,
        geometry,
        (1.0, 0.0),
        true,
        plane * 2,
        &frame,
        opts,
    )?;
    let total = dims.iter().map(|&d| d as u64).product::<u64>() * ty.size() as u64;

    // The data stream: after the header, or the data files in turn.
    let attached = h.data_files.is_empty();
    let sources: Vec<PathBuf> = if attached {
        vec![path.to_path_buf()]
    } else {
        h.data_files.clone()
    };
    for src in &sources {
        asm.add_file(src);
    }
    if encoding == Encoding::Text {
        return read_text(path, &h, &sources, attached, r, asm, ty, opts);
    }
    if sources.len() == 1 {
        let src = &sources[0];
        let rest: Option<Box<dyn BufRead>> = if attached { Some(Box::new(r)) } else { None };
        let (mut stream, offset) = open_data(path, src, rest, &h, encoding, total)?;
        stream_slices(&mut asm, &mut *stream, ty, little, src, offset, progress)?;
        // Bytes left over mean the sizes do not describe the file.
        if encoding == Encoding::Raw && h.byte_skip >= 0 {
            let mut extra = [0u8; 1];
            if asm.wants(dims[2] - 1)
                && read_full(&mut *stream, &mut extra).map_err(io_at(src))? > 0
            {
                let len = std::fs::metadata(src).map_err(io_at(src))?.len();
                return Err(ScanError::SizeMismatch {
                    path: src.clone(),
                    what: format!("bytes of voxel data after byte offset {offset}"),
                    expected: total,
                    found: len.saturating_sub(offset),
                });
            }
        }
        return asm.finish();
    }
    // Several data files, each holding whole slices.
    if dims[2] % sources.len() != 0 {
        return Err(header(
            path,
            at("data file"),
            format!(
                "{} data files do not split {} slices evenly",
                sources.len(),
                dims[2]
            ),
        ));
    }
    let per = dims[2] / sources.len();
    let mut buf = vec![0u8; plane as usize];
    let mut z = 0;
    for src in &sources {
        let (mut stream, offset) = open_data(path, src, None, &h, encoding, per as u64 * plane)?;
        for s in 0..per {
            let got = read_full(&mut *stream, &mut buf).map_err(io_at(src))?;
            if got < buf.len() {
                return Err(ScanError::Truncated {
                    path: src.clone(),
                    offset,
                    expected: per as u64 * plane,
                    found: s as u64 * plane + got as u64,
                });
            }
            push_bytes(&mut asm, z, &buf, ty, little, (1.0, 0.0))?;
            z += 1;
            progress(z as u64, dims[2] as u64);
        }
    }
    asm.finish()
}

/// Where a field is in the header (`line 7`), for errors.
fn field_line(h: &Header, field: &str) -> String {
    format!("line {}", h.lines.get(field).copied().unwrap_or(1))
}

/// The size of a detached data file, which must be a regular file: a
/// device or a pipe has no size to check against the header, and skipping
/// or reading it may never end.
fn regular_len(hdr_path: &Path, h: &Header, src: &Path, f: &File) -> Result<u64> {
    let m = f.metadata().map_err(io_at(src))?;
    if !m.is_file() {
        return Err(header(
            hdr_path,
            field_line(h, "data file"),
            format!(
                "{} is not a regular file (a device, a pipe or a folder); copy the voxel data \
                 into a file and name that",
                src.display()
            ),
        ));
    }
    Ok(m.len())
}

/// A byte skip must lie inside the data: within the file for raw data, and
/// within the most its compressed bytes can expand to for gzip (deflate
/// expands at most 1032-fold), so that skipping is bounded by the file.
fn check_byte_skip(hdr_path: &Path, h: &Header, encoding: Encoding, len: u64) -> Result<()> {
    if h.byte_skip <= 0 {
        return Ok(());
    }
    let skip = h.byte_skip as u64;
    let room = match encoding {
        Encoding::Gzip => len.saturating_mul(1032),
        _ => len,
    };
    if skip > room {
        return Err(header(
            hdr_path,
            field_line(h, "byte skip"),
            format!(
                "byte skip {skip} is beyond the {} bytes of data there can be (the file has {len} bytes)",
                room
            ),
        ));
    }
    Ok(())
}

/// Opens the decoded data stream of one source; returns it with the byte
/// offset (in the decoded stream) where the voxels start.
fn open_data(
    hdr_path: &Path,
    src: &Path,
    rest: Option<Box<dyn BufRead>>,
    h: &Header,
    encoding: Encoding,
    bytes: u64,
) -> Result<(Box<dyn Read>, u64)> {
    let attached = rest.is_some();
    let mut r: Box<dyn BufRead> = if let Some(rest) = rest {
        rest
    } else {
        let f = File::open(src).map_err(io_at(src))?;
        let len = regular_len(hdr_path, h, src, &f)?;
        check_byte_skip(hdr_path, h, encoding, len)?;
        if h.byte_skip == -1 && encoding == Encoding::Raw {
            // The data is the last `bytes` bytes of the file.
            if len < bytes {
                return Err(ScanError::Truncated {
                    path: src.to_path_buf(),
                    offset: 0,
                    expected: bytes,
                    found: len,
                });
            }
            let mut f = f;
            f.seek(SeekFrom::Start(len - bytes)).map_err(io_at(src))?;
            return Ok((Box::new(BufReader::new(f)), len - bytes));
        }
        Box::new(BufReader::new(f))
    };
    let mut offset = if attached { h.length } else { 0 };
    if h.byte_skip == -1 && attached {
        if encoding != Encoding::Raw {
            return Err(header(
                hdr_path,
                field_line(h, "byte skip"),
                "byte skip -1 is only allowed with raw encoding",
            ));
        }
        let len = std::fs::metadata(src).map_err(io_at(src))?.len();
        if len < h.length + bytes {
            return Err(ScanError::Truncated {
                path: src.to_path_buf(),
                offset: h.length,
                expected: bytes,
                found: len.saturating_sub(h.length),
            });
        }
        let skip = len - bytes - h.length;
        std::io::copy(&mut (&mut r).take(skip), &mut std::io::sink()).map_err(io_at(src))?;
        return Ok((Box::new(r), len - bytes));
    }
    if attached {
        let len = std::fs::metadata(src).map_err(io_at(src))?.len();
        check_byte_skip(hdr_path, h, encoding, len)?;
    }
    for k in 0..h.line_skip {
        let n = microfrep_io::bounded::skip_line(&mut r, u64::MAX).map_err(io_at(src))?;
        if n == 0 {
            return Err(header(
                hdr_path,
                field_line(h, "line skip"),
                format!(
                    "line skip {} but {} ends after {k} lines",
                    h.line_skip,
                    src.display()
                ),
            ));
        }
        offset += n;
    }
    let mut stream: Box<dyn Read> = match encoding {
        Encoding::Raw => r,
        Encoding::Gzip => {
            offset = 0;
            Box::new(MultiGzDecoder::new(r))
        }
        Encoding::Text => r,
    };
    if h.byte_skip > 0 {
        let skip = h.byte_skip as u64;
        let got = std::io::copy(&mut (&mut stream).take(skip), &mut std::io::sink())
            .map_err(io_at(src))?;
        if got < skip {
            return Err(ScanError::Truncated {
                path: src.to_path_buf(),
                offset,
                expected: skip + bytes,
                found: got,
            });
        }
        offset += skip;
    }
    Ok((stream, offset))
}

#[allow(clippy::too_many_arguments)]
fn read_text(
    path: &Path,
    h: &Header,
    sources: &[PathBuf],
    attached: bool,
    rest: BufReader<File>,
    mut asm: Assembler,
    ty: FileType,
    opts: &ReadOptions,
) -> Result<Volume> {
    let [nx, ny, nz] = asm.file_dims();
    let mut text = String::new();
    let mut rest = Some(rest);
    for src in sources {
        let len = std::fs::metadata(src).map_err(io_at(src))?.len();
        if len > opts.memory_limit / 2 {
            return Err(ScanError::TooLarge {
                what: format!("{} (text-encoded voxel data)", src.display()),
                need: len * 2,
                limit: opts.memory_limit,
                hint: "convert the file to raw or gzip encoding".into(),
            });
        }
        let own: Option<Box<dyn BufRead>> = if attached {
            rest.take().map(|r| Box::new(r) as Box<dyn BufRead>)
        } else {
            None
        };
        let (s, _) = open_data(path, src, own, h, Encoding::Text, 0)?;
        // Bounded by what is read: the size on disk says nothing for a
        // device or a pipe.
        let left = (opts.memory_limit / 2).saturating_sub(text.len() as u64);
        let data = microfrep_io::bounded::read_all(s, left).map_err(io_at(src))?;
        let data = String::from_utf8(data)
            .map_err(|_| header(path, "data", "text-encoded voxel data is not UTF-8 text"))?;
        text.push_str(&data);
    }
    let mut words = text.split_ascii_whitespace();
    let mut plane = vec![0.0f64; nx * ny];
    for z in 0..nz {
        for (i, v) in plane.iter_mut().enumerate() {
            let w = words.next().ok_or_else(|| ScanError::Truncated {
                path: path.to_path_buf(),
                offset: h.length,
                expected: (nx * ny * nz) as u64,
                found: (z * nx * ny + i) as u64,
            })?;
            *v = w.parse().map_err(|_| {
                header(
                    path,
                    format!("text sample {}", z * nx * ny + i),
                    format!("`{w}` is not a number"),
                )
            })?;
        }
        if matches!(ty, FileType::F32 | FileType::F64) {
            asm.push(z, &plane, (1.0, 0.0))?;
        } else {
            // Integers: keep the compact type.
            push_ints(&mut asm, z, &plane, ty)?;
        }
    }
    asm.finish()
}

fn push_ints(asm: &mut Assembler, z: usize, plane: &[f64], ty: FileType) -> Result<()> {
    macro_rules! as_ {
        ($t:ty) => {{
            let v: Vec<$t> = plane.iter().map(|&x| x as $t).collect();
            asm.push(z, &v, (1.0, 0.0))
        }};
    }
    match ty {
        FileType::U8 => as_!(u8),
        FileType::I8 => as_!(i8),
        FileType::U16 => as_!(u16),
        FileType::I16 => as_!(i16),
        FileType::U32 => as_!(u32),
        FileType::I32 => as_!(i32),
        FileType::U64 => as_!(u64),
        FileType::I64 => as_!(i64),
        FileType::F32 | FileType::F64 => asm.push(z, plane, (1.0, 0.0)),
    }
}

fn parse_header<R: BufRead>(path: &Path, r: &mut R) -> Result<Header> {
    let mut h = Header {
        ty: None,
        dimension: None,
        sizes: None,
        little: None,
        encoding: None,
        space: None,
        directions: None,
        origin: None,
        spacings: None,
        axis_mins: None,
        units_scale: 1.0,
        data_files: Vec::new(),
        line_skip: 0,
        byte_skip: 0,
        length: 0,
        lines: Default::default(),
    };
    let dir = path.parent().unwrap_or(Path::new(".")).to_path_buf();
    let mut line = Vec::new();
    let mut lineno = 0;
    let mut list_mode = false;
    let mut data_line = 0;
    loop {
        line.clear();
        let n = r
            .by_ref()
            .take((MAX_HEADER + 1) as u64)
            .read_until(b'\n', &mut line)
            .map_err(io_at(path))?;
        lineno += 1;
        h.length += n as u64;
        if h.length as usize > MAX_HEADER {
            return Err(header(
                path,
                format!("line {lineno}"),
                format!("header longer than {MAX_HEADER} bytes: not an NRRD file, or its blank line is missing"),
            ));
        }
        if n == 0 {
            break; // end of file: a detached header
        }
        let text = std::str::from_utf8(&line)
            .map_err(|_| header(path, format!("line {lineno}"), "header line is not text"))?;
        let text = text.trim_end_matches(['\n', '\r']);
        if lineno == 1 {
            if !(text.starts_with("NRRD000") && text.len() == 8) {
                return Err(header(
                    path,
                    "line 1",
                    format!("expected the magic `NRRD000N`, found `{}`", clip(text)),
                ));
            }
            continue;
        }
        if text.is_empty() {
            break; // the data follows
        }
        if list_mode {
            h.data_files.push(dir.join(text.trim()));
            continue;
        }
        if text.starts_with('#') {
            continue;
        }
        if text.contains(":=") {
            continue; // key/value pair
        }
        let loc = format!("line {lineno}");
        let (key, value) = text.split_once(": ").ok_or_else(|| {
            header(
                path,
                &loc,
                format!("expected `field: value`, found `{}`", clip(text)),
            )
        })?;
        let value = value.trim();
        let bad = |what: &str| {
            header(
                path,
                &loc,
                format!("{key}: {what}, found `{}`", clip(value)),
            )
        };
        let name: &'static str = match key {
            "type" => {
                h.ty = Some(parse_type(value).ok_or_else(|| bad("unknown sample type"))?);
                "type"
            }
            "dimension" => {
                h.dimension = Some(value.parse().map_err(|_| bad("expected an integer"))?);
                "dimension"
            }
            "sizes" => {
                let s: std::result::Result<Vec<usize>, _> =
                    value.split_ascii_whitespace().map(|w| w.parse()).collect();
                h.sizes = Some(s.map_err(|_| bad("expected positive integers"))?);
                "sizes"
            }
            "endian" => {
                h.little = Some(match value {
                    "little" => true,
                    "big" => false,
                    _ => return Err(bad("expected `little` or `big`")),
                });
                "endian"
            }
            "encoding" => {
                h.encoding = Some(match value {
                    "raw" => Encoding::Raw,
                    "gzip" | "gz" => Encoding::Gzip,
                    "text" | "txt" | "ascii" => Encoding::Text,
                    "bzip2" | "bz2" | "hex" => {
                        return Err(ScanError::Unsupported {
                            path: path.to_path_buf(),
                            what: format!("{loc}: encoding `{value}`; re-save as raw or gzip"),
                        })
                    }
                    _ => return Err(bad("unknown encoding")),
                });
                "encoding"
            }
            "space" => {
                h.space = Some(
                    match value {
                        "right-anterior-superior" | "RAS" => "RAS",
                        "left-anterior-superior" | "LAS" => "LAS",
                        "left-posterior-superior" | "LPS" => "LPS",
                        other => other,
                    }
                    .to_string(),
                );
                "space"
            }
            "space dimension" => {
                if value != "3" {
                    return Err(bad("only 3 is read"));
                }
                "space dimension"
            }
            "space directions" => {
                let mut dirs = Vec::new();
                let mut rest = value;
                while !rest.is_empty() {
                    rest = rest.trim_start();
                    if let Some(r2) = rest.strip_prefix("none") {
                        dirs.push(None);
                        rest = r2;
                    } else if rest.starts_with('(') {
                        let end = rest.find(')').ok_or_else(|| bad("unclosed `(`"))?;
                        dirs.push(Some(
                            parse_vec(&rest[1..end])
                                .ok_or_else(|| bad("expected (x,y,z) vectors"))?,
                        ));
                        rest = &rest[end + 1..];
                    } else if rest.is_empty() {
                        break;
                    } else {
                        return Err(bad("expected (x,y,z) vectors or `none`"));
                    }
                }
                h.directions = Some(dirs);
                "space directions"
            }
            "space origin" => {
                let v = value.trim();
                let inner = v
                    .strip_prefix('(')
                    .and_then(|v| v.strip_suffix(')'))
                    .ok_or_else(|| bad("expected (x,y,z)"))?;
                h.origin = Some(parse_vec(inner).ok_or_else(|| bad("expected (x,y,z)"))?);
                "space origin"
            }
            "space units" => {
                let units: Vec<&str> = value
                    .split_ascii_whitespace()
                    .map(|u| u.trim_matches('"'))
                    .collect();
                let scale = |u: &str| match u {
                    "mm" | "millimeter" | "millimeters" => Some(1.0),
                    "m" | "meter" | "meters" => Some(1000.0),
                    "cm" => Some(10.0),
                    "um" | "µm" | "micron" | "microns" => Some(1e-3),
                    _ => None,
                };
                let s: Option<Vec<f64>> = units.iter().map(|u| scale(u)).collect();
                match s.as_deref() {
                    Some([a, rest @ ..]) if rest.iter().all(|b| b == a) => h.units_scale = *a,
                    _ => return Err(bad("expected one length unit (mm, m, cm, um) for all axes")),
                }
                "space units"
            }
            "spacings" => {
                let s: std::result::Result<Vec<f64>, _> = value
                    .split_ascii_whitespace()
                    .map(|w| {
                        if w == "nan" || w == "NaN" {
                            Ok(f64::NAN)
                        } else {
                            w.parse()
                        }
                    })
                    .collect();
                h.spacings = Some(s.map_err(|_| bad("expected numbers"))?);
                "spacings"
            }
            "axis mins" | "axismins" => {
                let s: std::result::Result<Vec<f64>, _> =
                    value.split_ascii_whitespace().map(|w| w.parse()).collect();
                h.axis_mins = Some(s.map_err(|_| bad("expected numbers"))?);
                "axis mins"
            }
            "data file" | "datafile" => {
                data_line = lineno;
                let words: Vec<&str> = value.split_ascii_whitespace().collect();
                if value == "LIST" || words.first() == Some(&"LIST") {
                    list_mode = true;
                } else if words.len() >= 4 && words[0].contains('%') {
                    let nums: Option<Vec<i64>> =
                        words[1..4].iter().map(|w| w.parse().ok()).collect();
                    let [a, b, s] = nums
                        .as_deref()
                        .and_then(|n| <[i64; 3]>::try_from(n).ok())
                        .ok_or_else(|| bad("expected `format min max step`"))?;
                    if s == 0 || (b - a) / s < 0 || (b - a) / s > 1_000_000 {
                        return Err(bad("bad file number range"));
                    }
                    let mut i = a;
                    loop {
                        let name = sprintf_int(words[0], i)
                            .ok_or_else(|| bad("unsupported format (use %d or %0Nd)"))?;
                        h.data_files.push(dir.join(name));
                        if i == b {
                            break;
                        }
                        i += s;
                        if (s > 0 && i > b) || (s < 0 && i < b) {
                            break;
                        }
                    }
                } else {
                    h.data_files.push(dir.join(value));
                }
                "data file"
            }
            "line skip" | "lineskip" => {
                h.line_skip = value.parse().map_err(|_| bad("expected a count"))?;
                "line skip"
            }
            "byte skip" | "byteskip" => {
                h.byte_skip = value.parse().map_err(|_| bad("expected a count or -1"))?;
                if h.byte_skip < -1 {
                    return Err(bad("expected a count or -1"));
                }
                "byte skip"
            }
            _ => continue, // content, kinds, centers, labels, min, max, ...
        };
        h.lines.insert(name, lineno);
    }
    if data_line > 0 && h.data_files.is_empty() {
        return Err(header(
            path,
            format!("line {data_line}"),
            "data file list is empty",
        ));
    }
    Ok(h)
}

fn geometry(path: &Path, h: &Header) -> Result<Geometry> {
    let at = |k: &str| format!("line {}", h.lines.get(k).copied().unwrap_or(1));
    let u = h.units_scale;
    if let Some(dirs) = &h.directions {
        if dirs.len() != 3 || dirs.iter().any(|d| d.is_none()) {
            return Err(header(
                path,
                at("space directions"),
                format!(
                    "expected 3 spatial direction vectors, found {}",
                    dirs.iter().flatten().count()
                ),
            ));
        }
        let d: [[f64; 3]; 3] = std::array::from_fn(|a| dirs[a].unwrap_or([0.0; 3]).map(|v| v * u));
        let origin = h.origin.unwrap_or([0.0; 3]).map(|v| v * u);
        return Ok(Geometry {
            origin,
            dirs: d,
            spacing_known: true,
        });
    }
    let origin = match (&h.origin, &h.axis_mins) {
        (Some(o), _) => o.map(|v| v * u),
        (None, Some(m)) if m.len() == 3 => [m[0], m[1], m[2]],
        _ => [0.0; 3],
    };
    match &h.spacings {
        Some(s) if s.len() == 3 && s.iter().all(|v| v.is_finite() && *v != 0.0) => {
            let mut g = Geometry::diagonal([s[0] * u, s[1] * u, s[2] * u], origin);
            g.spacing_known = true;
            Ok(g)
        }
        Some(s) if s.len() != 3 => Err(header(
            path,
            at("spacings"),
            format!("`spacings` has {} values, dimension is 3", s.len()),
        )),
        _ => {
            let mut g = Geometry::diagonal([1.0; 3], origin);
            g.spacing_known = false;
            Ok(g)
        }
    }
}

fn parse_type(v: &str) -> Option<FileType> {
    Some(match v {
        "signed char" | "int8" | "int8_t" => FileType::I8,
        "uchar" | "unsigned char" | "uint8" | "uint8_t" => FileType::U8,
        "short" | "short int" | "signed short" | "signed short int" | "int16" | "int16_t" => {
            FileType::I16
        }
        "ushort" | "unsigned short" | "unsigned short int" | "uint16" | "uint16_t" => FileType::U16,
        "int" | "signed int" | "int32" | "int32_t" => FileType::I32,
        "uint" | "unsigned int" | "uint32" | "uint32_t" => FileType::U32,
        "longlong"
        | "long long"
        | "long long int"
        | "signed long long"
        | "signed long long int"
        | "int64"
        | "int64_t" => FileType::I64,
        "ulonglong" | "unsigned long long" | "unsigned long long int" | "uint64" | "uint64_t" => {
            FileType::U64
        }
        "float" => FileType::F32,
        "double" => FileType::F64,
        _ => return None,
    })
}

fn parse_vec(s: &str) -> Option<[f64; 3]> {
    let v: Vec<f64> = s
        .split(',')
        .map(|w| w.trim().parse().ok())
        .collect::<Option<Vec<f64>>>()?;
    <[f64; 3]>::try_from(v).ok()
}

/// `%d` or `%0Nd` in a data file name pattern.
fn sprintf_int(fmt: &str, i: i64) -> Option<String> {
    let start = fmt.find('%')?;
    let rest = &fmt[start + 1..];
    let end = rest.find('d')?;
    let spec = &rest[..end];
    let width: usize = if spec.is_empty() {
        0
    } else {
        spec.parse().ok()?
    };
    let pad = spec.starts_with('0');
    let num = if pad {
        format!("{i:0width$}")
    } else {
        format!("{i:width$}")
    };
    Some(format!("{}{}{}", &fmt[..start], num, &rest[end + 1..]))
}

fn clip(s: &str) -> String {
    let mut t: String = s.chars().take(60).collect();
    if t.len() < s.len() {
        t.push_str("...");
    }
    t
}
