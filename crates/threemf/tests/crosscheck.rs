//! Optional checks with outside tools, off by default:
//! `MICROFREP_3MF_VALIDATE=1` validates the model parts we write against
//! the vendored consortium schemas with Python `xmlschema`;
//! `MICROFREP_LIB3MF=1` reads our files with the consortium's lib3mf and
//! compares counts. Both use `MICROFREP_3MF_PYTHON`, or a venv in
//! `target/3mf-venv` (made with pip when missing). A requested check that
//! cannot run fails.

use microfrep_3mf::beam::{Ball, BallMode, BeamLattice, ClipMode};
use microfrep_3mf::*;
use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).to_path_buf()
}

fn python(module: &str) -> PathBuf {
    if let Ok(p) = std::env::var("MICROFREP_3MF_PYTHON") {
        return PathBuf::from(p);
    }
    let venv = root().join("../../target/3mf-venv");
    let py = venv.join("bin/python");
    let has = |py: &Path| {
        Command::new(py)
            .args(["-c", &format!("import {module}")])
            .output()
            .is_ok_and(|o| o.status.success())
    };
    if !has(&py) {
        eprintln!("installing xmlschema and lib3mf into {}", venv.display());
        let ok = Command::new("sh")
            .arg("-c")
            .arg(format!(
                "python3 -m venv {v} && {v}/bin/pip install --quiet xmlschema lib3mf",
                v = venv.display()
            ))
            .status()
            .is_ok_and(|s| s.success());
        assert!(
            ok && has(&py),
            "requested, but python3 -m venv / pip install failed"
        );
    }
    py
}

fn cube(s: f64) -> Mesh {
    let v: Vec<[f64; 3]> = (0..8)
        .map(|i| {
            [
                (i & 1) as f64 * s,
                (i >> 1 & 1) as f64 * s,
                (i >> 2) as f64 * s,
            ]
        })
        .collect();
    let t = vec![
        [0, 2, 1],
        [1, 2, 3],
        [4, 5, 6],
        [5, 7, 6],
        [0, 1, 4],
        [1, 5, 4],
        [2, 6, 3],
        [3, 6, 7],
        [0, 4, 2],
        [2, 4, 6],
        [1, 3, 5],
        [3, 7, 5],
    ];
    Mesh {
        vertices: v,
        triangles: t,
        ..Mesh::default()
    }
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
    vec![("core", core, 0), ("lattice", lat, 8), ("slices", sl, 0)]
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
    assert!(parts.len() >= 5, "{parts:?}");
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
