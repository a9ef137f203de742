//! Data fields that models bind by name (`--field NAME=SOURCE` in a
//! comment, or the edit's `fields`): read from files under the working
//! directory, built once and kept for every session of the server.
//!
//! A part is keyed by its canonical path, its source options, and the
//! file's size and modification time, so an edit of the model (every
//! keystroke is one) reuses the built field, and a changed file is read
//! again. Two sessions asking for the same part at once build it once (the
//! second waits for the first). Builds are not stopped by newer edits, which
//! almost always need the same part; errors are kept too, until the file
//! changes. At most [`MAX_PARTS`] parts are kept, the least recently used
//! dropped first.

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

    /// The field of `spec` (`PATH[:key=value,...]`, the path relative to
    /// the working directory), built now or earlier; `progress(stage,
    /// done, total)` hears about a build this call makes.
    pub(crate) fn get(
        &self,
        name: &str,
        spec: &str,
        progress: &(dyn Fn(&str, u64, u64) + Sync),
    ) -> Result<Bound, StudioError> {
        let src = microfrep::load::Source::parse(spec)
            .map_err(|e| StudioError::Request(format!("field {name}={spec}: {e}")))?;
        let checked = paths::existing(&self.root, &src.path)
            .map_err(|e| StudioError::Request(format!("field {name}={spec}: {e}")))?;
        let meta = std::fs::metadata(&checked.full)
            .map_err(|e| StudioError::Request(format!("field {name}={spec}: {e}")))?;
        let key = Key {
            path: checked.full.clone(),
            options: format!("{:?}", src.options),
            len: meta.len(),
            modified: meta.modified().ok(),
        };
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
            }),
            Err(e) => Err(StudioError::Request(format!("field {name}={spec}: {e}"))),
        }
    }
}
