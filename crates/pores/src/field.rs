//! The pore structure as a [`Field`]: positive in the solid, negative in the
//! pores, about a distance near the pore surfaces.
//!
//! Each cell `C` subtracts its own pore `P_C` (the paper's Boolean
//! difference of the pore and the sub-region), so the pore space is the
//! union of `C ∩ P_C` and the field is
//! `f = min(cap, min_C max(-c_C, -q_C))`, with `c_C` the distance-like
//! function of the cell box (`min_i (h_i - |x_i - m_i|)`, positive inside)
//! and `q_C` that of the pore (positive inside). It is continuous across
//! cell faces (a min and max of continuous functions). A cell farther than
//! `cap` (Chebyshev) from a point cannot bring `f` below `cap`, so each
//! leaf of the subdivision keeps the list of cells within `cap` of it and a
//! point costs one tree descent and a few pores.
//!
//! Bounds: every term is Lipschitz (the box functions with constant 1, the
//! pores with the constant of their table or 1 for the 2D signed
//! distances), so over a box with centre `c` and half-diagonal `r`,
//! `f in f(c) +- L r`, clamped to `[floor, cap]` where `floor` is minus the
//! largest cell half-extent; boxes with no pore cell within `cap` are
//! exactly `cap`.

use crate::cubemap::{gauge, CubeMap};
use crate::curve::{signed_distance, Quad};
use crate::tree::{Tree, NONE};
use microfrep_core::{Field, Interval};
use std::sync::Arc;

/// A 3D pore in the field.
#[derive(Clone, Debug)]
pub(crate) struct Pore3 {
    pub center: [f64; 3],
    pub inv_half: [f64; 3],
    pub lambda: f64,
    /// `m / lambda`, with `m = lambda R_mean h_min` the scale that makes
    /// `q = m (1 - g / lambda)` about a distance near the surface.
    pub k: f64,
    pub m: f64,
    pub table: Arc<CubeMap>,
}

/// A 2D pore in the field.
#[derive(Clone, Debug)]
pub(crate) struct Pore2 {
    pub arcs: [Quad; 4],
}

#[derive(Clone, Debug)]
pub(crate) enum Pores {
    Two(Vec<Option<Pore2>>),
    Three(Vec<Option<Pore3>>),
}

/// The pore structure of a part: `f >= 0` in the solid between the pores
/// (intersect it with the part, [`PoreField::solid`], for the porous part).
#[derive(Debug)]
pub struct PoreField {
    pub(crate) name: String,
    pub(crate) dim: usize,
    pub(crate) tree: Tree,
    /// Per leaf of the tree: range into `cand`.
    pub(crate) cand_start: Vec<u32>,
    pub(crate) cand: Vec<u32>,
    pub(crate) pores: Pores,
    pub(crate) cap: f64,
    pub(crate) lip: f64,
    pub(crate) floor: f64,
}

impl PoreField {
    #[inline]
    fn leaf_of(&self, p: [f64; 3]) -> usize {
        let [lo, hi] = self.tree.root_box();
        let q: [f64; 3] = std::array::from_fn(|a| p[a].clamp(lo[a], hi[a]));
        self.tree.locate(q) as usize
    }

    /// Value and gradient (the gradient of the active term).
    fn value(&self, p: [f64; 3], want_grad: bool) -> (f64, [f64; 3]) {
        if p.iter().any(|v| v.is_nan()) {
            return (f64::NAN, [f64::NAN; 3]);
        }
        let leaf = self.leaf_of(p);
        let (s, e) = (
            self.cand_start[leaf] as usize,
            self.cand_start[leaf + 1] as usize,
        );
        let mut best = self.cap;
        let mut grad = [0.0; 3];
        for &c in &self.cand[s..e] {
            let cell = &self.tree.cells[c as usize];
            // -c_C: the largest distance outside a face pair.
            let mut box_d = f64::NEG_INFINITY;
            let mut box_axis = 0;
            for a in 0..self.dim {
                let m = 0.5 * (cell.lo[a] + cell.hi[a]);
                let h = 0.5 * (cell.hi[a] - cell.lo[a]);
                let d = (p[a] - m).abs() - h;
                if d > box_d {
                    box_d = d;
                    box_axis = a;
                }
            }
            if box_d >= best {
                continue;
            }
            let (nq, gq) = match &self.pores {
                Pores::Three(v) => match &v[c as usize] {
                    Some(pore) => {
                        let y: [f64; 3] =
                            std::array::from_fn(|a| (p[a] - pore.center[a]) * pore.inv_half[a]);
                        let (g, dg) = gauge(&pore.table, y);
                        // -q = k g - m.
                        (
                            pore.k * g - pore.m,
                            std::array::from_fn(|a| pore.k * dg[a] * pore.inv_half[a]),
                        )
                    }
                    None => (f64::INFINITY, [0.0; 3]),
                },
                Pores::Two(v) => match &v[c as usize] {
                    Some(pore) => {
                        let (d, g) = signed_distance(&pore.arcs, [p[0], p[1]]);
                        (-d, [-g[0], -g[1], 0.0])
                    }
                    None => (f64::INFINITY, [0.0; 3]),
                },
            };
            let (term, g) = if box_d >= nq {
                let mut g = [0.0; 3];
                if want_grad {
                    let m = 0.5 * (cell.lo[box_axis] + cell.hi[box_axis]);
                    g[box_axis] = if p[box_axis] >= m { 1.0 } else { -1.0 };
                }
                (box_d, g)
            } else {
                (nq, gq)
            };
            if term < best {
                best = term;
                grad = g;
            }
        }
        (best, grad)
    }

    /// The value cap (the field's largest value: solid far from any pore).
    pub fn cap(&self) -> f64 {
        self.cap
    }

    /// A Lipschitz constant of the field.
    pub fn lipschitz(&self) -> f64 {
        self.lip
    }

    /// 2 or 3.
    pub fn dim(&self) -> usize {
        self.dim
    }
}

impl Field for PoreField {
    fn name(&self) -> &str {
        &self.name
    }

    fn eval(&self, p: [f64; 3]) -> f64 {
        self.value(p, false).0
    }

    fn grad(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
        self.value(p, true)
    }

    fn interval(&self, b: [Interval; 3]) -> Interval {
        if b.iter().any(|i| i.is_nan()) {
            return Interval::nan();
        }
        let dim = self.dim;
        let lo: [f64; 3] = std::array::from_fn(|a| b[a].lo);
        let hi: [f64; 3] = std::array::from_fn(|a| b[a].hi);
        // No pore cell within the cap: the field is the cap throughout.
        let elo: [f64; 3] = std::array::from_fn(|a| if a < dim { lo[a] - self.cap } else { lo[a] });
        let ehi: [f64; 3] = std::array::from_fn(|a| if a < dim { hi[a] + self.cap } else { hi[a] });
        let has_pore = |c: u32| match &self.pores {
            Pores::Two(v) => v[c as usize].is_some(),
            Pores::Three(v) => v[c as usize].is_some(),
        };
        let [rlo, rhi] = self.tree.root_box();
        let q: [f64; 3] =
            std::array::from_fn(|a| if a < dim { elo[a].max(rlo[a]) } else { rlo[a] });
        let r: [f64; 3] =
            std::array::from_fn(|a| if a < dim { ehi[a].min(rhi[a]) } else { rhi[a] });
        if (0..dim).any(|a| q[a] > r[a]) || !self.tree.any(q, r, &has_pore) {
            return Interval::point(self.cap);
        }
        let c: [f64; 3] =
            std::array::from_fn(|a| if a < dim { 0.5 * (lo[a] + hi[a]) } else { 0.0 });
        let rad = (0..dim)
            .map(|a| (0.5 * (hi[a] - lo[a])).powi(2))
            .sum::<f64>()
            .sqrt();
        if !rad.is_finite() || !c.iter().all(|v| v.is_finite()) {
            return Interval::new(self.floor, self.cap);
        }
        let v = self.eval(c);
        let w = self.lip * rad;
        let l = (v - w).max(self.floor);
        let h = (v + w).min(self.cap);
        // Rounding in the value and the radius: widen slightly.
        let eps = 1e-12 * (v.abs() + w + self.cap);
        Interval::new(l - eps, h + eps)
    }

    fn grad_interval(&self, _b: [Interval; 3]) -> [Interval; 3] {
        let l = Interval::new(-self.lip, self.lip);
        if self.dim == 2 {
            [l, l, Interval::point(0.0)]
        } else {
            [l, l, l]
        }
    }

    fn eval_batch(&self, x: &[f32], y: &[f32], z: &[f32], out: &mut [f32]) {
        for i in 0..out.len() {
            out[i] = self.value([x[i] as f64, y[i] as f64, z[i] as f64], false).0 as f32;
        }
    }
}

/// Candidate lists: for each leaf, the kept cells within `cap` of it
/// (Chebyshev, on the subdivided axes).
pub(crate) fn candidates(
    tree: &Tree,
    cap: f64,
    has_pore: &dyn Fn(u32) -> bool,
) -> (Vec<u32>, Vec<u32>) {
    let mut start = Vec::with_capacity(tree.leaves.len() + 1);
    let mut cand = Vec::new();
    for &(lo, hi, cell) in &tree.leaves {
        start.push(cand.len() as u32);
        let elo: [f64; 3] = std::array::from_fn(|a| if a < tree.dim { lo[a] - cap } else { lo[a] });
        let ehi: [f64; 3] = std::array::from_fn(|a| if a < tree.dim { hi[a] + cap } else { hi[a] });
        let first = cand.len();
        // The leaf's own cell first: it usually decides, and prunes the rest.
        if cell != NONE && has_pore(cell) {
            cand.push(cell);
        }
        tree.query(elo, ehi, &mut |c| {
            if c != cell && has_pore(c) {
                cand.push(c);
            }
        });
        debug_assert!(cand.len() >= first);
    }
    start.push(cand.len() as u32);
    (start, cand)
}
