//! Suite `structures`: volume fractions achieved against their targets,
//! through the HyperFun `mf*` library (rod lattice closed form, TPMS levels,
//! density-driven TPMS and strut lattices), and the cost of the density
//! tables. Fractions are measured independently of the density solver by the
//! analysis crate (volume on tetrahedra with crease refinement) on a shifted
//! cell; `ref_err` is its own error estimate.

use microfrep_analysis::{measure, Grid};
use microfrep_core::Expr;
use microfrep_core::Shape;
use std::time::Instant;

fn load(body: &str) -> Result<Expr, String> {
    microfrep_structures_hf::install();
    let src = format!("my_model(x[3], a[1]) {{ my_model = {body}; }}");
    let m = microfrep_hyperfun::load(&src, "bench", None).map_err(|e| e.to_string())?;
    Ok(m.value)
}

/// Volume fraction of `e` in `[lo, hi]^3` at `res` voxels per side, and the
/// analysis' error estimate of it.
fn fraction_at(e: &Expr, lo: f64, hi: f64, res: usize) -> Result<(f64, f64), String> {
    let grid = Grid::new([[lo; 3], [hi; 3]], res).map_err(|e| e.to_string())?;
    let m = measure(&Shape::from(e), None, &grid, &|_, _| {});
    let v = grid.box_volume();
    Ok((m.volume.value / v, m.volume.error() / v))
}

/// On the shifted unit cell `[0.37, 1.37]^3`: 64 voxels a side, 128 where
/// the error estimate is above 0.01 % of the fraction.
fn fraction(e: &Expr) -> Result<(f64, f64), String> {
    let (got, err) = fraction_at(e, 0.37, 1.37, 64)?;
    if err > 1e-4 * got.abs() {
        return fraction_at(e, 0.37, 1.37, 128);
    }
    Ok((got, err))
}

pub fn run() -> Result<(), String> {
    for l in [-0.5, 0.0, 0.5] {
        let g = load(&format!("mfLattice(x, 6.283185307179586, 0, {l}, 1)"))?;
        let want = microfrep_structures::lattice::rod_lattice_volume_fraction(l);
        let (got, ref_err) = fraction_at(&g, 0.0, 4.0, 128)?;
        println!(
            "RESULT rod_lattice l={l} target={want:.5} got={got:.5} rel_err={:.5} ref_err={ref_err:.1e}",
            (got - want).abs() / want
        );
    }
    for (name, want) in [
        ("mfGyroid", [0.170, 0.338, 0.5, 0.662, 0.830]),
        ("mfSchwarzP", [0.213, 0.357, 0.5, 0.643, 0.787]),
        ("mfSchwarzD", [0.081, 0.294, 0.5, 0.706, 0.919]),
    ] {
        for (t, w) in [-1.0, -0.5, 0.0, 0.5, 1.0].iter().zip(want) {
            let (got, ref_err) = fraction(&load(&format!("{name}(x, 1, {t})"))?)?;
            println!(
                "RESULT tpms_level {name} level={t} target={w} got={got:.4} abs_err={:.4} ref_err={ref_err:.1e}",
                (got - w).abs()
            );
        }
    }
    let tpms = [
        "gyroid",
        "schwarz-p",
        "schwarz-d",
        "neovius",
        "schoen-iwp",
        "fischer-koch-s",
    ];
    for (k, name) in tpms.iter().enumerate() {
        for sheet in [0, 1] {
            let t0 = Instant::now();
            load(&format!("mfTpmsDensity(x, {}, {sheet}, 1, 0.5)", k + 1))?;
            let solve = t0.elapsed().as_secs_f64();
            let mut worst: f64 = 0.0;
            for rho in [0.1, 0.2, 0.3, 0.5] {
                let e = load(&format!("mfTpmsDensity(x, {}, {sheet}, 1, {rho})", k + 1))?;
                let (got, ref_err) = fraction(&e)?;
                worst = worst.max((got - rho).abs() / rho);
                println!(
                    "RESULT tpms_density {name} sheet={sheet} target={rho} got={got:.6} ref_err={ref_err:.1e}"
                );
            }
            println!(
                "RESULT tpms_table {name} sheet={sheet} solve_s={solve:.3} worst_rel_err={worst:.5}"
            );
        }
    }
    let struts = ["simple-cubic", "bcc", "fcc", "octet", "kelvin", "diamond"];
    for (k, name) in struts.iter().enumerate() {
        let t0 = Instant::now();
        load(&format!("mfStrutsDensity(x, {}, 1, 0.1)", k + 1))?;
        let solve = t0.elapsed().as_secs_f64();
        let mut worst: f64 = 0.0;
        for rho in [0.1, 0.2, 0.3, 0.5] {
            let e = load(&format!("mfStrutsDensity(x, {}, 1, {rho})", k + 1))?;
            let (got, ref_err) = fraction(&e)?;
            worst = worst.max((got - rho).abs() / rho);
            println!("RESULT strut_density {name} target={rho} got={got:.6} ref_err={ref_err:.1e}");
        }
        println!("RESULT strut_table {name} solve_s={solve:.3} worst_rel_err={worst:.5}");
    }
    Ok(())
}
