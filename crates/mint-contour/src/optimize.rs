//! The normal optimizer (Dangl 1998, §3): merge near-coplanar triangles
//! into regions and re-triangulate each region from its boundary.
//!
//! Sources:
//! - M. Dangl 1998, §3 (free polygons by region growing, projection on the
//!   Newell normal, deleting collinear contour vertices where all regions
//!   agree, re-triangulation by smallest inner angle first).
//! - F. Wilmer, U. Tiede, K. H. Höhne, "Reduktion der Oberflächenbeschreibung
//!   durch Anpassung an die Objektform", Mustererkennung 1992 (the method).
//! - M. E. Newell's normal, as in F. S. Hill, "Computer Graphics", 1990.
//!
//! # Stages
//! 1. **Regions.** Faces are grown breadth-first over manifold edges (two
//!    faces, opposite directions) into regions whose normals all lie within
//!    `angle` of one another: each region keeps a cone (axis, half-angle)
//!    enclosing its normals and accepts a face only if the enlarged cone's
//!    full angle stays within `angle`. At `angle = 0` the test is exact
//!    coplanarity (`orient3d` of the face's vertices against the seed
//!    face's plane is zero), so only coplanar faces merge.
//! 2. **Boundaries.** A region is *free* (optimizable) when it is a disk
//!    with holes: every boundary vertex has one outgoing boundary edge, and
//!    `V − E + F = 2 − loops`. Its boundary loops are projected on the plane
//!    of its Newell normal; the projection must keep every face
//!    counter-clockwise, the loops must be simple and disjoint (exact test),
//!    and exactly one loop must be counter-clockwise (the outer one).
//!    Regions that fail stay as they are.
//! 3. **Collinear vertices.** A boundary vertex is dropped when, in every
//!    region around it, it is collinear with its two loop neighbours (within
//!    [`COLLINEAR_TOLERANCE`] of their distance) and every such region is
//!    free. Vertices on the mesh boundary or on non-manifold edges are kept.
//! 4. **Re-triangulation** of each free region's loops with
//!    [`crate::triangulate::triangulate`], no new vertices. A
//!    region whose polygon is no longer simple after the drops, whose
//!    triangulation needs a forced ear, or whose new diagonal duplicates an
//!    edge of the output is made non-free and stages 3 and 4 run again.
//!
//! Interior vertices of free regions disappear; the output keeps the input's
//! topology and boundary, and vertices are renumbered compactly in their
//! input order. Planar regions stay exactly planar: no vertex moves.

use crate::geom2d::{first_crossing, orient, signed_area, P2};
use crate::triangulate::triangulate;
use glam::DVec3;
use mint_core::TriMesh;
use robust::{orient3d, Coord3D};
use serde::Serialize;
use std::collections::HashMap;

/// Relative tolerance of the collinearity test: a vertex is collinear with
/// its neighbours `u, w` when its distance to the line `uw` is at most this
/// times `|uw|` and it lies between them.
pub const COLLINEAR_TOLERANCE: f64 = 1e-9;

/// What the optimizer did.
#[derive(Debug, Default, Clone, Serialize, PartialEq, Eq)]
pub struct OptimizeStats {
    pub faces_in: u64,
    pub faces_out: u64,
    pub vertices_in: u64,
    pub vertices_out: u64,
    /// Regions grown (single faces included).
    pub regions: u64,
    /// Regions re-triangulated.
    pub regions_optimized: u64,
    /// Regions of two or more faces kept as they were: not a disk with
    /// holes, folding or self-intersecting projection, or a failed
    /// re-triangulation.
    pub regions_kept: u64,
    /// Boundary vertices dropped as collinear.
    pub collinear_dropped: u64,
    /// Rounds of stages 3 and 4.
    pub rounds: u64,
}

/// `a / |a|`, or `None` for a zero or non-finite length. It divides by the
/// length: glam's `try_normalize` multiplies by the reciprocal, which
/// rounds differently and could change the regions and the output.
fn unit(a: DVec3) -> Option<DVec3> {
    let l = a.length();
    (l > 0.0 && l.is_finite()).then(|| a / l)
}
fn c3(p: [f64; 3]) -> Coord3D<f64> {
    Coord3D { x: p[0], y: p[1], z: p[2] }
}

/// A free region's boundary: loops of vertex ids, outer loop first.
#[derive(Debug, Clone)]
struct Free {
    loops: Vec<Vec<u32>>,
    u: DVec3,
    v: DVec3,
}

/// Optimizes a triangle mesh with the normal-angle threshold `angle_deg`.
pub fn optimize(positions: &[[f64; 3]], faces: &[[u32; 3]], angle_deg: f64) -> (TriMesh, OptimizeStats) {
    let nf = faces.len();
    let mut stats = OptimizeStats { faces_in: nf as u64, vertices_in: positions.len() as u64, ..Default::default() };
    let pos = |i: u32| positions[i as usize];
    let p3 = |i: u32| DVec3::from(positions[i as usize]);
    let normals: Vec<Option<DVec3>> = faces.iter().map(|f| unit((p3(f[1]) - p3(f[0])).cross(p3(f[2]) - p3(f[0])))).collect();

    // Edge adjacency: the neighbour across each face edge over manifold edges.
    let mut edges: Vec<((u32, u32), u32, u8)> = Vec::with_capacity(3 * nf);
    for (fi, f) in faces.iter().enumerate() {
        for e in 0..3 {
            let (a, b) = (f[e], f[(e + 1) % 3]);
            edges.push(((a.min(b), a.max(b)), fi as u32, e as u8));
        }
    }
    edges.sort_unstable();
    let mut neighbour = vec![[u32::MAX; 3]; nf];
    let mut pinned = vec![false; positions.len()]; // on the mesh boundary or a non-manifold edge
    let mut k = 0;
    while k < edges.len() {
        let mut m = k + 1;
        while m < edges.len() && edges[m].0 == edges[k].0 {
            m += 1;
        }
        let group = &edges[k..m];
        let manifold = group.len() == 2 && {
            let (f0, e0) = (group[0].1 as usize, group[0].2 as usize);
            let (f1, e1) = (group[1].1 as usize, group[1].2 as usize);
            faces[f0][e0] == faces[f1][(e1 + 1) % 3] && faces[f1][e1] == faces[f0][(e0 + 1) % 3] && f0 != f1
        };
        if manifold {
            neighbour[group[0].1 as usize][group[0].2 as usize] = group[1].1;
            neighbour[group[1].1 as usize][group[1].2 as usize] = group[0].1;
        } else {
            pinned[edges[k].0 .0 as usize] = true;
            pinned[edges[k].0 .1 as usize] = true;
        }
        k = m;
    }
    drop(edges);

    // 1. Regions.
    let alpha = angle_deg.to_radians();
    let mut region = vec![u32::MAX; nf];
    let mut members: Vec<Vec<u32>> = Vec::new();
    let mut queue = std::collections::VecDeque::new();
    for seed in 0..nf {
        if region[seed] != u32::MAX {
            continue;
        }
        let r = members.len() as u32;
        region[seed] = r;
        let mut list = vec![seed as u32];
        if let Some(n0) = normals[seed] {
            let (mut axis, mut half) = (n0, 0.0f64);
            let sf = faces[seed].map(pos);
            queue.push_back(seed);
            while let Some(f) = queue.pop_front() {
                for e in 0..3 {
                    let g = neighbour[f][e];
                    if g == u32::MAX || region[g as usize] != u32::MAX {
                        continue;
                    }
                    let Some(m) = normals[g as usize] else { continue };
                    let ok = if alpha == 0.0 {
                        m.dot(n0) > 0.0 && faces[g as usize].iter().all(|&v| orient3d(c3(sf[0]), c3(sf[1]), c3(sf[2]), c3(pos(v))) == 0.0)
                    } else {
                        let phi = axis.dot(m).clamp(-1.0, 1.0).acos();
                        if phi <= half {
                            true
                        } else {
                            let new_half = 0.5 * (half + phi);
                            if 2.0 * new_half <= alpha && phi < std::f64::consts::PI {
                                // Rotate the axis towards m by new_half - half.
                                let d = new_half - half;
                                let s = phi.sin();
                                let w1 = (phi - d).sin() / s;
                                let w2 = d.sin() / s;
                                if let Some(a) = unit(w1 * axis + w2 * m) {
                                    axis = a;
                                    half = new_half;
                                    true
                                } else {
                                    false
                                }
                            } else {
                                false
                            }
                        }
                    };
                    if ok {
                        region[g as usize] = r;
                        list.push(g);
                        queue.push_back(g as usize);
                    }
                }
            }
        }
        members.push(list);
    }
    stats.regions = members.len() as u64;

    // 2. Free regions: loops, topology, projection.
    let mut free: Vec<Option<Free>> = members.iter().map(|m| if m.len() >= 2 { free_region(m, faces, &neighbour, &region, positions) } else { None }).collect();

    // 3 and 4, until stable.
    let out_faces = loop {
        stats.rounds += 1;
        // Where each boundary vertex sits: (region, loop, index) entries.
        let mut around: HashMap<u32, Vec<(u32, u32, u32)>> = HashMap::new();
        for (r, f) in free.iter().enumerate() {
            if let Some(f) = f {
                for (li, l) in f.loops.iter().enumerate() {
                    for (k, &v) in l.iter().enumerate() {
                        around.entry(v).or_default().push((r as u32, li as u32, k as u32));
                    }
                }
            }
        }
        // A vertex on a non-free region's boundary appears in fewer entries
        // than regions around it: count the regions around each vertex.
        let mut regions_at: HashMap<u32, u32> = HashMap::new();
        {
            let mut seen: HashMap<(u32, u32), ()> = HashMap::new();
            for (fi, f) in faces.iter().enumerate() {
                for &v in f {
                    if around.contains_key(&v) && seen.insert((v, region[fi]), ()).is_none() {
                        *regions_at.entry(v).or_default() += 1;
                    }
                }
            }
        }
        let mut dropped: HashMap<u32, ()> = HashMap::new();
        for (&v, entries) in &around {
            if pinned[v as usize] || regions_at[&v] as usize != entries.len() {
                continue;
            }
            let all = entries.iter().all(|&(r, li, k)| {
                let l = &free[r as usize].as_ref().unwrap().loops[li as usize];
                let n = l.len();
                let (u, w) = (l[(k as usize + n - 1) % n], l[(k as usize + 1) % n]);
                collinear(p3(u), p3(v), p3(w))
            });
            if all {
                dropped.insert(v, ());
            }
        }
        // Re-triangulate every free region without the dropped vertices.
        let mut new_faces: Vec<Option<Vec<[u32; 3]>>> = vec![None; free.len()];
        let mut failed: Vec<usize> = Vec::new();
        for (r, f) in free.iter().enumerate() {
            let Some(f) = f else { continue };
            let loops: Vec<Vec<u32>> = f.loops.iter().map(|l| l.iter().copied().filter(|v| !dropped.contains_key(v)).collect()).collect();
            if loops.iter().any(|l| l.len() < 3) {
                failed.push(r);
                continue;
            }
            let uv: Vec<Vec<P2>> = loops.iter().map(|l| l.iter().map(|&v| [p3(v).dot(f.u), p3(v).dot(f.v)]).collect()).collect();
            let refs: Vec<&[P2]> = uv.iter().map(|x| x.as_slice()).collect();
            if first_crossing(&refs).is_some() || signed_area(&uv[0]) <= 0.0 || uv[1..].iter().any(|h| signed_area(h) >= 0.0) {
                failed.push(r);
                continue;
            }
            match triangulate(&uv[0], &refs[1..]) {
                Ok(t) if t.forced == 0 => {
                    let ids: Vec<u32> = loops.iter().flatten().copied().collect();
                    new_faces[r] = Some(t.triangles.iter().map(|tri| tri.map(|x| ids[x as usize])).collect());
                }
                _ => failed.push(r),
            }
        }
        if failed.is_empty() {
            // New diagonals must not duplicate an edge of the output.
            let mut count: HashMap<(u32, u32), u32> = HashMap::new();
            let mut owner: HashMap<(u32, u32), Vec<usize>> = HashMap::new();
            for (r, m) in members.iter().enumerate() {
                let tris: Vec<[u32; 3]> = match &new_faces[r] {
                    Some(t) => t.clone(),
                    None => m.iter().map(|&fi| faces[fi as usize]).collect(),
                };
                for t in tris {
                    for e in 0..3 {
                        let (a, b) = (t[e], t[(e + 1) % 3]);
                        let key = (a.min(b), a.max(b));
                        *count.entry(key).or_default() += 1;
                        if new_faces[r].is_some() {
                            let o = owner.entry(key).or_default();
                            if !o.contains(&r) {
                                o.push(r);
                            }
                        }
                    }
                }
            }
            // Edges over-used only because the input had them are not ours to fix.
            let mut input_count: HashMap<(u32, u32), u32> = HashMap::new();
            for t in faces {
                for e in 0..3 {
                    let (a, b) = (t[e], t[(e + 1) % 3]);
                    *input_count.entry((a.min(b), a.max(b))).or_default() += 1;
                }
            }
            for (key, &c) in &count {
                if c > 2 && c > input_count.get(key).copied().unwrap_or(0) {
                    if let Some(o) = owner.get(key) {
                        failed.extend(o.iter().copied());
                    }
                }
            }
            failed.sort_unstable();
            failed.dedup();
        }
        if failed.is_empty() {
            stats.collinear_dropped = dropped.len() as u64;
            let mut out = Vec::new();
            for (r, m) in members.iter().enumerate() {
                match &new_faces[r] {
                    Some(t) => {
                        stats.regions_optimized += 1;
                        out.extend_from_slice(t);
                    }
                    None => {
                        if m.len() >= 2 {
                            stats.regions_kept += 1;
                        }
                        out.extend(m.iter().map(|&fi| faces[fi as usize]));
                    }
                }
            }
            break out;
        }
        for r in failed {
            free[r] = None;
        }
    };

    // Compact the vertices in input order.
    let mut used = vec![u32::MAX; positions.len()];
    for f in &out_faces {
        for &v in f {
            used[v as usize] = 0;
        }
    }
    let mut mesh = TriMesh::default();
    for (i, u) in used.iter_mut().enumerate() {
        if *u == 0 {
            *u = mesh.positions.len() as u32;
            mesh.positions.push(positions[i]);
        }
    }
    mesh.faces = out_faces.iter().map(|f| f.map(|v| used[v as usize])).collect();
    stats.faces_out = mesh.faces.len() as u64;
    stats.vertices_out = mesh.positions.len() as u64;
    (mesh, stats)
}

/// `v` lies on the segment `uw` (within the tolerance).
fn collinear(u: DVec3, v: DVec3, w: DVec3) -> bool {
    let d = w - u;
    let l2 = d.dot(d);
    if l2 == 0.0 {
        return false;
    }
    let x = d.cross(v - u);
    let t = (v - u).dot(d);
    x.dot(x) <= COLLINEAR_TOLERANCE * COLLINEAR_TOLERANCE * l2 * l2 && t > 0.0 && t < l2
}

/// The boundary of a region if it is free (see the module docs).
fn free_region(members: &[u32], faces: &[[u32; 3]], neighbour: &[[u32; 3]], region: &[u32], positions: &[[f64; 3]]) -> Option<Free> {
    let r = region[members[0] as usize];
    let mut next: HashMap<u32, u32> = HashMap::new();
    let mut verts: HashMap<u32, ()> = HashMap::new();
    let mut boundary = 0usize;
    let mut area = DVec3::ZERO;
    for &fi in members {
        let f = faces[fi as usize];
        for &v in &f {
            verts.insert(v, ());
        }
        let [a, b, c] = f.map(|i| DVec3::from(positions[i as usize]));
        area += (b - a).cross(c - a);
        for e in 0..3 {
            let g = neighbour[fi as usize][e];
            if g == u32::MAX || region[g as usize] != r {
                boundary += 1;
                if next.insert(f[e], f[(e + 1) % 3]).is_some() {
                    return None; // a pinched boundary vertex
                }
            }
        }
    }
    // Loops.
    let mut loops: Vec<Vec<u32>> = Vec::new();
    let mut seen: HashMap<u32, ()> = HashMap::new();
    let mut starts: Vec<u32> = next.keys().copied().collect();
    starts.sort_unstable();
    for s in starts {
        if seen.contains_key(&s) {
            continue;
        }
        let mut l = Vec::new();
        let mut v = s;
        loop {
            seen.insert(v, ());
            l.push(v);
            v = *next.get(&v)?;
            if v == s {
                break;
            }
            if seen.contains_key(&v) {
                return None;
            }
        }
        loops.push(l);
    }
    // Disk with holes: V - E + F = 2 - loops.
    let (nv, nf) = (verts.len() as i64, members.len() as i64);
    let ne = (3 * nf + boundary as i64) / 2;
    if nv - ne + nf != 2 - loops.len() as i64 || loops.is_empty() {
        return None;
    }
    // Projection on the Newell plane keeps every face counter-clockwise.
    let n = unit(area)?;
    let k = (0..3).min_by(|&a, &b| n[a].abs().total_cmp(&n[b].abs())).unwrap();
    let mut e = DVec3::ZERO;
    e[k] = 1.0;
    let u = unit(n.cross(e))?;
    let v = n.cross(u);
    let proj = |i: u32| -> P2 {
        let p = DVec3::from(positions[i as usize]);
        [p.dot(u), p.dot(v)]
    };
    for &fi in members {
        let f = faces[fi as usize];
        if orient(proj(f[0]), proj(f[1]), proj(f[2])) <= 0.0 {
            return None;
        }
    }
    let uv: Vec<Vec<P2>> = loops.iter().map(|l| l.iter().map(|&i| proj(i)).collect()).collect();
    let refs: Vec<&[P2]> = uv.iter().map(|x| x.as_slice()).collect();
    if first_crossing(&refs).is_some() {
        return None;
    }
    let outer: Vec<usize> = (0..uv.len()).filter(|&i| signed_area(&uv[i]) > 0.0).collect();
    if outer.len() != 1 {
        return None;
    }
    let o = outer[0];
    loops.swap(0, o);
    Some(Free { loops, u, v })
}

#[cfg(test)]
mod tests {
    use super::*;

    use mint_testkit::flat_grid as grid;

    #[test]
    fn a_flat_grid_keeps_its_boundary_vertices() {
        // The grid's border is the mesh boundary: its vertices are kept, the
        // interior ones go. 4n border vertices give 4n - 2 triangles.
        let (p, f) = grid(6);
        let (m, s) = optimize(&p, &f, 0.0);
        assert_eq!((s.regions, s.regions_optimized), (1, 1));
        assert_eq!(m.positions.len(), 24);
        assert_eq!(m.faces.len(), 22);
        assert!(m.positions.iter().all(|q| q[2] == 0.0));
    }

    #[test]
    fn a_subdivided_cube_becomes_twelve_triangles() {
        // Each face a 3 x 3 grid: 6 * 18 = 108 triangles, closed. Edge-interior
        // vertices are collinear in both regions around them and go.
        let n = 3;
        let mut pos: Vec<[f64; 3]> = Vec::new();
        let mut idx: HashMap<[i64; 3], u32> = HashMap::new();
        let mut faces = Vec::new();
        let mut vid = |p: [i64; 3], pos: &mut Vec<[f64; 3]>| -> u32 {
            *idx.entry(p).or_insert_with(|| {
                pos.push(p.map(|x| x as f64));
                pos.len() as u32 - 1
            })
        };
        for axis in 0..3 {
            for side in [0i64, n] {
                let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
                for j in 0..n {
                    for i in 0..n {
                        let q = |di: i64, dj: i64| {
                            let mut p = [0i64; 3];
                            p[axis] = side;
                            p[a] = i + di;
                            p[b] = j + dj;
                            p
                        };
                        let c = [q(0, 0), q(1, 0), q(1, 1), q(0, 1)].map(|p| vid(p, &mut pos));
                        // Outward: counter-clockwise in (a, b) faces +axis.
                        if side == n {
                            faces.push([c[0], c[1], c[2]]);
                            faces.push([c[0], c[2], c[3]]);
                        } else {
                            faces.push([c[0], c[2], c[1]]);
                            faces.push([c[0], c[3], c[2]]);
                        }
                    }
                }
            }
        }
        let (m, s) = optimize(&pos, &faces, 5.0);
        assert_eq!((s.faces_in, s.faces_out, s.regions_optimized), (108, 12, 6));
        assert_eq!(m.positions.len(), 8);
        let c = mint_testkit::topology::check_closed_oriented(&m).unwrap();
        assert_eq!(c.volume, 27.0);
    }
}
