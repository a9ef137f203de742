//! Array lengths the `hf*` functions need, checked when a model is loaded.
//!
//! Array lengths are fixed by declarations, so every call can be checked
//! before anything runs. The reference interpreter checks only the point
//! array (a wrong length gives the sentinel value, kept here for
//! compatibility) and reads past the end of any other short array; here such
//! a call is an error at the argument's position instead of a value built
//! from garbage (or NaN).

/// What length an array argument of a library function must have.
/// Argument numbers are 0-based positions in the call.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Len {
    /// The point array: any length; the function returns its sentinel when
    /// the length is not 3, as the reference does.
    Point,
    /// Any length.
    Any,
    /// Exactly this many elements.
    Exactly(usize),
    /// At least this many.
    AtLeast(usize),
    /// A positive multiple of this (one group per item).
    MultipleOf(usize),
    /// `m` times the length of argument `k`: `Times(k, m)`.
    Times(usize, usize),
    /// `m` times (the length of argument `k` plus `c`): `TimesPlus(k, m, c)`.
    TimesPlus(usize, usize, usize),
    /// At least the length of argument `k`.
    AtLeastLen(usize),
    /// At least len(`a`) times (len(`b`) - `d`): `AtLeastProduct(a, b, d)`.
    AtLeastProduct(usize, usize, usize),
    /// A multiple of the length of argument `k`, with at least `g` groups.
    Groups(usize, usize),
}

impl Len {
    /// Whether `n` elements satisfy the rule, given all argument lengths
    /// (`None` for a real argument).
    // `is_multiple_of` needs Rust 1.87; the workspace supports 1.85.
    #[allow(clippy::manual_is_multiple_of)]
    pub fn accepts(self, n: usize, lens: &[Option<usize>]) -> bool {
        let len = |k: usize| lens.get(k).copied().flatten().unwrap_or(0);
        match self {
            Len::Point | Len::Any => true,
            Len::Exactly(m) => n == m,
            Len::AtLeast(m) => n >= m,
            Len::MultipleOf(m) => n >= m && n % m == 0,
            Len::Times(k, m) => n == m * len(k),
            Len::TimesPlus(k, m, c) => n == m * (len(k) + c),
            Len::AtLeastLen(k) => n >= len(k),
            Len::AtLeastProduct(a, b, d) => n >= len(a) * len(b).saturating_sub(d),
            Len::Groups(k, g) => len(k) > 0 && n % len(k) == 0 && n / len(k) >= g,
        }
    }

    /// The rule in words, e.g. "3 elements" or "3 times the length of
    /// argument 3 ('s', 2 elements) = 6 elements".
    pub fn describe(self, lens: &[Option<usize>], names: &[String]) -> String {
        let len = |k: usize| lens.get(k).copied().flatten().unwrap_or(0);
        let arg = |k: usize| {
            let name = names.get(k).map_or("", String::as_str);
            format!("argument {} ('{name}', {} elements)", k + 1, len(k))
        };
        match self {
            Len::Point | Len::Any => "any number of elements".into(),
            Len::Exactly(m) => format!("{m} elements"),
            Len::AtLeast(m) => format!("at least {m} elements"),
            Len::MultipleOf(m) => format!("a multiple of {m} elements (one group of {m} per item)"),
            Len::Times(k, 1) => format!("as many elements as {}", arg(k)),
            Len::Times(k, m) => {
                format!("{m} times as many elements as {} = {}", arg(k), m * len(k))
            }
            Len::TimesPlus(k, m, c) => format!(
                "{m} times (the length of {} plus {c}) = {} elements",
                arg(k),
                m * (len(k) + c)
            ),
            Len::AtLeastLen(k) => format!("at least as many elements as {}", arg(k)),
            Len::AtLeastProduct(a, b, d) => {
                let minus = if d > 0 {
                    format!(" minus {d}")
                } else {
                    String::new()
                };
                format!(
                    "at least the length of {} times the length of {}{minus} = {} elements",
                    arg(a),
                    arg(b),
                    len(a) * len(b).saturating_sub(d)
                )
            }
            Len::Groups(k, g) => format!(
                "a multiple of the length of {}, at least {g} groups",
                arg(k)
            ),
        }
    }
}

use Len::*;

const PRIM: &[Option<Len>] = &[Some(Point), Some(Exactly(3))];
const POINT_ONLY: &[Option<Len>] = &[Some(Point)];
const BLOBS: &[Option<Len>] = &[
    Some(Point),
    Some(AtLeast(1)),
    Some(Times(1, 1)),
    Some(Times(1, 1)),
    Some(Times(1, 1)),
    Some(Times(1, 1)),
];
const LOOKUP: &[Option<Len>] = &[None, Some(Any), Some(AtLeastProduct(1, 3, 0)), Some(Any)];
const COLOUR: &[Option<Len>] = &[Some(AtLeast(3)), Some(AtLeast(3))];
const LERP: &[Option<Len>] = &[Some(Any), Some(AtLeastLen(0)), Some(AtLeastLen(0))];

/// The rules of a reference library function (lower-case name), one entry
/// per leading argument (`None` for a real argument; arguments past the
/// end have no rule). `None` for a name outside the reference library
/// (extensions check their own arguments).
pub fn rules(name: &str) -> Option<&'static [Option<Len>]> {
    Some(match name {
        "hfsphere" | "hfellipsoid" | "hfcylinderx" | "hfcylindery" | "hfcylinderz"
        | "hfellcylx" | "hfellcyly" | "hfellcylz" | "hftorusx" | "hftorusy" | "hftorusz"
        | "hfconex" | "hfconey" | "hfconez" | "hfellconex" | "hfellconey" | "hfellconez"
        | "hfblock" | "hfsuperell" | "hfdconex" | "hfdconey" | "hfdconez" | "hfdtorusx"
        | "hfdtorusy" | "hfdtorusz" | "hfdellipsoid" => PRIM,
        "hfblobby" | "hfmetaball" => BLOBS,
        "hfsoft" => &BLOBS[..5],
        "hfnoiseg" | "hfshift3d" | "hfscale3d" | "hfrotate3dx" | "hfrotate3dy" | "hfrotate3dz"
        | "hftwistx" | "hftwisty" | "hftwistz" | "hftaperx" | "hftapery" | "hftaperz" => POINT_ONLY,
        "hfdcylinder" => &[Some(Point), Some(Exactly(3)), Some(Exactly(3))],
        // The control values' count depends on l, m, n: checked by the builder.
        "hfbeziervolume" => &[Some(Point), None, None, None, Some(Exactly(6)), Some(Any)],
        "hfr" => &[Some(Any)],
        "hfconvpoint" => &[Some(Point), Some(Times(2, 3)), Some(AtLeast(1))],
        "hfconvline" => &[
            Some(Point),
            Some(Times(3, 3)),
            Some(Times(3, 3)),
            Some(AtLeast(1)),
        ],
        "hfconvcurve" => &[Some(Point), Some(TimesPlus(2, 3, 1)), Some(AtLeast(1))],
        "hfconvliner" => &[Some(Point), Some(Times(2, 1)), Some(MultipleOf(3))],
        "hfconvtriangle" => &[Some(Point), Some(Times(2, 9)), Some(AtLeast(1))],
        "hfconvmesh" => &[
            Some(Point),
            Some(MultipleOf(3)),
            Some(Times(3, 3)),
            Some(AtLeast(1)),
        ],
        "hfconvarc" => &[
            Some(Point),
            Some(Times(6, 3)),
            Some(Times(6, 1)),
            Some(Times(6, 1)),
            Some(Times(6, 3)),
            Some(Times(6, 1)),
            Some(AtLeast(1)),
        ],
        "hfstretch3d" => &[Some(Point), Some(Exactly(3))],
        "hfspacemapexp" | "hfspacemapcubic" => &[
            Some(Point),
            Some(MultipleOf(3)),
            Some(Times(1, 1)),
            Some(Times(1, 1)),
        ],
        "hfa_union" => &[
            None,
            None,
            Some(Any),
            Some(AtLeastLen(2)),
            Some(AtLeastLen(2)),
        ],
        "hfa_setcolor" => &[None, Some(AtLeast(3))],
        "hfa_setattributes" => &[None, Some(Any), Some(Any)],
        "hfa_lerp" | "hfa_cerp" => LERP,
        "hfa_lookuptable" | "hfa_smoothlookuptable" => LOOKUP,
        "hfa_spline" => &[Some(Any), Some(Groups(0, 4))],
        "hfa_checkerboard" => &[
            Some(AtLeast(3)),
            Some(Exactly(3)),
            Some(Exactly(3)),
            Some(Any),
            Some(Any),
            Some(Any),
        ],
        "hfa_rgbtohsv" | "hfa_hsvtorgb" => COLOUR,
        "hfa_noiseg" | "hfa_noisep" | "hfa_turbulence" => &[Some(AtLeast(3))],
        "hfa_circles" => &[
            Some(AtLeast(3)),
            Some(Any),
            Some(AtLeastProduct(1, 3, 1)),
            Some(Any),
        ],
        "hfa_crackles" => &[
            Some(AtLeast(3)),
            Some(Any),
            None,
            Some(AtLeastProduct(1, 4, 1)),
            Some(Any),
        ],
        "hfblenduni" | "hfblendint" | "hfdblenduni" | "hfdblendint" | "hfduni" | "hfdint"
        | "hfdsub" | "hfsawtooth" | "hfa_wave" | "hfa_clamp" | "hfa_pulse" | "hfa_step"
        | "hfa_smoothstep" | "hfa_modulo" | "hfa_floor" => &[],
        _ => return None,
    })
}

/// Spelling of the reference library's names as documented.
const NAMES: &[&str] = &[
    "hfA_Cerp",
    "hfA_CheckerBoard",
    "hfA_Circles",
    "hfA_Clamp",
    "hfA_Crackles",
    "hfA_Floor",
    "hfA_HSVToRGB",
    "hfA_Lerp",
    "hfA_LookUpTable",
    "hfA_Modulo",
    "hfA_NoiseG",
    "hfA_NoiseP",
    "hfA_Pulse",
    "hfA_RGBToHSV",
    "hfA_SetAttributes",
    "hfA_SetColor",
    "hfA_SmoothLookUpTable",
    "hfA_SmoothStep",
    "hfA_Spline",
    "hfA_Step",
    "hfA_Turbulence",
    "hfA_Union",
    "hfA_Wave",
    "hfBezierVolume",
    "hfBlendInt",
    "hfBlendUni",
    "hfBlobby",
    "hfBlock",
    "hfConeX",
    "hfConeY",
    "hfConeZ",
    "hfConvArc",
    "hfConvCurve",
    "hfConvLine",
    "hfConvLineR",
    "hfConvMesh",
    "hfConvPoint",
    "hfConvTriangle",
    "hfCylinderX",
    "hfCylinderY",
    "hfCylinderZ",
    "hfDBlendInt",
    "hfDBlendUni",
    "hfDConeX",
    "hfDConeY",
    "hfDConeZ",
    "hfDCylinder",
    "hfDEllipsoid",
    "hfDInt",
    "hfDSub",
    "hfDTorusX",
    "hfDTorusY",
    "hfDTorusZ",
    "hfDUni",
    "hfEllConeX",
    "hfEllConeY",
    "hfEllConeZ",
    "hfEllCylX",
    "hfEllCylY",
    "hfEllCylZ",
    "hfEllipsoid",
    "hfMetaball",
    "hfNoiseG",
    "hfR",
    "hfRotate3DX",
    "hfRotate3DY",
    "hfRotate3DZ",
    "hfSawtooth",
    "hfScale3D",
    "hfShift3D",
    "hfSoft",
    "hfSpaceMapCubic",
    "hfSpaceMapExp",
    "hfSphere",
    "hfStretch3D",
    "hfSuperell",
    "hfTaperX",
    "hfTaperY",
    "hfTaperZ",
    "hfTorusX",
    "hfTorusY",
    "hfTorusZ",
    "hfTwistX",
    "hfTwistY",
    "hfTwistZ",
];

/// The documented spelling of a function name given in any case (the name
/// itself when it is not a reference library function).
pub fn display_name(name: &str) -> &str {
    NAMES
        .iter()
        .find(|n| n.eq_ignore_ascii_case(name))
        .copied()
        .unwrap_or(name)
}
