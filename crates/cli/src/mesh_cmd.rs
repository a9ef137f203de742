//! `microfrep mesh`: triangle mesh of a model to STL, OBJ, PLY or 3MF
//! (with `--implicit`, `--volumetric`, `--palette`: the 3MF volumetric and
//! implicit extensions, see [`VolumeArgs`]).

use crate::common::{check_terminates, frame, load_model, probe_terminates, ModelArgs, RunArgs};
use anyhow::{bail, Result};
use clap::Args;
use microfrep::export::{VolumeOptions, VolumeReport};
use microfrep::mesh::job::{mesh_to_file, AutoOptions, JobOptions, Tolerance};
use microfrep::mesh::report;
use microfrep::mesh::write::colour::ColourBy;
use microfrep::mesh::{CellMethod, Grid, MeshOptions};
use std::path::PathBuf;
use std::time::Instant;

#[derive(Args)]
pub struct MeshArgs {
    #[command(flatten)]
    model: ModelArgs,
    /// Output file; the format follows the extension (.stl, .obj, .ply, .3mf).
    #[arg(short, long)]
    output: PathBuf,
    /// Cells along the longest side of the box (default 256), or `auto`:
    /// the coarsest (from 32 up by 1.5) whose mesh keeps the model's volume
    /// within 0.5 %.
    #[arg(long, conflicts_with = "voxel", value_parser = parse_resolution)]
    resolution: Option<Resolution>,
    /// Cell size in model units (millimetres).
    #[arg(long)]
    voxel: Option<f64>,
    /// Write STL or PLY while meshing, never holding the whole mesh (done
    /// anyway when the mesh would not fit in memory); skips the edge check.
    #[arg(long)]
    stream: bool,
    /// Fail (writing nothing) when the mesh has more than PCT % less
    /// volume than the model sampled in every cell: thin features lost.
    #[arg(long, value_name = "PCT", default_value_t = 5.0)]
    max_volume_loss: f64,
    /// Leave every vertex on the surface: no chordal volume correction.
    #[arg(long)]
    no_volume_correction: bool,
    /// Cell method: cubes (default; about a third of the triangles, faster)
    /// or tets (marching tetrahedra: sharp creases cut less).
    #[arg(long, value_enum, default_value_t = Cells::Cubes)]
    cells: Cells,
    /// Keep creases and corners (CAD parts, CSG): where the normals in a
    /// cell spread, a vertex where the tangent planes meet; flat faces stay
    /// flat. On a box in general position, creases, corners and faces come
    /// within 0.015 cells; creases with a curved side come within a few
    /// hundredths of a cell, and strongly curved lattices mesh about 3x
    /// slower (their cells look like creases). With --cells cubes only.
    #[arg(long)]
    sharp: bool,
    /// Merge flat regions and straight creases into fewer, larger
    /// triangles while every triangle stays within this distance of the
    /// surface, checked against the model at points no farther apart than
    /// a cell: in cells (0.05), or in millimetres with a unit (0.01mm).
    /// Off by default: curved lattices have nearly nothing flat to merge,
    /// and the mesh must be held in memory. Best with --sharp (CAD parts).
    #[arg(long, value_name = "T", value_parser = parse_tolerance, allow_hyphen_values = true)]
    tolerance: Option<Tolerance>,
    /// Write a strut lattice model (mfStruts at the plain point, constant
    /// cell and radius, alone or `&` a part) to .3mf as triangles instead
    /// of a beam lattice (implied by --color-by and the volumetric options).
    #[arg(long)]
    triangles: bool,
    #[command(flatten)]
    volume: VolumeArgs,
    /// Vertex colours from an attribute (.ply, .obj, .3mf; not .stl).
    #[command(flatten)]
    colour: crate::render_cmd::ColourArgs,
    #[command(flatten)]
    run: RunArgs,
}

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
enum Cells {
    Cubes,
    Tets,
}

#[derive(Clone, Copy, Debug)]
enum Resolution {
    Cells(usize),
    Auto,
}

fn parse_tolerance(s: &str) -> Result<Tolerance, String> {
    let (num, unit) = match s.strip_suffix("mm") {
        Some(n) => (n, Tolerance::Units as fn(f64) -> Tolerance),
        None => (s, Tolerance::Cells as fn(f64) -> Tolerance),
    };
    match num.trim().parse::<f64>() {
        Ok(v) if v > 0.0 && v.is_finite() => Ok(unit(v)),
        _ => Err(format!(
            "'{s}' is not a positive distance in cells (0.05) or millimetres (0.01mm)"
        )),
    }
}

fn parse_resolution(s: &str) -> Result<Resolution, String> {
    match s {
        "auto" => Ok(Resolution::Auto),
        _ => s
            .parse()
            .map(Resolution::Cells)
            .map_err(|_| format!("'{s}' is not a cell count or 'auto'")),
    }
}

pub fn run(a: MeshArgs) -> Result<()> {
    let start = Instant::now();
    a.run.init()?;
    microfrep::mesh::write::format_of(&a.output)?;
    let volume = a.volume.options(&a.output)?;
    let m = load_model(&a.model, &a.run)?;
    let bounds = frame(&m, &a.model, &a.run)?;
    let b = bounds.corners();
    if let Some(v) = &volume {
        v.check(&m.shape, bounds)?;
    }
    probe_terminates(&m, b)?;
    let (resolution, auto) = match (a.resolution, a.voxel) {
        (Some(Resolution::Cells(n)), _) => (n, None),
        (Some(Resolution::Auto), _) => (0, Some(AutoOptions::default())),
        (None, Some(v)) => (Grid::resolution_for_voxel(b, v)?, None),
        (None, None) => (256, None),
    };
    let is_3mf = a
        .output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("3mf"));
    // A beam lattice has no vertices to colour: with --color-by (or the
    // volumetric extras) a strut model is written as triangles.
    if is_3mf && !a.triangles && volume.is_none() && a.colour.color_by.is_none() {
        if let Some(sm) = microfrep::export::strut_model_of(&m.shape) {
            let n = if resolution == 0 { 256 } else { resolution };
            let (beams, nodes) = microfrep::export::strut_model_3mf(&sm, bounds, n, &a.output)?;
            check_terminates(&m, &[&a.output])?;
            let out = a.output.display().to_string();
            if a.run.json {
                let j = serde_json::json!({ "output": out, "kind": "beam-lattice",
                    "lattice": sm.kind.name(), "cell": sm.cell, "radius": sm.radius,
                    "beams": beams, "nodes": nodes, "clipped": sm.part.is_some() });
                println!("{j}");
            } else if !a.run.quiet {
                println!(
                    "wrote {out} (beam lattice: {beams} {} beams on {nodes} nodes, radius {}, cell {}; --triangles writes the mesh)",
                    sm.kind.name(),
                    sm.radius,
                    sm.cell
                );
            }
            return Ok(());
        }
    }
    if !(a.max_volume_loss >= 0.0 && a.max_volume_loss <= 100.0) {
        anyhow::bail!(
            "--max-volume-loss {}: give a percentage from 0 to 100",
            a.max_volume_loss
        );
    }
    let mut opts = MeshOptions::new(b, resolution);
    opts.volume_correction = !a.no_volume_correction;
    opts.cells = match a.cells {
        Cells::Cubes => CellMethod::Cubes,
        Cells::Tets => CellMethod::Tetrahedra,
    };
    if a.sharp && opts.cells != CellMethod::Cubes {
        anyhow::bail!("--sharp places feature vertices in marching cubes: drop --cells tets");
    }
    opts.sharp = a.sharp;
    let bar = a.run.bar("bricks");
    bar.set_message("meshing");
    let progress = |done: usize, total: usize| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
    };
    let job = JobOptions {
        stream: a.stream,
        max_volume_loss: Some(a.max_volume_loss / 100.0),
        auto,
        colour: a.colour.get()?.map(|(channel, colormap, range)| ColourBy {
            channel,
            colormap,
            range,
        }),
        tolerance: a.tolerance,
        ..JobOptions::default()
    };
    let s = mesh_to_file(&m.shape, &opts, &a.output, &job, &progress);
    bar.finish_and_clear();
    let s = s?;
    let added = match &volume {
        Some(v) => Some(apply_volume(v, &a.output, &m.shape, bounds, &a.run)?),
        None => None,
    };
    check_terminates(&m, &[&a.output])?;
    let secs = start.elapsed().as_secs_f64();
    let peak = microfrep::io::limits::peak_rss().unwrap_or(f64::NAN);
    let out = a.output.display().to_string();
    let range = s.colour_scale.map(|c| [c.lo, c.hi]);
    if a.run.json {
        let mut j = report::to_json(&s, &out, secs, peak);
        if let Some(r) = &added {
            j["volumetric"] = volume_json(r);
        }
        if let Some(r) = range {
            j["colour_range"] = serde_json::json!(r);
        }
        println!("{j}");
    } else if !a.run.quiet {
        print!("{}", report::to_text(&s, &out, secs, peak));
        if let Some(r) = &added {
            println!("{}", volume_text(r));
        }
        if let Some([lo, hi]) = range {
            println!(
                "  colours    attribute {} over {lo} .. {hi}",
                a.colour.color_by.unwrap_or(0)
            );
        }
    }
    Ok(())
}

/// The 3MF volumetric and implicit extensions, for `mesh` and `fill`.
#[derive(Args, Clone, Debug, Default)]
pub struct VolumeArgs {
    /// 3MF: add the model's implicit function as a level set, the built
    /// object (an implicit node graph; an image stack of the field where
    /// the model holds meshes, scans or other data fields).
    #[arg(long)]
    pub implicit: bool,
    /// 3MF: add the attribute channels s[] as volume data (image stacks).
    #[arg(long)]
    pub volumetric: bool,
    /// 3MF: materials NAME=#RRGGBB,... mixed by the attributes (material k
    /// takes s[k], the last the remainder), a composite of the volume data;
    /// implies --volumetric.
    #[arg(long)]
    pub palette: Option<String>,
    /// 3MF: voxels of the image stacks along the longest side (default 64).
    #[arg(long, value_name = "N")]
    pub volume_resolution: Option<usize>,
}

impl VolumeArgs {
    /// Whether none of the options was given.
    pub fn is_empty(&self) -> bool {
        !(self.implicit || self.volumetric || self.palette.is_some())
            && self.volume_resolution.is_none()
    }

    /// The options, or `None` when none was given; refused for outputs
    /// other than .3mf.
    pub fn options(&self, out: &std::path::Path) -> Result<Option<VolumeOptions>> {
        let asked = self.implicit || self.volumetric || self.palette.is_some();
        if !asked && self.volume_resolution.is_none() {
            return Ok(None);
        }
        let is_3mf = out
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("3mf"));
        if !is_3mf {
            bail!(
                "{}: --implicit, --volumetric, --palette and --volume-resolution are 3MF \
                 extensions: write a .3mf file",
                out.display()
            );
        }
        if !asked {
            bail!("--volume-resolution: give --implicit, --volumetric or --palette too");
        }
        let palette = match &self.palette {
            Some(p) => Some(microfrep::graded::stack::Palette::parse(p)?),
            None => None,
        };
        Ok(Some(VolumeOptions {
            implicit: self.implicit,
            attributes: self.volumetric,
            palette,
            resolution: self
                .volume_resolution
                .unwrap_or(microfrep::export::DEFAULT_VOLUME_RESOLUTION),
            memory_limit: None,
        }))
    }
}

/// Adds the extensions to the 3MF just written (removed again on failure)
/// and prints the fallback note.
pub fn apply_volume(
    v: &VolumeOptions,
    out: &std::path::Path,
    shape: &microfrep::Shape,
    b: microfrep::Bounds,
    run: &RunArgs,
) -> Result<VolumeReport> {
    let bar = run.bar("sheets");
    bar.set_message("sampling volumes");
    let r = microfrep::export::add_volumetric_to_file(out, shape, b, v, &|d, t| {
        bar.set_length(t);
        bar.set_position(d);
    });
    bar.finish_and_clear();
    let r = r.inspect_err(|_| {
        let _ = std::fs::remove_file(out);
    })?;
    if let Some(n) = r.note() {
        run.note(&n);
    }
    Ok(r)
}

/// The summary of [`apply_volume`] as JSON.
pub fn volume_json(r: &VolumeReport) -> serde_json::Value {
    use microfrep::export::LevelSetSource;
    let ls = match &r.level_set {
        Some(LevelSetSource::Graph { nodes }) => {
            serde_json::json!({ "kind": "implicit", "nodes": nodes })
        }
        Some(LevelSetSource::ImageStack { fields }) => {
            serde_json::json!({ "kind": "image-stack", "fields": fields })
        }
        None => serde_json::Value::Null,
    };
    serde_json::json!({
        "level_set": ls, "attributes": r.attributes, "materials": r.materials,
        "images": r.images, "dims": r.grid.dims, "pitch": r.grid.pitch,
    })
}

/// The summary of [`apply_volume`] as a line of text.
pub fn volume_text(r: &VolumeReport) -> String {
    use microfrep::export::LevelSetSource;
    let mut parts = Vec::new();
    match &r.level_set {
        Some(LevelSetSource::Graph { nodes }) => {
            parts.push(format!("level set: implicit graph of {nodes} nodes"))
        }
        Some(LevelSetSource::ImageStack { .. }) => parts.push("level set: image stack".into()),
        None => {}
    }
    if r.attributes > 0 {
        parts.push(format!("{} attribute(s) as volume data", r.attributes));
    }
    if r.materials > 0 {
        parts.push(format!("a composite of {} materials", r.materials));
    }
    let [x, y, z] = r.grid.dims;
    if r.images > 0 {
        parts.push(format!("{} image stack(s) of {x} x {y} x {z}", r.images));
    }
    format!("  3MF extensions {}", parts.join("; "))
}
