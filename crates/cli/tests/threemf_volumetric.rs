//! The 3MF volumetric and implicit extensions from `mesh` and `fill`:
//! the level set's implicit graph read back evaluates like the model, the
//! attribute image stacks read back hold the attributes at the voxel
//! centres, a palette becomes a composite whose shares sum to one, a model
//! with a mesh field falls back to an image stack of its field (and says
//! so), and misuse is refused with a clear message and no file.
//!
//! `MICROFREP_LIB3MF=1` also reads the files with the consortium's lib3mf
//! (as `crates/threemf/tests/crosscheck.rs` does; it fails when requested
//! and lib3mf cannot run) and allows no reader warnings beyond lib3mf's own
//! (see `lib3mf_reads`); `MICROFREP_3MF_VALIDATE=1` validates the model
//! parts against the vendored schemas.

use microfrep::threemf::volumetric::{FunctionFromImage3D, FunctionRef, Image3D};
use microfrep::threemf::{Model, ObjectContent, Transform};
use microfrep::{load, LoadOptions};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn bin() -> PathBuf {
    PathBuf::from(env!("CARGO_BIN_EXE_microfrep"))
}

fn run(args: &[&str]) -> Output {
    Command::new(bin()).args(args).output().unwrap()
}

fn ok(args: &[&str]) -> Output {
    let out = run(args);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("mf-cli-3mfv-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

const WIFFLE: &str = "../../examples/park_fig4_wiffle_gradient.hf";
const BOX: &str = "--bounds=-2.2,-2.2,-2.2,2.2,2.2,2.2";

/// Deterministic points in the box `[-h, h]^3`.
fn points(n: usize, h: f64) -> Vec<[f64; 3]> {
    let mut s = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..n)
        .map(|_| [(); 3].map(|_| (2.0 * next() - 1.0) * h))
        .collect()
}

fn level_set(m: &Model) -> &microfrep::threemf::volumetric::LevelSet {
    let built = m.build[0].object;
    match &m.object(built).unwrap().content {
        ObjectContent::LevelSet(l) => l,
        c => panic!("the built object is not a level set: {c:?}"),
    }
}

fn image_fn(m: &Model, id: u32) -> (&FunctionFromImage3D, &Image3D) {
    let f = m.image_functions.iter().find(|f| f.id == id).unwrap();
    let im = m.images.iter().find(|i| i.id == f.image).unwrap();
    (f, im)
}

/// The model point of a voxel centre, from the reference's transform
/// (the inverse of `box_to_unit`).
fn centre(t: &Transform, dims: [usize; 3], i: [usize; 3]) -> [f64; 3] {
    std::array::from_fn(|a| {
        let (s, o) = (t.0[4 * a], t.0[9 + a]);
        ((i[a] as f64 + 0.5) / dims[a] as f64 - o) / s
    })
}

/// Every voxel's value through the image function, with the model point
/// of its centre.
fn voxels(m: &Model, r: &FunctionRef) -> Vec<([f64; 3], f64, f64)> {
    let (f, im) = image_fn(m, r.function);
    let step = f.value_scale / 65535.0;
    let [nx, ny, nz] = im.dims;
    let mut v = Vec::new();
    for iz in 0..nz {
        for iy in 0..ny {
            for ix in 0..nx {
                let p = centre(&r.transform, im.dims, [ix, iy, iz]);
                let val = im.value(ix, iy, iz, 0) * f.value_scale + f.value_offset;
                v.push((p, val, step));
            }
        }
    }
    v
}

/// The Python of the 3MF cross-checks (created on first use, as in
/// crates/threemf/tests/crosscheck.rs); a requested check without it fails.
fn python() -> PathBuf {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../target");
    microfrep_testsupport::pyvenv::python_with(&microfrep_testsupport::pyvenv::PythonSpec {
        override_var: "MICROFREP_3MF_PYTHON",
        venv: &dir.join("3mf-venv"),
        check: "import xmlschema, lib3mf",
        packages: &["xmlschema", "lib3mf"],
        log: &dir.join("3mf-install.log"),
    })
    .unwrap_or_else(|e| panic!("requested, but no Python for the 3MF checks: {e}"))
}

/// With `MICROFREP_3MF_VALIDATE=1`, the files' model parts validate against
/// the schemas vendored in `crates/threemf/schemas` (core and volumetric;
/// the implicit namespace has no current schema and is skipped).
fn xsd_valid(files: &[&Path]) {
    if std::env::var("MICROFREP_3MF_VALIDATE").as_deref() != Ok("1") {
        eprintln!("skipped: set MICROFREP_3MF_VALIDATE=1 to validate with Python xmlschema");
        return;
    }
    let threemf = Path::new(env!("CARGO_MANIFEST_DIR")).join("../threemf");
    let out = Command::new(python())
        .arg(threemf.join("tools/validate.py"))
        .arg(threemf.join("schemas"))
        .args(files)
        .output()
        .unwrap_or_else(|e| panic!("requested, but {} cannot run: {e}", python().display()));
    let text = String::from_utf8_lossy(&out.stdout);
    eprintln!("{text}{}", String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "schema validation failed");
    assert!(!text.contains("INVALID"), "{text}");
    assert!(text.matches(": valid").count() >= files.len(), "{text}");
}

fn lib3mf_reads(files: &[&Path]) {
    if std::env::var("MICROFREP_LIB3MF").as_deref() != Ok("1") {
        eprintln!("skipped: set MICROFREP_LIB3MF=1 to cross-check with lib3mf");
        return;
    }
    let py = python();
    let tool = Path::new(env!("CARGO_MANIFEST_DIR")).join("../threemf/tools/lib3mf_volumetric.py");
    for f in files {
        let out = Command::new(&py).arg(&tool).arg(f).output();
        let out = out.unwrap_or_else(|e| {
            panic!(
                "requested, but {} cannot run ({e}): make the venv of crates/threemf/tests/crosscheck.rs \
                 or set MICROFREP_3MF_PYTHON",
                py.display()
            )
        });
        assert!(
            out.status.success(),
            "lib3mf failed on {}: {}",
            f.display(),
            String::from_utf8_lossy(&out.stderr)
        );
        let text = String::from_utf8_lossy(&out.stdout).to_string();
        let get = |k: &str| -> usize {
            text.lines()
                .find_map(|l| l.strip_prefix(&format!("{k} ")))
                .and_then(|v| v.trim().parse().ok())
                .unwrap_or_else(|| panic!("no {k} in {text}"))
        };
        let m = microfrep::threemf::read_file(f).unwrap();
        let count =
            |p: fn(&ObjectContent) -> bool| m.objects.iter().filter(|o| p(&o.content)).count();
        assert_eq!(
            get("meshes"),
            count(|c| matches!(c, ObjectContent::Mesh(_))),
            "{text}"
        );
        assert_eq!(
            get("levelsets"),
            count(|c| matches!(c, ObjectContent::LevelSet(_))),
            "{text}"
        );
        assert_eq!(
            get("functions"),
            m.image_functions.len() + m.implicit_functions.len(),
            "{text}"
        );
        assert_eq!(get("images"), m.images.len(), "{text}");
        let nodes: usize = m
            .implicit_functions
            .iter()
            .map(|f| f.graph.nodes.len())
            .sum();
        assert_eq!(get("implicitnodes"), nodes, "{text}");
        let sheets: usize = m.images.iter().map(|i| i.dims[2]).sum();
        assert_eq!(get("sheets"), sheets, "{text}");
        let ls_vd = m.objects.iter().find_map(|o| match &o.content {
            ObjectContent::LevelSet(l) => l.volume_id,
            _ => None,
        });
        let vd = ls_vd.and_then(|id| m.volume_data.iter().find(|v| v.id == id));
        assert_eq!(
            get("properties"),
            vd.map_or(0, |v| v.properties.len()),
            "{text}"
        );
        assert_eq!(
            get("color"),
            usize::from(vd.is_some_and(|v| v.color.is_some())),
            "{text}"
        );
        let with_vd = m
            .objects
            .iter()
            .filter(|o| matches!(&o.content, ObjectContent::Mesh(me) if me.volume_id.is_some()))
            .count();
        assert_eq!(get("meshvolumedata"), with_vd, "{text}");
        // Warnings: lib3mf 2.5 warns once per image3d and functionfromimage3d
        // even on files its own writer made (`selfwarnings`, one image and
        // one function), and does not implement volumetric composites
        // (`compositesupport` 0: it warns on the composite and on each
        // mapping and drops them). Those are all the warnings allowed; once
        // lib3mf reads its own images quietly or supports composites, ours
        // must follow.
        let per_image = get("selfwarnings");
        assert!(per_image == 0 || per_image == 2, "{text}");
        let composite_support = get("compositesupport") == 1;
        let composite_elements: usize = m
            .volume_data
            .iter()
            .filter_map(|v| v.composite.as_ref())
            .map(|c| 1 + c.mappings.len())
            .sum();
        let allowed = per_image / 2 * (m.images.len() + m.image_functions.len())
            + if composite_support {
                0
            } else {
                composite_elements
            };
        assert_eq!(get("warnings"), allowed, "{text}");
        let mappings = vd
            .and_then(|v| v.composite.as_ref())
            .map(|c| c.mappings.len());
        if composite_support {
            let seen = text
                .lines()
                .find_map(|l| l.strip_prefix("composite "))
                .and_then(|v| v.trim().parse::<i64>().ok());
            assert_eq!(seen, Some(mappings.map_or(-1, |n| n as i64)), "{text}");
        } else if mappings.is_some() {
            eprintln!(
                "{}: lib3mf does not implement volumetric composites, composite not compared",
                f.display()
            );
        }
        eprintln!("lib3mf on {}:\n{text}", f.display());
    }
}

#[test]
fn implicit_graph_and_attribute_stacks_read_back_like_the_model() {
    let d = dir("graph");
    let out = d.join("wiffle.3mf");
    let o = ok(&[
        "mesh",
        WIFFLE,
        BOX,
        "-o",
        out.to_str().unwrap(),
        "--resolution",
        "40",
        "--implicit",
        "--volumetric",
        "--volume-resolution",
        "24",
        "--json",
    ]);
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["volumetric"]["level_set"]["kind"], "implicit", "{j}");
    assert_eq!(j["volumetric"]["attributes"], 2, "{j}");
    assert!(!String::from_utf8_lossy(&o.stderr).contains("image stack"));
    let m = microfrep::threemf::read_file(&out).unwrap();
    microfrep::threemf::validate(&m).unwrap();
    // The level set is built; its bounding mesh is a box; the part mesh
    // stays with the same volume data.
    let ls = level_set(&m);
    assert!(ls.mesh_bbox_only && ls.channel == "value");
    let f = m
        .implicit_functions
        .iter()
        .find(|f| f.id == ls.function)
        .unwrap();
    let loaded = load::load(WIFFLE, &LoadOptions::default()).unwrap();
    let shape = &loaded.shape;
    let mut pe = shape.point();
    let mut checked = 0;
    for p in points(400, 2.2) {
        let want = pe.eval(p);
        let got = f.eval_at(p).unwrap();
        if !want.is_finite() {
            assert!(!got.is_finite() || got.abs() > 1e12, "{p:?}: {want} {got}");
            continue;
        }
        assert!(
            (got + want).abs() <= 1e-9 * (1.0 + want.abs()),
            "at {p:?}: model {want}, level set {got} (should be its negative)"
        );
        checked += 1;
    }
    assert!(checked > 350, "{checked}");
    // Attribute stacks: every voxel within half a quantisation step (and
    // f32 rounding) of the attribute at its centre.
    let vd = &m.volume_data[0];
    assert_eq!(ls.volume_id, Some(vd.id));
    let part = m
        .objects
        .iter()
        .find(|o| matches!(&o.content, ObjectContent::Mesh(me) if me.volume_id == Some(vd.id)))
        .expect("the part mesh carries the volume data");
    assert!(matches!(&part.content, ObjectContent::Mesh(me) if me.triangles.len() > 1000));
    assert_eq!(
        vd.properties
            .iter()
            .map(|p| p.name.as_str())
            .collect::<Vec<_>>(),
        ["s1", "s2"]
    );
    let mut pa = microfrep::core::PointEval::new(shape.outputs());
    for (k, prop) in vd.properties.iter().enumerate() {
        let o = shape.attribute_output(k);
        let vox = voxels(&m, &prop.value);
        assert_eq!(vox.len(), 24 * 24 * 24);
        let mut spread = (f64::INFINITY, f64::NEG_INFINITY);
        for (p, got, step) in vox {
            let want = pa.eval_output(o, p);
            assert!(
                (got - want).abs() <= 0.5 * step + 1e-6 * (1.0 + want.abs()),
                "s{} at {p:?}: {want} stored as {got}",
                k + 1
            );
            spread = (spread.0.min(want), spread.1.max(want));
        }
        assert!(spread.1 - spread.0 > 0.5, "a graded channel: {spread:?}");
    }
    xsd_valid(&[&out]);
    lib3mf_reads(&[&out]);
}

#[test]
fn palette_is_a_composite_whose_shares_follow_the_attributes() {
    let d = dir("palette");
    let out = d.join("mix.3mf");
    let o = ok(&[
        "mesh",
        WIFFLE,
        BOX,
        "-o",
        out.to_str().unwrap(),
        "--resolution",
        "32",
        "--palette",
        "soft=#ff0000,stiff=#0000ff,void=#ffffff",
        "--volume-resolution",
        "16",
    ]);
    assert!(String::from_utf8_lossy(&o.stdout).contains("a composite of 3 materials"));
    let m = microfrep::threemf::read_file(&out).unwrap();
    microfrep::threemf::validate(&m).unwrap();
    // No level set asked: the mesh is built, and carries the volume data.
    let ObjectContent::Mesh(me) = &m.object(m.build[0].object).unwrap().content else {
        panic!("the mesh is built")
    };
    let vd = m
        .volume_data
        .iter()
        .find(|v| Some(v.id) == me.volume_id)
        .unwrap();
    let c = vd.composite.as_ref().unwrap();
    let bases = &m
        .base_materials
        .iter()
        .find(|b| b.id == c.base_materials)
        .unwrap()
        .bases;
    assert_eq!(bases[1].name, "stiff");
    assert_eq!(bases[1].color, [0, 0, 255, 255]);
    assert_eq!(c.mappings.len(), 3);
    let shares: Vec<_> = c.mappings.iter().map(|r| voxels(&m, r)).collect();
    let loaded = load::load(WIFFLE, &LoadOptions::default()).unwrap();
    let mut pa = microfrep::core::PointEval::new(loaded.shape.outputs());
    for q in 0..shares[0].len() {
        let (p, s0, step) = shares[0][q];
        let sum: f64 = shares.iter().map(|s| s[q].1).sum();
        assert!((sum - 1.0).abs() < 4.0 * step, "{p:?}: shares sum to {sum}");
        let s1 = pa.eval_output(loaded.shape.attribute_output(0), p);
        assert!(
            (s0 - s1.clamp(0.0, 1.0)).abs() <= 0.5 * step + 1e-6,
            "{p:?}: s1 {s1}, share {s0}"
        );
    }
    // The colour is the mix: red share times red, blue likewise.
    let col = vd.color.as_ref().unwrap();
    let (_, im) = image_fn(&m, col.function);
    let (_, s0, _) = shares[0][0];
    assert!((im.value(0, 0, 0, 0) - (s0 + shares[2][0].1)).abs() < 1.0 / 255.0 + 1e-4);
    // With a level set too: the composite rides on the level set's volume
    // data as well.
    let both = d.join("mix-levelset.3mf");
    ok(&[
        "mesh",
        WIFFLE,
        BOX,
        "-o",
        both.to_str().unwrap(),
        "--resolution",
        "24",
        "--implicit",
        "--volumetric",
        "--palette",
        "A=#ff0000,B=#0000ff",
        "--volume-resolution",
        "8",
    ]);
    let mb = microfrep::threemf::read_file(&both).unwrap();
    microfrep::threemf::validate(&mb).unwrap();
    let ls = level_set(&mb);
    let vd = mb
        .volume_data
        .iter()
        .find(|v| Some(v.id) == ls.volume_id)
        .unwrap();
    assert_eq!(vd.composite.as_ref().map(|c| c.mappings.len()), Some(2));
    assert_eq!(vd.properties.len(), 2);
    xsd_valid(&[&out, &both]);
    lib3mf_reads(&[&out, &both]);
}

#[test]
fn a_mesh_field_falls_back_to_an_image_stack_and_says_so() {
    let d = dir("fallback");
    let stl = d.join("ball.stl");
    ok(&[
        "mesh",
        "sphere",
        "-o",
        stl.to_str().unwrap(),
        "--resolution",
        "40",
        "--quiet",
    ]);
    let out = d.join("ball.3mf");
    let o = ok(&[
        "mesh",
        stl.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--resolution",
        "32",
        "--implicit",
        "--volume-resolution",
        "20",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("note: the level set is an image stack") && err.contains("field '"),
        "{err}"
    );
    let m = microfrep::threemf::read_file(&out).unwrap();
    microfrep::threemf::validate(&m).unwrap();
    assert!(m.implicit_functions.is_empty());
    let ls = level_set(&m);
    assert_eq!(ls.channel, "red");
    let r = FunctionRef::new(ls.function, "red", ls.transform);
    let vox = voxels(&m, &r);
    assert_eq!(vox.len(), 20 * 20 * 20);
    let loaded = load::load(stl.to_str().unwrap(), &LoadOptions::default()).unwrap();
    let mut pe = loaded.shape.point();
    let (mut inside, mut outside) = (0, 0);
    for (p, got, step) in vox {
        let want = -pe.eval(p);
        assert!(
            (got - want).abs() <= 0.5 * step + 1e-5 * (1.0 + want.abs()),
            "{p:?}: -f {want}, stored {got}"
        );
        if want < -0.05 {
            inside += 1;
        } else if want > 0.05 {
            outside += 1;
        }
    }
    assert!(inside > 1000 && outside > 1000, "{inside} {outside}");

    // A fill of the mesh part likewise.
    let fill = d.join("fill.3mf");
    let o = ok(&[
        "fill",
        stl.to_str().unwrap(),
        "-o",
        fill.to_str().unwrap(),
        "--structure",
        "gyroid",
        "--cell",
        "0.6",
        "--density",
        "0.3",
        "--resolution",
        "40",
        "--implicit",
        "--volume-resolution",
        "16",
        "--json",
    ]);
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(
        j["written"]["volumetric"]["level_set"]["kind"], "image-stack",
        "{j}"
    );
    let m = microfrep::threemf::read_file(&fill).unwrap();
    microfrep::threemf::validate(&m).unwrap();
    level_set(&m);
    xsd_valid(&[&out, &fill]);
    lib3mf_reads(&[&out, &fill]);
}

#[test]
fn misuse_is_refused_clearly_and_writes_nothing() {
    let d = dir("errors");
    let cases: &[(&[&str], &str, &str)] = &[
        (&["sphere", "--implicit"], "stl", "write a .3mf file"),
        (&["sphere", "--volumetric"], "3mf", "no attribute channels"),
        (
            &[
                WIFFLE,
                BOX,
                "--palette",
                "a=#ff0000,b=#00ff00,c=#0000ff,d=#000000",
            ],
            "3mf",
            "4 materials need 3 attribute channels",
        ),
        (
            &["sphere", "--implicit", "--volume-resolution", "0"],
            "3mf",
            "volume resolution 0",
        ),
        (
            &["sphere", "--volume-resolution", "8"],
            "3mf",
            "give --implicit",
        ),
        (&[WIFFLE, BOX, "--palette", "a=red"], "3mf", "#RRGGBB"),
    ];
    for (k, (args, ext, msg)) in cases.iter().enumerate() {
        let out = d.join(format!("e{k}.{ext}"));
        let mut a = vec!["mesh"];
        a.extend_from_slice(args);
        a.extend(["-o", out.to_str().unwrap(), "--resolution", "16"]);
        let o = run(&a);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(msg), "{a:?}: {err}");
        assert!(!out.exists(), "{a:?} left {}", out.display());
    }
    // A strut fill with an extension asked for is meshed (a beam lattice
    // cannot carry a level set): the file holds the implicit level set.
    let out = d.join("l.3mf");
    ok(&[
        "fill",
        "sphere",
        "-o",
        out.to_str().unwrap(),
        "--structure",
        "octet",
        "--cell",
        "0.5",
        "--density",
        "0.2",
        "--implicit",
    ]);
    let m = microfrep::threemf::read_file(&out).unwrap();
    microfrep::threemf::validate(&m).unwrap();
    assert!(!m.implicit_functions.is_empty());
    level_set(&m);
}

#[test]
fn a_strut_model_meshes_to_a_beam_lattice_unless_triangles() {
    let d = dir("struts");
    let model = d.join("octet.hf");
    let bare = d.join("bare.hf");
    let moved = d.join("moved.hf");
    let body = |x: &str, part: &str| {
        format!(
            "my_model(x[3], a[1]) {{\n  array xt[3];\n  xt[1] = x[1] + 0.1; xt[2] = x[2]; xt[3] = x[3];\n  \
             ball = 1 - x[1]^2 - x[2]^2 - x[3]^2;\n  my_model = mfStruts({x}, 4, 0.5, 0.05){part};\n}}\n"
        )
    };
    std::fs::write(&model, body("x", " & ball")).unwrap();
    std::fs::write(&bare, body("x", "")).unwrap();
    std::fs::write(&moved, body("xt", " & ball")).unwrap();
    let out = d.join("octet.3mf");
    let o = ok(&[
        "mesh",
        model.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--resolution",
        "40",
        "--json",
    ]);
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["kind"], "beam-lattice", "{j}");
    let m = microfrep::threemf::read_file(&out).unwrap();
    microfrep::threemf::validate(&m).unwrap();
    let lat = microfrep::threemf::lattices(&m).unwrap();
    assert_eq!(lat.len(), 1);
    assert_eq!(lat[0].beams.len() as u64, j["beams"].as_u64().unwrap());
    assert!(lat[0].beams.len() > 500, "{}", lat[0].beams.len());
    // Every beam lies on a strut of the model: the bare lattice's value
    // (radius minus the distance to the nearest strut axis) is the radius
    // at both ends and the middle.
    let lattice = load::load(bare.to_str().unwrap(), &LoadOptions::default()).unwrap();
    let mut pe = lattice.shape.point();
    for b in &lat[0].beams {
        assert!((b.r1 - 0.05).abs() < 1e-12 && (b.r2 - 0.05).abs() < 1e-12);
        let (p, q) = (lat[0].nodes[b.v1 as usize], lat[0].nodes[b.v2 as usize]);
        for t in [0.0, 0.5, 1.0] {
            let x: [f64; 3] = std::array::from_fn(|a| p[a] + t * (q[a] - p[a]));
            let v = pe.eval(x);
            assert!((v - 0.05).abs() < 1e-9, "beam {p:?}-{q:?} at {t}: {v}");
        }
        let r = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        assert!(
            r(p).min(r(q)) < 1.0 + 0.5,
            "{p:?} {q:?} far outside the ball"
        );
    }
    // --triangles, and models that are not a plain lattice, give meshes.
    let tri = d.join("tri.3mf");
    let mv = d.join("moved.3mf");
    for (src, dst, extra) in [(&model, &tri, "--triangles"), (&moved, &mv, "--quiet")] {
        ok(&[
            "mesh",
            src.to_str().unwrap(),
            "-o",
            dst.to_str().unwrap(),
            "--resolution",
            "40",
            extra,
        ]);
        let m = microfrep::threemf::read_file(dst).unwrap();
        assert!(microfrep::threemf::lattices(&m).unwrap().is_empty());
        let meshes = microfrep::threemf::meshes(&m).unwrap();
        assert!(meshes[0].triangles.len() > 1000);
    }
}
