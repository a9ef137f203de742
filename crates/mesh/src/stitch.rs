//! Joining the bricks' pieces into one indexed mesh: owned vertices are
//! numbered in brick order, references to other bricks' vertices are found
//! by edge key in their owner (so shared vertices exist once, no cracks).

use crate::brick::BrickMesh;
use crate::grid::Grid;
use crate::{Mesh, MeshError};
use rayon::prelude::*;

/// `parts[k]` is brick `k`'s piece (empty for skipped bricks).
pub fn stitch(grid: &Grid, parts: Vec<BrickMesh>) -> Result<Mesh, MeshError> {
    let mut offsets = Vec::with_capacity(parts.len() + 1);
    let mut tri_offsets = Vec::with_capacity(parts.len() + 1);
    let (mut nv, mut nt) = (0usize, 0usize);
    for p in &parts {
        offsets.push(nv);
        tri_offsets.push(nt);
        nv += p.owned_pos.len();
        nt += p.tris.len();
    }
    if nv > u32::MAX as usize {
        return Err(MeshError::TooLarge(format!(
            "{nv} vertices do not fit 32-bit indices; lower the resolution"
        )));
    }
    let mut vertices = Vec::with_capacity(nv);
    for p in &parts {
        vertices.extend_from_slice(&p.owned_pos);
    }
    let mut triangles = vec![[0u32; 3]; nt];
    let mut slices: Vec<&mut [[u32; 3]]> = Vec::with_capacity(parts.len());
    let mut rest = &mut triangles[..];
    for p in &parts {
        let (a, b) = rest.split_at_mut(p.tris.len());
        slices.push(a);
        rest = b;
    }
    slices
        .into_par_iter()
        .enumerate()
        .try_for_each(|(k, dst)| -> Result<(), MeshError> {
            let p = &parts[k];
            let owned = p.owned_pos.len() as u32;
            let foreign: Vec<u32> = p
                .foreign_keys
                .iter()
                .map(|&key| resolve(grid, &parts, &offsets, key))
                .collect::<Result<_, _>>()?;
            for (d, t) in dst.iter_mut().zip(&p.tris) {
                *d = t.map(|v| {
                    if v < owned {
                        (offsets[k] + v as usize) as u32
                    } else {
                        foreign[(v - owned) as usize]
                    }
                });
            }
            Ok(())
        })?;
    Ok(Mesh {
        vertices,
        triangles,
    })
}

fn resolve(
    grid: &Grid,
    parts: &[BrickMesh],
    offsets: &[usize],
    key: u64,
) -> Result<u32, MeshError> {
    let owner = grid.brick_index(grid.owner_brick(grid.node_from_index(key / 8)));
    let p = &parts[owner];
    match p.owned_keys.binary_search_by_key(&key, |&(k, _)| k) {
        Ok(i) => Ok((offsets[owner] + p.owned_keys[i].1 as usize) as u32),
        Err(_) => Err(MeshError::Internal(format!(
            "grid edge {key} is used by a brick but not made by its owner brick {owner}"
        ))),
    }
}
