//! Analytic stacks: a truncated cone of circles and a column of ellipses that
//! twist and grow. With caps, both methods must give a closed, consistently
//! oriented surface within 1% of the bounding-box diagonal of the analytic
//! solid (measured both ways with Metro-style sampling against a fine
//! reference mesh of the solid).
use super::util::{ellipse, max_and_mean_distance, parse, profile_text, reference_tube};
use mint_contour::angle::{self, AngleOptions};
use mint_contour::mc::{self, McOptions};
use mint_core::TriMesh;
use mint_testkit::topology::check_closed_oriented;

const SECTIONS: usize = 81;
const HEIGHT: f64 = 2.0;

fn cone(z: f64, n: usize) -> Vec<[f64; 3]> {
    ellipse([0.1, -0.2], 1.0 - 0.25 * z, 1.0 - 0.25 * z, 0.0, z, n)
}

fn twisted(z: f64, n: usize) -> Vec<[f64; 3]> {
    let s = 1.0 + 0.3 * z;
    ellipse([0.0, 0.0], 1.2 * s, 0.6 * s, 0.5 * z, z, n)
}

fn stack(ring: &dyn Fn(f64, usize) -> Vec<[f64; 3]>, n: usize) -> String {
    let sections: Vec<Vec<Vec<[f64; 3]>>> = (0..SECTIONS).map(|k| vec![ring(HEIGHT * k as f64 / (SECTIONS - 1) as f64, n)]).collect();
    profile_text(&sections)
}

fn check_both(name: &str, ring: &dyn Fn(f64, usize) -> Vec<[f64; 3]>) {
    let (frame, sections) = parse(&stack(ring, 96));
    let reference = reference_tube(ring, 0.0, HEIGHT, 801, 720);
    // Marching cubes.
    let mut m = TriMesh::default();
    let st = mc::reconstruct(frame, &sections, McOptions { cubes: 64, caps: true, ..Default::default() }, &mut m).unwrap();
    assert_eq!(st.non_canonical_cells, 0, "{name} mc");
    let c = check_closed_oriented(&m).unwrap_or_else(|e| panic!("{name} mc: {e}"));
    assert_eq!((c.components, c.genus), (1, 0), "{name} mc");
    let (max, mean_ab, mean_ba) = max_and_mean_distance(&m, &reference, 200_000);
    eprintln!("{name} mc: {} faces, max distance {max:.3e}, mean {mean_ab:.3e} / {mean_ba:.3e} of the diagonal", m.faces.len());
    assert!(max <= 0.01, "{name} mc: max distance {max}");
    // Angle criterion.
    let mut a = TriMesh::default();
    let st = angle::reconstruct(&sections, AngleOptions { caps: true, ..Default::default() }, &mut a).unwrap();
    assert_eq!((st.tubes, st.caps, st.forced_ears), ((SECTIONS - 1) as u64, 2, 0), "{name} angle");
    // n - 2 cap triangles at each end, 2n per tube.
    assert_eq!(a.faces.len(), (SECTIONS - 1) * 2 * 96 + 2 * 94, "{name} angle");
    let c = check_closed_oriented(&a).unwrap_or_else(|e| panic!("{name} angle: {e}"));
    assert_eq!((c.components, c.genus), (1, 0), "{name} angle");
    let (max, mean_ab, mean_ba) = max_and_mean_distance(&a, &reference, 200_000);
    eprintln!("{name} angle: {} faces, max distance {max:.3e}, mean {mean_ab:.3e} / {mean_ba:.3e} of the diagonal", a.faces.len());
    assert!(max <= 0.01, "{name} angle: max distance {max}");
}

#[test]
fn a_cone_of_circles() {
    check_both("cone", &cone);
}

#[test]
fn twisting_growing_ellipses() {
    check_both("twisted ellipses", &twisted);
}

#[test]
fn sections_in_decreasing_order_give_the_same_solid() {
    // The stack read top-down: the frame flips, the surface still faces out.
    let sections: Vec<Vec<Vec<[f64; 3]>>> = (0..SECTIONS).rev().map(|k| vec![twisted(HEIGHT * k as f64 / (SECTIONS - 1) as f64, 48)]).collect();
    let (frame, s) = parse(&profile_text(&sections));
    assert_eq!(frame.n, [0.0, 0.0, -1.0]);
    for method in 0..2 {
        let mut m = TriMesh::default();
        if method == 0 {
            mc::reconstruct(frame, &s, McOptions { cubes: 32, caps: true, ..Default::default() }, &mut m).unwrap();
        } else {
            angle::reconstruct(&s, AngleOptions { caps: true, ..Default::default() }, &mut m).unwrap();
        }
        let c = check_closed_oriented(&m).unwrap();
        assert!(c.volume > 0.0, "method {method}: volume {}", c.volume);
    }
}
