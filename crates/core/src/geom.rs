//! Small fixed-size geometry shared by the mesher, the analysis and the
//! density solver: 3-vectors as `[f64; 3]` and the Kuhn split of a cube.
//! (Plain arrays rather than a vector crate: these few operations are all
//! the callers need, and the arrays are what they store.)

/// `a - b`.
pub fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// Cross product `a x b`.
pub fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Dot product.
pub fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Euclidean length.
pub fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

/// The six tetrahedra of the Kuhn split of a cube, corners as bit masks
/// (bit `a` set = far side on axis `a`); each is a monotone path from corner
/// 0 to corner 7, so neighbouring cubes split their shared faces alike.
pub const KUHN_TETS: [[usize; 4]; 6] = [
    [0, 1, 3, 7],
    [0, 1, 5, 7],
    [0, 2, 3, 7],
    [0, 2, 6, 7],
    [0, 4, 5, 7],
    [0, 4, 6, 7],
];
