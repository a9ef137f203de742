//! Orthographic cameras fitted to a bounding box.

use crate::error::{RenderError, Result};

/// A 3-vector in world coordinates.
pub type V3 = [f64; 3];

/// Dot product.
pub fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Cross product `a x b`.
pub fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// `a` scaled to unit length (NaN components for the zero vector).
pub fn normalize(a: V3) -> V3 {
    let l = dot(a, a).sqrt();
    [a[0] / l, a[1] / l, a[2] / l]
}

/// Where the camera looks from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum View {
    /// From (+x, -y, +z), z up.
    Iso,
    /// From -y, z up, x to the right.
    Front,
    /// From +z, y up, x to the right.
    Top,
    /// From +x, z up, y to the right.
    Side,
}

impl std::str::FromStr for View {
    type Err = RenderError;
    fn from_str(s: &str) -> Result<View> {
        match s {
            "iso" => Ok(View::Iso),
            "front" => Ok(View::Front),
            "top" => Ok(View::Top),
            "side" => Ok(View::Side),
            _ => Err(RenderError::Invalid(format!(
                "unknown view '{s}' (iso, front, top, side)"
            ))),
        }
    }
}

impl View {
    /// Direction the rays travel and the screen's up vector.
    fn axes(self) -> (V3, V3) {
        match self {
            View::Iso => {
                let d = normalize([-1.0, 1.0, -1.0]);
                let up = [0.0, 0.0, 1.0];
                let k = dot(up, d);
                (d, normalize([-k * d[0], -k * d[1], 1.0 - k * d[2]]))
            }
            View::Front => ([0.0, 1.0, 0.0], [0.0, 0.0, 1.0]),
            View::Top => ([0.0, 0.0, -1.0], [0.0, 1.0, 0.0]),
            View::Side => ([-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
        }
    }
}

/// Parallel rays, one per pixel centre: ray `(px, py)` (row 0 at the top)
/// starts at `origin(px, py)` and runs along `dir` for `depth`.
#[derive(Clone, Debug)]
pub struct Camera {
    /// Unit direction the rays travel (into the screen).
    pub dir: V3,
    /// Unit world direction of the screen's +x (to the right).
    pub right: V3,
    /// Unit world direction of the screen's +y (up).
    pub up: V3,
    /// Centre of the image on the near plane.
    pub eye: V3,
    /// World size of a pixel.
    pub scale: f64,
    /// Length of each ray from the near plane, world units.
    pub depth: f64,
    /// Image width in pixels.
    pub width: usize,
    /// Image height in pixels.
    pub height: usize,
}

impl Camera {
    /// Frames the box `min`..`max` (with a small margin) in a `width x height` image.
    pub fn fit(view: View, min: V3, max: V3, width: usize, height: usize) -> Camera {
        let (dir, up) = view.axes();
        let right = cross(dir, up);
        let c = [0, 1, 2].map(|a| 0.5 * (min[a] + max[a]));
        let (mut eu, mut ev, mut r) = (0.0f64, 0.0f64, 0.0f64);
        for k in 0..8 {
            let p = [0, 1, 2].map(|a| if k >> a & 1 == 1 { max[a] } else { min[a] });
            let d = [p[0] - c[0], p[1] - c[1], p[2] - c[2]];
            eu = eu.max(dot(d, right).abs());
            ev = ev.max(dot(d, up).abs());
            r = r.max(dot(d, d).sqrt());
        }
        let margin = 1.05;
        let scale = margin * (2.0 * eu / width as f64).max(2.0 * ev / height as f64);
        let back = margin * r;
        Camera {
            dir,
            right,
            up,
            eye: [0, 1, 2].map(|a| c[a] - back * dir[a]),
            scale,
            depth: 2.0 * back,
            width,
            height,
        }
    }

    /// Screen coordinates (world units) of the centre of pixel `(px, py)`.
    pub fn screen(&self, px: f64, py: f64) -> (f64, f64) {
        (
            (px + 0.5 - 0.5 * self.width as f64) * self.scale,
            (0.5 * self.height as f64 - py - 0.5) * self.scale,
        )
    }

    /// The world point at screen `(u, v)` and depth `t`.
    pub fn point(&self, u: f64, v: f64, t: f64) -> V3 {
        [0, 1, 2].map(|a| self.eye[a] + u * self.right[a] + v * self.up[a] + t * self.dir[a])
    }
}

/// Checks an image size: both sides positive and at most 16384.
pub fn check_size(width: usize, height: usize) -> Result<()> {
    if width == 0 || height == 0 || width > 16384 || height > 16384 {
        return Err(RenderError::Invalid(format!(
            "image size {width}x{height}: each side must be 1..=16384"
        )));
    }
    Ok(())
}
