//! `mesh --color-by` and `render --color-by`: vertex colours read back from
//! PLY, OBJ and 3MF equal the colour map of the attribute at each vertex
//! (a closed form, and the model's own f64 evaluation); a rendered ramp
//! changes hue monotonically with a legend of the map's ends; a section
//! coloured by a material split shows each colour on its side, with a
//! legend and a scale bar of the length its pixel size gives; STL and
//! missing channels are refused with clear messages.

use microfrep::io::colormap::{Colormap, ColourScale};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn bin() -> PathBuf {
    PathBuf::from(env!("CARGO_BIN_EXE_microfrep"))
}

fn run(args: &[&str]) -> Output {
    Command::new(bin()).args(args).output().unwrap()
}

fn ok(args: &[&str]) -> serde_json::Value {
    let out = run(args);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

fn fails(args: &[&str]) -> String {
    let out = run(args);
    assert!(!out.status.success(), "{args:?} succeeded");
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("mf-cli-colours-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The cube [-1, 1]^3 with s[1] = x (a ramp) and s[2] = y z.
const RAMP: &str = "my_model(x[3], a[1], s[2]) {
  array c[3];
  c = [-1, -1, -1];
  s[1] = x[1];
  s[2] = x[2] * x[3];
  my_model = hfBlock(x, c, 2, 2, 2);
}
";
const BOX: &str = "-1.2,-1.2,-1.2,1.2,1.2,1.2";

fn ramp(d: &Path) -> String {
    let p = d.join("ramp.hf");
    std::fs::write(&p, RAMP).unwrap();
    p.to_str().unwrap().to_string()
}

fn example(name: &str) -> String {
    format!("{}/../../examples/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// Vertices and colours of the binary PLY this tool writes (float x y z,
/// optional float normals, uchar red green blue).
fn read_ply(p: &Path) -> (Vec<[f64; 3]>, Vec<[u8; 3]>) {
    let b = std::fs::read(p).unwrap();
    let end = b.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    let head = std::str::from_utf8(&b[..end]).unwrap();
    let n: usize = head
        .lines()
        .find_map(|l| l.strip_prefix("element vertex "))
        .unwrap()
        .parse()
        .unwrap();
    assert!(head.contains("property uchar red\nproperty uchar green\nproperty uchar blue\n"));
    let floats = head
        .lines()
        .take_while(|l| !l.starts_with("element face"))
        .filter(|l| l.starts_with("property float"))
        .count();
    let rec = 4 * floats + 3;
    (0..n)
        .map(|i| {
            let r = &b[end + i * rec..end + (i + 1) * rec];
            let f = |k: usize| f32::from_le_bytes(r[4 * k..4 * k + 4].try_into().unwrap()) as f64;
            ([f(0), f(1), f(2)], [r[rec - 3], r[rec - 2], r[rec - 1]])
        })
        .unzip()
}

fn read_obj(p: &Path) -> (Vec<[f64; 3]>, Vec<[u8; 3]>) {
    std::fs::read_to_string(p)
        .unwrap()
        .lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|l| {
            let w: Vec<f64> = l.split(' ').map(|t| t.parse().unwrap()).collect();
            assert_eq!(w.len(), 6, "{l}");
            let c = [w[3], w[4], w[5]].map(|x| {
                assert!((0.0..=1.0).contains(&x), "{l}");
                (255.0 * x).round() as u8
            });
            ([w[0], w[1], w[2]], c)
        })
        .unzip()
}

fn read_3mf(p: &Path) -> (Vec<[f64; 3]>, Vec<[u8; 3]>) {
    let m = microfrep_3mf::read_file(p).unwrap();
    let g = &m.color_groups[0];
    let microfrep_3mf::ObjectContent::Mesh(me) = &m.objects[0].content else {
        panic!("no mesh")
    };
    let props = me.properties.as_ref().unwrap();
    assert_eq!(props.pid, g.id);
    let mut c = vec![[0u8; 3]; me.vertices.len()];
    for (t, q) in me.triangles.iter().zip(&props.indices) {
        for k in 0..3 {
            let col = g.colors[q[k] as usize];
            c[t[k] as usize] = [col[0], col[1], col[2]];
        }
    }
    (me.vertices.clone(), c)
}

fn range(j: &serde_json::Value) -> [f64; 2] {
    let r = j["colour_range"].as_array().unwrap();
    [r[0].as_f64().unwrap(), r[1].as_f64().unwrap()]
}

fn within_one(got: [u8; 3], want: [u8; 3]) -> bool {
    (0..3).all(|k| got[k].abs_diff(want[k]) <= 1)
}

#[test]
fn mesh_colours_are_the_map_of_the_attribute_at_each_vertex() {
    let d = dir("mesh");
    let model = ramp(&d);
    type Reader = fn(&Path) -> (Vec<[f64; 3]>, Vec<[u8; 3]>);
    for (name, read, extra) in [
        ("r.ply", read_ply as Reader, None),
        ("r.obj", read_obj, Some("grey")),
        ("r.3mf", read_3mf, None),
        ("s.ply", read_ply, Some("stream")),
    ] {
        let out = d.join(name);
        let o = out.to_str().unwrap();
        let mut args = vec![
            "mesh",
            &model,
            "-o",
            o,
            "--bounds",
            BOX,
            "--resolution",
            "24",
            "--color-by",
            "1",
            "--json",
        ];
        let map = match extra {
            Some("grey") => {
                args.extend(["--colormap", "grey"]);
                Colormap::Grey
            }
            Some("stream") => {
                args.push("--stream");
                Colormap::Viridis
            }
            _ => Colormap::Viridis,
        };
        let j = ok(&args);
        // The default range is s[1] = x over the vertices: the cube's -1..1.
        let [lo, hi] = range(&j);
        assert!(
            (lo + 1.0).abs() < 1e-3 && (hi - 1.0).abs() < 1e-3,
            "{name}: {lo} {hi}"
        );
        let scale = ColourScale::new(map, lo, hi).unwrap();
        let (v, c) = read(&out);
        assert_eq!(v.len() as u64, j["vertices"].as_u64().unwrap(), "{name}");
        assert!(v.len() > 500);
        for (p, got) in v.iter().zip(&c) {
            // The closed form of the attribute: s[1] = x.
            let want = scale.colour(p[0]);
            assert!(
                within_one(*got, want),
                "{name} at {p:?}: {got:?} vs {want:?}"
            );
        }
    }
    // The colours in the file follow --range (clamped outside it).
    let out = d.join("n.ply");
    let j = ok(&[
        "mesh",
        &model,
        "-o",
        out.to_str().unwrap(),
        "--bounds",
        BOX,
        "--resolution",
        "16",
        "--color-by",
        "2",
        "--range",
        "-0.5,0.5",
        "--json",
    ]);
    assert_eq!(range(&j), [-0.5, 0.5]);
    let scale = ColourScale::new(Colormap::Viridis, -0.5, 0.5).unwrap();
    let (v, c) = read_ply(&out);
    for (p, got) in v.iter().zip(&c) {
        assert!(within_one(*got, scale.colour(p[1] * p[2])), "{p:?}");
    }
}

#[test]
fn a_park_example_is_coloured_by_its_own_f64_evaluation() {
    let d = dir("park");
    let model = example("park_fig2_bias_gain.hf");
    let out = d.join("p.ply");
    let j = ok(&[
        "mesh",
        &model,
        "-o",
        out.to_str().unwrap(),
        "--resolution",
        "48",
        "--color-by",
        "2",
        "--json",
    ]);
    let [lo, hi] = range(&j);
    let scale = ColourScale::new(Colormap::Viridis, lo, hi).unwrap();
    let loaded = microfrep::load(&model, &Default::default()).unwrap();
    let attr = &loaded.shape.attributes()[1];
    let mut pe = microfrep::core::PointEval::new(&microfrep::core::Tape::new(&attr.expr));
    let (v, c) = read_ply(&out);
    assert!(v.len() > 1000);
    let mut near = 0;
    for (p, got) in v.iter().zip(&c) {
        let want = scale.colour(pe.eval(*p));
        near += within_one(*got, want) as usize;
    }
    // The bias-gain grading has steps in x (between the cubes, outside the
    // solid) only; every vertex agrees.
    assert_eq!(near, v.len());
}

/// Hue in degrees.
fn hue(c: [u8; 3]) -> f64 {
    let [r, g, b] = c.map(|v| v as f64);
    let (mx, mn) = (r.max(g).max(b), r.min(g).min(b));
    let d = mx - mn;
    if d == 0.0 {
        return 0.0;
    }
    let h = if mx == r {
        (g - b) / d
    } else if mx == g {
        (b - r) / d + 2.0
    } else {
        (r - g) / d + 4.0
    };
    (60.0 * h).rem_euclid(360.0)
}

#[test]
fn render_shades_by_the_attribute_with_a_legend() {
    let d = dir("render");
    let model = ramp(&d);
    let out = d.join("r.png");
    let j = ok(&[
        "render",
        &model,
        "-o",
        out.to_str().unwrap(),
        "--bounds",
        BOX,
        "--view",
        "front",
        "--size",
        "400x240",
        "--color-by",
        "1",
        "--json",
    ]);
    let [lo, hi] = range(&j);
    assert!(lo < -0.95 && hi > 0.95, "{lo} {hi}");
    let bar: Vec<usize> = j["legend_bar"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap() as usize)
        .collect();
    let img = microfrep_io::png::decode(&std::fs::read(&out).unwrap(), &out).unwrap();
    assert_eq!(img.pixels, microfrep_io::png::Pixels::Rgb);
    let (w, h, px) = (img.width, img.height, img.data);
    assert_eq!((w, h), (400, 240));
    let pixel = |x: usize, y: usize| {
        let k = 3 * (y * w + x);
        [px[k], px[k + 1], px[k + 2]]
    };
    let bg = [250, 250, 250];
    // The front face x = -1..1, left to right: viridis hue falls
    // monotonically from purple to yellow.
    let row: Vec<[u8; 3]> = (0..bar[0] - 2)
        .map(|x| pixel(x, h / 2))
        .filter(|&c| c != bg)
        .collect();
    assert!(row.len() > 100);
    for p in row.windows(2) {
        assert!(hue(p[1]) <= hue(p[0]) + 1.0, "{:?} then {:?}", p[0], p[1]);
    }
    assert!(hue(row[0]) > 250.0 && hue(row[row.len() - 1]) < 70.0);
    // The legend's bar has the map's end colours at its ends.
    let (bx, by, bw, bh) = (bar[0], bar[1], bar[2], bar[3]);
    assert!(bx > row.len() && bx + bw < w && by + bh < h);
    assert_eq!(pixel(bx + bw / 2, by), Colormap::Viridis.rgb(1.0));
    assert_eq!(pixel(bx + bw / 2, by + bh - 1), Colormap::Viridis.rgb(0.0));
    // The labels: dark ink above and below the bar.
    let ink = |ys: std::ops::Range<usize>| {
        ys.flat_map(|y| (bar[0] - 40..w).map(move |x| (x, y)))
            .filter(|&(x, y)| pixel(x, y) == [30, 30, 30])
            .count()
    };
    assert!(ink(0..by) > 5 && ink(by + bh..h) > 5);
}

#[test]
fn bad_requests_are_refused_with_the_reason() {
    let d = dir("errors");
    let model = ramp(&d);
    let o = |n: &str| d.join(n).to_str().unwrap().to_string();
    let stl = o("r.stl");
    let e = fails(&[
        "mesh",
        &model,
        "-o",
        &stl,
        "--bounds",
        BOX,
        "--color-by",
        "1",
    ]);
    assert!(
        e.contains("no per-vertex colours") && e.contains(".ply"),
        "{e}"
    );
    let e = fails(&[
        "mesh",
        &model,
        "-o",
        &stl,
        "--bounds",
        BOX,
        "--color-by",
        "1",
        "--stream",
    ]);
    assert!(e.contains("no per-vertex colours"), "{e}");
    let ply = o("r.ply");
    let e = fails(&[
        "mesh",
        &model,
        "-o",
        &ply,
        "--bounds",
        BOX,
        "--color-by",
        "3",
    ]);
    assert!(
        e.contains("attribute 3 does not exist") && e.contains("2 attribute channel"),
        "{e}"
    );
    let e = fails(&["mesh", "sphere", "-o", &ply, "--color-by", "1"]);
    assert!(e.contains("0 attribute channel"), "{e}");
    let e = fails(&[
        "mesh",
        &model,
        "-o",
        &ply,
        "--bounds",
        BOX,
        "--color-by",
        "0",
    ]);
    assert!(e.contains("count from 1"), "{e}");
    let e = fails(&[
        "mesh",
        &model,
        "-o",
        &ply,
        "--color-by",
        "1",
        "--range",
        "2,1",
    ]);
    assert!(e.contains("LO < HI"), "{e}");
    let e = fails(&["mesh", &model, "-o", &ply, "--colormap", "grey"]);
    assert!(e.contains("--color-by"), "{e}");
    let e = fails(&[
        "mesh",
        &model,
        "-o",
        &ply,
        "--color-by",
        "1",
        "--colormap",
        "jet",
    ]);
    assert!(e.contains("viridis"), "{e}");
    let png = o("r.png");
    let e = fails(&[
        "render",
        &model,
        "-o",
        &png,
        "--bounds",
        BOX,
        "--color-by",
        "5",
    ]);
    assert!(
        e.contains("attribute 5 does not exist") && e.contains("2 attribute channel"),
        "{e}"
    );
    let e = fails(&[
        "render",
        &model,
        "-o",
        &png,
        "--bounds",
        BOX,
        "--color-by",
        "3",
        "--section",
        "z=0",
    ]);
    assert!(e.contains("attribute 3 does not exist"), "{e}");
    // Nothing was written (the model file only).
    assert_eq!(std::fs::read_dir(&d).unwrap().count(), 1);
}

/// The cube [-1, 1]^3 with s[1] = 1 for x < 0, else 0.
const SPLIT: &str = "my_model(x[3], a[1], s[1]) {
  array c[3];
  c = [-1, -1, -1];
  s[1] = 0;
  if x[1] < 0 then
    s[1] = 1;
  endif;
  my_model = hfBlock(x, c, 2, 2, 2);
}
";

#[test]
fn render_section_colours_the_material_with_a_legend_and_a_scale_bar() {
    let d = dir("section");
    let model = d.join("split.hf");
    std::fs::write(&model, SPLIT).unwrap();
    let out = d.join("s.png");
    let j = ok(&[
        "render",
        model.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--bounds",
        "-1,-1,-1,1,1,1",
        "--section",
        "z=0",
        "--size",
        "300x200",
        "--color-by",
        "1",
        "--json",
    ]);
    assert_eq!(range(&j), [0.0, 1.0]);
    let px_size = j["pixel"].as_f64().unwrap();
    // 300 x 200 less the legend strip (44) and the scale band (16): the
    // 2 x 2 section fits 256 x 184 pixels.
    assert!((px_size - 2.0 / 184.0).abs() < 1e-12, "{px_size}");
    let img = microfrep_io::png::decode(&std::fs::read(&out).unwrap(), &out).unwrap();
    let (w, h, px) = (img.width, img.height, img.data);
    assert_eq!((w, h), (300, 200));
    let pixel = |x: usize, y: usize| {
        let k = 3 * (y * w + x);
        [px[k], px[k + 1], px[k + 2]]
    };
    // The section is centred in the 256 pixels left of the legend: model x
    // runs from column 36 to 220, x = 0 at column 128.
    let (left, right) = (Colormap::Viridis.rgb(1.0), Colormap::Viridis.rgb(0.0));
    for y in [20, 92, 170] {
        for x in 40..216 {
            let c = pixel(x, y);
            if x + 1 < 128 {
                assert_eq!(c, left, "({x}, {y})");
            } else if x > 128 {
                assert_eq!(c, right, "({x}, {y})");
            } else {
                assert!(c == left || c == right, "({x}, {y}): {c:?}");
            }
        }
    }
    // Legend: the map's ends at the ends of its bar.
    let bar: Vec<usize> = j["legend_bar"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap() as usize)
        .collect();
    assert!(bar[0] >= 256);
    assert_eq!(
        pixel(bar[0] + bar[2] / 2, bar[1]),
        Colormap::Viridis.rgb(1.0)
    );
    assert_eq!(
        pixel(bar[0] + bar[2] / 2, bar[1] + bar[3] - 1),
        Colormap::Viridis.rgb(0.0)
    );
    // Scale bar: 0.5 model units, 46 pixels at 2/184 per pixel, in ink.
    let sb = &j["scale_bar"];
    assert_eq!(sb["length"].as_f64(), Some(0.5));
    let p: Vec<usize> = sb["pixels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap() as usize)
        .collect();
    assert_eq!(p[2], 46);
    for y in p[1]..p[1] + p[3] {
        let ink: Vec<usize> = (0..256).filter(|&x| pixel(x, y) == [30, 30, 30]).collect();
        assert_eq!(ink.len(), 46, "row {y}");
        assert_eq!(ink[0], p[0]);
    }
    // Without --color-by the section shows the value, through --colormap
    // over --range.
    let j = ok(&[
        "render",
        model.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--bounds",
        "-1,-1,-1,1,1,1",
        "--section",
        "z=0",
        "--size",
        "300x200",
        "--colormap",
        "grey",
        "--range=-3,3",
        "--json",
    ]);
    assert_eq!(range(&j), [-3.0, 3.0]);
    let img = microfrep_io::png::decode(&std::fs::read(&out).unwrap(), &out).unwrap();
    let k = 3 * (92 * 300 + 128);
    let c = &img.data[k..k + 3];
    assert!(
        c[0] == c[1] && c[1] == c[2] && c[0] > 128,
        "{c:?}: grey, above the middle"
    );
    assert!(j["scale_bar"]["length"].as_f64() == Some(0.5));
}

/// Park's Fig. 6 (written with mfSubspace) in section: titanium (s[2] = 1)
/// deep in the stem, bioceramic (s[2] = 0) in the shell under its surface.
#[test]
fn render_section_of_the_femur_shows_its_material_subspace() {
    let d = dir("femur");
    let out = d.join("f.png");
    let j = ok(&[
        "render",
        &example("park_fig6_femur_gradient.hf"),
        "-o",
        out.to_str().unwrap(),
        "--section",
        "z=0",
        "--size",
        "600x500",
        "--color-by",
        "2",
        "--json",
    ]);
    assert_eq!(range(&j), [0.0, 1.0]);
    let px = j["pixel"].as_f64().unwrap();
    let o: Vec<f64> = j["origin"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let img = microfrep_io::png::decode(&std::fs::read(&out).unwrap(), &out).unwrap();
    let at = |x: f64, y: f64| {
        let (c, r) = (((x - o[0]) / px) as usize, ((o[1] - y) / px) as usize);
        let k = 3 * (r * img.width + c);
        [img.data[k], img.data[k + 1], img.data[k + 2]]
    };
    // The stem at y = -1 has half-width 0.5 sqrt(1 - 1/7.5) = 0.465.
    assert_eq!(at(0.0, -1.0), Colormap::Viridis.rgb(1.0));
    assert_eq!(at(0.43, -1.0), Colormap::Viridis.rgb(0.0));
    assert_eq!(at(-0.43, -1.0), Colormap::Viridis.rgb(0.0));
    // The head's centre (0.6, 3.4), radius 0.75: titanium inside.
    assert_eq!(at(0.6, 3.4), Colormap::Viridis.rgb(1.0));
    // Outside: the background.
    assert_eq!(at(1.0, -1.0), [250, 250, 250]);
}
