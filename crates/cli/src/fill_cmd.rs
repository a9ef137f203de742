//! `microfrep fill PART`: the part filled with a structure, to a mesh, a
//! beam-lattice 3MF, a slice stack or a HyperFun file, with the figures
//! that matter measured on what was built (the facade's `fill` and its
//! report; this verb only parses, orders the steps and prints).

use crate::common::{num, parse_box, ModelArgs, RunArgs};
use anyhow::{bail, Context, Result};
use clap::Args;
use microfrep::fill::{
    fill, Density, FillOptions, FillReport, Filled, MeasureOptions, Part, Structure,
};
use microfrep::{Bounds, LoadOptions};
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct FillArgs {
    #[command(flatten)]
    part: ModelArgs,
    /// Output: a mesh (.stl .obj .ply .3mf), a HyperFun file (.hf), or a
    /// slice stack directory (an existing directory, a path ending in `/`,
    /// or any path with --format).
    #[arg(short, long)]
    output: PathBuf,
    /// gyroid, schwarz-p, schwarz-d, neovius, iwp, fks, sc, bcc, fcc, octet, kelvin, diamond, rods, pores, irregular.
    #[arg(long)]
    structure: String,
    /// Cell size (millimetres).
    #[arg(long, required_unless_present = "volume_per_pore")]
    cell: Option<f64>,
    /// Irregular pores: the size as the paper's volume per pore (m/P, mm^3)
    /// instead of --cell: cells of edge its cube root.
    #[arg(long, conflicts_with = "cell", value_name = "MM3")]
    volume_per_pore: Option<f64>,
    /// Infill density (volume fraction, 0..1).
    #[arg(long, conflicts_with_all = ["density_grade", "density_expr"])]
    density: Option<f64>,
    /// Graded by depth: SURFACE,INNER,DEPTH (density just below the skin, from DEPTH mm further in).
    #[arg(long, conflicts_with = "density_expr")]
    density_grade: Option<String>,
    /// Density as a HyperFun expression of x[1..3] and d (depth below the surface, mm).
    #[arg(long)]
    density_expr: Option<String>,
    /// Solid skin of this thickness (mm) joined to the infill.
    #[arg(long)]
    shell: Option<f64>,
    /// TPMS sheets instead of networks.
    #[arg(long)]
    sheet: bool,
    /// Write a strut fill to .3mf as one triangle mesh instead of a beam lattice.
    #[arg(long)]
    triangles: bool,
    /// Seed of irregular pores (0 to 2^53).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Irregular pores: spread of the derived polyhedra's vertices, 0 to
    /// 0.5 (default 0.15; 0 gives identical regular pores).
    #[arg(long)]
    irregularity: Option<f64>,
    /// Irregular pores: the parent polyhedron over the cell, per side, 4/3
    /// to 2 (default 1.6).
    #[arg(long)]
    parent_scale: Option<f64>,
    /// Irregular pores: `octree` (default) or `tmesh` (cells cut in two at
    /// half their longest side).
    #[arg(long, value_parser = ["octree", "tmesh"])]
    subdivision: Option<String>,
    /// Irregular pores: how far pores below 0.6274 porosity reach past
    /// their cell's face centres (relative to the half cell), 0 to 0.25
    /// (default 0.05: they open into their neighbours from 0.4559; 0 gives
    /// closed pores below 0.6274).
    #[arg(long)]
    opening: Option<f64>,
    /// Irregular pores: Eq. 9's t of the derived points set by hand, 24
    /// numbers in [0, 1] (vertex by vertex, x y z each), the same shape in
    /// every cell, scaled to each cell's porosity (instead of drawn with
    /// --irregularity).
    #[arg(long, value_name = "T1,...,T24")]
    pore_t: Option<String>,
    /// Park's material subspace DEPTH,RAMP below the part's surface
    /// (repeatable): layer k is material k, its fraction rising from 0 at
    /// DEPTH mm to 1 at DEPTH + RAMP mm (later layers over earlier ones),
    /// material 0 the rest; the channels s[1..] of a .3mf with
    /// --volumetric or --palette (the palette lists layer 1 .. K, then
    /// material 0).
    #[arg(long, value_name = "DEPTH,RAMP")]
    material_layer: Vec<String>,
    /// Mesh cells along the longest side, or `auto` (default): cells of at
    /// most half the skin and the walls or struts measured (walls thinner
    /// than both the design and the walls' 10th percentile are named in a
    /// note); a beam lattice's meshes follow its skin.
    #[arg(long, conflicts_with = "voxel")]
    resolution: Option<String>,
    /// Mesh cell size (mm).
    #[arg(long)]
    voxel: Option<f64>,
    /// Fail (writing nothing) when the mesh has more than PCT % less
    /// volume than the model sampled in every cell.
    #[arg(long, value_name = "PCT", default_value_t = 5.0)]
    max_volume_loss: f64,
    /// Slice stack format (png, svg, cli, 3mf); makes the output a slice stack.
    #[arg(long)]
    format: Option<String>,
    /// Slice layer height (mm).
    #[arg(long, default_value_t = 0.05)]
    layer: f64,
    /// Slice pixel size (mm).
    #[arg(long, default_value_t = 0.025)]
    pixel: f64,
    /// The thinnest wall or strut the printer makes (mm): thinner measured
    /// features refuse the job (nothing written), or warn with --thin warn.
    #[arg(long, value_name = "MM")]
    min_wall: Option<f64>,
    /// What --min-wall does with a thinner feature: refuse (default) or warn.
    #[arg(long, value_enum, default_value_t = ThinAction::Refuse)]
    thin: ThinAction,
    #[command(flatten)]
    volume: crate::mesh_cmd::VolumeArgs,
    #[command(flatten)]
    run: RunArgs,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum ThinAction {
    Refuse,
    Warn,
}

/// What the output is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Output {
    HyperFun,
    Mesh,
    BeamLattice,
    Slices,
}

fn output_kind(a: &FillArgs, structure: Structure) -> Result<Output> {
    let o = &a.output;
    let dir = a.format.is_some() || o.is_dir() || o.to_string_lossy().ends_with('/');
    if dir {
        return Ok(Output::Slices);
    }
    let ext = o
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    Ok(match ext.as_deref() {
        Some("hf") => Output::HyperFun,
        Some("3mf") if structure.is_struts() && !a.triangles && a.volume.is_empty() => {
            Output::BeamLattice
        }
        Some("stl" | "obj" | "ply" | "3mf") => Output::Mesh,
        _ => bail!(
            "-o {}: not a known output (a mesh .stl .obj .ply .3mf, a HyperFun .hf, or a slice \
             stack directory: an existing directory, a path ending in '/', or --format)",
            o.display()
        ),
    })
}

fn density_of(a: &FillArgs) -> Result<Density> {
    Ok(match (&a.density, &a.density_grade, &a.density_expr) {
        (Some(r), None, None) => Density::Constant(*r),
        (None, Some(g), None) => {
            let v: Vec<f64> = g
                .split(',')
                .map(|t| t.trim().parse())
                .collect::<Result<_, _>>()
                .map_err(|_| {
                    anyhow::anyhow!("--density-grade '{g}': expected SURFACE,INNER,DEPTH")
                })?;
            let [s, i, d] = v[..] else {
                bail!("--density-grade '{g}': expected SURFACE,INNER,DEPTH")
            };
            Density::Graded {
                at_surface: s,
                at_depth: i,
                depth: d,
            }
        }
        (None, None, Some(e)) => Density::Expression(e.clone()),
        _ => bail!("give one of --density, --density-grade, --density-expr"),
    })
}

pub fn run(a: FillArgs) -> Result<()> {
    a.run.init()?;
    let structure = Structure::parse(&a.structure, a.sheet).ok_or_else(|| {
        anyhow::anyhow!(
            "unknown structure '{}': {}",
            a.structure,
            microfrep::fill::with_option_names(Structure::NAMES, &microfrep::fill::cli_option)
        )
    })?;
    if a.sheet && !matches!(structure, Structure::Tpms { .. }) {
        bail!("--sheet applies to TPMS structures only");
    }
    let kind = output_kind(&a, structure)?;
    microfrep::io::atomic::check_not_input(&a.output)?;
    let slice_format = match kind {
        Output::Slices => Some(
            a.format
                .as_deref()
                .unwrap_or("png")
                .parse::<microfrep::fab::Format>()
                .map_err(|e| anyhow::anyhow!("--format: {e}"))?,
        ),
        _ => None,
    };
    if let Some(w) = a.min_wall {
        if !(w.is_finite() && w > 0.0) {
            bail!("--min-wall {w} must be a positive thickness");
        }
    }
    if !a.material_layer.is_empty() && (kind != Output::Mesh || a.volume.is_empty()) {
        bail!(
            "--material-layer makes attribute channels, which only a .3mf with --volumetric or \
             --palette carries: they would be lost in {}",
            a.output.display()
        );
    }
    let volume = match kind {
        Output::Mesh => a.volume.options(&a.output)?,
        _ if !a.volume.is_empty() => {
            bail!("--implicit, --volumetric and --palette add to a .3mf mesh output")
        }
        _ => None,
    };
    let opts = FillOptions {
        structure,
        cell: match (a.cell, a.volume_per_pore) {
            (Some(c), _) => c,
            (None, Some(v)) => {
                if structure != Structure::Irregular {
                    bail!("--volume-per-pore sizes irregular pores; give --cell");
                }
                if !(v.is_finite() && v > 0.0) {
                    bail!("--volume-per-pore {v} must be a positive volume (mm^3)");
                }
                v.cbrt()
            }
            (None, None) => bail!("give --cell (or --volume-per-pore for irregular pores)"),
        },
        density: density_of(&a)?,
        skin: a.shell,
        seed: a.seed,
        pores: microfrep::fill::PoreControls {
            irregularity: a.irregularity,
            parent_scale: a.parent_scale,
            tmesh: a.subdivision.as_deref() == Some("tmesh"),
            opening: a.opening,
            hand_t: match &a.pore_t {
                None => None,
                Some(t) => {
                    let v = crate::common::parse_numbers("--pore-t", t)?;
                    if v.len() != 24 {
                        bail!(
                            "--pore-t takes 24 numbers (t of the 8 derived points on x, y, z), \
                             got {}",
                            v.len()
                        );
                    }
                    Some(std::array::from_fn(|s| {
                        std::array::from_fn(|k| v[3 * s + k])
                    }))
                }
            },
        },
        material_layers: a
            .material_layer
            .iter()
            .map(|t| {
                let v = crate::common::parse_numbers("--material-layer", t)?;
                match v[..] {
                    [depth, ramp] => Ok(microfrep::fill::MaterialLayer { depth, ramp }),
                    _ => bail!("--material-layer {t}: give DEPTH,RAMP (millimetres)"),
                }
            })
            .collect::<Result<Vec<_>>>()?,
    };
    let part_opts = LoadOptions {
        object: a.part.object.clone(),
        params: a.part.params.clone(),
        fields: a.part.fields.clone(),
        memory_limit: None,
    };
    let bounds = match &a.part.bounds {
        Some(s) => {
            let (lo, hi) = parse_box("--bounds", s)?;
            Some(Bounds::new(lo, hi))
        }
        None => None,
    };
    let bar = a.run.bar("");
    let progress = |s: &str, d: u64, t: u64| {
        bar.set_message(s.to_string());
        bar.set_length(t.max(1));
        bar.set_position(d);
    };
    let built = (|| -> Result<(Filled, FillReport)> {
        let part = Part::load(&a.part.model, &part_opts, bounds, &progress)?;
        for p in &part.inputs {
            microfrep::io::atomic::register_input(p);
        }
        let f = fill(&part, &opts, &progress)?;
        let r = f.measure_local(&MeasureOptions::default(), &progress)?;
        Ok((f, r))
    })();
    bar.finish_and_clear();
    let (f, mut r) = built.with_context(|| format!("fill {}", a.part.model))?;
    // Printability before anything is written.
    if let (Some(w), Some(t)) = (a.min_wall, &r.thinnest) {
        let thinnest = match &r.skin {
            Some(s) => t.min.min(s.min),
            None => t.min,
        };
        if thinnest < w {
            let msg = format!(
                "the thinnest wall or strut measures {} mm (at {}), below --min-wall {w}",
                num(thinnest),
                point(&t.at)
            );
            match a.thin {
                ThinAction::Refuse => {
                    bail!("{msg}; nothing written (--thin warn writes it anyway)")
                }
                ThinAction::Warn => eprintln!("warning: {msg}"),
            }
        }
    }
    let b = f.bounds;
    // `gate` runs before the mesh is moved onto the output: nothing is
    // committed before every measurement has succeeded.
    let write = |r: &mut FillReport, gate: &dyn Fn() -> Result<()>| -> Result<serde_json::Value> {
        Ok(match kind {
            Output::HyperFun => {
                let text = f.hyperfun()?;
                microfrep::io::atomic::write_file(&a.output, text.as_bytes())?;
                serde_json::json!({ "kind": "hyperfun", "binding": f.binding(), "bytes": text.len() })
            }
            Output::BeamLattice => {
                let Some(rad) = f.design.strut_radius else {
                    bail!("a beam lattice takes a constant --density (or write --triangles)")
                };
                let Structure::Struts(k) = structure else {
                    unreachable!("beam lattices are struts")
                };
                let n = mesh_resolution(&a, thinnest_beam(&r, f.options.cell), b)?;
                let (beams, nodes) = microfrep::export::beam_lattice_fill_3mf(
                    &f.core,
                    f.skin.as_ref(),
                    k,
                    f.options.cell,
                    rad,
                    b,
                    n,
                    &a.output,
                )?;
                serde_json::json!({
                    "kind": "beam-lattice", "beams": beams, "nodes": nodes, "radius": rad,
                    "skin_mesh": f.skin.is_some(), "resolution": n,
                    "bytes": file_size(&a.output),
                })
            }
            Output::Mesh => {
                let n = mesh_resolution(&a, thinnest(&r), b)?;
                if let Some(area) = r.surface_estimate() {
                    check_mesh_size(area, b, n)?;
                }
                let (s, shells) = mesh_checked(&a, &f, b, n, gate)?;
                if let Some(t) = &r.thinnest {
                    if t.min < 2.0 * s.cell {
                        r.notes.push(format!(
                            "walls down to {} mm (at {}) are under two mesh cells of {} mm: the \
                         mesh may open them; --resolution {} shows them",
                            num(t.min),
                            point(&t.at),
                            num(s.cell),
                            (n as f64 * 2.0 * s.cell / t.min).ceil() as usize
                        ));
                    }
                }
                let mut j = serde_json::json!({
                    "kind": "mesh", "triangles": s.triangles, "bad_edges": s.bad_edges,
                    "volume": s.volume, "resolution": n, "cell": s.cell, "shells": shells,
                    "bytes": file_size(&a.output),
                });
                if let Some(v) = &volume {
                    let res = crate::mesh_cmd::apply_volume(v, &a.output, &f.model, b, &a.run)?;
                    j["volumetric"] = crate::mesh_cmd::volume_json(&res);
                }
                j
            }
            Output::Slices => {
                let grid = microfrep::fab::SliceGrid::new(b.min, b.max, a.layer, a.pixel)?;
                let format = slice_format.expect("parsed above");
                microfrep::fab::write_stack(&f.model, &grid, &format, &a.output, &|| {})?;
                serde_json::json!({ "kind": "slices", "layers": grid.layers })
            }
        })
    };
    // The whole part's connectivity does not change what is written, so
    // a mesh is made while it is measured (on its own thread, each using
    // the cores the other leaves idle), and moved onto the output only
    // once it is measured too. It measures the part's volume, which the
    // mesh's size check needs: where the part's box alone does not clear
    // the mesh, and for the other outputs, it is measured first.
    let beside = match kind {
        Output::Mesh => {
            let n = mesh_resolution(&a, thinnest(&r), b)?;
            let box_volume: f64 = b.size().iter().product();
            check_mesh_size(r.area_per_volume * box_volume, b, n).is_ok()
        }
        _ => false,
    };
    let conn_progress = |_: &str, _: u64, _: u64| {};
    let context = || format!("fill {}", a.part.model);
    let written = if beside {
        let mut conn = r.clone();
        let base = r.notes.len();
        let written = std::thread::scope(|sc| -> Result<serde_json::Value> {
            let measuring = sc.spawn(|| {
                f.add_connectivity(&mut conn, &MeasureOptions::default(), &conn_progress)
            });
            let measuring = std::sync::Mutex::new(Some(measuring));
            let gate = || -> Result<()> {
                let h = measuring.lock().expect("not poisoned").take();
                if let Some(h) = h {
                    h.join()
                        .map_err(|_| anyhow::anyhow!("measuring the connectivity failed"))?
                        .with_context(context)?;
                }
                Ok(())
            };
            let w = write(&mut r, &gate)?;
            gate()?;
            Ok(w)
        })?;
        r.connectivity = conn.connectivity;
        r.sealed = conn.sealed;
        r.seconds = conn.seconds;
        // Notes of the connectivity come after those of the writing.
        r.notes.extend(conn.notes.drain(base..));
        written
    } else {
        f.add_connectivity(&mut r, &MeasureOptions::default(), &conn_progress)
            .with_context(context)?;
        write(&mut r, &|| Ok(()))?
    };
    if a.run.json {
        println!("{}", report_json(&a, &f, &r, written));
    } else if !a.run.quiet {
        print_report(&a, &f, &r, &written);
    }
    Ok(())
}

fn file_size(p: &Path) -> Option<u64> {
    std::fs::metadata(p).ok().map(|m| m.len())
}

fn point(p: &[f64; 3]) -> String {
    format!("({}, {}, {})", num(p[0]), num(p[1]), num(p[2]))
}

/// The thinnest feature the mesh must show: the skin, and the walls and
/// struts down to the thinner of the designed feature and the walls' 10th
/// percentile (slivers below both, where random pores nearly touch, are
/// named in a note instead of driving the mesh to cells of a few microns).
fn thinnest(r: &FillReport) -> f64 {
    let mut t = r
        .thinnest
        .as_ref()
        .map_or(r.feature, |t| t.min.max(t.p10.min(r.feature)));
    if let Some(s) = &r.skin {
        t = t.min(s.min);
    }
    t.max(1e-12)
}

/// The thinnest feature a beam lattice's meshes must show: the skin (the
/// struts are beams, not triangles); without a skin, the core's clip mesh
/// follows the part to a quarter cell.
fn thinnest_beam(r: &FillReport, cell: f64) -> f64 {
    r.skin.as_ref().map_or(cell / 2.0, |s| s.min).max(1e-12)
}

/// Most mesh cells on a side (the mesher's limit).
const MAX_MESH_RESOLUTION: usize = 65533;

/// Mesh cells: `auto` (default) gives cells of at most half the thinnest
/// measured feature; an explicit resolution coarser than that is refused
/// with the one that works.
fn mesh_resolution(a: &FillArgs, t: f64, b: Bounds) -> Result<usize> {
    let longest = b.size().iter().copied().fold(0.0, f64::max);
    let need = (2.0 * longest / t).ceil() as usize;
    let asked = match (a.resolution.as_deref(), a.voxel) {
        (Some("auto") | None, None) => None,
        (Some(s), _) => Some(
            s.parse::<usize>()
                .map_err(|_| anyhow::anyhow!("--resolution '{s}': a cell count or 'auto'"))?,
        ),
        (None, Some(v)) => Some(microfrep::mesh::Grid::resolution_for_voxel(b.corners(), v)?),
    };
    match asked {
        None => {
            if need > MAX_MESH_RESOLUTION {
                bail!(
                    "the thinnest feature ({} mm) needs {need} mesh cells on the part's longest \
                     side ({} mm), over the limit of {}; write a slice stack or a .hf model, or \
                     fill with thicker walls (a higher --density or a larger --cell)",
                    num(t),
                    num(longest),
                    MAX_MESH_RESOLUTION
                );
            }
            Ok(need.max(16))
        }
        Some(n) if n < need => bail!(
            "--resolution {n} gives mesh cells of {} mm, more than half the thinnest wall, strut \
             or skin measured ({} mm): the mesh would lose them; use --resolution {need} or more, \
             or --resolution auto",
            num(longest / n as f64),
            num(t)
        ),
        Some(n) => Ok(n),
    }
}

/// Triangles of a marching-cubes mesh per unit area over the squared cell
/// (measured on fills of the femur: 2.9 for irregular pores; 3.3 for an
/// octet and 4.4 for a gyroid with a 2 mm skin, whose surfaces the estimate
/// leaves out).
const TRIANGLES_PER_CELL_AREA: f64 = 3.0;

/// Bytes a triangle takes while the written mesh is read back and checked
/// (vertices, indices, welding).
const CHECK_BYTES_PER_TRIANGLE: f64 = 150.0;

/// Refuses, before any work, a mesh that would not fit this machine: its
/// triangles estimated from the infill's measured surface and the part's
/// volume.
/// Refuses a mesh of `n` cells on the longest side of `b` over a surface
/// of `area` when it would not fit in memory.
fn check_mesh_size(area: f64, b: Bounds, n: usize) -> Result<()> {
    let longest = b.size().iter().copied().fold(0.0, f64::max);
    let h = longest / n as f64;
    let triangles = TRIANGLES_PER_CELL_AREA * area / (h * h);
    let need = triangles * CHECK_BYTES_PER_TRIANGLE;
    let limit = microfrep::io::limits::memory_limit().unwrap_or(f64::INFINITY);
    if need > limit {
        bail!(
            "the mesh that shows these walls ({n} cells of {} mm on the longest side) would have \
             about {:.0} million triangles ({:.1} GB as STL), needing about {:.0} GB of memory to \
             write and check, more than the {:.1} GB free; nothing written: write a slice stack \
             (--format png) or a .hf model, or fill with thicker walls (a larger --cell or a \
             higher --density)",
            num(h),
            triangles / 1e6,
            triangles * 50.0 / 1e9,
            need / 1e9,
            limit / 1e9
        );
    }
    Ok(())
}

/// Meshes into a staging folder, checks the written mesh (a skinned part
/// has its outer shell and at least one inner one), then moves it onto the
/// output: nothing replaces the output before the job has succeeded.
fn mesh_checked(
    a: &FillArgs,
    f: &Filled,
    b: Bounds,
    n: usize,
    gate: &dyn Fn() -> Result<()>,
) -> Result<(microfrep::mesh::job::Summary, usize)> {
    let name = a
        .output
        .file_name()
        .ok_or_else(|| anyhow::anyhow!("-o {}: not a file name", a.output.display()))?;
    let parent = a
        .output
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let stage = microfrep::io::atomic::AtomicDir::create(&parent.join(".microfrep-fill-stage"))?;
    let staged = stage.path().join(name);
    let mo = microfrep::mesh::MeshOptions::new(b.corners(), n);
    let job = microfrep::mesh::job::JobOptions {
        max_volume_loss: Some(a.max_volume_loss / 100.0),
        ..Default::default()
    };
    let s = microfrep::mesh::job::mesh_to_file(&f.model, &mo, &staged, &job, &|_, _| {})
        .map_err(|e| anyhow::anyhow!("{e}").context(format!("meshing {}", a.output.display())))?;
    // Counted by the mesher on its indexed output (read back only if it
    // could not count).
    let shells = match s.shells {
        Some(n) => n,
        None => microfrep::fill::report::mesh_shells(&staged)?,
    };
    if f.skin.is_some() && shells < 2 {
        bail!(
            "the written mesh has {shells} shell(s): a skinned part needs its outer and inner \
             surfaces; nothing written (raise --resolution)"
        );
    }
    gate()?;
    std::fs::rename(&staged, &a.output)
        .with_context(|| format!("moving the mesh onto {}", a.output.display()))?;
    drop(stage);
    Ok((s, shells))
}

fn report_json(
    a: &FillArgs,
    f: &Filled,
    r: &FillReport,
    written: serde_json::Value,
) -> serde_json::Value {
    let mut j = r.to_json(f);
    j["output"] = a.output.display().to_string().into();
    j["written"] = written;
    j
}

fn print_report(a: &FillArgs, f: &Filled, r: &FillReport, written: &serde_json::Value) {
    let kind = written["kind"].as_str().unwrap_or("");
    println!("wrote {} ({kind})", a.output.display());
    if kind == "mesh" {
        println!(
            "  mesh           {} triangles, {} shell(s), cells of {} mm, {} bytes",
            written["triangles"],
            written["shells"],
            num(written["cell"].as_f64().unwrap_or(f64::NAN)),
            written["bytes"]
        );
    }
    if let Some((n, file)) = f.binding() {
        if kind == "hyperfun" {
            println!("  load it with --field {n}={file}");
        }
    }
    println!(
        "  infill density {} ± {} (target {})",
        num(r.density.value),
        num(r.density.error),
        a.density.map_or("graded".into(), num)
    );
    if let Some(s) = &r.skin {
        println!(
            "  skin           min {} (at {}), mean {} (target {}; {} rays along the normals)",
            num(s.min),
            point(&s.at),
            num(s.mean),
            a.shell.map_or("-".into(), num),
            s.rays
        );
    }
    if let Some(t) = &r.thinnest {
        println!(
            "  thinnest wall  {} ± {} at {} (10th percentile {}, mean {})",
            num(t.min),
            num(r.voxel),
            point(&t.at),
            num(t.p10),
            num(t.mean)
        );
    }
    if let Some(t) = &r.pores {
        println!(
            "  pore size      mean {}, min {} (10th percentile {})",
            num(t.mean),
            num(t.min),
            num(t.p10)
        );
    }
    if let Some(c) = &r.connectivity {
        let sealed = match r.sealed {
            Some(true) => "; the skin seals the pores in: nothing gets in or out",
            Some(false) => "; the skin does not seal the pores",
            None => "",
        };
        println!(
            "  connectivity   {} solid component(s); {:.1} % of the pore volume open to the \
             outside, {} closed pore(s){sealed}",
            c.solid_components,
            100.0 * c.open_fraction,
            c.closed_pores
        );
    }
    println!(
        "  measured on    {} cubes of {} mm at {} mm voxels ({} for walls and pores; {} voxels \
         across the thinnest designed feature, {} mm); connectivity at {} mm voxels; {:.2} s",
        r.boxes,
        num(r.box_side),
        num(r.voxel),
        r.thickness_boxes,
        (r.feature / r.voxel).round(),
        num(r.feature),
        r.connectivity.as_ref().map_or("-".into(), |c| num(c.voxel)),
        r.seconds
    );
    for n in f.notes.iter().chain(&r.notes) {
        let n = microfrep::fill::with_option_names(n, &microfrep::fill::cli_option);
        println!("  note: {n}");
    }
}
