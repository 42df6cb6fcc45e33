//! Cross-section triangulation with the angle criterion (Dangl 1998, §2.2),
//! with branching handled by splitting contours.
//!
//! Sources:
//! - M. Dangl 1998, §2.2.1 (start pair: the vertex farthest from its
//!   contour's centroid, then the vertex of the next contour with the
//!   largest inner product of centroid vectors among those in a similar
//!   direction) and §2.2.2 (next vertex: the shorter new diagonal unless the
//!   direction criterion says otherwise).
//! - A. Klingert, W. Straub, "A Robust and Efficient Triangulation Algorithm
//!   for Contours on Parallel Planes", Report 11/92, Univ. Karlsruhe, 1992
//!   (the problem statement the 1998 method follows).
//! - D. Meyers, S. Skinner, K. Sloan, "Surfaces from contours", ACM TOG
//!   11(3), 1992, §4: branching by splitting the single contour so that each
//!   part pairs with one contour of the other section.
//!
//! # Data flow
//! Each [`Section`] becomes a `Prepared` section: its vertices are sent to the
//! sink at once (ids in file order), and each contour becomes a ring of ids,
//! counter-clockwise around solid (even nesting depth) or clockwise (holes),
//! so that "the solid is on the left" for every ring. For each pair of
//! consecutive sections, contours of equal depth parity whose projections
//! overlap are linked; each connected group of links is then
//! - one lower and one upper contour: a *tube*, triangulated by the march;
//! - one contour facing k > 1 (a branch or a merge): the single contour is
//!   split along chords between its vertices, each chord separating the
//!   partners' centroids; each part forms a tube with one partner, and the
//!   chord edge is shared by two tubes in opposite directions;
//! - anything else (k ≥ 2 facing m ≥ 2), or a split that found no chord:
//!   the best-overlapping pairs form tubes, the rest are left unmatched
//!   (counted in [`AngleStats::complex_groups`] and
//!   [`AngleStats::unsplit_groups`]).
//!
//! With `caps`, every contour end is closed by a smallest-inner-angle
//! triangulation of its section's region: the first and last sections, and
//! contours that appear or vanish inside the stack. A contour with no
//! partner on either side (it exists in one section only) has no thickness
//! and is left out ([`AngleStats::isolated`]); so is every contour of a
//! one-section stack. A ring turning
//! `P_i → P_i+1` below `Q_j → Q_j+1` gives the triangles `(P_i, P_i+1, Q_j)`
//! and `(P_i, Q_j+1, Q_j)`, which face out of the solid; so closed stacks
//! with caps are watertight and consistently oriented.
//!
//! # The march
//! From the start pair, `n + m` steps (closed contours) each emit one
//! triangle. With `dP = |P_i+1 Q_j|` and `dQ = |P_i Q_j+1|`: when `dP ≤ dQ`,
//! let α be the angle between `P_i → P_i+1` and `Q_j-1 → Q_j` and β the
//! angle between `P_i-1 → P_i` and `Q_j → Q_j+1`; take `P_i+1` if
//! `cos α > t`, else `Q_j+1` if `cos β > t`, else `P_i+1` (the paper's rule).
//! When `dQ < dP` the same rule with the roles of P and Q exchanged. Open
//! contours (`open`) march from first vertices to last vertices (`n + m - 2`
//! triangles), the upper polyline reversed if that pairs the ends better.
//!
//! # Limits (honest)
//! The march is a heuristic: contours that differ a lot in shape between
//! sections can give triangles that cross other triangles; splitting needs
//! a chord inside the contour that separates the partners, and when none is
//! found the group is joined one to one by overlap instead
//! ([`AngleStats::unsplit_groups`]), and the capped leftovers may cross the
//! tube beside them. The marching-cubes method has none of
//! these limits.

use crate::error::ContourError;
use crate::geom2d::{centroid, first_crossing, inside, orient, segments_touch, signed_area, P2};
use crate::profile::Section;
use crate::triangulate::triangulate;
use mint_core::MeshSink;
use serde::Serialize;

/// Options of the angle method.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AngleOptions {
    /// The direction threshold t (a cosine, in [-1, 1]). Default 0.5
    /// (60°): a direction difference above 60° is not "in agreement".
    pub threshold: f64,
    /// Contours are open polylines, not closed polygons. Default false.
    pub open: bool,
    /// Close contour ends with triangulated caps. Default false.
    pub caps: bool,
}

impl Default for AngleOptions {
    fn default() -> Self {
        AngleOptions { threshold: 0.5, open: false, caps: false }
    }
}

/// What one reconstruction did.
#[derive(Debug, Default, Clone, Serialize, PartialEq, Eq)]
pub struct AngleStats {
    /// Contour pairs joined by a strip of triangles.
    pub tubes: u64,
    /// Contours split to pair with several contours of the next or previous
    /// section (branches and merges).
    pub splits: u64,
    /// Branching groups whose split failed; they were joined one to one by
    /// overlap instead, and the contours left over capped (or left open).
    pub unsplit_groups: u64,
    /// Groups of several contours facing several, joined pairwise by overlap.
    pub complex_groups: u64,
    /// Caps triangulated (regions, each with its holes).
    pub caps: u64,
    /// Contours with no partner in either neighbouring section: they have
    /// no thickness and are left out (no faces).
    pub isolated: u64,
    /// Ears forced while triangulating caps (0 on valid input).
    pub forced_ears: u64,
    pub vertices: u64,
    pub faces: u64,
}

/// A ring of a prepared section: global ids and positions, oriented with
/// the solid on its left.
#[derive(Debug, Clone)]
struct Ring {
    ids: Vec<u32>,
    uv: Vec<P2>,
    depth: usize,
    centroid: P2,
    lo: P2,
    hi: P2,
}

#[derive(Debug, Clone)]
struct Prepared {
    rings: Vec<Ring>,
}

/// The angle-criterion reconstruction of a stack streamed section by
/// section: [`push`](AngleReconstructor::push) each section in order, then
/// [`finish`](AngleReconstructor::finish).
pub struct AngleReconstructor {
    opts: AngleOptions,
    prev: Option<Prepared>,
    /// For each ring of `prev`: does it have a partner below?
    prev_has_below: Vec<bool>,
    emitted: u64,
    stats: AngleStats,
}

impl AngleReconstructor {
    /// Starts a reconstruction.
    pub fn new(opts: AngleOptions) -> AngleReconstructor {
        AngleReconstructor { opts, prev: None, prev_has_below: Vec::new(), emitted: 0, stats: AngleStats::default() }
    }

    /// Adds the next section: sends its vertices, joins it to the previous
    /// one and closes the previous one's contour ends.
    pub fn push(&mut self, section: &Section, sink: &mut dyn MeshSink) -> Result<(), ContourError> {
        let cur = self.prepare(section, sink)?;
        let mut cur_has_below = vec![false; cur.rings.len()];
        if let Some(prev) = self.prev.take() {
            let mut prev_has_above = vec![false; prev.rings.len()];
            self.join(&prev, &cur, &mut prev_has_above, &mut cur_has_below, sink)?;
            let below = std::mem::take(&mut self.prev_has_below);
            self.close_ends(&prev, &below, &prev_has_above, sink)?;
        }
        self.prev = Some(cur);
        self.prev_has_below = cur_has_below;
        Ok(())
    }

    /// Closes the last section and returns the counters.
    pub fn finish(mut self, sink: &mut dyn MeshSink) -> Result<AngleStats, ContourError> {
        if let Some(prev) = self.prev.take() {
            let below = std::mem::take(&mut self.prev_has_below);
            let above = vec![false; prev.rings.len()];
            self.close_ends(&prev, &below, &above, sink)?;
        }
        Ok(self.stats)
    }

    /// Caps a section's contours once both neighbours are known: a bottom
    /// cap where a contour has nothing below, a top cap where it has nothing
    /// above. A contour with nothing on either side has no thickness: it is
    /// left out ([`AngleStats::isolated`]) rather than covered by two
    /// coincident caps.
    fn close_ends(&mut self, s: &Prepared, below: &[bool], above: &[bool], sink: &mut dyn MeshSink) -> Result<(), ContourError> {
        let n = s.rings.len();
        let isolated = (0..n).filter(|&i| !below[i] && !above[i]).count();
        self.stats.isolated += isolated as u64;
        if !self.opts.caps || self.opts.open {
            return Ok(());
        }
        let bottom: Vec<usize> = (0..n).filter(|&i| !below[i] && above[i]).collect();
        let top: Vec<usize> = (0..n).filter(|&i| below[i] && !above[i]).collect();
        self.cap(s, &bottom, false, sink)?;
        self.cap(s, &top, true, sink)
    }

    /// Sends a section's vertices and builds its rings.
    fn prepare(&mut self, s: &Section, sink: &mut dyn MeshSink) -> Result<Prepared, ContourError> {
        let mut rings = Vec::with_capacity(s.contours.len());
        for c in &s.contours {
            let base = self.emitted as u32;
            for p in &c.points {
                sink.vertex(*p)?;
            }
            self.emitted += c.points.len() as u64;
            self.stats.vertices += c.points.len() as u64;
            let ids: Vec<u32> = (0..c.points.len() as u32).map(|k| base + k).collect();
            rings.push(make_ring(ids, c.uv.clone(), 0));
        }
        if !self.opts.open {
            // Nesting depth by even-odd containment of one vertex; rings
            // counter-clockwise at even depth, clockwise at odd depth.
            let depths: Vec<usize> = (0..rings.len())
                .map(|i| (0..rings.len()).filter(|&j| j != i && inside(&rings[j].uv, rings[i].uv[0])).count())
                .collect();
            for (r, d) in rings.iter_mut().zip(depths) {
                r.depth = d;
                let ccw = signed_area(&r.uv) > 0.0;
                if ccw != (d % 2 == 0) {
                    r.ids.reverse();
                    r.uv.reverse();
                }
            }
        }
        Ok(Prepared { rings })
    }

    /// Links overlapping rings of two sections and triangulates each group.
    fn join(&mut self, lower: &Prepared, upper: &Prepared, has_above: &mut [bool], has_below: &mut [bool], sink: &mut dyn MeshSink) -> Result<(), ContourError> {
        let (nl, nu) = (lower.rings.len(), upper.rings.len());
        let mut links: Vec<(usize, usize, f64)> = Vec::new();
        for i in 0..nl {
            for j in 0..nu {
                let (p, q) = (&lower.rings[i], &upper.rings[j]);
                if p.depth % 2 != q.depth % 2 {
                    continue;
                }
                if let Some(score) = overlap(p, q, self.opts.open) {
                    links.push((i, j, score));
                }
            }
        }
        // Connected groups (union-find over lower 0..nl and upper nl..).
        let mut parent: Vec<usize> = (0..nl + nu).collect();
        fn find(p: &mut [usize], x: usize) -> usize {
            let mut r = x;
            while p[r] != r {
                r = p[r];
            }
            let mut y = x;
            while p[y] != r {
                let n = p[y];
                p[y] = r;
                y = n;
            }
            r
        }
        for &(i, j, _) in &links {
            let (a, b) = (find(&mut parent, i), find(&mut parent, nl + j));
            if a != b {
                parent[a.max(b)] = a.min(b);
            }
        }
        let mut groups: std::collections::BTreeMap<usize, (Vec<usize>, Vec<usize>)> = Default::default();
        for &(i, j, _) in &links {
            let r = find(&mut parent, i);
            let g = groups.entry(r).or_default();
            if !g.0.contains(&i) {
                g.0.push(i);
            }
            if !g.1.contains(&j) {
                g.1.push(j);
            }
        }
        for (_, (ls, us)) in groups {
            match (ls.len(), us.len()) {
                (1, 1) => {
                    self.tube(&lower.rings[ls[0]].ids, &lower.rings[ls[0]].uv, &upper.rings[us[0]].ids, &upper.rings[us[0]].uv, sink)?;
                    has_above[ls[0]] = true;
                    has_below[us[0]] = true;
                }
                (1, _) | (_, 1) if !self.opts.open => {
                    // One contour against several: split the single one.
                    let single_is_lower = ls.len() == 1;
                    let (single, many, single_sec, many_sec) =
                        if single_is_lower { (ls[0], &us, lower, upper) } else { (us[0], &ls, upper, lower) };
                    let partners: Vec<&Ring> = many.iter().map(|&k| &many_sec.rings[k]).collect();
                    let others: Vec<&[P2]> = single_sec.rings.iter().enumerate().filter(|&(k, _)| k != single).map(|(_, r)| r.uv.as_slice()).collect();
                    let ring = &single_sec.rings[single];
                    match split_for(ring, &partners, &others) {
                        Some(parts) => {
                            self.stats.splits += 1;
                            for (part, k) in parts {
                                let m = &many_sec.rings[many[k]];
                                if single_is_lower {
                                    self.tube(&part.0, &part.1, &m.ids, &m.uv, sink)?;
                                } else {
                                    self.tube(&m.ids, &m.uv, &part.0, &part.1, sink)?;
                                }
                            }
                            for &i in &ls {
                                has_above[i] = true;
                            }
                            for &j in &us {
                                has_below[j] = true;
                            }
                        }
                        None => {
                            // No chord: pair the best overlap, cap the rest.
                            self.stats.unsplit_groups += 1;
                            self.pair_by_overlap(&links, &ls, &us, lower, upper, has_above, has_below, sink)?;
                        }
                    }
                }
                _ => {
                    // Several against several: best overlaps first, one to one.
                    self.stats.complex_groups += 1;
                    self.pair_by_overlap(&links, &ls, &us, lower, upper, has_above, has_below, sink)?;
                }
            }
        }
        Ok(())
    }

    /// Joins the group's contours one to one, best overlap first; the rest
    /// stay unmatched (and are capped).
    #[allow(clippy::too_many_arguments)]
    fn pair_by_overlap(
        &mut self,
        links: &[(usize, usize, f64)],
        ls: &[usize],
        us: &[usize],
        lower: &Prepared,
        upper: &Prepared,
        has_above: &mut [bool],
        has_below: &mut [bool],
        sink: &mut dyn MeshSink,
    ) -> Result<(), ContourError> {
        let mut cand: Vec<&(usize, usize, f64)> = links.iter().filter(|l| ls.contains(&l.0) && us.contains(&l.1)).collect();
        cand.sort_by(|a, b| b.2.total_cmp(&a.2).then((a.0, a.1).cmp(&(b.0, b.1))));
        for &&(i, j, _) in &cand {
            if has_above[i] || has_below[j] {
                continue;
            }
            self.tube(&lower.rings[i].ids, &lower.rings[i].uv, &upper.rings[j].ids, &upper.rings[j].uv, sink)?;
            has_above[i] = true;
            has_below[j] = true;
        }
        Ok(())
    }

    /// One strip of triangles between a lower and an upper ring.
    fn tube(&mut self, pid: &[u32], puv: &[P2], qid: &[u32], quv: &[P2], sink: &mut dyn MeshSink) -> Result<(), ContourError> {
        self.stats.tubes += 1;
        let t = self.opts.threshold;
        let (n, m) = (pid.len(), qid.len());
        let mut emit = |f: [u32; 3], stats: &mut AngleStats| -> Result<(), ContourError> {
            stats.faces += 1;
            Ok(sink.face(f)?)
        };
        if self.opts.open {
            // Orient Q like P, then march from the first to the last vertices.
            let d = |a: P2, b: P2| (a[0] - b[0]).hypot(a[1] - b[1]);
            let same = d(puv[0], quv[0]) + d(puv[n - 1], quv[m - 1]);
            let rev = d(puv[0], quv[m - 1]) + d(puv[n - 1], quv[0]);
            let qmap: Vec<usize> = if rev < same { (0..m).rev().collect() } else { (0..m).collect() };
            let (mut i, mut j) = (0usize, 0usize);
            while i + 1 < n || j + 1 < m {
                let take_p = if i + 1 == n {
                    false
                } else if j + 1 == m {
                    true
                } else {
                    let p = |k: usize| puv[k];
                    let q = |k: usize| quv[qmap[k]];
                    decide(p(i), p(i + 1), (i > 0).then(|| p(i - 1)), q(j), q(j + 1), (j > 0).then(|| q(j - 1)), t)
                };
                if take_p {
                    emit([pid[i], pid[i + 1], qid[qmap[j]]], &mut self.stats)?;
                    i += 1;
                } else {
                    emit([pid[i], qid[qmap[j + 1]], qid[qmap[j]]], &mut self.stats)?;
                    j += 1;
                }
            }
            return Ok(());
        }
        let (i0, j0) = start_pair(puv, quv);
        let p = |k: usize| puv[(i0 + k) % n];
        let q = |k: usize| quv[(j0 + k) % m];
        let pi = |k: usize| pid[(i0 + k) % n];
        let qi = |k: usize| qid[(j0 + k) % m];
        let (mut i, mut j) = (0usize, 0usize);
        while i < n || j < m {
            let take_p = if i == n {
                false
            } else if j == m {
                true
            } else {
                decide(p(i), p(i + 1), Some(p(i + n - 1)), q(j), q(j + 1), Some(q(j + m - 1)), t)
            };
            if take_p {
                emit([pi(i), pi(i + 1), qi(j)], &mut self.stats)?;
                i += 1;
            } else {
                emit([pi(i), qi(j + 1), qi(j)], &mut self.stats)?;
                j += 1;
            }
        }
        Ok(())
    }

    /// Triangulates the region of the rings `which` of a section (each with
    /// the listed rings nested directly in it as holes) as a top cap
    /// (normal along the stack axis) or a bottom cap.
    fn cap(&mut self, s: &Prepared, which: &[usize], top: bool, sink: &mut dyn MeshSink) -> Result<(), ContourError> {
        if which.is_empty() {
            return Ok(());
        }
        // Depth among the capped rings decides outer boundaries and holes.
        let local_parent: Vec<Option<usize>> = which
            .iter()
            .map(|&i| {
                which
                    .iter()
                    .copied()
                    .filter(|&j| j != i && inside(&s.rings[j].uv, s.rings[i].uv[0]))
                    .max_by_key(|&j| s.rings[j].depth)
            })
            .collect();
        for (k, &i) in which.iter().enumerate() {
            let local_depth = {
                let mut d = 0;
                let mut p = local_parent[k];
                while let Some(j) = p {
                    d += 1;
                    p = local_parent[which.iter().position(|&x| x == j).unwrap()];
                }
                d
            };
            if local_depth % 2 == 1 {
                continue;
            }
            let holes: Vec<usize> = which.iter().enumerate().filter(|&(kk, _)| local_parent[kk] == Some(i)).map(|(_, &j)| j).collect();
            let outer = &s.rings[i];
            let hole_uv: Vec<&[P2]> = holes.iter().map(|&j| s.rings[j].uv.as_slice()).collect();
            let tri = match triangulate(&outer.uv, &hole_uv) {
                Ok(t) => t,
                Err(_) => {
                    self.stats.forced_ears += 1;
                    continue;
                }
            };
            self.stats.caps += 1;
            self.stats.forced_ears += tri.forced as u64;
            let mut ids: Vec<u32> = outer.ids.clone();
            for &j in &holes {
                ids.extend_from_slice(&s.rings[j].ids);
            }
            // Triangles come counter-clockwise in (u, v): normal +n.
            let keep = top == (outer.depth % 2 == 0);
            for t in tri.triangles {
                let f = t.map(|x| ids[x as usize]);
                sink.face(if keep { f } else { [f[0], f[2], f[1]] })?;
                self.stats.faces += 1;
            }
        }
        Ok(())
    }
}

fn make_ring(ids: Vec<u32>, uv: Vec<P2>, depth: usize) -> Ring {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in &uv {
        for d in 0..2 {
            lo[d] = lo[d].min(p[d]);
            hi[d] = hi[d].max(p[d]);
        }
    }
    let centroid = centroid(&uv);
    Ring { ids, uv, depth, centroid, lo, hi }
}

/// The paper's next-vertex rule: true to advance on P.
fn decide(p0: P2, p1: P2, pm: Option<P2>, q0: P2, q1: P2, qm: Option<P2>, t: f64) -> bool {
    let d2 = |a: P2, b: P2| (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2);
    let cos = |a0: P2, a1: P2, b0: P2, b1: P2| -> f64 {
        let (u, v) = ([a1[0] - a0[0], a1[1] - a0[1]], [b1[0] - b0[0], b1[1] - b0[1]]);
        let l = (u[0] * u[0] + u[1] * u[1]).sqrt() * (v[0] * v[0] + v[1] * v[1]).sqrt();
        if l > 0.0 {
            (u[0] * v[0] + u[1] * v[1]) / l
        } else {
            -1.0
        }
    };
    let p_shorter = d2(p1, q0) <= d2(p0, q1);
    if p_shorter {
        // α: P_i→P_i+1 vs Q_j-1→Q_j; β: P_i-1→P_i vs Q_j→Q_j+1.
        if qm.is_some_and(|qm| cos(p0, p1, qm, q0) > t) {
            return true;
        }
        if pm.is_some_and(|pm| cos(pm, p0, q0, q1) > t) {
            return false;
        }
        true
    } else {
        if pm.is_some_and(|pm| cos(q0, q1, pm, p0) > t) {
            return false;
        }
        if qm.is_some_and(|qm| cos(qm, q0, p0, p1) > t) {
            return true;
        }
        false
    }
}

/// The start pair (§2.2.1): P's vertex farthest from P's centroid, then Q's
/// vertex with the largest inner product of centroid vectors among those
/// within 45° of that direction (all of Q if none is).
fn start_pair(p: &[P2], q: &[P2]) -> (usize, usize) {
    let (cp, cq) = (centroid(p), centroid(q));
    let i0 = (0..p.len())
        .max_by(|&a, &b| {
            let da = (p[a][0] - cp[0]).powi(2) + (p[a][1] - cp[1]).powi(2);
            let db = (p[b][0] - cp[0]).powi(2) + (p[b][1] - cp[1]).powi(2);
            da.total_cmp(&db).then(b.cmp(&a))
        })
        .unwrap();
    let u = [p[i0][0] - cp[0], p[i0][1] - cp[1]];
    let lu = u[0].hypot(u[1]);
    let score = |j: usize| {
        let v = [q[j][0] - cq[0], q[j][1] - cq[1]];
        (u[0] * v[0] + u[1] * v[1], v[0].hypot(v[1]))
    };
    let similar = |j: usize| {
        let (d, lv) = score(j);
        lu > 0.0 && lv > 0.0 && d / (lu * lv) >= std::f64::consts::FRAC_1_SQRT_2
    };
    let pick = |filter: &dyn Fn(usize) -> bool| (0..q.len()).filter(|&j| filter(j)).max_by(|&a, &b| score(a).0.total_cmp(&score(b).0).then(b.cmp(&a)));
    let j0 = pick(&similar).or_else(|| pick(&|_| true)).unwrap();
    (i0, j0)
}

/// Whether two rings of consecutive sections overlap in projection, with a
/// score (the fractions of each one's vertices inside the other), or `None`.
/// Open polylines overlap when their bounding boxes do.
fn overlap(p: &Ring, q: &Ring, open: bool) -> Option<f64> {
    if p.hi[0] < q.lo[0] || q.hi[0] < p.lo[0] || p.hi[1] < q.lo[1] || q.hi[1] < p.lo[1] {
        return None;
    }
    if open {
        let w = (p.hi[0].min(q.hi[0]) - p.lo[0].max(q.lo[0])).max(0.0) * (p.hi[1].min(q.hi[1]) - p.lo[1].max(q.lo[1])).max(0.0);
        return Some(w + 1e-300);
    }
    let a = p.uv.iter().filter(|&&x| inside(&q.uv, x)).count() as f64 / p.uv.len() as f64;
    let b = q.uv.iter().filter(|&&x| inside(&p.uv, x)).count() as f64 / q.uv.len() as f64;
    if a + b > 0.0 {
        return Some(a + b);
    }
    first_crossing(&[&p.uv, &q.uv]).map(|_| 1e-6)
}

/// A part of a split ring: ids and positions, solid on the left.
type Part = (Vec<u32>, Vec<P2>);

/// Splits `ring` into one part per partner by chords between its vertices;
/// returns each part with its partner's index, or `None` when no valid chord
/// separates the partners.
fn split_for(ring: &Ring, partners: &[&Ring], others: &[&[P2]]) -> Option<Vec<(Part, usize)>> {
    // Order the partners along the direction of largest spread of their
    // centroids, then split recursively in halves.
    let cs: Vec<P2> = partners.iter().map(|r| r.centroid).collect();
    let mean = cs.iter().fold([0.0, 0.0], |s, c| [s[0] + c[0] / cs.len() as f64, s[1] + c[1] / cs.len() as f64]);
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for c in &cs {
        let (x, y) = (c[0] - mean[0], c[1] - mean[1]);
        sxx += x * x;
        sxy += x * y;
        syy += y * y;
    }
    let theta = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    let axis = [theta.cos(), theta.sin()];
    let mut order: Vec<usize> = (0..partners.len()).collect();
    order.sort_by(|&a, &b| (cs[a][0] * axis[0] + cs[a][1] * axis[1]).total_cmp(&(cs[b][0] * axis[0] + cs[b][1] * axis[1])).then(a.cmp(&b)));
    let mut out = Vec::new();
    split_rec((ring.ids.clone(), ring.uv.clone()), &order, partners, others, &mut out)?;
    Some(out)
}

fn split_rec(part: Part, group: &[usize], partners: &[&Ring], others: &[&[P2]], out: &mut Vec<(Part, usize)>) -> Option<()> {
    if group.len() == 1 {
        out.push((part, group[0]));
        return Some(());
    }
    let half = group.len() / 2;
    let (g1, g2) = group.split_at(half);
    let (a, b) = split_two(part, g1, g2, partners, others)?;
    split_rec(a, g1, partners, others, out)?;
    split_rec(b, g2, partners, others, out)
}

/// Splits a ring by one chord into the part facing group `g1` and the part
/// facing `g2`.
fn split_two(part: Part, g1: &[usize], g2: &[usize], partners: &[&Ring], others: &[&[P2]]) -> Option<(Part, Part)> {
    let (ids, uv) = part;
    let n = uv.len();
    if n < 4 {
        return None;
    }
    let cen = |g: &[usize]| {
        let mut s = [0.0, 0.0];
        let mut w = 0.0;
        for &k in g {
            let a = signed_area(&partners[k].uv).abs().max(1e-300);
            s[0] += partners[k].centroid[0] * a;
            s[1] += partners[k].centroid[1] * a;
            w += a;
        }
        [s[0] / w, s[1] / w]
    };
    let (c1, c2) = (cen(g1), cen(g2));
    let d = [c2[0] - c1[0], c2[1] - c1[1]];
    let dl = d[0].hypot(d[1]);
    if !(dl > 0.0) {
        return None;
    }
    let d = [d[0] / dl, d[1] / dl];
    let proj = |p: P2| p[0] * d[0] + p[1] * d[1];
    // Cut between the groups' extents along d (or between the centroids).
    let m1 = g1.iter().flat_map(|&k| partners[k].uv.iter()).map(|&p| proj(p)).fold(f64::NEG_INFINITY, f64::max);
    let m2 = g2.iter().flat_map(|&k| partners[k].uv.iter()).map(|&p| proj(p)).fold(f64::INFINITY, f64::min);
    let cut = if m1 < m2 { 0.5 * (m1 + m2) } else { 0.5 * (proj(c1) + proj(c2)) };
    let sigma: Vec<f64> = uv.iter().map(|&p| proj(p) - cut).collect();
    // Candidate vertices: the ends of edges that cross the cut line.
    let mut cand: Vec<usize> = Vec::new();
    for i in 0..n {
        let k = (i + 1) % n;
        if (sigma[i] <= 0.0) != (sigma[k] <= 0.0) {
            cand.push(i);
            cand.push(k);
        }
    }
    cand.sort_unstable();
    cand.dedup();
    let mut best: Option<(f64, usize, usize)> = None;
    for (x, &a) in cand.iter().enumerate() {
        for &b in &cand[x + 1..] {
            let gap = (b + n - a) % n;
            if gap < 2 || gap > n - 2 {
                continue;
            }
            let score = sigma[a].abs() + sigma[b].abs();
            if best.is_some_and(|(s, _, _)| s <= score) {
                continue;
            }
            if valid_chord(&uv, a, b, others) {
                best = Some((score, a, b));
            }
        }
    }
    let (_, a, b) = best?;
    let take = |from: usize, to: usize| -> Part {
        let mut i = from;
        let (mut pi, mut pu) = (Vec::new(), Vec::new());
        loop {
            pi.push(ids[i]);
            pu.push(uv[i]);
            if i == to {
                break;
            }
            i = (i + 1) % n;
        }
        (pi, pu)
    };
    let (pa, pb) = (take(a, b), take(b, a));
    // The part lying on the g1 side of the cut goes to g1.
    let side = |p: &Part| p.1.iter().map(|&q| proj(q) - cut).sum::<f64>() / p.1.len() as f64;
    if side(&pa) <= side(&pb) {
        Some((pa, pb))
    } else {
        Some((pb, pa))
    }
}

/// True if the chord between ring vertices `a` and `b` lies inside the
/// ring: it leaves both ends into the interior, touches no ring edge except
/// at its ends, and touches no other contour of the section.
fn valid_chord(uv: &[P2], a: usize, b: usize, others: &[&[P2]]) -> bool {
    let n = uv.len();
    let (pa, pb) = (uv[a], uv[b]);
    if pa == pb {
        return false;
    }
    let locally_inside = |i: usize, towards: P2| {
        let (x, y, z) = (uv[(i + n - 1) % n], uv[i], uv[(i + 1) % n]);
        if orient(x, y, z) >= 0.0 {
            orient(x, y, towards) > 0.0 && orient(y, z, towards) > 0.0
        } else {
            orient(x, y, towards) > 0.0 || orient(y, z, towards) > 0.0
        }
    };
    if !locally_inside(a, pb) || !locally_inside(b, pa) {
        return false;
    }
    for e in 0..n {
        let f = (e + 1) % n;
        if e == a || f == a || e == b || f == b {
            continue;
        }
        if segments_touch(pa, pb, uv[e], uv[f]) {
            return false;
        }
    }
    for o in others {
        let k = o.len();
        for e in 0..k {
            if segments_touch(pa, pb, o[e], o[(e + 1) % k]) {
                return false;
            }
        }
    }
    true
}

/// Reconstructs sections held in memory (tests and small stacks).
pub fn reconstruct(sections: &[Section], opts: AngleOptions, sink: &mut dyn MeshSink) -> Result<AngleStats, ContourError> {
    let mut r = AngleReconstructor::new(opts);
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
    use std::path::Path;

    fn stack(text: &str) -> Vec<Section> {
        read_all(text.as_bytes(), Path::new("t.pro"), ProfileOptions::default()).unwrap().1
    }

    #[test]
    fn two_squares_with_caps_make_a_closed_box_of_12_triangles() {
        let s = stack("pro\nsection 0 0 0 1 0 0 1 1 0 0 1 0\nsection 0 0 1 0 1 1 1 1 1 1 0 1\n");
        let mut m = TriMesh::default();
        let st = reconstruct(&s, AngleOptions { caps: true, ..Default::default() }, &mut m).unwrap();
        assert_eq!((st.tubes, st.caps, st.faces, st.vertices), (1, 2, 12, 8));
        let c = mint_testkit::topology::check_closed_oriented(&m).unwrap();
        assert!((c.volume - 1.0).abs() < 1e-12, "{}", c.volume);
    }

    #[test]
    fn an_annulus_pairs_outer_with_outer_and_hole_with_hole() {
        let ring = |z: f64, r: f64, n: usize| -> String {
            (0..n).map(|k| {
                let a = std::f64::consts::TAU * k as f64 / n as f64;
                format!("{} {} {z} ", r * a.cos(), r * a.sin())
            }).collect()
        };
        let mut t = String::from("pro\n");
        for k in 0..4 {
            let z = k as f64;
            t.push_str(&format!("section {}\ncontour {}\n", ring(z, 2.0, 12 + k), ring(z, 1.0, 7 + k)));
        }
        let s = stack(&t);
        let mut m = TriMesh::default();
        let st = reconstruct(&s, AngleOptions { caps: true, ..Default::default() }, &mut m).unwrap();
        assert_eq!((st.tubes, st.caps, st.forced_ears), (6, 2, 0));
        let c = mint_testkit::topology::check_closed_oriented(&m).unwrap();
        assert_eq!(c.genus, 1);
        assert!(c.volume > 0.0);
    }

    #[test]
    fn open_polylines_march_end_to_end() {
        // Two open arcs (5 and 7 points), the upper one listed backwards: it
        // is reversed to pair the ends, and 5 + 7 - 2 triangles join them.
        let arc = |z: f64, n: usize, rev: bool| -> String {
            let mut v: Vec<String> = (0..n).map(|k| {
                let a = std::f64::consts::PI * k as f64 / (n - 1) as f64;
                format!("{} {} {z} ", a.cos(), 0.5 * a.sin())
            }).collect();
            if rev {
                v.reverse();
            }
            v.concat()
        };
        let text = format!("pro\nsection {}\nsection {}\n", arc(0.0, 5, false), arc(1.0, 7, true));
        let s = read_all(text.as_bytes(), Path::new("t.pro"), ProfileOptions { check_intersections: false, ..Default::default() }).unwrap().1;
        let mut m = TriMesh::default();
        let st = reconstruct(&s, AngleOptions { open: true, ..Default::default() }, &mut m).unwrap();
        assert_eq!((st.tubes, st.faces), (1, 10));
        let r = mint_mesh::check(&m.positions, &m.faces);
        assert_eq!((r.boundary_loops, r.non_manifold_edges, r.inconsistently_oriented_edges, r.degenerate_faces), (1, 0, 0, 0));
    }

    #[test]
    fn a_branch_splits_the_single_contour() {
        let circle = |cx: f64, z: f64, r: f64, n: usize| -> String {
            (0..n).map(|k| {
                let a = std::f64::consts::TAU * k as f64 / n as f64;
                format!("{} {} {z} ", cx + r * a.cos(), 0.8 * r * a.sin())
            }).collect()
        };
        let t = format!(
            "pro\nsection {}\nsection {}\nsection {}\ncontour {}\nsection {}\ncontour {}\n",
            circle(0.0, 0.0, 3.0, 40),
            circle(0.0, 1.0, 3.0, 40),
            circle(-1.5, 2.0, 1.2, 20),
            circle(1.5, 2.0, 1.2, 20),
            circle(-1.5, 3.0, 1.2, 20),
            circle(1.5, 3.0, 1.2, 20)
        );
        let s = stack(&t);
        let mut m = TriMesh::default();
        let st = reconstruct(&s, AngleOptions { caps: true, ..Default::default() }, &mut m).unwrap();
        assert_eq!((st.splits, st.unsplit_groups), (1, 0));
        let c = mint_testkit::topology::check_closed_oriented(&m).unwrap();
        assert_eq!((c.components, c.genus), (1, 0));
    }
}
