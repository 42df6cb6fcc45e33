//! Real data from `../shared/data` (skipped with a message when absent, a
//! failure under `MINT_REQUIRE_DATA=1`): the Stanford bunny sliced into 100
//! sections and rebuilt by both methods, measured against the original (the
//! `mint distance` figures are printed); and no intersecting faces from
//! either method on the bunny in 50, 100 and 200 sections and the horse and
//! Igea in 100 sections along each axis. The real RT structure sets, read
//! from DICOM, are in `rtstruct`.
use super::util::data_dir;
use mint_contour::angle::AngleOptions;
use mint_contour::mc::McOptions;
use mint_contour::run::{self, Method, MethodStats};
use mint_core::TriMesh;
use mint_io::WriteOptions;
use mint_testkit::topology::check_closed_oriented;
use std::path::Path;

/// Never asks to stop, shows nothing.
const NEVER: &mint_core::progress::NoProgress = &mint_core::progress::NoProgress;

fn load(p: &Path) -> TriMesh {
    let (positions, faces) = run::load_mesh(p).unwrap();
    TriMesh { positions, faces }
}

#[test]
fn bunny_sliced_into_100_sections_and_rebuilt() {
    let Some(data) = data_dir() else { return };
    let bunny = data.join("stanford_bunny_zipper_mesh/bun_zipper.ply");
    let original = load(&bunny);
    let dir = tempfile::tempdir().unwrap();
    let pro = dir.path().join("bunny.pro");
    let s = run::slice_file(&bunny, &pro, 100, 2, NEVER).unwrap();
    let MethodStats::Slice(d) = &s.details else { panic!() };
    eprintln!("bunny sliced: {d:?}");
    assert_eq!(d.sections, 100);
    for (name, method) in [
        ("mc", Method::Mc(McOptions { cubes: 128, caps: true, ..Default::default() })),
        ("angle", Method::Angle(AngleOptions { caps: true, ..Default::default() })),
    ] {
        let out = dir.path().join(format!("{name}.ply"));
        let st = run::reconstruct_file(&pro, &out, method, WriteOptions::default(), NEVER).unwrap();
        let m = load(&out);
        let (ab, ba) = mint_mesh::symmetric_distance((&m.positions, &m.faces), (&original.positions, &original.faces), 200_000, 1);
        eprintln!(
            "bunny {name}: {} vertices, {} faces, {:.3}s; distance to the original: mean {:.3e} ({:.3e} of the diagonal), max {:.3e} ({:.3e}); back: mean {:.3e} ({:.3e}), max {:.3e} ({:.3e}); {:?}",
            st.vertices, st.faces, st.seconds, ab.mean, ab.mean_rel, ab.max, ab.max_rel, ba.mean, ba.mean_rel, ba.max, ba.max_rel, st.details
        );
        if name == "mc" {
            let MethodStats::Mc(d) = &st.details else { panic!() };
            assert_eq!(d.non_canonical_cells, 0);
            check_closed_oriented(&m).unwrap();
            assert!(ab.mean_rel <= 0.005, "mean distance {} of the diagonal", ab.mean_rel);
            assert!(ba.mean_rel <= 0.005, "mean distance back {} of the diagonal", ba.mean_rel);
        } else {
            // Crossings are the business of the tests below.
            check_closed_oriented(&m).unwrap();
            assert!(ab.mean_rel <= 0.01, "angle mean distance {} of the diagonal", ab.mean_rel);
        }
    }
}

/// Slices `mesh` into `sections` planes across `axis` and rebuilds it by
/// both methods, with caps, written as `mint contours` writes by default
/// (binary PLY, f32). Each output, read back and welded as `mint check`
/// does, must be watertight with no intersecting faces (exact
/// `mint_mesh::selfx`); the angle method must join every group.
fn no_crossings(mesh: &Path, sections: u32, axis: usize) {
    let t = std::time::Instant::now();
    let name = format!("{} {sections}{}", mesh.file_stem().unwrap().to_string_lossy(), ["x", "y", "z"][axis]);
    let dir = tempfile::tempdir().unwrap();
    let pro = dir.path().join("stack.pro");
    run::slice_file(mesh, &pro, sections, axis, NEVER).unwrap();
    for (method, m) in [
        ("angle", Method::Angle(AngleOptions { caps: true, ..Default::default() })),
        ("mc", Method::Mc(McOptions { caps: true, ..Default::default() })),
    ] {
        let out = dir.path().join(format!("{method}.ply"));
        let st = run::reconstruct_file(&pro, &out, m, WriteOptions::default(), NEVER).unwrap();
        let (mut positions, mut faces) = run::load_mesh(&out).unwrap();
        mint_mesh::weld(&mut positions, &mut faces);
        let r = mint_mesh::check(&positions, &faces);
        let x = mint_mesh::selfx::self_intersections(&positions, &faces, 4);
        let v = st.volume.clone().unwrap();
        eprintln!(
            "{name} {method}: {} faces, {} intersecting pairs, watertight {}, volume {:.4e} vs planimetric {:.4e} ({:+.2}%); {:?}",
            st.faces, x.pairs, r.watertight, v.mesh, v.planimetric, 100.0 * v.relative_difference.unwrap(), st.details
        );
        assert_eq!(x.pairs, 0, "{name} {method}: intersecting faces, e.g. {:?}", x.examples);
        assert!(r.watertight, "{name} {method}: not watertight: {r:?}");
        if let MethodStats::Angle(d) = &st.details {
            assert_eq!((d.paired, d.apart), (0, 0), "{name}: groups paired off or capped apart");
        }
        // Both surfaces span the sections (mc half a spacing more at each
        // end), so they hold about the planimetric volume.
        assert!(v.relative_difference.unwrap().abs() < 0.02, "{name} {method}: {v:?}");
    }
    eprintln!("{name}: {:.2}s", t.elapsed().as_secs_f64());
}

#[test]
fn bunny_in_50_100_and_200_sections_has_no_crossing_faces() {
    let Some(data) = data_dir() else { return };
    let bunny = data.join("stanford_bunny_zipper_mesh/bun_zipper.ply");
    for n in [50, 100, 200] {
        no_crossings(&bunny, n, 2);
    }
}

#[test]
fn horse_in_100_sections_along_x_y_z_has_no_crossing_faces() {
    let Some(data) = data_dir() else { return };
    for axis in 0..3 {
        no_crossings(&data.join("cyberware_horse_mesh/horse.ply"), 100, axis);
    }
}

#[test]
fn igea_in_100_sections_along_x_y_z_has_no_crossing_faces() {
    let Some(data) = data_dir() else { return };
    for axis in 0..3 {
        no_crossings(&data.join("cyberware_igea_mesh/igea.ply"), 100, axis);
    }
}
