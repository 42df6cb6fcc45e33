//! The marching-cubes case table, generated from one disambiguation rule and
//! tested exhaustively instead of typed in.
//!
//! ```text
//! Corner c = x + 2y + 4z              Edges (e: corners)
//!                                     x-edges  0: 0-1   1: 2-3   2: 4-5   3: 6-7
//!         6 -------3------- 7         y-edges  4: 0-2   5: 1-3   6: 4-6   7: 5-7
//!        /|                /|         z-edges  8: 0-4   9: 1-5  10: 2-6  11: 3-7
//!       6 |               7 |
//!      /  10             /  11        x-edge e = 0 + y + 2z
//!     4 -------2------- 5   |         y-edge e = 4 + x + 2z
//!     |   |             |   |         z-edge e = 8 + x + 2y
//!     |   2 -------1----|-- 3
//!     8  /              9  /          z
//!     | 4               | 5           |  y
//!     |/                |/            | /
//!     0 -------0------- 1             |/___ x
//! ```
//!
//! A cell's code has bit `c` set when corner `c` is inside the solid. On every
//! face of the cube the surface crosses 0, 2 or 4 edges. With 4 (an ambiguous
//! face: diagonal corners inside) the rule is *inside corners are separated*:
//! each inside corner is cut off by its own segment. The rule looks at the
//! face alone, so the two cells sharing a face draw the same segments
//! (Montani, Scateni, Scopigno 1994, "A modified look-up table for implicit
//! disambiguation of Marching Cubes").
//!
//! The segments on the six faces chain into closed polygons (each crossed edge
//! lies on two faces). Each segment is oriented so that the inside is on its
//! left seen from outside the solid; the polygons then give triangles facing
//! out of the solid. A polygon is triangulated without new vertices, by a
//! minimum-weight triangulation that never uses a diagonal joining two edges
//! of one cube face (the neighbouring cell could use the same diagonal and
//! make an edge shared by four triangles). Tests check every code, every
//! pair of face-adjacent cells and every ring of four cells around an edge.

use glam::DVec3;
use std::sync::OnceLock;

/// The two corners of each edge, lower corner first.
pub const EDGE_CORNERS: [[u8; 2]; 12] = [
    [0, 1], [2, 3], [4, 5], [6, 7],
    [0, 2], [1, 3], [4, 6], [5, 7],
    [0, 4], [1, 5], [2, 6], [3, 7],
];

/// Position of corner `c` as (x, y, z) in {0, 1}.
#[inline]
pub fn corner_offset(c: u8) -> [u32; 3] {
    [(c & 1) as u32, ((c >> 1) & 1) as u32, ((c >> 2) & 1) as u32]
}

/// The axis an edge is parallel to (0 = x, 1 = y, 2 = z).
#[inline]
pub fn edge_axis(e: u8) -> usize {
    (e / 4) as usize
}

/// The edge joining two corners, if they are adjacent.
fn edge_between(c1: u8, c2: u8) -> u8 {
    let (lo, hi) = (c1.min(c2), c1.max(c2));
    EDGE_CORNERS.iter().position(|&[a, b]| a == lo && b == hi).expect("corners are adjacent") as u8
}

/// The six faces: axis, side, and the four corners in cyclic order in the
/// plane of axes (axis+1, axis+2).
fn faces() -> [(usize, u8, [u8; 4]); 6] {
    let mut out = [(0, 0, [0u8; 4]); 6];
    let mut n = 0;
    for axis in 0..3 {
        for side in 0..2u8 {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let corner = |du: u8, dv: u8| -> u8 { (side << axis) | (du << u) | (dv << v) };
            out[n] = (axis, side, [corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)]);
            n += 1;
        }
    }
    out
}

fn midpoint(e: u8) -> [f64; 3] {
    let [a, b] = EDGE_CORNERS[e as usize];
    let (pa, pb) = (corner_offset(a), corner_offset(b));
    [0, 1, 2].map(|d| 0.5 * (pa[d] + pb[d]) as f64)
}


/// The generated table: for each of the 256 codes, triangles as edge triples.
pub struct McTable {
    offsets: [u16; 257],
    triangles: Vec<[u8; 3]>,
}

impl McTable {
    /// Triangles (as edge ids) for a cell code.
    #[inline]
    pub fn triangles(&self, code: u8) -> &[[u8; 3]] {
        let c = code as usize;
        &self.triangles[self.offsets[c] as usize..self.offsets[c + 1] as usize]
    }
}

/// The shared table, generated on first use.
pub fn mc_table() -> &'static McTable {
    static TABLE: OnceLock<McTable> = OnceLock::new();
    TABLE.get_or_init(generate)
}

/// The oriented boundary segments `(from_edge, to_edge)` of a code, per face.
pub fn face_segments(code: u8) -> Vec<(u8, u8)> {
    let inside = |c: u8| (code >> c) & 1 == 1;
    let mut segs = Vec::new();
    for (axis, side, cyc) in faces() {
        let mut normal = [0.0; 3];
        normal[axis] = if side == 1 { 1.0 } else { -1.0 };
        let face_edge = |i: usize| edge_between(cyc[i], cyc[(i + 1) % 4]);
        let crossed: Vec<usize> = (0..4).filter(|&i| inside(cyc[i]) != inside(cyc[(i + 1) % 4])).collect();
        let oriented = |e1: u8, e2: u8, c_in: u8| -> (u8, u8) {
            let (p, q) = (DVec3::from(midpoint(e1)), DVec3::from(midpoint(e2)));
            let c = DVec3::from(corner_offset(c_in).map(|x| x as f64));
            if (q - p).cross(c - p).dot(DVec3::from(normal)) < 0.0 {
                (e1, e2)
            } else {
                (e2, e1)
            }
        };
        match crossed.len() {
            0 => {}
            2 => {
                let c_in = *cyc.iter().find(|&&c| inside(c)).unwrap();
                segs.push(oriented(face_edge(crossed[0]), face_edge(crossed[1]), c_in));
            }
            4 => {
                // Ambiguous face: cut off each inside corner separately.
                for i in 0..4 {
                    if inside(cyc[i]) {
                        let before = face_edge((i + 3) % 4);
                        let after = face_edge(i);
                        segs.push(oriented(before, after, cyc[i]));
                    }
                }
            }
            _ => unreachable!("a square has an even number of sign changes"),
        }
    }
    segs
}

/// Edges of the cube that share a face with each other (not counting equality).
fn share_face(e1: u8, e2: u8) -> bool {
    faces().iter().any(|(_, _, cyc)| {
        let on = |e: u8| (0..4).any(|i| edge_between(cyc[i], cyc[(i + 1) % 4]) == e);
        on(e1) && on(e2)
    })
}

/// Minimum-weight triangulation of a polygon of edge ids (cycle order).
fn triangulate(poly: &[u8]) -> Vec<[u8; 3]> {
    let n = poly.len();
    if n == 3 {
        return vec![[poly[0], poly[1], poly[2]]];
    }
    // Weight of a diagonal: a face-sharing diagonal is forbidden (large
    // penalty), otherwise its squared length between edge midpoints.
    let w = |i: usize, j: usize| -> f64 {
        if (i + 1) % n == j || (j + 1) % n == i {
            return 0.0;
        }
        let (a, b) = (poly[i], poly[j]);
        DVec3::from(midpoint(a)).distance_squared(DVec3::from(midpoint(b))) + if share_face(a, b) { 1e6 } else { 0.0 }
    };
    let mut cost = vec![vec![0.0f64; n]; n];
    let mut split = vec![vec![0usize; n]; n];
    for len in 2..n {
        for i in 0..n - len {
            let j = i + len;
            let mut best = f64::INFINITY;
            for k in i + 1..j {
                let c = cost[i][k] + cost[k][j] + w(i, k) + w(k, j);
                if c < best - 1e-12 {
                    best = c;
                    split[i][j] = k;
                }
            }
            cost[i][j] = best;
        }
    }
    let mut tris = Vec::new();
    let mut stack = vec![(0usize, n - 1)];
    while let Some((i, j)) = stack.pop() {
        if j < i + 2 {
            continue;
        }
        let k = split[i][j];
        tris.push([poly[i], poly[k], poly[j]]);
        stack.push((i, k));
        stack.push((k, j));
    }
    tris.sort_unstable();
    tris
}

/// The closed polygons of a code, each as a cycle of edge ids starting at
/// its smallest edge.
pub fn polygons(code: u8) -> Vec<Vec<u8>> {
    let segs = face_segments(code);
    let mut next = [u8::MAX; 12];
    for &(a, b) in &segs {
        assert_eq!(next[a as usize], u8::MAX, "code {code}: edge {a} leaves twice");
        next[a as usize] = b;
    }
    let mut seen = [false; 12];
    let mut polys = Vec::new();
    for start in 0..12u8 {
        if next[start as usize] == u8::MAX || seen[start as usize] {
            continue;
        }
        let mut poly = Vec::new();
        let mut e = start;
        while !seen[e as usize] {
            seen[e as usize] = true;
            poly.push(e);
            e = next[e as usize];
        }
        assert_eq!(e, start, "code {code}: open chain");
        polys.push(poly);
    }
    polys
}

fn generate() -> McTable {
    let mut offsets = [0u16; 257];
    let mut triangles = Vec::new();
    for code in 0..=255u8 {
        for poly in polygons(code) {
            triangles.extend(triangulate(&poly));
        }
        offsets[code as usize + 1] = triangles.len() as u16;
    }
    McTable { offsets, triangles }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    fn crossed(code: u8, e: u8) -> bool {
        let [a, b] = EDGE_CORNERS[e as usize];
        ((code >> a) & 1) != ((code >> b) & 1)
    }

    #[test]
    fn every_code_gives_closed_polygons_over_exactly_its_crossed_edges() {
        let t = mc_table();
        for code in 0..=255u8 {
            let polys = polygons(code);
            let mut used = [0; 12];
            for p in &polys {
                assert!(p.len() >= 3, "code {code}");
                for &e in p {
                    used[e as usize] += 1;
                }
            }
            for e in 0..12u8 {
                assert_eq!(used[e as usize], crossed(code, e) as i32, "code {code} edge {e}");
            }
            let expected: usize = polys.iter().map(|p| p.len() - 2).sum();
            assert_eq!(t.triangles(code).len(), expected);
            // Inside the cube, every diagonal is used twice in opposite
            // directions; polygon sides (face segments) once.
            let mut half = HashMap::new();
            for tri in t.triangles(code) {
                for i in 0..3 {
                    *half.entry((tri[i], tri[(i + 1) % 3])).or_insert(0) += 1;
                }
            }
            let segs: std::collections::HashSet<(u8, u8)> = face_segments(code).into_iter().collect();
            for (&(a, b), &n) in &half {
                assert_eq!(n, 1, "code {code}: half-edge {a}->{b} used {n} times");
                if !segs.contains(&(a, b)) {
                    assert!(half.contains_key(&(b, a)), "code {code}: {a}->{b} unmatched");
                }
            }
            for s in &segs {
                assert!(half.contains_key(s), "code {code}: segment {s:?} not a triangle side");
            }
        }
        assert!(t.triangles(0).is_empty() && t.triangles(255).is_empty());
    }

    #[test]
    fn no_diagonal_joins_two_edges_of_one_face() {
        for code in 0..=255u8 {
            let segs: std::collections::HashSet<(u8, u8)> = face_segments(code).into_iter().collect();
            for tri in mc_table().triangles(code) {
                for i in 0..3 {
                    let (a, b) = (tri[i], tri[(i + 1) % 3]);
                    if !segs.contains(&(a, b)) && !segs.contains(&(b, a)) {
                        assert!(!share_face(a, b), "code {code}: diagonal {a}-{b} lies on a face");
                    }
                }
            }
        }
    }

    /// Builds the triangles of a block of cells with given node states, with
    /// vertices named by their global grid edge, and checks that the result is
    /// an oriented 2-manifold: no directed half-edge twice, no undirected edge
    /// on more than two triangles, and two triangles on an edge traverse it
    /// in opposite directions. Returns the half-edge multiset.
    fn block_mesh(dims: [u32; 3], state: &dyn Fn([u32; 3]) -> bool) -> Vec<[(u32, u32, u32, u8); 3]> {
        let mut tris = Vec::new();
        for z in 0..dims[2] {
            for y in 0..dims[1] {
                for x in 0..dims[0] {
                    let mut code = 0u8;
                    for c in 0..8u8 {
                        let o = corner_offset(c);
                        if state([x + o[0], y + o[1], z + o[2]]) {
                            code |= 1 << c;
                        }
                    }
                    for t in mc_table().triangles(code) {
                        tris.push(t.map(|e| {
                            let lo = corner_offset(EDGE_CORNERS[e as usize][0]);
                            (x + lo[0], y + lo[1], z + lo[2], edge_axis(e) as u8)
                        }));
                    }
                }
            }
        }
        tris
    }

    fn assert_oriented_manifold_edges(tris: &[[(u32, u32, u32, u8); 3]], ctx: &str) {
        let mut half: HashMap<_, u32> = HashMap::new();
        for t in tris {
            for i in 0..3 {
                let e = (t[i], t[(i + 1) % 3]);
                let n = half.entry(e).or_insert(0);
                *n += 1;
                assert_eq!(*n, 1, "{ctx}: half-edge used twice");
            }
        }
    }

    #[test]
    fn face_adjacent_cells_agree_for_all_4096_states_per_axis() {
        for axis in 0..3 {
            let mut dims = [1u32; 3];
            dims[axis] = 2;
            for bits in 0u32..4096 {
                // 12 nodes of a 2-cell block, numbered in x-fastest order.
                let n = [dims[0] + 1, dims[1] + 1];
                let state = |p: [u32; 3]| (bits >> (p[0] + n[0] * (p[1] + n[1] * p[2]))) & 1 == 1;
                let tris = block_mesh(dims, &state);
                assert_oriented_manifold_edges(&tris, &format!("axis {axis} bits {bits}"));
                // Every half-edge on the shared face is matched by its reverse.
                let set: std::collections::HashSet<_> =
                    tris.iter().flat_map(|t| (0..3).map(move |i| (t[i], t[(i + 1) % 3]))).collect();
                for &(a, b) in &set {
                    let on_shared = |v: (u32, u32, u32, u8)| {
                        let p = [v.0, v.1, v.2];
                        p[axis] == 1 && v.3 as usize != axis
                    };
                    if on_shared(a) && on_shared(b) {
                        assert!(set.contains(&(b, a)), "axis {axis} bits {bits}: seam edge unmatched");
                    }
                }
            }
        }
    }

    #[test]
    fn the_four_cells_around_an_edge_give_a_single_disk_at_its_vertex() {
        for axis in 0..3 {
            let mut dims = [2u32; 3];
            dims[axis] = 1;
            let n = [dims[0] + 1, dims[1] + 1];
            let mut centre = [1u32; 3];
            centre[axis] = 0;
            let centre_vertex = (centre[0], centre[1], centre[2], axis as u8);
            for bits in 0u32..(1 << 18) {
                let state = |p: [u32; 3]| (bits >> (p[0] + n[0] * (p[1] + n[1] * p[2]))) & 1 == 1;
                let tris = block_mesh(dims, &state);
                let fan: Vec<_> = tris.iter().filter(|t| t.contains(&centre_vertex)).collect();
                if fan.is_empty() {
                    continue;
                }
                // The link of the vertex: one directed edge (next, prev) per
                // triangle; it must form a single closed cycle.
                let mut next = HashMap::new();
                for t in &fan {
                    let i = t.iter().position(|v| *v == centre_vertex).unwrap();
                    assert!(next.insert(t[(i + 1) % 3], t[(i + 2) % 3]).is_none(), "bits {bits}");
                }
                let start = *next.keys().next().unwrap();
                let mut v = start;
                let mut steps = 0;
                loop {
                    v = *next.get(&v).unwrap_or_else(|| panic!("axis {axis} bits {bits}: open link"));
                    steps += 1;
                    if v == start {
                        break;
                    }
                }
                assert_eq!(steps, fan.len(), "axis {axis} bits {bits}: link has several cycles");
            }
        }
    }

    #[test]
    fn random_blocks_close_into_an_oriented_manifold_with_positive_volume() {
        let mut seed = 12345u64;
        let mut rnd = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 33) as u32
        };
        for trial in 0..300 {
            let dims = [5u32, 4, 6];
            let fill = rnd() % 100;
            let cells: Vec<bool> = (0..(dims[0] + 1) * (dims[1] + 1) * (dims[2] + 1)).map(|_| rnd() % 100 < fill).collect();
            let state = |p: [u32; 3]| {
                let inner = (0..3).all(|d| p[d] > 0 && p[d] < dims[d]);
                inner && cells[(p[0] + (dims[0] + 1) * (p[1] + (dims[1] + 1) * p[2])) as usize]
            };
            let tris = block_mesh(dims, &state);
            let mut half = std::collections::HashSet::new();
            for t in &tris {
                for i in 0..3 {
                    assert!(half.insert((t[i], t[(i + 1) % 3])), "trial {trial}");
                }
            }
            for &(a, b) in &half {
                assert!(half.contains(&(b, a)), "trial {trial}: boundary edge");
            }
            // Volume with vertices at edge midpoints: the count of inside nodes
            // is roughly the volume; it must be positive whenever any is inside.
            let pos = |v: (u32, u32, u32, u8)| {
                let mut p = [v.0 as f64, v.1 as f64, v.2 as f64];
                p[v.3 as usize] += 0.5;
                p
            };
            let vol: f64 = tris.iter().map(|t| DVec3::from(pos(t[0])).dot(DVec3::from(pos(t[1])).cross(DVec3::from(pos(t[2])))) / 6.0).sum();
            let any = (0..(dims[0] + 1)).any(|x| (0..(dims[1] + 1)).any(|y| (0..(dims[2] + 1)).any(|z| state([x, y, z]))));
            assert_eq!(vol > 1e-9, any, "trial {trial}: volume {vol}");
        }
    }
}
