//! Local thickness from a squared distance map (Hildebrand and Rüegsegger):
//! each voxel gets the largest ball, among the balls `|p - c|^2 < D(c)` of
//! all centres `c`, that contains it.
//!
//! Only "ridge" centres matter: a centre whose voxel set lies inside a
//! neighbour's (tested exactly on the lattice, see [`Reach`]) adds nothing,
//! and following such neighbours always ends at a ridge centre that covers
//! at least as much. The ridge balls are sorted by radius, largest first,
//! and painted row by row from a per-radius table of row spans; a bitmap of
//! the voxels not yet painted (one bit per voxel, cache-resident) makes a
//! row already painted cost a word test, and each voxel is written once.
//! Cost: the rows crossed by the ridge balls plus one write per voxel.
//! Chunks of planes are painted in parallel, each by its own walk over the
//! sorted balls, so the result does not depend on the thread count.

use super::edt::MAX_SIDE;
use rayon::prelude::*;
use std::ops::Range;

const _: () = assert!(MAX_SIDE <= u16::MAX as usize);

/// A ridge centre: its squared radius, its rank among the distinct squared
/// radii (largest first) and its position in the window (16 bytes; sides
/// are at most [`MAX_SIDE`], so positions fit `u16`).
#[derive(Clone, Copy, Debug)]
pub struct Ball {
    pub d: u32,
    pub rank: u32,
    pub at: [u16; 3],
}

/// Largest integer `r` with `r * r < d` (`d >= 1`).
fn reach(d: u64) -> i64 {
    let mut r = ((d - 1) as f64).sqrt() as i64;
    while (r + 1) * (r + 1) < d as i64 {
        r += 1;
    }
    while r > 0 && r * r >= d as i64 {
        r -= 1;
    }
    r
}

/// Whether the ball of squared radius `dn` at squared distance `k` from a
/// centre of squared radius `dc` contains that centre's ball:
/// `sqrt(dn) >= sqrt(dc) + sqrt(k)`, exactly.
fn contains(dn: u32, dc: u32, k: u64) -> bool {
    let (dn, dc) = (dn as u64, dc as u64);
    // sqrt(dn) >= sqrt(dc) + sqrt(k)  <=>  dn - dc - k >= 2 sqrt(k dc)
    match dn.checked_sub(dc + k) {
        Some(a) => (a as u128) * (a as u128) >= 4 * k as u128 * dc as u128,
        None => false,
    }
}

/// Squared radii up to which [`Reach`] tabulates the lattice balls.
const TABLE: u32 = 1 << 16;

/// Neighbours of a centre, per axis, tested for containment.
const RAD: i64 = 1;
/// Room for the offset classes of `RAD` (3 for 1, 9 for 2).
const CLASSES: usize = 9;

/// Containment of lattice balls (the voxel sets painted), which holds far
/// more often than containment of the continuous balls. For each offset
/// class `e` (sorted absolute components) and squared radius `D`,
/// `far[class][D]` is the largest `|q - e|^2` over lattice points
/// `|q|^2 < D`, so a ball of squared radius `dn` at offset `e` holds every
/// voxel of the ball `D` exactly when `dn > far`. Offsets run over the
/// `(2 RAD + 1)^3` cube, nearest first.
struct Reach {
    far: Vec<Vec<u32>>,
    /// `(dx, dy, dz, |e|^2, class)`, by increasing `|e|^2`.
    offsets: Vec<([i64; 3], u64, usize)>,
}

impl Reach {
    fn new(max_d: u32) -> Reach {
        let len = max_d.min(TABLE) as usize + 1;
        let mut classes = Vec::new();
        for a in 0..=RAD {
            for b in 0..=a {
                for c in 0..=b {
                    if a > 0 {
                        classes.push([a, b, c]);
                    }
                }
            }
        }
        // best[k][s]: the largest q . e over lattice points of squared norm
        // s; by symmetry q sorted and non-negative like e.
        let mut best = vec![vec![-1i64; len]; classes.len()];
        let r = (len as f64).sqrt() as i64 + 1;
        for a in 0..=r {
            for b in 0..=a {
                for c in 0..=b {
                    let s = (a * a + b * b + c * c) as usize;
                    if s >= len {
                        break;
                    }
                    for (k, e) in classes.iter().enumerate() {
                        best[k][s] = best[k][s].max(e[0] * a + e[1] * b + e[2] * c);
                    }
                }
            }
        }
        let far = classes
            .iter()
            .zip(&best)
            .map(|(e, best)| {
                let e2 = e.iter().map(|v| v * v).sum::<i64>();
                let mut t = vec![0u32; len];
                let mut m = 0i64;
                // far[d] covers the squared norms s < d.
                for (s, &b) in best[..len - 1].iter().enumerate() {
                    if b >= 0 {
                        m = m.max(s as i64 + 2 * b + e2);
                    }
                    t[s + 1] = m.min(u32::MAX as i64) as u32;
                }
                t
            })
            .collect();
        let mut offsets = Vec::new();
        for dz in -RAD..=RAD {
            for dy in -RAD..=RAD {
                for dx in -RAD..=RAD {
                    let mut e = [dx.abs(), dy.abs(), dz.abs()];
                    e.sort_unstable_by(|a, b| b.cmp(a));
                    if let Some(k) = classes.iter().position(|c| *c == e) {
                        offsets.push(([dx, dy, dz], (dx * dx + dy * dy + dz * dz) as u64, k));
                    }
                }
            }
        }
        offsets.sort_by_key(|o| o.1);
        assert!(classes.len() <= CLASSES);
        Reach { far, offsets }
    }

    /// Whether the ball `dn` at offset class `class` (squared length `k`)
    /// holds every voxel of the ball `dc`.
    fn holds(&self, dn: u32, dc: u32, class: usize, k: u64) -> bool {
        match self.far[class].get(dc as usize) {
            Some(&far) => dn > far,
            None => contains(dn, dc, k),
        }
    }
}

/// The ridge centres whose planes are in `zs`, sorted largest ball first
/// (ties in scan order), ranked by distinct squared radius. `d` is the
/// squared distance map of the window `dims` (0 outside the phase).
pub fn ridge(d: &[u32], dims: [usize; 3], zs: Range<usize>) -> Vec<Ball> {
    let [nx, ny, nz] = dims;
    let plane = nx * ny;
    let max_d = d.par_iter().cloned().max().unwrap_or(0);
    let reach = Reach::new(max_d);
    // Linear offsets of the neighbours, for centres away from the edges.
    let lin: Vec<(isize, usize)> = reach
        .offsets
        .iter()
        .map(|&(e, _, class)| {
            (
                (e[0] + nx as i64 * (e[1] + ny as i64 * e[2])) as isize,
                class,
            )
        })
        .collect();
    let mut balls: Vec<Ball> = zs
        .into_par_iter()
        .flat_map_iter(|z| {
            let mut out = Vec::new();
            for y in 0..ny {
                for x in 0..nx {
                    let i = x + nx * y + plane * z;
                    let dc = d[i];
                    if dc == 0 {
                        continue;
                    }
                    let inner = [x, y, z]
                        .iter()
                        .zip([nx, ny, nz])
                        .all(|(&c, n)| c as i64 >= RAD && c as i64 + RAD < n as i64);
                    let kept = match (inner, reach.far[0].get(dc as usize)) {
                        // Fast path: thresholds per class, no bounds tests.
                        (true, Some(_)) => {
                            let mut far = [0u32; CLASSES];
                            for (f, t) in far.iter_mut().zip(&reach.far) {
                                *f = t[dc as usize];
                            }
                            !lin.iter()
                                .any(|&(o, k)| d[(i as isize + o) as usize] > far[k])
                        }
                        _ => !dominated(d, dims, [x, y, z], dc, &reach),
                    };
                    if kept {
                        out.push(Ball {
                            d: dc,
                            rank: 0,
                            at: [x as u16, y as u16, z as u16],
                        });
                    }
                }
            }
            out
        })
        .collect();
    // Largest first; a stable sort keeps each radius's balls in scan order
    // (z, y, x), which keeps the painting walk local. The order among equal
    // radii cannot change the result: they paint the same value.
    balls.par_sort_by_key(|b| std::cmp::Reverse(b.d));
    let mut rank = 0u32;
    for i in 0..balls.len() {
        if i > 0 && balls[i].d != balls[i - 1].d {
            rank += 1;
        }
        balls[i].rank = rank;
    }
    balls
}

/// Whether a nearby centre's ball holds every voxel of the ball at `c`.
fn dominated(d: &[u32], dims: [usize; 3], c: [usize; 3], dc: u32, reach: &Reach) -> bool {
    let [nx, ny, nz] = dims;
    let n = [nx, ny, nz].map(|v| v as i64);
    let c = c.map(|v| v as i64);
    let inner = (0..3).all(|a| c[a] >= RAD && c[a] + RAD < n[a]);
    for &(e, k, class) in &reach.offsets {
        let p = [c[0] + e[0], c[1] + e[1], c[2] + e[2]];
        if !inner && (0..3).any(|a| p[a] < 0 || p[a] >= n[a]) {
            continue;
        }
        let i = p[0] as usize + nx * (p[1] as usize + ny * p[2] as usize);
        if reach.holds(d[i], dc, class, k) {
            return true;
        }
    }
    false
}

/// Paints the planes `zs` of the window into `out` (their voxels): each
/// phase voxel (`d > 0`) still 0 in `out` gets `rank + 1` of the largest
/// ball of `balls` covering it; voxels already set are kept.
pub fn paint(d: &[u32], dims: [usize; 3], zs: Range<usize>, balls: &[Ball], out: &mut [u32]) {
    let [nx, ny, _] = dims;
    let plane = nx * ny;
    let planes = zs.len();
    assert_eq!(out.len(), planes * plane, "paint buffer");
    if planes == 0 || plane == 0 {
        return;
    }
    let chunks = (rayon::current_num_threads() * 2).clamp(1, planes);
    let per = planes.div_ceil(chunks);
    out.par_chunks_mut(per * plane)
        .enumerate()
        .for_each(|(c, part)| {
            let z0 = zs.start + c * per;
            let z1 = z0 + part.len() / plane;
            paint_chunk(d, dims, z0..z1, balls, part);
        });
}

/// The rows of a lattice ball of squared radius `d`: for each `dz` from
/// `-r` to `r`, the `(dy, half width)` of its rows, in one list with the
/// start of each `dz`'s run.
struct Template {
    d: u32,
    r: i64,
    rows: Vec<(i32, i32)>,
    starts: Vec<usize>,
}

impl Template {
    fn new(d: u32) -> Template {
        let r = reach(d as u64);
        let mut rows = Vec::new();
        let mut starts = Vec::with_capacity(2 * r as usize + 2);
        for dz in -r..=r {
            starts.push(rows.len());
            let rem = d as i64 - dz * dz;
            let ry = reach(rem as u64);
            for dy in -ry..=ry {
                rows.push((dy as i32, reach((rem - dy * dy) as u64) as i32));
            }
        }
        starts.push(rows.len());
        Template { d, r, rows, starts }
    }
}

/// Rows per tile of the summary bitmap.
const TILE: usize = 8;

/// Paints planes `zs` into `out` (their voxels only). Unpainted voxels are
/// bits of a bitmap (one bit per voxel, rows padded to 64), small enough to
/// stay in cache, so testing a ball's row costs a word or two; a summary
/// bitmap (the OR of every [`TILE`] rows of a plane) lets a ball pass over
/// a tile of rows already painted with one test.
fn paint_chunk(d: &[u32], dims: [usize; 3], zs: Range<usize>, balls: &[Ball], out: &mut [u32]) {
    let [nx, ny, _] = dims;
    let plane = nx * ny;
    let base = zs.start * plane;
    let wpr = nx.div_ceil(64);
    let rows = out.len() / nx;
    let nyb = ny.div_ceil(TILE);
    let mut bits = vec![0u64; rows * wpr];
    let mut sum = vec![0u64; zs.len() * nyb * wpr];
    for (r, w) in bits.chunks_mut(wpr).enumerate() {
        let row = &d[base + r * nx..base + (r + 1) * nx];
        let done = &out[r * nx..(r + 1) * nx];
        for (x, (&v, &o)) in row.iter().zip(done).enumerate() {
            if v > 0 && o == 0 {
                w[x / 64] |= 1 << (x % 64);
            }
        }
        let s = ((r / ny) * nyb + (r % ny) / TILE) * wpr;
        for (s, &w) in sum[s..s + wpr].iter_mut().zip(w.iter()) {
            *s |= w;
        }
    }
    let z0 = zs.start as i64;
    let mut t = Template::new(1);
    for b in balls {
        let [cx, cy, cz] = b.at.map(|v| v as i64);
        if t.d != b.d {
            let r = reach(b.d as u64);
            if cz + r < z0 || cz - r >= zs.end as i64 {
                continue;
            }
            t = Template::new(b.d);
        }
        let za = (cz - t.r).max(z0);
        let zb = (cz + t.r).min(zs.end as i64 - 1);
        for z in za..=zb {
            let k = (z - cz + t.r) as usize;
            let zl = (z - z0) as usize;
            let spans = &t.rows[t.starts[k]..t.starts[k + 1]];
            // Rows by tiles: skip a tile whose summary has no unpainted bit
            // under the widest span of its rows.
            let mut i = 0;
            while i < spans.len() {
                let y0 = cy + spans[i].0 as i64;
                if y0 < 0 {
                    i += 1;
                    continue;
                }
                if y0 >= ny as i64 {
                    break;
                }
                let tile = y0 as usize / TILE;
                let y_end = ((tile + 1) * TILE).min(ny) as i64;
                let mut j = i;
                let mut widest = 0;
                while j < spans.len() && cy + (spans[j].0 as i64) < y_end {
                    widest = widest.max(spans[j].1);
                    j += 1;
                }
                let xa = (cx - widest as i64).max(0) as usize;
                let xb = (cx + widest as i64).min(nx as i64 - 1) as usize;
                let srow = (zl * nyb + tile) * wpr;
                if !any_in(&sum[srow..srow + wpr], xa, xb) {
                    i = j;
                    continue;
                }
                let mut hit = false;
                for &(dy, rx) in &spans[i..j] {
                    let y = (cy + dy as i64) as usize;
                    let xa = (cx - rx as i64).max(0) as usize;
                    let xb = (cx + rx as i64).min(nx as i64 - 1) as usize;
                    let r = zl * ny + y;
                    hit |= fill_row(
                        &mut bits[r * wpr..(r + 1) * wpr],
                        &mut out[r * nx..(r + 1) * nx],
                        xa,
                        xb,
                        b.rank + 1,
                    );
                }
                if hit {
                    for w in xa / 64..=xb / 64 {
                        let mut v = 0;
                        for y in tile * TILE..y_end as usize {
                            v |= bits[(zl * ny + y) * wpr + w];
                        }
                        sum[srow + w] = v;
                    }
                }
                i = j;
            }
        }
    }
}

/// The mask of bits `a..=b` within word `w`.
fn word_mask(w: usize, a: usize, b: usize) -> u64 {
    let lo = if w == a / 64 { a % 64 } else { 0 };
    let hi = if w == b / 64 { b % 64 } else { 63 };
    (u64::MAX >> (63 - hi)) & (u64::MAX << lo)
}

/// Whether any of bits `a..=b` is set.
fn any_in(bits: &[u64], a: usize, b: usize) -> bool {
    (a / 64..=b / 64).any(|w| bits[w] & word_mask(w, a, b) != 0)
}

/// Writes `v` into the unpainted voxels `a..=b` of one row and marks them
/// painted; whether there were any.
fn fill_row(bits: &mut [u64], out: &mut [u32], a: usize, b: usize, v: u32) -> bool {
    let mut hit = false;
    for w in a / 64..=b / 64 {
        let mask = word_mask(w, a, b);
        let mut m = bits[w] & mask;
        if m == 0 {
            continue;
        }
        hit = true;
        bits[w] &= !mask;
        while m != 0 {
            out[w * 64 + m.trailing_zeros() as usize] = v;
            m &= m - 1;
        }
    }
    hit
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn containment_is_exact() {
        // radius 2 inside radius 3 one step away: 2 + 1 <= 3.
        assert!(contains(9, 4, 1));
        assert!(!contains(8, 4, 1));
        // radius sqrt(2) inside 2 sqrt(2) a diagonal step away.
        assert!(contains(8, 2, 2));
        assert!(!contains(7, 2, 2));
        assert!(contains(12, 3, 3));
        assert!(!contains(11, 3, 3));
    }

    #[test]
    fn lattice_containment_matches_enumeration() {
        let t = Reach::new(200);
        let mut seen = Vec::new();
        for &(e, k, class) in &t.offsets {
            if seen.contains(&class) {
                continue;
            }
            seen.push(class);
            for dc in 1..200u32 {
                let r = (dc as f64).sqrt() as i64 + 1;
                let mut far = 0;
                for x in -r..=r {
                    for y in -r..=r {
                        for z in -r..=r {
                            if x * x + y * y + z * z < dc as i64 {
                                far = far
                                    .max((x - e[0]).pow(2) + (y - e[1]).pow(2) + (z - e[2]).pow(2));
                            }
                        }
                    }
                }
                assert_eq!(t.far[class][dc as usize] as i64, far, "dc {dc} e {e:?}");
                // The lattice test is never stricter than the continuous one.
                for dn in dc..dc + 60 {
                    if contains(dn, dc, k) {
                        assert!(t.holds(dn, dc, class, k));
                    }
                }
            }
        }
    }

    #[test]
    fn reach_is_strict() {
        assert_eq!(reach(1), 0);
        assert_eq!(reach(4), 1);
        assert_eq!(reach(5), 2);
        assert_eq!(reach(10), 3);
    }
}
