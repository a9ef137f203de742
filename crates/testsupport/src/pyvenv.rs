//! A Python interpreter with given packages, for the optional cross-checks
//! (PoreSpy, libigl, lib3mf) and the benchmarks that compare against Python
//! peers. Nothing in the library needs Python; this only saves each test and
//! bench from writing the same venv logic.
//!
//! [`python_with`] returns, in order: the interpreter named by an environment
//! variable (taken as it is), an existing virtual environment in which the
//! import check succeeds, or that environment created with `python3 -m venv`
//! and the packages installed by pip (its output in a log file).

use std::path::{Path, PathBuf};
use std::process::Command;

/// What [`python_with`] needs.
#[derive(Clone, Debug)]
pub struct PythonSpec<'a> {
    /// An environment variable that, when set, names the interpreter to use
    /// (no check, no install), e.g. `MICROFREP_PORESPY_PYTHON`.
    pub override_var: &'a str,
    /// The virtual environment to use or create, e.g. `target/porespy-venv`.
    pub venv: &'a Path,
    /// Python statements that succeed only when the packages are usable,
    /// e.g. `import porespy`.
    pub check: &'a str,
    /// The pip requirements to install, e.g. `["porespy"]`.
    pub packages: &'a [&'a str],
    /// Where pip's output goes (the file is replaced).
    pub log: &'a Path,
}

/// The interpreter described by `spec`, or why there is none (the venv or
/// the install failed, or the import check still fails afterwards; the
/// message names the log).
pub fn python_with(spec: &PythonSpec) -> Result<PathBuf, String> {
    if let Ok(p) = std::env::var(spec.override_var) {
        return Ok(PathBuf::from(p));
    }
    let py = spec.venv.join("bin/python");
    let usable = |py: &Path| {
        Command::new(py)
            .args(["-c", spec.check])
            .output()
            .is_ok_and(|o| o.status.success())
    };
    if usable(&py) {
        return Ok(py);
    }
    eprintln!(
        "installing {} into {} (log: {})",
        spec.packages.join(" "),
        spec.venv.display(),
        spec.log.display()
    );
    let log =
        std::fs::File::create(spec.log).map_err(|e| format!("{}: {e}", spec.log.display()))?;
    let log2 = log.try_clone().map_err(|e| e.to_string())?;
    let venv_ok = Command::new("python3")
        .args(["-m", "venv"])
        .arg(spec.venv)
        .stdout(log.try_clone().map_err(|e| e.to_string())?)
        .stderr(log2)
        .status()
        .is_ok_and(|s| s.success());
    let pip_ok = venv_ok
        && Command::new(&py)
            .args(["-m", "pip", "install", "--quiet"])
            .args(spec.packages)
            .stdout(log.try_clone().map_err(|e| e.to_string())?)
            .stderr(log)
            .status()
            .is_ok_and(|s| s.success());
    if pip_ok && usable(&py) {
        Ok(py)
    } else {
        Err(format!(
            "python3 -m venv {} / pip install {} failed (see {})",
            spec.venv.display(),
            spec.packages.join(" "),
            spec.log.display()
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_override_is_taken_as_it_is() {
        let var = "MICROFREP_PYVENV_TEST_OVERRIDE";
        std::env::set_var(var, "/no/such/python");
        let spec = PythonSpec {
            override_var: var,
            venv: Path::new("/no/such/venv"),
            check: "import sys",
            packages: &[],
            log: Path::new("/no/such/log"),
        };
        assert_eq!(
            python_with(&spec).unwrap(),
            PathBuf::from("/no/such/python")
        );
        std::env::remove_var(var);
        // Without it, an unwritable log is reported, not a panic.
        let e = python_with(&spec).unwrap_err();
        assert!(e.contains("/no/such/log"), "{e}");
    }
}
