//! The microstructure library for HyperFun: every structure of
//! `microfrep-structures` as an `mf*` function (documented in
//! `crates/structures/LIBRARY.md`), so a paper example is a short HyperFun
//! model.
//!
//! The functions are ordinary registry entries, exactly like the reference
//! library's `hf*` ones: the parser learns their names and argument kinds from
//! the registry, so no parser change is needed. A host calls [`install`] once
//! (the `microfrep` CLI does so before loading any model); from then on
//! every `microfrep_hyperfun::parse`/`load` sees them.

mod args;
mod cells;
mod graded;
mod pasko;
mod pores;
mod struts;
mod tables;
mod tpms;

use microfrep_hyperfun::library::{add_extension, Registry};

/// Prefix of every function of this library.
pub const PREFIX: &str = "mf";

/// Adds every `mf*` function to `r`.
pub fn register(r: &mut Registry) {
    pasko::register(r);
    cells::register(r);
    tpms::register(r);
    struts::register(r);
    graded::register(r);
    pores::register(r);
}

/// Installs the library into every standard HyperFun registry of this
/// process. Idempotent.
pub fn install() {
    add_extension("microfrep-structures", register);
}

/// The reference library plus this one, without installing anything.
pub fn registry() -> Registry {
    let mut r = Registry::reference();
    register(&mut r);
    r
}

/// Names (lower case) of this library's functions, sorted.
pub fn names() -> Vec<&'static str> {
    let mut r = Registry::empty();
    register(&mut r);
    r.names()
}
