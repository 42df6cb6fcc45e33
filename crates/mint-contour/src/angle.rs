//! Cross-section triangulation with the angle criterion (Dangl 1998, §2.2),
//! made crossing-free by an exact check and fallbacks, with every branching
//! case handled.
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
//! - H. Fuchs, Z. M. Kedem, S. P. Uselton, "Optimal surface reconstruction
//!   from planar contours", CACM 20(10), 1977: the minimum-area tiling
//!   ([`crate::tiling::min_area`]).
//! - H. N. Christiansen, T. W. Sederberg, "Conversion of complex contour
//!   line definitions into polygonal element mosaics", SIGGRAPH 1978:
//!   several contours of a section joined into one by bridges walked both
//!   ways, then tiled as one.
//! - D. Meyers, S. Skinner, K. Sloan, "Surfaces from contours", ACM TOG
//!   11(3), 1992, §4: branching by splitting the single contour so that each
//!   part pairs with one contour of the other section.
//!
//! # Data flow
//! Each [`Section`] becomes a `Prepared` section: its vertices are sent to
//! the sink at once (ids in file order), and each contour becomes a ring of
//! ids, counter-clockwise around solid (even nesting depth) or clockwise
//! (holes), so that "the solid is on the left" for every ring. For each pair
//! of consecutive sections (a *slab*), rings of equal depth parity whose
//! regions overlap in projection are linked (a ring's region is inside it
//! and outside its children: an island in a hole does not link to the
//! contour around the hole); each connected group of links is joined by
//! triangles, and every tiling is offered to the slab's exact check
//! ([`SlabCheck`]), which accepts it only if none of its triangles
//! intersects another one of it or one accepted before in the slab.
//!
//! # Fallback order
//! A *tube* joins a lower ring P to an upper ring Q; the tilings tried, in
//! order, until one is accepted:
//! 1. the paper's march from the paper's start pair;
//! 2. the march from other start pairs (the closest pair of vertices, then
//!    six vertices of P spread around it, each with its nearest in Q);
//! 3. the minimum-area tiling from each of those start pairs, in rounds:
//!    the triangles that crossed something are forbidden and the dynamic
//!    program run again (at most 16 rounds per start pair, 40 per tube).
//!
//! A group is joined by the first of these that works:
//! - one ring facing one: a tube;
//! - a branch (one lower ring facing several) whose single ring goes on
//!   below: the single ring is split along chords between its vertices,
//!   each chord separating the partners' centroids, and each part is a
//!   tube with one partner (the chord edge is shared by two tubes in
//!   opposite directions);
//! - any group (merges, many-to-many, branches at a contour capped below,
//!   failed splits): the rings of each side are joined into one by bridges,
//!   shortest first, and the two rings are a tube;
//! - the best-overlapping pairs, each a tube, the rings left over capped
//!   ([`AngleStats::paired`]);
//! - nothing: every ring of the group is capped ([`AngleStats::apart`]).
//!
//! The last two change the topology; they are counted per group, and per
//! slab with the other fallbacks ([`AngleStats::fallback_slabs`]). On the
//! real test data (bunny, horse, Igea; RT-STRUCT ROIs) only one group, in
//! the RT BODY, needed pairs, and none was capped apart.
//!
//! # Why a check per slab is enough
//! Triangles of different slabs meet only in a section plane, and there
//! only in contour edges and vertices and in the edges the branching code
//! lays in the plane. Those are kept apart by construction: chords lie
//! inside a ring that has partners on both sides (so no cap covers them)
//! and are laid only in a slab's lower plane, once per plane; bridges lie
//! outside the rings they join, touch no contour, and touch no bridge laid
//! in the same plane by the slab on the other side (the slab below hands
//! its upper-plane bridges on) nor, in one slab, each other. Caps lie in
//! the planes, inside their contours, where no tube triangle reaches.
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
//! triangles), the upper polyline reversed if that pairs the ends better;
//! they are not checked for crossings, and in a group of several they are
//! paired by overlap, the rest left unpaired ([`AngleStats::unpaired`]).
//!
//! # Limits (honest)
//! - No crossing is a property checked slab by slab, not a theorem about
//!   the fallbacks: a group the fallbacks cannot join is capped apart,
//!   which keeps the surface closed and crossing-free but cuts the solid.
//! - The in-plane arguments above assume valid input (disjoint simple
//!   contours, checked on read) and consistent nesting. Two cases are not
//!   excluded by construction: a bridge between islands inside a hole that
//!   is capped in that plane, and the cap of a contour whose hole goes on
//!   (a hole with no solid around it in the next section).
//! - Bridges and chords make the surface meet a section plane in an edge
//!   inside or between contours: a crease, not a smooth saddle.
//! - Memory: two sections, and per slab its triangles and a grid of about
//!   one cell per vertex. Time: the check adds an exact test per nearby
//!   triangle pair; the fallbacks cost O(nm) per round for rings of n and m
//!   vertices, and run only where the march crosses.

use crate::error::ContourError;
use crate::geom2d::{centroid, first_crossing, inside, orient, segments_touch, signed_area, P2};
use crate::profile::Section;
use crate::slabcheck::SlabCheck;
use crate::tiling::{decide, march, min_area_avoiding, other_starts, start_pair, Tiling};

/// Rounds of the minimum-area tiling per start pair, each forbidding the
/// triangles that crossed something in the round before; and the most
/// rounds per tube, over all start pairs. (On the real test data the first
/// start pair always did, within 10 rounds.)
const DP_ROUNDS: usize = 16;
const DP_RUNS: usize = 40;
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
    /// With `caps`: the end sections stand for half a section spacing
    /// beyond them, as each section does for the planimetric volume and
    /// in marching cubes (the clinical convention: a contour is a slab one
    /// slice thick). A copy of the first section is put half the first
    /// spacing before it, one of the last section half the last spacing
    /// after it, and the caps close the copies. Done by the drivers of
    /// [`crate::run`], which know the stack frame; [`AngleReconstructor`]
    /// reconstructs the sections it is given. Contours that appear or
    /// vanish inside the stack are still capped in their own plane.
    /// Default false (`mint contours` sets it for RT structure sets).
    pub extend_ends: bool,
}

impl Default for AngleOptions {
    fn default() -> Self {
        AngleOptions { threshold: 0.5, open: false, caps: false, extend_ends: false }
    }
}

/// Tubes by how they were tiled (the first tiling of the fallback order
/// whose triangles cross nothing).
#[derive(Debug, Default, Clone, Serialize, PartialEq, Eq)]
pub struct TilingCounts {
    /// The paper's march from the paper's start pair.
    pub march: u64,
    /// The paper's march from another start pair.
    pub restart: u64,
    /// A minimum-area (or, failing that, minimum-span) tiling.
    pub min_area: u64,
}

/// Section pairs (slabs) that needed each fallback at least once.
#[derive(Debug, Default, Clone, Serialize, PartialEq, Eq)]
pub struct FallbackCounts {
    /// Some tube was marched from another start pair.
    pub restart: u64,
    /// Some tube was tiled by minimum area or span.
    pub min_area: u64,
    /// Some group was split by a chord of its single contour.
    pub split: u64,
    /// Some group was joined into one ring per side by bridges.
    pub bridge: u64,
    /// Some group was joined pair by pair, best overlap first, with the
    /// contours left over capped.
    pub pairs: u64,
    /// Some group found no tiling without crossings and was capped apart.
    pub apart: u64,
}

/// What one reconstruction did.
#[derive(Debug, Default, Clone, Serialize, PartialEq, Eq)]
pub struct AngleStats {
    /// Strips of triangles between a lower and an upper ring (a contour, a
    /// part of a split contour, or contours joined by bridges).
    pub tubes: u64,
    /// One contour facing several, split by chords into one part per
    /// partner (branches).
    pub splits: u64,
    /// Groups whose contours were joined by bridges into one ring per side
    /// (merges, many-to-many, and branches whose split failed).
    pub bridged: u64,
    /// Groups that neither a split nor bridges could join without
    /// crossings, joined instead pair by pair (best overlap first); the
    /// contours left over are capped.
    pub paired: u64,
    /// Groups with no tiling without crossings at all: their contours are
    /// capped on both sides of the slab instead of joined.
    pub apart: u64,
    /// Caps triangulated (regions, each with its holes).
    pub caps: u64,
    /// Contours with no partner in either neighbouring section: they have
    /// no thickness and are left out (no faces).
    pub isolated: u64,
    /// Open polylines (`open`) left unpaired in a group of several.
    pub unpaired: u64,
    /// How the tubes were tiled.
    pub tiled: TilingCounts,
    /// Section pairs that needed each fallback.
    pub fallback_slabs: FallbackCounts,
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
    /// The rings nested directly inside this one (its holes, or a hole's
    /// islands): with them it bounds a region of solid or of void.
    children: Vec<usize>,
    centroid: P2,
    lo: P2,
    hi: P2,
}

#[derive(Debug, Clone)]
struct Prepared {
    rings: Vec<Ring>,
    /// Id of the first vertex, and every vertex in id order: in space and
    /// in the section plane.
    base: u32,
    pos: Vec<[f64; 3]>,
    uv: Vec<P2>,
}

impl Prepared {
    fn uv_of(&self, id: u32) -> P2 {
        self.uv[(id - self.base) as usize]
    }
}

/// A ring to tile: ids and positions in the section plane.
type Part = (Vec<u32>, Vec<P2>);

/// The slab being joined: its check and what it used.
struct Slab {
    check: SlabCheck,
    /// Fallbacks used (bits: [`FallbackCounts`] fields in order).
    used: u8,
    /// Bridges placed in the lower and upper planes (vertex ids).
    lower_bridges: Vec<[u32; 2]>,
    upper_bridges: Vec<[u32; 2]>,
}

const USED_RESTART: u8 = 1;
const USED_MIN_AREA: u8 = 2;
const USED_SPLIT: u8 = 4;
const USED_BRIDGE: u8 = 8;
const USED_PAIRS: u8 = 16;
const USED_APART: u8 = 32;

/// The angle-criterion reconstruction of a stack streamed section by
/// section: [`push`](AngleReconstructor::push) each section in order, then
/// [`finish`](AngleReconstructor::finish).
pub struct AngleReconstructor {
    opts: AngleOptions,
    prev: Option<Prepared>,
    /// For each ring of `prev`: does it have a partner below?
    prev_has_below: Vec<bool>,
    /// Bridges in `prev`'s plane placed by the slab below it.
    prev_bridges: Vec<[u32; 2]>,
    /// The coordinate axis most nearly along the stack normal (from the
    /// first contour), for the exact projection filter of [`SlabCheck`].
    drop: Option<usize>,
    emitted: u64,
    stats: AngleStats,
}

impl AngleReconstructor {
    /// Starts a reconstruction.
    pub fn new(opts: AngleOptions) -> AngleReconstructor {
        AngleReconstructor { opts, prev: None, prev_has_below: Vec::new(), prev_bridges: Vec::new(), drop: None, emitted: 0, stats: AngleStats::default() }
    }

    /// Adds the next section: sends its vertices, joins it to the previous
    /// one and closes the previous one's contour ends.
    pub fn push(&mut self, section: &Section, sink: &mut dyn MeshSink) -> Result<(), ContourError> {
        let cur = self.prepare(section, sink)?;
        let mut cur_has_below = vec![false; cur.rings.len()];
        let mut cur_bridges = Vec::new();
        if let Some(prev) = self.prev.take() {
            let mut prev_has_above = vec![false; prev.rings.len()];
            let below = std::mem::take(&mut self.prev_has_below);
            cur_bridges = self.join(&prev, &cur, &below, &mut prev_has_above, &mut cur_has_below, sink)?;
            self.close_ends(&prev, &below, &prev_has_above, sink)?;
        }
        self.prev = Some(cur);
        self.prev_has_below = cur_has_below;
        self.prev_bridges = cur_bridges;
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
        let first = self.emitted as u32;
        if self.drop.is_none() {
            let n = crate::profile::newell(&s.contours[0].points);
            self.drop = Some((0..3).max_by(|&a, &b| n[a].abs().total_cmp(&n[b].abs()).then(b.cmp(&a))).unwrap());
        }
        let (mut pos, mut all_uv) = (Vec::new(), Vec::new());
        for c in &s.contours {
            pos.extend_from_slice(&c.points);
            all_uv.extend_from_slice(&c.uv);
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
            for i in 0..rings.len() {
                if let Some(parent) = (0..rings.len()).find(|&j| depths[j] + 1 == depths[i] && inside(&rings[j].uv, rings[i].uv[0])) {
                    rings[parent].children.push(i);
                }
            }
            for (r, d) in rings.iter_mut().zip(depths) {
                r.depth = d;
                let ccw = signed_area(&r.uv) > 0.0;
                if ccw != (d % 2 == 0) {
                    r.ids.reverse();
                    r.uv.reverse();
                }
            }
        }
        Ok(Prepared { rings, base: first, pos, uv: all_uv })
    }

    /// Links overlapping rings of two sections and triangulates each group;
    /// returns the bridges placed in the upper plane.
    fn join(
        &mut self,
        lower: &Prepared,
        upper: &Prepared,
        below: &[bool],
        has_above: &mut [bool],
        has_below: &mut [bool],
        sink: &mut dyn MeshSink,
    ) -> Result<Vec<[u32; 2]>, ContourError> {
        let (nl, nu) = (lower.rings.len(), upper.rings.len());
        let mut links: Vec<(usize, usize, f64)> = Vec::new();
        for i in 0..nl {
            for j in 0..nu {
                let (p, q) = (&lower.rings[i], &upper.rings[j]);
                if p.depth % 2 != q.depth % 2 {
                    continue;
                }
                if let Some(score) = overlap(lower, i, upper, j, self.opts.open, false) {
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
        if self.opts.open {
            for (_, (ls, us)) in groups {
                self.pair_open(&links, &ls, &us, lower, upper, has_above, has_below, sink)?;
            }
            return Ok(Vec::new());
        }
        debug_assert_eq!(upper.base as usize, lower.base as usize + lower.pos.len());
        let pos: Vec<[f64; 3]> = lower.pos.iter().chain(&upper.pos).copied().collect();
        let uv: Vec<P2> = lower.uv.iter().chain(&upper.uv).copied().collect();
        let mut slab = Slab { check: SlabCheck::new(lower.base, pos, uv, self.drop.unwrap_or(2)), used: 0, lower_bridges: Vec::new(), upper_bridges: Vec::new() };
        for (_, (mut ls, mut us)) in groups {
            ls.sort_unstable();
            us.sort_unstable();
            let tris = match self.group(&mut slab, lower, upper, below, &ls, &us) {
                Some(tris) => {
                    for &i in &ls {
                        has_above[i] = true;
                    }
                    for &j in &us {
                        has_below[j] = true;
                    }
                    tris
                }
                None => {
                    // Last resorts: join pairs by overlap, cap the rest (or
                    // all, if no pair can be tiled); close_ends caps them.
                    let (tris, joined) = self.pairs(&mut slab, lower, upper, &links, &ls, &us, has_above, has_below);
                    if joined > 0 {
                        self.stats.paired += 1;
                        slab.used |= USED_PAIRS;
                    } else {
                        self.stats.apart += 1;
                        slab.used |= USED_APART;
                    }
                    tris
                }
            };
            for f in tris {
                sink.face(f)?;
                self.stats.faces += 1;
            }
        }
        let f = &mut self.stats.fallback_slabs;
        for (bit, c) in [(USED_RESTART, &mut f.restart), (USED_MIN_AREA, &mut f.min_area), (USED_SPLIT, &mut f.split), (USED_BRIDGE, &mut f.bridge), (USED_PAIRS, &mut f.pairs), (USED_APART, &mut f.apart)] {
            *c += (slab.used & bit != 0) as u64;
        }
        Ok(slab.upper_bridges)
    }

    /// The triangles joining one group of linked contours (accepted by the
    /// slab's check), or `None` when every way tried crosses something.
    fn group(&mut self, slab: &mut Slab, lower: &Prepared, upper: &Prepared, below: &[bool], ls: &[usize], us: &[usize]) -> Option<Vec<[u32; 3]>> {
        let ring = |sec: &Prepared, k: usize| -> Part { (sec.rings[k].ids.clone(), sec.rings[k].uv.clone()) };
        if ls.len() == 1 && us.len() == 1 {
            return self.tile(slab, &ring(lower, ls[0]), &ring(upper, us[0]));
        }
        let mark = slab.check.mark();
        // A branch whose single contour goes on below: split it by chords
        // (in the lower plane, inside a contour that is not capped there).
        if ls.len() == 1 && below[ls[0]] {
            let single = &lower.rings[ls[0]];
            let partners: Vec<&Ring> = us.iter().map(|&k| &upper.rings[k]).collect();
            let others: Vec<&[P2]> = lower.rings.iter().enumerate().filter(|&(k, _)| k != ls[0]).map(|(_, r)| r.uv.as_slice()).collect();
            if let Some(parts) = split_for(single, &partners, &others) {
                let mut all = Vec::new();
                let mut ok = true;
                for (part, k) in parts {
                    match self.tile(slab, &part, &ring(upper, us[k])) {
                        Some(t) => all.extend(t),
                        None => {
                            ok = false;
                            break;
                        }
                    }
                }
                if ok {
                    self.stats.splits += 1;
                    slab.used |= USED_SPLIT;
                    return Some(all);
                }
                slab.check.rollback(mark);
            }
        }
        // Join each side into one ring by bridges (Christiansen and
        // Sederberg), then tile the two rings.
        let mut forbid_lower: Vec<[u32; 2]> = self.prev_bridges.clone();
        forbid_lower.extend_from_slice(&slab.lower_bridges);
        let (lb, ub) = (slab.lower_bridges.len(), slab.upper_bridges.len());
        let p = bridge_rings(lower, ls, &forbid_lower, &mut slab.lower_bridges);
        let q = p.as_ref().and_then(|_| {
            let forbid_upper = slab.upper_bridges.clone();
            bridge_rings(upper, us, &forbid_upper, &mut slab.upper_bridges)
        });
        if let (Some(p), Some(q)) = (p, q) {
            if let Some(t) = self.tile(slab, &p, &q) {
                self.stats.bridged += 1;
                slab.used |= USED_BRIDGE;
                return Some(t);
            }
        }
        slab.lower_bridges.truncate(lb);
        slab.upper_bridges.truncate(ub);
        slab.check.rollback(mark);
        None
    }

    /// Joins a group's contours one to one, best overlap first, each pair
    /// tiled with the fallbacks; marks the joined ones and returns the
    /// triangles and the number of pairs.
    #[allow(clippy::too_many_arguments)]
    fn pairs(
        &mut self,
        slab: &mut Slab,
        lower: &Prepared,
        upper: &Prepared,
        links: &[(usize, usize, f64)],
        ls: &[usize],
        us: &[usize],
        has_above: &mut [bool],
        has_below: &mut [bool],
    ) -> (Vec<[u32; 3]>, usize) {
        let mut cand: Vec<(usize, usize, f64)> = links
            .iter()
            .filter(|l| ls.contains(&l.0) && us.contains(&l.1))
            .map(|&(i, j, _)| (i, j, overlap(lower, i, upper, j, false, true).unwrap_or(0.0)))
            .collect();
        cand.sort_by(|a, b| b.2.total_cmp(&a.2).then((a.0, a.1).cmp(&(b.0, b.1))));
        let (mut tris, mut joined) = (Vec::new(), 0);
        for &(i, j, _) in &cand {
            if has_above[i] || has_below[j] {
                continue;
            }
            let ring = |sec: &Prepared, k: usize| -> Part { (sec.rings[k].ids.clone(), sec.rings[k].uv.clone()) };
            if let Some(t) = self.tile(slab, &ring(lower, i), &ring(upper, j)) {
                tris.extend(t);
                has_above[i] = true;
                has_below[j] = true;
                joined += 1;
            }
        }
        (tris, joined)
    }

    /// Tiles a lower ring to an upper ring: the paper's march, then the
    /// fallbacks in order, until a tiling crosses nothing in the slab. The
    /// triangles returned are accepted by the slab's check.
    fn tile(&mut self, slab: &mut Slab, p: &Part, q: &Part) -> Option<Vec<[u32; 3]>> {
        let (pid, puv) = (&p.0, &p.1);
        let (qid, quv) = (&q.0, &q.1);
        let t = self.opts.threshold;
        let check = &mut slab.check;
        let accept = |tiling: Tiling, check: &mut SlabCheck| -> Option<Vec<[u32; 3]>> {
            let tris = tiling.triangles(pid, qid);
            (spans_distinct(&tiling, pid, qid) && check.try_add(&tris)).then_some(tris)
        };
        let first = start_pair(puv, quv);
        if let Some(tris) = accept(march(puv, quv, first.0, first.1, t), check) {
            self.stats.tubes += 1;
            self.stats.tiled.march += 1;
            return Some(tris);
        }
        let starts = other_starts(puv, quv, first, 6);
        for &(i0, j0) in &starts {
            if let Some(tris) = accept(march(puv, quv, i0, j0, t), check) {
                self.stats.tubes += 1;
                self.stats.tiled.restart += 1;
                slab.used |= USED_RESTART;
                return Some(tris);
            }
        }
        let pxyz: Vec<[f64; 3]> = pid.iter().map(|&i| check.point(i)).collect();
        let qxyz: Vec<[f64; 3]> = qid.iter().map(|&i| check.point(i)).collect();
        // Minimum area from each start pair; triangles that cross something
        // are forbidden and the program run again, a few rounds.
        let (n, m) = (pid.len(), qid.len());
        let mut budget = DP_RUNS;
        for &(i0, j0) in std::iter::once(&first).chain(&starts) {
            let mut forbidden = std::collections::HashSet::new();
            for _ in 0..DP_ROUNDS {
                if budget == 0 {
                    break;
                }
                budget -= 1;
                let Some(tiling) = min_area_avoiding(&pxyz, &qxyz, i0, j0, &forbidden) else { break };
                if let Some(tris) = accept(tiling.clone(), check) {
                    self.stats.tubes += 1;
                    self.stats.tiled.min_area += 1;
                    slab.used |= USED_MIN_AREA;
                    return Some(tris);
                }
                let bad = check.clashes(&tiling.triangles(pid, qid));
                if bad.is_empty() {
                    break;
                }
                let steps = tiling.step_list(n, m);
                forbidden.extend(bad.into_iter().map(|k| steps[k]));
            }
        }
        None
    }

    /// Open polylines: joins the group's polylines one to one, best overlap
    /// first; the rest stay unpaired.
    #[allow(clippy::too_many_arguments)]
    fn pair_open(
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
            self.open_strip(&lower.rings[i].ids, &lower.rings[i].uv, &upper.rings[j].ids, &upper.rings[j].uv, sink)?;
            has_above[i] = true;
            has_below[j] = true;
        }
        self.stats.unpaired += ls.iter().filter(|&&i| !has_above[i]).count() as u64 + us.iter().filter(|&&j| !has_below[j]).count() as u64;
        Ok(())
    }

    /// One strip of triangles between a lower and an upper open polyline.
    fn open_strip(&mut self, pid: &[u32], puv: &[P2], qid: &[u32], quv: &[P2], sink: &mut dyn MeshSink) -> Result<(), ContourError> {
        self.stats.tubes += 1;
        self.stats.tiled.march += 1;
        let t = self.opts.threshold;
        let (n, m) = (pid.len(), qid.len());
        let mut emit = |f: [u32; 3], stats: &mut AngleStats| -> Result<(), ContourError> {
            stats.faces += 1;
            Ok(sink.face(f)?)
        };
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
    Ring { ids, uv, depth, children: Vec::new(), centroid, lo, hi }
}

/// Whether two rings of consecutive sections overlap in projection, with a
/// score, or `None`. A ring stands for its region: inside it and outside
/// its children (a solid without its holes, or a hole without its
/// islands). With `score`, the score is the fraction of each one's
/// vertices inside the other's region (rings whose boundaries cross
/// overlap with a tiny score); without, the first vertex found inside
/// decides and the score is 1. Open polylines overlap when their bounding
/// boxes do, scored by the boxes' common area.
fn overlap(ps: &Prepared, i: usize, qs: &Prepared, j: usize, open: bool, score: bool) -> Option<f64> {
    let (p, q) = (&ps.rings[i], &qs.rings[j]);
    if p.hi[0] < q.lo[0] || q.hi[0] < p.lo[0] || p.hi[1] < q.lo[1] || q.hi[1] < p.lo[1] {
        return None;
    }
    if open {
        let w = (p.hi[0].min(q.hi[0]) - p.lo[0].max(q.lo[0])).max(0.0) * (p.hi[1].min(q.hi[1]) - p.lo[1].max(q.lo[1])).max(0.0);
        return Some(w + 1e-300);
    }
    let in_region = |sec: &Prepared, r: &Ring, x: P2| inside(&r.uv, x) && !r.children.iter().any(|&c| inside(&sec.rings[c].uv, x));
    if !score {
        if p.uv.iter().any(|&x| in_region(qs, q, x)) || q.uv.iter().any(|&x| in_region(ps, p, x)) {
            return Some(1.0);
        }
        return first_crossing(&[&p.uv, &q.uv]).map(|_| 1e-6);
    }
    let a = p.uv.iter().filter(|&&x| in_region(qs, q, x)).count() as f64 / p.uv.len() as f64;
    let b = q.uv.iter().filter(|&&x| in_region(ps, p, x)).count() as f64 / q.uv.len() as f64;
    if a + b > 0.0 {
        return Some(a + b);
    }
    first_crossing(&[&p.uv, &q.uv]).map(|_| 1e-6)
}


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
    let ccw = ring.depth % 2 == 0;
    split_rec((ring.ids.clone(), ring.uv.clone()), ccw, &order, partners, others, &mut out)?;
    Some(out)
}

fn split_rec(part: Part, ccw: bool, group: &[usize], partners: &[&Ring], others: &[&[P2]], out: &mut Vec<(Part, usize)>) -> Option<()> {
    if group.len() == 1 {
        out.push((part, group[0]));
        return Some(());
    }
    let half = group.len() / 2;
    let (g1, g2) = group.split_at(half);
    let (a, b) = split_two(part, ccw, g1, g2, partners, others)?;
    split_rec(a, ccw, g1, partners, others, out)?;
    split_rec(b, ccw, g2, partners, others, out)
}

/// Splits a ring by one chord into the part facing group `g1` and the part
/// facing `g2`.
fn split_two(part: Part, ccw: bool, g1: &[usize], g2: &[usize], partners: &[&Ring], others: &[&[P2]]) -> Option<(Part, Part)> {
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
            if valid_chord(&uv, ccw, a, b, others) {
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
/// ring (the region it encloses: solid for a counter-clockwise ring, void
/// for a hole): it leaves both ends into the interior, touches no ring edge
/// except at its ends, and touches no other contour of the section.
fn valid_chord(uv: &[P2], ccw: bool, a: usize, b: usize, others: &[&[P2]]) -> bool {
    let n = uv.len();
    let (pa, pb) = (uv[a], uv[b]);
    if pa == pb {
        return false;
    }
    let locally_inside = |i: usize, towards: P2| {
        let (x, y, z) = (uv[(i + n - 1) % n], uv[i], uv[(i + 1) % n]);
        let (x, z) = if ccw { (x, z) } else { (z, x) };
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

/// True if no edge between the rings (span) appears twice in the tiling:
/// rings joined by bridges visit the bridges' ends twice, and a span used
/// twice would carry four triangles.
fn spans_distinct(t: &Tiling, pid: &[u32], qid: &[u32]) -> bool {
    let (n, m) = (pid.len(), qid.len());
    let (mut i, mut j) = (t.i0, t.j0);
    let mut spans: Vec<(u32, u32)> = Vec::with_capacity(t.steps.len());
    for &p in &t.steps {
        spans.push((pid[i % n], qid[j % m]));
        if p {
            i += 1;
        } else {
            j += 1;
        }
    }
    spans.sort_unstable();
    spans.windows(2).all(|w| w[0] != w[1])
}

/// True if `t` lies strictly outside the region enclosed by a ring near its
/// vertex `v` (neighbours `a` before and `c` after; `ccw`: the ring turns
/// counter-clockwise), and on neither edge's line through `v`... that is,
/// not in the closed enclosed wedge.
fn outside_at(a: P2, v: P2, c: P2, ccw: bool, t: P2) -> bool {
    let (x, z) = if ccw { (a, c) } else { (c, a) };
    let (s1, s2) = (orient(x, v, t), orient(v, z, t));
    if orient(x, v, z) >= 0.0 {
        !(s1 >= 0.0 && s2 >= 0.0)
    } else {
        !(s1 >= 0.0 || s2 >= 0.0)
    }
}

/// A possible bridge: squared length, then its ends as (ring, position).
type Candidate = (f64, (usize, usize), (usize, usize));

/// Joins the rings `which` of a section into one ring by bridges: segments
/// between vertices of two rings that leave both into the region outside
/// them and touch no contour of the section, no bridge in `forbid` and no
/// bridge placed before (not even at an end). Each bridge is walked twice,
/// once each way, so the joined ring keeps the solid on its left: the
/// triangles on a bridge meet it from both sides, as a ridge. Shortest
/// bridges first, greedily (a spanning tree from the largest ring). New
/// bridges are appended to `placed`; `None` if some ring cannot be reached.
fn bridge_rings(sec: &Prepared, which: &[usize], forbid: &[[u32; 2]], placed: &mut Vec<[u32; 2]>) -> Option<Part> {
    let rings = &sec.rings;
    if which.len() == 1 {
        let r = &rings[which[0]];
        return Some((r.ids.clone(), r.uv.clone()));
    }
    // Every edge of the section, and where each vertex of `which` sits.
    let mut edges: Vec<(u32, u32)> = Vec::new();
    for r in rings {
        let n = r.ids.len();
        for k in 0..n {
            edges.push((r.ids[k], r.ids[(k + 1) % n]));
        }
    }
    let mut used: std::collections::HashSet<u32> = forbid.iter().chain(placed.iter()).flatten().copied().collect();
    let mut walls: Vec<(P2, P2)> = forbid.iter().chain(placed.iter()).map(|b| (sec.uv_of(b[0]), sec.uv_of(b[1]))).collect();
    let outside = |r: usize, k: usize, t: P2| {
        let ring = &rings[r];
        let n = ring.uv.len();
        outside_at(ring.uv[(k + n - 1) % n], ring.uv[k], ring.uv[(k + 1) % n], ring.depth % 2 == 0, t)
    };
    let first = *which
        .iter()
        .max_by(|&&a, &&b| signed_area(&rings[a].uv).abs().total_cmp(&signed_area(&rings[b].uv).abs()).then(b.cmp(&a)))
        .unwrap();
    let mut joined: Vec<u32> = rings[first].ids.clone();
    let mut members: Vec<usize> = vec![first];
    let mut rest: Vec<usize> = which.iter().copied().filter(|&r| r != first).collect();
    while !rest.is_empty() {
        // Candidate pairs (member vertex, other vertex), shortest first:
        // for each vertex of the other rings its nearest member vertex,
        // then, if none of those will do, every pair.
        let d2 = |a: P2, b: P2| (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2);
        let from: Vec<(usize, usize)> = members.iter().flat_map(|&r| (0..rings[r].ids.len()).map(move |k| (r, k))).filter(|&(r, k)| !used.contains(&rings[r].ids[k])).collect();
        let to: Vec<(usize, usize)> = rest.iter().flat_map(|&r| (0..rings[r].ids.len()).map(move |k| (r, k))).filter(|&(r, k)| !used.contains(&rings[r].ids[k])).collect();
        let valid = |a: (usize, usize), b: (usize, usize), walls: &[(P2, P2)]| -> bool {
            let (pa, pb) = (rings[a.0].uv[a.1], rings[b.0].uv[b.1]);
            let (ia, ib) = (rings[a.0].ids[a.1], rings[b.0].ids[b.1]);
            if pa == pb || !outside(a.0, a.1, pb) || !outside(b.0, b.1, pa) {
                return false;
            }
            if walls.iter().any(|w| segments_touch(pa, pb, w.0, w.1)) {
                return false;
            }
            !edges.iter().any(|&(e, f)| e != ia && f != ia && e != ib && f != ib && segments_touch(pa, pb, sec.uv_of(e), sec.uv_of(f)))
        };
        let mut cand: Vec<Candidate> = to
            .iter()
            .filter_map(|&b| {
                let pb = rings[b.0].uv[b.1];
                from.iter().map(|&a| (d2(rings[a.0].uv[a.1], pb), a, b)).min_by(|x, y| x.0.total_cmp(&y.0))
            })
            .collect();
        cand.sort_by(|x, y| x.0.total_cmp(&y.0).then((x.1, x.2).cmp(&(y.1, y.2))));
        let mut found = cand.iter().find(|c| valid(c.1, c.2, &walls)).copied();
        if found.is_none() && from.len() * to.len() <= 4_000_000 {
            let mut all: Vec<Candidate> = from.iter().flat_map(|&a| to.iter().map(move |&b| (a, b))).map(|(a, b)| (d2(rings[a.0].uv[a.1], rings[b.0].uv[b.1]), a, b)).collect();
            all.sort_by(|x, y| x.0.total_cmp(&y.0).then((x.1, x.2).cmp(&(y.1, y.2))));
            found = all.iter().take(20_000).find(|c| valid(c.1, c.2, &walls)).copied();
        }
        let (_, a, b) = found?;
        let (ia, ib) = (rings[a.0].ids[a.1], rings[b.0].ids[b.1]);
        // Splice: ..., a, b, (around b's ring), b, a, ...
        let at = joined.iter().position(|&x| x == ia).expect("a member vertex");
        let other = &rings[b.0].ids;
        let n = other.len();
        let mut next: Vec<u32> = Vec::with_capacity(joined.len() + n + 2);
        next.extend_from_slice(&joined[..=at]);
        next.extend((0..=n).map(|k| other[(b.1 + k) % n]));
        next.extend_from_slice(&joined[at..]);
        joined = next;
        used.insert(ia);
        used.insert(ib);
        walls.push((rings[a.0].uv[a.1], rings[b.0].uv[b.1]));
        placed.push([ia, ib]);
        members.push(b.0);
        rest.retain(|&r| r != b.0);
    }
    let uv = joined.iter().map(|&i| sec.uv_of(i)).collect();
    Some((joined, uv))
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
        assert_eq!((st.splits, st.bridged, st.apart), (1, 0, 0));
        let c = mint_testkit::topology::check_closed_oriented(&m).unwrap();
        assert_eq!((c.components, c.genus), (1, 0));
    }
}
