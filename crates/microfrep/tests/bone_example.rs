//! `examples/pasko_fig7_bone.hf` (Pasko et al. Fig. 7): the femur mesh
//! bound with `--field part=femur.stl`, with Eq. 9 pores graded by the
//! depth below its surface. A section of the shaft meshes watertight, and
//! the porosity measured in three depth bands rises with depth as designed
//! (the deepest band at the closed form of its constant pore radius).

mod common;
use microfrep::mesh::check::check;
use microfrep::mesh::{MeshOptions, Plan};
use microfrep::{load, LoadOptions};
use std::f64::consts::PI;
use std::path::PathBuf;

/// Deterministic points in a box.
fn points(lo: [f64; 3], hi: [f64; 3], n: usize) -> Vec<[f64; 3]> {
    let mut s = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..n)
        .map(|_| std::array::from_fn(|a| lo[a] + next() * (hi[a] - lo[a])))
        .collect()
}

/// The share of the periodic map's cell inside a pore of radius `r`
/// (sum of sin^2(2 pi u_i) below r^2), by sampling.
fn pore_share(r: f64) -> f64 {
    let pts = points([0.0; 3], [1.0; 3], 400_000);
    let hit = pts
        .iter()
        .filter(|u| u.iter().map(|c| (2.0 * PI * c).sin().powi(2)).sum::<f64>() < r * r)
        .count();
    hit as f64 / pts.len() as f64
}

#[test]
fn the_bone_example_is_watertight_and_its_pores_open_up_with_depth() {
    let Some(femur) = common::bone("femur.stl") else {
        return;
    };
    let model = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples/pasko_fig7_bone.hf");
    let opts = LoadOptions {
        fields: vec![("part".into(), femur.clone())],
        ..Default::default()
    };
    let m = load(model.to_str().unwrap(), &opts).unwrap();
    let part = load(&femur, &LoadOptions::default()).unwrap();
    let b = part.shape.bounds().unwrap();
    // A 60 mm section of the shaft, half way along the bone's length.
    let long = (0..3)
        .max_by(|&p, &q| (b.max[p] - b.min[p]).total_cmp(&(b.max[q] - b.min[q])))
        .unwrap();
    let mid = 0.5 * (b.min[long] + b.max[long]);
    let mut lo = b.min;
    let mut hi = b.max;
    lo[long] = mid - 30.0;
    hi[long] = mid + 30.0;

    // Porosity in depth bands: inside the bone at depth d, the share of
    // points in a pore.
    let mut model_ev = m.shape.point();
    let mut part_ev = part.shape.point();
    let mut bands = [(0u64, 0u64); 3];
    for p in points(lo, hi, 400_000) {
        let d = part_ev.eval(p);
        let band = if (0.0..2.0).contains(&d) {
            0
        } else if (3.0..6.0).contains(&d) {
            1
        } else if d >= 8.0 {
            2
        } else {
            continue;
        };
        bands[band].0 += 1;
        if model_ev.eval(p) < 0.0 {
            bands[band].1 += 1;
        }
    }
    let porosity: Vec<f64> = bands.iter().map(|&(n, p)| p as f64 / n as f64).collect();
    assert!(bands.iter().all(|&(n, _)| n > 2000), "{bands:?}");
    assert!(
        porosity[0] + 0.05 < porosity[1] && porosity[1] + 0.05 < porosity[2],
        "porosity by depth {porosity:?}"
    );
    // From 8 mm inwards the radius is the constant 1.2.
    let deep = pore_share(1.2);
    eprintln!("porosity by depth band (0-2, 3-6, 8+ mm): {porosity:?}; closed form deep: {deep}");
    assert!(
        (porosity[2] - deep).abs() < 0.03,
        "{} vs {deep}",
        porosity[2]
    );

    // The section meshes closed and manifold.
    let cells = ((hi[long] - lo[long]) / 0.5).round() as usize;
    let mesh = Plan::new(&m.shape, &MeshOptions::new([lo, hi], cells))
        .unwrap()
        .run(&|_| {})
        .unwrap();
    let r = check(&mesh);
    assert!(r.is_closed_manifold(), "{r:?}");
    assert!(r.volume > 0.0 && r.triangles > 10_000, "{r:?}");
}
