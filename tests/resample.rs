//! `mint resample` end to end through the library: generated closed inputs
//! at several grid sizes and offsets must give watertight, 2-manifold,
//! outward surfaces of the input's genus, with zero non-canonical cells,
//! vertices on the input surface, and bounded Metro distance; the output
//! bytes must not depend on threads, slabs or the memory budget; and a
//! 5-million-face input resamples under a 256 MiB heap limit.

use crate::common::{box_mesh, load, union, write_mesh, write_trimesh};
use mint_core::{GridSize, TriMesh, MARGIN};
use mint_mesh::TriangleBvh;
use crate::common::{resample, Opts};
use mint_pipeline::{NoProgress, ResampleSummary};
use mint_testkit::topology::check_closed_oriented;
use std::path::{Path, PathBuf};

fn run(input: &Path, out: &Path, opts: Opts) -> (ResampleSummary, TriMesh) {
    let s = resample(input, out, &opts, &NoProgress).unwrap();
    (s, load(out))
}

fn opts(size: GridSize) -> Opts {
    Opts::new(size)
}

/// All the properties a clean closed input must give.
fn assert_good(name: &str, input: &TriMesh, s: &ResampleSummary, out: &TriMesh, genus: Option<i64>) {
    assert_eq!(s.non_canonical_cells, 0, "{name}: non-canonical cells {:?}", s.non_canonical_list);
    let st = check_closed_oriented(out).unwrap_or_else(|e| panic!("{name}: {e}"));
    assert!(st.volume > 0.0, "{name}: volume {}", st.volume);
    let report = mint_mesh::check(&out.positions, &out.faces);
    assert!(report.watertight, "{name}: {report:?}");
    assert_eq!(report.unreferenced_vertices, 0, "{name}");
    assert_eq!(report.degenerate_faces, 0, "{name}: zero-area faces");
    if let Some(g) = genus {
        assert_eq!(report.genus_total, g, "{name}: genus");
    }
    // Every output vertex lies on the input surface, up to the margin and
    // the f32 rounding of the output file.
    let bvh = TriangleBvh::new(&input.positions, &input.faces).unwrap();
    let scale = input.positions.iter().flat_map(|p| p.iter()).fold(0.0f64, |m, x| m.max(x.abs()));
    let tol = MARGIN * s.cell_size * 1.01 + 4.0 * f32::EPSILON as f64 * scale;
    for p in &out.positions {
        let (d, _, _) = bvh.nearest(*p);
        assert!(d <= tol, "{name}: vertex {p:?} is {d} from the input (tolerance {tol})");
    }
    // Metro distance both ways within one cell diagonal.
    let diag = s.cell_size * 3f64.sqrt();
    let (ab, ba) = mint_mesh::symmetric_distance((&out.positions, &out.faces), (&input.positions, &input.faces), 20_000, 7);
    assert!(ab.max <= diag, "{name}: output→input max {} > cell diagonal {diag}", ab.max);
    assert!(ba.max <= diag, "{name}: input→output max {} > cell diagonal {diag}", ba.max);
}

struct Case {
    name: &'static str,
    mesh: TriMesh,
    genus: Option<i64>,
}

fn cases() -> Vec<Case> {
    let gen = |f: &dyn Fn(&mut TriMesh)| {
        let mut m = TriMesh::default();
        f(&mut m);
        m
    };
    let mut boxes = box_mesh([0.0, 0.0, 0.0], [4.0, 3.0, 5.0]);
    union(&mut boxes, &box_mesh([6.0, 1.0, 1.0], [8.0, 2.0, 3.0]));
    vec![
        Case { name: "sphere", mesh: gen(&|m| drop(mint_gen::sphere([0.1, 0.2, -0.3], 1.0, 20_000, m).unwrap())), genus: Some(0) },
        Case { name: "torus", mesh: gen(&|m| drop(mint_gen::torus([0.0; 3], 1.0, 0.35, 20_000, m).unwrap())), genus: Some(1) },
        Case { name: "genus-3", mesh: gen(&|m| drop(mint_gen::genus(3, 20_000, m).unwrap())), genus: Some(3) },
        Case { name: "components", mesh: gen(&|m| drop(mint_gen::components(20_000, 3, m).unwrap())), genus: None },
        Case { name: "integer boxes", mesh: boxes, genus: Some(0) },
    ]
}

#[test]
fn closed_inputs_give_watertight_outputs_at_several_sizes_and_offsets() {
    let dir = tempfile::tempdir().unwrap();
    for case in cases() {
        let input = write_trimesh(dir.path(), &format!("{}.ply", case.name.replace(' ', "_")), &case.mesh);
        let input_mesh = load(&input); // as stored (f32)
        let sizes: Vec<GridSize> = if case.name == "integer boxes" {
            vec![GridSize::CellSize(1.0), GridSize::CellSize(0.5), GridSize::CellSize(0.25)]
        } else if case.name == "components" {
            // Balls smaller than a cell vanish by design (detail below the
            // cell size is dropped); test grids whose cells are smaller.
            vec![GridSize::Cells(40_000), GridSize::Cells(200_000)]
        } else {
            vec![GridSize::Cells(3_000), GridSize::Cells(40_000)]
        };
        for size in sizes {
            for offset in [[0.0; 3], [0.5, 0.25, 0.125]] {
                if case.name == "integer boxes" && offset != [0.0; 3] {
                    continue; // keep box faces exactly on grid planes
                }
                let out = dir.path().join("out.ply");
                let (s, m) = run(&input, &out, opts(size).with(|o| { o.spec.grid.offset = offset; }));
                let genus = if case.name == "components" { None } else { case.genus };
                assert_good(&format!("{} {size:?} {offset:?}", case.name), &input_mesh, &s, &m, genus);
            }
        }
    }
}

#[test]
fn mean_distance_falls_as_the_cell_shrinks() {
    let dir = tempfile::tempdir().unwrap();
    let input = write_mesh(dir.path(), "torus.ply", |s| drop(mint_gen::torus([0.0; 3], 1.0, 0.35, 60_000, s).unwrap()));
    let im = load(&input);
    let mut means = Vec::new();
    for cells in [2_000u64, 20_000, 200_000] {
        let out = dir.path().join(format!("t{cells}.ply"));
        let (_, m) = run(&input, &out, opts(GridSize::Cells(cells)));
        let (_, ba) = mint_mesh::symmetric_distance((&m.positions, &m.faces), (&im.positions, &im.faces), 50_000, 3);
        means.push(ba.mean);
    }
    assert!(means[0] > means[1] && means[1] > means[2], "means {means:?}");
}

#[test]
fn output_bytes_do_not_depend_on_threads_slabs_or_memory() {
    let dir = tempfile::tempdir().unwrap();
    let input = write_mesh(dir.path(), "g.ply", |s| drop(mint_gen::genus(2, 50_000, s).unwrap()));
    let reference = dir.path().join("ref.ply");
    let base = opts(GridSize::Cells(30_000)).with(|o| { o.tuning.threads = 1; });
    let (s0, _) = run(&input, &reference, base.clone());
    assert_eq!(s0.slabs, 1, "the reference run is one slab");
    let want = std::fs::read(&reference).unwrap();
    let variants: Vec<(&str, Opts)> = vec![
        ("threads 2", base.clone().with(|o| { o.tuning.threads = 2; })),
        ("slab 1", base.clone().with(|o| { o.tuning.slab_layers = Some(1); o.tuning.threads = 2; })),
        ("slab 7", base.clone().with(|o| { o.tuning.slab_layers = Some(7); })),
        // The smallest budget (a smaller --mem is raised to it).
        ("small mem", base.clone().with(|o| { o.tuning.mem_bytes = mint_pipeline::Budget::MIN; o.tuning.threads = 2; })),
    ];
    for (name, o) in variants {
        let out = dir.path().join("v.ply");
        let (s, _) = run(&input, &out, o);
        assert!(name == "threads 2" || name == "small mem" || s.slabs > 1, "{name}: expected several slabs, got {}", s.slabs);
        assert!(std::fs::read(&out).unwrap() == want, "{name}: output bytes differ");
    }
}

fn mint_bin() -> PathBuf {
    PathBuf::from(env!("CARGO_BIN_EXE_mint"))
}

/// Resamples a generated sphere of `faces` faces to about 10M cells under a
/// 256 MiB heap limit (RLIMIT_DATA) and checks the output.
fn resample_under_limit(faces: u64) {
    if std::process::Command::new("prlimit").arg("--version").output().is_err() {
        if std::env::var_os("MINT_REQUIRE_DATA").is_some_and(|v| v != "0") {
            panic!("MINT_REQUIRE_DATA is set (CI): prlimit (util-linux) is not installed");
        }
        eprintln!("skipping: prlimit (util-linux) is not installed");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("big.ply");
    let st = std::process::Command::new(mint_bin())
        .args(["gen", "sphere"])
        .arg(&input)
        .args(["--faces", &faces.to_string()])
        .status()
        .unwrap();
    assert!(st.success());
    let out = dir.path().join("out.ply");
    let o = std::process::Command::new("prlimit")
        .arg("--data=268435456")
        .arg(mint_bin())
        .arg("resample")
        .arg(&input)
        .arg(&out)
        .args(["--cells", "10000000", "--mem", "200M", "--json", "--quiet"])
        .output()
        .unwrap();
    assert!(o.status.success(), "resample under 256 MiB failed: {}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["non_canonical_cells"], 0);
    assert!(v["peak_heap_bytes"].as_u64().unwrap() < 256 << 20);
    let m = load(&out);
    let r = mint_mesh::check(&m.positions, &m.faces);
    assert!(r.watertight && r.genus_total == 0, "{r:?}");
    // The check of the input stays within --mem under half that limit: in
    // generation order its corners are judged as they come, and with
    // vertices and faces shuffled they spill to disk.
    let shuffled = dir.path().join("shuffled.ply");
    let st = std::process::Command::new(mint_bin()).args(["gen", "sphere"]).arg(&shuffled).args(["--faces", &faces.to_string(), "--order", "shuffled"]).status().unwrap();
    assert!(st.success());
    for (file, must_spill) in [(&input, false), (&shuffled, true)] {
        let o = std::process::Command::new("prlimit").arg("--data=134217728").arg(mint_bin()).args(["check", &file.display().to_string(), "--json", "--mem", "48M"]).output().unwrap();
        assert!(o.status.success(), "check under 128 MiB failed: {}", String::from_utf8_lossy(&o.stderr));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!((v["watertight"].as_bool(), v["faces"].as_u64()), (Some(true), Some(faces)));
        if must_spill {
            assert!(v["spilled_bytes"].as_u64().unwrap() > 0, "the shuffled check was meant to spill under --mem 48M");
        }
    }
    std::fs::remove_file(&shuffled).unwrap();
    // A picture of the input streams through the same limit.
    let png = dir.path().join("in.png");
    let o = std::process::Command::new("prlimit").arg("--data=268435456").arg(mint_bin()).arg("render").arg(&input).arg(&png).args(["--json", "--quiet"]).output().unwrap();
    assert!(o.status.success(), "render under 256 MiB failed: {}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["triangles"].as_u64(), Some(faces));
}

#[test]
fn five_million_faces_resample_under_a_256_mib_heap_limit() {
    resample_under_limit(5_000_000);
}

/// By hand: `cargo test --release --test tests twenty_million -- --ignored`
#[test]
#[ignore = "writes 380 MB of temporary files; run by hand: cargo test --release --test tests twenty_million -- --ignored"]
fn twenty_million_faces_resample_under_a_256_mib_heap_limit() {
    resample_under_limit(20_000_000);
}

/// Real scans list vertices in no spatial order: the same mesh with its
/// vertices and faces shuffled resamples to the same bytes, through the
/// direct path (binary PLY), the streaming path (OBJ) and split into parts,
/// and with either way of dereferencing faces: the memory map, and the
/// sort, here under a budget small enough that its buckets spill to disk.
#[test]
fn a_shuffled_copy_resamples_to_the_same_bytes_with_mmap_and_sort_dereferencing() {
    use mint_pipeline::Deref;
    let dir = tempfile::tempdir().unwrap();
    let mut m = TriMesh::default();
    mint_gen::genus(2, 200_000, &mut m).unwrap();
    let ordered = write_mesh(dir.path(), "o.ply", |s| {
        for p in &m.positions {
            s.vertex(*p).unwrap();
        }
        for f in &m.faces {
            s.face(*f).unwrap();
        }
    });
    let shuffled = write_mesh(dir.path(), "s.ply", |s| mint_gen::shuffle_mesh(&m, 7, s).unwrap());
    let shuffled_obj = write_mesh(dir.path(), "s.obj", |s| mint_gen::shuffle_mesh(&m, 8, s).unwrap());
    let ordered_obj = write_mesh(dir.path(), "o.obj", |s| {
        for p in &m.positions {
            s.vertex(*p).unwrap();
        }
        for f in &m.faces {
            s.face(*f).unwrap();
        }
    });
    let run_it = |input: &Path, o: Opts| {
        let out = dir.path().join("out.ply");
        let (s, _) = run(input, &out, o);
        (std::fs::read(&out).unwrap(), s)
    };
    let bytes = |input: &Path, o: Opts| run_it(input, o).0;
    let base = opts(GridSize::Cells(80_000));
    let want = bytes(&ordered, base.clone().with(|o| { o.tuning.deref = Deref::Mmap; }));
    let want_obj = bytes(&ordered_obj, base.clone().with(|o| { o.tuning.deref = Deref::Mmap; }));
    for deref in [Deref::Mmap, Deref::Sort] {
        let d = base.clone().with(|o| { o.tuning.deref = deref; });
        // 20 MiB: the sort's corner buckets (about 4.8 MB) spill.
        let small = d.clone().with(|o| { o.tuning.mem_bytes = 20 << 20; });
        assert!(bytes(&ordered, d.clone()) == want, "{deref:?}: ordered binary PLY differs");
        let (got, s) = run_it(&shuffled, small.clone());
        assert!(got == want, "{deref:?}: shuffled binary PLY differs");
        assert_eq!(s.deref.starts_with("sort"), deref == Deref::Sort, "{}", s.deref);
        if deref == Deref::Sort {
            assert!(s.deref_spilled_bytes > 0, "the sort was meant to spill under 20 MiB");
        }
        let parts = d.clone().with(|o| { o.tuning.parts = 3; o.tuning.slabs = 2; o.tuning.work_dir = Some(dir.path().join(format!("w-{deref:?}"))); o.tuning.mem_bytes = 49 << 20; });
        assert!(bytes(&shuffled, parts) == want, "{deref:?}: shuffled binary PLY in parts differs");
        assert!(bytes(&shuffled_obj, small) == want_obj, "{deref:?}: shuffled OBJ differs");
    }
    // auto: this mesh's positions fit in cache, so the map is used.
    let (got, s) = run_it(&shuffled, base);
    assert!(got == want && s.deref.starts_with("mmap: the positions"), "{}", s.deref);
}

/// The staged engine's hole protocol (reconstruct stage, then reopen) and
/// mint-core's in-core one (`resample_in_core_holes`) give the same mesh on
/// a scan with holes, some closed and some left open by `--max-hole`, with
/// the grid cut into slabs: the property tests of the protocol test the
/// code that runs.
#[test]
fn the_engine_and_the_in_core_hole_protocol_give_the_same_mesh() {
    use mint_core::in_core::resample_in_core_holes;
    let dir = tempfile::tempdir().unwrap();
    let scan = write_mesh(dir.path(), "scan.ply", |s| {
        mint_gen::scan_like(60_000, 3, &Default::default(), s).unwrap();
    });
    let (positions, faces) = mint_io::read_mesh(&scan).unwrap();
    let tris: Vec<[[f64; 3]; 3]> = faces.iter().map(|f| f.map(|i| positions[i as usize])).collect();
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in &positions {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let (mut closed, mut open) = (0, 0);
    for max_hole in [1, 4, 8] {
        let out = dir.path().join(format!("out-{max_hole}.ply"));
        let o = opts(GridSize::Cells(40_000)).with(|o| { o.spec.max_hole = Some(max_hole); o.tuning.slabs = 3; o.tuning.work_dir = Some(dir.path().join(format!("w-{max_hole}"))); o.spec.write.double = true; });
        let (s, engine) = run(&scan, &out, o);
        (closed, open) = (closed + s.holes_closed, open + s.holes_left_open);
        let g = mint_core::Grid::around(lo, hi, GridSize::Cells(40_000), [0.0; 3], None).unwrap();
        assert_eq!((g.origin, g.cell, g.dims), (s.grid_origin, s.cell_size, s.grid_cells));
        let mut core = TriMesh::default();
        let (_, _, _, holes) = resample_in_core_holes(&g, tris.iter().copied(), mint_core::signs::SignRule::Auto, Some(max_hole), &mut core).unwrap();
        assert_eq!((holes.closed, holes.left_open), (s.holes_closed, s.holes_left_open));
        assert!(core.faces == engine.faces, "max_hole {max_hole}: other faces");
        assert!(core.positions == engine.positions, "max_hole {max_hole}: other vertices");
    }
    assert!(closed > 0 && open > 0, "the scan was meant to have holes both closed and left open: {closed} closed, {open} open");
}

/// Tiny cases where the surface passes exactly through grid nodes or two
/// solids touch along a line, each count with its reason.
#[test]
fn tiny_cases_on_nodes_and_touching_along_a_line_give_their_exact_counts() {
    let dir = tempfile::tempdir().unwrap();
    let run_mesh = |m: &TriMesh| {
        let input = write_trimesh(dir.path(), "in.ply", m);
        let out = dir.path().join("out.ply");
        let (s, out) = run(&input, &out, opts(GridSize::CellSize(1.0)));
        let r = mint_mesh::check(&out.positions, &out.faces);
        assert!(r.watertight, "{r:?}");
        (s.output_vertices, s.output_faces, r.components, s.grid_origin)
    };
    // [1, 2]³ on unit cells: extent 1 → 1 cell plus one of padding each
    // side, so the grid's nodes are 0, 1, 2, 3 and every corner of the box
    // is a node. A crossing exactly on a node is taken as just below it
    // (the tie-break), so a node on the surface is inside at the box's low
    // side and outside at its high side: inside nodes {n : 1 <= n < 2} =
    // {1}³, one node, whose six edges each cross once: an octahedron,
    // 6 vertices and 8 faces.
    let (v, f, c, origin) = run_mesh(&box_mesh([1.0; 3], [2.0; 3]));
    assert_eq!(origin, [0.0; 3]);
    assert_eq!((v, f, c), (6, 8, 1));
    // [1, 3]³ the same way: inside {1, 2}³, the 2×2×2 block of the other
    // test: 24 vertices, 44 faces.
    let (v, f, c, _) = run_mesh(&box_mesh([1.0; 3], [3.0; 3]));
    assert_eq!((v, f, c), (24, 44, 1));
    // Two boxes touching along the line x = y = 1.7: [0.3, 1.7]² × [0.3,
    // 2.7] and [1.7, 3.1]² × [0.3, 2.7]. The grid (extent 2.8 × 2.8 × 2.4)
    // has x and y nodes at -0.8 + i and z nodes at -1 + k, so the first
    // box holds nodes {1.2}² × {1, 2} and the second {2.2}² × {1, 2}:
    // two 1×1×2 columns, diagonal to each other, never joined by a grid
    // edge. The cells between them see two diagonal inside corners, which
    // the table separates: two components. Each column has 2·(1·1 + 1·2 +
    // 2·1) = 10 vertices (two per line through it) and, being a sphere
    // with 3F/2 edges, F = 2·(10 - 2) = 16 faces.
    let mut two = box_mesh([0.3, 0.3, 0.3], [1.7, 1.7, 2.7]);
    union(&mut two, &box_mesh([1.7, 1.7, 0.3], [3.1, 3.1, 2.7]));
    let (v, f, c, origin) = run_mesh(&two);
    assert!(origin.iter().zip([-0.8, -0.8, -1.0]).all(|(a, b)| (a - b).abs() < 1e-6), "{origin:?}"); // f32 input: 0.3 is 0.30000001…
    assert_eq!((v, f, c), (20, 32, 2));
}

/// Tiny cases with exact counts, each with its reason (as OpenVDB's "a
/// filled 6³ box gives exactly 216 quads").
#[test]
fn tiny_boxes_give_exactly_the_counts_their_inside_nodes_dictate() {
    let dir = tempfile::tempdir().unwrap();
    let counts = |lo: f64, hi: f64| {
        let input = write_trimesh(dir.path(), "box.ply", &box_mesh([lo; 3], [hi; 3]));
        let out = dir.path().join("out.ply");
        let (s, m) = run(&input, &out, opts(GridSize::CellSize(1.0)));
        let r = mint_mesh::check(&m.positions, &m.faces);
        assert!(r.watertight && r.genus_total == 0, "{r:?}");
        (s.output_vertices, s.output_faces)
    };
    // A box [0.3, 2.7]³ on unit cells: the grid (extent 2.4 → 3 cells plus
    // one of padding each side, centred) has nodes at -1, 0, …, 4, so the
    // nodes inside are {1, 2}³, a 2×2×2 block. Each of the 3·2·2 = 12
    // lines through the block crosses the box twice: 24 vertices. Faces:
    // one quad (2 triangles) per block face, a strip of one quad (2
    // triangles) per block edge, one triangle per corner: 6·2 + 12·2 + 8 = 44.
    assert_eq!(counts(0.3, 2.7), (24, 44));
    // [0.3, 3.7]³: extent 3.4 → 4 cells + 2, centre 2 → nodes at -1 … 5,
    // inside {1, 2, 3}³: 3·3·3 = 27 lines, 54 vertices; faces: 4 quads
    // per block face (8 triangles), 2 quads per block edge (4), 8 corners:
    // 6·8 + 12·4 + 8 = 104 (and V − E + F = 54 − 156 + 104 = 2).
    assert_eq!(counts(0.3, 3.7), (54, 104));
}
