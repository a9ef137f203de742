//! Ray casting with interval arithmetic. Each ray is clipped to the model's
//! box, then its depth range is split recursively, nearest half first,
//! skipping every segment whose interval bound (over the segment's bounding
//! box) proves it empty, down to quarter-pixel segments, which are sampled at
//! their ends and middle: a feature the ray crosses for more than an eighth
//! of a pixel is found however thin it is across.
//!
//! Loose bounds (deep R-function trees) would make that search visit every
//! quarter pixel of depth, so each ray has a budget of interval evaluations,
//! enough to descend once to a quarter pixel and test the siblings on the
//! way (two per halving); past it, segments of 256 samples are sampled densely in one batch at half
//! a pixel spacing instead. The first sample at or inside the surface is
//! refined by bisection. Where a ray neither hits at the fine level nor
//! has a quarter of its interval evaluations decide anything, the bounds
//! are too loose to help, and the next rays of the tile are sampled without
//! them.
//!
//! A model that is one data field alone (a mesh bound as the whole model)
//! is first asked where each ray enters it ([`Field::ray_entry`]): a mesh
//! answers by intersecting the ray with its triangles through its BVH,
//! exactly and in one traversal, where the search above would evaluate
//! the distance and the sign of the winding number at dozens of points.
//! Rays the field cannot answer are searched as above.

use crate::camera::{Camera, V3};
use microfrep_core::{
    BatchEval, Field, Interval, IntervalEval, Op, PointEval, RayEntry, Tape, BLOCK,
};
use std::sync::Arc;

/// Bisection steps after a hit: depth error below half a pixel / 2^14.
const BISECT: usize = 14;
/// Sample spacing along a ray once the budget is spent, in pixels.
const STEP_PIXELS: f64 = 0.5;
/// Shortest segment of the interval search, in pixels.
const FINE_PIXELS: f64 = 0.25;

/// Finds the first surface point along each camera ray (see the module
/// docs for the search); keeps evaluators and per-tile state between rays.
pub struct Tracer<'t> {
    cam: &'t Camera,
    /// The box rays are clipped to.
    lo: V3,
    hi: V3,
    iv: IntervalEval,
    pe: PointEval,
    batch: BatchEval,
    /// Whether at least a quarter of the last ray's interval evaluations
    /// decided their segment.
    bounds_help: bool,
    /// The field the model is, where the model is one data field at the
    /// coordinates themselves: asked first where each ray enters it
    /// ([`Field::ray_entry`]).
    direct: Option<Arc<dyn Field>>,
}

/// The field a tape's output 0 is, when that output is field value of the
/// coordinates `x, y, z` unchanged.
fn bare_field(tape: &Tape) -> Option<Arc<dyn Field>> {
    let ops = tape.ops();
    let out = *tape.outputs().first()? as usize;
    match ops.get(out)? {
        Op::Field {
            field,
            comp: 0,
            args,
        } => {
            let plain = (0..3)
                .all(|k| matches!(ops.get(args[k] as usize), Some(Op::Var(a)) if *a as usize == k));
            plain
                .then(|| tape.fields().get(*field as usize).cloned())
                .flatten()
        }
        _ => None,
    }
}

impl<'t> Tracer<'t> {
    /// A tracer of `tape` (output 0) seen by `cam` inside the box `lo`..`hi`.
    pub fn new(tape: &Tape, cam: &'t Camera, lo: V3, hi: V3) -> Tracer<'t> {
        Tracer {
            cam,
            lo,
            hi,
            iv: IntervalEval::new(tape),
            pe: PointEval::new(tape),
            batch: BatchEval::new(tape),
            bounds_help: true,
            direct: bare_field(tape),
        }
    }

    /// The first hit of the ray through `(u, v)` over `t` as the field
    /// finds it directly, `None` where it cannot tell. An entry depth is
    /// moved inside by the bisection's tolerance, as a bisected hit is, so
    /// the normal there is the surface's, not the rounding's.
    fn direct_ray(&self, u: f64, v: f64, t: [f64; 2]) -> Option<Option<f64>> {
        let f = self.direct.as_ref()?;
        let o = self.cam.point(u, v, 0.0);
        match f.ray_entry(o, self.cam.dir, t) {
            RayEntry::Unknown => None,
            RayEntry::Miss => Some(None),
            RayEntry::Enter(e) => {
                let nudge = FINE_PIXELS * self.cam.scale * 0.5f64.powi(BISECT as i32);
                Some(Some((e + nudge).min(t[1])))
            }
        }
    }

    /// The depth range where the ray through `(u, v)` is inside the box.
    fn clip(&self, u: f64, v: f64) -> Option<[f64; 2]> {
        let o = self.cam.point(u, v, 0.0);
        let d = self.cam.dir;
        let (mut t0, mut t1) = (0.0f64, self.cam.depth);
        for a in 0..3 {
            if d[a] == 0.0 {
                if o[a] < self.lo[a] || o[a] > self.hi[a] {
                    return None;
                }
                continue;
            }
            let (p, q) = ((self.lo[a] - o[a]) / d[a], (self.hi[a] - o[a]) / d[a]);
            t0 = t0.max(p.min(q));
            t1 = t1.min(p.max(q));
        }
        (t0 <= t1).then_some([t0, t1])
    }

    /// Forgets what earlier rays learnt about the bounds: call at the start
    /// of each tile so an image does not depend on how tiles were scheduled.
    pub fn start_tile(&mut self) {
        self.bounds_help = true;
    }

    /// Depths of the first hits of the rays through the pixels of the tile
    /// at `(x0, y0)` of `w x h` pixels, row by row. The rays of the tile are
    /// searched together first: their depth range is split, nearest part
    /// first, and parts are skipped for all of them while one interval
    /// evaluation over the box the bundle sweeps there proves them empty;
    /// from the first part that may hold surface each ray is searched on its
    /// own, as [`Self::pixel`] does.
    pub fn tile(&mut self, x0: usize, y0: usize, w: usize, h: usize) -> Vec<Option<f64>> {
        let cam = self.cam;
        let n = w * h;
        let mut hits = vec![None; n];
        // Active rays: (index in the tile, u, v, clipped depth range).
        let mut active: Vec<(usize, f64, f64, [f64; 2])> = Vec::with_capacity(n);
        for k in 0..n {
            let (u, v) = cam.screen((x0 + k % w) as f64, (y0 + k / w) as f64);
            if let Some(r) = self.clip(u, v) {
                active.push((k, u, v, r));
            }
        }
        if active.is_empty() {
            return hits;
        }
        if self.direct.is_some() {
            // The field answers ray by ray; the shared interval search
            // would only repeat its work.
            for &(idx, u, v, range) in &active {
                hits[idx] = match self.direct_ray(u, v, range) {
                    Some(h) => h,
                    None => self.ray(u, v, range),
                };
            }
            return hits;
        }
        let t0 = active.iter().map(|r| r.3[0]).fold(f64::INFINITY, f64::min);
        let t1 = active
            .iter()
            .map(|r| r.3[1])
            .fold(f64::NEG_INFINITY, f64::max);
        let (ua, va) = cam.screen(x0 as f64, y0 as f64);
        let (ub, vb) = cam.screen((x0 + w - 1) as f64, (y0 + h - 1) as f64);
        // Depth parts shorter than the tile is wide gain little from the
        // shared test.
        let min_len = (w.max(h) as f64 * cam.scale).max(FINE_PIXELS * cam.scale);
        let mut stack = vec![[t0, t1]];
        while let Some([a, b]) = stack.pop() {
            let mut lo = [f64::INFINITY; 3];
            let mut hi = [f64::NEG_INFINITY; 3];
            for (u, v, t) in [
                (ua, va, a),
                (ub, va, a),
                (ua, vb, a),
                (ub, vb, a),
                (ua, va, b),
                (ub, va, b),
                (ua, vb, b),
                (ub, vb, b),
            ] {
                let p = cam.point(u, v, t);
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
            let r = self.iv.eval(
                Interval::new(lo[0], hi[0]),
                Interval::new(lo[1], hi[1]),
                Interval::new(lo[2], hi[2]),
            );
            if r.hi < 0.0 {
                continue;
            }
            if b - a > min_len {
                let m = 0.5 * (a + b);
                stack.push([m, b]);
                stack.push([a, m]);
                continue;
            }
            // Nothing in front of `a` for any ray of the tile: each ray is
            // searched on its own from there.
            for &(idx, u, v, range) in &active {
                let s0 = range[0].max(a);
                if s0 <= range[1] {
                    hits[idx] = self.ray(u, v, [s0, range[1]]);
                }
            }
            return hits;
        }
        hits
    }

    /// Depth of the first hit of the ray through pixel `(px, py)`.
    pub fn pixel(&mut self, px: usize, py: usize) -> Option<f64> {
        let (u, v) = self.cam.screen(px as f64, py as f64);
        let range = self.clip(u, v)?;
        match self.direct_ray(u, v, range) {
            Some(h) => h,
            None => self.ray(u, v, range),
        }
    }

    fn ray(&mut self, u: f64, v: f64, t: [f64; 2]) -> Option<f64> {
        let cam = self.cam;
        let step = STEP_PIXELS * cam.scale;
        let coarse = (BLOCK - 1) as f64 * step;
        let fine = FINE_PIXELS * cam.scale;
        if !self.bounds_help {
            return self.march(u, v, t, step, coarse);
        }
        let halvings = ((t[1] - t[0]) / fine).log2().ceil().max(0.0) as usize;
        let mut budget = 2 * halvings + 4;
        // Interval evaluations and how many of them decided their segment.
        let (mut evals, mut decided) = (0usize, 0usize);
        // Depth-first, nearest segment first.
        let mut stack = vec![t];
        while let Some([a, b]) = stack.pop() {
            budget = budget.saturating_sub(1);
            let (p, q) = (cam.point(u, v, a), cam.point(u, v, b));
            let bx = [0, 1, 2].map(|k| Interval::new(p[k].min(q[k]), p[k].max(q[k])));
            let r = self.iv.eval(bx[0], bx[1], bx[2]);
            evals += 1;
            decided += (r.hi < 0.0 || (r.lo >= 0.0 && !r.may_be_nan())) as usize;
            if r.hi < 0.0 {
                continue;
            }
            if r.lo >= 0.0 && !r.may_be_nan() {
                self.bounds_help = true;
                return Some(a);
            }
            let leaf = if budget > 0 { fine } else { coarse };
            if b - a > leaf {
                let m = 0.5 * (a + b);
                stack.push([m, b]);
                stack.push([a, m]);
                continue;
            }
            let hit = if b - a <= fine {
                self.sample_fine(u, v, a, b)
            } else {
                self.sample(u, v, a, b, step)
            };
            if hit.is_some() {
                // A hit reached by descending to a fine segment is the
                // bounds working (each halving on the way is needed, none
                // "decides"), whatever the ratio says.
                self.bounds_help = b - a <= fine || 4 * decided >= evals;
                return hit;
            }
        }
        self.bounds_help = 4 * decided >= evals;
        None
    }

    /// Samples the whole range front to back, `coarse` at a time.
    fn march(&mut self, u: f64, v: f64, t: [f64; 2], step: f64, coarse: f64) -> Option<f64> {
        let mut a = t[0];
        while a < t[1] {
            let b = (a + coarse).min(t[1]);
            if let Some(hit) = self.sample(u, v, a, b, step) {
                return Some(hit);
            }
            a = b;
        }
        None
    }

    /// Samples `[a, b]` at `step` (ends included) in one batch; bisects
    /// before the first sample with `f >= 0`.
    fn sample(&mut self, u: f64, v: f64, a: f64, b: f64, step: f64) -> Option<f64> {
        let n = (((b - a) / step).ceil() as usize + 1).min(BLOCK);
        let dt = if n > 1 { (b - a) / (n - 1) as f64 } else { 0.0 };
        {
            let (x, y, z) = self.batch.coords_mut();
            for k in 0..n {
                let p = self.cam.point(u, v, a + k as f64 * dt);
                x[k] = p[0] as f32;
                y[k] = p[1] as f32;
                z[k] = p[2] as f32;
            }
        }
        let first = self.batch.eval_loaded(n).iter().position(|&f| f >= 0.0)?;
        let t = a + first as f64 * dt;
        Some(if first == 0 {
            t
        } else {
            self.bisect(u, v, t - dt, t)
        })
    }

    /// Ends and middle of a short segment, in f64.
    fn sample_fine(&mut self, u: f64, v: f64, a: f64, b: f64) -> Option<f64> {
        let m = 0.5 * (a + b);
        let mut prev = a;
        for t in [a, m, b] {
            if self.value(self.cam.point(u, v, t)) >= 0.0 {
                return Some(if t == a {
                    a
                } else {
                    self.bisect(u, v, prev, t)
                });
            }
            prev = t;
        }
        None
    }

    fn value(&mut self, p: V3) -> f64 {
        self.pe.eval(p)
    }

    /// Narrows `[a, b]` (outside at `a`, inside at `b` by the samples) to
    /// the crossing in f64, until it is narrower than `2^-BISECT` of the
    /// start; returns the inside end. Regula falsi with the Illinois
    /// modification, which takes about seven evaluations on a smooth
    /// crossing (bisection took fifteen); after `2 BISECT` steps without
    /// getting there (a kinked or noisy function) it bisects, so it always
    /// ends.
    fn bisect(&mut self, u: f64, v: f64, mut a: f64, mut b: f64) -> f64 {
        let mut fb = self.value(self.cam.point(u, v, b));
        if fb < 0.0 || fb.is_nan() {
            // f32 and f64 disagree at a grazing hit: keep the sample.
            return b;
        }
        let mut fa = self.value(self.cam.point(u, v, a));
        if fa.is_nan() {
            fa = -1.0;
        }
        let tol = (b - a) * 0.5f64.powi(BISECT as i32);
        let mut side = 0i8;
        let mut steps = 0;
        while b - a > tol {
            steps += 1;
            // The f32 samples said outside at `a`; if f64 disagrees, there
            // is no sign change to interpolate: bisect.
            let secant = steps <= 2 * BISECT && fa < 0.0;
            let t = b - fb * (b - a) / (fb - fa);
            let m = if secant && t > a && t < b {
                t
            } else {
                0.5 * (a + b)
            };
            let fm = self.value(self.cam.point(u, v, m));
            if fm >= 0.0 {
                b = m;
                fb = fm;
                if side == 1 {
                    fa *= 0.5;
                }
                side = 1;
            } else {
                a = m;
                // NaN counts as outside; its value must not steer the steps.
                fa = if fm.is_nan() { -1.0 } else { fm };
                if side == -1 {
                    fb *= 0.5;
                }
                side = -1;
            }
        }
        b
    }
}
