//! Section images: the model on an axis-aligned plane. [`section_image`]
//! colours it by an attribute (a material fraction) or by the value through
//! a [`Colormap`], with a legend and a scale bar in model units;
//! [`section()`] is the plain value image, a diverging map (blue outside,
//! white at zero, red inside). Both draw the zero contour in black.

use crate::error::{RenderError, Result};
use crate::image::RgbImage;
use crate::legend;
use crate::shade::BACKGROUND;
use microfrep_core::{BatchEval, Shape};
use microfrep_io::colormap::{Colormap, ColourScale, NAN_COLOUR};
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

/// What a coloured section shows and how ([`section_image`]).
#[derive(Clone, Debug, PartialEq)]
pub struct SectionShading {
    /// The attribute channel (0-based index into [`Shape::attributes`])
    /// shown inside the part, outside the background; `None`: the value
    /// itself, everywhere, over a range symmetric about 0 (so the map's
    /// middle colour is the surface).
    pub channel: Option<usize>,
    /// The colour map.
    pub colormap: Colormap,
    /// The values of the map's ends (default: the smallest and largest
    /// value over the shown pixels; for the value, `-m..m` with `m` the
    /// largest magnitude).
    pub range: Option<[f64; 2]>,
    /// A legend (colour bar and the range's ends) in a strip on the right
    /// and a scale bar in model units under the section; left out of
    /// images too small to hold them (under [`legend::MIN_WIDTH`] x
    /// [`legend::MIN_HEIGHT`]).
    pub legend: bool,
}

/// A section's scale bar: a horizontal bar of a round length in model
/// units, its length printed above it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScaleBar {
    /// Left end, pixels from the image's left edge.
    pub x: usize,
    /// Top row of the bar.
    pub y: usize,
    /// Length in pixels.
    pub width: usize,
    /// Thickness in pixels.
    pub height: usize,
    /// Length in model units (1, 2 or 5 times a power of ten).
    pub length: f64,
}

/// A coloured section and what it shows.
#[derive(Clone, Debug, PartialEq)]
pub struct SectionImage {
    /// The image, of the size asked for.
    pub image: RgbImage,
    /// The colour scale used.
    pub scale: ColourScale,
    /// Model units per pixel.
    pub pixel: f64,
    /// Model coordinates (on the plane's right and up axes) of the image's
    /// top left corner.
    pub origin: [f64; 2],
    /// The legend's colour bar, `[x, y, width, height]` in pixels (its top
    /// row is the range's high end), where one was drawn.
    pub bar: Option<[usize; 4]>,
    /// The scale bar, where one was drawn.
    pub scale_bar: Option<ScaleBar>,
}

/// The largest of 1, 2, 5 times a power of ten that is at most `v > 0`.
fn round_length(v: f64) -> f64 {
    let p = 10f64.powf(v.log10().floor());
    [5.0, 2.0, 1.0]
        .into_iter()
        .map(|k| k * p)
        .find(|&l| l <= v * (1.0 + 1e-12))
        .unwrap_or(p)
}

/// The section of the box `min`..`max` by `plane`, coloured through a
/// colour map by an attribute channel (inside the part) or by the value,
/// the zero contour (the part's surface) in black, with a legend on the
/// right and a scale bar in model units below. Values are evaluated in
/// f32 at pixel centres; undefined (NaN) ones are magenta.
pub fn section_image(
    shape: &Shape,
    plane: Plane,
    min: [f64; 3],
    max: [f64; 3],
    w: usize,
    h: usize,
    opts: &SectionShading,
) -> Result<SectionImage> {
    crate::camera::check_size(w, h)?;
    let attrs = shape.attributes();
    let out_k = match opts.channel {
        None => None,
        Some(k) if k < attrs.len() => Some(shape.attribute_output(k)),
        Some(k) => {
            return Err(RenderError::Invalid(format!(
                "attribute {} does not exist: the model has {} attribute channel(s)",
                k + 1,
                attrs.len()
            )))
        }
    };
    let given = match opts.range {
        Some([lo, hi]) => {
            Some(ColourScale::new(opts.colormap, lo, hi).map_err(RenderError::Invalid)?)
        }
        None => None,
    };
    let strip = if opts.legend {
        legend::strip_width(w, h)
    } else {
        None
    };
    // The scale bar's band: margin, label, gap, bar, margin.
    let (ts, m) = (legend::text_scale(h), legend::margin(h));
    let bar_t = 2 * ts;
    let band = strip.map(|_| 2 * m + 5 * ts + ts + bar_t);
    let (iw, ih) = (w - strip.unwrap_or(0), h - band.unwrap_or(0));
    let (ra, ua) = screen_axes(plane.axis);
    let pixel = ((max[ra] - min[ra]) / iw as f64).max((max[ua] - min[ua]) / ih as f64);
    let cu = 0.5 * (min[ra] + max[ra]);
    let cv = 0.5 * (min[ua] + max[ua]);
    let origin = [cu - 0.5 * iw as f64 * pixel, cv + 0.5 * ih as f64 * pixel];
    // Value and shown quantity per pixel of the section area.
    let mut vals = vec![[0f32; 2]; iw * ih];
    vals.par_chunks_mut(iw).enumerate().for_each_init(
        || {
            (
                BatchEval::new(shape.outputs()),
                vec![0f32; iw],
                vec![0f32; iw],
            )
        },
        |(ev, f, a), (y, row)| {
            let mut p = [vec![0f32; iw], vec![0f32; iw], vec![0f32; iw]];
            let v = origin[1] - (y as f64 + 0.5) * pixel;
            for (x, u) in p[ra].iter_mut().enumerate() {
                *u = (origin[0] + (x as f64 + 0.5) * pixel) as f32;
            }
            p[ua].fill(v as f32);
            p[plane.axis].fill(plane.value as f32);
            ev.eval_output(0, &p[0], &p[1], &p[2], f);
            if let Some(k) = out_k {
                ev.eval_output(k, &p[0], &p[1], &p[2], a);
            } else {
                a.copy_from_slice(f);
            }
            for (px, (f, a)) in row.iter_mut().zip(f.iter().zip(a.iter())) {
                *px = [*f, *a];
            }
        },
    );
    // Pixels whose centre lies in the box's section (the image may be
    // wider or taller than the box).
    let in_box = |x: usize, y: usize| {
        let u = origin[0] + (x as f64 + 0.5) * pixel;
        let v = origin[1] - (y as f64 + 0.5) * pixel;
        (min[ra]..=max[ra]).contains(&u) && (min[ua]..=max[ua]).contains(&v)
    };
    let boxed: Vec<bool> = (0..iw * ih).map(|i| in_box(i % iw, i / iw)).collect();
    let shown_at = |i: usize| boxed[i] && (out_k.is_none() || vals[i][0] >= 0.0);
    let scale = given.unwrap_or_else(|| match out_k {
        Some(_) => ColourScale::over(
            opts.colormap,
            (0..vals.len())
                .filter(|&i| shown_at(i))
                .map(|i| vals[i][1] as f64),
        ),
        None => {
            let m = (0..vals.len())
                .filter(|&i| boxed[i] && vals[i][1].is_finite())
                .fold(0f64, |a, i| a.max(vals[i][1].abs() as f64));
            let m = if m > 0.0 { m } else { 1.0 };
            ColourScale {
                map: opts.colormap,
                lo: -m,
                hi: m,
            }
        }
    });
    let mut image = RgbImage {
        width: w,
        height: h,
        data: vec![0; 3 * w * h],
    };
    legend::fill(&mut image, 0, 0, w, h, BACKGROUND);
    for y in 0..ih {
        for x in 0..iw {
            let v = vals[y * iw + x];
            let inside = v[0] >= 0.0;
            let edge = (x + 1 < iw && (vals[y * iw + x + 1][0] >= 0.0) != inside)
                || (y + 1 < ih && (vals[(y + 1) * iw + x][0] >= 0.0) != inside);
            let c = if !boxed[y * iw + x] {
                BACKGROUND
            } else if edge {
                [0, 0, 0]
            } else if !shown_at(y * iw + x) {
                BACKGROUND
            } else if v[1].is_nan() {
                NAN_COLOUR
            } else {
                scale.colour(v[1] as f64)
            };
            let k = 3 * (y * w + x);
            image.data[k..k + 3].copy_from_slice(&c);
        }
    }
    let bar = strip.map(|s| legend::draw(&mut image, iw, s, &scale));
    let scale_bar = band.map(|_| {
        // About a quarter of the section's width, at least one pixel.
        let length = round_length(0.25 * iw as f64 * pixel);
        let width = ((length / pixel).round() as usize).max(1);
        let (x, y) = (m, ih + m + 5 * ts + ts);
        legend::fill(&mut image, x, y, width, bar_t, legend::INK);
        let text = legend::label(length);
        legend::draw_text(&mut image, x, ih + m, ts, &text);
        ScaleBar {
            x,
            y,
            width,
            height: bar_t,
            length,
        }
    });
    Ok(SectionImage {
        image,
        scale,
        pixel,
        origin,
        bar,
        scale_bar,
    })
}
