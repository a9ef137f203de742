//! Suite `structures`: volume fractions achieved against their targets,
//! through the HyperFun `mf*` library (rod lattice closed form, TPMS levels,
//! density-driven TPMS and strut lattices on an independent sample), and the
//! cost of the density tables.

use microfrep_core::{Expr, Tape};
use microfrep_structures::sampling::Samples;
use std::time::Instant;

fn load(body: &str) -> Result<Expr, String> {
    microfrep_structures_hf::install();
    let src = format!("my_model(x[3], a[1]) {{ my_model = {body}; }}");
    let m = microfrep_hyperfun::load(&src, "bench", None).map_err(|e| e.to_string())?;
    Ok(m.value)
}

fn fraction(e: &Expr, s: &Samples) -> Result<f64, String> {
    s.fraction(&Tape::new(e), &[]).map_err(|e| e.to_string())
}

pub fn run() -> Result<(), String> {
    let err = |e: microfrep_structures::Error| e.to_string();
    // Independent of the solver's sample: a shifted cell, more points.
    let shifted = Samples::quasi_random([0.37; 3], [1.37; 3], 400_000).map_err(err)?;
    let unit = Samples::quasi_random([0.0; 3], [4.0; 3], 400_000).map_err(err)?;

    for l in [-0.5, 0.0, 0.5] {
        let g = load(&format!("mfLattice(x, 6.283185307179586, 0, {l}, 1)"))?;
        let want = microfrep_structures::lattice::rod_lattice_volume_fraction(l);
        let got = fraction(&g, &unit)?;
        println!(
            "RESULT rod_lattice l={l} target={want:.5} got={got:.5} rel_err={:.5}",
            (got - want).abs() / want
        );
    }
    for (name, want) in [
        ("mfGyroid", [0.170, 0.338, 0.5, 0.662, 0.830]),
        ("mfSchwarzP", [0.213, 0.357, 0.5, 0.643, 0.787]),
        ("mfSchwarzD", [0.081, 0.294, 0.5, 0.706, 0.919]),
    ] {
        for (t, w) in [-1.0, -0.5, 0.0, 0.5, 1.0].iter().zip(want) {
            let got = fraction(&load(&format!("{name}(x, 1, {t})"))?, &shifted)?;
            println!(
                "RESULT tpms_level {name} level={t} target={w} got={got:.4} abs_err={:.4}",
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
                let got = fraction(&e, &shifted)?;
                worst = worst.max((got - rho).abs() / rho);
                println!("RESULT tpms_density {name} sheet={sheet} target={rho} got={got:.4}");
            }
            println!(
                "RESULT tpms_table {name} sheet={sheet} solve_s={solve:.3} worst_rel_err={worst:.4}"
            );
        }
    }
    let struts = ["simple-cubic", "bcc", "fcc", "octet", "kelvin", "diamond"];
    let big = Samples::quasi_random([-0.3; 3], [1.7; 3], 400_000).map_err(err)?;
    for (k, name) in struts.iter().enumerate() {
        let t0 = Instant::now();
        load(&format!("mfStrutsDensity(x, {}, 1, 0.1)", k + 1))?;
        let solve = t0.elapsed().as_secs_f64();
        let mut worst: f64 = 0.0;
        for rho in [0.1, 0.2, 0.3, 0.5] {
            let e = load(&format!("mfStrutsDensity(x, {}, 1, {rho})", k + 1))?;
            let got = fraction(&e, &big)?;
            worst = worst.max((got - rho).abs() / rho);
            println!("RESULT strut_density {name} target={rho} got={got:.4}");
        }
        println!("RESULT strut_table {name} solve_s={solve:.3} worst_rel_err={worst:.4}");
    }
    Ok(())
}
