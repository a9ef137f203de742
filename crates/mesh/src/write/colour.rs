//! Per-vertex colours from an attribute channel of the model: the channel
//! is evaluated at every vertex (f32 batches, in parallel) and mapped
//! through a [`ColourScale`]. PLY, OBJ and 3MF store the colours
//! ([`super::MeshFormat::stores_colours`]); STL cannot.

use crate::MeshError;
use microfrep_core::{BatchEval, Shape, Tape};
pub use microfrep_io::colormap::{Colormap, ColourScale};
use rayon::prelude::*;

/// Which attribute to colour a mesh by, and how.
#[derive(Clone, Debug, PartialEq)]
pub struct ColourBy {
    /// The channel: a 0-based index into [`Shape::attributes`] (the CLI's
    /// `--color-by K` is 1-based, HyperFun's `s[K]`).
    pub channel: usize,
    /// The colour map.
    pub colormap: Colormap,
    /// Values mapped to the map's first and last colour; `None`: the
    /// channel's smallest and largest finite value over the vertices (see
    /// [`ColourScale::over`]).
    pub range: Option<[f64; 2]>,
}

/// The colours of a mesh's vertices and the scale that made them.
#[derive(Clone, Debug, PartialEq)]
pub struct VertexColours {
    /// One sRGB colour per vertex.
    pub rgb: Vec<[u8; 3]>,
    /// The scale used (its range is the one given, or the data's).
    pub scale: ColourScale,
}

/// Points per parallel evaluation task.
const CHUNK: usize = 4096;

/// The compiled channel `channel` of `shape`, or an error naming how many
/// channels the model has.
pub fn channel_tape(shape: &Shape, channel: usize) -> Result<Tape, MeshError> {
    let attrs = shape.attributes();
    match attrs.get(channel) {
        Some(a) => Ok(Tape::new(&a.expr)),
        None => Err(MeshError::Input(format!(
            "attribute {} does not exist: the model has {} attribute channel(s){}",
            channel + 1,
            attrs.len(),
            if attrs.is_empty() {
                " (a HyperFun model declares them as s[N] and assigns s[1]..s[N])"
            } else {
                ""
            }
        ))),
    }
}

/// The channel `tape` at every point, in f32, in parallel chunks (the
/// result does not depend on the number of threads).
pub fn eval_at(tape: &Tape, points: &[[f32; 3]]) -> Vec<f32> {
    let mut out = vec![0f32; points.len()];
    out.par_chunks_mut(CHUNK)
        .zip(points.par_chunks(CHUNK))
        .for_each_init(
            || BatchEval::new(tape),
            |ev, (o, p)| {
                let axis = |a: usize| -> Vec<f32> { p.iter().map(|q| q[a]).collect() };
                ev.eval(&axis(0), &axis(1), &axis(2), o);
            },
        );
    out
}

/// The scale of `by` over `values`: its range, or the values' own.
pub fn scale_of(by: &ColourBy, values: &[f32]) -> Result<ColourScale, MeshError> {
    match by.range {
        Some([lo, hi]) => ColourScale::new(by.colormap, lo, hi).map_err(MeshError::Input),
        None => Ok(ColourScale::over(
            by.colormap,
            values.iter().map(|&v| v as f64),
        )),
    }
}

/// Colours of `vertices` by the attribute `by` names.
pub fn vertex_colours(
    shape: &Shape,
    by: &ColourBy,
    vertices: &[[f32; 3]],
) -> Result<VertexColours, MeshError> {
    let tape = channel_tape(shape, by.channel)?;
    let values = eval_at(&tape, vertices);
    let scale = scale_of(by, &values)?;
    let rgb = values.par_iter().map(|&v| scale.colour(v as f64)).collect();
    Ok(VertexColours { rgb, scale })
}
