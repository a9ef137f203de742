//! Set operations are graph nodes with exact interval rules, so analysis
//! proves more bricks empty or full than plain interval arithmetic on the
//! same model written out as formulas, and measures the same volume.

use microfrep_analysis::{measure, Grid};
use microfrep_core::Shape;
use microfrep_structures::examples::shell_lattice;

#[test]
fn set_nodes_sample_fewer_bricks_than_the_written_out_formula() {
    let e = shell_lattice();
    let grid = Grid::new([[-1.2; 3], [1.2; 3]], 96).unwrap();
    let nodes = measure(&Shape::new(e.clone()), None, &grid, &|_, _| {});
    let plain = measure(&Shape::new(e.written_out()), None, &grid, &|_, _| {});
    assert!(
        nodes.sampled_bricks < plain.sampled_bricks,
        "{} vs {} of {}",
        nodes.sampled_bricks,
        plain.sampled_bricks,
        nodes.bricks
    );
    let (a, b) = (nodes.volume.value, plain.volume.value);
    assert!((a - b).abs() < 1e-3 * a, "{a} vs {b}");
}
