//! Times a ray-cast render of a built-in example: `cargo run --release -p
//! microfrep-render --example profile_render -- NAME SIZE [THREADS]`.

use microfrep_core::Shape;
use microfrep_render::{ray_cast, Camera, View};
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map(String::as_str).unwrap_or("shell_lattice");
    let n: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(1024);
    let threads: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(1);
    let ex = microfrep_structures::examples::by_name(name).expect("example name");
    let expr = (ex.build)();
    let shape = Shape::new(expr);
    let (lo, hi) = ex.bounds;
    let cam = Camera::fit(View::Iso, lo, hi, n, n);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("pool");
    let t = Instant::now();
    let img = pool.install(|| ray_cast(&shape, &cam, lo, hi));
    let hit = img.data.chunks(3).filter(|c| c != &[250, 250, 250]).count();
    println!(
        "{name} {n}: {:.3} s, {hit} pixels hit",
        t.elapsed().as_secs_f64()
    );
}
