//! Planar geometry shared by the contour algorithms: exact orientation
//! ([`orient`], Shewchuk's adaptive predicate from the `robust` crate),
//! polygon area and centroid, even-odd point-in-polygon, exact closed-segment
//! intersection, and [`first_crossing`], a sort-and-sweep search for two
//! edges of a set of closed polygons that touch where they should not.
//!
//! Points are `[f64; 2]`. Every topological answer (does this edge cross
//! that one, is this point inside) is a sign of an exact predicate on the
//! given f64 values; floating-point arithmetic is used only for measures
//! (areas, angles, distances) that never decide topology.
//!
//! Non-goal: NaN or infinite coordinates (the profile reader refuses them).

use robust::{orient2d, Coord};

/// A point of the plane.
pub type P2 = [f64; 2];

/// Twice the signed area of triangle `abc`, exactly signed: positive when
/// `a, b, c` turn counter-clockwise, zero when collinear.
#[inline]
pub fn orient(a: P2, b: P2, c: P2) -> f64 {
    orient2d(Coord { x: a[0], y: a[1] }, Coord { x: b[0], y: b[1] }, Coord { x: c[0], y: c[1] })
}

/// Signed area of a closed polygon (shoelace; counter-clockwise positive).
pub fn signed_area(poly: &[P2]) -> f64 {
    let n = poly.len();
    let mut s = 0.0;
    for i in 0..n {
        let (p, q) = (poly[i], poly[(i + 1) % n]);
        s += (p[0] - q[0]) * (p[1] + q[1]);
    }
    0.5 * s
}

/// Area centroid of a closed polygon; the vertex average if the area is 0.
pub fn centroid(poly: &[P2]) -> P2 {
    let n = poly.len();
    let o = poly[0];
    let (mut a, mut cx, mut cy) = (0.0, 0.0, 0.0);
    for i in 0..n {
        let p = [poly[i][0] - o[0], poly[i][1] - o[1]];
        let q = [poly[(i + 1) % n][0] - o[0], poly[(i + 1) % n][1] - o[1]];
        let w = p[0] * q[1] - q[0] * p[1];
        a += w;
        cx += (p[0] + q[0]) * w;
        cy += (p[1] + q[1]) * w;
    }
    if a.abs() > 0.0 && (cx / (3.0 * a)).is_finite() {
        [o[0] + cx / (3.0 * a), o[1] + cy / (3.0 * a)]
    } else {
        let s = poly.iter().fold([0.0, 0.0], |s, p| [s[0] + p[0], s[1] + p[1]]);
        [s[0] / n as f64, s[1] / n as f64]
    }
}

/// Even-odd point-in-polygon for `q` against a closed polygon, with the
/// symbolic tie-break of `q` moved by `(ε, ε²)`: a point on an edge or a
/// vertex is decided consistently (inside exactly one of two polygons that
/// share the edge), never "on".
pub fn inside(poly: &[P2], q: P2) -> bool {
    let n = poly.len();
    let mut odd = false;
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        // Horizontal line y = q.y + ε²: a vertex is above iff its y > q.y.
        let (au, bu) = (a[1] > q[1], b[1] > q[1]);
        if au == bu {
            continue;
        }
        let (lo, hi) = if au { (b, a) } else { (a, b) };
        // The crossing lies left of q + ε (counted) iff q is not left of the
        // upward edge lo→hi: orient ≤ 0 (on the line, the ε in x decides).
        if orient(lo, hi, q) <= 0.0 {
            odd = !odd;
        }
    }
    odd
}

#[inline]
fn on_segment(a: P2, b: P2, p: P2) -> bool {
    // p is collinear with ab: inside the closed box of ab.
    p[0] >= a[0].min(b[0]) && p[0] <= a[0].max(b[0]) && p[1] >= a[1].min(b[1]) && p[1] <= a[1].max(b[1])
}

/// True if the closed segments `ab` and `cd` share a point (exact).
pub fn segments_touch(a: P2, b: P2, c: P2, d: P2) -> bool {
    let d1 = orient(c, d, a);
    let d2 = orient(c, d, b);
    let d3 = orient(a, b, c);
    let d4 = orient(a, b, d);
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0)) && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0)) {
        return true;
    }
    (d1 == 0.0 && on_segment(c, d, a))
        || (d2 == 0.0 && on_segment(c, d, b))
        || (d3 == 0.0 && on_segment(a, b, c))
        || (d4 == 0.0 && on_segment(a, b, d))
}

/// True if the open interiors of segments `ab` and `cd` cross at one point
/// (a proper crossing; touching at endpoints or collinear overlap excluded).
pub fn segments_cross_properly(a: P2, b: P2, c: P2, d: P2) -> bool {
    let d1 = orient(c, d, a);
    let d2 = orient(c, d, b);
    let d3 = orient(a, b, c);
    let d4 = orient(a, b, d);
    ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0)) && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
}

/// Where two polygons' edges touch: `(polygon, edge)` of each (edge `e` runs
/// from vertex `e` to `e + 1`, cyclically).
pub type EdgeRef = (usize, usize);

/// Finds two edges of the closed polygons `polys` that share a point though
/// they should not: any two edges except consecutive edges of one polygon,
/// which may share only their common vertex (a consecutive pair that folds
/// back onto itself counts as touching). Polygons need at least 3 vertices
/// and no two equal consecutive vertices. Returns `None` when every polygon
/// is simple and no two polygons touch.
///
/// Sort-and-sweep on the edges' x-extents, then an exact test per pair whose
/// boxes overlap: O(n log n + k) for n edges and k overlapping boxes.
pub fn first_crossing(polys: &[&[P2]]) -> Option<(EdgeRef, EdgeRef)> {
    struct E {
        x0: f64,
        x1: f64,
        y0: f64,
        y1: f64,
        poly: usize,
        edge: usize,
    }
    let mut edges: Vec<E> = Vec::with_capacity(polys.iter().map(|p| p.len()).sum());
    for (pi, p) in polys.iter().enumerate() {
        let n = p.len();
        for e in 0..n {
            let (a, b) = (p[e], p[(e + 1) % n]);
            edges.push(E { x0: a[0].min(b[0]), x1: a[0].max(b[0]), y0: a[1].min(b[1]), y1: a[1].max(b[1]), poly: pi, edge: e });
        }
    }
    edges.sort_by(|a, b| a.x0.total_cmp(&b.x0));
    let seg = |e: &E| {
        let p = polys[e.poly];
        (p[e.edge], p[(e.edge + 1) % p.len()])
    };
    let mut active: Vec<usize> = Vec::new();
    for i in 0..edges.len() {
        let ei = &edges[i];
        active.retain(|&j| edges[j].x1 >= ei.x0);
        for &j in &active {
            let ej = &edges[j];
            if ej.y1 < ei.y0 || ei.y1 < ej.y0 {
                continue;
            }
            let (a, b) = seg(ei);
            let (c, d) = seg(ej);
            if ei.poly == ej.poly {
                let n = polys[ei.poly].len();
                let (lo, hi) = (ei.edge.min(ej.edge), ei.edge.max(ej.edge));
                let consecutive = hi == lo + 1 || (lo == 0 && hi == n - 1);
                if consecutive {
                    // Shared vertex s, other ends u (of the first edge) and w.
                    let (first, second) = if hi == lo + 1 { (lo, hi) } else { (hi, lo) };
                    let p = polys[ei.poly];
                    let u = p[first];
                    let s = p[second];
                    let w = p[(second + 1) % n];
                    // They overlap beyond s only if they fold back: collinear
                    // and pointing the same way from s.
                    if n == 3 {
                        if orient(u, s, w) == 0.0 {
                            return Some(((ei.poly, ei.edge), (ej.poly, ej.edge)));
                        }
                        continue;
                    }
                    let du = [u[0] - s[0], u[1] - s[1]];
                    let dw = [w[0] - s[0], w[1] - s[1]];
                    if orient(u, s, w) == 0.0 && du[0] * dw[0] + du[1] * dw[1] > 0.0 {
                        return Some(((ei.poly, ei.edge), (ej.poly, ej.edge)));
                    }
                    continue;
                }
            }
            if segments_touch(a, b, c, d) {
                let (x, y) = ((ei.poly, ei.edge), (ej.poly, ej.edge));
                return Some(if x < y { (x, y) } else { (y, x) });
            }
        }
        active.push(i);
    }
    None
}

/// Interior angle at `b` of a counter-clockwise polygon turning `a → b → c`,
/// in `(0, 2π)`: below π at convex vertices, π on straight runs.
#[inline]
pub fn inner_angle(a: P2, b: P2, c: P2) -> f64 {
    let u = [c[0] - b[0], c[1] - b[1]];
    let v = [a[0] - b[0], a[1] - b[1]];
    let cross = u[0] * v[1] - u[1] * v[0];
    let dot = u[0] * v[0] + u[1] * v[1];
    let t = cross.atan2(dot);
    if t < 0.0 {
        t + std::f64::consts::TAU
    } else {
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn area_centroid_and_inside_of_a_square() {
        let sq = [[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]];
        assert_eq!(signed_area(&sq), 4.0);
        assert_eq!(centroid(&sq), [1.0, 1.0]);
        assert!(inside(&sq, [1.0, 1.0]));
        assert!(!inside(&sq, [3.0, 1.0]));
        // On the boundary: the tie-break moves the point right and up, so the
        // left and bottom edges are inside and the right and top edges not.
        assert!(inside(&sq, [0.0, 1.0]));
        assert!(inside(&sq, [1.0, 0.0]));
        assert!(!inside(&sq, [2.0, 1.0]));
        assert!(!inside(&sq, [1.0, 2.0]));
        assert!(inside(&sq, [0.0, 0.0]));
        assert!(!inside(&sq, [2.0, 2.0]));
    }

    #[test]
    fn a_shared_edge_point_is_inside_exactly_one_of_two_squares() {
        let l = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        let r = [[1.0, 0.0], [2.0, 0.0], [2.0, 1.0], [1.0, 1.0]];
        for q in [[1.0, 0.5], [1.0, 0.0], [1.0, 1.0], [0.5, 1.0], [1.5, 0.0]] {
            assert!(!(inside(&l, q) && inside(&r, q)), "{q:?}");
        }
        assert_eq!(inside(&l, [1.0, 0.5]) as u8 + inside(&r, [1.0, 0.5]) as u8, 1);
    }

    #[test]
    fn crossings_are_found_and_simple_polygons_pass() {
        let sq: Vec<P2> = vec![[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]];
        let bow: Vec<P2> = vec![[0.0, 0.0], [2.0, 2.0], [2.0, 0.0], [0.0, 2.0]];
        let inner: Vec<P2> = vec![[0.5, 0.5], [1.5, 0.5], [1.0, 1.5]];
        let touching: Vec<P2> = vec![[2.0, 1.0], [3.0, 0.0], [3.0, 2.0]];
        let collinear: Vec<P2> = vec![[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [2.0, 2.0]];
        let spike: Vec<P2> = vec![[0.0, 0.0], [2.0, 0.0], [1.0, 0.0], [1.0, 2.0]];
        assert_eq!(first_crossing(&[&sq]), None);
        assert_eq!(first_crossing(&[&sq, &inner]), None);
        assert_eq!(first_crossing(&[&collinear]), None);
        assert_eq!(first_crossing(&[&bow]), Some(((0, 0), (0, 2))));
        assert!(first_crossing(&[&sq, &touching]).is_some());
        assert!(first_crossing(&[&spike]).is_some());
        assert!(first_crossing(&[&[[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]]]).is_some());
    }

    #[test]
    fn proper_crossing_and_touching_differ() {
        let (a, b) = ([0.0, 0.0], [2.0, 0.0]);
        assert!(segments_cross_properly(a, b, [1.0, -1.0], [1.0, 1.0]));
        assert!(!segments_cross_properly(a, b, [1.0, 0.0], [1.0, 1.0]));
        assert!(segments_touch(a, b, [1.0, 0.0], [1.0, 1.0]));
        assert!(segments_touch(a, b, [2.0, 0.0], [3.0, 0.0]));
        assert!(!segments_touch(a, b, [2.5, 0.0], [3.0, 0.0]));
        // A left turn is convex in a counter-clockwise polygon, a right turn reflex.
        assert!((inner_angle([0.0, 1.0], [0.0, 0.0], [1.0, 0.0]) - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
        assert!((inner_angle([1.0, 0.0], [0.0, 0.0], [0.0, 1.0]) - 1.5 * std::f64::consts::PI).abs() < 1e-15);
    }
}
