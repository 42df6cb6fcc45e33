//! `mint check` within a memory budget (mint_check::check_file) gives
//! the in-core report (read whole, weld, mint_mesh::check), field for field,
//! on clean and dirty meshes, welded and not, in memory and with a budget
//! so small that its buckets spill to disk.

use crate::common::{write_mesh, write_trimesh};
use mint_core::TriMesh;
use mint_check::{check_file, CheckOptions};
use mint_pipeline::NoProgress;
use std::path::Path;

fn in_core(path: &Path, weld: bool) -> mint_mesh::CheckReport {
    let (mut p, mut f) = mint_io::read_mesh(path).unwrap();
    let welded = if weld { mint_mesh::weld(&mut p, &mut f) } else { 0 };
    let mut r = mint_mesh::try_check(&p, &f).unwrap();
    r.welded_vertices = welded;
    r
}

fn same_report(path: &Path, spill_expected: bool) {
    for weld in [true, false] {
        let want = in_core(path, weld);
        for (mem, threads) in [(1u64 << 30, 1), (1, 2), (1, 3)] {
            let opts = CheckOptions { mem_bytes: mem, weld, tmp_dir: None, threads, list_boundary: 0 };
            let (got, stats) = check_file(path, &opts, &NoProgress).unwrap();
            assert_eq!(got, want, "{} weld {weld} mem {mem} threads {threads}", path.display());
            if mem == 1 && spill_expected {
                assert!(stats.bytes_spilled > 0, "{}: a 16 MiB floor was meant to spill", path.display());
            }
        }
    }
}

#[test]
fn the_bounded_check_gives_the_in_core_report_spilled_or_not() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    // A clean torus (1.2M faces) and the same mesh shuffled. In file order
    // each face goes to one vertex block, judged as soon as it is
    // complete, so whether anything spills under the 16 MiB floor depends
    // on timing; shuffled, every block waits for the end, and its faces
    // must spill.
    let mut torus = TriMesh::default();
    mint_gen::genus(1, 1_200_000, &mut torus).unwrap();
    let t = write_trimesh(dir, "torus.ply", &torus);
    same_report(&t, false);
    let ts = write_mesh(dir, "torus-shuffled.ply", |s| mint_gen::shuffle_mesh(&torus, 3, s).unwrap());
    same_report(&ts, true);
    // A dirty scan: holes, flipped faces, overlaps, non-manifold slivers.
    let scan = write_mesh(dir, "scan.ply", |s| {
        mint_gen::scan_like(200_000, 5, &Default::default(), s).unwrap();
    });
    same_report(&scan, false);
    // Many components, each genus 0.
    let balls = write_mesh(dir, "balls.ply", |s| {
        mint_gen::components(100_000, 2, s).unwrap();
    });
    same_report(&balls, false);
    // A soup (STL stores each corner apart), and the odd cases by hand:
    // collapsed and duplicate faces (collapsed duplicates too), a
    // huge coordinate, an unreferenced vertex, two cubes sharing a corner,
    // -0.0 welding to 0.0.
    let stl = write_trimesh(dir, "torus.stl", &{
        let mut m = TriMesh::default();
        mint_gen::genus(1, 20_000, &mut m).unwrap();
        m
    });
    same_report(&stl, false);
    let mut odd = crate::common::box_mesh([0.0; 3], [1.0; 3]);
    let other = crate::common::box_mesh([1.0; 3], [2.0; 3]);
    crate::common::union(&mut odd, &other);
    let n = odd.positions.len() as u32;
    odd.positions.extend([[1e30, 0.0, 0.0], [5.0, 5.0, 5.0], [-0.0, 0.0, 0.0], [3.0, 3.0, 3.0]]);
    odd.faces.extend([[0, 0, 1], [1, 0, 0], [0, 1, 0], [1, 2, 3], [1, 2, 3], [3, 2, 1], [n + 2, 1, 2], [n + 3, n + 3, n + 3]]);
    let odd = write_trimesh(dir, "odd.obj", &odd);
    same_report(&odd, false);
}
