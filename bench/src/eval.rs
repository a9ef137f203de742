//! Suite `eval`: single-thread batch evaluation of the built-in examples by
//! microfrep's `BatchEval` and by fidget's bulk float evaluator (VM and JIT)
//! on the same dense grid in [-1, 1]^3. The engines take turns, repetition
//! by repetition, so a busy machine slows them alike; each figure is the
//! best repetition. The values of both engines are compared point by point.

use crate::to_fidget::translate;
use fidget::context::{Context, Node};
use fidget::eval::{BulkEvaluator, Function, MathFunction};
use fidget::jit::JitFunction;
use fidget::shape::{EzShape, Shape, ShapeBulkEval};
use fidget::vm::VmFunction;
use microfrep_core::{BatchEval, Tape};
use microfrep_structures::examples;
use std::time::Instant;

const CASES: [&str; 2] = ["toriball", "shell_lattice"];
/// Grid points per axis: 128^3 = 2.1 M points per pass.
const N: usize = 128;
const REPS: usize = 7;
/// Slice lengths handed to fidget per call; the fastest is used, so the
/// peer is not slowed by a size that suits it badly.
const FIDGET_CHUNKS: [usize; 3] = [256, 1024, 8192];

/// Evaluates the whole grid into the output slice, `chunk` points per call.
type Engine<'a> = Box<dyn FnMut(&mut [f32], usize) -> Result<(), String> + 'a>;

pub fn run() -> Result<(), String> {
    let (x, y, z) = grid(N);
    let (x, y, z) = (&x[..], &y[..], &z[..]);
    for name in CASES {
        let ex = examples::by_name(name).ok_or(format!("no example '{name}'"))?;
        let expr = (ex.build)();
        let tape = Tape::new(&expr);
        let mut batch = BatchEval::new(&tape);
        let ours: Engine = Box::new(move |out, _| {
            batch.eval(x, y, z, out);
            Ok(())
        });
        let (ctx, root) = translate(&expr)?;
        let vm = fidget_engine::<VmFunction>(&ctx, root, x, y, z)?;
        let jit = fidget_engine::<JitFunction>(&ctx, root, x, y, z)?;

        let mut engines = [ours, vm, jit];
        let mut outs = vec![vec![0.0f32; x.len()]; 3];
        let mut chunks = [x.len(); 3];
        for k in 1..3 {
            chunks[k] = fastest_chunk(&mut engines[k], &mut outs[k])?;
        }
        let mut best = [f64::INFINITY; 3];
        for _ in 0..REPS {
            for k in 0..3 {
                let t = Instant::now();
                engines[k](&mut outs[k], chunks[k])?;
                best[k] = best[k].min(t.elapsed().as_secs_f64());
            }
        }
        // fidget computes -f: compare ours with the negation of theirs.
        let diff = |theirs: &[f32]| {
            outs[0]
                .iter()
                .zip(theirs)
                .map(|(a, b)| (a + b).abs())
                .fold(0.0f32, f32::max)
        };
        let [m, v, j] = best.map(|secs| x.len() as f64 / secs / 1e6);
        // The divider floor: the square roots and divisions the tape does
        // per point, alone, in blocks of 256 (the divider unit runs one
        // 8-lane op every few cycles, whatever else the tape does).
        let (roots, divs) = divider_ops(&tape);
        let floor = x.len() as f64 / floor_secs(x, roots, divs) / 1e6;
        println!(
            "RESULT {name} microfrep={m:.2} fidget_vm={v:.2} fidget_jit={j:.2} ratio={:.2} \
             points={} tape_len={} sqrt={roots} div={divs} divider_floor={floor:.2} \
             floor_over_jit={:.2} max_abs_diff_vm={:.2e} max_abs_diff_jit={:.2e} \
             fidget_chunks={}/{}",
            m / v.max(j),
            x.len(),
            tape.len(),
            floor / j,
            diff(&outs[1]),
            diff(&outs[2]),
            chunks[1],
            chunks[2],
        );
    }
    Ok(())
}

/// Square roots and divisions per point of the tape: `sqrt`, `/`, and the
/// R-function set operations (a root each, and a division where alpha is
/// not zero).
fn divider_ops(tape: &Tape) -> (usize, usize) {
    use microfrep_core::{BinaryOp, Op, UnaryOp};
    let constant = |v: microfrep_core::ValueId| match tape.ops()[v as usize] {
        Op::Const(c) => Some(c),
        _ => None,
    };
    let (mut roots, mut divs) = (0, 0);
    for op in tape.ops() {
        match *op {
            Op::Unary(UnaryOp::Sqrt, _) => roots += 1,
            Op::Binary(BinaryOp::Div, ..) => divs += 1,
            Op::Set { alpha, .. } => {
                roots += 1;
                if constant(alpha) != Some(0.0) {
                    divs += 1;
                }
            }
            _ => {}
        }
    }
    (roots, divs)
}

/// Seconds (best of `REPS`) of `roots` square roots and `divs` divisions
/// per point of `x`, in blocks of 256.
fn floor_secs(x: &[f32], roots: usize, divs: usize) -> f64 {
    let mut acc = vec![0.0f32; 256];
    let mut best = f64::INFINITY;
    for _ in 0..REPS {
        let t = Instant::now();
        for xs in x.chunks(256) {
            // Lanes innermost, as the evaluator's loops, so they vectorise.
            for k in 0..roots {
                for (a, &xi) in acc.iter_mut().zip(xs) {
                    *a += (xi.abs() + k as f32).sqrt();
                }
            }
            for k in 0..divs {
                for (a, &xi) in acc.iter_mut().zip(xs) {
                    *a += xi / (0.2 + k as f32);
                }
            }
        }
        best = best.min(t.elapsed().as_secs_f64());
    }
    std::hint::black_box(&acc);
    best
}

/// Cell-centred grid of n^3 points in [-1, 1]^3, x fastest.
fn grid(n: usize) -> (Vec<f32>, Vec<f32>, Vec<f32>) {
    let c = |i: usize| (-1.0 + (2.0 * i as f64 + 1.0) / n as f64) as f32;
    let total = n * n * n;
    let (mut x, mut y, mut z) = (
        Vec::with_capacity(total),
        Vec::with_capacity(total),
        Vec::with_capacity(total),
    );
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                x.push(c(i));
                y.push(c(j));
                z.push(c(k));
            }
        }
    }
    (x, y, z)
}

/// The slice length at which an engine runs fastest (one timed pass each,
/// after a warm-up).
fn fastest_chunk(engine: &mut Engine, out: &mut [f32]) -> Result<usize, String> {
    engine(out, FIDGET_CHUNKS[0])?;
    let mut best = (f64::INFINITY, FIDGET_CHUNKS[0]);
    for chunk in FIDGET_CHUNKS {
        let t = Instant::now();
        engine(out, chunk)?;
        let secs = t.elapsed().as_secs_f64();
        if secs < best.0 {
            best = (secs, chunk);
        }
    }
    Ok(best.1)
}

/// fidget's bulk float evaluator of the given kind over the grid.
fn fidget_engine<'a, F: Function + MathFunction + Clone + 'a>(
    ctx: &Context,
    root: Node,
    x: &'a [f32],
    y: &'a [f32],
    z: &'a [f32],
) -> Result<Engine<'a>, String>
where
    <F as Function>::FloatSliceEval: BulkEvaluator<Data = f32>,
{
    let shape = Shape::<F>::new(ctx, root).map_err(|e| e.to_string())?;
    let tape = shape.ez_float_slice_tape();
    let mut ev: ShapeBulkEval<F::FloatSliceEval> = Shape::<F>::new_float_slice_eval();
    Ok(Box::new(move |out: &mut [f32], chunk: usize| {
        for (i, o) in out.chunks_mut(chunk).enumerate() {
            let r = i * chunk..i * chunk + o.len();
            let v = ev
                .eval(&tape, &x[r.clone()], &y[r.clone()], &z[r])
                .map_err(|e| format!("fidget evaluation failed: {e}"))?;
            o.copy_from_slice(v);
        }
        Ok(())
    }))
}
