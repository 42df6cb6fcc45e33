//! Findings of a fuzzing campaign, run through the `mint` binary: lying
//! headers, huge coordinates, hostile CSG scenes, signals, outputs that are
//! inputs, and outputs that cannot be written. Every failure is one line on
//! stderr naming the file, exit code 1 (130 when interrupted), and nothing
//! is left at the output path.

use crate::cli::mint;
use std::path::{Path, PathBuf};
use std::process::Output;

fn run(args: &[&str]) -> Output {
    mint().args(args).output().unwrap()
}

fn ok(args: &[&str]) -> String {
    let o = run(args);
    assert!(o.status.success(), "mint {args:?} failed: {}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8(o.stdout).unwrap()
}

fn p(path: &Path) -> &str {
    path.to_str().unwrap()
}

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
