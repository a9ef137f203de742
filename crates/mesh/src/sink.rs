//! Where the pipeline's output goes: vertices and triangles arrive in their
//! final global order, a part at a time, so a mesh can be collected in
//! memory or written to disk as it is made.

use crate::edges::BrickEdges;
use crate::{Mesh, MeshError};

/// The vertices a batch of triangles may use: two consecutive runs of the
/// global vertex numbering.
pub struct VertexWindow<'a> {
    /// `(first, positions)` for each run: the global index of its first vertex
    /// and the positions from there on. The second run starts after the first;
    /// an unused second run starts at `u32::MAX` with no positions.
    pub runs: [(u32, &'a [[f32; 3]]); 2],
}

impl VertexWindow<'_> {
    /// Position of global vertex `i` (which must lie in the window).
    pub fn get(&self, i: u32) -> [f32; 3] {
        let [(b0, v0), (b1, v1)] = self.runs;
        if i >= b1 {
            v1[(i - b1) as usize]
        } else {
            v0[(i - b0) as usize]
        }
    }
}

/// Receives a mesh in order: every vertex before any triangle that uses it,
/// vertices and triangles each in their global order.
pub trait MeshSink {
    /// Takes the next vertices in global order: the first of `v` has the index
    /// one past the last vertex received before.
    fn vertices(&mut self, v: &[[f32; 3]]) -> Result<(), MeshError>;
    /// Takes the next triangles, with global vertex indices, counter-clockwise
    /// seen from outside; `window` holds the position of every vertex they use.
    fn triangles(&mut self, t: &[[u32; 3]], window: &VertexWindow) -> Result<(), MeshError>;
    /// [`Self::triangles`] with the buffer handed over, for sinks that keep
    /// triangles whole (no copy); by default it lends them to `triangles`.
    fn take_triangles(&mut self, t: Vec<[u32; 3]>, window: &VertexWindow) -> Result<(), MeshError> {
        self.triangles(&t, window)
    }
    /// Whether the sink takes an edge census
    /// ([`crate::edges::EdgeCensus`]). If so, the pipeline has every brick
    /// sort its edges while it meshes ([`BrickEdges`]) and hands them over
    /// with its triangles ([`Self::take_counted`]).
    fn counts_edges(&self) -> bool {
        false
    }
    /// [`Self::take_triangles`] for a sink that [`Self::counts_edges`]: one
    /// brick's triangles with its edges. By default the edges are ignored.
    fn take_counted(&mut self, part: Counted, window: &VertexWindow) -> Result<(), MeshError> {
        self.take_triangles(part.tris, window)
    }
}

/// One brick's triangles and its edges ([`MeshSink::take_counted`]), in
/// global vertex indices.
pub struct Counted {
    /// The triangles.
    pub tris: Vec<[u32; 3]>,
    /// Their edges, for the census.
    pub edges: BrickEdges,
}

/// A mesh with its edges and bad edges and its connected shells, as
/// counted while it was made (`None` where they could not be).
pub type CountedMesh = (Mesh, Option<(usize, usize)>, Option<usize>);

/// Collects the whole mesh in memory: the parts as they arrive (the
/// triangles without a copy), joined once at the end by
/// [`Collect::into_mesh`] into buffers of the exact size, several threads
/// copying. (Growing one buffer copied it again at every doubling, on the
/// pipeline's one sink thread.)
#[derive(Default)]
pub struct Collect {
    vertices: Vec<Vec<[f32; 3]>>,
    triangles: Vec<Vec<[u32; 3]>>,
    /// The edge census, when taken ([`Collect::counting`]).
    census: Option<crate::edges::EdgeCensus>,
    /// The shell census, when taken ([`Collect::counting_shells`]).
    shells: Option<crate::edges::ShellCensus>,
}

impl Collect {
    /// A sink that also counts the edges as they come, from the bricks
    /// ([`crate::edges::EdgeCensus::brick`]); see [`Collect::into_counted`].
    pub fn counting() -> Collect {
        Collect {
            census: Some(crate::edges::EdgeCensus::new()),
            ..Collect::default()
        }
    }

    /// [`Collect::counting`] that also counts the connected shells as the
    /// triangles come (as [`crate::edges::shells`] counts them); see
    /// [`Collect::into_counted_shells`].
    pub fn counting_shells() -> Collect {
        Collect {
            shells: Some(crate::edges::ShellCensus::new()),
            ..Collect::counting()
        }
    }

    /// [`Collect::into_counted`], with the shells of a
    /// [`Collect::counting_shells`] sink (`None` where none were counted
    /// or a triangle named an unknown vertex).
    pub fn into_counted_shells(mut self) -> CountedMesh {
        let shells = self.shells.take().and_then(|c| c.finish());
        let (mesh, edges) = self.into_counted();
        (mesh, edges, shells)
    }

    /// The mesh received so far, in order.
    pub fn into_mesh(self) -> Mesh {
        Mesh {
            vertices: concat(self.vertices),
            triangles: concat(self.triangles),
        }
    }

    /// The mesh and, for a [`Collect::counting`] sink, its edges and bad
    /// edges as [`crate::edges::edges`] counts them (`None` where the
    /// census could not tell: count them with that function).
    pub fn into_counted(mut self) -> (Mesh, Option<(usize, usize)>) {
        let edges = self.census.take().and_then(|c| c.finish());
        (self.into_mesh(), edges)
    }
}

/// The parts one after the other, copied in parallel into a buffer of the
/// exact size (zeroed by the allocator's fresh pages, not by a pass).
fn concat<T: Copy + Default + Send + Sync>(mut parts: Vec<Vec<T>>) -> Vec<T> {
    use rayon::prelude::*;
    if parts.len() <= 1 {
        return parts.pop().unwrap_or_default();
    }
    let total = parts.iter().map(Vec::len).sum();
    let mut out = vec![T::default(); total];
    let mut rest = &mut out[..];
    let mut dst = Vec::with_capacity(parts.len());
    for p in &parts {
        let (a, b) = rest.split_at_mut(p.len());
        dst.push(a);
        rest = b;
    }
    dst.into_par_iter()
        .zip(parts.par_iter())
        .for_each(|(d, s)| d.copy_from_slice(s));
    out
}

impl MeshSink for Collect {
    fn vertices(&mut self, v: &[[f32; 3]]) -> Result<(), MeshError> {
        if let Some(c) = &mut self.census {
            c.vertices(v.len());
        }
        if let Some(c) = &mut self.shells {
            c.vertices(v.len());
        }
        if !v.is_empty() {
            self.vertices.push(v.to_vec());
        }
        Ok(())
    }

    fn triangles(&mut self, t: &[[u32; 3]], window: &VertexWindow) -> Result<(), MeshError> {
        self.take_triangles(t.to_vec(), window)
    }

    fn take_triangles(&mut self, t: Vec<[u32; 3]>, _: &VertexWindow) -> Result<(), MeshError> {
        if let Some(c) = &mut self.census {
            c.triangles(&t);
        }
        if let Some(c) = &mut self.shells {
            c.triangles(&t);
        }
        if !t.is_empty() {
            self.triangles.push(t);
        }
        Ok(())
    }

    fn counts_edges(&self) -> bool {
        self.census.is_some()
    }

    fn take_counted(&mut self, part: Counted, _: &VertexWindow) -> Result<(), MeshError> {
        if let Some(c) = &mut self.census {
            c.brick(&part.edges);
        }
        if let Some(c) = &mut self.shells {
            c.triangles(&part.tris);
        }
        if !part.tris.is_empty() {
            self.triangles.push(part.tris);
        }
        Ok(())
    }
}

/// Counts and measures what passes through to an inner sink: the summary of
/// a mesh that is never held whole.
#[derive(Clone, Debug, PartialEq)]
pub struct Tally {
    /// Vertices passed through.
    pub vertices: u64,
    /// Triangles passed through.
    pub triangles: u64,
    /// Signed volume (divergence theorem) and area, f64 sums in order.
    pub volume: f64,
    /// Total triangle area in square model units.
    pub area: f64,
    /// Bounding box of the vertices (min, max).
    pub bbox: [[f64; 3]; 2],
    /// Edges and bad edges (not used exactly once each way), where an
    /// [`crate::edges::EdgeCensus`] counted them ([`Counting`]); `None`
    /// where nothing counted or the mesh did not come in its order.
    pub edges: Option<(usize, usize)>,
}

impl Default for Tally {
    fn default() -> Self {
        Tally {
            vertices: 0,
            triangles: 0,
            volume: 0.0,
            area: 0.0,
            bbox: [[f64::INFINITY; 3], [f64::NEG_INFINITY; 3]],
            edges: None,
        }
    }
}

/// Signed volume of the tetrahedron (origin, p, q, r) and area of (p, q, r).
pub fn volume_area_of(t: [[f32; 3]; 3]) -> (f64, f64) {
    let [p, q, r] = t.map(|v| v.map(|c| c as f64));
    let e1 = [q[0] - p[0], q[1] - p[1], q[2] - p[2]];
    let e2 = [r[0] - p[0], r[1] - p[1], r[2] - p[2]];
    let n = [
        e1[1] * e2[2] - e1[2] * e2[1],
        e1[2] * e2[0] - e1[0] * e2[2],
        e1[0] * e2[1] - e1[1] * e2[0],
    ];
    let area = 0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    let vol = (p[0] * (q[1] * r[2] - q[2] * r[1]) - p[1] * (q[0] * r[2] - q[2] * r[0])
        + p[2] * (q[0] * r[1] - q[1] * r[0]))
        / 6.0;
    (vol, area)
}

/// A sink that counts the edges of what passes through to `inner`, in one
/// streaming pass ([`crate::edges::EdgeCensus`]): the bad-edge figure of a
/// mesh that is never held whole.
pub struct Counting<'a> {
    /// The sink everything is forwarded to, unchanged.
    pub inner: &'a mut (dyn MeshSink + Send),
    /// The census so far.
    pub census: crate::edges::EdgeCensus,
}

impl MeshSink for Counting<'_> {
    fn vertices(&mut self, v: &[[f32; 3]]) -> Result<(), MeshError> {
        self.census.vertices(v.len());
        self.inner.vertices(v)
    }

    fn triangles(&mut self, t: &[[u32; 3]], window: &VertexWindow) -> Result<(), MeshError> {
        self.census.triangles(t);
        self.inner.triangles(t, window)
    }

    fn take_triangles(&mut self, t: Vec<[u32; 3]>, window: &VertexWindow) -> Result<(), MeshError> {
        self.census.triangles(&t);
        self.inner.take_triangles(t, window)
    }

    fn counts_edges(&self) -> bool {
        true
    }

    fn take_counted(&mut self, part: Counted, window: &VertexWindow) -> Result<(), MeshError> {
        self.census.brick(&part.edges);
        self.inner.take_triangles(part.tris, window)
    }
}

/// A sink that tallies and forwards to `inner`.
pub struct Tallying<'a> {
    /// The sink everything is forwarded to, unchanged.
    pub inner: &'a mut (dyn MeshSink + Send),
    /// Counts and measures of what has passed so far.
    pub tally: Tally,
}

impl MeshSink for Tallying<'_> {
    fn vertices(&mut self, v: &[[f32; 3]]) -> Result<(), MeshError> {
        let [lo, hi] = &mut self.tally.bbox;
        for p in v {
            for ((l, h), &c) in lo.iter_mut().zip(hi.iter_mut()).zip(p) {
                *l = l.min(c as f64);
                *h = h.max(c as f64);
            }
        }
        self.tally.vertices += v.len() as u64;
        self.inner.vertices(v)
    }

    fn triangles(&mut self, t: &[[u32; 3]], window: &VertexWindow) -> Result<(), MeshError> {
        self.add(t, window);
        self.inner.triangles(t, window)
    }

    fn counts_edges(&self) -> bool {
        self.inner.counts_edges()
    }

    fn take_counted(&mut self, part: Counted, window: &VertexWindow) -> Result<(), MeshError> {
        self.add(&part.tris, window);
        self.inner.take_counted(part, window)
    }
}

impl Tallying<'_> {
    /// Counts and measures triangles `t`.
    fn add(&mut self, t: &[[u32; 3]], window: &VertexWindow) {
        let (mut vol, mut area) = (0.0, 0.0);
        for tri in t {
            let (v, a) = volume_area_of(tri.map(|i| window.get(i)));
            vol += v;
            area += a;
        }
        self.tally.volume += vol;
        self.tally.area += area;
        self.tally.triangles += t.len() as u64;
    }
}
