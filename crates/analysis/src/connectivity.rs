//! Connected components of the solid and of the pore space, pore access
//! from outside, percolation and the Euler characteristic, on the voxel grid
//! of [`crate::grid`].
//!
//! Connectivity: the solid is 26-connected (voxels sharing a face, an edge or
//! a corner touch) and the pore space 6-connected (faces only), the usual
//! complementary pair, so a pore cannot leak through a solid edge. The Euler
//! characteristic is that of the union of the closed solid voxels (which
//! matches 26-connectivity): `V - E + F - C` of its cubical complex.
//!
//! Memory: the grid is sampled in slabs and labelled one layer at a time
//! with a union-find over provisional labels; only the current slab, two
//! layers of labels and the live part of the union-find are held, and
//! finished components are folded into the totals whenever the union-find
//! grows past a few layers' worth.

use crate::error::{AnalysisError, Result};
use crate::grid::{Progress, Sampler, OUTSIDE, PORE, SLAB, SOLID};

/// Connectivity of the solid and the pore space.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Connectivity {
    /// Number of 26-connected solid components.
    pub solid_components: usize,
    /// Volume of each solid component, largest first.
    pub solid_volumes: Vec<f64>,
    /// Number of 6-connected pore components.
    pub pore_components: usize,
    /// Total pore volume (voxels inside the region, not solid).
    pub pore_volume: f64,
    /// Pore volume in components that reach the outside: a face of the
    /// bounds or a voxel outside the region.
    pub open_pore_volume: f64,
    /// Pore components that do not reach the outside (closed cavities).
    pub closed_pores: usize,
    /// Volume of the closed cavities.
    pub closed_pore_volume: f64,
    /// Whether one pore component reaches from one end of the analysed
    /// voxels to the other along x, y and z: from the first to the last
    /// layer of voxels inside the region (or of the grid, without one).
    pub percolates: [bool; 3],
    /// Euler characteristic of the solid (closed voxels): 1 for a ball,
    /// 0 for a solid torus, 2 for a hollow ball.
    pub euler: i64,
}

impl Connectivity {
    /// Euler characteristic of the solid's boundary surface, `2 euler`
    /// (2 for a sphere, 0 for a torus, 2 - 2g for genus g).
    pub fn surface_euler(&self) -> i64 {
        2 * self.euler
    }

    /// Fraction of the pore volume connected to the outside; NaN
    /// (undefined) without pores.
    pub fn open_pore_fraction(&self) -> f64 {
        if self.pore_volume > 0.0 {
            self.open_pore_volume / self.pore_volume
        } else {
            f64::NAN
        }
    }
}

pub(crate) const NONE: u32 = u32::MAX;
/// Flag bits of a component: faces x-, x+, y-, y+, z-, z+ of the bounds,
/// then "next to a voxel outside the region".
pub(crate) const OUT: u8 = 1 << 6;

/// Peak bytes of [`connectivity`] on `sampler`'s grid (slab, labels and a
/// full union-find), used to refuse jobs that cannot fit.
pub fn predict_bytes(sampler: &Sampler) -> f64 {
    let [nx, ny, _] = sampler.grid.dims;
    let layer = (nx * ny) as f64;
    // Slab bytes; two label layers and two occupancy layers; the union-find
    // (parent, count, flags, kind) at its compaction limit, twice while it
    // is rebuilt; finished component volumes are small beside it.
    layer * SLAB as f64 + layer * 10.0 + 2.0 * uf_limit(nx * ny) as f64 * 14.0 + 32e6
}

pub(crate) fn uf_limit(layer: usize) -> usize {
    4 * layer + 4096
}

/// Labels the sampler's grid and measures its connectivity.
/// `progress(done_layers, total_layers)`.
pub fn connectivity(sampler: &Sampler, progress: Progress) -> Result<Connectivity> {
    let [nx, ny, _] = sampler.grid.dims;
    label(sampler, progress, uf_limit(nx * ny))
}

/// [`connectivity`] compacting the union-find past `limit` labels.
fn label(sampler: &Sampler, progress: Progress, limit: usize) -> Result<Connectivity> {
    let [nx, ny, nz] = sampler.grid.dims;
    let layer = nx
        .checked_mul(ny)
        .filter(|&l| l < (NONE as usize) / 8)
        .ok_or_else(|| AnalysisError::Input(format!("grid layer {nx} x {ny} is too large")))?;
    let mut st = State {
        nx,
        ny,
        nz,
        voxel: sampler.grid.voxel_volume(),
        uf: Uf::default(),
        prev_occ: vec![OUTSIDE; layer],
        prev_lab: vec![NONE; layer],
        cur_lab: vec![NONE; layer],
        out: Connectivity::default(),
        euler8: 0,
        region: NO_EXTENT,
        spans: Vec::new(),
    };
    let table = euler_table();
    let mut k0 = 0;
    while k0 < nz {
        let k1 = (k0 + SLAB).min(nz);
        let slab = sampler.slab(k0, k1);
        for k in k0..k1 {
            let occ = &slab[(k - k0) * layer..(k - k0 + 1) * layer];
            st.euler8 += euler_layer(&table, &st.prev_occ, occ, nx, ny);
            st.label_layer(k, occ);
            st.prev_occ.copy_from_slice(occ);
            std::mem::swap(&mut st.prev_lab, &mut st.cur_lab);
            if st.uf.parent.len() > limit {
                let mut live = std::mem::take(&mut st.prev_lab);
                st.compact(&mut live);
                st.prev_lab = live;
            }
        }
        progress(k1, nz);
        k0 = k1;
    }
    let empty = vec![OUTSIDE; layer];
    st.euler8 += euler_layer(&table, &st.prev_occ, &empty, nx, ny);
    st.compact(&mut []);
    st.out.percolates = percolation(&st.region, &st.spans);
    let mut out = st.out;
    out.euler = st.euler8 / 8;
    out.solid_components = out.solid_volumes.len();
    out.solid_volumes
        .sort_by(|a, b| b.partial_cmp(a).unwrap_or(std::cmp::Ordering::Equal));
    Ok(out)
}

/// Voxel index extents `[i min, i max, j min, j max, k min, k max]`.
pub(crate) type Extent = [u32; 6];

/// The extent of nothing (grows with [`grow`]).
pub(crate) const NO_EXTENT: Extent = [u32::MAX, 0, u32::MAX, 0, u32::MAX, 0];

/// `e` grown to hold `o`.
pub(crate) fn grow(e: &mut Extent, o: &Extent) {
    for a in 0..3 {
        e[2 * a] = e[2 * a].min(o[2 * a]);
        e[2 * a + 1] = e[2 * a + 1].max(o[2 * a + 1]);
    }
}

/// Whether a pore of extent `e` could still span a region whose extent is
/// now `region` along some axis (a region only grows, so a pore shorter
/// than it along every axis never percolates).
pub(crate) fn may_span(e: &Extent, region: &Extent) -> bool {
    (0..3).any(|a| {
        e[2 * a] <= region[2 * a] && e[2 * a + 1] >= region[2 * a + 1] && e[2 * a] <= e[2 * a + 1]
    })
}

/// Percolation per axis: some pore of `spans` reaches both ends of the
/// region's extent along it.
pub(crate) fn percolation(region: &Extent, spans: &[Extent]) -> [bool; 3] {
    std::array::from_fn(|a| {
        region[2 * a] <= region[2 * a + 1]
            && spans
                .iter()
                .any(|e| e[2 * a] == region[2 * a] && e[2 * a + 1] == region[2 * a + 1])
    })
}

#[derive(Default)]
pub(crate) struct Uf {
    pub(crate) parent: Vec<u32>,
    pub(crate) count: Vec<u64>,
    pub(crate) flags: Vec<u8>,
    pub(crate) kind: Vec<u8>,
    /// Voxel extents of each component.
    pub(crate) ext: Vec<Extent>,
}

impl Uf {
    pub(crate) fn make(&mut self, kind: u8) -> u32 {
        let id = self.parent.len() as u32;
        self.parent.push(id);
        self.count.push(0);
        self.flags.push(0);
        self.kind.push(kind);
        self.ext.push(NO_EXTENT);
        id
    }

    pub(crate) fn find(&mut self, mut x: u32) -> u32 {
        while self.parent[x as usize] != x {
            let p = self.parent[x as usize];
            self.parent[x as usize] = self.parent[p as usize];
            x = p;
        }
        x
    }

    pub(crate) fn union(&mut self, a: u32, b: u32) -> u32 {
        let (a, b) = (self.find(a), self.find(b));
        if a == b {
            return a;
        }
        let (keep, gone) = if a < b { (a, b) } else { (b, a) };
        self.parent[gone as usize] = keep;
        self.count[keep as usize] += self.count[gone as usize];
        self.flags[keep as usize] |= self.flags[gone as usize];
        let g = self.ext[gone as usize];
        grow(&mut self.ext[keep as usize], &g);
        keep
    }
}

pub(crate) struct State {
    pub(crate) nx: usize,
    pub(crate) ny: usize,
    pub(crate) nz: usize,
    pub(crate) voxel: f64,
    pub(crate) uf: Uf,
    pub(crate) prev_occ: Vec<u8>,
    pub(crate) prev_lab: Vec<u32>,
    pub(crate) cur_lab: Vec<u32>,
    pub(crate) out: Connectivity,
    pub(crate) euler8: i64,
    /// Extent of the voxels inside the region so far.
    pub(crate) region: Extent,
    /// Extents of the finished pore components that may still span the
    /// region ([`may_span`]).
    pub(crate) spans: Vec<Extent>,
}

impl State {
    /// Labels layer `k` into `cur_lab`, joining with `prev_lab`.
    pub(crate) fn label_layer(&mut self, k: usize, occ: &[u8]) {
        let (nx, ny) = (self.nx, self.ny);
        for j in 0..ny {
            for i in 0..nx {
                let v = i + nx * j;
                let kind = occ[v];
                if kind == OUTSIDE {
                    self.cur_lab[v] = NONE;
                    // A pore next to this voxel (below or before it) reaches
                    // the outside.
                    let mark = |l: u32, uf: &mut Uf| {
                        if l != NONE && uf.kind[l as usize] == PORE {
                            let r = uf.find(l);
                            uf.flags[r as usize] |= OUT;
                        }
                    };
                    mark(self.prev_lab[v], &mut self.uf);
                    if i > 0 {
                        mark(self.cur_lab[v - 1], &mut self.uf);
                    }
                    if j > 0 {
                        mark(self.cur_lab[v - nx], &mut self.uf);
                    }
                    continue;
                }
                let mut label = NONE;
                let mut join = |l: u32, uf: &mut Uf| {
                    if l == NONE || uf.kind[l as usize] != kind {
                        return;
                    }
                    label = if label == NONE {
                        uf.find(l)
                    } else {
                        uf.union(label, l)
                    };
                };
                if kind == PORE {
                    join(self.prev_lab[v], &mut self.uf);
                    if i > 0 {
                        join(self.cur_lab[v - 1], &mut self.uf);
                    }
                    if j > 0 {
                        join(self.cur_lab[v - nx], &mut self.uf);
                    }
                } else {
                    for dj in -1i64..=1 {
                        for di in -1i64..=1 {
                            let (ii, jj) = (i as i64 + di, j as i64 + dj);
                            if ii >= 0 && jj >= 0 && (ii as usize) < nx && (jj as usize) < ny {
                                let w = ii as usize + nx * jj as usize;
                                join(self.prev_lab[w], &mut self.uf);
                                // Voxels of this layer already visited.
                                if dj < 0 || (dj == 0 && di < 0) {
                                    join(self.cur_lab[w], &mut self.uf);
                                }
                            }
                        }
                    }
                }
                if label == NONE {
                    label = self.uf.make(kind);
                }
                let mut flags = 0u8;
                flags |= (i == 0) as u8 | ((i == nx - 1) as u8) << 1;
                flags |= ((j == 0) as u8) << 2 | ((j == ny - 1) as u8) << 3;
                flags |= ((k == 0) as u8) << 4 | ((k == self.nz - 1) as u8) << 5;
                if kind == PORE {
                    let outside_before = (i > 0 && occ[v - 1] == OUTSIDE)
                        || (j > 0 && occ[v - nx] == OUTSIDE)
                        || (k > 0 && self.prev_occ[v] == OUTSIDE)
                        || (i + 1 < nx && occ[v + 1] == OUTSIDE)
                        || (j + 1 < ny && occ[v + nx] == OUTSIDE);
                    if outside_before {
                        flags |= OUT;
                    }
                }
                let l = label as usize;
                self.uf.count[l] += 1;
                self.uf.flags[l] |= flags;
                let at = [i as u32, i as u32, j as u32, j as u32, k as u32, k as u32];
                grow(&mut self.uf.ext[l], &at);
                grow(&mut self.region, &at);
                self.cur_lab[v] = label;
            }
        }
    }

    /// Folds the components no label in `live` refers to into the totals
    /// and renumbers the rest densely.
    pub(crate) fn compact(&mut self, live: &mut [u32]) {
        let n = self.uf.parent.len();
        let mut map = vec![NONE; n];
        let mut next = Uf::default();
        for l in live.iter_mut() {
            if *l == NONE {
                continue;
            }
            let r = self.uf.find(*l) as usize;
            if map[r] == NONE {
                map[r] = next.make(self.uf.kind[r]);
                next.count[map[r] as usize] = self.uf.count[r];
                next.flags[map[r] as usize] = self.uf.flags[r];
                next.ext[map[r] as usize] = self.uf.ext[r];
            }
            *l = map[r];
        }
        for (r, &mapped) in map.iter().enumerate() {
            if self.uf.parent[r] as usize != r || mapped != NONE {
                continue;
            }
            let vol = self.uf.count[r] as f64 * self.voxel;
            let flags = self.uf.flags[r];
            if self.uf.kind[r] == SOLID {
                self.out.solid_volumes.push(vol);
            } else {
                let o = &mut self.out;
                o.pore_components += 1;
                o.pore_volume += vol;
                if flags & (OUT | 0x3f) != 0 {
                    o.open_pore_volume += vol;
                } else {
                    o.closed_pores += 1;
                    o.closed_pore_volume += vol;
                }
                let e = self.uf.ext[r];
                if may_span(&e, &self.region) {
                    self.spans.push(e);
                }
            }
        }
        self.uf = next;
    }
}

/// `8 (v - e/2 + f/4 - c/8)` for each 2x2x2 configuration of voxels around
/// a lattice vertex (bit `dx + 2 dy + 4 dz`): the vertex's share of the
/// vertices, edges, faces and cubes of the closed-voxel complex.
pub(crate) fn euler_table() -> [i64; 256] {
    let mut t = [0i64; 256];
    for (b, e8) in t.iter_mut().enumerate() {
        let set = |d: [usize; 3]| b >> (d[0] + 2 * d[1] + 4 * d[2]) & 1 == 1;
        let v = (b != 0) as i64;
        let mut edges = 0;
        let mut faces = 0;
        for a in 0..3 {
            let (p, q) = ((a + 1) % 3, (a + 2) % 3);
            for s in 0..2 {
                // Edge along a on side s: any of the four voxels with d[a] = s.
                let mut any = false;
                for u in 0..2 {
                    for w in 0..2 {
                        let mut d = [0; 3];
                        d[a] = s;
                        d[p] = u;
                        d[q] = w;
                        any |= set(d);
                    }
                }
                edges += any as i64;
            }
            // Faces normal to a: spanned by p and q in quadrant (sp, sq), in
            // the two voxels on either side along a.
            for sp in 0..2 {
                for sq in 0..2 {
                    let mut any = false;
                    for s in 0..2 {
                        let mut d = [0; 3];
                        d[a] = s;
                        d[p] = sp;
                        d[q] = sq;
                        any |= set(d);
                    }
                    faces += any as i64;
                }
            }
        }
        let cubes = b.count_ones() as i64;
        *e8 = 8 * v - 4 * edges + 2 * faces - cubes;
    }
    t
}

/// Euler contributions (times 8) of the lattice vertices between two
/// voxel layers `below` and `above`.
pub(crate) fn euler_layer(
    table: &[i64; 256],
    below: &[u8],
    above: &[u8],
    nx: usize,
    ny: usize,
) -> i64 {
    let solid = |l: &[u8], i: usize, j: usize| -> usize {
        (i >= 1 && j >= 1 && i <= nx && j <= ny && l[(i - 1) + nx * (j - 1)] == SOLID) as usize
    };
    let mut sum = 0;
    for j in 0..=ny {
        for i in 0..=nx {
            let mut b = 0;
            for (dz, l) in [below, above].into_iter().enumerate() {
                for dy in 0..2 {
                    for dx in 0..2 {
                        b |= solid(l, i + dx, j + dy) << (dx + 2 * dy + 4 * dz);
                    }
                }
            }
            if b != 0 {
                sum += table[b];
            }
        }
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Grid;
    use microfrep_core::{Expr, Shape};

    /// Compacting after every layer gives the same result as never.
    #[test]
    fn compaction_keeps_results() {
        let p = Expr::xyz();
        // Balls on a lattice, some touching: many components, and pores.
        let k = 2.0 * std::f64::consts::PI / 0.5;
        let e = ((&p[0] * k).cos() + (&p[1] * k).cos() + (&p[2] * k).cos()) - 1.2
            + 0.3 * (&p[0] * 1.7).sin();
        let t = Shape::from(&e);
        let s = Sampler::new(&t, None, Grid::new([[0.0; 3], [2.0; 3]], 48).unwrap());
        let never = label(&s, &|_, _| {}, usize::MAX).unwrap();
        let always = label(&s, &|_, _| {}, 0).unwrap();
        assert_eq!(never, always);
        assert!(never.solid_components > 1, "{never:?}");
    }

    #[test]
    fn single_voxel_windows_sum_to_one() {
        let t = euler_table();
        let total: i64 = (0..8).map(|bit| t[1 << bit]).sum();
        assert_eq!(total, 8);
        assert_eq!(t[0], 0);
    }
}
