//! Exact-count tests of `mint_mesh::check` on tiny meshes whose answers are
//! known by hand, a cross-check against a naive map-based reference on
//! random meshes from a small lattice (where coincidences are common), and
//! thread-count independence.

mod shapes;

use mint_mesh::{check, try_check, CheckReport, MeshError};
use proptest::prelude::*;
use shapes::*;
use std::collections::BTreeMap;

fn report(m: &Mesh) -> CheckReport {
    check(&m.0, &m.1)
}

/// Asserts the fields every clean closed genus-`g` single-component mesh has.
fn assert_closed(r: &CheckReport, v: u64, e: u64, f: u64, genus: i64) {
    assert_eq!((r.vertices, r.edges, r.faces), (v, e, f));
    assert_eq!(r.referenced_vertices, v);
    assert_eq!(r.unreferenced_vertices, 0);
    assert_eq!(r.components, 1);
    assert_eq!(r.boundary_edges, 0);
    assert_eq!(r.boundary_loops, 0);
    assert_eq!(r.non_manifold_edges, 0);
    assert_eq!(r.non_manifold_vertices, 0);
    assert_eq!(r.inconsistently_oriented_edges, 0);
    assert_eq!(r.degenerate_faces, 0);
    assert_eq!(r.duplicate_faces, 0);
    assert_eq!(r.euler_characteristic, 2 - 2 * genus);
    assert_eq!(r.genera, vec![genus]);
    assert_eq!(r.genus_total, genus);
    assert_eq!(r.closed_components, 1);
    assert!(r.watertight);
}

#[test]
fn tetrahedron_counts() {
    // The smallest closed surface: 4 - 6 + 4 = 2.
    let r = report(&tetrahedron());
    assert_closed(&r, 4, 6, 4, 0);
    assert!((r.signed_volume - 1.0 / 6.0).abs() < 1e-15);
    assert_eq!(r.bbox_min, Some([0.0; 3]));
    assert_eq!(r.bbox_max, Some([1.0; 3]));
}

#[test]
fn cube_counts() {
    let r = report(&cube());
    assert_closed(&r, 8, 18, 12, 0);
    assert_eq!(r.signed_volume, 1.0);
    assert_eq!(r.surface_area, 6.0);
}

#[test]
fn octahedron_counts() {
    let r = report(&octahedron());
    assert_closed(&r, 6, 12, 8, 0);
    assert!((r.signed_volume - 4.0 / 3.0).abs() < 1e-15);
}

#[test]
fn reversed_cube_has_negative_volume() {
    let mut m = cube();
    for f in &mut m.1 {
        f.swap(1, 2);
    }
    let r = report(&m);
    assert_closed(&r, 8, 18, 12, 0);
    assert_eq!(r.signed_volume, -1.0);
}

#[test]
fn cube_without_one_face_has_one_boundary_loop() {
    let mut m = cube();
    m.1.drain(0..2); // both triangles of one square
    let r = report(&m);
    assert_eq!(r.faces, 10);
    assert_eq!(r.boundary_edges, 4);
    assert_eq!(r.boundary_loops, 1);
    assert_eq!(r.non_simple_boundary_edges, 0);
    assert_eq!(r.euler_characteristic, 8 - 17 + 10);
    assert_eq!(r.components, 1);
    assert!(r.genera.is_empty());
    assert!(!r.watertight);
}

#[test]
fn open_tube_has_two_loops() {
    // A unit cube without its two x faces: a tube with two square rims.
    let m = polycube(&[[0, 0, 0]], |axis, _| axis != 0);
    let r = report(&m);
    assert_eq!((r.faces, r.boundary_edges, r.boundary_loops), (8, 8, 2));
    assert_eq!(r.euler_characteristic, 0);
    assert!(!r.watertight);
}

#[test]
fn two_cubes_sharing_a_vertex() {
    // Corner (1,1,1) is shared: its faces form two fans.
    let m = polycube(&[[0, 0, 0], [1, 1, 1]], |_, _| true);
    let r = report(&m);
    assert_eq!((r.vertices, r.faces, r.edges), (15, 24, 36));
    assert_eq!(r.non_manifold_vertices, 1);
    assert_eq!(r.non_manifold_edges, 0);
    assert_eq!(r.boundary_edges, 0);
    assert_eq!(r.inconsistently_oriented_edges, 0);
    assert_eq!(r.components, 1); // vertex connectivity
    assert!(r.genera.is_empty());
    assert!(!r.watertight);
    assert_eq!(r.signed_volume, 2.0);
}

#[test]
fn two_disjoint_cubes_are_two_closed_components() {
    let m = polycube(&[[0, 0, 0], [2, 0, 0]], |_, _| true);
    let r = report(&m);
    assert_eq!(r.components, 2);
    assert_eq!(r.genera, vec![0, 0]);
    assert_eq!(r.euler_characteristic, 4);
    assert!(r.watertight);
}

#[test]
fn three_triangles_on_one_edge() {
    let p = vec![
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, -1.0, 0.0],
        [0.0, 0.0, 1.0],
    ];
    let r = check(&p, &[[0, 1, 2], [1, 0, 3], [0, 1, 4]]);
    assert_eq!(r.non_manifold_edges, 1);
    assert_eq!(r.non_manifold_vertices, 0); // all three join one fan at 0 and 1
    assert_eq!(r.boundary_edges, 6);
    assert_eq!(r.boundary_loops, 0);
    assert_eq!(r.non_simple_boundary_edges, 6);
    assert_eq!(r.edges, 7);
    assert!(!r.watertight);
}

#[test]
fn bowtie_is_a_non_manifold_vertex_with_non_simple_boundary() {
    let p = vec![
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [-1.0, 0.0, 0.0],
        [-1.0, -1.0, 0.0],
    ];
    let r = check(&p, &[[0, 1, 2], [0, 3, 4]]);
    assert_eq!(r.non_manifold_vertices, 1);
    assert_eq!(r.boundary_edges, 6);
    assert_eq!(r.boundary_loops, 0);
    assert_eq!(r.non_simple_boundary_edges, 6);
    assert_eq!(r.components, 1);
}

#[test]
fn single_triangle() {
    let p = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let r = check(&p, &[[0, 1, 2]]);
    assert_eq!(
        (
            r.boundary_edges,
            r.boundary_loops,
            r.non_simple_boundary_edges
        ),
        (3, 1, 0)
    );
    assert_eq!(r.surface_area, 0.5);
}

#[test]
fn flipped_face_gives_three_inconsistent_edges() {
    let mut m = cube();
    m.1[5].swap(0, 1);
    let r = report(&m);
    assert_eq!(r.inconsistently_oriented_edges, 3);
    assert_eq!(r.boundary_edges, 0);
    assert_eq!(r.non_manifold_edges, 0);
    assert_eq!(r.non_manifold_vertices, 0);
    assert!(r.genera.is_empty());
    assert!(!r.watertight);
}

#[test]
fn torus_has_genus_one() {
    let m = torus(2.0, 0.5, 48, 24);
    let r = report(&m);
    assert_closed(&r, 1152, 3456, 2304, 1);
    let exact = 2.0 * std::f64::consts::PI.powi(2) * 2.0 * 0.25;
    assert!(r.signed_volume > 0.0 && (r.signed_volume / exact - 1.0).abs() < 0.03);
}

#[test]
fn polycube_plates_have_genus_of_their_holes() {
    // 3x3 frame: genus 1. 5x3 with two holes: genus 2 (a double torus).
    // 7x3 with three holes: genus 3.
    for holes in 1..=3i32 {
        let mut cells = Vec::new();
        for x in 0..(2 * holes + 1) {
            for y in 0..3 {
                if !(y == 1 && x % 2 == 1) {
                    cells.push([x, y, 0]);
                }
            }
        }
        let r = report(&polycube(&cells, |_, _| true));
        assert!(r.watertight, "{holes} holes");
        assert_eq!(r.genera, vec![i64::from(holes)]);
        assert_eq!(r.signed_volume, cells.len() as f64);
    }
}

#[test]
fn uv_sphere_counts() {
    // rings r, segments s: 2 + (r-1)s vertices, 2s(r-1) faces.
    let m = uv_sphere(1.0, 8, 16);
    let r = report(&m);
    assert_closed(&r, 2 + 7 * 16, 3 * 16 * 7, 2 * 16 * 7, 0);
}

#[test]
fn duplicate_and_degenerate_faces() {
    let mut m = tetrahedron();
    let f0 = m.1[0];
    m.1.push([f0[0], f0[2], f0[1]]); // same vertex set, reversed: duplicate
    m.1.push([f0[1], f0[2], f0[0]]); // same vertex set, rotated: duplicate
    m.1.push([0, 0, 1]); // collapsed: degenerate
    m.1.push([1, 0, 0]); // collapsed, same sorted triple: degenerate, duplicate
    m.0.push([0.5, 0.0, 0.0]); // vertex 4, on edge 0-1
    m.1.push([0, 4, 1]); // collinear: degenerate
    m.0.push([0.5, 0.0, 0.0]); // vertex 5 = vertex 4
    m.1.push([4, 5, 2]); // coincident corners: degenerate
    let r = report(&m);
    assert_eq!(r.faces, 10);
    assert_eq!(r.duplicate_faces, 3);
    assert_eq!(r.degenerate_faces, 4);
    assert_eq!(r.collapsed_faces, 2);
    // The three copies of face 0 make its edges used 3 times.
    assert!(r.non_manifold_edges >= 3);
    assert!(r.genera.is_empty());
}

#[test]
fn degeneracy_is_exact_not_epsilon() {
    let p = vec![
        [0.0, 0.0, 0.0],
        [1.0, 1.0, 1.0],
        [2.0, 2.0, 2.0 + 1e-15],
        [3.0, 3.0, 3.0],
    ];
    // 0,1,2 are not collinear (by 1e-15); 0,1,3 are.
    assert_eq!(check(&p, &[[0, 1, 2]]).degenerate_faces, 0);
    assert_eq!(check(&p, &[[0, 1, 3]]).degenerate_faces, 1);
    // Far from the origin, where a float cross product would be noise.
    let o = 1e8;
    let q = vec![[o, o, o], [o + 0.5, o + 0.25, o], [o + 1.0, o + 0.5, o]];
    assert_eq!(check(&q, &[[0, 1, 2]]).degenerate_faces, 1);
}

#[test]
fn unreferenced_vertices_and_empty_meshes() {
    let mut m = tetrahedron();
    m.0.push([5.0, 5.0, 5.0]);
    let r = report(&m);
    assert_eq!(
        (r.vertices, r.referenced_vertices, r.unreferenced_vertices),
        (5, 4, 1)
    );
    assert_eq!(r.bbox_max, Some([5.0; 3]));
    assert!(r.watertight);

    let r = check(&[], &[]);
    assert_eq!((r.vertices, r.faces, r.components), (0, 0, 0));
    assert_eq!(r.bbox_min, None);
    assert!(!r.watertight);

    let r = check(&[[f64::NAN, 0.0, 0.0], [1.0, 2.0, 3.0]], &[]);
    assert_eq!(r.non_finite_vertices, 1);
    assert_eq!(r.bbox_min, Some([1.0, 2.0, 3.0]));
}

#[test]
fn out_of_range_index_is_a_typed_error() {
    let m = tetrahedron();
    let mut f = m.1.clone();
    f[2] = [0, 1, 7];
    assert_eq!(
        try_check(&m.0, &f).unwrap_err(),
        MeshError::IndexOutOfRange {
            face: 2,
            index: 7,
            vertices: 4
        }
    );
}

#[test]
fn report_serializes() {
    let r = report(&cube());
    let j = serde_json::to_value(&r).unwrap();
    assert_eq!(j["boundary_edges"], 0);
    assert_eq!(j["watertight"], true);
    let back: CheckReport = serde_json::from_value(j).unwrap();
    assert_eq!(back, r);
}

#[test]
fn same_report_under_every_thread_count() {
    // A sphere big enough to span many chunks, with a hole and a flip.
    let mut m = uv_sphere(1.0, 300, 600);
    let n = m.1.len();
    m.1.remove(n / 2);
    m.1[n / 3].swap(0, 1);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let two = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let r1 = one.install(|| report(&m));
    let r2 = two.install(|| report(&m));
    assert_eq!(r1, r2);
    assert_eq!(r1.boundary_edges, 3);
    assert_eq!(r1.boundary_loops, 1);
    assert_eq!(r1.inconsistently_oriented_edges, 3);
}

/// Naive reference: maps of edges and per-vertex fans, for cross-checking.
fn reference(nv: usize, faces: &[[u32; 3]]) -> [u64; 5] {
    let mut edges: BTreeMap<(u32, u32), (u32, u32)> = BTreeMap::new();
    let proper: Vec<&[u32; 3]> = faces
        .iter()
        .filter(|f| f[0] != f[1] && f[1] != f[2] && f[0] != f[2])
        .collect();
    for f in &proper {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            let e = edges.entry((a.min(b), a.max(b))).or_default();
            if a < b {
                e.0 += 1;
            } else {
                e.1 += 1;
            }
        }
    }
    let boundary = edges.values().filter(|e| e.0 + e.1 == 1).count() as u64;
    let nme = edges.values().filter(|e| e.0 + e.1 >= 3).count() as u64;
    let inc = edges
        .values()
        .filter(|e| e.0 + e.1 == 2 && e.0 != 1)
        .count() as u64;
    // Fans: faces around v joined when they share an edge {v, w}.
    let mut nmv = 0;
    for v in 0..nv as u32 {
        let around: Vec<&&[u32; 3]> = proper.iter().filter(|f| f.contains(&v)).collect();
        let mut class: Vec<usize> = (0..around.len()).collect();
        loop {
            let mut changed = false;
            for i in 0..around.len() {
                for j in 0..around.len() {
                    let shared = around[i]
                        .iter()
                        .filter(|&&w| w != v && around[j].contains(&w))
                        .count();
                    if shared > 0 && class[i] != class[j] {
                        let m = class[i].min(class[j]);
                        class[i] = m;
                        class[j] = m;
                        changed = true;
                    }
                }
            }
            if !changed {
                break;
            }
        }
        let mut c = class.clone();
        c.sort();
        c.dedup();
        if c.len() >= 2 {
            nmv += 1;
        }
    }
    let mut sets: Vec<[u32; 3]> = faces
        .iter()
        .map(|f| {
            let mut s = *f;
            s.sort();
            s
        })
        .collect();
    sets.sort();
    let dups = sets.windows(2).filter(|w| w[0] == w[1]).count() as u64;
    [boundary, nme, inc, nmv, dups]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]
    #[test]
    fn matches_naive_reference_on_lattice_soups(
        nv in 3usize..9,
        raw in proptest::collection::vec((0u32..9, 0u32..9, 0u32..9), 1..14),
    ) {
        let positions: Vec<[f64; 3]> =
            (0..nv).map(|i| [(i % 2) as f64, (i / 2 % 2) as f64, (i / 4) as f64]).collect();
        let faces: Vec<[u32; 3]> =
            raw.iter().map(|&(a, b, c)| [a % nv as u32, b % nv as u32, c % nv as u32]).collect();
        let r = check(&positions, &faces);
        let [b, nme, inc, nmv, dups] = reference(nv, &faces);
        prop_assert_eq!(r.boundary_edges, b);
        prop_assert_eq!(r.non_manifold_edges, nme);
        prop_assert_eq!(r.inconsistently_oriented_edges, inc);
        prop_assert_eq!(r.non_manifold_vertices, nmv);
        prop_assert_eq!(r.duplicate_faces, dups);
        prop_assert_eq!(r.referenced_vertices + r.unreferenced_vertices, nv as u64);
        prop_assert!(r.non_simple_boundary_edges <= r.boundary_edges);
        // Relabelling vertices must not change the topology.
        let perm = |i: u32| (i + 3) % nv as u32;
        let pf: Vec<[u32; 3]> = faces.iter().map(|f| f.map(perm)).collect();
        let mut pp = positions.clone();
        for (i, p) in positions.iter().enumerate() {
            pp[perm(i as u32) as usize] = *p;
        }
        let r2 = check(&pp, &pf);
        prop_assert_eq!(
            (r2.boundary_edges, r2.boundary_loops, r2.components, r2.euler_characteristic, &r2.genera),
            (r.boundary_edges, r.boundary_loops, r.components, r.euler_characteristic, &r.genera)
        );
    }
}

/// A fan `v → a → b` per face, around vertex 0: either a random closed
/// cycle over distinct neighbours (with its faces shuffled, and sometimes
/// one face flipped, repeated or dropped, or two cycles together), or faces
/// drawn from a small alphabet where coincidences are common.
fn any_fan() -> impl Strategy<Value = Vec<(u32, u32)>> {
    let cycle = (prop::collection::vec(1u32..40, 2..30), any::<u64>(), 0u8..6).prop_map(|(ws, seed, edit)| {
        let mut ws = ws;
        ws.sort_unstable();
        ws.dedup();
        let mut fan: Vec<(u32, u32)> = (0..ws.len()).map(|i| (ws[i], ws[(i + 1) % ws.len()])).collect();
        let mut s = seed;
        let mut next = |n: usize| {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (s >> 33) as usize % n.max(1)
        };
        for i in (1..fan.len()).rev() {
            let j = next(i + 1);
            fan.swap(i, j);
        }
        let k = next(fan.len());
        match edit {
            1 => fan[k] = (fan[k].1, fan[k].0),
            2 => fan.push(fan[k]),
            3 => {
                fan.remove(k);
            }
            4 => {
                let more: Vec<(u32, u32)> = fan.iter().map(|&(a, b)| (a + 40, b + 40)).collect();
                fan.extend(more);
            }
            _ => {}
        }
        fan
    });
    let small = prop::collection::vec((1u32..6, 1u32..6), 0..12).prop_map(|f| f.into_iter().filter(|(a, b)| a != b).collect());
    prop_oneof![cycle, small]
}

proptest! {
    /// The per-vertex scan's closed-fan shortcut gives exactly what the
    /// general scan (sorting every edge's faces) gives, on closed fans and
    /// on everything near them.
    #[test]
    fn closed_fan_shortcut_equals_the_general_scan(fan in any_fan(), v in prop_oneof![Just(0u32), 20u32..60]) {
        use mint_mesh::check::{scan_vertex, scan_vertex_general, TopologyCounts, VertexScratch};
        // Around a vertex numbered below, among or above its neighbours.
        let fan: Vec<(u32, u32)> = fan.into_iter().filter(|&(a, b)| a != v && b != v).collect();
        let (mut s1, mut s2) = (VertexScratch::default(), VertexScratch::default());
        let (mut c1, mut c2) = (TopologyCounts::default(), TopologyCounts::default());
        let t1 = scan_vertex(v, &fan, &mut s1, &mut c1);
        let t2 = scan_vertex_general(v, &fan, &mut s2, &mut c2);
        prop_assert_eq!(t1, t2);
        prop_assert_eq!(c1, c2);
        prop_assert_eq!(&s1.boundary_out, &s2.boundary_out);
    }
}
