//! Booleans and CSG on intersection lists (issue 5): analytic volumes and
//! their convergence, mesh booleans' algebra, primitives against meshes,
//! and bad scenes.

use crate::common::{load, write_mesh};
use mint_core::expr::BoolOp;
use mint_core::{GridSize, TriMesh};
use crate::common::{boolean, csg, resample, Opts};
use mint_pipeline::{parse_scene, NoProgress};
use mint_testkit::topology::check_closed_oriented;
use std::path::Path;

fn opts(cells: u64) -> Opts {
    Opts::new(GridSize::Cells(cells))
}

/// Meshes a scene given as text; returns the output mesh's volume.
fn scene_volume(dir: &Path, text: &str, cells: u64) -> (f64, TriMesh) {
    let path = dir.join("scene.json");
    std::fs::write(&path, text).unwrap();
    let scene = parse_scene(text, &path).unwrap();
    let out = dir.join("out.ply");
    csg(&scene, "scene", &out, &opts(cells), &NoProgress).unwrap();
    let m = load(&out);
    let st = check_closed_oriented(&m).unwrap_or_else(|e| panic!("{text}: {e}"));
    (st.volume, m)
}

/// Volume of {p : inside(p)} in a box, by midpoint sampling on an n³ grid.
fn sampled_volume(lo: [f64; 3], hi: [f64; 3], n: usize, inside: impl Fn([f64; 3]) -> bool) -> f64 {
    let h = [0, 1, 2].map(|d| (hi[d] - lo[d]) / n as f64);
    let mut count = 0u64;
    for i in 0..n {
        for j in 0..n {
            for k in 0..n {
                let p = [lo[0] + (i as f64 + 0.5) * h[0], lo[1] + (j as f64 + 0.5) * h[1], lo[2] + (k as f64 + 0.5) * h[2]];
                count += inside(p) as u64;
            }
        }
    }
    count as f64 * h[0] * h[1] * h[2]
}

#[test]
fn sphere_and_box_booleans_converge_to_their_analytic_volumes() {
    let d = tempfile::tempdir().unwrap();
    // The paper's Figure 5: a box and a sphere overlapping. |box ∩ ball| by
    // integrating column lengths 2·min(0.8, √(1 − x² − y²)) over the square.
    let n = 2000;
    let h = 1.6 / n as f64;
    let mut inter = 0.0;
    for i in 0..n {
        for j in 0..n {
            let (x, y) = (-0.8 + (i as f64 + 0.5) * h, -0.8 + (j as f64 + 0.5) * h);
            let r = 1.0 - x * x - y * y;
            if r > 0.0 {
                inter += 2.0 * r.sqrt().min(0.8);
            }
        }
    }
    inter *= h * h;
    let (cube, ball) = (1.6f64.powi(3), 4.0 / 3.0 * std::f64::consts::PI);
    for (op, sym, exact) in [("intersection", "∩", inter), ("union", "∪", cube + ball - inter), ("difference", "−", cube - inter)] {
        let text = format!(r#"{{ "{op}": [ {{ "box": {{ "size": [1.6, 1.6, 1.6] }} }}, {{ "sphere": {{ "radius": 1.0 }} }} ] }}"#);
        let errs: Vec<f64> = [20_000u64, 300_000].iter().map(|&c| (scene_volume(d.path(), &text, c).0 - exact).abs() / exact).collect();
        assert!(errs[1] < errs[0], "box {sym} sphere: error does not shrink: {errs:?}");
        assert!(errs[1] < 0.015, "box {sym} sphere: relative volume error {}", errs[1]);
    }
}

#[test]
fn a_tree_of_seven_primitives_is_watertight_and_converges() {
    let d = tempfile::tempdir().unwrap();
    let text = r#"{ "union": [
      { "difference": [ { "box": { "size": [2, 2, 2] }, "rotate": [0, 0, 30] }, { "cylinder": { "radius": 0.5, "height": 3 } } ] },
      { "intersection": [ { "sphere": { "radius": 1.3 }, "translate": [0, 0, 1.2] }, { "cone": { "radius": 1.0, "height": 2.5 } } ] },
      { "torus": { "major": 1.4, "minor": 0.2 }, "rotate": [90, 0, 0] },
      { "intersection": [ { "halfspace": { "normal": [0, 0, -1], "offset": 1.0 } }, { "sphere": { "radius": 0.4 }, "translate": [0, 0, -1.0] } ] } ] }"#;
    let (s30, c30) = ((30f64).to_radians().sin(), (30f64).to_radians().cos());
    let inside = |p: [f64; 3]| {
        // Box rotated 30° about z: rotate p by −30°.
        let q = [c30 * p[0] + s30 * p[1], -s30 * p[0] + c30 * p[1], p[2]];
        let boxed = q.iter().all(|x| x.abs() <= 1.0) && !(p[0] * p[0] + p[1] * p[1] <= 0.25 && p[2].abs() <= 1.5);
        let s = [p[0], p[1], p[2] - 1.2];
        let cone = p[2] >= 0.0 && p[2] <= 2.5 && (p[0] * p[0] + p[1] * p[1]).sqrt() <= (2.5 - p[2]) / 2.5;
        let capped = s[0] * s[0] + s[1] * s[1] + s[2] * s[2] <= 1.69 && cone;
        // Torus rotated 90° about x: its axis is y.
        let rho = (p[0] * p[0] + p[2] * p[2]).sqrt();
        let torus = (rho - 1.4).powi(2) + p[1] * p[1] <= 0.04;
        let b = [p[0], p[1], p[2] + 1.0];
        let half_ball = b[0] * b[0] + b[1] * b[1] + b[2] * b[2] <= 0.16 && p[2] >= -1.0;
        boxed || capped || torus || half_ball
    };
    let exact = sampled_volume([-1.7, -1.7, -1.7], [1.7, 1.7, 2.6], 320, inside);
    let errs: Vec<f64> = [30_000u64, 400_000].iter().map(|&c| (scene_volume(d.path(), text, c).0 - exact).abs() / exact).collect();
    assert!(errs[1] < errs[0] && errs[1] < 0.03, "relative volume errors {errs:?}");
}

#[test]
fn mesh_booleans_obey_the_algebra() {
    let d = tempfile::tempdir().unwrap();
    let a = write_mesh(d.path(), "a.ply", |s| drop(mint_gen::torus([0.0; 3], 1.0, 0.35, 30_000, s).unwrap()));
    let b = write_mesh(d.path(), "b.ply", |s| drop(mint_gen::sphere([0.8, 0.0, 0.2], 0.7, 30_000, s).unwrap()));
    let o = opts(60_000);
    // A ∪ A and A ∩ A are A, byte for byte; A − A is empty.
    let ra = d.path().join("ra.ply");
    resample(&a, &ra, &o, &NoProgress).unwrap();
    let want = std::fs::read(&ra).unwrap();
    for op in [BoolOp::Union, BoolOp::Intersection] {
        let out = d.path().join("aa.ply");
        boolean(op, &a, &a, &out, &o, &NoProgress).unwrap();
        assert!(std::fs::read(&out).unwrap() == want, "A {op:?} A differs from resampling A");
    }
    let out = d.path().join("empty.ply");
    let s = boolean(BoolOp::Difference, &a, &a, &out, &o, &NoProgress).unwrap();
    assert_eq!(s.output_faces, 0);
    // |A ∪ B| = |A| + |B| − |A ∩ B|, on one grid (the union's box contains both).
    let vol = |op: BoolOp| {
        let out = d.path().join("v.ply");
        boolean(op, &a, &b, &out, &o, &NoProgress).unwrap();
        check_closed_oriented(&load(&out)).unwrap().volume
    };
    let (u, i, diff) = (vol(BoolOp::Union), vol(BoolOp::Intersection), vol(BoolOp::Difference));
    let va = 2.0 * std::f64::consts::PI.powi(2) * 1.0 * 0.35 * 0.35;
    let vb = 4.0 / 3.0 * std::f64::consts::PI * 0.7f64.powi(3);
    assert!(((u + i) - (va + vb)).abs() < 0.03 * (va + vb), "|A∪B| + |A∩B| = {} vs |A| + |B| = {}", u + i, va + vb);
    assert!(((diff + i) - va).abs() < 0.03 * va, "|A−B| + |A∩B| = {} vs |A| = {va}", diff + i);
}

#[test]
fn a_primitive_and_a_mesh_of_it_agree_within_a_cell() {
    let d = tempfile::tempdir().unwrap();
    let mesh = write_mesh(d.path(), "t.ply", |s| drop(mint_gen::torus([0.0; 3], 1.0, 0.35, 200_000, s).unwrap()));
    let from_mesh = d.path().join("m.ply");
    let s = resample(&mesh, &from_mesh, &opts(100_000), &NoProgress).unwrap();
    let (_, prim) = scene_volume(d.path(), r#"{ "torus": { "major": 1.0, "minor": 0.35 } }"#, 100_000);
    let m = load(&from_mesh);
    let diag = s.cell_size * 3f64.sqrt();
    let (ab, ba) = mint_mesh::symmetric_distance((&prim.positions, &prim.faces), (&m.positions, &m.faces), 30_000, 2);
    assert!(ab.max <= diag && ba.max <= diag, "max distances {} {} vs cell diagonal {diag}", ab.max, ba.max);
}
