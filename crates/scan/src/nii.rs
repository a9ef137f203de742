//! NIfTI-1 reader: `.nii`, `.nii.gz`, and `.hdr`/`.img` pairs.
//!
//! The `nifti` crate parses the 348-byte header (field layout, byte order);
//! the voxel data is streamed here slice by slice so the memory check comes
//! before any large allocation. Geometry comes from the sform when its code
//! is set, else the qform, else `pixdim`; `scl_slope`/`scl_inter` give the
//! values; spatial units are converted to mm.

use crate::error::{header, io_at, Result, ScanError};
use crate::volume::{stream_slices, Assembler, FileType, Geometry, Progress, ReadOptions, Volume};
use flate2::read::MultiGzDecoder;
use nifti::NiftiHeader;
use std::fs::File;
use std::io::{BufReader, Read};
use std::path::{Path, PathBuf};

const HEADER_BYTES: usize = 348;

/// Reads a NIfTI-1 volume.
pub fn read_nifti(path: &Path, opts: &ReadOptions, progress: Progress) -> Result<Volume> {
    let mut r = open_maybe_gz(path)?;
    let mut raw = [0u8; HEADER_BYTES];
    let got = crate::volume::read_full(&mut *r, &mut raw).map_err(io_at(path))?;
    if got < HEADER_BYTES {
        return Err(ScanError::Truncated {
            path: path.to_path_buf(),
            offset: 0,
            expected: HEADER_BYTES as u64,
            found: got as u64,
        });
    }
    let size_le = i32::from_le_bytes([raw[0], raw[1], raw[2], raw[3]]);
    let size_be = i32::from_be_bytes([raw[0], raw[1], raw[2], raw[3]]);
    if size_le == 540 || size_be == 540 {
        return Err(ScanError::Unsupported {
            path: path.to_path_buf(),
            what: "NIfTI-2 header (sizeof_hdr 540); convert to NIfTI-1".into(),
        });
    }
    if size_le != 348 && size_be != 348 {
        return Err(header(
            path,
            "sizeof_hdr (byte 0)",
            format!("expected 348, found {size_le} (not a NIfTI-1 file)"),
        ));
    }
    let h = NiftiHeader::from_reader(&raw[..]).map_err(|source| ScanError::Nifti {
        path: path.to_path_buf(),
        source,
    })?;
    let single = &h.magic == nifti::header::MAGIC_CODE_NIP1;
    if !single && &h.magic != nifti::header::MAGIC_CODE_NI1 {
        return Err(header(
            path,
            "magic (byte 344)",
            format!("expected `n+1` or `ni1`, found {:?}", h.magic),
        ));
    }
    let ty = match h.datatype {
        2 => FileType::U8,
        4 => FileType::I16,
        8 => FileType::I32,
        16 => FileType::F32,
        64 => FileType::F64,
        256 => FileType::I8,
        512 => FileType::U16,
        768 => FileType::U32,
        1024 => FileType::I64,
        1280 => FileType::U64,
        other => {
            return Err(ScanError::Unsupported {
                path: path.to_path_buf(),
                what: format!(
                    "datatype {other} (complex, RGB or unknown); only scalar grey volumes are read"
                ),
            })
        }
    };
    let ndim = h.dim[0] as usize;
    if !(1..=7).contains(&ndim) {
        return Err(header(
            path,
            "dim[0] (byte 40)",
            format!("number of dimensions must be 1 to 7, found {ndim}"),
        ));
    }
    let mut dims = [1usize; 3];
    for a in 0..ndim.min(3) {
        dims[a] = h.dim[a + 1] as usize;
        if dims[a] == 0 {
            return Err(header(
                path,
                format!("dim[{}]", a + 1),
                "size 0 on a spatial axis",
            ));
        }
    }
    if let Some(a) = (4..=ndim).find(|&a| h.dim[a] > 1) {
        return Err(ScanError::Unsupported {
            path: path.to_path_buf(),
            what: format!(
                "a {ndim}D image with {} samples on axis {a}; extract one 3D volume first",
                h.dim[a]
            ),
        });
    }
    let unit = match h.xyzt_units & 7 {
        1 => 1000.0,
        3 => 1e-3,
        _ => 1.0, // 2 = mm; 0 = unknown, taken as mm
    };
    let geometry = geometry(&h, unit);
    // scl_slope 0 means "no scaling"; NaN or infinite scaling is broken.
    if !(h.scl_slope.is_finite() && h.scl_inter.is_finite()) {
        return Err(header(
            path,
            "scl_slope / scl_inter (bytes 112, 116)",
            format!(
                "the intensity scaling (slope {}, intercept {}) is not finite",
                h.scl_slope, h.scl_inter
            ),
        ));
    }
    let scale = if h.scl_slope != 0.0 {
        (h.scl_slope as f64, h.scl_inter as f64)
    } else {
        (1.0, 0.0)
    };
    let little = h.endianness == nifti::Endianness::Little;
    let plane = (dims[0] * dims[1] * ty.size()) as u64;
    let mut asm = Assembler::new(
        path,
        dims,
        ty,
        geometry,
        scale,
        true,
        plane * 2,
        "RAS",
        opts,
    )?;
    let vox_offset = h.vox_offset;
    if !(vox_offset.is_finite() && vox_offset >= 0.0) {
        return Err(header(
            path,
            "vox_offset (byte 108)",
            format!("must be a non-negative offset, found {vox_offset}"),
        ));
    }
    let vox_offset = vox_offset as u64;
    let (mut data, data_path, skip) = if single {
        if vox_offset < HEADER_BYTES as u64 {
            return Err(header(
                path,
                "vox_offset (byte 108)",
                format!("must be at least 348 in a .nii file, found {vox_offset}"),
            ));
        }
        (r, path.to_path_buf(), vox_offset - HEADER_BYTES as u64)
    } else {
        let img = image_path(path);
        (open_maybe_gz(&img)?, img, vox_offset)
    };
    let skipped = std::io::copy(&mut (&mut data).take(skip), &mut std::io::sink())
        .map_err(io_at(&data_path))?;
    if skipped < skip {
        return Err(ScanError::Truncated {
            path: data_path,
            offset: vox_offset,
            expected: dims.iter().product::<usize>() as u64 * ty.size() as u64,
            found: 0,
        });
    }
    asm.add_file(&data_path);
    stream_slices(
        &mut asm, &mut *data, ty, little, &data_path, vox_offset, progress,
    )?;
    asm.finish()
}

/// The voxel axes: sform if set, else qform, else pixdim.
fn geometry(h: &NiftiHeader, unit: f64) -> Geometry {
    let pix: [f64; 3] = std::array::from_fn(|a| (h.pixdim[a + 1] as f64).abs() * unit);
    if h.sform_code > 0 {
        let rows = [h.srow_x, h.srow_y, h.srow_z];
        return Geometry {
            origin: std::array::from_fn(|w| rows[w][3] as f64 * unit),
            dirs: std::array::from_fn(|a| std::array::from_fn(|w| rows[w][a] as f64 * unit)),
            spacing_known: true,
        };
    }
    if h.qform_code > 0 {
        let (b, c, d) = (h.quatern_b as f64, h.quatern_c as f64, h.quatern_d as f64);
        let a = (1.0 - (b * b + c * c + d * d)).max(0.0).sqrt();
        let r = [
            [
                a * a + b * b - c * c - d * d,
                2.0 * (b * c - a * d),
                2.0 * (b * d + a * c),
            ],
            [
                2.0 * (b * c + a * d),
                a * a + c * c - b * b - d * d,
                2.0 * (c * d - a * b),
            ],
            [
                2.0 * (b * d - a * c),
                2.0 * (c * d + a * b),
                a * a + d * d - c * c - b * b,
            ],
        ];
        let qfac = if h.pixdim[0] < 0.0 { -1.0 } else { 1.0 };
        return Geometry {
            origin: [h.quatern_x, h.quatern_y, h.quatern_z].map(|v| v as f64 * unit),
            dirs: std::array::from_fn(|a| {
                let s = pix[a] * if a == 2 { qfac } else { 1.0 };
                std::array::from_fn(|w| r[w][a] * s)
            }),
            spacing_known: true,
        };
    }
    Geometry::diagonal(pix, [0.0; 3])
}

/// The `.img` (or `.img.gz`) file of a `.hdr` header.
fn image_path(hdr: &Path) -> PathBuf {
    let name = hdr
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let stem = name
        .strip_suffix(".gz")
        .unwrap_or(&name)
        .strip_suffix(".hdr")
        .unwrap_or(&name)
        .to_string();
    let plain = hdr.with_file_name(format!("{stem}.img"));
    if plain.exists() {
        plain
    } else {
        hdr.with_file_name(format!("{stem}.img.gz"))
    }
}

/// Opens a file, decompressing it when it starts with the gzip magic.
pub(crate) fn open_maybe_gz(path: &Path) -> Result<Box<dyn Read>> {
    let mut f = File::open(path).map_err(io_at(path))?;
    let mut magic = [0u8; 2];
    let n = crate::volume::read_full(&mut f, &mut magic).map_err(io_at(path))?;
    let head = std::io::Cursor::new(magic[..n].to_vec());
    let chained = BufReader::new(head.chain(f));
    Ok(if n == 2 && magic == [0x1f, 0x8b] {
        Box::new(BufReader::new(MultiGzDecoder::new(chained)))
    } else {
        Box::new(chained)
    })
}
