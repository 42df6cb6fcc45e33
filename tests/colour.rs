//! Colour (issue 27): read, drawn, and carried through resampling and
//! booleans. A sphere whose upper half is red and lower half blue, per
//! vertex, renders red above and blue below (`--color shading` ignores
//! the colours), and resamples to a sphere whose border between the two
//! stays within one cell; OBJ colour comes out as OBJ colour; a format
//! without colour, or `--no-color`, gives geometry only (with a warning in
//! the first case); a file without colour counts as white beside one with.

use crate::common::load;
use std::path::{Path, PathBuf};
use std::process::Command;

fn mint(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_mint")).args(args).output().unwrap()
}

/// A binary PLY of `mint gen sphere` with uchar RGB per vertex: red where
/// z > 0, blue elsewhere.
fn two_colour_sphere(dir: &Path) -> PathBuf {
    let plain = dir.join("plain.ply");
    let o = mint(&["gen", "sphere", plain.to_str().unwrap(), "--faces", "20000"]);
    assert!(o.status.success());
    let m = load(&plain);
    let mut b = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\nproperty double x\nproperty double y\nproperty double z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
        m.positions.len(),
        m.faces.len()
    )
    .into_bytes();
    for p in &m.positions {
        p.iter().for_each(|c| b.extend(c.to_le_bytes()));
        b.extend(if p[2] > 0.0 { [220u8, 30, 30] } else { [30, 30, 220] });
    }
    for f in &m.faces {
        b.push(3);
        f.iter().for_each(|v| b.extend((*v as i32).to_le_bytes()));
    }
    let path = dir.join("coloured.ply");
    std::fs::write(&path, b).unwrap();
    path
}

/// (reddish, bluish) pixel counts in the upper and lower halves.
fn halves(png_path: &Path) -> [(u32, u32); 2] {
    let (w, h, px) = crate::common::png_rgb(png_path);
    let mut out = [(0, 0); 2];
    for (i, p) in px.iter().enumerate() {
        let half = &mut out[(i / w >= h / 2) as usize];
        if p[0] as i32 > p[2] as i32 + 60 {
            half.0 += 1;
        } else if p[2] as i32 > p[0] as i32 + 60 {
            half.1 += 1;
        }
    }
    out
}

#[test]
fn a_two_colour_sphere_renders_in_its_colours() {
    let d = tempfile::tempdir().unwrap();
    let sphere = two_colour_sphere(d.path());
    let png = d.path().join("s.png");
    let o = mint(&["render", sphere.to_str().unwrap(), png.to_str().unwrap(), "--view", "front", "--up", "z", "--size", "300x300"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("drawn in their colours (per vertex, per face or textures): 1 of the files"), "{err}");
    let [top, bottom] = halves(&png);
    assert!(top.0 > 10_000 && top.1 < 200, "upper half red: {top:?}");
    assert!(bottom.1 > 10_000 && bottom.0 < 200, "lower half blue: {bottom:?}");
    // Ignoring the colours: no red anywhere (the flat shading is blue-grey).
    let o = mint(&["render", sphere.to_str().unwrap(), png.to_str().unwrap(), "--view", "front", "--up", "z", "--size", "300x300", "--color", "shading"]);
    assert!(o.status.success());
    let [top, bottom] = halves(&png);
    assert_eq!((top.0, bottom.0), (0, 0), "no red without the colours");
}

/// `mint gen … --color`: every vertex carries the colour field's colour at
/// its position (PLY and OBJ); a format without colour is refused.
#[test]
fn gen_color_writes_the_colour_field() {
    let d = tempfile::tempdir().unwrap();
    for name in ["t.ply", "t.obj"] {
        let out = d.path().join(name);
        let o = mint(&["gen", "torus", out.to_str().unwrap(), "--faces", "5000", "--color"]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let r = mint_io::MeshReader::open(&out, mint_io::ReadOptions::default()).unwrap();
        let c = r.colours().expect("colours");
        for i in 0..r.vertex_count() {
            let want = mint_gen::colour::colour_at(r.vertex(i));
            let got = c.get(i);
            // OBJ stores the channels as decimals of c/255, read back exactly.
            assert_eq!(got[..3], want[..3], "{name}: vertex {i}");
        }
    }
    let o = mint(&["gen", "torus", d.path().join("t.stl").to_str().unwrap(), "--color"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.trim_end().lines().count() == 1 && err.contains("holds per-vertex colour"), "{err}");
}

/// Positions and colours of a mesh file's vertices.
fn coloured_vertices(path: &Path) -> Vec<([f64; 3], [u8; 4])> {
    let r = mint_io::MeshReader::open(path, mint_io::ReadOptions::default()).unwrap();
    let c = r.colours().unwrap_or_else(|| panic!("{} has no colour", path.display()));
    (0..r.vertex_count()).map(|i| (r.vertex(i), c.get(i))).collect()
}

const RED: [u8; 4] = [220, 30, 30, 255];
const BLUE: [u8; 4] = [30, 30, 220, 255];

/// The colour border of a resampled two-colour sphere lies within a cell
/// (and an input edge, across which the input's own colours blend) of the
/// input's; everywhere else the colours are exactly the input's.
#[test]
fn a_two_colour_sphere_keeps_its_border_after_resampling() {
    let d = tempfile::tempdir().unwrap();
    let sphere = two_colour_sphere(d.path());
    // The input's longest edge: its colours blend across the border's faces.
    let m = load(&sphere);
    let edge = m.faces.iter().flat_map(|f| (0..3).map(move |i| (f[i], f[(i + 1) % 3]))).map(|(a, b)| {
        let (p, q) = (m.positions[a as usize], m.positions[b as usize]);
        ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
    });
    let edge = edge.fold(0.0f64, f64::max);
    for (cells, name) in [("30000", "a.ply"), ("300000", "b.ply")] {
        let out = d.path().join(name);
        let o = mint(&["resample", sphere.to_str().unwrap(), out.to_str().unwrap(), "--cells", cells, "--json"]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let summary: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(summary["colour"], true, "{summary}");
        assert!(!String::from_utf8_lossy(&o.stderr).contains("colour"), "no colour warning: {}", String::from_utf8_lossy(&o.stderr));
        let cell = summary["cell_size"].as_f64().unwrap();
        let vs = coloured_vertices(&out);
        assert!(vs.len() > 1000);
        let (mut pure, mut blended) = (0, 0);
        for (p, c) in &vs {
            if p[2].abs() > cell + edge {
                assert_eq!(*c, if p[2] > 0.0 { RED } else { BLUE }, "{cells} cells: vertex at z = {}", p[2]);
                pure += 1;
            } else {
                // Within the border band: a blend of the two, never anything else.
                assert!(c[1] == 30 && c[0] as u32 + c[2] as u32 >= 248 && c[0] as u32 + c[2] as u32 <= 252, "{c:?} at z = {}", p[2]);
                blended += 1;
            }
        }
        assert!(pure > 4 * blended, "{pure} pure, {blended} in the border band");
    }
}

/// OBJ colour in, OBJ colour out; a format without colour warns and keeps
/// the geometry; `--no-color` drops colour without a warning.
#[test]
fn colour_follows_the_output_format_and_no_color() {
    let d = tempfile::tempdir().unwrap();
    let obj = d.path().join("t.obj");
    assert!(mint(&["gen", "torus", obj.to_str().unwrap(), "--faces", "200000", "--color"]).status.success());
    let out = d.path().join("o.obj");
    let o = mint(&["resample", obj.to_str().unwrap(), out.to_str().unwrap(), "--cells", "500000", "--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let cell = serde_json::from_slice::<serde_json::Value>(&o.stdout).unwrap()["cell_size"].as_f64().unwrap();
    let vs = coloured_vertices(&out);
    // Each vertex's colour is the colour field's near its position: the
    // field is smooth between its borders (planes k/4; its channels change
    // by at most 383 per unit), so away from them the colour is that of
    // the input surface at the crossing, within a cell and an input edge.
    let m = load(&obj);
    let edge = m.faces.iter().map(|f| {
        let (p, q) = (m.positions[f[0] as usize], m.positions[f[1] as usize]);
        ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
    });
    let reach = cell + 2.0 * edge.fold(0.0f64, f64::max);
    let mut checked = 0;
    for (p, c) in &vs {
        if p.iter().any(|x| ((4.0 * x).round() / 4.0 - x).abs() < reach) {
            continue;
        }
        let want = mint_gen::colour::colour_at(*p);
        let tol = (383.0 * reach).ceil() as i32 + 2;
        assert!((0..3).all(|k| (c[k] as i32 - want[k] as i32).abs() <= tol), "{c:?} at {p:?}, the field says {want:?}");
        checked += 1;
    }
    assert!(checked > 500, "{checked} of {} vertices away from the field's borders", vs.len());
    let stl = d.path().join("o.stl");
    let o = mint(&["resample", obj.to_str().unwrap(), stl.to_str().unwrap(), "--cells", "50000"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success() && err.contains("cannot hold: the output is geometry only"), "{err}");
    let plain = d.path().join("p.ply");
    let o = mint(&["resample", obj.to_str().unwrap(), plain.to_str().unwrap(), "--cells", "50000", "--no-color"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success() && !err.contains("colour"), "{err}");
    assert!(mint_io::MeshReader::open(&plain, mint_io::ReadOptions::default()).unwrap().colours().is_none());
}

/// A boolean of a coloured and an uncoloured operand: the coloured one's
/// surface keeps its colours, the other's is white.
#[test]
fn a_boolean_carries_each_operand_colour() {
    let d = tempfile::tempdir().unwrap();
    let sphere = two_colour_sphere(d.path());
    let cube = d.path().join("cube.ply");
    let b = crate::common::box_mesh([0.3, 0.3, 0.3], [1.5, 1.5, 1.5]);
    std::fs::rename(crate::common::write_trimesh(d.path(), "cube-w.ply", &b), &cube).unwrap();
    let out = d.path().join("u.ply");
    let o = mint(&["bool", "union", sphere.to_str().unwrap(), cube.to_str().unwrap(), out.to_str().unwrap(), "--cells", "100000"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (mut white, mut other) = (0, 0);
    for (p, c) in coloured_vertices(&out) {
        let on_cube = p.iter().all(|&x| x > 0.35) && p.iter().any(|&x| x > 1.05);
        if on_cube {
            if c == [255; 4] {
                white += 1;
            } else {
                other += 1;
            }
        } else if p[2] < -0.1 {
            assert_eq!(c, BLUE, "the sphere's lower half at {p:?}");
        }
    }
    assert!(white > 500 && other * 50 < white, "{white} white vertices on the cube, {other} others");
}

/// A binary PLY of `mint gen sphere` with uchar RGB per *face*: red where
/// the face's centroid has x > 0, blue elsewhere.
fn face_coloured_sphere(dir: &Path) -> PathBuf {
    let plain = dir.join("fplain.ply");
    assert!(mint(&["gen", "sphere", plain.to_str().unwrap(), "--faces", "20000"]).status.success());
    let m = load(&plain);
    let mut b = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\nproperty double x\nproperty double y\nproperty double z\nelement face {}\nproperty list uchar int vertex_indices\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n",
        m.positions.len(),
        m.faces.len()
    )
    .into_bytes();
    for p in &m.positions {
        p.iter().for_each(|c| b.extend(c.to_le_bytes()));
    }
    for f in &m.faces {
        b.push(3);
        f.iter().for_each(|v| b.extend((*v as i32).to_le_bytes()));
        let x: f64 = f.iter().map(|&v| m.positions[v as usize][0]).sum();
        b.extend(if x > 0.0 { [220u8, 30, 30] } else { [30, 30, 220] });
    }
    let path = dir.join("fcoloured.ply");
    std::fs::write(&path, b).unwrap();
    path
}

/// Face colours stay on their side of the border between them, read
/// directly, by parts, and streamed (ascii); polygons give each of their
/// triangles their colour.
#[test]
fn face_colours_stay_on_their_side() {
    let d = tempfile::tempdir().unwrap();
    let sphere = face_coloured_sphere(d.path());
    let a = d.path().join("a.ply");
    let o = mint(&["resample", sphere.to_str().unwrap(), a.to_str().unwrap(), "--cells", "100000", "--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let cell = serde_json::from_slice::<serde_json::Value>(&o.stdout).unwrap()["cell_size"].as_f64().unwrap();
    let edge = 0.05; // the longest edge of a 20,000-face unit sphere is below this
    let vs = coloured_vertices(&a);
    let mut checked = 0;
    for (p, c) in &vs {
        if p[0].abs() > cell + edge {
            assert_eq!(*c, if p[0] > 0.0 { RED } else { BLUE }, "vertex at {p:?}");
            checked += 1;
        } else {
            assert!(*c == RED || *c == BLUE, "a face colour, not a blend: {c:?}");
        }
    }
    assert!(checked * 10 > vs.len() * 7, "{checked} of {}", vs.len());
    // Split into parts: the same bytes.
    let b = d.path().join("b.ply");
    let o = mint(&["resample", sphere.to_str().unwrap(), b.to_str().unwrap(), "--cells", "100000", "--parts", "3", "--slabs", "2", "--quiet"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(std::fs::read(&a).unwrap() == std::fs::read(&b).unwrap(), "parts change the bytes");
    // An ascii box of six quads, one colour per side.
    let cols = [[255, 0, 0], [0, 255, 0], [0, 0, 255], [255, 255, 0], [0, 255, 255], [255, 0, 255]];
    let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
    let mut t = String::from("ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\nproperty float z\nelement face 6\nproperty list uchar int vertex_indices\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n");
    for i in 0..8 {
        t += &format!("{} {} {}\n", i & 1, (i >> 1) & 1, (i >> 2) & 1);
    }
    for (q, c) in quads.iter().zip(cols) {
        t += &format!("4 {} {} {} {} {} {} {}\n", q[0], q[1], q[2], q[3], c[0], c[1], c[2]);
    }
    let boxp = d.path().join("box.ply");
    std::fs::write(&boxp, t).unwrap();
    let out = d.path().join("box-out.ply");
    let o = mint(&["resample", boxp.to_str().unwrap(), out.to_str().unwrap(), "--cells", "8000"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // Each side: (axis, value) of its plane.
    let sides = [(2, 0.0), (2, 1.0), (1, 0.0), (1, 1.0), (0, 0.0), (0, 1.0)];
    let mut seen = [0; 6];
    for (p, c) in coloured_vertices(&out) {
        // Vertices a tenth of the box from every other side lie on one side.
        let near: Vec<usize> = (0..6).filter(|&s| (p[sides[s].0] - sides[s].1).abs() < 0.1).collect();
        if near.len() == 1 {
            let s = near[0];
            assert_eq!(c[..3], cols[s], "side {s} at {p:?}");
            seen[s] += 1;
        }
    }
    assert!(seen.iter().all(|&n| n > 20), "{seen:?}");
}

/// A PNG of `n` x `n` squares of `s` texels each, black and white
/// (square (0, 0), at the image's top left, white).
fn checker_png(n: usize, s: usize) -> Vec<u8> {
    let w = n * s;
    let mut px = Vec::with_capacity(w * w * 3);
    for y in 0..w {
        for x in 0..w {
            px.extend(if (x / s + y / s) % 2 == 0 { [255u8; 3] } else { [0u8; 3] });
        }
    }
    let mut out = Vec::new();
    let mut e = png::Encoder::new(&mut out, w as u32, w as u32);
    e.set_color(png::ColorType::Rgb);
    e.write_header().unwrap().write_image_data(&px).unwrap();
    out
}

/// The unit plane z = 0.5 as a GLB whose material's texture is the
/// checkerboard of `n` x `n` squares, a PNG in its buffer (clamped).
fn checker_glb(n: usize) -> Vec<u8> {
    let png = checker_png(n, 8);
    let mut bin: Vec<u8> = Vec::new();
    PLANE.iter().for_each(|p| p.iter().for_each(|c| bin.extend((*c as f32).to_le_bytes())));
    PLANE.iter().for_each(|p| [p[0], p[1]].iter().for_each(|c| bin.extend((*c as f32).to_le_bytes())));
    [0u16, 1, 2, 0, 2, 3].iter().for_each(|i| bin.extend(i.to_le_bytes()));
    let img_off = bin.len();
    bin.extend(&png);
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let json = serde_json::json!({
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
        "textures": [{"source": 0, "sampler": 0}], "samplers": [{"wrapS": 33071, "wrapT": 33071}],
        "images": [{"bufferView": 3, "mimeType": "image/png"}],
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 32},
            {"buffer": 0, "byteOffset": 80, "byteLength": 12},
            {"buffer": 0, "byteOffset": img_off, "byteLength": png.len()}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0.5], "max": [1, 1, 0.5]},
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"},
            {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}
        ]
    });
    pack_glb(&json, &bin)
}

/// `dir/tileset.json`: two tiles (z up), `first` at the origin and
/// `second` two units along x.
fn two_tile_tileset(dir: &Path, first: &str, second: &str) -> PathBuf {
    let tileset = serde_json::json!({
        "asset": {"version": "1.0", "gltfUpAxis": "Z"},
        "geometricError": 1,
        "root": {"boundingVolume": {"box": [1.5, 0.5, 0.5, 1.5, 0, 0, 0, 0.5, 0, 0, 0, 0.5]}, "geometricError": 1, "refine": "ADD",
            "children": [
                {"boundingVolume": {"box": [0.5, 0.5, 0.5, 0.5, 0, 0, 0, 0.5, 0, 0, 0, 0.5]}, "geometricError": 0, "content": {"uri": first}},
                {"boundingVolume": {"box": [2.5, 0.5, 0.5, 0.5, 0, 0, 0, 0.5, 0, 0, 0, 0.5]}, "geometricError": 0, "content": {"uri": second},
                 "transform": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 2, 0, 0, 1]}
            ]}
    });
    let tsp = dir.join("tileset.json");
    std::fs::write(&tsp, serde_json::to_vec(&tileset).unwrap()).unwrap();
    tsp
}

/// A GLB of a glTF document and its binary buffer (padded to 4 bytes).
fn pack_glb(json: &serde_json::Value, bin: &[u8]) -> Vec<u8> {
    let mut j = serde_json::to_vec(json).unwrap();
    while j.len() % 4 != 0 {
        j.push(b' ');
    }
    let mut glb = Vec::new();
    glb.extend(b"glTF");
    glb.extend(2u32.to_le_bytes());
    glb.extend(((12 + 8 + j.len() + 8 + bin.len()) as u32).to_le_bytes());
    glb.extend((j.len() as u32).to_le_bytes());
    glb.extend(b"JSON");
    glb.extend(&j);
    glb.extend((bin.len() as u32).to_le_bytes());
    glb.extend(b"BIN\0");
    glb.extend(bin);
    glb
}

/// The unit square z = 0.5 (two triangles, facing +z) with (u, v) = (x, y).
const PLANE: [[f64; 3]; 4] = [[0.0, 0.0, 0.5], [1.0, 0.0, 0.5], [1.0, 1.0, 0.5], [0.0, 1.0, 0.5]];

/// Output vertices on the plane, away from the checkerboard's square
/// borders by more than `margin`, must have their square's colour exactly.
/// OBJ's v runs up (square row from the bottom), glTF's down.
fn assert_checkerboard(out: &Path, n: usize, v_up: bool, margin: f64) -> usize {
    let mut checked = 0;
    for (p, c) in coloured_vertices(out) {
        if (p[2] - 0.5).abs() > 1e-9 {
            continue;
        }
        // (A second copy of the plane two units along x reads the same.)
        let (u, v) = (p[0].rem_euclid(2.0), if v_up { 1.0 - p[1] } else { p[1] });
        let (fu, fv) = (u * n as f64, v * n as f64);
        if (fu - fu.round()).abs() < margin * n as f64 || (fv - fv.round()).abs() < margin * n as f64 {
            continue;
        }
        let white = (fu as usize + fv as usize) % 2 == 0;
        assert_eq!(c, if white { [255; 4] } else { [0, 0, 0, 255] }, "at {p:?}");
        checked += 1;
    }
    checked
}

/// A checkerboard texture on a plane comes out as the checkerboard at the
/// grid's resolution: OBJ + MTL + PNG, a GLB with the PNG inside, and a PLY
/// in MeshLab's texture convention.
#[test]
fn a_checkerboard_texture_comes_out_as_the_checkerboard() {
    let d = tempfile::tempdir().unwrap();
    let n = 4;
    std::fs::write(d.path().join("checker.png"), checker_png(n, 8)).unwrap();
    std::fs::write(d.path().join("plane.mtl"), "newmtl board\nKd 0.5 0.5 0.5\nmap_Kd checker.png\n").unwrap();
    let mut obj = String::from("mtllib plane.mtl\n");
    for p in PLANE {
        obj += &format!("v {} {} {}\nvt {} {}\n", p[0], p[1], p[2], p[0], p[1]);
    }
    obj += "usemtl board\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n";
    let objp = d.path().join("plane.obj");
    std::fs::write(&objp, obj).unwrap();
    let cells = "20000";
    let out = d.path().join("o.ply");
    let o = mint(&["resample", objp.to_str().unwrap(), out.to_str().unwrap(), "--cells", cells, "--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let cell = serde_json::from_slice::<serde_json::Value>(&o.stdout).unwrap()["cell_size"].as_f64().unwrap();
    // Half a texel of bilinear blending, and a cell.
    let checked = assert_checkerboard(&out, n, true, 0.5 / (8.0 * n as f64) + cell);
    assert!(checked > 200, "{checked} vertices checked");

    // Drawn in its texture: dark and light squares seen from above.
    let png = d.path().join("plane.png");
    let o = mint(&["render", objp.to_str().unwrap(), png.to_str().unwrap(), "--view", "top", "--up", "z", "--size", "200x200"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (w, h, px) = crate::common::png_rgb(&png);
    // The middle of the picture, inside the plane.
    let mid: Vec<&[u8; 3]> = px.iter().enumerate().filter(|(i, _)| (i % w).abs_diff(w / 2) < w / 5 && (i / w).abs_diff(h / 2) < h / 5).map(|(_, p)| p).collect();
    let dark = mid.iter().filter(|p| p.iter().all(|&c| c < 60)).count();
    let light = mid.iter().filter(|p| p.iter().all(|&c| c > 150)).count();
    assert!(dark > 500 && light > 500, "{dark} dark and {light} light pixels of {}", mid.len());
    // The same plane as a GLB with the PNG in its buffer (glTF's v runs down).
    let glb = checker_glb(n);
    let glbp = d.path().join("plane.glb");
    std::fs::write(&glbp, glb).unwrap();
    let out2 = d.path().join("o2.ply");
    let o = mint(&["resample", glbp.to_str().unwrap(), out2.to_str().unwrap(), "--cells", cells]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let checked = assert_checkerboard(&out2, n, false, 0.5 / (8.0 * n as f64) + cell);
    assert!(checked > 200, "{checked} vertices checked");

    // Two copies of the GLB as the tiles of a 3D Tiles tileset (z up, the
    // second two units along x): the textures of every tile.
    std::fs::write(d.path().join("tile.glb"), checker_glb(n)).unwrap();
    let tsp = two_tile_tileset(d.path(), "tile.glb", "tile.glb");
    let out4 = d.path().join("o4.ply");
    let o = mint(&["resample", tsp.to_str().unwrap(), out4.to_str().unwrap(), "--cells", "40000", "--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let cell4 = serde_json::from_slice::<serde_json::Value>(&o.stdout).unwrap()["cell_size"].as_f64().unwrap();
    let checked = assert_checkerboard(&out4, n, false, 0.5 / (8.0 * n as f64) + cell4);
    let far = coloured_vertices(&out4).iter().filter(|(p, _)| p[0] > 1.5).count();
    assert!(checked > 300 && far > 100, "{checked} vertices checked, {far} on the second tile");

    // The same plane as a PLY in MeshLab's convention: `comment
    // TextureFile` and a `texcoord` list per face (v up, as in OBJ).
    let mut ply = String::from("ply\nformat ascii 1.0\ncomment TextureFile checker.png\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 2\nproperty list uchar int vertex_indices\nproperty list uchar float texcoord\nend_header\n");
    for p in PLANE {
        ply += &format!("{} {} {}\n", p[0], p[1], p[2]);
    }
    for f in [[0, 1, 2], [0, 2, 3]] {
        let uv: Vec<String> = f.iter().map(|&v| format!("{} {}", PLANE[v][0], PLANE[v][1])).collect();
        ply += &format!("3 {} {} {} 6 {}\n", f[0], f[1], f[2], uv.join(" "));
    }
    let plyp = d.path().join("plane-tex.ply");
    std::fs::write(&plyp, ply).unwrap();
    let out3 = d.path().join("o3.ply");
    let o = mint(&["resample", plyp.to_str().unwrap(), out3.to_str().unwrap(), "--cells", cells]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let checked = assert_checkerboard(&out3, n, true, 0.5 / (8.0 * n as f64) + cell);
    assert!(checked > 200, "{checked} vertices checked");

    // Broken textures: a missing one warns and keeps the material's colour;
    // a damaged one is one line naming it; more than the budget is refused.
    std::fs::remove_file(d.path().join("checker.png")).unwrap();
    let o = mint(&["resample", objp.to_str().unwrap(), out.to_str().unwrap(), "--cells", cells]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success() && err.contains("checker.png") && err.contains("not found"), "{err}");
    assert!(coloured_vertices(&out).iter().all(|(_, c)| *c == [128, 128, 128, 255]), "Kd 0.5 without its texture");
    std::fs::write(d.path().join("checker.png"), &checker_png(n, 8)[..60]).unwrap();
    let o = mint(&["resample", objp.to_str().unwrap(), out.to_str().unwrap(), "--cells", cells]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.trim_end().lines().count() == 1 && err.contains("checker.png"), "{err}");
    std::fs::write(d.path().join("checker.png"), checker_png(512, 8)).unwrap();
    let o = mint(&["resample", objp.to_str().unwrap(), out.to_str().unwrap(), "--cells", cells, "--mem", "48M"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.trim_end().lines().count() == 1 && err.contains("MiB decoded") && err.contains("--mem"), "{err}");
}

/// Decimation (to 1%) and simplification keep colour by colour-aware
/// quadrics: a vertex whose merged neighbourhood lies on one side of the
/// border (farther from it than the output's longest edge) has exactly
/// that side's colour, and no vertex takes a colour the input does not
/// hold there (a blend of the two, never an overshoot).
#[test]
fn a_two_colour_sphere_keeps_its_colours_after_decimation() {
    let d = tempfile::tempdir().unwrap();
    let sphere = two_colour_sphere(d.path());
    for (cmd, name) in [("decimate", "d.ply"), ("simplify", "s.ply")] {
        let out = d.path().join(name);
        let o = mint(&[cmd, sphere.to_str().unwrap(), out.to_str().unwrap(), "--faces", "200", "--json"]);
        assert!(o.status.success(), "{cmd}: {}", String::from_utf8_lossy(&o.stderr));
        let s: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(s["colour"], true, "{s}");
        let vs = coloured_vertices(&out);
        let m = load(&out);
        let longest = m.faces.iter().flat_map(|f| (0..3).map(move |i| (f[i], f[(i + 1) % 3]))).map(|(a, b)| {
            let (p, q) = (m.positions[a as usize], m.positions[b as usize]);
            ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
        });
        let longest = longest.fold(0.0f64, f64::max);
        assert!(longest < 1.0, "{cmd}: an output edge of {longest}");
        let mut pure = 0;
        for (p, c) in &vs {
            if p[2].abs() > longest {
                assert_eq!(*c, if p[2] > 0.0 { RED } else { BLUE }, "{cmd}: vertex at z = {}", p[2]);
                pure += 1;
            } else {
                assert!(c[1] == 30 && (248..=252).contains(&(c[0] as u32 + c[2] as u32)), "{cmd}: {c:?} at z = {}", p[2]);
            }
        }
        assert!(pure * 3 > vs.len(), "{cmd}: {pure} of {} vertices away from the border", vs.len());
        // And --no-color writes geometry only.
        let o = mint(&[cmd, sphere.to_str().unwrap(), out.to_str().unwrap(), "--faces", "200", "--no-color", "--quiet"]);
        assert!(o.status.success());
        assert!(mint_io::MeshReader::open(&out, mint_io::ReadOptions::default()).unwrap().colours().is_none());
    }
}

/// A GLB of the unit plane z = 0.5 whose vertices carry `COLOR_0` (u8
/// RGBA, normalized), or no colour.
fn coloured_plane_glb(colour: Option<[u8; 4]>) -> Vec<u8> {
    let rgba = colour.unwrap_or([0; 4]);
    let mut bin: Vec<u8> = Vec::new();
    PLANE.iter().for_each(|p| p.iter().for_each(|c| bin.extend((*c as f32).to_le_bytes())));
    (0..4).for_each(|_| bin.extend(rgba));
    [0u16, 1, 2, 0, 2, 3].iter().for_each(|i| bin.extend(i.to_le_bytes()));
    bin.extend([0, 0]);
    let json = serde_json::json!({
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [if colour.is_some() {
            serde_json::json!({"attributes": {"POSITION": 0, "COLOR_0": 1}, "indices": 2})
        } else {
            serde_json::json!({"attributes": {"POSITION": 0}, "indices": 2})
        }]}],
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 16},
            {"buffer": 0, "byteOffset": 64, "byteLength": 12}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0.5], "max": [1, 1, 0.5]},
            {"bufferView": 1, "componentType": 5121, "normalized": true, "count": 4, "type": "VEC4"},
            {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}
        ]
    });
    pack_glb(&json, &bin)
}

/// The tiles of a tileset bring their vertex colours (`COLOR_0`); a tile
/// without any is white beside them, as a glTF primitive without
/// `COLOR_0` is.
#[test]
fn tiles_bring_their_vertex_colours() {
    let d = tempfile::tempdir().unwrap();
    std::fs::write(d.path().join("red.glb"), coloured_plane_glb(Some([200, 10, 10, 255]))).unwrap();
    // The first tile: the same plane with no colour at all.
    std::fs::write(d.path().join("plain.glb"), coloured_plane_glb(None)).unwrap();
    let tsp = two_tile_tileset(d.path(), "plain.glb", "red.glb");
    let out = d.path().join("o.ply");
    let o = mint(&["resample", tsp.to_str().unwrap(), out.to_str().unwrap(), "--cells", "20000"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let vs = coloured_vertices(&out);
    let (mut white, mut red) = (0, 0);
    for (p, c) in &vs {
        if (p[2] - 0.5).abs() > 1e-9 {
            continue;
        }
        if p[0] < 1.0 {
            assert_eq!(*c, [255; 4], "the plain tile at {p:?}");
            white += 1;
        } else if p[0] > 2.0 {
            assert_eq!(*c, [200, 10, 10, 255], "the red tile at {p:?}");
            red += 1;
        }
    }
    assert!(white > 100 && red > 100, "{white} white, {red} red");
}
