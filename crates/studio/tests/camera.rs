//! The view's refit rule (`assets/camera.js`, served in front of the viewer
//! in `/viewer.js`) run in Node.js: the script the studio serves, fetched
//! from a running studio, is loaded as a module and asked about boxes that
//! grow, shrink, move and leave the view, with the user's own zoom and
//! orbit.
//!
//! Needs `node` on `PATH` (or `MICROFREP_NODE`); where there is none the
//! test says it was skipped, except under CI (`CI` set), where that is a
//! failure. The headless-browser test (`browser.rs`) checks the same rule in
//! the real page.

use microfrep_studio::{ServeOptions, Studio};
use serde_json::Value;
use std::path::PathBuf;
use std::process::Command;

fn node() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("MICROFREP_NODE") {
        return Some(PathBuf::from(p));
    }
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|d| d.join("node"))
        .find(|p| p.is_file())
}

/// Cases run in Node: each prints `[name, value]`.
const HARNESS: &str = r#"
// The viewer's part needs only `window` until a viewer is made.
globalThis.window = globalThis;
const C = require(process.argv[2]);
if (typeof window.StudioViewer !== "function") throw new Error("no StudioViewer in the script");
const out = [];
const put = (name, v) => out.push([name, v]);
const unit = [[-1, -1, -1], [1, 1, 1]];
const scale = (b, s) => b.map((p) => p.map((x) => s * x));
const shift = (b, d) => b.map((p) => p.map((x, a) => x + d[a]));
const cam = C.fit(unit, -0.785, 0.6);
put("first", C.refitReason(null, unit, cam, 1.5));
put("same", C.refitReason(unit, unit, cam, 1.5));
put("grow 20 %", C.refitReason(unit, scale(unit, 1.2), cam, 1.5));
put("grow 30 %", C.refitReason(unit, scale(unit, 1.3), cam, 1.5));
put("grow 10x", C.refitReason(unit, scale(unit, 10), cam, 1.5));
put("shrink to 85 %", C.refitReason(unit, scale(unit, 0.85), cam, 1.5));
put("shrink to 75 %", C.refitReason(unit, scale(unit, 0.75), cam, 1.5));
put("shrink 10x", C.refitReason(unit, scale(unit, 0.1), cam, 1.5));
const d = C.diagonal(unit);
put("move 20 %", C.refitReason(unit, shift(unit, [0.2 * d, 0, 0]), cam, 1.5));
put("move 30 %", C.refitReason(unit, shift(unit, [0, 0, 0.3 * d]), cam, 1.5));
// Steps of 10 % each are measured against the fitted box: the third one
// (1.1^3 = 1.33) refits.
let fitted = unit, b = unit, steps = [];
for (let k = 0; k < 4; k++) {
  b = scale(b, 1.1);
  const why = C.refitReason(fitted, b, cam, 1.5);
  steps.push(why);
  if (why) fitted = b;
}
put("steps of 10 %", steps);
// The user zoomed in 5x on a corner and orbited: a small edit keeps that view.
const zoomed = { yaw: 1.1, pitch: -0.3, dist: cam.dist / 5, target: [0.8, 0.8, 0.8], fov: cam.fov };
put("zoomed, edit of 10 %", C.refitReason(unit, scale(unit, 1.1), zoomed, 1.5));
put("zoomed, box in view", C.inView(unit, zoomed, 1.5));
// Panned far away: the box is off screen, so the next edit refits.
const away = Object.assign({}, cam, { target: [0, 0, 40] });
put("panned away, in view", C.inView(unit, away, 1.5));
put("panned away, edit", C.refitReason(unit, scale(unit, 1.05), away, 1.5));
// Turned round at the same place, to look away from the box.
const e0 = C.eye(cam), f0 = C.axes(cam.yaw, cam.pitch).fwd;
const behind = { yaw: cam.yaw + Math.PI, pitch: -cam.pitch, dist: cam.dist, fov: cam.fov,
  target: e0.map((x, a) => x - f0[a] * cam.dist) };
put("turned round, same eye", Math.hypot(...C.eye(behind).map((x, a) => x - e0[a])));
put("looking away, in view", C.inView(unit, behind, 1.5));
const inside = Object.assign({}, cam, { dist: 0.1 });
put("camera inside, in view", C.inView(unit, inside, 1.5));
// A refit keeps the orbit angles and centres the new box in view.
const big = shift(scale(unit, 20), [5, -3, 100]);
const re = C.fit(big, zoomed.yaw, zoomed.pitch, zoomed.fov);
put("refit angles", [re.yaw, re.pitch]);
put("refit target", re.target);
put("refit centre on screen", C.project(C.centre(big), re, 1.5));
put("refit box in view", C.inView(big, re, 1.5));
put("refit distance / diagonal", re.dist / C.diagonal(big));
// A far corner of the fitted box projects inside the view (no clipping
// of the solid that fills the box's inscribed sphere).
const ins = [[-1, 0, 0], [1, 0, 0], [0, -1, 0], [0, 1, 0], [0, 0, -1], [0, 0, 1]]
  .map((p) => C.project(p, cam, 1.5)).map((s) => Math.max(Math.abs(s[0]), Math.abs(s[1])));
put("inscribed sphere's poles on screen", Math.max(...ins));
console.log(JSON.stringify(out));
"#;

#[test]
fn camera_refits_when_the_box_changes_materially() {
    let Some(node) = node() else {
        if std::env::var_os("CI").is_some() {
            panic!("CI is set but no `node` was found on PATH (or MICROFREP_NODE)");
        }
        println!("skipped: no `node` on PATH (set MICROFREP_NODE to run the camera test)");
        return;
    };
    let dir = std::env::temp_dir().join(format!("mf-studio-camera-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let studio = Studio::start(ServeOptions {
        port: 0,
        root: dir.clone(),
        ..ServeOptions::default()
    })
    .unwrap();
    let c = studio.client();
    let js = c.get("/viewer.js").unwrap();
    assert_eq!(js.status, 200);
    assert_eq!(
        js.header("content-type"),
        Some("text/javascript; charset=utf-8")
    );
    let text = String::from_utf8(js.body.clone()).unwrap();
    // The camera's functions come first, and the viewer uses the rule.
    let (cam_at, viewer_at) = (text.find("StudioCamera = api"), text.find("class Viewer"));
    assert!(cam_at.is_some() && cam_at < viewer_at);
    assert!(
        text.contains("Cam.refitReason("),
        "the viewer does not use the rule"
    );
    studio.stop();

    let script = dir.join("viewer.js");
    std::fs::write(&script, &js.body).unwrap();
    let harness = dir.join("harness.js");
    std::fs::write(&harness, HARNESS).unwrap();
    let out = Command::new(&node)
        .arg(&harness)
        .arg(&script)
        .output()
        .expect("run node");
    assert!(
        out.status.success(),
        "node failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_slice(&out.stdout).expect("harness output");
    let get = |name: &str| -> Value {
        v.as_array()
            .unwrap()
            .iter()
            .find(|p| p[0] == name)
            .unwrap_or_else(|| panic!("no case {name}"))[1]
            .clone()
    };
    let f = |x: &Value| x.as_f64().unwrap();
    let reason = |name: &str| get(name).as_str().map(str::to_string);
    assert_eq!(reason("first").as_deref(), Some("first"));
    assert_eq!(reason("same"), None);
    assert_eq!(reason("grow 20 %"), None);
    assert_eq!(reason("grow 30 %").as_deref(), Some("size"));
    assert_eq!(reason("grow 10x").as_deref(), Some("size"));
    assert_eq!(reason("shrink to 85 %"), None);
    assert_eq!(reason("shrink to 75 %").as_deref(), Some("size"));
    assert_eq!(reason("shrink 10x").as_deref(), Some("size"));
    assert_eq!(reason("move 20 %"), None);
    assert_eq!(reason("move 30 %").as_deref(), Some("moved"));
    assert_eq!(
        get("steps of 10 %"),
        serde_json::json!([null, null, "size", null])
    );
    assert_eq!(reason("zoomed, edit of 10 %"), None);
    assert_eq!(get("zoomed, box in view"), true);
    assert_eq!(get("panned away, in view"), false);
    assert_eq!(reason("panned away, edit").as_deref(), Some("out of view"));
    assert!(f(&get("turned round, same eye")) < 1e-9);
    assert_eq!(get("looking away, in view"), false);
    assert_eq!(get("camera inside, in view"), true);
    let angles = get("refit angles");
    assert_eq!(f(&angles[0]), 1.1);
    assert_eq!(f(&angles[1]), -0.3);
    let t = get("refit target");
    for (a, want) in [5.0, -3.0, 100.0].iter().enumerate() {
        assert!((f(&t[a]) - want).abs() < 1e-9, "{t}");
    }
    let s = get("refit centre on screen");
    assert!(f(&s[0]).abs() < 1e-9 && f(&s[1]).abs() < 1e-9, "{s}");
    assert_eq!(get("refit box in view"), true);
    // 0.92 / (2 sin 17.5 deg) of the diagonal.
    let ratio = f(&get("refit distance / diagonal"));
    let want = 0.92 / (2.0 * (17.5f64).to_radians().sin());
    assert!((ratio - want).abs() < 1e-9, "{ratio} vs {want}");
    let poles = f(&get("inscribed sphere's poles on screen"));
    assert!(poles < 1.0, "{poles}");
    let _ = std::fs::remove_dir_all(&dir);
}
