//! `mint volume` end to end (issue 32's done-when list): exact counts on
//! tiny volumes through the whole engine, the border closing the surface,
//! oblique affines putting a known point where the header says, labels
//! sharing their boundary, the same bytes under every configuration, the
//! shared real volumes closed and 2-manifold, and one line for each bad
//! input with nothing written.

use crate::cli::{mint, ok, p, run};
use mint_volume::{Frame, Sample, VolumeWriter};
use std::path::{Path, PathBuf};

fn shared(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/volumes").join(rel)
}

/// Writes `samples` (x fastest) as a volume at `path` with affine `m`.
fn write(path: &Path, dims: [u64; 3], sample: Sample, m: [[f64; 4]; 3], frame: Frame, samples: &[f32]) {
    let mut w = VolumeWriter::create(path, dims, sample, m, frame).unwrap();
    let n = (dims[0] * dims[1]) as usize;
    for k in 0..dims[2] as usize {
        w.write_slice(&samples[k * n..(k + 1) * n]).unwrap();
    }
    w.finish().unwrap();
}

const IDENTITY: [[f64; 4]; 3] = [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]];

fn check(path: &Path, extra: &[&str]) -> serde_json::Value {
    let mut args = vec!["check", p(path), "--json"];
    args.extend(extra);
    serde_json::from_str(&ok(&args)).unwrap()
}

fn watertight(path: &Path) {
    let c = check(path, &[]);
    assert_eq!(c["watertight"], true, "{}: {c}", path.display());
    assert_eq!((c["degenerate_faces"].as_u64(), c["duplicate_faces"].as_u64()), (Some(0), Some(0)), "{c}");
}

fn vertices(path: &Path) -> Vec<[f64; 3]> {
    mint_io::read_mesh(path).unwrap().0
}

#[test]
fn one_voxel_above_iso_is_an_octahedron_placed_by_an_oblique_affine() {
    let d = tempfile::tempdir().unwrap();
    let mut s = vec![0.0f32; 27];
    s[13] = 100.0;
    // 30 degrees about z, anisotropic spacing, an origin: LPS as DICOM would say.
    let (c, sn) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
    let m = [[0.5 * c, -0.7 * sn, 0.0, 10.0], [0.5 * sn, 0.7 * c, 0.0, -20.0], [0.0, 0.0, 2.0, 5.0]];
    for name in ["v.nii", "v.nhdr", "v.mha"] {
        let vol = d.path().join(name);
        write(&vol, [3, 3, 3], Sample::I16, m, Frame::Lps, &s);
        let out = d.path().join(format!("{name}.ply"));
        let json: serde_json::Value = serde_json::from_str(&ok(&["volume", p(&vol), p(&out), "--iso", "50", "--json"])).unwrap();
        let c = check(&out, &[]);
        assert_eq!((c["vertices"].as_u64(), c["faces"].as_u64(), c["watertight"].as_bool()), (Some(6), Some(8), Some(true)), "{name}: {c}");
        assert!(c["signed_volume"].as_f64().unwrap() > 0.0, "{name}: faces point out after a mirroring map");
        // Each vertex halfway from voxel (1,1,1) to a neighbour, in the file's frame.
        let world = |ijk: [f64; 3]| -> [f64; 3] { std::array::from_fn(|r| m[r][0] * ijk[0] + m[r][1] * ijk[1] + m[r][2] * ijk[2] + m[r][3]) };
        let mut want: Vec<[f64; 3]> = [[0.5, 1., 1.], [1.5, 1., 1.], [1., 0.5, 1.], [1., 1.5, 1.], [1., 1., 0.5], [1., 1., 1.5]].iter().map(|&q| world(q)).collect();
        if name.ends_with(".nii") {
            // NIfTI is RAS: the writer turned the LPS affine by negating x and y.
            want.iter_mut().for_each(|w| {
                w[0] = -w[0];
                w[1] = -w[1];
            });
            assert_eq!(json["volume"]["frame"], "RAS (patient)");
        } else if name.ends_with(".mha") {
            assert_eq!(json["volume"]["frame"], "LPS (patient)");
        }
        for v in vertices(&out) {
            assert!(want.iter().any(|w| (0..3).all(|k| (w[k] - v[k]).abs() < 1e-4)), "{name}: vertex {v:?} is not one of {want:?}");
        }
    }
}

#[test]
fn the_border_closes_the_surface_and_the_checkerboard_is_two_manifold() {
    let d = tempfile::tempdir().unwrap();
    // Every voxel inside: the surface is the box of the voxels' extent.
    let vol = d.path().join("full.nrrd");
    write(&vol, [4, 3, 2], Sample::U8, IDENTITY, Frame::Scanner, &[9.0; 24]);
    let out = d.path().join("full.ply");
    let o = run(&["volume", p(&vol), p(&out), "--iso", "9"]);
    assert!(o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("everything is inside"), "the warning: {}", String::from_utf8_lossy(&o.stderr));
    watertight(&out);
    for v in vertices(&out) {
        assert!((0..3).any(|k| (v[k] + 0.5).abs() < 1e-3 || (v[k] - ([4.0, 3.0, 2.0][k] - 0.5)).abs() < 1e-3), "{v:?} is not on the border");
    }
    // The ambiguous case: 2x2x2 alternating, at and beside the tie.
    let s: Vec<f32> = (0..8).map(|i| ((i & 1) ^ (i >> 1 & 1) ^ (i >> 2 & 1)) as f32).collect();
    let vol = d.path().join("cb.nrrd");
    write(&vol, [2, 2, 2], Sample::F32, IDENTITY, Frame::Scanner, &s);
    for iso in ["0.5", "1", "0.001"] {
        let out = d.path().join(format!("cb-{iso}.ply"));
        ok(&["volume", p(&vol), p(&out), "--iso", iso]);
        let c = check(&out, &["--no-weld"]);
        assert_eq!((c["boundary_edges"].as_u64(), c["non_manifold_edges"].as_u64()), (Some(0), Some(0)), "iso {iso}: {c}");
    }
}

/// The boundary edges of `faces` (edges one face uses), as vertex pairs.
fn boundary_edges(faces: &[[u32; 3]]) -> Vec<(u32, u32)> {
    let mut n = std::collections::HashMap::new();
    for f in faces {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            *n.entry((a.min(b), a.max(b))).or_insert(0u32) += 1;
        }
    }
    let mut e: Vec<(u32, u32)> = n.into_iter().filter(|&(_, c)| c == 1).map(|(e, _)| e).collect();
    e.sort_unstable();
    e
}

#[test]
fn open_border_leaves_the_surface_open_exactly_on_the_border() {
    let d = tempfile::tempdir().unwrap();
    // Layers z = 3..=4 of 6x5x8 voxels inside: a slab cut by the x and y
    // borders, plus a lone voxel well inside whose surface the border
    // never touches.
    let dims = [6u64, 5, 8];
    let mut s: Vec<f32> = (0..240).map(|i| if (3..=4).contains(&(i / 30)) { 10.0 } else { 0.0 }).collect();
    s[30 + 2 * 6 + 2] = 10.0;
    let vol = d.path().join("slab.nrrd");
    write(&vol, dims, Sample::U8, IDENTITY, Frame::Scanner, &s);
    let closed = d.path().join("closed.ply");
    ok(&["volume", p(&vol), p(&closed), "--iso", "5", "-q"]);
    watertight(&closed);
    let open = d.path().join("open.ply");
    let json: serde_json::Value = serde_json::from_str(&ok(&["volume", p(&vol), p(&open), "--iso", "5", "--open-border", "--json"])).unwrap();
    let (v, f) = mint_io::read_mesh(&open).unwrap();
    let (_, fc) = mint_io::read_mesh(&closed).unwrap();
    assert!(f.len() < fc.len() && !f.is_empty());
    assert_eq!(json["output_faces"].as_u64(), Some(f.len() as u64), "{json}");
    assert_eq!(json["output_vertices"].as_u64(), Some(v.len() as u64), "{json}");
    assert_eq!(json["volume"]["border_faces_removed"].as_u64(), Some((fc.len() - f.len()) as u64), "{json}");
    // Every vertex is used, and the boundary lies on the x and y border planes.
    let mut used = vec![false; v.len()];
    f.iter().flatten().for_each(|&i| used[i as usize] = true);
    assert!(used.iter().all(|&u| u), "an unused vertex is left");
    let b = boundary_edges(&f);
    assert_eq!(json["output_boundary_edges"].as_u64(), Some(b.len() as u64), "{json}");
    // Two sheets (top and bottom of the slab), each bounded by one loop.
    assert_eq!(json["output_boundary_loops"].as_u64(), Some(2), "{json}");
    let on_border = |q: [f64; 3]| (q[0] + 0.5).abs() < 1e-3 || (q[0] - 5.5).abs() < 1e-3 || (q[1] + 0.5).abs() < 1e-3 || (q[1] - 4.5).abs() < 1e-3;
    for &(a, c) in &b {
        assert!(on_border(v[a as usize]) && on_border(v[c as usize]), "boundary edge {:?}-{:?} off the border", v[a as usize], v[c as usize]);
    }
    let c = check(&open, &["--no-weld"]);
    assert_eq!((c["non_manifold_edges"].as_u64(), c["degenerate_faces"].as_u64(), c["duplicate_faces"].as_u64()), (Some(0), Some(0), Some(0)), "{c}");
    // The same bytes under other slabs, parts and threads.
    let want = std::fs::read(&open).unwrap();
    for extra in [&["--threads", "1"][..], &["--parts", "3", "--slab", "2", "--mem", "70M"][..]] {
        let o = d.path().join("open2.ply");
        let mut args = vec!["volume", p(&vol), p(&o), "--iso", "5", "--open-border", "-q"];
        args.extend(extra);
        ok(&args);
        assert!(std::fs::read(&o).unwrap() == want, "{extra:?}: other bytes");
    }
    // A real CT cut by its border: open there, still a 2-manifold (the
    // cap touches the body at points, whose vertices are split).
    let chest = d.path().join("chest.ply");
    let json: serde_json::Value = serde_json::from_str(&ok(&["volume", p(&shared("ct-chest-dicom-series-lungpetctdx")), p(&chest), "--iso", "300", "--open-border", "--json"])).unwrap();
    let c = check(&chest, &["--no-weld"]);
    assert_eq!((c["non_manifold_edges"].as_u64(), c["non_manifold_vertices"].as_u64(), c["inconsistently_oriented_edges"].as_u64(), c["unreferenced_vertices"].as_u64()), (Some(0), Some(0), Some(0), Some(0)), "{c}");
    assert!(json["volume"]["border_vertices_split"].as_u64().unwrap() > 0, "{json}");
    assert_eq!((c["boundary_edges"].as_u64(), c["boundary_loops"].as_u64()), (json["output_boundary_edges"].as_u64(), json["output_boundary_loops"].as_u64()), "{json}");
    assert_eq!(c["faces"].as_u64(), json["output_faces"].as_u64());
    // A surface the border never touches is the same with or without it.
    let mut t = vec![0.0f32; 240];
    t[30 * 4 + 2 * 6 + 2] = 10.0;
    write(&vol, dims, Sample::U8, IDENTITY, Frame::Scanner, &t);
    ok(&["volume", p(&vol), p(&closed), "--iso", "5", "-q"]);
    ok(&["volume", p(&vol), p(&open), "--iso", "5", "-q", "--open-border"]);
    assert!(std::fs::read(&open).unwrap() == std::fs::read(&closed).unwrap());
}

/// Samples of `R - |world(i, j, k) - c|` for affine `m`: the iso-0 surface
/// is a world sphere of radius `r` about `c`, whatever the affine.
fn world_ball(dims: [u64; 3], m: [[f64; 4]; 3], c: [f64; 3], r: f64) -> Vec<f32> {
    let mut s = Vec::new();
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                let q = [i as f64, j as f64, k as f64];
                let w: [f64; 3] = std::array::from_fn(|row| m[row][0] * q[0] + m[row][1] * q[1] + m[row][2] * q[2] + m[row][3]);
                s.push((r - ((w[0] - c[0]).powi(2) + (w[1] - c[1]).powi(2) + (w[2] - c[2]).powi(2)).sqrt()) as f32);
            }
        }
    }
    s
}

#[test]
fn a_volume_is_an_operand_of_csg_scenes_and_bool_in_its_world_frame() {
    let d = tempfile::tempdir().unwrap();
    let (c, r) = ([10.0, -2.0, 9.0], 6.0);
    // x flipped; then index i along world y and j along world x.
    let affines = [[[-0.8, 0.0, 0.0, 22.0], [0.0, 0.6, 0.0, -12.0], [0.0, 0.0, 1.25, 0.5]], [[0.0, 0.7, 0.0, 1.0], [0.9, 0.0, 0.0, -11.0], [0.0, 0.0, 1.1, 1.0]]];
    for (n, m) in affines.iter().enumerate() {
        let dims = [30u64, 34, 16];
        let vol = d.path().join(format!("ball{n}.nhdr"));
        write(&vol, dims, Sample::F32, *m, Frame::Scanner, &world_ball(dims, *m, c, r));
        // The ball with a box far from it: two closed components, the ball
        // where the header puts it.
        let scene = d.path().join(format!("u{n}.json"));
        std::fs::write(&scene, format!(r#"{{ "union": [ {{ "volume": {{ "file": "ball{n}.nhdr", "iso": 0 }} }}, {{ "box": {{ "size": [2, 2, 2] }}, "translate": [40, 0, 0] }} ] }}"#)).unwrap();
        let out = d.path().join(format!("u{n}.ply"));
        ok(&["csg", p(&scene), p(&out), "--cell-size", "0.4", "-q"]);
        let ch = check(&out, &[]);
        assert_eq!((ch["watertight"].as_bool(), ch["components"].as_u64()), (Some(true), Some(2)), "{n}: {ch}");
        let vs = vertices(&out);
        let ball: Vec<f64> = vs.iter().filter(|v| v[0] < 30.0).map(|v| ((v[0] - c[0]).powi(2) + (v[1] - c[1]).powi(2) + (v[2] - c[2]).powi(2)).sqrt()).collect();
        assert!(ball.len() > 1000, "{n}: {} ball vertices", ball.len());
        let worst = ball.iter().fold(0.0f64, |a, &x| a.max((x - r).abs()));
        assert!(worst < 0.2, "{n}: a ball vertex {worst} from the sphere");
        // The ball minus the half-space x <= c.x: a closed hemisphere.
        let scene = d.path().join(format!("h{n}.json"));
        std::fs::write(&scene, format!(r#"{{ "difference": [ {{ "volume": {{ "file": "ball{n}.nhdr", "iso": 0 }} }}, {{ "halfspace": {{ "normal": [1, 0, 0], "offset": {} }} }} ] }}"#, c[0])).unwrap();
        let half = d.path().join(format!("h{n}.ply"));
        ok(&["csg", p(&scene), p(&half), "--cell-size", "0.4", "-q"]);
        watertight(&half);
        let left = vertices(&half).iter().fold(f64::INFINITY, |a, v| a.min(v[0]));
        // (A crossing keeps MARGIN = 1/1024 cell off a grid node; f32 output.)
        assert!(left >= c[0] - 0.4 / 1024.0 - 1e-5, "{n}: a vertex at x = {left}, left of the cut");
        // The same bytes under other parts, slabs, threads and memory.
        let want = std::fs::read(&half).unwrap();
        for extra in [&["--threads", "1"][..], &["--parts", "3", "--slabs", "4", "--mem", "70M"][..]] {
            let o = d.path().join("again.ply");
            let mut args = vec!["csg", p(&scene), p(&o), "--cell-size", "0.4", "-q"];
            args.extend(extra);
            ok(&args);
            assert!(std::fs::read(&o).unwrap() == want, "{n} {extra:?}: other bytes");
        }
    }
    // `mint bool` with a volume side (--iso-a): the same bytes as the
    // scene of the same two operands.
    let sphere = d.path().join("s.ply");
    ok(&["gen", "sphere", p(&sphere), "--faces", "5000"]);
    let scene = d.path().join("b.json");
    std::fs::write(&scene, r#"{ "difference": [ { "volume": { "file": "ball0.nhdr", "iso": 0 } }, { "mesh": "s.ply", "translate": [0, 0, 0] } ] }"#).unwrap();
    let (by_csg, by_bool) = (d.path().join("bc.ply"), d.path().join("bb.ply"));
    ok(&["csg", p(&scene), p(&by_csg), "--cell-size", "0.4", "-q"]);
    ok(&["bool", "difference", p(&d.path().join("ball0.nhdr")), p(&sphere), p(&by_bool), "--iso-a", "0", "--cell-size", "0.4", "-q"]);
    watertight(&by_bool);
    assert!(std::fs::read(&by_bool).unwrap() == std::fs::read(&by_csg).unwrap(), "bool and csg differ");
    // What a scene cannot place: an oblique volume, a transformed one.
    let (cs, sn) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
    let oblique = [[cs, -sn, 0.0, 0.0], [sn, cs, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]];
    write(&d.path().join("ob.nhdr"), [8, 8, 8], Sample::U8, oblique, Frame::Scanner, &[1.0; 512]);
    for (json, want) in [
        (r#"{ "union": [ { "volume": { "file": "ob.nhdr", "iso": 1 } }, { "sphere": { "radius": 1 } } ] }"#, "oblique"),
        (r#"{ "union": [ { "volume": { "file": "ball0.nhdr", "iso": 0 }, "scale": 2 }, { "sphere": { "radius": 1 } } ] }"#, "placed by its own header"),
        (r#"{ "volume": { "file": "ball0.nhdr" } }"#, "missing key 'iso'"),
    ] {
        let scene = d.path().join("bad.json");
        std::fs::write(&scene, json).unwrap();
        let o = run(&["csg", p(&scene), p(&d.path().join("bad.ply")), "--cell-size", "0.5"]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(want) && err.trim().lines().count() == 1, "{json}: {err}");
        assert!(!d.path().join("bad.ply").exists());
    }
}

#[test]
fn labels_share_their_boundary_without_gaps() {
    let d = tempfile::tempdir().unwrap();
    let vol = d.path().join("l.nrrd");
    ok(&["gen", "labels", p(&vol), "--dims", "40,40,40"]);
    let out = d.path().join("l.ply");
    ok(&["volume", p(&vol), p(&out), "--labels"]);
    let mut sets = Vec::new();
    for v in [1, 2, 3] {
        let f = d.path().join(format!("l.label-{v}.ply"));
        watertight(&f);
        sets.push(vertices(&f).into_iter().map(|q| q.map(|c| c.to_bits())).collect::<std::collections::HashSet<_>>());
    }
    // Labels 1 and 2 touch (ball against box): many vertices bit for bit the same.
    let shared = sets[0].intersection(&sets[1]).count();
    assert!(shared > 20, "labels 1 and 2 share {shared} vertices");
    // One file: every label's surface, closed each (judged without welding).
    let one = d.path().join("one.ply");
    ok(&["volume", p(&vol), p(&one), "--labels", "1,2,3", "--one-file"]);
    let c = check(&one, &["--no-weld"]);
    assert_eq!((c["boundary_edges"].as_u64(), c["non_manifold_edges"].as_u64()), (Some(0), Some(0)), "{c}");
    let faces: u64 = (1..=3).map(|v| check(&d.path().join(format!("l.label-{v}.ply")), &[])["faces"].as_u64().unwrap()).sum();
    assert_eq!(c["faces"].as_u64(), Some(faces));
}

#[test]
fn a_volume_gives_the_same_bytes_under_every_configuration() {
    let d = tempfile::tempdir().unwrap();
    let vol = d.path().join("g.nhdr");
    ok(&["gen", "volume", p(&vol), "--dims", "70,60,50", "--spacing", "0.8,0.8,1.25"]);
    // Wide and flat: five bands of rows per plane, so that one thread
    // crosses them in two groups and two threads in one.
    let wide = d.path().join("w.nhdr");
    ok(&["gen", "volume", p(&wide), "--dims", "700,400,5"]);
    for (vol, grid) in [(&vol, &[][..]), (&vol, &["--cell-size", "1.7"][..]), (&wide, &[][..])] {
        let mut want: Option<Vec<u8>> = None;
        let work = d.path().join("work");
        let variants: [&[&str]; 6] = [&["--threads", "1"], &["--threads", "2"], &["--parts", "3", "--slabs", "4"], &["--mem", "70M", "--slab", "3"], &["--parts", "7", "--threads", "2"], &["--work", p(&work)]];
        for (i, v) in variants.iter().enumerate() {
            let out = d.path().join(format!("o{i}.ply"));
            let mut args = vec!["volume", p(&vol), p(&out), "--iso", "1000", "-q"];
            args.extend(grid);
            args.extend(*v);
            ok(&args);
            let got = std::fs::read(&out).unwrap();
            match &want {
                None => {
                    watertight(&out);
                    want = Some(got)
                }
                Some(w) => assert!(&got == w, "{grid:?} {v:?}: other bytes"),
            }
        }
        std::fs::remove_dir_all(&work).unwrap();
    }
}

#[test]
fn every_shared_volume_gives_a_closed_two_manifold_surface() {
    let d = tempfile::tempdir().unwrap();
    for (rel, iso, frame) in [
        ("ct-head-headsq-nrrd/quarter.nhdr", "1150", "scanner"),
        ("mr-head-mhd-vtk/HeadMRVolume.mhd", "60", "LPS (patient)"),
        ("ct-body-nifti-totalsegmentator/example_ct.nii.gz", "300", "RAS (patient)"),
        ("ct-body-nifti-totalsegmentator/example_ct_sm.nii.gz", "-500", "RAS (patient)"),
    ] {
        let out = d.path().join("o.ply");
        let json: serde_json::Value = serde_json::from_str(&ok(&["volume", p(&shared(rel)), p(&out), "--iso", iso, "--json"])).unwrap();
        assert_eq!(json["volume"]["frame"], frame, "{rel}");
        assert!(json["output_faces"].as_u64().unwrap() > 10_000, "{rel}: {json}");
        watertight(&out);
    }
}

#[test]
fn bad_volumes_fail_with_one_line_and_write_nothing() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    let w = |name: &str, bytes: &[u8]| -> PathBuf {
        let f = dir.join(name);
        std::fs::write(&f, bytes).unwrap();
        f
    };
    let mut cases: Vec<(PathBuf, Vec<&str>, &str)> = Vec::new();
    // Dimensions that do not match the data.
    w("short.raw", &[0u8; 100]);
    cases.push((w("short.nhdr", b"NRRD0004\ntype: uchar\ndimension: 3\nsizes: 5 5 5\nencoding: raw\ndata file: short.raw\n"), vec![], "the dimensions do not match the data"));
    // A truncated gzip slice.
    let mut gz = b"NRRD0004\ntype: uchar\ndimension: 3\nsizes: 8 8 8\nencoding: gzip\n\n".to_vec();
    let mut e = flate2_encoder();
    std::io::Write::write_all(&mut e, &[200u8; 300]).unwrap();
    gz.extend(e.finish().unwrap());
    cases.push((w("trunc.nrrd", &gz), vec![], "ends inside slice 4"));
    // Dimensions whose product overflows.
    cases.push((w("huge.nhdr", b"NRRD0004\ntype: short\ndimension: 3\nsizes: 4294967296 4294967296 4294967296\nendian: little\nencoding: raw\ndata file: short.raw\n"), vec![], "overflow"));
    // Raw dimensions that do not fit the file.
    cases.push((dir.join("short.raw"), vec!["--raw-dims", "10,10,10", "--raw-type", "u8"], "do not match the data"));
    // Not a volume.
    cases.push((w("x.txt", b"hello"), vec![], "not a volume mint knows"));
    // Slices too wide for the budget: two of 2048 x 2048 f32 samples and two
    // node planes do not fit 64M (16 MiB after the reserve).
    w("wide.raw", &vec![0u8; 2048 * 2048 * 2]);
    cases.push((dir.join("wide.raw"), vec!["--raw-dims", "2048,2048,2", "--raw-type", "u8", "--mem", "64M"], "more than the memory budget (16 MiB)"));
    for (input, extra, want) in cases {
        let out = dir.join("out.ply");
        let mut args = vec!["volume", p(&input), p(&out), "--iso", "1"];
        args.extend(extra);
        let o = run(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{}: succeeded", input.display());
        assert!(err.contains(want), "{}: {err}", input.display());
        assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
        assert!(!out.exists());
    }
    let names: Vec<String> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    assert!(names.iter().all(|n| !n.starts_with('.')), "temporary files left: {names:?}");
    // A NaN-filled float volume: a warning, an empty result.
    let vol = dir.join("nan.nrrd");
    write(&vol, [3, 3, 3], Sample::F32, IDENTITY, Frame::Scanner, &[f32::NAN; 27]);
    let o = mint().args(["volume", p(&vol), p(&dir.join("nan.ply")), "--iso", "0"]).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("27 of 27 samples are NaN") && err.contains("no sample is a finite number"), "{err}");
    // An iso above every value: warned, empty.
    let vol = dir.join("low.nrrd");
    write(&vol, [3, 3, 3], Sample::U8, IDENTITY, Frame::Scanner, &[5.0; 27]);
    let o = run(&["volume", p(&vol), p(&dir.join("low.ply")), "--iso", "6"]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("above every value"), "{}", String::from_utf8_lossy(&o.stderr));
}

fn flate2_encoder() -> flate2::write::GzEncoder<Vec<u8>> {
    flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default())
}

#[test]
fn compressed_and_multi_frame_dicom_give_the_bytes_of_their_uncompressed_series() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let d = tempfile::tempdir().unwrap();
    let mesh = |input: &Path, name: &str| -> (Vec<u8>, serde_json::Value) {
        let out = d.path().join(name);
        let json: serde_json::Value = serde_json::from_str(&ok(&["volume", p(input), p(&out), "--iso", "0", "--json"])).unwrap();
        watertight(&out);
        (std::fs::read(&out).unwrap(), json)
    };
    // Three 64 x 64 crops as single-frame files, and as one enhanced
    // multi-frame file (frames stored out of order), plain and compressed.
    let (want, j) = mesh(&data.join("dicom-multiframe/single"), "single.ply");
    assert!(j["output_faces"].as_u64().unwrap() > 1000, "{j}");
    for (name, format) in [
        ("enhanced.dcm", "DICOM series"),
        ("enhanced-rle.dcm", "DICOM series (RLE Lossless)"),
        ("enhanced-jpeg-lossless.dcm", "DICOM series (JPEG Lossless)"),
    ] {
        let one = d.path().join(name.replace(".dcm", ""));
        std::fs::create_dir(&one).unwrap();
        std::fs::copy(data.join("dicom-multiframe").join(name), one.join(name)).unwrap();
        let (got, j) = mesh(&one, &format!("{name}.ply"));
        assert_eq!(j["volume"]["format"], format, "{name}");
        assert!(got == want, "{name}: other bytes than the single-frame series");
    }
}

/// `bytes` (an explicit-VR little-endian DICOM file) with the last digit of
/// its SeriesInstanceUID (0020,000E) changed: another series, same length.
fn other_series(bytes: &[u8]) -> Vec<u8> {
    let tag = [0x20, 0x00, 0x0E, 0x00, b'U', b'I'];
    let i = bytes.windows(6).position(|w| w == tag).expect("a SeriesInstanceUID");
    let len = u16::from_le_bytes([bytes[i + 6], bytes[i + 7]]) as usize;
    let mut b = bytes.to_vec();
    let value = &mut b[i + 8..i + 8 + len];
    let last = value.iter().rposition(u8::is_ascii_digit).unwrap();
    value[last] = if value[last] == b'9' { b'0' } else { value[last] + 1 };
    b
}

#[test]
fn dicom_series_chooses_one_of_the_series_in_a_folder() {
    // Slices 1-4 of the shared chest series, 5-7 moved to another series.
    let src = shared("ct-chest-dicom-series-lungpetctdx");
    let d = tempfile::tempdir().unwrap();
    let dir = d.path().join("study");
    std::fs::create_dir(&dir).unwrap();
    for n in 1..=7 {
        let b = std::fs::read(src.join(format!("1-{n:02}.dcm"))).unwrap();
        std::fs::write(dir.join(format!("1-{n:02}.dcm")), if n <= 4 { b } else { other_series(&b) }).unwrap();
    }
    let out = d.path().join("out.ply");
    let o = run(&["volume", p(&dir), p(&out), "--iso", "300"]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && e.contains("holds 2 series") && e.contains("--dicom-series") && e.lines().count() == 1, "{e}");
    assert!(!out.exists(), "nothing written on error");
    let slices = |args: &[&str]| -> u64 {
        let mut a = vec!["volume"];
        a.extend(args);
        a.extend([p(&out), "--iso", "300", "--json"]);
        let j: serde_json::Value = serde_json::from_str(&ok(&a)).unwrap();
        watertight(&out);
        j["volume"]["slices_read"].as_u64().unwrap()
    };
    assert_eq!(slices(&[p(&dir), "--dicom-series", "1"]), 4);
    assert_eq!(slices(&[p(&dir), "--dicom-series", "2"]), 3);
    let f6 = dir.join("1-06.dcm");
    assert_eq!(slices(&[p(&f6)]), 3, "a file picks its own series");
    let o = run(&["volume", p(&dir), p(&out), "--iso", "300", "--dicom-series", "3"]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && e.contains("no series number 3"), "{e}");
    // A csg scene names the series the same way.
    let scene = d.path().join("s.json");
    std::fs::write(&scene, format!("{{\"volume\": {{\"file\": \"{}\", \"iso\": 300, \"dicom_series\": 2}}}}", dir.display())).unwrap();
    let j: serde_json::Value = serde_json::from_str(&ok(&["csg", p(&scene), p(&out), "--cells", "20000", "--json"])).unwrap();
    assert!(j["output_faces"].as_u64().unwrap() > 0, "{j}");
}
