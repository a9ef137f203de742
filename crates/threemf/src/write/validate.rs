//! The checks of a model before it is written.

use super::beam::check_lattice;
use crate::error::{Error, Result};
use crate::model::{Model, Object, ObjectContent, ObjectType};
use crate::volumetric::{check_dims, FunctionRef};
use std::collections::{HashMap, HashSet};

pub(super) fn bad(msg: impl Into<String>) -> Error {
    Error::BadInput(msg.into())
}

fn finite3(p: &[f64], what: impl Fn() -> String) -> Result<()> {
    if p.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(bad(format!("{} is not finite: {p:?}", what())))
    }
}

/// Checks everything the specifications require of what the writer emits:
/// unique ids, references to resources defined earlier, indices in range,
/// finite numbers, positive radii, increasing slice tops, planar transforms
/// for sliced objects.
pub fn validate(m: &Model) -> Result<()> {
    let mut ids = HashSet::new();
    for id in m.resource_ids() {
        if id == 0 || id > i32::MAX as u32 {
            return Err(bad(format!("resource id {id} is outside 1..=2^31-1")));
        }
        if !ids.insert(id) {
            return Err(bad(format!("resource id {id} is used twice")));
        }
    }
    let bases: HashMap<u32, usize> = m
        .base_materials
        .iter()
        .map(|b| (b.id, b.bases.len()))
        .collect();
    for b in &m.base_materials {
        if b.bases.is_empty() {
            return Err(bad(format!("basematerials {} has no base", b.id)));
        }
    }
    let colours: HashMap<u32, usize> = m
        .color_groups
        .iter()
        .map(|g| (g.id, g.colors.len()))
        .collect();
    for g in &m.color_groups {
        if g.colors.is_empty() {
            return Err(bad(format!("colorgroup {} has no colour", g.id)));
        }
    }
    for c in &m.composite_materials {
        let n = *bases.get(&c.base_materials).ok_or_else(|| {
            bad(format!(
                "compositematerials {} references missing basematerials {}",
                c.id, c.base_materials
            ))
        })?;
        if c.material_indices.iter().any(|&i| i as usize >= n) {
            return Err(bad(format!(
                "compositematerials {}: material index out of range",
                c.id
            )));
        }
        for (k, v) in c.composites.iter().enumerate() {
            if v.len() != c.material_indices.len() || v.iter().any(|x| !x.is_finite() || *x < 0.0) {
                return Err(bad(format!(
                    "compositematerials {} composite {k}: needs {} finite non-negative values",
                    c.id,
                    c.material_indices.len()
                )));
            }
        }
    }
    let images: HashSet<u32> = m.images.iter().map(|i| i.id).collect();
    for im in &m.images {
        check_dims(im.dims, im.layout, im.bit_depth).map_err(Error::BadInput)?;
        let want = im.dims.iter().product::<usize>() * im.layout.channels();
        if im.samples.len() != want {
            return Err(bad(format!(
                "image3d {}: {} samples, dims need {want}",
                im.id,
                im.samples.len()
            )));
        }
        let max = ((1u32 << im.bit_depth) - 1) as u16;
        if im.samples.iter().any(|&s| s > max) {
            return Err(bad(format!(
                "image3d {}: sample above {max} for bit depth {}",
                im.id, im.bit_depth
            )));
        }
    }
    for f in &m.image_functions {
        if !images.contains(&f.image) {
            return Err(bad(format!(
                "functionfromimage3d {} references missing image3d {}",
                f.id, f.image
            )));
        }
        if !f.value_offset.is_finite() || !f.value_scale.is_finite() {
            return Err(bad(format!(
                "functionfromimage3d {}: offset and scale must be finite",
                f.id
            )));
        }
    }
    for f in &m.implicit_functions {
        f.validate()
            .map_err(|e| bad(format!("implicitfunction {}: {e}", f.id)))?;
    }
    let functions: HashSet<u32> = m
        .image_functions
        .iter()
        .map(|f| f.id)
        .chain(m.implicit_functions.iter().map(|f| f.id))
        .collect();
    let check_ref = |r: &FunctionRef, what: &str| -> Result<()> {
        if !functions.contains(&r.function) {
            return Err(bad(format!(
                "{what} references missing function {}",
                r.function
            )));
        }
        if !crate::implicit::is_identifier(&r.channel) {
            return Err(bad(format!(
                "{what}: channel `{}` is not an identifier",
                r.channel
            )));
        }
        finite3(&r.transform.0, || format!("{what} transform"))
    };
    for vd in &m.volume_data {
        if let Some(c) = &vd.composite {
            let n = *bases.get(&c.base_materials).ok_or_else(|| {
                bad(format!(
                    "volumedata {}: composite references missing basematerials {}",
                    vd.id, c.base_materials
                ))
            })?;
            if c.mappings.len() != n {
                return Err(bad(format!(
                    "volumedata {}: composite needs one materialmapping per base material ({n}), got {}",
                    vd.id,
                    c.mappings.len()
                )));
            }
            for mm in &c.mappings {
                check_ref(mm, &format!("volumedata {} materialmapping", vd.id))?;
            }
        }
        if let Some(c) = &vd.color {
            check_ref(c, &format!("volumedata {} color", vd.id))?;
        }
        let mut names = HashSet::new();
        for p in &vd.properties {
            check_ref(
                &p.value,
                &format!("volumedata {} property {}", vd.id, p.name),
            )?;
            if !names.insert(&p.name) {
                return Err(bad(format!(
                    "volumedata {}: property {} twice",
                    vd.id, p.name
                )));
            }
        }
    }
    let volumes: HashSet<u32> = m.volume_data.iter().map(|v| v.id).collect();
    let stacks: HashSet<u32> = m.slice_stacks.iter().map(|s| s.id).collect();
    for st in &m.slice_stacks {
        if !st.zbottom.is_finite() {
            return Err(bad(format!("slicestack {}: zbottom not finite", st.id)));
        }
        let mut z = st.zbottom;
        for (k, sl) in st.slices.iter().enumerate() {
            if sl.ztop.partial_cmp(&z) != Some(std::cmp::Ordering::Greater) || !sl.ztop.is_finite()
            {
                return Err(bad(format!(
                    "slicestack {} slice {k}: ztop {} must be finite and above the previous top {z}",
                    st.id, sl.ztop
                )));
            }
            z = sl.ztop;
            for (j, p) in sl.polygons.iter().enumerate() {
                if p.len() < 3 {
                    return Err(bad(format!(
                        "slicestack {} slice {k} polygon {j}: fewer than 3 vertices",
                        st.id
                    )));
                }
                if p.iter().flatten().any(|v| !v.is_finite()) {
                    return Err(bad(format!(
                        "slicestack {} slice {k} polygon {j}: coordinate not finite",
                        st.id
                    )));
                }
            }
        }
    }
    // Objects: references only to objects defined earlier.
    let mut defined: HashMap<u32, &Object> = HashMap::new();
    for o in &m.objects {
        let oname = || format!("object {}", o.id);
        if let Some(s) = o.slice_stack {
            if !stacks.contains(&s) {
                return Err(bad(format!(
                    "object {} references missing slicestack {s}",
                    o.id
                )));
            }
        }
        if let Some((pid, pindex)) = o.property {
            match bases.get(&pid).or_else(|| colours.get(&pid)) {
                Some(&n) if (pindex as usize) < n => {}
                _ if m.composite_materials.iter().any(|c| c.id == pid) => {}
                _ => {
                    return Err(bad(format!(
                        "object {}: property {pid}/{pindex} not defined",
                        o.id
                    )))
                }
            }
        }
        match &o.content {
            ObjectContent::Components(cs) => {
                if cs.is_empty() {
                    return Err(bad(format!("object {} has no components", o.id)));
                }
                for c in cs {
                    if !defined.contains_key(&c.object) {
                        return Err(bad(format!(
                            "object {}: component references object {}, which is not defined before it",
                            o.id, c.object
                        )));
                    }
                    finite3(&c.transform.0, || {
                        format!("object {} component transform", o.id)
                    })?;
                }
            }
            ObjectContent::LevelSet(l) => {
                if !functions.contains(&l.function) {
                    return Err(bad(format!(
                        "levelset object {} references missing function {}",
                        o.id, l.function
                    )));
                }
                match defined.get(&l.mesh) {
                    Some(mo) if matches!(mo.content, ObjectContent::Mesh(_)) => {}
                    _ => {
                        return Err(bad(format!(
                            "levelset object {}: meshid {} is not a mesh defined before it",
                            o.id, l.mesh
                        )))
                    }
                }
                if let Some(v) = l.volume_id {
                    if !volumes.contains(&v) {
                        return Err(bad(format!(
                            "levelset object {}: missing volumedata {v}",
                            o.id
                        )));
                    }
                }
                finite3(&l.transform.0, || {
                    format!("levelset object {} transform", o.id)
                })?;
            }
            ObjectContent::Mesh(me) => {
                let nv = me.vertices.len();
                for (i, p) in me.vertices.iter().enumerate() {
                    finite3(p, || format!("{} vertex {i}", oname()))?;
                }
                for (i, t) in me.triangles.iter().enumerate() {
                    if t.iter().any(|&v| v as usize >= nv)
                        || t[0] == t[1]
                        || t[1] == t[2]
                        || t[0] == t[2]
                    {
                        return Err(bad(format!(
                            "{} triangle {i} {t:?}: indices must be distinct and below the vertex count {nv}",
                            oname()
                        )));
                    }
                }
                if let Some(p) = &me.properties {
                    if p.indices.len() != me.triangles.len() {
                        return Err(bad(format!(
                            "{}: one property triple per triangle needed",
                            oname()
                        )));
                    }
                    let n = bases
                        .get(&p.pid)
                        .or_else(|| colours.get(&p.pid))
                        .copied()
                        .or_else(|| {
                            m.composite_materials
                                .iter()
                                .find(|c| c.id == p.pid)
                                .map(|c| c.composites.len())
                        })
                        .ok_or_else(|| {
                            bad(format!(
                                "{}: triangle property group {} not defined",
                                oname(),
                                p.pid
                            ))
                        })?;
                    if p.indices.iter().flatten().any(|&i| i as usize >= n) {
                        return Err(bad(format!(
                            "{}: triangle property index out of range",
                            oname()
                        )));
                    }
                    if o.property.is_none() {
                        return Err(bad(format!(
                            "{}: triangle properties need an object-level pid/pindex",
                            oname()
                        )));
                    }
                }
                if let Some(v) = me.volume_id {
                    if !volumes.contains(&v) {
                        return Err(bad(format!(
                            "{} references missing volumedata {v}",
                            oname()
                        )));
                    }
                }
                if me.triangles.is_empty()
                    && me.beam_lattice.is_none()
                    && o.kind != ObjectType::Other
                {
                    return Err(bad(format!("{} has no triangles", oname())));
                }
                if let Some(l) = &me.beam_lattice {
                    check_lattice(o.id, l, nv, &defined)?;
                    if !matches!(o.kind, ObjectType::Model | ObjectType::SolidSupport) {
                        return Err(bad(format!(
                            "{}: a beam lattice needs type model or solidsupport",
                            oname()
                        )));
                    }
                }
            }
        }
        defined.insert(o.id, o);
    }
    let sliced: HashSet<u32> = m
        .objects
        .iter()
        .filter(|o| o.slice_stack.is_some())
        .map(|o| o.id)
        .collect();
    for it in &m.build {
        let Some(o) = defined.get(&it.object) else {
            return Err(bad(format!(
                "build item references missing object {}",
                it.object
            )));
        };
        if o.kind == ObjectType::Other {
            return Err(bad(format!(
                "build item references object {} of type other",
                it.object
            )));
        }
        finite3(&it.transform.0, || {
            format!("build item {} transform", it.object)
        })?;
        let t = &it.transform.0;
        if sliced.contains(&it.object)
            && (t[2] != 0.0 || t[5] != 0.0 || t[6] != 0.0 || t[7] != 0.0 || t[8] != 1.0)
        {
            return Err(bad(format!(
                "build item {}: an object with slices allows only planar transforms (m02 = m12 = m20 = m21 = 0, m22 = 1)",
                it.object
            )));
        }
    }
    Ok(())
}
