//! Round trips and bad inputs for the formats of layered reconstruction
//! (`mesh`, raw, VRML 2.0, 3DS): every writer read back by its reader, with
//! exact coordinates where the format keeps them; chains through
//! [`convert`]; detection by content; a 3DS mesh too big for one object;
//! and errors that name the file and position.

use crate::{convert, read_info, ErrorKind, Format, MeshReader, MeshWriter, ReadOptions, TriangleChunk, WriteOptions};
use mint_core::TriMesh;
use std::path::Path;

/// An octahedron with coordinates exact in f32, plus one unused vertex.
fn octahedron() -> TriMesh {
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

fn write(path: &Path, m: &TriMesh, opts: WriteOptions) {
    let mut w = MeshWriter::create(path, Format::from_path(path).unwrap(), opts).unwrap();
    for p in &m.positions {
        w.write_vertex(*p).unwrap();
    }
    for f in &m.faces {
        w.write_face(*f).unwrap();
    }
    let s = w.finish().unwrap();
    assert_eq!(s.bytes, std::fs::metadata(path).unwrap().len());
}

fn read(path: &Path) -> TriMesh {
    let mut r = MeshReader::open(path, ReadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    let mut m = TriMesh { positions: (0..r.vertex_count()).map(|i| r.vertex(i)).collect(), faces: Vec::new() };
    let mut c = TriangleChunk::new();
    while r.next_chunk(&mut c).unwrap_or_else(|e| panic!("{e}")) {
        m.faces.extend_from_slice(&c.indices);
    }
    m
}

fn soup(m: &TriMesh) -> Vec<[[f64; 3]; 3]> {
    m.faces.iter().map(|f| f.map(|i| m.positions[i as usize])).collect()
}

#[test]
fn indexed_formats_round_trip_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let m = octahedron();
    for name in ["a.mesh", "b.wrl", "c.3ds"] {
        let p = dir.path().join(name);
        write(&p, &m, WriteOptions::default());
        assert_eq!(read(&p), m, "{name}");
        let info = read_info(&p).unwrap();
        assert_eq!((info.vertex_count, info.face_count), (7, Some(8)), "{name}");
        // Detected by content too, under a neutral name.
        let q = dir.path().join(format!("{name}.data"));
        std::fs::copy(&p, &q).unwrap();
        assert_eq!(Format::from_path(&q).unwrap(), Format::from_path(&p).unwrap(), "{name}");
    }
    // f64 coordinates survive the text formats with `double`.
    let mut fine = m.clone();
    fine.positions[0] = [0.1, 1.0 / 3.0, -2e-7];
    for name in ["d.mesh", "e.wrl"] {
        let p = dir.path().join(name);
        write(&p, &fine, WriteOptions { double: true, ..Default::default() });
        assert_eq!(read(&p), fine, "{name}");
    }
}

#[test]
fn raw_is_a_soup_and_converts_back_by_welding() {
    let dir = tempfile::tempdir().unwrap();
    let m = octahedron();
    let raw = dir.path().join("a.raw");
    write(&raw, &m, WriteOptions::default());
    let back = read(&raw);
    assert_eq!(back.positions.len(), 24);
    assert_eq!(soup(&back), soup(&m));
    assert_eq!(read_info(&raw).unwrap().format, Format::Raw);
    let q = dir.path().join("a.data");
    std::fs::copy(&raw, &q).unwrap();
    assert_eq!(Format::from_path(&q).unwrap(), Format::Raw);
    // raw → mesh welds equal corners: the 6 used vertices come back.
    let mesh = dir.path().join("b.mesh");
    let s = convert(&raw, &mesh, ReadOptions::default(), WriteOptions::default(), &mut |_, _| {}).unwrap();
    assert_eq!((s.vertices_written, s.triangles), (6, 8));
    assert_eq!(soup(&read(&mesh)), soup(&m));
}

#[test]
fn convert_chains_through_every_new_format() {
    let dir = tempfile::tempdir().unwrap();
    let m = octahedron();
    let start = dir.path().join("start.ply");
    write(&start, &m, WriteOptions::default());
    let mut prev = start;
    for name in ["1.mesh", "2.wrl", "3.3ds", "4.obj", "5.raw", "6.stl", "7.off"] {
        let next = dir.path().join(name);
        convert(&prev, &next, ReadOptions::default(), WriteOptions::default(), &mut |_, _| {}).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(soup(&read(&next)), soup(&m), "{name}");
        prev = next;
    }
}

#[test]
fn mesh_files_with_1_based_indices_are_detected() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("one.mesh");
    std::fs::write(&p, "mesh\n# a quad, 1-based\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n").unwrap();
    let m = read(&p);
    assert_eq!(m.faces, vec![[0, 1, 2], [0, 2, 3]]);
    assert_eq!(read_info(&p).unwrap().elements[1].properties, vec!["vertex_indices (1-based)"]);
    let p0 = dir.path().join("zero.mesh");
    std::fs::write(&p0, "mesh\nv 0 0 0\nv 1 0 0\nv 1 1 0\nf 0 1 2\n").unwrap();
    assert_eq!(read(&p0).faces, vec![[0, 1, 2]]);
}

#[test]
fn a_big_mesh_is_cut_into_3ds_objects_and_read_back_whole() {
    // A strip of 70,000 quads: 140,002 vertices, 140,000 faces; no object
    // may hold more than 65,535 of either.
    let n = 70_000u32;
    let mut m = TriMesh::default();
    for i in 0..=n {
        m.positions.push([i as f64, 0.0, 0.0]);
        m.positions.push([i as f64, 1.0, 0.0]);
    }
    for i in 0..n {
        let (a, b, c, d) = (2 * i, 2 * i + 2, 2 * i + 3, 2 * i + 1);
        m.faces.push([a, b, c]);
        m.faces.push([a, c, d]);
    }
    m.positions.push([5.0, 5.0, 5.0]); // unused
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("big.3ds");
    write(&p, &m, WriteOptions::default());
    let info = read_info(&p).unwrap();
    assert!(info.elements.len() >= 3, "{} objects", info.elements.len());
    for e in &info.elements {
        assert!(e.count <= 65_535, "{}: {} faces", e.name, e.count);
    }
    let back = read(&p);
    assert_eq!(soup(&back), soup(&m));
    // The unused vertex is kept (in a trailing object).
    assert!(back.positions.contains(&[5.0, 5.0, 5.0]));
}

#[test]
fn bad_inputs_name_the_file_and_position() {
    let dir = tempfile::tempdir().unwrap();
    let cases: [(&str, &[u8], ErrorKind, &str); 6] = [
        ("a.mesh", b"mesh\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 7\n", ErrorKind::Index, "(element 'f', record 0, line 5, byte offset 29)"),
        ("b.mesh", b"mesh\nv 0 0 0\nq 1 2 3\n", ErrorKind::Format, "(line 3, byte offset 13)"),
        ("c.raw", b"0 0 0 1 0 0 0 1 0\n1 2 3\n", ErrorKind::Format, "line 2"),
        ("d.wrl", b"#VRML V2.0 utf8\nShape { geometry IndexedFaceSet { coordIndex [ 0 1 2 ] } }\n", ErrorKind::Format, "line 2"),
        ("e.wrl", b"#VRML V1.0 ascii\n", ErrorKind::Unsupported, "VRML 1.0"),
        ("f.3ds", b"MM\x10\x00\x00\x00\x3d\x3d\xff\x00\x00\x00\x00\x00\x00\x00", ErrorKind::Format, "byte offset 6"),
    ];
    for (name, bytes, kind, needle) in cases {
        let p = dir.path().join(name);
        std::fs::write(&p, bytes).unwrap();
        let e = MeshReader::open(&p, ReadOptions::default()).and_then(|mut r| {
            let mut c = TriangleChunk::new();
            while r.next_chunk(&mut c)? {}
            Ok(())
        });
        let e = e.err().unwrap_or_else(|| panic!("{name} should fail"));
        assert_eq!(e.kind(), kind, "{name}: {e}");
        let s = e.to_string();
        assert!(s.starts_with(&p.display().to_string()) && s.contains(needle), "{name}: {s}");
        assert_eq!(s.lines().count(), 1);
    }
    // A 3DS face index past its object's points.
    let mut d = Vec::new();
    let chunk = |id: u16, body: &[u8]| -> Vec<u8> {
        let mut c = id.to_le_bytes().to_vec();
        c.extend_from_slice(&(6 + body.len() as u32).to_le_bytes());
        c.extend_from_slice(body);
        c
    };
    let mut pts = 3u16.to_le_bytes().to_vec();
    for _ in 0..9 {
        pts.extend_from_slice(&0f32.to_le_bytes());
    }
    let mut fcs = 1u16.to_le_bytes().to_vec();
    for x in [0u16, 1, 9, 7] {
        fcs.extend_from_slice(&x.to_le_bytes());
    }
    let mesh = chunk(0x4100, &[chunk(0x4110, &pts), chunk(0x4120, &fcs)].concat());
    let obj = chunk(0x4000, &[b"x\0".to_vec(), mesh].concat());
    d.extend(chunk(0x4D4D, &chunk(0x3D3D, &obj)));
    let p = dir.path().join("g.3ds");
    std::fs::write(&p, &d).unwrap();
    let mut r = MeshReader::open(&p, ReadOptions::default()).unwrap();
    let e = r.next_chunk(&mut TriangleChunk::new()).err().unwrap();
    assert_eq!(e.kind(), ErrorKind::Index);
    assert!(e.to_string().contains("uses point 9, but the object has 3 points"), "{e}");
}
