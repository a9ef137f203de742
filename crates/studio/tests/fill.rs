//! `POST /api/fill`: the studio's fill is the facade's (the same source
//! and report as calling `microfrep::fill` directly), for the current
//! model and for a mesh file, and its answer edits into a model that
//! loads without diagnostics and has the values of the fill.

use microfrep::fill::{fill, FillOptions, MeasureOptions, Part, Structure};
use microfrep::{Bounds, Expr, LoadOptions, Shape};
use microfrep_studio::{ServeOptions, Studio};
use serde_json::json;
use std::time::Duration;

const BALL: &str = "my_model(x[3], a[1]) { my_model = 100 - x[1]^2 - x[2]^2 - x[3]^2; }";

fn quiet(_: &str, _: u64, _: u64) {}

#[test]
fn the_studio_fills_the_current_model_and_a_mesh_as_the_facade_does() {
    let root = std::env::temp_dir().join(format!("mf-studio-fill-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    std::fs::create_dir_all(root.join("parts")).unwrap();
    // A mesh part: a ball of radius 10, meshed.
    let x = Expr::xyz();
    let ball = Shape::new(100.0 - (x[0].square() + x[1].square() + x[2].square()));
    let mo = microfrep::mesh::MeshOptions::new([[-11.0; 3], [11.0; 3]], 48);
    let mesh = microfrep::mesh::Plan::new(&ball, &mo)
        .unwrap()
        .run(&|_| {})
        .unwrap();
    let stl = root.join("parts/ball.stl");
    microfrep::mesh::write::write_mesh(&stl, &mesh, None).unwrap();

    let studio = Studio::start(ServeOptions {
        port: 0,
        root: root.clone(),
        levels: vec![24],
        analysis: [24, 32],
        settle: Duration::ZERO,
        job_seconds: 60.0,
        ..ServeOptions::default()
    })
    .unwrap();
    let c = studio.client();
    let s = c.post_json("/api/session", &json!({})).unwrap()["session"]
        .as_str()
        .unwrap()
        .to_string();
    let st = c
        .post_json(
            "/api/edit",
            &json!({"session": s, "source": BALL, "file": "ball.hf",
                    "bounds": [[-10, -10, -10], [10, 10, 10]]}),
        )
        .unwrap();
    let gen = st["gen"].as_u64().unwrap();

    // The current model: a gyroid of 5 mm cells in a 1 mm skin.
    let answer = c
        .post_json(
            "/api/fill",
            &json!({"session": s, "gen": gen, "part": "current", "structure": "gyroid",
                    "cell": 5, "density": 0.3, "shell": 1}),
        )
        .unwrap();
    let part = Part::from_shape(
        microfrep::load(
            &{
                let p = root.join("ball.hf");
                std::fs::write(&p, BALL).unwrap();
                p.to_string_lossy().into_owned()
            },
            &LoadOptions::default(),
        )
        .unwrap()
        .shape,
        Some(Bounds::new([-10.0; 3], [10.0; 3])),
    )
    .unwrap();
    let mut opts = FillOptions::new(Structure::parse("gyroid", false).unwrap(), 5.0, 0.3);
    opts.skin = Some(1.0);
    let f = fill(&part, &opts, &quiet).unwrap();
    assert_eq!(answer["source"].as_str().unwrap(), f.hyperfun().unwrap());
    let r = f.measure(&MeasureOptions::default(), &quiet).unwrap();
    let want = r.to_json(&f);
    let got = &answer["report"];
    assert_eq!(got["density"], want["density"], "{got}");
    assert!(
        (got["density"]["measured"].as_f64().unwrap() - 0.3).abs() < 0.01,
        "{got}"
    );
    let skin = got["skin"]["min"].as_f64().unwrap();
    assert!((skin - 1.0).abs() < 0.1, "skin {skin}: {got}");
    assert_eq!(answer["file"], json!("ball-filled.hf"));
    assert_eq!(answer["fields"], json!({}));

    // The answer edits into a model without diagnostics.
    let st = c
        .post_json(
            "/api/edit",
            &json!({"session": s, "source": answer["source"], "file": answer["file"]}),
        )
        .unwrap();
    assert_eq!(st["diagnostics"], json!([]), "{st}");

    // A mesh part: bound by its path under the working directory.
    let answer = c
        .post_json(
            "/api/fill",
            &json!({"session": s, "part": "parts/ball.stl", "structure": "octet",
                    "cell": 4, "density": 0.2, "shell": 1.5}),
        )
        .unwrap();
    assert_eq!(answer["fields"], json!({"part": "parts/ball.stl"}));
    let src = answer["source"].as_str().unwrap();
    assert!(src.contains("--field part=parts/ball.stl"), "{src}");
    let d = answer["report"]["density"]["measured"].as_f64().unwrap();
    assert!((d - 0.2).abs() < 0.01, "{}", answer["report"]);
    let st = c
        .post_json(
            "/api/edit",
            &json!({"session": s, "source": src, "file": answer["file"]}),
        )
        .unwrap();
    assert_eq!(st["diagnostics"], json!([]), "{st}");
    // The same fill through the facade gives the same model.
    let part = Part::load(
        &stl.to_string_lossy(),
        &LoadOptions::default(),
        None,
        &quiet,
    )
    .unwrap();
    let mut opts = FillOptions::new(Structure::parse("octet", false).unwrap(), 4.0, 0.2);
    opts.skin = Some(1.5);
    let f = fill(&part, &opts, &quiet).unwrap();
    let facade = f.hyperfun().unwrap();
    // Only the binding's spelling differs (the studio's is relative).
    assert_eq!(
        src,
        facade.replace(&*stl.to_string_lossy(), "parts/ball.stl"),
        "the studio's fill differs from the facade's"
    );

    // Refusals name the body's keys and paths.
    for (body, status, says) in [
        (
            json!({"session": s, "part": "parts/ball.stl", "structure": "gyroid", "cell": 0, "density": 0.3}),
            400,
            "'cell'",
        ),
        (
            json!({"session": s, "part": "../outside.stl", "structure": "gyroid", "cell": 2, "density": 0.3}),
            403,
            "outside.stl",
        ),
        (
            json!({"session": s, "part": "current", "structure": "gyroid", "cell": 2, "density": 0.3}),
            400,
            "gen",
        ),
    ] {
        let r = c
            .request("POST", "/api/fill", Some(body.to_string().as_bytes()), &[])
            .unwrap();
        let text = String::from_utf8_lossy(&r.body).into_owned();
        assert_eq!(r.status, status, "{body}: {text}");
        assert!(text.contains(says), "{body}: {text}");
    }
    studio.stop();
    let _ = std::fs::remove_dir_all(&root);
}
