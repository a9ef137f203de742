//! Doo-Sabin subdivision of the cube's topology, symbolically.
//!
//! Every derived polyhedron of Kou and Tan has the topology of a cube (eight
//! vertices of valence three, six quadrilateral faces). Doo-Sabin
//! subdivision is linear in the control points, so each vertex of a
//! subdivided mesh is a fixed combination of the eight control points; this
//! module computes those combinations once and any pore's surface is then
//! a matrix product.
//!
//! Doo-Sabin is the quadratic scheme: on regular quad regions its limit is
//! the uniform biquadratic B-spline, the surface analogue of the closed
//! quadratic B-spline curve (Chaikin's corner cutting) of the 2D pores.
//! Each step replaces an n-gon's corner `i` by `sum_j a_n(i - j) v_j` with
//! `a_n(0) = (n + 5) / 4n` and `a_n(k) = (3 + 2 cos(2 pi k / n)) / 4n`, and
//! makes a face per old face, per old edge and per old vertex. The weights
//! of a face are circulant with unit row sums, so the new face made from an
//! old face has the same centroid, shrinks onto it and the centroid of every
//! face at every level is a point of the limit surface. [`limit_mesh`]
//! joins these centroids (the dual mesh) into a closed quad mesh whose
//! vertices lie exactly on the limit surface.

/// A polygon mesh whose vertices are combinations of the eight control
/// points (bit 0 of a control point's index is its x side, bit 1 y, bit 2 z).
#[derive(Clone, Debug)]
pub struct SymbolicMesh {
    /// Weights of the eight control points, per vertex.
    pub weights: Vec<[f64; 8]>,
    /// Faces as vertex indices, counter-clockwise seen from outside.
    pub faces: Vec<Vec<u32>>,
}

/// Sign (+1 or -1) of control point `s` on `axis`.
pub fn corner_sign(s: usize, axis: usize) -> f64 {
    if s >> axis & 1 == 1 {
        1.0
    } else {
        -1.0
    }
}

/// The control cube: vertex `s` has weight 1 on control point `s`.
pub fn cube() -> SymbolicMesh {
    let weights = (0..8)
        .map(|s| std::array::from_fn(|k| if k == s { 1.0 } else { 0.0 }))
        .collect();
    let mut faces = Vec::new();
    for axis in 0..3 {
        for side in [0usize, 1] {
            // The four corners with this bit, in cyclic order on the face.
            let (b, c) = other_axes(axis);
            let quad = [(0, 0), (1, 0), (1, 1), (0, 1)]
                .map(|(i, j)| (side << axis | i << b | j << c) as u32);
            // Orient outwards: the normal (p1 - p0) x (p2 - p0) along +axis
            // for side 1 and -axis for side 0.
            let p = |v: u32| -> [f64; 3] { std::array::from_fn(|a| corner_sign(v as usize, a)) };
            let n = cross(sub(p(quad[1]), p(quad[0])), sub(p(quad[2]), p(quad[0])));
            let outward = if side == 1 {
                n[axis] > 0.0
            } else {
                n[axis] < 0.0
            };
            let mut f = quad.to_vec();
            if !outward {
                f.reverse();
            }
            faces.push(f);
        }
    }
    SymbolicMesh { weights, faces }
}

/// The two axes other than `a`, in increasing order.
pub fn other_axes(a: usize) -> (usize, usize) {
    match a {
        0 => (1, 2),
        1 => (0, 2),
        _ => (0, 1),
    }
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Doo-Sabin weight of vertex `j` for the new corner `i` of an n-gon.
pub fn weight(n: usize, i: usize, j: usize) -> f64 {
    let k = (i + n - j) % n;
    let n = n as f64;
    if k == 0 {
        (n + 5.0) / (4.0 * n)
    } else {
        (3.0 + 2.0 * (2.0 * std::f64::consts::PI * k as f64 / n).cos()) / (4.0 * n)
    }
}

/// One Doo-Sabin step.
pub fn step(m: &SymbolicMesh) -> SymbolicMesh {
    use std::collections::HashMap;
    // New vertex per (face, corner).
    let mut first = Vec::with_capacity(m.faces.len());
    let mut weights = Vec::new();
    for f in &m.faces {
        first.push(weights.len() as u32);
        let n = f.len();
        for i in 0..n {
            let mut w = [0.0; 8];
            for (j, &v) in f.iter().enumerate() {
                let a = weight(n, i, j);
                for (k, wk) in w.iter_mut().enumerate() {
                    *wk += a * m.weights[v as usize][k];
                }
            }
            weights.push(w);
        }
    }
    let corner = |f: usize, i: usize| first[f] + i as u32;
    // Directed edge (u, v) -> (face, index of u in it).
    let mut edges: HashMap<(u32, u32), (usize, usize)> = HashMap::new();
    for (fi, f) in m.faces.iter().enumerate() {
        for i in 0..f.len() {
            edges.insert((f[i], f[(i + 1) % f.len()]), (fi, i));
        }
    }
    let mut faces: Vec<Vec<u32>> = Vec::new();
    // F-faces.
    for (fi, f) in m.faces.iter().enumerate() {
        faces.push((0..f.len()).map(|i| corner(fi, i)).collect());
    }
    // E-faces, one per undirected edge, taken from the direction u < v.
    let mut keys: Vec<(u32, u32)> = edges.keys().copied().filter(|(u, v)| u < v).collect();
    keys.sort_unstable();
    for (u, v) in keys {
        let (f, i) = edges[&(u, v)];
        let (g, k) = edges[&(v, u)];
        let nf = m.faces[f].len();
        let ng = m.faces[g].len();
        // In f the edge runs u -> v (u at i, v at i + 1); in g it runs v -> u.
        faces.push(vec![
            corner(f, (i + 1) % nf),
            corner(f, i),
            corner(g, (k + 1) % ng),
            corner(g, k),
        ]);
    }
    // V-faces: the corners at an old vertex, faces taken counter-clockwise
    // around it (the next face is the one across the edge entering the
    // vertex in the current face).
    let nv = m.weights.len();
    let mut at_vertex: Vec<Option<(usize, usize)>> = vec![None; nv];
    for (fi, f) in m.faces.iter().enumerate() {
        for (i, &v) in f.iter().enumerate() {
            at_vertex[v as usize].get_or_insert((fi, i));
        }
    }
    for start in at_vertex.into_iter().flatten() {
        let mut ring = Vec::new();
        let (mut f, mut i) = start;
        loop {
            ring.push(corner(f, i));
            let face = &m.faces[f];
            let v = face[i];
            let prev = face[(i + face.len() - 1) % face.len()];
            // The face holding v -> prev.
            let (g, k) = edges[&(v, prev)];
            f = g;
            i = k;
            if (f, i) == start {
                break;
            }
        }
        faces.push(ring);
    }
    SymbolicMesh { weights, faces }
}

/// A closed quad mesh with its vertices exactly on the Doo-Sabin limit
/// surface of the cube topology: the centroids of the faces of the mesh
/// after `level` steps, joined around each vertex.
#[derive(Clone, Debug)]
pub struct LimitMesh {
    /// Control-point weights of each limit point.
    pub points: Vec<[f64; 8]>,
    /// Quads of limit points, counter-clockwise seen from outside.
    pub quads: Vec<[u32; 4]>,
}

/// The limit mesh after `level >= 1` steps: `6 * 4^level + 2` points,
/// `6 * 4^level` quads.
pub fn limit_mesh(level: usize) -> LimitMesh {
    let mut m = cube();
    for _ in 0..level.max(1) {
        m = step(&m);
    }
    let points = m
        .faces
        .iter()
        .map(|f| {
            let mut w = [0.0; 8];
            for &v in f {
                for (k, wk) in w.iter_mut().enumerate() {
                    *wk += m.weights[v as usize][k] / f.len() as f64;
                }
            }
            w
        })
        .collect();
    // Faces around each vertex, counter-clockwise seen from outside: the
    // dual faces. After one step every vertex has valence 4.
    use std::collections::HashMap;
    let mut edges: HashMap<(u32, u32), (usize, usize)> = HashMap::new();
    let mut at_vertex: Vec<Option<(usize, usize)>> = vec![None; m.weights.len()];
    for (fi, f) in m.faces.iter().enumerate() {
        for i in 0..f.len() {
            edges.insert((f[i], f[(i + 1) % f.len()]), (fi, i));
            at_vertex[f[i] as usize].get_or_insert((fi, i));
        }
    }
    let mut quads = Vec::with_capacity(m.weights.len());
    for start in at_vertex.into_iter().flatten() {
        let mut ring = Vec::new();
        let (mut f, mut i) = start;
        loop {
            ring.push(f as u32);
            let face = &m.faces[f];
            let v = face[i];
            let prev = face[(i + face.len() - 1) % face.len()];
            let (g, k) = edges[&(v, prev)];
            f = g;
            i = k;
            if (f, i) == start {
                break;
            }
        }
        debug_assert_eq!(ring.len(), 4, "Doo-Sabin vertices have valence 4");
        quads.push([ring[0], ring[1], ring[2], ring[3]]);
    }
    LimitMesh { points, quads }
}

impl LimitMesh {
    /// Positions of the limit points for the control points `ctrl`.
    pub fn positions(&self, ctrl: &[[f64; 3]; 8]) -> Vec<[f64; 3]> {
        self.points
            .iter()
            .map(|w| {
                let mut p = [0.0; 3];
                for (s, c) in ctrl.iter().enumerate() {
                    for a in 0..3 {
                        p[a] += w[s] * c[a];
                    }
                }
                p
            })
            .collect()
    }

    /// Enclosed volume of the quad mesh (each quad split along its 0-2
    /// diagonal) for the given positions, by the divergence theorem.
    pub fn volume(&self, pos: &[[f64; 3]]) -> f64 {
        let det = |a: [f64; 3], b: [f64; 3], c: [f64; 3]| {
            a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                + a[2] * (b[0] * c[1] - b[1] * c[0])
        };
        self.quads
            .iter()
            .map(|q| {
                let p = q.map(|i| pos[i as usize]);
                det(p[0], p[1], p[2]) + det(p[0], p[2], p[3])
            })
            .sum::<f64>()
            / 6.0
    }
}
