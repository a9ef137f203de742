use microfrep_core::{Expr, Field};
use microfrep_pores::*;
fn block(lo: [f64; 3], hi: [f64; 3]) -> Expr {
    let p = Expr::xyz();
    let mut e: Option<Expr> = None;
    for a in 0..3 {
        let s = (&p[a] - lo[a]).min(Expr::constant(hi[a]) - &p[a]);
        e = Some(match e {
            None => s,
            Some(e) => e.min(s),
        });
    }
    e.unwrap()
}
fn main() {
    let n: usize = std::env::var("N")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1_000_000);
    let reps: usize = std::env::var("REPS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(5);
    let xs: Vec<f32> = (0..n).map(|i| ((i % 100) as f64 * 0.04) as f32).collect();
    let ys: Vec<f32> = (0..n)
        .map(|i| ((i / 100 % 100) as f64 * 0.04) as f32)
        .collect();
    let zs: Vec<f32> = (0..n).map(|i| ((i / 10000) as f64 * 0.04) as f32).collect();
    let mut out = vec![0f32; n];
    let g = microfrep_core::Tape::new(&{
        let p = Expr::xyz();
        let (x, y, z) = (&p[0] * 12.56, &p[1] * 12.56, &p[2] * 12.56);
        x.sin() * y.cos() + y.sin() * z.cos() + z.sin() * x.cos()
    });
    let mut ev = microfrep_core::BatchEval::new(&g);
    let mut best = f64::INFINITY;
    for _ in 0..reps {
        let t = std::time::Instant::now();
        ev.eval(&xs, &ys, &zs, &mut out);
        best = best.min(t.elapsed().as_nanos() as f64 / n as f64);
    }
    println!("gyroid batch: {best:.1} ns/point");
    for dim in if std::env::var("ONLY3").is_ok() {
        vec![Dim::Three]
    } else {
        vec![Dim::Two, Dim::Three]
    } {
        let b = [[0.0; 3], [4.0; 3]];
        let t = std::time::Instant::now();
        let built = Pores::build(
            &block(b[0], b[1]),
            b,
            Spec::Constant(0.5),
            Spec::Constant(0.7),
            1,
            &Options {
                dim,
                ..Options::default()
            },
        )
        .unwrap();
        let bt = t.elapsed();
        let mut best = f64::INFINITY;
        for _ in 0..reps {
            let t = std::time::Instant::now();
            built.field.eval_batch(&xs, &ys, &zs, &mut out);
            best = best.min(t.elapsed().as_nanos() as f64 / n as f64);
        }
        let neg = out.iter().filter(|v| **v < 0.0).count() as f64 / n as f64;
        let capd = out
            .iter()
            .filter(|v| **v as f64 >= built.field.cap() - 1e-6)
            .count() as f64
            / n as f64;
        println!("{dim:?}: {} pores built in {bt:?}; best {best:.1} ns/pt; pore fraction {neg:.3}, at cap {capd:.3}", built.pores);
    }
}
