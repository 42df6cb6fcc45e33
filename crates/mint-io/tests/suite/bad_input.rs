//! One test per kind of bad input or failing output. Each checks the error
//! kind and that `Display` is one line naming the file, the element and the
//! position, and (where an output is involved) that no output or temporary
//! file is left behind.
//!
//! A full disk is simulated with RLIMIT_FSIZE: the test binary reruns one
//! `#[ignore]`d test as a child under `prlimit --fsize` with SIGXFSZ
//! ignored, so writes past the limit fail with EFBIG, an ordinary I/O error,
//! exactly where a full disk would fail with ENOSPC. This needs no root and
//! no special file system (skipped with a message if prlimit is missing).
use std::path::{Path, PathBuf};

use mint_io::{convert, ErrorKind, Format, MeshReader, MeshWriter, ReadOptions, TriangleChunk, WriteOptions};

use super::roundtrip::octahedron;
use super::util::{check_error, entries, run_child_under_prlimit, write, write_file};

/// Reads `path` to the end and returns the error.
fn read_err(path: &Path) -> mint_io::Error {
    let mut r = match MeshReader::open(path, ReadOptions::default()) {
        Ok(r) => r,
        Err(e) => return e,
    };
    let mut c = TriangleChunk::new();
    loop {
        match r.next_chunk(&mut c) {
            Ok(true) => {}
            Ok(false) => panic!("{} read without error", path.display()),
            Err(e) => return e,
        }
    }
}

/// Converts `input` into a fresh directory and checks it stays empty.
fn convert_fails_cleanly(input: &Path, out_name: &str) -> mint_io::Error {
    let out_dir = tempfile::tempdir().unwrap();
    let e = convert(input, &out_dir.path().join(out_name), ReadOptions::default(), WriteOptions::default(), &mut |_, _| {}).unwrap_err();
    assert_eq!(entries(out_dir.path()), Vec::<String>::new(), "left behind after: {e}");
    e
}

/// A binary octahedron PLY and the offset of its body.
fn binary_ply(dir: &Path) -> (PathBuf, Vec<u8>, usize) {
    let p = dir.join("good.ply");
    write(&p, Format::Ply, WriteOptions::default(), &octahedron());
    let bytes = std::fs::read(&p).unwrap();
    let body = bytes.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    assert_eq!(bytes.len(), body + 7 * 12 + 8 * 13);
    (p, bytes, body)
}

fn ascii_ply(dir: &Path) -> String {
    let p = dir.join("good_ascii.ply");
    write(&p, Format::Ply, WriteOptions { ascii: true, ..WriteOptions::default() }, &octahedron());
    std::fs::read_to_string(&p).unwrap()
}

#[test]
fn truncated_binary_ply_vertex_section() {
    let dir = tempfile::tempdir().unwrap();
    let (_, bytes, body) = binary_ply(dir.path());
    let p = write_file(dir.path(), "cut.ply", &bytes[..body + 50]);
    let e = read_err(&p);
    assert_eq!(
        e.to_string(),
        format!(
            "{}: unexpected end of file: 7 records of 12 bytes declared, the file holds only 4 (truncated file, or the header counts are too large) (element 'vertex', record 4, byte offset {})",
            p.display(),
            body + 48
        )
    );
    check_error(&e, &p, ErrorKind::Format, &[]);
    check_error(&convert_fails_cleanly(&p, "out.obj"), &p, ErrorKind::Format, &["element 'vertex', record 4"]);
}

#[test]
fn truncated_binary_ply_face_section() {
    let dir = tempfile::tempdir().unwrap();
    let (_, bytes, body) = binary_ply(dir.path());
    let face5 = body + 84 + 5 * 13;
    let p = write_file(dir.path(), "cut.ply", &bytes[..face5 + 6]);
    let e = read_err(&p);
    assert_eq!(
        e.to_string(),
        format!(
            "{}: unexpected end of file inside this record (8 records declared; truncated file, or the header counts are too large) (element 'face', record 5, byte offset {face5})",
            p.display()
        )
    );
    check_error(&e, &p, ErrorKind::Format, &[]);
    check_error(&convert_fails_cleanly(&p, "out.ply"), &p, ErrorKind::Format, &["element 'face', record 5"]);
    // Cut exactly between records: the error names the first missing one.
    let p = write_file(dir.path(), "cut2.ply", &bytes[..face5]);
    check_error(&read_err(&p), &p, ErrorKind::Format, &["element 'face', record 5", &format!("byte offset {face5})")]);
}

#[test]
fn truncated_ascii_ply() {
    let dir = tempfile::tempdir().unwrap();
    let text = ascii_ply(dir.path());
    let lines: Vec<&str> = text.lines().collect();
    let header_lines = lines.iter().position(|l| *l == "end_header").unwrap() + 1;
    // Cut in the middle of the 7th face (record 6): "3 3 1 5" -> "3 3".
    let keep = header_lines + 7 + 6;
    let mut cut: String = lines[..keep].iter().map(|l| format!("{l}\n")).collect();
    cut.push_str("3 3");
    let p = write_file(dir.path(), "cut.ply", cut.as_bytes());
    let e = read_err(&p);
    check_error(&e, &p, ErrorKind::Format, &["unexpected end of file", &format!("(element 'face', record 6, line {}, byte offset", keep + 1)]);
    check_error(&convert_fails_cleanly(&p, "out.off"), &p, ErrorKind::Format, &["element 'face', record 6"]);
    // Cut inside the vertex section.
    let cut: String = lines[..header_lines + 3].iter().map(|l| format!("{l}\n")).collect();
    let p = write_file(dir.path(), "cut2.ply", cut.as_bytes());
    check_error(&read_err(&p), &p, ErrorKind::Format, &["unexpected end of file", "(element 'vertex', record 3, line"]);
}

#[test]
fn wrong_counts_trailing_data() {
    let dir = tempfile::tempdir().unwrap();
    // Binary: five extra bytes.
    let (_, mut bytes, body) = binary_ply(dir.path());
    let end = bytes.len();
    bytes.extend_from_slice(&[3, 0, 0, 0, 0]);
    let p = write_file(dir.path(), "extra.ply", &bytes);
    // Read as MeshLab and trimesh read it: the declared elements, the rest
    // ignored and reported as a warning.
    let mut r = MeshReader::open(&p, ReadOptions::default()).unwrap();
    let mut chunk = mint_io::TriangleChunk::new();
    let mut faces = 0;
    while r.next_chunk(&mut chunk).unwrap() {
        faces += chunk.len();
    }
    assert_eq!(r.stats().ignored_trailing_bytes, 5);
    let w = r.warnings();
    assert!(w.len() == 1 && w[0].contains("5 bytes after the last element") && w[0].contains("extra.ply"), "{w:?}");
    assert!(faces > 0);
    assert_eq!(end, body + 84 + 104);
    // Ascii: one face more than declared: also read, 8 bytes ignored.
    let text = ascii_ply(dir.path()) + "3 0 1 2\n";
    let p = write_file(dir.path(), "extra_ascii.ply", text.as_bytes());
    let mut r = MeshReader::open(&p, ReadOptions::default()).unwrap();
    while r.next_chunk(&mut chunk).unwrap() {}
    assert_eq!(r.stats().ignored_trailing_bytes, 8);
    // Ascii: one face fewer than declared.
    let text = ascii_ply(dir.path()).replace("element face 8", "element face 9");
    let p = write_file(dir.path(), "short_ascii.ply", text.as_bytes());
    check_error(&read_err(&p), &p, ErrorKind::Format, &["unexpected end of file", "(element 'face', record 8,"]);
    // OFF: more faces than the counts line says.
    let p = write_file(dir.path(), "a.off", b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 2 1 0\n");
    check_error(&read_err(&p), &p, ErrorKind::Format, &["unexpected data after the last face", "(element 'face', record 1, line 7, byte offset 36)"]);
    // OFF: fewer.
    let p = write_file(dir.path(), "b.off", b"OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    check_error(&read_err(&p), &p, ErrorKind::Format, &["2 faces declared, 1 found", "(element 'face', record 1,"]);
    // Binary STL whose size does not match its facet count.
    let stl = dir.path().join("a.stl");
    write(&stl, Format::Stl, WriteOptions::default(), &octahedron());
    let mut b = std::fs::read(&stl).unwrap();
    b.truncate(b.len() - 20);
    let p = write_file(dir.path(), "cut.stl", &b);
    let e = read_err(&p);
    assert_eq!(
        e.to_string(),
        format!(
            "{}: binary STL says 8 facets, which take 484 bytes, but the file has 464 bytes (the file is truncated) (element 'facet', record 7, byte offset 434)",
            p.display()
        )
    );
}

#[test]
fn index_out_of_range() {
    let dir = tempfile::tempdir().unwrap();
    let (_, mut bytes, body) = binary_ply(dir.path());
    // Face 3 ([3, 0, 4]): its second index becomes 7 (there are 7 vertices).
    let at = body + 84 + 3 * 13 + 5;
    bytes[at..at + 4].copy_from_slice(&7u32.to_le_bytes());
    let p = write_file(dir.path(), "bad.ply", &bytes);
    let e = read_err(&p);
    assert_eq!(
        e.to_string(),
        format!(
            "{}: vertex index 7 is out of range (the file has 7 vertices) (element 'face', record 3, byte offset {})",
            p.display(),
            body + 84 + 39
        )
    );
    check_error(&convert_fails_cleanly(&p, "o.obj"), &p, ErrorKind::Index, &["element 'face', record 3"]);
    // Negative index in ascii.
    let text = ascii_ply(dir.path()).replace("\n3 1 2 5\n", "\n3 1 -2 5\n");
    let p = write_file(dir.path(), "neg.ply", text.as_bytes());
    check_error(&read_err(&p), &p, ErrorKind::Index, &["vertex index -2 is out of range", "(element 'face', record 5, line"]);
    // OBJ: index 0, and an index past the end.
    let p = write_file(dir.path(), "zero.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 0 1 2\n");
    assert_eq!(
        read_err(&p).to_string(),
        format!("{}: vertex index 0 (OBJ indices start at 1) (element 'f', record 1, line 5, byte offset 32)", p.display())
    );
    let p = write_file(dir.path(), "big.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n");
    check_error(&read_err(&p), &p, ErrorKind::Index, &["vertex index 4 is out of range", "(element 'f', record 0, line 4, byte offset 24)"]);
    let p = write_file(dir.path(), "rel.obj", b"v 0 0 0\nf -1 -2 -3\nv 1 0 0\nv 0 1 0\n");
    check_error(&read_err(&p), &p, ErrorKind::Index, &["vertex index -2 is out of range", "1 defined before this line", "(element 'f', record 0, line 2"]);
    // OFF.
    let p = write_file(dir.path(), "a.off", b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n");
    check_error(&read_err(&p), &p, ErrorKind::Index, &["vertex index 3 is out of range", "(element 'face', record 0, line 6, byte offset 28)"]);
}

#[test]
fn nan_coordinate() {
    let dir = tempfile::tempdir().unwrap();
    let (_, mut bytes, body) = binary_ply(dir.path());
    // Vertex 2's x becomes NaN; face 0 ([0, 2, 4]) is the first to use it.
    bytes[body + 24..body + 28].copy_from_slice(&f32::NAN.to_le_bytes());
    let p = write_file(dir.path(), "nan.ply", &bytes);
    let e = read_err(&p);
    assert_eq!(
        e.to_string(),
        format!(
            "{}: vertex 2 used by this face has a non-finite coordinate (NaN, 2.25, 0) (element 'face', record 0, byte offset {})",
            p.display(),
            body + 84
        )
    );
    assert_eq!(e.kind(), ErrorKind::Value);
    check_error(&convert_fails_cleanly(&p, "o.ply"), &p, ErrorKind::Value, &["vertex 2"]);
    // Without positions the same file streams (no check).
    let mut r = MeshReader::open(&p, ReadOptions { resolve_positions: false, ..ReadOptions::default() }).unwrap();
    let mut c = TriangleChunk::new();
    assert!(r.next_chunk(&mut c).unwrap());
    // A NaN in an unused vertex (6) does not stop reading, but convert
    // refuses to copy it.
    let (_, mut bytes, body) = binary_ply(dir.path());
    bytes[body + 6 * 12 + 4..body + 6 * 12 + 8].copy_from_slice(&f32::NAN.to_le_bytes());
    let p = write_file(dir.path(), "unused_nan.ply", &bytes);
    assert_eq!(super::util::read(&p).faces.len(), 8);
    let e = convert_fails_cleanly(&p, "o.obj");
    assert_eq!(e.to_string(), format!("{}: vertex 6 has a non-finite coordinate (7, NaN, 7); it cannot be converted (element 'vertex', record 6)", p.display()));
}

#[test]
fn infinite_coordinate() {
    let dir = tempfile::tempdir().unwrap();
    // Ascii PLY: vertex 5 ("0 0 -0.125") gets -inf; face 4 ([2, 0, 5]) uses it first.
    let text = ascii_ply(dir.path()).replace("\n0 0 -0.125\n", "\n0 0 -inf\n");
    let p = write_file(dir.path(), "inf.ply", text.as_bytes());
    let e = read_err(&p);
    check_error(&e, &p, ErrorKind::Value, &["vertex 5 used by this face has a non-finite coordinate (0, 0, -inf)", "(element 'face', record 4, line"]);
    check_error(&convert_fails_cleanly(&p, "o.stl"), &p, ErrorKind::Value, &["vertex 5"]);
    // OBJ, and a value too large for f64 (parses as infinity).
    let p = write_file(dir.path(), "inf.obj", b"v 0 0 0\nv 1e400 0 0\nv 0 1 0\nf 1 2 3\n");
    check_error(&read_err(&p), &p, ErrorKind::Value, &["vertex 1 used by this face has a non-finite coordinate (inf, 0, 0)", "(element 'f', record 0, line 4"]);
    // ascii STL.
    let p = write_file(dir.path(), "inf.stl", b"solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex inf 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid s\n");
    check_error(&read_err(&p), &p, ErrorKind::Value, &["vertex 1 used by this face", "(element 'facet', record 0)"]);
}

#[test]
fn unknown_format() {
    let dir = tempfile::tempdir().unwrap();
    let p = write_file(dir.path(), "mesh.xyz", b"hello world\n");
    let e = read_err(&p);
    assert_eq!(
        e.to_string(),
        format!("{}: unknown mesh format (the extension is not .ply, .obj, .stl, .off, .mesh, .raw, .wrl, .3ds, .gltf or .glb and the content is none of them)", p.display())
    );
    assert_eq!(e.kind(), ErrorKind::Unsupported);
    convert_fails_cleanly(&p, "o.ply");
    // Known extension, wrong content.
    let p = write_file(dir.path(), "fake.ply", b"PLY?\n");
    check_error(&read_err(&p), &p, ErrorKind::Format, &["not a PLY file", "(element 'header', line 1, byte offset 0)"]);
    // Unknown output extension: refused before anything is created.
    let good = dir.path().join("g.ply");
    write(&good, Format::Ply, WriteOptions::default(), &octahedron());
    let out = tempfile::tempdir().unwrap();
    let target = out.path().join("out.xyz");
    let e = convert(&good, &target, ReadOptions::default(), WriteOptions::default(), &mut |_, _| {}).unwrap_err();
    check_error(&e, &target, ErrorKind::Unsupported, &["unknown output format"]);
    assert!(entries(out.path()).is_empty());
}

#[test]
fn unreadable_path() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("missing.ply");
    let e = read_err(&p);
    assert_eq!(e.to_string(), format!("{}: cannot open for reading: No such file or directory (os error 2)", p.display()));
    assert_eq!(e.kind(), ErrorKind::Io);
    assert_eq!(e.io_error().unwrap().kind(), std::io::ErrorKind::NotFound);
    convert_fails_cleanly(&p, "o.ply");
    let p = dir.path().join("missing");
    check_error(&read_err(&p), &p, ErrorKind::Io, &["cannot open to detect its format"]);
    // A directory.
    let d = dir.path().join("adir.ply");
    std::fs::create_dir(&d).unwrap();
    check_error(&read_err(&d), &d, ErrorKind::Io, &["is a directory"]);
    // A spill directory that does not exist (ascii input must spill).
    let text = dir.path().join("t.ply");
    write(&text, Format::Ply, WriteOptions { ascii: true, ..WriteOptions::default() }, &octahedron());
    let e = MeshReader::open(&text, ReadOptions { spill_dir: Some(dir.path().join("nope")), ..ReadOptions::default() }).unwrap_err();
    check_error(&e, &text, ErrorKind::Io, &["cannot create a spill file in"]);
}

#[test]
fn unwritable_output_path() {
    let dir = tempfile::tempdir().unwrap();
    let good = dir.path().join("g.ply");
    write(&good, Format::Ply, WriteOptions::default(), &octahedron());
    let target = dir.path().join("no/such/dir/out.ply");
    let e = convert(&good, &target, ReadOptions::default(), WriteOptions::default(), &mut |_, _| {}).unwrap_err();
    check_error(&e, &target, ErrorKind::Io, &["cannot create a temporary file beside the output: No such file or directory (os error 2)"]);
    // The output path is an existing directory: the rename at the end
    // fails, and the temporary file is removed.
    let out = tempfile::tempdir().unwrap();
    let target = out.path().join("taken.ply");
    std::fs::create_dir(&target).unwrap();
    let e = convert(&good, &target, ReadOptions::default(), WriteOptions::default(), &mut |_, _| {}).unwrap_err();
    check_error(&e, &target, ErrorKind::Io, &["cannot rename the temporary file onto the output"]);
    assert_eq!(entries(out.path()), vec!["taken.ply"]);
    assert_eq!(entries(&target), Vec::<String>::new());
    // A writer dropped without finish() leaves nothing.
    let mut w = MeshWriter::create(&out.path().join("dropped.ply"), Format::Ply, WriteOptions::default()).unwrap();
    w.write_vertex([0.0; 3]).unwrap();
    drop(w);
    assert_eq!(entries(out.path()), vec!["taken.ply"]);
}

#[test]
fn writer_contract_errors() {
    let out = tempfile::tempdir().unwrap();
    let path = out.path().join("w.ply");
    let mut w = MeshWriter::create(&path, Format::Ply, WriteOptions::default()).unwrap();
    w.write_vertex([0.0; 3]).unwrap();
    let e = w.write_vertex([f64::NAN, 0.0, 0.0]).unwrap_err();
    assert_eq!(e.to_string(), format!("{}: non-finite vertex coordinate (NaN, 0, 0) (element 'vertex', record 1)", path.display()));
    let e = w.write_vertex([1e300, 0.0, 0.0]).unwrap_err();
    check_error(&e, &path, ErrorKind::Value, &["does not fit in 32-bit floats"]);
    w.write_vertex([1.0, 0.0, 0.0]).unwrap();
    w.write_vertex([0.0, 1.0, 0.0]).unwrap();
    let e = w.write_face([0, 1, 3]).unwrap_err();
    assert_eq!(e.to_string(), format!("{}: vertex index 3 is out of range (3 vertices written) (element 'face', record 0)", path.display()));
    w.write_face([0, 1, 2]).unwrap();
    check_error(&w.write_vertex([0.0; 3]).unwrap_err(), &path, ErrorKind::Unsupported, &["after the first face"]);
    drop(w);
    assert!(entries(out.path()).is_empty());
}

/// Environment variable naming the child's output directory.
const CHILD_DIR: &str = "MINT_IO_TEST_CHILD_DIR";

#[test]
fn io_error_while_writing_removes_the_temp_file() {
    let out = tempfile::tempdir().unwrap();
    let Some(o) = run_child_under_prlimit(
        "suite::bad_input::child_write_past_fsize_limit",
        &["--fsize=1000000"],
        &[(CHILD_DIR, out.path())],
    ) else {
        return;
    };
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success() && stdout.contains("CHILD-OK"), "child failed: {:?}\n{stdout}\n{}", o.status, String::from_utf8_lossy(&o.stderr));
    assert!(entries(out.path()).is_empty(), "left behind: {:?}", entries(out.path()));
}

/// Run by the test above, under RLIMIT_FSIZE = 1 MB: writes a 2.6 MB PLY.
#[test]
#[ignore = "run as a child process under prlimit by io_error_while_writing_removes_the_temp_file"]
fn child_write_past_fsize_limit() {
    let Some(dir) = std::env::var_os(CHILD_DIR) else { return };
    let path = Path::new(&dir).join("big.ply");
    let r = (|| {
        let mut w = MeshWriter::create(&path, Format::Ply, WriteOptions::default())?;
        for i in 0..200_000u32 {
            w.write_vertex([i as f64, 0.0, 1.0])?;
        }
        for i in 0..200_000u32 - 2 {
            w.write_face([i, i + 1, i + 2])?;
        }
        w.finish()
    })();
    let e = r.expect_err("writing 2.6 MB under a 1 MB file size limit must fail");
    check_error(&e, &path, ErrorKind::Io, &["cannot write: File too large"]);
    assert!(entries(Path::new(&dir)).is_empty(), "left behind: {:?}", entries(Path::new(&dir)));
    println!("CHILD-OK {e}");
}

/// Reads a file to the end; any outcome but a panic is fine.
fn read_never_panics(path: &Path) {
    if let Ok(mut r) = MeshReader::open(path, ReadOptions { chunk_triangles: 3, ..ReadOptions::default() }) {
        let mut c = TriangleChunk::new();
        while let Ok(true) = r.next_chunk(&mut c) {}
    }
}

/// Valid files of every kind, to be damaged (made once).
fn seeds() -> &'static [(&'static str, Vec<u8>)] {
    static SEEDS: std::sync::OnceLock<Vec<(&'static str, Vec<u8>)>> = std::sync::OnceLock::new();
    SEEDS.get_or_init(|| make_seeds(tempfile::tempdir().unwrap().path()))
}

fn make_seeds(dir: &Path) -> Vec<(&'static str, Vec<u8>)> {
    let m = octahedron();
    let mut out = Vec::new();
    for (name, format, ascii) in [
        ("s.ply", Format::Ply, false),
        ("s_ascii.ply", Format::Ply, true),
        ("s.obj", Format::Obj, false),
        ("s.off", Format::Off, false),
        ("s.stl", Format::Stl, false),
        ("s_ascii.stl", Format::Stl, true),
    ] {
        let p = dir.join(name);
        write(&p, format, WriteOptions { ascii, ..WriteOptions::default() }, &m);
        out.push((name, std::fs::read(&p).unwrap()));
    }
    out
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig { cases: 200, ..Default::default() })]
    /// Truncated or corrupted files give errors, never panics (the
    /// unchecked position reads rely on the layout checks made at open).
    #[test]
    fn damaged_files_never_panic(cut in 0.0f64..1.0, flips in proptest::collection::vec((0.0f64..1.0, 0u8..=255), 0..4)) {
        let dir = tempfile::tempdir().unwrap();
        for (name, bytes) in seeds() {
            let mut bytes = bytes.clone();
            for &(at, b) in &flips {
                let last = bytes.len() - 1;
                let i = ((at * bytes.len() as f64) as usize).min(last);
                bytes[i] = b;
            }
            let keep = (cut * bytes.len() as f64) as usize + 1;
            bytes.truncate(keep.min(bytes.len()));
            let p = write_file(dir.path(), &format!("bad_{name}"), &bytes);
            read_never_panics(&p);
        }
    }
}
