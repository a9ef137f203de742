//! Ray-cast images: hits shaded Lambert plus ambient from the gradient, in
//! one surface colour ([`ray_cast`]) or coloured by an attribute channel
//! at the hit point ([`ray_cast_attribute`], with a legend).

use crate::camera::{dot, normalize, Camera, View};
use crate::error::{RenderError, Result};
use crate::image::RgbImage;
use crate::legend;
use crate::trace::Tracer;
use microfrep_core::{GradEval, PointEval, Shape, Tape};
use microfrep_io::colormap::{Colormap, ColourScale};
use rayon::prelude::*;

/// Side of the screen tiles traced as one task.
const TILE: usize = 16;
pub(crate) const BACKGROUND: [u8; 3] = [250, 250, 250];
const SURFACE: [f64; 3] = [0.85, 0.62, 0.35];
const AMBIENT: f64 = 0.25;
const GIB: f64 = (1u64 << 30) as f64;

/// What a ray found at one pixel: the light's intensity there (ambient
/// plus Lambert, 0.25..1) and the attribute's value (NaN without one).
#[derive(Clone, Copy)]
struct Hit {
    light: f64,
    value: f64,
}

/// Ray casts the model inside the box `min`..`max` with `cam`; tiles in
/// parallel, same bytes every run. The interval search is tight through
/// the model's set operations, which are nodes of its tape.
pub fn ray_cast(shape: &Shape, cam: &Camera, min: [f64; 3], max: [f64; 3]) -> RgbImage {
    let px = trace(shape, cam, min, max, None, |h| match h {
        None => BACKGROUND,
        Some(h) => SURFACE.map(|c| (255.0 * c * h.light).round().clamp(0.0, 255.0) as u8),
    });
    RgbImage {
        width: cam.width,
        height: cam.height,
        data: px.into_iter().flatten().collect(),
    }
}

/// How [`ray_cast_attribute`] colours the surface.
#[derive(Clone, Debug, PartialEq)]
pub struct AttributeShading {
    /// The channel: a 0-based index into [`Shape::attributes`].
    pub channel: usize,
    /// The colour map.
    pub colormap: Colormap,
    /// Values of the map's first and last colour; `None`: the smallest and
    /// largest finite value over the visible surface (see
    /// [`ColourScale::over`]).
    pub range: Option<[f64; 2]>,
    /// Draw a legend (a colour bar with the range's ends) in a strip on
    /// the right; left out of images too small to hold one (under
    /// [`legend::MIN_WIDTH`] x [`legend::MIN_HEIGHT`]).
    pub legend: bool,
}

/// An image coloured by an attribute, with what it shows.
#[derive(Clone, Debug, PartialEq)]
pub struct AttributeImage {
    /// The image, of the size asked for.
    pub image: RgbImage,
    /// The colour scale used.
    pub scale: ColourScale,
    /// The legend's colour bar, `[x, y, width, height]` in pixels (its top
    /// row is the range's high end), where one was drawn.
    pub bar: Option<[usize; 4]>,
}

/// Ray casts the model seen from `view` inside the box `min`..`max` into a
/// `width x height` image, each hit coloured by attribute channel
/// `opts.channel` at the hit point (f64) through the colour scale, times
/// the lighting of [`ray_cast`]; undefined (NaN) values are magenta. With
/// a legend, the model is framed in the image less the legend's strip.
pub fn ray_cast_attribute(
    shape: &Shape,
    view: View,
    min: [f64; 3],
    max: [f64; 3],
    width: usize,
    height: usize,
    opts: &AttributeShading,
) -> Result<AttributeImage> {
    crate::camera::check_size(width, height)?;
    let attrs = shape.attributes();
    let channel = attrs.get(opts.channel).ok_or_else(|| {
        RenderError::Invalid(format!(
            "attribute {} does not exist: the model has {} attribute channel(s)",
            opts.channel + 1,
            attrs.len()
        ))
    })?;
    let given = match opts.range {
        Some([lo, hi]) => {
            Some(ColourScale::new(opts.colormap, lo, hi).map_err(RenderError::Invalid)?)
        }
        None => None,
    };
    let strip = if opts.legend {
        legend::strip_width(width, height)
    } else {
        None
    };
    // Per pixel: the hits of the tiles and of the image (8 bytes each),
    // and the image.
    let bytes = 19.0 * width as f64 * height as f64;
    if let Some(m) = microfrep_io::limits::memory_limit().filter(|&m| bytes > m) {
        return Err(RenderError::Invalid(format!(
            "an attribute image of {width}x{height} needs about {:.1} GiB, {:.1} GiB are \
             available; choose a smaller --size",
            bytes / GIB,
            m / GIB
        )));
    }
    let inner = width - strip.unwrap_or(0);
    let cam = Camera::fit(view, min, max, inner, height);
    let tape = Tape::new(&channel.expr);
    // Light and value in f32; no hit: light NaN.
    let hits = trace(shape, &cam, min, max, Some(&tape), |h| match h {
        None => [f32::NAN; 2],
        Some(h) => [h.light as f32, h.value as f32],
    });
    let scale = given.unwrap_or_else(|| {
        ColourScale::over(
            opts.colormap,
            hits.iter().filter(|h| !h[0].is_nan()).map(|h| h[1] as f64),
        )
    });
    let mut data = vec![0u8; 3 * width * height];
    for (row, out) in hits.chunks(inner).zip(data.chunks_mut(3 * width)) {
        for (h, px) in row.iter().zip(out.chunks_exact_mut(3)) {
            let c = match h {
                [l, _] if l.is_nan() => BACKGROUND,
                [l, v] => scale
                    .colour(*v as f64)
                    .map(|c| (c as f64 * *l as f64).round().clamp(0.0, 255.0) as u8),
            };
            px.copy_from_slice(&c);
        }
    }
    let mut image = RgbImage {
        width,
        height,
        data,
    };
    let bar = strip.map(|s| legend::draw(&mut image, inner, s, &scale));
    Ok(AttributeImage { image, scale, bar })
}

/// `f` of the hit of every pixel of `cam`, rows top first; the value of
/// `channel` at each hit where one is given.
fn trace<T: Copy + Default + Send>(
    shape: &Shape,
    cam: &Camera,
    min: [f64; 3],
    max: [f64; 3],
    channel: Option<&Tape>,
    f: impl Fn(Option<Hit>) -> T + Sync,
) -> Vec<T> {
    let tape = shape.tape();
    let (w, h) = (cam.width, cam.height);
    // Light from over the viewer's left shoulder.
    let light = normalize([0, 1, 2].map(|a| -cam.dir[a] + 0.6 * cam.up[a] - 0.4 * cam.right[a]));
    let tiles: Vec<(usize, usize)> = (0..h)
        .step_by(TILE)
        .flat_map(|y| (0..w).step_by(TILE).map(move |x| (x, y)))
        .collect();
    let shaded: Vec<Vec<T>> = tiles
        .par_iter()
        .map_init(
            || {
                (
                    Tracer::new(tape, cam, min, max),
                    GradEval::new(tape),
                    channel.map(PointEval::new),
                )
            },
            |(tr, ge, ch), &(x0, y0)| {
                let (tw, th) = (TILE.min(w - x0), TILE.min(h - y0));
                tr.start_tile();
                let depths = tr.tile(x0, y0, tw, th);
                (0..tw * th)
                    .map(|k| {
                        let Some(t) = depths[k] else {
                            return f(None);
                        };
                        let (u, v) = cam.screen((x0 + k % tw) as f64, (y0 + k / tw) as f64);
                        let p = cam.point(u, v, t);
                        let (_, g) = ge.eval(p);
                        // Inside is f >= 0, so the outward normal is -grad f.
                        let n = [-g[0], -g[1], -g[2]];
                        let len = dot(n, n).sqrt();
                        let lambert = if len > 0.0 && len.is_finite() {
                            // Two-sided, so cut faces seen from behind still show.
                            (dot(n, light) / len).abs()
                        } else {
                            0.0
                        };
                        f(Some(Hit {
                            light: AMBIENT + (1.0 - AMBIENT) * lambert,
                            value: ch.as_mut().map_or(f64::NAN, |e| e.eval(p)),
                        }))
                    })
                    .collect()
            },
        )
        .collect();
    let mut hits = vec![T::default(); w * h];
    for (&(x0, y0), px) in tiles.iter().zip(&shaded) {
        let tw = TILE.min(w - x0);
        for (k, c) in px.iter().enumerate() {
            hits[(y0 + k / tw) * w + x0 + k % tw] = *c;
        }
    }
    hits
}
