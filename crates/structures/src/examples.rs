//! Built-in example models, built with the Rust API.

use crate::infill::{shell_with_infill, Join};
use crate::lattice::{rod_lattice, Slabs};
use crate::replicate::{replicate, Wave};
use microfrep_core::frep::{intersection, union_all};
use microfrep_core::Expr;
use microfrep_shapes::{block, sphere, torus, v3};

/// A named example with its natural bounding box.
pub struct Example {
    /// Name used to pick it (e.g. on the command line).
    pub name: &'static str,
    /// What the model is and where it comes from.
    pub description: &'static str,
    /// Box `(min, max)` the model fits in.
    pub bounds: ([f64; 3], [f64; 3]),
    /// Builds the model.
    pub build: fn() -> Expr,
}

/// Every built-in example.
pub fn all() -> Vec<Example> {
    vec![
        Example {
            name: "toriball",
            description: "Fryazinov et al. Algorithm 1: three tori (R 0.8, r 0.2) in a unit cell, \
                          triangle-wave replicated with cell width 0.2 (10x10x10 cells), \
                          intersected with the block [-1,1]^3",
            bounds: ([-1.0; 3], [1.0; 3]),
            build: toriball,
        },
        Example {
            name: "shell_lattice",
            description: "Pasko et al. Eq. 8: unit sphere shell (l_o = 0.2) with a rod lattice \
                          infill (q = 12, l = 0.4), alpha = 0",
            bounds: ([-1.0; 3], [1.0; 3]),
            build: shell_lattice,
        },
        Example {
            name: "sphere",
            description: "unit sphere 1 - x^2 - y^2 - z^2",
            bounds: ([-1.0; 3], [1.0; 3]),
            build: unit_sphere,
        },
    ]
}

/// The example called `name`, if any.
pub fn by_name(name: &str) -> Option<Example> {
    all().into_iter().find(|e| e.name == name)
}

/// The unit sphere `1 - x^2 - y^2 - z^2`.
pub fn unit_sphere() -> Expr {
    sphere(&Expr::xyz(), &v3([0.0; 3]), 1.0)
}

/// The tori-ball cell: union (alpha = 0) of three tori around the x, y, z
/// axes on the cell [-1, 1]^3.
pub fn toriball_cell(p: &[Expr; 3]) -> Expr {
    let c = v3([0.0; 3]);
    let t: Vec<Expr> = (0..3).map(|a| torus(p, &c, a, 0.8, 0.2)).collect();
    union_all(&t, 0.0)
}

/// Algorithm 1 of Fryazinov et al.: the tori-ball cell replicated by the
/// triangle wave with cell width `w` over all space, intersected with the
/// block [-1, 1]^3 (alpha = 0 throughout).
pub fn toriball() -> Expr {
    toriball_with(0.2)
}

/// [`toriball`] with cells of width `cell_width` instead of 0.2.
pub fn toriball_with(cell_width: f64) -> Expr {
    let p = Expr::xyz();
    let w = Expr::constant(cell_width);
    let waves = [
        Wave::Triangle(w.clone()),
        Wave::Triangle(w.clone()),
        Wave::Triangle(w),
    ];
    let q = replicate(&p, &waves, [-1.0; 3], [1.0; 3]);
    let cells = toriball_cell(&q);
    let bx = block(&p, &v3([-1.0; 3]), &v3([2.0; 3]));
    intersection(&cells, &bx, 0.0)
}

/// Pasko et al. Eq. 8 with F the unit sphere, inner offset 0.2, lattice q = 12, l = 0.4, alpha 0.
pub fn shell_lattice() -> Expr {
    shell_with_lattice(&unit_sphere(), 0.2, &Slabs::uniform(12.0, 0.4), 0.0)
}

/// Shell with a rod-lattice infill (Eq. 8), plain union.
pub fn shell_with_lattice(f: &Expr, l_o: f64, slabs: &Slabs, alpha: f64) -> Expr {
    let g = rod_lattice(&Expr::xyz(), slabs, alpha);
    shell_with_infill(f, l_o, &g, alpha, &Join::Plain)
}
