//! TIFF stacks: one multi-page TIFF (a page per slice) or a folder of
//! single-page TIFF slices in natural name order (`s2.tif` before
//! `s10.tif`). 8/16/32/64-bit grey pages, integer or float, any compression
//! the `tiff` crate decodes (none, LZW, deflate, PackBits). TIFF carries no
//! reliable voxel spacing, so [`ReadOptions::spacing`] is required.

use crate::error::{io_at, Result, ScanError};
use crate::volume::{Assembler, Geometry, Progress, ReadOptions, Volume};
use std::cmp::Ordering;
use std::fs::File;
use std::io::BufReader;
use std::path::{Path, PathBuf};
use tiff::decoder::{Decoder, DecodingResult, Limits};
use tiff::ColorType;

/// Whether a file name ends in `.tif` or `.tiff`.
pub(crate) fn is_tiff_name(p: &Path) -> bool {
    matches!(
        p.extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
            .as_deref(),
        Some("tif" | "tiff")
    )
}

fn tiff_err(path: &Path, page: usize) -> impl Fn(tiff::TiffError) -> ScanError + '_ {
    move |source| ScanError::Tiff {
        path: path.to_path_buf(),
        page,
        source,
    }
}

fn decoder(path: &Path, limit: u64) -> Result<Decoder<BufReader<File>>> {
    let f = File::open(path).map_err(io_at(path))?;
    let mut limits = Limits::default();
    limits.decoding_buffer_size = limit.min(usize::MAX as u64) as usize;
    Ok(Decoder::new(BufReader::new(f))
        .map_err(tiff_err(path, 0))?
        .with_limits(limits))
}

/// Size and sample kind of the current page.
fn page_info(
    d: &mut Decoder<BufReader<File>>,
    path: &Path,
    page: usize,
) -> Result<(usize, usize, ColorType)> {
    let (w, h) = d.dimensions().map_err(tiff_err(path, page))?;
    let c = d.colortype().map_err(tiff_err(path, page))?;
    if !matches!(c, ColorType::Gray(8 | 16 | 32 | 64)) {
        return Err(ScanError::Unsupported {
            path: path.to_path_buf(),
            what: format!(
                "page {page} has colour type {c:?}; only 8/16/32/64-bit grey pages are read"
            ),
        });
    }
    Ok((w as usize, h as usize, c))
}

/// Decodes the current page and pushes it as slice `z`.
fn push_page(
    asm: &mut Assembler,
    d: &mut Decoder<BufReader<File>>,
    path: &Path,
    page: usize,
    z: usize,
) -> Result<()> {
    let img = d.read_image().map_err(tiff_err(path, page))?;
    let s = (1.0, 0.0);
    match img {
        DecodingResult::U8(v) => asm.push(z, &v, s),
        DecodingResult::U16(v) => asm.push(z, &v, s),
        DecodingResult::U32(v) => asm.push(z, &v, s),
        DecodingResult::U64(v) => asm.push(z, &v, s),
        DecodingResult::I8(v) => asm.push(z, &v, s),
        DecodingResult::I16(v) => asm.push(z, &v, s),
        DecodingResult::I32(v) => asm.push(z, &v, s),
        DecodingResult::I64(v) => asm.push(z, &v, s),
        DecodingResult::F32(v) => asm.push(z, &v, s),
        DecodingResult::F64(v) => asm.push(z, &v, s),
        DecodingResult::F16(v) => {
            let v: Vec<f32> = v.iter().map(|h| h.to_f32()).collect();
            asm.push(z, &v, s)
        }
    }
    .map_err(|e| match e {
        ScanError::SizeMismatch {
            expected, found, ..
        } => ScanError::SizeMismatch {
            path: path.to_path_buf(),
            what: format!("samples in page {page}"),
            expected,
            found,
        },
        e => e,
    })
}

/// The file type for the assembler's memory plan: the page's sample kind.
fn file_type(
    c: ColorType,
    d: &mut Decoder<BufReader<File>>,
    path: &Path,
) -> Result<crate::volume::FileType> {
    use crate::volume::FileType as F;
    use tiff::tags::{SampleFormat, Tag};
    let fmt = d
        .find_tag(Tag::SampleFormat)
        .map_err(tiff_err(path, 0))?
        .and_then(|v| v.into_u16().ok())
        .map(SampleFormat::from_u16_exhaustive)
        .unwrap_or(SampleFormat::Uint);
    let bits = match c {
        ColorType::Gray(b) => b,
        _ => 8,
    };
    Ok(match (fmt, bits) {
        (SampleFormat::IEEEFP, _) => F::F32,
        (SampleFormat::Int, 8) => F::I8,
        (SampleFormat::Int, 16) => F::I16,
        (SampleFormat::Int, _) => F::I32,
        (_, 8) => F::U8,
        (_, 16) => F::U16,
        _ => F::U32,
    })
}

/// Reads a multi-page TIFF, one page per slice.
pub fn read_tiff(path: &Path, opts: &ReadOptions, progress: Progress) -> Result<Volume> {
    // First pass: count the pages and check they agree, decoding nothing.
    let mut d = decoder(path, opts.memory_limit)?;
    let (w, h, c) = page_info(&mut d, path, 0)?;
    let ty = file_type(c, &mut d, path)?;
    let mut pages = 1;
    while d.more_images() {
        d.next_image().map_err(tiff_err(path, pages))?;
        let (w2, h2, c2) = page_info(&mut d, path, pages)?;
        if (w2, h2) != (w, h) || c2 != c {
            return Err(ScanError::SizeMismatch {
                path: path.to_path_buf(),
                what: format!(
                    "page {pages}: {w2} x {h2} {c2:?}, page 0 is {w} x {h} {c:?}; pixels"
                ),
                expected: (w * h) as u64,
                found: (w2 * h2) as u64,
            });
        }
        pages += 1;
    }
    let plane = (w * h * 8) as u64;
    let mut asm = assembler(path, [w, h, pages], ty, plane, opts)?;
    let mut d = decoder(path, opts.memory_limit)?;
    let last = (0..pages).rev().find(|&z| asm.wants(z)).unwrap_or(0);
    for z in 0..=last {
        if z > 0 {
            d.next_image().map_err(tiff_err(path, z))?;
        }
        if asm.wants(z) {
            push_page(&mut asm, &mut d, path, z, z)?;
        }
        progress(z as u64 + 1, last as u64 + 1);
    }
    asm.finish()
}

fn assembler(
    path: &Path,
    dims: [usize; 3],
    ty: crate::volume::FileType,
    plane: u64,
    opts: &ReadOptions,
) -> Result<Assembler> {
    let mut g = Geometry::diagonal([1.0; 3], [0.0; 3]);
    g.spacing_known = false;
    Assembler::new(
        path,
        dims,
        ty,
        g,
        (1.0, 0.0),
        true,
        plane * 2,
        "unknown",
        opts,
    )
}

/// Reads a folder of single-page TIFF slices, sorted by name in natural
/// order (numbers compared by value).
pub fn read_tiff_folder(dir: &Path, opts: &ReadOptions, progress: Progress) -> Result<Volume> {
    let mut files: Vec<PathBuf> = crate::dcm::list_files(dir)?
        .into_iter()
        .filter(|p| is_tiff_name(p))
        .collect();
    if files.is_empty() {
        return Err(ScanError::Unsupported {
            path: dir.to_path_buf(),
            what: "no .tif or .tiff files in the folder".into(),
        });
    }
    files.sort_by(|a, b| natural_cmp(&a.to_string_lossy(), &b.to_string_lossy()));
    let mut d = decoder(&files[0], opts.memory_limit)?;
    let (w, h, c) = page_info(&mut d, &files[0], 0)?;
    let ty = file_type(c, &mut d, &files[0])?;
    // Check every slice's header before reading any pixels.
    for f in &files[1..] {
        let mut d = decoder(f, opts.memory_limit)?;
        let (w2, h2, c2) = page_info(&mut d, f, 0)?;
        if (w2, h2) != (w, h) || c2 != c {
            return Err(ScanError::SizeMismatch {
                path: f.clone(),
                what: format!(
                    "slice is {w2} x {h2} {c2:?}, {} is {w} x {h} {c:?}; pixels",
                    files[0].display()
                ),
                expected: (w * h) as u64,
                found: (w2 * h2) as u64,
            });
        }
        if d.more_images() {
            return Err(ScanError::Unsupported {
                path: f.clone(),
                what: "a multi-page TIFF in a folder of slices; read it on its own".into(),
            });
        }
    }
    let plane = (w * h * 8) as u64;
    let mut asm = assembler(dir, [w, h, files.len()], ty, plane, opts)?;
    for f in &files {
        asm.add_file(f);
    }
    let n = files.len();
    for (z, f) in files.iter().enumerate() {
        if asm.wants(z) {
            let mut d = decoder(f, opts.memory_limit)?;
            push_page(&mut asm, &mut d, f, 0, z)?;
        }
        progress(z as u64 + 1, n as u64);
    }
    asm.finish()
}

/// Natural order: runs of digits compare by value, the rest by character.
pub fn natural_cmp(a: &str, b: &str) -> Ordering {
    let (mut x, mut y) = (a.as_bytes(), b.as_bytes());
    loop {
        match (x.first(), y.first()) {
            (None, None) => return a.cmp(b),
            (None, _) => return Ordering::Less,
            (_, None) => return Ordering::Greater,
            (Some(c), Some(d)) if c.is_ascii_digit() && d.is_ascii_digit() => {
                let run = |s: &[u8]| s.iter().take_while(|c| c.is_ascii_digit()).count();
                let (m, n) = (run(x), run(y));
                let strip = |s: &[u8]| {
                    let z = s.iter().take_while(|&&c| c == b'0').count();
                    s[z..].to_vec()
                };
                let (p, q) = (strip(&x[..m]), strip(&y[..n]));
                let o = p.len().cmp(&q.len()).then_with(|| p.cmp(&q));
                if o != Ordering::Equal {
                    return o;
                }
                x = &x[m..];
                y = &y[n..];
            }
            (Some(c), Some(d)) => {
                if c != d {
                    return c.cmp(d);
                }
                x = &x[1..];
                y = &y[1..];
            }
        }
    }
}
