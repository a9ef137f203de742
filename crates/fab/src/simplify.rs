//! Douglas-Peucker simplification of closed loops.

/// Distance from `p` to the segment `a b`.
fn seg_dist(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let l2 = dx * dx + dy * dy;
    let t = if l2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    ((p[0] - a[0] - t * dx).powi(2) + (p[1] - a[1] - t * dy).powi(2)).sqrt()
}

/// Keeps the vertices of the closed loop `p` needed so that no dropped vertex
/// is farther than `tol` from the simplified loop. The loop is cut at vertex 0
/// and the vertex farthest from it, and each half simplified on its own.
pub fn simplify_closed(p: &[[f64; 2]], tol: f64) -> Vec<[f64; 2]> {
    let n = p.len();
    if n < 4 {
        return p.to_vec();
    }
    let d0 = |q: [f64; 2]| (q[0] - p[0][0]).powi(2) + (q[1] - p[0][1]).powi(2);
    let far = (1..n)
        .max_by(|&a, &b| d0(p[a]).total_cmp(&d0(p[b])))
        .expect("n >= 4");
    let mut keep = vec![false; n + 1];
    keep[0] = true;
    keep[far] = true;
    keep[n] = true;
    // Index n stands for vertex 0 again, closing the loop.
    let at = |k: usize| p[k % n];
    let mut stack = vec![(0, far), (far, n)];
    while let Some((a, b)) = stack.pop() {
        let mut best = (0.0, 0);
        for k in a + 1..b {
            let d = seg_dist(at(k), at(a), at(b));
            if d > best.0 {
                best = (d, k);
            }
        }
        if best.0 > tol {
            keep[best.1] = true;
            stack.push((a, best.1));
            stack.push((best.1, b));
        }
    }
    (0..n).filter(|&k| keep[k]).map(|k| p[k]).collect()
}

#[cfg(test)]
mod tests {
    use super::simplify_closed;

    #[test]
    fn drops_collinear_points_and_keeps_corners() {
        let mut sq = Vec::new();
        for k in 0..10 {
            sq.push([k as f64 * 0.1, 0.0]);
        }
        for k in 0..10 {
            sq.push([1.0, k as f64 * 0.1]);
        }
        for k in 0..10 {
            sq.push([1.0 - k as f64 * 0.1, 1.0]);
        }
        for k in 0..10 {
            sq.push([0.0, 1.0 - k as f64 * 0.1]);
        }
        let s = simplify_closed(&sq, 1e-9);
        assert_eq!(s, vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
    }

    #[test]
    fn every_input_vertex_stays_within_tolerance() {
        let circle: Vec<[f64; 2]> = (0..200)
            .map(|k| {
                let a = k as f64 * std::f64::consts::TAU / 200.0;
                [a.cos(), a.sin()]
            })
            .collect();
        let tol = 1e-3;
        let s = simplify_closed(&circle, tol);
        assert!(s.len() < 100 && s.len() > 10, "{} vertices", s.len());
        // Every input vertex lies within the tolerance of the result.
        for p in &circle {
            let d = (0..s.len())
                .map(|k| super::seg_dist(*p, s[k], s[(k + 1) % s.len()]))
                .fold(f64::INFINITY, f64::min);
            assert!(d <= tol, "vertex {p:?} at {d}");
        }
    }
}
