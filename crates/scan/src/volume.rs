//! The [`Volume`] type every reader produces, the reading options, and the
//! shared machinery of the readers: memory prediction, cropping and
//! downsampling while the slices stream in, and turning a file's voxel axes
//! into axis-aligned ones.

use crate::error::{human, Result, ScanError};
use rayon::prelude::*;
use std::path::{Path, PathBuf};

/// Default memory limit of [`ReadOptions`] and
/// [`ScanOptions`](crate::ScanOptions): 4 GiB.
pub const DEFAULT_MEMORY_LIMIT: u64 = 4 << 30;

/// How samples are stored in memory.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SampleType {
    /// Unsigned 8-bit.
    U8,
    /// Signed 8-bit.
    I8,
    /// Unsigned 16-bit.
    U16,
    /// Signed 16-bit (CT).
    I16,
    /// 32-bit float.
    F32,
}

impl SampleType {
    /// Bytes per sample.
    pub fn size(self) -> usize {
        match self {
            SampleType::U8 | SampleType::I8 => 1,
            SampleType::U16 | SampleType::I16 => 2,
            SampleType::F32 => 4,
        }
    }
}

/// The samples of a volume, x fastest, then y, then z. Integer types are
/// kept compact; [`Volume::slope`] and [`Volume::intercept`] turn them into
/// values. 32-bit and 64-bit integers and doubles in a file are stored as
/// `F32` (with the scaling applied).
#[derive(Clone, Debug, PartialEq)]
pub enum Samples {
    /// Unsigned 8-bit samples.
    U8(Vec<u8>),
    /// Signed 8-bit samples.
    I8(Vec<i8>),
    /// Unsigned 16-bit samples.
    U16(Vec<u16>),
    /// Signed 16-bit samples.
    I16(Vec<i16>),
    /// 32-bit float samples.
    F32(Vec<f32>),
}

impl Samples {
    /// Number of samples.
    pub fn len(&self) -> usize {
        match self {
            Samples::U8(v) => v.len(),
            Samples::I8(v) => v.len(),
            Samples::U16(v) => v.len(),
            Samples::I16(v) => v.len(),
            Samples::F32(v) => v.len(),
        }
    }

    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Storage type.
    pub fn sample_type(&self) -> SampleType {
        match self {
            Samples::U8(_) => SampleType::U8,
            Samples::I8(_) => SampleType::I8,
            Samples::U16(_) => SampleType::U16,
            Samples::I16(_) => SampleType::I16,
            Samples::F32(_) => SampleType::F32,
        }
    }

    /// Raw (unscaled) sample `i` as f64.
    pub fn raw(&self, i: usize) -> f64 {
        match self {
            Samples::U8(v) => v[i] as f64,
            Samples::I8(v) => v[i] as f64,
            Samples::U16(v) => v[i] as f64,
            Samples::I16(v) => v[i] as f64,
            Samples::F32(v) => v[i] as f64,
        }
    }

    fn zeros(ty: SampleType, n: usize) -> Samples {
        match ty {
            SampleType::U8 => Samples::U8(vec![0; n]),
            SampleType::I8 => Samples::I8(vec![0; n]),
            SampleType::U16 => Samples::U16(vec![0; n]),
            SampleType::I16 => Samples::I16(vec![0; n]),
            SampleType::F32 => Samples::F32(vec![0.0; n]),
        }
    }
}

/// A scanned or sampled volume on an axis-aligned grid: sample `(i, j, k)`
/// sits at `origin + (i sx, j sy, k sz)` millimetres (the centre of its
/// voxel), and its value is `slope * raw + intercept` (Hounsfield units for
/// CT). The axes always point along +x, +y, +z of the file's coordinate
/// frame: readers flip and permute axes to get there.
#[derive(Clone, Debug, PartialEq)]
pub struct Volume {
    /// Samples per axis.
    pub dims: [usize; 3],
    /// Distance between sample centres per axis, in mm (positive).
    pub spacing: [f64; 3],
    /// Centre of sample (0, 0, 0), in mm.
    pub origin: [f64; 3],
    /// The samples, x fastest, then y, then z.
    pub samples: Samples,
    /// Value = `slope * raw + intercept`.
    pub slope: f64,
    /// Value = `slope * raw + intercept`.
    pub intercept: f64,
    /// Coordinate frame of the coordinates: the file's own as it names it
    /// (`LPS` for DICOM, `RAS` for NIfTI, NRRD's `space`, or `unknown`)
    /// unless [`ReadOptions::frame`] chose another (`LPS`, `RAS` or
    /// `voxel`).
    pub frame: String,
    /// The file or folder it came from.
    pub source: PathBuf,
    /// Every file read for it (a detached header's data files, a series'
    /// slices, a `.hdr`'s `.img`, a sidecar): the files no output of the
    /// same run may replace.
    pub files: Vec<PathBuf>,
}

/// Options of every reader.
#[derive(Clone, Debug, PartialEq)]
pub struct ReadOptions {
    /// Most bytes the reader may allocate (the volume and its buffers).
    /// A file that needs more is refused before anything large is
    /// allocated, with a crop or step that would fit.
    pub memory_limit: u64,
    /// Voxel index box to keep, `[lo, hi)` per axis, in the file's own
    /// axis order (before any flip or permutation).
    pub crop: Option<[[usize; 3]; 2]>,
    /// Downsampling step: each output voxel is the mean of a `step`^3
    /// block (the result is then stored as f32). 1 keeps full resolution.
    pub step: usize,
    /// Voxel spacing in mm along the file's axes; replaces the file's
    /// (required for TIFF stacks, which carry none reliably).
    pub spacing: Option<[f64; 3]>,
    /// Centre of the file's first voxel in mm; replaces the file's.
    pub origin: Option<[f64; 3]>,
    /// DICOM: the SeriesInstanceUID to read when a folder holds several.
    pub series: Option<String>,
    /// The coordinate frame of the volume's coordinates (default: the
    /// file's own).
    pub frame: Frame,
}

/// The coordinate frame a scan's coordinates are given in.
///
/// Patient frames name where each axis points: `LPS` (DICOM, ITK, and the
/// files 3D Slicer saves) has +x towards the patient's left, +y posterior,
/// +z superior; `RAS` (NIfTI, and 3D Slicer's scene) has +x right, +y
/// anterior, +z superior. The two differ by the sign of x and y.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Frame {
    /// The frame the file names (LPS for DICOM, RAS for NIfTI, NRRD's
    /// `space`; TIFF stacks and raw files name none).
    #[default]
    File,
    /// Left, posterior, superior.
    Lps,
    /// Right, anterior, superior.
    Ras,
    /// The file's voxel grid in millimetres, ignoring its position and
    /// orientation: sample `(i, j, k)` as stored at `(i sx, j sy, k sz)`
    /// (plus [`ReadOptions::origin`] when given).
    Voxel,
}

impl Frame {
    /// Parses `file`, `lps`, `ras` or `voxel` (any case).
    pub fn parse(s: &str) -> Option<Frame> {
        match s.to_ascii_lowercase().as_str() {
            "file" => Some(Frame::File),
            "lps" => Some(Frame::Lps),
            "ras" => Some(Frame::Ras),
            "voxel" => Some(Frame::Voxel),
            _ => None,
        }
    }

    /// Axis signs of a named patient frame relative to RAS.
    fn signs(name: &str) -> Option<[f64; 3]> {
        let n = name.to_ascii_uppercase();
        let b = n.as_bytes();
        if b.len() != 3 {
            return None;
        }
        let s = |c: u8, pos: u8, neg: u8| match c {
            _ if c == pos => Some(1.0),
            _ if c == neg => Some(-1.0),
            _ => None,
        };
        Some([
            s(b[0], b'R', b'L')?,
            s(b[1], b'A', b'P')?,
            s(b[2], b'S', b'I')?,
        ])
    }
}

/// Moves a file's geometry into the frame asked for, returning the frame's
/// name. `file_frame` is what the file names.
fn into_frame(
    g: &mut Geometry,
    file_frame: &str,
    want: Frame,
    opts: &ReadOptions,
    path: &Path,
) -> Result<String> {
    let target = match want {
        Frame::File => return Ok(file_frame.to_string()),
        Frame::Voxel => {
            let s: [f64; 3] = std::array::from_fn(|a| norm(g.dirs[a]));
            *g = Geometry::diagonal(s, opts.origin.unwrap_or([0.0; 3]));
            return Ok("voxel".into());
        }
        Frame::Lps => "LPS",
        Frame::Ras => "RAS",
    };
    let (Some(from), Some(to)) = (Frame::signs(file_frame), Frame::signs(target)) else {
        return Err(ScanError::Invalid(format!(
            "{}: the file names no patient frame ({file_frame}), so it cannot be put in {target}; \
             use frame=file or frame=voxel",
            path.display()
        )));
    };
    let m: [f64; 3] = std::array::from_fn(|w| from[w] * to[w]);
    for w in 0..3 {
        g.origin[w] *= m[w];
        for d in g.dirs.iter_mut() {
            d[w] *= m[w];
        }
    }
    Ok(target.into())
}

impl Default for ReadOptions {
    fn default() -> ReadOptions {
        ReadOptions {
            memory_limit: DEFAULT_MEMORY_LIMIT,
            crop: None,
            step: 1,
            spacing: None,
            origin: None,
            series: None,
            frame: Frame::File,
        }
    }
}

/// Progress callback: `(done, total)` in work units.
pub type Progress<'a> = &'a (dyn Fn(u64, u64) + Sync);

/// A progress callback that ignores its calls.
pub fn no_progress(_: u64, _: u64) {}

impl Volume {
    /// A volume from its parts, checked: positive finite spacing, finite
    /// origin, as many samples as `dims` say, at least one per axis.
    pub fn new(
        dims: [usize; 3],
        spacing: [f64; 3],
        origin: [f64; 3],
        samples: Samples,
    ) -> Result<Volume> {
        let n = checked_count(dims)
            .ok_or_else(|| ScanError::Invalid(format!("volume dims {dims:?} overflow")))?;
        if dims.contains(&0) {
            return Err(ScanError::Invalid(format!(
                "volume dims {dims:?} must be at least 1 on each axis"
            )));
        }
        if samples.len() != n {
            return Err(ScanError::Invalid(format!(
                "volume of dims {dims:?} needs {n} samples, got {}",
                samples.len()
            )));
        }
        for a in 0..3 {
            if !(spacing[a].is_finite() && spacing[a] > 0.0) {
                return Err(ScanError::Invalid(format!(
                    "spacing on axis {a} must be positive and finite, got {}",
                    spacing[a]
                )));
            }
            if !origin[a].is_finite() {
                return Err(ScanError::Invalid(format!(
                    "origin on axis {a} is not finite"
                )));
            }
        }
        Ok(Volume {
            dims,
            spacing,
            origin,
            samples,
            slope: 1.0,
            intercept: 0.0,
            frame: "unknown".into(),
            source: PathBuf::new(),
            files: Vec::new(),
        })
    }

    /// Reads a scan, choosing the reader from the path: a folder of DICOM
    /// files or of TIFF slices, `.nrrd`/`.nhdr`, `.nii`/`.nii.gz`/`.hdr`,
    /// `.tif`/`.tiff`, `.raw` or `.json` (the `microfrep voxels` pair).
    pub fn open(path: &Path, opts: &ReadOptions) -> Result<Volume> {
        Volume::open_with_progress(path, opts, &no_progress)
    }

    /// [`Volume::open`] with a progress callback (slices read, total).
    pub fn open_with_progress(
        path: &Path,
        opts: &ReadOptions,
        progress: Progress,
    ) -> Result<Volume> {
        match Format::detect(path)? {
            Format::Nrrd => crate::nrrd::read_nrrd(path, opts, progress),
            Format::Nifti => crate::nii::read_nifti(path, opts, progress),
            Format::Tiff => crate::tif::read_tiff(path, opts, progress),
            Format::TiffFolder => crate::tif::read_tiff_folder(path, opts, progress),
            Format::Dicom => crate::dcm::read_dicom_series(path, opts, progress),
            Format::Raw => crate::raw::read_raw(path, opts, progress),
        }
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.samples.len()
    }

    /// Whether the volume has no samples (never, for a checked volume).
    pub fn is_empty(&self) -> bool {
        self.samples.is_empty()
    }

    /// Linear index of sample `(i, j, k)`.
    pub fn index(&self, i: usize, j: usize, k: usize) -> usize {
        i + self.dims[0] * (j + self.dims[1] * k)
    }

    /// Value (scaled) of sample `(i, j, k)`.
    pub fn value(&self, i: usize, j: usize, k: usize) -> f64 {
        self.value_at(self.index(i, j, k))
    }

    /// Value (scaled) of sample number `i`.
    pub fn value_at(&self, i: usize) -> f64 {
        self.samples.raw(i) * self.slope + self.intercept
    }

    /// Centre of sample `(i, j, k)` in mm.
    pub fn position(&self, idx: [usize; 3]) -> [f64; 3] {
        std::array::from_fn(|a| self.origin[a] + idx[a] as f64 * self.spacing[a])
    }

    /// The box of the voxels themselves (sample centres, half a voxel out
    /// on every side), `[min, max]` in mm.
    pub fn bounds(&self) -> [[f64; 3]; 2] {
        [
            std::array::from_fn(|a| self.origin[a] - 0.5 * self.spacing[a]),
            std::array::from_fn(|a| self.origin[a] + (self.dims[a] as f64 - 0.5) * self.spacing[a]),
        ]
    }

    /// Smallest and largest value, and the index of the first sample that
    /// is not finite, if any.
    pub fn range(&self) -> (f64, f64, Option<usize>) {
        let n = self.len();
        let chunk = 1 << 16;
        let parts: Vec<(f64, f64, Option<usize>)> = (0..n.div_ceil(chunk))
            .into_par_iter()
            .map(|c| {
                let mut lo = f64::INFINITY;
                let mut hi = f64::NEG_INFINITY;
                let mut bad = None;
                for i in c * chunk..((c + 1) * chunk).min(n) {
                    let v = self.value_at(i);
                    if !v.is_finite() {
                        bad = bad.or(Some(i));
                        continue;
                    }
                    lo = lo.min(v);
                    hi = hi.max(v);
                }
                (lo, hi, bad)
            })
            .collect();
        parts.into_iter().fold(
            (f64::INFINITY, f64::NEG_INFINITY, None),
            |(l, h, b), (pl, ph, pb)| (l.min(pl), h.max(ph), b.or(pb)),
        )
    }

    /// Voxel index `(i, j, k)` of linear index `i`.
    pub fn unindex(&self, i: usize) -> [usize; 3] {
        let [nx, ny, _] = self.dims;
        [i % nx, (i / nx) % ny, i / (nx * ny)]
    }

    /// Bytes the samples take.
    pub fn bytes(&self) -> u64 {
        self.len() as u64 * self.samples.sample_type().size() as u64
    }

    /// All values (scaled) as f32, x fastest.
    pub fn to_f32(&self) -> Vec<f32> {
        (0..self.len())
            .into_par_iter()
            .map(|i| self.value_at(i) as f32)
            .collect()
    }

    /// The intensities as a core [`GridField`](microfrep_core::GridField)
    /// over the sample centres (clamped outside). It holds f64 values and a
    /// per-cell range (24 bytes a sample), so it suits small volumes;
    /// [`IntensityField`](crate::IntensityField) is the compact one.
    pub fn to_grid_field(&self, name: &str) -> Result<microfrep_core::GridField> {
        let max =
            std::array::from_fn(|a| self.origin[a] + (self.dims[a] as f64 - 1.0) * self.spacing[a]);
        let values: Vec<f64> = (0..self.len()).map(|i| self.value_at(i)).collect();
        microfrep_core::GridField::new(name, self.dims, self.origin, max, values).map_err(
            |source| ScanError::Grid {
                path: self.source.clone(),
                source,
            },
        )
    }
}

/// Product of the dims, or `None` on overflow.
pub(crate) fn checked_count(dims: [usize; 3]) -> Option<usize> {
    dims.iter().try_fold(1usize, |n, &d| n.checked_mul(d))
}

/// The file formats [`Volume::open`] knows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// NRRD, attached (`.nrrd`) or detached (`.nhdr`).
    Nrrd,
    /// NIfTI-1, `.nii`, `.nii.gz` or a `.hdr`/`.img` pair.
    Nifti,
    /// One (multi-page) TIFF file.
    Tiff,
    /// A folder of single-page TIFF slices.
    TiffFolder,
    /// A folder of DICOM slices.
    Dicom,
    /// Raw bytes with the JSON sidecar of `microfrep voxels`.
    Raw,
}

impl Format {
    /// The format of a path, from its extension or, for a folder, its files.
    pub fn detect(path: &Path) -> Result<Format> {
        if path.is_dir() {
            let files = crate::dcm::list_files(path)?;
            if files.iter().any(|f| crate::dcm::looks_like_dicom(f)) {
                return Ok(Format::Dicom);
            }
            if files.iter().any(|f| crate::tif::is_tiff_name(f)) {
                return Ok(Format::TiffFolder);
            }
            return Err(ScanError::Unsupported {
                path: path.to_path_buf(),
                what: "folder holds neither DICOM files nor .tif/.tiff slices".into(),
            });
        }
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        let ext = |e: &str| name.ends_with(e);
        if ext(".nrrd") || ext(".nhdr") {
            Ok(Format::Nrrd)
        } else if ext(".nii") || ext(".nii.gz") || ext(".hdr") || ext(".hdr.gz") {
            Ok(Format::Nifti)
        } else if ext(".tif") || ext(".tiff") {
            Ok(Format::Tiff)
        } else if ext(".raw") || ext(".json") {
            Ok(Format::Raw)
        } else if ext(".dcm") {
            Err(ScanError::Unsupported {
                path: path.to_path_buf(),
                what: "a single DICOM file: pass the folder of the series".into(),
            })
        } else {
            Err(ScanError::Unsupported {
                path: path.to_path_buf(),
                what: "unknown extension: expected .nrrd, .nhdr, .nii, .nii.gz, .hdr, .tif, .tiff, .raw, .json or a folder".into(),
            })
        }
    }
}

/// Element type of the samples in a file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum FileType {
    U8,
    I8,
    U16,
    I16,
    U32,
    I32,
    U64,
    I64,
    F32,
    F64,
}

impl FileType {
    pub(crate) fn size(self) -> usize {
        match self {
            FileType::U8 | FileType::I8 => 1,
            FileType::U16 | FileType::I16 => 2,
            FileType::U32 | FileType::I32 | FileType::F32 => 4,
            FileType::U64 | FileType::I64 | FileType::F64 => 8,
        }
    }

    /// How samples of this type are stored at full resolution.
    fn stored(self) -> SampleType {
        match self {
            FileType::U8 => SampleType::U8,
            FileType::I8 => SampleType::I8,
            FileType::U16 => SampleType::U16,
            FileType::I16 => SampleType::I16,
            _ => SampleType::F32,
        }
    }
}

/// A sample type of a file: how it enters the output.
pub(crate) trait Elem: Copy + Send + Sync {
    fn f64(self) -> f64;
    /// Stores at `i` of compact `dst` of the same type, or converts with
    /// `scale` into an f32 `dst`.
    fn put(self, dst: &mut Samples, i: usize, scale: (f64, f64));
}

macro_rules! elem {
    ($t:ty, $var:ident) => {
        impl Elem for $t {
            fn f64(self) -> f64 {
                self as f64
            }
            fn put(self, dst: &mut Samples, i: usize, scale: (f64, f64)) {
                match dst {
                    Samples::$var(v) => v[i] = self,
                    Samples::F32(v) => v[i] = (self as f64 * scale.0 + scale.1) as f32,
                    // The assembler picks compact storage only for its own type.
                    _ => {}
                }
            }
        }
    };
    ($t:ty) => {
        impl Elem for $t {
            fn f64(self) -> f64 {
                self as f64
            }
            fn put(self, dst: &mut Samples, i: usize, scale: (f64, f64)) {
                if let Samples::F32(v) = dst {
                    v[i] = (self as f64 * scale.0 + scale.1) as f32;
                }
            }
        }
    };
}
elem!(u8, U8);
elem!(i8, I8);
elem!(u16, U16);
elem!(i16, I16);
impl Elem for f32 {
    fn f64(self) -> f64 {
        self as f64
    }
    fn put(self, dst: &mut Samples, i: usize, scale: (f64, f64)) {
        if let Samples::F32(v) = dst {
            v[i] = if scale == (1.0, 0.0) {
                self
            } else {
                (self as f64 * scale.0 + scale.1) as f32
            };
        }
    }
}
elem!(u32);
elem!(i32);
elem!(u64);
elem!(i64);
elem!(f64);

/// Where a file's voxels are: `world = origin + sum_a idx[a] * dirs[a]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Geometry {
    pub origin: [f64; 3],
    /// `dirs[a]`: world step of one voxel along file axis `a`.
    pub dirs: [[f64; 3]; 3],
    /// Whether the file gave a spacing at all (TIFF does not).
    pub spacing_known: bool,
}

impl Geometry {
    pub(crate) fn diagonal(spacing: [f64; 3], origin: [f64; 3]) -> Geometry {
        Geometry {
            origin,
            dirs: std::array::from_fn(|a| {
                std::array::from_fn(|w| if a == w { spacing[a] } else { 0.0 })
            }),
            spacing_known: true,
        }
    }

    /// With the options' spacing and origin in place of the file's.
    fn with_overrides(mut self, opts: &ReadOptions, path: &Path) -> Result<Geometry> {
        if let Some(s) = opts.spacing {
            for a in 0..3 {
                if !(s[a].is_finite() && s[a] > 0.0) {
                    return Err(ScanError::Invalid(format!(
                        "spacing option on axis {a} must be positive, got {}",
                        s[a]
                    )));
                }
                let len = norm(self.dirs[a]);
                self.dirs[a] = if len > 0.0 && len.is_finite() {
                    self.dirs[a].map(|v| v / len * s[a])
                } else {
                    std::array::from_fn(|w| if w == a { s[a] } else { 0.0 })
                };
            }
            self.spacing_known = true;
        }
        if let Some(o) = opts.origin {
            if o.iter().any(|v| !v.is_finite()) {
                return Err(ScanError::Invalid("origin option is not finite".into()));
            }
            self.origin = o;
        }
        if !self.spacing_known {
            return Err(ScanError::Invalid(format!(
                "{}: the file carries no voxel spacing; pass the spacing in mm (x, y, z)",
                path.display()
            )));
        }
        for a in 0..3 {
            let len = norm(self.dirs[a]);
            if !(len.is_finite() && len > 0.0) {
                return Err(ScanError::Invalid(format!(
                    "{}: voxel axis {a} has zero or non-finite length {:?}",
                    path.display(),
                    self.dirs[a]
                )));
            }
        }
        if self.origin.iter().any(|v| !v.is_finite()) {
            return Err(ScanError::Invalid(format!(
                "{}: origin {:?} is not finite",
                path.display(),
                self.origin
            )));
        }
        Ok(self)
    }

    /// The signed permutation the axes make: `perm[a]` is the world axis of
    /// file axis `a`, `flip[a]` whether it runs backwards.
    fn axes(&self, path: &Path) -> Result<([usize; 3], [bool; 3])> {
        let mut perm = [0; 3];
        let mut flip = [false; 3];
        let matrix: [[f64; 3]; 3] =
            std::array::from_fn(|w| std::array::from_fn(|a| self.dirs[a][w]));
        for a in 0..3 {
            let d = self.dirs[a];
            let len = norm(d);
            let w = (0..3)
                .max_by(|&p, &q| d[p].abs().total_cmp(&d[q].abs()))
                .unwrap_or(a);
            let off = (0..3)
                .filter(|&q| q != w)
                .map(|q| d[q].abs())
                .fold(0.0, f64::max);
            if off > 1e-4 * len || perm[..a].contains(&w) {
                return Err(ScanError::Oblique {
                    path: path.to_path_buf(),
                    matrix,
                });
            }
            perm[a] = w;
            flip[a] = d[w] < 0.0;
        }
        Ok((perm, flip))
    }
}

/// Length of `v`, scaled so that very large and very small finite
/// components neither overflow nor underflow.
pub(crate) fn norm(v: [f64; 3]) -> f64 {
    let m = v.iter().fold(0.0f64, |m, c| m.max(c.abs()));
    if m == 0.0 || !m.is_finite() {
        return m;
    }
    let s = v.map(|c| c / m);
    m * (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]).sqrt()
}

/// Collects the slices of a file into a [`Volume`], keeping only the crop,
/// averaging `step`^3 blocks, after checking the memory it will need.
pub(crate) struct Assembler {
    path: PathBuf,
    file_dims: [usize; 3],
    lo: [usize; 3],
    hi: [usize; 3],
    step: usize,
    out_dims: [usize; 3],
    out: Samples,
    /// Downsampling: sums and counts of the current output plane.
    acc: Vec<f64>,
    count: Vec<u32>,
    acc_z: Option<usize>,
    geometry: Geometry,
    perm: [usize; 3],
    flip: [bool; 3],
    /// Global scale for compact storage.
    scale: (f64, f64),
    compact: bool,
    frame: String,
    /// Files read besides `path`.
    files: Vec<PathBuf>,
}

impl Assembler {
    /// Plans the output of a file of `file_dims` samples of `ty`. `extra`
    /// is what the reader itself holds meanwhile (slice buffers).
    /// `uniform_scale` is false when slices carry their own scaling (the
    /// samples are then stored as f32 with it applied).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn new(
        path: &Path,
        file_dims: [usize; 3],
        ty: FileType,
        geometry: Geometry,
        scale: (f64, f64),
        uniform_scale: bool,
        extra: u64,
        frame: &str,
        opts: &ReadOptions,
    ) -> Result<Assembler> {
        if file_dims.contains(&0) {
            return Err(ScanError::Invalid(format!(
                "{}: volume dims {file_dims:?} must be at least 1 on each axis",
                path.display()
            )));
        }
        if checked_count(file_dims).is_none() {
            return Err(ScanError::Invalid(format!(
                "{}: volume dims {file_dims:?} overflow",
                path.display()
            )));
        }
        if !(scale.0.is_finite() && scale.1.is_finite()) {
            return Err(ScanError::Invalid(format!(
                "{}: intensity scaling (slope {}, intercept {}) is not finite",
                path.display(),
                scale.0,
                scale.1
            )));
        }
        let mut geometry = geometry.with_overrides(opts, path)?;
        let frame = into_frame(&mut geometry, frame, opts.frame, opts, path)?;
        let (perm, flip) = geometry.axes(path)?;
        let (lo, hi) = match opts.crop {
            None => ([0; 3], file_dims),
            Some([lo, hi]) => {
                for a in 0..3 {
                    if !(lo[a] < hi[a] && hi[a] <= file_dims[a]) {
                        return Err(ScanError::Invalid(format!(
                            "{}: crop {lo:?}..{hi:?} on axis {a} is empty or outside the volume's {file_dims:?} voxels",
                            path.display()
                        )));
                    }
                }
                (lo, hi)
            }
        };
        let step = opts.step;
        if step == 0 {
            return Err(ScanError::Invalid(
                "downsampling step must be at least 1".into(),
            ));
        }
        let out_dims: [usize; 3] = std::array::from_fn(|a| (hi[a] - lo[a]).div_ceil(step));
        let n = out_dims.iter().product::<usize>();
        let compact = step == 1 && uniform_scale;
        let stored = if compact {
            ty.stored()
        } else {
            SampleType::F32
        };
        let plane = (out_dims[0] * out_dims[1]) as u64;
        let acc_bytes = if step > 1 { plane * 12 } else { 0 };
        let identity = perm == [0, 1, 2];
        let copy = if identity { 1 } else { 2 };
        let need = n as u64 * stored.size() as u64 * copy + acc_bytes + extra;
        if need > opts.memory_limit {
            return Err(too_large(
                &format!(
                    "{} ({} x {} x {} voxels of {} bytes)",
                    path.display(),
                    out_dims[0],
                    out_dims[1],
                    out_dims[2],
                    stored.size()
                ),
                need,
                opts.memory_limit,
                file_dims,
                [lo, hi],
                stored.size() as u64,
                copy,
            ));
        }
        let compact_scale = if compact { scale } else { (1.0, 0.0) };
        Ok(Assembler {
            path: path.to_path_buf(),
            file_dims,
            lo,
            hi,
            step,
            out_dims,
            out: Samples::zeros(stored, n),
            acc: vec![0.0; if step > 1 { plane as usize } else { 0 }],
            count: vec![0; if step > 1 { plane as usize } else { 0 }],
            acc_z: None,
            geometry,
            perm,
            flip,
            scale: compact_scale,
            compact,
            frame,
            files: Vec::new(),
        })
    }

    /// Records a file read for this volume (see [`Volume::files`]).
    pub(crate) fn add_file(&mut self, p: &Path) {
        if p != self.path && !self.files.iter().any(|f| f == p) {
            self.files.push(p.to_path_buf());
        }
    }

    /// The file's dims.
    pub(crate) fn file_dims(&self) -> [usize; 3] {
        self.file_dims
    }

    /// Whether file slice `z` contributes.
    pub(crate) fn wants(&self, z: usize) -> bool {
        z >= self.lo[2] && z < self.hi[2]
    }

    /// Takes file slice `z` (x fastest, `nx * ny` samples) with its
    /// scaling (used when the output is f32).
    pub(crate) fn push<T: Elem>(&mut self, z: usize, plane: &[T], scale: (f64, f64)) -> Result<()> {
        let [nx, ny, _] = self.file_dims;
        if plane.len() != nx * ny {
            return Err(ScanError::SizeMismatch {
                path: self.path.clone(),
                what: format!("samples in slice {z}"),
                expected: (nx * ny) as u64,
                found: plane.len() as u64,
            });
        }
        if !self.wants(z) {
            return Ok(());
        }
        let scale = if self.compact { self.scale } else { scale };
        let [ox, oy, _] = self.out_dims;
        let (lo, hi) = (self.lo, self.hi);
        if self.step == 1 {
            let base = (z - lo[2]) * ox * oy;
            for j in lo[1]..hi[1] {
                let row = &plane[nx * j + lo[0]..nx * j + hi[0]];
                let o = base + (j - lo[1]) * ox;
                for (i, &v) in row.iter().enumerate() {
                    v.put(&mut self.out, o + i, scale);
                }
            }
            return Ok(());
        }
        let s = self.step;
        let oz = (z - lo[2]) / s;
        if self.acc_z != Some(oz) {
            self.flush();
            self.acc_z = Some(oz);
        }
        for j in lo[1]..hi[1] {
            let orow = (j - lo[1]) / s * ox;
            for i in lo[0]..hi[0] {
                let o = orow + (i - lo[0]) / s;
                self.acc[o] += plane[nx * j + i].f64() * scale.0 + scale.1;
                self.count[o] += 1;
            }
        }
        Ok(())
    }

    /// Writes the pending downsampled plane.
    fn flush(&mut self) {
        if let (Some(oz), Samples::F32(out)) = (self.acc_z.take(), &mut self.out) {
            let plane = self.acc.len();
            for (o, (a, c)) in out[oz * plane..(oz + 1) * plane]
                .iter_mut()
                .zip(self.acc.iter_mut().zip(self.count.iter_mut()))
            {
                *o = if *c > 0 { (*a / *c as f64) as f32 } else { 0.0 };
                *a = 0.0;
                *c = 0;
            }
        }
    }

    /// The volume, axis-aligned.
    pub(crate) fn finish(mut self) -> Result<Volume> {
        self.flush();
        let g = self.geometry;
        // Centre of output voxel 0 and the output steps, in file axes.
        let c: [f64; 3] =
            std::array::from_fn(|a| self.lo[a] as f64 + (self.step as f64 - 1.0) * 0.5);
        let mut origin = g.origin;
        for a in 0..3 {
            for w in 0..3 {
                origin[w] += c[a] * g.dirs[a][w];
            }
        }
        let dirs: [[f64; 3]; 3] = g.dirs.map(|d| d.map(|v| v * self.step as f64));
        let mut spacing = [0.0; 3];
        let mut dims = [0; 3];
        for a in 0..3 {
            let w = self.perm[a];
            spacing[w] = norm(dirs[a]);
            dims[w] = self.out_dims[a];
            if self.flip[a] {
                for (q, o) in origin.iter_mut().enumerate() {
                    *o += dirs[a][q] * (self.out_dims[a] as f64 - 1.0);
                }
            }
        }
        let samples = reorient(self.out, self.out_dims, self.perm, self.flip);
        let mut v = Volume::new(dims, spacing, origin, samples)?;
        v.slope = self.scale.0;
        v.intercept = self.scale.1;
        v.frame = self.frame;
        v.files = std::iter::once(self.path.clone())
            .filter(|p| p.is_file())
            .chain(self.files)
            .collect();
        v.source = self.path;
        Ok(v)
    }
}

/// The error for a volume over the limit, with a step and a crop that fit.
/// `size` is the stored bytes per voxel, `copy` 2 when the axes must be
/// permuted into a second buffer.
pub(crate) fn too_large(
    what: &str,
    need: u64,
    limit: u64,
    file_dims: [usize; 3],
    crop: [[usize; 3]; 2],
    size: u64,
    copy: u64,
) -> ScanError {
    let [lo, hi] = crop;
    let n = (0..3).map(|a| (hi[a] - lo[a]) as f64).product::<f64>();
    let fit = (limit as f64 / (size * copy) as f64).max(1.0);
    // Downsampled voxels are f32.
    let mut step = 2usize;
    while n / (step as f64).powi(3) * (4 * copy) as f64 > limit as f64 && step < 256 {
        step += 1;
    }
    let side = fit.cbrt().floor() as usize;
    ScanError::TooLarge {
        what: what.to_string(),
        need,
        limit,
        hint: format!(
            "{} voxels fit (about {side}^3): crop the {} x {} x {} volume to fewer voxels, use a downsampling step of {step}, or raise the limit",
            fit as u64, file_dims[0], file_dims[1], file_dims[2]
        ),
    }
}

/// Applies flips in place, or a permutation (with flips) into a new
/// buffer: new axis `perm[a]` is old axis `a`.
fn reorient(s: Samples, dims: [usize; 3], perm: [usize; 3], flip: [bool; 3]) -> Samples {
    fn go<T: Copy + Send + Sync + Default>(
        mut v: Vec<T>,
        dims: [usize; 3],
        perm: [usize; 3],
        flip: [bool; 3],
    ) -> Vec<T> {
        let [nx, ny, nz] = dims;
        if perm == [0, 1, 2] {
            let plane = nx * ny;
            if flip[0] {
                v.par_chunks_mut(nx).for_each(|r| r.reverse());
            }
            if flip[1] {
                v.par_chunks_mut(plane).for_each(|p| {
                    for j in 0..ny / 2 {
                        let (a, b) = p.split_at_mut((ny - 1 - j) * nx);
                        a[j * nx..(j + 1) * nx].swap_with_slice(&mut b[..nx]);
                    }
                });
            }
            if flip[2] {
                for k in 0..nz / 2 {
                    let (a, b) = v.split_at_mut((nz - 1 - k) * plane);
                    a[k * plane..(k + 1) * plane].swap_with_slice(&mut b[..plane]);
                }
            }
            return v;
        }
        let mut nd = [0; 3];
        for a in 0..3 {
            nd[perm[a]] = dims[a];
        }
        let mut out = vec![T::default(); v.len()];
        let strides = [1, nx, nx * ny];
        out.par_chunks_mut(nd[0] * nd[1])
            .enumerate()
            .for_each(|(k, p)| {
                for j in 0..nd[1] {
                    for i in 0..nd[0] {
                        let new = [i, j, k];
                        let mut old = 0;
                        for a in 0..3 {
                            let x = new[perm[a]];
                            let x = if flip[a] { dims[a] - 1 - x } else { x };
                            old += x * strides[a];
                        }
                        p[i + nd[0] * j] = v[old];
                    }
                }
            });
        out
    }
    match s {
        Samples::U8(v) => Samples::U8(go(v, dims, perm, flip)),
        Samples::I8(v) => Samples::I8(go(v, dims, perm, flip)),
        Samples::U16(v) => Samples::U16(go(v, dims, perm, flip)),
        Samples::I16(v) => Samples::I16(go(v, dims, perm, flip)),
        Samples::F32(v) => Samples::F32(go(v, dims, perm, flip)),
    }
}

/// Decodes `bytes` of `ty` with the given byte order into a typed plane
/// and pushes it as slice `z`.
pub(crate) fn push_bytes(
    asm: &mut Assembler,
    z: usize,
    bytes: &[u8],
    ty: FileType,
    little: bool,
    scale: (f64, f64),
) -> Result<()> {
    macro_rules! conv {
        ($t:ty, $n:expr) => {{
            let v: Vec<$t> = bytes
                .chunks_exact($n)
                .map(|c| {
                    let a: [u8; $n] = c.try_into().unwrap_or([0; $n]);
                    if little {
                        <$t>::from_le_bytes(a)
                    } else {
                        <$t>::from_be_bytes(a)
                    }
                })
                .collect();
            asm.push(z, &v, scale)
        }};
    }
    match ty {
        FileType::U8 => asm.push(z, bytes, scale),
        FileType::I8 => {
            let v: Vec<i8> = bytes.iter().map(|&b| b as i8).collect();
            asm.push(z, &v, scale)
        }
        FileType::U16 => conv!(u16, 2),
        FileType::I16 => conv!(i16, 2),
        FileType::U32 => conv!(u32, 4),
        FileType::I32 => conv!(i32, 4),
        FileType::U64 => conv!(u64, 8),
        FileType::I64 => conv!(i64, 8),
        FileType::F32 => conv!(f32, 4),
        FileType::F64 => conv!(f64, 8),
    }
}

/// Reads slice after slice of `ty` from `r` into `asm`, stopping after the
/// last slice the crop wants. `offset` is where the data starts (for the
/// error message of a truncated file).
pub(crate) fn stream_slices(
    asm: &mut Assembler,
    r: &mut dyn std::io::Read,
    ty: FileType,
    little: bool,
    path: &Path,
    offset: u64,
    progress: Progress,
) -> Result<()> {
    let [nx, ny, nz] = asm.file_dims();
    let plane = nx * ny * ty.size();
    let mut buf = vec![0u8; plane];
    let total = nz as u64 * plane as u64;
    let last = (0..nz).rev().find(|&z| asm.wants(z)).unwrap_or(0);
    for z in 0..=last {
        let got = read_full(r, &mut buf).map_err(crate::error::io_at(path))?;
        if got < plane {
            return Err(ScanError::Truncated {
                path: path.to_path_buf(),
                offset,
                expected: total,
                found: z as u64 * plane as u64 + got as u64,
            });
        }
        push_bytes(asm, z, &buf, ty, little, (1.0, 0.0))?;
        progress(z as u64 + 1, last as u64 + 1);
    }
    Ok(())
}

/// Fills `buf` as far as the stream allows; the count read.
pub(crate) fn read_full(r: &mut dyn std::io::Read, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut n = 0;
    while n < buf.len() {
        match r.read(&mut buf[n..]) {
            Ok(0) => break,
            Ok(k) => n += k,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(n)
}

/// Predicted bytes for a volume of `dims` stored as `ty`, for planning.
pub fn predict_bytes(dims: [usize; 3], ty: SampleType) -> u64 {
    dims.iter().map(|&d| d as u64).product::<u64>() * ty.size() as u64
}

/// A short description of a byte count, for messages.
pub fn describe_bytes(bytes: u64) -> String {
    human(bytes)
}
