//! The regular grid the surface is resampled on.
//!
//! A [`Grid`] is an origin, a cubic cell size `h` and a number of cells per
//! axis. Input coordinates are mapped once, per vertex, to *grid coordinates*
//! `(p - origin) / h`, in which grid nodes sit on integers. Every later
//! decision is exact on those f64 values, so the one rounding step is the same
//! for every face that shares a vertex.
//!
//! The grid also has a *slab axis* (the axis along which the out-of-core store
//! cuts the volume into slabs). All core algorithms work in the *local frame*
//! `(a, b, s)`: a cyclic permutation of `(x, y, z)` whose third axis is the
//! slab axis. A cyclic permutation keeps orientation, so triangles built in
//! the local frame face the same way in the world.
//!
//! The grid keeps one empty cell of padding on every side, so all boundary
//! nodes are outside the solid.

/// World axis index, 0 = x, 1 = y, 2 = z.
pub type Axis = usize;

/// How the user sizes the grid. In a plan: `{"cells": N}` or `{"cell_size": H}`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GridSize {
    /// About this many cells over the bounding box (cubic cells).
    Cells(u64),
    /// This exact cell edge length, in input units.
    CellSize(f64),
}

/// Errors in choosing a grid.
#[derive(Debug, Clone, PartialEq)]
pub enum GridError {
    /// The bounding box is empty or not finite: the input has no usable vertices.
    EmptyBounds,
    /// The cell size is not a positive finite number.
    BadCellSize(f64),
    /// The grid would have more nodes along a line family than record ids can
    /// address; use larger cells.
    TooManyCells { dims: [u64; 3], max_cross_section: u64 },
    /// The box (with its padding) does not fit in f64 along `axis`: its
    /// extent or its far side overflows.
    ExtentOverflow { axis: Axis, min: f64, max: f64 },
    /// A coordinate is so far from the origin, in cells, that grid
    /// coordinates would lose the precision the exact predicates need
    /// (see [`MAX_COORDINATE_CELLS`]).
    CoordinateTooLarge { axis: Axis, value: f64, cell: f64 },
}

impl std::fmt::Display for GridError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            GridError::EmptyBounds => write!(f, "the input has an empty or non-finite bounding box"),
            GridError::BadCellSize(h) => write!(f, "cell size {h} is not a positive finite number"),
            GridError::TooManyCells { dims, max_cross_section } => write!(
                f,
                "grid of {}x{}x{} cells is too fine: a cross-section may have at most {} nodes; use larger cells",
                dims[0], dims[1], dims[2], max_cross_section
            ),
            GridError::ExtentOverflow { axis, min, max } => write!(
                f,
                "the bounding box from {min:e} to {max:e} along {} is too large for f64 arithmetic; scale the input down",
                AXIS_NAMES[*axis]
            ),
            GridError::CoordinateTooLarge { axis, value, cell } => write!(
                f,
                "coordinate {value:e} along {} is more than 2^40 ({:.3e}) cells of {cell:e} from the origin, beyond the precision mint's exact predicates need: use larger cells, or translate the input towards the origin",
                AXIS_NAMES[*axis],
                MAX_COORDINATE_CELLS
            ),
        }
    }
}

impl std::error::Error for GridError {}

/// The largest number of nodes in a cross-section orthogonal to the slab axis
/// (record line ids have 30 bits).
pub const MAX_CROSS_SECTION_NODES: u64 = 1 << 30;

/// The largest |coordinate| / cell size a grid accepts, for the input's
/// coordinates and the grid's own nodes: 2^40. Grid coordinates are then
/// within 2^41 of the grid's nodes' integers, every integer node coordinate
/// is exact in f64, and rounding a coordinate to f64 moves it by at most
/// 2^-12 of a cell, so that the exact predicates see the mesh's shape at the
/// grid's resolution. (A scan in metres at a UTM northing of 5·10^6 may still
/// use cells of 5 µm.) Beyond it, the mesh is refused with
/// [`GridError::CoordinateTooLarge`].
pub const MAX_COORDINATE_CELLS: f64 = (1u64 << 40) as f64;

const AXIS_NAMES: [&str; 3] = ["x", "y", "z"];

/// A regular grid of cubic cells, with its slab axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Grid {
    /// World position of node (0, 0, 0).
    pub origin: [f64; 3],
    /// Edge length of a cell, in world units.
    pub cell: f64,
    /// Number of cells along each world axis (nodes are one more).
    pub dims: [u32; 3],
    /// The world axis along which slabs are cut.
    pub slab_axis: Axis,
}

impl Grid {
    /// Chooses a grid around the bounding box `[min, max]`.
    ///
    /// `offset` shifts the grid by a fraction of a cell along each axis
    /// (default 0; tests use it to place the surface differently). About one
    /// cell of padding (never less than half a cell) is kept on every side. `slab_axis = None` picks the longest
    /// axis (ties go to the lower axis).
    pub fn around(
        min: [f64; 3],
        max: [f64; 3],
        size: GridSize,
        offset: [f64; 3],
        slab_axis: Option<Axis>,
    ) -> Result<Grid, GridError> {
        if (0..3).any(|d| !(min[d].is_finite() && max[d].is_finite() && min[d] <= max[d])) {
            return Err(GridError::EmptyBounds);
        }
        let extent = [max[0] - min[0], max[1] - min[1], max[2] - min[2]];
        if let Some(d) = (0..3).find(|&d| !extent[d].is_finite()) {
            return Err(GridError::ExtentOverflow { axis: d, min: min[d], max: max[d] });
        }
        let cell = match size {
            GridSize::CellSize(h) => {
                if !(h.is_finite() && h > 0.0) {
                    return Err(GridError::BadCellSize(h));
                }
                h
            }
            GridSize::Cells(n) => cell_size_for_count(extent, n.max(1)),
        };
        for d in 0..3 {
            for value in [min[d], max[d]] {
                if !(value.abs() / cell <= MAX_COORDINATE_CELLS) {
                    return Err(GridError::CoordinateTooLarge { axis: d, value, cell });
                }
            }
        }
        let mut dims = [0u64; 3];
        let mut origin = [0.0; 3];
        for d in 0..3 {
            // Cells covering the extent, plus one of padding on each side.
            let inner = (extent[d] / cell).ceil().max(1.0) as u64;
            dims[d] = inner + 2;
            // (Halves first: the sum may overflow; the result is the same.)
            let centre = 0.5 * min[d] + 0.5 * max[d];
            origin[d] = centre - 0.5 * dims[d] as f64 * cell + offset[d] * cell;
            // An offset may push the box against the border: grow to keep the padding.
            if min[d] - origin[d] < 0.5 * cell {
                origin[d] -= cell;
                dims[d] += 1;
            }
            if origin[d] + dims[d] as f64 * cell - max[d] < 0.5 * cell {
                dims[d] += 1;
            }
            if !(origin[d].is_finite() && (origin[d] + dims[d] as f64 * cell).is_finite()) {
                return Err(GridError::ExtentOverflow { axis: d, min: min[d], max: max[d] });
            }
        }
        let slab_axis = slab_axis.unwrap_or_else(|| {
            let mut best = 0;
            for d in 1..3 {
                if dims[d] > dims[best] {
                    best = d;
                }
            }
            best
        });
        let (a, b) = ((slab_axis + 1) % 3, (slab_axis + 2) % 3);
        let cross = (dims[a] + 1) * (dims[b] + 1);
        if cross > MAX_CROSS_SECTION_NODES || dims.iter().any(|&n| n > (1 << 30)) {
            return Err(GridError::TooManyCells { dims, max_cross_section: MAX_CROSS_SECTION_NODES });
        }
        Ok(Grid { origin, cell, dims: dims.map(|n| n as u32), slab_axis })
    }

    /// The world axes of the local frame `(a, b, s)`.
    #[inline]
    pub fn local_axes(&self) -> [Axis; 3] {
        let s = self.slab_axis;
        [(s + 1) % 3, (s + 2) % 3, s]
    }

    /// Cells along the local axes `(a, b, s)`.
    #[inline]
    pub fn local_dims(&self) -> [u32; 3] {
        let ax = self.local_axes();
        [self.dims[ax[0]], self.dims[ax[1]], self.dims[ax[2]]]
    }

    /// Total number of cells.
    pub fn cell_count(&self) -> u64 {
        self.dims.iter().map(|&n| n as u64).product()
    }

    /// Maps a world point to local grid coordinates `(a, b, s)`.
    #[inline]
    pub fn to_local(&self, p: [f64; 3]) -> [f64; 3] {
        let ax = self.local_axes();
        let inv = 1.0 / self.cell;
        [
            (p[ax[0]] - self.origin[ax[0]]) * inv,
            (p[ax[1]] - self.origin[ax[1]]) * inv,
            (p[ax[2]] - self.origin[ax[2]]) * inv,
        ]
    }

    /// Maps local grid coordinates back to a world point.
    #[inline]
    pub fn to_world(&self, q: [f64; 3]) -> [f64; 3] {
        let ax = self.local_axes();
        let mut p = [0.0; 3];
        for i in 0..3 {
            p[ax[i]] = self.origin[ax[i]] + q[i] * self.cell;
        }
        p
    }

    /// The world length of a cell's diagonal.
    pub fn cell_diagonal(&self) -> f64 {
        self.cell * 3f64.sqrt()
    }
}

/// The cubic cell size whose grid over `extent` has about `n` cells (without
/// padding). Solved by bisection on the monotone cell count.
fn cell_size_for_count(extent: [f64; 3], n: u64) -> f64 {
    let longest = extent.iter().cloned().fold(0.0, f64::max);
    if longest <= 0.0 {
        return 1.0;
    }
    let count = |h: f64| -> f64 { extent.iter().map(|&e| (e / h).ceil().max(1.0)).product() };
    let (mut lo, mut hi) = (longest / (n as f64).max(1.0) / 2.0, longest * 2.0);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if count(mid) > n as f64 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_gives_about_n_cells_with_padding() {
        let g = Grid::around([0.0; 3], [1.0, 2.0, 4.0], GridSize::Cells(1000), [0.0; 3], None).unwrap();
        let inner: u64 = g.dims.iter().map(|&n| n as u64 - 2).product();
        assert!((700..=1000).contains(&inner), "{:?}", g.dims);
        assert_eq!(g.slab_axis, 2);
        // The box is at least one cell away from the border.
        let (lo, hi) = (g.to_local([0.0; 3]), g.to_local([1.0, 2.0, 4.0]));
        for d in 0..3 {
            assert!(lo[d] >= 0.5 && hi[d] <= g.local_dims()[d] as f64 - 0.5);
        }
    }

    #[test]
    fn local_frame_round_trips() {
        let g = Grid::around([-1.0; 3], [1.0; 3], GridSize::CellSize(0.1), [0.25, 0.5, 0.0], Some(0)).unwrap();
        let p = [0.3, -0.7, 0.9];
        let q = g.to_world(g.to_local(p));
        for d in 0..3 {
            assert!((p[d] - q[d]).abs() < 1e-12);
        }
        assert_eq!(g.local_axes(), [1, 2, 0]);
        for d in 0..3 {
            let l = g.to_local([-1.0; 3]);
            let h = g.to_local([1.0; 3]);
            assert!(l[d] >= 0.5 && h[d] <= g.local_dims()[d] as f64 - 0.5);
        }
    }

    #[test]
    fn bad_sizes_are_refused() {
        assert_eq!(
            Grid::around([0.0; 3], [1.0; 3], GridSize::CellSize(-1.0), [0.0; 3], None),
            Err(GridError::BadCellSize(-1.0))
        );
        assert_eq!(
            Grid::around([0.0; 3], [f64::NAN; 3], GridSize::Cells(10), [0.0; 3], None),
            Err(GridError::EmptyBounds)
        );
    }

    /// Coordinates of 1e308, a box spanning the whole f64 range, or a
    /// mesh 2^41 cells away from the origin are refused up front (they
    /// used to hang the exact search along the grid lines).
    #[test]
    fn coordinates_beyond_the_predicates_precision_are_refused() {
        let e = Grid::around([0.0, 1e308, 0.0], [1.0, 1e308, 1.0], GridSize::Cells(1000), [0.0; 3], None).unwrap_err();
        assert!(matches!(e, GridError::CoordinateTooLarge { axis: 1, value, .. } if value == 1e308), "{e:?}");
        assert!(e.to_string().contains("1e308 along y"), "{e}");
        let e = Grid::around([-1e308; 3], [1e308; 3], GridSize::Cells(1000), [0.0; 3], None).unwrap_err();
        assert_eq!(e, GridError::ExtentOverflow { axis: 0, min: -1e308, max: 1e308 });
        let far = MAX_COORDINATE_CELLS * 2.0;
        assert!(matches!(
            Grid::around([far, 0.0, 0.0], [far + 1.0, 1.0, 1.0], GridSize::CellSize(1.0), [0.0; 3], None),
            Err(GridError::CoordinateTooLarge { axis: 0, .. })
        ));
        // Just inside the bound: accepted.
        let near = MAX_COORDINATE_CELLS / 2.0;
        assert!(Grid::around([near, 0.0, 0.0], [near + 4.0, 1.0, 1.0], GridSize::CellSize(1.0), [0.0; 3], None).is_ok());
        // A huge cell size whose padding overflows.
        assert!(matches!(
            Grid::around([0.0; 3], [1.0; 3], GridSize::CellSize(1e308), [0.0; 3], None),
            Err(GridError::ExtentOverflow { .. })
        ));
    }
}
