//! Volumetric extension (consortium draft, namespace
//! `http://schemas.3mf.io/3dmanufacturing/volumetric/2022/01`): 3D images
//! stored as stacks of PNG sheets, functions that sample them, and volume
//! data (colour, material mixing ratios, named properties) attached to a
//! mesh through `v:volumeid`, plus level sets (an object whose shape is a
//! function's zero set inside a bounding mesh).
//!
//! Image layout: voxel `(ix, iy, iz)` sits at UVW `((ix + 1/2) / nx,
//! (iy + 1/2) / ny, (iz + 1/2) / nz)`: columns are U, rows V, sheets W. The
//! specification puts the last PNG row at the front (V = 0), like 2D
//! textures, so the writer stores `iy = 0` in the bottom row of each PNG
//! and the reader flips back.

use crate::error::{Error, Result};
use crate::model::Transform;

/// Channels of the PNG sheets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PixelLayout {
    /// Greyscale.
    Y,
    /// Greyscale and alpha.
    YA,
    /// Red, green, blue.
    Rgb,
    /// Red, green, blue, alpha.
    Rgba,
}

impl PixelLayout {
    /// Channels per pixel.
    pub fn channels(self) -> usize {
        match self {
            PixelLayout::Y => 1,
            PixelLayout::YA => 2,
            PixelLayout::Rgb => 3,
            PixelLayout::Rgba => 4,
        }
    }

    fn color_type(self) -> png::ColorType {
        match self {
            PixelLayout::Y => png::ColorType::Grayscale,
            PixelLayout::YA => png::ColorType::GrayscaleAlpha,
            PixelLayout::Rgb => png::ColorType::Rgb,
            PixelLayout::Rgba => png::ColorType::Rgba,
        }
    }

    /// Index of the stored channel that the sampled channel `c` (0 red,
    /// 1 green, 2 blue, 3 alpha) reads, or `None` for an absent alpha (1).
    pub fn source(self, c: usize) -> Option<usize> {
        match (self, c) {
            (PixelLayout::Y | PixelLayout::YA, 0..=2) => Some(0),
            (PixelLayout::YA, 3) => Some(1),
            (PixelLayout::Rgb | PixelLayout::Rgba, 0..=2) => Some(c),
            (PixelLayout::Rgba, 3) => Some(3),
            _ => None,
        }
    }
}

/// Largest voxel count of one image (the spec allows 1024^5; this crate
/// holds images in memory and stops at 2^31 samples).
pub const MAX_SAMPLES: u64 = 1 << 31;

/// A `<v:image3d>` with an image stack, samples held in memory.
#[derive(Clone, Debug, PartialEq)]
pub struct Image3D {
    /// Resource id.
    pub id: u32,
    /// Name.
    pub name: Option<String>,
    /// Voxels along U (PNG columns), V (rows), W (sheets).
    pub dims: [usize; 3],
    /// Channels.
    pub layout: PixelLayout,
    /// Bits per channel: 8 or 16.
    pub bit_depth: u8,
    /// Samples, channel fastest, then `ix`, then `iy` (V up), then `iz`.
    pub samples: Vec<u16>,
    /// Part names of the sheets as read (the writer makes its own when empty).
    pub sheet_paths: Vec<String>,
}

impl Image3D {
    /// An image of `dims` voxels whose channels are `f(ix, iy, iz)` in
    /// `[0, 1]` (clamped, quantised to the bit depth).
    pub fn from_fn(
        id: u32,
        dims: [usize; 3],
        layout: PixelLayout,
        bit_depth: u8,
        f: impl Fn(usize, usize, usize) -> [f64; 4],
    ) -> Result<Image3D> {
        check_dims(dims, layout, bit_depth).map_err(Error::BadInput)?;
        let max = ((1u32 << bit_depth) - 1) as f64;
        let nc = layout.channels();
        let mut samples = Vec::with_capacity(dims.iter().product::<usize>() * nc);
        for iz in 0..dims[2] {
            for iy in 0..dims[1] {
                for ix in 0..dims[0] {
                    let v = f(ix, iy, iz);
                    for &c in &v[..nc] {
                        let x = if c.is_nan() { 0.0 } else { c.clamp(0.0, 1.0) };
                        samples.push((x * max).round() as u16);
                    }
                }
            }
        }
        Ok(Image3D {
            id,
            name: None,
            dims,
            layout,
            bit_depth,
            samples,
            sheet_paths: Vec::new(),
        })
    }

    /// Stored channel `c` of a voxel, normalised to `[0, 1]`.
    pub fn value(&self, ix: usize, iy: usize, iz: usize, c: usize) -> f64 {
        let nc = self.layout.channels();
        let i = ((iz * self.dims[1] + iy) * self.dims[0] + ix) * nc + c;
        self.samples[i] as f64 / ((1u32 << self.bit_depth) - 1) as f64
    }

    /// Sampled channel (0 red, 1 green, 2 blue, 3 alpha, with the layout's
    /// substitutions) at UVW, nearest voxel, clamped to the image.
    pub fn sample_nearest(&self, uvw: [f64; 3], channel: usize) -> f64 {
        let idx: [usize; 3] = std::array::from_fn(|a| {
            let t = (uvw[a] * self.dims[a] as f64 - 0.5).round();
            t.clamp(0.0, (self.dims[a] - 1) as f64) as usize
        });
        match self.layout.source(channel) {
            Some(c) => self.value(idx[0], idx[1], idx[2], c),
            None => 1.0,
        }
    }

    /// Encodes sheet `iz` as PNG bytes (deterministic: no time or text
    /// chunks).
    pub fn encode_sheet(&self, iz: usize, part: &str) -> Result<Vec<u8>> {
        let [nx, ny, _] = self.dims;
        let nc = self.layout.channels();
        let mut out = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut out, nx as u32, ny as u32);
            enc.set_color(self.layout.color_type());
            enc.set_depth(if self.bit_depth == 16 {
                png::BitDepth::Sixteen
            } else {
                png::BitDepth::Eight
            });
            enc.set_compression(png::Compression::Best);
            let err = |source| Error::PngEncode {
                part: part.to_string(),
                source,
            };
            let mut w = enc.write_header().map_err(err)?;
            let bytes_per = if self.bit_depth == 16 { 2 } else { 1 };
            let mut data = Vec::with_capacity(nx * ny * nc * bytes_per);
            // PNG rows top first: the top row is the back (largest iy).
            for row in 0..ny {
                let iy = ny - 1 - row;
                let start = ((iz * ny + iy) * nx) * nc;
                for &s in &self.samples[start..start + nx * nc] {
                    if bytes_per == 2 {
                        data.extend_from_slice(&s.to_be_bytes());
                    } else {
                        data.push(s as u8);
                    }
                }
            }
            w.write_image_data(&data).map_err(err)?;
            w.finish().map_err(err)?;
        }
        Ok(out)
    }
}

/// Checks image dimensions, bit depth and size.
pub(crate) fn check_dims(
    dims: [usize; 3],
    _layout: PixelLayout,
    depth: u8,
) -> std::result::Result<(), String> {
    if dims.iter().any(|&d| d == 0 || d > 1 << 30) {
        return Err(format!("image3d dimensions {dims:?} must be in 1..=2^30"));
    }
    if depth != 8 && depth != 16 {
        return Err(format!("image3d bit depth {depth} must be 8 or 16"));
    }
    let n = dims.iter().map(|&d| d as u64).product::<u64>();
    if n > MAX_SAMPLES {
        return Err(format!(
            "image3d of {dims:?} = {n} voxels exceeds the in-memory limit of 2^31"
        ));
    }
    Ok(())
}

/// Texture filter.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Filter {
    /// Trilinear (the default).
    #[default]
    Linear,
    /// Nearest voxel.
    Nearest,
}

/// Behaviour outside `[0, 1]` on one texture axis.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TileStyle {
    /// Periodic (the default).
    #[default]
    Wrap,
    /// Mirrored repetition.
    Mirror,
    /// Clamped to the border.
    Clamp,
}

impl TileStyle {
    /// The attribute value.
    pub fn name(self) -> &'static str {
        match self {
            TileStyle::Wrap => "wrap",
            TileStyle::Mirror => "mirror",
            TileStyle::Clamp => "clamp",
        }
    }

    /// Parses an attribute value.
    pub fn from_name(s: &str) -> Option<TileStyle> {
        [TileStyle::Wrap, TileStyle::Mirror, TileStyle::Clamp]
            .into_iter()
            .find(|t| t.name() == s)
    }
}

/// A `<v:functionfromimage3d>`: samples an image at a normalised position.
/// Its outputs are `color` (vector) and `red`, `green`, `blue`, `alpha`.
#[derive(Clone, Debug, PartialEq)]
pub struct FunctionFromImage3D {
    /// Resource id.
    pub id: u32,
    /// Display name.
    pub display_name: Option<String>,
    /// The image.
    pub image: u32,
    /// Filter.
    pub filter: Filter,
    /// Added to the sampled value.
    pub value_offset: f64,
    /// Multiplies the sampled value.
    pub value_scale: f64,
    /// Tile style on U, V, W.
    pub tile: [TileStyle; 3],
}

impl FunctionFromImage3D {
    /// Samples `image` with the default filter, tiling clamped.
    pub fn new(id: u32, image: u32) -> FunctionFromImage3D {
        FunctionFromImage3D {
            id,
            display_name: None,
            image,
            filter: Filter::Linear,
            value_offset: 0.0,
            value_scale: 1.0,
            tile: [TileStyle::Clamp; 3],
        }
    }
}

/// A reference from volume data to a function output.
#[derive(Clone, Debug, PartialEq)]
pub struct FunctionRef {
    /// The function resource.
    pub function: u32,
    /// Output name (`red`, `color`, ... for image functions).
    pub channel: String,
    /// Object coordinates to function coordinates.
    pub transform: Transform,
    /// Smallest feature size hint (0: none).
    pub min_feature_size: f64,
    /// Value where the function is undefined.
    pub fallback: f64,
}

impl FunctionRef {
    /// `channel` of `function`, with the transform from object coordinates.
    pub fn new(function: u32, channel: &str, transform: Transform) -> FunctionRef {
        FunctionRef {
            function,
            channel: channel.to_string(),
            transform,
            min_feature_size: 0.0,
            fallback: 0.0,
        }
    }
}

/// Material mixing: one contribution per base material.
#[derive(Clone, Debug, PartialEq)]
pub struct Composite {
    /// The `<basematerials>` resource mixed.
    pub base_materials: u32,
    /// One mapping per base material, in order: the material's mixing
    /// contribution (the ratio is this value over the sum of all).
    pub mappings: Vec<FunctionRef>,
}

/// A named scalar or vector property.
#[derive(Clone, Debug, PartialEq)]
pub struct Property {
    /// Qualified name (prefix declared on the model, e.g. `mf:density`).
    pub name: String,
    /// Whether a consumer must support it.
    pub required: bool,
    /// Its values.
    pub value: FunctionRef,
}

/// A `<v:volumedata>` resource.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct VolumeData {
    /// Resource id.
    pub id: u32,
    /// Material mixing ratios.
    pub composite: Option<Composite>,
    /// Colour (a vector output).
    pub color: Option<FunctionRef>,
    /// Other properties.
    pub properties: Vec<Property>,
}

/// A `<v:levelset>` object: the shape is the zero set of a function's scalar
/// output inside a bounding mesh. The consortium's examples (a sphere as
/// `length(pos) - radius`) take the inside where the value is negative, the
/// opposite of microfrep's `f >= 0`: a model written as a level set must be
/// negated (see [`crate::from_core::levelset_function`]).
#[derive(Clone, Debug, PartialEq)]
pub struct LevelSet {
    /// The function.
    pub function: u32,
    /// Its scalar output used.
    pub channel: String,
    /// Object coordinates to function coordinates.
    pub transform: Transform,
    /// Smallest feature size hint.
    pub min_feature_size: f64,
    /// Value where the function is undefined.
    pub fallback: f64,
    /// The closed mesh bounding the evaluation.
    pub mesh: u32,
    /// Only the mesh's bounding box bounds the evaluation.
    pub mesh_bbox_only: bool,
    /// Volume data of the shape.
    pub volume_id: Option<u32>,
}
