//! The implicit extension (draft): implicit functions as node graphs.

use super::parser::{Attrs, Ctx, Ns, Parser};
use super::values::{parse_double, parse_id};
use crate::error::Result;
use crate::implicit::{
    FunctionOutput, ImplicitFunction, ImplicitGraph, ImplicitNode, NodeInput, NodeValue, PortType,
};

impl Parser<'_> {
    /// Implicit function elements (`None`: not one of them).
    pub(super) fn implicit_start(
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
            (Resources, Ns::Implicit, "implicitfunction") => {
                let id = parse_id(part, off, "id", need("id")?)?;
                self.resource_id(id, "implicitfunction")?;
                self.function = Some(ImplicitFunction {
                    id,
                    display_name: get("displayname").map(str::to_string),
                    inputs: Vec::new(),
                    graph: ImplicitGraph::default(),
                    outputs: Vec::new(),
                });
                Implicit
            }
            (Implicit, Ns::Implicit, "in") => FnIn,
            (Implicit, Ns::Implicit, "out") => FnOut,
            (FnIn, Ns::Implicit, t) => {
                let kind = PortType::from_name(t)
                    .ok_or_else(|| self.err(format!("unknown function input type <{t}>")))?;
                let id = need("identifier")?.to_string();
                self.function.as_mut().unwrap().inputs.push((id, kind));
                Skip
            }
            (FnOut, Ns::Implicit, t) => {
                let kind = PortType::from_ref_name(t)
                    .ok_or_else(|| self.err(format!("unknown function output <{t}>")))?;
                let o = FunctionOutput {
                    name: need("identifier")?.to_string(),
                    kind,
                    source: need("ref")?.to_string(),
                };
                self.function.as_mut().unwrap().outputs.push(o);
                Skip
            }
            (Implicit, Ns::Implicit, op) => {
                if crate::implicit::node_spec(op).is_none() {
                    return Err(self.err(format!("unknown implicit node <{op}>")));
                }
                let value = match op {
                    "constant" => {
                        NodeValue::Scalar(parse_double(part, off, "value", need("value")?)?)
                    }
                    "constvec" => NodeValue::Vector([
                        parse_double(part, off, "x", need("x")?)?,
                        parse_double(part, off, "y", need("y")?)?,
                        parse_double(part, off, "z", need("z")?)?,
                    ]),
                    "constmat" => {
                        let v: Vec<f64> = need("matrix")?
                            .split_ascii_whitespace()
                            .map(|x| parse_double(part, off, "matrix", x))
                            .collect::<Result<_>>()?;
                        let m: [f64; 16] = v
                            .try_into()
                            .map_err(|_| self.err("constmat needs 16 numbers"))?;
                        NodeValue::Matrix(m)
                    }
                    "constresourceid" => {
                        NodeValue::Resource(parse_id(part, off, "value", need("value")?)?)
                    }
                    _ => NodeValue::None,
                };
                self.node = Some(ImplicitNode {
                    id: need("identifier")?.to_string(),
                    op: op.to_string(),
                    value,
                    inputs: Vec::new(),
                    outputs: Vec::new(),
                });
                Node
            }
            (Node, Ns::Implicit, "in") => NodeIn,
            (Node, Ns::Implicit, "out") => NodeOut,
            (NodeIn, Ns::Implicit, t) => {
                let kind = PortType::from_ref_name(t)
                    .ok_or_else(|| self.err(format!("unknown node input <{t}>")))?;
                let i = NodeInput {
                    port: need("identifier")?.to_string(),
                    source: need("ref")?.to_string(),
                    kind,
                };
                self.node.as_mut().unwrap().inputs.push(i);
                Skip
            }
            (NodeOut, Ns::Implicit, t) => {
                let kind = PortType::from_name(t)
                    .ok_or_else(|| self.err(format!("unknown node output <{t}>")))?;
                let id = need("identifier")?.to_string();
                self.node.as_mut().unwrap().outputs.push((id, kind));
                Skip
            }
            _ => return Ok(None),
        };
        Ok(Some(ctx))
    }

    /// Closes an implicit function element.
    pub(super) fn implicit_end(&mut self, ctx: Ctx) -> Result<()> {
        use Ctx::*;
        match ctx {
            Node => {
                let n = self.node.take().unwrap();
                self.function.as_mut().unwrap().graph.nodes.push(n);
            }
            Implicit => {
                let f = self.function.take().unwrap();
                f.validate()
                    .map_err(|m| self.err(format!("implicitfunction {}: {m}", f.id)))?;
                self.model.implicit_functions.push(f);
            }
            _ => {}
        }
        Ok(())
    }
}
