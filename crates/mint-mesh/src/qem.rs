//! Quadric edge collapse in f64: M. Garland and P. Heckbert, "Surface
//! simplification using quadric error metrics", SIGGRAPH 1997.
//!
//! Every vertex carries the sum of the squared-distance quadrics of the
//! planes of its faces, weighted by their areas ([`Planes::Faces`]), or of
//! those planes lifted onto the smooth surface through the vertices
//! ([`Planes::Lifted`], for a resampled intermediate whose faces are chords
//! of the input). The edge whose collapse
//! costs least (the merged quadric at its best position: the quadric's
//! minimum when it is well conditioned, else the better endpoint or the
//! midpoint) is collapsed first, until the face target is reached. A
//! collapse is refused when it would break the surface: the two vertices
//! must share exactly the opposite vertices of their edge's faces (the link
//! condition, which keeps a 2-manifold a 2-manifold), no inner vertex may
//! be left with two faces (a fold), and no face around them may turn over
//! or become degenerate. Border vertices (on one simple boundary loop)
//! move only along their boundary edges, held there by a strongly
//! weighted plane through each boundary edge perpendicular to its face;
//! vertices on non-manifold edges, on faces with a repeated index or on
//! several boundary loops never move. So a closed surface stays closed
//! and keeps its genus, and an open one keeps its boundary loops.
//!
//! Why not meshoptimizer alone: its quadrics are f32, and their error
//! `pᵀAp + 2b·p + c` cancels terms of order one, so errors below about
//! 2.4e-4 of the mesh's extent are noise. A fine target on a smooth surface
//! needs far less (a 220k-face sphere: about 1e-5), and collapses ordered by
//! noise leave an uneven surface (docs/PERFORMANCE.md). In f64 the floor is
//! about 1e-8 of the extent.
//!
//! With a colour per vertex ([`collapse_coloured`]) each vertex's quadric
//! also prices its colour (Hoppe 1999's attribute quadric, see
//! `ColourQuadric`): a collapse across a colour border costs what a
//! geometric error does, so borders stay sharp, and each kept vertex's
//! colour is the quadric's best at its position, clamped to the gamut.
//!
//! Deterministic: one thread, a heap ordered by (cost, edge), no hashing.

use glam::DVec3;

use crate::edge_heap::{EdgeHeap, Key};

/// The ends of an edge that has gone.
const DEAD: u32 = u32::MAX;

/// How many times the refused edges may come back when the heap runs dry.
const READMISSIONS: u64 = 32;

/// A symmetric quadric `pᵀAp + 2b·p + c`, and the area it gathers.
#[derive(Debug, Clone, Copy, Default)]
struct Quadric {
    /// A: xx, xy, xz, yy, yz, zz.
    a: [f64; 6],
    b: [f64; 3],
    c: f64,
    /// Total face area (for errors as distances).
    w: f64,
}

impl Quadric {
    /// `w · (n·p + d)²` for the plane `n·p + d = 0` (`n` of unit length).
    fn plane(n: DVec3, d: f64, w: f64) -> Quadric {
        Quadric {
            a: [w * n.x * n.x, w * n.x * n.y, w * n.x * n.z, w * n.y * n.y, w * n.y * n.z, w * n.z * n.z],
            b: [w * n.x * d, w * n.y * d, w * n.z * d],
            c: w * d * d,
            w,
        }
    }
    fn add(&mut self, o: &Quadric) {
        for k in 0..6 {
            self.a[k] += o.a[k];
        }
        for k in 0..3 {
            self.b[k] += o.b[k];
        }
        self.c += o.c;
        self.w += o.w;
    }
    fn subtract(&mut self, o: &Quadric) {
        for k in 0..6 {
            self.a[k] -= o.a[k];
        }
        for k in 0..3 {
            self.b[k] -= o.b[k];
        }
        self.c -= o.c;
        self.w -= o.w;
    }
    fn sum(&self, o: &Quadric) -> Quadric {
        let mut q = *self;
        q.add(o);
        q
    }
    /// The quadric's value at `p` (never below zero).
    fn eval(&self, p: DVec3) -> f64 {
        let [xx, xy, xz, yy, yz, zz] = self.a;
        let v = xx * p.x * p.x + yy * p.y * p.y + zz * p.z * p.z + 2.0 * (xy * p.x * p.y + xz * p.x * p.z + yz * p.y * p.z)
            + 2.0 * (self.b[0] * p.x + self.b[1] * p.y + self.b[2] * p.z)
            + self.c;
        v.max(0.0)
    }
    /// Where the quadric is least, when `A` is well conditioned.
    fn minimum(&self) -> Option<DVec3> {
        let [xx, xy, xz, yy, yz, zz] = self.a;
        let c00 = yy * zz - yz * yz;
        let c01 = xz * yz - xy * zz;
        let c02 = xy * yz - xz * yy;
        let det = xx * c00 + xy * c01 + xz * c02;
        let scale = (xx + yy + zz) / 3.0;
        if !(det.abs() > 1e-9 * scale * scale * scale) {
            return None;
        }
        let c11 = xx * zz - xz * xz;
        let c12 = xy * xz - xx * yz;
        let c22 = xx * yy - xy * xy;
        let [b0, b1, b2] = self.b;
        let p = DVec3::new(c00 * b0 + c01 * b1 + c02 * b2, c01 * b0 + c11 * b1 + c12 * b2, c02 * b0 + c12 * b1 + c22 * b2) / -det;
        p.is_finite().then_some(p)
    }
}

/// What the collapse needs of a vertex's quadric: sums, differences, and
/// the quadric in position alone that prices a position.
trait VertexQuadric: Copy + Default + Send + Sync {
    fn add(&mut self, o: &Self);
    fn subtract(&mut self, o: &Self);
    fn sum(&self, o: &Self) -> Self {
        let mut q = *self;
        q.add(o);
        q
    }
    /// The quadric in position that prices a position (for a coloured one,
    /// with the best colour at each position substituted).
    fn reduced(&self) -> Quadric;
    /// The geometric part alone (errors are reported as distances).
    fn geometric(&self) -> &Quadric;
}

impl VertexQuadric for Quadric {
    fn add(&mut self, o: &Self) {
        Quadric::add(self, o)
    }
    fn subtract(&mut self, o: &Self) {
        Quadric::subtract(self, o)
    }
    fn reduced(&self) -> Quadric {
        *self
    }
    fn geometric(&self) -> &Quadric {
        self
    }
}

/// A geometric quadric with a colour attribute quadric (H. Hoppe, "New
/// quadric metric for simplifying meshes with appearance attributes",
/// IEEE Visualization 1999): over each face, each colour channel is the
/// linear function `g·p + d` that takes the corners' values; a vertex at
/// `p` with colour `s` costs `Σ area·λ·(g·p + d − s)²` more. Only the sums
/// over the faces are kept (per channel the area-weighted `g`, `d`, and
/// summed over the channels `g gᵀ`, `d g`, `d²`), so quadrics add as plain
/// ones do. For a position the best colour is `s = (S·p + t) / α` per
/// channel; substituted, the colour part is again a quadric in `p`
/// ([`VertexQuadric::reduced`]), whose minimum gives the position, and `s`
/// there the vertex's colour, clamped to [0, 1].
#[derive(Debug, Clone, Copy, Default)]
struct ColourQuadric {
    geo: Quadric,
    /// Σ over faces and channels of λ·area·g gᵀ (xx, xy, xz, yy, yz, zz).
    gg: [f64; 6],
    /// Σ λ·area·d·g, and Σ λ·area·d².
    dg: [f64; 3],
    dd: f64,
    /// Per channel Σ λ·area·g and Σ λ·area·d.
    s: [[f64; 3]; 3],
    t: [f64; 3],
    /// Σ λ·area.
    alpha: f64,
    /// The range of the colours merged into the vertex (the best colour is
    /// clamped to it: no overshoot beyond what the input holds there).
    lo: [f32; 3],
    hi: [f32; 3],
}

impl ColourQuadric {
    /// The colour (channels in [0, 1]) best at `p`.
    /// (A vertex on faces without area has no colour function: it keeps
    /// the middle of its range, its own colour when it merged nothing.)
    fn colour_at(&self, p: DVec3) -> [f64; 3] {
        std::array::from_fn(|j| {
            let (lo, hi) = if self.lo[j] <= self.hi[j] { (self.lo[j] as f64, self.hi[j] as f64) } else { (0.0, 1.0) };
            let c = (self.s[j][0] * p.x + self.s[j][1] * p.y + self.s[j][2] * p.z + self.t[j]) / self.alpha;
            if self.alpha > 0.0 && c.is_finite() {
                c.clamp(lo, hi)
            } else {
                0.5 * (lo + hi)
            }
        })
    }
}

impl VertexQuadric for ColourQuadric {
    fn add(&mut self, o: &Self) {
        self.geo.add(&o.geo);
        for k in 0..6 {
            self.gg[k] += o.gg[k];
        }
        for k in 0..3 {
            self.dg[k] += o.dg[k];
            self.t[k] += o.t[k];
            for m in 0..3 {
                self.s[k][m] += o.s[k][m];
            }
        }
        self.dd += o.dd;
        self.alpha += o.alpha;
        for k in 0..3 {
            self.lo[k] = self.lo[k].min(o.lo[k]);
            self.hi[k] = self.hi[k].max(o.hi[k]);
        }
    }
    /// (The colour range is not taken back: what was merged stays merged.)
    fn subtract(&mut self, o: &Self) {
        self.geo.subtract(&o.geo);
        for k in 0..6 {
            self.gg[k] -= o.gg[k];
        }
        for k in 0..3 {
            self.dg[k] -= o.dg[k];
            self.t[k] -= o.t[k];
            for m in 0..3 {
                self.s[k][m] -= o.s[k][m];
            }
        }
        self.dd -= o.dd;
        self.alpha -= o.alpha;
    }
    fn reduced(&self) -> Quadric {
        let mut q = self.geo;
        if !(self.alpha > 0.0) {
            return q;
        }
        let inv = 1.0 / self.alpha;
        let idx = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)];
        for (k, &(i, j)) in idx.iter().enumerate() {
            q.a[k] += self.gg[k] - inv * (0..3).map(|c| self.s[c][i] * self.s[c][j]).sum::<f64>();
        }
        for i in 0..3 {
            q.b[i] += self.dg[i] - inv * (0..3).map(|c| self.s[c][i] * self.t[c]).sum::<f64>();
        }
        q.c += self.dd - inv * (0..3).map(|c| self.t[c] * self.t[c]).sum::<f64>();
        q
    }
    fn geometric(&self) -> &Quadric {
        &self.geo
    }
}

/// The colour quadrics of a mesh: the geometric ones `geo` with, per face,
/// its colour channels' linear functions weighted by `lambda` × area.
fn colour_quadrics(pos: &[DVec3], tri: &[[u32; 3]], colours: &[[u8; 4]], lambda: f64, geo: Vec<Quadric>) -> Vec<ColourQuadric> {
    let mut quad: Vec<ColourQuadric> = geo.into_iter().map(|g| ColourQuadric { geo: g, lo: [f32::INFINITY; 3], hi: [f32::NEG_INFINITY; 3], ..Default::default() }).collect();
    for (q, c) in quad.iter_mut().zip(colours) {
        for k in 0..3 {
            q.lo[k] = c[k] as f32 / 255.0;
            q.hi[k] = q.lo[k];
        }
    }
    for t in tri {
        let [a, b, c] = t.map(|v| pos[v as usize]);
        let (e1, e2) = (b - a, c - a);
        let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
        let det = d11 * d22 - d12 * d12;
        let area = 0.5 * e1.cross(e2).length();
        if !(det > 0.0) || !(area > 0.0) {
            continue;
        }
        let w = lambda * area;
        let mut add = ColourQuadric { alpha: w, lo: [f32::INFINITY; 3], hi: [f32::NEG_INFINITY; 3], ..Default::default() };
        for j in 0..3 {
            let sv = t.map(|v| colours[v as usize][j] as f64 / 255.0);
            let (r1, r2) = (sv[1] - sv[0], sv[2] - sv[0]);
            // g = x e1 + y e2 with g·e1 = r1, g·e2 = r2.
            let x = (r1 * d22 - r2 * d12) / det;
            let y = (r2 * d11 - r1 * d12) / det;
            let g = e1 * x + e2 * y;
            let d = sv[0] - g.dot(a);
            let gg = [g.x * g.x, g.x * g.y, g.x * g.z, g.y * g.y, g.y * g.z, g.z * g.z];
            for k in 0..6 {
                add.gg[k] += w * gg[k];
            }
            for (k, gk) in g.to_array().into_iter().enumerate() {
                add.dg[k] += w * d * gk;
                add.s[j][k] = w * gk;
            }
            add.dd += w * d * d;
            add.t[j] = w * d;
        }
        for &v in t {
            quad[v as usize].add(&add);
        }
    }
    quad
}

/// What [`collapse`] did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct CollapseStats {
    /// Collapses done.
    pub collapses: u64,
    /// The largest collapse error, as an area-weighted RMS distance.
    pub max_error: f64,
    /// The largest side of the input's bounding box.
    pub extent: f64,
    /// Edges taken from the heap and judged.
    pub candidates: u64,
    /// Collapses refused by the link condition or the face checks.
    pub refused: u64,
    /// Times the refused edges were priced again and put back.
    pub rebuilds: u64,
    /// The `stop` hook ended the collapse early.
    pub stopped: bool,
}

/// The weight of a boundary edge's constraint plane, per squared edge length.
const BORDER_WEIGHT: f64 = 100.0;

/// A collapse's cost also holds `REGULARIZATION × (the area its quadric
/// gathers) × (edge length)²`, which orders collapses the planes cannot
/// price: on flat or straight stretches every position costs nothing, and
/// then the shortest edges go first, as they would in a uniform mesh.
/// Without it such ties went in index order and swept fans of slivers that
/// every later collapse would turn over (a 183k-face plate: 2M refused
/// collapses, 11 s; with it 0.6 s). Only the order changes, never where a
/// vertex goes; on curved surfaces the term is far below the planes' cost
/// (errors on the sphere, Igea, the horse and the bunny at 10% and 1%
/// within 2% of those without it, docs/PERFORMANCE.md).
pub const REGULARIZATION: f64 = 1e-6;

/// The face area two vertex quadrics gather together.
fn area_of<Q: VertexQuadric>(a: &Q, b: &Q) -> f64 {
    a.geometric().w + b.geometric().w
}

fn regularization() -> f64 {
    std::env::var("MINT_QEM_REG").ok().and_then(|v| v.parse().ok()).unwrap_or(REGULARIZATION)
}

/// Faces above which [`collapse`] works in [`BLOCKS`] spatial blocks first.
/// Was 400,000 (only large meshes in blocks, for the threads); a block of
/// a few tens of thousands of faces keeps its tables in the caches, and a
/// collapse there costs about two thirds of one in the whole mesh, so
/// every mesh but a small one goes through blocks: Igea (268k faces) to
/// 1% in 0.53 s instead of 1.14 s, mean errors of the shared meshes at 10%
/// and 1% within 3% of the whole-mesh collapse (docs/PERFORMANCE.md).
pub const BLOCK_MIN_FACES: usize = 40_000;
/// The number of blocks of a large mesh (fixed, so that the result does
/// not depend on the thread count). (32 blocks gave the 2M-face sphere
/// nothing; 64 thin slabs made its error 1.2-1.5x worse.)
pub const BLOCKS: usize = 8;
/// The blocks [`collapse`] cuts a mesh of `faces` faces into: [`BLOCKS`]
/// above [`BLOCK_MIN_FACES`] (or `MINT_QEM_BLOCK_MIN`, for measuring it), else 1.
pub fn blocks_for(faces: usize) -> usize {
    let min = std::env::var("MINT_QEM_BLOCK_MIN").ok().and_then(|v| v.parse().ok()).unwrap_or(BLOCK_MIN_FACES);
    if faces > min { BLOCKS } else { 1 }
}

/// Blocks stop at this multiple of their share of the target.
const BLOCK_SLACK: f64 = 1.1;

/// Nor does a block collapse below this many times its faces on a vertex
/// shared with another block (held still in the block phase): the whole
/// pass needs room to collapse those seams. On a 2M-face sphere the seams
/// are a few percent of a block, on the 70k-face bunny cut in 8 a third
/// of its share of a 10% target; with only [`BLOCK_SLACK`] and
/// [`BLOCK_MAX_RATIO`] the bunny at 10% came out with a 1.45x larger mean
/// error in blocks than in one piece, Laurana 1.42x. With 8x the seams the
/// shared meshes at 10% and 1% are within 1.5% of the whole-mesh collapse
/// and the thin shapes of `scripts/bench/thin.sh` within MeshLab's mean
/// error by the margins they had; 4x was faster on meshes below 100k
/// faces (the horse's blocks did two thirds of the work, not one third)
/// but put the thin tree at 10% at 1.13x MeshLab's mean error
/// (docs/PERFORMANCE.md).
pub const SEAM_FACTOR: u64 = 8;

/// [`BLOCK_SLACK`], or `MINT_QEM_BLOCK_SLACK` (for measuring it).
fn block_slack() -> f64 {
    std::env::var("MINT_QEM_BLOCK_SLACK").ok().and_then(|v| v.parse().ok()).filter(|&s: &f64| s >= 1.0).unwrap_or(BLOCK_SLACK)
}
/// Nor does a block collapse more than this ratio of its faces: the held
/// vertices along its cuts keep their fine faces through the block phase,
/// so a block asked for a large reduction would collapse its inside far
/// beyond what the whole pass, which later removes those seams, would
/// have chosen (a 2M-face sphere to 20k: seams of about 23k faces, more
/// than the target). The whole pass does the rest in cost order.
pub const BLOCK_MAX_RATIO: u64 = 8;

/// Which planes the vertices' quadrics gather.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Planes {
    /// The planes of the faces: the mesh is the surface to keep (a user's
    /// mesh, simplified itself).
    #[default]
    Faces,
    /// Each face's plane moved along its normal by the mean height above
    /// the face of the smooth surface that the vertex normals describe
    /// (see [`lift`]). For a mesh whose vertices lie on the surface to keep
    /// and whose faces are chords of it, as a Marching Intersections
    /// intermediate's are: its faces' planes lie inside a convex part by
    /// the chords' sag, so collapses guided by them settle the vertices
    /// too far in (a 22M-face sphere through a 880k-face intermediate to
    /// 220k faces: mean error 1.39× that of simplifying the sphere itself,
    /// 0.94× with lifted planes).
    Lifted,
}

/// Faces whose vertex normals lean further than this (cosine) from the
/// face's own normal are not lifted: they span a crease or a fold, where
/// the normals say nothing of a smooth surface.
const LIFT_MIN_COS: f64 = 0.9;

/// The mean height, along the face normal `n`, of a smooth surface through
/// the corners `x` with unit normals `ns` above their flat face, or 0 when
/// a corner's normal leans beyond [`LIFT_MIN_COS`]. Along each edge the
/// surface is the cubic with zero height at both ends and the slopes that
/// the end normals give (height per edge length `−(nᵢ·e)/(nᵢ·n)`); its
/// height at mid-edge is `(sᵢ − sⱼ)/8`. Over the face, the quadratic patch
/// through those three mid-edge heights has the mean of them: on a sphere
/// of radius R with edges h, h²/(8R), the chords' mean sag. Clamped to a
/// quarter of the longest edge.
pub fn lift(x: [DVec3; 3], ns: [DVec3; 3], n: DVec3) -> f64 {
    let mut sum = 0.0;
    let mut longest: f64 = 0.0;
    for k in 0..3 {
        let (i, j) = (k, (k + 1) % 3);
        let e = x[j] - x[i];
        longest = longest.max(e.length());
        let (ci, cj) = (ns[i].dot(n), ns[j].dot(n));
        if !(ci > LIFT_MIN_COS && cj > LIFT_MIN_COS) {
            return 0.0;
        }
        sum += (ns[j].dot(e) / cj - ns[i].dot(e) / ci) / 8.0;
    }
    (sum / 3.0).clamp(-0.25 * longest, 0.25 * longest)
}

/// Collapses edges of the mesh until at most `target_faces` faces remain
/// (or no collapse is allowed, or the next one's error would exceed
/// `max_error` times the largest side of the bounding box). Returns the
/// new positions (same indexing; removed vertices keep stale positions),
/// the remaining faces in their original order, and the statistics.
///
/// A mesh of more than [`BLOCK_MIN_FACES`] faces is first cut into
/// [`BLOCKS`] slabs of faces along its longest axis, each collapsed to its
/// share of the target on its own (in parallel on `threads` threads; the
/// vertices it shares with other slabs, and their edges, are left as they
/// are), and then the whole
/// is collapsed to the target from there, quadrics carried over. Working
/// on a slab at a time keeps the tables in the caches; the result depends
/// on the face count, never on `threads`.
pub fn collapse(positions: &[[f64; 3]], faces: &[[u32; 3]], target_faces: u64, max_error: f64, threads: usize) -> (Vec<[f64; 3]>, Vec<[u32; 3]>, CollapseStats) {
    let blocks = blocks_for(faces.len());
    collapse_in_blocks(positions, faces, Planes::Faces, target_faces, max_error, blocks, threads, &|| false)
}

/// [`collapse`] with the quadrics' [`Planes`], an explicit number of
/// blocks (1: the whole at once) and a `stop` hook, asked every few
/// thousand candidates: when it says true the collapse ends where it is
/// (the mesh is still valid, only less reduced) and `stats.stopped` is set.
#[allow(clippy::too_many_arguments)]
pub fn collapse_in_blocks(
    positions: &[[f64; 3]],
    faces: &[[u32; 3]],
    planes: Planes,
    target_faces: u64,
    max_error: f64,
    blocks: usize,
    threads: usize,
    stop: &(dyn Fn() -> bool + Sync),
) -> (Vec<[f64; 3]>, Vec<[u32; 3]>, CollapseStats) {
    let t = std::time::Instant::now();
    let (pos, centre, extent) = centred(positions);
    let max_distance = max_error * extent;
    let quad = initial_quadrics(&pos, faces, planes);
    trace("initial quadrics", t);
    let stats = CollapseStats { extent, ..Default::default() };
    let (out_pos, out_faces, _, stats) = collapse_with(pos, quad, faces, target_faces, max_distance, blocks, threads, stop, stats);
    let out_pos: Vec<[f64; 3]> = out_pos.iter().map(|p| (*p + centre).to_array()).collect();
    (out_pos, out_faces, stats)
}

/// Positions relative to the bounding box's centre (smaller terms, less
/// cancellation in the quadrics), the centre, and the box's largest side.
fn centred(positions: &[[f64; 3]]) -> (Vec<DVec3>, DVec3, f64) {
    let nv = positions.len();
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for p in positions {
        lo = lo.min(DVec3::from(*p));
        hi = hi.max(DVec3::from(*p));
    }
    let centre = if nv > 0 { (lo + hi) * 0.5 } else { DVec3::ZERO };
    let extent = if nv > 0 { (hi - lo).max_element() } else { 0.0 };
    (positions.iter().map(|p| DVec3::from(*p) - centre).collect(), centre, extent)
}

/// [`collapse_in_blocks`] of a mesh with a colour per vertex, by colour
/// quadrics ([`ColourQuadric`]): a full-range difference of colour across
/// a face costs what a distance of `colour_weight` × the extent does.
/// Returns also each vertex's colour (same indexing; the kept vertices'
/// from their quadrics, alpha 255).
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
pub fn collapse_coloured(
    positions: &[[f64; 3]],
    faces: &[[u32; 3]],
    planes: Planes,
    colours: &[[u8; 4]],
    colour_weight: f64,
    target_faces: u64,
    max_error: f64,
    blocks: usize,
    threads: usize,
    stop: &(dyn Fn() -> bool + Sync),
) -> (Vec<[f64; 3]>, Vec<[u32; 3]>, Vec<[u8; 4]>, CollapseStats) {
    let (pos, centre, extent) = centred(positions);
    let lambda = (colour_weight * extent).powi(2);
    let quad = colour_quadrics(&pos, faces, colours, lambda, initial_quadrics(&pos, faces, planes));
    let stats = CollapseStats { extent, ..Default::default() };
    let (out_pos, out_faces, quad, stats) = collapse_with(pos, quad, faces, target_faces, max_error * extent, blocks, threads, stop, stats);
    let out_colours = out_pos.iter().zip(&quad).map(|(p, q)| {
        let c = q.colour_at(*p).map(|x| (x * 255.0).round() as u8);
        [c[0], c[1], c[2], 255]
    });
    let out_colours: Vec<[u8; 4]> = out_colours.collect();
    let out_pos: Vec<[f64; 3]> = out_pos.iter().map(|p| (*p + centre).to_array()).collect();
    (out_pos, out_faces, out_colours, stats)
}

/// The block phase, then the whole: [`collapse_in_blocks`]'s work for any
/// kind of vertex quadric (positions relative to the box's centre).
#[allow(clippy::too_many_arguments)]
fn collapse_with<Q: VertexQuadric>(
    mut pos: Vec<DVec3>,
    mut quad: Vec<Q>,
    faces: &[[u32; 3]],
    target_faces: u64,
    max_distance: f64,
    blocks: usize,
    threads: usize,
    stop: &(dyn Fn() -> bool + Sync),
    mut stats: CollapseStats,
) -> (Vec<DVec3>, Vec<[u32; 3]>, Vec<Q>, CollapseStats) {
    let nv = pos.len();
    let mut tri = faces.to_vec();
    let blocks = blocks.clamp(1, 255);
    if blocks > 1 && !faces.is_empty() && target_faces < faces.len() as u64 {
        tri = collapse_blocks(&mut pos, &mut quad, faces, target_faces, max_distance, blocks, block_slack(), threads.max(1), stop, &mut stats);
    }
    if std::env::var_os("MINT_QEM_TRACE").is_some() {
        eprintln!("qem: blocks done: {} faces, {stats:?}", tri.len());
    }
    // The whole pass on the vertices still in use, renumbered in their
    // order (so the same collapses come in the same order): after the
    // blocks, tables a fraction of the size, which the caches hold.
    let mut used = vec![false; nv];
    for t in &tri {
        for &v in t {
            used[v as usize] = true;
        }
    }
    let used: Vec<u32> = (0..nv as u32).filter(|&v| used[v as usize]).collect();
    if used.len() == nv {
        let pinned = vec![false; nv];
        let (out_pos, out_faces, quad) = run(pos, tri, quad, &pinned, target_faces, max_distance, stop, &mut stats);
        return (out_pos, out_faces, quad, stats);
    }
    let mut local = vec![u32::MAX; nv];
    for (l, &g) in used.iter().enumerate() {
        local[g as usize] = l as u32;
    }
    let ltri: Vec<[u32; 3]> = tri.iter().map(|t| t.map(|v| local[v as usize])).collect();
    drop((tri, local));
    let lpos: Vec<DVec3> = used.iter().map(|&v| pos[v as usize]).collect();
    let lquad: Vec<Q> = used.iter().map(|&v| quad[v as usize]).collect();
    let pinned = vec![false; used.len()];
    let (lpos, lfaces, lquad) = run(lpos, ltri, lquad, &pinned, target_faces, max_distance, stop, &mut stats);
    for (l, &g) in used.iter().enumerate() {
        pos[g as usize] = lpos[l];
        quad[g as usize] = lquad[l];
    }
    let out_faces = lfaces.iter().map(|t| t.map(|l| used[l as usize])).collect();
    (pos, out_faces, quad, stats)
}

/// The block phase of [`collapse_in_blocks`]: returns the faces after it
/// (global ids, blocks in order), with `pos` and `quad` updated.
#[allow(clippy::too_many_arguments)]
fn collapse_blocks<Q: VertexQuadric>(
    pos: &mut [DVec3],
    quad: &mut [Q],
    faces: &[[u32; 3]],
    target_faces: u64,
    max_distance: f64,
    blocks: usize,
    slack: f64,
    threads: usize,
    stop: &(dyn Fn() -> bool + Sync),
    stats: &mut CollapseStats,
) -> Vec<[u32; 3]> {
    let t0 = std::time::Instant::now();
    let nv = pos.len();
    // Faces to blocks by the centroid along the longest axis, at quantiles.
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for p in pos.iter() {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    let d = (hi - lo).max_position();
    let key: Vec<f64> = faces.iter().map(|t| t.iter().map(|&v| pos[v as usize][d]).sum::<f64>()).collect();
    let mut sorted = key.clone();
    let cuts: Vec<f64> = (1..blocks)
        .map(|k| {
            let i = k * sorted.len() / blocks;
            *sorted.select_nth_unstable_by(i, |a, b| a.total_cmp(b)).1
        })
        .collect();
    drop(sorted);
    let block_of: Vec<u8> = key.iter().map(|k| cuts.iter().filter(|c| k.total_cmp(c).is_gt()).count() as u8).collect();
    drop(key);
    // Vertices in more than one block stay still in this phase.
    const NONE: u8 = u8::MAX;
    const SHARED: u8 = u8::MAX - 1;
    let mut vblock = vec![NONE; nv];
    for (f, t) in faces.iter().enumerate() {
        for &v in t {
            let b = &mut vblock[v as usize];
            *b = match *b {
                NONE => block_of[f],
                x if x == block_of[f] || x == SHARED => x,
                _ => SHARED,
            };
        }
    }
    // Each block as its own mesh: local ids in order of first use.
    let mut local = vec![u32::MAX; nv];
    let mut parts: Vec<Block> = (0..blocks).map(|_| Block::default()).collect();
    for (f, t) in faces.iter().enumerate() {
        let part = &mut parts[block_of[f] as usize];
        let lt = t.map(|v| {
            let id = if vblock[v as usize] == SHARED {
                *part.shared.entry(v).or_insert(part.global.len() as u32)
            } else {
                if local[v as usize] == u32::MAX {
                    local[v as usize] = part.global.len() as u32;
                }
                local[v as usize]
            };
            if id as usize == part.global.len() {
                part.global.push(v);
            }
            id
        });
        if t.iter().any(|&v| vblock[v as usize] == SHARED) {
            part.seam += 1;
        }
        part.faces.push(lt);
    }
    drop(local);
    trace("blocks cut", t0);
    let total = faces.len() as f64;
    let next = std::sync::atomic::AtomicUsize::new(0);
    let results: Vec<std::sync::Mutex<Option<BlockResult<Q>>>> = (0..blocks).map(|_| std::sync::Mutex::new(None)).collect();
    let (pos_r, quad_r, vblock_r) = (&*pos, &*quad, &vblock);
    let work = || loop {
        let b = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        if b >= blocks {
            return;
        }
        let part = &parts[b];
        let p: Vec<DVec3> = part.global.iter().map(|&v| pos_r[v as usize]).collect();
        let q: Vec<Q> = part.global.iter().map(|&v| quad_r[v as usize]).collect();
        let pinned: Vec<bool> = part.global.iter().map(|&v| vblock_r[v as usize] == SHARED).collect();
        // Its share of the target and a little more: the whole pass then
        // spends the rest where it costs least, first on the fine faces
        // along the held vertices.
        let share = ((slack * target_faces as f64) * part.faces.len() as f64 / total).round() as u64;
        let share = share.max(part.faces.len() as u64 / block_max_ratio()).max(seam_factor() * part.seam);
        let mut st = CollapseStats::default();
        let (p, f, q) = run(p, part.faces.clone(), q, &pinned, share, max_distance, stop, &mut st);
        *results[b].lock().unwrap() = Some(BlockResult { pos: p, faces: f, quad: q, stats: st });
    };
    if threads <= 1 {
        work();
    } else {
        std::thread::scope(|s| {
            for _ in 0..threads.min(blocks) {
                s.spawn(work);
            }
        });
    }
    trace("blocks collapsed", t0);
    // Merge: moved positions and quadrics back; a shared vertex gathers
    // what each block added to its quadric.
    let original: Vec<(u32, Q)> = (0..nv as u32).filter(|&v| vblock[v as usize] == SHARED).map(|v| (v, quad[v as usize])).collect();
    let mut out = Vec::new();
    for (part, r) in parts.iter().zip(results) {
        let r = r.into_inner().unwrap().expect("every block ran");
        stats.collapses += r.stats.collapses;
        stats.candidates += r.stats.candidates;
        stats.refused += r.stats.refused;
        stats.rebuilds += r.stats.rebuilds;
        stats.stopped |= r.stats.stopped;
        stats.max_error = stats.max_error.max(r.stats.max_error);
        for (l, &g) in part.global.iter().enumerate() {
            if vblock[g as usize] == SHARED {
                let base = original[original.binary_search_by_key(&g, |e| e.0).unwrap()].1;
                let mut added = r.quad[l];
                added.subtract(&base);
                quad[g as usize].add(&added);
            } else {
                pos[g as usize] = r.pos[l];
                quad[g as usize] = r.quad[l];
            }
        }
        out.extend(r.faces.iter().map(|t| t.map(|l| part.global[l as usize])));
    }
    out
}

/// With `MINT_QEM_TRACE`: how long since `t` it took to reach `what`.
fn trace(what: &str, t: std::time::Instant) {
    if std::env::var_os("MINT_QEM_TRACE").is_some() {
        eprintln!("qem: {what} at {:.3}s", t.elapsed().as_secs_f64());
    }
}

/// [`SEAM_FACTOR`], or `MINT_QEM_SEAM` (for measuring it).
fn seam_factor() -> u64 {
    std::env::var("MINT_QEM_SEAM").ok().and_then(|v| v.parse().ok()).unwrap_or(SEAM_FACTOR)
}

/// [`BLOCK_MAX_RATIO`], or `MINT_QEM_BLOCK_RATIO` (for measuring it).
fn block_max_ratio() -> u64 {
    std::env::var("MINT_QEM_BLOCK_RATIO").ok().and_then(|v| v.parse().ok()).filter(|&r| r >= 1).unwrap_or(BLOCK_MAX_RATIO)
}

/// One block of [`collapse_blocks`]: its faces in local ids, and the
/// global id of each local vertex.
#[derive(Default)]
struct Block {
    faces: Vec<[u32; 3]>,
    /// Faces on a vertex shared with another block.
    seam: u64,
    global: Vec<u32>,
    shared: std::collections::BTreeMap<u32, u32>,
}

struct BlockResult<Q> {
    pos: Vec<DVec3>,
    faces: Vec<[u32; 3]>,
    quad: Vec<Q>,
    stats: CollapseStats,
}

/// The quadrics of every vertex: the area-weighted planes of its faces
/// (lifted for [`Planes::Lifted`]), and for a vertex on a boundary edge the
/// plane through that edge perpendicular to its face, weighted by
/// [`BORDER_WEIGHT`].
fn initial_quadrics(pos: &[DVec3], tri: &[[u32; 3]], planes: Planes) -> Vec<Quadric> {
    let mut quad = vec![Quadric::default(); pos.len()];
    // Vertex normals, for lifting.
    let vn = if planes == Planes::Lifted { crate::normals::vertex_normals(pos, tri) } else { Vec::new() };
    for t in tri {
        let [a, b, c] = t.map(|v| pos[v as usize]);
        let n2 = (b - a).cross(c - a);
        let len = n2.length();
        if !(len > 0.0) {
            continue;
        }
        let n = n2 / len;
        let up = if planes == Planes::Lifted { lift([a, b, c], t.map(|v| vn[v as usize]), n) } else { 0.0 };
        let q = Quadric::plane(n, -n.dot(a) - up, 0.5 * len);
        for &v in t {
            quad[v as usize].add(&q);
        }
    }
    let classes = EdgeClasses::of(pos.len(), tri);
    let vf = vertex_faces(pos.len(), tri);
    for t in tri {
        if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
            continue;
        }
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if classes.border_edges[a as usize] == 0 || classes.border_edges[b as usize] == 0 || faces_on_edge(&vf, tri, a, b) != 1 {
                continue;
            }
            let [pa, pb, pc] = [a, b, t[(k + 2) % 3]].map(|x| pos[x as usize]);
            let n = (pb - pa).cross(pc - pa);
            let m = (pb - pa).cross(n);
            let len = m.length();
            if !(len > 0.0) {
                continue;
            }
            let m = m / len;
            let q = Quadric::plane(m, -m.dot(pa), BORDER_WEIGHT * (pb - pa).length_squared());
            quad[a as usize].add(&q);
            quad[b as usize].add(&q);
        }
    }
    quad
}

/// Vertex → faces.
fn vertex_faces(nv: usize, tri: &[[u32; 3]]) -> Vec<Vec<u32>> {
    let mut count = vec![0u32; nv];
    for t in tri {
        for &v in t {
            count[v as usize] += 1;
        }
    }
    let mut vf: Vec<Vec<u32>> = count.iter().map(|&c| Vec::with_capacity(c as usize)).collect();
    for (f, t) in tri.iter().enumerate() {
        for &v in t {
            vf[v as usize].push(f as u32);
        }
    }
    vf
}

/// The edges of a mesh, each once, and what they say of their vertices: a
/// vertex on a boundary edge is a *border* vertex; one on a non-manifold
/// edge, on a face with a repeated index, or on other than two boundary
/// edges is *locked*.
struct EdgeClasses {
    edges: Vec<(u32, u32)>,
    border_edges: Vec<u8>,
    locked: Vec<bool>,
}

impl EdgeClasses {
    fn of(nv: usize, tri: &[[u32; 3]]) -> EdgeClasses {
        let mut edges: Vec<u64> = Vec::with_capacity(tri.len() * 3);
        let mut locked = vec![false; nv];
        let mut border_edges = vec![0u8; nv];
        for t in tri {
            if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                for &v in t {
                    locked[v as usize] = true;
                }
                continue;
            }
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                edges.push((a.min(b) as u64) << 32 | a.max(b) as u64);
            }
        }
        edges.sort_unstable();
        let mut i = 0;
        let mut unique = Vec::with_capacity(edges.len() / 2);
        while i < edges.len() {
            let mut j = i + 1;
            while j < edges.len() && edges[j] == edges[i] {
                j += 1;
            }
            let (a, b) = ((edges[i] >> 32) as u32, edges[i] as u32);
            match j - i {
                2 => {}
                1 => {
                    for x in [a, b] {
                        border_edges[x as usize] = border_edges[x as usize].saturating_add(1);
                    }
                }
                _ => {
                    locked[a as usize] = true;
                    locked[b as usize] = true;
                }
            }
            unique.push((a, b));
            i = j;
        }
        for v in 0..nv {
            if border_edges[v] != 0 && border_edges[v] != 2 {
                locked[v] = true;
            }
        }
        EdgeClasses { edges: unique, border_edges, locked }
    }
}

/// The greedy collapse of one mesh (centred positions, quadrics given;
/// `pinned` vertices never move, and no edge of theirs collapses): returns the positions, the remaining
/// faces in order, and the quadrics.
fn run<Q: VertexQuadric>(
    mut pos: Vec<DVec3>,
    mut tri: Vec<[u32; 3]>,
    mut quad: Vec<Q>,
    pinned: &[bool],
    target_faces: u64,
    max_distance: f64,
    stop: &(dyn Fn() -> bool + Sync),
    stats: &mut CollapseStats,
) -> (Vec<DVec3>, Vec<[u32; 3]>, Vec<Q>) {
    let nv = pos.len();
    let mut alive = vec![true; tri.len()];
    let mut live = tri.len() as u64;
    let mut vf = vertex_faces(nv, &tri);
    let EdgeClasses { edges: unique, border_edges, mut locked } = EdgeClasses::of(nv, &tri);
    // A pinned vertex (shared with another block) takes part in no
    // collapse: its faces in other blocks are not seen here, so the link
    // condition could not be judged for its edges.
    for v in 0..nv {
        locked[v] |= pinned[v];
    }
    let locked = locked;
    let border: Vec<bool> = (0..nv).map(|v| border_edges[v] != 0 || locked[v]).collect();
    drop(border_edges);

    let eps = regularization();
    let flip = flip_cos();
    // The cost and position of collapsing edge (u, v): border and locked
    // vertices stay where they are, except that two border vertices may
    // merge along their boundary edge.
    let cost = |pos: &[DVec3], quad: &[Q], vf: &[Vec<u32>], tri: &[[u32; 3]], u: u32, v: u32| -> Option<(f64, DVec3)> {
        if pinned[u as usize] || pinned[v as usize] {
            return None;
        }
        let (bu, bv) = (border[u as usize], border[v as usize]);
        let along_border = bu && bv && !locked[u as usize] && !locked[v as usize] && faces_on_edge(vf, tri, u, v) == 1;
        if bu && bv && !along_border {
            return None;
        }
        let q = quad[u as usize].sum(&quad[v as usize]).reduced();
        let (pu, pv) = (pos[u as usize], pos[v as usize]);
        let p = if along_border || !(bu || bv) {
            let mid = (pu + pv) * 0.5;
            match q.minimum() {
                Some(m) if (m - mid).length() <= 2.0 * (pu - pv).length() => m,
                _ => [pu, pv, mid].into_iter().min_by(|a, b| q.eval(*a).total_cmp(&q.eval(*b))).unwrap(),
            }
        } else if bu {
            pu
        } else {
            pv
        };
        Some((q.eval(p) + eps * area_of(&quad[u as usize], &quad[v as usize]) * (pu - pv).length_squared(), p))
    };
    let key_of = |c: f64, a: u32, b: u32| Key { cost_bits: c.to_bits(), u: a.min(b), v: a.max(b) };
    // The edges: their ends (u < v; DEAD once gone) by id, and each
    // vertex's ids, one per neighbour through a live face.
    let mut ends: Vec<[u32; 2]> = unique.iter().map(|&(a, b)| [a, b]).collect();
    drop(unique);
    let mut ve: Vec<Vec<u32>> = vec![Vec::new(); nv];
    for (id, &[a, b]) in ends.iter().enumerate() {
        ve[a as usize].push(id as u32);
        ve[b as usize].push(id as u32);
    }
    let initial: Vec<(Key, u32)> = ends
        .iter()
        .enumerate()
        .filter_map(|(id, &[a, b])| cost(&pos, &quad, &vf, &tri, a, b).map(|(c, _)| (key_of(c, a, b), id as u32)))
        .collect();
    let mut heap = EdgeHeap::from(initial, ends.len());
    // Live edges taken out of the heap (refused, or unpriceable): they come
    // back when a collapse next to them prices them again, or, when the
    // heap runs dry short of the target, all together, if a collapse has
    // happened since they last came back (at most READMISSIONS times).
    let mut out: Vec<u32> = Vec::new();
    let mut collapses_at_readmission = u64::MAX;

    let max_cost_distance = max_distance;
    let t_loop = std::time::Instant::now();
    let mut nu: Vec<u32> = Vec::new();
    let mut nv_: Vec<u32> = Vec::new();
    let mut around: Vec<u32> = Vec::new();
    let mut fresh: Vec<u32> = Vec::new();
    let mut old_edges: Vec<(u32, u32)> = Vec::new();
    while live > target_faces {
        if heap.peek().is_none() && stats.collapses != collapses_at_readmission && stats.rebuilds < READMISSIONS {
            collapses_at_readmission = stats.collapses;
            for id in std::mem::take(&mut out) {
                let [a, b] = ends[id as usize];
                if a == DEAD || heap.contains(id) {
                    continue;
                }
                match cost(&pos, &quad, &vf, &tri, a, b) {
                    Some((c, _)) => heap.set(id, key_of(c, a, b)),
                    None => out.push(id),
                }
            }
            stats.rebuilds += 1;
        }
        let Some((key, id)) = heap.peek() else { break };
        stats.candidates += 1;
        if stats.candidates % 4096 == 0 && stop() {
            stats.stopped = true;
            break;
        }
        let [u, v] = ends[id as usize];
        // Whatever is decided, the edge leaves the heap: it collapses (and
        // leaves `out` again), or waits until it is priced again.
        heap.remove(id);
        out.push(id);
        let Some((c, p)) = cost(&pos, &quad, &vf, &tri, u, v) else { continue };
        if c.to_bits() != key.cost_bits {
            continue;
        }
        // The geometric error alone, as a distance.
        let g = quad[u as usize].geometric().sum(quad[v as usize].geometric());
        let distance = if g.w > 0.0 { (g.eval(p) / g.w).sqrt() } else { 0.0 };
        if distance > max_cost_distance {
            break;
        }
        // The faces on the edge, and the neighbours of each end.
        let mut shared = [u32::MAX; 2];
        let mut n_shared = 0;
        for &f in &vf[u as usize] {
            if tri[f as usize].contains(&v) {
                if n_shared < 2 {
                    shared[n_shared] = f;
                }
                n_shared += 1;
            }
        }
        if n_shared == 0 || n_shared > 2 {
            continue;
        }
        let shared = &shared[..n_shared];
        neighbours(&vf[u as usize], &tri, u, &mut nu);
        neighbours(&vf[v as usize], &tri, v, &mut nv_);
        // Link condition: the common neighbours are the opposite vertices of
        // the edge's faces (two inside, one on the border).
        let mut opposite = [u32::MAX; 2];
        for (k, &f) in shared.iter().enumerate() {
            opposite[k] = *tri[f as usize].iter().find(|&&x| x != u && x != v).unwrap();
        }
        let opposite = &opposite[..n_shared];
        let mut n_common = 0;
        let mut common_ok = true;
        for &x in &nu {
            if x != v && nv_.binary_search(&x).is_ok() {
                n_common += 1;
                common_ok &= opposite.contains(&x);
            }
        }
        if n_common != n_shared || !common_ok || (n_shared == 2 && opposite[0] == opposite[1]) {
            stats.refused += 1;
            continue;
        }
        // (An inner vertex left with two faces would be a fold; a border
        // one may keep a single face.)
        if opposite.iter().any(|&x| vf[x as usize].len() <= if border[x as usize] { 1 } else { 3 }) {
            stats.refused += 1;
            continue;
        }
        // No face turns over or degenerates.
        around.clear();
        around.extend(vf[u as usize].iter().chain(&vf[v as usize]).copied().filter(|f| !shared.contains(f)));
        let ok = around.iter().all(|&f| {
            let t = tri[f as usize];
            let old = t.map(|x| pos[x as usize]);
            let new = t.map(|x| if x == u || x == v { p } else { pos[x as usize] });
            let n0 = (old[1] - old[0]).cross(old[2] - old[0]);
            let n1 = (new[1] - new[0]).cross(new[2] - new[0]);
            n1.dot(n0) > flip * n0.length() * n1.length() && n1.length_squared() > 1e-24 * n0.length_squared()
        });
        if !ok {
            stats.refused += 1;
            continue;
        }
        // Collapse `gone` into `keep` (a border end is the one kept); the
        // edge goes, so it does not wait with the refused ones.
        out.pop();
        let (keep, gone) = if border[v as usize] && !border[u as usize] { (v, u) } else { (u, v) };
        for &f in shared {
            alive[f as usize] = false;
            live -= 1;
            for &x in &tri[f as usize] {
                if x != gone {
                    vf[x as usize].retain(|&g| g != f);
                }
            }
        }
        let moved = std::mem::take(&mut vf[gone as usize]);
        for f in moved {
            if !alive[f as usize] {
                continue;
            }
            for x in tri[f as usize].iter_mut() {
                if *x == gone {
                    *x = keep;
                }
            }
            vf[keep as usize].push(f);
        }
        let qg = quad[gone as usize];
        quad[keep as usize].add(&qg);
        pos[keep as usize] = p;
        stats.collapses += 1;
        stats.max_error = stats.max_error.max(distance);
        // Edges: keep's neighbours now, each by the id keep had for it, or
        // else gone's (renamed), or a new one; gone's other edges and the
        // collapsed one go. Then keep's edges are priced again.
        neighbours(&vf[keep as usize], &tri, keep, &mut nu);
        let old_keep = std::mem::take(&mut ve[keep as usize]);
        let old_gone = std::mem::take(&mut ve[gone as usize]);
        // (far end, id) of each old edge, keep's first: the first match wins.
        old_edges.clear();
        old_edges.extend(old_keep.iter().chain(&old_gone).map(|&id| {
            let [a, b] = ends[id as usize];
            (if a == keep || a == gone { b } else { a }, id)
        }));
        fresh.clear();
        for &x in &nu {
            let id = match old_edges.iter().find(|e| e.0 == x) {
                Some(e) => e.1,
                None => {
                    ends.push([DEAD; 2]);
                    heap.grow(ends.len());
                    ve[x as usize].push(ends.len() as u32 - 1);
                    ends.len() as u32 - 1
                }
            };
            ends[id as usize] = [keep.min(x), keep.max(x)];
            fresh.push(id);
        }
        for &(x, id) in &old_edges {
            if ends[id as usize][0] == DEAD || fresh.contains(&id) {
                continue;
            }
            heap.remove(id);
            if x != keep && x != gone {
                ve[x as usize].retain(|&e| e != id);
            }
            ends[id as usize] = [DEAD; 2];
        }
        for &id in &fresh {
            let [a, b] = ends[id as usize];
            match cost(&pos, &quad, &vf, &tri, a, b) {
                Some((c, _)) => heap.set(id, key_of(c, a, b)),
                None => {
                    heap.remove(id);
                    out.push(id);
                }
            }
        }
        ve[keep as usize] = std::mem::replace(&mut fresh, old_keep);
    }
    trace(&format!("run of {} faces: loop done", tri.len()), t_loop);
    let out_faces: Vec<[u32; 3]> = (0..tri.len()).filter(|&f| alive[f]).map(|f| tri[f]).collect();
    (pos, out_faces, quad)
}

/// The number of faces on edge (u, v).
fn faces_on_edge(vf: &[Vec<u32>], tri: &[[u32; 3]], u: u32, v: u32) -> usize {
    vf[u as usize].iter().filter(|&&f| tri[f as usize].contains(&v)).count()
}

/// The vertices sharing a face with `v` (sorted, without `v`).
fn neighbours(faces_of_v: &[u32], tri: &[[u32; 3]], v: u32, out: &mut Vec<u32>) {
    out.clear();
    for &f in faces_of_v {
        out.extend(tri[f as usize].iter().copied().filter(|&x| x != v));
    }
    out.sort_unstable();
    out.dedup();
}

/// A collapse is refused when a face around it would turn by more than
/// 60° (the cosine of the angle between its normals before and after must
/// exceed this). Was 0.2 (78°): on a torus whose tube is 2% of its size,
/// decimated to 0.1%, the max error fell from 1.99× to 0.82× MeshLab's
/// and the mean from 1.06× to 0.95×; the other shapes and scans of
/// `scripts/bench/thin.sh` stayed within their targets (docs/PERFORMANCE.md).
pub const FLIP_COS: f64 = 0.5;

/// [`FLIP_COS`], or `MINT_QEM_FLIP` (for measuring it).
fn flip_cos() -> f64 {
    std::env::var("MINT_QEM_FLIP").ok().and_then(|v| v.parse().ok()).unwrap_or(FLIP_COS)
}
