//! Random convex polyhedra for property tests: an incremental 3D convex hull
//! whose visibility test is the exact orient3d, so it always returns a closed,
//! outward-oriented triangle mesh even for points snapped to a lattice (many
//! coplanar and collinear points). Points that are not strictly outside the
//! current hull are skipped, which keeps the result a valid convex polyhedron.

use mint_core::TriMesh;
use robust::{orient3d, Coord3D};

fn c(p: [f64; 3]) -> Coord3D<f64> {
    Coord3D { x: p[0], y: p[1], z: p[2] }
}

/// > 0 when `q` is strictly on the outer side of face (a, b, c) (CCW seen from outside).
fn outside(a: [f64; 3], b: [f64; 3], cc: [f64; 3], q: [f64; 3]) -> bool {
    // robust::orient3d > 0 when q is below the plane of a, b, c (CCW from above),
    // i.e. opposite to the right-hand normal.
    orient3d(c(a), c(b), c(cc), c(q)) < 0.0
}

/// The convex hull of `points`, or `None` if they are (nearly) flat: fewer
/// than four points in general position.
pub fn convex_hull(points: &[[f64; 3]]) -> Option<TriMesh> {
    let n = points.len();
    // Initial tetrahedron from four affinely independent points.
    let i0 = 0;
    let i1 = (1..n).find(|&i| points[i] != points[i0])?;
    let i2 = (1..n).find(|&i| {
        let (a, b, q) = (points[i0], points[i1], points[i]);
        let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let v = [q[0] - a[0], q[1] - a[1], q[2] - a[2]];
        let cr = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
        cr.iter().any(|x| x.abs() > 1e-12)
    })?;
    let i3 = (1..n).find(|&i| orient3d(c(points[i0]), c(points[i1]), c(points[i2]), c(points[i])) != 0.0)?;
    let mut faces: Vec<[usize; 3]> = if outside(points[i0], points[i1], points[i2], points[i3]) {
        vec![[i0, i2, i1], [i0, i1, i3], [i1, i2, i3], [i2, i0, i3]]
    } else {
        vec![[i0, i1, i2], [i0, i3, i1], [i1, i3, i2], [i2, i3, i0]]
    };
    for (q, &p) in points.iter().enumerate() {
        if [i0, i1, i2, i3].contains(&q) {
            continue;
        }
        let visible: Vec<bool> = faces.iter().map(|f| outside(points[f[0]], points[f[1]], points[f[2]], p)).collect();
        if !visible.iter().any(|&v| v) {
            continue;
        }
        // Horizon: directed edges of visible faces whose twin is on a hidden face.
        let mut edges = std::collections::HashSet::new();
        for (f, &v) in faces.iter().zip(&visible) {
            if v {
                for k in 0..3 {
                    edges.insert((f[k], f[(k + 1) % 3]));
                }
            }
        }
        let mut kept: Vec<[usize; 3]> = faces.iter().zip(&visible).filter(|(_, &v)| !v).map(|(f, _)| *f).collect();
        for &(a, b) in &edges {
            if !edges.contains(&(b, a)) {
                kept.push([a, b, q]);
            }
        }
        faces = kept;
    }
    // Compact the vertices actually used.
    let mut map = vec![u32::MAX; n];
    let mut mesh = TriMesh::default();
    for f in &faces {
        for &v in f {
            if map[v] == u32::MAX {
                map[v] = mesh.positions.len() as u32;
                mesh.positions.push(points[v]);
            }
        }
    }
    mesh.faces = faces.iter().map(|f| f.map(|v| map[v])).collect();
    Some(mesh)
}

/// Triangles of a mesh as position triples.
pub fn soup(m: &TriMesh) -> Vec<[[f64; 3]; 3]> {
    m.faces.iter().map(|f| f.map(|i| m.positions[i as usize])).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::topology::check_closed_oriented;

    #[test]
    fn a_cube_of_lattice_points_gives_a_closed_hull() {
        let mut pts = Vec::new();
        for x in 0..3 {
            for y in 0..3 {
                for z in 0..3 {
                    pts.push([x as f64, y as f64, z as f64]);
                }
            }
        }
        let m = convex_hull(&pts).unwrap();
        let r = check_closed_oriented(&m).unwrap();
        assert!((r.volume - 8.0).abs() < 1e-12);
    }

    #[test]
    fn random_points_give_closed_hulls() {
        let mut rng = crate::Rng(7);
        for _ in 0..50 {
            let pts: Vec<[f64; 3]> = (0..40).map(|_| [rng.f64(), rng.f64(), rng.f64()]).collect();
            let m = convex_hull(&pts).unwrap();
            let r = check_closed_oriented(&m).unwrap();
            assert!(r.volume > 0.0);
        }
    }
}
