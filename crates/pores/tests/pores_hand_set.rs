//! The paper's hand-set derived points: in 2D three distances (Eq. 8 gives
//! the fourth), in 3D the 24 t values (their shape, scaled to the
//! porosity). Every pore keeps what was set, meets its porosity (by its own
//! measure and by an independent voxel count), and bad values are refused
//! by name.

mod pores_common;
use microfrep_pores::{HandSet, Options, PoreError, PoreShape, Pores, Spec, Subdivision};
use pores_common::{block, measure, unit_cells};

const BOX: [[f64; 3]; 2] = [[0.0; 3], [3.0, 3.0, 3.0]];
/// The 2D pores' slab (extruded along z).
const SLAB: [[f64; 3]; 2] = [[0.0; 3], [3.0, 3.0, 1.0]];

fn options(hand: HandSet, two_d: bool) -> Options {
    let base = if two_d {
        Options::two_d()
    } else {
        Options::default()
    };
    Options {
        subdivision: Subdivision::TMesh { percent: 0.5 },
        split_rule: Some(unit_cells()),
        hand_set: Some(hand),
        ..base
    }
}

#[test]
fn hand_set_distances_are_kept_and_eq8_meets_the_porosity() {
    let part = block(SLAB[0], SLAB[1]);
    let r = [0.2, 0.15, 0.25];
    let built = Pores::build(
        &part,
        SLAB,
        Spec::Constant(1.0),
        Spec::Constant(0.6),
        1,
        &options(HandSet::Distances(r), true),
    )
    .unwrap();
    assert_eq!(built.pores, 9);
    for c in &built.cells {
        let PoreShape::Two { r: got, .. } = c.shape else {
            panic!("{c:?}");
        };
        assert_eq!(&got[..3], &r, "{c:?}");
        assert!((c.porosity - 0.6).abs() < 1e-9, "{c:?}");
    }
    let m = measure(&built, &part, SLAB, 192, false);
    assert!(
        (m.porosity() - 0.6).abs() < 0.002 + m.volume_fraction_error(),
        "{}",
        m.porosity()
    );
    // A fourth distance outside [0, 1]: refused, naming the cell.
    let e = Pores::build(
        &part,
        SLAB,
        Spec::Constant(1.0),
        Spec::Constant(0.05),
        1,
        &options(HandSet::Distances([0.95, 0.95, 0.95]), true),
    )
    .err()
    .expect("refused");
    assert!(matches!(e, PoreError::Pore { .. }), "{e}");
    let e = Pores::build(
        &part,
        SLAB,
        Spec::Constant(1.0),
        Spec::Constant(0.5),
        1,
        &options(HandSet::Distances([0.3, 1.2, 0.5]), true),
    )
    .err()
    .expect("refused");
    assert!(e.to_string().contains("distances"), "{e}");
}

#[test]
fn hand_set_t_fix_the_shape_scaled_to_the_porosity() {
    let part = block(BOX[0], BOX[1]);
    let t: [[f64; 3]; 8] =
        std::array::from_fn(|s| std::array::from_fn(|k| 0.35 + 0.04 * ((s + 2 * k) % 4) as f64));
    for target in [0.55, 0.75] {
        let built = Pores::build(
            &part,
            BOX,
            Spec::Constant(1.0),
            Spec::Constant(target),
            1,
            &options(HandSet::T(t), false),
        )
        .unwrap();
        assert_eq!(built.pores, 27);
        for c in &built.cells {
            let PoreShape::Three { t: got, .. } = c.shape else {
                panic!("{c:?}");
            };
            // Eq. 9: vertex positions kappa (1 - t/2); the same shape up to
            // scale means one ratio for all 24.
            let ratio: Vec<f64> = (0..24)
                .map(|i| (1.0 - 0.5 * got[i / 3][i % 3]) / (1.0 - 0.5 * t[i / 3][i % 3]))
                .collect();
            let spread = ratio
                .iter()
                .fold(0.0f64, |m, r| m.max((r - ratio[0]).abs()));
            assert!(spread < 1e-9, "{target}: ratios {ratio:?}");
            assert!((c.porosity - target).abs() < 1e-9, "{c:?}");
        }
        let m = measure(&built, &part, BOX, 96, false);
        assert!(
            (m.porosity() - target).abs() < 0.004 + m.volume_fraction_error(),
            "{target}: {}",
            m.porosity()
        );
    }
    let mut bad = t;
    bad[3][1] = 1.5;
    let e = Pores::build(
        &part,
        BOX,
        Spec::Constant(1.0),
        Spec::Constant(0.6),
        1,
        &options(HandSet::T(bad), false),
    )
    .err()
    .expect("refused");
    assert!(e.to_string().contains("t"), "{e}");
    // Distances for a 3D build: refused.
    let e = Pores::build(
        &part,
        BOX,
        Spec::Constant(1.0),
        Spec::Constant(0.6),
        1,
        &options(HandSet::Distances([0.3, 0.3, 0.3]), false),
    )
    .err()
    .expect("refused");
    assert!(e.to_string().contains("hand"), "{e}");
}
