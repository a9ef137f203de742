//! Strut lattices as unit cells: capsules (round-ended cylinders) between
//! node pairs, united by `max` so the cell value is `r - distance to the
//! nearest strut axis`, a true distance field outside the junctions.
//!
//! Each lattice is a periodic graph: a node basis in the unit cell,
//! translated by whole cells, with bonds between nodes at one distance.
//! All nodes lie on a quarter-cell grid, so the graph is built in exact
//! integer arithmetic. The cell keeps every strut that comes within
//! [`MAX_RADIUS`] of it, so replicated cells join without seams.

use crate::replicate::{replicate, Wave};
use microfrep_core::transform::P3;
use microfrep_core::Expr;

/// Largest strut radius, in cell units, for which the cell holds every strut
/// that reaches into it.
pub const MAX_RADIUS: f64 = 0.3;

/// The strut lattice families, each a periodic graph of bonds of one
/// length between the nodes of a cubic cell.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StrutLattice {
    /// Cube edges.
    SimpleCubic,
    /// Corners to the body centre.
    Bcc,
    /// Face diagonals.
    Fcc,
    /// Face diagonals plus the octahedron between face centres.
    Octet,
    /// Edges of the truncated octahedra of the bcc packing (Kelvin foam).
    Kelvin,
    /// Tetrahedral bonds of the diamond crystal.
    Diamond,
}

/// A lattice point in quarter-cell units.
pub(crate) type Q = [i32; 3];

impl StrutLattice {
    /// Every family, in a fixed order.
    pub const ALL: [StrutLattice; 6] = [
        StrutLattice::SimpleCubic,
        StrutLattice::Bcc,
        StrutLattice::Fcc,
        StrutLattice::Octet,
        StrutLattice::Kelvin,
        StrutLattice::Diamond,
    ];

    /// Short name (as used by the `mf*` HyperFun library and the CLI).
    pub fn name(self) -> &'static str {
        match self {
            StrutLattice::SimpleCubic => "simple-cubic",
            StrutLattice::Bcc => "bcc",
            StrutLattice::Fcc => "fcc",
            StrutLattice::Octet => "octet",
            StrutLattice::Kelvin => "kelvin",
            StrutLattice::Diamond => "diamond",
        }
    }

    /// Node basis (quarter units, in [0, 4)) and squared bond length.
    pub(crate) fn basis(self) -> (Vec<Q>, i32) {
        let fcc = vec![[0, 0, 0], [0, 2, 2], [2, 0, 2], [2, 2, 0]];
        match self {
            StrutLattice::SimpleCubic => (vec![[0, 0, 0]], 16),
            StrutLattice::Bcc => (vec![[0, 0, 0], [2, 2, 2]], 12),
            StrutLattice::Fcc | StrutLattice::Octet => (fcc, 8),
            StrutLattice::Kelvin => {
                // Permutations of (0, +-1, +-2), taken modulo the cell.
                let mut v = Vec::new();
                for a in [-1, 1] {
                    for b in [-2, 2] {
                        for perm in [
                            [0, a, b],
                            [0, b, a],
                            [a, 0, b],
                            [b, 0, a],
                            [a, b, 0],
                            [b, a, 0],
                        ] {
                            let q = perm.map(|c: i32| c.rem_euclid(4));
                            if !v.contains(&q) {
                                v.push(q);
                            }
                        }
                    }
                }
                (v, 2)
            }
            StrutLattice::Diamond => {
                let mut v = fcc.clone();
                v.extend(fcc.iter().map(|q| q.map(|c| c + 1)));
                (v, 3)
            }
        }
    }

    /// The struts (end points in cell units) that come within
    /// [`MAX_RADIUS`] of the unit cell `[0, 1]^3`.
    pub fn struts(self) -> Vec<([f64; 3], [f64; 3])> {
        let (basis, len2) = self.basis();
        let mut nodes = Vec::new();
        // Nodes from one cell below to two above, so every bond touching
        // [0, 1]^3 (or passing within MAX_RADIUS of it) has both ends.
        for i in -1..=2 {
            for j in -1..=2 {
                for k in -1..=2 {
                    nodes.extend(
                        basis
                            .iter()
                            .map(|q| [q[0] + 4 * i, q[1] + 4 * j, q[2] + 4 * k]),
                    );
                }
            }
        }
        let mut out = Vec::new();
        for (n, a) in nodes.iter().enumerate() {
            for b in &nodes[n + 1..] {
                if !self.is_bond(a, b, len2) {
                    continue;
                }
                let (pa, pb) = (a.map(|c| c as f64 / 4.0), b.map(|c| c as f64 / 4.0));
                if segment_box_distance(pa, pb) <= MAX_RADIUS + 1e-9 {
                    out.push((pa, pb));
                }
            }
        }
        out
    }
}

impl StrutLattice {
    /// Whether lattice nodes `a` and `b` (quarter units) are joined by a strut.
    pub(crate) fn is_bond(self, a: &Q, b: &Q, len2: i32) -> bool {
        let d2: i32 = (0..3).map(|i| (a[i] - b[i]).pow(2)).sum();
        // Fcc keeps only bonds lying in a cell face plane.
        let in_face = (0..3).any(|i| a[i] == b[i] && a[i].rem_euclid(4) == 0);
        d2 == len2 && (self != StrutLattice::Fcc || in_face)
    }

    /// For each basis node, the offsets (quarter units) to the nodes it is
    /// bonded to, in a fixed order.
    pub(crate) fn bond_offsets(self) -> Vec<Vec<Q>> {
        let (basis, len2) = self.basis();
        let mut nodes = Vec::new();
        for i in -1..=1 {
            for j in -1..=1 {
                for k in -1..=1 {
                    nodes.extend(
                        basis
                            .iter()
                            .map(|q| [q[0] + 4 * i, q[1] + 4 * j, q[2] + 4 * k]),
                    );
                }
            }
        }
        basis
            .iter()
            .map(|a| {
                nodes
                    .iter()
                    .filter(|b| self.is_bond(a, b, len2))
                    .map(|b| [b[0] - a[0], b[1] - a[1], b[2] - a[2]])
                    .collect()
            })
            .collect()
    }
}

/// Distance from a segment to the unit cube; convex along the segment, so
/// a fine sampling is accurate to a small fraction of the cell.
fn segment_box_distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    const STEPS: usize = 64;
    (0..=STEPS)
        .map(|s| {
            let t = s as f64 / STEPS as f64;
            let d2: f64 = (0..3)
                .map(|i| {
                    let c = a[i] + (b[i] - a[i]) * t;
                    (-c).max(c - 1.0).max(0.0).powi(2)
                })
                .sum();
            d2.sqrt()
        })
        .fold(f64::INFINITY, f64::min)
}

/// Distance from `p` to the segment `a b`.
fn segment_distance(p: &P3, a: [f64; 3], b: [f64; 3]) -> Expr {
    let e: [f64; 3] = std::array::from_fn(|i| b[i] - a[i]);
    let e2: f64 = e.iter().map(|c| c * c).sum();
    let d: Vec<Expr> = (0..3).map(|i| &p[i] - a[i]).collect();
    let h = ((&d[0] * e[0] + &d[1] * e[1] + &d[2] * e[2]) / e2)
        .max(0.0)
        .min(1.0);
    let r: Vec<Expr> = (0..3).map(|i| &d[i] - &h * e[i]).collect();
    (r[0].square() + r[1].square() + r[2].square()).sqrt()
}

/// The unit cell on `[0, 1]^3` at the (cell-unit) point `q`: `r - min_i dist_i`.
/// `r` may be a field (at most [`MAX_RADIUS`]).
pub fn strut_cell(kind: StrutLattice, q: &P3, r: impl Into<Expr>) -> Expr {
    let nearest = kind
        .struts()
        .into_iter()
        .map(|(a, b)| segment_distance(q, a, b))
        .reduce(|x, y| x.min(y))
        .expect("every lattice has struts");
    r.into() - nearest
}

/// The lattice through space with cubic cells of size `cell` and strut
/// radius `r` in length units (may be a field of the point).
/// `cell` may be a field too (a variable period).
pub fn strut_lattice(
    kind: StrutLattice,
    p: &P3,
    cell: impl Into<Expr>,
    r: impl Into<Expr>,
) -> Expr {
    let cell = cell.into();
    let waves = std::array::from_fn(|_| Wave::Sawtooth(cell.clone()));
    let q = replicate(p, &waves, [0.0; 3], [1.0; 3]);
    strut_cell(kind, &q, r.into() / &cell) * cell
}
