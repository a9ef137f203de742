//! Parser against the corpus and the reference interpreter's parse errors.

use microfrep_hyperfun::{parse, parse_with, Options};
use std::path::Path;

/// The vendored reference data (a copy of the shared HyperFun folder).
const SHARED: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/testdata");

/// Fields of one CSV record; handles quoted fields with `""` and newlines.
fn csv_records(text: &str) -> Vec<Vec<String>> {
    let (mut rows, mut row, mut field) = (Vec::new(), Vec::new(), String::new());
    let mut chars = text.chars().peekable();
    let mut quoted = false;
    while let Some(c) = chars.next() {
        match (quoted, c) {
            (true, '"') if chars.peek() == Some(&'"') => {
                chars.next();
                field.push('"');
            }
            (true, '"') => quoted = false,
            (true, c) => field.push(c),
            (false, '"') => quoted = true,
            (false, ',') => row.push(std::mem::take(&mut field)),
            (false, '\n') => {
                row.push(std::mem::take(&mut field));
                rows.push(std::mem::take(&mut row));
            }
            (false, c) => field.push(c),
        }
    }
    rows
}

fn probes() -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(Path::new(SHARED).join("reference/probes.csv"))
        .expect("testdata/reference/probes.csv");
    csv_records(&text).into_iter().skip(1).collect()
}

#[test]
fn corpus_files_all_parse() {
    let dir = std::fs::read_dir(Path::new(SHARED).join("corpus")).expect("testdata/corpus");
    let mut n = 0;
    for e in dir {
        let path = e.unwrap().path();
        if path.extension().is_some_and(|x| x == "hf") {
            let src = std::fs::read_to_string(&path).unwrap();
            let file = path.display().to_string();
            let p = parse(&src, &file).unwrap_or_else(|d| panic!("{}", d.render(&src)));
            assert!(!p.objects.is_empty());
            n += 1;
        }
    }
    assert!(n >= 20, "only {n} corpus files");
}

/// Every probe the reference rejects at parse time is rejected here with
/// the same message, line and column (CR rejected as the reference does);
/// every other probe parses.
#[test]
fn probes_match_reference_parse_errors() {
    let rows = probes();
    let strict = Options { accept_cr: false };
    let (mut checked, mut bad) = (0, Vec::new());
    for r in &rows {
        let (name, program, status, message) = (&r[0], &r[1], &r[6], &r[7]);
        let got = parse_with(program, name, strict);
        if status == "PARSE_ERROR" {
            let d = got.err().unwrap_or_else(|| panic!("{name}: accepted"));
            // The reference's text, then (after ": ") what is wrong in plain words.
            let text = d.message.split(": ").next().unwrap_or("");
            let mine = format!("line={} pos={} msg={text}", d.pos.line, d.pos.col);
            if &mine != message {
                bad.push(format!("{name}: {mine} (reference: {message})"));
            }
            checked += 1;
        } else if let Err(d) = got {
            bad.push(d.render(program));
        }
    }
    bad.dedup();
    assert!(bad.is_empty(), "{}", bad.join("\n"));
    assert!(checked >= 20, "{checked}");
}

#[test]
fn crlf_is_accepted_with_a_warning_by_default() {
    let src = "my_model(x[3], a[1])\r\n{\r\n  my_model = x[1];\r\n}\r\n";
    let (p, w) = parse_with(src, "m.hf", Options::default()).unwrap();
    assert_eq!(p.objects[0].name, "my_model");
    assert_eq!(w.items.len(), 1);
    assert!(w.render(src).contains("m.hf:1:21: warning"));
}

/// Probes whose model is one literal: the parsed value equals the
/// reference output bit for bit (the non-correctly-rounded procedure).
#[test]
fn literal_values_match_reference_bits() {
    let rows = probes();
    let mut checked = 0;
    for r in rows
        .iter()
        .filter(|r| r[0].starts_with("num_") && r[6] == "OK")
    {
        let p = parse(&r[1], &r[0]).unwrap();
        if let microfrep_hyperfun::ast::ExprKind::Num(v) = p.objects[0].result.kind {
            let want: f64 = r[5].parse().unwrap();
            assert_eq!(v.to_bits(), want.to_bits(), "{}: {v:e} vs {want:e}", r[0]);
            checked += 1;
        }
    }
    assert!(checked >= 15, "{checked}");
}
