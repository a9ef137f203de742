//! The CLI as users of other tools expect it: scans in the frames they
//! know and help choosing an iso value (`scan-info`), vector options in
//! the documented form, one layer or a range of layers, printer presets,
//! `check` with the model options of `mesh`, and the README's commands.
#![allow(clippy::needless_range_loop)]

use std::path::{Path, PathBuf};
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_microfrep");

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("mf-cli-habits-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Runs the CLI; returns (exit code, stdout, stderr).
fn run(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(BIN).args(args).output().unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn ok(args: &[&str]) -> (String, String) {
    let (code, out, err) = run(args);
    assert_eq!(code, 0, "{args:?}\nstdout: {out}\nstderr: {err}");
    (out, err)
}

/// The ball's centre in LPS, its radius, the grid.
const C: [f64; 3] = [12.0, -30.0, 5.0];
const R: f64 = 4.0;
const N: usize = 24;
const H: f64 = 0.5;

fn origin() -> [f64; 3] {
    C.map(|c| c - 0.5 * H * (N as f64 - 1.0))
}

/// CT values (HU) of the phantom at sample (i, j, k): air -1000, a ramp
/// 1 mm wide, +1000 inside.
fn hu(i: usize, j: usize, k: usize) -> i16 {
    let o = origin();
    let p = [i, j, k];
    let d = (0..3)
        .map(|a| (o[a] + p[a] as f64 * H - C[a]).powi(2))
        .sum::<f64>()
        .sqrt();
    (2000.0 * (R - d)).clamp(-1000.0, 1000.0).round() as i16
}

/// A CT phantom as an LPS NRRD file.
fn phantom(d: &Path) -> PathBuf {
    let o = origin();
    let mut bytes = format!(
        "NRRD0004\ntype: short\ndimension: 3\nspace: left-posterior-superior\nsizes: {N} {N} {N}\n\
         space directions: ({H},0,0) (0,{H},0) (0,0,{H})\nspace origin: ({},{},{})\n\
         kinds: domain domain domain\nendian: little\nencoding: raw\n\n",
        o[0], o[1], o[2]
    )
    .into_bytes();
    for k in 0..N {
        for j in 0..N {
            for i in 0..N {
                bytes.extend(hu(i, j, k).to_le_bytes());
            }
        }
    }
    let p = d.join("ct.nrrd");
    std::fs::write(&p, bytes).unwrap();
    p
}

/// The bounding box of a binary STL.
fn stl_box(p: &Path) -> [[f64; 3]; 2] {
    let b = std::fs::read(p).unwrap();
    let n = u32::from_le_bytes(b[80..84].try_into().unwrap()) as usize;
    assert_eq!(b.len(), 84 + 50 * n, "binary STL");
    let mut bb = [[f64::INFINITY; 3], [f64::NEG_INFINITY; 3]];
    for t in 0..n {
        for v in 0..3 {
            for a in 0..3 {
                let at = 84 + 50 * t + 12 + 12 * v + 4 * a;
                let x = f32::from_le_bytes(b[at..at + 4].try_into().unwrap()) as f64;
                bb[0][a] = bb[0][a].min(x);
                bb[1][a] = bb[1][a].max(x);
            }
        }
    }
    bb
}

#[test]
fn scan_info_reports_frame_range_histogram_and_thresholds_with_their_volumes() {
    let d = dir("info");
    let ct = phantom(&d);
    let ct = ct.to_str().unwrap();
    let (out, _) = ok(&["scan-info", ct, "--json"]);
    let j: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(j["dims"], serde_json::json!([N, N, N]));
    assert_eq!(j["frame"], "LPS");
    assert_eq!(j["min"], -1000.0);
    assert_eq!(j["max"], 1000.0);
    assert_eq!(j["looks_like_ct"], true);
    let counts: Vec<u64> = j["histogram"]["counts"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_u64().unwrap())
        .collect();
    assert_eq!(counts.iter().sum::<u64>(), (N * N * N) as u64);
    // Each suggestion's volume against a count made here.
    let samples: Vec<i16> = (0..N * N * N)
        .map(|n| hu(n % N, n / N % N, n / (N * N)))
        .collect();
    let sugg = j["suggestions"].as_array().unwrap();
    let names: Vec<&str> = sugg.iter().map(|s| s["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["otsu", "bone"]);
    for s in sugg {
        let iso = s["iso"].as_f64().unwrap();
        let want = samples.iter().filter(|&&v| v as f64 >= iso).count() as u64;
        assert_eq!(s["voxels"].as_u64().unwrap(), want, "{s}");
        let vol = s["volume_mm3"].as_f64().unwrap();
        assert!((vol - want as f64 * H * H * H).abs() < 1e-9);
        assert!(s["source"]
            .as_str()
            .unwrap()
            .ends_with(&format!(":iso={iso}")));
    }
    // Otsu splits air from the ball: between the two levels.
    let otsu = sugg[0]["iso"].as_f64().unwrap();
    assert!(otsu > -900.0 && otsu < 900.0, "{otsu}");
    // The bone volume is near the ball of radius R - 0.15 (300 HU on the ramp).
    let bone = sugg[1]["volume_mm3"].as_f64().unwrap();
    let ball = 4.0 / 3.0 * std::f64::consts::PI * (R - 0.15f64).powi(3);
    assert!((bone / ball - 1.0).abs() < 0.05, "{bone} vs {ball}");

    // The text report names the frame and shows a histogram.
    let (out, _) = ok(&["scan-info", ct, "--rows", "10"]);
    assert!(out.contains("LPS (x to the patient's left"), "{out}");
    assert_eq!(out.matches(" %  ").count(), 10, "{out}");
    assert!(out.contains(&format!("{ct}:iso=300")), "{out}");
    // Reading options come before the suggested iso.
    let spec = format!("{ct}:frame=ras");
    let (out, _) = ok(&["scan-info", &spec, "--json"]);
    let j: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(j["frame"], "RAS");
    let bx = j["bounds_mm"][1][0].as_f64().unwrap();
    let want = -(origin()[0] - 0.5 * H);
    assert!((bx - want).abs() < 1e-9, "{bx} vs {want}");
    assert!(j["suggestions"][1]["source"]
        .as_str()
        .unwrap()
        .ends_with(":frame=ras,iso=300"));
    // Errors: no file, not a scan, an unknown frame, an unknown option.
    let (code, _, err) = run(&["scan-info", d.join("none.nrrd").to_str().unwrap()]);
    assert!(code != 0 && err.contains("no such file"), "{err}");
    let (code, _, err) = run(&["scan-info", &format!("{ct}:frame=world")]);
    assert!(
        code != 0 && err.contains("use file, lps, ras or voxel"),
        "{err}"
    );
    let (code, _, err) = run(&["scan-info", &format!("{ct}:iso=3")]);
    assert!(code != 0 && err.contains("unknown option 'iso'"), "{err}");
}

/// A mesh made from the scan lands where the frame puts it; the summary
/// says which frame; `spacing=X,Y,Z` is accepted as documented.
#[test]
fn meshes_from_scans_land_in_the_frame_asked_for() {
    let d = dir("frames");
    let ct = phantom(&d);
    let ct = ct.to_str().unwrap();
    for (frame, centre) in [
        ("lps", C),
        ("ras", [-C[0], -C[1], C[2]]),
        ("voxel", C.map(|_| 0.5 * H * (N as f64 - 1.0))),
    ] {
        let stl = d.join(format!("{frame}.stl"));
        let spec = format!("{ct}:iso=0,frame={frame}");
        let (_, err) = ok(&[
            "mesh",
            &spec,
            "-o",
            stl.to_str().unwrap(),
            "--resolution",
            "48",
        ]);
        assert!(err.contains("coordinates in"), "{err}");
        let bb = stl_box(&stl);
        for a in 0..3 {
            let mid = 0.5 * (bb[0][a] + bb[1][a]);
            let half = 0.5 * (bb[1][a] - bb[0][a]);
            assert!(
                (mid - centre[a]).abs() < 0.1,
                "{frame} axis {a}: {mid} vs {}",
                centre[a]
            );
            assert!((half - R).abs() < 0.25, "{frame} axis {a}: {half}");
        }
    }
    // Spacing as X,Y,Z (and as XxYxZ): doubling x doubles the x extent.
    for sp in ["1,0.5,0.5", "1x0.5x0.5"] {
        let stl = d.join("spaced.stl");
        let spec = format!("{ct}:iso=0,spacing={sp},frame=voxel");
        ok(&[
            "mesh",
            &spec,
            "-o",
            stl.to_str().unwrap(),
            "--resolution",
            "48",
            "--quiet",
        ]);
        let bb = stl_box(&stl);
        let (wx, wy) = (bb[1][0] - bb[0][0], bb[1][1] - bb[0][1]);
        assert!((wx / wy - 2.0).abs() < 0.05, "{sp}: {wx} {wy}");
    }
    let (code, _, err) = run(&["mesh", &format!("{ct}:iso=0,spacing=1,2"), "-o", "x.stl"]);
    assert!(code != 0 && err.contains("expected X,Y,Z in mm"), "{err}");
}

#[test]
fn slice_one_height_a_range_of_layers_presets_and_the_plan() {
    let d = dir("slice");
    let out = |n: &str| d.join(n).display().to_string();
    // A box 0.2 high sliced in 0.2 layers: one layer, no rounding error.
    let one = out("one");
    let model = d.join("slab.hf");
    std::fs::write(
        &model,
        "my_model(x[3], a[1]) { my_model = 0.5 - abs(x[1]); }",
    )
    .unwrap();
    let (j, _) = ok(&[
        "slice",
        model.to_str().unwrap(),
        "--bounds=-1,-1,10,1,1,10.2",
        "-o",
        &one,
        "--layer",
        "0.2",
        "--pixel",
        "0.1",
        "--json",
    ]);
    let j: serde_json::Value = serde_json::from_str(&j).unwrap();
    assert_eq!(
        (j["layers"].as_u64(), j["first_layer"].as_u64()),
        (Some(1), Some(0))
    );
    // The whole stack, then a range and one height of it: the same images
    // under the same names and heights.
    let full = out("full");
    ok(&[
        "slice", "sphere", "-o", &full, "--layer", "0.1", "--pixel", "0.05", "--quiet",
    ]);
    let part = out("part");
    let (_, err) = ok(&[
        "slice", "sphere", "-o", &part, "--layer", "0.1", "--pixel", "0.05", "--layers", "7..9",
    ]);
    assert!(
        err.contains("slicing: layers 7..9 of 40 x 40 pixels"),
        "{err}"
    );
    let names: Vec<String> = {
        let mut v: Vec<String> = std::fs::read_dir(&part)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    };
    assert_eq!(
        names,
        [
            "layer_00007.png",
            "layer_00008.png",
            "layer_00009.png",
            "manifest.json"
        ]
    );
    for n in &names[..3] {
        let a = std::fs::read(Path::new(&full).join(n)).unwrap();
        let b = std::fs::read(Path::new(&part).join(n)).unwrap();
        assert_eq!(a, b, "{n}");
    }
    let m: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(Path::new(&part).join("manifest.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(m["first_layer"], 7);
    assert!((m["layers"][0]["z"].as_f64().unwrap() - (-1.0 + 7.5 * 0.1)).abs() < 1e-12);
    // --z: layer 8's middle is at -0.15; the one layer sampled there is
    // layer 8's image.
    let at = out("at");
    ok(&[
        "slice",
        "sphere",
        "-o",
        &at,
        "--layer",
        "0.1",
        "--pixel",
        "0.05",
        "--z=-0.15",
        "--quiet",
    ]);
    let a = std::fs::read(Path::new(&at).join("layer_00000.png")).unwrap();
    assert_eq!(
        a,
        std::fs::read(Path::new(&full).join("layer_00008.png")).unwrap()
    );
    let m: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(Path::new(&at).join("manifest.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(m["layers"][0]["z"], -0.15);
    // Out of range and malformed requests.
    for (args, msg) in [
        (vec!["--layers", "38..45"], "the stack has layers 0..39"),
        (vec!["--layers", "9..7"], "expected FROM..TO"),
        (vec!["--z", "3"], "outside the box's z range"),
        (vec!["--preset", "mj-600x300-27um"], "square pixels"),
        (vec!["--preset", "nope"], "dlp-25um"),
    ] {
        let o = out("bad");
        let mut a = vec!["slice", "sphere", "-o", &o];
        a.extend(args);
        let (code, _, err) = run(&a);
        assert!(code != 0 && err.contains(msg), "{a:?}: {err}");
        assert!(!Path::new(&o).exists());
    }
    // Defaults come from the vat-50um preset, and the plan says so.
    let def = out("default");
    let (_, err) = ok(&["slice", "sphere", "-o", &def]);
    assert!(
        err.contains(
            "slicing: 40 layers of 40 x 40 pixels, pixel 0.05 and layer 0.05 (preset vat-50um)"
        ),
        "{err}"
    );
    let dlp = out("dlp");
    let (_, err) = ok(&[
        "slice", "sphere", "-o", &dlp, "--preset", "dlp-25um", "--layer", "0.1",
    ]);
    assert!(
        err.contains("20 layers of 80 x 80 pixels, pixel 0.025 and layer 0.1"),
        "{err}"
    );
}

#[test]
fn materials_lists_the_presets_it_knows() {
    let d = dir("materials");
    let o = d.join("m").display().to_string();
    let (code, _, err) = run(&[
        "materials",
        "sphere",
        "-o",
        &o,
        "--palette",
        "a=#ff0000",
        "--preset",
        "nope",
    ]);
    assert_ne!(code, 0);
    for p in [
        "mj-600x300-27um",
        "mj-600x300-14um",
        "mj-600x600-27um",
        "vat-50um",
        "dlp-25um",
    ] {
        assert!(err.contains(p), "{err}");
    }
}

#[test]
fn check_takes_fields_and_parameters_and_finds_constant_indices() {
    let d = dir("check");
    let ct = phantom(&d);
    let model = d.join("m.hf");
    std::fs::write(
        &model,
        "my_model(x[3], a[1]) { my_model = part(x) - a[1]; }",
    )
    .unwrap();
    let m = model.to_str().unwrap();
    // Without the field: unknown function, as mesh would say.
    let (code, _, err) = run(&["check", m]);
    assert!(code != 0 && err.contains("part"), "{err}");
    let field = format!("part={}:iso=0", ct.display());
    let (out, err) = ok(&["check", m, "--field", &field, "-a", "1=0.5"]);
    assert!(out.contains("ok (0 warning(s))"), "{out}");
    assert!(err.contains("part: coordinates in LPS"), "{err}");
    let (code, _, err) = run(&["check", m, "--field", &field, "-a", "2=0.5"]);
    assert!(code != 0 && err.contains("a[2] out of range"), "{err}");
    let (code, _, err) = run(&["check", m, "--field", "part=none.stl"]);
    assert!(code != 0 && err.contains("none.stl"), "{err}");
    // A constant index out of range, with its place.
    std::fs::write(
        &model,
        "my_model(x[3], a[1]) {\n  my_model = x[1] + x[4];\n}\n",
    )
    .unwrap();
    let (code, _, err) = run(&["check", m]);
    assert_ne!(code, 0);
    assert!(
        err.contains(":2:23: error: Array index out of range"),
        "{err}"
    );
}

#[test]
fn voxels_values_and_the_field_option_are_distinct() {
    let d = dir("voxels");
    let ct = phantom(&d);
    let model = d.join("m.hf");
    std::fs::write(&model, "my_model(x[3], a[1]) { my_model = part(x); }").unwrap();
    let raw = d.join("v.raw");
    let field = format!("part={}:iso=0", ct.display());
    ok(&[
        "voxels",
        model.to_str().unwrap(),
        "--field",
        &field,
        "--values",
        "-o",
        raw.to_str().unwrap(),
        "--voxel",
        "1",
        "--quiet",
    ]);
    let side: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("v.json")).unwrap()).unwrap();
    let n: usize = side["dims"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap() as usize)
        .product();
    // f32 values: four bytes a voxel.
    assert_eq!(std::fs::metadata(&raw).unwrap().len() as usize, 4 * n);
}

/// Every concrete command in the README's code blocks parses: the options
/// it shows exist and take the values it gives them.
#[test]
fn the_readme_commands_parse() {
    let readme =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../README.md"))
            .unwrap();
    let mut n = 0;
    let mut in_block = false;
    for line in readme.lines() {
        if line.starts_with("```") {
            in_block = !in_block;
            continue;
        }
        if !in_block {
            continue;
        }
        let cmd = line
            .strip_prefix("cargo run --release -p microfrep-cli -- ")
            .or_else(|| line.strip_prefix("$ microfrep "));
        let Some(cmd) = cmd else { continue };
        let cmd = cmd.split(" #").next().unwrap_or(cmd);
        let args: Vec<&str> = cmd.split_whitespace().collect();
        let out = Command::new(BIN)
            .args(&args)
            .env("MICROFREP_PARSE_ONLY", "1")
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "README: {line}\n{}",
            String::from_utf8_lossy(&out.stderr)
        );
        n += 1;
    }
    assert!(n >= 10, "only {n} commands found in the README");
}

/// `eval MODEL x y z --grad`, the README's order, with negative
/// coordinates; a field name bound twice is an error, not a silent choice.
#[test]
fn eval_flags_after_negative_coordinates_and_fields_bound_twice() {
    let (out, _) = ok(&["eval", "sphere", "0.5", "-0.25", "0", "--grad"]);
    let v: Vec<f64> = out.split_whitespace().map(|t| t.parse().unwrap()).collect();
    assert_eq!(v.len(), 4, "{out}");
    // The sphere is 1 - |p|^2 or 1 - |p|: the gradient points inwards.
    assert!(v[1] < 0.0 && v[2] > 0.0 && v[3].abs() < 1e-12, "{out}");
    let (out, _) = ok(&["eval", "sphere", "--grad", "-0.5", "0", "0"]);
    assert_eq!(out.split_whitespace().count(), 4, "{out}");
    let d = dir("twice");
    let ct = phantom(&d);
    let model = d.join("m.hf");
    std::fs::write(&model, "my_model(x[3], a[1]) { my_model = part(x); }").unwrap();
    let f1 = format!("part={}:iso=0", ct.display());
    let f2 = format!("part={}:iso=500", ct.display());
    let (code, _, err) = run(&[
        "eval",
        model.to_str().unwrap(),
        "--field",
        &f1,
        "--field",
        &f2,
        "0",
        "0",
        "0",
    ]);
    assert!(code != 0 && err.contains("bound twice"), "{err}");
}

/// An axis cube of side 2 about the origin, as HyperFun.
const CUBE: &str =
    "my_model(x[3], a[1]) {\n  my_model = min(min(1 - abs(x[1]), 1 - abs(x[2])), 1 - abs(x[3]));\n}\n";

/// The largest distance of a face of the box `b` from that of [-1, 1]^3.
fn off_unit_box(b: [[f64; 3]; 2]) -> f64 {
    (0..3)
        .map(|a| (b[0][a] + 1.0).abs().max((b[1][a] - 1.0).abs()))
        .fold(0.0, f64::max)
}

/// `mesh --sharp` keeps a CAD part's faces where they are: an axis cube
/// of side 2 meshed at 20 cells has its box at +-1 within 0.02 cells, where
/// the default's volume correction pushes the faces out by about 0.2
/// cells; a tets mesh with --sharp is refused.
#[test]
fn sharp_meshes_keep_a_cubes_faces_on_their_planes() {
    let d = dir("sharp");
    let m = d.join("cube.hf");
    std::fs::write(&m, CUBE).unwrap();
    let mesh = |extra: &[&str], out: &Path| {
        let mut args = vec![
            "mesh",
            m.to_str().unwrap(),
            "--bounds",
            "-1.2,-1.2,-1.2,1.2,1.2,1.2",
            "--resolution",
            "25",
            "-o",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        ok(&args);
        stl_box(out)
    };
    // Cells of 0.096: the faces fall between grid nodes.
    let h = 2.4 / 25.0;
    let plain = mesh(&[], &d.join("plain.stl"));
    let sharp = mesh(&["--sharp"], &d.join("sharp.stl"));
    let off = |b: [[f64; 3]; 2]| off_unit_box(b) / h;
    assert!(off(sharp) < 0.02, "sharp box {sharp:?}");
    assert!(
        off(plain) > 0.05,
        "the default's box {plain:?} (the test would not tell)"
    );
    let (code, _, err) = run(&[
        "mesh",
        m.to_str().unwrap(),
        "--cells",
        "tets",
        "--sharp",
        "-o",
        d.join("t.stl").to_str().unwrap(),
    ]);
    assert!(code != 0 && err.contains("--sharp"), "{err}");
}

/// `mesh --sharp --tolerance` merges a cube's faces into a few triangles
/// (12 at best; the merge stops where a collapse would not keep the
/// mesh closed) with its box still at +-1, reports what it merged and how
/// far from the surface it measured (in both units), and refuses a
/// tolerance that is not a positive distance or a mesh it must stream.
#[test]
fn tolerance_merges_a_cubes_faces_and_reports_it() {
    let d = dir("tolerance");
    let m = d.join("cube.hf");
    std::fs::write(&m, CUBE).unwrap();
    let h = 2.4 / 25.0;
    let mesh = |extra: &[&str], out: &Path| {
        let mut args = vec![
            "mesh",
            m.to_str().unwrap(),
            "--bounds",
            "-1.2,-1.2,-1.2,1.2,1.2,1.2",
            "--resolution",
            "25",
            "--sharp",
            "--json",
            "-o",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        let (o, _) = ok(&args);
        let j: serde_json::Value = serde_json::from_str(o.trim()).unwrap();
        (j, stl_box(out))
    };
    let (plain, _) = mesh(&[], &d.join("plain.stl"));
    for (t, limit) in [("0.05", 0.05 * h), ("0.002mm", 0.002)] {
        let (j, b) = mesh(&["--tolerance", t], &d.join("merged.stl"));
        let merged = &j["merged"];
        let after = j["triangles"].as_u64().unwrap();
        assert_eq!(merged["triangles_before"], plain["triangles"], "{j}");
        assert_eq!(merged["triangles_after"].as_u64(), Some(after), "{j}");
        assert!(
            after <= 100 && after * 20 < plain["triangles"].as_u64().unwrap(),
            "{j}"
        );
        assert!(merged["deviation"].as_f64().unwrap() <= limit, "{j}");
        assert_eq!(j["bad_edges"], 0, "{j}");
        assert!(off_unit_box(b) < 0.02 * h, "{b:?}");
        let v = j["volume"].as_f64().unwrap();
        assert!((v - 8.0).abs() < 1e-4, "{j}");
    }
    for bad in ["0", "-1", "x", "nanmm"] {
        let (code, _, err) = run(&[
            "mesh",
            m.to_str().unwrap(),
            "--tolerance",
            bad,
            "-o",
            d.join("bad.stl").to_str().unwrap(),
        ]);
        assert!(
            code != 0 && err.contains("positive distance"),
            "{bad}: {err}"
        );
    }
    let (code, _, err) = run(&[
        "mesh",
        m.to_str().unwrap(),
        "--resolution",
        "25",
        "--tolerance",
        "0.05",
        "--stream",
        "-o",
        d.join("s.stl").to_str().unwrap(),
    ]);
    assert!(code != 0 && err.contains("in memory"), "{err}");
    assert!(!d.join("s.stl").exists());
}
