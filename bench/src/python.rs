//! Suite `python`: the Python package's benchmarks (python/bench/bench.py),
//! run with the venv that `scripts/test-python` builds (or the Python of
//! `MICROFREP_PYTHON_VENV`), after the Rust batch evaluation of the same
//! model here for reference. The script prints its own `RESULT` lines:
//! `Shape.eval` on 10^7 points against `eval_points_par` in the same
//! process, and the Dask slicing and analysis times with 1 and 2 workers.

use microfrep_core::eval::eval_points_par;
use microfrep_core::Shape;
use std::path::PathBuf;
use std::process::Command;
use std::time::Instant;

pub fn run() -> Result<(), String> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let python = match std::env::var_os("MICROFREP_PYTHON_VENV") {
        Some(v) => PathBuf::from(v).join("bin/python"),
        None => root.join("target/python-venv/bin/python"),
    };
    if !python.exists() {
        return Err(format!(
            "{} not found: run scripts/test-python first (it builds the package into that venv), \
             or set MICROFREP_PYTHON_VENV",
            python.display()
        ));
    }
    // The same model and point count in Rust, for reference.
    let n = 10_000_000usize;
    let shape = Shape::new(microfrep_structures::examples::toriball());
    let mut s = 0x9e3779b97f4a7c15u64;
    let mut r = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0
    };
    let (x, y, z): (Vec<f32>, Vec<f32>, Vec<f32>) = (0..n).map(|_| (r(), r(), r())).fold(
        (Vec::new(), Vec::new(), Vec::new()),
        |(mut a, mut b, mut c), (p, q, w)| {
            a.push(p);
            b.push(q);
            c.push(w);
            (a, b, c)
        },
    );
    let mut best = f64::INFINITY;
    for _ in 0..3 {
        let t = Instant::now();
        let v = eval_points_par(shape.tape(), &x, &y, &z);
        best = best.min(t.elapsed().as_secs_f64());
        std::hint::black_box(v);
    }
    println!(
        "RESULT rust_eval model=toriball points={n} threads={} s={best:.4} mpts={:.1}",
        rayon::current_num_threads(),
        n as f64 / best / 1e6
    );
    let status = Command::new(&python)
        .arg(root.join("python/bench/bench.py"))
        .args(std::env::args().skip(2))
        .status()
        .map_err(|e| format!("running {}: {e}", python.display()))?;
    if !status.success() {
        return Err(format!("python/bench/bench.py failed ({status})"));
    }
    Ok(())
}
