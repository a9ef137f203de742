//! The beam lattice extension (1.2), with the balls namespace (and its
//! unprefixed 1.1 draft attributes).

use super::parser::{Attrs, Ctx, Ns, Parser};
use super::values::{parse_id, parse_index, parse_num};
use crate::beam::{Ball, BallMode, Beam, BeamLattice, Cap, ClipMode};
use crate::error::{invalid, Result};
use quick_xml::events::BytesStart;

impl Parser<'_> {
    /// Beams, parsed from the attribute bytes.
    pub(super) fn beam_hot(
        &mut self,
        parent: Ctx,
        ens: Ns,
        name: &str,
        e: &BytesStart,
    ) -> Result<Option<Ctx>> {
        use Ctx::*;
        match (parent, ens, name) {
            (Beams, Ns::Beam, "beam") => self.beam(e).map(Some),
            _ => Ok(None),
        }
    }

    /// A `<b:beam>` of a lattice.
    fn beam(&mut self, e: &BytesStart) -> Result<Ctx> {
        use Ctx::*;
        let l = self.lattice.as_ref().expect("inside a lattice");
        let (mut v1, mut v2) = (u32::MAX, u32::MAX);
        let (mut r1, mut r2) = (None, None);
        let (mut c1, mut c2) = (None, None);
        for a in e.attributes().flatten() {
            let v = std::str::from_utf8(&a.value).unwrap_or("?");
            match a.key.as_ref() {
                b"v1" => v1 = parse_index(self.part, self.off, "v1", v)?,
                b"v2" => v2 = parse_index(self.part, self.off, "v2", v)?,
                b"r1" => r1 = Some(parse_num(self.part, self.off, "r1", v)?),
                b"r2" => r2 = Some(parse_num(self.part, self.off, "r2", v)?),
                b"cap1" => {
                    c1 = Some(
                        Cap::from_name(v)
                            .ok_or_else(|| self.err(format!("unknown cap \"{v}\"")))?,
                    )
                }
                b"cap2" => {
                    c2 = Some(
                        Cap::from_name(v)
                            .ok_or_else(|| self.err(format!("unknown cap \"{v}\"")))?,
                    )
                }
                _ => {}
            }
        }
        let n = self.mesh.as_ref().expect("inside a mesh").vertices.len() as u32;
        let k = l.beams.len();
        if v1 >= n || v2 >= n || v1 == v2 {
            return Err(self.err(format!(
                "beam {k} ({v1}, {v2}) needs two distinct vertex indices below {n}"
            )));
        }
        if r2.is_some() && r1.is_none() {
            return Err(self.err(format!("beam {k} has r2 without r1")));
        }
        let r1v = r1.unwrap_or(l.radius);
        let r2v = r2.unwrap_or(r1v);
        if !(r1v > 0.0 && r2v > 0.0) {
            return Err(self.err(format!("beam {k}: radii must be positive")));
        }
        self.charge::<Beam>("beam")?;
        self.lattice.as_mut().unwrap().beams.push(Beam {
            v1,
            v2,
            r1: r1v,
            r2: r2v,
            cap1: c1,
            cap2: c2,
        });
        Ok(Skip)
    }

    /// Beam lattice and balls elements other than beams (`None`: not one of them).
    pub(super) fn beam_start(
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
            (Mesh, Ns::Beam, "beamlattice") => {
                let pos = |n: &str, v: &str| -> Result<f64> {
                    let x = parse_num(part, off, n, v)?;
                    if x > 0.0 {
                        Ok(x)
                    } else {
                        Err(invalid(part, off, format!("{n} must be positive")))
                    }
                };
                let mut l = BeamLattice::new(
                    pos("radius", need("radius")?)?,
                    pos("minlength", need("minlength")?)?,
                );
                if let Some(c) = get("cap") {
                    l.cap = Cap::from_name(c.trim())
                        .ok_or_else(|| self.err(format!("unknown cap \"{c}\"")))?;
                }
                // Balls attributes: the 1.2 namespace, or unprefixed (1.1 drafts).
                let bm = get_ns(Ns::Balls, "ballmode").or(get("ballmode"));
                if let Some(m) = bm {
                    l.ball_mode = BallMode::from_name(m.trim())
                        .ok_or_else(|| self.err(format!("unknown ballmode \"{m}\"")))?;
                }
                if let Some(r) = get_ns(Ns::Balls, "ballradius").or(get("ballradius")) {
                    l.ball_radius = Some(pos("ballradius", r)?);
                }
                if l.ball_mode != BallMode::None && l.ball_radius.is_none() {
                    return Err(self.err("ballmode other than none needs a ballradius"));
                }
                let cm = get("clippingmode").unwrap_or("none");
                let mode = ClipMode::from_name(cm.trim())
                    .ok_or_else(|| self.err(format!("unknown clippingmode \"{cm}\"")))?;
                match (mode, get("clippingmesh")) {
                    (ClipMode::None, _) => {}
                    (m, Some(id)) => {
                        l.clipping = Some((m, parse_id(part, off, "clippingmesh", id)?))
                    }
                    (_, None) => return Err(self.err("clippingmode needs a clippingmesh")),
                }
                l.representation = get("representationmesh")
                    .map(|v| parse_id(part, off, "representationmesh", v))
                    .transpose()?;
                self.lattice = Some(l);
                Lattice
            }
            (Lattice, Ns::Beam, "beams") => Beams,
            (Lattice, Ns::Balls | Ns::Beam, "balls") => Balls,
            (Balls, Ns::Balls | Ns::Beam, "ball") => {
                let vindex = parse_index(part, off, "vindex", need("vindex")?)?;
                let n = self.mesh.as_ref().unwrap().vertices.len() as u32;
                if vindex >= n {
                    return Err(self.err(format!(
                        "ball vindex {vindex} is not below the {n} vertices"
                    )));
                }
                let r = get("r").map(|v| parse_num(part, off, "r", v)).transpose()?;
                self.charge::<Ball>("ball")?;
                self.lattice
                    .as_mut()
                    .unwrap()
                    .balls
                    .push(Ball { vindex, r });
                Skip
            }
            (Lattice, Ns::Beam, "beamsets") => BeamSets,
            (BeamSets, Ns::Beam, "beamset") => {
                self.beamset = Some(crate::beam::BeamSet {
                    name: get("name").map(str::to_string),
                    identifier: get("identifier").map(str::to_string),
                    beams: Vec::new(),
                    balls: Vec::new(),
                });
                BeamSet
            }
            (BeamSet, Ns::Beam, "ref") => {
                let i = parse_index(part, off, "index", need("index")?)?;
                self.charge::<u32>("beam reference")?;
                self.beamset.as_mut().unwrap().beams.push(i);
                Skip
            }
            (BeamSet, Ns::Balls | Ns::Beam, "ballref") => {
                let i = parse_index(part, off, "index", need("index")?)?;
                self.charge::<u32>("ball reference")?;
                self.beamset.as_mut().unwrap().balls.push(i);
                Skip
            }
            _ => return Ok(None),
        };
        Ok(Some(ctx))
    }

    /// Closes a beam lattice element.
    pub(super) fn beam_end(&mut self, ctx: Ctx) -> Result<()> {
        if ctx == Ctx::BeamSet {
            let s = self.beamset.take().unwrap();
            self.lattice.as_mut().unwrap().beam_sets.push(s);
        }
        Ok(())
    }
}
