//! Output formats behind one trait, chosen by file extension.
//!
//! Each kind of product (meshes, layer stacks, voxel grids, images) has its
//! own trait for the writing itself, extending [`OutputFormat`], and a
//! [`FormatRegistry`] of its formats: adding a format is one type and one
//! registration line, and every verb reports unknown extensions with the
//! list of known ones.

use crate::{IoError, Result};
use std::path::Path;

/// What every output format says about itself.
pub trait OutputFormat: Send + Sync {
    /// Short name, e.g. "binary STL".
    fn name(&self) -> &'static str;
    /// Lower-case extensions without the dot, e.g. `["stl"]`; an empty
    /// string matches a path without extension (directories).
    fn extensions(&self) -> &'static [&'static str];
}

/// The formats of one kind of product, looked up by extension.
pub struct FormatRegistry<F: ?Sized + OutputFormat> {
    kind: &'static str,
    formats: Vec<Box<F>>,
}

impl<F: ?Sized + OutputFormat> FormatRegistry<F> {
    /// An empty registry for products called `kind` in messages ("mesh").
    pub fn new(kind: &'static str) -> Self {
        FormatRegistry {
            kind,
            formats: Vec::new(),
        }
    }

    /// Adds a format.
    pub fn register(&mut self, f: Box<F>) {
        self.formats.push(f);
    }

    /// Every registered format, in registration order.
    pub fn formats(&self) -> impl Iterator<Item = &F> {
        self.formats.iter().map(|b| &**b)
    }

    /// The known extensions as `.a, .b`.
    pub fn known(&self) -> String {
        let v: Vec<String> = self
            .formats
            .iter()
            .flat_map(|f| f.extensions().iter())
            .filter(|e| !e.is_empty())
            .map(|e| format!(".{e}"))
            .collect();
        v.join(", ")
    }

    /// The format of a path by its extension (case-insensitive).
    pub fn for_path(&self, path: &Path) -> Result<&F> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase())
            .unwrap_or_default();
        self.formats
            .iter()
            .find(|f| f.extensions().contains(&ext.as_str()))
            .map(|b| &**b)
            .ok_or_else(|| IoError::UnknownFormat {
                path: path.to_path_buf(),
                kind: self.kind,
                known: self.known(),
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    trait Thing: OutputFormat {
        fn tag(&self) -> u8;
    }
    struct A;
    impl OutputFormat for A {
        fn name(&self) -> &'static str {
            "a"
        }
        fn extensions(&self) -> &'static [&'static str] {
            &["aa", "a"]
        }
    }
    impl Thing for A {
        fn tag(&self) -> u8 {
            1
        }
    }

    #[test]
    fn lookup_by_extension_and_clear_errors() {
        let mut r: FormatRegistry<dyn Thing> = FormatRegistry::new("thing");
        r.register(Box::new(A));
        assert_eq!(r.for_path(Path::new("x.AA")).unwrap().tag(), 1);
        let e = r.for_path(Path::new("x.b")).err().unwrap().to_string();
        assert!(e.contains("unknown thing format (use .aa, .a)"), "{e}");
    }
}
