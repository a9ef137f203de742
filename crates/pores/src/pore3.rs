//! 3D pores (Kou and Tan, Sec. 4.2): the derived polyhedron of a cell
//! (Eq. 9), the smooth closed surface it controls, and the pore size solved
//! for a porosity of the cell.
//!
//! **Construction.** The pore is the Doo-Sabin limit surface of the derived
//! polyhedron. Doo-Sabin is the quadratic subdivision scheme (biquadratic
//! B-splines on regular regions), so it is the surface analogue of the 2D
//! pores' closed quadratic B-spline (Chaikin's curve), and the paper cites
//! it for this step; Catmull-Clark would be the cubic analogue. The surface
//! lies in the convex hull of its control polyhedron, touches the centre of
//! every face of a cubic one, and is linear in the control points.
//!
//! **Evaluation.** The topology is always the cube's, so the subdivided
//! mesh after [`LEVEL`] steps is computed once, symbolically: each face
//! centroid (a point exactly on the limit surface) as a fixed combination of
//! the eight control points. A pore's surface is then a matrix product, and
//! its radial function around the cell centre is tabulated on a cube map of
//! [`TEXELS`]^2 texels per face (each direction walks the mesh from the
//! regular pore's triangle to its own). The pore's FRep is
//! `q = m (1 - g / lambda)`, `g(y) = |y| / R(y / |y|)` the gauge of the
//! tabulated body in cell coordinates, `R` bilinear in the cube-map
//! coordinates: continuous, Lipschitz with a constant bounded per texel,
//! and about a distance near the surface. The zero set is the limit
//! surface to within 0.4 % (regular pore) to 0.7 % (irregularity 0.3) of
//! the radius at worst and 0.15 % on average, slightly inside (chords of
//! a convex surface): measured against the exact limit points after 7
//! steps by `tests/geometry.rs`.
//!
//! **Volume.** The porosity of a cell is `(1/3) int min(lambda R, rho)^3`
//! over the sphere of directions (`rho` the distance to the cell's
//! surface), by 2 x 2 Gauss points per texel of the same interpolated `R`,
//! so it is the volume of the FRep's pore itself, clipped to its cell, to
//! about 2e-4.
//!
//! **Range.** The regular pore (a cubic derived polyhedron) touches the
//! cell's faces at porosity 0.6274 (the exact limit surface: 0.6291; the
//! paper's sphere: pi/6 = 0.5236) and its edges at 0.9898, at
//! `lambda = 1.3329` (the surface passes through `(3/4, 3/4, 0)` of its
//! control cube, as the 2D curve does; the paper's sphere: 0.965). Between
//! the two every pore opens into its six neighbours and the solid stays one
//! piece; below the first the Doo-Sabin pores are closed.
//!
//! **Why the parent scale cannot open them lower, and what does.** Eq. 9
//! with all `t` equal puts every new vertex at `kappa (1 - t / 2)` on every
//! axis: the derived polyhedron of a regular pore is always a cube, so its
//! Doo-Sabin surface is always the same rounded cube, only scaled, and it
//! reaches the face centres at 0.6274 whatever `kappa` (the parent scale
//! only fixes which `t` gives which scale). The paper's 52.36 % is the
//! inscribed sphere's, a rounder body. So a pore whose target is too low
//! for the Doo-Sabin surface to reach `1 + opening` past the face centres
//! keeps that reach and gives up volume elsewhere: its radial table is
//! [`blend`]ed from the Doo-Sabin surface towards the sphere through the
//! face centres (`rho = 1`) and on towards a star pulled in at the corners
//! and edges (up to [`MAX_ROUNDNESS`]). With the default opening 0.05 every
//! pore opens into its six neighbours from 0.4559 ([`open_from`]) to
//! 0.9898, which covers the paper's 52.36 % to 96.5 %;
//! `tests/pores_interconnection.rs` measures porosity, percolation and
//! closed pores on a voxel grid from 0.47 to 0.97.
//!
//! **Weights.** The Doo-Sabin surface is the uniform biquadratic B-spline
//! surface of the derived polyhedron away from its eight corners (weight 1
//! everywhere, the analogue of the 2D curve at weight 1); it has no
//! rational form here, so 3D pores take only weight 1.
//!
//! Work is done in cell coordinates `y = (x - centre) / half`, where the
//! cell is `[-1, 1]^3`; Doo-Sabin subdivision commutes with affine maps,
//! so the pore of a stretched (T-mesh) cell is the stretched pore.
//!
//! The parent polyhedron is the cell scaled by `kappa` about its centre.
//! Each of its vertices `A` has three derived points `A_k = A + t_k (B_k - A)`
//! on its three edges, and the new vertex `A' = (A + A1 + A2 + A3) / 4`
//! (Eq. 9) lies at `kappa (1 - t_k / 2)` on axis `k`. Pores are drawn as a
//! random shape `b` (vertex `s` at `s * b_s`, `b = 1 + sigma * u` with `u`
//! uniform in [-1, 1], balanced per face, [`face_balanced`]) scaled by
//! `lambda` about the centre, so `t = 2 (1 - lambda b / kappa)`; the
//! Doo-Sabin surface of the scaled polyhedron is the scaled surface, so one
//! table of the shape serves every `lambda`, and `lambda` is solved from
//! the clipped volume.

use crate::cubemap::{gauge, quadrature, CubeMap, QuadPoint};
use crate::doo_sabin::{corner_sign, limit_mesh, LimitMesh};
use crate::raster::{tabulate, Walker};
use std::sync::{Arc, OnceLock};

/// Doo-Sabin steps before the limit mesh is tabulated.
pub const LEVEL: usize = 4;
/// Texels per cube-map face side.
pub const TEXELS: usize = 16;
/// Gauss points per texel side for the pore volume.
pub const QUAD_ORDER: usize = 2;
/// Default ratio of the parent polyhedron to the cell.
pub const KAPPA: f64 = 1.6;
/// Samples along each cell edge for the test that a pore stays off the
/// edges.
const EDGE_SAMPLES: usize = 33;

/// Tables and constants shared by every 3D pore.
pub(crate) struct Shared {
    pub mesh: LimitMesh,
    pub tris: Vec<[u32; 3]>,
    pub walker: Walker,
    pub quad: Vec<QuadPoint>,
    /// Points on the twelve edges of `[-1, 1]^3`.
    pub edges: Vec<[f64; 3]>,
    /// The regular pore (the Doo-Sabin surface of the cube itself).
    pub regular: Arc<CubeMap>,
    /// Porosity of the regular pore touching the cell's faces.
    pub p_face: f64,
    /// Its scale when it touches the cell's edges, and that porosity.
    pub lambda_edge: f64,
    pub p_edge: f64,
}

pub(crate) fn shared() -> &'static Shared {
    static S: OnceLock<Shared> = OnceLock::new();
    S.get_or_init(|| {
        let mesh = limit_mesh(LEVEL);
        let tris: Vec<[u32; 3]> = mesh
            .quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        let quad = quadrature(TEXELS, QUAD_ORDER, 1);
        let mut edges = Vec::new();
        for axis in 0..3 {
            for corner in 0..4usize {
                let (b, c) = crate::doo_sabin::other_axes(axis);
                for k in 0..EDGE_SAMPLES {
                    let mut p = [0.0; 3];
                    p[axis] = -1.0 + 2.0 * k as f64 / (EDGE_SAMPLES - 1) as f64;
                    p[b] = if corner & 1 == 1 { 1.0 } else { -1.0 };
                    p[c] = if corner & 2 == 2 { 1.0 } else { -1.0 };
                    edges.push(p);
                }
            }
        }
        let ctrl = control(&[[1.0; 3]; 8]);
        let reference = mesh.positions(&ctrl);
        let (regular, _) = tabulate(&reference, &tris, TEXELS)
            .expect("the cube's own Doo-Sabin surface surrounds its centre");
        let walker = Walker::new(&reference, &tris, TEXELS);
        let mut s = Shared {
            mesh,
            walker,
            tris,
            quad,
            edges,
            regular: Arc::new(regular),
            p_face: 0.0,
            lambda_edge: 0.0,
            p_edge: 0.0,
        };
        let rq = s.radii(&s.regular);
        s.p_face = fraction(&s.quad, &rq, 1.0);
        s.lambda_edge = 1.0 / edge_reach(&s, &s.regular);
        s.p_edge = fraction(&s.quad, &rq, s.lambda_edge);
        s
    })
}

impl Shared {
    /// The table's radius at every quadrature point.
    pub fn radii(&self, map: &CubeMap) -> Vec<f64> {
        let v = map.values();
        self.quad
            .iter()
            .map(|q| (0..4).map(|k| q.w[k] * v[q.idx[k] as usize] as f64).sum())
            .collect()
    }
}

/// Control points `s * b_s` of a shape in cell coordinates.
pub fn control(b: &[[f64; 3]; 8]) -> [[f64; 3]; 8] {
    std::array::from_fn(|s| std::array::from_fn(|a| corner_sign(s, a) * b[s][a]))
}

/// Eq. 9: the derived polyhedron of the parent box `centre +- kappa half`,
/// from the parameters `t[s][k]` of the derived point of parent vertex `s`
/// on its edge along axis `k` (vertex `s` has bit `k` set when it is on the
/// upper side of axis `k`). Each new vertex is the centroid of the parent
/// vertex and its three derived points.
pub fn derived_polyhedron(
    center: [f64; 3],
    half: [f64; 3],
    kappa: f64,
    t: &[[f64; 3]; 8],
) -> [[f64; 3]; 8] {
    std::array::from_fn(|s| {
        let a: [f64; 3] = std::array::from_fn(|k| center[k] + corner_sign(s, k) * kappa * half[k]);
        let mut sum = a;
        for k in 0..3 {
            // The neighbour of A across axis k.
            let mut b = a;
            b[k] = center[k] - corner_sign(s, k) * kappa * half[k];
            for j in 0..3 {
                sum[j] += a[j] + t[s][k] * (b[j] - a[j]);
            }
        }
        sum.map(|v| v / 4.0)
    })
}

/// Volume fraction of the cell `[-1, 1]^3` inside the pore `lambda R`
/// (`rq`: its radii at the quadrature points): `(1/24) sum w min(lambda R,
/// rho)^3`.
pub(crate) fn fraction(quad: &[QuadPoint], rq: &[f64], lambda: f64) -> f64 {
    quad.iter()
        .zip(rq)
        .map(|(q, &r)| q.weight * (lambda * r).min(q.rho).powi(3))
        .sum::<f64>()
        / 24.0
}

/// `d fraction / d lambda`.
fn fraction_slope(quad: &[QuadPoint], rq: &[f64], lambda: f64) -> f64 {
    quad.iter()
        .zip(rq)
        .filter(|(q, &r)| lambda * r < q.rho)
        .map(|(q, &r)| q.weight * r.powi(3))
        .sum::<f64>()
        * lambda
        * lambda
        / 8.0
}

/// The scale giving volume fraction `target` (0 < target < 1): safeguarded
/// Newton iteration on a bracket.
pub(crate) fn solve_lambda(quad: &[QuadPoint], rq: &[f64], target: f64) -> f64 {
    let mut lo = 0.0;
    let mut hi = quad
        .iter()
        .zip(rq)
        .map(|(q, &r)| q.rho / r)
        .fold(0.0, f64::max);
    let f1 = fraction(quad, rq, 1.0);
    let mut x = (target / f1).cbrt().clamp(lo, hi);
    for _ in 0..100 {
        let v = fraction(quad, rq, x) - target;
        if v.abs() < 1e-14 {
            break;
        }
        if v < 0.0 {
            lo = x;
        } else {
            hi = x;
        }
        let d = fraction_slope(quad, rq, x);
        let mut next = if d > 0.0 { x - v / d } else { f64::NAN };
        if !(next > lo && next < hi) {
            next = 0.5 * (lo + hi);
        }
        if (next - x).abs() <= 1e-15 * x.max(1.0) {
            x = next;
            break;
        }
        x = next;
    }
    x
}

/// The largest `R(y) / |y|` over the edge points: the pore `lambda R` stays
/// off the edges while `lambda` is below its inverse.
fn edge_reach(s: &Shared, map: &CubeMap) -> f64 {
    s.edges
        .iter()
        .map(|&y| gauge(map, y).0.recip())
        .fold(0.0, f64::max)
}

/// A solved pore, in cell coordinates.
#[derive(Clone, Debug)]
pub(crate) struct Solved {
    pub table: Arc<CubeMap>,
    pub lambda: f64,
    /// Irregularity used (after any reduction).
    pub sigma: f64,
    /// Eq. 9 parameters of the derived points.
    pub t: [[f64; 3]; 8],
    /// Porosity the table gives.
    pub porosity: f64,
    /// Blend towards the star shape ([`blend`]; 0: the Doo-Sabin pore).
    pub roundness: f64,
}

/// Range of porosities a parent box `kappa` times the cell reaches with
/// derived points on its edges (`t` in [0, 1]), the pore staying off the
/// cell's edges: from `fraction(kappa / 2)` (regular pore, `t = 1`) to the
/// regular pore touching the edges.
pub(crate) fn range(kappa: f64) -> (f64, f64) {
    let s = shared();
    let rq = s.radii(&s.regular);
    let lo = fraction(&s.quad, &rq, 0.5 * kappa);
    let hi = if s.lambda_edge <= kappa {
        s.p_edge
    } else {
        fraction(&s.quad, &rq, kappa)
    };
    (lo, hi)
}

/// Largest blend towards the star shape ([`blend`]) an opened pore may take.
pub const MAX_ROUNDNESS: f64 = 2.5;

/// Default reach of an opened pore past its cell's face centres, relative
/// to the half cell ([`crate::Options::opening`]).
pub const OPENING: f64 = 0.05;

/// The radial table `(1 - rho) R + rho R / R_reg` (per texel): at
/// `rho = 0` the Doo-Sabin pore `R`, at `rho = 1` its deformation applied
/// to the unit sphere (for the regular pore, the sphere through the face
/// centres), beyond 1 pulled in further towards the corners and edges.
/// The reach towards the six face centres, where `R_reg = 1`, does not
/// change.
pub fn blend(table: &CubeMap, rho: f64) -> CubeMap {
    let reg = shared().regular.values();
    let mut out = table.clone();
    for (v, &r) in out.values_mut().iter_mut().zip(reg) {
        let x = *v as f64;
        *v = ((1.0 - rho) * x + rho * x / r as f64) as f32;
    }
    out
}

/// Lowest porosity whose regular pore still opens into every face with
/// reach `1 + opening` (the star shape at [`MAX_ROUNDNESS`]); with
/// `opening = 0`, the face-touching porosity of the Doo-Sabin pore.
pub fn open_from(opening: f64) -> f64 {
    let s = shared();
    if opening <= 0.0 {
        return s.p_face;
    }
    let t = blend(&s.regular, MAX_ROUNDNESS);
    fraction(&s.quad, &s.radii(&t), 1.0 + opening)
}

/// Solves the pore of one cell for `target` in [`range`]: shape `1 + sigma u`,
/// reduced (halved, then 0) until the pore meets the rules: every `t` in
/// [0, 1]; above the face-touching porosity the pore contains the six face
/// centres (so it opens into every neighbour), below it the pore stays
/// inside the cell (closed); and it stays off the cell's edges (so the
/// solid stays connected).
///
/// With `opening > 0`, a target too low for the Doo-Sabin pore to reach
/// `1 + opening` past the face centres keeps that reach instead and meets
/// the target by the shape: the table is [`blend`]ed towards the star
/// shape (`rho` up to [`MAX_ROUNDNESS`], solved by bisection on the
/// volume), then `lambda` is solved on the blended table so the volume is
/// exact. Targets below [`open_from`] (or where no blend meets the rules)
/// fall back to the closed pore.
pub(crate) fn solve(
    target: f64,
    u: &[[f64; 3]; 8],
    sigma: f64,
    kappa: f64,
    opening: f64,
) -> Option<Solved> {
    let s = shared();
    let open_band = opening > 0.0 && target >= open_from(opening);
    for attempt in 0..=6 {
        let sig = if attempt == 6 {
            0.0
        } else {
            sigma / (1 << attempt) as f64
        };
        if attempt > 0 && attempt < 6 && sigma == 0.0 {
            continue;
        }
        let b: [[f64; 3]; 8] =
            std::array::from_fn(|v| std::array::from_fn(|a| 1.0 + sig * u[v][a]));
        let table = if sig == 0.0 {
            s.regular.clone()
        } else {
            match tabulate_shape(&b) {
                Some(m) => Arc::new(m),
                None => continue,
            }
        };
        let rq = s.radii(&table);
        let reach = 1.0 + opening;
        if open_band && fraction(&s.quad, &rq, reach) > target {
            if let Some(sol) = solve_open(&table, &rq, &b, target, sig, kappa, reach) {
                return Some(sol);
            }
            // Less irregularity before a closed pore.
            if attempt < 6 {
                continue;
            }
        }
        if let Some(sol) = check(&table, &rq, &b, target, sig, kappa, 0.0) {
            return Some(sol);
        }
    }
    None
}

/// The blended pore of reach `reach` meeting `target`, if the rules allow.
fn solve_open(
    table: &CubeMap,
    rq: &[f64],
    b: &[[f64; 3]; 8],
    target: f64,
    sig: f64,
    kappa: f64,
    reach: f64,
) -> Option<Solved> {
    let s = shared();
    // Radii of the star-end table, so the blend's radii are linear in rho.
    let star = blend(table, 1.0);
    let rs = s.radii(&star);
    let at = |rho: f64| {
        let r: Vec<f64> = rq
            .iter()
            .zip(&rs)
            .map(|(&a, &c)| (1.0 - rho) * a + rho * c)
            .collect();
        fraction(&s.quad, &r, reach)
    };
    if at(MAX_ROUNDNESS) > target {
        return None;
    }
    let (mut lo, mut hi) = (0.0, MAX_ROUNDNESS);
    for _ in 0..60 {
        let m = 0.5 * (lo + hi);
        if at(m) > target {
            lo = m;
        } else {
            hi = m;
        }
    }
    let rho = 0.5 * (lo + hi);
    let blended = blend(table, rho);
    if blended.values().iter().any(|&v| v.is_nan() || v <= 0.05) {
        return None;
    }
    let rb = s.radii(&blended);
    check(&Arc::new(blended), &rb, b, target, sig, kappa, rho)
}

/// `lambda` for `target` on `table` (radii `rq` at the quadrature points),
/// and the pore if it meets the rules.
fn check(
    table: &Arc<CubeMap>,
    rq: &[f64],
    b: &[[f64; 3]; 8],
    target: f64,
    sig: f64,
    kappa: f64,
    rho: f64,
) -> Option<Solved> {
    let s = shared();
    let lambda = solve_lambda(&s.quad, rq, target);
    let open = rho > 0.0 || target > s.p_face + 1e-9;
    let t: [[f64; 3]; 8] =
        std::array::from_fn(|v| std::array::from_fn(|a| 2.0 * (1.0 - lambda * b[v][a] / kappa)));
    let t_ok = t
        .iter()
        .flatten()
        .all(|&x| (-1e-12..=1.0 + 1e-12).contains(&x));
    let faces_ok = !open
        || (0..6).all(|f| {
            let mut y = [0.0; 3];
            y[f / 2] = if f % 2 == 0 { 1.0 } else { -1.0 };
            gauge(table, y).0 < lambda
        });
    let edges_ok = lambda * edge_reach(s, table) < 1.0;
    // Below the face-touching porosity the Doo-Sabin pore stays inside its
    // cell (closed pores, as in the paper's range).
    let closed_ok = open || s.quad.iter().zip(rq).all(|(q, &r)| lambda * r < q.rho);
    if t_ok && faces_ok && closed_ok && (edges_ok || target >= s.p_edge) {
        let porosity = fraction(&s.quad, rq, lambda);
        return Some(Solved {
            table: table.clone(),
            lambda,
            sigma: sig,
            t: t.map(|r| r.map(|x| x.clamp(0.0, 1.0))),
            porosity,
            roundness: rho,
        });
    }
    None
}

/// The radial table of the Doo-Sabin surface of the shape `b` (control
/// point `s` at `s * b_s` in cell coordinates): the limit mesh after
/// [`LEVEL`] steps, tabulated on [`TEXELS`] texels per face side. `None`
/// when the surface is not star-shaped around the centre.
pub fn tabulate_shape(b: &[[f64; 3]; 8]) -> Option<CubeMap> {
    let s = shared();
    let pos = s.mesh.positions(&control(b));
    s.walker
        .tabulate(&pos)
        .or_else(|| match tabulate(&pos, &s.tris, TEXELS) {
            Some((m, r)) if r.conflicts == 0 => Some(m),
            _ => None,
        })
}

/// Random directions of a pore's vertices: `u` uniform in [-1, 1] per
/// vertex and axis, less the mean over each face of the component normal
/// to it, so the pore's reach towards the six face centres (and with it the
/// opening into each neighbour) is that of the regular pore to first order
/// while the faces tilt and warp.
pub fn face_balanced(mut draw: impl FnMut() -> f64) -> [[f64; 3]; 8] {
    let mut u: [[f64; 3]; 8] = std::array::from_fn(|_| std::array::from_fn(|_| draw()));
    for a in 0..3 {
        for side in [0usize, 1] {
            let on = |s: usize| (s >> a & 1) == side;
            let mean = (0..8).filter(|&s| on(s)).map(|s| u[s][a]).sum::<f64>() / 4.0;
            for (s, us) in u.iter_mut().enumerate() {
                if on(s) {
                    us[a] -= mean;
                }
            }
        }
    }
    // Back into [-1, 1] (the mean removal can reach 1.75).
    let m = u.iter().flatten().fold(1.0f64, |m, v| m.max(v.abs()));
    u.map(|r| r.map(|v| v / m))
}
