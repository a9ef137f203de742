//! Colour maps for showing a scalar (an attribute channel) as colour:
//! [`Colormap`] turns a fraction in 0..1 into sRGB, [`ColourScale`] maps a
//! value through a range `lo..hi` first. Mesh colours and rendered images
//! use the same scale, so a value has the same colour in both.
//!
//! ```
//! use microfrep_io::colormap::{Colormap, ColourScale};
//! let grey = ColourScale::new(Colormap::Grey, 0.0, 2.0).unwrap();
//! assert_eq!(grey.colour(0.0), [0, 0, 0]);
//! assert_eq!(grey.colour(1.0), [128, 128, 128]);
//! assert_eq!(grey.colour(5.0), [255, 255, 255]); // clamped to the range
//! let v: Colormap = "viridis".parse().unwrap();
//! assert_eq!(v.rgb(0.0), [0x44, 0x01, 0x54]);
//! ```

/// The colour of an undefined (NaN) value: magenta, outside both maps.
pub const NAN_COLOUR: [u8; 3] = [255, 0, 255];

/// A map from a fraction in 0..1 to sRGB.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Colormap {
    /// Perceptually uniform, dark purple through teal to yellow (the
    /// matplotlib map, 256 entries interpolated linearly).
    #[default]
    Viridis,
    /// Black to white, linear in the 8-bit value.
    Grey,
}

impl Colormap {
    /// Every map.
    pub const ALL: [Colormap; 2] = [Colormap::Viridis, Colormap::Grey];

    /// The map's name, as [`str::parse`] takes it.
    pub fn name(self) -> &'static str {
        match self {
            Colormap::Viridis => "viridis",
            Colormap::Grey => "grey",
        }
    }

    /// The colour at fraction `t` (clamped to 0..1); [`NAN_COLOUR`] for NaN.
    pub fn rgb(self, t: f64) -> [u8; 3] {
        if t.is_nan() {
            return NAN_COLOUR;
        }
        let t = t.clamp(0.0, 1.0);
        match self {
            Colormap::Viridis => {
                let c = colorous::VIRIDIS.eval_continuous(t);
                [c.r, c.g, c.b]
            }
            Colormap::Grey => [(255.0 * t).round() as u8; 3],
        }
    }
}

impl std::str::FromStr for Colormap {
    type Err = String;
    fn from_str(s: &str) -> Result<Colormap, String> {
        match s {
            "viridis" => Ok(Colormap::Viridis),
            "grey" | "gray" => Ok(Colormap::Grey),
            _ => Err(format!("unknown colour map '{s}' (viridis, grey)")),
        }
    }
}

/// A value range mapped onto a [`Colormap`]: `lo` to its first colour,
/// `hi` to its last, values outside clamped, NaN to [`NAN_COLOUR`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ColourScale {
    /// The map.
    pub map: Colormap,
    /// Value of the first colour.
    pub lo: f64,
    /// Value of the last colour (above `lo`).
    pub hi: f64,
}

impl ColourScale {
    /// The scale of `lo..hi`; both finite and `lo < hi`, else an error
    /// saying so.
    pub fn new(map: Colormap, lo: f64, hi: f64) -> Result<ColourScale, String> {
        if !(lo.is_finite() && hi.is_finite() && lo < hi) {
            return Err(format!(
                "colour range {lo},{hi}: give two finite numbers, the first below the second"
            ));
        }
        Ok(ColourScale { map, lo, hi })
    }

    /// The scale over the finite values of `values` (NaN and infinities
    /// skipped): their minimum to their maximum. A single value `v` gets
    /// `v - 0.5 .. v + 0.5` (its colour is the map's middle); no finite
    /// value at all gets `0..1`.
    pub fn over(map: Colormap, values: impl IntoIterator<Item = f64>) -> ColourScale {
        let (lo, hi) = values
            .into_iter()
            .filter(|v| v.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                (a.min(v), b.max(v))
            });
        let (lo, hi) = if lo > hi {
            (0.0, 1.0)
        } else if lo == hi {
            (lo - 0.5, hi + 0.5)
        } else {
            (lo, hi)
        };
        ColourScale { map, lo, hi }
    }

    /// Where `v` falls in the range, 0 at `lo` and 1 at `hi` (not clamped;
    /// NaN for NaN).
    pub fn fraction(&self, v: f64) -> f64 {
        (v - self.lo) / (self.hi - self.lo)
    }

    /// The colour of `v`.
    pub fn colour(&self, v: f64) -> [u8; 3] {
        self.map.rgb(self.fraction(v))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn viridis_ends_and_middle_are_the_published_entries() {
        // Entries 0, 128 and 255 of the 256-colour table.
        assert_eq!(Colormap::Viridis.rgb(0.0), [0x44, 0x01, 0x54]);
        assert_eq!(Colormap::Viridis.rgb(1.0), [0xfd, 0xe7, 0x25]);
        let mid = Colormap::Viridis.rgb(128.0 / 255.0);
        for (a, b) in mid.iter().zip([0x21u8, 0x91, 0x8c]) {
            assert!(a.abs_diff(b) <= 1, "{mid:?}");
        }
        assert_eq!(Colormap::Viridis.rgb(f64::NAN), NAN_COLOUR);
    }

    #[test]
    fn scales_clamp_and_refuse_empty_ranges() {
        let s = ColourScale::new(Colormap::Grey, -1.0, 1.0).unwrap();
        assert_eq!(s.colour(-3.0), [0; 3]);
        assert_eq!(s.colour(0.0), [128; 3]);
        assert_eq!(s.colour(9.0), [255; 3]);
        assert!(ColourScale::new(Colormap::Grey, 1.0, 1.0).is_err());
        assert!(ColourScale::new(Colormap::Grey, 0.0, f64::NAN).is_err());
        let o = ColourScale::over(Colormap::Grey, [2.0, f64::NAN, -1.0, f64::INFINITY]);
        assert_eq!((o.lo, o.hi), (-1.0, 2.0));
        let c = ColourScale::over(Colormap::Grey, [3.0, 3.0]);
        assert_eq!((c.lo, c.hi), (2.5, 3.5));
        let n = ColourScale::over(Colormap::Grey, [f64::NAN]);
        assert_eq!((n.lo, n.hi), (0.0, 1.0));
        assert_eq!("gray".parse::<Colormap>(), Ok(Colormap::Grey));
        assert!("jet".parse::<Colormap>().unwrap_err().contains("viridis"));
    }
}
