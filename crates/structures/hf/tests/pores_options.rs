//! The paper's controls from HyperFun source: `mfPoresOpt` and
//! `mfPores2Opt` with their options array `[irregularity, parent_scale,
//! subdivision, weight, size_measure, opening]`.
mod common;
use common::*;
use microfrep_core::{Expr, ExprNode};

/// The pore count in the name of the pore field of a model.
fn pore_count(e: &Expr) -> usize {
    let mut stack = vec![e.clone()];
    while let Some(e) = stack.pop() {
        if let ExprNode::Field { field, .. } = e.node() {
            let name = field.name();
            return name
                .split(", ")
                .nth(1)
                .and_then(|s| s.strip_suffix(" pores"))
                .and_then(|n| n.parse().ok())
                .unwrap_or_else(|| panic!("{name}"));
        }
        stack.extend(e.children().into_iter().cloned());
    }
    panic!("no pore field in the model")
}

/// A 2 x 2 x 0.25 plate of 4 x 4 cells with `call` (its `o` is the
/// options array `opts`).
fn plate(call: &str, opts: &str) -> Probe {
    let n = opts.split(',').count();
    let src = format!(
        "my_model(x[3], a[1]) {{ array v[3]; array o[{n}]; v = [0, 0, 0]; o = [{opts}]; \
         b = hfBlock(x, v, 2, 2, 0.25); my_model = {call}; }}"
    );
    Probe::new(&load_src(&src, "plate.hf", None))
}

/// Pore share of the plate by a pixel count on an `n` x `n` grid.
fn pixel_porosity(p: &Probe, n: usize) -> f64 {
    let pts: Vec<[f64; 3]> = (0..n * n)
        .map(|k| {
            [
                ((k % n) as f64 + 0.5) / n as f64 * 2.0,
                ((k / n) as f64 + 0.5) / n as f64 * 2.0,
                0.125,
            ]
        })
        .collect();
    1.0 - fraction(p, &pts)
}

/// Spread (standard deviation) of the pore share of the four quarters of
/// every cell: 0 for identical regular pores (symmetric under a quarter
/// turn), larger the more irregular the pores.
fn quarter_spread(p: &Probe) -> f64 {
    let mut shares = Vec::new();
    for cell in 0..16 {
        let (ci, cj) = ((cell % 4) as f64 * 0.5, (cell / 4) as f64 * 0.5);
        for quarter in 0..4 {
            let (qi, qj) = ((quarter % 2) as f64 * 0.25, (quarter / 2) as f64 * 0.25);
            let m = 40;
            let pts: Vec<[f64; 3]> = (0..m * m)
                .map(|k| {
                    [
                        ci + qi + ((k % m) as f64 + 0.5) / m as f64 * 0.25,
                        cj + qj + ((k / m) as f64 + 0.5) / m as f64 * 0.25,
                        0.125,
                    ]
                })
                .collect();
            shares.push(1.0 - fraction(p, &pts));
        }
    }
    let mean = shares.iter().sum::<f64>() / shares.len() as f64;
    (shares.iter().map(|s| (s - mean).powi(2)).sum::<f64>() / shares.len() as f64).sqrt()
}

#[test]
fn irregularity_changes_the_pores() {
    let call = "mfPores2Opt(x, b, 0.5, 0.6, 3, o)";
    let regular = quarter_spread(&plate(call, "0"));
    let default = quarter_spread(&plate(call, "0.15"));
    let wild = quarter_spread(&plate(call, "0.4"));
    println!("quarter spread: irregularity 0 {regular:.4}, 0.15 {default:.4}, 0.4 {wild:.4}");
    assert!(regular < 2e-3, "{regular}");
    assert!(default > 0.02 && wild > default + 0.02, "{default} {wild}");
    // The default irregularity is mfPores2's (to rounding: the source's
    // 0.15 need not be the same double as the library's default).
    let plain = plate("mfPores2(x, b, 0.5, 0.6, 3)", "0");
    let same = plate(call, "0.15");
    for q in points([0.0; 3], [2.0, 2.0, 0.25], 400) {
        assert!((plain.at(q) - same.at(q)).abs() < 1e-12, "{q:?}");
    }
}

#[test]
fn weighted_pores_change_shape_and_meet_their_porosity() {
    // Regular pores with corner weight cos 45: circles of area 0.6 of the
    // cell.
    let circles = plate(
        "mfPores2Opt(x, b, 0.5, 0.6, 1, o)",
        "0, 1, 0, 0.70710678118654752",
    );
    let r = (0.6 * 0.25 / std::f64::consts::PI).sqrt();
    for cell in 0..16 {
        let c = [
            (cell % 4) as f64 * 0.5 + 0.25,
            (cell / 4) as f64 * 0.5 + 0.25,
        ];
        for k in 0..12 {
            let a = k as f64 * std::f64::consts::PI / 6.0 + 0.1;
            let at = |s: f64| [c[0] + s * r * a.cos(), c[1] + s * r * a.sin(), 0.125];
            assert!(!circles.inside(at(0.999)) && circles.inside(at(1.001)));
        }
    }
    let unweighted = plate("mfPores2Opt(x, b, 0.5, 0.6, 1, o)", "0, 1, 0, 1");
    // The weight-1 pore is no circle: it reaches further along the
    // diagonals of its rotated control square than along the axes.
    let differ = points([0.0; 3], [2.0, 2.0, 0.25], 4000)
        .into_iter()
        .filter(|&q| circles.inside(q) != unweighted.inside(q))
        .count();
    assert!(differ > 40, "{differ}");
    for (opts, target) in [
        ("0, 1, 0, 0.70710678118654752", 0.6),
        ("0.15, 1, 0, 0.5", 0.45),
        ("0.15, 1, 0, 1.6", 0.7),
        ("0.2, 1.2, 1, 2.5", 0.9),
    ] {
        let p = plate(&format!("mfPores2Opt(x, b, 0.5, {target}, 2, o)"), opts);
        let por = pixel_porosity(&p, 1200);
        println!("mfPores2Opt [{opts}], target {target}: pixel count {por:.5}");
        assert!((por - target).abs() < 1e-3 * target, "[{opts}]: {por}");
    }
}

#[test]
fn opened_3d_pores_and_size_per_pore() {
    let cube = |call: &str, opts: &str| {
        let n = opts.split(',').count();
        let src = format!(
            "my_model(x[3], a[1]) {{ array v[3]; array o[{n}]; v = [0, 0, 0]; o = [{opts}]; \
             b = hfBlock(x, v, 1, 1, 1); my_model = {call}; }}"
        );
        load_src(&src, "cube.hf", None)
    };
    // At 0.55 the default pores open into every face between cells; with
    // opening 0 (the plain Doo-Sabin pores) they are closed.
    let open = Probe::new(&cube("mfPoresOpt(x, b, 0.5, 0.55, 1, o)", "0.15"));
    let closed = Probe::new(&cube(
        "mfPoresOpt(x, b, 0.5, 0.55, 1, o)",
        "0.15, 1.6, 0, 1, 0, 0",
    ));
    for a in 0..3 {
        for i in 0..2 {
            for j in 0..2 {
                let mut q = [0.0; 3];
                q[(a + 1) % 3] = 0.25 + 0.5 * i as f64;
                q[(a + 2) % 3] = 0.25 + 0.5 * j as f64;
                q[a] = 0.5;
                assert!(!open.inside(q), "{q:?}");
                assert!(closed.inside(q), "{q:?}");
            }
        }
    }
    // Pore size as the volume per pore: 1 / 64 of the cube, 64 pores, as
    // an edge of 1/4; a T-mesh.
    let m = cube("mfPoresOpt(x, b, 1 / 64, 0.6, 1, o)", "0.15, 1.6, 0, 1, 1");
    assert_eq!(pore_count(&m.value), 64);
    let m = cube("mfPoresOpt(x, b, 0.3, 0.6, 1, o)", "0.15, 1.6, 1");
    assert_eq!(pore_count(&m.value), 64);
    let m = cube("mfPores2Opt(x, b, 1 / 16, 0.6, 1, o)", "0.15, 1, 0, 1, 1");
    assert_eq!(pore_count(&m.value), 16);
}

/// The load error of a model over the unit block.
fn load_error(opts: &str, call: &str) -> String {
    load_error_after(opts, "", call)
}

/// As [`load_error`], with statements `pre` after the options are set.
fn load_error_after(opts: &str, pre: &str, call: &str) -> String {
    microfrep_structures_hf::install();
    let n = opts.split(',').count();
    let src = format!(
        "my_model(x[3], a[1]) {{\n  array v[3];\n  array o[{n}];\n  v = [0, 0, 0];\n  o = [{opts}];\n  {pre}\n  b = hfBlock(x, v, 1, 1, 1);\n  my_model = {call};\n}}\n"
    );
    match microfrep_hyperfun::load(&src, "bad.hf", None) {
        Ok(_) => panic!("{opts}: loaded"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn bad_options_are_load_errors_naming_the_element() {
    let p3 = "mfPoresOpt(x, b, 0.5, 0.7, 1, o)";
    let p2 = "mfPores2Opt(x, b, 0.5, 0.6, 1, o)";
    for (opts, call, want) in [
        ("0.7", p3, "opts[1] (irregularity) = 0.7"),
        ("0.15, 1.2", p3, "opts[2] (parent_scale) = 1.2"),
        ("0.15, 1.5", p2, "opts[2] (parent_scale) = 1.5"),
        ("0.15, 1.6, 2", p3, "opts[3] (subdivision) = 2"),
        ("0.15, 1, 0, 0", p2, "opts[4] (weight) = 0"),
        ("0.15, 1, 0, -2", p2, "opts[4] (weight) = -2"),
        ("0.15, 1.6, 0, 2", p3, "opts[4] (weight) = 2"),
        ("0.15, 1.6, 0, 1, 3", p3, "opts[5] (size_measure) = 3"),
        ("0.15, 1.6, 0, 1, 0, 0.5", p3, "opts[6] (opening) = 0.5"),
        ("0, 0, 0, 0, 0, 0, 0", p3, "1 to 6 numbers"),
    ] {
        let e = load_error(opts, call);
        assert!(e.contains(want), "[{opts}]: {e}");
    }
    let e = load_error_after("0, 1.6", "o[1] = x[1];", p3);
    assert!(
        e.contains("opts[1] (irregularity) must be a constant"),
        "{e}"
    );
}

/// Hand-set derived points after the six controls: three distances in 2D
/// keep the porosity (Eq. 8 gives the fourth; pixel count) and make every
/// pore the same shape (no spread between cells' quarters from the draw);
/// 24 t values in 3D load; a wrong count is a load error.
#[test]
fn hand_set_distances_and_t_from_hyperfun() {
    let call = "mfPores2Opt(x, b, 0.5, 0.6, 1, o)";
    let p = plate(call, "0.15, 1, 0, 1, 0, 0.05, 0.2, 0.15, 0.25");
    let por = pixel_porosity(&p, 800);
    assert!((por - 0.6).abs() < 0.003, "{por}");
    let drawn = plate(call, "0.15");
    assert!(
        (pixel_porosity(&drawn, 800) - 0.6).abs() < 0.003,
        "the drawn pores' porosity"
    );
    let t = vec!["0.4"; 24].join(", ");
    let src = format!(
        "my_model(x[3], a[1]) {{ array v[3]; array o[30]; v = [0, 0, 0]; \
         o = [0.15, 1.6, 0, 1, 0, 0.05, {t}]; b = hfBlock(x, v, 2, 2, 2); \
         my_model = mfPoresOpt(x, b, 1, 0.6, 1, o); }}"
    );
    let m = load_src(&src, "hand3.hf", None);
    assert_eq!(pore_count(&m.value), 8);
    let e = load_error("0.15, 1, 0, 1, 0, 0.05, 0.3, 0.3", call);
    assert!(e.contains("3 hand-set distances"), "{e}");
}
