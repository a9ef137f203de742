//! The legend of an attribute image: a vertical colour bar, the range's
//! high end at its top and low end at its bottom, with both values printed
//! above and below it in a small built-in bitmap font, in a strip on the
//! image's right.

use crate::image::RgbImage;
use crate::shade::BACKGROUND;
use microfrep_io::colormap::ColourScale;

/// Smallest image width that gets a legend.
pub const MIN_WIDTH: usize = 96;
/// Smallest image height that gets a legend.
pub const MIN_HEIGHT: usize = 48;
/// Characters a label may take.
const LABEL: usize = 9;
/// Colour of the labels and of a section's scale bar.
pub const INK: [u8; 3] = [30, 30, 30];
const FRAME: [u8; 3] = [90, 90, 90];

/// Glyphs of 3 x 5 pixels, rows top first, 3 bits a row (high bit left).
fn glyph(c: char) -> Option<[u8; 5]> {
    Some(match c {
        '0' => [0b111, 0b101, 0b101, 0b101, 0b111],
        '1' => [0b010, 0b110, 0b010, 0b010, 0b111],
        '2' => [0b111, 0b001, 0b111, 0b100, 0b111],
        '3' => [0b111, 0b001, 0b111, 0b001, 0b111],
        '4' => [0b101, 0b101, 0b111, 0b001, 0b001],
        '5' => [0b111, 0b100, 0b111, 0b001, 0b111],
        '6' => [0b111, 0b100, 0b111, 0b101, 0b111],
        '7' => [0b111, 0b001, 0b001, 0b001, 0b001],
        '8' => [0b111, 0b101, 0b111, 0b101, 0b111],
        '9' => [0b111, 0b101, 0b111, 0b001, 0b111],
        '.' => [0b000, 0b000, 0b000, 0b000, 0b010],
        '-' => [0b000, 0b000, 0b111, 0b000, 0b000],
        '+' => [0b000, 0b010, 0b111, 0b010, 0b000],
        'e' => [0b010, 0b101, 0b111, 0b100, 0b011],
        _ => return None,
    })
}

/// Pixels per font pixel for an image `height` high.
pub fn text_scale(height: usize) -> usize {
    (height / 200).clamp(1, 8)
}

/// Margin around the legend's parts, in pixels, for an image `height` high.
pub fn margin(height: usize) -> usize {
    2 * text_scale(height) + 2
}

/// Width of the legend strip of a `width x height` image; `None` when the
/// image is too small for one.
pub fn strip_width(width: usize, height: usize) -> Option<usize> {
    if width < MIN_WIDTH || height < MIN_HEIGHT {
        return None;
    }
    let s = text_scale(height);
    Some((LABEL * 4 * s + 2 * margin(height)).min(width / 3))
}

/// A value as the legend prints it: three significant digits, fewer if
/// that is too long.
pub fn label(v: f64) -> String {
    let l = microfrep_io::text::sig(v, 3);
    if l.len() <= LABEL {
        l
    } else {
        microfrep_io::text::sig(v, 1)
    }
}

/// Pixels per character advance at scale `s`.
fn advance(s: usize) -> usize {
    4 * s
}

/// Width in pixels of `text` at scale `s`.
pub fn text_width(text: &str, s: usize) -> usize {
    (text.chars().count() * advance(s)).saturating_sub(s)
}

/// Draws `text` with its top left corner at `(x, y)`, font pixels `s`
/// image pixels wide; clipped at the image's edges. Characters without a
/// glyph are blank.
pub fn draw_text(img: &mut RgbImage, x: usize, y: usize, s: usize, text: &str) {
    for (k, c) in text.chars().enumerate() {
        let Some(g) = glyph(c) else { continue };
        let cx = x + k * advance(s);
        for (r, bits) in g.iter().enumerate() {
            for col in 0..3 {
                if bits >> (2 - col) & 1 == 1 {
                    fill(img, cx + col * s, y + r * s, s, s, INK);
                }
            }
        }
    }
}

pub(crate) fn fill(img: &mut RgbImage, x: usize, y: usize, w: usize, h: usize, c: [u8; 3]) {
    for yy in y..(y + h).min(img.height) {
        for xx in x..(x + w).min(img.width) {
            let k = 3 * (yy * img.width + xx);
            img.data[k..k + 3].copy_from_slice(&c);
        }
    }
}

/// Draws the legend of `scale` in the strip of `img` from column `x0`,
/// `width` wide (see [`strip_width`]); returns the colour bar's
/// `[x, y, width, height]` (inside its frame).
pub fn draw(img: &mut RgbImage, x0: usize, width: usize, scale: &ColourScale) -> [usize; 4] {
    let h = img.height;
    let (s, m) = (text_scale(h), margin(h));
    fill(img, x0, 0, width, h, BACKGROUND);
    let text_h = 5 * s;
    let bar_w = (6 * s).max(4).min(width.saturating_sub(2 * m + 2).max(1));
    let bar_x = x0 + (width - bar_w) / 2;
    let bar_y = m + text_h + m;
    let bar_h = h.saturating_sub(2 * bar_y).max(1);
    // The frame, one pixel outside the bar.
    fill(img, bar_x - 1, bar_y - 1, bar_w + 2, bar_h + 2, FRAME);
    for r in 0..bar_h {
        let t = if bar_h > 1 {
            1.0 - r as f64 / (bar_h - 1) as f64
        } else {
            1.0
        };
        fill(img, bar_x, bar_y + r, bar_w, 1, scale.map.rgb(t));
    }
    // Rounding noise next to zero (1e-13 for 0) prints as 0.
    let tidy = |v: f64| {
        if v.abs() < 1e-9 * (scale.hi - scale.lo) {
            0.0
        } else {
            v
        }
    };
    for (text, y) in [
        (label(tidy(scale.hi)), m),
        (label(tidy(scale.lo)), bar_y + bar_h + m),
    ] {
        let tw = text_width(&text, s);
        let x = x0 + width.saturating_sub(tw) / 2;
        draw_text(img, x, y, s, &text);
    }
    [bar_x, bar_y, bar_w, bar_h]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn blank(w: usize, h: usize) -> RgbImage {
        RgbImage {
            width: w,
            height: h,
            data: vec![255; 3 * w * h],
        }
    }

    fn ink(img: &RgbImage) -> usize {
        img.data.chunks(3).filter(|p| *p == INK).count()
    }

    #[test]
    fn glyphs_cover_every_character_a_label_uses_and_scale_by_area() {
        for v in [0.0, -1.5, 1234567.0, 1e-9, -2.5e12, 0.333333] {
            let l = label(v);
            assert!(l.len() <= LABEL, "{l}");
            assert!(l.chars().all(|c| glyph(c).is_some()), "{l}");
        }
        // "8" has 13 lit font pixels; at scale 3 each is 9 image pixels.
        for s in [1, 3] {
            let mut img = blank(20, 20);
            draw_text(&mut img, 1, 1, s, "8");
            assert_eq!(ink(&img), 13 * s * s);
        }
        // Drawing past the edge clips instead of panicking.
        let mut img = blank(5, 5);
        draw_text(&mut img, 3, 3, 2, "-1.5e+3");
        assert!(ink(&img) < 4);
    }

    #[test]
    fn the_bar_runs_from_the_high_colour_at_the_top_to_the_low_at_the_bottom() {
        let scale = ColourScale::new(microfrep_io::colormap::Colormap::Viridis, -2.0, 3.0).unwrap();
        let mut img = blank(300, 200);
        let w = strip_width(300, 200).unwrap();
        let [x, y, bw, bh] = draw(&mut img, 300 - w, w, &scale);
        assert!(x >= 300 - w && x + bw <= 300 && y + bh <= 200 && bh > 100);
        assert_eq!(img.pixel(x + bw / 2, y), scale.map.rgb(1.0));
        assert_eq!(img.pixel(x + bw / 2, y + bh - 1), scale.map.rgb(0.0));
        assert_eq!(img.pixel(x - 1, y), FRAME);
        // Both labels are printed: ink above and below the bar.
        let rows_with_ink = |r: std::ops::Range<usize>| {
            r.filter(|&yy| (300 - w..300).any(|xx| img.pixel(xx, yy) == INK))
                .count()
        };
        assert!(rows_with_ink(0..y) >= 5);
        assert!(rows_with_ink(y + bh..200) >= 5);
        assert!(strip_width(50, 200).is_none() && strip_width(300, 20).is_none());
    }
}
