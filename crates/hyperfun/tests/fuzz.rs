//! The parser never panics or hangs on mutated corpus files.

use microfrep_hyperfun::{parse_with, Options};
use proptest::prelude::*;

fn corpus() -> Vec<Vec<u8>> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("testdata/corpus");
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .expect("testdata/corpus")
        .filter_map(|e| e.ok())
        .map(|e| e.path())
        .collect();
    files.sort();
    let mut out: Vec<Vec<u8>> = files
        .iter()
        .filter(|p| p.extension().is_some_and(|x| x == "hf"))
        .filter_map(|p| std::fs::read(p).ok())
        .collect();
    // A small model exercising arrays, conditions and operators.
    out.push(b"my_model(x[3], a[1]) { array v[2]; v = [1, -2]; if x[1] > 0 then y = v[1]; else y = 2; endif; my_model = hfSphere(x, v, y) | 0.5^2; }".to_vec());
    out
}

#[derive(Debug, Clone)]
enum Edit {
    Set(usize, u8),
    Delete(usize, usize),
    /// Copy `len` bytes from `from` of another file to `at`.
    Splice {
        other: usize,
        from: usize,
        len: usize,
        at: usize,
    },
}

fn edit() -> impl Strategy<Value = Edit> {
    let byte = prop_oneof![
        any::<u8>(),
        prop::sample::select(b"()[]{},;+-*/^|&\\@~=<>.e0123456789 \n\r\"xas".to_vec())
    ];
    prop_oneof![
        (any::<usize>(), byte).prop_map(|(i, b)| Edit::Set(i, b)),
        (any::<usize>(), 0usize..40).prop_map(|(i, n)| Edit::Delete(i, n)),
        (any::<usize>(), any::<usize>(), 0usize..200, any::<usize>()).prop_map(
            |(other, from, len, at)| Edit::Splice {
                other,
                from,
                len,
                at
            }
        ),
    ]
}

fn apply(files: &[Vec<u8>], base: usize, edits: &[Edit]) -> Vec<u8> {
    let mut s = files[base % files.len()].clone();
    for e in edits {
        let n = s.len().max(1);
        match *e {
            Edit::Set(i, b) if !s.is_empty() => s[i % n] = b,
            Edit::Set(..) => {}
            Edit::Delete(i, len) => {
                let i = i % n;
                let j = (i + len).min(s.len());
                s.drain(i.min(s.len())..j);
            }
            Edit::Splice {
                other,
                from,
                len,
                at,
            } => {
                let o = &files[other % files.len()];
                let from = from % o.len().max(1);
                let piece = o[from..(from + len).min(o.len())].to_vec();
                let at = at % (s.len() + 1);
                s.splice(at..at, piece);
            }
        }
    }
    s
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

    #[test]
    fn parser_never_panics(base in any::<usize>(), edits in prop::collection::vec(edit(), 1..8), cr in any::<bool>()) {
        let files = corpus();
        let bytes = apply(&files, base, &edits);
        let src = String::from_utf8_lossy(&bytes);
        match parse_with(&src, "fuzz.hf", Options { accept_cr: cr }) {
            Ok((p, _)) => prop_assert!(!p.objects.is_empty()),
            Err(d) => {
                prop_assert!(d.has_errors());
                // Every message points inside the text and renders.
                let lines = src.split('\n').count() as u32;
                for e in &d.items {
                    prop_assert!(e.pos.line >= 1 && e.pos.line <= lines && e.pos.col >= 1);
                }
                prop_assert!(!d.render(&src).is_empty());
            }
        }
    }
}
