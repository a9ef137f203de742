//! Suite `slice`: direct fabrication and rendering, 2 threads throughout.
//! One 2048 x 2048 layer of the shell-with-lattice model by microfrep's
//! slicer and by fidget's 2D rasteriser (JIT); a 200-layer 1024 x 1024 PNG
//! stack of the tori-ball block written to disk; a 1024 x 1024 ray-cast
//! render of the shell-with-lattice model. Best of a few repetitions.

use crate::to_fidget::translate;
use fidget::jit::JitFunction;
use fidget::raster::pixel::{render, EvalConfig, RenderConfig};
use fidget::render::ThreadPool;
use fidget::shape::{BoundShape, Shape};
use microfrep_core::Tape;
use microfrep_fab::{rasterize_at, write_stack, Format, SliceGrid};
use microfrep_render::{ray_cast, Camera, View};
use microfrep_structures::examples::{shell_lattice, toriball};
use std::time::Instant;

const THREADS: usize = 2;
const REPS: usize = 3;

fn pool() -> Result<rayon::ThreadPool, String> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(THREADS)
        .build()
        .map_err(|e| e.to_string())
}

/// Best wall time of `REPS` runs of `f`, and its last result.
fn best<T>(mut f: impl FnMut() -> Result<T, String>) -> Result<(f64, T), String> {
    let mut t_best = f64::INFINITY;
    let mut last = None;
    for _ in 0..REPS {
        let t = Instant::now();
        let r = f()?;
        t_best = t_best.min(t.elapsed().as_secs_f64());
        last = Some(r);
    }
    Ok((t_best, last.expect("REPS > 0")))
}

pub fn run() -> Result<(), String> {
    let ours = pool()?;
    layer_vs_fidget(&ours)?;
    stack(&ours)?;
    render_case(&ours)
}

fn layer_vs_fidget(ours: &rayon::ThreadPool) -> Result<(), String> {
    let (n, z) = (2048usize, 0.1);
    let expr = shell_lattice();
    let tape = Tape::new(&expr);
    let grid =
        SliceGrid::new([-1.0; 3], [1.0; 3], 2.0, 2.0 / n as f64).map_err(|e| e.to_string())?;
    let (ms, layer) = best(|| Ok(ours.install(|| rasterize_at(&tape, &grid, z))))?;
    let inside = layer.values.iter().filter(|&&v| v >= 0.0).count();

    // fidget renders its default view [-1, 1]^2, filling tiles its interval
    // pass decides (as ours does); its function is -f (see to_fidget), so
    // its inside is ours.
    let (ctx, root) = translate(&expr)?;
    let shape = Shape::<JitFunction>::new(&ctx, root).map_err(|e| e.to_string())?;
    let theirs = ThreadPool::Custom(pool()?);
    let cfg = RenderConfig {
        z: z as f32,
        pixel_perfect: false,
        ..RenderConfig::from_size((n as u32).into())
    };
    let eval = EvalConfig {
        threads: Some(&theirs),
        ..Default::default()
    };
    let (fs, img) = best(|| {
        let bound: BoundShape<JitFunction, f32> =
            shape.clone().try_into().map_err(|e| format!("{e:?}"))?;
        render(bound, &cfg, &eval).ok_or_else(|| "fidget render cancelled".to_string())
    })?;
    let f_inside = img.iter().filter(|p| p.inside()).count();
    println!(
        "RESULT layer_shell_lattice_{n} microfrep_s={ms:.4} fidget_jit_s={fs:.4} ratio={:.2} \
         microfrep_inside_px={inside} fidget_inside_px={f_inside} threads={THREADS}",
        fs / ms
    );
    Ok(())
}

fn stack(ours: &rayon::ThreadPool) -> Result<(), String> {
    let tape = Tape::new(&toriball());
    let grid =
        SliceGrid::new([-1.0; 3], [1.0; 3], 0.01, 2.0 / 1024.0).map_err(|e| e.to_string())?;
    let dir = std::env::temp_dir().join(format!("microfrep-bench-slice-{}", std::process::id()));
    let (s, _) = best(|| {
        let _ = std::fs::remove_dir_all(&dir);
        ours.install(|| write_stack(&tape, &grid, Format::Png { aa: false }, &dir, &|| {}))
            .map_err(|e| e.to_string())
    })?;
    let bytes: u64 = std::fs::read_dir(&dir)
        .map_err(|e| e.to_string())?
        .filter_map(|e| e.ok()?.metadata().ok())
        .map(|m| m.len())
        .sum();
    let _ = std::fs::remove_dir_all(&dir);
    println!(
        "RESULT stack_toriball_200x1024 microfrep_s={s:.3} layers={} px={}x{} bytes={bytes} \
         threads={THREADS}",
        grid.layers, grid.nx, grid.ny
    );
    Ok(())
}

fn render_case(ours: &rayon::ThreadPool) -> Result<(), String> {
    let tape = Tape::new(&shell_lattice());
    let (lo, hi) = ([-1.0; 3], [1.0; 3]);
    let cam = Camera::fit(View::Iso, lo, hi, 1024, 1024);
    let (s, img) = best(|| Ok(ours.install(|| ray_cast(&tape, &cam, lo, hi))))?;
    let hit = img.data.chunks(3).filter(|c| c != &[250, 250, 250]).count();
    println!("RESULT render_shell_lattice_1024 microfrep_s={s:.3} hit_px={hit} threads={THREADS}");
    Ok(())
}
