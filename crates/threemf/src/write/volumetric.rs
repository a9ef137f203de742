//! The volumetric extension (draft): image stacks and their PNG sheets,
//! functions from images, volume data and level sets.

use super::xml::{esc, Mat, Num};
use crate::model::Model;
use crate::volumetric::{Filter, FunctionRef, LevelSet, VolumeData};
use std::collections::HashMap;
use std::fmt::Write as _;
use std::io::Write;

/// The sheet parts of the image stacks, (part, image id, sheet), and their
/// paths per image id.
#[allow(clippy::type_complexity)]
pub(super) fn plan_sheets(model: &Model) -> (Vec<(String, u32, usize)>, HashMap<u32, Vec<String>>) {
    let mut sheets: Vec<(String, u32, usize)> = Vec::new(); // (part, image id, sheet)
    let mut sheet_names: HashMap<u32, Vec<String>> = HashMap::new();
    for im in &model.images {
        for k in 0..im.dims[2] {
            let name = format!("3D/volumetric/image{}/sheet{:04}.png", im.id, k);
            sheet_names
                .entry(im.id)
                .or_default()
                .push(format!("/{name}"));
            sheets.push((name, im.id, k));
        }
    }
    (sheets, sheet_names)
}

/// The image stacks (naming their sheets, `sheets`) and the functions
/// from images, into `s`.
pub(super) fn images_xml(s: &mut String, m: &Model, sheets: &HashMap<u32, Vec<String>>) {
    for im in &m.images {
        write!(s, "<v:image3d id=\"{}\"", im.id).unwrap();
        if let Some(n) = &im.name {
            write!(s, " name=\"{}\"", esc(n)).unwrap();
        }
        write!(
            s,
            "><v:imagestack rowcount=\"{}\" columncount=\"{}\" sheetcount=\"{}\">",
            im.dims[1], im.dims[0], im.dims[2]
        )
        .unwrap();
        for p in &sheets[&im.id] {
            write!(s, "<v:imagesheet path=\"{p}\"/>").unwrap();
        }
        s.push_str("</v:imagestack></v:image3d>\n");
    }
    for f in &m.image_functions {
        write!(s, "<v:functionfromimage3d id=\"{}\"", f.id).unwrap();
        if let Some(n) = &f.display_name {
            write!(s, " displayname=\"{}\"", esc(n)).unwrap();
        }
        write!(
            s,
            " image3did=\"{}\" filter=\"{}\" valueoffset=\"{}\" valuescale=\"{}\" tilestyleu=\"{}\" tilestylev=\"{}\" tilestylew=\"{}\"/>",
            f.image,
            match f.filter {
                Filter::Linear => "linear",
                Filter::Nearest => "nearest",
            },
            Num(f.value_offset),
            Num(f.value_scale),
            f.tile[0].name(),
            f.tile[1].name(),
            f.tile[2].name()
        )
        .unwrap();
        s.push('\n');
    }
}

/// A level set object's `<v:levelset>`.
pub(super) fn levelset_xml<W: Write>(w: &mut W, l: &LevelSet) -> std::io::Result<()> {
    write!(
        w,
        "<v:levelset functionid=\"{}\" channel=\"{}\" meshid=\"{}\" meshbboxonly=\"{}\"",
        l.function,
        esc(&l.channel),
        l.mesh,
        l.mesh_bbox_only
    )?;
    if !l.transform.is_identity() {
        write!(w, " transform=\"{}\"", Mat(&l.transform))?;
    }
    if l.min_feature_size != 0.0 {
        write!(w, " minfeaturesize=\"{}\"", Num(l.min_feature_size))?;
    }
    if l.fallback != 0.0 {
        write!(w, " fallbackvalue=\"{}\"", Num(l.fallback))?;
    }
    if let Some(v) = l.volume_id {
        write!(w, " volumeid=\"{v}\"")?;
    }
    w.write_all(b"/>\n")?;
    Ok(())
}

fn fref_attrs(s: &mut String, r: &FunctionRef) {
    write!(
        s,
        " functionid=\"{}\" channel=\"{}\"",
        r.function,
        esc(&r.channel)
    )
    .unwrap();
    if !r.transform.is_identity() {
        write!(s, " transform=\"{}\"", Mat(&r.transform)).unwrap();
    }
    if r.min_feature_size != 0.0 {
        write!(s, " minfeaturesize=\"{}\"", Num(r.min_feature_size)).unwrap();
    }
    if r.fallback != 0.0 {
        write!(s, " fallbackvalue=\"{}\"", Num(r.fallback)).unwrap();
    }
}

pub(super) fn volumedata_xml(s: &mut String, vd: &VolumeData) {
    write!(s, "<v:volumedata id=\"{}\">", vd.id).unwrap();
    if let Some(c) = &vd.composite {
        write!(s, "<v:composite basematerialid=\"{}\">", c.base_materials).unwrap();
        for m in &c.mappings {
            s.push_str("<v:materialmapping");
            fref_attrs(s, m);
            s.push_str("/>");
        }
        s.push_str("</v:composite>");
    }
    if let Some(c) = &vd.color {
        s.push_str("<v:color");
        fref_attrs(s, c);
        s.push_str("/>");
    }
    for p in &vd.properties {
        write!(
            s,
            "<v:property name=\"{}\" required=\"{}\"",
            esc(&p.name),
            p.required
        )
        .unwrap();
        fref_attrs(s, &p.value);
        s.push_str("/>");
    }
    s.push_str("</v:volumedata>\n");
}
