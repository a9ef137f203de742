//! Parameters `a[k] = v` are checked against the object's `a[N]` before
//! anything is sized from the index.

use microfrep_hyperfun::load_with_params;

const SRC: &str = "my_model(x[3], a[2]) { my_model = a[1] + 10 * a[2] - x[1]; }";

fn err(params: &[(usize, f64)]) -> String {
    match load_with_params(SRC, "p.hf", None, params) {
        Ok(_) => panic!("accepted {params:?}"),
        Err(d) => d.message,
    }
}

#[test]
fn parameters_set_a_and_later_pairs_win() {
    let m = load_with_params(SRC, "p.hf", None, &[(2, 3.0), (1, 5.0), (1, 1.0)]).unwrap();
    assert_eq!(m.eval_points(&[[1.0, 0.0, 0.0]])[0], Ok(30.0));
    let m = load_with_params(SRC, "p.hf", None, &[]).unwrap();
    assert_eq!(m.eval_points(&[[1.0, 0.0, 0.0]])[0], Ok(-1.0));
}

#[test]
fn huge_or_zero_indices_are_errors_without_allocating() {
    let want = |k: u128| format!("parameter a[{k}] out of range: object 'my_model' has a[2]");
    assert_eq!(err(&[(3, 1.0)]), want(3));
    // These would ask for 80 GB, or overflow a capacity, if sized first.
    assert_eq!(err(&[(10_000_000_000, 1.0)]), want(10_000_000_000));
    assert_eq!(err(&[(usize::MAX, 1.0)]), want(usize::MAX as u128));
    assert_eq!(
        err(&[(0, 1.0)]),
        "parameter index must be 1 or more (a[1] is the first)"
    );
    assert_eq!(
        err(&[(1, f64::NAN)]),
        "parameter a[1] must be a finite number, not NaN"
    );
}
