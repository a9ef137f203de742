//! Smoke test of the studio's endpoints: a server on an ephemeral port,
//! driven over HTTP as the page drives it.

use microfrep_studio::client::Client;
use microfrep_studio::{wire, ServeOptions, Studio};
use serde_json::{json, Value};
use std::collections::HashMap;
use std::f64::consts::PI;
use std::path::PathBuf;
use std::time::{Duration, Instant};

fn root(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("mf-studio-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(d.join("models")).unwrap();
    d
}

fn start(root: &std::path::Path) -> (Studio, Client) {
    let studio = Studio::start(ServeOptions {
        port: 0,
        root: root.to_path_buf(),
        levels: vec![24, 48],
        analysis: [32, 64],
        settle: Duration::ZERO,
        job_seconds: 20.0,
        ..ServeOptions::default()
    })
    .unwrap();
    assert!(studio.addr().ip().is_loopback());
    let c = studio.client();
    (studio, c)
}

fn session(c: &Client) -> String {
    let s = c.post_json("/api/session", &json!({})).unwrap();
    s["session"].as_str().unwrap().to_string()
}

fn edit(c: &Client, s: &str, src: &str, extra: Value) -> Value {
    let mut body = json!({ "session": s, "source": src, "file": "m.hf" });
    if let Value::Object(m) = extra {
        for (k, v) in m {
            body[k] = v;
        }
    }
    c.post_json("/api/edit", &body).unwrap()
}

fn wait(c: &Client, s: &str, gen: u64) -> Value {
    let st = c
        .get_json(&format!("/api/wait?session={s}&gen={gen}&wait_ms=60000"))
        .unwrap();
    assert_eq!(
        st["finished"],
        json!(true),
        "generation {gen} did not finish: {st}"
    );
    st
}

const SPHERE: &str = "-- a[1] = 0.8\nmy_model(x[3], a[1]) {\n  my_model = a[1]*a[1] - x[1]*x[1] - x[2]*x[2] - x[3]*x[3];\n}\n";

fn unit_box() -> Value {
    json!([[-1.0, -1.0, -1.0], [1.0, 1.0, 1.0]])
}

/// Closed, consistently oriented 2-manifold: every directed edge once, and
/// its reverse once. Returns the enclosed volume.
fn closed_volume(pos: &[[f32; 3]], tris: &[[u32; 3]]) -> f64 {
    let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
    for t in tris {
        for k in 0..3 {
            *edges.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
        }
    }
    for (&(a, b), &n) in &edges {
        assert_eq!(n, 1, "directed edge {a}->{b} used {n} times");
        assert_eq!(edges.get(&(b, a)), Some(&1), "edge {a}-{b} has no twin");
    }
    let p = |i: u32| pos[i as usize].map(|c| c as f64);
    tris.iter()
        .map(|t| {
            let (a, b, c) = (p(t[0]), p(t[1]), p(t[2]));
            (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                + a[2] * (b[0] * c[1] - b[1] * c[0]))
                / 6.0
        })
        .sum()
}

#[test]
fn diagnostics_meshes_analysis_exports_and_refusals() {
    let dir = root("main");
    std::fs::write(dir.join("models/ball.hf"), SPHERE).unwrap();
    std::fs::write(dir.join("secret.txt"), "no").unwrap();
    let (studio, c) = start(&dir);

    // The page and its scripts are served; the API refuses foreign hosts and
    // POSTs without the studio header.
    let page = c.get("/").unwrap();
    assert_eq!(page.status, 200);
    assert!(String::from_utf8_lossy(&page.body).contains("studio.js"));
    assert!(page.header("content-security-policy").is_some());
    for asset in ["/studio.js", "/viewer.js", "/editor.js", "/studio.css"] {
        let r = c.get(asset).unwrap();
        assert_eq!(r.status, 200, "{asset}");
        assert!(r.body.len() > 1000, "{asset} is nearly empty");
    }
    let mut evil = c.clone();
    evil.host = "evil.example:80".into();
    assert_eq!(evil.get("/").unwrap().status, 421);
    let r = c.request("GET", "/api/session", None, &[]).unwrap();
    assert_eq!(r.status, 404);
    let s = session(&c);
    // A POST without the studio header (as a cross-site form would send).
    {
        use std::io::{Read, Write};
        let mut t = std::net::TcpStream::connect(studio.addr()).unwrap();
        let body = json!({"session": s, "source": SPHERE}).to_string();
        write!(
            t,
            "POST /api/edit HTTP/1.1\r\nHost: 127.0.0.1:{}\r\nX-Studio-Token: {}\r\nConnection: close\r\nContent-Type: text/plain\r\nContent-Length: {}\r\n\r\n{body}",
            studio.addr().port(),
            studio.token(),
            body.len()
        )
        .unwrap();
        let mut out = String::new();
        t.read_to_string(&mut out).unwrap();
        assert!(out.starts_with("HTTP/1.1 403"), "{out}");
        assert!(out.contains("X-Studio: 1"), "{out}");
    }

    // A broken model: diagnostics with positions, rendered as `check` does.
    let broken = "my_model(x[3], a[1]) {\n  r = 1 - x[1]*x[1];\n  my_model = r + ;\n}\n";
    let st = edit(&c, &s, broken, json!({}));
    assert_eq!(st["loaded"], json!(true), "{st}");
    let d = st["diagnostics"].as_array().unwrap();
    assert!(!d.is_empty());
    assert_eq!(d[0]["severity"], "error");
    assert_eq!(d[0]["line"], 3);
    assert_eq!(d[0]["col"], 18, "{d:?}");
    let rendered = st["rendered"].as_str().unwrap();
    assert!(rendered.starts_with("m.hf:3:18: error: "), "{rendered}");
    assert!(rendered.contains("\n    my_model = r + ;\n"), "{rendered}");
    assert!(st["model"].is_null());
    let unknown = edit(
        &c,
        &s,
        "my_model(x[3], a[1]) { my_model = nosuch(x); }",
        json!({}),
    );
    let d = unknown["diagnostics"].as_array().unwrap();
    assert!(
        d.iter().any(|d| d["severity"] == "error" && d["line"] == 1),
        "{unknown}"
    );

    // A sphere of radius a[1] = 0.8 (the comment's default): the mesh is
    // closed, and its volume and the analysis match the closed forms.
    let st = edit(&c, &s, SPHERE, json!({ "bounds": unit_box() }));
    let gen = st["gen"].as_u64().unwrap();
    assert_eq!(st["diagnostics"].as_array().unwrap().len(), 0, "{st}");
    let params = st["model"]["params"].as_array().unwrap();
    assert_eq!(params.len(), 1);
    assert_eq!(params[0]["name"], "a[1]");
    assert_eq!(params[0]["value"], 0.8);
    let st = wait(&c, &s, gen);
    assert_eq!(st["error"], Value::Null, "{st}");
    let meshes = st["meshes"].as_array().unwrap();
    assert_eq!(meshes.len(), 2, "{st}");
    assert_eq!(meshes[1]["resolution"], 48);
    let r = 0.8f64;
    let exact_v = 4.0 / 3.0 * PI * r.powi(3);
    for m in meshes {
        let blob = c.get(m["url"].as_str().unwrap()).unwrap();
        assert_eq!(blob.status, 200);
        assert_eq!(
            blob.header("content-type"),
            Some("application/octet-stream")
        );
        let (pos, nrm, attrs, tris) = wire::decode_mesh(&blob.body).expect("mesh blob");
        assert_eq!(tris.len() as u64, m["triangles"].as_u64().unwrap());
        assert!(attrs.is_empty());
        let v = closed_volume(&pos, &tris);
        let res = m["resolution"].as_f64().unwrap();
        assert!(
            (v - exact_v).abs() < 0.02 * exact_v * (48.0 / res),
            "volume {v} vs {exact_v} at {res}"
        );
        // Normals point outwards (along the position on a centred sphere).
        for (p, n) in pos.iter().zip(&nrm) {
            let d = p[0] * n[0] + p[1] * n[1] + p[2] * n[2];
            assert!(d > 0.75 * r as f32, "normal {n:?} at {p:?}");
        }
    }
    let a = &st["analysis"];
    assert_eq!(a["preview"]["resolution"], 32);
    assert_eq!(a["refined"]["resolution"], 64);
    let rep = &a["refined"]["report"];
    let vf = rep["volume_fraction"]["value"].as_f64().unwrap();
    let exact_vf = exact_v / 8.0;
    assert!(
        (vf - exact_vf).abs() < 2e-3,
        "volume fraction {vf} vs {exact_vf}"
    );
    let por = rep["porosity"]["value"].as_f64().unwrap();
    assert!((por - (1.0 - exact_vf)).abs() < 2e-3);
    let area = rep["area"]["value"].as_f64().unwrap();
    let exact_a = 4.0 * PI * r * r;
    assert!(
        (area - exact_a).abs() < 0.01 * exact_a,
        "area {area} vs {exact_a}"
    );
    let conn = &rep["connectivity"];
    assert_eq!(conn["solid_components"], 1);
    assert_eq!(conn["pore_components"], 1);
    assert_eq!(conn["closed_pores"], 0);
    assert_eq!(conn["euler_surface"], 2);
    // Percolation is of the pore space, which surrounds the ball.
    assert_eq!(conn["percolates"], json!({"x": true, "y": true, "z": true}));
    let t = &st["timings"];
    assert!(t["first_mesh_s"].as_f64().unwrap() <= t["refined_mesh_s"].as_f64().unwrap());

    // Moving the parameter: a[1] = 0.5 gives the smaller ball.
    let st = edit(
        &c,
        &s,
        SPHERE,
        json!({ "bounds": unit_box(), "params": [0.5] }),
    );
    let st = wait(&c, &s, st["gen"].as_u64().unwrap());
    let vf = st["analysis"]["refined"]["report"]["volume_fraction"]["value"]
        .as_f64()
        .unwrap();
    let exact = 4.0 / 3.0 * PI * 0.125 / 8.0;
    assert!((vf - exact).abs() < 2e-3, "{vf} vs {exact}");
    let gen = st["gen"].as_u64().unwrap();

    // Exports: STL of the finest mesh, the model, a slice stack as a zip.
    let stl = c
        .get(&format!("/api/export.stl?session={s}&gen={gen}"))
        .unwrap();
    assert_eq!(stl.status, 200);
    let n = u32::from_le_bytes(stl.body[80..84].try_into().unwrap()) as usize;
    assert_eq!(n as u64, st["meshes"][1]["triangles"].as_u64().unwrap());
    assert_eq!(stl.body.len(), 84 + 50 * n);
    assert!(stl.header("content-disposition").unwrap().contains("m.stl"));
    let hf = c
        .get(&format!("/api/export.hf?session={s}&gen={gen}"))
        .unwrap();
    assert_eq!(String::from_utf8(hf.body).unwrap(), SPHERE);
    let z = c
        .get(&format!(
            "/api/slices.zip?session={s}&gen={gen}&layer=0.25&pixel=0.05"
        ))
        .unwrap();
    assert_eq!(z.status, 200, "{}", String::from_utf8_lossy(&z.body));
    let mut zip = zip::ZipArchive::new(std::io::Cursor::new(z.body)).unwrap();
    let names: Vec<String> = zip.file_names().map(str::to_string).collect();
    assert_eq!(
        names.iter().filter(|n| n.ends_with(".png")).count(),
        8,
        "{names:?}"
    );
    let mut manifest = String::new();
    std::io::Read::read_to_string(
        &mut zip.by_name("m-slices/manifest.json").unwrap(),
        &mut manifest,
    )
    .unwrap();
    let mj: Value = serde_json::from_str(&manifest).unwrap();
    assert_eq!(mj["layers"].as_array().unwrap().len(), 8);
    assert_eq!(mj["image_size"], json!([40, 40]));
    let sec = c
        .get(&format!(
            "/api/section.png?session={s}&gen={gen}&axis=2&value=0&w=64&h=48"
        ))
        .unwrap();
    assert_eq!(sec.status, 200);
    assert_eq!(&sec.body[1..4], b"PNG");
    assert_eq!(u32::from_be_bytes(sec.body[16..20].try_into().unwrap()), 64);

    // Files: listing, opening and saving under the root only.
    let files = c.get_json("/api/files").unwrap();
    assert_eq!(files["files"], json!(["models/ball.hf"]));
    let f = c.get("/api/file?path=models%2Fball.hf").unwrap();
    assert_eq!(f.status, 200);
    assert_eq!(String::from_utf8(f.body).unwrap(), SPHERE);
    for bad in [
        "../secret.txt",
        "models/..%2F..%2Fsecret.hf",
        "%2Fetc%2Fpasswd.hf",
        "..%2F..%2F..%2Fetc%2Fhostname.hf",
        "secret.txt",
    ] {
        let r = c.get(&format!("/api/file?path={bad}")).unwrap();
        assert_eq!(r.status, 403, "{bad}: {}", String::from_utf8_lossy(&r.body));
    }
    let save = |path: &str| {
        c.request(
            "POST",
            "/api/save",
            Some(json!({"path": path, "source": "x"}).to_string().as_bytes()),
            &[],
        )
        .unwrap()
    };
    assert_eq!(save("../escape.hf").status, 403);
    assert_eq!(save("/tmp/escape.hf").status, 403);
    assert_eq!(save("models/notes.txt").status, 403);
    assert!(!dir.parent().unwrap().join("escape.hf").exists());
    let ok = save("models/saved.hf");
    assert_eq!(ok.status, 200);
    assert_eq!(
        std::fs::read_to_string(dir.join("models/saved.hf")).unwrap(),
        "x"
    );
    let slices = |d: &str| {
        c.request(
            "POST",
            "/api/slices",
            Some(
                json!({"session": s, "gen": gen, "dir": d, "layer": 0.5, "pixel": 0.1})
                    .to_string()
                    .as_bytes(),
            ),
            &[],
        )
        .unwrap()
    };
    // Output names are plain names of new folders under studio-output/.
    for bad in [
        "../out",
        "a/b",
        "/tmp/abs",
        "..",
        "a..b",
        ".hidden",
        "",
        "sub\\x",
        "models/../x",
    ] {
        let r = slices(bad);
        assert_eq!(r.status, 400, "{bad}: {}", String::from_utf8_lossy(&r.body));
        let msg = r.json()["error"].as_str().unwrap_or_default().to_string();
        assert!(
            msg.contains("output name") && msg.contains("studio-output"),
            "{bad}: {msg}"
        );
    }
    assert!(!dir.join("out").exists() && !dir.parent().unwrap().join("out").exists());
    assert!(!std::path::Path::new("/tmp/abs").exists());
    let r = slices("stack");
    assert_eq!(r.status, 200, "{}", String::from_utf8_lossy(&r.body));
    assert_eq!(r.json()["layers"], 4);
    assert_eq!(r.json()["written"], "studio-output/stack");
    assert!(dir.join("studio-output/stack/manifest.json").is_file());
    assert!(dir.join("studio-output/stack/layer_00003.png").is_file());
    assert_eq!(
        slices("stack").status,
        403,
        "existing folders are not overwritten"
    );
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().starts_with('.'))
        .collect();
    assert!(leftovers.is_empty(), "staging folders left: {leftovers:?}");

    // An unknown session and a vanished generation are clear errors.
    let r = c.get("/api/state?session=nope").unwrap();
    assert_eq!(r.status, 400);
    let r = c
        .get(&format!("/api/export.stl?session={s}&gen=1"))
        .unwrap();
    assert_eq!(r.status, 400);
    assert!(String::from_utf8_lossy(&r.body).contains("gone"));

    studio.stop();
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn looping_models_stop_with_an_error_and_the_server_goes_on() {
    let dir = root("loop");
    let (studio, c) = start(&dir);
    let s = session(&c);

    // A loop whose condition depends on the point: every evaluation runs to
    // HyperFun's iteration limit, so the probe refuses the model.
    let spin = "my_model(x[3], a[1]) {\n  i = 0;\n  while (x[1] < 10) loop\n    i = i + 1;\n  endloop;\n  my_model = 1 - x[1]*x[1];\n}\n";
    let t = Instant::now();
    let st = edit(&c, &s, spin, json!({ "bounds": unit_box() }));
    let st = wait(&c, &s, st["gen"].as_u64().unwrap());
    let err = st["error"].as_str().unwrap_or_default();
    assert!(
        err.contains("one evaluation of the model takes longer")
            || err.contains("does not terminate"),
        "{st}"
    );
    assert!(st["meshes"].as_array().unwrap().is_empty());
    assert!(t.elapsed() < Duration::from_secs(5), "{:?}", t.elapsed());

    // A loop that never ends whatever the point: lowering stops it at the
    // iteration limit; the model is refused with the loop's place.
    let fixed = "my_model(x[3], a[1]) {\n  i = 0;\n  while (i < 10) loop\n    i = i * 1;\n  endloop;\n  my_model = 1 - x[1]*x[1];\n}\n";
    let st = edit(&c, &s, fixed, json!({ "bounds": unit_box() }));
    let st = wait(&c, &s, st["gen"].as_u64().unwrap());
    // The loop's error and place are shown, and nothing is meshed.
    let err = st["error"].as_str().unwrap_or_default();
    assert!(
        err.contains("does not terminate") && err.contains("3:3"),
        "{st}"
    );
    assert!(st["meshes"].as_array().unwrap().is_empty());

    // A loop that builds a million-term expression before the limit stops
    // it: lowering recurses deeply (the worker has a large stack) and the
    // server survives it.
    let deep = "my_model(x[3], a[1]) {\n  i = 0;\n  r = 0;\n  while (i < 10) loop\n    r = r + x[1];\n  endloop;\n  my_model = 1 - x[1]*x[1] + r;\n}\n";
    let st = edit(&c, &s, deep, json!({ "bounds": unit_box() }));
    let st = wait(&c, &s, st["gen"].as_u64().unwrap());
    // Either the loop limit or the node budget stops it, whichever comes
    // first; the message lands in the error or in the rendered diagnostics.
    let err = format!(
        "{} {}",
        st["error"].as_str().unwrap_or_default(),
        st["rendered"].as_str().unwrap_or_default()
    );
    assert!(
        err.contains("Loop did not terminate") || err.contains("grows past"),
        "{st}"
    );
    assert!(st["meshes"].as_array().unwrap().is_empty());

    // A stale edit is dropped for the newest: a heavy model, at once
    // replaced by a sphere, finishes as the sphere.
    let heavy =
        "my_model(x[3], a[1]) {\n  my_model = sin(40*x[1])*sin(40*x[2])*sin(40*x[3]) + 0.1;\n}\n";
    let s2 = session(&c);
    let first = edit(
        &c,
        &s2,
        heavy,
        json!({ "bounds": unit_box(), "wait_ms": 0 }),
    );
    let st = edit(&c, &s2, SPHERE, json!({ "bounds": unit_box() }));
    let gen = st["gen"].as_u64().unwrap();
    assert!(gen > first["gen"].as_u64().unwrap());
    let st = wait(&c, &s2, gen);
    assert_eq!(st["gen"], gen);
    assert_eq!(st["error"], Value::Null);
    let vf = st["analysis"]["refined"]["report"]["volume_fraction"]["value"]
        .as_f64()
        .unwrap();
    assert!((vf - 4.0 / 3.0 * PI * 0.512 / 8.0).abs() < 2e-3);

    // The server still answers the other session.
    let st = edit(&c, &s, SPHERE, json!({ "bounds": unit_box() }));
    let st = wait(&c, &s, st["gen"].as_u64().unwrap());
    assert_eq!(st["error"], Value::Null, "{st}");
    studio.stop();
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn memory_limit_lowers_the_resolution() {
    let dir = root("mem");
    let studio = Studio::start(ServeOptions {
        port: 0,
        root: dir.clone(),
        levels: vec![16, 200],
        analysis: [16, 16],
        settle: Duration::ZERO,
        memory_limit: 100e6,
        ..ServeOptions::default()
    })
    .unwrap();
    let c = studio.client();
    let s = session(&c);
    // Many small features: at 200 cells the mesh would need far more than
    // 100 MB.
    let src = "my_model(x[3], a[1]) {\n  my_model = sin(30*x[1])*sin(30*x[2])*sin(30*x[3]);\n}\n";
    let st = edit(&c, &s, src, json!({ "bounds": unit_box() }));
    let st = wait(&c, &s, st["gen"].as_u64().unwrap());
    assert_eq!(st["error"], Value::Null, "{st}");
    let m = &st["meshes"][1];
    let res = m["resolution"].as_u64().unwrap();
    assert!((8..200).contains(&res), "{m}");
    assert!(
        m["note"]
            .as_str()
            .unwrap()
            .contains("resolution lowered from 200"),
        "{m}"
    );
    studio.stop();
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn tabs_have_their_own_sessions() {
    let dir = root("tabs");
    let (studio, c) = start(&dir);
    let handles: Vec<_> = [0.3, 0.5, 0.7]
        .into_iter()
        .map(|r| {
            let c = c.clone();
            std::thread::spawn(move || {
                let s = session(&c);
                // Each tab edits a few times; only its newest edit counts.
                let mut gen = 0;
                for k in 0..3 {
                    let st = edit(
                        &c,
                        &s,
                        SPHERE,
                        json!({ "bounds": unit_box(), "params": [r + 0.05 * (2 - k) as f64], "wait_ms": 0 }),
                    );
                    gen = st["latest_gen"].as_u64().unwrap();
                }
                let st = wait(&c, &s, gen);
                let vf = st["analysis"]["refined"]["report"]["volume_fraction"]["value"]
                    .as_f64()
                    .unwrap();
                (r, vf, st["model"]["params"][0]["value"].as_f64().unwrap())
            })
        })
        .collect();
    for h in handles {
        let (r, vf, p) = h.join().unwrap();
        assert_eq!(p, r);
        let exact = 4.0 / 3.0 * PI * r.powi(3) / 8.0;
        assert!((vf - exact).abs() < 2e-3, "radius {r}: {vf} vs {exact}");
    }
    studio.stop();
    let _ = std::fs::remove_dir_all(&dir);
}
