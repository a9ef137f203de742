//! The beam lattice extension (1.2) and its balls: the lattice of a mesh,
//! and its checks.

use super::validate::bad;
use super::xml::{esc, Num};
use crate::beam::{BallMode, BeamLattice, ClipMode};
use crate::error::Result;
use crate::model::{Object, ObjectContent};
use std::collections::{HashMap, HashSet};
use std::io::Write;

/// The `<b:beamlattice>` of a mesh.
pub(super) fn write_lattice<W: Write>(w: &mut W, l: &BeamLattice) -> std::io::Result<()> {
    write!(
        w,
        "<b:beamlattice radius=\"{}\" minlength=\"{}\" cap=\"{}\"",
        Num(l.radius),
        Num(l.min_length),
        l.cap.name()
    )?;
    if let Some((mode, id)) = l.clipping {
        write!(w, " clippingmode=\"{}\" clippingmesh=\"{id}\"", mode.name())?;
    }
    if let Some(id) = l.representation {
        write!(w, " representationmesh=\"{id}\"")?;
    }
    if l.ball_mode != BallMode::None {
        write!(w, " b2:ballmode=\"{}\"", l.ball_mode.name())?;
    }
    if let Some(r) = l.ball_radius {
        write!(w, " b2:ballradius=\"{}\"", Num(r))?;
    }
    w.write_all(b">\n<b:beams>\n")?;
    for b in &l.beams {
        write!(w, "<b:beam v1=\"{}\" v2=\"{}\"", b.v1, b.v2)?;
        if b.r1 != l.radius || b.r2 != l.radius {
            write!(w, " r1=\"{}\"", Num(b.r1))?;
            if b.r2 != b.r1 {
                write!(w, " r2=\"{}\"", Num(b.r2))?;
            }
        }
        if let Some(c) = b.cap1 {
            write!(w, " cap1=\"{}\"", c.name())?;
        }
        if let Some(c) = b.cap2 {
            write!(w, " cap2=\"{}\"", c.name())?;
        }
        w.write_all(b"/>\n")?;
    }
    w.write_all(b"</b:beams>\n")?;
    if !l.balls.is_empty() {
        w.write_all(b"<b2:balls>\n")?;
        for b in &l.balls {
            write!(w, "<b2:ball vindex=\"{}\"", b.vindex)?;
            if let Some(r) = b.r {
                write!(w, " r=\"{}\"", Num(r))?;
            }
            w.write_all(b"/>\n")?;
        }
        w.write_all(b"</b2:balls>\n")?;
    }
    if !l.beam_sets.is_empty() {
        w.write_all(b"<b:beamsets>\n")?;
        for s in &l.beam_sets {
            w.write_all(b"<b:beamset")?;
            if let Some(n) = &s.name {
                write!(w, " name=\"{}\"", esc(n))?;
            }
            if let Some(n) = &s.identifier {
                write!(w, " identifier=\"{}\"", esc(n))?;
            }
            w.write_all(b">")?;
            for i in &s.beams {
                write!(w, "<b:ref index=\"{i}\"/>")?;
            }
            for i in &s.balls {
                write!(w, "<b2:ballref index=\"{i}\"/>")?;
            }
            w.write_all(b"</b:beamset>\n")?;
        }
        w.write_all(b"</b:beamsets>\n")?;
    }
    w.write_all(b"</b:beamlattice>\n")
}

/// Checks a beam lattice of object `id` (`nv` vertices; `defined`: the
/// objects before it).
pub(super) fn check_lattice(
    id: u32,
    l: &BeamLattice,
    nv: usize,
    defined: &HashMap<u32, &Object>,
) -> Result<()> {
    let what = || format!("object {id} beam lattice");
    let pos = |v: f64| v.is_finite() && v > 0.0;
    if !pos(l.radius) || !pos(l.min_length) {
        return Err(bad(format!(
            "{}: radius and minlength must be positive and finite",
            what()
        )));
    }
    for (i, b) in l.beams.iter().enumerate() {
        if b.v1 as usize >= nv || b.v2 as usize >= nv || b.v1 == b.v2 {
            return Err(bad(format!(
                "{} beam {i} ({}, {}): needs two distinct vertex indices below {nv}",
                what(),
                b.v1,
                b.v2
            )));
        }
        if !pos(b.r1) || !pos(b.r2) {
            return Err(bad(format!(
                "{} beam {i}: radii must be positive and finite",
                what()
            )));
        }
    }
    if l.ball_mode != BallMode::None && !l.ball_radius.is_some_and(pos) {
        return Err(bad(format!(
            "{}: ball mode {} needs a positive ball radius",
            what(),
            l.ball_mode.name()
        )));
    }
    if !l.balls.is_empty() && l.ball_mode == BallMode::None {
        return Err(bad(format!("{}: balls given with ball mode none", what())));
    }
    let ends: HashSet<u32> = l.beams.iter().flat_map(|b| [b.v1, b.v2]).collect();
    for (i, b) in l.balls.iter().enumerate() {
        if !ends.contains(&b.vindex) {
            return Err(bad(format!(
                "{} ball {i}: vertex {} is not a beam end",
                what(),
                b.vindex
            )));
        }
        if b.r.is_some_and(|r| !pos(r)) {
            return Err(bad(format!("{} ball {i}: radius must be positive", what())));
        }
    }
    for s in &l.beam_sets {
        if s.beams.iter().any(|&i| i as usize >= l.beams.len())
            || s.balls.iter().any(|&i| i as usize >= l.balls.len())
        {
            return Err(bad(format!("{}: beam set reference out of range", what())));
        }
    }
    let mesh_ref = |rid: u32, role: &str| -> Result<()> {
        match defined.get(&rid).map(|o| &o.content) {
            Some(ObjectContent::Mesh(me)) if me.beam_lattice.is_none() && rid != id => Ok(()),
            Some(_) => Err(bad(format!(
                "{}: {role} {rid} must be a mesh object without a beam lattice",
                what()
            ))),
            None => Err(bad(format!(
                "{}: {role} {rid} is not an object defined before it",
                what()
            ))),
        }
    };
    if let Some((mode, cid)) = l.clipping {
        if mode == ClipMode::None {
            return Err(bad(format!(
                "{}: a clipping mesh needs clipping mode inside or outside",
                what()
            )));
        }
        mesh_ref(cid, "clippingmesh")?;
    }
    if let Some(rid) = l.representation {
        mesh_ref(rid, "representationmesh")?;
    }
    Ok(())
}
