//! glTF read by hand-made files with the exact triangles and positions each
//! must give: node hierarchies (matrix and TRS, in f64), strides, index
//! types, strips and fans, sparse accessors, data URIs and external
//! buffers, GLB; and one line naming the file and the JSON path for every
//! kind of broken file.

use mint_io::{MeshReader, ReadOptions};
use serde_json::json;

use super::util::{read_all, write_file};

pub(super) fn f32s(xs: &[f32]) -> Vec<u8> {
    xs.iter().flat_map(|x| x.to_le_bytes()).collect()
}

fn b64(data: &[u8]) -> String {
    const T: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for c in data.chunks(3) {
        let n = (c[0] as u32) << 16 | (*c.get(1).unwrap_or(&0) as u32) << 8 | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            if k <= c.len() {
                s.push(T[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

/// A GLB of `doc` with `bin` as its BIN chunk.
pub(super) fn glb(doc: &serde_json::Value, bin: &[u8]) -> Vec<u8> {
    let mut j = serde_json::to_vec(doc).unwrap();
    while j.len() % 4 != 0 {
        j.push(b' ');
    }
    let mut b = bin.to_vec();
    while b.len() % 4 != 0 {
        b.push(0);
    }
    let total = 12 + 8 + j.len() + 8 + b.len();
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((j.len() as u32).to_le_bytes());
    out.extend(0x4E4F_534Au32.to_le_bytes());
    out.extend(j);
    out.extend((b.len() as u32).to_le_bytes());
    out.extend(0x004E_4942u32.to_le_bytes());
    out.extend(b);
    out
}

/// Four positions of a unit tetrahedron, interleaved with 4 bytes of junk
/// (stride 16), then u16 indices of its four faces, then u8 indices of a
/// strip and a fan over the same corners.
fn tetra_bin() -> Vec<u8> {
    let mut bin = Vec::new();
    for p in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]] {
        bin.extend(f32s(&p));
        bin.extend([0xAB; 4]);
    }
    for i in [0u16, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3] {
        bin.extend(i.to_le_bytes());
    }
    bin.extend([0u8, 1, 2, 3]); // strip: (0,1,2), (2,1,3)
    bin.extend([0u8, 1, 2, 3]); // fan: (0,1,2), (0,2,3)
    bin.extend(f32s(&[5.0, 6.0, 7.0, 8.0, 9.0, 10.0])); // sparse values
    bin
}

fn tetra_doc(nodes: serde_json::Value, scenes: serde_json::Value) -> serde_json::Value {
    json!({
        "asset": {"version": "2.0"},
        "scenes": scenes,
        "nodes": nodes,
        "meshes": [
            {"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]},
            {"primitives": [{"attributes": {"POSITION": 0}, "indices": 2, "mode": 5}, {"attributes": {"POSITION": 0}, "indices": 3, "mode": 6}, {"attributes": {"POSITION": 0}, "mode": 1}]},
            {"primitives": [{"attributes": {"POSITION": 4}}]}
        ],
        "buffers": [{"byteLength": 64 + 24 + 8 + 24}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 64, "byteStride": 16},
            {"buffer": 0, "byteOffset": 64, "byteLength": 24},
            {"buffer": 0, "byteOffset": 88, "byteLength": 8},
            {"buffer": 0, "byteOffset": 96, "byteLength": 24}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3"},
            {"bufferView": 1, "componentType": 5123, "count": 12, "type": "SCALAR"},
            {"bufferView": 2, "componentType": 5121, "count": 4, "type": "SCALAR"},
            {"bufferView": 2, "byteOffset": 4, "componentType": 5121, "count": 4, "type": "SCALAR"},
            // Non-indexed: three zero positions, elements 1 and 2 (the
            // strip's bytes 1 and 2) replaced by the packed values of view 3.
            {"componentType": 5126, "count": 3, "type": "VEC3",
             "sparse": {"count": 2, "indices": {"bufferView": 2, "componentType": 5121, "byteOffset": 1},
                        "values": {"bufferView": 3}}}
        ]
    })
}

#[test]
fn gltf_nodes_strides_index_types_strips_fans_and_sparse() {
    let dir = tempfile::tempdir().unwrap();
    // Node 0: a translation far out (5e6, kept in f64) with a child that
    // rotates 90° about z and scales by 2, drawing mesh 0; node 2 draws mesh
    // 1 by a column-major matrix (translation 10, 0, 0); node 3 draws mesh 2.
    let nodes = json!([
        {"translation": [5000000.25, 0.0, 0.0], "children": [1]},
        {"rotation": [0.0, 0.0, std::f64::consts::FRAC_1_SQRT_2, std::f64::consts::FRAC_1_SQRT_2], "scale": [2.0, 2.0, 2.0], "mesh": 0},
        {"matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0, 10,0,0,1], "mesh": 1},
        {"mesh": 2},
        {"mesh": 0}
    ]);
    let doc = tetra_doc(nodes, json!([{"nodes": [0, 2, 3]}, {"nodes": [4]}]));
    let bin = tetra_bin();
    let mut with_scene = doc.clone();
    with_scene["scene"] = 0.into();
    let p = write_file(dir.path(), "t.glb", &glb(&with_scene, &bin));
    let (m, stats) = read_all(&p, ReadOptions::default()).unwrap();
    // Mesh 0 under node 1: p' = (5e6 + 0.25, 0, 0) + R(2p); R maps x to y.
    let near = |a: [f64; 3], b: [f64; 3]| (0..3).all(|k| (a[k] - b[k]).abs() < 1e-9);
    assert!(near(m.positions[1], [5000000.25, 2.0, 0.0]), "{:?}", m.positions[1]);
    assert!(near(m.positions[2], [5000000.25 - 2.0, 0.0, 0.0]), "{:?}", m.positions[2]);
    assert!(near(m.positions[3], [5000000.25, 0.0, 2.0]));
    assert!(near(m.positions[5], [11.0, 0.0, 0.0]));
    // Every triangle primitive brings its own copy of the positions it
    // uses (mesh 0: 4, strip: 4, fan: 4, mesh 2: 3); the line primitive
    // brings nothing.
    assert_eq!(m.positions.len(), 4 + 4 + 4 + 3);
    assert_eq!(m.faces[..4], [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]);
    assert_eq!(m.faces[4..6], [[4, 5, 6], [6, 5, 7]]);
    assert_eq!(m.faces[6..8], [[8, 9, 10], [8, 10, 11]]);
    assert_eq!(m.faces[8..], [[12, 13, 14]]);
    assert_eq!(m.positions[12..], [[0.0, 0.0, 0.0], [5.0, 6.0, 7.0], [8.0, 9.0, 10.0]]);
    assert_eq!(stats.triangles, 9);
    // No default scene: every scene (mesh 0 once more, untransformed).
    let p2 = write_file(dir.path(), "all.glb", &glb(&doc, &bin));
    let (m2, _) = read_all(&p2, ReadOptions::default()).unwrap();
    assert_eq!(m2.faces.len(), 9 + 4);
    assert_eq!(m2.positions[15..], [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);
    // The same as .gltf with a data URI, and with an external buffer.
    let mut d = with_scene.clone();
    d["buffers"][0]["uri"] = format!("data:application/octet-stream;base64,{}", b64(&bin)).into();
    let p3 = write_file(dir.path(), "t.gltf", serde_json::to_string(&d).unwrap().as_bytes());
    assert_eq!(read_all(&p3, ReadOptions::default()).unwrap().0, m);
    d["buffers"][0]["uri"] = "t%20data.bin".into();
    write_file(dir.path(), "t data.bin", &bin);
    let p4 = write_file(dir.path(), "ext.gltf", serde_json::to_string(&d).unwrap().as_bytes());
    assert_eq!(read_all(&p4, ReadOptions::default()).unwrap().0, m);
}

/// One untransformed instance of one TRIANGLES primitive in the GLB's own
/// buffer is read in place (no spill): the same positions and triangles as
/// the spilled reading of the same mesh under an identity matrix written
/// out (which takes the general path), strides and u16/u8/no indices alike,
/// and a bad index is still one line naming the accessor.
#[test]
fn a_plain_glb_is_read_in_place_with_the_same_result() {
    let dir = tempfile::tempdir().unwrap();
    let bin = tetra_bin();
    for (name, prim) in [
        ("u16", json!({"attributes": {"POSITION": 0}, "indices": 1})),
        ("u8", json!({"attributes": {"POSITION": 0}, "indices": 2})),
        ("none", json!({"attributes": {"POSITION": 0}})),
    ] {
        let mut plain = tetra_doc(json!([{"mesh": 0}]), json!([{"nodes": [0]}]));
        plain["meshes"][0]["primitives"] = json!([prim]);
        // The same as .gltf with its buffer in a data URI: not in the
        // mapping, so read the general way (spilled).
        let mut general = plain.clone();
        general["buffers"][0]["uri"] = format!("data:application/octet-stream;base64,{}", b64(&bin)).into();
        let (a, sa) = read_all(&write_file(dir.path(), &format!("{name}-plain.glb"), &glb(&plain, &bin)), ReadOptions::default()).unwrap();
        let (b, sb) = read_all(&write_file(dir.path(), &format!("{name}-general.gltf"), general.to_string().as_bytes()), ReadOptions::default()).unwrap();
        assert_eq!(a, b, "{name}");
        assert_eq!(sa.triangles, sb.triangles, "{name}");
        assert_eq!((sa.spilled_vertices, sb.spilled_vertices), (0, b.positions.len() as u64), "{name}: in place, and spilled");
        assert!(!a.faces.is_empty(), "{name}");
    }
    // An index past the positions, in place: one line naming the accessor.
    let mut bad = bin.clone();
    bad[64 + 2 * 5..64 + 2 * 5 + 2].copy_from_slice(&9u16.to_le_bytes());
    let doc = tetra_doc(json!([{"mesh": 0}]), json!([{"nodes": [0]}]));
    let p = write_file(dir.path(), "badindex.glb", &glb(&doc, &bad));
    let e = read_all(&p, ReadOptions::default()).map(|_| ()).unwrap_err().to_string();
    assert!(e.contains("badindex.glb") && e.contains("accessors[1]") && e.contains("index 9") && !e.contains('\n'), "{e}");
}

/// Each broken file: one line naming the file and where in the JSON.
#[test]
fn broken_gltf_files_give_one_line_naming_the_place() {
    let dir = tempfile::tempdir().unwrap();
    let base = tetra_doc(json!([{"mesh": 0}]), json!([{"nodes": [0]}]));
    let bin = tetra_bin();
    let cases: Vec<(&str, Box<dyn Fn(&mut serde_json::Value)>, &str)> = vec![
        // u8 indices read from the bytes of 5.0f32 (0, 0, 160, 64): 160 is no vertex.
        ("index", Box::new(|d| { d["accessors"][1]["bufferView"] = 3.into(); d["accessors"][1]["componentType"] = 5121.into(); }), "is out of range"),
        ("view", Box::new(|d| d["bufferViews"][1]["byteLength"] = 1000.into()), "bufferViews[1]"),
        ("stride", Box::new(|d| d["bufferViews"][0]["byteStride"] = 4.into()), "accessors[0]: byteStride 4"),
        ("count", Box::new(|d| d["accessors"][0]["count"] = 5.into()), "accessors[0]: 5 elements"),
        ("type", Box::new(|d| d["accessors"][0]["type"] = "VEC2".into()), "accessors[0]: type \"VEC2\""),
        ("cycle", Box::new(|d| { d["nodes"] = json!([{"children": [1]}, {"children": [0]}]); }), "nodes[0]"),
        ("two parents", Box::new(|d| { d["nodes"] = json!([{"children": [2]}, {"children": [2]}, {"mesh": 0}]); d["scenes"] = json!([{"nodes": [0, 1]}]); }), "two parents"),
        ("mesh", Box::new(|d| d["nodes"][0]["mesh"] = 7.into()), "nodes[0]: 'mesh' is 7"),
        ("matrix", Box::new(|d| d["nodes"][0]["matrix"] = json!([1, 2])), "'matrix' is not 16 finite numbers"),
        ("version", Box::new(|d| d["asset"]["version"] = "1.0".into()), "asset version"),
        ("quantized", Box::new(|d| d["accessors"][0]["componentType"] = 5123.into()), "KHR_mesh_quantization"),
        ("sparse", Box::new(|d| d["accessors"][4]["sparse"]["count"] = 9.into()), "accessors[4].sparse: count 9"),
        ("mode", Box::new(|d| d["meshes"][0]["primitives"][0]["mode"] = 9.into()), "mode 9"),
        ("zeros", Box::new(|d| { d["accessors"][4]["count"] = 5_000_000.into(); d["nodes"][0]["mesh"] = 2.into(); }), "5000000 elements without a bufferView"),
        // 1M zero positions (allowed) drawn by 20 nodes: 20M vertices from
        // a file of two kilobytes.
        ("instances", Box::new(|d| {
            d["accessors"][4]["count"] = 1_000_000.into();
            d["nodes"] = serde_json::Value::Array((0..20).map(|_| json!({"mesh": 2})).collect());
            d["scenes"] = json!([{"nodes": (0..20).collect::<Vec<u32>>()}]);
        }), "over 64 per byte of the file"),
        ("draco", Box::new(|d| d["extensionsRequired"] = json!(["KHR_materials_unlit", "KHR_draco_mesh_compression"])), "extensionsRequired[1]: the file requires extension \"KHR_draco_mesh_compression\""),
        ("meshopt", Box::new(|d| d["extensionsRequired"] = json!(["EXT_meshopt_compression"])), "\"EXT_meshopt_compression\", which mint does not implement"),
    ];
    for (name, edit, want) in cases {
        let mut d = base.clone();
        if name == "sparse" {
            d["nodes"][0]["mesh"] = 2.into();
        }
        edit(&mut d);
        let p = write_file(dir.path(), &format!("{}.glb", name.replace(' ', "-")), &glb(&d, &bin));
        let e = read_all(&p, ReadOptions::default()).map(|_| ()).unwrap_err().to_string();
        assert!(!e.contains('\n') && e.contains(&*p.file_name().unwrap().to_string_lossy()) && e.contains(want), "{name}: {e}");
    }
    // A GLB cut short, and one whose chunk runs past the end.
    let whole = glb(&base, &bin);
    for (name, bytes) in [("cut", whole[..10].to_vec()), ("chunk", { let mut b = whole.clone(); b.truncate(whole.len() - 40); b })] {
        let p = write_file(dir.path(), &format!("{name}.glb"), &bytes);
        let e = MeshReader::open(&p, ReadOptions::default()).map(|_| ()).unwrap_err().to_string();
        assert!(!e.contains('\n') && e.contains(&format!("{name}.glb")), "{name}: {e}");
    }
}
