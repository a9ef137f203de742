//! Suite `slice`: direct fabrication and rendering, 2 threads throughout.
//! One 2048 x 2048 layer of the shell-with-lattice model by microfrep's
//! slicer and by fidget's 2D rasteriser (JIT); a 200-layer 1024 x 1024 PNG
//! stack of the tori-ball block written to disk, and the same stack made
//! the mesh way (meshing at 1024 cells, streamed, cut by the layer planes,
//! each cut scan-filled and encoded); a 1024 x 1024 ray-cast render of the
//! shell-with-lattice model. Best of a few repetitions (the mesh way once).

use crate::to_fidget::translate;
use fidget::jit::JitFunction;
use fidget::raster::pixel::{render, EvalConfig, RenderConfig};
use fidget::render::ThreadPool;
use fidget::shape::{BoundShape, Shape};

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
    let stack_s = stack(&ours)?;
    stack_vs_mesh(&ours, stack_s)?;
    render_case(&ours)
}

fn layer_vs_fidget(ours: &rayon::ThreadPool) -> Result<(), String> {
    let (n, z) = (2048usize, 0.1);
    let expr = shell_lattice();
    let tape = microfrep_core::Shape::new(expr.clone());
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

/// The stack of the `stack` cases: 200 layers of 1024 x 1024 over [-1, 1]^3.
fn stack_grid() -> Result<SliceGrid, String> {
    SliceGrid::new([-1.0; 3], [1.0; 3], 0.01, 2.0 / 1024.0).map_err(|e| e.to_string())
}

fn stack(ours: &rayon::ThreadPool) -> Result<f64, String> {
    let tape = microfrep_core::Shape::new(toriball());
    let grid = stack_grid()?;
    let dir = std::env::temp_dir().join(format!("microfrep-bench-slice-{}", std::process::id()));
    let (s, _) = best(|| {
        let _ = std::fs::remove_dir_all(&dir);
        ours.install(|| write_stack(&tape, &grid, &Format::Png { aa: false }, &dir, &|| {}))
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
    Ok(s)
}

/// A mesh sink that cuts the triangles by the stack's layer planes as they
/// arrive (bottom slab first), scan-fills each layer once no later triangle
/// can reach it, and encodes it as the stack's PNG would be.
struct Cutter<'g> {
    grid: &'g SliceGrid,
    /// Mesh grid: z of node 0, and the z extent of one slab of bricks.
    z0: f64,
    slab: f64,
    h: f64,
    /// Segments (x0, y0, x1, y1) per pending layer.
    segs: Vec<Vec<[f32; 4]>>,
    next_layer: usize,
    images: Vec<Vec<u8>>,
    png_bytes: usize,
    secs: f64,
}

impl Cutter<'_> {
    /// Fills and encodes the layers below `z`.
    fn flush_below(&mut self, z: f64) -> Result<(), microfrep_mesh::MeshError> {
        let g = self.grid;
        while self.next_layer < g.layers && g.z(self.next_layer) < z {
            let k = self.next_layer;
            let segs = std::mem::take(&mut self.segs[k]);
            let pixels = scan_fill(g, &segs);
            let img = microfrep_fab::image::GreyImage {
                width: g.nx,
                height: g.ny,
                binary: true,
                pixels,
            };
            let png = img
                .encode(std::path::Path::new("mesh-cut"))
                .map_err(|e| microfrep_mesh::MeshError::Internal(e.to_string()))?;
            self.png_bytes += png.len();
            if [0, g.layers / 2, g.layers - 1].contains(&k) {
                self.images.push(img.pixels);
            }
            self.next_layer += 1;
        }
        Ok(())
    }
}

impl microfrep_mesh::sink::MeshSink for Cutter<'_> {
    fn vertices(&mut self, _: &[[f32; 3]]) -> Result<(), microfrep_mesh::MeshError> {
        Ok(())
    }

    fn triangles(
        &mut self,
        t: &[[u32; 3]],
        w: &microfrep_mesh::sink::VertexWindow,
    ) -> Result<(), microfrep_mesh::MeshError> {
        let start = Instant::now();
        let g = self.grid;
        let mut zmin = f64::INFINITY;
        for tri in t {
            let p = tri.map(|i| w.get(i));
            let lo = p[0][2].min(p[1][2]).min(p[2][2]) as f64;
            let hi = p[0][2].max(p[1][2]).max(p[2][2]) as f64;
            zmin = zmin.min(lo);
            // Layers k with lo < z(k) <= hi.
            let first = ((lo - g.min[2]) / g.layer - 0.5).floor() as i64 + 1;
            let last = ((hi - g.min[2]) / g.layer - 0.5).floor() as i64;
            for k in first.max(0)..=last.min(g.layers as i64 - 1) {
                let z = g.z(k as usize) as f32;
                let mut ends = [[0f32; 2]; 2];
                let mut n = 0;
                for e in 0..3 {
                    let (a, b) = (p[e], p[(e + 1) % 3]);
                    if (a[2] > z) != (b[2] > z) && n < 2 {
                        let s = (z - a[2]) / (b[2] - a[2]);
                        ends[n] = [a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1])];
                        n += 1;
                    }
                }
                if n == 2 {
                    self.segs[k as usize].push([ends[0][0], ends[0][1], ends[1][0], ends[1][1]]);
                }
            }
        }
        // Batches come slab by slab upwards: no later triangle reaches below
        // the start of this batch's slab, less the vertex correction.
        if zmin.is_finite() {
            let slab = ((zmin - self.z0) / self.slab + 1e-9).floor();
            self.flush_below(self.z0 + slab * self.slab - self.h)?;
        }
        self.secs += start.elapsed().as_secs_f64();
        Ok(())
    }
}

/// Even-odd scan fill of closed cut loops at the pixel centres, rows top
/// first (as the stack's PNGs): 255 inside.
fn scan_fill(g: &SliceGrid, segs: &[[f32; 4]]) -> Vec<u8> {
    let (nx, ny) = (g.nx, g.ny);
    let mut rows: Vec<Vec<f32>> = vec![Vec::new(); ny];
    let p = g.pixel;
    for s in segs {
        let (x0, y0, x1, y1) = (s[0] as f64, s[1] as f64, s[2] as f64, s[3] as f64);
        let (ya, yb) = (y0.min(y1), y0.max(y1));
        // Rows j whose centre y_j lies in [ya, yb).
        let j0 = ((ya - g.min[1]) / p - 0.5).ceil().max(0.0) as usize;
        let j1 = (((yb - g.min[1]) / p - 0.5).ceil().max(0.0) as usize).min(ny);
        for (j, row) in rows.iter_mut().enumerate().take(j1).skip(j0) {
            let y = g.y(j);
            let x = x0 + (y - y0) / (y1 - y0) * (x1 - x0);
            row.push(x as f32);
        }
    }
    let mut out = vec![0u8; nx * ny];
    for (j, xs) in rows.iter_mut().enumerate() {
        xs.sort_unstable_by(f32::total_cmp);
        let r = (ny - 1 - j) * nx;
        for pair in xs.chunks_exact(2) {
            // Pixels i whose centre x_i lies in [pair[0], pair[1]).
            let a = ((pair[0] as f64 - g.min[0]) / p - 0.5).ceil().max(0.0) as usize;
            let b = (((pair[1] as f64 - g.min[0]) / p - 0.5).ceil().max(0.0) as usize).min(nx);
            if a < b {
                out[r + a..r + b].fill(255);
            }
        }
    }
    out
}

/// The stack the mesh way: a streamed 1024-cell mesh cut by the 200 layer
/// planes; mesh time and cut time apart, and how many pixels of three
/// layers differ from the direct stack's.
fn stack_vs_mesh(ours: &rayon::ThreadPool, stack_s: f64) -> Result<(), String> {
    let grid = stack_grid()?;
    let expr = toriball();
    let opts = microfrep_mesh::MeshOptions::new([[-1.0; 3], [1.0; 3]], grid.nx);
    let t = Instant::now();
    let (tris, cut) = ours.install(|| -> Result<_, String> {
        let plan = microfrep_mesh::Plan::new(&microfrep_core::Shape::from(&expr), &opts)
            .map_err(|e| e.to_string())?;
        let mg = &plan.grid;
        let mut cutter = Cutter {
            grid: &grid,
            z0: mg.origin[2],
            slab: mg.brick as f64 * mg.h,
            h: mg.h,
            segs: vec![Vec::new(); grid.layers],
            next_layer: 0,
            images: Vec::new(),
            png_bytes: 0,
            secs: 0.0,
        };
        let mut count = microfrep_mesh::sink::Tallying {
            inner: &mut cutter,
            tally: Default::default(),
        };
        plan.run_into(&mut count, &|_| {})
            .map_err(|e| e.to_string())?;
        let tris = count.tally.triangles;
        let start = Instant::now();
        cutter
            .flush_below(f64::INFINITY)
            .map_err(|e| e.to_string())?;
        cutter.secs += start.elapsed().as_secs_f64();
        Ok((tris, cutter))
    })?;
    let total = t.elapsed().as_secs_f64();
    let tape = microfrep_core::Shape::new(expr.clone());
    let mut differ = 0usize;
    for (img, k) in cut.images.iter().zip([0, grid.layers / 2, grid.layers - 1]) {
        let direct =
            microfrep_fab::image::GreyImage::binary(&rasterize_at(&tape, &grid, grid.z(k)));
        differ += img
            .iter()
            .zip(&direct.pixels)
            .filter(|(a, b)| a != b)
            .count();
    }
    let px = 3 * grid.nx * grid.ny;
    println!(
        "RESULT stack_vs_mesh_toriball_200x1024 stack_s={stack_s:.3} mesh_cut_s={total:.3} \
         mesh_s={:.3} cut_s={:.3} ratio={:.1} mesh_cells={} mesh_tris={tris} png_bytes={} \
         differing_px={differ}/{px} threads={THREADS}",
        total - cut.secs,
        cut.secs,
        total / stack_s,
        grid.nx,
        cut.png_bytes
    );
    Ok(())
}

fn render_case(ours: &rayon::ThreadPool) -> Result<(), String> {
    let expr = shell_lattice();
    let tape = microfrep_core::Shape::new(expr.clone());
    let (lo, hi) = ([-1.0; 3], [1.0; 3]);
    let cam = Camera::fit(View::Iso, lo, hi, 1024, 1024);
    let (s, img) = best(|| Ok(ours.install(|| ray_cast(&tape, &cam, lo, hi))))?;
    let hit = img.data.chunks(3).filter(|c| c != &[250, 250, 250]).count();
    println!("RESULT render_shell_lattice_1024 microfrep_s={s:.3} hit_px={hit} threads={THREADS}");
    Ok(())
}
