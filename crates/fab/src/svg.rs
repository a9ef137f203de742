//! One SVG per layer: all loops as sub-paths of one path in model units
//! (y up), outer boundaries counter-clockwise and holes clockwise, so the
//! nonzero fill rule shows the holes.

use crate::contour::Polygon;
use std::fmt::Write;

/// The SVG document of one layer over the image rectangle `min`..`max`.
pub fn layer_svg(polys: &[Polygon], z: f64, min: [f64; 2], max: [f64; 2], tol: f64) -> String {
    let (w, h) = (max[0] - min[0], max[1] - min[1]);
    let mut s = String::new();
    let _ = writeln!(s, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="{} {} {w} {h}">"#,
        min[0], -max[1]
    );
    let _ = writeln!(
        s,
        "<desc>microfrep layer z={z}; {} loops; simplification tolerance {tol}</desc>",
        polys.len()
    );
    let _ = writeln!(s, r#"<g transform="scale(1,-1)">"#);
    let _ = writeln!(s, r#"<path fill="black" fill-rule="nonzero" d=""#);
    for p in polys {
        for (k, v) in p.iter().enumerate() {
            let cmd = if k == 0 { 'M' } else { 'L' };
            let _ = write!(s, "{cmd}{} {} ", v[0], v[1]);
        }
        let _ = writeln!(s, "Z");
    }
    let _ = writeln!(s, r#""/>"#);
    let _ = writeln!(s, "</g>\n</svg>");
    s
}

/// The loops of an SVG written by [`layer_svg`], for tests and tools.
pub fn read_layer_svg(text: &str) -> Vec<Polygon> {
    let Some(start) = text.find(" d=\"") else {
        return Vec::new();
    };
    let d = &text[start + 4..];
    let d = &d[..d.find('"').unwrap_or(d.len())];
    d.split('Z')
        .filter_map(|sub| {
            let nums: Vec<f64> = sub
                .split(|c: char| c == 'M' || c == 'L' || c.is_whitespace())
                .filter(|t| !t.is_empty())
                .filter_map(|t| t.parse().ok())
                .collect();
            (nums.len() >= 2).then(|| nums.chunks(2).map(|c| [c[0], c[1]]).collect())
        })
        .collect()
}
