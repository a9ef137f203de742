//! SVG cross-sections of 2D structures.

use microfrep_core::Expr;
use microfrep_pores::svg::section_svg;
use microfrep_pores::{Options, PoreError, PoreShape, Pores, Spec};

#[test]
fn grassy_stem_section_has_the_exact_pores_and_the_outline() {
    let p = Expr::xyz();
    let r = (p[0].square() + p[1].square()).sqrt();
    let part = (Expr::constant(1.0) - &r)
        .min(&r - 0.45)
        .min(p[2].clone())
        .min(Expr::constant(1.0) - &p[2]);
    let bounds = [[-1.0, -1.0, 0.0], [1.0, 1.0, 1.0]];
    let b = Pores::build(
        &part,
        bounds,
        Spec::Constant(0.125),
        Spec::Constant(0.6),
        3,
        &Options::two_d(),
    )
    .unwrap();
    let svg = section_svg(&b, &part, [[-1.0, -1.0], [1.0, 1.0]], 0.5, 0.01).unwrap();
    assert!(svg.starts_with("<?xml") && svg.trim_end().ends_with("</svg>"));
    assert!(svg.contains(&format!("{} pores in {} cells", b.pores, b.cells.len())));
    // One clipped path per pore, four quadratic arcs each, at the arcs'
    // own control points.
    assert_eq!(svg.matches("clip-path=\"url(#c").count(), b.pores);
    assert_eq!(svg.matches('Q').count(), 4 * b.pores);
    let first = b
        .cells
        .iter()
        .find_map(|c| match &c.shape {
            PoreShape::Two { arcs, .. } => Some(arcs[0]),
            _ => None,
        })
        .unwrap();
    assert!(svg.contains(&format!(
        "Q{} {} {} {}",
        first.p[1][0], first.p[1][1], first.p[2][0], first.p[2][1]
    )));
    // The outline: two loops (outer and inner circle) in the black path.
    let outline = svg.split("fill=\"black\"").nth(1).unwrap();
    let outline = &outline[..outline.find("/>").unwrap()];
    assert_eq!(outline.matches('M').count(), 2);
    assert!(matches!(
        section_svg(&b, &part, [[-1.0, -1.0], [1.0, 1.0]], 0.5, 0.0),
        Err(PoreError::Section(_))
    ));
}
