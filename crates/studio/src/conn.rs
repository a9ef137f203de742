//! Whether the client of a request is still connected, so a job whose
//! client went away (a closed tab, a cancelled download) stops at its next
//! check instead of holding its slot to the time limit.
//!
//! tiny_http does not hand out the request's socket, so the connection is
//! looked up in the kernel's table of TCP sockets (`/proc/net/tcp`, `tcp6`)
//! by its two ends: once the peer closed it, the server's end is no longer
//! `ESTABLISHED` (it is `CLOSE_WAIT`, or gone after a reset). The server's
//! own half-close of the reading side (tiny_http shuts it after a
//! `Connection: close` request) leaves it `ESTABLISHED`, so it is not
//! mistaken for the client leaving. Elsewhere than Linux a client is never
//! seen to leave.

use std::net::SocketAddr;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// Least time between two looks at the socket table.
pub(crate) const POLL: Duration = Duration::from_millis(100);

/// Watches one request's connection.
#[derive(Debug)]
pub(crate) struct Watch {
    remote: SocketAddr,
    local_port: u16,
    t0: Instant,
    /// Milliseconds after `t0` of the last look.
    last: AtomicU64,
    gone: AtomicBool,
}

impl Watch {
    /// A watch of the connection from `remote` to the server's `local_port`;
    /// `None` where connections cannot be watched (no address, no socket
    /// table to read, or the table does not list this connection: then it
    /// is never taken for gone).
    pub(crate) fn new(remote: Option<SocketAddr>, local_port: u16) -> Option<Watch> {
        let remote = remote?;
        lookup(remote, local_port)??;
        Some(Watch {
            remote,
            local_port,
            t0: Instant::now(),
            last: AtomicU64::new(0),
            gone: AtomicBool::new(false),
        })
    }

    /// True once the client closed or reset the connection. Cheap to call
    /// often and from many threads: the table is read at most every
    /// [`POLL`].
    pub(crate) fn gone(&self) -> bool {
        if self.gone.load(Ordering::Relaxed) {
            return true;
        }
        let now = self.t0.elapsed().as_millis() as u64;
        let last = self.last.load(Ordering::Relaxed);
        if now < last + POLL.as_millis() as u64 {
            return false;
        }
        if self
            .last
            .compare_exchange(last, now, Ordering::Relaxed, Ordering::Relaxed)
            .is_err()
        {
            return false;
        }
        // Listed but no longer established, or no longer listed at all
        // (reset and removed); an unreadable table tells nothing.
        let gone = match lookup(self.remote, self.local_port) {
            Some(Some(st)) => st != ESTABLISHED,
            Some(None) => true,
            None => false,
        };
        if gone {
            self.gone.store(true, Ordering::Relaxed);
        }
        gone
    }
}

/// `TCP_ESTABLISHED` in the kernel's numbering.
const ESTABLISHED: u8 = 1;
/// `TCP_CLOSE`.
const CLOSED: u8 = 7;

/// The server-side state of the connection from `remote` to `local_port`:
/// `ESTABLISHED` if any matching entry is, else another entry's state;
/// `Some(None)` if none is listed, `None` if the table cannot be read.
fn lookup(remote: SocketAddr, local_port: u16) -> Option<Option<u8>> {
    if !cfg!(target_os = "linux") {
        return None;
    }
    let (table, rem) = match remote {
        SocketAddr::V4(a) => (
            "/proc/net/tcp",
            format!(
                "{:08X}:{:04X}",
                u32::from_ne_bytes(a.ip().octets()),
                a.port()
            ),
        ),
        SocketAddr::V6(a) => {
            let o = a.ip().octets();
            let mut s = String::with_capacity(40);
            for w in o.chunks(4) {
                s += &format!("{:08X}", u32::from_ne_bytes([w[0], w[1], w[2], w[3]]));
            }
            ("/proc/net/tcp6", format!("{s}:{:04X}", a.port()))
        }
    };
    let text = std::fs::read_to_string(table).ok()?;
    let port = format!(":{local_port:04X}");
    let mut found = None;
    for line in text.lines().skip(1) {
        let mut f = line.split_whitespace();
        let (Some(_), Some(local), Some(r), Some(st)) = (f.next(), f.next(), f.next(), f.next())
        else {
            continue;
        };
        if r == rem && local.ends_with(&port) {
            let st = u8::from_str_radix(st, 16).unwrap_or(CLOSED);
            if st == ESTABLISHED {
                return Some(Some(st));
            }
            found = Some(st);
        }
    }
    Some(found)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    #[test]
    #[cfg(target_os = "linux")]
    fn a_closed_peer_is_seen_and_an_open_one_is_not() {
        let l = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        let port = l.local_addr().unwrap().port();
        let mut c = std::net::TcpStream::connect(("127.0.0.1", port)).unwrap();
        let (s, remote) = l.accept().unwrap();
        let w = Watch::new(Some(remote), port).expect("the socket table lists the connection");
        // A connection the table does not list is not watched.
        let unknown: SocketAddr = "127.0.0.1:1".parse().unwrap();
        assert!(Watch::new(Some(unknown), port).is_none());
        assert!(!w.gone());
        // The server's own half-close of reading is not the client leaving.
        s.shutdown(std::net::Shutdown::Read).unwrap();
        std::thread::sleep(POLL + Duration::from_millis(20));
        assert!(!w.gone());
        c.write_all(b"x").unwrap();
        drop(c);
        let t = Instant::now();
        while !w.gone() {
            assert!(
                t.elapsed() < Duration::from_secs(2),
                "the close was not seen"
            );
            std::thread::sleep(Duration::from_millis(20));
        }
        drop(s);
    }
}
