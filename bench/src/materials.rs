//! Suite `materials`: the cost of graded output against the plain binary
//! slice stack of the same model and grid, 2 threads. For three graded
//! examples (Park et al.'s Bezier cube, Wiffle gradient and femur gradient,
//! loaded as `microfrep` loads them) and one grid each:
//! (a) the 1-bit PNG stack of `microfrep slice`,
//! (b) the 8-bit attribute stack of `microfrep slice --attribute 1`,
//! (c) the RGBA material stack of `microfrep materials` (two materials,
//! error diffusion),
//! each written to a fresh directory under the temporary directory through
//! the library calls the CLI makes. Median of `REPS` interleaved runs; the
//! ratios are
//! `ratio_attribute = b / a` and `ratio_materials = c / a`; the `cpu_`
//! ratios are the same of the CPU time all threads spent (less disturbed
//! by other processes on a shared machine than wall time).

use microfrep::fab::{write_stack, AttributeStack, Format, SliceGrid};
use microfrep::graded::stack::{
    write_material_stack, MaterialStack, Palette, ShapeSource, StackGrid,
};
use microfrep::Shape;
use std::path::Path;
use std::time::Instant;

const THREADS: usize = 2;
const REPS: usize = 5;

/// A case: example file, pixel size and layer thickness.
struct Case {
    name: &'static str,
    file: &'static str,
    pixel: f64,
    layer: f64,
}

const CASES: &[Case] = &[
    Case {
        name: "bezier_cube",
        file: "park_fig1_bezier_cube.hf",
        pixel: 0.003,
        layer: 0.01,
    },
    Case {
        name: "wiffle_gradient",
        file: "park_fig4_wiffle_gradient.hf",
        pixel: 0.005,
        layer: 0.02,
    },
    Case {
        name: "femur_gradient",
        file: "park_fig6_femur_gradient.hf",
        pixel: 0.007,
        layer: 0.015,
    },
];

/// The median of `ts`.
fn median(mut ts: Vec<f64>) -> f64 {
    ts.sort_by(f64::total_cmp);
    ts[ts.len() / 2]
}

/// CPU seconds run so far by all threads of the process (Linux
/// `/proc/self/task/*/schedstat`; 0 where that cannot be read).
fn cpu_seconds() -> f64 {
    let Ok(tasks) = std::fs::read_dir("/proc/self/task") else {
        return 0.0;
    };
    let ns: u64 = tasks
        .filter_map(|t| std::fs::read_to_string(t.ok()?.path().join("schedstat")).ok())
        .filter_map(|s| s.split_whitespace().next()?.parse::<u64>().ok())
        .sum();
    ns as f64 * 1e-9
}

/// Wall and CPU time of `f` on a fresh `dir`.
fn timed(dir: &Path, f: impl FnOnce() -> Result<(), String>) -> Result<(f64, f64), String> {
    let _ = std::fs::remove_dir_all(dir);
    let (t, c) = (Instant::now(), cpu_seconds());
    f()?;
    Ok((t.elapsed().as_secs_f64(), cpu_seconds() - c))
}

/// Bytes of the files in `dir`.
fn dir_bytes(dir: &Path) -> u64 {
    std::fs::read_dir(dir)
        .map(|d| {
            d.filter_map(|e| e.ok()?.metadata().ok())
                .map(|m| m.len())
                .sum()
        })
        .unwrap_or(0)
}

pub fn run() -> Result<(), String> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(THREADS)
        .build()
        .map_err(|e| e.to_string())?;
    let examples = concat!(env!("CARGO_MANIFEST_DIR"), "/../examples");
    // `bench/run materials CASE` runs one case.
    let only = std::env::args().nth(2);
    for case in CASES {
        if only.as_deref().is_some_and(|o| o != case.name) {
            continue;
        }
        let path = format!("{examples}/{}", case.file);
        let m = microfrep::load(&path, &Default::default())
            .map_err(|e| format!("{}: {e}", case.file))?;
        pool.install(|| one(case, &m.shape))?;
    }
    Ok(())
}

fn one(case: &Case, shape: &Shape) -> Result<(), String> {
    let b = shape.bounds().map_err(|e| format!("{}: {e}", case.name))?;
    let grid = SliceGrid::new(b.min, b.max, case.layer, case.pixel).map_err(|e| e.to_string())?;
    let sgrid =
        StackGrid::new(b.min, b.max, [case.pixel; 2], case.layer).map_err(|e| e.to_string())?;
    if (sgrid.nx, sgrid.ny, sgrid.layers) != (grid.nx, grid.ny, grid.layers) {
        return Err(format!(
            "{}: slice grid {}x{}x{} and material grid {}x{}x{} differ",
            case.name, grid.nx, grid.ny, grid.layers, sgrid.nx, sgrid.ny, sgrid.layers
        ));
    }
    let tmp = std::env::temp_dir();
    let pid = std::process::id();
    let dir = |k: &str| tmp.join(format!("microfrep-bench-materials-{pid}-{}-{k}", case.name));

    let (da, db, dc) = (dir("plain"), dir("attribute"), dir("materials"));
    let attr = AttributeStack::new(shape, 0).map_err(|e| e.to_string())?;
    let palette = Palette::parse("primary=#FFFFFF,secondary=#FF0000").map_err(|e| e.to_string())?;
    let opts = MaterialStack::new(palette);
    let mut report = None;
    // Interleaved repetitions, so load from other processes spreads over
    // all three kinds alike.
    let (mut ta, mut tb, mut tc) = (Vec::new(), Vec::new(), Vec::new());
    // `bench/run materials CASE KINDS` (comma-separated: plain, attribute,
    // materials) times those kinds alone, for profiling or comparing two;
    // the ratios of kinds left out are meaningless.
    let kind = std::env::args().nth(3);
    let on = |k: &str| kind.as_deref().is_none_or(|o| o.split(',').any(|o| o == k));
    for _ in 0..REPS {
        ta.push(timed(&da, || {
            if !on("plain") {
                return Ok(());
            }
            write_stack(shape, &grid, &Format::Png { aa: false }, &da, &|| {})
                .map_err(|e| e.to_string())
        })?);
        tb.push(timed(&db, || {
            if !on("attribute") {
                return Ok(());
            }
            write_stack(shape, &grid, &attr, &db, &|| {}).map_err(|e| e.to_string())
        })?);
        tc.push(timed(&dc, || {
            if !on("materials") {
                return Ok(());
            }
            let src =
                ShapeSource::new(shape, &sgrid, opts.palette.len()).map_err(|e| e.to_string())?;
            let mut source = |k: usize, f: &mut [f32], m: &mut [bool]| src.fill(k, f, m);
            let r = write_material_stack(&dc, &sgrid, &opts, &mut source, &|_, _| {})
                .map_err(|e| e.to_string())?;
            report = Some(r);
            Ok(())
        })?);
    }
    let wall = |t: &[(f64, f64)]| median(t.iter().map(|p| p.0).collect());
    let cpu = |t: &[(f64, f64)]| median(t.iter().map(|p| p.1).collect());
    let (plain, attribute, materials) = (wall(&ta), wall(&tb), wall(&tc));
    let (plain_cpu, attribute_cpu, materials_cpu) = (cpu(&ta), cpu(&tb), cpu(&tc));
    let inside = report.map_or(0, |r| r.dither.inside);
    let bytes = [dir_bytes(&da), dir_bytes(&db), dir_bytes(&dc)];
    for d in [&da, &db, &dc] {
        let _ = std::fs::remove_dir_all(d);
    }
    println!(
        "RESULT {}_{}x{}x{} plain_s={plain:.3} attribute_s={attribute:.3} \
         materials_s={materials:.3} ratio_attribute={:.2} ratio_materials={:.2} \
         plain_cpu_s={plain_cpu:.3} attribute_cpu_s={attribute_cpu:.3} \
         materials_cpu_s={materials_cpu:.3} cpu_ratio_attribute={:.2} cpu_ratio_materials={:.2} \
         inside_voxels={} plain_bytes={} attribute_bytes={} materials_bytes={} threads={THREADS}",
        case.name,
        grid.nx,
        grid.ny,
        grid.layers,
        attribute / plain,
        materials / plain,
        attribute_cpu / plain_cpu,
        materials_cpu / plain_cpu,
        inside,
        bytes[0],
        bytes[1],
        bytes[2],
    );
    Ok(())
}
