//! Times the mesher on a built-in example, for profiling: `cargo run
//! --release -p microfrep-mesh --example profile_mesh -- NAME N [THREADS]`.
//! `STREAM=1` streams through a counting sink instead of collecting the
//! mesh; `BRICK=K` sets the brick size; `CUBES=1` uses marching cubes;
//! `SHARP=1` turns on sharp features.

use microfrep_core::Shape;
use microfrep_mesh::{MeshOptions, Plan};
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map(String::as_str).unwrap_or("toriball");
    let n: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(256);
    let threads: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(1);
    let ex = microfrep_structures::examples::by_name(name).expect("example name");
    let expr = (ex.build)();
    let (lo, hi) = ex.bounds;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("pool");
    pool.install(|| {
        let t = Instant::now();
        let mut opts = MeshOptions::new([lo, hi], n);
        if let Some(b) = std::env::var("BRICK").ok().and_then(|s| s.parse().ok()) {
            opts.brick = b;
        }
        if std::env::var("CUBES").is_ok() {
            opts.cells = microfrep_mesh::CellMethod::Cubes;
        }
        opts.sharp = std::env::var("SHARP").is_ok();
        let plan = Plan::new(&Shape::from(&expr), &opts).expect("plan");
        let t_plan = t.elapsed().as_secs_f64();
        // STREAM=1: through a counting sink, never holding the mesh.
        let (tris, verts) = if std::env::var("STREAM").is_ok() {
            struct Null;
            impl microfrep_mesh::sink::MeshSink for Null {
                fn vertices(&mut self, _: &[[f32; 3]]) -> Result<(), microfrep_mesh::MeshError> {
                    Ok(())
                }
                fn triangles(
                    &mut self,
                    _: &[[u32; 3]],
                    _: &microfrep_mesh::sink::VertexWindow,
                ) -> Result<(), microfrep_mesh::MeshError> {
                    Ok(())
                }
            }
            let mut t = microfrep_mesh::sink::Tallying {
                inner: &mut Null,
                tally: Default::default(),
            };
            plan.run_into(&mut t, &|_| {}).expect("mesh");
            (t.tally.triangles as usize, t.tally.vertices as usize)
        } else {
            let m = plan.run(&|_| {}).expect("mesh");
            (m.triangles.len(), m.vertices.len())
        };
        let t_all = t.elapsed().as_secs_f64();
        println!(
            "{name} {n}: plan {t_plan:.3} s, total {t_all:.3} s, {tris} triangles, {verts} vertices, {} surface bricks",
            plan.surface_bricks()
        );
    });
}
