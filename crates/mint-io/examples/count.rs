//! Reads mesh files completely and prints one line per file: vertices,
//! triangles, reader counters and time. Usage: `count FILE...`
use std::path::Path;
use std::time::Instant;

use mint_io::{MeshReader, ReadOptions, TriangleChunk};

fn main() {
    for arg in std::env::args().skip(1) {
        let t = Instant::now();
        let r = MeshReader::open(Path::new(&arg), ReadOptions::default()).and_then(|mut r| {
            let mut chunk = TriangleChunk::new();
            while r.next_chunk(&mut chunk)? {}
            Ok(r)
        });
        match r {
            Ok(r) => {
                let grid = r.range_grid().map(|g| format!(" grid {}x{} filled {}", g.cols, g.rows, g.filled())).unwrap_or_default();
                println!("{arg}: {} vertices, {:?}{grid} in {:.3} s", r.vertex_count(), r.stats(), t.elapsed().as_secs_f64());
            }
            Err(e) => println!("{e}"),
        }
    }
}
