//! Every reader on files written by the test (or by an independent writer:
//! the nifti, tiff and dicom crates, `microfrep voxels`): geometry, values,
//! the signed distance of a ball, and each class of bad input.

use dicom_core::value::PrimitiveValue;
use dicom_core::{DataElement, VR};
use dicom_dictionary_std::tags;
use dicom_object::{FileMetaTableBuilder, InMemDicomObject};
use microfrep_core::{Expr, Field, Shape};
use microfrep_scan::{ReadOptions, SampleType, Samples, ScanError, ScanField, ScanOptions, Volume};
use std::io::Write;
use std::path::{Path, PathBuf};

const C: [f64; 3] = [1.1, -0.4, 2.3];
const R: f64 = 3.0;

/// CT-like ball in HU: -1000 outside, +1000 inside, a ramp 2 mm wide.
fn hu(p: [f64; 3]) -> f64 {
    let d = ((p[0] - C[0]).powi(2) + (p[1] - C[1]).powi(2) + (p[2] - C[2]).powi(2)).sqrt();
    (1000.0 * (R - d)).clamp(-1000.0, 1000.0).round()
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("microfrep-scan-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Every sample of the volume equals `f` at its position.
fn assert_values(v: &Volume, f: impl Fn([f64; 3]) -> f64, tol: f64) {
    for k in 0..v.dims[2] {
        for j in 0..v.dims[1] {
            for i in 0..v.dims[0] {
                let p = v.position([i, j, k]);
                let (got, want) = (v.value(i, j, k), f(p));
                assert!(
                    (got - want).abs() <= tol,
                    "sample ({i}, {j}, {k}) at {p:?}: {got} vs {want}"
                );
            }
        }
    }
}

/// The signed field at `iso` is `R - |p - C|` within `tol` voxels near the
/// surface.
fn assert_ball(v: &Volume, iso: f64, tol: f64) {
    let f = ScanField::build(v, &ScanOptions::new(iso)).unwrap();
    let h = v.spacing.iter().cloned().fold(0.0, f64::max);
    let mut worst = 0.0f64;
    let n = 24;
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let t = [i, j, k].map(|x| (x as f64 + 0.41) / n as f64);
                let p: [f64; 3] = std::array::from_fn(|a| C[a] - R - 1.0 + (2.0 * R + 2.0) * t[a]);
                let want = R
                    - ((p[0] - C[0]).powi(2) + (p[1] - C[1]).powi(2) + (p[2] - C[2]).powi(2))
                        .sqrt();
                if want.abs() < 1.0 {
                    worst = worst.max((f.eval(p) - want).abs());
                }
            }
        }
    }
    assert!(worst <= tol * h, "worst {worst} mm, voxel {h} mm");
}

/// A sampling grid around the ball: file dims, and the world position of
/// file voxel `(a, b, c)` along `dirs` from `origin`.
struct Grid {
    dims: [usize; 3],
    origin: [f64; 3],
    dirs: [[f64; 3]; 3],
}

impl Grid {
    fn iso(h: [f64; 3]) -> Grid {
        let dims: [usize; 3] = std::array::from_fn(|a| ((2.0 * R + 3.0) / h[a]).ceil() as usize);
        Grid {
            dims,
            origin: std::array::from_fn(|a| C[a] - R - 1.5),
            dirs: std::array::from_fn(|a| std::array::from_fn(|w| if a == w { h[a] } else { 0.0 })),
        }
    }
    fn at(&self, idx: [usize; 3]) -> [f64; 3] {
        std::array::from_fn(|w| {
            self.origin[w] + (0..3).map(|a| idx[a] as f64 * self.dirs[a][w]).sum::<f64>()
        })
    }
    /// Values in file order (x fastest).
    fn values(&self, f: impl Fn([f64; 3]) -> f64) -> Vec<f64> {
        let mut v = Vec::new();
        for k in 0..self.dims[2] {
            for j in 0..self.dims[1] {
                for i in 0..self.dims[0] {
                    v.push(f(self.at([i, j, k])));
                }
            }
        }
        v
    }
}

fn vec3(v: [f64; 3]) -> String {
    format!("({},{},{})", v[0], v[1], v[2])
}

fn nrrd_header(g: &Grid, ty: &str, encoding: &str, endian: &str, extra: &str) -> String {
    format!(
        "NRRD0004\n# test\ntype: {ty}\ndimension: 3\nspace: left-posterior-superior\nsizes: {} {} {}\nspace directions: {} {} {}\nspace origin: {}\nkinds: domain domain domain\nendian: {endian}\nencoding: {encoding}\n{extra}",
        g.dims[0], g.dims[1], g.dims[2], vec3(g.dirs[0]), vec3(g.dirs[1]), vec3(g.dirs[2]), vec3(g.origin)
    )
}

fn i16_bytes(v: &[f64], big: bool) -> Vec<u8> {
    v.iter()
        .flat_map(|&x| {
            if big {
                (x as i16).to_be_bytes()
            } else {
                (x as i16).to_le_bytes()
            }
        })
        .collect()
}

#[test]
fn nrrd_raw_both_byte_orders_with_flipped_and_permuted_axes() {
    let d = tmp("nrrd-raw");
    // Little endian, y running backwards.
    let mut g = Grid::iso([0.5, 0.6, 0.7]);
    g.dirs[1] = [0.0, -0.6, 0.0];
    g.origin[1] = C[1] + R + 1.5;
    let p = d.join("flip.nrrd");
    let mut bytes = nrrd_header(&g, "short", "raw", "little", "\n").into_bytes();
    bytes.extend(i16_bytes(&g.values(hu), false));
    std::fs::write(&p, bytes).unwrap();
    let v = Volume::open(&p, &ReadOptions::default()).unwrap();
    assert_eq!(v.dims, g.dims);
    assert_eq!(v.spacing, [0.5, 0.6, 0.7]);
    assert!((v.origin[1] - (g.origin[1] - 0.6 * (g.dims[1] - 1) as f64)).abs() < 1e-9);
    assert_eq!(v.frame, "LPS");
    assert_eq!(v.samples.sample_type(), SampleType::I16);
    assert_values(&v, hu, 0.0);
    assert_ball(&v, 0.0, 0.2);

    // Big endian, file axes (z, x, y).
    let mut g = Grid::iso([0.5, 0.5, 0.5]);
    let (nx, ny, nz) = (g.dims[0], g.dims[1], g.dims[2]);
    g.dims = [nz, nx, ny];
    g.dirs = [[0.0, 0.0, 0.5], [0.5, 0.0, 0.0], [0.0, 0.5, 0.0]];
    let p = d.join("perm.nrrd");
    let mut bytes = nrrd_header(&g, "int16", "raw", "big", "\n").into_bytes();
    bytes.extend(i16_bytes(&g.values(hu), true));
    std::fs::write(&p, bytes).unwrap();
    let v = Volume::open(&p, &ReadOptions::default()).unwrap();
    assert_eq!(v.dims, [nx, ny, nz]);
    assert_values(&v, hu, 0.0);
}

#[test]
fn nrrd_gzip_float_and_detached_header() {
    let d = tmp("nrrd-gz");
    let g = Grid::iso([0.4, 0.4, 0.5]);
    let vals = g.values(hu);
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    for &x in &vals {
        gz.write_all(&(x as f32 / 1000.0).to_le_bytes()).unwrap();
    }
    let data = gz.finish().unwrap();
    let p = d.join("ball.nrrd");
    let mut bytes = nrrd_header(&g, "float", "gzip", "little", "\n").into_bytes();
    bytes.extend(&data);
    std::fs::write(&p, bytes).unwrap();
    let v = Volume::open(&p, &ReadOptions::default()).unwrap();
    assert_eq!(v.samples.sample_type(), SampleType::F32);
    assert_values(&v, |p| hu(p) / 1000.0, 1e-6);
    assert_ball(&v, 0.0, 0.2);

    // Detached: .nhdr naming a raw file next to it, with a byte skip.
    let mut raw = vec![7u8; 5];
    raw.extend(i16_bytes(&vals, false));
    std::fs::write(d.join("ball.raw"), raw).unwrap();
    let h = nrrd_header(
        &g,
        "short",
        "raw",
        "little",
        "byte skip: 5\ndata file: ball.raw\n",
    );
    let p = d.join("ball.nhdr");
    std::fs::write(&p, h).unwrap();
    let v = Volume::open(&p, &ReadOptions::default()).unwrap();
    assert_values(&v, hu, 0.0);
    // Detached gzip.
    std::fs::write(d.join("ball.raw.gz"), &data).unwrap();
    let h = nrrd_header(&g, "float", "gz", "little", "data file: ./ball.raw.gz\n");
    std::fs::write(&p, h).unwrap();
    let v = Volume::open(&p, &ReadOptions::default()).unwrap();
    assert_values(&v, |p| hu(p) / 1000.0, 1e-6);
}

#[test]
fn nrrd_errors_name_the_line_and_the_sizes() {
    let d = tmp("nrrd-bad");
    let g = Grid::iso([0.5; 3]);
    let vals = i16_bytes(&g.values(hu), false);
    let n = vals.len() as u64;
    let head = nrrd_header(&g, "short", "raw", "little", "\n");
    // Truncated data.
    let p = d.join("trunc.nrrd");
    let mut b = head.clone().into_bytes();
    b.extend(&vals[..vals.len() - 100]);
    std::fs::write(&p, b).unwrap();
    match Volume::open(&p, &ReadOptions::default()) {
        Err(ScanError::Truncated {
            expected,
            found,
            offset,
            ..
        }) => {
            assert_eq!((expected, found, offset), (n, n - 100, head.len() as u64));
        }
        other => panic!("{other:?}"),
    }
    // Extra bytes.
    let p = d.join("long.nrrd");
    let mut b = head.clone().into_bytes();
    b.extend(&vals);
    b.extend([0u8; 3]);
    std::fs::write(&p, b).unwrap();
    assert!(
        matches!(Volume::open(&p, &ReadOptions::default()), Err(ScanError::SizeMismatch { expected, found, .. }) if expected == n && found == n + 3)
    );
    // A bad field on line 6.
    let p = d.join("badline.nrrd");
    std::fs::write(&p, head.replacen("sizes: ", "sizes: x", 1)).unwrap();
    match Volume::open(&p, &ReadOptions::default()) {
        Err(e @ ScanError::Header { .. }) => {
            assert!(e.to_string().contains(":line 6: sizes"), "{e}")
        }
        other => panic!("{other:?}"),
    }
    // Not NRRD at all; and a missing data file.
    let p = d.join("junk.nrrd");
    std::fs::write(&p, b"\x00\x01garbage").unwrap();
    assert!(matches!(
        Volume::open(&p, &ReadOptions::default()),
        Err(ScanError::Header { .. })
    ));
    let p = d.join("missing.nhdr");
    std::fs::write(
        &p,
        nrrd_header(&g, "short", "raw", "little", "data file: nowhere.raw\n"),
    )
    .unwrap();
    assert!(
        matches!(Volume::open(&p, &ReadOptions::default()), Err(ScanError::Io { path, .. }) if path.ends_with("nowhere.raw"))
    );
    // A line skip past the end of a detached data file.
    std::fs::write(d.join("lines.raw"), b"one\ntwo\n").unwrap();
    let p = d.join("lineskip.nhdr");
    let h = nrrd_header(
        &g,
        "short",
        "raw",
        "little",
        "data file: lines.raw\nline skip: 5\n",
    );
    std::fs::write(&p, &h).unwrap();
    let e = Volume::open(&p, &ReadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains(":line 13: line skip 5 but") && e.contains("lines.raw ends after 2 lines"),
        "{e}"
    );
    // A byte skip beyond the data file, raw and gzip.
    std::fs::write(d.join("data.raw"), &vals).unwrap();
    let p = d.join("byteskip.nhdr");
    let skip = 2 * n;
    let h = nrrd_header(
        &g,
        "short",
        "raw",
        "little",
        &format!("data file: data.raw\nbyte skip: {skip}\n"),
    );
    std::fs::write(&p, &h).unwrap();
    let e = Volume::open(&p, &ReadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains(":line 13: byte skip") && e.contains(&format!("the file has {n} bytes")),
        "{e}"
    );
    // A detached data file that is a device: refused, not read forever.
    if Path::new("/dev/zero").exists() {
        let p = d.join("device.nhdr");
        let h = nrrd_header(&g, "short", "raw", "little", "data file: /dev/zero\n");
        std::fs::write(&p, &h).unwrap();
        let e = Volume::open(&p, &ReadOptions::default())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("device.nhdr:line 12:") && e.contains("/dev/zero is not a regular file"),
            "{e}"
        );
    }
    // Truncated gzip stream: an error, not a panic.
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    gz.write_all(&vals).unwrap();
    let z = gz.finish().unwrap();
    let p = d.join("trunc-gz.nrrd");
    let mut b = nrrd_header(&g, "short", "gzip", "little", "\n").into_bytes();
    b.extend(&z[..z.len() / 2]);
    std::fs::write(&p, b).unwrap();
    assert!(matches!(
        Volume::open(&p, &ReadOptions::default()),
        Err(ScanError::Io { .. } | ScanError::Truncated { .. })
    ));
    // Oblique axes.
    let mut go = Grid::iso([0.5; 3]);
    let (c, s) = (
        0.5 * 30f64.to_radians().cos(),
        0.5 * 30f64.to_radians().sin(),
    );
    go.dirs[0] = [c, s, 0.0];
    go.dirs[1] = [-s, c, 0.0];
    let p = d.join("oblique.nrrd");
    let mut b = nrrd_header(&go, "short", "raw", "little", "\n").into_bytes();
    b.extend(&vals);
    std::fs::write(&p, b).unwrap();
    assert!(matches!(
        Volume::open(&p, &ReadOptions::default()),
        Err(ScanError::Oblique { .. })
    ));
}

#[test]
fn memory_limit_crop_and_step() {
    let d = tmp("limits");
    let g = Grid::iso([0.25; 3]);
    let p = d.join("ball.nrrd");
    let mut b = nrrd_header(&g, "short", "raw", "little", "\n").into_bytes();
    b.extend(i16_bytes(&g.values(hu), false));
    std::fs::write(&p, b).unwrap();
    let n = g.dims.iter().product::<usize>() as u64;
    let opts = ReadOptions {
        memory_limit: n, // half of what 16-bit samples need
        ..Default::default()
    };
    match Volume::open(&p, &opts) {
        Err(e @ ScanError::TooLarge { .. }) => {
            let m = e.to_string();
            assert!(
                m.contains("over the memory limit") && m.contains("step of 2"),
                "{m}"
            );
        }
        other => panic!("{other:?}"),
    }
    // Downsampled by 2 fits (f32, 1/8 of the voxels) and averages blocks.
    let half = Volume::open(
        &p,
        &ReadOptions {
            step: 2,
            ..opts.clone()
        },
    )
    .unwrap();
    assert_eq!(half.dims, g.dims.map(|d| d.div_ceil(2)));
    assert_eq!(half.spacing, [0.5; 3]);
    let full = Volume::open(&p, &ReadOptions::default()).unwrap();
    let mean: f64 = (0..8)
        .map(|c| full.value(2 + (c & 1), 4 + (c >> 1 & 1), 6 + (c >> 2)))
        .sum::<f64>()
        / 8.0;
    assert!((half.value(1, 2, 3) - mean).abs() < 1e-3);
    let want_origin: [f64; 3] = std::array::from_fn(|a| g.origin[a] + 0.125);
    assert!(
        (0..3).all(|a| (half.origin[a] - want_origin[a]).abs() < 1e-9),
        "{:?}",
        half.origin
    );
    // A crop keeps the file's positions.
    let crop = Volume::open(
        &p,
        &ReadOptions {
            crop: Some([[3, 4, 5], [20, 21, 22]]),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(crop.dims, [17; 3]);
    assert_eq!(crop.value(0, 0, 0), full.value(3, 4, 5));
    assert_eq!(crop.position([0; 3]), full.position([3, 4, 5]));
    assert!(matches!(
        Volume::open(
            &p,
            &ReadOptions {
                crop: Some([[0; 3], [1000, 1, 1]]),
                ..Default::default()
            }
        ),
        Err(ScanError::Invalid(_))
    ));
}

fn nifti_header() -> nifti::NiftiHeader {
    nifti::NiftiHeader {
        xyzt_units: 2, // mm
        ..Default::default()
    }
}

#[test]
fn nifti_nii_and_nii_gz_with_scaling_and_sform() {
    use ndarray::Array3;
    let d = tmp("nifti");
    let g = Grid::iso([0.5, 0.6, 0.5]);
    let [nx, ny, nz] = g.dims;
    // Stored = (HU + 1024) / 2, scl_slope 2, scl_inter -1024; x runs backwards.
    let x0 = C[0] + R + 1.5;
    let pos = |i: usize, j: usize, k: usize| {
        [
            x0 - 0.5 * i as f64,
            g.origin[1] + 0.6 * j as f64,
            g.origin[2] + 0.5 * k as f64,
        ]
    };
    let a = Array3::from_shape_fn((nx, ny, nz), |(i, j, k)| {
        ((hu(pos(i, j, k)) + 1024.0) / 2.0).round() as i16
    });
    let mut h = nifti_header();
    h.scl_slope = 2.0;
    h.scl_inter = -1024.0;
    h.sform_code = 1;
    h.qform_code = 0;
    h.srow_x = [-0.5, 0.0, 0.0, x0 as f32];
    h.srow_y = [0.0, 0.6, 0.0, g.origin[1] as f32];
    h.srow_z = [0.0, 0.0, 0.5, g.origin[2] as f32];
    h.pixdim = [1.0, 0.5, 0.6, 0.5, 1.0, 1.0, 1.0, 1.0];
    // The nifti writer resets the scaling, so it is set in the bytes
    // (scl_slope at byte 112, scl_inter at 116); the .gz is that file
    // compressed.
    let plain = d.join("ball.nii");
    nifti::writer::WriterOptions::new(&plain)
        .reference_header(&h)
        .write_nifti(&a)
        .unwrap();
    let mut bytes = std::fs::read(&plain).unwrap();
    bytes[112..116].copy_from_slice(&2f32.to_le_bytes());
    bytes[116..120].copy_from_slice(&(-1024f32).to_le_bytes());
    std::fs::write(&plain, &bytes).unwrap();
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    gz.write_all(&bytes).unwrap();
    std::fs::write(d.join("ball.nii.gz"), gz.finish().unwrap()).unwrap();
    for name in ["ball.nii", "ball.nii.gz"] {
        let p = d.join(name);
        let v = Volume::open(&p, &ReadOptions::default()).unwrap();
        assert_eq!(v.dims, g.dims, "{name}");
        assert_eq!((v.slope, v.intercept), (2.0, -1024.0));
        assert_eq!(v.frame, "RAS");
        assert!((v.spacing[0] - 0.5).abs() < 1e-6 && (v.spacing[1] - 0.6).abs() < 1e-6);
        // Values at their world positions (within the halving's rounding).
        let f32r = |x: f64| x as f32 as f64;
        assert!((v.origin[0] - f32r(x0) + 0.5 * (nx - 1) as f64).abs() < 1e-5);
        assert_values(&v, |p| 2.0 * ((hu(p) + 1024.0) / 2.0).round() - 1024.0, 2.0);
        assert_ball(&v, 0.0, 0.2);
    }
    // qform only, big endian, u8.
    let mut h = nifti_header();
    h.sform_code = 0;
    h.qform_code = 1;
    h.quatern_x = 1.5;
    h.quatern_y = -2.0;
    h.quatern_z = 3.0;
    h.pixdim = [1.0, 1.0, 2.0, 3.0, 1.0, 1.0, 1.0, 1.0];
    h.endianness = nifti::Endianness::Big;
    let a = Array3::from_shape_fn((4, 3, 2), |(i, j, k)| (i + 10 * j + 100 * k) as u8);
    let p = d.join("q.nii");
    nifti::writer::WriterOptions::new(&p)
        .reference_header(&h)
        .write_nifti(&a)
        .unwrap();
    let v = Volume::open(&p, &ReadOptions::default()).unwrap();
    assert_eq!(
        (v.dims, v.spacing, v.origin),
        ([4, 3, 2], [1.0, 2.0, 3.0], [1.5, -2.0, 3.0])
    );
    assert_eq!(
        v.samples,
        Samples::U8(
            (0..24)
                .map(|n| (n % 4 + 10 * (n / 4 % 3) + 100 * (n / 12)) as u8)
                .collect()
        )
    );
    // Truncated and malformed files.
    let bytes = std::fs::read(&p).unwrap();
    let t = d.join("trunc.nii");
    std::fs::write(&t, &bytes[..bytes.len() - 5]).unwrap();
    assert!(matches!(
        Volume::open(&t, &ReadOptions::default()),
        Err(ScanError::Truncated {
            expected: 24,
            found: 19,
            ..
        })
    ));
    std::fs::write(&t, &bytes[..200]).unwrap();
    assert!(matches!(
        Volume::open(&t, &ReadOptions::default()),
        Err(ScanError::Truncated {
            expected: 348,
            found: 200,
            ..
        })
    ));
    std::fs::write(&t, vec![0u8; 400]).unwrap();
    assert!(matches!(
        Volume::open(&t, &ReadOptions::default()),
        Err(ScanError::Header { .. })
    ));
    // An infinite or NaN scaling is refused, not ignored.
    for bad in [f32::INFINITY, f32::NAN] {
        let mut b = bytes.clone();
        let at = if bad.is_nan() { 116 } else { 112 };
        let v = if h.endianness == nifti::Endianness::Big {
            bad.to_be_bytes()
        } else {
            bad.to_le_bytes()
        };
        b[at..at + 4].copy_from_slice(&v);
        std::fs::write(&t, &b).unwrap();
        let e = Volume::open(&t, &ReadOptions::default()).unwrap_err();
        assert!(e.to_string().contains("not finite"), "{e}");
    }
}

#[test]
fn tiff_multi_page_and_folder_in_natural_order() {
    use tiff::encoder::{colortype, TiffEncoder};
    let d = tmp("tiff");
    let g = Grid::iso([0.5; 3]);
    let [nx, ny, nz] = g.dims;
    let vals = g.values(hu);
    let plane = nx * ny;
    let page = |k: usize| -> Vec<i16> {
        vals[k * plane..(k + 1) * plane]
            .iter()
            .map(|&v| v as i16)
            .collect()
    };
    let p = d.join("stack.tif");
    let mut enc = TiffEncoder::new(std::fs::File::create(&p).unwrap()).unwrap();
    for k in 0..nz {
        enc.write_image::<colortype::GrayI16>(nx as u32, ny as u32, &page(k))
            .unwrap();
    }
    drop(enc);
    // No spacing: a clear error.
    match Volume::open(&p, &ReadOptions::default()) {
        Err(e @ ScanError::Invalid(_)) => assert!(e.to_string().contains("spacing"), "{e}"),
        other => panic!("{other:?}"),
    }
    let opts = ReadOptions {
        spacing: Some([0.5; 3]),
        origin: Some(g.origin),
        ..Default::default()
    };
    let v = Volume::open(&p, &opts).unwrap();
    assert_eq!(v.dims, g.dims);
    assert_values(&v, hu, 0.0);
    assert_ball(&v, 0.0, 0.2);

    // A folder of 16-bit slices named so that plain sorting would be wrong.
    let dir = d.join("slices");
    std::fs::create_dir_all(&dir).unwrap();
    for k in 0..nz {
        let f = std::fs::File::create(dir.join(format!("slice_{}.tif", k + 1))).unwrap();
        let u: Vec<u16> = page(k).iter().map(|&v| (v as i32 + 1024) as u16).collect();
        TiffEncoder::new(f)
            .unwrap()
            .write_image::<colortype::Gray16>(nx as u32, ny as u32, &u)
            .unwrap();
    }
    std::fs::write(dir.join("notes.txt"), "not a slice").unwrap();
    let v = Volume::open(&dir, &opts).unwrap();
    assert_eq!(v.samples.sample_type(), SampleType::U16);
    assert_values(&v, |p| hu(p) + 1024.0, 0.0);
    assert_ball(&v, 1024.0, 0.2);
    // A slice of another size.
    let f = std::fs::File::create(dir.join("slice_99.tif")).unwrap();
    TiffEncoder::new(f)
        .unwrap()
        .write_image::<colortype::Gray16>(3, 3, &[0u16; 9])
        .unwrap();
    assert!(
        matches!(Volume::open(&dir, &opts), Err(ScanError::SizeMismatch { path, .. }) if path.ends_with("slice_99.tif"))
    );
    // Truncated file.
    let bytes = std::fs::read(&p).unwrap();
    let t = d.join("trunc.tif");
    std::fs::write(&t, &bytes[..bytes.len() / 3]).unwrap();
    assert!(matches!(
        Volume::open(&t, &opts),
        Err(ScanError::Tiff { .. })
    ));
}

#[test]
fn natural_order_of_names() {
    let mut v = vec!["s10.tif", "s2.tif", "s1.tif", "s02b.tif", "a.tif"];
    v.sort_by(|a, b| microfrep_scan::tif::natural_cmp(a, b));
    assert_eq!(v, ["a.tif", "s1.tif", "s2.tif", "s02b.tif", "s10.tif"]);
}

/// Writes one CT slice: stored = (HU - intercept) / slope.
#[allow(clippy::too_many_arguments)]
fn write_ct_slice(
    path: &Path,
    series: &str,
    n: usize,
    g: &Grid,
    k: usize,
    z: f64,
    slope: f64,
    intercept: f64,
) {
    let [nx, ny, _] = g.dims;
    let mut px = Vec::with_capacity(nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let p = [
                g.origin[0] + 0.5 * i as f64,
                g.origin[1] + 0.6 * j as f64,
                z,
            ];
            px.push(((hu(p) - intercept) / slope).round() as i16 as u16);
        }
    }
    let ds = |t, v: String| DataElement::new(t, VR::DS, PrimitiveValue::from(v));
    let strs = |t, v: [f64; 3]| {
        DataElement::new(
            t,
            VR::DS,
            PrimitiveValue::Strs(v.map(|x| format!("{x}")).to_vec().into()),
        )
    };
    let uid = format!("2.25.{}{}", 1000 + n, k);
    let obj = InMemDicomObject::from_element_iter([
        DataElement::new(
            tags::SOP_CLASS_UID,
            VR::UI,
            PrimitiveValue::from("1.2.840.10008.5.1.4.1.1.2"),
        ),
        DataElement::new(
            tags::SOP_INSTANCE_UID,
            VR::UI,
            PrimitiveValue::from(uid.as_str()),
        ),
        DataElement::new(tags::MODALITY, VR::CS, PrimitiveValue::from("CT")),
        DataElement::new(
            tags::SERIES_INSTANCE_UID,
            VR::UI,
            PrimitiveValue::from(series),
        ),
        strs(tags::IMAGE_POSITION_PATIENT, [g.origin[0], g.origin[1], z]),
        DataElement::new(
            tags::IMAGE_ORIENTATION_PATIENT,
            VR::DS,
            PrimitiveValue::Strs(
                ["1", "0", "0", "0", "1", "0"]
                    .map(String::from)
                    .to_vec()
                    .into(),
            ),
        ),
        DataElement::new(tags::SAMPLES_PER_PIXEL, VR::US, PrimitiveValue::from(1u16)),
        DataElement::new(
            tags::PHOTOMETRIC_INTERPRETATION,
            VR::CS,
            PrimitiveValue::from("MONOCHROME2"),
        ),
        DataElement::new(tags::ROWS, VR::US, PrimitiveValue::from(ny as u16)),
        DataElement::new(tags::COLUMNS, VR::US, PrimitiveValue::from(nx as u16)),
        DataElement::new(
            tags::PIXEL_SPACING,
            VR::DS,
            PrimitiveValue::Strs(["0.6", "0.5"].map(String::from).to_vec().into()),
        ),
        DataElement::new(tags::BITS_ALLOCATED, VR::US, PrimitiveValue::from(16u16)),
        DataElement::new(tags::BITS_STORED, VR::US, PrimitiveValue::from(16u16)),
        DataElement::new(tags::HIGH_BIT, VR::US, PrimitiveValue::from(15u16)),
        DataElement::new(
            tags::PIXEL_REPRESENTATION,
            VR::US,
            PrimitiveValue::from(1u16),
        ),
        ds(tags::RESCALE_INTERCEPT, format!("{intercept}")),
        ds(tags::RESCALE_SLOPE, format!("{slope}")),
        DataElement::new(tags::PIXEL_DATA, VR::OW, PrimitiveValue::U16(px.into())),
    ]);
    obj.with_meta(FileMetaTableBuilder::new().transfer_syntax("1.2.840.10008.1.2.1"))
        .unwrap()
        .write_to_file(path)
        .unwrap();
}

fn ct_series(
    dir: &Path,
    series: &str,
    skip: Option<usize>,
    slope_of: impl Fn(usize) -> f64,
) -> Grid {
    std::fs::create_dir_all(dir).unwrap();
    let mut g = Grid::iso([0.5, 0.6, 0.7]);
    g.dirs[2] = [0.0, 0.0, 0.7];
    let nz = g.dims[2];
    for k in 0..nz {
        if Some(k) == skip {
            continue;
        }
        // File names in an order unrelated to the position.
        let name = format!("IM{:04}.dcm", (k * 7919) % 1000);
        let z = g.origin[2] + 0.7 * k as f64;
        write_ct_slice(&dir.join(name), series, 0, &g, k, z, slope_of(k), -1024.0);
    }
    g
}

#[test]
fn dicom_series_sorted_by_position_in_hounsfield_units() {
    let d = tmp("dicom");
    let dir = d.join("ct");
    let g = ct_series(&dir, "1.2.3.4", None, |_| 1.0);
    std::fs::write(dir.join("README"), "not dicom").unwrap();
    let v = Volume::open(&dir, &ReadOptions::default()).unwrap();
    assert_eq!(v.dims, g.dims);
    assert_eq!(v.samples.sample_type(), SampleType::I16);
    assert_eq!((v.slope, v.intercept), (1.0, -1024.0));
    assert!((0..3).all(|a| (v.spacing[a] - [0.5, 0.6, 0.7][a]).abs() < 1e-9));
    assert!((0..3).all(|a| (v.origin[a] - g.origin[a]).abs() < 1e-9));
    assert_eq!(v.frame, "LPS");
    assert_values(&v, hu, 0.0);
    assert_ball(&v, 0.0, 0.2);
    // Bone-like threshold at 300 HU: the ball shrinks by 0.3 mm.
    let f = ScanField::build(&v, &ScanOptions::new(300.0)).unwrap();
    let s = f.eval([C[0] + R - 0.3, C[1], C[2]]);
    assert!(s.abs() < 0.05, "{s}");

    // Per-slice rescale slopes: stored as f32 with each slice's scaling.
    let dir2 = d.join("slopes");
    ct_series(
        &dir2,
        "1.2.3.5",
        None,
        |k| if k % 2 == 0 { 1.0 } else { 2.0 },
    );
    let v = Volume::open(&dir2, &ReadOptions::default()).unwrap();
    assert_eq!(v.samples.sample_type(), SampleType::F32);
    assert_values(&v, hu, 1.0);
}

#[test]
fn dicom_errors_for_gaps_mixed_series_and_broken_files() {
    let d = tmp("dicom-bad");
    let dir = d.join("gap");
    ct_series(&dir, "1.2.3.4", Some(5), |_| 1.0);
    match Volume::open(&dir, &ReadOptions::default()) {
        Err(ScanError::SliceSpacing {
            found, expected, ..
        }) => {
            assert!((found - 1.4).abs() < 1e-6 && (expected - 0.7).abs() < 1e-6)
        }
        other => panic!("{other:?}"),
    }
    let dir = d.join("mixed");
    let g = ct_series(&dir, "1.2.3.4", None, |_| 1.0);
    write_ct_slice(
        &dir.join("other.dcm"),
        "9.9.9",
        1,
        &g,
        0,
        100.0,
        1.0,
        -1024.0,
    );
    match Volume::open(&dir, &ReadOptions::default()) {
        Err(e @ ScanError::MixedSeries { .. }) => {
            assert!(e.to_string().contains("9.9.9 (1 slices)"), "{e}")
        }
        other => panic!("{other:?}"),
    }
    // Choosing the series reads it.
    let v = Volume::open(
        &dir,
        &ReadOptions {
            series: Some("1.2.3.4".into()),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(v.dims, g.dims);
    // A truncated slice: an error naming the file.
    let dir = d.join("trunc");
    ct_series(&dir, "1.2.3.4", None, |_| 1.0);
    let f = dir.join("IM0000.dcm");
    let b = std::fs::read(&f).unwrap();
    std::fs::write(&f, &b[..b.len() - 300]).unwrap();
    match Volume::open(&dir, &ReadOptions::default()) {
        Err(e) => assert!(e.to_string().contains("IM0000.dcm"), "{e}"),
        Ok(_) => panic!("truncated slice read"),
    }
    // Memory limit.
    let dir = d.join("big");
    ct_series(&dir, "1.2.3.4", None, |_| 1.0);
    assert!(matches!(
        Volume::open(
            &dir,
            &ReadOptions {
                memory_limit: 5_000,
                ..Default::default()
            }
        ),
        Err(ScanError::TooLarge { .. })
    ));
}

/// The sphere of radius R around C as an FRep model.
fn ball_model() -> Shape {
    let [x, y, z] = Expr::xyz();
    let e = Expr::constant(R)
        - ((x - C[0]).square() + (y - C[1]).square() + (z - C[2]).square()).sqrt();
    Shape::new(e)
}

#[test]
fn microfrep_voxels_outputs_read_back() {
    use microfrep_fab::voxels::{write_voxels, VoxelGrid};
    let d = tmp("voxels");
    let tape = ball_model();
    let min = C.map(|c| c - R - 1.0);
    let max = C.map(|c| c + R + 1.0);
    let grid = VoxelGrid::new(min, max, 0.25).unwrap();
    // f32 field values: the iso-0 surface is the sphere, sub-voxel.
    for name in ["field.raw", "field.nrrd"] {
        let p = d.join(name);
        write_voxels(&tape, &grid, true, &p).unwrap();
        let v = Volume::open(&p, &ReadOptions::default()).unwrap();
        assert_eq!(v.dims, grid.dims);
        assert_eq!(v.spacing, [0.25; 3]);
        assert_eq!(v.origin, grid.origin);
        let model = |p: [f64; 3]| {
            R - ((p[0] - C[0]).powi(2) + (p[1] - C[1]).powi(2) + (p[2] - C[2]).powi(2)).sqrt()
        };
        assert_values(&v, model, 1e-5);
        assert_ball(&v, 0.0, 0.2);
    }
    // Occupancy bytes: the surface is known to half a voxel at best.
    for name in ["occ.raw", "occ.nrrd"] {
        let p = d.join(name);
        write_voxels(&tape, &grid, false, &p).unwrap();
        let v = Volume::open(&p, &ReadOptions::default()).unwrap();
        assert_eq!(v.samples.sample_type(), SampleType::U8);
        assert_ball(&v, 0.5, 1.0);
        // The solid's volume is the ball's within a few percent.
        let f = ScanField::build(&v, &ScanOptions::new(0.5)).unwrap();
        let inside = f.distances().iter().filter(|&&x| x >= 0.0).count() as f64 * 0.25f64.powi(3);
        let want = 4.0 / 3.0 * std::f64::consts::PI * R.powi(3);
        assert!((inside / want - 1.0).abs() < 0.03, "{inside} vs {want}");
    }
    // The sidecar path works too; a raw file of the wrong size does not.
    let v = Volume::open(&d.join("occ.json"), &ReadOptions::default()).unwrap();
    assert_eq!(v.dims, grid.dims);
    let mut f = std::fs::OpenOptions::new()
        .append(true)
        .open(d.join("occ.raw"))
        .unwrap();
    f.write_all(&[0]).unwrap();
    drop(f);
    assert!(matches!(
        Volume::open(&d.join("occ.raw"), &ReadOptions::default()),
        Err(ScanError::SizeMismatch { .. })
    ));
    let n = grid.dims.iter().product::<usize>() as u64;
    std::fs::write(d.join("occ.raw"), vec![0u8; n as usize - 10]).unwrap();
    assert!(
        matches!(Volume::open(&d.join("occ.raw"), &ReadOptions::default()), Err(ScanError::Truncated { expected, found, .. }) if expected == n && found == n - 10)
    );
    std::fs::write(d.join("occ.json"), "{\"dims\": [1, 2]}").unwrap();
    match Volume::open(&d.join("occ.raw"), &ReadOptions::default()) {
        Err(e @ ScanError::Header { .. }) => assert!(e.to_string().contains("dims"), "{e}"),
        other => panic!("{other:?}"),
    }
    std::fs::write(d.join("occ.json"), "{\"dims\": [1, 2").unwrap();
    assert!(matches!(
        Volume::open(&d.join("occ.raw"), &ReadOptions::default()),
        Err(ScanError::Json { .. })
    ));
}

#[test]
fn nrrd_text_and_file_lists() {
    let d = tmp("nrrd-text");
    let g = Grid::iso([0.5; 3]);
    let vals = g.values(hu);
    let text: Vec<String> = vals.iter().map(|v| format!("{v}")).collect();
    let p = d.join("text.nrrd");
    let mut b = nrrd_header(&g, "short", "text", "little", "\n");
    b.push_str(&text.join(" "));
    std::fs::write(&p, &b).unwrap();
    let v = Volume::open(&p, &ReadOptions::default()).unwrap();
    assert_eq!(v.samples.sample_type(), SampleType::I16);
    assert_values(&v, hu, 0.0);
    // One short: truncated, naming the sample count.
    std::fs::write(&p, &b[..b.rfind(' ').unwrap()]).unwrap();
    assert!(matches!(
        Volume::open(&p, &ReadOptions::default()),
        Err(ScanError::Truncated { .. })
    ));
    // A list of slice files.
    let [nx, ny, nz] = g.dims;
    let bytes = i16_bytes(&vals, false);
    let mut list = String::new();
    for k in 0..nz {
        let name = format!("s{k}.raw");
        std::fs::write(
            d.join(&name),
            &bytes[2 * k * nx * ny..2 * (k + 1) * nx * ny],
        )
        .unwrap();
        list.push_str(&name);
        list.push('\n');
    }
    let p = d.join("list.nhdr");
    std::fs::write(
        &p,
        nrrd_header(
            &g,
            "short",
            "raw",
            "little",
            &format!("data file: LIST\n{list}"),
        ),
    )
    .unwrap();
    let v = Volume::open(&p, &ReadOptions::default()).unwrap();
    assert_values(&v, hu, 0.0);
    // The same as a numbered pattern.
    std::fs::write(
        &p,
        nrrd_header(
            &g,
            "short",
            "raw",
            "little",
            &format!("data file: s%d.raw 0 {} 1\n", nz - 1),
        ),
    )
    .unwrap();
    let v = Volume::open(&p, &ReadOptions::default()).unwrap();
    assert_values(&v, hu, 0.0);
    // The volume as a core grid field: the sample at its centre.
    let gf = v.to_grid_field("ct").unwrap();
    assert_eq!(gf.eval(v.position([2, 3, 4])), v.value(2, 3, 4));
}

#[test]
fn nifti_header_and_image_pair() {
    use ndarray::Array3;
    let d = tmp("nifti-pair");
    let a = Array3::from_shape_fn((5, 4, 3), |(i, j, k)| (i * j + k) as f32 * 0.5);
    let mut h = nifti_header();
    h.sform_code = 0;
    h.qform_code = 0;
    h.pixdim = [1.0, 0.001, 0.002, 0.003, 1.0, 1.0, 1.0, 1.0];
    h.xyzt_units = 1; // metres
    let p = d.join("pair.hdr");
    nifti::writer::WriterOptions::new(&p)
        .reference_header(&h)
        .write_nifti(&a)
        .unwrap();
    assert!(d.join("pair.img").exists());
    let v = Volume::open(&p, &ReadOptions::default()).unwrap();
    assert_eq!(v.dims, [5, 4, 3]);
    assert!(
        (0..3).all(|i| (v.spacing[i] - [1.0, 2.0, 3.0][i]).abs() < 1e-4),
        "{:?}",
        v.spacing
    );
    assert_eq!(v.value(3, 2, 1), 3.5);
}

/// The same phantom (the ball at `C`, given in the patient frame LPS) as a
/// DICOM series and as a NIfTI file whose sform is in RAS: read in either
/// frame, the landmark lands at the same world coordinates from both.
#[test]
fn scan_frames_put_a_landmark_at_the_same_place_from_dicom_and_nifti() {
    use microfrep_scan::Frame;
    use ndarray::Array3;
    let d = tmp("frames");
    let dir = d.join("ct");
    let g = ct_series(&dir, "1.2.3.9", None, |_| 1.0);
    let [nx, ny, nz] = g.dims;
    // NIfTI as converters write it from DICOM: RAS = (-x, -y, z) of LPS.
    let lps = |i: usize, j: usize, k: usize| g.at([i, j, k]);
    let a = Array3::from_shape_fn((nx, ny, nz), |(i, j, k)| hu(lps(i, j, k)) as i16);
    let mut h = nifti_header();
    h.sform_code = 1;
    h.qform_code = 0;
    h.srow_x = [-0.5, 0.0, 0.0, -g.origin[0] as f32];
    h.srow_y = [0.0, -0.6, 0.0, -g.origin[1] as f32];
    h.srow_z = [0.0, 0.0, 0.7, g.origin[2] as f32];
    h.pixdim = [1.0, 0.5, 0.6, 0.7, 1.0, 1.0, 1.0, 1.0];
    let nii = d.join("ct.nii");
    nifti::writer::WriterOptions::new(&nii)
        .reference_header(&h)
        .write_nifti(&a)
        .unwrap();
    let ras_c = [-C[0], -C[1], C[2]];
    let voxel_c: [f64; 3] = std::array::from_fn(|a| C[a] - g.origin[a]);
    let cases = [
        (Frame::Lps, "LPS", C),
        (Frame::Ras, "RAS", ras_c),
        (Frame::Voxel, "voxel", voxel_c),
    ];
    for (frame, name, c) in cases {
        for (src, file_frame) in [(&dir, "LPS"), (&nii, "RAS")] {
            let opts = ReadOptions {
                frame,
                ..ReadOptions::default()
            };
            let v = Volume::open(src, &opts).unwrap();
            assert_eq!(v.frame, name, "{}", src.display());
            let f = ScanField::build(&v, &ScanOptions::new(0.0)).unwrap();
            // The centre is deep inside; the surface is R away along each
            // axis, both ways (which places the centre within 0.1 mm).
            let at = |p: [f64; 3]| f.eval(p);
            assert!(at(c) > 2.0, "{name} {}: {}", src.display(), at(c));
            for ax in 0..3 {
                for s in [-1.0, 1.0] {
                    let mut p = c;
                    p[ax] += s * R;
                    assert!(
                        at(p).abs() < 0.1,
                        "{name} {} {p:?}: {}",
                        src.display(),
                        at(p)
                    );
                }
            }
            // Read in its own frame, the file gives its own coordinates.
            let own = Volume::open(src, &ReadOptions::default()).unwrap();
            assert_eq!(own.frame, file_frame);
        }
    }
    // In their own frames the two files disagree: that is what frames fix.
    let own_nii = Volume::open(&nii, &ReadOptions::default()).unwrap();
    let f = ScanField::build(&own_nii, &ScanOptions::new(0.0)).unwrap();
    let off = [C[0] + R, C[1], C[2]];
    let ras_off = [ras_c[0] + R, ras_c[1], ras_c[2]];
    assert!(f.eval(ras_off).abs() < 0.1 && f.eval(off).abs() > 1.0);
    // A file that names no patient frame cannot be moved into one.
    let raw = d.join("plain.nrrd");
    let hdr = format!(
        "NRRD0004\ntype: short\ndimension: 3\nsizes: {nx} {ny} {nz}\nspacings: 0.5 0.6 0.7\n\
         endian: little\nencoding: raw\n\n"
    );
    let mut bytes = hdr.into_bytes();
    bytes.extend(i16_bytes(&g.values(hu), false));
    std::fs::write(&raw, bytes).unwrap();
    let v = Volume::open(&raw, &ReadOptions::default()).unwrap();
    assert_eq!(v.frame, "unknown");
    let opts = ReadOptions {
        frame: Frame::Ras,
        ..ReadOptions::default()
    };
    let e = Volume::open(&raw, &opts).unwrap_err().to_string();
    assert!(
        e.contains("names no patient frame") && e.contains("frame=voxel"),
        "{e}"
    );
    assert_eq!(
        Volume::open(
            &raw,
            &ReadOptions {
                frame: Frame::Voxel,
                ..ReadOptions::default()
            }
        )
        .unwrap()
        .origin,
        [0.0; 3]
    );
    assert_eq!(Frame::parse("RaS"), Some(Frame::Ras));
    assert_eq!(Frame::parse("world"), None);
}
