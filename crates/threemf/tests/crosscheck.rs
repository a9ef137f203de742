//! Optional checks with outside tools, off by default:
//! `MICROFREP_3MF_VALIDATE=1` validates the model parts we write against
//! the vendored consortium schemas with Python `xmlschema`;
//! `MICROFREP_LIB3MF=1` reads our files with the consortium's lib3mf and
//! compares counts, and for the volumetric sample requires that lib3mf
//! warns about nothing beyond its own known gaps (see
//! `lib3mf_reads_the_volumetric_sample`). Both use `MICROFREP_3MF_PYTHON`, or a venv in
//! `target/3mf-venv` (made with pip when missing). A requested check that
//! cannot run fails.

use microfrep_3mf::beam::{Ball, BallMode, BeamLattice, ClipMode};
use microfrep_3mf::volumetric::*;
use microfrep_3mf::*;
use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).to_path_buf()
}

/// The Python with xmlschema and lib3mf (`module` is the one the caller
/// needs); a requested check that cannot get it fails.
fn python(module: &str) -> PathBuf {
    let dir = root().join("../../target");
    microfrep_testsupport::pyvenv::python_with(&microfrep_testsupport::pyvenv::PythonSpec {
        override_var: "MICROFREP_3MF_PYTHON",
        venv: &dir.join("3mf-venv"),
        check: "import xmlschema, lib3mf",
        packages: &["xmlschema", "lib3mf"],
        log: &dir.join("3mf-install.log"),
    })
    .unwrap_or_else(|e| panic!("requested, but no Python with {module}: {e}"))
}

fn cube(s: f64) -> Mesh {
    Mesh::cuboid([0.0; 3], [s; 3])
}

/// A few packages exercising core, beam lattice (with balls) and slices.
fn samples() -> Vec<(&'static str, Model, usize)> {
    let mut core = Model::new(Unit::Inch);
    core.metadata.push(Metadata {
        name: "Title".into(),
        value: "cubes".into(),
    });
    let c = core.add_mesh(Some("cube"), cube(1.0));
    let a = core.add_components(
        Some("pair"),
        vec![
            Component {
                object: c,
                transform: Transform::IDENTITY,
            },
            Component {
                object: c,
                transform: Transform::translation([2.0, 0.0, 0.0]),
            },
        ],
    );
    core.add_item(a, Transform::rotation_z(0.3));

    let mut lat = Model::new(Unit::Millimeter);
    let clip = lat.add_mesh(Some("clip"), cube(2.0));
    let nodes: Vec<[f64; 3]> = (0..8)
        .map(|i| [(i & 1) as f64, (i >> 1 & 1) as f64, (i >> 2) as f64])
        .collect();
    let mut l = BeamLattice::new(0.1, 1e-4);
    for (a, b) in [
        (0, 1),
        (0, 2),
        (0, 4),
        (1, 3),
        (2, 3),
        (4, 5),
        (6, 7),
        (3, 7),
    ] {
        l.push(a, b, 0.1, 0.15);
    }
    l.ball_mode = BallMode::Mixed;
    l.ball_radius = Some(0.2);
    l.balls = vec![Ball { vindex: 0, r: None }];
    l.clipping = Some((ClipMode::Inside, clip));
    let id = lat.add_mesh(
        Some("lattice"),
        Mesh {
            vertices: nodes,
            beam_lattice: Some(l),
            ..Mesh::default()
        },
    );
    lat.add_item(id, Transform::IDENTITY);

    let mut sl = Model::new(Unit::Millimeter);
    let o = sl.add_mesh(Some("sliced"), cube(4.0));
    let sq: Polygon = vec![[1.0, 1.0], [3.0, 1.0], [3.0, 3.0], [1.0, 3.0]];
    let layers = (0..30)
        .map(|k| if k == 4 { vec![] } else { vec![sq.clone()] })
        .collect();
    let sid = sl.next_id();
    sl.slice_stacks
        .push(SliceStack::uniform(sid, 0.0, 0.1, layers));
    sl.objects[0].slice_stack = Some(sid);
    sl.objects[0].mesh_resolution = MeshResolution::Low;
    sl.add_item(o, Transform::IDENTITY);
    vec![
        ("core", core, 0),
        ("lattice", lat, 8),
        ("slices", sl, 0),
        ("volumetric", volumetric(), 0),
    ]
}

/// Every volumetric and implicit element the writer makes: an image stack,
/// a function sampling it, volume data with a composite, a colour and a
/// property on a mesh and on a level set of an implicit sphere.
fn volumetric() -> Model {
    let mut m = Model::new(Unit::Millimeter);
    m.base_materials.push(BaseMaterials {
        id: 1,
        bases: vec![
            Base {
                name: "soft".into(),
                color: [255, 0, 0, 255],
            },
            Base {
                name: "stiff".into(),
                color: [0, 0, 255, 255],
            },
        ],
    });
    let im = Image3D::from_fn(2, [4, 3, 2], PixelLayout::Rgba, 8, |x, y, z| {
        [x as f64 / 3.0, y as f64 / 2.0, z as f64, 1.0]
    })
    .unwrap();
    m.images.push(im);
    let mut f = FunctionFromImage3D::new(3, 2);
    f.filter = Filter::Nearest;
    f.tile = [TileStyle::Wrap, TileStyle::Mirror, TileStyle::Clamp];
    f.value_scale = 2.0;
    f.value_offset = -0.5;
    m.image_functions.push(f);
    let to_unit = Transform::box_to_unit([-1.0; 3], [1.0; 3]);
    m.volume_data.push(VolumeData {
        id: 4,
        composite: Some(Composite {
            base_materials: 1,
            mappings: vec![
                FunctionRef::new(3, "red", to_unit),
                FunctionRef::new(3, "green", to_unit),
            ],
        }),
        color: Some(FunctionRef::new(3, "color", to_unit)),
        properties: vec![Property {
            name: "density".into(),
            required: true,
            value: FunctionRef::new(3, "blue", to_unit),
        }],
    });
    let [x, y, z] = microfrep_core::Expr::xyz();
    let ball = 1.0 - (x.square() + y.square() + z.square()).sqrt();
    m.implicit_functions
        .push(microfrep_3mf::from_core::levelset_function(&ball, 5, Some("ball")).unwrap());
    let mut part = cube(2.0);
    for v in &mut part.vertices {
        *v = v.map(|c| c - 1.0);
    }
    part.volume_id = Some(4);
    let bounds = m.add_mesh(Some("bounds"), part);
    let id = m.next_id();
    m.objects.push(Object {
        content: ObjectContent::LevelSet(LevelSet {
            function: 5,
            channel: "value".into(),
            transform: Transform::IDENTITY,
            min_feature_size: 0.01,
            fallback: 1.0,
            mesh: bounds,
            mesh_bbox_only: true,
            volume_id: Some(4),
        }),
        ..Object::mesh(id, Some("ball"), Mesh::default())
    });
    m.add_item(id, Transform::IDENTITY);
    m
}

fn write_all(dir: &Path) -> Vec<(PathBuf, Model, usize)> {
    std::fs::create_dir_all(dir).unwrap();
    let opts = WriteOptions {
        max_slices_per_part: 10,
        ..WriteOptions::default()
    };
    samples()
        .into_iter()
        .map(|(name, m, beams)| {
            let p = dir.join(format!("{name}.3mf"));
            write_file(&p, &m, &opts).unwrap();
            (p, m, beams)
        })
        .collect()
}

#[test]
fn written_model_parts_validate_against_the_consortium_schemas() {
    if std::env::var("MICROFREP_3MF_VALIDATE").as_deref() != Ok("1") {
        eprintln!("skipped: set MICROFREP_3MF_VALIDATE=1 to validate with Python xmlschema");
        return;
    }
    let py = python("xmlschema");
    let dir = root().join("../../target/3mf-validate");
    let mut parts = Vec::new();
    for (p, _, _) in write_all(&dir) {
        let mut z = zip::ZipArchive::new(std::fs::File::open(&p).unwrap()).unwrap();
        for i in 0..z.len() {
            let mut f = z.by_index(i).unwrap();
            if f.name().ends_with(".model") {
                let out = dir.join(format!(
                    "{}-{}",
                    p.file_stem().unwrap().to_string_lossy(),
                    f.name().replace('/', "_")
                ));
                let mut w = std::fs::File::create(&out).unwrap();
                std::io::copy(&mut f, &mut w).unwrap();
                parts.push(out);
            }
        }
    }
    assert!(parts.len() >= 6, "{parts:?}");
    // A broken copy of the volumetric part must fail: the volumetric
    // elements are checked, not skipped by the core's lax wildcards.
    let vol = parts
        .iter()
        .find(|p| p.to_string_lossy().contains("volumetric-"))
        .unwrap();
    let broken = dir.join("broken-volumetric.model");
    let text = std::fs::read_to_string(vol).unwrap();
    assert!(text.contains("meshbboxonly=\"true\""), "{text}");
    std::fs::write(
        &broken,
        text.replace("meshbboxonly=\"true\"", "meshbboxonly=\"yes\""),
    )
    .unwrap();
    let bad = Command::new(&py)
        .arg(root().join("tools/validate.py"))
        .arg(root().join("schemas"))
        .arg(&broken)
        .output()
        .unwrap();
    let bad_text = String::from_utf8_lossy(&bad.stdout);
    assert!(
        !bad.status.success() && bad_text.contains("INVALID"),
        "{bad_text}"
    );
    let out = Command::new(&py)
        .arg(root().join("tools/validate.py"))
        .arg(root().join("schemas"))
        .args(&parts)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    eprintln!("{text}{}", String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "schema validation failed");
    assert_eq!(text.matches(": valid").count(), parts.len());
}

#[test]
fn lib3mf_reads_what_we_write() {
    if std::env::var("MICROFREP_LIB3MF").as_deref() != Ok("1") {
        eprintln!("skipped: set MICROFREP_LIB3MF=1 to cross-check with lib3mf");
        return;
    }
    let py = python("lib3mf");
    let dir = root().join("../../target/3mf-lib3mf");
    for (p, m, beams) in write_all(&dir) {
        let out = Command::new(&py)
            .arg(root().join("tools/lib3mf_counts.py"))
            .arg(&p)
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&out.stdout).to_string();
        assert!(
            out.status.success(),
            "lib3mf failed on {}: {}",
            p.display(),
            String::from_utf8_lossy(&out.stderr)
        );
        let rows: Vec<Vec<String>> = text
            .lines()
            .map(|l| l.split(' ').map(str::to_string).collect())
            .collect();
        let meshes: Vec<&Object> = m
            .objects
            .iter()
            .filter(|o| matches!(o.content, ObjectContent::Mesh(_)))
            .collect();
        assert_eq!(rows.len(), meshes.len(), "{}: {text}", p.display());
        for (row, o) in rows.iter().zip(meshes) {
            let ObjectContent::Mesh(me) = &o.content else {
                unreachable!()
            };
            assert_eq!(row[1], me.vertices.len().to_string(), "{text}");
            assert_eq!(row[2], me.triangles.len().to_string(), "{text}");
            let want = me.beam_lattice.as_ref().map_or(0, |l| l.beams.len());
            assert_eq!(row[3], want.to_string(), "{text}");
        }
        assert!(text.contains(&format!(" {beams}")) || beams == 0);
    }
}

#[test]
fn lib3mf_reads_the_volumetric_sample() {
    if std::env::var("MICROFREP_LIB3MF").as_deref() != Ok("1") {
        eprintln!("skipped: set MICROFREP_LIB3MF=1 to cross-check with lib3mf");
        return;
    }
    let py = python("lib3mf");
    let dir = root().join("../../target/3mf-lib3mf");
    std::fs::create_dir_all(&dir).unwrap();
    let m = volumetric();
    let p = dir.join("volumetric-only.3mf");
    write_file(&p, &m, &WriteOptions::default()).unwrap();
    let out = Command::new(&py)
        .arg(root().join("tools/lib3mf_volumetric.py"))
        .arg(&p)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    eprintln!("lib3mf on {}:\n{text}", p.display());
    assert!(
        out.status.success(),
        "lib3mf failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let get = |k: &str| -> i64 {
        text.lines()
            .find_map(|l| l.strip_prefix(&format!("{k} ")))
            .and_then(|v| v.trim().parse().ok())
            .unwrap_or_else(|| panic!("no {k} in {text}"))
    };
    let nodes = m.implicit_functions[0].graph.nodes.len() as i64;
    for (k, want) in [
        ("meshes", 1),
        ("levelsets", 1),
        ("functions", 2),
        ("images", 1),
        ("sheets", 2),
        ("implicitnodes", nodes),
        ("properties", 1),
        ("color", 1),
        ("meshvolumedata", 1),
    ] {
        assert_eq!(get(k), want, "{k}: {text}");
    }
    // lib3mf 2.5 warns once per image3d and functionfromimage3d even on
    // its own files (`selfwarnings` for one of each), and does not
    // implement volumetric composites (warning on the composite and each
    // mapping, then dropping them). Nothing else may be warned about; once
    // lib3mf reads composites, it must see ours.
    assert!(
        text.lines().any(|l| l == "image 3 4 2"),
        "rows, columns, sheets: {text}"
    );
    let per = get("selfwarnings");
    assert!(per == 0 || per == 2, "{text}");
    let support = get("compositesupport") == 1;
    let allowed = per / 2 * 2 + if support { 0 } else { 3 };
    assert_eq!(get("warnings"), allowed, "{text}");
    if support {
        assert_eq!(get("composite"), 2, "{text}");
    } else {
        assert_eq!(get("composite"), -1, "{text}");
    }
}

#[test]
fn a_volumetric_file_written_by_lib3mf_reads_here() {
    if std::env::var("MICROFREP_LIB3MF").as_deref() != Ok("1") {
        eprintln!("skipped: set MICROFREP_LIB3MF=1 to cross-check with lib3mf");
        return;
    }
    let py = python("lib3mf");
    let dir = root().join("../../target/3mf-lib3mf");
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("written-by-lib3mf.3mf");
    let out = Command::new(&py)
        .arg(root().join("tools/lib3mf_write_volumetric.py"))
        .arg(&p)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "lib3mf could not write: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let m = read_file(&p).unwrap();
    validate(&m).unwrap();
    // The image stack: 2 columns (U), 3 rows (V), 2 sheets of constant grey
    // 0 and 100.
    assert_eq!(m.images.len(), 1);
    let im = &m.images[0];
    assert_eq!(im.dims, [2, 3, 2]);
    assert_eq!(im.value(1, 2, 0, 0), 0.0);
    assert!((im.value(0, 1, 1, 0) - 100.0 / 255.0).abs() < 1e-12);
    let f = &m.image_functions[0];
    assert_eq!(f.image, im.id);
    assert_eq!(f.filter, Filter::Nearest);
    assert_eq!(
        f.tile,
        [TileStyle::Clamp, TileStyle::Wrap, TileStyle::Mirror]
    );
    assert_eq!((f.value_offset, f.value_scale), (0.5, 2.0));
    // Volume data on the cube and the level set: colour and one property.
    let vd = &m.volume_data[0];
    assert_eq!(vd.color.as_ref().map(|c| c.channel.as_str()), Some("color"));
    assert_eq!(vd.properties.len(), 1);
    assert_eq!(vd.properties[0].name, "density");
    assert_eq!(vd.properties[0].value.channel, "red");
    assert!(vd.composite.is_none());
    let ls = m
        .objects
        .iter()
        .find_map(|o| match &o.content {
            ObjectContent::LevelSet(l) => Some(l),
            _ => None,
        })
        .expect("a level set");
    assert_eq!(ls.channel, "shape");
    assert!(ls.mesh_bbox_only);
    assert_eq!(ls.min_feature_size, 0.1);
    assert_eq!(ls.volume_id, Some(vd.id));
    // The implicit function is |pos|: evaluate it.
    let g = m
        .implicit_functions
        .iter()
        .find(|g| g.id == ls.function)
        .unwrap();
    let v = g
        .eval(&[(
            "pos",
            microfrep_3mf::implicit::Value::Vector([3.0, 4.0, 12.0]),
        )])
        .unwrap();
    assert_eq!(v[0].1, microfrep_3mf::implicit::Value::Scalar(13.0));
}
