//! Vertex colours from an attribute: PLY, OBJ and 3MF files read back give
//! each vertex the colour map's colour of the attribute evaluated (f64) at
//! that vertex, within one 8-bit step; streamed PLY equals the in-memory
//! file; STL, missing channels and bad ranges are refused before meshing.

use microfrep_core::{Expr, Shape};
use microfrep_mesh::job::{mesh_to_file, JobOptions};
use microfrep_mesh::write::colour::{Colormap, ColourBy, ColourScale};
use microfrep_mesh::{MeshError, MeshOptions};
use microfrep_shapes as prims;
use std::path::{Path, PathBuf};

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("microfrep-colours-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A ball of radius 0.9 with s1 = x + y/2 (range about -1..1) and s2 = z^2.
fn ball() -> Shape {
    let [x, y, z] = Expr::xyz();
    Shape::from(&prims::sphere(&Expr::xyz(), &prims::v3([0.0; 3]), 0.9))
        .with_attribute("s1", &x + 0.5 * &y)
        .with_attribute("s2", z.square())
}

fn opts() -> MeshOptions {
    MeshOptions::new([[-1.0; 3], [1.0; 3]], 24)
}

fn job(by: ColourBy, stream: bool) -> JobOptions {
    JobOptions {
        stream,
        colour: Some(by),
        ..JobOptions::default()
    }
}

/// Vertices and colours of a binary little-endian PLY, by its header.
fn read_ply(p: &Path) -> (Vec<[f32; 3]>, Vec<[u8; 3]>) {
    let b = std::fs::read(p).unwrap();
    let end = b.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    let head = std::str::from_utf8(&b[..end]).unwrap();
    assert!(head.contains("format binary_little_endian 1.0"));
    let mut n = 0usize;
    let mut props: Vec<(String, usize)> = Vec::new();
    let mut in_vertex = false;
    for l in head.lines() {
        let w: Vec<&str> = l.split_whitespace().collect();
        match w.as_slice() {
            ["element", "vertex", k] => {
                n = k.parse().unwrap();
                in_vertex = true;
            }
            ["element", ..] => in_vertex = false,
            ["property", t, name] if in_vertex => {
                let size = match *t {
                    "float" => 4,
                    "uchar" => 1,
                    _ => panic!("{t}"),
                };
                props.push((name.to_string(), size));
            }
            _ => {}
        }
    }
    let rec: usize = props.iter().map(|p| p.1).sum();
    let off = |name: &str| {
        let k = props.iter().position(|p| p.0 == name).unwrap();
        props[..k].iter().map(|p| p.1).sum::<usize>()
    };
    let (ox, or) = (off("x"), off("red"));
    assert_eq!((off("green"), off("blue")), (or + 1, or + 2));
    let mut v = Vec::new();
    let mut c = Vec::new();
    for i in 0..n {
        let r = &b[end + i * rec..end + (i + 1) * rec];
        let f = |k: usize| f32::from_le_bytes(r[ox + 4 * k..ox + 4 * k + 4].try_into().unwrap());
        v.push([f(0), f(1), f(2)]);
        c.push([r[or], r[or + 1], r[or + 2]]);
    }
    (v, c)
}

/// Vertices and colours of `v x y z r g b` lines.
fn read_obj(p: &Path) -> (Vec<[f32; 3]>, Vec<[u8; 3]>) {
    let s = std::fs::read_to_string(p).unwrap();
    let mut v = Vec::new();
    let mut c = Vec::new();
    for l in s.lines().filter(|l| l.starts_with("v ")) {
        let w: Vec<f32> = l[2..].split(' ').map(|t| t.parse().unwrap()).collect();
        assert_eq!(w.len(), 6, "{l}");
        v.push([w[0], w[1], w[2]]);
        let byte = |x: f32| {
            assert!((0.0..=1.0).contains(&x));
            (x * 255.0).round() as u8
        };
        c.push([byte(w[3]), byte(w[4]), byte(w[5])]);
    }
    (v, c)
}

/// Vertices and per-vertex colours of the mesh of a 3MF written here.
fn read_3mf(p: &Path) -> (Vec<[f32; 3]>, Vec<[u8; 3]>) {
    let m = microfrep_3mf::read_file(p).unwrap();
    assert_eq!(m.color_groups.len(), 1);
    let g = &m.color_groups[0];
    let microfrep_3mf::ObjectContent::Mesh(me) = &m.objects[0].content else {
        panic!("not a mesh")
    };
    assert_eq!(m.objects[0].property, Some((g.id, 0)));
    let props = me.properties.as_ref().unwrap();
    assert_eq!(props.pid, g.id);
    let mut c = vec![None; me.vertices.len()];
    for (t, q) in me.triangles.iter().zip(&props.indices) {
        for k in 0..3 {
            let col = g.colors[q[k] as usize];
            assert_eq!(col[3], 255);
            let rgb = [col[0], col[1], col[2]];
            // A vertex has one colour, whichever triangle names it.
            assert!(c[t[k] as usize].is_none_or(|x| x == rgb));
            c[t[k] as usize] = Some(rgb);
        }
    }
    let v = me.vertices.iter().map(|p| p.map(|x| x as f32)).collect();
    (v, c.into_iter().map(Option::unwrap).collect())
}

/// Checks each colour against the map of the attribute at its vertex in
/// f64; returns the largest difference seen.
fn check(shape: &Shape, channel: usize, scale: &ColourScale, v: &[[f32; 3]], c: &[[u8; 3]]) {
    assert_eq!(v.len(), c.len());
    assert!(v.len() > 1000);
    let tape = microfrep_core::Tape::new(&shape.attributes()[channel].expr);
    let mut pe = microfrep_core::PointEval::new(&tape);
    for (p, got) in v.iter().zip(c) {
        let want = scale.colour(pe.eval(p.map(|x| x as f64)));
        for k in 0..3 {
            assert!(
                got[k].abs_diff(want[k]) <= 1,
                "vertex {p:?}: {got:?}, expected {want:?}"
            );
        }
    }
}

#[test]
fn ply_obj_and_3mf_carry_the_attribute_colour_of_every_vertex() {
    let d = dir("formats");
    let shape = ball();
    let by = ColourBy {
        channel: 0,
        colormap: Colormap::Viridis,
        range: None,
    };
    for (name, read) in [
        (
            "b.ply",
            read_ply as fn(&Path) -> (Vec<[f32; 3]>, Vec<[u8; 3]>),
        ),
        ("b.obj", read_obj),
        ("b.3mf", read_3mf),
    ] {
        let out = d.join(name);
        let s = mesh_to_file(&shape, &opts(), &out, &job(by.clone(), false), &|_, _| {}).unwrap();
        let scale = s.colour_scale.unwrap();
        // The default range is the attribute's over the vertices: nearly
        // the ball's extremes of x + y/2, +-0.9 sqrt(1.25).
        let ext = 0.9 * 1.25f64.sqrt();
        assert!(
            (scale.lo + ext).abs() < 0.05 && (scale.hi - ext).abs() < 0.05,
            "{scale:?}"
        );
        let (v, c) = read(&out);
        assert_eq!(v.len() as u64, s.vertices, "{name}");
        check(&shape, 0, &scale, &v, &c);
        // Both ends of the map are used.
        assert!(c.contains(&Colormap::Viridis.rgb(0.0)) && c.contains(&Colormap::Viridis.rgb(1.0)));
    }
    // A given range and the grey map: z^2 over 0..0.25, clamped above.
    let by = ColourBy {
        channel: 1,
        colormap: Colormap::Grey,
        range: Some([0.0, 0.25]),
    };
    let out = d.join("g.ply");
    let s = mesh_to_file(&shape, &opts(), &out, &job(by, false), &|_, _| {}).unwrap();
    let scale = s.colour_scale.unwrap();
    assert_eq!((scale.lo, scale.hi), (0.0, 0.25));
    let (v, c) = read_ply(&out);
    check(&shape, 1, &scale, &v, &c);
    assert!(c.iter().all(|x| x[0] == x[1] && x[1] == x[2]));
    let white = v.iter().zip(&c).filter(|(_, c)| c[0] == 255).count();
    let above = v.iter().filter(|p| p[2].abs() > 0.5).count();
    assert!(white >= above && above > 100, "{white} {above}");
}

#[test]
fn colours_held_in_memory_are_in_the_predicted_peak() {
    let d = dir("peak");
    let by = ColourBy {
        channel: 0,
        colormap: Colormap::Viridis,
        range: None,
    };
    let shape = ball();
    let (tape, grid) = microfrep_mesh::Plan::frame(&shape, &opts()).unwrap();
    let est = microfrep_mesh::memory::estimate_grid(&tape, &grid, opts().cells);
    let run = |j: &JobOptions, name: &str| {
        mesh_to_file(&shape, &opts(), &d.join(name), j, &|_, _| {}).unwrap()
    };
    let plain = run(&JobOptions::default(), "plain.ply");
    let coloured = run(&job(by.clone(), false), "coloured.ply");
    let streamed = run(&job(by, true), "streamed.ply");
    assert!(!plain.streamed && !coloured.streamed && streamed.streamed);
    let extra = coloured.predicted_bytes - plain.predicted_bytes;
    let want = microfrep_mesh::memory::COLOUR_BYTES_PER_VERT * est.vertices;
    assert!(
        want > 0.0 && (extra - want).abs() < 1e-6 * want,
        "{extra} vs {want}"
    );
    // Streamed, the values wait in a scratch file: no more memory.
    let plain_streamed = run(
        &JobOptions {
            stream: true,
            ..JobOptions::default()
        },
        "plain_streamed.ply",
    );
    assert_eq!(streamed.predicted_bytes, plain_streamed.predicted_bytes);
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn streamed_coloured_ply_equals_the_in_memory_file() {
    let d = dir("stream");
    for range in [None, Some([-0.5, 0.5])] {
        let by = ColourBy {
            channel: 0,
            colormap: Colormap::Viridis,
            range,
        };
        let (a, b) = (d.join("a.ply"), d.join("b.ply"));
        let sa = mesh_to_file(&ball(), &opts(), &a, &job(by.clone(), false), &|_, _| {}).unwrap();
        let sb = mesh_to_file(&ball(), &opts(), &b, &job(by, true), &|_, _| {}).unwrap();
        assert!(sb.streamed && !sa.streamed);
        assert_eq!(sa.colour_scale, sb.colour_scale);
        assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
    }
}

#[test]
fn stl_missing_channels_and_bad_ranges_are_refused_before_meshing() {
    let d = dir("errors");
    let by = |channel, range| ColourBy {
        channel,
        colormap: Colormap::Viridis,
        range,
    };
    for stream in [false, true] {
        let e = mesh_to_file(
            &ball(),
            &opts(),
            &d.join("b.stl"),
            &job(by(0, None), stream),
            &|_, _| {},
        )
        .unwrap_err();
        assert!(matches!(e, MeshError::Input(_)), "{e}");
        let m = e.to_string();
        assert!(
            m.contains("b.stl") && m.contains("no per-vertex colours") && m.contains(".ply"),
            "{m}"
        );
    }
    let e = mesh_to_file(
        &ball(),
        &opts(),
        &d.join("b.ply"),
        &job(by(2, None), false),
        &|_, _| {},
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("attribute 3 does not exist") && e.contains("2 attribute channel"),
        "{e}"
    );
    let plain = Shape::from(&prims::sphere(&Expr::xyz(), &prims::v3([0.0; 3]), 0.9));
    let e = mesh_to_file(
        &plain,
        &opts(),
        &d.join("b.ply"),
        &job(by(0, None), false),
        &|_, _| {},
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("0 attribute channel") && e.contains("s[N]"),
        "{e}"
    );
    let e = mesh_to_file(
        &ball(),
        &opts(),
        &d.join("b.obj"),
        &job(by(0, Some([1.0, 0.0])), false),
        &|_, _| {},
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("colour range"), "{e}");
    // Nothing was written.
    assert_eq!(std::fs::read_dir(&d).unwrap().count(), 0);
}
