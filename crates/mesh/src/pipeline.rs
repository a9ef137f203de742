//! The meshing pipeline, a group of z-slabs of bricks at a time, so output
//! can leave for its sink (memory or disk) while the rest is being made and
//! only four groups are held at once.
//!
//! A brick's triangles use vertices it owns and vertices owned by bricks
//! above it in x, y or z (see [`crate::brick`]), so group `g`'s triangles
//! use groups `g` and `g + 1` only, and a vertex of group `g` is used by
//! triangles of groups `g - 1` and `g` only. Each brick refines its foreign
//! vertices too (the same bits as their owner), so it sums the volume
//! correction of all its triangles and finishes every vertex no other brick
//! touches while meshing. Once group `g + 1` is meshed: group `g`'s
//! triangles get global indices (stage A); the correction sums of vertices
//! owned by other bricks are added to their owners in brick order (B);
//! group `g`'s shared vertices have seen all their triangles and take
//! their final positions (C); and group `g - 1`'s triangles have all their
//! vertices final (D). The output is the same as if the whole mesh had been
//! made at once, whatever the group size, and the same on every run.

use crate::brick::{mesh_brick, BrickMesh, Finish, Scratch};
use crate::classify::BrickClass;
use crate::correct::{add, apply_all, Acc};
use crate::edges::BrickEdges;
use crate::sink::{Counted, MeshSink, VertexWindow};
use crate::{MeshError, Plan};
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// A group's work after stage A, per brick.
#[derive(Default)]
struct Work {
    /// Correction sums of the brick's shared vertices (those of its
    /// `owned_keys`, same order) from other bricks' triangles, added in
    /// brick order (B); kept apart from the brick's own sums so the sums do
    /// not depend on how bricks are grouped.
    inbound: Vec<Acc>,
    /// Foreign vertices as (owner brick, index among its shared vertices).
    foreign: Vec<(u32, u32)>,
    /// The brick's triangles, in global vertex indices after stage A.
    tris: Vec<[u32; 3]>,
    /// The brick's edges for the sink's census, if it takes one (global
    /// after stage A).
    edges: Option<BrickEdges>,
}

/// A scratch lent from a pipeline's pool, given back when dropped.
struct Lent<'a> {
    s: Option<Scratch>,
    pool: &'a Mutex<Vec<Scratch>>,
}

impl Drop for Lent<'_> {
    fn drop(&mut self) {
        if let (Some(s), Ok(mut p)) = (self.s.take(), self.pool.lock()) {
            p.push(s);
        }
    }
}

/// Consecutive bricks `first..first + meshes.len()` (whole z-slabs).
struct Group {
    first: usize,
    meshes: Vec<BrickMesh>,
    /// Global index of each brick's first owned vertex.
    offsets: Vec<u32>,
    work: Vec<Work>,
    /// Global index of the group's first vertex.
    base: u32,
    /// After stage C: the group's vertices in global order.
    verts: Vec<[f32; 3]>,
}

impl Group {
    fn holds(&self, brick: usize) -> bool {
        (self.first..self.first + self.work.len()).contains(&brick)
    }
}

/// A foreign vertex found in its owner: (owner brick, its index among the
/// owner's shared vertices, global index).
type Found = (u32, u32, u32);

/// The read-only part of a group that stage A looks vertices up in.
#[derive(Clone, Copy)]
struct Owners<'a> {
    first: usize,
    meshes: &'a [BrickMesh],
    offsets: &'a [u32],
}

impl Owners<'_> {
    fn holds(&self, brick: usize) -> bool {
        (self.first..self.first + self.meshes.len()).contains(&brick)
    }
}

fn owners(g: &Group) -> Owners<'_> {
    Owners {
        first: g.first,
        meshes: &g.meshes,
        offsets: &g.offsets,
    }
}

/// Finds the vertex on grid edge `key` in its owner brick, which must be in
/// one of `groups`.
fn find(plan: &Plan, groups: [Option<Owners>; 2], key: u64) -> Result<Found, MeshError> {
    let grid = &plan.grid;
    let owner = grid.brick_index(grid.owner_brick(grid.node_from_index(key / 8)));
    let g = groups
        .into_iter()
        .flatten()
        .find(|g| g.holds(owner))
        .ok_or_else(|| {
            MeshError::Internal(format!(
                "grid edge {key} belongs to brick {owner}, outside the pipeline's window"
            ))
        })?;
    let j = owner - g.first;
    let m = &g.meshes[j];
    match m.owned_keys.binary_search_by_key(&key, |&(k, _)| k) {
        Ok(i) => {
            let local = m.owned_keys[i].1;
            Ok((owner as u32, i as u32, g.offsets[j] + local))
        }
        Err(_) => Err(MeshError::Internal(format!(
            "grid edge {key} is used by a brick but not made by its owner brick {owner}"
        ))),
    }
}

impl Plan {
    /// Z-slabs of bricks per pipeline step (see [`crate::memory`]).
    pub(crate) fn slabs_per_group(&self) -> usize {
        crate::memory::slabs_per_group(&self.grid)
    }

    /// Meshes bricks `range` (whole slabs), numbering owned vertices from
    /// `*next_vertex` on; `count_edges`: bricks sort their edges for the
    /// sink's census.
    #[allow(clippy::too_many_arguments)]
    fn mesh_group(
        &self,
        range: std::ops::Range<usize>,
        count_edges: bool,
        next_vertex: &mut u64,
        done: &AtomicUsize,
        scratch: &Mutex<Vec<Scratch>>,
        progress: &(dyn Fn(usize) + Sync),
    ) -> Result<Group, MeshError> {
        let first = range.start;
        let clamp = BoxClamp::new(self.bounds);
        let finish = Finish {
            h: self.grid.h,
            correct: self.correct,
            sharp: self.sharp,
            lo: clamp.lo,
            hi: clamp.hi,
        };
        // Scratch buffers (evaluators, tables) are made once per thread and
        // lent to every split of every group (rayon makes a dozen splits
        // per group), not made afresh for each.
        let lend = || {
            let s = scratch.lock().ok().and_then(|mut p| p.pop());
            Lent {
                s: Some(s.unwrap_or_else(|| {
                    Scratch::new(
                        &self.tape,
                        self.grid.brick,
                        self.simplify,
                        finish,
                        count_edges,
                    )
                })),
                pool: scratch,
            }
        };
        let mut meshes: Vec<BrickMesh> = range
            .into_par_iter()
            .map_init(lend, |s, k| {
                let s = s.s.as_mut().expect("lent until dropped");
                if self.classes[k] != BrickClass::Surface {
                    return BrickMesh::default();
                }
                let b = self.grid.brick_coords(k);
                let m = mesh_brick(&self.grid, &self.classes, self.table, b, s);
                progress(done.fetch_add(1, Ordering::Relaxed) + 1);
                m
            })
            .collect();
        let base = *next_vertex;
        let mut offsets = Vec::with_capacity(meshes.len());
        for m in &meshes {
            offsets.push(*next_vertex as u32);
            *next_vertex += m.owned_pos.len() as u64;
        }
        if *next_vertex > u32::MAX as u64 {
            return Err(MeshError::TooLarge(format!(
                "more than {} vertices do not fit 32-bit indices; lower the resolution",
                u32::MAX
            )));
        }
        let thin: usize = meshes.iter().map(|m| m.thin_cells).sum();
        self.thin_cells.fetch_add(thin, Ordering::Relaxed);
        let work = meshes
            .iter_mut()
            .map(|m| Work {
                inbound: vec![[0; 6]; m.owned_keys.len()],
                // Still in the brick's local numbering until stage A.
                tris: std::mem::take(&mut m.tris),
                edges: m.edges.take(),
                ..Work::default()
            })
            .collect();
        Ok(Group {
            first,
            meshes,
            offsets,
            work,
            base: base as u32,
            verts: Vec::new(),
        })
    }

    /// Stage A for `g`: global triangles; `next` is the following group,
    /// if any.
    fn stage_a(&self, g: &mut Group, next: Option<&Group>) -> Result<(), MeshError> {
        let Group {
            meshes,
            offsets,
            work,
            first,
            ..
        } = g;
        let here = Owners {
            first: *first,
            meshes,
            offsets,
        };
        let (meshes, offsets) = (here.meshes, here.offsets);
        let lookup = |key: u64| find(self, [Some(here), next.map(owners)], key);
        work.par_iter_mut().enumerate().try_for_each_init(
            Vec::new,
            |globals: &mut Vec<u32>, (j, w)| -> Result<(), MeshError> {
                let m = &meshes[j];
                if w.tris.is_empty() {
                    return Ok(());
                }
                // Local -> global index of every vertex the brick uses: its
                // owned ones, then the foreign ones from their owners.
                let off = offsets[j];
                globals.clear();
                globals.extend(off..off + m.owned_pos.len() as u32);
                w.foreign.clear();
                for &key in &m.foreign_keys {
                    let (ob, oi, gi) = lookup(key)?;
                    w.foreign.push((ob, oi));
                    globals.push(gi);
                }
                // To global indices, in place (a fresh vector cost a page
                // fault per 340 triangles); a table lookup, not a branch.
                if self.sharp {
                    // Triangles a lower brick's flip took stay marked until
                    // `cross_flips` of this group drops them.
                    for t in w.tris.iter_mut().filter(|t| t[0] != u32::MAX) {
                        *t = t.map(|v| globals[v as usize]);
                    }
                } else {
                    for t in w.tris.iter_mut() {
                        *t = t.map(|v| globals[v as usize]);
                    }
                }
                if let Some(e) = w.edges.as_mut() {
                    for u in e.shared.iter_mut() {
                        *u = u.map(|v| globals[v as usize]);
                    }
                }
                Ok(())
            },
        )
    }
}

/// Sharp features across brick faces, after stage A of `g`: a fan
/// triangle `f1 a b` of a brick of `g` and `f2 b a` of a brick above it (in
/// `g` or `next`) on the same face segment are flipped into `f1 a f2` and
/// `f2 b f1` where [`crate::sharp::flip`] finds both proper, as a brick
/// does within itself. The lower brick takes both new triangles (its
/// triangles may use the upper brick's vertices, not the other way round)
/// and the upper brick's triangle goes; a pair of feature vertices is
/// joined once at most. Pairs are taken in brick and triangle order, so
/// the result does not depend on the grouping. The volume correction
/// keeps the sums of the triangles before the flip (the vertices of
/// features with flat sides do not move).
fn cross_flips(h: f64, g: &mut Group, mut next: Option<&mut Group>) {
    use crate::fasthash::{FastMap, FastSet};
    const DEAD: [u32; 3] = [u32::MAX; 3];
    let mut at: FastMap<[u64; 2], (usize, usize)> = FastMap::default();
    for grp in std::iter::once(&*g).chain(next.as_deref()) {
        for (j, m) in grp.meshes.iter().enumerate() {
            for (r, rim) in m.rims.iter().enumerate() {
                at.insert(rim.keys, (grp.first + j, r));
            }
        }
    }
    let mut joined: FastSet<(u32, usize, u32)> = FastSet::default();
    for j in 0..g.meshes.len() {
        let lower = g.first + j;
        for r in 0..g.meshes[j].rims.len() {
            let rim = &g.meshes[j].rims[r];
            let Some(&(upper, q)) = at.get(&[rim.keys[1], rim.keys[0]]) else {
                continue;
            };
            let ta = g.work[j].tris[rim.tri as usize];
            if upper <= lower || ta == DEAD {
                continue;
            }
            // The upper brick's group, its triangle and `f2`'s global index
            // (its triangles are global in `g`, still local in `next`).
            let here = g.holds(upper);
            let (other, tb, f2, uj) = if here {
                let uj = upper - g.first;
                let o = g.meshes[uj].rims[q].clone();
                let tb = g.work[uj].tris[o.tri as usize];
                (o, tb, tb[0], uj)
            } else {
                let n = next.as_deref().expect("the partner is in the window");
                let uj = upper - n.first;
                let o = n.meshes[uj].rims[q].clone();
                let tb = n.work[uj].tris[o.tri as usize];
                (o, tb, n.offsets[uj] + tb[0], uj)
            };
            if tb == DEAD
                || joined.contains(&(ta[0], upper, tb[0]))
                || !crate::sharp::flip(rim.f, other.f, rim.a, rim.b, rim.na, rim.nb, h)
            {
                continue;
            }
            joined.insert((ta[0], upper, tb[0]));
            let [f1, a, b] = ta;
            let w = &mut g.work[j];
            w.tris[rim.tri as usize] = [f1, a, f2];
            w.tris.push([f2, b, f1]);
            if let Some(e) = w.edges.as_mut() {
                // a -> b goes (shared); a -> f2, f2 -> f1, f1 -> f2 and
                // f2 -> b come (f2 is in no face plane).
                drop_use(&mut e.shared, [a, b]);
                e.own_uses += 4;
            }
            let w = if here {
                &mut g.work[uj]
            } else {
                &mut next.as_deref_mut().expect("in the window").work[uj]
            };
            w.tris[other.tri as usize] = DEAD;
            if let Some(e) = w.edges.as_mut() {
                // f2 -> b' and a' -> f2 go with b' -> a' (shared).
                drop_use(&mut e.shared, [tb[1], tb[2]]);
                e.own_uses -= 2;
            }
        }
    }
    for w in &mut g.work {
        w.tris.retain(|t| *t != DEAD);
    }
}

/// Removes the first use `u` from `shared`.
fn drop_use(shared: &mut Vec<[u32; 2]>, u: [u32; 2]) {
    if let Some(i) = shared.iter().position(|&x| x == u) {
        shared.remove(i);
    }
}

/// Stage B: adds the sums of `g`'s foreign vertices to their owners (in `g`
/// or `next`), in brick order.
fn stage_b(g: &mut Group, mut next: Option<&mut Group>) {
    for j in 0..g.work.len() {
        let foreign = std::mem::take(&mut g.work[j].foreign);
        let sums = std::mem::take(&mut g.meshes[j].foreign_acc);
        for (&(ob, oi), s) in foreign.iter().zip(&sums) {
            let ob = ob as usize;
            let target = if g.holds(ob) {
                &mut g.work[ob - g.first]
            } else {
                let n = next.as_deref_mut().expect("stage A found the owner");
                &mut n.work[ob - n.first]
            };
            add(&mut target.inbound[oi as usize], s);
        }
    }
}

/// Stage C: final positions of `g`'s shared vertices (corrected, then kept
/// inside the box; the others were finished by their brick); frees what
/// later stages do not need.
fn stage_c(g: &mut Group, h: f64, clamp: &BoxClamp, sharp: bool) {
    g.meshes
        .par_iter_mut()
        .zip(g.work.par_iter())
        .for_each(|(m, w)| {
            let mut p: Vec<[f32; 3]> = m
                .owned_keys
                .iter()
                .map(|&(_, v)| m.owned_pos[v as usize])
                .collect();
            apply_all(
                &mut p,
                &m.shared_acc,
                &w.inbound,
                h,
                clamp.lo,
                clamp.hi,
                sharp,
            );
            for (&(_, v), q) in m.owned_keys.iter().zip(p) {
                m.owned_pos[v as usize] = q;
            }
        });
    let n: usize = g.meshes.iter().map(|m| m.owned_pos.len()).sum();
    let mut verts = Vec::with_capacity(n);
    for m in &g.meshes {
        verts.extend_from_slice(&m.owned_pos);
    }
    g.verts = verts;
    g.meshes = Vec::new();
    for w in &mut g.work {
        w.inbound = Vec::new();
    }
}

fn emit_triangles(
    sink: &mut (dyn MeshSink + Send),
    g: Group,
    next: Option<&Group>,
) -> Result<(), MeshError> {
    let empty: &[[f32; 3]] = &[];
    let window = VertexWindow {
        runs: [
            (g.base, &g.verts[..]),
            next.map_or((u32::MAX, empty), |n| (n.base, &n.verts[..])),
        ],
    };
    for w in g.work {
        match w.edges {
            Some(edges) => {
                let tris = w.tris;
                sink.take_counted(Counted { tris, edges }, &window)?
            }
            None => sink.take_triangles(w.tris, &window)?,
        }
    }
    Ok(())
}

/// Runs the whole pipeline into `sink`. Each step finishes one group and
/// hands its output to the sink on one thread while the others mesh the
/// group after next.
pub fn run(
    plan: &Plan,
    sink: &mut (dyn MeshSink + Send),
    progress: &(dyn Fn(usize) + Sync),
) -> Result<(), MeshError> {
    plan.thin_cells.store(0, Ordering::Relaxed);
    let clamp = BoxClamp::new(plan.bounds);
    let grid = &plan.grid;
    let per_group = plan.slabs_per_group() * grid.bricks[0] * grid.bricks[1];
    let total = grid.brick_count();
    let done = AtomicUsize::new(0);
    let scratch = Mutex::new(Vec::new());
    let count_edges = sink.counts_edges();
    let mut next_vertex = 0u64;
    let mut starts = (0..total).step_by(per_group);
    let mut mesh_next = || -> Result<Option<Group>, MeshError> {
        match starts.next() {
            Some(s) => plan
                .mesh_group(
                    s..(s + per_group).min(total),
                    count_edges,
                    &mut next_vertex,
                    &done,
                    &scratch,
                    progress,
                )
                .map(Some),
            None => Ok(None),
        }
    };
    let mut prev: Option<Group> = None;
    let mut cur = mesh_next()?;
    let mut next = mesh_next()?;
    while let Some(mut g) = cur.take() {
        // Stages A to D of `g` need only `g`, `next` and `prev`, so they
        // run while the pool meshes the group after `next`.
        let (emitted, after) = rayon::join(
            || -> Result<(), MeshError> {
                plan.stage_a(&mut g, next.as_ref())?;
                if plan.sharp {
                    cross_flips(plan.grid.h, &mut g, next.as_mut());
                }
                stage_b(&mut g, next.as_mut());
                stage_c(&mut g, plan.grid.h, &clamp, plan.sharp);
                sink.vertices(&g.verts)?;
                match prev.take() {
                    Some(p) => emit_triangles(sink, p, Some(&g)),
                    None => Ok(()),
                }
            },
            &mut mesh_next,
        );
        emitted?;
        prev = Some(g);
        cur = next;
        next = after?;
    }
    if let Some(p) = prev {
        emit_triangles(sink, p, None)?;
    }
    Ok(())
}

/// The meshed box in f32, rounded inwards. The volume correction never
/// pushes a vertex through it ([`crate::correct::apply_all`]), and what
/// refinement left outside (a probe a little past a face where a tet's
/// diagonal crosses the box's edge) is clamped onto the face. Vertices
/// move; which triangles use them does not, so the mesh stays closed and
/// manifold. Since no box face lies on a node plane ([`crate::Grid`]), no
/// vertex sits exactly on one before clamping, and clamping one
/// coordinate of vertices on distinct grid edges keeps them distinct (the
/// tests check for coincident vertices and degenerate triangles).
pub(crate) struct BoxClamp {
    pub(crate) lo: [f32; 3],
    pub(crate) hi: [f32; 3],
}

impl BoxClamp {
    pub(crate) fn new(b: [[f64; 3]; 2]) -> BoxClamp {
        // The f32 nearest `v`, moved one step up (or down) if it lies
        // beyond `v` that way.
        let inward = |v: f64, up: bool| {
            let f = v as f32;
            let beyond = if up { (f as f64) < v } else { (f as f64) > v };
            if !beyond {
                f
            } else if f == 0.0 {
                let tiny = f32::from_bits(1);
                if up {
                    tiny
                } else {
                    -tiny
                }
            } else if (f > 0.0) == up {
                f32::from_bits(f.to_bits() + 1)
            } else {
                f32::from_bits(f.to_bits() - 1)
            }
        };
        BoxClamp {
            lo: b[0].map(|v| inward(v, true)),
            hi: b[1].map(|v| inward(v, false)),
        }
    }
}
