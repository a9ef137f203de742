//! Implicit extension (consortium draft, namespace
//! `http://schemas.3mf.io/3dmanufacturing/implicit/2023/12`): functions as
//! graphs of native nodes (`addition`, `sin`, `min`, `select`, ...) whose
//! inputs reference earlier nodes' outputs as `node.output` (or the
//! function's arguments as `inputs.name`).
//!
//! [`ImplicitGraph`] is plain data with the ops by their element names;
//! [`NATIVE_NODES`] lists every native node with its port names;
//! [`ImplicitFunction::eval`] evaluates scalar and vector graphs, which the
//! tests use to check a written function against the model it came from.

use std::collections::HashMap;

/// Type of a port.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PortType {
    /// A number.
    Scalar,
    /// Three numbers.
    Vector,
    /// A 4x4 matrix.
    Matrix,
    /// A resource id.
    ResourceId,
}

impl PortType {
    /// Element name of a declaration (`scalar`, `vector`, ...).
    pub fn name(self) -> &'static str {
        match self {
            PortType::Scalar => "scalar",
            PortType::Vector => "vector",
            PortType::Matrix => "matrix",
            PortType::ResourceId => "resourceid",
        }
    }

    /// Element name of a reference (`scalarref`, ...).
    pub fn ref_name(self) -> &'static str {
        match self {
            PortType::Scalar => "scalarref",
            PortType::Vector => "vectorref",
            PortType::Matrix => "matrixref",
            PortType::ResourceId => "resourceref",
        }
    }

    /// Parses a declaration element name.
    pub fn from_name(s: &str) -> Option<PortType> {
        [
            PortType::Scalar,
            PortType::Vector,
            PortType::Matrix,
            PortType::ResourceId,
        ]
        .into_iter()
        .find(|t| t.name() == s)
    }

    /// Parses a reference element name.
    pub fn from_ref_name(s: &str) -> Option<PortType> {
        [
            PortType::Scalar,
            PortType::Vector,
            PortType::Matrix,
            PortType::ResourceId,
        ]
        .into_iter()
        .find(|t| t.ref_name() == s)
    }
}

/// A native node: element name, input and output port names.
#[derive(Clone, Copy, Debug)]
pub struct NodeSpec {
    /// Element name.
    pub name: &'static str,
    /// Input identifiers (empty for constants; `functioncall` takes any).
    pub inputs: &'static [&'static str],
    /// Output identifiers.
    pub outputs: &'static [&'static str],
}

const A: &[&str] = &["A"];
const AB: &[&str] = &["A", "B"];
const R: &[&str] = &["result"];

/// Every native node of the implicit extension draft.
pub const NATIVE_NODES: &[NodeSpec] = &[
    NodeSpec {
        name: "addition",
        inputs: AB,
        outputs: R,
    },
    NodeSpec {
        name: "subtraction",
        inputs: AB,
        outputs: R,
    },
    NodeSpec {
        name: "multiplication",
        inputs: AB,
        outputs: R,
    },
    NodeSpec {
        name: "division",
        inputs: AB,
        outputs: R,
    },
    NodeSpec {
        name: "constant",
        inputs: &[],
        outputs: &["value"],
    },
    NodeSpec {
        name: "constvec",
        inputs: &[],
        outputs: &["vector"],
    },
    NodeSpec {
        name: "constmat",
        inputs: &[],
        outputs: &["matrix"],
    },
    NodeSpec {
        name: "constresourceid",
        inputs: &[],
        outputs: &["value"],
    },
    NodeSpec {
        name: "composevector",
        inputs: &["x", "y", "z"],
        outputs: R,
    },
    NodeSpec {
        name: "vectorfromscalar",
        inputs: A,
        outputs: R,
    },
    NodeSpec {
        name: "decomposevector",
        inputs: A,
        outputs: &["x", "y", "z"],
    },
    NodeSpec {
        name: "composematrix",
        inputs: &[
            "m00", "m01", "m02", "m03", "m10", "m11", "m12", "m13", "m20", "m21", "m22", "m23",
            "m30", "m31", "m32", "m33",
        ],
        outputs: R,
    },
    NodeSpec {
        name: "matrixfromcolumns",
        inputs: &["A", "B", "C", "D"],
        outputs: R,
    },
    NodeSpec {
        name: "matrixfromrows",
        inputs: &["A", "B", "C", "D"],
        outputs: R,
    },
    NodeSpec {
        name: "dot",
        inputs: AB,
        outputs: R,
    },
    NodeSpec {
        name: "cross",
        inputs: AB,
        outputs: R,
    },
    NodeSpec {
        name: "matvecmultiplication",
        inputs: AB,
        outputs: R,
    },
    NodeSpec {
        name: "transpose",
        inputs: A,
        outputs: R,
    },
    NodeSpec {
        name: "inverse",
        inputs: A,
        outputs: R,
    },
    NodeSpec {
        name: "sin",
        inputs: A,
        outputs: R,
    },
    NodeSpec {
        name: "cos",
        inputs: A,
        outputs: R,
    },
    NodeSpec {
        name: "tan",
        inputs: A,
        outputs: R,
    },
    NodeSpec {
        name: "arcsin",
        inputs: A,
        outputs: R,
    },
    NodeSpec {
        name: "arccos",
        inputs: A,
        outputs: R,
    },
    NodeSpec {
        name: "arctan",
        inputs: A,
        outputs: R,
    },
    NodeSpec {
        name: "arctan2",
        inputs: AB,
        outputs: R,
    },
    NodeSpec {
        name: "min",
        inputs: AB,
        outputs: R,
    },
    NodeSpec {
        name: "max",
        inputs: AB,
        outputs: R,
    },
    NodeSpec {
        name: "abs",
        inputs: A,
        outputs: R,
    },
    NodeSpec {
        name: "fmod",
        inputs: AB,
        outputs: R,
    },
    NodeSpec {
        name: "mod",
        inputs: AB,
        outputs: R,
    },
    NodeSpec {
        name: "pow",
        inputs: AB,
        outputs: R,
    },
    NodeSpec {
        name: "sqrt",
        inputs: A,
        outputs: R,
    },
    NodeSpec {
        name: "exp",
        inputs: A,
        outputs: R,
    },
    NodeSpec {
        name: "log",
        inputs: A,
        outputs: R,
    },
    NodeSpec {
        name: "log2",
        inputs: A,
        outputs: R,
    },
    NodeSpec {
        name: "log10",
        inputs: A,
        outputs: R,
    },
    NodeSpec {
        name: "select",
        inputs: &["A", "B", "C", "D"],
        outputs: R,
    },
    NodeSpec {
        name: "clamp",
        inputs: &["A", "min", "max"],
        outputs: R,
    },
    NodeSpec {
        name: "cosh",
        inputs: A,
        outputs: R,
    },
    NodeSpec {
        name: "sinh",
        inputs: A,
        outputs: R,
    },
    NodeSpec {
        name: "tanh",
        inputs: A,
        outputs: R,
    },
    NodeSpec {
        name: "round",
        inputs: A,
        outputs: R,
    },
    NodeSpec {
        name: "ceil",
        inputs: A,
        outputs: R,
    },
    NodeSpec {
        name: "floor",
        inputs: A,
        outputs: R,
    },
    NodeSpec {
        name: "sign",
        inputs: A,
        outputs: R,
    },
    NodeSpec {
        name: "fract",
        inputs: A,
        outputs: R,
    },
    NodeSpec {
        name: "functioncall",
        inputs: &["functionID"],
        outputs: &[],
    },
    NodeSpec {
        name: "mesh",
        inputs: &["pos", "mesh"],
        outputs: &["distance"],
    },
    NodeSpec {
        name: "unsignedmesh",
        inputs: &["pos", "mesh"],
        outputs: &["distance"],
    },
    NodeSpec {
        name: "length",
        inputs: A,
        outputs: R,
    },
];

/// The native node named `name`.
pub fn node_spec(name: &str) -> Option<&'static NodeSpec> {
    NATIVE_NODES.iter().find(|s| s.name == name)
}

/// Constant data carried by a node's attributes.
#[derive(Clone, Debug, Default, PartialEq)]
pub enum NodeValue {
    /// None (operations).
    #[default]
    None,
    /// `constant value="..."`.
    Scalar(f64),
    /// `constvec x y z`.
    Vector([f64; 3]),
    /// `constmat matrix="..."` (row-major).
    Matrix([f64; 16]),
    /// `constresourceid value="..."`.
    Resource(u32),
}

/// One input of a node: port name, where it comes from and its type.
#[derive(Clone, Debug, PartialEq)]
pub struct NodeInput {
    /// Port identifier (`A`, `B`, `x`, ...).
    pub port: String,
    /// `node.output` or `inputs.argument`.
    pub source: String,
    /// Type of the referenced output.
    pub kind: PortType,
}

/// A node of an implicit function.
#[derive(Clone, Debug, PartialEq)]
pub struct ImplicitNode {
    /// Identifier (letters, digits, `_`; unique in the function).
    pub id: String,
    /// Element name of the operation (see [`NATIVE_NODES`]).
    pub op: String,
    /// Constant data.
    pub value: NodeValue,
    /// Inputs.
    pub inputs: Vec<NodeInput>,
    /// Outputs and their types.
    pub outputs: Vec<(String, PortType)>,
}

/// The nodes of a function, each referencing only earlier nodes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ImplicitGraph {
    /// Nodes in evaluation order.
    pub nodes: Vec<ImplicitNode>,
}

/// An output of the function.
#[derive(Clone, Debug, PartialEq)]
pub struct FunctionOutput {
    /// Output identifier.
    pub name: String,
    /// Its type.
    pub kind: PortType,
    /// `node.output` it takes.
    pub source: String,
}

/// An `<i:implicitfunction>` resource.
#[derive(Clone, Debug, PartialEq)]
pub struct ImplicitFunction {
    /// Resource id.
    pub id: u32,
    /// Display name.
    pub display_name: Option<String>,
    /// Arguments: names and types.
    pub inputs: Vec<(String, PortType)>,
    /// The node graph.
    pub graph: ImplicitGraph,
    /// Outputs.
    pub outputs: Vec<FunctionOutput>,
}

/// A value during evaluation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Value {
    /// A number.
    Scalar(f64),
    /// A 3-vector.
    Vector([f64; 3]),
}

/// Whether `s` is a valid identifier (`[A-Za-z0-9_]+`).
pub fn is_identifier(s: &str) -> bool {
    !s.is_empty() && s.bytes().all(|b| b.is_ascii_alphanumeric() || b == b'_')
}

fn fmin(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else if a < b {
        a
    } else {
        b
    }
}

fn fmax(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else if a > b {
        a
    } else {
        b
    }
}

fn sign(a: f64) -> f64 {
    if a > 0.0 {
        1.0
    } else if a < 0.0 {
        -1.0
    } else {
        0.0
    }
}

impl ImplicitFunction {
    /// Checks identifiers, that every input names a known port of its node
    /// and references an argument or an earlier node's output of the type it
    /// claims, and that outputs reference existing node outputs. The message
    /// names the node.
    pub fn validate(&self) -> Result<(), String> {
        let mut outputs: HashMap<String, PortType> = HashMap::new();
        for (n, t) in &self.inputs {
            if !is_identifier(n) {
                return Err(format!("function input `{n}` is not an identifier"));
            }
            outputs.insert(format!("inputs.{n}"), *t);
        }
        for node in &self.graph.nodes {
            if !is_identifier(&node.id) || node.id == "inputs" || node.id == "outputs" {
                return Err(format!("node identifier `{}` is not allowed", node.id));
            }
            let Some(spec) = node_spec(&node.op) else {
                return Err(format!(
                    "node `{}`: unknown operation `{}`",
                    node.id, node.op
                ));
            };
            for inp in &node.inputs {
                if spec.name != "functioncall" && !spec.inputs.contains(&inp.port.as_str()) {
                    return Err(format!(
                        "node `{}` ({}): no input port `{}`",
                        node.id, node.op, inp.port
                    ));
                }
                match outputs.get(&inp.source) {
                    None => {
                        return Err(format!(
                            "node `{}` input `{}` references `{}`, which is not an argument or an earlier node's output",
                            node.id, inp.port, inp.source
                        ))
                    }
                    Some(t) if *t != inp.kind => {
                        return Err(format!(
                            "node `{}` input `{}`: `{}` is a {}, not a {}",
                            node.id,
                            inp.port,
                            inp.source,
                            t.name(),
                            inp.kind.name()
                        ))
                    }
                    _ => {}
                }
            }
            for (o, t) in &node.outputs {
                if outputs.insert(format!("{}.{o}", node.id), *t).is_some() {
                    return Err(format!("node identifier `{}` is used twice", node.id));
                }
            }
        }
        for o in &self.outputs {
            match outputs.get(&o.source) {
                Some(t) if *t == o.kind => {}
                _ => {
                    return Err(format!(
                        "function output `{}` references `{}`, not a {} node output",
                        o.name,
                        o.source,
                        o.kind.name()
                    ))
                }
            }
        }
        Ok(())
    }

    /// Evaluates the function for the given arguments; supports scalar and
    /// vector nodes (not matrices, resources or calls). Semantics follow the
    /// draft: `select` is `A < B ? C : D`, `fmod` C's `fmod`, `mod`
    /// `A - B floor(A / B)`, `round` half away from zero, `min`/`max` NaN if
    /// either is NaN.
    pub fn eval(&self, args: &[(&str, Value)]) -> Result<Vec<(String, Value)>, String> {
        let mut vals: HashMap<String, Value> = HashMap::new();
        for (n, v) in args {
            vals.insert(format!("inputs.{n}"), *v);
        }
        for node in &self.graph.nodes {
            let get = |port: &str| -> Result<Value, String> {
                let inp = node
                    .inputs
                    .iter()
                    .find(|i| i.port == port)
                    .ok_or_else(|| format!("node `{}` has no input `{port}`", node.id))?;
                vals.get(&inp.source)
                    .copied()
                    .ok_or_else(|| format!("node `{}`: `{}` has no value", node.id, inp.source))
            };
            let out = eval_node(node, &get)?;
            if let ([(_, v)], [(declared, _)]) = (out.as_slice(), node.outputs.as_slice()) {
                // A single output goes by the name the node declares.
                vals.insert(format!("{}.{declared}", node.id), *v);
            } else {
                for (name, v) in out {
                    vals.insert(format!("{}.{name}", node.id), v);
                }
            }
        }
        self.outputs
            .iter()
            .map(|o| {
                vals.get(&o.source)
                    .map(|v| (o.name.clone(), *v))
                    .ok_or_else(|| format!("output `{}`: `{}` has no value", o.name, o.source))
            })
            .collect()
    }

    /// The first output at position `p`, for a function of one vector
    /// argument (`pos`) with a scalar first output.
    pub fn eval_at(&self, p: [f64; 3]) -> Result<f64, String> {
        let name = self
            .inputs
            .first()
            .map(|i| i.0.as_str())
            .ok_or("function has no input")?;
        match self.eval(&[(name, Value::Vector(p))])?.first() {
            Some((_, Value::Scalar(v))) => Ok(*v),
            _ => Err("first output is not a scalar".into()),
        }
    }
}

fn eval_node(
    node: &ImplicitNode,
    get: &dyn Fn(&str) -> Result<Value, String>,
) -> Result<Vec<(&'static str, Value)>, String> {
    use Value::*;
    let unsupported = || format!("node `{}`: `{}` is not evaluated here", node.id, node.op);
    let map1 = |f: fn(f64) -> f64| -> Result<Value, String> {
        Ok(match get("A")? {
            Scalar(a) => Scalar(f(a)),
            Vector(v) => Vector(v.map(f)),
        })
    };
    let map2 = |f: &dyn Fn(f64, f64) -> f64| -> Result<Value, String> {
        Ok(match (get("A")?, get("B")?) {
            (Scalar(a), Scalar(b)) => Scalar(f(a, b)),
            (Vector(a), Vector(b)) => Vector(std::array::from_fn(|i| f(a[i], b[i]))),
            (Scalar(a), Vector(b)) => Vector(b.map(|b| f(a, b))),
            (Vector(a), Scalar(b)) => Vector(a.map(|a| f(a, b))),
        })
    };
    let vec = |v: Value| match v {
        Vector(v) => Ok(v),
        Scalar(_) => Err(format!("node `{}`: expected a vector", node.id)),
    };
    let scalar = |v: Value| match v {
        Scalar(v) => Ok(v),
        Vector(_) => Err(format!("node `{}`: expected a scalar", node.id)),
    };
    let r = match node.op.as_str() {
        "constant" => match node.value {
            NodeValue::Scalar(v) => Scalar(v),
            _ => return Err(format!("constant `{}` has no value", node.id)),
        },
        "constvec" => match node.value {
            NodeValue::Vector(v) => Vector(v),
            _ => return Err(format!("constvec `{}` has no value", node.id)),
        },
        "addition" => map2(&|a, b| a + b)?,
        "subtraction" => map2(&|a, b| a - b)?,
        "multiplication" => map2(&|a, b| a * b)?,
        "division" => map2(&|a, b| a / b)?,
        "min" => map2(&fmin)?,
        "max" => map2(&fmax)?,
        "fmod" => map2(&|a, b| a % b)?,
        "mod" => map2(&|a, b| a - b * (a / b).floor())?,
        "pow" => map2(&f64::powf)?,
        "arctan2" => map2(&f64::atan2)?,
        "sin" => map1(f64::sin)?,
        "cos" => map1(f64::cos)?,
        "tan" => map1(f64::tan)?,
        "arcsin" => map1(f64::asin)?,
        "arccos" => map1(f64::acos)?,
        "arctan" => map1(f64::atan)?,
        "abs" => map1(f64::abs)?,
        "sqrt" => map1(f64::sqrt)?,
        "exp" => map1(f64::exp)?,
        "log" => map1(f64::ln)?,
        "log2" => map1(f64::log2)?,
        "log10" => map1(f64::log10)?,
        "cosh" => map1(f64::cosh)?,
        "sinh" => map1(f64::sinh)?,
        "tanh" => map1(f64::tanh)?,
        "round" => map1(f64::round)?,
        "ceil" => map1(f64::ceil)?,
        "floor" => map1(f64::floor)?,
        "sign" => map1(sign)?,
        "fract" => map1(|a| a - a.floor())?,
        "select" => {
            let (a, b) = (scalar(get("A")?)?, scalar(get("B")?)?);
            if a < b {
                get("C")?
            } else {
                get("D")?
            }
        }
        "clamp" => {
            let (a, lo, hi) = (
                scalar(get("A")?)?,
                scalar(get("min")?)?,
                scalar(get("max")?)?,
            );
            Scalar(fmax(lo, fmin(a, hi)))
        }
        "composevector" => Vector([scalar(get("x")?)?, scalar(get("y")?)?, scalar(get("z")?)?]),
        "vectorfromscalar" => Vector([scalar(get("A")?)?; 3]),
        "decomposevector" => {
            let v = vec(get("A")?)?;
            return Ok(vec![
                ("x", Scalar(v[0])),
                ("y", Scalar(v[1])),
                ("z", Scalar(v[2])),
            ]);
        }
        "dot" => {
            let (a, b) = (vec(get("A")?)?, vec(get("B")?)?);
            Scalar(a[0] * b[0] + a[1] * b[1] + a[2] * b[2])
        }
        "cross" => {
            let (a, b) = (vec(get("A")?)?, vec(get("B")?)?);
            Vector([
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ])
        }
        "length" => {
            let a = vec(get("A")?)?;
            Scalar((a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt())
        }
        _ => return Err(unsupported()),
    };
    let name = node_spec(&node.op)
        .and_then(|s| s.outputs.first().copied())
        .unwrap_or("result");
    Ok(vec![(name, r)])
}
