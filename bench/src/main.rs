//! Benchmark driver: `bench/run SUITE` runs one suite, which prints
//! `RESULT <case> key=value ...` lines. To add a suite: a module, an arm in
//! `main`'s match and a line in `SUITES`.

mod analyze;
mod eval;
mod hyperfun;
mod materials;
mod mesh;
mod parts;
mod pores;
mod python;
mod simplify;
mod slice;
mod structures;
mod studio;
mod threemf;
mod to_fidget;

/// Suite names and what they measure, for the usage message.
const SUITES: &[(&str, &str)] = &[
    (
        "analyze",
        "local thickness (pore, solid) of the tori-ball block at 256^3 vs PoreSpy",
    ),
    (
        "eval",
        "single-thread batch evaluation vs the fidget crate's VM and JIT",
    ),
    (
        "mesh",
        "tori-ball block meshing (128^3, 256^3) and a rotated box (sharp features) vs fidget's octree mesher, 2 threads; PLY vs STL job",
    ),
    (
        "hyperfun",
        "HyperFun models (gyroid, tori-ball) lowered vs the same expressions via the Rust API",
    ),
    (
        "structures",
        "volume fractions achieved vs targets via the mf* HyperFun library, density-table cost",
    ),
    (
        "3mf",
        "beam-lattice, slice-stack and volumetric 3MF vs STL: file sizes, write times",
    ),
    (
        "parts",
        "mesh signed distance queries/s vs libigl, 1M-triangle BVH build, peak memory",
    ),
    (
        "pores",
        "Kou-Tan bone (>1000 pores): build, mesh at 256^3, slicing vs a gyroid of the same cell",
    ),
    (
        "python",
        "Python package: Shape.eval on 10^7 points vs eval_points_par, Dask slice/analyze 1 vs 2 workers",
    ),
    (
        "studio",
        "microfrep serve: edit to first preview mesh and to refined mesh, three examples",
    ),
    (
        "simplify",
        "per-region tape simplification vs the full tape: meshing and slicing three part-with-lattice models",
    ),
    (
        "materials",
        "graded stacks (attribute grey, dithered RGBA) vs the plain slice stack, three Park examples",
    ),
    (
        "slice",
        "one 2048^2 layer vs fidget's 2D rasteriser, a 200-layer PNG stack, a 1024^2 render",
    ),
];

fn usage() -> String {
    let lines: Vec<String> = SUITES
        .iter()
        .map(|(n, d)| format!("  {n:<10} {d}"))
        .collect();
    format!("usage: bench/run SUITE\nsuites:\n{}", lines.join("\n"))
}

fn main() {
    let name = std::env::args().nth(1).unwrap_or_default();
    let result = match name.as_str() {
        "analyze" => analyze::run(),
        "eval" => eval::run(),
        "mesh" => mesh::run(),
        "parts" => parts::run(),
        "pores" => pores::run(),
        "simplify" => simplify::run(),
        "python" => python::run(),
        "slice" => slice::run(),
        "hyperfun" => hyperfun::run(),
        "materials" => materials::run(),
        "structures" => structures::run(),
        "3mf" => threemf::run(),
        "studio" => studio::run(),
        "" => Err(usage()),
        other => Err(format!("unknown suite '{other}'\n{}", usage())),
    };
    if let Err(e) = result {
        eprintln!("bench/run: {e}");
        std::process::exit(2);
    }
}
