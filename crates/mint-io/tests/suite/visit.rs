//! The direct record path (`TriangleRecords::visit`) against the streaming
//! reader: every triangle of a mesh whose vertices and faces are shuffled
//! (so that prefetching has work to do), with the corner prefetch on and
//! off and the finiteness check on and off, over ranges that start and end
//! anywhere, for f32 and f64 positions; and a NaN position, reported unless
//! the caller said every position is finite.
use mint_core::TriMesh;
use mint_io::{Format, MeshReader, ReadOptions, TriangleVisitor, WriteOptions};

use super::util::{ply_bytes, read, soup, write, write_file, El, V};

/// A `n` x `n` vertex grid bent into a bowl, its vertices and faces in an
/// order unrelated to space (a fixed 64-bit LCG, Fisher-Yates).
fn shuffled_grid(n: u32) -> TriMesh {
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = |bound: usize| {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((state >> 33) as usize) % bound
    };
    let nv = (n * n) as usize;
    let mut order: Vec<u32> = (0..nv as u32).collect();
    for i in (1..nv).rev() {
        order.swap(i, next(i + 1));
    }
    let mut slot = vec![0u32; nv];
    for (new, &old) in order.iter().enumerate() {
        slot[old as usize] = new as u32;
    }
    let positions = order
        .iter()
        .map(|&v| {
            let (x, y) = ((v % n) as f64 / n as f64, (v / n) as f64 / n as f64);
            [x, y, 0.1 + x * x + y * y / 3.0]
        })
        .collect();
    let mut faces = Vec::new();
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let v = |i: u32, j: u32| slot[(j * n + i) as usize];
            faces.push([v(i, j), v(i + 1, j), v(i + 1, j + 1)]);
            faces.push([v(i, j), v(i + 1, j + 1), v(i, j + 1)]);
        }
    }
    for i in (1..faces.len()).rev() {
        faces.swap(i, next(i + 1));
    }
    TriMesh { positions, faces }
}

#[test]
fn visiting_records_gives_the_streamed_triangles_with_and_without_prefetch() {
    let d = tempfile::tempdir().unwrap();
    let m = shuffled_grid(300);
    for double in [false, true] {
        let path = d.path().join(format!("grid-{double}.ply"));
        write(&path, Format::Ply, WriteOptions { double, ..WriteOptions::default() }, &m);
        let want = soup(&read(&path));
        let reader = MeshReader::open(&path, ReadOptions::default()).unwrap();
        let mut records = reader.triangle_records().unwrap().expect("binary PLY triangles are fixed records");
        assert_eq!(records.len(), want.len() as u64);
        for (prefetch, known) in [(true, false), (false, false), (true, true), (false, true)] {
            records.set_prefetch(prefetch);
            records.set_positions_known_finite(known);
            // Whole, then in uneven steps whose look-ahead crosses each end.
            for step in [u64::MAX, 1, 31, 4097] {
                let mut got = Vec::with_capacity(want.len());
                let mut at = 0;
                while at < records.len() {
                    let to = at.saturating_add(step).min(records.len());
                    records.visit(at, to, &mut |p: &[[f64; 3]; 3]| got.push(*p)).unwrap();
                    at = to;
                }
                assert!(got == want, "double {double}, prefetch {prefetch}, known finite {known}, step {step}: other triangles");
            }
        }
    }
}

#[test]
fn a_nan_position_is_reported_unless_the_caller_vouched_for_every_position() {
    let d = tempfile::tempdir().unwrap();
    let path = d.path().join("nan.ply");
    write(&path, Format::Ply, WriteOptions::default(), &shuffled_grid(20));
    // The writer refuses NaN: patch vertex 7's y in the file.
    let mut bytes = std::fs::read(&path).unwrap();
    let body = bytes.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    bytes[body + 7 * 12 + 4..body + 7 * 12 + 8].copy_from_slice(&f32::NAN.to_le_bytes());
    std::fs::write(&path, &bytes).unwrap();
    let reader = MeshReader::open(&path, ReadOptions::default()).unwrap();
    let mut records = reader.triangle_records().unwrap().unwrap();
    let mut seen = 0;
    let e = records.visit(0, records.len(), &mut |_: &[[f64; 3]; 3]| seen += 1).unwrap_err();
    assert_eq!(e.kind(), mint_io::ErrorKind::Value, "{e}");
    assert!(e.to_string().contains("vertex 7"), "{e}");
    records.set_positions_known_finite(true);
    let mut nan = 0;
    records.visit(0, records.len(), &mut |p: &[[f64; 3]; 3]| nan += p.iter().flatten().any(|c| c.is_nan()) as usize).unwrap();
    assert!(nan > 0 && seen < records.len() as usize);
}

/// A visitor that takes the raw f32 windows itself and records which
/// method each triangle came through.
#[derive(Default)]
struct Raw {
    tris: Vec<[[f64; 3]; 3]>,
    raw: usize,
}

impl TriangleVisitor for Raw {
    fn triangle(&mut self, p: &[[f64; 3]; 3]) {
        self.tris.push(*p);
    }
    fn triangle_f32le(&mut self, raw: &[[u8; 16]; 3]) {
        let f = |r: &[u8; 16], o: usize| f32::from_le_bytes(r[o..o + 4].try_into().unwrap()) as f64;
        self.tris.push(raw.each_ref().map(|r| [f(r, 0), f(r, 4), f(r, 8)]));
        self.raw += 1;
    }
}

/// Vouched-for packed f32 positions come as raw windows with the streamed
/// values, up to the last vertex; where the last vertex ends the file (its
/// window would run past the map: faces before vertices), they come as
/// converted triangles instead, and the same.
#[test]
fn raw_f32_windows_give_the_same_triangles_and_never_run_past_the_file() {
    let d = tempfile::tempdir().unwrap();
    let m = shuffled_grid(40);
    let verts: Vec<Vec<V>> = m.positions.iter().map(|p| p.iter().map(|&c| V::N(c)).collect()).collect();
    let faces: Vec<Vec<V>> = m.faces.iter().map(|f| vec![V::L(f.iter().map(|&i| i as f64).collect())]).collect();
    let vertex = || El { name: "vertex", props: &["float x", "float y", "float z"], records: verts.clone() };
    let face = || El { name: "face", props: &["list uchar int vertex_indices"], records: faces.clone() };
    for (name, vertices_last) in [("vf.ply", false), ("fv.ply", true)] {
        let els = if vertices_last { [face(), vertex()] } else { [vertex(), face()] };
        let path = write_file(d.path(), name, &ply_bytes("binary_little_endian", &[], &els));
        let want = soup(&read(&path));
        let reader = MeshReader::open(&path, ReadOptions::default()).unwrap();
        let mut records = reader.triangle_records().unwrap().unwrap();
        records.set_positions_known_finite(true);
        let mut v = Raw::default();
        records.visit(0, records.len(), &mut v).unwrap();
        assert!(v.tris == want, "{name}: other triangles");
        assert_eq!(v.raw, if vertices_last { 0 } else { want.len() }, "{name}: raw windows");
    }
}
