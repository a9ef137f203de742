//! A whole meshing job, model to file: the policy the CLI, the studio and
//! the Python bindings share. It checks the predicted peak memory against
//! what the process may really use, streams STL and PLY to disk when the
//! mesh would not fit (or when asked), writes the other formats from
//! memory, and summarises the result (counts, bad edges, volume, area,
//! bounding box, run-time errors of the model, thin features).

use crate::check::summary;
use crate::memory::{self, Estimate};
use crate::write::{format_of, stream_mesh, write_mesh};
use crate::{MeshError, MeshOptions, Plan};
use microfrep_core::{ErrorCensus, Shape};
use std::path::Path;

/// How to run a job beyond the meshing options.
#[derive(Clone, Debug, Default)]
pub struct JobOptions {
    /// Stream to disk even if the mesh would fit in memory (STL, PLY).
    pub stream: bool,
    /// Bytes the job may use; default: [`microfrep_io::limits::memory_limit`].
    pub memory_limit: Option<f64>,
}

/// What a finished job reports.
#[derive(Clone, Debug)]
pub struct Summary {
    /// Cells on the longest side.
    pub resolution: usize,
    /// Cell size.
    pub cell: f64,
    /// Triangles written.
    pub triangles: u64,
    /// Vertices written.
    pub vertices: u64,
    /// Edges not shared by exactly two oppositely oriented triangles; not
    /// known for a streamed mesh.
    pub bad_edges: Option<usize>,
    /// Euler characteristic V - E + F (not known when streamed).
    pub euler: Option<i64>,
    /// Signed volume by the divergence theorem.
    pub volume: f64,
    /// Surface area.
    pub area: f64,
    /// Bounding box of the vertices.
    pub bbox: [[f64; 3]; 2],
    /// Whether the mesh was streamed to disk.
    pub streamed: bool,
    /// Predicted peak bytes.
    pub predicted_bytes: f64,
    /// See [`Plan::thin_cells`].
    pub thin_cells: usize,
    /// Run-time errors of the model at the grid nodes (models with an
    /// error channel only).
    pub runtime_errors: Option<ErrorCensus>,
}

const GIB: f64 = (1u64 << 30) as f64;

/// Meshes `shape` with `opts` into `out` (format by extension);
/// `progress(done, total)` counts surface bricks.
pub fn mesh_to_file(
    shape: &Shape,
    opts: &MeshOptions,
    out: &Path,
    job: &JobOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Summary, MeshError> {
    let format = format_of(out)?;
    microfrep_io::atomic::check_not_input(out)?;
    let plan = Plan::new(shape, opts)?;
    let est = memory::estimate(&plan);
    let avail = job.memory_limit.or_else(microfrep_io::limits::memory_limit);
    let too_big = |bytes: f64| avail.is_some_and(|m| bytes > m);
    let stream = format.streams() && (job.stream || too_big(est.bytes));
    let predicted = if stream {
        memory::streaming_bytes(&plan, &est)
    } else {
        est.bytes
    };
    if let Some(m) = avail.filter(|&m| predicted > m) {
        return Err(too_large(&plan, &est, predicted, m, format.streams()));
    }
    if stream {
        check_disk(out, &est)?;
    }
    let total = plan.surface_bricks();
    let progress = |done: usize| progress(done, total);
    let mut s = if stream {
        let t = stream_mesh(&plan, out, format.wants_normals(), &progress)?;
        Summary {
            resolution: opts.resolution,
            cell: plan.grid.h,
            triangles: t.triangles,
            vertices: t.vertices,
            bad_edges: None,
            euler: None,
            volume: t.volume,
            area: t.area,
            bbox: t.bbox,
            streamed: true,
            predicted_bytes: predicted,
            thin_cells: 0,
            runtime_errors: None,
        }
    } else {
        let mesh = plan.run(&progress)?;
        let normals = format.wants_normals().then(|| plan.normals(&mesh));
        write_mesh(out, &mesh, normals.as_deref())?;
        let r = summary(&mesh);
        Summary {
            resolution: opts.resolution,
            cell: plan.grid.h,
            triangles: r.triangles as u64,
            vertices: r.vertices as u64,
            bad_edges: Some(r.bad_edges),
            euler: Some(r.euler),
            volume: r.volume,
            area: r.area,
            bbox: r.bbox,
            streamed: false,
            predicted_bytes: predicted,
            thin_cells: 0,
            runtime_errors: None,
        }
    };
    s.thin_cells = plan.thin_cells();
    s.runtime_errors = error_census(shape, &plan);
    Ok(s)
}

/// Run-time errors at the grid nodes (those nodes are NaN: outside).
fn error_census(shape: &Shape, plan: &Plan) -> Option<ErrorCensus> {
    let g = &plan.grid;
    let axis = |a: usize| -> Vec<f64> {
        (0..=g.cells[a])
            .map(|i| g.origin[a] + g.h * i as f64)
            .collect()
    };
    shape.error_census(&axis(0), &axis(1), &axis(2))
}

fn too_large(plan: &Plan, est: &Estimate, predicted: f64, avail: f64, streams: bool) -> MeshError {
    let n = plan.grid.cells.iter().copied().max().unwrap_or(1);
    let hint = if streams {
        ""
    } else {
        " (or write .stl or .ply, which are streamed to disk)"
    };
    MeshError::TooLarge(format!(
        "meshing at resolution {n} needs about {:.1} GiB but {:.1} GiB are available; \
         resolution {} would fit{hint}",
        predicted / GIB,
        avail / GIB,
        memory::resolution_fitting(est, n, avail)
    ))
}

/// Refuses a streamed job whose predicted file would not fit on the disk.
fn check_disk(out: &Path, est: &Estimate) -> Result<(), MeshError> {
    // Binary STL: 50 bytes a triangle; PLY: about 13 a face and 24 a vertex.
    let bytes = 50.0 * est.triangles + 84.0;
    let dir = out.parent().unwrap_or(Path::new("."));
    match microfrep_io::limits::free_disk(dir) {
        Some(free) if bytes > free => Err(MeshError::TooLarge(format!(
            "{}: the mesh needs about {:.1} GiB of disk but {:.1} GiB are free",
            out.display(),
            bytes / GIB,
            free / GIB
        ))),
        _ => Ok(()),
    }
}
