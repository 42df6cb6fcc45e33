//! Streaming read benchmark. Writes (if absent) a binary little-endian PLY
//! grid mesh of about `TRIANGLES` triangles (float x y z, `list uchar int`
//! faces) to `FILE`, then reads it back single-threaded several times and
//! prints one line per run: triangles/s and MB/s, with positions resolved
//! and without. Usage: `bench_read FILE [TRIANGLES] [RUNS]`
//! (default 10_000_000 triangles, 5 runs).
use std::path::Path;
use std::time::Instant;

use mint_io::{Format, MeshReader, MeshWriter, ReadOptions, TriangleChunk, WriteOptions};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let path = Path::new(args.get(1).ok_or("usage: bench_read FILE [TRIANGLES] [RUNS]")?);
    let tris: u64 = args.get(2).map_or(Ok(10_000_000), |s| s.parse())?;
    let runs: usize = args.get(3).map_or(Ok(5), |s| s.parse())?;
    if !path.exists() {
        // A square grid of n x n vertices has 2 (n-1)^2 triangles.
        let n = ((tris as f64 / 2.0).sqrt().ceil() as u32) + 1;
        let t = Instant::now();
        let mut w = MeshWriter::create(path, Format::Ply, WriteOptions::default())?;
        for j in 0..n {
            for i in 0..n {
                let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
                w.write_vertex([x, y, (x * 7.0).sin() * (y * 5.0).cos() * 0.1])?;
            }
        }
        for j in 0..n - 1 {
            for i in 0..n - 1 {
                let v = j * n + i;
                w.write_face([v, v + 1, v + n + 1])?;
                w.write_face([v, v + n + 1, v + n])?;
            }
        }
        let s = w.finish()?;
        println!("wrote {}: {} vertices, {} triangles, {} bytes in {:.2} s", path.display(), s.vertices, s.faces, s.bytes, t.elapsed().as_secs_f64());
    }
    let bytes = std::fs::metadata(path)?.len() as f64;
    for resolve in [true, false] {
        for run in 0..runs {
            let t = Instant::now();
            let mut r = MeshReader::open(path, ReadOptions { resolve_positions: resolve, ..ReadOptions::default() })?;
            let mut chunk = TriangleChunk::new();
            let mut n = 0u64;
            let mut check = 0.0f64;
            while r.next_chunk(&mut chunk)? {
                n += chunk.len() as u64;
                if let Some(p) = chunk.positions.last() {
                    check += p[2][0];
                }
            }
            let s = t.elapsed().as_secs_f64();
            println!(
                "read {} resolve_positions={resolve} run {run}: {n} triangles in {s:.3} s = {:.1} Mtri/s, {:.0} MB/s (check {check:.3})",
                path.display(),
                n as f64 / s / 1e6,
                bytes / s / 1e6
            );
        }
    }
    Ok(())
}
