//! DICOM series: a folder of single-frame slice files (CT, MR, ...).
//!
//! The `dicom-object` crate parses each file (meta group, transfer syntax,
//! attributes). A first pass reads every file's attributes up to the pixel
//! data; the slices of the one series are sorted by ImagePositionPatient
//! along the slice normal (the cross product of the two
//! ImageOrientationPatient directions) and checked: one series, the same
//! size, pixel format and orientation, even spacing, no shear. Then the
//! memory is checked and the pixel data of each file is decoded here
//! (uncompressed little- or big-endian transfer syntaxes, 8/16/32-bit
//! samples with BitsStored masking and sign extension) and scaled by
//! RescaleSlope / RescaleIntercept (Hounsfield units for CT).

use crate::error::{io_at, Result, ScanError};
use crate::volume::{Assembler, FileType, Geometry, Progress, ReadOptions, Volume};
use dicom_core::value::DicomValueType;
use dicom_core::value::{PrimitiveValue, Value};
use dicom_core::Tag;
use dicom_dictionary_std::tags;
use dicom_object::{DefaultDicomObject, OpenFileOptions};
use std::collections::BTreeMap;
use std::io::Read;
use std::path::{Path, PathBuf};

/// Regular, non-hidden files of a folder, sorted by name.
pub(crate) fn list_files(dir: &Path) -> Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).map_err(io_at(dir))? {
        let e = e.map_err(io_at(dir))?;
        let p = e.path();
        let hidden = e.file_name().to_string_lossy().starts_with('.');
        if !hidden && p.is_file() {
            out.push(p);
        }
    }
    out.sort();
    Ok(out)
}

/// Whether a file has the DICOM preamble and `DICM` magic.
pub(crate) fn looks_like_dicom(p: &Path) -> bool {
    let mut b = [0u8; 132];
    match std::fs::File::open(p) {
        Ok(mut f) => f.read_exact(&mut b).is_ok() && &b[128..] == b"DICM",
        Err(_) => false,
    }
}

/// What the first pass learns about one slice.
#[derive(Clone, Debug)]
struct Slice {
    path: PathBuf,
    series: String,
    ipp: [f64; 3],
    iop: [f64; 6],
    spacing: [f64; 2],
    rows: usize,
    cols: usize,
    bits: u16,
    stored: u16,
    signed: bool,
    slope: f64,
    intercept: f64,
    thickness: Option<f64>,
}

fn dicom_err<E: std::error::Error + Send + Sync + 'static>(
    path: &Path,
    tag: &str,
) -> impl Fn(E) -> ScanError {
    let tag = tag.to_string();
    let path = path.to_path_buf();
    move |e| ScanError::Dicom {
        path: path.clone(),
        tag: tag.clone(),
        source: Box::new(e),
    }
}

fn bad(path: &Path, tag: &str, message: String) -> ScanError {
    ScanError::Header {
        path: path.to_path_buf(),
        location: tag.to_string(),
        message,
    }
}

const TAG_IPP: &str = "(0020,0032) ImagePositionPatient";
const TAG_IOP: &str = "(0020,0037) ImageOrientationPatient";
const TAG_PS: &str = "(0028,0030) PixelSpacing";

fn floats(
    obj: &DefaultDicomObject,
    path: &Path,
    tag: Tag,
    name: &str,
    n: usize,
) -> Result<Option<Vec<f64>>> {
    let Some(e) = obj.element_opt(tag).map_err(dicom_err(path, name))? else {
        return Ok(None);
    };
    let v = e.to_multi_float64().map_err(dicom_err(path, name))?;
    if v.len() != n || v.iter().any(|x| !x.is_finite()) {
        return Err(bad(
            path,
            name,
            format!("expected {n} finite numbers, found {v:?}"),
        ));
    }
    Ok(Some(v))
}

fn int(obj: &DefaultDicomObject, path: &Path, tag: Tag, name: &str) -> Result<Option<i64>> {
    match obj.element_opt(tag).map_err(dicom_err(path, name))? {
        None => Ok(None),
        Some(e) => Ok(Some(e.to_int::<i64>().map_err(dicom_err(path, name))?)),
    }
}

fn required<T>(v: Option<T>, path: &Path, name: &str) -> Result<T> {
    v.ok_or_else(|| bad(path, name, "missing (required for a volume slice)".into()))
}

/// The first pass over one file: attributes up to the pixel data.
/// `None` for a file without an image (DICOMDIR, structured report).
fn read_slice(path: &Path) -> Result<Option<Slice>> {
    let obj = OpenFileOptions::new()
        .read_until(tags::PIXEL_DATA)
        .open_file(path)
        .map_err(dicom_err(path, ""))?;
    let Some(rows) = int(&obj, path, tags::ROWS, "(0028,0010) Rows")? else {
        return Ok(None);
    };
    let cols = required(
        int(&obj, path, tags::COLUMNS, "(0028,0011) Columns")?,
        path,
        "(0028,0011) Columns",
    )?;
    if let Some(frames) = int(
        &obj,
        path,
        tags::NUMBER_OF_FRAMES,
        "(0028,0008) NumberOfFrames",
    )? {
        if frames > 1 {
            return Err(ScanError::Unsupported {
                path: path.to_path_buf(),
                what: format!("a multi-frame image ({frames} frames); only single-frame slice series are read"),
            });
        }
    }
    let spp = int(
        &obj,
        path,
        tags::SAMPLES_PER_PIXEL,
        "(0028,0002) SamplesPerPixel",
    )?
    .unwrap_or(1);
    if spp != 1 {
        return Err(ScanError::Unsupported {
            path: path.to_path_buf(),
            what: format!("(0028,0002) SamplesPerPixel is {spp}; only grey images are read"),
        });
    }
    let bits = required(
        int(
            &obj,
            path,
            tags::BITS_ALLOCATED,
            "(0028,0100) BitsAllocated",
        )?,
        path,
        "(0028,0100) BitsAllocated",
    )?;
    if !matches!(bits, 8 | 16 | 32) {
        return Err(ScanError::Unsupported {
            path: path.to_path_buf(),
            what: format!("(0028,0100) BitsAllocated is {bits}; expected 8, 16 or 32"),
        });
    }
    let stored = int(&obj, path, tags::BITS_STORED, "(0028,0101) BitsStored")?.unwrap_or(bits);
    if !(1..=bits).contains(&stored) {
        return Err(bad(
            path,
            "(0028,0101) BitsStored",
            format!("{stored} is not in 1..={bits}"),
        ));
    }
    let signed = int(
        &obj,
        path,
        tags::PIXEL_REPRESENTATION,
        "(0028,0103) PixelRepresentation",
    )?
    .unwrap_or(0)
        == 1;
    let ipp = required(
        floats(&obj, path, tags::IMAGE_POSITION_PATIENT, TAG_IPP, 3)?,
        path,
        TAG_IPP,
    )?;
    let iop = required(
        floats(&obj, path, tags::IMAGE_ORIENTATION_PATIENT, TAG_IOP, 6)?,
        path,
        TAG_IOP,
    )?;
    let ps = required(
        floats(&obj, path, tags::PIXEL_SPACING, TAG_PS, 2)?,
        path,
        TAG_PS,
    )?;
    if ps.iter().any(|&s| s <= 0.0) {
        return Err(bad(
            path,
            TAG_PS,
            format!("spacing must be positive, found {ps:?}"),
        ));
    }
    let slope = floats(
        &obj,
        path,
        tags::RESCALE_SLOPE,
        "(0028,1053) RescaleSlope",
        1,
    )?
    .map_or(1.0, |v| v[0]);
    let intercept = floats(
        &obj,
        path,
        tags::RESCALE_INTERCEPT,
        "(0028,1052) RescaleIntercept",
        1,
    )?
    .map_or(0.0, |v| v[0]);
    let thickness = floats(
        &obj,
        path,
        tags::SPACING_BETWEEN_SLICES,
        "(0018,0088) SpacingBetweenSlices",
        1,
    )?
    .or(floats(
        &obj,
        path,
        tags::SLICE_THICKNESS,
        "(0018,0050) SliceThickness",
        1,
    )?)
    .map(|v| v[0])
    .filter(|&t| t > 0.0);
    let series = match obj
        .element_opt(tags::SERIES_INSTANCE_UID)
        .map_err(dicom_err(path, "(0020,000E) SeriesInstanceUID"))?
    {
        Some(e) => e
            .to_str()
            .map_err(dicom_err(path, "(0020,000E) SeriesInstanceUID"))?
            .trim_end_matches(['\0', ' '])
            .to_string(),
        None => String::new(),
    };
    if rows <= 0 || cols <= 0 {
        return Err(bad(
            path,
            "(0028,0010) Rows",
            format!("image is {cols} x {rows}"),
        ));
    }
    Ok(Some(Slice {
        path: path.to_path_buf(),
        series,
        ipp: [ipp[0], ipp[1], ipp[2]],
        iop: [iop[0], iop[1], iop[2], iop[3], iop[4], iop[5]],
        spacing: [ps[0], ps[1]],
        rows: rows as usize,
        cols: cols as usize,
        bits: bits as u16,
        stored: stored as u16,
        signed,
        slope,
        intercept,
        thickness,
    }))
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Reads the DICOM series in a folder.
pub fn read_dicom_series(dir: &Path, opts: &ReadOptions, progress: Progress) -> Result<Volume> {
    let files: Vec<PathBuf> = list_files(dir)?
        .into_iter()
        .filter(|p| looks_like_dicom(p))
        .collect();
    if files.is_empty() {
        return Err(ScanError::Unsupported {
            path: dir.to_path_buf(),
            what: "no DICOM files (with the DICM preamble) in the folder".into(),
        });
    }
    let total = files.len() as u64 * 2;
    let mut slices = Vec::new();
    for (i, f) in files.iter().enumerate() {
        if let Some(s) = read_slice(f)? {
            slices.push(s);
        }
        progress(i as u64 + 1, total);
    }
    // One series.
    let mut by_series: BTreeMap<String, Vec<Slice>> = BTreeMap::new();
    for s in slices {
        by_series.entry(s.series.clone()).or_default().push(s);
    }
    let mut slices = match &opts.series {
        Some(uid) => by_series
            .remove(uid)
            .ok_or_else(|| ScanError::MixedSeries {
                dir: dir.to_path_buf(),
                message: format!(
                    "no series {uid}; the folder holds {}",
                    series_list(&by_series)
                ),
            })?,
        None if by_series.len() > 1 => {
            return Err(ScanError::MixedSeries {
                dir: dir.to_path_buf(),
                message: format!(
                    "mixed series: the folder holds {}; choose one by its SeriesInstanceUID",
                    series_list(&by_series)
                ),
            })
        }
        None => by_series.into_values().next().unwrap_or_default(),
    };
    if slices.is_empty() {
        return Err(ScanError::Unsupported {
            path: dir.to_path_buf(),
            what: "the DICOM files hold no images".into(),
        });
    }
    // Same size, pixel format and orientation.
    let s0 = slices[0].clone();
    for s in &slices[1..] {
        let what = if (s.rows, s.cols) != (s0.rows, s0.cols) {
            Some(format!(
                "{} x {} pixels, {} has {} x {}",
                s.cols,
                s.rows,
                s0.path.display(),
                s0.cols,
                s0.rows
            ))
        } else if (s.bits, s.stored, s.signed) != (s0.bits, s0.stored, s0.signed) {
            Some(format!(
                "pixel format {}/{} bits signed={}, {} has {}/{} signed={}",
                s.bits,
                s.stored,
                s.signed,
                s0.path.display(),
                s0.bits,
                s0.stored,
                s0.signed
            ))
        } else if (0..6).any(|i| (s.iop[i] - s0.iop[i]).abs() > 1e-4) {
            Some(format!(
                "orientation {:?}, {} has {:?}",
                s.iop,
                s0.path.display(),
                s0.iop
            ))
        } else if (0..2).any(|i| (s.spacing[i] - s0.spacing[i]).abs() > 1e-4 * s0.spacing[i]) {
            Some(format!(
                "pixel spacing {:?}, {} has {:?}",
                s.spacing,
                s0.path.display(),
                s0.spacing
            ))
        } else {
            None
        };
        if let Some(w) = what {
            return Err(ScanError::MixedSeries {
                dir: dir.to_path_buf(),
                message: format!("{} does not match the series: {w}", s.path.display()),
            });
        }
    }
    let row = [s0.iop[0], s0.iop[1], s0.iop[2]];
    let col = [s0.iop[3], s0.iop[4], s0.iop[5]];
    let normal = cross(row, col);
    let nn = crate::volume::norm(normal);
    if !(nn > 0.5) {
        return Err(bad(
            &s0.path,
            TAG_IOP,
            format!("row and column directions {:?} are not orthonormal", s0.iop),
        ));
    }
    let normal = normal.map(|v| v / nn);
    slices.sort_by(|a, b| {
        dot(a.ipp, normal)
            .total_cmp(&dot(b.ipp, normal))
            .then_with(|| a.path.cmp(&b.path))
    });
    let pos: Vec<f64> = slices.iter().map(|s| dot(s.ipp, normal)).collect();
    let gap = if slices.len() > 1 {
        let g = pos[1] - pos[0];
        for i in 0..slices.len() - 1 {
            let gi = pos[i + 1] - pos[i];
            if !(gi > 1e-3) || (gi - g).abs() > 1e-2 + 5e-3 * g {
                return Err(ScanError::SliceSpacing {
                    dir: dir.to_path_buf(),
                    first: slices[i].path.clone(),
                    second: slices[i + 1].path.clone(),
                    found: gi,
                    expected: g,
                });
            }
            // The in-plane offset must not drift (gantry tilt).
            let d: [f64; 3] = std::array::from_fn(|a| {
                slices[i + 1].ipp[a] - slices[0].ipp[a] - (pos[i + 1] - pos[0]) * normal[a]
            });
            if crate::volume::norm(d) > 1e-2 + 1e-3 * (pos[i + 1] - pos[0]).abs() {
                return Err(ScanError::Unsupported {
                    path: slices[i + 1].path.clone(),
                    what: format!("the slice is shifted by {d:?} mm across the stack (gantry tilt); resample the series to a rectilinear grid first"),
                });
            }
        }
        Some(g)
    } else {
        s0.thickness
    };
    let uniform = slices
        .iter()
        .all(|s| s.slope == s0.slope && s.intercept == s0.intercept);
    let ty = match (s0.bits, s0.signed) {
        (8, false) => FileType::U8,
        (8, true) => FileType::I8,
        (16, false) => FileType::U16,
        (16, true) => FileType::I16,
        (_, false) => FileType::U32,
        (_, true) => FileType::I32,
    };
    let g = gap.unwrap_or(1.0);
    let geometry = Geometry {
        origin: slices[0].ipp,
        // Columns run along the row direction, with the column spacing
        // (PixelSpacing[1]); rows along the column direction.
        dirs: [
            row.map(|v| v * s0.spacing[1]),
            col.map(|v| v * s0.spacing[0]),
            normal.map(|v| v * g),
        ],
        spacing_known: gap.is_some(),
    };
    let dims = [s0.cols, s0.rows, slices.len()];
    let plane = (s0.cols * s0.rows) as u64;
    // The whole file (pixel data and a decoded copy) is held per slice.
    let extra = plane * (s0.bits as u64 / 8) * 3;
    let mut asm = Assembler::new(
        dir,
        dims,
        ty,
        geometry,
        (s0.slope, s0.intercept),
        uniform,
        extra,
        "LPS",
        opts,
    )?;
    for s in &slices {
        asm.add_file(&s.path);
    }
    let n = slices.len() as u64;
    for (z, s) in slices.iter().enumerate() {
        if asm.wants(z) {
            read_pixels(&mut asm, s, z)?;
        }
        progress(n + z as u64 + 1, n * 2);
    }
    asm.finish()
}

fn series_list(m: &BTreeMap<String, Vec<Slice>>) -> String {
    m.iter()
        .map(|(k, v)| {
            format!(
                "{} ({} slices)",
                if k.is_empty() {
                    "<no SeriesInstanceUID>"
                } else {
                    k
                },
                v.len()
            )
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// The second pass over one file: its pixels, as slice `z`.
fn read_pixels(asm: &mut Assembler, s: &Slice, z: usize) -> Result<()> {
    let path = &s.path;
    let obj = dicom_object::open_file(path).map_err(dicom_err(path, ""))?;
    let ts = obj
        .meta()
        .transfer_syntax()
        .trim_end_matches(['\0', ' '])
        .to_string();
    let big = match ts.as_str() {
        "1.2.840.10008.1.2" | "1.2.840.10008.1.2.1" | "1.2.840.10008.1.2.1.99" => false,
        "1.2.840.10008.1.2.2" => true,
        other => {
            return Err(ScanError::Unsupported {
                path: path.clone(),
                what: format!("compressed transfer syntax {other} (JPEG, JPEG 2000, RLE, ...); decompress the series first (e.g. `gdcmconv --raw` or `dcmdjpeg`)"),
            })
        }
    };
    let name = "(7FE0,0010) PixelData";
    let e = obj
        .element(tags::PIXEL_DATA)
        .map_err(dicom_err(path, name))?;
    let n = s.rows * s.cols;
    let scale = (s.slope, s.intercept);
    let mismatch = |found: usize| ScanError::SizeMismatch {
        path: path.clone(),
        what: format!("{name}: samples for {} x {} pixels", s.cols, s.rows),
        expected: n as u64,
        found: found as u64,
    };
    let prim = match e.value() {
        Value::Primitive(p) => p,
        _ => {
            return Err(ScanError::Unsupported {
                path: path.clone(),
                what: format!("{name} is encapsulated (compressed); decompress the series first"),
            })
        }
    };
    let shift = s.bits - s.stored;
    match (s.bits, prim) {
        (8, PrimitiveValue::U8(b)) => {
            if b.len() < n {
                return Err(mismatch(b.len()));
            }
            let b = &b[..n];
            if s.signed {
                let v: Vec<i8> = b.iter().map(|&x| ((x << shift) as i8) >> shift).collect();
                asm.push(z, &v, scale)
            } else {
                let v: Vec<u8> = b.iter().map(|&x| x & (0xffu16 >> shift) as u8).collect();
                asm.push(z, &v, scale)
            }
        }
        (16, p) => {
            let words: Vec<u16> = match p {
                PrimitiveValue::U16(v) => v.to_vec(),
                PrimitiveValue::I16(v) => v.iter().map(|&x| x as u16).collect(),
                PrimitiveValue::U8(b) => b
                    .chunks_exact(2)
                    .map(|c| {
                        if big {
                            u16::from_be_bytes([c[0], c[1]])
                        } else {
                            u16::from_le_bytes([c[0], c[1]])
                        }
                    })
                    .collect(),
                other => {
                    return Err(bad(
                        path,
                        name,
                        format!("unexpected value type {:?}", other.value_type()),
                    ))
                }
            };
            if words.len() < n {
                return Err(mismatch(words.len()));
            }
            let words = &words[..n];
            if s.signed {
                let v: Vec<i16> = words
                    .iter()
                    .map(|&x| ((x << shift) as i16) >> shift)
                    .collect();
                asm.push(z, &v, scale)
            } else {
                let mask = (0xffffu32 >> shift) as u16;
                let v: Vec<u16> = words.iter().map(|&x| x & mask).collect();
                asm.push(z, &v, scale)
            }
        }
        (32, p) => {
            let words: Vec<u32> = match p {
                PrimitiveValue::U32(v) => v.to_vec(),
                PrimitiveValue::I32(v) => v.iter().map(|&x| x as u32).collect(),
                PrimitiveValue::U16(v) => v
                    .chunks_exact(2)
                    .map(|c| c[0] as u32 | (c[1] as u32) << 16)
                    .collect(),
                PrimitiveValue::U8(b) => b
                    .chunks_exact(4)
                    .map(|c| {
                        let a = [c[0], c[1], c[2], c[3]];
                        if big {
                            u32::from_be_bytes(a)
                        } else {
                            u32::from_le_bytes(a)
                        }
                    })
                    .collect(),
                other => {
                    return Err(bad(
                        path,
                        name,
                        format!("unexpected value type {:?}", other.value_type()),
                    ))
                }
            };
            if words.len() < n {
                return Err(mismatch(words.len()));
            }
            let words = &words[..n];
            if s.signed {
                let v: Vec<i32> = words
                    .iter()
                    .map(|&x| ((x << shift) as i32) >> shift)
                    .collect();
                asm.push(z, &v, scale)
            } else {
                let v: Vec<u32> = words.iter().map(|&x| x & (u32::MAX >> shift)).collect();
                asm.push(z, &v, scale)
            }
        }
        (_, other) => Err(bad(
            path,
            name,
            format!(
                "unexpected value type {:?} for {} bits",
                other.value_type(),
                s.bits
            ),
        )),
    }
}
