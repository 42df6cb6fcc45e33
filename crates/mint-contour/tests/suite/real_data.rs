//! Real data from `../shared/data` (skipped with a message when absent):
//! the Stanford bunny sliced into 100 sections and rebuilt by both methods,
//! measured against the original (the `mint distance` figures are printed);
//! and the contour stacks of a real RT structure set (DICOM RTSTRUCT,
//! converted to profiles here), including a lung with branching.
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
            // The angle method is a heuristic: it is closed here, but its
            // strips cut across concave parts; report how many triangles cross.
            check_closed_oriented(&m).unwrap();
            let clash = super::util::clashing_faces(&m);
            let flat = |f: usize| { let t = m.faces[f].map(|i| m.positions[i as usize][2]); t[0] == t[1] && t[1] == t[2] };
            let kinds = clash.iter().fold([0usize; 3], |mut k, &(a, b)| { k[flat(a) as usize + flat(b) as usize] += 1; k });
            let mut zs: Vec<i64> = clash.iter().map(|&(a, _)| (m.positions[m.faces[a][0] as usize][2] * 1e4) as i64).collect();
            zs.sort(); zs.dedup();
            eprintln!("bunny angle: {} pairs of crossing triangles (tube-tube {}, tube-cap {}, cap-cap {}), at {} heights: {:?}", clash.len(), kinds[0], kinds[1], kinds[2], zs.len(), &zs[..zs.len().min(40)]);
            assert!(ab.mean_rel <= 0.01, "angle mean distance {} of the diagonal", ab.mean_rel);
        }
    }
}

/// The contours of one ROI of `rtss_contours.txt` as a profile.
fn rtstruct_profile(txt: &str, roi: &str) -> String {
    let mut out = String::from("pro\n");
    let mut in_roi = false;
    let mut first_in_slice = false;
    for line in txt.lines() {
        let w: Vec<&str> = line.split_whitespace().collect();
        match w.first() {
            Some(&"ROI") => in_roi = w.get(2) == Some(&roi),
            Some(&"SLICE") if in_roi => first_in_slice = true,
            Some(&"CONTOUR") if in_roi => {
                out.push_str(if first_in_slice { "section\n" } else { "contour\n" });
                first_in_slice = false;
            }
            Some(x) if in_roi && (x.starts_with('-') || x.as_bytes()[0].is_ascii_digit()) => {
                out.push_str(line);
                out.push('\n');
            }
            _ => {}
        }
    }
    out
}

#[test]
fn rtstruct_body_and_lung_stacks() {
    let Some(data) = data_dir() else { return };
    let txt = std::fs::read_to_string(data.join("rtstruct_dicompyler_breast/rtss_contours.txt")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    for roi in ["BODY", "Lt_Lung", "Heart"] {
        let pro = dir.path().join(format!("{roi}.pro"));
        std::fs::write(&pro, rtstruct_profile(&txt, roi)).unwrap();
        let out = dir.path().join(format!("{roi}-mc.ply"));
        let r = run::reconstruct_file(&pro, &out, Method::Mc(McOptions { cubes: 128, caps: true, ..Default::default() }), WriteOptions::default(), NEVER);
        let st = match r {
            Ok(st) => st,
            Err(e) => {
                // Real clinical contours may break the contract; the error
                // must then name the file and the line.
                let msg = e.to_string();
                eprintln!("rtstruct {roi}: refused: {msg}");
                assert!(msg.starts_with(&pro.display().to_string()) && msg.contains("(line "), "{msg}");
                continue;
            }
        };
        let MethodStats::Mc(d) = &st.details else { panic!() };
        eprintln!("rtstruct {roi} mc: {} sections, {} contour vertices -> {} faces in {:.3}s", st.input_faces_or_sections, st.input_vertices, st.faces, st.seconds);
        assert_eq!(d.non_canonical_cells, 0, "{roi}");
        check_closed_oriented(&load(&out)).unwrap_or_else(|e| panic!("{roi}: {e}"));
        let out = dir.path().join(format!("{roi}-angle.ply"));
        let st = run::reconstruct_file(&pro, &out, Method::Angle(AngleOptions { caps: true, ..Default::default() }), WriteOptions::default(), NEVER).unwrap();
        eprintln!("rtstruct {roi} angle: {} faces, {:?}", st.faces, st.details);
    }
}
