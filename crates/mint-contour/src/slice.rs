//! Slicing a triangle mesh by parallel planes into a contour stack: the
//! inverse of reconstruction, used to make test data from real meshes.
//!
//! [`Slicer::new`] takes the plane levels along an axis; triangles are fed
//! one at a time ([`Slicer::add`], with their vertex ids), and
//! [`Slicer::finish`] chains the segments of each level into closed
//! contours. The planes are `level_k = min + (k + ½)·(max − min)/N`, so no
//! plane touches the mesh's extreme points.
//!
//! Exactness: a vertex lies *above* a plane when its coordinate is `≥` the
//! level (a vertex on the plane is moved up by an infinitesimal), so every
//! triangle that straddles the plane gives exactly one segment, between the
//! crossing points of its two straddling edges. A crossing point is keyed by
//! its edge `(lower vertex, upper vertex)` and computed from that edge
//! alone, so the two triangles sharing an edge agree on it bit for bit and
//! segments chain by key, never by comparing coordinates. A plane through a
//! vertex gives that vertex's exact position for every edge into it; the
//! repeated points are then removed. A segment runs
//! from the crossing of the edge that goes down to the crossing of the edge
//! that goes up (in the triangle's winding), which leaves the solid on the
//! left seen from above for an outward-oriented mesh.
//!
//! Consecutive points closer than [`MERGE_TOLERANCE`] of their contour's
//! size are merged (a plane passing within rounding of a vertex gives
//! several such points, and their slivers would vanish in f32 output).
//!
//! Open or non-manifold meshes leave open chains (where a plane passes
//! through a hole); each open chain's end is joined to the nearest open
//! chain start ([`SliceStats::chains_closed`]). Contours that then are
//! degenerate, or cross another contour of their level, are dropped
//! ([`SliceStats::contours_dropped`]) so that the output is always a valid
//! profile.

use crate::geom2d::{first_crossing, signed_area, P2};
use serde::Serialize;
use std::collections::HashMap;

/// Consecutive contour points closer than this fraction of the contour's
/// bounding-box diagonal are merged into the first of them.
pub const MERGE_TOLERANCE: f64 = 1e-9;

/// Counters of a slicing.
#[derive(Debug, Default, Clone, Serialize, PartialEq, Eq)]
pub struct SliceStats {
    /// Planes asked for.
    pub planes: u64,
    /// Planes that met the mesh and kept at least one contour.
    pub sections: u64,
    /// Contours written, and their vertices.
    pub contours: u64,
    pub vertices: u64,
    /// Open chains joined to the nearest chain start (holes in the mesh).
    pub chains_closed: u64,
    /// Contours dropped: fewer than 3 distinct points, no area, or crossing
    /// another contour.
    pub contours_dropped: u64,
}

/// One segment of a level: from the crossing on edge `from` to `to`.
#[derive(Debug, Clone, Copy)]
struct Seg {
    from: (u32, u32),
    to: (u32, u32),
    p: [f64; 3],
}

/// Collects the segments of every level; see the module docs.
pub struct Slicer {
    axis: usize,
    levels: Vec<f64>,
    segs: Vec<Vec<Seg>>,
}

impl Slicer {
    /// `n` planes across `[min, max]` along `axis`.
    pub fn new(axis: usize, min: f64, max: f64, n: u32) -> Slicer {
        let step = (max - min) / n as f64;
        let levels: Vec<f64> = (0..n).map(|k| min + (k as f64 + 0.5) * step).collect();
        Slicer { axis, segs: vec![Vec::new(); levels.len()], levels }
    }

    /// The plane levels.
    pub fn levels(&self) -> &[f64] {
        &self.levels
    }

    /// Adds one triangle: its vertex ids and positions, counter-clockwise
    /// seen from outside.
    pub fn add(&mut self, ids: [u32; 3], p: [[f64; 3]; 3]) {
        let d = self.axis;
        let lo = p.iter().map(|q| q[d]).fold(f64::INFINITY, f64::min);
        let hi = p.iter().map(|q| q[d]).fold(f64::NEG_INFINITY, f64::max);
        // Levels with lo < level ≤ hi are straddled (on-plane points are above).
        let first = self.levels.partition_point(|&l| l <= lo);
        let last = self.levels.partition_point(|&l| l <= hi);
        for k in first..last {
            let level = self.levels[k];
            let above = [p[0][d] >= level, p[1][d] >= level, p[2][d] >= level];
            let (mut down, mut up) = (None, None);
            for e in 0..3 {
                let (a, b) = (e, (e + 1) % 3);
                if above[a] && !above[b] {
                    down = Some((ids[b], ids[a], p[b], p[a]));
                } else if !above[a] && above[b] {
                    up = Some((ids[a], ids[b], p[a], p[b]));
                }
            }
            let (Some(dn), Some(upe)) = (down, up) else { continue };
            let point = |(_, _, lo, hi): (u32, u32, [f64; 3], [f64; 3])| {
                if hi[d] == level {
                    // The plane passes through the upper vertex: every edge
                    // into it crosses exactly there (equal points, deduplicated).
                    return hi;
                }
                let t = (level - lo[d]) / (hi[d] - lo[d]);
                let mut q = [lo[0] + t * (hi[0] - lo[0]), lo[1] + t * (hi[1] - lo[1]), lo[2] + t * (hi[2] - lo[2])];
                q[d] = level;
                q
            };
            // The segment starts at the crossing of the downward edge.
            self.segs[k].push(Seg { from: (dn.0, dn.1), to: (upe.0, upe.1), p: point(dn) });
        }
    }

    /// Chains the segments into contours per level: `(level, contours)` for
    /// every level that kept at least one contour.
    pub fn finish(self, stats: &mut SliceStats) -> Vec<(f64, Vec<Vec<[f64; 3]>>)> {
        stats.planes = self.levels.len() as u64;
        let axis = self.axis;
        let mut out = Vec::new();
        for (k, segs) in self.segs.into_iter().enumerate() {
            let contours = chain(segs, axis, stats);
            if !contours.is_empty() {
                stats.sections += 1;
                stats.contours += contours.len() as u64;
                stats.vertices += contours.iter().map(|c| c.len() as u64).sum::<u64>();
                out.push((self.levels[k], contours));
            }
        }
        out
    }
}

/// In-plane coordinates for the checks (the two other axes, cyclic).
fn flat(p: [f64; 3], axis: usize) -> P2 {
    [p[(axis + 1) % 3], p[(axis + 2) % 3]]
}

fn chain(segs: Vec<Seg>, axis: usize, stats: &mut SliceStats) -> Vec<Vec<[f64; 3]>> {
    // Each crossing key starts at most one segment (more on non-manifold edges).
    let mut by_from: HashMap<(u32, u32), Vec<usize>> = HashMap::with_capacity(segs.len());
    let mut has_pred: HashMap<(u32, u32), bool> = HashMap::with_capacity(segs.len());
    for (i, s) in segs.iter().enumerate() {
        by_from.entry(s.from).or_default().push(i);
        has_pred.insert(s.to, true);
    }
    let mut used = vec![false; segs.len()];
    let mut loops: Vec<Vec<[f64; 3]>> = Vec::new();
    let mut open: Vec<Vec<[f64; 3]>> = Vec::new();
    let walk = |start: usize, used: &mut Vec<bool>| -> (Vec<[f64; 3]>, bool) {
        let mut pts = Vec::new();
        let mut i = start;
        loop {
            used[i] = true;
            pts.push(segs[i].p);
            let next = by_from.get(&segs[i].to).and_then(|v| v.iter().copied().find(|&j| !used[j]));
            match next {
                Some(j) => i = j,
                None => return (pts, segs[i].to == segs[start].from),
            }
        }
    };
    // Open chains first (they start where no segment ends), then loops.
    let mut starts: Vec<usize> = (0..segs.len()).filter(|&i| !has_pred.contains_key(&segs[i].from)).collect();
    starts.extend(0..segs.len());
    for s in starts {
        if used[s] {
            continue;
        }
        let (pts, closed) = walk(s, &mut used);
        if closed {
            loops.push(pts);
        } else {
            open.push(pts);
        }
    }
    // Join open chains: each end to the nearest remaining chain start.
    while !open.is_empty() {
        let mut cur = open.swap_remove(0);
        loop {
            let end = *cur.last().unwrap();
            let d = |p: [f64; 3]| (p[0] - end[0]).powi(2) + (p[1] - end[1]).powi(2) + (p[2] - end[2]).powi(2);
            let self_d = d(cur[0]);
            let best = (0..open.len()).min_by(|&a, &b| d(open[a][0]).total_cmp(&d(open[b][0])));
            match best {
                Some(b) if d(open[b][0]) < self_d => {
                    let next = open.swap_remove(b);
                    cur.extend(next);
                    stats.chains_closed += 1;
                }
                _ => {
                    stats.chains_closed += 1;
                    break;
                }
            }
        }
        loops.push(cur);
    }
    // Clean: exact duplicates, then degenerate or crossing contours.
    let mut clean: Vec<Vec<[f64; 3]>> = Vec::new();
    for mut c in loops {
        // Points closer than MERGE_TOLERANCE of the contour's size are one
        // point: a plane passing within rounding of a vertex makes several.
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for p in &c {
            for d in 0..3 {
                lo[d] = lo[d].min(p[d]);
                hi[d] = hi[d].max(p[d]);
            }
        }
        let tol2 = (MERGE_TOLERANCE * MERGE_TOLERANCE) * ((hi[0] - lo[0]).powi(2) + (hi[1] - lo[1]).powi(2) + (hi[2] - lo[2]).powi(2));
        let close = |a: &[f64; 3], b: &[f64; 3]| (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2) <= tol2;
        c.dedup_by(|b, a| close(a, b));
        while c.len() > 1 && close(&c[0], &c[c.len() - 1]) {
            c.pop();
        }
        let uv: Vec<P2> = c.iter().map(|&p| flat(p, axis)).collect();
        if c.len() < 3 || signed_area(&uv) == 0.0 {
            stats.contours_dropped += 1;
            continue;
        }
        clean.push(c);
    }
    loop {
        let uv: Vec<Vec<P2>> = clean.iter().map(|c| c.iter().map(|&p| flat(p, axis)).collect()).collect();
        let refs: Vec<&[P2]> = uv.iter().map(|v| v.as_slice()).collect();
        match first_crossing(&refs) {
            None => break,
            Some(((a, _), (b, _))) => {
                // Drop the smaller of the two (or the self-intersecting one).
                let drop = if a == b || signed_area(&uv[a]).abs() <= signed_area(&uv[b]).abs() { a } else { b };
                clean.remove(drop);
                stats.contours_dropped += 1;
            }
        }
    }
    clean
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An axis-aligned box as 12 outward triangles.
    fn cube() -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        let v: Vec<[f64; 3]> = (0..8).map(|i| [(i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64]).collect();
        let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
        let f = quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect();
        (v, f)
    }

    #[test]
    fn a_cube_slices_into_counter_clockwise_squares() {
        let (v, f) = cube();
        let mut s = Slicer::new(2, 0.0, 1.0, 4);
        for t in &f {
            s.add(*t, t.map(|i| v[i as usize]));
        }
        let mut st = SliceStats::default();
        let out = s.finish(&mut st);
        assert_eq!(out.len(), 4);
        assert_eq!(out.iter().map(|o| o.0).collect::<Vec<_>>(), vec![0.125, 0.375, 0.625, 0.875]);
        for (_, c) in &out {
            assert_eq!(c.len(), 1);
            let uv: Vec<P2> = c[0].iter().map(|&p| flat(p, 2)).collect();
            // Corners of the unit square (the cut passes through edges), solid on the left.
            assert!((signed_area(&uv) - 1.0).abs() < 1e-12, "{uv:?}");
        }
        assert_eq!((st.chains_closed, st.contours_dropped), (0, 0));
    }

    #[test]
    fn a_plane_through_vertices_still_gives_one_loop() {
        // Levels exactly at the heights of the cube's vertices.
        let (v, f) = cube();
        let mut s = Slicer { axis: 2, levels: vec![0.0, 1.0], segs: vec![Vec::new(), Vec::new()] };
        for t in &f {
            s.add(*t, t.map(|i| v[i as usize]));
        }
        let mut st = SliceStats::default();
        let out = s.finish(&mut st);
        // The bottom face is "above" level 0: the level cuts nothing but the
        // walls' bottom edges, and the contour is the unit square.
        assert_eq!(out.len(), 1);
        assert_eq!(out[0].1[0].len(), 4);
    }
}
