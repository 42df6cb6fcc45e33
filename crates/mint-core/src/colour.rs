//! Colour carried through resampling: the colour of a crossing, and the
//! colour of each output vertex.
//!
//! Every output vertex of Marching Intersections lies on one grid edge, at
//! (or at the mean of) the crossings of that edge's line with the input, so
//! its colour can be taken exactly there:
//! - [`crossing_colour`]: a crossing's colour is its triangle's colour at
//!   the crossing point, interpolated from the three corner colours by the
//!   barycentric coordinates of the line's position in the triangle's
//!   projection (exact for face colours: three equal corners);
//! - [`colour_vertices`]: a vertex whose edge holds crossings takes the
//!   colour of the crossing nearest to it on that edge (the one it was made
//!   from; overlapping layers merged into their mean take the nearest one's);
//!   a vertex *synthesized* where its edge holds none (hole caps, the back
//!   and rim of an open sheet) takes the colour of the crossing of its plane
//!   nearest to it in the plane (searched within [`SEARCH_RINGS`] rings of
//!   nodes; farther, the plane's mean colour; a plane without crossings
//!   gives [`NO_COLOUR`]), the in-plane stand-in for the input's nearest
//!   point.
//!
//! Both rules read only the raw records of the vertex's own plane, so the
//! colours, like the positions, do not depend on the slab partition, the
//! parts or the threads. Colours are 8-bit RGBA; files without colour
//! count as [`WHITE`].

use crate::discretize::Crossing;
use crate::grid::Grid;
use crate::intercept::{Intercept, FAMILY_A, FAMILY_B, FAMILY_S};
use std::collections::HashMap;

/// 8-bit red, green, blue, alpha.
pub type Rgba = [u8; 4];

/// The colour of a surface that has none.
pub const WHITE: Rgba = [255; 4];

/// A synthesized vertex's colour when its plane holds no crossing at all.
pub const NO_COLOUR: Rgba = [128, 128, 128, 255];

/// How many rings of in-plane nodes a synthesized vertex searches for the
/// nearest crossing before it takes its plane's mean colour.
pub const SEARCH_RINGS: u32 = 16;

/// One raw record with its colour; a plane of them sorted by
/// [`sort_coloured`] is what [`colour_vertices`] reads.
pub type Tinted = (Intercept, Rgba);

/// The colour of triangle `local` (grid coordinates) with corner colours
/// `corners` where crossing `c` meets it: barycentric in the projection on
/// the crossing's line family, each channel rounded to the nearest byte.
#[inline]
pub fn crossing_colour(local: &[[f64; 3]; 3], corners: &[Rgba; 3], c: &Crossing) -> Rgba {
    if corners[0] == corners[1] && corners[1] == corners[2] {
        return corners[0];
    }
    let w = barycentric(local, c);
    std::array::from_fn(|k| {
        let x = w[0] * corners[0][k] as f64 + w[1] * corners[1][k] as f64 + w[2] * corners[2][k] as f64;
        x.round().clamp(0.0, 255.0) as u8
    })
}

/// The line of a record as a crossing (family and lattice coordinates,
/// what [`barycentric`] needs; the inverse of [`Crossing::intercept`] on a
/// grid with `nb` cells along local axis b).
pub fn crossing_of(r: &Intercept, nb: u32) -> Crossing {
    let (family, u, v) = match r.family() {
        FAMILY_A => (0, r.index(), r.plane),
        FAMILY_B => (1, r.plane, r.index()),
        _ => (2, r.index() / (nb + 1), r.index() % (nb + 1)),
    };
    Crossing { family, u: u as i64, v: v as i64, cell: r.cell() as i64, value: r.value(), entering: r.entering() }
}

/// Barycentric weights of crossing `c`'s line in triangle `local`'s
/// projection along the line (clamped to the triangle: the line is inside
/// by the exact test, rounding may put it a hair outside).
pub fn barycentric(local: &[[f64; 3]; 3], c: &Crossing) -> [f64; 3] {
    let d = c.family as usize;
    let (u, v) = ((d + 1) % 3, (d + 2) % 3);
    let p = local.map(|x| [x[u], x[v]]);
    let q = [c.u as f64, c.v as f64];
    let cross = |a: [f64; 2], b: [f64; 2], o: [f64; 2]| (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
    let w = [cross(p[1], p[2], q), cross(p[2], p[0], q), cross(p[0], p[1], q)];
    let sum = w[0] + w[1] + w[2];
    if !sum.is_finite() || sum == 0.0 {
        return [1.0 / 3.0; 3];
    }
    let mut w = w.map(|x| (x / sum).max(0.0));
    let s = w[0] + w[1] + w[2];
    if s > 0.0 {
        w = w.map(|x| x / s);
    }
    w
}

/// Sorts one plane's raw coloured records into the order
/// [`colour_vertices`] searches: by [`Intercept::sort_key`], then colour,
/// a total order whatever the order they arrived in.
pub fn sort_coloured(records: &mut [Tinted]) {
    records.sort_unstable_by_key(|(r, c)| (r.sort_key(), u32::from_le_bytes(*c)));
}

/// Where an output vertex lies: its plane, line and the cell along it.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Edge {
    plane: u32,
    line: u32,
    cell: u32,
    value: f64,
    /// In-plane node coordinates (a, b) of the edge's lower end.
    node: [u32; 2],
    /// The vertex's in-plane position (a, b).
    at: [f64; 2],
}

/// The edge an output vertex (world position) lies on. Vertices sit a
/// margin inside their cell edge, so the axis of the edge is the local
/// coordinate farthest from an integer, and the two others round exactly.
fn edge_of(grid: &Grid, p: [f64; 3]) -> Option<Edge> {
    let l = grid.to_local(p);
    let off = l.map(|x| (x - x.round()).abs());
    let axis = if off[0] >= off[1] && off[0] >= off[2] { 0 } else if off[1] >= off[2] { 1 } else { 2 };
    let [_, nb, _] = grid.local_dims();
    let r = |x: f64| -> Option<u32> { (x >= -0.5 && x < u32::MAX as f64).then(|| x.round() as u32) };
    let value = l[axis];
    if !(value >= 0.0) {
        return None;
    }
    let cell = value as u32;
    Some(match axis {
        0 => {
            let (b, k) = (r(l[1])?, r(l[2])?);
            Edge { plane: k, line: (FAMILY_A << 30) | b, cell, value, node: [cell, b], at: [value, b as f64] }
        }
        1 => {
            let (a, k) = (r(l[0])?, r(l[2])?);
            Edge { plane: k, line: (FAMILY_B << 30) | a, cell, value, node: [a, cell], at: [a as f64, value] }
        }
        _ => {
            let (a, b) = (r(l[0])?, r(l[1])?);
            Edge { plane: cell, line: (FAMILY_S << 30) | (a * (nb + 1) + b), cell, value, node: [a, b], at: [a as f64, b as f64] }
        }
    })
}

/// In-plane node coordinates (a, b) of a record's cell edge.
fn node_of(r: &Intercept, nb: u32) -> [u32; 2] {
    match r.family() {
        FAMILY_A => [r.cell(), r.index()],
        FAMILY_B => [r.index(), r.cell()],
        _ => [r.index() / (nb + 1), r.index() % (nb + 1)],
    }
}

/// One plane's crossings by in-plane node, for synthesized vertices: each
/// with its in-plane position and colour, in sorted order.
struct PlaneColours {
    nodes: HashMap<[u32; 2], Vec<([f64; 2], Rgba)>>,
    mean: Option<Rgba>,
}

impl PlaneColours {
    fn new(records: &[Tinted], nb: u32) -> PlaneColours {
        let mut nodes: HashMap<[u32; 2], Vec<([f64; 2], Rgba)>> = HashMap::new();
        let (mut sum, mut n) = ([0u64; 4], 0u64);
        for (r, c) in records {
            nodes.entry(node_of(r, nb)).or_default().push((in_plane(r, nb), *c));
            for k in 0..4 {
                sum[k] += c[k] as u64;
            }
            n += 1;
        }
        PlaneColours { nodes, mean: (n > 0).then(|| mean(sum, n)) }
    }

    /// The colour of the crossing nearest to in-plane position `at` (node
    /// `node`): the rings of nodes around it are searched outwards until
    /// one holds a crossing, then as far again as a nearer one could lie.
    /// Ties go to the crossing first in sorted order.
    fn near(&self, node: [u32; 2], at: [f64; 2]) -> Rgba {
        let Some(fallback) = self.mean else { return NO_COLOUR };
        let (a, b) = (node[0] as i64, node[1] as i64);
        let mut best: Option<(f64, Rgba)> = None;
        let mut last = SEARCH_RINGS as i64;
        let mut ring = 0i64;
        while ring <= last {
            let mut take = |i: i64, j: i64| {
                if i < 0 || j < 0 || i > u32::MAX as i64 || j > u32::MAX as i64 {
                    return;
                }
                for (p, c) in self.nodes.get(&[i as u32, j as u32]).into_iter().flatten() {
                    let d = (p[0] - at[0]).powi(2) + (p[1] - at[1]).powi(2);
                    if best.is_none_or(|(bd, _)| d < bd) {
                        best = Some((d, *c));
                    }
                }
            };
            if ring == 0 {
                take(a, b);
            } else {
                for t in -ring..ring {
                    take(a + t, b - ring);
                    take(a + ring, b + t);
                    take(a - t, b + ring);
                    take(a - ring, b - t);
                }
            }
            if let Some((d, _)) = best {
                // A node of ring r holds crossings at least r - 1 away.
                last = last.min(d.sqrt().ceil() as i64 + 1);
            }
            ring += 1;
        }
        best.map_or(fallback, |(_, c)| c)
    }
}

/// A record's position in its plane's (a, b) coordinates.
fn in_plane(r: &Intercept, nb: u32) -> [f64; 2] {
    match r.family() {
        FAMILY_A => [r.value(), r.index() as f64],
        FAMILY_B => [r.index() as f64, r.value()],
        _ => [(r.index() / (nb + 1)) as f64, (r.index() % (nb + 1)) as f64],
    }
}

fn mean(sum: [u64; 4], n: u64) -> Rgba {
    sum.map(|s| ((s + n / 2) / n).min(255) as u8)
}

/// The colour of each output vertex of a slab whose owned planes are
/// `k0 .. k0 + planes.len()`; `planes[i]` holds plane `k0 + i`'s raw records
/// with their colours, sorted by [`sort_coloured`] (every operand's, for
/// booleans). See the module docs for the rules.
pub fn colour_vertices(grid: &Grid, k0: u32, vertices: &[[f64; 3]], planes: &[Vec<Tinted>]) -> Vec<Rgba> {
    let [_, nb, _] = grid.local_dims();
    let mut near: Vec<Option<PlaneColours>> = (0..planes.len()).map(|_| None).collect();
    vertices
        .iter()
        .map(|&p| {
            let Some(e) = edge_of(grid, p) else { return NO_COLOUR };
            let Some(i) = e.plane.checked_sub(k0).map(|i| i as usize).filter(|&i| i < planes.len()) else { return NO_COLOUR };
            let recs = &planes[i];
            let start = recs.partition_point(|(r, _)| r.line < e.line || (r.line == e.line && r.cell() < e.cell));
            let len = recs[start..].partition_point(|(r, _)| r.line == e.line && r.cell() == e.cell);
            let on_edge = &recs[start..start + len];
            if let Some(best) = on_edge.iter().min_by(|x, y| (x.0.value() - e.value).abs().total_cmp(&(y.0.value() - e.value).abs())) {
                return best.1;
            }
            near[i].get_or_insert_with(|| PlaneColours::new(recs, nb)).near(e.node, e.at)
        })
        .collect()
}

/// A mesh with one colour per vertex, the in-memory sink of coloured runs.
#[derive(Debug, Default, Clone, PartialEq)]
pub struct ColouredMesh {
    pub positions: Vec<[f64; 3]>,
    pub colours: Vec<Rgba>,
    pub faces: Vec<[u32; 3]>,
}

impl crate::sink::MeshSink for ColouredMesh {
    fn vertex(&mut self, p: [f64; 3]) -> Result<(), crate::sink::SinkError> {
        self.vertex_rgba(p, WHITE)
    }
    fn vertex_rgba(&mut self, p: [f64; 3], c: Rgba) -> Result<(), crate::sink::SinkError> {
        self.positions.push(p);
        self.colours.push(c);
        Ok(())
    }
    fn face(&mut self, f: [u32; 3]) -> Result<(), crate::sink::SinkError> {
        self.faces.push(f);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::discretize::discretize_triangle;
    use crate::grid::GridSize;

    #[test]
    fn a_crossing_takes_the_barycentric_colour_of_its_point() {
        // A triangle in the plane z = 0.3 over x, y in [0, 8]; family-2
        // lines (parallel to z) cross it at integer (x, y).
        let t = [[0.2, 0.1, 0.3], [8.7, 0.4, 0.3], [0.5, 7.9, 0.3]];
        let cols = [[255, 0, 0, 255], [0, 255, 0, 255], [0, 0, 255, 0]];
        let mut n = 0;
        discretize_triangle(&t, |c| {
            if c.family != 2 {
                return;
            }
            n += 1;
            // Exact barycentrics of (x, y) = (c.u, c.v) in the xy triangle.
            let (x, y) = (c.u as f64, c.v as f64);
            let det = (t[1][0] - t[0][0]) * (t[2][1] - t[0][1]) - (t[2][0] - t[0][0]) * (t[1][1] - t[0][1]);
            let l1 = ((x - t[0][0]) * (t[2][1] - t[0][1]) - (t[2][0] - t[0][0]) * (y - t[0][1])) / det;
            let l2 = ((t[1][0] - t[0][0]) * (y - t[0][1]) - (x - t[0][0]) * (t[1][1] - t[0][1])) / det;
            let l0 = 1.0 - l1 - l2;
            let want: Rgba = std::array::from_fn(|k| (l0 * cols[0][k] as f64 + l1 * cols[1][k] as f64 + l2 * cols[2][k] as f64).round() as u8);
            assert_eq!(crossing_colour(&t, &cols, &c), want, "at ({x}, {y})");
        });
        assert!(n >= 25, "{n} crossings");
    }

    #[test]
    fn a_record_gives_back_its_crossing() {
        let t = [[0.2, 0.1, 0.3], [8.7, 0.4, 5.3], [0.5, 7.9, 2.3]];
        let nb = 11;
        let mut n = 0;
        discretize_triangle(&t, |c| {
            let back = crossing_of(&c.intercept(nb), nb);
            assert_eq!((back.family, back.u, back.v), (c.family, c.u, c.v));
            assert_eq!(barycentric(&t, &back), barycentric(&t, &c));
            n += 1;
        });
        assert!(n > 20);
    }

    #[test]
    fn face_colours_are_kept_exactly() {
        let t = [[0.2, 0.1, 0.3], [8.7, 0.4, 0.3], [0.5, 7.9, 0.3]];
        let c = [[10, 20, 30, 40]; 3];
        discretize_triangle(&t, |x| assert_eq!(crossing_colour(&t, &c, &x), c[0]));
    }

    #[test]
    fn vertices_find_their_edge_and_synthesized_ones_their_nearest_crossings() {
        let g = Grid::around([0.0; 3], [10.0; 3], GridSize::CellSize(1.0), [0.0; 3], Some(2)).unwrap();
        let [_, nb, _] = g.local_dims();
        let red = [255, 0, 0, 255];
        let blue = [0, 0, 255, 255];
        // Plane 3: an A record on line b = 2 in cell 4 (red), a B record on
        // line a = 7 in cell 1 (blue), an S record at node (5, 5) (blue).
        let mut plane = vec![
            (Intercept::new(3, FAMILY_A, 2, 4.25, true), red),
            (Intercept::new(3, FAMILY_B, 7, 1.5, false), blue),
            (Intercept::new(3, FAMILY_S, 5 * (nb + 1) + 5, 3.75, true), blue),
        ];
        sort_coloured(&mut plane);
        let at = |l: [f64; 3]| g.to_world(l);
        let vs = [
            at([4.25, 2.0, 3.0]),  // on the A record
            at([7.0, 1.5, 3.0]),   // on the B record
            at([5.0, 5.0, 3.75]),  // on the S record
            at([4.5, 3.0, 3.0]),   // synthesized next to the A record
            at([5.0, 4.0, 3.5]),   // synthesized next to the S record
            at([6.0, 1.0, 3.5]),   // synthesized: A and B records one ring away
        ];
        let c = colour_vertices(&g, 3, &vs, &[plane.clone()]);
        assert_eq!(c[..5], [red, blue, blue, red, blue]);
        // Ring 1 of node (6, 1) holds the B record's node (7, 1) only.
        assert_eq!(c[5], blue);
        // Other planes are not this slab's.
        assert_eq!(colour_vertices(&g, 4, &vs[..1], &[plane]), vec![NO_COLOUR]);
        assert_eq!(colour_vertices(&g, 3, &vs[..1], &[Vec::new()]), vec![NO_COLOUR]);
    }
}
