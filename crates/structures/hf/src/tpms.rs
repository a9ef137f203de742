//! TPMS network and sheet solids with any cell size and level (both may be
//! fields), and with a target density field.

use crate::args::{code, out, three, value};
use crate::tables::tpms_table;
use microfrep_hyperfun::library::{Arg, Kind::*, Output, Registry};
use microfrep_structures::tpms::{tpms, Solid, Tpms};

fn solid(sheet: bool) -> Solid {
    if sheet {
        Solid::Sheet
    } else {
        Solid::Network
    }
}

/// `mfGyroid(x, cell, level)` and the like: surface `K` of `Tpms::ALL`.
fn named<const K: usize, const SHEET: bool>(a: &[Arg]) -> Output {
    out(|| {
        let x = three(&a[0], "x")?;
        value(tpms(
            Tpms::ALL[K],
            solid(SHEET),
            &x,
            a[1].real(),
            a[2].real(),
        ))
    })
}

/// `mfTpms(x, kind, sheet, cell, level)`.
fn generic(a: &[Arg]) -> Output {
    out(|| {
        let x = three(&a[0], "x")?;
        let k = code(&a[1], "TPMS kind", 1, 6)? as usize;
        let sheet = code(&a[2], "sheet flag", 0, 1)? == 1;
        value(tpms(
            Tpms::ALL[k - 1],
            solid(sheet),
            &x,
            a[3].real(),
            a[4].real(),
        ))
    })
}

/// `mfTpmsDensity(x, kind, sheet, cell, rho)`.
fn density(a: &[Arg]) -> Output {
    out(|| {
        let x = three(&a[0], "x")?;
        let k = code(&a[1], "TPMS kind", 1, 6)? as usize;
        let sheet = code(&a[2], "sheet flag", 0, 1)? == 1;
        let (kind, s) = (Tpms::ALL[k - 1], solid(sheet));
        let table = tpms_table(kind, s).map_err(Output::error)?;
        let level = table.piecewise(&a[4].real());
        value(tpms(kind, s, &x, a[3].real(), level))
    })
}

pub(crate) fn register(r: &mut Registry) {
    const K: &[microfrep_hyperfun::library::Kind] = &[A, R, R];
    r.register("mfgyroid", K, named::<0, false>);
    r.register("mfschwarzp", K, named::<1, false>);
    r.register("mfschwarzd", K, named::<2, false>);
    r.register("mfneovius", K, named::<3, false>);
    r.register("mfschoeniwp", K, named::<4, false>);
    r.register("mffischerkochs", K, named::<5, false>);
    r.register("mfgyroidsheet", K, named::<0, true>);
    r.register("mfschwarzpsheet", K, named::<1, true>);
    r.register("mfschwarzdsheet", K, named::<2, true>);
    r.register("mfneoviussheet", K, named::<3, true>);
    r.register("mfschoeniwpsheet", K, named::<4, true>);
    r.register("mffischerkochssheet", K, named::<5, true>);
    r.register("mftpms", &[A, R, R, R, R], generic);
    r.register("mftpmsdensity", &[A, R, R, R, R], density);
}
