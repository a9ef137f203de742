//! Extension hook: other crates add functions to the HyperFun library (e.g.
//! the microstructure library `mf*`) without this crate depending on them.
//! A host installs an extension once at start-up; from then on every
//! [`Registry::standard`] (used by parsing and lowering) includes it.

use super::Registry;
use std::sync::RwLock;

/// Adds functions to a registry.
pub type Extension = fn(&mut Registry);

static EXTENSIONS: RwLock<Vec<(&'static str, Extension)>> = RwLock::new(Vec::new());

/// Installs `ext` under `key`; installing the same key again does nothing,
/// so hosts may call this on every model load.
pub fn add_extension(key: &'static str, ext: Extension) {
    let mut v = EXTENSIONS.write().unwrap_or_else(|e| e.into_inner());
    if !v.iter().any(|(k, _)| *k == key) {
        v.push((key, ext));
    }
}

/// Keys of the installed extensions, in installation order.
pub fn extensions() -> Vec<&'static str> {
    let v = EXTENSIONS.read().unwrap_or_else(|e| e.into_inner());
    v.iter().map(|(k, _)| *k).collect()
}

/// Runs every installed extension on `r`.
pub(super) fn apply(r: &mut Registry) {
    let v = EXTENSIONS.read().unwrap_or_else(|e| e.into_inner());
    for (_, ext) in v.iter() {
        ext(r);
    }
}
