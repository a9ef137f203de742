//! Anti-aliasing: the fraction of each pixel's square covered by the solid,
//! from the value and gradient at its centre (the surface taken as the
//! straight line `f + g.(p - c) = 0` across the pixel).

use crate::raster::LayerValues;
use microfrep_core::{GradEval, Shape};
use rayon::prelude::*;

/// Area fraction of the square `[-h/2, h/2]^2` where `f + g.d >= 0`, exact
/// for a linear function.
pub fn box_coverage(f: f64, g: [f64; 2], h: f64) -> f64 {
    let (a, b) = {
        let (u, v) = (g[0].abs() * h, g[1].abs() * h);
        if u >= v {
            (u, v)
        } else {
            (v, u)
        }
    };
    // Over the square, g.d spans [-(a+b)/2, (a+b)/2]; s measures how far the
    // level f + g.d = 0 is from the corner where f + g.d is smallest.
    let s = f + 0.5 * (a + b);
    if s.is_nan() || s <= 0.0 {
        return if f >= 0.0 && a == 0.0 { 1.0 } else { 0.0 };
    }
    if s >= a + b {
        return 1.0;
    }
    if s < b {
        s * s / (2.0 * a * b)
    } else if s <= a {
        (s - 0.5 * b) / a
    } else {
        1.0 - (a + b - s) * (a + b - s) / (2.0 * a * b)
    }
}

/// 8-bit coverage of every pixel of a layer (row 0 at the lowest y).
/// Pixels far from the surface by a finite-difference estimate take their
/// centre's side; near ones get the exact gradient and [`box_coverage`].
pub fn coverage(shape: &Shape, layer: &LayerValues, pixel: f64, min: [f64; 2]) -> Vec<u8> {
    let nx = layer.nx;
    let mut out = vec![0u8; nx * layer.ny];
    out.par_chunks_mut(nx).enumerate().for_each_init(
        || GradEval::new(shape.tape()),
        |ge, (j, row)| {
            for (i, px) in row.iter_mut().enumerate() {
                let v = layer.at(i, j);
                let c = if v.is_infinite() || !near(layer, i, j) {
                    if v >= 0.0 {
                        1.0
                    } else {
                        0.0
                    }
                } else {
                    let p = [
                        min[0] + (i as f64 + 0.5) * pixel,
                        min[1] + (j as f64 + 0.5) * pixel,
                        layer.z,
                    ];
                    let (f, g) = ge.eval(p);
                    box_coverage(f, [g[0], g[1]], pixel)
                };
                *px = (c * 255.0).round() as u8;
            }
        },
    );
    out
}

/// Whether the surface may pass within the pixel: the value is small
/// against the change to the neighbours, or a neighbour is on the other side.
fn near(layer: &LayerValues, i: usize, j: usize) -> bool {
    let v = layer.at(i, j) as f64;
    let mut slope: f64 = 0.0;
    let nb = [
        (i.wrapping_sub(1), j),
        (i + 1, j),
        (i, j.wrapping_sub(1)),
        (i, j + 1),
    ];
    for (a, b) in nb {
        if a >= layer.nx || b >= layer.ny {
            continue;
        }
        let w = layer.at(a, b) as f64;
        if (w >= 0.0) != (v >= 0.0) || w.is_infinite() {
            return true;
        }
        slope = slope.max((w - v).abs());
    }
    // The value changes by about `slope` per pixel; the surface is within
    // the pixel's half diagonal when |v| < 0.71 slope; the margin covers
    // curvature.
    v.abs() <= 1.5 * slope || v == 0.0
}

#[cfg(test)]
mod tests {
    use super::box_coverage;

    #[test]
    fn axis_aligned_edge_is_linear() {
        // g = (1, 0): the covered part is a strip of width h/2 + f.
        for f in [-0.6, -0.5, -0.2, 0.0, 0.3, 0.5, 0.7] {
            let c = box_coverage(f, [1.0, 0.0], 1.0);
            assert!((c - (0.5 + f).clamp(0.0, 1.0)).abs() < 1e-12, "f={f}: {c}");
        }
    }

    #[test]
    fn diagonal_edge_matches_triangle_areas() {
        // g = (1, 1): a = b = h; the corner triangle has area s^2 / 2.
        let c = box_coverage(-0.5, [1.0, 1.0], 1.0);
        assert!((c - 0.125).abs() < 1e-12);
        for f in [-0.9, -0.4, -0.1, 0.0, 0.2, 0.8] {
            let g = [0.6, 0.8];
            let sum = box_coverage(f, g, 1.0) + box_coverage(-f, [-g[0], -g[1]], 1.0);
            assert!((sum - 1.0).abs() < 1e-12, "complement at f={f}");
        }
        assert_eq!(box_coverage(0.0, [0.3, -0.7], 1.0), 0.5);
    }
}
