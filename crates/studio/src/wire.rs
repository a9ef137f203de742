//! The mesh buffers the page downloads, in one little-endian blob laid out
//! for typed-array views without copying:
//!
//! | offset | content |
//! | --- | --- |
//! | 0 | magic `MFMESH01` (8 bytes) |
//! | 8 | `u32` vertices `n`, `u32` triangles `t`, `u32` attributes `k`, `u32` 0 |
//! | 24 | `f32` positions, `3n` |
//! | | `f32` normals, `3n` |
//! | | `f32` attribute values, `k` blocks of `n` |
//! | | `u32` triangle corners, `3t` (counter-clockwise from outside) |

use crate::engine::MeshData;

/// Magic bytes that open a mesh blob.
pub const MAGIC: &[u8; 8] = b"MFMESH01";
/// Bytes before the positions.
pub const HEADER: usize = 24;

/// Encodes a mesh as the blob described in the [module docs](self).
pub fn encode_mesh(m: &MeshData) -> Vec<u8> {
    let n = m.vertices.len();
    let t = m.triangles.len();
    let k = m.attributes.len();
    let mut out = Vec::with_capacity(HEADER + 4 * (6 * n + k * n + 3 * t));
    out.extend_from_slice(MAGIC);
    for v in [n as u32, t as u32, k as u32, 0] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    for p in m.vertices.iter().chain(&m.normals) {
        for c in p {
            out.extend_from_slice(&c.to_le_bytes());
        }
    }
    for a in &m.attributes {
        for v in a {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    for tri in &m.triangles {
        for i in tri {
            out.extend_from_slice(&i.to_le_bytes());
        }
    }
    out
}

/// A decoded blob: positions, normals, attributes, triangles.
pub type Decoded = (Vec<[f32; 3]>, Vec<[f32; 3]>, Vec<Vec<f32>>, Vec<[u32; 3]>);

/// Decodes a blob of [`encode_mesh`]; `None` if it is malformed
/// (wrong magic, or a length that does not match its counts).
pub fn decode_mesh(b: &[u8]) -> Option<Decoded> {
    if b.len() < HEADER || &b[..8] != MAGIC {
        return None;
    }
    let word = |i: usize| u32::from_le_bytes(b[i..i + 4].try_into().unwrap());
    let (n, t, k) = (word(8) as usize, word(12) as usize, word(16) as usize);
    let need = HEADER.checked_add(4usize.checked_mul(6 * n + k * n + 3 * t)?)?;
    if b.len() != need {
        return None;
    }
    let mut at = HEADER;
    let mut take = || {
        let v = word(at);
        at += 4;
        v
    };
    let mut f = || f32::from_bits(take());
    let pos: Vec<[f32; 3]> = (0..n).map(|_| [f(), f(), f()]).collect();
    let nrm: Vec<[f32; 3]> = (0..n).map(|_| [f(), f(), f()]).collect();
    let attrs: Vec<Vec<f32>> = (0..k).map(|_| (0..n).map(|_| f()).collect()).collect();
    let tris: Vec<[u32; 3]> = (0..t).map(|_| [take(), take(), take()]).collect();
    Some((pos, nrm, attrs, tris))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip() {
        let m = MeshData {
            resolution: 4,
            vertices: vec![[0.0, 1.0, 2.0], [3.0, 4.0, 5.0], [6.0, 7.0, -8.5]],
            normals: vec![[1.0, 0.0, 0.0]; 3],
            attributes: vec![vec![0.25, 0.5, 0.75]],
            triangles: vec![[0, 1, 2], [2, 1, 0]],
            note: None,
        };
        let b = encode_mesh(&m);
        assert_eq!(b.len(), HEADER + 4 * (18 + 3 + 6));
        let (p, n, a, t) = decode_mesh(&b).unwrap();
        assert_eq!(
            (p, n, a, t),
            (m.vertices, m.normals, m.attributes, m.triangles)
        );
        assert!(decode_mesh(&b[..b.len() - 1]).is_none());
    }
}
