//! Helpers shared by the suite: reading a whole mesh through the streaming
//! API (cross-checking chunk positions against random access), writing a
//! `TriMesh`, building PLY files byte by byte in any encoding, error-shape
//! assertions, and running this test binary again as a child under
//! `prlimit`.
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use mint_core::TriMesh;
use mint_io::{Error, ErrorKind, Format, MeshReader, MeshWriter, ReadOptions, ReadStats, TriangleChunk, WriteOptions};

/// The shared real-data folder, or `None` (with a message) if absent.
pub fn data_dir() -> Option<PathBuf> {
    let p = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/data"));
    if p.is_dir() {
        Some(p)
    } else {
        if std::env::var_os("MINT_REQUIRE_DATA").is_some_and(|v| v != "0") {
            panic!("MINT_REQUIRE_DATA is set (CI): real-data folder {} not found", p.display());
        }
        eprintln!("SKIPPED: real-data folder {} not found", p.display());
        None
    }
}

/// Reads every vertex (random access) and every triangle (streaming) of
/// `path`; checks that resolved chunk positions equal `vertex()` lookups.
pub fn read_all(path: &Path, opts: ReadOptions) -> Result<(TriMesh, ReadStats), Error> {
    let resolve = opts.resolve_positions;
    let mut r = MeshReader::open(path, opts)?;
    let mut m = TriMesh::default();
    for i in 0..r.vertex_count() {
        m.positions.push(r.vertex(i));
    }
    let mut chunk = TriangleChunk::new();
    while r.next_chunk(&mut chunk)? {
        assert!(!chunk.is_empty());
        if resolve {
            assert_eq!(chunk.positions.len(), chunk.indices.len());
            for (t, p) in chunk.indices.iter().zip(&chunk.positions) {
                for k in 0..3 {
                    assert_eq!(p[k], m.positions[t[k] as usize]);
                }
            }
        } else {
            assert!(chunk.positions.is_empty());
        }
        m.faces.extend_from_slice(&chunk.indices);
    }
    assert_eq!(r.bytes_done(), r.bytes_total());
    assert!(!r.next_chunk(&mut chunk)?, "a finished reader stays finished");
    Ok((m, r.stats()))
}

/// Reads with default options, panicking on error.
pub fn read(path: &Path) -> TriMesh {
    read_all(path, ReadOptions::default()).unwrap_or_else(|e| panic!("{e}")).0
}

pub fn write(path: &Path, format: Format, opts: WriteOptions, m: &TriMesh) {
    let mut w = MeshWriter::create(path, format, opts).unwrap();
    for p in &m.positions {
        w.write_vertex(*p).unwrap();
    }
    for f in &m.faces {
        w.write_face(*f).unwrap();
    }
    let s = w.finish().unwrap();
    assert_eq!((s.vertices, s.faces), (m.positions.len() as u64, m.faces.len() as u64));
    assert_eq!(s.bytes, std::fs::metadata(path).unwrap().len());
}

/// The mesh with positions rounded to f32 (what text formats without
/// types give back from a `float` writer is the shortest decimal of the
/// f32, whose f32 rounding is exact).
pub fn as_f32(m: &TriMesh) -> TriMesh {
    TriMesh { positions: m.positions.iter().map(|p| p.map(|c| c as f32 as f64)).collect(), faces: m.faces.clone() }
}

/// The triangles as position triples, for comparing soups and welded meshes.
pub fn soup(m: &TriMesh) -> Vec<[[f64; 3]; 3]> {
    m.faces.iter().map(|f| f.map(|i| m.positions[i as usize])).collect()
}

/// Names in a directory, sorted.
pub fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    v.sort();
    v
}

/// Asserts the error's kind and that its Display is one line starting with
/// the path and containing every `parts` string.
pub fn check_error(e: &Error, path: &Path, kind: ErrorKind, parts: &[&str]) {
    let s = e.to_string();
    assert_eq!(e.kind(), kind, "{s}");
    assert_eq!(s.lines().count(), 1, "not one line: {s:?}");
    assert!(s.starts_with(&format!("{}: ", path.display())), "does not start with the path: {s}");
    for p in parts {
        assert!(s.contains(p), "{s:?} lacks {p:?}");
    }
}

/// A PLY value for [`ply_bytes`]: a number or a list.
#[derive(Debug, Clone)]
pub enum V {
    N(f64),
    L(Vec<f64>),
}

/// An element for [`ply_bytes`]: properties as declared after `property`.
pub struct El<'a> {
    pub name: &'a str,
    pub props: &'a [&'a str],
    pub records: Vec<Vec<V>>,
}

fn put(out: &mut Vec<u8>, ty: &str, v: f64, enc: &str) {
    if enc == "ascii" {
        out.extend_from_slice(format!("{v} ").as_bytes());
        return;
    }
    let be = enc == "binary_big_endian";
    macro_rules! b {
        ($t:ty) => {{
            let x = v as $t;
            out.extend_from_slice(&if be { x.to_be_bytes() } else { x.to_le_bytes() });
        }};
    }
    match ty {
        "char" | "int8" => b!(i8),
        "uchar" | "uint8" => b!(u8),
        "short" | "int16" => b!(i16),
        "ushort" | "uint16" => b!(u16),
        "int" | "int32" => b!(i32),
        "uint" | "uint32" => b!(u32),
        "float" | "float32" => b!(f32),
        "double" | "float64" => b!(f64),
        other => panic!("type {other}"),
    }
}

/// Serialises a PLY file in `enc` ("ascii", "binary_little_endian",
/// "binary_big_endian"); `extra_header` lines go after the format line.
pub fn ply_bytes(enc: &str, extra_header: &[&str], els: &[El]) -> Vec<u8> {
    let mut out = format!("ply\nformat {enc} 1.0\n").into_bytes();
    for l in extra_header {
        out.extend_from_slice(format!("{l}\n").as_bytes());
    }
    for el in els {
        out.extend_from_slice(format!("element {} {}\n", el.name, el.records.len()).as_bytes());
        for p in el.props {
            out.extend_from_slice(format!("property {p}\n").as_bytes());
        }
    }
    out.extend_from_slice(b"end_header\n");
    for el in els {
        for rec in &el.records {
            assert_eq!(rec.len(), el.props.len());
            for (p, v) in el.props.iter().zip(rec) {
                let words: Vec<&str> = p.split_whitespace().collect();
                match (v, words.as_slice()) {
                    (V::N(x), [ty, _]) => put(&mut out, ty, *x, enc),
                    (V::L(xs), ["list", ct, it, _]) => {
                        put(&mut out, ct, xs.len() as f64, enc);
                        for x in xs {
                            put(&mut out, it, *x, enc);
                        }
                    }
                    _ => panic!("value {v:?} does not fit property {p}"),
                }
            }
            if enc == "ascii" {
                out.push(b'\n');
            }
        }
    }
    out
}

pub fn write_file(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

/// Runs the `#[ignore]`d test `name` of this binary in a child process
/// under `prlimit <limits>`, with SIGXFSZ ignored (so exceeding
/// RLIMIT_FSIZE makes write() fail with EFBIG instead of killing the
/// child). Returns `None` (after saying so) if prlimit is not available.
pub fn run_child_under_prlimit(name: &str, limits: &[&str], env: &[(&str, &Path)]) -> Option<Output> {
    if Command::new("prlimit").arg("--version").output().is_err() {
        if std::env::var_os("MINT_REQUIRE_DATA").is_some_and(|v| v != "0") {
            panic!("MINT_REQUIRE_DATA is set (CI): prlimit (util-linux) is not installed");
        }
        eprintln!("SKIPPED: prlimit (util-linux) is not installed");
        return None;
    }
    let exe = std::env::current_exe().unwrap();
    let mut cmd = Command::new("sh");
    cmd.arg("-c").arg("trap '' XFSZ; exec \"$@\"").arg("sh").arg("prlimit").args(limits).arg(exe);
    cmd.args([name, "--exact", "--ignored", "--nocapture", "--test-threads=1"]);
    for (k, v) in env {
        cmd.env(k, v);
    }
    Some(cmd.output().unwrap())
}
