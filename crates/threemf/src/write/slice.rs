//! The slice extension (1.0.2): slice stacks, and the parts that hold
//! the stacks too large for the root part.

use super::xml::{xml_head, Num};
use super::WriteOptions;
use crate::model::{ns, Model};
use crate::slice::{Slice, SliceStack};
use std::collections::HashMap;
use std::fmt::Write as _;
use std::io::Write;

/// Parts (name, XML) for the slice stacks too large for the root part,
/// and the slicerefs (stack id, path) that name them, per stack id.
#[allow(clippy::type_complexity)]
pub(super) fn plan_slice_parts(
    model: &Model,
    opts: &WriteOptions,
) -> (Vec<(String, String)>, HashMap<u32, Vec<(u32, String)>>) {
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
    (slice_parts, slice_refs)
}

/// The slice stacks of the root part: whole, or the slicerefs of the parts
/// they went to (into `s`, and out to `w` when `s` grows large).
pub(super) fn slicestacks_xml<W: Write>(
    w: &mut W,
    s: &mut String,
    m: &Model,
    slice_refs: &HashMap<u32, Vec<(u32, String)>>,
) -> std::io::Result<()> {
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
            None => slicestack_xml(s, st),
        }
        if s.len() > 1 << 20 {
            w.write_all(s.as_bytes())?;
            s.clear();
        }
    }
    Ok(())
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

pub(super) fn slicestack_xml(s: &mut String, st: &SliceStack) {
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
