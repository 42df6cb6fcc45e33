//! Discretization: the signed intersections of one triangle with the three
//! families of grid lines (Rocchini et al. 2001, §2.1, "scan conversion").
//!
//! Family `d` holds the lines parallel to local axis `d`; a line is named by
//! its integer coordinates `(u, v)` on the two other axes, taken in cyclic
//! order `u = d+1, v = d+2`, so that the projected triangle's orientation in
//! `(u, v)` is the sign of the normal's component `n_d`.
//!
//! For each family the triangle is projected on the `(u, v)` plane; every
//! lattice point inside the projection (decided by [`edge_side`], exact, with
//! the grid's symbolic tie-break) is one [`Crossing`]. Its *cell* along the
//! line — between which two nodes the surface passes — is decided by exact
//! plane-side tests at those nodes ([`plane_side`]), so all three families
//! agree on every node. Its *value* is the f64 position along the line,
//! clamped [`MARGIN`] inside the cell so that no output vertex sits on a node
//! and no output face has zero area. The sign is *entering* when the line,
//! walking towards +d, passes from outside to inside: `n_d < 0` for a
//! triangle that faces outward.
//!
//! Contract: vertex coordinates are finite local grid coordinates.
//! A triangle whose projection on a family's plane has zero area produces no
//! crossing on that family (the perturbed lines miss it); its neighbours carry
//! the crossings.

use crate::intercept::{Intercept, FAMILY_A, FAMILY_B, FAMILY_S};
use crate::predicates::{edge_side, normal_signs, plane_side};

/// How far inside its cell edge a crossing value is kept, in cells.
/// A value closer than this to a grid node is moved to this distance.
pub const MARGIN: f64 = 1.0 / 1024.0;

/// One signed intersection of a triangle with a grid line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Crossing {
    /// The family: the local axis the line is parallel to (0, 1 or 2).
    pub family: u8,
    /// The line's integer coordinate on axis `family + 1 (mod 3)`.
    pub u: i64,
    /// The line's integer coordinate on axis `family + 2 (mod 3)`.
    pub v: i64,
    /// The cell along the line: the crossing lies between nodes `cell` and `cell + 1`.
    pub cell: i64,
    /// The position along the line, in `[cell + MARGIN, cell + 1 - MARGIN]`.
    pub value: f64,
    /// True when the line enters the solid here.
    pub entering: bool,
}

impl Crossing {
    /// Packs the crossing into its 16-byte record, on a grid with `nb`
    /// cells along local axis b (family-S lines are numbered `a * (nb + 1) + b`).
    #[inline]
    pub fn intercept(&self, nb: u32) -> Intercept {
        match self.family as u32 {
            FAMILY_A => Intercept::new(self.v as u32, FAMILY_A, self.u as u32, self.value, self.entering),
            FAMILY_B => Intercept::new(self.u as u32, FAMILY_B, self.v as u32, self.value, self.entering),
            _ => Intercept::new(self.cell as u32, FAMILY_S, self.u as u32 * (nb + 1) + self.v as u32, self.value, self.entering),
        }
    }
}

/// Reports every crossing of triangle `p` (local grid coordinates) with the
/// grid lines, calling `emit` once per crossing.
///
/// Order of emission: family 0, 1, 2; within a family, by `v` then `u`.
#[inline(always)]
pub fn discretize_triangle(p: &[[f64; 3]; 3], emit: impl FnMut(Crossing)) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for q in p {
        for d in 0..3 {
            lo[d] = lo[d].min(q[d]);
            hi[d] = hi[d].max(q[d]);
        }
    }
    // Candidate integer range per axis for a perturbed lattice coordinate
    // q + δ inside [lo, hi]: q in [ceil(lo), ceil(hi) - 1].
    let first = [ceil(lo[0]), ceil(lo[1]), ceil(lo[2])];
    // first <= ceil(hi) - 1 is first < hi, first being an integer: one
    // rounding per axis instead of two on the common path.
    let has = [first[0] < hi[0], first[1] < hi[1], first[2] < hi[2]];
    // Fast reject: no family has a lattice point in its projected box.
    if !((has[1] && has[2]) || (has[2] && has[0]) || (has[0] && has[1])) {
        return;
    }
    // Callers pass finite corners (files are checked as they are read);
    // should one not be, the triangle crosses nothing, rather than walking
    // an unbounded range of lines or clamping to NaN.
    if !p.iter().flatten().all(|c| c.is_finite()) {
        return;
    }
    let last = [ceil(hi[0]) - 1.0, ceil(hi[1]) - 1.0, ceil(hi[2]) - 1.0];
    debug_assert_eq!(has, [first[0] <= last[0], first[1] <= last[1], first[2] <= last[2]]);
    crossings(p, lo, hi, first, last, has, emit);
}

/// The lines a triangle's bounding box holds: exact tests per line. Kept
/// out of line so that the common case above (no line inside the box: most
/// triangles of a fine mesh on a coarser grid) inlines into callers' loops.
#[inline(never)]
fn crossings(p: &[[f64; 3]; 3], lo: [f64; 3], hi: [f64; 3], first: [f64; 3], last: [f64; 3], has: [bool; 3], mut emit: impl FnMut(Crossing)) {
    let signs = normal_signs(p);
    for d in 0..3 {
        let (u, v) = ((d + 1) % 3, (d + 2) % 3);
        if !(has[u] && has[v]) || signs[d] == 0 {
            continue;
        }
        let orient = signs[d];
        let a = [p[0][u], p[0][v]];
        let b = [p[1][u], p[1][v]];
        let c = [p[2][u], p[2][v]];
        let qv0 = first[v] as i64;
        let qv1 = last[v] as i64;
        let qu0 = first[u] as i64;
        let qu1 = last[u] as i64;
        for qv in qv0..=qv1 {
            for qu in qu0..=qu1 {
                let q = [qu as f64, qv as f64];
                if edge_side(a, b, q, u, v) != orient
                    || edge_side(b, c, q, u, v) != orient
                    || edge_side(c, a, q, u, v) != orient
                {
                    continue;
                }
                let (cell, value) = locate_along_line(p, signs, d, u, v, q, lo[d], hi[d]);
                emit(Crossing { family: d as u8, u: qu, v: qv, cell, value, entering: orient < 0 });
            }
        }
    }
}

/// `x.ceil()` for grid coordinates (|x| < 2^62), without the libm call
/// that `f64::ceil` compiles to on baseline x86-64.
#[inline(always)]
fn ceil(x: f64) -> f64 {
    let t = x as i64 as f64;
    if t < x {
        t + 1.0
    } else {
        t
    }
}

/// Finds the cell along line `(u, v) = q` of family `d` where the triangle's
/// plane crosses it, exactly, and a clamped f64 value inside that cell.
#[inline]
#[allow(clippy::too_many_arguments)]
fn locate_along_line(
    p: &[[f64; 3]; 3],
    signs: [i32; 3],
    d: usize,
    u: usize,
    v: usize,
    q: [f64; 2],
    lo: f64,
    hi: f64,
) -> (i64, f64) {
    // Approximate position from the plane equation n·(x - p0) = 0.
    let e1 = [p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]];
    let e2 = [p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]];
    let n = [
        e1[1] * e2[2] - e1[2] * e2[1],
        e1[2] * e2[0] - e1[0] * e2[2],
        e1[0] * e2[1] - e1[1] * e2[0],
    ];
    let mut t = p[0][d] - (n[u] * (q[0] - p[0][u]) + n[v] * (q[1] - p[0][v])) / n[d];
    if !t.is_finite() {
        t = 0.5 * (lo + hi);
    }
    t = t.clamp(lo, hi);
    // Node k is *below* the crossing when the plane function at the perturbed
    // node has the sign opposite to n_d (the function grows along +d at rate n_d).
    let below = -signs[d];
    let node = |k: f64| -> [f64; 3] {
        let mut x = [0.0; 3];
        x[d] = k;
        x[u] = q[0];
        x[v] = q[1];
        x
    };
    let mut cell = -ceil(-t); // floor
    // Walk to the cell whose lower node is below and upper node is above.
    // The crossing lies within [lo, hi] and the estimate is within a cell
    // or two of it, so this ends within a few steps.
    let mut found = false;
    for _ in 0..WALK_STEPS {
        if plane_side(p, signs, node(cell)) != below {
            cell -= 1.0;
            continue;
        }
        if plane_side(p, signs, node(cell + 1.0)) == below {
            cell += 1.0;
            continue;
        }
        found = true;
        break;
    }
    if !found {
        cell = bisect_crossing(|k| plane_side(p, signs, node(k)) == below, lo, hi, t);
    }
    let value = t.clamp(cell + MARGIN, cell + 1.0 - MARGIN);
    (cell as i64, value)
}

/// Steps of the walk from the estimate before [`bisect_crossing`] takes over
/// (the estimate is rarely more than one cell off; a plane almost parallel
/// to the line may put it farther).
const WALK_STEPS: u32 = 16;

/// The cell `k` with `below(k)` and `!below(k + 1)` in `[floor(lo) - 1,
/// ceil(hi)]`, by bisection on the monotone `below` (the plane function is
/// linear along the line): at most about 64 steps on any finite input. If
/// `below` is not monotone there (it is for the exact predicates on finite
/// grid coordinates within [`crate::grid::MAX_COORDINATE_CELLS`]), the
/// estimate `t`'s cell clamped to `[lo, hi]`, deterministically.
#[cold]
#[inline(never)]
fn bisect_crossing(below: impl Fn(f64) -> bool, lo: f64, hi: f64, t: f64) -> f64 {
    let fallback = (-ceil(-t)).clamp(-ceil(-lo), (ceil(hi) - 1.0).max(-ceil(-lo)));
    let (mut a, mut b) = (-ceil(-lo) - 1.0, ceil(hi));
    if !(below(a) && !below(b)) {
        return fallback;
    }
    // Invariant: below(a), !below(b), a < b.
    while b - a > 1.0 {
        let mid = -ceil(-(0.5 * a + 0.5 * b));
        if !(a < mid && mid < b) {
            return fallback; // coordinates too large for unit steps
        }
        if below(mid) {
            a = mid;
        } else {
            b = mid;
        }
    }
    a
}

#[cfg(test)]
mod tests {
    use super::*;

    fn collect(p: [[f64; 3]; 3]) -> Vec<Crossing> {
        let mut out = Vec::new();
        discretize_triangle(&p, |c| out.push(c));
        out
    }

    /// The search along a line terminates on any finite input: the walk
    /// gives way to bisection, and bisection to a deterministic clamp when
    /// the coordinates are too large for unit steps (it used to loop
    /// forever on grid coordinates of 1e293).
    #[test]
    fn the_search_along_a_line_always_terminates() {
        assert_eq!(bisect_crossing(|k| k < 1000.5, 0.0, 2000.0, 3.0), 1000.0);
        assert_eq!(bisect_crossing(|k| k < -7.5, -9.0, 2000.0, 3.0), -8.0);
        // Not monotone as asked (never below): the estimate's cell, clamped.
        assert_eq!(bisect_crossing(|_| false, 0.0, 20.0, 30.0), 19.0);
        assert_eq!(bisect_crossing(|k| k < 1e30, 0.0, 1e300, 5.0), 5.0);
        // A triangle far beyond the grid's range of exact unit steps.
        let y = 1e293;
        let t = [[0.5, y, 0.5], [3.5, y, 0.2], [0.2, y * (1.0 + f64::EPSILON), 3.5]];
        let c = collect(t);
        assert!(c.iter().all(|c| c.value.is_finite()));
        // A very slanted triangle, whose estimate may be far from the crossing:
        // the exact cell is still found.
        let t = [[0.5, 0.5, 0.0], [1.5, 0.5, 1e6], [0.5, 1.5, 1e6 + 1e-3]];
        for c in collect(t) {
            assert!(c.value >= c.cell as f64 && c.value <= c.cell as f64 + 1.0);
        }
    }

    /// A triangle with a NaN or infinite corner crosses nothing, wherever
    /// the bad value is, and does not panic or loop (it used to panic in
    /// `clamp` on NaN).
    #[test]
    fn a_triangle_with_a_non_finite_corner_crosses_nothing() {
        let good = [[0.5, 0.5, 0.2], [3.5, 0.7, 0.4], [0.6, 3.5, 2.5]];
        assert!(!collect(good).is_empty());
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            for k in 0..3 {
                for d in 0..3 {
                    let mut t = good;
                    t[k][d] = bad;
                    assert!(collect(t).is_empty(), "{bad} at corner {k}, axis {d}");
                }
            }
        }
    }

    #[test]
    fn a_small_triangle_between_lines_has_no_crossings() {
        let t = [[0.1, 0.1, 0.1], [0.4, 0.1, 0.2], [0.1, 0.4, 0.3]];
        assert!(collect(t).is_empty());
    }

    #[test]
    fn a_horizontal_triangle_crosses_vertical_lines_with_its_orientation() {
        // Facing +z (counter-clockwise seen from above): lines along z leave the solid.
        let t = [[0.5, 0.5, 2.25], [3.5, 0.5, 2.25], [0.5, 3.5, 2.25]];
        let c = collect(t);
        // Lattice points strictly inside (1..3, 1..3) with u + v < 4 in the projection.
        assert!(c.iter().all(|x| x.family == 2 && !x.entering && x.cell == 2));
        assert!(c.iter().all(|x| (x.value - 2.25).abs() < 1e-12));
        let pts: Vec<(i64, i64)> = c.iter().map(|x| (x.u, x.v)).collect();
        assert_eq!(pts, vec![(1, 1), (2, 1), (1, 2)]);
    }

    #[test]
    fn a_plane_through_nodes_is_put_on_one_side_consistently() {
        // The plane z = 2 through nodes: with ε³ > 0 the perturbed nodes at
        // z = 2 are above a triangle facing +z, so the crossing is in cell 1.
        let up = [[0.5, 0.5, 2.0], [3.5, 0.5, 2.0], [0.5, 3.5, 2.0]];
        assert!(collect(up).iter().all(|x| x.cell == 1 && (x.value - (2.0 - MARGIN)).abs() < 1e-15));
        // Facing -z: the perturbation is a translation, so the node is still
        // above the plane and the crossing stays in cell 1, now entering.
        let down = [up[0], up[2], up[1]];
        let c = collect(down);
        assert_eq!(c.len(), 3);
        assert!(c.iter().all(|x| x.cell == 1 && x.entering));
    }

    #[test]
    fn two_triangles_sharing_a_diagonal_through_lattice_points_count_each_point_once() {
        // A unit-grid square [0,4]² at z = 1.5 split along its diagonal, which
        // passes through lattice points (1,1), (2,2), (3,3).
        let a = [0.0, 0.0, 1.5];
        let b = [4.0, 0.0, 1.5];
        let c = [4.0, 4.0, 1.5];
        let d = [0.0, 4.0, 1.5];
        let mut hits = std::collections::BTreeMap::new();
        for t in [[a, b, c], [a, c, d]] {
            for x in collect(t) {
                *hits.entry((x.family, x.u, x.v)).or_insert(0) += 1;
            }
        }
        // Lattice points with perturbed coordinates inside [0,4)²: 0..=3 on each axis.
        assert_eq!(hits.len(), 16);
        assert!(hits.values().all(|&n| n == 1));
    }
}
