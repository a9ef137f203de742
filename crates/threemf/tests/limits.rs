//! The reader's limits: component fan-out counted before it is expanded,
//! zip bombs (declared and actual sizes) against the memory limit, and
//! resource ids that must be unique.

use microfrep_3mf::{expansion, meshes_with, read_from_with, Error, Model, ReadOptions};
use proptest::prelude::*;
use std::io::{Cursor, Write};

const CT: &str = r#"<?xml version="1.0"?><Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types"><Default Extension="rels" ContentType="application/vnd.openxmlformats-package.relationships+xml"/><Default Extension="model" ContentType="application/vnd.ms-package.3dmanufacturing-3dmodel+xml"/></Types>"#;
const RELS: &str = r#"<?xml version="1.0"?><Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships"><Relationship Target="/3D/3dmodel.model" Id="r0" Type="http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"/></Relationships>"#;

fn package(model: &[u8]) -> Vec<u8> {
    let mut z = zip::ZipWriter::new(Cursor::new(Vec::new()));
    let o = zip::write::SimpleFileOptions::default();
    for (n, d) in [
        ("[Content_Types].xml", CT.as_bytes()),
        ("_rels/.rels", RELS.as_bytes()),
        ("3D/3dmodel.model", model),
    ] {
        z.start_file(n, o).unwrap();
        z.write_all(d).unwrap();
    }
    z.finish().unwrap().into_inner()
}

fn model_xml(resources: &str, build: &str) -> String {
    format!(
        r#"<?xml version="1.0"?><model xmlns="http://schemas.microsoft.com/3dmanufacturing/core/2015/02" unit="millimeter"><resources>{resources}</resources><build>{build}</build></model>"#
    )
}

const TET: &str = r#"<object id="1"><mesh><vertices><vertex x="0" y="0" z="0"/><vertex x="1" y="0" z="0"/><vertex x="0" y="1" z="0"/><vertex x="0" y="0" z="1"/></vertices><triangles><triangle v1="0" v2="2" v3="1"/><triangle v1="0" v2="1" v3="3"/><triangle v1="0" v2="3" v3="2"/><triangle v1="1" v2="2" v3="3"/></triangles></mesh></object>"#;

/// A tetrahedron under `levels` levels of objects holding `fan` components
/// each of the level below.
fn fan_out(levels: u32, fan: u32) -> Vec<u8> {
    fan_out_of(TET, levels, fan)
}

/// `leaf` (object 1) under `levels` levels of `fan` components each.
fn fan_out_of(leaf: &str, levels: u32, fan: u32) -> Vec<u8> {
    let mut r = String::from(leaf);
    for l in 0..levels {
        r += &format!(r#"<object id="{}"><components>"#, l + 2);
        for k in 0..fan {
            r += &format!(
                r#"<component objectid="{}" transform="1 0 0 0 1 0 0 0 1 {k} 0 0"/>"#,
                l + 1
            );
        }
        r += "</components></object>";
    }
    package(model_xml(&r, &format!(r#"<item objectid="{}"/>"#, levels + 1)).as_bytes())
}

fn read(bytes: &[u8], limit: u64) -> Result<Model, Error> {
    read_from_with(
        Cursor::new(bytes),
        &ReadOptions {
            memory_limit: limit,
        },
    )
}

/// The report's file: 40 levels of 2 components each (2^40 tetrahedra) is
/// refused at once, from the counts, before anything is expanded.
#[test]
fn forty_levels_of_two_are_refused_before_expanding() {
    let bytes = fan_out(40, 2);
    assert!(bytes.len() < 4096, "{}", bytes.len());
    let t = std::time::Instant::now();
    let m = read(&bytes, 1 << 30).unwrap();
    let e = expansion(&m).unwrap();
    assert_eq!(e.instances, 1 << 40);
    assert_eq!(e.triangles, 4 << 40);
    let err = meshes_with(&m, 1 << 30).unwrap_err().to_string();
    assert!(
        err.contains("expand") && err.contains("memory limit"),
        "{err}"
    );
    // The default entry point refuses it too (with the machine's limit).
    let err = microfrep_3mf::meshes(&m).unwrap_err().to_string();
    assert!(err.contains("expand"), "{err}");
    let err = microfrep_3mf::lattices(&m);
    assert!(err.is_ok(), "no beams, nothing to refuse");
    assert!(t.elapsed().as_secs_f64() < 2.0, "{:?}", t.elapsed());
    // 20 levels: 4M triangles, 144 MiB flattened.
    let m = read(&fan_out(20, 2), 1 << 30).unwrap();
    let err = meshes_with(&m, 64 << 20).unwrap_err().to_string();
    assert!(err.contains("about 144 MiB, more than the 64 MiB"), "{err}");
}

/// A tree that gives nothing (2^40 instances of an object without
/// triangles or beams) is not walked: flattening it is quick and empty.
#[test]
fn trees_that_give_nothing_are_not_walked() {
    let empty = r#"<object id="1"><mesh><vertices><vertex x="0" y="0" z="0"/></vertices><triangles/></mesh></object>"#;
    let m = read(&fan_out_of(empty, 40, 2), 1 << 30).unwrap();
    let e = expansion(&m).unwrap();
    assert_eq!(
        (e.instances, e.triangles, e.lattice_instances),
        (1 << 40, 0, 0)
    );
    let t = std::time::Instant::now();
    assert!(meshes_with(&m, 1 << 20).unwrap().is_empty());
    assert!(microfrep_3mf::lattices_with(&m, 1 << 20)
        .unwrap()
        .is_empty());
    assert!(t.elapsed().as_secs_f64() < 2.0, "{:?}", t.elapsed());
    // Beside it, a real mesh is still found, once.
    let both = format!(
        "{}{}",
        TET.replace("id=\"1\"", "id=\"99\""),
        r#"<object id="98"><components><component objectid="99"/><component objectid="41"/></components></object>"#
    );
    let mut r = String::from(empty);
    for l in 0..40 {
        r += &format!(
            r#"<object id="{}"><components><component objectid="{l1}"/><component objectid="{l1}"/></components></object>"#,
            l + 2,
            l1 = l + 1
        );
    }
    r += &both;
    let m = read(
        &package(model_xml(&r, r#"<item objectid="98"/>"#).as_bytes()),
        1 << 30,
    )
    .unwrap();
    let ms = meshes_with(&m, 1 << 20).unwrap();
    assert_eq!(ms.len(), 1);
    assert_eq!(ms[0].triangles.len(), 4);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Any tree: counted exactly (saturating), and flattened exactly when
    /// its meshes fit the limit, refused when they do not.
    #[test]
    fn fan_out_is_counted_exactly_and_checked(levels in 0u32..70, fan in 1u32..5, limit_kib in 1u64..4096) {
        let m = read(&fan_out(levels, fan), 1 << 30).unwrap();
        let r = expansion(&m);
        if levels > 64 {
            prop_assert!(r.is_err());
            return Ok(());
        }
        let e = r.unwrap();
        let inst = (fan as u128)
            .checked_pow(levels)
            .map_or(u64::MAX, |n| n.min(u64::MAX as u128) as u64);
        prop_assert_eq!(e.instances, inst);
        prop_assert_eq!(e.triangles, inst.saturating_mul(4));
        prop_assert_eq!(e.vertices, inst.saturating_mul(4));
        let limit = limit_kib << 10;
        let fits = e.mesh_bytes() <= limit;
        match meshes_with(&m, limit) {
            Ok(ms) => {
                prop_assert!(fits);
                prop_assert_eq!(ms.len() as u64, inst);
                prop_assert!(ms.iter().all(|x| x.triangles.len() == 4));
            }
            Err(err) => {
                prop_assert!(!fits, "{}", err);
                let too_large = matches!(err, Error::TooLarge { .. });
                prop_assert!(too_large);
            }
        }
    }
}

/// Vertices by the million in a small package: refused from the declared
/// size before reading, with the part named.
#[test]
fn declared_sizes_are_checked_before_reading() {
    let n = 1_000_000;
    let mut xml = String::from(
        r#"<?xml version="1.0"?><model xmlns="http://schemas.microsoft.com/3dmanufacturing/core/2015/02"><resources><object id="1"><mesh><vertices>"#,
    );
    for _ in 0..n {
        xml += r#"<vertex x="0" y="0" z="0"/>"#;
    }
    xml += r#"</vertices><triangles><triangle v1="0" v2="1" v3="2"/></triangles></mesh></object></resources><build><item objectid="1"/></build></model>"#;
    let bytes = package(xml.as_bytes());
    assert!(bytes.len() < xml.len() / 100);
    let err = read(&bytes, 8 << 20).unwrap_err().to_string();
    assert!(
        err.contains("/3D/3dmodel.model") && err.contains("declares"),
        "{err}"
    );
    // With room, it reads.
    let m = read(&bytes, 1 << 30).unwrap();
    assert_eq!(m.objects.len(), 1);
}

/// Elements that take more memory than their XML (components: 104 bytes
/// from 40 of text) are counted as they are read.
#[test]
fn arrays_are_counted_while_reading() {
    let n = 20_000;
    let mut r = String::from(TET);
    r += r#"<object id="2"><components>"#;
    for _ in 0..n {
        r += r#"<component objectid="1"/>"#;
    }
    r += "</components></object>";
    let xml = model_xml(&r, r#"<item objectid="2"/>"#);
    let bytes = package(xml.as_bytes());
    // The text passes the declared-size check, the components do not fit.
    let limit = xml.len() as u64;
    let err = read(&bytes, limit).unwrap_err().to_string();
    assert!(err.contains("component"), "{err}");
    assert!(read(&bytes, 100 * limit).is_ok());
}

/// A zip entry that inflates to more than it declares is cut off at its
/// declared size, so the check before reading cannot be lied to.
#[test]
fn entries_longer_than_declared_are_refused() {
    let mut r = String::from(TET);
    for i in 0..2000 {
        r += &format!(
            r#"<object id="{}"><components><component objectid="1"/></components></object>"#,
            i + 2
        );
    }
    let xml = model_xml(&r, r#"<item objectid="2"/>"#);
    let mut bytes = package(xml.as_bytes());
    // Patch the uncompressed size of the model entry (local header and
    // central directory) down to 1000 bytes.
    let name = b"3D/3dmodel.model";
    let real = xml.len() as u32;
    let mut patched = 0;
    for i in 0..bytes.len() - 4 {
        let sig = &bytes[i..i + 4];
        let (size_at, name_at) = if sig == [0x50, 0x4b, 0x03, 0x04] {
            (i + 22, i + 30)
        } else if sig == [0x50, 0x4b, 0x01, 0x02] {
            (i + 24, i + 46)
        } else {
            continue;
        };
        if bytes.get(name_at..name_at + name.len()) == Some(&name[..])
            && bytes[size_at..size_at + 4] == real.to_le_bytes()
        {
            bytes[size_at..size_at + 4].copy_from_slice(&1000u32.to_le_bytes());
            patched += 1;
        }
    }
    assert_eq!(patched, 2);
    assert!(read(&bytes, 1 << 30).is_err());
}

/// Resource ids are unique among all resources of a model, whatever their
/// kinds.
#[test]
fn duplicate_resource_ids_are_refused() {
    let kinds = [
        r#"<object id="ID"><components><component objectid="1"/></components></object>"#,
        r##"<basematerials id="ID"><base name="a" displaycolor="#FF0000"/></basematerials>"##,
        r##"<m:colorgroup xmlns:m="http://schemas.microsoft.com/3dmanufacturing/material/2015/02" id="ID"><m:color color="#FF0000"/></m:colorgroup>"##,
    ];
    for a in kinds {
        for b in kinds {
            let r = format!("{TET}{}{}", a.replace("ID", "5"), b.replace("ID", "5"));
            let bytes = package(model_xml(&r, r#"<item objectid="1"/>"#).as_bytes());
            let err = read(&bytes, 1 << 30).unwrap_err().to_string();
            assert!(err.contains("id 5 is already"), "{a} {b}: {err}");
            let r = format!("{TET}{}{}", a.replace("ID", "5"), b.replace("ID", "6"));
            let bytes = package(model_xml(&r, r#"<item objectid="1"/>"#).as_bytes());
            read(&bytes, 1 << 30).unwrap();
        }
    }
    // The report's case: two objects with the same id.
    let r = format!(
        "{TET}{}",
        TET.replace("id=\"1\"", "id=\"1\" name=\"again\"")
    );
    let bytes = package(model_xml(&r, r#"<item objectid="1"/>"#).as_bytes());
    let err = read(&bytes, 1 << 30).unwrap_err().to_string();
    assert!(err.contains("object id 1 is already"), "{err}");
}
