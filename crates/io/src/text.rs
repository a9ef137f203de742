//! Numbers for people: significant digits, whatever the scale, so a 1 mm
//! part modelled in metres is not "0.000000" and 1e200 is not 201 digits.

/// `v` with `digits` significant digits: plain notation for magnitudes
/// from 1e-4 to below 1e7, scientific otherwise; "undefined" for NaN,
/// "inf"/"-inf" for infinities.
pub fn sig(v: f64, digits: usize) -> String {
    let digits = digits.clamp(1, 17);
    if v.is_nan() {
        return "undefined".into();
    }
    if v.is_infinite() {
        return if v > 0.0 { "inf".into() } else { "-inf".into() };
    }
    if v == 0.0 {
        return "0".into();
    }
    let mag = v.abs().log10().floor() as i32;
    if (-4..7).contains(&mag) {
        let decimals = (digits as i32 - 1 - mag).max(0) as usize;
        let s = format!("{v:.decimals$}");
        trim_zeros(&s)
    } else {
        let s = format!("{v:.*e}", digits - 1);
        match s.split_once('e') {
            Some((m, e)) => format!("{}e{e}", trim_zeros(m)),
            None => s,
        }
    }
}

fn trim_zeros(s: &str) -> String {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s.to_string()
    }
}

/// The shortest decimal that reads back as exactly `v` (Rust's `{}`), but
/// in scientific notation when plain notation would be long (beyond 1e16
/// or below 1e-5), for machine-readable point values.
pub fn exact(v: f64) -> String {
    if v.is_finite() && v != 0.0 && !(1e-5..1e16).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn significant_digits_at_every_scale() {
        assert_eq!(sig(1.638_123_456, 7), "1.638123");
        assert_eq!(sig(0.000_523_598_8, 4), "0.0005236");
        assert_eq!(sig(5.235_988e-10, 4), "5.236e-10");
        assert_eq!(sig(1e200, 3), "1e200");
        assert_eq!(sig(-12345.678, 7), "-12345.68");
        assert_eq!(sig(2.0, 6), "2");
        assert_eq!(sig(f64::NAN, 6), "undefined");
        assert_eq!(exact(1e200), "1e200");
        assert_eq!(exact(0.1), "0.1");
        assert_eq!(exact(1e-300).parse::<f64>().unwrap(), 1e-300);
    }
}
