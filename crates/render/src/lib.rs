//! Direct rendering of FRep models, no mesh: orthographic ray casting with
//! interval-arithmetic root finding, cut-away views and section images.
//!
//! [`ray_cast`] shades what a [`Camera`] sees of a model inside a box;
//! [`ray_cast_attribute`] colours the same surface by an attribute channel
//! through a [`Colormap`], with a [`legend`];
//! [`cutaway`] opens the octant nearest the viewer first, [`section()`]
//! maps the model's value on a plane to colour, and [`section_image`]
//! colours a plane by an attribute (the material) or the value, with a
//! legend and a scale bar in model units. Images are [`RgbImage`]s,
//! written with [`RgbImage::save_png`]. The same model, box and size give
//! the same bytes on every run.
//!
//! ```
//! use microfrep_core::{Expr, Shape};
//! use microfrep_render::{ray_cast, section, Camera, Plane, View};
//!
//! let [x, y, z] = Expr::xyz();
//! let ball = Shape::new(1.0 - (x.square() + y.square() + z.square()));
//! let (min, max) = ([-1.2; 3], [1.2; 3]);
//!
//! // Seen from above, the middle pixel shows the ball, a corner the background.
//! let cam = Camera::fit(View::Top, min, max, 32, 32);
//! let img = ray_cast(&ball, &cam, min, max);
//! assert_eq!(img.pixel(0, 0), [250, 250, 250]);
//! assert_ne!(img.pixel(16, 16), [250, 250, 250]);
//!
//! // The section z = 0: red inside (f > 0), blue outside.
//! let plane: Plane = "z=0".parse().unwrap();
//! let sec = section(&ball, plane, min, max, 32, 32);
//! let [r, _, b] = sec.pixel(16, 16);
//! assert!(r > b);
//! let [r, _, b] = sec.pixel(0, 0);
//! assert!(b > r);
//! ```

#![warn(missing_docs)]

pub mod camera;
mod error;
pub mod image;
pub mod legend;
pub mod section;
pub mod shade;
pub mod trace;

pub use camera::{Camera, View};
pub use error::{RenderError, Result};
pub use image::RgbImage;
pub use microfrep_io::colormap::{Colormap, ColourScale};
pub use section::{section, section_image, Plane, ScaleBar, SectionImage, SectionShading};
pub use shade::{ray_cast, ray_cast_attribute, AttributeImage, AttributeShading};

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
