//! Vertex attribute transfer: each vertex of one mesh takes the colour of
//! another mesh at its nearest point (the corner colours of the nearest
//! triangle, mixed by the barycentric coordinates of the closest point),
//! the ideal transfer against which colour carrying is measured, and how
//! `mint decimate` and `mint simplify` colour what the geometric quadric
//! collapse leaves.
//!
//! Deterministic: the nearest triangle comes from [`TriangleBvh::nearest`]
//! (a fixed traversal); vertices are independent, done in fixed chunks.

use crate::bvh::TriangleBvh;
use crate::error::MeshError;
use glam::DVec3;
use rayon::prelude::*;

/// The colour of mesh (`positions`, `faces`, `colours` per vertex) at the
/// point nearest to each of `points`.
pub fn colours_at_nearest(positions: &[[f64; 3]], faces: &[[u32; 3]], colours: &[[u8; 4]], points: &[[f64; 3]]) -> Result<Vec<[u8; 4]>, MeshError> {
    let bvh = TriangleBvh::new(positions, faces)?;
    Ok(points
        .par_chunks(4096)
        .flat_map_iter(|chunk| {
            chunk.iter().map(|&p| {
                let (_, q, f) = bvh.nearest(p);
                let t = faces[f as usize];
                let w = barycentric(q, t.map(|v| positions[v as usize]));
                std::array::from_fn(|k| {
                    let c = w[0] * colours[t[0] as usize][k] as f64 + w[1] * colours[t[1] as usize][k] as f64 + w[2] * colours[t[2] as usize][k] as f64;
                    c.round().clamp(0.0, 255.0) as u8
                })
            })
        })
        .collect())
}

/// Barycentric weights of `q` (a point of the triangle) in triangle `t`;
/// a degenerate triangle gives its nearest corner's weight one.
fn barycentric(q: [f64; 3], t: [[f64; 3]; 3]) -> [f64; 3] {
    let [a, b, c] = t.map(DVec3::from);
    let q = DVec3::from(q);
    let (v0, v1, v2) = (b - a, c - a, q - a);
    let (d00, d01, d11, d20, d21) = (v0.dot(v0), v0.dot(v1), v1.dot(v1), v2.dot(v0), v2.dot(v1));
    let den = d00 * d11 - d01 * d01;
    if !(den.abs() > 0.0) || !den.is_finite() {
        let d = [q.distance_squared(a), q.distance_squared(b), q.distance_squared(c)];
        let i = (0..3).min_by(|&x, &y| d[x].total_cmp(&d[y])).unwrap();
        let mut w = [0.0; 3];
        w[i] = 1.0;
        return w;
    }
    let v = ((d11 * d20 - d01 * d21) / den).clamp(0.0, 1.0);
    let w = ((d00 * d21 - d01 * d20) / den).clamp(0.0, 1.0 - v);
    [1.0 - v - w, v, w]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_point_takes_the_colour_where_it_projects() {
        let pos = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let cols = [[255, 0, 0, 255], [0, 255, 0, 255], [0, 0, 255, 255]];
        let got = colours_at_nearest(&pos, &[[0, 1, 2]], &cols, &[[0.0, 0.0, 5.0], [0.5, 0.5, -1.0], [0.25, 0.25, 0.1], [9.0, -3.0, 0.0]]).unwrap();
        assert_eq!(got, vec![[255, 0, 0, 255], [0, 128, 128, 255], [128, 64, 64, 255], [0, 255, 0, 255]]);
    }
}
