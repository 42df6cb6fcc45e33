//! Marching cubes over a contour stack (Dangl 1998, §2.3), on the
//! resampler's machinery: the stack becomes one more solid on a grid, fed to
//! [`mint_core::reconstruct::reconstruct_slab`].
//!
//! Sources:
//! - M. Dangl 1998, §2.3: N cubes across the bounding box in x and y, the
//!   sections as z planes; node states by point-in-polygon; in-plane edge
//!   vertices interpolated from the real contour, z edges at the midpoint
//!   where nothing better is known.
//! - C. Rocchini, P. Cignoni, F. Ganovelli, C. Montani, P. Pingi, R. Scopigno,
//!   "Marching Intersections: an efficient resampling algorithm for surface
//!   management", SMI 2001: surfaces as signed intersections with grid lines.
//!
//! # Data flow
//! ```text
//! Section (u, v) ──grid units──> SectionLines: per grid line, the exact crossings
//!       │                          of the contours (cell decided by orient2d)
//!       │ A/B intercepts (sign by parity)      │ two consecutive sections
//!       v                                      v
//!   plane records  <──────── S intercepts: nodes whose state differs
//!       │ filter_plane (sort, removal)
//!       v
//!   window of W+1 planes ──reconstruct_slab──> vertices, faces ──> MeshSink
//! ```
//! The grid ([`StackGrid`]) has cubic in-plane cells of size `h = extent /
//! cubes` and one plane per section, plus an empty cap plane below and above
//! (plane `k + 1` is section `k`). Local coordinates are `(a, b, s)` with
//! `a = (u - u0) / h`, `b = (v - v0) / h` and `s` the plane index; the
//! mint-core [`Grid`] is the identity (`cell = 1`, origin 0, slab axis z).
//!
//! # Exactness
//! A grid node `(i, j)` is moved by the infinitesimal `(ε, ε²)`. Family-A
//! lines (along `a`, in plane `s = k`) then sit at `b = j + ε²`, family-B
//! lines at `a = i + ε`: a contour vertex is above an A line iff `y > j`,
//! right of a B line iff `x > i`, and which cell a crossing falls in is the
//! sign of one exact `orient2d` (with the ε terms deciding zeros). Both line
//! families therefore count crossings of rays from the same perturbed node,
//! so they agree on every node's even-odd state, and so do the S lines,
//! which compare the states of the two planes. Crossing *positions* are
//! computed in floating point and clamped [`MARGIN`] inside their cell.
//!
//! # S (between-section) intercepts
//! Where a node's state differs between sections `k` and `k + 1`, the S edge
//! gets one vertex at `t` from plane `k`: `t = d_k / (d_k + d_{k+1})`, where
//! `d` is the node's distance to the nearest contour crossing along the same
//! grid line (A, or B when that is nearer) in each section. This is the
//! zero of the linearly interpolated signed distance; it is exact for
//! locally parallel straight contours and follows sloped walls that the
//! midpoint would turn into steps. When a section has no crossing on either
//! line (an empty cap plane, a contour that ends), nothing is known and the
//! midpoint `t = 1/2` is used, as in the 1998 method: caps sit half a section
//! spacing beyond the end sections.
//!
//! # Streaming and vertex ids
//! Sections arrive one at a time; a plane's records are final once the next
//! section is known (its S intercepts need both). Windows of
//! [`McOptions::window`] layers are reconstructed as slabs: a slab owns planes
//! `k0 .. k1` and refers to plane `k1` by rank, so global ids are the
//! slab-local ids plus the vertices emitted before (see
//! `mint_core::reconstruct`). At most two sections' lines and one window of
//! records are in memory.
//!
//! Without caps the two cap layers are not reconstructed and the last
//! section's in-plane vertices are emitted directly: the surface is open at
//! both ends.

use crate::error::ContourError;
use crate::geom2d::{orient, P2};
use crate::profile::{Section, StackFrame};
use mint_core::intercept::{filter_plane, FAMILY_A, FAMILY_B, FAMILY_S};
use mint_core::cells::intercept_local_position;
use mint_core::reconstruct::reconstruct_slab;
use mint_core::{Grid, Intercept, MeshSink, MARGIN};
use serde::Serialize;
use std::path::Path;

/// Default layers per reconstructed window (memory holds `window + 1` planes).
pub const WINDOW_LAYERS: usize = 8;

/// Options of the marching-cubes method.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct McOptions {
    /// Cubes across the larger side of the stack's bounding box in the
    /// section planes. Default 64.
    pub cubes: u32,
    /// Close the surface with caps half a section spacing beyond the first
    /// and last sections. Default false (open ends).
    pub caps: bool,
    /// Layers reconstructed per window; the output is the same for any
    /// value. Default [`WINDOW_LAYERS`] (8); 0 is taken as 1.
    pub window: usize,
}

impl Default for McOptions {
    fn default() -> Self {
        McOptions { cubes: 64, caps: false, window: WINDOW_LAYERS }
    }
}

/// What one reconstruction did.
#[derive(Debug, Default, Clone, Serialize, PartialEq)]
pub struct McStats {
    /// Grid cells along `u`, `v` and the stack (including padding and caps).
    pub grid_cells: [u32; 3],
    /// In-plane cube size, in input units.
    pub cube_size: f64,
    /// Intercepts kept after the removal filter, and removed.
    pub intercepts_kept: u64,
    pub intercepts_removed: u64,
    /// Between-section intercepts placed by distance interpolation, and at
    /// the midpoint (caps, ending contours).
    pub s_interpolated: u64,
    pub s_midpoint: u64,
    pub active_cells: u64,
    /// Cells the table could not triangulate: always 0 on valid input.
    pub non_canonical_cells: u64,
    pub vertices: u64,
    pub faces: u64,
}

/// What the grid needs to know about a stack (the first pass).
#[derive(Debug, Clone, PartialEq)]
pub struct StackSummary {
    pub frame: StackFrame,
    /// Bounding box of all contour points in `(u, v)`.
    pub uv_min: P2,
    pub uv_max: P2,
    /// Offset of every section along the stack normal, increasing.
    pub offsets: Vec<f64>,
    pub vertices: u64,
    pub contours: u64,
}

impl StackSummary {
    /// Summarises sections held in memory.
    pub fn of(frame: StackFrame, sections: &[Section]) -> StackSummary {
        let mut s = StackSummary::new(frame);
        for sec in sections {
            s.add(sec);
        }
        s
    }

    /// An empty summary to [`add`](StackSummary::add) sections to.
    pub fn new(frame: StackFrame) -> StackSummary {
        StackSummary { frame, uv_min: [f64::INFINITY; 2], uv_max: [f64::NEG_INFINITY; 2], offsets: Vec::new(), vertices: 0, contours: 0 }
    }

    /// Accounts for one more section.
    pub fn add(&mut self, s: &Section) {
        for c in &s.contours {
            for p in &c.uv {
                for d in 0..2 {
                    self.uv_min[d] = self.uv_min[d].min(p[d]);
                    self.uv_max[d] = self.uv_max[d].max(p[d]);
                }
            }
            self.vertices += c.uv.len() as u64;
        }
        self.contours += s.contours.len() as u64;
        self.offsets.push(s.offset);
    }
}

/// The grid of a stack: in-plane cells and the plane offsets.
#[derive(Debug, Clone)]
pub struct StackGrid {
    pub frame: StackFrame,
    /// `(u, v)` of grid node (0, 0).
    pub origin: P2,
    /// In-plane cell size.
    pub h: f64,
    /// The mint-core grid (identity mapping, local = world = grid units).
    pub grid: Grid,
    /// Offset along the normal of every plane: cap, sections, cap.
    pub plane_offsets: Vec<f64>,
}

impl StackGrid {
    /// Chooses the grid for `cubes` cubes across the larger in-plane side.
    pub fn new(summary: &StackSummary, cubes: u32, path: &Path) -> Result<StackGrid, ContourError> {
        let n = summary.offsets.len();
        if n == 0 {
            return Err(ContourError::input(path, "the stack has no sections"));
        }
        let ext = [summary.uv_max[0] - summary.uv_min[0], summary.uv_max[1] - summary.uv_min[1]];
        let longest = ext[0].max(ext[1]);
        if !(longest > 0.0 && longest.is_finite()) || cubes == 0 {
            return Err(ContourError::input(path, "the contours have no extent, or --cubes is 0"));
        }
        let h = longest / cubes as f64;
        let origin = [summary.uv_min[0] - 1.5 * h, summary.uv_min[1] - 1.5 * h];
        let cells = |d: usize| ((summary.uv_max[d] - origin[d]) / h + 1.5).ceil() as u64;
        let (na, nb) = (cells(0), cells(1));
        if (na + 1) * (nb + 1) > mint_core::grid::MAX_CROSS_SECTION_NODES || n as u64 + 1 > (1 << 30) {
            return Err(ContourError::input(path, format!("{cubes} cubes give a {na}x{nb} grid, too fine for 30-bit line ids; use fewer cubes")));
        }
        let gap0 = if n >= 2 { summary.offsets[1] - summary.offsets[0] } else { h };
        let gap1 = if n >= 2 { summary.offsets[n - 1] - summary.offsets[n - 2] } else { h };
        let mut plane_offsets = Vec::with_capacity(n + 2);
        plane_offsets.push(summary.offsets[0] - gap0);
        plane_offsets.extend_from_slice(&summary.offsets);
        plane_offsets.push(summary.offsets[n - 1] + gap1);
        let grid = Grid { origin: [0.0; 3], cell: 1.0, dims: [na as u32, nb as u32, n as u32 + 1], slab_axis: 2 };
        Ok(StackGrid { frame: summary.frame, origin, h, grid, plane_offsets })
    }

    /// Grid coordinates of a `(u, v)` point.
    #[inline]
    pub fn to_grid(&self, p: P2) -> P2 {
        [(p[0] - self.origin[0]) / self.h, (p[1] - self.origin[1]) / self.h]
    }

    /// World position of local grid coordinates `(a, b, s)`.
    #[inline]
    pub fn to_world(&self, q: [f64; 3]) -> [f64; 3] {
        let last = self.plane_offsets.len() - 2;
        let p = (q[2].floor().max(0.0) as usize).min(last);
        let off = self.plane_offsets[p] + (q[2] - p as f64) * (self.plane_offsets[p + 1] - self.plane_offsets[p]);
        self.frame.unproject([self.origin[0] + q[0] * self.h, self.origin[1] + q[1] * self.h], off)
    }
}

/// One crossing of a contour with a grid line: the cell it falls in (exact)
/// and its position along the line (floating point, unclamped).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Cross {
    cell: u32,
    at: f64,
}

/// The crossings of one section with every A line (index `j`) and B line
/// (index `i`), sorted along each line; compressed rows.
#[derive(Debug, Default, Clone)]
pub struct SectionLines {
    a: Vec<Cross>,
    a_start: Vec<u32>,
    b: Vec<Cross>,
    b_start: Vec<u32>,
}

impl SectionLines {
    /// No crossings (a cap plane).
    fn empty(na: u32, nb: u32) -> SectionLines {
        SectionLines { a: Vec::new(), a_start: vec![0; nb as usize + 2], b: Vec::new(), b_start: vec![0; na as usize + 2] }
    }

    #[inline]
    fn a_line(&self, j: u32) -> &[Cross] {
        &self.a[self.a_start[j as usize] as usize..self.a_start[j as usize + 1] as usize]
    }

    #[inline]
    fn b_line(&self, i: u32) -> &[Cross] {
        &self.b[self.b_start[i as usize] as usize..self.b_start[i as usize + 1] as usize]
    }
}

/// Distance from `x` to the nearest crossing position on a line.
#[inline]
fn nearest(line: &[Cross], x: f64) -> f64 {
    let k = line.partition_point(|c| c.at < x);
    let mut d = f64::INFINITY;
    if k < line.len() {
        d = line[k].at - x;
    }
    if k > 0 {
        d = d.min(x - line[k - 1].at);
    }
    d.abs()
}

/// Computes the crossings of a section's contours (in grid units) with all
/// grid lines; see the module docs for the exact cell rule.
fn section_lines(g: &StackGrid, section: &Section, scratch: &mut Vec<P2>) -> SectionLines {
    let [na, nb, _] = g.grid.dims;
    let mut a: Vec<(u32, Cross)> = Vec::new();
    let mut b: Vec<(u32, Cross)> = Vec::new();
    for c in &section.contours {
        scratch.clear();
        scratch.extend(c.uv.iter().map(|&p| g.to_grid(p)));
        let n = scratch.len();
        for e in 0..n {
            let (p, q) = (scratch[e], scratch[(e + 1) % n]);
            // A lines b = j + ε²: crossed iff exactly one end has y > j.
            if p[1] != q[1] {
                let (lo, hi) = if p[1] < q[1] { (p, q) } else { (q, p) };
                let (j0, j1) = (lo[1].ceil() as i64, hi[1].ceil() as i64);
                for j in j0..j1 {
                    let jf = j as f64;
                    let x = lo[0] + (jf - lo[1]) * (hi[0] - lo[0]) / (hi[1] - lo[1]);
                    // Crossing before node i ⇔ orient(lo, hi, (i, j)) ≤ 0.
                    let before = |i: i64| orient(lo, hi, [i as f64, jf]) <= 0.0;
                    let mut cell = (x.floor() as i64).clamp(0, na as i64 - 1);
                    while !before(cell + 1) {
                        cell += 1;
                    }
                    while before(cell) {
                        cell -= 1;
                    }
                    a.push((j as u32, Cross { cell: cell as u32, at: x }));
                }
            }
            // B lines a = i + ε: crossed iff exactly one end has x > i.
            if p[0] != q[0] {
                let (l, r) = if p[0] < q[0] { (p, q) } else { (q, p) };
                let (i0, i1) = (l[0].ceil() as i64, r[0].ceil() as i64);
                for i in i0..i1 {
                    let ifl = i as f64;
                    let y = l[1] + (ifl - l[0]) * (r[1] - l[1]) / (r[0] - l[0]);
                    // Crossing before node j ⇔ orient(l, r, (i, j)) > 0, or
                    // = 0 with the edge not rising (the ε terms decide).
                    let before = |j: i64| {
                        let o = orient(l, r, [ifl, j as f64]);
                        o > 0.0 || (o == 0.0 && r[1] <= l[1])
                    };
                    let mut cell = (y.floor() as i64).clamp(0, nb as i64 - 1);
                    while !before(cell + 1) {
                        cell += 1;
                    }
                    while before(cell) {
                        cell -= 1;
                    }
                    b.push((i as u32, Cross { cell: cell as u32, at: y }));
                }
            }
        }
    }
    let order = |x: &(u32, Cross), y: &(u32, Cross)| (x.0, x.1.cell).cmp(&(y.0, y.1.cell)).then(x.1.at.total_cmp(&y.1.at));
    a.sort_unstable_by(order);
    b.sort_unstable_by(order);
    let csr = |v: Vec<(u32, Cross)>, lines: u32| -> (Vec<Cross>, Vec<u32>) {
        let mut start = vec![0u32; lines as usize + 2];
        for (l, _) in &v {
            start[*l as usize + 1] += 1;
        }
        for k in 1..start.len() {
            start[k] += start[k - 1];
        }
        (v.into_iter().map(|x| x.1).collect(), start)
    };
    let (a, a_start) = csr(a, nb + 1);
    let (b, b_start) = csr(b, na + 1);
    SectionLines { a, a_start, b, b_start }
}

/// Appends the A and B intercepts of a section at `plane`: alternating signs
/// along each line (the first crossing enters), values clamped in the cell.
fn in_plane_intercepts(lines: &SectionLines, plane: u32, out: &mut Vec<Intercept>) {
    for (family, data, start) in [(FAMILY_A, &lines.a, &lines.a_start), (FAMILY_B, &lines.b, &lines.b_start)] {
        for l in 0..start.len() - 1 {
            let row = &data[start[l] as usize..start[l + 1] as usize];
            for (k, c) in row.iter().enumerate() {
                let v = c.at.clamp(c.cell as f64 + MARGIN, c.cell as f64 + 1.0 - MARGIN);
                out.push(Intercept::new(plane, family, l as u32, v, k % 2 == 0));
            }
        }
    }
}

/// Appends the S intercepts of the layer between `lower` (plane `layer`) and
/// `upper`: one per node whose state differs, at the distance-interpolated
/// height (module docs). Returns (interpolated, midpoint) counts.
fn between_intercepts(lower: &SectionLines, upper: &SectionLines, layer: u32, na: u32, nb: u32, out: &mut Vec<Intercept>) -> (u64, u64) {
    let (mut interp, mut mid) = (0u64, 0u64);
    for j in 0..=nb {
        let (lo, up) = (lower.a_line(j), upper.a_line(j));
        if lo.is_empty() && up.is_empty() {
            continue;
        }
        let (mut x, mut y) = (0usize, 0usize);
        let (mut pl, mut pu) = (false, false);
        let mut node = 0u32;
        loop {
            let cl = lo.get(x).map(|c| c.cell).unwrap_or(u32::MAX);
            let cu = up.get(y).map(|c| c.cell).unwrap_or(u32::MAX);
            let c = cl.min(cu);
            if c == u32::MAX {
                break;
            }
            // Nodes node ..= c keep the current states.
            if pl != pu {
                for i in node..=c.min(na) {
                    let (dl, du) = {
                        let (al, au) = (nearest(lo, i as f64), nearest(up, i as f64));
                        let (bl, bu) = (nearest(lower.b_line(i), j as f64), nearest(upper.b_line(i), j as f64));
                        if al.max(au) <= bl.max(bu) {
                            (al, au)
                        } else {
                            (bl, bu)
                        }
                    };
                    let t = if dl.is_finite() && du.is_finite() && dl + du > 0.0 {
                        interp += 1;
                        dl / (dl + du)
                    } else {
                        mid += 1;
                        0.5
                    };
                    let k = layer as f64;
                    let v = (k + t).clamp(k + MARGIN, k + 1.0 - MARGIN);
                    out.push(Intercept::new(layer, FAMILY_S, i * (nb + 1) + j, v, !pl && pu));
                }
            }
            while x < lo.len() && lo[x].cell == c {
                pl = !pl;
                x += 1;
            }
            while y < up.len() && up[y].cell == c {
                pu = !pu;
                y += 1;
            }
            node = c + 1;
        }
    }
    (interp, mid)
}

/// The marching-cubes reconstruction of a stack streamed section by section.
/// Call [`push`](McReconstructor::push) for every section in order, then
/// [`finish`](McReconstructor::finish); vertices and faces go to the sink as
/// windows complete (faces only refer to vertices already sent).
pub struct McReconstructor {
    g: StackGrid,
    opts: McOptions,
    /// Plane index of the last section pushed (0: none yet).
    plane: u32,
    /// The previous plane's lines and its A/B records (not yet final).
    prev: Option<(SectionLines, Vec<Intercept>)>,
    /// Final planes from `k0` on.
    window: Vec<Vec<Intercept>>,
    k0: u32,
    emitted: u64,
    scratch: Vec<P2>,
    stats: McStats,
}

impl McReconstructor {
    /// Starts a reconstruction on the grid chosen for `summary`.
    pub fn new(summary: &StackSummary, opts: McOptions, path: &Path) -> Result<McReconstructor, ContourError> {
        let g = StackGrid::new(summary, opts.cubes, path)?;
        let [na, nb, _] = g.grid.dims;
        let stats = McStats { grid_cells: g.grid.dims, cube_size: g.h, ..McStats::default() };
        // With caps, plane 0 (empty) precedes the first section.
        let prev = opts.caps.then(|| (SectionLines::empty(na, nb), Vec::new()));
        Ok(McReconstructor { g, opts, plane: 0, prev, window: Vec::new(), k0: if opts.caps { 0 } else { 1 }, emitted: 0, scratch: Vec::new(), stats })
    }

    /// The grid in use.
    pub fn grid(&self) -> &StackGrid {
        &self.g
    }

    /// Adds the next section.
    pub fn push(&mut self, section: &Section, sink: &mut dyn MeshSink) -> Result<(), ContourError> {
        self.plane += 1;
        let lines = section_lines(&self.g, section, &mut self.scratch);
        let mut recs = Vec::with_capacity(lines.a.len() + lines.b.len());
        in_plane_intercepts(&lines, self.plane, &mut recs);
        self.advance(lines, recs, sink)
    }

    /// Finalises the previous plane now that the next one's lines are known.
    fn advance(&mut self, lines: SectionLines, recs: Vec<Intercept>, sink: &mut dyn MeshSink) -> Result<(), ContourError> {
        let [na, nb, _] = self.g.grid.dims;
        if let Some((plines, mut precs)) = self.prev.take() {
            let layer = self.plane - 1;
            let (i, m) = between_intercepts(&plines, &lines, layer, na, nb, &mut precs);
            self.stats.s_interpolated += i;
            self.stats.s_midpoint += m;
            self.final_plane(precs, sink)?;
        }
        self.prev = Some((lines, recs));
        Ok(())
    }

    /// Filters a final plane and reconstructs a window when it is full.
    fn final_plane(&mut self, mut recs: Vec<Intercept>, sink: &mut dyn MeshSink) -> Result<(), ContourError> {
        let f = filter_plane(&mut recs);
        self.stats.intercepts_kept += f.kept;
        self.stats.intercepts_removed += f.removed;
        self.window.push(recs);
        if self.window.len() > self.opts.window.max(1) {
            self.flush(sink)?;
        }
        Ok(())
    }

    /// Reconstructs the window's layers and keeps its last plane.
    fn flush(&mut self, sink: &mut dyn MeshSink) -> Result<(), ContourError> {
        if self.window.len() < 2 {
            return Ok(());
        }
        let res = reconstruct_slab(&self.g.grid, self.k0, &self.window, 0);
        for v in &res.vertices {
            sink.vertex(self.g.to_world(*v))?;
        }
        let base = self.emitted;
        for f in &res.faces {
            sink.face(f.map(|i| (base + i as u64) as u32))?;
        }
        self.emitted += res.vertices.len() as u64;
        self.stats.vertices += res.stats.vertices;
        self.stats.faces += res.stats.faces;
        self.stats.active_cells += res.stats.active_cells;
        self.stats.non_canonical_cells += res.stats.non_canonical_cells;
        let last = self.window.pop().unwrap();
        self.k0 += self.window.len() as u32;
        self.window.clear();
        self.window.push(last);
        Ok(())
    }

    /// Ends the stack: closes it with the top cap (or emits the last
    /// section's vertices for an open surface) and returns the counters.
    pub fn finish(mut self, sink: &mut dyn MeshSink) -> Result<McStats, ContourError> {
        let [na, nb, _] = self.g.grid.dims;
        if self.opts.caps {
            self.plane += 1;
            self.advance(SectionLines::empty(na, nb), Vec::new(), sink)?;
            let (_, top) = self.prev.take().unwrap();
            self.final_plane(top, sink)?;
            self.flush(sink)?;
        } else if let Some((_, mut last)) = self.prev.take() {
            let f = filter_plane(&mut last);
            self.stats.intercepts_kept += f.kept;
            self.stats.intercepts_removed += f.removed;
            if self.window.is_empty() {
                // A single section: nothing to join.
                self.window.push(last);
            } else {
                self.window.push(last);
                self.flush(sink)?;
            }
            // The last plane is owned by nobody: emit its vertices.
            for r in &self.window[0] {
                sink.vertex(self.g.to_world(intercept_local_position(r, nb)))?;
                self.stats.vertices += 1;
            }
        }
        Ok(self.stats)
    }
}

/// Reconstructs sections held in memory (tests and small stacks).
pub fn reconstruct(frame: StackFrame, sections: &[Section], opts: McOptions, sink: &mut dyn MeshSink) -> Result<McStats, ContourError> {
    let summary = StackSummary::of(frame, sections);
    let mut r = McReconstructor::new(&summary, opts, Path::new("(stack)"))?;
    for s in sections {
        r.push(s, sink)?;
    }
    r.finish(sink)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::profile::{read_all, ProfileOptions};
    use mint_core::TriMesh;

    fn stack(text: &str) -> (StackFrame, Vec<Section>) {
        read_all(text.as_bytes(), Path::new("t.pro"), ProfileOptions::default()).unwrap()
    }

    fn closed(m: &TriMesh) -> mint_testkit::topology::ClosedStats {
        mint_testkit::topology::check_closed_oriented(m).unwrap_or_else(|e| panic!("{e}"))
    }

    #[test]
    fn a_square_prism_is_a_closed_box() {
        // Two squares 4 x 4, one apart; 4 cubes across: cell size 1.
        let (f, s) = stack("pro\nsection 0 0 0 4 0 0 4 4 0 0 4 0\nsection 0 0 1 4 0 1 4 4 1 0 4 1\n");
        let mut m = TriMesh::default();
        let st = reconstruct(f, &s, McOptions { cubes: 4, caps: true, ..Default::default() }, &mut m).unwrap();
        assert_eq!(st.non_canonical_cells, 0);
        let c = closed(&m);
        assert_eq!((c.components, c.genus), (1, 0));
        // Caps half a spacing beyond the end sections: height 2 (up to the
        // chamfers of marching cubes); sides from 0 to 4, less the margin.
        assert!(c.volume > 0.0 && c.volume <= 32.0 + 1e-9, "volume {}", c.volume);
        let zs: Vec<f64> = m.positions.iter().map(|p| p[2]).collect();
        assert_eq!(zs.iter().cloned().fold(f64::INFINITY, f64::min), -0.5);
        assert_eq!(zs.iter().cloned().fold(f64::NEG_INFINITY, f64::max), 1.5);
    }

    #[test]
    fn without_caps_the_tube_is_open_at_both_ends() {
        let (f, s) = stack("pro\nsection 0 0 0 4 0 0 4 4 0 0 4 0\nsection 0 0 1 4 0 1 4 4 1 0 4 1\nsection 0 0 2 4 0 2 4 4 2 0 4 2\n");
        let mut m = TriMesh::default();
        let st = reconstruct(f, &s, McOptions { cubes: 8, caps: false, ..Default::default() }, &mut m).unwrap();
        assert_eq!(st.non_canonical_cells, 0);
        let r = mint_mesh::check(&m.positions, &m.faces);
        assert_eq!((r.boundary_loops, r.non_manifold_edges, r.inconsistently_oriented_edges, r.unreferenced_vertices), (2, 0, 0, 0));
        assert!(m.positions.iter().all(|p| p[2] >= 0.0 && p[2] <= 2.0));
    }

    #[test]
    fn windows_do_not_change_the_output() {
        // 20 sections of a shifting triangle: several windows; the same mesh
        // as one big window would give (checked through closedness and the
        // vertex count, which counts every intercept once).
        let mut t = String::from("pro\n");
        for k in 0..20 {
            let d = 0.1 * k as f64;
            t.push_str(&format!("section {d} 0 {k} {} 0 {k} {} 3 {k}\n", 4.0 + d, 2.0 + d));
        }
        let (f, s) = stack(&t);
        let mut m = TriMesh::default();
        let st = reconstruct(f, &s, McOptions { cubes: 16, caps: true, ..Default::default() }, &mut m).unwrap();
        assert_eq!(st.non_canonical_cells, 0);
        assert_eq!(st.vertices as usize, m.positions.len());
        assert_eq!(st.vertices, st.intercepts_kept);
        closed(&m);
    }
}
