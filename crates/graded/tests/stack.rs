//! Material and grey stacks: palette parsing, images decoded back against
//! the manifest, transparent outside, atomic writes, presets; material
//! subspaces as fractions.

use microfrep_core::{Expr, PointEval, Tape};
use microfrep_graded::dither::Method;
use microfrep_graded::stack::{
    layer_file, preset, write_grey_stack, write_material_stack, Background, MaterialStack, Palette,
    StackGrid, PRESETS,
};
use microfrep_graded::subspace::{MaterialModel, Subspace};
use microfrep_graded::Error;
use std::path::{Path, PathBuf};

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("graded-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn decode(path: &Path) -> (png::ColorType, usize, usize, Vec<u8>) {
    let dec = png::Decoder::new(std::fs::File::open(path).unwrap());
    let mut r = dec.read_info().unwrap();
    let mut buf = vec![0; r.output_buffer_size()];
    let info = r.next_frame(&mut buf).unwrap();
    buf.truncate(info.buffer_size());
    (
        info.color_type,
        info.width as usize,
        info.height as usize,
        buf,
    )
}

#[test]
fn palettes_parse_and_bad_ones_say_what_is_expected() {
    let p = Palette::parse(" VeroCyan=#00A0E0 , soft-1=#ff0000,liquid.x=#000000").unwrap();
    assert_eq!(p.len(), 3);
    assert_eq!(p.materials()[1].rgb, [255, 0, 0]);
    assert_eq!(p.spec(), "VeroCyan=#00A0E0,soft-1=#FF0000,liquid.x=#000000");
    assert_eq!(p.spec().parse::<Palette>().unwrap(), p);
    let cases = [
        ("", 0, "empty palette"),
        ("a=#FFFFFF,b", 2, "expected NAME=#RRGGBB"),
        ("a=FFFFFF", 1, "# followed by 6 hex digits"),
        ("a=#FFFFF", 1, "6 hex digits"),
        ("a=#GG0000", 1, "6 hex digits"),
        ("a b=#FF0000", 1, "letters, digits"),
        ("=#FF0000", 1, "non-empty"),
        ("a=#FF0000,A=#00FF00", 2, "already used by entry 1"),
        ("a=#FF0000,b=#ff0000", 2, "tell them apart"),
    ];
    for (spec, entry, msg) in cases {
        match Palette::parse(spec) {
            Err(Error::Palette {
                entry: e, message, ..
            }) => {
                assert_eq!(e, entry, "{spec}");
                assert!(message.contains(msg), "{spec}: {message}");
            }
            other => panic!("{spec}: {other:?}"),
        }
    }
    let many: Vec<String> = (0..256).map(|i| format!("m{i}=#{:06X}", i)).collect();
    assert!(Palette::parse(&many.join(",")).is_err());
}

#[test]
fn presets_have_their_nominal_pitch() {
    let p = preset("mj-600x300-27um").unwrap();
    assert!((p.pitch()[0] - 0.042333).abs() < 1e-6 && (p.pitch()[1] - 0.084667).abs() < 1e-6);
    assert_eq!(p.layer, 0.027);
    assert!((preset("vat-50um").unwrap().pitch()[0] - 0.05).abs() < 1e-12);
    assert!(PRESETS.iter().all(|p| preset(p.name) == Some(p)));
    let g = StackGrid::from_preset([0.0; 3], [1.0, 1.0, 0.27], p).unwrap();
    assert_eq!((g.nx, g.ny, g.layers), (24, 12, 10));
    assert!(StackGrid::new([0.0; 3], [1.0; 3], [0.0, 1.0], 0.1).is_err());
    assert!(StackGrid::new([0.0; 3], [1e9, 1.0, 1.0], [1e-3, 1.0], 0.1).is_err());
}

/// A half-filled box graded along x between two materials, a third
/// material in a corner block.
fn source(grid: &StackGrid) -> impl FnMut(usize, &mut [f32], &mut [bool]) + '_ {
    move |k, frac, mask| {
        for j in 0..grid.ny {
            for i in 0..grid.nx {
                let q = j * grid.nx + i;
                let (x, y, z) = (grid.x(i), grid.y(j), grid.z(k));
                mask[q] = y < 0.5;
                frac[3 * q] = x as f32;
                frac[3 * q + 1] = if z > 0.6 && x > 0.6 {
                    1.0 - x as f32
                } else {
                    0.0
                };
            }
        }
    }
}

#[test]
fn material_stack_images_match_the_manifest() {
    let grid = StackGrid::new([0.0; 3], [1.0; 3], [0.02, 0.025], 0.05).unwrap();
    let palette = Palette::parse("hard=#FFFFFF,soft=#FF0000,clear=#000000").unwrap();
    let out = tmp("material");
    let mut opts = MaterialStack::new(palette.clone());
    opts.preset = Some("custom".into());
    let calls = std::sync::atomic::AtomicU64::new(0);
    let mut src = source(&grid);
    let r = write_material_stack(&out, &grid, &opts, &mut src, &|d, t| {
        assert!(d <= t);
        calls.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    })
    .unwrap();
    assert_eq!(calls.into_inner(), grid.layers as u64);
    assert_eq!((grid.nx, grid.ny, grid.layers), (50, 40, 20));
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("manifest.json")).unwrap()).unwrap();
    assert_eq!(m["pitch_x"], 0.02);
    assert_eq!(m["pitch_y"], 0.025);
    assert_eq!(m["layer_height"], 0.05);
    assert_eq!(m["image_size"], serde_json::json!([50, 40]));
    assert_eq!(m["dithering"], "error-diffusion");
    assert_eq!(m["preset"], "custom");
    assert_eq!(m["palette"], palette.spec());
    // Count colours in the images.
    let mut counts = [0u64; 3];
    let mut bytes = 0;
    for k in 0..grid.layers {
        let path = out.join(layer_file(k));
        bytes += std::fs::metadata(&path).unwrap().len();
        let (ct, w, h, px) = decode(&path);
        assert_eq!((ct, w, h), (png::ColorType::Rgba, 50, 40));
        for (q, c) in px.chunks(4).enumerate() {
            let (row, _i) = (q / w, q % w);
            let y = grid.y(h - 1 - row);
            if y < 0.5 {
                let mat = palette
                    .materials()
                    .iter()
                    .position(|m| m.rgb == [c[0], c[1], c[2]]);
                assert_eq!(c[3], 255);
                counts[mat.expect("a palette colour")] += 1;
            } else {
                assert_eq!(c, [0, 0, 0, 0], "outside is transparent");
            }
        }
    }
    assert_eq!(bytes, r.bytes);
    for mat in 0..3 {
        assert_eq!(m["materials"][mat]["voxels"], counts[mat]);
        assert_eq!(counts[mat], r.dither.counts[mat]);
        let integral = m["materials"][mat]["fraction_integral"].as_f64().unwrap();
        assert!((counts[mat] as f64 - integral).abs() <= 0.005 * integral + 1.0);
    }
    assert_eq!(r.dither.inside, 50 * 20 * 20);
    // No partial directory is left next to the output.
    let parent = out.parent().unwrap();
    let name = out.file_name().unwrap().to_string_lossy().to_string();
    assert!(std::fs::read_dir(parent).unwrap().all(|e| !e
        .unwrap()
        .file_name()
        .to_string_lossy()
        .starts_with(&format!(".{name}.partial"))));
    // Writing again over it is refused.
    let e = write_material_stack(&out, &grid, &opts, &mut source(&grid), &|_, _| {}).unwrap_err();
    assert!(e.to_string().contains("already exists"), "{e}");
    std::fs::remove_dir_all(&out).unwrap();
}

#[test]
fn opaque_backgrounds_and_deterministic_bytes() {
    let grid = StackGrid::new([0.0; 3], [1.0, 1.0, 0.2], [0.05, 0.05], 0.05).unwrap();
    let palette = Palette::parse("a=#FFFFFF,b=#FF0000,c=#0000FF").unwrap();
    let mut opts = MaterialStack::new(palette);
    opts.background = Background::Opaque([255, 255, 255]);
    let e = write_material_stack(&tmp("clash"), &grid, &opts, &mut source(&grid), &|_, _| {})
        .unwrap_err();
    assert!(e.to_string().contains("background colour"), "{e}");
    assert!(!tmp("clash").exists());
    opts.background = Background::Opaque([0, 255, 0]);
    opts.method = Method::Stochastic { seed: 3 };
    let (a, b) = (tmp("det-a"), tmp("det-b"));
    write_material_stack(&a, &grid, &opts, &mut source(&grid), &|_, _| {}).unwrap();
    write_material_stack(&b, &grid, &opts, &mut source(&grid), &|_, _| {}).unwrap();
    for k in 0..grid.layers {
        let (fa, fb) = (a.join(layer_file(k)), b.join(layer_file(k)));
        assert_eq!(std::fs::read(&fa).unwrap(), std::fs::read(&fb).unwrap());
        let (_, _, _, px) = decode(&fa);
        // Top rows (y >= 0.5) are the opaque background.
        assert_eq!(&px[..4], &[0, 255, 0, 255]);
    }
    for d in [a, b] {
        std::fs::remove_dir_all(d).unwrap();
    }
}

#[test]
fn grey_stack_pixels_are_255_times_the_clamped_value() {
    let grid = StackGrid::new([0.0; 3], [1.0, 0.5, 0.1], [0.1, 0.1], 0.05).unwrap();
    let out = tmp("grey");
    let r = write_grey_stack(
        &out,
        &grid,
        &mut |k, v, mask| {
            for q in 0..v.len() {
                let i = q % grid.nx;
                mask[q] = i != 0;
                v[q] = match i {
                    1 => -0.5,
                    2 => f32::NAN,
                    3 => 2.0,
                    _ => grid.x(i) as f32 + 0.1 * k as f32,
                };
            }
        },
        &|_, _| {},
    )
    .unwrap();
    assert_eq!(r.dither.inside, 9 * 5 * 2);
    for k in 0..2 {
        let (ct, w, h, px) = decode(&out.join(layer_file(k)));
        assert_eq!((ct, w, h), (png::ColorType::Grayscale, 10, 5));
        for row in px.chunks(10) {
            assert_eq!(&row[..4], &[0, 0, 0, 255]);
            for (i, &p) in row.iter().enumerate().skip(4) {
                let s = (grid.x(i) as f32 + 0.1 * k as f32).min(1.0);
                assert_eq!(p, (255.0 * s).round() as u8, "i {i}");
            }
        }
    }
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("manifest.json")).unwrap()).unwrap();
    assert_eq!(m["format"], "grey-8bit-png");
    std::fs::remove_dir_all(&out).unwrap();
}

#[test]
fn material_subspaces_give_fractions_summing_to_one_inside() {
    let p = Expr::xyz();
    let part = 1.0 - (p[0].square() + p[1].square() + p[2].square());
    let mut m = MaterialModel::new(3, 0).unwrap();
    // Material 1 graded along x in the upper half box; material 2 over it in
    // a small corner block (later subspaces win).
    m.push(Subspace::in_box(
        [-1.0, -1.0, 0.0],
        [1.0, 1.0, 1.0],
        Expr::x(),
        1,
    ))
    .unwrap();
    m.push(
        Subspace::in_box([0.5, 0.0, 0.5], [1.0, 0.5, 1.0], Expr::constant(0.75), 2).with_base(1),
    )
    .unwrap();
    let f = m.fractions(&part);
    let tape = Tape::with_outputs(&f);
    let mut ev = PointEval::new(&tape);
    for k in 0..500 {
        let q = [
            -1.1 + 2.2 * (k as f64 * 0.618_034).fract(),
            -1.1 + 2.2 * (k as f64 * 0.381_966).fract(),
            -1.1 + 2.2 * (k as f64 * 0.236_068).fract(),
        ];
        let v = ev.eval_all(q);
        let inside = 1.0 - q.iter().map(|c| c * c).sum::<f64>() >= 0.0;
        let s: f64 = v.iter().sum();
        if !inside {
            assert!(v.iter().all(|&x| x == 0.0));
            continue;
        }
        assert!((s - 1.0).abs() < 1e-12 && v.iter().all(|x| (0.0..=1.0).contains(x)));
        let in_corner = q[0] >= 0.5 && (0.0..=0.5).contains(&q[1]) && q[2] >= 0.5;
        if in_corner {
            assert_eq!(v, vec![0.0, 0.25, 0.75]);
        } else if q[2] >= 0.0 {
            let u = (q[0] + 1.0) / 2.0;
            assert!((v[1] - u).abs() < 1e-12 && (v[0] - (1.0 - u)).abs() < 1e-12);
        } else {
            assert_eq!(v, vec![1.0, 0.0, 0.0]);
        }
    }
    assert!(MaterialModel::new(0, 0).is_err());
    assert!(MaterialModel::new(2, 2).is_err());
    let mut m = MaterialModel::new(2, 0).unwrap();
    assert!(m
        .push(Subspace::in_box([0.0; 3], [1.0; 3], Expr::x(), 0))
        .is_err());
    assert!(m
        .push(Subspace::in_box([0.0; 3], [1.0; 3], Expr::x(), 2))
        .is_err());
}
