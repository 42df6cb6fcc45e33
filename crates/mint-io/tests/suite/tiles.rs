//! 3D Tiles read by hand-made tilesets with the exact positions each must
//! give: tile transforms composed down the tree (column-major, f64, at an
//! ECEF-sized offset), y-up glTF turned z-up, a b3dm's RTC_CENTER, REPLACE
//! (the root's coarse content is not read) and ADD (the parent's content
//! is), an external tileset, 1.1 `contents`; a lone b3dm; and one line
//! naming the tileset and the tile for each broken one.

use mint_io::{Format, MeshReader, ReadOptions};
use serde_json::json;

use super::gltf::{f32s, glb};
use super::util::{read_all, write_file};

/// A tetrahedron's four corners, offset by `o`, in a GLB.
fn tetra_glb(o: [f32; 3]) -> Vec<u8> {
    let mut bin = Vec::new();
    for p in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]] {
        bin.extend(f32s(&[p[0] + o[0], p[1] + o[1], p[2] + o[2]]));
    }
    for i in [0u16, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3] {
        bin.extend(i.to_le_bytes());
    }
    let doc = json!({
        "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "buffers": [{"byteLength": 72}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 24}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3"}, {"bufferView": 1, "componentType": 5123, "count": 12, "type": "SCALAR"}]
    });
    glb(&doc, &bin)
}

/// A b3dm holding `glb`, with `table` as its feature table JSON.
fn b3dm(table: &serde_json::Value, glb: &[u8]) -> Vec<u8> {
    let mut ft = serde_json::to_vec(table).unwrap();
    while (28 + ft.len()) % 8 != 0 {
        ft.push(b' ');
    }
    let total = 28 + ft.len() + glb.len();
    let mut out = b"b3dm".to_vec();
    for v in [1u32, total as u32, ft.len() as u32, 0, 0, 0] {
        out.extend(v.to_le_bytes());
    }
    out.extend(ft);
    out.extend(glb);
    out
}

fn corners(o: [f32; 3]) -> Vec<[f64; 3]> {
    [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]].iter().map(|p| [(p[0] + o[0]) as f64, (p[1] + o[1]) as f64, (p[2] + o[2]) as f64]).collect()
}

/// glTF y-up to z-up.
fn zup(p: [f64; 3]) -> [f64; 3] {
    [p[0], -p[2], p[1]]
}

fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

const ECEF: [f64; 3] = [6378137.0, 12.5, -3.25];

/// Writes the tileset of the module doc into `dir`; returns its path and
/// the positions its finest level must give.
fn tileset(dir: &std::path::Path) -> (std::path::PathBuf, Vec<[f64; 3]>) {
    let (oa, ob, oc, od) = ([0.5f32, 0.0, 0.0], [0.0f32, 2.0, 0.0], [0.0f32, 0.0, 3.0], [4.0f32, 4.0, 4.0]);
    write_file(dir, "coarse.glb", &tetra_glb([9.0, 9.0, 9.0]));
    write_file(dir, "a.glb", &tetra_glb(oa));
    let rtc = [100.0, 200.0, 300.0];
    write_file(dir, "b.b3dm", &b3dm(&json!({"BATCH_LENGTH": 0, "RTC_CENTER": rtc}), &tetra_glb(ob)));
    write_file(dir, "d.glb", &tetra_glb(od));
    std::fs::create_dir_all(dir.join("sub")).unwrap();
    write_file(dir, "sub/c.glb", &tetra_glb(oc));
    write_file(dir, "sub/tileset.json", json!({"asset": {"version": "1.1"}, "geometricError": 1, "root": {"geometricError": 0, "boundingVolume": {"sphere": [0, 0, 0, 10]}, "contents": [{"uri": "c.glb"}]}}).to_string().as_bytes());
    let ts = json!({
        "asset": {"version": "1.0"}, "geometricError": 100,
        "root": {
            "transform": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, ECEF[0], ECEF[1], ECEF[2], 1],
            "refine": "REPLACE", "geometricError": 10, "boundingVolume": {"sphere": [0, 0, 0, 1000]},
            "content": {"uri": "coarse.glb"},
            "children": [
                {"geometricError": 0, "boundingVolume": {"sphere": [0, 0, 0, 10]}, "content": {"url": "a.glb"}},
                {"geometricError": 0, "boundingVolume": {"sphere": [0, 0, 0, 10]}, "transform": [0, 1, 0, 0, -1, 0, 0, 0, 0, 0, 1, 0, 10, 20, 30, 1], "content": {"uri": "b.b3dm"}},
                {"geometricError": 1, "boundingVolume": {"sphere": [0, 0, 0, 10]}, "refine": "ADD", "content": {"uri": "d.glb"},
                 "children": [{"geometricError": 0, "boundingVolume": {"sphere": [0, 0, 0, 10]}, "content": {"uri": "sub/tileset.json"}}]}
            ]
        }
    });
    let path = write_file(dir, "tileset.json", ts.to_string().as_bytes());
    let mut want = Vec::new();
    for p in corners(oa) {
        want.push(add(ECEF, zup(p)));
    }
    for p in corners(ob) {
        // R: 90 degrees about z, (x, y, z) -> (-y, x, z), then (10, 20, 30).
        let q = add(rtc, zup(p));
        want.push(add(add(ECEF, [10.0, 20.0, 30.0]), [-q[1], q[0], q[2]]));
    }
    for p in corners(od).into_iter().chain(corners(oc)) {
        want.push(add(ECEF, zup(p)));
    }
    (path, want)
}

#[test]
fn a_tileset_reads_its_finest_level_with_every_transform() {
    let d = tempfile::tempdir().unwrap();
    let (path, want) = tileset(d.path());
    assert_eq!(Format::from_path(&path).unwrap(), Format::Tiles);
    let (m, _) = read_all(&path, ReadOptions::default()).unwrap();
    assert_eq!((m.positions.len(), m.faces.len()), (16, 16), "four tiles of a tetrahedron: the coarse root replaced, the ADD parent kept");
    for (k, w) in want.iter().enumerate() {
        let p = m.positions[k];
        let err = (0..3).map(|i| (p[i] - w[i]).abs()).fold(0.0, f64::max);
        assert!(err < 1e-6, "vertex {k}: {p:?}, want {w:?}");
    }
    let info = MeshReader::open(&path, ReadOptions::default()).unwrap().info().clone();
    let tiles = info.elements.iter().find(|e| e.name == "tiles").unwrap();
    assert_eq!(tiles.count, 4);
    // A lone b3dm: its RTC_CENTER and z-up.
    let (m, _) = read_all(&d.path().join("b.b3dm"), ReadOptions::default()).unwrap();
    assert_eq!(m.positions.len(), 4);
    let w = add([100.0, 200.0, 300.0], zup(corners([0.0, 2.0, 0.0])[3]));
    assert!((0..3).all(|i| (m.positions[3][i] - w[i]).abs() < 1e-9), "{:?} against {w:?}", m.positions[3]);
}

#[test]
fn broken_tilesets_give_one_line_naming_the_tile() {
    let d = tempfile::tempdir().unwrap();
    let (path, _) = tileset(d.path());
    let text = std::fs::read_to_string(&path).unwrap();
    let cases: Vec<(&str, String, &[&str])> = vec![
        ("missing content", text.replace("b.b3dm", "gone.b3dm"), &["root.children[1].content", "gone.b3dm"]),
        ("points", text.replace("\"a.glb\"", "\"a.pnts\""), &["root.children[0].content", ".pnts"]),
        ("short transform", text.replace("[0,1,0,0,-1,0,0,0,0,0,1,0,10,20,30,1]", "[0,1,0]"), &["root.children[1].transform", "16 finite numbers"]),
        ("bad refine", text.replace("\"ADD\"", "\"MERGE\""), &["root.children[2].refine", "MERGE"]),
        ("remote", text.replace("\"a.glb\"", "\"https://example.com/a.glb\""), &["only files beside the tileset"]),
        ("no root", "{\"asset\": {\"version\": \"1.0\"}}".to_string(), &["no root tile"]),
        ("version", text.replace("\"1.0\"", "\"2.0\""), &["version"]),
        ("not json", "{\"asset\": ".to_string(), &["not JSON"]),
        ("implicit", text.replace("\"refine\":\"ADD\"", "\"refine\":\"ADD\",\"implicitTiling\":{}"), &["implicit tiling"]),
    ];
    for (name, body, needles) in cases {
        assert!(body != text || name == "no root", "{name}: the edit did not apply");
        let p = write_file(d.path(), "broken.json", body.as_bytes());
        let e = read_all(&p, ReadOptions::default()).map(|_| ()).unwrap_err().to_string();
        assert!(!e.contains('\n'), "{name}: not one line: {e}");
        assert!(e.contains("broken.json"), "{name}: {e}");
        for n in needles {
            assert!(e.contains(n), "{name}: {e:?} lacks {n:?}");
        }
    }
    // A cycle of external tilesets.
    write_file(d.path(), "loop.json", json!({"asset": {"version": "1.0"}, "root": {"geometricError": 0, "content": {"uri": "loop.json"}}}).to_string().as_bytes());
    let e = read_all(&d.path().join("loop.json"), ReadOptions::default()).map(|_| ()).unwrap_err().to_string();
    assert!(e.contains("cycle") && !e.contains('\n'), "{e}");
    // Tiles nested too deep.
    let mut tile = json!({"geometricError": 0});
    for _ in 0..100 {
        tile = json!({"geometricError": 0, "children": [tile]});
    }
    write_file(d.path(), "deep.json", json!({"asset": {"version": "1.0"}, "root": tile}).to_string().as_bytes());
    let e = read_all(&d.path().join("deep.json"), ReadOptions::default()).map(|_| ()).unwrap_err().to_string();
    // (serde_json's own nesting limit comes first within one file.)
    assert!((e.contains("deeper than") || e.contains("recursion limit")) && e.contains("deep.json") && !e.contains('\n'), "{e}");
    // Deep through external tilesets: each names the next.
    for k in 0..70 {
        write_file(d.path(), &format!("chain{k}.json"), json!({"asset": {"version": "1.0"}, "root": {"geometricError": 0, "content": {"uri": format!("chain{}.json", k + 1)}}}).to_string().as_bytes());
    }
    let e = read_all(&d.path().join("chain0.json"), ReadOptions::default()).map(|_| ()).unwrap_err().to_string();
    assert!(e.contains("deeper than") && !e.contains('\n'), "{e}");
    // A b3dm cut short, and one whose tables run past its end.
    let good = std::fs::read(d.path().join("b.b3dm")).unwrap();
    let p = write_file(d.path(), "short.b3dm", &good[..20]);
    let e = read_all(&p, ReadOptions::default()).map(|_| ()).unwrap_err().to_string();
    assert!(e.contains("short.b3dm") && e.contains("28-byte header"), "{e}");
    let mut bad = good.clone();
    bad[12..16].copy_from_slice(&10_000u32.to_le_bytes());
    let p = write_file(d.path(), "long.b3dm", &bad);
    let e = read_all(&p, ReadOptions::default()).map(|_| ()).unwrap_err().to_string();
    assert!(e.contains("long.b3dm") && e.contains("run past"), "{e}");
}
