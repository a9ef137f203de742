//! Round trips through the writer and reader, and the errors for bad files.

use microfrep_3mf::beam::*;
use microfrep_3mf::implicit::Value;
use microfrep_3mf::slice::{orient_by_nesting, signed_area};
use microfrep_3mf::volumetric::*;
use microfrep_3mf::*;
use std::io::{Cursor, Write};

fn write(m: &Model, opts: &WriteOptions) -> Vec<u8> {
    write_to(Cursor::new(Vec::new()), m, opts)
        .unwrap()
        .into_inner()
}

fn read(bytes: &[u8]) -> Result<Model> {
    read_from(Cursor::new(bytes.to_vec()))
}

fn cube(s: f64) -> Mesh {
    Mesh::cuboid([0.0; 3], [s; 3])
}

fn volume(m: &NamedMesh) -> f64 {
    m.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| m.vertices[i as usize]);
            (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                + a[2] * (b[0] * c[1] - b[1] * c[0]))
                / 6.0
        })
        .sum()
}

#[test]
fn core_components_transforms_and_units_flatten_to_millimetres() {
    for unit in Unit::ALL {
        let mut m = Model::new(unit);
        m.metadata.push(Metadata {
            name: "Title".into(),
            value: "a & <b>".into(),
        });
        let c = m.add_mesh(Some("cube"), cube(2.0));
        let asm = m.add_components(
            Some("pair"),
            vec![
                Component {
                    object: c,
                    transform: Transform::IDENTITY,
                },
                Component {
                    object: c,
                    transform: Transform::translation([5.0, 0.0, 0.0]),
                },
                // A mirror: volume must stay positive.
                Component {
                    object: c,
                    transform: Transform::scale([-1.0, 1.0, 1.0]),
                },
            ],
        );
        m.add_item(
            asm,
            Transform::rotation_z(0.5).then(&Transform::translation([1.0, 2.0, 3.0])),
        );
        m.add_item(c, Transform::scale([2.0, 1.0, 1.0]));
        let bytes = write(&m, &WriteOptions::default());
        let back = read(&bytes).unwrap();
        assert_eq!(back, m, "{unit:?}");
        let meshes = meshes(&back).unwrap();
        assert_eq!(meshes.len(), 4);
        let k = unit.to_mm().powi(3);
        for (i, want) in [8.0, 8.0, 8.0, 16.0].iter().enumerate() {
            let v = volume(&meshes[i]);
            assert!(
                (v - want * k).abs() < 1e-9 * k.max(1.0),
                "{unit:?} mesh {i}: {v}"
            );
        }
        // Second component: translated by 5, rotated, then moved by (1, 2, 3).
        let p = meshes[1].vertices[0];
        let (s, co) = 0.5f64.sin_cos();
        let u = unit.to_mm();
        let want = [(5.0 * co + 1.0) * u, (5.0 * s + 2.0) * u, 3.0 * u];
        for a in 0..3 {
            assert!((p[a] - want[a]).abs() < 1e-9 * u.max(1.0), "{p:?} {want:?}");
        }
    }
}

#[test]
fn writes_are_deterministic() {
    let mut m = Model::new(Unit::Millimeter);
    let c = m.add_mesh(None, cube(1.0));
    m.add_item(c, Transform::IDENTITY);
    assert_eq!(
        write(&m, &WriteOptions::default()),
        write(&m, &WriteOptions::default())
    );
}

fn lattice_model() -> Model {
    let mut m = Model::new(Unit::Millimeter);
    let clip = m.add_mesh(Some("clip"), cube(3.0));
    let rep = m.add_mesh(Some("representation"), cube(2.5));
    let nodes: Vec<[f64; 3]> = (0..27)
        .map(|i| [(i % 3) as f64, (i / 3 % 3) as f64, (i / 9) as f64])
        .collect();
    let mut l = BeamLattice::new(0.1, 1e-4);
    for i in 0..27u32 {
        for (d, ok) in [(1, i % 3 < 2), (3, i / 3 % 3 < 2), (9, i / 9 < 2)] {
            if ok {
                l.push(i, i + d, 0.1 + 0.01 * (i % 5) as f64, 0.1);
            }
        }
    }
    l.beams[0].cap1 = Some(Cap::Butt);
    l.beams[1].cap2 = Some(Cap::Hemisphere);
    l.ball_mode = BallMode::Mixed;
    l.ball_radius = Some(0.2);
    l.balls = vec![
        Ball {
            vindex: 13,
            r: Some(0.3),
        },
        Ball { vindex: 0, r: None },
    ];
    l.beam_sets = vec![BeamSet {
        name: Some("edges".into()),
        identifier: Some("e1".into()),
        beams: vec![0, 1, 2],
        balls: vec![1],
    }];
    l.clipping = Some((ClipMode::Inside, clip));
    l.representation = Some(rep);
    let id = m.add_mesh(
        Some("lattice"),
        Mesh {
            vertices: nodes,
            beam_lattice: Some(l),
            ..Mesh::default()
        },
    );
    m.add_item(id, Transform::IDENTITY);
    m
}

#[test]
fn beam_lattice_round_trips_with_balls_sets_clipping_and_representation() {
    let m = lattice_model();
    let bytes = write(&m, &WriteOptions::default());
    let xml = root_xml(&bytes);
    assert!(
        xml.contains("requiredextensions=\"b b2\""),
        "{}",
        &xml[..400]
    );
    assert!(xml.contains("clippingmode=\"inside\"") && xml.contains("representationmesh=\""));
    let back = read(&bytes).unwrap();
    assert_eq!(back, m);
    let l = lattices(&back).unwrap();
    assert_eq!(l.len(), 1);
    assert_eq!(l[0].beams.len(), 54);
    let b = l[0].beams[4];
    assert_eq!(b.r1, 0.1 + 0.01 * (b.v1 % 5) as f64);
    assert_eq!(b.r2, 0.1);
    // The lattice-only object has no triangles; the meshes of the build are empty.
    assert!(meshes(&back).unwrap().is_empty());
}

fn root_xml(bytes: &[u8]) -> String {
    let mut z = zip::ZipArchive::new(Cursor::new(bytes.to_vec())).unwrap();
    let mut f = z.by_name("3D/3dmodel.model").unwrap();
    let mut s = String::new();
    std::io::Read::read_to_string(&mut f, &mut s).unwrap();
    s
}

#[test]
fn slice_stacks_round_trip_and_split_over_parts() {
    let mut m = Model::new(Unit::Millimeter);
    let lowres = m.add_mesh(Some("part"), cube(10.0));
    let mut layers = Vec::new();
    for k in 0..25 {
        if k % 7 == 3 {
            layers.push(vec![]); // an empty layer
            continue;
        }
        let r = 3.0 + 0.1 * k as f64;
        let outer: Polygon = (0..12)
            .map(|i| {
                let a = i as f64 * std::f64::consts::TAU / 12.0;
                [5.0 + r * a.cos(), 5.0 + r * a.sin()]
            })
            .collect();
        let mut hole: Polygon = (0..6)
            .map(|i| {
                let a = i as f64 * std::f64::consts::TAU / 6.0;
                [5.0 + a.cos(), 5.0 + a.sin()]
            })
            .collect();
        hole.reverse();
        layers.push(vec![outer, hole]);
    }
    let sid = m.next_id();
    m.slice_stacks
        .push(SliceStack::uniform(sid, 0.0, 0.4, layers));
    m.objects[0].slice_stack = Some(sid);
    m.objects[0].mesh_resolution = MeshResolution::Low;
    m.add_item(lowres, Transform::translation([1.0, 1.0, 0.0]));
    for opts in [
        WriteOptions::default(),
        WriteOptions {
            max_slices_per_part: 10,
            ..WriteOptions::default()
        },
        WriteOptions {
            max_slice_bytes_per_part: 2000,
            ..WriteOptions::default()
        },
    ] {
        let bytes = write(&m, &opts);
        let xml = root_xml(&bytes);
        let parts = xml.matches("<s:sliceref").count();
        assert_eq!(
            parts > 0,
            opts.max_slices_per_part < 25 || opts.max_slice_bytes_per_part < 1 << 20
        );
        assert!(
            xml.contains("requiredextensions=\"s\"") && xml.contains("s:meshresolution=\"lowres\"")
        );
        let back = read(&bytes).unwrap();
        assert_eq!(
            back.slice_stacks, m.slice_stacks,
            "{opts:?} ({parts} parts)"
        );
        let st = &back.slice_stacks[0];
        for s in &st.slices {
            if let [outer, hole] = s.polygons.as_slice() {
                assert!(signed_area(outer) > 0.0 && signed_area(hole) < 0.0);
            }
        }
    }
    // A non-planar build transform is refused for a sliced object.
    let mut bad = m.clone();
    bad.build[0].transform =
        Transform([1.0, 0.0, 0.1, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]);
    assert!(write_to(Cursor::new(Vec::new()), &bad, &WriteOptions::default()).is_err());
}

#[test]
fn orientation_by_nesting_makes_outer_ccw_and_holes_cw() {
    let sq = |c: f64, r: f64| -> Polygon {
        vec![
            [c - r, c - r],
            [c - r, c + r],
            [c + r, c + r],
            [c + r, c - r],
        ]
    };
    let mut p = vec![sq(0.0, 3.0), sq(0.0, 2.0), sq(0.0, 1.0)];
    orient_by_nesting(&mut p);
    assert!(signed_area(&p[0]) > 0.0 && signed_area(&p[1]) < 0.0 && signed_area(&p[2]) > 0.0);
}

#[test]
fn volumetric_image_stack_and_composite_round_trip() {
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
    let im = Image3D::from_fn(2, [5, 4, 3], PixelLayout::Rgb, 16, |x, y, z| {
        let r = x as f64 / 4.0;
        [r, 1.0 - r, (y + z) as f64 / 5.0, 1.0]
    })
    .unwrap();
    m.images.push(im);
    m.image_functions.push(FunctionFromImage3D::new(3, 2));
    let to_unit = Transform::box_to_unit([0.0; 3], [10.0; 3]);
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
            required: false,
            value: FunctionRef::new(3, "blue", to_unit),
        }],
    });
    let mut mesh = cube(10.0);
    mesh.volume_id = Some(4);
    let id = m.add_mesh(Some("graded"), mesh);
    m.add_item(id, Transform::IDENTITY);
    let bytes = write(&m, &WriteOptions::default());
    let mut back = read(&bytes).unwrap();
    assert_eq!(back.images[0].sheet_paths.len(), 3);
    back.images[0].sheet_paths.clear();
    assert_eq!(back, m);
    // Voxel (4, 0, 0): red 1, green 0; the V axis is not flipped on the way.
    let im = &back.images[0];
    assert_eq!(im.value(4, 0, 0, 0), 1.0);
    assert!((im.value(0, 3, 2, 2) - 1.0).abs() < 1e-4);
    assert!((im.sample_nearest([0.95, 0.1, 0.1], 1)).abs() < 1e-9);
}

#[test]
fn core_graph_as_implicit_function_evaluates_like_the_core() {
    use microfrep_core::{Expr, PointEval, Tape};
    let [x, y, z] = Expr::xyz();
    let exprs = [
        (x.square() + y.square() + z.square()).sqrt() - 1.0,
        (&x * 3.0).sin().max((&y * 2.0).cos()) - z.abs().min(0.5),
        Expr::select(x.lt(&y), x.tan().atan(), z.exp().ln() + y.powi(3)),
        x.trunc()
            + y.fract()
            + Expr::unary(microfrep_core::UnaryOp::Tri, z.clone())
            + Expr::unary(microfrep_core::UnaryOp::Saw, x.clone()),
        x.modulo(0.7)
            + y.rem(0.3)
            + x.atan2(&y)
            + x.pow(2.0).round()
            + z.sign()
            + y.floor()
            + x.ceil(),
        x.le(&y)
            + x.ge(&z)
            + x.gt(&y)
            + x.eq_(&x)
            + y.ne_(&z)
            + x.and(&y)
            + z.or(&x)
            + x.not()
            + x.neg()
            + (&y / 3.0).asin()
            + (&z / 4.0).acos()
            + x.sinh()
            - y.cosh() * z.tanh()
            + Expr::param("r", 0.25),
    ];
    for (k, e) in exprs.iter().enumerate() {
        let f = microfrep_3mf::from_core::implicit_from_expr(e, 7, Some("model")).unwrap();
        f.validate().unwrap();
        // Through a file and back.
        let mut m = Model::new(Unit::Millimeter);
        m.implicit_functions.push(f);
        let mut box_mesh = cube(1.0);
        box_mesh.volume_id = None;
        let id = m.add_mesh(None, box_mesh);
        m.add_item(id, Transform::IDENTITY);
        let back = read(&write(&m, &WriteOptions::default())).unwrap();
        assert_eq!(back.implicit_functions, m.implicit_functions);
        let f = &back.implicit_functions[0];
        let tape = Tape::new(e);
        let mut ev = PointEval::new(&tape);
        for i in 0..300 {
            let p = [
                ((i * 37 % 101) as f64 / 101.0 - 0.5) * 3.0,
                ((i * 53 % 103) as f64 / 103.0 - 0.5) * 3.0,
                ((i * 71 % 107) as f64 / 107.0 - 0.5) * 3.0,
            ];
            let want = ev.eval(p);
            let got = f.eval(&[("pos", Value::Vector(p))]).unwrap()[0].1;
            let Value::Scalar(got) = got else { panic!() };
            assert!(
                (want - got).abs() <= 1e-12 * (1.0 + want.abs()) || (want.is_nan() && got.is_nan()),
                "expr {k} at {p:?}: core {want} implicit {got}"
            );
        }
    }
}

#[test]
fn fields_are_listed_as_unsupported() {
    use microfrep_core::{Expr, Graph, GridField};
    use std::sync::Arc;
    let g = GridField::sample("scan", [3, 3, 3], [0.0; 3], [1.0; 3], |p| p[0]).unwrap();
    let e = Expr::field(Arc::new(g)) - Expr::x();
    let mut graph = Graph::new();
    let root = graph.add(&e);
    let u = microfrep_3mf::from_core::unsupported(&graph, root);
    assert_eq!(u.len(), 1);
    assert!(u[0].what.contains("scan"));
    assert!(microfrep_3mf::from_core::implicit_from_expr(&e, 1, None).is_err());
}

/// A package built by hand from parts.
fn package(parts: &[(&str, &str)]) -> Vec<u8> {
    let mut z = zip::ZipWriter::new(Cursor::new(Vec::new()));
    for (n, d) in parts {
        z.start_file(*n, zip::write::SimpleFileOptions::default())
            .unwrap();
        z.write_all(d.as_bytes()).unwrap();
    }
    z.finish().unwrap().into_inner()
}

const CT: &str = r#"<?xml version="1.0"?><Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types"><Default Extension="rels" ContentType="application/vnd.openxmlformats-package.relationships+xml"/><Default Extension="model" ContentType="application/vnd.ms-package.3dmanufacturing-3dmodel+xml"/></Types>"#;
const RELS: &str = r#"<?xml version="1.0"?><Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships"><Relationship Target="/3D/3dmodel.model" Id="r0" Type="http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"/></Relationships>"#;

fn model_xml(body: &str, attrs: &str) -> String {
    format!(
        r#"<?xml version="1.0"?><model xmlns="http://schemas.microsoft.com/3dmanufacturing/core/2015/02" {attrs}><resources>{body}</resources><build/></model>"#
    )
}

fn read_err(parts: &[(&str, &str)]) -> String {
    read(&package(parts)).unwrap_err().to_string()
}

#[test]
fn malformed_packages_give_clear_errors() {
    let tri = r#"<object id="1"><mesh><vertices><vertex x="0" y="0" z="0"/><vertex x="1" y="0" z="0"/><vertex x="0" y="1" z="0"/></vertices><triangles><triangle v1="0" v2="1" v3="7"/></triangles></mesh></object>"#;
    let e = read_err(&[
        ("_rels/.rels", RELS),
        ("3D/3dmodel.model", &model_xml(tri, "")),
    ]);
    assert!(e.contains("[Content_Types].xml"), "{e}");
    let e = read_err(&[
        ("[Content_Types].xml", CT),
        ("3D/3dmodel.model", &model_xml(tri, "")),
    ]);
    assert!(e.contains("_rels/.rels"), "{e}");
    let e = read_err(&[("[Content_Types].xml", CT), ("_rels/.rels", RELS)]);
    assert!(e.contains("missing part /3D/3dmodel.model"), "{e}");
    let e = read_err(&[
        ("[Content_Types].xml", CT),
        ("_rels/.rels", "<Relationships"),
        ("3D/3dmodel.model", ""),
    ]);
    assert!(e.contains("_rels/.rels") && e.contains("XML"), "{e}");
    let e = read_err(&[
        ("[Content_Types].xml", CT),
        ("_rels/.rels", RELS),
        ("3D/3dmodel.model", &model_xml(tri, "")),
    ]);
    assert!(
        e.contains("/3D/3dmodel.model") || e.contains("3D/3dmodel.model"),
        "{e}"
    );
    assert!(e.contains("triangle 0") && e.contains("byte"), "{e}");
    let nan = tri.replace("x=\"1\"", "x=\"NaN\"");
    let e = read_err(&[
        ("[Content_Types].xml", CT),
        ("_rels/.rels", RELS),
        ("3D/3dmodel.model", &model_xml(&nan, "")),
    ]);
    assert!(e.contains("not a finite number"), "{e}");
    let req = model_xml(
        tri,
        r#"xmlns:p="http://example.com/unknown/2030" requiredextensions="p""#,
    );
    let e = read_err(&[
        ("[Content_Types].xml", CT),
        ("_rels/.rels", RELS),
        ("3D/3dmodel.model", &req),
    ]);
    assert!(
        e.contains("requires extension http://example.com/unknown/2030"),
        "{e}"
    );
    let undeclared = model_xml(tri, r#"requiredextensions="q""#);
    let e = read_err(&[
        ("[Content_Types].xml", CT),
        ("_rels/.rels", RELS),
        ("3D/3dmodel.model", &undeclared),
    ]);
    assert!(e.contains("undeclared"), "{e}");
    let dtd = format!("<!DOCTYPE model>{}", model_xml("", ""));
    let e = read_err(&[
        ("[Content_Types].xml", CT),
        ("_rels/.rels", RELS),
        ("3D/3dmodel.model", &dtd),
    ]);
    assert!(e.contains("DTD"), "{e}");
    let bad_ct = CT.replace("3dmodel+xml", "text+xml");
    let e = read_err(&[
        ("[Content_Types].xml", &bad_ct),
        ("_rels/.rels", RELS),
        ("3D/3dmodel.model", &model_xml("", "")),
    ]);
    assert!(e.contains("content type"), "{e}");
    assert!(read(b"not a zip").unwrap_err().to_string().contains("zip"));
    // A good hand-made package reads.
    let ok = tri.replace("v3=\"7\"", "v3=\"2\"");
    let m = read(&package(&[
        ("[Content_Types].xml", CT),
        ("_rels/.rels", RELS),
        ("3D/3dmodel.model", &model_xml(&ok, "")),
    ]))
    .unwrap();
    assert_eq!(m.objects.len(), 1);
}

#[test]
fn writer_refuses_bad_models() {
    let mut m = Model::new(Unit::Millimeter);
    let mut c = cube(1.0);
    c.triangles[3] = [0, 1, 99];
    let id = m.add_mesh(None, c);
    m.add_item(id, Transform::IDENTITY);
    assert!(validate(&m).unwrap_err().to_string().contains("triangle 3"));
    let mut m = lattice_model();
    if let ObjectContent::Mesh(me) = &mut m.objects[2].content {
        me.beam_lattice.as_mut().unwrap().beams[0].r1 = f64::NAN;
    }
    assert!(validate(&m).is_err());
    let mut m = Model::new(Unit::Millimeter);
    m.add_item(5, Transform::IDENTITY);
    assert!(validate(&m).is_err());
}
