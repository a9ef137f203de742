//! Subdivision of the box around a part into cells (Kou and Tan, Sec. 3):
//! quadtree / octree refinement where the requested pore size is smaller
//! than the cell (Eqs. 1-3), or T-mesh refinement, which cuts a cell in two
//! across one direction only; cells that interval arithmetic proves to be
//! outside the part are neither refined nor kept.
//!
//! Both are stored as one binary tree of axis-aligned splits (a quadtree
//! split is two levels of it, an octree split three), which also serves as
//! the point-location index of the pore field.

use crate::error::PoreError;
use microfrep_core::{Interval, IntervalEval, PointEval, Tape};

/// How cells are refined.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Subdivision {
    /// Quadtree (2D) or octree (3D) over the smallest square / cube holding
    /// the bounds: a cell whose longest side exceeds the requested pore
    /// size is cut into `2^d` equal cells, so a cell at depth `i` has
    /// `1 / 2^(d i)` of the first box's area or volume (Eqs. 1-3).
    Tree,
    /// T-mesh refinement over the bounds: a cell whose area (volume)
    /// exceeds the pore size squared (cubed) is cut in two, across its
    /// longest side, at `percent` of that side (0.5 halves it). A cell too
    /// long in one direction only is thus cut in that direction alone,
    /// where the tree would cut it into `2^d`.
    TMesh {
        /// Where the cutting line (plane) goes, as a fraction of the side
        /// in (0, 1).
        percent: f64,
    },
}

/// A split decided by a custom rule ([`crate::Options::split_rule`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Split {
    /// Keep the cell as it is.
    Leaf,
    /// Cut into `2^d` equal cells.
    Tree,
    /// Cut in two across `axis` (0 = x, 1 = y, 2 = z) at `percent` of its
    /// side, the T-mesh split of the paper's Fig. 4 (direction and
    /// percentage).
    Across {
        /// Axis normal to the cutting line or plane.
        axis: usize,
        /// Position of the cut as a fraction of the side, in (0, 1).
        percent: f64,
    },
}

/// A cell handed to a custom split rule.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CellInfo {
    /// Lower corner.
    pub lo: [f64; 3],
    /// Upper corner.
    pub hi: [f64; 3],
    /// Number of splits above it.
    pub depth: usize,
    /// Requested pore size over the cell (the smallest sampled).
    pub size: f64,
}

/// How the part meets a cell.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Inside {
    /// The part covers the whole cell (proven by interval arithmetic).
    Full,
    /// The part's boundary may cross the cell.
    Boundary,
}

/// One leaf cell of the subdivision that holds part of the part.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cell {
    /// Lower corner.
    pub lo: [f64; 3],
    /// Upper corner.
    pub hi: [f64; 3],
    /// Number of binary splits above it.
    pub depth: usize,
    /// Requested pore size (smallest of the samples over the cell).
    pub size: f64,
    /// How the part meets it.
    pub inside: Inside,
}

impl Cell {
    /// Centre.
    pub fn center(&self) -> [f64; 3] {
        std::array::from_fn(|a| 0.5 * (self.lo[a] + self.hi[a]))
    }
    /// Half extents.
    pub fn half(&self) -> [f64; 3] {
        std::array::from_fn(|a| 0.5 * (self.hi[a] - self.lo[a]))
    }
}

pub(crate) const NONE: u32 = u32::MAX;

#[derive(Clone, Copy, Debug)]
pub(crate) enum Node {
    /// A leaf: index into [`Tree::leaves`].
    Leaf(u32),
    Split {
        axis: u8,
        at: f64,
        kids: [u32; 2],
    },
}

/// The subdivision: a binary tree of splits and its kept cells.
#[derive(Clone, Debug)]
pub struct Tree {
    pub(crate) dim: usize,
    pub(crate) lo: [f64; 3],
    pub(crate) hi: [f64; 3],
    pub(crate) nodes: Vec<Node>,
    /// Every leaf box (kept or dropped) and its kept cell (or NONE).
    pub(crate) leaves: Vec<([f64; 3], [f64; 3], u32)>,
    pub(crate) cells: Vec<Cell>,
    /// Leaf cells outside the part (dropped).
    pub(crate) dropped: usize,
}

/// What the subdivision needs to know.
pub(crate) struct Params<'a> {
    pub dim: usize,
    pub bounds: [[f64; 3]; 2],
    pub part: &'a Tape,
    pub size: &'a dyn Fn([f64; 3]) -> f64,
    pub subdivision: Subdivision,
    pub rule: Option<&'a (dyn Fn(&CellInfo) -> Split + Send + Sync)>,
    pub max_cells: usize,
}

/// Cells up to this much larger (relative) than the requested size are
/// not refined, so bounds proven by interval analysis, a little larger
/// than the part (about 0.1 % for R-function blocks), still give cells of
/// the requested size.
pub const SLACK: f64 = 1e-2;

/// Deepest binary split allowed.
pub const MAX_DEPTH: usize = 60;

impl Tree {
    /// Subdivides the box of `p.bounds` by the size field.
    pub(crate) fn build(p: &Params) -> Result<Tree, PoreError> {
        let [blo, bhi] = p.bounds;
        let (lo, hi) = match p.subdivision {
            Subdivision::Tree => {
                // The smallest square (cube) holding the bounds, centred on them.
                let side = (0..p.dim).map(|a| bhi[a] - blo[a]).fold(0.0, f64::max);
                let lo = std::array::from_fn(|a| {
                    if a < p.dim {
                        0.5 * (blo[a] + bhi[a]) - 0.5 * side
                    } else {
                        blo[a]
                    }
                });
                let hi = std::array::from_fn(|a| {
                    if a < p.dim {
                        0.5 * (blo[a] + bhi[a]) + 0.5 * side
                    } else {
                        bhi[a]
                    }
                });
                (lo, hi)
            }
            Subdivision::TMesh { percent } => {
                if !(percent > 0.0 && percent < 1.0) {
                    return Err(PoreError::Option {
                        name: "T-mesh percent",
                        value: percent,
                        why: "must be in (0, 1)",
                    });
                }
                (blo, bhi)
            }
        };
        let mut tree = Tree {
            dim: p.dim,
            lo,
            hi,
            nodes: vec![Node::Leaf(NONE)],
            leaves: Vec::new(),
            cells: Vec::new(),
            dropped: 0,
        };
        let mut iv = IntervalEval::new(p.part);
        let mut pt = PointEval::new(p.part);
        // Depth-first, first child first, so cell order is deterministic.
        let mut stack: Vec<(u32, [f64; 3], [f64; 3], usize)> = vec![(0, lo, hi, 0)];
        let mut pending = 1usize;
        while let Some((node, lo, hi, depth)) = stack.pop() {
            pending -= 1;
            let f = iv.eval(
                Interval::new(lo[0], hi[0]),
                Interval::new(lo[1], hi[1]),
                Interval::new(lo[2], hi[2]),
            );
            if !f.may_be_nan() && f.hi < 0.0 {
                tree.drop_leaf(node, lo, hi);
                continue;
            }
            let size = min_size(p, lo, hi)?;
            let split = decide(p, lo, hi, depth, size)?;
            let split = match split {
                Split::Leaf => None,
                s => Some(s),
            };
            match split {
                None => {
                    let full = !f.may_be_nan() && f.lo >= 0.0;
                    if !full && outside_by_samples(&mut pt, p.dim, lo, hi) {
                        tree.drop_leaf(node, lo, hi);
                        continue;
                    }
                    if tree.cells.len() >= p.max_cells {
                        return Err(too_many(p, lo, hi, size));
                    }
                    tree.nodes[node as usize] = Node::Leaf(tree.leaves.len() as u32);
                    tree.leaves.push((lo, hi, tree.cells.len() as u32));
                    tree.cells.push(Cell {
                        lo,
                        hi,
                        depth,
                        size,
                        inside: if full { Inside::Full } else { Inside::Boundary },
                    });
                }
                Some(s) => {
                    if depth + p.dim > MAX_DEPTH {
                        return Err(PoreError::TooDeep {
                            depth: MAX_DEPTH,
                            size,
                            at: center(lo, hi),
                        });
                    }
                    // The cuts of this split, as a list of (axis, percent);
                    // a tree split cuts every axis in half.
                    let cuts: Vec<(usize, f64)> = match s {
                        Split::Tree => (0..p.dim).map(|a| (a, 0.5)).collect(),
                        Split::Across { axis, percent } => vec![(axis, percent)],
                        Split::Leaf => unreachable!(),
                    };
                    let mut boxes = vec![(node, lo, hi)];
                    for (axis, percent) in cuts {
                        let mut next = Vec::with_capacity(boxes.len() * 2);
                        for (nd, lo, hi) in boxes {
                            let at = lo[axis] + percent * (hi[axis] - lo[axis]);
                            let a = tree.nodes.len() as u32;
                            tree.nodes.push(Node::Leaf(NONE));
                            tree.nodes.push(Node::Leaf(NONE));
                            tree.nodes[nd as usize] = Node::Split {
                                axis: axis as u8,
                                at,
                                kids: [a, a + 1],
                            };
                            let mut h0 = hi;
                            h0[axis] = at;
                            let mut l1 = lo;
                            l1[axis] = at;
                            next.push((a, lo, h0));
                            next.push((a + 1, l1, hi));
                        }
                        boxes = next;
                    }
                    let d = depth
                        + match s {
                            Split::Tree => p.dim,
                            _ => 1,
                        };
                    pending += boxes.len();
                    if tree.cells.len() + pending > p.max_cells {
                        return Err(too_many(p, lo, hi, size));
                    }
                    for (nd, lo, hi) in boxes.into_iter().rev() {
                        stack.push((nd, lo, hi, d));
                    }
                }
            }
        }
        Ok(tree)
    }

    fn drop_leaf(&mut self, node: u32, lo: [f64; 3], hi: [f64; 3]) {
        self.dropped += 1;
        self.nodes[node as usize] = Node::Leaf(self.leaves.len() as u32);
        self.leaves.push((lo, hi, NONE));
    }

    /// Kept cells, in tree order.
    pub fn cells(&self) -> &[Cell] {
        &self.cells
    }

    /// Leaf cells dropped as outside the part.
    pub fn dropped(&self) -> usize {
        self.dropped
    }

    #[inline]
    pub(crate) fn root_box_ref(&self) -> [&[f64; 3]; 2] {
        [&self.lo, &self.hi]
    }

    /// The box subdivided (S0): the bounds, or the square / cube around
    /// them for [`Subdivision::Tree`].
    pub fn root_box(&self) -> [[f64; 3]; 2] {
        [self.lo, self.hi]
    }

    /// Calls `f` for every kept cell whose closed box meets `lo..hi`.
    pub(crate) fn query(&self, lo: [f64; 3], hi: [f64; 3], f: &mut dyn FnMut(u32)) {
        let mut stack = vec![0usize];
        while let Some(n) = stack.pop() {
            match self.nodes[n] {
                Node::Leaf(l) => {
                    let c = self.leaves[l as usize].2;
                    if c != NONE {
                        f(c);
                    }
                }
                Node::Split { axis, at, kids } => {
                    let a = axis as usize;
                    if hi[a] >= at {
                        stack.push(kids[1] as usize);
                    }
                    if lo[a] <= at {
                        stack.push(kids[0] as usize);
                    }
                }
            }
        }
    }

    /// Whether some kept cell for which `keep` holds meets `lo..hi`.
    pub(crate) fn any(&self, lo: [f64; 3], hi: [f64; 3], keep: &dyn Fn(u32) -> bool) -> bool {
        let mut stack = vec![0usize];
        while let Some(n) = stack.pop() {
            match self.nodes[n] {
                Node::Leaf(l) => {
                    let c = self.leaves[l as usize].2;
                    if c != NONE && keep(c) {
                        return true;
                    }
                }
                Node::Split { axis, at, kids } => {
                    let a = axis as usize;
                    if hi[a] >= at {
                        stack.push(kids[1] as usize);
                    }
                    if lo[a] <= at {
                        stack.push(kids[0] as usize);
                    }
                }
            }
        }
        false
    }
}

fn center(lo: [f64; 3], hi: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|a| 0.5 * (lo[a] + hi[a]))
}

fn too_many(p: &Params, lo: [f64; 3], hi: [f64; 3], size: f64) -> PoreError {
    PoreError::TooManyCells {
        limit: p.max_cells,
        size,
        at: center(lo, hi),
    }
}

/// The requested pore size over a cell: the smallest of its value at the
/// centre and the corners (in 2D, at the middle of the z range).
fn min_size(p: &Params, lo: [f64; 3], hi: [f64; 3]) -> Result<f64, PoreError> {
    let c = center(lo, hi);
    let mut s = f64::INFINITY;
    let corners = 1usize << p.dim;
    for k in 0..=corners {
        let q: [f64; 3] = if k == corners {
            c
        } else {
            std::array::from_fn(|a| {
                if a >= p.dim {
                    c[a]
                } else if k >> a & 1 == 1 {
                    hi[a]
                } else {
                    lo[a]
                }
            })
        };
        let v = (p.size)(q);
        if !(v.is_finite() && v > 0.0) {
            return Err(PoreError::Size { value: v, at: q });
        }
        s = s.min(v);
    }
    Ok(s)
}

/// The split a cell gets.
fn decide(
    p: &Params,
    lo: [f64; 3],
    hi: [f64; 3],
    depth: usize,
    size: f64,
) -> Result<Split, PoreError> {
    if let Some(rule) = p.rule {
        let s = rule(&CellInfo {
            lo,
            hi,
            depth,
            size,
        });
        if let Split::Across { axis, percent } = s {
            if axis >= p.dim || !(percent > 0.0 && percent < 1.0) {
                return Err(PoreError::Option {
                    name: "split rule (axis, percent)",
                    value: if axis >= p.dim { axis as f64 } else { percent },
                    why: "the axis must be one of the subdivided ones and the percent in (0, 1)",
                });
            }
        }
        return Ok(s);
    }
    let ext: Vec<f64> = (0..p.dim).map(|a| hi[a] - lo[a]).collect();
    let slack = 1.0 + SLACK;
    Ok(match p.subdivision {
        Subdivision::Tree => {
            if ext.iter().any(|&e| e > size * slack) {
                Split::Tree
            } else {
                Split::Leaf
            }
        }
        Subdivision::TMesh { percent } => {
            let measure: f64 = ext.iter().product();
            if measure > size.powi(p.dim as i32) * slack {
                let mut axis = 0;
                for a in 1..p.dim {
                    if ext[a] > ext[axis] * (1.0 + 1e-9) {
                        axis = a;
                    }
                }
                Split::Across { axis, percent }
            } else {
                Split::Leaf
            }
        }
    })
}

/// Whether the part is not positive at any point of a 3^d lattice over
/// the cell (then the cell is dropped even though its interval was
/// inconclusive: it holds at most a sliver of the part, or touches it only
/// along its boundary).
fn outside_by_samples(pt: &mut PointEval, dim: usize, lo: [f64; 3], hi: [f64; 3]) -> bool {
    let n = 3usize.pow(dim as u32);
    for k in 0..n {
        let mut idx = [1usize; 3];
        let mut r = k;
        for i in idx.iter_mut().take(dim) {
            *i = r % 3;
            r /= 3;
        }
        let q: [f64; 3] = std::array::from_fn(|a| lo[a] + (hi[a] - lo[a]) * idx[a] as f64 / 2.0);
        let v = pt.eval(q);
        if v.is_nan() || v > 0.0 {
            return false;
        }
    }
    true
}
