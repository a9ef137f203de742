//! [`MeshField`]: a triangle mesh as a signed distance field of the core.

use crate::bvh::{self, Bvh, Hit};
use crate::geom::{unit_normal, Feature};
use crate::mesh::{dot, norm, sub, Topology, TriMesh};
use crate::winding::{self, Expansion, QueryBox};
use crate::MeshError;
use microfrep_core::{Field, Interval, RayEntry};
use rayon::prelude::*;
use std::fmt;

/// How inside and outside are told apart.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SignMethod {
    /// [`SignMethod::PseudoNormal`] when the mesh (after orientation repair,
    /// if enabled) is watertight ([`Topology::is_watertight`]) and no two of
    /// its triangles cross, else [`SignMethod::Winding`].
    #[default]
    Auto,
    /// Generalized winding number > 1/2 is inside; robust to holes, flips,
    /// soups, non-manifold edges and self-intersections.
    Winding,
    /// Sign of the closest feature's angle-weighted pseudo-normal; exact for
    /// a watertight mesh without self-intersections. Requested explicitly,
    /// a mesh that is not watertight is an error; self-intersections are
    /// then not looked for.
    PseudoNormal,
}

/// Options of [`MeshField::build`].
#[derive(Clone, Debug)]
pub struct BuildOptions {
    /// Name for diagnostics.
    pub name: String,
    /// Sign rule.
    pub sign: SignMethod,
    /// Far-field parameter of the fast winding number: a node's expansion is
    /// used at distances above `beta` times its radius (Barill et al. use 2;
    /// larger is more accurate and slower).
    pub beta: f64,
    /// Make the orientation consistent across manifold edges first
    /// ([`TriMesh::orient`]); flipped triangles then cost nothing.
    pub orient: bool,
    /// Most bytes the build may use ([`MeshField::predict_memory`]).
    pub memory_limit: u64,
}

impl Default for BuildOptions {
    fn default() -> Self {
        BuildOptions {
            name: "mesh".into(),
            sign: SignMethod::Auto,
            beta: 2.0,
            orient: true,
            memory_limit: crate::memory::default_limit(),
        }
    }
}

enum Sign {
    Pseudo {
        /// Across each edge of each triangle (leaf order), the neighbour
        /// (leaf order).
        neighbours: Vec<[u32; 3]>,
        /// Mesh vertex of each corner (leaf order).
        corners: Vec<[u32; 3]>,
        /// Angle-weighted vertex normals.
        vertex_normals: Vec<[f64; 3]>,
    },
    Winding {
        expansions: Vec<Expansion>,
    },
}

/// The closest point of the mesh to a query.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Closest {
    /// The point.
    pub point: [f64; 3],
    /// Its distance from the query.
    pub distance: f64,
    /// Triangle of the input mesh.
    pub triangle: usize,
    /// Where on the triangle.
    pub feature: Feature,
}

/// A triangle mesh as a signed distance field: `+distance` inside,
/// `-distance` outside (millimetres), gradients, sound interval bounds and a
/// fast batch path. See the crate documentation for the guarantees.
pub struct MeshField {
    name: String,
    bvh: Bvh,
    sign: Sign,
    topology: Topology,
    flipped: usize,
    inverted: Option<f64>,
    self_intersecting: Option<bool>,
    bbox: [[f64; 3]; 2],
    diag: f64,
    beta: f64,
    /// Cached per-cell search seeds and signs ([`SeedGrid`]).
    grid: Option<SeedGrid>,
}

/// A uniform grid over the mesh's box (grown a little), built with the
/// field: per cell the triangle nearest to its centre (a seed that bounds
/// the nearest-triangle search of any point in the cell from the start)
/// and, for the winding-number sign, the sign of the whole cell where
/// [`winding::winding_interval`] decides it (the fast winding number at
/// every point of the cell is then on the same side of 1/2, so the
/// point's sign is known without evaluating it). Both depend only on the
/// mesh, so answers stay a function of the point alone.
struct SeedGrid {
    lo: [f64; 3],
    /// Cells per unit length along each axis.
    inv: [f64; 3],
    n: [usize; 3],
    /// Nearest triangle (leaf order) to each cell's centre.
    seed: Vec<u32>,
    /// Sign of the cell: 1 inside, -1 outside, 0 unknown (always 0 for the
    /// pseudo-normal sign, which is cheap anyway).
    sign: Vec<i8>,
}

impl SeedGrid {
    /// The cell holding `p`, if any (`p` finite).
    #[inline]
    fn cell(&self, p: [f64; 3]) -> Option<usize> {
        let mut idx = 0;
        for a in 0..3 {
            let f = (p[a] - self.lo[a]) * self.inv[a];
            // Also false for NaN.
            if !(f >= 0.0 && f < self.n[a] as f64) {
                return None;
            }
            let i = (f as usize).min(self.n[a] - 1);
            idx = idx * self.n[a] + i;
        }
        Some(idx)
    }

    /// The box of cell `(i, j, k)`, widened by a millionth of a cell on
    /// every side so that it holds every point that [`SeedGrid::cell`]
    /// maps to it despite rounding.
    fn cell_box(&self, ijk: [usize; 3]) -> [Interval; 3] {
        std::array::from_fn(|a| {
            let w = 1.0 / self.inv[a];
            let lo = self.lo[a] + ijk[a] as f64 * w;
            Interval::new(lo - 1e-6 * w, lo + w + 1e-6 * w)
        })
    }
}

/// Cells of the [`SeedGrid`] per triangle, and the bounds of its size.
const GRID_CELLS_PER_TRIANGLE: usize = 2;
const GRID_MIN_CELLS: usize = 4096;
const GRID_MAX_CELLS: usize = 1 << 16;

impl fmt::Debug for MeshField {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("MeshField")
            .field("name", &self.name)
            .field("triangles", &self.bvh.tris.len())
            .field("nodes", &self.bvh.nodes.len())
            .field("sign", &self.sign_method())
            .field("topology", &self.topology)
            .field("flipped", &self.flipped)
            .field("self_intersecting", &self.self_intersecting)
            .finish()
    }
}

/// Nodes a box's winding-number bound may visit before answering "either".
const INTERVAL_BUDGET: usize = 4000;

/// Points farther than this many box diagonals from the mesh's box are
/// outside without a sign test (see [`MeshField::probe`]). At a million
/// diagonals the squared distances of different triangles still differ by
/// about 1e-10 of their size, far above f64 rounding, so the answer agrees
/// with the sign test wherever that test is still reliable.
const FAR_DIAGONALS: f64 = 1e6;

/// A query located: its nearest triangle, or, far from the mesh, how far
/// and in which direction (unit, from the mesh towards the point).
enum Probe {
    Near(Hit),
    Far { distance: f64, direction: [f64; 3] },
}

impl MeshField {
    /// Builds with the default options and no progress report.
    pub fn new(mesh: &TriMesh) -> Result<MeshField, MeshError> {
        MeshField::build(mesh, &BuildOptions::default(), &|_, _| {})
    }

    /// Bytes a build needs at most for a mesh of this size.
    pub fn predict_memory(triangles: u64, vertices: u64, sign: SignMethod) -> u64 {
        let t = triangles;
        // Topology and orientation: half-edges 48 t, pairs and adjacency
        // 60 t, a repaired copy 12 t + 24 v.
        let common = t.saturating_mul(120) + vertices.saturating_mul(24);
        let sign_bytes = match sign {
            // Pseudo-normals: neighbours and corners 24 t, vertex normals 24 v.
            SignMethod::PseudoNormal => t.saturating_mul(24) + vertices.saturating_mul(24),
            // Expansions: at most 2 t nodes of 152 bytes.
            _ => t.saturating_mul(2 * 152),
        };
        // The seed grid: a triangle and a sign per cell.
        let grid = (GRID_CELLS_PER_TRIANGLE as u64)
            .saturating_mul(t)
            .clamp(GRID_MIN_CELLS as u64, GRID_MAX_CELLS as u64)
            * 5;
        bvh::predict_bytes(t)
            .saturating_add(common)
            .saturating_add(grid)
            .saturating_add(sign_bytes)
    }

    /// Builds the field: topology report, optional orientation repair, BVH,
    /// sign data. `progress(done, total)` is called along the way (total is
    /// 4 x triangles). Errors: invalid mesh, more memory than allowed, or
    /// [`SignMethod::PseudoNormal`] requested for a mesh that is not
    /// watertight.
    pub fn build(
        mesh: &TriMesh,
        opts: &BuildOptions,
        progress: &(dyn Fn(u64, u64) + Sync),
    ) -> Result<MeshField, MeshError> {
        mesh.validate()?;
        let t = mesh.triangles.len() as u64;
        let need = MeshField::predict_memory(t, mesh.vertices.len() as u64, opts.sign);
        if need > opts.memory_limit {
            return Err(MeshError::TooLarge {
                triangles: t,
                need,
                limit: opts.memory_limit,
            });
        }
        if !(opts.beta.is_finite() && opts.beta >= 1.0) {
            return Err(MeshError::BadOption(format!(
                "beta must be finite and at least 1, got {}",
                opts.beta
            )));
        }
        let total = 4 * t;
        let mut topology = mesh.topology();
        progress(t, total);
        let mut flipped = 0;
        let mut repaired = None;
        if opts.orient && topology.inconsistent_edges > 0 {
            let mut m = mesh.clone();
            flipped = m.orient();
            topology = m.topology();
            repaired = Some(m);
        }
        // A closed, coherently wound mesh whose normals point inwards has a
        // negative volume; both sign rules would take its outside for its
        // inside (the winding number is -1 in it), so it is turned over.
        let mut inverted = None;
        if opts.orient && topology.is_closed_and_oriented() {
            let v = repaired.as_ref().unwrap_or(mesh).volume();
            if v < 0.0 {
                let m = repaired.get_or_insert_with(|| mesh.clone());
                for t in &mut m.triangles {
                    t.swap(1, 2);
                }
                inverted = Some(v);
            }
        }
        let mesh = repaired.as_ref().unwrap_or(mesh);
        progress(2 * t, total);
        if opts.sign == SignMethod::PseudoNormal && !topology.is_watertight() {
            return Err(MeshError::NotWatertight(topology.warnings().join("; ")));
        }
        let bvh = Bvh::build(mesh, progress, 2 * t, total);
        let mut self_intersecting = None;
        let method = match opts.sign {
            SignMethod::Auto if topology.is_watertight() => {
                let corners: Vec<[u32; 3]> = bvh
                    .original
                    .iter()
                    .map(|&o| mesh.triangles[o as usize])
                    .collect();
                let crossing = crate::intersect::has_self_intersection(&bvh, &corners);
                self_intersecting = Some(crossing);
                if crossing {
                    SignMethod::Winding
                } else {
                    SignMethod::PseudoNormal
                }
            }
            SignMethod::Auto => SignMethod::Winding,
            m => m,
        };
        let sign = match method {
            SignMethod::PseudoNormal => pseudo_normals(mesh, &bvh),
            _ => Sign::Winding {
                expansions: winding::build(&bvh, opts.beta),
            },
        };
        progress(total, total);
        let bbox = mesh.bbox();
        Ok(MeshField {
            name: opts.name.clone(),
            bvh,
            sign,
            topology,
            flipped,
            inverted,
            self_intersecting,
            bbox,
            diag: norm(sub(bbox[1], bbox[0])),
            beta: opts.beta,
            grid: None,
        })
        .map(|mut f| {
            f.grid = f.seed_grid();
            f
        })
    }

    /// The [`SeedGrid`] of a field built without one.
    fn seed_grid(&self) -> Option<SeedGrid> {
        if self.bvh.tris.is_empty() || !self.diag.is_finite() || self.diag <= 0.0 {
            return None;
        }
        let [blo, bhi] = self.bbox;
        let lo: [f64; 3] =
            std::array::from_fn(|a| blo[a] - 0.1 * (bhi[a] - blo[a]) - 0.01 * self.diag);
        let hi: [f64; 3] =
            std::array::from_fn(|a| bhi[a] + 0.1 * (bhi[a] - blo[a]) + 0.01 * self.diag);
        let ext: [f64; 3] = std::array::from_fn(|a| hi[a] - lo[a]);
        let cells =
            (GRID_CELLS_PER_TRIANGLE * self.bvh.tris.len()).clamp(GRID_MIN_CELLS, GRID_MAX_CELLS);
        let size = (ext[0] * ext[1] * ext[2] / cells as f64).cbrt();
        if !(size.is_finite() && size > 0.0) {
            return None;
        }
        let n: [usize; 3] =
            std::array::from_fn(|a| ((ext[a] / size).ceil() as usize).clamp(1, 1024));
        let inv: [f64; 3] = std::array::from_fn(|a| n[a] as f64 / ext[a]);
        let mut grid = SeedGrid {
            lo,
            inv,
            n,
            seed: Vec::new(),
            sign: Vec::new(),
        };
        let winding = matches!(self.sign, Sign::Winding { .. });
        // One row (fixed i, j) per task; along the row the previous
        // cell's triangle seeds the next search.
        let rows: Vec<(Vec<u32>, Vec<i8>)> = (0..n[0] * n[1])
            .into_par_iter()
            .map(|row| {
                let (i, j) = (row / n[1], row % n[1]);
                let mut seeds = Vec::with_capacity(n[2]);
                let mut signs = Vec::with_capacity(n[2]);
                let mut prev = u32::MAX;
                for k in 0..n[2] {
                    let b = grid.cell_box([i, j, k]);
                    let c = [0, 1, 2].map(|a| b[a].mid());
                    let mut seed = Hit::NONE;
                    if prev != u32::MAX {
                        self.bvh.test(c, prev as usize, &mut seed);
                    }
                    let h = self.bvh.closest(c, seed);
                    prev = h.tri;
                    seeds.push(h.tri);
                    let mut s = 0i8;
                    if winding {
                        let v = self.interval(b);
                        if v.lo > 0.0 {
                            s = 1;
                        } else if v.hi < 0.0 {
                            s = -1;
                        }
                    }
                    signs.push(s);
                }
                (seeds, signs)
            })
            .collect();
        for (a, b) in rows {
            grid.seed.extend(a);
            grid.sign.extend(b);
        }
        Some(grid)
    }

    /// The sign rule in use ([`SignMethod::Auto`] resolved).
    pub fn sign_method(&self) -> SignMethod {
        match self.sign {
            Sign::Pseudo { .. } => SignMethod::PseudoNormal,
            Sign::Winding { .. } => SignMethod::Winding,
        }
    }

    /// Topology of the mesh as used (after orientation repair).
    pub fn topology(&self) -> &Topology {
        &self.topology
    }

    /// Triangles flipped by the orientation repair.
    pub fn flipped(&self) -> usize {
        self.flipped
    }

    /// The (negative) volume of the mesh as given, when it was closed and
    /// coherently wound but inside out, and so was turned over.
    pub fn inverted(&self) -> Option<f64> {
        self.inverted
    }

    /// Whether triangles of the mesh cross each other: tested (through the
    /// BVH) only for watertight meshes under [`SignMethod::Auto`], where a
    /// crossing makes the build fall back to the winding number; `None`
    /// where not tested.
    pub fn self_intersecting(&self) -> Option<bool> {
        self.self_intersecting
    }

    /// Bounds of the mesh (min, max).
    pub fn bbox(&self) -> [[f64; 3]; 2] {
        self.bbox
    }

    /// The BVH (for statistics).
    pub fn bvh(&self) -> &Bvh {
        &self.bvh
    }

    /// Far-field parameter in use.
    pub fn beta(&self) -> f64 {
        self.beta
    }

    /// The closest point of the mesh to `p` (exact, f64); `None` when `p`
    /// has a NaN or infinite coordinate, or is so far away that its squared
    /// distance does not fit an f64 (beyond about 1e154).
    pub fn closest(&self, p: [f64; 3]) -> Option<Closest> {
        if p.iter().any(|c| !c.is_finite()) {
            return None;
        }
        let h = self.bvh.closest(p, Hit::NONE);
        if h.tri == u32::MAX || !h.d2.is_finite() {
            return None;
        }
        Some(Closest {
            point: h.point,
            distance: h.d2.sqrt(),
            triangle: self.bvh.original[h.tri as usize] as usize,
            feature: h.feature,
        })
    }

    /// Unsigned distance to the mesh (infinite at an infinite coordinate,
    /// NaN at a NaN one).
    pub fn distance(&self, p: [f64; 3]) -> f64 {
        if p.iter().any(|c| c.is_nan()) {
            return f64::NAN;
        }
        match self.probe(p, Hit::NONE) {
            Probe::Near(h) => h.d2.sqrt(),
            Probe::Far { distance, .. } => distance,
        }
    }

    /// Whether `p` is far enough from the mesh's box that it is outside
    /// under either sign rule, measured as the largest per-axis excess over
    /// the box (so that no square can overflow), with that excess vector.
    fn far_excess(&self, p: [f64; 3]) -> Option<[f64; 3]> {
        let [lo, hi] = self.bbox;
        let q: [f64; 3] = std::array::from_fn(|a| {
            if p[a] < lo[a] {
                p[a] - lo[a]
            } else if p[a] > hi[a] {
                p[a] - hi[a]
            } else {
                0.0
            }
        });
        let m = q.iter().fold(0.0f64, |m, c| m.max(c.abs()));
        (m > FAR_DIAGONALS * self.diag).then_some(q)
    }

    /// The nearest triangle to a point that is not NaN, or, for a point far
    /// from the mesh, its distance and direction.
    ///
    /// Far from the box (more than [`FAR_DIAGONALS`] diagonals) every point
    /// is outside: a closed mesh holds nothing outside its box, and the
    /// winding number of any mesh there is below 1/2 (a solid angle of at
    /// most area / distance^2). Deciding this before the search matters,
    /// because at such distances the squared distances of all triangles
    /// round to the same f64 (the nearest one, and with it the
    /// pseudo-normal sign, is then arbitrary), and beyond 1e154 they
    /// overflow and the search finds nothing.
    fn probe(&self, p: [f64; 3], seed: Hit) -> Probe {
        let far = self.far_excess(p);
        if p.iter().all(|c| c.is_finite()) {
            let mut seed = seed;
            if let Some(g) = &self.grid {
                if let Some(c) = g.cell(p) {
                    let t = g.seed[c];
                    if t != u32::MAX && t != seed.tri {
                        self.bvh.test(p, t as usize, &mut seed);
                    }
                }
            }
            let h = self.bvh.closest(p, seed);
            if h.tri != u32::MAX && h.d2.is_finite() {
                if far.is_none() {
                    return Probe::Near(h);
                }
                let d = h.d2.sqrt();
                return Probe::Far {
                    distance: d,
                    direction: sub(p, h.point).map(|c| c / d),
                };
            }
        }
        // Infinite, or so far that the squares overflow (coordinates are
        // below MAX_COORDINATE, so only far points get here): the excess
        // over the box, scaled to stay finite. Its length differs from the
        // distance to the mesh by at most the box's diagonal, which is
        // below one f64 step at these distances.
        let q = far.unwrap_or([f64::INFINITY; 3]);
        let m = q.iter().fold(0.0f64, |m, c| m.max(c.abs()));
        let s = if m.is_infinite() {
            q.map(|c| if c.is_infinite() { c.signum() } else { 0.0 })
        } else {
            q.map(|c| c / m)
        };
        let n = norm(s);
        Probe::Far {
            distance: m * n,
            direction: s.map(|c| c / n),
        }
    }

    /// Generalized winding number at `p` (fast, hierarchical), where the
    /// field was built with [`SignMethod::Winding`]. It tends to 0 far away and is 0 at an infinite coordinate.
    pub fn winding_number(&self, p: [f64; 3]) -> Option<f64> {
        match &self.sign {
            Sign::Winding { .. }
                if p.iter().any(|c| c.is_infinite()) && !p.iter().any(|c| c.is_nan()) =>
            {
                Some(0.0)
            }
            Sign::Winding { expansions } => Some(winding::winding_number(&self.bvh, expansions, p)),
            Sign::Pseudo { .. } => None,
        }
    }

    /// Whether `p` is inside (field value > 0, or on the surface).
    pub fn is_inside(&self, p: [f64; 3]) -> bool {
        self.eval(p) >= 0.0
    }

    /// +1 inside, -1 outside, for the point `p` with nearest hit `h`.
    fn sign_at(&self, p: [f64; 3], h: &Hit) -> f64 {
        match &self.sign {
            Sign::Pseudo {
                neighbours,
                corners,
                vertex_normals,
            } => {
                let t = h.tri as usize;
                let n = match h.feature {
                    Feature::Face => unit_normal(&self.bvh.tris[t]),
                    Feature::Edge(k) => {
                        let a = unit_normal(&self.bvh.tris[t]);
                        let nb = neighbours[t][k as usize];
                        if nb == u32::MAX {
                            a
                        } else {
                            let b = unit_normal(&self.bvh.tris[nb as usize]);
                            [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
                        }
                    }
                    Feature::Vertex(k) => vertex_normals[corners[t][k as usize] as usize],
                };
                if dot(sub(p, h.point), n) > 0.0 {
                    -1.0
                } else {
                    1.0
                }
            }
            Sign::Winding { expansions } => {
                // The cell's sign where the grid knows it (`p` is then in a
                // cell whose box keeps clear of the surface and over which
                // the fast winding number stays on one side of 1/2).
                if let Some(g) = &self.grid {
                    if let Some(c) = g.cell(p) {
                        match g.sign[c] {
                            1 => return 1.0,
                            -1 => return -1.0,
                            _ => {}
                        }
                    }
                }
                if winding::winding_number(&self.bvh, expansions, p) > 0.5 {
                    1.0
                } else {
                    -1.0
                }
            }
        }
    }

    /// Distances below this at `p` are too small for the direction from
    /// the closest point to be trusted: a billionth of the mesh's size and
    /// of `p`'s distance from the origin, some ten million times the
    /// rounding of the coordinates.
    fn rounding_scale(&self, p: [f64; 3]) -> f64 {
        1e-9 * (self.diag + p.iter().fold(0.0f64, |m, c| m.max(c.abs())))
    }

    fn value_from(&self, p: [f64; 3], h: &Hit) -> f64 {
        let d = h.d2.sqrt();
        if d == 0.0 {
            return 0.0;
        }
        self.sign_at(p, h) * d
    }

    /// The field's value at a located point.
    fn value_of(&self, p: [f64; 3], probe: &Probe) -> f64 {
        match probe {
            Probe::Near(h) => self.value_from(p, h),
            Probe::Far { distance, .. } => -distance,
        }
    }
}

fn pseudo_normals(mesh: &TriMesh, bvh: &Bvh) -> Sign {
    let n = mesh.triangles.len();
    let mut leaf_of = vec![0u32; n];
    for (leaf, &orig) in bvh.original.iter().enumerate() {
        leaf_of[orig as usize] = leaf as u32;
    }
    let nb = mesh.neighbours();
    let neighbours: Vec<[u32; 3]> = bvh
        .original
        .par_iter()
        .map(|&o| {
            nb[o as usize].map(|x| {
                if x == u32::MAX {
                    x
                } else {
                    leaf_of[x as usize]
                }
            })
        })
        .collect();
    let corners: Vec<[u32; 3]> = bvh
        .original
        .iter()
        .map(|&o| mesh.triangles[o as usize])
        .collect();
    let mut vertex_normals = vec![[0.0; 3]; mesh.vertices.len()];
    for t in 0..n {
        let c = mesh.corners(t);
        let nt = unit_normal(&c);
        for k in 0..3 {
            let e1 = sub(c[(k + 1) % 3], c[k]);
            let e2 = sub(c[(k + 2) % 3], c[k]);
            let (l1, l2) = (norm(e1), norm(e2));
            if l1 == 0.0 || l2 == 0.0 {
                continue;
            }
            let angle = (dot(e1, e2) / (l1 * l2)).clamp(-1.0, 1.0).acos();
            let v = &mut vertex_normals[mesh.triangles[t][k] as usize];
            for a in 0..3 {
                v[a] += angle * nt[a];
            }
        }
    }
    Sign::Pseudo {
        neighbours,
        corners,
        vertex_normals,
    }
}

impl Field for MeshField {
    fn name(&self) -> &str {
        &self.name
    }

    fn is_signed_distance(&self) -> bool {
        true
    }

    fn eval(&self, p: [f64; 3]) -> f64 {
        if p.iter().any(|c| c.is_nan()) {
            return f64::NAN;
        }
        self.value_of(p, &self.probe(p, Hit::NONE))
    }

    fn grad(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
        if p.iter().any(|c| c.is_nan()) {
            return (f64::NAN, [f64::NAN; 3]);
        }
        let h = match self.probe(p, Hit::NONE) {
            Probe::Near(h) => h,
            // Outside: the value falls moving away from the mesh.
            Probe::Far {
                distance,
                direction,
            } => return (-distance, direction.map(|c| -c)),
        };
        let d = h.d2.sqrt();
        if d == 0.0 || !d.is_finite() {
            // On the surface: the inward face normal.
            let n = unit_normal(&self.bvh.tris[h.tri as usize]);
            return (0.0, n.map(|c| -c));
        }
        let s = self.sign_at(p, &h);
        if d <= self.rounding_scale(p) {
            // So close that `p - closest` is mostly rounding (a hit a ray
            // caster refined onto the surface): its direction would be
            // noise, so the face's inward normal stands for it, as on the
            // surface itself.
            let n = unit_normal(&self.bvh.tris[h.tri as usize]);
            if n != [0.0; 3] {
                return (s * d, n.map(|c| -c));
            }
        }
        let g = sub(p, h.point).map(|c| s * c / d);
        (s * d, g)
    }

    fn interval(&self, b: [Interval; 3]) -> Interval {
        if b.iter().any(|i| i.is_nan()) {
            return Interval::nan();
        }
        if b.iter().any(|i| !(i.lo.is_finite() && i.hi.is_finite())) {
            return Interval::ENTIRE;
        }
        let c = [0, 1, 2].map(|a| b[a].mid());
        let h = [0, 1, 2]
            .map(|a| {
                let r = (b[a].hi - c[a]).max(c[a] - b[a].lo);
                r * r
            })
            .iter()
            .sum::<f64>()
            .sqrt()
            * (1.0 + 1e-12);
        let d = self.distance(c);
        let slack = 1e-12 * (self.diag + d + h);
        let lo = (d - h - slack).max(0.0);
        let hi = d + h + slack;
        let either = Interval::new(-hi, hi);
        // Sign known only where the box keeps clear of the surface.
        if d - h <= 1e-9 * self.diag + slack {
            return either;
        }
        let inside = match &self.sign {
            // The whole box far away: outside, as for single points.
            _ if d - h - slack > FAR_DIAGONALS * self.diag => Some(false),
            // Closed and oriented: the sign cannot change off the surface.
            Sign::Pseudo { .. } => Some(self.eval(c) > 0.0),
            Sign::Winding { expansions } => {
                let q = QueryBox {
                    iv: b,
                    c,
                    h,
                    dmin: d - h - slack,
                };
                match winding::winding_interval(&self.bvh, expansions, &q, INTERVAL_BUDGET) {
                    Some(w) if w.lo > 0.5 => Some(true),
                    Some(w) if w.hi <= 0.5 => Some(false),
                    _ => None,
                }
            }
        };
        match inside {
            Some(true) => Interval::new(lo, hi),
            Some(false) => Interval::new(-hi, -lo),
            None => either,
        }
    }

    fn grad_interval(&self, b: [Interval; 3]) -> [Interval; 3] {
        if b.iter().any(|i| i.is_nan()) {
            return [Interval::nan(); 3];
        }
        // The gradient is a unit vector everywhere (also on the surface).
        [Interval::new(-1.0, 1.0); 3]
    }

    /// Answers for a closed, coherently oriented mesh (every edge shared
    /// by two triangles traversing it in opposite directions: what either
    /// sign rule needs to be exact, crossings allowed) and a ray that
    /// starts outside the mesh's box. The exact winding number is then 0
    /// at the start and changes only where the ray crosses a triangle, so
    /// the inside begins at the first triangle crossed if that crossing
    /// enters (against the outward normal). A first crossing that leaves,
    /// which only a mesh with crossing or inverted parts has, is left to
    /// the caller's search. This follows the exact winding number where
    /// the sampled search follows its fast approximation; the two differ
    /// only where the approximation errs by more than 1/2.
    fn ray_entry(&self, o: [f64; 3], d: [f64; 3], range: [f64; 2]) -> RayEntry {
        if !self.topology.is_closed_and_oriented() {
            return RayEntry::Unknown;
        }
        if o.iter().chain(&d).chain(&range).any(|c| !c.is_finite()) || !(range[0] <= range[1]) {
            return RayEntry::Unknown;
        }
        let start: [f64; 3] = std::array::from_fn(|a| o[a] + range[0] * d[a]);
        let [lo, hi] = self.bbox;
        if (0..3).all(|a| start[a] >= lo[a] && start[a] <= hi[a]) {
            return RayEntry::Unknown;
        }
        match self.bvh.first_hit(o, d, range) {
            None => RayEntry::Miss,
            Some((t, tri)) => {
                let n = unit_normal(&self.bvh.tris[tri as usize]);
                if dot(n, d) < 0.0 {
                    RayEntry::Enter(t)
                } else {
                    RayEntry::Unknown
                }
            }
        }
    }

    fn eval_batch(&self, x: &[f32], y: &[f32], z: &[f32], out: &mut [f32]) {
        // Neighbouring points of a block share their nearest triangle more
        // often than not: outside the seed grid the previous point's
        // triangle seeds the search.
        let mut prev = u32::MAX;
        for i in 0..out.len() {
            let p = [x[i] as f64, y[i] as f64, z[i] as f64];
            if p.iter().any(|c| c.is_nan()) {
                out[i] = f32::NAN;
                continue;
            }
            let mut seed = Hit::NONE;
            // Inside the seed grid its cell's triangle seeds the search
            // ([`MeshField::probe`]); the previous point's is for elsewhere.
            let in_grid = self.grid.as_ref().is_some_and(|g| g.cell(p).is_some());
            if prev != u32::MAX && !in_grid {
                self.bvh.test(p, prev as usize, &mut seed);
            }
            let probe = self.probe(p, seed);
            if let Probe::Near(h) = &probe {
                prev = h.tri;
            }
            out[i] = self.value_of(p, &probe) as f32;
        }
    }
}
