//! Number formats, escaping, and the head of a model part with the
//! namespaces the model uses.

use crate::beam::{BallMode, BeamLattice};
use crate::model::{ns, MeshResolution, Model, ObjectContent, Transform};
use std::fmt::{self, Display, Write as _};

/// A number as 3MF writes it: the shortest decimal that reads back as the
/// same f32 when the value is an f32, else the same f64 (never an exponent).
pub(super) struct Num(pub(super) f64);

impl Display for Num {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        let v = self.0;
        if v == 0.0 {
            return f.write_str("0");
        }
        let s = v as f32;
        if s as f64 == v {
            write!(f, "{s}")
        } else {
            write!(f, "{v}")
        }
    }
}

/// An xs:double that may be infinite or NaN.
pub(super) struct Double(pub(super) f64);

impl Display for Double {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        match self.0 {
            v if v.is_nan() => f.write_str("NaN"),
            f64::INFINITY => f.write_str("INF"),
            f64::NEG_INFINITY => f.write_str("-INF"),
            v => write!(f, "{}", Num(v)),
        }
    }
}

/// A transform as its 12 numbers.
pub(super) struct Mat<'a>(pub(super) &'a Transform);

impl Display for Mat<'_> {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        for (i, v) in self.0 .0.iter().enumerate() {
            if i > 0 {
                f.write_str(" ")?;
            }
            write!(f, "{}", Num(*v))?;
        }
        Ok(())
    }
}

/// Escapes text for XML.
pub(super) fn esc(s: &str) -> std::borrow::Cow<'_, str> {
    quick_xml::escape::escape(s)
}

/// Which extensions the model uses, and which it requires.
pub(super) struct Extensions {
    pub(super) declare: Vec<(&'static str, &'static str)>,
    pub(super) required: Vec<&'static str>,
}

impl Extensions {
    pub(super) fn of(m: &Model) -> Extensions {
        let lattices: Vec<&BeamLattice> = m
            .objects
            .iter()
            .filter_map(|o| match &o.content {
                ObjectContent::Mesh(me) => me.beam_lattice.as_ref(),
                _ => None,
            })
            .collect();
        let balls = lattices
            .iter()
            .any(|l| !l.balls.is_empty() || l.ball_mode != BallMode::None);
        let lowres = m
            .objects
            .iter()
            .any(|o| o.mesh_resolution == MeshResolution::Low);
        let levelset = m
            .objects
            .iter()
            .any(|o| matches!(o.content, ObjectContent::LevelSet(_)));
        let implicit_in_levelset = m.objects.iter().any(|o| match &o.content {
            ObjectContent::LevelSet(l) => m.implicit_functions.iter().any(|f| f.id == l.function),
            _ => false,
        });
        let volumetric = !m.images.is_empty()
            || !m.image_functions.is_empty()
            || !m.volume_data.is_empty()
            || levelset;
        let mut e = Extensions {
            declare: Vec::new(),
            required: Vec::new(),
        };
        let mut add = |p: &'static str, u: &'static str, used: bool, req: bool| {
            if used {
                e.declare.push((p, u));
                if req {
                    e.required.push(p);
                }
            }
        };
        let materials = !m.composite_materials.is_empty() || !m.color_groups.is_empty();
        add("m", ns::MATERIAL, materials, false);
        add("b", ns::BEAM, !lattices.is_empty(), true);
        add("b2", ns::BALLS, balls, true);
        add("s", ns::SLICE, !m.slice_stacks.is_empty() || lowres, lowres);
        add("v", ns::VOLUMETRIC, volumetric, levelset);
        add(
            "i",
            ns::IMPLICIT,
            !m.implicit_functions.is_empty(),
            implicit_in_levelset,
        );
        e
    }
}

/// The XML declaration and the `<model>` start tag.
pub(super) fn xml_head(out: &mut String, m: &Model, declare: &[(&str, &str)], required: &str) {
    out.push_str("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    write!(out, "<model unit=\"{}\"", m.unit.name()).unwrap();
    if let Some(l) = &m.language {
        write!(out, " xml:lang=\"{}\"", esc(l)).unwrap();
    }
    write!(out, " xmlns=\"{}\"", ns::CORE).unwrap();
    for (p, u) in declare {
        write!(out, " xmlns:{p}=\"{u}\"").unwrap();
    }
    if !required.is_empty() {
        write!(out, " requiredextensions=\"{required}\"").unwrap();
    }
    out.push_str(">\n");
}
