//! Slice extension (1.0.2): stacks of closed polygons per layer.
//!
//! A slice covers the z range from the previous slice's `ztop` (or the
//! stack's `zbottom`) to its own `ztop`; `ztop` strictly increases; a layer
//! with no material is a slice with no polygons. Polygons are filled by the
//! positive fill rule of the core specification (winding number above zero),
//! so outer boundaries run counter-clockwise seen from +z and holes
//! clockwise: the orientation of `microfrep_fab::layer_polygons`.
//! [`orient_by_nesting`] fixes the orientation of loops given in any order.
//!
//! Large stacks go to separate model parts (`/2D/...model`) referenced by
//! `<s:sliceref>`, as the specification recommends; see
//! [`crate::write::WriteOptions`].

/// A closed polygon, first vertex not repeated, counter-clockwise for
/// material (seen from +z).
pub type Polygon = Vec<[f64; 2]>;

/// One layer.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Slice {
    /// Top of the layer (model units).
    pub ztop: f64,
    /// Its polygons (may be empty).
    pub polygons: Vec<Polygon>,
}

/// A `<s:slicestack>` resource.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SliceStack {
    /// Resource id.
    pub id: u32,
    /// Bottom of the first slice.
    pub zbottom: f64,
    /// The layers, bottom to top.
    pub slices: Vec<Slice>,
}

impl SliceStack {
    /// A stack from uniform layers: layer `k` spans `[zbottom + k h,
    /// zbottom + (k + 1) h]`.
    pub fn uniform(id: u32, zbottom: f64, layer: f64, layers: Vec<Vec<Polygon>>) -> SliceStack {
        SliceStack {
            id,
            zbottom,
            slices: layers
                .into_iter()
                .enumerate()
                .map(|(k, polygons)| Slice {
                    ztop: zbottom + (k + 1) as f64 * layer,
                    polygons,
                })
                .collect(),
        }
    }
}

/// Signed area of a polygon (positive for counter-clockwise).
pub fn signed_area(p: &[[f64; 2]]) -> f64 {
    let n = p.len();
    (0..n)
        .map(|k| {
            let (a, b) = (p[k], p[(k + 1) % n]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum::<f64>()
        * 0.5
}

/// Whether `q` is inside polygon `p` (even-odd crossing test).
fn contains(p: &[[f64; 2]], q: [f64; 2]) -> bool {
    let mut inside = false;
    let n = p.len();
    for k in 0..n {
        let (a, b) = (p[k], p[(k + 1) % n]);
        if (a[1] > q[1]) != (b[1] > q[1]) {
            let x = a[0] + (q[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1]);
            if q[0] < x {
                inside = !inside;
            }
        }
    }
    inside
}

/// Orients non-crossing loops by how deeply each is nested in the others:
/// even depth (outer boundaries, islands in holes) counter-clockwise, odd
/// depth (holes) clockwise. Bounding boxes skip most pair tests.
pub fn orient_by_nesting(polygons: &mut [Polygon]) {
    let boxes: Vec<[f64; 4]> = polygons
        .iter()
        .map(|p| {
            p.iter().fold(
                [
                    f64::INFINITY,
                    f64::INFINITY,
                    f64::NEG_INFINITY,
                    f64::NEG_INFINITY,
                ],
                |b, v| {
                    [
                        b[0].min(v[0]),
                        b[1].min(v[1]),
                        b[2].max(v[0]),
                        b[3].max(v[1]),
                    ]
                },
            )
        })
        .collect();
    let depth: Vec<usize> = (0..polygons.len())
        .map(|i| {
            let Some(&q) = polygons[i].first() else {
                return 0;
            };
            (0..polygons.len())
                .filter(|&j| {
                    j != i
                        && boxes[j][0] <= boxes[i][0]
                        && boxes[j][1] <= boxes[i][1]
                        && boxes[j][2] >= boxes[i][2]
                        && boxes[j][3] >= boxes[i][3]
                        && contains(&polygons[j], q)
                })
                .count()
        })
        .collect();
    for (p, d) in polygons.iter_mut().zip(depth) {
        let ccw = signed_area(p) > 0.0;
        if ccw != (d % 2 == 0) {
            p.reverse();
        }
    }
}
