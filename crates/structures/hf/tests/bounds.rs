//! Every bounded model in examples/ gets, without --bounds, a box whose
//! sides are within 10 % of the model's true extent (the bounding box of
//! its mesh inside a box 20 % larger), found in under a second; the
//! unbounded ones (bare lattices, cells repeated over all space) get the
//! error that asks for --bounds.

mod common;

use common::{example, examples_dir};
use microfrep_mesh::{check::summary, MeshOptions, Plan};
use std::time::Instant;

/// Models whose solid fills all space periodically.
const UNBOUNDED: &[&str] = &[
    "pasko_fig2a_lattice.hf",
    "pasko_fig2b_double_frequency.hf",
    "pasko_fig2c_variable_thickness.hf",
    "pasko_fig2d_blended_rods.hf",
    "fryazinov_fig3_nonsymmetric_cell.hf",
];

/// Bounded models whose intervals cannot see their extent within the
/// search budget: a metamorphosis `f1 (1 - t) + f2 t` of two large
/// polynomials, whose solid is confined by their mix far inside the block
/// that bounds each; its box is the block (20 wide, the solid 6.5 high).
const LOOSE: &[&str] = &["fryazinov_fig8_morph_to_torus.hf"];

/// Examples of a mesh part bound with `--field` (tested with the mesh in
/// the facade's tests).
const NEEDS_FIELDS: &[&str] = &["pasko_fig7_bone.hf"];

#[test]
fn bounded_examples_get_a_tight_box_fast() {
    let mut files: Vec<String> = std::fs::read_dir(examples_dir())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".hf") && !NEEDS_FIELDS.contains(&n.as_str()))
        .collect();
    files.sort();
    let mut checked = 0;
    for f in &files {
        let m = example(f, None);
        let shape = m.shape();
        let t = Instant::now();
        let b = shape.bounds();
        let secs = t.elapsed().as_secs_f64();
        if UNBOUNDED.contains(&f.as_str()) {
            let e = b.unwrap_err().to_string();
            assert!(e.contains("--bounds"), "{f}: {e}");
            continue;
        }
        let b = b.unwrap_or_else(|e| panic!("{f}: {e}"));
        if LOOSE.contains(&f.as_str()) {
            continue;
        }
        // Generous: a release build on a 2-core machine loaded by the rest
        // of the test suite (alone, each takes 0.1 to 1 s).
        eprintln!("{f}: {secs:.2} s");
        assert!(
            secs < 5.0 || std::env::var("MF_SLOW").is_ok(),
            "{f}: {secs:.2} s"
        );
        // The true extent: the mesh's bounding box in a box 20 % larger
        // (fine enough for the thinnest lattice rods of the examples).
        let size = b.size();
        let big = [
            std::array::from_fn(|a| b.min[a] - 0.1 * size[a]),
            std::array::from_fn(|a| b.max[a] + 0.1 * size[a]),
        ];
        let mesh = Plan::new(&shape, &MeshOptions::new(big, 160))
            .unwrap()
            .run(&|_| {})
            .unwrap();
        let r = summary(&mesh);
        let worst = (0..3)
            .map(|a| size[a] / (r.bbox[1][a] - r.bbox[0][a]))
            .fold(0.0, f64::max);
        eprintln!("{f}: box / extent {worst:.4}");
        for a in 0..3 {
            let true_side = r.bbox[1][a] - r.bbox[0][a];
            // A mesh cell of slack (the mesh samples at nodes).
            let cell = 1.2 * size.iter().copied().fold(0.0, f64::max) / 160.0;
            assert!(
                size[a] <= 1.1 * true_side + 2.0 * cell && size[a] >= true_side - 2.0 * cell,
                "{f}: axis {a}: box side {} vs extent {true_side}",
                size[a]
            );
        }
        checked += 1;
    }
    assert!(checked >= 25, "{checked}");
}
