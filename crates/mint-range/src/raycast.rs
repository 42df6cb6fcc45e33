//! [`RayBvh`]: a bounding-volume hierarchy over triangles for line
//! queries, which mint-mesh's nearest-point tree does not answer: the first
//! hit of a ray ([`RayBvh::first_hit`], for `mint scan`) and every hit on a
//! segment ([`RayBvh::segment_hits`], for consensus geometry, which
//! intersects a line along a vertex normal with each scan).
//!
//! Sources: ray–triangle intersection by Möller and Trumbore, "Fast,
//! minimum storage ray/triangle intersection", JGT 2(1), 1997 (two-sided);
//! ray–box by the slab method (Kay and Kajiya 1986). The tree is built by
//! median split on the longest axis of the centroid bounds, leaves of at
//! most 4 triangles, nodes in depth-first order; queries use an explicit
//! stack. Contract: finite coordinates; degenerate triangles are never hit.

use glam::DVec3;

const LEAF: usize = 4;

#[derive(Debug, Clone, Copy)]
struct Node {
    lo: [f64; 3],
    hi: [f64; 3],
    /// Leaf: first triangle (in `order`) and count > 0; inner: right child
    /// index and count 0 (the left child follows the node).
    first: u32,
    count: u32,
}

/// A ray-query tree over borrowed-then-copied triangles; see the module docs.
#[derive(Debug, Clone)]
pub struct RayBvh {
    tris: Vec<[DVec3; 3]>,
    ids: Vec<u32>,
    nodes: Vec<Node>,
}

/// One intersection: the parameter `t` along the query direction, the face
/// (index in the input face list) and the barycentric weights of the hit
/// point on that face's corners.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    pub t: f64,
    pub face: u32,
    pub bary: [f64; 3],
}

impl RayBvh {
    /// Builds the tree. An empty face list gives a tree that never hits.
    pub fn new(positions: &[[f64; 3]], faces: &[[u32; 3]]) -> RayBvh {
        let tris: Vec<[DVec3; 3]> = faces.iter().map(|f| f.map(|i| DVec3::from(positions[i as usize]))).collect();
        let mut ids: Vec<u32> = (0..faces.len() as u32).collect();
        let cent: Vec<DVec3> = tris.iter().map(|t| (t[0] + t[1] + t[2]) / 3.0).collect();
        let mut nodes = Vec::with_capacity(2 * faces.len() / LEAF + 1);
        if !tris.is_empty() {
            build(&tris, &cent, &mut ids, 0, &mut nodes);
        }
        let tris = ids.iter().map(|&i| tris[i as usize]).collect();
        RayBvh { tris, ids, nodes }
    }

    /// Calls `f` for every hit with `t` in `[t0, t1]` of the line
    /// `o + t·d` (in no particular order).
    pub fn segment_hits(&self, o: DVec3, d: DVec3, t0: f64, t1: f64, mut f: impl FnMut(Hit)) {
        self.walk(o, d, t0, t1, |h| {
            f(h);
            t1
        });
    }

    /// The hit with the smallest `t` in `[t0, t1]`, if any.
    pub fn first_hit(&self, o: DVec3, d: DVec3, t0: f64, t1: f64) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        self.walk(o, d, t0, t1, |h| {
            if best.is_none_or(|b| h.t < b.t) {
                best = Some(h);
            }
            best.map_or(t1, |b| b.t)
        });
        best
    }

    /// Visits the hits with `t` in `[t0, t1]`, where `visit` returns the
    /// new upper end of the interval (the nodes beyond it are skipped).
    fn walk(&self, o: DVec3, d: DVec3, t0: f64, mut t1: f64, mut visit: impl FnMut(Hit) -> f64) {
        if self.nodes.is_empty() {
            return;
        }
        let inv = d.recip();
        let mut stack = [0u32; 64];
        let mut sp = 1;
        while sp > 0 {
            sp -= 1;
            let idx = stack[sp];
            let n = self.nodes[idx as usize];
            if !slab(&n, o, inv, t0, t1) {
                continue;
            }
            if n.count > 0 {
                for k in n.first..n.first + n.count {
                    if let Some((t, b)) = intersect(&self.tris[k as usize], o, d) {
                        if t >= t0 && t <= t1 {
                            t1 = visit(Hit { t, face: self.ids[k as usize], bary: b });
                        }
                    }
                }
            } else {
                // The left child is the node right after its parent.
                stack[sp] = n.first;
                stack[sp + 1] = idx + 1;
                sp += 2;
            }
        }
    }
}

fn build(tris: &[[DVec3; 3]], cent: &[DVec3], ids: &mut [u32], base: u32, nodes: &mut Vec<Node>) -> usize {
    let me = nodes.len();
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    let mut clo = [f64::INFINITY; 3];
    let mut chi = [f64::NEG_INFINITY; 3];
    for &i in ids.iter() {
        for p in &tris[i as usize] {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let c = cent[i as usize];
        for k in 0..3 {
            clo[k] = clo[k].min(c[k]);
            chi[k] = chi[k].max(c[k]);
        }
    }
    nodes.push(Node { lo, hi, first: base, count: ids.len() as u32 });
    if ids.len() <= LEAF {
        return me;
    }
    let axis = (0..3).max_by(|&a, &b| (chi[a] - clo[a]).total_cmp(&(chi[b] - clo[b]))).unwrap_or(0);
    let half = ids.len() / 2;
    ids.select_nth_unstable_by(half, |&a, &b| cent[a as usize][axis].total_cmp(&cent[b as usize][axis]).then(a.cmp(&b)));
    let (l, r) = ids.split_at_mut(half);
    build(tris, cent, l, base, nodes);
    let right = build(tris, cent, r, base + half as u32, nodes);
    nodes[me].first = right as u32;
    nodes[me].count = 0;
    me
}

#[inline]
fn slab(n: &Node, o: DVec3, inv: DVec3, t0: f64, t1: f64) -> bool {
    let (mut a, mut b) = (t0, t1);
    for k in 0..3 {
        let mut ta = (n.lo[k] - o[k]) * inv[k];
        let mut tb = (n.hi[k] - o[k]) * inv[k];
        if ta > tb {
            std::mem::swap(&mut ta, &mut tb);
        }
        // NaN (0 · ∞ when o is on the slab plane and d is parallel) keeps
        // the box: `max`/`min` ignore a NaN operand.
        a = a.max(ta);
        b = b.min(tb);
        if a > b {
            return false;
        }
    }
    true
}

/// Möller–Trumbore, two-sided: `(t, barycentrics)` or `None`.
#[inline]
pub fn intersect(t: &[DVec3; 3], o: DVec3, d: DVec3) -> Option<(f64, [f64; 3])> {
    let e1 = t[1] - t[0];
    let e2 = t[2] - t[0];
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = 1.0 / det;
    let s = o - t[0];
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = d.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    Some((e2.dot(q) * inv, [1.0 - u - v, u, v]))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(n: usize) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        let mut p = Vec::new();
        let mut f = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                p.push([i as f64, j as f64, 0.5 * i as f64]);
            }
        }
        let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        for j in 0..n {
            for i in 0..n {
                f.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                f.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        (p, f)
    }

    #[test]
    fn rays_hit_the_plane_where_it_is() {
        let (p, f) = grid(20);
        let b = RayBvh::new(&p, &f);
        for (x, y) in [(0.3, 0.7), (10.5, 3.25), (19.9, 19.9), (7.0, 7.0)] {
            let h = b.first_hit(DVec3::new(x, y, 100.0), DVec3::NEG_Z, 0.0, f64::INFINITY).unwrap();
            assert!((h.t - (100.0 - 0.5 * x)).abs() < 1e-9, "{x} {y}: {h:?}");
            let tri = f[h.face as usize];
            let q: [f64; 3] = [0, 1, 2].map(|k| (0..3).map(|c| h.bary[c] * p[tri[c] as usize][k]).sum());
            assert!((q[0] - x).abs() < 1e-9 && (q[1] - y).abs() < 1e-9);
        }
        assert!(b.first_hit(DVec3::new(-1.0, 5.0, 100.0), DVec3::NEG_Z, 0.0, f64::INFINITY).is_none());
        // Segment hits: a line through two stacked copies.
        let mut p2 = p.clone();
        p2.extend(p.iter().map(|q| [q[0], q[1], q[2] + 1.0]));
        let nv = p.len() as u32;
        let mut f2 = f.clone();
        f2.extend(f.iter().map(|t| t.map(|i| i + nv)));
        let b2 = RayBvh::new(&p2, &f2);
        let mut ts = Vec::new();
        b2.segment_hits(DVec3::new(4.5, 4.5, 2.25), DVec3::Z, -5.0, 5.0, |h| ts.push(h.t));
        ts.sort_by(f64::total_cmp);
        // A point on a shared diagonal can be reported by both triangles.
        ts.dedup_by(|a, b| (*a - *b).abs() < 1e-12);
        assert_eq!(ts.len(), 2);
        assert!((ts[0] - 0.0).abs() < 1e-9 && (ts[1] - 1.0).abs() < 1e-9);
    }
}
