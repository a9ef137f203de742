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
//!
//! A caller that makes its bytes in large blocks can also fill a staging
//! buffer in place ([`Direct::lend`], [`Direct::put`]): the buffer keeps
//! the unaligned rest of what came before at its start, the caller's block
//! follows, the aligned part goes to the disk and the new rest (less than
//! a page) is copied to the next buffer. No copy of the block at all.

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
/// written (16 MiB in all, more after larger lends).
const BUFFERS: usize = 4;

/// One aligned page.
#[derive(Clone, Copy)]
#[repr(C, align(4096))]
struct Page([u8; ALIGN]);

/// A staging buffer, a whole number of pages, aligned to [`ALIGN`].
pub(super) struct Stage(Vec<Page>);

impl Stage {
    /// A buffer of at least `bytes` bytes.
    fn new(bytes: usize) -> Stage {
        Stage(vec![Page([0; ALIGN]); bytes.div_ceil(ALIGN)])
    }

    fn capacity(&self) -> usize {
        self.0.len() * ALIGN
    }

    pub(super) fn bytes(&self) -> &[u8] {
        // SAFETY: `Page` is a plain byte array with no padding (its size
        // equals its alignment), so the pages are `len * ALIGN` initialised
        // bytes in one allocation, borrowed for as long as `self`.
        unsafe { std::slice::from_raw_parts(self.0.as_ptr().cast::<u8>(), self.0.len() * ALIGN) }
    }

    pub(super) fn bytes_mut(&mut self) -> &mut [u8] {
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
    /// The buffer being filled (absent while lent, and after `finish`).
    stage: Option<Stage>,
    /// Bytes in `stage`.
    fill: usize,
    /// File offset of `stage`'s first byte (a multiple of [`ALIGN`]).
    at: u64,
    queue: Option<SyncSender<Job>>,
    spare: Receiver<Stage>,
    /// Staging buffers made and not dropped.
    made: usize,
    /// Size of new staging buffers: [`STAGE`], or the largest lend.
    cap: usize,
    worker: Option<JoinHandle<io::Result<()>>>,
}

fn lent_out() -> io::Error {
    io::Error::other("a buffer of the file is lent out (write it back with put)")
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
            stage: Some(Stage::new(STAGE)),
            fill: 0,
            at: 0,
            queue: Some(queue),
            spare,
            made: 1,
            cap: STAGE,
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
            let stage = self.stage.as_mut().ok_or_else(lent_out)?;
            let room = stage.capacity() - self.fill;
            let n = room.min(data.len());
            stage.bytes_mut()[self.fill..self.fill + n].copy_from_slice(&data[..n]);
            self.fill += n;
            data = &data[n..];
            if n == room {
                self.send_aligned()?;
            }
        }
        Ok(())
    }

    /// Sends the whole pages of the buffer being filled to the writer; the
    /// rest (less than a page) moves to the start of a fresh buffer.
    fn send_aligned(&mut self) -> io::Result<()> {
        let aligned = self.fill / ALIGN * ALIGN;
        if aligned == 0 {
            return Ok(());
        }
        let mut next = self.spare_stage(self.cap)?;
        let stage = self.stage.take().ok_or_else(lent_out)?;
        let tail = self.fill - aligned;
        next.bytes_mut()[..tail].copy_from_slice(&stage.bytes()[aligned..self.fill]);
        self.stage = Some(next);
        self.send((self.at, stage, aligned))?;
        self.at += aligned as u64;
        self.fill = tail;
        Ok(())
    }

    /// A free staging buffer of at least `bytes`: one the writer gave back,
    /// a new one while fewer than [`BUFFERS`] exist, else the next one it
    /// gives back (one too small is dropped and made anew).
    fn spare_stage(&mut self, bytes: usize) -> io::Result<Stage> {
        let s = match self.spare.try_recv() {
            Ok(s) => s,
            Err(_) if self.made < BUFFERS => {
                self.made += 1;
                return Ok(Stage::new(self.cap.max(bytes)));
            }
            Err(_) => match self.spare.recv() {
                Ok(s) => s,
                Err(_) => return Err(self.stopped()),
            },
        };
        Ok(if s.capacity() < bytes {
            Stage::new(self.cap.max(bytes))
        } else {
            s
        })
    }

    /// A staging buffer holding, at its start, the bytes written and not
    /// yet sent (fewer than a page; their count is returned), with room
    /// for `len` more: filled by the caller and handed back to
    /// [`Direct::put`]. Nothing may be written meanwhile.
    pub(super) fn lend(&mut self, len: usize) -> io::Result<(Stage, usize)> {
        self.send_aligned()?;
        let need = self.fill + len;
        let stage = self.stage.take().ok_or_else(lent_out)?;
        if stage.capacity() >= need {
            return Ok((stage, self.fill));
        }
        self.cap = self.cap.max(need.div_ceil(ALIGN) * ALIGN);
        let mut big = Stage::new(self.cap);
        big.bytes_mut()[..self.fill].copy_from_slice(&stage.bytes()[..self.fill]);
        Ok((big, self.fill))
    }

    /// Takes back a buffer from [`Direct::lend`] with `filled` bytes in
    /// all (the ones it came with and the caller's) and sends its whole
    /// pages.
    pub(super) fn put(&mut self, stage: Stage, filled: usize) -> io::Result<()> {
        if self.stage.is_some() || filled > stage.capacity() {
            return Err(io::Error::other("put without a matching lend"));
        }
        self.stage = Some(stage);
        self.fill = filled;
        self.send_aligned()
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
        let stage = self.stage.take().ok_or_else(lent_out)?;
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
