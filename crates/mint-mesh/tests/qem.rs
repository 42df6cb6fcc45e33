//! The f64 quadric edge collapse (`mint_mesh::qem::collapse`): whatever the
//! shape and the target, the surface keeps its topology (closed, 2-manifold,
//! oriented, same components and genera; an open surface keeps its
//! boundary loops), and the error stays small where the shape is smooth.

mod shapes;

use mint_mesh::qem::{collapse, collapse_in_blocks, Planes};
use mint_mesh::{check, CheckReport};
use proptest::prelude::*;
use shapes::*;

/// Collapses `m` to `target` faces and checks the result with its
/// unreferenced vertices dropped.
fn collapsed(m: &Mesh, target: u64) -> (Mesh, CheckReport) {
    collapsed_in(m, target, 1)
}

/// The same, in `blocks` blocks first (on two threads).
fn collapsed_in(m: &Mesh, target: u64, blocks: usize) -> (Mesh, CheckReport) {
    let (p, f, _) = collapse_in_blocks(&m.0, &m.1, Planes::Faces, target, f64::INFINITY, blocks, 2, &|| false);
    let mut map = vec![u32::MAX; p.len()];
    let mut q = Vec::new();
    let g: Vec<[u32; 3]> = f
        .iter()
        .map(|t| {
            t.map(|v| {
                if map[v as usize] == u32::MAX {
                    map[v as usize] = q.len() as u32;
                    q.push(p[v as usize]);
                }
                map[v as usize]
            })
        })
        .collect();
    let r = check(&q, &g);
    ((q, g), r)
}

fn same_topology(before: &CheckReport, after: &CheckReport) -> Result<(), TestCaseError> {
    prop_assert_eq!(after.watertight, before.watertight);
    prop_assert_eq!(after.non_manifold_edges, 0);
    prop_assert_eq!(after.non_manifold_vertices, 0);
    prop_assert_eq!(after.inconsistently_oriented_edges, 0);
    prop_assert_eq!(after.degenerate_faces, 0);
    prop_assert_eq!(after.duplicate_faces, 0);
    prop_assert_eq!(after.components, before.components);
    prop_assert_eq!(&after.genera, &before.genera);
    prop_assert_eq!(after.boundary_loops, before.boundary_loops);
    Ok(())
}

/// `m` with every vertex moved by a drawn offset (cycled through
/// `jitter`), scaled by `amount` (in units of the mesh's spacing).
fn jittered(mut m: Mesh, jitter: &[[f64; 3]], amount: f64) -> Mesh {
    for (i, p) in m.0.iter_mut().enumerate() {
        let j = jitter[i % jitter.len()];
        for k in 0..3 {
            p[k] += amount * j[k];
        }
    }
    m
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn closed_shapes_keep_their_topology_at_any_target(
        shape in 0usize..3,
        res in 4u32..14,
        jitter in prop::collection::vec([-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0], 1..8),
        fraction in 0.0f64..1.0,
        blocks in 1usize..5,
    ) {
        let m = match shape {
            0 => uv_sphere(1.0, res, 2 * res),
            1 => torus(1.0, 0.4, 2 * res, res),
            _ => polycube(&[[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0], [2, 1, 0], [0, 2, 0], [1, 2, 0], [2, 2, 0]], |_, _| true),
        };
        let m = jittered(m, &jitter, 0.02 / f64::from(res));
        let before = check(&m.0, &m.1);
        prop_assume!(before.watertight);
        let target = (fraction * m.1.len() as f64) as u64;
        let (out, after) = collapsed_in(&m, target, blocks);
        same_topology(&before, &after)?;
        prop_assert!(!out.1.is_empty());
    }

    #[test]
    fn open_shapes_keep_their_boundary_loops(
        res in 5u32..14,
        cut in 0.0f64..0.8,
        jitter in prop::collection::vec([-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0], 1..8),
        fraction in 0.0f64..1.0,
        blocks in 1usize..5,
    ) {
        // A sphere with the faces above `cut` removed: one boundary loop.
        let s = jittered(uv_sphere(1.0, res, 2 * res), &jitter, 0.02 / f64::from(res));
        let faces: Vec<[u32; 3]> = s.1.iter().copied().filter(|f| f.iter().map(|&v| s.0[v as usize][2]).sum::<f64>() / 3.0 < cut).collect();
        let m = (s.0.clone(), faces);
        let before = check(&m.0, &m.1);
        prop_assume!(before.boundary_loops == 1 && before.non_manifold_vertices == 0);
        let target = (fraction * m.1.len() as f64) as u64;
        let (_, after) = collapsed_in(&m, target, blocks);
        same_topology(&before, &after)?;
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// Any soup (repeated indices, duplicates, non-manifold edges, flat or
    /// coincident points): no panic, valid indices, and no more faces.
    #[test]
    fn any_soup_collapses_without_panicking(
        points in prop::collection::vec([0i32..4, 0i32..4, 0i32..2], 3..12),
        raw in prop::collection::vec((0u32..12, 0u32..12, 0u32..12), 1..30),
        target in 0u64..30,
    ) {
        let p: Vec<[f64; 3]> = points.iter().map(|q| q.map(f64::from)).collect();
        let n = p.len() as u32;
        let f: Vec<[u32; 3]> = raw.iter().map(|&(a, b, c)| [a % n, b % n, c % n]).collect();
        let (q, g, _) = collapse(&p, &f, target, f64::INFINITY, 1);
        prop_assert_eq!(q.len(), p.len());
        prop_assert!(g.len() <= f.len());
        prop_assert!(g.iter().flatten().all(|&v| v < n));
        prop_assert!(q.iter().flatten().all(|c| c.is_finite()));
    }
}

#[test]
fn blocks_give_the_same_mesh_on_any_thread_count() {
    let m = torus(1.0, 0.4, 120, 60);
    let runs: Vec<_> = [1, 2, 3, 8].iter().map(|&t| collapse_in_blocks(&m.0, &m.1, Planes::Faces, 2000, f64::INFINITY, 5, t, &|| false)).collect();
    for r in &runs[1..] {
        assert_eq!(r.1, runs[0].1);
        assert!(r.0.iter().zip(&runs[0].0).all(|(a, b)| a.map(f64::to_bits) == b.map(f64::to_bits)));
    }
    let (_, after) = collapsed_in(&m, 2000, 5);
    assert!(after.watertight && after.genera == vec![1], "{after:?}");
}

#[test]
fn a_fine_sphere_keeps_close_to_the_sphere() {
    // 80 x 160 bands, 25,280 faces, to 1,000: every kept vertex stays within
    // a small fraction of the new edge length of the unit sphere.
    let m = uv_sphere(1.0, 80, 160);
    let (out, r) = collapsed(&m, 1000);
    assert!(r.watertight, "{r:?}");
    assert!(out.1.len() <= 1000 && out.1.len() >= 990, "{} faces", out.1.len());
    for p in &out.0 {
        let d = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        assert!((d - 1.0).abs() < 5e-3, "vertex at radius {d}");
    }
}

#[test]
fn a_flat_square_becomes_two_triangles_with_its_corners_kept() {
    // A 6 x 6 grid of squares on z = 0: the border vertices slide along the
    // border only, so the four corners survive and the square stays whole.
    let n = 6u32;
    let p: Vec<[f64; 3]> = (0..=n).flat_map(|j| (0..=n).map(move |i| [f64::from(i), f64::from(j), 0.0])).collect();
    let v = |i: u32, j: u32| j * (n + 1) + i;
    let mut f = Vec::new();
    for j in 0..n {
        for i in 0..n {
            f.push([v(i, j), v(i + 1, j), v(i + 1, j + 1)]);
            f.push([v(i, j), v(i + 1, j + 1), v(i, j + 1)]);
        }
    }
    let ((q, g), r) = collapsed(&(p, f), 2);
    assert_eq!((g.len(), r.boundary_loops), (2, 1), "{g:?}");
    for corner in [[0.0, 0.0, 0.0], [6.0, 0.0, 0.0], [0.0, 6.0, 0.0], [6.0, 6.0, 0.0]] {
        assert!(q.iter().any(|x| (0..3).all(|k| (x[k] - corner[k]).abs() < 1e-9)), "corner {corner:?} lost: {q:?}");
    }
}


#[test]
fn a_soup_of_separate_triangles_ends_at_once_with_nothing_to_collapse() {
    // 3,000 triangles sharing no vertex: every edge is a border edge whose
    // collapse would leave a triangle with two corners, so none is allowed.
    // (The heap used to be rebuilt forever here: its size stayed above the
    // rebuild threshold with no collapse to shrink it.)
    let mut p = Vec::new();
    let mut f = Vec::new();
    for k in 0..3000u32 {
        let x = f64::from(k);
        p.extend([[x, 0.0, 0.0], [x + 0.5, 0.0, 0.0], [x, 0.5, 0.3]]);
        f.push([3 * k, 3 * k + 1, 3 * k + 2]);
    }
    let (_, g, stats) = collapse(&p, &f, 10, f64::INFINITY, 1);
    assert_eq!((g.len(), stats.collapses), (3000, 0));
}

/// A sharp colour border on a flat plane stays sharp: colour quadrics make
/// a collapse across it cost, so the vertices left on either side keep
/// their side's colour, and only the border's own column blends.
#[test]
fn a_sharp_colour_border_stays_sharp() {
    let n = 40usize;
    let mut p = Vec::new();
    let mut c = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let x = i as f64 / n as f64;
            p.push([x, j as f64 / n as f64, 0.0]);
            c.push(if i <= n / 2 { [255u8, 0, 0, 255] } else { [0, 0, 255, 255] });
        }
    }
    let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    let mut f = Vec::new();
    for j in 0..n {
        for i in 0..n {
            f.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            f.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    let (q, g, colours, _) = mint_mesh::qem::collapse_coloured(&p, &f, Planes::Faces, &c, 0.01, 120, f64::INFINITY, 1, 1, &|| false);
    assert!(g.len() <= 120, "{} faces", g.len());
    let used: std::collections::BTreeSet<u32> = g.iter().flatten().copied().collect();
    let mut pure = 0;
    for &v in &used {
        let (x, col) = (q[v as usize][0], colours[v as usize]);
        if (x - 0.5).abs() > 1.5 / n as f64 {
            assert_eq!(col, if x < 0.5 { [255, 0, 0, 255] } else { [0, 0, 255, 255] }, "vertex at x = {x}");
            pure += 1;
        }
        assert!(col[1] == 0 && (254..=256).contains(&(col[0] as u32 + col[2] as u32)), "{col:?} at x = {x}");
    }
    assert!(pure * 2 > used.len(), "{pure} of {} vertices away from the border", used.len());
    // The border's column of vertices is kept: some vertex lies on it.
    assert!(used.iter().filter(|&&v| (q[v as usize][0] - 0.5).abs() < 1e-9).count() >= 2);
}

/// Mean |radius − 1| over points spread evenly on the faces of `m`
/// (barycentric lattice of 15 points a face, weighted by area).
fn mean_off_unit_sphere(m: &Mesh) -> f64 {
    let (mut sum, mut area) = (0.0, 0.0);
    for t in &m.1 {
        let [a, b, c] = t.map(|v| glam::DVec3::from(m.0[v as usize]));
        let w = 0.5 * (b - a).cross(c - a).length();
        let n = 4;
        let mut s = 0.0;
        let mut k = 0;
        for i in 0..=n {
            for j in 0..=n - i {
                let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                s += ((a + (b - a) * u + (c - a) * v).length() - 1.0).abs();
                k += 1;
            }
        }
        sum += w * s / k as f64;
        area += w;
    }
    sum / area
}

#[test]
fn lift_is_the_mean_sag_of_a_chord_face_of_a_sphere() {
    // A face inscribed in a sphere of radius 2, with the sphere's normals
    // at its corners: the lift is the sphere's mean height above the face
    // (measured here on a fine barycentric lattice), h²/(8R) for edges h.
    use glam::DVec3;
    let r = 2.0;
    let x = [DVec3::new(0.1, 0.0, 1.0), DVec3::new(-0.05, 0.09, 1.0), DVec3::new(-0.06, -0.08, 1.0)].map(|p| p.normalize() * r);
    let n = (x[1] - x[0]).cross(x[2] - x[0]).normalize();
    let lift = mint_mesh::qem::lift(x, x.map(|p| p.normalize()), n);
    let (mut sum, mut k) = (0.0, 0);
    let steps = 200;
    for i in 0..=steps {
        for j in 0..=steps - i {
            let p = x[0] + (x[1] - x[0]) * (i as f64 / steps as f64) + (x[2] - x[0]) * (j as f64 / steps as f64);
            // Height along n from p to the sphere: |p + t n| = r.
            let b = p.dot(n);
            sum += -b + (b * b - p.length_squared() + r * r).sqrt();
            k += 1;
        }
    }
    let mean = sum / k as f64;
    assert!(mean > 0.0 && (lift - mean).abs() < 0.05 * mean, "lift {lift:e}, mean height {mean:e}");
    // A crease (normals leaning past the threshold) is not lifted.
    let bent = [n, n, (n + DVec3::X).normalize()];
    assert_eq!(mint_mesh::qem::lift(x, bent, n), 0.0);
}

#[test]
fn lifted_planes_keep_a_chord_mesh_closer_to_its_sphere() {
    // A UV sphere's faces are chords: collapsed 4:1 on its faces' planes the
    // vertices settle inside; on lifted planes the result lies closer to
    // the sphere itself (0.80x the mean distance when this was written;
    // asked: 0.85x), and keeps its topology.
    let m = uv_sphere(1.0, 80, 160);
    let run = |planes: Planes| {
        let (p, f, _) = collapse_in_blocks(&m.0, &m.1, planes, 6000, f64::INFINITY, 1, 1, &|| false);
        let r = check(&p, &f);
        assert!(r.watertight && r.genera == vec![0], "{planes:?}: {r:?}");
        mean_off_unit_sphere(&(p, f))
    };
    let (faces, lifted) = (run(Planes::Faces), run(Planes::Lifted));
    assert!(lifted < 0.85 * faces, "mean distance to the sphere: faces' planes {faces:e}, lifted {lifted:e}");
}

/// Vertices no face uses change nothing: the whole pass works on the used
/// ones renumbered in order, so the same collapses come in the same order
/// (after the blocks most vertices are unused; here they are interleaved).
#[test]
fn unused_vertices_change_nothing() {
    let m = torus(1.0, 0.4, 60, 30);
    let mut p = Vec::new();
    let mut at = Vec::new();
    for (i, v) in m.0.iter().enumerate() {
        if i % 3 == 0 {
            p.push(m.0[0]); // (inside the box: the box sets the centring)
        }
        at.push(p.len() as u32);
        p.push(*v);
    }
    let f: Vec<[u32; 3]> = m.1.iter().map(|t| t.map(|v| at[v as usize])).collect();
    let (q0, g0, _) = collapse_in_blocks(&m.0, &m.1, Planes::Faces, 500, f64::INFINITY, 1, 1, &|| false);
    let (q1, g1, _) = collapse_in_blocks(&p, &f, Planes::Faces, 500, f64::INFINITY, 1, 1, &|| false);
    let g0: Vec<[u32; 3]> = g0.iter().map(|t| t.map(|v| at[v as usize])).collect();
    assert_eq!(g0, g1);
    for (i, &j) in at.iter().enumerate() {
        if g0.iter().flatten().any(|&v| v == j) {
            assert_eq!(q0[i].map(f64::to_bits), q1[j as usize].map(f64::to_bits));
        }
    }
}
