//! World-space geometry from a model: build items and components resolved,
//! transforms applied, units converted to millimetres.

use crate::beam::Beam;
use crate::error::{invalid, Error, Result};
use crate::model::{Model, ObjectContent, Transform};
use crate::read::ReadOptions;
use std::collections::HashMap;
use std::path::Path;

/// A triangle mesh in world coordinates, millimetres.
#[derive(Clone, Debug, PartialEq)]
pub struct NamedMesh {
    /// Object name, else `object <id>` (with the build item's part number
    /// when it has one).
    pub name: String,
    /// Vertices (mm, world space).
    pub vertices: Vec<[f64; 3]>,
    /// Triangles, counter-clockwise seen from outside (kept so under
    /// mirroring transforms, as the core specification requires).
    pub triangles: Vec<[u32; 3]>,
}

/// A beam lattice in world coordinates, millimetres.
#[derive(Clone, Debug, PartialEq)]
pub struct NamedLattice {
    /// As for [`NamedMesh::name`].
    pub name: String,
    /// Node positions (mm, world space): the mesh vertices.
    pub nodes: Vec<[f64; 3]>,
    /// Beams with radii in mm (scaled by the unit and by the cube root of
    /// the transform's determinant: exact for similarity transforms).
    pub beams: Vec<Beam>,
}

/// Deepest component nesting followed (deeper is treated as a cycle).
const MAX_DEPTH: usize = 64;

/// What flattening a model gives: instances of mesh objects, vertices,
/// triangles and beams, counted through the component tree without
/// expanding it (each object once), saturating at `u64::MAX`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Expansion {
    /// Mesh object instances.
    pub instances: u64,
    /// Vertices of instances with triangles.
    pub vertices: u64,
    /// Triangles.
    pub triangles: u64,
    /// Instances with beam lattices.
    pub lattice_instances: u64,
    /// Vertices of instances with beam lattices (lattice nodes).
    pub nodes: u64,
    /// Beams.
    pub beams: u64,
}

impl Expansion {
    fn add(self, o: Expansion) -> Expansion {
        Expansion {
            instances: self.instances.saturating_add(o.instances),
            vertices: self.vertices.saturating_add(o.vertices),
            triangles: self.triangles.saturating_add(o.triangles),
            lattice_instances: self.lattice_instances.saturating_add(o.lattice_instances),
            nodes: self.nodes.saturating_add(o.nodes),
            beams: self.beams.saturating_add(o.beams),
        }
    }

    /// Bytes of the flattened triangle meshes ([`meshes`]).
    pub fn mesh_bytes(&self) -> u64 {
        self.vertices
            .saturating_mul(24)
            .saturating_add(self.triangles.saturating_mul(12))
    }

    /// Bytes of the flattened lattices ([`lattices`]).
    pub fn lattice_bytes(&self) -> u64 {
        self.nodes.saturating_mul(24).saturating_add(
            self.beams
                .saturating_mul(std::mem::size_of::<Beam>() as u64),
        )
    }
}

/// Counts what flattening `m` gives ([`Expansion`]), in time linear in the
/// number of objects and components however deep the sharing goes. Errors
/// as flattening does: missing objects, nesting deeper than 64 (a cycle).
pub fn expansion(m: &Model) -> Result<Expansion> {
    counts(m).map(|(total, _)| total)
}

/// [`expansion`] of the whole build, and of each object reached.
fn counts(m: &Model) -> Result<(Expansion, HashMap<u32, Expansion>)> {
    fn count(
        m: &Model,
        id: u32,
        depth: usize,
        memo: &mut HashMap<u32, Expansion>,
    ) -> Result<Expansion> {
        if let Some(e) = memo.get(&id) {
            return Ok(*e);
        }
        let o = object_at(m, id, depth)?;
        let e = match &o.content {
            ObjectContent::Components(cs) => {
                let mut e = Expansion::default();
                for c in cs {
                    e = e.add(count(m, c.object, depth + 1, memo)?);
                }
                e
            }
            ObjectContent::Mesh(me) => {
                let tris = !me.triangles.is_empty();
                let beams = me.beam_lattice.as_ref().map_or(0, |l| l.beams.len() as u64);
                Expansion {
                    instances: 1,
                    vertices: if tris { me.vertices.len() as u64 } else { 0 },
                    triangles: me.triangles.len() as u64,
                    lattice_instances: u64::from(me.beam_lattice.is_some()),
                    nodes: if me.beam_lattice.is_some() {
                        me.vertices.len() as u64
                    } else {
                        0
                    },
                    beams,
                }
            }
            _ => Expansion {
                instances: 1,
                ..Expansion::default()
            },
        };
        memo.insert(id, e);
        Ok(e)
    }
    let mut memo = HashMap::new();
    let mut total = Expansion::default();
    for it in &m.build {
        total = total.add(count(m, it.object, 0, &mut memo)?);
    }
    Ok((total, memo))
}

/// Object `id`, reached through `depth` components: an error when it is
/// missing or deeper than [`MAX_DEPTH`] (a cycle).
fn object_at(m: &Model, id: u32, depth: usize) -> Result<&crate::model::Object> {
    let o = m
        .object(id)
        .ok_or_else(|| invalid("model", 0, format!("missing object {id}")))?;
    if depth > MAX_DEPTH {
        return Err(invalid(
            "model",
            0,
            format!("components nest deeper than {MAX_DEPTH} at object {id} (a cycle?)"),
        ));
    }
    Ok(o)
}

/// Refuses an expansion that does not fit `limit` bytes or 32-bit indices.
fn check_expansion(e: &Expansion, bytes: u64, what: &str, limit: u64) -> Result<()> {
    let too_large = |message: String| Error::TooLarge {
        part: "model".into(),
        message,
    };
    if bytes > limit {
        return Err(too_large(format!(
            "its build items expand (through components) into {} instances with {} {what}, \
             about {} MiB, more than the {} MiB this job may use (the memory limit)",
            e.instances,
            if what == "triangles" {
                e.triangles
            } else {
                e.beams
            },
            bytes >> 20,
            limit >> 20
        )));
    }
    let verts = if what == "triangles" {
        e.vertices
    } else {
        e.nodes
    };
    if verts > u32::MAX as u64 {
        return Err(too_large(format!(
            "its build items expand into {verts} vertices, more than 32-bit indices allow"
        )));
    }
    Ok(())
}

/// Visits every mesh object instance reachable from the build with its
/// world transform (model units to mm included), skipping the objects
/// (and all below them) whose counts in `memo` fail `keep`: a subtree that
/// gives nothing is not walked, so the walk's work is bounded by what it
/// gives (times the depth), not by the fan-out of the tree.
fn instances(
    m: &Model,
    memo: &HashMap<u32, Expansion>,
    keep: &dyn Fn(&Expansion) -> bool,
    f: &mut dyn FnMut(&crate::model::Object, &Transform, &str) -> Result<()>,
) -> Result<()> {
    let mm = Transform::scale([m.unit.to_mm(); 3]);
    type Keep<'a> = (&'a HashMap<u32, Expansion>, &'a dyn Fn(&Expansion) -> bool);
    fn walk(
        m: &Model,
        keep: Keep,
        id: u32,
        t: Transform,
        name: &str,
        depth: usize,
        f: &mut dyn FnMut(&crate::model::Object, &Transform, &str) -> Result<()>,
    ) -> Result<()> {
        let o = object_at(m, id, depth)?;
        match &o.content {
            ObjectContent::Components(cs) => {
                for c in cs {
                    if keep.0.get(&c.object).is_some_and(|e| !(keep.1)(e)) {
                        continue;
                    }
                    walk(m, keep, c.object, c.transform.then(&t), name, depth + 1, f)?;
                }
                Ok(())
            }
            _ => f(o, &t, name),
        }
    }
    for it in &m.build {
        let base = it.transform.then(&mm);
        let tag = it.part_number.clone().unwrap_or_default();
        if memo.get(&it.object).is_some_and(|e| !keep(e)) {
            continue;
        }
        walk(m, (memo, keep), it.object, base, &tag, 0, f)?;
    }
    Ok(())
}

fn label(o: &crate::model::Object, tag: &str) -> String {
    let n = o.name.clone().unwrap_or_else(|| format!("object {}", o.id));
    if tag.is_empty() {
        n
    } else {
        format!("{n} ({tag})")
    }
}

/// The triangle meshes of every build item, flattened (components and
/// transforms applied) to world space in millimetres. Objects without
/// triangles (lattice-only, level sets) give nothing here; see
/// [`lattices`].
pub fn meshes(m: &Model) -> Result<Vec<NamedMesh>> {
    meshes_with(m, ReadOptions::default().memory_limit)
}

/// [`meshes`], refused before anything is expanded when the flattened
/// meshes would take more than `memory_limit` bytes ([`expansion`]).
pub fn meshes_with(m: &Model, memory_limit: u64) -> Result<Vec<NamedMesh>> {
    let (e, memo) = counts(m)?;
    check_expansion(&e, e.mesh_bytes(), "triangles", memory_limit)?;
    let mut out = Vec::new();
    instances(m, &memo, &|e| e.triangles > 0, &mut |o, t, tag| {
        if let ObjectContent::Mesh(me) = &o.content {
            if me.triangles.is_empty() {
                return Ok(());
            }
            let flip = t.determinant() < 0.0;
            out.push(NamedMesh {
                name: label(o, tag),
                vertices: me.vertices.iter().map(|p| t.apply(*p)).collect(),
                triangles: me
                    .triangles
                    .iter()
                    .map(|&[a, b, c]| if flip { [a, c, b] } else { [a, b, c] })
                    .collect(),
            });
        }
        Ok(())
    })?;
    Ok(out)
}

/// The beam lattices of every build item in world space, millimetres.
pub fn lattices(m: &Model) -> Result<Vec<NamedLattice>> {
    lattices_with(m, ReadOptions::default().memory_limit)
}

/// [`lattices`], refused before anything is expanded when the flattened
/// lattices would take more than `memory_limit` bytes.
pub fn lattices_with(m: &Model, memory_limit: u64) -> Result<Vec<NamedLattice>> {
    let (e, memo) = counts(m)?;
    check_expansion(&e, e.lattice_bytes(), "beams", memory_limit)?;
    let mut out = Vec::new();
    instances(m, &memo, &|e| e.lattice_instances > 0, &mut |o, t, tag| {
        if let ObjectContent::Mesh(me) = &o.content {
            if let Some(l) = &me.beam_lattice {
                let s = t.determinant().abs().cbrt();
                out.push(NamedLattice {
                    name: label(o, tag),
                    nodes: me.vertices.iter().map(|p| t.apply(*p)).collect(),
                    beams: l
                        .beams
                        .iter()
                        .map(|b| Beam {
                            r1: b.r1 * s,
                            r2: b.r2 * s,
                            ..*b
                        })
                        .collect(),
                });
            }
        }
        Ok(())
    })?;
    Ok(out)
}

/// Reads the package at `path` and flattens its meshes ([`meshes`]): the
/// entry point for `.3mf` input parts.
pub fn read_meshes(path: impl AsRef<Path>) -> Result<Vec<NamedMesh>> {
    read_meshes_with(path, &ReadOptions::default())
}

/// [`read_meshes`] within `opts.memory_limit`: the package read and its
/// flattened meshes together.
pub fn read_meshes_with(path: impl AsRef<Path>, opts: &ReadOptions) -> Result<Vec<NamedMesh>> {
    let m = crate::read::read_file_with(path, opts)?;
    meshes_with(&m, opts.memory_limit.saturating_sub(model_bytes(&m)))
}

/// Bytes held by the arrays of a model read (vertices, triangles, beams),
/// which stay in memory while it is flattened.
fn model_bytes(m: &Model) -> u64 {
    m.objects
        .iter()
        .map(|o| match &o.content {
            ObjectContent::Mesh(me) => {
                (me.vertices.len() * 24
                    + me.triangles.len() * 12
                    + me.beam_lattice
                        .as_ref()
                        .map_or(0, |l| l.beams.len() * std::mem::size_of::<Beam>()))
                    as u64
            }
            _ => 0,
        })
        .sum()
}

/// Reads the package at `path` and gives its beam lattices ([`lattices`]).
pub fn read_beam_lattices(path: impl AsRef<Path>) -> Result<Vec<NamedLattice>> {
    lattices(&crate::read::read_file(path)?)
}
