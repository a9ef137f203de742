//! The main job in one call: a part (mesh, scan or HyperFun model) filled
//! with a structure at a density (constant, graded by depth below the skin,
//! or any expression of `x`), joined to an optional solid skin (Pasko et
//! al. Eq. 8 with exact `min`/`max`, so the skin has the requested
//! thickness where the part's field is a distance).
//!
//! The filled model is written as HyperFun source using the `mf*` library
//! ([`Filled::source`]): that text is what the shape is built from, so a
//! user can save it, keep editing it, and load it again (a mesh or scan
//! part is bound by name, `--field part=FILE`, noted in the file's first
//! lines).

use crate::load::{self, LoadError, LoadOptions, Loaded, Progress, SourceKind};
use microfrep_core::Bounds;

/// The infill structures.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Structure {
    /// A triply periodic minimal surface, network (solid on one side) or
    /// sheet (a wall around the surface); kind 1..6 as `mfTpms`.
    Tpms {
        /// 1 gyroid, 2 Schwarz P, 3 Schwarz D, 4 Neovius, 5 Schoen IWP,
        /// 6 Fischer-Koch S.
        kind: u8,
        /// Sheet instead of network.
        sheet: bool,
    },
    /// A strut lattice, kind 1..6 as `mfStruts` (sc, bcc, fcc, octet,
    /// kelvin, diamond).
    Struts(u8),
    /// Pasko's rod lattice (`mfLattice`, alpha = 1: exact min/max).
    Rods,
    /// Pasko's porous medium: spherical pores on a cubic grid.
    Pores,
    /// Kou and Tan's irregular pores (`mfPores`).
    Irregular,
}

impl Structure {
    /// Parses a structure name as the CLI takes it.
    pub fn parse(name: &str, sheet: bool) -> Option<Structure> {
        let tpms = |kind| Some(Structure::Tpms { kind, sheet });
        match name {
            "gyroid" => tpms(1),
            "schwarz-p" | "schwarzp" => tpms(2),
            "schwarz-d" | "schwarzd" | "diamond-tpms" => tpms(3),
            "neovius" => tpms(4),
            "iwp" | "schoen-iwp" => tpms(5),
            "fks" | "fischer-koch-s" => tpms(6),
            "sc" => Some(Structure::Struts(1)),
            "bcc" => Some(Structure::Struts(2)),
            "fcc" => Some(Structure::Struts(3)),
            "octet" => Some(Structure::Struts(4)),
            "kelvin" => Some(Structure::Struts(5)),
            "diamond" => Some(Structure::Struts(6)),
            "rods" => Some(Structure::Rods),
            "pores" => Some(Structure::Pores),
            "irregular" => Some(Structure::Irregular),
            _ => None,
        }
    }

    /// The names [`Structure::parse`] takes.
    pub const NAMES: &'static str = "gyroid, schwarz-p, schwarz-d, neovius, iwp, fks (TPMS; \
        --sheet for sheets), sc, bcc, fcc, octet, kelvin, diamond (struts), rods, pores, irregular";

    /// Whether the structure is a strut lattice (a beam lattice in 3MF).
    pub fn is_struts(self) -> bool {
        matches!(self, Structure::Struts(_))
    }
}

/// The infill's density (volume fraction of the infill inside the part).
#[derive(Clone, Debug, PartialEq)]
pub enum Density {
    /// One density everywhere.
    Constant(f64),
    /// `at_surface` just below the skin, `at_depth` from `depth` below the
    /// surface inwards, linear in between.
    Graded {
        /// Density at the surface.
        at_surface: f64,
        /// Density from `depth` inwards.
        at_depth: f64,
        /// Depth of the ramp (model units).
        depth: f64,
    },
    /// A HyperFun expression of `x[1..3]` (and `d`, the depth below the
    /// surface).
    Expression(String),
}

/// What to fill with.
#[derive(Clone, Debug)]
pub struct FillOptions {
    /// The structure.
    pub structure: Structure,
    /// Cell size (model units).
    pub cell: f64,
    /// The density.
    pub density: Density,
    /// Solid skin thickness; `None` for no skin.
    pub skin: Option<f64>,
    /// Seed of the irregular pores.
    pub seed: u64,
}

/// A filled part.
pub struct Filled {
    /// The filled model (skin and infill inside the part).
    pub model: Loaded,
    /// The infill alone inside the core (the part below the skin), for
    /// measuring its density.
    pub infill: Loaded,
    /// The core: the part below the skin.
    pub core: Loaded,
    /// The skin alone (empty without one).
    pub skin: Loaded,
    /// The HyperFun source the model was built from.
    pub source: String,
    /// The part's box.
    pub bounds: Bounds,
    /// The `--field` binding the source needs, if any: `(name, source)`.
    pub binding: Option<(String, String)>,
    /// The part as evaluated in the model (the cached field for a mesh).
    part: Option<microfrep_core::Shape>,
}

fn err(part: &str, message: String) -> LoadError {
    LoadError::Options {
        source_name: part.to_string(),
        message,
    }
}

fn num(v: f64) -> String {
    // Shortest round trip: the file reloads to the same model.
    format!("{v:?}")
}

/// Fills the part `part` (a source as [`load::load`] takes it) with
/// `opts`; `part_opts` are the part's own load options (a HyperFun part's
/// object and parameters).
pub fn fill(
    part: &str,
    part_opts: &LoadOptions,
    opts: &FillOptions,
    progress: Progress,
) -> Result<Filled, LoadError> {
    if !(opts.cell.is_finite() && opts.cell > 0.0) {
        return Err(err(
            part,
            format!("cell size {} must be positive", opts.cell),
        ));
    }
    if let Some(t) = opts.skin {
        if !(t.is_finite() && t > 0.0) {
            return Err(err(part, format!("skin thickness {t} must be positive")));
        }
    }
    let check = |r: f64| -> Result<(), LoadError> {
        if r.is_finite() && r > 0.0 && r < 1.0 {
            Ok(())
        } else {
            Err(err(part, format!("density {r} must be between 0 and 1")))
        }
    };
    match &opts.density {
        Density::Constant(r) => check(*r)?,
        Density::Graded {
            at_surface,
            at_depth,
            depth,
        } => {
            check(*at_surface)?;
            check(*at_depth)?;
            if !(depth.is_finite() && *depth > 0.0) {
                return Err(err(part, format!("grading depth {depth} must be positive")));
            }
        }
        Density::Expression(_) => {}
    }
    if let (Structure::Pores, Density::Constant(r)) = (opts.structure, &opts.density) {
        let min = 1.0 - std::f64::consts::PI / 6.0;
        if *r < min {
            return Err(err(
                part,
                format!("spherical pores on a cubic grid give densities {min:.4} to 1; {r} is out of range (for lower densities use irregular pores or a TPMS)"),
            ));
        }
    }
    let base = load::load_with_progress(part, part_opts, progress)?;
    let bounds = base
        .shape
        .bounds()
        .map_err(|e| err(part, format!("the part's bounds: {e}")))?;
    let mut out = String::new();
    out.push_str("-- Made by `microfrep fill`: the part filled with ");
    out.push_str(&format!(
        "{:?}, cell {}, density {:?}, skin {:?}.\n",
        opts.structure, opts.cell, opts.density, opts.skin
    ));
    let mut binding = None;
    // A mesh part is sampled once on a grid (its distance clamped to a band
    // around the surface, far bricks filled from their interval): the
    // filled model evaluates the part at every sample of every consumer,
    // and the exact distance through the hierarchy is the costly part.
    let mut cache: Option<f64> = None;
    // The part's value `p` and its depth `d` below the surface.
    let (part_call, depth) = match base.kind {
        SourceKind::HyperFun => {
            let path = load::Source::parse(part)?.path;
            let text = std::fs::read_to_string(&path).map_err(|e| LoadError::Io {
                path: path.clone().into(),
                source: e,
            })?;
            let object = base
                .hyperfun
                .as_ref()
                .map(|m| m.object.clone())
                .unwrap_or_else(|| "my_model".into());
            let renamed = rename_object(&text, &object, "fill_part");
            out.push_str(&format!("-- The part: object {object} of {path}.\n"));
            out.push_str(&renamed);
            out.push('\n');
            // The part's parameters travel as the constant array `pa`.
            let call = "fill_part(x, pa)".to_string();
            // A HyperFun part is no distance: depth from the normalised function.
            (call, "mfNormalize(p)".to_string())
        }
        SourceKind::Mesh | SourceKind::Scan => {
            if base.kind == SourceKind::Mesh {
                cache = Some(band_of(opts, &bounds));
            }
            out.push_str(&format!(
                "-- Bind the part when loading: --field part={part}\n"
            ));
            binding = Some(("part".to_string(), part.to_string()));
            // Meshes and scans are signed distances: depth is the value.
            ("part(x)".to_string(), "p".to_string())
        }
        SourceKind::Example => {
            let text =
                microfrep_hyperfun::printer::try_to_hyperfun(base.shape.value(), "fill_part")
                    .map_err(|e| err(part, format!("the example has no HyperFun form: {e}")))?;
            out.push_str(&format!("-- The part: the built-in example {part}.\n"));
            out.push_str(&text);
            out.push('\n');
            ("fill_part(x, pa)".to_string(), "mfNormalize(p)".to_string())
        }
        SourceKind::Data => {
            return Err(err(
                part,
                "fill takes a mesh, a scan or a HyperFun file as the part".into(),
            ))
        }
    };
    let rho = match &opts.density {
        Density::Constant(r) => {
            if !(r.is_finite() && *r > 0.0 && *r < 1.0) {
                return Err(err(part, format!("density {r} must be between 0 and 1")));
            }
            num(*r)
        }
        Density::Graded {
            at_surface,
            at_depth,
            depth: dd,
        } => {
            for r in [at_surface, at_depth] {
                if !(r.is_finite() && *r > 0.0 && *r < 1.0) {
                    return Err(err(part, format!("density {r} must be between 0 and 1")));
                }
            }
            if !(dd.is_finite() && *dd > 0.0) {
                return Err(err(part, format!("grading depth {dd} must be positive")));
            }
            let start = opts.skin.unwrap_or(0.0);
            format!(
                "mfGrade(d - {}, {}, {}, {})",
                num(start),
                num(*dd),
                num(*at_surface),
                num(*at_depth)
            )
        }
        Density::Expression(e) => format!("({e})"),
    };
    let constant_rho = match &opts.density {
        Density::Constant(r) => Some(*r),
        _ => None,
    };
    let c = num(opts.cell);
    let infill = match opts.structure {
        Structure::Tpms { kind, sheet } => {
            format!("mfTpmsDensity(x, {kind}, {}, {c}, rho)", u8::from(sheet))
        }
        Structure::Struts(kind) => format!("mfStrutsDensity(x, {kind}, {c}, rho)"),
        Structure::Rods => {
            let r = constant_rho.ok_or_else(|| {
                err(
                    part,
                    "rods take a constant density (graded: use a TPMS or struts)".into(),
                )
            })?;
            let l = rod_threshold(r).ok_or_else(|| {
                err(
                    part,
                    format!(
                        "rods reach densities 0 to {:.3}; {r} is out of range",
                        rod_threshold_max()
                    ),
                )
            })?;
            let q = 2.0 * std::f64::consts::PI / opts.cell;
            format!("mfLattice(x, {}, 0, {}, 1)", num(q), num(l))
        }
        Structure::Pores => {
            let r = constant_rho.ok_or_else(|| {
                err(
                    part,
                    "pores take a constant density (graded: use a TPMS or struts)".into(),
                )
            })?;
            let min = 1.0 - std::f64::consts::PI / 6.0;
            if r < min {
                return Err(err(
                    part,
                    format!("spherical pores on a cubic grid give densities {min:.4} to 1; {r} is out of range (for lower densities use irregular pores or a TPMS)"),
                ));
            }
            let radius = opts.cell * ((1.0 - r) * 3.0 / (4.0 * std::f64::consts::PI)).cbrt();
            let h = num(0.5 * opts.cell);
            format!("fill_pores(x, {c}, {h}, {})", num(radius))
        }
        Structure::Irregular => {
            let r = constant_rho.unwrap_or(f64::NAN);
            let porosity = if r.is_nan() {
                format!("1 - {rho}")
            } else {
                num(1.0 - r)
            };
            format!("mfPores(x, p, {c}, {porosity}, {})", opts.seed)
        }
    };
    if opts.structure == Structure::Pores {
        out.push_str(
            "fill_pores(x[3], c, h, r) {\n  array q[3], lo[3], hi[3];\n  q[1] = x[1]; q[2] = x[2]; q[3] = x[3];\n  lo = [-h, -h, -h];\n  hi = [h, h, h];\n  t = mfSawtoothMap(q, c, lo, hi);\n  fill_pores = q[1]*q[1] + q[2]*q[2] + q[3]*q[3] - r*r;\n}\n",
        );
    }
    let pa = base
        .hyperfun
        .as_ref()
        .map(|m| m.params.iter().map(|(_, v)| num(*v)).collect::<Vec<_>>())
        .unwrap_or_default();
    let mut body = String::new();
    if matches!(base.kind, SourceKind::HyperFun | SourceKind::Example) {
        let pa = if pa.is_empty() {
            vec!["0".to_string()]
        } else {
            pa
        };
        body.push_str(&format!(
            "  array pa[{}];\n  pa = [{}];\n",
            pa.len(),
            pa.join(", ")
        ));
    }
    body.push_str(&format!(
        "  p = {part_call};\n  d = {depth};\n  rho = {rho};\n  g = {infill};\n"
    ));
    let skin = opts.skin.map(num);
    let (model, core, fill_only, skin_only) = match &skin {
        Some(t) => (
            format!("max(min(p, {t} - d), min(p, g))"),
            format!("min(p, d - {t})"),
            format!("min(min(p, d - {t}), g)"),
            format!("min(p, {t} - d)"),
        ),
        None => (
            "min(p, g)".to_string(),
            "p".to_string(),
            "min(p, g)".to_string(),
            "-1".to_string(),
        ),
    };
    for (name, value) in [
        ("my_model", &model),
        ("fill_core", &core),
        ("fill_infill", &fill_only),
        ("fill_skin", &skin_only),
    ] {
        out.push_str(&format!(
            "{name}(x[3], a[1]) {{\n{body}  {name} = {value};\n}}\n"
        ));
    }
    // Build the three shapes from the one source.
    let tmp = temp_source(&out)?;
    let fields = binding.iter().cloned().collect::<Vec<_>>();
    let cached: Option<std::sync::Arc<dyn microfrep_core::Field>> = match cache {
        Some(band) => {
            let f = base.shape.value().clone();
            Some(cache_field(&f, &bounds, band, opts.cell, progress)?)
        }
        None => None,
    };
    let with = |object: &str| LoadOptions {
        object: Some(object.into()),
        params: Vec::new(),
        fields: fields.clone(),
        memory_limit: part_opts.memory_limit,
    };
    let spec = tmp.path.display().to_string();
    let loaded = |object: &str| -> Result<Loaded, LoadError> {
        let mut l = match &cached {
            Some(c) => {
                load::load_hyperfun_with(&spec, &with(object), vec![("part".into(), c.clone())])?
            }
            None => load::load_with_progress(&spec, &with(object), progress)?,
        };
        l.shape = l.shape.with_bounds(bounds);
        l.inputs = base.inputs.clone();
        Ok(l)
    };
    let model = loaded("my_model")?;
    let core = loaded("fill_core")?;
    let infill = loaded("fill_infill")?;
    let skin_shape = loaded("fill_skin")?;
    let part = cached
        .as_ref()
        .map(|c| microfrep_core::Shape::from_field(c.clone()).with_bounds(bounds));
    Ok(Filled {
        model,
        infill,
        core,
        skin: skin_shape,
        source: out,
        bounds,
        binding,
        part,
    })
}

/// Half width of the band around the surface where the cached distance is
/// exact: wider than the skin, the grading ramp and a few grid steps.
fn band_of(opts: &FillOptions, b: &Bounds) -> f64 {
    let size = b.size();
    let h = cache_spacing(opts.cell, b);
    let grade = match opts.density {
        Density::Graded { depth, .. } => depth + opts.skin.unwrap_or(0.0),
        // An expression may read the depth anywhere: keep it all.
        Density::Expression(_) => size.iter().copied().fold(0.0, f64::max),
        Density::Constant(_) => 0.0,
    };
    (opts.skin.unwrap_or(0.0) + 4.0 * h).max(grade + 2.0 * h)
}

/// Most samples of the cached part (512 MiB of f64).
const CACHE_SAMPLES: usize = 1 << 26;

/// Grid step of the cached part: an eighth of a cell, no finer than the
/// sample budget allows over the part's box.
fn cache_spacing(cell: f64, b: &Bounds) -> f64 {
    let vol: f64 = b.size().iter().map(|s| s.max(1e-9)).product();
    let budget = (vol / CACHE_SAMPLES as f64).cbrt();
    (cell / 8.0).max(budget)
}

/// The part's field sampled on a grid over its box (padded by two steps),
/// clamped to `[-band, band]`; bricks whose interval keeps `|f| >= band`
/// are filled without sampling.
fn cache_field(
    f: &microfrep_core::Expr,
    b: &Bounds,
    band: f64,
    cell: f64,
    progress: Progress,
) -> Result<std::sync::Arc<dyn microfrep_core::Field>, LoadError> {
    use microfrep_core::{BatchEval, GridField, Interval, IntervalEval, Tape};
    use rayon::prelude::*;
    let h = cache_spacing(cell, b);
    let lo: [f64; 3] = std::array::from_fn(|a| b.min[a] - 2.0 * h);
    let dims: [usize; 3] =
        std::array::from_fn(|a| ((b.max[a] + 2.0 * h - lo[a]) / h).ceil() as usize + 1);
    let hi: [f64; 3] = std::array::from_fn(|a| lo[a] + (dims[a] - 1) as f64 * h);
    let tape = Tape::new(f);
    const BR: usize = 16;
    let nb: [usize; 3] = std::array::from_fn(|a| dims[a].div_ceil(BR));
    let total = nb[0] * nb[1] * nb[2];
    let done = std::sync::atomic::AtomicU64::new(0);
    let bricks: Vec<(usize, Vec<f64>)> = (0..total)
        .into_par_iter()
        .map_init(
            || (IntervalEval::new(&tape), BatchEval::new(&tape)),
            |(ie, be), k| {
                let bi = [k % nb[0], (k / nb[0]) % nb[1], k / (nb[0] * nb[1])];
                let i0: [usize; 3] = std::array::from_fn(|a| bi[a] * BR);
                let n: [usize; 3] = std::array::from_fn(|a| BR.min(dims[a] - i0[a]));
                let iv = |a: usize| {
                    Interval::new(
                        lo[a] + i0[a] as f64 * h,
                        lo[a] + (i0[a] + n[a] - 1) as f64 * h,
                    )
                };
                let r = ie.eval(iv(0), iv(1), iv(2));
                let count = n[0] * n[1] * n[2];
                let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                if d % 64 == 0 {
                    progress("sampling the part", d, total as u64);
                }
                if !r.may_be_nan() && r.lo >= band {
                    return (k, vec![band; count]);
                }
                if r.hi <= -band {
                    return (k, vec![-band; count]);
                }
                let (mut x, mut y, mut z) = (
                    Vec::with_capacity(count),
                    Vec::with_capacity(count),
                    Vec::with_capacity(count),
                );
                for c in 0..n[2] {
                    for bj in 0..n[1] {
                        for ai in 0..n[0] {
                            x.push((lo[0] + (i0[0] + ai) as f64 * h) as f32);
                            y.push((lo[1] + (i0[1] + bj) as f64 * h) as f32);
                            z.push((lo[2] + (i0[2] + c) as f64 * h) as f32);
                        }
                    }
                }
                let mut out = vec![0.0f32; count];
                be.eval(&x, &y, &z, &mut out);
                (
                    k,
                    out.into_iter()
                        .map(|v| (v as f64).clamp(-band, band))
                        .map(|v| if v.is_nan() { -band } else { v })
                        .collect(),
                )
            },
        )
        .collect();
    let mut values = vec![0.0f64; dims[0] * dims[1] * dims[2]];
    for (k, vals) in bricks {
        let bi = [k % nb[0], (k / nb[0]) % nb[1], k / (nb[0] * nb[1])];
        let i0: [usize; 3] = std::array::from_fn(|a| bi[a] * BR);
        let n: [usize; 3] = std::array::from_fn(|a| BR.min(dims[a] - i0[a]));
        let mut q = 0;
        for c in 0..n[2] {
            for bj in 0..n[1] {
                for ai in 0..n[0] {
                    let idx = (i0[0] + ai) + dims[0] * ((i0[1] + bj) + dims[1] * (i0[2] + c));
                    values[idx] = vals[q];
                    q += 1;
                }
            }
        }
    }
    let g = GridField::new("part", dims, lo, hi, values).map_err(|e| LoadError::Options {
        source_name: "part".into(),
        message: format!("caching the part: {e}"),
    })?;
    Ok(std::sync::Arc::new(g))
}

/// The model source written to a private temporary file while loading.
struct TempSource {
    path: std::path::PathBuf,
}

impl Drop for TempSource {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

fn temp_source(text: &str) -> Result<TempSource, LoadError> {
    use std::sync::atomic::{AtomicU64, Ordering};
    static N: AtomicU64 = AtomicU64::new(0);
    let path = std::env::temp_dir().join(format!(
        "microfrep-fill-{}-{}.hf",
        std::process::id(),
        N.fetch_add(1, Ordering::Relaxed)
    ));
    std::fs::write(&path, text).map_err(|e| LoadError::Io {
        path: path.clone(),
        source: e,
    })?;
    Ok(TempSource { path })
}

/// Every whole-word occurrence of `name` (HyperFun names ignore case)
/// replaced by `with`.
fn rename_object(src: &str, name: &str, with: &str) -> String {
    let lower = src.to_ascii_lowercase();
    let name = name.to_ascii_lowercase();
    let word = |c: u8| c.is_ascii_alphanumeric() || c == b'_';
    let b = lower.as_bytes();
    let mut out = String::with_capacity(src.len());
    let mut i = 0;
    let mut in_comment = false;
    while i < src.len() {
        if !in_comment && lower[i..].starts_with("--") {
            in_comment = true;
        }
        if b[i] == b'\n' {
            in_comment = false;
        }
        if !in_comment
            && lower[i..].starts_with(&name)
            && (i == 0 || !word(b[i - 1]))
            && b.get(i + name.len()).is_none_or(|&c| !word(c))
        {
            out.push_str(with);
            i += name.len();
            continue;
        }
        let ch = src[i..].chars().next().expect("inside the string");
        out.push(ch);
        i += ch.len_utf8();
    }
    out
}

/// Volume fraction of Pasko's rod lattice with threshold `l` (alpha = 1:
/// the exact union of three square-section rods of the slabs
/// `sin(q x) - l >= 0`), by the closed form of the structures crate.
fn rod_fraction(l: f64) -> f64 {
    microfrep_structures::lattice::rod_lattice_volume_fraction(l)
}

fn rod_threshold_max() -> f64 {
    rod_fraction(-1.0 + 1e-9)
}

/// The threshold whose rod lattice has density `r`, by bisection (the
/// fraction decreases with `l`).
fn rod_threshold(r: f64) -> Option<f64> {
    let (mut lo, mut hi) = (-1.0 + 1e-9, 1.0 - 1e-9);
    if r <= rod_fraction(hi) || r >= rod_fraction(lo) {
        return None;
    }
    for _ in 0..80 {
        let mid = 0.5 * (lo + hi);
        if rod_fraction(mid) > r {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(0.5 * (lo + hi))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn renaming_keeps_other_words_and_comments() {
        let src = "-- my_model here\nmy_model(x[3], a[1]) { My_Model = x[1]; my_model2 = 1; }";
        let r = rename_object(src, "my_model", "fill_part");
        assert_eq!(
            r,
            "-- my_model here\nfill_part(x[3], a[1]) { fill_part = x[1]; my_model2 = 1; }"
        );
    }

    #[test]
    fn rod_thresholds_invert_the_closed_form() {
        for r in [0.1, 0.3, 0.5] {
            let l = rod_threshold(r).unwrap();
            assert!((rod_fraction(l) - r).abs() < 1e-9, "{r}: {l}");
        }
        assert!(rod_threshold(1.5).is_none() && rod_threshold(0.0).is_none());
    }
}

/// What [`Filled::measure`] finds.
#[derive(Clone, Debug)]
pub struct FillReport {
    /// Infill volume fraction inside the core (below the skin), with its
    /// error estimate.
    pub density: (f64, f64),
    /// The skin's mean thickness: twice its volume over the areas of the
    /// part's surface and of the core's.
    pub skin: Option<f64>,
    /// Local thickness of the filled solid: minimum and 10th percentile.
    pub thinnest: Option<(f64, f64)>,
    /// Solid components of the filled model.
    pub components: Option<usize>,
    /// Fraction of the pore space inside the part connected to the part's
    /// outside (through the skin: 0 with a closed skin).
    pub open_pores: Option<f64>,
    /// The grid used.
    pub grid: microfrep_analysis::Grid,
}

impl Filled {
    /// The part as the filled model evaluates it (for a mesh part, its
    /// sampled distance).
    pub fn part(&self) -> Result<microfrep_core::Shape, microfrep_analysis::AnalysisError> {
        part_shape(self)
    }

    /// Measures the filled part on a grid of `resolution` voxels on the
    /// longest side of its box.
    pub fn measure(
        &self,
        resolution: usize,
    ) -> Result<FillReport, microfrep_analysis::AnalysisError> {
        use microfrep_analysis::{analyze, AnalyzeOptions, Grid};
        let grid = Grid::new(self.bounds.corners(), resolution)?;
        let quiet = |_: microfrep_analysis::Stage, _: usize, _: usize| {};
        let measure_only = AnalyzeOptions {
            connectivity: false,
            thickness: false,
            ..AnalyzeOptions::default()
        };
        let inf = analyze(
            &self.infill.shape,
            Some(&self.core.shape),
            grid.clone(),
            &measure_only,
            &quiet,
        )?;
        let p_shape = part_shape(self)?;
        let full = AnalyzeOptions::default();
        // Connectivity inside the part: pores open to the part's outside.
        let model = analyze(
            &self.model.shape,
            Some(&p_shape),
            grid.clone(),
            &full,
            &quiet,
        )?;
        let skin = if self.source.contains("max(min(p, ") {
            let core = analyze(&self.core.shape, None, grid.clone(), &measure_only, &quiet)?;
            let p = analyze(&p_shape, None, grid.clone(), &measure_only, &quiet)?;
            let vs = p.volume() - core.volume();
            Some(2.0 * vs / (p.area() + core.area()))
        } else {
            None
        };
        let thinnest = model.thickness.as_ref().and_then(|t| match &t.solid {
            microfrep_analysis::thickness::PhaseThickness::Measured(s) => Some((s.min, s.p10)),
            _ => None,
        });
        let components = model.connectivity.as_ref().map(|c| c.solid_components);
        let open_pores = model.connectivity.as_ref().map(|c| c.open_pore_fraction());
        Ok(FillReport {
            density: (inf.volume_fraction(), inf.volume_fraction_error()),
            skin,
            thinnest,
            components,
            open_pores,
            grid,
        })
    }
}

/// The part alone, from the same source (its `fill_part` call or field).
fn part_shape(f: &Filled) -> Result<microfrep_core::Shape, microfrep_analysis::AnalysisError> {
    if let Some(p) = &f.part {
        return Ok(p.clone());
    }
    let tmp = temp_source(&format!(
        "{}\nfill_whole(x[3], a[1]) {{\n{}  fill_whole = p;\n}}\n",
        f.source,
        body_of(&f.source)
    ))
    .map_err(|e| microfrep_analysis::AnalysisError::Input(e.to_string()))?;
    let opts = LoadOptions {
        object: Some("fill_whole".into()),
        fields: f.binding.iter().cloned().collect(),
        ..Default::default()
    };
    let l = load::load(&tmp.path.display().to_string(), &opts)
        .map_err(|e| microfrep_analysis::AnalysisError::Input(e.to_string()))?;
    Ok(l.shape.with_bounds(f.bounds))
}

/// The statements shared by the generated objects (up to `g = ...`).
fn body_of(src: &str) -> String {
    let start = src
        .find("my_model(x[3], a[1]) {\n")
        .map(|i| i + 23)
        .unwrap_or(0);
    let rest = &src[start..];
    let end = rest.find("  my_model = ").unwrap_or(0);
    rest[..end].to_string()
}
