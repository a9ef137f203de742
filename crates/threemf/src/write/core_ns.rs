//! The root model part: metadata, the resources (the extensions' from
//! their files), objects with their meshes and components, and the
//! build.

use super::beam::write_lattice;
use super::implicit::implicit_xml;
use super::materials::materials_xml;
use super::slice::slicestacks_xml;
use super::volumetric::{images_xml, levelset_xml, volumedata_xml};
use super::xml::{esc, xml_head, Extensions, Mat, Num};
use crate::model::{MeshResolution, Model, Object, ObjectContent};
use std::collections::HashMap;
use std::io::Write;

/// The root model part, streamed to `w`: the slice stacks name their
/// parts (`slice_refs`), the image stacks their sheets (`sheets`).
pub(super) fn write_root<W: Write>(
    w: &mut W,
    m: &Model,
    ext: &Extensions,
    slice_refs: &HashMap<u32, Vec<(u32, String)>>,
    sheets: &HashMap<u32, Vec<String>>,
) -> std::io::Result<()> {
    let mut head = String::new();
    xml_head(&mut head, m, &ext.declare, &ext.required.join(" "));
    w.write_all(head.as_bytes())?;
    for md in &m.metadata {
        writeln!(
            w,
            "<metadata name=\"{}\">{}</metadata>",
            esc(&md.name),
            esc(&md.value)
        )?;
    }
    w.write_all(b"<resources>\n")?;
    let mut s = String::new();
    materials_xml(w, &mut s, m)?;
    images_xml(&mut s, m, sheets);
    for f in &m.implicit_functions {
        implicit_xml(&mut s, f);
    }
    for vd in &m.volume_data {
        volumedata_xml(&mut s, vd);
    }
    slicestacks_xml(w, &mut s, m, slice_refs)?;
    w.write_all(s.as_bytes())?;
    for o in &m.objects {
        write_object(w, o)?;
    }
    w.write_all(b"</resources>\n<build>\n")?;
    for it in &m.build {
        write!(w, "<item objectid=\"{}\"", it.object)?;
        if !it.transform.is_identity() {
            write!(w, " transform=\"{}\"", Mat(&it.transform))?;
        }
        if let Some(p) = &it.part_number {
            write!(w, " partnumber=\"{}\"", esc(p))?;
        }
        w.write_all(b"/>\n")?;
    }
    w.write_all(b"</build>\n</model>\n")
}

fn write_object<W: Write>(w: &mut W, o: &Object) -> std::io::Result<()> {
    write!(w, "<object id=\"{}\" type=\"{}\"", o.id, o.kind.name())?;
    if let Some(n) = &o.name {
        write!(w, " name=\"{}\"", esc(n))?;
    }
    if let Some(p) = &o.part_number {
        write!(w, " partnumber=\"{}\"", esc(p))?;
    }
    if let Some((pid, pindex)) = o.property {
        write!(w, " pid=\"{pid}\" pindex=\"{pindex}\"")?;
    }
    if let Some(sid) = o.slice_stack {
        write!(w, " s:slicestackid=\"{sid}\"")?;
    }
    if o.mesh_resolution == MeshResolution::Low {
        w.write_all(b" s:meshresolution=\"lowres\"")?;
    }
    w.write_all(b">\n")?;
    match &o.content {
        ObjectContent::Components(cs) => {
            w.write_all(b"<components>")?;
            for c in cs {
                write!(w, "<component objectid=\"{}\"", c.object)?;
                if !c.transform.is_identity() {
                    write!(w, " transform=\"{}\"", Mat(&c.transform))?;
                }
                w.write_all(b"/>")?;
            }
            w.write_all(b"</components>\n")?;
        }
        ObjectContent::LevelSet(l) => levelset_xml(w, l)?,
        ObjectContent::Mesh(me) => {
            w.write_all(b"<mesh")?;
            if let Some(v) = me.volume_id {
                write!(w, " v:volumeid=\"{v}\"")?;
            }
            w.write_all(b">\n<vertices>\n")?;
            for p in &me.vertices {
                writeln!(
                    w,
                    "<vertex x=\"{}\" y=\"{}\" z=\"{}\"/>",
                    Num(p[0]),
                    Num(p[1]),
                    Num(p[2])
                )?;
            }
            w.write_all(b"</vertices>\n<triangles>\n")?;
            for (i, t) in me.triangles.iter().enumerate() {
                write!(
                    w,
                    "<triangle v1=\"{}\" v2=\"{}\" v3=\"{}\"",
                    t[0], t[1], t[2]
                )?;
                if let Some(p) = &me.properties {
                    let q = p.indices[i];
                    if q[0] == q[1] && q[1] == q[2] {
                        write!(w, " pid=\"{}\" p1=\"{}\"", p.pid, q[0])?;
                    } else {
                        write!(
                            w,
                            " pid=\"{}\" p1=\"{}\" p2=\"{}\" p3=\"{}\"",
                            p.pid, q[0], q[1], q[2]
                        )?;
                    }
                }
                w.write_all(b"/>\n")?;
            }
            w.write_all(b"</triangles>\n")?;
            if let Some(l) = &me.beam_lattice {
                write_lattice(w, l)?;
            }
            w.write_all(b"</mesh>\n")?;
        }
    }
    w.write_all(b"</object>\n")
}
