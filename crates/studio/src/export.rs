//! Downloads and files made on request: STL, slice stacks (a zip, or a
//! folder under the working directory), section images and renders.
//!
//! Each runs under a time limit (the stage limit of the configuration) and
//! a panic is caught; at most [`MAX_JOBS`] run at once. Files are written
//! into a staging folder and moved into place only when complete, so a
//! stopped job leaves nothing behind.

use crate::conn::Watch;
use crate::engine::{self, SliceFormat};
use crate::error::{io_at, StudioError};
use crate::paths;
use crate::server::Shared;
use crate::session::{guarded, Guard, Snapshot};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Export jobs running at once.
pub const MAX_JOBS: usize = 2;
/// Most pixels (width x height x layers) of a slice stack sent as a zip.
pub const MAX_ZIP_PIXELS: f64 = 2e9;
/// Largest export mesh resolution.
pub const MAX_RESOLUTION: usize = 2048;

static STAGING: AtomicU64 = AtomicU64::new(0);

/// Holds one of the [`MAX_JOBS`] export slots.
struct Slot<'a>(&'a Shared);

impl<'a> Slot<'a> {
    fn take(sh: &'a Shared) -> Result<Slot<'a>, StudioError> {
        if sh.jobs.fetch_add(1, Ordering::SeqCst) >= MAX_JOBS {
            sh.jobs.fetch_sub(1, Ordering::SeqCst);
            return Err(StudioError::Busy(format!(
                "the studio is busy: {MAX_JOBS} renders or exports are already running; \
                 retry when they finish"
            )));
        }
        Ok(Slot(sh))
    }
}

impl Drop for Slot<'_> {
    fn drop(&mut self) {
        self.0.jobs.fetch_sub(1, Ordering::SeqCst);
    }
}

/// A folder removed (with everything in it) when dropped.
struct Staging(PathBuf);

impl Staging {
    fn new(parent: &Path) -> Result<Staging, StudioError> {
        let n = STAGING.fetch_add(1, Ordering::SeqCst);
        let p = parent.join(format!(".studio-staging-{}-{n}", std::process::id()));
        std::fs::create_dir(&p).map_err(io_at(&p))?;
        Ok(Staging(p))
    }
}

impl Drop for Staging {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn limit_guard(sh: &Shared, client: Option<Watch>) -> Guard {
    Guard::new(None, sh.sessions.config().job_seconds).for_client(client)
}

/// A slice format by name: `png`, `png-aa`, `svg`, `cli`.
pub fn slice_format(s: &str) -> Result<SliceFormat, StudioError> {
    match s {
        "png" => Ok(SliceFormat::Png),
        "png-aa" => Ok(SliceFormat::PngAa),
        "svg" => Ok(SliceFormat::Svg),
        "cli" => Ok(SliceFormat::Cli),
        _ => Err(StudioError::Request(format!(
            "unknown slice format '{s}' (png, png-aa, svg, cli)"
        ))),
    }
}

/// Section image of the snapshot's model.
pub(crate) fn section(
    sh: &Shared,
    snap: &Snapshot,
    axis: usize,
    value: f64,
    w: usize,
    h: usize,
    client: Option<Watch>,
) -> Result<Vec<u8>, StudioError> {
    let g = limit_guard(sh, client);
    guarded(&g, |_| {
        Ok(engine::section_png(
            &snap.shape,
            axis,
            value,
            snap.bounds,
            w,
            h,
        )?)
    })
}

/// Ray-cast image (the view where WebGL is missing).
pub(crate) fn render(
    sh: &Shared,
    snap: &Snapshot,
    view: &str,
    cut: bool,
    w: usize,
    h: usize,
    client: Option<Watch>,
) -> Result<Vec<u8>, StudioError> {
    let _slot = Slot::take(sh)?;
    let g = limit_guard(sh, client);
    guarded(&g, |_| {
        Ok(engine::render_png(
            &snap.shape,
            view,
            cut,
            snap.bounds,
            w,
            h,
        )?)
    })
}

/// Binary STL: of a finished mesh at `resolution` (default the finest
/// finished one), else meshed now.
pub(crate) fn stl(
    sh: &Shared,
    snap: &Snapshot,
    resolution: Option<usize>,
    client: Option<Watch>,
) -> Result<Vec<u8>, StudioError> {
    let have = match resolution {
        None => snap.meshes.iter().max_by_key(|m| m.data.resolution),
        Some(r) => snap.meshes.iter().find(|m| m.data.resolution == r),
    };
    if let Some(m) = have {
        return Ok(engine::stl_bytes(&m.data)?);
    }
    let res = resolution
        .or(sh.sessions.config().levels.first().copied())
        .unwrap_or(64);
    if !(8..=MAX_RESOLUTION).contains(&res) {
        return Err(StudioError::Request(format!(
            "resolution {res} must be between 8 and {MAX_RESOLUTION}"
        )));
    }
    let _slot = Slot::take(sh)?;
    let g = limit_guard(sh, client);
    let limit = sh.sessions.config().memory_limit;
    let m = guarded(&g, |check| {
        Ok(engine::mesh(&snap.shape, snap.bounds, res, limit, check)?)
    })?;
    Ok(engine::stl_bytes(&m)?)
}

/// The facade's fill of a part ([`crate::fill`]), in an export slot under
/// the job time limit.
pub(crate) fn fill(
    sh: &Shared,
    req: &crate::fill::Request,
    snap: Option<&Snapshot>,
    client: Option<Watch>,
) -> Result<serde_json::Value, StudioError> {
    let _slot = Slot::take(sh)?;
    let g = limit_guard(sh, client);
    let limit = sh.sessions.config().memory_limit;
    guarded(&g, |check| {
        crate::fill::run(&sh.root, req, snap, limit, check)
    })
}

fn file_stem(file: &str) -> String {
    let base = file.rsplit('/').next().unwrap_or(file);
    let stem = base.strip_suffix(".hf").unwrap_or(base);
    let clean: String = stem
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "_-".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect();
    if clean.is_empty() {
        "model".into()
    } else {
        clean
    }
}

/// The slice stack as a zip: `NAME-slices/layer_00000.png`, ...,
/// `manifest.json` (or one `.cli` file).
pub(crate) fn slices_zip(
    sh: &Shared,
    snap: &Snapshot,
    layer: f64,
    pixel: f64,
    format: SliceFormat,
    client: Option<Watch>,
) -> Result<Vec<u8>, StudioError> {
    let (nx, ny, layers) = engine::slice_dims(snap.bounds, layer, pixel)?;
    let pixels = nx as f64 * ny as f64 * layers as f64;
    if pixels > MAX_ZIP_PIXELS {
        return Err(StudioError::Request(format!(
            "{nx} x {ny} pixels x {layers} layers is too much for one download; write the \
             stack to a folder instead"
        )));
    }
    let _slot = Slot::take(sh)?;
    let stage = Staging::new(&sh.scratch)?;
    let name = format!("{}-slices", file_stem(&snap.file));
    let out = stage.0.join(match format {
        SliceFormat::Cli => format!("{name}.cli"),
        _ => name.clone(),
    });
    let g = limit_guard(sh, client);
    guarded(&g, |check| {
        Ok(engine::write_slices(
            &snap.shape,
            snap.bounds,
            layer,
            pixel,
            format,
            &out,
            check,
        )?)
    })?;
    let mut files: Vec<(String, PathBuf)> = Vec::new();
    if out.is_dir() {
        let rd = std::fs::read_dir(&out).map_err(io_at(&out))?;
        for e in rd {
            let e = e.map_err(io_at(&out))?;
            files.push((
                format!("{name}/{}", e.file_name().to_string_lossy()),
                e.path(),
            ));
        }
    } else {
        files.push((format!("{name}.cli"), out.clone()));
    }
    files.sort();
    let mut zw = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    for (entry, path) in files {
        let bytes = std::fs::read(&path).map_err(io_at(&path))?;
        // PNGs are compressed already; text formats deflate well.
        let method = if entry.ends_with(".png") {
            zip::CompressionMethod::Stored
        } else {
            zip::CompressionMethod::Deflated
        };
        let opts = zip::write::SimpleFileOptions::default()
            .compression_method(method)
            .last_modified_time(zip::DateTime::default());
        zw.start_file(entry, opts)?;
        zw.write_all(&bytes).map_err(io_at(&path))?;
    }
    Ok(zw.finish()?.into_inner())
}

/// The folder under the working directory that slice stacks are written
/// into (made when first needed).
pub const OUTPUT_DIR: &str = "studio-output";

/// Checks an output name: a plain name (letters, digits, `.`, `_`, `-`;
/// at most 128; not starting with `.`), so that it names a new entry of
/// [`OUTPUT_DIR`] and nothing else.
pub(crate) fn output_name(name: &str) -> Result<(), StudioError> {
    let why = if name.is_empty() {
        Some("is empty")
    } else if name.contains('/') || name.contains('\\') {
        Some("has a path separator")
    } else if name.contains("..") {
        Some("contains '..'")
    } else if name.starts_with('.') {
        Some("starts with '.'")
    } else if name.len() > 128 {
        Some("is longer than 128 characters")
    } else if !name
        .chars()
        .all(|c| c.is_ascii_alphanumeric() || "._-".contains(c))
    {
        Some("has characters other than letters, digits, '.', '_' and '-'")
    } else {
        None
    };
    match why {
        Some(why) => Err(StudioError::Request(format!(
            "output name '{name}' refused: it {why}; give a plain folder name (e.g. \
             'slices'), which is made under {OUTPUT_DIR}/ in the working directory"
        ))),
        None => Ok(()),
    }
}

/// Writes the slice stack to `OUTPUT_DIR/name` under the working directory
/// (`name` a plain name, see [`output_name`]; the folder must not exist
/// yet); returns the path written, relative to the working directory, and
/// the layer count.
#[allow(clippy::too_many_arguments)]
pub(crate) fn slices_dir(
    sh: &Shared,
    snap: &Snapshot,
    layer: f64,
    pixel: f64,
    format: SliceFormat,
    name: &str,
    client: Option<Watch>,
) -> Result<(String, usize), StudioError> {
    output_name(name)?;
    let out = sh.root.join(OUTPUT_DIR);
    match std::fs::symlink_metadata(&out) {
        Ok(m) if m.is_dir() => {}
        Ok(_) => {
            return Err(StudioError::Path {
                path: OUTPUT_DIR.into(),
                reason: "is not a folder (a file or a link is in its place)".into(),
            })
        }
        Err(_) => std::fs::create_dir(&out).map_err(io_at(&out))?,
    }
    let target = paths::writable(&sh.root, &format!("{OUTPUT_DIR}/{name}"), true)?;
    let (_, _, layers) = engine::slice_dims(snap.bounds, layer, pixel)?;
    let _slot = Slot::take(sh)?;
    let parent = target
        .full
        .parent()
        .ok_or_else(|| StudioError::Request("no parent folder".into()))?;
    let stage = Staging::new(parent)?;
    let tmp = stage.0.join("stack");
    let g = limit_guard(sh, client);
    guarded(&g, |check| {
        Ok(engine::write_slices(
            &snap.shape,
            snap.bounds,
            layer,
            pixel,
            format,
            &tmp,
            check,
        )?)
    })?;
    std::fs::rename(&tmp, &target.full).map_err(io_at(&target.full))?;
    Ok((target.relative, layers))
}

/// Writes `bytes` to `path` through a temporary file in the same folder.
pub(crate) fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), StudioError> {
    let parent = path.parent().unwrap_or(Path::new("."));
    let stage = Staging::new(parent)?;
    let tmp = stage.0.join("file");
    std::fs::write(&tmp, bytes).map_err(io_at(&tmp))?;
    std::fs::rename(&tmp, path).map_err(io_at(path))
}
