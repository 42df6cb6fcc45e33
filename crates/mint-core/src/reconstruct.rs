//! Reconstruction: a run of grid layers (a *slab*) → vertices and triangles
//! (Rocchini et al. 2001, §2.3).
//!
//! Input: the sorted, filtered intercepts of planes `k0 ..= k1` (see
//! [`crate::intercept`]). Plane `k` holds the family-A and -B intercepts lying
//! in it and the family-S intercepts of layer `k` (between planes `k` and
//! `k+1`). The slab *owns* planes `k0 .. k1`: it emits their intercepts as
//! vertices, in sorted order. Plane `k1` belongs to the next slab; the slab
//! only refers to its A and B intercepts, which sort before its S ones, so
//! their ranks are the same in both slabs. A vertex's id is therefore
//! `(intercepts of all earlier planes) + rank`, whatever the partition into
//! slabs: a seam gets exactly one vertex per intercept, and the output bytes
//! do not depend on slab sizes.
//!
//! Node states come from family-A lines (the orientation rule: inside after
//! an entering intercept). Every cell with an intercept on one of its 12 edges
//! is *active*; its 8 states make the code for [`mc_table`](crate::mc_table).
//! A cell is *canonical* when every edge whose end states differ carries
//! exactly one intercept of the right sign and every other edge none; other
//! cells are counted, listed, and not triangulated (hole closing fills them).

use crate::grid::Grid;
use crate::intercept::{Intercept, PlaneLines, FAMILY_A, FAMILY_B, FAMILY_S};
use crate::mc_table::{corner_offset, mc_table, EDGE_CORNERS};

/// Counters of one reconstruction.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct SlabStats {
    pub vertices: u64,
    pub faces: u64,
    pub active_cells: u64,
    pub non_canonical_cells: u64,
}

impl std::ops::AddAssign for SlabStats {
    fn add_assign(&mut self, o: SlabStats) {
        self.vertices += o.vertices;
        self.faces += o.faces;
        self.active_cells += o.active_cells;
        self.non_canonical_cells += o.non_canonical_cells;
    }
}

/// What one slab produced. Face indices are slab-local: add the number of
/// vertices emitted by all earlier slabs to get global ids.
#[derive(Debug, Default, Clone)]
pub struct SlabResult {
    /// World positions of the owned planes' intercepts, in id order.
    pub vertices: Vec<[f64; 3]>,
    pub faces: Vec<[u32; 3]>,
    /// Non-canonical cells, as world-axis cell coordinates (at most `max_listed`).
    pub non_canonical: Vec<[u32; 3]>,
    /// Robust path: ids ([`crate::holes::cell_id`]) of cells with a
    /// synthesized vertex on an edge, i.e. cells that cap a hole.
    pub hole_cells: Vec<u64>,
    pub stats: SlabStats,
}

/// The local grid position of an intercept.
#[inline]
pub fn intercept_local_position(r: &Intercept, nb: u32) -> [f64; 3] {
    let k = r.plane as f64;
    match r.family() {
        FAMILY_A => [r.value(), r.index() as f64, k],
        FAMILY_B => [r.index() as f64, r.value(), k],
        _ => [(r.index() / (nb + 1)) as f64, (r.index() % (nb + 1)) as f64, r.value()],
    }
}

/// Reconstructs layers `k0 .. k0 + planes.len() - 1` from `planes[i]` =
/// sorted, filtered intercepts of plane `k0 + i`. The last plane is the
/// boundary plane owned by the next slab (it may be empty at the top).
pub fn reconstruct_slab(grid: &Grid, k0: u32, planes: &[Vec<Intercept>], max_listed: usize) -> SlabResult {
    assert!(!planes.is_empty());
    let [na, nb, _] = grid.local_dims();
    let owned = planes.len() - 1;
    let mut bases = Vec::with_capacity(planes.len());
    let mut total = 0u64;
    for p in planes {
        bases.push(total as u32);
        total += p.len() as u64;
    }
    let mut out = SlabResult::default();
    let owned_vertices: usize = planes[..owned].iter().map(|p| p.len()).sum();
    out.vertices.reserve(owned_vertices);
    let axes = grid.local_axes();
    let mut cells = Vec::new();
    for layer in 0..owned {
        for r in &planes[layer] {
            out.vertices.push(grid.to_world(intercept_local_position(r, nb)));
        }
        let k = k0 + layer as u32;
        let lower = PlaneLines::new(&planes[layer]);
        let upper = PlaneLines::new(&planes[layer + 1]);
        active_cells(&lower, &upper, na, nb, &mut cells);
        out.stats.active_cells += cells.len() as u64;
        let mut cx = LayerCursor { lower, upper, lower_base: bases[layer], upper_base: bases[layer + 1], k, nb };
        for &id in &cells {
            let (i, j) = ((id % na as u64) as u32, (id / na as u64) as u32);
            match cx.cell(i, j) {
                Some((code, ids)) => {
                    for t in mc_table().triangles(code) {
                        out.faces.push(t.map(|e| ids[e as usize]));
                    }
                }
                None => {
                    out.stats.non_canonical_cells += 1;
                    if out.non_canonical.len() < max_listed {
                        let mut w = [0u32; 3];
                        w[axes[0]] = i;
                        w[axes[1]] = j;
                        w[axes[2]] = k;
                        out.non_canonical.push(w);
                    }
                }
            }
        }
    }
    out.stats.vertices = out.vertices.len() as u64;
    out.stats.faces = out.faces.len() as u64;
    out
}

/// Collects the ids `j * na + i` of the cells of the layer between `lower`
/// and `upper` that have an intercept on an edge, sorted and unique.
pub(crate) fn active_cells(lower: &PlaneLines, upper: &PlaneLines, na: u32, nb: u32, cells: &mut Vec<u64>) {
    cells.clear();
    let mut mark = |i: i64, j: i64| {
        if i >= 0 && j >= 0 && (i as u32) < na && (j as u32) < nb {
            cells.push(j as u64 * na as u64 + i as u64);
        }
    };
    for (plane, with_s) in [(lower, true), (upper, false)] {
        for r in plane.records() {
            let idx = r.index() as i64;
            match r.family() {
                FAMILY_A => {
                    let (i, j) = (r.cell() as i64, idx);
                    mark(i, j - 1);
                    mark(i, j);
                }
                FAMILY_B => {
                    let (i, j) = (idx, r.cell() as i64);
                    mark(i - 1, j);
                    mark(i, j);
                }
                _ if with_s => {
                    let (i, j) = (idx / (nb as i64 + 1), idx % (nb as i64 + 1));
                    mark(i - 1, j - 1);
                    mark(i, j - 1);
                    mark(i - 1, j);
                    mark(i, j);
                }
                _ => {}
            }
        }
    }
    cells.sort_unstable();
    cells.dedup();
}

struct LayerCursor<'a> {
    lower: PlaneLines<'a>,
    upper: PlaneLines<'a>,
    lower_base: u32,
    upper_base: u32,
    k: u32,
    nb: u32,
}

impl LayerCursor<'_> {
    /// The code and per-edge vertex ids of cell (i, j), or None if the cell
    /// is not canonical.
    fn cell(&mut self, i: u32, j: u32) -> Option<(u8, [u32; 12])> {
        let planes = [&self.lower, &self.upper];
        let bases = [self.lower_base, self.upper_base];
        let mut code = 0u8;
        let mut a_lines = [[0..0, 0..0], [0..0, 0..0]]; // [z][y]
        for z in 0..2 {
            for y in 0..2 {
                a_lines[z][y] = planes[z].line(FAMILY_A, j + y as u32);
            }
        }
        for c in 0..8u8 {
            let [x, y, z] = corner_offset(c);
            if planes[z as usize].state_before(a_lines[z as usize][y as usize].clone(), i + x) {
                code |= 1 << c;
            }
        }
        let mut ids = [u32::MAX; 12];
        for e in 0..12u8 {
            let [c0, c1] = EDGE_CORNERS[e as usize];
            let s0 = (code >> c0) & 1 == 1;
            let s1 = (code >> c1) & 1 == 1;
            let o = corner_offset(c0);
            let (plane, range) = match e / 4 {
                0 => {
                    let z = o[2] as usize;
                    (z, planes[z].in_cell(a_lines[z][o[1] as usize].clone(), i))
                }
                1 => {
                    let z = o[2] as usize;
                    let line = planes[z].line(FAMILY_B, i + o[0]);
                    (z, planes[z].in_cell(line, j))
                }
                _ => {
                    let idx = (i + o[0]) * (self.nb + 1) + (j + o[1]);
                    let line = self.lower.line(FAMILY_S, idx);
                    (0, self.lower.in_cell(line, self.k))
                }
            };
            if s0 == s1 {
                if !range.is_empty() {
                    return None;
                }
                continue;
            }
            if range.len() != 1 {
                return None;
            }
            let r = planes[plane].records()[range.start];
            if r.entering() != s1 {
                return None;
            }
            ids[e as usize] = bases[plane] + range.start as u32;
        }
        Some((code, ids))
    }
}

/// Resamples a triangle soup held in memory: discretize, filter, reconstruct
/// as one slab, and push the result into `sink`. For tests and small inputs;
/// the out-of-core pipeline does the same per slab.
pub fn resample_in_core<I>(grid: &Grid, triangles: I, sink: &mut dyn crate::MeshSink) -> Result<SlabResult, crate::SinkError>
where
    I: IntoIterator<Item = [[f64; 3]; 3]>,
{
    let mut planes = discretize_in_core(grid, triangles);
    for p in &mut planes {
        crate::intercept::filter_plane(p);
    }
    let result = reconstruct_slab(grid, 0, &planes, usize::MAX);
    for v in &result.vertices {
        sink.vertex(*v)?;
    }
    for f in &result.faces {
        sink.face(*f)?;
    }
    Ok(result)
}

/// The raw intercepts of `triangles` (world coordinates), per plane.
pub(crate) fn discretize_in_core<I>(grid: &Grid, triangles: I) -> Vec<Vec<Intercept>>
where
    I: IntoIterator<Item = [[f64; 3]; 3]>,
{
    let [_, nb, ns] = grid.local_dims();
    let mut planes: Vec<Vec<Intercept>> = vec![Vec::new(); ns as usize + 1];
    for t in triangles {
        let local = t.map(|p| grid.to_local(p));
        crate::discretize::discretize_triangle(&local, |c| {
            let r = crossing_to_intercept(&c, nb);
            planes[r.plane as usize].push(r);
        });
    }
    planes
}

/// Packs a crossing of a triangle in local grid coordinates into its record.
#[inline]
pub fn crossing_to_intercept(c: &crate::Crossing, nb: u32) -> Intercept {
    match c.family as u32 {
        FAMILY_A => Intercept::new(c.v as u32, FAMILY_A, c.u as u32, c.value, c.entering),
        FAMILY_B => Intercept::new(c.u as u32, FAMILY_B, c.v as u32, c.value, c.entering),
        _ => Intercept::new(c.cell as u32, FAMILY_S, c.u as u32 * (nb + 1) + c.v as u32, c.value, c.entering),
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::grid::GridSize;
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
