//! Property tests of the resampling core on random closed meshes: random
//! convex hulls, unions of disjoint hulls, and hulls whose vertices are
//! snapped onto the grid lattice (vertices on nodes, edges on lines, faces on
//! planes). The output must always be a closed, oriented 2-manifold without
//! zero-area faces, with zero non-canonical cells.

use mint_core::reconstruct::resample_in_core;
use mint_core::{Grid, GridSize, TriMesh};
use mint_testkit::hull::{convex_hull, soup};
use mint_testkit::topology::check_closed_oriented;
use mint_testkit::Rng;
use proptest::prelude::*;

/// A random convex hull around `centre`, optionally snapped to multiples of `snap`.
fn random_hull(rng: &mut Rng, centre: [f64; 3], radius: f64, n: usize, snap: Option<f64>) -> Option<Vec<[[f64; 3]; 3]>> {
    let pts: Vec<[f64; 3]> = (0..n)
        .map(|_| {
            let p = [0, 1, 2].map(|d| centre[d] + rng.range(-radius, radius));
            match snap {
                Some(s) => p.map(|x| (x / s).round() * s),
                None => p,
            }
        })
        .collect();
    convex_hull(&pts).map(|m| soup(&m))
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
    fn random_convex_hulls_resample_watertight(seed in any::<u64>(), cells in 50u64..20000, axis in 0usize..3, off in 0.0f64..1.0) {
        let mut rng = Rng(seed);
        if let Some(tris) = random_hull(&mut rng, [0.0; 3], 1.0, 30, None) {
            let (lo, hi) = bounds(&tris);
            let g = Grid::around(lo, hi, GridSize::Cells(cells), [off, off * 0.7, off * 0.3], Some(axis)).unwrap();
            resample_and_check(&tris, &g)?;
        }
    }

    #[test]
    fn unions_of_disjoint_hulls_resample_watertight(seed in any::<u64>(), cells in 200u64..30000, axis in 0usize..3) {
        let mut rng = Rng(seed);
        let mut tris = Vec::new();
        for k in 0..4 {
            let c = [3.0 * k as f64, rng.range(-0.3, 0.3), rng.range(-0.3, 0.3)];
            if let Some(t) = random_hull(&mut rng, c, 1.0, 20, None) {
                tris.extend(t);
            }
        }
        prop_assume!(!tris.is_empty());
        let (lo, hi) = bounds(&tris);
        let g = Grid::around(lo, hi, GridSize::Cells(cells), [0.0; 3], Some(axis)).unwrap();
        resample_and_check(&tris, &g)?;
    }

    #[test]
    fn hulls_snapped_onto_the_lattice_resample_watertight(seed in any::<u64>(), snap_half in any::<bool>(), axis in 0usize..3) {
        // Cell size 1 with an integer-aligned grid: snapped vertices sit on
        // nodes (snap 1) or on half-cells (snap 0.5): edges run along grid
        // lines and faces along grid planes all the time.
        let mut rng = Rng(seed);
        let snap = if snap_half { 0.5 } else { 1.0 };
        let mut tris = Vec::new();
        for k in 0..2 {
            if let Some(t) = random_hull(&mut rng, [10.0 * k as f64, 0.0, 0.0], 4.0, 25, Some(snap)) {
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
/// faces, and nothing panics.
fn random_soup(rng: &mut Rng) -> Vec<[[f64; 3]; 3]> {
    let mut tris = Vec::new();
    for k in 0..3 {
        let c = [2.5 * k as f64 + rng.range(-0.5, 0.5), rng.range(-0.5, 0.5), 0.0];
        let snap = if rng.f64() < 0.3 { Some(0.25) } else { None };
        if let Some(t) = random_hull(rng, c, 1.0, 25, snap) {
            for tri in t {
                let r = rng.f64();
                if r < 0.1 {
                    continue; // hole
                }
                let tri = if rng.f64() < 0.3 { [tri[0], tri[2], tri[1]] } else { tri };
                tris.push(tri);
                if r > 0.95 {
                    // an overlapping, slightly shifted copy
                    tris.push(tri.map(|p| [p[0] + 0.01, p[1], p[2] - 0.01]));
                }
            }
        }
    }
    for _ in 0..5 {
        let p = [rng.range(-1.0, 6.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)];
        tris.push([p, [p[0] + rng.range(-0.5, 0.5), p[1] + 0.3, p[2]], [p[0], p[1], p[2] + rng.range(-0.5, 0.5)]]);
    }
    tris
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 150, .. ProptestConfig::default() })]

    #[test]
    fn random_soups_always_give_closed_manifolds_under_robust_rules(seed in any::<u64>(), cells in 100u64..20000, rule_pick in 0usize..3) {
        use mint_core::robust::resample_in_core_with;
        use mint_core::signs::SignRule;
        let mut rng = Rng(seed);
        let tris = random_soup(&mut rng);
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
    fn random_soups_with_open_holes_stay_manifold(seed in any::<u64>(), cells in 500u64..20000, max_hole in 1u32..6) {
        use mint_core::holes::open_cells;
        use mint_core::reconstruct::crossing_to_intercept;
        use mint_core::robust::{census_plane, reconstruct_slab_solids, Expr};
        let mut rng = Rng(seed);
        let tris = random_soup(&mut rng);
        prop_assume!(!tris.is_empty());
        let (lo, hi) = bounds(&tris);
        let g = Grid::around(lo, hi, GridSize::Cells(cells), [0.0; 3], None).unwrap();
        let [na, nb, ns] = g.local_dims();
        let mut planes: Vec<Vec<mint_core::Intercept>> = vec![Vec::new(); ns as usize + 1];
        for t in &tris {
            let local = t.map(|p| g.to_local(p));
            mint_core::discretize_triangle(&local, |c| {
                let r = crossing_to_intercept(&c, nb);
                planes[r.plane as usize].push(r);
            });
        }
        let mut census = mint_core::signs::LineCensus::default();
        for p in &planes {
            census += census_plane(&mut p.clone());
        }
        let rule = census.resolve();
        let (first, _) = reconstruct_slab_solids(&g, 0, vec![planes.clone()], &[rule], &Expr::Operand(0), None);
        let mut holes = first.hole_cells.clone();
        let (open, _) = open_cells(&mut holes, [na, nb, ns], max_hole);
        let (res, _) = reconstruct_slab_solids(&g, 0, vec![planes], &[rule], &Expr::Operand(0), Some(&open));
        let r = mint_mesh::check(&res.vertices, &res.faces);
        prop_assert_eq!((r.non_manifold_edges, r.non_manifold_vertices, r.inconsistently_oriented_edges), (0, 0, 0), "{:?}", r);
        prop_assert_eq!(r.unreferenced_vertices, 0);
    }
}
