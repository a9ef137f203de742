//! The core namespace: metadata, resources, objects with their meshes and
//! components, and the build; and the references between resources,
//! checked once the whole model is read.

use super::parser::{Attrs, Ctx, Ns, Parser};
use super::values::{parse_id, parse_index, parse_num, parse_transform};
use crate::error::{invalid, Result};
use crate::model::*;
use quick_xml::events::BytesStart;
use std::collections::HashMap;

impl Parser<'_> {
    /// Vertices and triangles, parsed from the attribute bytes.
    pub(super) fn core_hot(
        &mut self,
        parent: Ctx,
        ens: Ns,
        name: &str,
        e: &BytesStart,
    ) -> Result<Option<Ctx>> {
        use Ctx::*;
        match (parent, ens, name) {
            (Vertices, Ns::Core, "vertex") => self.vertex(e).map(Some),
            (Triangles, Ns::Core, "triangle") => self.triangle(e).map(Some),
            _ => Ok(None),
        }
    }

    /// A `<vertex>` of a mesh.
    fn vertex(&mut self, e: &BytesStart) -> Result<Ctx> {
        use Ctx::*;
        let mut p = [f64::NAN; 3];
        for a in e.attributes().flatten() {
            let i = match a.key.as_ref() {
                b"x" => 0,
                b"y" => 1,
                b"z" => 2,
                _ => continue,
            };
            let v = std::str::from_utf8(&a.value).unwrap_or("?");
            p[i] = parse_num(self.part, self.off, "vertex coordinate", v)?;
        }
        if p.iter().any(|c| c.is_nan()) {
            let n = self.mesh.as_ref().map_or(0, |m| m.vertices.len());
            return Err(self.err(format!("vertex {n} lacks x, y or z")));
        }
        self.charge::<[f64; 3]>("vertice")?;
        self.mesh.as_mut().expect("inside a mesh").vertices.push(p);
        Ok(Skip)
    }

    /// A `<triangle>` of a mesh, with its properties.
    fn triangle(&mut self, e: &BytesStart) -> Result<Ctx> {
        use Ctx::*;
        let mut t = [u32::MAX; 3];
        let mut pr = [u32::MAX; 3];
        let mut pid = None;
        for a in e.attributes().flatten() {
            let v = std::str::from_utf8(&a.value).unwrap_or("?");
            match a.key.as_ref() {
                b"v1" => t[0] = parse_index(self.part, self.off, "v1", v)?,
                b"v2" => t[1] = parse_index(self.part, self.off, "v2", v)?,
                b"v3" => t[2] = parse_index(self.part, self.off, "v3", v)?,
                b"p1" => pr[0] = parse_index(self.part, self.off, "p1", v)?,
                b"p2" => pr[1] = parse_index(self.part, self.off, "p2", v)?,
                b"p3" => pr[2] = parse_index(self.part, self.off, "p3", v)?,
                b"pid" => pid = Some(parse_id(self.part, self.off, "pid", v)?),
                _ => {}
            }
        }
        let mesh = self.mesh.as_mut().expect("inside a mesh");
        let n = mesh.vertices.len() as u32;
        let k = mesh.triangles.len();
        if t.iter().any(|&v| v >= n) {
            return Err(self.err(format!(
                "triangle {k} has vertex indices {t:?}; the mesh has {n} vertices (or v1, v2, v3 missing)"
            )));
        }
        if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
            return Err(self.err(format!("triangle {k} repeats a vertex: {t:?}")));
        }
        mesh.triangles.push(t);
        self.charge::<[u32; 6]>("triangle")?;
        // Properties are kept when the whole mesh uses one group.
        if let (Some(pid), true) = (pid, pr[0] != u32::MAX) {
            let q = [
                pr[0],
                if pr[1] == u32::MAX { pr[0] } else { pr[1] },
                if pr[2] == u32::MAX { pr[0] } else { pr[2] },
            ];
            if self.tri_pids.is_none() && k == 0 {
                self.tri_pids = Some(pid);
            }
            if self.tri_pids != Some(pid) {
                self.tri_props_ok = false;
            }
            self.tri_props.push(q);
        } else {
            self.tri_props_ok = false;
        }
        Ok(Skip)
    }

    /// Core elements other than vertices and triangles (`None`: not one of them).
    pub(super) fn core_start(
        &mut self,
        parent: Ctx,
        ens: Ns,
        name: &str,
        a: &Attrs,
    ) -> Result<Option<Ctx>> {
        use Ctx::*;
        let (part, off) = (self.part, self.off);
        let get = |n: &str| a.get(n);
        let get_ns = |ns: Ns, n: &str| a.get_ns(ns, n);
        let need = |n: &str| a.need(n);
        let ctx = match (parent, ens, name) {
            (Model, Ns::Core, "metadata") => {
                self.metadata_name = Some(need("name")?.to_string());
                self.text.clear();
                Metadata
            }
            (Model, Ns::Core, "resources") => Resources,
            (Model, Ns::Core, "build") => Build,
            (Build, Ns::Core, "item") => {
                let object = parse_id(part, off, "objectid", need("objectid")?)?;
                let transform = match get("transform") {
                    Some(t) => parse_transform(part, off, t)?,
                    None => Transform::IDENTITY,
                };
                self.charge::<BuildItem>("build item")?;
                self.model.build.push(BuildItem {
                    object,
                    transform,
                    part_number: get("partnumber").map(str::to_string),
                });
                Skip
            }
            (Resources, Ns::Core, "object") => {
                let id = parse_id(part, off, "id", need("id")?)?;
                self.resource_id(id, "object")?;
                let kind = match get("type") {
                    Some(t) => ObjectType::from_name(t.trim())
                        .ok_or_else(|| self.err(format!("unknown object type \"{t}\"")))?,
                    None => ObjectType::Model,
                };
                let property = match (get("pid"), get("pindex")) {
                    (Some(a), b) => Some((
                        parse_id(part, off, "pid", a)?,
                        parse_index(part, off, "pindex", b.unwrap_or("0"))?,
                    )),
                    _ => None,
                };
                let slice_stack = get_ns(Ns::Slice, "slicestackid")
                    .map(|v| parse_id(part, off, "s:slicestackid", v))
                    .transpose()?;
                if get_ns(Ns::Slice, "slicepath").is_some() {
                    return Err(self.err("s:slicepath on an object (slices of another part) is not supported; use <s:sliceref>"));
                }
                let mesh_resolution = match get_ns(Ns::Slice, "meshresolution") {
                    Some("lowres") => MeshResolution::Low,
                    Some("fullres") | None => MeshResolution::Full,
                    Some(v) => return Err(self.err(format!("unknown s:meshresolution \"{v}\""))),
                };
                self.object = Some(crate::model::Object {
                    id,
                    name: get("name").map(str::to_string),
                    part_number: get("partnumber").map(str::to_string),
                    kind,
                    property,
                    content: ObjectContent::Components(Vec::new()),
                    slice_stack,
                    mesh_resolution,
                });
                Object
            }
            (Object, Ns::Core, "mesh") => {
                let volume_id = get_ns(Ns::Volumetric, "volumeid")
                    .map(|v| parse_id(part, off, "v:volumeid", v))
                    .transpose()?;
                self.mesh = Some(crate::model::Mesh {
                    volume_id,
                    ..Default::default()
                });
                self.tri_pids = None;
                self.tri_props.clear();
                self.tri_props_ok = true;
                Mesh
            }
            (Object, Ns::Core, "components") => {
                self.components.clear();
                Components
            }
            (Components, Ns::Core, "component") => {
                let object = parse_id(part, off, "objectid", need("objectid")?)?;
                let transform = match get("transform") {
                    Some(t) => parse_transform(part, off, t)?,
                    None => Transform::IDENTITY,
                };
                self.charge::<Component>("component")?;
                self.components.push(Component { object, transform });
                Skip
            }
            (Mesh, Ns::Core, "vertices") => Vertices,
            (Mesh, Ns::Core, "triangles") => Triangles,
            _ => return Ok(None),
        };
        Ok(Some(ctx))
    }

    /// Closes a core element.
    pub(super) fn core_end(&mut self, ctx: Ctx) -> Result<()> {
        use Ctx::*;
        match ctx {
            Metadata => {
                let name = self.metadata_name.take().unwrap_or_default();
                let value = std::mem::take(&mut self.text);
                self.model
                    .metadata
                    .push(crate::model::Metadata { name, value });
            }
            Mesh => {
                let mut mesh = self.mesh.take().unwrap();
                mesh.beam_lattice = self.lattice.take();
                if self.tri_props_ok
                    && !mesh.triangles.is_empty()
                    && self.tri_props.len() == mesh.triangles.len()
                {
                    mesh.properties = Some(TriangleProperties {
                        pid: self.tri_pids.unwrap(),
                        indices: std::mem::take(&mut self.tri_props),
                    });
                }
                self.object.as_mut().unwrap().content = ObjectContent::Mesh(mesh);
            }
            Components => {
                if self.components.is_empty() {
                    return Err(self.err("<components> without a component"));
                }
                self.object.as_mut().unwrap().content =
                    ObjectContent::Components(std::mem::take(&mut self.components));
            }
            Object => {
                let o = self.object.take().unwrap();
                if matches!(&o.content, ObjectContent::Components(c) if c.is_empty()) {
                    return Err(
                        self.err(format!("object {} has neither a mesh nor components", o.id))
                    );
                }
                self.model.objects.push(o);
            }
            _ => {}
        }
        Ok(())
    }
}

/// References between resources, checked after the whole model is read.
pub(super) fn check_references(m: &Model, part: &str) -> Result<()> {
    let objects: HashMap<u32, &crate::model::Object> =
        m.objects.iter().map(|o| (o.id, o)).collect();
    let e = |msg: String| invalid(part, 0, msg);
    for o in &m.objects {
        if let ObjectContent::Components(cs) = &o.content {
            for c in cs {
                if !objects.contains_key(&c.object) {
                    return Err(e(format!(
                        "object {}: component references missing object {}",
                        o.id, c.object
                    )));
                }
            }
        }
        if let ObjectContent::Mesh(me) = &o.content {
            if let Some(l) = &me.beam_lattice {
                for r in l.clipping.map(|c| c.1).into_iter().chain(l.representation) {
                    if !matches!(
                        objects.get(&r).map(|x| &x.content),
                        Some(ObjectContent::Mesh(_))
                    ) {
                        return Err(e(format!(
                            "object {}: lattice references {r}, which is not a mesh object",
                            o.id
                        )));
                    }
                }
            }
        }
        if let Some(s) = o.slice_stack {
            if !m.slice_stacks.iter().any(|st| st.id == s) {
                return Err(e(format!("object {}: missing slicestack {s}", o.id)));
            }
        }
    }
    for it in &m.build {
        if !objects.contains_key(&it.object) {
            return Err(e(format!(
                "build item references missing object {}",
                it.object
            )));
        }
    }
    Ok(())
}
