//! Triply periodic minimal surfaces (their usual trigonometric
//! approximations) as network solids `{f < t}` and sheet solids `{|f| < t}`,
//! with any cell size. With `X = 2 pi x / L` etc.:
//!
//! | surface | f |
//! | --- | --- |
//! | gyroid | `sin X cos Y + sin Y cos Z + sin Z cos X` |
//! | Schwarz P | `cos X + cos Y + cos Z` |
//! | Schwarz D | `sin X sin Y sin Z + sin X cos Y cos Z + cos X sin Y cos Z + cos X cos Y sin Z` |
//! | Neovius | `3 (cos X + cos Y + cos Z) + 4 cos X cos Y cos Z` |
//! | Schoen IWP | `2 (cos X cos Y + cos Y cos Z + cos Z cos X) - (cos 2X + cos 2Y + cos 2Z)` |
//! | Fischer-Koch S | `cos 2X sin Y cos Z + cos X cos 2Y sin Z + sin X cos Y cos 2Z` |

use microfrep_core::transform::P3;
use microfrep_core::Expr;

/// A triply periodic minimal surface (the approximations in the module
/// table).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tpms {
    /// Schoen's gyroid.
    Gyroid,
    /// Schwarz's primitive surface.
    SchwarzP,
    /// Schwarz's diamond surface.
    SchwarzD,
    /// Neovius' surface.
    Neovius,
    /// Schoen's I-WP surface.
    SchoenIwp,
    /// Fischer and Koch's S surface.
    FischerKochS,
}

impl Tpms {
    /// Every surface, in the order of the module table.
    pub const ALL: [Tpms; 6] = [
        Tpms::Gyroid,
        Tpms::SchwarzP,
        Tpms::SchwarzD,
        Tpms::Neovius,
        Tpms::SchoenIwp,
        Tpms::FischerKochS,
    ];

    /// Lower-case, hyphenated name (`gyroid`, `schwarz-p`, ...).
    pub fn name(self) -> &'static str {
        match self {
            Tpms::Gyroid => "gyroid",
            Tpms::SchwarzP => "schwarz-p",
            Tpms::SchwarzD => "schwarz-d",
            Tpms::Neovius => "neovius",
            Tpms::SchoenIwp => "schoen-iwp",
            Tpms::FischerKochS => "fischer-koch-s",
        }
    }

    /// A bound on `|f|`: the sum of the coefficients' magnitudes. Levels
    /// outside `[-bound, bound]` give an empty or full solid.
    pub fn bound(self) -> f64 {
        match self {
            Tpms::Gyroid | Tpms::SchwarzP | Tpms::FischerKochS => 3.0,
            Tpms::SchwarzD => 4.0,
            Tpms::Neovius => 13.0,
            Tpms::SchoenIwp => 9.0,
        }
    }

    /// The surface function at `p` for cells of size `cell` (may be a field).
    pub fn field(self, p: &P3, cell: impl Into<Expr>) -> Expr {
        let k = 2.0 * std::f64::consts::PI / cell.into();
        let a: Vec<Expr> = p.iter().map(|c| c * &k).collect();
        let s: Vec<Expr> = a.iter().map(Expr::sin).collect();
        let c: Vec<Expr> = a.iter().map(Expr::cos).collect();
        let c2 = || -> Vec<Expr> { a.iter().map(|x| (2.0 * x).cos()).collect() };
        match self {
            Tpms::Gyroid => &s[0] * &c[1] + &s[1] * &c[2] + &s[2] * &c[0],
            Tpms::SchwarzP => &c[0] + &c[1] + &c[2],
            Tpms::SchwarzD => {
                &s[0] * &s[1] * &s[2]
                    + &s[0] * &c[1] * &c[2]
                    + &c[0] * &s[1] * &c[2]
                    + &c[0] * &c[1] * &s[2]
            }
            Tpms::Neovius => 3.0 * (&c[0] + &c[1] + &c[2]) + 4.0 * (&c[0] * &c[1] * &c[2]),
            Tpms::SchoenIwp => {
                let d = c2();
                2.0 * (&c[0] * &c[1] + &c[1] * &c[2] + &c[2] * &c[0]) - (&d[0] + &d[1] + &d[2])
            }
            Tpms::FischerKochS => {
                let d = c2();
                &d[0] * &s[1] * &c[2] + &c[0] * &d[1] * &s[2] + &s[0] * &c[1] * &d[2]
            }
        }
    }
}

/// How a surface becomes a solid.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Solid {
    /// One side of the level set: `{f < level}`.
    Network,
    /// A wall around the surface: `{|f| < level}`.
    Sheet,
}

/// The solid of `kind` with cells of size `cell`; `level` may be a field
/// (graded density).
pub fn tpms(
    kind: Tpms,
    solid: Solid,
    p: &P3,
    cell: impl Into<Expr>,
    level: impl Into<Expr>,
) -> Expr {
    let f = kind.field(p, cell);
    match solid {
        Solid::Network => level.into() - f,
        Solid::Sheet => level.into() - f.abs(),
    }
}
