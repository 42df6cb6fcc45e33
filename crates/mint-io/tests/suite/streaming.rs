//! Streaming at scale: a procedurally generated 1600 x 1600 vertex grid
//! (2 * 1599^2 = 5,113,602 triangles, about 95 MB of binary PLY) is streamed
//! into a `MeshWriter` and read back chunk by chunk, every index and
//! position compared with the generator. Then the same file is read again
//! in a child process under `prlimit --data` (RLIMIT_DATA, which counts
//! heap but not file mappings) of 48 MiB: holding the faces alone would
//! need 61 MB of indices, so the read passes only if memory does not grow
//! with the face count. The child first checks that the limit is real by
//! failing to reserve 64 MiB.
use std::path::Path;

use mint_io::{Format, MeshReader, MeshWriter, ReadOptions, TriangleChunk, WriteOptions};

use super::util::run_child_under_prlimit;

const N: u32 = 1600;
const TRIANGLES: u64 = 2 * (N as u64 - 1) * (N as u64 - 1);

fn vertex(i: u32) -> [f64; 3] {
    let (x, y) = ((i % N) as f64, (i / N) as f64);
    // Exact in f32: multiples of 1/4 below 2^20.
    [x * 0.25, y * 0.5, ((i % 7) as f64) * 0.25]
}

/// Triangle `t` of the grid: two per cell, cells in row-major order.
fn triangle(t: u64) -> [u32; 3] {
    let cell = (t / 2) as u32;
    let v = (cell / (N - 1)) * N + cell % (N - 1);
    if t & 1 == 0 {
        [v, v + 1, v + N + 1]
    } else {
        [v, v + N + 1, v + N]
    }
}

fn write_grid(path: &Path) {
    let mut w = MeshWriter::create(path, Format::Ply, WriteOptions::default()).unwrap();
    for i in 0..N * N {
        w.write_vertex(vertex(i)).unwrap();
    }
    for t in 0..TRIANGLES {
        w.write_face(triangle(t)).unwrap();
    }
    let s = w.finish().unwrap();
    assert_eq!((s.vertices, s.faces), ((N * N) as u64, TRIANGLES));
}

/// Reads the grid back and compares; returns the number of chunks.
fn read_and_compare(path: &Path) -> u64 {
    let mut r = MeshReader::open(path, ReadOptions::default()).unwrap();
    assert_eq!(r.vertex_count(), N * N);
    assert_eq!(r.stats().spilled_vertices, 0, "binary positions are read in place");
    let mut chunk = TriangleChunk::new();
    let (mut t, mut chunks) = (0u64, 0u64);
    let mut last_done = 0;
    while r.next_chunk(&mut chunk).unwrap() {
        assert!(chunk.len() <= 65536);
        for (f, p) in chunk.indices.iter().zip(&chunk.positions) {
            let want = triangle(t);
            assert_eq!(*f, want, "triangle {t}");
            assert_eq!(*p, want.map(vertex), "triangle {t}");
            t += 1;
        }
        assert!(r.bytes_done() >= last_done);
        last_done = r.bytes_done();
        chunks += 1;
    }
    assert_eq!(t, TRIANGLES);
    assert_eq!(r.bytes_done(), r.bytes_total());
    chunks
}

const CHILD_FILE: &str = "MINT_IO_TEST_GRID_FILE";

#[test]
fn five_million_triangles_stream_in_bounded_memory() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("grid.ply");
    write_grid(&path);
    let head = std::fs::read(&path).unwrap().windows(11).position(|w| w == b"end_header\n").unwrap() as u64 + 11;
    assert_eq!(std::fs::metadata(&path).unwrap().len(), head + (N * N) as u64 * 12 + TRIANGLES * 13, "header + vertices + faces");
    assert_eq!(read_and_compare(&path), TRIANGLES.div_ceil(65536));
    let Some(o) = run_child_under_prlimit("suite::streaming::child_read_grid_under_data_limit", &["--data=50331648"], &[(CHILD_FILE, &path)]) else {
        return;
    };
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success() && stdout.contains("CHILD-OK"), "child failed: {:?}\n{stdout}\n{}", o.status, String::from_utf8_lossy(&o.stderr));
}

/// Run by the test above under RLIMIT_DATA = 48 MiB.
#[test]
#[ignore = "run as a child process under prlimit by five_million_triangles_stream_in_bounded_memory"]
fn child_read_grid_under_data_limit() {
    let Some(path) = std::env::var_os(CHILD_FILE) else { return };
    // The limit is in force: 64 MiB of heap cannot be had.
    assert!(Vec::<u8>::new().try_reserve_exact(64 << 20).is_err(), "RLIMIT_DATA is not in force");
    read_and_compare(Path::new(&path));
    println!("CHILD-OK");
}
