//! Layer contours: marching squares over the pixel-centre grid, vertices
//! refined on the cell edges, segments joined into closed loops.
//!
//! Loops run with the solid on their left, so outer boundaries are
//! counter-clockwise and holes clockwise (x right, y up). Diagonal pairs of
//! inside pixels are joined (8-connected solid, 4-connected empty space), the
//! same rule a flood fill must use to count the same components. The image is
//! padded with empty pixels, so loops of a solid cut by the bounds close along
//! the bounds.

use crate::grid::SliceGrid;
use crate::raster::LayerValues;
use microfrep_core::{PointEval, Shape};
use std::collections::HashMap;

/// Illinois steps per vertex: enough for about 1e-7 pixel on smooth edges.
const REFINE_STEPS: usize = 8;

/// A closed polygon, first vertex not repeated.
pub type Polygon = Vec<[f64; 2]>;

/// Edge key: horizontal edges join pixel (i, j) to (i + 1, j), vertical ones
/// (i, j) to (i, j + 1); indices are shifted by one for the padding.
fn key(i: i64, j: i64, vertical: bool) -> u64 {
    (((i + 1) as u64) << 33) | (((j + 1) as u64) << 1) | vertical as u64
}

fn unkey(k: u64) -> (i64, i64, bool) {
    (
        (k >> 33) as i64 - 1,
        ((k >> 1) & 0xffff_ffff) as i64 - 1,
        k & 1 == 1,
    )
}

/// Closed loops of the layer's zero set, solid on the left.
pub fn contours(shape: &Shape, grid: &SliceGrid, layer: &LayerValues) -> Vec<Polygon> {
    let (nx, ny) = (layer.nx as i64, layer.ny as i64);
    let inside = |i: i64, j: i64| -> bool {
        i >= 0 && j >= 0 && i < nx && j < ny && layer.inside(i as usize, j as usize)
    };
    // next[e] = the edge the contour leaves through after entering at e.
    let mut next: HashMap<u64, u64> = HashMap::new();
    let mut starts = Vec::new();
    for cj in -1..ny {
        for ci in -1..nx {
            let c = [
                inside(ci, cj),
                inside(ci + 1, cj),
                inside(ci + 1, cj + 1),
                inside(ci, cj + 1),
            ];
            if c.iter().all(|&b| b == c[0]) {
                continue;
            }
            // Cell edges in counter-clockwise order: edge k runs from corner
            // k to corner k + 1.
            let e = [
                key(ci, cj, false),
                key(ci + 1, cj, true),
                key(ci, cj + 1, false),
                key(ci, cj, true),
            ];
            for k in 0..4 {
                if c[k] && !c[(k + 1) % 4] {
                    // Walking the cell boundary counter-clockwise, the solid
                    // ends on edge k and starts again on edge m: the segment
                    // k -> m has the solid corner k on its left.
                    let m = (1..4)
                        .map(|d| (k + d) % 4)
                        .find(|&m| !c[m] && c[(m + 1) % 4])
                        .expect("a crossing into the solid follows one out of it");
                    next.insert(e[k], e[m]);
                    starts.push(e[k]);
                }
            }
        }
    }
    let mut pe = PointEval::new(shape.tape());
    let mut loops = Vec::new();
    for s in starts {
        if !next.contains_key(&s) {
            continue;
        }
        let mut poly = Vec::new();
        let mut cur = s;
        while let Some(n) = next.remove(&cur) {
            poly.push(vertex(&mut pe, grid, layer, cur));
            cur = n;
        }
        loops.push(poly);
    }
    loops
}

/// The zero crossing on an edge: on the bounds for padding pixels, else
/// interpolated from the samples and refined by Illinois steps.
fn vertex(pe: &mut PointEval, grid: &SliceGrid, layer: &LayerValues, e: u64) -> [f64; 2] {
    let (i, j, vertical) = unkey(e);
    let (i2, j2) = if vertical { (i, j + 1) } else { (i + 1, j) };
    let real = |i: i64, j: i64| i >= 0 && j >= 0 && i < layer.nx as i64 && j < layer.ny as i64;
    let centre = |i: i64, j: i64| {
        [
            grid.min[0] + (i as f64 + 0.5) * grid.pixel,
            grid.min[1] + (j as f64 + 0.5) * grid.pixel,
        ]
    };
    let (pa, pb) = (centre(i, j), centre(i2, j2));
    if !real(i, j) || !real(i2, j2) {
        return [0.5 * (pa[0] + pb[0]), 0.5 * (pa[1] + pb[1])];
    }
    let z = layer.z;
    let mut value = |p: [f64; 2]| pe.eval([p[0], p[1], z]);
    let sample = |i: i64, j: i64| layer.at(i as usize, j as usize) as f64;
    let mut fa = sample(i, j);
    let mut fb = sample(i2, j2);
    if fa.is_infinite() {
        fa = value(pa);
    }
    if fb.is_infinite() {
        fb = value(pb);
    }
    let at = |t: f64| [pa[0] + t * (pb[0] - pa[0]), pa[1] + t * (pb[1] - pa[1])];
    let (mut ta, mut tb) = (0.0, 1.0);
    let mut t = 0.5;
    for _ in 0..REFINE_STEPS {
        t = if fa.is_finite() && fb.is_finite() && fa != fb {
            (ta - fa * (tb - ta) / (fb - fa)).clamp(ta, tb)
        } else {
            0.5 * (ta + tb)
        };
        let fm = value(at(t));
        if fm == 0.0 || !fm.is_finite() {
            break;
        }
        if (fm >= 0.0) == (fa >= 0.0) {
            ta = t;
            fa = fm;
            fb *= 0.5;
        } else {
            tb = t;
            fb = fm;
            fa *= 0.5;
        }
    }
    at(t)
}

/// Twice the signed area: positive for counter-clockwise loops.
pub fn signed_area(p: &[[f64; 2]]) -> f64 {
    let n = p.len();
    (0..n)
        .map(|k| {
            let (a, b) = (p[k], p[(k + 1) % n]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum::<f64>()
        * 0.5
}
