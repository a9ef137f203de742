//! Rust errors as the package's exceptions, with the CLI's messages.

use crate::{
    AnalysisError, BoundsError, HyperFunError, InputError, LoadError, MemoryLimitError, MeshError,
    RenderError, SliceError, StructureError,
};
use microfrep::hyperfun::Diagnostics;
use pyo3::prelude::*;
use pyo3::types::PyTuple;

/// The message of an error with its chain of causes, as `anyhow` prints
/// them in the CLI (`message: cause: cause`), without repeating a cause
/// the message already holds.
pub fn chain(e: &dyn std::error::Error) -> String {
    let mut s = e.to_string();
    let mut src = e.source();
    while let Some(c) = src {
        let t = c.to_string();
        if !s.contains(&t) {
            s.push_str(": ");
            s.push_str(&t);
        }
        src = c.source();
    }
    s
}

/// A bad argument.
pub fn input(msg: impl Into<String>) -> PyErr {
    InputError::new_err(msg.into())
}

/// HyperFun diagnostics as a `HyperFunError`: the rendered report (source
/// lines and carets) and a closing count, as the CLI prints them; the
/// located messages as `.locations`.
pub fn hyperfun(py: Python<'_>, d: &Diagnostics, text: &str, file: &str) -> PyErr {
    let mut msg = d.render(text);
    let n = d.errors().count().max(1);
    msg.push_str(&format!("{file}: {n} error(s)"));
    let err = HyperFunError::new_err(msg);
    let locs: Vec<(String, u32, u32, String)> = d
        .errors()
        .map(|x| (d.file.clone(), x.pos.line, x.pos.col, x.message.clone()))
        .collect();
    if let Ok(t) = PyTuple::new(py, locs) {
        let _ = err.value(py).setattr("locations", t);
    }
    err
}

/// A loader error; HyperFun errors are rendered against `text` (the file
/// is read again if `text` is not given, as the CLI does).
pub fn load(py: Python<'_>, e: microfrep::LoadError, spec: &str, text: Option<&str>) -> PyErr {
    match e {
        microfrep::LoadError::HyperFun(d) => {
            let t = match text {
                Some(t) => t.to_string(),
                None => std::fs::read_to_string(spec).unwrap_or_default(),
            };
            hyperfun(py, &d, &t, spec)
        }
        e => LoadError::new_err(chain(&e)),
    }
}

pub fn bounds(name: &str, e: microfrep::core::BoundsError) -> PyErr {
    BoundsError::new_err(format!("model '{name}': {}", chain(&e)))
}

pub fn mesh(e: microfrep::mesh::MeshError) -> PyErr {
    match e {
        microfrep::mesh::MeshError::TooLarge(m) => MemoryLimitError::new_err(m),
        microfrep::mesh::MeshError::Input(m) => InputError::new_err(m),
        e => MeshError::new_err(chain(&e)),
    }
}

pub fn fab(e: microfrep::fab::FabError) -> PyErr {
    match e {
        microfrep::fab::FabError::Invalid(m) => InputError::new_err(m),
        e => SliceError::new_err(chain(&e)),
    }
}

pub fn io(e: microfrep::io::IoError) -> PyErr {
    SliceError::new_err(chain(&e))
}

pub fn render(e: microfrep::render::RenderError) -> PyErr {
    RenderError::new_err(chain(&e))
}

pub fn analysis(e: microfrep::analysis::AnalysisError) -> PyErr {
    match e {
        microfrep::analysis::AnalysisError::Memory(m) => MemoryLimitError::new_err(m),
        microfrep::analysis::AnalysisError::Input(m) => InputError::new_err(m),
    }
}

pub fn structure(e: impl std::error::Error) -> PyErr {
    StructureError::new_err(chain(&e))
}

pub fn structure_msg(m: String) -> PyErr {
    StructureError::new_err(m)
}

#[allow(dead_code)]
pub fn analysis_msg(m: String) -> PyErr {
    AnalysisError::new_err(m)
}

/// Bytes this process may allocate: 80 % of what the system reports, as
/// the CLI takes it, else 4 GiB.
pub fn memory_limit() -> f64 {
    microfrep::io::limits::memory_limit()
        .map(|m| 0.8 * m)
        .unwrap_or(4.0 * (1u64 << 30) as f64)
}

/// Refuses an output of `bytes` over the memory limit.
pub fn check_memory(bytes: f64, what: &str) -> PyResult<()> {
    let limit = memory_limit();
    if bytes > limit {
        return Err(MemoryLimitError::new_err(format!(
            "{what} needs {:.0} MiB, over the {:.0} MiB this process may use",
            bytes / MIB,
            limit / MIB
        )));
    }
    Ok(())
}

const MIB: f64 = 1024.0 * 1024.0;
