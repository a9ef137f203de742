//! Large outputs written past the page cache (Linux `O_DIRECT`).
//!
//! A buffered `write` copies every byte into the page cache, and on a busy
//! machine that copy (fresh pages, memory-cgroup charges, dirty-page
//! throttling) cost from 0.07 to 1.4 s of CPU for a 315 MB mesh, with
//! `commit`'s sync then waiting for the whole file to reach the disk.
//! Written with `O_DIRECT` from aligned buffers, the disk reads the bytes
//! from those buffers itself (about 12 ms of CPU for the same file), a
//! thread of its own issues the writes while the caller goes on encoding,
//! and the final sync has only the metadata and the last page left.
//!
//! [`Direct`] takes over an empty file: it sets `O_DIRECT` (refused on file
//! systems without it: the caller stays buffered), fills 4 MiB staging
//! buffers aligned to 4 KiB, and hands each full one to its writer thread
//! (a few in flight, so memory stays bounded). [`Direct::finish`] writes
//! the aligned part of the last buffer the same way, then clears
//! `O_DIRECT` and writes the remaining bytes (less than a page) through the
//! page cache, so the file has exactly the bytes written, no padding. A
//! write refused with `EINVAL` (a device with blocks larger than 4 KiB)
//! clears `O_DIRECT` and is repeated buffered: slower, never wrong.

use std::fs::File;
use std::io::{self, Seek, SeekFrom};
use std::os::unix::fs::FileExt;
use std::os::unix::io::AsRawFd;
use std::sync::mpsc::{channel, sync_channel, Receiver, Sender, SyncSender};
use std::thread::JoinHandle;

/// Alignment of buffers, offsets and lengths for `O_DIRECT`: the largest
/// logical block size in common use.
const ALIGN: usize = 4096;
/// Bytes per staging buffer (one write).
const STAGE: usize = 4 << 20;
/// Staging buffers at most: one filling, the others queued or being
/// written (16 MiB in all).
const BUFFERS: usize = 4;

/// One aligned page.
#[derive(Clone, Copy)]
#[repr(C, align(4096))]
struct Page([u8; ALIGN]);

/// A staging buffer of [`STAGE`] bytes, aligned to [`ALIGN`].
struct Stage(Vec<Page>);

impl Stage {
    fn new() -> Stage {
        Stage(vec![Page([0; ALIGN]); STAGE / ALIGN])
    }

    fn bytes(&self) -> &[u8] {
        // SAFETY: `Page` is a plain byte array with no padding (its size
        // equals its alignment), so the pages are `len * ALIGN` initialised
        // bytes in one allocation, borrowed for as long as `self`.
        unsafe { std::slice::from_raw_parts(self.0.as_ptr().cast::<u8>(), self.0.len() * ALIGN) }
    }

    fn bytes_mut(&mut self) -> &mut [u8] {
        // SAFETY: as in `bytes`, and the borrow is unique.
        unsafe {
            std::slice::from_raw_parts_mut(self.0.as_mut_ptr().cast::<u8>(), self.0.len() * ALIGN)
        }
    }
}

/// A write for the writer thread: file offset, buffer, bytes of it.
type Job = (u64, Stage, usize);

/// Sets or clears `O_DIRECT` on `f`'s open file description.
fn set_direct(f: &File, on: bool) -> io::Result<()> {
    let fd = f.as_raw_fd();
    // SAFETY: fcntl on a descriptor `f` owns, with integer arguments only.
    let flags = unsafe { libc::fcntl(fd, libc::F_GETFL) };
    if flags < 0 {
        return Err(io::Error::last_os_error());
    }
    let want = if on {
        flags | libc::O_DIRECT
    } else {
        flags & !libc::O_DIRECT
    };
    // SAFETY: as above.
    if unsafe { libc::fcntl(fd, libc::F_SETFL, want) } < 0 {
        return Err(io::Error::last_os_error());
    }
    Ok(())
}

/// Writes `bytes` at `at`; a write refused for its alignment is repeated
/// without `O_DIRECT` (which then stays off).
fn write_at(f: &File, bytes: &[u8], at: u64) -> io::Result<()> {
    match f.write_all_at(bytes, at) {
        Err(e) if e.raw_os_error() == Some(libc::EINVAL) => {
            set_direct(f, false)?;
            f.write_all_at(bytes, at)
        }
        r => r,
    }
}

/// The writer thread: each job written in turn, its buffer sent back; the
/// first error ends it (the writer then sees its queue closed).
fn writer(f: File, jobs: Receiver<Job>, spare: Sender<Stage>) -> io::Result<()> {
    for (at, stage, len) in jobs {
        write_at(&f, &stage.bytes()[..len], at)?;
        // The writer may be gone (dropped after an error): nothing to do.
        let _ = spare.send(stage);
    }
    Ok(())
}

/// A file being written front to back with `O_DIRECT` by a thread of its
/// own.
pub(super) struct Direct {
    /// Present until [`Direct::finish`].
    file: Option<File>,
    /// The buffer being filled (absent only inside [`Direct::finish`]).
    stage: Option<Stage>,
    /// Bytes in `stage`.
    fill: usize,
    /// File offset of `stage`'s first byte (a multiple of [`STAGE`]).
    at: u64,
    queue: Option<SyncSender<Job>>,
    spare: Receiver<Stage>,
    /// Staging buffers made so far.
    made: usize,
    worker: Option<JoinHandle<io::Result<()>>>,
}

impl Direct {
    /// Takes over `file`, which must be empty with its position at 0;
    /// gives it back (unchanged but for its position) when the file system
    /// refuses `O_DIRECT` or no thread can be started.
    pub(super) fn start(file: File) -> Result<Direct, File> {
        let Ok(dup) = file.try_clone() else {
            return Err(file);
        };
        if set_direct(&file, true).is_err() {
            return Err(file);
        }
        let (queue, jobs) = sync_channel::<Job>(BUFFERS - 2);
        let (back, spare) = channel();
        let spawned = std::thread::Builder::new()
            .name("microfrep-write".into())
            .spawn(move || writer(dup, jobs, back));
        let worker = match spawned {
            Ok(w) => w,
            Err(_) => {
                let _ = set_direct(&file, false);
                return Err(file);
            }
        };
        Ok(Direct {
            file: Some(file),
            stage: Some(Stage::new()),
            fill: 0,
            at: 0,
            queue: Some(queue),
            spare,
            made: 1,
            worker: Some(worker),
        })
    }

    /// Bytes written so far.
    pub(super) fn len(&self) -> u64 {
        self.at + self.fill as u64
    }

    /// Appends `data`.
    pub(super) fn write_all(&mut self, mut data: &[u8]) -> io::Result<()> {
        while !data.is_empty() {
            let stage = self.stage.as_mut().expect("present outside finish");
            let n = (STAGE - self.fill).min(data.len());
            stage.bytes_mut()[self.fill..self.fill + n].copy_from_slice(&data[..n]);
            self.fill += n;
            data = &data[n..];
            if self.fill == STAGE {
                let next = self.spare_stage()?;
                let full = self.stage.replace(next).expect("present");
                self.send((self.at, full, STAGE))?;
                self.at += STAGE as u64;
                self.fill = 0;
            }
        }
        Ok(())
    }

    /// A free staging buffer: one the writer gave back, a new one while
    /// fewer than [`BUFFERS`] exist, else the next one it gives back.
    fn spare_stage(&mut self) -> io::Result<Stage> {
        if let Ok(s) = self.spare.try_recv() {
            return Ok(s);
        }
        if self.made < BUFFERS {
            self.made += 1;
            return Ok(Stage::new());
        }
        match self.spare.recv() {
            Ok(s) => Ok(s),
            Err(_) => Err(self.stopped()),
        }
    }

    fn send(&mut self, job: Job) -> io::Result<()> {
        let q = self.queue.as_ref().expect("present until finish");
        match q.send(job) {
            Ok(()) => Ok(()),
            Err(_) => Err(self.stopped()),
        }
    }

    /// Joins the writer thread; its error, or why it stopped.
    fn join(&mut self) -> io::Result<()> {
        self.queue = None;
        match self.worker.take().map(|w| w.join()) {
            None | Some(Ok(Ok(()))) => Ok(()),
            Some(Ok(Err(e))) => Err(e),
            Some(Err(_)) => Err(io::Error::other("the file writer thread panicked")),
        }
    }

    /// The error that stopped the writer thread.
    fn stopped(&mut self) -> io::Error {
        match self.join() {
            Err(e) => e,
            Ok(()) => io::Error::other("the file writer thread stopped"),
        }
    }

    /// Writes everything still staged, clears `O_DIRECT` and returns the
    /// file, positioned at its end (for buffered writing from there on).
    pub(super) fn finish(&mut self) -> io::Result<File> {
        let stage = self.stage.take().expect("finish is called once");
        let aligned = self.fill / ALIGN * ALIGN;
        let tail = stage.bytes()[aligned..self.fill].to_vec();
        let res = if aligned > 0 {
            self.send((self.at, stage, aligned))
        } else {
            Ok(())
        };
        let joined = self.join();
        res?;
        joined?;
        let mut file = self.file.take().expect("finish is called once");
        set_direct(&file, false)?;
        let end = self.len();
        file.write_all_at(&tail, self.at + aligned as u64)?;
        file.seek(SeekFrom::Start(end))?;
        Ok(file)
    }
}

impl Drop for Direct {
    fn drop(&mut self) {
        // Unfinished: the writer stops after the writes already queued (at
        // most a few buffers); joined so none lands after the file is gone.
        let _ = self.join();
    }
}

/// Whether the file system of `dir` accepts `O_DIRECT` (for tests).
#[cfg(test)]
pub(super) fn supported_in(dir: &std::path::Path) -> bool {
    let p = dir.join(format!(".microfrep-probe-{}", std::process::id()));
    let Ok(f) = File::create(&p) else {
        return false;
    };
    let ok = set_direct(&f, true).is_ok();
    drop(f);
    let _ = std::fs::remove_file(&p);
    ok
}
