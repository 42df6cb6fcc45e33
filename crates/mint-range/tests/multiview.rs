//! Multiview registration (issue 17) on the dragon stand (15 real scans in
//! a ring, `../shared/data/stanford_dragon_stand_range_scans`) and on the
//! synthetic scene: from perturbed starts, from the `.conf`, and with one
//! scan planted far away. The real-data tests skip when the data folder is
//! absent and fail then under `MINT_REQUIRE_DATA=1` (CI).
//!
//! Errors are measured as the issue measures them: the pose of each scan
//! relative to the first (the anchor), against the same in the `.conf`:
//! the rotation angle, and the displacement of the model's centre.
//!
//! About the `.conf` as a reference: every start ends at the same poses
//! (within 0.02°), 0.58–0.60° and 1.24 mm from the `.conf` at the worst
//! scan (`dragonStandRight_192`, across the ring from the anchor), a
//! smooth tilt about the horizontal axis that grows around the ring.
//! These poses fit the scans more tightly than the `.conf` does: the
//! median distance of each scan's samples to the other scans is
//! 0.023–0.036 mm against the `.conf`'s 0.041–0.057 mm, and moving the
//! result towards the `.conf` along that tilt raises the pair RMS all the
//! way (`examples/align_eval.rs` with `ENERGY=1` prints both). So the
//! bounds below are what mint reaches, not the 0.5° (and 0.2°
//! from the `.conf`), which would take fitting the scans less well.

#[allow(dead_code)] // the scene's truth mesh and noise are for the other tests
mod common;

use glam::DVec3;
use mint_range::geom::Rigid;
use mint_range::align::align;
use mint_range::icp::{AlignOptions, Status};
use mint_range::multiview::PairStatus;
use mint_range::ScanMesh;

struct Dragon {
    scans: Vec<ScanMesh>,
    conf: Vec<Rigid>,
    center: DVec3,
}

fn dragon() -> Option<Dragon> {
    let set_path = mint_testkit::shared_data()?.join("stanford_dragon_stand_range_scans/dragonStandRight.conf");
    let set = mint_range::ScanSet::read(&set_path).unwrap();
    let scans = mint_range::load_set(&set, &set_path, &mint_range::MeshOptions::default()).unwrap();
    let conf: Vec<Rigid> = set.entries.iter().map(|e| e.pose).collect();
    let (lo, hi) = mint_range::scan_mesh::bbox(scans.iter().zip(&conf).flat_map(|(s, p)| s.bbox_corners().into_iter().map(move |c| p.apply(c))));
    Some(Dragon { scans, conf, center: (DVec3::from(lo) + DVec3::from(hi)) * 0.5 })
}


/// Scan `i` relative to scan 0, against the same in `truth`: rotation in
/// degrees and displacement of `center`.
fn relative_error(truth: &[Rigid], got: &[Rigid], i: usize, center: DVec3) -> (f64, f64) {
    let rel_t = truth[0].inverse().after(&truth[i]);
    let rel_g = got[0].inverse().after(&got[i]);
    let c = rel_t.inverse().apply(truth[0].inverse().apply(center));
    (rel_t.inverse().after(&rel_g).angle().to_degrees(), rel_t.apply(c).distance(rel_g.apply(c)))
}

/// Registers the dragon stand from `starts` perturbations of `deg`/`mm`
/// (every scan but the first moved); returns the worst (degrees, metres)
/// over all starts and the largest spread between starts.
fn dragon_from_starts(d: &Dragon, deg: f64, mm: f64, seeds: std::ops::Range<u64>) -> (f64, f64, f64) {
    let mut worst = (0.0f64, 0.0f64);
    let mut results: Vec<Vec<Rigid>> = Vec::new();
    for seed in seeds {
        let mut rng = mint_mesh::SplitMix64::new(1000 + seed);
        let initial: Vec<Rigid> = d.conf.iter().enumerate().map(|(i, p)| if i == 0 { *p } else { mint_range::synth::move_exactly(p, d.center, deg, mm * 1e-3, &mut rng) }).collect();
        let t = std::time::Instant::now();
        let r = align(&d.scans, &initial, &AlignOptions::default()).unwrap();
        let secs = t.elapsed().as_secs_f64();
        let mut w = (0.0f64, 0.0f64);
        for (i, rep) in r.reports.iter().enumerate() {
            assert!(!matches!(rep.status, Status::Failed(_)), "seed {seed}: {} failed: {:?}", rep.name, rep.status);
            let (a, s) = relative_error(&d.conf, &r.poses, i, d.center);
            w = (w.0.max(a), w.1.max(s));
        }
        eprintln!("{deg}°/{mm} mm, seed {seed}: worst {:.3}° {:.3} mm, {} rounds, {secs:.1}s", w.0, w.1 * 1e3, r.rounds);
        worst = (worst.0.max(w.0), worst.1.max(w.1));
        results.push(r.poses);
    }
    let spread = results.iter().flat_map(|a| results.iter().map(move |b| (0..a.len()).map(|i| relative_error(a, b, i, d.center).0).fold(0.0, f64::max))).fold(0.0, f64::max);
    (worst.0, worst.1, spread)
}

/// The failure: from 3°/3 mm the old registration ended 6.4° (and
/// from these starts up to 10.9°/14 mm, 16.3°/35.6 mm from 5°/5 mm) off.
/// One start each at 3°/3 mm and 5°/5 mm (about 7 s each on two cores);
/// the full matrix is `dragon_stand_from_ten_starts`.
#[test]
fn dragon_stand_registers_from_perturbed_starts() {
    let Some(d) = dragon() else { return };
    for (deg, mm, seed) in [(3.0, 3.0, 0), (5.0, 5.0, 1)] {
        let (a, s, _) = dragon_from_starts(&d, deg, mm, seed..seed + 1);
        assert!(a < 0.65 && s < 1.5e-3, "{deg}°/{mm} mm: worst {a}° {s} m");
    }
}

/// Five starts each at 3°/3 mm and 5°/5 mm: every one ends within 0.65°
/// and 1.5 mm of the `.conf` and within 0.05° of every other. About 70 s
/// on two cores; run with `--ignored`.
#[test]
#[ignore]
fn dragon_stand_from_ten_starts() {
    let Some(d) = dragon() else { return };
    for (deg, mm) in [(3.0, 3.0), (5.0, 5.0)] {
        let (a, s, spread) = dragon_from_starts(&d, deg, mm, 0..5);
        eprintln!("{deg}°/{mm} mm: worst {a:.3}° {:.3} mm, spread between starts {spread:.3}°", s * 1e3);
        assert!(a < 0.65 && s < 1.5e-3 && spread < 0.05, "{deg}°/{mm} mm: worst {a}° {s} m, spread {spread}°");
    }
}

/// Issue 31's target: 20 starts of 5°/5 mm and 10 of 8°/8 mm (seeds 100..):
/// every scan registered on every start (retried where it first failed),
/// and all starts within 0.05° and 0.5 mm of each other. Several minutes
/// on two cores; run with `--ignored` (`scripts/bench/align_peers.sh`
/// measures the same starts against a peer).
#[test]
#[ignore]
fn dragon_stand_from_thirty_starts_registers_every_scan() {
    let Some(d) = dragon() else { return };
    let mut all: Vec<Vec<Rigid>> = Vec::new();
    for (deg, mm, seeds) in [(5.0, 5.0, 100..120), (8.0, 8.0, 200..210)] {
        for seed in seeds {
            let (poses, retried) = dragon_start(&d, deg, mm, seed);
            eprintln!("{deg}°/{mm} mm seed {seed}: retried {retried:?}");
            all.push(poses);
        }
    }
    let (mut deg, mut shift) = (0.0f64, 0.0f64);
    for a in &all {
        for b in &all {
            for i in 0..a.len() {
                let (x, y) = relative_error(a, b, i, d.center);
                deg = deg.max(x);
                shift = shift.max(y);
            }
        }
    }
    eprintln!("spread between the 30 starts: {deg:.4}° {:.4} mm", shift * 1e3);
    assert!(deg < 0.05 && shift < 0.5e-3, "spread {deg}° {shift} m");
}

/// One start of `deg`/`mm` (seed `seed`, as [`dragon_from_starts`]):
/// asserts that every scan ends registered; returns the poses and the
/// scans that were retried.
fn dragon_start(d: &Dragon, deg: f64, mm: f64, seed: u64) -> (Vec<Rigid>, Vec<String>) {
    let mut rng = mint_mesh::SplitMix64::new(1000 + seed);
    let initial: Vec<Rigid> = d.conf.iter().enumerate().map(|(i, p)| if i == 0 { *p } else { mint_range::synth::move_exactly(p, d.center, deg, mm * 1e-3, &mut rng) }).collect();
    let r = align(&d.scans, &initial, &AlignOptions::default()).unwrap();
    for rep in &r.reports {
        assert!(!matches!(rep.status, Status::Failed(_)), "{deg}°/{mm} mm seed {seed}: {} failed: {:?}", rep.name, rep.status);
    }
    (r.poses, r.reports.iter().filter(|r| r.retries > 0).map(|r| format!("{} ({} tries, from {:?})", r.name, r.retries, r.retried_from)).collect())
}

/// Started at the `.conf`, every scan is registered and judged sound, and
/// moves to the same poses as from the perturbed starts (see the module
/// docs for why that is 0.58° and not under 0.2°).
#[test]
fn dragon_stand_started_at_the_conf() {
    let Some(d) = dragon() else { return };
    let r = align(&d.scans, &d.conf, &AlignOptions::default()).unwrap();
    let mut worst: f64 = 0.0;
    for (i, rep) in r.reports.iter().enumerate() {
        assert!(!matches!(rep.status, Status::Failed(_)), "{} failed: {:?}", rep.name, rep.status);
        assert!(rep.converged && rep.partners.len() >= 4, "{rep:?}");
        worst = worst.max(relative_error(&d.conf, &r.poses, i, d.center).0);
    }
    eprintln!("from the .conf: worst scan moved {worst:.3}°");
    assert!(worst < 0.65, "{worst}");
    // Every scan's neighbours on the ring are among its partners, and
    // no pair of neighbours is rejected.
    for p in &r.pairs {
        assert!(p.overlap < 0.3 || p.status == PairStatus::Accepted, "{p:?}");
    }
}

/// The dragon stand with scan `bad` turned `deg` about the turntable's axis
/// (the world's y) from its `.conf` pose and the others moved by 3°/3 mm.
fn dragon_planted(d: &Dragon, bad: usize, deg: f64) -> (Vec<Rigid>, mint_range::align::AlignResult) {
    let mut rng = mint_mesh::SplitMix64::new(1000);
    let mut initial: Vec<Rigid> = d.conf.iter().enumerate().map(|(i, p)| if i == 0 { *p } else { mint_range::synth::move_exactly(p, d.center, 3.0, 3e-3, &mut rng) }).collect();
    let turn = Rigid::from_axis_angle(DVec3::Y, deg.to_radians());
    initial[bad] = Rigid { r: turn.r, t: (d.center - turn.rotate(d.center)).to_array() }.after(&d.conf[bad]);
    let r = align(&d.scans, &initial, &AlignOptions::default()).unwrap();
    eprintln!("{} turned {deg}°: {:?}, {} retries, from {:?}", r.reports[bad].name, r.reports[bad].status, r.reports[bad].retries, r.reports[bad].retried_from);
    (initial, r)
}

/// The others end as well as without the planted scan.
fn others_within_bounds(d: &Dragon, r: &mint_range::align::AlignResult, bad: usize) {
    for (i, rep) in r.reports.iter().enumerate().filter(|&(i, _)| i != bad) {
        assert!(!matches!(rep.status, Status::Failed(_)), "{} failed: {:?}", rep.name, rep.status);
        let (a, s) = relative_error(&d.conf, &r.poses, i, d.center);
        assert!(a < 0.65 && s < 1.5e-3, "{}: {a}° {s} m", rep.name);
    }
}

/// `dragonStandRight_72` (the smallest scan) turned 60°: registered
/// against `_96` from there it ends with an RMS far above the median
/// (before retries, even 30° was reported failed); retried from its
/// registered neighbours' predictions with the coarse search it comes back
/// to its `.conf` pose. (Measured: 30° and 60° come back, 90°, 120° and
/// 180° do not.)
#[test]
fn dragon_stand_planted_60_degrees_comes_back_on_a_retry() {
    let Some(d) = dragon() else { return };
    let bad = 3;
    let (_, r) = dragon_planted(&d, bad, 60.0);
    let rep = &r.reports[bad];
    assert!(rep.retries > 0 && rep.retried_from.is_some(), "it was retried: {rep:?}");
    assert!(!matches!(rep.status, Status::Failed(_)), "{rep:?}");
    let (a, s) = relative_error(&d.conf, &r.poses, bad, d.center);
    assert!(a < 0.65 && s < 1.5e-3, "{}: {a}° {s} m", rep.name);
    others_within_bounds(&d, &r, bad);
}

/// The same scan turned 90°, where its initial pose overlaps nothing: it
/// is retried (from its neighbours' predictions and its own start, each
/// three ways), still fails, keeps its initial pose, is nobody's partner,
/// and the others end as well as without it.
#[test]
fn dragon_stand_planted_90_degrees_is_retried_flagged_and_spoils_nothing() {
    let Some(d) = dragon() else { return };
    let bad = 3;
    let (initial, r) = dragon_planted(&d, bad, 90.0);
    let rep = &r.reports[bad];
    assert!(rep.retries > 0, "it was retried: {rep:?}");
    let Status::Failed(why) = &rep.status else { panic!("{rep:?}") };
    assert!(why.contains("retried from"), "{why}");
    assert_eq!(r.poses[bad], initial[bad], "a failed scan keeps its initial pose");
    assert!(r.reports.iter().all(|x| !x.partners.contains(&rep.name)), "the failed scan is nobody's partner");
    others_within_bounds(&d, &r, bad);
}

/// A start of 8°/8 mm (seed 206) on which `dragonStandRight_168` failed
/// before retries existed: it is retried and every scan ends registered,
/// within the bounds of the other starts.
#[test]
fn dragon_stand_start_that_failed_before_retries_registers_every_scan() {
    let Some(d) = dragon() else { return };
    let (poses, retried) = dragon_start(&d, 8.0, 8.0, 206);
    eprintln!("retried: {retried:?}");
    assert!(!retried.is_empty(), "seed 206 needs a retry: it no longer tests them");
    for i in 0..poses.len() {
        let (a, s) = relative_error(&d.conf, &poses, i, d.center);
        assert!(a < 0.65 && s < 1.5e-3, "scan {i}: {a}° {s} m");
    }
}

/// The synthetic scene (8 noisy views of a bumpy sphere), one view turned
/// 90° about the centre and the others moved by up to 3° and 1% of the
/// diagonal: the turned view fails and keeps its pose, the others are
/// recovered to 0.2°. Needs no data. (Turned by 30° it comes back: the
/// scene is a bumpy sphere, and the judged registration, retried from
/// twice the start distance, finds it; turned by 60° or more it ends
/// elsewhere on the sphere with an RMS far above its peers'.)
#[test]
fn a_view_planted_far_away_fails_alone() {
    let s = common::scene();
    let mut initial = common::perturbed(&s, 3.0, 0.01, 11);
    let bad = 5;
    let mut rng = mint_mesh::SplitMix64::new(7);
    initial[bad] = mint_range::synth::move_exactly(&s.scans[bad].pose, s.center, 90.0, 0.0, &mut rng);
    let r = align(&s.meshes, &initial, &AlignOptions::default()).unwrap();
    for (i, rep) in r.reports.iter().enumerate() {
        let (a, sh) = common::pose_errors(&s.scans[i].pose, &r.poses[i], s.center);
        eprintln!("{:<8} {:?} -> {a:.3}° {:.2e}", rep.name, rep.status, sh / s.diag);
    }
    assert!(matches!(r.reports[bad].status, Status::Failed(_)), "{:?}", r.reports[bad]);
    assert!(r.reports[bad].retries > 0, "a failed view is retried: {:?}", r.reports[bad]);
    assert_eq!(r.poses[bad], initial[bad]);
    for (i, rep) in r.reports.iter().enumerate().filter(|&(i, _)| i != bad) {
        let (a, sh) = common::pose_errors(&s.scans[i].pose, &r.poses[i], s.center);
        assert!(!matches!(rep.status, Status::Failed(_)) && a < 0.2 && sh < 2e-3 * s.diag, "{}: {:?} {a}° {sh}", rep.name, rep.status);
    }
}

/// Three generated shapes (two bumpy spheres of different seeds and bump
/// amplitudes, and a bumpy ellipsoid flattened 1 : 0.6 : 0.35), 10 or 12
/// noisy views each, every view but the first moved by 5° and 1% of the
/// diagonal: every view ends within 0.2° of its true pose. (mint-gen's
/// other shapes are symmetric, so their views have no unique pose: the
/// genus-3 plate, a slab with three square holes in a row, has views
/// registered 90° and 180° away that fit as well.)
#[test]
fn three_synthetic_shapes_register_to_a_fifth_of_a_degree() {
    let bumpy = |seed: u64, amplitude: f64| {
        let mut t = mint_core::TriMesh::default();
        let opts = mint_gen::ScanOptions { holes: 0, flips: 0, patches: 0, slivers: 0, noise_amplitude: amplitude, ..Default::default() };
        mint_gen::scan_like(60_000, seed, &opts, &mut t).unwrap();
        t
    };
    let mut ellipsoid = bumpy(5, 0.2);
    for p in &mut ellipsoid.positions {
        p[1] *= 0.6;
        p[2] *= 0.35;
    }
    for (name, truth, views) in [("bumpy sphere 7", bumpy(7, 0.2), 10), ("bumpy sphere 11", bumpy(11, 0.12), 12), ("bumpy ellipsoid", ellipsoid, 12)] {
        let s = common::scene_of(truth, views, 160, 9);
        let initial = common::perturbed(&s, 5.0, 0.01, 21);
        let r = align(&s.meshes, &initial, &AlignOptions::default()).unwrap();
        let mut worst: f64 = 0.0;
        for (i, rep) in r.reports.iter().enumerate() {
            let (a, sh) = common::pose_errors(&s.scans[i].pose, &r.poses[i], s.center);
            eprintln!("{name} {:<8} {:?} -> {a:.3}° {:.2e}", rep.name, rep.status, sh / s.diag);
            worst = worst.max(a);
        }
        eprintln!("{name}: worst {worst:.3}°");
        assert!(worst <= 0.2, "{name}: worst view {worst}° from its true pose");
    }
}

