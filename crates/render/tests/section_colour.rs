//! Sections coloured by material or value (`section_image`): a known
//! attribute split shows its two colours on either side of the boundary to
//! within a pixel, the legend shows the map's ends and the scale bar has
//! the length in pixels that its length in model units gives at the image's
//! pixel size.

use microfrep_core::{Expr, Shape};
use microfrep_render::legend::INK;
use microfrep_render::{section_image, Colormap, Plane, SectionShading};

const LO: [f64; 3] = [-1.0; 3];
const HI: [f64; 3] = [1.0; 3];
const BG: [u8; 3] = [250, 250, 250];

/// The cube [-1, 1]^3 with s1 = 1 for x < 0, else 0.
fn split_cube() -> Shape {
    let [x, y, z] = Expr::xyz();
    let f = (1.0 - x.abs()).min(1.0 - y.abs()).min(1.0 - z.abs());
    let s1 = Expr::select(x.lt(0.0), Expr::constant(1.0), Expr::constant(0.0));
    Shape::new(f).with_attribute("s1", s1)
}

fn material(channel: usize, colormap: Colormap) -> SectionShading {
    SectionShading {
        channel: Some(channel),
        colormap,
        range: None,
        legend: true,
    }
}

#[test]
fn the_section_shows_each_material_on_its_side_of_the_boundary() {
    let plane: Plane = "z=0".parse().unwrap();
    let (w, h) = (300, 200);
    let out = section_image(
        &split_cube(),
        plane,
        LO,
        HI,
        w,
        h,
        &material(0, Colormap::Viridis),
    )
    .unwrap();
    let img = &out.image;
    assert_eq!((img.width, img.height), (w, h));
    assert_eq!((out.scale.lo, out.scale.hi), (0.0, 1.0));
    let (left, right) = (Colormap::Viridis.rgb(1.0), Colormap::Viridis.rgb(0.0));
    let px = out.pixel;
    // Image column and row of model x and y (pixel centres at +0.5).
    let col = |x: f64| (x - out.origin[0]) / px - 0.5;
    let row = |y: f64| (out.origin[1] - y) / px - 0.5;
    let (c0, c1) = (col(-1.0).ceil() as usize + 2, col(1.0).floor() as usize - 2);
    let (r0, r1) = (row(1.0).ceil() as usize + 2, row(-1.0).floor() as usize - 2);
    let boundary = col(0.0);
    assert!(c1 > c0 + 100 && r1 > r0 + 100, "{c0}..{c1} x {r0}..{r1}");
    let (mut n_left, mut n_right) = (0, 0);
    for y in r0..=r1 {
        for x in c0..=c1 {
            let c = img.pixel(x, y);
            let d = x as f64 - boundary;
            if d < -1.0 {
                assert_eq!(c, left, "({x}, {y}): left of the boundary at {boundary}");
                n_left += 1;
            } else if d > 1.0 {
                assert_eq!(c, right, "({x}, {y}): right of the boundary at {boundary}");
                n_right += 1;
            } else {
                assert!(c == left || c == right, "({x}, {y}): {c:?}");
            }
        }
    }
    // The halves are equal to within a column per row.
    let rows = (r1 - r0 + 1) as i64;
    assert!(
        (n_left as i64 - n_right as i64).abs() <= 2 * rows,
        "{n_left} {n_right}"
    );
    // Outside the part: the background; the part's surface: black.
    assert_eq!(img.pixel(0, 100), BG);
    let mid = row(0.0).round() as usize;
    let edge = col(1.0).round() as usize;
    assert!((edge - 1..=edge + 1).any(|x| img.pixel(x, mid) == [0, 0, 0]));

    // The legend: the map's high end at the top of the bar, the low end at
    // its bottom, right of the section.
    let [bx, by, bw, bh] = out.bar.expect("a legend");
    assert!(bx > col(1.0) as usize && bx + bw <= w && bh > 100);
    assert_eq!(img.pixel(bx + bw / 2, by), Colormap::Viridis.rgb(1.0));
    assert_eq!(
        img.pixel(bx + bw / 2, by + bh - 1),
        Colormap::Viridis.rgb(0.0)
    );
    // Its labels (ink above and below the bar).
    let ink_rows = |r: std::ops::Range<usize>| {
        r.filter(|&y| (bx - 10..w).any(|x| img.pixel(x, y) == INK))
            .count()
    };
    assert!(ink_rows(0..by) >= 5 && ink_rows(by + bh..h) >= 5);
}

#[test]
fn the_scale_bar_has_its_length_at_the_pixel_size() {
    let plane: Plane = "z=0".parse().unwrap();
    let (w, h) = (300, 200);
    let out = section_image(
        &split_cube(),
        plane,
        LO,
        HI,
        w,
        h,
        &material(0, Colormap::Grey),
    )
    .unwrap();
    // 300 x 200 with a 44-pixel legend strip and a 16-pixel scale band:
    // the 2 x 2 section fits 256 x 184 pixels, so a pixel is 2/184.
    assert!((out.pixel - 2.0 / 184.0).abs() < 1e-15, "{}", out.pixel);
    let b = out.scale_bar.expect("a scale bar");
    // A quarter of the section's width is 0.70; the round length below it: 0.5.
    assert_eq!(b.length, 0.5);
    let want = (0.5 / out.pixel).round() as usize;
    assert_eq!(want, 46);
    assert_eq!(b.width, want);
    // Every row of the bar: exactly `want` pixels of its colour, from x on.
    let img = &out.image;
    let legend_x = out.bar.unwrap()[0] - 10;
    for y in b.y..b.y + b.height {
        let run: Vec<usize> = (0..legend_x).filter(|&x| img.pixel(x, y) == INK).collect();
        assert_eq!(run.len(), want, "row {y}");
        assert_eq!((run[0], run[want - 1]), (b.x, b.x + want - 1));
    }
    assert!(b.y > out.origin[1] as usize && b.y + b.height < h);
    // Its label, "0.5", in ink above it and nowhere on the section.
    let ink_above = (b.y - 8..b.y).any(|y| (b.x..b.x + 20).any(|x| img.pixel(x, y) == INK));
    assert!(ink_above);
    // A section twice as large in model units: a bar of twice the length.
    let big = section_image(
        &split_cube(),
        plane,
        [-2.0; 3],
        [2.0; 3],
        w,
        h,
        &material(0, Colormap::Grey),
    )
    .unwrap();
    let b2 = big.scale_bar.unwrap();
    assert_eq!((b2.length, b2.width), (1.0, want));
}

#[test]
fn the_value_section_is_symmetric_about_the_surface() {
    let [x, y, z] = Expr::xyz();
    let ball = Shape::new(1.0 - (x.square() + y.square() + z.square()));
    let opts = SectionShading {
        channel: None,
        colormap: Colormap::Viridis,
        range: None,
        legend: true,
    };
    let out = section_image(
        &ball,
        "x=0".parse().unwrap(),
        [-1.2; 3],
        [1.2; 3],
        400,
        300,
        &opts,
    )
    .unwrap();
    assert_eq!(out.scale.lo, -out.scale.hi);
    // The largest magnitude over the box's section: -1.88 at its corners.
    assert!(
        out.scale.hi > 1.85 && out.scale.hi <= 1.88,
        "{:?}",
        out.scale
    );
    let c = |u: f64, v: f64| {
        let x = ((u - out.origin[0]) / out.pixel) as usize;
        let y = ((out.origin[1] - v) / out.pixel) as usize;
        out.image.pixel(x, y)
    };
    // The centre: value 1, three quarters up the map; a corner of the
    // box, near the bottom.
    let top = out.scale.colour(1.0);
    let centre = c(0.0, 0.0);
    assert!(
        centre
            .iter()
            .zip(top)
            .all(|(a, b)| (*a as i32 - b as i32).abs() <= 3),
        "{centre:?}"
    );
    let corner = c(1.19, 1.19);
    let low = out.scale.colour(1.0 - 2.0 * 1.19f64.powi(2));
    assert!(
        corner
            .iter()
            .zip(low)
            .all(|(a, b)| (*a as i32 - b as i32).abs() <= 3),
        "{corner:?}"
    );
    // Beside the box (the image is wider than the section): background.
    assert_eq!(out.image.pixel(1, 150), BG);
    assert!(out.bar.is_some() && out.scale_bar.is_some());
    // Bad channels are refused.
    let e = section_image(
        &ball,
        "z=0".parse().unwrap(),
        [-1.2; 3],
        [1.2; 3],
        100,
        100,
        &material(0, Colormap::Viridis),
    )
    .unwrap_err();
    assert!(e.to_string().contains("attribute 1 does not exist"), "{e}");
    // No legend or scale bar in a tiny image.
    let small = section_image(
        &split_cube(),
        "z=0".parse().unwrap(),
        LO,
        HI,
        40,
        30,
        &material(0, Colormap::Viridis),
    )
    .unwrap();
    assert!(small.bar.is_none() && small.scale_bar.is_none());
}
