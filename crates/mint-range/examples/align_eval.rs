//! Measures `mint align` on a real scan set: each scan but the first is
//! moved from its `.conf` pose by exactly DEG degrees about a random axis
//! (through the model's centre) and MM millimetres in a random direction,
//! then registered; prints each start's worst rotation and centre
//! displacement against the `.conf`, and the time.
//!
//! cargo run --release -p mint-range --example align_eval -- SET.conf DEG MM SEEDS [--global off] [--start-distance D]

use mint_range::geom::{add, dist, scale, sub, Rigid, V3};
use mint_range::icp::{align, AlignOptions};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let set_path = std::path::PathBuf::from(&args[0]);
    let deg: f64 = args[1].parse().unwrap();
    let mm: f64 = args[2].parse().unwrap();
    let seeds: u64 = args[3].parse().unwrap();
    let mut opts = AlignOptions::default();
    let mut k = 4;
    while k < args.len() {
        match args[k].as_str() {
            "--start-distance" => {
                opts.start_distance = Some(args[k + 1].parse().unwrap());
                k += 2;
            }
            other => panic!("unknown option {other}"),
        }
    }
    let set = mint_range::ScanSet::read(&set_path).unwrap();
    let t = std::time::Instant::now();
    let scans = mint_range::load_set(&set, &set_path, &mint_range::MeshOptions::default()).unwrap();
    eprintln!("loaded {} scans in {:.2}s", scans.len(), t.elapsed().as_secs_f64());
    let truth: Vec<Rigid> = set.entries.iter().map(|e| e.pose).collect();
    let (lo, hi) = mint_range::scan_mesh::bbox(scans.iter().zip(&truth).flat_map(|(s, p)| s.bbox_corners().into_iter().map(move |c| p.apply(c))));
    let center = scale(add(lo, hi), 0.5);
    eprintln!("centre {center:?}, diagonal {:.4}", dist(lo, hi));
    let mut worst_all = (0.0f64, 0.0f64);
    for seed in 0..seeds {
        let mut rng = mint_mesh::SplitMix64::new(1000 + seed);
        let initial: Vec<Rigid> = if deg == 0.0 && mm == 0.0 {
            truth.clone()
        } else {
            truth.iter().enumerate().map(|(i, p)| if i == 0 { *p } else { exact_perturb(p, center, deg, mm * 1e-3, &mut rng) }).collect()
        };
        let t = std::time::Instant::now();
        let r = align(&scans, &initial, &opts).unwrap();
        let secs = t.elapsed().as_secs_f64();
        let mut worst = (0.0f64, 0.0f64, String::new());
        for i in 0..scans.len() {
            let (d, s) = errors(&truth[0], &truth[i], &r.poses[0], &r.poses[i], center);
            if d > worst.0 {
                worst.2 = scans[i].name.clone();
            }
            worst.0 = worst.0.max(d);
            worst.1 = worst.1.max(s);
            if std::env::var_os("VERBOSE").is_some() {
                let rep = &r.reports[i];
                eprintln!("  {:<24} {:?} rms {:.3e} it {} -> {d:.3}° {:.3} mm", rep.name, rep.status, rep.rms, rep.iterations, s * 1e3);
            }
        }
        worst_all.0 = worst_all.0.max(worst.0);
        worst_all.1 = worst_all.1.max(worst.1);
        println!("seed {seed}: worst {:.3}° ({}) {:.3} mm  in {secs:.1}s", worst.0, worst.2, worst.1 * 1e3);
    }
    println!("all: worst {:.3}° {:.3} mm", worst_all.0, worst_all.1 * 1e3);
}

/// Error of scan i relative to scan 0, against the truth: the rotation
/// angle and the displacement of the centre.
fn errors(t0: &Rigid, ti: &Rigid, p0: &Rigid, pi: &Rigid, center: V3) -> (f64, f64) {
    let rel_t = t0.inverse().after(ti);
    let rel_p = p0.inverse().after(pi);
    let d = rel_t.inverse().after(&rel_p);
    let c = rel_t.inverse().apply(t0.inverse().apply(center));
    (d.angle().to_degrees(), dist(rel_t.apply(c), rel_p.apply(c)))
}

fn exact_perturb(pose: &Rigid, center: V3, deg: f64, shift: f64, rng: &mut mint_mesh::SplitMix64) -> Rigid {
    let axis = unit(rng);
    let rot = Rigid::from_axis_angle(axis, deg.to_radians());
    let s = scale(unit(rng), shift);
    Rigid { r: rot.r, t: add(sub(center, rot.rotate(center)), s) }.after(pose)
}

fn unit(rng: &mut mint_mesh::SplitMix64) -> V3 {
    loop {
        let v = [2.0 * rng.next_f64() - 1.0, 2.0 * rng.next_f64() - 1.0, 2.0 * rng.next_f64() - 1.0];
        let n = mint_range::geom::norm(v);
        if n > 1e-3 && n <= 1.0 {
            return scale(v, 1.0 / n);
        }
    }
}
