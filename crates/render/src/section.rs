//! Section images: the model's value on an axis-aligned plane, coloured with
//! a diverging map (blue outside, white at zero, red inside) and the zero
//! contour drawn in black.

use crate::error::{RenderError, Result};
use crate::image::RgbImage;
use microfrep_core::{BatchEval, Shape};
use rayon::prelude::*;

/// An axis-aligned plane `axis = value` (axis 0, 1, 2 for x, y, z).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    /// Axis the plane is normal to: 0, 1, 2 for x, y, z.
    pub axis: usize,
    /// Coordinate of the plane on that axis, mm.
    pub value: f64,
}

impl std::str::FromStr for Plane {
    type Err = RenderError;
    /// `x=0.5`, `y=-1`, `z=0`.
    fn from_str(s: &str) -> Result<Plane> {
        let bad = || RenderError::Invalid(format!("section '{s}': expected x=V, y=V or z=V"));
        let (a, v) = s.split_once('=').ok_or_else(bad)?;
        let axis = match a.trim() {
            "x" => 0,
            "y" => 1,
            "z" => 2,
            _ => return Err(bad()),
        };
        let value: f64 = v.trim().parse().map_err(|_| bad())?;
        if !value.is_finite() {
            return Err(bad());
        }
        Ok(Plane { axis, value })
    }
}

/// Screen axes of a section: (right, up).
fn screen_axes(axis: usize) -> (usize, usize) {
    match axis {
        0 => (1, 2),
        1 => (0, 2),
        _ => (0, 1),
    }
}

/// The section of the box `min`..`max` by `plane`, fitted into the image.
pub fn section(
    shape: &Shape,
    plane: Plane,
    min: [f64; 3],
    max: [f64; 3],
    w: usize,
    h: usize,
) -> RgbImage {
    let (ra, ua) = screen_axes(plane.axis);
    let scale = ((max[ra] - min[ra]) / w as f64).max((max[ua] - min[ua]) / h as f64);
    let cu = 0.5 * (min[ra] + max[ra]);
    let cv = 0.5 * (min[ua] + max[ua]);
    let mut vals = vec![0f32; w * h];
    vals.par_chunks_mut(w).enumerate().for_each_init(
        || BatchEval::new(shape.tape()),
        |ev, (y, row)| {
            let mut p = [vec![0f32; w], vec![0f32; w], vec![0f32; w]];
            let v = cv + (0.5 * h as f64 - y as f64 - 0.5) * scale;
            for (x, u) in p[ra].iter_mut().enumerate() {
                *u = (cu + (x as f64 + 0.5 - 0.5 * w as f64) * scale) as f32;
            }
            p[ua].fill(v as f32);
            p[plane.axis].fill(plane.value as f32);
            ev.eval(&p[0], &p[1], &p[2], row);
        },
    );
    // Colour scale: the largest finite magnitude, so the map uses its range.
    let m = vals
        .iter()
        .filter(|v| v.is_finite())
        .fold(0f32, |a, v| a.max(v.abs()));
    let m = if m > 0.0 { m } else { 1.0 };
    let mut data = Vec::with_capacity(3 * w * h);
    for y in 0..h {
        for x in 0..w {
            let f = vals[y * w + x];
            let inside = f >= 0.0;
            // Zero contour: a sign change to the right or below.
            let edge = (x + 1 < w && (vals[y * w + x + 1] >= 0.0) != inside)
                || (y + 1 < h && (vals[(y + 1) * w + x] >= 0.0) != inside);
            let c = if edge {
                [0, 0, 0]
            } else if f.is_nan() {
                [128, 128, 128]
            } else {
                diverging((f / m).clamp(-1.0, 1.0) as f64)
            };
            data.extend_from_slice(&c);
        }
    }
    RgbImage {
        width: w,
        height: h,
        data,
    }
}

/// Blue (-1) through white (0) to red (+1).
fn diverging(s: f64) -> [u8; 3] {
    let (lo, hi) = ([59.0, 76.0, 192.0], [180.0, 4.0, 38.0]);
    let end = if s < 0.0 { lo } else { hi };
    let a = s.abs();
    [0, 1, 2].map(|k| (255.0 + (end[k] - 255.0) * a).round() as u8)
}
