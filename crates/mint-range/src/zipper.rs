//! Zippering (`mint zipper`): scans become one mesh, added one at a time,
//! after Turk and Levoy 1994, §5, then consensus geometry (§6, in
//! [`crate::consensus`]).
//!
//! Source: G. Turk and M. Levoy, "Zippered Polygon Meshes from Range
//! Images", SIGGRAPH 1994.
//!
//! The model starts as the first scan (in world coordinates). Each further
//! scan S joins the model M in four steps ([`zipper`]):
//! 1. **Redundancy removal** (§5.1): repeatedly delete boundary triangles
//!    (a corner on the boundary) of S, then of M, whose three corners lie
//!    within `d` of the other mesh at points not on its boundary (the
//!    nearest triangle has no boundary corner). First only where at least
//!    two corners are less confident than the matched points of the other
//!    mesh (the more confident surface stays), then without that
//!    restriction, until nothing changes. Nearest points come from a
//!    [`mint_mesh::TriangleBvh`] over each mesh; a deleted triangle found
//!    nearest counts as "not on the mesh".
//! 2. **Trimming** (mint's step in place of §5.2's wall clipping): the two
//!    meshes now overlap by about one triangle along the seam; boundary
//!    triangles of S whose centroid lies within `d` of M are deleted,
//!    repeatedly, so the meshes meet instead of overlapping.
//! 3. **Stitching** (mint's replacement for the clipping and constrained
//!    re-triangulation of §5.2): along each seam, the boundary of M and the
//!    facing boundary of S (matched vertex to vertex within
//!    [`ZipperOptions::stitch_factor`]·s) are joined by a strip of
//!    triangles, advancing along both boundaries and always taking the
//!    shorter new edge — the classic contour-stitching triangulation of the
//!    polygon between two polylines. A walk stops where a new edge across
//!    the seam would be longer than the matching radius. The meshes then share those boundary
//!    vertices, with no new vertices and no slivers from cutting; an edge
//!    that already exists is never created twice.
//! 4. The union becomes the new model (unused vertices dropped).
//!
//! After the last scan: faces that would make an edge non-manifold are
//! dropped and vertices with several fans are split ([`make_manifold`]),
//! holes of at most [`ZipperOptions::max_hole_edges`] edges (the "tiny
//! gaps" of §5.1) are filled, and **small triangles** are removed (§5.3):
//! the vertex opposite the longest side of a triangle whose altitude is
//! below [`ZipperOptions::min_altitude`]·s is deleted and its hole filled
//! by a fan (a half-edge collapse that keeps the mesh 2-manifold). The
//! result is a 2-manifold with boundary loops where no scan saw the
//! surface.
//!
//! Memory: the model, one scan and two nearest-point trees at a time,
//! plus what the [`ScanSource`] keeps (a set file's scans are loaded on
//! demand within a budget, [`crate::source::ScanFiles`]); consensus
//! geometry then visits the scans one at a time again.

use crate::consensus::{consensus_with, ConsensusOptions, ConsensusReport};
use mint_core::progress::{NoProgress, Progress};
use crate::error::RangeError;
use crate::geom::Rigid;
use crate::mesh_ops::{compact, fill_small_holes, key, make_manifold, remove_small_components, remove_small_triangles};
use crate::scan_mesh::ScanMesh;
use crate::source::ScanSource;
use mint_mesh::TriangleBvh;
use glam::DVec3;
use serde::Serialize;
use rustc_hash::FxHashMap as HashMap;

/// Options of [`zipper`]; every field has a documented default.
#[derive(Debug, Clone, PartialEq)]
pub struct ZipperOptions {
    /// The tolerance d of redundancy removal and trimming, as a multiple of
    /// s (the largest sampling distance of the scans). Default 3.
    pub distance_factor: f64,
    /// Boundary vertices of the two meshes within this multiple of s are
    /// stitched. Default 4 (the longest edge a range mesh keeps).
    pub stitch_factor: f64,
    /// Holes of at most this many edges are filled: the gaps left where a
    /// seam could not be stitched (stitching stops rather than create a
    /// non-manifold edge). Default 24.
    pub max_hole_edges: usize,
    /// Connected pieces of fewer faces are dropped (stray bits of scans).
    /// Default 20.
    pub min_component_faces: usize,
    /// Triangles with an altitude below this multiple of s are removed.
    /// Default 0.1.
    pub min_altitude: f64,
    /// After the last scan, stitch open seams between any two scans again
    /// with twice the radius. Default false.
    pub restitch: bool,
    /// Run consensus geometry at the end. Default true.
    pub consensus: bool,
    /// Options of consensus geometry.
    pub consensus_options: ConsensusOptions,
}

impl Default for ZipperOptions {
    fn default() -> Self {
        ZipperOptions { distance_factor: 3.0, stitch_factor: 4.0, max_hole_edges: 24, min_component_faces: 20, min_altitude: 0.1, restitch: false, consensus: true, consensus_options: ConsensusOptions::default() }
    }
}

/// What [`zipper`] did.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct ZipperReport {
    pub scans: usize,
    /// Triangles deleted as redundant (both meshes, all steps).
    pub redundant: usize,
    /// Triangles deleted by trimming.
    pub trimmed: usize,
    /// Triangles added by stitching.
    pub stitched: usize,
    /// Faces dropped and vertices split to make the result 2-manifold.
    pub non_manifold_faces_dropped: usize,
    pub vertices_split: usize,
    /// Faces of components smaller than `min_component_faces`, dropped.
    pub small_components_faces: usize,
    /// Holes filled.
    pub holes_filled: usize,
    /// Vertices deleted by small-triangle removal.
    pub small_triangle_vertices: usize,
    pub vertices: usize,
    pub faces: usize,
    /// The tolerance d used.
    pub distance: f64,
    pub consensus: Option<ConsensusReport>,
}

/// A mesh being zippered: world positions, per-vertex confidence, faces
/// with a liveness flag.
#[derive(Debug, Clone, Default)]
struct Work {
    pos: Vec<[f64; 3]>,
    conf: Vec<f64>,
    /// The scan each vertex came from.
    origin: Vec<u32>,
    faces: Vec<[u32; 3]>,
    alive: Vec<bool>,
}

impl Work {
    fn from_scan(scan: &ScanMesh, pose: &Rigid, id: u32) -> Work {
        Work {
            origin: vec![id; scan.positions.len()],
            pos: scan.positions.iter().map(|&p| pose.apply(p)).collect(),
            conf: scan.confidence.clone(),
            faces: scan.faces.clone(),
            alive: vec![true; scan.faces.len()],
        }
    }

    /// Keeps live faces and used vertices.
    fn compacted(mut self) -> Work {
        let mut faces: Vec<[u32; 3]> = self.faces.iter().zip(&self.alive).filter(|(_, &a)| a).map(|(f, _)| *f).collect();
        let old = self.pos.clone();
        let map = compact(&mut self.pos, &mut faces);
        let mut conf = vec![0.0; self.pos.len()];
        let mut origin = vec![0; self.pos.len()];
        for (o, &n) in map.iter().enumerate() {
            if n != u32::MAX {
                conf[n as usize] = self.conf[o];
                origin[n as usize] = self.origin[o];
            }
        }
        debug_assert_eq!(old.len(), map.len());
        Work { pos: self.pos, conf, origin, alive: vec![true; faces.len()], faces }
    }
}

/// Live boundary bookkeeping of a [`Work`]: alive faces per undirected edge
/// and, per vertex, the number of incident boundary edges.
struct Topo {
    edge_faces: HashMap<(u32, u32), u32>,
    boundary_edges: Vec<u32>,
}

impl Topo {
    fn new(w: &Work) -> Topo {
        let mut edge_faces = HashMap::with_capacity_and_hasher(w.faces.len() * 3 / 2, Default::default());
        for (i, f) in w.faces.iter().enumerate() {
            if !w.alive[i] {
                continue;
            }
            for k in 0..3 {
                *edge_faces.entry(key(f[k], f[(k + 1) % 3])).or_insert(0) += 1;
            }
        }
        let mut boundary_edges = vec![0u32; w.pos.len()];
        for (&(a, b), &n) in &edge_faces {
            if n == 1 {
                boundary_edges[a as usize] += 1;
                boundary_edges[b as usize] += 1;
            }
        }
        Topo { edge_faces, boundary_edges }
    }

    #[inline]
    fn on_boundary(&self, v: u32) -> bool {
        self.boundary_edges[v as usize] > 0
    }

    fn remove(&mut self, w: &mut Work, f: u32) {
        w.alive[f as usize] = false;
        let t = w.faces[f as usize];
        for k in 0..3 {
            let e = key(t[k], t[(k + 1) % 3]);
            let n = self.edge_faces.get_mut(&e).expect("a live face's edge is counted");
            *n -= 1;
            match *n {
                1 => {
                    self.boundary_edges[e.0 as usize] += 1;
                    self.boundary_edges[e.1 as usize] += 1;
                }
                0 => {
                    self.boundary_edges[e.0 as usize] -= 1;
                    self.boundary_edges[e.1 as usize] -= 1;
                }
                _ => {}
            }
        }
    }
}

/// Zippers the scans at their poses into one mesh (see the module docs),
/// then runs consensus geometry if asked. Returns `(positions, faces,
/// report)`. Errors: mismatched lengths, no scans, bad options.
pub fn zipper<S: ScanSource + ?Sized>(scans: &S, poses: &[Rigid], opts: &ZipperOptions) -> Result<crate::Merged<ZipperReport>, RangeError> {
    zipper_with(scans, poses, opts, &NoProgress)
}

/// [`zipper`], reporting each scan joined ([`crate::phases::ZIPPER`]) and the
/// consensus passes, and stopping with [`RangeError::Cancelled`] between
/// scans when asked.
pub fn zipper_with<S: ScanSource + ?Sized>(scans: &S, poses: &[Rigid], opts: &ZipperOptions, progress: &dyn Progress) -> Result<crate::Merged<ZipperReport>, RangeError> {
    if scans.is_empty() {
        return Err(RangeError::option("scans", "nothing to zipper"));
    }
    if scans.len() != poses.len() {
        return Err(RangeError::option("poses", format!("{} poses for {} scans", poses.len(), scans.len())));
    }
    for (name, v) in [("distance_factor", opts.distance_factor), ("stitch_factor", opts.stitch_factor), ("min_altitude", opts.min_altitude)] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(RangeError::option(name, format!("{v} is not a finite non-negative number")));
        }
    }
    let s = scans.max_sampling();
    let d = opts.distance_factor * s;
    let mut report = ZipperReport { scans: scans.len(), distance: d, ..Default::default() };
    progress.start(crate::phases::ZIPPER, poses.len() as u64);
    let mut model = Work::from_scan(&*scans.scan(0)?, &poses[0], 0);
    progress.advance(1);
    for (k, pose) in poses.iter().enumerate().skip(1) {
        if progress.cancelled() {
            return Err(RangeError::Cancelled);
        }
        let mut sw = Work::from_scan(&*scans.scan(k)?, pose, k as u32);
        zip_pair(&mut model, &mut sw, d, opts.stitch_factor * s, &mut report)?;
        progress.advance(1);
    }
    progress.finish();
    if opts.restitch {
        // A last pass over seams left open between any two scans, with
        // twice the radius.
        report.stitched += stitch(&mut model, 2.0 * opts.stitch_factor * s, None);
    }
    let mut pos = model.pos;
    let mut faces: Vec<[u32; 3]> = model.faces.iter().zip(&model.alive).filter(|(_, &a)| a).map(|(f, _)| *f).collect();
    let (dropped, split) = make_manifold(&mut pos, &mut faces);
    report.non_manifold_faces_dropped += dropped;
    report.vertices_split += split;
    report.small_components_faces = remove_small_components(&mut faces, opts.min_component_faces);
    report.holes_filled = fill_small_holes(&pos, &mut faces, opts.max_hole_edges);
    report.small_triangle_vertices = remove_small_triangles(&pos, &mut faces, opts.min_altitude * s);
    let (dropped, split) = make_manifold(&mut pos, &mut faces);
    report.non_manifold_faces_dropped += dropped;
    report.vertices_split += split;
    compact(&mut pos, &mut faces);
    if opts.consensus {
        report.consensus = Some(consensus_with(&mut pos, &faces, scans, poses, &opts.consensus_options, progress)?);
    }
    report.vertices = pos.len();
    report.faces = faces.len();
    Ok((pos, faces, report))
}

fn bvh(w: &Work) -> Result<Option<TriangleBvh>, RangeError> {
    if w.faces.is_empty() {
        return Ok(None);
    }
    TriangleBvh::new(&w.pos, &w.faces).map(Some).map_err(|e| RangeError::Mesh { what: "zipper".into(), source: e })
}

/// Joins `s` into `m` (steps 1–4 of the module docs).
fn zip_pair(m: &mut Work, s: &mut Work, d: f64, stitch_r: f64, report: &mut ZipperReport) -> Result<(), RangeError> {
    let (Some(bm), Some(bs)) = (bvh(m)?, bvh(s)?) else {
        // One side is empty: the union is the other.
        append(m, s);
        return Ok(());
    };
    let mut tm = Topo::new(m);
    let mut ts = Topo::new(s);
    let mut nm = Nearest::new(m);
    let mut ns = Nearest::new(s);
    // 1. Redundancy removal: with the confidence rule, then without. A
    //    face that fails the test keeps failing while the rule stays (the
    //    other mesh only loses faces, so its nearest triangle only dies or
    //    gains boundary corners) — except when a vertex of the other mesh
    //    leaves the boundary but keeps faces, which is checked. So each
    //    pass looks only at faces around the last pass's deletions.
    for use_conf in [true, false] {
        let mut cand_s = boundary_faces(s, &ts);
        let mut cand_m = boundary_faces(m, &tm);
        loop {
            let cut_s = eat(s, &mut ts, &mut ns, &cand_s, m, &tm, &bm, d, use_conf);
            let cut_m = eat(m, &mut tm, &mut nm, &cand_m, s, &ts, &bs, d, use_conf);
            report.redundant += cut_s.len() + cut_m.len();
            if cut_s.is_empty() && cut_m.is_empty() {
                break;
            }
            // A face that failed can pass again only if a vertex of the
            // other mesh stopped being a boundary vertex while keeping
            // faces (possible on the model, whose stitched vertices may
            // have several fans): then look at every boundary face again.
            cand_s = if nm.left_boundary_keeping_faces(m, &tm, &cut_m) { boundary_faces(s, &ts) } else { ns.faces_around(s, &cut_s) };
            cand_m = if ns.left_boundary_keeping_faces(s, &ts, &cut_s) { boundary_faces(m, &tm) } else { nm.faces_around(m, &cut_m) };
        }
    }
    // 2. Trimming: S retreats until it meets M instead of overlapping it.
    //    Only where the centroid lies over M: its nearest point is inside a
    //    live triangle of M, not on that triangle's edges. M does not
    //    change here, so again only faces around deletions are looked at
    //    again.
    let mut cand = boundary_faces(s, &ts);
    loop {
        let cut: Vec<u32> = {
            use rayon::prelude::*;
            let (sr, tsr, mr) = (&*s, &ts, &*m);
            cand.par_iter()
                .copied()
                .filter(|&fi| {
                    let f = sr.faces[fi as usize];
                    if !sr.alive[fi as usize] || !f.iter().any(|&v| tsr.on_boundary(v)) {
                        return false;
                    }
                    let [a, b, c] = f.map(|v| DVec3::from(sr.pos[v as usize]));
                    let c = ((a + b + c) * (1.0 / 3.0)).to_array();
                    bm.nearest_within(c, d).is_some_and(|(_, cp, mf)| mr.alive[mf as usize] && strictly_inside(cp, mr.faces[mf as usize].map(|v| mr.pos[v as usize])))
                })
                .collect()
        };
        if cut.is_empty() {
            break;
        }
        report.trimmed += cut.len();
        for &f in &cut {
            ts.remove(s, f);
        }
        cand = ns.faces_around(s, &cut);
    }
    // 3. Stitching, on the union. Only edges between boundary vertices can
    // matter to it, and the union's boundary is the two boundaries.
    let mut on_boundary: Vec<bool> = (0..m.pos.len() as u32).map(|v| tm.on_boundary(v)).collect();
    on_boundary.extend((0..s.pos.len() as u32).map(|v| ts.on_boundary(v)));
    append(m, s);
    report.stitched += stitch(m, stitch_r, Some(&on_boundary));
    // 4. The union is the new model.
    *m = std::mem::take(m).compacted();
    Ok(())
}

/// True when `p` (a point of triangle `t`'s plane) has all barycentric
/// coordinates above 1e-9: it is not on an edge of `t`.
fn strictly_inside(p: [f64; 3], t: [[f64; 3]; 3]) -> bool {
    let (p, t) = (DVec3::from(p), t.map(DVec3::from));
    let n = (t[1] - t[0]).cross(t[2] - t[0]);
    let nn = n.dot(n);
    if nn == 0.0 {
        return false;
    }
    (0..3).all(|k| (t[(k + 2) % 3] - t[(k + 1) % 3]).cross(p - t[(k + 1) % 3]).dot(n) / nn > 1e-9)
}

/// Moves `s`'s live faces and vertices into `m`.
fn append(m: &mut Work, s: &Work) {
    let off = m.pos.len() as u32;
    m.pos.extend_from_slice(&s.pos);
    m.conf.extend_from_slice(&s.conf);
    m.origin.extend_from_slice(&s.origin);
    for (f, &a) in s.faces.iter().zip(&s.alive) {
        if a {
            m.faces.push(f.map(|v| v + off));
            m.alive.push(true);
        }
    }
}

/// The faces of `w` with a live boundary corner, in index order.
fn boundary_faces(w: &Work, t: &Topo) -> Vec<u32> {
    (0..w.faces.len() as u32).filter(|&f| w.alive[f as usize] && w.faces[f as usize].iter().any(|&v| t.on_boundary(v))).collect()
}

/// Per vertex of one mesh: its faces (for the worklists) and, computed
/// once per pair of meshes, the nearest face of the other mesh within `d`
/// (the tree does not change while the pair is zippered; whether that face
/// is still alive is checked at each use).
struct Nearest {
    face_start: Vec<u32>,
    face_list: Vec<u32>,
    /// `UNKNOWN`, `NONE`, or a face of the other mesh.
    near: Vec<u32>,
}

const UNKNOWN: u32 = u32::MAX;
const NONE: u32 = u32::MAX - 1;

impl Nearest {
    fn new(w: &Work) -> Nearest {
        let mut face_start = vec![0u32; w.pos.len() + 1];
        for f in &w.faces {
            for &v in f {
                face_start[v as usize + 1] += 1;
            }
        }
        for i in 0..w.pos.len() {
            face_start[i + 1] += face_start[i];
        }
        let mut fill = face_start.clone();
        let mut face_list = vec![0u32; face_start[w.pos.len()] as usize];
        for (fi, f) in w.faces.iter().enumerate() {
            for &v in f {
                face_list[fill[v as usize] as usize] = fi as u32;
                fill[v as usize] += 1;
            }
        }
        Nearest { face_start, face_list, near: vec![UNKNOWN; w.pos.len()] }
    }

    /// Live faces sharing a vertex with the faces `cut`, sorted, unique.
    fn faces_around(&self, w: &Work, cut: &[u32]) -> Vec<u32> {
        let mut out: Vec<u32> = cut
            .iter()
            .flat_map(|&f| w.faces[f as usize])
            .flat_map(|v| &self.face_list[self.face_start[v as usize] as usize..self.face_start[v as usize + 1] as usize])
            .copied()
            .filter(|&f| w.alive[f as usize])
            .collect();
        out.sort_unstable();
        out.dedup();
        out
    }

    /// True if a corner of the deleted faces `cut` is no longer on the
    /// boundary of `w` but still has live faces.
    fn left_boundary_keeping_faces(&self, w: &Work, t: &Topo, cut: &[u32]) -> bool {
        cut.iter().flat_map(|&f| w.faces[f as usize]).any(|v| {
            !t.on_boundary(v) && self.face_list[self.face_start[v as usize] as usize..self.face_start[v as usize + 1] as usize].iter().any(|&f| w.alive[f as usize])
        })
    }

    /// Fills in the nearest faces of the corners of `faces` not yet known.
    fn resolve(&mut self, x: &Work, faces: &[u32], by: &TriangleBvh, d: f64) {
        use rayon::prelude::*;
        let mut todo: Vec<u32> = faces.iter().flat_map(|&f| x.faces[f as usize]).filter(|&v| self.near[v as usize] == UNKNOWN).collect();
        todo.sort_unstable();
        todo.dedup();
        let found: Vec<u32> = todo.par_iter().map(|&v| by.nearest_within(x.pos[v as usize], d).map_or(NONE, |(_, _, f)| f)).collect();
        for (v, f) in todo.into_iter().zip(found) {
            self.near[v as usize] = f;
        }
    }
}

/// One pass of redundancy removal of `x`'s boundary triangles (among
/// `candidates`) against `y`; returns the deleted faces.
#[allow(clippy::too_many_arguments)]
fn eat(x: &mut Work, tx: &mut Topo, nx: &mut Nearest, candidates: &[u32], y: &Work, ty: &Topo, by: &TriangleBvh, d: f64, use_conf: bool) -> Vec<u32> {
    let candidates: Vec<u32> = candidates.iter().copied().filter(|&f| x.alive[f as usize] && x.faces[f as usize].iter().any(|&v| tx.on_boundary(v))).collect();
    nx.resolve(x, &candidates, by, d);
    // The mean confidence of the nearest face of y, if it is alive and has
    // no boundary corner.
    let near = |v: u32| -> Option<f64> {
        let f = nx.near[v as usize];
        if f == NONE || !y.alive[f as usize] {
            return None;
        }
        let t = y.faces[f as usize];
        if t.iter().any(|&w| ty.on_boundary(w)) {
            return None;
        }
        Some(t.iter().map(|&w| y.conf[w as usize]).sum::<f64>() / 3.0)
    };
    let mut cut = Vec::new();
    for &fi in &candidates {
        let f = x.faces[fi as usize];
        let mut lower = 0;
        let mut all = true;
        for &v in &f {
            match near(v) {
                Some(c) => {
                    if x.conf[v as usize] < c {
                        lower += 1;
                    }
                }
                None => {
                    all = false;
                    break;
                }
            }
        }
        if all && (!use_conf || lower >= 2) {
            cut.push(fi);
        }
    }
    for &f in &cut {
        tx.remove(x, f);
    }
    cut
}

/// Stitches boundaries of `w` that come from different scans; returns the
/// number of triangles added. `boundary`, when given, marks every vertex
/// on a boundary edge (others may be marked too): only edges between
/// marked vertices are then indexed, which is all stitching looks at.
fn stitch(w: &mut Work, r: f64, boundary: Option<&[bool]>) -> usize {
    // Directed half-edges of live faces; boundary half-edges have no twin.
    let mut half: HashMap<(u32, u32), u32> = HashMap::default();
    let mut undirected: HashMap<(u32, u32), u8> = HashMap::default();
    let indexed = |a: u32, b: u32| boundary.is_none_or(|m| m[a as usize] && m[b as usize]);
    for (i, f) in w.faces.iter().enumerate() {
        if !w.alive[i] {
            continue;
        }
        for k in 0..3 {
            if !indexed(f[k], f[(k + 1) % 3]) {
                continue;
            }
            half.insert((f[k], f[(k + 1) % 3]), i as u32);
            *undirected.entry(key(f[k], f[(k + 1) % 3])).or_insert(0) += 1;
        }
    }
    // next/prev along boundaries, only at vertices with one boundary fan.
    let mut next: HashMap<u32, u32> = HashMap::default();
    let mut prev: HashMap<u32, u32> = HashMap::default();
    let mut multi: HashMap<u32, ()> = HashMap::default();
    for &(a, b) in half.keys() {
        if half.contains_key(&(b, a)) {
            continue;
        }
        if next.insert(a, b).is_some() {
            multi.insert(a, ());
        }
        if prev.insert(b, a).is_some() {
            multi.insert(b, ());
        }
    }
    for v in multi.keys() {
        next.remove(v);
        prev.remove(v);
    }
    // Nearest boundary vertex of the other part within r, through a hash grid.
    let cell = r.max(f64::MIN_POSITIVE);
    let ckey = |p: [f64; 3]| [0, 1, 2].map(|k| (p[k] / cell).floor() as i64);
    let dist = |a: u32, b: u32| DVec3::from(w.pos[a as usize]).distance(DVec3::from(w.pos[b as usize]));
    let mut grid: HashMap<[i64; 3], Vec<u32>> = HashMap::default();
    for &v in next.keys() {
        grid.entry(ckey(w.pos[v as usize])).or_default().push(v);
    }
    let side = |v: u32| w.origin[v as usize];
    let partner = |v: u32| -> Option<u32> {
        let c = ckey(w.pos[v as usize]);
        let mut best: Option<(f64, u32)> = None;
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some(list) = grid.get(&[c[0] + dx, c[1] + dy, c[2] + dz]) {
                        for &u in list {
                            if side(u) == side(v) {
                                continue;
                            }
                            let dd = dist(v, u);
                            if dd <= r && best.is_none_or(|b| dd < b.0 || (dd == b.0 && u < b.1)) {
                                best = Some((dd, u));
                            }
                        }
                    }
                }
            }
        }
        best.map(|b| b.1)
    };
    let mut matched: HashMap<u32, u32> = HashMap::default();
    let mut starts: Vec<u32> = next.keys().copied().collect();
    starts.sort_unstable();
    for &v in next.keys() {
        if let Some(u) = partner(v) {
            matched.insert(v, u);
        }
    }
    // Start each walk at the first matched vertex of a run along the model's
    // boundary (a vertex whose predecessor is unmatched), then anywhere.
    starts.sort_by_key(|&a| {
        let run_start = prev.get(&a).is_none_or(|p| !matched.contains_key(p));
        (!run_start, a)
    });
    let mut used: HashMap<(u32, u32), ()> = HashMap::default();
    let mut added = 0;
    let mut new_faces = Vec::new();
    for a0 in starts {
        let Some(&b0) = matched.get(&a0) else { continue };
        if !prev.contains_key(&b0) || !next.contains_key(&a0) {
            continue;
        }
        let (mut a, mut b) = (a0, b0);
        let mut steps = 0usize;
        loop {
            steps += 1;
            if steps > 100_000 {
                break;
            }
            let can_a = next.get(&a).copied().filter(|&a2| matched.contains_key(&a2) && !used.contains_key(&(a, a2)) && a2 != b && side(a2) != side(b));
            let can_b = prev.get(&b).copied().filter(|&b2| matched.contains_key(&b2) && !used.contains_key(&(b2, b)) && b2 != a && side(b2) != side(a));
            // A new face must not repeat a half-edge nor overload an edge.
            let ok = |f: [u32; 3], half: &HashMap<(u32, u32), u32>, und: &HashMap<(u32, u32), u8>| {
                (0..3).all(|k| {
                    let (x, y) = (f[k], f[(k + 1) % 3]);
                    !half.contains_key(&(x, y)) && und.get(&key(x, y)).copied().unwrap_or(0) < 2
                })
            };
            // ... and its new edge across the seam stays within r: a walk
            // never drifts along one boundary while the other lags behind.
            let fa = can_a.map(|a2| [a2, a, b]).filter(|f| ok(*f, &half, &undirected) && dist(f[0], b) <= r);
            let fb = can_b.map(|b2| [b, b2, a]).filter(|f| ok(*f, &half, &undirected) && dist(f[1], a) <= r);
            let take_a = match (fa, fb) {
                (Some(_), Some(_)) => {
                    let la = dist(can_a.unwrap(), b);
                    let lb = dist(a, can_b.unwrap());
                    la <= lb
                }
                (Some(_), None) => true,
                (None, Some(_)) => false,
                (None, None) => break,
            };
            let f = if take_a { fa.unwrap() } else { fb.unwrap() };
            for k in 0..3 {
                half.insert((f[k], f[(k + 1) % 3]), u32::MAX);
                *undirected.entry(key(f[k], f[(k + 1) % 3])).or_insert(0) += 1;
            }
            new_faces.push(f);
            added += 1;
            if take_a {
                let a2 = can_a.unwrap();
                used.insert((a, a2), ());
                a = a2;
            } else {
                let b2 = can_b.unwrap();
                used.insert((b2, b), ());
                b = b2;
            }
            if a == a0 && b == b0 {
                break;
            }
        }
    }
    for f in new_faces {
        w.faces.push(f);
        w.alive.push(true);
    }
    added
}
