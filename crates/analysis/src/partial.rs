//! The measures of [`mod@crate::measure`] and [`mod@crate::connectivity`] computed
//! on ranges of voxel layers (z-slabs) of one grid, by separate processes
//! or machines, and merged into exactly what one process computes.
//!
//! # Volume and area
//! The measure works brick by brick ([`BRICK`] voxels a side) in two
//! passes, with one refinement depth for the whole grid. In parts:
//! 1. [`survey`] on each slab of whole bricks (its layers `k0..k1` start
//!    and end on brick boundaries, or at the top of the grid) measures the
//!    bricks without creased cells and lists the others with their counts;
//! 2. [`refine_depth`] of the summed counts gives the grid's depth;
//! 3. [`refine`] measures each slab's listed bricks at that depth;
//! 4. [`merge_measures`] puts every brick's measures in brick order and sums
//!    them in the order [`crate::measure::measure`] does: the result is the
//!    same bits.
//!
//! # Connectivity
//! [`label_slab`] labels layers `k0..k1` (any range), reading one layer on
//! each side for the pores' access to the outside and for the Euler
//! characteristic. Components that stay inside the slab are folded into its
//! totals; those that reach an inner face of the slab are returned with the
//! labels of its bottom and top layers, their kind, voxel count and flags.
//! [`merge_labels`] joins the labels that touch across each face
//! (6-neighbours for pores, 26 for the solid) with a union-find and folds the
//! joined components as the one-process labelling does: the counts,
//! percolation, open-pore fraction and Euler characteristic are identical,
//! the volumes equal up to the order of their floating-point sums.
//!
//! ```
//! use microfrep_analysis::{partial, measure, connectivity, Grid, Sampler};
//! use microfrep_core::{Expr, Shape};
//! use microfrep_shapes as prims;
//! let ball = Shape::new(prims::sphere(&Expr::xyz(), &prims::v3([0.0; 3]), 0.8));
//! let grid = Grid::new([[-1.0; 3], [1.0; 3]], 32).unwrap();
//! // Two slabs of 16 layers.
//! let s: Vec<_> = [(0, 16), (16, 32)]
//!     .iter()
//!     .map(|&(k0, k1)| partial::survey(&ball, None, &grid, k0, k1, &|_, _| {}).unwrap())
//!     .collect();
//! let depth = partial::refine_depth(
//!     s.iter().map(|p| p.creased).sum(),
//!     s.iter().map(|p| p.nodes).sum(),
//! );
//! let mut bricks = Vec::new();
//! for p in &s {
//!     bricks.extend(p.bricks.iter().copied());
//!     bricks.extend(partial::refine(&ball, None, &grid, depth, &p.redo, &|_, _| {}));
//! }
//! let creased = s.iter().map(|p| p.creased).sum();
//! let m = partial::merge_measures(&grid, depth, creased, bricks).unwrap();
//! assert_eq!(m, measure(&ball, None, &grid, &|_, _| {}));
//!
//! let sampler = Sampler::new(&ball, None, grid.clone());
//! let slabs: Vec<_> = [(0, 10), (10, 32)]
//!     .iter()
//!     .map(|&(k0, k1)| partial::label_slab(&sampler, k0, k1, &|_, _| {}).unwrap())
//!     .collect();
//! let c = partial::merge_labels(&grid, &slabs).unwrap();
//! assert_eq!(c.solid_components, 1);
//! assert_eq!(c.euler, connectivity(&sampler, &|_, _| {}).unwrap().euler);
//! ```

use crate::connectivity::{
    euler_layer, euler_table, grow, percolation, uf_limit, Connectivity, Extent, State, Uf, NONE,
    NO_EXTENT, OUT,
};
use crate::error::{AnalysisError, Result};
use crate::grid::{Grid, Progress, Sampler, OUTSIDE, PORE, SLAB, SOLID};
use crate::measure::{
    pass, Measures, Part, BRICK, LEAF_POINTS, MAX_DEPTH, REFINE_BUDGET, SPLIT_POINTS,
};
use crate::volume::Estimate;
use microfrep_core::Shape;

/// The measures of one brick.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BrickMeasures {
    /// Brick index: `bx + nbx (by + nby bz)` with `nb = ceil(dims / BRICK)`.
    pub brick: usize,
    /// Solid volume in the brick.
    pub volume: Estimate,
    /// Region volume in the brick.
    pub region: Estimate,
    /// Surface area in the brick.
    pub area: Estimate,
    /// Whether the brick was sampled (else proven full or empty).
    pub sampled: bool,
    /// The brick's solid volume by random samples and that estimate's
    /// variance (see [`Measures::sampled_volume`]).
    pub sampled_volume: [f64; 2],
}

/// What [`survey`] found in a slab of bricks.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Survey {
    /// Measures of the bricks without creased cells (final at any depth).
    pub bricks: Vec<BrickMeasures>,
    /// Bricks with creased cells, to measure again with [`refine`].
    pub redo: Vec<usize>,
    /// Creased top-level cells in the slab.
    pub creased: usize,
    /// Points sampled in the slab.
    pub nodes: usize,
}

/// Number of bricks per axis of `grid`.
pub fn brick_counts(grid: &Grid) -> [usize; 3] {
    grid.dims.map(|d| d.div_ceil(BRICK))
}

/// The indices of the bricks of voxel layers `k0..k1`, which must start and
/// end on brick boundaries (multiples of [`BRICK`], or the top of the grid).
pub fn bricks_of_layers(grid: &Grid, k0: usize, k1: usize) -> Result<Vec<usize>> {
    let nz = grid.dims[2];
    #[allow(clippy::manual_is_multiple_of)] // is_multiple_of is newer than rust-version 1.85
    let aligned = |k: usize| k % BRICK == 0 || k == nz;
    if !(k0 < k1 && k1 <= nz && aligned(k0) && aligned(k1)) {
        return Err(AnalysisError::Input(format!(
            "voxel layers {k0}..{k1} are not a range of whole bricks of {BRICK} layers in \
             0..{nz}"
        )));
    }
    let nb = brick_counts(grid);
    let per = nb[0] * nb[1];
    Ok((k0 / BRICK * per..k1.div_ceil(BRICK) * per).collect())
}

fn brick_measures(b: usize, p: &Part) -> BrickMeasures {
    BrickMeasures {
        brick: b,
        volume: p.volume,
        region: p.region,
        area: p.area,
        sampled: p.sampled,
        sampled_volume: p.jitter,
    }
}

/// The first pass of the measure on voxel layers `k0..k1` (whole bricks,
/// see [`bricks_of_layers`]). `progress(done, total)` counts bricks.
pub fn survey(
    solid: &Shape,
    region: Option<&Shape>,
    grid: &Grid,
    k0: usize,
    k1: usize,
    progress: Progress,
) -> Result<Survey> {
    let which = bricks_of_layers(grid, k0, k1)?;
    let parts = pass(
        solid.tape(),
        region.map(|r| r.tape()),
        grid,
        0,
        true,
        true,
        &which,
        progress,
    );
    let mut s = Survey::default();
    for (&b, p) in which.iter().zip(&parts) {
        s.creased += p.creased;
        s.nodes += p.nodes;
        if p.creased > 0 {
            s.redo.push(b);
        } else {
            s.bricks.push(brick_measures(b, p));
        }
    }
    Ok(s)
}

/// The refinement depth of a grid whose slabs surveyed `creased` creased
/// cells and `nodes` points in all: the deepest whose cost fits the work
/// budget, as [`crate::measure::measure`] chooses it.
pub fn refine_depth(creased: usize, nodes: usize) -> u32 {
    let budget = REFINE_BUDGET * nodes as f64;
    let mut depth = 0;
    let mut cost = 0.0;
    for d in (1..=MAX_DEPTH).filter(|_| creased > 0) {
        cost += (SPLIT_POINTS + 4.0 * LEAF_POINTS) * 4f64.powi(d as i32 - 1) * creased as f64;
        if cost > budget {
            break;
        }
        depth = d;
    }
    depth
}

/// The second pass: measures the `bricks` (a survey's `redo`) with creased
/// cells halved `depth` times. `progress(done, total)` counts bricks.
pub fn refine(
    solid: &Shape,
    region: Option<&Shape>,
    grid: &Grid,
    depth: u32,
    bricks: &[usize],
    progress: Progress,
) -> Vec<BrickMeasures> {
    let parts = pass(
        solid.tape(),
        region.map(|r| r.tape()),
        grid,
        depth.min(MAX_DEPTH),
        false,
        true,
        bricks,
        progress,
    );
    bricks
        .iter()
        .zip(&parts)
        .map(|(&b, p)| brick_measures(b, p))
        .collect()
}

/// The grid's measures from every brick's (each exactly once, in any
/// order), summed in brick order: the same bits as one process's.
pub fn merge_measures(
    grid: &Grid,
    depth: u32,
    creased: usize,
    bricks: impl IntoIterator<Item = BrickMeasures>,
) -> Result<Measures> {
    let nb = brick_counts(grid);
    let total = nb[0] * nb[1] * nb[2];
    let mut all: Vec<Option<BrickMeasures>> = vec![None; total];
    for b in bricks {
        let slot = all.get_mut(b.brick).ok_or_else(|| {
            AnalysisError::Input(format!("brick {} is not in the grid of {total}", b.brick))
        })?;
        if slot.is_some() {
            return Err(AnalysisError::Input(format!(
                "brick {} was measured twice",
                b.brick
            )));
        }
        *slot = Some(b);
    }
    if let Some(missing) = all.iter().position(Option::is_none) {
        return Err(AnalysisError::Input(format!(
            "brick {missing} of {total} was not measured"
        )));
    }
    let mut m = Measures {
        bricks: total,
        refine_depth: depth,
        creased_cells: creased,
        ..Measures::default()
    };
    for p in all.into_iter().flatten() {
        m.volume.add(p.volume);
        m.region_volume.add(p.region);
        m.area.add(p.area);
        m.sampled_volume += p.sampled_volume[0];
        m.sampled_volume_error += p.sampled_volume[1];
        if p.sampled {
            m.sampled_bricks += 1;
        } else {
            m.proven_volume += p.region.value;
        }
    }
    m.sampled_volume_error = m.sampled_volume_error.sqrt();
    Ok(m)
}

/// The labels of a slab of voxel layers, see the [module docs](self).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SlabLabels {
    /// First layer.
    pub k0: usize,
    /// One past the last layer.
    pub k1: usize,
    /// Totals of the components inside the slab (`solid_volumes` unsorted,
    /// `solid_components` and `euler` not set).
    pub inner: Connectivity,
    /// Eight times the Euler characteristic of the slab's lattice vertex
    /// planes (the plane below each layer, and the top of the grid in the
    /// last slab).
    pub euler8: i64,
    /// Kind ([`PORE`] or [`SOLID`]) of each boundary component.
    pub kinds: Vec<u8>,
    /// Voxels of each boundary component in the slab.
    pub counts: Vec<u64>,
    /// Flags of each boundary component: bits 0..6 faces x-, x+, y-, y+,
    /// z-, z+ of the grid, bit 6 next to a voxel outside the region.
    pub flags: Vec<u8>,
    /// Voxel extents of each boundary component, six per component:
    /// i min, i max, j min, j max, k min, k max.
    pub extents: Vec<u32>,
    /// Extent of the slab's voxels inside the region (as `extents`; an
    /// empty extent has min > max).
    pub region: [u32; 6],
    /// Extents of the slab's finished pore components that may span the
    /// whole region (six numbers each), for percolation.
    pub spans: Vec<u32>,
    /// Boundary component of each voxel of layer `k0` (`u32::MAX`: none),
    /// x fastest; empty when `k0 == 0`.
    pub bottom: Vec<u32>,
    /// The same for layer `k1 - 1`; empty when `k1` is the top of the grid.
    pub top: Vec<u32>,
}

/// Labels voxel layers `k0..k1` of `sampler`'s grid.
/// `progress(done_layers, total_layers)` counts the slab's layers.
pub fn label_slab(
    sampler: &Sampler,
    k0: usize,
    k1: usize,
    progress: Progress,
) -> Result<SlabLabels> {
    let [nx, ny, nz] = sampler.grid.dims;
    if !(k0 < k1 && k1 <= nz) {
        return Err(AnalysisError::Input(format!(
            "voxel layers {k0}..{k1} are not a range in 0..{nz}"
        )));
    }
    let layer = nx
        .checked_mul(ny)
        .filter(|&l| l < (NONE as usize) / 8)
        .ok_or_else(|| AnalysisError::Input(format!("grid layer {nx} x {ny} is too large")))?;
    let below = if k0 > 0 {
        sampler.slab(k0 - 1, k0)
    } else {
        vec![OUTSIDE; layer]
    };
    let mut st = State {
        nx,
        ny,
        nz,
        voxel: sampler.grid.voxel_volume(),
        uf: Uf::default(),
        prev_occ: below,
        prev_lab: vec![NONE; layer],
        cur_lab: vec![NONE; layer],
        out: Connectivity::default(),
        euler8: 0,
        region: NO_EXTENT,
        spans: Vec::new(),
    };
    let table = euler_table();
    let limit = uf_limit(layer);
    let mut bottom: Vec<u32> = Vec::new();
    // Compacts the union-find keeping the bottom layer's labels and `live`.
    let compact = |st: &mut State, bottom: &mut Vec<u32>, live: &mut Vec<u32>| {
        let nb = bottom.len();
        let mut keep = std::mem::take(bottom);
        keep.append(live);
        st.compact(&mut keep);
        *live = keep.split_off(nb);
        *bottom = keep;
    };
    let mut c0 = k0;
    while c0 < k1 {
        let c1 = (c0 + SLAB).min(k1);
        let slab = sampler.slab(c0, c1);
        for k in c0..c1 {
            let occ = &slab[(k - c0) * layer..(k - c0 + 1) * layer];
            st.euler8 += euler_layer(&table, &st.prev_occ, occ, nx, ny);
            st.label_layer(k, occ);
            st.prev_occ.copy_from_slice(occ);
            std::mem::swap(&mut st.prev_lab, &mut st.cur_lab);
            if k == k0 && k0 > 0 {
                bottom = st.prev_lab.clone();
            }
            if st.uf.parent.len() > limit {
                let mut live = std::mem::take(&mut st.prev_lab);
                compact(&mut st, &mut bottom, &mut live);
                st.prev_lab = live;
            }
        }
        progress(c1 - k0, k1 - k0);
        c0 = c1;
    }
    let mut top = Vec::new();
    if k1 < nz {
        // Pores of the top layer next to a voxel outside the region above.
        let above = sampler.slab(k1, k1 + 1);
        for (v, &a) in above.iter().enumerate() {
            let l = st.prev_lab[v];
            if a == OUTSIDE && l != NONE && st.uf.kind[l as usize] == PORE {
                let r = st.uf.find(l) as usize;
                st.uf.flags[r] |= OUT;
            }
        }
        top = std::mem::take(&mut st.prev_lab);
    } else {
        let empty = vec![OUTSIDE; layer];
        st.euler8 += euler_layer(&table, &st.prev_occ, &empty, nx, ny);
    }
    compact(&mut st, &mut bottom, &mut top);
    Ok(SlabLabels {
        k0,
        k1,
        inner: std::mem::take(&mut st.out),
        euler8: st.euler8,
        kinds: std::mem::take(&mut st.uf.kind),
        counts: std::mem::take(&mut st.uf.count),
        flags: std::mem::take(&mut st.uf.flags),
        extents: st.uf.ext.iter().flatten().copied().collect(),
        region: st.region,
        spans: st.spans.iter().flatten().copied().collect(),
        bottom,
        top,
    })
}

/// The grid's connectivity from the labels of slabs that tile its layers
/// (in any order).
pub fn merge_labels(grid: &Grid, slabs: &[SlabLabels]) -> Result<Connectivity> {
    let [nx, ny, nz] = grid.dims;
    let layer = nx * ny;
    let mut order: Vec<&SlabLabels> = slabs.iter().collect();
    order.sort_by_key(|s| s.k0);
    let mut next = 0;
    for s in &order {
        if s.k0 != next || s.k1 <= s.k0 {
            return Err(AnalysisError::Input(format!(
                "slabs do not tile the layers 0..{nz}: layers {next}.. expected, {}..{} given",
                s.k0, s.k1
            )));
        }
        let n = s.kinds.len();
        let plane_ok = |p: &[u32], want: bool| {
            (if want { p.len() == layer } else { p.is_empty() })
                && p.iter().all(|&l| l == NONE || (l as usize) < n)
        };
        if s.counts.len() != n
            || s.flags.len() != n
            || s.extents.len() != 6 * n
            || s.spans.len() % 6 != 0
            || !plane_ok(&s.bottom, s.k0 > 0)
            || !plane_ok(&s.top, s.k1 < nz)
        {
            return Err(AnalysisError::Input(format!(
                "labels of layers {}..{} are inconsistent with the grid of {nx} x {ny} x {nz}",
                s.k0, s.k1
            )));
        }
        next = s.k1;
    }
    if next != nz {
        return Err(AnalysisError::Input(format!(
            "slabs do not tile the layers 0..{nz}: they end at {next}"
        )));
    }
    let mut uf = Uf::default();
    let mut offset = Vec::with_capacity(order.len());
    let mut region = NO_EXTENT;
    let mut spans: Vec<Extent> = Vec::new();
    let ext = |v: &[u32]| -> Extent { std::array::from_fn(|q| v[q]) };
    for s in &order {
        offset.push(uf.parent.len() as u32);
        for i in 0..s.kinds.len() {
            let id = uf.make(s.kinds[i]) as usize;
            uf.count[id] = s.counts[i];
            uf.flags[id] = s.flags[i];
            uf.ext[id] = ext(&s.extents[6 * i..6 * i + 6]);
        }
        grow(&mut region, &s.region);
        spans.extend(s.spans.chunks_exact(6).map(ext));
    }
    for w in 0..order.len().saturating_sub(1) {
        let (a, b) = (order[w], order[w + 1]);
        let (oa, ob) = (offset[w], offset[w + 1]);
        for j in 0..ny {
            for i in 0..nx {
                let la = a.top[i + nx * j];
                if la == NONE {
                    continue;
                }
                let kind = a.kinds[la as usize];
                let mut join = |v: usize| {
                    let lb = b.bottom[v];
                    if lb != NONE && b.kinds[lb as usize] == kind {
                        uf.union(oa + la, ob + lb);
                    }
                };
                if kind == PORE {
                    join(i + nx * j);
                } else if kind == SOLID {
                    for jj in j.saturating_sub(1)..=(j + 1).min(ny - 1) {
                        for ii in i.saturating_sub(1)..=(i + 1).min(nx - 1) {
                            join(ii + nx * jj);
                        }
                    }
                }
            }
        }
    }
    // Fold the joined components as the one-process labelling does.
    let mut st = State {
        nx,
        ny,
        nz,
        voxel: grid.voxel_volume(),
        uf,
        prev_occ: Vec::new(),
        prev_lab: Vec::new(),
        cur_lab: Vec::new(),
        out: Connectivity::default(),
        euler8: 0,
        region,
        spans,
    };
    st.compact(&mut []);
    let percolates = percolation(&st.region, &st.spans);
    let mut out = st.out;
    out.percolates = percolates;
    let mut euler8 = 0;
    for s in &order {
        let c = &s.inner;
        out.solid_volumes.extend_from_slice(&c.solid_volumes);
        out.pore_components += c.pore_components;
        out.pore_volume += c.pore_volume;
        out.open_pore_volume += c.open_pore_volume;
        out.closed_pores += c.closed_pores;
        out.closed_pore_volume += c.closed_pore_volume;
        euler8 += s.euler8;
    }
    out.euler = euler8 / 8;
    out.solid_components = out.solid_volumes.len();
    out.solid_volumes
        .sort_by(|a, b| b.partial_cmp(a).unwrap_or(std::cmp::Ordering::Equal));
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{connectivity, measure};
    use microfrep_core::Expr;
    use microfrep_shapes as prims;

    /// Balls on a lattice, some touching, with a wavy offset: many solid
    /// components and pores, creases where the R-function cuts them.
    fn model() -> Shape {
        let p = Expr::xyz();
        let k = 2.0 * std::f64::consts::PI / 0.5;
        let e = ((&p[0] * k).cos() + (&p[1] * k).cos() + (&p[2] * k).cos()) - 1.2
            + 0.3 * (&p[0] * 1.7).sin();
        Shape::new(e)
    }

    fn region() -> Shape {
        Shape::new(prims::sphere(&Expr::xyz(), &prims::v3([1.0; 3]), 0.95))
    }

    fn measure_in_parts(s: &Shape, r: Option<&Shape>, g: &Grid, cuts: &[usize]) -> Measures {
        let surveys: Vec<Survey> = cuts
            .windows(2)
            .map(|w| survey(s, r, g, w[0], w[1], &|_, _| {}).unwrap())
            .collect();
        let creased = surveys.iter().map(|p| p.creased).sum();
        let depth = refine_depth(creased, surveys.iter().map(|p| p.nodes).sum());
        let mut bricks = Vec::new();
        // Slabs merged in reverse, to show the order does not matter.
        for p in surveys.iter().rev() {
            bricks.extend(refine(s, r, g, depth, &p.redo, &|_, _| {}));
            bricks.extend(p.bricks.iter().copied());
        }
        merge_measures(g, depth, creased, bricks).unwrap()
    }

    #[test]
    fn measures_in_slabs_are_the_same_bits() {
        let g = Grid::new([[0.0; 3], [2.0; 3]], 56).unwrap();
        let s = model();
        for r in [None, Some(region())] {
            let whole = measure(&s, r.as_ref(), &g, &|_, _| {});
            assert!(
                whole.volume.value > 0.1 && whole.refine_depth > 0,
                "{whole:?}"
            );
            for cuts in [&[0, 56][..], &[0, 16, 32, 48, 56], &[0, 48, 56]] {
                let parts = measure_in_parts(&s, r.as_ref(), &g, cuts);
                assert_eq!(parts, whole, "cuts {cuts:?}");
            }
        }
    }

    #[test]
    fn labels_in_slabs_merge_to_the_whole() {
        let g = Grid::new([[0.0; 3], [2.0; 3]], 48).unwrap();
        let s = model();
        for r in [None, Some(region())] {
            let sampler = Sampler::new(&s, r.as_ref(), g.clone());
            let whole = connectivity(&sampler, &|_, _| {}).unwrap();
            assert!(
                whole.solid_components > 1 && whole.pore_components >= 1,
                "{whole:?}"
            );
            for cuts in [&[0, 48][..], &[0, 1, 2, 30, 48], &[0, 7, 19, 20, 47, 48]] {
                let slabs: Vec<SlabLabels> = cuts
                    .windows(2)
                    .map(|w| label_slab(&sampler, w[0], w[1], &|_, _| {}).unwrap())
                    .collect();
                let c = merge_labels(&g, &slabs).unwrap();
                assert_eq!(c.solid_components, whole.solid_components, "{cuts:?}");
                assert_eq!(c.pore_components, whole.pore_components, "{cuts:?}");
                assert_eq!(c.closed_pores, whole.closed_pores, "{cuts:?}");
                assert_eq!(c.percolates, whole.percolates, "{cuts:?}");
                assert_eq!(c.euler, whole.euler, "{cuts:?}");
                let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs().max(1e-30);
                assert!(close(c.pore_volume, whole.pore_volume), "{cuts:?}");
                assert!(
                    close(c.open_pore_volume, whole.open_pore_volume),
                    "{cuts:?}"
                );
                assert!(close(c.closed_pore_volume, whole.closed_pore_volume));
                for (a, b) in c.solid_volumes.iter().zip(&whole.solid_volumes) {
                    assert!(close(*a, *b), "{cuts:?}");
                }
            }
        }
    }

    /// A hollow ball: a closed cavity that spans slabs, and a solid that
    /// joins only through them (Euler characteristic 2).
    #[test]
    fn cavity_across_slabs_stays_closed() {
        let p = Expr::xyz();
        let c = prims::v3([0.0; 3]);
        let shell = prims::sphere(&p, &c, 0.9).min(-prims::sphere(&p, &c, 0.5));
        let s = Shape::new(shell);
        let g = Grid::new([[-1.0; 3], [1.0; 3]], 40).unwrap();
        let sampler = Sampler::new(&s, None, g.clone());
        let slabs: Vec<SlabLabels> = [(0, 13), (13, 20), (20, 21), (21, 40)]
            .iter()
            .map(|&(a, b)| label_slab(&sampler, a, b, &|_, _| {}).unwrap())
            .collect();
        let c = merge_labels(&g, &slabs).unwrap();
        assert_eq!(c.solid_components, 1);
        assert_eq!(c.closed_pores, 1);
        assert_eq!(c.pore_components, 2);
        assert_eq!(c.euler, 2);
        assert_eq!(c.percolates, [true; 3]);
        let cavity = 4.0 / 3.0 * std::f64::consts::PI * 0.125;
        assert!((c.closed_pore_volume - cavity).abs() < 0.1 * cavity);
    }

    #[test]
    fn bad_ranges_are_refused() {
        let g = Grid::new([[0.0; 3], [1.0; 3]], 40).unwrap();
        assert!(bricks_of_layers(&g, 0, 40).is_ok());
        assert!(bricks_of_layers(&g, 32, 40).is_ok());
        assert!(bricks_of_layers(&g, 8, 40).is_err());
        assert!(bricks_of_layers(&g, 0, 41).is_err());
        let sampler = Sampler::new(&model(), None, g.clone());
        assert!(label_slab(&sampler, 5, 5, &|_, _| {}).is_err());
        let a = label_slab(&sampler, 0, 20, &|_, _| {}).unwrap();
        let e = merge_labels(&g, &[a.clone()]).unwrap_err();
        assert!(e.to_string().contains("end at 20"), "{e}");
        let e = merge_labels(&g, &[a.clone(), a]).unwrap_err();
        assert!(e.to_string().contains("tile"), "{e}");
        let b = BrickMeasures::default();
        assert!(merge_measures(&g, 0, 0, [b, b]).is_err());
        assert!(merge_measures(&g, 0, 0, [b]).is_err());
    }
}
