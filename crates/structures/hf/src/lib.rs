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
//!
//! ```
//! microfrep_structures_hf::install();
//! // A gyroid sheet (2 mm cells, wall |f| < 0.3) inside a ball of radius 2.
//! let src = "my_model(x[3], a[1]) {
//!     ball = 4 - x[1]^2 - x[2]^2 - x[3]^2;
//!     my_model = mfGyroidSheet(x, 2, 0.3) & ball;
//! }";
//! let model = microfrep_hyperfun::load(src, "gyroid.hf", None).unwrap();
//! let v = model.eval_points(&[[0.0; 3], [0.5, 0.0, 0.0]]);
//! assert!(*v[0].as_ref().unwrap() > 0.0); // on the surface: in the wall
//! assert!(*v[1].as_ref().unwrap() < 0.0); // a quarter cell away: outside
//! assert!(microfrep_structures_hf::names().contains(&"mfgyroidsheet"));
//! ```

#![warn(missing_docs)]

mod args;
mod cells;
mod graded;
mod pasko;
mod pores;
mod struts;
mod tables;
mod tpms;

pub use struts::{strut_model, StrutCall, StrutModel};
pub use tables::{solve_strut_table, solve_tpms_table, strut_table, tpms_table};

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
