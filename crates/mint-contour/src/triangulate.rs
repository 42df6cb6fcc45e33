//! Polygon triangulation, "smallest inner angle first" (Dangl 1998, §2.1).
//!
//! Sources:
//! - M. Dangl, "Three-Dimensional Object Reconstruction from Layered Spatial
//!   Data", PRIP-TR-50, TU Vienna, 1998, §2.1: repeatedly cut off the
//!   triangle at the vertex with the smallest inner angle; no new vertices.
//! - D. Eberly, "Triangulation by Ear Clipping", Geometric Tools, 2002-2015:
//!   the ear test (only reflex vertices can lie in an ear) and joining holes
//!   to the outer boundary by bridges, holes in decreasing order of their
//!   rightmost x.
//! - G. H. Meisters, "Polygons have ears", Amer. Math. Monthly 82, 1975:
//!   every simple polygon with more than three vertices has two ears, so
//!   the loop below always finds one on valid input.
//!
//! [`triangulate`] takes an outer boundary and holes (any orientation),
//! turns the outer one counter-clockwise and the holes clockwise, joins each
//! hole to the boundary by a *bridge* (a pair of coincident edges between a
//! hole vertex and a visible boundary vertex), and clips ears from the
//! resulting weakly simple ring. An ear is a strictly convex vertex whose
//! triangle contains no other vertex of the ring in its closed interior
//! (vertices at the same position as one of its three corners excepted:
//! those are the bridge copies). Among the ears, the one with the smallest
//! inner angle is cut first: a heap keyed by angle, with lazy invalidation;
//! an ear blocked by a reflex vertex is looked at again when that vertex
//! changes. The result has `n - 2 + 2h` triangles for `n` vertices and `h`
//! holes, all counter-clockwise, indexing the input vertices (outer first,
//! then each hole in order).
//!
//! Contract: the outer boundary and the holes are simple, the holes lie
//! strictly inside the outer boundary and outside one another, and no two
//! consecutive vertices are equal (the profile reader and the optimizer
//! check this first). Collinear runs are fine. On invalid input the
//! function still returns `n - 2 + 2h` triangles but counts the ears it had
//! to force ([`Triangulation::forced`]); callers treat a non-zero count as
//! failure. All decisions are exact orientation signs; angles only order
//! the ears.

use crate::geom2d::{inner_angle, orient, P2};
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// Triangles of a polygon, counter-clockwise, as indices of its vertices.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Triangulation {
    /// `n - 2 + 2h` triangles.
    pub triangles: Vec<[u32; 3]>,
    /// Ears cut although their triangle contained another vertex, or at a
    /// vertex that was not strictly convex: 0 on valid input.
    pub forced: u32,
}

/// Why a polygon cannot be triangulated at all.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TriangulateError {
    /// The outer boundary or a hole has fewer than 3 vertices.
    #[error("a polygon needs at least 3 vertices, this one has {0}")]
    TooFewVertices(usize),
    /// No vertex of the boundary is visible from a hole: the hole is not
    /// inside the outer boundary, or it crosses it.
    #[error("hole {0} cannot be joined to the outer boundary (is it inside, and disjoint from the other contours?)")]
    NoBridge(usize),
}

/// Triangulates `outer` with `holes`; see the module docs.
pub fn triangulate(outer: &[P2], holes: &[&[P2]]) -> Result<Triangulation, TriangulateError> {
    // All points in one array: outer, then each hole.
    let mut pts: Vec<P2> = Vec::with_capacity(outer.len() + holes.iter().map(|h| h.len()).sum::<usize>());
    pts.extend_from_slice(outer);
    let mut hole_rings: Vec<Vec<u32>> = Vec::with_capacity(holes.len());
    for h in holes {
        let base = pts.len() as u32;
        pts.extend_from_slice(h);
        hole_rings.push((base..base + h.len() as u32).collect());
    }
    for n in std::iter::once(outer.len()).chain(holes.iter().map(|h| h.len())) {
        if n < 3 {
            return Err(TriangulateError::TooFewVertices(n));
        }
    }
    let mut ring: Vec<u32> = (0..outer.len() as u32).collect();
    if ring_area(&pts, &ring) < 0.0 {
        ring.reverse();
    }
    for h in &mut hole_rings {
        if ring_area(&pts, h) > 0.0 {
            h.reverse();
        }
    }
    // Bridges: holes by decreasing rightmost x (Eberly), each from its
    // rightmost vertex to the nearest visible vertex of the ring so far.
    let mut order: Vec<usize> = (0..hole_rings.len()).collect();
    let rightmost = |h: &Vec<u32>| -> usize {
        (0..h.len()).max_by(|&a, &b| cmp_xy(pts[h[a] as usize], pts[h[b] as usize])).unwrap()
    };
    order.sort_by(|&a, &b| {
        let (pa, pb) = (pts[hole_rings[a][rightmost(&hole_rings[a])] as usize], pts[hole_rings[b][rightmost(&hole_rings[b])] as usize]);
        cmp_xy(pb, pa).then(a.cmp(&b))
    });
    for (k, &hi) in order.iter().enumerate() {
        let h = &hole_rings[hi];
        let m = rightmost(h);
        let hole: Vec<u32> = (0..h.len()).map(|i| h[(m + i) % h.len()]).collect();
        let later: Vec<&[u32]> = order[k + 1..].iter().map(|&o| hole_rings[o].as_slice()).collect();
        let at = find_bridge(&pts, &ring, &hole, &later).ok_or(TriangulateError::NoBridge(hi))?;
        let p = ring[at];
        let mut merged = Vec::with_capacity(ring.len() + hole.len() + 2);
        merged.extend_from_slice(&ring[..=at]);
        merged.extend_from_slice(&hole);
        merged.push(hole[0]);
        merged.push(p);
        merged.extend_from_slice(&ring[at + 1..]);
        ring = merged;
    }
    Ok(clip_ears(&pts, &ring))
}

/// Lexicographic order on (x, y).
fn cmp_xy(a: P2, b: P2) -> std::cmp::Ordering {
    a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1]))
}

fn ring_area(pts: &[P2], ring: &[u32]) -> f64 {
    let n = ring.len();
    let mut s = 0.0;
    for i in 0..n {
        let (p, q) = (pts[ring[i] as usize], pts[ring[(i + 1) % n] as usize]);
        s += (p[0] - q[0]) * (p[1] + q[1]);
    }
    0.5 * s
}

/// True if the direction from `b` towards `p` points into the interior
/// sector at `b` of a ring turning `a → b → c` with its interior on the
/// left (strictly: not along either edge).
fn locally_inside(a: P2, b: P2, c: P2, p: P2) -> bool {
    if orient(a, b, c) >= 0.0 {
        orient(a, b, p) > 0.0 && orient(b, c, p) > 0.0
    } else {
        orient(a, b, p) > 0.0 || orient(b, c, p) > 0.0
    }
}

/// The ring position of the vertex a hole's first vertex is bridged to: the
/// nearest ring vertex whose segment to it leaves both ends into the
/// polygon's interior and touches no edge of the ring, of the hole or of
/// the holes still to be bridged, except at its own two ends.
fn find_bridge(pts: &[P2], ring: &[u32], hole: &[u32], later: &[&[u32]]) -> Option<usize> {
    let m = pts[hole[0] as usize];
    let (hp, hn) = (pts[hole[hole.len() - 1] as usize], pts[hole[1] as usize]);
    let n = ring.len();
    let mut cand: Vec<(f64, usize)> = (0..n)
        .map(|i| {
            let p = pts[ring[i] as usize];
            ((p[0] - m[0]).powi(2) + (p[1] - m[1]).powi(2), i)
        })
        .collect();
    cand.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    'cand: for &(_, i) in &cand {
        let p = pts[ring[i] as usize];
        let (a, c) = (pts[ring[(i + n - 1) % n] as usize], pts[ring[(i + 1) % n] as usize]);
        if p == m || !locally_inside(a, p, c, m) || !locally_inside(hp, m, hn, p) {
            continue;
        }
        // The segment m–p may meet an edge only at p (ring edges) or at m
        // (hole edges).
        let blocked = |ring: &[u32], end: P2| -> bool {
            let k = ring.len();
            (0..k).any(|e| {
                let (u, v) = (pts[ring[e] as usize], pts[ring[(e + 1) % k] as usize]);
                if u == end || v == end {
                    // An edge at the allowed end may only touch there:
                    // collinear overlap beyond it blocks.
                    let other = if u == end { v } else { u };
                    return orient(m, p, other) == 0.0 && crate::geom2d::segments_touch(m, p, other, other);
                }
                crate::geom2d::segments_touch(m, p, u, v)
            })
        };
        if blocked(ring, p) || blocked(hole, m) {
            continue 'cand;
        }
        for h in later {
            if blocked(h, [f64::NAN, f64::NAN]) {
                continue 'cand;
            }
        }
        return Some(i);
    }
    None
}

/// Closed triangle test, exact: `p` inside `abc` (counter-clockwise) or on
/// its boundary.
#[inline]
fn in_closed_triangle(a: P2, b: P2, c: P2, p: P2) -> bool {
    orient(a, b, p) >= 0.0 && orient(b, c, p) >= 0.0 && orient(c, a, p) >= 0.0
}

/// Ear clipping of a weakly simple counter-clockwise ring, smallest inner
/// angle first.
fn clip_ears(pts: &[P2], ring: &[u32]) -> Triangulation {
    let n = ring.len();
    let mut out = Triangulation { triangles: Vec::with_capacity(n.saturating_sub(2)), forced: 0 };
    let mut prev: Vec<usize> = (0..n).map(|i| (i + n - 1) % n).collect();
    let mut next: Vec<usize> = (0..n).map(|i| (i + 1) % n).collect();
    let mut alive = vec![true; n];
    let mut version = vec![0u32; n];
    let mut reflex = vec![false; n];
    let mut blocked_by: Vec<Vec<usize>> = vec![Vec::new(); n];
    let p = |i: usize| pts[ring[i] as usize];
    let mut left = n;
    let mut heap: BinaryHeap<Reverse<(u64, usize, u32)>> = BinaryHeap::with_capacity(n);
    let mut reflex_list: Vec<usize> = Vec::new();
    for i in 0..n {
        let (a, b, c) = (p(prev[i]), p(i), p(next[i]));
        if orient(a, b, c) > 0.0 {
            heap.push(Reverse((inner_angle(a, b, c).to_bits(), i, 0)));
        } else {
            reflex[i] = true;
            reflex_list.push(i);
        }
    }
    // Is node i an ear now? Returns the blocking vertex if not.
    let ear_blocker = |i: usize, prev: &[usize], next: &[usize], reflex: &[bool], reflex_list: &[usize], alive: &[bool]| -> Option<usize> {
        let (a, b, c) = (p(prev[i]), p(i), p(next[i]));
        for &r in reflex_list {
            if !alive[r] || !reflex[r] || r == i || r == prev[i] || r == next[i] {
                continue;
            }
            let q = p(r);
            if q == a || q == b || q == c {
                continue;
            }
            if in_closed_triangle(a, b, c, q) {
                return Some(r);
            }
        }
        None
    };
    while left > 3 {
        let mut cut = None;
        while let Some(Reverse((_, i, ver))) = heap.pop() {
            if !alive[i] || ver != version[i] || reflex[i] {
                continue;
            }
            if orient(p(prev[i]), p(i), p(next[i])) <= 0.0 {
                continue;
            }
            match ear_blocker(i, &prev, &next, &reflex, &reflex_list, &alive) {
                None => {
                    cut = Some(i);
                    break;
                }
                Some(r) => blocked_by[r].push(i),
            }
        }
        let i = match cut {
            Some(i) => i,
            None => {
                // Nothing valid in the heap: rescan everything (an ear may
                // have been unblocked without a neighbour changing), then
                // force the smallest convex angle on invalid input.
                let mut best: Option<(f64, usize, bool)> = None;
                let mut j = (0..n).find(|&j| alive[j]).unwrap();
                for _ in 0..left {
                    let (a, b, c) = (p(prev[j]), p(j), p(next[j]));
                    let convex = orient(a, b, c) > 0.0;
                    let ear = convex && ear_blocker(j, &prev, &next, &reflex, &reflex_list, &alive).is_none();
                    let ang = inner_angle(a, b, c);
                    let better = match best {
                        None => true,
                        Some((ba, _, be)) => (ear && !be) || (ear == be && ang < ba),
                    };
                    if better {
                        best = Some((ang, j, ear));
                    }
                    j = next[j];
                }
                let (_, j, ear) = best.unwrap();
                if !ear {
                    out.forced += 1;
                }
                j
            }
        };
        // Cut the ear (a, i, c).
        let (a, c) = (prev[i], next[i]);
        out.triangles.push([ring[a], ring[i], ring[c]]);
        alive[i] = false;
        next[a] = c;
        prev[c] = a;
        left -= 1;
        for j in [a, c] {
            version[j] += 1;
            let (pa, pb, pc) = (p(prev[j]), p(j), p(next[j]));
            let convex = orient(pa, pb, pc) > 0.0;
            if convex {
                if reflex[j] {
                    reflex[j] = false;
                    for k in std::mem::take(&mut blocked_by[j]) {
                        if alive[k] {
                            version[k] += 1;
                            let (ka, kb, kc) = (p(prev[k]), p(k), p(next[k]));
                            heap.push(Reverse((inner_angle(ka, kb, kc).to_bits(), k, version[k])));
                        }
                    }
                }
                heap.push(Reverse((inner_angle(pa, pb, pc).to_bits(), j, version[j])));
            } else if !reflex[j] {
                reflex[j] = true;
                reflex_list.push(j);
            }
        }
        if reflex_list.len() > 64 && reflex_list.len() > 2 * left {
            reflex_list.retain(|&r| alive[r] && reflex[r]);
        }
    }
    let i = (0..n).find(|&j| alive[j]).unwrap();
    let (a, c) = (prev[i], next[i]);
    out.triangles.push([ring[a], ring[i], ring[c]]);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom2d::signed_area;

    fn area_of(pts: &[P2], t: &Triangulation) -> f64 {
        t.triangles.iter().map(|&[a, b, c]| 0.5 * orient(pts[a as usize], pts[b as usize], pts[c as usize])).sum()
    }

    #[test]
    fn a_square_gives_two_triangles_and_a_concave_l_gives_four() {
        let sq = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        let t = triangulate(&sq, &[]).unwrap();
        assert_eq!((t.triangles.len(), t.forced), (2, 0));
        let l = [[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [1.0, 1.0], [1.0, 2.0], [0.0, 2.0]];
        let t = triangulate(&l, &[]).unwrap();
        assert_eq!((t.triangles.len(), t.forced), (4, 0));
        assert_eq!(area_of(&l, &t), 3.0);
        // Clockwise input gives counter-clockwise triangles too.
        let mut cw = l.to_vec();
        cw.reverse();
        let t = triangulate(&cw, &[]).unwrap();
        assert!(t.triangles.iter().all(|&[a, b, c]| orient(cw[a as usize], cw[b as usize], cw[c as usize]) > 0.0));
    }

    #[test]
    fn smallest_angle_goes_first() {
        // A long thin triangle tip at (10, 0.5) is the smallest angle.
        let p = [[0.0, 0.0], [10.0, 0.5], [0.0, 1.0], [-1.0, 0.5]];
        let t = triangulate(&p, &[]).unwrap();
        assert_eq!(t.triangles[0], [0, 1, 2]);
    }

    #[test]
    fn collinear_runs_need_no_new_vertices() {
        // A rectangle with 3 extra points on each side: 16 vertices, 14 triangles.
        let mut p = Vec::new();
        for i in 0..4 {
            p.push([i as f64, 0.0]);
        }
        for i in 0..4 {
            p.push([4.0, i as f64]);
        }
        for i in 0..4 {
            p.push([4.0 - i as f64, 4.0]);
        }
        for i in 0..4 {
            p.push([0.0, 4.0 - i as f64]);
        }
        let t = triangulate(&p, &[]).unwrap();
        assert_eq!((t.triangles.len(), t.forced), (14, 0));
        assert_eq!(area_of(&p, &t), 16.0);
        assert!(t.triangles.iter().all(|&[a, b, c]| orient(p[a as usize], p[b as usize], p[c as usize]) > 0.0));
    }

    #[test]
    fn a_square_with_a_square_hole_gives_eight_triangles() {
        let outer = [[0.0, 0.0], [3.0, 0.0], [3.0, 3.0], [0.0, 3.0]];
        let hole = [[1.0, 1.0], [2.0, 1.0], [2.0, 2.0], [1.0, 2.0]];
        let t = triangulate(&outer, &[&hole]).unwrap();
        assert_eq!((t.triangles.len(), t.forced), (8, 0));
        let all: Vec<P2> = outer.iter().chain(hole.iter()).copied().collect();
        assert_eq!(area_of(&all, &t), 8.0);
        assert_eq!(signed_area(&outer) - signed_area(&hole), 8.0);
    }

    #[test]
    fn too_few_vertices_is_an_error() {
        assert_eq!(triangulate(&[[0.0, 0.0], [1.0, 0.0]], &[]), Err(TriangulateError::TooFewVertices(2)));
        let outside = [[5.0, 5.0], [6.0, 5.0], [6.0, 6.0]];
        let sq = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        // A "hole" outside the boundary: no boundary vertex sees it from inside.
        assert_eq!(triangulate(&sq, &[&outside]), Err(TriangulateError::NoBridge(0)));
    }
}
