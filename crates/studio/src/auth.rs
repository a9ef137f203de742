//! The studio's secret: a random token that every request for the page and
//! the API must carry (header `X-Studio-Token`, or the query parameter
//! `token` where a browser cannot send a header: the page's address, images
//! and downloads), and random session ids, both from the OS's random source.

use crate::error::StudioError;
use std::io::Read;

/// Bytes of randomness in a generated token (256 bits).
pub const TOKEN_BYTES: usize = 32;
/// Bytes of randomness in a session id (128 bits).
pub const SESSION_BYTES: usize = 16;

/// `n` bytes from the OS's random source, as lower-case hex.
pub(crate) fn random_hex(n: usize) -> Result<String, StudioError> {
    let mut buf = vec![0u8; n];
    std::fs::File::open("/dev/urandom")
        .and_then(|mut f| f.read_exact(&mut buf))
        .map_err(|e| StudioError::Io {
            path: "/dev/urandom (the OS random source)".into(),
            source: e,
        })?;
    Ok(buf.iter().map(|b| format!("{b:02x}")).collect())
}

/// A token given in the options: 16 to 256 characters, letters, digits,
/// `-` and `_` (so it goes into a URL as it is).
pub(crate) fn check_token(t: &str) -> Result<(), StudioError> {
    let ok = (16..=256).contains(&t.len())
        && t.chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_');
    if ok {
        Ok(())
    } else {
        Err(StudioError::Request(
            "the studio's token must be 16 to 256 letters, digits, '-' or '_'".into(),
        ))
    }
}

/// Compares in time independent of where the strings differ.
pub(crate) fn same(a: &str, b: &str) -> bool {
    let (a, b) = (a.as_bytes(), b.as_bytes());
    if a.len() != b.len() {
        return false;
    }
    a.iter().zip(b).fold(0u8, |d, (x, y)| d | (x ^ y)) == 0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tokens_are_random_and_compared_exactly() {
        let a = random_hex(TOKEN_BYTES).unwrap();
        let b = random_hex(TOKEN_BYTES).unwrap();
        assert_eq!(a.len(), 64);
        assert_ne!(a, b);
        assert!(check_token(&a).is_ok());
        assert!(check_token("short").is_err());
        assert!(check_token("has space in it, sixteen+").is_err());
        assert!(same(&a, &a.clone()));
        assert!(!same(&a, &b));
        assert!(!same(&a, &a[1..]));
    }
}
