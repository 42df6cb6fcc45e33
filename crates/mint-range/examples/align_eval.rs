//! Measures `mint align` on a real scan set: each scan but the first is
//! moved from its `.conf` pose by exactly DEG degrees about a random axis
//! (through the model's centre) and MM millimetres in a random direction,
//! then registered; prints each start's worst rotation and centre
//! displacement against the `.conf`, and the time.
//!
//! cargo run --release -p mint-range --example align_eval -- SET.conf DEG MM SEEDS [--global off] [--start-distance D]
//! [--metric plane|point] [--one-way] [--reject R] [--max-samples N] [--plant K DEG]
//!
//! Environment: VERBOSE=1 prints every scan and pair; ENERGY=1 compares the
//! fit of the result and of the `.conf` (pair RMS, median distance of each
//! scan to the others, and along the smooth part of their difference);
//! PLANT_Y=1 turns the planted scan about the world's y axis.
#![allow(clippy::needless_range_loop)]

use glam::DVec3;
use mint_range::geom::Rigid;
use mint_range::align::align;
use mint_range::icp::AlignOptions;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let set_path = std::path::PathBuf::from(&args[0]);
    let deg: f64 = args[1].parse().unwrap();
    let mm: f64 = args[2].parse().unwrap();
    let seeds: u64 = args[3].parse().unwrap();
    let mut opts = AlignOptions::default();
    let mut plant: Option<(usize, f64)> = None;
    let mut k = 4;
    while k < args.len() {
        match args[k].as_str() {
            "--start-distance" => {
                opts.start_distance = Some(args[k + 1].parse().unwrap());
                k += 2;
            }
            "--metric" => {
                opts.metric = match args[k + 1].as_str() {
                    "plane" => mint_range::icp::Metric::PointToPlane,
                    "point" => mint_range::icp::Metric::PointToPoint,
                    _ => mint_range::icp::Metric::PlaneThenPoint,
                };
                k += 2;
            }
            "--one-way" => {
                opts.symmetric = false;
                k += 1;
            }
            "--reject" => {
                opts.reject = args[k + 1].parse().unwrap();
                k += 2;
            }
            "--max-samples" => {
                opts.max_samples = args[k + 1].parse().unwrap();
                k += 2;
            }
            "--plant" => {
                plant = Some((args[k + 1].parse().unwrap(), args[k + 2].parse().unwrap()));
                k += 3;
            }
            "--global" => {
                opts.global = args[k + 1] != "off";
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
    let (lo, hi) = (DVec3::from(lo), DVec3::from(hi));
    let center = (lo + hi) * 0.5;
    eprintln!("centre {:?}, diagonal {:.4}", center.to_array(), lo.distance(hi));
    let mut worst_all = (0.0f64, 0.0f64);
    for seed in 0..seeds {
        let mut rng = mint_mesh::SplitMix64::new(1000 + seed);
        let initial: Vec<Rigid> = if deg == 0.0 && mm == 0.0 {
            truth.clone()
        } else {
            truth.iter().enumerate().map(|(i, p)| if i == 0 { *p } else { mint_range::synth::move_exactly(p, center, deg, mm * 1e-3, &mut rng) }).collect()
        };
        let mut initial = initial;
        if let Some((kp, deg)) = plant {
            initial[kp] = if std::env::var_os("PLANT_Y").is_some() {
                let rot = Rigid::from_axis_angle(DVec3::Y, deg.to_radians());
                Rigid { r: rot.r, t: (center - rot.rotate(center)).to_array() }.after(&truth[kp])
            } else {
                mint_range::synth::move_exactly(&truth[kp], center, deg, 0.0, &mut rng)
            };
        }
        let t = std::time::Instant::now();
        let r = align(&scans, &initial, &opts).unwrap();
        if let Some((kp, _)) = plant {
            let (dd, sh) = mint_range::geom::pose_error(&initial[kp], &r.poses[kp], &scans[kp].bbox_corners());
            let (e, es) = errors(&truth[0], &truth[kp], &r.poses[0], &r.poses[kp], center);
            println!("  planted {}: {:?}, moved {dd:.3}° {:.3} mm, ends {e:.3}° {:.3} mm from the truth", scans[kp].name, r.reports[kp].status, sh * 1e3, es * 1e3);
        }
        let secs = t.elapsed().as_secs_f64();
        let mut worst = (0.0f64, 0.0f64, String::new());
        for i in (0..scans.len()).filter(|&i| plant.is_none_or(|p| p.0 != i)) {
            let (d, s) = errors(&truth[0], &truth[i], &r.poses[0], &r.poses[i], center);
            if d > worst.0 {
                worst.2 = scans[i].name.clone();
            }
            worst.0 = worst.0.max(d);
            worst.1 = worst.1.max(s);
            if std::env::var_os("VERBOSE").is_some() {
                let rep = &r.reports[i];
                let dd = truth[i].inverse().after(&r.poses[i]);
                let q = dd.quat();
                let ax = truth[i].rotate(DVec3::new(q[0], q[1], q[2]).normalize_or_zero());
                eprintln!("  axis (world) [{:.2} {:.2} {:.2}]", ax[0], ax[1], ax[2]);
                eprintln!("  {:<24} {:?} rms/s {:.3} it {} conv {} partners {} -> {d:.3}° {:.3} mm", rep.name, rep.status, rep.rms_rel, rep.iterations, rep.converged, rep.partners.len(), s * 1e3);
            }
        }
        if std::env::var_os("VERBOSE").is_some() {
            eprintln!("  rounds {}", r.rounds);
            for p in &r.pairs {
                eprintln!("    {:<24} {:<24} ov {:.2}->{:.2} rms/s {:.3} it {:>3} conv {} att {} resid {:.3e} {:?}", p.a, p.b, p.overlap_before, p.overlap, p.rms_rel, p.iterations, p.converged, p.attempts, p.residual, p.status);
            }
        }
        if std::env::var_os("ENERGY").is_some() {
            let d = r.distance;
            let energy = |poses: &[Rigid]| {
                let (mut e, mut c) = (0.0, 0usize);
                for p in &r.pairs {
                    let a = scans.iter().position(|s| s.name == p.a).unwrap();
                    let b = scans.iter().position(|s| s.name == p.b).unwrap();
                    for (x, y) in [(a, b), (b, a)] {
                        let (m, n) = mint_range::icp::objective(&scans, poses, x, &[y], d, 3.0).unwrap();
                        e += m * n as f64;
                        c += n;
                    }
                }
                (e / c as f64).sqrt()
            };
            eprintln!("  energy: truth {:.5e}  result {:.5e}", energy(&truth), energy(&r.poses));
            // Median distance of each scan's interior vertices (every 4th) to
            // the union of the other scans, within 5 mm (no weights, no trim).
            let bvhs: Vec<mint_mesh::TriangleBvh> = scans.iter().map(|s| mint_mesh::TriangleBvh::new(&s.positions, &s.faces).unwrap()).collect();
            let medians = |poses: &[Rigid]| -> Vec<f64> {
                (0..scans.len())
                    .map(|i| {
                        let mut ds: Vec<f64> = Vec::new();
                        for (v, p) in scans[i].positions.iter().enumerate().step_by(4) {
                            if scans[i].boundary[v] || scans[i].confidence[v] <= 0.0 {
                                continue;
                            }
                            let w = poses[i].apply(*p);
                            let mut best = f64::INFINITY;
                            for j in (0..scans.len()).filter(|&j| j != i) {
                                if let Some((dd, _, _)) = bvhs[j].nearest_within(poses[j].inverse().apply(w), 5e-3) {
                                    best = best.min(dd);
                                }
                            }
                            if best.is_finite() {
                                ds.push(best);
                            }
                        }
                        ds.sort_by(f64::total_cmp);
                        ds[ds.len() / 2]
                    })
                    .collect()
            };
            let mt = medians(&truth);
            let mr = medians(&r.poses);
            eprintln!("  median to union (mm): truth {:?}", mt.iter().map(|v| (v * 1e6).round() / 1000.0).collect::<Vec<_>>());
            eprintln!("  median to union (mm): result {:?}", mr.iter().map(|v| (v * 1e6).round() / 1000.0).collect::<Vec<_>>());
            // The smooth part of the difference: each component of the
            // rotation vector and centre shift fitted by a + b cos θ + c sin θ
            // over the ring (θ = 24° k), applied to the result.
            let n = truth.len();
            let logs: Vec<[f64; 6]> = truth
                .iter()
                .zip(&r.poses)
                .map(|(a, b)| {
                    let dlt = a.after(&b.inverse()); // result -> truth
                    let q = dlt.quat();
                    let s = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt();
                    let ang = 2.0 * s.atan2(q[3]);
                    let w = if s > 0.0 { DVec3::new(q[0], q[1], q[2]) * (ang / s) } else { DVec3::ZERO };
                    let rot = Rigid::from_rotation_vector(w, [0.0; 3]);
                    let t = dlt.apply(center) - center;
                    let _ = rot;
                    [w[0], w[1], w[2], t[0], t[1], t[2]]
                })
                .collect();
            let mut smooth = vec![[0.0; 6]; n];
            for comp in 0..6 {
                let (mut a0, mut a1, mut a2) = (0.0, 0.0, 0.0);
                for k in 0..n {
                    let th = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
                    a0 += logs[k][comp] / n as f64;
                    a1 += 2.0 * logs[k][comp] * th.cos() / n as f64;
                    a2 += 2.0 * logs[k][comp] * th.sin() / n as f64;
                }
                for k in 0..n {
                    let th = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
                    smooth[k][comp] = a0 + a1 * th.cos() + a2 * th.sin();
                }
            }
            for alpha in [0.25, 0.5, 1.0] {
                let moved: Vec<Rigid> = r.poses.iter().enumerate().map(|(k, p)| {
                    let v = smooth[k];
                    let rot = Rigid::from_rotation_vector(DVec3::new(alpha * v[0], alpha * v[1], alpha * v[2]), [0.0; 3]);
                    Rigid { r: rot.r, t: (center - rot.rotate(center) + DVec3::new(alpha * v[3], alpha * v[4], alpha * v[5])).to_array() }.after(p)
                }).collect();
                let worst = (0..n).map(|k| truth[k].inverse().after(&moved[k]).angle().to_degrees()).fold(0.0, f64::max);
                eprintln!("  smooth mode x{alpha}: energy {:.5e}, worst vs truth {worst:.3}°", energy(&moved));
            }
            for lam in [0.25, 0.5, 0.75, 1.25] {
                let interp: Vec<Rigid> = truth
                    .iter()
                    .zip(&r.poses)
                    .map(|(a, b)| {
                        let dlt = b.after(&a.inverse());
                        let q = dlt.quat();
                        let s = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt();
                        let ang = 2.0 * s.atan2(q[3]);
                        let w = if s > 0.0 { DVec3::new(q[0], q[1], q[2]) * (lam * ang / s) } else { DVec3::ZERO };
                        let rot = Rigid::from_rotation_vector(w, [0.0; 3]);
                        // translation part: interpolate the motion of the centre
                        let c2 = dlt.apply(center);
                        let t = center - rot.rotate(center) + (c2 - center) * lam;
                        Rigid { r: rot.r, t: t.to_array() }.after(a)
                    })
                    .collect();
                eprintln!("  energy at {lam}: {:.5e}", energy(&interp));
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
fn errors(t0: &Rigid, ti: &Rigid, p0: &Rigid, pi: &Rigid, center: DVec3) -> (f64, f64) {
    let rel_t = t0.inverse().after(ti);
    let rel_p = p0.inverse().after(pi);
    let d = rel_t.inverse().after(&rel_p);
    let c = rel_t.inverse().apply(t0.inverse().apply(center));
    (d.angle().to_degrees(), rel_t.apply(c).distance(rel_p.apply(c)))
}

