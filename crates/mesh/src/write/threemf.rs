//! 3MF through the `microfrep-3mf` crate: one mesh object in millimetres;
//! vertex colours become a colour group (materials extension) with one
//! colour per vertex, each triangle's corners pointing at their vertices'.

use super::MeshFormat;
use crate::Mesh;
use microfrep_io::{AtomicFile, OutputFormat};

pub(super) struct ThreeMf;

impl OutputFormat for ThreeMf {
    fn name(&self) -> &'static str {
        "3MF"
    }
    fn extensions(&self) -> &'static [&'static str] {
        &["3mf"]
    }
}

impl MeshFormat for ThreeMf {
    fn stores_colours(&self) -> bool {
        true
    }
    fn write(
        &self,
        mesh: &Mesh,
        _: Option<&[[f32; 3]]>,
        colours: Option<&[[u8; 3]]>,
        out: &mut AtomicFile,
    ) -> std::io::Result<()> {
        let mut model = microfrep_3mf::Model::new(microfrep_3mf::Unit::Millimeter);
        let mut m = microfrep_3mf::Mesh {
            vertices: mesh.vertices.iter().map(|p| p.map(|c| c as f64)).collect(),
            triangles: mesh.triangles.clone(),
            ..Default::default()
        };
        let group = colours.map(|cs| {
            let id = model.next_id();
            model.color_groups.push(microfrep_3mf::ColorGroup {
                id,
                colors: cs.iter().map(|c| [c[0], c[1], c[2], 255]).collect(),
            });
            m.properties = Some(microfrep_3mf::TriangleProperties {
                pid: id,
                indices: mesh.triangles.clone(),
            });
            id
        });
        let id = model.add_mesh(Some("microfrep mesh"), m);
        if let Some(g) = group {
            // Triangle properties need an object-level default.
            model.objects.last_mut().expect("just added").property = Some((g, 0));
        }
        model.add_item(id, microfrep_3mf::Transform::IDENTITY);
        microfrep_3mf::write_to(out, &model, &microfrep_3mf::WriteOptions::default())
            .map(|_| ())
            .map_err(std::io::Error::other)
    }
}
