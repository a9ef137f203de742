//! The report for people and programs: [`to_json`] gives the keys of
//! `microfrep analyze --json` (shared by every host: the CLI, the studio,
//! the Python bindings), [`to_text`] the text summary.

use crate::report::Report;
use crate::thickness::{PhaseThickness, Thickness, ThicknessStats};
use serde_json::{json, Value};
use std::fmt::Write as _;

fn s(v: f64) -> String {
    microfrep_io::text::sig(v, 7)
}
fn s5(v: f64) -> String {
    microfrep_io::text::sig(v, 5)
}
fn e(v: f64) -> String {
    if v.is_nan() {
        "undefined".into()
    } else {
        format!("{v:.2e}")
    }
}

/// The report as JSON (the keys of `microfrep analyze --json`); `model`
/// and `region` name the inputs. Undefined figures (a porosity with an
/// empty region) are `null`.
pub fn to_json(r: &Report, model: &str, region: Option<&str>) -> Value {
    let g = &r.grid;
    let m = &r.measures;
    let conn = r.connectivity.as_ref().map(|c| {
        json!({
            "solid_connectivity": 26,
            "pore_connectivity": 6,
            "solid_components": c.solid_components,
            "solid_volumes": c.solid_volumes,
            "pore_components": c.pore_components,
            "pore_volume": c.pore_volume,
            "open_pore_volume": c.open_pore_volume,
            "open_pore_fraction": c.open_pore_fraction(),
            "closed_pores": c.closed_pores,
            "closed_pore_volume": c.closed_pore_volume,
            "percolates": { "x": c.percolates[0], "y": c.percolates[1], "z": c.percolates[2] },
            "percolation_between": if region.is_some() { "the region's first and last voxel layers" } else { "the box's faces" },
            "euler_solid": c.euler,
            "euler_surface": c.surface_euler(),
        })
    });
    json!({
        "model": model,
        "region": region,
        "bounds": [g.lo, g.hi],
        "dims": g.dims,
        "voxel": g.step,
        "volume": { "value": r.volume(), "error": r.volume_error(), "coarse": m.volume.coarse },
        "region_volume": { "value": r.region_volume(), "error": r.region_volume_error() },
        "volume_fraction": { "value": r.volume_fraction(), "error": r.volume_fraction_error() },
        "porosity": { "value": r.porosity(), "error": r.volume_fraction_error() },
        "area": { "value": r.area(), "error": r.area_error(), "coarse": m.area.coarse },
        "specific_surface": { "value": r.specific_surface(), "error": r.specific_surface_error() },
        "proven_volume": m.proven_volume,
        "sampled_volume": { "value": m.sampled_volume, "error": m.sampled_volume_error },
        "bricks": { "sampled": m.sampled_bricks, "total": m.bricks },
        "refine_depth": m.refine_depth,
        "creased_cells": m.creased_cells,
        "notes": r.notes(),
        "connectivity": conn,
        "thickness": r.thickness.as_ref().map(thickness_json),
        "attributes": r.attributes.iter().enumerate().map(|(k, a)| json!({
            "index": k + 1,
            "name": a.name,
            "integral": { "value": a.integral, "error": a.error },
            "mean": a.mean,
            "min": a.min,
            "max": a.max,
        })).collect::<Vec<_>>(),
        "seconds": { "measure": r.seconds[0], "connectivity": r.seconds[1], "thickness": r.seconds[2] },
        "accuracy": "errors are estimates from the grid and the grid coarsened by 2 \
                     (Richardson: second order on smooth surfaces, first order at creases); \
                     connectivity and thickness are exact on the voxel grid",
    })
}

fn thickness_json(t: &Thickness) -> Value {
    let phase = |p: &PhaseThickness| match p {
        PhaseThickness::Skipped => json!("skipped"),
        PhaseThickness::Empty => json!("empty"),
        PhaseThickness::Unbounded { voxels } => json!({ "unbounded": true, "voxels": voxels }),
        PhaseThickness::Measured(s) => stats_json(s),
    };
    json!({
        "voxel": t.voxel,
        "solid": phase(&t.solid),
        "pore": phase(&t.pore),
        "slabs": t.slabs,
        "diameter_cap": t.diameter_cap,
    })
}

fn stats_json(s: &ThicknessStats) -> Value {
    json!({
        "voxels": s.voxels,
        "mean": s.mean,
        "min": s.min,
        "p10": s.p10,
        "median": s.median,
        "p90": s.p90,
        "max": s.max,
        "capped_voxels": s.capped_voxels,
        "exact_up_to": s.exact_up_to,
        "ladder_ratio": s.ladder_ratio,
        "histogram": { "edges": s.histogram.edges, "counts": s.histogram.counts },
    })
}

/// The report as text, one figure a line, numbers with significant
/// digits.
pub fn to_text(r: &Report, model: &str, region: Option<&str>) -> String {
    let mut out = String::new();
    macro_rules! println {
        ($($t:tt)*) => {{ let _ = writeln!(out, $($t)*); }};
    }
    let g = &r.grid;
    let m = &r.measures;
    println!("analysis of {model}");
    println!(
        "  grid        {} x {} x {} voxels of {} (bounds {:?} .. {:?})",
        g.dims[0],
        g.dims[1],
        g.dims[2],
        s(g.voxel_size()),
        g.lo,
        g.hi
    );
    let within = match region {
        Some(name) => format!("inside region {name}"),
        None => "in the bounds".to_string(),
    };
    println!(
        "  volume      {} ± {} ({within})",
        s(r.volume()),
        e(r.volume_error())
    );
    println!(
        "  region      {} ± {}",
        s(r.region_volume()),
        e(r.region_volume_error())
    );
    println!(
        "  fraction    {} ± {} (porosity {})",
        s(r.volume_fraction()),
        e(r.volume_fraction_error()),
        s(r.porosity())
    );
    println!("  area        {} ± {}", s(r.area()), e(r.area_error()));
    println!(
        "  specific    {} ± {} (area / volume)",
        s(r.specific_surface()),
        e(r.specific_surface_error())
    );
    println!(
        "  sampling    {} of {} bricks sampled, the rest ({:.1}% of the region) exact by \
         intervals; {} voxels with creases or sharp curvature halved {} time(s)",
        m.sampled_bricks,
        m.bricks,
        100.0 * m.proven_volume / r.region_volume().max(f64::MIN_POSITIVE),
        m.creased_cells,
        m.refine_depth
    );
    if let Some(c) = &r.connectivity {
        let others = c.solid_volumes.iter().skip(1).fold(0.0, |a, v| a + v);
        println!(
            "  solid       {} component(s) (26-connected); volume outside the largest {}",
            c.solid_components,
            s(others)
        );
        println!(
            "  pores       {} component(s) (6-connected), {} % of pore volume open to the \
             outside, {} closed (volume {})",
            c.pore_components,
            s5(100.0 * c.open_pore_fraction()),
            c.closed_pores,
            s(c.closed_pore_volume)
        );
        let yn = |b: bool| if b { "yes" } else { "no" };
        let ends = if region.is_some() {
            "one pore from the first to the last voxel layer of the region"
        } else {
            "one pore from face to face of the box"
        };
        println!(
            "  percolation x {}, y {}, z {} ({ends})",
            yn(c.percolates[0]),
            yn(c.percolates[1]),
            yn(c.percolates[2])
        );
        println!(
            "  euler       {} (solid), {} (its surface)",
            c.euler,
            c.surface_euler()
        );
    }
    if let Some(t) = &r.thickness {
        for (name, p) in [("thickness", &t.solid), ("pore size", &t.pore)] {
            match p {
                PhaseThickness::Measured(st) => {
                    println!(
                        "  {name:<11} mean {}, median {}, p10 {}, p90 {}, max {}",
                        s5(st.mean),
                        s5(st.median),
                        s5(st.p10),
                        s5(st.p90),
                        s5(st.max)
                    );
                    if let Some(cut) = st.exact_up_to {
                        println!(
                            "  note        {name} above {} is a lower bound \
                             (radius ladder {:.1} % apart, to bound the work)",
                            s5(cut),
                            100.0 * (st.ladder_ratio - 1.0)
                        );
                    }
                    if st.capped_voxels > 0 {
                        println!(
                            "  note        {} {name} voxels capped at the slab limit",
                            st.capped_voxels
                        );
                    }
                }
                PhaseThickness::Unbounded { .. } => {
                    println!("  {name:<11} unbounded (the phase fills the grid)")
                }
                PhaseThickness::Empty => println!("  {name:<11} none (empty phase)"),
                PhaseThickness::Skipped => {}
            }
        }
        if let Some(cap) = t.diameter_cap {
            println!(
                "  note        thickness above {} is capped (slabbed grid)",
                s5(cap)
            );
        }
    }
    for (k, a) in r.attributes.iter().enumerate() {
        println!(
            "  s[{}]        integral {} ± {}, mean {}, min {}, max {}",
            k + 1,
            s(a.integral),
            e(a.error),
            s(a.mean),
            s(a.min),
            s(a.max)
        );
    }
    for n in r.notes() {
        println!("  note        {n}");
    }
    println!(
        "  accuracy    ± are Richardson estimates (grid vs grid coarsened by 2); \
         connectivity and thickness are exact on the voxel grid unless a note says otherwise"
    );
    let mut times = format!("{:.2} s volume/area", r.seconds[0]);
    if r.connectivity.is_some() {
        times += &format!(", {:.2} s connectivity", r.seconds[1]);
    }
    if r.thickness.is_some() {
        times += &format!(", {:.2} s thickness", r.seconds[2]);
    }
    println!("  time        {times}");
    out
}
