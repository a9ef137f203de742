//! Watertight, 2-manifold triangle meshes of FRep models (inside is f >= 0).
//!
//! A uniform grid is cut into bricks; bricks are classified with interval
//! arithmetic (tight through set operations, which are nodes of the core
//! graph; empty and full ones skipped), surface bricks are sampled
//! densely with the f32 batch evaluator and meshed by marching tetrahedra
//! or marching cubes ([`tets`] and [`cubes`] argue why the result is closed
//! and manifold; [`CellMethod`]), vertices are
//! keyed by their global grid edge so bricks share them, and moved onto the
//! surface by regula falsi on the batch evaluator; a last pass offsets them
//! along their normals to cancel the chordal volume loss ([`correct`]).
//! Bricks run in parallel, a few z-slabs of bricks at a time, and the mesh
//! goes to a [`sink::MeshSink`] as it is made (memory, or a file for meshes
//! too large to hold: [`write::stream_mesh`]); the output depends only on
//! the model and the options.
//!
//! ```
//! use microfrep_core::{Expr, Shape};
//! use microfrep_shapes as prims;
//! use microfrep_mesh::{check::check, MeshOptions, Plan};
//! let ball = Shape::new(prims::sphere(&Expr::xyz(), &prims::v3([0.0; 3]), 1.0));
//! let opts = MeshOptions::new([[-1.0; 3], [1.0; 3]], 16);
//! let mesh = Plan::new(&ball, &opts).unwrap().run(&|_| {}).unwrap();
//! let r = check(&mesh);
//! assert!(r.is_closed_manifold() && r.euler == 2);
//! ```

#![warn(missing_docs)]

mod brick;
pub mod check;
mod classify;
pub mod correct;
pub mod cubes;
pub mod decimate;
pub mod edges;
mod fasthash;
mod grid;
pub mod job;
mod lanes;
pub mod measure;
pub mod memory;
mod pipeline;
mod refine;
pub mod report;
pub mod sampled;
pub mod sharp;
pub mod sink;
pub mod tets;
pub mod write;

use classify::{classify, BrickClass};
pub use grid::Grid;
use microfrep_core::{Expr, GradBatchEval, Shape, Tape};
use rayon::prelude::*;

/// Why a meshing job was refused or failed. Input and size problems are
/// found before any large allocation; `Empty` and `VolumeLoss` after the
/// mesh was made, in which case no output file is left behind.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// A bad option or model for meshing (no underlying error).
    #[error("{0}")]
    Input(String),
    /// The job would not fit in memory.
    #[error("{0}")]
    TooLarge(String),
    /// The mesh came out empty (the message says why); nothing was
    /// written.
    #[error("{0}")]
    Empty(String),
    /// The mesh lost more of the model's volume than allowed (features
    /// thinner than a cell); nothing was written.
    #[error("{0}")]
    VolumeLoss(String),
    /// A broken invariant of the mesher (a bug).
    #[error("internal meshing error: {0}")]
    Internal(String),
    /// Writing the output failed.
    #[error("cannot write {path}")]
    Io {
        /// The output.
        path: String,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The I/O layer refused or failed (input protection, unknown format,
    /// temporaries).
    #[error(transparent)]
    File(#[from] microfrep_io::IoError),
    /// A write inside a mesh sink failed (reported with the path by the
    /// caller that knows it).
    #[error("writing the mesh")]
    Stream(#[source] std::io::Error),
}

/// An indexed triangle mesh; triangles are counter-clockwise seen from
/// outside.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions in model units (millimetres), f32 as in STL and 3MF.
    pub vertices: Vec<[f32; 3]>,
    /// Triangles as three indices into `vertices`.
    pub triangles: Vec<[u32; 3]>,
}

/// What to mesh and how: the box, the resolution and the method. Start
/// from [`MeshOptions::new`] and change fields as needed.
#[derive(Clone, Debug)]
pub struct MeshOptions {
    /// Box to mesh (min, max); the solid is clipped to it.
    pub bounds: [[f64; 3]; 2],
    /// Cells on the longest side of `bounds`.
    pub resolution: usize,
    /// Cells per brick side.
    pub brick: usize,
    /// How a cell's surface is made from its corner signs.
    pub cells: CellMethod,
    /// Evaluate each surface brick with the tape shortened where interval
    /// arithmetic decides set-operation branches over the brick
    /// ([`microfrep_core::Simplify`]); the brick's face nodes, shared with
    /// its neighbours, keep the full tape.
    pub simplify: bool,
    /// Whether vertices are moved off their chords to cancel the chordal
    /// volume loss ([`correct`]; default on). Off, every vertex lies on the
    /// surface to the refinement tolerance (and inside the box); on, each
    /// moves along its normal by 3/4 of its triangles' mean gap to the
    /// surface (at most 3/8 of a cell, more than elsewhere at creases and
    /// thin features), which keeps volumes within 0.1 % where the chords
    /// alone lose a few percent.
    pub volume_correction: bool,
    /// Sharp features (creases and corners) with marching cubes
    /// ([`sharp`]; default off): a cell whose vertex normals spread by more
    /// than 35 degrees gets a vertex where their tangent planes meet, with
    /// its cycle fanned around it; crease segments between two such cells
    /// are flipped onto the crease (within a brick, the two vertices are
    /// merged instead where they found the same stretch of crease); cells
    /// beside a feature are tested too even where their corner samples
    /// look flat; vertices of those
    /// cells are moved onto the surface by Newton steps along their edges.
    /// The volume correction then leaves the vertices of features with
    /// flat sides, and vertices whose triangles are coplanar, where they
    /// are. The output is deterministic for given options, but merges and
    /// the test of the cells beside a feature stop at brick faces, so it
    /// depends on the brick size there (a little, in small bricks).
    /// Ignored with [`CellMethod::Tetrahedra`].
    pub sharp: bool,
    /// Bytes the plan's own tables may take (the brick classes, one byte a
    /// brick); default: [`microfrep_io::limits::memory_limit`]. The mesh
    /// itself is budgeted by [`memory::estimate`] and the job layer.
    pub memory_limit: Option<f64>,
}

/// Surface extraction inside a cell. Both give closed, oriented 2-manifolds
/// with vertices shared across cells (see [`tets`] and [`cubes`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum CellMethod {
    /// Marching tetrahedra on the Kuhn split: vertices also on face and
    /// body diagonals, so creases are cut less (the rod lattice's area is
    /// within 0.7 % at 20 cells per period), about 1.6x the triangles of
    /// dual contouring.
    Tetrahedra,
    /// Marching cubes with a fixed rule for ambiguous faces: vertices on
    /// grid edges only, about a third of the triangles and vertices of
    /// [`CellMethod::Tetrahedra`] and about 2.5x faster; smooth surfaces
    /// are as accurate, sharp creases are chamfered (the rod lattice's area
    /// is 3.3 % low at 20 cells per period, 0.7 % at 80). The default:
    /// smaller files, faster, and as accurate on smooth microstructures.
    #[default]
    Cubes,
}

impl CellMethod {
    pub(crate) fn table(self) -> &'static tets::CellTable {
        match self {
            CellMethod::Tetrahedra => tets::cell_table(),
            CellMethod::Cubes => cubes::cell_table(),
        }
    }
}

impl MeshOptions {
    /// Options for meshing the box `bounds` (min, max; model units) with
    /// `resolution` cells on its longest side: bricks of 32 cells, marching
    /// cubes, per-brick tape simplification and volume correction on, and the
    /// memory limit of the environment. Nothing is checked here;
    /// [`Plan::new`] rejects bad values.
    pub fn new(bounds: [[f64; 3]; 2], resolution: usize) -> Self {
        MeshOptions {
            bounds,
            resolution,
            brick: 32,
            cells: CellMethod::default(),
            simplify: true,
            memory_limit: None,
            volume_correction: true,
            sharp: false,
        }
    }
}

/// A meshing job after interval classification, before the dense work:
/// enough to predict its memory (see [`memory`]).
pub struct Plan {
    /// The model clipped to the box (output 0), with its other outputs.
    pub tape: Tape,
    /// The grid of cells the model is sampled on (one cell of padding beyond
    /// the box on every side).
    pub grid: Grid,
    /// The box meshed: vertices are kept inside it.
    pub bounds: [[f64; 3]; 2],
    classes: Vec<BrickClass>,
    cells: CellMethod,
    simplify: bool,
    table: &'static tets::CellTable,
    /// See [`MeshOptions::volume_correction`].
    correct: bool,
    /// See [`MeshOptions::sharp`] (false with marching tetrahedra).
    sharp: bool,
    thin_cells: std::sync::atomic::AtomicUsize,
}

impl Plan {
    /// Checks the options, clips the model to the box and classifies every
    /// brick by interval arithmetic (full, empty or surface); the dense
    /// sampling is left to [`Plan::run`].
    ///
    /// # Errors
    /// [`MeshError::Input`] for a brick size outside 2..=256, bounds that are
    /// not finite with min < max, a resolution outside 1..=65533, or cells too
    /// small for f32 coordinates at the box's position;
    /// [`MeshError::TooLarge`] when the brick table alone exceeds
    /// [`MeshOptions::memory_limit`].
    pub fn new(shape: &Shape, opts: &MeshOptions) -> Result<Plan, MeshError> {
        let (tape, grid) = Plan::frame(shape, opts)?;
        Plan::classified(tape, grid, opts)
    }

    /// The first half of [`Plan::new`]: the checked grid and the model
    /// clipped to the box, before any large allocation (so the job layer
    /// can predict the memory first, [`memory::estimate_grid`]).
    pub fn frame(shape: &Shape, opts: &MeshOptions) -> Result<(Tape, Grid), MeshError> {
        if !(2..=256).contains(&opts.brick) {
            return Err(MeshError::Input(format!(
                "brick size {} must be between 2 and 256",
                opts.brick
            )));
        }
        let grid = Grid::new(opts.bounds, opts.resolution, opts.brick)?;
        let clipped = shape.map(|e| clip(e, opts.bounds));
        Ok((clipped.tape().clone(), grid))
    }

    /// The second half of [`Plan::new`]: classifies the bricks of `grid`
    /// by interval arithmetic, after checking that their table fits
    /// `opts.memory_limit`.
    pub fn classified(tape: Tape, grid: Grid, opts: &MeshOptions) -> Result<Plan, MeshError> {
        let bytes = memory::classes_bytes(&grid);
        let avail = opts
            .memory_limit
            .or_else(microfrep_io::limits::memory_limit);
        if let Some(m) = avail.filter(|&m| bytes > m) {
            return Err(MeshError::TooLarge(format!(
                "resolution {}: the table of {} bricks alone needs {:.1} GiB but {:.1} GiB \
                 are available; lower the resolution",
                opts.resolution,
                grid.brick_count(),
                bytes / memory::GIB,
                m / memory::GIB
            )));
        }
        let classes = classify(&tape, &grid);
        Ok(Plan {
            tape,
            grid,
            bounds: opts.bounds,
            classes,
            cells: opts.cells,
            simplify: opts.simplify,
            table: opts.cells.table(),
            correct: opts.volume_correction,
            sharp: opts.sharp && opts.cells == CellMethod::Cubes,
            thin_cells: Default::default(),
        })
    }

    /// Number of bricks that will be sampled densely.
    pub fn surface_bricks(&self) -> usize {
        self.classes
            .iter()
            .filter(|c| **c == BrickClass::Surface)
            .count()
    }

    /// Meshes all surface bricks into memory; `progress` is called with
    /// the number of bricks done after each one.
    pub fn run(&self, progress: &(dyn Fn(usize) + Sync)) -> Result<Mesh, MeshError> {
        let mut c = sink::Collect::default();
        self.run_into(&mut c, progress)?;
        Ok(c.into_mesh())
    }

    /// [`Self::run`], with the edges and bad edges counted while the mesh
    /// is made (as [`check::edges`] counts them; `None` where the census
    /// could not tell).
    pub fn run_counted(
        &self,
        progress: &(dyn Fn(usize) + Sync),
    ) -> Result<(Mesh, Option<(usize, usize)>), MeshError> {
        let mut c = sink::Collect::counting();
        self.run_into(&mut c, progress)?;
        Ok(c.into_counted())
    }

    /// [`Self::run_counted`], with the connected shells counted while the
    /// mesh is made too (as [`check::shells`] counts them; `None` where
    /// that count could not be taken so).
    pub fn run_counted_shells(
        &self,
        progress: &(dyn Fn(usize) + Sync),
    ) -> Result<sink::CountedMesh, MeshError> {
        let mut c = sink::Collect::counting_shells();
        self.run_into(&mut c, progress)?;
        Ok(c.into_counted_shells())
    }

    /// Meshes all surface bricks into `sink`, a few z-slabs of bricks at a
    /// time (so a sink that writes to disk keeps memory bounded); the
    /// output is the same as [`Self::run`]'s.
    pub fn run_into(
        &self,
        sink: &mut (dyn sink::MeshSink + Send),
        progress: &(dyn Fn(usize) + Sync),
    ) -> Result<(), MeshError> {
        pipeline::run(self, sink, progress)
    }

    /// After [`Self::run`]: cells in surface-free bricks where interval
    /// analysis could not exclude a feature thinner than a cell (such
    /// features vanish from the mesh; they never leave a hole).
    pub fn thin_cells(&self) -> usize {
        self.thin_cells.load(std::sync::atomic::Ordering::Relaxed)
    }

    /// Unit outward normals (minus the normalised gradient) at the vertices.
    pub fn normals(&self, mesh: &Mesh) -> Vec<[f32; 3]> {
        self.normals_at(&mesh.vertices)
    }

    /// Unit outward normals (minus the normalised gradient) at `points`.
    pub fn normals_at(&self, points: &[[f32; 3]]) -> Vec<[f32; 3]> {
        let mut out = vec![[0.0f32; 3]; points.len()];
        out.par_chunks_mut(4096)
            .zip(points.par_chunks(4096))
            .for_each_init(
                || GradBatchEval::new(&self.tape),
                |ev, (dst, src)| {
                    let x: Vec<f32> = src.iter().map(|p| p[0]).collect();
                    let y: Vec<f32> = src.iter().map(|p| p[1]).collect();
                    let z: Vec<f32> = src.iter().map(|p| p[2]).collect();
                    let mut g = vec![[0.0f32; 4]; src.len()];
                    ev.eval(&x, &y, &z, &mut g);
                    for (d, g) in dst.iter_mut().zip(&g) {
                        let len = (g[1] * g[1] + g[2] * g[2] + g[3] * g[3]).sqrt();
                        *d = if len > 0.0 && len.is_finite() {
                            [-g[1] / len, -g[2] / len, -g[3] / len]
                        } else {
                            [0.0; 3]
                        };
                    }
                },
            );
        out
    }
}

/// The model intersected (min) with the box, so the mesh is closed where the
/// solid leaves the box.
fn clip(expr: &Expr, bounds: [[f64; 3]; 2]) -> Expr {
    let p = Expr::xyz();
    let mut f = expr.clone();
    for a in 0..3 {
        f = f.min(&p[a] - bounds[0][a]).min(bounds[1][a] - &p[a]);
    }
    f
}
