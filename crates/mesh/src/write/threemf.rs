//! 3MF (core specification): an OPC zip package with the content types,
//! the root relationship and one model part holding one mesh object, in
//! millimetres.

use crate::Mesh;
use std::fs::File;
use std::io::{BufWriter, Write};
use zip::write::SimpleFileOptions;

const CONTENT_TYPES: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types">
<Default Extension="rels" ContentType="application/vnd.openxmlformats-package.relationships+xml"/>
<Default Extension="model" ContentType="application/vnd.ms-package.3dmanufacturing-3dmodel+xml"/>
</Types>
"#;

const RELS: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships">
<Relationship Target="/3D/3dmodel.model" Id="rel0" Type="http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"/>
</Relationships>
"#;

pub fn write(file: File, mesh: &Mesh) -> std::io::Result<File> {
    let mut zip = zip::ZipWriter::new(file);
    let opts = SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
    let zerr = |e: zip::result::ZipError| std::io::Error::other(e);
    zip.start_file("[Content_Types].xml", opts).map_err(zerr)?;
    zip.write_all(CONTENT_TYPES.as_bytes())?;
    zip.start_file("_rels/.rels", opts).map_err(zerr)?;
    zip.write_all(RELS.as_bytes())?;
    zip.start_file("3D/3dmodel.model", opts).map_err(zerr)?;
    {
        let mut w = BufWriter::with_capacity(1 << 20, &mut zip);
        writeln!(w, r#"<?xml version="1.0" encoding="UTF-8"?>"#)?;
        writeln!(
            w,
            r#"<model unit="millimeter" xml:lang="en-US" xmlns="http://schemas.microsoft.com/3dmanufacturing/core/2015/02">"#
        )?;
        writeln!(
            w,
            r#"<resources><object id="1" type="model"><mesh><vertices>"#
        )?;
        for p in &mesh.vertices {
            writeln!(w, r#"<vertex x="{}" y="{}" z="{}"/>"#, p[0], p[1], p[2])?;
        }
        writeln!(w, "</vertices><triangles>")?;
        for t in &mesh.triangles {
            writeln!(
                w,
                r#"<triangle v1="{}" v2="{}" v3="{}"/>"#,
                t[0], t[1], t[2]
            )?;
        }
        writeln!(w, "</triangles></mesh></object></resources>")?;
        writeln!(w, r#"<build><item objectid="1"/></build></model>"#)?;
        w.flush()?;
    }
    zip.finish().map_err(zerr)
}
