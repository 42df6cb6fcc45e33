//! Vertex normals: the one place that says what a vertex's normal is (the
//! sum of its faces' cross products, so each face counts by its area, made
//! unit). Used by the quadric collapse's lifted planes and by the range
//! scans' consensus and scan meshes.

use glam::DVec3;

/// Unit area-weighted vertex normals (zero for unused vertices and where
/// the faces' normals cancel), from positions as `[f64; 3]` or `DVec3`.
pub fn vertex_normals<P: Copy + Into<DVec3>>(positions: &[P], faces: &[[u32; 3]]) -> Vec<DVec3> {
    let mut n = vec![DVec3::ZERO; positions.len()];
    for f in faces {
        let [a, b, c] = f.map(|i| positions[i as usize].into());
        let fnrm = (b - a).cross(c - a);
        for &i in f {
            n[i as usize] += fnrm;
        }
    }
    n.into_iter().map(DVec3::normalize_or_zero).collect()
}
