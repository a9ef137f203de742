//! Colour groups (materials extension): per-vertex colours written as
//! `<m:colorgroup>` with triangles pointing at their corners' colours, read
//! back unchanged; bad colours and references are refused.

use microfrep_3mf::*;
use std::io::{Cursor, Write};

fn tet() -> Mesh {
    Mesh {
        vertices: vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ],
        triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        ..Mesh::default()
    }
}

fn coloured(colors: Vec<[u8; 4]>) -> Model {
    let mut model = Model::new(Unit::Millimeter);
    model.color_groups.push(ColorGroup { id: 1, colors });
    let mut m = tet();
    m.properties = Some(TriangleProperties {
        pid: 1,
        indices: m.triangles.clone(),
    });
    let id = model.add_mesh(Some("tet"), m);
    model.objects.last_mut().unwrap().property = Some((1, 0));
    model.add_item(id, Transform::IDENTITY);
    model
}

fn write(m: &Model) -> Result<Vec<u8>> {
    write_to(Cursor::new(Vec::new()), m, &WriteOptions::default()).map(|c| c.into_inner())
}

fn root_xml(bytes: &[u8]) -> String {
    let mut z = zip::ZipArchive::new(Cursor::new(bytes.to_vec())).unwrap();
    let mut f = z.by_name("3D/3dmodel.model").unwrap();
    let mut s = String::new();
    std::io::Read::read_to_string(&mut f, &mut s).unwrap();
    s
}

#[test]
fn colour_groups_round_trip_per_vertex() {
    let colors = vec![
        [255, 0, 0, 255],
        [0, 128, 0, 255],
        [1, 2, 3, 4],
        [0xAB, 0xCD, 0xEF, 0x80],
    ];
    let model = coloured(colors.clone());
    let bytes = write(&model).unwrap();
    let xml = root_xml(&bytes);
    assert!(
        xml.contains("xmlns:m=\"http://schemas.microsoft.com/3dmanufacturing/material/2015/02\"")
    );
    assert!(xml.contains("<m:colorgroup id=\"1\">"), "{xml}");
    assert!(xml.contains("<m:color color=\"#ABCDEF80\"/>"), "{xml}");
    assert!(
        xml.contains("pid=\"1\" p1=\"0\" p2=\"2\" p3=\"1\""),
        "{xml}"
    );
    let back = read_from(Cursor::new(bytes)).unwrap();
    assert_eq!(back, model);
    assert_eq!(back.color_groups[0].colors, colors);
}

fn package(model: &str) -> Vec<u8> {
    const CT: &str = r#"<?xml version="1.0"?><Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types"><Default Extension="rels" ContentType="application/vnd.openxmlformats-package.relationships+xml"/><Default Extension="model" ContentType="application/vnd.ms-package.3dmanufacturing-3dmodel+xml"/></Types>"#;
    const RELS: &str = r#"<?xml version="1.0"?><Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships"><Relationship Target="/3D/3dmodel.model" Id="r0" Type="http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"/></Relationships>"#;
    let mut z = zip::ZipWriter::new(Cursor::new(Vec::new()));
    for (n, d) in [
        ("[Content_Types].xml", CT),
        ("_rels/.rels", RELS),
        ("3D/3dmodel.model", model),
    ] {
        z.start_file(n, zip::write::SimpleFileOptions::default())
            .unwrap();
        z.write_all(d.as_bytes()).unwrap();
    }
    z.finish().unwrap().into_inner()
}

fn group_xml(colours: &str) -> String {
    format!(
        r#"<?xml version="1.0"?><model xmlns="http://schemas.microsoft.com/3dmanufacturing/core/2015/02" xmlns:m="http://schemas.microsoft.com/3dmanufacturing/material/2015/02"><resources><m:colorgroup id="5">{colours}</m:colorgroup></resources><build/></model>"#
    )
}

#[test]
fn hand_written_groups_read_and_bad_colours_are_refused() {
    let m = read_from(Cursor::new(package(&group_xml(
        r##"<m:color color="#102030"/><m:color color=" #FFFFFF00 "/>"##,
    ))))
    .unwrap();
    assert_eq!(
        m.color_groups,
        vec![ColorGroup {
            id: 5,
            colors: vec![[0x10, 0x20, 0x30, 255], [255, 255, 255, 0]]
        }]
    );
    for bad in [
        r##"<m:color color="#12345"/>"##,
        r##"<m:color color="red"/>"##,
        r##"<m:color color="#GG0000"/>"##,
        r##"<m:color/>"##,
        "",
    ] {
        let e = read_from(Cursor::new(package(&group_xml(bad))))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("colour") && e.contains("3D/3dmodel.model"),
            "{bad}: {e}"
        );
    }
}

#[test]
fn writer_refuses_bad_colour_references() {
    // An index past the group's colours.
    let mut m = coloured(vec![[0, 0, 0, 255]; 3]);
    let e = write(&m).unwrap_err().to_string();
    assert!(e.contains("index out of range"), "{e}");
    // An empty group.
    m.color_groups[0].colors.clear();
    let e = write(&m).unwrap_err().to_string();
    assert!(e.contains("colorgroup 1 has no colour"), "{e}");
    // A pid that names no group.
    let mut m = coloured(vec![[0, 0, 0, 255]; 4]);
    m.color_groups[0].id = 9;
    let e = write(&m).unwrap_err().to_string();
    assert!(e.contains("not defined"), "{e}");
}
