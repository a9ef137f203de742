//! Material subspaces (Park et al. §2.3 end, §3.1): a graded region with its
//! own defining function and local coordinates, mapped onto the part, so
//! homogeneous and heterogeneous regions are kept apart and a part may hold
//! several graded regions.
//!
//! A [`Subspace`] says *where* (its region, inside `>= 0`, in the part's
//! coordinates), *in which coordinates* its data live (three local
//! coordinates as functions of the part point, e.g. a box mapped to
//! `[0, 1]^3`, or two surface coordinates and the depth below a reference
//! surface scaled by a prescribed depth), and *what* (the fraction of one
//! material as an expression of the local coordinates, clamped to `[0, 1]`;
//! the rest of the voxel is the subspace's base material).
//!
//! A [`MaterialModel`] has a primary material filling the homogeneous part
//! and a list of subspaces applied in order: inside a subspace its
//! composition replaces what the earlier ones gave, so a later subspace
//! overrides an earlier one where they overlap. [`MaterialModel::fractions`]
//! turns it into one expression per material for a part: inside the part
//! (`part >= 0`) they are in `[0, 1]` and sum to 1; outside all are 0 (the
//! convention of attribute channels and grey layers). Each is an ordinary
//! [`Expr`], ready to be a channel of a shape or an output of a tape.
//!
//! ```
//! use microfrep_core::{Expr, PointEval, Tape};
//! use microfrep_shapes as prims;
//! use microfrep_graded::subspace::{MaterialModel, Subspace};
//! use microfrep_graded::dmf::bias;
//! let p = Expr::xyz();
//! let part = prims::sphere(&p, &prims::v3([0.0; 3]), 1.0);
//! // A core graded from ceramic (0) at depth 0.2 to metal (1) at depth 0.6.
//! let depth = 1.0 - (p[0].square() + p[1].square() + p[2].square()).sqrt();
//! let core = Subspace::below_surface(&depth, 0.2, 0.4, [p[0].clone(), p[1].clone()],
//!     bias(&Expr::z(), 0.7), 1);
//! let mut m = MaterialModel::new(2, 0).unwrap();
//! m.push(core).unwrap();
//! let f = m.fractions(&part);
//! let tape = Tape::with_outputs(&f);
//! let v = PointEval::new(&tape).eval_all([0.0, 0.0, 0.9]);
//! assert_eq!(v, vec![1.0, 0.0]); // depth 0.1: the primary shell
//! let v = PointEval::new(&tape).eval_all([0.0, 0.0, 0.0]);
//! assert_eq!(v, vec![0.0, 1.0]); // depth 1: all metal
//! ```

use crate::dmf::clamp01;
use crate::error::{Error, Result};
use microfrep_core::Expr;

/// A graded region of a part.
#[derive(Clone, Debug)]
pub struct Subspace {
    region: Expr,
    local: [Expr; 3],
    fraction: Expr,
    material: usize,
    base: Option<usize>,
}

impl Subspace {
    /// A subspace with region `region` (inside `>= 0`, part coordinates),
    /// local coordinates `local` (functions of the part point) and the
    /// fraction of `material` written in the local coordinates (its `x`,
    /// `y`, `z` are the local `u`, `v`, `w`).
    pub fn new(region: Expr, local: [Expr; 3], fraction: Expr, material: usize) -> Subspace {
        Subspace {
            region,
            local,
            fraction,
            material,
            base: None,
        }
    }

    /// The box `[min, max]` as region, mapped to local coordinates
    /// `[0, 1]^3` (the domain of a Bezier box field on the unit cube).
    pub fn in_box(min: [f64; 3], max: [f64; 3], fraction: Expr, material: usize) -> Subspace {
        let p = Expr::xyz();
        let region = (0..3)
            .map(|a| (&p[a] - min[a]).min(max[a] - &p[a]))
            .reduce(|r, s| r.min(s))
            .expect("three axes");
        let local = std::array::from_fn(|a| (&p[a] - min[a]) / (max[a] - min[a]));
        Subspace::new(region, local, fraction, material)
    }

    /// The layer from depth `from` downwards below a reference surface
    /// (`depth` from [`crate::depth`]), with local coordinates `u`, `v`
    /// (given, e.g. two part coordinates) and
    /// `w = clamp((depth - from) / ramp, 0, 1)`: the prescribed depth `from`
    /// is a shell of the base material of constant depth, the grading runs
    /// over `ramp` below it, and deeper points see `w = 1`.
    pub fn below_surface(
        depth: &Expr,
        from: f64,
        ramp: f64,
        uv: [Expr; 2],
        fraction: Expr,
        material: usize,
    ) -> Subspace {
        let region = depth - from;
        let w = clamp01(&(&region / ramp));
        let [u, v] = uv;
        Subspace::new(region, [u, v, w], fraction, material)
    }

    /// The material taking the remainder `1 - fraction` inside this
    /// subspace (default: the model's primary material).
    pub fn with_base(mut self, base: usize) -> Subspace {
        self.base = Some(base);
        self
    }

    /// The region's defining function.
    pub fn region(&self) -> &Expr {
        &self.region
    }

    /// The fraction of [`Subspace::material`] in part coordinates, clamped
    /// to `[0, 1]`.
    pub fn fraction(&self) -> Expr {
        clamp01(&self.fraction.remap(&self.local))
    }

    /// The graded material.
    pub fn material(&self) -> usize {
        self.material
    }

    /// The composition `comp` (one fraction per material) with this
    /// subspace laid over it: where the region is `>= 0` the graded
    /// material takes [`Subspace::fraction`], the base material (the one
    /// set by [`Subspace::with_base`], else `primary`) the rest and every
    /// other material 0; elsewhere `comp` is kept. Materials beyond
    /// `comp.len()` are ignored (check them with [`MaterialModel::push`]).
    pub fn over(&self, comp: &[Expr], primary: usize) -> Vec<Expr> {
        let base = self.base.unwrap_or(primary);
        let phi = self.fraction();
        let inside = self.region.ge(0.0);
        comp.iter()
            .enumerate()
            .map(|(m, prior)| {
                let here = if m == self.material {
                    phi.clone()
                } else if m == base {
                    1.0 - &phi
                } else {
                    Expr::constant(0.0)
                };
                Expr::select(inside.clone(), here, prior.clone())
            })
            .collect()
    }
}

/// A primary material and graded subspaces.
#[derive(Clone, Debug)]
pub struct MaterialModel {
    materials: usize,
    primary: usize,
    subspaces: Vec<Subspace>,
}

impl MaterialModel {
    /// `materials` materials (at least 1, at most 255), `primary` filling
    /// the part outside every subspace.
    pub fn new(materials: usize, primary: usize) -> Result<MaterialModel> {
        if !(1..=255).contains(&materials) {
            return Err(Error::Invalid(format!(
                "a material model needs 1 to 255 materials, got {materials}"
            )));
        }
        if primary >= materials {
            return Err(Error::Invalid(format!(
                "primary material {primary} out of range 0..{materials}"
            )));
        }
        Ok(MaterialModel {
            materials,
            primary,
            subspaces: Vec::new(),
        })
    }

    /// Adds a subspace (after, so over, the earlier ones).
    pub fn push(&mut self, s: Subspace) -> Result<&mut MaterialModel> {
        let base = s.base.unwrap_or(self.primary);
        for (what, m) in [("graded", s.material), ("base", base)] {
            if m >= self.materials {
                return Err(Error::Invalid(format!(
                    "subspace {}: {what} material {m} out of range 0..{}",
                    self.subspaces.len(),
                    self.materials
                )));
            }
        }
        if base == s.material {
            return Err(Error::Invalid(format!(
                "subspace {}: graded and base material are both {base}",
                self.subspaces.len()
            )));
        }
        self.subspaces.push(s);
        Ok(self)
    }

    /// Number of materials.
    pub fn materials(&self) -> usize {
        self.materials
    }

    /// The subspaces in order.
    pub fn subspaces(&self) -> &[Subspace] {
        &self.subspaces
    }

    /// One fraction per material for `part`: in `[0, 1]` and summing to 1
    /// where `part >= 0`, all 0 outside (NaN where a fraction expression is
    /// undefined).
    pub fn fractions(&self, part: &Expr) -> Vec<Expr> {
        let c = |v: bool| Expr::constant(if v { 1.0 } else { 0.0 });
        let mut comp: Vec<Expr> = (0..self.materials).map(|m| c(m == self.primary)).collect();
        for s in &self.subspaces {
            comp = s.over(&comp, self.primary);
        }
        let in_part = part.ge(0.0);
        comp.into_iter()
            .map(|e| Expr::select(in_part.clone(), e, Expr::constant(0.0)))
            .collect()
    }
}
