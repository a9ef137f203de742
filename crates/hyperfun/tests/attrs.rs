//! Attribute helpers `hfA_*` (LIBRARY.md section 7) that the reference
//! probes do not cover: each checked against its closed form through a
//! whole model, so the array writes are exercised too.

use microfrep_hyperfun::load;

/// Value of `body` (statements plus `my_model = ...;`) at `p`.
fn at(body: &str, p: [f64; 3]) -> f64 {
    let src = format!("my_model(x[3], a[1]) {{ {body} }}");
    let m = load(&src, "attrs.hf", None).unwrap_or_else(|e| panic!("{e}"));
    m.eval_points(&[p])[0]
        .clone()
        .unwrap_or_else(|e| panic!("{body}: {e}"))
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * b.abs().max(1.0)
}

#[test]
fn set_color_and_set_attributes_write_only_inside() {
    let b = "array o[3]; o = [9, 9, 9]; r = hfA_SetColor(x[1], o, 1, 2, 3); \
             my_model = 100*o[1] + 10*o[2] + o[3] + 1000*r;";
    assert_eq!(at(b, [0.5, 0.0, 0.0]), 1123.0);
    assert_eq!(at(b, [-0.5, 0.0, 0.0]), 1999.0);
    let b = "array o[3], s1[2]; o = [9, 9, 9]; s1 = [1, 2]; \
             r = hfA_SetAttributes(x[1], o, s1); my_model = 100*o[1] + 10*o[2] + o[3];";
    assert_eq!(at(b, [0.0, 0.0, 0.0]), 129.0);
    assert_eq!(at(b, [-1.0, 0.0, 0.0]), 999.0);
}

#[test]
fn lerp_and_cerp_interpolate_and_clamp_and_return_the_parameter() {
    for f in ["hfA_Lerp", "hfA_Cerp"] {
        let b = format!(
            "array o[2], s1[2], s2[2]; o = [0, 0]; s1 = [0, 10]; s2 = [4, 20]; \
             u = {f}(o, s1, s2, x[1], 1, 3); my_model = 1000*u + 10*o[1] + o[2];"
        );
        // u = (2 - 1)/(3 - 1) = 0.5: o = (2, 15).
        assert!(close(at(&b, [2.0, 0.0, 0.0]), 500.0 + 20.0 + 15.0));
        // Below and above: the end arrays; u is returned unclamped.
        assert!(close(at(&b, [0.0, 0.0, 0.0]), -500.0 + 10.0));
        assert!(close(at(&b, [5.0, 0.0, 0.0]), 2000.0 + 40.0 + 20.0));
    }
}

#[test]
fn lookup_tables_pick_or_blend_attribute_groups() {
    let setup = "array o[2], at[6], mp[3]; o = [0, 0]; at = [1, 2, 3, 4, 5, 6]; mp = [0, 1, 2];";
    let plain = format!("{setup} r = hfA_LookUpTable(x[1], o, at, mp); my_model = 10*o[1] + o[2];");
    // Below the first entry the reference ends up with the last group (its
    // "no interval matched" fallback overwrites the first group it copied).
    assert_eq!(at(&plain, [-1.0, 0.0, 0.0]), 56.0);
    assert_eq!(at(&plain, [0.5, 0.0, 0.0]), 12.0); // [0, 1): group 1
    assert_eq!(at(&plain, [1.5, 0.0, 0.0]), 34.0); // [1, 2): group 2
    assert_eq!(at(&plain, [7.0, 0.0, 0.0]), 56.0); // beyond: the last group
    let smooth =
        format!("{setup} r = hfA_SmoothLookUpTable(x[1], o, at, mp); my_model = 10*o[1] + o[2];");
    // Halfway through [1, 2): halfway between groups 2 and 3.
    assert!(close(at(&smooth, [1.5, 0.0, 0.0]), 10.0 * 4.0 + 5.0));
    assert!(close(at(&smooth, [0.25, 0.0, 0.0]), 10.0 * 1.5 + 2.5));
}

#[test]
fn spline_passes_through_inner_knots_and_clamps_outside() {
    // Knots 0, 1, 4, 9, 16 (one value per group): spans = 5 - 3 = 2.
    let b = "array o[1], k[5]; o = [0]; k = [0, 1, 4, 9, 16]; \
             r = hfA_Spline(o, k, x[1], 0, 1); my_model = o[1];";
    // Catmull-Rom interpolates its second and third control values.
    assert!(close(at(b, [0.0, 0.0, 0.0]), 1.0));
    assert!(close(at(b, [0.5, 0.0, 0.0]), 4.0));
    // On span 0 at u = 0.5 the curve through 0, 1, 4, 9 gives 2.25 (x^2 at 1.5).
    assert!(close(at(b, [0.25, 0.0, 0.0]), 2.25));
    assert_eq!(at(b, [-1.0, 0.0, 0.0]), 0.0);
    assert_eq!(at(b, [2.0, 0.0, 0.0]), 16.0);
}

#[test]
fn checker_board_colours_block_and_gap() {
    let b = "array sz[3], gp[3], o[1], cb[1], cg[1]; sz = [1, 1, 1]; gp = [1, 1, 1]; \
             o = [0]; cb = [7]; cg = [3]; \
             r = hfA_CheckerBoard(x, sz, gp, o, cb, cg); my_model = o[1];";
    assert_eq!(at(b, [0.5, 0.5, 0.5]), 7.0);
    assert_eq!(at(b, [2.5, -1.5, 4.5]), 7.0);
    assert_eq!(at(b, [1.5, 0.5, 0.5]), 3.0);
    assert_eq!(at(b, [0.5, 0.5, -0.5]), 3.0);
}

#[test]
fn rgb_hsv_round_trip_and_known_hues() {
    let to_hsv = |r: f64, g: f64, b: f64| -> [f64; 3] {
        let body = |k: usize| {
            format!(
                "array c[3], h[3]; c = [{r}, {g}, {b}]; h = [0, 0, 0]; \
                 t = hfA_RGBToHSV(c, h); my_model = h[{k}];"
            )
        };
        [1, 2, 3].map(|k| at(&body(k), [0.0; 3]))
    };
    assert_eq!(to_hsv(1.0, 0.0, 0.0), [0.0, 1.0, 1.0]);
    assert_eq!(to_hsv(0.0, 0.5, 0.0), [120.0, 1.0, 0.5]);
    assert_eq!(to_hsv(0.0, 0.0, 1.0), [240.0, 1.0, 1.0]);
    assert_eq!(to_hsv(0.5, 0.5, 0.5), [0.0, 0.0, 0.5]);
    // The hue wheel: yellow at 60 degrees, a hue of -300 wraps to 60.
    for h in ["60", "-300", "420"] {
        let body = |k: usize| {
            format!(
                "array c[3], o[3]; c = [{h}, 1, 1]; o = [0, 0, 0]; \
                 t = hfA_HSVToRGB(c, o); my_model = o[{k}];"
            )
        };
        let rgb = [1, 2, 3].map(|k| at(&body(k), [0.0; 3]));
        assert_eq!(rgb, [1.0, 1.0, 0.0], "hue {h}");
    }
    // Point-dependent hue (symbolic wrap): x[1] = -300 gives yellow too.
    let b = "array c[3], o[3]; c = [0, 1, 1]; o = [0, 0, 0]; c[1] = x[1]; \
             t = hfA_HSVToRGB(c, o); my_model = 100*o[1] + 10*o[2] + o[3];";
    assert!(close(at(b, [-300.0, 0.0, 0.0]), 110.0));
    assert!(close(at(b, [180.0, 0.0, 0.0]), 11.0));
}

#[test]
fn noise_helpers_stay_in_their_ranges() {
    let g = "my_model = hfA_NoiseG(x, 2, 0.7);";
    let p = "my_model = hfA_NoiseP(x);";
    let t = "my_model = hfA_Turbulence(x, 4);";
    for i in 0..50 {
        let q = [
            0.37 * i as f64 - 7.0,
            0.11 * i as f64,
            1.3 - 0.05 * i as f64,
        ];
        let v = at(g, q);
        assert!((0.0..=1.0).contains(&v), "{v}");
        assert!(at(p, q).abs() <= 2.0);
        // Octaves f = 4, 2, 1: each term |2 n - 1| / f with |n| <= 2.
        let tv = at(t, q);
        assert!((0.0..=5.0 * (0.25 + 0.5 + 1.0)).contains(&tv), "{tv}");
    }
    // Gradient noise is 0 on the integer lattice: |2*0 - 1| summed.
    assert!(close(at(t, [3.0, -2.0, 5.0]), 0.25 + 0.5 + 1.0));
    assert_eq!(at(p, [1.0, 2.0, 3.0]), 0.0);
}

#[test]
fn circles_and_crackles_pick_table_groups() {
    // |p| = 2.25 -> fmod 0.25 lies in [0, 0.5): group 1.
    let b = "array o[1], at[4], mp[3]; o = [0]; at = [5, 6, 0, 0]; mp = [0, 0.5, 1]; \
             r = hfA_Circles(x, o, at, mp); my_model = o[1] + 100*at[4];";
    // at[4] (0-based index = table length) is overwritten with 1.1.
    assert!(close(at(b, [2.25, 0.0, 0.0]), 5.0 + 110.0));
    assert!(close(at(b, [0.0, 1.75, 0.0]), 6.0 + 110.0));
    // Crackles: a value in [0, 1] (the cycle of a sine), so with the table
    // [0, 2) every point takes group 1.
    let b = "array o[1], at[2], mp[2]; o = [0]; at = [4, 0]; mp = [0, 2]; \
             r = hfA_Crackles(x, o, 1.5, at, mp); my_model = o[1];";
    for q in [[0.3, 0.4, 0.5], [-2.0, 1.0, 7.5]] {
        assert_eq!(at(b, q), 4.0);
    }
}

#[test]
fn hf_r_is_zero_outside_r() {
    assert_eq!(at("my_model = hfR(x, 1) + 2;", [1.0, 2.0, 3.0]), 2.0);
}

/// Every `hf*` function named in LIBRARY.md sections 1-7 is callable
/// (section 8 lists the ones the reference does not expose).
#[test]
fn every_library_md_function_is_registered() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/testdata/LIBRARY.md");
    let text = std::fs::read_to_string(path).expect("testdata/LIBRARY.md");
    let text = text.split("## 8.").next().unwrap();
    let reg = microfrep_hyperfun::library::Registry::standard();
    let mut names: Vec<String> = text
        .split('`')
        .filter_map(|t| t.split_once('('))
        .map(|(n, _)| n.to_string())
        .filter(|n| n.starts_with("hf") && n.chars().all(|c| c.is_ascii_alphanumeric() || c == '_'))
        .collect();
    names.sort();
    names.dedup();
    assert!(names.len() >= 85, "{}", names.len());
    let missing: Vec<&String> = names.iter().filter(|n| reg.get(n).is_none()).collect();
    assert!(missing.is_empty(), "{missing:?}");
}

#[test]
fn distance_cone_and_cylinder_have_their_own_sentinels() {
    let two = |call: &str| {
        let src = format!(
            "my_model(x[2], a[1]) {{ array c[3], u[3]; c = [0, 0, 0]; u = [0, 0, 1]; my_model = {call}; }}"
        );
        let m = load(&src, "s.hf", None).unwrap();
        m.eval_points(&[[0.0; 3]])[0].clone().unwrap()
    };
    assert_eq!(two("hfDConeX(x, c, 0.5)"), -11111111111.0);
    assert_eq!(two("hfDConeZ(x, c, 0.5)"), -11111111111.0);
    assert_eq!(two("hfDCylinder(x, c, u, 1)"), -11111111111.1);
    assert_eq!(two("hfSphere(x, c, 1)"), -1111111111111.0);
}
