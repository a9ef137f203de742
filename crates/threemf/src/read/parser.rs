//! The streaming parser of a model part: element contexts, attributes,
//! and the dispatch of each element to the file of its namespace.

use super::package::{xml_err, Budget};
use crate::beam::{BeamLattice, BeamSet};
use crate::error::{invalid, Error, Result};
use crate::implicit::{ImplicitFunction, ImplicitNode};
use crate::model::*;
use crate::slice::{Slice, SliceStack};
use crate::volumetric::*;
use quick_xml::events::{BytesStart, Event};
use quick_xml::name::{QName, ResolveResult};
use quick_xml::NsReader;
use std::io::BufRead;

/// One `<s:sliceref>`: referenced stack id, part path, byte offset.
pub(super) type SliceRef = (u32, String, u64);

/// Slice references found while parsing, per referencing stack id.
#[derive(Default)]
pub(super) struct Refs {
    pub(super) slice_refs: Vec<(u32, Vec<SliceRef>)>,
}

/// The namespaces this reader knows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Ns {
    None,
    Core,
    Material,
    Slice,
    Beam,
    Balls,
    Volumetric,
    Implicit,
    Production,
    Other,
}

pub(super) fn ns_of(r: &ResolveResult) -> Ns {
    match r {
        ResolveResult::Unbound => Ns::None,
        ResolveResult::Unknown(_) => Ns::Other,
        ResolveResult::Bound(n) => match n.as_ref() {
            x if x == ns::CORE.as_bytes() => Ns::Core,
            x if x == ns::MATERIAL.as_bytes() => Ns::Material,
            x if x == ns::SLICE.as_bytes() => Ns::Slice,
            x if x == ns::BEAM.as_bytes() => Ns::Beam,
            x if x == ns::BALLS.as_bytes() => Ns::Balls,
            x if x == ns::VOLUMETRIC.as_bytes() => Ns::Volumetric,
            x if x == ns::IMPLICIT.as_bytes() => Ns::Implicit,
            x if x == ns::PRODUCTION.as_bytes() => Ns::Production,
            _ => Ns::Other,
        },
    }
}

/// Element contexts of the streaming parser.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Ctx {
    Model,
    Metadata,
    Resources,
    Build,
    BaseMaterials,
    CompositeMaterials,
    ColorGroup,
    Object,
    Mesh,
    Vertices,
    Triangles,
    Components,
    Lattice,
    Beams,
    Balls,
    BeamSets,
    BeamSet,
    SliceStack,
    Slice,
    SliceVertices,
    Polygon,
    Image3D,
    ImageStack,
    VolumeData,
    Composite,
    Implicit,
    FnIn,
    FnOut,
    Node,
    NodeIn,
    NodeOut,
    /// An element skipped with all its content.
    Skip,
}

/// An attribute: namespace, local name, value.
pub(super) struct Attr {
    pub(super) ns: Ns,
    pub(super) name: String,
    pub(super) value: String,
}

/// The attributes of one element (not a hot one), for the namespace files.
pub(super) struct Attrs<'a> {
    pub(super) list: Vec<Attr>,
    part: &'a str,
    off: u64,
    /// The element's local name, for errors.
    name: &'a str,
}

impl Attrs<'_> {
    /// The unprefixed attribute `n`.
    pub(super) fn get(&self, n: &str) -> Option<&str> {
        self.list
            .iter()
            .find(|a| a.ns == Ns::None && a.name == n)
            .map(|a| a.value.as_str())
    }

    /// The attribute `n` of namespace `ns`.
    pub(super) fn get_ns(&self, ns: Ns, n: &str) -> Option<&str> {
        self.list
            .iter()
            .find(|a| a.ns == ns && a.name == n)
            .map(|a| a.value.as_str())
    }

    /// The unprefixed attribute `n`, which the element must have.
    pub(super) fn need(&self, n: &str) -> Result<&str> {
        self.get(n).ok_or_else(|| {
            invalid(
                self.part,
                self.off,
                format!("<{}> lacks the attribute {n}", self.name),
            )
        })
    }
}

/// The state of the parse of one model part.
pub(super) struct Parser<'p> {
    pub(super) part: &'p str,
    /// Memory the package may still take; every array element is counted
    /// twice its size (a growing vector holds up to twice its length).
    pub(super) budget: &'p Budget,
    /// Resource ids seen, which must be unique in a model part.
    pub(super) ids: std::collections::HashSet<u32>,
    pub(super) off: u64,
    pub(super) model: Model,
    pub(super) refs: Refs,
    pub(super) object: Option<Object>,
    pub(super) mesh: Option<Mesh>,
    pub(super) tri_pids: Option<u32>,
    pub(super) tri_props: Vec<[u32; 3]>,
    pub(super) tri_props_ok: bool,
    pub(super) components: Vec<Component>,
    pub(super) lattice: Option<BeamLattice>,
    pub(super) beamset: Option<BeamSet>,
    pub(super) stack: Option<SliceStack>,
    pub(super) stack_refs: Vec<SliceRef>,
    pub(super) slice: Option<Slice>,
    pub(super) slice_vertices: Vec<[f64; 2]>,
    pub(super) polygon: Option<(u32, Vec<u32>)>,
    pub(super) image: Option<Image3D>,
    pub(super) volume: Option<VolumeData>,
    pub(super) composite: Option<Composite>,
    pub(super) function: Option<ImplicitFunction>,
    pub(super) node: Option<ImplicitNode>,
    pub(super) metadata_name: Option<String>,
    pub(super) text: String,
}

pub(super) fn parse_model<R: BufRead>(r: R, part: &str, budget: &Budget) -> Result<(Model, Refs)> {
    let mut reader = NsReader::from_reader(r);
    reader.config_mut().expand_empty_elements = false;
    let mut p = Parser {
        part,
        budget,
        ids: std::collections::HashSet::new(),
        off: 0,
        model: Model::default(),
        refs: Refs::default(),
        object: None,
        mesh: None,
        tri_pids: None,
        tri_props: Vec::new(),
        tri_props_ok: true,
        components: Vec::new(),
        lattice: None,
        beamset: None,
        stack: None,
        stack_refs: Vec::new(),
        slice: None,
        slice_vertices: Vec::new(),
        polygon: None,
        image: None,
        volume: None,
        composite: None,
        function: None,
        node: None,
        metadata_name: None,
        text: String::new(),
    };
    let mut stack: Vec<Ctx> = Vec::new();
    let mut buf = Vec::new();
    let mut seen_model = false;
    loop {
        p.off = reader.buffer_position();
        let (res, ev) = reader
            .read_resolved_event_into(&mut buf)
            .map_err(xml_err(part, p.off))?;
        let ens = ns_of(&res);
        match ev {
            Event::Start(ref e) | Event::Empty(ref e) => {
                let name = std::str::from_utf8(e.local_name().as_ref())
                    .unwrap_or("")
                    .to_string();
                let ctx = match stack.last().copied() {
                    Some(Ctx::Skip) => Ctx::Skip,
                    None => {
                        if ens != Ns::Core || name != "model" || seen_model {
                            return Err(invalid(
                                part,
                                p.off,
                                format!("root element is <{name}>, not one core <model>"),
                            ));
                        }
                        seen_model = true;
                        p.model_start(&reader, e)?;
                        Ctx::Model
                    }
                    Some(parent) => p.start(&reader, parent, ens, &name, e)?,
                };
                if matches!(ev, Event::Empty(_)) {
                    p.end(ctx)?;
                } else {
                    stack.push(ctx);
                }
            }
            Event::End(_) => {
                let ctx = stack
                    .pop()
                    .ok_or_else(|| invalid(part, p.off, "unbalanced end tag"))?;
                p.end(ctx)?;
            }
            Event::Text(t) if stack.last() == Some(&Ctx::Metadata) => {
                let s = t.unescape().map_err(xml_err(part, p.off))?;
                p.text.push_str(&s);
            }
            Event::DocType(_) => {
                return Err(invalid(
                    part,
                    p.off,
                    "DTDs are not allowed (core spec 2.3.2)",
                ))
            }
            Event::Eof => break,
            _ => {}
        }
        buf.clear();
    }
    if !seen_model {
        return Err(invalid(part, 0, "no <model> element"));
    }
    if !stack.is_empty() {
        return Err(invalid(part, p.off, "document ends inside an element"));
    }
    Ok((p.model, p.refs))
}

impl Parser<'_> {
    pub(super) fn err(&self, msg: impl Into<String>) -> Error {
        invalid(self.part, self.off, msg)
    }

    /// Counts one more array element of type `T` against the budget.
    pub(super) fn charge<T>(&self, what: &str) -> Result<()> {
        let off = self.off;
        self.budget
            .take(self.part, 2 * std::mem::size_of::<T>() as u64, || {
                format!("the {what}s up to byte {off}")
            })
    }

    /// Records a resource id, refusing one used before in this part.
    pub(super) fn resource_id(&mut self, id: u32, kind: &str) -> Result<()> {
        if !self.ids.insert(id) {
            return Err(self.err(format!(
                "{kind} id {id} is already the id of another resource (ids must be unique)"
            )));
        }
        Ok(())
    }

    fn attrs<R>(&self, reader: &NsReader<R>, e: &BytesStart) -> Result<Vec<Attr>> {
        let mut v = Vec::new();
        for a in e.attributes() {
            let a = a.map_err(|err| Error::Xml {
                part: self.part.into(),
                offset: self.off,
                source: err.into(),
            })?;
            let (res, local) = reader.resolve_attribute(a.key);
            let ns = if a.key.as_ref().starts_with(b"xmlns") {
                continue;
            } else {
                ns_of(&res)
            };
            let value = a.unescape_value().map_err(|source| Error::Attribute {
                part: self.part.into(),
                offset: self.off,
                source,
            })?;
            v.push(Attr {
                ns,
                name: String::from_utf8_lossy(local.as_ref()).into_owned(),
                value: value.into_owned(),
            });
        }
        Ok(v)
    }

    fn model_start<R>(&mut self, reader: &NsReader<R>, e: &BytesStart) -> Result<()> {
        for a in self.attrs(reader, e)? {
            match (a.ns, a.name.as_str()) {
                (Ns::None, "unit") => {
                    self.model.unit = Unit::from_name(a.value.trim())
                        .ok_or_else(|| self.err(format!("unknown unit \"{}\"", a.value)))?
                }
                (_, "lang") => self.model.language = Some(a.value),
                (Ns::None, "requiredextensions") => {
                    for prefix in a.value.split_ascii_whitespace() {
                        let q = format!("{prefix}:x");
                        let (res, _) = reader.resolve_element(QName(q.as_bytes()));
                        let namespace = match &res {
                            ResolveResult::Bound(n) => {
                                String::from_utf8_lossy(n.as_ref()).into_owned()
                            }
                            _ => "undeclared".to_string(),
                        };
                        if !ns::SUPPORTED.contains(&namespace.as_str()) {
                            return Err(Error::UnsupportedExtension {
                                part: self.part.into(),
                                prefix: prefix.into(),
                                namespace,
                            });
                        }
                    }
                }
                _ => {}
            }
        }
        Ok(())
    }

    /// Opens an element: hot ones (vertices, triangles, beams, colours,
    /// slice vertices and segments) parse their attributes as bytes,
    /// without allocating; the others go to the file of their namespace.
    fn start<R>(
        &mut self,
        reader: &NsReader<R>,
        parent: Ctx,
        ens: Ns,
        name: &str,
        e: &BytesStart,
    ) -> Result<Ctx> {
        let hot = match ens {
            Ns::Core => self.core_hot(parent, ens, name, e)?,
            Ns::Beam => self.beam_hot(parent, ens, name, e)?,
            Ns::Material => self.material_hot(parent, ens, name, e)?,
            Ns::Slice => self.slice_hot(parent, ens, name, e)?,
            _ => None,
        };
        if let Some(ctx) = hot {
            return Ok(ctx);
        }
        let attrs = Attrs {
            list: self.attrs(reader, e)?,
            part: self.part,
            off: self.off,
            name,
        };
        if attrs
            .list
            .iter()
            .any(|a| a.ns == Ns::Production && a.name == "path")
        {
            return Err(self.err(
                "p:path (objects in other model parts, production extension) is not supported",
            ));
        }
        let ctx = match ens {
            // Base materials are core elements.
            Ns::Core => match self.core_start(parent, ens, name, &attrs)? {
                None => self.material_start(parent, ens, name, &attrs)?,
                ctx => ctx,
            },
            Ns::Material => self.material_start(parent, ens, name, &attrs)?,
            Ns::Beam | Ns::Balls => self.beam_start(parent, ens, name, &attrs)?,
            Ns::Slice => self.slice_start(parent, ens, name, &attrs)?,
            Ns::Volumetric => self.volumetric_start(parent, ens, name, &attrs)?,
            Ns::Implicit => self.implicit_start(parent, ens, name, &attrs)?,
            Ns::None | Ns::Production | Ns::Other => None,
        };
        match ctx {
            Some(ctx) => Ok(ctx),
            None if ens == Ns::Core && parent != Ctx::Skip => {
                Err(self.err(format!("unexpected core element <{name}> here")))
            }
            // Other namespaces: extension points, ignored (required ones were
            // rejected at <model>).
            None => Ok(Ctx::Skip),
        }
    }

    /// Closes an element: the file of its namespace moves what it built
    /// into the model.
    fn end(&mut self, ctx: Ctx) -> Result<()> {
        use Ctx::*;
        match ctx {
            Metadata | Mesh | Components | Object => self.core_end(ctx),
            ColorGroup => self.material_end(ctx),
            BeamSet => self.beam_end(ctx),
            Polygon | Slice | SliceStack => self.slice_end(ctx),
            Image3D | Composite | VolumeData => self.volumetric_end(ctx),
            Node | Implicit => self.implicit_end(ctx),
            _ => Ok(()),
        }
    }
}
