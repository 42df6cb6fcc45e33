//! The fuzz targets (tools/fuzz, bodies in tools/fuzz-targets) on stable:
//! every file of `tools/fuzz/corpus/<target>/` and
//! `tools/fuzz/regressions/<target>/` (minimized crashes found by cargo-fuzz,
//! fixed since), then a short deterministic mutation smoke of the corpus.
//! A target fails by panicking; the failing file (or the mutated bytes, hex)
//! is named. Long runs are by hand: see README.md, "Fuzzing".

use mint_fuzz_targets::{mutate, TARGETS};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};

fn fuzz_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/fuzz")
}

fn files(dir: &Path) -> Vec<PathBuf> {
    let Ok(rd) = std::fs::read_dir(dir) else { return Vec::new() };
    let mut v: Vec<PathBuf> = rd.map(|e| e.unwrap().path()).filter(|p| p.is_file()).collect();
    v.sort();
    v
}

/// Runs `f` on `data`; a panic becomes an error naming `what`.
fn run_one(f: fn(&[u8]), data: &[u8], what: impl FnOnce() -> String) -> Result<(), String> {
    catch_unwind(AssertUnwindSafe(|| f(data))).map_err(|p| {
        let msg = p.downcast_ref::<String>().cloned().or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string())).unwrap_or_default();
        format!("{}: {msg}", what())
    })
}

/// Every corpus and regression directory is a target's.
#[test]
fn fuzz_directories_name_targets() {
    for sub in ["corpus", "regressions"] {
        let Ok(rd) = std::fs::read_dir(fuzz_dir().join(sub)) else { continue };
        for e in rd {
            let name = e.unwrap().file_name().into_string().unwrap();
            assert!(mint_fuzz_targets::target(&name).is_some(), "tools/fuzz/{sub}/{name} is no fuzz target's");
        }
    }
    for (name, _) in TARGETS {
        assert!(!files(&fuzz_dir().join("corpus").join(name)).is_empty(), "no seed corpus for target {name}");
        assert!(fuzz_dir().join("fuzz_targets").join(format!("{name}.rs")).is_file(), "no cargo-fuzz target for {name}");
    }
}

#[test]
fn fuzz_corpus_and_regressions_replay() {
    let mut failures = Vec::new();
    let mut n = 0;
    for (name, f) in TARGETS {
        for sub in ["corpus", "regressions"] {
            for file in files(&fuzz_dir().join(sub).join(name)) {
                let data = std::fs::read(&file).unwrap();
                n += 1;
                if let Err(e) = run_one(*f, &data, || format!("{name}: {}", file.display())) {
                    failures.push(e);
                }
            }
        }
    }
    assert!(failures.is_empty(), "{} of {n} fuzz inputs fail:\n{}", failures.len(), failures.join("\n"));
}

/// Mutations per target: the resampling target runs a whole pipeline per
/// input, so it gets fewer.
///
/// By hand, a longer campaign: `MINT_FUZZ_SCALE=50` multiplies them, and
/// `MINT_FUZZ_TARGETS=read_glb,read_gltf` runs only those targets.
fn mutations(name: &str) -> usize {
    let base = match name {
        "resample" => 800,
        "stage" => 600,
        _ => 4000,
    };
    let only = std::env::var("MINT_FUZZ_TARGETS").ok();
    if only.is_some_and(|o| !o.split(',').any(|t| t == name)) {
        return 0;
    }
    base * std::env::var("MINT_FUZZ_SCALE").ok().and_then(|s| s.parse::<usize>().ok()).unwrap_or(1).max(1)
}

#[test]
fn fuzz_mutation_smoke() {
    let mut failures = Vec::new();
    for (k, (name, f)) in TARGETS.iter().enumerate() {
        let seeds: Vec<Vec<u8>> = files(&fuzz_dir().join("corpus").join(name)).iter().map(|p| std::fs::read(p).unwrap()).collect();
        let mut rng = mutate::Rng(0x6d69_6e74 + k as u64);
        let t0 = std::time::Instant::now();
        for i in 0..mutations(name) {
            let data = mutate::mutate(&seeds[i % seeds.len()], &mut rng);
            if let Err(e) = run_one(*f, &data, || format!("{name}, mutation {i}, input (hex) {}", data.iter().map(|b| format!("{b:02x}")).collect::<String>())) {
                failures.push(e);
                if failures.len() >= 10 {
                    break;
                }
            }
        }
        eprintln!("fuzz smoke: {name}: {} mutations in {:.2} s", mutations(name), t0.elapsed().as_secs_f64());
    }
    assert!(failures.is_empty(), "{} mutated fuzz inputs fail:\n{}", failures.len(), failures.join("\n"));
}
