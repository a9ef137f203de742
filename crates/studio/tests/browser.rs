//! Browser test: headless Chromium loads the studio, a model is typed,
//! diagnostics and analysis figures are read off the page, a parameter
//! slider is dragged and the image must change. Screenshots go to
//! `target/studio-screenshots/`.
//!
//! Off by default (it needs Debian's `chromium`; the test installs
//! nothing): run with `MICROFREP_BROWSER=1`. When requested, a missing
//! Chromium is a failure. Chromium is driven over the DevTools protocol on
//! a pipe (`--remote-debugging-pipe`: NUL-separated JSON on fds 3 and 4).

use base64::Engine as _;
use microfrep_studio::{ServeOptions, Studio};
use serde_json::{json, Value};
use std::f64::consts::PI;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc::{channel, Receiver};
use std::time::{Duration, Instant};

fn chromium() -> Option<PathBuf> {
    if let Ok(p) = std::env::var("MICROFREP_CHROMIUM") {
        return Some(PathBuf::from(p));
    }
    for p in ["/usr/bin/chromium", "/usr/bin/chromium-browser"] {
        if Path::new(p).is_file() {
            return Some(PathBuf::from(p));
        }
    }
    None
}

struct Browser {
    child: Child,
    input: ChildStdin,
    replies: Receiver<Value>,
    next: u64,
    session: Option<String>,
    profile: PathBuf,
}

impl Browser {
    fn launch(exe: &Path) -> Browser {
        let profile =
            std::env::temp_dir().join(format!("mf-studio-chromium-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&profile);
        std::fs::create_dir_all(&profile).unwrap();
        let flags = [
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--remote-debugging-pipe",
            "--window-size=1400,860",
            "--hide-scrollbars",
        ];
        // The pipe protocol reads fd 3 and writes fd 4: the shell moves our
        // stdin and stdout pipes there.
        let mut child = Command::new("sh")
            .arg("-c")
            .arg("exec \"$0\" \"$@\" 3<&0 4>&1 0</dev/null 1>/dev/null")
            .arg(exe)
            .args(flags)
            .arg(format!("--user-data-dir={}", profile.display()))
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("start chromium");
        let input = child.stdin.take().unwrap();
        let mut out = child.stdout.take().unwrap();
        let (tx, rx) = channel();
        std::thread::spawn(move || {
            let mut buf = Vec::new();
            let mut chunk = [0u8; 1 << 16];
            loop {
                let n = match out.read(&mut chunk) {
                    Ok(0) | Err(_) => return,
                    Ok(n) => n,
                };
                buf.extend_from_slice(&chunk[..n]);
                while let Some(i) = buf.iter().position(|&b| b == 0) {
                    let msg: Vec<u8> = buf.drain(..=i).collect();
                    if let Ok(v) = serde_json::from_slice::<Value>(&msg[..msg.len() - 1]) {
                        if tx.send(v).is_err() {
                            return;
                        }
                    }
                }
            }
        });
        Browser {
            child,
            input,
            replies: rx,
            next: 0,
            session: None,
            profile,
        }
    }

    fn call(&mut self, method: &str, params: Value, on_page: bool) -> Value {
        self.next += 1;
        let mut m = json!({ "id": self.next, "method": method, "params": params });
        if on_page {
            m["sessionId"] = json!(self.session.clone().expect("no page"));
        }
        let mut bytes = m.to_string().into_bytes();
        bytes.push(0);
        self.input.write_all(&bytes).unwrap();
        self.input.flush().unwrap();
        let until = Instant::now() + Duration::from_secs(60);
        loop {
            let left = until.saturating_duration_since(Instant::now());
            let v = self
                .replies
                .recv_timeout(left)
                .unwrap_or_else(|_| panic!("no reply from chromium to {method}"));
            if v["id"] == json!(self.next) {
                if let Some(e) = v.get("error") {
                    panic!("{method}: {e}");
                }
                return v["result"].clone();
            }
        }
    }

    fn open(&mut self, url: &str) {
        let t = self.call("Target.createTarget", json!({"url": "about:blank"}), false);
        let s = self.call(
            "Target.attachToTarget",
            json!({"targetId": t["targetId"], "flatten": true}),
            false,
        );
        self.session = Some(s["sessionId"].as_str().unwrap().to_string());
        self.call("Page.enable", json!({}), true);
        self.call("Runtime.enable", json!({}), true);
        self.call("Page.navigate", json!({ "url": url }), true);
    }

    fn eval(&mut self, expr: &str) -> Value {
        let r = self.call(
            "Runtime.evaluate",
            json!({"expression": expr, "returnByValue": true, "awaitPromise": true}),
            true,
        );
        if let Some(e) = r.get("exceptionDetails") {
            panic!("page script {expr}: {e}");
        }
        r["result"]["value"].clone()
    }

    /// Polls `expr` until it is true, or fails with `what` and a page report.
    fn wait_for(&mut self, expr: &str, what: &str, secs: u64) {
        let until = Instant::now() + Duration::from_secs(secs);
        while Instant::now() < until {
            if self.eval(&format!("!!({expr})")) == json!(true) {
                return;
            }
            std::thread::sleep(Duration::from_millis(100));
        }
        let report = self.eval(
            "JSON.stringify({url: location.href, ready: document.readyState, \
             scripts: [typeof StudioCamera, typeof StudioViewer, typeof studio], \
             res: performance.getEntriesByType('resource').map(e => [e.name, Math.round(e.startTime), Math.round(e.responseEnd)]), \
             status: document.getElementById('status') && document.getElementById('status').textContent, \
             diag: document.getElementById('diagnostics') && document.getElementById('diagnostics').textContent, \
             state: window.studio && studio.state && {gen: studio.state.gen, stage: studio.state.stage, error: studio.state.error}})",
        );
        panic!("timed out waiting for {what}: {report}");
    }

    fn screenshot(&mut self, path: &Path) {
        let r = self.call("Page.captureScreenshot", json!({"format": "png"}), true);
        let png = base64::engine::general_purpose::STANDARD
            .decode(r["data"].as_str().unwrap())
            .unwrap();
        assert_eq!(&png[1..4], b"PNG");
        std::fs::write(path, png).unwrap();
    }

    fn mouse(&mut self, kind: &str, x: f64, y: f64) {
        self.call(
            "Input.dispatchMouseEvent",
            json!({"type": kind, "x": x, "y": y, "button": "left", "buttons": if kind == "mouseReleased" { 0 } else { 1 }, "clickCount": 1}),
            true,
        );
    }
}

impl Drop for Browser {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
        let _ = std::fs::remove_dir_all(&self.profile);
    }
}

fn screenshots() -> PathBuf {
    let base = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../../target"));
    let d = base.join("studio-screenshots");
    std::fs::create_dir_all(&d).unwrap();
    d
}

const BROKEN: &str = "-- a ball whose radius is a[1]\nmy_model(x[3], a[1]) {\n  r2 = x[1]*x[1] + x[2]*x[2] + x[3]*x[3];\n  my_model = a[1]*a[1] - r2 +;\n}\n";
const BALL: &str = "-- a ball whose radius is a[1]\n-- a[1] = 0.6 in [0.2, 0.9]\n-- Box [-1, 1]^3.\nmy_model(x[3], a[1]) {\n  r2 = x[1]*x[1] + x[2]*x[2] + x[3]*x[3];\n  my_model = a[1]*a[1] - r2;\n}\n";

#[test]
fn studio_in_headless_chromium() {
    if std::env::var("MICROFREP_BROWSER").as_deref() != Ok("1") {
        println!(
            "skipped: set MICROFREP_BROWSER=1 to run the browser test (needs Debian's chromium)"
        );
        return;
    }
    let exe = chromium().expect(
        "MICROFREP_BROWSER=1 but no Chromium found (install Debian's `chromium`, or set \
         MICROFREP_CHROMIUM to its path)",
    );
    let root = std::env::temp_dir().join(format!("mf-studio-browser-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    std::fs::create_dir_all(&root).unwrap();
    let studio = Studio::start(ServeOptions {
        port: 0,
        root: root.clone(),
        levels: vec![32, 64],
        analysis: [32, 64],
        settle: Duration::from_millis(100),
        ..ServeOptions::default()
    })
    .unwrap();
    let shots = screenshots();
    let mut b = Browser::launch(&exe);
    b.open(&studio.url());
    b.wait_for(
        "window.studio && studio.ready",
        "the page to start a session",
        30,
    );
    b.wait_for(
        "studio.state && studio.state.done && studio.meshLoads > 0",
        "the sample model",
        60,
    );
    assert_eq!(
        b.eval("studio.viewer.ok"),
        json!(true),
        "no WebGL in Chromium"
    );
    b.screenshot(&shots.join("01-sample.png"));

    // Type a model with a syntax error, as a user would.
    b.eval("document.getElementById('filename').value = 'ball.hf'; const t = document.getElementById('source'); t.focus(); t.select(); true");
    b.call("Input.insertText", json!({ "text": BROKEN }), true);
    b.wait_for(
        "document.getElementById('diagnostics').textContent.includes('ball.hf:4:')",
        "the diagnostics of the broken model",
        30,
    );
    let diag = b.eval("document.getElementById('diagnostics').textContent");
    let diag = diag.as_str().unwrap();
    assert!(diag.contains("ball.hf:4:30: error:"), "{diag}");
    assert!(diag.contains("my_model = a[1]*a[1] - r2 +;"), "{diag}");
    // The gutter marks line 4, and the editor underlines the position.
    assert_eq!(
        b.eval("document.querySelector('.gutter').children[3].className"),
        json!("err")
    );
    assert_eq!(
        b.eval("document.querySelectorAll('.editor pre .me').length > 0"),
        json!(true)
    );
    b.screenshot(&shots.join("02-diagnostics.png"));

    // Fix it: a ball of radius 0.6 in [-1, 1]^3.
    b.eval("const u = document.getElementById('source'); u.focus(); u.select(); true");
    b.call("Input.insertText", json!({ "text": BALL }), true);
    b.wait_for(
        "studio.state && studio.state.done && studio.state.analysis.refined && studio.state.model && studio.state.model.params.length === 1",
        "the ball's refined analysis",
        60,
    );
    b.wait_for(
        "document.getElementById('analysis-body').dataset.kind === 'refined'",
        "the analysis panel",
        10,
    );
    let vf: f64 = b
        .eval("+document.getElementById('analysis-body').dataset.volumeFraction")
        .as_f64()
        .unwrap();
    let exact = |r: f64| 4.0 / 3.0 * PI * r.powi(3) / 8.0;
    assert!(
        (vf - exact(0.6)).abs() < 2e-3,
        "volume fraction {vf} vs {}",
        exact(0.6)
    );
    let panel = b.eval("document.getElementById('analysis-body').textContent");
    let panel = panel.as_str().unwrap();
    assert!(
        panel.contains("volume fraction") && panel.contains("porosity"),
        "{panel}"
    );
    assert!(panel.contains(&format!("{:.4}", vf)), "{panel}");
    b.wait_for("studio.shown.level === 1", "the refined mesh on screen", 30);
    std::thread::sleep(Duration::from_millis(300));
    let before = b.eval("studio.viewer.pixelHash()");
    b.screenshot(&shots.join("03-ball.png"));

    // Drag the a[1] slider from 0.6 towards 0.9.
    let rect = b.eval(
        "(() => { const s = document.querySelector('#param-list input[type=range]'); \
         const r = s.getBoundingClientRect(); return [r.left, r.top, r.width, r.height, +s.value]; })()",
    );
    let r: Vec<f64> = rect
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let gen0 = b.eval("studio.state.gen").as_u64().unwrap();
    let y = r[1] + r[3] / 2.0;
    let x0 = r[0] + r[2] * (r[4] / 1000.0);
    b.mouse("mousePressed", x0, y);
    for k in 1..=5 {
        b.mouse(
            "mouseMoved",
            x0 + (r[0] + 0.9 * r[2] - x0) * k as f64 / 5.0,
            y,
        );
        std::thread::sleep(Duration::from_millis(30));
    }
    b.mouse("mouseReleased", r[0] + 0.9 * r[2], y);
    let value: f64 = b.eval("studio.params[0].value").as_f64().unwrap();
    assert!(value > 0.75 && value < 0.9, "slider value {value}");
    b.wait_for(
        &format!("studio.state.gen > {gen0} && studio.state.done && studio.state.analysis.refined && studio.shown.gen === studio.state.gen && studio.shown.level === 1"),
        "the model after the slider moved",
        60,
    );
    std::thread::sleep(Duration::from_millis(300));
    let vf2: f64 = b
        .eval("studio.state.analysis.refined.report.volume_fraction.value")
        .as_f64()
        .unwrap();
    assert!(
        (vf2 - exact(value)).abs() < 3e-3,
        "volume fraction {vf2} vs {} at a[1] = {value}",
        exact(value)
    );
    let after = b.eval("studio.viewer.pixelHash()");
    assert_ne!(before["hash"], after["hash"], "the image did not change");
    assert!(
        after["lit"].as_f64().unwrap() > 1.2 * before["lit"].as_f64().unwrap(),
        "the bigger ball covers no more pixels: {before} {after}"
    );
    b.screenshot(&shots.join("04-slider.png"));

    // A section through the middle with its value map, and the cut-away.
    b.eval("const a = document.getElementById('sec-axis'); a.value = '1'; a.dispatchEvent(new Event('change')); \
            const m = document.getElementById('sec-map'); m.checked = true; m.dispatchEvent(new Event('change')); true");
    b.wait_for("studio.viewer.quad !== null", "the section's value map", 20);
    std::thread::sleep(Duration::from_millis(300));
    let cut = b.eval("studio.viewer.pixelHash()");
    assert_ne!(
        cut["hash"], after["hash"],
        "the section did not change the image"
    );
    b.screenshot(&shots.join("05-section.png"));

    // The camera refits when an edit changes the model's size, keeping the
    // user's orbit; a small edit after a hand zoom keeps the zoom.
    b.eval("(() => { const s = document.getElementById('sec-axis'); s.value = '-1'; s.dispatchEvent(new Event('change')); return true; })()");
    let rect = b.eval(
        "(() => { const r = document.getElementById('canvas').getBoundingClientRect(); \
         return [r.left + r.width / 2, r.top + r.height / 2]; })()",
    );
    let (cx, cy) = (rect[0].as_f64().unwrap(), rect[1].as_f64().unwrap());
    b.mouse("mousePressed", cx, cy);
    for k in 1..=4 {
        b.mouse("mouseMoved", cx + 20.0 * k as f64, cy + 8.0 * k as f64);
    }
    b.mouse("mouseReleased", cx + 80.0, cy + 32.0);
    let orbit = b.eval("[studio.viewer.yaw, studio.viewer.pitch, studio.viewer.refits]");
    assert!(
        (orbit[0].as_f64().unwrap() + 0.785).abs() > 0.3,
        "the drag did not orbit: {orbit}"
    );
    let big = b.eval("studio.viewer.pixelHash()");
    let small = |r: f64| {
        format!("my_model(x[3], a[1]) {{\n  my_model = {r}*{r} - x[1]*x[1] - x[2]*x[2] - x[3]*x[3];\n}}\n")
    };
    let gen = b.eval("studio.state.gen").as_u64().unwrap();
    b.eval(&format!("studio.setSource({}); true", json!(small(0.3))));
    b.wait_for(
        &format!("studio.state.gen > {gen} && studio.state.done && studio.state.model && studio.state.model.bounds_source === 'proven' && studio.shown.gen === studio.state.gen && studio.shown.level === 1"),
        "the small ball with proven bounds",
        60,
    );
    std::thread::sleep(Duration::from_millis(300));
    let after = b.eval(
        "[studio.viewer.yaw, studio.viewer.pitch, studio.viewer.refits, studio.viewer.lastRefit]",
    );
    assert_eq!(after[0], orbit[0], "the refit lost the orbit");
    assert_eq!(after[1], orbit[1], "the refit lost the orbit");
    assert_eq!(
        after[2].as_u64().unwrap(),
        orbit[2].as_u64().unwrap() + 1,
        "{after}"
    );
    assert_eq!(after[3], "size");
    // Without the refit the ball of radius 0.3 would cover about
    // (0.3 / 0.85)^2 = 12 % of the pixels of the big one; refitted to its
    // own box it fills the view as the big ball did its box.
    let refit = b.eval("studio.viewer.pixelHash()");
    let (l0, l1) = (big["lit"].as_f64().unwrap(), refit["lit"].as_f64().unwrap());
    assert!(
        l1 > 0.6 * l0,
        "the small ball is not framed: {l1} lit pixels vs {l0}"
    );
    b.screenshot(&shots.join("06-refit.png"));
    // Zoom in by hand, then grow the ball by 5 %: the view stays.
    b.call(
        "Input.dispatchMouseEvent",
        json!({"type": "mouseWheel", "x": cx, "y": cy, "deltaX": 0, "deltaY": -400}),
        true,
    );
    let zoomed = b.eval("[studio.viewer.dist, studio.viewer.refits]");
    let gen = b.eval("studio.state.gen").as_u64().unwrap();
    b.eval(&format!("studio.setSource({}); true", json!(small(0.315))));
    b.wait_for(
        &format!("studio.state.gen > {gen} && studio.state.done && studio.shown.gen === studio.state.gen && studio.shown.level === 1"),
        "the slightly bigger ball",
        60,
    );
    let kept = b.eval("[studio.viewer.dist, studio.viewer.refits]");
    assert_eq!(kept, zoomed, "a 5 % edit undid the hand zoom");

    // A mesh part bound by a comment: the femur, 470 mm long, after a ball
    // 0.6 across; the view refits to it.
    let femur = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/meshes/femur.stl");
    if femur.is_file() {
        std::fs::create_dir_all(root.join("parts")).unwrap();
        std::fs::copy(&femur, root.join("parts/femur.stl")).unwrap();
        let src = "-- load with --field part=parts/femur.stl\nmy_model(x[3], a[1]) {\n  my_model = part(x);\n}\n";
        let gen = b.eval("studio.state.gen").as_u64().unwrap();
        let refits = b.eval("studio.viewer.refits").as_u64().unwrap();
        b.eval(&format!("studio.setSource({}); true", json!(src)));
        b.wait_for(
            &format!("studio.state.gen > {gen} && studio.state.done && studio.shown.gen === studio.state.gen && studio.shown.level === 1"),
            "the femur part",
            60,
        );
        let ok = b.eval("document.getElementById('diagnostics').textContent");
        assert!(
            ok.as_str()
                .unwrap()
                .contains("part = parts/femur.stl (mesh"),
            "{ok}"
        );
        assert_eq!(b.eval("studio.state.model.bounds_source"), "part");
        assert_eq!(b.eval("studio.viewer.refits"), refits + 1);
        assert_eq!(b.eval("studio.viewer.lastRefit"), "size");
        std::thread::sleep(Duration::from_millis(300));
        let lit = b.eval("studio.viewer.pixelHash()")["lit"].as_f64().unwrap();
        assert!(lit > 0.02 * l0, "the femur is hardly on screen: {lit}");
        b.screenshot(&shots.join("07-femur.png"));
    } else {
        println!("no ../shared/meshes/femur.stl: the mesh-part step was skipped");
    }
    println!("screenshots in {}", shots.display());
    drop(b);
    studio.stop();
    let _ = std::fs::remove_dir_all(&root);
}
