//! The volumetric extension (draft): image stacks, functions from images,
//! volume data (material mapping, colour, properties) and level sets.

use super::parser::{Attr, Attrs, Ctx, Ns, Parser};
use super::values::{parse_bool, parse_id, parse_num, parse_transform};
use crate::error::{invalid, Error, Result};
use crate::model::*;
use crate::volumetric::*;

impl Parser<'_> {
    /// Volumetric elements (`None`: not one of them).
    pub(super) fn volumetric_start(
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
            (Object, Ns::Volumetric, "levelset") => {
                let ls = ObjectContent::LevelSet(LevelSet {
                    function: parse_id(part, off, "functionid", need("functionid")?)?,
                    channel: need("channel")?.to_string(),
                    transform: get("transform")
                        .map(|t| parse_transform(part, off, t))
                        .transpose()?
                        .unwrap_or_default(),
                    min_feature_size: get("minfeaturesize")
                        .map(|v| parse_num(part, off, "minfeaturesize", v))
                        .transpose()?
                        .unwrap_or(0.0),
                    fallback: get("fallbackvalue")
                        .map(|v| parse_num(part, off, "fallbackvalue", v))
                        .transpose()?
                        .unwrap_or(0.0),
                    mesh: parse_id(part, off, "meshid", need("meshid")?)?,
                    mesh_bbox_only: get("meshbboxonly")
                        .map(|v| parse_bool(part, off, "meshbboxonly", v))
                        .transpose()?
                        .unwrap_or(false),
                    volume_id: get("volumeid")
                        .map(|v| parse_id(part, off, "volumeid", v))
                        .transpose()?,
                });
                self.object.as_mut().unwrap().content = ls;
                Skip
            }
            (Resources, Ns::Volumetric, "image3d") => {
                let id = parse_id(part, off, "id", need("id")?)?;
                self.resource_id(id, "image3d")?;
                self.image = Some(crate::volumetric::Image3D {
                    id,
                    name: get("name").map(str::to_string),
                    dims: [0; 3],
                    layout: PixelLayout::Y,
                    bit_depth: 8,
                    samples: Vec::new(),
                    sheet_paths: Vec::new(),
                });
                Image3D
            }
            (Image3D, Ns::Volumetric, "imagestack") => {
                let n = |k: &str| -> Result<usize> {
                    need(k)?
                        .trim()
                        .parse::<usize>()
                        .ok()
                        .filter(|&v| v > 0)
                        .ok_or_else(|| {
                            invalid(part, off, format!("{k} must be a positive integer"))
                        })
                };
                let dims = [n("columncount")?, n("rowcount")?, n("sheetcount")?];
                check_dims(dims, PixelLayout::Y, 8).map_err(|m| Error::TooLarge {
                    part: part.into(),
                    message: m,
                })?;
                self.image.as_mut().unwrap().dims = dims;
                ImageStack
            }
            (ImageStack, Ns::Volumetric, "imagesheet") => {
                let p = need("path")?.to_string();
                self.image.as_mut().unwrap().sheet_paths.push(p);
                Skip
            }
            (Resources, Ns::Volumetric, "functionfromimage3d") => {
                let id = parse_id(part, off, "id", need("id")?)?;
                self.resource_id(id, "functionfromimage3d")?;
                let tile = |k: &str| -> Result<TileStyle> {
                    match get(k) {
                        None => Ok(TileStyle::Wrap),
                        Some(v) => TileStyle::from_name(v.trim())
                            .ok_or_else(|| invalid(part, off, format!("unknown {k} \"{v}\""))),
                    }
                };
                self.model.image_functions.push(FunctionFromImage3D {
                    id,
                    display_name: get("displayname").map(str::to_string),
                    image: parse_id(part, off, "image3did", need("image3did")?)?,
                    filter: match get("filter").map(str::trim) {
                        None | Some("linear") => Filter::Linear,
                        Some("nearest") => Filter::Nearest,
                        Some(v) => return Err(self.err(format!("unknown filter \"{v}\""))),
                    },
                    value_offset: get("valueoffset")
                        .map(|v| parse_num(part, off, "valueoffset", v))
                        .transpose()?
                        .unwrap_or(0.0),
                    value_scale: get("valuescale")
                        .map(|v| parse_num(part, off, "valuescale", v))
                        .transpose()?
                        .unwrap_or(1.0),
                    tile: [
                        tile("tilestyleu")?,
                        tile("tilestylev")?,
                        tile("tilestylew")?,
                    ],
                });
                Skip
            }
            (Resources, Ns::Volumetric, "volumedata") => {
                let id = parse_id(part, off, "id", need("id")?)?;
                self.resource_id(id, "volumedata")?;
                self.volume = Some(crate::volumetric::VolumeData {
                    id,
                    ..Default::default()
                });
                VolumeData
            }
            (VolumeData, Ns::Volumetric, "composite") => {
                self.composite = Some(crate::volumetric::Composite {
                    base_materials: parse_id(part, off, "basematerialid", need("basematerialid")?)?,
                    mappings: Vec::new(),
                });
                Composite
            }
            (Composite, Ns::Volumetric, "materialmapping") => {
                let r = self.fref(&a.list)?;
                self.composite.as_mut().unwrap().mappings.push(r);
                Skip
            }
            (VolumeData, Ns::Volumetric, "color") => {
                let r = self.fref(&a.list)?;
                self.volume.as_mut().unwrap().color = Some(r);
                Skip
            }
            (VolumeData, Ns::Volumetric, "property") => {
                let r = self.fref(&a.list)?;
                let p = Property {
                    name: need("name")?.to_string(),
                    required: get("required")
                        .map(|v| parse_bool(part, off, "required", v))
                        .transpose()?
                        .unwrap_or(false),
                    value: r,
                };
                self.volume.as_mut().unwrap().properties.push(p);
                Skip
            }
            _ => return Ok(None),
        };
        Ok(Some(ctx))
    }

    /// A function reference: the attributes of `<v:materialmapping>`,
    /// `<v:color>` and `<v:property>`.
    fn fref(&self, attrs: &[Attr]) -> Result<FunctionRef> {
        let (part, off) = (self.part, self.off);
        let get = |n: &str| {
            attrs
                .iter()
                .find(|a| a.ns == Ns::None && a.name == n)
                .map(|a| a.value.as_str())
        };
        let need =
            |n: &str| get(n).ok_or_else(|| invalid(part, off, format!("lacks the attribute {n}")));
        Ok(FunctionRef {
            function: parse_id(part, off, "functionid", need("functionid")?)?,
            channel: need("channel")?.to_string(),
            transform: get("transform")
                .map(|t| parse_transform(part, off, t))
                .transpose()?
                .unwrap_or_default(),
            min_feature_size: get("minfeaturesize")
                .map(|v| parse_num(part, off, "minfeaturesize", v))
                .transpose()?
                .unwrap_or(0.0),
            fallback: get("fallbackvalue")
                .map(|v| parse_num(part, off, "fallbackvalue", v))
                .transpose()?
                .unwrap_or(0.0),
        })
    }

    /// Closes a volumetric element.
    pub(super) fn volumetric_end(&mut self, ctx: Ctx) -> Result<()> {
        use Ctx::*;
        match ctx {
            Image3D => {
                let im = self.image.take().unwrap();
                if im.sheet_paths.len() != im.dims[2] {
                    return Err(self.err(format!(
                        "image3d {}: sheetcount {} but {} imagesheets",
                        im.id,
                        im.dims[2],
                        im.sheet_paths.len()
                    )));
                }
                self.model.images.push(im);
            }
            Composite => {
                let c = self.composite.take().unwrap();
                self.volume.as_mut().unwrap().composite = Some(c);
            }
            VolumeData => {
                let v = self.volume.take().unwrap();
                self.model.volume_data.push(v);
            }
            _ => {}
        }
        Ok(())
    }
}
