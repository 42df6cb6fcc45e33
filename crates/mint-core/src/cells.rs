//! The cells between planes of edge vertices, and the one walk over them
//! that both reconstructions use ([`crate::reconstruct`], the paper's strict
//! rule, and [`crate::robust`], the state-first rule).
//!
//! A slab is given as the sorted vertex records of planes `k0 ..= k1`:
//! plane `k` holds the vertices on the family-A and -B edges lying in it and
//! the family-S vertices of layer `k` (between planes `k` and `k + 1`).
//! [`walk_slab`] emits the vertices of the owned planes `k0 .. k1` in record
//! order, so a vertex's id is `(records of all earlier planes) + rank`
//! whatever the slab partition, and visits every *active* cell (a cell with
//! a record on one of its 12 edges) of each owned layer in id order. The
//! caller decides each cell's corner code and vertices; [`Layer::edge`]
//! finds the records of one cell edge, and [`push_cell_triangles`] turns a
//! code and its edge vertices into triangles by [`mc_table`].

use crate::grid::Grid;
use crate::intercept::{Intercept, PlaneLines, FAMILY_A, FAMILY_B, FAMILY_S};
use crate::mc_table::{corner_offset, mc_table, EDGE_CORNERS};
use std::ops::Range;

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
    /// World positions of the owned planes' vertices, in id order.
    pub vertices: Vec<[f64; 3]>,
    pub faces: Vec<[u32; 3]>,
    /// Strict path: non-canonical cells, as world-axis cell coordinates
    /// (at most the number the caller asked for).
    pub non_canonical: Vec<[u32; 3]>,
    /// Robust path: ids ([`crate::holes::cell_id`]) of cells with a
    /// synthesized vertex on an edge, i.e. cells that cap a hole.
    pub hole_cells: Vec<u64>,
    pub stats: SlabStats,
}

/// The local grid position of a record.
#[inline]
pub fn intercept_local_position(r: &Intercept, nb: u32) -> [f64; 3] {
    let k = r.plane as f64;
    match r.family() {
        FAMILY_A => [r.value(), r.index() as f64, k],
        FAMILY_B => [r.index() as f64, r.value(), k],
        _ => [(r.index() / (nb + 1)) as f64, (r.index() % (nb + 1)) as f64, r.value()],
    }
}

/// Where each A and B line of a plane starts in its records, and where its
/// S records start: a cell edge is then found by one short search within
/// its line (S lines are searched among the S records alone), not two over
/// the whole plane. Built in O(records + na + nb).
struct LineStarts {
    /// `a[j] .. a[j + 1]`: the records of A line `j` (`nb + 2` entries).
    a: Vec<u32>,
    /// `b[i] .. b[i + 1]`: the records of B line `i` (`na + 2` entries).
    b: Vec<u32>,
    /// The first S record.
    s: usize,
}

impl LineStarts {
    fn new(records: &[Intercept], na: u32, nb: u32) -> LineStarts {
        let mut a = vec![0u32; nb as usize + 2];
        let mut b = vec![0u32; na as usize + 2];
        let mut s = records.len();
        for (n, r) in records.iter().enumerate() {
            match r.family() {
                FAMILY_A => a[r.index() as usize + 1] += 1,
                FAMILY_B => b[r.index() as usize + 1] += 1,
                _ => {
                    s = n;
                    break;
                }
            }
        }
        let mut run = 0u32;
        for c in a.iter_mut() {
            run += *c;
            *c = run;
        }
        for c in b.iter_mut() {
            run += *c;
            *c = run;
        }
        // (b's entries continue a's count: B records follow the A records.)
        LineStarts { a, b, s }
    }
}

/// Layer `k` of a slab: the cells between the records of plane `k` (lower)
/// and plane `k + 1` (upper).
pub(crate) struct Layer<'a> {
    planes: [PlaneLines<'a>; 2],
    starts: [LineStarts; 2],
    bases: [u32; 2],
    /// The layer's index within its slab (0 for the slab's first).
    pub(crate) index: usize,
    pub(crate) k: u32,
    pub(crate) na: u32,
    pub(crate) nb: u32,
}

impl<'a> Layer<'a> {
    /// The records of plane 0 (lower) or 1 (upper).
    #[inline]
    pub(crate) fn plane(&self, z: usize) -> &PlaneLines<'a> {
        &self.planes[z]
    }

    /// The output id of record `index` of plane `z`.
    #[inline]
    pub(crate) fn vertex_id(&self, z: usize, index: usize) -> u32 {
        self.bases[z] + index as u32
    }

    /// The records on edge `e` (numbered as in [`mc_table`]) of cell
    /// `(i, j)`: which plane holds them (0 lower, 1 upper) and their index
    /// range there. Family-S edges are held by the lower plane.
    #[inline]
    pub(crate) fn edge(&self, i: u32, j: u32, e: u8) -> (usize, Range<usize>) {
        let o = corner_offset(EDGE_CORNERS[e as usize][0]);
        match e / 4 {
            0 => {
                let z = o[2] as usize;
                let (p, st) = (&self.planes[z], &self.starts[z]);
                let l = (j + o[1]) as usize;
                (z, p.in_cell(st.a[l] as usize..st.a[l + 1] as usize, i))
            }
            1 => {
                let z = o[2] as usize;
                let (p, st) = (&self.planes[z], &self.starts[z]);
                let l = (i + o[0]) as usize;
                (z, p.in_cell(st.b[l] as usize..st.b[l + 1] as usize, j))
            }
            _ => {
                let (p, st) = (&self.planes[0], &self.starts[0]);
                let line = PlaneLines::new(&p.records()[st.s..]).line(FAMILY_S, (i + o[0]) * (self.nb + 1) + (j + o[1]));
                (0, p.in_cell(st.s + line.start..st.s + line.end, self.k))
            }
        }
    }

    /// The ids `j * na + i` of the layer's active cells, sorted and unique.
    fn active_cells(&self, cells: &mut Vec<u64>) {
        let (na, nb) = (self.na, self.nb);
        cells.clear();
        let mut mark = |i: i64, j: i64| {
            if i >= 0 && j >= 0 && (i as u32) < na && (j as u32) < nb {
                cells.push(j as u64 * na as u64 + i as u64);
            }
        };
        for (plane, with_s) in [(&self.planes[0], true), (&self.planes[1], false)] {
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
                    FAMILY_S if with_s => {
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
}

/// Walks the owned layers `k0 .. k0 + planes.len() - 1` of a slab whose
/// planes `k0 ..= k1` hold `planes` (each sorted by
/// [`Intercept::sort_key`]; the last plane belongs to the next slab). It
/// emits the owned planes' vertices into `out.vertices` and calls
/// `cell(layer, i, j, out)` for every active cell of every owned layer, in
/// order; the callback pushes the cell's triangles. The vertex, face and
/// active-cell counts of `out.stats` are set at the end.
pub(crate) fn walk_slab<P: AsRef<[Intercept]>>(
    grid: &Grid,
    k0: u32,
    planes: &[P],
    out: &mut SlabResult,
    mut cell: impl FnMut(&Layer, u32, u32, &mut SlabResult),
) {
    assert!(!planes.is_empty());
    let [na, nb, _] = grid.local_dims();
    let owned = planes.len() - 1;
    let mut bases = Vec::with_capacity(planes.len());
    let mut total = 0u64;
    for p in planes {
        bases.push(total as u32);
        total += p.as_ref().len() as u64;
    }
    out.vertices.reserve(planes[..owned].iter().map(|p| p.as_ref().len()).sum());
    let mut cells = Vec::new();
    for index in 0..owned {
        let records = planes[index].as_ref();
        for r in records {
            out.vertices.push(grid.to_world(intercept_local_position(r, nb)));
        }
        let upper = planes[index + 1].as_ref();
        let layer = Layer {
            planes: [PlaneLines::new(records), PlaneLines::new(upper)],
            starts: [LineStarts::new(records, na, nb), LineStarts::new(upper, na, nb)],
            bases: [bases[index], bases[index + 1]],
            index,
            k: k0 + index as u32,
            na,
            nb,
        };
        layer.active_cells(&mut cells);
        out.stats.active_cells += cells.len() as u64;
        for &id in &cells {
            cell(&layer, (id % na as u64) as u32, (id / na as u64) as u32, out);
        }
    }
    out.stats.vertices = out.vertices.len() as u64;
    out.stats.faces = out.faces.len() as u64;
}

/// Appends the triangles of a cell with corner code `code` (bit `c` set
/// when corner `c` is inside) whose edge `e` carries vertex `ids[e]`.
#[inline]
pub(crate) fn push_cell_triangles(code: u8, ids: &[u32; 12], faces: &mut Vec<[u32; 3]>) {
    for t in mc_table().triangles(code) {
        faces.push(t.map(|e| ids[e as usize]));
    }
}
