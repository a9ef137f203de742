//! The implicit extension (draft): implicit functions as node graphs.

use super::xml::{esc, Double};
use crate::implicit::{ImplicitFunction, NodeValue};
use std::fmt::Write as _;

/// An `<i:implicitfunction>`.
pub(super) fn implicit_xml(s: &mut String, f: &ImplicitFunction) {
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
