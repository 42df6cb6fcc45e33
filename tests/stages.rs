//! The staged engine (issue 11): a run split into tasks, run in any order,
//! by separate processes, killed and resumed, gives the bytes of one
//! process; and every way a work directory can be wrong gives one line.

use crate::common::{box_mesh, write_mesh, write_trimesh};
use mint_core::expr::BoolOp;
use mint_core::GridSize;
use mint_pipeline::engine::{plan_run, run_task, TaskOptions, TaskOutcome};
use crate::common::{boolean, csg, resample, Opts};
use mint_pipeline::{parse_scene, Job, NoProgress, Plan};
use std::path::{Path, PathBuf};

fn opts(cells: u64) -> Opts {
    Opts::new(GridSize::Cells(cells)).with(|o| o.tuning.threads = 2)
}

fn mint_bin() -> PathBuf {
    PathBuf::from(env!("CARGO_BIN_EXE_mint"))
}

/// A small SplitMix64 for task orders and kill times.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn shuffle<T>(&mut self, v: &mut [T]) {
        for i in (1..v.len()).rev() {
            v.swap(i, (self.next() % (i as u64 + 1)) as usize);
        }
    }
}

#[derive(Clone, Copy, Debug)]
enum Order {
    Forward,
    Reverse,
    Shuffled(u64),
}

/// Runs every task of the plan in `dir`, stage by stage, each stage's
/// tasks in `order`.
fn run_all_tasks(dir: &Path, order: Order) {
    let plan = Plan::load(dir).unwrap();
    for st in &plan.stages {
        let mut tasks: Vec<u32> = (0..st.tasks).collect();
        match order {
            Order::Forward => {}
            Order::Reverse => tasks.reverse(),
            Order::Shuffled(seed) => Rng(seed ^ st.tasks as u64).shuffle(&mut tasks),
        }
        for t in tasks {
            let topts = TaskOptions { threads: Some(1 + (t as usize % 2)), mem_bytes: None, deref: Some(if t % 3 == 1 { mint_pipeline::Deref::Sort } else { mint_pipeline::Deref::Auto }) };
            let o = run_task(dir, st.name, t, &topts, &NoProgress)
                .unwrap_or_else(|e| panic!("{} {t}: {e}", st.name));
            assert_eq!(o, TaskOutcome::Ran);
        }
    }
}

/// Plans `job` into a fresh directory with `parts` and `slabs`, runs it task
/// by task in `order`, and returns the output bytes.
fn staged_bytes(root: &Path, name: &str, job: Job, o: &Opts, parts: u32, slabs: u32, order: Order) -> Vec<u8> {
    let dir = root.join(format!("work-{name}"));
    let out = root.join(format!("{name}.ply"));
    let o = o.clone().with(|o| { o.tuning.parts = parts; o.tuning.slabs = slabs; });
    plan_run(&o.spec(job, &out), None, &o.tuning, &dir).unwrap();
    run_all_tasks(&dir, order);
    // Every task again: all no-ops, output unchanged.
    let plan = Plan::load(&dir).unwrap();
    for st in &plan.stages {
        for t in 0..st.tasks {
            assert_eq!(run_task(&dir, st.name, t, &TaskOptions::default(), &NoProgress).unwrap(), TaskOutcome::AlreadyDone);
        }
    }
    std::fs::read(&out).unwrap()
}

#[test]
fn staged_resample_equals_one_process_for_any_parts_slabs_and_task_order() {
    let d = tempfile::tempdir().unwrap();
    let input = write_mesh(d.path(), "g.ply", |s| drop(mint_gen::genus(2, 300_000, s).unwrap()));
    let reference = d.path().join("ref.ply");
    resample(&input, &reference, &opts(60_000), &NoProgress).unwrap();
    let want = std::fs::read(&reference).unwrap();
    let job = || Job::Resample { inputs: vec![input.clone()] };
    for (i, (parts, slabs, order)) in
        [(1, 1, Order::Forward), (3, 4, Order::Reverse), (5, 2, Order::Shuffled(7)), (2, 9, Order::Shuffled(11)), (7, 40, Order::Reverse)].into_iter().enumerate()
    {
        let got = staged_bytes(d.path(), &format!("r{i}"), job(), &opts(60_000), parts, slabs, order);
        assert!(got == want, "{parts} parts, {slabs} slabs, {order:?}: output bytes differ");
    }
    // The strict rule is a variant of the same stages.
    let strict = opts(60_000).with(|o| { o.spec.signs = mint_core::signs::SignRule::Orient; });
    resample(&input, &reference, &strict, &NoProgress).unwrap();
    let want = std::fs::read(&reference).unwrap();
    let got = staged_bytes(d.path(), "strict", job(), &strict, 4, 3, Order::Shuffled(3));
    assert!(got == want, "strict: output bytes differ");
}

#[test]
fn staged_bool_and_csg_equal_one_process() {
    let d = tempfile::tempdir().unwrap();
    let a = write_mesh(d.path(), "a.ply", |s| drop(mint_gen::genus(1, 100_000, s).unwrap()));
    let b = write_trimesh(d.path(), "b.ply", &box_mesh([-0.2, -0.3, -0.4], [0.9, 0.8, 0.7]));
    let reference = d.path().join("ref.ply");
    boolean(BoolOp::Difference, &a, &b, &reference, &opts(50_000), &NoProgress).unwrap();
    let want = std::fs::read(&reference).unwrap();
    let job = Job::Bool { op: BoolOp::Difference, a: vec![a.clone()], b: vec![b.clone()], iso_a: None, iso_b: None };
    let o = opts(50_000).with(|o| { o.spec.max_hole = None; });
    let got = staged_bytes(d.path(), "bool", job, &o, 3, 5, Order::Shuffled(5));
    assert!(got == want, "bool: output bytes differ");

    let scene_path = d.path().join("scene.json");
    let text = r#"{ "union": [ { "difference": [ { "box": { "size": [2, 2, 2] }, "rotate": [0, 0, 30] }, { "sphere": { "radius": 1.2 } } ] },
                              { "mesh": "a.ply", "scale": 0.5, "translate": [0.3, 0, 0] } ] }"#;
    std::fs::write(&scene_path, text).unwrap();
    let scene = parse_scene(text, &scene_path).unwrap();
    csg(&scene, &scene_path.display().to_string(), &reference, &opts(50_000), &NoProgress).unwrap();
    let want = std::fs::read(&reference).unwrap();
    let got = staged_bytes(d.path(), "csg", Job::Csg { scene: scene_path.clone() }, &o, 2, 4, Order::Reverse);
    assert!(got == want, "csg: output bytes differ");
}

#[test]
fn parts_split_binary_stl_too_and_read_text_files_whole() {
    let d = tempfile::tempdir().unwrap();
    let ply = write_mesh(d.path(), "g.ply", |s| drop(mint_gen::genus(3, 150_000, s).unwrap()));
    let reference = d.path().join("ref.ply");
    resample(&ply, &reference, &opts(40_000), &NoProgress).unwrap();
    let want = std::fs::read(&reference).unwrap();
    for ext in ["stl", "obj"] {
        let other = d.path().join(format!("g.{ext}"));
        mint_io::convert(&ply, &other, Default::default(), Default::default(), &mut |_, _| {}).unwrap();
        let plain = d.path().join(format!("plain-{ext}.ply"));
        resample(&other, &plain, &opts(40_000), &NoProgress).unwrap();
        let want_other = std::fs::read(&plain).unwrap();
        let o = opts(40_000).with(|o| { o.tuning.parts = 4; o.tuning.slabs = 3; o.tuning.work_dir = Some(d.path().join(format!("w-{ext}"))); });
        let out = d.path().join(format!("parts-{ext}.ply"));
        resample(&other, &out, &o, &NoProgress).unwrap();
        assert!(std::fs::read(&out).unwrap() == want_other, "{ext}: 4 parts differ from 1");
        if ext == "stl" {
            // An STL soup has other vertex ids but the same f32 positions:
            // the same grid, crossings and output as the PLY.
            assert!(want_other == want, "stl and ply outputs differ");
        }
    }
}

#[test]
fn a_run_killed_at_random_moments_resumes_to_the_same_bytes() {
    let d = tempfile::tempdir().unwrap();
    let input = d.path().join("s.ply");
    let st = std::process::Command::new(mint_bin()).args(["gen", "sphere"]).arg(&input).args(["--faces", "2000000"]).output().unwrap();
    assert!(st.status.success());
    let reference = d.path().join("ref.ply");
    let args = |out: &Path, work: Option<&Path>| {
        let mut c = std::process::Command::new(mint_bin());
        c.arg("resample").arg(&input).arg(out).args(["--cells", "4000000", "--quiet", "--threads", "2"]);
        if let Some(w) = work {
            c.arg("--work").arg(w).args(["--parts", "6", "--slabs", "6"]);
        }
        c
    };
    let t = std::time::Instant::now();
    assert!(args(&reference, None).status().unwrap().success());
    let full = t.elapsed().as_secs_f64();
    let want = std::fs::read(&reference).unwrap();
    let mut rng = Rng(2026);
    let mut round = 0;
    let mut tries = 0;
    while round < 3 {
        let work = d.path().join(format!("w{round}-{tries}"));
        let out = d.path().join(format!("o{round}-{tries}.ply"));
        let mut kills = 0;
        // Earlier moments on each retry: a busy machine can make the runs
        // that resume much faster than the reference was.
        let span = full * [0.9, 0.45, 0.2, 0.1][tries.min(3)];
        for attempt in 0..40 {
            let mut child = args(&out, Some(&work)).stdout(std::process::Stdio::null()).stderr(std::process::Stdio::null()).spawn().unwrap();
            // A random moment within the run.
            let wait = span * (rng.next() % 1000) as f64 / 1000.0;
            std::thread::sleep(std::time::Duration::from_secs_f64(wait));
            let finished = child.try_wait().unwrap().is_some();
            if !finished && attempt < 6 {
                child.kill().unwrap(); // SIGKILL
                child.wait().unwrap();
                kills += 1;
                assert!(!out.exists() || std::fs::read(&out).unwrap() == want, "round {round}: a killed run left a partial output");
                continue;
            }
            assert!(child.wait().unwrap().success(), "round {round}: the resumed run failed");
            break;
        }
        if kills == 0 {
            // The run ended before any kill: not a test of resuming; again, earlier.
            tries += 1;
            assert!(tries < 8, "round {round}: no run was killed before it ended in {tries} tries");
            continue;
        }
        assert!(std::fs::read(&out).unwrap() == want, "round {round} ({kills} kills): output bytes differ");
        // (A SIGKILLed writer cannot remove its own temporary output file;
        // what matters is that the output itself is never partial.)
        round += 1;
        tries = 0;
    }
}

/// Runs the mint binary; returns (success, stderr).
fn mint(args: &[&std::ffi::OsStr]) -> (bool, String) {
    let o = std::process::Command::new(mint_bin()).args(args).output().unwrap();
    (o.status.success(), String::from_utf8_lossy(&o.stderr).into_owned())
}

fn one_line_error(stderr: &str, needle: &str) {
    let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(lines.len(), 1, "expected one line, got: {stderr}");
    assert!(lines[0].starts_with("mint: error: ") && lines[0].contains(needle), "expected '{needle}' in: {stderr}");
}

#[test]
fn a_bad_work_directory_gets_one_line_and_no_output() {
    let d = tempfile::tempdir().unwrap();
    // Four chunks of faces: every one of the 3 parts has some.
    let input = write_mesh(d.path(), "g.ply", |s| drop(mint_gen::genus(1, 250_000, s).unwrap()));
    let out = d.path().join("out.ply");
    let work = d.path().join("work");
    let os = |s: &str| std::ffi::OsString::from(s);
    let plan_args: Vec<std::ffi::OsString> = vec![os("stage"), os("plan"), os("resample"), input.clone().into(), out.clone().into(), os("--cells"), os("20000"), os("--work"), work.clone().into(), os("--parts"), os("3"), os("--slabs"), os("2"), os("--quiet")];
    let refs: Vec<&std::ffi::OsStr> = plan_args.iter().map(|s| s.as_os_str()).collect();
    let (ok, err) = mint(&refs);
    assert!(ok, "{err}");
    let run = |stage: &str, task: u32| {
        let o = std::process::Command::new(mint_bin()).args(["stage", "run"]).arg(&work).arg(stage).arg(task.to_string()).arg("--quiet").output().unwrap();
        (o.status.success(), String::from_utf8_lossy(&o.stderr).into_owned())
    };
    // A stage whose inputs are incomplete.
    let (ok, err) = run("discretize", 0);
    assert!(!ok);
    one_line_error(&err, "stage 'bounds' is not complete: tasks 0, 1, 2 of 3 not done");
    for t in 0..3 {
        assert!(run("bounds", t).0);
    }
    let (ok, err) = run("bounds", 1);
    assert!(ok && err.contains("already done"), "{err}");
    for t in 0..3 {
        assert!(run("discretize", t).0);
    }
    // A missing part: remove one discretize task's directory.
    let part = work.join("discretize").join("00001");
    let saved = d.path().join("saved-part");
    std::fs::rename(&part, &saved).unwrap();
    let (ok, err) = run("census", 0);
    assert!(!ok);
    one_line_error(&err, "stage 'discretize' is not complete: task 1 of 3 not done");
    std::fs::rename(&saved, &part).unwrap();
    // Damaged shards (checksum): every census task reads part 1's shards.
    let shards: Vec<PathBuf> = std::fs::read_dir(part.join("op-0")).unwrap().flatten().map(|e| e.path()).filter(|p| std::fs::metadata(p).unwrap().len() > 32).collect();
    assert!(!shards.is_empty());
    let good: Vec<Vec<u8>> = shards.iter().map(|p| std::fs::read(p).unwrap()).collect();
    for (p, g) in shards.iter().zip(&good) {
        let mut bad = g.clone();
        bad[20] ^= 0x40;
        std::fs::write(p, &bad).unwrap();
    }
    for t in 0..2 {
        let (ok, err) = run("census", t);
        assert!(!ok, "census {t}: a damaged shard went unnoticed");
        one_line_error(&err, "checksum");
    }
    for (p, g) in shards.iter().zip(&good) {
        std::fs::write(p, g).unwrap();
    }
    let result = part.join("result.json");
    let good_result = std::fs::read(&result).unwrap();
    let mut bad_result = good_result.clone();
    let at = bad_result.len() - 10;
    bad_result[at] = if bad_result[at] == b'1' { b'2' } else { b'1' };
    std::fs::write(&result, &bad_result).unwrap();
    let (ok, err) = run("census", 0);
    assert!(!ok);
    one_line_error(&err, "damaged task result");
    std::fs::write(&result, &good_result).unwrap();
    // The input changed after planning.
    let original = std::fs::read(&input).unwrap();
    let mut touched = original.clone();
    let n = touched.len();
    touched[n - 3] ^= 1;
    std::fs::write(&input, &touched).unwrap();
    let (ok, err) = run("census", 0);
    assert!(!ok);
    one_line_error(&err, "this input changed since the run was planned");
    // Same size and content but a new time: still refused (a plan trusts only its fingerprint).
    std::fs::write(&input, &original).unwrap();
    let (ok, err) = run("census", 0);
    assert!(!ok);
    one_line_error(&err, "changed");
    // Re-plan after putting the file back as planned is impossible (mtime);
    // a new plan in the same directory is refused with the reason.
    let (ok, err) = mint(&refs);
    assert!(!ok);
    one_line_error(&err, "is not the file this run was planned for");
    // Other options for the same directory.
    let mut other: Vec<std::ffi::OsString> = plan_args.clone();
    other[6] = os("30000");
    let refs2: Vec<&std::ffi::OsStr> = other.iter().map(|s| s.as_os_str()).collect();
    let (ok, err) = mint(&refs2);
    assert!(!ok);
    one_line_error(&err, "planned");
    // A plan from another version.
    let plan_path = work.join("plan.json");
    let text = std::fs::read_to_string(&plan_path).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    v["version"] = 999.into();
    mint_pipeline::plan::seal(&mut v);
    std::fs::write(&plan_path, serde_json::to_string(&v).unwrap()).unwrap();
    let (ok, err) = run("census", 0);
    assert!(!ok);
    one_line_error(&err, "a plan of format 999");
    assert!(!out.exists(), "no output after errors");
    // Not a work directory at all.
    let (ok, err) = run_in(d.path());
    assert!(!ok);
    one_line_error(&err, "not a work directory");
}

fn run_in(dir: &Path) -> (bool, String) {
    let o = std::process::Command::new(mint_bin()).args(["stage", "status"]).arg(dir).output().unwrap();
    (o.status.success(), String::from_utf8_lossy(&o.stderr).into_owned())
}

#[test]
fn resample_with_a_work_directory_resumes_and_refuses_other_options() {
    let d = tempfile::tempdir().unwrap();
    let input = write_mesh(d.path(), "g.ply", |s| drop(mint_gen::genus(2, 80_000, s).unwrap()));
    let work = d.path().join("w");
    let out = d.path().join("o.ply");
    let o = opts(30_000).with(|o| { o.tuning.work_dir = Some(work.clone()); o.tuning.parts = 2; o.tuning.slabs = 3; });
    let s1 = resample(&input, &out, &o, &NoProgress).unwrap();
    assert_eq!((s1.tasks_resumed, s1.tasks_run), (0, 2 + 2 + 3 + 3 + 3 + 1));
    let bytes = std::fs::read(&out).unwrap();
    // Again: everything is done; the output stays.
    let s2 = resample(&input, &out, &o, &NoProgress).unwrap();
    assert_eq!((s2.tasks_run, s2.output_faces), (0, s1.output_faces));
    // The output was deleted: only the write stage runs again.
    std::fs::remove_file(&out).unwrap();
    let s3 = resample(&input, &out, &o, &NoProgress).unwrap();
    assert_eq!(s3.tasks_run, 1);
    assert!(std::fs::read(&out).unwrap() == bytes);
    // Another memory budget and thread count: fine (same bytes).
    let s4 = resample(&input, &out, &o.clone().with(|o| { o.tuning.mem_bytes = 64 << 20; o.tuning.threads = 1; }), &NoProgress);
    assert!(s4.is_ok());
    // Other grid options: refused, naming the option.
    let e = resample(&input, &out, &o.clone().with(|o| { o.spec.grid.size = GridSize::Cells(31_000); }), &NoProgress).unwrap_err().to_string();
    assert!(e.contains("cells") && e.contains("another work directory"), "{e}");
    let e = resample(&input, &out, &o.clone().with(|o| { o.tuning.slabs = 4; }), &NoProgress).unwrap_err().to_string();
    assert!(e.contains("3 slabs"), "{e}");
}

/// A work directory names files, not path strings: a run planned with a
/// relative input resumes with its absolute path; and `decimate --work`,
/// whose intermediate now lives in the work directory, runs again with the
/// same command (it used to name a random temporary file in its plan).
#[test]
fn work_directories_compare_files_and_decimate_resumes() {
    let d = tempfile::tempdir().unwrap();
    write_mesh(d.path(), "s.ply", |s| drop(mint_gen::sphere([0.0; 3], 1.0, 20_000, s).unwrap()));
    let mint_in = |args: &[&str]| {
        let o = std::process::Command::new(mint_bin()).current_dir(d.path()).args(args).output().unwrap();
        assert!(o.status.success(), "{args:?}: {}", String::from_utf8_lossy(&o.stderr));
    };
    mint_in(&["stage", "plan", "resample", "s.ply", "o.ply", "--cells", "5000", "--work", "w", "--quiet"]);
    let abs = d.path().join("s.ply");
    mint_in(&["resample", abs.to_str().unwrap(), "o.ply", "--cells", "5000", "--work", "w", "--quiet"]);
    let plan: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(d.path().join("w/plan.json")).unwrap()).unwrap();
    assert_eq!(plan["spec"]["job"]["inputs"][0].as_str().unwrap(), abs.to_str().unwrap());
    for out in ["d1.ply", "d2.ply"] {
        mint_in(&["decimate", "s.ply", out, "--faces", "2000", "--work", "dw", "--quiet", "--route", "resample"]);
    }
    assert!(d.path().join("dw/intermediate.ply").is_file());
    assert_eq!(std::fs::read(d.path().join("d1.ply")).unwrap(), std::fs::read(d.path().join("d2.ply")).unwrap());
}

/// A shard whose checksum is valid but whose record names a grid line past
/// the grid (a crafted or stale work directory) is refused with one line;
/// it panicked with an index out of bounds (issue 26).
#[test]
fn a_shard_record_outside_the_grid_is_refused_not_a_panic() {
    let d = tempfile::tempdir().unwrap();
    let input = write_mesh(d.path(), "g.ply", |s| drop(mint_gen::genus(1, 20_000, s).unwrap()));
    let work = d.path().join("w");
    let o = std::process::Command::new(mint_bin()).args(["stage", "plan", "resample"]).arg(&input).arg(d.path().join("o.ply")).args(["--cells", "20000", "--quiet", "--work"]).arg(&work).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let run = |stage: &str| std::process::Command::new(mint_bin()).args(["stage", "run"]).arg(&work).args([stage, "0", "--quiet"]).output().unwrap();
    assert!(run("bounds").status.success() && run("discretize").status.success());
    // Rewrite the first record of the first shard, then its checksums.
    let task = work.join("discretize/00000");
    let text = std::fs::read_to_string(task.join("result.json")).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(text.split_once('\n').unwrap().1).unwrap();
    let shards = v["shards"][0]["shards"].as_array_mut().unwrap();
    let shard = shards.iter_mut().find(|s| s["len"].as_u64().unwrap() >= 16).unwrap();
    let path = task.join(format!("op-0/shard-{:05}.bin", shard["index"].as_u64().unwrap()));
    let mut bytes = std::fs::read(&path).unwrap();
    bytes[4..8].copy_from_slice(&1_000_000u32.to_le_bytes()); // family A, line 1,000,000
    std::fs::write(&path, &bytes).unwrap();
    shard["crc32"] = crc32fast::hash(&bytes).into();
    std::fs::write(task.join("result.json"), mint_pipeline::workdir::checked_json(&v)).unwrap();
    for stage in ["census", "reconstruct"] {
        let o = run(stage);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && !err.contains("panicked"), "{stage}: {err}");
        if stage == "census" {
            one_line_error(&err, "outside the");
        }
    }
}

/// A damaged `faces.bin` is blamed on itself, not on the output (it read
/// "out.ply: vertex index 4294967295 is out of range"), and nothing is written.
#[test]
fn a_damaged_slab_result_is_blamed_on_itself() {
    let d = tempfile::tempdir().unwrap();
    let input = write_mesh(d.path(), "g.ply", |s| drop(mint_gen::genus(1, 20_000, s).unwrap()));
    let work = d.path().join("w");
    let out = d.path().join("o.ply");
    let o = std::process::Command::new(mint_bin()).args(["stage", "plan", "resample"]).arg(&input).arg(&out).args(["--cells", "20000", "--quiet", "--close-all", "--work"]).arg(&work).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let run = |stage: &str| std::process::Command::new(mint_bin()).args(["stage", "run"]).arg(&work).args([stage, "0", "--quiet"]).output().unwrap();
    for stage in ["bounds", "discretize", "census", "reconstruct"] {
        assert!(run(stage).status.success(), "{stage}");
    }
    let faces = work.join("reconstruct/00000/faces.bin");
    let mut bytes = std::fs::read(&faces).unwrap();
    bytes[0..4].copy_from_slice(&u32::MAX.to_le_bytes());
    std::fs::write(&faces, &bytes).unwrap();
    let o = run("write");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{err}");
    one_line_error(&err, "faces.bin");
    assert!(!out.exists());
}

/// A run killed with SIGKILL leaves its `.mint-work-*` directory; the next
/// run in that folder removes it and says so, and never touches the
/// directory of a run that is alive (issue 26).
#[test]
fn debris_of_killed_runs_is_removed_by_the_next_run() {
    let d = tempfile::tempdir().unwrap();
    let input = d.path().join("s.ply");
    assert!(std::process::Command::new(mint_bin()).args(["gen", "sphere"]).arg(&input).args(["--faces", "2000000"]).output().unwrap().status.success());
    let out = d.path().join("out.ply");
    let debris = || -> Vec<PathBuf> {
        let mut v: Vec<PathBuf> = std::fs::read_dir(d.path()).unwrap().flatten().map(|e| e.path()).filter(|p| p.file_name().unwrap().to_string_lossy().starts_with(".mint-work-")).collect();
        v.sort();
        v
    };
    let mut left = Vec::new();
    for wait_ms in [300u64, 150, 80, 40, 20, 10, 5] {
        let mut child = std::process::Command::new(mint_bin()).arg("resample").arg(&input).arg(&out).args(["--cells", "4000000", "--quiet", "--threads", "1"]).spawn().unwrap();
        std::thread::sleep(std::time::Duration::from_millis(wait_ms));
        let _ = child.kill();
        let _ = child.wait();
        left = debris();
        if !left.is_empty() {
            break;
        }
    }
    assert!(!left.is_empty(), "no run was killed while its work directory existed");
    // A live run's directory (its owner lock held) is never removed.
    let live = d.path().join(".mint-work-live");
    std::fs::create_dir(&live).unwrap();
    let _held = mint_pipeline::workdir::OwnerLock::of_dir(&live).unwrap();
    let o = std::process::Command::new(mint_bin()).arg("resample").arg(&input).arg(&out).args(["--cells", "20000", "--quiet"]).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    for l in &left {
        assert!(!l.exists(), "{} is still there", l.display());
        assert!(err.contains(&format!("mint: removed {}", l.display())), "{err}");
    }
    assert_eq!(debris(), vec![live]);
}

/// A task killed with SIGKILL leaves its temporary directory; `stage status`
/// reports it as stale (no live process holds it), not as running forever,
/// and running the task again removes it. A task a live process is writing
/// stays "running" (issue 26).
#[test]
fn a_killed_task_is_reported_stale_and_redone() {
    let d = tempfile::tempdir().unwrap();
    let input = d.path().join("s.ply");
    assert!(std::process::Command::new(mint_bin()).args(["gen", "sphere"]).arg(&input).args(["--faces", "2000000"]).output().unwrap().status.success());
    let work = d.path().join("w");
    let out = d.path().join("o.ply");
    let o = std::process::Command::new(mint_bin())
        .args(["stage", "plan", "resample"]).arg(&input).arg(&out)
        .args(["--cells", "3000000", "--work"]).arg(&work).args(["--parts", "1", "--slabs", "1", "--quiet"])
        .output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let status = || -> serde_json::Value {
        let o = std::process::Command::new(mint_bin()).args(["stage", "status"]).arg(&work).arg("--json").output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        serde_json::from_slice(&o.stdout).unwrap()
    };
    let stage = |v: &serde_json::Value, name: &str| v["stages"].as_array().unwrap().iter().find(|s| s["name"] == name).unwrap().clone();
    let task = |stage: &str| {
        std::process::Command::new(mint_bin()).args(["stage", "run"]).arg(&work).args([stage, "0", "--threads", "1"]).output().unwrap()
    };
    assert!(task("bounds").status.success());
    // Kill the discretize task while its temporary directory exists.
    let mut killed = false;
    for wait_ms in [60u64, 40, 30, 80, 20, 50, 120, 10, 200, 400, 35, 45, 25, 15] {
        let mut child = std::process::Command::new(mint_bin()).args(["stage", "run"]).arg(&work).args(["discretize", "0", "--threads", "1", "--quiet"])
            .stderr(std::process::Stdio::null()).spawn().unwrap();
        std::thread::sleep(std::time::Duration::from_millis(wait_ms));
        let _ = child.kill();
        let _ = child.wait();
        let s = stage(&status(), "discretize");
        if s["done"] == 0 && s["stale"] == 1 {
            assert_eq!(s["running"], 0, "{s}");
            killed = true;
            break;
        }
        assert_eq!(s["running"], 0, "a dead task counted as running: {s}");
        if s["done"] == 1 {
            let _ = std::fs::remove_dir_all(work.join("discretize"));
        }
    }
    assert!(killed, "no discretize task was killed while it was writing");
    let text = std::process::Command::new(mint_bin()).args(["stage", "status"]).arg(&work).output().unwrap();
    assert!(String::from_utf8_lossy(&text.stdout).contains("stale: 1 task"), "{}", String::from_utf8_lossy(&text.stdout));
    // A live writer (its lock held) is running, not stale.
    let live = work.join("census").join(".00000.tmp-1-1");
    std::fs::create_dir_all(&live).unwrap();
    let held = mint_pipeline::workdir::OwnerLock::of_dir(&live).unwrap();
    let s = stage(&status(), "census");
    assert_eq!((s["running"].as_u64(), s["stale"].as_u64()), (Some(1), Some(0)), "{s}");
    drop(held);
    assert_eq!(stage(&status(), "census")["stale"], 1);
    std::fs::remove_dir_all(&live).unwrap();
    // Running the task again redoes it and removes the debris.
    let o = task("discretize");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = stage(&status(), "discretize");
    assert_eq!((s["done"].as_u64(), s["running"].as_u64(), s["stale"].as_u64()), (Some(1), Some(0), Some(0)), "{s}");
    let names: Vec<String> = std::fs::read_dir(work.join("discretize")).unwrap().flatten().map(|e| e.file_name().to_string_lossy().into_owned()).collect();
    assert!(names.iter().all(|n| !n.contains(".tmp-")), "{names:?}");
    assert!(!work.join("discretize").join("00000").join(".owner").exists(), "the lock file stays out of the result");
}

/// Asks to stop as soon as the write phase has finished: the output is in
/// place by then.
#[derive(Default)]
struct CancelAfterWrite {
    writing: std::sync::atomic::AtomicBool,
    cancel: std::sync::atomic::AtomicBool,
}
impl mint_core::progress::Progress for CancelAfterWrite {
    fn start(&self, phase: mint_core::progress::Phase, _total: u64) {
        if phase == mint_pipeline::progress::WRITE {
            self.writing.store(true, std::sync::atomic::Ordering::SeqCst);
        }
    }
    fn finish(&self) {
        if self.writing.load(std::sync::atomic::Ordering::SeqCst) {
            self.cancel.store(true, std::sync::atomic::Ordering::SeqCst);
        }
    }
    fn cancelled(&self) -> bool {
        self.cancel.load(std::sync::atomic::Ordering::SeqCst)
    }
}

/// Resume messages that do not lie (issue 26): a cancel that arrives after
/// the output is written does not report "no output written", and a damaged
/// task result with the output deleted fails before writing anything
/// instead of writing the output and then exiting 1.
#[test]
fn a_late_cancel_and_a_damaged_result_tell_the_truth() {
    let d = tempfile::tempdir().unwrap();
    let input = write_mesh(d.path(), "g.ply", |s| drop(mint_gen::genus(1, 20_000, s).unwrap()));
    let out = d.path().join("o.ply");
    let o = opts(20_000).with(|o| o.tuning.work_dir = Some(d.path().join("w")));
    let s = resample(&input, &out, &o, &CancelAfterWrite::default());
    assert!(s.is_ok(), "{:?}", s.err().map(|e| e.to_string()));
    assert!(out.exists());
    let want = std::fs::read(&out).unwrap();
    // A cancel before the write stage: no output, and it says so.
    std::fs::remove_file(&out).unwrap();
    struct Stop;
    impl mint_core::progress::Progress for Stop {
        fn cancelled(&self) -> bool {
            true
        }
    }
    let e = resample(&input, &out, &o, &Stop).unwrap_err().to_string();
    assert!(e.contains("interrupted; no output written") && !out.exists(), "{e}");
    // A damaged bounds result, output deleted: one line, nothing written.
    let result = d.path().join("w").join("bounds").join("00000").join("result.json");
    let good = std::fs::read(&result).unwrap();
    let mut bad = good.clone();
    let at = bad.len() / 2;
    bad[at] ^= 0x01;
    std::fs::write(&result, &bad).unwrap();
    let o2 = std::process::Command::new(mint_bin()).arg("resample").arg(&input).arg(&out)
        .args(["--cells", "20000", "--threads", "2", "--quiet", "--work"]).arg(d.path().join("w")).output().unwrap();
    let err = String::from_utf8_lossy(&o2.stderr);
    assert_eq!(o2.status.code(), Some(1), "{err}");
    one_line_error(&err, "damaged task result");
    assert!(!out.exists(), "an output was written by a run that then failed");
    // Repaired: the same bytes.
    std::fs::write(&result, &good).unwrap();
    assert!(resample(&input, &out, &o, &NoProgress).is_ok());
    assert!(std::fs::read(&out).unwrap() == want);
}
