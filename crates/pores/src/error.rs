//! Errors of building a pore structure.

/// Why a pore structure could not be built.
#[derive(Debug, thiserror::Error)]
pub enum PoreError {
    /// The box is empty, inverted or not finite.
    #[error("bounds {lo:?} .. {hi:?} must be finite with min < max on every axis")]
    Bounds {
        /// Lower corner given.
        lo: [f64; 3],
        /// Upper corner given.
        hi: [f64; 3],
    },
    /// The size field gave a value that is not a positive number.
    #[error("pore size {value} at {at:?} must be a positive finite number")]
    Size {
        /// The value.
        value: f64,
        /// Where it was evaluated.
        at: [f64; 3],
    },
    /// The porosity field gave a value that is not a number.
    #[error("porosity {value} at {at:?} is not a finite number")]
    PorosityNotFinite {
        /// The value.
        value: f64,
        /// Where it was evaluated (the cell's centre).
        at: [f64; 3],
    },
    /// A porosity the construction cannot reach.
    #[error(
        "porosity {value} at {at:?} is outside the range the {dim}D pores reach: \
         {min:.4} to {max:.4} (or exactly 0 for a cell without a pore){hint}"
    )]
    PorosityRange {
        /// The value.
        value: f64,
        /// Where it was evaluated (the cell's centre).
        at: [f64; 3],
        /// Smallest porosity reachable.
        min: f64,
        /// Largest porosity reachable.
        max: f64,
        /// 2 or 3.
        dim: usize,
        /// How to reach more, if there is a way.
        hint: &'static str,
    },
    /// Refinement would make too many cells.
    #[error(
        "subdivision would make more than {limit} cells (pore size {size} near {at:?}); \
         give a larger pore size or raise Options::max_cells"
    )]
    TooManyCells {
        /// The limit.
        limit: usize,
        /// Pore size requested where the limit was hit.
        size: f64,
        /// Centre of the cell being split.
        at: [f64; 3],
    },
    /// The structure would need more memory than allowed.
    #[error(
        "{cells} cells need about {} MiB, over the limit of {} MiB; give a larger pore \
         size or raise Options::memory_limit",
        need >> 20,
        limit >> 20
    )]
    Memory {
        /// Cells made by the subdivision.
        cells: usize,
        /// Predicted bytes.
        need: u64,
        /// The limit.
        limit: u64,
    },
    /// Refinement would go deeper than the tree allows.
    #[error("subdivision deeper than {depth} splits (pore size {size} near {at:?})")]
    TooDeep {
        /// Deepest split allowed.
        depth: usize,
        /// Pore size requested there.
        size: f64,
        /// Centre of the cell being split.
        at: [f64; 3],
    },
    /// An option out of its range.
    #[error("option {name} = {value}: {why}")]
    Option {
        /// Which option.
        name: &'static str,
        /// Its value.
        value: f64,
        /// The rule it breaks.
        why: &'static str,
    },
    /// No cell of the box holds any of the part.
    #[error("the part is empty inside the bounds {lo:?} .. {hi:?}")]
    EmptyPart {
        /// Lower corner.
        lo: [f64; 3],
        /// Upper corner.
        hi: [f64; 3],
    },
    /// The part could not be bounded by interval analysis.
    #[error("cannot find the part's bounds; give them explicitly")]
    PartBounds(#[source] microfrep_core::BoundsError),
    /// A pore surface could not be tabulated (its control polyhedron does
    /// not surround the cell's centre).
    #[error("pore of cell {cell} (centre {at:?}) could not be tabulated: {why}")]
    Pore {
        /// Index of the cell.
        cell: usize,
        /// Its centre.
        at: [f64; 3],
        /// What went wrong.
        why: &'static str,
    },
    /// Writing an SVG section failed.
    #[error("cannot make the section's part outline")]
    Section(#[source] microfrep_fab::FabError),
}
