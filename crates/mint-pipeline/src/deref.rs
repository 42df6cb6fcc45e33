//! Dereferencing: how each face's three vertex indices become positions.
//!
//! `mmap` fetches the three positions of every face from the memory-mapped
//! vertex array. That is free when neighbouring faces use neighbouring
//! vertices, and ruinous when they do not: in a mesh whose vertices are in
//! no spatial order every corner is a cache miss, and once the vertex array
//! is larger than the page cache, a random disk read.
//!
//! `sort` is Lindstrom & Silva's answer (2001, "A memory insensitive
//! technique for large model simplification"), done by distribution rather
//! than by comparison, since the keys are dense integers:
//! 1. **scatter**: stream the faces; send each corner `(vertex, block,
//!    corner)` to the bucket of its vertex's block of vertices (a block is
//!    small enough to stay in cache);
//! 2. **join**: for each vertex block in order, copy its positions (one
//!    sequential read of the vertex array in all) and send every corner's
//!    position to the bucket of its face block;
//! 3. **assemble**: workers take face blocks, place each corner's position
//!    into the block's triangle array, and discretize the block chunk by
//!    chunk, exactly as the direct path does.
//!
//! Buckets stay in memory while they fit the budget and spill to files in a
//! temporary directory otherwise ([`mint_store::Buckets`]); all I/O is
//! sequential. Faces keep their order and chunks their boundaries, so the
//! per-chunk volumes and the output bytes are those of `mmap`.
//!
//! [`choose`] decides for `auto`: `sort` when a sample of the faces shows
//! poor locality and the positions will not stay in memory, `mmap`
//! otherwise; the summary says which ran and why.

use crate::error::PipelineError;
use crate::discretize::{discretize_on_pool, CHUNK_TRIANGLES};
use crate::kernels::{discretize_slice, LocalMap};
use crate::progress::{Phase, Progress};
use mint_core::grid::Grid;
use mint_core::primitives::Transform;
use mint_io::{MeshReader, TriangleChunk, TriangleRecords, VertexPositions};
use mint_store::{BucketReader, Buckets, Record, ShardWriter, StoreError};
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::sync::Mutex;

/// Scattering corners to vertex blocks (units: faces).
pub const SCATTER: Phase = Phase::named("dereference: scatter");
/// Joining corners with the vertex array (units: vertex blocks).
pub const JOIN: Phase = Phase::named("dereference: join");
/// Assembling and discretizing face blocks (units: faces).
pub const ASSEMBLE: Phase = Phase::named("discretize");

mint_core::choice! {
    /// How face corners are resolved to positions (`--deref`).
    pub enum Deref {
        /// `sort` when sampled locality is poor and the positions are larger
        /// than a cache; `mmap` otherwise.
        Auto => "auto",
        /// Fetch positions from the mapped vertex array.
        Mmap => "mmap",
        /// Lindstrom–Silva external dereferencing (see the module docs).
        Sort => "sort",
    }
}

impl Default for Deref {
    fn default() -> Self {
        Deref::Auto
    }
}

/// What ran, and why (reported in the summary).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DerefChoice {
    pub sort: bool,
    pub reason: String,
}

/// Positions at most this large are fetched from the map whatever their
/// order: they stay in the processor's caches.
const CACHE_SIZED: u64 = 32 << 20;
/// More distinct 4 KiB pages of positions per face than this is poor
/// locality (an ordered mesh touches a few pages per window; a shuffled
/// one about three per face).
const POOR_PAGES_PER_FACE: f64 = 0.25;
/// Bytes of positions per vertex block (one block is joined at a time and
/// should stay in cache).
const BLOCK_BYTES: u64 = 1 << 20;
/// Most buckets of either kind.
const MAX_BUCKETS: u64 = 4096;

/// Decides how to dereference faces `range` of `records` (`None`: a format
/// that streams, whose locality is not sampled).
///
/// `sort` costs more than `mmap` whenever the positions stay in memory,
/// even in no order (measured on a shuffled 100M-face torus: 4.5 s against
/// 14 s warm; see docs/PERFORMANCE.md): random reads from RAM are cheaper
/// than writing and reading every corner twice. It wins, by orders of
/// magnitude, once the positions do not stay in memory: then every corner
/// is a random disk read. So `auto` sorts when sampled locality is poor
/// and the positions are larger than three quarters of the memory this
/// process may use for the page cache ([`cache_room`]), leaving the rest to
/// the streaming faces and the heap (measured: a 600 MB vertex array runs
/// well by map in a 1 GiB cgroup, 4.7 s, and not at all in 400 MiB, over
/// 200 s, where the sort takes 31 s).
pub(crate) fn choose(mode: Deref, records: Option<&TriangleRecords>, positions: &VertexPositions, range: (u64, u64)) -> DerefChoice {
    match mode {
        Deref::Mmap => return DerefChoice { sort: false, reason: "asked for (--deref mmap)".into() },
        Deref::Sort => return DerefChoice { sort: true, reason: "asked for (--deref sort)".into() },
        Deref::Auto => {}
    }
    let bytes = positions.stored_bytes();
    if bytes <= CACHE_SIZED {
        return DerefChoice { sort: false, reason: format!("the positions ({}) fit in cache", mib(bytes)) };
    }
    let room = cache_room();
    if bytes <= room / 4 * 3 {
        return DerefChoice { sort: false, reason: format!("the positions ({}) stay in memory ({} available)", mib(bytes), mib(room)) };
    }
    let Some(records) = records else {
        return DerefChoice { sort: true, reason: format!("the positions ({}) are larger than 3/4 of the memory available ({}), and this format's locality is not sampled", mib(bytes), mib(room)) };
    };
    let pages = records.pages_per_face(positions, range);
    if pages > POOR_PAGES_PER_FACE {
        DerefChoice { sort: true, reason: format!("poor vertex locality ({pages:.2} pages of positions per face, sampled) and positions ({}) larger than 3/4 of the memory available ({})", mib(bytes), mib(room)) }
    } else {
        DerefChoice { sort: false, reason: format!("good vertex locality ({pages:.3} pages of positions per face, sampled)") }
    }
}

/// Memory the page cache may give this process: `MemAvailable`, or less
/// under a cgroup memory limit (v2 `memory.max`, v1
/// `memory.limit_in_bytes`). `u64::MAX` when unknown.
fn cache_room() -> u64 {
    let read = |p: &str| std::fs::read_to_string(p).ok();
    let num = |s: Option<String>| s.and_then(|s| s.trim().parse::<u64>().ok());
    let mut room = read("/proc/meminfo")
        .and_then(|s| s.lines().find(|l| l.starts_with("MemAvailable:"))?.split_whitespace().nth(1)?.parse::<u64>().ok())
        .map_or(u64::MAX, |kb| kb * 1024);
    if let Some(cg) = read("/proc/self/cgroup") {
        for line in cg.lines() {
            let mut f = line.splitn(3, ':');
            let (_, ctrl, path) = (f.next(), f.next().unwrap_or(""), f.next().unwrap_or(""));
            let limit = if ctrl.is_empty() {
                num(read(&format!("/sys/fs/cgroup{path}/memory.max")))
            } else if ctrl.split(',').any(|c| c == "memory") {
                num(read(&format!("/sys/fs/cgroup/memory{path}/memory.limit_in_bytes")))
            } else {
                continue;
            };
            if let Some(l) = limit {
                room = room.min(l);
            }
        }
    }
    room
}

fn mib(b: u64) -> String {
    format!("{:.0} MiB", b as f64 / (1u64 << 20) as f64)
}

/// Where the faces come from.
pub(crate) enum Faces<'a> {
    /// Fixed-size records `first .. end`; chunks are [`CHUNK_TRIANGLES`]
    /// records from `first`.
    Records { records: &'a TriangleRecords, first: u64, end: u64 },
    /// A streaming reader; each chunk it returns is one chunk.
    Reader(&'a mut MeshReader),
}

/// A corner on its way to its vertex block: its vertex's place in the
/// block (low 20 bits) and its face block (high 12 bits), and the corner's
/// number in its face block (`3 * face + k`). Eight bytes.
#[derive(Clone, Copy)]
struct Corner {
    v_block: u32,
    corner: u32,
}

/// Bits of [`Corner::v_block`] for the vertex's place in its block.
const V_BITS: u32 = 20;

impl Record for Corner {
    const SIZE: usize = 8;
    #[inline]
    fn put(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.v_block.to_le_bytes());
        out.extend_from_slice(&self.corner.to_le_bytes());
    }
    #[inline]
    fn get(b: &[u8]) -> Self {
        let w = |i: usize| u32::from_le_bytes(b[i..i + 4].try_into().unwrap());
        Corner { v_block: w(0), corner: w(4) }
    }
}

/// A coordinate as the sort stores it: `f32` when the file stores nothing
/// wider (exact), `f64` otherwise.
trait Coord: Copy + Send + Sync + 'static {
    const SIZE: usize;
    fn from_f64(x: f64) -> Self;
    fn to_f64(self) -> f64;
    fn put(self, out: &mut Vec<u8>);
    fn get(b: &[u8]) -> Self;
}

impl Coord for f32 {
    const SIZE: usize = 4;
    #[inline]
    fn from_f64(x: f64) -> Self {
        x as f32
    }
    #[inline]
    fn to_f64(self) -> f64 {
        self as f64
    }
    #[inline]
    fn put(self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_le_bytes());
    }
    #[inline]
    fn get(b: &[u8]) -> Self {
        f32::from_le_bytes(b[..4].try_into().unwrap())
    }
}

impl Coord for f64 {
    const SIZE: usize = 8;
    #[inline]
    fn from_f64(x: f64) -> Self {
        x
    }
    #[inline]
    fn to_f64(self) -> f64 {
        self
    }
    #[inline]
    fn put(self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_le_bytes());
    }
    #[inline]
    fn get(b: &[u8]) -> Self {
        f64::from_le_bytes(b[..8].try_into().unwrap())
    }
}

/// A corner with its position, on its way to its face block.
#[derive(Clone, Copy)]
struct Resolved<C: Coord> {
    corner: u32,
    p: [C; 3],
}

impl<C: Coord> Record for Resolved<C> {
    const SIZE: usize = 4 + 3 * C::SIZE;
    #[inline]
    fn put(&self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.corner.to_le_bytes());
        for c in self.p {
            c.put(out);
        }
    }
    #[inline]
    fn get(b: &[u8]) -> Self {
        Resolved { corner: u32::from_le_bytes(b[..4].try_into().unwrap()), p: [0, 1, 2].map(|k| C::get(&b[4 + k * C::SIZE..])) }
    }
}

impl<C: Coord> Resolved<C> {
    #[inline]
    fn new(corner: u32, p: [f64; 3]) -> Self {
        Resolved { corner, p: p.map(C::from_f64) }
    }
    #[inline]
    fn pos(&self) -> [f64; 3] {
        self.p.map(C::to_f64)
    }
}

/// What a sorted dereference did, for the summary.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct SortStats {
    pub vertex_blocks: u64,
    pub face_blocks: u64,
    /// Bytes the buckets wrote to disk (0: everything fitted the budget).
    pub bytes_spilled: u64,
}

/// Face blocks: consecutive chunks, at most `max_faces` faces each (but at
/// least one chunk). `chunks[i]` is chunk `i`'s face count.
struct Blocks {
    /// Per block: its first chunk, one past its last chunk, its first face.
    spans: Vec<(usize, usize, u64)>,
    /// Chunk face counts.
    chunks: Vec<u32>,
    faces_in_open: u64,
    max_faces: u64,
}

impl Blocks {
    fn new(max_faces: u64) -> Blocks {
        Blocks { spans: Vec::new(), chunks: Vec::new(), faces_in_open: 0, max_faces }
    }

    /// Adds a chunk of `n` faces; returns its block and the block-local
    /// number of its first face.
    fn add_chunk(&mut self, n: u32, first_face: u64) -> (u32, u64) {
        let ci = self.chunks.len();
        self.chunks.push(n);
        match self.spans.last_mut() {
            Some(last) if self.faces_in_open + n as u64 <= self.max_faces => {
                last.1 = ci + 1;
                let at = self.faces_in_open;
                self.faces_in_open += n as u64;
                (self.spans.len() as u32 - 1, at)
            }
            _ => {
                self.spans.push((ci, ci + 1, first_face));
                self.faces_in_open = n as u64;
                (self.spans.len() as u32 - 1, 0)
            }
        }
    }
}

/// Discretizes every face of `faces` into `store`, dereferencing by sorting
/// (see the module docs), with about `budget` bytes of heap and spill files
/// under `spill_dir`. Returns the faces read, six times the signed volume
/// of each chunk (as the direct and streaming paths return them), and what
/// the sort did.
#[allow(clippy::too_many_arguments)]
pub(crate) fn discretize_sorted(
    faces: Faces,
    positions: &VertexPositions,
    grid: &Grid,
    store: &mut ShardWriter,
    threads: usize,
    progress: &dyn Progress,
    xf: Option<&Transform>,
    spill_dir: &Path,
    budget: &mint_store::Budget,
) -> Result<(u64, Vec<f64>, SortStats), PipelineError> {
    let tmp = tempfile::Builder::new()
        .prefix(".mint-deref-")
        .tempdir_in(spill_dir)
        .map_err(|source| PipelineError::Temp { path: spill_dir.to_path_buf(), op: "creating the dereference spill directory", source })?;
    let threads = threads.max(1);
    let nv = positions.len() as u64;
    let job = |per_vertex: u64| {
        // Vertex blocks stay in cache (and a vertex's place in its block
        // fits V_BITS).
        let block_vertices = (BLOCK_BYTES / per_vertex).min(1 << V_BITS).max(nv.div_ceil(MAX_BUCKETS)).max(1);
        SortJob { positions, grid, threads, progress, xf, dir: tmp.path(), budget, nv, block_vertices, vertex_blocks: nv.div_ceil(block_vertices).max(1) }
    };
    if positions.exact_in_f32() {
        run::<f32>(faces, store, &job(3 * f32::SIZE as u64))
    } else {
        run::<f64>(faces, store, &job(3 * f64::SIZE as u64))
    }
}

/// What every step of one sorted dereference shares.
struct SortJob<'a> {
    positions: &'a VertexPositions,
    grid: &'a Grid,
    threads: usize,
    progress: &'a dyn Progress,
    xf: Option<&'a Transform>,
    /// The spill directory.
    dir: &'a Path,
    budget: &'a mint_store::Budget,
    nv: u64,
    /// Vertices per vertex block, and the blocks.
    block_vertices: u64,
    vertex_blocks: u64,
}

/// The three steps of a sorted dereference, in order: scatter, join,
/// assemble (see the module docs).
fn run<C: Coord>(faces: Faces, store: &mut ShardWriter, job: &SortJob) -> Result<(u64, Vec<f64>, SortStats), PipelineError> {
    let trace = std::env::var_os("MINT_DEREF_TRACE").is_some();
    let t0 = std::time::Instant::now();
    let (blocks, scatter, nfaces) = scatter_corners(faces, job)?;
    if trace {
        eprintln!("deref: scatter {:.2}s ({} vertex blocks of {}, {} face blocks)", t0.elapsed().as_secs_f64(), job.vertex_blocks, job.block_vertices, blocks.spans.len());
    }
    let t0 = std::time::Instant::now();
    let (gather, spilled) = join_blocks::<C>(scatter, &blocks, job)?;
    let stats = SortStats { vertex_blocks: job.vertex_blocks, face_blocks: blocks.spans.len().max(1) as u64, bytes_spilled: spilled };
    if trace {
        eprintln!("deref: join {:.2}s; {} bytes spilled", t0.elapsed().as_secs_f64(), spilled);
    }
    let t0 = std::time::Instant::now();
    let volumes = assemble::<C>(gather, &blocks, store, job, nfaces)?;
    if trace {
        eprintln!("deref: assemble and discretize {:.2}s", t0.elapsed().as_secs_f64());
    }
    Ok((nfaces, volumes, stats))
}

/// Step 1: every face's corners to the buckets of their vertex blocks
/// (one set of buckets per worker), numbering the faces in blocks of whole
/// chunks. Returns the face blocks, the buckets to read, and the faces.
fn scatter_corners(mut faces: Faces, job: &SortJob) -> Result<(Blocks, Vec<Mutex<BucketReader<Corner>>>, u64), PipelineError> {
    let SortJob { threads, progress, dir, budget, block_vertices, vertex_blocks, .. } = *job;
    let chunk = CHUNK_TRIANGLES as u64;
    let total_faces = match &faces {
        Faces::Records { records, first, end } => (*end).min(records.len()).saturating_sub(*first),
        Faces::Reader(r) => r.info().face_count.unwrap_or(0),
    };
    // Face blocks are whole chunks: one chunk (its triangles stay in cache
    // while corners are placed) unless that makes more than MAX_BUCKETS.
    let max_block = (total_faces.div_ceil(MAX_BUCKETS - 1).div_ceil(chunk) * chunk).max(chunk);
    let mut blocks = Blocks::new(max_block);
    let scatter_budget = budget.sort_buckets_per_thread();
    let scatter: Vec<Mutex<Buckets<Corner>>> =
        (0..threads).map(|t| Mutex::new(Buckets::new(dir, &format!("corners-{t}"), vertex_blocks as usize, scatter_budget))).collect();
    let scatter_one = |b: &mut Buckets<Corner>, t: [u32; 3], block: u32, corner: &mut u32| -> Result<(), StoreError> {
        for v in t {
            let vb = v as u64 / block_vertices;
            let local = v as u64 - vb * block_vertices;
            b.push(vb as usize, Corner { v_block: local as u32 | block << V_BITS, corner: *corner })?;
            *corner += 1;
        }
        Ok(())
    };
    progress.start(SCATTER, total_faces);
    let nfaces;
    match &mut faces {
        Faces::Records { records, first, end } => {
            let records: &TriangleRecords = records;
            let (first, end) = (*first, (*end).min(records.len()));
            let chunks = end.saturating_sub(first).div_ceil(chunk);
            let spans: Vec<(u32, u64)> = (0..chunks)
                .map(|c| {
                    let a = first + c * chunk;
                    blocks.add_chunk(((a + chunk).min(end) - a) as u32, a - first)
                })
                .collect();
            // Each worker scatters into its own buckets (locked once a chunk).
            mint_core::pool::for_each(threads, chunks, |t| &scatter[t], |mine, c| {
                let mut mine = mine.lock().unwrap();
                let (block, at) = spans[c as usize];
                let a = first + c * chunk;
                let b = (a + chunk).min(end);
                let mut corner = (at * 3) as u32;
                let mut err: Option<StoreError> = None;
                let visited = records.visit_indices(a, b, |_, t| {
                    if err.is_none() {
                        err = scatter_one(&mut mine, t, block, &mut corner).err();
                    }
                });
                if let Some(e) = crate::discretize::chunk_outcome(visited, err, progress) {
                    return Err(e);
                }
                progress.advance(b - a);
                Ok(())
            })?;
            nfaces = end.saturating_sub(first);
        }
        Faces::Reader(reader) => {
            let mut mine = scatter[0].lock().unwrap();
            let mut c = TriangleChunk::new();
            let mut n = 0u64;
            while reader.next_chunk(&mut c)? {
                let (block, at) = blocks.add_chunk(c.indices.len() as u32, n);
                let mut corner = (at * 3) as u32;
                for t in &c.indices {
                    scatter_one(&mut mine, *t, block, &mut corner)?;
                }
                n += c.indices.len() as u64;
                progress.advance(c.indices.len() as u64);
                if progress.cancelled() {
                    return Err(PipelineError::Cancelled);
                }
            }
            nfaces = n;
        }
    }
    progress.finish();
    let scatter = scatter.into_iter().map(|m| Mutex::new(m.into_inner().unwrap().finish())).collect();
    Ok((blocks, scatter, nfaces))
}

/// Step 2: each vertex block's positions joined with its corners, into
/// the buckets of their face blocks (one set per worker). Returns those
/// buckets to read, and the bytes both steps spilled.
fn join_blocks<C: Coord>(scatter: Vec<Mutex<BucketReader<Corner>>>, blocks: &Blocks, job: &SortJob) -> Result<(Vec<BucketReader<Resolved<C>>>, u64), PipelineError> {
    let SortJob { positions, threads, progress, dir, budget, nv, block_vertices, vertex_blocks, .. } = *job;
    let face_blocks = blocks.spans.len().max(1);
    let gather_budget = budget.sort_buckets_per_thread();
    let gather: Vec<Mutex<Buckets<Resolved<C>>>> = (0..threads).map(|t| Mutex::new(Buckets::new(dir, &format!("positions-{t}"), face_blocks, gather_budget))).collect();
    progress.start(JOIN, vertex_blocks);
    // Each worker joins vertex blocks into its own gather buckets, with a
    // block of positions as scratch.
    mint_core::pool::for_each(
        threads,
        vertex_blocks,
        |t| (&gather[t], Vec::<[f64; 3]>::with_capacity(block_vertices as usize)),
        |(out, block), vb| {
            let mut out = out.lock().unwrap();
            let v0 = vb * block_vertices;
            let v1 = (v0 + block_vertices).min(nv);
            block.clear();
            block.extend((v0..v1).map(|i| positions.get(i as u32)));
            let mut err: Option<StoreError> = None;
            for set in &scatter {
                let bucket = set.lock().unwrap().take(vb as usize);
                let read = bucket.read(|batch| {
                    if err.is_some() {
                        return;
                    }
                    for c in batch {
                        let p = block[(c.v_block & ((1 << V_BITS) - 1)) as usize];
                        if let Err(e) = out.push((c.v_block >> V_BITS) as usize, Resolved::<C>::new(c.corner, p)) {
                            err = Some(e);
                            return;
                        }
                    }
                });
                if let Err(e) = read {
                    err.get_or_insert(e);
                }
            }
            match err {
                Some(e) => Err(PipelineError::from(e)),
                None if progress.cancelled() => Err(PipelineError::Cancelled),
                None => {
                    progress.advance(1);
                    Ok(())
                }
            }
        },
    )?;
    progress.finish();
    let mut spilled = 0;
    for set in scatter {
        spilled += set.into_inner().unwrap().bytes_spilled();
    }
    let gather: Vec<BucketReader<Resolved<C>>> = gather.into_iter().map(|m| m.into_inner().unwrap().finish()).collect();
    spilled += gather.iter().map(|g| g.bytes_spilled()).sum::<u64>();
    Ok((gather, spilled))
}

/// Step 3: each face block's triangles assembled from its buckets and
/// discretized chunk by chunk into `store`; six times each chunk's signed
/// volume, in chunk order.
fn assemble<C: Coord>(gather: Vec<BucketReader<Resolved<C>>>, blocks: &Blocks, store: &mut ShardWriter, job: &SortJob, nfaces: u64) -> Result<Vec<f64>, PipelineError> {
    let SortJob { grid, threads, progress, xf, .. } = *job;
    let [_, nb, _] = grid.local_dims();
    let local = LocalMap::new(grid);
    let axis = grid.slab_axis;
    let gather: Vec<Mutex<BucketReader<Resolved<C>>>> = gather.into_iter().map(Mutex::new).collect();
    let gather = &gather;
    let local = &local;
    progress.start(ASSEMBLE, nfaces);
    // Each worker assembles whole face blocks into its own triangles.
    discretize_on_pool(
        threads,
        blocks.spans.len() as u64,
        blocks.chunks.len(),
        store,
        progress,
        |_| Vec::<[[f64; 3]; 3]>::new(),
        |tris, tx, b| {
            if progress.cancelled() {
                return Err(PipelineError::Cancelled);
            }
            let (c0, c1, _) = blocks.spans[b as usize];
            let n: u64 = blocks.chunks[c0..c1].iter().map(|&n| n as u64).sum();
            tris.clear();
            tris.resize(n as usize, [[0.0; 3]; 3]);
            for set in gather {
                let bucket = set.lock().unwrap().take(b as usize);
                bucket.read(|batch| {
                    for r in batch {
                        let c = r.corner as usize;
                        tris[c / 3][c % 3] = r.pos();
                    }
                })?;
            }
            let mut at = 0usize;
            for ci in c0..c1 {
                let m = blocks.chunks[ci] as usize;
                let mut recs = Vec::with_capacity(1024);
                let mut volume = 0.0;
                discretize_slice(&tris[at..at + m], axis, local, xf, nb, &mut recs, &mut volume);
                at += m;
                progress.advance(m as u64);
                if tx.send((ci, recs, Vec::new(), volume)).is_err() {
                    break; // the writer stopped on an error and raised `stop`
                }
            }
            Ok(())
        },
    )
}
