//! Property tests of the resampling core on random closed meshes: random
//! convex hulls, unions of disjoint hulls, and hulls whose vertices are
//! snapped onto the grid lattice (vertices on nodes, edges on lines, faces on
//! planes). The output must always be a closed, oriented 2-manifold without
//! zero-area faces, with zero non-canonical cells.
//!
//! The geometry itself is drawn (points on small integer lattices, per-face
//! edits as flags), not a seed, so that proptest shrinks a failure to a few
//! points; failures found are kept in `proptest-regressions/`.

use mint_core::in_core::resample_in_core;
use mint_core::{Grid, GridSize, TriMesh};
use mint_testkit::hull::{convex_hull, soup};
use mint_testkit::topology::check_closed_oriented;
use proptest::prelude::*;

/// Points of a lattice of `steps` per unit in [-1, 1]³ (`steps` = 1024 is
/// all but continuous; 2 or 4 put vertices on grid nodes and half-cells).
fn lattice_points(n: std::ops::Range<usize>, steps: i32) -> impl Strategy<Value = Vec<[i32; 3]>> {
    prop::collection::vec([-steps..=steps, -steps..=steps, -steps..=steps], n)
}

/// The convex hull of `pts` (lattice units of `1/steps`) scaled by `radius`
/// around `centre`, as a triangle soup.
fn hull_of(pts: &[[i32; 3]], steps: i32, centre: [f64; 3], radius: f64) -> Option<Vec<[[f64; 3]; 3]>> {
    let p: Vec<[f64; 3]> = pts.iter().map(|q| [0, 1, 2].map(|d| centre[d] + radius * q[d] as f64 / steps as f64)).collect();
    convex_hull(&p).map(|m| soup(&m))
}

fn resample_and_check(tris: &[[[f64; 3]; 3]], grid: &Grid) -> Result<(), TestCaseError> {
    let mut out = TriMesh::default();
    let r = resample_in_core(grid, tris.iter().copied(), &mut out).unwrap();
    prop_assert_eq!(r.stats.non_canonical_cells, 0, "non-canonical cells: {:?}", r.non_canonical);
    let stats = check_closed_oriented(&out).map_err(|e| TestCaseError::fail(format!("{e} (grid {grid:?})")))?;
    prop_assert!(out.faces.is_empty() || stats.volume > 0.0, "volume {}", stats.volume);
    Ok(())
}

fn bounds(tris: &[[[f64; 3]; 3]]) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for t in tris {
        for p in t {
            for d in 0..3 {
                lo[d] = lo[d].min(p[d]);
                hi[d] = hi[d].max(p[d]);
            }
        }
    }
    (lo, hi)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, .. ProptestConfig::default() })]

    #[test]
    fn random_convex_hulls_resample_watertight(pts in lattice_points(4..30, 1024), cells in 50u64..20000, axis in 0usize..3, off in 0.0f64..1.0) {
        if let Some(tris) = hull_of(&pts, 1024, [0.0; 3], 1.0) {
            let (lo, hi) = bounds(&tris);
            let g = Grid::around(lo, hi, GridSize::Cells(cells), [off, off * 0.7, off * 0.3], Some(axis)).unwrap();
            resample_and_check(&tris, &g)?;
        }
    }

    #[test]
    fn unions_of_disjoint_hulls_resample_watertight(hulls in prop::collection::vec(lattice_points(4..20, 1024), 1..4), cells in 200u64..30000, axis in 0usize..3) {
        let mut tris = Vec::new();
        for (k, pts) in hulls.iter().enumerate() {
            if let Some(t) = hull_of(pts, 1024, [3.0 * k as f64, 0.0, 0.0], 1.0) {
                tris.extend(t);
            }
        }
        prop_assume!(!tris.is_empty());
        let (lo, hi) = bounds(&tris);
        let g = Grid::around(lo, hi, GridSize::Cells(cells), [0.0; 3], Some(axis)).unwrap();
        resample_and_check(&tris, &g)?;
    }

    #[test]
    fn hulls_snapped_onto_the_lattice_resample_watertight(a in lattice_points(4..25, 8), b in lattice_points(4..25, 8), snap_half in any::<bool>(), axis in 0usize..3) {
        // Cell size 1 with an integer-aligned grid: vertices sit on nodes
        // (radius 4 on a lattice of 4 steps: unit steps) or on half-cells
        // (8 steps: half units): edges run along grid lines and faces along
        // grid planes all the time.
        let steps = if snap_half { 8 } else { 4 };
        let clamp = |v: &Vec<[i32; 3]>| v.iter().map(|p| p.map(|x| x.clamp(-steps, steps))).collect::<Vec<_>>();
        let mut tris = Vec::new();
        for (k, pts) in [clamp(&a), clamp(&b)].iter().enumerate() {
            if let Some(t) = hull_of(pts, steps, [10.0 * k as f64, 0.0, 0.0], 4.0) {
                tris.extend(t);
            }
        }
        prop_assume!(!tris.is_empty());
        let (lo, hi) = bounds(&tris);
        let lo = lo.map(f64::floor);
        let hi = hi.map(f64::ceil);
        let g = Grid::around(lo, hi, GridSize::CellSize(1.0), [0.0; 3], Some(axis)).unwrap();
        // The grid origin must be on the integer lattice for the snap to mean anything.
        prop_assert!(g.origin.iter().all(|o| o.fract() == 0.0), "origin {:?}", g.origin);
        resample_and_check(&tris, &g)?;
    }
}

/// Random triangle soups: hull pieces with random orientation, random holes
/// (faces dropped), overlapping copies, stray triangles. Under every robust
/// sign rule the output is a closed, oriented 2-manifold without zero-area
/// faces, and nothing panics. Drawn as data: the hulls' lattice points (a
/// quarter of them snapped to quarter units), one edit per face (0 keep,
/// 1 drop, 2 flip, 3 keep and add a shifted copy), and the strays' corners.
fn soup_strategy() -> impl Strategy<Value = (Vec<(Vec<[i32; 3]>, bool)>, Vec<u8>, Vec<[[i32; 3]; 3]>)> {
    (
        prop::collection::vec((lattice_points(4..25, 64), prop::bool::weighted(0.3)), 1..4),
        prop::collection::vec(prop::sample::select(vec![0u8, 0, 0, 0, 0, 0, 1, 2, 2, 3]), 0..200),
        prop::collection::vec([[-64i32..=64, -64..=64, -64..=64], [-64i32..=64, -64..=64, -64..=64], [-64i32..=64, -64..=64, -64..=64]], 0..5),
    )
}

fn soup_of(data: &(Vec<(Vec<[i32; 3]>, bool)>, Vec<u8>, Vec<[[i32; 3]; 3]>)) -> Vec<[[f64; 3]; 3]> {
    let (hulls, edits, strays) = data;
    let mut tris = Vec::new();
    let mut e = 0;
    for (k, (pts, snap)) in hulls.iter().enumerate() {
        let pts: Vec<[i32; 3]> = if *snap { pts.iter().map(|p| p.map(|x| x / 16 * 16)).collect() } else { pts.clone() };
        if let Some(t) = hull_of(&pts, 64, [2.5 * k as f64, 0.0, 0.0], 1.0) {
            for tri in t {
                let edit = if edits.is_empty() { 0 } else { edits[e % edits.len()] };
                e += 1;
                match edit {
                    1 => continue,
                    2 => tris.push([tri[0], tri[2], tri[1]]),
                    3 => {
                        tris.push(tri);
                        tris.push(tri.map(|p| [p[0] + 0.01, p[1], p[2] - 0.01]));
                    }
                    _ => tris.push(tri),
                }
            }
        }
    }
    for s in strays {
        tris.push(s.map(|p| [3.0 * p[0] as f64 / 64.0 + 2.5, p[1] as f64 / 64.0, p[2] as f64 / 64.0]));
    }
    tris
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 150, .. ProptestConfig::default() })]

    #[test]
    fn random_soups_always_give_closed_manifolds_under_robust_rules(data in soup_strategy(), cells in 100u64..20000, rule_pick in 0usize..3) {
        use mint_core::in_core::resample_in_core_with;
        use mint_core::signs::SignRule;
        let tris = soup_of(&data);
        prop_assume!(!tris.is_empty());
        let (lo, hi) = bounds(&tris);
        let g = Grid::around(lo, hi, GridSize::Cells(cells), [0.0; 3], None).unwrap();
        let rule = [SignRule::Auto, SignRule::Union, SignRule::Parity][rule_pick];
        let mut out = TriMesh::default();
        resample_in_core_with(&g, tris.iter().copied(), rule, &mut out).unwrap();
        check_closed_oriented(&out).map_err(|e| TestCaseError::fail(format!("{rule:?}: {e}")))?;
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 100, .. ProptestConfig::default() })]

    /// With holes left open (`--max-hole`), random soups still never give a
    /// non-manifold edge or vertex, nor an inconsistently oriented edge.
    #[test]
    fn random_soups_with_open_holes_stay_manifold(data in soup_strategy(), cells in 500u64..20000, max_hole in 1u32..6) {
        use mint_core::in_core::resample_in_core_holes;
        use mint_core::signs::SignRule;
        let tris = soup_of(&data);
        prop_assume!(!tris.is_empty());
        let (lo, hi) = bounds(&tris);
        let g = Grid::around(lo, hi, GridSize::Cells(cells), [0.0; 3], None).unwrap();
        // The protocol itself (reconstruct, group the hole cells, reopen),
        // as mint-core runs it; the engine runs the same steps as stages.
        let mut out = TriMesh::default();
        let (res, _, _, _) = resample_in_core_holes(&g, tris.iter().copied(), SignRule::Auto, Some(max_hole), &mut out).unwrap();
        let r = mint_mesh::check(&res.vertices, &res.faces);
        prop_assert_eq!((r.non_manifold_edges, r.non_manifold_vertices, r.inconsistently_oriented_edges), (0, 0, 0), "{:?}", r);
        prop_assert_eq!(r.unreferenced_vertices, 0);
    }
}

/// `--open-border` on a random voxel volume at its own resolution: the
/// closed surface, the cap's faces left out (`on_border`), and the bowtie
/// vertices split (`fan_splits`), composed here as the engine's write
/// stage composes them.
fn open_border_mesh(dims: [u64; 3], inside: &[bool]) -> (Vec<[f64; 3]>, Vec<[u32; 3]>, [(f64, f64); 3]) {
    use mint_core::robust::reconstruct_slab_robust;
    use mint_core::signs::SignRule;
    use mint_core::volume::{border_mask, fan_splits, on_border, volume_planes, Field, Placement};
    let hi = dims.map(|n| (n - 1) as f64);
    let g = Grid::around([0.0; 3], hi, GridSize::CellSize(1.0), [0.0; 3], Some(2)).unwrap();
    let [na, nb, ns] = g.local_dims();
    let p = Placement { axis: [0, 1, 2], start: g.origin, step: [1.0; 3], dims, nodes: [na + 1, nb + 1, ns + 1] };
    let samples: Vec<f32> = inside.iter().map(|&b| b as u8 as f32).collect();
    let r = reconstruct_slab_robust(&g, 0, volume_planes(&p, Field::Iso(0.5), &samples), SignRule::Union).0;
    let domain: [(f64, f64); 3] = std::array::from_fn(|d| (-0.5, dims[d] as f64 - 0.5));
    let masks: Vec<u8> = r.vertices.iter().map(|&v| border_mask(v, domain, 1.0)).collect();
    let kept: Vec<[u32; 3]> = r.faces.iter().copied().filter(|f| !on_border(f.map(|v| masks[v as usize]))).collect();
    let mut incident = Vec::new();
    for f in &kept {
        for k in 0..3 {
            if masks[f[k] as usize] != 0 {
                let (a, b) = (f[(k + 1) % 3], f[(k + 2) % 3]);
                incident.push((f[k], a.min(b), a.max(b)));
            }
        }
    }
    let mut vertices = r.vertices.clone();
    let mut copy = std::collections::HashMap::new();
    let mut made = std::collections::HashMap::new();
    for (v, a, b, k) in fan_splits(incident) {
        let id = *made.entry((v, k)).or_insert_with(|| {
            vertices.push(r.vertices[v as usize]);
            vertices.len() as u32 - 1
        });
        copy.insert((v, a, b), id);
    }
    let faces: Vec<[u32; 3]> = kept
        .iter()
        .map(|f| std::array::from_fn(|k| {
            let (a, b) = (f[(k + 1) % 3], f[(k + 2) % 3]);
            *copy.get(&(f[k], a.min(b), a.max(b))).unwrap_or(&f[k])
        }))
        .collect();
    // Drop the vertices no face uses, as the write stage does.
    let mut id = vec![u32::MAX; vertices.len()];
    let mut out = Vec::new();
    let faces: Vec<[u32; 3]> = faces
        .iter()
        .map(|f| f.map(|v| {
            if id[v as usize] == u32::MAX {
                id[v as usize] = out.len() as u32;
                out.push(vertices[v as usize]);
            }
            id[v as usize]
        }))
        .collect();
    (out, faces, domain)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, .. ProptestConfig::default() })]

    /// Random voxel volumes with `--open-border`: the surface left is an
    /// oriented 2-manifold with boundary (no non-manifold edge or vertex,
    /// no unused vertex) whose boundary lies on the volume's border, and no
    /// face is left out of a surface the border does not touch.
    #[test]
    fn open_border_volumes_are_manifolds_with_their_boundary_on_the_border(
        dims in prop::array::uniform3(1u64..6),
        bits in prop::collection::vec(any::<bool>(), 125),
    ) {
        let n = (dims[0] * dims[1] * dims[2]) as usize;
        let (v, f, domain) = open_border_mesh(dims, &bits[..n]);
        let r = mint_mesh::check(&v, &f);
        prop_assert_eq!((r.non_manifold_edges, r.non_manifold_vertices, r.inconsistently_oriented_edges, r.unreferenced_vertices), (0, 0, 0, 0), "{:?}", r);
        let on = |q: [f64; 3]| (0..3).any(|d| (q[d] - domain[d].0).abs() < 1e-2 || (q[d] - domain[d].1).abs() < 1e-2);
        let mut count = std::collections::HashMap::new();
        for t in &f {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                *count.entry((a.min(b), a.max(b))).or_insert(0u32) += 1;
            }
        }
        for (&(a, b), &c) in &count {
            if c == 1 {
                prop_assert!(on(v[a as usize]) && on(v[b as usize]), "boundary edge {:?}-{:?} off the border", v[a as usize], v[b as usize]);
            }
        }
    }
}
