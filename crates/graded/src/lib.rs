#![warn(missing_docs)]
//! Functionally graded materials after Park, Crawford and Beaman
//! ("Functionally gradient material design and modeling using hypertexture
//! for solid freeform fabrication"): a part's geometry is an FRep function
//! and, at every point inside, material fractions vary continuously, built
//! from procedural density modulation or from measured data and linked to
//! the geometry through reference surfaces. This crate holds the
//! mathematics and the fabrication output:
//!
//! - [`dmf`]: Perlin's bias and gain (exact conventions there), their
//!   cascade, noise and turbulence modulation;
//! - [`smooth`]: Park's n-ary `union_a` / `intersect_a` in microfrep's sign
//!   convention;
//! - [`depth`]: depth below a reference surface, exact for distance fields,
//!   the normalised function otherwise (accuracy stated there);
//! - [`subspace`]: material subspaces mapped onto a part, turned into one
//!   fraction expression per material;
//! - [`bezier`], [`csv`]: tensor-product and barycentric Bernstein-Bezier
//!   fields, and measured data on a grid read from CSV;
//! - [`dither`]: one material per voxel by 3D error diffusion, stochastic or
//!   ordered dithering, streamed layer by layer;
//! - [`stack`]: RGBA material layer stacks for material jetting and 8-bit
//!   grey stacks for vat printing, with a manifest.
//!
//! Inside is `f >= 0` throughout; units are millimetres.
//!
//! A graded cube, its fractions as expressions, dithered and written as a
//! material stack:
//!
//! ```
//! use microfrep_core::{BatchEval, Expr, Tape};
//! use microfrep_shapes as prims;
//! use microfrep_graded::{dmf, subspace::{MaterialModel, Subspace}};
//! use microfrep_graded::stack::{write_material_stack, MaterialStack, Palette, StackGrid};
//! let p = Expr::xyz();
//! let part = prims::block(&p, &prims::v3([0.0; 3]), &prims::v3([1.0; 3]));
//! // Secondary material rising with height, bias-shaped, in the whole cube.
//! let grading = dmf::bias(&Expr::z(), 0.3);
//! let mut model = MaterialModel::new(2, 0).unwrap();
//! model.push(Subspace::in_box([0.0; 3], [1.0; 3], grading, 1)).unwrap();
//! let mut outputs = vec![part.clone()];
//! outputs.extend(model.fractions(&part));
//! let tape = Tape::with_outputs(&outputs);
//!
//! let grid = StackGrid::new([0.0; 3], [1.0; 3], [0.05, 0.05], 0.05).unwrap();
//! let palette = Palette::parse("rigid=#FFFFFF,soft=#FF0000").unwrap();
//! let mut ev = BatchEval::new(&tape);
//! let mut source = |k: usize, frac: &mut [f32], inside: &mut [bool]| {
//!     let n = grid.nx * grid.ny;
//!     let xs: Vec<f32> = (0..n).map(|q| grid.x(q % grid.nx) as f32).collect();
//!     let ys: Vec<f32> = (0..n).map(|q| grid.y(q / grid.nx) as f32).collect();
//!     let zs = vec![grid.z(k) as f32; n];
//!     let mut v = vec![0.0f32; n];
//!     for out in 0..3 {
//!         ev.eval_output(out, &xs, &ys, &zs, &mut v);
//!         for q in 0..n {
//!             match out {
//!                 0 => inside[q] = v[q] >= 0.0,
//!                 m => frac[q * 2 + m - 1] = v[q],
//!             }
//!         }
//!     }
//! };
//! let dir = std::env::temp_dir().join(format!("graded-doc-{}", std::process::id()));
//! let report = write_material_stack(&dir, &grid, &MaterialStack::new(palette),
//!     &mut source, &|_, _| {}).unwrap();
//! assert_eq!(report.layers, 20);
//! assert_eq!(report.dither.inside, 20 * 20 * 20);
//! // Volume of each material within a voxel of its integral.
//! for m in 0..2 {
//!     assert!((report.dither.counts[m] as f64 - report.dither.integrals[m]).abs() <= 1.0);
//! }
//! std::fs::remove_dir_all(&dir).unwrap();
//! ```

pub mod bezier;
pub mod csv;
pub mod depth;
pub mod dither;
pub mod dmf;
pub mod error;
pub mod smooth;
pub mod stack;
pub mod subspace;

pub use error::{Error, Result};
