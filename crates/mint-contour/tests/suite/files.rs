//! The file drivers behind `mint slice`, `mint contours` and `mint optimize`:
//! a mesh sliced into a profile and rebuilt in every output format, the
//! status counters, bad profiles reported with file and line, and no output
//! left behind on failure.
use super::util::{ellipse, reference_tube};
use mint_contour::angle::AngleOptions;
use mint_contour::mc::McOptions;
use mint_contour::run::{self, Method, MethodStats};
use mint_contour::{ContourError, ProfileErrorKind};
use mint_io::{Format, MeshWriter, WriteOptions};
use mint_testkit::topology::check_closed_oriented;
use std::path::Path;

/// Never asks to stop, shows nothing.
const NEVER: &mint_core::progress::NoProgress = &mint_core::progress::NoProgress;

fn write_mesh(path: &Path, m: &mint_core::TriMesh) {
    let mut w = MeshWriter::create(path, Format::from_path(path).unwrap(), WriteOptions { double: true, ..Default::default() }).unwrap();
    for p in &m.positions {
        w.write_vertex(*p).unwrap();
    }
    for f in &m.faces {
        w.write_face(*f).unwrap();
    }
    w.finish().unwrap();
}

fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    v.sort();
    v
}

#[test]
fn slice_then_rebuild_in_every_format() {
    let dir = tempfile::tempdir().unwrap();
    let solid = reference_tube(&|z, n| ellipse([0.0, 0.0], 1.0 + 0.2 * z, 0.7, 0.2 * z, z, n), 0.0, 2.0, 41, 64);
    let mesh = dir.path().join("solid.ply");
    write_mesh(&mesh, &solid);
    let pro = dir.path().join("solid.pro");
    let s = run::slice_file(&mesh, &pro, 25, 2, NEVER).unwrap();
    let MethodStats::Slice(d) = &s.details else { panic!() };
    assert_eq!((d.planes, d.sections, d.contours, d.chains_closed, d.contours_dropped), (25, 25, 25, 0, 0));
    assert_eq!(s.parameters["sections"], run::Value::Int(25));
    let text = std::fs::read_to_string(&pro).unwrap();
    assert!(text.starts_with("pro\n# sliced from "));
    for (name, method) in [
        ("mc.ply", Method::Mc(McOptions { cubes: 48, caps: true, ..Default::default() })),
        ("mc.mesh", Method::Mc(McOptions { cubes: 48, caps: true, ..Default::default() })),
        ("angle.wrl", Method::Angle(AngleOptions { caps: true, ..Default::default() })),
        ("angle.3ds", Method::Angle(AngleOptions { caps: true, ..Default::default() })),
        ("angle.obj", Method::Angle(AngleOptions { caps: true, ..Default::default() })),
        ("mc-open.off", Method::Mc(McOptions { cubes: 48, caps: false, ..Default::default() })),
    ] {
        let out = dir.path().join(name);
        let st = run::reconstruct_file(&pro, &out, method, WriteOptions::default(), NEVER).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!((st.command.as_str(), st.input_faces_or_sections), ("contours", 25), "{name}");
        let (positions, faces) = run::load_mesh(&out).unwrap();
        assert_eq!((positions.len() as u64, faces.len() as u64), (st.vertices, st.faces), "{name}");
        let m = mint_core::TriMesh { positions, faces };
        if name.starts_with("mc-open") {
            let r = mint_mesh::check(&m.positions, &m.faces);
            assert_eq!((r.boundary_loops, r.non_manifold_edges), (2, 0), "{name}");
        } else {
            check_closed_oriented(&m).unwrap_or_else(|e| panic!("{name}: {e}"));
        }
    }
    // The optimizer through files.
    let opt = dir.path().join("opt.ply");
    let st = run::optimize_file(&dir.path().join("mc.ply"), &opt, 2.0, WriteOptions::default()).unwrap();
    assert!(st.faces < st.input_faces_or_sections);
    assert_eq!(st.parameters["angle"], run::Value::Float(2.0));
}

#[test]
fn bad_profiles_fail_with_file_and_line_and_leave_no_output() {
    let dir = tempfile::tempdir().unwrap();
    let cases: [(&str, ProfileErrorKind, u64); 6] = [
        ("pro\nsection\n0 0 0\n1 0 0\n", ProfileErrorKind::TooFewVertices, 2),
        ("pro\nsection\n0 0 0\n2 0 0\n0 2 0\n2 2 0\n", ProfileErrorKind::SelfIntersecting, 2),
        ("pro\nsection 0 0 0 1 0 0 0 1 0\nsection\n0 0 1\n1 0 1\n0 1 1.5\n1 1 1\n", ProfileErrorKind::NonPlanar, 3),
        ("pro\nsection 0 0 1 1 0 1 0 1 1\nsection 0 0 2 1 0 2 0 1 2\n# back\nsection 0 0 0 1 0 0 0 1 0\n", ProfileErrorKind::OutOfOrder, 5),
        ("pro\nsection 0 0 0 1 0 0 0 1 0\n# c\nsection 0 0 1 1 0 1 x 1 1\n", ProfileErrorKind::Syntax, 4),
        ("PRO\n", ProfileErrorKind::Syntax, 1),
    ];
    for (k, (text, kind, line)) in cases.iter().enumerate() {
        let pro = dir.path().join(format!("bad{k}.pro"));
        std::fs::write(&pro, text).unwrap();
        for method in [Method::Mc(McOptions::default()), Method::Angle(AngleOptions::default())] {
            let out = dir.path().join("out.ply");
            let e = run::reconstruct_file(&pro, &out, method, WriteOptions::default(), NEVER).unwrap_err();
            match &e {
                ContourError::Profile(p) => assert_eq!((p.kind, p.line), (*kind, *line), "case {k}: {e}"),
                other => panic!("case {k}: {other}"),
            }
            let msg = e.to_string();
            assert!(msg.starts_with(&pro.display().to_string()) && msg.ends_with(&format!("(line {line})")), "{msg}");
        }
    }
    // Only the inputs remain: no output, no temporary files.
    let left = entries(dir.path());
    assert!(left.iter().all(|n| n.starts_with("bad")), "{left:?}");
}

#[test]
fn a_cancelled_run_leaves_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let pro = dir.path().join("a.pro");
    std::fs::write(&pro, "pro\nsection 0 0 0 1 0 0 0 1 0\nsection 0 0 1 1 0 1 0 1 1\n").unwrap();
    let e = run::reconstruct_file(&pro, &dir.path().join("a.ply"), Method::Mc(McOptions::default()), WriteOptions::default(), &AlwaysCancelled).unwrap_err();
    assert!(matches!(e, ContourError::Cancelled));
    assert_eq!(entries(dir.path()), vec!["a.pro"]);
}




/// Asks to stop at the first chance.
struct AlwaysCancelled;
impl mint_core::progress::Progress for AlwaysCancelled {
    fn cancelled(&self) -> bool {
        true
    }
}
