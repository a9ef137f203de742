//! Suite `hyperfun`: batch throughput of HyperFun models lowered to the core
//! graph against the same expressions built with the Rust API, single
//! thread, on a 128^3 grid over [-1.6, 1.6]^3. `ratio` = HyperFun / Rust
//! (value output only; `with_errors` also computes the error-code output).

use microfrep_core::{frep, BatchEval, Expr, Tape};
use std::time::Instant;

const N: usize = 128;
const REPS: usize = 3;
const ROUNDS: usize = 4;

/// The tori-ball block in HyperFun: triangle-wave replication of three
/// tori (cell width 0.2) intersected with the block [-1, 1]^3.
const TORIBALL_HF: &str = "
my_model(x[3], a[1])
{
  array q[3], c[3], v[3];
  c = [0, 0, 0];
  v = [-1, -1, -1];
  w = 0.2;
  -- triangle wave of period 2w mapped onto the cell [-1, 1]
  t = x[1] / (2*w);  q[1] = 4*abs(t - floor(t + 0.5)) - 1;
  t = x[2] / (2*w);  q[2] = 4*abs(t - floor(t + 0.5)) - 1;
  t = x[3] / (2*w);  q[3] = 4*abs(t - floor(t + 0.5)) - 1;
  cell = hfTorusX(q, c, 0.8, 0.2) | hfTorusY(q, c, 0.8, 0.2) | hfTorusZ(q, c, 0.8, 0.2);
  my_model = cell & hfBlock(x, v, 2, 2, 2);
}
";

/// The same tori-ball with the Rust API.
fn toriball_rust() -> Expr {
    let p = Expr::xyz();
    let q: Vec<Expr> = p
        .iter()
        .map(|c| {
            let t = c / 0.4;
            4.0 * (&t - (&t + 0.5).floor()).abs() - 1.0
        })
        .collect();
    let torus = |k: usize| {
        let (i, j) = [(1, 2), (0, 2), (0, 1)][k];
        0.2f64 * 0.2 - q[0].square() - q[1].square() - q[2].square() - 0.8f64 * 0.8
            + 1.6 * (q[i].square() + q[j].square()).sqrt()
    };
    let cell = frep::union(&frep::union(&torus(0), &torus(1), 0.0), &torus(2), 0.0);
    let slab = |c: &Expr| (c + 1.0) * (1.0 - c);
    let r0 = |u: &Expr, v: &Expr| u + v - (u.square() + v.square()).sqrt();
    let block = r0(&r0(&slab(&p[0]), &slab(&p[1])), &slab(&p[2]));
    frep::intersection(&cell, &block, 0.0)
}

/// `corpus/penev_s4_gyroid.hf` with the Rust API.
fn gyroid_rust() -> Expr {
    let [x, y, z] = Expr::xyz();
    let s = |a: &Expr, b: &Expr| (3.0 * a).sin() * (3.0 * b).cos();
    let g = s(&x, &y) + s(&y, &z) + s(&z, &x) - 0.2;
    let r = (&x * &x + &y * &y + &z * &z).sqrt() - 1.4;
    -Expr::select(g.gt(&r), g.clone(), r)
}

pub fn run() -> Result<(), String> {
    let gyroid_path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../crates/hyperfun/testdata/corpus/penev_s4_gyroid.hf"
    );
    let gyroid_src =
        std::fs::read_to_string(gyroid_path).map_err(|e| format!("reading {gyroid_path}: {e}"))?;
    let cases = [
        ("gyroid", gyroid_src.as_str(), gyroid_rust()),
        ("toriball", TORIBALL_HF, toriball_rust()),
    ];
    let (x, y, z) = grid(N);
    for (name, src, rust) in cases {
        let m = microfrep_hyperfun::load(src, name, None).map_err(|e| format!("{name}: {e}"))?;
        let hf_tape = Tape::new(&m.value);
        let both = m.tape();
        let rust_tape = Tape::new(&rust);
        // Interleaved rounds, best of each, so load from other processes
        // does not favour whichever runs first.
        let (mut t_hf, mut t_both, mut t_rust) = (f64::INFINITY, f64::INFINITY, f64::INFINITY);
        let (mut v_hf, mut v_rust) = (Vec::new(), Vec::new());
        for _ in 0..ROUNDS {
            let (t, v) = time(&hf_tape, &x, &y, &z);
            (t_hf, v_hf) = (t_hf.min(t), v);
            t_both = t_both.min(time(&both, &x, &y, &z).0);
            let (t, v) = time(&rust_tape, &x, &y, &z);
            (t_rust, v_rust) = (t_rust.min(t), v);
        }
        let diff = v_hf
            .iter()
            .zip(&v_rust)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0f32, f32::max);
        let mpts = |s: f64| x.len() as f64 / s / 1e6;
        println!(
            "RESULT hyperfun_{name} hyperfun={:.2} with_errors={:.2} rust_api={:.2} ratio={:.3} \
             points={} tape_len_hf={} tape_len_rust={} same_tape={} lowered={} max_abs_diff={diff:.2e}",
            mpts(t_hf),
            mpts(t_both),
            mpts(t_rust),
            t_rust / t_hf,
            x.len(),
            hf_tape.len(),
            rust_tape.len(),
            hf_tape.listing() == rust_tape.listing(),
            m.lowered,
        );
    }
    Ok(())
}

/// Best wall time of `REPS` passes over the grid (after a warm-up) and the
/// values of output 0.
fn time(tape: &Tape, x: &[f32], y: &[f32], z: &[f32]) -> (f64, Vec<f32>) {
    let mut ev = BatchEval::new(tape);
    let mut out = vec![0.0f32; x.len()];
    ev.eval(x, y, z, &mut out);
    let mut best = f64::INFINITY;
    for _ in 0..REPS {
        let t = Instant::now();
        ev.eval(x, y, z, &mut out);
        best = best.min(t.elapsed().as_secs_f64());
    }
    (best, out)
}

/// Cell-centred grid of n^3 points in [-1.6, 1.6]^3, x fastest.
fn grid(n: usize) -> (Vec<f32>, Vec<f32>, Vec<f32>) {
    let c = |i: usize| (1.6 * (-1.0 + (2.0 * i as f64 + 1.0) / n as f64)) as f32;
    let mut v = (Vec::new(), Vec::new(), Vec::new());
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                v.0.push(c(i));
                v.1.push(c(j));
                v.2.push(c(k));
            }
        }
    }
    v
}
