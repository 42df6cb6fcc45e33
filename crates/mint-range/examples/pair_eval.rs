//! Exploration: pairwise ICP between ring neighbours of a set (i, i+k),
//! the second moved by an exact perturbation; prints the relative error.
//! cargo run --release -p mint-range --example pair_eval -- SET.conf DEG MM SEEDS K [start_distance]
use glam::DVec3;
use mint_range::geom::Rigid;
use mint_range::align::align;
use mint_range::icp::{AlignOptions, Strategy};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let set_path = std::path::PathBuf::from(&args[0]);
    let deg: f64 = args[1].parse().unwrap();
    let mm: f64 = args[2].parse().unwrap();
    let seeds: u64 = args[3].parse().unwrap();
    let kstep: usize = args[4].parse().unwrap();
    let sd: Option<f64> = args.get(5).map(|s| s.parse().unwrap());
    let set = mint_range::ScanSet::read(&set_path).unwrap();
    let scans = mint_range::load_set(&set, &set_path, &mint_range::MeshOptions::default()).unwrap();
    let truth: Vec<Rigid> = set.entries.iter().map(|e| e.pose).collect();
    let (lo, hi) = mint_range::scan_mesh::bbox(scans.iter().zip(&truth).flat_map(|(s, p)| s.bbox_corners().into_iter().map(move |c| p.apply(c))));
    let center = (DVec3::from(lo) + DVec3::from(hi)) * 0.5;
    let n = scans.len();
    for s in &scans { eprint!("{:.2e} ", s.sampling); }
    eprintln!();
    for i in 0..n {
        let j = (i + kstep) % n;
        let mut line = format!("{:>4}-{:<4}", i, j);
        for seed in 0..seeds {
            let mut rng = mint_mesh::SplitMix64::new(1000 + seed);
            let init = mint_range::synth::move_exactly(&truth[j], center, deg, mm * 1e-3, &mut rng);
            let pair = [scans[i].clone(), scans[j].clone()];
            let t = std::time::Instant::now();
            let r = align(&pair, &[truth[i], init], &AlignOptions { strategy: Strategy::Anchor, start_distance: sd, ..Default::default() }).unwrap();
            let d = truth[j].inverse().after(&r.poses[1]);
            let c = truth[j].inverse().apply(center);
            line += &format!(" | {:.2}° {:.1}mm rms {:.2} it {} {:.1}s", d.angle().to_degrees(), truth[j].apply(c).distance(r.poses[1].apply(c)) * 1e3, r.reports[1].rms / scans[j].sampling, r.reports[1].iterations, t.elapsed().as_secs_f64());
        }
        println!("{line}");
    }
}

