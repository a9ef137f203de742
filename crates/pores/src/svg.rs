//! SVG cross-sections of 2D structures: the part's section filled, the
//! pores drawn over it exactly (each pore's four quadratic Bezier arcs as
//! SVG `Q` commands, clipped to its cell).

use crate::build::{Built, PoreShape};
use crate::error::PoreError;
use microfrep_core::{Expr, Shape};
use microfrep_fab::contour::contours;
use microfrep_fab::{rasterize_at, SliceGrid};
use std::fmt::Write;

/// The section at height `z` of the part minus the 2D pores of `built`, in
/// model units (y up): the part's outline traced at `pixel`, the pores
/// exact. `bounds` is the xy window.
pub fn section_svg(
    built: &Built,
    part: &Expr,
    bounds: [[f64; 2]; 2],
    z: f64,
    pixel: f64,
) -> Result<String, PoreError> {
    let [lo, hi] = bounds;
    let grid = SliceGrid::new(
        [lo[0], lo[1], z - 0.5 * pixel],
        [hi[0], hi[1], z + 0.5 * pixel],
        pixel,
        pixel,
    )
    .map_err(PoreError::Section)?;
    let tape = Shape::from(part);
    let layer = rasterize_at(&tape, &grid, z);
    let outline = contours(&tape, &grid, &layer);
    let (w, h) = (hi[0] - lo[0], hi[1] - lo[1]);
    let mut s = String::new();
    let _ = writeln!(s, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="{} {} {w} {h}">"#,
        lo[0], -hi[1]
    );
    let _ = writeln!(
        s,
        "<desc>Kou-Tan pores, section z={z}: {} pores in {} cells</desc>",
        built.pores,
        built.cells.len()
    );
    let _ = writeln!(s, r#"<g transform="scale(1,-1)">"#);
    let _ = write!(s, r#"<path fill="black" fill-rule="nonzero" d=""#);
    for p in &outline {
        for (k, v) in p.iter().enumerate() {
            let _ = write!(s, "{}{} {} ", if k == 0 { 'M' } else { 'L' }, v[0], v[1]);
        }
        let _ = write!(s, "Z ");
    }
    let _ = writeln!(s, r#""/>"#);
    let _ = writeln!(s, "<defs>");
    for (i, c) in built.cells.iter().enumerate() {
        if matches!(c.shape, PoreShape::Two { .. }) {
            let _ = writeln!(
                s,
                r#"<clipPath id="c{i}"><rect x="{}" y="{}" width="{}" height="{}"/></clipPath>"#,
                c.cell.lo[0],
                c.cell.lo[1],
                c.cell.hi[0] - c.cell.lo[0],
                c.cell.hi[1] - c.cell.lo[1]
            );
        }
    }
    let _ = writeln!(s, "</defs>");
    for (i, c) in built.cells.iter().enumerate() {
        if let PoreShape::Two { arcs, .. } = &c.shape {
            let _ = write!(
                s,
                r#"<path fill="white" clip-path="url(#c{i})" d="M{} {} "#,
                arcs[0].p[0][0], arcs[0].p[0][1]
            );
            for a in arcs {
                // SVG has no rational arcs: a weighted arc is drawn as 16
                // polynomial pieces on the control points of its parts
                // (well under a thousandth of the cell off the curve).
                let pieces = if a.w == 1.0 { 1 } else { 16 };
                for k in 0..pieces {
                    let q = if pieces == 1 {
                        *a
                    } else {
                        a.sub(k as f64 / pieces as f64, (k + 1) as f64 / pieces as f64)
                    };
                    let _ = write!(
                        s,
                        "Q{} {} {} {} ",
                        q.p[1][0], q.p[1][1], q.p[2][0], q.p[2][1]
                    );
                }
            }
            let _ = writeln!(s, r#"Z"/>"#);
        }
    }
    let _ = writeln!(s, "</g>\n</svg>");
    Ok(s)
}
