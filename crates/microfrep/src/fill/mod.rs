//! The main job in one call: a part (a mesh, a scan, a HyperFun model or a
//! built-in example) filled with a structure at a density (constant, graded
//! by depth below the skin, or any field), inside an optional solid skin.
//!
//! Everything is built as one expression graph from typed options
//! ([`FillOptions`]): the part's value `p`, its depth `d` below the surface
//! in millimetres (the value itself for meshes and scans, a Newton estimate
//! of the distance for other functions: [`part::depth_estimate`]), the
//! density field `rho`, the structure `g` solved for `rho`, and
//!
//! - without a skin: `model = min(p, g)`;
//! - with a skin of thickness `t`: `skin = min(p, t - d)`,
//!   `core = min(p, d - t)`, `model = max(skin, min(core, g))`.
//!
//! The CLI, the Python package and the studio call [`fill`]; none builds a
//! fill of its own. [`Filled::hyperfun`] writes the same graph as HyperFun
//! source (through the HyperFun printer), which loads back to the same
//! values; [`Filled::measure`] measures what was built ([`report`]).

pub mod part;
pub mod report;

pub use part::Part;
pub use report::{FillReport, MeasureOptions};

use crate::load::{LoadError, Progress};
use microfrep_core::{Bounds, Expr, Field, Shape};
use microfrep_structures::struts::StrutLattice;
use microfrep_structures::tpms::{Solid, Tpms};
use std::sync::Arc;

/// The infill structures.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Structure {
    /// A triply periodic minimal surface, network (solid on one side) or
    /// sheet (a wall around the surface).
    Tpms {
        /// The surface.
        kind: Tpms,
        /// Sheet instead of network.
        sheet: bool,
    },
    /// A strut lattice.
    Struts(StrutLattice),
    /// Pasko's rod lattice (three families of square rods, exact min/max).
    Rods,
    /// Pasko's porous medium: spherical pores on a cubic grid (their
    /// radius follows the density, so they grade).
    Pores,
    /// Kou and Tan's irregular pores (octree cells, one pore each).
    Irregular,
}

impl Structure {
    /// Parses a structure name as the CLI and Python take it.
    pub fn parse(name: &str, sheet: bool) -> Option<Structure> {
        let tpms = |kind| Some(Structure::Tpms { kind, sheet });
        let s = |k| Some(Structure::Struts(k));
        match name.to_ascii_lowercase().replace('_', "-").as_str() {
            "gyroid" => tpms(Tpms::Gyroid),
            "schwarz-p" | "schwarzp" => tpms(Tpms::SchwarzP),
            "schwarz-d" | "schwarzd" | "diamond-tpms" => tpms(Tpms::SchwarzD),
            "neovius" => tpms(Tpms::Neovius),
            "iwp" | "schoen-iwp" => tpms(Tpms::SchoenIwp),
            "fks" | "fischer-koch-s" => tpms(Tpms::FischerKochS),
            "sc" => s(StrutLattice::ALL[0]),
            "bcc" => s(StrutLattice::ALL[1]),
            "fcc" => s(StrutLattice::ALL[2]),
            "octet" => s(StrutLattice::ALL[3]),
            "kelvin" => s(StrutLattice::ALL[4]),
            "diamond" => s(StrutLattice::ALL[5]),
            "rods" => Some(Structure::Rods),
            "pores" => Some(Structure::Pores),
            "irregular" => Some(Structure::Irregular),
            _ => None,
        }
    }

    /// The names [`Structure::parse`] takes (option names marked, see
    /// [`with_option_names`]).
    pub const NAMES: &'static str = "gyroid, schwarz-p, schwarz-d, neovius, iwp, fks (TPMS; \
        sheets with \u{27e8}sheet\u{27e9}), sc, bcc, fcc, octet, kelvin, diamond (struts), rods, pores \
        (spherical), irregular (Kou-Tan pores)";

    /// Every structure (TPMS as networks and as sheets), for test matrices.
    pub fn all() -> Vec<Structure> {
        let mut v = Vec::new();
        for kind in Tpms::ALL {
            v.push(Structure::Tpms { kind, sheet: false });
            v.push(Structure::Tpms { kind, sheet: true });
        }
        v.extend(StrutLattice::ALL.iter().map(|k| Structure::Struts(*k)));
        v.extend([Structure::Rods, Structure::Pores, Structure::Irregular]);
        v
    }

    /// The name as the CLI spells it (with ` sheet` for TPMS sheets).
    pub fn name(self) -> String {
        match self {
            Structure::Tpms { kind, sheet } => {
                let n = match kind {
                    Tpms::Gyroid => "gyroid",
                    Tpms::SchwarzP => "schwarz-p",
                    Tpms::SchwarzD => "schwarz-d",
                    Tpms::Neovius => "neovius",
                    Tpms::SchoenIwp => "iwp",
                    Tpms::FischerKochS => "fks",
                };
                if sheet {
                    format!("{n} sheet")
                } else {
                    n.to_string()
                }
            }
            Structure::Struts(k) => {
                ["sc", "bcc", "fcc", "octet", "kelvin", "diamond"][strut_index(k)].to_string()
            }
            Structure::Rods => "rods".into(),
            Structure::Pores => "spherical pores".into(),
            Structure::Irregular => "irregular pores".into(),
        }
    }

    /// Whether the structure is a strut lattice (a beam lattice in 3MF).
    pub fn is_struts(self) -> bool {
        matches!(self, Structure::Struts(_))
    }
}

fn strut_index(k: StrutLattice) -> usize {
    StrutLattice::ALL.iter().position(|s| *s == k).unwrap_or(0)
}

/// The infill's density: the volume fraction of the structure inside the
/// core (the part below the skin).
#[derive(Clone, Debug)]
pub enum Density {
    /// One density everywhere.
    Constant(f64),
    /// `at_surface` just below the skin, `at_depth` from `depth` further
    /// in, linear in between.
    Graded {
        /// Density at the surface (below the skin).
        at_surface: f64,
        /// Density from `depth` inwards.
        at_depth: f64,
        /// Length of the ramp (millimetres).
        depth: f64,
    },
    /// A HyperFun expression of `x[1..3]` and `d` (the depth below the
    /// part's surface, millimetres), such as `0.2 + 0.01 * d`.
    Expression(String),
    /// A field built with the Rust or Python API (an expression of the
    /// coordinates).
    Field(Expr),
}

/// What to fill with.
#[derive(Clone, Debug)]
pub struct FillOptions {
    /// The structure.
    pub structure: Structure,
    /// Cell size (millimetres).
    pub cell: f64,
    /// The density.
    pub density: Density,
    /// Solid skin thickness; `None` for no skin.
    pub skin: Option<f64>,
    /// Seed of the irregular pores (0 to 2^53).
    pub seed: u64,
    /// Kou and Tan's controls of the irregular pores (the paper's
    /// defaults unless set).
    pub pores: PoreControls,
    /// Park's material subspaces below the part's surface: layer `k`
    /// (from 1) is material `k`, the part's primary material 0 the rest;
    /// they become the filled model's attribute channels `s1..sK`.
    pub material_layers: Vec<MaterialLayer>,
}

/// A material subspace below the part's surface (Park et al. Sec. 2.3,
/// 3.1, as [`microfrep_graded::subspace::Subspace::below_surface`]): from
/// `depth` millimetres below the surface its material's fraction rises
/// linearly to 1 over `ramp` millimetres, and stays 1 deeper; a later
/// layer overrides an earlier one where it has begun.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MaterialLayer {
    /// Depth below the part's surface where the layer begins (mm, >= 0).
    pub depth: f64,
    /// Length of the ramp from 0 to all of the layer's material (mm, > 0).
    pub ramp: f64,
}

/// Kou and Tan's controls of the irregular pores; `None` keeps the
/// paper's value (the defaults of [`microfrep_pores::Options`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PoreControls {
    /// Spread of the derived polyhedra's vertices, in [0, 0.5] (0.15): 0
    /// gives identical regular pores.
    pub irregularity: Option<f64>,
    /// The parent polyhedron over the cell, per side, in [4/3, 2] (1.6).
    pub parent_scale: Option<f64>,
    /// T-mesh subdivision (cells cut in two at half their longest side)
    /// instead of the octree.
    pub tmesh: bool,
    /// How far a pore below the Doo-Sabin pore's face-touching porosity
    /// (0.6274) reaches past its cell's face centres, relative to the half
    /// cell, in [0, 0.25] (0.05: pores open into their neighbours from
    /// 0.4559 porosity; 0 gives the plain construction).
    pub opening: Option<f64>,
    /// Eq. 9's parameters `t[s][k]` of every pore's derived points, set by
    /// hand (each in [0, 1]): they fix the pores' shape, whose scale then
    /// meets each cell's porosity; `None` draws them (with
    /// `irregularity`).
    pub hand_t: Option<[[f64; 3]; 8]>,
}

impl PoreControls {
    /// Whether every control keeps the paper's value.
    pub fn is_default(&self) -> bool {
        *self == PoreControls::default()
    }

    /// The pores' build options.
    pub fn options(&self) -> microfrep_pores::Options {
        let mut o = microfrep_pores::Options::default();
        if let Some(i) = self.irregularity {
            o.irregularity = i;
        }
        if self.parent_scale.is_some() {
            o.parent_scale = self.parent_scale;
        }
        if self.tmesh {
            o.subdivision = microfrep_pores::Subdivision::TMesh { percent: 0.5 };
        }
        if let Some(v) = self.opening {
            o.opening = v;
        }
        o.hand_set = self.hand_t.map(microfrep_pores::HandSet::T);
        o
    }

    /// The options array of HyperFun's `mfPoreFieldOpt` (as `mfPoresOpt`
    /// takes it): `[irregularity, parent_scale, subdivision, weight,
    /// size_measure, opening]`, then the 24 hand-set `t` if set.
    pub fn hyperfun_array(&self) -> Vec<f64> {
        let o = self.options();
        let mut v = vec![
            o.irregularity,
            o.parent_scale.unwrap_or(microfrep_pores::pore3::KAPPA),
            if self.tmesh { 1.0 } else { 0.0 },
            1.0,
            0.0,
            o.opening,
        ];
        if let Some(t) = self.hand_t {
            v.extend(t.iter().flatten());
        }
        v
    }
}

impl FillOptions {
    /// Options with a constant density, no skin, seed 1.
    pub fn new(structure: Structure, cell: f64, density: f64) -> FillOptions {
        FillOptions {
            structure,
            cell,
            density: Density::Constant(density),
            skin: None,
            seed: 1,
            pores: PoreControls::default(),
            material_layers: Vec::new(),
        }
    }
}

/// Why a fill was refused.
#[derive(Debug, thiserror::Error)]
pub enum FillError {
    /// The part could not be loaded.
    #[error(transparent)]
    Load(#[from] LoadError),
    /// An option is out of range or does not fit the part or structure.
    /// Option names in the text are marked `⟨name⟩` (see
    /// [`with_option_names`]); the error prints them as the CLI spells
    /// them (`--name`).
    #[error("{}", with_option_names(.0, &cli_option))]
    Option(String),
    /// The structure could not be built.
    #[error("{}", with_option_names(.0, &cli_option))]
    Build(String),
}

impl FillError {
    /// The message with the option names as a front end spells them:
    /// `name("cell")` gives `--cell` on the command line, `cell=` in
    /// Python. Names are the CLI's without the dashes (`cell`, `shell`,
    /// `seed`, `density`, `density-grade`, `density-expr`, `bounds`,
    /// `sheet`, `resolution`).
    pub fn message_with(&self, name: &dyn Fn(&str) -> String) -> String {
        match self {
            FillError::Option(m) | FillError::Build(m) => with_option_names(m, name),
            e => e.to_string(),
        }
    }
}

/// The CLI's spelling of an option.
pub fn cli_option(name: &str) -> String {
    format!("--{name}")
}

/// `text` with every marked option name `⟨name⟩` spelled by `name` (a
/// front end's spelling: [`cli_option`] for the command line). Messages
/// and notes of the fill mark the options they advise.
pub fn with_option_names(text: &str, name: &dyn Fn(&str) -> String) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(a) = rest.find('\u{27e8}') {
        out.push_str(&rest[..a]);
        let after = &rest[a + '\u{27e8}'.len_utf8()..];
        match after.find('\u{27e9}') {
            Some(b) => {
                out.push_str(&name(&after[..b]));
                rest = &after[b + '\u{27e9}'.len_utf8()..];
            }
            None => {
                out.push_str(&rest[a..]);
                rest = "";
            }
        }
    }
    out.push_str(rest);
    out
}

fn bad(message: impl Into<String>) -> FillError {
    FillError::Option(message.into())
}

/// A filled part: the shapes every consumer takes, and what they were
/// built from.
#[derive(Clone)]
pub struct Filled {
    /// The filled model (skin and infill inside the part), with the part's
    /// attribute channels.
    pub model: Shape,
    /// The part as the fill evaluates it (for a mesh, its sampled distance).
    pub part: Shape,
    /// The core: the part below the skin (the part itself without one).
    pub core: Shape,
    /// The infill alone inside the core.
    pub infill: Shape,
    /// The skin alone, when there is one.
    pub skin: Option<Shape>,
    /// The depth below the part's surface (millimetres; an estimate for a
    /// part whose value is not a distance).
    pub depth: Expr,
    /// The density field.
    pub density: Expr,
    /// The box the part and every shape here are laid on.
    pub bounds: Bounds,
    /// What was asked.
    pub options: FillOptions,
    /// The designed sizes (strut radius, pores), for the report.
    pub design: Design,
    /// Warnings for the user.
    pub notes: Vec<String>,
    /// Files read (to protect from being overwritten).
    pub inputs: Vec<std::path::PathBuf>,
    /// The pore structure, for irregular pores.
    pores: Option<PoreBuild>,
    /// How the part is written in HyperFun.
    part_form: part::PartForm,
}

/// Designed sizes of the structure, where they are known in closed form.
#[derive(Clone, Debug, Default)]
pub struct Design {
    /// Strut radius (millimetres) for a constant-density strut lattice.
    pub strut_radius: Option<f64>,
    /// Irregular pores: pores made, cells dropped outside the part.
    pub pores: Option<(usize, usize)>,
}

#[derive(Clone)]
struct PoreBuild {
    field: Arc<dyn Field>,
    porosity: Expr,
}

/// Fills `part` with `opts`. `progress(stage, done, total)` reports the
/// long steps (sampling a mesh part, building pores).
pub fn fill(part: &Part, opts: &FillOptions, progress: Progress) -> Result<Filled, FillError> {
    check_options(part, opts)?;
    let b = part.bounds;
    let cap = depth_cap(part, opts);
    let prepared = part.prepare(cap, depth_needed(part, opts), opts.cell, progress)?;
    let p = prepared.value.clone();
    let d = prepared.depth.clone();
    let skin_t = opts.skin;
    let rho = density_field(&opts.density, &d, skin_t)?;
    check_density_range(&prepared, &rho, opts)?;
    let x = Expr::xyz();
    let mut design = Design::default();
    let mut pores = None;
    let c = opts.cell;
    let g = match opts.structure {
        Structure::Tpms { kind, sheet } => {
            let s = if sheet { Solid::Sheet } else { Solid::Network };
            let table = microfrep_structures_hf::tpms_table(kind, s).map_err(FillError::Build)?;
            microfrep_structures::tpms::tpms(kind, s, &x, c, table.piecewise(&rho))
        }
        Structure::Struts(k) => {
            let table = microfrep_structures_hf::strut_table(k).map_err(FillError::Build)?;
            let r = table.piecewise(&rho) * c;
            if let Some(r) = r.as_const() {
                design.strut_radius = Some(r);
            }
            microfrep_structures::struts::strut_lattice(k, &x, c, r)
        }
        Structure::Rods => {
            let Some(r) = rho.as_const() else {
                return Err(bad(
                    "rods take a constant density (for a graded density use a TPMS, struts or pores)",
                ));
            };
            let l = rod_threshold(r).ok_or_else(|| {
                bad(format!(
                    "rods reach densities 0 to {:.3}; {r} is out of range",
                    rod_fraction(-1.0 + 1e-9)
                ))
            })?;
            let q = 2.0 * std::f64::consts::PI / c;
            let slabs = microfrep_structures::lattice::Slabs::uniform(q, l);
            microfrep_structures::lattice::rod_lattice(&x, &slabs, 1.0)
        }
        Structure::Pores => {
            // Spheres of radius r(rho) centred in cubic cells of side c:
            // the solid is where the distance to the cell centre exceeds r.
            let radius = ((1.0 - &rho) * (3.0 / (4.0 * std::f64::consts::PI))).pow(1.0 / 3.0) * c;
            let q: [Expr; 3] =
                std::array::from_fn(|i| (microfrep_core::frep::sawtooth(&x[i], c) - 0.5) * c);
            let r2 = q[0].square() + q[1].square() + q[2].square();
            r2.sqrt() - radius
        }
        Structure::Irregular => {
            let porosity = 1.0 - &rho;
            let built = microfrep_pores::Pores::build_with_progress(
                &p,
                b.corners(),
                microfrep_pores::Spec::Constant(c),
                microfrep_pores::Spec::from(porosity.clone()),
                opts.seed,
                &opts.pores.options(),
                &|d, n| progress("making the pores", d, n),
            )
            .map_err(|e| match e {
                microfrep_pores::PoreError::Option { name, value, why } => bad(format!(
                    "⟨{}⟩ {value}: {why}",
                    match name {
                        "t" => "pore-t".to_string(),
                        n => n.replace('_', "-"),
                    }
                )),
                e => FillError::Build(format!("irregular pores: {e}")),
            })?;
            design.pores = Some((built.pores, built.dropped));
            let field: Arc<dyn Field> = built.field.clone();
            pores = Some(PoreBuild {
                field: field.clone(),
                porosity,
            });
            Expr::field_at(field, x.clone())
        }
    };
    let (model, core, infill, skin) = match skin_t {
        Some(t) => {
            let skin = p.min(t - &d);
            let core = p.min(&d - t);
            let infill = core.min(&g);
            (skin.max(&infill), core, infill, Some(skin))
        }
        None => {
            let m = p.min(&g);
            (m.clone(), p.clone(), m, None)
        }
    };
    let shape = |e: Expr| Shape::new(e).with_bounds(b);
    let mut model_shape = shape(model);
    for a in part.shape.attributes() {
        model_shape = model_shape.with_attribute(&a.name, a.expr.clone());
    }
    if !opts.material_layers.is_empty() {
        use microfrep_graded::subspace::{MaterialModel, Subspace};
        let k = opts.material_layers.len();
        let mut m =
            MaterialModel::new(k + 1, 0).map_err(|e| bad(format!("⟨material-layer⟩: {e}")))?;
        for (i, l) in opts.material_layers.iter().enumerate() {
            // The layer's fraction is its depth coordinate w, which rises
            // from 0 to 1 over the ramp.
            let s = Subspace::below_surface(
                &d,
                l.depth,
                l.ramp,
                [x[0].clone(), x[1].clone()],
                Expr::z(),
                i + 1,
            );
            m.push(s)
                .map_err(|e| bad(format!("⟨material-layer⟩: {e}")))?;
        }
        let fractions = m.fractions(&p);
        for (i, e) in fractions.into_iter().enumerate().skip(1) {
            model_shape = model_shape.with_attribute(&format!("s{i}"), e);
        }
    }
    let mut notes = part.notes.clone();
    if let (Structure::Irregular, Some((made, _))) = (opts.structure, design.pores) {
        if made < 8 {
            notes.push(format!(
                "only {made} pore(s) fit the part: the density is a property of the cells, \
                 not of the part; use a smaller ⟨cell⟩"
            ));
        }
    }
    Ok(Filled {
        model: model_shape,
        part: shape(p),
        core: shape(core),
        infill: shape(infill),
        skin: skin.map(shape),
        depth: d,
        density: rho,
        bounds: b,
        options: opts.clone(),
        design,
        notes,
        inputs: part.inputs.clone(),
        pores,
        part_form: prepared.form,
    })
}

/// How deep the depth must be right: the skin, the grading ramp, and a
/// margin; an expression may read the depth anywhere.
fn depth_cap(part: &Part, opts: &FillOptions) -> f64 {
    let size = part.bounds.size();
    let diag = (size[0].powi(2) + size[1].powi(2) + size[2].powi(2)).sqrt();
    let skin = opts.skin.unwrap_or(0.0);
    let cap = match &opts.density {
        Density::Constant(_) | Density::Field(_) => 2.0 * skin + opts.cell,
        Density::Graded { depth, .. } => 2.0 * (skin + depth) + opts.cell,
        Density::Expression(_) => diag,
    };
    cap.max(2.0 * layers_depth(opts) + opts.cell)
}

/// The depth below which every material layer is whole.
fn layers_depth(opts: &FillOptions) -> f64 {
    opts.material_layers
        .iter()
        .map(|l| l.depth + l.ramp)
        .fold(0.0, f64::max)
}

/// How deep the model reads the depth's value (below that only "deeper"
/// matters): the skin for a constant density, the skin and the grading
/// ramp for a graded one, everywhere for an expression.
fn depth_needed(part: &Part, opts: &FillOptions) -> f64 {
    let skin = opts.skin.unwrap_or(0.0);
    let needed = match &opts.density {
        Density::Constant(_) | Density::Field(_) => skin,
        Density::Graded { depth, .. } => skin + depth,
        Density::Expression(_) => depth_cap(part, opts),
    };
    needed.max(layers_depth(opts))
}

fn check_options(part: &Part, opts: &FillOptions) -> Result<(), FillError> {
    let c = opts.cell;
    if !(c.is_finite() && c > 0.0) {
        return Err(bad(format!(
            "⟨cell⟩ {c} must be a positive size in millimetres"
        )));
    }
    let size = part.bounds.size();
    let smallest = size.iter().copied().fold(f64::INFINITY, f64::min);
    let largest = size.iter().copied().fold(0.0, f64::max);
    if c > largest {
        return Err(bad(format!(
            "⟨cell⟩ {c} is larger than the part ({:.4} x {:.4} x {:.4}): not one cell fits, so \
             the fill would be no structure; choose a cell below {largest:.4}",
            size[0], size[1], size[2]
        )));
    }
    if opts.structure == Structure::Irregular && c > smallest {
        return Err(bad(format!(
            "⟨cell⟩ {c} is larger than the part's smallest side {smallest:.4}: irregular pores \
             need whole cells in the part; choose a cell below {smallest:.4}"
        )));
    }
    // Features below 1e-6 of the part are below what f32 batches resolve.
    if c < largest * 1e-5 {
        return Err(bad(format!(
            "⟨cell⟩ {c} is too small for a part {largest:.4} long: more than 10^5 cells per \
             side; choose a cell of at least {:.3e}",
            largest * 1e-5
        )));
    }
    if let Some(t) = opts.skin {
        if !(t.is_finite() && t > 0.0) {
            return Err(bad(format!("⟨shell⟩ {t} must be a positive thickness")));
        }
        if 2.0 * t >= smallest {
            return Err(bad(format!(
                "⟨shell⟩ {t} leaves no core: the part's smallest side is {smallest:.4}"
            )));
        }
    }
    if !opts.pores.is_default() && opts.structure != Structure::Irregular {
        return Err(bad(format!(
            "⟨irregularity⟩, ⟨parent-scale⟩, ⟨subdivision⟩, ⟨opening⟩ and ⟨pore-t⟩ shape \
             irregular pores; the structure is {}",
            opts.structure.name()
        )));
    }
    for (i, l) in opts.material_layers.iter().enumerate() {
        if !(l.depth.is_finite() && l.depth >= 0.0 && l.ramp.is_finite() && l.ramp > 0.0) {
            return Err(bad(format!(
                "⟨material-layer⟩ {} ({},{}): the depth must be 0 or more and the ramp positive \
                 (millimetres)",
                i + 1,
                l.depth,
                l.ramp
            )));
        }
    }
    if opts.material_layers.len() > 254 {
        return Err(bad("⟨material-layer⟩: at most 254 layers (255 materials)"));
    }
    if !opts.material_layers.is_empty() && !part.shape.attributes().is_empty() {
        return Err(bad(
            "⟨material-layer⟩ gives the model its attribute channels, and the part has its own: \
             drop one",
        ));
    }
    if opts.seed >= 1 << 53 {
        return Err(bad(format!(
            "⟨seed⟩ {} is above 2^53 (seeds are exact in HyperFun's numbers up to 2^53)",
            opts.seed
        )));
    }
    let unit = |what: &str, r: f64| {
        if r.is_finite() && r > 0.0 && r < 1.0 {
            Ok(())
        } else {
            Err(bad(format!(
                "{what} {r} must be between 0 and 1 (a volume fraction)"
            )))
        }
    };
    match &opts.density {
        Density::Constant(r) => unit("⟨density⟩", *r)?,
        Density::Graded {
            at_surface,
            at_depth,
            depth,
        } => {
            unit("⟨density-grade⟩ surface density", *at_surface)?;
            unit("⟨density-grade⟩ inner density", *at_depth)?;
            if !(depth.is_finite() && *depth > 0.0) {
                return Err(bad(format!(
                    "⟨density-grade⟩ depth {depth} must be positive"
                )));
            }
        }
        Density::Expression(e) if e.trim().is_empty() => {
            return Err(bad("⟨density-expr⟩ is empty"));
        }
        _ => {}
    }
    Ok(())
}

/// The density as a field of the point and the depth `d`.
fn density_field(density: &Density, d: &Expr, skin: Option<f64>) -> Result<Expr, FillError> {
    Ok(match density {
        Density::Constant(r) => Expr::constant(*r),
        Density::Graded {
            at_surface,
            at_depth,
            depth,
        } => {
            let t = ((d - skin.unwrap_or(0.0)) / *depth).max(0.0).min(1.0);
            *at_surface + (*at_depth - *at_surface) * t
        }
        Density::Field(e) => e.clone(),
        Density::Expression(text) => expression(text, d)?,
    })
}

/// A placeholder for the depth while a density expression is lowered.
#[derive(Debug)]
struct DepthMark;

impl Field for DepthMark {
    fn name(&self) -> &str {
        "d"
    }
    fn eval(&self, _: [f64; 3]) -> f64 {
        0.0
    }
    fn grad(&self, _: [f64; 3]) -> (f64, [f64; 3]) {
        (0.0, [0.0; 3])
    }
    fn interval(&self, _: [microfrep_core::Interval; 3]) -> microfrep_core::Interval {
        microfrep_core::Interval::ENTIRE
    }
}

/// Lowers the HyperFun expression `text` of `x[1..3]` and `d`.
fn expression(text: &str, d: &Expr) -> Result<Expr, FillError> {
    crate::install_library();
    let mark: Arc<dyn Field> = Arc::new(DepthMark);
    // One line, so a position in it is a column of the expression.
    let prefix = "fill_density(x[3], a[1]) { d = fill_depth(x); fill_density = ";
    let src = format!("{prefix}{text}; }}");
    let opts = microfrep_hyperfun::LoadOptions {
        object: Some("fill_density".into()),
        params: Vec::new(),
        fields: vec![("fill_depth".into(), mark.clone())],
    };
    let model =
        microfrep_hyperfun::load_with_options(&src, "density expression", &opts).map_err(|e| {
            let col = (e.pos.col as usize).saturating_sub(prefix.len());
            bad(format!(
                "⟨density-expr⟩ '{text}': {} (at column {})",
                e.message,
                col.max(1)
            ))
        })?;
    let e = model.shape().value().clone();
    Ok(e.replace_fields(&|f, comp, _| {
        if Arc::ptr_eq(f, &mark) && comp == 0 {
            Some(d.clone())
        } else {
            None
        }
    }))
}

/// Refuses a density field that leaves (0, 1), or that a strut lattice
/// cannot reach, at points sampled inside the part.
fn check_density_range(
    prepared: &part::Prepared,
    rho: &Expr,
    opts: &FillOptions,
) -> Result<(), FillError> {
    let (lo_ok, hi_ok) = match opts.structure {
        Structure::Struts(k) => {
            let t = microfrep_structures_hf::strut_table(k).map_err(FillError::Build)?;
            let ds = t.density();
            (ds[0], ds[ds.len() - 1])
        }
        Structure::Tpms { kind, sheet } => {
            let s = if sheet { Solid::Sheet } else { Solid::Network };
            let t = microfrep_structures_hf::tpms_table(kind, s).map_err(FillError::Build)?;
            let ds = t.density();
            (ds[0], ds[ds.len() - 1])
        }
        Structure::Pores => (1.0 - std::f64::consts::PI / 6.0, 1.0),
        Structure::Rods | Structure::Irregular => (0.0, 1.0),
    };
    let what = match &opts.density {
        Density::Constant(_) => "⟨density⟩",
        Density::Graded { .. } => "⟨density-grade⟩",
        Density::Expression(_) => "⟨density-expr⟩",
        Density::Field(_) => "the density field",
    };
    let hint = match opts.structure {
        Structure::Pores => {
            " (spherical pores on a cubic grid cannot go lower; use irregular pores or a TPMS)"
        }
        _ => "",
    };
    let check = |v: f64, at: [f64; 3]| -> Result<(), FillError> {
        if !(v.is_finite() && v > 0.0 && v < 1.0) {
            return Err(bad(format!(
                "{what} gives {v} at ({:.4}, {:.4}, {:.4}): a density must be between 0 and 1",
                at[0], at[1], at[2]
            )));
        }
        if v < lo_ok - 1e-9 || v > hi_ok + 1e-9 {
            return Err(bad(format!(
                "{what} gives {v} at ({:.4}, {:.4}, {:.4}); {} reaches densities {lo_ok:.4} to \
                 {hi_ok:.4}{hint}",
                at[0],
                at[1],
                at[2],
                opts.structure.name()
            )));
        }
        Ok(())
    };
    if let Some(v) = rho.as_const() {
        return check(v, prepared.sample_point());
    }
    let ev = microfrep_core::Shape::new(rho.clone()).point();
    let mut ev = ev;
    for at in prepared.inside_points(4096) {
        check(ev.eval(at), at)?;
    }
    Ok(())
}

/// Volume fraction of Pasko's rod lattice with threshold `l` (closed form).
fn rod_fraction(l: f64) -> f64 {
    microfrep_structures::lattice::rod_lattice_volume_fraction(l)
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

impl Filled {
    /// The filled model as HyperFun source: the same graph through the
    /// HyperFun printer, so loading it gives the same values (a mesh or
    /// scan part is called as `part(x)`, bound when loading with
    /// `--field part=FILE`, as the header says).
    pub fn hyperfun(&self) -> Result<String, FillError> {
        if !self.options.material_layers.is_empty() {
            return Err(bad(
                "the ⟨material-layer⟩s are attribute channels of the model, which its HyperFun \
                 form does not carry yet: write a .3mf with --volumetric or --palette",
            ));
        }
        let part_field = self.part_form.field();
        let pores = self.pores.clone();
        let p = self.part.value().clone();
        let b = self.bounds;
        let c = self.options.cell;
        let seed = self.options.seed as f64;
        let controls = self.options.pores.clone();
        let names = move |f: &Arc<dyn Field>, comp: u8| {
            use microfrep_hyperfun::printer::{FieldArg, FieldCall};
            if let Some((pf, name)) = &part_field {
                if Arc::ptr_eq(f, pf) && comp == 0 {
                    return Some(FieldCall {
                        name: name.clone(),
                        args: vec![FieldArg::Point],
                    });
                }
            }
            if let Some(pb) = &pores {
                if Arc::ptr_eq(f, &pb.field) && comp == 0 {
                    let mut args = vec![
                        FieldArg::Point,
                        FieldArg::Expr(p.clone()),
                        FieldArg::Expr(Expr::constant(c)),
                        FieldArg::Expr(pb.porosity.clone()),
                        FieldArg::Expr(Expr::constant(seed)),
                        FieldArg::Array(vec![
                            b.min[0], b.min[1], b.min[2], b.max[0], b.max[1], b.max[2],
                        ]),
                    ];
                    let name = if controls.is_default() {
                        "mfPoreField"
                    } else {
                        args.push(FieldArg::Array(controls.hyperfun_array()));
                        "mfPoreFieldOpt"
                    };
                    return Some(FieldCall {
                        name: name.into(),
                        args,
                    });
                }
            }
            None
        };
        let body = microfrep_hyperfun::printer::try_to_hyperfun_with(
            self.model.value(),
            "my_model",
            &names,
        )
        .map_err(|e| {
            bad(format!(
                "the filled model cannot be written as HyperFun: {e}; write a mesh or a slice \
                 stack instead"
            ))
        })?;
        let o = &self.options;
        let mut head = String::new();
        head.push_str(&format!(
            "-- Made by `microfrep fill`: {} of {} mm cells, density {}, {}.\n",
            o.structure.name(),
            o.cell,
            density_text(&o.density),
            match o.skin {
                Some(t) => format!("a {t} mm skin"),
                None => "no skin".into(),
            }
        ));
        if !o.pores.is_default() {
            let a = o.pores.hyperfun_array();
            head.push_str(&format!(
                "-- Kou-Tan controls: irregularity {}, parent scale {}, {} subdivision, \
                 opening {}{}.\n",
                a[0],
                a[1],
                if o.pores.tmesh { "T-mesh" } else { "octree" },
                a[5],
                if o.pores.hand_t.is_some() {
                    ", t set by hand"
                } else {
                    ""
                }
            ));
        }
        head.push_str(&format!(
            "-- The part's box: [{}, {}, {}] .. [{}, {}, {}].\n",
            b.min[0], b.min[1], b.min[2], b.max[0], b.max[1], b.max[2]
        ));
        if let Some(spec) = self.part_form.binding() {
            head.push_str(&format!(
                "-- The part is a data field: load with --field part={spec}\n"
            ));
        }
        if !self.model.attributes().is_empty() {
            head.push_str("-- The part's attribute channels are not written here.\n");
        }
        Ok(head + &body)
    }

    /// The `--field` binding the `.hf` form needs, if any: `(name, source)`.
    pub fn binding(&self) -> Option<(String, String)> {
        self.part_form
            .binding()
            .map(|s| ("part".to_string(), s.to_string()))
    }

    /// Measures what was built ([`report::measure`]).
    pub fn measure(
        &self,
        opts: &MeasureOptions,
        progress: Progress,
    ) -> Result<FillReport, FillError> {
        report::measure(self, opts, progress)
    }

    /// All but the connectivity ([`report::measure_local`]).
    pub fn measure_local(
        &self,
        opts: &MeasureOptions,
        progress: Progress,
    ) -> Result<FillReport, FillError> {
        report::measure_local(self, opts, progress)
    }

    /// The connectivity, into a report from [`Filled::measure_local`]
    /// ([`report::add_connectivity`]).
    pub fn add_connectivity(
        &self,
        r: &mut FillReport,
        opts: &MeasureOptions,
        progress: Progress,
    ) -> Result<(), FillError> {
        report::add_connectivity(self, r, opts, progress)
    }
}

/// The density in words, for headers and reports.
pub fn density_text(d: &Density) -> String {
    match d {
        Density::Constant(r) => format!("{r}"),
        Density::Graded {
            at_surface,
            at_depth,
            depth,
        } => format!("graded {at_surface} at the surface to {at_depth} from {depth} mm deep"),
        Density::Expression(e) => format!("'{e}'"),
        Density::Field(_) => "a field".into(),
    }
}

#[cfg(test)]
mod tests {
    /// Messages name options as the front end spells them: the CLI's
    /// `--cell` by default, Python's `cell=` through `message_with`.
    #[test]
    fn errors_name_options_in_each_front_ends_spelling() {
        let e = bad("\u{27e8}cell\u{27e9} 0 must be positive; try \u{27e8}density-grade\u{27e9}");
        assert_eq!(
            e.to_string(),
            "--cell 0 must be positive; try --density-grade"
        );
        let py = |n: &str| format!("{}=", n.replace('-', "_"));
        assert_eq!(
            e.message_with(&py),
            "cell= 0 must be positive; try density_grade="
        );
        // Unmarked text and a lone marker pass through.
        assert_eq!(with_option_names("a \u{27e8}b", &cli_option), "a \u{27e8}b");
        // No message of the fill spells a CLI option itself.
        // The code before the tests.
        let all = include_str!("mod.rs");
        let src = &all[..all.find("#[cfg(test)]").unwrap_or(all.len())];
        let dashes = "-".repeat(2);
        let needles: Vec<String> = ["cell", "shell", "density", "seed", "sheet", "bounds"]
            .iter()
            .map(|n| format!("{dashes}{n}"))
            .collect();
        for line in src.lines().filter(|l| !l.trim_start().starts_with("//")) {
            if line.contains("assert") || line.contains("Made by") || line.contains("load with") {
                continue;
            }
            for o in &needles {
                assert!(
                    !line.contains(o.as_str()),
                    "an option spelled for the CLI: {line}"
                );
            }
        }
    }

    use super::*;

    #[test]
    fn rod_thresholds_invert_the_closed_form() {
        for r in [0.1, 0.3, 0.5] {
            let l = rod_threshold(r).unwrap();
            assert!((rod_fraction(l) - r).abs() < 1e-9, "{r}: {l}");
        }
        assert!(rod_threshold(1.5).is_none() && rod_threshold(0.0).is_none());
    }

    #[test]
    fn structure_names_parse_back() {
        for s in Structure::all() {
            let n = s.name();
            let sheet = n.ends_with(" sheet");
            let base = n.trim_end_matches(" sheet");
            let base = match base {
                "spherical pores" => "pores",
                "irregular pores" => "irregular",
                b => b,
            };
            assert_eq!(Structure::parse(base, sheet), Some(s), "{n}");
        }
    }
}
