//! Attribute values: numbers, indices, resource ids, transforms, booleans
//! and colours, with errors that name the part and the offset.

use crate::error::{invalid, Result};
use crate::model::Transform;

pub(super) fn parse_num(part: &str, off: u64, what: &str, v: &str) -> Result<f64> {
    let t = v.trim();
    match t.parse::<f64>() {
        Ok(x) if x.is_finite() && !t.contains(['i', 'I', 'n', 'N']) => Ok(x),
        Ok(_) => Err(invalid(
            part,
            off,
            format!("{what} = \"{v}\" is not a finite number"),
        )),
        Err(_) => Err(invalid(
            part,
            off,
            format!("{what} = \"{v}\" is not a number"),
        )),
    }
}

/// An sRGB colour `#RRGGBB` or `#RRGGBBAA` (alpha 255 when absent).
pub(super) fn parse_colour(part: &str, off: u64, v: &str) -> Result<[u8; 4]> {
    let hex = v.trim().strip_prefix('#').unwrap_or("");
    let byte = |i: usize| {
        hex.get(i..i + 2)
            .and_then(|h| u8::from_str_radix(h, 16).ok())
    };
    match (hex.len(), byte(0), byte(2), byte(4)) {
        (6, Some(r), Some(g), Some(b)) => Ok([r, g, b, 255]),
        (8, Some(r), Some(g), Some(b)) => match byte(6) {
            Some(a) => Ok([r, g, b, a]),
            None => Err(invalid(
                part,
                off,
                format!("colour \"{v}\" is not #RRGGBB or #RRGGBBAA"),
            )),
        },
        _ => Err(invalid(
            part,
            off,
            format!("colour \"{v}\" is not #RRGGBB or #RRGGBBAA"),
        )),
    }
}

/// An xs:double (may be INF, -INF, NaN).
pub(super) fn parse_double(part: &str, off: u64, what: &str, v: &str) -> Result<f64> {
    match v.trim() {
        "INF" => Ok(f64::INFINITY),
        "-INF" => Ok(f64::NEG_INFINITY),
        "NaN" => Ok(f64::NAN),
        t => parse_num(part, off, what, t),
    }
}

pub(super) fn parse_index(part: &str, off: u64, what: &str, v: &str) -> Result<u32> {
    v.trim()
        .parse::<u32>()
        .ok()
        .filter(|&x| x <= i32::MAX as u32)
        .ok_or_else(|| {
            invalid(
                part,
                off,
                format!("{what} = \"{v}\" is not an index in 0..2^31"),
            )
        })
}

pub(super) fn parse_id(part: &str, off: u64, what: &str, v: &str) -> Result<u32> {
    let x = parse_index(part, off, what, v)?;
    if x == 0 {
        return Err(invalid(
            part,
            off,
            format!("{what} must be a positive resource id"),
        ));
    }
    Ok(x)
}

pub(super) fn parse_transform(part: &str, off: u64, v: &str) -> Result<Transform> {
    let vals: Vec<&str> = v.split_ascii_whitespace().collect();
    if vals.len() != 12 {
        return Err(invalid(
            part,
            off,
            format!("transform \"{v}\" needs 12 numbers, has {}", vals.len()),
        ));
    }
    let mut m = [0.0; 12];
    for (i, x) in vals.iter().enumerate() {
        m[i] = parse_num(part, off, "transform entry", x)?;
    }
    Ok(Transform(m))
}

pub(super) fn parse_bool(part: &str, off: u64, what: &str, v: &str) -> Result<bool> {
    match v.trim() {
        "true" | "1" => Ok(true),
        "false" | "0" => Ok(false),
        _ => Err(invalid(
            part,
            off,
            format!("{what} = \"{v}\" is not a boolean"),
        )),
    }
}
