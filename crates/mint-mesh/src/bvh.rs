//! [`TriangleBvh`]: an axis-aligned bounding-box tree over a mesh's
//! triangles, answering "which point of the mesh is nearest to `p`?"
//! exactly, for point-to-surface distances (Metro sampling in
//! [`mod@crate::distance`], error measures in other crates).
//!
//! Sources: the closest point on a triangle is Ericson, *Real-Time Collision
//! Detection* (2005), §5.1.5 "Closest point on triangle to point", which
//! walks the triangle's Voronoi regions with dot products only
//! ([`closest_point_on_triangle`]); degenerate (zero-area) triangles, where
//! its barycentric division fails, fall back to the nearest of the three
//! edges. The tree is a binary BVH built by object median split on the
//! longest axis of the centroid bounds (Wald, "On fast construction of
//! SAH-based bounding volume hierarchies", 2007, discusses the trade-off;
//! the median is chosen here because it is fast to build, needs no
//! parameters and bounds the depth by `log2(n)`).
//!
//! Data model, chosen for memory locality since queries are bound by cache
//! misses: each inner node holds the boxes of *both* its children (so one
//! 64-byte cache line decides which to visit) and refers to each child as
//! either another inner node or a leaf's range of triangles; inner nodes are
//! stored depth-first (a left inner child follows its parent). Boxes are
//! `f32` rounded outward: a conservative box only prunes a little less, it
//! never changes an answer, because distances to triangles are computed in
//! `f64`. Triangles are stored in leaf order,
//! with their original face index, and the positions are renumbered in
//! order of first use by that order, so one leaf's corners sit together in
//! memory. Memory is about 24 bytes per vertex plus 37 bytes per face. Every
//! subtree's node count follows from its triangle count alone, so the two
//! halves of each split are built in parallel into disjoint slices; the tree
//! is identical under any thread count. Queries use an explicit stack and
//! visit the nearer child first. Contract: finite coordinates; a NaN query
//! point gives an arbitrary triangle and a NaN distance.

use glam::DVec3;
use crate::error::MeshError;
use rayon::prelude::*;

/// Most triangles in a leaf.
const LEAF_SIZE: usize = 4;
/// Subtrees smaller than this are built on the current thread.
const PAR_THRESHOLD: usize = 1 << 14;

/// A child of an inner node: inner node `index` if `count == 0`, else the
/// leaf of `count` triangles starting at `index`.
#[derive(Debug, Clone, Copy)]
struct Child {
    index: u32,
    count: u32,
}

/// An inner node: both children's boxes and references, one cache line.
#[derive(Debug, Clone, Copy)]
#[repr(C, align(64))]
struct Node {
    min: [[f32; 3]; 2],
    max: [[f32; 3]; 2],
    child: [Child; 2],
}

const EMPTY_NODE: Node = Node {
    min: [[0.0; 3]; 2],
    max: [[0.0; 3]; 2],
    child: [Child { index: 0, count: 0 }; 2],
};

/// A bounding-volume hierarchy over triangles with exact nearest-point
/// queries. Build once with [`TriangleBvh::new`], then call
/// [`TriangleBvh::nearest`] from any number of threads.
#[derive(Debug, Clone)]
pub struct TriangleBvh {
    /// Referenced positions, renumbered by first use in leaf order.
    positions: Vec<[f64; 3]>,
    /// Triangles in leaf order, indexing `positions`.
    tris: Vec<[u32; 3]>,
    /// Original face index of each triangle in `tris`.
    ids: Vec<u32>,
    /// Inner nodes (none when everything fits one leaf).
    nodes: Vec<Node>,
    /// The root: inner node 0, or the single leaf.
    root: Child,
    /// Exact bounds of all triangles.
    bounds: ([f64; 3], [f64; 3]),
}

/// A triangle during the build: its centroid (in `f32`: it only guides the
/// splits) and original index, 16 bytes kept together so partitioning
/// streams through memory.
#[derive(Clone, Copy)]
struct Item {
    c: [f32; 3],
    id: u32,
}

impl TriangleBvh {
    /// Builds the tree over all faces (degenerate ones included: they are
    /// part of the surface as segments or points).
    ///
    /// Errors: [`MeshError::Empty`] without faces,
    /// [`MeshError::IndexOutOfRange`] for a bad index, and the size errors
    /// of [`MeshError`].
    pub fn new(positions: &[[f64; 3]], faces: &[[u32; 3]]) -> Result<Self, MeshError> {
        if faces.is_empty() {
            return Err(MeshError::Empty {
                what: "a BVH needs at least one face",
            });
        }
        MeshError::validate(positions, faces, u32::MAX as usize)?;

        let mut items: Vec<Item> = faces
            .par_iter()
            .enumerate()
            .map(|(id, f)| {
                let [a, b, c] = f.map(|i| positions[i as usize]);
                Item {
                    c: std::array::from_fn(|k| ((a[k] + b[k] + c[k]) / 3.0) as f32),
                    id: id as u32,
                }
            })
            .collect();
        let mut nodes = vec![EMPTY_NODE; inner_count(faces.len())];
        let ctx = BuildCtx { positions, faces };
        let (_, _, root) = build(&ctx, &mut items, 0, 0, &mut nodes);
        let ids: Vec<u32> = items.iter().map(|it| it.id).collect();
        drop(items);

        // Renumber vertices by first use in leaf order.
        let mut remap = vec![u32::MAX; positions.len()];
        let mut local = Vec::new();
        let tris: Vec<[u32; 3]> = ids
            .iter()
            .map(|&id| {
                faces[id as usize].map(|v| {
                    let r = &mut remap[v as usize];
                    if *r == u32::MAX {
                        *r = local.len() as u32;
                        local.push(positions[v as usize]);
                    }
                    *r
                })
            })
            .collect();
        drop(remap);
        let bounds = local
            .par_iter()
            .fold(
                || ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]),
                |(lo, hi), p| {
                    (
                        std::array::from_fn(|k| lo[k].min(p[k])),
                        std::array::from_fn(|k| hi[k].max(p[k])),
                    )
                },
            )
            .reduce(
                || ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]),
                |a, b| {
                    (
                        std::array::from_fn(|k| a.0[k].min(b.0[k])),
                        std::array::from_fn(|k| a.1[k].max(b.1[k])),
                    )
                },
            );
        Ok(Self {
            positions: local,
            tris,
            ids,
            nodes,
            root,
            bounds,
        })
    }

    /// Number of triangles in the tree.
    pub fn len(&self) -> usize {
        self.tris.len()
    }

    /// Always false: a tree has at least one triangle.
    pub fn is_empty(&self) -> bool {
        self.tris.is_empty()
    }

    /// The exact bounding box of all triangles, `(min, max)`.
    pub fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        self.bounds
    }

    /// The nearest point of the surface to `p`: `(distance, closest point,
    /// index of its face in the input face list)`. Exact up to the rounding
    /// of Ericson's closest-point formulas; among equally near triangles the
    /// first one the traversal meets wins (deterministic for a given tree).
    pub fn nearest(&self, p: [f64; 3]) -> (f64, [f64; 3], u32) {
        match self.search(p, f64::INFINITY, None) {
            Some((d2, q, t)) => (d2.sqrt(), q, self.ids[t]),
            None => (f64::NAN, [f64::NAN; 3], self.ids[0]),
        }
    }

    /// Like [`nearest`](Self::nearest) but only looks for points strictly
    /// closer than `max_dist`; `None` if there is none. A finite radius
    /// prunes the search.
    pub fn nearest_within(&self, p: [f64; 3], max_dist: f64) -> Option<(f64, [f64; 3], u32)> {
        self.search(p, max_dist * max_dist, None)
            .map(|(d2, q, t)| (d2.sqrt(), q, self.ids[t]))
    }

    /// Like [`nearest_within`](Self::nearest_within), starting from the
    /// triangle found by the previous query through the same `hint` (and
    /// updating it): when successive query points are close, as the
    /// samples of a scan row are, that triangle's distance prunes most of
    /// the tree at once. The distance found is the same as without the
    /// hint; among equally near triangles which one wins may differ, so a
    /// deterministic caller passes hints along a fixed order of queries.
    pub fn nearest_within_hinted(&self, p: [f64; 3], max_dist: f64, hint: &mut Option<u32>) -> Option<(f64, [f64; 3], u32)> {
        let r = self.search(p, max_dist * max_dist, hint.map(|t| t as usize));
        if let Some((_, _, t)) = r {
            *hint = Some(t as u32);
        }
        r.map(|(d2, q, t)| (d2.sqrt(), q, self.ids[t]))
    }

    /// The nearest point as `(squared distance, point, internal triangle)`,
    /// starting from the bound `best_d2` and, if given, the internal
    /// triangle `hint` (a good guess, e.g. the answer for a nearby point,
    /// prunes most of the tree at once). The distance is the same whatever
    /// the hint; only which of several equally near triangles wins may
    /// differ.
    pub(crate) fn search(
        &self,
        p: [f64; 3],
        mut best_d2: f64,
        hint: Option<usize>,
    ) -> Option<(f64, [f64; 3], usize)> {
        let mut best: Option<([f64; 3], usize)> = None;
        if let Some(t) = hint {
            let (d2, q) = self.tri_dist2(p, t);
            if d2 < best_d2 {
                best_d2 = d2;
                best = Some((q, t));
            }
        }
        // Depth is at most log2(faces) + 1 <= 33, and each level leaves at
        // most one deferred sibling on the stack.
        let mut stack = [(self.root, 0.0f64); 96];
        let mut sp = 1usize;
        while sp > 0 {
            sp -= 1;
            let (c, d2) = stack[sp];
            if d2 >= best_d2 {
                continue;
            }
            if c.count > 0 {
                let first = c.index as usize;
                for t in first..first + c.count as usize {
                    let (d2, q) = self.tri_dist2(p, t);
                    if d2 < best_d2 {
                        best_d2 = d2;
                        best = Some((q, t));
                    }
                }
                continue;
            }
            let node = &self.nodes[c.index as usize];
            let dl = box_dist2(node.min[0], node.max[0], p);
            let dr = box_dist2(node.min[1], node.max[1], p);
            // Push the farther child first so the nearer one pops first.
            let (near, dn, far, df) = if dl <= dr {
                (0, dl, 1, dr)
            } else {
                (1, dr, 0, dl)
            };
            if df < best_d2 {
                stack[sp] = (node.child[far], df);
                sp += 1;
            }
            if dn < best_d2 {
                stack[sp] = (node.child[near], dn);
                sp += 1;
            }
        }
        best.map(|(q, t)| (best_d2, q, t))
    }

    #[inline]
    fn tri_dist2(&self, p: [f64; 3], t: usize) -> (f64, [f64; 3]) {
        let [a, b, c] = self.tris[t].map(|i| self.positions[i as usize]);
        let q = closest_point_on_triangle(p, a, b, c);
        (DVec3::from(p).distance_squared(DVec3::from(q)), q)
    }
}

struct BuildCtx<'a> {
    positions: &'a [[f64; 3]],
    faces: &'a [[u32; 3]],
}

/// Inner nodes in a subtree over `n` triangles (median splits: `n/2` and
/// `n - n/2`).
fn inner_count(n: usize) -> usize {
    leaf_count(n) - 1
}

fn leaf_count(n: usize) -> usize {
    leaf_count_pair(n).0
}

/// `(leaf_count(m), leaf_count(m + 1))`. The halves of `m` and `m + 1` are
/// both `h = m / 2` or `h + 1`, so one recursion on `h` serves both.
fn leaf_count_pair(m: usize) -> (usize, usize) {
    if m < LEAF_SIZE {
        return (1, 1);
    }
    let (lh, lh1) = leaf_count_pair(m / 2);
    let lm = if m <= LEAF_SIZE {
        1
    } else if m & 1 == 0 {
        2 * lh
    } else {
        lh + lh1
    };
    let lm1 = if m & 1 == 0 { lh + lh1 } else { 2 * lh1 };
    (lm, lm1)
}

/// Builds the subtree over `items` into `nodes` (its inner nodes, the first
/// of which is its root at absolute index `base`); `items` starts at
/// absolute position `first` of the whole item array. Returns the
/// subtree's box and how to refer to it.
fn build(
    ctx: &BuildCtx,
    items: &mut [Item],
    base: usize,
    first: usize,
    nodes: &mut [Node],
) -> ([f32; 3], [f32; 3], Child) {
    let n = items.len();
    debug_assert_eq!(nodes.len(), inner_count(n));
    if n <= LEAF_SIZE {
        let (min, max) = tri_bounds(ctx, items);
        return (
            min,
            max,
            Child {
                index: first as u32,
                count: n as u32,
            },
        );
    }
    // Split on the longest axis of the centroid bounds, at the median.
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for it in items.iter() {
        for k in 0..3 {
            lo[k] = lo[k].min(it.c[k]);
            hi[k] = hi[k].max(it.c[k]);
        }
    }
    let axis = (0..3)
        .max_by(|&x, &y| (hi[x] - lo[x]).total_cmp(&(hi[y] - lo[y])).then(y.cmp(&x)))
        .expect("three axes");
    let half = n / 2;
    items.select_nth_unstable_by(half, |x, y| {
        x.c[axis].total_cmp(&y.c[axis]).then(x.id.cmp(&y.id))
    });
    let (litems, ritems) = items.split_at_mut(half);
    let nl = inner_count(half);
    let (root, rest) = nodes.split_first_mut().expect("an inner node");
    let (lnodes, rnodes) = rest.split_at_mut(nl);
    let (l, r) = if n >= PAR_THRESHOLD {
        rayon::join(
            || build(ctx, litems, base + 1, first, lnodes),
            || build(ctx, ritems, base + 1 + nl, first + half, rnodes),
        )
    } else {
        (
            build(ctx, litems, base + 1, first, lnodes),
            build(ctx, ritems, base + 1 + nl, first + half, rnodes),
        )
    };
    *root = Node {
        min: [l.0, r.0],
        max: [l.1, r.1],
        child: [l.2, r.2],
    };
    (
        std::array::from_fn(|k| l.0[k].min(r.0[k])),
        std::array::from_fn(|k| l.1[k].max(r.1[k])),
        Child {
            index: base as u32,
            count: 0,
        },
    )
}

/// Bounds of a leaf's triangles, rounded outward to `f32`.
fn tri_bounds(ctx: &BuildCtx, items: &[Item]) -> ([f32; 3], [f32; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for it in items {
        for &v in &ctx.faces[it.id as usize] {
            let p = ctx.positions[v as usize];
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
    }
    (lo.map(f32_down), hi.map(f32_up))
}

/// The largest `f32` not above `x` (`x` finite or infinite).
fn f32_down(x: f64) -> f32 {
    let f = x as f32;
    if f64::from(f) <= x {
        f
    } else if f > 0.0 {
        f32::from_bits(f.to_bits() - 1)
    } else if f == 0.0 {
        -f32::from_bits(1)
    } else {
        f32::from_bits(f.to_bits() + 1)
    }
}

/// The smallest `f32` not below `x`.
fn f32_up(x: f64) -> f32 {
    -f32_down(-x)
}

#[inline]
fn box_dist2(min: [f32; 3], max: [f32; 3], p: [f64; 3]) -> f64 {
    let mut d2 = 0.0;
    for k in 0..3 {
        let d = (f64::from(min[k]) - p[k])
            .max(0.0)
            .max(p[k] - f64::from(max[k]));
        d2 += d * d;
    }
    d2
}

/// The point of triangle `abc` nearest to `p` (Ericson, *Real-Time
/// Collision Detection*, §5.1.5): classify `p` against the Voronoi regions
/// of the vertices, then the edges, else project onto the face. A triangle
/// with zero area (collinear or coincident corners) is treated as its three
/// edges.
pub fn closest_point_on_triangle(p: [f64; 3], a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> [f64; 3] {
    let (p, a, b, c) = (DVec3::from(p), DVec3::from(a), DVec3::from(b), DVec3::from(c));
    let ab = b - a;
    let ac = c - a;
    let n = ab.cross(ac);
    if n.dot(n) == 0.0 {
        return closest_on_edges(p, a, b, c).to_array();
    }
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return a.to_array(); // vertex region A
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return b.to_array(); // vertex region B
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (a + ab * v).to_array(); // edge region AB
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return c.to_array(); // vertex region C
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (a + ac * w).to_array(); // edge region AC
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (b + (c - b) * w).to_array(); // edge region BC
    }
    // Face region: barycentric (u, v, w) = (va, vb, vc) / (va + vb + vc).
    let denom = 1.0 / (va + vb + vc);
    let v = vb * denom;
    let w = vc * denom;
    let q = a + ab * v + ac * w;
    if q.is_finite() {
        q.to_array()
    } else {
        // Nearly degenerate triangles can overflow the division.
        closest_on_edges(p, a, b, c).to_array()
    }
}

fn closest_on_segment(p: DVec3, a: DVec3, b: DVec3) -> DVec3 {
    let ab = b - a;
    let l2 = ab.dot(ab);
    if l2 == 0.0 {
        return a;
    }
    let t = ((p - a).dot(ab) / l2).clamp(0.0, 1.0);
    a + ab * t
}

fn closest_on_edges(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    let mut best = closest_on_segment(p, a, b);
    let mut bd = p.distance_squared(best);
    for q in [closest_on_segment(p, b, c), closest_on_segment(p, c, a)] {
        let d = p.distance_squared(q);
        if d < bd {
            bd = d;
            best = q;
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    fn dist(p: [f64; 3], q: [f64; 3]) -> f64 {
        DVec3::from(p).distance(DVec3::from(q))
    }

    #[test]
    fn inner_count_matches_recursion() {
        fn rec(n: usize) -> usize {
            if n <= LEAF_SIZE {
                0
            } else {
                1 + rec(n / 2) + rec(n - n / 2)
            }
        }
        for n in 1..2000 {
            assert_eq!(inner_count(n), rec(n), "n = {n}");
        }
        assert_eq!(inner_count(1 << 20), rec(1 << 20));
        assert_eq!(inner_count(1_000_003), rec(1_000_003));
    }

    #[test]
    fn voronoi_regions_of_one_triangle() {
        let (a, b, c) = ([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
        let cp = |p| closest_point_on_triangle(p, a, b, c);
        assert_eq!(cp([-1.0, -1.0, 2.0]), a);
        assert_eq!(cp([2.0, -0.5, 1.0]), b);
        assert_eq!(cp([-0.5, 3.0, -1.0]), c);
        assert_eq!(cp([0.5, -2.0, 0.0]), [0.5, 0.0, 0.0]); // edge AB
        assert_eq!(cp([-2.0, 0.25, 0.0]), [0.0, 0.25, 0.0]); // edge AC
        assert_eq!(cp([1.0, 1.0, 0.0]), [0.5, 0.5, 0.0]); // edge BC
        assert_eq!(cp([0.25, 0.25, 3.0]), [0.25, 0.25, 0.0]); // face
    }

    #[test]
    fn degenerate_triangles_are_segments_or_points() {
        let (a, b, c) = ([0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [1.0, 0.0, 0.0]);
        assert_eq!(
            closest_point_on_triangle([1.5, 1.0, 0.0], a, b, c),
            [1.5, 0.0, 0.0]
        );
        let p = [3.0; 3];
        assert_eq!(closest_point_on_triangle([1.0, 2.0, 3.0], p, p, p), p);
    }

    #[test]
    fn bvh_matches_brute_force_on_a_triangle_soup() {
        let mut rng = SplitMix64::new(7);
        let mut positions = Vec::new();
        let mut faces = Vec::new();
        for t in 0..1000u32 {
            let o: [f64; 3] = std::array::from_fn(|_| rng.next_f64() * 10.0);
            for _ in 0..3 {
                positions.push(std::array::from_fn(|k| o[k] + rng.next_f64() - 0.5));
            }
            faces.push([3 * t, 3 * t + 1, 3 * t + 2]);
        }
        let bvh = TriangleBvh::new(&positions, &faces).unwrap();
        assert_eq!(bvh.len(), 1000);
        for _ in 0..500 {
            let p: [f64; 3] = std::array::from_fn(|_| rng.next_f64() * 14.0 - 2.0);
            let (d, q, id) = bvh.nearest(p);
            let brute = faces
                .iter()
                .map(|f| {
                    let [a, b, c] = f.map(|i| positions[i as usize]);
                    dist(p, closest_point_on_triangle(p, a, b, c))
                })
                .fold(f64::INFINITY, f64::min);
            assert_eq!(d, brute);
            assert!((dist(p, q) - d).abs() <= 1e-12);
            let [a, b, c] = faces[id as usize].map(|i| positions[i as usize]);
            assert_eq!(dist(p, closest_point_on_triangle(p, a, b, c)), d);
        }
    }

    #[test]
    fn f32_rounding_is_outward() {
        for x in [
            0.1f64, -0.1, 1e-50, -1e-50, 0.0, 3.0, 1e40, -1e40, 16777217.0,
        ] {
            assert!(f64::from(f32_down(x)) <= x, "{x}");
            assert!(f64::from(f32_up(x)) >= x, "{x}");
        }
        assert_eq!(f32_down(3.0), 3.0);
        assert_eq!(f32_up(3.0), 3.0);
    }

    #[test]
    fn hints_do_not_change_distances() {
        let mut rng = SplitMix64::new(11);
        let positions: Vec<[f64; 3]> = (0..300)
            .map(|_| std::array::from_fn(|_| rng.next_f64()))
            .collect();
        let faces: Vec<[u32; 3]> = (0..100).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
        let bvh = TriangleBvh::new(&positions, &faces).unwrap();
        for i in 0..200 {
            let p: [f64; 3] = std::array::from_fn(|_| rng.next_f64() * 2.0 - 0.5);
            let plain = bvh.search(p, f64::INFINITY, None).unwrap();
            let hinted = bvh.search(p, f64::INFINITY, Some(i % 100)).unwrap();
            assert_eq!(plain.0, hinted.0);
        }
    }

    #[test]
    fn nearest_within_prunes() {
        let positions = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let bvh = TriangleBvh::new(&positions, &[[0, 1, 2]]).unwrap();
        assert!(bvh.nearest_within([0.0, 0.0, 2.0], 1.5).is_none());
        let (d, q, id) = bvh.nearest_within([0.0, 0.0, 2.0], 2.5).unwrap();
        assert_eq!((d, q, id), (2.0, [0.0, 0.0, 0.0], 0));
    }

    #[test]
    fn errors_are_typed() {
        let p = [[0.0; 3]; 3];
        assert!(matches!(
            TriangleBvh::new(&p, &[]),
            Err(MeshError::Empty { .. })
        ));
        assert_eq!(
            TriangleBvh::new(&p, &[[0, 1, 3]]).unwrap_err(),
            MeshError::IndexOutOfRange {
                face: 0,
                index: 3,
                vertices: 3
            }
        );
    }
}
