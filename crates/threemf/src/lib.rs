//! 3MF packages for microfrep: the core format (meshes, components, build
//! items, units, metadata) and the extensions that keep lattice and graded
//! parts small — beam lattices (1.2, with balls, clipping and representation
//! meshes), slice stacks (1.0.2, split over parts), and the volumetric and
//! implicit drafts (image stacks of PNG sheets, volume data with material
//! mixing, colour and properties, level sets, implicit node graphs).
//!
//! The crate takes and gives plain data ([`Model`] and its parts: vertices
//! and triangles, beam lists, polygons per layer, voxel samples, node
//! graphs); it does not depend on the mesher. [`write_file`] validates and
//! writes a package deterministically; [`read_file`] reads one back, and
//! [`read_meshes`] flattens build items and components into world-space
//! triangle meshes in millimetres (for `.3mf` input parts). Errors name the
//! part and the byte offset; files that require an unsupported extension are
//! refused.
//!
//! ```
//! use microfrep_3mf::{Mesh, Model, Transform, Unit, WriteOptions};
//! let mut model = Model::new(Unit::Millimeter);
//! let tet = Mesh {
//!     vertices: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
//!     triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
//!     ..Mesh::default()
//! };
//! let id = model.add_mesh(Some("tet"), tet);
//! model.add_item(id, Transform::translation([10.0, 0.0, 0.0]));
//! let bytes = microfrep_3mf::write_to(std::io::Cursor::new(Vec::new()), &model, &WriteOptions::default())
//!     .unwrap()
//!     .into_inner();
//! let back = microfrep_3mf::read_from(std::io::Cursor::new(bytes)).unwrap();
//! let meshes = microfrep_3mf::meshes(&back).unwrap();
//! assert_eq!(meshes[0].vertices[1], [11.0, 0.0, 0.0]);
//! ```
#![warn(missing_docs)]

pub mod beam;
pub mod error;
pub mod flatten;
pub mod from_core;
pub mod implicit;
pub mod model;
pub mod read;
pub mod slice;
pub mod volumetric;
pub mod write;

pub use beam::{Ball, BallMode, Beam, BeamLattice, BeamSet, Cap, ClipMode};
pub use error::{Error, Result};
pub use flatten::{
    expansion, lattices, lattices_with, meshes, meshes_with, read_beam_lattices, read_meshes,
    read_meshes_with, Expansion, NamedLattice, NamedMesh,
};
pub use implicit::{ImplicitFunction, ImplicitGraph, ImplicitNode};
pub use model::{
    Base, BaseMaterials, BuildItem, ColorGroup, Component, CompositeMaterials, Mesh,
    MeshResolution, Metadata, Model, Object, ObjectContent, ObjectType, Transform,
    TriangleProperties, Unit,
};
pub use read::{read_file, read_file_with, read_from, read_from_with, ReadOptions};
pub use slice::{Polygon, Slice, SliceStack};
pub use write::{validate, write_file, write_to, WriteOptions};
