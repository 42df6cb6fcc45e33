//! Hand-made files that exercise format features, each with the exact
//! triangles it must give: PLY extra properties, list types, polygons and
//! short faces in all three encodings; elements in odd order with unknown
//! elements and triangle strips; range grids; OBJ corner forms and
//! relative indices; OFF variants; STL headers that lie.
use mint_core::TriMesh;
use mint_io::{read_info, Format, MeshReader, RangeGrid, ReadOptions};

use super::util::{ply_bytes, read, read_all, write_file, El, V};

const ENCODINGS: [&str; 3] = ["ascii", "binary_little_endian", "binary_big_endian"];

fn n(x: f64) -> V {
    V::N(x)
}
fn l(xs: &[f64]) -> V {
    V::L(xs.to_vec())
}

/// Five vertices with junk properties around x, y, z; faces with a flag
/// before and a texcoord list after the indices: a quad, a 2-gon (skipped),
/// a triangle and a pentagon.
fn polygons(enc: &str) -> Vec<u8> {
    let vertex = El {
        name: "vertex",
        props: &["float x", "uchar red", "double y", "list uchar float junk", "float z", "float confidence"],
        records: vec![
            vec![n(0.0), n(255.0), n(0.0), l(&[9.0, 9.0]), n(0.0), n(1.0)],
            vec![n(1.0), n(0.0), n(0.0), l(&[]), n(0.0), n(1.0)],
            vec![n(1.0), n(0.0), n(1.0), l(&[7.0]), n(0.0), n(1.0)],
            vec![n(0.0), n(0.0), n(1.0), l(&[]), n(0.0), n(1.0)],
            vec![n(0.5), n(0.0), n(0.5), l(&[]), n(1.5), n(0.5)],
        ],
    };
    let face = El {
        name: "face",
        props: &["uchar flags", "list ushort uint vertex_indices", "list uchar float texcoord"],
        records: vec![
            vec![n(7.0), l(&[0.0, 1.0, 2.0, 3.0]), l(&[0.5, 0.5])],
            vec![n(1.0), l(&[0.0, 1.0]), l(&[])],
            vec![n(2.0), l(&[0.0, 1.0, 4.0]), l(&[1.0, 2.0, 3.0])],
            vec![n(0.0), l(&[0.0, 1.0, 2.0, 3.0, 4.0]), l(&[])],
        ],
    };
    ply_bytes(enc, &["comment features test"], &[vertex, face])
}

#[test]
fn ply_polygons_extra_properties_every_encoding_and_chunk_size() {
    let dir = tempfile::tempdir().unwrap();
    let want_faces = vec![[0, 1, 2], [0, 2, 3], [0, 1, 4], [0, 1, 2], [0, 2, 3], [0, 3, 4]];
    let want_pos = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0], [0.5, 0.5, 1.5]];
    for enc in ENCODINGS {
        let p = write_file(dir.path(), &format!("{enc}.ply"), &polygons(enc));
        for chunk in [1, 2, 4, 65536] {
            let (m, stats) = read_all(&p, ReadOptions { chunk_triangles: chunk, ..ReadOptions::default() }).unwrap();
            assert_eq!(m, TriMesh { positions: want_pos.clone(), faces: want_faces.clone() }, "{enc} chunk {chunk}");
            assert_eq!((stats.triangles, stats.short_faces), (6, 1), "{enc}");
            // Variable-size vertex records are spilled in every encoding.
            assert_eq!(stats.spilled_vertices, 5, "{enc}");
        }
        let info = read_info(&p).unwrap();
        assert_eq!(info.encoding, enc);
        assert_eq!(info.face_count, Some(4));
        assert_eq!(info.comments, vec!["features test"]);
        assert_eq!(info.elements[1].properties[1], "list ushort uint vertex_indices");
    }
}

#[test]
fn ply_fixed_vertex_records_of_any_scalar_types_are_read_in_place() {
    let dir = tempfile::tempdir().unwrap();
    for (tx, ty, tz) in [("char", "int16", "uint8"), ("uint32", "float64", "short"), ("int", "ushort", "float32")] {
        let props = [format!("{tx} x"), "float nx".to_string(), format!("{ty} y"), format!("{tz} z"), "uchar alpha".to_string()];
        let props: Vec<&str> = props.iter().map(|s| s.as_str()).collect();
        let vertex = El {
            name: "vertex",
            props: &props,
            records: vec![
                vec![n(1.0), n(0.5), n(2.0), n(3.0), n(9.0)],
                vec![n(4.0), n(0.5), n(5.0), n(6.0), n(9.0)],
                vec![n(7.0), n(0.5), n(8.0), n(9.0), n(9.0)],
            ],
        };
        let face = El { name: "face", props: &["list int8 uint16 vertex_index"], records: vec![vec![l(&[2.0, 1.0, 0.0])]] };
        for enc in ENCODINGS {
            let p = write_file(dir.path(), "t.ply", &ply_bytes(enc, &[], &[vertex_clone(&vertex), vertex_clone(&face)]));
            let (m, stats) = read_all(&p, ReadOptions::default()).unwrap();
            assert_eq!(m.positions, vec![[1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [7.0, 8.0, 9.0]], "{enc} {tx} {ty} {tz}");
            assert_eq!(m.faces, vec![[2, 1, 0]]);
            assert_eq!(stats.spilled_vertices, if enc == "ascii" { 3 } else { 0 });
        }
    }
}

fn vertex_clone<'a>(e: &El<'a>) -> El<'a> {
    El { name: e.name, props: e.props, records: e.records.clone() }
}

/// Elements in an unusual order: an unknown element with a list, faces
/// before vertices, another unknown element, the vertices, then strips.
fn odd_order(enc: &str) -> Vec<u8> {
    let material = El { name: "material", props: &["list uchar int ids", "float shine"], records: vec![vec![l(&[1.0, 2.0]), n(0.5)], vec![l(&[]), n(1.0)]] };
    let face = El { name: "face", props: &["list uchar int vertex_indices"], records: vec![vec![l(&[5.0, 4.0, 3.0])], vec![l(&[0.0, 5.0, 1.0])]] };
    let edge = El { name: "edge", props: &["int vertex1", "int vertex2"], records: vec![vec![n(0.0), n(1.0)]] };
    let vertex = El {
        name: "vertex",
        props: &["float x", "float y", "float z"],
        records: (0..6).map(|i| vec![n(i as f64), n((i * i) as f64), n(-(i as f64))]).collect(),
    };
    // Strip 0 1 2 3 4 gives (0,1,2) (2,1,3) (2,3,4); after -1, strip
    // 3 3 4 5 gives the degenerate (3,3,4), dropped, then (4,3,5).
    let strips = El {
        name: "tristrips",
        props: &["list int int vertex_indices"],
        records: vec![vec![l(&[0.0, 1.0, 2.0, 3.0, 4.0, -1.0, 3.0, 3.0, 4.0, 5.0, -1.0])]],
    };
    ply_bytes(enc, &[], &[material, face, edge, vertex, strips])
}

#[test]
fn ply_faces_before_vertices_unknown_elements_and_strips() {
    let dir = tempfile::tempdir().unwrap();
    let want = vec![[5, 4, 3], [0, 5, 1], [0, 1, 2], [2, 1, 3], [2, 3, 4], [4, 3, 5]];
    for enc in ENCODINGS {
        let p = write_file(dir.path(), &format!("{enc}.ply"), &odd_order(enc));
        for chunk in [1, 3, 65536] {
            let (m, stats) = read_all(&p, ReadOptions { chunk_triangles: chunk, ..ReadOptions::default() }).unwrap();
            assert_eq!(m.faces, want, "{enc} chunk {chunk}");
            assert_eq!(m.positions[5], [5.0, 25.0, -5.0]);
            assert_eq!(stats.degenerate_strip_triangles, 1);
            assert_eq!(stats.short_faces, 0);
        }
        let info = read_info(&p).unwrap();
        assert_eq!(info.vertex_count, 6);
        assert_eq!(info.face_count, Some(3), "2 faces + 1 strip record");
        let names: Vec<&str> = info.elements.iter().map(|e| e.name.as_str()).collect();
        assert_eq!(names, ["material", "face", "edge", "vertex", "tristrips"]);
    }
}

#[test]
fn ply_range_grid() {
    let dir = tempfile::tempdir().unwrap();
    let vertex = El { name: "vertex", props: &["float x", "float y", "float z"], records: (0..4).map(|i| vec![n(i as f64), n(0.0), n(1.0)]).collect() };
    let cells = [Some(0.0), None, Some(1.0), Some(2.0), None, Some(3.0)];
    let grid = El {
        name: "range_grid",
        props: &["list uchar int vertex_indices"],
        records: cells.iter().map(|c| vec![l(c.as_slice())]).collect(),
    };
    for enc in ENCODINGS {
        let bytes = ply_bytes(enc, &["obj_info is_mesh 0", "obj_info num_cols 3", "obj_info num_rows 2"], &[vertex_clone(&vertex), vertex_clone(&grid)]);
        let p = write_file(dir.path(), "scan.ply", &bytes);
        let r = MeshReader::open(&p, ReadOptions::default()).unwrap();
        let g = r.range_grid().unwrap();
        assert_eq!(g, RangeGrid { cols: 3, rows: 2, cells: vec![Some(0), None, Some(1), Some(2), None, Some(3)] });
        assert_eq!((g.cell(2, 0), g.cell(1, 1), g.filled()), (Some(1), None, 4));
        assert_eq!(r.info().face_count, None);
        assert_eq!(r.info().obj_info, vec!["is_mesh 0", "num_cols 3", "num_rows 2"]);
        let (m, _) = read_all(&p, ReadOptions::default()).unwrap();
        assert_eq!((m.positions.len(), m.faces.len()), (4, 0));
        // Without the grid size the grid cannot be interpreted.
        let bytes = ply_bytes(enc, &["obj_info num_cols 4"], &[vertex_clone(&vertex), vertex_clone(&grid)]);
        let p = write_file(dir.path(), "bad.ply", &bytes);
        let e = MeshReader::open(&p, ReadOptions::default()).unwrap_err();
        assert!(e.to_string().contains("element 'range_grid'"), "{e}");
    }
}

#[test]
fn obj_corner_forms_relative_indices_and_ignored_lines() {
    let dir = tempfile::tempdir().unwrap();
    let text = "# exported by hand\r\nmtllib a.mtl\no thing\nv 0 0 0\nv 1 0 0 1.0\nv 1 1 0\nvt 0 0\nvn 0 0 1\n\
v 0 1 0 # trailing comment\ng grp\nusemtl m\ns 1\nf 1/1/1 2/1/1 3/1/1 4/1/1\nf -4//1 -3//1 -2//1\nf 1 2\nl 1 2\n\
v 5 5 5\nf -1 -2 -3\nf 5/1 4/1 3/1\n";
    let p = write_file(dir.path(), "a.obj", text.as_bytes());
    let (m, stats) = read_all(&p, ReadOptions::default()).unwrap();
    assert_eq!(m.faces, vec![[0, 1, 2], [0, 2, 3], [0, 1, 2], [4, 3, 2], [4, 3, 2]]);
    assert_eq!(m.positions[4], [5.0, 5.0, 5.0]);
    assert_eq!(stats.short_faces, 1);
    let info = read_info(&p).unwrap();
    assert_eq!((info.vertex_count, info.face_count), (5, Some(5)));
    assert_eq!(info.comments, vec!["exported by hand"]);
}

#[test]
fn obj_lines_continued_with_a_backslash() {
    let dir = tempfile::tempdir().unwrap();
    // A face split over three lines (one with a blank after the backslash,
    // one with CRLF), and a vertex split over two.
    let text = "v 0 0 0\nv 1 0 \\\n 0\nv 1 1 0\nv 0 1 0\nf 1 2 \\\r\n 3 \\ \n 4\nf 1 3 4\n";
    let p = write_file(dir.path(), "c.obj", text.as_bytes());
    let (m, _) = read_all(&p, ReadOptions::default()).unwrap();
    assert_eq!(m.positions[1], [1.0, 0.0, 0.0]);
    assert_eq!(m.faces, vec![[0, 1, 2], [0, 2, 3], [0, 2, 3]]);
    let info = read_info(&p).unwrap();
    assert_eq!((info.vertex_count, info.face_count), (4, Some(2)));
}

#[test]
fn off_variants() {
    let dir = tempfile::tempdir().unwrap();
    // COFF: per-vertex colours; faces with colours; comments, blank lines.
    let text = "# a comment\nCOFF\n\n5 3 0 # counts\n0 0 0 255 0 0 255\n1 0 0 255 0 0 255\n1 1 0 0 0 0 255\n\
0 1 0 1 1 1 1\n0.5 0.5 1.5 0 0 0 0\n4 0 1 2 3 0.5 0.5 0.5\n# between faces\n3 0 1 4\n2 1 2\n\n";
    let p = write_file(dir.path(), "a.off", text.as_bytes());
    let (m, stats) = read_all(&p, ReadOptions::default()).unwrap();
    assert_eq!(m.faces, vec![[0, 1, 2], [0, 2, 3], [0, 1, 4]]);
    assert_eq!(m.positions[4], [0.5, 0.5, 1.5]);
    assert_eq!(stats.short_faces, 1);
    // Counts on the keyword line, CRLF line ends.
    let p = write_file(dir.path(), "b.off", b"OFF 3 1 0\r\n0 0 0\r\n1 0 0\r\n0 1 0\r\n3 0 1 2\r\n");
    assert_eq!(read(&p).faces, vec![[0, 1, 2]]);
    let info = read_info(&p).unwrap();
    assert_eq!((info.format, info.vertex_count, info.face_count), (Format::Off, 3, Some(1)));
}

#[test]
fn stl_binary_header_starting_with_solid_and_multi_solid_ascii() {
    let dir = tempfile::tempdir().unwrap();
    let mut bin = b"solid this is really binary".to_vec();
    bin.resize(80, b' ');
    bin.extend_from_slice(&1u32.to_le_bytes());
    for v in [[0.0f32, 0.0, 1.0], [0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        for c in v {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    bin.extend_from_slice(&[0, 0]);
    let p = write_file(dir.path(), "b.stl", &bin);
    let info = read_info(&p).unwrap();
    assert_eq!((info.encoding.as_str(), info.face_count), ("binary", Some(1)));
    assert_eq!(info.comments, vec!["solid this is really binary"]);
    assert_eq!(read(&p).positions, vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
    // The same bytes without an extension are sniffed as STL.
    let q = write_file(dir.path(), "noext", &bin);
    assert_eq!(Format::from_path(&q).unwrap(), Format::Stl);

    let text = "solid one\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n   vertex 0 1 0\n  endloop\n endfacet\nendsolid one\n\
solid two\n facet normal 0 0 0\n  outer loop\n   vertex 0 0 1e0\n   vertex 1 0 1\n   vertex 0 1 1\n  endloop\n endfacet\nendsolid\n";
    let p = write_file(dir.path(), "t.stl", text.as_bytes());
    let m = read(&p);
    assert_eq!(m.faces, vec![[0, 1, 2], [3, 4, 5]]);
    assert_eq!(m.positions[3], [0.0, 0.0, 1.0]);
    assert_eq!(read_info(&p).unwrap().comments, vec!["one"]);
}

#[test]
fn sniffing_without_extensions() {
    let dir = tempfile::tempdir().unwrap();
    for (name, bytes, format) in [
        ("p", polygons("binary_little_endian"), Format::Ply),
        ("o", b"# x\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".to_vec(), Format::Obj),
        ("f", b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n".to_vec(), Format::Off),
    ] {
        let p = write_file(dir.path(), name, &bytes);
        assert_eq!(Format::from_path(&p).unwrap(), format);
        assert!(!read(&p).faces.is_empty());
    }
    // Extensions are case-insensitive.
    let p = write_file(dir.path(), "UPPER.PLY", &polygons("ascii"));
    assert_eq!(read(&p).faces.len(), 6);
}

#[test]
fn resolve_positions_off_gives_indices_only() {
    let dir = tempfile::tempdir().unwrap();
    let p = write_file(dir.path(), "a.ply", &polygons("binary_little_endian"));
    let (m, _) = read_all(&p, ReadOptions { resolve_positions: false, ..ReadOptions::default() }).unwrap();
    assert_eq!(m.faces.len(), 6);
}

/// Triangles with a flag before the index list and a fixed-size property
/// after it, so that a record is 1 + 1 + 3·4 + 4 bytes.
fn triangles_with_extras(enc: &str, corners: &[usize]) -> Vec<u8> {
    let vertex = El { name: "vertex", props: &["float x", "float y", "float z"], records: (0..9).map(|i| vec![n(i as f64), n(0.0), n((i * i) as f64)]).collect() };
    let face = El {
        name: "face",
        props: &["uchar flags", "list uchar int vertex_indices", "float quality"],
        records: corners.iter().enumerate().map(|(i, &k)| vec![n(i as f64), l(&(0..k).map(|c| ((i + c) % 9) as f64).collect::<Vec<_>>()), n(0.5)]).collect(),
    };
    ply_bytes(enc, &[], &[vertex, face])
}

fn read_range(p: &std::path::Path, first: u64, end: u64, chunk: usize) -> Result<Vec<[u32; 3]>, mint_io::Error> {
    let mut r = MeshReader::open_range(p, ReadOptions { chunk_triangles: chunk, ..ReadOptions::default() }, first, end)?;
    let mut out = Vec::new();
    let mut c = mint_io::TriangleChunk::new();
    while r.next_chunk(&mut c)? {
        assert!(c.len() <= chunk);
        out.extend_from_slice(&c.indices);
    }
    Ok(out)
}

#[test]
fn binary_files_read_in_ranges_give_the_whole_file_in_order() {
    let dir = tempfile::tempdir().unwrap();
    for enc in ["binary_little_endian", "binary_big_endian"] {
        let p = write_file(dir.path(), &format!("{enc}.ply"), &triangles_with_extras(enc, &[3; 11]));
        let whole = read(&p).faces;
        assert_eq!(whole.len(), 11);
        let r = MeshReader::open(&p, ReadOptions::default()).unwrap();
        assert_eq!(r.splittable_records(), Some(11));
        for cuts in [vec![0u64, 11], vec![0, 4, 8, 11], vec![0, 0, 5, 5, 11], vec![0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11]] {
            for chunk in [1, 3, 65536] {
                let mut got = Vec::new();
                for w in cuts.windows(2) {
                    got.extend(read_range(&p, w[0], w[1], chunk).unwrap());
                }
                assert_eq!(got, whole, "{enc} cuts {cuts:?} chunk {chunk}");
            }
        }
        // A quad inside the range: one error naming the record, never a wrong split.
        let q = write_file(dir.path(), &format!("quad-{enc}.ply"), &triangles_with_extras(enc, &[3, 3, 3, 4, 3, 3]));
        assert!(read_range(&q, 0, 3, 2).is_ok());
        let e = read_range(&q, 2, 5, 2).unwrap_err().to_string();
        assert!(e.contains("record 3") && e.contains("4 corners"), "{e}");
        // Beyond the end of a truncated body: refused up front.
        let bytes = triangles_with_extras(enc, &[3; 11]);
        let t = write_file(dir.path(), &format!("trunc-{enc}.ply"), &bytes[..bytes.len() - 5]);
        assert!(MeshReader::open_range(&t, ReadOptions::default(), 0, 11).is_err());
    }
    // Text files cannot be split; binary STL can.
    let a = write_file(dir.path(), "ascii.ply", &triangles_with_extras("ascii", &[3; 4]));
    assert_eq!(MeshReader::open(&a, ReadOptions::default()).unwrap().splittable_records(), None);
    let e = MeshReader::open_range(&a, ReadOptions::default(), 0, 2).unwrap_err().to_string();
    assert!(e.contains("cannot be read in parts"), "{e}");
    let stl = dir.path().join("t.stl");
    let m = read(&dir.path().join("binary_little_endian.ply"));
    super::util::write(&stl, Format::Stl, Default::default(), &m);
    let whole = read(&stl).faces;
    let mut got = read_range(&stl, 0, 6, 4).unwrap();
    got.extend(read_range(&stl, 6, 11, 4).unwrap());
    assert_eq!(got, whole);
}

/// An ascii PLY as VCGLIB writes some (a public test file trimesh reads):
/// face lines carry more numbers than the header declares. The declared
/// values are read, the rest of each line is ignored, and one warning names
/// the element and the first such line; CRLF line ends count as line ends.
/// Records still may span lines (the tokenizer reads on to the next line
/// when a line holds too few values).
#[test]
fn ascii_ply_lines_with_undeclared_values_are_read_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    for eol in ["\n", "\r\n"] {
        let lines = [
            "ply",
            "format ascii 1.0",
            "comment VCGLIB generated",
            "element vertex 4",
            "property float x",
            "property float y",
            "property float z",
            "element face 4",
            "property list uchar int vertex_indices",
            "end_header",
            "0 0 0",
            "1 0 0 0.5",
            "0 1 0",
            "0 0 1",
            "3 0 2 1 6 0.1 0.2 0.3 0.4 0.5 0.6",
            "3 0 1 3",
            "3 0",
            "  3 2",
            "3 1 2 3 6 0 0 1 0 0 1 ",
        ];
        let text = lines.join(eol) + eol;
        let p = write_file(dir.path(), "vcg.ply", text.as_bytes());
        let (m, _) = read_all(&p, ReadOptions::default()).unwrap();
        assert_eq!(m.faces, vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]], "{eol:?}");
        assert_eq!(m.positions[1], [1.0, 0.0, 0.0]);
        let mut r = MeshReader::open(&p, ReadOptions::default()).unwrap();
        let mut chunk = mint_io::TriangleChunk::new();
        while r.next_chunk(&mut chunk).unwrap() {}
        let w = r.warnings();
        assert_eq!(w.len(), 2, "{w:?}");
        assert!(w[0].contains("vcg.ply: line 12: element 'vertex'") && w[0].contains("(1 line like this)"), "{w:?}");
        assert!(w[1].contains("vcg.ply: line 15: element 'face'") && w[1].contains("1 property") && w[1].contains("(2 lines like this)"), "{w:?}");
    }
}
