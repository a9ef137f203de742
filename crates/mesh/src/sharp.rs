//! Sharp features in the style of extended marching cubes (Kobbelt, Botsch,
//! Schwanecke and Seidel, 2001), on the cycles of [`crate::cubes`].
//!
//! Marching cubes puts vertices on grid edges only, so a crease or a corner
//! of the model that passes through a cell is cut off by the cell's
//! triangles (chamfered). Here a cell's cycle of face segments whose vertex
//! normals spread by more than a feature angle gets one extra vertex: the
//! point that best fits the tangent planes at the cycle's vertices in the
//! least-squares sense (a quadratic error function as in dual contouring,
//! solved through the eigenvectors of its 3x3 matrix, directions with small
//! eigenvalues left at the cycle's mass point; for a crease, the middle of
//! the crease line's chord through the cell). It may lie up to half a cell
//! outside its cell: a crease or corner often runs through cells whose
//! corners are all outside, and only their neighbours see it. A cycle
//! whose tangent planes miss the point by more than a twentieth of a cell
//! is a smooth surface curved within the cell, not a feature.
//!
//! The cycle's disk is then a fan around that vertex: the same boundary,
//! so the mesh stays closed, oriented and manifold. Two fans of
//! neighbouring cells that share a face segment `a b` have the triangles
//! `F1 a b` and `F2 b a`; the segment chords across the crease between the
//! two feature vertices, and those triangles stand across it. Flipping the
//! segment to `F1 F2` (the triangles `F1 a F2` and `F2 b F1`, [`flip`])
//! lays a mesh edge along the crease; it keeps every edge in two triangles
//! and is done once at most between two cells, so `F1 F2` is new. Where
//! the flip is not proper because both cells placed their vertex on the
//! same stretch of crease, the two vertices become one and the two
//! triangles on the segment go: the two disks join into one (the caller,
//! `brick`, does this within a brick). A fan with a triangle that is
//! degenerate or faces against its crossings' normals ([`fan_ok`]), and is
//! not flipped away, is refused: the cell keeps its old triangles.

use microfrep_core::geom::{cross, dot, sub};

/// Cosine of the feature angle: a cycle whose vertex normals have two
/// directions more than this angle apart (35 degrees) is a feature.
pub const FEATURE_COS: f64 = 0.819_152;

/// Eigenvalues of the error function's matrix below this fraction of the
/// largest are dropped (the point stays at the mass point along them).
const TRUNCATE: f64 = 0.02;

/// How far, in cells, a feature vertex may lie outside the cell whose
/// normals found it.
const SLACK: f64 = 0.5;

/// The root mean square distance, in cells, from the feature vertex to the
/// tangent planes above which the cycle counts as smooth.
const RESIDUAL: f64 = 0.05;

/// Smallest doubled area, in cell areas, of a fan or flipped triangle.
const MIN_AREA: f64 = 1e-6;

/// The eigenvalues and unit eigenvectors (columns) of the symmetric 3x3
/// matrix `a`, by cyclic Jacobi rotations.
fn eigen(mut a: [[f64; 3]; 3]) -> ([f64; 3], [[f64; 3]; 3]) {
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _ in 0..32 {
        let off = a[0][1].abs() + a[0][2].abs() + a[1][2].abs();
        let scale = a[0][0].abs() + a[1][1].abs() + a[2][2].abs();
        if off <= 1e-15 * scale || off == 0.0 {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if a[p][q] == 0.0 {
                continue;
            }
            // The rotation in the (p, q) plane that zeroes a[p][q].
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            // Columns p and q, then rows p and q.
            for row in a.iter_mut() {
                let (akp, akq) = (row[p], row[q]);
                row[p] = c * akp - s * akq;
                row[q] = s * akp + c * akq;
            }
            let (rp, rq) = (a[p], a[q]);
            for k in 0..3 {
                a[p][k] = c * rp[k] - s * rq[k];
                a[q][k] = s * rp[k] + c * rq[k];
            }
            for row in v.iter_mut() {
                let (vp, vq) = (row[p], row[q]);
                row[p] = c * vp - s * vq;
                row[q] = s * vp + c * vq;
            }
        }
    }
    ([a[0][0], a[1][1], a[2][2]], v)
}

/// How many matrices [`eigen_lanes`] takes at once.
const LANES: usize = 4;

/// [`eigen`] of `LANES` matrices side by side, each lane doing exactly the
/// operations `eigen` does on it (rotations it would skip, and sweeps after
/// it would have stopped, are computed and dropped), so the results are
/// the same bits; the lanes' arithmetic runs in vector registers.
fn eigen_lanes(m: [[[f64; 3]; 3]; LANES]) -> [([f64; 3], [[f64; 3]; 3]); LANES] {
    type L = [f64; LANES];
    let mut a: [[L; 3]; 3] = std::array::from_fn(|r| std::array::from_fn(|c| m.map(|x| x[r][c])));
    let one: L = [1.0; LANES];
    let zero: L = [0.0; LANES];
    let mut v: [[L; 3]; 3] = [[one, zero, zero], [zero, one, zero], [zero, zero, one]];
    let mut live = [true; LANES];
    for _ in 0..32 {
        for l in 0..LANES {
            let off = a[0][1][l].abs() + a[0][2][l].abs() + a[1][2][l].abs();
            let scale = a[0][0][l].abs() + a[1][1][l].abs() + a[2][2][l].abs();
            if off <= 1e-15 * scale || off == 0.0 {
                live[l] = false;
            }
        }
        if !live.contains(&true) {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            let go: [bool; LANES] = std::array::from_fn(|l| live[l] && a[p][q][l] != 0.0);
            if !go.contains(&true) {
                continue;
            }
            let mut c = [0.0; LANES];
            let mut s = [0.0; LANES];
            for l in 0..LANES {
                let theta = (a[q][q][l] - a[p][p][l]) / (2.0 * a[p][q][l]);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                c[l] = 1.0 / (t * t + 1.0).sqrt();
                s[l] = t * c[l];
            }
            let pick = |new: f64, old: f64, l: usize| if go[l] { new } else { old };
            for row in a.iter_mut() {
                let (akp, akq) = (row[p], row[q]);
                for l in 0..LANES {
                    row[p][l] = pick(c[l] * akp[l] - s[l] * akq[l], akp[l], l);
                    row[q][l] = pick(s[l] * akp[l] + c[l] * akq[l], akq[l], l);
                }
            }
            let (rp, rq) = (a[p], a[q]);
            for k in 0..3 {
                for l in 0..LANES {
                    a[p][k][l] = pick(c[l] * rp[k][l] - s[l] * rq[k][l], rp[k][l], l);
                    a[q][k][l] = pick(s[l] * rp[k][l] + c[l] * rq[k][l], rq[k][l], l);
                }
            }
            for row in v.iter_mut() {
                let (vp, vq) = (row[p], row[q]);
                for l in 0..LANES {
                    row[p][l] = pick(c[l] * vp[l] - s[l] * vq[l], vp[l], l);
                    row[q][l] = pick(s[l] * vp[l] + c[l] * vq[l], vq[l], l);
                }
            }
        }
    }
    std::array::from_fn(|l| {
        (
            [a[0][0][l], a[1][1][l], a[2][2][l]],
            std::array::from_fn(|r| std::array::from_fn(|c| v[r][c][l])),
        )
    })
}

/// Whether the unit normals `ns` spread by more than the feature angle.
pub fn is_feature(ns: &[[f64; 3]]) -> bool {
    ns.iter()
        .enumerate()
        .any(|(i, a)| ns[i + 1..].iter().any(|b| dot(*a, *b) < FEATURE_COS))
}

/// A cycle whose normals spread by the feature angle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Feature {
    /// Its feature vertex (in cell units), where one is found.
    pub point: Option<[f64; 3]>,
    /// Whether its tangent planes meet to within [`PLANAR`] cells: the
    /// sides of the feature are flat, and the volume correction leaves its
    /// vertices alone.
    pub planar: bool,
}

/// The root mean square distance, in cells, from the feature point to the
/// tangent planes below which the sides of a feature count as flat.
pub const PLANAR: f64 = 0.005;

/// The feature vertex of a cycle with vertices `ps` (in cell units, the
/// cell being the unit cube) and unit outward normals `ns`: the least
/// squares meet of the tangent planes (for a crease, the middle of the
/// crease line's chord through the cell); `None` when the normals do not
/// spread by the feature angle or one is missing (zero). The point is left
/// out when it lies more than half a cell outside the cell or more than
/// `RESIDUAL` cells (root mean square) off the tangent planes. Whether the
/// fan around it is proper is for the caller ([`fan_ok`], after flips).
pub fn feature_point(ps: &[[f64; 3]], ns: &[[f64; 3]]) -> Option<Feature> {
    let q = quadric(ps, ns)?;
    let (lam, v) = eigen(q.a);
    match solve(ps, ns, &q, lam, v) {
        Step::Done(f) => f,
        Step::Line { x, along } => {
            let t = nearest_to_cell(x, along);
            judge(ps, ns, std::array::from_fn(|k| x[k] + t * along[k]))
        }
    }
}

/// [`feature_point`] of many cycles at once, the vertices and normals of
/// cycle `i` being `ps[r.clone()]` and `ns[r.clone()]` for the `i`-th range
/// `r` of `cycles`: the same results, bit for bit, with the eigenvectors
/// of several matrices found side by side (four at a time in vector lanes).
pub fn feature_points(
    ps: &[[f64; 3]],
    ns: &[[f64; 3]],
    cycles: &[std::ops::Range<usize>],
    out: &mut Vec<Option<Feature>>,
) {
    out.clear();
    let qs: Vec<Option<Quadric>> = cycles
        .iter()
        .map(|r| quadric(&ps[r.clone()], &ns[r.clone()]))
        .collect();
    let which: Vec<usize> = (0..qs.len()).filter(|&i| qs[i].is_some()).collect();
    let mut eig = vec![([0.0; 3], [[0.0; 3]; 3]); which.len()];
    for (chunk, res) in which.chunks(LANES).zip(eig.chunks_mut(LANES)) {
        let mut a = [[[0.0; 3]; 3]; LANES];
        for (l, &i) in chunk.iter().enumerate() {
            a[l] = qs[i].as_ref().expect("chosen").a;
        }
        let e = eigen_lanes(a);
        res.copy_from_slice(&e[..chunk.len()]);
    }
    let mut e = eig.into_iter();
    let mut lines = Vec::new();
    for (i, (r, q)) in cycles.iter().zip(&qs).enumerate() {
        out.push(q.as_ref().and_then(|q| {
            let (lam, v) = e.next().expect("one per quadric");
            match solve(&ps[r.clone()], &ns[r.clone()], q, lam, v) {
                Step::Done(f) => f,
                Step::Line { x, along } => {
                    lines.push((i, x, along));
                    None
                }
            }
        }));
    }
    for chunk in lines.chunks(LANES) {
        let mut xs = [[0.5; 3]; LANES];
        let mut alongs = [[1.0, 0.0, 0.0]; LANES];
        for (l, &(_, x, along)) in chunk.iter().enumerate() {
            xs[l] = x;
            alongs[l] = along;
        }
        let ts = nearest_lanes(xs, alongs);
        for (&(i, x, along), t) in chunk.iter().zip(ts) {
            let r = cycles[i].clone();
            out[i] = judge(
                &ps[r.clone()],
                &ns[r],
                std::array::from_fn(|k| x[k] + t * along[k]),
            );
        }
    }
}

/// The error function of a cycle: its matrix, its vector and the mass
/// point it is centred on.
struct Quadric {
    a: [[f64; 3]; 3],
    b: [f64; 3],
    c: [f64; 3],
}

/// The error function of the cycle `ps`, `ns` when its normals spread by
/// the feature angle and none is missing.
fn quadric(ps: &[[f64; 3]], ns: &[[f64; 3]]) -> Option<Quadric> {
    let n = ps.len();
    if n < 3 || ns.iter().any(|v| dot(*v, *v) < 0.5) || !is_feature(ns) {
        return None;
    }
    let mut c = [0.0; 3];
    for p in ps {
        for k in 0..3 {
            c[k] += p[k] / n as f64;
        }
    }
    let mut a = [[0.0; 3]; 3];
    let mut b = [0.0; 3];
    for (p, m) in ps.iter().zip(ns) {
        let d = dot(*m, sub(*p, c));
        for r in 0..3 {
            b[r] += m[r] * d;
            for s in 0..3 {
                a[r][s] += m[r] * m[s];
            }
        }
    }
    Some(Quadric { a, b, c })
}

/// The feature of the cycle `ps`, `ns` with error function `q`, whose
/// matrix has eigenvalues `lam` and eigenvectors (columns) `v`.
fn solve(ps: &[[f64; 3]], ns: &[[f64; 3]], q: &Quadric, lam: [f64; 3], v: [[f64; 3]; 3]) -> Step {
    let (b, c) = (q.b, q.c);
    let top = lam.iter().cloned().fold(0.0, f64::max);
    let mut x = c;
    let mut kept = 0;
    let mut along = [0.0; 3];
    for k in 0..3 {
        let col = [v[0][k], v[1][k], v[2][k]];
        if lam[k] > TRUNCATE * top {
            kept += 1;
            let t = dot(col, b) / lam[k];
            for r in 0..3 {
                x[r] += t * col[r];
            }
        } else {
            along = col;
        }
    }
    let x = match kept {
        // A corner: where the planes meet, which must be in the cell.
        3 => x,
        // A crease: the middle of its chord through the cell, or where
        // the line misses the cell, its point nearest the cell (which
        // must be within `SLACK`).
        2 => {
            let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
            for k in 0..3 {
                if along[k].abs() > 1e-12 {
                    let (a, b) = ((0.0 - x[k]) / along[k], (1.0 - x[k]) / along[k]);
                    t0 = t0.max(a.min(b));
                    t1 = t1.min(a.max(b));
                } else if !(0.0..=1.0).contains(&x[k]) {
                    // Parallel to the slab and outside it.
                    t0 = f64::INFINITY;
                }
            }
            // The middle of the crease's chord through the cell (a point on
            // a face of the cell would lay the fan triangle of that face's
            // segment into the face); where the line misses the cell, its
            // point nearest the cell: a crease through a cell whose corners
            // are all outside is seen only by its neighbours, and each of
            // them must put its vertex on the crease where it passes them
            // for the chain of flipped segments to follow it.
            if t0 <= t1 && t0.is_finite() && t1.is_finite() {
                let t = 0.5 * (t0 + t1);
                std::array::from_fn(|k| x[k] + t * along[k])
            } else {
                return Step::Line { x, along };
            }
        }
        _ => return Step::Done(None),
    };
    Step::Done(judge(ps, ns, x))
}

/// Where [`solve`] got to: the feature, or a crease line that misses the
/// cell, whose point nearest the cell ([`nearest_to_cell`]) is for
/// [`judge`].
enum Step {
    Done(Option<Feature>),
    Line { x: [f64; 3], along: [f64; 3] },
}

/// The feature of the cycle `ps`, `ns` whose tangent planes meet best at
/// `x`.
fn judge(ps: &[[f64; 3]], ns: &[[f64; 3]], x: [f64; 3]) -> Option<Feature> {
    let n = ps.len();
    // Tangent planes of a crease or corner meet in the point; those of a
    // smooth surface curved within the cell (a tube a cell or two thick)
    // miss it by a fair part of the cell: that is no sharp feature.
    let miss = ps
        .iter()
        .zip(ns)
        .map(|(p, m)| dot(*m, sub(x, *p)).powi(2))
        .sum::<f64>();
    let rms = (miss / n as f64).sqrt();
    // Outside the cell by at most `SLACK` (a crease that only grazes a cell
    // whose corners all lie outside leaves its neighbours to place it).
    let inside = x.iter().all(|v| (-SLACK..=1.0 + SLACK).contains(v));
    Some(Feature {
        point: (inside && rms <= RESIDUAL).then_some(x),
        planar: rms <= PLANAR,
    })
}

/// The parameter `t` of the point `x + t along` of a line (`along` a unit
/// vector) nearest the unit cell: the distance to the cell is convex in
/// `t`, so a golden-section search on a bracket around the point nearest
/// the cell's centre finds it.
fn nearest_to_cell(x: [f64; 3], along: [f64; 3]) -> f64 {
    let gap = |t: f64| -> f64 {
        (0..3)
            .map(|k| {
                let v = x[k] + t * along[k];
                (v.max(0.0) - v).max(v - v.min(1.0)).powi(2)
            })
            .sum()
    };
    let c = dot(sub([0.5; 3], x), along);
    let (mut a, mut b) = (c - 2.0, c + 2.0);
    const R: f64 = 0.618_033_988_749_895;
    for _ in 0..60 {
        let (p, q) = (b - R * (b - a), a + R * (b - a));
        if gap(p) <= gap(q) {
            b = q;
        } else {
            a = p;
        }
    }
    0.5 * (a + b)
}

/// [`nearest_to_cell`] of `LANES` lines side by side, each lane doing
/// exactly its operations (the same bits).
fn nearest_lanes(x: [[f64; 3]; LANES], along: [[f64; 3]; LANES]) -> [f64; LANES] {
    let gap = |t: [f64; LANES]| -> [f64; LANES] {
        std::array::from_fn(|l| {
            (0..3)
                .map(|k| {
                    let v = x[l][k] + t[l] * along[l][k];
                    (v.max(0.0) - v).max(v - v.min(1.0)).powi(2)
                })
                .sum()
        })
    };
    let c: [f64; LANES] = std::array::from_fn(|l| dot(sub([0.5; 3], x[l]), along[l]));
    let mut a = c.map(|c| c - 2.0);
    let mut b = c.map(|c| c + 2.0);
    const R: f64 = 0.618_033_988_749_895;
    for _ in 0..60 {
        let p: [f64; LANES] = std::array::from_fn(|l| b[l] - R * (b[l] - a[l]));
        let q: [f64; LANES] = std::array::from_fn(|l| a[l] + R * (b[l] - a[l]));
        let (gp, gq) = (gap(p), gap(q));
        for l in 0..LANES {
            if gp[l] <= gq[l] {
                b[l] = q[l];
            } else {
                a[l] = p[l];
            }
        }
    }
    std::array::from_fn(|l| 0.5 * (a[l] + b[l]))
}

/// Whether the fan triangle `f a b` (positions in any common frame, `na`
/// and `nb` the unit normals at `a` and `b`, `h` the cell size) is proper
/// and faces along the normals at its crossings. A triangle whose
/// crossings lie on the two sides of a feature (their normals differ by
/// more than the feature angle) spans the crease from a face segment that
/// cuts across it: it stands across the crease, about perpendicular to both
/// sides, and is taken unless it turns more than 120 degrees from their
/// mean normal (it is flipped away where the next cell has a fan too).
/// With `any_facing`, only properness counts.
pub fn fan_ok(
    f: [f64; 3],
    a: [f64; 3],
    b: [f64; 3],
    na: [f64; 3],
    nb: [f64; 3],
    h: f64,
    any_facing: bool,
) -> bool {
    let t = cross(sub(a, f), sub(b, f));
    let m = [na[0] + nb[0], na[1] + nb[1], na[2] + nb[2]];
    let (lt, lm) = (dot(t, t).sqrt(), dot(m, m).sqrt());
    let least = if dot(na, nb) < FEATURE_COS { -0.5 } else { 0.0 };
    lt > MIN_AREA * h * h && (any_facing || dot(t, m) > least * lt * lm)
}

/// Whether to flip the segment `a b` shared by the fan triangles `f1 a b`
/// and `f2 b a` into `f1 a f2` and `f2 b f1` (positions in any common
/// frame, `na` and `nb` the unit normals at `a` and `b`, `h` the cell
/// size): both new triangles proper and facing along those normals.
pub fn flip(
    f1: [f64; 3],
    f2: [f64; 3],
    a: [f64; 3],
    b: [f64; 3],
    na: [f64; 3],
    nb: [f64; 3],
    h: f64,
) -> bool {
    let tri = |p: [f64; 3], q: [f64; 3], r: [f64; 3]| cross(sub(q, p), sub(r, p));
    let (t1, t2) = (tri(f1, a, f2), tri(f2, b, f1));
    let min = MIN_AREA * h * h;
    let proper = |t: [f64; 3], m: [f64; 3]| dot(t, t).sqrt() > min && dot(t, m) > 0.0;
    proper(t1, na) && proper(t2, nb)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eigen_decomposes_a_symmetric_matrix() {
        let a = [[2.0, 1.0, 0.0], [1.0, 2.0, 0.5], [0.0, 0.5, 1.0]];
        let (l, v) = eigen(a);
        for k in 0..3 {
            let col = [v[0][k], v[1][k], v[2][k]];
            for r in 0..3 {
                let av = a[r][0] * col[0] + a[r][1] * col[1] + a[r][2] * col[2];
                assert!((av - l[k] * col[r]).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn eigen_lanes_are_eigen_bit_for_bit() {
        // Matrices of unit normals as the error functions make them, some
        // with zero off-diagonal entries (skipped rotations), some already
        // diagonal (lanes that stop at once).
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut rnd = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for round in 0..200 {
            let m: [[[f64; 3]; 3]; LANES] = std::array::from_fn(|l| {
                let mut a = [[0.0; 3]; 3];
                for _ in 0..3 + (round + l) % 4 {
                    let mut n = [rnd(), rnd(), rnd()];
                    match (round + 2 * l) % 5 {
                        0 => n[2] = 0.0,
                        1 => n = [0.0, 0.0, 1.0],
                        _ => {}
                    }
                    let len = dot(n, n).sqrt();
                    for r in 0..3 {
                        for s in 0..3 {
                            a[r][s] += n[r] * n[s] / (len * len);
                        }
                    }
                }
                a
            });
            let lanes = eigen_lanes(m);
            for l in 0..LANES {
                let (lam, v) = eigen(m[l]);
                assert_eq!(lam.map(f64::to_bits), lanes[l].0.map(f64::to_bits));
                assert_eq!(
                    v.map(|r| r.map(f64::to_bits)),
                    lanes[l].1.map(|r| r.map(f64::to_bits))
                );
            }
        }
    }

    #[test]
    fn nearest_lanes_are_nearest_to_cell_bit_for_bit() {
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        let mut rnd = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..200 {
            let x: [[f64; 3]; LANES] = std::array::from_fn(|_| [0; 3].map(|_| 4.0 * rnd() - 1.5));
            let along: [[f64; 3]; LANES] = std::array::from_fn(|_| {
                let d = [0; 3].map(|_| rnd() - 0.5);
                let len = dot(d, d).sqrt();
                d.map(|v| v / len)
            });
            let ts = nearest_lanes(x, along);
            for l in 0..LANES {
                assert_eq!(ts[l].to_bits(), nearest_to_cell(x[l], along[l]).to_bits());
            }
        }
    }

    #[test]
    fn a_crease_point_lies_on_the_crease() {
        // The crease x = 0.3, y = 0.4 of the block x < 0.3, y < 0.4 through
        // a cell: the point lies on the crease line, at the mass point
        // along it.
        let ps = [
            [0.0, 0.4, 0.0],
            [0.0, 0.4, 1.0],
            [0.3, 0.0, 1.0],
            [0.3, 0.0, 0.0],
        ];
        let ns = [
            [0.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
        ];
        let f = feature_point(&ps, &ns).expect("a crease");
        assert!(f.planar);
        let x = f.point.expect("a crease point");
        assert!(
            (x[0] - 0.3).abs() < 1e-12 && (x[1] - 0.4).abs() < 1e-12,
            "{x:?}"
        );
        assert!((x[2] - 0.5).abs() < 1e-12, "{x:?}");
        // A plane is no feature.
        let flat = [[1.0, 0.0, 0.0]; 4];
        assert!(feature_point(&ps, &flat).is_none());
    }
}
