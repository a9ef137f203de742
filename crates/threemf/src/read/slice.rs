//! The slice extension (1.0.2): slice stacks of polygons, and stacks
//! kept in other model parts (`<s:sliceref>`), read after the root part.

use super::package::{open_counted, predicted_from_xml, Budget};
use super::parser::{parse_model, Attrs, Ctx, Ns, Parser, Refs};
use super::values::{parse_id, parse_index, parse_num};
use crate::error::{invalid, Result};
use crate::model::Model;
use crate::slice::Slice;
use quick_xml::events::BytesStart;
use std::io::{BufReader, Read, Seek};

impl Parser<'_> {
    /// Slice vertices and polygon segments, parsed from the attribute bytes.
    pub(super) fn slice_hot(
        &mut self,
        parent: Ctx,
        ens: Ns,
        name: &str,
        e: &BytesStart,
    ) -> Result<Option<Ctx>> {
        use Ctx::*;
        match (parent, ens, name) {
            (SliceVertices, Ns::Slice, "vertex") => self.slice_vertex(e).map(Some),
            (Polygon, Ns::Slice, "segment") => self.segment(e).map(Some),
            _ => Ok(None),
        }
    }

    /// An `<s:vertex>` of a slice.
    fn slice_vertex(&mut self, e: &BytesStart) -> Result<Ctx> {
        use Ctx::*;
        let mut p = [f64::NAN; 2];
        for a in e.attributes().flatten() {
            let i = match a.key.as_ref() {
                b"x" => 0,
                b"y" => 1,
                _ => continue,
            };
            let v = std::str::from_utf8(&a.value).unwrap_or("?");
            p[i] = parse_num(self.part, self.off, "slice vertex coordinate", v)?;
        }
        if p.iter().any(|c| c.is_nan()) {
            return Err(self.err("slice vertex lacks x or y"));
        }
        self.charge::<[f64; 2]>("slice vertice")?;
        self.slice_vertices.push(p);
        Ok(Skip)
    }

    /// An `<s:segment>` of a polygon.
    fn segment(&mut self, e: &BytesStart) -> Result<Ctx> {
        use Ctx::*;
        let mut v2 = u32::MAX;
        for a in e.attributes().flatten() {
            if a.key.as_ref() == b"v2" {
                let v = std::str::from_utf8(&a.value).unwrap_or("?");
                v2 = parse_index(self.part, self.off, "v2", v)?;
            }
        }
        if v2 as usize >= self.slice_vertices.len() {
            return Err(self.err(format!(
                "segment v2 = {v2} is not below the slice's {} vertices",
                self.slice_vertices.len()
            )));
        }
        self.charge::<[f64; 3]>("polygon segment")?;
        self.polygon.as_mut().expect("inside a polygon").1.push(v2);
        Ok(Skip)
    }

    /// Slice elements other than vertices and segments (`None`: not one of them).
    pub(super) fn slice_start(
        &mut self,
        parent: Ctx,
        ens: Ns,
        name: &str,
        a: &Attrs,
    ) -> Result<Option<Ctx>> {
        use Ctx::*;
        let (part, off) = (self.part, self.off);
        let get = |n: &str| a.get(n);
        let need = |n: &str| a.need(n);
        let ctx = match (parent, ens, name) {
            (Resources, Ns::Slice, "slicestack") => {
                let id = parse_id(part, off, "id", need("id")?)?;
                self.resource_id(id, "slicestack")?;
                let zbottom = get("zbottom")
                    .map(|v| parse_num(part, off, "zbottom", v))
                    .transpose()?
                    .unwrap_or(0.0);
                self.stack = Some(crate::slice::SliceStack {
                    id,
                    zbottom,
                    slices: Vec::new(),
                });
                self.stack_refs.clear();
                SliceStack
            }
            (SliceStack, Ns::Slice, "slice") => {
                let ztop = parse_num(part, off, "ztop", need("ztop")?)?;
                let st = self.stack.as_ref().unwrap();
                let below = st.slices.last().map(|s| s.ztop).unwrap_or(st.zbottom);
                if ztop.partial_cmp(&below) != Some(std::cmp::Ordering::Greater) {
                    return Err(self.err(format!(
                        "slice ztop {ztop} does not increase (previous {below})"
                    )));
                }
                if !self.stack_refs.is_empty() {
                    return Err(self.err("a slicestack must not mix <slice> and <sliceref>"));
                }
                self.slice = Some(crate::slice::Slice {
                    ztop,
                    polygons: Vec::new(),
                });
                self.slice_vertices.clear();
                Slice
            }
            (SliceStack, Ns::Slice, "sliceref") => {
                let id = parse_id(part, off, "slicestackid", need("slicestackid")?)?;
                let path = need("slicepath")?.to_string();
                if !self.stack.as_ref().unwrap().slices.is_empty() {
                    return Err(self.err("a slicestack must not mix <slice> and <sliceref>"));
                }
                self.stack_refs.push((id, path, off));
                Skip
            }
            (Slice, Ns::Slice, "vertices") => SliceVertices,
            (Slice, Ns::Slice, "polygon") => {
                let s = parse_index(part, off, "startv", need("startv")?)?;
                if s as usize >= self.slice_vertices.len() {
                    return Err(self.err(format!(
                        "polygon startv {s} is not below the {} vertices",
                        self.slice_vertices.len()
                    )));
                }
                self.polygon = Some((s, Vec::new()));
                Polygon
            }
            _ => return Ok(None),
        };
        Ok(Some(ctx))
    }

    /// Closes a slice element.
    pub(super) fn slice_end(&mut self, ctx: Ctx) -> Result<()> {
        use Ctx::*;
        match ctx {
            Polygon => {
                let (start, segs) = self.polygon.take().unwrap();
                if segs.last() != Some(&start) {
                    return Err(self.err("open polygon: its last segment must end at startv (open polygons, for support, are not supported)"));
                }
                let mut poly = Vec::with_capacity(segs.len());
                poly.push(self.slice_vertices[start as usize]);
                for &v in &segs[..segs.len() - 1] {
                    poly.push(self.slice_vertices[v as usize]);
                }
                self.slice.as_mut().unwrap().polygons.push(poly);
            }
            Slice => {
                let s = self.slice.take().unwrap();
                self.stack.as_mut().unwrap().slices.push(s);
            }
            SliceStack => {
                let st = self.stack.take().unwrap();
                if !self.stack_refs.is_empty() {
                    self.refs
                        .slice_refs
                        .push((st.id, std::mem::take(&mut self.stack_refs)));
                }
                self.model.slice_stacks.push(st);
            }
            _ => {}
        }
        Ok(())
    }
}

/// Reads the slice stacks kept in other parts (`refs`, from the root part
/// `root`) into the stacks of `model` that reference them.
pub(super) fn read_slice_refs<R: Read + Seek>(
    zip: &mut zip::ZipArchive<R>,
    root: &str,
    model: &mut Model,
    refs: Refs,
    budget: &Budget,
) -> Result<()> {
    for (stack_id, refs) in refs.slice_refs {
        let mut slices = Vec::new();
        for (ref_id, path, offset) in refs {
            let part = path.trim_start_matches('/').to_string();
            let ctx = format!("sliceref of slicestack {stack_id} in /{root}");
            let f = open_counted(zip, &part, &ctx, predicted_from_xml, budget)?;
            let (sub, subrefs) = parse_model(BufReader::new(f), &part, budget)?;
            if !subrefs.slice_refs.is_empty() {
                return Err(invalid(
                    &part,
                    0,
                    "a referenced slice stack must not hold further slicerefs",
                ));
            }
            let st = sub
                .slice_stacks
                .into_iter()
                .find(|s| s.id == ref_id)
                .ok_or_else(|| {
                    invalid(
                        root,
                        offset,
                        format!("slicestack {ref_id} not found in /{part}"),
                    )
                })?;
            let last = slices.last().map(|s: &Slice| s.ztop);
            if let (Some(z), Some(first)) = (last, st.slices.first()) {
                if first.ztop.partial_cmp(&z) != Some(std::cmp::Ordering::Greater) {
                    return Err(invalid(
                        &part,
                        0,
                        format!(
                            "slice tops must increase across parts: {} after {z}",
                            first.ztop
                        ),
                    ));
                }
            }
            slices.extend(st.slices);
        }
        if let Some(st) = model.slice_stacks.iter_mut().find(|s| s.id == stack_id) {
            st.slices = slices;
        }
    }
    Ok(())
}
