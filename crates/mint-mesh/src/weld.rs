//! [`weld`]: merges vertices at identical positions, as MeshLab and trimesh
//! do on import. Formats like STL store every triangle with its own three
//! corners, and OBJ files split vertices at texture seams; judged by their
//! indices such meshes have a boundary along every edge. Welding compares
//! positions exactly (bit for bit, with -0.0 equal to 0.0), never within a
//! tolerance, so it joins only what the file itself says is one point.
//! Non-finite positions are never welded.
//!
//! Memory: one sort of `(position, index)` pairs, 32 bytes per vertex.

/// The key two positions weld by: their bits, with -0.0 taken as 0.0.
/// Only finite positions weld (callers check [`f64::is_finite`]).
#[inline]
pub fn position_key(p: &[f64; 3]) -> [u64; 3] {
    p.map(|c| if c == 0.0 { 0u64 } else { c.to_bits() })
}

/// Welds `positions` in place: returns the new positions (the first vertex
/// of each group of identical positions, in their original order) and
/// rewrites `faces` to them. Returns how many vertices were merged away.
pub fn weld(positions: &mut Vec<[f64; 3]>, faces: &mut [[u32; 3]]) -> u64 {
    let n = positions.len();
    let key = |p: &[f64; 3]| position_key(p);
    let mut order: Vec<u32> = (0..n as u32).collect();
    order.sort_unstable_by_key(|&i| (key(&positions[i as usize]), i));
    // canonical[i]: the smallest index with i's position.
    let mut canonical: Vec<u32> = (0..n as u32).collect();
    let mut g = 0;
    while g < n {
        let first = order[g];
        let p = positions[first as usize];
        let mut h = g + 1;
        if p.iter().all(|c| c.is_finite()) {
            while h < n && key(&positions[order[h] as usize]) == key(&p) {
                canonical[order[h] as usize] = first;
                h += 1;
            }
        }
        g = h;
    }
    drop(order);
    // New ids: canonical vertices in their original order.
    let mut new_id = vec![u32::MAX; n];
    let mut kept = 0u32;
    for i in 0..n {
        if canonical[i] == i as u32 {
            new_id[i] = kept;
            positions[kept as usize] = positions[i];
            kept += 1;
        }
    }
    for f in faces.iter_mut() {
        for v in f.iter_mut() {
            *v = new_id[canonical[*v as usize] as usize];
        }
    }
    positions.truncate(kept as usize);
    (n - kept as usize) as u64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_triangle_soup_cube_welds_to_eight_vertices() {
        let corners = |i: u32| [(i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64];
        let quads = [[0u32, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
        let mut positions = Vec::new();
        let mut faces = Vec::new();
        for q in quads {
            for t in [[q[0], q[1], q[2]], [q[0], q[2], q[3]]] {
                let base = positions.len() as u32;
                positions.extend(t.map(corners));
                faces.push([base, base + 1, base + 2]);
            }
        }
        assert_eq!(positions.len(), 36);
        let merged = weld(&mut positions, &mut faces);
        assert_eq!((merged, positions.len()), (28, 8));
        let r = crate::check(&positions, &faces);
        assert!(r.watertight, "{r:?}");
    }

    #[test]
    fn signed_zeros_weld_and_nans_do_not() {
        let mut p = vec![[0.0, 1.0, 2.0], [-0.0, 1.0, 2.0], [f64::NAN, 0.0, 0.0], [f64::NAN, 0.0, 0.0], [0.0, 1.0, 2.0 + 1e-15]];
        let mut f = vec![[0, 1, 4], [2, 3, 4]];
        assert_eq!(weld(&mut p, &mut f), 1);
        assert_eq!(p.len(), 4);
        assert_eq!(f, vec![[0, 0, 3], [1, 2, 3]]);
    }
}
