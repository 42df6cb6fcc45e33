//! Per-vertex colour read (issue 27, its first step): PLY `red green blue
//! [alpha]` as uchar, ushort, float or double, binary (in place) and ASCII
//! (spilled), `diffuse_*` names; OBJ `v x y z r g b`; the real coloured
//! scans of ../shared/data/colour_scans with their stated colours; and one
//! line for each bad colour.

use std::collections::HashSet;

use mint_io::{MeshReader, ReadOptions};

use super::util::{data_dir, write_file};

fn colours_of(path: &std::path::Path) -> Option<Vec<[u8; 4]>> {
    let r = MeshReader::open(path, ReadOptions::default()).unwrap();
    r.colours().map(|c| (0..c.count()).map(|i| c.get(i)).collect())
}

fn ply_header(format: &str, props: &str, n: usize) -> String {
    format!("ply\nformat {format} 1.0\nelement vertex {n}\nproperty float x\nproperty float y\nproperty float z\n{props}element face 1\nproperty list uchar int vertex_indices\nend_header\n")
}

#[test]
fn ply_colours_in_every_type_binary_and_ascii() {
    let d = tempfile::tempdir().unwrap();
    // Binary little-endian, uchar RGB, no alpha: read in place.
    let mut b = ply_header("binary_little_endian", "property uchar red\nproperty uchar green\nproperty uchar blue\n", 3).into_bytes();
    for (k, c) in [[255u8, 0, 0], [0, 128, 0], [1, 2, 3]].iter().enumerate() {
        for x in [k as f32, 0.0, 0.0] {
            b.extend(x.to_le_bytes());
        }
        b.extend(c);
    }
    b.push(3);
    for i in [0i32, 1, 2] {
        b.extend(i.to_le_bytes());
    }
    let p = write_file(d.path(), "u8.ply", &b);
    assert_eq!(colours_of(&p).unwrap(), vec![[255, 0, 0, 255], [0, 128, 0, 255], [1, 2, 3, 255]]);
    // Binary big-endian, ushort RGBA: the high byte.
    let mut b = ply_header("binary_big_endian", "property ushort red\nproperty ushort green\nproperty ushort blue\nproperty ushort alpha\n", 3).into_bytes();
    for k in 0..3u16 {
        for x in [k as f32, 1.0, 0.0] {
            b.extend(x.to_be_bytes());
        }
        for c in [0xFFFFu16, 0x8000, 0x00FF, 0x1234 * (k + 1)] {
            b.extend(c.to_be_bytes());
        }
    }
    b.push(3);
    for i in [0i32, 1, 2] {
        b.extend(i.to_be_bytes());
    }
    let p = write_file(d.path(), "u16.ply", &b);
    assert_eq!(colours_of(&p).unwrap(), vec![[255, 128, 0, 0x12], [255, 128, 0, 0x24], [255, 128, 0, 0x36]]);
    // ASCII, float colours named diffuse_*, clamped and rounded (spilled).
    let t = ply_header("ascii", "property float diffuse_red\nproperty float diffuse_green\nproperty float diffuse_blue\n", 3)
        + "0 0 0 1 0.5 0\n1 0 0 2 -1 0.25\n0 1 0 0 0 1\n3 0 1 2\n";
    let p = write_file(d.path(), "f32.ply", t.as_bytes());
    assert_eq!(colours_of(&p).unwrap(), vec![[255, 128, 0, 255], [255, 0, 64, 255], [0, 0, 255, 255]]);
    // No colour: none; red and green without blue are other properties.
    let t = ply_header("ascii", "", 3) + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    assert!(colours_of(&write_file(d.path(), "none.ply", t.as_bytes())).is_none());
    let t = ply_header("ascii", "property uchar red\nproperty uchar green\n", 3) + "0 0 0 1 2\n1 0 0 1 2\n0 1 0 1 2\n3 0 1 2\n";
    assert!(colours_of(&write_file(d.path(), "partial.ply", t.as_bytes())).is_none());
}

#[test]
fn obj_vertex_colours_and_mixed_lines() {
    let d = tempfile::tempdir().unwrap();
    let p = write_file(d.path(), "c.obj", b"# coloured\nv 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0.5 0.5 1 # a comment\nf 1 2 3\n");
    assert_eq!(colours_of(&p).unwrap(), vec![[255, 0, 0, 255], [0, 255, 0, 255], [128, 128, 255, 255]]);
    // `v x y z w` is not a colour.
    let p = write_file(d.path(), "w.obj", b"v 0 0 0 1\nv 1 0 0 1\nv 0 1 0 1\nf 1 2 3\n");
    assert!(colours_of(&p).is_none());
    for (name, text) in [("mix1.obj", "v 0 0 0 1 0 0\nv 1 0 0\nv 0 1 0 0 0 1\nf 1 2 3\n"), ("mix2.obj", "v 0 0 0\nv 1 0 0 1 1 1\nv 0 1 0\nf 1 2 3\n")] {
        let p = write_file(d.path(), name, text.as_bytes());
        let e = MeshReader::open(&p, ReadOptions::default()).unwrap_err().to_string();
        assert!(e.contains(name) && e.contains("mix 3 and 6 numbers") && e.contains("line 2") && !e.contains('\n'), "{e}");
    }
}

#[test]
fn bad_ply_colours_give_one_line() {
    let d = tempfile::tempdir().unwrap();
    for (name, props, needle) in [
        ("int.ply", "property int red\nproperty int green\nproperty int blue\n", "'red' of an odd type"),
        ("list.ply", "property uchar red\nproperty uchar green\nproperty list uchar uchar blue\n", "'blue' is a list"),
        ("alpha.ply", "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty char alpha\n", "'alpha' of an odd type"),
    ] {
        let t = ply_header("ascii", props, 0);
        let p = write_file(d.path(), name, t.as_bytes());
        let e = MeshReader::open(&p, ReadOptions::default()).unwrap_err().to_string();
        assert!(e.contains(name) && e.contains(needle) && !e.contains('\n'), "{name}: {e}");
    }
}

/// The coloured scans, with the colours their PROVENANCE.md states.
#[test]
fn the_coloured_scans_read_with_their_stated_colours() {
    let Some(dir) = data_dir() else { return };
    let c = colours_of(&dir.join("colour_scans/rgbd_object_iory/obj.ply")).expect("per-vertex RGBA");
    assert_eq!(c.len(), 14975);
    let rgb: HashSet<[u8; 3]> = c.iter().map(|c| [c[0], c[1], c[2]]).collect();
    assert_eq!(rgb.len(), 13130, "distinct RGB");
    assert_eq!(c.iter().map(|c| c[3]).collect::<HashSet<_>>().len(), 1, "alpha constant");
    let c = colours_of(&dir.join("colour_scans/laurana_meshlab/Laurana50k.ply")).expect("per-vertex colour");
    assert!(c.iter().all(|c| c[0] == c[1] && c[1] == c[2]), "grey");
    let levels: HashSet<u8> = c.iter().map(|c| c[0]).collect();
    assert_eq!((levels.len(), levels.iter().min().copied(), levels.iter().max().copied()), (154, Some(0), Some(153)));
    // Textured or face-coloured captures carry no per-vertex colour.
    assert!(colours_of(&dir.join("colour_scans/copyroom_planeopt/copyroom_c2000_opt.ply")).is_none());
}

/// glTF `COLOR_0`: normalized u8 VEC4 and FLOAT VEC3 read as RGBA; a
/// primitive without colour gets white; a COLOR_0 of the wrong count is
/// one line naming its accessor.
#[test]
fn gltf_color_0() {
    use super::gltf::{f32s, glb};
    use serde_json::json;
    let d = tempfile::tempdir().unwrap();
    let mut bin = f32s(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]); // 36 bytes
    bin.extend([255u8, 0, 0, 255, 0, 255, 0, 128, 0, 0, 255, 0]); // u8 VEC4, 12 bytes
    bin.extend(f32s(&[0.5, 0.25, 1.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0])); // f32 VEC3, 36 bytes
    let doc = |colour_count: u64| {
        json!({
            "asset": {"version": "2.0"}, "scenes": [{"nodes": [0, 1, 2]}], "nodes": [{"mesh": 0}, {"mesh": 1}, {"mesh": 2}],
            "meshes": [
                {"primitives": [{"attributes": {"POSITION": 0, "COLOR_0": 1}}]},
                {"primitives": [{"attributes": {"POSITION": 0, "COLOR_0": 2}}]},
                {"primitives": [{"attributes": {"POSITION": 0}}]}
            ],
            "buffers": [{"byteLength": 84}],
            "bufferViews": [{"buffer": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 12}, {"buffer": 0, "byteOffset": 48, "byteLength": 36}],
            "accessors": [
                {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"},
                {"bufferView": 1, "componentType": 5121, "normalized": true, "count": colour_count, "type": "VEC4"},
                {"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC3"}
            ]
        })
    };
    let p = write_file(d.path(), "c.glb", &glb(&doc(3), &bin));
    let c = colours_of(&p).unwrap();
    assert_eq!(c.len(), 9);
    assert_eq!(c[..3], [[255, 0, 0, 255], [0, 255, 0, 128], [0, 0, 255, 0]]);
    assert_eq!(c[3..6], [[128, 64, 255, 255], [0, 0, 0, 255], [255, 255, 255, 255]]);
    assert_eq!(c[6..], [[255; 4]; 3]);
    let p = write_file(d.path(), "bad.glb", &glb(&doc(2), &bin));
    let e = MeshReader::open(&p, ReadOptions::default()).unwrap_err().to_string();
    assert!(e.contains("bad.glb") && e.contains("accessors[1]") && e.contains("COLOR_0 has 2 elements") && !e.contains('\n'), "{e}");
}

/// Converting keeps per-vertex colour where the output holds it (PLY
/// binary and ASCII, OBJ, glTF `COLOR_0`) byte for byte, and says when it
/// drops it (STL).
#[test]
fn convert_keeps_colours_where_the_format_holds_them() {
    use mint_io::{convert, WriteOptions};
    let Some(dir) = data_dir() else { return };
    let src = dir.join("colour_scans/rgbd_object_iory/obj.ply");
    let want = colours_of(&src).unwrap();
    let d = tempfile::tempdir().unwrap();
    for (name, ascii) in [("a.obj", false), ("b.ply", false), ("c.ply", true), ("f.glb", false), ("g.gltf", false)] {
        let out = d.path().join(name);
        let s = convert(&src, &out, ReadOptions::default(), WriteOptions { ascii, colours: true, ..Default::default() }, &mut |_, _| {}).unwrap();
        assert_eq!(s.colour_kept, Some(true), "{name}");
        let got = colours_of(&out).unwrap();
        // OBJ holds no alpha: compare RGB there.
        if name.ends_with(".obj") {
            assert!(got.iter().zip(&want).all(|(g, w)| g[..3] == w[..3]), "{name}: colours differ");
        } else {
            assert_eq!(got, want, "{name}");
        }
    }
    let s = convert(&src, &d.path().join("d.stl"), ReadOptions::default(), WriteOptions { colours: true, ..Default::default() }, &mut |_, _| {}).unwrap();
    assert_eq!(s.colour_kept, Some(false));
    let s = convert(&src, &d.path().join("e.ply"), ReadOptions::default(), WriteOptions::default(), &mut |_, _| {}).unwrap();
    assert_eq!(s.colour_kept, None, "not asked for");
    assert!(colours_of(&d.path().join("e.ply")).is_none());
}
