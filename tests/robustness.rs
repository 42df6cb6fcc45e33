//! Findings of a fuzzing campaign, run through the `mint` binary: lying
//! headers, huge coordinates, hostile CSG scenes, signals, outputs that are
//! inputs, and outputs that cannot be written. Every failure is one line on
//! stderr naming the file, exit code 1 (130 when interrupted), and nothing
//! is left at the output path.

use crate::cli::mint;
use std::path::{Path, PathBuf};
use std::process::Output;

use crate::cli::{ok, p, run};

fn entries(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).collect();
    v.sort();
    v
}

/// Asserts a clean failure: exit code 1, one line on stderr that contains
/// every one of `needles`, no panic.
fn fails_with(args: &[&str], needles: &[&str]) -> String {
    let o = run(args);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(1), "mint {args:?}: exit {:?}: {err}", o.status);
    assert_eq!(err.lines().count(), 1, "mint {args:?}: not one line: {err}");
    for n in needles {
        assert!(err.contains(n), "mint {args:?}: error lacks {n:?}: {err}");
    }
    err
}

const TRIANGLE_ASCII: &str = "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";

/// Headers that claim 2^32 - 1, 2^62 or 2^64 - 1 faces (PLY ascii, binary,
/// tristrips; OFF) over a file holding one: `check` and `distance` (which
/// load meshes in memory) report the truncation in one line instead of
/// aborting on an allocation of the header's size.
#[test]
fn lying_face_counts_give_a_truncation_error_not_an_allocation_failure() {
    let d = tempfile::tempdir().unwrap();
    let mut files = Vec::new();
    for n in [u32::MAX as u64, 1u64 << 62, u64::MAX] {
        let head = |fmt: &str, el: &str, list: &str| format!("ply\nformat {fmt} 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement {el} {n}\nproperty list {list} vertex_indices\nend_header\n");
        let ascii = d.path().join(format!("ascii{n}.ply"));
        std::fs::write(&ascii, head("ascii", "face", "uchar int") + TRIANGLE_ASCII).unwrap();
        let strips = d.path().join(format!("strips{n}.ply"));
        std::fs::write(&strips, head("ascii", "tristrips", "int int") + TRIANGLE_ASCII).unwrap();
        let binary = d.path().join(format!("binary{n}.ply"));
        let mut b = head("binary_little_endian", "face", "uchar int").into_bytes();
        for v in [0f32, 0., 0., 1., 0., 0., 0., 1., 0.] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b.push(3);
        for i in 0..3i32 {
            b.extend_from_slice(&i.to_le_bytes());
        }
        std::fs::write(&binary, b).unwrap();
        files.extend([ascii, strips, binary]);
    }
    let off = d.path().join("lying.off");
    std::fs::write(&off, format!("OFF\n3 {} 0\n{TRIANGLE_ASCII}", u32::MAX)).unwrap();
    files.push(off);
    for f in &files {
        let name = f.file_name().unwrap().to_str().unwrap();
        fails_with(&["check", p(f)], &[name, "truncated"]);
        fails_with(&["distance", p(f), p(f), "--samples", "10"], &[name, "truncated"]);
    }
}

/// Runs `args`, killing the process after `secs` seconds: a hang fails the
/// test instead of blocking the suite.
fn run_within(args: &[&str], secs: u64) -> Output {
    let mut child = mint().args(args).stdout(std::process::Stdio::piped()).stderr(std::process::Stdio::piped()).spawn().unwrap();
    let t0 = std::time::Instant::now();
    while child.try_wait().unwrap().is_none() {
        if t0.elapsed().as_secs() >= secs {
            let _ = child.kill();
            let _ = child.wait();
            panic!("mint {args:?} still running after {secs} s");
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

/// A tetrahedron at y = 1e308, and CSG scenes translating a mesh or a
/// primitive by 1e308, used to hang in the exact search along the grid
/// lines: now refused at once, naming the input and the coordinate.
#[test]
fn huge_coordinates_are_refused_up_front_naming_the_input_and_the_value() {
    let d = tempfile::tempdir().unwrap();
    let tet = d.path().join("far.ply");
    std::fs::write(&tet, "ply\nformat ascii 1.0\nelement vertex 4\nproperty double x\nproperty double y\nproperty double z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n0 1e308 0\n1 1e308 0\n0 1e308 1\n0.3 1e308 0.3\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 2 0 3\n").unwrap();
    let sphere = d.path().join("s.ply");
    ok(&["gen", "sphere", p(&sphere), "--faces", "2000"]);
    let mesh_scene = d.path().join("far-mesh.json");
    std::fs::write(&mesh_scene, format!("{{ \"mesh\": {:?}, \"translate\": [0, 1e308, 0] }}", p(&sphere))).unwrap();
    let prim_scene = d.path().join("far-sphere.json");
    std::fs::write(&prim_scene, "{ \"sphere\": { \"radius\": 1 }, \"translate\": [0, 1e308, 0] }").unwrap();
    let out_dir = d.path().join("out");
    std::fs::create_dir(&out_dir).unwrap();
    let out = out_dir.join("o.ply");
    let cases: [(Vec<&str>, &str); 3] = [
        (vec!["resample", p(&tet), p(&out), "--cells", "1000"], "far.ply"),
        (vec!["csg", p(&mesh_scene), p(&out), "--cells", "1000"], "far-mesh.json"),
        (vec!["csg", p(&prim_scene), p(&out), "--cells", "1000"], "far-sphere.json"),
    ];
    for (args, name) in cases {
        let o = run_within(&args, 30);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.contains(name) && err.contains("1e308") && err.contains("2^40"), "{err}");
        assert!(entries(&out_dir).is_empty(), "{args:?} left {:?}", entries(&out_dir));
    }
}

/// CSG scenes: a half-space normal of [1e200, 0, 0] (used to panic), 10,000
/// nested unions (used to overflow the stack), a sphere of radius 1e-100
/// (used to give a face pointing at a vertex never written).
#[test]
fn hostile_scenes_are_meshed_or_refused_in_one_line() {
    let d = tempfile::tempdir().unwrap();
    let out_dir = d.path().join("out");
    std::fs::create_dir(&out_dir).unwrap();
    let out = out_dir.join("o.ply");
    let half = d.path().join("half.json");
    std::fs::write(&half, "{ \"intersection\": [ { \"box\": { \"size\": [2, 2, 2] } },\n { \"halfspace\": { \"normal\": [1e200, 0, 0], \"offset\": 0 } } ] }").unwrap();
    ok(&["csg", p(&half), p(&out), "--cells", "10000", "--quiet"]);
    let c: serde_json::Value = serde_json::from_str(&ok(&["check", p(&out), "--json"])).unwrap();
    assert_eq!(c["watertight"], true);
    // The half box x <= 0.
    assert!(c["bbox_max"][0].as_f64().unwrap() < 0.1 && c["bbox_min"][0].as_f64().unwrap() < -0.9, "{c}");
    std::fs::remove_file(&out).unwrap();
    let nested = d.path().join("nested.json");
    let n = 10_000;
    std::fs::write(&nested, "{ \"union\": [\n".repeat(n) + "{ \"sphere\": { \"radius\": 1 } }" + &" ] }".repeat(n)).unwrap();
    fails_with(&["csg", p(&nested), p(&out), "--cells", "1000"], &["nested.json:", "256"]);
    let tiny = d.path().join("tiny.json");
    std::fs::write(&tiny, "{ \"sphere\": { \"radius\": 1e-100 } }").unwrap();
    ok(&["csg", p(&tiny), p(&out), "--cells", "1000", "--quiet"]);
    let c: serde_json::Value = serde_json::from_str(&ok(&["check", p(&out), "--json"])).unwrap();
    assert_eq!(c["watertight"], true, "{c}");
    assert_eq!(c["genus_total"], 0, "{c}");
    std::fs::remove_file(&out).unwrap();
    assert!(entries(&out_dir).is_empty(), "{:?}", entries(&out_dir));
}

fn signal(pid: u32, sig: &str) {
    let s = std::process::Command::new("kill").args([&format!("-{sig}"), &pid.to_string()]).status().unwrap();
    assert!(s.success(), "kill -{sig} failed");
}

/// Starts `args`, waits `ms`, checks that it is still running (else the
/// test proves nothing and fails), sends `sig`, and returns the output.
fn interrupt(args: &[&str], ms: u64, sig: &str) -> Output {
    let mut child = mint().args(args).stdout(std::process::Stdio::piped()).stderr(std::process::Stdio::piped()).spawn().unwrap();
    std::thread::sleep(std::time::Duration::from_millis(ms));
    assert!(child.try_wait().unwrap().is_none(), "mint {args:?} finished before the signal: use a bigger input");
    signal(child.id(), sig);
    child.wait_with_output().unwrap()
}

/// SIGTERM and SIGHUP stop a run like Ctrl-C: exit 130, the work directory
/// and the temporary output removed; `mint convert` stops too (it used to
/// ignore Ctrl-C), and so does `mint simplify` while it collapses.
#[test]
fn sigterm_and_sighup_stop_cleanly_with_exit_130() {
    let d = tempfile::tempdir().unwrap();
    let input = d.path().join("in.ply");
    ok(&["gen", "sphere", p(&input), "--faces", "2000000"]);
    let out_dir = d.path().join("out");
    std::fs::create_dir(&out_dir).unwrap();
    let out = out_dir.join("o.ply");
    for sig in ["TERM", "HUP"] {
        let o = interrupt(&["resample", p(&input), p(&out), "--cells", "400000000", "--quiet"], 200, sig);
        assert_eq!(o.status.code(), Some(130), "SIG{sig}: {:?}: {}", o.status, String::from_utf8_lossy(&o.stderr));
        assert!(entries(&out_dir).is_empty(), "SIG{sig} left {:?}", entries(&out_dir));
    }
    // The in-core simplifier listens too, between collapses.
    let o = interrupt(&["simplify", p(&input), p(&out_dir.join("s.ply")), "--faces", "100", "--quiet"], 1500, "TERM");
    assert_eq!(o.status.code(), Some(130), "simplify, SIGTERM: {:?}: {}", o.status, String::from_utf8_lossy(&o.stderr));
    assert!(entries(&out_dir).is_empty(), "simplify, SIGTERM left {:?}", entries(&out_dir));
    for (sig, name) in [("INT", "c.obj"), ("TERM", "c.ply"), ("HUP", "c.stl")] {
        let o = interrupt(&["convert", p(&input), p(&out_dir.join(name)), "--ascii", "--quiet"], 100, sig);
        assert_eq!(o.status.code(), Some(130), "convert, SIG{sig}: {:?}: {}", o.status, String::from_utf8_lossy(&o.stderr));
        assert!(entries(&out_dir).is_empty(), "convert, SIG{sig} left {:?}", entries(&out_dir));
    }
}

/// Under a file-size limit the write fails with "File too large" (SIGXFSZ
/// is ignored) and nothing is left behind.
#[test]
fn a_file_size_limit_gives_file_too_large_and_no_debris() {
    if std::process::Command::new("prlimit").arg("--version").output().is_err() {
        if std::env::var_os("MINT_REQUIRE_DATA").is_some_and(|v| v != "0") {
            panic!("MINT_REQUIRE_DATA is set (CI): prlimit (util-linux) is not installed");
        }
        eprintln!("skipping: prlimit (util-linux) is not installed");
        return;
    }
    let d = tempfile::tempdir().unwrap();
    let input = d.path().join("in.ply");
    ok(&["gen", "sphere", p(&input), "--faces", "200000"]);
    let out_dir = d.path().join("out");
    std::fs::create_dir(&out_dir).unwrap();
    for args in [vec!["convert", p(&input), "OUT.obj", "--quiet"], vec!["resample", p(&input), "OUT.ply", "--cells", "1000000", "--quiet"]] {
        let out = out_dir.join(args[2]);
        let args: Vec<&str> = args.iter().map(|a| if a.starts_with("OUT") { p(&out) } else { a }).collect();
        let o = std::process::Command::new("prlimit").arg("--fsize=200000").arg(env!("CARGO_BIN_EXE_mint")).args(&args).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {:?}: {err}", o.status);
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.contains("File too large"), "{err}");
        assert!(entries(&out_dir).is_empty(), "{args:?} left {:?}", entries(&out_dir));
    }
}

/// An output that is an input (same path, `./` spelling, hard link,
/// symbolic link) is refused by every command that writes from inputs,
/// before anything is written; the input keeps its bytes.
#[test]
fn an_output_that_is_an_input_is_refused_and_the_input_kept() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    let scan = dir.join("scan.ply");
    ok(&["gen", "sphere", p(&scan), "--faces", "2000"]);
    let before = std::fs::read(&scan).unwrap();
    let hard = dir.join("hard.ply");
    std::fs::hard_link(&scan, &hard).unwrap();
    let soft = dir.join("soft.ply");
    std::os::unix::fs::symlink(&scan, &soft).unwrap();
    let dotted = format!("{}/./scan.ply", p(dir));
    let scene = dir.join("scene.json");
    std::fs::write(&scene, "{ \"union\": [ { \"mesh\": \"scan.ply\" }, { \"sphere\": { \"radius\": 0.5 } } ] }").unwrap();
    let pro = dir.join("scan.pro");
    ok(&["slice", p(&scan), p(&pro), "--sections", "8", "--quiet"]);
    let pro_before = std::fs::read(&pro).unwrap();
    let work = dir.join("work");
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["resample", p(&scan), p(&scan), "--cells", "1000"], "scan.ply"),
        (vec!["resample", p(&scan), &dotted, "--cells", "1000"], "scan.ply"),
        (vec!["resample", p(&scan), p(&hard), "--cells", "1000"], "hard.ply"),
        (vec!["resample", p(&soft), p(&hard), "--cells", "1000"], "hard.ply"),
        (vec!["convert", p(&scan), p(&hard)], "hard.ply"),
        (vec!["bool", "union", p(&scan), p(&scan), p(&hard), "--cells", "1000"], "hard.ply"),
        (vec!["csg", p(&scene), p(&hard), "--cells", "1000"], "hard.ply"),
        (vec!["csg", p(&scene), p(&scene), "--cells", "1000"], "scene.json"),
        (vec!["slice", p(&scan), p(&hard), "--sections", "4"], "hard.ply"),
        (vec!["contours", p(&pro), p(&pro), "--method", "mc"], "scan.pro"),
        (vec!["optimize", p(&scan), p(&soft), "--angle", "5"], "soft.ply"),
        (vec!["stage", "plan", "resample", p(&scan), p(&hard), "--cells", "1000", "--work", p(&work)], "hard.ply"),
    ];
    for (args, out) in cases {
        let err = fails_with(&args, &[out, "is the same file as the input", "write to another path"]);
        assert!(!err.contains("panicked"), "{err}");
        assert!(std::fs::read(&scan).unwrap() == before, "{args:?} changed the input");
    }
    assert!(std::fs::read(&pro).unwrap() == pro_before);
    // mint scan into the directory holding its input under a view's name.
    let views = dir.join("views");
    std::fs::create_dir(&views).unwrap();
    let mesh = views.join("view_00.mesh.ply");
    std::fs::copy(&scan, &mesh).unwrap();
    fails_with(&["scan", p(&mesh), p(&views), "--views", "2"], &["view_00.mesh.ply", "is the same file as the input"]);
    assert!(std::fs::read(&mesh).unwrap() == before);
    assert_eq!(entries(&views), vec![mesh.clone()]);
}

/// An output that is an existing directory, or whose directory does not
/// exist, fails at once (before the input is even read: a huge input would
/// be discretized first otherwise).
#[test]
fn an_output_directory_fails_before_any_work() {
    let d = tempfile::tempdir().unwrap();
    let input = d.path().join("in.ply");
    ok(&["gen", "sphere", p(&input), "--faces", "2000"]);
    let out_dir = d.path().join("out");
    std::fs::create_dir(&out_dir).unwrap();
    let scene = d.path().join("scene.json");
    std::fs::write(&scene, "{ \"sphere\": { \"radius\": 1 } }").unwrap();
    let missing = d.path().join("nowhere").join("o.ply");
    for out in [&out_dir, &missing] {
        for args in [vec!["resample", p(&input), p(out), "--cells", "1000"], vec!["convert", p(&input), p(out)], vec!["csg", p(&scene), p(out), "--cells", "10"], vec!["optimize", p(&input), p(out), "--angle", "1"]] {
            let name = out.file_name().unwrap().to_str().unwrap();
            let err = fails_with(&args, &[name]);
            assert!(err.contains("is a directory") || err.contains("does not exist"), "{args:?}: {err}");
        }
    }
    assert!(entries(&out_dir).is_empty(), "{:?}", entries(&out_dir));
}

/// A flat input resamples to an empty mesh: exit 0, a warning saying why,
/// and `warnings` in the JSON summary.
#[test]
fn a_flat_input_gives_an_empty_output_with_a_warning() {
    let d = tempfile::tempdir().unwrap();
    let flat = d.path().join("flat.ply");
    let header = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n";
    // A square open sheet is resampled as an open sheet, with a warning
    // that says so (it was empty before open inputs were read as sheets).
    let square = d.path().join("square.ply");
    std::fs::write(&square, header.replace("element face 4", "element face 2") + "3 0 1 2\n3 0 2 3\n").unwrap();
    let out = d.path().join("o.ply");
    let o = run(&["resample", p(&square), p(&out), "--cells", "1000", "--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(j["output_faces"].as_u64().unwrap() > 0, "{j}");
    assert_eq!(j["sign_rule"], "sheet");
    let w = j["warnings"].as_array().unwrap();
    assert!(w.len() == 1 && w[0].as_str().unwrap().contains("the input is open"), "{w:?}");
    // The same square with each face both ways: a closed surface of no
    // thickness, every crossing cancels, nothing is left.
    std::fs::write(&flat, format!("{header}3 0 1 2\n3 0 2 3\n3 0 2 1\n3 0 3 2\n")).unwrap();
    let o = run(&["resample", p(&flat), p(&out), "--cells", "1000", "--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("warning") && err.contains("the output is empty") && err.contains("thinner than a cell"), "{err}");
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["output_faces"], 0);
    let w = j["warnings"].as_array().unwrap();
    assert_eq!(w.len(), 1);
    assert!(w[0].as_str().unwrap().contains("the output is empty"), "{w:?}");
    // A closed input has none.
    let sphere = d.path().join("s.ply");
    ok(&["gen", "sphere", p(&sphere), "--faces", "2000"]);
    let j: serde_json::Value = serde_json::from_str(&ok(&["resample", p(&sphere), p(&out), "--cells", "1000", "--json"])).unwrap();
    assert_eq!(j["warnings"], serde_json::json!([]));
}

/// A binary PLY whose faces are not all triangles (here a two-corner face)
/// has shorter face records than the fixed-size reading assumes; it must be
/// streamed, not refused as truncated (a bug until 2026-12-01: resample
/// and check called it "unexpected end of file").
#[test]
fn a_binary_ply_with_a_two_corner_face_is_read_not_called_truncated() {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/fuzz/regressions/read_ply/binary-face-with-two-corners.ply");
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("out.ply");
    ok(&["resample", &file.display().to_string(), &out.display().to_string(), "--cells", "1000", "--quiet"]);
    let c: serde_json::Value = serde_json::from_str(&ok(&["check", &file.display().to_string(), "--json"])).unwrap();
    assert_eq!(c["faces"].as_u64(), Some(3), "the two-corner face makes no triangle");
}
