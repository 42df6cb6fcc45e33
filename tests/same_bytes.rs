//! One same-bytes harness for every deterministic command: each runs once
//! as a reference, then under other thread counts, slab sizes, memory
//! budgets and splits into parts and slabs, and every output must be the
//! reference byte for byte.

use std::path::Path;
use std::process::Command;

fn mint() -> Command {
    Command::new(env!("CARGO_BIN_EXE_mint"))
}

fn p(path: &Path) -> String {
    path.display().to_string()
}

/// Runs `args` (with `OUT` replaced by an output path) once per variant:
/// extra arguments and environment. All outputs must equal the first.
fn same_bytes(dir: &Path, name: &str, args: &[String], variants: &[(&[&str], &[(&str, &str)])]) {
    let mut want: Option<Vec<u8>> = None;
    for (i, (extra, env)) in variants.iter().enumerate() {
        let out = dir.join(format!("{name}-{i}.ply"));
        let mut c = mint();
        for a in args {
            c.arg(if a == "OUT" { p(&out) } else { a.clone() });
        }
        c.args(*extra);
        for (k, v) in *env {
            c.env(k, v);
        }
        let o = c.output().unwrap();
        assert!(o.status.success(), "{name} {extra:?} {env:?}: {}", String::from_utf8_lossy(&o.stderr));
        let got = std::fs::read(&out).unwrap();
        match &want {
            None => want = Some(got),
            Some(w) => assert!(&got == w, "{name}: {extra:?} {env:?} gives other bytes than {:?}", variants[0]),
        }
    }
}

fn run(args: &[&str]) {
    let o = mint().args(args).output().unwrap();
    assert!(o.status.success(), "mint {args:?}: {}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn every_deterministic_command_gives_the_same_bytes_under_every_configuration() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    let scan = dir.join("scan.ply");
    run(&["gen", "scan", &p(&scan), "--faces", "150000"]);
    let torus = dir.join("torus.ply");
    run(&["gen", "torus", &p(&torus), "--faces", "60000"]);
    let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<String>>();
    let w = |n: &str| p(&dir.join(n));
    // resample: threads, sub-slab size, memory budget, parts and slabs.
    let work = w("work-r");
    same_bytes(
        dir,
        "resample",
        &s(&["resample", &p(&scan), "OUT", "--cells", "200000", "--quiet"]),
        &[
            (&["--threads", "1"], &[]),
            (&["--threads", "2"], &[]),
            // The baseline x86-64 compilation of the per-triangle loop
            // instead of the AVX2 one (the same on CPUs without AVX2).
            (&[], &[("MINT_NO_AVX2", "1")]),
            (&["--slab", "3"], &[]),
            (&["--mem", "50M", "--threads", "2"], &[]),
            (&["--parts", "3", "--slabs", "4", "--work", &work], &[]),
        ],
    );
    // Colour carried (binary PLY and text OBJ inputs, PLY and OBJ outputs).
    let cscan = dir.join("cscan.ply");
    run(&["gen", "scan", &p(&cscan), "--faces", "100000", "--color"]);
    let cobj = dir.join("ctorus.obj");
    run(&["gen", "torus", &p(&cobj), "--faces", "40000", "--color"]);
    let work = w("work-c");
    same_bytes(
        dir,
        "resample-colour",
        &s(&["resample", &p(&cscan), "OUT", "--cells", "150000", "--quiet"]),
        &[
            (&["--threads", "1"], &[]),
            (&["--threads", "2"], &[]),
            (&["--slab", "2"], &[]),
            (&["--mem", "40M", "--threads", "2"], &[]),
            (&["--parts", "3", "--slabs", "4", "--work", &work], &[]),
        ],
    );
    same_bytes(
        dir,
        "bool-colour",
        &s(&["bool", "union", &p(&cobj), &p(&torus), "OUT", "--cells", "80000", "--quiet"]),
        &[(&["--threads", "1"], &[]), (&["--threads", "2", "--slab", "1"], &[]), (&["--parts", "2", "--slabs", "3"], &[])],
    );
    // bool and csg.
    same_bytes(
        dir,
        "bool",
        &s(&["bool", "difference", &p(&scan), &p(&torus), "OUT", "--cells", "100000", "--quiet"]),
        &[(&["--threads", "1"], &[]), (&["--threads", "2", "--slab", "2"], &[]), (&["--parts", "2", "--slabs", "3"], &[])],
    );
    let scene = dir.join("scene.json");
    std::fs::write(&scene, r#"{ "union": [ { "mesh": "torus.ply" }, { "difference": [ { "box": { "size": [1, 1, 1] } }, { "sphere": { "radius": 0.6 } } ] } ] }"#).unwrap();
    same_bytes(
        dir,
        "csg",
        &s(&["csg", &p(&scene), "OUT", "--cells", "100000", "--quiet"]),
        &[(&["--threads", "1"], &[]), (&["--threads", "2", "--slab", "1"], &[]), (&["--parts", "2", "--slabs", "5"], &[])],
    );
    // contours, both methods (rayon-parallel parts run on 1 and 2 threads).
    let pro = dir.join("torus.pro");
    run(&["slice", &p(&torus), &p(&pro), "--sections", "30"]);
    for method in ["mc", "angle"] {
        same_bytes(
            dir,
            &format!("contours-{method}"),
            &s(&["contours", &p(&pro), "OUT", "--method", method, "--caps", "--quiet"]),
            &[(&[], &[("RAYON_NUM_THREADS", "1")]), (&[], &[("RAYON_NUM_THREADS", "2")])],
        );
    }
    // zipper and the grid merge: threads and the scan budget.
    let scans = dir.join("scans");
    run(&["scan", &p(&torus), &p(&scans), "--views", "6", "--noise", "0.002"]);
    let conf = p(&scans.join("scans.conf"));
    same_bytes(
        dir,
        "zipper",
        &s(&["zipper", &conf, "OUT"]),
        &[(&[], &[("RAYON_NUM_THREADS", "1")]), (&[], &[("RAYON_NUM_THREADS", "2")]), (&["--mem", "1"], &[("RAYON_NUM_THREADS", "2")])],
    );
    same_bytes(
        dir,
        "zipper-grid",
        &s(&["zipper", &conf, "OUT", "--method", "grid", "--cells", "100000"]),
        &[(&[], &[("RAYON_NUM_THREADS", "1")]), (&[], &[("RAYON_NUM_THREADS", "2")]), (&["--mem", "1"], &[("RAYON_NUM_THREADS", "2")])],
    );
}
