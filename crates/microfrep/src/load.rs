//! The one loader of models: a HyperFun file, a triangle mesh, a volume
//! image, a built-in example, each into a [`Shape`].
//!
//! A source is written `PATH[:key=value,...]` (or an example name). The
//! keys of each kind:
//! - meshes (`.stl`, `.obj`, `.ply`, `.3mf`): `weld=TOL` (merge vertices
//!   closer than TOL; default 0, exact duplicates), `sign=auto|winding|normal`;
//! - scans (`.nrrd`, `.nhdr`, `.nii`, `.nii.gz`, `.tif`, `.tiff`, a folder
//!   of TIFF or DICOM slices, `.raw` with its `.json`): `iso=V` (required:
//!   the value at and above which a voxel is inside), `smooth=MM`,
//!   `spacing=X,Y,Z` (TIFF), `step=N`, `series=UID` (DICOM);
//! - data (`.csv`, only as a `--field`): `mode=interpolate|weights`.
//!
//! HyperFun models may call such sources by name: [`LoadOptions::fields`]
//! binds `NAME=SOURCE` as a function `NAME(x[3])` (the `--field` option of
//! every verb).

use microfrep_core::{Bounds, Expr, Field, Interval, Shape};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// What a source turned out to be.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SourceKind {
    /// A HyperFun file.
    HyperFun,
    /// A triangle mesh.
    Mesh,
    /// A volume image.
    Scan,
    /// Measured data on a grid (a Bernstein-Bezier field).
    Data,
    /// A built-in example model.
    Example,
}

/// A source and its options, parsed from `PATH[:key=value,...]`.
#[derive(Clone, Debug, PartialEq)]
pub struct Source {
    /// The file, folder or example name.
    pub path: String,
    /// The `key=value` options after the colon.
    pub options: BTreeMap<String, String>,
}

impl Source {
    /// Parses `PATH[:key=value,...]`. A colon followed by no `=` is part of
    /// the path (so `C:\x` and `a:b.stl` stay paths).
    pub fn parse(s: &str) -> Result<Source, LoadError> {
        if let Some((p, opts)) = s.rsplit_once(':') {
            if opts.contains('=') && !p.is_empty() {
                let mut options: BTreeMap<String, String> = BTreeMap::new();
                // A token without `=` continues the previous value, so a
                // vector reads as `spacing=0.5,0.5,1` (or `0.5x0.5x1`).
                let mut last: Option<String> = None;
                for kv in opts.split(',').filter(|t| !t.trim().is_empty()) {
                    match (kv.split_once('='), &last) {
                        (Some((k, v)), _) => {
                            let k = k.trim().to_ascii_lowercase();
                            options.insert(k.clone(), v.trim().to_string());
                            last = Some(k);
                        }
                        (None, Some(k)) => {
                            let v = options.get_mut(k).expect("the last key is present");
                            v.push(',');
                            v.push_str(kv.trim());
                        }
                        (None, None) => {
                            return Err(LoadError::Options {
                                source_name: s.to_string(),
                                message: format!("'{kv}' is not key=value"),
                            })
                        }
                    }
                }
                return Ok(Source {
                    path: p.to_string(),
                    options,
                });
            }
        }
        Ok(Source {
            path: s.to_string(),
            options: BTreeMap::new(),
        })
    }

    fn number(&self, key: &str) -> Result<Option<f64>, LoadError> {
        match self.options.get(key) {
            None => Ok(None),
            Some(v) => v
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .map(Some)
                .ok_or_else(|| self.bad(format!("{key}={v} is not a finite number"))),
        }
    }

    fn bad(&self, message: String) -> LoadError {
        LoadError::Options {
            source_name: self.path.clone(),
            message,
        }
    }

    fn check_keys(&self, allowed: &[&str]) -> Result<(), LoadError> {
        match self.options.keys().find(|k| !allowed.contains(&k.as_str())) {
            Some(k) => Err(self.bad(format!(
                "unknown option '{k}' (this kind of file takes: {})",
                allowed.join(", ")
            ))),
            None => Ok(()),
        }
    }
}

/// Progress of a long load: (stage, done, total).
pub type Progress<'a> = &'a (dyn Fn(&str, u64, u64) + Sync);

/// How to load.
#[derive(Clone, Default)]
pub struct LoadOptions {
    /// HyperFun object to evaluate (default `my_model`, else the first).
    pub object: Option<String>,
    /// HyperFun parameters `a[k] = v` as `(k, v)`, 1-based.
    pub params: Vec<(usize, f64)>,
    /// Sources bound as HyperFun functions: `(NAME, SOURCE)`.
    pub fields: Vec<(String, String)>,
    /// Bytes readers and field builders may use; default: what the process
    /// may allocate ([`microfrep_io::limits::memory_limit`]).
    pub memory_limit: Option<u64>,
}

/// A loaded model.
pub struct Loaded {
    /// The model every consumer takes.
    pub shape: Shape,
    /// What the source was.
    pub kind: SourceKind,
    /// The lowered HyperFun model (HyperFun sources only).
    pub hyperfun: Option<microfrep_hyperfun::Model>,
    /// Warnings for the user (an open mesh, a repaired orientation, ...).
    pub notes: Vec<String>,
    /// Files read, to protect them from being overwritten by outputs.
    pub inputs: Vec<PathBuf>,
}

/// Why a model could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    /// A HyperFun file with errors (rendered with source lines and carets
    /// by [`microfrep_hyperfun::Diagnostics::render`]).
    #[error("{0}")]
    HyperFun(#[source] microfrep_hyperfun::Diagnostics),
    /// A file could not be read.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// A mesh file is malformed.
    #[error(transparent)]
    MeshRead(#[from] microfrep_meshfield::read::ReadError),
    /// A mesh cannot become a field.
    #[error("{path}: {source}")]
    MeshField {
        /// The file.
        path: PathBuf,
        /// The cause.
        #[source]
        source: microfrep_meshfield::MeshError,
    },
    /// A 3MF package is malformed.
    #[error(transparent)]
    ThreeMf(#[from] microfrep_3mf::Error),
    /// A 3MF package read as an input part is malformed or too large: the
    /// package's error (which names the part and the byte in it) under
    /// the file's name.
    #[error("{path}: {source}")]
    ThreeMfFile {
        /// The package.
        path: PathBuf,
        /// The cause.
        #[source]
        source: microfrep_3mf::Error,
    },
    /// A volume image is malformed or too large.
    #[error(transparent)]
    Scan(#[from] microfrep_scan::ScanError),
    /// Measured data is malformed.
    #[error(transparent)]
    Data(#[from] microfrep_graded::Error),
    /// Bad options of a source.
    #[error("{source_name}: {message}")]
    Options {
        /// The source.
        source_name: String,
        /// What is wrong.
        message: String,
    },
    /// The name is no file and no example.
    #[error("unknown model '{name}': not a file, and not a built-in example (known: {known})")]
    Unknown {
        /// The name given.
        name: String,
        /// The examples.
        known: String,
    },
}

fn limit(opts: &LoadOptions) -> u64 {
    opts.memory_limit
        .unwrap_or_else(microfrep_io::limits::default_memory_budget)
}

/// What kind a path names, by its extension (or a folder: a scan).
pub fn kind_of(path: &Path) -> Option<SourceKind> {
    if path.is_dir() {
        return Some(SourceKind::Scan);
    }
    let name = path.file_name()?.to_string_lossy().to_ascii_lowercase();
    let ends = |e: &str| name.ends_with(e);
    if ends(".hf") {
        Some(SourceKind::HyperFun)
    } else if [".stl", ".obj", ".ply", ".3mf"].iter().any(|e| ends(e)) {
        Some(SourceKind::Mesh)
    } else if [
        ".nrrd", ".nhdr", ".nii", ".nii.gz", ".hdr", ".tif", ".tiff", ".raw",
    ]
    .iter()
    .any(|e| ends(e))
    {
        Some(SourceKind::Scan)
    } else if ends(".csv") {
        Some(SourceKind::Data)
    } else {
        None
    }
}

/// Loads a model from a source (`PATH[:key=value,...]` or an example name).
pub fn load(spec: &str, opts: &LoadOptions) -> Result<Loaded, LoadError> {
    load_with_progress(spec, opts, &|_, _, _| {})
}

/// [`load`] with progress reports for long builds (mesh hierarchies,
/// distance transforms).
pub fn load_with_progress(
    spec: &str,
    opts: &LoadOptions,
    progress: Progress,
) -> Result<Loaded, LoadError> {
    microfrep_structures_hf::install();
    let src = Source::parse(spec)?;
    let path = Path::new(&src.path);
    let kind = if path.exists() {
        kind_of(path)
    } else {
        kind_of(path).filter(|k| *k == SourceKind::HyperFun)
    };
    let hf_only = || -> Result<(), LoadError> {
        if opts.object.is_some() || !opts.params.is_empty() || !opts.fields.is_empty() {
            return Err(
                src.bad("--object, --param and --field apply to HyperFun (.hf) models only".into())
            );
        }
        Ok(())
    };
    match kind {
        Some(SourceKind::HyperFun) => {
            src.check_keys(&[])?;
            load_hyperfun(path, opts, progress)
        }
        Some(SourceKind::Data) => Err(src.bad(
            "measured data is a field, not a model: bind it with --field NAME=FILE.csv and \
             call NAME(x) in a HyperFun model"
                .into(),
        )),
        Some(k) => {
            hf_only()?;
            let f = field(&src, k, limit(opts), progress)?;
            let shape = Shape::from_field(f.field).with_bounds(f.bounds);
            Ok(Loaded {
                shape,
                kind: k,
                hyperfun: None,
                notes: f.notes,
                inputs: f.files,
            })
        }
        None => {
            if let Some(ex) = microfrep_structures::examples::by_name(&src.path) {
                hf_only()?;
                src.check_keys(&[])?;
                let (lo, hi) = ex.bounds;
                return Ok(Loaded {
                    shape: Shape::new((ex.build)()).with_bounds(Bounds::new(lo, hi)),
                    kind: SourceKind::Example,
                    hyperfun: None,
                    notes: Vec::new(),
                    inputs: Vec::new(),
                });
            }
            if path.exists() {
                return Err(src.bad(
                    "unknown kind of file (HyperFun .hf; meshes .stl .obj .ply .3mf; scans \
                     .nrrd .nii .nii.gz .tif .tiff .raw or a folder of slices)"
                        .into(),
                ));
            }
            let known: Vec<&str> = microfrep_structures::examples::all()
                .iter()
                .map(|e| e.name)
                .collect();
            Err(LoadError::Unknown {
                name: src.path.clone(),
                known: known.join(", "),
            })
        }
    }
}

/// Loads a HyperFun file whose `--field` names are already built fields
/// (e.g. a part sampled once and shared by several models).
pub fn load_hyperfun_with(
    spec: &str,
    opts: &LoadOptions,
    fields: Vec<(String, Arc<dyn Field>)>,
) -> Result<Loaded, LoadError> {
    microfrep_structures_hf::install();
    let path = Path::new(spec);
    let text = std::fs::read_to_string(path).map_err(|e| LoadError::Io {
        path: path.to_path_buf(),
        source: e,
    })?;
    let lo = microfrep_hyperfun::LoadOptions {
        object: opts.object.clone(),
        params: opts.params.clone(),
        fields,
    };
    let m = microfrep_hyperfun::load_with_options(&text, spec, &lo).map_err(LoadError::HyperFun)?;
    Ok(Loaded {
        shape: m.shape(),
        kind: SourceKind::HyperFun,
        hyperfun: Some(m),
        notes: Vec::new(),
        inputs: vec![path.to_path_buf()],
    })
}

fn load_hyperfun(path: &Path, opts: &LoadOptions, progress: Progress) -> Result<Loaded, LoadError> {
    let text = std::fs::read_to_string(path).map_err(|e| LoadError::Io {
        path: path.to_path_buf(),
        source: e,
    })?;
    let bound = bind_fields(opts, progress)?;
    let mut inputs = vec![path.to_path_buf()];
    inputs.extend(bound.inputs);
    let (fields, notes) = (bound.fields, bound.notes);
    let file = path.display().to_string();
    let lo = microfrep_hyperfun::LoadOptions {
        object: opts.object.clone(),
        params: opts.params.clone(),
        fields,
    };
    let m =
        microfrep_hyperfun::load_with_options(&text, &file, &lo).map_err(LoadError::HyperFun)?;
    Ok(Loaded {
        shape: m.shape(),
        kind: SourceKind::HyperFun,
        hyperfun: Some(m),
        notes,
        inputs,
    })
}

/// The data fields of [`LoadOptions::fields`], built.
pub struct BoundFields {
    /// `(NAME, field)`, as a HyperFun model calls them.
    pub fields: Vec<(String, Arc<dyn Field>)>,
    /// Notes for the user, each prefixed with its field's name.
    pub notes: Vec<String>,
    /// The files they were read from.
    pub inputs: Vec<PathBuf>,
}

/// Builds every field of `opts.fields` (meshes, scans, CSV data), as a
/// HyperFun load does before lowering the model.
pub fn bind_fields(opts: &LoadOptions, progress: Progress) -> Result<BoundFields, LoadError> {
    let mut out = BoundFields {
        fields: Vec::new(),
        notes: Vec::new(),
        inputs: Vec::new(),
    };
    for (i, (name, spec)) in opts.fields.iter().enumerate() {
        let src = Source::parse(spec)?;
        if let Some((_, first)) = opts.fields[..i].iter().find(|(n, _)| n == name) {
            return Err(src.bad(format!(
                "the field name '{name}' is bound twice (to {first} and to {spec}); give each \
                 --field its own name"
            )));
        }
        let p = Path::new(&src.path);
        let kind = kind_of(p).ok_or_else(|| {
            src.bad("--field takes a mesh, a scan or a .csv of measured data".into())
        })?;
        if kind == SourceKind::HyperFun {
            return Err(
                src.bad("--field takes a mesh, a scan or a .csv, not a HyperFun file".into())
            );
        }
        let f = field(&src, kind, limit(opts), progress)?;
        out.notes
            .extend(f.notes.into_iter().map(|n| format!("{name}: {n}")));
        out.inputs.extend(f.files);
        out.fields.push((name.clone(), f.field));
    }
    Ok(out)
}

/// A data field built from a source, with where its solid lies.
pub struct BuiltField {
    /// The field (positive inside, distances in millimetres for meshes and
    /// scans).
    pub field: Arc<dyn Field>,
    /// A box holding the field's solid.
    pub bounds: Bounds,
    /// Warnings for the user.
    pub notes: Vec<String>,
    /// Every file read for it (a scan's data files and slices as well as
    /// the file named): no output of the run may replace them.
    pub files: Vec<PathBuf>,
}

/// Builds the field of a mesh, scan or data source.
pub fn field(
    src: &Source,
    kind: SourceKind,
    memory_limit: u64,
    progress: Progress,
) -> Result<BuiltField, LoadError> {
    let path = Path::new(&src.path);
    match kind {
        SourceKind::Mesh => mesh_field(src, path, memory_limit, progress),
        SourceKind::Scan => scan_field(src, path, memory_limit, progress),
        SourceKind::Data => {
            src.check_keys(&["mode"])?;
            let mode = match src.options.get("mode").map(String::as_str) {
                None | Some("interpolate") => microfrep_graded::csv::CsvMode::Interpolate,
                Some("weights") => microfrep_graded::csv::CsvMode::Weights,
                Some(m) => return Err(src.bad(format!("mode={m}: use interpolate or weights"))),
            };
            let b = microfrep_graded::csv::read_csv(path, mode)?;
            let (lo, hi) = b.bounds();
            let bounds = Bounds::new(lo, hi);
            Ok(BuiltField {
                field: Arc::new(b),
                bounds,
                notes: Vec::new(),
                files: vec![path.to_path_buf()],
            })
        }
        SourceKind::HyperFun | SourceKind::Example => {
            Err(src.bad("not a data source (a mesh, a scan or a .csv)".into()))
        }
    }
}

fn mesh_field(
    src: &Source,
    path: &Path,
    memory_limit: u64,
    progress: Progress,
) -> Result<BuiltField, LoadError> {
    use microfrep_meshfield::{BuildOptions, MeshField, SignMethod, TriMesh};
    src.check_keys(&["weld", "sign", "smooth"])?;
    let smooth = src.number("smooth")?;
    if let Some(r) = smooth {
        if r <= 0.0 {
            return Err(src.bad(format!("smooth={r} must be a positive length in mm")));
        }
    }
    let mut beams = None;
    let mesh = if src.path.to_ascii_lowercase().ends_with(".3mf") {
        let opts = microfrep_3mf::ReadOptions { memory_limit };
        let err = |e| match e {
            // Already names the file.
            e @ microfrep_3mf::Error::Io { .. } => LoadError::ThreeMf(e),
            e => LoadError::ThreeMfFile {
                path: path.to_path_buf(),
                source: e,
            },
        };
        let model = microfrep_3mf::read_file_with(path, &opts).map_err(err)?;
        let parts = microfrep_3mf::meshes_with(&model, memory_limit).map_err(err)?;
        let mut v = Vec::new();
        let mut t = Vec::new();
        for p in parts {
            let base = v.len() as u32;
            v.extend(p.vertices);
            t.extend(p.triangles.iter().map(|tri| tri.map(|i| i + base)));
        }
        // Beam lattices are struts: a field of their own, united with the
        // triangles (a skin) when there are any.
        beams = beam_field(&model, memory_limit, path)?;
        if t.is_empty() {
            if let Some(b) = beams {
                return Ok(b);
            }
            return Err(LoadError::Options {
                source_name: src.path.clone(),
                message: empty_3mf_reason(&model),
            });
        }
        TriMesh::new(v, t).map_err(|e| LoadError::MeshField {
            path: path.to_path_buf(),
            source: e,
        })?
    } else {
        let opts = microfrep_meshfield::read::ReadOptions { memory_limit };
        microfrep_meshfield::read::read_mesh_with(path, &opts)?
    };
    // A flat mesh (a single sheet, a 2D drawing) bounds no volume.
    if let Some(bb) = mesh_extent(&mesh.vertices) {
        let size: [f64; 3] = std::array::from_fn(|a| bb[1][a] - bb[0][a]);
        let big = size.iter().cloned().fold(0.0, f64::max);
        if let Some(a) = (0..3).find(|&a| size[a] <= 1e-9 * big) {
            return Err(src.bad(format!(
                "the mesh is flat: its extent along {} is {}, so it encloses no volume and is \
                 no solid to mesh, fill, slice or analyse",
                ["x", "y", "z"][a],
                size[a]
            )));
        }
    }
    let weld = src.number("weld")?.unwrap_or(0.0);
    if weld < 0.0 {
        return Err(src.bad(format!("weld={weld} must not be negative")));
    }
    let (mesh, _) = mesh.weld(weld);
    let sign = match src.options.get("sign").map(String::as_str) {
        None | Some("auto") => SignMethod::Auto,
        Some("winding") => SignMethod::Winding,
        Some("normal") => SignMethod::PseudoNormal,
        Some(s) => return Err(src.bad(format!("sign={s}: use auto, winding or normal"))),
    };
    let opts = BuildOptions {
        name: path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| "mesh".into()),
        sign,
        memory_limit,
        ..BuildOptions::default()
    };
    let f =
        MeshField::build(&mesh, &opts, &|d, t| progress("mesh hierarchy", d, t)).map_err(|e| {
            LoadError::MeshField {
                path: path.to_path_buf(),
                source: e,
            }
        })?;
    let mut notes = f.topology().warnings();
    if f.flipped() > 0 {
        notes.push(format!(
            "{} triangles were flipped to make the orientation consistent",
            f.flipped()
        ));
    }
    if let Some(v) = f.inverted() {
        notes.push(format!(
            "the mesh was inside out (closed, but its triangles face inwards: signed volume {}); \
             it was turned over",
            microfrep_io::text::sig(v, 4)
        ));
    }
    let bb = f.bbox();
    // A little room around the part, so its faces are inside the box.
    let pad: [f64; 3] = std::array::from_fn(|a| 1e-3 * (bb[1][a] - bb[0][a]).max(1e-9));
    let bounds = Bounds::new(
        std::array::from_fn(|a| bb[0][a] - pad[a]),
        std::array::from_fn(|a| bb[1][a] + pad[a]),
    );
    let field: Arc<dyn Field> = match smooth {
        None => Arc::new(f),
        Some(h) => {
            let s = smooth_field(&f, bb, h, memory_limit, progress).map_err(|m| src.bad(m))?;
            notes.push(format!(
                "smoothed: a C2 cubic B-spline of the distance on a {} mm grid (surfaces within \
                 about h^2 / (6 r) of the mesh where it curves with radius r, edges and corners \
                 rounded over about {} mm)",
                microfrep_io::text::sig(h, 4),
                microfrep_io::text::sig(h, 4)
            ));
            Arc::new(s)
        }
    };
    let mut built = BuiltField {
        field,
        bounds,
        notes,
        files: vec![path.to_path_buf()],
    };
    if let Some(b) = beams {
        let (lo, hi) = (built.bounds.min, built.bounds.max);
        built.bounds = Bounds::new(
            std::array::from_fn(|a| lo[a].min(b.bounds.min[a])),
            std::array::from_fn(|a| hi[a].max(b.bounds.max[a])),
        );
        built.notes.extend(b.notes);
        built.field = Arc::new(UnionField {
            name: format!("{} (triangles and beams)", built.field.name()),
            a: built.field,
            b: b.field,
        });
    }
    Ok(built)
}

/// A mesh's distance as a smooth field: sampled every `h` mm over its box
/// (and three steps more on every side, so the spline near the surface
/// mixes real samples), the samples the controls of a cubic B-spline.
fn smooth_field(
    f: &microfrep_meshfield::MeshField,
    bb: [[f64; 3]; 2],
    h: f64,
    memory_limit: u64,
    progress: Progress,
) -> Result<microfrep_core::SplineField, String> {
    use rayon::prelude::*;
    let lo: [f64; 3] = std::array::from_fn(|a| bb[0][a] - 3.0 * h);
    let dims: [usize; 3] = std::array::from_fn(|a| ((bb[1][a] - bb[0][a]) / h).ceil() as usize + 7);
    let n = dims.iter().try_fold(1usize, |n, &d| n.checked_mul(d));
    let n = match n {
        Some(n) if (n as u64).saturating_mul(8) <= memory_limit / 2 && n <= 1 << 28 => n,
        _ => {
            return Err(format!(
                "smooth={h}: a grid of {} x {} x {} samples is too large; use a larger smoothing \
                 length",
                dims[0], dims[1], dims[2]
            ))
        }
    };
    let plane = dims[0] * dims[1];
    let done = std::sync::atomic::AtomicU64::new(0);
    let values: Vec<f64> = (0..dims[2])
        .into_par_iter()
        .flat_map_iter(|k| {
            let mut x = Vec::with_capacity(plane);
            let mut y = Vec::with_capacity(plane);
            let mut z = Vec::with_capacity(plane);
            for j in 0..dims[1] {
                for i in 0..dims[0] {
                    x.push((lo[0] + i as f64 * h) as f32);
                    y.push((lo[1] + j as f64 * h) as f32);
                    z.push((lo[2] + k as f64 * h) as f32);
                }
            }
            let mut out = vec![0.0f32; plane];
            f.eval_batch(&x, &y, &z, &mut out);
            let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            progress("smoothing the mesh", d + 1, dims[2] as u64);
            out.into_iter().map(|v| v as f64)
        })
        .collect();
    debug_assert_eq!(values.len(), n);
    microfrep_core::SplineField::new(
        &format!("{} (smoothed)", f.name()),
        dims,
        lo,
        [h; 3],
        values,
    )
    .map(|s| s.as_distance())
    .map_err(|e| format!("smooth={h}: {e}"))
}

/// The box of a mesh's vertices, if it has any.
fn mesh_extent(v: &[[f64; 3]]) -> Option<[[f64; 3]; 2]> {
    let first = *v.first()?;
    Some(v.iter().fold([first, first], |[lo, hi], p| {
        [
            std::array::from_fn(|a| lo[a].min(p[a])),
            std::array::from_fn(|a| hi[a].max(p[a])),
        ]
    }))
}

/// The beam lattices of a 3MF model as one strut field, if it has beams.
fn beam_field(
    model: &microfrep_3mf::Model,
    memory_limit: u64,
    path: &Path,
) -> Result<Option<BuiltField>, LoadError> {
    use microfrep_structures::strut_graph::StrutGraph;
    let lattices =
        microfrep_3mf::lattices_with(model, memory_limit).map_err(|e| LoadError::ThreeMfFile {
            path: path.to_path_buf(),
            source: e,
        })?;
    let mut g = StrutGraph {
        nodes: Vec::new(),
        beams: Vec::new(),
        radii: Vec::new(),
    };
    for l in &lattices {
        let base = g.nodes.len() as u32;
        g.nodes.extend(&l.nodes);
        for b in &l.beams {
            g.beams.push((b.v1 + base, b.v2 + base));
            g.radii.push([b.r1, b.r2]);
        }
    }
    if g.beams.is_empty() {
        return Ok(None);
    }
    let bad = |e: microfrep_structures::Error| LoadError::Options {
        source_name: path.display().to_string(),
        message: format!("its beam lattice: {e}"),
    };
    let bb = g.bounds().ok_or_else(|| LoadError::Options {
        source_name: path.display().to_string(),
        message: "its beam lattice has no extent".into(),
    })?;
    let f = g.field().map_err(bad)?;
    let n = g.beams.len();
    let mut built = BuiltField {
        field: Arc::new(f),
        bounds: Bounds::new(bb[0], bb[1]),
        notes: vec![format!(
            "{n} beams of the beam lattice read as struts (frustums with round ends)"
        )],
        files: vec![path.to_path_buf()],
    };
    // A clipping mesh keeps the struts inside (or outside) it.
    let clips: Vec<(microfrep_3mf::ClipMode, u32)> = model
        .objects
        .iter()
        .filter_map(|o| match &o.content {
            microfrep_3mf::ObjectContent::Mesh(m) => m.beam_lattice.as_ref()?.clipping,
            _ => None,
        })
        .filter(|c| c.0 != microfrep_3mf::ClipMode::None)
        .collect();
    match clips.as_slice() {
        [] => {}
        [(mode, id)] if lattices.len() == 1 => {
            use microfrep_meshfield::{BuildOptions, MeshField, TriMesh};
            let mesh = model.objects.iter().find_map(|o| match &o.content {
                microfrep_3mf::ObjectContent::Mesh(m) if o.id == *id => Some(m),
                _ => None,
            });
            let mesh = mesh.ok_or_else(|| LoadError::Options {
                source_name: path.display().to_string(),
                message: format!("its beam lattice is clipped by object {id}, which is not a mesh"),
            })?;
            let tm = TriMesh::new(mesh.vertices.clone(), mesh.triangles.clone()).map_err(|e| {
                LoadError::MeshField {
                    path: path.to_path_buf(),
                    source: e,
                }
            })?;
            let opts = BuildOptions {
                name: "clipping mesh".into(),
                memory_limit,
                ..BuildOptions::default()
            };
            let clip =
                MeshField::build(&tm, &opts, &|_, _| {}).map_err(|e| LoadError::MeshField {
                    path: path.to_path_buf(),
                    source: e,
                })?;
            let inside = *mode == microfrep_3mf::ClipMode::Inside;
            built.field = Arc::new(ClipField {
                name: format!("{n} beams clipped by a mesh"),
                beams: built.field,
                clip: Arc::new(clip),
                inside,
            });
            built.notes.push(format!(
                "the struts are clipped to {} of the lattice's clipping mesh",
                if inside { "the inside" } else { "the outside" }
            ));
        }
        _ => {
            return Err(LoadError::Options {
                source_name: path.display().to_string(),
                message: "several beam lattices with clipping meshes are not read yet; write \
                          one lattice, or give its triangles (--triangles)"
                    .into(),
            })
        }
    }
    Ok(Some(built))
}

/// Struts kept inside (`min(beams, clip)`) or outside (`min(beams, -clip)`)
/// a clipping mesh.
#[derive(Debug)]
struct ClipField {
    name: String,
    beams: Arc<dyn Field>,
    clip: Arc<dyn Field>,
    inside: bool,
}

impl ClipField {
    fn sign(&self) -> f64 {
        if self.inside {
            1.0
        } else {
            -1.0
        }
    }
}

impl Field for ClipField {
    fn name(&self) -> &str {
        &self.name
    }
    fn eval(&self, p: [f64; 3]) -> f64 {
        self.beams.eval(p).min(self.sign() * self.clip.eval(p))
    }
    fn grad(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
        let (vb, gb) = self.beams.grad(p);
        let (vc, gc) = self.clip.grad(p);
        let s = self.sign();
        if vb <= s * vc {
            (vb, gb)
        } else {
            (s * vc, gc.map(|g| s * g))
        }
    }
    fn interval(&self, b: [Interval; 3]) -> Interval {
        let c = self.clip.interval(b);
        let c = if self.inside { c } else { c.neg() };
        self.beams.interval(b).min(c)
    }
    fn eval_batch(&self, x: &[f32], y: &[f32], z: &[f32], out: &mut [f32]) {
        let mut c = vec![0.0f32; out.len()];
        self.beams.eval_batch(x, y, z, out);
        self.clip.eval_batch(x, y, z, &mut c);
        let s = self.sign() as f32;
        for (o, v) in out.iter_mut().zip(c) {
            *o = o.min(s * v);
        }
    }
}

/// Why a 3MF package gives no solid: what it holds, and what to do.
fn empty_3mf_reason(model: &microfrep_3mf::Model) -> String {
    use microfrep_3mf::ObjectContent;
    let level_sets = model
        .objects
        .iter()
        .filter(|o| matches!(o.content, ObjectContent::LevelSet(_)))
        .count();
    if level_sets > 0 {
        format!(
            "the package holds {level_sets} level set object(s) (the volumetric and implicit \
             extensions) and no triangles or beams: microfrep reads meshes and beam lattices \
             from 3MF; load the model it was written from (the .hf, or the example), or write \
             the 3MF without --implicit"
        )
    } else if !model.slice_stacks.is_empty() {
        "the package holds slice stacks and no triangles or beams: slices are a print job, \
         not a solid to load; load the model they were sliced from"
            .into()
    } else {
        "the package's build holds no triangles and no beams".into()
    }
}

/// The union (larger value) of two fields: a mesh's skin and its struts.
#[derive(Debug)]
struct UnionField {
    name: String,
    a: Arc<dyn Field>,
    b: Arc<dyn Field>,
}

impl Field for UnionField {
    fn name(&self) -> &str {
        &self.name
    }
    fn eval(&self, p: [f64; 3]) -> f64 {
        self.a.eval(p).max(self.b.eval(p))
    }
    fn grad(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
        let (va, ga) = self.a.grad(p);
        let (vb, gb) = self.b.grad(p);
        if va >= vb {
            (va, ga)
        } else {
            (vb, gb)
        }
    }
    fn interval(&self, b: [Interval; 3]) -> Interval {
        self.a.interval(b).max(self.b.interval(b))
    }
    fn eval_batch(&self, x: &[f32], y: &[f32], z: &[f32], out: &mut [f32]) {
        let mut other = vec![0.0f32; out.len()];
        self.a.eval_batch(x, y, z, out);
        self.b.eval_batch(x, y, z, &mut other);
        for (o, v) in out.iter_mut().zip(other) {
            *o = o.max(v);
        }
    }
}

fn scan_field(
    src: &Source,
    path: &Path,
    memory_limit: u64,
    progress: Progress,
) -> Result<BuiltField, LoadError> {
    use microfrep_scan::{ScanField, ScanOptions};
    src.check_keys(&["iso", "smooth", "spacing", "step", "series", "frame"])?;
    let iso = src.number("iso")?.ok_or_else(|| {
        src.bad(
            "a scan needs its iso value: the intensity at and above which a voxel is inside, \
             e.g. :iso=300 for bone in CT (Hounsfield units) or :iso=0.5 for occupancy; \
             `microfrep scan-info FILE` suggests one"
                .into(),
        )
    })?;
    let (vol, notes) = read_volume(src, path, memory_limit, progress)?;
    let mut so = ScanOptions::new(iso);
    so.smooth = src.number("smooth")?.unwrap_or(0.0);
    so.memory_limit = memory_limit;
    let f =
        ScanField::build_with_progress(&vol, &so, &|d, t| progress("distance transform", d, t))?;
    let b = f.bounds();
    Ok(BuiltField {
        bounds: Bounds::new(b[0], b[1]),
        field: f.into_field(),
        notes,
        files: std::iter::once(path.to_path_buf())
            .chain(vol.files.iter().cloned())
            .collect(),
    })
}

/// Reads a scan `PATH[:spacing=X,Y,Z,step=N,series=UID,frame=F]` as a
/// volume (no iso value needed), with a note on its coordinate frame: what
/// `scan-info` shows before a threshold is chosen.
pub fn read_scan(
    spec: &str,
    memory_limit: Option<u64>,
    progress: Progress,
) -> Result<(microfrep_scan::Volume, Vec<String>), LoadError> {
    let src = Source::parse(spec)?;
    let path = Path::new(&src.path);
    if !path.exists() {
        return Err(LoadError::Io {
            path: path.to_path_buf(),
            source: std::io::Error::new(std::io::ErrorKind::NotFound, "no such file or folder"),
        });
    }
    if kind_of(path) != Some(SourceKind::Scan) {
        return Err(src.bad(
            "not a scan (.nrrd .nhdr .nii .nii.gz .hdr .tif .raw, or a folder of DICOM or TIFF slices)"
                .into(),
        ));
    }
    src.check_keys(&["spacing", "step", "series", "frame"])?;
    let limit = memory_limit.unwrap_or_else(microfrep_io::limits::default_memory_budget);
    read_volume(&src, path, limit, progress)
}

fn read_volume(
    src: &Source,
    path: &Path,
    memory_limit: u64,
    progress: Progress,
) -> Result<(microfrep_scan::Volume, Vec<String>), LoadError> {
    use microfrep_scan::{Frame, ReadOptions, Volume};
    let mut ro = ReadOptions {
        memory_limit,
        ..ReadOptions::default()
    };
    if let Some(s) = src.options.get("spacing") {
        let v: Vec<f64> = s
            .split([',', 'x'])
            .map(|t| t.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| src.bad(format!("spacing={s}: expected X,Y,Z in mm")))?;
        let v = match v.as_slice() {
            [a] => [*a; 3],
            [a, b, c] => [*a, *b, *c],
            _ => return Err(src.bad(format!("spacing={s}: expected X,Y,Z in mm"))),
        };
        if v.iter().any(|x| !(x.is_finite() && *x > 0.0)) {
            return Err(src.bad(format!("spacing={s}: spacings must be positive")));
        }
        ro.spacing = Some(v);
    }
    if let Some(s) = src.number("step")? {
        if !(s >= 1.0 && s.fract() == 0.0 && s <= 64.0) {
            return Err(src.bad(format!("step={s}: a whole number from 1 to 64")));
        }
        ro.step = s as usize;
    }
    ro.series = src.options.get("series").cloned();
    if let Some(f) = src.options.get("frame") {
        ro.frame = Frame::parse(f)
            .ok_or_else(|| src.bad(format!("frame={f}: use file, lps, ras or voxel")))?;
    }
    let vol = Volume::open_with_progress(path, &ro, &|d, t| progress("reading scan", d, t))?;
    let notes = vec![frame_note(&vol.frame, ro.frame)];
    Ok((vol, notes))
}

/// What a scan's coordinates mean, for the summary.
fn frame_note(frame: &str, asked: microfrep_scan::Frame) -> String {
    let what = match frame {
        "LPS" => {
            "LPS (x to the patient's left, y posterior, z superior: DICOM's frame)".to_string()
        }
        "RAS" => {
            "RAS (x to the patient's right, y anterior, z superior: NIfTI's frame)".to_string()
        }
        "voxel" => {
            "the voxel grid in mm (sample 0 at the origin, the file's axis order)".to_string()
        }
        "unknown" => "the file's axes in mm (it names no patient frame)".to_string(),
        other => format!("the file's frame `{other}` (not a patient frame)"),
    };
    let how = if asked == microfrep_scan::Frame::File {
        "the file's own; FILE:frame=lps, ras or voxel chooses another"
    } else {
        "chosen with :frame="
    };
    format!("coordinates in {what}, {how}")
}

/// The expression of a bound field at `(x, y, z)`, for Rust models.
pub fn field_expr(f: &BuiltField) -> Expr {
    Expr::field(f.field.clone())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sources_parse_with_and_without_options() {
        let s = Source::parse("bone.nrrd:iso=300,smooth=0.5").unwrap();
        assert_eq!(s.path, "bone.nrrd");
        assert_eq!(s.options["iso"], "300");
        assert_eq!(s.options["smooth"], "0.5");
        let s = Source::parse("dir/a:b.stl").unwrap();
        assert_eq!(s.path, "dir/a:b.stl");
        assert!(s.options.is_empty());
        assert!(Source::parse("x.stl:weld").unwrap().options.is_empty());
        assert!(Source::parse("x.stl:sign,weld=1").is_err());
        // Vectors: commas continue the value, as the docs write them.
        let s = Source::parse("ct/:iso=300,spacing=0.5,0.5,1.25,step=2").unwrap();
        assert_eq!(s.options["spacing"], "0.5,0.5,1.25");
        assert_eq!(s.options["step"], "2");
        // A stray word after a number is no longer a number.
        let s = Source::parse("x.stl:weld=1,sign").unwrap();
        assert!(s.number("weld").is_err());
    }

    fn temp(name: &str) -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!("microfrep-load-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d.join(name)
    }

    #[test]
    fn inside_out_meshes_are_turned_over_with_a_note() {
        let v = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        // Outward faces reversed: closed, coherent, inside out.
        let faces = [[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]];
        let mut stl = String::from("solid t\n");
        for f in faces {
            stl += "facet normal 0 0 0\nouter loop\n";
            for i in f {
                let p: [f64; 3] = v[i];
                stl += &format!("vertex {} {} {}\n", p[0], p[1], p[2]);
            }
            stl += "endloop\nendfacet\n";
        }
        stl += "endsolid t\n";
        let p = temp("inside-out.stl");
        std::fs::write(&p, stl).unwrap();
        let l = load(p.to_str().unwrap(), &LoadOptions::default()).unwrap();
        let note = l.notes.iter().find(|n| n.contains("inside out"));
        assert!(
            note.is_some_and(|n| n.contains("signed volume -0.1667")),
            "{:?}",
            l.notes
        );
        // Turned over: the inside is inside.
        let mut pe = l.shape.point();
        let inside = pe.eval([0.1, 0.1, 0.1]);
        let outside = pe.eval([1.0, 1.0, 1.0]);
        assert!(inside > 0.0 && outside < 0.0, "{inside} {outside}");
    }

    /// Beam lattices read back as struts: alone, united with a skin mesh,
    /// clipped by a mesh; a package with neither triangles nor beams says
    /// what it holds.
    #[test]
    fn beam_lattice_3mf_packages_read_back_as_struts() {
        use microfrep_3mf::{
            write_file, BeamLattice, ClipMode, Mesh, Model, Transform, Unit, WriteOptions,
        };
        // One beam along x from 0 to 10, radius 1 (and 0.5 at the far end
        // in the clipped case).
        let write = |name: &str, skin: bool, clip: bool| {
            let mut m = Model::new(Unit::Millimeter);
            let clip_id =
                clip.then(|| m.add_mesh(Some("clip"), Mesh::cuboid([-2.0; 3], [5.0, 2.0, 2.0])));
            let mut l = BeamLattice::new(1.0, 1e-4);
            l.push(0, 1, 1.0, 1.0);
            if let Some(c) = clip_id {
                l.clipping = Some((ClipMode::Inside, c));
            }
            if skin {
                let s = m.add_mesh(
                    Some("skin"),
                    Mesh::cuboid([20.0, -1.0, -1.0], [22.0, 1.0, 1.0]),
                );
                m.add_item(s, Transform::IDENTITY);
            }
            let id = m.add_mesh(
                Some("lattice"),
                Mesh {
                    vertices: vec![[0.0; 3], [10.0, 0.0, 0.0]],
                    beam_lattice: Some(l),
                    ..Mesh::default()
                },
            );
            m.add_item(id, Transform::IDENTITY);
            let p = temp(name);
            write_file(&p, &m, &WriteOptions::default()).unwrap();
            p
        };
        let at = |p: &std::path::Path, q: [f64; 3]| {
            let l = load(p.to_str().unwrap(), &LoadOptions::default()).unwrap();
            l.shape.point().eval(q)
        };
        let alone = write("beams.3mf", false, false);
        assert!((at(&alone, [5.0, 0.0, 0.0]) - 1.0).abs() < 1e-9);
        assert!((at(&alone, [5.0, 2.0, 0.0]) + 1.0).abs() < 1e-9);
        // The round end: 1 - 0.5 at half a radius past the end.
        assert!((at(&alone, [10.5, 0.0, 0.0]) - 0.5).abs() < 1e-9);
        let l = load(alone.to_str().unwrap(), &LoadOptions::default()).unwrap();
        assert!(
            l.notes.iter().any(|n| n.contains("1 beams")),
            "{:?}",
            l.notes
        );
        assert!(l.shape.bounds().unwrap().max[0] >= 11.0);
        // With a skin: both are solid.
        let both = write("skin-beams.3mf", true, false);
        assert!(at(&both, [5.0, 0.0, 0.0]) > 0.5);
        assert!(at(&both, [21.0, 0.0, 0.0]) > 0.5);
        assert!(at(&both, [15.0, 0.0, 0.0]) < 0.0);
        // Clipped to x <= 5: the far half is gone.
        let clipped = write("clipped.3mf", false, true);
        assert!(at(&clipped, [3.0, 0.0, 0.0]) > 0.5);
        assert!(at(&clipped, [7.0, 0.0, 0.0]) < 0.0);
        // Neither triangles nor beams: what the package holds.
        let mut m = Model::new(Unit::Millimeter);
        let s = m.slice_stacks.len();
        assert_eq!(s, 0);
        let empty = temp("empty.3mf");
        let id = m.add_mesh(Some("nothing"), Mesh::default());
        m.add_item(id, Transform::IDENTITY);
        if write_file(&empty, &m, &WriteOptions::default()).is_ok() {
            let e = load(empty.to_str().unwrap(), &LoadOptions::default())
                .err()
                .unwrap();
            assert!(e.to_string().contains("no triangles and no beams"), "{e}");
        }
    }

    /// `FILE.stl:smooth=H`: the mesh's distance as a C2 spline. Across
    /// the medial axis of a cube (the plane x = y near an edge) the plain
    /// distance's gradient jumps by sqrt 2; the smooth one's is continuous.
    /// Its zero set stays on the flat faces, and the edges are rounded by
    /// less than a step.
    #[test]
    fn smoothed_mesh_fields_have_continuous_gradients_and_keep_the_surface() {
        let c = 5.0;
        let v: Vec<[f64; 3]> = (0..8)
            .map(|i| std::array::from_fn(|a| if i >> a & 1 == 1 { c } else { -c }))
            .collect();
        // Outward faces of the cube (vertex bit a set: +c on axis a).
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let mut stl = String::from("solid c\n");
        for q in quads {
            for t in [[q[0], q[1], q[2]], [q[0], q[2], q[3]]] {
                stl += "facet normal 0 0 0\nouter loop\n";
                for i in t {
                    stl += &format!("vertex {} {} {}\n", v[i][0], v[i][1], v[i][2]);
                }
                stl += "endloop\nendfacet\n";
            }
        }
        stl += "endsolid c\n";
        let p = temp("cube-smooth.stl");
        std::fs::write(&p, stl).unwrap();
        let plain = load(p.to_str().unwrap(), &LoadOptions::default()).unwrap();
        let spec = format!("{}:smooth=1", p.display());
        let smooth = load(&spec, &LoadOptions::default()).unwrap();
        assert!(
            smooth.notes.iter().any(|n| n.contains("B-spline")),
            "{:?}",
            smooth.notes
        );
        let jump = |s: &Shape, e: f64| {
            let mut g = s.grad();
            let (_, a) = g.eval([3.0, 3.0 + e, 0.0]);
            let (_, b) = g.eval([3.0 + e, 3.0, 0.0]);
            ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
        };
        assert!(
            jump(&plain.shape, 1e-3) > 1.4,
            "{}",
            jump(&plain.shape, 1e-3)
        );
        for e in [1e-2, 1e-3, 1e-4] {
            assert!(
                jump(&smooth.shape, e) < 20.0 * e,
                "{e}: {}",
                jump(&smooth.shape, e)
            );
        }
        // On the faces, away from the edges: the surface itself, and the
        // distance inside.
        let mut pe = smooth.shape.point();
        assert!(pe.eval([5.0, 0.5, -0.5]).abs() < 1e-6);
        assert!((pe.eval([3.0, 0.0, 0.0]) - 2.0).abs() < 1e-6);
        // An edge is rounded inwards by less than a step.
        let e = pe.eval([5.0, 5.0, 0.0]);
        assert!(e < 0.0 && e > -1.0, "{e}");
        // Bad lengths are refused.
        let bad = format!("{}:smooth=0", p.display());
        assert!(load(&bad, &LoadOptions::default()).is_err());
    }

    #[test]
    fn bad_3mf_parts_are_named_with_the_file() {
        let p = temp("not-a-zip.3mf");
        std::fs::write(&p, b"PK\x03\x04 this is no zip").unwrap();
        let e = load(p.to_str().unwrap(), &LoadOptions::default())
            .err()
            .unwrap()
            .to_string();
        assert!(
            e.starts_with(&format!("{}: the archive: zip archive error", p.display())),
            "{e}"
        );
    }

    #[test]
    fn unknown_names_list_the_examples() {
        let e = load("no-such-model", &LoadOptions::default())
            .err()
            .unwrap();
        let t = e.to_string();
        assert!(t.contains("toriball"), "{t}");
        let e = load(
            "toriball",
            &LoadOptions {
                object: Some("x".into()),
                ..Default::default()
            },
        )
        .err()
        .unwrap();
        assert!(e.to_string().contains("HyperFun"), "{e}");
    }
}

/// What [`check_source`] found in a HyperFun text: the evaluated object as
/// a model, when it lowers, and every diagnostic of the whole file.
#[derive(Debug)]
pub struct SourceCheck {
    /// The evaluated object, lowered with its parameters and fields;
    /// `None` when it has errors (errors in other objects do not stop it).
    pub model: Option<microfrep_hyperfun::Model>,
    /// Errors and warnings with positions, in source order (those of
    /// `microfrep check`, the warnings on calls whose reference result is
    /// a quirk included).
    pub diagnostics: microfrep_hyperfun::Diagnostics,
    /// Errors without a position (no such object, a parameter out of
    /// range).
    pub unlocated: Vec<String>,
    /// All of them as `microfrep check` prints them: `file:line:col:
    /// severity: message`, the source line and a caret, then the
    /// unlocated ones as `file: error: message`.
    pub rendered: String,
}

/// Checks the HyperFun text `src` (named `file` in messages) as `microfrep
/// check` does, every object lowered on its own, and lowers the evaluated
/// object (`object`, default `my_model`, else the first) with the
/// parameters and the already built data `fields` that `opts` names: the
/// editor's view of a model (the studio's), where a load stops at the
/// first error.
pub fn check_source(src: &str, file: &str, opts: &microfrep_hyperfun::LoadOptions) -> SourceCheck {
    microfrep_structures_hf::install();
    let (diagnostics, unlocated, model) =
        match microfrep_hyperfun::check::check_with(src, file, opts) {
            Ok(r) => (r.diagnostics, r.unlocated, r.model),
            Err(parse) => (parse, Vec::new(), None),
        };
    let mut rendered = diagnostics.render(src);
    for m in &unlocated {
        rendered += &format!("{file}: error: {m}\n");
    }
    SourceCheck {
        model,
        diagnostics,
        unlocated,
        rendered,
    }
}
