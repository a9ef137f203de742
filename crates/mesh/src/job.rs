//! A whole meshing job, model to file: the policy the CLI, the studio and
//! the Python bindings share.
//!
//! Before anything large is allocated, the job checks that f32 sampling
//! resolves the box and the model (against the f64 reference,
//! [`microfrep_io::precision`]) and predicts its peak memory (brick table
//! included) against what the process may really use
//! ([`microfrep_io::limits::memory_limit`]: RAM, cgroup, `RLIMIT_AS`);
//! STL and PLY are streamed to disk when the mesh would not fit (or when
//! asked), after a check of the free disk. Otherwise an STL is still
//! encoded, measured and sent to the disk while the mesh is made, its
//! edges counted meanwhile ([`crate::check::EdgeCensus`], from the bricks'
//! own edges and the stitched ones, [`crate::check::BrickEdges`]): the
//! same bytes and figures as meshing into memory first, in little more
//! than the meshing's time. After meshing, and before the
//! output appears, the mesh is refused when it is empty (with the reason)
//! or when it lost more volume than [`JobOptions::max_volume_loss`] against
//! the model's own sampled volume ([`crate::sampled`]): features thinner
//! than a cell vanish from a mesh without a hole, and this is how they are
//! noticed. [`JobOptions::auto`] chooses the resolution instead: the
//! coarsest at which the mesh keeps the model's volume.
//! [`JobOptions::colour`] colours the vertices by an attribute channel
//! (PLY, OBJ, 3MF; checked before meshing).

use crate::memory::{self, Estimate, GIB};
use crate::sampled::{sampled_volume, SampledVolume};
use crate::sink::{MeshSink, Tally, Tallying, VertexWindow};
use crate::write::colour::{channel_tape, scale_of, vertex_colours, ColourBy, ColourScale};
use crate::write::{
    check_colours, format_of, stream_mesh_coloured, write_uncommitted_measured, MeshFormat,
};
use crate::{Grid, Mesh, MeshError, MeshOptions, Plan};
use microfrep_core::{ErrorCensus, Shape};
use std::path::Path;
use std::time::Instant;

/// How to run a job beyond the meshing options.
#[derive(Clone, Debug)]
pub struct JobOptions {
    /// Stream to disk even if the mesh would fit in memory (STL, PLY).
    pub stream: bool,
    /// Bytes the job may use; default: [`microfrep_io::limits::memory_limit`].
    pub memory_limit: Option<f64>,
    /// The largest fraction of the model's volume the mesh may lose
    /// (sampled volume minus mesh volume, over the sampled volume) before
    /// the job fails with [`MeshError::VolumeLoss`] and writes nothing;
    /// `None` skips the check (and the sampling). Default 0.05.
    pub max_volume_loss: Option<f64>,
    /// Choose the resolution ([`MeshOptions::resolution`] is then ignored).
    pub auto: Option<AutoOptions>,
    /// Colour the vertices by an attribute channel (formats that store
    /// colours only: PLY, OBJ, 3MF; streamed PLY too).
    pub colour: Option<ColourBy>,
    /// Merge flat regions and straight creases ([`crate::decimate`]) while
    /// the mesh stays this close to the surface. Default `None`: the
    /// merge finds next to nothing on the curved surfaces of lattices,
    /// where it would cost a pass over the whole mesh, and it needs the
    /// mesh in memory (no streaming).
    pub tolerance: Option<Tolerance>,
}

/// How far a merged region may lie from the surface ([`JobOptions::tolerance`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Tolerance {
    /// In cells of the grid.
    Cells(f64),
    /// In model units (millimetres).
    Units(f64),
}

impl Tolerance {
    /// The tolerance in model units on a grid of cell size `h`.
    pub fn in_units(self, h: f64) -> f64 {
        match self {
            Tolerance::Cells(c) => c * h,
            Tolerance::Units(u) => u,
        }
    }

    /// The amount, whichever unit it is in.
    pub fn value(self) -> f64 {
        match self {
            Tolerance::Cells(v) | Tolerance::Units(v) => v,
        }
    }
}

impl Default for JobOptions {
    fn default() -> Self {
        JobOptions {
            stream: false,
            memory_limit: None,
            max_volume_loss: Some(0.05),
            auto: None,
            colour: None,
            tolerance: None,
        }
    }
}

/// How `--resolution auto` searches: from `start` cells up by factors of
/// 1.5 until the mesh's volume agrees with the sampled volume within
/// `tolerance` (the difference plus twice the sampling's own error) and
/// changed by less than twice `tolerance` since the previous step, or
/// `max` cells (or the memory) are reached.
#[derive(Clone, Copy, Debug)]
pub struct AutoOptions {
    /// First resolution tried.
    pub start: usize,
    /// Most cells on the longest side.
    pub max: usize,
    /// Relative volume agreement asked for.
    pub tolerance: f64,
}

impl Default for AutoOptions {
    fn default() -> Self {
        AutoOptions {
            start: 32,
            max: 4096,
            tolerance: 0.005,
        }
    }
}

/// One resolution tried by [`JobOptions::auto`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Trial {
    /// Cells on the longest side.
    pub resolution: usize,
    /// Volume of the mesh.
    pub mesh_volume: f64,
    /// The model's sampled volume and its error.
    pub sampled: SampledVolume,
    /// Wall-clock seconds of the trial.
    pub seconds: f64,
}

/// What a finished job reports.
#[derive(Clone, Debug)]
pub struct Summary {
    /// Cells on the longest side.
    pub resolution: usize,
    /// The cell method.
    pub cells: crate::CellMethod,
    /// Cell size.
    pub cell: f64,
    /// Triangles written.
    pub triangles: u64,
    /// Vertices written.
    pub vertices: u64,
    /// Edges not shared by exactly two oppositely oriented triangles
    /// (counted while streaming for a streamed mesh; `None` only if it did
    /// not come in the order that count needs).
    pub bad_edges: Option<usize>,
    /// Euler characteristic V - E + F (as `bad_edges`).
    pub euler: Option<i64>,
    /// Connected shells (triangles joined through shared vertices),
    /// counted from the mesher's indexed output; `None` for a streamed
    /// mesh.
    pub shells: Option<usize>,
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
    /// The model's volume sampled independently of the mesh (not with
    /// `max_volume_loss: None`).
    pub sampled_volume: Option<SampledVolume>,
    /// `(sampled - mesh) / sampled` volume, where sampled.
    pub volume_loss: Option<f64>,
    /// The resolutions tried by `auto`, in order (the last is the one
    /// written); empty without `auto`.
    pub trials: Vec<Trial>,
    /// The colour scale of the vertex colours (with
    /// [`JobOptions::colour`]): its range is the one asked for or the
    /// attribute's over the vertices.
    pub colour_scale: Option<ColourScale>,
    /// What merging flat regions did (with [`JobOptions::tolerance`]).
    pub decimation: Option<crate::decimate::Decimation>,
}

/// Meshes `shape` with `opts` into `out` (format by extension);
/// `progress(done, total)` counts surface bricks (per trial with `auto`).
pub fn mesh_to_file(
    shape: &Shape,
    opts: &MeshOptions,
    out: &Path,
    job: &JobOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Summary, MeshError> {
    let format = format_of(out)?;
    microfrep_io::atomic::check_not_input(out)?;
    if let Some(t) = job.tolerance {
        if !(t.value() > 0.0 && t.value().is_finite()) {
            return Err(MeshError::Input(format!(
                "tolerance {}: give a positive distance",
                t.value()
            )));
        }
        if job.stream {
            return Err(MeshError::Input(
                "merging flat regions (a tolerance) needs the mesh in memory: drop the \
                 streaming, or the tolerance"
                    .into(),
            ));
        }
    }
    if let Some(by) = &job.colour {
        // Refused before any meshing: no colours in the format, no such
        // channel, a bad range.
        check_colours(format, out)?;
        channel_tape(shape, by.channel)?;
        scale_of(by, &[])?;
    }
    let avail = job.memory_limit.or_else(microfrep_io::limits::memory_limit);
    let mut opts = opts.clone();
    opts.memory_limit = avail;
    check_precision(shape, opts.bounds)?;
    let mut trials = Vec::new();
    let mut kept = None;
    if let Some(auto) = &job.auto {
        let (n, mesh) = choose_resolution(shape, &opts, auto, avail, &mut trials, progress)?;
        opts.resolution = n;
        kept = mesh;
    }
    let (tape, grid) = Plan::frame(shape, &opts)?;
    let mut est = memory::estimate_grid(&tape, &grid, opts.cells);
    if job.colour.is_some() {
        est = memory::with_colours(&est);
    }
    let too_big = |bytes: f64| avail.is_some_and(|m| bytes > m);
    let stream = format.streams() && (job.stream || too_big(est.bytes));
    if stream && job.tolerance.is_some() {
        return Err(MeshError::TooLarge(format!(
            "merging flat regions (a tolerance) needs the mesh in memory, about {:.1} GiB, \
             but {:.1} GiB are available; lower the resolution or drop the tolerance",
            est.bytes / GIB,
            avail.unwrap_or(0.0) / GIB
        )));
    }
    let predicted = if stream {
        memory::streaming_bytes_grid(&grid, &est)
    } else {
        est.bytes
    };
    check_size(&opts, &est, stream, avail, format.streams())?;
    if stream {
        check_disk(out, &est)?;
    }
    let plan = Plan::classified(tape, grid, &opts)?;
    // A mesh the resolution search kept is written as it is (unless asked
    // to stream).
    let kept = kept.filter(|_| !job.stream);
    // (A mesh to merge is held whole first.)
    let stl_while_meshing =
        !stream && kept.is_none() && job.tolerance.is_none() && crate::write::is_stl(format);
    // Meshed here in memory (or as STL): the volume is sampled alongside.
    let meshed_here = !stream && kept.is_none();
    let mut sampled = match (&job.max_volume_loss, trials.last()) {
        (None, _) => None,
        (Some(_), Some(t)) if t.resolution == opts.resolution => Some(t.sampled),
        // Sampled alongside the meshing, below.
        (Some(_), _) if meshed_here => None,
        (Some(_), _) => Some(sampled_volume(&plan)),
    };
    let total = plan.surface_bricks();
    let progress = |done: usize| progress(done, total);
    // Runs after meshing, before the output is committed.
    let verdict =
        |t: &Tally, sampled: Option<&SampledVolume>| verdict(shape, &plan, &opts, job, sampled, t);
    let colour_scale;
    let mut decimation = None;
    let mut s = if stream {
        let colour = job.colour.as_ref().map(|c| (shape, c));
        let normals = format.wants_normals();
        let verdict = |t: &Tally| verdict(t, sampled.as_ref());
        let (t, scale) = stream_mesh_coloured(&plan, out, normals, colour, &progress, &verdict)?;
        colour_scale = scale;
        // Counted while streaming (unknown only if the pipeline's order
        // did not hold: the mesh is too big to be made again in memory).
        let checked = t
            .edges
            .map(|(edges, bad)| (bad, t.vertices as i64 - edges as i64 + t.triangles as i64));
        summary_of(&opts, &plan, &t, checked, predicted, true)
    } else if stl_while_meshing {
        // STL is encoded, measured and on its way to the disk while the
        // mesh is made, and its edges are counted meanwhile; its triangles
        // are never held whole. The model's volume is sampled alongside
        // (it fills the meshing's idle moments). Put in place only if the
        // verdict passes (dropped, the file is removed).
        colour_scale = None;
        let sample = job.max_volume_loss.is_some() && sampled.is_none();
        // Over the estimate (pages not written are never taken, so a
        // generous reservation costs nothing).
        let expected = (1.25 * est.vertices).min(u32::MAX as f64) as usize;
        let (meshed, v) = rayon::join(
            || crate::write::mesh_to_stl(&plan, out, expected, &progress),
            || sample.then(|| sampled_volume(&plan)),
        );
        sampled = sampled.or(v);
        let (file, m) = meshed?;
        let t = Tally {
            vertices: m.vertices,
            triangles: m.triangles,
            volume: m.measured.0,
            area: m.measured.1,
            bbox: m.bbox,
            edges: m.edges,
        };
        verdict(&t, sampled.as_ref())?;
        let (edges, bad_edges) = match m.edges {
            Some(e) => e,
            // The census relies on the pipeline's order (see
            // `check::EdgeCensus`); should that not hold, the mesh is made
            // again in memory and counted.
            None => crate::check::edges(&plan.run(&progress)?),
        };
        file.commit()?;
        let euler = t.vertices as i64 - edges as i64 + t.triangles as i64;
        let mut s = summary_of(&opts, &plan, &t, Some((bad_edges, euler)), predicted, false);
        s.shells = m.shells;
        s
    } else {
        // Edges and shells counted while meshing (from the bricks), and the
        // volume sampled alongside (as for STL), except for a mesh the
        // resolution search kept.
        let (mut mesh, mut counted, mut shells) = match kept {
            Some(m) => (m, None, None),
            None => {
                let sample = job.max_volume_loss.is_some() && sampled.is_none();
                let (meshed, v) = rayon::join(
                    || plan.run_counted_shells(&progress),
                    || sample.then(|| sampled_volume(&plan)),
                );
                sampled = sampled.or(v);
                meshed?
            }
        };
        if let Some(t) = job.tolerance {
            let h = plan.grid.h;
            let d = crate::decimate::decimate(&mut mesh, &plan.tape, h, t.in_units(h));
            if d.removed > 0 {
                // Counted again on what is written.
                counted = None;
                shells = None;
            }
            decimation = Some(d);
        }
        let colours = match &job.colour {
            Some(by) => Some(vertex_colours(shape, by, &mesh.vertices)?),
            None => None,
        };
        colour_scale = colours.as_ref().map(|c| c.scale);
        // The file is encoded first (all threads), then synced and put in
        // place, if the verdict passes, on a thread of its own (the sync
        // waits on the disk) while the pool counts the edges if the
        // meshing could not; dropped, the file is removed. (Run side by side under `rayon::join`, the
        // encoder's ordered writes waited behind stolen census work.) The
        // verdict needs the volume: STL measures it while encoding (the
        // facet normals are the same products), PLY while encoding its
        // faces, other formats take a pass over the triangles.
        let bbox = crate::check::bbox(&mesh);
        let measured = (!format.measures_volume()).then(|| crate::check::volume_area(&mesh));
        let (file, m) = write(
            format,
            out,
            &plan,
            &mesh,
            colours.as_ref().map(|c| &c.rgb[..]),
        );
        let (volume, area) = measured
            .or(m)
            .unwrap_or_else(|| crate::check::volume_area(&mesh));
        let t = Tally {
            vertices: mesh.vertices.len() as u64,
            triangles: mesh.triangles.len() as u64,
            volume,
            area,
            bbox,
            edges: None,
        };
        verdict(&t, sampled.as_ref())?;
        let file = file?;
        let (committed, (edges, bad_edges), shells) = std::thread::scope(|sc| {
            let sync = sc.spawn(move || file.commit());
            let e = counted.unwrap_or_else(|| crate::check::edges(&mesh));
            let shells = shells.unwrap_or_else(|| crate::check::shells(&mesh));
            (sync.join(), e, shells)
        });
        committed.map_err(|_| MeshError::Internal("the file sync thread panicked".into()))??;
        let euler = t.vertices as i64 - edges as i64 + t.triangles as i64;
        let mut s = summary_of(&opts, &plan, &t, Some((bad_edges, euler)), predicted, false);
        s.shells = Some(shells);
        s
    };
    s.thin_cells = plan.thin_cells();
    s.runtime_errors = error_census(shape, &plan);
    s.sampled_volume = sampled;
    s.volume_loss = sampled.and_then(|v| loss(v.value, s.volume));
    s.trials = trials;
    s.colour_scale = colour_scale;
    s.decimation = decimation;
    Ok(s)
}

/// Writes the mesh uncommitted; the volume and area where the format
/// measured them while encoding. On a write error the volume is still
/// wanted (the verdict's error comes first), hence the pair.
fn write(
    format: &dyn MeshFormat,
    out: &Path,
    plan: &Plan,
    mesh: &Mesh,
    colours: Option<&[[u8; 3]]>,
) -> (
    Result<microfrep_io::AtomicFile, MeshError>,
    Option<(f64, f64)>,
) {
    let normals = format.wants_normals().then(|| plan.normals(mesh));
    match write_uncommitted_measured(out, mesh, normals.as_deref(), colours) {
        Ok((f, m)) => (Ok(f), m),
        Err(e) => (Err(e), None),
    }
}

fn summary_of(
    opts: &MeshOptions,
    plan: &Plan,
    t: &Tally,
    checked: Option<(usize, i64)>,
    predicted: f64,
    streamed: bool,
) -> Summary {
    Summary {
        resolution: opts.resolution,
        cells: opts.cells,
        cell: plan.grid.h,
        triangles: t.triangles,
        vertices: t.vertices,
        bad_edges: checked.map(|c| c.0),
        euler: checked.map(|c| c.1),
        shells: None,
        volume: t.volume,
        area: t.area,
        bbox: t.bbox,
        streamed,
        predicted_bytes: predicted,
        thin_cells: 0,
        runtime_errors: None,
        sampled_volume: None,
        volume_loss: None,
        trials: Vec::new(),
        colour_scale: None,
        decimation: None,
    }
}

/// The fraction of `sampled` volume a mesh of volume `mesh` lacks.
fn loss(sampled: f64, mesh: f64) -> Option<f64> {
    (sampled > 0.0).then(|| (sampled - mesh) / sampled)
}

/// Refuses an empty mesh (saying why) and one that lost too much volume.
fn verdict(
    shape: &Shape,
    plan: &Plan,
    opts: &MeshOptions,
    job: &JobOptions,
    sampled: Option<&SampledVolume>,
    t: &Tally,
) -> Result<(), MeshError> {
    if t.triangles == 0 {
        return Err(MeshError::Empty(empty_reason(shape, plan, opts, sampled)));
    }
    if let (Some(max), Some(v)) = (job.max_volume_loss, sampled) {
        if let Some(l) = loss(v.value, t.volume).filter(|&l| l > max) {
            let hint = if job.auto.is_some() {
                format!(
                    "it is the finest resolution the search allowed ({} cells at most, and \
                     the memory)",
                    job.auto.map_or(0, |a| a.max)
                )
            } else {
                "use a finer --resolution (or --resolution auto to choose one)".to_string()
            };
            return Err(MeshError::VolumeLoss(format!(
                "the mesh at resolution {} has {:.1} % less volume than the model ({} against \
                 {} ± {} sampled in every cell): features thinner than about a cell ({}) \
                 fell between the samples and vanished; {hint}, or raise --max-volume-loss \
                 (now {} %) to accept it",
                opts.resolution,
                100.0 * l,
                sig(t.volume),
                sig(v.value),
                microfrep_io::text::sig(v.error, 2),
                sig(plan.grid.h),
                sig(100.0 * max),
            )));
        }
    }
    Ok(())
}

fn sig(v: f64) -> String {
    microfrep_io::text::sig(v, 4)
}

/// Why a mesh came out empty, for the error message.
fn empty_reason(
    shape: &Shape,
    plan: &Plan,
    opts: &MeshOptions,
    sampled: Option<&SampledVolume>,
) -> String {
    let [lo, hi] = opts.bounds;
    let b = format!("{lo:?}..{hi:?}");
    let h = sig(plan.grid.h);
    // A model NaN everywhere also has intervals that prove nothing inside:
    // name the cause, not the symptom.
    let mut pe = shape.point();
    let pts = microfrep_io::precision::probe_points(lo, hi, 512);
    if pts.iter().all(|p| pe.eval(*p).is_nan()) {
        return format!(
            "the mesh is empty: the model is NaN (undefined) everywhere in the box {b}"
        );
    }
    if plan
        .classes
        .iter()
        .all(|c| *c == crate::classify::BrickClass::Empty)
    {
        return format!(
            "the mesh is empty: interval analysis proves the model outside (f < 0) \
             everywhere in the box {b}; check --bounds"
        );
    }
    if let Some(c) = error_census(shape, plan).filter(|c| c.samples > 0 && c.errors == c.samples) {
        return format!(
            "the mesh is empty: the model is undefined (a run-time error) at every grid \
             node: {c}"
        );
    }
    if let Some(v) = sampled.filter(|v| v.value > 0.0) {
        return format!(
            "the mesh is empty at resolution {} (cells of {h}): no grid node is inside the \
             model, though sampling every cell finds a volume of about {}: the model's \
             features are smaller than a cell; use a finer --resolution (or --resolution auto)",
            opts.resolution,
            sig(v.value)
        );
    }
    if plan.thin_cells() > 0 {
        return format!(
            "the mesh is empty at resolution {} (cells of {h}); interval analysis found {} \
             cells that may hold features thinner than a cell: use a finer --resolution",
            opts.resolution,
            plan.thin_cells()
        );
    }
    format!(
        "the mesh is empty: no sample of the {} grid (cells of {h}) is inside the model in \
         the box {b}; the part is smaller than a cell or outside the box",
        opts.resolution
    )
}

/// Refuses a model whose f32 values disagree with its f64 values in the
/// box (see [`microfrep_io::precision::check_agreement`]).
pub fn check_precision(shape: &Shape, bounds: [[f64; 3]; 2]) -> Result<(), MeshError> {
    use microfrep_io::precision::{check_agreement, probe_points, PROBE_POINTS};
    let pts = probe_points(bounds[0], bounds[1], PROBE_POINTS);
    let axis = |a: usize| -> Vec<f32> { pts.iter().map(|p| p[a] as f32).collect() };
    let mut v32 = vec![0.0f32; pts.len()];
    shape.batch().eval(&axis(0), &axis(1), &axis(2), &mut v32);
    let mut pe = shape.point();
    let v64: Vec<f64> = pts.iter().map(|p| pe.eval(*p)).collect();
    check_agreement(&pts, &v32, &v64).map_err(|e| MeshError::Input(format!("cannot mesh: {e}")))
}

/// Refuses a job predicted to need more memory than `avail`, or more
/// vertices than 32-bit indices hold; the message names the largest
/// resolution that would fit both.
fn check_size(
    opts: &MeshOptions,
    est: &Estimate,
    streamed: bool,
    avail: Option<f64>,
    streams: bool,
) -> Result<(), MeshError> {
    let n = opts.resolution;
    let predict = |m: usize| -> (f64, f64) {
        // Surface (triangles, vertices) grows with the square of the
        // resolution, the brick table with its cube.
        let r = m as f64 / n as f64;
        let e = Estimate {
            triangles: est.triangles * r * r,
            vertices: est.vertices * r * r,
            bytes: (est.bytes - est.volume_bytes) * r * r + est.volume_bytes * r * r * r,
            volume_bytes: est.volume_bytes * r * r * r,
        };
        let bytes = match Grid::new(opts.bounds, m.max(1), opts.brick) {
            Ok(g) if streamed => memory::streaming_bytes_grid(&g, &e),
            _ => e.bytes,
        };
        (bytes, e.vertices)
    };
    let ok = |m: usize| {
        let (b, v) = predict(m);
        v <= u32::MAX as f64 && avail.is_none_or(|a| b <= a)
    };
    if ok(n) {
        return Ok(());
    }
    // The predictions grow with the resolution: bisect for the largest
    // that fits.
    let (mut lo, mut hi) = (0usize, n);
    while hi - lo > 1 {
        let mid = lo + (hi - lo) / 2;
        if ok(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let fit = if lo == 0 {
        "no resolution would fit".to_string()
    } else {
        format!("resolution {lo} would fit")
    };
    let (bytes, vertices) = predict(n);
    if vertices > u32::MAX as f64 {
        return Err(MeshError::TooLarge(format!(
            "meshing at resolution {n} would make about {vertices:.2e} vertices, more than \
             32-bit indices hold ({}); {fit}",
            u32::MAX
        )));
    }
    let hint = if streams {
        ""
    } else {
        " (or write .stl or .ply, which are streamed to disk)"
    };
    Err(MeshError::TooLarge(format!(
        "meshing at resolution {n} needs about {:.1} GiB but {:.1} GiB are available; \
         {fit}{hint}",
        bytes / GIB,
        avail.unwrap_or(0.0) / GIB,
    )))
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

/// A sink that keeps nothing: meshing for the tally alone.
struct Discard;

impl MeshSink for Discard {
    fn vertices(&mut self, _: &[[f32; 3]]) -> Result<(), MeshError> {
        Ok(())
    }
    fn triangles(&mut self, _: &[[u32; 3]], _: &VertexWindow) -> Result<(), MeshError> {
        Ok(())
    }
}

/// The search of [`JobOptions::auto`]: the chosen resolution, and its mesh
/// if it was held in memory.
fn choose_resolution(
    shape: &Shape,
    opts: &MeshOptions,
    auto: &AutoOptions,
    avail: Option<f64>,
    trials: &mut Vec<Trial>,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<(usize, Option<Mesh>), MeshError> {
    let max = auto.max.min(crate::grid::MAX_CELLS - 3);
    let mut n = auto.start.clamp(2, max);
    let mut best: Option<(usize, Option<Mesh>)> = None;
    loop {
        let t0 = Instant::now();
        let mut o = opts.clone();
        o.resolution = n;
        let (tape, grid) = Plan::frame(shape, &o)?;
        let est = memory::estimate_grid(&tape, &grid, o.cells);
        let fits = |b: f64| avail.is_none_or(|m| b <= m);
        let tally_bytes = memory::streaming_bytes_grid(&grid, &est);
        if !fits(tally_bytes) || est.vertices > u32::MAX as f64 {
            // The next step does not fit: stay at the last one.
            if let Some(b) = best {
                return Ok(b);
            }
            check_size(&o, &est, true, avail, true)?;
        }
        let plan = Plan::classified(tape, grid, &o)?;
        let sampled = sampled_volume(&plan);
        let total = plan.surface_bricks();
        let step = |d: usize| progress(d, total);
        let (volume, mesh) = if fits(est.bytes) {
            let m = plan.run(&step)?;
            (crate::check::volume_area(&m).0, Some(m))
        } else {
            let mut discard = Discard;
            let mut t = Tallying {
                inner: &mut discard,
                tally: Tally::default(),
            };
            plan.run_into(&mut t, &step)?;
            (t.tally.volume, None)
        };
        let prev = trials.last().map(|t: &Trial| t.mesh_volume);
        trials.push(Trial {
            resolution: n,
            mesh_volume: volume,
            sampled,
            seconds: t0.elapsed().as_secs_f64(),
        });
        best = Some((n, mesh));
        let v = sampled.value;
        let done = if v <= 0.0 {
            // Nothing to resolve (the empty mesh is reported later).
            volume <= 0.0
        } else {
            // The difference, with the sampling's uncertainty, within the
            // tolerance; and the mesh's volume settled since the last step.
            let agrees = (v - volume).abs() + 2.0 * sampled.error <= auto.tolerance * v;
            let settled = prev.is_some_and(|p| ((volume - p) / v).abs() <= 2.0 * auto.tolerance);
            agrees && settled
        };
        if done || n >= max {
            return Ok(best.expect("set above"));
        }
        n = ((n as f64 * 1.5).ceil() as usize).min(max);
    }
}
