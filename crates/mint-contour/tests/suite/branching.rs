//! Holes and branching. An annulus stack (a hole through the solid) and a
//! Y-shaped stack (one contour, then two): marching cubes must be closed and
//! oriented with zero non-canonical cells; the angle method must produce no
//! two triangles that cross or overlap (and, here, close as well).
use super::util::{clashing_faces, ellipse, parse, profile_text};
use mint_contour::angle::{self, AngleOptions};
use mint_contour::mc::{self, McOptions};
use mint_core::TriMesh;
use mint_testkit::topology::check_closed_oriented;

fn annulus() -> String {
    let sections: Vec<Vec<Vec<[f64; 3]>>> = (0..30)
        .map(|k| {
            let z = 0.1 * k as f64;
            let r = 0.3 + 0.1 * (z * 1.3).sin();
            vec![ellipse([0.0, 0.0], 2.0, 1.5, 0.1 * z, z, 60), ellipse([0.2, 0.0], r + 0.4, r, 0.0, z, 24)]
        })
        .collect();
    profile_text(&sections)
}

/// A trunk of 12 sections (an ellipse) that splits into two arms of 12.
fn y_shape() -> String {
    let mut sections: Vec<Vec<Vec<[f64; 3]>>> = Vec::new();
    for k in 0..12 {
        let z = 0.15 * k as f64;
        sections.push(vec![ellipse([0.0, 0.0], 2.0 + 0.05 * k as f64, 1.0, 0.0, z, 64)]);
    }
    for k in 12..24 {
        let z = 0.15 * k as f64;
        let spread = 1.3 + 0.08 * (k - 12) as f64;
        sections.push(vec![ellipse([-spread, 0.0], 0.8, 0.8, 0.0, z, 40), ellipse([spread, 0.0], 0.8, 0.8, 0.0, z, 40)]);
    }
    profile_text(&sections)
}

#[test]
fn an_annulus_stack_is_a_closed_torus_with_both_methods() {
    let (frame, s) = parse(&annulus());
    let mut m = TriMesh::default();
    let st = mc::reconstruct(frame, &s, McOptions { cubes: 80, caps: true, ..Default::default() }, &mut m).unwrap();
    assert_eq!(st.non_canonical_cells, 0);
    let c = check_closed_oriented(&m).unwrap();
    assert_eq!((c.components, c.genus), (1, 1));
    let mut a = TriMesh::default();
    let st = angle::reconstruct(&s, AngleOptions { caps: true, ..Default::default() }, &mut a).unwrap();
    assert_eq!((st.tubes, st.caps, st.splits), (58, 2, 0));
    let c = check_closed_oriented(&a).unwrap();
    assert_eq!((c.components, c.genus), (1, 1));
    assert_eq!(clashing_faces(&a), vec![], "angle method triangles cross");
}

#[test]
fn a_y_shaped_branch() {
    let (frame, s) = parse(&y_shape());
    let mut m = TriMesh::default();
    let st = mc::reconstruct(frame, &s, McOptions { cubes: 96, caps: true, ..Default::default() }, &mut m).unwrap();
    assert_eq!(st.non_canonical_cells, 0);
    let c = check_closed_oriented(&m).unwrap();
    assert_eq!((c.components, c.genus), (1, 0));
    let mut a = TriMesh::default();
    let st = angle::reconstruct(&s, AngleOptions { caps: true, ..Default::default() }, &mut a).unwrap();
    eprintln!("y-shape angle: {st:?}");
    assert_eq!((st.splits, st.bridged, st.apart), (1, 0, 0));
    assert_eq!(clashing_faces(&a), vec![], "angle method triangles cross");
    let c = check_closed_oriented(&a).unwrap();
    assert_eq!((c.components, c.genus), (1, 0));
}

#[test]
fn two_arms_merging_into_one_and_three_way_branches() {
    // Upside down (merge) and a three-way split: both must stay clean.
    let mut sections: Vec<Vec<Vec<[f64; 3]>>> = Vec::new();
    for k in 0..6 {
        let z = 0.2 * k as f64;
        sections.push(vec![ellipse([-1.5, 0.0], 0.7, 0.7, 0.0, z, 30), ellipse([1.5, 0.0], 0.7, 0.7, 0.0, z, 30)]);
    }
    for k in 6..12 {
        sections.push(vec![ellipse([0.0, 0.0], 2.6, 1.0, 0.0, 0.2 * k as f64, 80)]);
    }
    for k in 12..18 {
        let z = 0.2 * k as f64;
        sections.push(vec![
            ellipse([-1.8, 0.0], 0.5, 0.5, 0.0, z, 24),
            ellipse([0.0, 0.0], 0.5, 0.5, 0.0, z, 24),
            ellipse([1.8, 0.0], 0.5, 0.5, 0.0, z, 24),
        ]);
    }
    let (frame, s) = parse(&profile_text(&sections));
    let mut m = TriMesh::default();
    let st = mc::reconstruct(frame, &s, McOptions { cubes: 100, caps: true, ..Default::default() }, &mut m).unwrap();
    assert_eq!(st.non_canonical_cells, 0);
    let c = check_closed_oriented(&m).unwrap();
    assert_eq!((c.components, c.genus), (1, 0));
    let mut a = TriMesh::default();
    let st = angle::reconstruct(&s, AngleOptions { caps: true, ..Default::default() }, &mut a).unwrap();
    eprintln!("merge and 3-way split, angle: {st:?}");
    // The merge joins the two arms by a bridge; the three-way branch splits.
    assert_eq!((st.splits, st.bridged, st.apart), (1, 1, 0));
    assert_eq!(clashing_faces(&a), vec![], "angle method triangles cross");
    let c = check_closed_oriented(&a).unwrap();
    assert_eq!((c.components, c.genus), (1, 0));
}
