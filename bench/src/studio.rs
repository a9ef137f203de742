//! Suite `studio`: responsiveness of `microfrep serve`. A studio server runs
//! in this process with its default levels (meshes at 48, 128 and 192
//! cells, analysis at 64 then 128 voxels, refinement 0.3 s after the last
//! edit) and is driven over HTTP on loopback as the page drives it. Times
//! are the server's own, from the moment the edit request arrived: the
//! first preview mesh ready to download (`first_image_s`), the finest mesh
//! ready (`refined_s`), and the quick and refined analysis figures. Each
//! example is loaded once, then edited `EDITS` times (the edit changes a
//! comment, which costs what any edit costs: the studio redoes every stage);
//! figures are medians. `interrupt_first_image_s`: an edit posted while
//! the previous one is busy refining, to its first image (the stale work is
//! stopped at its next brick).

use microfrep_studio::client::Client;
use microfrep_studio::{ServeOptions, Studio};
use serde_json::{json, Value};
use std::time::Duration;

const EXAMPLES: [&str; 3] = [
    "fryazinov_fig4_toriball_block",
    "pasko_fig4_shape_with_lattice",
    "pasko_fig3a_sphere_shell_lattice",
];
const EDITS: usize = 3;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn io(e: std::io::Error) -> String {
    e.to_string()
}

fn post_edit(c: &Client, s: &str, src: &str, file: &str) -> Result<u64, String> {
    let st = c
        .post_json(
            "/api/edit",
            &json!({ "session": s, "source": src, "file": file, "wait_ms": 0 }),
        )
        .map_err(io)?;
    st["latest_gen"]
        .as_u64()
        .ok_or_else(|| format!("no generation in {st}"))
}

fn wait_done(c: &Client, s: &str, gen: u64) -> Result<Value, String> {
    let st = c
        .get_json(&format!("/api/wait?session={s}&gen={gen}&wait_ms=300000"))
        .map_err(io)?;
    if st["finished"] != json!(true) || !st["error"].is_null() {
        return Err(format!(
            "generation {gen} did not finish cleanly: {}",
            st["error"]
        ));
    }
    Ok(st)
}

/// Polls until generation `gen` has a first mesh; returns the state.
fn wait_first(c: &Client, s: &str, gen: u64) -> Result<Value, String> {
    let mut since = 0;
    for _ in 0..10_000 {
        let st = c
            .get_json(&format!(
                "/api/state?session={s}&since={since}&wait_ms=5000"
            ))
            .map_err(io)?;
        since = st["version"].as_u64().unwrap_or(0);
        if st["gen"] == json!(gen) && st["timings"]["first_mesh_s"].is_number() {
            return Ok(st);
        }
    }
    Err("no first mesh".into())
}

pub fn run() -> Result<(), String> {
    let root = std::env::current_dir().map_err(io)?;
    let studio = Studio::start(ServeOptions {
        port: 0,
        root: root.clone(),
        ..ServeOptions::default()
    })
    .map_err(|e| e.to_string())?;
    let c = Client::new(studio.addr());
    for name in EXAMPLES {
        let file = format!("examples/{name}.hf");
        let src = std::fs::read_to_string(root.join(&file)).map_err(|e| format!("{file}: {e}"))?;
        let s = c.post_json("/api/session", &json!({})).map_err(io)?;
        let s = s["session"].as_str().unwrap_or_default().to_string();
        wait_done(&c, &s, post_edit(&c, &s, &src, &file)?)?;
        let mut keys: Vec<(&str, Vec<f64>)> = [
            "first_mesh_s",
            "refined_mesh_s",
            "quick_analysis_s",
            "refined_analysis_s",
        ]
        .iter()
        .map(|k| (*k, Vec::new()))
        .collect();
        let mut last = Value::Null;
        for k in 0..EDITS {
            let edited = format!("{src}-- edit {k}\n");
            let st = wait_done(&c, &s, post_edit(&c, &s, &edited, &file)?)?;
            for (key, v) in keys.iter_mut() {
                v.push(st["timings"][*key].as_f64().unwrap_or(f64::NAN));
            }
            last = st;
        }
        // An edit that arrives while the previous one is refining.
        let busy = post_edit(&c, &s, &format!("{src}-- busy\n"), &file)?;
        let _ = wait_first(&c, &s, busy)?;
        std::thread::sleep(Duration::from_millis(400));
        let next = post_edit(&c, &s, &format!("{src}-- next\n"), &file)?;
        let st = wait_first(&c, &s, next)?;
        let interrupt = st["timings"]["first_mesh_s"].as_f64().unwrap_or(f64::NAN);
        wait_done(&c, &s, next)?;
        let m = last["meshes"].as_array().cloned().unwrap_or_default();
        let tri = |i: usize| m.get(i).map_or(0, |m| m["triangles"].as_u64().unwrap_or(0));
        let res: Vec<String> = m.iter().map(|m| m["resolution"].to_string()).collect();
        let vf = last["analysis"]["refined"]["report"]["volume_fraction"]["value"]
            .as_f64()
            .unwrap_or(f64::NAN);
        let med: Vec<f64> = keys.into_iter().map(|(_, v)| median(v)).collect();
        println!(
            "RESULT studio_{name} first_image_s={:.3} refined_s={:.3} quick_analysis_s={:.3} \
             refined_analysis_s={:.3} interrupt_first_image_s={interrupt:.3} levels={} \
             triangles_first={} triangles_refined={} volume_fraction={vf:.5} edits={EDITS} threads={}",
            med[0],
            med[1],
            med[2],
            med[3],
            res.join("/"),
            tri(0),
            tri(m.len().saturating_sub(1)),
            rayon_threads(),
        );
    }
    studio.stop();
    Ok(())
}

fn rayon_threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}
