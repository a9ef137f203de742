//! Radial functions on the sphere of directions, tabulated on a cube map.
//!
//! A star-shaped body around the origin is `{y : |y| < R(y / |y|)}`. `R` is
//! sampled at the grid vertices of the six faces of a cube map (directions
//! `(u, v, 1)` permuted, `u, v` in `[-1, 1]`) and interpolated bilinearly
//! in `(u, v)`. Vertices on the edges and corners of the cube are shared by
//! the faces that meet there (one value, copied), and along a cube edge the
//! interpolation uses only that edge's values, so `R` is continuous on the
//! whole sphere. The interpolant stays within the range of each texel's
//! four corners, which gives sound bounds.

use crate::doo_sabin::other_axes;

/// Face `f` of the cube map: axis `f / 2`, positive side for even `f`.
pub fn face_axis(f: usize) -> (usize, f64) {
    (f / 2, if f.is_multiple_of(2) { 1.0 } else { -1.0 })
}

/// The face a direction belongs to and its face coordinates `(u, v)`
/// (the largest component decides; ties go to the lower axis).
#[inline]
pub fn locate(y: [f64; 3]) -> (usize, f64, f64) {
    let a = [y[0].abs(), y[1].abs(), y[2].abs()];
    let m = if a[0] >= a[1] && a[0] >= a[2] {
        0
    } else if a[1] >= a[2] {
        1
    } else {
        2
    };
    let (b, c) = other_axes(m);
    let f = 2 * m + (y[m] < 0.0) as usize;
    let inv = 1.0 / a[m];
    (f, y[b] * inv, y[c] * inv)
}

/// The (unnormalised) direction of face coordinates `(u, v)` on face `f`.
pub fn direction(f: usize, u: f64, v: f64) -> [f64; 3] {
    let (m, s) = face_axis(f);
    let (b, c) = other_axes(m);
    let mut d = [0.0; 3];
    d[m] = s;
    d[b] = u;
    d[c] = v;
    d
}

/// Value and face-coordinate derivatives of a tabulated radial function.
#[derive(Clone, Copy, Debug)]
pub struct Sample {
    /// Face of the direction.
    pub face: usize,
    /// Face coordinates.
    pub u: f64,
    /// Face coordinates.
    pub v: f64,
    /// Interpolated radius.
    pub r: f64,
    /// `dR/du`.
    pub ru: f64,
    /// `dR/dv`.
    pub rv: f64,
}

/// A radial function tabulated on `(n + 1)^2` vertices per face.
#[derive(Clone, Debug)]
pub struct CubeMap {
    n: usize,
    values: Vec<f32>,
}

impl CubeMap {
    /// A table of `n` texels per face side, every value `r`.
    pub fn constant(n: usize, r: f32) -> CubeMap {
        CubeMap {
            n,
            values: vec![r; 6 * (n + 1) * (n + 1)],
        }
    }

    /// Texels per face side.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Index of vertex `(i, j)` of face `f`.
    #[inline]
    pub fn index(&self, f: usize, i: usize, j: usize) -> usize {
        (f * (self.n + 1) + j) * (self.n + 1) + i
    }

    /// Face coordinate of grid line `i`.
    pub fn coord(&self, i: usize) -> f64 {
        -1.0 + 2.0 * i as f64 / self.n as f64
    }

    /// All values, face by face, `i` fastest.
    pub fn values(&self) -> &[f32] {
        &self.values
    }

    /// Mutable values (the caller keeps shared vertices equal; see
    /// [`CubeMap::share_edges`]).
    pub fn values_mut(&mut self) -> &mut [f32] {
        &mut self.values
    }

    /// Lattice point on the cube surface `[0, n]^3` of vertex `(i, j)` of
    /// face `f`.
    fn lattice(&self, f: usize, i: usize, j: usize) -> [usize; 3] {
        let (m, s) = face_axis(f);
        let (b, c) = other_axes(m);
        let mut l = [0; 3];
        l[m] = if s > 0.0 { self.n } else { 0 };
        l[b] = i;
        l[c] = j;
        l
    }

    /// The first face (in index order) holding lattice point `l`, and the
    /// vertex there.
    fn owner(&self, l: [usize; 3]) -> (usize, usize, usize) {
        for f in 0..6 {
            let (m, s) = face_axis(f);
            let on = if s > 0.0 { l[m] == self.n } else { l[m] == 0 };
            if on {
                let (b, c) = other_axes(m);
                return (f, l[b], l[c]);
            }
        }
        unreachable!("lattice point {l:?} is not on the cube surface")
    }

    /// Makes every vertex on a cube edge or corner take the value of its
    /// first face, so the faces agree exactly where they meet.
    pub fn share_edges(&mut self) {
        let n = self.n;
        for f in 0..6 {
            for j in 0..=n {
                for i in 0..=n {
                    if i != 0 && i != n && j != 0 && j != n {
                        continue;
                    }
                    let (g, gi, gj) = self.owner(self.lattice(f, i, j));
                    if g != f {
                        let v = self.values[self.index(g, gi, gj)];
                        let k = self.index(f, i, j);
                        self.values[k] = v;
                    }
                }
            }
        }
    }

    /// A borrowed view of the table.
    #[inline]
    pub fn view(&self) -> View<'_> {
        View {
            n: self.n,
            values: &self.values,
        }
    }

    /// Radius and its derivatives in the direction of `y` (not zero).
    #[inline]
    pub fn sample(&self, y: [f64; 3]) -> Sample {
        self.view().sample(y)
    }

    /// Bounds of the table: smallest value, largest value, and the largest
    /// `|dR/du|` and `|dR/dv|` anywhere.
    pub fn stats(&self) -> (f64, f64, f64, f64) {
        let n = self.n;
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        let (mut su, mut sv) = (0.0f64, 0.0f64);
        let h = 0.5 * n as f64;
        for f in 0..6 {
            for j in 0..=n {
                for i in 0..=n {
                    let v = self.values[self.index(f, i, j)] as f64;
                    lo = lo.min(v);
                    hi = hi.max(v);
                    if i < n {
                        let d = self.values[self.index(f, i + 1, j)] as f64 - v;
                        su = su.max(d.abs() * h);
                    }
                    if j < n {
                        let d = self.values[self.index(f, i, j + 1)] as f64 - v;
                        sv = sv.max(d.abs() * h);
                    }
                }
            }
        }
        (lo, hi, su, sv)
    }
}

/// A borrowed table: `n` texels per side, `6 (n + 1)^2` values.
#[derive(Clone, Copy, Debug)]
pub struct View<'a> {
    /// Texels per face side.
    pub n: usize,
    /// Values, as in [`CubeMap::values`].
    pub values: &'a [f32],
}

impl View<'_> {
    /// Texel and local coordinate of a face coordinate.
    #[inline]
    fn cell(&self, u: f64) -> (usize, f64) {
        let t = (u + 1.0) * (0.5 * self.n as f64);
        let i = (t as i64).clamp(0, self.n as i64 - 1) as usize;
        (i, t - i as f64)
    }

    /// Radius and its derivatives in the direction of `y` (not zero).
    #[inline]
    pub fn sample(&self, y: [f64; 3]) -> Sample {
        let (face, u, v) = locate(y);
        self.sample_face(face, u, v)
    }

    /// Radius and derivatives at face coordinates.
    #[inline]
    pub fn sample_face(&self, face: usize, u: f64, v: f64) -> Sample {
        let (i, tu) = self.cell(u);
        let (j, tv) = self.cell(v);
        let w = self.n + 1;
        let k = (face * w + j) * w + i;
        let r00 = self.values[k] as f64;
        let r10 = self.values[k + 1] as f64;
        let r01 = self.values[k + w] as f64;
        let r11 = self.values[k + w + 1] as f64;
        let a = r00 + (r10 - r00) * tu;
        let b = r01 + (r11 - r01) * tu;
        let r = a + (b - a) * tv;
        let h = 0.5 * self.n as f64;
        let ru = ((r10 - r00) * (1.0 - tv) + (r11 - r01) * tv) * h;
        let rv = (b - a) * h;
        Sample {
            face,
            u,
            v,
            r,
            ru,
            rv,
        }
    }

    /// Gauge and gradient (see [`gauge`]).
    #[inline]
    pub fn gauge(&self, y: [f64; 3]) -> (f64, [f64; 3]) {
        let len = (y[0] * y[0] + y[1] * y[1] + y[2] * y[2]).sqrt();
        if len == 0.0 {
            return (0.0, [0.0; 3]);
        }
        let s = self.sample(y);
        let g = len / s.r;
        let (m, sign) = face_axis(s.face);
        let (b, c) = other_axes(m);
        let am = y[m].abs();
        // grad u = (e_b - u sign e_m) / |y_m|, likewise v with e_c.
        let k = len / (s.r * s.r * am);
        let mut grad = [y[0] / (len * s.r), y[1] / (len * s.r), y[2] / (len * s.r)];
        grad[b] -= k * s.ru;
        grad[c] -= k * s.rv;
        grad[m] += k * sign * (s.ru * s.u + s.rv * s.v);
        (g, grad)
    }
}

/// Gauge `g(y) = |y| / R(y / |y|)` of a star body (`g < 1` inside) and its
/// gradient; `g(0) = 0` with gradient 0 there.
#[inline]
pub fn gauge(map: &CubeMap, y: [f64; 3]) -> (f64, [f64; 3]) {
    map.view().gauge(y)
}

impl CubeMap {
    /// A bound on `|grad g|` of the gauge `g(y) = |y| / R(y / |y|)`, per
    /// texel and then the largest: with `s = |y| / |y_m|`,
    /// `|grad g|^2 = 1 / R^2 + s^2 (R_u^2 + R_v^2 + (u R_u + v R_v)^2) / R^4`
    /// (the second part is orthogonal to `y`), each factor bounded over the
    /// texel by its corners (bilinear `R` stays within them, `R_u` within
    /// its two u-edge differences).
    pub fn gauge_lipschitz(&self) -> f64 {
        let n = self.n;
        let h = 0.5 * n as f64;
        let mut worst = 0.0f64;
        for f in 0..6 {
            for j in 0..n {
                for i in 0..n {
                    let v = |a: usize, b: usize| self.values[self.index(f, i + a, j + b)] as f64;
                    let (r00, r10, r01, r11) = (v(0, 0), v(1, 0), v(0, 1), v(1, 1));
                    let rlo = r00.min(r10).min(r01).min(r11);
                    let ru = (r10 - r00).abs().max((r11 - r01).abs()) * h;
                    let rv = (r01 - r00).abs().max((r11 - r10).abs()) * h;
                    let umax = self.coord(i).abs().max(self.coord(i + 1).abs());
                    let vmax = self.coord(j).abs().max(self.coord(j + 1).abs());
                    let s2 = 1.0 + umax * umax + vmax * vmax;
                    let cross = ru * umax + rv * vmax;
                    let g2 =
                        1.0 / (rlo * rlo) + s2 * (ru * ru + rv * rv + cross * cross) / rlo.powi(4);
                    worst = worst.max(g2);
                }
            }
        }
        worst.sqrt() * (1.0 + 1e-9)
    }
}

/// A bound on `|grad g|` for a table with the given [`CubeMap::stats`].
pub fn gauge_lipschitz(rmin: f64, su: f64, sv: f64) -> f64 {
    // |y| |grad u| = (|y| / |y_m|) sqrt(1 + u^2) <= sqrt(3) sqrt(2).
    (1.0 / rmin + 6f64.sqrt() * (su + sv) / (rmin * rmin)) * (1.0 + 1e-9)
}

/// One point of the quadrature over the sphere of directions: the four
/// table entries it interpolates, their bilinear weights, the distance
/// `rho` from the centre of the cube `[-1, 1]^3` to its surface in this
/// direction, and the solid-angle weight.
#[derive(Clone, Copy, Debug)]
pub struct QuadPoint {
    /// Table indices of the texel corners.
    pub idx: [u32; 4],
    /// Bilinear weights of the corners.
    pub w: [f64; 4],
    /// Distance to the unit cube's surface.
    pub rho: f64,
    /// Solid angle represented.
    pub weight: f64,
}

/// Gauss-Legendre nodes and weights on [0, 1] for `order` 1 to 4.
fn gauss(order: usize) -> Vec<(f64, f64)> {
    let (x, w): (&[f64], &[f64]) = match order {
        1 => (&[0.0], &[2.0]),
        2 => (
            &[-0.577_350_269_189_625_8, 0.577_350_269_189_625_8],
            &[1.0, 1.0],
        ),
        3 => (
            &[-0.774_596_669_241_483_4, 0.0, 0.774_596_669_241_483_4],
            &[5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0],
        ),
        _ => (
            &[
                -0.861_136_311_594_052_6,
                -0.339_981_043_584_856_3,
                0.339_981_043_584_856_3,
                0.861_136_311_594_052_6,
            ],
            &[
                0.347_854_845_137_453_9,
                0.652_145_154_862_546_1,
                0.652_145_154_862_546_1,
                0.347_854_845_137_453_9,
            ],
        ),
    };
    x.iter()
        .zip(w)
        .map(|(x, w)| (0.5 * (x + 1.0), 0.5 * w))
        .collect()
}

/// Quadrature points of the whole sphere for tables of `n` texels per
/// side: `order x order` Gauss points per texel (each texel split into
/// `split x split` parts), weighted by the solid angle
/// `du dv / (1 + u^2 + v^2)^(3/2)`.
pub fn quadrature(n: usize, order: usize, split: usize) -> Vec<QuadPoint> {
    let map = CubeMap::constant(n, 0.0);
    let h = 2.0 / n as f64;
    let g = gauss(order);
    let mut nodes = Vec::new();
    for p in 0..split {
        for &(t, w) in &g {
            nodes.push(((p as f64 + t) / split as f64, w / split as f64));
        }
    }
    let mut out = Vec::with_capacity(6 * n * n * nodes.len() * nodes.len());
    for f in 0..6 {
        for j in 0..n {
            for i in 0..n {
                let k = map.index(f, i, j) as u32;
                let w1 = (n + 1) as u32;
                for &(tu, wu) in &nodes {
                    for &(tv, wv) in &nodes {
                        let u = map.coord(i) + tu * h;
                        let v = map.coord(j) + tv * h;
                        let q = 1.0 + u * u + v * v;
                        out.push(QuadPoint {
                            idx: [k, k + 1, k + w1, k + w1 + 1],
                            w: [
                                (1.0 - tu) * (1.0 - tv),
                                tu * (1.0 - tv),
                                (1.0 - tu) * tv,
                                tu * tv,
                            ],
                            rho: q.sqrt(),
                            weight: wu * wv * h * h / (q * q.sqrt()),
                        });
                    }
                }
            }
        }
    }
    out
}
