//! Mesh checks: edge manifoldness, orientation, degenerate and duplicate
//! elements, Euler characteristic, volume and area.

use crate::Mesh;
use rayon::prelude::*;

/// What [`check`] found in a mesh: element counts, defects, the Euler
/// characteristic and the enclosed volume and area (model units). A mesh of
/// a solid is sound when [`CheckReport::is_closed_manifold`] holds; a
/// connected one then has genus `(2 - euler) / 2`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CheckReport {
    /// Number of vertices.
    pub vertices: usize,
    /// Number of triangles.
    pub triangles: usize,
    /// Undirected edges.
    pub edges: usize,
    /// Edges not used exactly once in each direction (boundary, non-manifold
    /// or inconsistently oriented).
    pub bad_edges: usize,
    /// Triangles with a repeated index or zero area.
    pub degenerate: usize,
    /// Triangles on the same three vertices as an earlier one.
    pub duplicate_triangles: usize,
    /// Vertices at the same position as another one.
    pub duplicate_vertices: usize,
    /// V - E + F.
    pub euler: i64,
    /// Signed volume (positive for outward orientation).
    pub volume: f64,
    /// Total area of the triangles, in square model units.
    pub area: f64,
    /// Bounding box of the vertices (min, max).
    pub bbox: [[f64; 3]; 2],
}

impl CheckReport {
    /// Every edge in exactly two triangles with opposite directions, no
    /// degenerate or duplicate elements, positive volume.
    pub fn is_closed_manifold(&self) -> bool {
        self.bad_edges == 0
            && self.degenerate == 0
            && self.duplicate_triangles == 0
            && self.duplicate_vertices == 0
            && (self.triangles == 0 || self.volume > 0.0)
    }
}

fn p64(p: [f32; 3]) -> [f64; 3] {
    p.map(|v| v as f64)
}

/// Volume and area of a mesh (divergence theorem; f64 sums in a fixed order).
pub fn volume_area(mesh: &Mesh) -> (f64, f64) {
    let sums = mesh
        .triangles
        .par_chunks(crate::write::CHUNK)
        .map(|ch| chunk_volume_area(&mesh.vertices, ch))
        .collect::<Vec<_>>();
    total_volume_area(&sums)
}

/// The volume and area sums of one chunk of [`volume_area`] (triangles
/// `ts` of vertices `vs`), in its order.
pub(crate) fn chunk_volume_area(vs: &[[f32; 3]], ts: &[[u32; 3]]) -> (f64, f64) {
    let (mut v, mut a) = (0.0, 0.0);
    for t in ts {
        let [p, q, r] = t.map(|i| p64(vs[i as usize]));
        let e1 = [q[0] - p[0], q[1] - p[1], q[2] - p[2]];
        let e2 = [r[0] - p[0], r[1] - p[1], r[2] - p[2]];
        let n = [
            e1[1] * e2[2] - e1[2] * e2[1],
            e1[2] * e2[0] - e1[0] * e2[2],
            e1[0] * e2[1] - e1[1] * e2[0],
        ];
        a += 0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        v += (p[0] * (q[1] * r[2] - q[2] * r[1]) - p[1] * (q[0] * r[2] - q[2] * r[0])
            + p[2] * (q[0] * r[1] - q[1] * r[0]))
            / 6.0;
    }
    (v, a)
}

/// [`volume_area`] from the sums of its chunks ([`chunk_volume_area`] of
/// each [`crate::write::CHUNK`] triangles), added in order.
pub(crate) fn total_volume_area(sums: &[(f64, f64)]) -> (f64, f64) {
    sums.iter()
        .fold((0.0, 0.0), |(v, a), &(dv, da)| (v + dv, a + da))
}

/// What a mesher's summary reports: counts, bad edges, Euler
/// characteristic, volume, area and bounding box, in time linear in the
/// mesh (no global sort), in parallel ([`edges`]). Duplicate triangles
/// show as bad edges; coincident vertices and degenerate triangles are not
/// looked for (the mesher makes neither by construction; [`check`] counts
/// them).
pub fn summary(mesh: &Mesh) -> CheckReport {
    let nv = mesh.vertices.len();
    let (volume, area) = volume_area(mesh);
    let (edges, bad_edges) = edges(mesh);
    let bbox = bbox(mesh);
    CheckReport {
        vertices: nv,
        triangles: mesh.triangles.len(),
        edges,
        bad_edges,
        degenerate: 0,
        duplicate_triangles: 0,
        duplicate_vertices: 0,
        euler: nv as i64 - edges as i64 + mesh.triangles.len() as i64,
        volume,
        area,
        bbox,
    }
}

/// Bounding box of the vertices (min, max; infinite the wrong way round
/// when there are none).
pub fn bbox(mesh: &Mesh) -> [[f64; 3]; 2] {
    mesh.vertices
        .par_chunks(1 << 16)
        .map(|ch| {
            let mut bb = [[f64::INFINITY; 3], [f64::NEG_INFINITY; 3]];
            for p in ch {
                for a in 0..3 {
                    bb[0][a] = bb[0][a].min(p[a] as f64);
                    bb[1][a] = bb[1][a].max(p[a] as f64);
                }
            }
            bb
        })
        .reduce(
            || [[f64::INFINITY; 3], [f64::NEG_INFINITY; 3]],
            |a, b| {
                [
                    std::array::from_fn(|k| a[0][k].min(b[0][k])),
                    std::array::from_fn(|k| a[1][k].max(b[1][k])),
                ]
            },
        )
}

/// Triangles per chunk of the edge census.
const EDGE_CHUNK: usize = 1 << 15;

/// Undirected edges and bad edges of `mesh`: an edge `{a, b}` is good when
/// `a -> b` and `b -> a` are each used by exactly one triangle; an edge
/// from a vertex to itself (a triangle with a repeated corner) counts once
/// per vertex, as a bad edge. Linear time, in parallel: every directed
/// edge goes to the bucket of its lower-numbered end (vertices in ranges,
/// one parallel scatter into contiguous per-range regions), then each
/// range is sorted by its lower end by counting and each vertex's few
/// edges are grouped by the other end.
///
/// # Panics
/// When a triangle refers to a vertex that does not exist.
pub fn edges(mesh: &Mesh) -> (usize, usize) {
    let nv = mesh.vertices.len();
    if mesh.triangles.is_empty() {
        return (0, 0);
    }
    // Ranges of 2^shift vertices, about 256 of them (at least 4096 each).
    let shift = (nv.max(1).div_ceil(256).next_power_of_two().trailing_zeros()).max(12);
    let ranges = (nv >> shift) + 1;
    let low = |t: &[u32; 3], k: usize| t[k].min(t[(k + 1) % 3]);
    // Per chunk of triangles, directed edges per range.
    let counts: Vec<Vec<u32>> = mesh
        .triangles
        .par_chunks(EDGE_CHUNK)
        .map(|ch| {
            let mut c = vec![0u32; ranges];
            for t in ch {
                for k in 0..3 {
                    let v = low(t, k) as usize;
                    assert!(
                        v < nv && t[k].max(t[(k + 1) % 3]) < nv as u32,
                        "triangle refers to a vertex past {nv}"
                    );
                    c[v >> shift] += 1;
                }
            }
            c
        })
        .collect();
    // Range r's region holds its edges from chunk 0, then chunk 1, ...
    let mut buf = vec![0u64; 3 * mesh.triangles.len()];
    let mut slots: Vec<Vec<&mut [u64]>> = counts.iter().map(|_| Vec::new()).collect();
    let mut regions: Vec<&mut [u64]> = Vec::with_capacity(ranges);
    {
        let mut rest = &mut buf[..];
        for r in 0..ranges {
            let len: usize = counts.iter().map(|c| c[r] as usize).sum();
            let (region, tail) = rest.split_at_mut(len);
            rest = tail;
            regions.push(region);
        }
    }
    // Split each region into its chunks' parts (the regions stay borrowed
    // through the parts).
    let mut bounds = Vec::with_capacity(ranges);
    for (r, region) in regions.into_iter().enumerate() {
        bounds.push(region.len());
        let mut rest = region;
        for (c, cnt) in counts.iter().enumerate() {
            let (part, tail) = rest.split_at_mut(cnt[r] as usize);
            rest = tail;
            slots[c].push(part);
        }
    }
    // Scatter: entry = (lower end - range start) << 33 | upper end << 1 |
    // (1 when the edge runs from the lower end to the upper).
    mesh.triangles
        .par_chunks(EDGE_CHUNK)
        .zip(slots.par_iter_mut())
        .for_each(|(ch, parts)| {
            let mut at = vec![0usize; ranges];
            for t in ch {
                for k in 0..3 {
                    let (a, b) = (t[k], t[(k + 1) % 3]);
                    let (lo, hi) = (a.min(b) as u64, a.max(b) as u64);
                    let r = (lo >> shift) as usize;
                    let local = lo - ((r as u64) << shift);
                    parts[r][at[r]] = local << 33 | hi << 1 | (a < b) as u64;
                    at[r] += 1;
                }
            }
        });
    drop(slots);
    // Per range: counting sort by lower end, then each vertex's edges.
    let mut regions: Vec<&[u64]> = Vec::with_capacity(ranges);
    let mut rest = &buf[..];
    for len in bounds {
        let (region, tail) = rest.split_at(len);
        rest = tail;
        regions.push(region);
    }
    let size = 1usize << shift;
    regions
        .par_iter()
        .map_init(
            || {
                (
                    Vec::<u8>::new(),
                    Vec::<u64>::new(),
                    Vec::<u32>::new(),
                    Vec::<u64>::new(),
                )
            },
            |(len, table, start, sorted), region| {
                census_by_table(region, size, len, table)
                    .unwrap_or_else(|| census_by_sort(region, size, start, sorted))
            },
        )
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1))
}

/// Distinct upper ends one vertex's table holds in [`census_by_table`].
const FAN: usize = 8;

/// Edges and bad edges of one range's entries (see [`edges`]) by a table
/// of up to [`FAN`] distinct upper ends per lower end, each with its
/// counts of uses either way: one pass over the entries, no sort. `None`
/// when a vertex has more upper neighbours than that (the caller then
/// sorts).
fn census_by_table(
    region: &[u64],
    size: usize,
    len: &mut Vec<u8>,
    table: &mut Vec<u64>,
) -> Option<(usize, usize)> {
    len.clear();
    len.resize(size, 0);
    // Slots need no clearing: only the first `len[v]` of a vertex's are read.
    table.resize(size * FAN, 0);
    // Slot = upper end << 8 | uses lower -> upper << 4 | uses upper ->
    // lower, each count saturating at 15.
    for &e in region {
        let v = (e >> 33) as usize;
        let hi = (e >> 1) & 0xffff_ffff;
        let one = if e & 1 == 1 { 0x10 } else { 0x01 };
        let n = len[v] as usize;
        let fan = &mut table[v * FAN..v * FAN + FAN];
        match fan[..n].iter().position(|s| s >> 8 == hi) {
            Some(i) => {
                let s = &mut fan[i];
                let c = if one == 0x10 {
                    (*s >> 4) & 0xf
                } else {
                    *s & 0xf
                };
                if c < 15 {
                    *s += one;
                }
            }
            None if n < FAN => {
                fan[n] = hi << 8 | one;
                len[v] += 1;
            }
            None => return None,
        }
    }
    let (mut e, mut b) = (0usize, 0usize);
    for (v, &n) in len.iter().enumerate() {
        for s in &table[v * FAN..v * FAN + n as usize] {
            e += 1;
            // Good: once each way. A repeated corner (upper end = lower
            // end) only ever counts as a use upper -> lower: never good.
            if s & 0xff != 0x11 {
                b += 1;
            }
        }
    }
    Some((e, b))
}

/// [`census_by_table`] for any range: a counting sort of the entries by
/// lower end, then each vertex's edges sorted by upper end.
fn census_by_sort(
    region: &[u64],
    size: usize,
    start: &mut Vec<u32>,
    sorted: &mut Vec<u64>,
) -> (usize, usize) {
    start.clear();
    start.resize(size + 1, 0);
    for &e in region.iter() {
        start[(e >> 33) as usize + 1] += 1;
    }
    for i in 0..size {
        start[i + 1] += start[i];
    }
    sorted.clear();
    sorted.resize(region.len(), 0);
    for &e in region.iter() {
        let s = &mut start[(e >> 33) as usize];
        sorted[*s as usize] = e;
        *s += 1;
    }
    // `start[i]` is now the end of vertex i's edges.
    let (mut e, mut b) = (0usize, 0usize);
    let mut from = 0usize;
    for &to in &start[..size] {
        let to = to as usize;
        let fan = &mut sorted[from..to];
        from = to;
        if fan.is_empty() {
            continue;
        }
        fan.sort_unstable();
        let mut i = 0;
        while i < fan.len() {
            let hi = (fan[i] >> 1) & 0xffff_ffff;
            let mut j = i;
            let (mut ups, mut downs) = (0, 0);
            while j < fan.len() && (fan[j] >> 1) & 0xffff_ffff == hi {
                if fan[j] & 1 == 1 {
                    ups += 1;
                } else {
                    downs += 1;
                }
                j += 1;
            }
            e += 1;
            // A repeated corner (upper end = lower end) only ever counts
            // as `downs`: never good.
            if ups != 1 || downs != 1 {
                b += 1;
            }
            i = j;
        }
    }
    (e, b)
}

/// Distinct upper neighbours a vertex holds in [`EdgeCensus`]'s table.
const OPEN_FAN: usize = 8;

/// `Row::len` of a vertex whose edges went to the side list.
const SPILLED: u8 = u8::MAX;

/// A use lower end -> upper end, and one back, in `Row::uses`.
const UP: u8 = 0x10;
const DOWN: u8 = 0x01;
/// The uses of a good edge: once each way.
const GOOD: u8 = UP + DOWN;

/// One open vertex of [`EdgeCensus`], half a cache line: its distinct
/// upper neighbours (as upper minus lower end) and, for each, its uses
/// either way (`UP` and `DOWN` counts, four bits each, stuck at 15).
#[derive(Clone, Copy)]
#[repr(C, align(32))]
struct Row {
    keys: [u16; OPEN_FAN],
    uses: [u8; OPEN_FAN],
    /// The vertex the row now belongs to; a row of another is empty.
    tag: u32,
    len: u8,
}

const EMPTY_ROW: Row = Row {
    keys: [0; OPEN_FAN],
    uses: [0; OPEN_FAN],
    tag: u32::MAX,
    len: 0,
};

/// The edge census of [`edges`], taken while a mesh streams in the order a
/// [`crate::sink::MeshSink`] receives it: one pass over the triangles as
/// they come, no buffer of the mesh's edges, and exact:
/// [`EdgeCensus::finish`] gives the counts of [`edges`], or `None` when
/// the mesh did not come in the order the census relies on (the caller then
/// counts with [`edges`], which needs no order).
///
/// Every directed edge is recorded at its lower-numbered end, in a table of
/// the vertices still open: up to eight distinct upper neighbours each
/// (within 65535 of it), with their counts of uses either way; a vertex
/// with more, and an edge with ends farther apart, go to a side list that
/// is sorted at the end. Edges and good edges are counted as the uses come.
/// It relies on the order in which the meshing pipeline emits a mesh: a
/// batch of triangles only uses vertices of the last two batches of
/// vertices. So when a batch of vertices arrives, the vertices before the
/// previous batch are closed and their rows free for new ones; a triangle
/// naming a closed vertex as the lower end of an edge (or a vertex not yet
/// received) makes the census incomplete. The table takes 32 bytes per
/// open vertex (two batches).
///
/// From the meshing pipeline, a sink can take each brick's edges instead
/// of its triangles ([`EdgeCensus::brick`], [`BrickEdges`]): the edges only
/// that brick uses are closed by construction and counted whole, and only
/// those where bricks are stitched together (a few percent) are looked up
/// use by use. That costs about a tenth of the census by triangles (which
/// is compute-bound, about 25 ns a triangle).
pub struct EdgeCensus {
    /// Vertices received.
    next: u64,
    /// Vertices below this are closed.
    closed: u64,
    /// First vertex of the latest batch (closed when the next one comes).
    latest: u64,
    /// Rows of the open vertices, at `vertex & (rows.len() - 1)`.
    rows: Vec<Row>,
    /// Edges of spilled vertices and of far ends: (lower, upper, use).
    side: Vec<(u32, u32, u8)>,
    /// Distinct edges in the table, and those of them used once each way.
    edges: u64,
    good: u64,
    /// An edge named a closed or unknown vertex, or a brick's counts did
    /// not add up ([`EdgeCensus::brick`]).
    out_of_order: bool,
}

impl Default for EdgeCensus {
    fn default() -> Self {
        Self::new()
    }
}

/// Adds one use (`UP` or `DOWN`) of the edge to the upper neighbour `key`
/// to `row` (of vertex `tag`); the change to the distinct edges and to the
/// good ones, or `None`, unchanged, when the row is spilled or full without
/// the key.
#[inline(always)]
fn add(row: &mut Row, tag: u32, key: u16, one: u8) -> Option<(u64, i64)> {
    if row.tag != tag {
        row.tag = tag;
        row.len = 0;
    }
    let n = row.len as usize;
    if n > OPEN_FAN {
        return None;
    }
    let mut hit = 0u32;
    for (i, &k) in row.keys.iter().enumerate() {
        hit |= ((k == key) as u32) << i;
    }
    // Only the first `n` keys are the vertex's (the rest are stale).
    hit &= (1u32 << n) - 1;
    if hit == 0 && n == OPEN_FAN {
        return None;
    }
    let found = hit != 0;
    let i = if found {
        hit.trailing_zeros() as usize
    } else {
        n
    };
    row.keys[i] = key;
    let u = if found { row.uses[i] } else { 0 };
    let v = bump(u, one);
    row.uses[i] = v;
    row.len = (n + !found as usize) as u8;
    Some((!found as u64, (v == GOOD) as i64 - (u == GOOD) as i64))
}

/// Counts `u` with one more use `one` (`UP` or `DOWN`); each count sticks
/// at 15 (never good again).
#[inline(always)]
fn bump(u: u8, one: u8) -> u8 {
    let stuck = if one == UP {
        u >= 0xf0
    } else {
        u & 0x0f == 0x0f
    };
    if stuck {
        u
    } else {
        u + one
    }
}

/// [`add`] for two uses of one row, to two different keys: both or (the
/// row unchanged) neither.
#[inline(always)]
fn add2(row: &mut Row, tag: u32, uses: [(u16, u8); 2]) -> Option<(u64, i64)> {
    if row.tag != tag {
        row.tag = tag;
        row.len = 0;
    }
    let n = row.len as usize;
    if n > OPEN_FAN - 2 {
        // Spilled, or maybe too full for both: one at a time.
        let mut copy = *row;
        let a = add(&mut copy, tag, uses[0].0, uses[0].1)?;
        let b = add(&mut copy, tag, uses[1].0, uses[1].1)?;
        *row = copy;
        return Some((a.0 + b.0, a.1 + b.1));
    }
    let (mut h0, mut h1) = (0u32, 0u32);
    for (i, &k) in row.keys.iter().enumerate() {
        h0 |= ((k == uses[0].0) as u32) << i;
        h1 |= ((k == uses[1].0) as u32) << i;
    }
    let valid = (1u32 << n) - 1;
    let (h0, h1) = (h0 & valid, h1 & valid);
    let i0 = if h0 != 0 {
        h0.trailing_zeros() as usize
    } else {
        n
    };
    let n1 = n + (h0 == 0) as usize;
    let i1 = if h1 != 0 {
        h1.trailing_zeros() as usize
    } else {
        n1
    };
    let mut g = 0i64;
    for (i, found, (key, one)) in [(i0, h0 != 0, uses[0]), (i1, h1 != 0, uses[1])] {
        row.keys[i] = key;
        let u = if found { row.uses[i] } else { 0 };
        let v = bump(u, one);
        row.uses[i] = v;
        g += (v == GOOD) as i64 - (u == GOOD) as i64;
    }
    row.len = (n1 + (h1 == 0) as usize) as u8;
    Some(((h0 == 0) as u64 + (h1 == 0) as u64, g))
}

impl EdgeCensus {
    /// An empty census.
    pub fn new() -> Self {
        EdgeCensus {
            next: 0,
            closed: 0,
            latest: 0,
            rows: Vec::new(),
            side: Vec::new(),
            edges: 0,
            good: 0,
            out_of_order: false,
        }
    }

    /// The next `n` vertices arrive (one batch, as
    /// [`crate::sink::MeshSink::vertices`] receives them); the vertices
    /// before the previous batch are closed.
    pub fn vertices(&mut self, n: usize) {
        self.closed = self.latest;
        self.latest = self.next;
        self.next += n as u64;
        let open = (self.next - self.closed) as usize;
        if open > self.rows.len() {
            // More rows, a power of two, for the next batch too if it is
            // like this one; the open rows move to their new places.
            let len = open.max(2 * n + n / 8).next_power_of_two().max(1024);
            let mut rows = vec![EMPTY_ROW; len];
            let old = self.rows.len().wrapping_sub(1);
            for (i, r) in self.rows.iter().enumerate() {
                let t = r.tag as usize;
                if (self.closed..self.latest).contains(&(t as u64)) && t & old == i {
                    rows[t & (len - 1)] = *r;
                }
            }
            self.rows = rows;
        }
    }

    /// The next triangles, in the order they arrive.
    pub fn triangles(&mut self, t: &[[u32; 3]]) {
        if self.rows.is_empty() {
            self.out_of_order |= !t.is_empty();
            return;
        }
        let mask = self.rows.len() - 1;
        let (closed, next) = (self.closed, self.next);
        let (mut edges, mut good) = (0u64, 0i64);
        for tri in t {
            // Corners sorted, x < y < z, and whether a -> b -> c runs
            // x -> y -> z (even) or x -> z -> y (odd). x holds the edges to
            // y and to z, y the edge to z.
            let [a, b, c] = *tri;
            let (mut x, mut y, mut z) = (a, b, c);
            let mut odd = false;
            if x > y {
                (x, y) = (y, x);
                odd = !odd;
            }
            if y > z {
                (y, z) = (z, y);
                odd = !odd;
            }
            if x > y {
                (x, y) = (y, x);
                odd = !odd;
            }
            // Rare: a repeated corner, out of order, ends far apart.
            if x == y || y == z || (x as u64) < closed || z as u64 >= next || z - x > 0xffff {
                for (p, q) in [(a, b), (b, c), (c, a)] {
                    self.edge(p.min(q), p.max(q), if p < q { UP } else { DOWN });
                }
                continue;
            }
            // Even: x -> y, y -> z, z -> x; odd: the other way round.
            let (fwd, back) = if odd { (DOWN, UP) } else { (UP, DOWN) };
            let (ky, kz) = ((y - x) as u16, (z - x) as u16);
            match add2(
                &mut self.rows[x as usize & mask],
                x,
                [(ky, fwd), (kz, back)],
            ) {
                Some((e, g)) => {
                    edges += e;
                    good += g;
                }
                None => {
                    self.edge(x, y, fwd);
                    self.edge(x, z, back);
                }
            }
            match add(&mut self.rows[y as usize & mask], y, (z - y) as u16, fwd) {
                Some((e, g)) => {
                    edges += e;
                    good += g;
                }
                None => self.edge(y, z, fwd),
            }
        }
        self.edges += edges;
        self.good = (self.good as i64 + good) as u64;
    }

    /// One use of the edge from `lo` to `hi` through every check.
    #[cold]
    fn edge(&mut self, lo: u32, hi: u32, one: u8) {
        if (lo as u64) < self.closed || hi as u64 >= self.next {
            self.out_of_order = true;
            return;
        }
        let r = lo as usize & (self.rows.len() - 1);
        let spilled = self.rows[r].tag == lo && self.rows[r].len == SPILLED;
        // Ends far apart (every use of such an edge has them, so all go to
        // the side list) or a spilled vertex.
        if hi - lo > 0xffff || spilled {
            self.side.push((lo, hi, one));
            return;
        }
        if let Some((e, g)) = add(&mut self.rows[r], lo, (hi - lo) as u16, one) {
            self.edges += e;
            self.good = (self.good as i64 + g) as u64;
            return;
        }
        // Full: the vertex's uses move to the side list.
        let row = self.rows[r];
        for (&key, &u) in row.keys.iter().zip(&row.uses) {
            let up = (u >> 4, UP);
            let down = (u & 0x0f, DOWN);
            for (times, what) in [up, down] {
                for _ in 0..times {
                    self.side.push((lo, lo + key as u32, what));
                }
            }
            self.edges -= 1;
            self.good -= (u == GOOD) as u64;
        }
        self.rows[r].len = SPILLED;
        self.side.push((lo, hi, one));
    }

    /// The edges of one brick's triangles, in their order (after the
    /// brick's vertices, like [`EdgeCensus::triangles`]): its own edges
    /// whole, closed by construction, and the uses of its shared ones one
    /// by one (see [`BrickEdges`]).
    pub fn brick(&mut self, e: &BrickEdges) {
        // Every own edge is used once each way: an odd count cannot be,
        // and leaves the census unsure rather than wrong.
        self.out_of_order |= e.own_uses % 2 == 1;
        self.edges += e.own_uses / 2;
        self.good += e.own_uses / 2;
        // A few percent of the uses: the careful path is quick enough.
        for &[p, q] in &e.shared {
            let (lo, hi, one) = if p < q { (p, q, UP) } else { (q, p, DOWN) };
            self.edge(lo, hi, one);
        }
    }

    /// Undirected edges and bad edges, as [`edges`] counts them; `None`
    /// when a triangle named a vertex already closed or not yet received
    /// (or a brick's counts did not add up).
    pub fn finish(mut self) -> Option<(usize, usize)> {
        if self.out_of_order {
            return None;
        }
        self.side.sort_unstable();
        for run in self.side.chunk_by(|p, q| (p.0, p.1) == (q.0, q.1)) {
            let ups = run.iter().filter(|u| u.2 == UP).count();
            self.edges += 1;
            self.good += (ups == 1 && run.len() == 2) as u64;
        }
        Some((self.edges as usize, (self.edges - self.good) as usize))
    }
}

/// The edges of one brick's triangles as the census of the whole mesh
/// ([`EdgeCensus::brick`]) takes them, made while the brick meshes.
///
/// A mesh vertex lies on a grid edge. One off the brick's face planes
/// bounds cells of this brick only, so only this brick's triangles use it,
/// and every edge with such an end (most edges: all but a few percent) has
/// all its uses here. Those edges are closed by construction: each is a
/// segment inside one cell, or on a face between two cells of the brick,
/// and the cell tables give every such segment once each way, for any
/// signs at the corners (checked for every pattern of two adjacent cells,
/// in both tables, by `own_edges_of_any_two_cells_are_closed`). They are
/// counted, not looked up: an edge per two uses. The edges with both ends
/// in face planes, where bricks are stitched together, are the ones the
/// census checks use by use (`shared`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BrickEdges {
    /// Uses of the brick's own edges (twice their number).
    pub own_uses: u64,
    /// Directed uses `[from, to]` of the edges with both ends in face
    /// planes, in triangle order.
    pub shared: Vec<[u32; 2]>,
}

impl BrickEdges {
    /// Sorts the edge uses of `tris` (vertices `0..face.len()`; `face[v]`:
    /// vertex `v` lies in a face plane of the brick).
    ///
    /// # Panics
    /// When a triangle names a vertex past `face.len()`.
    pub fn of(tris: &[[u32; 3]], face: &[bool]) -> BrickEdges {
        let mut shared = Vec::new();
        for t in tris {
            for (p, q) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                if face[p as usize] & face[q as usize] {
                    shared.push([p, q]);
                }
            }
        }
        BrickEdges {
            own_uses: 3 * tris.len() as u64 - shared.len() as u64,
            shared,
        }
    }
}

/// The full check: [`summary`]'s figures plus degenerate and duplicate
/// triangles and coincident vertices (sorting; for tests and audits).
pub fn check(mesh: &Mesh) -> CheckReport {
    let nv = mesh.vertices.len();
    let (volume, area) = volume_area(mesh);

    // Directed half-edges a -> b as a << 32 | b, sorted.
    let mut half: Vec<u64> = mesh
        .triangles
        .par_iter()
        .flat_map_iter(|t| (0..3).map(move |k| ((t[k] as u64) << 32) | t[(k + 1) % 3] as u64))
        .collect();
    half.par_sort_unstable();
    let count = |h: u64| -> usize {
        let s = half.partition_point(|&x| x < h);
        half[s..].iter().take_while(|&&x| x == h).count()
    };
    // An undirected edge {a, b} is good when a->b and b->a occur once each;
    // it is examined from its smaller end.
    let mut edges = 0;
    let mut bad_edges = 0;
    let mut i = 0;
    while i < half.len() {
        let h = half[i];
        let mut j = i;
        while j < half.len() && half[j] == h {
            j += 1;
        }
        let (a, b) = (h >> 32, h & 0xffff_ffff);
        let rev = (b << 32) | a;
        let n_rev = count(rev);
        if a < b || n_rev == 0 {
            edges += 1;
            if j - i != 1 || n_rev != 1 {
                bad_edges += 1;
            }
        }
        i = j;
    }

    let degenerate = mesh
        .triangles
        .par_iter()
        .filter(|t| {
            if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                return true;
            }
            let [p, q, r] = t.map(|i| p64(mesh.vertices[i as usize]));
            let e1 = [q[0] - p[0], q[1] - p[1], q[2] - p[2]];
            let e2 = [r[0] - p[0], r[1] - p[1], r[2] - p[2]];
            let n = [
                e1[1] * e2[2] - e1[2] * e2[1],
                e1[2] * e2[0] - e1[0] * e2[2],
                e1[0] * e2[1] - e1[1] * e2[0],
            ];
            n == [0.0; 3]
        })
        .count();

    let mut sorted: Vec<[u32; 3]> = mesh
        .triangles
        .par_iter()
        .map(|t| {
            let mut s = *t;
            s.sort_unstable();
            s
        })
        .collect();
    sorted.par_sort_unstable();
    let duplicate_triangles = sorted.windows(2).filter(|w| w[0] == w[1]).count();
    drop(sorted);

    let mut pos: Vec<[u32; 3]> = mesh
        .vertices
        .par_iter()
        .map(|p| p.map(|v| (v + 0.0).to_bits()))
        .collect();
    pos.par_sort_unstable();
    let duplicate_vertices = pos.windows(2).filter(|w| w[0] == w[1]).count();

    let mut bbox = [[f64::INFINITY; 3], [f64::NEG_INFINITY; 3]];
    for p in &mesh.vertices {
        for a in 0..3 {
            bbox[0][a] = bbox[0][a].min(p[a] as f64);
            bbox[1][a] = bbox[1][a].max(p[a] as f64);
        }
    }
    CheckReport {
        vertices: nv,
        triangles: mesh.triangles.len(),
        edges,
        bad_edges,
        degenerate,
        duplicate_triangles,
        duplicate_vertices,
        euler: nv as i64 - edges as i64 + mesh.triangles.len() as i64,
        volume,
        area,
        bbox,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetra() -> Mesh {
        Mesh {
            vertices: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        }
    }

    #[test]
    fn tetrahedron_is_closed_with_known_volume_and_area() {
        let r = check(&tetra());
        assert!(r.is_closed_manifold(), "{r:?}");
        assert_eq!((r.edges, r.euler), (6, 2));
        assert!((r.volume - 1.0 / 6.0).abs() < 1e-12);
        let area = 1.5 + 3f64.sqrt() / 2.0;
        assert!((r.area - area).abs() < 1e-6);
    }

    #[test]
    fn summary_agrees_with_the_full_check() {
        let mut meshes = vec![tetra()];
        let mut m = tetra();
        m.triangles[3] = [1, 3, 2];
        meshes.push(m);
        let mut m = tetra();
        m.triangles.pop();
        meshes.push(m);
        let mut m = tetra();
        m.triangles.push([3, 2, 1]);
        meshes.push(m);
        for m in &meshes {
            let (s, c) = (summary(m), check(m));
            assert_eq!(
                (s.edges, s.bad_edges, s.euler, s.volume, s.area, s.bbox),
                (c.edges, c.bad_edges, c.euler, c.volume, c.area, c.bbox),
                "{m:?}"
            );
        }
    }

    /// Edges and bad edges by a map of directed-edge counts: the definition
    /// [`edges`] implements (a self-loop is one bad edge).
    fn edges_by_map(m: &Mesh) -> (usize, usize) {
        let mut count = std::collections::BTreeMap::<(u32, u32), usize>::new();
        for t in &m.triangles {
            for k in 0..3 {
                *count.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
            }
        }
        let (mut e, mut b) = (0, 0);
        let mut seen = std::collections::BTreeSet::new();
        for &(a, c) in count.keys() {
            let key = (a.min(c), a.max(c));
            if !seen.insert(key) {
                continue;
            }
            e += 1;
            let n = |x, y| count.get(&(x, y)).copied().unwrap_or(0);
            if a == c || n(key.0, key.1) != 1 || n(key.1, key.0) != 1 {
                b += 1;
            }
        }
        (e, b)
    }

    /// `n` tetrahedra with scrambled vertex numbers (`4 n` vertices, so
    /// several ranges of the census and edges between them), some faces
    /// flipped, dropped, doubled or degenerate.
    fn scrambled(n: u32) -> Mesh {
        let nv = 4 * n;
        let perm = |i: u32| ((i as u64 * 7919 + 13) % nv as u64) as u32;
        let mut m = Mesh {
            vertices: vec![[0.0; 3]; nv as usize],
            triangles: Vec::new(),
        };
        for k in 0..n {
            let v = |i: u32| perm(4 * k + i);
            let mut faces = vec![
                [v(0), v(2), v(1)],
                [v(0), v(1), v(3)],
                [v(0), v(3), v(2)],
                [v(1), v(2), v(3)],
            ];
            match k % 7 {
                1 => faces[3] = [v(1), v(3), v(2)],
                2 => {
                    faces.pop();
                }
                3 => faces.push([v(3), v(2), v(1)]),
                4 => faces.push([v(1), v(1), v(2)]),
                _ => {}
            }
            m.triangles.extend(faces);
        }
        m
    }

    #[test]
    fn edge_census_matches_the_definition_across_vertex_ranges() {
        let n = 5000;
        let m = scrambled(n);
        let got = edges(&m);
        assert_eq!(got, edges_by_map(&m));
        // Closed tetrahedra (k % 7 in 0, 5, 6) have no bad edges; each
        // defect adds 3 (flipped, hole, doubled) or, for the repeated
        // corner, its self-loop and the two edges it doubles.
        assert!(got.1 > 0 && got.0 > 6 * n as usize);
        assert_eq!(edges(&tetra()), (6, 0));
        // A vertex with more upper neighbours than a range's table holds
        // (a fan of 20 triangles around vertex 0) takes the sorting path.
        let mut fan = Mesh {
            vertices: vec![[0.0; 3]; 22],
            triangles: (1..21).map(|i| [0, i, i + 1]).collect(),
        };
        fan.triangles.push([0, 21, 1]);
        fan.triangles.push([0, 21, 1]);
        assert_eq!(edges(&fan), edges_by_map(&fan));
    }

    /// The census of `m` given all its vertices as one batch, then its
    /// triangles in `parts` pieces.
    fn census_in_one_batch(m: &Mesh, parts: usize) -> Option<(usize, usize)> {
        let mut c = EdgeCensus::new();
        c.vertices(m.vertices.len());
        let per = m.triangles.len().div_ceil(parts.max(1)).max(1);
        for t in m.triangles.chunks(per) {
            c.triangles(t);
        }
        c.finish()
    }

    #[test]
    fn streamed_census_matches_the_definition() {
        // Defects of every kind, ends up to 20000 apart.
        let m = scrambled(5000);
        assert_eq!(census_in_one_batch(&m, 7), Some(edges_by_map(&m)));
        assert_eq!(census_in_one_batch(&tetra(), 1), Some((6, 0)));
        // A fan of 20 triangles around vertex 0: more upper neighbours
        // than a row holds (the side list), one edge doubled.
        let mut fan = Mesh {
            vertices: vec![[0.0; 3]; 22],
            triangles: (1..21).map(|i| [0, i, i + 1]).collect(),
        };
        fan.triangles.push([0, 21, 1]);
        fan.triangles.push([0, 21, 1]);
        assert_eq!(census_in_one_batch(&fan, 3), Some(edges_by_map(&fan)));
        // Ends more than 65535 apart (the side list), and an edge used 40
        // times one way and 20 the other (counts stuck at 15: bad).
        let mut far = tetra();
        far.vertices.resize(100_000, [0.0; 3]);
        far.triangles.extend([[0, 99_999, 1], [1, 99_999, 0]]);
        for _ in 0..20 {
            far.triangles.extend([[2, 3, 50], [2, 3, 51], [3, 2, 52]]);
        }
        // Repeated corners at vertices with other upper neighbours, before
        // and after them, near and far (whatever slots their keys take).
        for k in 0..40u32 {
            let v = 100 + 200 * k;
            far.triangles.push([v, v, v + 1 + k]);
            far.triangles.push([v, v + 1 + k, v + 2 + 2 * k]);
            far.triangles.push([v + 2 + 2 * k, v + 1 + k, v]);
            far.triangles.push([v, v + 3 + 3 * k, v]);
        }
        let want = edges_by_map(&far);
        assert!(want.1 > 0);
        assert_eq!(census_in_one_batch(&far, 5), Some(want));
        assert_eq!(census_in_one_batch(&Mesh::default(), 1), Some((0, 0)));
    }

    #[test]
    fn streamed_census_counts_meshes_as_the_pipeline_emits_them() {
        // A sink that keeps the mesh and takes the census as it comes:
        // triangle by triangle, or from the bricks' edges (`by_brick`).
        #[derive(Default)]
        struct Both {
            mesh: Mesh,
            census: EdgeCensus,
            by_brick: bool,
            own: u64,
            shared: usize,
        }
        impl crate::sink::MeshSink for Both {
            fn vertices(&mut self, v: &[[f32; 3]]) -> Result<(), crate::MeshError> {
                self.census.vertices(v.len());
                self.mesh.vertices.extend_from_slice(v);
                Ok(())
            }
            fn triangles(
                &mut self,
                t: &[[u32; 3]],
                _: &crate::sink::VertexWindow,
            ) -> Result<(), crate::MeshError> {
                self.census.triangles(t);
                self.mesh.triangles.extend_from_slice(t);
                Ok(())
            }
            fn counts_edges(&self) -> bool {
                self.by_brick
            }
            fn take_counted(
                &mut self,
                part: crate::sink::Counted,
                _: &crate::sink::VertexWindow,
            ) -> Result<(), crate::MeshError> {
                self.census.brick(&part.edges);
                self.own += part.edges.own_uses;
                self.shared += part.edges.shared.len();
                self.mesh.triangles.extend_from_slice(&part.tris);
                Ok(())
            }
        }
        use microfrep_core::{Expr, Shape};
        use microfrep_shapes as prims;
        let p = Expr::xyz();
        // Two balls (one through the box's face), small bricks: many
        // slabs, so many batches and closed vertices; and a dense gyroid
        // sheet cut by the box.
        let a = prims::sphere(&p, &prims::v3([0.1, 0.0, -0.2]), 0.7);
        let b = prims::sphere(&p, &prims::v3([0.6, 0.5, 0.9]), 0.35);
        let balls = Shape::new(a.max(&b));
        use microfrep_structures::tpms::{tpms, Solid, Tpms};
        let gyroid = Shape::new(tpms(Tpms::Gyroid, Solid::Sheet, &p, 0.5, 0.1));
        let cases = [
            (&balls, 60, 8, crate::CellMethod::Cubes),
            (&balls, 33, 4, crate::CellMethod::Cubes),
            (&balls, 40, 32, crate::CellMethod::Cubes),
            (&balls, 45, 8, crate::CellMethod::Tetrahedra),
            (&gyroid, 50, 8, crate::CellMethod::Cubes),
            (&gyroid, 37, 16, crate::CellMethod::Tetrahedra),
        ];
        for (shape, cells, brick, method) in cases {
            for by_brick in [false, true] {
                let mut o = crate::MeshOptions::new([[-1.0; 3], [1.0; 3]], cells);
                o.brick = brick;
                o.cells = method;
                let plan = crate::Plan::new(shape, &o).unwrap();
                let mut b = Both {
                    by_brick,
                    ..Both::default()
                };
                plan.run_into(&mut b, &|_| {}).unwrap();
                let want = edges(&b.mesh);
                assert_eq!(want.1, 0);
                let what = format!("{cells} cells, bricks of {brick}, {method:?}, {by_brick}");
                assert_eq!(b.census.finish(), Some(want), "{what}");
                if by_brick {
                    // Most edges are a brick's own; the stitched ones are
                    // checked use by use.
                    assert!(b.shared > 0 && b.own > 2 * b.shared as u64, "{what}");
                    assert_eq!(b.own as usize + b.shared, 3 * b.mesh.triangles.len());
                    // The in-memory mesh counted while it is made.
                    let (m, e) = plan.run_counted(&|_| {}).unwrap();
                    assert!(m == b.mesh, "{what}");
                    assert_eq!(e, Some(want), "{what}");
                }
            }
        }
    }

    #[test]
    fn brick_edges_are_counted_whole_and_shared_ones_checked() {
        // Shared uses alone are counted as the triangles would be, defects
        // and all.
        let m = scrambled(3000);
        let mut c = EdgeCensus::new();
        c.vertices(m.vertices.len());
        for part in m.triangles.chunks(777) {
            let e = BrickEdges::of(part, &vec![true; m.vertices.len()]);
            assert_eq!(e.own_uses, 0);
            c.brick(&e);
        }
        assert_eq!(c.finish(), Some(edges_by_map(&m)));
        // A closed tetrahedron with no vertex on a face: its own edges,
        // counted whole.
        let t = tetra();
        let e = BrickEdges::of(&t.triangles, &[false; 4]);
        assert_eq!((e.own_uses, e.shared.len()), (12, 0));
        let mut c = EdgeCensus::new();
        c.vertices(4);
        c.brick(&e);
        assert_eq!(c.finish(), Some((6, 0)));
        // Vertices 0 and 1 on a face: edge 0-1 is shared, the rest own.
        let e = BrickEdges::of(&t.triangles, &[true, true, false, false]);
        assert_eq!((e.own_uses, e.shared.len()), (10, 2));
        let mut c = EdgeCensus::new();
        c.vertices(4);
        c.brick(&e);
        assert_eq!(c.finish(), Some((6, 0)));
        // Own uses that do not pair up cannot be: the census says it does
        // not know.
        let mut c = EdgeCensus::new();
        c.vertices(4);
        c.brick(&BrickEdges {
            own_uses: 11,
            shared: Vec::new(),
        });
        assert_eq!(c.finish(), None);
    }

    #[test]
    fn streamed_census_knows_when_the_order_does_not_hold() {
        let t = tetra();
        let mut c = EdgeCensus::new();
        c.vertices(4);
        c.triangles(&t.triangles);
        c.vertices(4);
        c.vertices(4);
        // Vertices 0..4 are closed now.
        c.triangles(&[[0, 8, 9]]);
        assert_eq!(c.finish(), None);
        // A vertex not received yet.
        let mut c = EdgeCensus::new();
        c.vertices(3);
        c.triangles(&t.triangles);
        assert_eq!(c.finish(), None);
        // Triangles before any vertex.
        let mut c = EdgeCensus::new();
        c.triangles(&t.triangles);
        assert_eq!(c.finish(), None);
        // In order across batches, rows growing: exact.
        let mut c = EdgeCensus::new();
        let mut all = Mesh::default();
        for k in 0..6u32 {
            let n = 4 * (k as usize + 1) * 500;
            let base = all.vertices.len() as u32;
            c.vertices(n);
            all.vertices.resize(base as usize + n, [0.0; 3]);
            let tris: Vec<[u32; 3]> = (0..n as u32 / 4)
                .flat_map(|j| {
                    tetra()
                        .triangles
                        .into_iter()
                        .map(move |t| t.map(|v| base + 4 * j + v))
                })
                .collect();
            c.triangles(&tris);
            all.triangles.extend(tris);
        }
        assert_eq!(c.finish(), Some(edges_by_map(&all)));
    }

    #[test]
    fn defects_are_counted() {
        let mut m = tetra();
        m.triangles[3] = [1, 3, 2]; // flipped face: 3 edges now one-directional
        assert_eq!(check(&m).bad_edges, 3);
        let mut m = tetra();
        m.triangles.pop(); // hole
        assert_eq!(check(&m).bad_edges, 3);
        let mut m = tetra();
        m.triangles.push([3, 2, 1]);
        let r = check(&m);
        assert_eq!(r.duplicate_triangles, 1);
        let mut m = tetra();
        m.vertices.push([0.0; 3]);
        m.triangles.push([4, 4, 1]);
        let r = check(&m);
        assert_eq!((r.duplicate_vertices, r.degenerate), (1, 1));
    }
}

/// Connected shells of a mesh (triangles joined through shared vertex
/// indices), counted as the mesh comes: a union-find over the vertices,
/// four bytes each, fed batch by batch in any order. Vertices no triangle
/// uses are not shells.
#[derive(Default)]
pub struct ShellCensus {
    /// Parent of each vertex; a root is its own parent.
    parent: Vec<u32>,
    /// Whether a triangle used the vertex.
    used: Vec<bool>,
    /// Triangles naming a vertex not received (the count is then unknown).
    unknown: bool,
}

impl ShellCensus {
    /// An empty census.
    pub fn new() -> Self {
        Self::default()
    }

    /// The next `n` vertices arrive.
    pub fn vertices(&mut self, n: usize) {
        let start = self.parent.len() as u32;
        self.parent.extend(start..start + n as u32);
        self.used.resize(self.parent.len(), false);
    }

    fn find(&mut self, mut i: u32) -> u32 {
        while self.parent[i as usize] != i {
            let g = self.parent[self.parent[i as usize] as usize];
            self.parent[i as usize] = g;
            i = g;
        }
        i
    }

    /// The next triangles.
    pub fn triangles(&mut self, t: &[[u32; 3]]) {
        let n = self.parent.len() as u32;
        for tri in t {
            if tri.iter().any(|&v| v >= n) {
                self.unknown = true;
                continue;
            }
            for &v in tri {
                self.used[v as usize] = true;
            }
            self.join(tri);
        }
    }

    /// Joins the corners of one triangle: the larger root under the
    /// smaller.
    fn join(&mut self, tri: &[u32; 3]) {
        for &v in &tri[1..] {
            let a = self.find(tri[0]);
            let b = self.find(v);
            if a != b {
                let (r, c) = if a < b { (a, b) } else { (b, a) };
                self.parent[c as usize] = r;
            }
        }
    }

    /// The shells, or `None` when a triangle named a vertex never received.
    pub fn finish(mut self) -> Option<usize> {
        if self.unknown {
            return None;
        }
        let mut n = 0;
        for i in 0..self.parent.len() as u32 {
            if self.used[i as usize] && self.find(i) == i {
                n += 1;
            }
        }
        Some(n)
    }
}

/// Shells of an indexed mesh (see [`ShellCensus`]); 0 if a triangle names
/// a vertex the mesh lacks.
pub fn shells(mesh: &crate::Mesh) -> usize {
    let mut c = ShellCensus::new();
    c.vertices(mesh.vertices.len());
    c.triangles(&mesh.triangles);
    c.finish().unwrap_or(0)
}
