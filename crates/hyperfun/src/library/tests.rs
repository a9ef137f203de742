use super::*;

fn c(v: f64) -> Expr {
    Expr::constant(v)
}
fn arr(v: &[f64]) -> Arg {
    Arg::Array(v.iter().map(|&x| c(x)).collect())
}
fn call(name: &str, args: &[Arg]) -> Output {
    let r = Registry::standard();
    let f = r.get(name).expect("registered");
    assert_eq!(f.kinds.len(), args.len(), "{name} arity");
    (f.build)(args)
}
fn val(name: &str, args: &[Arg]) -> f64 {
    call(name, args)
        .value
        .as_const()
        .expect("constant arguments fold")
}

#[test]
fn sphere_is_r2_minus_distance2_and_checks_point_length() {
    let v = val(
        "hfSphere",
        &[arr(&[1.0, 2.0, 2.0]), arr(&[0.0; 3]), Arg::Real(c(4.0))],
    );
    assert_eq!(v, 16.0 - 9.0);
    let bad = val(
        "HFSPHERE",
        &[arr(&[1.0, 2.0]), arr(&[0.0; 3]), Arg::Real(c(4.0))],
    );
    assert_eq!(bad, SENTINEL);
}

#[test]
fn block_is_r0_intersection_of_slabs_with_sentinel_for_negative_edges() {
    let p = arr(&[0.5, 0.5, 0.5]);
    let v = val(
        "hfblock",
        &[
            p.clone(),
            arr(&[0.0; 3]),
            Arg::Real(c(1.0)),
            Arg::Real(c(1.0)),
            Arg::Real(c(1.0)),
        ],
    );
    let s = 0.25_f64;
    let g = s + s - (2.0 * s * s).sqrt();
    assert_eq!(v, g + s - (g * g + s * s).sqrt());
    let bad = val(
        "hfblock",
        &[
            p,
            arr(&[0.0; 3]),
            Arg::Real(c(-1.0)),
            Arg::Real(c(1.0)),
            Arg::Real(c(1.0)),
        ],
    );
    assert_eq!(bad, SENTINEL);
}

#[test]
fn shift_writes_the_inverse_mapped_point_and_returns_one() {
    let out = call(
        "hfshift3d",
        &[
            arr(&[1.0, 2.0, 3.0]),
            Arg::Real(c(1.0)),
            Arg::Real(c(-1.0)),
            Arg::Real(c(0.5)),
        ],
    );
    assert_eq!(out.value.as_const(), Some(1.0));
    let (pos, p) = &out.writes[0];
    assert_eq!(*pos, 0);
    let p: Vec<f64> = p.iter().map(|e| e.as_const().unwrap()).collect();
    assert_eq!(p, vec![0.0, 3.0, 2.5]);
}

#[test]
fn rotation_about_z_turns_the_object_by_plus_theta() {
    // A point at +y seen by an object turned +90 degrees maps back to +x.
    let out = call(
        "hfrotate3dz",
        &[
            arr(&[0.0, 1.0, 0.0]),
            Arg::Real(c(std::f64::consts::FRAC_PI_2)),
        ],
    );
    let p: Vec<f64> = out.writes[0]
        .1
        .iter()
        .map(|e| e.as_const().unwrap())
        .collect();
    assert!(
        (p[0] - 1.0).abs() < 1e-15 && p[1].abs() < 1e-15 && p[2] == 0.0,
        "{p:?}"
    );
}

#[test]
fn blends_add_the_displacement_to_r0_operations() {
    let a = [3.0, 4.0, 1.0, 1.0, 1.0].map(|v| Arg::Real(c(v)));
    let bump = 1.0 / (1.0 + 9.0 + 16.0);
    assert_eq!(val("hfblenduni", &a), 12.0 + bump);
    assert_eq!(val("hfblendint", &a), 2.0 + bump);
}

#[test]
fn lookup_is_case_insensitive_and_unknown_names_are_absent() {
    let r = Registry::standard();
    assert!(r.get("HfTwistZ").is_some());
    assert!(r.get("hfnosuch").is_none());
    assert!(r.names().windows(2).all(|w| w[0] < w[1]));
}
