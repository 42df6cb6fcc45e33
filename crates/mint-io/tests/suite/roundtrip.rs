//! Round trips: every writer option read back exactly, chains of formats
//! through `convert` (STL welded back into an indexed mesh), and a property
//! test over random meshes on a small lattice.
use std::path::Path;

use mint_core::TriMesh;
use mint_io::{convert, read_info, Format, MeshReader, MeshWriter, ReadOptions, WriteOptions};
use proptest::prelude::*;

use super::util::{as_f32, entries, read, soup, write};

/// An octahedron with coordinates exact in f32, plus one unused vertex.
pub fn octahedron() -> TriMesh {
    let positions = vec![
        [1.5, 0.0, 0.0],
        [-1.5, 0.0, 0.0],
        [0.0, 2.25, 0.0],
        [0.0, -2.25, 0.0],
        [0.0, 0.0, 0.125],
        [0.0, 0.0, -0.125],
        [7.0, 7.0, 7.0],
    ];
    let faces = vec![[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]];
    TriMesh { positions, faces }
}

fn opts(ascii: bool, double: bool) -> WriteOptions {
    WriteOptions { ascii, double, ..WriteOptions::default() }
}

#[test]
fn indexed_formats_round_trip_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let m = octahedron();
    for (name, format, ascii, double, encoding) in [
        ("a.ply", Format::Ply, false, false, "binary_little_endian"),
        ("b.ply", Format::Ply, true, false, "ascii"),
        ("c.ply", Format::Ply, false, true, "binary_little_endian"),
        ("d.ply", Format::Ply, true, true, "ascii"),
        ("e.obj", Format::Obj, false, false, "ascii"),
        ("f.off", Format::Off, false, true, "ascii"),
    ] {
        let p = dir.path().join(name);
        write(&p, format, opts(ascii, double), &m);
        assert_eq!(read(&p), m, "{name}");
        let info = read_info(&p).unwrap();
        assert_eq!((info.format, info.encoding.as_str()), (format, encoding), "{name}");
        assert_eq!((info.vertex_count, info.face_count), (7, Some(8)), "{name}");
    }
    let info = read_info(&dir.path().join("c.ply")).unwrap();
    assert_eq!(info.elements[0].properties, vec!["double x", "double y", "double z"]);
    assert_eq!(info.elements[1].properties, vec!["list uchar int vertex_indices"]);
    assert_eq!(info.comments, vec!["written by mint-io"]);
    // Nothing but the outputs is left in the directory.
    assert_eq!(entries(dir.path()), vec!["a.ply", "b.ply", "c.ply", "d.ply", "e.obj", "f.off"]);
}

#[test]
fn double_keeps_f64_and_float_rounds_to_f32() {
    let dir = tempfile::tempdir().unwrap();
    let m = TriMesh { positions: vec![[0.1, 1.0 / 3.0, -2e-7], [1e10, 2.0, 3.0], [0.0, -0.0, 5.5]], faces: vec![[0, 1, 2]] };
    let f32ed = TriMesh { positions: m.positions.iter().map(|p| p.map(|c| c as f32 as f64)).collect(), faces: m.faces.clone() };
    for (name, format, ascii) in [("a.ply", Format::Ply, false), ("b.ply", Format::Ply, true), ("c.obj", Format::Obj, false), ("d.off", Format::Off, false)] {
        let p = dir.path().join(name);
        write(&p, format, opts(ascii, true), &m);
        assert_eq!(read(&p), m, "{name} double");
        write(&p, format, opts(ascii, false), &m);
        // PLY declares `float`, so the reader rounds to f32 in both
        // encodings; OBJ and OFF give back the decimal of the f32.
        assert_eq!(as_f32(&read(&p)), f32ed, "{name} float");
        if format == Format::Ply {
            assert_eq!(read(&p), f32ed, "{name} float");
        }
    }
}

#[test]
fn stl_is_a_soup_and_convert_welds_it_back() {
    let dir = tempfile::tempdir().unwrap();
    let m = octahedron();
    for (name, ascii) in [("bin.stl", false), ("text.stl", true)] {
        let p = dir.path().join(name);
        write(&p, Format::Stl, opts(ascii, false), &m);
        let s = read(&p);
        // 3 vertices per facet, triangle k = (3k, 3k+1, 3k+2).
        assert_eq!(s.positions.len(), 24);
        assert_eq!(s.faces, (0..8).map(|k| [3 * k, 3 * k + 1, 3 * k + 2]).collect::<Vec<_>>());
        assert_eq!(soup(&s), soup(&m));
        let info = read_info(&p).unwrap();
        assert_eq!(info.encoding, if ascii { "ascii" } else { "binary" });
        assert_eq!((info.vertex_count, info.face_count), (24, Some(8)));
        // Welding: the 6 used vertices come back, in first-use order.
        let out = dir.path().join(format!("{name}.ply"));
        let sum = convert(&p, &out, ReadOptions::default(), WriteOptions::default(), &mut |_, _| {}).unwrap();
        assert_eq!((sum.vertices_read, sum.vertices_written, sum.triangles), (24, 6, 8));
        let w = read(&out);
        assert_eq!(w.positions.len(), 6);
        assert_eq!(soup(&w), soup(&m));
    }
    // A binary STL's facet normals are the unit right-hand normals.
    let bytes = std::fs::read(dir.path().join("bin.stl")).unwrap();
    let f = |at: usize| f32::from_le_bytes(bytes[at..at + 4].try_into().unwrap());
    let n0 = [f(84), f(88), f(92)];
    let expect: [f64; 3] = [2.25 * 0.125, 1.5 * 0.125, 1.5 * 2.25];
    let len = (expect[0] * expect[0] + expect[1] * expect[1] + expect[2] * expect[2]).sqrt();
    for k in 0..3 {
        assert!((n0[k] as f64 - expect[k] / len).abs() < 1e-6, "{n0:?}");
    }
}

#[test]
fn convert_chain_through_every_format() {
    let dir = tempfile::tempdir().unwrap();
    let m = octahedron();
    let start = dir.path().join("0.ply");
    write(&start, Format::Ply, opts(true, false), &m);
    let chain = ["1.obj", "2.stl", "3.off", "4.ply", "5.stl", "6.obj", "7.ply"];
    let mut prev = start.clone();
    let mut calls = 0;
    for (i, name) in chain.iter().enumerate() {
        let next = dir.path().join(name);
        let w = WriteOptions { ascii: i % 2 == 0, ..WriteOptions::default() };
        convert(&prev, &next, ReadOptions::default(), w, &mut |done, total| {
            assert!(done <= total);
            calls += 1;
        })
        .unwrap();
        prev = next;
    }
    assert!(calls >= chain.len());
    let end = read(&prev);
    // The unused vertex is lost when the chain passes through STL.
    assert_eq!(end.positions.len(), 6);
    assert_eq!(soup(&end), soup(&m));
    // Without STL in between, conversion is exact, unused vertex included.
    let a = dir.path().join("a.off");
    let b = dir.path().join("b.ply");
    convert(&start, &a, ReadOptions::default(), WriteOptions::default(), &mut |_, _| {}).unwrap();
    convert(&a, &b, ReadOptions::default(), WriteOptions::default(), &mut |_, _| {}).unwrap();
    assert_eq!(read(&b), m);
}

#[test]
fn same_result_for_every_chunk_size() {
    let dir = tempfile::tempdir().unwrap();
    let m = octahedron();
    let p = dir.path().join("a.ply");
    write(&p, Format::Ply, WriteOptions::default(), &m);
    for chunk in [0, 1, 2, 3, 5, 7, 8, 65536] {
        let mut r = MeshReader::open(&p, ReadOptions { chunk_triangles: chunk, ..ReadOptions::default() }).unwrap();
        let mut c = mint_io::TriangleChunk::new();
        let mut faces = Vec::new();
        let mut chunks = 0;
        while r.next_chunk(&mut c).unwrap() {
            assert!(c.len() <= chunk.max(1));
            faces.extend_from_slice(&c.indices);
            chunks += 1;
        }
        assert_eq!(faces, m.faces);
        assert_eq!(chunks, 8usize.div_ceil(chunk.max(1)));
    }
}

fn lattice_mesh() -> impl Strategy<Value = TriMesh> {
    (1usize..12).prop_flat_map(|nv| {
        let pos = prop::collection::vec(prop::array::uniform3(-8i32..8), nv..=nv);
        let faces = prop::collection::vec(prop::array::uniform3(0..nv as u32), 0..20);
        (pos, faces).prop_map(|(pos, faces)| TriMesh {
            positions: pos.into_iter().map(|p| p.map(|c| c as f64 * 0.5)).collect(),
            faces,
        })
    })
}

fn check_all_formats(dir: &Path, m: &TriMesh) {
    for (name, format, ascii) in [("a.ply", Format::Ply, false), ("b.ply", Format::Ply, true), ("c.obj", Format::Obj, false), ("d.off", Format::Off, false)] {
        let p = dir.join(name);
        write(&p, format, opts(ascii, false), m);
        assert_eq!(&read(&p), m, "{name}");
    }
    let stl = dir.join("e.stl");
    write(&stl, Format::Stl, WriteOptions::default(), m);
    assert_eq!(soup(&read(&stl)), soup(m));
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]
    #[test]
    fn random_lattice_meshes_round_trip(m in lattice_mesh()) {
        let dir = tempfile::tempdir().unwrap();
        check_all_formats(dir.path(), &m);
    }
}

/// `write_vertices` and `write_faces` (the bulk path of the Python arrays)
/// write the same bytes as one `write_vertex` and `write_face` each, in
/// every PLY encoding and precision and for a format without a bulk path,
/// and refuse a bad record naming it, appending nothing.
#[test]
fn bulk_writes_give_the_same_bytes_as_one_at_a_time() {
    let d = tempfile::tempdir().unwrap();
    let ps: Vec<[f64; 3]> = (0..70_000).map(|i| { let t = i as f64 * 0.001; [t.sin(), t.cos() * 1e3, -t] }).collect();
    let fs: Vec<[u32; 3]> = (0..69_998u32).map(|i| [i, i + 1, i + 2]).collect();
    for (name, double, ascii) in [("a.ply", false, false), ("b.ply", true, false), ("c.ply", true, true), ("d.off", false, false)] {
        let opts = || WriteOptions { double, ascii, ..Default::default() };
        let (one, bulk) = (d.path().join(format!("one-{name}")), d.path().join(format!("bulk-{name}")));
        let mut w = MeshWriter::create(&one, Format::from_path(&one).unwrap(), opts()).unwrap();
        ps.iter().for_each(|&p| w.write_vertex(p).unwrap());
        fs.iter().for_each(|&f| w.write_face(f).unwrap());
        w.finish().unwrap();
        let mut w = MeshWriter::create(&bulk, Format::from_path(&bulk).unwrap(), opts()).unwrap();
        w.write_vertices(&ps[..1000]).unwrap();
        w.write_vertices(&ps[1000..]).unwrap();
        w.write_faces(&fs).unwrap();
        w.finish().unwrap();
        assert_eq!(std::fs::read(&one).unwrap(), std::fs::read(&bulk).unwrap(), "{name}");
    }
    let bad = d.path().join("bad.ply");
    let mut w = MeshWriter::create(&bad, Format::Ply, WriteOptions::default()).unwrap();
    let mut nan = ps[..10].to_vec();
    nan[7][1] = f64::NAN;
    let e = w.write_vertices(&nan).unwrap_err();
    assert!(e.to_string().contains("vertex 7") || e.to_string().contains("record 7"), "{e}");
    assert_eq!(w.vertices(), 0);
    w.write_vertices(&ps[..10]).unwrap();
    let e = w.write_faces(&[[0, 1, 2], [0, 1, 10]]).unwrap_err();
    assert!(e.to_string().contains("out of range"), "{e}");
    assert_eq!(w.faces(), 0);
}
