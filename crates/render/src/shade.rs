//! Ray-cast images: hits shaded Lambert plus ambient from the gradient.

use crate::camera::{dot, normalize, Camera};
use crate::image::RgbImage;
use crate::trace::Tracer;
use microfrep_core::{GradEval, Shape};
use rayon::prelude::*;

/// Side of the screen tiles traced as one task.
const TILE: usize = 16;
const BACKGROUND: [u8; 3] = [250, 250, 250];
const SURFACE: [f64; 3] = [0.85, 0.62, 0.35];
const AMBIENT: f64 = 0.25;

/// Ray casts the model inside the box `min`..`max` with `cam`; tiles in
/// parallel, same bytes every run. The interval search is tight through
/// the model's set operations, which are nodes of its tape.
pub fn ray_cast(shape: &Shape, cam: &Camera, min: [f64; 3], max: [f64; 3]) -> RgbImage {
    let tape = shape.tape();
    let (w, h) = (cam.width, cam.height);
    // Light from over the viewer's left shoulder.
    let light = normalize([0, 1, 2].map(|a| -cam.dir[a] + 0.6 * cam.up[a] - 0.4 * cam.right[a]));
    let tiles: Vec<(usize, usize)> = (0..h)
        .step_by(TILE)
        .flat_map(|y| (0..w).step_by(TILE).map(move |x| (x, y)))
        .collect();
    let shaded: Vec<Vec<[u8; 3]>> = tiles
        .par_iter()
        .map_init(
            || (Tracer::new(tape, cam, min, max), GradEval::new(tape)),
            |(tr, ge), &(x0, y0)| {
                let (tw, th) = (TILE.min(w - x0), TILE.min(h - y0));
                tr.start_tile();
                let depths = tr.tile(x0, y0, tw, th);
                (0..tw * th)
                    .map(|k| {
                        let Some(t) = depths[k] else {
                            return BACKGROUND;
                        };
                        let (u, v) = cam.screen((x0 + k % tw) as f64, (y0 + k / tw) as f64);
                        let (_, g) = ge.eval(cam.point(u, v, t));
                        // Inside is f >= 0, so the outward normal is -grad f.
                        let n = [-g[0], -g[1], -g[2]];
                        let len = dot(n, n).sqrt();
                        let lambert = if len > 0.0 && len.is_finite() {
                            // Two-sided, so cut faces seen from behind still show.
                            (dot(n, light) / len).abs()
                        } else {
                            0.0
                        };
                        let i = AMBIENT + (1.0 - AMBIENT) * lambert;
                        SURFACE.map(|c| (255.0 * c * i).round().clamp(0.0, 255.0) as u8)
                    })
                    .collect()
            },
        )
        .collect();
    let mut data = vec![0u8; 3 * w * h];
    for (&(x0, y0), px) in tiles.iter().zip(&shaded) {
        let tw = TILE.min(w - x0);
        for (k, c) in px.iter().enumerate() {
            let (x, y) = (x0 + k % tw, y0 + k / tw);
            data[3 * (y * w + x)..3 * (y * w + x) + 3].copy_from_slice(c);
        }
    }
    RgbImage {
        width: w,
        height: h,
        data,
    }
}
