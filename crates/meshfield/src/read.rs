//! Mesh readers: STL (binary and ASCII), OBJ, PLY (ASCII, binary little and
//! big endian), dispatched by extension in [`read_mesh`].
//!
//! Every reader returns the triangles as stored (an STL gives an unwelded
//! soup; weld with [`TriMesh::weld`]); polygons are split into fans. Every
//! malformed input is a [`ReadError`] naming the file and the line (text) or
//! byte offset (binary) and the triangle or vertex concerned. Sizes declared
//! in headers are checked against the file size before anything is
//! allocated, and the file itself against [`ReadOptions::memory_limit`].
//!
//! STL flavour detection: a file is binary when its header's triangle count
//! matches its size exactly (`84 + 50 n` bytes), whatever its first bytes
//! say (many exporters write "solid" into the binary header); otherwise it is
//! ASCII if it starts with `solid` and its first kilobyte is text; otherwise
//! it is a binary STL whose size disagrees with its header (an error).

use crate::mesh::TriMesh;
use std::fmt;
use std::path::{Path, PathBuf};

/// Where in a file an error is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Location {
    /// A line of a text file (1-based).
    Line(usize),
    /// A byte offset in a binary file (0-based).
    Byte(u64),
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Location::Line(l) => write!(f, "line {l}"),
            Location::Byte(b) => write!(f, "byte {b}"),
        }
    }
}

/// What went wrong while reading a mesh.
#[derive(Debug, thiserror::Error)]
pub enum ReadErrorKind {
    /// The file could not be read.
    #[error("cannot read the file")]
    Io(#[source] std::io::Error),
    /// The extension names no known format.
    #[error("unknown mesh format {0:?} (known: .stl, .obj, .ply)")]
    UnknownFormat(String),
    /// A known format that this crate does not read.
    #[error("{0} files are not yet supported here (they will be read by the microfrep-3mf crate)")]
    NotYetSupported(&'static str),
    /// Malformed text or header.
    #[error("{at}: {message}")]
    Syntax {
        /// Where.
        at: Location,
        /// What was expected and found.
        message: String,
    },
    /// A binary STL shorter than its header's triangle count needs.
    #[error(
        "binary STL is truncated: the header declares {declared} triangles, which need {expected} \
         bytes, but the file has {actual} bytes (triangle {first_missing} is incomplete)"
    )]
    TruncatedStl {
        /// Triangle count in the header.
        declared: u32,
        /// Bytes that count needs (84 + 50 n).
        expected: u64,
        /// Bytes in the file.
        actual: u64,
        /// First triangle that is not complete.
        first_missing: u64,
    },
    /// A binary STL longer than its header's triangle count says.
    #[error(
        "binary STL header declares {declared} triangles ({expected} bytes) but the file has \
         {actual} bytes, room for {implied} triangles"
    )]
    StlCountMismatch {
        /// Triangle count in the header.
        declared: u32,
        /// Bytes that count needs.
        expected: u64,
        /// Bytes in the file.
        actual: u64,
        /// Whole triangles the file size has room for.
        implied: u64,
    },
    /// A coordinate of a triangle corner is NaN or infinite (STL).
    #[error("{at}: triangle {triangle}, vertex {corner}: coordinate {axis} is {value}")]
    NonFiniteCorner {
        /// Where.
        at: Location,
        /// Triangle (0-based).
        triangle: usize,
        /// Corner of the triangle (0, 1, 2).
        corner: usize,
        /// x, y or z.
        axis: char,
        /// The value.
        value: f64,
    },
    /// A vertex coordinate is NaN or infinite (OBJ, PLY).
    #[error("{at}: vertex {vertex}: coordinate {axis} is {value}")]
    NonFiniteVertex {
        /// Where.
        at: Location,
        /// Vertex (0-based).
        vertex: usize,
        /// x, y or z.
        axis: char,
        /// The value.
        value: f64,
    },
    /// A face refers to a vertex that does not exist.
    #[error("{at}: face {face} uses vertex index {index}, but {available} vertices exist")]
    BadIndex {
        /// Where.
        at: Location,
        /// Face (0-based).
        face: usize,
        /// The index as written (1-based or negative in OBJ, 0-based in PLY).
        index: i64,
        /// Vertices defined at that point.
        available: usize,
    },
    /// The file ends in the middle of something.
    #[error("{at}: the file ends inside {inside}")]
    UnexpectedEnd {
        /// Where it ends.
        at: Location,
        /// What was being read.
        inside: String,
    },
    /// The file holds no triangles.
    #[error("the file holds no triangles")]
    Empty,
    /// Reading would need more memory than allowed.
    #[error("{what} would need about {need} bytes, more than the limit of {limit} bytes")]
    TooLarge {
        /// What was to be allocated.
        what: String,
        /// Bytes needed.
        need: u64,
        /// The limit.
        limit: u64,
    },
}

/// A reading error with the file it concerns.
#[derive(Debug)]
pub struct ReadError {
    /// The file.
    pub path: PathBuf,
    /// What went wrong and where.
    pub kind: ReadErrorKind,
}

impl fmt::Display for ReadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.path.display(), self.kind)
    }
}

impl std::error::Error for ReadError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match &self.kind {
            ReadErrorKind::Io(e) => Some(e),
            _ => None,
        }
    }
}

/// Limits for reading.
#[derive(Clone, Debug)]
pub struct ReadOptions {
    /// Most bytes the file and the mesh made from it may take together.
    pub memory_limit: u64,
}

impl Default for ReadOptions {
    fn default() -> Self {
        ReadOptions {
            memory_limit: crate::memory::default_limit(),
        }
    }
}

/// Whether `m` is a named pipe, which is read (bounded, as it has no
/// size) where a device is refused.
fn is_fifo(m: &std::fs::Metadata) -> bool {
    #[cfg(unix)]
    {
        std::os::unix::fs::FileTypeExt::is_fifo(&m.file_type())
    }
    #[cfg(not(unix))]
    {
        let _ = m;
        false
    }
}

/// Mesh file formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// STL, binary or ASCII.
    Stl,
    /// Wavefront OBJ.
    Obj,
    /// Stanford PLY.
    Ply,
    /// 3MF (not read by this crate).
    ThreeMf,
}

impl Format {
    /// The format named by a path's extension (case-insensitive).
    pub fn from_path(path: &Path) -> Result<Format, ReadErrorKind> {
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        match ext.as_str() {
            "stl" => Ok(Format::Stl),
            "obj" => Ok(Format::Obj),
            "ply" => Ok(Format::Ply),
            "3mf" => Ok(Format::ThreeMf),
            _ => Err(ReadErrorKind::UnknownFormat(if ext.is_empty() {
                "(no extension)".into()
            } else {
                format!(".{ext}")
            })),
        }
    }
}

/// Reads a mesh file, choosing the reader by extension (`.stl`, `.obj`,
/// `.ply`; `.3mf` is an error for now).
pub fn read_mesh(path: impl AsRef<Path>) -> Result<TriMesh, ReadError> {
    read_mesh_with(path, &ReadOptions::default())
}

/// [`read_mesh`] with options.
pub fn read_mesh_with(path: impl AsRef<Path>, opts: &ReadOptions) -> Result<TriMesh, ReadError> {
    let path = path.as_ref();
    let err = |kind| ReadError {
        path: path.to_path_buf(),
        kind,
    };
    let format = Format::from_path(path).map_err(err)?;
    if format == Format::ThreeMf {
        return Err(err(ReadErrorKind::NotYetSupported("3MF")));
    }
    let meta = std::fs::metadata(path).map_err(|e| err(ReadErrorKind::Io(e)))?;
    if !(meta.is_file() || is_fifo(&meta)) {
        return Err(err(ReadErrorKind::Io(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "not a regular file (a device or a folder); a mesh is read from a file or a pipe",
        ))));
    }
    let size = meta.len();
    // The file, plus a mesh of at most ~2x its size (binary STL: 84 bytes of
    // mesh per 50 of file; text formats are larger per triangle).
    let need = size.saturating_mul(3);
    if need > opts.memory_limit {
        return Err(err(ReadErrorKind::TooLarge {
            what: format!("reading this {size}-byte file"),
            need,
            limit: opts.memory_limit,
        }));
    }
    // What is read is bounded too: a device or a pipe (a link to /dev/zero
    // named z.stl) reports a size of 0 and never ends.
    let data = microfrep_io::bounded::read_file(path, opts.memory_limit / 3)
        .map_err(|e| err(ReadErrorKind::Io(e)))?;
    parse(format, &data).map_err(err)
}

/// Parses a mesh held in memory.
pub fn parse(format: Format, data: &[u8]) -> Result<TriMesh, ReadErrorKind> {
    let mesh = match format {
        Format::Stl => parse_stl(data)?,
        Format::Obj => parse_obj(data)?,
        Format::Ply => parse_ply(data)?,
        Format::ThreeMf => return Err(ReadErrorKind::NotYetSupported("3MF")),
    };
    if mesh.triangles.is_empty() {
        return Err(ReadErrorKind::Empty);
    }
    Ok(mesh)
}

const AXES: [char; 3] = ['x', 'y', 'z'];

/// Whether the STL data is ASCII (see the module doc).
pub fn stl_is_ascii(data: &[u8]) -> bool {
    if data.len() >= 84 {
        let n = u32::from_le_bytes([data[80], data[81], data[82], data[83]]) as u64;
        if 84 + 50 * n == data.len() as u64 {
            return false;
        }
    }
    let start = data
        .iter()
        .position(|b| !b.is_ascii_whitespace())
        .unwrap_or(data.len());
    let rest = &data[start..];
    let solid = rest.starts_with(b"solid") && rest.get(5).is_none_or(|b| b.is_ascii_whitespace());
    solid
        && data[..data.len().min(1024)]
            .iter()
            .all(|&b| b == b'\t' || b == b'\n' || b == b'\r' || (0x20..0x7f).contains(&b))
}

/// Parses STL, binary or ASCII.
pub fn parse_stl(data: &[u8]) -> Result<TriMesh, ReadErrorKind> {
    if stl_is_ascii(data) {
        parse_stl_ascii(data)
    } else {
        parse_stl_binary(data)
    }
}

fn parse_stl_binary(data: &[u8]) -> Result<TriMesh, ReadErrorKind> {
    let actual = data.len() as u64;
    if actual < 84 {
        return Err(ReadErrorKind::UnexpectedEnd {
            at: Location::Byte(actual),
            inside: "the 84-byte binary STL header (and it does not start with \"solid\" as an ASCII STL would)".into(),
        });
    }
    let declared = u32::from_le_bytes([data[80], data[81], data[82], data[83]]);
    let expected = 84 + 50 * declared as u64;
    if actual < expected {
        return Err(ReadErrorKind::TruncatedStl {
            declared,
            expected,
            actual,
            first_missing: (actual - 84) / 50,
        });
    }
    if actual > expected {
        return Err(ReadErrorKind::StlCountMismatch {
            declared,
            expected,
            actual,
            implied: (actual - 84) / 50,
        });
    }
    let n = declared as usize;
    let mut vertices = Vec::with_capacity(3 * n);
    let mut triangles = Vec::with_capacity(n);
    for t in 0..n {
        let base = 84 + 50 * t;
        for k in 0..3 {
            let mut v = [0.0; 3];
            for (a, c) in v.iter_mut().enumerate() {
                let o = base + 12 + 12 * k + 4 * a;
                let x = f32::from_le_bytes([data[o], data[o + 1], data[o + 2], data[o + 3]]);
                if !x.is_finite() {
                    return Err(ReadErrorKind::NonFiniteCorner {
                        at: Location::Byte(o as u64),
                        triangle: t,
                        corner: k,
                        axis: AXES[a],
                        value: x as f64,
                    });
                }
                *c = x as f64;
            }
            vertices.push(v);
        }
        let b = 3 * t as u32;
        triangles.push([b, b + 1, b + 2]);
    }
    Ok(TriMesh {
        vertices,
        triangles,
    })
}

/// Whitespace-separated tokens with line numbers.
struct Tokens<'a> {
    data: &'a [u8],
    pos: usize,
    line: usize,
}

impl<'a> Tokens<'a> {
    fn new(data: &'a [u8]) -> Self {
        Tokens {
            data,
            pos: 0,
            line: 1,
        }
    }

    /// Moves past whitespace, counting lines.
    fn skip_ws(&mut self) {
        while self.pos < self.data.len() && self.data[self.pos].is_ascii_whitespace() {
            if self.data[self.pos] == b'\n' {
                self.line += 1;
            }
            self.pos += 1;
        }
    }

    /// The next token and its line.
    fn next(&mut self) -> Option<(&'a [u8], usize)> {
        self.skip_ws();
        if self.pos >= self.data.len() {
            return None;
        }
        let s = self.pos;
        while self.pos < self.data.len() && !self.data[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        Some((&self.data[s..self.pos], self.line))
    }

    /// Skips to the start of the next line.
    fn skip_line(&mut self) {
        while self.pos < self.data.len() && self.data[self.pos] != b'\n' {
            self.pos += 1;
        }
    }

    fn expect(&mut self, word: &str, inside: &str) -> Result<usize, ReadErrorKind> {
        match self.next() {
            Some((t, line)) if t.eq_ignore_ascii_case(word.as_bytes()) => Ok(line),
            Some((t, line)) => Err(ReadErrorKind::Syntax {
                at: Location::Line(line),
                message: format!("expected '{word}', found '{}'", show(t)),
            }),
            None => Err(ReadErrorKind::UnexpectedEnd {
                at: Location::Line(self.line),
                inside: inside.into(),
            }),
        }
    }

    fn number(&mut self, inside: &str) -> Result<(f64, usize), ReadErrorKind> {
        match self.next() {
            Some((t, line)) => Ok((parse_f64(t, line)?, line)),
            None => Err(ReadErrorKind::UnexpectedEnd {
                at: Location::Line(self.line),
                inside: inside.into(),
            }),
        }
    }
}

fn show(t: &[u8]) -> String {
    let s = String::from_utf8_lossy(&t[..t.len().min(40)]).into_owned();
    if t.len() > 40 {
        s + "..."
    } else {
        s
    }
}

fn parse_f64(t: &[u8], line: usize) -> Result<f64, ReadErrorKind> {
    std::str::from_utf8(t)
        .ok()
        .and_then(|s| s.parse::<f64>().ok())
        .ok_or_else(|| ReadErrorKind::Syntax {
            at: Location::Line(line),
            message: format!("expected a number, found '{}'", show(t)),
        })
}

fn parse_stl_ascii(data: &[u8]) -> Result<TriMesh, ReadErrorKind> {
    let mut tk = Tokens::new(data);
    let mut vertices = Vec::new();
    let mut triangles = Vec::new();
    tk.expect("solid", "the STL")?;
    tk.skip_line();
    loop {
        match tk.next() {
            None => {
                return Err(ReadErrorKind::UnexpectedEnd {
                    at: Location::Line(tk.line),
                    inside: "a solid (no 'endsolid')".into(),
                })
            }
            Some((t, _)) if t.eq_ignore_ascii_case(b"endsolid") => {
                tk.skip_line();
                match tk.next() {
                    None => break,
                    Some((t, _)) if t.eq_ignore_ascii_case(b"solid") => {
                        tk.skip_line();
                        continue;
                    }
                    Some((t, line)) => {
                        return Err(ReadErrorKind::Syntax {
                            at: Location::Line(line),
                            message: format!(
                                "expected 'solid' or the end after 'endsolid', found '{}'",
                                show(t)
                            ),
                        })
                    }
                }
            }
            Some((t, _)) if t.eq_ignore_ascii_case(b"facet") => {
                let tri = triangles.len();
                let inside = format!("facet {tri}");
                tk.expect("normal", &inside)?;
                for _ in 0..3 {
                    tk.number(&inside)?;
                }
                tk.expect("outer", &inside)?;
                tk.expect("loop", &inside)?;
                for k in 0..3 {
                    tk.expect("vertex", &inside)?;
                    let mut v = [0.0; 3];
                    for (a, c) in v.iter_mut().enumerate() {
                        let (x, line) = tk.number(&inside)?;
                        if !x.is_finite() {
                            return Err(ReadErrorKind::NonFiniteCorner {
                                at: Location::Line(line),
                                triangle: tri,
                                corner: k,
                                axis: AXES[a],
                                value: x,
                            });
                        }
                        *c = x;
                    }
                    vertices.push(v);
                }
                tk.expect("endloop", &inside)?;
                tk.expect("endfacet", &inside)?;
                let b = 3 * tri as u32;
                triangles.push([b, b + 1, b + 2]);
            }
            Some((t, line)) => {
                return Err(ReadErrorKind::Syntax {
                    at: Location::Line(line),
                    message: format!("expected 'facet' or 'endsolid', found '{}'", show(t)),
                })
            }
        }
    }
    Ok(TriMesh {
        vertices,
        triangles,
    })
}

/// Parses Wavefront OBJ: `v` lines (x y z, further values ignored) and `f`
/// lines (`i`, `i/t`, `i//n`, `i/t/n`; negative indices count back from the
/// last vertex); polygons become fans; other statements are ignored. A face
/// may only use vertices defined above it.
pub fn parse_obj(data: &[u8]) -> Result<TriMesh, ReadErrorKind> {
    let mut vertices: Vec<[f64; 3]> = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut faces = 0usize;
    let mut line_no = 0usize;
    let mut joined: Vec<u8> = Vec::new();
    let mut corners: Vec<u32> = Vec::new();
    let mut lines = data.split(|&b| b == b'\n');
    while let Some(raw) = lines.next() {
        line_no += 1;
        let first_line = line_no;
        let mut line: &[u8] = raw;
        // Continuation lines end with a backslash.
        if line.trim_ascii_end().ends_with(b"\\") {
            joined.clear();
            let mut cur = line;
            loop {
                let t = cur.trim_ascii_end();
                if let Some(body) = t.strip_suffix(b"\\") {
                    joined.extend_from_slice(body);
                    joined.push(b' ');
                    match lines.next() {
                        Some(next) => {
                            line_no += 1;
                            cur = next;
                        }
                        None => {
                            return Err(ReadErrorKind::UnexpectedEnd {
                                at: Location::Line(line_no),
                                inside: "a line continued with '\\'".into(),
                            })
                        }
                    }
                } else {
                    joined.extend_from_slice(cur);
                    break;
                }
            }
            line = &joined;
        }
        let mut it = line
            .split(|b| b.is_ascii_whitespace())
            .filter(|t| !t.is_empty());
        let Some(key) = it.next() else { continue };
        match key {
            b"v" => {
                let mut v = [0.0; 3];
                for (a, c) in v.iter_mut().enumerate() {
                    let t = it.next().ok_or_else(|| ReadErrorKind::Syntax {
                        at: Location::Line(first_line),
                        message: format!("vertex {} has fewer than 3 coordinates", vertices.len()),
                    })?;
                    let x = parse_f64(t, first_line)?;
                    if !x.is_finite() {
                        return Err(ReadErrorKind::NonFiniteVertex {
                            at: Location::Line(first_line),
                            vertex: vertices.len(),
                            axis: AXES[a],
                            value: x,
                        });
                    }
                    *c = x;
                }
                if vertices.len() >= u32::MAX as usize {
                    return Err(ReadErrorKind::Syntax {
                        at: Location::Line(first_line),
                        message: "more than 2^32 - 1 vertices".into(),
                    });
                }
                vertices.push(v);
            }
            b"f" | b"fo" => {
                corners.clear();
                for t in it {
                    let idx = t.split(|&b| b == b'/').next().unwrap_or(t);
                    let i: i64 = std::str::from_utf8(idx)
                        .ok()
                        .and_then(|s| s.parse().ok())
                        .ok_or_else(|| ReadErrorKind::Syntax {
                            at: Location::Line(first_line),
                            message: format!("expected a vertex index, found '{}'", show(t)),
                        })?;
                    let n = vertices.len() as i64;
                    let resolved = if i > 0 { i - 1 } else { n + i };
                    if i == 0 || resolved < 0 || resolved >= n {
                        return Err(ReadErrorKind::BadIndex {
                            at: Location::Line(first_line),
                            face: faces,
                            index: i,
                            available: vertices.len(),
                        });
                    }
                    corners.push(resolved as u32);
                }
                if corners.len() < 3 {
                    return Err(ReadErrorKind::Syntax {
                        at: Location::Line(first_line),
                        message: format!(
                            "face {faces} has {} vertices, at least 3 needed",
                            corners.len()
                        ),
                    });
                }
                for k in 1..corners.len() - 1 {
                    triangles.push([corners[0], corners[k], corners[k + 1]]);
                }
                faces += 1;
            }
            _ => {}
        }
    }
    Ok(TriMesh {
        vertices,
        triangles,
    })
}

/// Scalar types of PLY properties.
#[derive(Clone, Copy, Debug, PartialEq)]
enum PlyType {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl PlyType {
    fn parse(s: &[u8]) -> Option<PlyType> {
        Some(match s {
            b"char" | b"int8" => PlyType::I8,
            b"uchar" | b"uint8" => PlyType::U8,
            b"short" | b"int16" => PlyType::I16,
            b"ushort" | b"uint16" => PlyType::U16,
            b"int" | b"int32" => PlyType::I32,
            b"uint" | b"uint32" => PlyType::U32,
            b"float" | b"float32" => PlyType::F32,
            b"double" | b"float64" => PlyType::F64,
            _ => return None,
        })
    }
    fn size(self) -> usize {
        match self {
            PlyType::I8 | PlyType::U8 => 1,
            PlyType::I16 | PlyType::U16 => 2,
            PlyType::I32 | PlyType::U32 | PlyType::F32 => 4,
            PlyType::F64 => 8,
        }
    }
    fn is_integer(self) -> bool {
        !matches!(self, PlyType::F32 | PlyType::F64)
    }
}

#[derive(Debug)]
struct PlyProperty {
    name: Vec<u8>,
    /// Some(count type) for a list.
    list: Option<PlyType>,
    ty: PlyType,
}

#[derive(Debug)]
struct PlyElement {
    name: Vec<u8>,
    count: u64,
    props: Vec<PlyProperty>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum PlyFormat {
    Ascii,
    Le,
    Be,
}

/// Parses PLY (ASCII, binary little or big endian): element `vertex` with
/// properties `x y z` (any scalar type) and element `face` with a list
/// property (`vertex_indices`, `vertex_index` or the first list); other
/// elements and properties are skipped.
pub fn parse_ply(data: &[u8]) -> Result<TriMesh, ReadErrorKind> {
    let syntax = |line: usize, message: String| ReadErrorKind::Syntax {
        at: Location::Line(line),
        message,
    };
    // Header.
    let mut pos = 0usize;
    let mut line = 0usize;
    let mut format = None;
    let mut elements: Vec<PlyElement> = Vec::new();
    loop {
        line += 1;
        let Some(end) = data[pos..].iter().position(|&b| b == b'\n') else {
            return Err(ReadErrorKind::UnexpectedEnd {
                at: Location::Line(line),
                inside: "the PLY header (no 'end_header')".into(),
            });
        };
        let text = data[pos..pos + end].trim_ascii();
        pos += end + 1;
        let words: Vec<&[u8]> = text
            .split(|b| b.is_ascii_whitespace())
            .filter(|w| !w.is_empty())
            .collect();
        if line == 1 {
            if text != b"ply" {
                return Err(syntax(1, "a PLY file starts with the line 'ply'".into()));
            }
            continue;
        }
        match words.first().copied() {
            None | Some(b"comment") | Some(b"obj_info") => {}
            Some(b"format") => {
                format = Some(match words.get(1).copied() {
                    Some(b"ascii") => PlyFormat::Ascii,
                    Some(b"binary_little_endian") => PlyFormat::Le,
                    Some(b"binary_big_endian") => PlyFormat::Be,
                    other => {
                        return Err(syntax(
                            line,
                            format!("unknown PLY format '{}'", show(other.unwrap_or(b""))),
                        ))
                    }
                })
            }
            Some(b"element") => {
                let (Some(name), Some(count)) = (words.get(1), words.get(2)) else {
                    return Err(syntax(line, "expected 'element NAME COUNT'".into()));
                };
                let count = std::str::from_utf8(count)
                    .ok()
                    .and_then(|s| s.parse::<u64>().ok())
                    .ok_or_else(|| syntax(line, format!("bad element count '{}'", show(count))))?;
                // A second element of a name would leave which one holds
                // the mesh to guesswork.
                if elements.iter().any(|e| e.name == *name) {
                    return Err(syntax(line, format!("a second element '{}'", show(name))));
                }
                elements.push(PlyElement {
                    name: name.to_vec(),
                    count,
                    props: Vec::new(),
                });
            }
            Some(b"property") => {
                let Some(el) = elements.last_mut() else {
                    return Err(syntax(line, "property before any element".into()));
                };
                let bad = || syntax(line, format!("bad property '{}'", show(text)));
                let prop = if words.get(1).copied() == Some(b"list") {
                    let (Some(c), Some(t), Some(n)) = (words.get(2), words.get(3), words.get(4))
                    else {
                        return Err(bad());
                    };
                    let c = PlyType::parse(c)
                        .filter(|c| c.is_integer())
                        .ok_or_else(bad)?;
                    let t = PlyType::parse(t).ok_or_else(bad)?;
                    PlyProperty {
                        name: n.to_vec(),
                        list: Some(c),
                        ty: t,
                    }
                } else {
                    let (Some(t), Some(n)) = (words.get(1), words.get(2)) else {
                        return Err(bad());
                    };
                    PlyProperty {
                        name: n.to_vec(),
                        list: None,
                        ty: PlyType::parse(t).ok_or_else(bad)?,
                    }
                };
                if el.props.iter().any(|q| q.name == prop.name) {
                    return Err(syntax(
                        line,
                        format!(
                            "a second property '{}' in element '{}'",
                            show(&prop.name),
                            show(&el.name)
                        ),
                    ));
                }
                el.props.push(prop);
            }
            Some(b"end_header") => break,
            Some(w) => {
                return Err(syntax(
                    line,
                    format!("unknown PLY header line '{}'", show(w)),
                ))
            }
        }
    }
    let format = format.ok_or_else(|| syntax(2, "the PLY header has no 'format' line".into()))?;
    let body = &data[pos..];
    // Sizes against the file before allocating.
    let min_bytes = |e: &PlyElement| -> u64 {
        e.props
            .iter()
            .map(|p| match (format, p.list) {
                (PlyFormat::Ascii, _) => 2,
                (_, Some(c)) => c.size() as u64,
                (_, None) => p.ty.size() as u64,
            })
            .sum::<u64>()
            .max(1)
    };
    let mut need = 0u64;
    for e in &elements {
        need = need.saturating_add(e.count.saturating_mul(min_bytes(e)));
    }
    if need > body.len() as u64 {
        return Err(ReadErrorKind::UnexpectedEnd {
            at: Location::Byte(data.len() as u64),
            inside: format!(
                "the PLY body: the header declares elements needing at least {need} bytes, {} remain",
                body.len()
            ),
        });
    }
    let vertex_el = elements.iter().position(|e| e.name == b"vertex");
    let xyz: Option<[usize; 3]> = vertex_el.and_then(|v| {
        let p = &elements[v].props;
        let f = |n: &[u8]| p.iter().position(|q| q.name == n && q.list.is_none());
        Some([f(b"x")?, f(b"y")?, f(b"z")?])
    });
    if vertex_el.is_some() && xyz.is_none() {
        return Err(syntax(
            line,
            "element 'vertex' lacks scalar properties x, y and z".into(),
        ));
    }
    let face_el = elements.iter().position(|e| e.name == b"face");
    let face_list: Option<usize> = face_el.and_then(|f| {
        let p = &elements[f].props;
        p.iter()
            .position(|q| {
                q.list.is_some() && (q.name == b"vertex_indices" || q.name == b"vertex_index")
            })
            .or_else(|| p.iter().position(|q| q.list.is_some()))
    });
    if face_el.is_some() && face_list.is_none() {
        return Err(syntax(line, "element 'face' has no list property".into()));
    }
    let nv = vertex_el.map_or(0, |v| elements[v].count) as usize;
    let mut vertices: Vec<[f64; 3]> = Vec::with_capacity(nv);
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut faces = 0usize;
    let mut corners: Vec<i64> = Vec::new();
    let mut values: Vec<f64> = Vec::new();

    let mut reader = PlyBody {
        data: body,
        base: pos as u64,
        pos: 0,
        tokens: Tokens {
            data: body,
            pos: 0,
            line: line + 1,
        },
        format,
    };
    for (ei, el) in elements.iter().enumerate() {
        for item in 0..el.count {
            let inside = format!("{} {item}", String::from_utf8_lossy(&el.name));
            let at = reader.location();
            let is_vertex = Some(ei) == vertex_el;
            let is_face = Some(ei) == face_el;
            values.clear();
            for (pi, p) in el.props.iter().enumerate() {
                match p.list {
                    None => {
                        let v = reader.scalar(p.ty, &inside)?;
                        if is_vertex {
                            values.push(v);
                        }
                    }
                    Some(ct) => {
                        let n = reader.scalar(ct, &inside)?;
                        if !(0.0..=1e6).contains(&n) {
                            return Err(ReadErrorKind::Syntax {
                                at,
                                message: format!(
                                    "{inside}: list length {n} is out of range (a whole number \
                                     from 0 to 1000000)"
                                ),
                            });
                        }
                        let take = is_face && Some(pi) == face_list;
                        if take {
                            corners.clear();
                        }
                        for _ in 0..n as usize {
                            let v = reader.scalar(p.ty, &inside)?;
                            if take {
                                // An index is a whole number: a fraction or
                                // NaN (which `as` would make 0) is an error.
                                if !(v.is_finite() && v.fract() == 0.0 && v.abs() < 1e18) {
                                    return Err(ReadErrorKind::Syntax {
                                        at,
                                        message: format!(
                                            "{inside}: vertex index {v} is not a whole number"
                                        ),
                                    });
                                }
                                corners.push(v as i64);
                            }
                        }
                    }
                }
            }
            if is_vertex {
                let idx = xyz.unwrap_or([0, 1, 2]);
                let v = idx.map(|i| values[scalar_slot(&el.props, i)]);
                for (a, &c) in v.iter().enumerate() {
                    if !c.is_finite() {
                        return Err(ReadErrorKind::NonFiniteVertex {
                            at,
                            vertex: vertices.len(),
                            axis: AXES[a],
                            value: c,
                        });
                    }
                }
                vertices.push(v);
            }
            if is_face {
                if corners.len() < 3 {
                    return Err(ReadErrorKind::Syntax {
                        at,
                        message: format!(
                            "face {faces} has {} vertices, at least 3 needed",
                            corners.len()
                        ),
                    });
                }
                for &c in corners.iter() {
                    if c < 0 || c as u64 >= nv as u64 {
                        return Err(ReadErrorKind::BadIndex {
                            at,
                            face: faces,
                            index: c,
                            available: nv,
                        });
                    }
                }
                for k in 1..corners.len() - 1 {
                    triangles.push([corners[0] as u32, corners[k] as u32, corners[k + 1] as u32]);
                }
                faces += 1;
            }
        }
    }
    Ok(TriMesh {
        vertices,
        triangles,
    })
}

/// Index among the scalar (non-list) values of an element for property `i`.
fn scalar_slot(props: &[PlyProperty], i: usize) -> usize {
    props[..i].iter().filter(|p| p.list.is_none()).count()
}

struct PlyBody<'a> {
    data: &'a [u8],
    /// Offset of the body in the file.
    base: u64,
    pos: usize,
    tokens: Tokens<'a>,
    format: PlyFormat,
}

impl PlyBody<'_> {
    fn location(&mut self) -> Location {
        match self.format {
            PlyFormat::Ascii => {
                self.tokens.skip_ws();
                Location::Line(self.tokens.line)
            }
            _ => Location::Byte(self.base + self.pos as u64),
        }
    }

    fn scalar(&mut self, ty: PlyType, inside: &str) -> Result<f64, ReadErrorKind> {
        if self.format == PlyFormat::Ascii {
            return self.tokens.number(inside).map(|(v, _)| v);
        }
        let n = ty.size();
        if self.pos + n > self.data.len() {
            return Err(ReadErrorKind::UnexpectedEnd {
                at: Location::Byte(self.base + self.data.len() as u64),
                inside: inside.into(),
            });
        }
        let mut b = [0u8; 8];
        b[..n].copy_from_slice(&self.data[self.pos..self.pos + n]);
        if self.format == PlyFormat::Be {
            b[..n].reverse();
        }
        self.pos += n;
        Ok(match ty {
            PlyType::I8 => b[0] as i8 as f64,
            PlyType::U8 => b[0] as f64,
            PlyType::I16 => i16::from_le_bytes([b[0], b[1]]) as f64,
            PlyType::U16 => u16::from_le_bytes([b[0], b[1]]) as f64,
            PlyType::I32 => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            PlyType::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            PlyType::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            PlyType::F64 => f64::from_le_bytes(b),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn binary_stl(header: &[u8], tris: &[[[f32; 3]; 3]], count: u32) -> Vec<u8> {
        let mut d = vec![b' '; 80];
        d[..header.len()].copy_from_slice(header);
        d.extend_from_slice(&count.to_le_bytes());
        for t in tris {
            d.extend_from_slice(&[0u8; 12]);
            for v in t {
                for c in v {
                    d.extend_from_slice(&c.to_le_bytes());
                }
            }
            d.extend_from_slice(&[0, 0]);
        }
        d
    }

    const TRI: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

    #[test]
    fn binary_stl_with_solid_header_is_binary() {
        let d = binary_stl(b"solid exported by some CAD", &[TRI, TRI], 2);
        assert!(!stl_is_ascii(&d));
        let m = parse_stl(&d).unwrap();
        assert_eq!(m.triangles.len(), 2);
        assert_eq!(m.vertices[1], [1.0, 0.0, 0.0]);
    }

    #[test]
    fn ascii_stl_is_ascii() {
        let s =
            "solid cube\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n   \
                 vertex 0 1 0\n  endloop\n endfacet\nendsolid cube\n";
        assert!(stl_is_ascii(s.as_bytes()));
        let m = parse_stl(s.as_bytes()).unwrap();
        assert_eq!(m.triangles, vec![[0, 1, 2]]);
        assert_eq!(m.vertices[2], [0.0, 1.0, 0.0]);
    }

    #[test]
    fn stl_errors_say_where() {
        let d = binary_stl(b"x", &[TRI, TRI], 3);
        let e = parse_stl(&d).unwrap_err();
        assert!(
            matches!(
                e,
                ReadErrorKind::TruncatedStl {
                    declared: 3,
                    first_missing: 2,
                    ..
                }
            ),
            "{e}"
        );
        let d = binary_stl(b"solid but binary", &[TRI, TRI], 1);
        let e = parse_stl(&d).unwrap_err();
        assert!(
            matches!(e, ReadErrorKind::StlCountMismatch { implied: 2, .. }),
            "{e}"
        );
        let mut bad = TRI;
        bad[1][2] = f32::NAN;
        let d = binary_stl(b"", &[TRI, bad], 2);
        let e = parse_stl(&d).unwrap_err();
        assert_eq!(
            e.to_string(),
            format!(
                "byte {}: triangle 1, vertex 1: coordinate z is NaN",
                84 + 50 + 12 + 12 + 8
            )
        );
        let s = "solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 inf 0\nendloop\nendfacet\nendsolid\n";
        let e = parse_stl(s.as_bytes()).unwrap_err();
        assert_eq!(
            e.to_string(),
            "line 6: triangle 0, vertex 2: coordinate y is inf"
        );
        let s = "solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0\n";
        let e = parse_stl(s.as_bytes()).unwrap_err();
        assert!(
            e.to_string().contains("expected a number, found ''")
                || e.to_string().contains("ends inside facet 0"),
            "{e}"
        );
        let s = "solid a\nfacet normal 0 0 1\nouter lop\n";
        assert_eq!(
            parse_stl(s.as_bytes()).unwrap_err().to_string(),
            "line 3: expected 'loop', found 'lop'"
        );
        let e = parse(Format::Stl, b"solid empty\nendsolid empty\n").unwrap_err();
        assert!(matches!(e, ReadErrorKind::Empty));
        let e = parse_stl(b"abc").unwrap_err();
        assert!(e.to_string().contains("84-byte"), "{e}");
    }

    #[test]
    fn obj_polygons_negative_indices_and_errors() {
        let s = "# quad\nv 0 0 0\nv 1 0 0\nv 1 1 0 1.0\nv 0 1 0\nvt 0 0\nf 1/1 2//3 3/4/5 -1\n";
        let m = parse_obj(s.as_bytes()).unwrap();
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        let e = parse_obj(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n").unwrap_err();
        assert_eq!(
            e.to_string(),
            "line 4: face 0 uses vertex index 4, but 3 vertices exist"
        );
        let e = parse_obj(b"v 0 0 0\nv 1 nan 0\n").unwrap_err();
        assert_eq!(e.to_string(), "line 2: vertex 1: coordinate y is NaN");
        let e = parse_obj(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 0 2\n").unwrap_err();
        assert!(matches!(e, ReadErrorKind::BadIndex { index: 0, .. }));
        let m = parse_obj(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 \\\n 3\n").unwrap();
        assert_eq!(m.triangles.len(), 1);
    }

    fn ply_binary(big: bool) -> Vec<u8> {
        let fmt = if big {
            "binary_big_endian"
        } else {
            "binary_little_endian"
        };
        let mut d = format!(
            "ply\nformat {fmt} 1.0\ncomment test\nelement vertex 4\nproperty float x\nproperty float y\n\
             property double z\nproperty uchar red\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
        )
        .into_bytes();
        let vs = [
            [0.0f32, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ];
        for v in vs {
            for c in &v[..2] {
                d.extend(if big {
                    c.to_be_bytes()
                } else {
                    c.to_le_bytes()
                });
            }
            let z = v[2] as f64;
            d.extend(if big {
                z.to_be_bytes()
            } else {
                z.to_le_bytes()
            });
            d.push(255);
        }
        d.push(4);
        for i in [0i32, 1, 2, 3] {
            d.extend(if big {
                i.to_be_bytes()
            } else {
                i.to_le_bytes()
            });
        }
        d
    }

    #[test]
    fn ply_all_three_encodings() {
        let ascii = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
                      element face 1\nproperty list uchar int vertex_index\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
        let m = parse_ply(ascii).unwrap();
        assert_eq!(
            (m.vertices.len(), m.triangles.clone()),
            (3, vec![[0, 1, 2]])
        );
        for big in [false, true] {
            let m = parse_ply(&ply_binary(big)).unwrap();
            assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]]);
            assert_eq!(m.vertices[2], [1.0, 1.0, 0.0]);
        }
    }

    #[test]
    fn ply_errors_say_where() {
        let mut d = ply_binary(false);
        d.truncate(d.len() - 3);
        let e = parse_ply(&d).unwrap_err();
        assert!(
            matches!(
                e,
                ReadErrorKind::UnexpectedEnd {
                    at: Location::Byte(_),
                    ..
                }
            ),
            "{e}"
        );
        assert!(e.to_string().contains("face 0"), "{e}");
        let mut d = ply_binary(false);
        let n = d.len();
        d[n - 4..].copy_from_slice(&9i32.to_le_bytes());
        let e = parse_ply(&d).unwrap_err();
        assert!(
            matches!(
                e,
                ReadErrorKind::BadIndex {
                    index: 9,
                    face: 0,
                    ..
                }
            ),
            "{e}"
        );
        let ascii = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
                      end_header\n0 0 0\n1 0 0\n0 nan 0\n";
        let e = parse_ply(ascii).unwrap_err();
        assert_eq!(e.to_string(), "line 10: vertex 2: coordinate y is NaN");
        let e = parse_ply(
            b"ply\nformat ascii 1.0\nelement vertex 1000000000\nproperty float x\nend_header\n1\n",
        )
        .unwrap_err();
        assert!(matches!(e, ReadErrorKind::UnexpectedEnd { .. }), "{e}");
        let e = parse_ply(b"ply\nformat ascii 1.0\nelemnt vertex 1\n").unwrap_err();
        assert_eq!(e.to_string(), "line 3: unknown PLY header line 'elemnt'");
    }

    #[test]
    fn ply_refuses_repeated_names_and_fractional_indices() {
        let head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                    property float z\n";
        let verts = "0 0 0\n1 0 0\n0 1 0\n";
        let face = "element face 1\nproperty list uchar int vertex_index\n";
        let ply = |extra: &str, body: &str| format!("{head}{extra}end_header\n{verts}{body}");
        // The well-formed file reads.
        let m = parse_ply(ply(face, "3 0 1 2\n").as_bytes()).unwrap();
        assert_eq!(m.triangles, vec![[0, 1, 2]]);
        // A second element of a name.
        let e = parse_ply(ply(&format!("{face}{face}"), "3 0 1 2\n3 0 1 2\n").as_bytes());
        assert_eq!(
            e.unwrap_err().to_string(),
            "line 9: a second element 'face'"
        );
        // A second property of a name.
        let e = parse_ply(
            ply(
                "element face 1\nproperty uchar n\nproperty uchar n\n",
                "1 1\n",
            )
            .as_bytes(),
        );
        assert_eq!(
            e.unwrap_err().to_string(),
            "line 9: a second property 'n' in element 'face'"
        );
        // A list length out of range; a list length of a float type.
        let e = parse_ply(ply(&face.replace("uchar", "uint"), "2000000 0 1 2\n").as_bytes());
        let e = e.unwrap_err().to_string();
        assert!(
            e.starts_with("line 13: face 0: list length 2000000 is out of range"),
            "{e}"
        );
        let e = parse_ply(ply(&face.replace("uchar", "float"), "3 0 1 2\n").as_bytes());
        let e = e.unwrap_err().to_string();
        assert!(e.starts_with("line 8: bad property"), "{e}");
        // An index that is not a whole number.
        for bad in ["1.5", "nan", "inf"] {
            let e =
                parse_ply(ply(&face.replace("int", "float"), &format!("3 0 {bad} 2\n")).as_bytes());
            let e = e.unwrap_err().to_string();
            assert!(
                e.starts_with("line 13: face 0: vertex index")
                    && e.ends_with("is not a whole number"),
                "{bad}: {e}"
            );
        }
        // Whole numbers in a float list are indices as any.
        let m = parse_ply(ply(&face.replace("int", "float"), "3 0 1 2\n").as_bytes()).unwrap();
        assert_eq!(m.triangles, vec![[0, 1, 2]]);
    }

    #[test]
    fn dispatch_by_extension() {
        let e = read_mesh("part.3mf").unwrap_err();
        assert!(e.to_string().contains("not yet supported here"), "{e}");
        let e = read_mesh("part.xyz").unwrap_err();
        assert!(
            e.to_string().contains("unknown mesh format \".xyz\""),
            "{e}"
        );
        // A device under a mesh's name is refused, not read forever.
        #[cfg(unix)]
        if Path::new("/dev/zero").exists() {
            let dir = std::env::temp_dir().join(format!("mf-read-dev-{}", std::process::id()));
            std::fs::create_dir_all(&dir).unwrap();
            let z = dir.join("z.stl");
            let _ = std::fs::remove_file(&z);
            std::os::unix::fs::symlink("/dev/zero", &z).unwrap();
            let e = read_mesh(&z).unwrap_err();
            let _ = std::fs::remove_dir_all(&dir);
            let text = format!("{e}: {}", std::error::Error::source(&e).unwrap());
            assert!(
                text.contains("z.stl: cannot read the file: not a regular file"),
                "{text}"
            );
        }
        let e = read_mesh("/nonexistent/part.stl").unwrap_err();
        assert!(matches!(e.kind, ReadErrorKind::Io(_)));
        assert!(std::error::Error::source(&e).is_some());
    }
}
