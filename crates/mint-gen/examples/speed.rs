//! Timing runs of the generators and of `mint_mesh::check`/`distance`, one
//! line per run: what, faces, wall and CPU seconds, peak RSS. Run with
//! `cargo run --release -p mint-gen --example speed -- [max_faces]`
//! (default 10 million). Peak RSS is read from /proc on Linux, `?` elsewhere.

use mint_gen::{scan_like, sphere, CountingSink, ScanOptions, TriMesh};
use std::time::Instant;

fn peak_rss_mb() -> String {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .map(|l| l[6..].trim().to_string())
        })
        .unwrap_or_else(|| "?".into())
}

/// Process CPU time (user + system) in seconds, from /proc on Linux.
fn cpu_s() -> f64 {
    std::fs::read_to_string("/proc/self/stat")
        .ok()
        .and_then(|s| {
            let f: Vec<&str> = s.rsplit(')').next()?.split_whitespace().collect();
            Some((f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?) / 100.0)
        })
        .unwrap_or(f64::NAN)
}

struct Clock(Instant, f64);

fn start() -> Clock {
    Clock(Instant::now(), cpu_s())
}

fn line(what: &str, faces: u64, t: Clock) {
    println!(
        "{what:<28} {faces:>11} faces {:>7.2} s wall {:>7.2} s cpu  peak {}",
        t.0.elapsed().as_secs_f64(),
        cpu_s() - t.1,
        peak_rss_mb()
    );
}

fn main() {
    let max: u64 = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(10_000_000);
    let t = start();
    let mut c = CountingSink::default();
    sphere([0.0; 3], 1.0, max, &mut c).unwrap();
    line("sphere -> CountingSink", c.faces, t);

    let t = start();
    let mut c = CountingSink::default();
    scan_like(max, 1, &ScanOptions::default(), &mut c).unwrap();
    line("scan_like -> CountingSink", c.faces, t);

    let t = start();
    let mut m = TriMesh::default();
    let d = scan_like(max, 1, &ScanOptions::default(), &mut m).unwrap();
    line("scan_like -> TriMesh", m.faces.len() as u64, t);

    let t = start();
    let r = mint_mesh::check(&m.positions, &m.faces);
    line("check", r.faces, t);
    assert_eq!(r.boundary_edges, d.expected.boundary_edges);

    let t = start();
    let bvh = mint_mesh::TriangleBvh::new(&m.positions, &m.faces).unwrap();
    line("TriangleBvh::new", bvh.len() as u64, t);

    let mut s = TriMesh::default();
    sphere([0.0; 3], 1.0, max / 10, &mut s).unwrap();
    let t = start();
    let dr = mint_mesh::distance_to_bvh((&s.positions, &s.faces), &bvh, 1_000_000, 1).unwrap();
    line("distance, 1M samples", m.faces.len() as u64, t);
    println!(
        "  mean {:.3e} max {:.3e} (noisy surface: far from A relative to B's triangles)",
        dr.mean, dr.max
    );
    drop(bvh);
    drop(m);

    let mut b = TriMesh::default();
    sphere([0.0; 3], 1.0, max, &mut b).unwrap();
    let t = start();
    let bvh = mint_mesh::TriangleBvh::new(&b.positions, &b.faces).unwrap();
    line("TriangleBvh::new (sphere)", bvh.len() as u64, t);
    let t = start();
    let dr = mint_mesh::distance_to_bvh((&s.positions, &s.faces), &bvh, 1_000_000, 1).unwrap();
    line("distance, 1M samples", b.faces.len() as u64, t);
    println!(
        "  mean {:.3e} max {:.3e} (same sphere, finer)",
        dr.mean, dr.max
    );
}
