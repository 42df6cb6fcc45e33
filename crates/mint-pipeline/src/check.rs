//! `mint check` within a memory budget: the same [`CheckReport`] as the
//! in-core [`mint_mesh::check()`], for meshes of any size.
//!
//! The in-core check classifies every edge and fan from each vertex's own
//! incident faces. Here those incidences come from disk instead of a table
//! in memory:
//! 1. **weld** (unless `--no-weld`): positions go to buckets by a hash of
//!    their bits; each bucket is sorted, and every vertex gets the smallest
//!    index at its position (`canonical`, kept only if something welds);
//! 2. **faces**, one ordered pass: per-face geometry in the in-core chunks
//!    (so volume and area are the same bits), a union-find over vertices
//!    for components, and each proper face's three corners `(v, a, b)` sent
//!    to the bucket of `v`'s block of vertices; collapsed faces' keys to
//!    their own buckets;
//! 3. **vertices**, block by block: the block's corners are grouped by
//!    vertex (a counting sort) and each vertex is judged by
//!    [`mint_mesh::check::scan_vertex`], the in-core code itself.
//!
//! Memory: per vertex a union-find parent (4 bytes), two bits, and 4 more
//! bytes when welding merges anything; per component its Euler
//! characteristic; per simple boundary vertex one edge; nothing per face or
//! per edge beyond the buckets, which spill to disk past `--mem`. The
//! positions are read through the file's memory map and are not counted.
//! One vertex's incident faces must fit in memory.

use crate::error::PipelineError;
use crate::progress::{Phase, Progress};
use mint_io::{MeshReader, ReadOptions, TriangleChunk, VertexPositions};
use mint_mesh::check::{fan_pair, is_collapsed, report_from, scan_vertex, union_smallest, Bbox, FaceGeom, TopologyCounts, Totals, VertexScratch, FACE_CHUNK};
use mint_mesh::weld::position_key;
use mint_mesh::CheckReport;
use mint_store::{Buckets, Record, StoreError};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Mutex;

/// Welding positions (units: vertices).
pub const WELD: Phase = Phase::named("check: weld");
/// Reading faces (units: faces).
pub const FACES: Phase = Phase::named("check: faces");
/// Judging vertices (units: vertex blocks).
pub const VERTICES: Phase = Phase::named("check: vertices");

/// Options of [`check_file`].
#[derive(Debug, Clone)]
pub struct CheckOptions {
    /// Heap budget in bytes (the buckets spill to disk beyond it; more
    /// than 512 MiB is not used: it only slows the check, measured).
    pub mem_bytes: u64,
    /// Weld vertices at identical positions first (as `mint check` does).
    pub weld: bool,
    /// Directory for spill files. Default: the system's temporary directory.
    pub tmp_dir: Option<PathBuf>,
    /// Worker threads (at least 1). The report is the same for any value.
    pub threads: usize,
    /// Also list up to this many boundary edges (for pictures). Default 0.
    pub list_boundary: usize,
}

/// What [`check_file`] reports beside the check itself.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct CheckStats {
    /// Bytes the buckets wrote to disk (0: everything fitted `--mem`).
    pub bytes_spilled: u64,
    pub vertex_blocks: u64,
    /// Up to `list_boundary` boundary edges `v → w` (welded vertex ids,
    /// which index the file's positions), smallest `v` first.
    #[serde(skip)]
    pub boundary: Vec<[u32; 2]>,
}

/// A corner `v → a → b` of a proper face, on its way to `v`'s block.
#[derive(Clone, Copy)]
struct Corner {
    v: u32,
    a: u32,
    b: u32,
}

impl Record for Corner {
    const SIZE: usize = 12;
    #[inline]
    fn put(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.v.to_le_bytes());
        out.extend_from_slice(&self.a.to_le_bytes());
        out.extend_from_slice(&self.b.to_le_bytes());
    }
    #[inline]
    fn get(b: &[u8]) -> Self {
        let w = |i: usize| u32::from_le_bytes(b[i..i + 4].try_into().unwrap());
        Corner { v: w(0), a: w(4), b: w(8) }
    }
}

/// A position's hash (of its weld key) and its vertex.
#[derive(Clone, Copy)]
struct Hashed {
    h: u64,
    v: u32,
}

impl Record for Hashed {
    const SIZE: usize = 12;
    #[inline]
    fn put(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.h.to_le_bytes());
        out.extend_from_slice(&self.v.to_le_bytes());
    }
    #[inline]
    fn get(b: &[u8]) -> Self {
        Hashed { h: u64::from_le_bytes(b[..8].try_into().unwrap()), v: u32::from_le_bytes(b[8..12].try_into().unwrap()) }
    }
}

/// A collapsed face's sorted indices.
#[derive(Clone, Copy)]
struct Triple([u32; 3]);

impl Record for Triple {
    const SIZE: usize = 12;
    #[inline]
    fn put(&self, out: &mut Vec<u8>) {
        for k in self.0 {
            out.extend_from_slice(&k.to_le_bytes());
        }
    }
    #[inline]
    fn get(b: &[u8]) -> Self {
        let w = |i: usize| u32::from_le_bytes(b[i..i + 4].try_into().unwrap());
        Triple([w(0), w(4), w(8)])
    }
}

/// A fixed-size bit set.
struct Bits(Vec<u64>);

impl Bits {
    fn new(n: usize) -> Bits {
        Bits(vec![0; n.div_ceil(64)])
    }
    #[inline]
    fn set(&mut self, i: u32) {
        self.0[i as usize / 64] |= 1 << (i % 64);
    }
    #[inline]
    fn get(&self, i: u32) -> bool {
        self.0[i as usize / 64] >> (i % 64) & 1 == 1
    }
}

fn mix(k: &[u64; 3]) -> u64 {
    let mut h = 0x9E37_79B9_7F4A_7C15u64;
    for &x in k {
        h = (h ^ x).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        h ^= h >> 31;
    }
    h
}

/// Checks the mesh in `path` within `opts.mem_bytes` of heap; see the
/// module docs. Returns the same report as reading the mesh whole, welding
/// it (when `opts.weld`) and calling [`mint_mesh::check()`].
pub fn check_file(path: &Path, opts: &CheckOptions, progress: &dyn Progress) -> Result<(CheckReport, CheckStats), PipelineError> {
    let tmp_root = opts.tmp_dir.clone().unwrap_or_else(std::env::temp_dir);
    let tmp = tempfile::Builder::new()
        .prefix(".mint-check-")
        .tempdir_in(&tmp_root)
        .map_err(|source| PipelineError::Temp { path: tmp_root.clone(), op: "creating the check's spill directory", source })?;
    let dir = tmp.path();
    let mut reader = MeshReader::open(path, ReadOptions { chunk_triangles: FACE_CHUNK, spill_dir: Some(dir.to_path_buf()), resolve_positions: false })?;
    let positions = reader.positions();
    let nv = positions.len();
    // Past about 512 MiB, more memory only slows the check: first-touch
    // page faults on the buckets, and vertex blocks too large for the
    // caches (100M faces: 9.7 s at 256M and 512M, 13 s at 1G, 14.5 s at
    // 5.9G); spilled buckets come back from the page cache anyway.
    let budget = opts.mem_bytes.clamp(16 << 20, 512 << 20);
    let mut stats = CheckStats::default();

    let trace = std::env::var_os("MINT_CHECK_TRACE").is_some();
    let t0 = std::time::Instant::now();
    let lap = |what: &str| {
        if trace {
            eprintln!("check: {what} at {:.2}s", t0.elapsed().as_secs_f64());
        }
    };
    // Bounding box over every position (welding never changes it).
    let mut bbox = Bbox::empty();
    for i in 0..nv {
        bbox.add(positions.get(i));
    }

    lap("bbox");
    // 1. Weld.
    let (canonical, welded) = if opts.weld { weld(&positions, dir, budget / 2, opts.threads.max(1), progress, &mut stats)? } else { (None, 0) };

    lap("weld");
    // 2. Faces.
    let threads = opts.threads.max(1);
    let block_vertices = {
        // Blocks of vertices whose corners fill about an eighth of the
        // budget per worker, at 12 bytes a corner and about six corners a
        // vertex.
        let per_block = (budget / 8 / threads as u64 / (12 * 6)).max(1 << 12);
        per_block.max((nv as u64).div_ceil(4096)).max(1)
    };
    let blocks = (nv as u64).div_ceil(block_vertices).max(1);
    stats.vertex_blocks = blocks;
    let id = |v: u32| canonical.as_ref().map_or(v, |c: &Vec<u32>| c[v as usize]);
    let sink = |n: usize, t: usize| Sink {
        corners: Buckets::new(dir, &format!("corners-{t}"), blocks as usize, budget / 2 / n as u64),
        collapsed: Buckets::new(dir, &format!("collapsed-{t}"), 64, budget / 16 / n as u64),
        block_vertices,
    };
    let records = reader.triangle_records()?;
    let mut pass = None;
    if let Some(records) = &records {
        match faces_direct(records, &id, &positions, threads, &sink, progress) {
            Ok(p) => pass = Some(p),
            // Polygons in a fixed-record file: read it as a stream.
            Err(PipelineError::Io(e)) if e.kind() == mint_io::ErrorKind::Unsupported => {}
            Err(e) => return Err(e),
        }
    }
    let pass = match pass {
        Some(p) => p,
        None => faces_streamed(&mut reader, &id, &positions, sink(1, 0), progress)?,
    };
    let FacePass { mut parent, referenced, has_collapsed, geom, nfaces, sinks } = pass;
    if nfaces > (u32::MAX / 3) as u64 {
        return Err(PipelineError::stage(path, format!("{nfaces} faces: `check` handles at most {} (u32 indices)", u32::MAX / 3)));
    }

    lap("faces");
    // Component labels, in place (parent[v] <= v), as in core.
    let mut next = 0u32;
    let mut nref = 0u64;
    for v in 0..nv {
        if !referenced.get(v) {
            parent[v as usize] = u32::MAX;
            continue;
        }
        nref += 1;
        let p = parent[v as usize] as usize;
        parent[v as usize] = if p == v as usize {
            next += 1;
            next - 1
        } else {
            parent[p]
        };
    }
    let labels = parent;
    let components = next as u64;
    let mut chi = vec![0i64; components as usize];
    let mut bad = vec![false; components as usize];
    for v in 0..nv {
        let l = labels[v as usize];
        if l != u32::MAX {
            chi[l as usize] += 1;
            bad[l as usize] |= has_collapsed.get(v);
        }
    }
    drop(has_collapsed);
    drop(referenced);

    // 3. Vertices, blocks in parallel.
    let mut corner_sets = Vec::new();
    let mut collapsed_sets = Vec::new();
    for s in sinks {
        let c = s.corners.finish();
        stats.bytes_spilled += c.bytes_spilled();
        corner_sets.push(Mutex::new(c));
        collapsed_sets.push(s.collapsed.finish());
    }
    let (counts, mut simple, mut boundary) = vertices(&corner_sets, &labels, nv, block_vertices, blocks, threads, opts.list_boundary, &mut chi, &mut bad, progress)?;
    simple.sort_unstable();
    boundary.sort_unstable();
    boundary.truncate(opts.list_boundary);
    stats.boundary = boundary;
    drop(corner_sets);

    lap("vertices");
    // Duplicates among collapsed faces: bucket b of every worker's set.
    let mut duplicate_collapsed = 0u64;
    for b in 0..64 {
        let mut keys: Vec<[u32; 3]> = Vec::new();
        for set in &mut collapsed_sets {
            stats.bytes_spilled += if b == 0 { set.bytes_spilled() } else { 0 };
            set.read(b, |batch| keys.extend(batch.iter().map(|t| t.0)))?;
        }
        keys.sort_unstable();
        duplicate_collapsed += keys.windows(2).filter(|p| p[0] == p[1]).count() as u64;
    }

    let mut report = report_from(Totals {
        vertices: nv as u64 - welded,
        faces: nfaces,
        referenced: nref,
        components,
        bbox,
        geom,
        counts,
        simple: &simple,
        chi: &chi,
        bad: &bad,
        duplicate_collapsed,
    });
    report.welded_vertices = welded;
    Ok((report, stats))
}

/// Where one worker's corners and collapsed faces go.
struct Sink {
    corners: Buckets<Corner>,
    collapsed: Buckets<Triple>,
    block_vertices: u64,
}

impl Sink {
    /// One face (welded indices): its corners, or its key if collapsed.
    #[inline]
    fn face(&mut self, f: [u32; 3]) -> Result<(), StoreError> {
        if is_collapsed(&f) {
            let mut k = f;
            k.sort_unstable();
            return self.collapsed.push((mix(&[k[0] as u64, k[1] as u64, k[2] as u64]) % 64) as usize, Triple(k));
        }
        for v in f {
            let (a, b) = fan_pair(&f, v);
            self.corners.push((v as u64 / self.block_vertices) as usize, Corner { v, a, b })?;
        }
        Ok(())
    }
}

/// What the pass over the faces leaves.
struct FacePass {
    parent: Vec<u32>,
    referenced: Bits,
    has_collapsed: Bits,
    geom: FaceGeom,
    nfaces: u64,
    sinks: Vec<Sink>,
}

/// The union-find side of one face (welded indices).
#[inline]
fn link(parent: &mut [u32], referenced: &mut Bits, has_collapsed: &mut Bits, f: [u32; 3]) {
    for v in f {
        referenced.set(v);
    }
    union_smallest(parent, f[0], f[1]);
    union_smallest(parent, f[0], f[2]);
    if is_collapsed(&f) {
        has_collapsed.set(f[0]);
    }
}

/// The faces of a file with fixed-size records: one thread runs the
/// union-find over all faces in order, while `threads` workers take chunks
/// of [`FACE_CHUNK`] faces for geometry (combined in chunk order) and
/// corners (each into its own buckets).
fn faces_direct(
    records: &mint_io::TriangleRecords,
    id: &(dyn Fn(u32) -> u32 + Sync),
    positions: &VertexPositions,
    threads: usize,
    sink: &(dyn Fn(usize, usize) -> Sink + Sync),
    progress: &dyn Progress,
) -> Result<FacePass, PipelineError> {
    let n = records.len();
    let nv = positions.len();
    let chunks = n.div_ceil(FACE_CHUNK as u64) as usize;
    let next = AtomicUsize::new(0);
    let stop = AtomicBool::new(false);
    let failed: Mutex<Option<PipelineError>> = Mutex::new(None);
    let geoms: Mutex<Vec<FaceGeom>> = Mutex::new(vec![FaceGeom::default(); chunks]);
    progress.start(FACES, n);
    let (uf, sinks) = std::thread::scope(|s| {
        let uf = s.spawn(|| -> Result<(Vec<u32>, Bits, Bits), PipelineError> {
            let mut parent: Vec<u32> = (0..nv).collect();
            let mut referenced = Bits::new(nv as usize);
            let mut has_collapsed = Bits::new(nv as usize);
            records.visit_indices(0, n, |_, t| link(&mut parent, &mut referenced, &mut has_collapsed, t.map(id)))?;
            Ok((parent, referenced, has_collapsed))
        });
        let workers: Vec<_> = (0..threads)
            .map(|w| {
                let (next, stop, failed, geoms) = (&next, &stop, &failed, &geoms);
                s.spawn(move || {
                    let mut out = sink(threads, w);
                    loop {
                        let c = next.fetch_add(1, Ordering::Relaxed);
                        if c >= chunks || stop.load(Ordering::Relaxed) {
                            return out;
                        }
                        let (a, b) = (c as u64 * FACE_CHUNK as u64, ((c + 1) as u64 * FACE_CHUNK as u64).min(n));
                        let mut g = FaceGeom::default();
                        let mut err = None;
                        let visited = records.visit_indices(a, b, |_, t| {
                            let f = t.map(id);
                            // The welded mesh's positions: each vertex's
                            // canonical one (-0.0 may have become 0.0).
                            g.add(&f, f.map(|v| positions.get(v)));
                            if err.is_none() {
                                err = out.face(f).err();
                            }
                        });
                        if let Some(e) = crate::passes::chunk_outcome(visited, err, progress) {
                            failed.lock().unwrap().get_or_insert(e);
                            stop.store(true, Ordering::Relaxed);
                            return out;
                        }
                        geoms.lock().unwrap()[c] = g;
                        progress.advance(b - a);
                    }
                })
            })
            .collect();
        let sinks: Vec<Sink> = workers.into_iter().map(|w| w.join().expect("check worker panicked")).collect();
        (uf.join().expect("union-find panicked"), sinks)
    });
    if let Some(e) = failed.into_inner().unwrap() {
        return Err(e);
    }
    let (parent, referenced, has_collapsed) = uf?;
    progress.finish();
    let geom = geoms.into_inner().unwrap().iter().fold(FaceGeom::default(), |acc, g| acc.then(g));
    Ok(FacePass { parent, referenced, has_collapsed, geom, nfaces: n, sinks })
}

/// The faces of any file, streamed in order by one thread.
fn faces_streamed(reader: &mut MeshReader, id: &dyn Fn(u32) -> u32, positions: &VertexPositions, mut out: Sink, progress: &dyn Progress) -> Result<FacePass, PipelineError> {
    let nv = positions.len();
    let mut parent: Vec<u32> = (0..nv).collect();
    let mut referenced = Bits::new(nv as usize);
    let mut has_collapsed = Bits::new(nv as usize);
    let mut geom = FaceGeom::default();
    let mut nfaces = 0u64;
    progress.start(FACES, reader.info().face_count.unwrap_or(0));
    let mut chunk = TriangleChunk::new();
    // Geometry is summed over FACE_CHUNK faces at a time, as in core.
    let mut g = FaceGeom::default();
    let mut in_chunk = 0usize;
    while reader.next_chunk(&mut chunk)? {
        for t in &chunk.indices {
            let f = t.map(id);
            g.add(&f, f.map(|v| positions.get(v)));
            in_chunk += 1;
            if in_chunk == FACE_CHUNK {
                geom = geom.then(&g);
                g = FaceGeom::default();
                in_chunk = 0;
            }
            link(&mut parent, &mut referenced, &mut has_collapsed, f);
            out.face(f)?;
        }
        nfaces += chunk.indices.len() as u64;
        progress.advance(chunk.indices.len() as u64);
        if progress.cancelled() {
            return Err(PipelineError::Cancelled);
        }
    }
    if in_chunk > 0 {
        geom = geom.then(&g);
    }
    progress.finish();
    Ok(FacePass { parent, referenced, has_collapsed, geom, nfaces, sinks: vec![out] })
}

/// Judges every vertex, blocks in parallel: each worker gathers a block's
/// corners from every set, groups them by vertex (a counting sort), and
/// scans each vertex; Euler characteristics and flags go to the vertex's
/// component. Returns the counts and the simple boundary edges (unsorted).
#[allow(clippy::too_many_arguments)]
fn vertices(
    sets: &[Mutex<mint_store::BucketReader<Corner>>],
    labels: &[u32],
    nv: u32,
    block_vertices: u64,
    blocks: u64,
    threads: usize,
    list_boundary: usize,
    chi: &mut [i64],
    bad: &mut [bool],
    progress: &dyn Progress,
) -> Result<(TopologyCounts, Vec<(u32, u32)>, Vec<[u32; 2]>), PipelineError> {
    let next = AtomicUsize::new(0);
    let stop = AtomicBool::new(false);
    let failed: Mutex<Option<PipelineError>> = Mutex::new(None);
    let shared = Mutex::new((chi, bad));
    progress.start(VERTICES, blocks);
    let parts: Vec<(TopologyCounts, Vec<(u32, u32)>, Vec<[u32; 2]>)> = std::thread::scope(|s| {
        let workers: Vec<_> = (0..threads)
            .map(|_| {
                let (next, stop, failed, shared) = (&next, &stop, &failed, &shared);
                s.spawn(move || {
                    let mut counts = TopologyCounts::default();
                    let mut simple = Vec::new();
                    let mut listed: Vec<[u32; 2]> = Vec::new();
                    let mut scratch = VertexScratch::default();
                    let (mut start, mut fans, mut records, mut deltas): (Vec<u32>, Vec<(u32, u32)>, Vec<Corner>, Vec<(u32, i64, bool)>) = Default::default();
                    loop {
                        let blk = next.fetch_add(1, Ordering::Relaxed) as u64;
                        if blk >= blocks || stop.load(Ordering::Relaxed) {
                            return (counts, simple, listed);
                        }
                        let v0 = (blk * block_vertices) as u32;
                        let v1 = ((blk + 1) * block_vertices).min(nv as u64) as u32;
                        let n = (v1 - v0) as usize;
                        records.clear();
                        for set in sets {
                            let bucket = set.lock().unwrap().take(blk as usize);
                            if let Err(e) = bucket.read(|batch| records.extend_from_slice(batch)) {
                                failed.lock().unwrap().get_or_insert(e.into());
                                stop.store(true, Ordering::Relaxed);
                                return (counts, simple, listed);
                            }
                        }
                        start.clear();
                        start.resize(n + 1, 0);
                        for c in &records {
                            start[(c.v - v0) as usize + 1] += 1;
                        }
                        for i in 0..n {
                            start[i + 1] += start[i];
                        }
                        fans.clear();
                        fans.resize(records.len(), (0, 0));
                        let mut at = start.clone();
                        for c in &records {
                            let s = &mut at[(c.v - v0) as usize];
                            fans[*s as usize] = (c.a, c.b);
                            *s += 1;
                        }
                        deltas.clear();
                        for i in 0..n {
                            let (s, e) = (start[i] as usize, start[i + 1] as usize);
                            if s == e {
                                continue;
                            }
                            let v = v0 + i as u32;
                            let t = scan_vertex(v, &fans[s..e], &mut scratch, &mut counts);
                            deltas.push((labels[v as usize], t.faces_here as i64 - t.edges_here as i64, t.bad));
                            if let Some(w) = t.simple_next {
                                simple.push((v, w));
                            }
                            // Each worker keeps its smallest; the caller
                            // sorts and keeps the smallest overall.
                            if listed.len() < list_boundary {
                                listed.extend(scratch.boundary_out.iter().map(|&w| [v, w]));
                            }
                        }
                        {
                            let mut g = shared.lock().unwrap();
                            for &(l, d, b) in &deltas {
                                g.0[l as usize] += d;
                                g.1[l as usize] |= b;
                            }
                        }
                        progress.advance(1);
                        if progress.cancelled() {
                            failed.lock().unwrap().get_or_insert(PipelineError::Cancelled);
                            stop.store(true, Ordering::Relaxed);
                            return (counts, simple, listed);
                        }
                    }
                })
            })
            .collect();
        workers.into_iter().map(|w| w.join().expect("check worker panicked")).collect()
    });
    if let Some(e) = failed.into_inner().unwrap() {
        return Err(e);
    }
    progress.finish();
    let mut counts = TopologyCounts::default();
    let mut simple = Vec::new();
    let mut listed = Vec::new();
    for (c, s, l) in parts {
        counts.add(&c);
        simple.extend(s);
        listed.extend(l);
    }
    Ok((counts, simple, listed))
}

/// Welds by position: each vertex's smallest index at its exact position
/// (finite positions only), or `None` when nothing welds; and how many
/// vertices were merged away. Workers hash their share of the vertices into
/// buckets of `(hash, vertex)`; then each bucket is sorted by hash, and
/// only vertices whose hashes collide are compared by position.
fn weld(positions: &VertexPositions, dir: &Path, budget: u64, threads: usize, progress: &dyn Progress, stats: &mut CheckStats) -> Result<(Option<Vec<u32>>, u64), PipelineError> {
    let nv = positions.len();
    // Buckets that each sort within an eighth of the budget.
    let nb = ((nv as u64 * 12).div_ceil((budget / 8).max(1))).clamp(1, 4096) as usize;
    progress.start(WELD, nv as u64);
    let per = nv.div_ceil(threads as u32).max(1);
    let sets: Vec<Result<mint_store::BucketReader<Hashed>, StoreError>> = std::thread::scope(|s| {
        let workers: Vec<_> = (0..threads as u32)
            .map(|t| {
                s.spawn(move || {
                    let mut keyed = Buckets::<Hashed>::new(dir, &format!("weld-{t}"), nb, budget / 2 / threads as u64);
                    for v in (t * per).min(nv)..((t + 1) * per).min(nv) {
                        let p = positions.get(v);
                        if p.iter().all(|c| c.is_finite()) {
                            let h = mix(&position_key(&p));
                            keyed.push((h % nb as u64) as usize, Hashed { h, v })?;
                        }
                    }
                    Ok(keyed.finish())
                })
            })
            .collect();
        workers.into_iter().map(|w| w.join().expect("weld worker panicked")).collect()
    });
    let mut sets: Vec<Mutex<mint_store::BucketReader<Hashed>>> = sets.into_iter().map(|r| r.map(Mutex::new)).collect::<Result<_, _>>()?;
    progress.finish();
    stats.bytes_spilled += sets.iter_mut().map(|m| m.get_mut().unwrap().bytes_spilled()).sum::<u64>();
    let next = AtomicUsize::new(0);
    let merges: Vec<Result<Vec<(u32, u32)>, StoreError>> = std::thread::scope(|s| {
        let workers: Vec<_> = (0..threads)
            .map(|_| {
                let (sets, next) = (&sets, &next);
                s.spawn(move || {
                    let mut merges = Vec::new();
                    let mut recs: Vec<Hashed> = Vec::new();
                    let mut run: Vec<([u64; 3], u32)> = Vec::new();
                    loop {
                        let b = next.fetch_add(1, Ordering::Relaxed);
                        if b >= nb {
                            return Ok(merges);
                        }
                        recs.clear();
                        for set in sets {
                            let bucket = set.lock().unwrap().take(b);
                            bucket.read(|batch| recs.extend_from_slice(batch))?;
                        }
                        recs.sort_unstable_by_key(|r| (r.h, r.v));
                        let mut g = 0;
                        while g < recs.len() {
                            let mut h = g + 1;
                            while h < recs.len() && recs[h].h == recs[g].h {
                                h += 1;
                            }
                            if h - g > 1 {
                                // Equal hashes: compare the positions themselves.
                                run.clear();
                                run.extend(recs[g..h].iter().map(|r| (position_key(&positions.get(r.v)), r.v)));
                                run.sort_unstable();
                                let mut i = 0;
                                while i < run.len() {
                                    let mut j = i + 1;
                                    while j < run.len() && run[j].0 == run[i].0 {
                                        merges.push((run[j].1, run[i].1));
                                        j += 1;
                                    }
                                    i = j;
                                }
                            }
                            g = h;
                        }
                    }
                })
            })
            .collect();
        workers.into_iter().map(|w| w.join().expect("weld worker panicked")).collect()
    });
    let mut canonical: Option<Vec<u32>> = None;
    let mut merged = 0u64;
    for m in merges {
        for (v, c) in m? {
            canonical.get_or_insert_with(|| (0..nv).collect())[v as usize] = c;
            merged += 1;
        }
    }
    Ok((canonical, merged))
}
