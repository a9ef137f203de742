//! 3MF through the `microfrep-3mf` crate: one mesh object in millimetres.

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
    fn write(
        &self,
        mesh: &Mesh,
        _: Option<&[[f32; 3]]>,
        out: &mut AtomicFile,
    ) -> std::io::Result<()> {
        let mut model = microfrep_3mf::Model::new(microfrep_3mf::Unit::Millimeter);
        let m = microfrep_3mf::Mesh {
            vertices: mesh.vertices.iter().map(|p| p.map(|c| c as f64)).collect(),
            triangles: mesh.triangles.clone(),
            ..Default::default()
        };
        let id = model.add_mesh(Some("microfrep mesh"), m);
        model.add_item(id, microfrep_3mf::Transform::IDENTITY);
        microfrep_3mf::write_to(out, &model, &microfrep_3mf::WriteOptions::default())
            .map(|_| ())
            .map_err(std::io::Error::other)
    }
}
