//! Paths the page names, kept inside the studio's root (the working
//! directory): relative, without `..`, and not leading out through a
//! symbolic link.

use crate::error::StudioError;
use std::path::{Component, Path, PathBuf};

/// A path under the root that was checked: `full` is inside `root`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Checked {
    /// The path as the page gave it (relative, `/`-separated).
    pub relative: String,
    /// Root joined with the path; its parent exists and lies inside the root.
    pub full: PathBuf,
}

fn refuse(path: &str, why: &str) -> StudioError {
    StudioError::Path {
        path: path.to_string(),
        reason: why.to_string(),
    }
}

/// Checks the lexical form: non-empty, relative, plain names only (no
/// `..`, `.`, root or drive prefix), no NUL, at most 4096 bytes.
fn lexical(path: &str) -> Result<PathBuf, StudioError> {
    if path.is_empty() {
        return Err(refuse(path, "empty path"));
    }
    if path.len() > 4096 || path.contains('\0') || path.contains('\\') {
        return Err(refuse(path, "not a plain relative path"));
    }
    let p = Path::new(path);
    let mut out = PathBuf::new();
    for c in p.components() {
        match c {
            Component::Normal(n) => out.push(n),
            Component::ParentDir => return Err(refuse(path, "'..' is not allowed")),
            Component::RootDir | Component::Prefix(_) => {
                return Err(refuse(path, "absolute paths are not allowed"))
            }
            Component::CurDir => return Err(refuse(path, "'.' components are not allowed")),
        }
    }
    if out.as_os_str().is_empty() {
        return Err(refuse(path, "empty path"));
    }
    Ok(out)
}

/// Resolves an existing file or directory under `root` (canonical): the
/// canonical target must lie inside `root`, so links out are refused.
pub fn existing(root: &Path, path: &str) -> Result<Checked, StudioError> {
    let rel = lexical(path)?;
    let full = root.join(&rel);
    let canon = full
        .canonicalize()
        .map_err(|e| refuse(path, &format!("cannot open: {e}")))?;
    if !canon.starts_with(root) {
        return Err(refuse(path, "leads outside the working directory"));
    }
    Ok(Checked {
        relative: path.to_string(),
        full: canon,
    })
}

/// Resolves a path to create or overwrite under `root` (canonical): its
/// parent must exist inside `root`, and the path itself must not be a
/// symbolic link. With `must_not_exist`, an existing path is refused.
pub fn writable(root: &Path, path: &str, must_not_exist: bool) -> Result<Checked, StudioError> {
    let rel = lexical(path)?;
    let name = rel
        .file_name()
        .ok_or_else(|| refuse(path, "no file name"))?
        .to_owned();
    let parent = root.join(rel.parent().unwrap_or(Path::new("")));
    let parent = parent
        .canonicalize()
        .map_err(|e| refuse(path, &format!("its folder cannot be opened: {e}")))?;
    if !parent.starts_with(root) {
        return Err(refuse(path, "leads outside the working directory"));
    }
    let full = parent.join(name);
    match std::fs::symlink_metadata(&full) {
        Ok(m) if m.file_type().is_symlink() => {
            return Err(refuse(path, "is a symbolic link"));
        }
        Ok(_) if must_not_exist => return Err(refuse(path, "already exists")),
        Ok(m) if m.is_dir() => return Err(refuse(path, "is a directory")),
        _ => {}
    }
    Ok(Checked {
        relative: path.to_string(),
        full,
    })
}

/// `.hf` files under `root`, as relative `/`-separated paths, sorted:
/// at most `limit` of them, searching `depth` levels deep, skipping hidden
/// folders, `target` and symbolic links.
pub fn list_models(root: &Path, depth: usize, limit: usize) -> Vec<String> {
    let mut out = Vec::new();
    let mut stack = vec![(root.to_path_buf(), String::new(), 0usize)];
    while let Some((dir, prefix, level)) = stack.pop() {
        let Ok(rd) = std::fs::read_dir(&dir) else {
            continue;
        };
        let mut entries: Vec<_> = rd.flatten().collect();
        entries.sort_by_key(|e| e.file_name());
        for e in entries {
            let name = e.file_name().to_string_lossy().into_owned();
            if name.starts_with('.') {
                continue;
            }
            let Ok(ft) = e.file_type() else { continue };
            let rel = format!("{prefix}{name}");
            if ft.is_dir() && level + 1 < depth && name != "target" && name != "node_modules" {
                stack.push((e.path(), format!("{rel}/"), level + 1));
            } else if ft.is_file() && name.to_ascii_lowercase().ends_with(".hf") {
                out.push(rel);
            }
        }
    }
    out.sort();
    out.truncate(limit);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn root() -> (PathBuf, PathBuf) {
        let base = std::env::temp_dir().join(format!("mf-studio-paths-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&base);
        let root = base.join("root");
        std::fs::create_dir_all(root.join("sub")).unwrap();
        std::fs::write(root.join("sub/a.hf"), "x").unwrap();
        std::fs::write(base.join("secret.hf"), "s").unwrap();
        (base, root.canonicalize().unwrap())
    }

    #[test]
    fn refuses_escapes_and_accepts_plain_paths() {
        let (base, root) = root();
        assert!(existing(&root, "sub/a.hf").is_ok());
        for bad in [
            "../secret.hf",
            "sub/../../secret.hf",
            "/etc/passwd",
            "",
            "./sub/a.hf",
            "sub\\a.hf",
        ] {
            let e = existing(&root, bad).unwrap_err();
            assert!(matches!(e, StudioError::Path { .. }), "{bad}: {e}");
        }
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink(base.join("secret.hf"), root.join("link.hf")).unwrap();
            std::os::unix::fs::symlink(&base, root.join("out")).unwrap();
            let e = existing(&root, "link.hf").unwrap_err().to_string();
            assert!(e.contains("outside"), "{e}");
            let e = existing(&root, "out/secret.hf").unwrap_err().to_string();
            assert!(e.contains("outside"), "{e}");
            let e = writable(&root, "link.hf", false).unwrap_err().to_string();
            assert!(e.contains("symbolic link"), "{e}");
            let e = writable(&root, "out/new.hf", false)
                .unwrap_err()
                .to_string();
            assert!(e.contains("outside"), "{e}");
        }
        let w = writable(&root, "sub/new.hf", true).unwrap();
        assert_eq!(w.full, root.join("sub/new.hf"));
        assert!(writable(&root, "sub/a.hf", true).is_err());
        assert!(writable(&root, "nodir/new.hf", false).is_err());
        assert_eq!(list_models(&root, 3, 10), vec!["sub/a.hf".to_string()]);
        let _ = std::fs::remove_dir_all(&base);
    }
}
