//! Layer stacks for multi-material and grey-scale printers.
//!
//! **Material stacks** ([`write_material_stack`]): one RGBA PNG per layer,
//! each inside voxel painted with its material's palette colour (alpha
//! 255), after dithering the fractions ([`crate::dither`]). This is the
//! input of material-jetting "voxel printing" workflows (e.g. Stratasys
//! GrabCAD Voxel Print, OpenVCAD's material inkjet compiler), which map each
//! colour to a print head's material. Outside voxels are written as
//! [`Background::Transparent`], `(0, 0, 0, 0)`, by default: OpenVCAD's
//! material-inkjet stacks are RGBA with the empty "void" material apart
//! from every real material, and a transparent pixel cannot be mistaken for
//! a material whose colour is black. For tools that ignore alpha and read a
//! colour as "no material" (white backgrounds are common for GrabCAD's
//! clear or empty voxels), choose [`Background::Opaque`]; a palette colour
//! equal to an opaque background is refused. (We could not find a published
//! statement of GrabCAD's own rule; check the printer's import settings.)
//!
//! **Grey stacks** ([`write_grey_stack`]): one 8-bit greyscale PNG per
//! layer, `round(255 clamp(s, 0, 1))` inside and 0 outside, for grey-scale
//! vat printers (exposure or density per pixel).
//!
//! Both write into a directory with a `manifest.json`: pitch in x and y,
//! layer height, origin, image size, the palette, per-material voxel counts
//! and fraction integrals, and the file of each layer. Images are written
//! like the core slicer's (`microfrep-fab`): row 0 of a file is the largest
//! y, layer 0 is the bottom, samples at voxel centres. The directory is
//! written under a temporary name next to the target and renamed when
//! complete ([`write_dir_atomically`], the one place that touches the
//! target); `out` must not exist.
//!
//! Pitch presets ([`PRESETS`]) name common material-jetting and vat grids.

use crate::dither::{dither, DitherReport, LayerSource, Layout, Method, OUTSIDE};
use crate::error::{io_at, Error, Result};
use microfrep_core::{BatchEval, Interval, IntervalEval, Shape, Simplify, Tape};
use rayon::prelude::*;
use std::fs;
use std::path::{Path, PathBuf};

/// One material of a palette.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Material {
    /// Name (letters, digits, `_`, `-`, `.`).
    pub name: String,
    /// Colour in the layer images.
    pub rgb: [u8; 3],
}

/// Materials in index order, parsed from `NAME=#RRGGBB,NAME=#RRGGBB,...`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Palette {
    materials: Vec<Material>,
}

impl Palette {
    /// Parses `NAME=#RRGGBB,...` (spaces around items allowed, at most 255
    /// materials, names and colours unique).
    pub fn parse(spec: &str) -> Result<Palette> {
        let bad = |entry: usize, text: &str, message: String| Error::Palette {
            entry,
            text: text.to_string(),
            message,
        };
        if spec.trim().is_empty() {
            return Err(bad(
                0,
                spec,
                "empty palette: expected NAME=#RRGGBB,NAME=#RRGGBB,...".into(),
            ));
        }
        let mut materials: Vec<Material> = Vec::new();
        for (i, item) in spec.split(',').enumerate() {
            let e = i + 1;
            let item = item.trim();
            let Some((name, colour)) = item.split_once('=') else {
                return Err(bad(e, item, "expected NAME=#RRGGBB".into()));
            };
            let (name, colour) = (name.trim(), colour.trim());
            if name.is_empty()
                || !name
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || "_-.".contains(c))
            {
                return Err(bad(
                    e,
                    item,
                    format!("name {name:?} must be non-empty letters, digits, '_', '-' or '.'"),
                ));
            }
            let hex = colour.strip_prefix('#').unwrap_or("");
            if hex.len() != 6 || !hex.chars().all(|c| c.is_ascii_hexdigit()) {
                return Err(bad(
                    e,
                    item,
                    format!("colour {colour:?} must be # followed by 6 hex digits (#RRGGBB)"),
                ));
            }
            let byte = |k: usize| u8::from_str_radix(&hex[2 * k..2 * k + 2], 16).expect("hex");
            let rgb = [byte(0), byte(1), byte(2)];
            if let Some(p) = materials
                .iter()
                .position(|m| m.name.eq_ignore_ascii_case(name))
            {
                return Err(bad(
                    e,
                    item,
                    format!("name {name:?} already used by entry {}", p + 1),
                ));
            }
            if let Some(p) = materials.iter().position(|m| m.rgb == rgb) {
                return Err(bad(
                    e,
                    item,
                    format!(
                        "colour {colour} already used by entry {} ({}): a printer could not tell them apart",
                        p + 1,
                        materials[p].name
                    ),
                ));
            }
            if materials.len() == crate::dither::MAX_MATERIALS {
                return Err(bad(
                    e,
                    item,
                    format!("more than {} materials", crate::dither::MAX_MATERIALS),
                ));
            }
            materials.push(Material {
                name: name.to_string(),
                rgb,
            });
        }
        Ok(Palette { materials })
    }

    /// The materials in index order.
    pub fn materials(&self) -> &[Material] {
        &self.materials
    }

    /// Number of materials.
    pub fn len(&self) -> usize {
        self.materials.len()
    }

    /// Whether there are no materials (never, for a parsed palette).
    pub fn is_empty(&self) -> bool {
        self.materials.is_empty()
    }

    /// The `NAME=#RRGGBB,...` form.
    pub fn spec(&self) -> String {
        self.materials
            .iter()
            .map(|m| format!("{}={}", m.name, hex(m.rgb)))
            .collect::<Vec<_>>()
            .join(",")
    }
}

impl std::str::FromStr for Palette {
    type Err = Error;
    fn from_str(s: &str) -> Result<Palette> {
        Palette::parse(s)
    }
}

fn hex(rgb: [u8; 3]) -> String {
    format!("#{:02X}{:02X}{:02X}", rgb[0], rgb[1], rgb[2])
}

/// A named printer grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Preset {
    /// Name to select it by.
    pub name: &'static str,
    /// Resolution along x and y, dots per inch.
    pub dpi: [f64; 2],
    /// Layer height in millimetres.
    pub layer: f64,
    /// What it is for.
    pub note: &'static str,
}

impl Preset {
    /// Voxel pitch along x and y in millimetres (`25.4 / dpi`).
    pub fn pitch(&self) -> [f64; 2] {
        self.dpi.map(|d| 25.4 / d)
    }
}

/// Common grids (nominal values; check the machine's own settings).
pub const PRESETS: [Preset; 5] = [
    Preset {
        name: "mj-600x300-27um",
        dpi: [600.0, 300.0],
        layer: 0.027,
        note: "material jetting voxel printing (PolyJet J7-series class): 600 x 300 dpi, \
               27 um layers, the grid of OpenVCAD's GCVF exporter",
    },
    Preset {
        name: "mj-600x300-14um",
        dpi: [600.0, 300.0],
        layer: 0.014,
        note: "material jetting, high-quality mode: 600 x 300 dpi, 14 um layers",
    },
    Preset {
        name: "mj-600x600-27um",
        dpi: [600.0, 600.0],
        layer: 0.027,
        note: "material jetting with square 42.3 um pixels, 27 um layers",
    },
    Preset {
        name: "vat-50um",
        dpi: [508.0, 508.0],
        layer: 0.05,
        note: "grey-scale vat photopolymerisation (LCD / DLP): 50 um pixels and layers",
    },
    Preset {
        name: "dlp-25um",
        dpi: [1016.0, 1016.0],
        layer: 0.025,
        note: "high-resolution DLP vat photopolymerisation (micro-lattices, scaffolds): \
               25 um pixels and layers",
    },
];

/// The preset called `name`.
pub fn preset(name: &str) -> Option<&'static Preset> {
    PRESETS.iter().find(|p| p.name == name)
}

/// The preset called `name`, or an error listing every preset.
pub fn find_preset(name: &str) -> std::result::Result<&'static Preset, String> {
    preset(name).ok_or_else(|| {
        let list: Vec<String> = PRESETS
            .iter()
            .map(|p| format!("  {:<16} {}", p.name, p.note))
            .collect();
        format!(
            "unknown preset '{name}'; the presets are:\n{}",
            list.join("\n")
        )
    })
}

const MAX_SIDE: usize = 1 << 17;
const MAX_PIXELS: usize = 1 << 30;
const MAX_LAYERS: usize = 1 << 20;

/// Voxels of `pitch[0] x pitch[1]` in a layer, layers of height `layer`,
/// covering a box from its corner `min`; samples at voxel centres.
#[derive(Clone, Debug, PartialEq)]
pub struct StackGrid {
    /// Outer corner of voxel (0, 0) of layer 0.
    pub min: [f64; 3],
    /// Voxel size along x and y.
    pub pitch: [f64; 2],
    /// Layer height.
    pub layer: f64,
    /// Voxels along x.
    pub nx: usize,
    /// Voxels along y.
    pub ny: usize,
    /// Layers.
    pub layers: usize,
}

fn count(len: f64, step: f64, what: &str, max: usize) -> Result<usize> {
    let n = (len / step - 1e-9).ceil().max(1.0);
    if n > max as f64 {
        return Err(Error::Invalid(format!(
            "{what}: {n} exceeds the limit of {max} (step too small for the bounds?)"
        )));
    }
    Ok(n as usize)
}

impl StackGrid {
    /// The grid over `[min, max]` (grown to whole voxels and layers).
    pub fn new(min: [f64; 3], max: [f64; 3], pitch: [f64; 2], layer: f64) -> Result<StackGrid> {
        for (name, v) in [
            ("x pitch", pitch[0]),
            ("y pitch", pitch[1]),
            ("layer", layer),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::Invalid(format!("{name} must be positive, got {v}")));
            }
        }
        for a in 0..3 {
            if !(min[a].is_finite() && max[a].is_finite() && max[a] > min[a]) {
                return Err(Error::Invalid(format!(
                    "bounds on axis {a} must be finite with min < max, got {} .. {}",
                    min[a], max[a]
                )));
            }
        }
        let nx = count(max[0] - min[0], pitch[0], "image width", MAX_SIDE)?;
        let ny = count(max[1] - min[1], pitch[1], "image height", MAX_SIDE)?;
        if nx * ny > MAX_PIXELS {
            return Err(Error::Invalid(format!(
                "layer of {nx} x {ny} voxels exceeds the limit of {MAX_PIXELS}"
            )));
        }
        let layers = count(max[2] - min[2], layer, "layer count", MAX_LAYERS)?;
        Ok(StackGrid {
            min,
            pitch,
            layer,
            nx,
            ny,
            layers,
        })
    }

    /// The grid of a preset over `[min, max]`.
    pub fn from_preset(min: [f64; 3], max: [f64; 3], p: &Preset) -> Result<StackGrid> {
        StackGrid::new(min, max, p.pitch(), p.layer)
    }

    /// Centre of voxel column `i`.
    pub fn x(&self, i: usize) -> f64 {
        self.min[0] + (i as f64 + 0.5) * self.pitch[0]
    }
    /// Centre of voxel row `j`.
    pub fn y(&self, j: usize) -> f64 {
        self.min[1] + (j as f64 + 0.5) * self.pitch[1]
    }
    /// Middle of layer `k`.
    pub fn z(&self, k: usize) -> f64 {
        self.min[2] + (k as f64 + 0.5) * self.layer
    }
    /// Voxel count.
    pub fn voxels(&self) -> u64 {
        (self.nx * self.ny) as u64 * self.layers as u64
    }
    fn layout(&self, materials: usize) -> Layout {
        Layout {
            nx: self.nx,
            ny: self.ny,
            layers: self.layers,
            materials,
        }
    }
}

/// Colour of outside voxels in material stacks.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Background {
    /// `(0, 0, 0, 0)`.
    #[default]
    Transparent,
    /// This colour, opaque.
    Opaque([u8; 3]),
}

impl Background {
    fn rgba(self) -> [u8; 4] {
        match self {
            Background::Transparent => [0; 4],
            Background::Opaque([r, g, b]) => [r, g, b, 255],
        }
    }
}

/// Options of a material stack.
#[derive(Clone, Debug)]
pub struct MaterialStack {
    /// Material colours; its length is the number of materials.
    pub palette: Palette,
    /// Dithering method.
    pub method: Method,
    /// Colour of outside voxels.
    pub background: Background,
    /// Preset name to record in the manifest, if the grid came from one.
    pub preset: Option<String>,
    /// Limit on the dithering buffers, bytes.
    pub memory_limit: u64,
}

impl MaterialStack {
    /// Error diffusion, transparent background, and the memory this
    /// process may use ([`microfrep_io::limits::default_memory_budget`]:
    /// free memory, the cgroup's limit and `ulimit -v`).
    pub fn new(palette: Palette) -> MaterialStack {
        MaterialStack {
            palette,
            method: Method::ErrorDiffusion,
            background: Background::Transparent,
            preset: None,
            memory_limit: microfrep_io::limits::default_memory_budget(),
        }
    }
}

/// What a stack write produced.
#[derive(Clone, Debug, PartialEq)]
pub struct StackReport {
    /// Layers written.
    pub layers: usize,
    /// The dithering counts and integrals (for a grey stack: one channel,
    /// `counts[0]` the inside voxels, `integrals[0]` the sum of `s`).
    pub dither: DitherReport,
    /// Bytes of image data written.
    pub bytes: u64,
}

/// File name of layer `k`.
pub fn layer_file(k: usize) -> String {
    format!("layer_{k:05}.png")
}

/// Writes the directory `out` by filling a temporary sibling directory with
/// `fill` and renaming it when `fill` succeeds (removing it otherwise).
/// `out` must not exist.
pub fn write_dir_atomically<R>(out: &Path, fill: impl FnOnce(&Path) -> Result<R>) -> Result<R> {
    // The project's atomic directory: a unique temporary next to `out`,
    // renamed when complete, removed on error or interruption.
    let dir = microfrep_io::AtomicDir::create(out).map_err(Error::File)?;
    let r = fill(dir.path())?;
    dir.commit().map_err(Error::File)?;
    Ok(r)
}

/// PNG bytes of an image, rows top first; `path` only names it in errors.
fn encode(
    path: &Path,
    width: usize,
    height: usize,
    colour: png::ColorType,
    data: &[u8],
) -> Result<Vec<u8>> {
    let err = |source| Error::Png {
        path: path.to_path_buf(),
        source,
    };
    let mut buf = Vec::new();
    let mut enc = png::Encoder::new(&mut buf, width as u32, height as u32);
    enc.set_color(colour);
    enc.set_depth(png::BitDepth::Eight);
    enc.set_compression(png::Compression::Fast);
    enc.set_filter(png::FilterType::Sub);
    enc.set_adaptive_filter(png::AdaptiveFilterType::NonAdaptive);
    let mut w = enc.write_header().map_err(err)?;
    w.write_image_data(data).map_err(err)?;
    w.finish().map_err(err)?;
    Ok(buf)
}

/// Layers kept before they are encoded in parallel and written.
fn batch_size() -> usize {
    2 * rayon::current_num_threads()
}

/// Encodes one layer's bytes to PNG (`path` names it in errors).
type Encoder<'a> = dyn Fn(&Path, &[u8]) -> Result<Vec<u8>> + Sync + 'a;

/// Encodes pending layers in parallel and writes them in order.
fn flush(
    dir: &Path,
    pending: &mut Vec<(usize, Vec<u8>)>,
    encode_layer: &Encoder<'_>,
    bytes: &mut u64,
) -> Result<()> {
    let encoded: Vec<Result<(PathBuf, Vec<u8>)>> = pending
        .par_iter()
        .map(|(k, layer)| {
            let path = dir.join(layer_file(*k));
            encode_layer(&path, layer).map(|b| (path, b))
        })
        .collect();
    pending.clear();
    for r in encoded {
        let (path, b) = r?;
        let _g = microfrep_io::atomic::begin_write(&path).map_err(Error::File)?;
        fs::write(&path, &b).map_err(io_at(&path))?;
        *bytes += b.len() as u64;
    }
    Ok(())
}

/// Dithers the fractions from `source` (see [`crate::dither`]) and writes
/// the material stack into the new directory `out`.
///
/// `source(k, fractions, inside)` fills layer `k`: `fractions` holds
/// `palette.len()` values per voxel (voxel `i + nx j`, row `j = 0` at the
/// lowest y, sampled at [`StackGrid::x`], [`StackGrid::y`],
/// [`StackGrid::z`]), `inside` the part's mask. `progress(done, total)`
/// counts layers.
pub fn write_material_stack(
    out: &Path,
    grid: &StackGrid,
    opts: &MaterialStack,
    source: &mut LayerSource<'_>,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<StackReport> {
    let n = opts.palette.len();
    let layout = grid.layout(n);
    let bg = opts.background.rgba();
    if let Background::Opaque(c) = opts.background {
        if let Some(m) = opts.palette.materials().iter().find(|m| m.rgb == c) {
            return Err(Error::Invalid(format!(
                "material {} has the background colour {}: outside voxels would print as it",
                m.name,
                hex(c)
            )));
        }
    }
    let mut lut = [bg; 256];
    for (m, mat) in opts.palette.materials().iter().enumerate() {
        lut[m] = [mat.rgb[0], mat.rgb[1], mat.rgb[2], 255];
    }
    lut[OUTSIDE as usize] = bg;
    let (nx, ny) = (grid.nx, grid.ny);
    let encode_layer = |path: &Path, idx: &[u8]| -> Result<Vec<u8>> {
        let mut rgba = vec![0u8; nx * ny * 4];
        for (r, row) in rgba.chunks_mut(nx * 4).enumerate() {
            let j = ny - 1 - r;
            for (px, &m) in row.chunks_mut(4).zip(&idx[j * nx..(j + 1) * nx]) {
                px.copy_from_slice(&lut[m as usize]);
            }
        }
        encode(path, nx, ny, png::ColorType::Rgba, &rgba)
    };
    write_dir_atomically(out, |dir| {
        let mut pending = Vec::new();
        let mut bytes = 0u64;
        let batch = batch_size();
        let report = dither(
            layout,
            opts.method,
            opts.memory_limit,
            source,
            &mut |k, layer| {
                pending.push((k, layer.to_vec()));
                if pending.len() >= batch {
                    flush(dir, &mut pending, &encode_layer, &mut bytes)?;
                }
                Ok(())
            },
            progress,
        )?;
        flush(dir, &mut pending, &encode_layer, &mut bytes)?;
        let mfile = dir.join("manifest.json");
        let text = material_manifest(grid, opts, &report);
        let _g = microfrep_io::atomic::begin_write(&mfile).map_err(Error::File)?;
        fs::write(&mfile, text).map_err(io_at(&mfile))?;
        Ok(StackReport {
            layers: grid.layers,
            dither: report,
            bytes,
        })
    })
}

fn grid_json(grid: &StackGrid) -> serde_json::Map<String, serde_json::Value> {
    let mut m = serde_json::Map::new();
    m.insert("units".into(), "mm".into());
    m.insert("pitch_x".into(), grid.pitch[0].into());
    m.insert("pitch_y".into(), grid.pitch[1].into());
    m.insert("layer_height".into(), grid.layer.into());
    m.insert(
        "dpi".into(),
        serde_json::json!([25.4 / grid.pitch[0], 25.4 / grid.pitch[1]]),
    );
    m.insert(
        "origin".into(),
        serde_json::json!([grid.min[0], grid.min[1], grid.min[2]]),
    );
    m.insert("image_size".into(), serde_json::json!([grid.nx, grid.ny]));
    m.insert("layers".into(), grid.layers.into());
    m.insert(
        "notes".into(),
        "origin is the outer corner of voxel (0, 0) at the bottom of layer 0; image row 0 is \
         the largest y; samples at voxel centres and mid-layer; layer_00000 is the bottom"
            .into(),
    );
    m.insert(
        "files".into(),
        (0..grid.layers).map(layer_file).collect::<Vec<_>>().into(),
    );
    m
}

fn material_manifest(grid: &StackGrid, opts: &MaterialStack, r: &DitherReport) -> String {
    let mut m = grid_json(grid);
    m.insert("format".into(), "material-rgba-png".into());
    m.insert("dithering".into(), opts.method.name().into());
    if let Method::Stochastic { seed } = opts.method {
        m.insert("seed".into(), seed.into());
    }
    if let Some(p) = &opts.preset {
        m.insert("preset".into(), p.clone().into());
    }
    m.insert(
        "background".into(),
        match opts.background {
            Background::Transparent => "transparent #00000000".to_string(),
            Background::Opaque(c) => format!("opaque {}", hex(c)),
        }
        .into(),
    );
    let materials: Vec<serde_json::Value> = opts
        .palette
        .materials()
        .iter()
        .enumerate()
        .map(|(i, mat)| {
            serde_json::json!({
                "index": i,
                "name": mat.name,
                "color": hex(mat.rgb),
                "voxels": r.counts[i],
                "fraction_integral": r.integrals[i],
            })
        })
        .collect();
    m.insert("palette".into(), opts.palette.spec().into());
    m.insert("materials".into(), materials.into());
    m.insert("inside_voxels".into(), r.inside.into());
    let mut s = serde_json::to_string_pretty(&serde_json::Value::Object(m)).expect("json");
    s.push('\n');
    s
}

/// Writes a grey stack: `source(k, values, inside)` fills one attribute
/// value per voxel of layer `k` and the mask; pixels are
/// `round(255 clamp(s, 0, 1))` inside (NaN as 0), 0 outside.
pub fn write_grey_stack(
    out: &Path,
    grid: &StackGrid,
    source: &mut LayerSource<'_>,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<StackReport> {
    let (nx, ny) = (grid.nx, grid.ny);
    let plane = nx * ny;
    // One layer of values, mask and pixels, plus the pending batch.
    let bytes_needed = plane as u128 * (4 + 1 + 1) + (batch_size() * plane) as u128;
    let limit = microfrep_io::limits::default_memory_budget() as u128;
    if bytes_needed > limit {
        return Err(Error::TooLarge {
            what: format!("grey layers of {nx} x {ny} pixels"),
            bytes: bytes_needed,
            limit,
        });
    }
    let encode_layer = |path: &Path, px: &[u8]| encode(path, nx, ny, png::ColorType::Grayscale, px);
    write_dir_atomically(out, |dir| {
        let mut values = vec![0.0f32; plane];
        let mut mask = vec![false; plane];
        let mut pending: Vec<(usize, Vec<u8>)> = Vec::new();
        let mut bytes = 0u64;
        let mut inside = 0u64;
        let mut total = 0.0f64;
        let batch = batch_size();
        for k in 0..grid.layers {
            values.iter_mut().for_each(|v| *v = 0.0);
            mask.iter_mut().for_each(|v| *v = false);
            source(k, &mut values, &mut mask);
            let mut px = vec![0u8; plane];
            for (r, row) in px.chunks_mut(nx).enumerate() {
                let j = ny - 1 - r;
                let src = &values[j * nx..(j + 1) * nx];
                let inm = &mask[j * nx..(j + 1) * nx];
                for ((px, &s), &m) in row.iter_mut().zip(src).zip(inm) {
                    if m {
                        let s = if s.is_nan() { 0.0 } else { s.clamp(0.0, 1.0) };
                        *px = (255.0 * s).round() as u8;
                        inside += 1;
                        total += s as f64;
                    }
                }
            }
            pending.push((k, px));
            if pending.len() >= batch {
                flush(dir, &mut pending, &encode_layer, &mut bytes)?;
            }
            progress(k as u64 + 1, grid.layers as u64);
        }
        flush(dir, &mut pending, &encode_layer, &mut bytes)?;
        let mut m = grid_json(grid);
        m.insert("format".into(), "grey-8bit-png".into());
        m.insert(
            "pixel".into(),
            "round(255 * clamp(s, 0, 1)) inside, 0 outside".into(),
        );
        m.insert("inside_voxels".into(), inside.into());
        m.insert("value_integral".into(), total.into());
        let mfile = dir.join("manifest.json");
        let mut s = serde_json::to_string_pretty(&serde_json::Value::Object(m)).expect("json");
        s.push('\n');
        let _g = microfrep_io::atomic::begin_write(&mfile).map_err(Error::File)?;
        fs::write(&mfile, s).map_err(io_at(&mfile))?;
        Ok(StackReport {
            layers: grid.layers,
            dither: DitherReport {
                counts: vec![inside],
                integrals: vec![total],
                inside,
            },
            bytes,
        })
    })
}

/// The layer source of a [`Shape`] for [`write_material_stack`] (what
/// `microfrep materials` writes): voxel `q` is inside where the value is
/// `>= 0` at its centre, and material `c < materials - 1` takes attribute
/// channel `c` there (NaN as 0; the last material takes the remainder).
///
/// The value and each channel are compiled alone, once. A layer is filled
/// in bands of rows in parallel; tiles of voxels are classified by interval
/// bounds of the value (as the slicer does: proven outside are skipped,
/// proven inside need no sample), channels are evaluated only at inside
/// voxels, with a tape shortened where the intervals decide branches
/// ([`Simplify::Exact`], the same bits).
pub struct ShapeSource {
    value: Tape,
    channels: Vec<Tape>,
    grid: StackGrid,
}

/// Side of the tiles that bands of rows are cut into.
const TILE: usize = 64;
/// Side of the leaves sampled in one batch (16 x 16 = one block).
const LEAF: usize = 16;
/// Tiles at least this many voxels on a side may get their own tape.
const SIMPLIFY_TILE: usize = 32;

/// An evaluator pair of one tape.
struct Evals {
    tape: Tape,
    batch: BatchEval,
    interval: IntervalEval,
}

impl Evals {
    fn new(tape: &Tape) -> Evals {
        Evals {
            tape: tape.clone(),
            batch: BatchEval::new(tape),
            interval: IntervalEval::new(tape),
        }
    }
}

/// One band of rows of a layer being filled.
struct SourceBand<'a> {
    grid: &'a StackGrid,
    z: f64,
    /// First row of the band.
    j0: usize,
    /// Values per voxel in `fractions`.
    n: usize,
}

impl ShapeSource {
    /// The source of `materials` materials (`materials - 1` attribute
    /// channels of `shape` are read) on `grid`.
    pub fn new(shape: &Shape, grid: &StackGrid, materials: usize) -> Result<ShapeSource> {
        let have = shape.attributes().len();
        if materials == 0 || materials - 1 > have {
            return Err(Error::Invalid(format!(
                "{materials} materials need {} attribute channels; the model has {have}",
                materials.max(1) - 1
            )));
        }
        Ok(ShapeSource {
            value: shape.tape().clone(),
            channels: shape.attributes()[..materials - 1]
                .iter()
                .map(|a| Tape::new(&a.expr))
                .collect(),
            grid: grid.clone(),
        })
    }

    /// Fills layer `k` into cleared buffers: `fractions` holds
    /// `channels + 1` values per voxel (voxel `i + nx j`), `inside` the
    /// mask (the [`LayerSource`] contract).
    pub fn fill(&self, k: usize, fractions: &mut [f32], inside: &mut [bool]) {
        let g = &self.grid;
        let n = self.channels.len() + 1;
        let row = g.nx;
        assert_eq!(inside.len(), g.nx * g.ny, "mask size");
        assert_eq!(fractions.len(), g.nx * g.ny * n, "fraction buffer size");
        let z = g.z(k);
        fractions
            .par_chunks_mut(TILE * row * n)
            .zip(inside.par_chunks_mut(TILE * row))
            .enumerate()
            .for_each_init(
                || {
                    (
                        Evals::new(&self.value),
                        self.channels.iter().map(Evals::new).collect::<Vec<_>>(),
                    )
                },
                |(value, channels), (b, (frac, mask))| {
                    let band = SourceBand {
                        grid: g,
                        z,
                        j0: b * TILE,
                        n,
                    };
                    let h = mask.len() / row;
                    for i0 in (0..g.nx).step_by(TILE) {
                        let w = TILE.min(g.nx - i0);
                        band.mask_tile(value, mask, [i0, band.j0], [w, h]);
                        for (c, ev) in channels.iter_mut().enumerate() {
                            band.channel_tile(ev, c, mask, frac, [i0, band.j0], [w, h]);
                        }
                    }
                },
            );
    }
}

impl SourceBand<'_> {
    /// Index in the band's buffers of voxel `(i, j)`.
    fn at(&self, i: usize, j: usize) -> usize {
        (j - self.j0) * self.grid.nx + i
    }

    fn bounds(&self, ev: &mut Evals, at: [usize; 2], size: [usize; 2]) -> Interval {
        let g = self.grid;
        let xs = Interval::with_f32_ends(g.x(at[0]), g.x(at[0] + size[0] - 1));
        let ys = Interval::with_f32_ends(g.y(at[1]), g.y(at[1] + size[1] - 1));
        ev.interval
            .eval(xs, ys, Interval::with_f32_ends(self.z, self.z))
    }

    /// The inside mask over a tile.
    fn mask_tile(&self, ev: &mut Evals, mask: &mut [bool], at: [usize; 2], size: [usize; 2]) {
        let b = self.bounds(ev, at, size);
        if b.hi < 0.0 {
            return;
        }
        if b.lo >= 0.0 && !b.may_be_nan() {
            for j in at[1]..at[1] + size[1] {
                let r = self.at(at[0], j);
                mask[r..r + size[0]].fill(true);
            }
            return;
        }
        if size[0] > LEAF || size[1] > LEAF {
            for (a, s) in quarters(at, size) {
                self.mask_tile(ev, mask, a, s);
            }
            return;
        }
        let g = self.grid;
        let zf = self.z as f32;
        {
            let (x, y, zz) = ev.batch.coords_mut();
            let mut q = 0;
            for j in at[1]..at[1] + size[1] {
                for i in at[0]..at[0] + size[0] {
                    (x[q], y[q], zz[q]) = (g.x(i) as f32, g.y(j) as f32, zf);
                    q += 1;
                }
            }
        }
        let v = ev.batch.eval_loaded(size[0] * size[1]);
        for (dj, vs) in v.chunks(size[0]).enumerate() {
            let r = self.at(at[0], at[1] + dj);
            for (m, &f) in mask[r..r + size[0]].iter_mut().zip(vs) {
                *m = f >= 0.0;
            }
        }
    }

    /// Channel `c` at the inside voxels of a tile.
    fn channel_tile(
        &self,
        ev: &mut Evals,
        c: usize,
        mask: &[bool],
        frac: &mut [f32],
        at: [usize; 2],
        size: [usize; 2],
    ) {
        let rows = at[1]..at[1] + size[1];
        let cols = at[0]..at[0] + size[0];
        let any = rows.clone().any(|j| {
            let r = self.at(at[0], j);
            mask[r..r + size[0]].iter().any(|&m| m)
        });
        if !any {
            return;
        }
        if size[0] >= SIMPLIFY_TILE && size[1] >= SIMPLIFY_TILE {
            self.bounds(ev, at, size);
            let short = ev
                .tape
                .simplify(ev.interval.values(), Simplify::Exact)
                .filter(|t| 10 * t.len() < 8 * ev.tape.len());
            if let Some(t) = short {
                let mut local = Evals::new(&t);
                return self.channel_tile(&mut local, c, mask, frac, at, size);
            }
        }
        if size[0] > LEAF || size[1] > LEAF {
            for (a, s) in quarters(at, size) {
                self.channel_tile(ev, c, mask, frac, a, s);
            }
            return;
        }
        let g = self.grid;
        let zf = self.z as f32;
        let mut idx = [0usize; LEAF * LEAF];
        let mut m = 0;
        {
            let (x, y, zz) = ev.batch.coords_mut();
            for j in rows {
                let yf = g.y(j) as f32;
                for i in cols.clone() {
                    let q = self.at(i, j);
                    if mask[q] {
                        (x[m], y[m], zz[m]) = (g.x(i) as f32, yf, zf);
                        idx[m] = q;
                        m += 1;
                    }
                }
            }
        }
        let s = ev.batch.eval_loaded(m);
        let n = self.n;
        for (&q, &v) in idx[..m].iter().zip(s) {
            frac[q * n + c] = if v.is_nan() { 0.0 } else { v };
        }
    }
}

/// The four quarters of a tile (fewer when a side is one voxel).
fn quarters(at: [usize; 2], size: [usize; 2]) -> Vec<([usize; 2], [usize; 2])> {
    let hw = size[0].div_ceil(2);
    let hh = size[1].div_ceil(2);
    let mut out = Vec::with_capacity(4);
    for (dx, w) in [(0, hw), (hw, size[0] - hw)] {
        for (dy, h) in [(0, hh), (hh, size[1] - hh)] {
            if w > 0 && h > 0 {
                out.push(([at[0] + dx, at[1] + dy], [w, h]));
            }
        }
    }
    out
}
