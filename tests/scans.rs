//! Dirty real scans (issue 4): flipped faces, holes, overlapping layers and
//! real meshes through the robust default (`--signs auto`).

use crate::common::{load, write_mesh, write_trimesh};
use mint_core::signs::SignRule;
use mint_core::{GridSize, TriMesh};
use crate::common::{resample, Opts};
use mint_pipeline::{NoProgress, ResampleSummary};
use mint_testkit::topology::check_closed_oriented;
use std::path::Path;

fn run(input: &Path, out: &Path, o: Opts) -> (ResampleSummary, TriMesh) {
    let s = resample(input, out, &o, &NoProgress).unwrap_or_else(|e| panic!("{}: {e}", input.display()));
    (s, load(out))
}

fn cells(n: u64) -> Opts {
    Opts::new(GridSize::Cells(n))
}

#[test]
fn the_scan_like_surface_resamples_watertight_and_close_to_the_input() {
    let d = tempfile::tempdir().unwrap();
    let input = write_mesh(d.path(), "scan.ply", |s| {
        mint_gen::scan_like(200_000, 5, &mint_gen::ScanOptions::default(), s).unwrap();
    });
    let im = load(&input);
    for n in [30_000u64, 100_000, 1_000_000] {
        let out = d.path().join("o.ply");
        let (s, m) = run(&input, &out, cells(n));
        let st = check_closed_oriented(&m).unwrap_or_else(|e| panic!("{n} cells: {e}"));
        assert_eq!(st.genus, 0, "{n} cells");
        assert_eq!(s.sign_rule, "union", "{n} cells: a few flipped faces keep the union rule");
        let diag = s.cell_size * 3f64.sqrt();
        let r = mint_mesh::distance((&m.positions, &m.faces), (&im.positions, &im.faces), 50_000, 1);
        assert!(r.mean <= 1e-2 * diag, "{n} cells: mean output→input distance {} > 1e-2 cell diagonal {}", r.mean, 1e-2 * diag);
    }
}

#[test]
fn a_torus_with_half_its_faces_flipped_gives_the_clean_torus_bytes() {
    let d = tempfile::tempdir().unwrap();
    let mut clean = TriMesh::default();
    mint_gen::torus([0.0; 3], 1.0, 0.35, 40_000, &mut clean).unwrap();
    let mut flipped = clean.clone();
    let mut rng = mint_testkit::Rng(11);
    for f in &mut flipped.faces {
        if rng.f64() < 0.5 {
            f.swap(1, 2);
        }
    }
    let a = write_trimesh(d.path(), "clean.ply", &clean);
    let b = write_trimesh(d.path(), "flipped.ply", &flipped);
    let (oa, ob) = (d.path().join("a.ply"), d.path().join("b.ply"));
    run(&a, &oa, cells(50_000).with(|o| { o.spec.signs = SignRule::Orient; }));
    let (s, _) = run(&b, &ob, cells(50_000));
    assert_eq!(s.sign_rule, "parity");
    assert!(std::fs::read(&oa).unwrap() == std::fs::read(&ob).unwrap(), "outputs differ");
    let (sp, _) = run(&b, &ob, cells(50_000).with(|o| { o.spec.signs = SignRule::Parity; }));
    assert_eq!(sp.sign_rule, "parity");
    assert!(std::fs::read(&oa).unwrap() == std::fs::read(&ob).unwrap(), "parity output differs");
}

#[test]
fn two_copies_a_tenth_of_a_cell_apart_give_one_watertight_shell() {
    let d = tempfile::tempdir().unwrap();
    let mut one = TriMesh::default();
    mint_gen::sphere([0.0; 3], 1.0, 40_000, &mut one).unwrap();
    let single = write_trimesh(d.path(), "one.ply", &one);
    let (s1, m1) = run(&single, &d.path().join("o1.ply"), cells(100_000));
    let h = s1.cell_size;
    let mut two = one.clone();
    let off = one.positions.len() as u32;
    two.positions.extend(one.positions.iter().map(|p| [p[0] + 0.1 * h, p[1], p[2]]));
    two.faces.extend(one.faces.iter().map(|f| f.map(|i| i + off)));
    let double = write_trimesh(d.path(), "two.ply", &two);
    let (s2, m2) = run(&double, &d.path().join("o2.ply"), cells(100_000));
    assert_eq!(s2.sign_rule, "union");
    let st = check_closed_oriented(&m2).unwrap();
    assert_eq!(st.components, 1, "one shell, not two");
    let f1 = m1.faces.len() as f64;
    assert!((m2.faces.len() as f64 - f1).abs() < 0.05 * f1, "{} vs {}", m2.faces.len(), f1);
}

#[test]
fn real_meshes_resample_at_three_sizes_manifold_and_watertight_when_closed() {
    let Some(data) = mint_testkit::shared_data() else { return };
    let files = [
        "stanford_bunny_zipper_mesh/bun_zipper.ply",
        "stanford_bunny_zipper_mesh/bun_zipper_res2.ply",
        "stanford_bunny_zipper_mesh/bun_zipper_res4.ply",
        "cyberware_horse_mesh/horse.ply",
        "cyberware_igea_mesh/igea.ply",
    ];
    let d = tempfile::tempdir().unwrap();
    for f in files {
        let input = data.join(f);
        for n in [10_000u64, 100_000, 1_000_000] {
            let out = d.path().join("o.ply");
            // Default: holes wider than 16 cells stay open (the bunny's base
            // at 1M cells); never non-manifold, never misoriented.
            let (s, m) = run(&input, &out, cells(n));
            let r = mint_mesh::check(&m.positions, &m.faces);
            assert_eq!((r.non_manifold_edges, r.non_manifold_vertices, r.inconsistently_oriented_edges), (0, 0, 0), "{f} at {n}: {r:?}");
            assert_eq!(r.watertight, s.holes_left_open == 0, "{f} at {n}: {r:?}");
            // --close-all: watertight.
            let (s, m) = run(&input, &out, cells(n).with(|o| { o.spec.max_hole = None; }));
            let r = mint_mesh::check(&m.positions, &m.faces);
            assert!(r.watertight, "{f} at {n} cells with --close-all: {r:?}");
            eprintln!("{f} at {n} cells: {} faces, rule {}, {} lines through holes, {} synthesized", s.output_faces, s.sign_rule, s.inconsistent_lines, s.synthesized_vertices);
        }
    }
}

#[test]
fn single_view_range_scans_resample_without_error_and_never_non_manifold() {
    let Some(data) = mint_testkit::shared_data() else { return };
    let d = tempfile::tempdir().unwrap();
    for f in ["bun000", "top2", "chin"] {
        let input = data.join("stanford_bunny_range_scans").join(format!("{f}.ply"));
        for n in [10_000u64, 100_000, 1_000_000] {
            let out = d.path().join("o.ply");
            // The range-image layer triangulates; the engine sees a mesh.
            let mesh = mint_range::range_image_as_mesh(&input, d.path()).unwrap().expect("a range image");
            let (s, m) = run(mesh.path(), &out, cells(n));
            assert!(s.output_faces > 0, "{f} at {n}");
            let r = mint_mesh::check(&m.positions, &m.faces);
            assert_eq!((r.non_manifold_edges, r.non_manifold_vertices, r.inconsistently_oriented_edges), (0, 0, 0), "{f} at {n}: {r:?}");
        }
        // The temporary mesh of the range image is gone.
        assert!(std::fs::read_dir(d.path()).unwrap().all(|e| !e.unwrap().file_name().to_string_lossy().starts_with(".mint-range-")));
    }
}

#[test]
fn a_hole_wider_than_max_hole_stays_open_with_one_loop_and_close_all_closes_it() {
    let d = tempfile::tempdir().unwrap();
    // A sphere of radius 1 on a grid of cell h; one hole 10 cells across.
    let cells = 200_000u64;
    let h = (2.3f64.powi(3) / cells as f64).cbrt();
    let opts = mint_gen::ScanOptions { holes: 1, flips: 0, patches: 0, slivers: 0, hole_radius: 5.0 * h, noise_amplitude: 0.0, ..Default::default() };
    let input = write_mesh(d.path(), "holed.ply", |s| {
        mint_gen::scan_like(200_000, 3, &opts, s).unwrap();
    });
    let out = d.path().join("o.ply");
    let (s, m) = run(&input, &out, cells_opts(cells).with(|o| { o.spec.max_hole = Some(4); }));
    let r = mint_mesh::check(&m.positions, &m.faces);
    assert_eq!(s.holes_left_open, 1, "{s:?}");
    assert_eq!((r.non_manifold_edges, r.non_manifold_vertices, r.inconsistently_oriented_edges), (0, 0, 0), "{r:?}");
    assert_eq!(r.boundary_loops, 1, "{r:?}");
    assert_eq!(r.non_simple_boundary_edges, 0);
    let (s, m) = run(&input, &out, cells_opts(cells).with(|o| { o.spec.max_hole = None; }));
    assert_eq!(s.holes_left_open, 0);
    let r = mint_mesh::check(&m.positions, &m.faces);
    assert!(r.watertight, "{r:?}");
}

fn cells_opts(n: u64) -> Opts {
    cells(n)
}

/// The summary reports the output's own boundary loops, the same as
/// `mint check` counts on the output, split into slabs or not.
#[test]
fn the_summary_counts_the_boundary_loops_check_counts() {
    let d = tempfile::tempdir().unwrap();
    let input = write_mesh(d.path(), "scan.ply", |s| {
        mint_gen::scan_like(200_000, 5, &mint_gen::ScanOptions::default(), s).unwrap();
    });
    for (max_hole, slabs) in [(1u32, 1u32), (2, 1), (1, 3), (0, 4)] {
        let out = d.path().join("o.ply");
        let o = cells(1_000_000).with(|o| { o.spec.max_hole = Some(max_hole); o.tuning.slabs = slabs; o.tuning.slab_layers = Some(3); });
        let (s, m) = run(&input, &out, o);
        let r = mint_mesh::check(&m.positions, &m.faces);
        assert!(s.holes_left_open > 0, "max_hole {max_hole}: expected open holes");
        assert_eq!((s.output_boundary_edges, s.output_boundary_loops), (r.boundary_edges, r.boundary_loops), "max_hole {max_hole}, {slabs} slabs");
    }
}
