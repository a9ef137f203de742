//! How much memory and disk a job may use.
//!
//! [`memory_limit`] is the smallest of what `/proc/meminfo` says is
//! available, the cgroup's remaining allowance (v2 `memory.max` minus
//! `memory.current`, or v1 `limit_in_bytes` minus `usage_in_bytes`) and the
//! address-space limit `RLIMIT_AS` minus the current virtual size, so a job
//! in a container or under `ulimit -v` is sized to what it can really get.

use std::path::Path;

/// Bytes this process may still allocate, if anything is known.
pub fn memory_limit() -> Option<f64> {
    let candidates = [
        meminfo_available(),
        cgroup_remaining(),
        rlimit_as_remaining(),
    ];
    candidates.into_iter().flatten().reduce(f64::min)
}

/// The budget of a reader or a build that is given none: 80 % of
/// [`memory_limit`], else 4 GiB.
pub fn default_memory_budget() -> u64 {
    memory_limit().map(|m| (0.8 * m) as u64).unwrap_or(4 << 30)
}

/// `MemAvailable` from /proc/meminfo.
pub fn meminfo_available() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/meminfo").ok()?;
    kib_field(&s, "MemAvailable:")
}

/// Peak resident set size of this process (`VmHWM`).
pub fn peak_rss() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    kib_field(&s, "VmHWM:")
}

/// A `Name: N kB` field of a /proc file, in bytes.
pub fn kib_field(s: &str, name: &str) -> Option<f64> {
    let line = s.lines().find(|l| l.starts_with(name))?;
    let kib: f64 = line[name.len()..]
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    Some(kib * 1024.0)
}

fn read_number(p: &str) -> Option<f64> {
    let s = std::fs::read_to_string(p).ok()?;
    let t = s.trim();
    if t == "max" {
        return None;
    }
    t.parse::<f64>().ok()
}

/// The cgroup of this process: its v2 path, from /proc/self/cgroup.
fn cgroup_v2_dir() -> Option<String> {
    let s = std::fs::read_to_string("/proc/self/cgroup").ok()?;
    let path = s.lines().find_map(|l| l.strip_prefix("0::"))?;
    Some(format!("/sys/fs/cgroup{}", path.trim_end_matches('/')))
}

/// Remaining allowance of the memory cgroup, if limited.
pub fn cgroup_remaining() -> Option<f64> {
    if let Some(dir) = cgroup_v2_dir() {
        // The limit may be set on the group or an ancestor: take the
        // tightest along the path.
        let mut best: Option<f64> = None;
        let mut d = dir.as_str();
        loop {
            if let Some(max) = read_number(&format!("{d}/memory.max")) {
                let cur = read_number(&format!("{d}/memory.current")).unwrap_or(0.0);
                let left = (max - cur).max(0.0);
                best = Some(best.map_or(left, |b| b.min(left)));
            }
            match d.rfind('/') {
                Some(i) if d.len() > "/sys/fs/cgroup".len() => d = &d[..i],
                _ => break,
            }
        }
        if best.is_some() {
            return best;
        }
    }
    let max = read_number("/sys/fs/cgroup/memory/memory.limit_in_bytes")?;
    // v1 reports "no limit" as a huge number.
    if max > 1e18 {
        return None;
    }
    let cur = read_number("/sys/fs/cgroup/memory/memory.usage_in_bytes").unwrap_or(0.0);
    Some((max - cur).max(0.0))
}

/// `RLIMIT_AS` minus the current virtual size, if limited.
pub fn rlimit_as_remaining() -> Option<f64> {
    let mut r = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit writes the struct it is given and nothing else.
    if unsafe { libc::getrlimit(libc::RLIMIT_AS, &mut r) } != 0 {
        return None;
    }
    if r.rlim_cur == libc::RLIM_INFINITY {
        return None;
    }
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let used = kib_field(&s, "VmSize:").unwrap_or(0.0);
    Some((r.rlim_cur as f64 - used).max(0.0))
}

/// Free bytes on the file system that `path` (or its nearest existing
/// ancestor) is on.
pub fn free_disk(path: &Path) -> Option<f64> {
    use std::os::unix::ffi::OsStrExt;
    let mut p = if path.as_os_str().is_empty() {
        Path::new(".")
    } else {
        path
    };
    while !p.exists() {
        p = match p.parent() {
            Some(q) if !q.as_os_str().is_empty() => q,
            _ => Path::new("."),
        };
        if p == Path::new(".") {
            break;
        }
    }
    let c = std::ffi::CString::new(p.as_os_str().as_bytes()).ok()?;
    // SAFETY: statvfs reads the NUL-terminated path and fills the struct.
    let mut s: libc::statvfs = unsafe { std::mem::zeroed() };
    if unsafe { libc::statvfs(c.as_ptr(), &mut s) } != 0 {
        return None;
    }
    Some(s.f_bavail as f64 * s.f_frsize as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_kib_fields() {
        let s = "MemTotal:       16318460 kB\nMemAvailable:    8000000 kB\n";
        assert_eq!(kib_field(s, "MemAvailable:"), Some(8_000_000.0 * 1024.0));
        assert_eq!(kib_field(s, "Nope:"), None);
    }

    #[test]
    fn limits_are_positive_where_known() {
        let m = memory_limit().expect("meminfo is readable on Linux");
        assert!(m > 0.0 && m <= meminfo_available().unwrap());
        let d = free_disk(Path::new("no/such/dir/below/here")).unwrap();
        assert!(d > 0.0);
        assert!(peak_rss().unwrap() > 0.0);
    }
}
