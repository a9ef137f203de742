//! Strut lattices: the unit cell, the replicated lattice with a radius
//! field, and the lattice with a target density field.

use crate::args::{code, out, three, value};
use crate::tables::strut_table;
use microfrep_hyperfun::library::{Arg, Kind::*, Output, Registry};
use microfrep_structures::struts::{strut_cell, strut_lattice, StrutLattice};

fn kind(a: &Arg) -> Result<StrutLattice, Output> {
    Ok(StrutLattice::ALL[code(a, "strut lattice kind", 1, 6)? as usize - 1])
}

/// `mfStrutCell(q, kind, r)`: the unit cell on [0, 1]^3.
fn cell(a: &[Arg]) -> Output {
    out(|| {
        let q = three(&a[0], "q")?;
        value(strut_cell(kind(&a[1])?, &q, a[2].real()))
    })
}

/// `mfStruts(x, kind, cell, r)`.
fn lattice(a: &[Arg]) -> Output {
    out(|| {
        let x = three(&a[0], "x")?;
        value(strut_lattice(kind(&a[1])?, &x, a[2].real(), a[3].real()))
    })
}

/// `mfStrutsDensity(x, kind, cell, rho)`.
fn density(a: &[Arg]) -> Output {
    out(|| {
        let x = three(&a[0], "x")?;
        let k = kind(&a[1])?;
        let table = strut_table(k).map_err(Output::error)?;
        let cell = a[2].real();
        let r = table.piecewise(&a[3].real()) * &cell;
        value(strut_lattice(k, &x, cell, r))
    })
}

pub(crate) fn register(r: &mut Registry) {
    r.register("mfstrutcell", &[A, R, R], cell);
    r.register("mfstruts", &[A, R, R, R], lattice);
    r.register("mfstrutsdensity", &[A, R, R, R], density);
}
