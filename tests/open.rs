//! Open inputs (issue 28): a terrain tile, a bowl, a lone triangle and a
//! soup of loose triangles enclose no volume. `--signs auto` reads them as
//! sheets: the output is the input resampled as an open surface with its
//! faces' orientation (never a solid, whatever the sign of the volume it
//! happens to sweep), its boundary within two cells of the input's, and the
//! same bytes for any slab split; closed inputs are not affected.

use crate::common::{load, resample, write_trimesh, Opts};
use mint_core::{GridSize, TriMesh};
use mint_pipeline::{NoProgress, SlabAxis};

/// z = f(x, y) over the unit square, `n` × `n` quads; normals up, or down
/// when `down`.
fn terrain(n: u32, down: bool) -> TriMesh {
    let mut m = TriMesh::default();
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
            m.positions.push([x, y, height(x, y)]);
        }
    }
    for j in 0..n {
        for i in 0..n {
            let a = j * (n + 1) + i;
            let (b, c, d) = (a + 1, a + n + 1, a + n + 2);
            for f in [[a, b, d], [a, d, c]] {
                m.faces.push(if down { [f[0], f[2], f[1]] } else { f });
            }
        }
    }
    m
}

fn height(x: f64, y: f64) -> f64 {
    0.1 * (6.0 * x).sin() * (5.0 * y).cos()
}

fn normal(m: &TriMesh, f: [u32; 3]) -> [f64; 3] {
    let [a, b, c] = f.map(|i| m.positions[i as usize]);
    let (u, v) = ([b[0] - a[0], b[1] - a[1], b[2] - a[2]], [c[0] - a[0], c[1] - a[1], c[2] - a[2]]);
    [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
}

/// Vertices on edges that only one face uses.
fn boundary_vertices(faces: &[[u32; 3]]) -> Vec<u32> {
    let mut edges: Vec<(u32, u32)> = faces.iter().flat_map(|f| [(f[0], f[1]), (f[1], f[2]), (f[2], f[0])]).map(|(a, b)| (a.min(b), a.max(b))).collect();
    edges.sort_unstable();
    let mut out = Vec::new();
    let mut k = 0;
    while k < edges.len() {
        let mut e = k;
        while e + 1 < edges.len() && edges[e + 1] == edges[k] {
            e += 1;
        }
        if e == k {
            out.extend([edges[k].0, edges[k].1]);
        }
        k = e + 1;
    }
    out.sort_unstable();
    out.dedup();
    out
}

/// Checks what every open output must be: 2-manifold, consistently
/// oriented, no closed component, no degenerate face.
fn assert_open_manifold(m: &TriMesh, what: &str) -> mint_mesh::CheckReport {
    let r = mint_mesh::check(&m.positions, &m.faces);
    assert!(r.faces > 0, "{what}: empty");
    assert_eq!((r.non_manifold_edges, r.non_manifold_vertices, r.inconsistently_oriented_edges), (0, 0, 0), "{what}: {r:?}");
    assert_eq!(r.closed_components, 0, "{what}: a solid came out of an open input: {r:?}");
    assert_eq!((r.degenerate_faces, r.duplicate_faces), (0, 0), "{what}: {r:?}");
    r
}

#[test]
fn a_terrain_tile_stays_an_open_sheet_facing_the_way_its_faces_do() {
    let d = tempfile::tempdir().unwrap();
    for down in [false, true] {
        let input = write_trimesh(d.path(), &format!("terrain-{down}.ply"), &terrain(40, down));
        let out = d.path().join(format!("out-{down}.ply"));
        let s = resample(&input, &out, &Opts::new(GridSize::Cells(200_000)), &NoProgress).unwrap();
        assert_eq!((s.sign_rule.as_str(), s.orientation_from.as_str(), s.orientation_inverted), ("sheet", "faces", false));
        let m = load(&out);
        let r = assert_open_manifold(&m, "terrain");
        assert_eq!((r.components, r.boundary_loops), (1, 1), "one sheet with one rim: {r:?}");
        let h = s.cell_size;
        // On the input: every vertex within a cell of the height field.
        for p in &m.positions {
            assert!((p[2] - height(p[0], p[1])).abs() <= h, "vertex {p:?} is off the terrain");
        }
        // Facing the input's way: the area whose normal points up (down).
        let (mut agree, mut total) = (0.0, 0.0);
        for f in &m.faces {
            let n = normal(&m, *f);
            let a = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            total += a;
            if (n[2] > 0.0) != down {
                agree += a;
            }
        }
        assert!(agree >= 0.999 * total, "down={down}: only {:.4} of the area faces the input's way", agree / total);
        // The rim: every boundary vertex within two cells of the square's border.
        let rim = boundary_vertices(&m.faces);
        assert!(!rim.is_empty());
        for v in rim {
            let p = m.positions[v as usize];
            let dist = p[0].min(1.0 - p[0]).min(p[1]).min(1.0 - p[1]).abs();
            assert!(dist <= 2.0 * h, "boundary vertex {p:?} is {:.2} cells from the input's boundary", dist / h);
        }
        // Area close to the input's (the rim recedes by at most about a cell).
        let area = r.surface_area;
        let input_area = mint_mesh::check(&terrain(40, down).positions, &terrain(40, down).faces).surface_area;
        assert!(area < input_area && area > input_area * (1.0 - 8.0 * h), "area {area} against the input's {input_area}");
    }
}

#[test]
fn a_sheet_gives_the_same_bytes_for_any_slab_split() {
    // The sheet rule reads the layer below each plane: slabs must agree on it.
    let d = tempfile::tempdir().unwrap();
    let reference = d.path().join("ref.ply");
    let o = Opts::new(GridSize::Cells(150_000));
    let terrain = write_trimesh(d.path(), "t.ply", &terrain(30, false));
    let fan = write_trimesh(d.path(), "fan.ply", &fan());
    for (input, axis, parts, slabs, layers) in
        [(&terrain, 0, 1, 3, Some(2)), (&terrain, 1, 3, 7, Some(1)), (&terrain, 2, 2, 2, None), (&terrain, 2, 3, 5, Some(1)), (&fan, 2, 2, 5, Some(1)), (&fan, 0, 3, 4, Some(3))]
    {
        // Slabs along z cut the terrain's faces across: every plane's
        // states then depend on the S intercepts of the layer below.
        let axis = [SlabAxis::X, SlabAxis::Y, SlabAxis::Z][axis];
        let o = o.with(|o| o.spec.grid.axis = axis);
        resample(input, &reference, &o, &NoProgress).unwrap();
        let want = std::fs::read(&reference).unwrap();
        let out = d.path().join(format!("p{parts}-{slabs}.ply"));
        let o = o.with(|o| {
            o.tuning.parts = parts;
            o.tuning.slabs = slabs;
            o.tuning.slab_layers = layers;
            o.tuning.threads = 2;
        });
        resample(input, &out, &o, &NoProgress).unwrap();
        assert!(std::fs::read(&out).unwrap() == want, "{input:?} {axis:?}: {parts} parts, {slabs} slabs, {layers:?} layers: bytes differ");
    }
}

/// Three faces meeting at a corner (an open box corner).
fn fan() -> TriMesh {
    TriMesh { positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], faces: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2]] }
}

#[test]
fn nothing_from_nothing_a_lone_triangle_a_fan_and_a_soup_stay_open() {
    let d = tempfile::tempdir().unwrap();
    let tri = TriMesh { positions: vec![[0.0, 0.0, 0.0], [1.0, 0.1, 0.2], [0.3, 1.0, 0.4]], faces: vec![[0, 1, 2]] };
    let fan = fan();
    // 100 loose triangles, random positions and orientations.
    let mut soup = TriMesh::default();
    let mut rng = mint_core::rng::SplitMix64::new(5);
    for t in 0..100u32 {
        let c = [rng.next_f64(), rng.next_f64(), rng.next_f64()];
        for _ in 0..3 {
            soup.positions.push([c[0] + 0.2 * rng.next_f64(), c[1] + 0.2 * rng.next_f64(), c[2] + 0.2 * rng.next_f64()]);
        }
        soup.faces.push([3 * t, 3 * t + 1, 3 * t + 2]);
    }
    for (name, m) in [("triangle", &tri), ("fan", &fan), ("soup", &soup)] {
        let input = write_trimesh(d.path(), &format!("{name}.ply"), m);
        let out = d.path().join(format!("{name}-out.ply"));
        let s = resample(&input, &out, &Opts::new(GridSize::Cells(100_000)), &NoProgress).unwrap();
        assert_eq!(s.sign_rule, "sheet", "{name}");
        let got = load(&out);
        let r = assert_open_manifold(&got, name);
        let input_area = mint_mesh::check(&m.positions, &m.faces).surface_area;
        // Nothing is added: at most the input's area, and a volume no
        // larger than that area swept by a cell.
        assert!(r.surface_area <= input_area * 1.001, "{name}: area {} > the input's {input_area}", r.surface_area);
        assert!(r.signed_volume.abs() <= input_area * s.cell_size, "{name}: encloses {}", r.signed_volume);
        if name != "soup" {
            assert_eq!(r.components, 1, "{name}: {r:?}");
            assert!(r.surface_area >= 0.8 * input_area, "{name}: area {} of {input_area}", r.surface_area);
        }
    }
    // A triangle smaller than a cell: nothing at all, and the summary says so.
    let small = TriMesh { positions: vec![[0.0, 0.0, 0.0], [10.0, 0.0, 0.0], [0.0, 10.0, 0.0], [0.01, 0.01, 3.0], [0.012, 0.01, 3.0], [0.01, 0.012, 3.0]], faces: vec![[3, 4, 5]] };
    let input = write_trimesh(d.path(), "small.ply", &small);
    let out = d.path().join("small-out.ply");
    let s = resample(&input, &out, &Opts::new(GridSize::Cells(1000)), &NoProgress).unwrap();
    assert_eq!(s.output_faces, 0);
    assert!(s.empty_reason().is_some());
}

#[test]
fn closed_inputs_are_still_solids_and_signs_sheet_can_be_asked_for() {
    let d = tempfile::tempdir().unwrap();
    let mut sphere = TriMesh::default();
    mint_gen::sphere([0.0; 3], 1.0, 20_000, &mut sphere).unwrap();
    let input = write_trimesh(d.path(), "s.ply", &sphere);
    let out = d.path().join("s-out.ply");
    let s = resample(&input, &out, &Opts::new(GridSize::Cells(100_000)), &NoProgress).unwrap();
    assert_eq!((s.sign_rule.as_str(), s.orientation_from.as_str()), ("union", "volume"));
    assert!(mint_mesh::check(&load(&out).positions, &load(&out).faces).watertight);
    // A terrain asked to be a solid closes (the old behaviour, on request).
    let input = write_trimesh(d.path(), "t.ply", &terrain(20, false));
    let o = Opts::new(GridSize::Cells(50_000)).with(|o| o.spec.signs = mint_core::signs::SignRule::Union);
    let s = resample(&input, &out, &o, &NoProgress).unwrap();
    assert_eq!(s.sign_rule, "union");
}

/// `mint decimate` of an open input: an open sheet, decimated, its
/// boundary kept, and the resampling's warning (naming `mint resample
/// --signs union`, since decimate has no `--signs`).
#[test]
fn decimate_keeps_an_open_sheet_open_and_says_so() {
    let d = tempfile::tempdir().unwrap();
    let input = write_trimesh(d.path(), "t.ply", &terrain(40, false));
    let out = d.path().join("d.ply");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_mint")).arg("decimate").arg(&input).arg(&out).args(["--faces", "1500", "--json", "--route", "resample"]).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert_eq!(err.matches("the input is open").count(), 1, "{err}");
    assert!(err.contains("`mint resample --signs union` closes it"), "{err}");
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["warnings"].as_array().unwrap().len(), 1, "{j}");
    let m = load(&out);
    let r = assert_open_manifold(&m, "decimated terrain");
    assert_eq!((r.components, r.boundary_loops), (1, 1), "{r:?}");
    assert!((m.faces.len() as f64 - 1500.0).abs() <= 30.0, "{} faces", m.faces.len());
    // By default a clean open sheet is simplified itself, its boundary
    // loop kept where it was (no resampling, so no sheet warning).
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_mint")).arg("decimate").arg(&input).arg(&out).args(["--faces", "1500", "--json"]).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["route"].as_str(), Some("direct"), "{j}");
    assert!(j["output_faces"].as_u64().unwrap().abs_diff(1500) <= 30, "{j}");
    assert!(j["route_reason"].as_str().unwrap().contains("open along 1 boundary loop"), "{j}");
    let r = assert_open_manifold(&load(&out), "decimated terrain, direct");
    assert_eq!((r.components, r.boundary_loops), (1, 1), "{r:?}");
}
