//! Edge counting: the linear-time census of a mesh's edges and bad edges
//! ([`edges`]), the same census taken while a mesh streams to a sink or a
//! writer ([`EdgeCensus`], by brick with [`BrickEdges`]), and the shells
//! counted as the mesh comes ([`ShellCensus`]). [`crate::check`] re-exports
//! them.

use crate::Mesh;
use rayon::prelude::*;

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
