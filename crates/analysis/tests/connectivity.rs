//! Connected components, closed cavities, percolation and Euler
//! characteristic on voxelised models with known topology.

use microfrep_analysis::connectivity::{connectivity, Connectivity};
use microfrep_analysis::{Grid, Sampler};
use microfrep_core::frep::{subtraction, union};
use microfrep_core::{Expr, Shape};
use microfrep_shapes::{sphere, torus, v3};
use microfrep_structures::lattice::{rod_lattice, Slabs};

fn run(e: &Expr, region: Option<&Expr>, bounds: [[f64; 3]; 2], n: usize) -> Connectivity {
    let t = Shape::from(e);
    let r = region.map(Shape::from);
    let s = Sampler::new(&t, r.as_ref(), Grid::new(bounds, n).unwrap());
    connectivity(&s, &|_, _| {}).unwrap()
}

const BOX: [[f64; 3]; 2] = [[-1.2; 3], [1.2; 3]];

#[test]
fn sphere_is_one_component_with_euler_two() {
    let p = Expr::xyz();
    let c = run(&sphere(&p, &v3([0.0; 3]), 1.0), None, BOX, 64);
    assert_eq!(c.solid_components, 1);
    assert_eq!(c.euler, 1);
    assert_eq!(c.surface_euler(), 2);
    assert_eq!(c.pore_components, 1);
    assert_eq!(c.closed_pores, 0);
    assert_eq!(c.open_pore_fraction(), 1.0);
    // Pore space wraps around the ball: it touches every face pair.
    assert_eq!(c.percolates, [true; 3]);
}

#[test]
fn torus_has_euler_zero() {
    let p = Expr::xyz();
    let c = run(&torus(&p, &v3([0.0; 3]), 2, 0.7, 0.25), None, BOX, 96);
    assert_eq!(c.solid_components, 1);
    assert_eq!(c.euler, 0);
    assert_eq!(c.surface_euler(), 0);
}

#[test]
fn two_disjoint_spheres_are_two_components() {
    let p = Expr::xyz();
    let a = sphere(&p, &v3([-0.6, 0.0, 0.0]), 0.4);
    let b = sphere(&p, &v3([0.6, 0.0, 0.0]), 0.3);
    let c = run(&union(&a, &b, 1.0), None, BOX, 64);
    assert_eq!(c.solid_components, 2);
    assert_eq!(c.euler, 2);
    // Volumes largest first, near 4/3 pi r^3.
    let v = |r: f64| 4.0 / 3.0 * std::f64::consts::PI * r * r * r;
    assert!(
        (c.solid_volumes[0] / v(0.4) - 1.0).abs() < 0.03,
        "{:?}",
        c.solid_volumes
    );
    assert!(
        (c.solid_volumes[1] / v(0.3) - 1.0).abs() < 0.03,
        "{:?}",
        c.solid_volumes
    );
}

#[test]
fn closed_cavity_is_a_pore_cut_off_from_outside() {
    let p = Expr::xyz();
    let shell = subtraction(
        &sphere(&p, &v3([0.0; 3]), 1.0),
        &sphere(&p, &v3([0.0; 3]), 0.5),
        1.0,
    );
    let c = run(&shell, None, BOX, 64);
    assert_eq!(c.solid_components, 1);
    assert_eq!(c.pore_components, 2);
    assert_eq!(c.closed_pores, 1);
    let cavity = 4.0 / 3.0 * std::f64::consts::PI * 0.125;
    assert!((c.closed_pore_volume / cavity - 1.0).abs() < 0.05);
    assert!(c.open_pore_fraction() < 1.0);
    // A hollow ball: two boundary spheres.
    assert_eq!(c.euler, 2);
    assert_eq!(c.surface_euler(), 4);
}

#[test]
fn cavity_inside_a_region_counts_as_closed_and_region_edge_as_open() {
    // Porosity measured inside a part: the region is a ball, the model a
    // solid ball with a cavity and a channel to the region's surface.
    let p = Expr::xyz();
    let region = sphere(&p, &v3([0.0; 3]), 1.0);
    let cavity = sphere(&p, &v3([0.0; 3]), 0.3);
    let channel = microfrep_shapes::cylinder(&p, &v3([0.0; 3]), 0, 0.15);
    let tunnel = microfrep_core::frep::intersection(&channel, &(&p[0] - 0.5), 1.0);
    let solid = subtraction(&subtraction(&region, &cavity, 1.0), &tunnel, 1.0);
    let c = run(&solid, Some(&region), BOX, 64);
    // The cavity is closed, the tunnel reaches the region's boundary.
    assert_eq!(c.pore_components, 2);
    assert_eq!(c.closed_pores, 1);
    assert!(c.open_pore_volume > 0.0);
    assert!(!c.percolates.iter().any(|&b| b));
}

#[test]
fn rod_lattice_pores_percolate_on_all_axes() {
    let p = Expr::xyz();
    let pi = std::f64::consts::PI;
    let lat = rod_lattice(&p, &Slabs::uniform(2.0 * pi, 0.3), 1.0);
    let c = run(&lat, None, [[0.0; 3], [2.0; 3]], 64);
    assert_eq!(c.percolates, [true; 3]);
    assert_eq!(c.pore_components, 1);
    assert_eq!(c.solid_components, 1);
    // Rods around x, y, z = 1/4 and 5/4: a thickened grid graph of 8 nodes
    // and 12 edges (rod ends at the faces do not count): V - E = -4.
    assert_eq!(c.euler, -4);
}

/// Percolation inside a region is judged between the region's own first
/// and last voxel layers: a cube of interconnected pores percolates on
/// every axis whether the analysis box is the cube or padded around it;
/// pores sealed by a skin do not.
#[test]
fn percolation_in_a_region_is_the_same_for_a_padded_and_an_exact_box() {
    let p = Expr::xyz();
    let pi = std::f64::consts::PI;
    let lat = rod_lattice(&p, &Slabs::uniform(2.0 * pi, 0.3), 1.0);
    // The region: the cube [0, 2]^3.
    let cube = microfrep_shapes::block(&p, &v3([0.0; 3]), &v3([2.0; 3]));
    let exact = run(&lat, Some(&cube), [[0.0; 3], [2.0; 3]], 64);
    for pad in [0.2f64, 0.37] {
        let b = [[-pad; 3], [2.0 + pad; 3]];
        let n = (64.0 * (2.0 + 2.0 * pad) / 2.0).round() as usize;
        let padded = run(&lat, Some(&cube), b, n);
        assert_eq!(padded.percolates, [true; 3], "pad {pad}");
        assert_eq!(padded.percolates, exact.percolates, "pad {pad}");
    }
    assert_eq!(exact.percolates, [true; 3]);
    // A solid skin around the pores: still percolating inside the region
    // only where a pore runs end to end, which a skin stops (the region's
    // extreme layers are solid).
    let inner = microfrep_shapes::block(&p, &v3([0.1; 3]), &v3([1.8; 3]));
    let skinned = union(&subtraction(&cube, &inner, 1.0), &lat, 1.0);
    let c = run(&skinned, Some(&cube), [[-0.2; 3], [2.2; 3]], 77);
    assert_eq!(c.percolates, [false; 3]);
    assert_eq!(c.closed_pores, 1);
}
