//! A finished job's [`Summary`] for people ([`to_text`]) and programs
//! ([`to_json`], the keys of `microfrep mesh --json`), shared by every
//! host.

use crate::job::Summary;
use crate::CellMethod;
use microfrep_io::text::sig;
use serde_json::{json, Value};
use std::fmt::Write as _;

/// The cell method's name as `--cells` takes it.
pub fn cells_name(c: CellMethod) -> &'static str {
    match c {
        CellMethod::Cubes => "cubes",
        CellMethod::Tetrahedra => "tets",
    }
}

/// The summary as JSON; `output` names the file, `seconds` and
/// `peak_bytes` are the host's wall time and peak resident size. Figures
/// not known (a streamed mesh's edge check) are `null`.
pub fn to_json(s: &Summary, output: &str, seconds: f64, peak_bytes: f64) -> Value {
    json!({
        "output": output,
        "resolution": s.resolution,
        "cells": cells_name(s.cells),
        "cell": s.cell,
        "triangles": s.triangles,
        "vertices": s.vertices,
        "bad_edges": s.bad_edges,
        "euler": s.euler,
        "streamed": s.streamed,
        "volume": s.volume,
        "area": s.area,
        "bbox": s.bbox,
        "seconds": seconds,
        "peak_bytes": peak_bytes,
        "predicted_peak_bytes": s.predicted_bytes,
        "thin_cells": s.thin_cells,
        "runtime_errors": s.runtime_errors.as_ref().map(|c| c.errors),
        "sampled_volume": s.sampled_volume.map(|v| json!({ "value": v.value, "error": v.error })),
        "volume_loss": s.volume_loss,
        "merged": s.decimation.map(|d| json!({
            "triangles_before": d.triangles.0,
            "triangles_after": d.triangles.1,
            "vertices_removed": d.removed,
            "deviation": d.deviation,
            "deviation_cells": d.deviation / s.cell,
            "points_checked": d.samples,
        })),
        "auto": s.trials.iter().map(|t| json!({
            "resolution": t.resolution,
            "mesh_volume": t.mesh_volume,
            "sampled_volume": t.sampled.value,
            "seconds": t.seconds,
        })).collect::<Vec<_>>(),
    })
}

/// The summary as text, a figure a line.
pub fn to_text(s: &Summary, output: &str, seconds: f64, peak_bytes: f64) -> String {
    const MIB: f64 = 1024.0 * 1024.0;
    let num = |v: f64| sig(v, 7);
    let mut o = String::new();
    macro_rules! line {
        ($($t:tt)*) => {{ let _ = writeln!(o, $($t)*); }};
    }
    line!("wrote {output}");
    line!(
        "  grid       {} cells on the longest side, cell {} ({})",
        s.resolution,
        num(s.cell),
        cells_name(s.cells)
    );
    if !s.trials.is_empty() {
        let t: Vec<String> = s.trials.iter().map(|t| t.resolution.to_string()).collect();
        line!("  auto       tried {} cells", t.join(", "));
    }
    line!("  triangles  {}", s.triangles);
    if let Some(d) = s.decimation {
        line!(
            "  merged     flat regions: {} -> {} triangles, within {} cells of the \
             surface ({} points checked against the field)",
            d.triangles.0,
            d.triangles.1,
            sig(d.deviation / s.cell, 2),
            d.samples
        );
    }
    line!("  vertices   {}", s.vertices);
    match (s.bad_edges, s.euler) {
        (Some(b), Some(e)) => line!("  bad edges  {b} (euler {e})"),
        _ => line!("  bad edges  not counted (the streamed mesh did not come in the order the count needs)"),
    }
    match (s.sampled_volume, s.volume_loss) {
        (Some(v), Some(l)) => line!(
            "  volume     {} (model {} ± {} sampled: {} % lost)",
            num(s.volume),
            num(v.value),
            sig(v.error, 2),
            sig(100.0 * l, 2)
        ),
        _ => line!("  volume     {}", num(s.volume)),
    }
    line!("  area       {}", num(s.area));
    let bb = |p: [f64; 3]| p.map(num).join(", ");
    line!("  bbox       [{}] .. [{}]", bb(s.bbox[0]), bb(s.bbox[1]));
    line!("  time       {seconds:.2} s");
    if let Some(c) = s.runtime_errors.as_ref().filter(|c| c.errors > 0) {
        line!("  run-time errors at {c}; those nodes count as outside");
    }
    if s.thin_cells > 0 {
        line!(
            "  note       interval analysis found {} cells that may hold features thinner \
             than a cell; they are not in the mesh (the volume check above measures what \
             they hold)",
            s.thin_cells
        );
    }
    line!(
        "  peak mem   {:.1} MiB (predicted {:.1} MiB)",
        peak_bytes / MIB,
        s.predicted_bytes / MIB
    );
    o
}
