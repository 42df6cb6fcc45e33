//! The floor under resampling a fixed-record file: every triangle visited
//! with its three positions resolved (`TriangleRecords::visit`, the path
//! `mint resample` takes, with its prefetching and checks), and nothing
//! done with them but a sum. On a mesh whose vertices are in no spatial
//! order this is the cost of the random gathers alone, which no amount of
//! work on discretization can go below.
//!
//! Usage: `gather_floor FILE [THREADS] [RUNS]` (default 2 threads, 3 runs).
//! Prints one line per run: seconds and million triangles per second.
use std::path::Path;
use std::time::Instant;

use mint_io::{MeshReader, ReadOptions};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let path = Path::new(args.get(1).ok_or("usage: gather_floor FILE [THREADS] [RUNS]")?);
    let threads: u64 = args.get(2).map_or(Ok(2), |s| s.parse())?;
    let runs: usize = args.get(3).map_or(Ok(3), |s| s.parse())?;
    let reader = MeshReader::open(path, ReadOptions::default())?;
    let records = reader.triangle_records()?.ok_or("the file's faces are not fixed-size records")?;
    let n = records.len();
    for run in 0..runs {
        let t = Instant::now();
        let sums: Vec<f64> = std::thread::scope(|s| {
            let workers: Vec<_> = (0..threads)
                .map(|k| {
                    let records = &records;
                    s.spawn(move || {
                        // Chunks handed out in turn, as resample does.
                        let chunk = 64 * 1024;
                        let mut sum = 0.0f64;
                        let mut c = k * chunk;
                        while c < n {
                            records.visit(c, (c + chunk).min(n), &mut |p: &[[f64; 3]; 3]| sum += p[0][0] + p[1][1] + p[2][2]).expect("visit");
                            c += threads * chunk;
                        }
                        sum
                    })
                })
                .collect();
            workers.into_iter().map(|w| w.join().expect("worker")).collect()
        });
        let s = t.elapsed().as_secs_f64();
        println!("gather {} threads={threads} run {run}: {n} triangles in {s:.3} s = {:.1} Mtri/s (check {:.3})", path.display(), n as f64 / s / 1e6, sums.iter().sum::<f64>());
    }
    Ok(())
}
