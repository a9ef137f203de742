//! Reading with a bound on what is actually read, not on what `stat`
//! says: a device (`/dev/zero`), a pipe or a file that grows reports a size
//! of 0 or less than it delivers, so the size check of a reader is only a
//! first, early refusal, and the read itself must stop at the limit too.

use std::io::{BufRead, Read};
use std::path::Path;

/// The error for input beyond `limit` bytes.
fn too_long(limit: u64, what: &str) -> std::io::Error {
    std::io::Error::new(
        std::io::ErrorKind::InvalidData,
        format!(
            "{what} goes on past {limit} bytes, the most this reader takes \
             (a device or a pipe that does not end?)"
        ),
    )
}

/// All of `r`, refused with an error once it passes `limit` bytes.
pub fn read_all(r: impl Read, limit: u64) -> std::io::Result<Vec<u8>> {
    let mut data = Vec::new();
    r.take(limit.saturating_add(1)).read_to_end(&mut data)?;
    if data.len() as u64 > limit {
        return Err(too_long(limit, "the input"));
    }
    Ok(data)
}

/// The file at `path`, refused once it passes `limit` bytes (whatever
/// its size on disk says), and refused at once when its size on disk
/// already does.
pub fn read_file(path: &Path, limit: u64) -> std::io::Result<Vec<u8>> {
    let f = std::fs::File::open(path)?;
    if f.metadata()?.len() > limit {
        return Err(too_long(limit, "the file"));
    }
    read_all(f, limit)
}

/// [`read_file`] as UTF-8 text.
pub fn read_file_to_string(path: &Path, limit: u64) -> std::io::Result<String> {
    String::from_utf8(read_file(path, limit)?)
        .map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidData, e.utf8_error()))
}

/// Reads one line (through `\n`, which is kept) into `buf`, refusing a
/// line longer than `max` bytes; `Ok(0)` at the end of the input.
pub fn read_line(r: &mut impl BufRead, buf: &mut Vec<u8>, max: usize) -> std::io::Result<usize> {
    let n = r
        .take((max as u64).saturating_add(1))
        .read_until(b'\n', buf)?;
    if n > max && buf.last() != Some(&b'\n') {
        return Err(too_long(max as u64, "a line"));
    }
    Ok(n)
}

/// Skips one line without keeping it (no memory however long it is), but
/// refuses one longer than `max` bytes; returns the bytes skipped, 0 at the
/// end of the input (so a caller counting lines stops there instead of
/// waiting for lines that never come).
pub fn skip_line(r: &mut impl BufRead, max: u64) -> std::io::Result<u64> {
    let mut n = 0u64;
    loop {
        let (done, used) = {
            let b = r.fill_buf()?;
            if b.is_empty() {
                return Ok(n);
            }
            match b.iter().position(|&c| c == b'\n') {
                Some(i) => (true, i + 1),
                None => (false, b.len()),
            }
        };
        r.consume(used);
        n += used as u64;
        // The line end itself is not counted against `max`.
        if n - u64::from(done) > max {
            return Err(too_long(max, "a line"));
        }
        if done {
            return Ok(n);
        }
    }
}

/// The lines of `r` as strings without their line ends (`\n` or `\r\n`),
/// each at most `max` bytes before its `\n` (longer ones are an error), and at most `max_total` bytes in all,
/// line ends included (more is an error, after which the iterator ends).
pub fn lines<R: BufRead>(r: R, max: usize, max_total: u64) -> Lines<R> {
    Lines {
        r,
        max,
        total: max_total,
        left: max_total,
        done: false,
    }
}

/// The iterator of [`lines`].
pub struct Lines<R> {
    r: R,
    max: usize,
    total: u64,
    left: u64,
    done: bool,
}

impl<R: BufRead> Lines<R> {
    fn fail(&mut self, e: std::io::Error) -> Option<std::io::Result<String>> {
        self.done = true;
        Some(Err(e))
    }
}

impl<R: BufRead> Iterator for Lines<R> {
    type Item = std::io::Result<String>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.done {
            return None;
        }
        if self.left == 0 {
            // The budget is spent: the input must end here.
            self.done = true;
            return match self.r.fill_buf() {
                Ok([]) => None,
                Ok(_) => Some(Err(too_long(self.total, "the input"))),
                Err(e) => Some(Err(e)),
            };
        }
        let mut buf = Vec::new();
        // A line may not take more than what is left of the total, its
        // line end included: `read_line` allows `max` bytes plus the end,
        // which the check of `n` below then refuses.
        let max = self.max.min(self.left.min(usize::MAX as u64) as usize);
        let n = match read_line(&mut self.r, &mut buf, max) {
            Ok(0) => {
                self.done = true;
                return None;
            }
            Ok(n) => n as u64,
            Err(e) => {
                let e = if max < self.max {
                    too_long(self.total, "the input")
                } else {
                    e
                };
                return self.fail(e);
            }
        };
        if n > self.left {
            return self.fail(too_long(self.total, "the input"));
        }
        self.left -= n;
        if buf.last() == Some(&b'\n') {
            buf.pop();
            if buf.last() == Some(&b'\r') {
                buf.pop();
            }
        }
        match String::from_utf8(buf) {
            Ok(s) => Some(Ok(s)),
            Err(e) => self.fail(std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                e.utf8_error(),
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::{BufReader, Cursor};

    /// Endless input, like /dev/zero or `yes`.
    struct Endless(u8);
    impl Read for Endless {
        fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
            buf.fill(self.0);
            Ok(buf.len())
        }
    }

    #[test]
    fn endless_inputs_stop_at_the_limit() {
        let e = read_all(Endless(0), 1 << 20).unwrap_err();
        assert!(e.to_string().contains("1048576 bytes"), "{e}");
        assert_eq!(read_all(Cursor::new(vec![7u8; 10]), 10).unwrap().len(), 10);
        assert!(read_all(Cursor::new(vec![7u8; 11]), 10).is_err());
        let mut r = BufReader::new(Endless(b'a'));
        let mut buf = Vec::new();
        assert!(read_line(&mut r, &mut buf, 4096).is_err());
        // Newlines forever: bounded in total.
        let mut n = 0;
        for l in lines(BufReader::new(Endless(b'\n')), 100, 1 << 16) {
            match l {
                Ok(s) => assert!(s.is_empty()),
                Err(e) => {
                    assert!(e.to_string().contains("65536"), "{e}");
                    break;
                }
            }
            n += 1;
        }
        assert_eq!(n, 1 << 16);
        let got: Vec<String> = lines(Cursor::new("a b\r\nc\n\nd"), 10, 100)
            .collect::<Result<_, _>>()
            .unwrap();
        assert_eq!(got, ["a b", "c", "", "d"]);
        assert!(lines(Cursor::new("abcdefghijkl\n"), 10, 100)
            .next()
            .unwrap()
            .is_err());
    }

    #[test]
    fn devices_are_bounded_by_what_they_deliver() {
        let z = Path::new("/dev/zero");
        if z.exists() {
            let e = read_file(z, 1 << 16).unwrap_err();
            assert!(e.to_string().contains("65536"), "{e}");
        }
    }

    #[test]
    fn skipping_lines_stops_at_the_end() {
        let mut r = Cursor::new(b"one\ntwo".to_vec());
        assert_eq!(skip_line(&mut r, 10).unwrap(), 4);
        assert_eq!(skip_line(&mut r, 10).unwrap(), 3);
        assert_eq!(skip_line(&mut r, 10).unwrap(), 0);
        assert_eq!(skip_line(&mut r, 10).unwrap(), 0);
        // A line of a million bytes costs no memory.
        let mut r = BufReader::new(Cursor::new(vec![b'x'; 1 << 20]));
        assert_eq!(skip_line(&mut r, 1 << 20).unwrap(), 1 << 20);
        // The line end is not counted against the limit.
        let mut r = Cursor::new(b"abcd\nabcde\n".to_vec());
        assert_eq!(skip_line(&mut r, 4).unwrap(), 5);
        let e = skip_line(&mut r, 4).unwrap_err();
        assert!(e.to_string().contains("a line goes on past 4 bytes"), "{e}");
        // An endless line stops at the limit.
        let mut r = BufReader::new(Endless(b'x'));
        let e = skip_line(&mut r, 1 << 16).unwrap_err();
        assert!(e.to_string().contains("65536"), "{e}");
    }

    #[test]
    fn the_total_counts_line_ends_and_takes_exactly_its_size() {
        let all = |s: &str, max: usize, total: u64| -> Result<Vec<String>, String> {
            lines(Cursor::new(s.to_string()), max, total)
                .collect::<Result<Vec<_>, _>>()
                .map_err(|e| e.to_string())
        };
        // Exactly the total, with or without a last line end.
        assert_eq!(all("ab\ncd\n", 10, 6).unwrap(), ["ab", "cd"]);
        assert_eq!(all("ab\ncd", 10, 5).unwrap(), ["ab", "cd"]);
        assert_eq!(all("", 10, 0).unwrap(), Vec::<String>::new());
        // One byte more, wherever it falls.
        for (s, total) in [("ab\ncd\n", 5), ("ab\ncd", 4), ("ab\n", 2), ("\n", 0)] {
            let e = all(s, 10, total).unwrap_err();
            assert!(
                e.contains(&format!("past {total} bytes")),
                "{s:?} {total}: {e}"
            );
        }
        // Each line at most `max` bytes, its `\n` aside (a `\r` counts).
        assert_eq!(
            all("abcd\nabc\r\nabcd", 4, 100).unwrap(),
            ["abcd", "abc", "abcd"]
        );
        let e = all("abcd\nabcde\n", 4, 100).unwrap_err();
        assert!(e.contains("a line goes on past 4 bytes"), "{e}");
        // After an error, nothing more.
        let mut it = lines(Cursor::new("abcdef\nx\n"), 4, 100);
        assert!(it.next().unwrap().is_err());
        assert!(it.next().is_none());
        // Not UTF-8.
        let mut it = lines(Cursor::new(vec![0xff, b'\n', b'a']), 4, 100);
        assert!(it.next().unwrap().is_err());
        assert!(it.next().is_none());
    }
}
