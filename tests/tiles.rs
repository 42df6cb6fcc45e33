//! Several files as one surface (issue 28): a mesh cut into tiles, each
//! triangle in one tile and every tile with its own vertex array, in
//! several formats, resamples to the bytes of the whole file, given in any
//! order, as a directory or a list, in one process and staged; bool takes
//! a directory as an operand; check and decimate read the tiles as one
//! surface; broken tile sets get one line naming the file and its place.
//! Also glTF written by other tools, and pictures the right way up.

use crate::common::{load, write_trimesh};
use mint_core::TriMesh;
use mint_io::{Format, MeshWriter, WriteOptions};
use std::path::{Path, PathBuf};
use std::process::Command;

fn mint_bin() -> PathBuf {
    PathBuf::from(env!("CARGO_BIN_EXE_mint"))
}

fn mint(args: &[&str]) -> std::process::Output {
    Command::new(mint_bin()).args(args).output().unwrap()
}

fn ok(args: &[&str]) -> String {
    let o = mint(args);
    assert!(o.status.success(), "mint {}: {}", args.join(" "), String::from_utf8_lossy(&o.stderr));
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// `m` cut into `names.len()` tiles: triangle i goes to tile (i * 7919) mod
/// n, so every tile is scattered over the surface; each keeps only the
/// vertices it uses, renumbered.
fn tiles(dir: &Path, m: &TriMesh, names: &[&str]) -> Vec<PathBuf> {
    let n = names.len();
    let mut out = Vec::new();
    for (t, name) in names.iter().enumerate() {
        let mut map = vec![u32::MAX; m.positions.len()];
        let mut tile = TriMesh { positions: Vec::new(), faces: Vec::new() };
        for (i, f) in m.faces.iter().enumerate() {
            if (i * 7919) % n != t {
                continue;
            }
            tile.faces.push(f.map(|v| {
                if map[v as usize] == u32::MAX {
                    map[v as usize] = tile.positions.len() as u32;
                    tile.positions.push(m.positions[v as usize]);
                }
                map[v as usize]
            }));
        }
        // f64 where the format can (the positions are f32 values, which
        // text written as f32's shortest digits would not give back).
        let path = dir.join(name);
        let format = Format::from_path(&path).unwrap();
        let double = !matches!(format, Format::Stl | Format::Gltf);
        let mut w = MeshWriter::create(&path, format, WriteOptions { double, ..Default::default() }).unwrap();
        for p in &tile.positions {
            w.write_vertex(*p).unwrap();
        }
        for f in &tile.faces {
            w.write_face(*f).unwrap();
        }
        w.finish().unwrap();
        out.push(path);
    }
    out
}

#[test]
fn tiles_resample_to_the_bytes_of_the_whole_file_in_any_order_and_split() {
    let d = tempfile::tempdir().unwrap();
    let whole = d.path().join("whole.ply");
    ok(&["gen", "torus", s(&whole), "--faces", "20000"]);
    // f32 positions, so that every tile format holds them exactly.
    let m = load(&whole);
    let td = d.path().join("tiles");
    std::fs::create_dir(&td).unwrap();
    let files = tiles(&td, &m, &["t0.ply", "t1.obj", "t2.stl", "t3.glb", "t4.off", "t5.ply", "t6.obj"]);
    std::fs::write(td.join("notes.txt"), "not a mesh").unwrap();
    let out = |n: &str| d.path().join(n);
    ok(&["resample", s(&whole), s(&out("ref.ply")), "--cells", "30000", "--quiet"]);
    let reference = std::fs::read(out("ref.ply")).unwrap();
    // A directory; the files in another order; a list; staged in parts.
    ok(&["resample", s(&td), s(&out("dir.ply")), "--cells", "30000", "--quiet"]);
    let rev_out = out("rev.ply");
    let mut rev: Vec<&str> = files.iter().rev().map(|p| s(p)).collect();
    rev.push(s(&rev_out));
    let mut args = vec!["resample"];
    args.extend(rev);
    args.extend(["--cells", "30000", "--quiet"]);
    ok(&args);
    let list = d.path().join("tiles.txt");
    let names: Vec<String> = files.iter().map(|p| format!("tiles/{}", p.file_name().unwrap().to_string_lossy())).collect();
    std::fs::write(&list, format!("# the tiles\n{}\n", names.join("\n"))).unwrap();
    let at = format!("@{}", list.display());
    ok(&["resample", &at, s(&out("list.ply")), "--cells", "30000", "--quiet"]);
    let work = d.path().join("work");
    let json = ok(&["resample", s(&td), s(&out("staged.ply")), "--cells", "30000", "--parts", "3", "--slabs", "2", "--work", s(&work), "--json"]);
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(v["input_files"], 7);
    assert_eq!(v["input_faces"], 20000);
    for n in ["dir.ply", "rev.ply", "list.ply", "staged.ply"] {
        assert!(std::fs::read(out(n)).unwrap() == reference, "{n} differs from the whole file's resampling");
    }
    // More parts than files, and fewer.
    for parts in ["2", "11"] {
        let o = out(&format!("p{parts}.ply"));
        ok(&["resample", s(&td), s(&o), "--cells", "30000", "--parts", parts, "--work", s(&d.path().join(format!("w{parts}"))), "--quiet"]);
        assert!(std::fs::read(&o).unwrap() == reference, "--parts {parts}");
    }
    // bool with a directory operand: the same as with the whole file.
    let cube = d.path().join("cube.ply");
    write_trimesh(d.path(), "cube.ply", &crate::common::box_mesh([-0.2, -0.2, -0.2], [0.9, 0.9, 0.9]));
    ok(&["bool", "difference", s(&whole), s(&cube), s(&out("b1.ply")), "--cells", "30000", "--quiet"]);
    ok(&["bool", "difference", s(&td), s(&cube), s(&out("b2.ply")), "--cells", "30000", "--quiet"]);
    assert!(std::fs::read(out("b1.ply")).unwrap() == std::fs::read(out("b2.ply")).unwrap());
    // check: the tiles weld into the whole surface.
    let c1: serde_json::Value = serde_json::from_str(&ok(&["check", s(&whole), "--json"])).unwrap();
    let c2: serde_json::Value = serde_json::from_str(&ok(&["check", s(&td), "--json"])).unwrap();
    for k in ["vertices", "faces", "watertight", "components", "genus", "boundary_edges"] {
        assert_eq!(c1[k], c2[k], "check {k}");
    }
    assert_eq!(c2["files"], 7);
    // decimate reads the tiles as one surface.
    let dj: serde_json::Value = serde_json::from_str(&ok(&["decimate", s(&td), s(&out("dec.ply")), "--faces", "2000", "--json"])).unwrap();
    assert_eq!(dj["input_faces"], 20000);
    assert!(dj["output_watertight"].as_bool().unwrap(), "{dj}");
    // render draws a directory as one column.
    ok(&["render", s(&td), s(&whole), s(&out("r.png")), "--size", "64x48", "--quiet"]);
}

#[test]
fn broken_tile_sets_give_one_line_naming_the_file_and_its_place() {
    let d = tempfile::tempdir().unwrap();
    let a = d.path().join("a.ply");
    ok(&["gen", "sphere", s(&a), "--faces", "500"]);
    let line = |args: &[&str], want: &[&str]| {
        let o = mint(args);
        let e = String::from_utf8_lossy(&o.stderr).into_owned();
        assert!(!o.status.success(), "{args:?} succeeded");
        assert_eq!(e.trim_end().lines().count(), 1, "{e}");
        for w in want {
            assert!(e.contains(w), "{args:?}: {e} lacks {w}");
        }
    };
    let out = d.path().join("o.ply");
    // An empty directory, a list naming a missing file, a file twice.
    let empty = d.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    line(&["resample", s(&empty), s(&out), "--cells", "1000"], &["empty", "holds no mesh file"]);
    let list = d.path().join("l.txt");
    std::fs::write(&list, "a.ply\nmissing.obj\n").unwrap();
    let at = format!("@{}", list.display());
    line(&["resample", &at, s(&out), "--cells", "1000"], &["l.txt: line 2", "missing.obj: no such file"]);
    line(&["resample", s(&a), s(&a), s(&out), "--cells", "1000"], &["named twice"]);
    // A tile that fails to read: its name and its place among the files.
    let bad = d.path().join("b.obj");
    std::fs::write(&bad, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n").unwrap();
    line(&["resample", s(&a), s(&bad), s(&out), "--cells", "1000"], &["input 2 of 2", "b.obj"]);
    line(&["check", s(&a), s(&bad)], &["b.obj"]);
    // Text tiles are read side by side; of two bad ones, the first in file
    // order is the one named, as reading them one by one would name it.
    let tiles = d.path().join("text");
    std::fs::create_dir(&tiles).unwrap();
    for k in 1..=5 {
        let p = tiles.join(format!("c{k}.obj"));
        ok(&["convert", s(&a), s(&p), "--quiet"]);
        if k == 2 || k == 4 {
            let mut t = std::fs::read_to_string(&p).unwrap();
            t.push_str("f 1 2 99999\n");
            std::fs::write(&p, t).unwrap();
        }
    }
    for _ in 0..3 {
        line(&["resample", s(&tiles), s(&out), "--cells", "1000", "--parts", "5", "--threads", "2"], &["input 2 of 5", "c2.obj"]);
    }
    assert!(!out.exists());
}

/// `../shared/data/…`, which CI must have: a missing file fails the test.
fn shared(rel: &str) -> PathBuf {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data").join(rel);
    assert!(p.is_file(), "{} is missing: ../shared must sit beside the project", p.display());
    p
}

/// GLBs written by other tools (Blender's glTF exporters; provenance in
/// ../shared/data/colour_scans/PROVENANCE.md) read with the counts their
/// provenance states, as closed surfaces.
#[test]
fn glbs_written_by_other_tools_read_whole() {
    for (rel, vertices, faces) in [("colour_scans/kiri_scan_glb/Untitled.glb", 11_313, 19_490), ("colour_scans/leeperrysmith_glb/LeePerrySmith.glb", 9_279, 17_684)] {
        let p = shared(rel);
        let info = mint_io::read_info(&p).unwrap();
        assert_eq!((info.vertex_count, info.face_count), (vertices, Some(faces)), "{rel}");
        let c: serde_json::Value = serde_json::from_str(&ok(&["check", s(&p), "--json"])).unwrap();
        assert_eq!(c["faces"], faces, "{rel}");
        assert!(c["watertight"].as_bool().unwrap(), "{rel}: {c}");
    }
}

/// Widths (covered pixels per row) of the rows of a picture that hold
/// the surface, top first.
fn row_widths(png_path: &Path) -> Vec<u32> {
    let (w, h, px) = crate::common::png_rgb(png_path);
    (0..h).map(|y| px[y * w..(y + 1) * w].iter().filter(|p| **p != [250, 250, 250]).count() as u32).filter(|&n| n > 0).collect()
}

/// A bust exported by MeshLab (y-up) is drawn right side up in the front
/// view by default: narrow head at the top, wide shoulders at the bottom.
/// With `--up z` (the old default) it was seen from the top of its head.
#[test]
fn a_y_up_bust_renders_right_side_up_in_the_front_view() {
    let d = tempfile::tempdir().unwrap();
    let bust = shared("colour_scans/laurana_meshlab/Laurana50k.ply");
    let (front, z) = (d.path().join("front.png"), d.path().join("z.png"));
    ok(&["render", s(&bust), s(&front), "--view", "front", "--size", "200x200", "--quiet"]);
    ok(&["render", s(&bust), s(&z), "--view", "front", "--up", "z", "--size", "200x200", "--quiet"]);
    let rows = row_widths(&front);
    let k = rows.len() / 5;
    let mean = |r: &[u32]| r.iter().sum::<u32>() as f64 / r.len() as f64;
    let (top, bottom) = (mean(&rows[..k]), mean(&rows[rows.len() - k..]));
    assert!(top < 0.6 * bottom, "head {top:.0} px wide, shoulders {bottom:.0}: not right side up");
    // Taller than wide, as a bust stands; from above (z up) it is not.
    assert!(rows.len() as f64 > 0.9 * *rows.iter().max().unwrap() as f64);
    let zrows = row_widths(&z);
    assert!((zrows.len() as f64) < 0.8 * *zrows.iter().max().unwrap() as f64, "--up z draws the bust from above");
}

/// A 3D Tiles tileset of GLB tiles is one surface: z-up tiles without
/// transforms give the whole file's bytes; y-up tiles under a root
/// transform at an ECEF-sized offset give the same surface, moved, and
/// the summary counts the tiles.
#[test]
fn a_tileset_resamples_as_one_surface_and_says_how_many_tiles() {
    let d = tempfile::tempdir().unwrap();
    let whole = d.path().join("whole.ply");
    ok(&["gen", "torus", s(&whole), "--faces", "20000"]);
    let m = load(&whole);
    let names: Vec<String> = (0..5).map(|k| format!("t{k}.glb")).collect();
    let refs: Vec<&str> = names.iter().map(String::as_str).collect();
    let glbs = tiles(d.path(), &m, &refs);
    let children: Vec<serde_json::Value> =
        glbs.iter().map(|p| serde_json::json!({"geometricError": 0, "boundingVolume": {"sphere": [0, 0, 0, 2]}, "content": {"uri": p.file_name().unwrap().to_str().unwrap()}})).collect();
    let set = |up: &str, transform: Option<[f64; 16]>| {
        let mut root = serde_json::json!({"geometricError": 1, "refine": "REPLACE", "boundingVolume": {"sphere": [0, 0, 0, 2]}, "children": children});
        if let Some(t) = transform {
            root["transform"] = serde_json::json!(t);
        }
        serde_json::json!({"asset": {"version": "1.0", "gltfUpAxis": up}, "geometricError": 2, "root": root}).to_string()
    };
    let flat = d.path().join("tileset.json");
    std::fs::write(&flat, set("Z", None)).unwrap();
    let (a, b) = (d.path().join("a.ply"), d.path().join("b.ply"));
    ok(&["resample", s(&whole), s(&a), "--cells", "40000", "--quiet"]);
    let o = mint(&["resample", s(&flat), s(&b), "--cells", "40000"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("1 file holding 5 tiles"), "{err}");
    assert!(std::fs::read(&a).unwrap() == std::fs::read(&b).unwrap(), "a tileset of the tiles gives other bytes than the whole file");
    // y-up tiles (the default) under a root translation: the torus turned
    // z-up and moved, the same volume and genus.
    let off = [4_000_000.0, 3_000_000.0, 3_500_000.0];
    let moved = d.path().join("moved.json");
    std::fs::write(&moved, set("Y", Some([1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, off[0], off[1], off[2], 1.0]))).unwrap();
    let j: serde_json::Value = serde_json::from_str(&ok(&["resample", s(&moved), s(&b), "--cells", "40000", "--json"])).unwrap();
    assert_eq!(j["input_tiles"], 5);
    let (r0, r1) = (mint_mesh::check(&load(&a).positions, &load(&a).faces), mint_mesh::check(&load(&b).positions, &load(&b).faces));
    assert!(r1.watertight && r1.genus_total == 1, "{r1:?}");
    assert!((r1.signed_volume - r0.signed_volume).abs() < 0.02 * r0.signed_volume, "{} against {}", r1.signed_volume, r0.signed_volume);
    // The torus's axis (z in the file) is y in glTF terms, so turned z-up it lies along -y.
    let (lo, hi) = (r1.bbox_min.unwrap(), r1.bbox_max.unwrap());
    let (l0, h0) = (r0.bbox_min.unwrap(), r0.bbox_max.unwrap());
    for (k, (lk, hk)) in [(l0[0], h0[0]), (-h0[2], -l0[2]), (l0[1], h0[1])].into_iter().enumerate() {
        assert!((lo[k] - off[k] - lk).abs() < 0.05 && (hi[k] - off[k] - hk).abs() < 0.05, "axis {k}: [{}, {}] against [{lk}, {hk}]", lo[k] - off[k], hi[k] - off[k]);
    }
}

/// One part reads two tiles into one shard store; when the second, a binary
/// PLY, turns out to hold a quad (and a two-corner face, which keeps the
/// file's length that of triangles) after many triangles, what was written of
/// it is taken back out of the store and the file streamed instead: the
/// same bytes as with that tile as ASCII (always streamed).
#[test]
fn a_tile_whose_faces_turn_out_not_to_be_triangles_is_taken_back_and_streamed() {
    let d = tempfile::tempdir().unwrap();
    let whole = d.path().join("whole.ply");
    // More than one chunk of faces (64Ki) before the quad.
    ok(&["gen", "torus", s(&whole), "--faces", "300000"]);
    let m = load(&whole);
    let half = m.faces.len() / 2;
    let write = |path: &Path, binary: bool, faces: &[[u32; 3]], quad: bool| {
        let n = faces.len() + 2 * quad as usize;
        let mut out = format!(
            "ply\nformat {} 1.0\nelement vertex {}\nproperty double x\nproperty double y\nproperty double z\nelement face {n}\nproperty list uchar int vertex_indices\nend_header\n",
            if binary { "binary_little_endian" } else { "ascii" },
            m.positions.len()
        )
        .into_bytes();
        for p in &m.positions {
            if binary {
                p.iter().for_each(|c| out.extend(c.to_le_bytes()));
            } else {
                out.extend(format!("{:?} {:?} {:?}\n", p[0], p[1], p[2]).bytes());
            }
        }
        let mut polys: Vec<Vec<u32>> = faces.iter().map(|f| f.to_vec()).collect();
        if quad {
            // A quad over two triangles' corners near the end of the file,
            // and a two-corner face after it: the file has the length of
            // one of triangles only, so its faces are read as fixed-size
            // records until the quad.
            let (a, b) = (faces[0], faces[1]);
            polys.insert(polys.len() - 3, vec![a[0], a[1], a[2], b[2]]);
            polys.insert(polys.len() - 1, vec![b[0], b[1]]);
        }
        for f in polys {
            if binary {
                out.push(f.len() as u8);
                f.iter().for_each(|v| out.extend((*v as i32).to_le_bytes()));
            } else {
                out.extend(format!("{} {}\n", f.len(), f.iter().map(|v| v.to_string()).collect::<Vec<_>>().join(" ")).bytes());
            }
        }
        std::fs::write(path, out).unwrap();
    };
    let (a, b) = (d.path().join("a"), d.path().join("b"));
    std::fs::create_dir(&a).unwrap();
    std::fs::create_dir(&b).unwrap();
    for dir in [&a, &b] {
        write(&dir.join("t0.ply"), true, &m.faces[..half], false);
    }
    write(&a.join("t1.ply"), false, &m.faces[half..], true);
    write(&b.join("t1.ply"), true, &m.faces[half..], true);
    let (oa, ob) = (d.path().join("a.ply"), d.path().join("b.ply"));
    let ja: serde_json::Value = serde_json::from_str(&ok(&["resample", s(&a), s(&oa), "--cells", "40000", "--parts", "1", "--json"])).unwrap();
    let jb: serde_json::Value = serde_json::from_str(&ok(&["resample", s(&b), s(&ob), "--cells", "40000", "--parts", "1", "--json"])).unwrap();
    assert!(std::fs::read(&oa).unwrap() == std::fs::read(&ob).unwrap(), "the quad's binary tile gives other bytes than its ASCII copy");
    // Records left behind would merge with their copies into the same
    // vertices; the counts tell.
    assert_eq!((&jb["intercepts_found"], &jb["shard_bytes"], &jb["input_faces"]), (&ja["intercepts_found"], &ja["shard_bytes"], &ja["input_faces"]));
}

/// A plain GLB is read in place like binary PLY: its triangles split over
/// parts, each visited on every thread, with the bytes of the PLY.
#[test]
fn a_glb_splits_over_parts_like_binary_ply() {
    let d = tempfile::tempdir().unwrap();
    let (ply, glb) = (d.path().join("t.ply"), d.path().join("t.glb"));
    ok(&["gen", "torus", s(&ply), "--faces", "300000"]);
    ok(&["convert", s(&ply), s(&glb), "--quiet"]);
    let want = d.path().join("want.ply");
    ok(&["resample", s(&ply), s(&want), "--cells", "200000", "--quiet"]);
    for parts in ["1", "3"] {
        let out = d.path().join(format!("glb-{parts}.ply"));
        let j: serde_json::Value = serde_json::from_str(&ok(&["resample", s(&glb), s(&out), "--cells", "200000", "--parts", parts, "--json"])).unwrap();
        assert!(std::fs::read(&out).unwrap() == std::fs::read(&want).unwrap(), "{parts} parts: other bytes than the PLY's");
        assert!(j["deref"].as_str().unwrap().contains("mmap"), "{j}");
    }
}
