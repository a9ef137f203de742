//! `bench/run simplify`: per-region tape simplification (tapes shortened
//! where intervals decide set-operation branches over a brick or a tile)
//! against the full tape, for meshing (256^3) and slicing (40 layers of
//! 1024^2) of three part-with-lattice models, same run, 2 threads.

use microfrep_core::Shape;
use microfrep_fab::{rasterize_with, SliceGrid};
use microfrep_mesh::{check::summary, MeshOptions, Plan};
use std::time::Instant;

const MODELS: &[&str] = &[
    "examples/pasko_fig4_shape_with_lattice.hf",
    "examples/fryazinov_fig11_shell_minus_cells.hf",
    "shell_lattice",
];

fn best<T>(mut f: impl FnMut() -> T) -> (f64, T) {
    let mut out = None;
    let mut t_best = f64::INFINITY;
    for _ in 0..3 {
        let t = Instant::now();
        let r = f();
        t_best = t_best.min(t.elapsed().as_secs_f64());
        out = Some(r);
    }
    (t_best, out.expect("three runs"))
}

fn load(spec: &str) -> Result<Shape, String> {
    microfrep_structures_hf::install();
    if let Some(ex) = microfrep_structures::examples::by_name(spec) {
        let (lo, hi) = ex.bounds;
        return Ok(Shape::new((ex.build)()).with_bounds(microfrep_core::Bounds::new(lo, hi)));
    }
    let src = std::fs::read_to_string(spec).map_err(|e| format!("{spec}: {e}"))?;
    let m = microfrep_hyperfun::load(&src, spec, None).map_err(|e| e.to_string())?;
    Ok(m.shape())
}

pub fn run() -> Result<(), String> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .map_err(|e| e.to_string())?;
    for spec in MODELS {
        let shape = load(spec)?;
        let b = shape.bounds().map_err(|e| e.to_string())?;
        let name = spec
            .rsplit('/')
            .next()
            .unwrap_or(spec)
            .trim_end_matches(".hf");
        let mesh = |simplify: bool| {
            let mut o = MeshOptions::new(b.corners(), 256);
            o.simplify = simplify;
            pool.install(|| Plan::new(&shape, &o).and_then(|p| p.run(&|_| {})))
                .map_err(|e| e.to_string())
        };
        let (t_full, m_full) = best(|| mesh(false));
        let (t_simp, m_simp) = best(|| mesh(true));
        let (a, c) = (summary(&m_full?), summary(&m_simp?));
        println!(
            "RESULT simplify_mesh_{name}_256 full_s={t_full:.3} simplified_s={t_simp:.3} \
             ratio={:.2} tris_full={} tris_simplified={} bad_edges_simplified={} \
             volume_full={:.6} volume_simplified={:.6}",
            t_full / t_simp,
            a.triangles,
            c.triangles,
            c.bad_edges,
            a.volume,
            c.volume
        );
        let grid = SliceGrid::new(
            b.min,
            b.max,
            (b.max[2] - b.min[2]) / 40.0,
            (b.max[0] - b.min[0]).max(b.max[1] - b.min[1]) / 1024.0,
        )
        .map_err(|e| e.to_string())?;
        let slice = |simplify: bool| {
            pool.install(|| {
                (0..grid.layers)
                    .map(|k| rasterize_with(&shape, &grid, grid.z(k), simplify))
                    .collect::<Vec<_>>()
            })
        };
        let (s_full, l_full) = best(|| slice(false));
        let (s_simp, l_simp) = best(|| slice(true));
        let differ: usize = l_full
            .iter()
            .zip(&l_simp)
            .map(|(p, q)| {
                p.values
                    .iter()
                    .zip(&q.values)
                    .filter(|(a, b)| (**a >= 0.0) != (**b >= 0.0))
                    .count()
            })
            .sum();
        println!(
            "RESULT simplify_slice_{name}_40x1024 full_s={s_full:.3} simplified_s={s_simp:.3} \
             ratio={:.2} differing_px={differ}",
            s_full / s_simp
        );
    }
    Ok(())
}
