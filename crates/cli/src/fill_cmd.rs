//! `microfrep fill PART`: the part filled with a structure, to a mesh, a
//! slice stack or a HyperFun file, with the figures that matter.

use crate::common::{frame, num, ModelArgs, RunArgs};
use anyhow::{bail, Result};
use clap::Args;
use microfrep::fill::{fill, Density, FillOptions, Structure};
use microfrep::LoadOptions;
use std::path::PathBuf;

#[derive(Args)]
pub struct FillArgs {
    #[command(flatten)]
    part: ModelArgs,
    /// Output: a mesh (.stl .obj .ply .3mf), a HyperFun file (.hf), or a
    /// directory for a slice stack (see --format).
    #[arg(short, long)]
    output: PathBuf,
    /// gyroid, schwarz-p, schwarz-d, neovius, iwp, fks, sc, bcc, fcc, octet, kelvin, diamond, rods, pores, irregular.
    #[arg(long)]
    structure: String,
    /// Cell size (model units, millimetres).
    #[arg(long)]
    cell: f64,
    /// Infill density (volume fraction, 0..1).
    #[arg(long, conflicts_with_all = ["density_grade", "density_expr"])]
    density: Option<f64>,
    /// Graded by depth: SURFACE,INNER,DEPTH (density just below the skin, from DEPTH inwards).
    #[arg(long)]
    density_grade: Option<String>,
    /// Density as a HyperFun expression of x[1..3] and d (depth below the surface).
    #[arg(long)]
    density_expr: Option<String>,
    /// Solid skin of this thickness joined to the infill.
    #[arg(long)]
    shell: Option<f64>,
    /// TPMS sheets instead of networks.
    #[arg(long)]
    sheet: bool,
    /// Write a strut fill to .3mf as plain triangles instead of a beam lattice.
    #[arg(long)]
    triangles: bool,
    /// Seed of irregular pores.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Cells (mesh) or voxels (figures) on the longest side (default 256 and 128).
    #[arg(long, conflicts_with = "voxel")]
    resolution: Option<usize>,
    /// Cell size of the mesh (model units).
    #[arg(long)]
    voxel: Option<f64>,
    /// Slice stack format for a directory output: png, svg or cli.
    #[arg(long, default_value = "png")]
    format: String,
    /// Slice layer and pixel size for a directory output.
    #[arg(long, default_value_t = 0.05)]
    layer: f64,
    #[arg(long, default_value_t = 0.025)]
    pixel: f64,
    #[command(flatten)]
    volume: crate::mesh_cmd::VolumeArgs,
    #[command(flatten)]
    run: RunArgs,
}

pub fn run(a: FillArgs) -> Result<()> {
    a.run.init()?;
    let volume = a.volume.options(&a.output)?;
    let structure = Structure::parse(&a.structure, a.sheet).ok_or_else(|| {
        anyhow::anyhow!("unknown structure '{}': {}", a.structure, Structure::NAMES)
    })?;
    let density = match (&a.density, &a.density_grade, &a.density_expr) {
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
    };
    let opts = FillOptions {
        structure,
        cell: a.cell,
        density,
        skin: a.shell,
        seed: a.seed,
    };
    let part_opts = LoadOptions {
        object: a.part.object.clone(),
        params: a.part.params.clone(),
        fields: a.part.fields.clone(),
        memory_limit: None,
    };
    let bar = a.run.bar("");
    let progress = |s: &str, d: u64, t: u64| {
        bar.set_message(s.to_string());
        bar.set_length(t);
        bar.set_position(d);
    };
    let f = fill(&a.part.model, &part_opts, &opts, &progress);
    bar.finish_and_clear();
    let f = f.map_err(anyhow::Error::new)?;
    for p in &f.model.inputs {
        microfrep::io::atomic::register_input(p);
    }
    let ext = a
        .output
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    let written = match ext.as_deref() {
        Some("hf") => {
            microfrep::io::atomic::write_file(&a.output, f.source.as_bytes())?;
            serde_json::json!({ "kind": "hyperfun", "binding": f.binding })
        }
        Some("3mf") if structure.is_struts() && !a.triangles => {
            let Structure::Struts(kind) = structure else {
                unreachable!("checked")
            };
            let Some(rho) = a.density else {
                bail!("a beam lattice takes a constant --density (or write --triangles)")
            };
            if a.shell.is_some() {
                bail!("a beam lattice with a skin: write --triangles (one solid mesh)")
            }
            if volume.is_some() {
                bail!("--implicit, --volumetric and --palette add to a mesh: write --triangles")
            }
            let k = microfrep::structures::struts::StrutLattice::ALL[kind as usize - 1];
            let r = microfrep::structures::density::strut_radius(
                k,
                rho,
                microfrep::structures::density::STRUT_CELLS,
            )? * a.cell;
            let b = frame(&f.model, &a.part, &a.run)?;
            let part = f.part()?;
            let (beams, nodes) = microfrep::export::beam_lattice_3mf(
                &part,
                kind,
                a.cell,
                r,
                b,
                a.resolution.unwrap_or(128),
                &a.output,
            )?;
            serde_json::json!({ "kind": "beam-lattice", "beams": beams, "nodes": nodes, "radius": r })
        }
        Some("stl" | "obj" | "ply" | "3mf") => {
            let bounds = frame(&f.model, &a.part, &a.run)?;
            if let Some(v) = &volume {
                v.check(&f.model.shape, bounds)?;
            }
            let b = bounds.corners();
            let n = match (a.resolution, a.voxel) {
                (Some(n), _) => n,
                (None, Some(v)) => microfrep::mesh::Grid::resolution_for_voxel(b, v)?,
                (None, None) => 256,
            };
            let mo = microfrep::mesh::MeshOptions::new(b, n);
            let s = microfrep::mesh::job::mesh_to_file(
                &f.model.shape,
                &mo,
                &a.output,
                &Default::default(),
                &|_, _| {},
            )?;
            let mut j = serde_json::json!({ "kind": "mesh", "triangles": s.triangles, "bad_edges": s.bad_edges, "volume": s.volume, "resolution": n });
            if let Some(v) = &volume {
                let r =
                    crate::mesh_cmd::apply_volume(v, &a.output, &f.model.shape, bounds, &a.run)?;
                j["volumetric"] = crate::mesh_cmd::volume_json(&r);
            }
            j
        }
        _ => {
            let b = frame(&f.model, &a.part, &a.run)?;
            let grid = microfrep::fab::SliceGrid::new(b.min, b.max, a.layer, a.pixel)?;
            let format = match a.format.as_str() {
                "png" => microfrep::fab::Format::Png { aa: false },
                "svg" => microfrep::fab::Format::Svg,
                "cli" => microfrep::fab::Format::Cli,
                other => bail!("--format {other}: png, svg or cli"),
            };
            microfrep::fab::write_stack(&f.model.shape, &grid, &format, &a.output, &|| {})?;
            serde_json::json!({ "kind": "slices", "layers": grid.layers })
        }
    };
    let r = f.measure(a.resolution.unwrap_or(128).min(192))?;
    if a.run.json {
        let s = serde_json::json!({
            "output": a.output.display().to_string(), "written": written,
            "density": { "target": a.density, "measured": r.density.0, "error": r.density.1 },
            "skin": { "target": a.shell, "measured": r.skin },
            "thinnest": r.thinnest.map(|(m, p)| serde_json::json!({ "min": m, "p10": p })),
            "solid_components": r.components, "open_pore_fraction": r.open_pores,
        });
        println!("{s}");
    } else if !a.run.quiet {
        println!(
            "wrote {} ({})",
            a.output.display(),
            written["kind"].as_str().unwrap_or("")
        );
        if let Some((n, file)) = &f.binding {
            println!("  the .hf form needs --field {n}={file}");
        }
        println!(
            "  infill density {} ± {:.1e} (target {})",
            num(r.density.0),
            r.density.1,
            a.density.map_or("graded".into(), num)
        );
        if let (Some(m), Some(t)) = (r.skin, a.shell) {
            println!("  skin           {} (target {})", num(m), num(t));
        }
        if let Some((m, p)) = r.thinnest {
            println!("  thinnest       {} (10th percentile {})", num(m), num(p));
        }
        if let (Some(c), Some(o)) = (r.components, r.open_pores) {
            println!(
                "  solid          {c} component(s); {:.1}% of the pores open to the outside",
                100.0 * o
            );
        }
    }
    Ok(())
}
