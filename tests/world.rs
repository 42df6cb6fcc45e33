//! World coordinates (issue 26): geo-referenced (UTM-like) and tiny models
//! keep their geometry through resample, bool, decimate, simplify and
//! convert: f64 where f32 cannot place the output within a thousandth of a
//! cell (or a millionth of the extent without a grid), a one-line refusal
//! from formats that hold only f32, and a `check` whose verdict agrees with
//! its counts on a collapsed mesh.

use crate::common::{box_mesh, load, resample, Opts};
use mint_core::{GridSize, MeshSink, TriMesh};
use mint_io::{Format, MeshWriter, WriteOptions};
use mint_pipeline::NoProgress;
use std::path::{Path, PathBuf};

/// A UTM-like offset: x ≈ 5·10⁵, y ≈ 5.4·10⁶ metres.
const AT: [f64; 3] = [512345.25, 5412345.5, 120.0];

fn mint_bin() -> PathBuf {
    PathBuf::from(env!("CARGO_BIN_EXE_mint"))
}

/// Writes `m` with f64 coordinates (as geo-referenced data comes).
fn write_f64(dir: &Path, name: &str, m: &TriMesh) -> PathBuf {
    let path = dir.join(name);
    let mut w = MeshWriter::create(&path, Format::from_path(&path).unwrap(), WriteOptions { double: true, ..Default::default() }).unwrap();
    for p in &m.positions {
        w.vertex(*p).unwrap();
    }
    for f in &m.faces {
        w.face(*f).unwrap();
    }
    w.finish().unwrap();
    path
}

/// A sphere of radius `r` around `c`, as a UV mesh.
fn sphere(c: [f64; 3], r: f64) -> TriMesh {
    let mut m = TriMesh::default();
    mint_gen::sphere([0.0; 3], 1.0, 40_000, &mut m).unwrap();
    for p in &mut m.positions {
        *p = [c[0] + r * p[0], c[1] + r * p[1], c[2] + r * p[2]];
    }
    m
}

fn header_is_double(path: &Path) -> bool {
    let bytes = std::fs::read(path).unwrap();
    let head = String::from_utf8_lossy(&bytes[..bytes.len().min(400)]).into_owned();
    head.contains("property double x")
}

#[test]
fn a_utm_sphere_keeps_its_shape_and_is_watertight() {
    let d = tempfile::tempdir().unwrap();
    let input = write_f64(d.path(), "utm.ply", &sphere(AT, 10.0));
    let out = d.path().join("out.ply");
    let s = resample(&input, &out, &Opts::new(GridSize::Cells(1_000_000)), &NoProgress).unwrap();
    assert!(s.output_precision.starts_with("f64"), "{}", s.output_precision);
    assert!(header_is_double(&out));
    let m = load(&out);
    let r = mint_mesh::check(&m.positions, &m.faces);
    assert!(r.watertight, "{r:?}");
    // Every vertex is a crossing of a grid line with the input's triangles:
    // within the chord error of the sphere, never on a half-metre lattice.
    // (f32 would move them by up to 0.25.)
    for p in &m.positions {
        let rad = ((p[0] - AT[0]).powi(2) + (p[1] - AT[1]).powi(2) + (p[2] - AT[2]).powi(2)).sqrt();
        assert!(rad > 10.0 - 0.01 && rad < 10.0 + 1e-6, "radius {rad}");
    }
    // The same sphere at the origin gives the same surface, moved (a few
    // near-tie cells may differ: the inputs differ by rounding).
    let centred = write_f64(d.path(), "centred.ply", &sphere([0.0; 3], 10.0));
    let out0 = d.path().join("out0.ply");
    let s0 = resample(&centred, &out0, &Opts::new(GridSize::Cells(1_000_000)), &NoProgress).unwrap();
    assert_eq!(s0.output_precision, "f32");
    let m0 = load(&out0);
    assert!((m0.positions.len() as f64 - m.positions.len() as f64).abs() <= 1e-3 * m.positions.len() as f64);
    let moved: Vec<[f64; 3]> = m.positions.iter().map(|p| [p[0] - AT[0], p[1] - AT[1], p[2] - AT[2]]).collect();
    let (ab, ba) = mint_mesh::symmetric_distance((&moved, &m.faces), (&m0.positions, &m0.faces), 20_000, 1);
    assert!(ab.mean.max(ba.mean) <= 0.01 * s.cell_size && ab.max.max(ba.max) <= s.cell_size, "{ab:?} {ba:?}");
}

#[test]
fn a_building_at_five_million_metres_stays_on_its_faces() {
    let d = tempfile::tempdir().unwrap();
    let (lo, hi) = ([5.0e6, 5.0e6, 100.0], [5.0e6 + 30.0, 5.0e6 + 20.0, 150.0]);
    let input = write_f64(d.path(), "box.ply", &box_mesh(lo, hi));
    let out = d.path().join("out.ply");
    let s = resample(&input, &out, &Opts::new(GridSize::CellSize(0.25)), &NoProgress).unwrap();
    let m = load(&out);
    assert!(mint_mesh::check(&m.positions, &m.faces).watertight);
    for p in &m.positions {
        let off = (0..3).map(|k| (p[k] - lo[k]).abs().min((p[k] - hi[k]).abs())).fold(f64::INFINITY, f64::min);
        assert!(off <= 0.01 * s.cell_size, "{p:?} is {off} off the box's faces");
    }
    // Decimated too: watertight, f64, on the box (to the collapse's error).
    let dec = d.path().join("dec.ply");
    let o = std::process::Command::new(mint_bin()).arg("decimate").arg(&input).arg(&dec).args(["--faces", "500", "--json", "--quiet"]).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(j["output_precision"].as_str().unwrap().starts_with("f64"), "{j}");
    assert!(j["output_watertight"].as_bool().unwrap());
    assert!(header_is_double(&dec));
}

#[test]
fn f32_only_formats_refuse_and_convert_keeps_f64() {
    let d = tempfile::tempdir().unwrap();
    let m = sphere(AT, 10.0);
    let input = write_f64(d.path(), "utm.ply", &m);
    for out in ["o.stl", "o.3ds"] {
        let o = std::process::Command::new(mint_bin()).arg("resample").arg(&input).arg(d.path().join(out)).args(["--cells", "20000", "--quiet"]).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.lines().count() == 1 && err.contains("stores f32 coordinates") && err.contains(".ply or .obj"), "{out}: {err}");
        assert!(!d.path().join(out).exists());
        let o = std::process::Command::new(mint_bin()).arg("convert").arg(&input).arg(d.path().join(out)).output().unwrap();
        assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("stores f32 coordinates"));
    }
    // OBJ keeps every coordinate bit for bit.
    let obj = d.path().join("o.obj");
    let o = std::process::Command::new(mint_bin()).arg("convert").arg(&input).arg(&obj).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(load(&obj).positions, m.positions);
}

#[test]
fn a_tiny_scene_keeps_distinct_vertices_and_a_collapsed_mesh_is_not_watertight() {
    let d = tempfile::tempdir().unwrap();
    let scene = d.path().join("tiny.json");
    std::fs::write(&scene, r#"{"sphere": {"radius": 1e-100}}"#).unwrap();
    let out = d.path().join("tiny.ply");
    let o = std::process::Command::new(mint_bin()).arg("csg").arg(&scene).arg(&out).args(["--cells", "20000", "--quiet"]).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let m = load(&out);
    let mut keys: Vec<[u64; 3]> = m.positions.iter().map(|p| p.map(f64::to_bits)).collect();
    keys.sort_unstable();
    keys.dedup();
    assert_eq!(keys.len(), m.positions.len(), "vertices collapsed onto each other");
    assert!(mint_mesh::check(&m.positions, &m.faces).watertight);
    // The same output forced into f32 collapses, and check says so.
    let mut collapsed = m.clone();
    for p in &mut collapsed.positions {
        *p = p.map(|c| c as f32 as f64);
    }
    let mut welded = collapsed.clone();
    mint_mesh::weld(&mut welded.positions, &mut welded.faces);
    let r = mint_mesh::check(&welded.positions, &welded.faces);
    assert!(!r.watertight, "{r:?}");
}

/// A closed stdout ends a command quietly, killed by SIGPIPE as every Unix
/// tool is (it panicked with "failed printing to stdout: Broken pipe").
#[test]
fn a_closed_stdout_ends_the_command_quietly() {
    use std::os::unix::process::ExitStatusExt;
    let d = tempfile::tempdir().unwrap();
    let input = write_f64(d.path(), "s.ply", &sphere([0.0; 3], 1.0));
    for args in [&["check", "--json"][..], &["info"][..], &["validate", "--json"][..], &["check"][..]] {
        let mut child = std::process::Command::new(mint_bin())
            .args(&args[..1])
            .arg(&input)
            .args(&args[1..])
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        drop(child.stdout.take()); // like `| head -0`
        let o = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!err.contains("panicked") && !err.contains("Broken pipe"), "{args:?}: {err}");
        assert!(o.status.success() || o.status.signal() == Some(libc_sigpipe()), "{args:?}: {:?} {err}", o.status);
    }
}

fn libc_sigpipe() -> i32 {
    13
}

/// The summary's intercept counts add up, also when nothing is kept (they
/// wrapped around: "kept 18446744073709550729").
#[test]
fn intercept_counts_add_up_even_when_the_result_is_empty() {
    let d = tempfile::tempdir().unwrap();
    // A two-sided triangle (the same face both ways): every crossing cancels.
    let tri = TriMesh { positions: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], faces: vec![[0, 1, 2], [0, 2, 1]] };
    let input = write_f64(d.path(), "tri.ply", &tri);
    let s = resample(&input, &d.path().join("o.ply"), &Opts::new(GridSize::Cells(10_000)), &NoProgress).unwrap();
    assert_eq!((s.output_faces, s.intercepts_kept, s.intercepts_removed), (0, 0, s.intercepts_found), "{s:?}");
    let scan = crate::common::write_mesh(d.path(), "scan.ply", |sink| drop(mint_gen::scan_like(60_000, 3, &Default::default(), sink).unwrap()));
    for slabs in [1, 3] {
        let o = Opts::new(GridSize::Cells(40_000)).with(|o| {
            o.tuning.slabs = slabs;
            o.tuning.slab_layers = Some(2);
            o.tuning.work_dir = Some(d.path().join(format!("w{slabs}")));
        });
        let s = resample(&scan, &d.path().join("s.ply"), &o, &NoProgress).unwrap();
        assert_eq!(s.intercepts_kept + s.intercepts_removed, s.intercepts_found, "{s:?}");
        assert_eq!(s.intercepts_kept, s.output_vertices - s.synthesized_vertices);
    }
}

/// A VCGLIB-style ascii PLY whose face lines carry more numbers than the
/// header declares resamples, and the run says so once (issue 26: it was
/// refused).
#[test]
fn undeclared_values_on_ascii_ply_lines_are_read_and_reported() {
    let d = tempfile::tempdir().unwrap();
    let input = d.path().join("vcg.ply");
    let body = "ply\nformat ascii 1.0\ncomment VCGLIB generated\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
element face 4\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n\
3 0 2 1 6 0 0 1 0 0 1\n3 0 1 3 6 0 0 1 0 0 1\n3 0 3 2\n3 1 2 3\n";
    std::fs::write(&input, body).unwrap();
    let out = d.path().join("o.ply");
    let o = std::process::Command::new(mint_bin()).arg("resample").arg(&input).arg(&out).args(["--cells", "1000", "--json"]).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let w = v["warnings"].as_array().unwrap();
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(w[0].as_str().unwrap().contains("line 15: element 'face'"), "{w:?}");
    assert_eq!(err.matches("mint: warning:").count(), 1, "{err}");
    assert_eq!(v["output_faces"].as_u64().map(|f| f > 0), Some(true));
}

/// A sphere whose pole vertex is moved along y to `y` (a spike of needle
/// triangles), as a binary PLY.
fn spiked_sphere(dir: &Path, name: &str, y: f64) -> PathBuf {
    let mut m = sphere([0.0; 3], 1.0);
    // The vertex with the largest fan: the spike's triangles are many.
    let mut valence = vec![0u32; m.positions.len()];
    for f in &m.faces {
        for &v in f {
            valence[v as usize] += 1;
        }
    }
    let pole = (0..valence.len()).max_by_key(|&i| (valence[i], std::cmp::Reverse(i))).unwrap();
    m.positions[pole][1] = y;
    write_f64(dir, name, &m)
}

/// One spike makes decimate neither slow, hungry nor empty (issue 26: a
/// vertex at y = 2^31 took 28 s and 2.8 GiB to write an empty mesh). A
/// moderate spike is left out of the area estimate (the cells stay those of
/// the sphere, the output is a watertight sphere); a far one, whose box no
/// grid of those cells can hold, is refused at once with one line naming
/// the largest needle; and a resampling that comes out empty is refused
/// rather than written as an empty mesh.
#[test]
fn a_spike_does_not_sink_decimate() {
    let d = tempfile::tempdir().unwrap();
    let decimate = |input: &Path, out: &Path| {
        let t = std::time::Instant::now();
        let o = std::process::Command::new(mint_bin()).arg("decimate").arg(input).arg(out).args(["--faces", "500", "--json", "--route", "resample"]).output().unwrap();
        (o, t.elapsed().as_secs_f64())
    };
    let plain = write_f64(d.path(), "plain.ply", &sphere([0.0; 3], 1.0));
    let (o, _) = decimate(&plain, &d.path().join("p.ply"));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let p: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(p["needles_ignored"], 0);
    let h0 = p["cell_size"].as_f64().unwrap();
    // A spike 1000 radii long: left out, same cells, a clean sphere.
    let spiked = spiked_sphere(d.path(), "spike.ply", 1000.0);
    let out = d.path().join("s.ply");
    let (o, _) = decimate(&spiked, &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(s["needles_ignored"].as_u64().unwrap() > 0, "{s}");
    let h = s["cell_size"].as_f64().unwrap();
    assert!((h / h0 - 1.0).abs() < 0.05, "cells {h} against {h0} without the spike");
    assert!(s["output_watertight"].as_bool().unwrap() && s["output_faces"].as_u64().unwrap() >= 400, "{s}");
    let m = load(&out);
    let r = m.positions.iter().map(|p| (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt()).fold(0.0f64, f64::max);
    assert!(r < 1.5, "the output reaches {r} from the centre");
    // A spike to 2^31: refused at once, naming the needle.
    let far = spiked_sphere(d.path(), "far.ply", 2f64.powi(31));
    let out = d.path().join("f.ply");
    let (o, secs) = decimate(&far, &out);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("far.ply") && err.contains("needle") && err.contains("face ") && err.contains("2.147e9 long"), "{err}");
    assert!(secs < 10.0, "refusing took {secs} s");
    assert!(!out.exists());
    // A two-sided sheet (each face both ways) resamples to nothing: refused.
    let tri = TriMesh { positions: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], faces: vec![[0, 1, 2], [0, 2, 1]] };
    let sheet = write_f64(d.path(), "tri.ply", &tri);
    let out = d.path().join("t.ply");
    let (o, _) = decimate(&sheet, &out);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("the surface is empty") && err.contains("nothing written"), "{err}");
    assert!(!out.exists());
}

/// A needle 2·10⁵ cells long makes a grid of 1.5M nearly empty layers: the
/// run stays within its memory budget (sub-slabs count their planes, not
/// only their records), and a budget too small for the per-layer tables is
/// refused at once with one line instead of exhausting memory (issue 26:
/// 13.9 GiB under a 5.9 GiB budget for a longer needle).
#[test]
fn a_grid_of_many_empty_layers_stays_within_its_budget() {
    let d = tempfile::tempdir().unwrap();
    let input = spiked_sphere(d.path(), "needle.ply", 2e5);
    let run = |mem: &str| {
        std::process::Command::new(mint_bin()).arg("resample").arg(&input).arg(d.path().join(format!("o{mem}.ply")))
            .args(["--cell-size", "0.1", "--mem", mem, "--json"]).output().unwrap()
    };
    let o = run("64M");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("layers along its slab axis") && err.contains("--mem"), "{err}");
    let o = run("384M");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let peak = v["peak_heap_bytes"].as_u64().unwrap();
    assert!(peak <= 384 << 20, "peak heap {} MiB over a 384 MiB budget", peak >> 20);
    assert!(v["output_faces"].as_u64().unwrap() > 1000 && v["grid_cells"][1].as_u64().unwrap() > 1_000_000, "{v}");
}

/// glTF keeps world coordinates (issue 26): positions are f32 offsets from
/// an origin in the node's f64 translation, so a UTM sphere and a building
/// at 5·10⁶ m resample, decimate and convert to glTF and back, watertight,
/// every vertex within 1% of a cell of where the f64 output puts it. What
/// glTF cannot hold is refused with one line: `--double`, and a model too
/// small for f32 even relative to its centre.
#[test]
fn gltf_round_trips_keep_world_coordinates() {
    let d = tempfile::tempdir().unwrap();
    let mint = |args: &[&std::ffi::OsStr]| std::process::Command::new(mint_bin()).args(args).output().unwrap();
    let os = |p: &Path| p.as_os_str().to_owned();
    // The UTM sphere: the same run written as f64 PLY and as GLB.
    let input = write_f64(d.path(), "utm.ply", &sphere(AT, 10.0));
    let (ply, glb) = (d.path().join("s.ply"), d.path().join("s.glb"));
    let s = resample(&input, &ply, &Opts::new(GridSize::Cells(1_000_000)), &NoProgress).unwrap();
    let g = resample(&input, &glb, &Opts::new(GridSize::Cells(1_000_000)), &NoProgress).unwrap();
    assert!(g.output_precision.starts_with("f32 relative to an origin"), "{}", g.output_precision);
    let (a, b) = (load(&ply), load(&glb));
    assert_eq!(a.faces, b.faces);
    let worst = a.positions.iter().zip(&b.positions).map(|(p, q)| (0..3).map(|k| (p[k] - q[k]).abs()).fold(0.0, f64::max)).fold(0.0, f64::max);
    assert!(worst <= 0.01 * s.cell_size, "glTF moved a vertex by {worst} (cell {})", s.cell_size);
    assert!(mint_mesh::check(&b.positions, &b.faces).watertight);
    // The building: resample, decimate, convert to .gltf and back.
    let (lo, hi) = ([5.0e6, 5.0e6, 100.0], [5.0e6 + 30.0, 5.0e6 + 20.0, 150.0]);
    let boxp = write_f64(d.path(), "box.ply", &box_mesh(lo, hi));
    let on_box = |m: &TriMesh, tol: f64, what: &str| {
        assert!(mint_mesh::check(&m.positions, &m.faces).watertight, "{what}: not watertight");
        for p in &m.positions {
            let off = (0..3).map(|k| (p[k] - lo[k]).abs().min((p[k] - hi[k]).abs())).fold(f64::INFINITY, f64::min);
            assert!(off <= tol, "{what}: {p:?} is {off} off the box's faces");
        }
    };
    let rglb = d.path().join("r.glb");
    let s = resample(&boxp, &rglb, &Opts::new(GridSize::CellSize(0.25)), &NoProgress).unwrap();
    on_box(&load(&rglb), 0.01 * s.cell_size, "resampled to GLB");
    let (dply, dglb) = (d.path().join("d.ply"), d.path().join("d.glb"));
    for out in [&dply, &dglb] {
        let o = mint(&["decimate".as_ref(), os(&boxp).as_os_str(), os(out).as_os_str(), "--faces".as_ref(), "500".as_ref(), "--quiet".as_ref()]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let (p, q) = (load(&dply), load(&dglb));
    assert_eq!(p.faces, q.faces);
    let worst = p.positions.iter().zip(&q.positions).map(|(a, b)| (0..3).map(|k| (a[k] - b[k]).abs()).fold(0.0, f64::max)).fold(0.0, f64::max);
    assert!(worst <= 0.01 * 0.25, "decimated to GLB: a vertex moved by {worst}");
    on_box(&q, 0.01, "decimated to GLB");
    let (gltf, back) = (d.path().join("c.gltf"), d.path().join("back.ply"));
    for (from, to) in [(&dply, &gltf), (&gltf, &back)] {
        let o = mint(&["convert".as_ref(), os(from).as_os_str(), os(to).as_os_str()]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    assert!(d.path().join("c.bin").is_file(), ".gltf writes its buffer beside it");
    let r = load(&back);
    assert_eq!(r.faces, p.faces);
    let worst = p.positions.iter().zip(&r.positions).map(|(a, b)| (0..3).map(|k| (a[k] - b[k]).abs()).fold(0.0, f64::max)).fold(0.0, f64::max);
    assert!(worst <= 1e-5, "PLY -> glTF -> PLY moved a vertex by {worst}");
    // What glTF cannot hold: one line each, nothing written.
    let o = mint(&["resample".as_ref(), os(&boxp).as_os_str(), os(&d.path().join("x.glb")).as_os_str(), "--cells".as_ref(), "1000".as_ref(), "--double".as_ref()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.lines().count() == 1 && err.contains("--double cannot apply"), "{err}");
    let scene = d.path().join("tiny.json");
    std::fs::write(&scene, r#"{"sphere": {"radius": 1e-100}}"#).unwrap();
    let o = mint(&["csg".as_ref(), os(&scene).as_os_str(), os(&d.path().join("t.glb")).as_os_str(), "--cells".as_ref(), "20000".as_ref()]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.lines().count() == 1 && err.contains("glTF stores f32 positions") && err.contains(".ply"), "{err}");
    assert!(!d.path().join("x.glb").exists() && !d.path().join("t.glb").exists());
}
