//! Triangle meshes (STL, OBJ, PLY) as signed distance fields of the
//! microfrep core: exact distance, a sign that stays right on imperfect
//! meshes, sound interval bounds, and a batch path for the hot loops.
//!
//! A part's mesh (a CAD export, a bone segmentation) becomes a
//! [`microfrep_core::Field`] whose value is `+distance` inside and
//! `-distance` outside, in the mesh's units (millimetres), so it composes
//! with lattices, offsets and blends like any other node
//! (`Expr::field(Arc::new(field))`).
//!
//! ```
//! use microfrep_core::Field;
//! use microfrep_meshfield::{MeshField, SignMethod, TriMesh};
//! // A unit right tetrahedron, outward-facing.
//! let mesh = TriMesh::new(
//!     vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
//!     vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
//! )
//! .unwrap();
//! assert!(mesh.topology().is_watertight());
//! assert!((mesh.volume() - 1.0 / 6.0).abs() < 1e-15);
//! let field = MeshField::new(&mesh).unwrap();
//! assert_eq!(field.sign_method(), SignMethod::PseudoNormal);
//! assert!((field.eval([0.1, 0.1, 0.1]) - 0.1).abs() < 1e-12); // inside, 0.1 from three faces
//! assert!((field.eval([-1.0, 0.2, 0.2]) + 1.0).abs() < 1e-12); // outside, 1 from the face x = 0
//! // Read files with `read::read_mesh("part.stl")`, then weld: `mesh.weld(0.0).0`.
//! ```
//!
//! # Pipeline and guarantees
//!
//! * **Reading** ([`read`]): STL (binary and ASCII, told apart by the
//!   header's triangle count against the file size, not by the word
//!   "solid"), OBJ, PLY (ASCII and binary, both byte orders). Errors carry
//!   the file and the line or byte offset, and name the triangle or vertex.
//!   `.3mf` is dispatched to an error until the 3MF crate is wired in.
//! * **Welding** ([`TriMesh::weld`]) is an explicit step, exact or within a
//!   tolerance, deterministic.
//! * **Topology** ([`TriMesh::topology`]): open, non-manifold and
//!   inconsistently oriented edges, non-manifold vertices, degenerate
//!   triangles, so a caller can warn ("mesh is not closed: 12 open edges")
//!   and carry on. **Orientation repair** ([`TriMesh::orient`], on by
//!   default in [`BuildOptions::orient`]) makes every patch of triangles
//!   connected through manifold edges consistent, keeping the orientation
//!   of the larger part of its area.
//! * **BVH** ([`bvh`]): binned SAH (16 bins, 3 axes) built in parallel with
//!   rayon, leaves of at most 4 triangles, 32-byte nodes with f32 boxes
//!   rounded outward (so they contain the f64 triangles), triangles stored
//!   with f64 corners in leaf order.
//! * **Distance** is exact in f64: a best-first descent pruned by box
//!   distance, then the closest point on each leaf triangle by its Voronoi
//!   regions, which also gives the feature (face, edge, vertex). Degenerate
//!   triangles are treated as their edges. The result is the distance to the
//!   polyhedron up to f64 rounding (tested against brute force to 1e-9 of
//!   the bbox diagonal).
//! * **Sign.** Where the mesh is *watertight* (closed, consistently
//!   oriented, manifold at every vertex, no degenerate triangle), the sign
//!   is the side of the closest feature's angle-weighted pseudo-normal
//!   (Baerentzen and Aanaes), which is exact for such a mesh without
//!   self-intersections; these are looked for first (pairs of triangles in
//!   overlapping BVH boxes that cross, by orientation tests), and a
//!   crossing mesh falls back to the winding number. Otherwise
//!   the sign is the **generalized winding number** `w > 1/2` (Jacobson et
//!   al. 2013) computed hierarchically after Barill et al. 2018: each BVH
//!   node stores the moments of its triangles' normal field up to second
//!   order (vector area `N`, first moment `M`, second moment `T`, the
//!   triangles' own second moments exact), about its area-weighted centroid;
//!   a node farther than `beta x radius` from the query contributes the
//!   truncated Taylor expansion of the solid-angle integral, nearer leaves
//!   the exact solid angle of each triangle (Van Oosterom and Strackee).
//!   This is an approximation: the relative error of a node's term decays
//!   like `(1/beta)^3`, and with `beta = 2` the total error stays far below
//!   the 1/2 that would flip a sign away from holes (the tests check the
//!   sign at every point farther than 1e-3 of the diagonal from the
//!   surface). Holes, unwelded soups, non-manifold edges and overlapping
//!   shells give the inside that the winding number defines; near a hole the
//!   sign follows the hole's minimal "membrane" (w = 1/2).
//! * **Gradient**: `s (p - c) / |p - c|` with `c` the closest point and `s`
//!   the sign; on the surface the inward face normal. A unit vector, so
//!   [`microfrep_core::Field::grad_interval`] is `[-1, 1]` per component.
//! * **Intervals** ([`microfrep_core::Field::interval`]): with `d` the distance at the box
//!   centre and `h` the half diagonal, `|f|` lies in `[d - h, d + h]`
//!   (distance is 1-Lipschitz). The sign is claimed only when the box keeps
//!   clear of the surface (`d - h > 0`, with a margin of 1e-9 diagonal):
//!   watertight meshes then have one sign over the box (the centre's); for
//!   the winding number the very approximation that the point evaluation
//!   uses is enclosed over the box (same far/near decisions; each far
//!   expansion at the centre plus `h` times a bound of its gradient from the
//!   moment norms; each near triangle's solid angle at the centre plus
//!   `2 area h / d^3`, the bound of its gradient), and the sign is claimed only if
//!   that enclosure is clear of 1/2. Otherwise the answer is `[-(d + h),
//!   d + h]`. Sound for every point of the box, checked by
//!   [`microfrep_core::field_check::check_field`].
//! * **Batch** ([`microfrep_core::Field::eval_batch`]): one call per block from one thread;
//!   each point's search is seeded with the previous point's triangle (its
//!   distance bounds the search from the start), in f64, so the batch equals
//!   the point evaluation; only `&self` is used, so blocks run in parallel
//!   without contention.
//! * **Memory** is predicted before building ([`MeshField::predict_memory`])
//!   and a build that would exceed [`BuildOptions::memory_limit`] is an
//!   error, not an abort. Long builds report progress.

#![warn(missing_docs)]
// Loops over the three axes index several arrays at once, like the formulas.
#![allow(clippy::needless_range_loop)]

pub mod bvh;
mod field;
pub mod geom;
mod intersect;
mod mesh;
pub mod read;
pub mod winding;

pub use field::{BuildOptions, Closest, MeshField, SignMethod};
pub use geom::Feature;
pub use mesh::{Topology, TriMesh, DEGENERATE_RATIO, MAX_COORDINATE};

/// Errors of mesh validation and field building.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// No triangles.
    #[error("the mesh has no triangles")]
    Empty,
    /// More vertices than 32-bit indices allow.
    #[error("the mesh has {0} vertices, more than 32-bit indices allow")]
    TooManyVertices(usize),
    /// A coordinate is NaN or infinite.
    #[error("vertex {vertex} is not finite: {value:?}")]
    NonFinite {
        /// Vertex index.
        vertex: usize,
        /// Its position.
        value: [f64; 3],
    },
    /// A coordinate is too large for distances to be computed.
    #[error(
        "vertex {vertex} at {value:?} is farther than {limit:e} from the origin; scale the mesh"
    )]
    HugeCoordinate {
        /// Vertex index.
        vertex: usize,
        /// Its position.
        value: [f64; 3],
        /// The largest coordinate accepted.
        limit: f64,
    },
    /// A triangle refers to a vertex that does not exist.
    #[error("triangle {triangle} has indices {indices:?}, but there are {vertices} vertices")]
    BadIndex {
        /// Triangle index.
        triangle: usize,
        /// Its indices.
        indices: [u32; 3],
        /// Number of vertices.
        vertices: usize,
    },
    /// The build would need more memory than allowed.
    #[error(
        "a field of {triangles} triangles needs about {} MiB, more than the limit of {} MiB",
        need >> 20,
        limit >> 20
    )]
    TooLarge {
        /// Triangles.
        triangles: u64,
        /// Bytes needed.
        need: u64,
        /// The limit.
        limit: u64,
    },
    /// The pseudo-normal sign was requested for a mesh that is not watertight.
    #[error("the pseudo-normal sign needs a watertight mesh: {0}")]
    NotWatertight(String),
    /// An option is out of range.
    #[error("{0}")]
    BadOption(String),
}

/// Memory limits.
pub mod memory {
    /// Default limit: the readers' shared budget, 80 % of what the process
    /// may allocate (available memory, cgroup, `ulimit -v`), else 4 GiB
    /// ([`microfrep_io::limits::default_memory_budget`]).
    pub fn default_limit() -> u64 {
        microfrep_io::limits::default_memory_budget()
    }
}
