//! Materials and colour: base materials (a core element), composite
//! materials and colour groups (the materials extension).

use super::parser::{Attrs, Ctx, Ns, Parser};
use super::values::{parse_colour, parse_id, parse_index, parse_num};
use crate::error::{invalid, Result};
use crate::model::*;
use quick_xml::events::BytesStart;

impl Parser<'_> {
    /// Colours of a colour group, parsed from the attribute bytes.
    pub(super) fn material_hot(
        &mut self,
        parent: Ctx,
        ens: Ns,
        name: &str,
        e: &BytesStart,
    ) -> Result<Option<Ctx>> {
        use Ctx::*;
        match (parent, ens, name) {
            (ColorGroup, Ns::Material, "color") => self.color(e).map(Some),
            _ => Ok(None),
        }
    }

    /// An `<m:color>` of a colour group.
    fn color(&mut self, e: &BytesStart) -> Result<Ctx> {
        use Ctx::*;
        let mut c = None;
        for a in e.attributes().flatten() {
            if a.key.as_ref() == b"color" {
                let v = std::str::from_utf8(&a.value).unwrap_or("?");
                c = Some(parse_colour(self.part, self.off, v)?);
            }
        }
        let g = self.model.color_groups.last_mut().expect("inside a group");
        let c = c.ok_or_else(|| {
            invalid(
                self.part,
                self.off,
                format!(
                    "colour {} of colorgroup {} lacks color",
                    g.colors.len(),
                    g.id
                ),
            )
        })?;
        g.colors.push(c);
        self.charge::<[u8; 4]>("colour")?;
        Ok(Skip)
    }

    /// Material elements, core and extension (`None`: not one of them).
    pub(super) fn material_start(
        &mut self,
        parent: Ctx,
        ens: Ns,
        name: &str,
        a: &Attrs,
    ) -> Result<Option<Ctx>> {
        use Ctx::*;
        let (part, off) = (self.part, self.off);
        let need = |n: &str| a.need(n);
        let ctx = match (parent, ens, name) {
            (Resources, Ns::Core, "basematerials") => {
                let id = parse_id(part, off, "id", need("id")?)?;
                self.resource_id(id, "basematerials")?;
                self.model.base_materials.push(crate::model::BaseMaterials {
                    id,
                    bases: Vec::new(),
                });
                BaseMaterials
            }
            (BaseMaterials, Ns::Core, "base") => {
                let c = need("displaycolor")?;
                let hex = c.trim().trim_start_matches('#');
                let byte = |i: usize| u8::from_str_radix(hex.get(i..i + 2).unwrap_or("zz"), 16);
                let color = match (hex.len(), byte(0), byte(2), byte(4)) {
                    (6 | 8, Ok(r), Ok(g), Ok(b)) => [
                        r,
                        g,
                        b,
                        if hex.len() == 8 {
                            byte(6).map_err(|_| self.err("bad displaycolor"))?
                        } else {
                            255
                        },
                    ],
                    _ => {
                        return Err(
                            self.err(format!("displaycolor \"{c}\" is not #RRGGBB or #RRGGBBAA"))
                        )
                    }
                };
                let name = need("name")?.to_string();
                self.model
                    .base_materials
                    .last_mut()
                    .unwrap()
                    .bases
                    .push(Base { name, color });
                Skip
            }
            (Resources, Ns::Material, "compositematerials") => {
                let id = parse_id(part, off, "id", need("id")?)?;
                self.resource_id(id, "compositematerials")?;
                let matid = parse_id(part, off, "matid", need("matid")?)?;
                let idx = need("matindices")?
                    .split_ascii_whitespace()
                    .map(|v| parse_index(part, off, "matindices", v))
                    .collect::<Result<Vec<_>>>()?;
                self.model
                    .composite_materials
                    .push(crate::model::CompositeMaterials {
                        id,
                        base_materials: matid,
                        material_indices: idx,
                        composites: Vec::new(),
                    });
                CompositeMaterials
            }
            (CompositeMaterials, Ns::Material, "composite") => {
                let v = need("values")?
                    .split_ascii_whitespace()
                    .map(|v| parse_num(part, off, "composite value", v))
                    .collect::<Result<Vec<_>>>()?;
                self.model
                    .composite_materials
                    .last_mut()
                    .unwrap()
                    .composites
                    .push(v);
                Skip
            }
            (Resources, Ns::Material, "colorgroup") => {
                let id = parse_id(part, off, "id", need("id")?)?;
                self.resource_id(id, "colorgroup")?;
                self.model.color_groups.push(crate::model::ColorGroup {
                    id,
                    colors: Vec::new(),
                });
                ColorGroup
            }
            _ => return Ok(None),
        };
        Ok(Some(ctx))
    }

    /// Closes a material element.
    pub(super) fn material_end(&mut self, ctx: Ctx) -> Result<()> {
        if ctx == Ctx::ColorGroup {
            let g = self.model.color_groups.last().expect("just read");
            if g.colors.is_empty() {
                return Err(self.err(format!("colorgroup {} has no colour", g.id)));
            }
        }
        Ok(())
    }
}
