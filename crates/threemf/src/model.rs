//! The in-memory model: what a 3MF package holds, as plain data. The
//! writer serialises a [`Model`]; the reader gives one back.

use crate::beam::BeamLattice;
use crate::implicit::ImplicitFunction;
use crate::slice::SliceStack;
use crate::volumetric::{FunctionFromImage3D, Image3D, LevelSet, VolumeData};

/// XML namespaces of the core specification and the extensions written and
/// read here.
pub mod ns {
    /// Core specification (1.x).
    pub const CORE: &str = "http://schemas.microsoft.com/3dmanufacturing/core/2015/02";
    /// Materials and properties extension.
    pub const MATERIAL: &str = "http://schemas.microsoft.com/3dmanufacturing/material/2015/02";
    /// Slice extension.
    pub const SLICE: &str = "http://schemas.microsoft.com/3dmanufacturing/slice/2015/07";
    /// Beam lattice extension.
    pub const BEAM: &str = "http://schemas.microsoft.com/3dmanufacturing/beamlattice/2017/02";
    /// Balls within beam lattices (beam lattice extension 1.2).
    pub const BALLS: &str =
        "http://schemas.microsoft.com/3dmanufacturing/beamlattice/balls/2020/07";
    /// Volumetric extension (draft as published by the consortium).
    pub const VOLUMETRIC: &str = "http://schemas.3mf.io/3dmanufacturing/volumetric/2022/01";
    /// Implicit extension (draft as published by the consortium).
    pub const IMPLICIT: &str = "http://schemas.3mf.io/3dmanufacturing/implicit/2023/12";
    /// Production extension: recognised so that its use gives a clear error.
    pub const PRODUCTION: &str = "http://schemas.microsoft.com/3dmanufacturing/production/2015/06";
    /// The namespaces this crate implements (allowed in `requiredextensions`).
    pub const SUPPORTED: [&str; 7] = [CORE, MATERIAL, SLICE, BEAM, BALLS, VOLUMETRIC, IMPLICIT];
}

/// Length unit of a model (the `unit` attribute).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Unit {
    /// 0.001 mm.
    Micron,
    /// The default.
    #[default]
    Millimeter,
    /// 10 mm.
    Centimeter,
    /// 25.4 mm.
    Inch,
    /// 304.8 mm.
    Foot,
    /// 1000 mm.
    Meter,
}

impl Unit {
    /// Every unit.
    pub const ALL: [Unit; 6] = [
        Unit::Micron,
        Unit::Millimeter,
        Unit::Centimeter,
        Unit::Inch,
        Unit::Foot,
        Unit::Meter,
    ];

    /// Millimetres per unit.
    pub fn to_mm(self) -> f64 {
        match self {
            Unit::Micron => 0.001,
            Unit::Millimeter => 1.0,
            Unit::Centimeter => 10.0,
            Unit::Inch => 25.4,
            Unit::Foot => 304.8,
            Unit::Meter => 1000.0,
        }
    }

    /// The attribute value.
    pub fn name(self) -> &'static str {
        match self {
            Unit::Micron => "micron",
            Unit::Millimeter => "millimeter",
            Unit::Centimeter => "centimeter",
            Unit::Inch => "inch",
            Unit::Foot => "foot",
            Unit::Meter => "meter",
        }
    }

    /// Parses an attribute value.
    pub fn from_name(s: &str) -> Option<Unit> {
        Unit::ALL.into_iter().find(|u| u.name() == s)
    }
}

/// An affine transform as 3MF writes it: `m00 m01 m02 m10 m11 m12 m20 m21
/// m22 m30 m31 m32`, applied to row vectors, so a point maps to
/// `x' = x m00 + y m10 + z m20 + m30` (and likewise for y', z').
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform(pub [f64; 12]);

impl Default for Transform {
    fn default() -> Self {
        Transform::IDENTITY
    }
}

impl Transform {
    /// No change.
    pub const IDENTITY: Transform =
        Transform([1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]);

    /// A translation.
    pub fn translation(t: [f64; 3]) -> Transform {
        let mut m = Transform::IDENTITY;
        m.0[9..12].copy_from_slice(&t);
        m
    }

    /// Scaling about the origin.
    pub fn scale(s: [f64; 3]) -> Transform {
        Transform([
            s[0], 0.0, 0.0, 0.0, s[1], 0.0, 0.0, 0.0, s[2], 0.0, 0.0, 0.0,
        ])
    }

    /// Rotation by `angle` radians about the z axis (counter-clockwise seen
    /// from +z).
    pub fn rotation_z(angle: f64) -> Transform {
        let (s, c) = angle.sin_cos();
        Transform([c, s, 0.0, -s, c, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0])
    }

    /// The map of the box `[min, max]` onto the unit cube (as used to sample
    /// a 3D image over a box).
    pub fn box_to_unit(min: [f64; 3], max: [f64; 3]) -> Transform {
        let s: [f64; 3] = std::array::from_fn(|i| 1.0 / (max[i] - min[i]));
        let mut m = Transform::scale(s);
        for i in 0..3 {
            m.0[9 + i] = 0.0 - min[i] * s[i];
        }
        m
    }

    /// Applies the transform to a point.
    pub fn apply(&self, p: [f64; 3]) -> [f64; 3] {
        let m = &self.0;
        std::array::from_fn(|c| p[0] * m[c] + p[1] * m[3 + c] + p[2] * m[6 + c] + m[9 + c])
    }

    /// `self` then `then`: the transform that maps `p` to
    /// `then.apply(self.apply(p))`.
    pub fn then(&self, then: &Transform) -> Transform {
        let (a, b) = (&self.0, &then.0);
        let mut m = [0.0; 12];
        for r in 0..4 {
            for c in 0..3 {
                let mut v = if r == 3 { b[9 + c] } else { 0.0 };
                for k in 0..3 {
                    v += a[3 * r + k] * b[3 * k + c];
                }
                m[3 * r + c] = v;
            }
        }
        Transform(m)
    }

    /// Determinant of the linear part (negative for mirroring transforms).
    pub fn determinant(&self) -> f64 {
        let m = &self.0;
        m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6])
            + m[2] * (m[3] * m[7] - m[4] * m[6])
    }

    /// Whether this is the identity bit for bit.
    pub fn is_identity(&self) -> bool {
        *self == Transform::IDENTITY
    }
}

/// A `<metadata>` entry.
#[derive(Clone, Debug, PartialEq)]
pub struct Metadata {
    /// Name (`Title`, `Designer`, `Application`, ... or a prefixed vendor name).
    pub name: String,
    /// Text value.
    pub value: String,
}

/// Object type (`type` attribute).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ObjectType {
    /// A part to build (the default).
    #[default]
    Model,
    /// Support that is built solid.
    SolidSupport,
    /// Support.
    Support,
    /// A surface (open mesh).
    Surface,
    /// Anything else (not built: clipping or representation meshes, ...).
    Other,
}

impl ObjectType {
    /// The attribute value.
    pub fn name(self) -> &'static str {
        match self {
            ObjectType::Model => "model",
            ObjectType::SolidSupport => "solidsupport",
            ObjectType::Support => "support",
            ObjectType::Surface => "surface",
            ObjectType::Other => "other",
        }
    }

    /// Parses an attribute value.
    pub fn from_name(s: &str) -> Option<ObjectType> {
        [
            ObjectType::Model,
            ObjectType::SolidSupport,
            ObjectType::Support,
            ObjectType::Surface,
            ObjectType::Other,
        ]
        .into_iter()
        .find(|t| t.name() == s)
    }
}

/// Per-triangle properties (materials extension): a property group and an
/// index into it at each corner.
#[derive(Clone, Debug, PartialEq)]
pub struct TriangleProperties {
    /// Resource id of the property group (base or composite materials, or
    /// a colour group).
    pub pid: u32,
    /// Property index at the three corners of each triangle.
    pub indices: Vec<[u32; 3]>,
}

/// A triangle mesh object's geometry, in model units.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub vertices: Vec<[f64; 3]>,
    /// Triangles as vertex indices, counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
    /// Optional per-triangle properties (same length as `triangles`).
    pub properties: Option<TriangleProperties>,
    /// A beam lattice on this mesh's vertices.
    pub beam_lattice: Option<BeamLattice>,
    /// Volumetric data (`v:volumeid`) of this mesh.
    pub volume_id: Option<u32>,
}

impl Mesh {
    /// The closed box `[min, max]`: 8 vertices (vertex `i` takes `max` on
    /// axis `a` where bit `a` of `i` is set, else `min`) and 12 triangles
    /// facing outwards. For clipping meshes, bounding boxes of level sets
    /// and tests.
    pub fn cuboid(min: [f64; 3], max: [f64; 3]) -> Mesh {
        let vertices = (0..8)
            .map(|i| std::array::from_fn(|a| if i >> a & 1 == 1 { max[a] } else { min[a] }))
            .collect();
        let triangles = vec![
            [0, 2, 1],
            [1, 2, 3],
            [4, 5, 6],
            [5, 7, 6],
            [0, 1, 4],
            [1, 5, 4],
            [2, 6, 3],
            [3, 6, 7],
            [0, 4, 2],
            [2, 4, 6],
            [1, 3, 5],
            [3, 7, 5],
        ];
        Mesh {
            vertices,
            triangles,
            ..Mesh::default()
        }
    }
}

/// A component of a components object.
#[derive(Clone, Debug, PartialEq)]
pub struct Component {
    /// Referenced object.
    pub object: u32,
    /// Its placement.
    pub transform: Transform,
}

/// What an object is made of.
#[derive(Clone, Debug, PartialEq)]
pub enum ObjectContent {
    /// A mesh (possibly with a beam lattice or volume data).
    Mesh(Mesh),
    /// Other objects placed by transforms.
    Components(Vec<Component>),
    /// A level set of a function (volumetric extension).
    LevelSet(LevelSet),
}

/// Mesh resolution hint of the slice extension.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum MeshResolution {
    /// The mesh is exact (default).
    #[default]
    Full,
    /// The mesh is a coarse stand-in for the slices.
    Low,
}

/// An `<object>` resource.
#[derive(Clone, Debug, PartialEq)]
pub struct Object {
    /// Resource id (unique among all resources of its part).
    pub id: u32,
    /// Name.
    pub name: Option<String>,
    /// Part number.
    pub part_number: Option<String>,
    /// Type.
    pub kind: ObjectType,
    /// Object-level property (`pid`, `pindex`).
    pub property: Option<(u32, u32)>,
    /// Geometry.
    pub content: ObjectContent,
    /// Slice stack of this object (`s:slicestackid`).
    pub slice_stack: Option<u32>,
    /// `s:meshresolution`.
    pub mesh_resolution: MeshResolution,
}

impl Object {
    /// A mesh object of type model.
    pub fn mesh(id: u32, name: Option<&str>, mesh: Mesh) -> Object {
        Object {
            id,
            name: name.map(str::to_string),
            part_number: None,
            kind: ObjectType::Model,
            property: None,
            content: ObjectContent::Mesh(mesh),
            slice_stack: None,
            mesh_resolution: MeshResolution::Full,
        }
    }
}

/// One base material.
#[derive(Clone, Debug, PartialEq)]
pub struct Base {
    /// Name (design intent, not a machine setting).
    pub name: String,
    /// Display colour, sRGB with alpha.
    pub color: [u8; 4],
}

/// A `<basematerials>` resource.
#[derive(Clone, Debug, PartialEq)]
pub struct BaseMaterials {
    /// Resource id.
    pub id: u32,
    /// The materials, indexed from 0.
    pub bases: Vec<Base>,
}

/// A `<m:compositematerials>` resource (materials extension): mixtures of
/// base materials assignable to triangle corners.
#[derive(Clone, Debug, PartialEq)]
pub struct CompositeMaterials {
    /// Resource id.
    pub id: u32,
    /// The base materials resource mixed.
    pub base_materials: u32,
    /// Which of its materials are mixed, in the order of the values.
    pub material_indices: Vec<u32>,
    /// Mixing ratios, one value per material index, per composite.
    pub composites: Vec<Vec<f64>>,
}

/// A `<m:colorgroup>` resource (materials extension): sRGB colours with
/// alpha, assignable to triangle corners (the mesh writer stores one per
/// vertex).
#[derive(Clone, Debug, PartialEq)]
pub struct ColorGroup {
    /// Resource id.
    pub id: u32,
    /// The colours, indexed from 0.
    pub colors: Vec<[u8; 4]>,
}

/// A build item.
#[derive(Clone, Debug, PartialEq)]
pub struct BuildItem {
    /// Object to build.
    pub object: u32,
    /// Placement on the build platform.
    pub transform: Transform,
    /// Part number.
    pub part_number: Option<String>,
}

/// Everything in a package's model (the root part and the parts it pulls
/// slices from).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Model {
    /// Length unit.
    pub unit: Unit,
    /// `xml:lang`.
    pub language: Option<String>,
    /// Model metadata.
    pub metadata: Vec<Metadata>,
    /// Base materials.
    pub base_materials: Vec<BaseMaterials>,
    /// Composite materials.
    pub composite_materials: Vec<CompositeMaterials>,
    /// Colour groups.
    pub color_groups: Vec<ColorGroup>,
    /// 3D images (volumetric).
    pub images: Vec<Image3D>,
    /// Functions sampling 3D images.
    pub image_functions: Vec<FunctionFromImage3D>,
    /// Implicit functions.
    pub implicit_functions: Vec<ImplicitFunction>,
    /// Volume data resources.
    pub volume_data: Vec<VolumeData>,
    /// Slice stacks.
    pub slice_stacks: Vec<SliceStack>,
    /// Objects, in file order (referenced objects first).
    pub objects: Vec<Object>,
    /// Build items.
    pub build: Vec<BuildItem>,
}

impl Model {
    /// An empty model in `unit`.
    pub fn new(unit: Unit) -> Model {
        Model {
            unit,
            ..Model::default()
        }
    }

    /// The smallest id not used by any resource yet.
    pub fn next_id(&self) -> u32 {
        self.resource_ids().max().unwrap_or(0) + 1
    }

    /// All resource ids, in no particular order.
    pub fn resource_ids(&self) -> impl Iterator<Item = u32> + '_ {
        self.base_materials
            .iter()
            .map(|r| r.id)
            .chain(self.composite_materials.iter().map(|r| r.id))
            .chain(self.color_groups.iter().map(|r| r.id))
            .chain(self.images.iter().map(|r| r.id))
            .chain(self.image_functions.iter().map(|r| r.id))
            .chain(self.implicit_functions.iter().map(|r| r.id))
            .chain(self.volume_data.iter().map(|r| r.id))
            .chain(self.slice_stacks.iter().map(|r| r.id))
            .chain(self.objects.iter().map(|r| r.id))
    }

    /// Adds a mesh object (type model) and returns its id.
    pub fn add_mesh(&mut self, name: Option<&str>, mesh: Mesh) -> u32 {
        let id = self.next_id();
        self.objects.push(Object::mesh(id, name, mesh));
        id
    }

    /// Adds a components object and returns its id.
    pub fn add_components(&mut self, name: Option<&str>, components: Vec<Component>) -> u32 {
        let id = self.next_id();
        let mut o = Object::mesh(id, name, Mesh::default());
        o.content = ObjectContent::Components(components);
        self.objects.push(o);
        id
    }

    /// Adds a build item.
    pub fn add_item(&mut self, object: u32, transform: Transform) {
        self.build.push(BuildItem {
            object,
            transform,
            part_number: None,
        });
    }

    /// The object with this id.
    pub fn object(&self, id: u32) -> Option<&Object> {
        self.objects.iter().find(|o| o.id == id)
    }
}
