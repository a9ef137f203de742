//! Data fields that models bind by name (`--field NAME=SOURCE` in a
//! comment, the edit's `fields`, or the server's own
//! [`crate::ServeOptions::fields`]): read from files under the working
//! directory (any file for the server's own), built once and kept for every
//! session of the server.
//!
//! A part is keyed by its canonical path, its source options, and the
//! file's size and modification time, so an edit of the model (every
//! keystroke is one) reuses the built field, and a changed file is read
//! again. Two sessions asking for the same part at once build it once (the
//! second waits for the first). Builds are not stopped by newer edits, which
//! almost always need the same part; errors are kept too, until the file
//! changes. At most [`MAX_PARTS`] parts are kept, the least recently used
//! dropped first.
//!
//! A large scan that is not built yet first comes as a coarse stand-in
//! ([`Parts::coarse_step`]: the scan averaged over blocks of `step`^3
//! voxels, so its distance transform takes a fraction of the time) for the
//! first image, while the full scan is built in the background.

use crate::engine::{self, Part};
use crate::error::StudioError;
use crate::paths;
use crate::session::panic_message;
use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, OnceLock};

/// Built parts kept at once.
pub const MAX_PARTS: usize = 4;

/// Scans of more bytes than this come coarse first, unless already built
/// or read with a `step` of their own.
pub const COARSE_BYTES: u64 = 4 << 20;

/// Bytes a coarse stand-in aims at: the step is the smallest power of two
/// whose cube brings the file's bytes below this (at most 8).
const COARSE_TARGET: u64 = 1 << 20;

#[derive(Clone, Debug, PartialEq, Eq, Hash)]
struct Key {
    path: PathBuf,
    options: String,
    len: u64,
    modified: Option<std::time::SystemTime>,
}

type Built = Arc<OnceLock<Result<Arc<Part>, String>>>;

struct Entry {
    cell: Built,
    used: u64,
}

/// The parts of one server.
pub(crate) struct Parts {
    root: PathBuf,
    memory_limit: u64,
    map: Mutex<HashMap<Key, Entry>>,
    clock: AtomicU64,
}

/// A part as a model binds it.
#[derive(Clone)]
pub(crate) struct Bound {
    /// The function name.
    pub name: String,
    /// The source as written (`PATH[:key=value,...]`).
    pub spec: String,
    /// The built field.
    pub part: Arc<Part>,
    /// Whether it was built before this edit asked for it.
    pub cached: bool,
    /// The averaging step of a coarse stand-in (None: the part itself).
    pub coarse: Option<usize>,
}

impl Parts {
    pub(crate) fn new(root: PathBuf, memory_limit: u64) -> Parts {
        Parts {
            root,
            memory_limit,
            map: Mutex::new(HashMap::new()),
            clock: AtomicU64::new(0),
        }
    }

    /// The source, its checked path and its cache key.
    fn resolve(
        &self,
        name: &str,
        spec: &str,
        trusted: bool,
    ) -> Result<(microfrep::load::Source, paths::Checked, Key), StudioError> {
        let bad =
            |e: &dyn std::fmt::Display| StudioError::Request(format!("field {name}={spec}: {e}"));
        let src = microfrep::load::Source::parse(spec).map_err(|e| bad(&e))?;
        // The server's own bindings (its operator's) may name any file;
        // the page's and the models' stay under the working directory.
        let checked = if trusted {
            let full = self
                .root
                .join(&src.path)
                .canonicalize()
                .map_err(|e| bad(&e))?;
            paths::Checked {
                relative: src.path.clone(),
                full,
            }
        } else {
            paths::existing(&self.root, &src.path).map_err(|e| bad(&e))?
        };
        let meta = std::fs::metadata(&checked.full).map_err(|e| bad(&e))?;
        // A folder of slices: its files' sizes and latest change.
        let (len, modified) = if meta.is_dir() {
            let mut len = 0;
            let mut latest = meta.modified().ok();
            if let Ok(rd) = std::fs::read_dir(&checked.full) {
                for m in rd.flatten().filter_map(|e| e.metadata().ok()) {
                    len += m.len();
                    latest = latest.max(m.modified().ok());
                }
            }
            (len, latest)
        } else {
            (meta.len(), meta.modified().ok())
        };
        let key = Key {
            path: checked.full.clone(),
            options: format!("{:?}", src.options),
            len,
            modified,
        };
        Ok((src, checked, key))
    }

    /// The averaging step for a coarse stand-in of `spec`: for a scan of
    /// more than [`COARSE_BYTES`] that is not built yet and has no `step`
    /// of its own; None otherwise (or when `spec` is bad: [`Parts::get`]
    /// then says why).
    pub(crate) fn coarse_step(&self, name: &str, spec: &str, trusted: bool) -> Option<usize> {
        use microfrep::load::{kind_of, SourceKind};
        let (src, checked, key) = self.resolve(name, spec, trusted).ok()?;
        let scan = kind_of(&checked.full) == Some(SourceKind::Scan);
        if !scan || src.options.contains_key("step") || key.len <= COARSE_BYTES {
            return None;
        }
        let map = self.map.lock().unwrap_or_else(|e| e.into_inner());
        if map.get(&key).is_some_and(|e| e.cell.get().is_some()) {
            return None;
        }
        let mut step: u64 = 2;
        while step < 8 && key.len / (step * step * step) > COARSE_TARGET {
            step *= 2;
        }
        Some(step as usize)
    }

    /// The coarse stand-in of `spec` at `step` (see [`Parts::coarse_step`]).
    pub(crate) fn get_coarse(
        &self,
        name: &str,
        spec: &str,
        trusted: bool,
        step: usize,
        progress: &(dyn Fn(&str, u64, u64) + Sync),
    ) -> Result<Bound, StudioError> {
        let with = match spec.rsplit_once(':') {
            Some((p, o)) if o.contains('=') && !p.is_empty() => format!("{spec},step={step}"),
            _ => format!("{spec}:step={step}"),
        };
        let mut b = self.get(name, &with, trusted, progress)?;
        b.spec = spec.to_string();
        b.coarse = Some(step);
        Ok(b)
    }

    /// The field of `spec` (`PATH[:key=value,...]`, the path relative to
    /// the working directory, and inside it unless `trusted`), built now or
    /// earlier; `progress(stage, done, total)` hears about a build this
    /// call makes.
    pub(crate) fn get(
        &self,
        name: &str,
        spec: &str,
        trusted: bool,
        progress: &(dyn Fn(&str, u64, u64) + Sync),
    ) -> Result<Bound, StudioError> {
        let (src, checked, key) = self.resolve(name, spec, trusted)?;
        let cell = {
            let mut map = self.map.lock().unwrap_or_else(|e| e.into_inner());
            let now = self.clock.fetch_add(1, Ordering::Relaxed);
            if !map.contains_key(&key) && map.len() >= MAX_PARTS {
                let oldest = map
                    .iter()
                    .filter(|(_, e)| e.cell.get().is_some())
                    .min_by_key(|(_, e)| e.used)
                    .map(|(k, _)| k.clone());
                if let Some(k) = oldest {
                    map.remove(&k);
                }
            }
            let e = map.entry(key).or_insert_with(|| Entry {
                cell: Arc::new(OnceLock::new()),
                used: now,
            });
            e.used = now;
            e.cell.clone()
        };
        let cached = cell.get().is_some();
        let r = cell.get_or_init(|| {
            let limit = self.memory_limit;
            let full = checked.full.clone();
            let options = src.options.clone();
            match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                engine::build_part(&full, options, limit, progress)
            })) {
                Ok(Ok(p)) => Ok(Arc::new(p)),
                Ok(Err(e)) => Err(e.to_string()),
                Err(p) => Err(format!("internal error: {}", panic_message(&p))),
            }
        });
        match r {
            Ok(part) => Ok(Bound {
                name: name.to_string(),
                spec: spec.to_string(),
                part: part.clone(),
                cached,
                coarse: None,
            }),
            Err(e) => Err(StudioError::Request(format!("field {name}={spec}: {e}"))),
        }
    }
}
