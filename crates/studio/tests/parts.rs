//! Mesh parts in the studio: a model that binds `../shared/meshes/femur.stl`
//! (copied under a scratch working directory) with a `--field part=FILE`
//! comment, as `microfrep fill` writes it, or with the edit's `fields`.
//! The part is built once and kept, its box is taken as the model's box
//! where intervals prove the model inside it, the meshes go coarse to fine,
//! and the time to the first image is printed next to a formula model's
//! (the tori-ball block, as the `studio` bench suite uses).
//!
//! A large scan (a synthetic 256^3 NRRD, made here) comes first as a
//! coarse stand-in, then the full scan.
//!
//! Run `cargo test --release -p microfrep-studio --test parts -- --nocapture
//! --test-threads 1` for the table. The femur test is skipped, with a
//! message, where `../shared/meshes/` is absent.

use microfrep_studio::client::Client;
use microfrep_studio::{wire, ServeOptions, Studio};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::time::Duration;

fn femur() -> Option<PathBuf> {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/meshes/femur.stl");
    p.is_file().then_some(p)
}

/// Triangles of a binary STL.
fn stl_triangles(bytes: &[u8]) -> Vec<[[f64; 3]; 3]> {
    let n = u32::from_le_bytes(bytes[80..84].try_into().unwrap()) as usize;
    assert_eq!(bytes.len(), 84 + 50 * n, "not a binary STL");
    (0..n)
        .map(|t| {
            let at = 84 + 50 * t + 12;
            std::array::from_fn(|v| {
                std::array::from_fn(|a| {
                    let o = at + 12 * v + 4 * a;
                    f32::from_le_bytes(bytes[o..o + 4].try_into().unwrap()) as f64
                })
            })
        })
        .collect()
}

fn signed_volume(tris: impl Iterator<Item = [[f64; 3]; 3]>) -> f64 {
    tris.map(|[a, b, c]| {
        (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
            + a[2] * (b[0] * c[1] - b[1] * c[0]))
            / 6.0
    })
    .sum()
}

fn post(c: &Client, body: Value) -> Value {
    c.post_json("/api/edit", &body).unwrap()
}

fn wait(c: &Client, s: &str, gen: u64) -> Value {
    let st = c
        .get_json(&format!("/api/wait?session={s}&gen={gen}&wait_ms=120000"))
        .unwrap();
    assert_eq!(st["finished"], json!(true), "generation {gen}: {st}");
    st
}

/// Posts `src` and waits for every stage; the final state.
fn run(c: &Client, s: &str, src: &str, extra: Value) -> Value {
    let mut body = json!({"session": s, "source": src, "file": "m.hf", "wait_ms": 0});
    if let Value::Object(m) = extra {
        for (k, v) in m {
            body[k] = v;
        }
    }
    let gen = post(c, body)["latest_gen"].as_u64().unwrap();
    wait(c, s, gen)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

/// Posts `src` and waits until its quick analysis is in (the worker then
/// waits for the model to settle, so the next edit stops nothing); the
/// first-image seconds.
fn first_image(c: &Client, s: &str, src: &str) -> f64 {
    let body = json!({"session": s, "source": src, "file": "m.hf", "wait_ms": 0});
    let gen = post(c, body)["latest_gen"].as_u64().unwrap();
    let mut since = 0;
    loop {
        let st = c
            .get_json(&format!(
                "/api/state?session={s}&since={since}&wait_ms=10000"
            ))
            .unwrap();
        since = st["version"].as_u64().unwrap();
        if st["gen"] == json!(gen) {
            assert!(st["error"].is_null(), "{st}");
            if st["timings"]["quick_analysis_s"].is_number() {
                return st["timings"]["first_mesh_s"].as_f64().unwrap();
            }
        }
    }
}

/// First-image seconds of a cold edit and the median of `n` warm ones (each
/// edit changes a comment), and the state of one more edit run to the end.
fn first_images(c: &Client, src: &str, n: usize) -> (f64, f64, Value) {
    let s = c.post_json("/api/session", &json!({})).unwrap()["session"]
        .as_str()
        .unwrap()
        .to_string();
    let cold = first_image(c, &s, src);
    let warm: Vec<f64> = (0..n)
        .map(|k| first_image(c, &s, &format!("{src}-- edit {k}\n")))
        .collect();
    let last = run(c, &s, &format!("{src}-- last\n"), json!({}));
    assert!(last["error"].is_null(), "{last}");
    (cold, median(warm), last)
}

const FEMUR: &str = "-- The femur alone.\n-- The part is a data field: load with --field part=parts/femur.stl\nmy_model(x[3], a[1]) {\n  my_model = part(x);\n}\n";

/// A gyroid of 12 mm cells inside a 2 mm skin, as `microfrep fill` makes.
const FEMUR_FILL: &str = "-- The femur filled with a gyroid.\n-- load with --field part=parts/femur.stl\nmy_model(x[3], a[1]) {\n  w = 2 * 3.14159265 / 12;\n  g = sin(w*x[1])*cos(w*x[2]) + sin(w*x[2])*cos(w*x[3]) + sin(w*x[3])*cos(w*x[1]);\n  skin = min(part(x), 2 - part(x));\n  my_model = max(skin, min(part(x), 0.45 - abs(g)));\n}\n";

#[test]
fn mesh_parts_come_coarse_to_fine_as_fast_as_formulas() {
    let Some(stl) = femur() else {
        println!("skipped: ../shared/meshes/femur.stl is not there");
        return;
    };
    let dir = std::env::temp_dir().join(format!("mf-studio-parts-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("parts")).unwrap();
    std::fs::copy(&stl, dir.join("parts/femur.stl")).unwrap();
    let stl_bytes = std::fs::read(&stl).unwrap();
    let femur_tris = stl_triangles(&stl_bytes);
    let femur_volume = signed_volume(femur_tris.iter().copied()).abs();
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for t in &femur_tris {
        for p in t {
            for a in 0..3 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
    }
    // The studio's defaults (meshes at 48, 128, 192; analysis at 64, 128),
    // refinement a second after an edit, so that edits posted once the
    // quick analysis is in stop no work.
    let studio = Studio::start(ServeOptions {
        port: 0,
        root: dir.clone(),
        settle: Duration::from_secs(1),
        ..ServeOptions::default()
    })
    .unwrap();
    let c = studio.client();
    let formula = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../examples/fryazinov_fig4_toriball_block.hf"),
    )
    .unwrap();

    let (f_cold, f_warm, _) = first_images(&c, &formula, 3);
    let (p_cold, p_warm, st) = first_images(&c, FEMUR, 3);
    // The part: built on the first edit, kept for the next.
    let parts = st["parts"].as_array().unwrap();
    assert_eq!(parts.len(), 1, "{st}");
    assert_eq!(parts[0]["name"], "part");
    assert_eq!(parts[0]["source"], "parts/femur.stl");
    assert_eq!(parts[0]["kind"], "mesh");
    assert_eq!(parts[0]["cached"], true);
    // Its box, proven to hold the model, instead of a bounds search.
    let m = &st["model"];
    assert_eq!(m["bounds_source"], "part", "{m}");
    let b: Vec<Vec<f64>> = serde_json::from_value(m["bounds"].clone()).unwrap();
    for a in 0..3 {
        let ext = hi[a] - lo[a];
        assert!(b[0][a] < lo[a] && b[1][a] > hi[a], "{b:?} vs {lo:?} {hi:?}");
        assert!(b[0][a] > lo[a] - 0.05 * ext && b[1][a] < hi[a] + 0.05 * ext);
    }
    // Coarse to fine, each mesh closed with the femur's volume.
    let meshes = st["meshes"].as_array().unwrap();
    let res: Vec<u64> = meshes
        .iter()
        .map(|m| m["resolution"].as_u64().unwrap())
        .collect();
    assert_eq!(res, vec![48, 128, 192], "{st}");
    let mut errors = Vec::new();
    for m in meshes {
        let blob = c.get(m["url"].as_str().unwrap()).unwrap();
        let (pos, _, _, tris) = wire::decode_mesh(&blob.body).unwrap();
        let v = signed_volume(
            tris.iter()
                .map(|t| t.map(|i| pos[i as usize].map(f64::from))),
        );
        errors.push((v - femur_volume).abs() / femur_volume);
    }
    assert!(errors[2] < 0.01, "volume errors {errors:?}");
    assert!(errors[0] < 0.15, "volume errors {errors:?}");
    let vf = st["analysis"]["refined"]["report"]["volume"]["value"]
        .as_f64()
        .unwrap();
    assert!(
        (vf - femur_volume).abs() < 0.03 * femur_volume,
        "{vf} vs {femur_volume}"
    );

    let (g_cold, g_warm, st) = first_images(&c, FEMUR_FILL, 3);
    assert_eq!(st["model"]["bounds_source"], "part");
    assert_eq!(st["parts"][0]["cached"], true);

    // A model that reaches out of its part: a ball 100 mm above the femur.
    // The part's box is refused, the bounds search finds the ball.
    let out = FEMUR.replace(
        "my_model = part(x);",
        "my_model = max(part(x), 20 - sqrt(x[1]^2 + x[2]^2 + (x[3] - 600)^2));",
    );
    let (o_cold, o_warm, st) = first_images(&c, &out, 1);
    assert_eq!(st["model"]["bounds_source"], "proven", "{st}");
    let top = st["model"]["bounds"][1][2].as_f64().unwrap();
    assert!(top > 619.0 && top < 640.0, "{st}");

    // The edit's `fields` bind a part without a comment.
    let s = c.post_json("/api/session", &json!({})).unwrap()["session"]
        .as_str()
        .unwrap()
        .to_string();
    let bare = "my_model(x[3], a[1]) {\n  my_model = bone(x);\n}\n";
    let st = run(&c, &s, bare, json!({"fields": {"bone": "parts/femur.stl"}}));
    assert!(st["error"].is_null(), "{st}");
    assert_eq!(st["parts"][0]["name"], "bone");
    assert_eq!(st["parts"][0]["cached"], true, "same file, same part");
    assert_eq!(st["meshes"].as_array().unwrap().len(), 3);
    // Unbound, the name is an unknown function, as in `microfrep check`.
    let st = run(&c, &s, bare, json!({}));
    assert!(st["model"].is_null());
    assert!(
        st["rendered"]
            .as_str()
            .unwrap()
            .contains("'bone' is not a known function"),
        "{st}"
    );
    // Parts outside the working directory, missing files and bad fields
    // are errors of the model.
    for (spec, says) in [
        ("../femur.stl", "'..' is not allowed"),
        ("parts/nope.stl", "cannot open"),
        ("parts/femur.stl:weld=-1", "must not be negative"),
    ] {
        let st = run(&c, &s, bare, json!({"fields": {"bone": spec}}));
        let r = st["rendered"].as_str().unwrap();
        assert!(
            r.contains(&format!("field bone={spec}: ")) && r.contains(says),
            "{st}"
        );
        assert!(st["model"].is_null() && st["diagnostics"][0]["severity"] == "error");
    }
    let r = c
        .request(
            "POST",
            "/api/edit",
            Some(
                json!({"session": s, "source": bare, "fields": {"1x": "a.stl"}})
                    .to_string()
                    .as_bytes(),
            ),
            &[],
        )
        .unwrap();
    assert_eq!(r.status, 400);

    println!("time to first image (mesh at 48 cells), seconds from the edit's arrival:");
    println!("| model | first edit | later edits (median) |");
    println!("| --- | --- | --- |");
    println!("| formula: tori-ball block (Box comment) | {f_cold:.3} | {f_warm:.3} |");
    println!("| femur.stl part alone | {p_cold:.3} | {p_warm:.3} |");
    println!("| femur.stl part, gyroid fill and skin | {g_cold:.3} | {g_warm:.3} |");
    println!(
        "| femur.stl part and a ball outside it (bounds searched) | {o_cold:.3} | {o_warm:.3} |"
    );
    // The part's box spares the bounds search: a later edit of the femur
    // comes as fast as the formula's (generous margins for a shared
    // machine).
    assert!(
        p_warm < 0.5 && p_warm < 3.0 * f_warm + 0.1,
        "{p_warm} vs {f_warm}"
    );
    studio.stop();
    let _ = std::fs::remove_dir_all(&dir);
}

/// An NRRD scan of `n`^3 bytes: an ellipsoid of semi-axes 0.7 c, 0.7 c and
/// 0.7 c / 1.2 voxels (c = (n - 1) / 2) about the centre, values falling
/// through 128 at its surface; `spacing` mm a voxel. Returns its volume in
/// mm^3.
fn write_scan(path: &Path, n: usize, spacing: f64) -> f64 {
    let c = (n - 1) as f64 / 2.0;
    let mut data = Vec::with_capacity(n * n * n);
    for k in 0..n {
        let z = (k as f64 - c) / c * 1.2;
        for j in 0..n {
            let y = (j as f64 - c) / c;
            for i in 0..n {
                let x = (i as f64 - c) / c;
                let r = (x * x + y * y + z * z).sqrt();
                data.push((255.0 * (0.5 + (0.7 - r) * 8.0)).clamp(0.0, 255.0) as u8);
            }
        }
    }
    let head = format!(
        "NRRD0004\ntype: uint8\ndimension: 3\nsizes: {n} {n} {n}\nspacings: {spacing} {spacing} {spacing}\nencoding: raw\n\n"
    );
    let mut bytes = head.into_bytes();
    bytes.extend_from_slice(&data);
    std::fs::write(path, bytes).unwrap();
    // 128 is crossed at r = 0.7 - 0.5 / (255 * 8) of the unit radius.
    let r = (0.7 - 0.5 / 2040.0) * c * spacing;
    4.0 / 3.0 * std::f64::consts::PI * r * r * r / 1.2
}

#[test]
fn large_scans_come_coarse_first_then_full() {
    let dir = std::env::temp_dir().join(format!("mf-studio-scan-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    // 16 MiB: over the 4 MiB from which scans come coarse first.
    let volume = write_scan(&dir.join("ct.nrrd"), 256, 0.4);
    let studio = Studio::start(ServeOptions {
        port: 0,
        root: dir.clone(),
        levels: vec![48, 96],
        analysis: [48, 96],
        ..ServeOptions::default()
    })
    .unwrap();
    let c = studio.client();
    let s = c.post_json("/api/session", &json!({})).unwrap()["session"]
        .as_str()
        .unwrap()
        .to_string();
    let src = "-- --field ct=ct.nrrd:iso=128\nmy_model(x[3], a[1]) {\n  my_model = ct(x);\n}\n";
    let st = run(&c, &s, src, json!({}));
    assert!(st["error"].is_null(), "{st}");
    let t = &st["timings"];
    let first = t["first_mesh_s"].as_f64().unwrap();
    let full = t["full_parts_s"]
        .as_f64()
        .expect("the full scan came after");
    assert!(first < full, "{t}");
    // The state ends with the full scan.
    assert_eq!(st["parts"][0]["coarse_step"], Value::Null, "{st}");
    assert_eq!(st["parts"][0]["kind"], "scan");
    assert_eq!(st["model"]["bounds_source"], "part");
    let meshes = st["meshes"].as_array().unwrap();
    assert_eq!(meshes.len(), 2);
    let vol = |m: &Value| {
        let blob = c.get(m["url"].as_str().unwrap()).unwrap();
        let (pos, _, _, tris) = wire::decode_mesh(&blob.body).unwrap();
        signed_volume(
            tris.iter()
                .map(|t| t.map(|i| pos[i as usize].map(f64::from))),
        )
    };
    let (v0, v1) = (vol(&meshes[0]), vol(&meshes[1]));
    // The first image, of the coarse stand-in, already has the shape.
    assert!((v0 - volume).abs() < 0.05 * volume, "{v0} vs {volume}");
    assert!((v1 - volume).abs() < 0.01 * volume, "{v1} vs {volume}");
    let a = st["analysis"]["refined"]["report"]["volume"]["value"]
        .as_f64()
        .unwrap();
    assert!((a - volume).abs() < 0.02 * volume, "{a} vs {volume}");
    // The next edit has the full scan at once.
    let st2 = run(&c, &s, &format!("{src}-- again\n"), json!({}));
    assert_eq!(st2["parts"][0]["cached"], true);
    assert!(st2["timings"]["full_parts_s"].is_null(), "{st2}");
    let warm = st2["timings"]["first_mesh_s"].as_f64().unwrap();
    println!(
        "256^3 scan (16 MiB): first image {first:.3} s (coarse stand-in), full scan ready at \
         {full:.3} s; next edit's first image {warm:.3} s"
    );
    // A small scan is built whole at once (2 MiB).
    write_scan(&dir.join("small.nrrd"), 128, 0.8);
    let st = run(
        &c,
        &s,
        "-- --field ct=small.nrrd:iso=128\nmy_model(x[3], a[1]) {\n  my_model = ct(x);\n}\n",
        json!({}),
    );
    assert!(st["error"].is_null(), "{st}");
    assert!(st["timings"]["full_parts_s"].is_null(), "{st}");
    assert_eq!(st["parts"][0]["cached"], false);
    studio.stop();

    // The server's own bindings (the CLI's `--field`) may name files outside
    // the working directory; the page's may not.
    let inner = dir.join("work");
    std::fs::create_dir_all(&inner).unwrap();
    let small = format!("{}:iso=128", dir.join("small.nrrd").display());
    let studio = Studio::start(ServeOptions {
        port: 0,
        root: inner,
        levels: vec![32],
        analysis: [32, 32],
        fields: vec![("ct".into(), small.clone())],
        ..ServeOptions::default()
    })
    .unwrap();
    let c = studio.client();
    let s = c.post_json("/api/session", &json!({})).unwrap()["session"]
        .as_str()
        .unwrap()
        .to_string();
    let bare = "my_model(x[3], a[1]) {\n  my_model = ct(x);\n}\n";
    let st = run(&c, &s, bare, json!({}));
    assert!(st["error"].is_null(), "{st}");
    assert_eq!(st["parts"][0]["source"], small);
    assert_eq!(st["meshes"].as_array().unwrap().len(), 1);
    let st = run(&c, &s, bare, json!({"fields": {"ct": small}}));
    assert!(
        st["rendered"]
            .as_str()
            .unwrap()
            .contains("absolute paths are not allowed"),
        "{st}"
    );
    studio.stop();
    let _ = std::fs::remove_dir_all(&dir);
}
