//! Direct rendering of FRep models, no mesh: orthographic ray casting with
//! interval-arithmetic root finding, cut-away views and section images.

pub mod camera;
mod error;
pub mod image;
pub mod section;
pub mod shade;
pub mod trace;

pub use camera::{Camera, View};
pub use error::{RenderError, Result};
pub use image::RgbImage;
pub use section::{section, Plane};
pub use shade::ray_cast;

use microfrep_core::{Expr, Shape};

/// The model with the octant of the box `min`..`max` nearest the viewer
/// removed (intersection with the complement of that octant), so the inside
/// shows. Exact min/max, so the cut faces are planar.
pub fn cutaway(model: &Shape, view: View, min: [f64; 3], max: [f64; 3]) -> Shape {
    let cam = Camera::fit(view, min, max, 1, 1);
    let p = Expr::xyz();
    let keep: Vec<Expr> = (0..3)
        .map(|a| {
            let c = 0.5 * (min[a] + max[a]);
            // The viewer is on the side opposite the ray direction.
            if cam.dir[a] <= 0.0 {
                c - &p[a]
            } else {
                &p[a] - c
            }
        })
        .collect();
    model.map(|m| m.min(keep[0].max(&keep[1]).max(&keep[2])))
}
