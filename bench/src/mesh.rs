//! `bench/run mesh`: the tori-ball block meshed by microfrep (uniform grid,
//! n cells, marching cubes; marching tetrahedra timed alongside) and by
//! fidget's Manifold Dual Contouring (octree depth d, 2^d cells), both on 2
//! threads, with each mesh's size, bad edges and volume
//! error (reference: 1.6378 by Monte Carlo, +- 0.0003); also meshing
//! without the volume correction (`microfrep_nocorr_s`, and
//! `correction_cost`, the time with it over the time without). Times are
//! medians of 3 interleaved rounds (marching tetrahedra: one run). Then
//! the rotated box of the sharp-feature issue, by both meshers, against
//! the exact box (`rotated_box`).

use crate::to_fidget::translate;
use fidget::jit::JitFunction;
use fidget::render::ThreadPool;
use fidget::shape::{BoundShape, Shape};
use microfrep_mesh::check::check;
use microfrep_mesh::{CellMethod, Mesh, MeshOptions, Plan};
use microfrep_structures::examples::toriball;
use std::time::Instant;

const VOLUME: f64 = 1.6378;

/// CPU seconds (user + system) used by this process so far, from
/// /proc/self/stat (clock ticks of 1/100 s): the work of a mesher, which
/// unlike its wall time does not grow when other jobs share the cores.
fn cpu_seconds() -> f64 {
    let s = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    // Fields after the parenthesised command name; utime and stime are the
    // 14th and 15th fields of the line.
    let rest = s.rsplit_once(") ").map(|(_, r)| r).unwrap_or("");
    let f: Vec<f64> = rest
        .split(' ')
        .skip(11)
        .take(2)
        .filter_map(|v| v.parse().ok())
        .collect();
    f.iter().sum::<f64>() / 100.0
}
const THREADS: usize = 2;
/// Interleaved rounds per tori-ball size.
const REPS: usize = 3;

/// A fidget mesh as ours, for the checks.
fn from_fidget(fm: &fidget::mesh::Mesh) -> Mesh {
    Mesh {
        vertices: fm.vertices.iter().map(|v| [v.x, v.y, v.z]).collect(),
        triangles: fm
            .triangles
            .iter()
            .map(|t| [t.x as u32, t.y as u32, t.z as u32])
            .collect(),
    }
}

/// The median of `ts`.
fn median(mut ts: Vec<f64>) -> f64 {
    ts.sort_by(f64::total_cmp);
    ts[ts.len() / 2]
}

pub fn run() -> Result<(), String> {
    let expr = toriball();
    let pool = || {
        rayon::ThreadPoolBuilder::new()
            .num_threads(THREADS)
            .build()
            .map_err(|e| e.to_string())
    };
    let ours = pool()?;
    let theirs = ThreadPool::Custom(pool()?);
    let (ctx, root) = translate(&expr)?;
    for (n, depth) in [(128usize, 7u8), (256, 8)] {
        // Marching cubes (the default cell method); marching tetrahedra is
        // timed too, for reference.
        // One microfrep mesh with options `o`: the mesh, wall and CPU time
        // (the shape compiled inside, as `microfrep mesh` does).
        let mesh_ours = |o: &MeshOptions| -> Result<(Mesh, f64, f64), String> {
            let (t, c) = (Instant::now(), cpu_seconds());
            let m = ours.install(|| {
                Plan::new(&microfrep_core::Shape::from(&expr), o)
                    .and_then(|p| p.run(&|_| {}))
                    .map_err(|e| e.to_string())
            })?;
            Ok((m, t.elapsed().as_secs_f64(), cpu_seconds() - c))
        };
        let mut opts = MeshOptions::new([[-1.0; 3], [1.0; 3]], n);
        opts.cells = CellMethod::Tetrahedra;
        let tets_s = mesh_ours(&opts)?.1;
        opts.cells = CellMethod::Cubes;
        let mut nocorr = opts.clone();
        nocorr.volume_correction = false;
        let shape = Shape::<JitFunction>::new(&ctx, root).map_err(|e| e.to_string())?;
        let bound: BoundShape<JitFunction, f32> = shape.try_into().map_err(|e| format!("{e:?}"))?;
        let settings = fidget::mesh::Settings {
            depth,
            threads: Some(&theirs),
            ..Default::default()
        };
        // REPS interleaved rounds (microfrep, microfrep without the
        // correction, fidget), so load from other processes falls on all
        // alike; medians of wall and CPU time. The last meshes are kept
        // for the checks.
        let (mut ours_t, mut ours_c, mut nocorr_t, mut theirs_t, mut theirs_c) =
            (vec![], vec![], vec![], vec![], vec![]);
        let mut kept = None;
        for _ in 0..REPS {
            drop(kept.take());
            let (m, t, c) = mesh_ours(&opts)?;
            ours_t.push(t);
            ours_c.push(c);
            // The same without the volume correction (its cost).
            nocorr_t.push(mesh_ours(&nocorr)?.1);
            // fidget meshes its default region [-1, 1]^3, the block's bounds.
            let (t, c) = (Instant::now(), cpu_seconds());
            let fm = fidget::mesh::Octree::build(&bound, &settings)
                .ok_or("fidget meshing was cancelled")?
                .walk_dual();
            theirs_t.push(t.elapsed().as_secs_f64());
            theirs_c.push(cpu_seconds() - c);
            kept = Some((m, fm));
        }
        let (m, fm) = kept.ok_or("no rounds were run")?;
        let (ms, mc, nocorr_s, fs, fc) = (
            median(ours_t),
            median(ours_c),
            median(nocorr_t),
            median(theirs_t),
            median(theirs_c),
        );
        let fm = from_fidget(&fm);
        let (a, b) = (check(&m), check(&fm));
        println!(
            "RESULT toriball_{n} microfrep_s={ms:.3} fidget_s={fs:.3} ratio={:.1} \
             microfrep_cpu_s={mc:.2} fidget_cpu_s={fc:.2} cpu_ratio={:.1} microfrep_tris={} fidget_tris={} microfrep_bad_edges={} fidget_bad_edges={} \
             microfrep_vol_err={:.4} fidget_vol_err={:.4} fidget_depth={depth} \
             cells=cubes microfrep_tets_s={tets_s:.3} tets_ratio={:.1} \
             microfrep_nocorr_s={nocorr_s:.3} correction_cost={:.2} rounds={REPS}",
            fs / ms,
            fc / mc,
            a.triangles,
            b.triangles,
            a.bad_edges,
            b.bad_edges,
            (a.volume - VOLUME) / VOLUME,
            (b.volume.abs() - VOLUME) / VOLUME,
            fs / tets_s,
            ms / nocorr_s,
        );
    }
    rotated_box(&ours, &theirs)?;
    gyroid_sheet_job(&ours)?;
    ply_vs_stl(&ours)
}

/// The same `microfrep mesh` job on the tori-ball block at 128 cells in
/// [-1, 1]^3, written as STL and as PLY (which also needs the vertex
/// normals, a batched gradient per vertex), 2 threads, best of 3
/// interleaved runs. Target: the PLY job at most 1.25x the STL job.
fn ply_vs_stl(pool: &rayon::ThreadPool) -> Result<(), String> {
    use microfrep_core::Shape;
    use microfrep_mesh::job::{mesh_to_file, JobOptions};
    let model = toriball();
    let b = [[-1.0; 3], [1.0; 3]];
    let path = |ext: &str| {
        std::env::temp_dir().join(format!(
            "microfrep-bench-plyvsstl-{}.{ext}",
            std::process::id()
        ))
    };
    let mut best = [f64::INFINITY; 2];
    let mut triangles = 0;
    for _ in 0..3 {
        for (k, ext) in ["stl", "ply"].into_iter().enumerate() {
            let out = path(ext);
            let _ = std::fs::remove_file(&out);
            let t = Instant::now();
            let s = pool.install(|| {
                mesh_to_file(
                    &Shape::new(model.clone()),
                    &MeshOptions::new(b, 128),
                    &out,
                    &JobOptions::default(),
                    &|_, _| {},
                )
                .map_err(|e| e.to_string())
            })?;
            best[k] = best[k].min(t.elapsed().as_secs_f64());
            triangles = s.triangles;
            let _ = std::fs::remove_file(&out);
        }
    }
    println!(
        "RESULT ply_vs_stl toriball_128 stl_s={:.3} ply_s={:.3} ratio={:.2} target=1.25 \
         triangles={triangles} runs=3 threads={THREADS}",
        best[0],
        best[1],
        best[1] / best[0],
    );
    Ok(())
}

/// The rotated box of the sharp-feature issue (half sizes 0.6, 0.4, 0.3,
/// turned 20 degrees about z, then 15 about x, in [-1, 1]^3) at 32 and 64
/// cells: microfrep with and without sharp features against fidget's
/// octree at depth 5 and 6, each mesh measured against the exact box
/// (largest distance of a vertex from its surface, of points of its 12
/// edges and of its corners from the mesh, all in cells; volume error) and
/// timed (median of 3).
fn rotated_box(ours: &rayon::ThreadPool, theirs: &ThreadPool) -> Result<(), String> {
    use microfrep_core::Expr;
    use microfrep_mesh::measure::to_mesh;
    let (a, b) = (20f64.to_radians(), 15f64.to_radians());
    let rz = [
        [a.cos(), -a.sin(), 0.0],
        [a.sin(), a.cos(), 0.0],
        [0.0, 0.0, 1.0],
    ];
    let rx = [
        [1.0, 0.0, 0.0],
        [0.0, b.cos(), -b.sin()],
        [0.0, b.sin(), b.cos()],
    ];
    let r: [[f64; 3]; 3] = std::array::from_fn(|i| {
        std::array::from_fn(|j| (0..3).map(|k| rx[i][k] * rz[k][j]).sum::<f64>())
    });
    let half = [0.6, 0.4, 0.3];
    let p = Expr::xyz();
    let mut e: Option<Expr> = None;
    for k in 0..3 {
        let q = &p[0] * r[0][k] + &p[1] * r[1][k] + &p[2] * r[2][k];
        let faces = (half[k] - &q).min(&(half[k] + &q));
        e = Some(match e {
            None => faces,
            Some(g) => g.min(&faces),
        });
    }
    let e = e.ok_or("no faces")?;
    let world = |q: [f64; 3]| -> [f64; 3] {
        std::array::from_fn(|i| (0..3).map(|k| r[i][k] * q[k]).sum::<f64>())
    };
    let corners: Vec<[f64; 3]> = (0..8)
        .map(|c| std::array::from_fn(|k| if c >> k & 1 == 1 { half[k] } else { -half[k] }))
        .collect();
    let mut edges = Vec::new();
    for (i, a) in corners.iter().enumerate() {
        for b in &corners[i + 1..] {
            if (0..3).filter(|&k| a[k] != b[k]).count() == 1 {
                for t in 1..40 {
                    let t = t as f64 / 40.0;
                    edges.push(world(std::array::from_fn(|k| a[k] + t * (b[k] - a[k]))));
                }
            }
        }
    }
    let corners: Vec<[f64; 3]> = corners.into_iter().map(world).collect();
    let exact = 8.0 * half[0] * half[1] * half[2];
    // Figures in cells of `h`: vertices off, edges, corners, volume error.
    let figures = |m: &Mesh, h: f64| -> String {
        let vertex = m
            .vertices
            .iter()
            .map(|v| {
                let v = v.map(|c| c as f64);
                let q: [f64; 3] = std::array::from_fn(|k| (0..3).map(|i| r[i][k] * v[i]).sum());
                let out: [f64; 3] = std::array::from_fn(|k| (q[k].abs() - half[k]).max(0.0));
                let o = (out[0] * out[0] + out[1] * out[1] + out[2] * out[2]).sqrt();
                if o > 0.0 {
                    o
                } else {
                    (0..3)
                        .map(|k| half[k] - q[k].abs())
                        .fold(f64::INFINITY, f64::min)
                }
            })
            .fold(0.0, f64::max);
        let far = |pts: &[[f64; 3]]| pts.iter().map(|&q| to_mesh(m, q)).fold(0.0, f64::max);
        let c = check(m);
        format!(
            "vertex_cells={:.4} edge_cells={:.4} corner_cells={:.4} vol_err={:.2e} tris={} bad_edges={}",
            vertex / h,
            far(&edges) / h,
            far(&corners) / h,
            (c.volume.abs() - exact) / exact,
            c.triangles,
            c.bad_edges
        )
    };
    let (ctx, root) = translate(&e)?;
    let shape = Shape::<JitFunction>::new(&ctx, root).map_err(|e| e.to_string())?;
    let bound: BoundShape<JitFunction, f32> = shape.try_into().map_err(|e| format!("{e:?}"))?;
    for (n, depth) in [(32usize, 5u8), (64, 6)] {
        let run_ours = |sharp: bool| -> Result<(Mesh, f64), String> {
            let mut o = MeshOptions::new([[-1.0; 3], [1.0; 3]], n);
            o.sharp = sharp;
            let mut ts = vec![];
            let mut kept = None;
            for _ in 0..REPS {
                let t = Instant::now();
                let m = ours.install(|| {
                    Plan::new(&microfrep_core::Shape::from(&e), &o)
                        .and_then(|p| p.run(&|_| {}))
                        .map_err(|e| e.to_string())
                })?;
                ts.push(t.elapsed().as_secs_f64());
                kept = Some(m);
            }
            Ok((kept.ok_or("no rounds")?, median(ts)))
        };
        let h = microfrep_mesh::Grid::new([[-1.0; 3], [1.0; 3]], n, 32)
            .map_err(|e| e.to_string())?
            .h;
        let (plain, plain_s) = run_ours(false)?;
        let (sharp, sharp_s) = run_ours(true)?;
        // The sharp mesh with its flat regions merged at 0.05 cells.
        let tape = Plan::new(
            &microfrep_core::Shape::from(&e),
            &MeshOptions::new([[-1.0; 3], [1.0; 3]], n),
        )
        .map_err(|e| e.to_string())?
        .tape;
        let mut merged = sharp.clone();
        let t = Instant::now();
        microfrep_mesh::decimate::decimate(&mut merged, &tape, h, 0.05 * h);
        let merge_s = t.elapsed().as_secs_f64();
        let settings = fidget::mesh::Settings {
            depth,
            threads: Some(theirs),
            ..Default::default()
        };
        let mut ts = vec![];
        let mut kept = None;
        for _ in 0..REPS {
            let t = Instant::now();
            let fm = fidget::mesh::Octree::build(&bound, &settings)
                .ok_or("fidget meshing was cancelled")?
                .walk_dual();
            ts.push(t.elapsed().as_secs_f64());
            kept = Some(fm);
        }
        let fm = kept.ok_or("no rounds")?;
        let fm = from_fidget(&fm);
        // fidget's cells: 2 / 2^depth.
        let fh = 2.0 / (1u32 << depth) as f64;
        println!(
            "RESULT rotated_box_{n} sharp: {} s={sharp_s:.4} | sharp_tolerance_0.05: {} \
             merge_s={merge_s:.4} | plain: {} s={plain_s:.4} | fidget_depth_{depth}: {} s={:.4}",
            figures(&sharp, h),
            figures(&merged, h),
            figures(&plain, h),
            figures(&fm, fh),
            median(ts)
        );
    }
    Ok(())
}

/// The whole `microfrep mesh` job (bounds found by interval analysis, the
/// termination and precision probes, meshing, the mesh check, the
/// sampled-volume check, the STL written atomically) against meshing
/// alone (`Plan::run` in the same box, found beforehand), on a 20 mm cube
/// of 4 mm gyroid sheets at 256 cells, 2 threads. Each job starts from a
/// fresh shape, so it finds the bounds itself (`bounds_s`: that search
/// alone). Target: the job at most 1.5x the meshing.
fn gyroid_sheet_job(pool: &rayon::ThreadPool) -> Result<(), String> {
    use microfrep_core::{Expr, Shape};
    use microfrep_mesh::job::{mesh_to_file, JobOptions};
    use microfrep_structures::tpms::{tpms, Solid, Tpms};
    let p = Expr::xyz();
    let cube = microfrep_shapes::block(
        &p,
        &microfrep_shapes::v3([0.0; 3]),
        &microfrep_shapes::v3([20.0; 3]),
    );
    let model = cube.min(tpms(Tpms::Gyroid, Solid::Sheet, &p, 4.0, 0.3));
    let shape = Shape::new(model.clone());
    let t = Instant::now();
    let b = shape.bounds().map_err(|e| e.to_string())?.corners();
    let bounds_s = t.elapsed().as_secs_f64();
    let out =
        std::env::temp_dir().join(format!("microfrep-bench-gyroid-{}.stl", std::process::id()));
    let mut best = [f64::INFINITY; 2];
    let mut figures = (0, 0, 0.0);
    for _ in 0..3 {
        let t = Instant::now();
        let m = pool.install(|| {
            Plan::new(&shape, &MeshOptions::new(b, 256))
                .and_then(|p| p.run(&|_| {}))
                .map_err(|e| e.to_string())
        })?;
        best[0] = best[0].min(t.elapsed().as_secs_f64());
        drop(m);
        let _ = std::fs::remove_file(&out);
        let t = Instant::now();
        let s = pool.install(|| {
            let shape = Shape::new(model.clone());
            let b = shape.bounds().map_err(|e| e.to_string())?.corners();
            mesh_to_file(
                &shape,
                &MeshOptions::new(b, 256),
                &out,
                &JobOptions::default(),
                &|_, _| {},
            )
            .map_err(|e| e.to_string())
        })?;
        best[1] = best[1].min(t.elapsed().as_secs_f64());
        figures = (s.triangles, s.bad_edges.unwrap_or(usize::MAX), s.volume);
    }
    let _ = std::fs::remove_file(&out);
    println!(
        "RESULT gyroid_sheet_job_256 mesh_only_s={:.3} job_to_stl_s={:.3} ratio={:.2} target=1.5 \
         bounds_s={bounds_s:.3} triangles={} bad_edges={} volume={:.4} runs=3 threads={THREADS}",
        best[0],
        best[1],
        best[1] / best[0],
        figures.0,
        figures.1,
        figures.2,
    );
    Ok(())
}
