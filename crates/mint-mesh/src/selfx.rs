//! [`self_intersections`]: the pairs of faces of a mesh that intersect,
//! decided exactly (Shewchuk's adaptive `orient3d`/`orient2d` from the
//! `robust` crate: the sign of every determinant is exact, so the verdict
//! is not a matter of tolerance).
//!
//! Two faces that share vertices intersect only if they overlap beyond what
//! they share:
//! - sharing an edge: when they are coplanar and lie on the same side of it
//!   (folded onto each other); otherwise they meet only along the edge;
//! - sharing one vertex `v`: when the edge opposite `v` of either meets the
//!   other face, or (coplanar) their angles at `v` overlap;
//! - sharing nothing: when an edge of either meets the other (closed
//!   segments and triangles: touching counts), or, coplanar, when they
//!   overlap in their plane.
//!
//! Faces with zero area (collinear or repeated corners) are skipped: `check`
//! counts them as degenerate. Faces on the same three vertices are not
//! counted here either (`check` counts them as duplicates).
//!
//! Broad phase: a uniform grid over the mesh's box with about one face per
//! cell; each face is listed in the cells its box overlaps, and a pair is
//! tested in the first cell the two share. Memory: the positions and faces,
//! plus about 16 bytes per (face, cell) entry.

use robust::{orient2d, orient3d, Coord, Coord3D};

type P = [f64; 3];

fn o3(a: P, b: P, c: P, d: P) -> i8 {
    let c3 = |p: P| Coord3D { x: p[0], y: p[1], z: p[2] };
    let v = orient3d(c3(a), c3(b), c3(c), c3(d));
    (v > 0.0) as i8 - (v < 0.0) as i8
}

fn o2(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> i8 {
    let c2 = |p: [f64; 2]| Coord { x: p[0], y: p[1] };
    let v = orient2d(c2(a), c2(b), c2(c));
    (v > 0.0) as i8 - (v < 0.0) as i8
}

/// A projection (dropping one axis) in which triangle `t` keeps non-zero
/// area, if any: the exact test, not the largest normal component.
fn projection(t: &[P; 3]) -> Option<usize> {
    (0..3).rev().find(|&drop| {
        let pr = |p: P| proj(p, drop);
        o2(pr(t[0]), pr(t[1]), pr(t[2])) != 0
    })
}

fn proj(p: P, drop: usize) -> [f64; 2] {
    match drop {
        0 => [p[1], p[2]],
        1 => [p[2], p[0]],
        _ => [p[0], p[1]],
    }
}

/// Closed segments [p, q] and [r, s] in the plane meet.
fn seg_seg_2d(p: [f64; 2], q: [f64; 2], r: [f64; 2], s: [f64; 2]) -> bool {
    let (d1, d2, d3, d4) = (o2(r, s, p), o2(r, s, q), o2(p, q, r), o2(p, q, s));
    if d1 * d2 < 0 && d3 * d4 < 0 {
        return true;
    }
    let on = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
        a[0].min(b[0]) <= c[0] && c[0] <= a[0].max(b[0]) && a[1].min(b[1]) <= c[1] && c[1] <= a[1].max(b[1])
    };
    (d1 == 0 && on(r, s, p)) || (d2 == 0 && on(r, s, q)) || (d3 == 0 && on(p, q, r)) || (d4 == 0 && on(p, q, s))
}

/// Point `p` in the closed triangle `t` (plane).
fn point_in_tri_2d(p: [f64; 2], t: [[f64; 2]; 3]) -> bool {
    let (a, b, c) = (o2(t[0], t[1], p), o2(t[1], t[2], p), o2(t[2], t[0], p));
    (a >= 0 && b >= 0 && c >= 0) || (a <= 0 && b <= 0 && c <= 0)
}

/// Closed segment [p, q] meets the closed, non-degenerate triangle `t`.
fn seg_tri(p: P, q: P, t: &[P; 3]) -> bool {
    let (s1, s2) = (o3(t[0], t[1], t[2], p), o3(t[0], t[1], t[2], q));
    if s1 * s2 > 0 {
        return false;
    }
    if s1 == 0 && s2 == 0 {
        // In the triangle's plane.
        let Some(drop) = projection(t) else { return false };
        let tt = t.map(|x| proj(x, drop));
        let (a, b) = (proj(p, drop), proj(q, drop));
        return point_in_tri_2d(a, tt) || point_in_tri_2d(b, tt) || (0..3).any(|k| seg_seg_2d(a, b, tt[k], tt[(k + 1) % 3]));
    }
    // The segment crosses (or touches) the plane at one point: inside the
    // triangle when it sees the three edges turning the same way.
    let (e0, e1, e2) = (o3(p, q, t[0], t[1]), o3(p, q, t[1], t[2]), o3(p, q, t[2], t[0]));
    (e0 >= 0 && e1 >= 0 && e2 >= 0) || (e0 <= 0 && e1 <= 0 && e2 <= 0)
}

/// Faces `a` and `b` (indices into `pos`, both of non-zero area) intersect
/// beyond what they share; see the module docs.
pub fn faces_intersect(pos: &[P], a: [u32; 3], b: [u32; 3]) -> bool {
    let shared: Vec<u32> = a.iter().copied().filter(|v| b.contains(v)).collect();
    let ta = a.map(|i| pos[i as usize]);
    let tb = b.map(|i| pos[i as usize]);
    match shared.len() {
        3 => false,
        2 => {
            let (u, v) = (shared[0], shared[1]);
            let p = *a.iter().find(|&&x| x != u && x != v).unwrap();
            let q = *b.iter().find(|&&x| x != u && x != v).unwrap();
            let (pu, pv, pp, pq) = (pos[u as usize], pos[v as usize], pos[p as usize], pos[q as usize]);
            if o3(pu, pv, pp, pq) != 0 {
                return false;
            }
            let Some(drop) = projection(&ta) else { return false };
            let (su, sv) = (proj(pu, drop), proj(pv, drop));
            let (sp, sq) = (o2(su, sv, proj(pp, drop)), o2(su, sv, proj(pq, drop)));
            sp != 0 && sp == sq
        }
        1 => {
            let v = shared[0];
            let rest = |t: [u32; 3]| {
                let k = t.iter().position(|&x| x == v).unwrap();
                (t[(k + 1) % 3], t[(k + 2) % 3])
            };
            let (a1, a2) = rest(a);
            let (b1, b2) = rest(b);
            let (pa1, pa2, pb1, pb2) = (pos[a1 as usize], pos[a2 as usize], pos[b1 as usize], pos[b2 as usize]);
            if seg_tri(pa1, pa2, &tb) || seg_tri(pb1, pb2, &ta) {
                return true;
            }
            // Coplanar: do the angles at v overlap? (An edge from v of one
            // face strictly inside the other's angle, or two edges from v
            // along one ray.)
            let pv = pos[v as usize];
            if o3(ta[0], ta[1], ta[2], pb1) != 0 || o3(ta[0], ta[1], ta[2], pb2) != 0 {
                return false;
            }
            let Some(drop) = projection(&ta) else { return false };
            let (c, x1, x2, y1, y2) = (proj(pv, drop), proj(pa1, drop), proj(pa2, drop), proj(pb1, drop), proj(pb2, drop));
            let inside = |r: [f64; 2], s1: [f64; 2], s2: [f64; 2]| {
                // r strictly inside the angle s1-c-s2 (convex, < 180°).
                let o = o2(c, s1, s2);
                o != 0 && o2(c, s1, r) == o && o2(c, r, s2) == o
            };
            let along = |r: [f64; 2], s: [f64; 2]| {
                o2(c, r, s) == 0 && (r[0] - c[0]) * (s[0] - c[0]) + (r[1] - c[1]) * (s[1] - c[1]) > 0.0
            };
            inside(y1, x1, x2) || inside(y2, x1, x2) || inside(x1, y1, y2) || inside(x2, y1, y2)
                || along(x1, y1) || along(x1, y2) || along(x2, y1) || along(x2, y2)
        }
        _ => (0..3).any(|k| seg_tri(ta[k], ta[(k + 1) % 3], &tb) || seg_tri(tb[k], tb[(k + 1) % 3], &ta)),
    }
}

/// What [`self_intersections`] found.
#[derive(Debug, Clone, Default, PartialEq, Eq, serde::Serialize)]
pub struct SelfIntersections {
    /// Pairs of faces that intersect beyond what they share.
    pub pairs: u64,
    /// Up to `max_examples` of them, as face indices `(i, j)`, `i < j`, in order.
    pub examples: Vec<[u32; 2]>,
    /// Faces skipped for zero area.
    pub skipped_degenerate: u64,
}

fn degenerate(t: &[P; 3]) -> bool {
    projection(t).is_none()
}

/// The intersecting pairs of faces of `positions`/`faces`; see the module docs.
pub fn self_intersections(positions: &[P], faces: &[[u32; 3]], max_examples: usize) -> SelfIntersections {
    let n = faces.len();
    let mut out = SelfIntersections::default();
    let tri = |f: usize| faces[f].map(|i| positions[i as usize]);
    let live: Vec<bool> = (0..n).map(|f| !degenerate(&tri(f))).collect();
    out.skipped_degenerate = live.iter().filter(|&&l| !l).count() as u64;
    let boxes: Vec<(P, P)> = (0..n)
        .map(|f| {
            let t = tri(f);
            ([0, 1, 2].map(|d| t[0][d].min(t[1][d]).min(t[2][d])), [0, 1, 2].map(|d| t[0][d].max(t[1][d]).max(t[2][d])))
        })
        .collect();
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for (f, (l, h)) in boxes.iter().enumerate() {
        if live[f] {
            for d in 0..3 {
                lo[d] = lo[d].min(l[d]);
                hi[d] = hi[d].max(h[d]);
            }
        }
    }
    let m = live.iter().filter(|&&l| l).count();
    if m < 2 || !lo.iter().chain(&hi).all(|x| x.is_finite()) {
        return out;
    }
    // Cells about the size of a face's box, at most 8 per face in all.
    let ext = [0, 1, 2].map(|d| hi[d] - lo[d]);
    let mean = boxes.iter().zip(&live).filter(|(_, &l)| l).map(|((l, h), _)| (0..3).map(|d| h[d] - l[d]).fold(0.0, f64::max)).sum::<f64>() / m as f64;
    let mut h = if mean > 0.0 { mean } else { ext.iter().cloned().fold(0.0, f64::max).max(1.0) };
    let count = |h: f64| ext.map(|e| ((e / h).floor() as u64 + 1).min(1 << 20));
    let mut dims = count(h);
    while (dims[0] as f64) * (dims[1] as f64) * (dims[2] as f64) > 8.0 * m as f64 + 8.0 {
        h *= 1.5;
        dims = count(h);
    }
    let cell = |p: P| [0, 1, 2].map(|d| (((p[d] - lo[d]) / h).floor().max(0.0) as u64).min(dims[d] - 1));
    let mut entries: Vec<(u64, u32)> = Vec::new();
    for f in 0..n {
        if !live[f] {
            continue;
        }
        let (a, b) = (cell(boxes[f].0), cell(boxes[f].1));
        for x in a[0]..=b[0] {
            for y in a[1]..=b[1] {
                for z in a[2]..=b[2] {
                    entries.push(((x * dims[1] + y) * dims[2] + z, f as u32));
                }
            }
        }
    }
    entries.sort_unstable();
    let overlap = |i: usize, j: usize| (0..3).all(|d| boxes[i].0[d] <= boxes[j].1[d] && boxes[j].0[d] <= boxes[i].1[d]);
    let mut found: Vec<[u32; 2]> = Vec::new();
    let mut g = 0;
    while g < entries.len() {
        let mut e = g + 1;
        while e < entries.len() && entries[e].0 == entries[g].0 {
            e += 1;
        }
        let here = &entries[g..e];
        for (k, &(c, i)) in here.iter().enumerate() {
            for &(_, j) in &here[k + 1..] {
                let (i, j) = (i as usize, j as usize);
                if !overlap(i, j) {
                    continue;
                }
                // Test a pair only in the first cell both boxes cover.
                let (ci, cj) = (cell(boxes[i].0), cell(boxes[j].0));
                let first = [0, 1, 2].map(|d| ci[d].max(cj[d]));
                if (first[0] * dims[1] + first[1]) * dims[2] + first[2] != c {
                    continue;
                }
                if faces_intersect(positions, faces[i], faces[j]) {
                    found.push([i.min(j) as u32, i.max(j) as u32]);
                }
            }
        }
        g = e;
    }
    found.sort_unstable();
    out.pairs = found.len() as u64;
    out.examples = found.into_iter().take(max_examples).collect();
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every pair, tested directly: the reference for the broad phase.
    fn brute(pos: &[P], faces: &[[u32; 3]]) -> u64 {
        let live: Vec<bool> = faces.iter().map(|f| !degenerate(&f.map(|i| pos[i as usize]))).collect();
        let mut n = 0;
        for i in 0..faces.len() {
            for j in i + 1..faces.len() {
                if live[i] && live[j] && faces_intersect(pos, faces[i], faces[j]) {
                    n += 1;
                }
            }
        }
        n
    }

    fn tetra(o: P, s: f64) -> (Vec<P>, Vec<[u32; 3]>) {
        let p = vec![o, [o[0] + s, o[1], o[2]], [o[0], o[1] + s, o[2]], [o[0], o[1], o[2] + s]];
        (p, vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    }

    fn join(a: (Vec<P>, Vec<[u32; 3]>), b: (Vec<P>, Vec<[u32; 3]>)) -> (Vec<P>, Vec<[u32; 3]>) {
        let off = a.0.len() as u32;
        let mut p = a.0;
        p.extend(b.0);
        let mut f = a.1;
        f.extend(b.1.iter().map(|t| t.map(|i| i + off)));
        (p, f)
    }

    #[test]
    fn a_closed_mesh_has_none_and_planted_crossings_are_found() {
        let (p, f) = tetra([0.0; 3], 1.0);
        assert_eq!(self_intersections(&p, &f, 10).pairs, 0, "adjacent faces meet only along what they share");
        // Two interpenetrating tetrahedra: their faces cross.
        let (p, f) = join(tetra([0.0; 3], 1.0), tetra([0.2, 0.2, 0.2], 1.0));
        let r = self_intersections(&p, &f, 10);
        assert!(r.pairs > 0);
        assert_eq!(r.pairs, brute(&p, &f));
        // Far apart: none.
        let (p, f) = join(tetra([0.0; 3], 1.0), tetra([5.0, 0.0, 0.0], 1.0));
        assert_eq!(self_intersections(&p, &f, 10).pairs, 0);
    }

    #[test]
    fn shared_features_count_only_when_they_overlap_beyond() {
        // Two coplanar triangles sharing edge 0-1: on opposite sides (a flat
        // strip), then folded onto the same side.
        let p = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, 1.0, 0.0], [0.5, -1.0, 0.0], [0.3, 0.5, 0.0]];
        assert!(!faces_intersect(&p, [0, 1, 2], [1, 0, 3]));
        assert!(faces_intersect(&p, [0, 1, 2], [1, 0, 4]));
        // Sharing one vertex, coplanar: adjacent sectors do not overlap, nested ones do.
        let q = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0], [2.0, 0.5, 0.0], [0.9, 0.4, 0.0]];
        assert!(!faces_intersect(&q, [0, 1, 2], [0, 2, 3]));
        assert!(faces_intersect(&q, [0, 1, 2], [0, 4, 5]));
        // Sharing one vertex, a fan folded through the other face.
        let r = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.3, 0.3, -1.0], [0.3, 0.3, 1.0]];
        assert!(faces_intersect(&r, [0, 1, 2], [0, 3, 4]));
    }

    #[test]
    fn the_broad_phase_agrees_with_every_pair_on_random_lattice_soups() {
        let mut s = 12345u64;
        let mut next = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (s >> 33) as u32
        };
        for round in 0..60 {
            // Points on a small lattice, where coincidences are the rule.
            let np = 8 + (round % 12);
            let pos: Vec<P> = (0..np).map(|_| [0, 1, 2].map(|_| (next() % 5) as f64 * 0.5)).collect();
            let faces: Vec<[u32; 3]> = (0..(10 + round % 25))
                .map(|_| loop {
                    let t = [next() % np as u32, next() % np as u32, next() % np as u32];
                    if t[0] != t[1] && t[1] != t[2] && t[0] != t[2] {
                        break t;
                    }
                })
                .collect();
            let got = self_intersections(&pos, &faces, 0).pairs;
            assert_eq!(got, brute(&pos, &faces), "round {round}");
        }
    }
}
