use microfrep::core::Interval;
fn main() {
    let a: Vec<String> = std::env::args().collect();
    let m = microfrep::load(&a[1], &Default::default()).unwrap();
    let t = m.shape.tape();
    let mut ie = m.shape.interval();
    let s: f64 = a[2].parse().unwrap();
    let c: f64 = a.get(3).map(|v| v.parse().unwrap()).unwrap_or(0.0);
    let iv = Interval::new(c - s, c + s);
    let r = ie.eval(iv, iv, iv);
    println!("len {} root {:?}", t.len(), r);
    println!("bounds {:?}", m.shape.bounds());
    // Print the first few values that are NaN-unknown or ENTIRE.
    let vals = ie.values();
    for (i, op) in t.ops().iter().enumerate() {
        let v = vals[i];
        if v.is_nan() {
            println!("v{i} {:?} = {:?}", op, v);
            break;
        }
    }
}
#[allow(dead_code)]
fn unused() {}
