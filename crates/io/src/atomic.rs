//! Outputs that appear whole or not at all.
//!
//! An [`AtomicFile`] or [`AtomicDir`] is written under a temporary name in
//! the target's directory (`.microfrep-PID-N.partial`: short, so a target
//! name of any allowed length works, and unique per process and output, so
//! two runs writing the same target never share a temporary) and renamed
//! onto the target by `commit`, which on POSIX file systems replaces it in
//! one step. Until then the temporary is listed in a process-wide registry:
//! dropping the writer, or [`cleanup_all`] (which the CLI calls from its
//! Ctrl-C and SIGTERM handler), removes it. Two runs writing one target at
//! the same time each rename their own complete file, so the target is
//! always one of the files a run reported.
//!
//! Inputs are protected: paths given to [`register_input`] (the model, a
//! mesh, a scan, and every file one of them names: a detached NRRD data
//! file, the members of a DICOM series, the files of a TIFF stack, a data
//! field's CSV) cannot be the target of an output of the same run, under
//! any name (the same file by another path, a symbolic or a hard link).
//!
//! A failed commit leaves nothing behind: the temporary and its scratch
//! files are removed. Several files committed as one output
//! ([`commit_all`]) either all replace their targets or leave every old
//! target as it was.
//!
//! A file that outgrows [`AtomicFile`]'s 4 MiB buffer before any seek or
//! flush goes on, on Linux, with direct I/O from a writer thread of its
//! own (`O_DIRECT`: the disk reads aligned staging buffers, no copy into
//! the page cache, and the bytes are on their way while the caller works,
//! so `commit`'s sync has little left to wait for); a seek or a flush
//! returns it to buffered writing, and a file system without direct I/O
//! keeps it buffered throughout. The bytes are the same either way. A
//! writer that makes its bytes in large blocks can fill the file's own
//! buffers in place ([`AtomicFile::lend`], [`AtomicFile::put`]): with
//! direct I/O they then reach the disk without a single copy.

use crate::{IoError, Result};
use std::fs::{self, File};
use std::io::{BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

#[cfg(target_os = "linux")]
mod direct;

/// Temporaries being written: (owner id, path, is a directory).
static LIVE: Mutex<Vec<(u64, PathBuf, bool)>> = Mutex::new(Vec::new());
/// This run's inputs: canonical path, and (device, inode) where known.
static INPUTS: Mutex<Vec<(PathBuf, Option<(u64, u64)>)>> = Mutex::new(Vec::new());
static SEQ: AtomicU64 = AtomicU64::new(1);
/// Set by [`cleanup_all`]: no new file is written into a temporary.
static SHUTTING_DOWN: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);
/// Files being written into temporary directories right now.
static IN_FLIGHT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

/// Held while one file is written into a temporary directory, so that
/// [`cleanup_all`] waits for it instead of racing it (a worker thread
/// that writes a layer after its directory was removed would leave a
/// half-made directory behind).
pub struct WriteGuard(());

impl Drop for WriteGuard {
    fn drop(&mut self) {
        IN_FLIGHT.fetch_sub(1, Ordering::SeqCst);
    }
}

/// A [`WriteGuard`] for one write, or an error once the process is
/// cleaning up to exit (the write must not happen).
pub fn begin_write(path: &Path) -> Result<WriteGuard> {
    IN_FLIGHT.fetch_add(1, Ordering::SeqCst);
    let g = WriteGuard(());
    if SHUTTING_DOWN.load(Ordering::SeqCst) {
        return Err(IoError::Io {
            path: path.to_path_buf(),
            source: std::io::Error::new(
                std::io::ErrorKind::Interrupted,
                "interrupted: the outputs are being removed",
            ),
        });
    }
    Ok(g)
}

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// Buffer of [`AtomicFile`]: large writes keep system calls rare.
const BUFFER: usize = 4 << 20;

/// Declares `path` an input of this run: no output may replace it.
pub fn register_input(path: &Path) {
    if let Ok(c) = fs::canonicalize(path) {
        let id = file_id(&c);
        let mut inputs = lock(&INPUTS);
        if !inputs.iter().any(|(p, _)| *p == c) {
            inputs.push((c, id));
        }
    }
}

/// Declares every path of `paths` an input (see [`register_input`]).
pub fn register_inputs<P: AsRef<Path>>(paths: impl IntoIterator<Item = P>) {
    for p in paths {
        register_input(p.as_ref());
    }
}

/// Whether `path` is a registered input (under any name).
pub fn is_input(path: &Path) -> bool {
    let Some(c) = canonical_target(path) else {
        return false;
    };
    let id = file_id(&c);
    // By inode only while the input still is that file: a removed input's
    // inode may be reused by a new file.
    lock(&INPUTS)
        .iter()
        .any(|(p, i)| *p == c || (id.is_some() && *i == id && file_id(p) == id))
}

/// The (device, inode) pair of an existing file: the same file whatever
/// path or hard link names it.
fn file_id(path: &Path) -> Option<(u64, u64)> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        fs::metadata(path).ok().map(|m| (m.dev(), m.ino()))
    }
    #[cfg(not(unix))]
    {
        let _ = path;
        None
    }
}

/// Removes every temporary still being written (for a signal handler: the
/// process is about to exit). Safe to call at any time.
pub fn cleanup_all() {
    // No new writes, then wait (briefly) for those under way, so no worker
    // thread recreates a file in a directory being removed.
    SHUTTING_DOWN.store(true, Ordering::SeqCst);
    let t = std::time::Instant::now();
    while IN_FLIGHT.load(Ordering::SeqCst) > 0 && t.elapsed() < std::time::Duration::from_secs(5) {
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    let live = std::mem::take(&mut *lock(&LIVE));
    for (_, p, dir) in live {
        let _ = if dir {
            fs::remove_dir_all(&p)
        } else {
            fs::remove_file(&p)
        };
    }
}

/// Number of temporaries currently registered (for tests).
pub fn live_temporaries() -> usize {
    lock(&LIVE).len()
}

/// The canonical form of a path that may not exist yet: its parent
/// canonicalised, plus its file name.
fn canonical_target(target: &Path) -> Option<PathBuf> {
    if let Ok(c) = fs::canonicalize(target) {
        return Some(c);
    }
    let parent = match target.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    Some(fs::canonicalize(parent).ok()?.join(target.file_name()?))
}

/// Refuses a target that is one of the registered inputs.
pub fn check_not_input(target: &Path) -> Result<()> {
    if is_input(target) {
        return Err(IoError::WouldOverwriteInput {
            path: target.to_path_buf(),
        });
    }
    Ok(())
}

/// A fresh temporary path in `target`'s directory, registered under `id`.
fn temp_for(target: &Path, id: u64, n: u64, dir: bool) -> Result<PathBuf> {
    if target.file_name().is_none() {
        return Err(IoError::NotAFileName {
            path: target.to_path_buf(),
        });
    }
    let parent = match target.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let t = parent.join(format!(
        ".microfrep-{}-{id}-{n}.partial",
        std::process::id()
    ));
    lock(&LIVE).push((id, t.clone(), dir));
    Ok(t)
}

fn unregister(id: u64) -> Vec<(PathBuf, bool)> {
    let mut live = lock(&LIVE);
    let (mine, rest): (Vec<_>, Vec<_>) = live.drain(..).partition(|(i, _, _)| *i == id);
    *live = rest;
    mine.into_iter().map(|(_, p, d)| (p, d)).collect()
}

fn remove_all(paths: &[(PathBuf, bool)]) {
    for (p, dir) in paths {
        let _ = if *dir {
            fs::remove_dir_all(p)
        } else {
            fs::remove_file(p)
        };
    }
}

/// A file written under a temporary name and renamed onto its target by
/// [`AtomicFile::commit`]; dropped uncommitted, it leaves nothing behind.
/// Writes go through a 4 MiB buffer; past it, on Linux, straight to the
/// disk from a writer thread (see the [module docs](self)).
pub struct AtomicFile {
    target: PathBuf,
    temp: PathBuf,
    file: Option<Out>,
    /// Whether the file may still switch to direct writes: nothing has
    /// reached it yet, and no seek or flush happened.
    may_go_direct: bool,
    /// A buffer is lent out ([`AtomicFile::lend`]): nothing may be written.
    lent: bool,
    /// The buffer lent out when writing buffered, kept for the next lend.
    plain: Vec<u8>,
    id: u64,
    scratch: u64,
    /// Renamed onto the target: nothing is left to remove.
    placed: bool,
}

/// Space for the next bytes of an [`AtomicFile`], lent by
/// [`AtomicFile::lend`] to be filled in place ([`Lent::bytes`]) and
/// handed back with [`AtomicFile::put`].
pub struct Lent {
    buf: LentBuf,
    /// Where the caller's bytes start in `buf`.
    start: usize,
    len: usize,
}

enum LentBuf {
    Plain(Vec<u8>),
    #[cfg(target_os = "linux")]
    Stage(direct::Stage),
}

impl Lent {
    /// The lent bytes, to be filled (their old contents are unspecified).
    pub fn bytes(&mut self) -> &mut [u8] {
        let (start, end) = (self.start, self.start + self.len);
        match &mut self.buf {
            LentBuf::Plain(v) => &mut v[start..end],
            #[cfg(target_os = "linux")]
            LentBuf::Stage(s) => &mut s.bytes_mut()[start..end],
        }
    }
}

/// Where an [`AtomicFile`]'s bytes go.
enum Out {
    Buffered(BufWriter<File>),
    #[cfg(target_os = "linux")]
    Direct(direct::Direct),
}

impl AtomicFile {
    /// Starts writing `target` (which is not touched until `commit`).
    pub fn create(target: &Path) -> Result<AtomicFile> {
        check_not_input(target)?;
        let id = SEQ.fetch_add(1, Ordering::Relaxed);
        let temp = temp_for(target, id, 0, false)?;
        let file = fs::OpenOptions::new()
            .write(true)
            .read(true)
            .create_new(true)
            .open(&temp);
        let file = match file {
            Ok(f) => f,
            Err(e) => {
                unregister(id);
                return Err(IoError::Io {
                    path: target.to_path_buf(),
                    source: e,
                });
            }
        };
        Ok(AtomicFile {
            target: target.to_path_buf(),
            temp,
            file: Some(Out::Buffered(BufWriter::with_capacity(BUFFER, file))),
            may_go_direct: cfg!(target_os = "linux"),
            lent: false,
            plain: Vec::new(),
            id,
            scratch: 0,
            placed: false,
        })
    }

    /// The target this file becomes.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Whether the bytes now go to the disk by direct I/O (see the
    /// [module docs](self)); false before the first 4 MiB, after a seek or
    /// a flush, off Linux and on file systems without direct I/O.
    pub fn writes_direct(&self) -> bool {
        match &self.file {
            #[cfg(target_os = "linux")]
            Some(Out::Direct(_)) => true,
            _ => false,
        }
    }

    /// A scratch file next to the temporary (for formats assembled from
    /// parts), removed with it; the caller creates and writes it.
    pub fn scratch_path(&mut self) -> PathBuf {
        self.scratch += 1;
        // `temp_for` only fails on a target without a file name, which
        // `create` has already excluded.
        temp_for(&self.target, self.id, self.scratch, false)
            .unwrap_or_else(|_| self.temp.with_extension(format!("s{}", self.scratch)))
    }

    /// An [`IoError::Io`] about the target.
    pub fn err(&self, e: std::io::Error) -> IoError {
        IoError::Io {
            path: self.target.clone(),
            source: e,
        }
    }

    /// The buffered writer, after finishing direct writes if they were
    /// under way (for seeks and flushes, and for a file system refusing
    /// direct I/O).
    fn buffered(&mut self) -> std::io::Result<&mut BufWriter<File>> {
        self.not_lent()?;
        self.may_go_direct = false;
        #[cfg(target_os = "linux")]
        if let Some(Out::Direct(d)) = &mut self.file {
            let f = d.finish()?;
            self.file = Some(Out::Buffered(BufWriter::with_capacity(BUFFER, f)));
        }
        match self.file.as_mut().expect("file is present until commit") {
            Out::Buffered(w) => Ok(w),
            #[cfg(target_os = "linux")]
            Out::Direct(_) => unreachable!("finished above"),
        }
    }

    /// Switches to direct writes when `more` bytes would overflow the
    /// buffer of a file nothing has reached yet.
    #[cfg(target_os = "linux")]
    fn maybe_go_direct(&mut self, more: usize) -> std::io::Result<()> {
        let Some(Out::Buffered(w)) = &self.file else {
            return Ok(());
        };
        if w.buffer().len() + more <= w.capacity() {
            return Ok(());
        }
        self.may_go_direct = false;
        let Some(Out::Buffered(w)) = self.file.take() else {
            unreachable!("matched above")
        };
        let (file, pending) = w.into_parts();
        let pending = pending.unwrap_or_else(|p| p.into_inner());
        // The buffer has never been flushed, so the file is empty.
        debug_assert_eq!((&file).stream_position().ok(), Some(0));
        match direct::Direct::start(file) {
            Ok(mut d) => {
                let r = d.write_all(&pending);
                self.file = Some(Out::Direct(d));
                r
            }
            Err(file) => {
                let mut w = BufWriter::with_capacity(BUFFER, file);
                let r = w.write_all(&pending);
                self.file = Some(Out::Buffered(w));
                r
            }
        }
    }

    fn not_lent(&self) -> std::io::Result<()> {
        if self.lent {
            return Err(std::io::Error::other(
                "a buffer of the file is lent out (write it back with put)",
            ));
        }
        Ok(())
    }

    /// Lends space for the next `len` bytes of the file, to be filled in
    /// place and handed back with [`AtomicFile::put`]: for large outputs
    /// made in blocks. With direct writes the block then goes to the disk
    /// from where it was made, without a copy; otherwise `put` writes it as
    /// `write_all` would. Nothing may be written until it is put back (a
    /// write, seek, flush or commit meanwhile fails).
    pub fn lend(&mut self, len: usize) -> std::io::Result<Lent> {
        self.not_lent()?;
        #[cfg(target_os = "linux")]
        if self.may_go_direct {
            self.maybe_go_direct(len)?;
        }
        let lent = match self.file.as_mut().expect("file is present until commit") {
            #[cfg(target_os = "linux")]
            Out::Direct(d) => {
                let (stage, start) = d.lend(len)?;
                Lent {
                    buf: LentBuf::Stage(stage),
                    start,
                    len,
                }
            }
            Out::Buffered(_) => {
                let mut v = std::mem::take(&mut self.plain);
                v.resize(len, 0);
                Lent {
                    buf: LentBuf::Plain(v),
                    start: 0,
                    len,
                }
            }
        };
        self.lent = true;
        Ok(lent)
    }

    /// Writes the bytes of a buffer from [`AtomicFile::lend`].
    pub fn put(&mut self, lent: Lent) -> std::io::Result<()> {
        if !self.lent {
            return Err(std::io::Error::other("put without a lend"));
        }
        self.lent = false;
        let filled = lent.start + lent.len;
        match (
            lent.buf,
            self.file.as_mut().expect("file is present until commit"),
        ) {
            (LentBuf::Plain(v), Out::Buffered(w)) => {
                let r = w.write_all(&v[..filled]);
                self.plain = v;
                r
            }
            #[cfg(target_os = "linux")]
            (LentBuf::Stage(s), Out::Direct(d)) => d.put(s, filled),
            #[cfg(target_os = "linux")]
            _ => Err(std::io::Error::other(
                "put of a buffer lent in another mode",
            )),
        }
    }

    /// Flushes, syncs and renames the file onto its target. If any step
    /// fails, the temporary is removed and the target is as it was.
    pub fn commit(mut self) -> Result<()> {
        self.seal()?;
        self.place()
    }

    /// Everything of a commit but the rename: the bytes are flushed and
    /// synced to the temporary. On an error the file stays uncommitted
    /// (dropping it removes the temporary).
    fn seal(&mut self) -> Result<()> {
        if let Err(e) = self.not_lent() {
            return Err(self.err(e));
        }
        let Some(out) = self.file.take() else {
            return Ok(());
        };
        let file = match out {
            Out::Buffered(w) => w.into_inner().map_err(|e| e.into_error()),
            #[cfg(target_os = "linux")]
            Out::Direct(mut d) => d.finish(),
        };
        file.and_then(|f| f.sync_all()).map_err(|e| self.err(e))
    }

    /// Renames the sealed temporary onto the target.
    fn place(&mut self) -> Result<()> {
        fs::rename(&self.temp, &self.target).map_err(|e| self.err(e))?;
        self.placed = true;
        // Renamed: only the scratch files are left to remove.
        let rest: Vec<_> = unregister(self.id)
            .into_iter()
            .filter(|(p, _)| *p != self.temp)
            .collect();
        remove_all(&rest);
        Ok(())
    }
}

impl Write for AtomicFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.write_all(buf)?;
        Ok(buf.len())
    }
    fn write_all(&mut self, buf: &[u8]) -> std::io::Result<()> {
        self.not_lent()?;
        #[cfg(target_os = "linux")]
        if self.may_go_direct {
            self.maybe_go_direct(buf.len())?;
        }
        match self.file.as_mut().expect("file is present until commit") {
            Out::Buffered(w) => w.write_all(buf),
            #[cfg(target_os = "linux")]
            Out::Direct(d) => d.write_all(buf),
        }
    }
    /// Puts every byte written so far in the file (ending direct writes).
    fn flush(&mut self) -> std::io::Result<()> {
        self.buffered()?.flush()
    }
}

impl Seek for AtomicFile {
    fn seek(&mut self, pos: SeekFrom) -> std::io::Result<u64> {
        self.buffered()?.seek(pos)
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        // Dropping the writer first: a direct writer's thread is joined
        // before its file is removed.
        drop(self.file.take());
        if !self.placed {
            remove_all(&unregister(self.id));
        }
    }
}

/// A directory written under a temporary name and renamed onto its target
/// by [`AtomicDir::commit`]; the target must not exist. Dropped
/// uncommitted, it leaves nothing behind.
pub struct AtomicDir {
    target: PathBuf,
    temp: PathBuf,
    id: u64,
    done: bool,
}

impl AtomicDir {
    /// Starts writing the directory `target`.
    pub fn create(target: &Path) -> Result<AtomicDir> {
        check_not_input(target)?;
        if target.exists() {
            return Err(IoError::Exists {
                path: target.to_path_buf(),
            });
        }
        let id = SEQ.fetch_add(1, Ordering::Relaxed);
        let temp = temp_for(target, id, 0, true)?;
        if let Err(e) = fs::create_dir(&temp) {
            unregister(id);
            return Err(IoError::Io {
                path: target.to_path_buf(),
                source: e,
            });
        }
        Ok(AtomicDir {
            target: target.to_path_buf(),
            temp,
            id,
            done: false,
        })
    }

    /// Where to write the directory's files meanwhile.
    pub fn path(&self) -> &Path {
        &self.temp
    }

    /// The target this directory becomes.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Writes one file of the directory.
    pub fn write(&self, name: &str, bytes: &[u8]) -> Result<()> {
        let _g = begin_write(&self.target.join(name))?;
        fs::write(self.temp.join(name), bytes).map_err(|e| IoError::Io {
            path: self.target.join(name),
            source: e,
        })
    }

    /// Renames the directory onto its target (which must still not exist).
    pub fn commit(mut self) -> Result<()> {
        if self.target.exists() {
            return Err(IoError::Exists {
                path: self.target.clone(),
            });
        }
        fs::rename(&self.temp, &self.target).map_err(|e| IoError::Io {
            path: self.target.clone(),
            source: e,
        })?;
        self.done = true;
        unregister(self.id);
        Ok(())
    }
}

impl Drop for AtomicDir {
    fn drop(&mut self) {
        if !self.done {
            remove_all(&unregister(self.id));
        }
    }
}

/// Writes `bytes` to `target` atomically.
pub fn write_file(target: &Path, bytes: &[u8]) -> Result<()> {
    let mut f = AtomicFile::create(target)?;
    f.write_all(bytes).map_err(|e| f.err(e))?;
    f.commit()
}

/// Commits several files as one output (a `.raw` and its `.json` sidecar):
/// either every target is replaced by its new file, or every target is
/// left as it was (an old file kept, a missing one still missing) and no
/// temporary remains.
///
/// All files are synced first, and every target is checked to be a file
/// or absent, so most failures happen before anything is renamed. Each
/// existing target is then kept under a backup name (a hard link, so it
/// never goes missing; where the file system has none, a rename) until
/// all renames have succeeded; if one fails, the targets already replaced
/// get their backups back.
pub fn commit_all(mut files: Vec<AtomicFile>) -> Result<()> {
    for f in &mut files {
        f.seal()?;
    }
    for f in &files {
        if fs::symlink_metadata(&f.target).is_ok_and(|m| m.is_dir()) {
            return Err(f.err(std::io::Error::other(
                "the target is a directory; nothing was replaced",
            )));
        }
    }
    // (backup path, whether the target was moved rather than linked).
    let mut backups: Vec<Option<(PathBuf, bool)>> = Vec::with_capacity(files.len());
    let restore = |files: &[AtomicFile], backups: &[Option<(PathBuf, bool)>], placed: usize| {
        for (k, (f, b)) in files.iter().zip(backups).enumerate() {
            match b {
                Some((b, moved)) if k < placed || *moved => {
                    if fs::rename(b, &f.target).is_err() {
                        // The backup is now the only copy of the old file:
                        // it stays, whatever happens to the writer.
                        lock(&LIVE).retain(|(_, p, _)| p != b);
                    }
                }
                Some((b, _)) => {
                    let _ = fs::remove_file(b);
                }
                None if k < placed => {
                    let _ = fs::remove_file(&f.target);
                }
                None => {}
            }
        }
    };
    for f in &mut files {
        if fs::symlink_metadata(&f.target).is_err() {
            backups.push(None);
            continue;
        }
        f.scratch += 1;
        let b = temp_for(&f.target, f.id, f.scratch, false)?;
        let kept = match fs::hard_link(&f.target, &b) {
            Ok(()) => Ok(false),
            Err(_) => fs::rename(&f.target, &b).map(|_| true),
        };
        match kept {
            Ok(moved) => backups.push(Some((b, moved))),
            Err(e) => {
                restore(&files, &backups, 0);
                return Err(files[backups.len()].err(e));
            }
        }
    }
    for k in 0..files.len() {
        if let Err(e) = fs::rename(&files[k].temp, &files[k].target) {
            restore(&files, &backups, k);
            return Err(files[k].err(e));
        }
    }
    // All replaced: the backups go (they are scratch files of their
    // writers), the temporaries are now the targets.
    for f in &mut files {
        f.placed = true;
        let rest: Vec<_> = unregister(f.id)
            .into_iter()
            .filter(|(p, _)| *p != f.temp)
            .collect();
        remove_all(&rest);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("mf-io-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        fs::create_dir_all(&d).unwrap();
        d
    }

    fn entries(d: &Path) -> Vec<String> {
        let mut v: Vec<String> = fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn dropped_outputs_leave_nothing_and_committed_ones_appear_whole() {
        let d = dir("drop");
        let t = d.join("a.bin");
        {
            let mut f = AtomicFile::create(&t).unwrap();
            f.write_all(&[1; 1000]).unwrap();
            let s = f.scratch_path();
            fs::write(&s, b"scratch").unwrap();
            assert_eq!(entries(&d).len(), 2);
        }
        assert!(entries(&d).is_empty(), "{:?}", entries(&d));
        let mut f = AtomicFile::create(&t).unwrap();
        f.write_all(b"done").unwrap();
        f.commit().unwrap();
        assert_eq!(entries(&d), vec!["a.bin".to_string()]);
        assert_eq!(fs::read(&t).unwrap(), b"done");
        let sub = d.join("stack");
        {
            let a = AtomicDir::create(&sub).unwrap();
            a.write("x.png", b"x").unwrap();
        }
        assert_eq!(entries(&d), vec!["a.bin".to_string()]);
        let a = AtomicDir::create(&sub).unwrap();
        a.write("x.png", b"x").unwrap();
        a.commit().unwrap();
        assert_eq!(entries(&sub), vec!["x.png".to_string()]);
        assert!(matches!(
            AtomicDir::create(&sub),
            Err(IoError::Exists { .. })
        ));
        fs::remove_dir_all(&d).unwrap();
    }

    /// Bytes of a pattern with no period near a page or a staging buffer.
    fn pattern(n: usize) -> Vec<u8> {
        (0..n as u64)
            .map(|i| (i.wrapping_mul(2654435761) >> 13) as u8)
            .collect()
    }

    /// Whether this platform and file system should take the direct path.
    fn expect_direct(d: &Path) -> bool {
        #[cfg(target_os = "linux")]
        return direct::supported_in(d);
        #[cfg(not(target_os = "linux"))]
        {
            let _ = d;
            false
        }
    }

    #[test]
    fn large_files_written_direct_have_exactly_the_bytes_written() {
        let d = dir("direct");
        // Sizes around the buffer, a staging buffer and a page, so the
        // switch, full and partial stages and the unaligned tail all occur.
        for (k, n) in [(4 << 20) + 1, (12 << 20) + 4096, (21 << 20) + 777, 3 << 20]
            .into_iter()
            .enumerate()
        {
            let want = pattern(n);
            let t = d.join(format!("m{k}.bin"));
            let mut f = AtomicFile::create(&t).unwrap();
            // Writes of odd sizes, some larger than the buffer.
            let mut at = 0;
            let mut step = 1000;
            while at < n {
                let e = (at + step).min(n);
                f.write_all(&want[at..e]).unwrap();
                at = e;
                step = step * 3 % 9_000_001 + 1;
            }
            assert_eq!(f.writes_direct(), n > BUFFER && expect_direct(&d), "{n}");
            // Not visible before the commit, whatever the path.
            assert!(!t.exists());
            f.commit().unwrap();
            assert!(fs::read(&t).unwrap() == want, "size {n}");
        }
        assert_eq!(entries(&d).len(), 4, "{:?}", entries(&d));
        fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn a_seek_after_direct_writes_patches_the_file_and_a_drop_leaves_nothing() {
        let d = dir("direct-seek");
        let t = d.join("s.stl");
        let mut want = pattern((9 << 20) + 50);
        let mut f = AtomicFile::create(&t).unwrap();
        f.write_all(&want).unwrap();
        assert_eq!(f.writes_direct(), expect_direct(&d));
        // Patch a count near the start (as the streaming STL writer does),
        // then go on appending.
        f.seek(SeekFrom::Start(80)).unwrap();
        f.write_all(&[1, 2, 3, 4]).unwrap();
        assert!(!f.writes_direct());
        f.seek(SeekFrom::End(0)).unwrap();
        f.write_all(b"tail").unwrap();
        want[80..84].copy_from_slice(&[1, 2, 3, 4]);
        want.extend_from_slice(b"tail");
        f.commit().unwrap();
        assert!(fs::read(&t).unwrap() == want);
        // Dropped in the middle of direct writes: no temporary remains and
        // the committed file is untouched.
        {
            let mut f = AtomicFile::create(&t).unwrap();
            f.write_all(&pattern(11 << 20)).unwrap();
            assert_eq!(f.writes_direct(), expect_direct(&d));
            assert_eq!(entries(&d).len(), 2);
        }
        assert_eq!(entries(&d), vec!["s.stl".to_string()]);
        assert!(fs::read(&t).unwrap() == want);
        fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn blocks_filled_in_place_land_where_written_ones_would() {
        let d = dir("lend");
        let n = (30 << 20) + 1234;
        let want = pattern(n);
        let t = d.join("l.stl");
        let mut f = AtomicFile::create(&t).unwrap();
        // A header, then blocks lent and written alternately, small and
        // larger than a staging buffer, before and after the switch to
        // direct writes.
        let sizes = [84, 1000, 3 << 20, 50, 13 << 20, 4096, 7 << 20, 999_999];
        let (mut at, mut k) = (0, 0);
        while at < n {
            let e = (at + sizes[k % sizes.len()]).min(n);
            if k % 2 == 0 {
                f.write_all(&want[at..e]).unwrap();
            } else {
                let mut l = f.lend(e - at).unwrap();
                assert_eq!(l.bytes().len(), e - at);
                // Nothing else while it is out.
                assert!(f.write_all(b"x").is_err());
                assert!(f.lend(1).is_err());
                assert!(f.flush().is_err());
                l.bytes().copy_from_slice(&want[at..e]);
                f.put(l).unwrap();
            }
            at = e;
            k += 1;
        }
        assert_eq!(f.writes_direct(), expect_direct(&d));
        assert!(f
            .put(Lent {
                buf: LentBuf::Plain(Vec::new()),
                start: 0,
                len: 0
            })
            .is_err());
        f.commit().unwrap();
        assert!(fs::read(&t).unwrap() == want);
        // A file committed with a buffer still lent out fails and leaves
        // nothing new.
        let u = d.join("u.stl");
        let mut f = AtomicFile::create(&u).unwrap();
        f.write_all(&pattern(5 << 20)).unwrap();
        let _l = f.lend(100).unwrap();
        assert!(f.commit().is_err());
        assert_eq!(entries(&d), vec!["l.stl".to_string()]);
        fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn two_writers_of_one_target_use_separate_temporaries() {
        let d = dir("two");
        let t = d.join("m.stl");
        let mut a = AtomicFile::create(&t).unwrap();
        let mut b = AtomicFile::create(&t).unwrap();
        a.write_all(b"first").unwrap();
        b.write_all(b"second").unwrap();
        b.commit().unwrap();
        assert_eq!(fs::read(&t).unwrap(), b"second");
        a.commit().unwrap();
        assert_eq!(fs::read(&t).unwrap(), b"first");
        assert_eq!(entries(&d), vec!["m.stl".to_string()]);
        fs::remove_dir_all(&d).unwrap();
    }

    /// What a directory holds: names and contents of its plain files,
    /// `/` for a subdirectory.
    fn contents(d: &Path) -> Vec<(String, Vec<u8>)> {
        let mut v: Vec<_> = fs::read_dir(d)
            .unwrap()
            .map(|e| {
                let e = e.unwrap();
                let name = e.file_name().to_string_lossy().into_owned();
                let body = if e.path().is_dir() {
                    b"/".to_vec()
                } else {
                    fs::read(e.path()).unwrap()
                };
                (name, body)
            })
            .collect();
        v.sort();
        v
    }

    #[test]
    fn a_failed_commit_leaves_no_temporary() {
        // The case: the target is a directory, so the rename fails
        // after everything was written; also with scratch files and past
        // the buffer (direct writes).
        let d = dir("failed-commit");
        for (k, n) in [10usize, (5 << 20) + 3].into_iter().enumerate() {
            let t = d.join(format!("o{k}.stl"));
            fs::create_dir(&t).unwrap();
            fs::write(t.join("inside"), b"keep").unwrap();
            let mut f = AtomicFile::create(&t).unwrap();
            f.write_all(&pattern(n)).unwrap();
            fs::write(f.scratch_path(), b"scratch").unwrap();
            assert!(f.commit().is_err());
            assert_eq!(entries(&d).len(), k + 1, "{:?}", entries(&d));
            assert_eq!(fs::read(t.join("inside")).unwrap(), b"keep");
        }
        fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn a_multi_file_output_replaces_all_its_targets_or_none() {
        // The case first: an old x.raw, x.json a directory.
        let d = dir("commit-all");
        let raw = d.join("x.raw");
        fs::write(&raw, b"precious").unwrap();
        fs::create_dir(d.join("x.json")).unwrap();
        let mut a = AtomicFile::create(&raw).unwrap();
        a.write_all(b"new raw").unwrap();
        let mut b = AtomicFile::create(&d.join("x.json")).unwrap();
        b.write_all(b"{}").unwrap();
        assert!(commit_all(vec![a, b]).is_err());
        assert_eq!(fs::read(&raw).unwrap(), b"precious");
        assert_eq!(entries(&d), vec!["x.json".to_string(), "x.raw".to_string()]);
        fs::remove_dir_all(&d).unwrap();
        // Every mix of 1 to 4 targets, each absent, an old file or a
        // directory (whose rename fails), in every order: a directory
        // anywhere leaves everything as it was, else all are new.
        for n in 1..=4usize {
            for mix in 0..3usize.pow(n as u32) {
                let d = dir(&format!("commit-all-{n}-{mix}"));
                let kinds: Vec<usize> = (0..n).map(|k| mix / 3usize.pow(k as u32) % 3).collect();
                let targets: Vec<PathBuf> = (0..n).map(|k| d.join(format!("t{k}.out"))).collect();
                for (t, kind) in targets.iter().zip(&kinds) {
                    match kind {
                        1 => fs::write(t, format!("old {}", t.display())).unwrap(),
                        2 => fs::create_dir(t).unwrap(),
                        _ => {}
                    }
                }
                let before = contents(&d);
                let files: Vec<AtomicFile> = targets
                    .iter()
                    .map(|t| {
                        let mut f = AtomicFile::create(t).unwrap();
                        f.write_all(format!("new {}", t.display()).as_bytes())
                            .unwrap();
                        f
                    })
                    .collect();
                let r = commit_all(files);
                if kinds.contains(&2) {
                    assert!(r.is_err(), "{kinds:?}");
                    assert_eq!(contents(&d), before, "{kinds:?}");
                } else {
                    r.unwrap();
                    for t in &targets {
                        assert_eq!(
                            fs::read(t).unwrap(),
                            format!("new {}", t.display()).as_bytes()
                        );
                    }
                    assert_eq!(entries(&d).len(), n, "{kinds:?}: {:?}", entries(&d));
                }
                fs::remove_dir_all(&d).unwrap();
            }
        }
    }

    #[test]
    fn a_rename_failing_midway_restores_the_targets_already_replaced() {
        // A failure the checks before the renames cannot see: the second
        // temporary disappears (as on a file system that loses it), so its
        // rename fails after the first target was replaced.
        let d = dir("commit-all-midway");
        let (t0, t1) = (d.join("a.raw"), d.join("a.json"));
        fs::write(&t0, b"old raw").unwrap();
        fs::write(&t1, b"old json").unwrap();
        let mut a = AtomicFile::create(&t0).unwrap();
        a.write_all(b"new raw").unwrap();
        let mut b = AtomicFile::create(&t1).unwrap();
        b.write_all(b"new json").unwrap();
        b.seal().unwrap();
        fs::remove_file(&b.temp).unwrap();
        assert!(commit_all(vec![a, b]).is_err());
        assert_eq!(fs::read(&t0).unwrap(), b"old raw");
        assert_eq!(fs::read(&t1).unwrap(), b"old json");
        assert_eq!(entries(&d).len(), 2, "{:?}", entries(&d));
        fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn inputs_are_protected_under_any_name() {
        let d = dir("input-names");
        let data = d.join("ball.raw");
        fs::write(&data, b"scan").unwrap();
        register_inputs([&data]);
        std::os::unix::fs::symlink(&data, d.join("sym.raw")).unwrap();
        fs::hard_link(&data, d.join("hard.raw")).unwrap();
        for name in ["ball.raw", "sym.raw", "hard.raw", "./ball.raw"] {
            let e = AtomicFile::create(&d.join(name)).err();
            assert!(
                matches!(e, Some(IoError::WouldOverwriteInput { .. })),
                "{name}"
            );
        }
        let e = AtomicDir::create(&data).err();
        assert!(matches!(e, Some(IoError::WouldOverwriteInput { .. })));
        assert_eq!(fs::read(&data).unwrap(), b"scan");
        // Another file is fine.
        write_file(&d.join("other.raw"), b"x").unwrap();
        fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn long_names_work_and_inputs_are_protected() {
        let d = dir("long");
        // 255 bytes: the longest name most file systems allow.
        let t = d.join("n".repeat(251) + ".stl");
        write_file(&t, b"ok").unwrap();
        assert_eq!(fs::read(&t).unwrap(), b"ok");
        let model = d.join("model.hf");
        fs::write(&model, b"model").unwrap();
        register_input(&model);
        let e = AtomicFile::create(&d.join(".").join("model.hf"))
            .err()
            .unwrap();
        assert!(matches!(e, IoError::WouldOverwriteInput { .. }), "{e}");
        assert_eq!(fs::read(&model).unwrap(), b"model");
        fs::remove_dir_all(&d).unwrap();
    }
}
