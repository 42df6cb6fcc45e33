//! [`SlabCheck`]: the exact test that keeps a slab's triangles from
//! crossing. A slab is the space between two consecutive sections; every
//! triangle the angle method makes between them is offered to the slab's
//! check as part of a batch (one tiling), and a batch is accepted only if
//! none of its triangles intersects an accepted triangle or another
//! triangle of the batch, in the sense of `mint_mesh::selfx` (the test
//! `mint check --self-intersections` applies to the whole output: faces
//! sharing a vertex or an edge count only when they overlap beyond it).
//!
//! Triangles of different slabs can meet only in a section plane, where
//! they share contour edges and vertices (and the in-plane edges the
//! branching code places, which it keeps apart itself); caps lie in the
//! planes. So a check per slab is enough for the tubes.
//!
//! Broad phase: a uniform grid over the slab's projection on the section
//! plane, cells of about twice the mean edge length; a triangle is listed
//! in the cells its projection may touch (per column of cells, its extent
//! there, padded by a cell). The narrow phase is exact (Shewchuk's
//! predicates, through `mint_mesh::selfx::faces_intersect`) on the world
//! positions the output file gets, so a batch accepted here is a pair-free
//! part of `mint check --self-intersections` on `--double` output.

use crate::geom2d::{orient, P2};

type P3 = [f64; 3];

/// The triangles accepted so far in one slab, with their grid.
pub struct SlabCheck {
    /// Id of the slab's first vertex; the slab's vertices have consecutive ids.
    base: u32,
    pos: Vec<P3>,
    uv: Vec<P2>,
    /// The positions projected along a coordinate axis (exactly).
    flat: Vec<P2>,
    lo: P2,
    inv: [f64; 2],
    dims: [usize; 2],
    cells: Vec<Vec<u32>>,
    /// Accepted triangles (local ids) and their boxes in space.
    tris: Vec<[u32; 3]>,
    boxes: Vec<(P3, P3)>,
    stamp: Vec<u32>,
    epoch: u32,
}

impl SlabCheck {
    /// A check for the vertices with ids `base..base + pos.len()`: positions
    /// in space and in the section plane. `drop` is the coordinate axis most
    /// nearly along the stack normal: the exact filter works on the
    /// positions with that coordinate dropped (a projection that rounds
    /// nothing).
    pub fn new(base: u32, pos: Vec<P3>, uv: Vec<P2>, drop: usize) -> SlabCheck {
        let flat: Vec<P2> = pos.iter().map(|p| [p[(drop + 1) % 3], p[(drop + 2) % 3]]).collect();
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in &uv {
            for d in 0..2 {
                lo[d] = lo[d].min(p[d]);
                hi[d] = hi[d].max(p[d]);
            }
        }
        let ext = [(hi[0] - lo[0]).max(f64::MIN_POSITIVE), (hi[1] - lo[1]).max(f64::MIN_POSITIVE)];
        // Cells of about twice the mean edge length (vertices in id order
        // run along the contours), at most 8 per vertex.
        let mean = uv.windows(2).map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1])).sum::<f64>() / uv.len().max(2) as f64;
        let mut h = (2.0 * mean).max(ext[0].max(ext[1]) / 4096.0);
        let count = |h: f64| [((ext[0] / h) as usize).clamp(1, 4096), ((ext[1] / h) as usize).clamp(1, 4096)];
        let mut dims = count(h);
        while dims[0] * dims[1] > 8 * uv.len() + 16 {
            h *= 1.25;
            dims = count(h);
        }
        let inv = [dims[0] as f64 / ext[0], dims[1] as f64 / ext[1]];
        SlabCheck { base, pos, uv, flat, lo, inv, dims, cells: vec![Vec::new(); dims[0] * dims[1]], tris: Vec::new(), boxes: Vec::new(), stamp: Vec::new(), epoch: 0 }
    }

    /// Position in space of the vertex with global id `id`.
    pub fn point(&self, id: u32) -> P3 {
        self.pos[(id - self.base) as usize]
    }

    fn cell(&self, p: P2, d: usize) -> usize {
        (((p[d] - self.lo[d]) * self.inv[d]).floor().max(0.0) as usize).min(self.dims[d] - 1)
    }

    /// The cells the projection of local triangle `t` may touch, as
    /// column ranges `(x, y0, y1)`: per column, the triangle's extent in
    /// that column's strip, padded by a cell on each side (rounding and
    /// non-axis frames), so that two triangles whose projections meet share
    /// a cell. A long thin triangle lists O(w + h) cells, not its box's w·h.
    fn columns(&self, t: [u32; 3]) -> Vec<(usize, usize, usize)> {
        let q = t.map(|i| self.uv[i as usize]);
        let xlo = q[0][0].min(q[1][0]).min(q[2][0]);
        let xhi = q[0][0].max(q[1][0]).max(q[2][0]);
        let (c0, c1) = (self.cell([xlo, 0.0], 0), self.cell([xhi, 0.0], 0));
        let ylast = self.dims[1] - 1;
        let mut out = Vec::with_capacity(c1 - c0 + 1);
        for c in c0..=c1 {
            // The strip of column c (the end columns reach to the triangle).
            let sx0 = if c == c0 { xlo } else { self.lo[0] + c as f64 / self.inv[0] };
            let sx1 = if c == c1 { xhi } else { self.lo[0] + (c + 1) as f64 / self.inv[0] };
            let (mut ylo, mut yhi) = (f64::INFINITY, f64::NEG_INFINITY);
            for k in 0..3 {
                let (a, b) = (q[k], q[(k + 1) % 3]);
                if a[0] >= sx0 && a[0] <= sx1 {
                    ylo = ylo.min(a[1]);
                    yhi = yhi.max(a[1]);
                }
                for x in [sx0, sx1] {
                    if (a[0] - x) * (b[0] - x) < 0.0 {
                        let y = a[1] + (b[1] - a[1]) * ((x - a[0]) / (b[0] - a[0]));
                        ylo = ylo.min(y);
                        yhi = yhi.max(y);
                    }
                }
            }
            if ylo > yhi {
                // Rounding left the strip empty: take the whole box height.
                ylo = q[0][1].min(q[1][1]).min(q[2][1]);
                yhi = q[0][1].max(q[1][1]).max(q[2][1]);
            }
            let (y0, y1) = (self.cell([0.0, ylo], 1), self.cell([0.0, yhi], 1));
            out.push((c, y0.saturating_sub(1), (y1 + 1).min(ylast)));
        }
        out
    }

    fn local(&self, f: [u32; 3]) -> [u32; 3] {
        f.map(|i| {
            debug_assert!(i >= self.base && ((i - self.base) as usize) < self.pos.len(), "vertex {i} is not in this slab");
            i - self.base
        })
    }

    fn push(&mut self, t: [u32; 3]) {
        let p = t.map(|i| self.pos[i as usize]);
        let b = ([0, 1, 2].map(|d| p[0][d].min(p[1][d]).min(p[2][d])), [0, 1, 2].map(|d| p[0][d].max(p[1][d]).max(p[2][d])));
        let k = self.tris.len() as u32;
        for (x, y0, y1) in self.columns(t) {
            for y in y0..=y1 {
                self.cells[x * self.dims[1] + y].push(k);
            }
        }
        self.tris.push(t);
        self.boxes.push(b);
        self.stamp.push(0);
    }

    fn pop(&mut self) {
        let t = self.tris.pop().expect("a triangle to take back");
        self.boxes.pop();
        self.stamp.pop();
        for (x, y0, y1) in self.columns(t) {
            for y in y0..=y1 {
                self.cells[x * self.dims[1] + y].pop();
            }
        }
    }

    /// The first accepted (or earlier in the batch) triangle that the
    /// latest pushed triangle intersects.
    fn clash_of_last(&mut self) -> Option<usize> {
        self.clashes_of_last(true).into_iter().next()
    }

    /// Every accepted (or earlier) triangle the latest one intersects.
    fn all_clashes_of_last(&mut self) -> Vec<usize> {
        self.clashes_of_last(false)
    }

    fn clashes_of_last(&mut self, first_only: bool) -> Vec<usize> {
        let mut found = Vec::new();
        let k = self.tris.len() - 1;
        let t = self.tris[k];
        let b = self.boxes[k];
        self.epoch = self.epoch.wrapping_add(1);
        if self.epoch == 0 {
            self.stamp.iter_mut().for_each(|s| *s = 0);
            self.epoch = 1;
        }
        for (x, y0, y1) in self.columns(t) {
            for y in y0..=y1 {
                let c = x * self.dims[1] + y;
                for idx in 0..self.cells[c].len() {
                    let o = self.cells[c][idx] as usize;
                    if o == k || self.stamp[o] == self.epoch {
                        continue;
                    }
                    self.stamp[o] = self.epoch;
                    let u = self.tris[o];
                    if t.iter().all(|v| u.contains(v)) {
                        // The same three vertices twice: a fin of no volume.
                        found.push(o);
                        if first_only {
                            return found;
                        }
                        continue;
                    }
                    let ob = self.boxes[o];
                    if (0..3).any(|d| ob.1[d] < b.0[d] || b.1[d] < ob.0[d]) {
                        continue;
                    }
                    if apart_in_projection(&self.flat, t, u) {
                        continue;
                    }
                    if mint_mesh::selfx::faces_intersect(&self.pos, t, self.tris[o]) {
                        found.push(o);
                        if first_only {
                            return found;
                        }
                    }
                }
            }
        }
        found
    }

    /// The number of accepted triangles, to [`rollback`](SlabCheck::rollback) to.
    pub fn mark(&self) -> usize {
        self.tris.len()
    }

    /// Takes back every triangle accepted after `mark`.
    pub fn rollback(&mut self, mark: usize) {
        while self.tris.len() > mark {
            self.pop();
        }
    }

    /// The triangles of the batch `faces` (by index in the batch) that
    /// intersect an accepted triangle or another triangle of the batch.
    /// Accepts nothing.
    pub fn clashes(&mut self, faces: &[[u32; 3]]) -> Vec<usize> {
        let start = self.tris.len();
        let mut bad = vec![false; faces.len()];
        for (k, &f) in faces.iter().enumerate() {
            let t = self.local(f);
            self.push(t);
            for o in self.all_clashes_of_last() {
                bad[k] = true;
                if o >= start {
                    bad[o - start] = true;
                }
            }
        }
        self.rollback(start);
        (0..faces.len()).filter(|&k| bad[k]).collect()
    }

    /// Accepts the batch `faces` (global ids) if none of its triangles
    /// intersects an accepted triangle or another one of the batch;
    /// otherwise accepts nothing and returns false.
    pub fn try_add(&mut self, faces: &[[u32; 3]]) -> bool {
        let start = self.tris.len();
        for &f in faces {
            let t = self.local(f);
            self.push(t);
            if self.clash_of_last().is_some() {
                self.rollback(start);
                return false;
            }
        }
        true
    }
}

/// True if the projections of triangles `a` and `b` (indices into `flat`)
/// show that they meet at most in the vertices they share, so that they do
/// not intersect in space either: a line (through an edge of one of them)
/// has the one triangle on one side and the other strictly on the other,
/// touching the line only at shared vertices. Exact (`orient2d` signs);
/// false when unsure.
fn apart_in_projection(flat: &[P2], a: [u32; 3], b: [u32; 3]) -> bool {
    let shared = a.iter().filter(|v| b.contains(v)).count();
    if shared >= 2 {
        return false;
    }
    for (s, t) in [(a, b), (b, a)] {
        for k in 0..3 {
            let (e0, e1, r) = (s[k], s[(k + 1) % 3], s[(k + 2) % 3]);
            let (p, q) = (flat[e0 as usize], flat[e1 as usize]);
            let side = orient(p, q, flat[r as usize]);
            if side == 0.0 {
                continue;
            }
            // Every vertex of t strictly on the other side, except a vertex
            // shared with s at an end of this edge (then the other two must
            // be strictly across).
            let ok = t.iter().all(|&v| {
                if v == e0 || v == e1 {
                    return true;
                }
                let o = orient(p, q, flat[v as usize]);
                o != 0.0 && (o > 0.0) != (side > 0.0)
            });
            if ok && !t.contains(&r) {
                return true;
            }
        }
    }
    false
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crossing_batches_are_refused_and_leave_nothing_behind() {
        // A unit square below, the same square above; vertices 10..18.
        let pos: Vec<P3> = vec![
            [0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [1.0, 1.0, 1.0], [0.0, 1.0, 1.0],
        ];
        let uv: Vec<P2> = pos.iter().map(|p| [p[0], p[1]]).collect();
        let mut c = SlabCheck::new(10, pos, uv, 2);
        // The front wall y = 0.
        assert!(c.try_add(&[[10, 11, 14], [11, 15, 14]]));
        // Two diagonal triangles (planes x = y and x + y = 1) that cross
        // each other: refused together, and nothing is left behind.
        assert!(!c.try_add(&[[10, 12, 16], [11, 13, 17]]));
        assert_eq!(c.tris.len(), 2);
        // One of them alone touches the wall only at a shared vertex.
        assert!(c.try_add(&[[10, 12, 16]]));
        assert!(!c.try_add(&[[11, 13, 17]]));
        // Folded onto the wall across a shared edge: refused.
        assert!(!c.try_add(&[[10, 11, 15]]));
        // The same three vertices as an accepted triangle.
        assert!(!c.try_add(&[[16, 12, 10]]));
        assert_eq!(c.tris.len(), 3);
        let m = c.mark();
        assert!(c.try_add(&[[12, 13, 17]]));
        c.rollback(m);
        assert_eq!(c.tris.len(), 3);
    }
}
