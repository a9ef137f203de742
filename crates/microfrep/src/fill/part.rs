//! The part of a fill: its value, its box, and its depth below the surface
//! in millimetres.
//!
//! A mesh or a scan is a signed distance already; it is sampled once on a
//! grid around its surface (the exact distance through the mesh's hierarchy
//! is the costly part, and every consumer evaluates the part at every
//! sample). Any other function (a HyperFun model, a formula) is no
//! distance: `hfSphere` is `r^2 - |x|^2`, and its normalised form
//! `f / sqrt(f^2 + |grad f|^2)` never exceeds 1, so a skin measured in it is
//! not a skin in millimetres. Its depth is estimated by
//! [`depth_estimate`], two Newton steps along the gradient.

use super::{bad, FillError};
use crate::load::{self, LoadOptions, Progress, SourceKind};
use microfrep_core::{Bounds, Expr, ExprNode, Field, Shape};
use std::path::PathBuf;
use std::sync::Arc;

/// A part to fill.
#[derive(Clone)]
pub struct Part {
    /// The part (inside `>= 0`) with its attribute channels.
    pub shape: Shape,
    /// The box cells and outputs are laid on: the mesh's or scan's extent,
    /// `--bounds`, or what interval analysis proves.
    pub bounds: Bounds,
    /// Whether the value is a signed distance (meshes, scans).
    pub distance: bool,
    /// The source to bind when the model is saved as HyperFun
    /// (`--field part=SOURCE`), for a data-field part.
    pub source: Option<String>,
    /// Warnings from loading.
    pub notes: Vec<String>,
    /// Files read.
    pub inputs: Vec<PathBuf>,
}

/// The root data field of a shape sampled at the plain point, if any.
fn root_field(e: &Expr) -> Option<&Arc<dyn Field>> {
    match e.node() {
        ExprNode::Field {
            field,
            comp: 0,
            args,
        } => {
            let identity = args
                .iter()
                .enumerate()
                .all(|(i, a)| matches!(a.node(), ExprNode::Var(v) if *v as usize == i));
            identity.then_some(field)
        }
        _ => None,
    }
}

impl Part {
    /// Loads a part as [`load::load`] takes it (`FILE[:options]` or an
    /// example name); `bounds` replaces the part's own box.
    pub fn load(
        spec: &str,
        opts: &LoadOptions,
        bounds: Option<Bounds>,
        progress: Progress,
    ) -> Result<Part, FillError> {
        let l = load::load_with_progress(spec, opts, progress)?;
        if l.kind == SourceKind::Data {
            return Err(bad(
                "fill takes a mesh, a scan, a HyperFun model or an example as the part",
            ));
        }
        let source =
            matches!(l.kind, SourceKind::Mesh | SourceKind::Scan).then(|| spec.to_string());
        let mut part = Part::from_shape(l.shape, bounds)?;
        part.source = source.or(part.source);
        part.notes = l.notes;
        part.inputs = l.inputs;
        Ok(part)
    }

    /// A part from a shape built with the API (Python's `mf.load`, a
    /// formula); `bounds` replaces the shape's own box.
    pub fn from_shape(shape: Shape, bounds: Option<Bounds>) -> Result<Part, FillError> {
        let bounds = match bounds {
            Some(b) => b,
            None => shape.bounds().map_err(|e| {
                bad(format!(
                    "cannot find the part's box ({e}); give it with \u{27e8}bounds\u{27e9} \
                     (xmin, ymin, zmin, xmax, ymax, zmax)"
                ))
            })?,
        };
        if !bounds.is_valid() {
            return Err(bad(format!(
                "the part's box {:?} is empty",
                bounds.corners()
            )));
        }
        let field = root_field(shape.value());
        let distance = field.is_some_and(|f| f.is_signed_distance());
        let source = field.filter(|_| distance).map(|f| f.name().to_string());
        Ok(Part {
            shape: shape.with_bounds(bounds),
            bounds,
            distance,
            source,
            notes: Vec::new(),
            inputs: Vec::new(),
        })
    }

    /// The value and depth the fill evaluates: a distance part sampled on
    /// a grid (spacing from `cap`, clamped a few steps outside its surface
    /// and a few steps below the depth `needed`), any other part as it is
    /// with its depth estimated down to `cap`.
    pub(crate) fn prepare(
        &self,
        cap: f64,
        needed: f64,
        cell: f64,
        progress: Progress,
    ) -> Result<Prepared, FillError> {
        if self.distance {
            let h = cache_spacing(cell, cap, &self.bounds);
            // Inside, the depth must be right down to the cap; outside only
            // the sign matters (and a few steps of distance, for the
            // mesher's and the skin measure's samples near the surface).
            let band = needed.min(cap) + 2.0 * h;
            let band_out = 2.0 * h;
            let cached = cache_field(
                self.shape.value(),
                &self.bounds,
                h,
                band,
                band_out,
                progress,
            )?;
            let value = Expr::field(cached.clone());
            return Ok(Prepared {
                value: value.clone(),
                depth: value,
                form: PartForm::Field {
                    field: cached,
                    source: self.source.clone().unwrap_or_else(|| "part".into()),
                },
                bounds: self.bounds,
            });
        }
        let value = self.shape.value().clone();
        Ok(Prepared {
            depth: depth_estimate(&value, cap),
            value,
            form: PartForm::Graph,
            bounds: self.bounds,
        })
    }
}

/// How the part is written in HyperFun.
#[derive(Clone)]
pub(crate) enum PartForm {
    /// As its own graph.
    Graph,
    /// As the function `part(x)` bound to `source`.
    Field {
        field: Arc<dyn Field>,
        source: String,
    },
}

impl PartForm {
    pub(crate) fn field(&self) -> Option<(Arc<dyn Field>, String)> {
        match self {
            PartForm::Graph => None,
            PartForm::Field { field, .. } => Some((field.clone(), "part".into())),
        }
    }

    pub(crate) fn binding(&self) -> Option<&str> {
        match self {
            PartForm::Graph => None,
            PartForm::Field { source, .. } => Some(source),
        }
    }
}

/// The part as the fill evaluates it.
pub(crate) struct Prepared {
    pub(crate) value: Expr,
    pub(crate) depth: Expr,
    pub(crate) form: PartForm,
    pub(crate) bounds: Bounds,
}

impl Prepared {
    /// The centre of the box.
    pub(crate) fn sample_point(&self) -> [f64; 3] {
        std::array::from_fn(|a| 0.5 * (self.bounds.min[a] + self.bounds.max[a]))
    }

    /// Up to `n` points inside the part, on a fixed low-discrepancy
    /// sequence over its box (the same points every run).
    pub(crate) fn inside_points(&self, n: usize) -> Vec<[f64; 3]> {
        let mut ev = Shape::new(self.value.clone()).point();
        let b = self.bounds;
        let mut out = Vec::with_capacity(n);
        for k in 0..64 * n {
            let u = halton3(k as u64 + 1);
            let p: [f64; 3] = std::array::from_fn(|a| b.min[a] + u[a] * (b.max[a] - b.min[a]));
            if ev.eval(p) >= 0.0 {
                out.push(p);
                if out.len() == n {
                    break;
                }
            }
        }
        out
    }
}

/// The Halton point `k` in bases 2, 3, 5.
pub(crate) fn halton3(k: u64) -> [f64; 3] {
    let h = |mut i: u64, base: u64| {
        let (mut f, mut r) = (1.0, 0.0);
        while i > 0 {
            f /= base as f64;
            r += f * (i % base) as f64;
            i /= base;
        }
        r
    };
    [h(k, 2), h(k, 3), h(k, 5)]
}

/// The depth below the zero set of `f` (inside `f >= 0`), in model units,
/// for a function that is not a distance: the first-order distance
/// `d1 = f / |grad f|`, then one more Newton step from the point moved by
/// `d1` along the unit gradient, `d = d1 + f(q) / |grad f(q)|`. Exact for
/// planes and for the box's `min` of slabs, within 1e-4 of the distance for
/// `r^2 - |x|^2` at a tenth of the radius. Where `|d1| >= cap` the value is
/// `cap` with the sign of `f` (deep inside or far outside); where the
/// gradient vanishes the point counts as deep.
pub fn depth_estimate(f: &Expr, cap: f64) -> Expr {
    let tiny = 1e-30;
    let g = f.gradient();
    let norm = |g: &[Expr; 3]| {
        (g[0].square() + g[1].square() + g[2].square())
            .sqrt()
            .max(tiny)
    };
    let n0 = norm(&g);
    let d1 = (f / &n0).max(-cap).min(cap);
    let x = Expr::xyz();
    let q: [Expr; 3] = std::array::from_fn(|i| &x[i] - &d1 * (&g[i] / &n0));
    let fq = f.remap(&q);
    let gq: [Expr; 3] = std::array::from_fn(|i| g[i].remap(&q));
    let d2 = (&d1 + fq / norm(&gq)).max(-cap).min(cap);
    // Deep points keep the capped first estimate (the step from there is
    // meaningless).
    let deep = d1.abs().ge(cap * 0.999);
    Expr::select(deep, d1, d2)
}

/// Most samples of the cached part (256 MiB of f64).
const CACHE_SAMPLES: usize = 1 << 25;

/// Grid step of the cached part: an eighth of a cell and a third of the
/// depth that matters (the skin), no finer than the sample budget allows.
fn cache_spacing(cell: f64, cap: f64, b: &Bounds) -> f64 {
    let vol: f64 = b.size().iter().map(|s| s.max(1e-9)).product();
    let budget = (vol / CACHE_SAMPLES as f64).cbrt();
    (cell / 8.0).min(cap / 6.0).max(budget)
}

/// The part's field sampled on a grid of step `h` over its box (padded by
/// two steps), clamped to `[-band_out, band]`; bricks whose interval keeps
/// `f >= band` or `f <= -band_out` are filled without sampling.
fn cache_field(
    f: &Expr,
    b: &Bounds,
    h: f64,
    band: f64,
    band_out: f64,
    progress: Progress,
) -> Result<Arc<dyn Field>, FillError> {
    use microfrep_core::{BatchEval, GridField, Interval, IntervalEval, Tape};
    use rayon::prelude::*;
    let lo: [f64; 3] = std::array::from_fn(|a| b.min[a] - 2.0 * h);
    let dims: [usize; 3] =
        std::array::from_fn(|a| ((b.max[a] + 2.0 * h - lo[a]) / h).ceil() as usize + 1);
    let hi: [f64; 3] = std::array::from_fn(|a| lo[a] + (dims[a] - 1) as f64 * h);
    let tape = Tape::new(f);
    const BR: usize = 8;
    const SUB: usize = BR / 2;
    let nb: [usize; 3] = std::array::from_fn(|a| dims[a].div_ceil(BR));
    let total = nb[0] * nb[1] * nb[2];
    let done = std::sync::atomic::AtomicU64::new(0);
    // The clamped value of the nodes `i0 + r[0] .. i0 + r[1]` where their
    // interval decides it.
    let decided = |ie: &mut IntervalEval, i0: [usize; 3], r: [[usize; 3]; 2]| -> Option<f64> {
        let iv = |a: usize| {
            Interval::new(
                lo[a] + (i0[a] + r[0][a]) as f64 * h,
                lo[a] + (i0[a] + r[1][a] - 1) as f64 * h,
            )
        };
        let v = ie.eval(iv(0), iv(1), iv(2));
        if !v.may_be_nan() && v.lo >= band {
            Some(band)
        } else if v.hi <= -band_out {
            Some(-band_out)
        } else {
            None
        }
    };
    let bricks: Vec<(usize, Vec<f64>)> = (0..total)
        .into_par_iter()
        .map_init(
            || (IntervalEval::new(&tape), BatchEval::new(&tape)),
            |(ie, be), k| {
                let bi = [k % nb[0], (k / nb[0]) % nb[1], k / (nb[0] * nb[1])];
                let i0: [usize; 3] = std::array::from_fn(|a| bi[a] * BR);
                let n: [usize; 3] = std::array::from_fn(|a| BR.min(dims[a] - i0[a]));
                let count = n[0] * n[1] * n[2];
                let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                if d % 64 == 0 {
                    progress("sampling the part", d, total as u64);
                }
                // The brick, then its octants (a brick is wider than the
                // band, so most of a surface brick lies beyond it).
                let whole = [[0usize; 3], n];
                if let Some(v) = decided(&mut *ie, i0, whole) {
                    return (k, vec![v; count]);
                }
                let mut vals = vec![f64::NAN; count];
                let mut x = Vec::with_capacity(count);
                let mut y = Vec::with_capacity(count);
                let mut z = Vec::with_capacity(count);
                let mut at = Vec::with_capacity(count);
                let parts: Vec<[[usize; 3]; 2]> = (0..8)
                    .filter_map(|o: usize| {
                        let s0: [usize; 3] =
                            std::array::from_fn(|a| if o >> a & 1 == 1 { SUB } else { 0 });
                        let s1: [usize; 3] =
                            std::array::from_fn(
                                |a| if o >> a & 1 == 1 { n[a] } else { SUB.min(n[a]) },
                            );
                        (0..3).all(|a| s0[a] < s1[a]).then_some([s0, s1])
                    })
                    .collect();
                for [s0, s1] in parts {
                    let fixed = decided(&mut *ie, i0, [s0, s1]);
                    for c in s0[2]..s1[2] {
                        for bj in s0[1]..s1[1] {
                            for ai in s0[0]..s1[0] {
                                let q = ai + n[0] * (bj + n[1] * c);
                                match fixed {
                                    Some(v) => vals[q] = v,
                                    None => {
                                        x.push((lo[0] + (i0[0] + ai) as f64 * h) as f32);
                                        y.push((lo[1] + (i0[1] + bj) as f64 * h) as f32);
                                        z.push((lo[2] + (i0[2] + c) as f64 * h) as f32);
                                        at.push(q);
                                    }
                                }
                            }
                        }
                    }
                }
                if !at.is_empty() {
                    let mut out = vec![0.0f32; at.len()];
                    be.eval(&x, &y, &z, &mut out);
                    for (&q, v) in at.iter().zip(out) {
                        vals[q] = if v.is_nan() {
                            -band_out
                        } else {
                            (v as f64).clamp(-band_out, band)
                        };
                    }
                }
                (k, vals)
            },
        )
        .collect();
    let mut values = vec![0.0f64; dims[0] * dims[1] * dims[2]];
    for (k, vals) in bricks {
        let bi = [k % nb[0], (k / nb[0]) % nb[1], k / (nb[0] * nb[1])];
        let i0: [usize; 3] = std::array::from_fn(|a| bi[a] * BR);
        let n: [usize; 3] = std::array::from_fn(|a| BR.min(dims[a] - i0[a]));
        let mut q = 0;
        for c in 0..n[2] {
            for bj in 0..n[1] {
                let row = dims[0] * ((i0[1] + bj) + dims[1] * (i0[2] + c));
                for ai in 0..n[0] {
                    values[i0[0] + ai + row] = vals[q];
                    q += 1;
                }
            }
        }
    }
    let g = GridField::new("part", dims, lo, hi, values)
        .map_err(|e| FillError::Build(format!("sampling the part: {e}")))?
        .as_distance();
    Ok(Arc::new(g))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn depth_estimate_is_a_distance_for_a_quadratic_ball() {
        // hfSphere's r^2 - |x|^2 with r = 10: depth 10 - |x|.
        let x = Expr::xyz();
        let f = 100.0 - (x[0].square() + x[1].square() + x[2].square());
        let d = depth_estimate(&f, 5.0);
        let mut ev = Shape::new(d).point();
        for rho in [10.5, 10.0, 9.9, 9.5, 9.0, 8.0, 7.0] {
            let p = [rho * 0.6, rho * 0.0, rho * 0.8];
            let got = ev.eval(p);
            let want = (10.0 - rho).clamp(-5.0, 5.0);
            // Two Newton steps: near exact in the skin, within 1 % deeper.
            let tol = if want.abs() <= 1.5 {
                2e-3
            } else {
                0.01 * want.abs()
            };
            assert!((got - want).abs() < tol, "{rho}: {got} vs {want}");
        }
        // Deep inside (the gradient vanishes at the centre): capped.
        assert_eq!(ev.eval([0.0, 0.0, 0.0]), 5.0);
        assert_eq!(ev.eval([0.5, 0.0, 0.0]), 5.0);
    }

    #[test]
    fn depth_estimate_is_exact_in_a_box() {
        let x = Expr::xyz();
        let f = (1.0 - x[0].abs())
            .min(2.0 - x[1].abs())
            .min(3.0 - x[2].abs())
            * 7.0;
        let mut ev = Shape::new(depth_estimate(&f, 10.0)).point();
        for p in [
            [0.5f64, 0.0, 0.0],
            [0.9, 1.9, 0.0],
            [-0.2, 1.5, 2.7],
            [1.5, 0.0, 0.0],
        ] {
            let want = (1.0 - p[0].abs())
                .min(2.0 - p[1].abs())
                .min(3.0 - p[2].abs());
            assert!((ev.eval(p) - want).abs() < 1e-9, "{p:?}");
        }
    }
}
