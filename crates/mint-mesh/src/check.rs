//! [`check()`] reads an indexed triangle mesh and returns a [`CheckReport`]:
//! what a mesh is, and everything that keeps it from being a clean closed
//! surface. Data flows in four passes over flat arrays: (1) per-face geometry
//! in fixed chunks (volume, area, exact degeneracy); (2) a counting sort of
//! face corners into a vertex→face incidence table; (3) a union-find over
//! vertices for components, run beside (4) a per-vertex pass that looks only
//! at a vertex's own incident faces to classify every edge and fan. No hash
//! map is built: memory is about 12 bytes per face plus 20 bytes per vertex
//! on top of the input (10 million faces: under 200 MB extra), so tens of
//! millions of faces fit in a few GB.
//!
//! # Definitions
//!
//! Let `V` be the positions and `F` the faces. A face is *collapsed* if it
//! repeats a vertex index (`[a, a, b]`). Collapsed faces count as degenerate
//! and as references to their vertices, and they join vertices into
//! components, but they take no part in edge topology: they add no edges and
//! no fans, and a component holding one is never *closed*. Every other face
//! is *proper* and contributes its three directed edges `a→b, b→c, c→a`.
//!
//! - `vertices`, `faces`: the input lengths.
//! - `referenced_vertices`: vertices used by at least one face (collapsed or
//!   not); `unreferenced_vertices` the rest.
//! - `bbox_min`, `bbox_max`: over all vertices with finite coordinates
//!   (referenced or not); `None` if there is none. `non_finite_vertices`
//!   counts the others (NaN or infinite coordinates make the geometric
//!   fields meaningless but do not change the topological ones).
//! - `components`: connected components of the referenced vertices, two
//!   vertices being connected when they share a face (vertex connectivity:
//!   two cubes touching at one corner are one component). Components are
//!   numbered by their smallest vertex index.
//! - `edges`: undirected edges `{a, b}` of proper faces. The *multiplicity*
//!   of an edge is the number of proper faces using it.
//! - `boundary_edges`: edges of multiplicity 1.
//! - `non_manifold_edges`: edges of multiplicity 3 or more.
//! - `inconsistently_oriented_edges`: edges of multiplicity exactly 2 whose
//!   two faces traverse them in the same direction (a flipped face inside a
//!   closed surface gives 3).
//! - `boundary_loops`: each boundary edge is directed as its one face
//!   traverses it. A vertex is a *simple boundary vertex* when exactly one
//!   boundary edge leaves it and exactly one enters it. A boundary loop is a
//!   closed cycle of boundary edges through simple boundary vertices only;
//!   `boundary_loops` counts them, and `non_simple_boundary_edges` counts the
//!   boundary edges on no such loop (e.g. the two free edges of a sliver
//!   triangle hung on an interior edge, or a boundary that touches itself
//!   at a vertex).
//! - `non_manifold_vertices`: vertices whose incident proper faces form two
//!   or more *fans*, a fan being a class of faces around the vertex
//!   connected through edges incident to that vertex. Two cubes sharing a
//!   corner make that corner one. The ends of a non-manifold edge are not
//!   counted for that reason alone: the faces on the edge join one fan.
//! - `degenerate_faces`: collapsed faces plus proper faces of exactly zero
//!   area (three collinear or coincident positions), decided exactly with
//!   `robust::orient2d` on the xy, yz and zx projections (the three
//!   components of the cross product), never with a tolerance.
//!   `collapsed_faces` is the collapsed subset.
//! - `duplicate_faces`: faces whose sorted index triple equals that of an
//!   earlier face (same vertex set, any order or orientation); the first
//!   copy is not counted, so `k` copies of a face add `k - 1`. Duplicates
//!   still take part in topology, so they usually also show up as
//!   non-manifold or inconsistently oriented edges.
//! - `euler_characteristic`: `χ = referenced_vertices - edges + proper faces`
//!   over the whole mesh.
//! - A component is *closed* when it holds no collapsed face and none of its
//!   edges is a boundary, non-manifold or inconsistently oriented edge and
//!   none of its vertices is non-manifold; it is then a closed, oriented
//!   2-manifold. `closed_components` counts them and `genera` lists
//!   `(2 - χ_c) / 2` for each, in component order; `genus_total` is the sum.
//! - `signed_volume`: `Σ det(p0, p1, p2) / 6` over proper faces, relative to
//!   the origin (for a closed, outward-oriented surface this is the enclosed
//!   volume, positive; each term is computed as `p0 · ((p1-p0)×(p2-p0))`,
//!   which keeps a mesh millions of units from the origin accurate).
//!   `surface_area`: `Σ |(p1-p0)×(p2-p0)| / 2`. Both are
//!   summed in fixed chunks of faces combined in order, so they are
//!   bit-identical under any thread count.
//! - `watertight`: no boundary, non-manifold or inconsistently oriented
//!   edge, no non-manifold vertex, no collapsed (repeated-index) or
//!   duplicated face, every component closed, and at least one proper
//!   face. Unreferenced vertices and zero-area faces with three distinct
//!   vertices do not by themselves spoil it.
//!
//! Non-goals: no geometric self-intersection test, no repair.

use crate::error::MeshError;
use mint_core::TriMesh;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::sync::atomic::{AtomicU32, Ordering};

/// Faces per chunk in the geometry pass; fixes the summation order.
pub const FACE_CHUNK: usize = 1 << 14;
/// Vertices per chunk in the per-vertex topology pass.
const VERTEX_CHUNK: usize = 1 << 12;
/// Label of an unreferenced vertex.
const NONE: u32 = u32::MAX;
/// High bit of the per-vertex info word: the vertex spoils closedness.
const BAD: u32 = 1 << 31;

/// Everything [`check()`] finds; see the [module docs](self) for each
/// definition.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CheckReport {
    pub vertices: u64,
    pub faces: u64,
    pub referenced_vertices: u64,
    pub unreferenced_vertices: u64,
    pub non_finite_vertices: u64,
    pub bbox_min: Option<[f64; 3]>,
    pub bbox_max: Option<[f64; 3]>,
    pub components: u64,
    pub edges: u64,
    pub boundary_edges: u64,
    pub boundary_loops: u64,
    pub non_simple_boundary_edges: u64,
    pub non_manifold_edges: u64,
    pub non_manifold_vertices: u64,
    pub inconsistently_oriented_edges: u64,
    pub degenerate_faces: u64,
    pub collapsed_faces: u64,
    pub duplicate_faces: u64,
    pub euler_characteristic: i64,
    pub closed_components: u64,
    pub genera: Vec<i64>,
    pub genus_total: i64,
    pub signed_volume: f64,
    pub surface_area: f64,
    pub watertight: bool,
    /// Vertices merged into an identical earlier position before judging
    /// (`mint check` welds unless `--no-weld`; 0 when not welded).
    #[serde(default)]
    pub welded_vertices: u64,
}

/// Checks a mesh; see the [module docs](self) for what is measured.
///
/// # Panics
/// If a face index is out of range or the mesh is too large for `u32`
/// indices; use [`try_check`] to get a [`MeshError`] instead.
pub fn check(positions: &[[f64; 3]], faces: &[[u32; 3]]) -> CheckReport {
    try_check(positions, faces).unwrap_or_else(|e| panic!("mint_mesh::check: {e}"))
}

/// [`check()`] on a [`TriMesh`].
pub fn check_mesh(mesh: &TriMesh) -> CheckReport {
    check(&mesh.positions, &mesh.faces)
}

/// Checks a mesh, returning an error for out-of-range indices or sizes
/// beyond `u32` indexing instead of panicking.
pub fn try_check(positions: &[[f64; 3]], faces: &[[u32; 3]]) -> Result<CheckReport, MeshError> {
    // The three corners of every face must fit in a u32 corner table.
    MeshError::validate(positions, faces, (u32::MAX / 3) as usize)?;
    let nv = positions.len();

    // Geometry: bbox over vertices, volume/area/degeneracy over faces.
    let bbox = bounding_box(positions);
    let geom = face_geometry(positions, faces);

    // Topology: incidence table, then components beside the per-vertex pass.
    let incidence = Incidence::build(nv, faces);
    let ((labels, referenced, components), local) = rayon::join(
        || component_labels(nv, faces),
        || local_topology(nv, faces, &incidence),
    );
    drop(incidence);

    // Per-component Euler characteristic and closedness.
    let mut chi = vec![0i64; components as usize];
    let mut bad = vec![false; components as usize];
    for (&l, &info) in labels.iter().zip(&local.vinfo) {
        if l == NONE {
            continue;
        }
        chi[l as usize] += 1 - i64::from(info & !BAD);
        bad[l as usize] |= info & BAD != 0;
    }
    for f in faces {
        let l = labels[f[0] as usize] as usize;
        if is_collapsed(f) {
            bad[l] = true;
        } else {
            chi[l] += 1;
        }
    }
    Ok(report_from(Totals {
        vertices: nv as u64,
        faces: faces.len() as u64,
        referenced,
        components,
        bbox,
        geom,
        counts: local.counts,
        simple: &local.simple,
        chi: &chi,
        bad: &bad,
        duplicate_collapsed: duplicate_collapsed(faces),
    }))
}

/// Everything a [`CheckReport`] is made from, as the in-core check and the
/// bounded one (mint-pipeline's `check_file`) both compute it.
pub struct Totals<'a> {
    pub vertices: u64,
    pub faces: u64,
    pub referenced: u64,
    pub components: u64,
    pub bbox: Bbox,
    pub geom: FaceGeom,
    pub counts: TopologyCounts,
    /// `(v, w)` for each simple boundary vertex and its outgoing boundary
    /// edge, sorted by `v`.
    pub simple: &'a [(u32, u32)],
    /// Per component, in component order: Euler characteristic, and
    /// whether it is not a closed oriented manifold.
    pub chi: &'a [i64],
    pub bad: &'a [bool],
    pub duplicate_collapsed: u64,
}

/// The report from its totals; see the [module docs](self).
pub fn report_from(t: Totals) -> CheckReport {
    let genera: Vec<i64> = (0..t.components as usize).filter(|&c| !t.bad[c]).map(|c| (2 - t.chi[c]) / 2).collect();
    let (boundary_loops, loop_edges) = walk_boundary_loops(t.simple);
    let proper_faces = t.faces - t.geom.collapsed;
    let c = &t.counts;
    let duplicate_faces = c.duplicates + t.duplicate_collapsed;
    // The verdict agrees with every count: a collapsed (repeated-index) or
    // duplicated face, or a component that is not closed, is not part of a
    // closed 2-manifold, whatever the edges say.
    let watertight = c.boundary == 0
        && c.non_manifold_edges == 0
        && c.non_manifold_vertices == 0
        && c.inconsistent == 0
        && t.geom.collapsed == 0
        && duplicate_faces == 0
        && proper_faces > 0
        && genera.len() as u64 == t.components;
    CheckReport {
        vertices: t.vertices,
        faces: t.faces,
        referenced_vertices: t.referenced,
        unreferenced_vertices: t.vertices - t.referenced,
        non_finite_vertices: t.bbox.non_finite,
        bbox_min: t.bbox.min,
        bbox_max: t.bbox.max,
        components: t.components,
        edges: c.edges,
        boundary_edges: c.boundary,
        boundary_loops,
        non_simple_boundary_edges: c.boundary - loop_edges,
        non_manifold_edges: c.non_manifold_edges,
        non_manifold_vertices: c.non_manifold_vertices,
        inconsistently_oriented_edges: c.inconsistent,
        degenerate_faces: t.geom.degenerate,
        collapsed_faces: t.geom.collapsed,
        duplicate_faces,
        euler_characteristic: t.referenced as i64 - c.edges as i64 + proper_faces as i64,
        closed_components: genera.len() as u64,
        genus_total: genera.iter().sum(),
        welded_vertices: 0,
        genera,
        signed_volume: t.geom.volume6 / 6.0,
        surface_area: t.geom.area2 / 2.0,
        watertight,
    }
}

/// True when a face repeats a vertex index.
#[inline]
pub fn is_collapsed(f: &[u32; 3]) -> bool {
    f[0] == f[1] || f[1] == f[2] || f[0] == f[2]
}

/// Bounding box over finite positions, and how many are not finite.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bbox {
    pub min: Option<[f64; 3]>,
    pub max: Option<[f64; 3]>,
    pub non_finite: u64,
}

impl Bbox {
    /// Nothing seen yet.
    pub fn empty() -> Bbox {
        Bbox { min: None, max: None, non_finite: 0 }
    }

    /// Adds one position.
    #[inline]
    pub fn add(&mut self, p: [f64; 3]) {
        if !p.iter().all(|x| x.is_finite()) {
            self.non_finite += 1;
            return;
        }
        let lo = self.min.get_or_insert(p);
        let hi = self.max.get_or_insert(p);
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }

    /// Adds every position another box has seen.
    pub fn merge(&mut self, o: &Bbox) {
        self.non_finite += o.non_finite;
        if let (Some(lo), Some(hi)) = (o.min, o.max) {
            let (min, max) = (self.min.get_or_insert(lo), self.max.get_or_insert(hi));
            for k in 0..3 {
                min[k] = min[k].min(lo[k]);
                max[k] = max[k].max(hi[k]);
            }
        }
    }
}

fn bounding_box(positions: &[[f64; 3]]) -> Bbox {
    positions
        .par_chunks(FACE_CHUNK)
        .map(|chunk| {
            let mut b = Bbox::empty();
            for &p in chunk {
                b.add(p);
            }
            b
        })
        .reduce(Bbox::empty, |mut a, b| {
            a.merge(&b);
            a
        })
}

/// Per-face geometry sums: six times the signed volume, twice the area,
/// degenerate and collapsed faces. Summed over [`FACE_CHUNK`] faces at a
/// time and the chunks combined in order ([`FaceGeom::then`]), so that the
/// sums are bit-identical however the work is split.
#[derive(Default, Debug, Clone, Copy, PartialEq)]
pub struct FaceGeom {
    pub volume6: f64,
    pub area2: f64,
    pub degenerate: u64,
    pub collapsed: u64,
}

impl FaceGeom {
    /// Adds one face: its indices (after welding) and corner positions.
    #[inline(always)]
    pub fn add(&mut self, f: &[u32; 3], [a, b, c]: [[f64; 3]; 3]) {
        if is_collapsed(f) {
            self.collapsed += 1;
            self.degenerate += 1;
            return;
        }
        // glam's cross, dot and length written out, operation for
        // operation (the same bits), with the edges shared by the filter.
        let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        let n = [u[1] * v[2] - v[1] * u[2], u[2] * v[0] - v[2] * u[0], u[0] * v[1] - v[0] * u[1]];
        self.area2 += ((n[0] * n[0]) + (n[1] * n[1]) + (n[2] * n[2])).sqrt();
        // det(a, b, c) = a · ((b - a) × (c - a)): the same value, but from
        // the edges, so that a mesh far from the origin (UTM, ECEF) does not
        // lose its volume to cancellation between products of coordinates.
        self.volume6 += (a[0] * n[0]) + (a[1] * n[1]) + (a[2] * n[2]);
        if !surely_not_collinear(u, v) && collinear_cold(a[0], a[1], a[2], b[0], b[1], b[2], c[0], c[1], c[2]) {
            self.degenerate += 1;
        }
    }

    /// This chunk's sums followed by the next chunk's.
    pub fn then(self, g: &FaceGeom) -> FaceGeom {
        FaceGeom { volume6: self.volume6 + g.volume6, area2: self.area2 + g.area2, degenerate: self.degenerate + g.degenerate, collapsed: self.collapsed + g.collapsed }
    }
}

fn face_geometry(positions: &[[f64; 3]], faces: &[[u32; 3]]) -> FaceGeom {
    let parts: Vec<FaceGeom> = faces
        .par_chunks(FACE_CHUNK)
        .map(|chunk| {
            let mut g = FaceGeom::default();
            for f in chunk {
                g.add(f, f.map(|i| positions[i as usize]));
            }
            g
        })
        .collect();
    // Combine in chunk order: the sum does not depend on the thread count.
    parts.iter().fold(FaceGeom::default(), |acc, g| acc.then(g))
}

/// A filter before [`collinear_exact`], given the edges `u = b-a` and
/// `v = c-a`: true when one component of `u×v`, computed in floating
/// point, is certainly not zero. Each component is a 2D orientation `l - r` of products of differences;
/// Shewchuk's bound on its rounding error is about `3.3e-16 * (|l| + |r|)`,
/// so a computed value beyond three times that cannot come from zero
/// (checked only well above the subnormal range, and never for NaN). Only
/// the rest (near-degenerate faces) pay for the exact test.
#[inline(always)]
fn surely_not_collinear(u: [f64; 3], v: [f64; 3]) -> bool {
    let orient = |i: usize, j: usize| {
        let (l, r) = (u[i] * v[j], u[j] * v[i]);
        // Far from underflow, where the relative bound holds.
        let m = l.abs() + r.abs();
        m > 1e-280 && (l - r).abs() > 1e-15 * m
    };
    orient(0, 1) || orient(1, 2) || orient(2, 0)
}

/// [`collinear_exact`] out of line, taking scalars: a call that takes the
/// corner arrays themselves made the compiler keep them in memory on the
/// hot path of [`FaceGeom::add`] (stalled stores and loads, measured).
#[cold]
#[inline(never)]
#[allow(clippy::too_many_arguments)]
fn collinear_cold(ax: f64, ay: f64, az: f64, bx: f64, by: f64, bz: f64, cx: f64, cy: f64, cz: f64) -> bool {
    collinear_exact([ax, ay, az], [bx, by, bz], [cx, cy, cz])
}

/// True iff the three points are exactly collinear (or coincident): the
/// three components of `(b-a)×(c-a)` are the orientations of the xy, yz and
/// zx projections, each evaluated exactly by `robust::orient2d`.
pub(crate) fn collinear_exact(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> bool {
    use robust::{orient2d, Coord};
    let o = |i: usize, j: usize| {
        orient2d(
            Coord { x: a[i], y: a[j] },
            Coord { x: b[i], y: b[j] },
            Coord { x: c[i], y: c[j] },
        )
    };
    o(0, 1) == 0.0 && o(1, 2) == 0.0 && o(2, 0) == 0.0
}

/// Vertex→face incidence table of the proper faces (CSR layout): the faces
/// around vertex `v` are `faces[v_offsets[v]..v_offsets[v+1]]`, in no
/// particular order (filled in parallel; nothing downstream depends on it).
struct Incidence {
    offsets: Vec<u32>,
    faces: Vec<AtomicU32>,
}

impl Incidence {
    fn build(nv: usize, faces: &[[u32; 3]]) -> Self {
        let cursor: Vec<AtomicU32> = (0..nv).into_par_iter().map(|_| AtomicU32::new(0)).collect();
        faces.par_iter().filter(|f| !is_collapsed(f)).for_each(|f| {
            for &i in f {
                cursor[i as usize].fetch_add(1, Ordering::Relaxed);
            }
        });
        let mut offsets = vec![0u32; nv + 1];
        for v in 0..nv {
            offsets[v + 1] = offsets[v] + cursor[v].load(Ordering::Relaxed);
        }
        cursor
            .par_iter()
            .zip(offsets.par_iter())
            .for_each(|(c, &o)| c.store(o, Ordering::Relaxed));
        let total = offsets[nv] as usize;
        let table: Vec<AtomicU32> = (0..total)
            .into_par_iter()
            .map(|_| AtomicU32::new(0))
            .collect();
        faces
            .par_iter()
            .enumerate()
            .filter(|(_, f)| !is_collapsed(f))
            .for_each(|(fi, f)| {
                for &i in f {
                    let slot = cursor[i as usize].fetch_add(1, Ordering::Relaxed);
                    table[slot as usize].store(fi as u32, Ordering::Relaxed);
                }
            });
        Self {
            offsets,
            faces: table,
        }
    }
}

/// The root of `x`'s class in a union-find forest (`parent[r] == r` at a
/// root), halving the path on the way.
#[inline]
pub fn find_root(parent: &mut [u32], mut x: u32) -> u32 {
    while parent[x as usize] != x {
        let g = parent[parent[x as usize] as usize];
        parent[x as usize] = g;
        x = g;
    }
    x
}

/// Joins the classes of `a` and `b`, linking the larger root under the
/// smaller: `parent[x] <= x` always, so classes come out labelled in the
/// order of their smallest member (the order [`check`] numbers components).
/// True when two classes were merged.
#[inline]
pub fn union_smallest(parent: &mut [u32], a: u32, b: u32) -> bool {
    let (ra, rb) = (find_root(parent, a), find_root(parent, b));
    if ra == rb {
        return false;
    }
    parent[ra.max(rb) as usize] = ra.min(rb);
    true
}

/// Joins the classes of a face's three vertices under the smallest of
/// their roots: the classes [`union_smallest`] twice would give, with one
/// root lookup fewer.
#[inline]
pub fn union_face(parent: &mut [u32], f: [u32; 3]) {
    let r = f.map(|v| find_root(parent, v));
    let low = r[0].min(r[1]).min(r[2]);
    for x in r {
        parent[x as usize] = low;
    }
}

/// Union-find over vertices through faces. Returns per-vertex component
/// labels (`NONE` for unreferenced vertices), the number of referenced
/// vertices and the number of components. Roots are always the smallest
/// vertex of their class, so labels follow smallest-vertex order.
fn component_labels(nv: usize, faces: &[[u32; 3]]) -> (Vec<u32>, u64, u64) {
    let mut parent: Vec<u32> = (0..nv as u32).collect();
    let mut referenced = vec![false; nv];
    for f in faces {
        for &i in f {
            referenced[i as usize] = true;
        }
        union_face(&mut parent, *f);
    }
    // In place: parent[v] <= v, so by the time v is visited its parent holds
    // a final label (roots get fresh labels in ascending order).
    let mut next = 0u32;
    let mut nref = 0u64;
    for v in 0..nv {
        if !referenced[v] {
            parent[v] = NONE;
            continue;
        }
        nref += 1;
        let p = parent[v] as usize;
        parent[v] = if p == v {
            next += 1;
            next - 1
        } else {
            parent[p]
        };
    }
    (parent, nref, u64::from(next))
}

/// Edge and vertex counts summed over the per-vertex scans.
#[derive(Default, Debug, Clone, Copy, PartialEq)]
pub struct TopologyCounts {
    pub edges: u64,
    pub boundary: u64,
    pub non_manifold_edges: u64,
    pub inconsistent: u64,
    pub non_manifold_vertices: u64,
    pub duplicates: u64,
}

impl TopologyCounts {
    pub fn add(&mut self, o: &TopologyCounts) {
        self.edges += o.edges;
        self.boundary += o.boundary;
        self.non_manifold_edges += o.non_manifold_edges;
        self.inconsistent += o.inconsistent;
        self.non_manifold_vertices += o.non_manifold_vertices;
        self.duplicates += o.duplicates;
    }
}

struct Local {
    counts: TopologyCounts,
    /// Per vertex: number of edges `{v, w}` with `w > v` (low 31 bits) and
    /// the `BAD` flag.
    vinfo: Vec<u32>,
    /// `(v, w)` for each simple boundary vertex `v` and its outgoing boundary
    /// edge `v→w`, sorted by `v`.
    simple: Vec<(u32, u32)>,
}

/// The per-vertex pass: each vertex looks at its incident faces only, so
/// every edge `{v, w}` is seen whole from both ends and classified at the
/// smaller one, and the fans at `v` are found by a small local union-find.
fn local_topology(nv: usize, faces: &[[u32; 3]], inc: &Incidence) -> Local {
    let mut vinfo = vec![0u32; nv];
    let parts: Vec<(TopologyCounts, Vec<(u32, u32)>)> = vinfo
        .par_chunks_mut(VERTEX_CHUNK)
        .enumerate()
        .map(|(ci, info)| {
            let mut counts = TopologyCounts::default();
            let mut simple = Vec::new();
            let mut scratch = VertexScratch::default();
            let mut fan: Vec<(u32, u32)> = Vec::new();
            let v0 = ci * VERTEX_CHUNK;
            for (dv, slot) in info.iter_mut().enumerate() {
                let v = (v0 + dv) as u32;
                let (s, e) = (
                    inc.offsets[v as usize] as usize,
                    inc.offsets[v as usize + 1] as usize,
                );
                if e == s {
                    continue;
                }
                fan.clear();
                fan.extend((s..e).map(|k| fan_pair(&faces[inc.faces[k].load(Ordering::Relaxed) as usize], v)));
                let t = scan_vertex(v, &fan, &mut scratch, &mut counts);
                if let Some(next) = t.simple_next {
                    simple.push((v, next));
                }
                *slot = t.edges_here | if t.bad { BAD } else { 0 };
            }
            (counts, simple)
        })
        .collect();
    let mut counts = TopologyCounts::default();
    let mut simple = Vec::new();
    for (c, s) in parts {
        counts.add(&c);
        simple.extend(s);
    }
    Local {
        counts,
        vinfo,
        simple,
    }
}

/// The other two corners of proper face `f` around its corner `v`, in the
/// face's order: `(a, b)` with `v → a → b`.
#[inline]
pub fn fan_pair(f: &[u32; 3], v: u32) -> (u32, u32) {
    if f[0] == v {
        (f[1], f[2])
    } else if f[1] == v {
        (f[2], f[0])
    } else {
        (f[0], f[1])
    }
}

/// Reused buffers of [`scan_vertex`]; after a scan, `boundary_out` holds
/// the far ends `w` of the boundary edges `v → w` that leave the vertex.
#[derive(Default)]
pub struct VertexScratch {
    keys: Vec<u64>,
    lp: Vec<u32>,
    dup: Vec<u64>,
    pub boundary_out: Vec<u32>,
}

/// What [`scan_vertex`] finds at one vertex.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VertexTopology {
    /// Edges `{v, w}` with `w > v` (each edge is counted at its smaller end).
    pub edges_here: u32,
    /// Faces whose smallest vertex is `v` (each face is counted once).
    pub faces_here: u32,
    /// The vertex spoils closedness: an edge here is a boundary,
    /// non-manifold or inconsistently oriented edge, or the vertex is
    /// non-manifold.
    pub bad: bool,
    /// For a simple boundary vertex, its outgoing boundary edge's end.
    pub simple_next: Option<u32>,
}

/// The per-vertex scan: vertex `v` looks at its incident proper faces only,
/// each given as [`fan_pair`], so every edge `{v, w}` is seen whole from
/// both ends and classified (and counted into `counts`) at the smaller one,
/// and the fans at `v` are found by a small local union-find.
pub fn scan_vertex(v: u32, fan: &[(u32, u32)], s: &mut VertexScratch, counts: &mut TopologyCounts) -> VertexTopology {
    if let Some(t) = closed_fan(v, fan) {
        s.boundary_out.clear();
        counts.edges += u64::from(t.edges_here);
        return t;
    }
    scan_vertex_general(v, fan, s, counts)
}

/// Largest degree [`closed_fan`] tries (it is quadratic in the degree).
const CLOSED_FAN_MAX: usize = 24;

/// The common case of [`scan_vertex`], decided without sorting: a vertex
/// whose `d ≥ 3` faces form one closed, consistently oriented fan. The
/// `a`s are distinct, and following each face `v → a → b` to the face whose
/// `a` is its `b` visits every face once before coming back. Then every
/// edge `{v, w}` has exactly one face on each side in opposite directions,
/// the faces form one fan, and no two faces share their vertex set (that
/// needs a cycle of two), so the general scan would count nothing but the
/// edges and faces here. `None` for anything else, which the general scan
/// judges.
#[inline]
fn closed_fan(v: u32, fan: &[(u32, u32)]) -> Option<VertexTopology> {
    let d = fan.len();
    if !(3..=CLOSED_FAN_MAX).contains(&d) {
        return None;
    }
    let (mut edges_here, mut faces_here) = (0u32, 0u32);
    for (i, &(a, b)) in fan.iter().enumerate() {
        if a == v || b == v || a == b || fan[..i].iter().any(|p| p.0 == a) {
            return None;
        }
        edges_here += u32::from(a > v);
        faces_here += u32::from(a > v && b > v);
    }
    let mut k = 0usize;
    for step in 1..=d {
        let b = fan[k].1;
        k = fan.iter().position(|p| p.0 == b)?;
        if (k == 0) != (step == d) {
            return None;
        }
    }
    Some(VertexTopology { edges_here, faces_here, bad: false, simple_next: None })
}

/// [`scan_vertex`] for any fan: every edge's faces counted by sorting.
pub fn scan_vertex_general(v: u32, fan: &[(u32, u32)], s: &mut VertexScratch, counts: &mut TopologyCounts) -> VertexTopology {
    let d = fan.len();
    let (keys, lp, dup) = (&mut s.keys, &mut s.lp, &mut s.dup);
    keys.clear();
    dup.clear();
    s.boundary_out.clear();
    let mut faces_here = 0u32;
    for (k, &(a, b)) in fan.iter().enumerate() {
        // Key: neighbour (32 bits), direction (1 bit, 1 = v→w), local face
        // (31 bits: a degree is at most the face count, kept below 2³¹).
        keys.push(u64::from(a) << 32 | 1 << 31 | k as u64);
        keys.push(u64::from(b) << 32 | k as u64);
        if v < a && v < b {
            dup.push(u64::from(a.min(b)) << 32 | u64::from(a.max(b)));
            faces_here += 1;
        }
    }
    keys.sort_unstable();
    lp.clear();
    lp.extend(0..d as u32);
    let mut unions = 0usize;
    let (mut bout, mut bin, mut next) = (0u32, 0u32, 0u32);
    let mut bad = false;
    let mut edges_here = 0u32;
    let mut g = 0;
    while g < keys.len() {
        let w = (keys[g] >> 32) as u32;
        let first = (keys[g] & 0x7FFF_FFFF) as u32;
        let (mut n_out, mut n_in) = (0u32, 0u32);
        let mut h = g;
        while h < keys.len() && (keys[h] >> 32) as u32 == w {
            if keys[h] >> 31 & 1 == 1 {
                n_out += 1;
            } else {
                n_in += 1;
            }
            let k = (keys[h] & 0x7FFF_FFFF) as u32;
            if union_smallest(lp, first, k) {
                unions += 1;
            }
            h += 1;
        }
        g = h;
        let m = n_out + n_in;
        let inconsistent = m == 2 && n_out != 1;
        if m == 1 {
            if n_out == 1 {
                bout += 1;
                next = w;
                s.boundary_out.push(w);
            } else {
                bin += 1;
            }
        }
        bad |= m != 2 || inconsistent;
        if w > v {
            edges_here += 1;
            counts.edges += 1;
            counts.boundary += u64::from(m == 1);
            counts.non_manifold_edges += u64::from(m >= 3);
            counts.inconsistent += u64::from(inconsistent);
        }
    }
    if d - unions >= 2 {
        counts.non_manifold_vertices += 1;
        bad = true;
    }
    if dup.len() > 1 {
        dup.sort_unstable();
        counts.duplicates += dup.windows(2).filter(|p| p[0] == p[1]).count() as u64;
    }
    VertexTopology { edges_here, faces_here, bad, simple_next: (bout == 1 && bin == 1).then_some(next) }
}

/// Duplicates among collapsed faces (the per-vertex pass never sees them).
pub fn duplicate_collapsed(faces: &[[u32; 3]]) -> u64 {
    let mut keys: Vec<[u32; 3]> = faces
        .iter()
        .filter(|f| is_collapsed(f))
        .map(|f| {
            let mut k = *f;
            k.sort_unstable();
            k
        })
        .collect();
    keys.sort_unstable();
    keys.windows(2).filter(|p| p[0] == p[1]).count() as u64
}

/// Follows boundary edges from simple boundary vertices (`(v, w)` sorted
/// by `v`); returns the number of closed loops and the number of edges on
/// them.
pub fn walk_boundary_loops(simple: &[(u32, u32)]) -> (u64, u64) {
    let mut visited = vec![false; simple.len()];
    let (mut loops, mut loop_edges) = (0u64, 0u64);
    for start in 0..simple.len() {
        if visited[start] {
            continue;
        }
        visited[start] = true;
        let (u, mut w) = simple[start];
        let mut len = 1u64;
        loop {
            if w == u {
                loops += 1;
                loop_edges += len;
                break;
            }
            match simple.binary_search_by_key(&w, |e| e.0) {
                Ok(i) if !visited[i] => {
                    visited[i] = true;
                    len += 1;
                    w = simple[i].1;
                }
                // A non-simple vertex, or a path already found open.
                _ => break,
            }
        }
    }
    (loops, loop_edges)
}
