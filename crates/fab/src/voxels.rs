//! Voxel export: occupancy (one byte per voxel, 1 inside) or f32 field
//! values at voxel centres, x fastest then y then z, as NRRD, legacy VTK
//! structured points, or raw bytes with a JSON sidecar. Written one z-slab
//! at a time.

use crate::error::{io_at, FabError, Result};
use microfrep_core::{eval_grid_par, Shape};
use microfrep_io::AtomicFile;
use std::io::Write;
use std::path::Path;

/// Limit on the voxel count, so a typo in the size is an error, not a
/// disk-filling run.
const MAX_VOXELS: usize = 1 << 32;

/// The file formats of [`write_voxels`], chosen by the output's extension.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum VoxelFormat {
    /// Bare voxel bytes (`.raw`), with a `.json` sidecar giving dimensions,
    /// spacing, origin and value type.
    Raw,
    /// Legacy VTK structured points (`.vtk`) with binary data.
    Vtk,
    /// NRRD (`.nrrd`): a text header followed by the raw voxel bytes.
    Nrrd,
}

impl VoxelFormat {
    /// From the output's extension: `.raw`, `.vtk` or `.nrrd`.
    pub fn from_path(p: &Path) -> Result<VoxelFormat> {
        match p.extension().and_then(|e| e.to_str()) {
            Some("raw") => Ok(VoxelFormat::Raw),
            Some("vtk") => Ok(VoxelFormat::Vtk),
            Some("nrrd") => Ok(VoxelFormat::Nrrd),
            _ => Err(FabError::Invalid(format!(
                "{}: extension must be .raw, .vtk or .nrrd",
                p.display()
            ))),
        }
    }
}

/// The sampled lattice: `dims` voxels of side `spacing`, the first voxel's
/// centre at `origin`.
#[derive(Clone, Debug, PartialEq)]
pub struct VoxelGrid {
    /// Voxels per axis, each at least 1.
    pub dims: [usize; 3],
    /// Side of the cubic voxels, model units (millimetres).
    pub spacing: f64,
    /// Centre of voxel `(0, 0, 0)` in model units: half a voxel inside the box's
    /// lower corner.
    pub origin: [f64; 3],
}

impl VoxelGrid {
    /// The grid of cubic voxels of side `voxel` covering `min..max` (model
    /// units); counts are rounded up, so the grid may reach a little past `max`.
    ///
    /// # Errors
    /// [`FabError::Invalid`] when `voxel` is not a positive number, the box is
    /// not finite with `min < max`, a voxel is larger than a side of the box,
    /// f32 samples could not resolve the voxel size at the box's coordinates,
    /// or there would be more than 2^32 voxels.
    pub fn new(min: [f64; 3], max: [f64; 3], voxel: f64) -> Result<VoxelGrid> {
        if !(voxel.is_finite() && voxel > 0.0) {
            return Err(FabError::Invalid(format!(
                "voxel size must be positive, got {voxel}"
            )));
        }
        let mut dims = [0; 3];
        for a in 0..3 {
            let len = max[a] - min[a];
            if !(len.is_finite() && len > 0.0) {
                return Err(FabError::Invalid(format!(
                    "bounds on axis {a} must be finite with min < max"
                )));
            }
            if voxel > len {
                return Err(FabError::Invalid(format!(
                    "the voxel size {voxel} exceeds the box's {} side {len}: the voxel centres \
                     would lie outside the box; use a voxel of at most {len}",
                    ["x", "y", "z"][a]
                )));
            }
            dims[a] = (len / voxel - 1e-9).ceil().max(1.0) as usize;
        }
        microfrep_io::precision::check_grid(min, max, voxel)
            .map_err(|e| FabError::Invalid(format!("cannot sample voxels: {e}")))?;
        let n = dims.iter().map(|&d| d as f64).product::<f64>();
        if n > MAX_VOXELS as f64 {
            return Err(FabError::Invalid(format!(
                "{} x {} x {} voxels exceed the limit of {MAX_VOXELS}",
                dims[0], dims[1], dims[2]
            )));
        }
        Ok(VoxelGrid {
            dims,
            spacing: voxel,
            origin: [0, 1, 2].map(|a| min[a] + 0.5 * voxel),
        })
    }
}

/// Samples the model on `grid` and writes `out` (format from its
/// extension); `.raw` gets a `.json` sidecar next to it. With `field` the
/// values are f32, else occupancy bytes. The files appear only when both
/// are complete (atomic outputs, committed together).
pub fn write_voxels(shape: &Shape, grid: &VoxelGrid, field: bool, out: &Path) -> Result<()> {
    let format = VoxelFormat::from_path(out)?;
    let s = grid.spacing;
    let lo = grid.origin.map(|o| o - 0.5 * s);
    let hi: [f64; 3] = std::array::from_fn(|a| lo[a] + grid.dims[a] as f64 * s);
    crate::grid::check_precision(shape, lo, hi)?;
    // One z-layer at a time: its values (4 bytes a voxel) and its bytes.
    let layer = (grid.dims[0] * grid.dims[1]) as f64 * (4.0 + if field { 4.0 } else { 1.0 });
    if let Some(m) = microfrep_io::limits::memory_limit().filter(|&m| layer > 0.8 * m) {
        return Err(FabError::TooLarge(format!(
            "a layer of {} x {} voxels needs about {:.0} MiB but {:.0} MiB are available; use \
             a coarser --voxel",
            grid.dims[0],
            grid.dims[1],
            layer / (1024.0 * 1024.0),
            m / (1024.0 * 1024.0)
        )));
    }
    let mut f = AtomicFile::create(out)?;
    let inside = write_into(shape, grid, field, format, &mut f).map_err(io_at(out))?;
    if inside == 0 {
        // Dropping `f` removes the temporary: nothing is written.
        let [nx, ny, nz] = grid.dims;
        return Err(FabError::Empty(format!(
            "{}: none of the {nx} x {ny} x {nz} voxels (of {s}) has its centre inside the \
             model: the part is smaller than a voxel, undefined (NaN) or outside the box; \
             use a smaller --voxel or check --bounds",
            out.display()
        )));
    }
    if format == VoxelFormat::Raw {
        let side = out.with_extension("json");
        let mut s = AtomicFile::create(&side)?;
        s.write_all(sidecar(grid, field).as_bytes())
            .map_err(io_at(&side))?;
        microfrep_io::atomic::commit_all(vec![f, s])?;
    } else {
        f.commit()?;
    }
    Ok(())
}

fn write_into(
    shape: &Shape,
    g: &VoxelGrid,
    field: bool,
    format: VoxelFormat,
    w: &mut AtomicFile,
) -> std::io::Result<u64> {
    let [nx, ny, nz] = g.dims;
    let [ox, oy, oz] = g.origin;
    let s = g.spacing;
    let header = match format {
        VoxelFormat::Raw => String::new(),
        VoxelFormat::Nrrd => format!(
            "NRRD0004\n# microfrep voxels\ntype: {}\ndimension: 3\nspace: 3D-right-handed\n\
             sizes: {nx} {ny} {nz}\nspace directions: ({s},0,0) (0,{s},0) (0,0,{s})\n\
             space origin: ({ox},{oy},{oz})\nendian: little\nencoding: raw\n\n",
            if field { "float" } else { "uint8" }
        ),
        VoxelFormat::Vtk => format!(
            "# vtk DataFile Version 3.0\nmicrofrep voxels\nBINARY\nDATASET STRUCTURED_POINTS\n\
             DIMENSIONS {nx} {ny} {nz}\nORIGIN {ox} {oy} {oz}\nSPACING {s} {s} {s}\n\
             POINT_DATA {}\nSCALARS {} 1\nLOOKUP_TABLE default\n",
            nx * ny * nz,
            if field {
                "value float"
            } else {
                "occupancy unsigned_char"
            }
        ),
    };
    w.write_all(header.as_bytes())?;
    let mut bytes = Vec::new();
    let mut inside = 0u64;
    for k in 0..nz {
        let vals = eval_grid_par(
            shape.tape(),
            [nx, ny, 1],
            [ox, oy, oz + k as f64 * s],
            [s, s, s],
        );
        bytes.clear();
        inside += vals.iter().filter(|&&v| v >= 0.0).count() as u64;
        if field {
            for v in vals {
                // Legacy VTK binary data is big-endian.
                let b = if format == VoxelFormat::Vtk {
                    v.to_be_bytes()
                } else {
                    v.to_le_bytes()
                };
                bytes.extend_from_slice(&b);
            }
        } else {
            bytes.extend(vals.iter().map(|&v| (v >= 0.0) as u8));
        }
        w.write_all(&bytes)?;
    }
    if format == VoxelFormat::Vtk {
        w.write_all(b"\n")?;
    }
    Ok(inside)
}

fn sidecar(g: &VoxelGrid, field: bool) -> String {
    let [nx, ny, nz] = g.dims;
    let [ox, oy, oz] = g.origin;
    format!(
        "{{\n  \"dims\": [{nx}, {ny}, {nz}],\n  \"spacing\": [{s}, {s}, {s}],\n  \
         \"origin\": [{ox}, {oy}, {oz}],\n  \"type\": \"{}\",\n  \"endian\": \"little\",\n  \
         \"order\": \"x fastest, then y, then z; origin is the centre of the first voxel\"\n}}\n",
        if field { "float32" } else { "uint8 (1 inside)" },
        s = g.spacing
    )
}
