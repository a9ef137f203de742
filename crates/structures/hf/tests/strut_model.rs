//! `strut_model` finds the lattice of an `mfStruts` model: alone, clipped
//! by a part on either side of `&`, through `mfStrutsDensity`; and refuses
//! what is not one beam lattice (a moved point, a graded radius, a union).

use microfrep_structures::struts::StrutLattice;
use microfrep_structures_hf::strut_model;

fn value(body: &str) -> microfrep_core::Expr {
    microfrep_structures_hf::install();
    let src = format!(
        "my_model(x[3], a[1]) {{\n array xt[3];\n xt[1] = x[1] + 0.1; xt[2] = x[2]; xt[3] = x[3];\n \
         ball = 1 - x[1]^2 - x[2]^2 - x[3]^2;\n my_model = {body};\n}}"
    );
    microfrep_hyperfun::load(&src, "t.hf", None)
        .unwrap()
        .shape()
        .value()
        .clone()
}

#[test]
fn finds_plain_and_clipped_lattices_and_refuses_the_rest() {
    let s = strut_model(&value("mfStruts(x, 2, 0.5, 0.05)")).unwrap();
    assert_eq!(s.kind, StrutLattice::Bcc);
    assert_eq!((s.cell, s.radius), (0.5, 0.05));
    assert!(s.part.is_none());
    for body in [
        "mfStruts(x, 4, 0.5, 0.05) & ball",
        "ball & mfStruts(x, 4, 0.5, 0.05)",
    ] {
        let s = strut_model(&value(body)).unwrap();
        assert_eq!(s.kind, StrutLattice::Octet);
        let part = s.part.expect("clipped");
        let v =
            microfrep_core::PointEval::new(&microfrep_core::Tape::new(&part)).eval([0.5, 0.0, 0.0]);
        assert!((v - 0.75).abs() < 1e-12, "the part is the ball: {v}");
    }
    // The density form gives the radius its table gives (in (0, cell/2)).
    let s = strut_model(&value("mfStrutsDensity(x, 1, 2, 0.2) & ball")).unwrap();
    assert!(s.radius > 0.0 && s.radius < 1.0, "{}", s.radius);
    for body in [
        "mfStruts(xt, 4, 0.5, 0.05) & ball",
        "mfStruts(x, 4, 0.5, 0.02 + 0.01 * x[1]) & ball",
        "mfStruts(x, 4, 0.5, 0.05) | ball",
        "ball",
    ] {
        assert!(strut_model(&value(body)).is_none(), "{body}");
    }
}
