//! The strict reconstruction: a run of grid layers (a *slab*) → vertices
//! and triangles by the paper's rule (Rocchini et al. 2001, §2.3).
//!
//! Input: the sorted, filtered intercepts of planes `k0 ..= k1` (see
//! [`crate::intercept`]); [`crate::cells::walk_slab`] numbers them as
//! vertices and visits the active cells. Node states come from family-A
//! lines (the orientation rule: inside after an entering intercept); a
//! cell's 8 states make the code for [`mc_table`](crate::mc_table). A cell
//! is *canonical* when every edge whose end states differ carries exactly
//! one intercept of the right sign and every other edge none; other cells
//! are counted, listed, and not triangulated (the robust path,
//! [`crate::robust`], closes them).

use crate::cells::{push_cell_triangles, walk_slab, Layer, SlabResult};
use crate::grid::Grid;
use crate::intercept::{Intercept, FAMILY_A};
use crate::mc_table::{corner_offset, EDGE_CORNERS};

/// Reconstructs layers `k0 .. k0 + planes.len() - 1` from `planes[i]` =
/// sorted, filtered intercepts of plane `k0 + i`. The last plane is the
/// boundary plane owned by the next slab (it may be empty at the top).
/// At most `max_listed` non-canonical cells are listed (all are counted).
pub fn reconstruct_slab(grid: &Grid, k0: u32, planes: &[Vec<Intercept>], max_listed: usize) -> SlabResult {
    let axes = grid.local_axes();
    let mut out = SlabResult::default();
    walk_slab(grid, k0, planes, &mut out, |layer, i, j, out| match canonical_cell(layer, i, j) {
        Some((code, ids)) => push_cell_triangles(code, &ids, &mut out.faces),
        None => {
            out.stats.non_canonical_cells += 1;
            if out.non_canonical.len() < max_listed {
                let mut w = [0u32; 3];
                w[axes[0]] = i;
                w[axes[1]] = j;
                w[axes[2]] = layer.k;
                out.non_canonical.push(w);
            }
        }
    });
    out
}

/// The code and per-edge vertex ids of cell (i, j), or None if the cell is
/// not canonical.
fn canonical_cell(layer: &Layer, i: u32, j: u32) -> Option<(u8, [u32; 12])> {
    let mut code = 0u8;
    for c in 0..8u8 {
        let [x, y, z] = corner_offset(c);
        let plane = layer.plane(z as usize);
        if plane.state_before(plane.line(FAMILY_A, j + y), i + x) {
            code |= 1 << c;
        }
    }
    let mut ids = [u32::MAX; 12];
    for e in 0..12u8 {
        let [c0, c1] = EDGE_CORNERS[e as usize];
        let s0 = (code >> c0) & 1 == 1;
        let s1 = (code >> c1) & 1 == 1;
        let (z, range) = layer.edge(i, j, e);
        if s0 == s1 {
            if !range.is_empty() {
                return None;
            }
            continue;
        }
        if range.len() != 1 || layer.plane(z).records()[range.start].entering() != s1 {
            return None;
        }
        ids[e as usize] = layer.vertex_id(z, range.start);
    }
    Some((code, ids))
}

#[cfg(test)]
pub(crate) mod tests {
    use crate::grid::{Grid, GridSize};
    use crate::in_core::resample_in_core;
    use crate::TriMesh;
    use std::collections::HashMap;

    /// A UV sphere as a triangle soup (outward); shared with `robust`'s tests.
    pub(crate) fn sphere(c: [f64; 3], r: f64, n_lat: usize, n_lon: usize) -> Vec<[[f64; 3]; 3]> {
        let p = |i: usize, j: usize| {
            let th = std::f64::consts::PI * i as f64 / n_lat as f64;
            let ph = 2.0 * std::f64::consts::PI * j as f64 / n_lon as f64;
            [c[0] + r * th.sin() * ph.cos(), c[1] + r * th.sin() * ph.sin(), c[2] + r * th.cos()]
        };
        let mut t = Vec::new();
        for i in 0..n_lat {
            for j in 0..n_lon {
                let (a, b, cc, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
                if i != 0 {
                    t.push([a, b, d]);
                }
                if i != n_lat - 1 {
                    t.push([b, cc, d]);
                }
            }
        }
        t
    }

    /// An axis-aligned box with integer corners, 12 triangles, outward.
    pub(crate) fn cube(lo: [f64; 3], hi: [f64; 3]) -> Vec<[[f64; 3]; 3]> {
        let v = |i: usize| [if i & 1 == 0 { lo[0] } else { hi[0] }, if i & 2 == 0 { lo[1] } else { hi[1] }, if i & 4 == 0 { lo[2] } else { hi[2] }];
        let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
        quads.iter().flat_map(|q| [[v(q[0]), v(q[1]), v(q[2])], [v(q[0]), v(q[2]), v(q[3])]]).collect()
    }

    fn assert_watertight(m: &TriMesh) -> f64 {
        let mut half = HashMap::new();
        for f in &m.faces {
            assert!(f[0] != f[1] && f[1] != f[2] && f[0] != f[2]);
            for i in 0..3 {
                assert!(half.insert((f[i], f[(i + 1) % 3]), ()).is_none(), "half-edge twice");
            }
        }
        for &(a, b) in half.keys() {
            assert!(half.contains_key(&(b, a)), "boundary edge {a}-{b}");
        }
        m.faces
            .iter()
            .map(|f| {
                let [a, b, c] = f.map(|i| m.positions[i as usize]);
                (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0])) / 6.0
            })
            .sum()
    }

    #[test]
    fn a_sphere_resamples_to_a_closed_oriented_surface_at_many_offsets() {
        let tris = sphere([0.1, -0.2, 0.3], 1.0, 40, 80);
        for (cells, off) in [(1000u64, [0.0; 3]), (8000, [0.3, 0.1, 0.7]), (30000, [0.5, 0.5, 0.5]), (5000, [0.9, 0.2, 0.4])] {
            for axis in 0..3 {
                let g = Grid::around([-0.9, -1.2, -0.7], [1.1, 0.8, 1.3], GridSize::Cells(cells), off, Some(axis)).unwrap();
                let mut m = TriMesh::default();
                let r = resample_in_core(&g, tris.iter().copied(), &mut m).unwrap();
                assert_eq!(r.stats.non_canonical_cells, 0);
                let vol = assert_watertight(&m);
                let exact = 4.0 / 3.0 * std::f64::consts::PI;
                assert!((vol - exact).abs() < 0.05 * exact + 3.0 * g.cell * 4.0 * std::f64::consts::PI, "vol {vol}");
                // Every vertex lies on the input sphere (within the polygonization error and the margin).
                for p in &m.positions {
                    let d = ((p[0] - 0.1).powi(2) + (p[1] + 0.2).powi(2) + (p[2] - 0.3).powi(2)).sqrt();
                    assert!((d - 1.0).abs() < 0.01 + g.cell * MARGIN_CHECK, "vertex off the surface: {d}");
                }
            }
        }
    }
    const MARGIN_CHECK: f64 = 2.0 * crate::MARGIN;

    #[test]
    fn integer_boxes_on_grid_lines_resample_to_closed_chamfered_boxes() {
        // Box faces lie exactly on grid planes, edges on grid lines, corners on nodes.
        for (lo, hi) in [([0.0, 0.0, 0.0], [3.0, 2.0, 4.0]), ([1.0, -2.0, 5.0], [2.0, 1.0, 6.0])] {
            for axis in 0..3 {
                let g = Grid::around(lo, hi, GridSize::CellSize(1.0), [0.0; 3], Some(axis)).unwrap();
                let mut m = TriMesh::default();
                let r = resample_in_core(&g, cube(lo, hi), &mut m).unwrap();
                assert_eq!(r.stats.non_canonical_cells, 0);
                let vol = assert_watertight(&m);
                // Perturbed nodes sit at +ε, so the kept vertices are a margin
                // below each box plane: the box keeps its size, and marching
                // cubes chamfers its edges by at most half a cell squared per
                // unit of edge length.
                let exact: f64 = (0..3).map(|d| hi[d] - lo[d]).product();
                let edges: f64 = 4.0 * (0..3).map(|d| hi[d] - lo[d]).sum::<f64>();
                assert!(vol <= exact + 1e-9 && vol >= exact - 0.5 * edges, "vol {vol} vs {exact}");
            }
        }
    }
}
