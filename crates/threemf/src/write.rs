//! The package writer: validates a [`Model`] and writes the OPC package
//! (content types, relationships, the root model part, slice parts, PNG
//! sheets). Output is deterministic: fixed part order and zip timestamps.

use crate::beam::{BallMode, BeamLattice, ClipMode};
use crate::error::{Error, Result};
use crate::implicit::{ImplicitFunction, NodeValue};
use crate::model::{ns, MeshResolution, Model, Object, ObjectContent, ObjectType, Transform};
use crate::slice::{Slice, SliceStack};
use crate::volumetric::{check_dims, Filter, FunctionRef, VolumeData};
use std::collections::{HashMap, HashSet};
use std::fmt::{self, Display, Write as _};
use std::io::{BufWriter, Seek, Write};
use std::path::Path;
use zip::write::SimpleFileOptions;

/// The root model part written by this crate.
pub const ROOT_MODEL: &str = "3D/3dmodel.model";

const CT_MODEL: &str = "application/vnd.ms-package.3dmanufacturing-3dmodel+xml";
const CT_RELS: &str = "application/vnd.openxmlformats-package.relationships+xml";
/// Relationship type of the StartPart and of other model parts.
pub(crate) const REL_MODEL: &str = "http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel";
/// Relationship type of textures (PNG sheets).
pub(crate) const REL_TEXTURE: &str =
    "http://schemas.microsoft.com/3dmanufacturing/2013/01/3dtexture";

/// How the writer splits and compresses.
#[derive(Clone, Debug)]
pub struct WriteOptions {
    /// A slice stack with more slices than this goes to separate parts
    /// referenced by `<s:sliceref>`, at most this many slices each.
    pub max_slices_per_part: usize,
    /// ... or when its XML would exceed this many bytes (per part).
    pub max_slice_bytes_per_part: usize,
    /// Deflate the parts (the default); `false` stores them.
    pub deflate: bool,
}

impl Default for WriteOptions {
    fn default() -> Self {
        WriteOptions {
            max_slices_per_part: 1000,
            max_slice_bytes_per_part: 32 << 20,
            deflate: true,
        }
    }
}

/// Writes `model` to the file `path` atomically: a temporary next to it,
/// renamed when complete (see `microfrep_io::atomic`); on an error nothing
/// is left behind.
pub fn write_file(path: impl AsRef<Path>, model: &Model, opts: &WriteOptions) -> Result<()> {
    let path = path.as_ref();
    let io = |e: microfrep_io::IoError| match e {
        microfrep_io::IoError::Io { source, .. } => Error::Io {
            path: path.display().to_string(),
            source,
        },
        other => Error::Io {
            path: path.display().to_string(),
            source: std::io::Error::other(other),
        },
    };
    let mut f = microfrep_io::AtomicFile::create(path).map_err(io)?;
    write_to(&mut f, model, opts)?;
    f.commit().map_err(io)
}

/// Writes `model` as a package into `w` and gives `w` back.
pub fn write_to<W: Write + Seek>(w: W, model: &Model, opts: &WriteOptions) -> Result<W> {
    validate(model)?;
    let mut pkg = Package::new(w, opts.deflate);
    let ext = Extensions::of(model);
    // Plan the slice parts and image sheets first: the root part names them.
    let mut next_id = model.next_id();
    let mut slice_parts: Vec<(String, String)> = Vec::new(); // (name, xml)
    let mut slice_refs: HashMap<u32, Vec<(u32, String)>> = HashMap::new();
    for st in &model.slice_stacks {
        let chunks = chunk_slices(st, opts);
        if chunks.len() <= 1 && st.slices.len() <= opts.max_slices_per_part {
            continue;
        }
        let mut zb = st.zbottom;
        for (k, range) in chunks.into_iter().enumerate() {
            let id = next_id;
            next_id += 1;
            let name = format!("2D/slicestack{}_{:04}.model", st.id, k);
            let part = SliceStack {
                id,
                zbottom: zb,
                slices: st.slices[range].to_vec(),
            };
            zb = part.slices.last().map(|s| s.ztop).unwrap_or(zb);
            let mut xml = String::new();
            xml_head(&mut xml, model, &[("s", ns::SLICE)], "");
            xml.push_str("<resources>");
            slicestack_xml(&mut xml, &part);
            xml.push_str("</resources><build/></model>\n");
            slice_refs
                .entry(st.id)
                .or_default()
                .push((id, format!("/{name}")));
            slice_parts.push((name, xml));
        }
    }
    let mut sheets: Vec<(String, u32, usize)> = Vec::new(); // (part, image id, sheet)
    let mut sheet_names: HashMap<u32, Vec<String>> = HashMap::new();
    for im in &model.images {
        for k in 0..im.dims[2] {
            let name = format!("3D/volumetric/image{}/sheet{:04}.png", im.id, k);
            sheet_names
                .entry(im.id)
                .or_default()
                .push(format!("/{name}"));
            sheets.push((name, im.id, k));
        }
    }

    // [Content_Types].xml and the package relationships.
    let mut ct = String::from(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<Types xmlns=\"http://schemas.openxmlformats.org/package/2006/content-types\">",
    );
    write!(
        ct,
        "<Default Extension=\"rels\" ContentType=\"{CT_RELS}\"/>"
    )
    .unwrap();
    write!(
        ct,
        "<Default Extension=\"model\" ContentType=\"{CT_MODEL}\"/>"
    )
    .unwrap();
    if !sheets.is_empty() {
        ct.push_str("<Default Extension=\"png\" ContentType=\"image/png\"/>");
    }
    ct.push_str("</Types>\n");
    pkg.add("[Content_Types].xml", ct.as_bytes())?;
    let rels = format!(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<Relationships xmlns=\"http://schemas.openxmlformats.org/package/2006/relationships\"><Relationship Target=\"/{ROOT_MODEL}\" Id=\"rel0\" Type=\"{REL_MODEL}\"/></Relationships>\n"
    );
    pkg.add("_rels/.rels", rels.as_bytes())?;

    // The root model part, streamed (meshes can be large).
    pkg.start(ROOT_MODEL)?;
    {
        let mut out = BufWriter::with_capacity(1 << 20, &mut pkg);
        write_root(&mut out, model, &ext, &slice_refs, &sheet_names)
            .map_err(|e| io_err(ROOT_MODEL, e))?;
        out.flush().map_err(|e| io_err(ROOT_MODEL, e))?;
    }
    if !slice_parts.is_empty() || !sheets.is_empty() {
        let mut r = String::from(
            "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<Relationships xmlns=\"http://schemas.openxmlformats.org/package/2006/relationships\">",
        );
        let mut n = 0;
        for (name, _) in &slice_parts {
            write!(
                r,
                "<Relationship Target=\"/{name}\" Id=\"rel{n}\" Type=\"{REL_MODEL}\"/>"
            )
            .unwrap();
            n += 1;
        }
        for (name, _, _) in &sheets {
            write!(
                r,
                "<Relationship Target=\"/{name}\" Id=\"rel{n}\" Type=\"{REL_TEXTURE}\"/>"
            )
            .unwrap();
            n += 1;
        }
        r.push_str("</Relationships>\n");
        pkg.add("3D/_rels/3dmodel.model.rels", r.as_bytes())?;
    }
    for (name, xml) in &slice_parts {
        pkg.add(name, xml.as_bytes())?;
    }
    for (name, id, k) in &sheets {
        let im = model
            .images
            .iter()
            .find(|i| i.id == *id)
            .expect("planned above");
        let png = im.encode_sheet(*k, name)?;
        pkg.add(name, &png)?;
    }
    pkg.finish()
}

fn io_err(part: &str, source: std::io::Error) -> Error {
    Error::Io {
        path: part.to_string(),
        source,
    }
}

/// A zip archive being written, with fixed timestamps. The writer is not
/// dropped when writing fails (a dropped `ZipWriter` tries to finish the
/// archive on the failed stream and prints to stderr); only
/// [`Package::finish`] closes it. The failed package's buffers are left to
/// the process (the caller removes the output).
struct Package<W: Write + Seek> {
    zip: std::mem::ManuallyDrop<zip::ZipWriter<W>>,
    opts: SimpleFileOptions,
    part: String,
}

impl<W: Write + Seek> Package<W> {
    fn new(w: W, deflate: bool) -> Self {
        let method = if deflate {
            zip::CompressionMethod::Deflated
        } else {
            zip::CompressionMethod::Stored
        };
        let opts = SimpleFileOptions::default()
            .compression_method(method)
            .last_modified_time(zip::DateTime::default())
            .large_file(false);
        Package {
            zip: std::mem::ManuallyDrop::new(zip::ZipWriter::new(w)),
            opts,
            part: String::new(),
        }
    }

    fn start(&mut self, name: &str) -> Result<()> {
        self.part = name.to_string();
        // Parts over 4 GiB need zip64; the writer decides per part by size
        // only when told, so ask for it where a part might grow large.
        let opts = if name.ends_with(".model") {
            self.opts.large_file(true)
        } else {
            self.opts
        };
        self.zip
            .start_file(name, opts)
            .map_err(|source| Error::Zip {
                part: name.to_string(),
                source,
            })
    }

    fn add(&mut self, name: &str, data: &[u8]) -> Result<()> {
        self.zip
            .start_file(name, self.opts)
            .map_err(|source| Error::Zip {
                part: name.to_string(),
                source,
            })?;
        self.zip.write_all(data).map_err(|e| io_err(name, e))
    }

    fn finish(self) -> Result<W> {
        std::mem::ManuallyDrop::into_inner(self.zip)
            .finish()
            .map_err(|source| Error::Zip {
                part: "the archive".into(),
                source,
            })
    }
}

impl<W: Write + Seek> Write for Package<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.zip.write(buf)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.zip.flush()
    }
}

/// A number as 3MF writes it: the shortest decimal that reads back as the
/// same f32 when the value is an f32, else the same f64 (never an exponent).
pub(crate) struct Num(pub f64);

impl Display for Num {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        let v = self.0;
        if v == 0.0 {
            return f.write_str("0");
        }
        let s = v as f32;
        if s as f64 == v {
            write!(f, "{s}")
        } else {
            write!(f, "{v}")
        }
    }
}

/// An xs:double that may be infinite or NaN.
struct Double(f64);

impl Display for Double {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        match self.0 {
            v if v.is_nan() => f.write_str("NaN"),
            f64::INFINITY => f.write_str("INF"),
            f64::NEG_INFINITY => f.write_str("-INF"),
            v => write!(f, "{}", Num(v)),
        }
    }
}

struct Mat<'a>(&'a Transform);

impl Display for Mat<'_> {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        for (i, v) in self.0 .0.iter().enumerate() {
            if i > 0 {
                f.write_str(" ")?;
            }
            write!(f, "{}", Num(*v))?;
        }
        Ok(())
    }
}

fn esc(s: &str) -> std::borrow::Cow<'_, str> {
    quick_xml::escape::escape(s)
}

/// Which extensions the model uses, and which it requires.
struct Extensions {
    declare: Vec<(&'static str, &'static str)>,
    required: Vec<&'static str>,
}

impl Extensions {
    fn of(m: &Model) -> Extensions {
        let lattices: Vec<&BeamLattice> = m
            .objects
            .iter()
            .filter_map(|o| match &o.content {
                ObjectContent::Mesh(me) => me.beam_lattice.as_ref(),
                _ => None,
            })
            .collect();
        let balls = lattices
            .iter()
            .any(|l| !l.balls.is_empty() || l.ball_mode != BallMode::None);
        let lowres = m
            .objects
            .iter()
            .any(|o| o.mesh_resolution == MeshResolution::Low);
        let levelset = m
            .objects
            .iter()
            .any(|o| matches!(o.content, ObjectContent::LevelSet(_)));
        let implicit_in_levelset = m.objects.iter().any(|o| match &o.content {
            ObjectContent::LevelSet(l) => m.implicit_functions.iter().any(|f| f.id == l.function),
            _ => false,
        });
        let volumetric = !m.images.is_empty()
            || !m.image_functions.is_empty()
            || !m.volume_data.is_empty()
            || levelset;
        let mut e = Extensions {
            declare: Vec::new(),
            required: Vec::new(),
        };
        let mut add = |p: &'static str, u: &'static str, used: bool, req: bool| {
            if used {
                e.declare.push((p, u));
                if req {
                    e.required.push(p);
                }
            }
        };
        let materials = !m.composite_materials.is_empty() || !m.color_groups.is_empty();
        add("m", ns::MATERIAL, materials, false);
        add("b", ns::BEAM, !lattices.is_empty(), true);
        add("b2", ns::BALLS, balls, true);
        add("s", ns::SLICE, !m.slice_stacks.is_empty() || lowres, lowres);
        add("v", ns::VOLUMETRIC, volumetric, levelset);
        add(
            "i",
            ns::IMPLICIT,
            !m.implicit_functions.is_empty(),
            implicit_in_levelset,
        );
        e
    }
}

fn xml_head(out: &mut String, m: &Model, declare: &[(&str, &str)], required: &str) {
    out.push_str("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    write!(out, "<model unit=\"{}\"", m.unit.name()).unwrap();
    if let Some(l) = &m.language {
        write!(out, " xml:lang=\"{}\"", esc(l)).unwrap();
    }
    write!(out, " xmlns=\"{}\"", ns::CORE).unwrap();
    for (p, u) in declare {
        write!(out, " xmlns:{p}=\"{u}\"").unwrap();
    }
    if !required.is_empty() {
        write!(out, " requiredextensions=\"{required}\"").unwrap();
    }
    out.push_str(">\n");
}

fn write_root<W: Write>(
    w: &mut W,
    m: &Model,
    ext: &Extensions,
    slice_refs: &HashMap<u32, Vec<(u32, String)>>,
    sheets: &HashMap<u32, Vec<String>>,
) -> std::io::Result<()> {
    let mut head = String::new();
    xml_head(&mut head, m, &ext.declare, &ext.required.join(" "));
    w.write_all(head.as_bytes())?;
    for md in &m.metadata {
        writeln!(
            w,
            "<metadata name=\"{}\">{}</metadata>",
            esc(&md.name),
            esc(&md.value)
        )?;
    }
    w.write_all(b"<resources>\n")?;
    let mut s = String::new();
    for bm in &m.base_materials {
        write!(s, "<basematerials id=\"{}\">", bm.id).unwrap();
        for b in &bm.bases {
            let c = b.color;
            write!(
                s,
                "<base name=\"{}\" displaycolor=\"#{:02X}{:02X}{:02X}{:02X}\"/>",
                esc(&b.name),
                c[0],
                c[1],
                c[2],
                c[3]
            )
            .unwrap();
        }
        s.push_str("</basematerials>\n");
    }
    for cm in &m.composite_materials {
        let idx: Vec<String> = cm.material_indices.iter().map(|i| i.to_string()).collect();
        write!(
            s,
            "<m:compositematerials id=\"{}\" matid=\"{}\" matindices=\"{}\">",
            cm.id,
            cm.base_materials,
            idx.join(" ")
        )
        .unwrap();
        for c in &cm.composites {
            let v: Vec<String> = c.iter().map(|x| Num(*x).to_string()).collect();
            write!(s, "<m:composite values=\"{}\"/>", v.join(" ")).unwrap();
        }
        s.push_str("</m:compositematerials>\n");
    }
    for cg in &m.color_groups {
        writeln!(s, "<m:colorgroup id=\"{}\">", cg.id).unwrap();
        for c in &cg.colors {
            writeln!(
                s,
                "<m:color color=\"#{:02X}{:02X}{:02X}{:02X}\"/>",
                c[0], c[1], c[2], c[3]
            )
            .unwrap();
            if s.len() > 1 << 20 {
                w.write_all(s.as_bytes())?;
                s.clear();
            }
        }
        s.push_str("</m:colorgroup>\n");
    }
    for im in &m.images {
        write!(s, "<v:image3d id=\"{}\"", im.id).unwrap();
        if let Some(n) = &im.name {
            write!(s, " name=\"{}\"", esc(n)).unwrap();
        }
        write!(
            s,
            "><v:imagestack rowcount=\"{}\" columncount=\"{}\" sheetcount=\"{}\">",
            im.dims[1], im.dims[0], im.dims[2]
        )
        .unwrap();
        for p in &sheets[&im.id] {
            write!(s, "<v:imagesheet path=\"{p}\"/>").unwrap();
        }
        s.push_str("</v:imagestack></v:image3d>\n");
    }
    for f in &m.image_functions {
        write!(s, "<v:functionfromimage3d id=\"{}\"", f.id).unwrap();
        if let Some(n) = &f.display_name {
            write!(s, " displayname=\"{}\"", esc(n)).unwrap();
        }
        write!(
            s,
            " image3did=\"{}\" filter=\"{}\" valueoffset=\"{}\" valuescale=\"{}\" tilestyleu=\"{}\" tilestylev=\"{}\" tilestylew=\"{}\"/>",
            f.image,
            match f.filter {
                Filter::Linear => "linear",
                Filter::Nearest => "nearest",
            },
            Num(f.value_offset),
            Num(f.value_scale),
            f.tile[0].name(),
            f.tile[1].name(),
            f.tile[2].name()
        )
        .unwrap();
        s.push('\n');
    }
    for f in &m.implicit_functions {
        implicit_xml(&mut s, f);
    }
    for vd in &m.volume_data {
        volumedata_xml(&mut s, vd);
    }
    for st in &m.slice_stacks {
        match slice_refs.get(&st.id) {
            Some(refs) => {
                write!(
                    s,
                    "<s:slicestack id=\"{}\" zbottom=\"{}\">",
                    st.id,
                    Num(st.zbottom)
                )
                .unwrap();
                for (id, path) in refs {
                    write!(
                        s,
                        "<s:sliceref slicestackid=\"{id}\" slicepath=\"{path}\"/>"
                    )
                    .unwrap();
                }
                s.push_str("</s:slicestack>\n");
            }
            None => slicestack_xml(&mut s, st),
        }
        if s.len() > 1 << 20 {
            w.write_all(s.as_bytes())?;
            s.clear();
        }
    }
    w.write_all(s.as_bytes())?;
    for o in &m.objects {
        write_object(w, o)?;
    }
    w.write_all(b"</resources>\n<build>\n")?;
    for it in &m.build {
        write!(w, "<item objectid=\"{}\"", it.object)?;
        if !it.transform.is_identity() {
            write!(w, " transform=\"{}\"", Mat(&it.transform))?;
        }
        if let Some(p) = &it.part_number {
            write!(w, " partnumber=\"{}\"", esc(p))?;
        }
        w.write_all(b"/>\n")?;
    }
    w.write_all(b"</build>\n</model>\n")
}

fn write_object<W: Write>(w: &mut W, o: &Object) -> std::io::Result<()> {
    write!(w, "<object id=\"{}\" type=\"{}\"", o.id, o.kind.name())?;
    if let Some(n) = &o.name {
        write!(w, " name=\"{}\"", esc(n))?;
    }
    if let Some(p) = &o.part_number {
        write!(w, " partnumber=\"{}\"", esc(p))?;
    }
    if let Some((pid, pindex)) = o.property {
        write!(w, " pid=\"{pid}\" pindex=\"{pindex}\"")?;
    }
    if let Some(sid) = o.slice_stack {
        write!(w, " s:slicestackid=\"{sid}\"")?;
    }
    if o.mesh_resolution == MeshResolution::Low {
        w.write_all(b" s:meshresolution=\"lowres\"")?;
    }
    w.write_all(b">\n")?;
    match &o.content {
        ObjectContent::Components(cs) => {
            w.write_all(b"<components>")?;
            for c in cs {
                write!(w, "<component objectid=\"{}\"", c.object)?;
                if !c.transform.is_identity() {
                    write!(w, " transform=\"{}\"", Mat(&c.transform))?;
                }
                w.write_all(b"/>")?;
            }
            w.write_all(b"</components>\n")?;
        }
        ObjectContent::LevelSet(l) => {
            write!(
                w,
                "<v:levelset functionid=\"{}\" channel=\"{}\" meshid=\"{}\" meshbboxonly=\"{}\"",
                l.function,
                esc(&l.channel),
                l.mesh,
                l.mesh_bbox_only
            )?;
            if !l.transform.is_identity() {
                write!(w, " transform=\"{}\"", Mat(&l.transform))?;
            }
            if l.min_feature_size != 0.0 {
                write!(w, " minfeaturesize=\"{}\"", Num(l.min_feature_size))?;
            }
            if l.fallback != 0.0 {
                write!(w, " fallbackvalue=\"{}\"", Num(l.fallback))?;
            }
            if let Some(v) = l.volume_id {
                write!(w, " volumeid=\"{v}\"")?;
            }
            w.write_all(b"/>\n")?;
        }
        ObjectContent::Mesh(me) => {
            w.write_all(b"<mesh")?;
            if let Some(v) = me.volume_id {
                write!(w, " v:volumeid=\"{v}\"")?;
            }
            w.write_all(b">\n<vertices>\n")?;
            for p in &me.vertices {
                writeln!(
                    w,
                    "<vertex x=\"{}\" y=\"{}\" z=\"{}\"/>",
                    Num(p[0]),
                    Num(p[1]),
                    Num(p[2])
                )?;
            }
            w.write_all(b"</vertices>\n<triangles>\n")?;
            for (i, t) in me.triangles.iter().enumerate() {
                write!(
                    w,
                    "<triangle v1=\"{}\" v2=\"{}\" v3=\"{}\"",
                    t[0], t[1], t[2]
                )?;
                if let Some(p) = &me.properties {
                    let q = p.indices[i];
                    if q[0] == q[1] && q[1] == q[2] {
                        write!(w, " pid=\"{}\" p1=\"{}\"", p.pid, q[0])?;
                    } else {
                        write!(
                            w,
                            " pid=\"{}\" p1=\"{}\" p2=\"{}\" p3=\"{}\"",
                            p.pid, q[0], q[1], q[2]
                        )?;
                    }
                }
                w.write_all(b"/>\n")?;
            }
            w.write_all(b"</triangles>\n")?;
            if let Some(l) = &me.beam_lattice {
                write_lattice(w, l)?;
            }
            w.write_all(b"</mesh>\n")?;
        }
    }
    w.write_all(b"</object>\n")
}

fn write_lattice<W: Write>(w: &mut W, l: &BeamLattice) -> std::io::Result<()> {
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

fn slice_xml(s: &mut String, sl: &Slice) {
    if sl.polygons.is_empty() {
        writeln!(s, "<s:slice ztop=\"{}\"/>", Num(sl.ztop)).unwrap();
        return;
    }
    write!(s, "<s:slice ztop=\"{}\"><s:vertices>", Num(sl.ztop)).unwrap();
    for p in sl.polygons.iter().flatten() {
        write!(s, "<s:vertex x=\"{}\" y=\"{}\"/>", Num(p[0]), Num(p[1])).unwrap();
    }
    s.push_str("</s:vertices>");
    let mut start = 0usize;
    for p in &sl.polygons {
        write!(s, "<s:polygon startv=\"{start}\">").unwrap();
        for k in 1..p.len() {
            write!(s, "<s:segment v2=\"{}\"/>", start + k).unwrap();
        }
        write!(s, "<s:segment v2=\"{start}\"/></s:polygon>").unwrap();
        start += p.len();
    }
    s.push_str("</s:slice>\n");
}

fn slicestack_xml(s: &mut String, st: &SliceStack) {
    writeln!(
        s,
        "<s:slicestack id=\"{}\" zbottom=\"{}\">",
        st.id,
        Num(st.zbottom)
    )
    .unwrap();
    for sl in &st.slices {
        slice_xml(s, sl);
    }
    s.push_str("</s:slicestack>\n");
}

/// Slice index ranges per part, by count and by serialised size.
fn chunk_slices(st: &SliceStack, opts: &WriteOptions) -> Vec<std::ops::Range<usize>> {
    let max_n = opts.max_slices_per_part.max(1);
    let mut out = Vec::new();
    let (mut start, mut bytes) = (0usize, 0usize);
    let mut buf = String::new();
    for (i, sl) in st.slices.iter().enumerate() {
        buf.clear();
        slice_xml(&mut buf, sl);
        let n = i - start;
        if n > 0 && (n >= max_n || bytes + buf.len() > opts.max_slice_bytes_per_part) {
            out.push(start..i);
            start = i;
            bytes = 0;
        }
        bytes += buf.len();
    }
    if start < st.slices.len() {
        out.push(start..st.slices.len());
    }
    out
}

fn fref_attrs(s: &mut String, r: &FunctionRef) {
    write!(
        s,
        " functionid=\"{}\" channel=\"{}\"",
        r.function,
        esc(&r.channel)
    )
    .unwrap();
    if !r.transform.is_identity() {
        write!(s, " transform=\"{}\"", Mat(&r.transform)).unwrap();
    }
    if r.min_feature_size != 0.0 {
        write!(s, " minfeaturesize=\"{}\"", Num(r.min_feature_size)).unwrap();
    }
    if r.fallback != 0.0 {
        write!(s, " fallbackvalue=\"{}\"", Num(r.fallback)).unwrap();
    }
}

fn volumedata_xml(s: &mut String, vd: &VolumeData) {
    write!(s, "<v:volumedata id=\"{}\">", vd.id).unwrap();
    if let Some(c) = &vd.composite {
        write!(s, "<v:composite basematerialid=\"{}\">", c.base_materials).unwrap();
        for m in &c.mappings {
            s.push_str("<v:materialmapping");
            fref_attrs(s, m);
            s.push_str("/>");
        }
        s.push_str("</v:composite>");
    }
    if let Some(c) = &vd.color {
        s.push_str("<v:color");
        fref_attrs(s, c);
        s.push_str("/>");
    }
    for p in &vd.properties {
        write!(
            s,
            "<v:property name=\"{}\" required=\"{}\"",
            esc(&p.name),
            p.required
        )
        .unwrap();
        fref_attrs(s, &p.value);
        s.push_str("/>");
    }
    s.push_str("</v:volumedata>\n");
}

fn implicit_xml(s: &mut String, f: &ImplicitFunction) {
    write!(s, "<i:implicitfunction id=\"{}\"", f.id).unwrap();
    if let Some(n) = &f.display_name {
        write!(s, " displayname=\"{}\"", esc(n)).unwrap();
    }
    s.push_str(">\n<i:in>");
    for (n, t) in &f.inputs {
        write!(s, "<i:{} identifier=\"{}\"/>", t.name(), esc(n)).unwrap();
    }
    s.push_str("</i:in>\n");
    for node in &f.graph.nodes {
        write!(s, "<i:{} identifier=\"{}\"", node.op, node.id).unwrap();
        match &node.value {
            NodeValue::None => {}
            NodeValue::Scalar(v) => write!(s, " value=\"{}\"", Double(*v)).unwrap(),
            NodeValue::Vector(v) => write!(
                s,
                " x=\"{}\" y=\"{}\" z=\"{}\"",
                Double(v[0]),
                Double(v[1]),
                Double(v[2])
            )
            .unwrap(),
            NodeValue::Matrix(m) => {
                let v: Vec<String> = m.iter().map(|x| Double(*x).to_string()).collect();
                write!(s, " matrix=\"{}\"", v.join(" ")).unwrap();
            }
            NodeValue::Resource(r) => write!(s, " value=\"{r}\"").unwrap(),
        }
        s.push('>');
        if !node.inputs.is_empty() {
            s.push_str("<i:in>");
            for i in &node.inputs {
                write!(
                    s,
                    "<i:{} identifier=\"{}\" ref=\"{}\"/>",
                    i.kind.ref_name(),
                    i.port,
                    i.source
                )
                .unwrap();
            }
            s.push_str("</i:in>");
        }
        s.push_str("<i:out>");
        for (o, t) in &node.outputs {
            write!(s, "<i:{} identifier=\"{o}\"/>", t.name()).unwrap();
        }
        writeln!(s, "</i:out></i:{}>", node.op).unwrap();
    }
    s.push_str("<i:out>");
    for o in &f.outputs {
        write!(
            s,
            "<i:{} identifier=\"{}\" ref=\"{}\"/>",
            o.kind.ref_name(),
            esc(&o.name),
            o.source
        )
        .unwrap();
    }
    s.push_str("</i:out>\n</i:implicitfunction>\n");
}

fn bad(msg: impl Into<String>) -> Error {
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

fn check_lattice(
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
