//! `cleanup_all` (what the CLI's signal handler calls) removes every
//! temporary of the process, files and directories; alone in its binary so
//! no other test's temporaries are swept away.

use microfrep_io::atomic::{cleanup_all, live_temporaries, AtomicDir, AtomicFile};
use std::io::Write;

#[test]
fn cleanup_removes_every_temporary() {
    let d = std::env::temp_dir().join(format!("mf-io-cleanup-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    let mut f = AtomicFile::create(&d.join("a.stl")).unwrap();
    f.write_all(&[7; 5000]).unwrap();
    f.flush().unwrap();
    let s = f.scratch_path();
    std::fs::write(&s, b"scratch").unwrap();
    let dir = AtomicDir::create(&d.join("stack")).unwrap();
    dir.write("layer_00000.png", b"png").unwrap();
    assert_eq!(live_temporaries(), 3);
    assert_eq!(std::fs::read_dir(&d).unwrap().count(), 3);
    cleanup_all();
    assert_eq!(live_temporaries(), 0);
    assert_eq!(std::fs::read_dir(&d).unwrap().count(), 0);
    // The writers still drop cleanly afterwards.
    drop(f);
    drop(dir);
    assert_eq!(std::fs::read_dir(&d).unwrap().count(), 0);
    std::fs::remove_dir_all(&d).unwrap();
}
