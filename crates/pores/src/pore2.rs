//! Solving a 2D pore for a porosity (Eqs. 5-8).
//!
//! The parent polygon is the cell scaled by `kappa` about its centre
//! (`kappa = 1`, the paper's Fig. 12: the derived points lie on the cell's
//! own sides and the pore is closed). The derived points sit at fractions
//! `r1..r4` along the parent's sides. Three are drawn at random around a
//! base configuration of the right area and the fourth follows from Eq. 8
//! with `alpha = 5/6`; when the pore reaches past the cell (`kappa > 1`)
//! the fourth is instead solved on the exact area of the pore clipped to
//! the cell.
//!
//! With a corner weight `w != 1` the arcs are rational
//! ([`crate::curve::rational_bspline`]) and `alpha` is
//! [`crate::curve::alpha`]`(w)` instead of 5/6: the enclosed area is still
//! a fixed share of the control polygon, so Eq. 8 still gives the fourth
//! distance in closed form.

use crate::curve::{
    alpha, clipped_area, derived_polygon, polygon_fraction, rational_bspline, solve_r4, Quad, P2,
};
use crate::rng::Rng;

/// Largest parent scale: at 4/3 the largest pore covers the cell's corners.
pub const MAX_KAPPA: f64 = 4.0 / 3.0;

/// A solved 2D pore.
#[derive(Clone, Debug)]
pub(crate) struct Solved2 {
    /// Fractions along the parent's sides (first side from the parent's
    /// lower-left corner, counter-clockwise).
    pub r: [f64; 4],
    /// The derived polygon (the curve's control polygon).
    pub ctrl: [P2; 4],
    /// The curve's four arcs.
    pub arcs: [Quad; 4],
    /// Exact porosity of the cell.
    pub porosity: f64,
    /// Whether Eq. 8 gave the fourth distance (else it was solved on the
    /// clipped area).
    pub eq8: bool,
}

/// Cell and parent geometry.
struct Geometry {
    lo: P2,
    hi: P2,
    plo: P2,
    phi: P2,
    area: f64,
    parent_area: f64,
    /// Corner weight of the arcs.
    w: f64,
    /// Share of the control polygon the curve encloses.
    alpha: f64,
}

impl Geometry {
    fn new(lo: P2, hi: P2, kappa: f64, w: f64) -> Geometry {
        let c = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])];
        let h = [0.5 * (hi[0] - lo[0]) * kappa, 0.5 * (hi[1] - lo[1]) * kappa];
        let area = (hi[0] - lo[0]) * (hi[1] - lo[1]);
        Geometry {
            lo,
            hi,
            plo: [c[0] - h[0], c[1] - h[1]],
            phi: [c[0] + h[0], c[1] + h[1]],
            area,
            parent_area: area * kappa * kappa,
            w,
            alpha: alpha(w),
        }
    }

    fn pore(&self, r: [f64; 4]) -> ([P2; 4], [Quad; 4]) {
        let ctrl = derived_polygon(self.plo, self.phi, r);
        (ctrl, rational_bspline(&ctrl, self.w))
    }

    /// Porosity of the cell with fractions `r`.
    fn porosity(&self, r: [f64; 4]) -> f64 {
        let (_, arcs) = self.pore(r);
        clipped_area(&arcs, self.lo, self.hi) / self.area
    }

    /// Porosity without clipping (Eqs. 4-6).
    fn unclipped(&self, r: [f64; 4]) -> f64 {
        self.alpha * polygon_fraction(r) * self.parent_area / self.area
    }
}

/// The symmetric configuration with polygon fraction `q`: all four
/// fractions equal for `q >= 1/2` (a rotated square), alternating `a`,
/// `1 - a` below (a parallelogram along a diagonal, the elongated pores).
pub fn base(q: f64) -> [f64; 4] {
    let q = q.clamp(0.0, 1.0);
    if q >= 0.5 {
        let r = 0.5 * (1.0 - (2.0 * q - 1.0).sqrt());
        [r; 4]
    } else {
        let a = 0.5 * (1.0 - (1.0 - 2.0 * q).sqrt());
        [a, 1.0 - a, a, 1.0 - a]
    }
}

/// Largest porosity for a parent scale: the pore of the parent polygon
/// itself (all fractions 0), clipped to the cell.
pub fn max_porosity(kappa: f64) -> f64 {
    max_porosity_weighted(kappa, 1.0)
}

/// As [`max_porosity`], for arcs of corner weight `w`.
pub fn max_porosity_weighted(kappa: f64, w: f64) -> f64 {
    Geometry::new([-1.0, -1.0], [1.0, 1.0], kappa, w).porosity([0.0; 4])
}

/// Bisection for `g(x) = target` on `[a, b]` with `g` increasing.
fn bisect(mut a: f64, mut b: f64, target: f64, g: impl Fn(f64) -> f64) -> f64 {
    for _ in 0..80 {
        let m = 0.5 * (a + b);
        if g(m) < target {
            a = m;
        } else {
            b = m;
        }
    }
    0.5 * (a + b)
}

/// Solves the pore of the cell `lo..hi` for porosity `target` in
/// `(0, max_porosity(kappa)]`, with random distances of spread `sigma`
/// (0 gives the symmetric pore) and arcs of corner weight `w`.
pub(crate) fn solve(
    lo: P2,
    hi: P2,
    kappa: f64,
    w: f64,
    target: f64,
    sigma: f64,
    rng: &mut Rng,
) -> Solved2 {
    let g = Geometry::new(lo, hi, kappa, w);
    // Polygon fraction of the symmetric pore: closed form when the pore
    // stays in the cell, else bisection on the clipped area (which grows
    // with q along the base family).
    let q_open = target * g.area / (g.alpha * g.parent_area);
    let q = if q_open <= 1.0 && (g.porosity(base(q_open)) - target).abs() < 1e-12 {
        q_open
    } else {
        bisect(0.0, 1.0, target, |q| g.porosity(base(q)))
    };
    let mut b = base(q);
    // Orientation: which side is solved, and for elongated pores which
    // diagonal they lie along.
    let rot = (rng.next_u64() % 4) as usize;
    if q < 0.5 && rng.unit() < 0.5 {
        b = b.map(|r| 1.0 - r);
    }
    let u = [rng.signed(), rng.signed(), rng.signed()];
    let mut sig = sigma;
    for attempt in 0..12 {
        if attempt == 11 || sig == 0.0 {
            break;
        }
        let mut r = b;
        for k in 0..3 {
            r[(rot + k) % 4] = (b[(rot + k) % 4] + 0.5 * sig * u[k]).clamp(0.0, 1.0);
        }
        let i4 = (rot + 3) % 4;
        // Eq. 8 in fractions, labels rotated so the solved side is last.
        let rr = |k: usize| r[(rot + k) % 4];
        let r4 = solve_r4(rr(0), rr(1), rr(2), q_open);
        if r4.is_finite() && (0.0..=1.0).contains(&r4) {
            r[i4] = r4;
            let p = g.porosity(r);
            if (p - target).abs() <= 1e-12 * target.max(1e-3) && (p - g.unclipped(r)).abs() <= 1e-12
            {
                return finish(&g, r, true);
            }
        }
        // The pore reaches past the cell: the fourth fraction from the
        // clipped area, on a bracket found by sampling.
        if kappa > 1.0 {
            let f = |x: f64| {
                let mut s = r;
                s[i4] = x;
                g.porosity(s) - target
            };
            let xs: Vec<f64> = (0..=16).map(|k| k as f64 / 16.0).collect();
            let vs: Vec<f64> = xs.iter().map(|&x| f(x)).collect();
            if let Some(k) = (0..16).find(|&k| vs[k] * vs[k + 1] <= 0.0) {
                let (mut a, mut bb, mut fa) = (xs[k], xs[k + 1], vs[k]);
                for _ in 0..80 {
                    let m = 0.5 * (a + bb);
                    let fm = f(m);
                    if (fm <= 0.0) == (fa <= 0.0) {
                        a = m;
                        fa = fm;
                    } else {
                        bb = m;
                    }
                }
                r[i4] = 0.5 * (a + bb);
                if (g.porosity(r) - target).abs() <= 1e-9 {
                    return finish(&g, r, false);
                }
            }
        }
        sig *= 0.5;
    }
    finish(&g, b, q == q_open)
}

/// The pore of the cell `lo..hi` for porosity `target` with the first
/// three fractions `r3` set by hand: the fourth from Eq. 8 (or, where the
/// pore reaches past the cell, from the clipped area), `None` when no
/// fourth in [0, 1] meets the porosity.
pub(crate) fn solve_given(
    lo: P2,
    hi: P2,
    kappa: f64,
    w: f64,
    target: f64,
    r3: [f64; 3],
) -> Option<Solved2> {
    let g = Geometry::new(lo, hi, kappa, w);
    let q_open = target * g.area / (g.alpha * g.parent_area);
    let mut r = [r3[0], r3[1], r3[2], 0.0];
    let r4 = solve_r4(r3[0], r3[1], r3[2], q_open);
    if r4.is_finite() && (0.0..=1.0).contains(&r4) {
        r[3] = r4;
        let p = g.porosity(r);
        if (p - target).abs() <= 1e-12 * target.max(1e-3) && (p - g.unclipped(r)).abs() <= 1e-12 {
            return Some(finish(&g, r, true));
        }
    }
    // Clipped by the cell: the fourth fraction by bisection on the clipped
    // area over [0, 1], where the porosity changes sign against the target.
    let f = |x: f64| {
        let mut s = r;
        s[3] = x;
        g.porosity(s) - target
    };
    let fa0 = f(0.0);
    if fa0 * f(1.0) > 0.0 {
        return None;
    }
    let (mut a, mut b) = (0.0, 1.0);
    for _ in 0..80 {
        let m = 0.5 * (a + b);
        if (f(m) <= 0.0) == (fa0 <= 0.0) {
            a = m;
        } else {
            b = m;
        }
    }
    r[3] = 0.5 * (a + b);
    ((g.porosity(r) - target).abs() <= 1e-9).then(|| finish(&g, r, false))
}

fn finish(g: &Geometry, r: [f64; 4], eq8: bool) -> Solved2 {
    let (ctrl, arcs) = g.pore(r);
    Solved2 {
        r,
        ctrl,
        arcs,
        porosity: g.porosity(r),
        eq8,
    }
}
