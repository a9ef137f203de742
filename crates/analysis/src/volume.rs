//! Volume of `{f >= 0}` inside a tetrahedron for the linear interpolant of
//! the vertex values: closed forms for the 1-3 and 2-2 sign splits, from
//! the cut points of the zero set on the edges.

use crate::area::iso_polygon;

/// Fraction of the tetrahedron's volume where the linear interpolant of the
/// vertex values `f` is `>= 0` (see [`crate::area::IsoPolygon::inside_fraction`]).
pub fn tet_fraction(f: [f64; 4]) -> f64 {
    iso_polygon(f).inside_fraction()
}

/// Statistic of one measure: the value at the grid's resolution, the value
/// on the grid coarsened by two, and the error estimate from the two.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Estimate {
    /// Value at the grid's resolution.
    pub value: f64,
    /// Value from every other node (voxels twice as large).
    pub coarse: f64,
    /// The part of `value - coarse` from cells refined around creases,
    /// where the method is of first order.
    pub kink_diff: f64,
}

impl Estimate {
    /// Exact value (from cells proven full or empty).
    pub fn exact(v: f64) -> Estimate {
        Estimate {
            value: v,
            coarse: v,
            kink_diff: 0.0,
        }
    }

    /// Estimated error of `value` (Richardson): on smooth parts the method
    /// is of second order, so the error is a third of the difference to the
    /// coarse value; around creases it is of first order, so the error is
    /// the whole difference.
    pub fn error(&self) -> f64 {
        let smooth = self.value - self.coarse - self.kink_diff;
        smooth.abs() / 3.0 + self.kink_diff.abs()
    }

    pub(crate) fn add(&mut self, o: Estimate) {
        self.value += o.value;
        self.coarse += o.coarse;
        self.kink_diff += o.kink_diff;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Monte Carlo-free check: the fraction of a linear function's positive
    /// part agrees with midpoint quadrature over a fine barycentric lattice.
    fn quadrature(f: [f64; 4]) -> f64 {
        let n = 60;
        let (mut inside, mut all) = (0usize, 0usize);
        for i in 0..n {
            for j in 0..n - i {
                for k in 0..n - i - j {
                    // Sub-tet barycentric centre (one orientation suffices
                    // for this tolerance).
                    let b = [
                        (i as f64 + 0.25) / n as f64,
                        (j as f64 + 0.25) / n as f64,
                        (k as f64 + 0.25) / n as f64,
                    ];
                    let b0 = 1.0 - b[0] - b[1] - b[2];
                    let v = b0 * f[0] + b[0] * f[1] + b[1] * f[2] + b[2] * f[3];
                    inside += (v >= 0.0) as usize;
                    all += 1;
                }
            }
        }
        inside as f64 / all as f64
    }

    #[test]
    fn fractions_match_quadrature_and_complements() {
        let cases = [
            [1.0, -1.0, -2.0, -0.5],
            [1.0, 0.3, -2.0, -0.5],
            [0.2, 0.7, 0.1, -0.9],
            [0.5, -0.5, 0.5, -0.5],
        ];
        for f in cases {
            let v = tet_fraction(f);
            assert!((v - quadrature(f)).abs() < 0.03, "{f:?}: {v}");
            let neg = tet_fraction(f.map(|x| -x));
            assert!((v + neg - 1.0).abs() < 1e-12, "{f:?}");
        }
        assert_eq!(tet_fraction([1.0; 4]), 1.0);
        assert_eq!(tet_fraction([-1.0; 4]), 0.0);
        assert!((tet_fraction([1.0, -1.0, -1.0, -1.0]) - 0.125).abs() < 1e-15);
    }
}
