//! Shared helpers of the analysis tests.

use microfrep_analysis::{measure, Grid, Measures};
use microfrep_core::{Expr, Shape};

/// Volume and area measures of `e` in `bounds` at `n` voxels on the
/// longest side, optionally inside `region`.
pub fn measures(e: &Expr, region: Option<&Expr>, bounds: [[f64; 3]; 2], n: usize) -> Measures {
    let t = Shape::from(e);
    let r = region.map(Shape::from);
    measure(&t, r.as_ref(), &Grid::new(bounds, n).unwrap(), &|_, _| {})
}

/// Asserts `got` is within `rel` of `want`, and that the stated error
/// `err` is no smaller than a quarter of the real one (an estimate, not a
/// bound).
pub fn close(what: &str, got: f64, err: f64, want: f64, rel: f64) {
    let real = (got - want).abs();
    assert!(
        real <= rel * want.abs(),
        "{what}: {got} vs {want} (rel {:.2e})",
        real / want.abs()
    );
    assert!(
        4.0 * err >= real,
        "{what}: stated error {err:.3e} under real {real:.3e}"
    );
}
