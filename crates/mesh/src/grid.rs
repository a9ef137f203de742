//! The uniform grid of the mesher: cells of size `h` over the box, each box
//! face just beyond a node plane, padded by a cell on every side so the
//! outermost nodes lie outside the clipped solid, and cut into cubic bricks
//! of `brick` cells.

use crate::MeshError;

/// The mesher's uniform grid: node `i` at `origin + h * i` (model units),
/// `cells[a] + 1` nodes per axis, cut into cubic bricks of `brick` cells
/// (the last brick on an axis may be shorter). Made by [`Grid::new`], which
/// checks the bounds and resolution.
#[derive(Clone, Debug)]
pub struct Grid {
    /// Position of node (0, 0, 0).
    pub origin: [f64; 3],
    /// Cell size.
    pub h: f64,
    /// Cells per axis, padding included.
    pub cells: [usize; 3],
    /// Cells per brick side.
    pub brick: usize,
    /// Bricks per axis.
    pub bricks: [usize; 3],
}

/// Largest number of cells on one axis: node indices times 8 edge
/// directions must fit a u64 key with room to spare.
pub const MAX_CELLS: usize = 1 << 16;

/// How far (in cells) a box face lies beyond the node plane inside it:
/// twice the least distance of a vertex from its edge's ends (see
/// `refine`), so vertices on edges that cross a face land on it.
const GAP: f64 = 2e-3;

impl Grid {
    /// Grid with `n` cells on the longest side of `bounds` (min, max).
    pub fn new(bounds: [[f64; 3]; 2], n: usize, brick: usize) -> Result<Grid, MeshError> {
        let [lo, hi] = bounds;
        let ext: [f64; 3] = std::array::from_fn(|a| hi[a] - lo[a]);
        if ext.iter().chain(lo.iter()).any(|v| !v.is_finite()) || ext.iter().any(|&e| e <= 0.0) {
            return Err(MeshError::Input(format!(
                "bounds {lo:?}..{hi:?} must be finite with min < max on every axis"
            )));
        }
        if n == 0 || n > MAX_CELLS - 3 {
            return Err(MeshError::Input(format!(
                "resolution {n} must be between 1 and {}",
                MAX_CELLS - 3
            )));
        }
        let longest = ext.iter().cloned().fold(0.0, f64::max);
        // A gap of GAP cells beyond each face of the longest side (below).
        let h = longest / (n as f64 + 2.0 * GAP);
        // f32 samples must resolve the cells everywhere in the box.
        microfrep_io::precision::check_grid(lo, hi, h)
            .map_err(|e| MeshError::Input(format!("cannot mesh at resolution {n}: {e}")))?;
        // Each face of the box lies a little beyond the nearest node plane
        // inside it: `gap` on the longest side and the lower faces, at
        // least `gap / 2` on the others. A face on a node plane would put
        // the vertices of the edges leaving the box through its nodes a
        // fraction of a cell outside the box (they lie strictly inside
        // their edges); a face just inside a node plane would chamfer the
        // box's edges by a whole cell.
        let gap = GAP * h;
        let mut cells = [0; 3];
        let mut origin = [0.0; 3];
        for a in 0..3 {
            // Node 1 lies `gap` inside the box from the lower face.
            let mut o = lo[a] + gap - h;
            let beyond = |o: f64| {
                let t = (hi[a] - (o + h)) / h;
                (t - t.floor()) * h
            };
            if beyond(o) < 0.5 * gap {
                // The upper face is too close beyond a node: shift both.
                o -= gap;
            }
            // Cells up to the first node beyond the upper face, plus one
            // of padding.
            let inner = ((hi[a] - o) / h).ceil() as usize;
            cells[a] = inner + 1;
            origin[a] = o;
        }
        let bricks = cells.map(|c| c.div_ceil(brick));
        Ok(Grid {
            origin,
            h,
            cells,
            brick,
            bricks,
        })
    }

    /// Grid with cells of size `voxel` (at most): the resolution it implies.
    pub fn resolution_for_voxel(bounds: [[f64; 3]; 2], voxel: f64) -> Result<usize, MeshError> {
        let longest = (0..3)
            .map(|a| bounds[1][a] - bounds[0][a])
            .fold(0.0, f64::max);
        if !(voxel > 0.0 && voxel.is_finite()) {
            return Err(MeshError::Input(format!("voxel size {voxel} must be > 0")));
        }
        let n = (longest / voxel).ceil();
        if !(n >= 1.0 && n <= (MAX_CELLS - 3) as f64) {
            return Err(MeshError::Input(format!(
                "voxel size {voxel} gives {n} cells on the longest side (limit {})",
                MAX_CELLS - 3
            )));
        }
        Ok(n as usize)
    }

    /// Position of node `i` in model units (no bounds check).
    pub fn node_pos(&self, i: [usize; 3]) -> [f64; 3] {
        std::array::from_fn(|a| self.origin[a] + self.h * i[a] as f64)
    }

    /// Linear node index, x fastest.
    pub fn node_index(&self, i: [usize; 3]) -> u64 {
        let nx = self.cells[0] as u64 + 1;
        let ny = self.cells[1] as u64 + 1;
        i[0] as u64 + nx * (i[1] as u64 + ny * i[2] as u64)
    }

    /// Node coordinates of linear index `k`: the inverse of
    /// [`Grid::node_index`].
    pub fn node_from_index(&self, k: u64) -> [usize; 3] {
        let nx = self.cells[0] as u64 + 1;
        let ny = self.cells[1] as u64 + 1;
        [
            (k % nx) as usize,
            ((k / nx) % ny) as usize,
            (k / (nx * ny)) as usize,
        ]
    }

    /// Number of bricks of the grid, all axes together.
    pub fn brick_count(&self) -> usize {
        self.bricks.iter().product()
    }

    /// Linear index of the brick at coordinates `b`, x fastest.
    pub fn brick_index(&self, b: [usize; 3]) -> usize {
        b[0] + self.bricks[0] * (b[1] + self.bricks[1] * b[2])
    }

    /// Brick coordinates of linear index `k`: the inverse of
    /// [`Grid::brick_index`].
    pub fn brick_coords(&self, k: usize) -> [usize; 3] {
        let [bx, by, _] = self.bricks;
        [k % bx, (k / bx) % by, k / (bx * by)]
    }

    /// First node and node count per axis of brick `b` (its closed box).
    pub fn brick_nodes(&self, b: [usize; 3]) -> ([usize; 3], [usize; 3]) {
        let lo = b.map(|v| v * self.brick);
        let n = std::array::from_fn(|a| (self.brick).min(self.cells[a] - lo[a]) + 1);
        (lo, n)
    }

    /// The brick whose half-open node range holds node `i`: it owns the grid
    /// edges that start at `i`.
    pub fn owner_brick(&self, i: [usize; 3]) -> [usize; 3] {
        std::array::from_fn(|a| (i[a] / self.brick).min(self.bricks[a] - 1))
    }

    /// Whether node `i` lies on the outer padding layer (always outside).
    pub fn on_border(&self, i: [usize; 3]) -> bool {
        (0..3).any(|a| i[a] == 0 || i[a] == self.cells[a])
    }
}
