//! What the facade's tests share.

use std::path::PathBuf;

/// A bone mesh of `../shared/meshes` (or `MICROFREP_MESHES`): `None`, with
/// a line saying the test was skipped, when it is absent; a failure when
/// `MICROFREP_MESHES` names a folder without it.
pub fn bone(name: &str) -> Option<String> {
    let dir = std::env::var_os("MICROFREP_MESHES")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/meshes")
        });
    let p = dir.join(name);
    if p.exists() {
        Some(p.display().to_string())
    } else if std::env::var_os("MICROFREP_MESHES").is_some() {
        panic!("MICROFREP_MESHES is set but {} is absent", p.display());
    } else {
        eprintln!(
            "SKIPPED: {} is absent (set MICROFREP_MESHES to the bone meshes)",
            p.display()
        );
        None
    }
}
