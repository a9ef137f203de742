//! Meshing one surface brick: dense f32 sampling of its nodes, a table of
//! triangles per cell sign pattern, refinement of the vertices it owns.

use crate::check::BrickEdges;
use crate::classify::{proven_sign, unproven_cells, BrickClass};
use crate::correct::{accumulate, apply_all, Acc};
use crate::grid::Grid;
use crate::refine::{common_t_min, refine_edges, Edge};
use crate::tets::CellTable;
use microfrep_core::{BatchEval, GradBatchEval, Interval, IntervalEval, Simplify, Tape, BLOCK};

/// The part of the mesh made by one brick. Vertices on grid edges that start
/// in this brick's half-open node range are owned here; the others are
/// referenced by key and resolved against their owner when stitching.
#[derive(Default)]
pub struct BrickMesh {
    /// Final positions of the owned vertices, except those in `owned_keys`
    /// (other bricks' triangles may still add to their correction): those
    /// are as refined, neither corrected nor clamped yet.
    pub owned_pos: Vec<[f32; 3]>,
    /// (global edge key, index into `owned_pos`) of the owned vertices on
    /// the brick's lower faces (the only ones other bricks use), by key.
    pub owned_keys: Vec<(u64, u32)>,
    /// Correction sums of the vertices of `owned_keys` (same order) from
    /// this brick's triangles.
    pub shared_acc: Vec<Acc>,
    pub foreign_keys: Vec<u64>,
    /// Correction sums of the foreign vertices (order of `foreign_keys`)
    /// from this brick's triangles, for their owners.
    pub foreign_acc: Vec<Acc>,
    /// The brick's own copy of its foreign vertices and whether it sampled
    /// on a shortened tape (for the test that both copies agree).
    #[cfg(test)]
    pub foreign_pos: Vec<[f32; 3]>,
    #[cfg(test)]
    pub shortened: bool,
    /// Indices below `owned_pos.len()` are owned vertices, the rest
    /// `foreign_keys[i - owned]`.
    pub tris: Vec<[u32; 3]>,
    /// See [`unproven_cells`]; counted only in bricks with no surface.
    pub thin_cells: usize,
    /// The brick's edges for an edge census, when asked for
    /// ([`Scratch::new`]); the shared uses in the numbering of `tris`.
    pub edges: Option<BrickEdges>,
    /// Sharp features: fan triangles on segments in the brick's face
    /// planes, which may flip with a neighbour brick's.
    pub rims: Vec<Rim>,
}

/// A fan triangle `f a b` of a sharp feature ([`crate::sharp`]) whose
/// segment `a b` lies in a face plane of its brick and was not flipped
/// there: the fan of the neighbour brick's cell across that face has the
/// triangle `f' b a`, and the pipeline flips the pair as the brick does
/// within itself.
#[derive(Clone, Debug, PartialEq)]
pub struct Rim {
    /// Grid edge keys of `a` and `b`.
    pub keys: [u64; 2],
    /// Its index in [`BrickMesh::tris`].
    pub tri: u32,
    /// Positions of `f`, `a` and `b`, and the unit normals at `a` and `b`.
    pub f: [f64; 3],
    pub a: [f64; 3],
    pub b: [f64; 3],
    pub na: [f64; 3],
    pub nb: [f64; 3],
}

/// Per-thread buffers, reused from brick to brick.
pub struct Scratch {
    tape: Tape,
    /// Evaluate each brick with the tape shortened where intervals decide
    /// set-operation branches (nodes on the brick's faces, which other
    /// bricks share, with the full tape).
    simplify: bool,
    batch: BatchEval,
    interval: IntervalEval,
    vals: Vec<f32>,
    inside: Vec<u8>,
    /// Local edge -> local vertex, u32::MAX when unset, for the edges that
    /// start in two node layers: ((z & 1) * layer + y * nx + x) * stride +
    /// slot (see [`mesh_brick`]).
    vmap: Vec<u32>,
    /// Start node (x, y, z; 9 bits each) and direction (bits 27..30) of
    /// each local vertex.
    verts: Vec<u32>,
    remap: Vec<u32>,
    /// Edges to refine on the brick's own (possibly shortened) tape and on
    /// the full tape, each with the local vertex it makes.
    edges: Vec<Edge>,
    edge_of: Vec<u32>,
    full_edges: Vec<Edge>,
    full_edge_of: Vec<u32>,
    refined: Vec<[f32; 3]>,
    /// Positions of all local vertices (owned, then foreign), and their
    /// correction sums.
    pos: Vec<[f32; 3]>,
    acc: Vec<Acc>,
    tris: Vec<[u32; 3]>,
    finish: Finish,
    /// Sort each brick's edges for a census ([`BrickMesh::edges`]).
    count_edges: bool,
    /// Whether each local vertex lies in a face plane of the brick.
    face: Vec<bool>,
    /// With sharp features: the gradient evaluator of the full tape, and
    /// every surface cell as (sign pattern, its first triangle in `tris`,
    /// packed local cell coordinates).
    grad: Option<GradBatchEval>,
    cells: Vec<(u8, u32, u32)>,
    /// Whether each of `cells` has corner samples that spread
    /// ([`spread_at_corners`]).
    spread: Vec<bool>,
}

/// How a brick's vertices are finished: the grid's cell size, the volume
/// correction on or off, and the box they are clamped into.
#[derive(Clone, Copy)]
pub struct Finish {
    pub h: f64,
    pub correct: bool,
    /// Sharp features ([`crate::sharp`]; marching cubes only).
    pub sharp: bool,
    pub lo: [f32; 3],
    pub hi: [f32; 3],
}

impl Scratch {
    /// Buffers for bricks of `brick` cells; `count_edges`: sort each
    /// brick's edges for a census ([`BrickMesh::edges`]).
    pub fn new(
        tape: &Tape,
        brick: usize,
        simplify: bool,
        finish: Finish,
        count_edges: bool,
    ) -> Self {
        let nodes = (brick + 1).pow(3);
        Scratch {
            grad: finish.sharp.then(|| GradBatchEval::new(tape)),
            cells: Vec::new(),
            spread: Vec::new(),
            count_edges,
            face: Vec::new(),
            tape: tape.clone(),
            simplify,
            finish,
            edge_of: Vec::new(),
            full_edges: Vec::new(),
            full_edge_of: Vec::new(),
            refined: Vec::new(),
            pos: Vec::new(),
            acc: Vec::new(),
            batch: BatchEval::new(tape),
            interval: IntervalEval::new(tape),
            edges: Vec::new(),
            tris: Vec::new(),
            vals: vec![0.0; nodes],
            inside: vec![0; nodes],
            vmap: vec![u32::MAX; 2 * (brick + 1) * (brick + 1) * 8],
            verts: Vec::new(),
            remap: Vec::new(),
        }
    }
}

/// Where a cell edge's vertex is looked up, relative to its cell.
struct EdgeOffset {
    slot: usize,
    packed: u32,
    dz: usize,
}

/// Meshes brick `b`; `classes` gives the proven signs of shared nodes.
pub fn mesh_brick(
    grid: &Grid,
    classes: &[BrickClass],
    table: &CellTable,
    b: [usize; 3],
    s: &mut Scratch,
) -> BrickMesh {
    let (lo, n) = grid.brick_nodes(b);
    let mut local = sample(grid, lo, n, s);
    fix_signs(grid, classes, lo, n, s);
    let total = n[0] * n[1] * n[2];
    let first = s.inside[0];
    if s.inside[..total].iter().all(|&v| v == first) {
        let thin_cells = unproven_cells(&mut s.interval, grid, lo, n, first == 1);
        return BrickMesh {
            thin_cells,
            ..BrickMesh::default()
        };
    }

    // Triangles of the cells from `table`, a layer of cells at a time;
    // vertices deduplicated per local edge through `vmap`, which holds the
    // two node layers the current cell layer touches (small enough to stay
    // in cache).
    let (sx, sy) = (1, n[0]);
    let sz = n[0] * n[1];
    s.tris.clear();
    s.verts.clear();
    s.cells.clear();
    s.spread.clear();
    let sharp = s.grad.is_some();
    let mut q = vec![0u8; n[0]];
    // Per cell edge (start corner * 8 + direction): its vmap slot and packed
    // start node relative to the cell's, and which node layer it starts in.
    // Slots per node in `vmap`: 8 (by direction) when the table uses
    // diagonals, else 4 with the three axes in slots 1, 2, 3 (a smaller
    // footprint in cache).
    let axes_only = table
        .tris
        .iter()
        .flatten()
        .all(|e| (e & 7).is_power_of_two());
    let stride = if axes_only { 4 } else { 8 };
    let slot_of = |dir: usize| {
        if axes_only {
            (dir & 3) | ((dir >> 2) * 3)
        } else {
            dir
        }
    };
    let offs: [EdgeOffset; 64] = std::array::from_fn(|e| {
        let (c, dir) = (e >> 3, e & 7);
        let (dx, dy, dz) = (c & 1, (c >> 1) & 1, c >> 2);
        EdgeOffset {
            slot: (dy * sy + dx) * stride + slot_of(dir),
            packed: (dx | dy << 9 | dz << 18 | dir << 27) as u32,
            dz,
        }
    });
    for k in 0..n[2] - 1 {
        let lay = [(k & 1) * sz * stride, ((k + 1) & 1) * sz * stride];
        for j in 0..n[1] - 1 {
            let row = j * sy + k * sz;
            // Corner bits of the four node rows around this row of cells:
            // bit c for corner c = x + 2 y + 4 z, x = 0 here.
            let r = |dj: usize, dk: usize| &s.inside[row + dj * sy + dk * sz..][..n[0]];
            let (r00, r10, r01, r11) = (r(0, 0), r(1, 0), r(0, 1), r(1, 1));
            for i in 0..n[0] {
                q[i] = r00[i] | (r10[i] << 2) | (r01[i] << 4) | (r11[i] << 6);
            }
            for i in 0..n[0] - 1 {
                let mask = (q[i] | (q[i + 1] << 1)) as usize;
                if mask == 0 || mask == 255 {
                    continue;
                }
                let range = table.start[mask] as usize..table.start[mask + 1] as usize;
                let (base, pbase) = ((j * sy + i) * stride, (i | j << 9 | k << 18) as u32);
                if sharp {
                    s.cells.push((mask as u8, s.tris.len() as u32, pbase));
                    s.spread.push(spread_at_corners(&s.vals, row + i, sy, sz));
                }
                for tri in &table.tris[range] {
                    s.tris.push(tri.map(|e| {
                        let o = &offs[e as usize];
                        let v = &mut s.vmap[lay[o.dz] + base + o.slot];
                        if *v == u32::MAX {
                            *v = s.verts.len() as u32;
                            s.verts.push(pbase + o.packed);
                        }
                        *v
                    }));
                }
            }
        }
        // Node layer k is touched by no later cell layer.
        let parity = (k & 1) * sz * stride;
        s.vmap[parity..parity + sz * stride].fill(u32::MAX);
    }
    let parity = ((n[2] - 1) & 1) * sz * stride;
    s.vmap[parity..parity + sz * stride].fill(u32::MAX);
    // Owned vertices first (in creation order), then foreign ones. A vertex
    // is owned when its edge starts below the brick's upper faces (or on
    // the grid's last brick along that axis).
    let last: [bool; 3] = std::array::from_fn(|a| b[a] + 1 == grid.bricks[a]);
    let mut out = BrickMesh::default();
    s.remap.clear();
    s.remap.resize(s.verts.len(), u32::MAX);
    s.edges.clear();
    s.edge_of.clear();
    s.full_edges.clear();
    s.full_edge_of.clear();
    s.face.clear();
    let mut owned = 0u32;
    let mut foreign = 0u32;
    // Edges are at least a cell long, and their ends lie within the
    // brick's nodes.
    let t_min = {
        let (a, b) = (
            grid.node_pos(lo),
            grid.node_pos(std::array::from_fn(|k| lo[k] + n[k] - 1)),
        );
        let far = (0..3)
            .map(|k| a[k].abs().max(b[k].abs()))
            .fold(0.0, f64::max);
        common_t_min(far, grid.h)
    };
    for (vi, &packed) in s.verts.iter().enumerate() {
        let ln = [0, 9, 18].map(|sh| (packed >> sh) as usize & 511);
        let dir = (packed >> 27) as usize;
        let l = ln[0] + ln[1] * sy + ln[2] * sz;
        let g: [usize; 3] = std::array::from_fn(|a| lo[a] + ln[a]);
        let gkey = grid.node_index(g) * 8 + dir as u64;
        let e = l + (dir & 1) * sx + ((dir >> 1) & 1) * sy + ((dir >> 2) & 1) * sz;
        let end: [usize; 3] = std::array::from_fn(|a| g[a] + (dir >> a & 1));
        let (pa, pb) = (grid.node_pos(g), grid.node_pos(end));
        let (p0, p1, g0, g1) = if s.inside[l] == 1 {
            (pa, pb, s.vals[l], s.vals[e])
        } else {
            (pb, pa, s.vals[e], s.vals[l])
        };
        let edge = match t_min {
            Some(t) => Edge::with_t_min(p0, p1, g0, g1, t),
            None => Edge::new(p0, p1, g0, g1),
        };
        // Edges in a face plane are shared with a neighbour, which refines
        // them too (its foreign vertices): both do it on the full tape, so
        // both get the same bits.
        let in_face = (0..3).any(|a| (ln[a] == 0 || ln[a] + 1 == n[a]) && dir >> a & 1 == 0);
        if s.count_edges {
            s.face.push(in_face);
        }
        let at = if (0..3).all(|a| ln[a] + 1 < n[a] || last[a]) {
            s.remap[vi] = owned;
            // Only vertices on the lower faces can be wanted by other bricks.
            if ln.contains(&0) {
                out.owned_keys.push((gkey, owned));
            }
            owned += 1;
            owned - 1
        } else {
            out.foreign_keys.push(gkey);
            s.remap[vi] = u32::MAX - 1 - foreign;
            foreign += 1;
            u32::MAX - foreign
        };
        if in_face || local.is_none() {
            s.full_edges.push(edge);
            s.full_edge_of.push(at);
        } else {
            s.edges.push(edge);
            s.edge_of.push(at);
        }
    }
    // Foreign vertices follow the owned ones, in the order of `foreign_keys`.
    let to_local = |at: u32| {
        if at >= u32::MAX - foreign {
            owned + (u32::MAX - 1 - at)
        } else {
            at
        }
    };
    for r in s.remap.iter_mut() {
        *r = to_local(*r);
    }
    s.pos.clear();
    s.pos.resize((owned + foreign) as usize, [0.0; 3]);
    // The shortened tape keeps the zero set, so the roots are the same
    // (found in fewer operations).
    if let Some(ev) = local.as_mut() {
        s.refined.clear();
        refine_edges(ev, &s.edges, &mut s.refined);
        for (&at, &p) in s.edge_of.iter().zip(&s.refined) {
            s.pos[to_local(at) as usize] = p;
        }
    }
    s.refined.clear();
    refine_edges(&mut s.batch, &s.full_edges, &mut s.refined);
    for (&at, &p) in s.full_edge_of.iter().zip(&s.refined) {
        s.pos[to_local(at) as usize] = p;
    }
    // Sharp features: fans around feature vertices, owned by this brick
    // and numbered after its other owned vertices (the foreign ones move up).
    let mut pinned = Vec::new();
    if sharp {
        let (feats, pin, rims) = features(grid, lo, n, table, s);
        pinned = pin;
        out.rims = rims;
        if !feats.is_empty() {
            let nf = feats.len() as u32;
            for r in s.remap.iter_mut() {
                if *r >= owned {
                    *r += nf;
                }
            }
            s.remap.extend(owned..owned + nf);
            if s.count_edges {
                s.face.resize(s.remap.len(), false);
            }
            s.pos.splice(owned as usize..owned as usize, feats);
            owned += nf;
        }
    }
    out.owned_keys.sort_unstable();
    if s.count_edges {
        let mut e = BrickEdges::of(&s.tris, &s.face);
        for u in &mut e.shared {
            *u = u.map(|v| s.remap[v as usize]);
        }
        out.edges = Some(e);
    }
    out.tris = s
        .tris
        .iter()
        .map(|t| t.map(|v| s.remap[v as usize]))
        .collect();
    // The volume correction of this brick's triangles, while they are in
    // cache: every vertex they use is known here (foreign ones refined
    // alike by their owner). Vertices no other brick touches are final.
    let f = s.finish;
    s.acc.clear();
    s.acc.resize(s.pos.len(), [0; 6]);
    if f.correct {
        accumulate(&mut s.batch, &s.pos, &out.tris, f.h, &mut s.acc);
        if sharp {
            // Vertices of features with flat sides keep their place.
            for &v in &pinned {
                s.acc[s.remap[v as usize] as usize][5] += 1;
            }
        }
    }
    let owned = owned as usize;
    out.shared_acc = out
        .owned_keys
        .iter()
        .map(|&(_, v)| s.acc[v as usize])
        .collect();
    out.foreign_acc = s.acc[owned..].to_vec();
    #[cfg(test)]
    {
        out.foreign_pos = s.pos[owned..].to_vec();
        out.shortened = local.is_some();
    }
    out.owned_pos = s.pos[..owned].to_vec();
    let unmoved: Vec<[f32; 3]> = out
        .owned_keys
        .iter()
        .map(|&(_, v)| out.owned_pos[v as usize])
        .collect();
    apply_all(
        &mut out.owned_pos,
        &s.acc[..owned],
        &[],
        f.h,
        f.lo,
        f.hi,
        f.sharp,
    );
    for (&(_, v), &p) in out.owned_keys.iter().zip(&unmoved) {
        out.owned_pos[v as usize] = p;
    }
    out
}

/// Whether the corner samples of the cell at node `l` (strides `sy`, `sz`
/// in `vals`) could hide a feature: the gradients from the differences
/// along each corner's three cell edges differ by more than 20 degrees
/// somewhere, or one of them vanishes. A plane passes (its differences
/// are the same everywhere); only cells that fail pay for gradients. (At
/// the feature angle, 35 degrees, the tori-ball's candidates fall from
/// 768k to 451k and `--sharp` takes 11 % less time, but 0.7 % of the
/// wiffle cube's fans go, perhaps on real creases: not taken until that is
/// known.) A crease near a corner that mixes the two sides too little here
/// is found from the neighbour cells ([`features`], second pass).
fn spread_at_corners(vals: &[f32], l: usize, sy: usize, sz: usize) -> bool {
    const COS: f32 = 0.939_692_6;
    let v = |x: usize, y: usize, z: usize| vals[l + x + y * sy + z * sz];
    let g: [[f32; 3]; 8] = std::array::from_fn(|c| {
        let (x, y, z) = (c & 1, c >> 1 & 1, c >> 2);
        [
            v(1, y, z) - v(0, y, z),
            v(x, 1, z) - v(x, 0, z),
            v(x, y, 1) - v(x, y, 0),
        ]
    });
    let len = g.map(|d| (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt());
    if len
        .iter()
        .any(|&l| l.is_nan() || l <= 0.0 || !l.is_finite())
    {
        return true;
    }
    (0..8).any(|a| {
        (a + 1..8).any(|b| {
            let d = g[a][0] * g[b][0] + g[a][1] * g[b][1] + g[a][2] * g[b][2];
            d < COS * len[a] * len[b]
        })
    })
}

/// Crossings closer than this to a grid node, in cells, count as at the
/// node in [`features`].
const AT_NODE: f64 = 0.02;

/// The sharp features of the brick's cells ([`crate::sharp`]): each cycle
/// whose vertex normals spread is fanned around a new vertex (numbered
/// after the brick's local vertices, `s.remap.len()` on, in `s.tris`),
/// then crease segments shared by two fans of this brick are flipped.
/// Returns the new vertices' positions, and the vertices of every
/// feature with flat sides (fanned or not, and the feature vertex of those
/// fanned), which the volume correction leaves in place. Normals come from the full tape at
/// the vertices' positions, so a cell gets the same feature vertex in any
/// brick layout that gives it the same vertices.
fn features(
    grid: &Grid,
    lo: [usize; 3],
    n: [usize; 3],
    table: &CellTable,
    s: &mut Scratch,
) -> (Vec<[f32; 3]>, Vec<u32>, Vec<Rim>) {
    use crate::fasthash::{FastMap, FastSet};
    let cycles = crate::cubes::cycle_table();
    let h = grid.h;
    let np = s.pos.len();
    let mut normals = vec![[0.0f64; 3]; np];
    let mut done = vec![false; np];
    let first = s.remap.len() as u32;
    // Candidate fans: the feature vertex, and the cycle's triangles in
    // `s.tris` and fan triangles in `fans` (one per crossing, in order).
    let mut feats: Vec<[f32; 3]> = Vec::new();
    let mut old: Vec<std::ops::Range<usize>> = Vec::new();
    let mut old_tris: Vec<usize> = Vec::new();
    let mut fans: Vec<[u32; 3]> = Vec::new();
    let mut fan_of: Vec<usize> = Vec::new();
    let (mut vs, mut ps, mut ns) = (Vec::new(), Vec::new(), Vec::new());
    let (mut spans, mut of_cycle, mut results) = (Vec::new(), Vec::new(), Vec::new());
    let mut pinned = Vec::new();
    let mut planar = Vec::new();
    // Two passes: the cells whose corner samples spread, then the surface
    // cells beside a cell that found a feature point whose own corners
    // looked flat (a crease passing near one of their corners mixes the
    // two sides' differences too little for the corner test, and its
    // chain of feature vertices would break there).
    let mut found = vec![false; s.cells.len()];
    let mut pass: Vec<usize> = (0..s.cells.len()).filter(|&c| s.spread[c]).collect();
    for round in 0..2 {
        if round == 1 {
            // The cells were made in (z, y, x) order: those of row (y, z)
            // are `s.cells[row[y + ny z]..row[y + ny z + 1]]`, by x.
            let ny = n[1] - 1;
            let mut row = vec![0u32; ny * (n[2] - 1) + 1];
            for &(_, _, packed) in &s.cells {
                row[(packed >> 9 & 511) as usize + ny * (packed >> 18) as usize + 1] += 1;
            }
            for r in 1..row.len() {
                row[r] += row[r - 1];
            }
            let cells = &s.cells;
            let index = |q: u32| {
                let (j, k) = ((q >> 9 & 511) as usize, (q >> 18 & 511) as usize);
                if j >= ny || k + 1 >= n[2] {
                    return None;
                }
                let r = j + ny * k;
                let (a, b) = (row[r] as usize, row[r + 1] as usize);
                (a..b).find(|&c| cells[c].2 == q)
            };
            let mut next = vec![false; s.cells.len()];
            for (c, &(_, _, packed)) in s.cells.iter().enumerate() {
                if !found[c] {
                    continue;
                }
                for sh in [0, 9, 18] {
                    for q in [packed.wrapping_sub(1 << sh), packed + (1 << sh)] {
                        // Stay on the same row: the other fields unchanged.
                        let same = [0, 9, 18]
                            .iter()
                            .all(|&o| o == sh || (q >> o) & 511 == (packed >> o) & 511);
                        if let Some(d) = index(q).filter(|_| same) {
                            next[d] |= !s.spread[d];
                        }
                    }
                }
            }
            pass = (0..s.cells.len()).filter(|&c| next[c]).collect();
            if pass.is_empty() {
                break;
            }
        }
        crossing_normals(grid, lo, table, s, &pass, &mut done, &mut normals);
        // Every cycle of the pass's cells, then their feature points at
        // once (in cell units, the cell's first corner at the origin).
        vs.clear();
        ps.clear();
        ns.clear();
        spans.clear();
        of_cycle.clear();
        for &c in &pass {
            let (mask, base, packed) = s.cells[c];
            let m = mask as usize;
            let t0 = table.start[m] as usize;
            let cell = [0, 9, 18].map(|sh| (packed >> sh) as usize & 511);
            let corner = grid.node_pos(std::array::from_fn(|a| lo[a] + cell[a]));
            for (ci, cy) in cycles.cycles[cycles.start[m] as usize..cycles.start[m + 1] as usize]
                .iter()
                .enumerate()
            {
                let tris = cy.tris.start as usize..cy.tris.end as usize;
                let from = vs.len();
                for &e in &cy.edges {
                    let v = tris.clone().find_map(|t| {
                        let tri = s.tris[base as usize + t - t0];
                        table.tris[t].iter().position(|&x| x == e).map(|q| tri[q])
                    });
                    let v = v.expect("a cycle's crossings are its triangles' corners");
                    vs.push(v);
                    let i = s.remap[v as usize] as usize;
                    let p = s.pos[i];
                    ps.push(std::array::from_fn(|k| (p[k] as f64 - corner[k]) / h));
                    ns.push(normals[i]);
                }
                spans.push(from..vs.len());
                of_cycle.push((c, cycles.start[m] as usize + ci, corner));
            }
        }
        crate::sharp::feature_points(&ps, &ns, &spans, &mut results);
        for ((span, &(c, ci, corner)), feature) in spans.iter().zip(&of_cycle).zip(&results) {
            let (_, base, _) = s.cells[c];
            let t0 = table.start[s.cells[c].0 as usize] as usize;
            let cy = &cycles.cycles[ci];
            let tris = cy.tris.start as usize..cy.tris.end as usize;
            let vs = &vs[span.clone()];
            let Some(feature) = feature else {
                continue;
            };
            if feature.planar {
                pinned.extend_from_slice(vs);
            }
            let Some(x) = feature.point else {
                continue;
            };
            found[c] = true;
            planar.push(feature.planar);
            let id = first + feats.len() as u32;
            let f = feats.len();
            feats.push(std::array::from_fn(|k| (corner[k] + h * x[k]) as f32));
            let start = old_tris.len();
            old_tris.extend(tris.map(|t| base as usize + t - t0));
            old.push(start..old_tris.len());
            let n = vs.len();
            for i in 0..n {
                fans.push([id, vs[i], vs[(i + 1) % n]]);
                fan_of.push(f);
            }
        }
    }
    if feats.is_empty() {
        return (feats, pinned, Vec::new());
    }
    // Shared segments: fan triangles `f1 a b` and `f2 b a` of two cells
    // that share no other segment.
    let mut seg: FastMap<(u32, u32), usize> = FastMap::default();
    let mut pairs: FastMap<(u32, u32), u32> = FastMap::default();
    let mut shared = Vec::new();
    for (ti, t) in fans.iter().enumerate() {
        let key = (t[1].min(t[2]), t[1].max(t[2]));
        match seg.get(&key) {
            Some(&o) => {
                let f = (fans[o][0].min(t[0]), fans[o][0].max(t[0]));
                *pairs.entry(f).or_default() += 1;
                shared.push((o, ti));
            }
            None => {
                seg.insert(key, ti);
            }
        }
    }
    shared.retain(|&(o, ti)| {
        let ([f1, a, b], [f2, b2, a2]) = (fans[o], fans[ti]);
        (a2, b2) == (a, b) && f1 != f2
    });
    let single = |fans: &[[u32; 3]], o: usize, ti: usize| {
        let (f1, f2) = (fans[o][0], fans[ti][0]);
        pairs[&(f1.min(f2), f1.max(f2))] == 1
    };
    let pos = |feats: &[[f32; 3]], v: u32| -> [f64; 3] {
        let p = if v >= first {
            feats[(v - first) as usize]
        } else {
            s.pos[s.remap[v as usize] as usize]
        };
        p.map(|c| c as f64)
    };
    let normal = |v: u32| normals[s.remap[v as usize] as usize];
    let flips = |feats: &[[f32; 3]], fans: &[[u32; 3]], o: usize, ti: usize| {
        let ([f1, a, b], [f2, ..]) = (fans[o], fans[ti]);
        let p = |v| pos(feats, v);
        crate::sharp::flip(p(f1), p(f2), p(a), p(b), normal(a), normal(b), h)
    };
    // Merges: two feature vertices within half a cell of each other whose
    // shared segment does not flip (both cells found the same stretch of
    // crease, one of them just outside itself) become one, at their
    // midpoint, with the two triangles on the segment dropped: the two
    // fans join into one disk. A cell merges once at most, and only with a
    // cell whose cycle shares no crossing but the segment's two.
    let mut group: Vec<usize> = (0..feats.len()).collect();
    let mut dead = vec![false; fans.len()];
    let mut merged = vec![false; feats.len()];
    // The fan triangles of each cell are consecutive in `fans`.
    let mut fan_range = vec![0..0; feats.len()];
    for (ti, &c) in fan_of.iter().enumerate() {
        if fan_range[c].is_empty() {
            fan_range[c] = ti..ti;
        }
        fan_range[c].end = ti + 1;
    }
    let cycle_of = |c: usize| fans[fan_range[c].clone()].iter();
    for &(o, ti) in &shared {
        let (c1, c2) = (fan_of[o], fan_of[ti]);
        if merged[c1] || merged[c2] || !single(&fans, o, ti) {
            continue;
        }
        let (f1, f2) = (pos(&feats, fans[o][0]), pos(&feats, fans[ti][0]));
        let d = sub3(f1, f2);
        if (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt() > 0.5 * h || flips(&feats, &fans, o, ti)
        {
            continue;
        }
        let common = cycle_of(c1)
            .filter(|t| cycle_of(c2).any(|u| u[1] == t[1]))
            .count();
        if common != 2 {
            continue;
        }
        group[c2] = c1;
        merged[c1] = true;
        merged[c2] = true;
        feats[c1] = std::array::from_fn(|k| (0.5 * (f1[k] + f2[k])) as f32);
        dead[o] = true;
        dead[ti] = true;
    }
    for (t, &c) in fans.iter_mut().zip(&fan_of) {
        t[0] = first + group[c] as u32;
    }
    // partner[ti]: the fan triangle it flips with, if the flip is proper.
    // Two cells whose cycles share two segments (an ambiguous face) flip
    // one of them at most, so the edge `f1 f2` is made once.
    let mut partner = vec![usize::MAX; fans.len()];
    let mut joined = FastSet::default();
    for &(o, ti) in &shared {
        let (f1, f2) = (fans[o][0], fans[ti][0]);
        let fresh = !joined.contains(&(f1.min(f2), f1.max(f2)));
        if !dead[o] && f1 != f2 && fresh && flips(&feats, &fans, o, ti) {
            joined.insert((f1.min(f2), f1.max(f2)));
            partner[o] = ti;
            partner[ti] = o;
        }
    }
    // A fan (or a merged pair) is kept when each of its triangles is
    // proper or flips with a kept fan's; refusing a fan can refuse its flip
    // partners, so repeat until nothing changes.
    let ok: Vec<bool> = fans
        .iter()
        .zip(&dead)
        .map(|(&[f, a, b], &d)| {
            let p = |v| pos(&feats, v);
            // A crossing within a fiftieth of a cell of a grid node (a
            // surface through the node: its crossings on the node's edges
            // all lie beside it, a thousandth of an edge out) makes fan
            // triangles whose facing is rounding noise; refusing them would
            // cut the crease there, so they are taken whichever way they
            // face (a fold no wider than the cluster of crossings at
            // worst), if proper.
            let at_node = |q: [f64; 3]| {
                (0..3)
                    .map(|k| {
                        let u = (q[k] - grid.origin[k]) / h;
                        (u - u.round()).powi(2)
                    })
                    .sum::<f64>()
                    < AT_NODE * AT_NODE
            };
            let loose = at_node(p(a)) || at_node(p(b));
            d || crate::sharp::fan_ok(p(f), p(a), p(b), normal(a), normal(b), h, loose)
        })
        .collect();
    let mut keep = vec![true; feats.len()];
    loop {
        let mut changed = false;
        for (ti, &c) in fan_of.iter().enumerate() {
            let (g, p) = (group[c], partner[ti]);
            let flipped = p != usize::MAX && keep[group[fan_of[p]]];
            if keep[g] && !ok[ti] && !flipped {
                keep[g] = false;
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    for (ti, &c) in fan_of.iter().enumerate() {
        let p = partner[ti];
        if keep[group[c]] && p != usize::MAX && keep[group[fan_of[p]]] {
            // `f1 a b` becomes `f1 a f2`, and its partner `f2 b a` becomes
            // `f2 b f1` in its turn (the first corners do not change).
            fans[ti][2] = fans[p][0];
        }
    }
    // Number the kept feature vertices densely, in order.
    let mut new_id = vec![u32::MAX; feats.len()];
    let mut kept = Vec::new();
    for c in 0..feats.len() {
        if keep[group[c]] {
            if group[c] == c {
                new_id[c] = first + kept.len() as u32;
                if planar[c] {
                    pinned.push(new_id[c]);
                }
                kept.push(feats[c]);
            }
            for &t in &old_tris[old[c].clone()] {
                s.tris[t] = [u32::MAX; 3];
            }
        }
    }
    s.tris.retain(|t| t[0] != u32::MAX);
    // The grid edge of local vertex `v` when it lies in a face plane of the
    // brick (where a neighbour brick has the same vertex).
    let face_key = |v: u32| -> Option<u64> {
        let packed = s.verts[v as usize];
        let ln = [0, 9, 18].map(|sh| (packed >> sh) as usize & 511);
        let dir = (packed >> 27) as usize;
        let in_face = (0..3).any(|a| (ln[a] == 0 || ln[a] + 1 == n[a]) && dir >> a & 1 == 0);
        in_face.then(|| grid.node_index(std::array::from_fn(|a| lo[a] + ln[a])) * 8 + dir as u64)
    };
    let mut rims = Vec::new();
    for (ti, t) in fans.iter().enumerate() {
        if keep[group[fan_of[ti]]] && !dead[ti] {
            let at = |v: u32| {
                if v >= first {
                    new_id[(v - first) as usize]
                } else {
                    v
                }
            };
            // Not flipped here, on a segment in a face plane: a fan of the
            // neighbour brick may flip with it (`pipeline`).
            if t[2] < first {
                if let (Some(ka), Some(kb)) = (face_key(t[1]), face_key(t[2])) {
                    let p = |v: u32| s.pos[s.remap[v as usize] as usize].map(|c| c as f64);
                    rims.push(Rim {
                        keys: [ka, kb],
                        tri: s.tris.len() as u32,
                        f: feats[group[fan_of[ti]]].map(|c| c as f64),
                        a: p(t[1]),
                        b: p(t[2]),
                        na: normal(t[1]),
                        nb: normal(t[2]),
                    });
                }
            }
            s.tris.push(t.map(at));
        }
    }
    (kept, pinned, rims)
}

/// Unit outward normals, from the full tape's gradient, at the crossings of
/// the cells `pass` (indices into `s.cells`) not `done` yet; each crossing
/// first moved onto the zero set along its edge where regula falsi left it
/// off (see below).
fn crossing_normals(
    grid: &Grid,
    lo: [usize; 3],
    table: &CellTable,
    s: &mut Scratch,
    pass: &[usize],
    done: &mut [bool],
    normals: &mut [[f64; 3]],
) {
    let h = grid.h;
    let np = s.pos.len();
    // The local vertices of the candidate cells (`at[i]`: the place of
    // local vertex `i` among them), their edges and their samples.
    let mut at = vec![u32::MAX; np];
    let mut which: Vec<usize> = Vec::new();
    for &(mask, base, _) in pass.iter().map(|&c| &s.cells[c]) {
        let m = mask as usize;
        let count = (table.start[m + 1] - table.start[m]) as usize;
        for t in &s.tris[base as usize..base as usize + count] {
            for &v in t {
                let i = s.remap[v as usize] as usize;
                if at[i] == u32::MAX && !done[i] {
                    at[i] = which.len() as u32;
                    which.push(i);
                }
            }
        }
    }
    let mut edge_of = vec![(0usize, [0.0f64; 2]); which.len()];
    for (vi, &packed) in s.verts.iter().enumerate() {
        let w = at[s.remap[vi] as usize];
        if w == u32::MAX {
            continue;
        }
        let ln = [0, 9, 18].map(|sh| (packed >> sh) as usize & 511);
        let axis = ((packed >> 27) as usize).trailing_zeros() as usize;
        let a = grid.node_pos(std::array::from_fn(|k| lo[k] + ln[k]));
        let t = 1e-3 * h;
        edge_of[w as usize] = (axis, [a[axis] + t, a[axis] + h - t]);
    }
    let ev = s.grad.as_mut().expect("sharp features have a gradient");
    let mut g = vec![[0.0f32; 4]; which.len()];
    {
        let col = |k: usize| -> Vec<f32> { which.iter().map(|&i| s.pos[i][k]).collect() };
        ev.eval(&col(0), &col(1), &col(2), &mut g);
    }
    // Regula falsi leaves vertices a few hundredths of a cell off the
    // surface where their edge crosses a crease (the field has a kink
    // there); Newton steps along the edge, each kept only where it lowers
    // |f|, put them on it.
    let mut todo: Vec<usize> = Vec::new();
    let mut trial: Vec<[f32; 3]> = Vec::new();
    for _ in 0..4 {
        todo.clear();
        trial.clear();
        for (w, gi) in g.iter().enumerate() {
            let i = which[w];
            let (axis, [lo_t, hi_t]) = edge_of[w];
            let slope = gi[1 + axis];
            let len = (gi[1] * gi[1] + gi[2] * gi[2] + gi[3] * gi[3]).sqrt();
            let off = gi[0].abs() > 1e-4 * h as f32 * len;
            if !off || slope == 0.0 {
                continue;
            }
            let mut p = s.pos[i];
            let x = (p[axis] as f64 - gi[0] as f64 / slope as f64).clamp(lo_t, hi_t);
            p[axis] = x as f32;
            if p != s.pos[i] {
                todo.push(w);
                trial.push(p);
            }
        }
        if todo.is_empty() {
            break;
        }
        let col = |k: usize| -> Vec<f32> { trial.iter().map(|p| p[k]).collect() };
        let mut gt = vec![[0.0f32; 4]; todo.len()];
        ev.eval(&col(0), &col(1), &col(2), &mut gt);
        for ((&w, &p), gn) in todo.iter().zip(&trial).zip(&gt) {
            if gn[0].abs() < g[w][0].abs() {
                s.pos[which[w]] = p;
                g[w] = *gn;
            }
        }
    }
    for (&i, g) in which.iter().zip(&g) {
        done[i] = true;
        let n = &mut normals[i];
        let d = [g[1] as f64, g[2] as f64, g[3] as f64];
        let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        if len > 0.0 && len.is_finite() {
            *n = d.map(|v| -v / len);
        }
    }
}

fn sub3(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// Samples the brick's nodes in f32 batches; inside is `f >= 0` (NaN is
/// outside). Coordinates come from global node indices, so a node shared by
/// two bricks gets the same value in both. Returns the evaluator of the
/// shortened tape, where one was made.
fn sample(grid: &Grid, lo: [usize; 3], n: [usize; 3], s: &mut Scratch) -> Option<BatchEval> {
    let axis = |a: usize| -> Vec<f32> {
        (0..n[a])
            .map(|i| (grid.origin[a] + grid.h * (lo[a] + i) as f64) as f32)
            .collect()
    };
    let (xs, ys, zs) = (axis(0), axis(1), axis(2));
    let total = n[0] * n[1] * n[2];
    let mut local = None;
    if s.simplify {
        let a = grid.node_pos(lo);
        let b = grid.node_pos(std::array::from_fn(|k| lo[k] + n[k] - 1));
        let iv = |k: usize| Interval::new(a[k], b[k]);
        s.interval.eval(iv(0), iv(1), iv(2));
        local = s
            .tape
            .simplify(s.interval.values(), Simplify::Sign)
            // Worth it only when much shorter: the faces are evaluated twice.
            .filter(|t| 10 * t.len() < 7 * s.tape.len())
            .map(|t| BatchEval::new(&t));
    }
    let ev = local.as_mut().unwrap_or(&mut s.batch);
    let (mut i, mut j, mut k) = (0, 0, 0);
    let mut start = 0;
    while start < total {
        let len = BLOCK.min(total - start);
        let (bx, by, bz) = ev.coords_mut();
        for q in 0..len {
            bx[q] = xs[i];
            by[q] = ys[j];
            bz[q] = zs[k];
            i += 1;
            if i == n[0] {
                i = 0;
                j += 1;
                if j == n[1] {
                    j = 0;
                    k += 1;
                }
            }
        }
        let v = ev.eval_loaded(len);
        s.vals[start..start + len].copy_from_slice(v);
        for (d, &f) in s.inside[start..start + len].iter_mut().zip(v) {
            *d = (f >= 0.0) as u8;
        }
        start += len;
    }
    if local.is_some() {
        // Nodes on the faces are shared with the neighbours: there every
        // brick must see the same value, the full tape's.
        let (mut px, mut py, mut pz, mut at) = (vec![], vec![], vec![], vec![]);
        for k in 0..n[2] {
            for j in 0..n[1] {
                for i in 0..n[0] {
                    let face = i == 0
                        || j == 0
                        || k == 0
                        || i + 1 == n[0]
                        || j + 1 == n[1]
                        || k + 1 == n[2];
                    if face {
                        px.push(xs[i]);
                        py.push(ys[j]);
                        pz.push(zs[k]);
                        at.push(i + n[0] * (j + n[1] * k));
                    }
                }
            }
        }
        let mut out = vec![0.0f32; at.len()];
        s.batch.eval(&px, &py, &pz, &mut out);
        for (&q, &f) in at.iter().zip(&out) {
            s.vals[q] = f;
            s.inside[q] = (f >= 0.0) as u8;
        }
    }
    local
}

/// Makes the signs of nodes on the brick's faces agree with every brick
/// that shares them: the outer padding layer is outside, and nodes in a
/// brick proven empty or full take that sign.
fn fix_signs(grid: &Grid, classes: &[BrickClass], lo: [usize; 3], n: [usize; 3], s: &mut Scratch) {
    // Bricks sharing a node with this one lie among its 26 neighbours; when
    // none of them is proven empty or full (most of a dense structure), no
    // node needs the per-node search.
    let b = grid.owner_brick(lo);
    let near = |a: usize| b[a].saturating_sub(1)..(b[a] + 2).min(grid.bricks[a]);
    let any_proven = near(2).any(|z| {
        near(1)
            .any(|y| near(0).any(|x| classes[grid.brick_index([x, y, z])] != BrickClass::Surface))
    });
    let mut fix = |i: usize, j: usize, k: usize| {
        let g = [lo[0] + i, lo[1] + j, lo[2] + k];
        let l = i + n[0] * (j + n[1] * k);
        if grid.on_border(g) {
            s.inside[l] = 0;
        } else if any_proven {
            if let Some(v) = proven_sign(grid, classes, g) {
                s.inside[l] = v as u8;
            }
        }
    };
    for k in 0..n[2] {
        for j in 0..n[1] {
            let face = k == 0 || k == n[2] - 1 || j == 0 || j == n[1] - 1;
            if face {
                (0..n[0]).for_each(|i| fix(i, j, k));
            } else {
                fix(0, j, k);
                fix(n[0] - 1, j, k);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{MeshOptions, Plan};

    /// What [`BrickEdges`] relies on: for any signs at the corners of two
    /// adjacent cells, in both cell tables, every segment inside either
    /// cell or on the face between them is used once each way. (Every edge
    /// of a brick with an end off its face planes is such a segment, of two
    /// cells of the brick.) Exhaustive: 4096 patterns per axis.
    #[test]
    fn own_edges_of_any_two_cells_are_closed() {
        use std::collections::HashMap;
        for (name, table) in [
            ("cubes", crate::cubes::cell_table()),
            ("tets", crate::tets::cell_table()),
        ] {
            for axis in 0..3 {
                // Nodes of the two cells: 3 along `axis`, 2 across.
                let n: [usize; 3] = std::array::from_fn(|a| if a == axis { 3 } else { 2 });
                let node = |p: [usize; 3]| p[0] + n[0] * (p[1] + n[1] * p[2]);
                let mut checked = 0;
                for signs in 0u32..1 << 12 {
                    // Directed uses of (grid edge, grid edge), grid edges as
                    // (start node, direction), and each use's cell.
                    let mut uses: HashMap<([usize; 4], [usize; 4]), u32> = HashMap::new();
                    let mut of_cell = Vec::new();
                    for cell in 0..2 {
                        let origin: [usize; 3] =
                            std::array::from_fn(|a| (a == axis) as usize * cell);
                        let corner = |c: usize| -> [usize; 3] {
                            std::array::from_fn(|a| origin[a] + (c >> a & 1))
                        };
                        let mask = (0..8).fold(0, |m, c| m | ((signs >> node(corner(c)) & 1) << c));
                        let range = table.start[mask as usize] as usize
                            ..table.start[mask as usize + 1] as usize;
                        let key = |e: u8| {
                            let p = corner(e as usize >> 3);
                            [p[0], p[1], p[2], e as usize & 7]
                        };
                        for t in &table.tris[range] {
                            for i in 0..3 {
                                let (a, b) = (key(t[i]), key(t[(i + 1) % 3]));
                                *uses.entry((a, b)).or_default() += 1;
                                of_cell.push((a, b, origin));
                            }
                        }
                    }
                    // The faces of the cell at `origin` that contain grid
                    // edge `e` (as (axis, cell-relative side)).
                    let faces = |e: [usize; 4], origin: [usize; 3]| -> Vec<(usize, usize)> {
                        (0..3)
                            .filter(|&a| e[3] >> a & 1 == 0)
                            .map(|a| (a, e[a] - origin[a]))
                            .collect()
                    };
                    for &(a, b, origin) in &of_cell {
                        let common: Vec<_> = faces(a, origin)
                            .into_iter()
                            .filter(|f| faces(b, origin).contains(f))
                            .collect();
                        // Inside the cell, or on the face between the cells.
                        let between =
                            |&(fa, side): &(usize, usize)| fa == axis && origin[axis] + side == 1;
                        if common.is_empty() || common.iter().any(between) {
                            let there = uses[&(a, b)];
                            let back = uses.get(&(b, a)).copied().unwrap_or(0);
                            assert_eq!(
                                (there, back),
                                (1, 1),
                                "{name}, axis {axis}, signs {signs:012b}: edge {a:?} - {b:?}"
                            );
                            checked += 1;
                        }
                    }
                }
                assert!(
                    checked > 10_000,
                    "{name}, axis {axis}: {checked} uses checked"
                );
            }
        }
    }

    /// A brick computes the positions of its foreign vertices itself (for
    /// the volume correction of its triangles); they must be the owner's
    /// bits, also where either brick sampled on a shortened tape.
    #[test]
    fn foreign_vertices_are_the_owners_bits_with_shortened_tapes() {
        let e = microfrep_structures::examples::shell_lattice();
        let mut o = MeshOptions::new([[-1.1; 3], [1.1; 3]], 56);
        o.brick = 8;
        let plan = Plan::new(&microfrep_core::Shape::from(&e), &o).unwrap();
        let finish = Finish {
            h: plan.grid.h,
            correct: true,
            sharp: false,
            lo: [-1.1; 3],
            hi: [1.1; 3],
        };
        let mut s = Scratch::new(&plan.tape, plan.grid.brick, true, finish, false);
        let meshes: Vec<BrickMesh> = (0..plan.grid.brick_count())
            .map(|k| {
                if plan.classes[k] != BrickClass::Surface {
                    return BrickMesh::default();
                }
                let b = plan.grid.brick_coords(k);
                mesh_brick(&plan.grid, &plan.classes, plan.table, b, &mut s)
            })
            .collect();
        let shortened = meshes.iter().filter(|m| m.shortened).count();
        assert!(
            shortened >= 10,
            "only {shortened} bricks shortened their tape"
        );
        let mut compared = 0;
        for m in &meshes {
            for (&key, &p) in m.foreign_keys.iter().zip(&m.foreign_pos) {
                let g = &plan.grid;
                let owner = g.brick_index(g.owner_brick(g.node_from_index(key / 8)));
                let om = &meshes[owner];
                let i = om
                    .owned_keys
                    .binary_search_by_key(&key, |&(k, _)| k)
                    .expect("the owner makes the vertex");
                let q = om.owned_pos[om.owned_keys[i].1 as usize];
                assert_eq!(p.map(f32::to_bits), q.map(f32::to_bits), "edge {key}");
                compared += (m.shortened || om.shortened) as usize;
            }
        }
        assert!(
            compared > 1000,
            "{compared} vertices compared near shortened bricks"
        );
    }
}
