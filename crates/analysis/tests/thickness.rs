//! Local thickness: the exact distance transform and the Hildebrand local
//! thickness against brute force on random grids, slab processing against
//! the one-window result, and closed forms (plate, cylinder, square-rod
//! lattice) through the sampler.

use microfrep_analysis::grid::{Grid, Sampler, PORE, SOLID};
use microfrep_analysis::thickness::edt::{edt_squared, INF};
use microfrep_analysis::thickness::{
    local_thickness_field, thickness, thickness_of_labels, PhaseThickness, Thickness,
    ThicknessOptions,
};
use microfrep_analysis::AnalysisError;
use microfrep_core::{Expr, Shape};
use microfrep_shapes::{cylinder, v3};
use microfrep_structures::lattice::{rod_lattice, Slabs};

/// Small deterministic generator (xorshift64*).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
}

fn random_grid(rng: &mut Rng) -> ([usize; 3], Vec<u8>) {
    let dims = [0; 3].map(|_| 1 + rng.below(9) as usize);
    let fill = rng.below(101);
    let n = dims.iter().product();
    let labels = (0..n)
        .map(|_| if rng.below(100) < fill { SOLID } else { PORE })
        .collect();
    (dims, labels)
}

fn coords(i: usize, dims: [usize; 3]) -> [i64; 3] {
    [
        (i % dims[0]) as i64,
        (i / dims[0] % dims[1]) as i64,
        (i / (dims[0] * dims[1])) as i64,
    ]
}

fn dist2(a: [i64; 3], b: [i64; 3]) -> i64 {
    (0..3).map(|k| (a[k] - b[k]).pow(2)).sum()
}

fn brute_edt(labels: &[u8], dims: [usize; 3], phase: u8) -> Vec<u32> {
    (0..labels.len())
        .map(|i| {
            if labels[i] != phase {
                return 0;
            }
            (0..labels.len())
                .filter(|&j| labels[j] != phase)
                .map(|j| dist2(coords(i, dims), coords(j, dims)) as u32)
                .min()
                .unwrap_or(INF)
        })
        .collect()
}

#[test]
fn edt_matches_brute_force_on_random_grids() {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    for case in 0..400 {
        let (dims, labels) = random_grid(&mut rng);
        for phase in [SOLID, PORE] {
            let fast = edt_squared(&labels, dims, |l| l == phase);
            assert_eq!(
                fast,
                brute_edt(&labels, dims, phase),
                "case {case} dims {dims:?}"
            );
        }
    }
}

/// Hildebrand's definition verbatim: the largest ball `|p - c|^2 < D(c)`
/// over all centres that contains `p`, as a diameter in voxels.
fn brute_local_thickness(labels: &[u8], dims: [usize; 3], phase: u8) -> Vec<f32> {
    let d = brute_edt(labels, dims, phase);
    if d.contains(&INF) {
        return d
            .iter()
            .map(|&v| if v > 0 { f32::INFINITY } else { 0.0 })
            .collect();
    }
    (0..labels.len())
        .map(|p| {
            let best = (0..labels.len())
                .filter(|&c| dist2(coords(p, dims), coords(c, dims)) < d[c] as i64)
                .map(|c| d[c])
                .max()
                .unwrap_or(0);
            2.0 * (best as f32).sqrt()
        })
        .collect()
}

#[test]
fn local_thickness_matches_definition_on_random_grids() {
    let mut rng = Rng(0x1234_5678_9abc_def1);
    for case in 0..300 {
        let (dims, labels) = random_grid(&mut rng);
        for phase in [SOLID, PORE] {
            let fast = local_thickness_field(&labels, dims, phase).unwrap();
            assert_eq!(
                fast,
                brute_local_thickness(&labels, dims, phase),
                "case {case} dims {dims:?} phase {phase}"
            );
        }
    }
}

#[test]
fn local_thickness_matches_definition_on_a_blob_grid() {
    // Larger than the random grids (several tiles of rows and 64-bit
    // words per row): overlapping balls, both phases, brute force.
    let dims = [70, 19, 9];
    let mut rng = Rng(7);
    let balls: Vec<([f64; 3], f64)> = (0..25)
        .map(|_| {
            let c = dims.map(|d| rng.below(d as u64) as f64);
            (c, 1.0 + rng.below(400) as f64 / 100.0)
        })
        .collect();
    let labels: Vec<u8> = (0..dims.iter().product())
        .map(|i| {
            let p = coords(i, dims).map(|v| v as f64);
            let inside = balls
                .iter()
                .any(|(c, r)| (0..3).map(|k| (p[k] - c[k]).powi(2)).sum::<f64>() < r * r);
            if inside {
                SOLID
            } else {
                PORE
            }
        })
        .collect();
    for phase in [SOLID, PORE] {
        assert_eq!(
            local_thickness_field(&labels, dims, phase).unwrap(),
            brute_local_thickness(&labels, dims, phase),
            "phase {phase}"
        );
    }
}

/// Solid balls of radius 1.5..4 voxels at random in a 32 x 32 x 64 grid,
/// plus walls every 12 voxels so the pores stay small too.
fn small_features() -> ([usize; 3], Vec<u8>) {
    let dims = [32, 32, 64];
    let mut rng = Rng(42);
    let balls: Vec<([f64; 3], f64)> = (0..120)
        .map(|_| {
            let c = dims.map(|d| rng.below(d as u64) as f64);
            (c, 1.5 + rng.below(250) as f64 / 100.0)
        })
        .collect();
    let n = dims.iter().product();
    let labels = (0..n)
        .map(|i| {
            let p = coords(i, dims).map(|v| v as f64);
            let wall = p.iter().any(|&v| v as i64 % 12 == 0);
            let ball = balls
                .iter()
                .any(|(c, r)| (0..3).map(|k| (p[k] - c[k]).powi(2)).sum::<f64>() < r * r);
            if wall || ball {
                SOLID
            } else {
                PORE
            }
        })
        .collect();
    (dims, labels)
}

fn stats_of(t: &PhaseThickness) -> &microfrep_analysis::thickness::ThicknessStats {
    t.stats().expect("measured phase")
}

#[test]
fn slabs_agree_with_one_window_when_features_fit_the_halo() {
    let (dims, labels) = small_features();
    let exact = thickness_of_labels(&labels, dims, 0.1, &ThicknessOptions::default()).unwrap();
    assert_eq!(exact.slabs, 1);
    assert_eq!(exact.diameter_cap, None);
    // 32 x 32 layers: 88 bytes per layer voxel and halo voxel, so halo 8.
    let opts = ThicknessOptions {
        memory_limit: 8 * 88 * 32 * 32,
        ..Default::default()
    };
    let slabbed = thickness_of_labels(&labels, dims, 0.1, &opts).unwrap();
    assert!(slabbed.slabs > 1, "{} slabs", slabbed.slabs);
    let cap = slabbed.diameter_cap.unwrap();
    assert!((cap - 1.6).abs() < 1e-12);
    for (a, b) in [(&exact.solid, &slabbed.solid), (&exact.pore, &slabbed.pore)] {
        let (a, b) = (stats_of(a), stats_of(b));
        assert!(a.max < cap, "features must fit the halo: max {}", a.max);
        assert_eq!(a, b);
    }
}

#[test]
fn too_large_layers_are_refused() {
    let dims = [4000, 4000, 2];
    let labels = vec![PORE; 4000 * 4000 * 2];
    let opts = ThicknessOptions {
        memory_limit: 64 << 20,
        ..Default::default()
    };
    match thickness_of_labels(&labels, dims, 1.0, &opts) {
        Err(AnalysisError::Memory(m)) => assert!(m.contains("4000 x 4000"), "{m}"),
        other => panic!("expected a memory error, got {other:?}"),
    }
}

#[test]
fn a_phase_filling_the_grid_is_unbounded_and_its_complement_empty() {
    let labels = vec![SOLID; 5 * 6 * 7];
    let t = thickness_of_labels(&labels, [5, 6, 7], 1.0, &ThicknessOptions::default()).unwrap();
    assert_eq!(t.solid, PhaseThickness::Unbounded { voxels: 210 });
    assert_eq!(t.pore, PhaseThickness::Empty);
}

/// The solid's thickness only (the pore space around a convex solid, open
/// at the bounds, has no use here and is the slow case).
fn sampled(model: &Expr, resolution: usize) -> Thickness {
    let opts = ThicknessOptions {
        measure_pore: false,
        ..Default::default()
    };
    sampled_in(model, [[-1.0; 3], [1.0; 3]], resolution, &opts)
}

fn sampled_in(
    model: &Expr,
    bounds: [[f64; 3]; 2],
    resolution: usize,
    opts: &ThicknessOptions,
) -> Thickness {
    let tape = Shape::from(model);
    let grid = Grid::new(bounds, resolution).unwrap();
    let sampler = Sampler::new(&tape, None, grid);
    let last = std::sync::Mutex::new((0, 0, 0));
    let t = thickness(&sampler, opts, &|done, total| {
        let mut l = last.lock().unwrap();
        assert!(
            done <= total && done >= l.0,
            "progress {done}/{total} after {}",
            l.0
        );
        *l = (done, total, l.2 + 1);
    })
    .unwrap();
    let (done, total, calls) = *last.lock().unwrap();
    assert!(
        calls > 1 && done == total,
        "progress ended at {done}/{total}"
    );
    t
}

#[test]
fn plate_thickness_is_its_width() {
    // Plate |z| <= t/2 across the box: every solid voxel's ball spans the
    // plate, so the whole distribution sits at t (within one voxel).
    let t = 0.3;
    let z = &Expr::xyz()[2];
    let plate = Expr::constant(t / 2.0) - z.abs();
    let r = sampled(&plate, 64);
    let h = r.voxel;
    let s = stats_of(&r.solid);
    for v in [s.min, s.p10, s.median, s.mean, s.p90, s.max] {
        assert!((v - t).abs() <= h, "{v} vs {t} (voxel {h})");
    }
    assert_eq!(s.voxels, 64 * 64 * 10);
    assert_eq!(r.pore, PhaseThickness::Skipped);
}

#[test]
fn cylinder_thickness_is_its_diameter() {
    // Cylinders along z: local thickness 2r everywhere in the continuous
    // solid. On the grid balls are centred on voxel centres: with the axis
    // through a voxel centre the distribution (p10 up) is within one voxel
    // of 2r; with the axis between voxel centres (on a voxel corner) the
    // best centre is 0.7 voxel off the axis and the reading may be low by up
    // to 1.5 voxels.
    let h = 2.0 / 96.0;
    for r0 in [0.15, 0.3, 0.45] {
        for (axis, tol) in [(0.5 * h, 1.0), (0.0, 1.5)] {
            let c = cylinder(&Expr::xyz(), &v3([axis, axis, 0.0]), 2, r0);
            let r = sampled(&c, 96);
            assert!((r.voxel - h).abs() < 1e-12);
            let s = stats_of(&r.solid);
            for v in [s.p10, s.median, s.mean, s.p90, s.max] {
                assert!(
                    (v - 2.0 * r0).abs() <= tol * h,
                    "r {r0} axis {axis}: {v} vs {} (voxel {h}): {s:?}",
                    2.0 * r0
                );
            }
        }
    }
}

#[test]
fn square_rod_lattice_pore_and_strut_sizes_match_closed_forms() {
    // Rods of square section w along x, y and z, period p (alpha = 1, so
    // min/max joins: exact squares). Rods sit on the edges of cubic
    // cavities of side a = p - w, whose faces are open windows (a x a) into
    // the next cavities. The largest ball in the pore space is centred in a
    // cavity and touches its 12 edge rods: the distance from a cube's centre
    // to its edges is a / sqrt(2), so the largest pore size is
    // sqrt(2) (p - w) (not p - w: the ball bulges through the windows).
    // Struts: away from the joints the section is a w x w square, so the
    // strut thickness is w; at a joint of three rods the largest ball reaches
    // the re-entrant edges at w / sqrt(2) from the centre: sqrt(2) w.
    // Period 0.5 (q = 4 pi), rod fraction 1/4 per axis (l = sin(pi/4)):
    // w = 0.125; at 64 voxels per unit a rod is 8 voxels wide.
    let (p, w) = (0.5, 0.125);
    let q = 4.0 * std::f64::consts::PI;
    let l = (std::f64::consts::PI / 4.0).sin();
    let lattice = rod_lattice(&Expr::xyz(), &Slabs::uniform(q, l), 1.0);
    // The box's faces pass through rod axes, so the cavities next to them
    // are closed by half rods like the others (the border is open).
    let bounds = [[-0.875; 3], [0.625; 3]];
    let r = sampled_in(&lattice, bounds, 96, &ThicknessOptions::default());
    let h = r.voxel;
    let pore = stats_of(&r.pore);
    let want_pore = 2f64.sqrt() * (p - w);
    assert!(
        (pore.max - want_pore).abs() <= h,
        "largest pore {} vs {want_pore} (voxel {h})",
        pore.max
    );
    let solid = stats_of(&r.solid);
    assert!(
        (solid.median - w).abs() <= h,
        "strut median {} vs {w}",
        solid.median
    );
    assert!(
        (solid.max - 2f64.sqrt() * w).abs() <= h,
        "joint {} vs {}",
        solid.max,
        2f64.sqrt() * w
    );
}

#[test]
fn ladder_gives_floored_lower_bounds_of_the_exact_values() {
    // The open space around a ball in a box: huge balls everywhere, the
    // case the work budget exists for. A tiny budget forces the ladder.
    let n = 40usize;
    let dims = [n; 3];
    let labels: Vec<u8> = (0..n * n * n)
        .map(|i| {
            let p = coords(i, dims).map(|v| v as f64 - 19.5);
            if p.iter().map(|v| v * v).sum::<f64>() < 64.0 {
                SOLID
            } else {
                PORE
            }
        })
        .collect();
    let run = |work: f64| {
        let opts = ThicknessOptions {
            measure_solid: false,
            work_per_voxel: work,
            ..Default::default()
        };
        let t = thickness_of_labels(&labels, dims, 1.0, &opts).unwrap();
        stats_of(&t.pore).clone()
    };
    let exact = run(f64::INFINITY);
    let ladder = run(4.0);
    assert_eq!(exact.exact_up_to, None);
    assert_eq!(exact.ladder_ratio, 1.0);
    let cut = ladder.exact_up_to.expect("ladder used");
    let q = ladder.ladder_ratio;
    assert!(cut < exact.max && q >= 1.05, "cut {cut} ratio {q}");
    assert_eq!(ladder.max, exact.max, "the top rung is the largest ball");
    assert_eq!(ladder.voxels, exact.voxels);
    for (l, e) in [
        (ladder.p10, exact.p10),
        (ladder.median, exact.median),
        (ladder.p90, exact.p90),
        (ladder.mean, exact.mean),
    ] {
        assert!(l <= e + 1e-9, "ladder {l} above exact {e}");
        assert!(
            l >= e / q - 1.0,
            "ladder {l} too far below exact {e} (ratio {q})"
        );
    }
}

#[test]
fn sampled_slabs_match_one_window_for_the_struts() {
    // The rod lattice's struts (largest ball radius about 5.7 voxels) under
    // a memory limit that gives slabs of 20 layers with a halo of 10, each
    // window sampled on its own: the same distribution as one window.
    let q = 4.0 * std::f64::consts::PI;
    let l = (std::f64::consts::PI / 4.0).sin();
    let lattice = rod_lattice(&Expr::xyz(), &Slabs::uniform(q, l), 1.0);
    let bounds = [[-0.875; 3], [0.625; 3]];
    let solid_only = |memory_limit| ThicknessOptions {
        measure_pore: false,
        memory_limit,
        ..Default::default()
    };
    let one = sampled_in(&lattice, bounds, 96, &solid_only(1 << 30));
    let slabbed = sampled_in(&lattice, bounds, 96, &solid_only(10 * 88 * 96 * 96));
    assert_eq!(one.slabs, 1);
    assert_eq!(slabbed.slabs, 5);
    assert_eq!(slabbed.diameter_cap, Some(20.0 * one.voxel));
    assert_eq!(stats_of(&one.solid), stats_of(&slabbed.solid));
    assert_eq!(slabbed.pore, PhaseThickness::Skipped);
}
