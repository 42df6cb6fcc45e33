//! Holes too large to close: which cells stay open.
//!
//! The robust reconstruction closes every hole: where node states change
//! across an edge that no intercept crosses, it synthesizes a vertex at the
//! edge's midpoint, and the cells around such edges cap the hole
//! (*hole cells*). With `--max-hole K`, connected groups of hole cells
//! (through shared faces) whose bounding box is larger than K cells along
//! some axis are left open instead: those cells emit no triangles, and the
//! surface keeps a boundary loop around the hole.
//!
//! Removing cells from a closed marching-cubes surface keeps every edge on
//! at most two triangles; it keeps every vertex manifold as long as, around
//! each grid edge, the open cells are contiguous (a vertex on that edge has
//! one fan through the four cells; an open pair of diagonal cells would cut
//! it into two). [`open_cells`] therefore grows the open set until no grid
//! edge has exactly two diagonal open cells.
//!
//! Everything here depends only on the set of hole cells, which depends
//! only on the input and the grid, so the output stays independent of the
//! slab partition. The set is small: it grows with the area of the holes in
//! cells, not with the input.

use crate::intercept::{Intercept, FAMILY_A, FAMILY_B};

/// The id of local cell `(i, j, k)`.
#[inline]
pub fn cell_id(c: [u32; 3], dims: [u32; 2]) -> u64 {
    (c[2] as u64 * dims[1] as u64 + c[1] as u64) * dims[0] as u64 + c[0] as u64
}

fn cell_of(id: u64, dims: [u32; 2]) -> [u32; 3] {
    let (na, nb) = (dims[0] as u64, dims[1] as u64);
    [(id % na) as u32, ((id / na) % nb) as u32, (id / (na * nb)) as u32]
}

/// A sorted set of open cells.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct OpenCells {
    ids: Vec<u64>,
}

impl OpenCells {
    pub fn contains(&self, id: u64) -> bool {
        self.ids.binary_search(&id).is_ok()
    }
    pub fn len(&self) -> usize {
        self.ids.len()
    }
    pub fn is_empty(&self) -> bool {
        self.ids.is_empty()
    }
    /// True when every cell around the edge of record `r` is open (its
    /// vertex would be used by no triangle).
    pub fn surrounds(&self, r: &Intercept, dims: [u32; 2]) -> bool {
        if self.ids.is_empty() {
            return false;
        }
        let (c, k) = (r.cell() as i64, r.plane as i64);
        let idx = r.index() as i64;
        // The four cells around the edge, as (i, j, k) offsets.
        let cells: [[i64; 3]; 4] = match r.family() {
            FAMILY_A => [[c, idx - 1, k - 1], [c, idx, k - 1], [c, idx - 1, k], [c, idx, k]],
            FAMILY_B => [[idx - 1, c, k - 1], [idx, c, k - 1], [idx - 1, c, k], [idx, c, k]],
            _ => {
                let (i, j) = (idx / (dims[1] as i64 + 1), idx % (dims[1] as i64 + 1));
                [[i - 1, j - 1, c], [i, j - 1, c], [i - 1, j, c], [i, j, c]]
            }
        };
        cells.iter().all(|q| {
            // Cells outside the grid hold no surface: count them as open.
            q.iter().any(|&x| x < 0) || q[0] >= dims[0] as i64 || q[1] >= dims[1] as i64 || self.contains(cell_id([q[0] as u32, q[1] as u32, q[2] as u32], dims))
        })
    }
}

/// What the hole analysis found.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct HoleStats {
    /// Groups of hole cells small enough to close.
    pub closed: u64,
    /// Groups larger than `max_hole`, left open.
    pub left_open: u64,
}

/// Groups `hole_cells` (any order, duplicates allowed; sorted and
/// deduplicated in place, and with `max_hole` 0 moved into the result) by
/// shared faces and returns the cells of groups wider than `max_hole`
/// cells, grown so that the remaining surface stays vertex-manifold.
pub fn open_cells(hole_cells: &mut Vec<u64>, dims: [u32; 3], max_hole: u32) -> (OpenCells, HoleStats) {
    hole_cells.sort_unstable();
    hole_cells.dedup();
    let d2 = [dims[0], dims[1]];
    let n = hole_cells.len();
    let mut parent: Vec<usize> = (0..n).collect();
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    for a in 0..n {
        let c = cell_of(hole_cells[a], d2);
        for axis in 0..3 {
            let mut q = c;
            q[axis] += 1;
            if q[axis] >= dims[axis] {
                continue;
            }
            if let Ok(b) = hole_cells.binary_search(&cell_id(q, d2)) {
                let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
                if ra != rb {
                    parent[ra.max(rb)] = ra.min(rb);
                }
            }
        }
    }
    let mut stats = HoleStats::default();
    let mut open = Vec::new();
    if max_hole == 0 {
        // Every group is open (a sheet's back and rim): no boxes needed, a
        // third of the memory for the large sets a sheet has.
        stats.left_open = (0..n).filter(|&a| find(&mut parent, a) == a).count() as u64;
        drop(parent);
        open = std::mem::take(hole_cells);
        return grow_open(open, dims, stats);
    }
    // Bounding box per group.
    let mut lo = vec![[u32::MAX; 3]; n];
    let mut hi = vec![[0u32; 3]; n];
    for a in 0..n {
        let r = find(&mut parent, a);
        let c = cell_of(hole_cells[a], d2);
        for d in 0..3 {
            lo[r][d] = lo[r][d].min(c[d]);
            hi[r][d] = hi[r][d].max(c[d]);
        }
    }
    for a in 0..n {
        let r = find(&mut parent, a);
        let wide = (0..3).any(|d| hi[r][d] - lo[r][d] + 1 > max_hole);
        if a == r {
            if wide {
                stats.left_open += 1;
            } else {
                stats.closed += 1;
            }
        }
        if wide {
            open.push(hole_cells[a]);
        }
    }
    grow_open(open, dims, stats)
}

/// Grows the open cells until they are contiguous around every grid edge.
fn grow_open(mut open: Vec<u64>, dims: [u32; 3], stats: HoleStats) -> (OpenCells, HoleStats) {
    let d2 = [dims[0], dims[1]];
    open.sort_unstable();
    open.dedup();
    let mut set = OpenCells { ids: open };
    // Keep open cells contiguous around every grid edge, in rounds: each
    // round opens, for every two diagonal open cells around an edge whose
    // two side cells are closed, the side with the smaller id (checked
    // against the set as the round began). The first round looks at every
    // open cell, later rounds only at the cells the round before opened: a
    // pair that needs a side opened has a cell opened in the round before
    // (older pairs were settled then, and opening cells never unsettles
    // one), and the diagonal relation is symmetric. So the rounds add what
    // looking at every cell would add, at a fraction of the cost on a
    // sheet, whose back and rim are all open.
    let mut frontier: Option<Vec<u64>> = None;
    loop {
        let mut add = Vec::new();
        for &id in frontier.as_deref().unwrap_or(&set.ids) {
            let c = cell_of(id, d2);
            // For each axis, the cell diagonal to c around each of its 4
            // edges parallel to that axis.
            for axis in 0..3 {
                let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
                for (du, dv) in [(-1i64, -1i64), (-1, 1), (1, -1), (1, 1)] {
                    let at = |cu: i64, cv: i64| -> Option<[u32; 3]> {
                        let mut q = [c[0] as i64, c[1] as i64, c[2] as i64];
                        q[u] += cu;
                        q[v] += cv;
                        (q.iter().zip(dims).all(|(&x, n)| x >= 0 && x < n as i64)).then(|| [q[0] as u32, q[1] as u32, q[2] as u32])
                    };
                    let (Some(diag), Some(side1), Some(side2)) = (at(du, dv), at(du, 0), at(0, dv)) else { continue };
                    let (i1, i2) = (cell_id(side1, d2), cell_id(side2, d2));
                    if set.contains(cell_id(diag, d2)) && !set.contains(i1) && !set.contains(i2) {
                        add.push(i1.min(i2));
                    }
                }
            }
        }
        if add.is_empty() {
            return (set, stats);
        }
        add.sort_unstable();
        add.dedup();
        // Merge the sorted additions (none already open) into the set.
        let old = std::mem::take(&mut set.ids);
        let mut merged = Vec::with_capacity(old.len() + add.len());
        let (mut i, mut j) = (0, 0);
        while i < old.len() || j < add.len() {
            if j == add.len() || (i < old.len() && old[i] < add[j]) {
                merged.push(old[i]);
                i += 1;
            } else {
                merged.push(add[j]);
                j += 1;
            }
        }
        set.ids = merged;
        frontier = Some(add);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_groups_close_and_wide_ones_open() {
        let dims = [20, 20, 20];
        let d2 = [20, 20];
        let mut cells: Vec<u64> = (0..3).map(|i| cell_id([i, 0, 0], d2)).collect();
        cells.extend((0..12).map(|i| cell_id([i, 5, 5], d2)));
        let (open, stats) = open_cells(&mut cells, dims, 4);
        assert_eq!(stats, HoleStats { closed: 1, left_open: 1 });
        assert!(open.contains(cell_id([7, 5, 5], d2)));
        assert!(!open.contains(cell_id([1, 0, 0], d2)));
    }

    #[test]
    fn diagonal_open_pairs_are_filled_in() {
        let dims = [10, 10, 10];
        let d2 = [10, 10];
        // Two wide groups that touch only diagonally, around the z edge
        // between cells (5,1,1) and (6,2,1).
        let mut cells: Vec<u64> = (0..6).map(|i| cell_id([i, 1, 1], d2)).collect();
        cells.extend((6..10).map(|i| cell_id([i, 2, 1], d2)));
        let (open, stats) = open_cells(&mut cells, dims, 2);
        assert_eq!(stats.left_open, 2);
        assert!(open.contains(cell_id([6, 1, 1], d2)) || open.contains(cell_id([5, 2, 1], d2)));
    }
}
