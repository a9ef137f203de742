//! Library calls with wrong arguments are load-time errors with the
//! argument's position, never NaN or values read past an array's end.

use microfrep_hyperfun::library::shapes::{display_name, rules, Len};
use microfrep_hyperfun::library::{Kind, Registry};
use microfrep_hyperfun::load;

/// Lengths that satisfy every rule of a call (`None` for real arguments).
/// With `fixed = Some((k, n))`, argument `k` has `n` elements and the
/// others follow it.
fn valid_lengths(name: &str, kinds: &[Kind], fixed: Option<(usize, usize)>) -> Vec<Option<usize>> {
    let rules = rules(name).unwrap_or_else(|| panic!("{name} has no argument rules"));
    let rule = |k: usize| rules.get(k).copied().flatten().unwrap_or(Len::Any);
    let mut lens: Vec<Option<usize>> = vec![None; kinds.len()];
    // Lengths that depend on others settle in a few rounds.
    for _ in 0..kinds.len() + 1 {
        for k in 0..kinds.len() {
            if kinds[k] != Kind::A {
                continue;
            }
            if let Some((j, n)) = fixed.filter(|f| f.0 == k) {
                lens[j] = Some(n);
                continue;
            }
            let len = |j: usize| lens[j].unwrap_or(2);
            lens[k] = Some(match rule(k) {
                Len::Point => 3,
                // hfBezierVolume's control values: l*m*n with l = m = n = 1.
                Len::Any if name == "hfbeziervolume" => 1,
                Len::Any => 2,
                Len::Exactly(n) | Len::AtLeast(n) => n,
                Len::MultipleOf(m) => 2 * m,
                Len::Times(j, m) => m * len(j),
                Len::TimesPlus(j, m, c) => m * (len(j) + c),
                Len::AtLeastLen(j) => len(j),
                Len::AtLeastProduct(a, b, d) => (len(a) * len(b).saturating_sub(d)).max(1),
                Len::Groups(j, g) => len(j) * g,
            });
        }
    }
    lens
}

/// A model calling `name` with arrays of the given lengths (all elements
/// 1, reals 1), and the column of each argument.
fn model(name: &str, lens: &[Option<usize>]) -> (String, Vec<u32>) {
    let mut decls = Vec::new();
    let mut fills = String::new();
    for (k, len) in lens.iter().enumerate() {
        if let Some(n) = len {
            decls.push(format!("q{k}[{n}]"));
            fills += &format!("q{k} = [{}]; ", vec!["1"; *n].join(", "));
        }
    }
    let arrays = if decls.is_empty() {
        String::new()
    } else {
        format!("array {}; ", decls.join(", "))
    };
    let mut src = format!("my_model(x[3], a[1]) {{ {arrays}{fills}my_model = {name}(");
    let mut cols = Vec::new();
    for (k, len) in lens.iter().enumerate() {
        if k > 0 {
            src += ", ";
        }
        cols.push(src.len() as u32 + 1);
        src += &match len {
            Some(_) => format!("q{k}"),
            None => "1".into(),
        };
    }
    src += "); }";
    (src, cols)
}

/// Every reference library function: the call with valid lengths loads;
/// each array argument with a length rule, given a wrong length, is an
/// error naming the function and the argument, at the argument.
#[test]
fn every_library_function_rejects_wrong_array_lengths() {
    let registry = Registry::reference();
    let (mut checked, mut failures) = (0, Vec::new());
    for name in registry.names() {
        let f = registry.get(name).unwrap();
        let good = valid_lengths(name, f.kinds, None);
        let (src, _) = model(name, &good);
        if let Err(d) = load(&src, "t.hf", None) {
            failures.push(format!("{name}: valid call rejected: {d}\n  {src}"));
            continue;
        }
        let rules = rules(name).unwrap();
        for (k, rule) in rules.iter().enumerate() {
            let Some(rule) = rule else { continue };
            let n = good[k].unwrap();
            let bad = match rule {
                Len::Point | Len::Any => continue,
                Len::AtLeast(_) | Len::AtLeastLen(_) | Len::AtLeastProduct(..) if n <= 1 => {
                    continue
                }
                Len::AtLeast(_) | Len::AtLeastLen(_) | Len::AtLeastProduct(..) => n - 1,
                _ => n + 1,
            };
            let lens = valid_lengths(name, f.kinds, Some((k, bad)));
            let (src, cols) = model(name, &lens);
            checked += 1;
            match load(&src, "t.hf", None) {
                Ok(_) => failures.push(format!("{name}: argument {} of {bad} accepted", k + 1)),
                Err(d) => {
                    let want = format!(
                        "{}: argument {} ('q{k}') has {bad} element",
                        display_name(name),
                        k + 1
                    );
                    if !d.message.starts_with(&want) || (d.pos.line, d.pos.col) != (1, cols[k]) {
                        failures.push(format!("{name}: got '{d}', want '{want}' at 1:{}", cols[k]));
                    }
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(checked >= 50, "only {checked} checks");
}

#[test]
fn every_reference_function_has_rules_and_a_documented_name() {
    for name in Registry::reference().names() {
        assert!(rules(name).is_some(), "{name}");
        assert_ne!(
            display_name(name),
            name,
            "{name} has no documented spelling"
        );
        assert!(display_name(name).eq_ignore_ascii_case(name));
    }
}

fn load_err(src: &str) -> String {
    match load(src, "t.hf", None) {
        Ok(_) => panic!("loads: {src}"),
        Err(d) => d.to_string(),
    }
}

#[test]
fn short_centre_array_is_an_error_not_nan() {
    let src = "my_model(x[3], a[1]) { array c[2]; c = [0, 0]; my_model = hfSphere(x, c, 1); }";
    assert_eq!(
        load_err(src),
        "t.hf:1:71: hfSphere: argument 2 ('c') has 2 elements; it must have 3 elements"
    );
    // In a branch no point takes, and in a called object, too.
    let src = "o(x[3], a[1]) { array c[4]; c = [0, 0, 0, 0]; o = hfSphere(x, c, 1); }\n\
               my_model(x[3], a[1]) { my_model = o(x, a); }";
    let e = load_err(src);
    assert!(
        e.starts_with("t.hf:1:63: hfSphere: argument 2 ('c') has 4"),
        "{e}"
    );
    let src = "my_model(x[3], a[1]) { array c[2]; c = [0, 0]; t = 0;\n\
               if x[1] > 1e9 then t = hfSphere(x, c, 1); endif; my_model = t; }";
    let e = load_err(src);
    assert!(e.starts_with("t.hf:2:36: hfSphere"), "{e}");
    // The point array keeps the reference's sentinel.
    let src = "my_model(x[2], a[1]) { array c[3]; c = [0, 0, 0]; my_model = hfSphere(x, c, 1); }";
    let m = load(src, "t.hf", None).unwrap();
    assert_eq!(m.eval_points(&[[0.0; 3]])[0], Ok(-1111111111111.0));
}

#[test]
fn constant_arguments_are_checked() {
    // hfBezierVolume: control counts 1..=20 and l*m*n control values.
    let bez = |counts: &str, w: usize| {
        format!(
            "my_model(x[3], a[1]) {{ array b[6], w[{w}]; b = [0, 0, 0, 1, 1, 1]; w = [{}]; \
             my_model = hfBezierVolume(x, {counts}, b, w); }}",
            vec!["1"; w].join(", ")
        )
    };
    if let Err(d) = load(&bez("2, 2, 2", 8), "t.hf", None) {
        panic!("{d}");
    }
    let e = load_err(&bez("2, 2, 2", 7));
    assert!(e.contains("hfBezierVolume: argument 6 (the control values) has 7 elements; it must have l*m*n = 8"), "{e}");
    let e = load_err(&bez("25, 1, 1", 25));
    assert!(
        e.contains("hfBezierVolume: the control count l (argument 2) is 25"),
        "{e}"
    );
    // hfConvMesh: triangle vertex indices name vertices.
    let mesh = |tri: &str| {
        format!(
            "my_model(x[3], a[1]) {{ array v[9], t[3], w[1]; v = [0, 0, 0, 1, 0, 0, 0, 1, 0]; \
             t = [{tri}]; w = [1]; my_model = hfConvMesh(x, v, t, w, 0.5); }}"
        )
    };
    assert!(load(&mesh("1, 2, 3"), "t.hf", None).is_ok());
    let e = load_err(&mesh("1, 2, 4"));
    assert!(e.contains("hfConvMesh: element 3 of argument 3 (the triangles) is 4, not a vertex index from 1 to 3"), "{e}");
    // hfSawtooth: a bounded number of terms.
    let e = load_err("my_model(x[3], a[1]) { my_model = hfSawtooth(x[1], 1e9, 1, 1); }");
    assert!(
        e.contains("t.hf:1:35: hfSawtooth: the term count (argument 2) is 1000000000"),
        "{e}"
    );
}

/// A count only known per point (computed by a point-dependent loop) that
/// is invalid there is a run-time error at the call, not a silent NaN.
#[test]
fn invalid_constants_met_per_point_are_run_time_errors() {
    let src = "my_model(x[3], a[1]) { n = 0; while n < x[1] loop n = n + 1; endloop;\n\
               my_model = hfSawtooth(x[2], n * 1e9, 1, 1); }";
    let m = load(src, "t.hf", None).unwrap();
    assert!(!m.lowered);
    let r = m.eval_points(&[[0.5, 0.0, 0.0], [-1.0, 0.0, 0.0]]);
    let e = r[0].clone().unwrap_err();
    assert!(e.message.starts_with("hfSawtooth: the term count"), "{e}");
    assert_eq!((e.line, e.col), (2, 12));
    // n = 0 there: no terms, value 0.
    assert_eq!(r[1], Ok(0.0));
}
