//! The pore structure as a Field: all four modes, determinism, and errors.

use microfrep_core::field_check::{check_field, FieldCheck};
use microfrep_core::{Expr, Field};
use microfrep_pores::{Dim, Options, PoreError, Pores, Spec, Subdivision};
use microfrep_shapes as prims;
use std::sync::Arc;

fn ball() -> Expr {
    prims::sphere(&Expr::xyz(), &prims::v3([0.0; 3]), 1.0)
}

fn graded_size() -> Spec {
    // Smaller cells towards +x.
    Spec::Fn(Arc::new(|p: [f64; 3]| 0.35 - 0.12 * p[0].clamp(-1.0, 1.0)))
}

#[test]
fn three_d_field_passes_the_four_mode_check() {
    for sub in [Subdivision::Tree, Subdivision::TMesh { percent: 0.5 }] {
        let b = Pores::build(
            &ball(),
            [[-1.0; 3], [1.0; 3]],
            graded_size(),
            Spec::Constant(0.75),
            3,
            &Options {
                subdivision: sub,
                ..Options::default()
            },
        )
        .unwrap();
        assert!(b.pores > 50, "{}", b.pores);
        let f: Arc<dyn Field> = b.field.clone();
        let r = check_field(&f, &FieldCheck::new([[-1.2; 3], [1.2; 3]])).unwrap();
        assert!(r.points == 2000 && r.boxes == 300, "{r:?}");
        // Most points are smooth (kinks only where two terms meet).
        assert!(r.not_smooth < r.points / 10, "{r:?}");
    }
}

#[test]
fn two_d_field_passes_the_four_mode_check() {
    for kappa in [1.0, 1.2] {
        let b = Pores::build(
            &ball(),
            [[-1.0; 3], [1.0; 3]],
            graded_size(),
            Spec::Constant(0.6),
            3,
            &Options {
                parent_scale: Some(kappa),
                ..Options::two_d()
            },
        )
        .unwrap();
        let f: Arc<dyn Field> = b.field.clone();
        let r = check_field(&f, &FieldCheck::new([[-1.2; 3], [1.2; 3]])).unwrap();
        assert!(r.not_smooth < r.points / 10, "{r:?}");
        // Extruded: independent of z.
        for p in [[0.1, 0.2], [-0.33, 0.7], [0.5, -0.05]] {
            assert_eq!(f.eval([p[0], p[1], -3.0]), f.eval([p[0], p[1], 0.4]));
        }
    }
}

#[test]
fn same_seed_same_values_other_seed_other_pores() {
    let build = |seed| {
        Pores::build(
            &ball(),
            [[-1.0; 3], [1.0; 3]],
            Spec::Constant(0.4),
            Spec::Constant(0.7),
            seed,
            &Options::default(),
        )
        .unwrap()
    };
    let (a, b, c) = (build(1), build(1), build(2));
    let pts: Vec<[f64; 3]> = (0..500)
        .map(|i| {
            let t = i as f64;
            [
                (t * 0.618).fract() * 2.0 - 1.0,
                (t * 0.414).fract() * 2.0 - 1.0,
                (t * 0.732).fract() * 2.0 - 1.0,
            ]
        })
        .collect();
    let va: Vec<u64> = pts.iter().map(|&p| a.field.eval(p).to_bits()).collect();
    let vb: Vec<u64> = pts.iter().map(|&p| b.field.eval(p).to_bits()).collect();
    let vc: Vec<u64> = pts.iter().map(|&p| c.field.eval(p).to_bits()).collect();
    assert_eq!(va, vb);
    assert!(va.iter().zip(&vc).filter(|(x, y)| x != y).count() > 250);
}

#[test]
fn thread_count_does_not_change_the_structure() {
    let build = || {
        Pores::build(
            &ball(),
            [[-1.0; 3], [1.0; 3]],
            graded_size(),
            Spec::Constant(0.7),
            9,
            &Options::default(),
        )
        .unwrap()
    };
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(build);
    let many = rayon::ThreadPoolBuilder::new()
        .num_threads(4)
        .build()
        .unwrap()
        .install(build);
    assert_eq!(one.field.name(), many.field.name());
    for i in 0..2000 {
        let t = i as f64;
        let p = [
            (t * 0.618).fract() * 2.4 - 1.2,
            (t * 0.414).fract() * 2.4 - 1.2,
            (t * 0.732).fract() * 2.4 - 1.2,
        ];
        assert_eq!(one.field.eval(p).to_bits(), many.field.eval(p).to_bits());
    }
}

#[test]
fn bad_inputs_are_clear_errors() {
    let part = ball();
    let bounds = [[-1.0; 3], [1.0; 3]];
    let o = Options::default();
    let e = Pores::build(
        &part,
        bounds,
        Spec::Constant(0.4),
        Spec::Constant(0.2),
        0,
        &o,
    )
    .unwrap_err();
    match e {
        PoreError::PorosityRange {
            min, max, dim: 3, ..
        } => {
            assert!(
                min > 0.3 && min < 0.35 && max > 0.98 && max < 0.995,
                "{min} {max}"
            )
        }
        e => panic!("{e}"),
    }
    let msg = Pores::build(
        &part,
        bounds,
        Spec::Constant(0.4),
        Spec::Constant(0.9),
        0,
        &Options::two_d(),
    )
    .unwrap_err()
    .to_string();
    assert!(
        msg.contains("0.8333") && msg.contains("parent scale"),
        "{msg}"
    );
    assert!(matches!(
        Pores::build(
            &part,
            bounds,
            Spec::Constant(-1.0),
            Spec::Constant(0.7),
            0,
            &o
        ),
        Err(PoreError::Size { .. })
    ));
    assert!(matches!(
        Pores::build(
            &part,
            bounds,
            Spec::Constant(f64::NAN),
            Spec::Constant(0.7),
            0,
            &o
        ),
        Err(PoreError::Size { .. })
    ));
    assert!(matches!(
        Pores::build(
            &part,
            bounds,
            Spec::Constant(0.4),
            Spec::Constant(f64::NAN),
            0,
            &o
        ),
        Err(PoreError::PorosityNotFinite { .. })
    ));
    assert!(matches!(
        Pores::build(
            &part,
            [[0.0; 3], [0.0; 3]],
            Spec::Constant(0.4),
            Spec::Constant(0.7),
            0,
            &o
        ),
        Err(PoreError::Bounds { .. })
    ));
    assert!(matches!(
        Pores::build(
            &part,
            bounds,
            Spec::Constant(1e-4),
            Spec::Constant(0.7),
            0,
            &o
        ),
        Err(PoreError::TooManyCells { .. })
    ));
    assert!(matches!(
        Pores::build(
            &part,
            bounds,
            Spec::Constant(0.1),
            Spec::Constant(0.7),
            0,
            &Options {
                memory_limit: 1 << 20,
                ..Options::default()
            }
        ),
        Err(PoreError::Memory { .. })
    ));
    let far = prims::sphere(&Expr::xyz(), &prims::v3([10.0; 3]), 1.0);
    assert!(matches!(
        Pores::build(
            &far,
            bounds,
            Spec::Constant(0.4),
            Spec::Constant(0.7),
            0,
            &o
        ),
        Err(PoreError::EmptyPart { .. })
    ));
    for (name, o) in [
        (
            "irregularity",
            Options {
                irregularity: 0.7,
                ..Options::default()
            },
        ),
        (
            "parent_scale",
            Options {
                parent_scale: Some(1.2),
                ..Options::default()
            },
        ),
        (
            "parent_scale",
            Options {
                parent_scale: Some(1.5),
                ..Options::two_d()
            },
        ),
        (
            "T-mesh percent",
            Options {
                subdivision: Subdivision::TMesh { percent: 1.0 },
                ..Options::default()
            },
        ),
    ] {
        match Pores::build(
            &part,
            bounds,
            Spec::Constant(0.4),
            Spec::Constant(0.7),
            0,
            &o,
        ) {
            Err(PoreError::Option { name: n, .. }) => assert_eq!(n, name),
            r => panic!("{name}: {:?}", r.map(|b| b.pores)),
        }
    }
    let _ = Dim::Two;
}

/// The f32 batch on the blocks a slicer or mesher hands it (coherent
/// points: a 16 x 16 tile of pixels, a row across many cells, a small
/// cube of voxels) and on scattered points (more leaves in one block than
/// the batch groups, which take the scalar path), against the f64 point
/// values. Both the own-cell path and the neighbour passes are hit: the
/// values span pores, walls and the cap.
#[test]
fn batch_on_coherent_blocks_matches_the_point_values() {
    for sub in [Subdivision::Tree, Subdivision::TMesh { percent: 0.5 }] {
        let b = Pores::build(
            &ball(),
            [[-1.0; 3], [1.0; 3]],
            graded_size(),
            Spec::Constant(0.75),
            5,
            &Options {
                subdivision: sub,
                ..Options::default()
            },
        )
        .unwrap();
        let f = &b.field;
        let cap = f.cap();
        let mut blocks: Vec<Vec<[f32; 3]>> = Vec::new();
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut unit = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..400 {
            let o = [0.0; 3].map(|_: f64| -1.1 + 2.2 * unit());
            let px = 0.004 + 0.02 * unit();
            // A tile of 16 x 16 pixels at one height.
            blocks.push(
                (0..256)
                    .map(|q| {
                        let (i, j) = ((q % 16) as f64, (q / 16) as f64);
                        [(o[0] + i * px) as f32, (o[1] + j * px) as f32, o[2] as f32]
                    })
                    .collect(),
            );
            // A cube of 6^3 voxels.
            blocks.push(
                (0..216)
                    .map(|q| {
                        let ijk = [q % 6, (q / 6) % 6, q / 36];
                        std::array::from_fn(|a| (o[a] + ijk[a] as f64 * px) as f32)
                    })
                    .collect(),
            );
        }
        for k in 0..20 {
            let (yv, zv) = (-1.0 + 0.1 * k as f64, 0.35 - 0.03 * k as f64);
            blocks.push(
                (0..256)
                    .map(|i| {
                        [
                            (-1.15 + 2.3 * i as f64 / 255.0) as f32,
                            yv as f32,
                            zv as f32,
                        ]
                    })
                    .collect(),
            );
        }
        for _ in 0..8 {
            blocks.push(
                (0..256)
                    .map(|_| [0; 3].map(|_| (-1.2 + 2.4 * unit()) as f32))
                    .collect(),
            );
        }
        let (mut pore, mut wall, mut capped, mut worst) = (0, 0, 0, 0.0f64);
        for pts in &blocks {
            let xs: Vec<f32> = pts.iter().map(|p| p[0]).collect();
            let ys: Vec<f32> = pts.iter().map(|p| p[1]).collect();
            let zs: Vec<f32> = pts.iter().map(|p| p[2]).collect();
            let mut out = vec![0.0f32; pts.len()];
            f.eval_batch(&xs, &ys, &zs, &mut out);
            for (p, &v) in pts.iter().zip(&out) {
                let e = f.eval(p.map(|c| c as f64));
                let err = (v as f64 - e).abs();
                assert!(
                    err <= 2e-6 * (1.0 + e.abs()),
                    "batch {v} vs point {e} at {p:?}"
                );
                worst = worst.max(err);
                if e < 0.0 {
                    pore += 1;
                } else if e < cap {
                    wall += 1;
                } else {
                    capped += 1;
                }
            }
        }
        let total = pore + wall + capped;
        assert!(
            pore > total / 5 && wall > total / 20,
            "{pore} {wall} {capped}"
        );
        assert!(worst < 2e-6, "{worst}");
    }
}
