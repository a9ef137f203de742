//! Base materials (core), composite materials and colour groups (the
//! materials extension).

use super::xml::{esc, Num};
use crate::model::Model;
use std::fmt::Write as _;
use std::io::Write;

/// The material resources, into `s` (and out to `w` when `s` grows large).
pub(super) fn materials_xml<W: Write>(w: &mut W, s: &mut String, m: &Model) -> std::io::Result<()> {
    for bm in &m.base_materials {
        write!(s, "<basematerials id=\"{}\">", bm.id).unwrap();
        for b in &bm.bases {
            let c = b.color;
            write!(
                s,
                "<base name=\"{}\" displaycolor=\"#{:02X}{:02X}{:02X}{:02X}\"/>",
                esc(&b.name),
                c[0],
                c[1],
                c[2],
                c[3]
            )
            .unwrap();
        }
        s.push_str("</basematerials>\n");
    }
    for cm in &m.composite_materials {
        let idx: Vec<String> = cm.material_indices.iter().map(|i| i.to_string()).collect();
        write!(
            s,
            "<m:compositematerials id=\"{}\" matid=\"{}\" matindices=\"{}\">",
            cm.id,
            cm.base_materials,
            idx.join(" ")
        )
        .unwrap();
        for c in &cm.composites {
            let v: Vec<String> = c.iter().map(|x| Num(*x).to_string()).collect();
            write!(s, "<m:composite values=\"{}\"/>", v.join(" ")).unwrap();
        }
        s.push_str("</m:compositematerials>\n");
    }
    for cg in &m.color_groups {
        writeln!(s, "<m:colorgroup id=\"{}\">", cg.id).unwrap();
        for c in &cg.colors {
            writeln!(
                s,
                "<m:color color=\"#{:02X}{:02X}{:02X}{:02X}\"/>",
                c[0], c[1], c[2], c[3]
            )
            .unwrap();
            if s.len() > 1 << 20 {
                w.write_all(s.as_bytes())?;
                s.clear();
            }
        }
        s.push_str("</m:colorgroup>\n");
    }
    Ok(())
}
