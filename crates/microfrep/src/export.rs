//! Compact printer files (3MF extensions) from models: slice stacks (the
//! slice extension) and beam lattices (the beam lattice extension), each
//! with a mesh of the part so viewers without the extension still show it.

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
    let max = [
        grid.min[0] + grid.nx as f64 * grid.pixel,
        grid.min[1] + grid.ny as f64 * grid.pixel,
        grid.min[2] + grid.layers as f64 * grid.layer,
    ];
    let mut m = Model::new(Unit::Millimeter);
    let low = m.add_mesh(
        Some("part"),
        mesh3(shape, Bounds::new(grid.min, max), preview)?,
    );
    let sid = m.next_id();
    m.slice_stacks
        .push(SliceStack::uniform(sid, grid.min[2], grid.layer, layers));
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
/// lattice's clipping mesh and the representation viewers show. Returns
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
    use microfrep_structures::strut_graph::StrutGraph;
    use microfrep_structures::struts::StrutLattice;
    let k = StrutLattice::ALL[(kind.clamp(1, 6) - 1) as usize];
    let g = StrutGraph::tile(k, bounds.min, bounds.max, cell, |_| radius)?.clip(part.value());
    let mut m = Model::new(Unit::Millimeter);
    let clip = m.add_mesh(Some("part"), mesh3(part, bounds, resolution)?);
    let mut l = BeamLattice::new(radius, 1e-4);
    for (&(a, b), r) in g.beams.iter().zip(&g.radii) {
        l.push(a, b, r[0], r[1]);
    }
    l.clipping = Some((ClipMode::Inside, clip));
    l.representation = Some(clip);
    let id = m.add_mesh(
        Some("lattice"),
        Mesh3 {
            vertices: g.nodes.clone(),
            beam_lattice: Some(l),
            ..Mesh3::default()
        },
    );
    m.add_item(id, Transform::IDENTITY);
    write_file(out, &m, &WriteOptions::default())?;
    Ok((g.beams.len(), g.nodes.len()))
}
