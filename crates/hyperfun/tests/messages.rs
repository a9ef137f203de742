//! Diagnostics a user can act on: byte-order marks, long generated lines.

use microfrep_hyperfun::{load, parse};

#[test]
fn a_byte_order_mark_is_skipped() {
    let src = "\u{feff}my_model(x[3], a[1]) { my_model = x[1]; }";
    let p = parse(src, "bom.hf").unwrap();
    assert_eq!(p.objects[0].name, "my_model");
    let m = load(src, "bom.hf", None).unwrap();
    assert_eq!(m.eval_points(&[[2.0, 0.0, 0.0]])[0], Ok(2.0));
    // Columns count from after the mark, and the caret is under the error.
    let bad = "\u{feff}my_model(x[3], a[1]) { my_model = zz; }";
    let d = parse(bad, "bom.hf").unwrap_err();
    assert_eq!((d.pos.line, d.pos.col), (1, 35));
    let r = d.render(bad);
    let lines: Vec<&str> = r.lines().collect();
    assert_eq!(lines[1].find("zz"), lines[2].find('^'), "{r}");
}

#[test]
fn long_lines_are_cut_around_the_caret() {
    let terms = vec!["x[1]"; 40_000].join(" + ");
    let src = format!("my_model(x[3], a[1]) {{ my_model = {terms} + zz + {terms}; }}");
    assert!(src.len() > 200_000);
    let d = parse(&src, "long.hf").unwrap_err();
    let r = d.render(&src);
    assert!(r.len() < 600, "{} bytes", r.len());
    let lines: Vec<&str> = r.lines().collect();
    assert!(
        lines[1].starts_with("  ...") && lines[1].ends_with("..."),
        "{r}"
    );
    let caret = lines[2].find('^').unwrap();
    assert_eq!(&lines[1][caret..caret + 2], "zz", "{r}");
    // Short lines are shown whole; a position past the end does not panic.
    let short = "my_model(x[3], a[1]) { my_model = zz; }";
    let r = parse(short, "s.hf").unwrap_err().render(short);
    assert!(r.contains(&format!("  {short}\n")), "{r}");
    let truncated = "my_model(x[3], a[1]) { my_model = 1 +";
    assert!(!parse(truncated, "t.hf")
        .unwrap_err()
        .render(truncated)
        .is_empty());
}
