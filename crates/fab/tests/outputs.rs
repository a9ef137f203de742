//! Files on disk: PNG stacks with manifest, CLI round trip, voxel grids,
//! and refusals that leave nothing behind.

use microfrep_core::Shape;
use microfrep_fab::cli_format::read_cli;
use microfrep_fab::contour::signed_area;
use microfrep_fab::image::{decode_png, GreyImage};
use microfrep_fab::voxels::{write_voxels, VoxelGrid};
use microfrep_fab::{layer_polygons, rasterize, write_stack, FabError, Format, SliceGrid};
use microfrep_structures::examples::{shell_lattice, unit_sphere};
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

/// A fresh, empty scratch directory per test.
fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("microfrep-fab-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn png_stack_matches_layers_and_manifest() {
    let tape = Shape::from(&unit_sphere());
    let grid = SliceGrid::new([-1.0; 3], [1.0; 3], 0.25, 0.02).unwrap();
    let dir = scratch("png");
    let out = dir.join("stack");
    let done = AtomicUsize::new(0);
    let progress = || {
        done.fetch_add(1, Ordering::Relaxed);
    };
    write_stack(&tape, &grid, &Format::Png { aa: false }, &out, &progress).unwrap();
    assert_eq!(done.load(Ordering::Relaxed), grid.layers);
    for k in 0..grid.layers {
        let img = decode_png(&out.join(format!("layer_{k:05}.png"))).unwrap();
        let expect = GreyImage::binary(&rasterize(&tape, &grid, k));
        assert!(img.binary);
        assert_eq!((img.width, img.height), (100, 100));
        assert_eq!(img.pixels, expect.pixels, "layer {k}");
    }
    let manifest = std::fs::read_to_string(out.join("manifest.json")).unwrap();
    assert!(manifest.contains("\"image_size\": [100, 100]"));
    assert!(manifest.contains("{\"file\": \"layer_00007.png\", \"z\": 0.875}"));
    // Only the finished stack is left: no temporary directory.
    let names: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
    assert_eq!(names.len(), 1);
    // A second run refuses to overwrite.
    let err = write_stack(&tape, &grid, &Format::Svg, &out, &|| {}).unwrap_err();
    assert!(err.to_string().contains("already exists"), "{err}");
}

#[test]
fn aa_png_is_8_bit_with_grey_edges() {
    let tape = Shape::from(&unit_sphere());
    let grid = SliceGrid::new([-1.0, -1.0, -0.1], [1.0, 1.0, 0.1], 0.2, 0.05).unwrap();
    let out = scratch("aa").join("stack");
    write_stack(&tape, &grid, &Format::Png { aa: true }, &out, &|| {}).unwrap();
    let img = decode_png(&out.join("layer_00000.png")).unwrap();
    assert!(!img.binary);
    let grey = img.pixels.iter().filter(|&&p| p > 0 && p < 255).count();
    // Edge pixels of the r = 1 circle: roughly its perimeter in pixels.
    assert!(grey > 60 && grey < 250, "{grey} grey pixels");
}

#[test]
fn cli_file_round_trips() {
    let tape = Shape::from(&shell_lattice());
    let grid = SliceGrid::new([-1.05; 3], [1.05; 3], 0.3, 0.03).unwrap();
    let out = scratch("cli").join("part.cli");
    write_stack(&tape, &grid, &Format::Cli, &out, &|| {}).unwrap();
    let file = read_cli(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(file.units, 1.0);
    assert_eq!(file.layers.len(), grid.layers);
    let mut total = 0;
    for (k, layer) in file.layers.iter().enumerate() {
        assert!((layer.z - (-1.05 + 0.3 * (k + 1) as f64)).abs() < 1e-12);
        let polys = layer_polygons(&tape, &grid, &rasterize(&tape, &grid, k));
        assert_eq!(layer.polylines.len(), polys.len(), "layer {k}");
        for (pl, p) in layer.polylines.iter().zip(&polys) {
            assert_eq!(pl.points.first(), pl.points.last());
            assert_eq!(&pl.points[..pl.points.len() - 1], &p[..]);
            assert_eq!(pl.dir == 1, signed_area(p) > 0.0);
        }
        total += polys.len();
    }
    assert!(total > 10, "{total} polylines: too few to test");
}

#[test]
fn cli_reader_rejects_broken_files_with_line() {
    let good = "$$HEADERSTART\n$$UNITS/1\n$$LAYERS/1\n$$HEADEREND\n$$GEOMETRYSTART\n\
                $$LAYER/0.5\n$$POLYLINE/1,1,4,0,0,1,0,0,1,0,0\n$$GEOMETRYEND\n";
    assert_eq!(
        read_cli(good).unwrap().layers[0].polylines[0].points.len(),
        4
    );
    let short = good.replace("1,1,4,0,0", "1,1,5,0,0");
    assert!(matches!(
        read_cli(&short),
        Err(FabError::Parse { line: 7, .. })
    ));
    let truncated = good.replace("$$GEOMETRYEND\n", "");
    assert!(read_cli(&truncated).is_err());
    let bad_num = good.replace("$$LAYER/0.5", "$$LAYER/zero");
    assert!(matches!(
        read_cli(&bad_num),
        Err(FabError::Parse { line: 6, .. })
    ));
}

#[test]
fn voxels_nrrd_holds_the_sphere_volume() {
    let tape = Shape::from(&unit_sphere());
    let grid = VoxelGrid::new([-1.0; 3], [1.0; 3], 0.04).unwrap();
    assert_eq!(grid.dims, [50, 50, 50]);
    let out = scratch("vox").join("ball.nrrd");
    write_voxels(&tape, &grid, false, &out).unwrap();
    let bytes = std::fs::read(&out).unwrap();
    let split = bytes.windows(2).position(|w| w == b"\n\n").unwrap() + 2;
    let header = std::str::from_utf8(&bytes[..split]).unwrap();
    assert!(header.contains("sizes: 50 50 50"));
    assert!(header.contains("space origin: (-0.98,-0.98,-0.98)"));
    let data = &bytes[split..];
    assert_eq!(data.len(), 50 * 50 * 50);
    let vol = data.iter().filter(|&&b| b == 1).count() as f64 * 0.04f64.powi(3);
    let exact = 4.0 / 3.0 * std::f64::consts::PI;
    assert!((vol - exact).abs() / exact < 0.01, "{vol} vs {exact}");
}

#[test]
fn voxels_raw_field_with_sidecar_and_vtk() {
    let tape = Shape::from(&unit_sphere());
    let grid = VoxelGrid::new([-1.0; 3], [1.0; 3], 0.5).unwrap();
    let dir = scratch("raw");
    let raw = dir.join("f.raw");
    write_voxels(&tape, &grid, true, &raw).unwrap();
    let data = std::fs::read(&raw).unwrap();
    assert_eq!(data.len(), 4 * 64);
    // Voxel (1, 2, 3) has its centre at (-0.25, 0.25, 0.75).
    let k = 4 * (1 + 4 * (2 + 4 * 3));
    let v = f32::from_le_bytes(data[k..k + 4].try_into().unwrap());
    assert!((v - (1.0 - 0.0625 - 0.0625 - 0.5625)).abs() < 1e-6);
    let side = std::fs::read_to_string(dir.join("f.json")).unwrap();
    assert!(side.contains("\"dims\": [4, 4, 4]") && side.contains("\"spacing\": [0.5, 0.5, 0.5]"));
    let vtk = dir.join("f.vtk");
    write_voxels(&tape, &grid, true, &vtk).unwrap();
    let bytes = std::fs::read(&vtk).unwrap();
    let text = String::from_utf8_lossy(&bytes);
    assert!(text.contains("DIMENSIONS 4 4 4") && text.contains("SCALARS value float 1"));
    let start = text.find("LOOKUP_TABLE default\n").unwrap() + 21;
    let v = f32::from_be_bytes(bytes[start + k..start + k + 4].try_into().unwrap());
    assert!((v - 0.3125).abs() < 1e-6);
    let err = write_voxels(&tape, &grid, true, &dir.join("f.txt")).unwrap_err();
    assert!(err.to_string().contains(".nrrd"));
}

#[test]
fn bad_parameters_are_errors() {
    assert!(SliceGrid::new([0.0; 3], [1.0; 3], 0.0, 0.1).is_err());
    assert!(SliceGrid::new([0.0; 3], [1.0; 3], 0.1, 1e-9).is_err());
    assert!(SliceGrid::new([0.0; 3], [0.0, 1.0, 1.0], 0.1, 0.1).is_err());
    assert!(VoxelGrid::new([0.0; 3], [1.0; 3], 1e-5).is_err());
    assert!(VoxelGrid::new([0.0; 3], [1.0; 3], f64::NAN).is_err());
}
