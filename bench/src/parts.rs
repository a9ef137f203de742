//! Suite `parts`: triangle meshes as signed distance fields
//! (microfrep-meshfield) against libigl's `signed_distance` with the fast
//! winding number sign, on the same mesh and points, 2 threads each (ours: a
//! rayon pool of 2, one `eval_batch` call per block of 256 points; libigl:
//! `IGL_NUM_THREADS=2`). Cases: the femur of ../shared/meshes welded
//! (watertight: pseudo-normal sign) and as read (an unwelded soup: winding
//! number sign), 200k points uniform in the bbox grown by 10 %; then the BVH
//! build and the whole field build of a 1M-triangle sphere, and the peak
//! resident memory of this process (VmHWM) after it. libigl runs from
//! `target/libigl-venv` (or `MICROFREP_LIBIGL_PYTHON`), created on first
//! use; its columns read `na` if that fails. Last, `fill` end to end: a
//! 100k-triangle torus part filled with a 2 mm gyroid and meshed at 0.1 mm
//! to STL (target under 30 s), with its peak memory; and the README's femur
//! job, `microfrep fill` against the script a user would write with libigl,
//! NumPy, scikit-image and trimesh (bench/fill_pipeline.py) at 256, 512 and
//! 1024 cells (`fill_vs_pipeline_N`).

use microfrep_core::Field;
use microfrep_meshfield::bvh::Bvh;
use microfrep_meshfield::read::read_mesh;
use microfrep_meshfield::{BuildOptions, MeshField, SignMethod, TriMesh};
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

const POINTS: usize = 200_000;
const SCRIPT: &str = "crates/meshfield/tests/libigl_sd.py";

pub fn run() -> Result<(), String> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .map_err(|e| e.to_string())?;
    let dir = PathBuf::from("target/parts-bench");
    std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
    let python = libigl_python(&dir);
    let femur = Path::new("../shared/meshes/femur.stl");
    if femur.exists() {
        let raw = read_mesh(femur).map_err(|e| e.to_string())?;
        let welded = raw.weld(0.0).0;
        for (tag, mesh) in [("femur", &welded), ("femur_soup", &raw)] {
            queries(&pool, &dir, python.as_deref(), tag, mesh)?;
        }
    } else {
        eprintln!("bench/run parts: ../shared/meshes/femur.stl not found; query cases skipped");
    }
    build_1m(&pool)?;
    fill_part(&pool, &dir)?;
    if femur.exists() {
        stl_vs_hf(&dir, femur)?;
    }
    fill_vs_pipeline(&dir)
}

/// The README's femur fill written both as a mesh (a 440k-triangle STL) and
/// as its model (`.hf` with the femur bound as its part), then `microfrep
/// render` (default size) and `microfrep analyze` of each, interleaved,
/// best of 2, the whole CLI process timed. Targets: the STL within 2x of
/// the `.hf` for both.
fn stl_vs_hf(dir: &Path, femur: &Path) -> Result<(), String> {
    let cli = cli_binary()?;
    let run = |args: &[&str]| -> Result<f64, String> {
        let t = Instant::now();
        let out = Command::new(&cli)
            .args(args)
            .output()
            .map_err(|e| e.to_string())?;
        if !out.status.success() {
            return Err(format!(
                "microfrep {}: {}",
                args.join(" "),
                String::from_utf8_lossy(&out.stderr)
            ));
        }
        Ok(t.elapsed().as_secs_f64())
    };
    let femur = femur.to_str().ok_or("femur path is not UTF-8")?;
    let stl = dir.join("femur_gyroid.stl");
    let hf = dir.join("femur_gyroid.hf");
    let (stl, hf) = (
        stl.to_str().ok_or("path is not UTF-8")?,
        hf.to_str().ok_or("path is not UTF-8")?,
    );
    for out in [stl, hf] {
        let _ = std::fs::remove_file(out);
        run(&[
            "fill",
            femur,
            "--structure",
            "gyroid",
            "--cell",
            "12",
            "--density",
            "0.3",
            "--shell",
            "2",
            "-o",
            out,
        ])?;
    }
    let part = format!("part={femur}");
    let png = dir.join("render.png");
    let png = png.to_str().ok_or("path is not UTF-8")?;
    for verb in ["render", "analyze"] {
        let mut best = [f64::INFINITY; 2];
        for _ in 0..2 {
            let _ = std::fs::remove_file(png);
            let mesh_args: Vec<&str> = match verb {
                "render" => vec!["render", stl, "-o", png],
                _ => vec!["analyze", stl],
            };
            best[0] = best[0].min(run(&mesh_args)?);
            let _ = std::fs::remove_file(png);
            let model_args: Vec<&str> = match verb {
                "render" => vec!["render", hf, "--field", &part, "-o", png],
                _ => vec!["analyze", hf, "--field", &part],
            };
            best[1] = best[1].min(run(&model_args)?);
        }
        println!(
            "RESULT {verb}_stl_vs_hf femur_gyroid stl_s={:.2} hf_s={:.2} ratio={:.2} target=2 runs=2",
            best[0],
            best[1],
            best[0] / best[1]
        );
    }
    Ok(())
}

/// The femur job of the README, `microfrep fill femur.stl --structure
/// gyroid --cell 12 --density 0.3 --shell 2 --resolution N -o x.stl` (the
/// whole process, its measured report included), against the script a
/// user would write instead (bench/fill_pipeline.py: libigl's signed
/// distance on a grid, a NumPy gyroid with the skin, scikit-image's
/// marching cubes, trimesh's STL), run in the same bench, at N = 256, 512
/// and 1024 cells on the longest side. `fill` refuses a resolution whose
/// cells are more than half the skin or the thinnest wall measured; then
/// it runs again with `--resolution auto` and the line gives both
/// resolutions. The peer runs from `target/fill-peer-venv` (or
/// `MICROFREP_FILL_PEER_PYTHON`), created on first use; its columns read
/// `na` if that fails or if the grid would need more than half the memory.
fn fill_vs_pipeline(dir: &Path) -> Result<(), String> {
    let femur = Path::new("../shared/meshes/femur.stl");
    if !femur.exists() {
        eprintln!(
            "bench/run parts: ../shared/meshes/femur.stl not found; fill_vs_pipeline skipped"
        );
        return Ok(());
    }
    let spec = microfrep_testsupport::pyvenv::PythonSpec {
        override_var: "MICROFREP_FILL_PEER_PYTHON",
        venv: Path::new("target/fill-peer-venv"),
        check: "import igl, numpy, skimage, trimesh",
        packages: &["libigl", "numpy", "scikit-image", "trimesh"],
        log: &dir.join("fill-peer-install.log"),
    };
    let python = microfrep_testsupport::pyvenv::python_with(&spec)
        .map_err(|e| {
            eprintln!("bench/run parts: the fill peer is not available ({e}); its columns read na")
        })
        .ok();
    let cli = cli_binary()?;
    let mesh = read_mesh(femur).map_err(|e| e.to_string())?;
    let [lo, hi] = mesh.bbox();
    let size: [f64; 3] = std::array::from_fn(|a| hi[a] - lo[a]);
    let longest = size.iter().copied().fold(0.0, f64::max);
    let out = dir.join("femur_fill.stl");
    let peer_out = dir.join("femur_peer.stl");
    for n in [256usize, 512, 1024] {
        // The peer's grid: about 7 float32 volumes alive at its peak.
        let h = longest / n as f64;
        let nodes: f64 = size.iter().map(|s| (s / h).ceil() + 5.0).product();
        let fits = nodes * 4.0 * 7.0
            < 0.5 * microfrep::io::limits::memory_limit().unwrap_or(f64::INFINITY);
        let peer = match (&python, fits) {
            (Some(py), true) => {
                let t = Instant::now();
                let o = Command::new(py)
                    .arg("bench/fill_pipeline.py")
                    .arg(femur)
                    .args([n.to_string(), "12".into(), "0.3".into(), "2".into()])
                    .arg(&peer_out)
                    .output()
                    .map_err(|e| e.to_string())?;
                let s = t.elapsed().as_secs_f64();
                if o.status.success() {
                    let j: serde_json::Value =
                        serde_json::from_slice(&o.stdout).unwrap_or_default();
                    Some((s, j))
                } else {
                    eprintln!(
                        "bench/run parts: the fill peer failed at {n}: {}",
                        String::from_utf8_lossy(&o.stderr)
                    );
                    None
                }
            }
            (Some(_), false) => {
                eprintln!("bench/run parts: the fill peer at {n} would need more than half the memory; na");
                None
            }
            (None, _) => None,
        };
        let _ = std::fs::remove_file(&peer_out);
        let run = |res: &str| -> Result<(f64, Option<serde_json::Value>, String), String> {
            let _ = std::fs::remove_file(&out);
            let t = Instant::now();
            let o = Command::new(&cli)
                .arg("fill")
                .arg(femur)
                .args([
                    "--structure",
                    "gyroid",
                    "--cell",
                    "12",
                    "--density",
                    "0.3",
                    "--shell",
                    "2",
                ])
                .args(["--resolution", res, "--json", "-o"])
                .arg(&out)
                .output()
                .map_err(|e| e.to_string())?;
            let s = t.elapsed().as_secs_f64();
            let j = o
                .status
                .success()
                .then(|| serde_json::from_slice(&o.stdout).ok())
                .flatten();
            Ok((s, j, String::from_utf8_lossy(&o.stderr).into_owned()))
        };
        let (mut fill_s, mut j, why) = run(&n.to_string())?;
        let mut refused_s = None;
        if j.is_none() {
            eprintln!(
                "bench/run parts: fill --resolution {n} refused ({}); again with auto",
                why.trim()
            );
            refused_s = Some(fill_s);
            (fill_s, j, _) = run("auto")?;
        }
        let _ = std::fs::remove_file(&out);
        let Some(j) = j else {
            eprintln!("bench/run parts: fill of the femur failed at {n}");
            continue;
        };
        let num = |v: &serde_json::Value| v.as_f64().map_or("na".to_string(), |x| format!("{x}"));
        let peer_s = peer.as_ref().map(|p| p.0);
        println!(
            "RESULT fill_vs_pipeline_{n} part=femur structure=gyroid cell_mm=12 density=0.3 skin_mm=2 \
             pipeline_resolution={n} pipeline_s={} pipeline_sd_s={} pipeline_triangles={} \
             fill_resolution={} fill_s={fill_s:.2} ratio={} report_s={} fill_triangles={} \
             measured_density={} measured_skin_min={} refused_{n}_s={}",
            fmt(peer_s, 2),
            peer.as_ref().map_or("na".into(), |p| fmt(p.1["steps"]["signed_distance"].as_f64(), 2)),
            peer.as_ref().map_or("na".into(), |p| num(&p.1["triangles"])),
            num(&j["written"]["resolution"]),
            fmt(peer_s.map(|p| p / fill_s), 2),
            fmt(j["measured"]["seconds"].as_f64(), 2),
            num(&j["written"]["triangles"]),
            fmt(j["density"]["measured"].as_f64(), 4),
            fmt(j["skin"]["min"].as_f64(), 3),
            fmt(refused_s, 2),
        );
    }
    Ok(())
}

/// The CLI binary beside this one (target/release/microfrep), built first
/// so it is the current code.
fn cli_binary() -> Result<PathBuf, String> {
    let ok = Command::new("cargo")
        .args(["build", "--quiet", "--release", "-p", "microfrep-cli"])
        .status()
        .is_ok_and(|s| s.success());
    let exe = std::env::current_exe().map_err(|e| e.to_string())?;
    let cli = exe.with_file_name("microfrep");
    if !ok || !cli.exists() {
        return Err(format!("cannot build the CLI ({})", cli.display()));
    }
    Ok(cli)
}

/// The main job end to end on a part of about 100k triangles: a torus
/// (major radius 12 mm, minor 5 mm) meshed by microfrep to STL, read back
/// as a mesh part, filled with a 2 mm gyroid network at 30 % inside a
/// 0.3 mm skin, and meshed at 0.1 mm cells to STL, as `microfrep fill PART
/// --structure gyroid --cell 2 --density 0.3 --shell 0.3 --voxel 0.1 -o
/// OUT.stl` does (figures excluded). Target: under 30 s.
fn fill_part(pool: &rayon::ThreadPool, dir: &Path) -> Result<(), String> {
    use microfrep::fill::{fill, Density, FillOptions, Part, Structure};
    use microfrep::mesh::job::{mesh_to_file, JobOptions};
    use microfrep::mesh::{Grid, MeshOptions};
    use microfrep_shapes as prims;
    let part = dir.join("torus_part.stl");
    let torus = microfrep_core::Shape::new(prims::torus(
        &microfrep_core::Expr::xyz(),
        &prims::v3([0.0; 3]),
        2,
        12.0,
        5.0,
    ));
    let pb = [[-17.5, -17.5, -5.5], [17.5, 17.5, 5.5]];
    let ps = pool
        .install(|| {
            mesh_to_file(
                &torus,
                &MeshOptions::new(pb, 135),
                &part,
                &JobOptions::default(),
                &|_, _| {},
            )
        })
        .map_err(|e| e.to_string())?;
    let opts = FillOptions {
        structure: Structure::parse("gyroid", false).ok_or("no gyroid")?,
        cell: 2.0,
        density: Density::Constant(0.3),
        skin: Some(0.3),
        seed: 1,
        pores: Default::default(),
        material_layers: Vec::new(),
    };
    let out = dir.join("torus_gyroid.stl");
    let _ = std::fs::remove_file(&out);
    drop(torus);
    // The peak from here on is this job's (Linux resets VmHWM on "5").
    let _ = std::fs::write("/proc/self/clear_refs", "5");
    let t = Instant::now();
    let (filled_s, m) = pool.install(|| -> Result<_, String> {
        let progress = |_: &str, _: u64, _: u64| {};
        let p = Part::load(
            part.to_str().ok_or("path")?,
            &microfrep::LoadOptions::default(),
            None,
            &progress,
        )
        .map_err(|e| e.to_string())?;
        let f = fill(&p, &opts, &progress).map_err(|e| e.to_string())?;
        let filled_s = t.elapsed().as_secs_f64();
        let b = f.bounds.corners();
        let n = Grid::resolution_for_voxel(b, 0.1).map_err(|e| e.to_string())?;
        let m = mesh_to_file(
            &f.model,
            &MeshOptions::new(b, n),
            &out,
            &JobOptions::default(),
            &|_, _| {},
        )
        .map_err(|e| e.to_string())?;
        Ok((filled_s, m))
    })?;
    let total_s = t.elapsed().as_secs_f64();
    let bytes = std::fs::metadata(&out).map(|m| m.len()).unwrap_or(0);
    println!(
        "RESULT parts_fill_torus_gyroid part_triangles={} cell_mm=2 density=0.3 skin_mm=0.3 voxel_mm=0.1 \
         resolution={} threads=2 load_and_fill_s={filled_s:.2} total_s={total_s:.2} target_s=30 \
         triangles={} bad_edges={} stl_mib={:.0} peak_mib={:.0}",
        ps.triangles,
        m.resolution,
        m.triangles,
        m.bad_edges.map_or("na".to_string(), |b| b.to_string()),
        bytes as f64 / (1u64 << 20) as f64,
        peak_mib(),
    );
    let _ = std::fs::remove_file(&out);
    Ok(())
}

/// Splitmix64 points uniform in the bbox grown by 10 %.
fn points(m: &TriMesh, n: usize) -> Vec<[f64; 3]> {
    let [lo, hi] = m.bbox();
    let mut s = 0x1234_5678u64;
    let mut unit = || {
        s = s.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = s;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..n)
        .map(|_| {
            [0, 1, 2].map(|a| {
                let w = hi[a] - lo[a];
                // On the f32 grid, so both sides see the same points.
                (lo[a] - 0.1 * w + 1.2 * w * unit()) as f32 as f64
            })
        })
        .collect()
}

fn queries(
    pool: &rayon::ThreadPool,
    dir: &Path,
    python: Option<&Path>,
    tag: &str,
    mesh: &TriMesh,
) -> Result<(), String> {
    let t = Instant::now();
    let field = pool
        .install(|| MeshField::build(mesh, &BuildOptions::default(), &|_, _| {}))
        .map_err(|e| e.to_string())?;
    let build_s = t.elapsed().as_secs_f64();
    let pts = points(mesh, POINTS);
    let (x, y, z): (Vec<f32>, Vec<f32>, Vec<f32>) = (
        pts.iter().map(|p| p[0] as f32).collect(),
        pts.iter().map(|p| p[1] as f32).collect(),
        pts.iter().map(|p| p[2] as f32).collect(),
    );
    let mut out = vec![0f32; POINTS];
    let mut best = f64::INFINITY;
    for _ in 0..3 {
        let t = Instant::now();
        pool.install(|| {
            out.par_chunks_mut(256).enumerate().for_each(|(i, o)| {
                let r = i * 256..i * 256 + o.len();
                field.eval_batch(&x[r.clone()], &y[r.clone()], &z[r], o);
            })
        });
        best = best.min(t.elapsed().as_secs_f64());
    }
    let ours_qps = POINTS as f64 / best;
    // Point path, one thread, for reference.
    let t = Instant::now();
    let n1 = 20_000;
    let mut acc = 0.0;
    for p in &pts[..n1] {
        acc += field.eval(*p);
    }
    let point_qps = n1 as f64 / t.elapsed().as_secs_f64();
    std::hint::black_box(acc);
    let theirs = python.and_then(|py| match libigl(py, dir, tag, mesh, &pts) {
        Ok(r) => Some(r),
        Err(e) => {
            eprintln!("bench/run parts: libigl failed: {e}");
            None
        }
    });
    // Agreement: sign and distance (libigl's magnitudes in this mode are
    // approximate; the sign is compared where |d| > 1e-3 diagonal).
    let diag = mesh.diagonal();
    let agree = theirs.as_ref().map(|(_, s)| {
        let (mut n, mut same) = (0, 0);
        for i in 0..POINTS {
            if (out[i] as f64).abs() > 1e-3 * diag {
                n += 1;
                same += ((out[i] > 0.0) == (s[i] > 0.0)) as usize;
            }
        }
        same as f64 / n as f64
    });
    let igl_qps = theirs.as_ref().map(|(q, _)| *q);
    println!(
        "RESULT parts_queries_{tag} triangles={} sign={:?} points={POINTS} threads=2 \
         microfrep_qps={ours_qps:.0} libigl_qps={} ratio={} microfrep_point_qps_1thread={point_qps:.0} \
         microfrep_build_s={build_s:.4} sign_agreement={}",
        mesh.triangles.len(),
        field.sign_method(),
        fmt(igl_qps, 0),
        fmt(igl_qps.map(|q| ours_qps / q), 2),
        fmt(agree, 5),
    );
    Ok(())
}

fn fmt(v: Option<f64>, digits: usize) -> String {
    v.map_or("na".to_string(), |v| format!("{v:.digits$}"))
}

/// A UV sphere of radius 50 with about `n` triangles.
fn fine_sphere(n: usize) -> TriMesh {
    let k = ((n as f64 / 2.0).sqrt()) as usize;
    let (nu, nv) = (k, k);
    let mut v = vec![[0.0, 0.0, -50.0], [0.0, 0.0, 50.0]];
    for j in 1..nv {
        let th = std::f64::consts::PI * j as f64 / nv as f64;
        for i in 0..nu {
            let ph = 2.0 * std::f64::consts::PI * i as f64 / nu as f64;
            v.push([
                50.0 * th.sin() * ph.cos(),
                50.0 * th.sin() * ph.sin(),
                -50.0 * th.cos(),
            ]);
        }
    }
    let id = |i: usize, j: usize| (2 + (j - 1) * nu + i % nu) as u32;
    let mut t = Vec::new();
    for i in 0..nu {
        t.push([0, id(i + 1, 1), id(i, 1)]);
        t.push([1, id(i, nv - 1), id(i + 1, nv - 1)]);
        for j in 1..nv - 1 {
            t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    let mut m = TriMesh::new(v, t).expect("sphere");
    if m.volume() < 0.0 {
        for tri in &mut m.triangles {
            tri.swap(1, 2);
        }
    }
    m
}

fn build_1m(pool: &rayon::ThreadPool) -> Result<(), String> {
    let mesh = fine_sphere(1_000_000);
    let n = mesh.triangles.len();
    let mut bvh_s = f64::INFINITY;
    let mut depth = 0;
    let mut nodes = 0;
    for _ in 0..3 {
        let t = Instant::now();
        let bvh = pool.install(|| Bvh::build(&mesh, &|_, _| {}, 0, n as u64));
        bvh_s = bvh_s.min(t.elapsed().as_secs_f64());
        depth = bvh.depth();
        nodes = bvh.nodes.len();
    }
    let before = peak_mib();
    let t = Instant::now();
    let field = pool
        .install(|| MeshField::build(&mesh, &BuildOptions::default(), &|_, _| {}))
        .map_err(|e| e.to_string())?;
    let field_s = t.elapsed().as_secs_f64();
    let sign = field.sign_method();
    drop(field);
    let t = Instant::now();
    let opts = BuildOptions {
        sign: SignMethod::Winding,
        ..Default::default()
    };
    let wfield = pool
        .install(|| MeshField::build(&mesh, &opts, &|_, _| {}))
        .map_err(|e| e.to_string())?;
    let winding_s = t.elapsed().as_secs_f64();
    std::hint::black_box(wfield.eval([1.0, 2.0, 3.0]));
    drop(wfield);
    println!(
        "RESULT parts_build_1m triangles={n} threads=2 bvh_build_s={bvh_s:.3} bvh_nodes={nodes} \
         bvh_depth={depth} field_build_s={field_s:.3} field_sign={sign:?} winding_field_build_s={winding_s:.3} \
         peak_mib={:.0} peak_before_fields_mib={before:.0} predicted_pseudo_mib={} predicted_winding_mib={}",
        peak_mib(),
        MeshField::predict_memory(n as u64, mesh.vertices.len() as u64, SignMethod::PseudoNormal) >> 20,
        MeshField::predict_memory(n as u64, mesh.vertices.len() as u64, SignMethod::Winding) >> 20,
    );
    Ok(())
}

/// Peak resident memory of this process (VmHWM), MiB.
fn peak_mib() -> f64 {
    let s = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    s.lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<f64>().ok())
        .map_or(f64::NAN, |kib| kib / 1024.0)
}

/// libigl's queries per second and signed values (positive inside).
fn libigl(
    py: &Path,
    dir: &Path,
    tag: &str,
    m: &TriMesh,
    pts: &[[f64; 3]],
) -> Result<(f64, Vec<f64>), String> {
    let w = |name: &str, bytes: Vec<u8>| -> Result<PathBuf, String> {
        let p = dir.join(format!("{tag}.{name}"));
        std::fs::write(&p, bytes).map_err(|e| e.to_string())?;
        Ok(p)
    };
    let v = w(
        "v",
        m.vertices
            .iter()
            .flatten()
            .flat_map(|c| c.to_le_bytes())
            .collect(),
    )?;
    let f = w(
        "f",
        m.triangles
            .iter()
            .flatten()
            .flat_map(|&i| (i as i64).to_le_bytes())
            .collect(),
    )?;
    let p = w(
        "p",
        pts.iter().flatten().flat_map(|c| c.to_le_bytes()).collect(),
    )?;
    let o = dir.join(format!("{tag}.s"));
    let out = Command::new(py)
        .arg(SCRIPT)
        .args([&v, &f, &p, &o])
        .arg("3")
        .env("IGL_NUM_THREADS", "2")
        .output()
        .map_err(|e| e.to_string())?;
    if !out.status.success() {
        return Err(String::from_utf8_lossy(&out.stderr).into_owned());
    }
    let text = String::from_utf8_lossy(&out.stdout);
    let at = text.find("\"qps\":").ok_or("no qps in libigl output")? + 6;
    let rest = text[at..].trim_start();
    let qps: f64 = rest[..rest.find([',', '}']).unwrap_or(rest.len())]
        .trim()
        .parse()
        .map_err(|e| format!("{e}"))?;
    let s = std::fs::read(&o)
        .map_err(|e| e.to_string())?
        .chunks_exact(8)
        .map(|b| f64::from_le_bytes(b.try_into().unwrap()))
        .collect();
    Ok((qps, s))
}

/// The Python with libigl: `MICROFREP_LIBIGL_PYTHON`, or the venv under
/// target/, created on first use.
fn libigl_python(dir: &Path) -> Option<PathBuf> {
    let spec = microfrep_testsupport::pyvenv::PythonSpec {
        override_var: "MICROFREP_LIBIGL_PYTHON",
        venv: Path::new("target/libigl-venv"),
        check: "import igl, numpy",
        packages: &["libigl", "numpy"],
        log: &dir.join("libigl-install.log"),
    };
    microfrep_testsupport::pyvenv::python_with(&spec)
        .map_err(|e| eprintln!("bench/run parts: libigl not available ({e}); its columns read na"))
        .ok()
}
