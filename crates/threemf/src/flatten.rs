//! World-space geometry from a model: build items and components resolved,
//! transforms applied, units converted to millimetres.

use crate::beam::Beam;
use crate::error::{invalid, Result};
use crate::model::{Model, ObjectContent, Transform};
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

/// Visits every mesh object instance reachable from the build with its
/// world transform (model units to mm included).
fn instances(
    m: &Model,
    f: &mut dyn FnMut(&crate::model::Object, &Transform, &str) -> Result<()>,
) -> Result<()> {
    let mm = Transform::scale([m.unit.to_mm(); 3]);
    fn walk(
        m: &Model,
        id: u32,
        t: Transform,
        name: &str,
        depth: usize,
        f: &mut dyn FnMut(&crate::model::Object, &Transform, &str) -> Result<()>,
    ) -> Result<()> {
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
        match &o.content {
            ObjectContent::Components(cs) => {
                for c in cs {
                    walk(m, c.object, c.transform.then(&t), name, depth + 1, f)?;
                }
                Ok(())
            }
            _ => f(o, &t, name),
        }
    }
    for it in &m.build {
        let base = it.transform.then(&mm);
        let tag = it.part_number.clone().unwrap_or_default();
        walk(m, it.object, base, &tag, 0, f)?;
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
    let mut out = Vec::new();
    instances(m, &mut |o, t, tag| {
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
    let mut out = Vec::new();
    instances(m, &mut |o, t, tag| {
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
    meshes(&crate::read::read_file(path)?)
}

/// Reads the package at `path` and gives its beam lattices ([`lattices`]).
pub fn read_beam_lattices(path: impl AsRef<Path>) -> Result<Vec<NamedLattice>> {
    lattices(&crate::read::read_file(path)?)
}
