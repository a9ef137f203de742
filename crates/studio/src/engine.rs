//! Every call the studio makes into the other microfrep crates, in one
//! place: loading HyperFun, bounds, meshing, analysis, sections, renders,
//! slice stacks and STL. The rest of the crate sees only the plain types
//! defined here, so a change of those crates' APIs is a change of this file.
//!
//! Long calls take `check: &(dyn Fn() + Sync)`, called between units of work
//! (a brick, a layer, a slab). The caller's `check` unwinds (with
//! [`std::panic::resume_unwind`]) to stop a stale or over-long job; nothing
//! here catches that unwind.

use microfrep_analysis::AnalyzeOptions;
use microfrep_core::shape::BoundsOptions;
use microfrep_core::{BatchEval, Field, Interval, PointEval, Shape};
use microfrep_hyperfun::{Diagnostic, Severity};
use microfrep_mesh::{memory, MeshOptions, Plan};
use rayon::prelude::*;
use serde_json::Value;
use std::collections::BTreeMap;
use std::io::Cursor;
use std::path::Path;
use std::sync::Arc;

/// Why an engine call failed: a message for the page.
#[derive(Debug, thiserror::Error)]
pub enum EngineError {
    /// The job is bigger than the limits allow (memory, evaluation cost).
    #[error("{0}")]
    Limit(String),
    /// Meshing failed.
    #[error("meshing: {0}")]
    Mesh(#[from] microfrep_mesh::MeshError),
    /// Analysis failed.
    #[error("analysis: {0}")]
    Analysis(#[from] microfrep_analysis::AnalysisError),
    /// Slicing failed.
    #[error("slicing: {0}")]
    Fab(#[from] microfrep_fab::FabError),
    /// Rendering failed.
    #[error("rendering: {0}")]
    Render(#[from] microfrep_render::RenderError),
    /// The model's bounds could not be found.
    #[error("{0}")]
    Bounds(#[from] microfrep_core::BoundsError),
    /// A data field (a mesh, scan or CSV part) could not be read or built.
    #[error("{0}")]
    Part(#[from] microfrep::LoadError),
    /// Encoding an output in memory failed.
    #[error("encoding {what}")]
    Encode {
        /// What was being encoded.
        what: &'static str,
        /// The writer's error.
        source: std::io::Error,
    },
}

/// One diagnostic of a model, as `microfrep check` reports it.
#[derive(Clone, Debug, PartialEq)]
pub struct Diag {
    /// True for an error, false for a warning.
    pub error: bool,
    /// 1-based line (0 when the message has no position).
    pub line: u32,
    /// 1-based column (0 when the message has no position).
    pub col: u32,
    /// The message.
    pub message: String,
}

/// A model that lowered: the shape every job takes and what the page shows.
#[derive(Clone, Debug)]
pub struct Loaded {
    /// The compiled model.
    pub shape: Shape,
    /// The evaluated object.
    pub object: String,
    /// All objects of the file, in order.
    pub objects: Vec<String>,
    /// `a[k]` parameters as (graph name `a1`, value).
    pub params: Vec<(String, f64)>,
    /// Whether the model lowered to the graph (false: evaluated per point).
    pub lowered: bool,
    /// Names of the shape's attribute channels.
    pub attributes: Vec<String>,
}

/// The result of [`load`]: the model (if it lowered) and every diagnostic,
/// also rendered as `check` prints them.
#[derive(Debug)]
pub struct LoadResult {
    /// The model, when there was no error.
    pub model: Option<Loaded>,
    /// Errors and warnings in source order.
    pub diags: Vec<Diag>,
    /// `file:line:col: severity: message`, the line and a caret, per item.
    pub rendered: String,
}

fn diag_of(d: &Diagnostic) -> Diag {
    Diag {
        error: d.severity == Severity::Error,
        line: d.pos.line,
        col: d.pos.col,
        message: d.message.clone(),
    }
}

/// Checks and lowers object `object` (default `my_model`, else the first)
/// of `src` with `a[1..] = params` and the data `fields` callable as
/// `NAME(x)`, through the facade's [`microfrep::load::check_source`]: the
/// diagnostics of `microfrep check` (every object lowered, so errors
/// anywhere are found), and the model, still returned when only other
/// objects fail.
pub fn load(
    src: &str,
    file: &str,
    object: Option<&str>,
    params: &[f64],
    fields: &[(String, Arc<dyn Field>)],
) -> LoadResult {
    let opts = microfrep_hyperfun::LoadOptions {
        object: object.map(str::to_string),
        params: params
            .iter()
            .enumerate()
            .map(|(k, &v)| (k + 1, v))
            .collect(),
        fields: fields.to_vec(),
    };
    let c = microfrep::load::check_source(src, file, &opts);
    let mut diags: Vec<Diag> = c.diagnostics.items.iter().map(diag_of).collect();
    diags.extend(c.unlocated.iter().map(|m| Diag {
        error: true,
        line: 0,
        col: 0,
        message: m.clone(),
    }));
    let model = c.model.map(|m| {
        let shape = m.shape();
        Loaded {
            attributes: shape.attributes().iter().map(|a| a.name.clone()).collect(),
            shape,
            object: m.object,
            objects: m.objects,
            params: m.params,
            lowered: m.lowered,
        }
    });
    LoadResult {
        model,
        diags,
        rendered: c.rendered,
    }
}

/// The model's proven bounds (interval subdivision), with `check` called
/// as the search goes.
pub fn prove_bounds(
    shape: &Shape,
    check: Arc<dyn Fn() + Send + Sync>,
) -> Result<[[f64; 3]; 2], EngineError> {
    let opts = BoundsOptions {
        progress: Some(Arc::new(move |_| check())),
        ..BoundsOptions::default()
    };
    Ok(shape.bounds_with(&opts)?.corners())
}

/// A data field read from a file under the working directory (a mesh or
/// scan part, or measured data), which models call by name.
pub struct Part {
    /// The field: positive inside, distances in the file's units for meshes
    /// and scans.
    pub field: Arc<dyn Field>,
    /// A box holding the field's solid.
    pub bounds: [[f64; 3]; 2],
    /// `mesh`, `scan` or `data`.
    pub kind: &'static str,
    /// Warnings (an open mesh, a repaired orientation, ...).
    pub notes: Vec<String>,
    /// Seconds reading and building took.
    pub seconds: f64,
}

/// Reads `path` (already resolved) with the source options `options`
/// (`weld=`, `iso=`, ... as after the colon of `FILE:key=value`) and builds
/// its field with the loader every microfrep verb uses
/// ([`microfrep::load::field`]). `progress(stage, done, total)` is called
/// as the build goes.
pub fn build_part(
    path: &Path,
    options: BTreeMap<String, String>,
    memory_limit: u64,
    progress: &(dyn Fn(&str, u64, u64) + Sync),
) -> Result<Part, EngineError> {
    use microfrep::load::{self as ld, SourceKind};
    let t = std::time::Instant::now();
    let src = ld::Source {
        path: path.to_string_lossy().into_owned(),
        options,
    };
    let kind = match ld::kind_of(path) {
        Some(SourceKind::Mesh) => ("mesh", SourceKind::Mesh),
        Some(SourceKind::Scan) => ("scan", SourceKind::Scan),
        Some(SourceKind::Data) => ("data", SourceKind::Data),
        _ => {
            return Err(EngineError::Limit(format!(
                "{}: a field is a mesh (.stl .obj .ply .3mf), a scan (.nrrd .nii .tif, a DICOM \
                 or TIFF folder, .raw) or data (.csv)",
                path.display()
            )))
        }
    };
    let f = ld::field(&src, kind.1, memory_limit, progress)?;
    Ok(Part {
        field: f.field,
        bounds: f.bounds.corners(),
        kind: kind.0,
        notes: f.notes,
        seconds: t.elapsed().as_secs_f64(),
    })
}

/// Whether intervals prove the model empty (`f < 0`) everywhere outside
/// `inner` within the cube `|x|, |y|, |z| < 1e6` that bounds searches
/// start from: then `inner` is a sound box for it (a part's box, when the
/// part bounds the model). The 26 boxes around `inner` are split in halves
/// along their longest side until each piece is decided, at most `budget`
/// interval evaluations; false when the budget runs out or some piece may
/// hold solid. `check` is called every 256 evaluations.
pub fn empty_outside(
    shape: &Shape,
    inner: [[f64; 3]; 2],
    budget: usize,
    check: &(dyn Fn() + Sync),
) -> bool {
    const FAR: f64 = 1e6;
    if (0..3).any(|a| !(inner[0][a] > -FAR && inner[1][a] < FAR && inner[0][a] < inner[1][a])) {
        return false;
    }
    let cuts = |a: usize| [-FAR, inner[0][a], inner[1][a], FAR];
    let mut todo: Vec<[[f64; 3]; 2]> = Vec::new();
    for k in 0..27 {
        let c = [k % 3, k / 3 % 3, k / 9];
        if c == [1, 1, 1] {
            continue;
        }
        todo.push([
            std::array::from_fn(|a| cuts(a)[c[a]]),
            std::array::from_fn(|a| cuts(a)[c[a] + 1]),
        ]);
    }
    let mut ev = shape.interval();
    let mut pe = shape.point();
    let mut evals = 0;
    while let Some(b) = todo.pop() {
        if evals >= budget {
            return false;
        }
        evals += 1;
        if evals % 256 == 0 {
            check();
        }
        let iv = |a: usize| Interval::new(b[0][a], b[1][a]);
        let r = ev.eval(iv(0), iv(1), iv(2));
        if !(r.is_nan() || r.hi >= 0.0) {
            continue;
        }
        // Solid at the centre: the model reaches out of `inner`.
        if pe.eval(std::array::from_fn(|a| 0.5 * (b[0][a] + b[1][a]))) >= 0.0 {
            return false;
        }
        let a = (0..3)
            .max_by(|&i, &j| (b[1][i] - b[0][i]).total_cmp(&(b[1][j] - b[0][j])))
            .unwrap_or(0);
        let mid = 0.5 * (b[0][a] + b[1][a]);
        if !(mid > b[0][a] && mid < b[1][a]) {
            return false;
        }
        let (mut lo, mut hi) = (b, b);
        lo[1][a] = mid;
        hi[0][a] = mid;
        todo.push(lo);
        todo.push(hi);
    }
    true
}

/// What evaluating the model at a few points showed.
#[derive(Clone, Debug, Default)]
pub struct Probe {
    /// Points evaluated.
    pub points: usize,
    /// Seconds per point of the f64 point evaluator.
    pub seconds_per_point: f64,
    /// Run-time errors seen: (message, line, col, count), most frequent first.
    pub errors: Vec<(String, u32, u32, usize)>,
}

/// Evaluates value and error code at up to `n^3` points spread over the
/// box, stopping early once `budget_s` seconds are spent or `stop()` is
/// true (checked between points).
pub fn probe(
    shape: &Shape,
    bounds: [[f64; 3]; 2],
    n: usize,
    budget_s: f64,
    stop: &dyn Fn() -> bool,
) -> Probe {
    let tape = shape.outputs();
    let mut pe = PointEval::new(tape);
    let t = std::time::Instant::now();
    let mut sites: Vec<(String, u32, u32, usize)> = Vec::new();
    let mut points = 0;
    let at = |a: usize, i: usize| {
        let f = (i as f64 + 0.5) / n as f64;
        bounds[0][a] + f * (bounds[1][a] - bounds[0][a])
    };
    'outer: for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                if stop() || (points > 0 && t.elapsed().as_secs_f64() > budget_s) {
                    break 'outer;
                }
                let out = pe.eval_all([at(0, i), at(1, j), at(2, k)]);
                points += 1;
                let code = shape.error_output().map_or(0.0, |e| out[e]);
                if let Some(e) = shape.runtime_error(code) {
                    match sites
                        .iter_mut()
                        .find(|s| s.0 == e.message && s.1 == e.line && s.2 == e.col)
                    {
                        Some(s) => s.3 += 1,
                        None => sites.push((e.message, e.line, e.col, 1)),
                    }
                }
            }
        }
    }
    sites.sort_by_key(|s| std::cmp::Reverse(s.3));
    Probe {
        points,
        seconds_per_point: t.elapsed().as_secs_f64() / points.max(1) as f64,
        errors: sites,
    }
}

/// A mesh ready for the page: positions, outward unit normals, per-vertex
/// attribute values and counter-clockwise triangles.
#[derive(Clone, Debug, Default)]
pub struct MeshData {
    /// Cells on the longest side it was made with.
    pub resolution: usize,
    /// Vertex positions.
    pub vertices: Vec<[f32; 3]>,
    /// Unit outward normals (zero where the gradient vanishes).
    pub normals: Vec<[f32; 3]>,
    /// Per attribute channel, its value at each vertex.
    pub attributes: Vec<Vec<f32>>,
    /// Triangles, counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
    /// Why the resolution is lower than asked, if it is.
    pub note: Option<String>,
}

/// Meshes the model in `bounds` at `resolution` cells on the longest side;
/// above 64 cells the peak memory is predicted first
/// ([`microfrep_mesh::memory::estimate`]) and the resolution lowered to fit
/// `memory_limit` bytes. `check` is called after every brick.
pub fn mesh(
    shape: &Shape,
    bounds: [[f64; 3]; 2],
    resolution: usize,
    memory_limit: f64,
    check: &(dyn Fn() + Sync),
) -> Result<MeshData, EngineError> {
    let mut opts = MeshOptions::new(bounds, resolution);
    // Small bricks: a stale job stops sooner. The classification of the
    // bricks before the first check takes time in proportion to their
    // number, so fine resolutions take larger ones: about 32 a side at
    // most (e.g. a 60-term model at 1000 cells: 0.4 s instead of 3.4 s
    // with 16-cell bricks), so an export whose client left stops soon.
    opts.brick = brick_for(resolution);
    let mut plan = Plan::new(shape, &opts)?;
    check();
    let mut note = None;
    // At 64 cells or fewer the mesh is small whatever the model (at most a
    // few tens of MB), so the estimate's sampling is not worth its time.
    if resolution > 64 {
        let e = memory::estimate(&plan);
        if e.bytes > memory_limit {
            let fit = memory::resolution_fitting(&e, resolution, memory_limit);
            if fit < 8 {
                return Err(EngineError::Limit(format!(
                    "meshing at {resolution} cells would need about {:.0} MiB, over the \
                     limit of {:.0} MiB",
                    e.bytes / MIB,
                    memory_limit / MIB
                )));
            }
            note = Some(format!(
                "resolution lowered from {resolution} to {fit}: {resolution} would need about \
                 {:.0} MiB (limit {:.0} MiB)",
                e.bytes / MIB,
                memory_limit / MIB
            ));
            opts.resolution = fit;
            plan = Plan::new(shape, &opts)?;
        }
    }
    check();
    let m = plan.run(&|_| check())?;
    check();
    let normals = plan.normals(&m);
    check();
    let attributes = attribute_values(shape, &m.vertices);
    Ok(MeshData {
        resolution: opts.resolution,
        vertices: m.vertices,
        normals,
        attributes,
        triangles: m.triangles,
        note,
    })
}

/// Brick size (cells a side) for meshing at `resolution`: 16, up to 64
/// so that there are at most about 32 bricks a side.
pub(crate) fn brick_for(resolution: usize) -> usize {
    resolution.div_ceil(32).clamp(16, 64)
}

/// Each attribute channel of the shape evaluated at `points`.
pub fn attribute_values(shape: &Shape, points: &[[f32; 3]]) -> Vec<Vec<f32>> {
    let tape = shape.outputs();
    (0..shape.attributes().len())
        .map(|k| {
            let out = shape.attribute_output(k);
            let mut vals = vec![0f32; points.len()];
            vals.par_chunks_mut(4096)
                .zip(points.par_chunks(4096))
                .for_each_init(
                    || BatchEval::new(tape),
                    |ev, (dst, src)| {
                        let x: Vec<f32> = src.iter().map(|p| p[0]).collect();
                        let y: Vec<f32> = src.iter().map(|p| p[1]).collect();
                        let z: Vec<f32> = src.iter().map(|p| p[2]).collect();
                        ev.eval_output(out, &x, &y, &z, dst);
                    },
                );
            vals
        })
        .collect()
}

/// Binary STL of a mesh, in memory.
pub fn stl_bytes(mesh: &MeshData) -> Result<Vec<u8>, EngineError> {
    let enc = |source| EngineError::Encode {
        what: "STL",
        source,
    };
    let mut w = microfrep_mesh::write::StlWriter::new(Cursor::new(Vec::new())).map_err(enc)?;
    for t in &mesh.triangles {
        w.push(t.map(|i| mesh.vertices[i as usize])).map_err(enc)?;
    }
    Ok(w.finish().map_err(enc)?.into_inner())
}

/// Watertightness of a mesh: (closed 2-manifold, Euler characteristic).
pub fn mesh_check(mesh: &MeshData) -> (bool, i64) {
    let m = microfrep_mesh::Mesh {
        vertices: mesh.vertices.clone(),
        triangles: mesh.triangles.clone(),
    };
    let r = microfrep_mesh::check::check(&m);
    (r.is_closed_manifold(), r.euler)
}

/// Volume fraction, porosity, area, connectivity and percolation of the
/// model in `bounds` on a grid of `resolution` voxels on the longest side,
/// as the JSON of `microfrep analyze --json --no-thickness` (same keys).
/// `check` is called per brick and per layer.
pub fn analyze(
    shape: &Shape,
    bounds: [[f64; 3]; 2],
    resolution: usize,
    memory_limit: u64,
    check: &(dyn Fn() + Sync),
) -> Result<Value, EngineError> {
    let grid = microfrep_analysis::Grid::new(bounds, resolution)?;
    let opts = AnalyzeOptions {
        connectivity: true,
        thickness: false,
        memory_limit,
        ..AnalyzeOptions::default()
    };
    let r = microfrep_analysis::analyze(shape, None, grid, &opts, &|_, _, _| check())?;
    // The keys of `microfrep analyze --json`, as every host reports them.
    Ok(microfrep_analysis::summary::to_json(&r, "studio", None))
}

/// The model's value on the plane `axis = value` across the box, as a PNG
/// (blue outside, white at zero, red inside, the zero contour black).
pub fn section_png(
    shape: &Shape,
    axis: usize,
    value: f64,
    bounds: [[f64; 3]; 2],
    width: usize,
    height: usize,
) -> Result<Vec<u8>, EngineError> {
    microfrep_render::camera::check_size(width, height)?;
    let plane = microfrep_render::Plane { axis, value };
    let img = microfrep_render::section(shape, plane, bounds[0], bounds[1], width, height);
    img.encode_png().map_err(|e| EngineError::Encode {
        what: "PNG",
        source: std::io::Error::other(e),
    })
}

/// A ray-cast image of the model from `view` (`iso`, `front`, `top`,
/// `side`), optionally cut away, as a PNG: the page's view where the
/// browser has no WebGL.
pub fn render_png(
    shape: &Shape,
    view: &str,
    cutaway: bool,
    bounds: [[f64; 3]; 2],
    width: usize,
    height: usize,
) -> Result<Vec<u8>, EngineError> {
    microfrep_render::camera::check_size(width, height)?;
    let view: microfrep_render::View = view.parse()?;
    let cut;
    let shape = if cutaway {
        cut = microfrep_render::cutaway(shape, view, bounds[0], bounds[1]);
        &cut
    } else {
        shape
    };
    let cam = microfrep_render::Camera::fit(view, bounds[0], bounds[1], width, height);
    let img = microfrep_render::ray_cast(shape, &cam, bounds[0], bounds[1]);
    img.encode_png().map_err(|e| EngineError::Encode {
        what: "PNG",
        source: std::io::Error::other(e),
    })
}

/// Slice stack formats the studio offers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SliceFormat {
    /// 1-bit PNG per layer.
    Png,
    /// 8-bit area-coverage PNG per layer.
    PngAa,
    /// SVG contours per layer.
    Svg,
    /// One Common Layer Interface file.
    Cli,
}

/// Layers and pixels of a slice stack of the box, without slicing:
/// `(nx, ny, layers)`, or the slicer's error for bad steps.
pub fn slice_dims(
    bounds: [[f64; 3]; 2],
    layer: f64,
    pixel: f64,
) -> Result<(usize, usize, usize), EngineError> {
    let g = microfrep_fab::SliceGrid::new(bounds[0], bounds[1], layer, pixel)?;
    Ok((g.nx, g.ny, g.layers))
}

/// Slices the model in `bounds` into `out` (which must not exist): a
/// directory of layer files with `manifest.json`, or one `.cli` file.
/// `check` is called after every layer.
pub fn write_slices(
    shape: &Shape,
    bounds: [[f64; 3]; 2],
    layer: f64,
    pixel: f64,
    format: SliceFormat,
    out: &Path,
    check: &(dyn Fn() + Sync),
) -> Result<(), EngineError> {
    let grid = microfrep_fab::SliceGrid::new(bounds[0], bounds[1], layer, pixel)?;
    let format = match format {
        SliceFormat::Png => microfrep_fab::Format::Png { aa: false },
        SliceFormat::PngAa => microfrep_fab::Format::Png { aa: true },
        SliceFormat::Svg => microfrep_fab::Format::Svg,
        SliceFormat::Cli => microfrep_fab::Format::Cli,
    };
    microfrep_fab::write_stack(shape, &grid, &format, out, check)?;
    Ok(())
}

/// Bytes the system reports available (`MemAvailable`), if known.
pub fn memory_available() -> Option<f64> {
    microfrep_io::limits::memory_limit()
}

const MIB: f64 = 1024.0 * 1024.0;

#[cfg(test)]
mod tests {
    use super::*;
    use microfrep_core::Expr;
    use microfrep_shapes as prims;

    #[test]
    fn attribute_channels_are_evaluated_at_the_vertices() {
        let p = Expr::xyz();
        let ball = prims::sphere(&p, &prims::v3([0.0; 3]), 0.7);
        // Two channels: height, and squared distance from the z axis.
        let shape = Shape::new(ball)
            .with_attribute("height", p[2].clone())
            .with_attribute("r2", p[0].square() + p[1].square());
        let m = mesh(&shape, [[-1.0; 3], [1.0; 3]], 24, 1e9, &|| {}).unwrap();
        assert_eq!(m.attributes.len(), 2);
        assert!(!m.vertices.is_empty());
        for (i, v) in m.vertices.iter().enumerate() {
            assert!((m.attributes[0][i] - v[2]).abs() < 1e-6);
            assert!((m.attributes[1][i] - (v[0] * v[0] + v[1] * v[1])).abs() < 1e-5);
        }
        let (closed, euler) = mesh_check(&m);
        assert!(closed && euler == 2);
        let stl = stl_bytes(&m).unwrap();
        assert_eq!(stl.len(), 84 + 50 * m.triangles.len());
    }

    #[test]
    fn part_boxes_are_checked_by_intervals() {
        let p = Expr::xyz();
        let ball = Shape::new(prims::sphere(&p, &prims::v3([0.0; 3]), 0.5));
        assert!(empty_outside(&ball, [[-0.6; 3], [0.6; 3]], 10_000, &|| {}));
        // The ball reaches out of a smaller box, or one beside it.
        assert!(!empty_outside(&ball, [[-0.4; 3], [0.4; 3]], 10_000, &|| {}));
        assert!(!empty_outside(&ball, [[0.1; 3], [2.0; 3]], 10_000, &|| {}));
        // Out of budget: not proven.
        assert!(!empty_outside(&ball, [[-0.6; 3], [0.6; 3]], 3, &|| {}));
        // A lattice is everywhere.
        let wave = Shape::new(p[0].clone().sin());
        assert!(!empty_outside(&wave, [[-0.6; 3], [0.6; 3]], 10_000, &|| {}));
    }

    #[test]
    fn a_mesh_file_becomes_a_part_that_models_call() {
        // The cube [0, 2]^3, outward-facing.
        let v = [
            [0.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [2.0, 2.0, 0.0],
            [0.0, 2.0, 0.0],
            [0.0, 0.0, 2.0],
            [2.0, 0.0, 2.0],
            [2.0, 2.0, 2.0],
            [0.0, 2.0, 2.0],
        ];
        let t = [
            [0, 2, 1],
            [0, 3, 2],
            [4, 5, 6],
            [4, 6, 7],
            [0, 1, 5],
            [0, 5, 4],
            [3, 7, 6],
            [3, 6, 2],
            [0, 4, 7],
            [0, 7, 3],
            [1, 2, 6],
            [1, 6, 5],
        ];
        let m = MeshData {
            vertices: v.to_vec(),
            triangles: t.to_vec(),
            ..MeshData::default()
        };
        let dir = std::env::temp_dir().join(format!("mf-studio-part-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("cube.stl");
        std::fs::write(&path, stl_bytes(&m).unwrap()).unwrap();
        let part = build_part(&path, BTreeMap::new(), 1 << 30, &|_, _, _| {}).unwrap();
        assert_eq!(part.kind, "mesh");
        for a in 0..3 {
            assert!(part.bounds[0][a] < 0.0 && part.bounds[0][a] > -0.01);
            assert!(part.bounds[1][a] > 2.0 && part.bounds[1][a] < 2.01);
        }
        assert!((part.field.eval([1.0, 1.0, 1.0]) - 1.0).abs() < 1e-9);
        assert!((part.field.eval([1.0, 1.0, 3.0]) + 1.0).abs() < 1e-9);
        let src = "my_model(x[3], a[1]) { my_model = cube(x) - 0.5; }";
        let fields = vec![("cube".to_string(), part.field.clone())];
        let r = load(src, "t.hf", None, &[], &fields);
        assert!(r.diags.is_empty(), "{}", r.rendered);
        let shape = r.model.unwrap().shape;
        assert!((shape.point().eval([1.0, 1.0, 1.0]) - 0.5).abs() < 1e-9);
        // The cube's box, padded, holds the model; unbound, `cube` is unknown.
        assert!(empty_outside(&shape, [[-0.1; 3], [2.1; 3]], 50_000, &|| {}));
        let r = load(src, "t.hf", None, &[], &[]);
        assert!(
            r.rendered.contains("'cube' is not a known function"),
            "{}",
            r.rendered
        );
        // Not a data source.
        let hf = dir.join("m.hf");
        std::fs::write(&hf, src).unwrap();
        assert!(build_part(&hf, BTreeMap::new(), 1 << 30, &|_, _, _| {}).is_err());
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn diagnostics_match_check() {
        let src = "my_model(x[3], a[1]) {\n  my_model = 1 - ;\n}\nother(x[3], a[1]) {\n  other = zz(x);\n}\n";
        let r = load(src, "t.hf", None, &[], &[]);
        assert!(r.model.is_none());
        assert_eq!(r.diags[0].line, 2);
        assert!(r.diags[0].error);
        assert!(r.rendered.starts_with("t.hf:2:"), "{}", r.rendered);
        // The evaluated object is fine, another object is not: the error is
        // reported and the model still shown.
        let src = "my_model(x[3], a[1]) {\n  my_model = 1 - x[1];\n}\nother(x[3], a[1]) {\n  other = mfTpms(x, 9, 0, 1, 0);\n}\n";
        let r = load(src, "t.hf", None, &[], &[]);
        assert!(
            r.diags.iter().any(|d| d.error && d.line == 5),
            "{:?}",
            r.diags
        );
        assert_eq!(r.model.unwrap().object, "my_model");
        let r = load(src, "t.hf", Some("other"), &[], &[]);
        assert!(r.model.is_none());
        let ok = load(
            "my_model(x[3], a[2]) { my_model = a[1] - x[1]; }",
            "t.hf",
            None,
            &[0.5],
            &[],
        );
        let m = ok.model.unwrap();
        assert_eq!(
            m.params,
            vec![("a1".to_string(), 0.5), ("a2".to_string(), 0.0)]
        );
        assert!(m.attributes.is_empty());
        assert_eq!(m.shape.point().eval([0.25, 0.0, 0.0]), 0.25);
    }
}
