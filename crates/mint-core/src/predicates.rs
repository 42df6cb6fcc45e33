//! Exact geometric predicates with one symbolic tie-break for the whole grid.
//!
//! Every topological decision of the resampler is a sign: is lattice point `q`
//! left of a projected triangle edge, is grid node `N` below or above a
//! triangle's plane. Both come from Shewchuk's adaptive exact predicates (the
//! `robust` crate), evaluated on the f64 grid coordinates of the input
//! vertices, so they are exact for the values they are given.
//!
//! Zero (a lattice point exactly on an edge, a node exactly on a plane) is
//! never returned. Ties are broken by *simulation of simplicity*: the grid is
//! translated by the infinitesimal vector `d = (ε, ε², ε³)` (axes 0, 1, 2 of
//! the local frame), with `ε` smaller than any positive quantity. Because the
//! whole grid moves together, a perturbed node lies on the three perturbed
//! lines through it, and the three line families agree on every node's
//! inside/outside state. A line through a vertex or edge shared by several
//! triangles crosses exactly one of them. This is the "top-left rule" of
//! rasterizers, derived rather than chosen.
//!
//! Contract: coordinates are finite. Non-goal: NaN (the reader rejects it).

use robust::{orient2d, orient3d, Coord, Coord3D};

/// The exponent of `ε` in the perturbation of local axis `axis` (0, 1, 2):
/// axis 0 moves by ε, axis 1 by ε², axis 2 by ε³, so lower axes dominate.
#[inline]
fn perturbation_rank(axis: usize) -> usize {
    axis
}

/// Sign (+1 or -1, never 0) of the 2D edge function `(b - a) × (q + δ - a)`,
/// where points are in the plane of local axes `(u, v)` and `q` is a lattice
/// point perturbed by `δ = (ε^(u+1), ε^(v+1))`.
///
/// Returns 0 only when `a == b` (a degenerate edge), which callers exclude by
/// skipping triangles whose projection has zero area.
#[inline]
pub fn edge_side(a: [f64; 2], b: [f64; 2], q: [f64; 2], u: usize, v: usize) -> i32 {
    let det = orient2d(
        Coord { x: a[0], y: a[1] },
        Coord { x: b[0], y: b[1] },
        Coord { x: q[0], y: q[1] },
    );
    if det > 0.0 {
        return 1;
    }
    if det < 0.0 {
        return -1;
    }
    // Exactly on the edge's line: the perturbation decides.
    // value = det + (b_u - a_u)·δv - (b_v - a_v)·δu
    let du = b[0] - a[0];
    let dv = b[1] - a[1];
    let (first, second) = if perturbation_rank(u) < perturbation_rank(v) {
        (-dv, du) // δu dominates
    } else {
        (du, -dv) // δv dominates
    };
    sign_of(first).or_else(|| sign_of(second)).unwrap_or(0)
}

#[inline]
fn sign_of(x: f64) -> Option<i32> {
    if x > 0.0 {
        Some(1)
    } else if x < 0.0 {
        Some(-1)
    } else {
        None
    }
}

/// Sign of the plane function `n · (x + d - p0)` for node `x`, where
/// `n = (p1 - p0) × (p2 - p0)` is the triangle's (unnormalized) normal and
/// `d = (ε, ε², ε³)` the grid's perturbation. Positive means the perturbed
/// node lies on the side the normal points to.
///
/// Returns 0 only for a triangle with zero normal (collinear vertices).
#[inline]
pub fn plane_side(p: &[[f64; 3]; 3], normal_signs: [i32; 3], x: [f64; 3]) -> i32 {
    let c = |q: [f64; 3]| Coord3D { x: q[0], y: q[1], z: q[2] };
    // robust::orient3d is positive when x lies *below* the plane through
    // p0, p1, p2, i.e. opposite to the normal (p1-p0)×(p2-p0).
    let det = -orient3d(c(p[0]), c(p[1]), c(p[2]), c(x));
    if det > 0.0 {
        1
    } else if det < 0.0 {
        -1
    } else {
        // On the plane: the first non-zero normal component decides,
        // because d's component along axis 0 dominates axis 1, then axis 2.
        normal_signs.into_iter().find(|&s| s != 0).unwrap_or(0)
    }
}

/// Exact signs of the three components of `(p1 - p0) × (p2 - p0)`: component
/// `d` is the orientation of the triangle projected along axis `d` onto the
/// plane of the cyclically next two axes `(d+1, d+2)`.
#[inline]
pub fn normal_signs(p: &[[f64; 3]; 3]) -> [i32; 3] {
    let mut s = [0; 3];
    for (d, sd) in s.iter_mut().enumerate() {
        let (u, v) = ((d + 1) % 3, (d + 2) % 3);
        let det = orient2d(
            Coord { x: p[0][u], y: p[0][v] },
            Coord { x: p[1][u], y: p[1][v] },
            Coord { x: p[2][u], y: p[2][v] },
        );
        *sd = if det > 0.0 {
            1
        } else if det < 0.0 {
            -1
        } else {
            0
        };
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    const TRI: [[f64; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

    #[test]
    fn plane_side_follows_the_normal() {
        let s = normal_signs(&TRI);
        assert_eq!(s, [0, 0, 1]);
        assert_eq!(plane_side(&TRI, s, [0.2, 0.2, 1.0]), 1);
        assert_eq!(plane_side(&TRI, s, [0.2, 0.2, -1.0]), -1);
        // On the plane: the normal has only a z component, ε³ > 0 puts the
        // perturbed node above.
        assert_eq!(plane_side(&TRI, s, [0.2, 0.2, 0.0]), 1);
        let flipped = [TRI[0], TRI[2], TRI[1]];
        let fs = normal_signs(&flipped);
        assert_eq!(plane_side(&flipped, fs, [5.0, 5.0, 0.0]), -1);
    }

    #[test]
    fn normal_sign_components_are_cyclic_projections() {
        // Triangle in the plane x = 0 facing +x.
        let t = [[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        assert_eq!(normal_signs(&t), [1, 0, 0]);
        // Facing +y: (z, x) orientation.
        let t = [[0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]];
        assert_eq!(normal_signs(&t), [0, 1, 0]);
    }

    #[test]
    fn a_point_on_a_shared_edge_belongs_to_exactly_one_side() {
        // Edge from (0,0) to (2,2) shared by two triangles; q=(1,1) is on it.
        let a = [0.0, 0.0];
        let b = [2.0, 2.0];
        let q = [1.0, 1.0];
        for (u, v) in [(0, 1), (1, 2), (2, 0)] {
            let s1 = edge_side(a, b, q, u, v);
            let s2 = edge_side(b, a, q, u, v);
            assert_ne!(s1, 0);
            assert_eq!(s1, -s2, "axes ({u},{v})");
        }
        // Axis-parallel edges too.
        for (a, b) in [([0.0, 1.0], [3.0, 1.0]), ([1.0, 0.0], [1.0, 3.0])] {
            let q = [1.0, 1.0];
            assert_eq!(edge_side(a, b, q, 0, 1), -edge_side(b, a, q, 0, 1));
            assert_ne!(edge_side(a, b, q, 0, 1), 0);
        }
    }

    #[test]
    fn a_point_at_a_shared_vertex_is_inside_exactly_one_triangle_of_a_fan() {
        // Fan of triangles around the origin in the (u,v) plane; the lattice
        // point at the centre must be inside exactly one of them.
        let ring: Vec<[f64; 2]> = vec![
            [2.0, 0.0],
            [1.0, 2.0],
            [-1.0, 1.0],
            [-2.0, -1.0],
            [0.0, -2.0],
            [1.0, -1.0],
        ];
        let c = [0.0, 0.0];
        for (u, v) in [(0, 1), (1, 2), (2, 0)] {
            let mut inside = 0;
            for i in 0..ring.len() {
                let a = ring[i];
                let b = ring[(i + 1) % ring.len()];
                let s = [edge_side(c, a, c, u, v), edge_side(a, b, c, u, v), edge_side(b, c, c, u, v)];
                if s.iter().all(|&x| x == 1) {
                    inside += 1;
                }
            }
            assert_eq!(inside, 1, "axes ({u},{v})");
        }
    }
}
