//! Compact printer files (3MF extensions) from models: slice stacks (the
//! slice extension) and beam lattices (the beam lattice extension), each
//! with a mesh of the part so viewers without the extension still show it,
//! and the volumetric and implicit extensions added to a meshed part
//! ([`add_volumetric`], [`add_volumetric_to_file`]): the model's own
//! function as a level set, its attribute channels as volume data.

use crate::threemf::{
    write_file, BeamLattice, ClipMode, Mesh as Mesh3, MeshResolution, Model, SliceStack, Transform,
    Unit, WriteOptions,
};
use microfrep_core::{Bounds, Shape};
use microfrep_fab::{layer_polygons, rasterize, SliceGrid};
use microfrep_mesh::{MeshError, MeshOptions, Plan};
use rayon::prelude::*;
use std::path::Path;

/// Why an export failed.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// Meshing the part's representation failed.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// Writing the package failed.
    #[error(transparent)]
    ThreeMf(#[from] microfrep_3mf::Error),
    /// The strut lattice could not be built.
    #[error(transparent)]
    Struts(#[from] microfrep_structures::Error),
    /// A volumetric or implicit export that cannot be made as asked (no
    /// attribute channels, a palette longer than the channels, a zero
    /// resolution, a package without one mesh to attach to).
    #[error("{0}")]
    Volumetric(String),
    /// The image stacks would not fit in memory.
    #[error(
        "image stacks of {dims:?} voxels ({images} channel(s)) need about {need:.3e} bytes, \
         {avail:.3e} are available: {fit}"
    )]
    VolumeMemory {
        /// Voxels per axis.
        dims: [usize; 3],
        /// Scalar channels sampled.
        images: usize,
        /// Predicted bytes.
        need: f64,
        /// Bytes available.
        avail: f64,
        /// The largest resolution that would fit, in words.
        fit: String,
    },
}

fn mesh3(shape: &Shape, b: Bounds, resolution: usize) -> Result<Mesh3, MeshError> {
    let m = Plan::new(shape, &MeshOptions::new(b.corners(), resolution))?.run(&|_| {})?;
    Ok(Mesh3 {
        vertices: m.vertices.iter().map(|v| v.map(f64::from)).collect(),
        triangles: m.triangles,
        ..Default::default()
    })
}

/// The model sliced on `grid` as a 3MF slice stack (closed polygons per
/// layer, outer loops counter-clockwise, every layer present) with a mesh
/// of `preview` cells on the longest side as the object's low-resolution
/// geometry. Returns the number of layers.
pub fn slice_3mf(
    shape: &Shape,
    grid: &SliceGrid,
    preview: usize,
    out: &Path,
    progress: &(dyn Fn() + Sync),
) -> Result<usize, ExportError> {
    let layers: Vec<Vec<Vec<[f64; 2]>>> = (0..grid.layers)
        .into_par_iter()
        .map(|k| {
            let p = layer_polygons(shape, grid, &rasterize(shape, grid, k));
            progress();
            p
        })
        .collect();
    let n = layers.len();
    // The bottom of the first layer written (a range of a stack starts
    // above the stack's bottom).
    let z0 = grid.min[2] + grid.first as f64 * grid.layer;
    let max = [
        grid.min[0] + grid.nx as f64 * grid.pixel,
        grid.min[1] + grid.ny as f64 * grid.pixel,
        z0 + grid.layers as f64 * grid.layer,
    ];
    let min = [grid.min[0], grid.min[1], z0];
    let mut m = Model::new(Unit::Millimeter);
    let low = m.add_mesh(Some("part"), mesh3(shape, Bounds::new(min, max), preview)?);
    let sid = m.next_id();
    m.slice_stacks
        .push(SliceStack::uniform(sid, z0, grid.layer, layers));
    if let Some(o) = m.objects.iter_mut().find(|o| o.id == low) {
        o.slice_stack = Some(sid);
        o.mesh_resolution = MeshResolution::Low;
    }
    m.add_item(low, Transform::IDENTITY);
    write_file(out, &m, &WriteOptions::default())?;
    Ok(n)
}

/// A strut lattice of `kind` (1..6: sc, bcc, fcc, octet, kelvin, diamond)
/// with cells `cell` and strut radius `radius` (model units), clipped to
/// `part`, as a 3MF beam lattice; the part meshed at `resolution` is the
/// lattice's clipping mesh (see [`beam_lattice_fill_3mf`]). Returns
/// (beams, nodes).
pub fn beam_lattice_3mf(
    part: &Shape,
    kind: u8,
    cell: f64,
    radius: f64,
    bounds: Bounds,
    resolution: usize,
    out: &Path,
) -> Result<(usize, usize), ExportError> {
    use microfrep_structures::struts::StrutLattice;
    let k = StrutLattice::ALL[(kind.clamp(1, 6) - 1) as usize];
    beam_lattice_fill_3mf(part, None, k, cell, radius, bounds, resolution, out)
}

/// A filled part's struts as a 3MF beam lattice, with its skin: the
/// lattice (of `kind`, cells `cell`, radius `radius`) is clipped to the
/// `core` (meshed at `resolution`, an object the build does not print),
/// and the `skin`, when there is one, is a mesh object of its own; both are
/// items of one build. The lattice has no representation mesh (viewers
/// that cannot draw beams show the skin alone). Returns (beams, nodes).
#[allow(clippy::too_many_arguments)]
pub fn beam_lattice_fill_3mf(
    core: &Shape,
    skin: Option<&Shape>,
    kind: microfrep_structures::struts::StrutLattice,
    cell: f64,
    radius: f64,
    bounds: Bounds,
    resolution: usize,
    out: &Path,
) -> Result<(usize, usize), ExportError> {
    use microfrep_structures::strut_graph::StrutGraph;
    let g = StrutGraph::tile(kind, bounds.min, bounds.max, cell, |_| radius)?.clip(core.value());
    if g.beams.is_empty() {
        return Err(ExportError::Volumetric(
            "no strut of the lattice lies inside the part's core: nothing to write".into(),
        ));
    }
    let mut m = Model::new(Unit::Millimeter);
    let clip = m.add_mesh(Some("core"), mesh3(core, bounds, resolution)?);
    let mut l = BeamLattice::new(radius, 1e-4);
    for (&(a, b), r) in g.beams.iter().zip(&g.radii) {
        l.push(a, b, r[0], r[1]);
    }
    l.clipping = Some((ClipMode::Inside, clip));
    let skin_id = match skin {
        Some(s) => Some(m.add_mesh(Some("skin"), mesh3(s, bounds, resolution)?)),
        None => None,
    };
    let id = m.add_mesh(
        Some("lattice"),
        Mesh3 {
            vertices: g.nodes.clone(),
            beam_lattice: Some(l),
            ..Mesh3::default()
        },
    );
    if let Some(s) = skin_id {
        m.add_item(s, Transform::IDENTITY);
    }
    m.add_item(id, Transform::IDENTITY);
    write_file(out, &m, &WriteOptions::default())?;
    Ok((g.beams.len(), g.nodes.len()))
}

/// A HyperFun strut lattice model (an `mfStruts` or `mfStrutsDensity`
/// call at the plain point with constant cell and radius, alone or
/// intersected with a part): see [`strut_model_of`].
pub use microfrep_structures_hf::StrutModel;

/// The strut lattice `shape` is, when it is one (see
/// [`microfrep_structures_hf::strut_model`]; the model must have been
/// lowered in this process, as [`crate::load()`] does).
pub fn strut_model_of(shape: &Shape) -> Option<StrutModel> {
    microfrep_structures_hf::strut_model(shape.value())
}

/// A strut lattice model as a 3MF beam lattice ([`beam_lattice_3mf`]):
/// the part it is intersected with (or the box `bounds`, when it has none)
/// meshed at `resolution` clips it. Returns (beams, nodes).
pub fn strut_model_3mf(
    s: &StrutModel,
    bounds: Bounds,
    resolution: usize,
    out: &Path,
) -> Result<(usize, usize), ExportError> {
    use microfrep_structures::struts::StrutLattice;
    let part = match &s.part {
        Some(e) => Shape::new(e.clone()),
        None => {
            let [x, y, z] = microfrep_core::Expr::xyz();
            let (lo, hi) = (bounds.min, bounds.max);
            let slab = |v: &microfrep_core::Expr, a: usize| (v - lo[a]).min(&(hi[a] - v));
            Shape::new(slab(&x, 0).min(slab(&y, 1)).min(slab(&z, 2)))
        }
    };
    let kind = StrutLattice::ALL
        .iter()
        .position(|k| *k == s.kind)
        .map_or(1, |i| i as u8 + 1);
    beam_lattice_3mf(&part, kind, s.cell, s.radius, bounds, resolution, out)
}

// Volumetric and implicit extensions ------------------------------------

/// Voxels of the image stacks along the longest side unless asked
/// otherwise.
pub const DEFAULT_VOLUME_RESOLUTION: usize = 64;

/// Most voxels along one side of an image stack.
pub const MAX_VOLUME_RESOLUTION: usize = 4096;

/// What [`add_volumetric`] adds to a meshed part.
#[derive(Clone, Debug)]
pub struct VolumeOptions {
    /// Add the model's own function as a `<v:levelset>` object (the built
    /// item then): an implicit node graph when every operation of the model
    /// has one ([`microfrep_3mf::from_core::levelset_function`]), else an
    /// image stack of the field sampled on the grid.
    pub implicit: bool,
    /// Add every attribute channel as a property of a `<v:volumedata>`
    /// attached to the part (an image stack each).
    pub attributes: bool,
    /// Materials mixed by the attribute channels: material `k` takes the
    /// share `s[k+1]`, the last one the remainder (the reading of
    /// `microfrep materials`), written as base materials and a composite of
    /// the volume data, with the mixed display colour.
    pub palette: Option<microfrep_graded::stack::Palette>,
    /// Voxels of the image stacks along the longest side of the box
    /// (cubic voxels).
    pub resolution: usize,
    /// Bytes the sampling may use; default:
    /// [`microfrep_io::limits::memory_limit`].
    pub memory_limit: Option<f64>,
}

impl Default for VolumeOptions {
    fn default() -> Self {
        VolumeOptions {
            implicit: false,
            attributes: false,
            palette: None,
            resolution: DEFAULT_VOLUME_RESOLUTION,
            memory_limit: None,
        }
    }
}

/// The voxel grid of the image stacks: cubic voxels of side `pitch`,
/// `dims` of them, centred on the box; voxel `(ix, iy, iz)` has its centre
/// at `min + (i + 1/2) pitch`, which is UVW `((ix + 1/2) / nx, ...)` under
/// [`VolumeGrid::to_unit`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VolumeGrid {
    /// Lower corner of the voxels.
    pub min: [f64; 3],
    /// Voxel side.
    pub pitch: f64,
    /// Voxels per axis.
    pub dims: [usize; 3],
}

impl VolumeGrid {
    /// `n` voxels along the longest side of `b`, as many of the same size
    /// as cover the other sides.
    pub fn new(b: Bounds, n: usize) -> Result<VolumeGrid, ExportError> {
        if n == 0 || n > MAX_VOLUME_RESOLUTION {
            return Err(ExportError::Volumetric(format!(
                "volume resolution {n}: give 1 to {MAX_VOLUME_RESOLUTION} voxels"
            )));
        }
        let size = b.size();
        let longest = size.iter().cloned().fold(0.0, f64::max);
        if !(longest > 0.0 && longest.is_finite() && b.min.iter().all(|v| v.is_finite())) {
            return Err(ExportError::Volumetric(format!(
                "the box {:?}..{:?} has no finite extent to sample",
                b.min, b.max
            )));
        }
        let pitch = longest / n as f64;
        let dims: [usize; 3] =
            std::array::from_fn(|a| ((size[a] / pitch - 1e-9).ceil().max(1.0) as usize).min(n));
        let min = std::array::from_fn(|a| b.min[a] - (dims[a] as f64 * pitch - size[a]) / 2.0);
        Ok(VolumeGrid { min, pitch, dims })
    }

    /// Upper corner of the voxels.
    pub fn max(&self) -> [f64; 3] {
        std::array::from_fn(|a| self.min[a] + self.dims[a] as f64 * self.pitch)
    }

    /// Centre of a voxel.
    pub fn centre(&self, ix: usize, iy: usize, iz: usize) -> [f64; 3] {
        let i = [ix, iy, iz];
        std::array::from_fn(|a| self.min[a] + (i[a] as f64 + 0.5) * self.pitch)
    }

    /// Number of voxels.
    pub fn voxels(&self) -> u64 {
        self.dims.iter().map(|&d| d as u64).product()
    }

    /// Model coordinates to the image's UVW.
    pub fn to_unit(&self) -> Transform {
        Transform::box_to_unit(self.min, self.max())
    }
}

/// Where a level set's function came from.
#[derive(Clone, Debug, PartialEq)]
pub enum LevelSetSource {
    /// The model's graph as an implicit node graph of this many nodes.
    Graph {
        /// Implicit nodes.
        nodes: usize,
    },
    /// An image stack of the field sampled on the grid, because these
    /// nodes of the model have no implicit node (data fields: meshes,
    /// scans, tables).
    ImageStack {
        /// What each node is (`field 'name'`).
        fields: Vec<String>,
    },
}

/// What [`add_volumetric`] added.
#[derive(Clone, Debug, PartialEq)]
pub struct VolumeReport {
    /// The grid of the image stacks (none were written when
    /// [`VolumeReport::images`] is 0).
    pub grid: VolumeGrid,
    /// The level set's function, when asked for.
    pub level_set: Option<LevelSetSource>,
    /// Resource id of the level set object.
    pub level_set_object: Option<u32>,
    /// Resource id of the volume data attached to the part.
    pub volume_data: Option<u32>,
    /// Attribute channels written as properties.
    pub attributes: usize,
    /// Materials of the composite.
    pub materials: usize,
    /// Image stacks written.
    pub images: usize,
}

impl VolumeReport {
    /// The note for the user when the level set fell back to an image
    /// stack.
    pub fn note(&self) -> Option<String> {
        match &self.level_set {
            Some(LevelSetSource::ImageStack { fields }) => Some(format!(
                "the level set is an image stack of the field ({} x {} x {} voxels of {}): \
                 the model's {} no implicit node",
                self.grid.dims[0],
                self.grid.dims[1],
                self.grid.dims[2],
                microfrep_io::text::sig(self.grid.pitch, 4),
                list_fields(fields),
            )),
            _ => None,
        }
    }
}

fn list_fields(fields: &[String]) -> String {
    let mut u: Vec<&str> = fields.iter().map(String::as_str).collect();
    u.dedup();
    if u.len() == 1 {
        format!("{} has", u[0])
    } else {
        format!("{} have", u.join(", "))
    }
}

/// What is sampled, decided before any work.
struct VolumePlan {
    grid: VolumeGrid,
    /// Field nodes that force the level set to an image stack.
    fallback: Option<Vec<String>>,
    /// Attribute channels written as properties.
    attributes: usize,
    /// Attribute channels read (properties and mixing).
    read: usize,
    /// Materials of the palette.
    materials: usize,
}

impl VolumePlan {
    /// Scalar images (one channel each) plus the colour image's channels.
    fn channels(&self) -> usize {
        usize::from(self.fallback.is_some())
            + self.attributes
            + self.materials
            + if self.materials > 0 { 3 } else { 0 }
    }
    fn outputs(&self) -> usize {
        usize::from(self.fallback.is_some()) + self.read
    }
    /// Peak bytes: f32 samples of every output read plus the u16 image
    /// samples, and the encoded sheets (bounded by the raw size).
    fn bytes(&self, voxels: f64) -> f64 {
        voxels * (4.0 * self.outputs() as f64 + 4.0 * self.channels() as f64)
    }
}

impl VolumeOptions {
    fn plan(&self, shape: &Shape, b: Bounds) -> Result<VolumePlan, ExportError> {
        if !self.implicit && !self.attributes && self.palette.is_none() {
            return Err(ExportError::Volumetric(
                "nothing to add: ask for the implicit function, the attributes or a palette".into(),
            ));
        }
        let grid = VolumeGrid::new(b, self.resolution)?;
        let channels = shape.attributes().len();
        if (self.attributes || self.palette.is_some()) && channels == 0 {
            return Err(ExportError::Volumetric(
                "the model has no attribute channels s[] to write as volume data".into(),
            ));
        }
        let materials = self.palette.as_ref().map_or(0, |p| p.len());
        if materials > 0 && materials < 2 {
            return Err(ExportError::Volumetric(
                "a palette to mix needs at least 2 materials".into(),
            ));
        }
        if materials > channels + 1 {
            return Err(ExportError::Volumetric(format!(
                "{materials} materials need {} attribute channels s[1..]; the model has {channels}",
                materials - 1
            )));
        }
        let fallback = if self.implicit {
            let mut g = microfrep_core::Graph::new();
            let root = g.add(shape.value());
            let bad = microfrep_3mf::from_core::unsupported(&g, root);
            (!bad.is_empty()).then(|| bad.into_iter().map(|u| u.what).collect())
        } else {
            None
        };
        let attributes = if self.attributes || materials > 0 {
            channels
        } else {
            0
        };
        let read = attributes.max(materials.saturating_sub(1));
        let plan = VolumePlan {
            grid,
            fallback,
            attributes,
            read,
            materials,
        };
        if plan.channels() > 0 {
            let voxels = grid.voxels();
            if voxels > microfrep_3mf::volumetric::MAX_SAMPLES {
                return Err(ExportError::Volumetric(format!(
                    "image stacks of {:?} voxels exceed 2^31 voxels; lower the volume resolution",
                    grid.dims
                )));
            }
            let need = plan.bytes(voxels as f64);
            let avail = self
                .memory_limit
                .or_else(microfrep_io::limits::memory_limit);
            if let Some(avail) = avail.filter(|&a| need > a) {
                let fit = (self.resolution as f64 * (avail / need).cbrt()).floor() as usize;
                return Err(ExportError::VolumeMemory {
                    dims: grid.dims,
                    images: plan.channels(),
                    need,
                    avail,
                    fit: if fit >= 1 {
                        format!("volume resolution {fit} would fit")
                    } else {
                        "no volume resolution would fit".into()
                    },
                });
            }
        }
        Ok(plan)
    }

    /// Checks the request against the model and the memory before any
    /// work (a model without attribute channels, a palette longer than the
    /// channels, image stacks too large), and gives the image grid.
    pub fn check(&self, shape: &Shape, b: Bounds) -> Result<VolumeGrid, ExportError> {
        self.plan(shape, b).map(|p| p.grid)
    }
}

/// Samples the outputs `outs` of the shape's output tape at the voxel
/// centres (f32, all threads, one sheet at a time), each as one array in
/// image order (`ix` fastest, then `iy`, then `iz`).
fn sample_outputs(
    shape: &Shape,
    grid: &VolumeGrid,
    outs: &[usize],
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Vec<Vec<f32>> {
    use std::sync::atomic::{AtomicU64, Ordering};
    let [nx, ny, nz] = grid.dims;
    let done = AtomicU64::new(0);
    let sheets: Vec<Vec<Vec<f32>>> = (0..nz)
        .into_par_iter()
        .map_init(
            || microfrep_core::BatchEval::new(shape.outputs()),
            |ev, iz| {
                let n = nx * ny;
                let (mut x, mut y, mut z) = (vec![0f32; n], vec![0f32; n], vec![0f32; n]);
                for iy in 0..ny {
                    for ix in 0..nx {
                        let c = grid.centre(ix, iy, iz);
                        let q = ix + nx * iy;
                        (x[q], y[q], z[q]) = (c[0] as f32, c[1] as f32, c[2] as f32);
                    }
                }
                let r = outs
                    .iter()
                    .map(|&o| {
                        let mut v = vec![0f32; n];
                        ev.eval_output(o, &x, &y, &z, &mut v);
                        v
                    })
                    .collect();
                progress(done.fetch_add(1, Ordering::Relaxed) + 1, nz as u64);
                r
            },
        )
        .collect();
    (0..outs.len())
        .map(|k| sheets.iter().flat_map(|s| s[k].iter().copied()).collect())
        .collect()
}

/// A 16-bit greyscale image of `v` mapped linearly from its finite range
/// onto `[0, 1]`, with the `(offset, scale)` that map the samples back
/// (`value = sample * scale + offset`); NaN samples become `nan`
/// (in `[0, 1]`).
fn scalar_image(
    id: u32,
    grid: &VolumeGrid,
    v: &[f32],
    nan: f64,
    name: &str,
) -> Result<(microfrep_3mf::volumetric::Image3D, f64, f64), ExportError> {
    use microfrep_3mf::volumetric::{Image3D, PixelLayout};
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for &x in v.iter().filter(|x| x.is_finite()) {
        lo = lo.min(x as f64);
        hi = hi.max(x as f64);
    }
    if lo > hi {
        (lo, hi) = (0.0, 0.0);
    }
    let scale = if hi > lo { hi - lo } else { 1.0 };
    let [nx, ny, _] = grid.dims;
    let mut im = Image3D::from_fn(id, grid.dims, PixelLayout::Y, 16, |ix, iy, iz| {
        let x = v[ix + nx * (iy + ny * iz)] as f64;
        let t = if x.is_nan() { nan } else { (x - lo) / scale };
        [t, 0.0, 0.0, 1.0]
    })?;
    im.name = Some(name.to_string());
    Ok((im, lo, scale))
}

fn image_function(
    id: u32,
    image: u32,
    name: &str,
    offset: f64,
    scale: f64,
) -> microfrep_3mf::volumetric::FunctionFromImage3D {
    let mut f = microfrep_3mf::volumetric::FunctionFromImage3D::new(id, image);
    f.display_name = Some(name.to_string());
    f.value_offset = offset;
    f.value_scale = scale;
    f
}

/// A closed box mesh (12 triangles, outward).
fn box_mesh(b: Bounds) -> Mesh3 {
    Mesh3::cuboid(b.min, b.max)
}

/// A property name for attribute `k`: its own name when it is an XML-safe
/// identifier, else `s{k+1}`.
fn property_name(shape: &Shape, k: usize) -> String {
    let n = &shape.attributes()[k].name;
    if microfrep_3mf::implicit::is_identifier(n) {
        n.clone()
    } else {
        format!("s{}", k + 1)
    }
}

/// Adds the volumetric and implicit resources of `shape` to `model`,
/// whose mesh object `part` is the meshed part (in model units, which must
/// be millimetres like the shape):
///
/// - with [`VolumeOptions::attributes`] (or a palette), a `<v:volumedata>`
///   on the part: one property per attribute channel (named after the
///   channel), each an `<v:image3d>` stack of 16-bit greyscale sheets
///   sampled at the voxel centres of [`VolumeGrid`], read through a
///   `<v:functionfromimage3d>` whose offset and scale give back the
///   channel's values (its finite range spread over the 65536 levels; NaN
///   stored as the lowest);
/// - with a palette of `n` materials, base materials and a composite whose
///   mapping `k` is the share of material `k` (an image each; the first
///   `n - 1` the clamped channels, scaled down where they sum above 1, the
///   last the remainder) and the mixed colour as the volume data's colour;
/// - with [`VolumeOptions::implicit`], a box mesh of `b` (type other) and a
///   `<v:levelset>` object bounded by it (`meshbboxonly`), carrying the
///   same volume data, whose function is the model negated (the extension
///   takes the inside where the value is negative): its node graph when
///   every operation has an implicit node, else an image stack of `-f`
///   sampled like the attributes (channel `red`, fallback value 1, i.e.
///   outside). The build items of `part` are moved to the level set: the
///   mesh stays in the package as the part's triangle form.
///
/// `progress(done, total)` counts sampled sheets. Nothing is added on
/// error.
pub fn add_volumetric(
    model: &mut Model,
    part: u32,
    shape: &Shape,
    b: Bounds,
    opts: &VolumeOptions,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<VolumeReport, ExportError> {
    use microfrep_3mf::volumetric::{
        Composite, FunctionRef, Image3D, LevelSet, PixelLayout, Property, VolumeData,
    };
    use microfrep_3mf::{Base, BaseMaterials, ObjectContent, ObjectType};
    let plan = opts.plan(shape, b)?;
    let is_mesh = model
        .object(part)
        .is_some_and(|o| matches!(o.content, ObjectContent::Mesh(_)));
    if !is_mesh {
        return Err(ExportError::Volumetric(format!(
            "object {part} is not a mesh object of the package"
        )));
    }
    let mut m = model.clone();
    let grid = plan.grid;
    let to_unit = grid.to_unit();
    // Sampled outputs: the value (for the fallback), then the channels read.
    let mut outs = Vec::new();
    if plan.fallback.is_some() {
        outs.push(0);
    }
    outs.extend((0..plan.read).map(|k| shape.attribute_output(k)));
    let samples = if outs.is_empty() {
        Vec::new()
    } else {
        sample_outputs(shape, &grid, &outs, progress)
    };
    let (value, channels) = match plan.fallback {
        Some(_) => (Some(&samples[0]), &samples[1..]),
        None => (None, &samples[..]),
    };
    let scalar = |m: &mut Model, v: &[f32], nan: f64, name: &str| -> Result<u32, ExportError> {
        let iid = m.next_id();
        let (im, off, scale) = scalar_image(iid, &grid, v, nan, name)?;
        m.images.push(im);
        let fid = m.next_id();
        m.image_functions
            .push(image_function(fid, iid, name, off, scale));
        Ok(fid)
    };
    // Volume data.
    let mut volume = None;
    if plan.attributes > 0 || plan.materials > 0 {
        let mut vd = VolumeData::default();
        for (k, v) in channels.iter().enumerate().take(plan.attributes) {
            let name = property_name(shape, k);
            let f = scalar(&mut m, v, 0.0, &name)?;
            vd.properties.push(Property {
                name,
                required: false,
                value: FunctionRef::new(f, "red", to_unit),
            });
        }
        if let Some(p) = &opts.palette {
            let n = plan.materials;
            let voxels = grid.voxels() as usize;
            // Shares as `microfrep materials` reads them.
            let mut shares = vec![vec![0f32; voxels]; n];
            for q in 0..voxels {
                let mut sum = 0f32;
                for k in 0..n - 1 {
                    let x = channels[k][q];
                    let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
                    shares[k][q] = x;
                    sum += x;
                }
                if sum > 1.0 {
                    for s in shares.iter_mut().take(n - 1) {
                        s[q] /= sum;
                    }
                    sum = 1.0;
                }
                shares[n - 1][q] = (1.0 - sum).max(0.0);
            }
            let bid = m.next_id();
            m.base_materials.push(BaseMaterials {
                id: bid,
                bases: p
                    .materials()
                    .iter()
                    .map(|mat| Base {
                        name: mat.name.clone(),
                        color: [mat.rgb[0], mat.rgb[1], mat.rgb[2], 255],
                    })
                    .collect(),
            });
            let mut mappings = Vec::new();
            for (k, s) in shares.iter().enumerate() {
                let iid = m.next_id();
                let name = format!("share of {}", p.materials()[k].name);
                let mut im = Image3D::from_fn(iid, grid.dims, PixelLayout::Y, 16, |ix, iy, iz| {
                    let [nx, ny, _] = grid.dims;
                    [s[ix + nx * (iy + ny * iz)] as f64, 0.0, 0.0, 1.0]
                })?;
                im.name = Some(name.clone());
                m.images.push(im);
                let fid = m.next_id();
                m.image_functions
                    .push(image_function(fid, iid, &name, 0.0, 1.0));
                mappings.push(FunctionRef::new(fid, "red", to_unit));
            }
            let iid = m.next_id();
            let mut im = Image3D::from_fn(iid, grid.dims, PixelLayout::Rgb, 8, |ix, iy, iz| {
                let [nx, ny, _] = grid.dims;
                let q = ix + nx * (iy + ny * iz);
                let mut c = [0.0, 0.0, 0.0, 1.0];
                for (k, mat) in p.materials().iter().enumerate() {
                    for (ca, &ra) in c.iter_mut().zip(&mat.rgb) {
                        *ca += shares[k][q] as f64 * ra as f64 / 255.0;
                    }
                }
                c
            })?;
            im.name = Some("colour".into());
            m.images.push(im);
            let fid = m.next_id();
            m.image_functions
                .push(image_function(fid, iid, "colour", 0.0, 1.0));
            vd.composite = Some(Composite {
                base_materials: bid,
                mappings,
            });
            vd.color = Some(FunctionRef::new(fid, "color", to_unit));
        }
        vd.id = m.next_id();
        volume = Some(vd.id);
        m.volume_data.push(vd);
        if let Some(o) = m.objects.iter_mut().find(|o| o.id == part) {
            if let ObjectContent::Mesh(me) = &mut o.content {
                me.volume_id = volume;
            }
        }
    }
    // Level set.
    let mut level_set = None;
    let mut level_set_object = None;
    if opts.implicit {
        let (function, channel, transform, source) = match (&plan.fallback, value) {
            (Some(fields), Some(v)) => {
                let neg: Vec<f32> = v.iter().map(|x| -x).collect();
                let f = scalar(&mut m, &neg, 1.0, "level set")?;
                let src = LevelSetSource::ImageStack {
                    fields: fields.clone(),
                };
                (f, "red", to_unit, src)
            }
            _ => {
                let id = m.next_id();
                let f =
                    microfrep_3mf::from_core::levelset_function(shape.value(), id, Some("model"))
                        .map_err(|bad| {
                        ExportError::Volumetric(format!(
                            "no implicit node for {}",
                            bad.iter()
                                .map(|u| u.what.as_str())
                                .collect::<Vec<_>>()
                                .join(", ")
                        ))
                    })?;
                let nodes = f.graph.nodes.len();
                m.implicit_functions.push(f);
                (
                    id,
                    "value",
                    Transform::IDENTITY,
                    LevelSetSource::Graph { nodes },
                )
            }
        };
        let bx = m.add_mesh(Some("level set bounds"), box_mesh(b));
        if let Some(o) = m.objects.iter_mut().find(|o| o.id == bx) {
            o.kind = ObjectType::Other;
        }
        let id = m.next_id();
        let name = m
            .object(part)
            .and_then(|o| o.name.clone())
            .unwrap_or_else(|| "part".into());
        let mut o =
            microfrep_3mf::Object::mesh(id, Some(&format!("{name} (level set)")), Mesh3::default());
        o.content = ObjectContent::LevelSet(LevelSet {
            function,
            channel: channel.into(),
            transform,
            min_feature_size: 0.0,
            fallback: 1.0,
            mesh: bx,
            mesh_bbox_only: true,
            volume_id: volume,
        });
        m.objects.push(o);
        let mut moved = false;
        for it in m.build.iter_mut().filter(|it| it.object == part) {
            it.object = id;
            moved = true;
        }
        if !moved {
            m.add_item(id, Transform::IDENTITY);
        }
        level_set = Some(source);
        level_set_object = Some(id);
    }
    microfrep_3mf::validate(&m)?;
    let images = m.images.len() - model.images.len();
    *model = m;
    Ok(VolumeReport {
        grid,
        level_set,
        level_set_object,
        volume_data: volume,
        attributes: plan.attributes,
        materials: plan.materials,
        images,
    })
}

/// Reads the 3MF package at `path` (a meshed part as `microfrep mesh`
/// writes it: one mesh object, built), adds what [`add_volumetric`] adds,
/// and writes it back atomically.
pub fn add_volumetric_to_file(
    path: &Path,
    shape: &Shape,
    b: Bounds,
    opts: &VolumeOptions,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<VolumeReport, ExportError> {
    use microfrep_3mf::ObjectContent;
    opts.plan(shape, b)?;
    let mut m = microfrep_3mf::read_file(path)?;
    let meshes: Vec<u32> = m
        .build
        .iter()
        .map(|it| it.object)
        .filter(|&id| {
            m.object(id)
                .is_some_and(|o| matches!(o.content, ObjectContent::Mesh(_)))
        })
        .collect();
    let [part] = meshes[..] else {
        return Err(ExportError::Volumetric(format!(
            "{}: volume data is added to a package with one built mesh object; it has {}",
            path.display(),
            meshes.len()
        )));
    };
    if m.unit != Unit::Millimeter {
        return Err(ExportError::Volumetric(format!(
            "{}: the package is in {}s, the model in millimetres",
            path.display(),
            m.unit.name()
        )));
    }
    let r = add_volumetric(&mut m, part, shape, b, opts, progress)?;
    write_file(path, &m, &WriteOptions::default())?;
    Ok(r)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn volume_grid_covers_the_box_with_cubic_voxels_centred() {
        let g = VolumeGrid::new(Bounds::new([0.0; 3], [4.0, 2.0, 1.0]), 8).unwrap();
        assert_eq!((g.dims, g.pitch, g.min), ([8, 4, 2], 0.5, [0.0; 3]));
        // One side not a whole number of voxels: centred overhang.
        let g = VolumeGrid::new(Bounds::new([0.0; 3], [3.0, 1.0, 3.0]), 4).unwrap();
        assert_eq!(g.dims, [4, 2, 4]);
        assert!((g.min[1] + 0.25).abs() < 1e-12 && (g.max()[1] - 1.25).abs() < 1e-12);
        // Voxel centres land on UVW (i + 1/2) / n.
        let uvw = g.to_unit().apply(g.centre(0, 1, 3));
        for (a, want) in [0.5 / 4.0, 1.5 / 2.0, 3.5 / 4.0].iter().enumerate() {
            assert!((uvw[a] - want).abs() < 1e-12, "{uvw:?}");
        }
        assert!(VolumeGrid::new(Bounds::new([0.0; 3], [1.0; 3]), 0).is_err());
        assert!(VolumeGrid::new(Bounds::new([0.0; 3], [0.0; 3]), 8).is_err());
    }

    #[test]
    fn requests_are_checked_before_any_work() {
        let [x, y, z] = microfrep_core::Expr::xyz();
        let ball = 1.0 - (x.square() + y.square() + z.square());
        let b = Bounds::new([-1.0; 3], [1.0; 3]);
        let plain = Shape::new(ball.clone());
        let graded = Shape::new(ball).with_attribute("s1", x.clone());
        let opts = |f: &dyn Fn(&mut VolumeOptions)| {
            let mut o = VolumeOptions::default();
            f(&mut o);
            o
        };
        let msg = |o: VolumeOptions, s: &Shape| o.check(s, b).unwrap_err().to_string();
        assert!(msg(opts(&|_| {}), &plain).contains("nothing to add"));
        assert!(msg(opts(&|o| o.attributes = true), &plain).contains("no attribute channels"));
        let three =
            microfrep_graded::stack::Palette::parse("a=#000000,b=#ffffff,c=#ff0000").unwrap();
        let p = opts(&|o| o.palette = Some(three.clone()));
        assert!(msg(p, &graded).contains("3 materials need 2 attribute channels"));
        // 64^3 voxels of two channels in 1 MB: refused, with what fits.
        let big = opts(&|o| {
            o.attributes = true;
            o.implicit = true;
            o.memory_limit = Some(1e6);
        });
        let e = big.check(&graded, b).unwrap_err();
        assert!(
            matches!(e, ExportError::VolumeMemory { ref fit, .. } if fit.contains("would fit")),
            "{e}"
        );
        // The implicit graph alone samples nothing.
        let g = opts(&|o| {
            o.implicit = true;
            o.memory_limit = Some(1.0);
        });
        assert!(g.check(&plain, b).is_ok());
    }
}
