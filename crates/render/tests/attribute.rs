//! Images coloured by an attribute: the colour follows the attribute at
//! the hit point through the colour map, the legend shows the map's ends,
//! and bad channels and ranges are refused.

use microfrep_core::{Expr, Shape};
use microfrep_render::{
    ray_cast, ray_cast_attribute, AttributeShading, Camera, Colormap, ColourScale, View,
};

const LO: [f64; 3] = [-1.2; 3];
const HI: [f64; 3] = [1.2; 3];
const BG: [u8; 3] = [250, 250, 250];

/// The cube [-1, 1]^3 with attribute s1 = x (a ramp from -1 to 1).
fn ramp_cube() -> Shape {
    let [x, y, z] = Expr::xyz();
    let f = (1.0 - x.abs()).min(1.0 - y.abs()).min(1.0 - z.abs());
    Shape::new(f).with_attribute("s1", x)
}

/// Hue in degrees, 0..360.
fn hue(c: [u8; 3]) -> f64 {
    let [r, g, b] = c.map(|v| v as f64);
    let (mx, mn) = (r.max(g).max(b), r.min(g).min(b));
    let d = mx - mn;
    let h = if d == 0.0 {
        0.0
    } else if mx == r {
        60.0 * ((g - b) / d).rem_euclid(6.0)
    } else if mx == g {
        60.0 * ((b - r) / d + 2.0)
    } else {
        60.0 * ((r - g) / d + 4.0)
    };
    h.rem_euclid(360.0)
}

fn shading(range: Option<[f64; 2]>, legend: bool) -> AttributeShading {
    AttributeShading {
        channel: 0,
        colormap: Colormap::Viridis,
        range,
        legend,
    }
}

#[test]
fn hue_follows_a_ramp_in_x_and_the_legend_shows_the_ends() {
    let (w, h) = (320, 200);
    let out = ray_cast_attribute(
        &ramp_cube(),
        View::Front,
        LO,
        HI,
        w,
        h,
        &shading(None, true),
    )
    .unwrap();
    let img = &out.image;
    assert_eq!((img.width, img.height), (w, h));
    // The range is the visible surface's: x over the front face.
    assert!(
        out.scale.lo < -0.97 && out.scale.hi > 0.97,
        "{:?}",
        out.scale
    );
    let [bx, by, bw, bh] = out.bar.expect("a legend");
    assert!(bx > w / 2, "bar at {bx}");
    // Along the middle row, the front face's pixels run from purple to
    // yellow: viridis hue falls monotonically (one degree of rounding).
    let row: Vec<[u8; 3]> = (0..bx - 2)
        .map(|x| img.pixel(x, h / 2))
        .filter(|&c| c != BG)
        .collect();
    assert!(row.len() > 100, "{} surface pixels", row.len());
    for p in row.windows(2) {
        assert!(hue(p[1]) <= hue(p[0]) + 1.0, "{:?} then {:?}", p[0], p[1]);
    }
    assert!(hue(row[0]) - hue(row[row.len() - 1]) > 150.0);
    // The legend: the map's high end at the top of the bar, low at the bottom.
    assert_eq!(img.pixel(bx + bw / 2, by), Colormap::Viridis.rgb(1.0));
    assert_eq!(
        img.pixel(bx + bw / 2, by + bh - 1),
        Colormap::Viridis.rgb(0.0)
    );
    // Same bytes every run.
    let again = ray_cast_attribute(
        &ramp_cube(),
        View::Front,
        LO,
        HI,
        w,
        h,
        &shading(None, true),
    )
    .unwrap();
    assert_eq!(again.image, out.image);
}

#[test]
fn a_given_range_clamps_and_the_plain_image_is_unchanged() {
    // Range 0..0.5: the left half of the face (x < 0) is the low colour
    // times the light, the right end the high colour.
    let out = ray_cast_attribute(
        &ramp_cube(),
        View::Front,
        LO,
        HI,
        200,
        120,
        &shading(Some([0.0, 0.5]), false),
    )
    .unwrap();
    assert!(out.bar.is_none());
    assert_eq!(
        out.scale,
        ColourScale::new(Colormap::Viridis, 0.0, 0.5).unwrap()
    );
    let img = &out.image;
    let row: Vec<[u8; 3]> = (0..200)
        .map(|x| img.pixel(x, 60))
        .filter(|&c| c != BG)
        .collect();
    let (lo, hi) = (Colormap::Viridis.rgb(0.0), Colormap::Viridis.rgb(1.0));
    let scaled = |p: [u8; 3], c: [u8; 3]| {
        // p = c * light for one light level: the channel ratios agree.
        let k = (0..3).max_by_key(|&k| c[k]).unwrap();
        let l = p[k] as f64 / c[k] as f64;
        l > 0.2 && (0..3).all(|k| (p[k] as f64 - c[k] as f64 * l).abs() <= 1.5)
    };
    assert!(scaled(row[2], lo), "{:?}", row[2]);
    assert!(scaled(row[row.len() / 4], lo));
    assert!(scaled(row[row.len() - 3], hi), "{:?}", row[row.len() - 3]);
    // Without the legend the framing is ray_cast's: the silhouettes agree.
    let cam = Camera::fit(View::Front, LO, HI, 200, 120);
    let plain = ray_cast(&ramp_cube(), &cam, LO, HI);
    for (a, b) in plain.data.chunks(3).zip(img.data.chunks(3)) {
        assert_eq!(a == BG, b == BG);
    }
}

#[test]
fn missing_channels_and_bad_ranges_are_refused() {
    let e = ray_cast_attribute(
        &ramp_cube(),
        View::Front,
        LO,
        HI,
        64,
        64,
        &AttributeShading {
            channel: 3,
            ..shading(None, true)
        },
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("attribute 4") && e.contains("1 attribute channel"),
        "{e}"
    );
    for r in [[1.0, 1.0], [2.0, 1.0], [0.0, f64::INFINITY]] {
        let e = ray_cast_attribute(
            &ramp_cube(),
            View::Front,
            LO,
            HI,
            64,
            64,
            &shading(Some(r), true),
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("colour range"), "{e}");
    }
}
