//! Colour (issue 27, first step: reading it and drawing it). A sphere whose
//! upper half is red and lower half blue, per vertex, renders red above and
//! blue below; `--color shading` ignores the colours; the summary says
//! which files were drawn in colour.

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
    assert!(err.contains("per-vertex colours: 1 of the files"), "{err}");
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
