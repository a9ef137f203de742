//! The builder: subdivision, one pore per cell solved for its porosity,
//! and the field.

use crate::cubemap::CubeMap;
use crate::curve::{Quad, P2};
use crate::error::PoreError;
use crate::field::{
    neighbours, CellBox, Fast3, Fast3f, Index, LeafBoxF, Pore3, PoreField, Pores as FieldPores,
};
use crate::pore2::{self, MAX_KAPPA};
use crate::pore3::TEXELS;
use crate::pore3::{self, KAPPA};
use crate::rng::Rng;
use crate::tree::{Cell, CellInfo, Params, Split, Subdivision, Tree};
use microfrep_core::{Expr, PointEval, Tape};
use rayon::prelude::*;
use std::sync::Arc;

/// A scalar given per point: a constant, an expression of the coordinates,
/// or a function.
#[derive(Clone)]
pub enum Spec {
    /// The same value everywhere.
    Constant(f64),
    /// An expression of `x, y, z` (evaluated with the f64 reference
    /// evaluator).
    Expr(Expr),
    /// A function of the point.
    Fn(Arc<dyn Fn([f64; 3]) -> f64 + Send + Sync>),
}

impl std::fmt::Debug for Spec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Spec::Constant(c) => write!(f, "Constant({c})"),
            Spec::Expr(e) => write!(f, "Expr({e:?})"),
            Spec::Fn(_) => write!(f, "Fn(..)"),
        }
    }
}

impl From<f64> for Spec {
    fn from(v: f64) -> Spec {
        Spec::Constant(v)
    }
}

impl From<Expr> for Spec {
    fn from(e: Expr) -> Spec {
        match e.as_const() {
            Some(c) => Spec::Constant(c),
            None => Spec::Expr(e),
        }
    }
}

/// Requested pore size: the cell edge, in model units.
pub type SizeSpec = Spec;
/// Target porosity of each cell (pore volume over cell volume), evaluated
/// at the cell's centre.
pub type PorositySpec = Spec;

/// A sampler of a [`Spec`] for one thread.
enum Sampler {
    Constant(f64),
    Tape(Tape),
    Fn(Arc<dyn Fn([f64; 3]) -> f64 + Send + Sync>),
}

impl Sampler {
    fn new(s: &Spec) -> Sampler {
        match s {
            Spec::Constant(c) => Sampler::Constant(*c),
            Spec::Expr(e) => Sampler::Tape(Tape::new(e)),
            Spec::Fn(f) => Sampler::Fn(f.clone()),
        }
    }
    fn evaluator(&self) -> impl FnMut([f64; 3]) -> f64 + '_ {
        let mut ev = match self {
            Sampler::Tape(t) => Some(PointEval::new(t)),
            _ => None,
        };
        move |p| match self {
            Sampler::Constant(c) => *c,
            Sampler::Tape(_) => ev.as_mut().map_or(f64::NAN, |e| e.eval(p)),
            Sampler::Fn(f) => f(p),
        }
    }
}

/// 2D (cross-sections in the xy plane, extruded along z) or 3D.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dim {
    /// Quadtree cells in the xy plane, closed quadratic B-spline pores.
    Two,
    /// Octree cells, Doo-Sabin pores.
    Three,
}

/// A custom split rule: direction and percentage per cell (T-mesh).
pub type SplitRule = Arc<dyn Fn(&CellInfo) -> Split + Send + Sync>;

/// What the size argument of a build measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum SizeMeasure {
    /// The cell edge (the requested pore size), in model units.
    #[default]
    Edge,
    /// The paper's cell area (2D) or volume (3D) per pore, `m / P` of
    /// Sec. 4.3: the part's area or volume `m` over the number of pores
    /// `P` wanted. Cells are refined until their area / volume is at most
    /// this (the edge is its square / cube root).
    PerPore,
}

/// Derived points set by hand (the paper's hand-set distances and `t`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum HandSet {
    /// 2D: the fractions `l_i / side_i` of the first three derived points
    /// along the parent's sides (counter-clockwise from its lower-left
    /// corner), each in (0, 1); Eq. 8 gives the fourth from the cell's
    /// porosity (a cell whose porosity has no fourth in [0, 1] is an
    /// error).
    Distances([f64; 3]),
    /// 3D: Eq. 9's parameters `t[s][k]` of the derived points (vertex `s`
    /// as in [`crate::pore3`], axis `k`), each in [0, 1]. They fix the
    /// pore's shape (the derived polyhedron up to scale); its scale is then
    /// solved for the cell's porosity, so the built `t` are these moved
    /// together (reported in [`PoreShape::Three`]). A cell where that
    /// shape cannot meet its porosity within the rules is an error.
    T([[f64; 3]; 8]),
}

/// Build options.
#[derive(Clone)]
pub struct Options {
    /// 2D or 3D.
    pub dim: Dim,
    /// Quadtree / octree or T-mesh.
    pub subdivision: Subdivision,
    /// A custom rule that decides every cell's split (overrides
    /// `subdivision`'s rule, not its first box).
    pub split_rule: Option<SplitRule>,
    /// Irregularity in [0, 0.5]: the spread of the random derived points
    /// (2D: of the fractions along the sides; 3D: of the derived
    /// polyhedron's vertices, relative). 0 gives identical regular pores.
    pub irregularity: f64,
    /// Parent polygon / polyhedron over cell, per side. `None`: 1 in 2D
    /// (closed pores, the paper's Fig. 12), 1.6 in 3D. 2D accepts
    /// [1, 4/3); above 1 pores cut the cell sides and merge with their
    /// neighbours. 3D accepts [4/3, 2]: the derived points then stay on the
    /// parent's edges (`t` in [0, 1]) from the face-touching pore to the
    /// edge-touching one. In 3D the scale does not change the pores'
    /// shapes, only where their derived points lie: it cannot open them
    /// below 0.6274 (see [`crate::pore3`]); [`Options::opening`] does.
    pub parent_scale: Option<f64>,
    /// 2D: the weight of the corner control point of every arc of the pore
    /// curve (rational quadratic arcs, the NURBS form of the paper's
    /// pores; see [`crate::curve`]). 1 (the default) is the polynomial
    /// B-spline; below 1 the pores are rounder (`sqrt(2)/2` makes the
    /// regular pore a circle), above 1 squarer. Any finite weight above 0;
    /// the porosity is met exactly whatever the weight (heavier corners
    /// with a parent scale above 1 reach the cell corners sooner: the
    /// largest pore of parent scale `k` covers them once
    /// `k (1/2 + w) / (1 + w) >= 1`). 3D accepts only 1:
    /// the Doo-Sabin surface is the uniform biquadratic B-spline surface
    /// on the derived polyhedron (all weights 1), and it has no rational
    /// form.
    pub weight: f64,
    /// 3D: how far an opened pore reaches past its cell's face centres,
    /// relative to the half cell, where the Doo-Sabin pore alone would not
    /// reach the faces (targets below its face-touching porosity, 0.6274).
    /// Such a pore keeps the reach and meets its porosity by its shape
    /// instead, blended from the Doo-Sabin surface towards a sphere and a
    /// star ([`crate::pore3::blend`]): with the default 0.05 every pore
    /// opens into its six neighbours from porosity
    /// [`crate::pore3::open_from`]`(0.05)` (0.4559) up, which covers the
    /// paper's 52.36 % to 96.5 %. 0 gives the plain construction (closed
    /// pores below 0.6274). In [0, 0.25].
    pub opening: f64,
    /// What the size argument measures: the cell edge (default) or the
    /// cell area / volume per pore.
    pub size_measure: SizeMeasure,
    /// The derived points set by hand, the same for every pore, instead of
    /// drawn at random (`irregularity` is then not used); `None` draws
    /// them.
    pub hand_set: Option<HandSet>,
    /// Most cells the subdivision may make.
    pub max_cells: usize,
    /// Most bytes the field may hold (the 3D pores' tables take about
    /// 7 KiB a pore); a build predicted to need more is refused before the
    /// pores are made.
    pub memory_limit: u64,
}

impl Default for Options {
    fn default() -> Options {
        Options {
            dim: Dim::Three,
            subdivision: Subdivision::Tree,
            split_rule: None,
            irregularity: 0.15,
            parent_scale: None,
            weight: 1.0,
            opening: pore3::OPENING,
            size_measure: SizeMeasure::Edge,
            hand_set: None,
            max_cells: 1 << 21,
            memory_limit: 4 << 30,
        }
    }
}

impl std::fmt::Debug for Options {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Options")
            .field("dim", &self.dim)
            .field("subdivision", &self.subdivision)
            .field("split_rule", &self.split_rule.as_ref().map(|_| ".."))
            .field("irregularity", &self.irregularity)
            .field("parent_scale", &self.parent_scale)
            .field("weight", &self.weight)
            .field("opening", &self.opening)
            .field("size_measure", &self.size_measure)
            .field("hand_set", &self.hand_set)
            .field("max_cells", &self.max_cells)
            .field("memory_limit", &self.memory_limit)
            .finish()
    }
}

impl Options {
    /// Defaults for 2D.
    pub fn two_d() -> Options {
        Options {
            dim: Dim::Two,
            ..Options::default()
        }
    }
}

/// One cell's pore as built.
#[derive(Clone, Debug)]
pub enum PoreShape {
    /// No pore (target porosity 0).
    None,
    /// A 2D pore.
    Two {
        /// Fractions `l_i / side_i` of the derived points along the parent's
        /// sides (counter-clockwise from its lower-left corner).
        r: [f64; 4],
        /// The derived polygon (control polygon).
        ctrl: [P2; 4],
        /// The curve as four quadratic Bezier arcs.
        arcs: [Quad; 4],
        /// Whether Eq. 8 gave the fourth distance in closed form.
        eq8: bool,
    },
    /// A 3D pore.
    Three {
        /// Eq. 9 parameters `t[s][k]` of the derived points.
        t: [[f64; 3]; 8],
        /// The derived polyhedron (control polyhedron), model coordinates.
        vertices: [[f64; 3]; 8],
        /// Scale of the pore's shape.
        lambda: f64,
        /// Irregularity used (lower than asked where the rules needed it).
        irregularity: f64,
        /// Blend of the pore's radial table towards the star shape
        /// ([`crate::pore3::blend`]): 0 for the Doo-Sabin pore itself,
        /// above 0 for a pore opened by [`Options::opening`].
        roundness: f64,
    },
}

/// One cell and its pore.
#[derive(Clone, Debug)]
pub struct PoreCell {
    /// The cell.
    pub cell: Cell,
    /// Target porosity.
    pub target: f64,
    /// Porosity the pore gives (exact in 2D; the tabulated pore's volume by
    /// quadrature in 3D).
    pub porosity: f64,
    /// The pore.
    pub shape: PoreShape,
}

/// What a build made.
#[derive(Clone, Debug)]
pub struct Built {
    /// The field (an `Arc`, ready for [`Expr::field`]).
    pub field: Arc<PoreField>,
    /// Every kept cell with its pore.
    pub cells: Vec<PoreCell>,
    /// Cells with a pore.
    pub pores: usize,
    /// Cells dropped as outside the part.
    pub dropped: usize,
    /// Pores whose irregularity was reduced to meet the rules.
    pub regularized: usize,
    /// Porosity range of the construction with these options.
    pub range: (f64, f64),
    /// 3D: the lowest porosity at which every pore opens into its six
    /// neighbours (with [`Options::opening`] 0, that of the regular
    /// Doo-Sabin pore touching the cell faces, 0.6274; with the default
    /// opening, 0.4559). Infinite in 2D.
    pub open_above: f64,
}

impl Built {
    /// The field as an expression.
    pub fn expr(&self) -> Expr {
        Expr::field(self.field.clone())
    }

    /// The part minus its pores: `min(part, field)`.
    pub fn solid(&self, part: &Expr) -> Expr {
        part.min(self.expr())
    }
}

/// Builder of Kou-Tan pore structures.
pub struct Pores;

/// The porosity range of the construction: `(min, max)` reachable per
/// cell (besides 0, no pore) for these options.
pub fn porosity_range(options: &Options) -> Result<(f64, f64), PoreError> {
    let kappa = kappa_of(options)?;
    check_weight(options)?;
    Ok(match options.dim {
        Dim::Two => (0.0, pore2::max_porosity_weighted(kappa, options.weight)),
        Dim::Three => pore3::range(kappa),
    })
}

/// 3D constants of the construction: the porosity of the regular pore
/// touching the cell faces (the minimum of the paper's range) and touching
/// the cell edges (its maximum).
pub fn porosity_extremes_3d() -> (f64, f64) {
    let s = pore3::shared();
    (s.p_face, s.p_edge)
}

fn kappa_of(o: &Options) -> Result<f64, PoreError> {
    let (k, lo, hi, why) = match o.dim {
        Dim::Two => (
            o.parent_scale.unwrap_or(1.0),
            1.0,
            MAX_KAPPA,
            "2D parent scale must be in [1, 4/3)",
        ),
        Dim::Three => (
            o.parent_scale.unwrap_or(KAPPA),
            pore3::shared().lambda_edge,
            2.0,
            "3D parent scale must be in [4/3, 2]",
        ),
    };
    let ok = match o.dim {
        Dim::Two => k >= lo && k < hi,
        Dim::Three => k >= lo - 1e-9 && k <= hi,
    };
    if !ok {
        return Err(PoreError::Option {
            name: "parent_scale",
            value: k,
            why,
        });
    }
    Ok(k)
}

fn check_weight(o: &Options) -> Result<(), PoreError> {
    let w = o.weight;
    if !(w.is_finite() && w > 0.0) {
        return Err(PoreError::Option {
            name: "weight",
            value: w,
            why: "must be a finite number above 0 (1: the polynomial curve)",
        });
    }
    if o.dim == Dim::Three && w != 1.0 {
        return Err(PoreError::Option {
            name: "weight",
            value: w,
            why: "3D pores take only weight 1 (the Doo-Sabin surface has no rational form)",
        });
    }
    Ok(())
}

fn check_options(o: &Options) -> Result<(), PoreError> {
    let sigma = o.irregularity;
    if !(0.0..=0.5).contains(&sigma) {
        return Err(PoreError::Option {
            name: "irregularity",
            value: sigma,
            why: "must be in [0, 0.5]",
        });
    }
    check_weight(o)?;
    match (o.hand_set, o.dim) {
        (None, _) => {}
        (Some(HandSet::Distances(r)), Dim::Two) => {
            if let Some(&v) = r.iter().find(|v| !(**v > 0.0 && **v < 1.0)) {
                return Err(PoreError::Option {
                    name: "distances",
                    value: v,
                    why: "hand-set distances are fractions of the sides in (0, 1)",
                });
            }
        }
        (Some(HandSet::T(t)), Dim::Three) => {
            if let Some(&v) = t.iter().flatten().find(|v| !(0.0..=1.0).contains(*v)) {
                return Err(PoreError::Option {
                    name: "t",
                    value: v,
                    why: "hand-set t are Eq. 9 parameters in [0, 1]",
                });
            }
        }
        (Some(HandSet::Distances(_)), Dim::Three) | (Some(HandSet::T(_)), Dim::Two) => {
            return Err(PoreError::Option {
                name: "hand_set",
                value: f64::NAN,
                why: "2D pores take three hand-set distances, 3D pores 24 t values",
            });
        }
    }
    if !(0.0..=0.25).contains(&o.opening) {
        return Err(PoreError::Option {
            name: "opening",
            value: o.opening,
            why: "must be in [0, 0.25]",
        });
    }
    kappa_of(o).map(|_| ())
}

fn check_bounds(b: [[f64; 3]; 2]) -> Result<(), PoreError> {
    if (0..3).all(|a| b[0][a].is_finite() && b[1][a].is_finite() && b[0][a] < b[1][a]) {
        Ok(())
    } else {
        Err(PoreError::Bounds { lo: b[0], hi: b[1] })
    }
}

/// Bounds of a part proven by interval analysis (as the mesher finds
/// them). Cells follow these bounds, so a part whose intervals are tight
/// (a block of `min`s of slabs, HyperFun's `hfBlock`) gets cells that line
/// up with it; where the bounds are looser the subdivision simply starts
/// from a larger box (the part itself is unchanged: outside the subdivided
/// box the field is solid).
pub fn part_bounds(part: &Expr) -> Result<[[f64; 3]; 2], PoreError> {
    let shape = microfrep_core::Shape::from(part);
    let b = shape
        .bounds()
        .map(|b| b.corners())
        .map_err(PoreError::PartBounds)?;
    Ok(tighten(&shape, b))
}

/// Plane samples per side when [`tighten`] looks for solid on a plane.
const PLANE_SAMPLES: usize = 32;

/// The proven box `b` pulled in, face by face, to the last plane on which
/// samples find solid: interval bounds of R-function blocks are padded by
/// about 0.1 % of the size, so cells laid on them do not line up with the
/// part (its porosity then misses its target per cell). For a block the
/// result is its exact box; for curved parts the face moves in by at most
/// the cap a sample grid of 32 x 32 per face can miss.
fn tighten(shape: &microfrep_core::Shape, b: [[f64; 3]; 2]) -> [[f64; 3]; 2] {
    let mut pe = shape.point();
    let mut out = b;
    for a in 0..3 {
        let (p, q) = ((a + 1) % 3, (a + 2) % 3);
        let mut solid_on = |c: f64| {
            let n = PLANE_SAMPLES;
            (0..n * n).any(|k| {
                let mut x = [0.0; 3];
                x[a] = c;
                x[p] = b[0][p] + (k % n) as f64 / (n - 1) as f64 * (b[1][p] - b[0][p]);
                x[q] = b[0][q] + (k / n) as f64 / (n - 1) as f64 * (b[1][q] - b[0][q]);
                pe.eval(x) >= 0.0
            })
        };
        let mid = 0.5 * (b[0][a] + b[1][a]);
        let size = b[1][a] - b[0][a];
        if !solid_on(mid) {
            continue;
        }
        for side in 0..2 {
            // `outer` has no solid found, `inner` has.
            let (mut outer, mut inner) = (b[side][a], mid);
            if solid_on(outer) {
                continue;
            }
            for _ in 0..60 {
                if (outer - inner).abs() <= 1e-12 * size {
                    break;
                }
                let m = 0.5 * (outer + inner);
                if solid_on(m) {
                    inner = m;
                } else {
                    outer = m;
                }
            }
            out[side][a] = inner;
        }
    }
    out
}

impl Pores {
    /// Builds the pore structure of `part` (inside is `part >= 0`) in
    /// `bounds`: cells refined by `size`, one pore per cell meeting the
    /// cell's `porosity`, random with `seed`.
    pub fn build(
        part: &Expr,
        bounds: [[f64; 3]; 2],
        size: SizeSpec,
        porosity: PorositySpec,
        seed: u64,
        options: &Options,
    ) -> Result<Built, PoreError> {
        Pores::build_with_progress(part, bounds, size, porosity, seed, options, &|_, _| {})
    }

    /// As [`Pores::build`], reporting `(pores done, pores)`.
    pub fn build_with_progress(
        part: &Expr,
        bounds: [[f64; 3]; 2],
        size: SizeSpec,
        porosity: PorositySpec,
        seed: u64,
        options: &Options,
        progress: &(dyn Fn(u64, u64) + Sync),
    ) -> Result<Built, PoreError> {
        check_bounds(bounds)?;
        check_options(options)?;
        let sigma = options.irregularity;
        let kappa = kappa_of(options)?;
        let range = porosity_range(options)?;
        let dim = match options.dim {
            Dim::Two => 2,
            Dim::Three => 3,
        };
        let part_tape = Tape::new(part);
        let size_s = Sampler::new(&size);
        let size_fn = std::cell::RefCell::new(size_s.evaluator());
        let per_pore = options.size_measure == SizeMeasure::PerPore;
        let size_eval = |p: [f64; 3]| {
            let v = (size_fn.borrow_mut())(p);
            // Area / volume per pore to the cell edge (bad values pass
            // through to the size check unchanged).
            if per_pore && v > 0.0 {
                v.powf(1.0 / dim as f64)
            } else {
                v
            }
        };
        let tree = Tree::build(&Params {
            dim,
            bounds,
            part: &part_tape,
            size: &size_eval,
            subdivision: options.subdivision,
            rule: options.split_rule.as_deref(),
            max_cells: options.max_cells,
        })?;
        if tree.cells.is_empty() {
            return Err(PoreError::EmptyPart {
                lo: bounds[0],
                hi: bounds[1],
            });
        }
        // Memory: per cell its record, box, fast data and lists, and in 3D
        // (at most) a table per pore, plus the index grid.
        let per_cell = match options.dim {
            Dim::Two => 600,
            Dim::Three => 600 + 4 * 6 * (TEXELS as u64 + 1).pow(2),
        };
        let need = per_cell * tree.cells.len() as u64 + 4 * (1 << 21);
        if need > options.memory_limit {
            return Err(PoreError::Memory {
                cells: tree.cells.len(),
                need,
                limit: options.memory_limit,
            });
        }
        // Targets at the cell centres (2D: the middle of the z range).
        let por_s = Sampler::new(&porosity);
        let mut por = por_s.evaluator();
        let mut targets = Vec::with_capacity(tree.cells.len());
        for c in &tree.cells {
            let at = c.center();
            let v = por(at);
            if !v.is_finite() {
                return Err(PoreError::PorosityNotFinite { value: v, at });
            }
            if v != 0.0 && !(v >= range.0 - 1e-12 && v <= range.1 + 1e-12) {
                return Err(PoreError::PorosityRange {
                    value: v,
                    at,
                    min: range.0,
                    max: range.1,
                    dim,
                    hint: match options.dim {
                        Dim::Two if v > range.1 => {
                            "; a parent scale above 1 (Options::parent_scale) lets 2D pores cut \
                             the cell sides and reach higher porosities"
                        }
                        _ => "",
                    },
                });
            }
            targets.push(if v == 0.0 {
                0.0
            } else {
                v.clamp(range.0, range.1)
            });
        }
        let total = tree.cells.len() as u64;
        let done = std::sync::atomic::AtomicU64::new(0);
        let tick = || {
            let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            if d.is_multiple_of(64) || d == total {
                progress(d, total);
            }
        };
        let (cells, field_pores, regularized) = match options.dim {
            Dim::Two => {
                let solved: Vec<PoreCell> = tree
                    .cells
                    .par_iter()
                    .zip(&targets)
                    .enumerate()
                    .map(|(i, (c, &target))| {
                        let out = solve_2d(c, target, kappa, options, sigma, seed, i);
                        tick();
                        out
                    })
                    .collect::<Result<_, _>>()?;
                let pores = solved
                    .iter()
                    .map(|p| match &p.shape {
                        PoreShape::Two { arcs, .. } => Some(*arcs),
                        _ => None,
                    })
                    .collect();
                (solved, Raw::Two(pores), 0)
            }
            Dim::Three => {
                let solved: Vec<Result<Solved3, PoreError>> = tree
                    .cells
                    .par_iter()
                    .zip(&targets)
                    .enumerate()
                    .map(|(i, (c, &target))| {
                        let out = solve_3d(c, target, kappa, sigma, options, seed, i);
                        tick();
                        out
                    })
                    .collect();
                let mut cells = Vec::with_capacity(solved.len());
                let mut pores = Vec::with_capacity(solved.len());
                let mut reg = 0;
                for s in solved {
                    let (c, p, r) = s?;
                    cells.push(c);
                    pores.push(p);
                    reg += r as usize;
                }
                (cells, Raw::Three(pores), reg)
            }
        };
        let pore_count = cells
            .iter()
            .filter(|c| !matches!(c.shape, PoreShape::None))
            .count();
        // Cap: half the smallest cell side; Lipschitz constant and floor.
        let mut min_side = f64::INFINITY;
        let mut max_half = 0.0f64;
        for c in &tree.cells {
            for a in 0..dim {
                min_side = min_side.min(c.hi[a] - c.lo[a]);
                max_half = max_half.max(0.5 * (c.hi[a] - c.lo[a]));
            }
        }
        let cap = 0.5 * min_side;
        let boxes: Vec<CellBox> = tree
            .cells
            .iter()
            .map(|c| CellBox {
                c: c.center(),
                h: c.half(),
            })
            .collect();
        let mut lip = 1.0f64;
        let mut tables: Vec<f32> = Vec::new();
        let pores = match field_pores {
            Raw::Two(v) => FieldPores::Two(v),
            Raw::Three(v) => {
                // The regular table first, shared by every regular pore.
                let regular = pore3::shared().regular.clone();
                tables.extend_from_slice(regular.values());
                let mut out = Vec::with_capacity(v.len());
                for (i, p) in v.into_iter().enumerate() {
                    out.push(p.map(|(table, lambda)| {
                        let rmean = mean(&table);
                        let h = boxes[i].h;
                        let hmin = h[0].min(h[1]).min(h[2]);
                        lip = lip.max(rmean * table.gauge_lipschitz());
                        let offset = if Arc::ptr_eq(&table, &regular) {
                            0
                        } else {
                            tables.extend_from_slice(table.values());
                            tables.len() - table.values().len()
                        };
                        let m = lambda * rmean * hmin;
                        Pore3 {
                            inv_half: h.map(|v| 1.0 / v),
                            k: m / lambda,
                            m,
                            offset,
                        }
                    }));
                }
                FieldPores::Three(out)
            }
        };
        let lip = lip * (1.0 + 1e-6);
        let has_pore: Vec<bool> = cells
            .iter()
            .map(|c| !matches!(c.shape, PoreShape::None))
            .collect();
        let (own, cand_start, cand, leaf_box) = neighbours(&tree, cap, &|c| has_pore[c as usize]);
        let index = Index::new(&tree);
        let fast3 = match &pores {
            FieldPores::Three(v) => v
                .iter()
                .zip(&boxes)
                .map(|(p, b)| Fast3 {
                    c: b.c,
                    h: b.h,
                    inv: b.h.map(|v| 1.0 / v),
                    k: p.map_or(0.0, |p| p.k),
                    m: p.map_or(0.0, |p| p.m),
                    off: p.map_or(u32::MAX, |p| p.offset as u32),
                })
                .collect(),
            FieldPores::Two(_) => Vec::new(),
        };
        let fast3f = fast3
            .iter()
            .map(|f| Fast3f::new(f, &tables, TEXELS))
            .collect();
        let leaf_box_f = leaf_box.iter().map(LeafBoxF::new).collect();
        let dropped = tree.dropped;
        let name = format!(
            "kou-tan pores ({dim}D, {pore_count} pores, {} cells, seed {seed})",
            tree.cells.len()
        );
        let field = PoreField {
            name,
            dim,
            tree,
            index,
            own,
            cand_start,
            cand,
            leaf_box,
            boxes,
            pores,
            texels: TEXELS,
            tables,
            fast3f,
            leaf_box_f,
            fast3,
            cap,
            lip,
            floor: -max_half,
        };
        let open_above = match options.dim {
            Dim::Two => f64::INFINITY,
            Dim::Three => pore3::open_from(options.opening),
        };
        Ok(Built {
            field: Arc::new(field),
            cells,
            pores: pore_count,
            dropped,
            regularized,
            range,
            open_above,
        })
    }

    /// The `fill --structure irregular` entry: a 3D structure of cells of
    /// edge `cell` and relative density `density` (porosity
    /// `1 - density`) in the part, returning the porous part and the
    /// build.
    pub fn fill(
        part: &Expr,
        bounds: [[f64; 3]; 2],
        cell: f64,
        density: f64,
        seed: u64,
    ) -> Result<(Expr, Built), PoreError> {
        let b = Pores::build(
            part,
            bounds,
            Spec::Constant(cell),
            Spec::Constant(1.0 - density),
            seed,
            &Options::default(),
        )?;
        Ok((b.solid(part), b))
    }
}

fn solve_2d(
    c: &Cell,
    target: f64,
    kappa: f64,
    options: &Options,
    sigma: f64,
    seed: u64,
    i: usize,
) -> Result<PoreCell, PoreError> {
    if target == 0.0 {
        return Ok(PoreCell {
            cell: *c,
            target,
            porosity: 0.0,
            shape: PoreShape::None,
        });
    }
    let (lo, hi) = ([c.lo[0], c.lo[1]], [c.hi[0], c.hi[1]]);
    let s = match options.hand_set {
        Some(HandSet::Distances(r)) => pore2::solve_given(lo, hi, kappa, options.weight, target, r)
            .ok_or(PoreError::Pore {
                cell: i,
                at: c.center(),
                why: "the hand-set distances leave no fourth distance in [0, 1] for this \
                      porosity (Eq. 8)",
            })?,
        _ => {
            let mut rng = Rng::for_cell(seed, i as u64);
            pore2::solve(lo, hi, kappa, options.weight, target, sigma, &mut rng)
        }
    };
    Ok(PoreCell {
        cell: *c,
        target,
        porosity: s.porosity,
        shape: PoreShape::Two {
            r: s.r,
            ctrl: s.ctrl,
            arcs: s.arcs,
            eq8: s.eq8,
        },
    })
}

type Solved3 = (PoreCell, Option<(Arc<CubeMap>, f64)>, bool);

/// Pores as solved, before the field is assembled.
enum Raw {
    Two(Vec<Option<[Quad; 4]>>),
    Three(Vec<Option<(Arc<CubeMap>, f64)>>),
}

fn solve_3d(
    c: &Cell,
    target: f64,
    kappa: f64,
    sigma: f64,
    options: &Options,
    seed: u64,
    i: usize,
) -> Result<Solved3, PoreError> {
    let opening = options.opening;
    if target == 0.0 {
        return Ok((
            PoreCell {
                cell: *c,
                target,
                porosity: 0.0,
                shape: PoreShape::None,
            },
            None,
            false,
        ));
    }
    let s = match options.hand_set {
        Some(HandSet::T(t)) => {
            // The shape of t: the vertices' relative positions (Eq. 9 puts
            // vertex s on axis k at kappa (1 - t/2) of the half cell), as
            // offsets from their mean taken whole (irregularity 1).
            let b = t.map(|r| r.map(|x| 1.0 - 0.5 * x));
            let mean = b.iter().flatten().sum::<f64>() / 24.0;
            let u = b.map(|r| r.map(|x| x / mean - 1.0));
            pore3::solve(target, &u, 1.0, kappa, opening)
                .filter(|s| s.sigma == 1.0)
                .ok_or(PoreError::Pore {
                    cell: i,
                    at: c.center(),
                    why: "the hand-set t give a shape that cannot meet this porosity within \
                          the rules (the pore would reach past the cell's edges or close \
                          where it must open)",
                })?
        }
        _ => {
            let mut rng = Rng::for_cell(seed, i as u64);
            let u = pore3::face_balanced(|| rng.signed());
            pore3::solve(target, &u, sigma, kappa, opening).ok_or(PoreError::Pore {
                cell: i,
                at: c.center(),
                why: "no irregularity down to 0 meets the porosity within the rules",
            })?
        }
    };
    let vertices = pore3::derived_polyhedron(c.center(), c.half(), kappa, &s.t);
    Ok((
        PoreCell {
            cell: *c,
            target,
            porosity: s.porosity,
            shape: PoreShape::Three {
                t: s.t,
                vertices,
                lambda: s.lambda,
                irregularity: s.sigma,
                roundness: s.roundness,
            },
        },
        Some((s.table, s.lambda)),
        s.sigma < sigma,
    ))
}

fn mean(t: &CubeMap) -> f64 {
    let v = t.values();
    v.iter().map(|&x| x as f64).sum::<f64>() / v.len() as f64
}
