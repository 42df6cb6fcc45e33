//! Mesh surgery used by zippering, on plain `(positions, faces)` arrays:
//! compaction, making a triangle set a 2-manifold ([`make_manifold`]),
//! boundary loops, filling small holes ([`fill_small_holes`]), and removing
//! small triangles by vertex deletion ([`remove_small_triangles`]).
//!
//! Connectivity is rebuilt from the face list each time a function needs
//! it, as a map from directed half-edges `(from, to)` to faces; every
//! decision is topological (vertex ids), never a comparison of positions.
//! Faces are oriented consistently throughout: a new face always takes the
//! reverse of the half-edges it closes.

use crate::scan_mesh::face_normal;
use glam::DVec3;
use rustc_hash::FxHashMap as HashMap;

/// Drops unused vertices; returns the old → new map (`u32::MAX` for dropped).
pub fn compact(positions: &mut Vec<[f64; 3]>, faces: &mut [[u32; 3]]) -> Vec<u32> {
    let mut map = vec![u32::MAX; positions.len()];
    let mut out = Vec::new();
    for f in faces.iter_mut() {
        for v in f.iter_mut() {
            if map[*v as usize] == u32::MAX {
                map[*v as usize] = out.len() as u32;
                out.push(positions[*v as usize]);
            }
            *v = map[*v as usize];
        }
    }
    *positions = out;
    map
}

/// Makes the faces a 2-manifold with boundary: drops faces with a repeated
/// corner, faces repeating a directed half-edge of an earlier face (an
/// orientation clash or a third face on an edge; the later face goes), and
/// then splits every vertex whose faces form more than one fan into one
/// vertex per fan (new vertices are appended, copies of the position).
/// Returns `(faces dropped, vertices split off)`.
pub fn make_manifold(positions: &mut Vec<[f64; 3]>, faces: &mut Vec<[u32; 3]>) -> (usize, usize) {
    let before = faces.len();
    let mut half: HashMap<(u32, u32), u32> = HashMap::with_capacity_and_hasher(faces.len() * 3, Default::default());
    let mut undirected: HashMap<(u32, u32), u8> = HashMap::with_capacity_and_hasher(faces.len() * 3, Default::default());
    let mut kept = Vec::with_capacity(faces.len());
    for f in faces.iter() {
        if f[0] == f[1] || f[1] == f[2] || f[0] == f[2] {
            continue;
        }
        let hs = [(f[0], f[1]), (f[1], f[2]), (f[2], f[0])];
        if hs.iter().any(|h| half.contains_key(h) || undirected.get(&key(h.0, h.1)).copied().unwrap_or(0) >= 2) {
            continue;
        }
        for h in hs {
            half.insert(h, kept.len() as u32);
            *undirected.entry(key(h.0, h.1)).or_insert(0) += 1;
        }
        kept.push(*f);
    }
    let dropped = before - kept.len();
    *faces = kept;
    // Fans: faces around a vertex connected through shared edges.
    let mut corners: Vec<Vec<(u32, usize)>> = vec![Vec::new(); positions.len()];
    for (fi, f) in faces.iter().enumerate() {
        for k in 0..3 {
            corners[f[k] as usize].push((fi as u32, k));
        }
    }
    let mut split = 0;
    for v in 0..positions.len() {
        let cs = &corners[v];
        if cs.len() < 2 {
            continue;
        }
        // Union-find over the corners of v: two faces are in one fan when
        // they share an edge through v.
        let mut parent: Vec<usize> = (0..cs.len()).collect();
        fn find(p: &mut [usize], mut i: usize) -> usize {
            while p[i] != i {
                p[i] = p[p[i]];
                i = p[i];
            }
            i
        }
        let mut by_other: HashMap<u32, usize> = HashMap::default();
        for (ci, &(fi, k)) in cs.iter().enumerate() {
            let f = faces[fi as usize];
            for other in [f[(k + 1) % 3], f[(k + 2) % 3]] {
                if let Some(&cj) = by_other.get(&other) {
                    let (a, b) = (find(&mut parent, ci), find(&mut parent, cj));
                    parent[a] = b;
                } else {
                    by_other.insert(other, ci);
                }
            }
        }
        let roots: Vec<usize> = (0..cs.len()).map(|i| find(&mut parent, i)).collect();
        let mut first_root = None;
        let mut new_id: HashMap<usize, u32> = HashMap::default();
        for (ci, &(fi, k)) in cs.iter().enumerate() {
            let r = roots[ci];
            if first_root.is_none() {
                first_root = Some(r);
            }
            if Some(r) == first_root {
                continue;
            }
            let id = *new_id.entry(r).or_insert_with(|| {
                positions.push(positions[v]);
                split += 1;
                (positions.len() - 1) as u32
            });
            faces[fi as usize][k] = id;
        }
    }
    (dropped, split)
}

#[inline]
pub(crate) fn key(a: u32, b: u32) -> (u32, u32) {
    (a.min(b), a.max(b))
}

/// Drops connected components (through shared edges) of fewer than
/// `min_faces` faces; returns the number of faces dropped.
pub fn remove_small_components(faces: &mut Vec<[u32; 3]>, min_faces: usize) -> usize {
    let mut parent: Vec<u32> = (0..faces.len() as u32).collect();
    fn find(p: &mut [u32], mut i: u32) -> u32 {
        while p[i as usize] != i {
            p[i as usize] = p[p[i as usize] as usize];
            i = p[i as usize];
        }
        i
    }
    let mut by_edge: HashMap<(u32, u32), u32> = HashMap::with_capacity_and_hasher(faces.len() * 3 / 2, Default::default());
    for (i, f) in faces.iter().enumerate() {
        for k in 0..3 {
            let e = key(f[k], f[(k + 1) % 3]);
            match by_edge.get(&e) {
                Some(&j) => {
                    let (a, b) = (find(&mut parent, i as u32), find(&mut parent, j));
                    parent[a as usize] = b;
                }
                None => {
                    by_edge.insert(e, i as u32);
                }
            }
        }
    }
    let roots: Vec<u32> = (0..faces.len() as u32).map(|i| find(&mut parent, i)).collect();
    let mut size: HashMap<u32, usize> = HashMap::default();
    for &r in &roots {
        *size.entry(r).or_insert(0) += 1;
    }
    let before = faces.len();
    let mut i = 0;
    faces.retain(|_| {
        i += 1;
        size[&roots[i - 1]] >= min_faces
    });
    before - faces.len()
}

/// Boundary loops of a 2-manifold mesh, each as its vertices in the order
/// of the boundary half-edges (the mesh on their left).
pub fn boundary_loops(faces: &[[u32; 3]]) -> Vec<Vec<u32>> {
    let mut half: HashMap<(u32, u32), ()> = HashMap::with_capacity_and_hasher(faces.len() * 3, Default::default());
    for f in faces {
        for k in 0..3 {
            half.insert((f[k], f[(k + 1) % 3]), ());
        }
    }
    let mut next: HashMap<u32, u32> = HashMap::default();
    for &(a, b) in half.keys() {
        if !half.contains_key(&(b, a)) {
            next.insert(a, b);
        }
    }
    let mut starts: Vec<u32> = next.keys().copied().collect();
    starts.sort_unstable();
    let mut seen: HashMap<u32, ()> = HashMap::default();
    let mut loops = Vec::new();
    for s in starts {
        if seen.contains_key(&s) {
            continue;
        }
        let mut l = vec![s];
        seen.insert(s, ());
        let mut v = next[&s];
        while v != s {
            if seen.insert(v, ()).is_some() {
                break;
            }
            l.push(v);
            match next.get(&v) {
                Some(&w) => v = w,
                None => break,
            }
        }
        loops.push(l);
    }
    loops
}

/// Fills every boundary loop of at most `max_edges` edges by ear cutting:
/// repeatedly the ear whose new edge is shortest among those that do not
/// already exist. Returns the number of loops filled.
pub fn fill_small_holes(positions: &[[f64; 3]], faces: &mut Vec<[u32; 3]>, max_edges: usize) -> usize {
    let mut undirected: HashMap<(u32, u32), u8> = HashMap::with_capacity_and_hasher(faces.len() * 3, Default::default());
    for f in faces.iter() {
        for k in 0..3 {
            *undirected.entry(key(f[k], f[(k + 1) % 3])).or_insert(0) += 1;
        }
    }
    let edge_len = |a: u32, b: u32| DVec3::from(positions[a as usize]).distance(DVec3::from(positions[b as usize]));
    let mut filled = 0;
    for mut l in boundary_loops(faces) {
        if l.len() < 3 || l.len() > max_edges {
            continue;
        }
        let mut new_faces = Vec::new();
        let mut ok = true;
        while l.len() > 3 {
            let n = l.len();
            let best = (0..n)
                .filter(|&i| {
                    let (p, q) = (l[(i + n - 1) % n], l[(i + 1) % n]);
                    !undirected.contains_key(&key(p, q))
                })
                .min_by(|&i, &j| {
                    let li = edge_len(l[(i + n - 1) % n], l[(i + 1) % n]);
                    let lj = edge_len(l[(j + n - 1) % n], l[(j + 1) % n]);
                    li.total_cmp(&lj)
                });
            let Some(i) = best else {
                ok = false;
                break;
            };
            let (p, c, q) = (l[(i + n - 1) % n], l[i], l[(i + 1) % n]);
            new_faces.push([c, p, q]);
            undirected.insert(key(p, q), 1);
            l.remove(i);
        }
        if !ok {
            continue;
        }
        new_faces.push([l[1], l[0], l[2]]);
        for f in &new_faces {
            for k in 0..3 {
                *undirected.entry(key(f[k], f[(k + 1) % 3])).or_insert(0) += 1;
            }
        }
        faces.extend(new_faces);
        filled += 1;
    }
    filled
}

/// Removes triangles with an altitude below `min_altitude` by deleting the
/// vertex opposite their longest side and filling its hole with a fan from
/// one of its neighbours (a half-edge collapse): the neighbour is the first,
/// nearest first, for which the link condition holds (the result stays a
/// 2-manifold) and no remaining face turns by more than 60°. Boundary
/// vertices are kept. Returns the number of vertices deleted (their
/// positions stay, unused, until [`compact`]).
pub fn remove_small_triangles(positions: &[[f64; 3]], faces: &mut Vec<[u32; 3]>, min_altitude: f64) -> usize {
    let dist = |a: u32, b: u32| DVec3::from(positions[a as usize]).distance(DVec3::from(positions[b as usize]));
    let mut removed = 0;
    for _round in 0..4 {
        let mut vf: Vec<Vec<u32>> = vec![Vec::new(); positions.len()];
        for (i, f) in faces.iter().enumerate() {
            for &v in f {
                vf[v as usize].push(i as u32);
            }
        }
        let mut half: HashMap<(u32, u32), u32> = HashMap::with_capacity_and_hasher(faces.len() * 3, Default::default());
        for (i, f) in faces.iter().enumerate() {
            for k in 0..3 {
                half.insert((f[k], f[(k + 1) % 3]), i as u32);
            }
        }
        let is_boundary = |v: u32, vf: &Vec<Vec<u32>>, faces: &Vec<[u32; 3]>, half: &HashMap<(u32, u32), u32>| {
            vf[v as usize].iter().any(|&fi| {
                let f = faces[fi as usize];
                (0..3).any(|k| !half.contains_key(&(f[(k + 1) % 3], f[k])))
            })
        };
        let mut dead = vec![false; faces.len()];
        let mut touched = vec![false; positions.len()];
        let mut count = 0;
        for fi in 0..faces.len() {
            if dead[fi] {
                continue;
            }
            let f = faces[fi];
            let area2 = face_normal(positions, f).length();
            let lens = [dist(f[1], f[2]), dist(f[2], f[0]), dist(f[0], f[1])];
            let (k, &longest) = lens.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)).unwrap();
            if longest == 0.0 || area2 / longest >= min_altitude {
                continue;
            }
            let v = f[k];
            if touched[v as usize] || is_boundary(v, &vf, faces, &half) {
                continue;
            }
            let around: Vec<u32> = vf[v as usize].iter().copied().filter(|&g| !dead[g as usize]).collect();
            if around.iter().any(|&g| faces[g as usize].iter().any(|&w| touched[w as usize])) {
                continue;
            }
            let mut link: Vec<u32> = around.iter().flat_map(|&g| faces[g as usize]).filter(|&w| w != v).collect();
            link.sort_unstable();
            link.dedup();
            let mut cands = link.clone();
            cands.sort_by(|&a, &b| dist(a, v).total_cmp(&dist(b, v)));
            'cand: for u in cands {
                // Link condition: common neighbours of u and v are exactly the
                // two vertices opposite the edge uv.
                let mut lu: Vec<u32> = vf[u as usize].iter().filter(|&&g| !dead[g as usize]).flat_map(|&g| faces[g as usize]).filter(|&w| w != u).collect();
                lu.sort_unstable();
                lu.dedup();
                let common = link.iter().filter(|w| lu.binary_search(w).is_ok()).count();
                let opposite = around.iter().filter(|&&g| faces[g as usize].contains(&u)).count();
                if opposite != 2 || common != 2 {
                    continue;
                }
                for &g in &around {
                    let gf = faces[g as usize];
                    if gf.contains(&u) {
                        continue;
                    }
                    let old = face_normal(positions, gf).normalize_or_zero();
                    let nf = gf.map(|w| if w == v { u } else { w });
                    let new = face_normal(positions, nf).normalize_or_zero();
                    // No fold-over; a face with no normal (zero area)
                    // cannot fold and must not block its own removal.
                    if old != DVec3::ZERO && old.dot(new) < 0.5 {
                        continue 'cand;
                    }
                }
                for &g in &around {
                    let gf = faces[g as usize];
                    if gf.contains(&u) {
                        dead[g as usize] = true;
                    } else {
                        faces[g as usize] = gf.map(|w| if w == v { u } else { w });
                    }
                }
                touched[v as usize] = true;
                for &w in &link {
                    touched[w as usize] = true;
                }
                count += 1;
                break;
            }
        }
        let mut i = 0;
        faces.retain(|_| {
            i += 1;
            !dead[i - 1]
        });
        removed += count;
        if count == 0 {
            break;
        }
    }
    removed
}

/// The smallest altitude of a triangle.
pub fn min_altitude(p: [[f64; 3]; 3]) -> f64 {
    let p = p.map(DVec3::from);
    let area2 = (p[1] - p[0]).cross(p[2] - p[0]).length();
    let longest = p[0].distance(p[1]).max(p[1].distance(p[2])).max(p[2].distance(p[0]));
    if longest == 0.0 {
        0.0
    } else {
        area2 / longest
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use mint_testkit::flat_grid as grid;

    #[test]
    fn a_bowtie_vertex_is_split_and_a_third_face_dropped() {
        // Two triangles touching at vertex 0 only, plus a face repeating a half-edge.
        let mut p = vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]];
        let mut f = vec![[0, 1, 2], [0, 3, 4], [0, 1, 4]];
        let (dropped, split) = make_manifold(&mut p, &mut f);
        assert_eq!((dropped, split), (1, 1));
        assert_eq!(f, vec![[0, 1, 2], [5, 3, 4]]);
        assert_eq!(p.len(), 6);
    }

    #[test]
    fn a_hole_of_four_edges_is_filled_and_the_grid_has_one_loop() {
        let (p, mut f) = grid(3);
        // Remove the two triangles of the middle square: a 4-edge hole.
        f.retain(|t| !(t.contains(&5) && t.contains(&10)));
        assert_eq!(boundary_loops(&f).len(), 2);
        let filled = fill_small_holes(&p, &mut f, 4);
        assert_eq!(filled, 1);
        assert_eq!(f.len(), 18);
        let loops = boundary_loops(&f);
        assert_eq!(loops.len(), 1);
        assert_eq!(loops[0].len(), 12);
        let (mut p2, mut f2) = (p.clone(), f.clone());
        assert_eq!(make_manifold(&mut p2, &mut f2), (0, 0));
    }

    #[test]
    fn a_sliver_is_removed_by_collapsing_its_apex() {
        let (mut p, mut f) = grid(4);
        // Push vertex (2,2) almost onto the diagonal... of its neighbour square:
        // move it next to (3,2) so triangles around it become thin.
        p[12] = [2.98, 2.0, 0.0];
        let n0 = f.len();
        let r = remove_small_triangles(&p, &mut f, 0.05);
        assert_eq!(r, 1);
        assert_eq!(f.len(), n0 - 2);
        assert!(f.iter().all(|t| !t.contains(&12)));
        let (mut p2, mut f2) = (p.clone(), f.clone());
        assert_eq!(make_manifold(&mut p2, &mut f2), (0, 0));
        assert_eq!(boundary_loops(&f).len(), 1);
    }
}
